-- Validation: a closed volume of water (index 1.33) filling the lower 40% of a Cornell box, a
-- diffuse ball and block under it, an area light above: refraction, the n² law seen from air,
-- caustics through the flat surface.
-- region above_water 0.15 0.05 0.85 0.35
-- region under_water 0.15 0.7 0.85 0.98
-- region ball 0.4 0.6 0.75 0.9

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/box.lua')
dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/water.lua')
yellow = gr.material({0.7, 0.6, 0.2}, {0, 0, 0}, 0)
add_water()
add_ball('ball', yellow)
add_block()

gr.render(root, 'water_volume.png', 96, 96, {0, 0, 0.95}, {0, 0, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
