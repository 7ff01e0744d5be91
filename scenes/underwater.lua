-- The final scene's pool seen from under its surface: the camera is in the water (caustic finds
-- the medium it is in), looking along the floor and up at the wavy surface. Above, Snell's
-- window: the room and the lamp squeezed into a cone of 48.6° round each facet's normal; round
-- it, the surface mirrors the floor by total internal reflection; on the floor, the caustic
-- network of the waves, and the glass ball, the silver ball and the copper ring.
--
--   cargo run --release -- render scenes/underwater.lua                 # 1024 x 1024
--   cargo run --release -- render scenes/underwater.lua --scale 0.25    # a 256 x 256 preview
--
-- The room is scenes/lib/pool_room.lua; `-D WATER_N=257` makes a lighter water mesh.

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/pool_room.lua')

gr.render(root, 'underwater.png', 1024, 1024,
          {0.3, -0.72, 1.0}, {-0.2, 0.34, -1}, {0, 1, 0}, 76,
          {0, 0, 0}, {lamp})
