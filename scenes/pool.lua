-- caustic's showcase: a tiled pool of water with a glass ball, a chrome ball and a metal ring.
-- The water surface is a generated 2M-triangle wave mesh; create it first (from the repository root):
--   cargo run --release -p caustic-tools --bin water -- --n 1001 --seed 7 --size 2 --amplitude 0.03 --wavelength 0.6 -o meshes/water_1001.glb
-- then render:  cargo run --release -- render scenes/pool.lua

tile   = gr.material({0.55, 0.75, 0.85}, {0.1, 0.1, 0.1}, 20)
stone  = gr.material({0.8, 0.78, 0.72}, {0, 0, 0}, 0)
water  = gr.material({0.05, 0.1, 0.15}, {0.3, 0.3, 0.3}, 80, 0.9, 1.33, 0.6)
glass  = gr.material({0.1, 0.1, 0.1}, {0.1, 0.1, 0.1}, 100, 0.95, 1.5, 0)
chrome = gr.material({0.1, 0.1, 0.1}, {0.8, 0.8, 0.8}, 200)
copper = gr.material({0.7, 0.35, 0.2}, {0.4, 0.3, 0.2}, 60)

scene = gr.node('pool')

-- A pool 2 wide and 2 deep, floor at y = -0.6, the water surface at y = 0.
floor = gr.cube('floor'); floor:set_material(tile)
floor:scale(2, 0.1, 2); floor:translate(-1, -0.7, -1); scene:add_child(floor)
for i, w in ipairs({{-1.1, -1}, {1, -1}}) do
  wall = gr.cube('wall' .. i); wall:set_material(tile)
  wall:scale(0.1, 0.8, 2); wall:translate(w[1], -0.6, w[2]); scene:add_child(wall)
end
back = gr.cube('back'); back:set_material(tile)
back:scale(2.2, 0.8, 0.1); back:translate(-1.1, -0.6, -1.1); scene:add_child(back)
deck = gr.cube('deck'); deck:set_material(stone)
deck:scale(8, 0.1, 6); deck:translate(-4, 0.1, -7.1); scene:add_child(deck)

surface = gr.mesh('water', '../meshes/water_1001.glb'); surface:set_material(water)
scene:add_child(surface)

ball = gr.nh_sphere('glass ball', {-0.35, -0.3, 0.1}, 0.25); ball:set_material(glass); scene:add_child(ball)
mirror = gr.nh_sphere('chrome ball', {0.45, -0.42, -0.4}, 0.18); mirror:set_material(chrome); scene:add_child(mirror)

outer = gr.cylinder('outer'); outer:set_material(copper)
inner = gr.cylinder('inner'); inner:set_material(copper); inner:scale(0.85, 0.85, 1.2)
ring = gr.difference('ring', outer, inner)
ring:rotate('x', 90); ring:scale(0.22, 0.03, 0.22); ring:translate(0.3, -0.57, 0.45); scene:add_child(ring)

sun = gr.light({1.5, 3, 2.5}, {0.9, 0.85, 0.8}, {1, 0, 0}, 100, 2000000)
fill = gr.light({-3, 2, 3}, {0.25, 0.3, 0.35}, {1, 0, 0})

gr.render(scene, 'pool.png', 800, 600,
          {0, 1.3, 2.6}, {0, -0.55, -1}, {0, 1, 0}, 45,
          {0.25, 0.27, 0.3}, {sun, fill})
