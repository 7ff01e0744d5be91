-- A Cornell box with a glass ball: the ball focuses the ceiling light into a caustic on the floor.
-- Physical falloff {0, 0, 1} so photons and shadow rays share the inverse-square law.
--   cargo run --release -- render scenes/cornell_glass.lua --stats

white = gr.material({0.75, 0.75, 0.75}, {0, 0, 0}, 0)
red   = gr.material({0.75, 0.15, 0.12}, {0, 0, 0}, 0)
green = gr.material({0.15, 0.65, 0.15}, {0, 0, 0}, 0)
glass = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)

box = gr.node('box')
function wall(name, mat, sx, sy, sz, tx, ty, tz)
  local w = gr.cube(name)
  w:set_material(mat); w:scale(sx, sy, sz); w:translate(tx, ty, tz)
  box:add_child(w)
end
wall('floor',   white, 2.2, 0.1, 2.2, -1.1, -1.1, -1.1)
wall('ceiling', white, 2.2, 0.1, 2.2, -1.1,  1.0, -1.1)
wall('back',    white, 2.2, 2.2, 0.1, -1.1, -1.1, -1.1)
wall('left',    red,   0.1, 2.2, 2.2, -1.1, -1.1, -1.1)
wall('right',   green, 0.1, 2.2, 2.2,  1.0, -1.1, -1.1)

if not EMPTY then
  ball = gr.nh_sphere('glass ball', {0.15, -0.55, 0.1}, 0.45)
  ball:set_material(glass)
  box:add_child(ball)
end

lamp = gr.area_light({0, 0.99, 0}, {3, 3, 3}, {0, 0, 1}, nil, 400000, {0.4, 0, 0}, {0, 0, 0.4})

gr.render(box, 'cornell_glass.png', 400, 400,
          {0, 0, 3.6}, {0, 0, -1}, {0, 1, 0}, 40,
          {0, 0, 0}, {lamp})
