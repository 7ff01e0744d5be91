-- The room of caustic's final scene (scenes/final.lua) and of its view from under the water
-- (scenes/underwater.lua): the extended CS488 project's final room (its room2.lua). A Cornell box
-- with a rocky, bump-mapped floor and tiled walls, filled to 2/5 of its height with water whose
-- surface is a 2M-triangle wave mesh (generated once as glTF, cached in scenes/.cache/) with
-- Perlin ripples on top; under the water a glass ball, a silver ball and a metal ring (a CSG
-- difference of two cylinders); a small area light on the ceiling. It defines the globals
-- `root` and `lamp`; a scene loads it with
--   dofile((debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. 'lib/pool_room.lua')
-- `-D WATER_N=257` (any grid side) makes a lighter water mesh for quick experiments.

-- This file is in scenes/lib/; the textures are in scenes/textures/.
local here = (debug.getinfo(1, 'S').source:match('^@(.*[/\\])') or '') .. '../'
local function texture(name) return here .. 'textures/' .. name .. '.png' end

-- Tiles and rock: the texture replaces kd; the normal maps bevel the tiles and roughen the rock.
local function tiles(colour)
  return gr.material({0.7, 0.7, 0.7}, {0.04, 0.04, 0.04}, 40, 0, 1, 0,
                     texture('tiles_' .. colour), texture('tiles_norm'))
end
rock    = gr.material({0.6, 0.55, 0.5}, {0, 0, 0}, 0, 0, 1, 0, texture('rock'), texture('rock_norm'))
ceiling = gr.material({0.75, 0.75, 0.73}, {0, 0, 0}, 0)
-- Clear water (index 1.33) with Perlin ripples bending its normals; glass (1.5); silver; copper.
water   = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.33, 0.25)
glass   = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.5)
silver  = gr.material({0.02, 0.02, 0.02}, {0.92, 0.92, 0.94}, 400)
copper  = gr.material({0.35, 0.17, 0.1}, {0.55, 0.35, 0.22}, 80)

root = gr.node('room')
-- A wall: a slab 0.1 thick around the box [-1, 1]^3, extending past the corners.
local function wall(name, mat, sx, sy, sz, tx, ty, tz)
  local w = gr.cube(name)
  w:set_material(mat); w:scale(sx, sy, sz); w:translate(tx, ty, tz)
  root:add_child(w)
end
wall('floor',   rock,             2.2, 0.1, 2.2, -1.1, -1.1, -1.1)
wall('ceiling', ceiling,          2.2, 0.1, 2.2, -1.1,  1.0, -1.1)
wall('back',    tiles('white'),   2.2, 2.2, 0.1, -1.1, -1.1, -1.1)
wall('left',    tiles('red'),     0.1, 2.2, 2.2, -1.1, -1.1, -1.1)
wall('right',   tiles('green'),   0.1, 2.2, 2.2,  1.0, -1.1, -1.1)

-- The water: a closed body 2.1 wide, its wavy surface at y = -0.2. Its sides and bottom lie
-- inside the walls' and floor's slabs, hidden, so no face coincides with a wall's; only the
-- surface and the front face (z = 1.05, the box is open there) are seen.
pool = gr.water_mesh('water', {n = WATER_N or 1001, seed = 7, size = 2.1, amplitude = 0.012,
                               wavelength = 0.45, spread = 1.2, depth = 0.85})
pool:set_material(water); pool:translate(0, -0.2, 0); root:add_child(pool)

ball = gr.nh_sphere('glass ball', {-0.38, -0.72, 0.2}, 0.26)
ball:set_material(glass); root:add_child(ball)
mirror = gr.nh_sphere('silver ball', {0.45, -0.76, -0.4}, 0.22)
mirror:set_material(silver); root:add_child(mirror)

-- The ring lies flat on the floor: a cylinder minus a thinner, taller one, turned upright.
outer = gr.cylinder('outer'); outer:set_material(copper)
inner = gr.cylinder('inner'); inner:set_material(copper); inner:scale(0.86, 0.86, 1.5)
ring = gr.difference('ring', outer, inner)
ring:rotate('x', 90); ring:scale(0.2, 0.025, 0.2); ring:translate(0.3, -0.975, 0.45)
root:add_child(ring)

-- A 0.3 x 0.3 panel under the ceiling, emitting down (u x v = -y), physical falloff;
-- a power turns photon mapping on (the photon counts come from the command line).
lamp = gr.area_light({0, 0.99, 0}, {3.5, 3.5, 3.5}, {0, 0, 1}, 1, nil, {0.3, 0, 0}, {0, 0, 0.3})

-- The budgets this scene needs (the command line's flags override them): every photon that
-- lights the floor under the water is a caustic photon, so the caustic map is large; the
-- irradiance cache gathers at its own records, so 4 gather rays per sample serve only the few
-- points no record reaches; shadow rays from
-- under the water always meet its surface, so 2 per sample suffice.
gr.settings{caustic_photons = 4000000, photons = 400000, gather_rays = 4, light_samples = 2}
