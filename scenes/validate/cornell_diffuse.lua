-- Validation: a diffuse Cornell box (red and green walls, two diffuse blocks) under an area
-- light. Every surface is in the subset caustic and Mitsuba 3 share (tools/validate/).
-- region floor 0.15 0.75 0.85 0.98
-- region ceiling 0.05 0.0 0.35 0.17
-- region walls 0.0 0.2 0.12 0.8

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/box.lua')

tall = gr.cube('tall'); tall:scale(0.55, 1.1, 0.55); tall:rotate('Y', 20); tall:translate(-0.6, -1.0, -0.55)
tall:set_material(white); root:add_child(tall)
short = gr.cube('short'); short:scale(0.55, 0.55, 0.55); short:rotate('Y', -18); short:translate(0.1, -1.0, 0.0)
short:set_material(white); root:add_child(short)

gr.render(root, 'cornell_diffuse.png', 96, 96, {0, 0, 0.95}, {0, 0, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
