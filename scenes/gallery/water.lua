-- Gallery: water. gr.water_mesh generates a wave surface (here 257 x 257 vertices, 131k
-- triangles) closed into a body of water 0.55 deep, cached as a glTF file in .cache/ beside the
-- script (or in $CAUSTIC_CACHE). Clear water (index 1.33) in a tiled pool: its waves focus a
-- point light into a net of caustics on the pool's floor, and the floor's tiles bend through it.
--
--   cargo run --release -- render scenes/gallery/water.lua     # water.png

local here = debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or ''
local function texture(name) return here .. '../textures/' .. name .. '.png' end

tiles = gr.material({1, 1, 1}, {0, 0, 0}, 0, 0, 1, 0, texture('tiles_white'))
paint = gr.material({0.45, 0.65, 0.75}, {0, 0, 0}, 0)
stone = gr.material({0.6, 0.58, 0.55}, {0, 0, 0}, 0)
water = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.33)

root = gr.node('root')
local function slab(name, mat, sx, sy, sz, tx, ty, tz)
  local s = gr.cube(name)
  s:set_material(mat); s:scale(sx, sy, sz); s:translate(tx, ty, tz)
  root:add_child(s)
end
-- The pool: 2 x 2 inside, its rim at y = 0.05, a tiled floor whose top is at y = -0.6.
slab('ground', stone, 12, 0.1, 12, -6, -0.8, -6)
slab('pool floor', tiles, 2.2, 0.1, 2.2, -1.1, -0.7, -1.1)
slab('left',  paint, 0.1, 0.75, 2.2, -1.1, -0.7, -1.1)
slab('right', paint, 0.1, 0.75, 2.2,  1.0, -0.7, -1.1)
slab('back',  paint, 2.2, 0.75, 0.1, -1.1, -0.7, -1.1)
slab('front', paint, 2.2, 0.75, 0.1, -1.1, -0.7,  1.0)

-- The water's surface lies at y = -0.05; its sides and bottom are hidden inside the walls and the
-- floor (the water is 2.05 wide, the walls start at +-1), so no face of it touches a tile.
pool = gr.water_mesh('water', {n = 257, seed = 3, size = 2.05, amplitude = 0.015,
                               wavelength = 0.45, depth = 0.55})
pool:set_material(water); pool:translate(0, -0.05, 0); root:add_child(pool)

-- A red ball resting on the pool's floor, under water.
ball = gr.nh_sphere('ball', {-0.4, -0.4, 0.2}, 0.2)
ball:set_material(gr.material({0.7, 0.1, 0.08}, {0.2, 0.2, 0.2}, 50)); root:add_child(ball)

-- A point light high above, physical falloff; its power turns photon mapping on. Every photon
-- that reaches the pool's floor passed the waves, so the caustic map carries the floor's light.
sun = gr.light({1.5, 6, 2}, {60, 60, 60}, {0, 0, 1}, 1)
gr.settings{caustic_photons = 1000000, photons = 100000, gather_rays = 8}

gr.render(root, 'water.png', 256, 192,
          {0, 2.5, 2.3}, {0, -1, -0.9}, {0, 1, 0}, 45,
          {0, 0, 0}, {sun})
