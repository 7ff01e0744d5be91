-- Gallery: a caustic. A glass ball (transparency 1, index 1.5) focuses a point light into a
-- bright spot inside its own shadow on the floor: light that only photon mapping's caustic map
-- carries. The light has a power, which turns photon mapping on.
--
--   cargo run --release -- render scenes/gallery/caustic_glass.lua     # caustic_glass.png

white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)

root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(white)
floor:scale(20, 1, 12); floor:translate(-12, -1, -3); root:add_child(floor)
wall = gr.cube('wall'); wall:set_material(white)
wall:scale(20, 6, 1); wall:translate(-12, -1, -3); root:add_child(wall)

ball = gr.nh_sphere('glass ball', {0, 0.5, 0}, 0.5); ball:set_material(glass); root:add_child(ball)

-- Physical falloff {0, 0, 1}; far away and low (35 degrees up), behind the camera's left: the
-- ball's long shadow falls away from it, with the caustic inside, clear of the ball.
lamp = gr.light({-4.9, 6.2, 6.6}, {100, 100, 100}, {0, 0, 1}, 1)

-- The caustic map is seen directly, so it needs many photons; the global map (light bounced
-- off the floor and wall) few.
gr.settings{caustic_photons = 400000, photons = 50000}

gr.render(root, 'caustic_glass.png', 256, 192,
          {3.2, 1.9, 2.6}, {-3, -1.7, -3}, {0, 1, 0}, 35,
          {0, 0, 0}, {lamp})
