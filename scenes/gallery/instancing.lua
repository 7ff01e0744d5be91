-- Gallery: instancing a large mesh. gr.water_mesh generates one rippled sheet of 257 x 257
-- vertices (131k triangles), cached as a glTF file; the scene places it 36 times, turned and
-- coloured in turn, as a quilt of 4.7M triangles. The triangles are stored once: every node that
-- names the same file shares one mesh and its BVH, and a node added under several parents is
-- drawn under each (`caustic render --stats` prints the triangles placed and stored).
--
--   cargo run --release -- render scenes/gallery/instancing.lua --stats     # instancing.png

-- The same parameters name the same cached file, so the four sheets below are one mesh with
-- four materials.
local sheet = {n = 257, seed = 11, size = 1, amplitude = 0.05, wavelength = 0.4, spread = 3.1}
local colours = {{0.7, 0.15, 0.1}, {0.85, 0.65, 0.15}, {0.15, 0.45, 0.3}, {0.15, 0.3, 0.7}}
local sheets = {}
for c, kd in ipairs(colours) do
  sheets[c] = gr.water_mesh('sheet ' .. c, sheet)
  sheets[c]:set_material(gr.material(kd, {0.25, 0.25, 0.25}, 50))
end

root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(gr.material({0.3, 0.3, 0.3}, {0, 0, 0}, 0))
floor:scale(40, 1, 40); floor:translate(-20, -1.1, -20); root:add_child(floor)
-- A 6 x 6 grid of places 1.05 apart, each turning its sheet by some quarter turns.
for i = 0, 5 do
  for j = 0, 5 do
    local place = gr.node('place ' .. i .. ',' .. j)
    place:rotate('y', 90 * ((i + 2 * j) % 4))
    place:translate(1.05 * (i - 2.5), 0, 1.05 * (j - 2.5))
    place:add_child(sheets[(i + j) % 4 + 1])
    root:add_child(place)
  end
end

gr.render(root, 'instancing.png', 256, 192,
          {0, 2.6, 5.2}, {0, -0.5, -1}, {0, 1, 0}, 45,
          {0.2, 0.2, 0.2},
          {gr.light({-8, 2, -2}, {0.9, 0.85, 0.8}, {1, 0, 0}),
           gr.light({3, 6, 6}, {0.3, 0.3, 0.35}, {1, 0, 0})})
