-- caustic's final scene: the extended CS488 project's final room (its room2.lua), at full quality.
-- A Cornell box with a rocky, bump-mapped floor and tiled walls, filled to 2/5 of its height
-- with water whose surface is a 2M-triangle wave mesh (generated once as glTF, cached in
-- scenes/.cache/) with Perlin ripples on top; under the water a glass ball, a silver ball and a
-- metal ring (a CSG difference of two cylinders); a small area light on the ceiling.
-- Caustics through the waves and the glass ball on the floor, colour bleeding from the walls.
--
--   cargo run --release -- render scenes/final.lua                 # 1024 x 1024, final.png
--   cargo run --release -- render scenes/final.lua --scale 0.25    # a 256 x 256 preview
--
-- The textures come from `cargo run --release -p caustic-tools --bin textures -- -o scenes/textures`.
-- `-D WATER_N=257` (any grid side) makes a lighter water mesh for quick experiments.
-- The room itself is in scenes/lib/pool_room.lua, shared with scenes/underwater.lua.

dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/pool_room.lua')

gr.render(root, 'final.png', 1024, 1024,
          {0, 0, 3.6}, {0, 0, -1}, {0, 1, 0}, 40,
          {0, 0, 0}, {lamp})
