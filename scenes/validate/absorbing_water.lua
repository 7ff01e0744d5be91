-- Validation: absorbing water. The scene of water_volume.lua with water that keeps
-- {0.5, 0.8, 0.9} of the light over 1 (Beer–Lambert), exported to Mitsuba as a homogeneous
-- medium inside the dielectric: the floor far from the camera turns blue-green, the caustic
-- dims with the depth it is focused through.
-- region above_water 0.15 0.05 0.85 0.35
-- region under_water 0.15 0.7 0.85 0.98
-- region ball 0.4 0.6 0.75 0.9

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/box.lua')
dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/water.lua')
gr.absorption(water_m, {0.5, 0.8, 0.9}, 1)
yellow = gr.material({0.7, 0.6, 0.2}, {0, 0, 0}, 0)
add_water()
add_ball('ball', yellow)
add_block()

gr.render(root, 'absorbing_water.png', 96, 96, {0, 0, 0.95}, {0, 0, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
