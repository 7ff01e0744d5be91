-- Validation: the camera under water. The scene of water_volume.lua seen from inside the water
-- (index 1.33), looking along and up at the surface: Snell's window (the box above, squeezed
-- into a cone of 48.6° round the vertical) and, outside it, total internal reflection of the
-- floor, the ball and the block; the caustic network of the flat surface on the floor.
-- region window 0.3 0.0 0.7 0.2
-- region reflection 0.05 0.25 0.95 0.45
-- region under_water 0.15 0.7 0.85 0.98

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/box.lua')
dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/water.lua')
yellow = gr.material({0.7, 0.6, 0.2}, {0, 0, 0}, 0)
add_water()
add_ball('ball', yellow)
add_block()

gr.render(root, 'camera_under_water.png', 96, 96, {0, -0.45, 0.9}, {0, 0.3, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
