//! The `gr` functions that make lights: the course's point light, the extended project's area
//! and sphere lights, and glTF's spot and directional lights ([`crate::light`] says what each
//! sheds and how it emits photons).
//!
//! ```lua
//! lamp = gr.light({0, 0.5, 0}, {0.7, 0.5, 0.9}, {1, 0, 0}, 10000, 200000)
//! panel = gr.area_light({0, 2, 0}, {4, 4, 4}, {0, 0, 1}, nil, nil, {0.5, 0, 0}, {0, 0, 0.5})
//! ball = gr.sphere_light({0, 0.4, 0}, {1, 1, 1}, {0, 0, 1}, nil, nil, 0.05)
//! spot = gr.spot_light({0, 2, 0}, {0, -1, 0}, {1, 1, 1}, 15, 20)      -- degrees
//! sun = gr.directional_light({-0.3, -1, -0.2}, {0.3, 0.3, 0.3})
//! ```
//!
//! Spot and directional lights are physical (inverse-square for the spot, none for the sun):
//! they take no falloff. Their `power` and `num_photons`, optional last, steer the photon budget
//! as the others' do.

use super::State;
use super::gr::charge;
use crate::desc::{LightDesc, LightId, LightShape};
use crate::lua::args::{Args, LightRef};
use glam::{DVec3, Vec3};
use mlua::{Lua, Value};

/// `gr.light(pos, rgb, falloff [, power [, num_photons]])`.
pub(super) fn gr_light(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    new_light(lua, s, a, LightShape::Point)
}

/// `gr.area_light(pos, rgb, falloff, power, num_photons, u, v)`: power and num_photons may be nil.
pub(super) fn gr_area_light(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let (u, v) = (a.point(6)?, a.point(7)?);
    let min_area = crate::range::MIN_LIGHT_SIZE * crate::range::MIN_LIGHT_SIZE;
    if u.cross(v).length() < min_area {
        return Err(a.bad(
            7,
            format!("the edges u and v must span a parallelogram of area at least {min_area:e} (not zero or parallel)"),
        ));
    }
    let (u, v) = (u.as_vec3(), v.as_vec3());
    new_light(lua, s, a, LightShape::Area { u, v })
}

/// `gr.sphere_light(pos, rgb, falloff, power, num_photons, radius)`.
pub(super) fn gr_sphere_light(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let radius = a.length(6, "radius")?;
    if radius < crate::range::MIN_LIGHT_SIZE {
        let min = crate::range::MIN_LIGHT_SIZE;
        return Err(a.bad(6, format!("radius {radius:e} is smaller than {min:e}")));
    }
    let radius = radius as f32;
    new_light(lua, s, a, LightShape::Sphere { radius })
}

/// `gr.spot_light(pos, dir, rgb, inner, outer [, power [, num_photons]])`: a spot at `pos`
/// shining along `dir`, of head-on colour `rgb`, full within `inner` degrees of its axis and
/// dark beyond `outer` (`0 ≤ inner ≤ outer ≤ 90`), glTF's falloff between.
pub(super) fn gr_spot_light(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let position = a.point(1)?.as_vec3();
    let direction = direction(a, 2)?;
    let colour = a.intensity(3)?;
    let (inner, outer) = (a.number(4)?, a.number(5)?);
    if !((0.0..=90.0).contains(&inner) && (0.0..=90.0).contains(&outer) && inner <= outer) {
        return Err(a.bad(
            5,
            format!(
                "spot angles must satisfy 0 <= inner <= outer <= 90 degrees, got inner {inner} and outer {outer}"
            ),
        ));
    }
    let (power, photons) = budget(a, 6)?;
    let shape = LightShape::Spot {
        direction,
        inner: inner.to_radians() as f32,
        outer: outer.to_radians() as f32,
    };
    push_light(
        lua,
        s,
        a,
        (shape, position, colour),
        [0.0, 0.0, 1.0],
        (power, photons),
    )
}

/// `gr.directional_light(dir, rgb [, power [, num_photons]])`: parallel light travelling along
/// `dir` from beyond the scene, lighting a surface facing it as `kd·rgb·cos θ` (irradiance
/// `π·rgb`).
pub(super) fn gr_directional_light(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let direction = direction(a, 1)?;
    let colour = a.intensity(2)?;
    let (power, photons) = budget(a, 3)?;
    let shape = LightShape::Directional { direction };
    push_light(
        lua,
        s,
        a,
        (shape, Vec3::ZERO, colour),
        [0.0, 0.0, 1.0],
        (power, photons),
    )
}

/// Checks argument `i` as a direction: a non-zero 3-tuple, returned normalised (in double
/// precision: `{0, -1e30, 0}` squared overflows `f32`).
fn direction(a: &Args, i: usize) -> mlua::Result<Vec3> {
    let d = a.dvec3(i)?.normalize_or_zero();
    if d == DVec3::ZERO {
        return Err(a.bad(i, "direction must not be zero"));
    }
    Ok(d.as_vec3())
}

/// Reads `gr.light`'s layout (position, colour, falloff, power, num_photons) for a light of
/// `shape`.
fn new_light(lua: &Lua, s: &mut State, a: &Args, shape: LightShape) -> mlua::Result<Value> {
    let position = a.point(1)?.as_vec3();
    let colour = a.intensity(2)?;
    let falloff = falloff(a, 3)?;
    let budget = budget(a, 4)?;
    push_light(lua, s, a, (shape, position, colour), falloff, budget)
}

/// Checks argument `i` as a falloff `{c0, c1, c2}`: each 0 or within the range, not all 0.
fn falloff(a: &Args, i: usize) -> mlua::Result<[f32; 3]> {
    let falloff64 = a.dvec3(i)?;
    let falloff = falloff64.as_vec3();
    let (min, max) = (crate::range::MIN_FALLOFF, crate::range::MAX_FALLOFF);
    if let Some(c) = falloff64
        .to_array()
        .into_iter()
        .find(|&c| c != 0.0 && !(min..=max).contains(&c))
    {
        return Err(a.bad(
            i,
            format!("falloff coefficient {c:e} must be 0 or in [{min:e}, {max:e}]"),
        ));
    }
    if falloff.min_element() < 0.0 || falloff.max_element() <= 0.0 {
        return Err(a.bad(
            i,
            format!(
                "falloff {{c0, c1, c2}} must be >= 0 and not all 0, got {{{}, {}, {}}}",
                falloff.x, falloff.y, falloff.z
            ),
        ));
    }
    Ok(falloff.to_array())
}

/// Checks the optional `power` (argument `i`) and `num_photons` (argument `i + 1`).
fn budget(a: &Args, i: usize) -> mlua::Result<(Option<f64>, Option<f64>)> {
    let power = a.opt_number(i)?;
    if let Some(p) = power
        && !(0.0..=crate::range::MAX_POWER).contains(&p)
    {
        let max = crate::range::MAX_POWER;
        return Err(a.bad(
            i,
            format!(
                "power must be in [0, {max:e}], got {}",
                crate::range::show(p)
            ),
        ));
    }
    let photons = a.opt_number(i + 1)?;
    if let Some(n) = photons
        && !(0.0..=crate::range::MAX_PHOTONS as f64).contains(&n)
    {
        return Err(a.bad(
            i + 1,
            format!(
                "photon count must be in [0, {}], got {n}",
                crate::range::MAX_PHOTONS
            ),
        ));
    }
    Ok((power, photons))
}

/// Adds the light of `shape` at `position` with `colour`, `falloff` and the photon budget
/// `(power, num_photons)` to the description, charged to the memory budget.
fn push_light(
    lua: &Lua,
    s: &mut State,
    a: &Args,
    (shape, position, colour): (LightShape, Vec3, Vec3),
    falloff: [f32; 3],
    (power, photons): (Option<f64>, Option<f64>),
) -> mlua::Result<Value> {
    charge(s, a, size_of::<LightDesc>(), "a light")?;
    let id = LightId(s.desc.lights.len() as u32);
    s.desc.lights.push(LightDesc {
        shape,
        position,
        colour,
        falloff,
        power: power.map(|p| p as f32),
        photons: photons.map(|n| n as u64),
        loc: a.loc.clone(),
    });
    Ok(Value::UserData(lua.create_userdata(LightRef(id))?))
}
