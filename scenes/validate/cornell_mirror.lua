-- Validation: a mirror ball (ks 0.9) in a Cornell box under an area light: light reflected onto
-- the floor and the ceiling, and the light seen in the ball.
-- region floor 0.15 0.78 0.85 0.98
-- region ceiling 0.05 0.0 0.35 0.17
-- region ball 0.4 0.5 0.75 0.78

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/box.lua')

mirror = gr.material({0, 0, 0}, {0.9, 0.9, 0.9}, 0)
ball = gr.sphere('ball'); ball:scale(0.35, 0.35, 0.35); ball:translate(0.25, -0.65, -0.1)
ball:set_material(mirror); root:add_child(ball)
block = gr.cube('block'); block:scale(0.5, 0.9, 0.5); block:rotate('Y', 20); block:translate(-0.7, -1.0, -0.7)
block:set_material(white); root:add_child(block)

gr.render(root, 'cornell_mirror.png', 96, 96, {0, 0, 0.95}, {0, 0, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
