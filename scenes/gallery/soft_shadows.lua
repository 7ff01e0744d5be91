-- Gallery: soft shadows from an area light. Three balls at rising heights under a 1 x 1 panel
-- light: the ball resting on the floor casts a shadow with a sharp core; the higher ones cast
-- shadows whose penumbra (the floor that sees part of the panel) widens, and whose umbra
-- shrinks, as the gap to the floor grows. Shadow rays sample points on the panel.
--
--   cargo run --release -- render scenes/gallery/soft_shadows.lua     # soft_shadows.png

floor_m = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(floor_m)
floor:scale(40, 1, 40); floor:translate(-20, -1, -20); root:add_child(floor)

for i, colour in ipairs({{0.7, 0.2, 0.15}, {0.85, 0.65, 0.15}, {0.2, 0.35, 0.75}}) do
  local ball = gr.sphere('ball ' .. i)
  ball:set_material(gr.material(colour, {0.2, 0.2, 0.2}, 40))
  ball:scale(0.35, 0.35, 0.35); ball:translate(1.1 * (i - 2), 0.35 + 0.45 * (i - 1), -0.3)
  root:add_child(ball)
end

-- The panel, 3 up and a little in front of the balls, emitting down (u x v = -y); course
-- falloff {1, 0, 0} as in A4. No power or photon count: a Whitted render with the ambient term,
-- 8 shadow rays per camera sample.
lamp = gr.area_light({0, 3, 0.8}, {0.8, 0.8, 0.8}, {1, 0, 0}, nil, nil, {1, 0, 0}, {0, 0, 1})
gr.settings{light_samples = 8}

gr.render(root, 'soft_shadows.png', 256, 192,
          {0.3, 2.7, 4.6}, {0, -0.47, -1}, {0, 1, 0}, 42,
          {0.2, 0.2, 0.2}, {lamp})
