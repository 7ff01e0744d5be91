-- Gallery: Perlin noise. The 6th argument of gr.material, s, bends the shading normal by the
-- gradient of 3-D Perlin noise (about ten features per scene unit): 1 tilts normals by 10-20
-- degrees. It shows in highlights and reflections: three chrome balls with s = 0, 0.5 and 2
-- stand on a dark mirror pool with s = 1, whose reflection of them ripples.
--
--   cargo run --release -- render scenes/gallery/perlin.lua     # perlin.png

pool = gr.material({0.02, 0.03, 0.05}, {0.6, 0.6, 0.6}, 200, 0, 1, 1)
local function chrome(s)
  return gr.material({0.05, 0.05, 0.05}, {0.85, 0.8, 0.7}, 300, 0, 1, s)
end

root = gr.node('root')
floor = gr.cube('pool'); floor:set_material(pool)
floor:scale(40, 1, 40); floor:translate(-20, -1, -20); root:add_child(floor)

-- A pale wall with a red and a blue block before it, for the balls and the pool to reflect.
local function block(name, rgb, sx, sy, x, z)
  local b = gr.cube(name); b:set_material(gr.material(rgb, {0, 0, 0}, 0))
  b:scale(sx, sy, 0.3); b:translate(x, 0, z); root:add_child(b)
end
block('wall', {0.8, 0.75, 0.65}, 40, 6, -20, -4)
block('red block', {0.7, 0.12, 0.1}, 1.6, 1.2, -1.8, -2)
block('blue block', {0.1, 0.2, 0.7}, 1.6, 1.2, 0.2, -2)

for i, s in ipairs({0, 0.5, 2}) do
  local ball = gr.sphere('ball ' .. s); ball:set_material(chrome(s))
  ball:scale(0.5, 0.5, 0.5); ball:translate(1.2 * (i - 2), 0.5, 0)
  root:add_child(ball)
end

gr.render(root, 'perlin.png', 256, 192,
          {0, 1.2, 4}, {0, -0.25, -1}, {0, 1, 0}, 40,
          {0.25, 0.25, 0.25},
          {gr.light({-3, 5, 4}, {0.8, 0.8, 0.8}, {1, 0, 0}),
           gr.light({3, 2, 3}, {0.3, 0.3, 0.3}, {1, 0, 0})})
