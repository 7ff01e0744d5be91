-- Gallery: normal maps. The 8th argument of gr.material names an RGB tangent-space normal map
-- (or a grey height map) that bends the shading normal: the geometry stays flat or round, the
-- light says otherwise. Left: a smooth white ball and a flat tiled slab without maps; right:
-- the same two with rock_norm.png (pebbles) and tiles_norm.png (bevelled tiles and grout).
-- A low light from the left grazes the surfaces, where bumps show most.
--
--   cargo run --release -- render scenes/gallery/normal_map.lua     # normal_map.png

local here = debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or ''
local function texture(name) return here .. '../textures/' .. name .. '.png' end

floor_m = gr.material({0.35, 0.35, 0.4}, {0, 0, 0}, 0)
plaster = gr.material({0.8, 0.78, 0.72}, {0.1, 0.1, 0.1}, 20)
rough   = gr.material({0.8, 0.78, 0.72}, {0.1, 0.1, 0.1}, 20, 0, 1, 0, nil, texture('rock_norm'))
tiles   = gr.material({1, 1, 1}, {0.15, 0.15, 0.15}, 60, 0, 1, 0, texture('tiles_white'))
bevel   = gr.material({1, 1, 1}, {0.15, 0.15, 0.15}, 60, 0, 1, 0, texture('tiles_white'),
                      texture('tiles_norm'))

root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(floor_m)
floor:scale(40, 1, 40); floor:translate(-20, -1, -20); root:add_child(floor)

local function ball(mat, x)
  local b = gr.sphere('ball'); b:set_material(mat)
  b:scale(0.35, 0.35, 0.35); b:translate(x, 0.35, 0.5); root:add_child(b)
end
-- An upright slab 1.5 square, its textured face (+z) towards the camera.
local function slab(mat, x)
  local s = gr.cube('slab'); s:set_material(mat)
  s:scale(1.5, 1.5, 0.1); s:translate(x - 0.75, 0, -0.6); root:add_child(s)
end
ball(plaster, -0.8); slab(tiles, -0.8)
ball(rough, 0.8);    slab(bevel, 0.8)

gr.render(root, 'normal_map.png', 256, 192,
          {0, 0.95, 3.6}, {0, -0.1, -1}, {0, 1, 0}, 40,
          {0.15, 0.15, 0.15},
          {gr.light({-6, 1.2, 1.2}, {0.9, 0.88, 0.8}, {1, 0, 0}),
           gr.light({2, 4, 5}, {0.2, 0.2, 0.25}, {1, 0, 0})})
