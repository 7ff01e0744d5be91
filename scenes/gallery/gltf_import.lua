-- Gallery: importing glTF. gr.mesh reads meshes/trinkets.gltf (JSON beside its trinkets.bin
-- buffer): a node hierarchy whose transforms are baked into one mesh, and the file's own
-- metallic-roughness materials turned into caustic's: a polished gold ring, a ring of glass
-- (KHR_materials_transmission and KHR_materials_ior) and a glazed ceramic vase.
-- The file comes from `cargo run --release -p caustic-tools --bin gallery_gltf -- -o scenes/gallery/meshes`.
--
--   cargo run --release -- render scenes/gallery/gltf_import.lua     # gltf_import.png

local here = debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or ''

wood = gr.material({0.55, 0.35, 0.2}, {0.05, 0.05, 0.05}, 20)
wall = gr.material({0.8, 0.78, 0.72}, {0, 0, 0}, 0)

root = gr.node('root')
table = gr.cube('table'); table:set_material(wood)
table:scale(40, 1, 40); table:translate(-20, -1, -20); root:add_child(table)
back = gr.cube('wall'); back:set_material(wall)
back:scale(40, 20, 1); back:translate(-20, -1, -3); root:add_child(back)

-- No set_material: each triangle keeps the glTF material of its primitive.
trinkets = gr.mesh('trinkets', here .. 'meshes/trinkets.gltf')
root:add_child(trinkets)

gr.render(root, 'gltf_import.png', 256, 192,
          {0, 1.7, 4.3}, {0, -0.3, -1}, {0, 1, 0}, 40,
          {0.3, 0.3, 0.3},
          {gr.light({-3, 5, 4}, {0.75, 0.75, 0.7}, {1, 0, 0}),
           gr.light({4, 3, 3}, {0.25, 0.25, 0.3}, {1, 0, 0})})
