-- Gallery: diffuse interreflection. A Cornell box lit by one small area light in its ceiling:
-- everything the light does not reach directly (the ceiling, the blocks' shaded sides) is lit by
-- light bounced off the other walls, and the red and green walls bleed their colour onto the
-- white blocks and the floor. The global photon map carries that light and final gathering
-- reads it; the light's power turns photon mapping on.
--
--   cargo run --release -- render scenes/gallery/interreflection.lua     # interreflection.png
--   cargo run --release -- render scenes/gallery/interreflection.lua --gi off   # direct light only

white = gr.material({0.75, 0.75, 0.75}, {0, 0, 0}, 0)
red   = gr.material({0.75, 0.12, 0.1}, {0, 0, 0}, 0)
green = gr.material({0.12, 0.6, 0.15}, {0, 0, 0}, 0)

root = gr.node('box')
-- A wall: a slab 0.1 thick outside the box [-1, 1]^3, extending past the corners.
local function wall(name, mat, sx, sy, sz, tx, ty, tz)
  local w = gr.cube(name)
  w:set_material(mat); w:scale(sx, sy, sz); w:translate(tx, ty, tz)
  root:add_child(w)
end
wall('floor',   white, 2.2, 0.1, 2.2, -1.1, -1.1, -1.1)
wall('ceiling', white, 2.2, 0.1, 2.2, -1.1,  1.0, -1.1)
wall('back',    white, 2.2, 2.2, 0.1, -1.1, -1.1, -1.1)
wall('left',    red,   0.1, 2.2, 2.2, -1.1, -1.1, -1.1)
wall('right',   green, 0.1, 2.2, 2.2,  1.0, -1.1, -1.1)

-- A tall and a short block, turned to face the coloured walls.
local function block(name, h, angle, x, z)
  local b = gr.cube(name)
  b:set_material(white); b:translate(-0.5, 0, -0.5); b:scale(0.55, h, 0.55)
  b:rotate('y', angle); b:translate(x, -1, z); root:add_child(b)
end
block('tall block', 1.2, 20, -0.35, -0.3)
block('short block', 0.55, -18, 0.4, 0.35)

-- A 0.5 x 0.5 panel just under the ceiling, emitting down (u x v = -y), physical falloff.
lamp = gr.area_light({0, 0.99, 0}, {2.5, 2.5, 2.5}, {0, 0, 1}, 1, nil, {0.5, 0, 0}, {0, 0, 0.5})
gr.settings{photons = 100000, light_samples = 2}

gr.render(root, 'interreflection.png', 256, 256,
          {0, 0, 3.6}, {0, 0, -1}, {0, 1, 0}, 40,
          {0, 0, 0}, {lamp})
