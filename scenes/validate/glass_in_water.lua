-- Validation: a glass ball (index 1.5) inside a closed volume of water (index 1.33): the
-- water-to-glass interfaces refract by 1.5/1.33, and the caustic under the ball is focused
-- through both.
-- region above_water 0.15 0.05 0.85 0.35
-- region under_water 0.15 0.7 0.85 0.98
-- region caustic 0.4 0.8 0.8 0.98

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/box.lua')

water_m = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.33)
-- The water stops 0.005 short of every wall: coincident faces are their own test.
water = gr.cube('water'); water:scale(1.99, 0.795, 1.99); water:translate(-0.995, -0.995, -0.995)
water:set_material(water_m); root:add_child(water)
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
ball = gr.sphere('ball'); ball:scale(0.3, 0.3, 0.3); ball:translate(0.25, -0.6, -0.2)
ball:set_material(glass); root:add_child(ball)
block = gr.cube('block'); block:scale(0.45, 0.5, 0.45); block:rotate('Y', 20); block:translate(-0.7, -0.99, -0.7)
block:set_material(white); root:add_child(block)

gr.render(root, 'glass_in_water.png', 96, 96, {0, 0, 0.95}, {0, 0, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
