-- A desk with a lamp and a gem, for the modern API: each node's transforms act in call order.
-- desk_legacy.lua is the same scene written for the legacy API, with every node's calls in the
-- reverse order; `caustic render desk_legacy.lua --dialect legacy` renders this image.
--   caustic render scenes/legacy/desk.lua

wood  = gr.material({0.55, 0.35, 0.18}, {0.1, 0.1, 0.1}, 10)
metal = gr.material({0.2, 0.2, 0.25}, {0.7, 0.7, 0.7}, 60)
shade = gr.material({0.9, 0.8, 0.3}, {0.2, 0.2, 0.2}, 20)
jade  = gr.material({0.1, 0.6, 0.3}, {0.5, 0.5, 0.5}, 80)
floor = gr.material({0.6, 0.6, 0.65}, {0, 0, 0}, 0)

scene = gr.node('scene')
scene:rotate('x', 15)
scene:translate(0, -1, -6)

ground = gr.cube('ground')
scene:add_child(ground)
ground:set_material(floor)
ground:scale(8, 0.1, 8)
ground:translate(-4, -0.1, -4)

-- The desk: a top on four instances of one leg.
desk = gr.node('desk')
scene:add_child(desk)
desk:rotate('y', -20)

top = gr.cube('top')
desk:add_child(top)
top:set_material(wood)
top:scale(3, 0.1, 1.5)
top:translate(-1.5, 1, -0.75)

leg = gr.cube('leg')
leg:set_material(wood)
leg:scale(0.1, 1, 0.1)
leg:translate(-0.05, 0, -0.05)
for i, xz in ipairs({{-1.35, -0.6}, {1.35, -0.6}, {-1.35, 0.6}, {1.35, 0.6}}) do
  local place = gr.node('leg' .. i)
  desk:add_child(place)
  place:translate(table.unpack({xz[1], 0, xz[2]}))
  place:add_child(leg)
end

-- The lamp: a base, a tilted arm and a pyramid shade at its end.
lamp = gr.node('lamp')
desk:add_child(lamp)
lamp:rotate('y', 30)
lamp:translate(0.8, 1.1, -0.2)

base = gr.cylinder('base')
lamp:add_child(base)
base:set_material(metal)
base:scale(0.25, 0.25, 0.03)
base:rotate('x', 90)

arm = gr.node('arm')
lamp:add_child(arm)
arm:rotate('z', 25)

rod = gr.cube('rod')
arm:add_child(rod)
rod:set_material(metal)
rod:scale(0.06, 0.9, 0.06)
rod:translate(-0.03, 0, -0.03)

hat = gr.mesh('hat', {{-1, 0, -1}, {1, 0, -1}, {1, 0, 1}, {-1, 0, 1}, {0, 1, 0}},
              {{0, 1, 2, 3}, {0, 4, 1}, {1, 4, 2}, {2, 4, 3}, {3, 4, 0}})
arm:add_child(hat)
hat:set_material(shade)
hat:scale(0.25, 0.3, 0.25)
hat:rotate('z', -60)
hat:translate(0, 0.85, 0)

gem = gr.mesh('gem', 'gem.obj')
desk:add_child(gem)
gem:set_material(jade)
gem:scale(0.2, 0.25, 0.2)
gem:rotate('y', 45)
gem:translate(-0.7, 1.35, 0.1)

gr.render(scene, 'desk.png', 128, 96,
          {0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 45,
          {0.25, 0.25, 0.25}, {gr.light({-4, 6, 2}, {0.9, 0.9, 0.9}, {1, 0, 0})})
