//! glTF 2.0 meshes: reads `.gltf` (external `.bin` files or base64 data URIs) and `.glb` into one
//! [`MeshData`], and writes a mesh back out ([`write_gltf`]). Every fault names the file.
//!
//! ```lua
//! boat = gr.mesh('boat', 'meshes/boat.glb')   -- or .gltf; the extension picks the loader
//! ```
//!
//! # What is read
//! Every mesh primitive reachable from the default scene (else scene 0; with no scene at all,
//! every root node), with each node's TRS or matrix transform composed down the hierarchy and
//! baked into the vertices: positions by the node's world transform, normals by its inverse
//! transpose and renormalised (left untouched under an identity transform). A node whose
//! transform mirrors space (negative determinant) has its triangles' winding reversed, as the
//! spec asks, so front faces stay front faces; a node with a singular transform (zero scale)
//! draws nothing and is skipped. Primitives in `TRIANGLES`, `TRIANGLE_STRIP` and `TRIANGLE_FAN`
//! mode are read, indexed (`u8`, `u16`, `u32`) or not; `POINTS` and `LINE*` primitives are
//! skipped. Surplus indices of a `TRIANGLES` primitive (a count not divisible by 3) are ignored.
//! As in the OBJ loader, normals are all-or-nothing over the merged mesh. Texture coordinates
//! (`TEXCOORD_0`) are kept when any primitive has them, the vertices of those without at
//! (0, 0): a textured box in an untextured room keeps its texture's layout.
//! Positions, in the file and after the node transforms, must lie within the renderer's range
//! ([`crate::range::MAX_COORDINATE`]); the error names the accessor or node and the vertex.
//! Sparse accessors, accessors without a buffer view, node cycles and nodes with two parents are
//! rejected, as are required extensions other than the two materials ones below.
//! [`load_gltf_mesh_with`] reads one glTF mesh alone instead, in its own frame (no node
//! transform), with the same materials and emitters: what `gr.gltf` places under each node that
//! holds it, the hierarchy itself read by [`hierarchy`].
//!
//! # Materials
//! glTF's metallic-roughness model maps onto the one BSDF's lobes ([`crate::material`]). With
//! base colour `c`, metallic `m`, roughness `r` and specular colour `F0 = mix(0.04, c, m)` (the
//! usual dielectric 4 %):
//! - `kd = c · (1 − m)`: a dielectric keeps its base colour, a metal has no diffuse lobe;
//! - `ks = F0` with GGX roughness `r` (`alpha = r²`, the glTF convention, as `gr.roughness`
//!   takes it): a rough conductor of colour `F0` ([`crate::material::microfacet`]), the smooth
//!   mirror at `r = 0`; on a dielectric the 4 % lobe stands for its specular reflection;
//! - `transparency` = `KHR_materials_transmission`'s factor, `ior` = `KHR_materials_ior` (1.5
//!   when absent, the glTF default), with the roughness making the interface a rough
//!   dielectric (frosted glass);
//! - `KHR_materials_volume`: absorption `−ln(attenuationColor)/attenuationDistance`.
//!
//! The glTF default material (white, fully metallic and rough) thus becomes a white conductor
//! of roughness 1, as glTF defines it. Factors are clamped to their glTF ranges (`ior` to at
//! least 1). When no primitive has a material, the mesh carries none; otherwise primitives
//! without one get the glTF default material.
//!
//! # Textures
//! A material's base colour, metallic-roughness and normal textures are carried in
//! [`MeshMaterial::pbr`] with their factors, each image as an
//! [`ImageSource`](crate::geometry::mesh::ImageSource): a file (an
//! external URI, resolved against the file's folder; read by the scene build if it lies in the
//! scene's folders, a warning if it cannot be read) or the encoded PNG or JPEG bytes the file
//! embeds (a buffer view of the GLB binary chunk or of any buffer, or a base64 `data:` URI),
//! copied once per image and charged to the load's account. A buffer view outside its buffer
//! and a `data:` URI that is not valid base64 are errors naming the file, the material, the
//! texture and the image index; so, when the scene build decodes it, is an embedded image that
//! is corrupt, truncated, or larger than the decoder allows ([`crate::scene::images`]).
//! Shading looks them up at every hit ([`crate::material::pbr`]), all per texel:
//! - base colour: sRGB-decoded, times `baseColorFactor`;
//! - metallic (blue) and roughness (green): linear, times their factors; with the base colour
//!   they give `kd = base·(1 − metallic)`, `ks = mix(0.04, base, metallic)` and the GGX
//!   roughness at the hit, as above;
//! - normal: a tangent-space map, `2c/255 − 1` with x and y times `scale`, in the frame of the
//!   triangle's `∂p/∂u` from its texture coordinates (+u the tangent, `n × tangent` the image's
//!   "up"; glTF's `TANGENT` attribute is not read, so where a texture is laid out mirrored its
//!   normals' y is flipped).
//!
//! Every texture is looked up with `TEXCOORD_0`, bilinearly, repeating, whatever its sampler
//! and `texCoord` say. Alpha and the occlusion and transmission textures are ignored. A
//! whole-scene render lists each of these, and the emissive stand-in below ([`scene`]).
//!
//! # Emission
//! A primitive whose material emits (`emissiveFactor × KHR_materials_emissive_strength`) is a
//! surface like any other (it reflects by its material and hides what is behind it, as glTF
//! and every path tracer have it) and also a light: its triangles, under its node's transform,
//! are one of [`MeshData::emitters`], which the scene build turns into a light where the mesh
//! is placed ([`crate::scene::emitters`]). Such a light has one radiance over its triangles, so
//! an emissive texture stands in by its mean colour: the factors times the image's mean texel,
//! sRGB-decoded (its pattern is not drawn). The image is decoded for that and dropped; an
//! embedded one that cannot be decoded is an error, an image file that cannot be read a
//! warning (the factors alone then make the radiance). The radiance must lie within a light's
//! range ([`crate::range`]), and a file carries at most [`MAX_EMITTER_TRIANGLES`] emissive
//! triangles.

mod buffer;
pub mod hierarchy;
mod images;
pub mod scene;
mod write;

pub use write::write_gltf;

use crate::budget::Account;
use crate::geometry::mesh::{MeshData, MeshEmitter, MeshMaterial, MeshPbr};
use crate::material::pbr::Reflectance;
use buffer::{
    Buffer, glb_chunks, load_buffers, read_indices, read_triangle_list, read_uvs, read_vec3,
    split_glb,
};
use glam::{DAffine3, DMat3, DQuat, DVec3, Vec2, Vec3};
use gltf::json::validation::Checked;
use gltf::mesh::Mode;
use gltf::{Document, Semantic};
use images::Images;
use std::borrow::Cow;
use std::io;
use std::path::{Path, PathBuf};

/// Phong exponent given to a perfectly smooth glTF surface.
const MAX_SHININESS: f32 = 10_000.0;

/// Most emissive triangles a file may carry: each one is tested against every camera ray that
/// meets its light's bounds ([`crate::light::Light::seen_by`]), so lamps, not emissive scans.
pub const MAX_EMITTER_TRIANGLES: usize = 4096;

/// A fault found while reading a glTF file; every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum GltfError {
    /// The file itself could not be read (`error` is shown in the message, not as a source).
    #[error("{}: cannot read: {error}", path.display())]
    Read { path: PathBuf, error: io::Error },
    /// The file is malformed: bad JSON or GLB, a missing buffer, data out of range or not finite.
    #[error("{}: {message}", path.display())]
    Invalid { path: PathBuf, message: String },
    /// The file is valid glTF but needs something caustic does not read.
    #[error("{}: unsupported: {message}", path.display())]
    Unsupported { path: PathBuf, message: String },
}

impl From<GltfError> for crate::error::Error {
    /// Returns the file error the fault is: its message names the file.
    fn from(e: GltfError) -> crate::error::Error {
        let (path, message) = match e {
            GltfError::Read { path, error } => (path, format!("cannot read: {error}")),
            GltfError::Invalid { path, message } => (path, message),
            GltfError::Unsupported { path, message } => (path, format!("unsupported: {message}")),
        };
        crate::error::Error::File { path, message }
    }
}

/// Reads a `.gltf` or `.glb` file into one mesh (see the module doc for what is read).
pub fn load_gltf(path: &Path) -> Result<MeshData, GltfError> {
    load_gltf_with(path, &crate::budget::Budget::machine_default().account())
}

/// [`load_gltf`], charging each primitive's triangles to `account` before they are read.
pub fn load_gltf_with(path: &Path, account: &Account) -> Result<MeshData, GltfError> {
    load_gltf_mesh_with(path, None, account)
}

/// Parses glTF JSON or GLB bytes already in memory; `path` names the file in messages and
/// locates its external buffers and images.
pub fn parse_gltf(bytes: &[u8], path: &Path) -> Result<MeshData, GltfError> {
    parse_gltf_with(
        bytes,
        path,
        &crate::budget::Budget::machine_default().account(),
    )
}

/// [`parse_gltf`], charging each primitive's triangles to `account` before they are read: a
/// small file whose nodes and primitives share one large accessor would otherwise make billions.
pub fn parse_gltf_with(
    bytes: &[u8],
    path: &Path,
    account: &Account,
) -> Result<MeshData, GltfError> {
    let (doc, bin) = open_document(bytes, path)?;
    let bin = bin.map(|b| Buffer::Bytes(Cow::Borrowed(b)));
    parse_part(&doc, bin, path, account, None)
}

/// Reads glTF mesh `mesh` of the file at `path` alone, in the mesh's own frame (no node
/// transform), with the file's materials and emitters as [`load_gltf`] gives them: what
/// `gr.gltf` places under each node that holds it; `None` reads the whole file as
/// [`load_gltf_with`] does.
pub fn load_gltf_mesh_with(
    path: &Path,
    mesh: Option<u32>,
    account: &Account,
) -> Result<MeshData, GltfError> {
    let (json, bin) = read_head(path)?;
    let (doc, _) = open_document(&json, path)?;
    parse_part(&doc, bin, path, account, mesh)
}

/// Reads the file's default scene with every node's transform baked in (`only` is `None`), or
/// glTF mesh `only` alone in its own frame.
fn parse_part(
    doc: &Document,
    bin: Option<Buffer>,
    path: &Path,
    account: &Account,
    only: Option<u32>,
) -> Result<MeshData, GltfError> {
    let invalid = |message: String| GltfError::Invalid {
        path: path.to_owned(),
        message,
    };
    let dir = path.parent().unwrap_or(Path::new(""));
    let buffers = load_buffers(doc, bin, dir, account.read_scope()).map_err(invalid)?;
    let mut images = Images::new(doc, &buffers, path, dir, account);
    let mut parts = Vec::new();
    let (mut emitters, mut emitted) = (Vec::new(), 0);
    let mut default_material = None;
    // Each mesh to read, with its transform and where it is placed, for messages.
    let placed: Vec<(gltf::Mesh, DAffine3, String)> = match only {
        None => placements(doc)
            .map_err(invalid)?
            .into_iter()
            .filter_map(|(node, world)| {
                let at = format!(" under node {}", node.index());
                node.mesh().map(|m| (m, world, at))
            })
            .collect(),
        Some(m) => {
            let mesh = doc.meshes().nth(m as usize).ok_or_else(|| {
                invalid(format!(
                    "mesh {m} does not exist (the file has {})",
                    doc.meshes().len()
                ))
            })?;
            vec![(mesh, DAffine3::IDENTITY, String::new())]
        }
    };
    for (mesh, world, under) in placed {
        let det = world.matrix3.determinant();
        if det == 0.0 || !det.is_finite() {
            continue;
        }
        for prim in mesh.primitives() {
            let at = format!("mesh {} primitive {}", mesh.index(), prim.index());
            let what = format!("{at}{under}: {}", primitive_size(&prim));
            account
                .try_charge(primitive_bytes(&prim), what)
                .map_err(|e| invalid(e.to_string()))?;
            let Some(mut part) =
                read_primitive(&prim, &buffers).map_err(|e| GltfError::Invalid {
                    path: path.to_owned(),
                    message: format!("{at}: {e}"),
                })?
            else {
                continue;
            };
            bake(&mut part, &world).map_err(|e| invalid(format!("{at}{under}: {e}")))?;
            if let Some(emitter) = emitter(&prim.material(), &part, &mut images).map_err(invalid)? {
                emitted += emitter.triangles.len();
                if emitted > MAX_EMITTER_TRIANGLES {
                    return Err(GltfError::Unsupported {
                        path: path.to_owned(),
                        message: format!(
                            "{at}: more than {MAX_EMITTER_TRIANGLES} emissive triangles in the \
                             file; caustic tests every one against each camera ray"
                        ),
                    });
                }
                // Still a surface too: it reflects by its material and hides what is behind.
                emitters.push(emitter);
            }
            if part.material.is_none() && default_material.is_none() {
                default_material = Some(material(&prim.material(), &mut images).map_err(invalid)?);
            }
            parts.push(part);
        }
    }
    let mut mesh = merge(parts, default_material, doc, &mut images, path).map_err(invalid)?;
    mesh.emitters = emitters;
    Ok(mesh)
}

/// Returns the emitter a primitive's triangles make when its material emits, or `None` when
/// it does not: radiance `emissiveFactor × emissiveStrength`, times the emissive texture's mean
/// colour where it has one (an emitter has one radiance; the texture's pattern is not drawn).
fn emitter(
    m: &gltf::Material,
    part: &Part,
    images: &mut Images,
) -> Result<Option<MeshEmitter>, String> {
    let strength = m.emissive_strength().unwrap_or(1.0);
    let mut radiance = Vec3::from(m.emissive_factor()) * strength;
    if radiance == Vec3::ZERO {
        return Ok(None);
    }
    let name = material_name(m);
    if let Some(info) = m.emissive_texture() {
        let mean = images
            .srgb_mean(&info.texture())
            .map_err(|e| format!("{name}: emissive texture: {e}"))?;
        radiance *= mean.unwrap_or(Vec3::ONE);
        if radiance == Vec3::ZERO {
            return Ok(None);
        }
    }
    let what = format!("{name}: emitted radiance");
    crate::range::within(&radiance.to_array(), &what, crate::range::MAX_INTENSITY)?;
    let triangles = part
        .triangles
        .iter()
        .map(|t| t.map(|i| part.positions[i as usize]))
        .collect();
    Ok(Some(MeshEmitter {
        name,
        radiance,
        triangles,
    }))
}

/// Returns a material's name for messages: its own, else its index.
fn material_name(m: &gltf::Material) -> String {
    match (m.name(), m.index()) {
        (Some(name), _) => name.to_owned(),
        (None, Some(i)) => format!("material {i}"),
        (None, None) => "default material".to_owned(),
    }
}

/// Reads the glTF file at `path` (a regular file) and returns its validated document and the
/// file's length in bytes, for what needs the document but not the GLB's binary chunk (which
/// is not read).
fn read_document(path: &Path) -> Result<(Document, u64), GltfError> {
    let size = std::fs::metadata(path).map_or(0, |m| m.len());
    let (json, _) = read_head(path)?;
    let (doc, _) = open_document(&json, path)?;
    Ok((doc, size))
}

/// Reads what a glTF file on disk needs read up front: the whole of a `.gltf` (JSON), or a
/// GLB's JSON chunk, its `BIN` chunk left in the file as a [`Buffer::File`] that accessors
/// read in runs (see [`buffer`]'s module doc).
fn read_head(path: &Path) -> Result<(Vec<u8>, Option<Buffer<'static>>), GltfError> {
    let invalid = |message: String| GltfError::Invalid {
        path: path.to_owned(),
        message,
    };
    let file = Buffer::file(path).map_err(|error| GltfError::Read {
        path: path.to_owned(),
        error,
    })?;
    let word = |at: usize| buffer::u32_at(&file.read(at, 4).ok()?, 0);
    if file.read(0, 4).ok().as_deref() != Some(&buffer::GLB_MAGIC[..]) {
        let text = file.read(0, file.len()).map_err(invalid)?.into_owned();
        return Ok((text, None));
    }
    let (json, bin) = glb_chunks(file.len(), word).map_err(invalid)?;
    let json = file
        .read(json.start, json.len())
        .map_err(invalid)?
        .into_owned();
    Ok((json, bin.map(|b| file.span(b))))
}

/// Returns the validated document of glTF JSON or GLB `bytes` and the GLB's binary chunk, if
/// any; rejects required extensions caustic does not read.
fn open_document<'b>(
    bytes: &'b [u8],
    path: &Path,
) -> Result<(Document, Option<&'b [u8]>), GltfError> {
    let invalid = |message: String| GltfError::Invalid {
        path: path.to_owned(),
        message,
    };
    let (json, bin) = if bytes.starts_with(buffer::GLB_MAGIC) {
        split_glb(bytes).map_err(invalid)?
    } else {
        (bytes, None)
    };
    // The spec says JSON has no byte-order mark but lets readers ignore one; serde_json would not.
    let root = gltf::json::Root::from_slice(crate::io::strip_bom(json))
        .map_err(|e| invalid(format!("invalid glTF JSON: {e}")))?;
    let enabled = gltf::json::extensions::ENABLED_EXTENSIONS;
    if let Some(ext) = root
        .extensions_required
        .iter()
        .find(|e| !enabled.contains(&e.as_str()))
    {
        return Err(GltfError::Unsupported {
            path: path.to_owned(),
            message: format!(
                "required extension {ext} (caustic reads {})",
                enabled.join(", ")
            ),
        });
    }
    // gltf-json's validation indexes the accessors by POSITION without a bounds check.
    let positions = Checked::Valid(Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let bad = prim.attributes.get(&positions).map(|i| i.value());
            if let Some(bad) = bad.filter(|&i| i >= root.accessors.len()) {
                return Err(invalid(format!(
                    "mesh {m} primitive {p}: POSITION accessor {bad} does not exist"
                )));
            }
        }
    }
    let doc = Document::from_json(root).map_err(|e| invalid(validation_message(e)))?;
    Ok((doc, bin))
}

/// Formats gltf's validation errors (at most three) as one message.
fn validation_message(error: gltf::Error) -> String {
    match error {
        gltf::Error::Validation(errors) => {
            let listed: Vec<String> = errors
                .iter()
                .take(3)
                .map(|(path, e)| format!("{path}: {e}"))
                .collect();
            let more = errors.len().saturating_sub(3);
            let tail = if more > 0 {
                format!(" (and {more} more)")
            } else {
                String::new()
            };
            format!("invalid glTF: {}{tail}", listed.join("; "))
        }
        other => format!("invalid glTF: {other}"),
    }
}

/// Returns each node reached from the scene's roots with its `world_from_node`, in depth-first
/// order; fails on a node reached twice (a cycle or a shared child) or a bad transform.
fn placements(doc: &Document) -> Result<Vec<(gltf::Node<'_>, DAffine3)>, String> {
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; doc.nodes().len()];
            for child in doc.nodes().flat_map(|n| n.children()) {
                is_child[child.index()] = true;
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut seen = vec![false; doc.nodes().len()];
    let mut stack: Vec<_> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DAffine3::IDENTITY))
        .collect();
    let mut out = Vec::new();
    while let Some((node, parent)) = stack.pop() {
        let i = node.index();
        if std::mem::replace(&mut seen[i], true) {
            return Err(format!(
                "node {i} is reached twice (glTF nodes must form a tree)"
            ));
        }
        let world = parent * local_transform(&node)?;
        let children: Vec<_> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
        out.push((node, world));
    }
    Ok(out)
}

/// Returns a node's `parent_from_node` in double precision.
fn local_transform(node: &gltf::Node) -> Result<DAffine3, String> {
    let d = |v: [f32; 3]| DVec3::from_array(v.map(f64::from));
    let m = match node.transform() {
        gltf::scene::Transform::Matrix { matrix: c } => DAffine3::from_cols(
            d([c[0][0], c[0][1], c[0][2]]),
            d([c[1][0], c[1][1], c[1][2]]),
            d([c[2][0], c[2][1], c[2][2]]),
            d([c[3][0], c[3][1], c[3][2]]),
        ),
        gltf::scene::Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let q = DQuat::from_array(rotation.map(f64::from));
            let length = q.length();
            if !(length > 0.0 && length.is_finite()) {
                return Err(format!(
                    "node {} has a zero rotation quaternion",
                    node.index()
                ));
            }
            DAffine3::from_scale_rotation_translation(d(scale), q / length, d(translation))
        }
    };
    if !m.is_finite() {
        return Err(format!("node {} has a non-finite transform", node.index()));
    }
    Ok(m)
}

/// Returns the vertex and index counts of a primitive, as its accessors declare them.
fn primitive_counts(prim: &gltf::Primitive) -> (u64, u64) {
    let vertices = prim
        .get(&Semantic::Positions)
        .map_or(0, |a| a.count() as u64);
    let indices = prim.indices().map_or(vertices, |a| a.count() as u64);
    (vertices, indices)
}

/// Returns a primitive's size for messages: "N vertices, M indices".
fn primitive_size(prim: &gltf::Primitive) -> String {
    let (vertices, indices) = primitive_counts(prim);
    format!("{vertices} vertices and {indices} indices, which")
}

/// Returns the bytes reading and merging a primitive takes, from its accessors' counts:
/// positions, normals and uvs, its indices, and the triangles they make (at most one per index),
/// each once in the primitive's part and once in the merged mesh; 0 for points and lines.
fn primitive_bytes(prim: &gltf::Primitive) -> u64 {
    let (vertices, indices) = primitive_counts(prim);
    let triangles = match prim.mode() {
        Mode::Triangles => indices / 3,
        Mode::TriangleStrip | Mode::TriangleFan => indices,
        _ => return 0,
    };
    let vertex = (2 * size_of::<Vec3>() + size_of::<Vec2>()) as u64;
    let triangle = 2 * size_of::<[u32; 3]>() as u64;
    vertices
        .saturating_mul(2 * vertex)
        .saturating_add(indices.saturating_mul(size_of::<u32>() as u64))
        .saturating_add(triangles.saturating_mul(triangle))
}

/// One triangle primitive's data before merging, in the primitive's own index space.
struct Part {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    triangles: Vec<[u32; 3]>,
    material: Option<usize>,
}

/// Reads one primitive, or `None` for points and lines; checks every index against the vertices.
fn read_primitive(prim: &gltf::Primitive, buffers: &[Buffer]) -> Result<Option<Part>, String> {
    let mode = prim.mode();
    if !matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(None);
    }
    let Some(position) = prim.get(&Semantic::Positions) else {
        return Err("has no POSITION attribute".to_owned());
    };
    let positions = read_vec3(&position, buffers, "position")?;
    let count = positions.len();
    let attribute = |semantic: Semantic, name: &str| -> Result<Option<gltf::Accessor>, String> {
        match prim.get(&semantic) {
            Some(a) if a.count() != count => Err(format!(
                "{name} accessor {} has {} elements for {count} positions",
                a.index(),
                a.count()
            )),
            a => Ok(a),
        }
    };
    let normals = attribute(Semantic::Normals, "NORMAL")?
        .map(|a| read_vec3(&a, buffers, "normal"))
        .transpose()?;
    let uvs = attribute(Semantic::TexCoords(0), "TEXCOORD_0")?
        .map(|a| read_uvs(&a, buffers))
        .transpose()?;
    let triangles = match prim.indices() {
        // The common case read straight into triangles: no list of single indices is made.
        Some(a) if mode == Mode::Triangles => read_triangle_list(&a, buffers, count)?,
        Some(a) => assemble(mode, &read_indices(&a, buffers, count)?),
        None if count > u32::MAX as usize => {
            return Err(format!("has {count} vertices, more than 4294967295"));
        }
        None => assemble(mode, &(0..count as u32).collect::<Vec<_>>()),
    };
    Ok(Some(Part {
        positions,
        normals,
        uvs,
        triangles,
        material: prim.material().index(),
    }))
}

/// Returns the triangles a `TRIANGLES`, `TRIANGLE_STRIP` or `TRIANGLE_FAN` index list draws, with
/// the winding glTF 2.0 §3.7.2.1 gives.
fn assemble(mode: Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    let n = idx.len().saturating_sub(2);
    match mode {
        Mode::TriangleStrip => (0..n)
            .map(|i| [idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..n).map(|i| [idx[i + 1], idx[i + 2], idx[0]]).collect(),
        _ => idx.as_chunks::<3>().0.to_vec(),
    }
}

/// Moves a primitive into the mesh's frame by `world` (invertible), keeping front faces front.
fn bake(part: &mut Part, world: &DAffine3) -> Result<(), String> {
    if *world == DAffine3::IDENTITY {
        return Ok(());
    }
    for (i, p) in part.positions.iter_mut().enumerate() {
        *p = world.transform_point3(p.as_dvec3()).as_vec3();
        if !p.is_finite() {
            return Err(format!("vertex {i} lands at a non-finite position"));
        }
        crate::range::coordinate(p.to_array()).map_err(|e| format!("vertex {i} lands at {e}"))?;
    }
    let normal_matrix: DMat3 = world.matrix3.inverse().transpose();
    for n in part.normals.iter_mut().flatten() {
        *n = (normal_matrix * n.as_dvec3()).normalize_or_zero().as_vec3();
    }
    if world.matrix3.determinant() < 0.0 {
        for t in &mut part.triangles {
            t.swap(1, 2);
        }
    }
    Ok(())
}

/// Merges the parts into one mesh and attaches the materials they use; `default_material` is
/// the glTF default material, for parts that have none.
fn merge(
    parts: Vec<Part>,
    default_material: Option<MeshMaterial>,
    doc: &Document,
    images: &mut Images,
    path: &Path,
) -> Result<MeshData, String> {
    let has_normals = parts.iter().all(|p| p.normals.is_some());
    let has_uvs = parts.iter().any(|p| p.uvs.is_some());
    let has_materials = parts.iter().any(|p| p.material.is_some());
    let default_index = doc.materials().len();
    let mut mesh = MeshData {
        source: path.to_owned(),
        ..Default::default()
    };
    for mut part in parts {
        let base = mesh.positions.len();
        if base + part.positions.len() > u32::MAX as usize {
            return Err("mesh has more than 4294967295 vertices".to_owned());
        }
        if mesh.positions.is_empty() && mesh.triangles.is_empty() {
            // The first part's arrays become the mesh's, moved, not copied: a file of one
            // primitive (most large ones) is never held twice.
            mesh.positions = std::mem::take(&mut part.positions);
            if has_normals {
                mesh.normals = part.normals.take().unwrap_or_default();
            }
            if has_uvs {
                let n = mesh.positions.len();
                mesh.uvs = part.uvs.take().unwrap_or_else(|| vec![Vec2::ZERO; n]);
            }
            mesh.triangles = std::mem::take(&mut part.triangles);
            if has_materials {
                let m = part.material.unwrap_or(default_index) as u32;
                mesh.triangle_materials = vec![m; mesh.triangles.len()];
            }
            continue;
        }
        let base = base as u32;
        mesh.positions.extend(&part.positions);
        if has_normals {
            mesh.normals.extend(part.normals.iter().flatten());
        }
        if has_uvs {
            match &part.uvs {
                Some(uvs) => mesh.uvs.extend(uvs),
                None => mesh
                    .uvs
                    .extend(std::iter::repeat_n(Vec2::ZERO, part.positions.len())),
            }
        }
        mesh.triangles
            .extend(part.triangles.iter().map(|t| t.map(|i| base + i)));
        if has_materials {
            let m = part.material.unwrap_or(default_index) as u32;
            let count = part.triangles.len();
            mesh.triangle_materials
                .extend(std::iter::repeat_n(m, count));
        }
    }
    if has_materials {
        for m in doc.materials() {
            mesh.materials.push(material(&m, images)?);
        }
        mesh.materials.extend(default_material);
    }
    Ok(mesh)
}

/// Returns the mesh material a glTF material maps to (the mapping is in the module doc).
fn material(m: &gltf::Material, images: &mut Images) -> Result<MeshMaterial, String> {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _] = pbr.base_color_factor();
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    let ior = m.ior().unwrap_or(1.5);
    // KHR_materials_volume: what light keeps after `attenuationDistance` (infinite by default:
    // clear) inside the volume.
    let (attenuation, distance) = m.volume().map_or(([1.0; 3], f32::INFINITY), |v| {
        (v.attenuation_color(), v.attenuation_distance())
    });
    let factors = [
        r,
        g,
        b,
        pbr.metallic_factor(),
        pbr.roughness_factor(),
        transmission,
        ior,
        attenuation[0],
        attenuation[1],
        attenuation[2],
    ];
    let name = material_name(m);
    if factors.iter().any(|f| !f.is_finite()) {
        return Err(format!("{name} has a non-finite factor"));
    }
    if distance.is_nan() || distance <= 0.0 {
        return Err(format!(
            "{name} has attenuationDistance {distance}; KHR_materials_volume needs a positive distance"
        ));
    }
    let base = Vec3::new(r, g, b).clamp(Vec3::ZERO, Vec3::ONE);
    let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
    let roughness = pbr.roughness_factor().clamp(0.0, 1.0);
    let surface = Reflectance::metallic(base.into(), metallic, roughness);
    let mut texture = |info: Option<gltf::Texture>, slot: &str| {
        info.map(|t| images.source(&t))
            .transpose()
            .map_err(|e| format!("{name}: {slot} texture: {e}"))
    };
    let base_colour_texture =
        texture(pbr.base_color_texture().map(|i| i.texture()), "base colour")?;
    let metallic_roughness_texture = texture(
        pbr.metallic_roughness_texture().map(|i| i.texture()),
        "metallic-roughness",
    )?;
    let normal = m.normal_texture();
    let normal_texture = texture(normal.as_ref().map(|n| n.texture()), "normal")?;
    let normal_scale = normal.as_ref().map_or(1.0, |n| n.scale());
    if !normal_scale.is_finite() {
        return Err(format!("{name} has a non-finite normal texture scale"));
    }
    let textured = base_colour_texture.is_some()
        || metallic_roughness_texture.is_some()
        || normal_texture.is_some();
    let pbr = textured.then_some(MeshPbr {
        base_colour: base,
        metallic,
        roughness,
        base_colour_texture,
        metallic_roughness_texture,
        normal_texture,
        normal_scale,
    });
    Ok(MeshMaterial {
        name,
        kd: surface.kd.into(),
        ks: surface.ks.into(),
        // Unused above roughness 0 (the GGX lobe replaces Phong); a perfect mirror at 0.
        shininess: MAX_SHININESS,
        transparency: transmission.clamp(0.0, 1.0),
        ior: ior.clamp(1.0, crate::range::MAX_IOR as f32),
        absorption: crate::material::absorption(attenuation, distance),
        roughness,
        texture: None,
        pbr,
        // Validated where the primitive becomes a light (`emitter`); kept only when it can be.
        emission: Some(Vec3::from(m.emissive_factor()) * m.emissive_strength().unwrap_or(1.0))
            .filter(|e| e.is_finite() && e.min_element() >= 0.0)
            .unwrap_or(Vec3::ZERO),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_follow_the_spec_winding() {
        let idx = [0, 1, 2, 3, 4];
        let strip = assemble(Mode::TriangleStrip, &idx);
        assert_eq!(strip, [[0, 1, 2], [1, 3, 2], [2, 3, 4]]);
        let fan = assemble(Mode::TriangleFan, &idx);
        assert_eq!(fan, [[1, 2, 0], [2, 3, 0], [3, 4, 0]]);
        assert_eq!(assemble(Mode::Triangles, &idx), [[0, 1, 2]]);
        assert!(assemble(Mode::TriangleFan, &idx[..2]).is_empty());
    }

    #[test]
    fn mirroring_transform_reverses_winding_and_transforms_normals() {
        let mut part = Part {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: Some(vec![Vec3::Z; 3]),
            uvs: None,
            triangles: vec![[0, 1, 2]],
            material: None,
        };
        let mirror = DAffine3::from_scale(DVec3::new(-2.0, 1.0, 1.0));
        bake(&mut part, &mirror).unwrap();
        assert_eq!(
            part.positions,
            [Vec3::ZERO, Vec3::new(-2.0, 0.0, 0.0), Vec3::Y]
        );
        assert_eq!(part.triangles, [[0, 2, 1]]);
        assert_eq!(part.normals.unwrap(), [Vec3::Z; 3]);
    }
}
