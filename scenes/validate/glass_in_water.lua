-- Validation: a glass ball (index 1.5) inside a closed volume of water (index 1.33): the
-- water-to-glass interfaces refract by 1.5/1.33, and the caustic under the ball is focused
-- through both.
-- region above_water 0.15 0.05 0.85 0.35
-- region under_water 0.15 0.7 0.85 0.98
-- region caustic 0.4 0.8 0.8 0.98

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/box.lua')
dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/water.lua')
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
add_water()
add_ball('ball', glass)
add_block()

gr.render(root, 'glass_in_water.png', 96, 96, {0, 0, 0.95}, {0, 0, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
