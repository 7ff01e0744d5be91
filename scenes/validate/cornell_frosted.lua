-- Validation: a frosted glass ball (a GGX rough dielectric, index 1.5, gr.roughness 0.3:
-- alpha 0.09) in the Cornell box under its area light: the box blurred through the ball, the
-- lamp's soft highlight, and the soft caustic the ball focuses on the floor.
-- region caustic 0.45 0.78 0.85 0.98
-- region ceiling 0.05 0.0 0.35 0.17
-- region ball 0.4 0.5 0.75 0.78

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/box.lua')

frosted = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
gr.roughness(frosted, 0.3)
ball = gr.sphere('ball'); ball:scale(0.35, 0.35, 0.35); ball:translate(0.25, -0.65, -0.1)
ball:set_material(frosted); root:add_child(ball)
block = gr.cube('block'); block:scale(0.45, 0.8, 0.45); block:rotate('Y', 20); block:translate(-0.7, -0.99, -0.7)
block:set_material(white); root:add_child(block)

gr.render(root, 'cornell_frosted.png', 96, 96, {0, 0, 0.95}, {0, 0, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
