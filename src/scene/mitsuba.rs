//! `caustic export-mitsuba`: a built scene as a Mitsuba 3 XML scene, for the subset both renderers
//! share, so that Mitsuba's path tracer can serve as the reference caustic converges to.
//!
//! # The shared subset, and how it maps
//! - Shapes: spheres (uniform scale) become Mitsuba spheres, cubes become `cube` shapes with the
//!   unit cube `[0, 1]³` mapped onto Mitsuba's `[-1, 1]³`, triangle meshes become OBJ files
//!   written beside the XML in world space (vertex normals kept).
//! - Materials (caustic shades both sides of every surface, so opaque BSDFs are `twosided`):
//!   diffuse `kd` (`ks = 0`, `t = 0`) → `diffuse`; a mirror (`kd = 0`, `t = 0`, no Phong
//!   highlight: `p = 0`) → `conductor` with `material = none` and `specular_reflectance = ks`;
//!   a rough mirror (`kd = 0`, `t = 0`, `gr.roughness`) → `roughconductor` of distribution
//!   `ggx`, `alpha = roughness²`, `material = none` and `specular_reflectance = ks`;
//!   a rough clear dielectric (`t = 1`, `gr.roughness`) → `roughdielectric` (`ggx`, `alpha`);
//!   a clear dielectric (`t = 1`) → `dielectric` with `int_ior = ior` and `ext_ior` the index of
//!   the densest dielectric whose box holds it (glass in water), else 1; an index below 1 is
//!   relative to that one (an air bubble in water, `ior = 0.75`: `int_ior = 0.75·1.33`);
//! - absorption ([`Material::absorption`], `gr.absorption`) → a `homogeneous` medium of
//!   `sigma_t = σ` (written as `σ / max σ` at `scale = max σ`) and albedo 0, the dielectric's `interior` (and the `exterior` of the solids
//!   inside it), and the camera's medium when the eye is in it; the integrator is then `volpath`.
//! - Lights (physical falloff `{0, 0, 1}` only): point → `point` with intensity `π·rgb`; area →
//!   an emitting `rectangle` of radiance `π·rgb/A` on the side of `u × v`, black behind; sphere
//!   → an emitting `sphere` of radiance `rgb/R²` (see [`crate::light`] for why those are the
//!   same lights); an emissive surface (a glTF emissive material, whose mesh light covers its
//!   triangles) → its shape with its BSDF and an `area` emitter of its radiance; directional →
//!   `directional` of irradiance `π·rgb` along the light's direction of travel.
//! - A spot → `spot` of intensity `π·rgb` aimed along its axis, `cutoff_angle` its outer and
//!   `beam_width` its inner angle. **Not the same falloff**: Mitsuba's ramps linearly in the
//!   angle, `(outer − θ)/(outer − inner)`, where glTF's (caustic's, [`crate::light::spot`]) is
//!   the square of a ramp in the cosine, `((cos θ − cos outer)/(cos inner − cos outer))²`,
//!   which is darker through the penumbra (at its middle about a quarter against a half). The
//!   two agree within the inner cone and beyond the outer one, so only a spot whose inner angle
//!   is (nearly) its outer one, a hard cone, is the same light in both renderers; the exporter
//!   writes the others all the same, and the difference is the penumbra's, never elsewhere.
//! - A glTF base colour texture on a non-metal (`metallicFactor` 0, no metallic-roughness
//!   texture: `ks` is glTF's constant 4%) → a `bitmap` reflectance of the diffuse lobe, written
//!   beside the XML as an EXR of the texels sRGB-decoded and multiplied by what the lobe's
//!   reflectance multiplies them by (`baseColorFactor`, and the blend's `1/(1 − w)`), read raw
//!   with bilinear filtering and repeat wrapping, as caustic looks textures up; the mesh's OBJ
//!   carries its texture coordinates (`vt u 1−v`: OBJ's `v` runs up the image, glTF's down).
//! - The camera: `perspective` with the vertical field of view, a box pixel filter, an HDR film.
//!   The integrator: `path`, unbounded depth with Russian roulette.
//!
//! Anything else is an error naming the object and, where there is one, the script line:
//! CSG, cylinders, cones, Phong highlights, partly transparent or mixed materials, the course's
//! textures, other glTF textures (metallic-roughness, a metal's base colour), normal maps,
//! Perlin noise, the course's falloff, non-uniformly scaled spheres, overlapping
//! dielectrics. Never a silent approximation. Caustic's background gradient has no Mitsuba
//! counterpart (black there): validation scenes are closed.

use super::{Scene, Shape};
use crate::desc::{RenderDesc, SceneDesc};
use crate::error::{Error, Loc, Result};
use crate::geometry::Analytic;
use crate::light::{Light, Shape as LightShape};
use crate::material::Material;
use glam::{Affine3A, Vec3A};
use std::fmt::Write as _;
use std::path::Path;

/// Returns the name of the OBJ file the mesh of instance `i` is written to, beside the XML
/// file whose name without extension is `stem`.
fn mesh_name(stem: &str, i: usize) -> String {
    format!("{stem}_mesh{i}.obj")
}

/// Returns the name of the OBJ file holding the triangles of material `m` of instance `i`
/// (a mesh whose file gives each triangle its material).
fn part_name(stem: &str, i: usize, m: u32) -> String {
    format!("{stem}_mesh{i}_material{m}.obj")
}

/// Returns the OBJ files of instance `i`: one, or one per material of a mesh whose file gives
/// each triangle its material, with the material each file takes (`None`: the instance's).
fn mesh_files(scene: &Scene, stem: &str, i: usize) -> Vec<(String, Option<u32>)> {
    let inst = &scene.instances[i];
    match inst.shape {
        Shape::Mesh(_) if inst.mesh_materials => scene
            .instance_materials(inst)
            .into_iter()
            .map(|m| (part_name(stem, i, m), Some(m)))
            .collect(),
        Shape::Mesh(_) => vec![(mesh_name(stem, i), None)],
        Shape::Analytic(_) | Shape::Csg(_) => Vec::new(),
    }
}

/// Returns every file [`export`] of `scene` to `xml` writes: `xml` and the OBJ files of each
/// mesh instance beside it, so that a caller can check them all before the export starts.
pub fn outputs(scene: &Scene, xml: &Path) -> Vec<std::path::PathBuf> {
    let stem = xml
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let meshes = (0..scene.instances.len()).flat_map(|i| mesh_files(scene, &stem, i));
    let textures = (scene.materials.iter().enumerate())
        .filter(|(_, m)| matches!(base_colour_texture(m), Ok(Some(_))))
        .map(|(id, _)| format!("{stem}_kd{id}.exr"));
    std::iter::once(xml.to_path_buf())
        .chain(meshes.map(|(name, _)| xml.with_file_name(name)))
        .chain(textures.map(|name| xml.with_file_name(name)))
        .collect()
}

/// Writes the Mitsuba 3 scene of `scene` (built from `desc`'s `gr.render` call `r`) to `xml`, at
/// `width × height` pixels and `spp` samples per pixel; meshes go to OBJ files beside it, and
/// base colour textures to EXR files.
pub fn export(
    desc: &SceneDesc,
    r: &RenderDesc,
    scene: &Scene,
    (width, height): (u32, u32),
    spp: u32,
    xml: &Path,
) -> Result<()> {
    let mut s = String::new();
    let _ = writeln!(s, "<scene version=\"3.0.0\">");
    let _ = writeln!(
        s,
        "  <!-- exported by caustic export-mitsuba from {} -->",
        r.loc
    );
    let eye_medium = integrator_and_media(&mut s, scene);
    sensor(&mut s, r, (width, height), spp, &eye_medium);
    let dir = xml.parent().unwrap_or(Path::new("."));
    let stem = xml
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    for (i, inst) in scene.instances.iter().enumerate() {
        let node = desc.node(inst.node);
        let at = |what: String| Error::at(&node.loc, format!("node '{}': {what}", node.name));
        let (outside, ext) = outside(scene, i, 0);
        let bsdf_of = |material: u32| -> Result<String> {
            let m = &scene.materials[material as usize];
            let loc = material_loc(desc, material, &node.loc);
            let texture = base_colour_texture(m).map_err(|e| Error::at(loc, e))?;
            let file = texture.map(|_| format!("{stem}_kd{material}.exr"));
            let xml = bsdf(m, ext, file.as_deref()).map_err(|e| Error::at(loc, e))?;
            if let (Some(t), Some(file)) = (texture, &file) {
                write_reflectance(t, kd_scale(m), &dir.join(file))?;
            }
            Ok(xml + &media_refs(scene, material, outside))
        };
        let m = inst.world_from_object;
        if let Shape::Mesh(k) = inst.shape {
            for (name, material) in mesh_files(scene, &stem, i) {
                let id = material.unwrap_or(inst.material);
                let bsdf = bsdf_of(id)? + &surface_emitter(&scene.materials[id as usize]);
                let obj = Obj {
                    mesh: &scene.meshes[k as usize],
                    world_from_object: &m,
                    normal_to_world: inst.normal_to_world,
                    material,
                };
                obj.write(&dir.join(&name))?;
                let _ = writeln!(
                    s,
                    "  <shape type=\"obj\"><string name=\"filename\" value=\"{name}\"/>{bsdf}</shape>"
                );
            }
            continue;
        }
        let bsdf = bsdf_of(inst.material)?;
        match inst.shape {
            Shape::Analytic(Analytic::Sphere) => {
                let radius = uniform_scale(&m).ok_or_else(|| {
                    at("a non-uniformly scaled sphere is outside the Mitsuba subset".into())
                })?;
                let c = m.translation;
                let _ = writeln!(
                    s,
                    "  <shape type=\"sphere\"><point name=\"center\" value=\"{}, {}, {}\"/><float name=\"radius\" value=\"{radius}\"/>{bsdf}</shape>",
                    c.x, c.y, c.z
                );
            }
            Shape::Analytic(Analytic::Cube) => {
                // Mitsuba's cube spans [-1, 1]³: to_world = M · translate(½) · scale(½).
                let unit = Affine3A::from_scale_rotation_translation(
                    glam::Vec3::splat(0.5),
                    glam::Quat::IDENTITY,
                    glam::Vec3::splat(0.5),
                );
                let _ = writeln!(
                    s,
                    "  <shape type=\"cube\">{}{bsdf}</shape>",
                    matrix(&(m * unit))
                );
            }
            Shape::Analytic(Analytic::Cylinder | Analytic::Cone)
            | Shape::Csg(_)
            | Shape::Mesh(_) => {
                return Err(at(format!(
                    "a {} is outside the Mitsuba subset (spheres, cubes and triangle meshes)",
                    inst.shape.label()
                )));
            }
        }
    }
    lights(&mut s, desc, r, scene)?;
    let _ = writeln!(s, "</scene>");
    crate::files::write_bytes(xml, s.as_bytes()).map_err(|e| Error::File {
        path: xml.to_path_buf(),
        message: format!("cannot write the Mitsuba scene: {e}"),
    })
}

/// Returns the area emitter of a surface that emits (a glTF emissive material), else nothing.
/// The surface is written with its own BSDF and this emitter, as Mitsuba has emissive shapes:
/// its mesh light ([`crate::scene::emitters`]) covers the same triangles and is not written
/// again ([`lights`]). Mitsuba's area emitter emits on the side the shading normal faces,
/// which for the flat panels glTF files light with is the winding's.
fn surface_emitter(m: &Material) -> String {
    if m.emission == Vec3A::ZERO {
        return String::new();
    }
    format!(
        "<emitter type=\"area\"><rgb name=\"radiance\" value=\"{}\"/></emitter>",
        rgb(m.emission)
    )
}

/// Writes the scene's lights ([`emitter`]).
fn lights(s: &mut String, desc: &SceneDesc, r: &RenderDesc, scene: &Scene) -> Result<()> {
    for (l, light) in scene.lights.iter().enumerate() {
        emitter(s, light).map_err(|e| Error::at(r.light_loc(desc, l), e))?;
    }
    Ok(())
}

/// Writes the integrator (`volpath` where a solid absorbs, else `path`) and a `homogeneous`
/// medium per absorbing material; returns the reference to the camera's medium for the sensor
/// (empty in air or a clear solid).
fn integrator_and_media(s: &mut String, scene: &Scene) -> String {
    let absorbing: Vec<u32> = (0..scene.materials.len() as u32)
        .filter(|&m| absorbs(&scene.materials[m as usize]))
        .collect();
    let integrator = if absorbing.is_empty() {
        "path"
    } else {
        "volpath"
    };
    let _ = writeln!(
        s,
        "  <integrator type=\"{integrator}\"><integer name=\"max_depth\" value=\"-1\"/></integrator>"
    );
    for &m in &absorbing {
        // Mitsuba reads an RGB `sigma_t` as a reflectance (each channel in [0, 1]): the
        // coefficients go in divided by their largest, which is the medium's `scale`.
        let a = scene.materials[m as usize].absorption;
        let scale = a.max_element();
        let _ = writeln!(
            s,
            "  <medium type=\"homogeneous\" id=\"{}\"><rgb name=\"sigma_t\" value=\"{}, {}, {}\"/><float name=\"scale\" value=\"{scale}\"/><rgb name=\"albedo\" value=\"0, 0, 0\"/></medium>",
            medium_id(m),
            a.x / scale,
            a.y / scale,
            a.z / scale
        );
    }
    scene
        .eye_media
        .stack
        .winner()
        .filter(|m| absorbing.contains(m))
        .map(|m| format!("<ref id=\"{}\"/>", medium_id(m)))
        .unwrap_or_default()
}

/// Returns the references to the absorbing media on either side of a dielectric of material
/// `material` whose outside is `outside`'s medium (empty for an opaque material or clear media).
fn media_refs(scene: &Scene, material: u32, outside: Option<u32>) -> String {
    let mut refs = String::new();
    let m = &scene.materials[material as usize];
    if m.transparency <= 0.0 {
        return refs;
    }
    if absorbs(m) {
        refs += &format!("<ref name=\"interior\" id=\"{}\"/>", medium_id(material));
    }
    if let Some(o) = outside.filter(|o| absorbs(&scene.materials[*o as usize])) {
        refs += &format!("<ref name=\"exterior\" id=\"{}\"/>", medium_id(o));
    }
    refs
}

/// Returns the script line of scene material `id` (materials past the script's come from mesh
/// files: the node's line).
fn material_loc<'a>(desc: &'a SceneDesc, id: u32, node: &'a Loc) -> &'a Loc {
    desc.materials.get(id as usize).map_or(node, |m| &m.loc)
}

/// Writes the camera; `medium` is the reference to the absorbing medium it is in, if any.
fn sensor(s: &mut String, r: &RenderDesc, (width, height): (u32, u32), spp: u32, medium: &str) {
    let c = &r.camera;
    let target = c.eye + c.view;
    let _ = writeln!(
        s,
        "  <sensor type=\"perspective\"><float name=\"fov\" value=\"{}\"/><string name=\"fov_axis\" value=\"y\"/>\
         <transform name=\"to_world\"><lookat origin=\"{}, {}, {}\" target=\"{}, {}, {}\" up=\"{}, {}, {}\"/></transform>\
         <sampler type=\"independent\"><integer name=\"sample_count\" value=\"{spp}\"/></sampler>\
         <film type=\"hdrfilm\"><integer name=\"width\" value=\"{width}\"/><integer name=\"height\" value=\"{height}\"/>\
         <string name=\"pixel_format\" value=\"rgb\"/><rfilter type=\"box\"/></film>{medium}</sensor>",
        c.fov_deg, c.eye.x, c.eye.y, c.eye.z, target.x, target.y, target.z, c.up.x, c.up.y, c.up.z
    );
}

/// Returns the base colour texture of `m` when it is the one texturing the Mitsuba subset
/// takes (see the module doc), none for an untextured material, or why `m` is outside it.
fn base_colour_texture(
    m: &Material,
) -> std::result::Result<Option<&crate::material::texture::Texture>, String> {
    if m.bump.is_some() || m.perlin_scale > 0.0 {
        return Err("normal maps and Perlin noise are outside the Mitsuba subset".into());
    }
    if m.texture.is_some() {
        return Err("the course's textures are outside the Mitsuba subset".into());
    }
    let Some(p) = &m.metal_rough else {
        return Ok(None);
    };
    match (&p.base_colour_texture, &p.metallic_roughness_texture) {
        (Some(t), None) if p.metallic == 0.0 && m.transparency == 0.0 => Ok(Some(t)),
        (None, None) => Ok(None),
        _ => Err(
            "of glTF's textures, only a non-metal's base colour texture (metallic 0, no \
                  metallic-roughness texture, opaque) is in the Mitsuba subset"
                .into(),
        ),
    }
}

/// Returns what the diffuse lobe's reflectance multiplies a base colour texel by:
/// `baseColorFactor`, over `1 − w` when the lobe is blended with a mirror lobe of weight `w`
/// (see [`bsdf`]).
fn kd_scale(m: &Material) -> Vec3A {
    let factor = m.metal_rough.as_ref().map_or(Vec3A::ONE, |p| p.base_colour);
    if m.ks.max_element() > 0.0 && m.roughness > 0.0 {
        factor / (1.0 - m.ks.max_element().min(1.0)).max(1e-6)
    } else {
        factor
    }
}

/// Writes texture `t`'s texels, sRGB-decoded and multiplied by `scale`, as a linear EXR.
fn write_reflectance(
    t: &crate::material::texture::Texture,
    scale: Vec3A,
    path: &Path,
) -> Result<()> {
    let film = crate::film::Film {
        width: t.width,
        height: t.height,
        pixels: t.srgb_texels().into_iter().map(|c| c * scale).collect(),
        samples: vec![1; (t.width * t.height) as usize],
        window: crate::film::Window::full(t.width, t.height),
    };
    crate::io::image::write_image(&film, path, crate::io::image::Tonemap::Clamp)
}

/// Returns the Mitsuba BSDF of `m` (its diffuse reflectance the bitmap `texture` when given:
/// [`base_colour_texture`]), or why it is outside the subset.
fn bsdf(m: &Material, ext_ior: f32, texture: Option<&str>) -> std::result::Result<String, String> {
    if m.texture.is_some() || m.bump.is_some() || m.perlin_scale > 0.0 {
        return Err("textures, normal maps and Perlin noise are outside the Mitsuba subset".into());
    }
    let rgb = |v: Vec3A| format!("{}, {}, {}", v.x, v.y, v.z);
    // The diffuse reflectance, `kd` scaled by `scale`: a colour, or the texture (whose texels
    // the file already holds scaled).
    let reflectance = |kd: Vec3A| match texture {
        Some(file) => format!(
            "<texture type=\"bitmap\" name=\"reflectance\"><string name=\"filename\" value=\"{file}\"/>\
             <string name=\"filter_type\" value=\"bilinear\"/><string name=\"wrap_mode\" value=\"repeat\"/>\
             <boolean name=\"raw\" value=\"true\"/></texture>"
        ),
        None => format!("<rgb name=\"reflectance\" value=\"{}\"/>", rgb(kd)),
    };
    let black = |v: Vec3A| v.max_element() <= 0.0;
    if m.transparency == 1.0 {
        // An index below 1 is relative to the medium outside (crate::material::medium).
        let int_ior = if m.ior < 1.0 { m.ior * ext_ior } else { m.ior };
        if m.roughness > 0.0 {
            let alpha = crate::material::microfacet::Ggx::from_roughness(m.roughness).alpha;
            return Ok(format!(
                "<bsdf type=\"roughdielectric\"><string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"{alpha}\"/>\
                 <float name=\"int_ior\" value=\"{int_ior}\"/><float name=\"ext_ior\" value=\"{ext_ior}\"/></bsdf>"
            ));
        }
        return Ok(format!(
            "<bsdf type=\"dielectric\"><float name=\"int_ior\" value=\"{int_ior}\"/><float name=\"ext_ior\" value=\"{ext_ior}\"/></bsdf>"
        ));
    }
    if m.transparency > 0.0 {
        return Err(format!(
            "a partly transparent material (t = {}) is outside the Mitsuba subset (t = 0 or 1)",
            m.transparency
        ));
    }
    if black(m.ks) {
        return Ok(format!(
            "<bsdf type=\"twosided\"><bsdf type=\"diffuse\">{}</bsdf></bsdf>",
            reflectance(m.kd)
        ));
    }
    if black(m.kd) && m.roughness > 0.0 {
        // The rough conductor replaces the mirror and the highlight (p is ignored).
        let alpha = crate::material::microfacet::Ggx::from_roughness(m.roughness).alpha;
        return Ok(format!(
            "<bsdf type=\"twosided\"><bsdf type=\"roughconductor\"><string name=\"material\" value=\"none\"/>\
             <string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"{alpha}\"/>\
             <rgb name=\"specular_reflectance\" value=\"{}\"/></bsdf></bsdf>",
            rgb(m.ks)
        ));
    }
    if m.roughness > 0.0 {
        // kd and a rough ks lobe add (crate::material::bsdf): their sum is the blend of weight
        // w = max ks of each divided by its weight, both within [0, 1] where kd + ks is.
        let alpha = crate::material::microfacet::Ggx::from_roughness(m.roughness).alpha;
        let w = m.ks.max_element().min(1.0);
        return Ok(format!(
            "<bsdf type=\"twosided\"><bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"{w}\"/>\
             <bsdf type=\"diffuse\">{}</bsdf>\
             <bsdf type=\"roughconductor\"><string name=\"material\" value=\"none\"/>\
             <string name=\"distribution\" value=\"ggx\"/><float name=\"alpha\" value=\"{alpha}\"/>\
             <rgb name=\"specular_reflectance\" value=\"{}\"/></bsdf></bsdf></bsdf>",
            reflectance(m.kd / (1.0 - w).max(1e-6)),
            rgb(m.ks / w)
        ));
    }
    if black(m.kd) && m.shininess <= 0.0 {
        return Ok(format!(
            "<bsdf type=\"twosided\"><bsdf type=\"conductor\"><string name=\"material\" value=\"none\"/>\
             <rgb name=\"specular_reflectance\" value=\"{}\"/></bsdf></bsdf>",
            rgb(m.ks)
        ));
    }
    Err("a material with a Phong highlight (p > 0) or both kd and ks is outside the Mitsuba subset (diffuse, mirror with p = 0, or t = 1)".into())
}

/// Returns the material of the medium outside dielectric instance `i` and its absolute index:
/// the densest other dielectric whose box holds its box (a relative index below 1 taken against
/// what holds that one in turn), else none and 1 (air). Caustic's media rule (the highest index
/// wins) agrees there. `depth` bounds the chain of holders (boxes of equal size hold each other).
fn outside(scene: &Scene, i: usize, depth: u32) -> (Option<u32>, f32) {
    let b = scene.instances[i].bounds;
    let mut best = (None, 1.0f32);
    if depth > 8 {
        return best;
    }
    for (j, other) in scene.instances.iter().enumerate() {
        let m = &scene.materials[other.material as usize];
        if j == i || m.transparency <= 0.0 {
            continue;
        }
        let o = other.bounds;
        if o.min.cmple(b.min).all() && o.max.cmpge(b.max).all() {
            let ior = if m.ior < 1.0 {
                m.ior * outside(scene, j, depth + 1).1
            } else {
                m.ior
            };
            if ior > best.1 {
                best = (Some(other.material), ior);
            }
        }
    }
    best
}

/// Returns whether `m` is a dielectric whose interior absorbs.
fn absorbs(m: &Material) -> bool {
    m.transparency > 0.0 && m.absorption != Vec3A::ZERO
}

/// Returns the id of the Mitsuba medium of material `m`.
fn medium_id(m: u32) -> String {
    format!("medium{m}")
}

/// Returns the scale of `m` when it is a uniform scale times a rotation (within 1e-4).
fn uniform_scale(m: &Affine3A) -> Option<f32> {
    let (x, y, z) = (m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis);
    let r = x.length();
    let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * r.max(1e-30);
    (close(y.length(), r) && close(z.length(), r) && close(x.dot(y), 0.0) && close(x.dot(z), 0.0))
        .then_some(r)
}

/// Returns `m` as a Mitsuba `to_world` transform (row-major 4 × 4).
fn matrix(m: &Affine3A) -> String {
    let c = [
        m.matrix3.x_axis,
        m.matrix3.y_axis,
        m.matrix3.z_axis,
        m.translation,
    ];
    let rows: Vec<String> = (0..3)
        .map(|i| format!("{} {} {} {}", c[0][i], c[1][i], c[2][i], c[3][i]))
        .collect();
    format!(
        "<transform name=\"to_world\"><matrix value=\"{} 0 0 0 1\"/></transform>",
        rows.join(" ")
    )
}

/// The BSDF of an emitter's shape: black, so that it only emits, as caustic's lights do.
const BLACK: &str = "<bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0, 0, 0\"/></bsdf>";

/// Returns `v` as a Mitsuba RGB value.
fn rgb(v: Vec3A) -> String {
    format!("{}, {}, {}", v.x, v.y, v.z)
}

/// Writes `light` as a Mitsuba emitter; a mesh light's triangles go to the OBJ file `obj`.
fn emitter(s: &mut String, light: &Light) -> std::result::Result<(), String> {
    if light.falloff != [0.0, 0.0, 1.0] {
        return Err(format!(
            "the course's falloff {:?} is outside the Mitsuba subset (only {{0, 0, 1}}, the physical inverse square)",
            light.falloff
        ));
    }
    let pi = std::f32::consts::PI;
    let black = BLACK;
    match light.shape {
        LightShape::Point { position } => {
            let _ = writeln!(
                s,
                "  <emitter type=\"point\"><point name=\"position\" value=\"{}\"/><rgb name=\"intensity\" value=\"{}\"/></emitter>",
                rgb(position),
                rgb(pi * light.colour)
            );
        }
        LightShape::Spot {
            position,
            axis,
            cone,
        } => {
            // Mitsuba's falloff is linear in angle, not glTF's: see the module doc.
            let _ = writeln!(
                s,
                "  <emitter type=\"spot\"><transform name=\"to_world\"><lookat origin=\"{}\" target=\"{}\" up=\"{}\"/></transform>\
                 <rgb name=\"intensity\" value=\"{}\"/><float name=\"cutoff_angle\" value=\"{}\"/>\
                 <float name=\"beam_width\" value=\"{}\"/></emitter>",
                rgb(position),
                rgb(position + axis),
                rgb(axis.any_orthonormal_vector()),
                rgb(pi * light.colour),
                cone.outer.to_degrees(),
                cone.inner.to_degrees()
            );
        }
        LightShape::Directional { dir, .. } => {
            let _ = writeln!(
                s,
                "  <emitter type=\"directional\"><vector name=\"direction\" value=\"{}\"/><rgb name=\"irradiance\" value=\"{}\"/></emitter>",
                rgb(dir),
                rgb(pi * light.colour)
            );
        }
        LightShape::Area {
            centre,
            u,
            v,
            normal,
            area,
        } => {
            let m = Affine3A::from_cols(u * 0.5, v * 0.5, normal, centre);
            let _ = writeln!(
                s,
                "  <shape type=\"rectangle\">{}{black}<emitter type=\"area\"><rgb name=\"radiance\" value=\"{}\"/></emitter></shape>",
                matrix(&m),
                rgb(pi * light.colour / area)
            );
        }
        // An emissive surface's light: written with the surface ([`surface_emitter`]).
        LightShape::Mesh(_) => {}
        LightShape::Sphere { centre, radius } => {
            let _ = writeln!(
                s,
                "  <shape type=\"sphere\"><point name=\"center\" value=\"{}\"/><float name=\"radius\" value=\"{radius}\"/>{black}\
                 <emitter type=\"area\"><rgb name=\"radiance\" value=\"{}\"/></emitter></shape>",
                rgb(centre),
                rgb(light.colour / (radius * radius))
            );
        }
    }
    Ok(())
}

/// One OBJ file of a placed mesh: its triangles in world space (with vertex normals when it
/// has them), all of them or those of one scene material.
struct Obj<'a> {
    mesh: &'a crate::accel::mesh::MeshGeom,
    world_from_object: &'a Affine3A,
    normal_to_world: glam::Mat3A,
    /// Only the triangles of this scene material, or all of them.
    material: Option<u32>,
}

impl Obj<'_> {
    /// Writes the file to `path`.
    fn write(&self, path: &Path) -> Result<()> {
        let mesh = self.mesh;
        let data = mesh.data();
        let mut s = String::with_capacity(data.positions.len() * 40 + data.triangles.len() * 24);
        for p in &data.positions {
            let q = self.world_from_object.transform_point3(*p);
            let _ = writeln!(s, "v {} {} {}", q.x, q.y, q.z);
        }
        for n in &data.normals {
            let q = (self.normal_to_world * glam::Vec3A::from(*n)).normalize_or_zero();
            let _ = writeln!(s, "vn {} {} {}", q.x, q.y, q.z);
        }
        for uv in &data.uvs {
            let _ = writeln!(s, "vt {} {}", uv.x, 1.0 - uv.y);
        }
        let with_normals = !data.normals.is_empty();
        let with_uvs = !data.uvs.is_empty();
        // In BVH order, the order of `materials`.
        for i in 0..mesh.len() {
            if self
                .material
                .is_some_and(|m| mesh.materials.get(i) != Some(&m))
            {
                continue;
            }
            let [a, b, c] = mesh.triangle(i as u32).map(|i| i + 1);
            if with_normals && with_uvs {
                let _ = writeln!(s, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}");
            } else if with_uvs {
                let _ = writeln!(s, "f {a}/{a} {b}/{b} {c}/{c}");
            } else if with_normals {
                let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
            } else {
                let _ = writeln!(s, "f {a} {b} {c}");
            }
        }
        write_text(path, &s)
    }
}

/// Writes one of the export's mesh files.
fn write_text(path: &Path, s: &str) -> Result<()> {
    crate::files::write_bytes(path, s.as_bytes()).map_err(|e| Error::File {
        path: path.to_path_buf(),
        message: format!("cannot write mesh: {e}"),
    })
}
