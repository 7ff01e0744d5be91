-- Gallery: coloured water and glass. gr.absorption(material, colour, distance) makes the inside of
-- a transparent material absorb (Beer–Lambert, as glTF's KHR_materials_volume and Mitsuba's
-- homogeneous media do): light keeps `colour` after `distance` in it. A clear glass of
-- blue-green water and an amber glass ball on a white table under an area light: the longer the
-- path through them, the deeper the colour (the ball's centre against its rim, the water seen
-- through its depth against its surface), and the caustics they cast are coloured by what they
-- kept.
--
--   cargo run --release -- render scenes/gallery/coloured_glass.lua     # coloured_glass.png

white = gr.material({0.8, 0.8, 0.8}, {0, 0, 0}, 0)
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
water = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.33)
gr.absorption(water, {0.25, 0.7, 0.8}, 0.5)
amber = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
gr.absorption(amber, {0.9, 0.5, 0.12}, 0.5)

root = gr.node('root')
table = gr.cube('table'); table:set_material(white); table:scale(8, 0.1, 8); table:translate(-4, -0.1, -4)
root:add_child(table)
back = gr.cube('back'); back:set_material(white); back:scale(8, 4, 0.1); back:translate(-4, 0, -2)
root:add_child(back)

-- The glass: an upright cylinder (gr.cylinder's axis is z, turned to y) 0.9 tall and 0.4 in
-- radius, hollowed out above a base 0.1 thick by a cylinder 0.35 in radius.
outer = gr.cylinder('outer'); outer:set_material(glass)
outer:rotate('x', 90); outer:scale(0.4, 0.45, 0.4); outer:translate(0, 0.45, 0)
inner = gr.cylinder('inner'); inner:set_material(glass)
inner:rotate('x', 90); inner:scale(0.35, 0.5, 0.35); inner:translate(0, 0.6, 0)
cup = gr.difference('glass', outer, inner); cup:translate(-0.35, 0, 0)
root:add_child(cup)
-- The water fills it to 0.7, 0.002 clear of the glass (faces that meet are their own test).
liquid = gr.cylinder('water'); liquid:set_material(water)
liquid:rotate('x', 90); liquid:scale(0.348, 0.299, 0.348); liquid:translate(-0.35, 0.401, 0)
root:add_child(liquid)

ball = gr.sphere('ball'); ball:set_material(amber)
ball:scale(0.3, 0.3, 0.3); ball:translate(0.55, 0.3, 0.25)
root:add_child(ball)

lamp = gr.area_light({0.2, 2.6, -1.2}, {9, 9, 9}, {0, 0, 1}, 1, nil, {0.6, 0, 0}, {0, 0, 0.6})
gr.render(root, 'coloured_glass.png', 256, 192, {0, 1.5, 3.4}, {0, -0.38, -1}, {0, 1, 0}, 38,
          {0, 0, 0}, {lamp})
