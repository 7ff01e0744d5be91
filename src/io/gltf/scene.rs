//! glTF files as whole scenes: `caustic render scene.glb` reads the file's default scene into a
//! [`SceneDesc`], as a script would describe it, and renders it like any other.
//!
//! ```text
//! caustic render pool.glb                       # the first camera, 800 pixels wide
//! caustic render pool.glb --camera Closeup --size 1024 768 -o closeup.png
//! caustic info pool.glb                         # what it uses, and what caustic ignores
//! ```
//!
//! # What the description holds
//! - **Geometry**: the whole file as one `gr.mesh` node ([`super::load_gltf`]: every primitive
//!   under its node's transform, with the file's materials). Emissive primitives are lights,
//!   not geometry ([`crate::scene::emitters`]).
//! - **Camera**: the node of the camera `--camera` names (a camera's or its node's name), else
//!   of the first perspective camera in the scene's node order. glTF cameras look down their
//!   node's −Z with +Y up; `yfov` is the vertical field of view. The image is `--size` pixels, or
//!   [`DEFAULT_WIDTH`] wide at the camera's `aspectRatio` (4:3 without one). A file without a
//!   camera is framed from the front (+Z), a little above, its bounds filling the view.
//! - **Punctual lights** (`KHR_lights_punctual`) in the units Blender's exporter writes, all
//!   at 683 lm/W, as Blender converts its watts, so that lights and emissive surfaces (whose
//!   `emissiveFactor × emissiveStrength` Blender writes as the radiance Cycles renders) agree.
//!   In caustic's terms (the course's `rgb` is a physical quantity over π, [`crate::light`])
//!   every kind is `rgb = color · intensity / (683 π)`:
//!   - a **point** light of `intensity` cd is `intensity / 683` W/sr, with physical
//!     (inverse-square) falloff;
//!   - a **spot** is that point light shining down its node's −Z, times glTF's angular falloff
//!     between `innerConeAngle` and `outerConeAngle` ([`crate::light::spot`]: the
//!     specification's squared ramp in the cosine, exactly 0 beyond the outer cone). Its flux is
//!     `intensity/683 · ∫ t² dω`, less than a point light's: Blender writes a spot of P watts
//!     as the point light of P watts, whose cone then cuts it;
//!   - a **directional** light of `intensity` lx is an irradiance of `intensity / 683` W/m² on
//!     a surface facing it, travelling down its node's −Z from beyond the scene
//!     ([`crate::light::directional`]); a surface of reflectance `kd` at angle θ to it shows
//!     `kd/π · E · cos θ`.
//!
//!   Lights and emitters are physical: each has a `power` (its flux summed over the channels;
//!   a directional light's through the disc that covers the file's bounds), so photon mapping
//!   is on and shares the photons by flux.
//! - **Bounds**: a light's `color × intensity / (683 π)` must lie within a light colour's range
//!   ([`crate::range::MAX_INTENSITY`]), its position within the coordinate range, a spot's cone
//!   angles within `0 ≤ inner ≤ outer ≤ π/2`, and a spot's or directional light's node must
//!   give it a direction; else the file is refused, with the light named (by its name, or
//!   `light N` by its index). So is a file placing more than [`MAX_LIGHTS`] punctual lights.
//! - **A file with no light at all** (no punctual light and no emissive material, as many
//!   sample models) gets a point light at the camera, bright enough that the middle of its
//!   bounds receives an irradiance of 1 W/m², and a warning says so.
//!
//! What caustic cannot honour (animations, skins, morph targets, orthographic cameras, alpha,
//! vertex colours, occlusion and transmission textures, extensions it does not read) and what it stands in for (an emissive texture's pattern by its mean colour,
//! every sampler by bilinear repeating lookups, texture coordinate sets beyond the first by the
//! first) is listed in [`SceneDesc::warnings`], printed once by `caustic render` and
//! `caustic info`: never silently dropped. The base colour, metallic-roughness and normal
//! textures, embedded or not, are read ([`super::load_gltf`]).

use super::{GltfError, placements, read_document};
use crate::budget::Budget;
use crate::desc::{
    CameraDesc, LightDesc, LightShape, MeshDesc, MeshFormat, MeshSource, NodeKind, RenderDesc,
    SceneDesc,
};
use crate::error::Loc;
use glam::{DAffine3, DVec3, Vec3};
use gltf::Document;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Image width when neither `--size` nor anything else sets it.
pub const DEFAULT_WIDTH: u32 = 800;

/// Most punctual lights a file may place: caustic samples every light at every shaded point,
/// so a file of a million lights would render for days.
pub const MAX_LIGHTS: usize = 1024;

/// Lumens per watt: how Blender's glTF exporter turns watts into candela and lux, and how
/// caustic turns them back.
pub const LUMENS_PER_WATT: f32 = 683.0;

/// The extensions whose meaning caustic renders; any other in `extensionsUsed` is listed.
const HONOURED: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
    "KHR_materials_volume",
];

/// How to view a glTF scene: the command line's choices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct View {
    /// `--camera NAME`: a camera by its own or its node's name; `None`: the first.
    pub camera: Option<String>,
    /// `--size W H`; `None`: [`DEFAULT_WIDTH`] wide at the camera's aspect ratio.
    pub size: Option<(u32, u32)>,
    /// Where the image goes.
    pub output: PathBuf,
}

/// Reads the glTF file at `path` as a scene viewed by `view`; the description draws on
/// `budget` (whose read scope bounds the files the glTF file may name).
pub fn describe_scene(path: &Path, view: &View, budget: Budget) -> Result<SceneDesc, GltfError> {
    let (doc, _) = read_document(path)?;
    let invalid = |message: String| GltfError::Invalid {
        path: path.to_owned(),
        message,
    };
    let placed = placements(&doc).map_err(invalid)?;
    let loc = Loc {
        file: Arc::from(path.display().to_string()),
        line: 0,
    };
    let mut desc = SceneDesc {
        budget,
        ..SceneDesc::default()
    };
    let root = desc.add_node("scene", NodeKind::Group, loc.clone());
    let mesh = crate::desc::MeshId(0);
    desc.meshes.push(MeshDesc {
        source: MeshSource::File {
            given: path.display().to_string(),
            path: path.to_owned(),
            format: MeshFormat::Gltf,
            part: None,
        },
        loc: loc.clone(),
    });
    let geometry = desc.add_node("geometry", NodeKind::Mesh(mesh), loc.clone());
    desc.nodes[root.0 as usize]
        .children
        .push((geometry, loc.clone()));

    let bounds = scene_bounds(&placed);
    let (camera, aspect) = camera(&placed, view.camera.as_deref(), bounds, path)?;
    let (width, height) = view.size.unwrap_or_else(|| {
        let h = (DEFAULT_WIDTH as f32 / aspect.unwrap_or(4.0 / 3.0)).round();
        (DEFAULT_WIDTH, (h as u32).clamp(1, 16 * DEFAULT_WIDTH))
    });
    let mut warnings = unsupported(&doc);
    for (node, world) in &placed {
        let Some(light) = node.light() else { continue };
        let d = punctual_light(&light, world, bounds, &loc).map_err(invalid)?;
        if desc.lights.len() == MAX_LIGHTS {
            return Err(GltfError::Unsupported {
                path: path.to_owned(),
                message: format!(
                    "more than {MAX_LIGHTS} punctual lights (node {}); caustic samples every \
                     light at every shaded point",
                    node.index()
                ),
            });
        }
        desc.lights.push(d);
    }
    let emissive = doc
        .materials()
        .any(|m| m.emissive_factor().iter().any(|&f| f > 0.0));
    if desc.lights.is_empty() && !emissive {
        let centre = (bounds.0 + bounds.1) / 2.0;
        let d2 = (centre - camera.eye.as_dvec3()).length_squared().max(1e-6) as f32;
        desc.lights.push(LightDesc {
            shape: LightShape::Point,
            position: camera.eye,
            colour: Vec3::splat(d2 / std::f32::consts::PI),
            falloff: [0.0, 0.0, 1.0],
            power: None,
            photons: None,
            loc: loc.clone(),
        });
        warnings.push(
            "the file has no light caustic renders (no punctual light, no emissive \
             material): it is lit by a point light at the camera"
                .to_owned(),
        );
    }
    desc.renders.push(RenderDesc {
        root,
        output: view.output.clone(),
        width,
        height,
        camera,
        ambient: Vec3::ZERO,
        lights: (0..desc.lights.len() as u32)
            .map(crate::desc::LightId)
            .collect(),
        loc,
        settings: Vec::new(),
    });
    desc.warnings = warnings;
    Ok(desc)
}

/// Returns the world bounds of the scene's mesh nodes from their POSITION accessors' `min` and
/// `max` (which glTF requires), or the unit cube round the origin when none gives them.
pub(super) fn scene_bounds(placed: &[(gltf::Node, DAffine3)]) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for (node, world) in placed {
        let Some(mesh) = node.mesh() else { continue };
        for prim in mesh.primitives() {
            let b = prim.bounding_box();
            let (a, c) = (
                DVec3::from_array(b.min.map(f64::from)),
                DVec3::from_array(b.max.map(f64::from)),
            );
            for k in 0..8 {
                let corner = DVec3::new(
                    if k & 1 == 0 { a.x } else { c.x },
                    if k & 2 == 0 { a.y } else { c.y },
                    if k & 4 == 0 { a.z } else { c.z },
                );
                let p = world.transform_point3(corner);
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    let sane = lo.is_finite() && hi.is_finite() && (hi - lo).max_element() < 1e7;
    if sane {
        (lo, hi)
    } else {
        (DVec3::splat(-1.0), DVec3::splat(1.0))
    }
}

/// Returns the camera `name` picks (or the first perspective one, or a framing of `bounds`)
/// and its aspect ratio, if the file gives one.
fn camera(
    placed: &[(gltf::Node, DAffine3)],
    name: Option<&str>,
    bounds: (DVec3, DVec3),
    path: &Path,
) -> Result<(CameraDesc, Option<f32>), GltfError> {
    let with_camera = placed
        .iter()
        .filter_map(|(node, world)| node.camera().map(|c| (node, c, world)));
    let chosen = match name {
        Some(want) => {
            let found = with_camera
                .clone()
                .find(|(node, c, _)| c.name() == Some(want) || node.name() == Some(want));
            if found.is_none() {
                let names: Vec<String> = with_camera
                    .map(|(node, c, _)| {
                        c.name()
                            .or(node.name())
                            .map_or(format!("camera {}", c.index()), str::to_owned)
                    })
                    .collect();
                return Err(GltfError::Invalid {
                    path: path.to_owned(),
                    message: format!(
                        "--camera {want}: no camera of that name (the scene has {})",
                        if names.is_empty() {
                            "none".to_owned()
                        } else {
                            names.join(", ")
                        }
                    ),
                });
            }
            found
        }
        None => with_camera
            .clone()
            .find(|(_, c, _)| matches!(c.projection(), gltf::camera::Projection::Perspective(_))),
    };
    let Some((node, cam, world)) = chosen else {
        return Ok((framing(bounds), None));
    };
    let gltf::camera::Projection::Perspective(p) = cam.projection() else {
        return Err(GltfError::Unsupported {
            path: path.to_owned(),
            message: format!(
                "camera of node {} is orthographic; caustic renders perspective cameras",
                node.index()
            ),
        });
    };
    let fov_deg = p.yfov().to_degrees();
    if !(fov_deg > 0.0 && fov_deg < 180.0) {
        return Err(GltfError::Invalid {
            path: path.to_owned(),
            message: format!(
                "camera {} has yfov {} radians; it must lie in (0, π)",
                cam.index(),
                p.yfov()
            ),
        });
    }
    let view = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(DVec3::Y).normalize_or_zero();
    if view == DVec3::ZERO || up == DVec3::ZERO || view.cross(up).length() < 1e-6 {
        return Err(GltfError::Invalid {
            path: path.to_owned(),
            message: format!("camera node {} has a degenerate transform", node.index()),
        });
    }
    let eye = world.translation.as_vec3();
    crate::range::coordinate(eye.to_array()).map_err(|e| GltfError::Invalid {
        path: path.to_owned(),
        message: format!("camera node {}: {e}", node.index()),
    })?;
    let aspect = p
        .aspect_ratio()
        .filter(|a| a.is_finite() && (1e-3..=1e3).contains(a));
    Ok((
        CameraDesc {
            eye,
            view: view.as_vec3(),
            up: up.as_vec3(),
            fov_deg,
        },
        aspect,
    ))
}

/// Returns a camera that frames `bounds` from the front (+Z) and a little above, with a 40°
/// vertical field of view.
fn framing((lo, hi): (DVec3, DVec3)) -> CameraDesc {
    let fov: f64 = 40.0;
    let centre = (lo + hi) / 2.0;
    let radius = ((hi - lo).length() / 2.0).max(1e-3);
    let distance = 1.1 * radius / (fov.to_radians() / 2.0).sin();
    let from = DVec3::new(0.0, 0.35, 1.0).normalize();
    let eye = centre + from * distance;
    CameraDesc {
        eye: eye.as_vec3(),
        view: (-from).as_vec3(),
        up: Vec3::Y,
        fov_deg: fov as f32,
    }
}

/// Returns the light a punctual light at `world` makes, in a file whose geometry lies in
/// `bounds`; a colour, intensity, position, direction or cone angle out of range is an error
/// naming the light.
///
/// The units: a point or spot light of `intensity` cd is `intensity/683` W/sr, a directional
/// light of `intensity` lx is `intensity/683` W/m², and either is `rgb = color·intensity /
/// (683 π)` in caustic's terms (see the module doc). Spots and directional lights shine down
/// their node's −Z.
pub(super) fn punctual_light(
    light: &gltf::khr_lights_punctual::Light,
    world: &DAffine3,
    bounds: (DVec3, DVec3),
    loc: &Loc,
) -> Result<LightDesc, String> {
    use gltf::khr_lights_punctual::Kind;
    let name = light
        .name()
        .map_or(format!("light {}", light.index()), |n| {
            format!("light '{n}'")
        });
    let colour =
        Vec3::from(light.color()) * light.intensity() / (LUMENS_PER_WATT * std::f32::consts::PI);
    crate::range::within(
        &colour.to_array(),
        &format!("{name}: colour × intensity / (683 π)"),
        crate::range::MAX_INTENSITY,
    )?;
    let position = world.translation.as_vec3();
    crate::range::coordinate(position.to_array()).map_err(|e| format!("{name}: {e}"))?;
    let direction = || {
        let d = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
        if d == DVec3::ZERO || !d.is_finite() {
            Err(format!(
                "{name}: its node's transform gives it no direction"
            ))
        } else {
            Ok(d.as_vec3())
        }
    };
    let shape = match light.kind() {
        Kind::Point => LightShape::Point,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            crate::light::spot::check_angles(inner_cone_angle, outer_cone_angle)
                .map_err(|e| format!("{name}: {e}"))?;
            LightShape::Spot {
                direction: direction()?,
                inner: inner_cone_angle,
                outer: outer_cone_angle,
            }
        }
        Kind::Directional => LightShape::Directional {
            direction: direction()?,
        },
    };
    let mut d = LightDesc {
        shape,
        position,
        colour,
        falloff: [0.0, 0.0, 1.0],
        power: None,
        photons: None,
        loc: loc.clone(),
    };
    // A physical light: it takes part in photon mapping, its share of photons by its flux
    // summed over the channels (a directional light's through the disc over the file's bounds,
    // which the build's bounds of the placed geometry match).
    let world_box = crate::accel::Bounds {
        min: bounds.0.as_vec3().into(),
        max: bounds.1.as_vec3().into(),
    };
    d.power = Some(
        crate::light::Light::from_desc(&d, world_box)
            .flux()
            .element_sum(),
    );
    Ok(d)
}

/// Returns the texture coordinate set of each texture a material's textures caustic reads use,
/// with the texture's name.
fn texture_sets(m: &gltf::Material) -> Vec<(&'static str, u32)> {
    let pbr = m.pbr_metallic_roughness();
    let mut out = Vec::new();
    if let Some(t) = pbr.base_color_texture() {
        out.push(("base colour", t.tex_coord()));
    }
    if let Some(t) = pbr.metallic_roughness_texture() {
        out.push(("metallic-roughness", t.tex_coord()));
    }
    if let Some(t) = m.normal_texture() {
        out.push(("normal", t.tex_coord()));
    }
    if let Some(t) = m.emissive_texture() {
        out.push(("emissive", t.tex_coord()));
    }
    out
}

/// Returns the lines for samplers caustic stands in for: every texture is looked up bilinearly
/// and repeats, whatever its sampler asks.
fn samplers(doc: &Document) -> Vec<String> {
    use gltf::texture::{MagFilter, WrappingMode};
    let mut out = Vec::new();
    let samplers: Vec<_> = doc.textures().map(|t| t.sampler()).collect();
    let nearest = samplers
        .iter()
        .filter(|s| s.mag_filter() == Some(MagFilter::Nearest))
        .count();
    let textures = |n: usize| match n {
        1 => "1 texture asks".to_owned(),
        n => format!("{n} textures ask"),
    };
    if nearest > 0 {
        out.push(format!(
            "{} for nearest filtering: looked up bilinearly",
            textures(nearest)
        ));
    }
    let clamped = samplers
        .iter()
        .filter(|s| s.wrap_s() != WrappingMode::Repeat || s.wrap_t() != WrappingMode::Repeat)
        .count();
    if clamped > 0 {
        out.push(format!(
            "{} for clamped or mirrored wrapping: drawn repeating",
            textures(clamped)
        ));
    }
    out
}

/// Returns what the file uses that caustic does not render, or renders through a stand-in,
/// one line each.
fn unsupported(doc: &Document) -> Vec<String> {
    let mut out = Vec::new();
    let count = |n: usize, what: &str, effect: &str| {
        (n > 0).then(|| format!("{n} {what}{}: {effect}", if n == 1 { "" } else { "s" }))
    };
    out.extend(count(
        doc.animations().len(),
        "animation",
        "the scene is drawn as it stands, unanimated",
    ));
    out.extend(count(
        doc.skins().len(),
        "skin",
        "skinned meshes are drawn in their bind pose",
    ));
    let prims = || doc.meshes().flat_map(|m| m.primitives());
    let morphs = prims()
        .filter(|p| p.morph_targets().next().is_some())
        .count();
    out.extend(count(
        morphs,
        "primitive with morph targets",
        "drawn in its base shape",
    ));
    let coloured = prims()
        .filter(|p| p.get(&gltf::Semantic::Colors(0)).is_some())
        .count();
    out.extend(count(
        coloured,
        "primitive with vertex colours",
        "they are not read",
    ));
    let ortho = doc
        .cameras()
        .filter(|c| matches!(c.projection(), gltf::camera::Projection::Orthographic(_)))
        .count();
    out.extend(count(
        ortho,
        "orthographic camera",
        "caustic renders perspective cameras",
    ));
    out.extend(samplers(doc));
    for m in doc.materials() {
        let name = m
            .name()
            .map_or(format!("material {}", m.index().unwrap_or(0)), |n| {
                format!("material '{n}'")
            });
        for (slot, set) in texture_sets(&m) {
            if set != 0 {
                out.push(format!(
                    "{name}: {slot} texture uses TEXCOORD_{set}: looked up with TEXCOORD_0, \
                     the one set caustic reads"
                ));
            }
        }
        if m.emissive_texture().is_some() && m.emissive_factor() != [0.0; 3] {
            out.push(format!(
                "{name}: emissive texture: its mean colour stands in (an emitter has one \
                 radiance)"
            ));
        }
        let mut unread = Vec::new();
        if m.occlusion_texture().is_some() {
            unread.push("occlusion texture");
        }
        if m.transmission()
            .is_some_and(|t| t.transmission_texture().is_some())
        {
            unread.push("transmission texture");
        }
        if m.alpha_mode() != gltf::material::AlphaMode::Opaque {
            unread.push("alpha (drawn opaque)");
        }
        if !unread.is_empty() {
            out.push(format!("{name}: {} not read", unread.join(", ")));
        }
    }
    for ext in doc.extensions_used() {
        if !HONOURED.contains(&ext) {
            out.push(format!("extension {ext} is not read"));
        }
    }
    out
}
