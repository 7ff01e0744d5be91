-- Gallery: rough metal and frosted glass. gr.roughness(material, r) gives a material GGX
-- microfacets of roughness r (alpha = r², as glTF and Mitsuba's rough materials have it): a
-- mirror becomes brushed metal, whose reflection of the lamp spreads into a soft highlight, and
-- glass becomes frosted glass, which blurs what is seen through it and casts a soft caustic.
-- The lamp is sampled at the frosted surface as well as found by its scattered rays, weighed by
-- multiple importance sampling, so the frosted ball shows its highlight without fireflies.
--
--   cargo run --release -- render scenes/gallery/rough_materials.lua     # rough_materials.png

white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
blue = gr.material({0.2, 0.3, 0.6}, {0, 0, 0}, 0)
copper = gr.material({0, 0, 0}, {0.955, 0.638, 0.538}, 0)
gr.roughness(copper, 0.35)
frosted = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
gr.roughness(frosted, 0.3)
root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(white)
floor:scale(8, 0.1, 8); floor:translate(-4, -0.1, -4); root:add_child(floor)
wall = gr.cube('wall'); wall:set_material(blue)
wall:scale(8, 4, 0.1); wall:translate(-4, 0, -1.6); root:add_child(wall)

metal = gr.nh_sphere('metal', {-0.7, 0.5, 0}, 0.5); metal:set_material(copper); root:add_child(metal)
glass = gr.nh_sphere('glass', {0.7, 0.5, 0}, 0.5); glass:set_material(frosted); root:add_child(glass)

-- A 1 × 1 lamp 2.5 above the floor, facing down, physical falloff, with a power (photon mapping).
lamp = gr.area_light({0, 2.5, 0.3}, {6, 6, 6}, {0, 0, 1}, 1, nil, {1, 0, 0}, {0, 0, 1})
gr.render(root, 'rough_materials.png', 256, 160, {0, 1.3, 3.6}, {0, -0.75, -3.6}, {0, 1, 0}, 40,
          {0, 0, 0}, {lamp})
