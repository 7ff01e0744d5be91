-- The Cornell box every scene in scenes/validate/ shares: white floor, ceiling, back and front
-- walls, a red left and a green right wall, the light's fixture and the area light `light`.
-- It defines the globals white, red, green, black, root and light; a scene loads it with
--   dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/box.lua')

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

-- The light's fixture: a black panel between the light and the ceiling, so that both renderers
-- absorb the light that reaches it from below (Mitsuba's emitter is a surface; caustic's is not).
black = gr.material({0, 0, 0}, {0, 0, 0}, 0)
fixture = gr.cube('fixture'); fixture:scale(0.52, 0.005, 0.52); fixture:translate(-0.26, 0.994, -0.26)
fixture:set_material(black); root:add_child(fixture)
light = gr.area_light({0, 0.99, 0}, {1, 1, 1}, {0, 0, 1}, 1, nil, {0.5, 0, 0}, {0, 0, 0.5})  -- u × v = -y: emits downwards
