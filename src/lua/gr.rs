//! The `gr` table: every function a script can call, installed from one list of entries.
//!
//! The API is the CS488 A4 starter's (the course's `gr` module: nodes, primitives, materials, lights,
//! transforms, `gr.render`) plus the
//! extended ray tracer's commands, with every extra argument optional:
//!
//! ```lua
//! glass = gr.material({0.2, 0.2, 0.2}, {0.05, 0.05, 0.05}, 25, 0.8, 1.85, 0)
//! cone  = gr.cone('c')   -- apex at the origin, radius 1 at z = 1
//! ring  = gr.difference('ring', gr.cylinder('outer'), gr.cylinder('inner'))
//! light = gr.light({0, 0.5, 0}, {0.7, 0.5, 0.9}, {1, 0, 0}, 10000, 200000)
//! cow   = gr.mesh('cow', 'cow.obj')   -- resolved here, read when a scene is built
//! ```
//!
//! As in the course, one table is both the global `gr` and the source of every node method, so
//! `n:translate(1, 2, 3)` is `gr.translate(n, 1, 2, 3)` and `n:render(...)` is `gr.render(n, ...)`.
//! `gr.render` calls the [`RenderHook`](super::RenderHook) synchronously: the script carries on
//! after each image. An unknown name (`gr.spere`) fails at the line that used it and lists the
//! functions that exist.

use super::legacy::{self, Sign};
use super::{MAX_PIXELS, State, lights};
use crate::budget::At;
use crate::desc::{
    CameraDesc, CsgOp, LightId, MaterialDesc, MaterialId, MeshDesc, MeshFormat, MeshId, MeshSource,
    NodeDesc, NodeId, NodeKind, RenderDesc,
};
use crate::error::{Error, Fault};
use crate::lua::args::{Args, LightRef, MaterialRef, NodeRef, caller_loc, lua_err};
use glam::DAffine3;
use mlua::{Lua, MetaMethod, MultiValue, Table, UserData, Value};
use std::cell::RefCell;
use std::path::PathBuf;
use std::rc::Rc;

type GrFn = fn(&Lua, &mut State, &Args) -> mlua::Result<Value>;
/// A `gr` function returning several values (`node, lights = gr.gltf(...)`).
type GrMultiFn = fn(&Lua, &mut State, &Args) -> mlua::Result<MultiValue>;

/// A `gr` function of either list.
#[derive(Clone, Copy)]
enum Body {
    One(GrFn),
    Many(GrMultiFn),
}

/// How a `gr` function is meant to be called.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Call {
    /// `gr.sphere(...)`: listed when a script names an unknown function.
    Function,
    /// `n:translate(...)` (also `gr.translate(n, ...)`): a node method, not listed.
    Method,
}

/// Every `gr` function, in the order the unknown-function message lists them.
const GR: &[(&str, Call, GrFn)] = &[
    ("node", Call::Function, gr_node),
    ("joint", Call::Function, gr_joint),
    ("sphere", Call::Function, |l, s, a| {
        gr_simple(l, s, a, NodeKind::Sphere)
    }),
    ("cube", Call::Function, |l, s, a| {
        gr_simple(l, s, a, NodeKind::Cube)
    }),
    ("cylinder", Call::Function, |l, s, a| {
        gr_simple(l, s, a, NodeKind::Cylinder)
    }),
    ("cone", Call::Function, |l, s, a| {
        gr_simple(l, s, a, NodeKind::Cone)
    }),
    ("nh_sphere", Call::Function, gr_nh_sphere),
    ("nh_box", Call::Function, gr_nh_box),
    ("mesh", Call::Function, gr_mesh),
    ("water_mesh", Call::Function, gr_water_mesh),
    ("union", Call::Function, |l, s, a| {
        gr_csg(l, s, a, CsgOp::Union)
    }),
    ("intersection", Call::Function, |l, s, a| {
        gr_csg(l, s, a, CsgOp::Intersection)
    }),
    ("difference", Call::Function, |l, s, a| {
        gr_csg(l, s, a, CsgOp::Difference)
    }),
    ("material", Call::Function, gr_material),
    ("absorption", Call::Function, gr_absorption),
    ("roughness", Call::Function, gr_roughness),
    ("light", Call::Function, lights::gr_light),
    ("area_light", Call::Function, lights::gr_area_light),
    ("sphere_light", Call::Function, lights::gr_sphere_light),
    ("spot_light", Call::Function, lights::gr_spot_light),
    (
        "directional_light",
        Call::Function,
        lights::gr_directional_light,
    ),
    ("settings", Call::Function, |_, s, a| {
        super::settings::settings(s, a).map(|()| Value::Nil)
    }),
    ("render", Call::Function, gr_render),
    ("add_child", Call::Method, gr_add_child),
    ("set_material", Call::Method, gr_set_material),
    ("translate", Call::Method, gr_translate),
    ("scale", Call::Method, gr_scale),
    ("rotate", Call::Method, gr_rotate),
];

/// The `gr` functions returning several values, listed after [`GR`]'s.
const GR_MULTI: &[(&str, GrMultiFn)] = &[("gltf", super::gltf::gr_gltf)];

/// Registry key of the `gr` table, which node values use as their method table.
const GR_KEY: &str = "caustic.gr";

/// Sets the global `gr` to a table of [`GR`]'s functions, each working on `state`.
pub(super) fn install(lua: &Lua, state: &Rc<RefCell<State>>) -> mlua::Result<()> {
    let gr = lua.create_table()?;
    let single = GR.iter().map(|&(name, _, f)| (name, Body::One(f)));
    let multi = GR_MULTI.iter().map(|&(name, f)| (name, Body::Many(f)));
    for (name, f) in single.chain(multi) {
        let st = Rc::clone(state);
        let func = lua.create_function(move |lua, vals: MultiValue| {
            let args = Args::new(lua, name, vals);
            let mut s = st
                .try_borrow_mut()
                .map_err(|_| args.fail(format!("gr.{name} called while a render is running")))?;
            match f {
                Body::Many(many) => many(lua, &mut s, &args),
                Body::One(one) => one(lua, &mut s, &args).map(|v| MultiValue::from_iter([v])),
            }
        })?;
        gr.raw_set(name, func)?;
    }
    // Unknown names fail loudly at the line that used them instead of yielding nil.
    let meta = lua.create_table()?;
    meta.raw_set(
        "__index",
        lua.create_function(|lua, (_t, key): (Value, Value)| -> mlua::Result<Value> {
            let key = key.to_string().unwrap_or_else(|_| "?".into());
            let listed: Vec<&str> = GR
                .iter()
                .filter(|(_, call, _)| *call == Call::Function)
                .map(|(name, _, _)| *name)
                .chain(GR_MULTI.iter().map(|(name, _)| *name))
                .collect();
            Err(lua_err(Error::fault_at(
                Fault::UnknownFunction,
                &caller_loc(lua),
                format!(
                    "unknown function gr.{key} (caustic has gr.{})",
                    listed.join(", gr.")
                ),
            )))
        })?,
    )?;
    gr.set_metatable(Some(meta))?;
    lua.set_named_registry_value(GR_KEY, &gr)?;
    lua.globals().set("gr", gr)?;
    Ok(())
}

/// Charges `bytes` for a description entry made at `a`'s line to the command's budget.
pub(super) fn charge(s: &State, a: &Args, bytes: usize, what: &str) -> mlua::Result<()> {
    let at = At::Script(&a.loc);
    s.desc
        .budget
        .charge(bytes as u64, what, at)
        .map_err(lua_err)
}

fn new_node(
    lua: &Lua,
    s: &mut State,
    a: &Args,
    name: String,
    kind: NodeKind,
) -> mlua::Result<Value> {
    let bytes = size_of::<NodeDesc>() + name.len();
    charge(
        s,
        a,
        bytes,
        &format!("a node named by {} bytes", name.len()),
    )?;
    let id = s.desc.add_node(name, kind, a.loc.clone());
    Ok(Value::UserData(lua.create_userdata(NodeRef(id))?))
}

fn gr_node(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    new_node(lua, s, a, a.string(1)?, NodeKind::Group)
}

fn gr_joint(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let name = a.string(1)?;
    // The A4 starter stores the joint ranges and applies nothing: a joint is a plain node.
    a.dvec3(2)?;
    a.dvec3(3)?;
    new_node(lua, s, a, name, NodeKind::Group)
}

fn gr_simple(lua: &Lua, s: &mut State, a: &Args, kind: NodeKind) -> mlua::Result<Value> {
    new_node(lua, s, a, a.string(1)?, kind)
}

fn gr_nh_sphere(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let name = a.string(1)?;
    let center = a.point(2)?;
    let radius = a.length(3, "radius")?;
    new_node(lua, s, a, name, NodeKind::NhSphere { center, radius })
}

fn gr_nh_box(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let name = a.string(1)?;
    let corner = a.point(2)?;
    let size = a.length(3, "size")?;
    new_node(lua, s, a, name, NodeKind::NhBox { corner, size })
}

fn gr_mesh(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let name = a.string(1)?;
    let id = match a.get(2) {
        Some(Value::Table(_)) => {
            s.saw(Sign::InlineMesh, &a.loc);
            super::inline::inline_mesh(s, a)?
        }
        _ => mesh_from_file(s, a, &a.string(2)?)?,
    };
    new_node(lua, s, a, name, NodeKind::Mesh(id))
}

/// `gr.water_mesh(name, {params})`: a generated, cached wave surface (`super::generated`).
fn gr_water_mesh(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let name = a.string(1)?;
    let id = super::generated::water_mesh(s, a)?;
    new_node(lua, s, a, name, NodeKind::Mesh(id))
}

/// Returns the fault of a file the scene cannot read: outside its folders, or not found.
pub(super) fn input_fault(message: &str) -> Fault {
    if message.contains("outside the folders a scene may read") {
        Fault::Sandbox
    } else {
        Fault::NotFound
    }
}

/// Resolves a mesh file and checks its format; the file is read when a scene is built.
pub(super) fn mesh_from_file(s: &mut State, a: &Args, given: &str) -> mlua::Result<MeshId> {
    let path = s
        .resolve_input("mesh file", given)
        .map_err(|m| a.fault(input_fault(&m), m))?;
    mesh_at(s, a, given, path)
}

/// Adds the mesh file at `path` (named `given` by the script, or made by caustic itself) to
/// the description, once per file.
pub(super) fn mesh_at(s: &mut State, a: &Args, given: &str, path: PathBuf) -> mlua::Result<MeshId> {
    mesh_part_at(s, a, given, path, None)
}

/// [`mesh_at`] for glTF mesh `part` of the file read alone in its own frame (`gr.gltf`), or the
/// whole file when `None`; each (file, part) is added once.
pub(super) fn mesh_part_at(
    s: &mut State,
    a: &Args,
    given: &str,
    path: PathBuf,
    part: Option<u32>,
) -> mlua::Result<MeshId> {
    let key = (
        std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone()),
        part,
    );
    if let Some(&id) = s.mesh_cache.get(&key) {
        return Ok(id);
    }
    let Some(format) = MeshFormat::from_path(&path) else {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        return Err(a.fault(Fault::MeshLoad, format!(
            "cannot load mesh '{given}': unsupported format '.{ext}' (caustic reads .obj, .gltf and .glb)"
        )));
    };
    let bytes = size_of::<MeshDesc>() + given.len() + path.as_os_str().len();
    charge(s, a, bytes, "a mesh entry")?;
    let id = MeshId(s.desc.meshes.len() as u32);
    s.desc.meshes.push(MeshDesc {
        source: MeshSource::File {
            given: given.to_string(),
            path,
            format,
            part,
        },
        loc: a.loc.clone(),
    });
    s.mesh_cache.insert(key, id);
    Ok(id)
}

fn gr_csg(lua: &Lua, s: &mut State, a: &Args, op: CsgOp) -> mlua::Result<Value> {
    let name = a.string(1)?;
    let mut operands = [a.node(2)?, a.node(3)?];
    for (k, id) in operands.iter_mut().enumerate() {
        if !s.desc.node(*id).kind.is_geometry() {
            return Err(a.bad(k + 2, "Geometry node expected"));
        }
    }
    let [x, y] = operands;
    new_node(lua, s, a, name, NodeKind::Csg { op, a: x, b: y })
}

fn gr_material(lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let kd = a.reflectance(1)?;
    let ks = a.reflectance(2)?;
    let shininess = a.number(3)?;
    if shininess < 0.0 {
        return Err(a.bad(3, format!("Phong exponent must be >= 0, got {shininess}")));
    }
    let transparency = a.opt_number(4)?.unwrap_or(0.0);
    if !(0.0..=1.0).contains(&transparency) {
        return Err(a.bad(
            4,
            format!("transparency must be in [0, 1], got {transparency}"),
        ));
    }
    let ior = a.opt_number(5)?.unwrap_or(1.0);
    let (min_ior, max_ior) = (crate::range::MIN_IOR, crate::range::MAX_IOR);
    if transparency > 0.0 && !(min_ior..=max_ior).contains(&ior) {
        return Err(a.bad(
            5,
            format!(
                "index of refraction must be in [{min_ior}, {max_ior}] (below 1: relative to the solid around), got {ior}"
            ),
        ));
    }
    let perlin_scale = a.opt_number(6)?.unwrap_or(0.0);
    if perlin_scale < 0.0 {
        return Err(a.bad(6, format!("Perlin scale must be >= 0, got {perlin_scale}")));
    }
    let mut image = |i: usize, what: &str| -> mlua::Result<Option<PathBuf>> {
        match a.opt_string(i)? {
            None => Ok(None),
            Some(given) => match s.resolve_input(what, &given) {
                Ok(p) => Ok(Some(p)),
                Err(m) if s.desc.missing_textures_warn => {
                    if s.warned_images.insert(given.clone()) {
                        s.warn(&a.loc, format!("{m}; rendering with kd instead"));
                    }
                    Ok(None)
                }
                Err(m) => Err(a.fault(input_fault(&m), m)),
            },
        }
    };
    let texture = image(7, "texture")?;
    let bump = image(8, "bump map")?;
    let paths = [&texture, &bump].map(|p| p.as_ref().map_or(0, |p| p.as_os_str().len()));
    charge(
        s,
        a,
        size_of::<MaterialDesc>() + paths[0] + paths[1],
        "a material",
    )?;
    let excess = crate::range::excess_albedo(kd.to_array(), ks.to_array(), transparency as f32);
    if let Some(m) = excess
        && s.warned_albedo.insert(a.loc.to_string())
    {
        s.warn(&a.loc, format!("gr.material: {m}"));
    }
    let id = MaterialId(s.desc.materials.len() as u32);
    s.desc.materials.push(MaterialDesc {
        kd,
        ks,
        shininess: shininess as f32,
        transparency: transparency as f32,
        ior: if ior > 0.0 { ior as f32 } else { 1.0 },
        absorption: glam::Vec3::ZERO,
        roughness: 0.0,
        perlin_scale: perlin_scale as f32,
        texture,
        bump,
        loc: a.loc.clone(),
    });
    Ok(Value::UserData(lua.create_userdata(MaterialRef(id))?))
}

/// `gr.absorption(material, colour, distance)`: the interior of a transparent solid of
/// `material` keeps `colour` (each channel in `(0, 1]`) of the light that crosses `distance`
/// of it (Beer–Lambert, as glTF's `KHR_materials_volume` and Mitsuba's homogeneous medium say
/// it); `{1, 1, 1}` is clear.
fn gr_absorption(_lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let material = a.material(1)?;
    let colour = a.colour(2)?;
    if colour.min_element() <= 0.0 || colour.max_element() > 1.0 {
        return Err(a.bad(
            2,
            format!(
                "the colour kept must be in (0, 1] per channel, got {{{}, {}, {}}}",
                colour.x, colour.y, colour.z
            ),
        ));
    }
    let distance = a.length(3, "distance")?;
    if distance < crate::range::MIN_LIGHT_SIZE {
        let min = crate::range::MIN_LIGHT_SIZE;
        return Err(a.bad(
            3,
            format!("distance must be at least {min}, got {distance}"),
        ));
    }
    let m = &mut s.desc.materials[material.0 as usize];
    m.absorption = crate::material::absorption(colour.to_array(), distance as f32);
    if m.transparency <= 0.0 {
        s.warn(
            &a.loc,
            "gr.absorption on an opaque material (t = 0): nothing enters it to be absorbed".into(),
        );
    }
    Ok(Value::Nil)
}

/// `gr.roughness(material, roughness)`: the material's mirror lobe becomes a rough conductor
/// and its dielectric interface a rough one (GGX, `alpha = roughness²`,
/// `crate::material::microfacet`), replacing the mirror, the Phong highlight and the smooth
/// interface; 0 is smooth.
fn gr_roughness(_lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let material = a.material(1)?;
    let roughness = a.number(2)?;
    if !(0.0..=1.0).contains(&roughness) {
        return Err(a.bad(2, format!("roughness must be in [0, 1], got {roughness}")));
    }
    s.desc.materials[material.0 as usize].roughness = roughness as f32;
    Ok(Value::Nil)
}

fn gr_render(_lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let root = a.node(1)?;
    let file = a.string(2)?;
    let width = a.image_size(3)?;
    let height = a.image_size(4)?;
    if width as u64 * height as u64 > MAX_PIXELS {
        return Err(a.fail(format!(
            "image {width}x{height} is larger than {MAX_PIXELS} pixels"
        )));
    }
    let eye = a.point(5)?.as_vec3();
    // Directions are normalised in double precision: {0, 0, -1e30} squared overflows f32.
    let view = a.dvec3(6)?.normalize_or_zero().as_vec3();
    let up = a.dvec3(7)?.normalize_or_zero().as_vec3();
    let fov_deg = a.number(8)?;
    let ambient = a.intensity(9)?;
    let lights = a.lights(10)?;
    if view.length_squared() == 0.0 {
        return Err(a.bad(6, "view direction must not be zero"));
    }
    if view.normalize().cross(up).length_squared() < 1e-12 {
        return Err(a.bad(7, "up must not be zero or parallel to the view direction"));
    }
    if !(fov_deg > 0.0 && fov_deg < 180.0) {
        return Err(a.bad(
            8,
            format!("field of view must be in (0, 180) degrees, got {fov_deg}"),
        ));
    }
    let render = RenderDesc {
        root,
        output: s.resolve_output(&file),
        width,
        height,
        camera: CameraDesc {
            eye,
            view,
            up,
            fov_deg: fov_deg as f32,
        },
        ambient,
        lights,
        loc: a.loc.clone(),
        settings: s
            .desc
            .settings
            .iter()
            .flat_map(|(_, tokens)| tokens.iter().cloned())
            .collect(),
    };
    let tokens: usize = render
        .settings
        .iter()
        .map(|t| size_of::<String>() + t.len())
        .sum();
    let lights = render.lights.len() * size_of::<LightId>();
    let bytes = size_of::<RenderDesc>() + tokens + lights + render.output.as_os_str().len();
    charge(s, a, bytes, "a render entry and its settings")?;
    s.desc.renders.push(render.clone());
    legacy::before_render(s, &render);
    let State { desc, hook, .. } = s;
    hook(desc, &render).map_err(|e| match e {
        e @ (Error::Script { .. } | Error::Lua(_) | Error::Interrupted(_)) => lua_err(e),
        other => a.fail(other.to_string()),
    })?;
    Ok(Value::Nil)
}

fn gr_add_child(_lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let parent = a.node(1)?;
    let child = a.node(2)?;
    if parent == child {
        return Err(a.bad(2, "a node cannot be its own child"));
    }
    link(s, a, parent, child)?;
    Ok(Value::Nil)
}

/// Makes `child` a child of `parent` at the script line of `a`, charged to the budget.
pub(super) fn link(s: &mut State, a: &Args, parent: NodeId, child: NodeId) -> mlua::Result<()> {
    charge(
        s,
        a,
        size_of::<(NodeId, crate::error::Loc)>(),
        "a child entry",
    )?;
    s.desc.nodes[parent.0 as usize]
        .children
        .push((child, a.loc.clone()));
    Ok(())
}

fn gr_set_material(_lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    let node = a.node(1)?;
    let material = a.material(2)?;
    if !s.desc.node(node).kind.is_geometry() {
        return Err(a.bad(1, "Geometry node expected"));
    }
    s.desc.nodes[node.0 as usize].material = Some(material);
    Ok(Value::Nil)
}

/// Composes the transform `t` of one `translate`, `scale` or `rotate` call into node 1's matrix,
/// in the script's dialect: the one place call order becomes a matrix.
fn compose(s: &mut State, a: &Args, t: DAffine3) -> mlua::Result<Value> {
    let node = a.node(1)?;
    let m = &mut s.desc.nodes[node.0 as usize].transform;
    *m = s.dialect.compose(*m, t);
    if let Some(w) = &mut s.watch {
        w.compose(node, t);
    }
    Ok(Value::Nil)
}

fn gr_translate(_lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    a.node(1)?;
    let t = DAffine3::from_translation(a.dvec3_at(2)?);
    compose(s, a, t)
}

fn gr_scale(_lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    a.node(1)?;
    let t = DAffine3::from_scale(a.dvec3_at(2)?);
    compose(s, a, t)
}

fn gr_rotate(_lua: &Lua, s: &mut State, a: &Args) -> mlua::Result<Value> {
    a.node(1)?;
    let axis = a.string(2)?;
    if axis.chars().count() != 1 {
        return Err(a.bad(2, "Single character expected"));
    }
    let angle = a.number(3)?.to_radians();
    let t = match axis.to_ascii_lowercase().as_str() {
        "x" => DAffine3::from_rotation_x(angle),
        "y" => DAffine3::from_rotation_y(angle),
        "z" => DAffine3::from_rotation_z(angle),
        _ => return Err(a.bad(2, "Axis must be x, y or z")),
    };
    compose(s, a, t)
}

impl UserData for NodeRef {
    fn add_methods<M: mlua::UserDataMethods<Self>>(methods: &mut M) {
        // Node methods are the `gr` functions themselves, as in the course where `gr` is the
        // node metatable's `__index`.
        methods.add_meta_function(MetaMethod::Index, |lua, (_node, key): (Value, Value)| {
            let gr: Table = lua.named_registry_value(GR_KEY)?;
            let f: Value = gr.raw_get(key.clone())?;
            if f.is_nil() {
                let key = key.to_string().unwrap_or_else(|_| "?".into());
                return Err(lua_err(Error::fault_at(
                    Fault::UnknownFunction,
                    &caller_loc(lua),
                    format!("gr.node has no method '{key}'"),
                )));
            }
            Ok(f)
        });
        methods.add_meta_method(MetaMethod::ToString, |_, node, ()| {
            Ok(format!("gr.node #{}", node.0.0))
        });
    }
}

impl UserData for MaterialRef {
    fn add_methods<M: mlua::UserDataMethods<Self>>(methods: &mut M) {
        methods.add_meta_method(MetaMethod::ToString, |_, m, ()| {
            Ok(format!("gr.material #{}", m.0.0))
        });
    }
}

impl UserData for LightRef {
    fn add_methods<M: mlua::UserDataMethods<Self>>(methods: &mut M) {
        methods.add_meta_method(MetaMethod::ToString, |_, l, ()| {
            Ok(format!("gr.light #{}", l.0.0))
        });
    }
}
