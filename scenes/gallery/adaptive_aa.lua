-- Gallery: adaptive anti-aliasing. A checkerboard of thin black and white tiles running to the
-- horizon and a row of thin posts: sharp, high-contrast edges that alias with one ray per pixel.
-- gr.settings{adaptive = true} traces each pixel's corners and splits the pixels whose corners
-- differ by more than the threshold, up to 3 times: flat areas cost about one ray per pixel and
-- the edges many more. --aa-map writes how many camera rays each pixel took.
--
--   cargo run --release -- render scenes/gallery/adaptive_aa.lua --aa-map aa_map.png
--   cargo run --release -- render scenes/gallery/adaptive_aa.lua --spp 1   # aliased, to compare

black = gr.material({0.03, 0.03, 0.03}, {0, 0, 0}, 0)
white = gr.material({0.9, 0.9, 0.9}, {0, 0, 0}, 0)
brass = gr.material({0.6, 0.45, 0.15}, {0.3, 0.3, 0.3}, 60)

root = gr.node('root')
-- 24 x 24 tiles of side 0.5: two cubes, a black and a white one, each placed by 288 nodes.
local tile_b = gr.cube('black tile'); tile_b:set_material(black); tile_b:scale(0.5, 0.05, 0.5)
local tile_w = gr.cube('white tile'); tile_w:set_material(white); tile_w:scale(0.5, 0.05, 0.5)
for i = 0, 23 do
  for j = 0, 23 do
    local place = gr.node('tile ' .. i .. ',' .. j)
    place:translate(0.5 * i - 6, -0.05, 0.5 * j - 10)
    place:add_child((i + j) % 2 == 0 and tile_b or tile_w)
    root:add_child(place)
  end
end

-- Thin posts, a few pixels wide, in a row across the board.
for k = 0, 6 do
  local post = gr.cylinder('post ' .. k); post:set_material(brass)
  post:scale(0.03, 0.03, 0.6); post:rotate('x', 90); post:translate(0.6 * k - 1.8, 0.6, -0.5)
  root:add_child(post)
end

gr.settings{adaptive = true}

gr.render(root, 'adaptive_aa.png', 256, 192,
          {0, 1.3, 3}, {0, -0.35, -1}, {0, 1, 0}, 50,
          {0.3, 0.3, 0.3},
          {gr.light({-2, 5, 3}, {0.7, 0.7, 0.7}, {1, 0, 0})})
