-- Gallery: OBJ import. gr.mesh reads meshes/house.obj, a small house written by hand, with its
-- five MTL materials (Kd, Ks, Ns from house.mtl). The mesh is read once and shared by every
-- node that names the file: the second house, behind, is the same mesh turned and scaled, with
-- set_material overriding the file's materials by one white clay.
--
--   cargo run --release -- render scenes/gallery/obj_import.lua     # obj_import.png

local here = debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or ''

grass = gr.material({0.25, 0.45, 0.15}, {0, 0, 0}, 0)
clay  = gr.material({0.8, 0.8, 0.78}, {0.1, 0.1, 0.1}, 20)

root = gr.node('root')
ground = gr.cube('ground'); ground:set_material(grass)
ground:scale(40, 1, 40); ground:translate(-20, -1, -20); root:add_child(ground)

-- No set_material: the house keeps the materials its MTL file gives each face.
house = gr.mesh('house', here .. 'meshes/house.obj')
house:rotate('y', -25); house:translate(-0.5, 0, 0); root:add_child(house)

model = gr.mesh('clay house', here .. 'meshes/house.obj'); model:set_material(clay)
model:scale(0.7, 0.7, 0.7); model:rotate('y', 40); model:translate(2.6, 0, -2.6)
root:add_child(model)

gr.render(root, 'obj_import.png', 256, 192,
          {0.6, 1.9, 5.6}, {0, -0.25, -1}, {0, 1, 0}, 40,
          {0.3, 0.3, 0.3},
          {gr.light({-4, 6, 5}, {0.75, 0.75, 0.7}, {1, 0, 0}),
           gr.light({5, 3, 2}, {0.2, 0.2, 0.25}, {1, 0, 0})})
