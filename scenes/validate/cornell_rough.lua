-- Validation: a rough metal ball (a GGX rough conductor, gr.roughness 0.4: alpha 0.16, copper
-- coloured) in the Cornell box under its area light: the lamp's blurred highlight and the
-- walls' blurred reflections on the ball, its soft glossy caustic on the floor.
-- region ball 0.4 0.5 0.75 0.78
-- region floor 0.15 0.78 0.85 0.98
-- region ceiling 0.05 0.0 0.35 0.17

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/box.lua')

copper = gr.material({0, 0, 0}, {0.95, 0.64, 0.54}, 0)
gr.roughness(copper, 0.4)
ball = gr.sphere('ball'); ball:scale(0.35, 0.35, 0.35); ball:translate(0.25, -0.65, -0.1)
ball:set_material(copper); root:add_child(ball)
block = gr.cube('block'); block:scale(0.45, 0.8, 0.45); block:rotate('Y', 20); block:translate(-0.7, -0.99, -0.7)
block:set_material(white); root:add_child(block)

gr.render(root, 'cornell_rough.png', 96, 96, {0, 0, 0.95}, {0, 0, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
