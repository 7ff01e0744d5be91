-- The water scenes' shared parts (scenes/validate/, in the box of lib/box.lua): a closed body
-- of water (index 1.33) filling the lower 40% of the box, a sphere under it and a white block
-- standing in it. It defines `water_m` and the functions below; a scene loads it after box.lua
-- with
--   dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/water.lua')

water_m = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.33)

-- The water, stopping 0.005 short of every wall: coincident faces are their own test.
function add_water()
  local water = gr.cube('water'); water:scale(1.99, 0.795, 1.99); water:translate(-0.995, -0.995, -0.995)
  water:set_material(water_m); root:add_child(water)
end

-- A sphere of radius 0.3 under the water, named `name`, of material `mat`.
function add_ball(name, mat)
  local ball = gr.sphere(name); ball:scale(0.3, 0.3, 0.3); ball:translate(0.25, -0.6, -0.2)
  ball:set_material(mat); root:add_child(ball)
end

-- The white block standing on the floor, half under the water.
function add_block()
  local block = gr.cube('block'); block:scale(0.45, 0.5, 0.45); block:rotate('Y', 20); block:translate(-0.7, -0.99, -0.7)
  block:set_material(white); root:add_child(block)
end
