-- Gallery: the two quadrics of the extended project, gr.cylinder and gr.cone, both capped.
-- A cylinder stands upright (its axis turned from z to y), a cone stands on its cap with its
-- apex up, and a second cone lies on its side to show its shading and its cap.
--
--   cargo run --release -- render scenes/gallery/cylinder_cone.lua     # cylinder_cone.png

floor_m = gr.material({0.55, 0.55, 0.6}, {0, 0, 0}, 0)
blue    = gr.material({0.15, 0.3, 0.7}, {0.12, 0.12, 0.12}, 40)
orange  = gr.material({0.8, 0.4, 0.1}, {0.12, 0.12, 0.12}, 40)
green   = gr.material({0.2, 0.6, 0.3}, {0.12, 0.12, 0.12}, 40)

root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(floor_m)
floor:scale(40, 1, 40); floor:translate(-20, -1, -20); root:add_child(floor)

-- gr.cylinder: axis z, radius 1, z in [-1, 1]. Turned about x, its axis is y; raised by its
-- half height, it stands on the floor.
cyl = gr.cylinder('cylinder'); cyl:set_material(blue)
cyl:scale(0.5, 0.5, 0.8); cyl:rotate('x', 90); cyl:translate(-1.1, 0.8, 0)
root:add_child(cyl)

-- gr.cone: apex at the origin, axis +z, radius 1 at z = 1. Turned by 90 about x, +z points
-- down (-y): the cap lies below the apex, and raising the cone by its height sets it on the floor.
cone = gr.cone('cone'); cone:set_material(orange)
cone:scale(0.55, 0.55, 1.4); cone:rotate('x', 90); cone:translate(0.3, 1.4, -0.3)
root:add_child(cone)

-- A cone on its side: tipped by its half angle (atan(0.35 / 0.9) = 21.25 degrees) so that one
-- line of it lies on the floor, then turned about y to show its cap.
lying = gr.cone('lying cone'); lying:set_material(green)
lying:scale(0.35, 0.35, 0.9); lying:rotate('x', -21.25); lying:rotate('y', 115)
lying:translate(0.8, 0, 0.8)
root:add_child(lying)

gr.render(root, 'cylinder_cone.png', 256, 192,
          {0.2, 1.7, 4.6}, {0, -0.33, -1}, {0, 1, 0}, 45,
          {0.25, 0.25, 0.25},
          {gr.light({-3, 5, 4}, {0.8, 0.8, 0.8}, {1, 0, 0}),
           gr.light({4, 3, 2}, {0.25, 0.25, 0.3}, {1, 0, 0})})
