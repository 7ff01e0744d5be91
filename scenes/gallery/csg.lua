-- Gallery: constructive solid geometry, the three operations side by side on the same cube
-- (red) and sphere (blue): union, intersection and difference (cube minus sphere). Each operand
-- keeps its own material, so every surface shows which solid it came from.
--
--   cargo run --release -- render scenes/gallery/csg.lua     # csg.png

floor_m = gr.material({0.6, 0.6, 0.6}, {0, 0, 0}, 0)
red     = gr.material({0.75, 0.15, 0.1}, {0.1, 0.1, 0.1}, 40)
blue    = gr.material({0.15, 0.3, 0.75}, {0.1, 0.1, 0.1}, 40)

root = gr.node('root')
floor = gr.cube('floor'); floor:set_material(floor_m)
floor:scale(40, 1, 40); floor:translate(-20, -1, -20); root:add_child(floor)

-- The operands, both centred on the origin: a unit cube and a sphere of radius 0.65, which
-- bulges through the middle of each face and leaves the corners out.
local function cube()
  local c = gr.cube('cube'); c:set_material(red); c:translate(-0.5, -0.5, -0.5)
  return c
end
local function sphere()
  local s = gr.sphere('sphere'); s:set_material(blue); s:scale(0.65, 0.65, 0.65)
  return s
end

-- A CSG node is a geometry node like any other: it can be moved, turned and instanced.
local function show(solid, x)
  solid:rotate('x', -20); solid:rotate('y', 35); solid:translate(x, 0.9, 0)
  root:add_child(solid)
end
show(gr.union('union', cube(), sphere()), -1.7)
show(gr.intersection('intersection', cube(), sphere()), 0)
show(gr.difference('difference', cube(), sphere()), 1.7)

gr.render(root, 'csg.png', 256, 128,
          {0, 2.0, 5}, {0, -0.22, -1}, {0, 1, 0}, 30,
          {0.25, 0.25, 0.25},
          {gr.light({-3, 6, 5}, {0.8, 0.8, 0.8}, {1, 0, 0}),
           gr.light({4, 3, 3}, {0.25, 0.25, 0.3}, {1, 0, 0})})
