-- Gallery: a spot light and the sun. gr.spot_light(pos, dir, rgb, inner, outer) shines a cone,
-- full within 14 degrees of its axis and dark beyond 20, with glTF's smooth falloff between,
-- onto the floor, where a glass ball in it focuses a caustic into its own shadow.
-- gr.directional_light(dir, rgb) is parallel light from beyond the scene: every surface facing
-- it is lit by kd·rgb·cos θ at any distance, and the posts cast sharp, parallel shadows. Both
-- have a power, which turns photon mapping on (caustics and indirect light).
--
--   cargo run --release -- render scenes/gallery/spot_and_sun.lua     # spot_and_sun.png

white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
red = gr.material({0.7, 0.2, 0.15}, {0, 0, 0}, 0)
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(white)
floor:scale(8, 0.1, 8); floor:translate(-4, -0.1, -4); root:add_child(floor)

ball = gr.nh_sphere('ball', {0, 0.35, 0}, 0.35); ball:set_material(glass); root:add_child(ball)
for i, x in ipairs({-1.8, -0.6, 0.6, 1.8}) do
  local post = gr.cube('post ' .. i); post:set_material(red)
  post:scale(0.15, 0.9, 0.15); post:translate(x - 0.075, 0, -1.6); root:add_child(post)
end

-- The spot 3 above the ball, looking straight down at it; the sun low from the right and behind.
spot = gr.spot_light({0, 3, 0}, {0, -1, 0}, {9, 8.5, 7.5}, 14, 20, 1)
sun = gr.directional_light({-1, -0.7, 0.5}, {0.6, 0.65, 0.8}, 1)
gr.render(root, 'spot_and_sun.png', 256, 192, {0, 3.2, 5}, {0, -3, -5}, {0, 1, 0}, 45,
          {0, 0, 0}, {spot, sun})
