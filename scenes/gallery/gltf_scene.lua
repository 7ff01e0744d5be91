-- Gallery: a Blender scene placed whole. gr.gltf reads meshes/blender_room.glb, written by
-- Blender's own glTF exporter (scenes/gltf/textured_box.glb), as a node hierarchy: a room of
-- grey walls lit by the ceiling panel's emissive material (a surface that is also an area
-- light) and a box wearing the file's embedded checker texture (an sRGB PNG inside the GLB).
-- The script adds what the file lacks: a glass ball beside the box and a small lamp whose
-- light it focuses into a caustic (the panel's own caustic is the soft glow in its shadow).
--
--   cargo run --release -- render scenes/gallery/gltf_scene.lua     # gltf_scene.png

local here = debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or ''

root = gr.node('root')
room = gr.gltf('room', here .. 'meshes/blender_room.glb')
root:add_child(room)

glass = gr.material({0, 0, 0}, {1, 1, 1}, 0, 1, 1.5)
ball = gr.nh_sphere('ball', {-0.62, 0.2, -0.25}, 0.2)
ball:set_material(glass)
root:add_child(ball)

-- The file's own camera: Blender's, 5 cm inside the front wall.
gr.render(root, 'gltf_scene.png', 256, 192,
          {0, 1.1, 1.45}, {0, -0.4706, -0.8824}, {0, 1, 0}, 42.18,
          {0, 0, 0},
          {gr.light({-0.4, 2.0, -1.2}, {0.8, 0.8, 0.8}, {0, 0, 1}, 1)})
