-- Gallery: image textures. The 7th argument of gr.material names a PNG or JPEG that replaces kd,
-- looked up at each primitive's own texture coordinates: around and down the sphere, across
-- each face of the cube, around the cylinder and over its caps, and across the floor's top face.
--
--   cargo run --release -- render scenes/gallery/texture.lua     # texture.png

-- Textures are named from this script's folder, so the scene renders from anywhere.
local here = debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or ''
local function texture(name) return here .. '../textures/' .. name .. '.png' end

-- kd is ignored where a texture is given; ks and the exponent still make a highlight.
local function textured(name)
  return gr.material({1, 1, 1}, {0.05, 0.05, 0.05}, 30, 0, 1, 0, texture(name))
end

root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(textured('rock'))
floor:scale(6, 1, 6); floor:translate(-3, -1, -3.5); root:add_child(floor)

ball = gr.sphere('ball'); ball:set_material(textured('tiles_green'))
ball:scale(0.6, 0.6, 0.6); ball:rotate('y', 30); ball:translate(-1.3, 0.6, 0); root:add_child(ball)

box = gr.cube('box'); box:set_material(textured('tiles_red'))
box:translate(-0.5, 0, -0.5); box:rotate('y', 30); box:translate(0.1, 0, -0.3); root:add_child(box)

drum = gr.cylinder('drum'); drum:set_material(textured('tiles_white'))
drum:scale(0.45, 0.45, 0.6); drum:rotate('x', 90); drum:translate(1.4, 0.6, 0.3)
root:add_child(drum)

gr.render(root, 'texture.png', 256, 192,
          {0, 2, 4.3}, {0, -0.4, -1}, {0, 1, 0}, 45,
          {0.3, 0.3, 0.3},
          {gr.light({-3, 6, 5}, {0.75, 0.75, 0.75}, {1, 0, 0})})
