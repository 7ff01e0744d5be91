-- Validation: a diffuse Cornell box (red and green walls, two diffuse blocks) under an area
-- light. Every surface is in the subset caustic and Mitsuba 3 share (tools/validate/).
-- region floor 0.15 0.75 0.85 0.98
-- region ceiling 0.15 0.02 0.85 0.12
-- region walls 0.0 0.2 0.12 0.8

white = gr.material({0.73, 0.73, 0.73}, {0, 0, 0}, 0)
red = gr.material({0.63, 0.065, 0.05}, {0, 0, 0}, 0)
green = gr.material({0.14, 0.45, 0.091}, {0, 0, 0}, 0)

root = gr.node('root')
-- A wall: a slab 0.1 thick, extending past the corners so no two walls meet only along an edge.
function wall(name, mat, sx, sy, sz, tx, ty, tz)
  local w = gr.cube(name)
  w:scale(sx, sy, sz)
  w:translate(tx, ty, tz)
  w:set_material(mat)
  root:add_child(w)
end
wall('floor', white, 2.4, 0.1, 2.4, -1.2, -1.1, -1.2)
wall('ceiling', white, 2.4, 0.1, 2.4, -1.2, 1.0, -1.2)
wall('back', white, 2.4, 2.4, 0.1, -1.2, -1.2, -1.1)
wall('front', white, 2.4, 2.4, 0.1, -1.2, -1.2, 1.0)
wall('left', red, 0.1, 2.4, 2.4, -1.1, -1.2, -1.2)
wall('right', green, 0.1, 2.4, 2.4, 1.0, -1.2, -1.2)

tall = gr.cube('tall'); tall:scale(0.55, 1.1, 0.55); tall:rotate('Y', 20); tall:translate(-0.6, -1.0, -0.55)
tall:set_material(white); root:add_child(tall)
short = gr.cube('short'); short:scale(0.55, 0.55, 0.55); short:rotate('Y', -18); short:translate(0.1, -1.0, 0.0)
short:set_material(white); root:add_child(short)

-- The light's fixture: a black panel between the light and the ceiling, so that both renderers
-- absorb the light that reaches it from below (Mitsuba's emitter is a surface; caustic's is not).
black = gr.material({0, 0, 0}, {0, 0, 0}, 0)
fixture = gr.cube('fixture'); fixture:scale(0.52, 0.005, 0.52); fixture:translate(-0.26, 0.994, -0.26)
fixture:set_material(black); root:add_child(fixture)
light = gr.area_light({0, 0.99, 0}, {1, 1, 1}, {0, 0, 1}, nil, 200000, {0.5, 0, 0}, {0, 0, 0.5})  -- u × v = -y: emits downwards
gr.render(root, 'cornell_diffuse.png', 96, 96, {0, 0, 0.95}, {0, 0, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
