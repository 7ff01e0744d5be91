-- Validation: a closed volume of water (index 1.33) filling the lower 40% of a Cornell box, a
-- diffuse ball and block under it, an area light above: refraction, the n² law seen from air,
-- caustics through the flat surface.
-- region above_water 0.15 0.05 0.85 0.35
-- region under_water 0.15 0.7 0.85 0.98
-- region ball 0.4 0.6 0.75 0.9

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


water_m = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.33)
-- The water stops 0.005 short of every wall: coincident faces are their own test.
water = gr.cube('water'); water:scale(1.99, 0.795, 1.99); water:translate(-0.995, -0.995, -0.995)
water:set_material(water_m); root:add_child(water)
yellow = gr.material({0.7, 0.6, 0.2}, {0, 0, 0}, 0)
ball = gr.sphere('ball'); ball:scale(0.3, 0.3, 0.3); ball:translate(0.25, -0.6, -0.2)
ball:set_material(yellow); root:add_child(ball)
block = gr.cube('block'); block:scale(0.45, 0.5, 0.45); block:rotate('Y', 20); block:translate(-0.7, -0.99, -0.7)
block:set_material(white); root:add_child(block)

-- The light's fixture: a black panel between the light and the ceiling, so that both renderers
-- absorb the light that reaches it from below (Mitsuba's emitter is a surface; caustic's is not).
black = gr.material({0, 0, 0}, {0, 0, 0}, 0)
fixture = gr.cube('fixture'); fixture:scale(0.52, 0.005, 0.52); fixture:translate(-0.26, 0.994, -0.26)
fixture:set_material(black); root:add_child(fixture)
light = gr.area_light({0, 0.99, 0}, {1, 1, 1}, {0, 0, 1}, nil, 200000, {0.5, 0, 0}, {0, 0, 0.5})  -- u × v = -y: emits downwards
gr.render(root, 'water_volume.png', 96, 96, {0, 0, 0.95}, {0, 0, -1}, {0, 1, 0}, 80,
          {0, 0, 0}, {light})
