//! Mesh files in and out: glTF 2.0 import (hierarchies, index widths, containers, topologies,
//! materials, faults), OBJ materials from MTL, the loaders behind `gr.mesh`, and the same wave
//! mesh through OBJ and glTF. Every file is written by the test itself under `target/`.

use crate::common::{GltfFile, assert_same_mesh, out_dir};
use caustic::geometry::mesh::{ImageSource, MeshMaterial, MeshPbr};
use caustic::io::gltf::{load_gltf, parse_gltf};
use caustic::scene::meshes::load_meshes;
use glam::{Vec2, Vec3, vec3};
use std::path::Path;

// ---- glTF import ----

/// The unit triangle `(1,0,0), (0,1,0), (0,0,1)` with +z normals: positions accessor 0,
/// normals accessor 1.
fn unit_triangle() -> GltfFile {
    let mut f = GltfFile::default();
    f.floats("VEC3", &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    f.floats("VEC3", &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    f
}

const TRIANGLE_MESH: &str =
    r#""meshes":[{"primitives":[{"attributes":{"POSITION":0,"NORMAL":1}}]}]"#;

#[test]
fn node_hierarchy_bakes_trs_and_matrix_transforms_exactly() {
    let dir = out_dir("gltf-hierarchy");
    // Scene 1 is the default. Parent: T(1,2,3)·R_y(180°)·S(2,3,4), so v ↦ (1−2x, 2+3y, 3−4z).
    // Child: the column-major matrix T(0,1,0)·S(0.5), so in the world v ↦ (1−x, 5+1.5y, 3−2z).
    let rest = format!(
        r#""scene":1,"scenes":[{{"nodes":[]}},{{"nodes":[0]}}],"nodes":[
          {{"mesh":0,"children":[1],"translation":[1,2,3],"rotation":[0,1,0,0],"scale":[2,3,4]}},
          {{"mesh":0,"matrix":[0.5,0,0,0, 0,0.5,0,0, 0,0,0.5,0, 0,1,0,1]}}],{TRIANGLE_MESH}"#
    );
    let mesh = load_gltf(&unit_triangle().write_glb(&dir, "tree", &rest)).unwrap();
    let parent = [
        vec3(-1.0, 2.0, 3.0),
        vec3(1.0, 5.0, 3.0),
        vec3(1.0, 2.0, -1.0),
    ];
    let child = [
        vec3(0.0, 5.0, 3.0),
        vec3(1.0, 6.5, 3.0),
        vec3(1.0, 5.0, 1.0),
    ];
    assert_eq!(mesh.positions, [parent, child].concat());
    assert_eq!(mesh.triangles, [[0, 1, 2], [3, 4, 5]]);
    // The inverse transposes diag(−1/2, 1/3, −1/4) and diag(−1, 2/3, −1/2) send +z to −z.
    assert_eq!(mesh.normals, [-Vec3::Z; 6]);
    assert!(mesh.materials.is_empty() && mesh.triangle_materials.is_empty());

    // Without scenes every root node is read; a mirroring scale reverses the winding.
    let rest = format!(
        r#""nodes":[{{"mesh":0,"scale":[-1,1,1]}},{{"children":[0]}},{{"mesh":0}}],{TRIANGLE_MESH}"#
    );
    let mesh = load_gltf(&unit_triangle().write_embedded(&dir, "roots", &rest)).unwrap();
    assert_eq!(mesh.positions[..3], [-Vec3::X, Vec3::Y, Vec3::Z]);
    assert_eq!(mesh.triangles, [[0, 2, 1], [3, 4, 5]]);
    assert_eq!(mesh.normals, [Vec3::Z; 6]);
}

#[test]
fn reads_u8_u16_and_u32_indices_alike() {
    let dir = out_dir("gltf-indices");
    let mut meshes = Vec::new();
    for component in [5121, 5123, 5125] {
        let mut f = GltfFile::default();
        f.floats(
            "VEC3",
            &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0],
        );
        f.indices(component, &[0, 1, 2, 0, 2, 3, 3]);
        let rest = r#""meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],"nodes":[{"mesh":0}]"#;
        meshes.push(load_gltf(&f.write_external(&dir, &format!("quad{component}"), rest)).unwrap());
    }
    // The surplus seventh index is ignored.
    assert_eq!(meshes[0].triangles, [[0, 1, 2], [0, 2, 3]]);
    assert_same_mesh(&meshes[0], &meshes[1]);
    assert_same_mesh(&meshes[0], &meshes[2]);
}

/// A quad with normals, uvs and a material, as a glTF body over `f`'s accessors.
fn textured_quad(f: &mut GltfFile) -> String {
    f.floats(
        "VEC3",
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0],
    );
    f.floats(
        "VEC3",
        &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0],
    );
    f.floats("VEC2", &[0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0]);
    f.indices(5123, &[0, 1, 2, 0, 2, 3]);
    r#""scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,"translation":[0,0,-1]}],
       "materials":[{"name":"paint","pbrMetallicRoughness":{"baseColorFactor":[0.5,0.25,1,1]}}],
       "meshes":[{"primitives":[{"attributes":{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2},"indices":3,"material":0}]}]"#
        .to_owned()
}

/// Texture coordinates survive a primitive without them: a textured quad beside an
/// untextured one (Blender's textured box in a plain room) keeps its own, and the other's
/// vertices sit at (0, 0), rather than every triangle falling back to the whole texture.
#[test]
fn texture_coordinates_survive_a_primitive_without_them() {
    let dir = out_dir("gltf-partial-uvs");
    let mut f = GltfFile::default();
    let _ = textured_quad(&mut f);
    let rest = r#""nodes":[{"mesh":0}],"meshes":[{"primitives":[
        {"attributes":{"POSITION":0,"NORMAL":1},"indices":3},
        {"attributes":{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2},"indices":3}]}]"#;
    let mesh = load_gltf(&f.write_glb(&dir, "partial", rest)).unwrap();
    assert_eq!(mesh.uvs.len(), mesh.positions.len());
    assert_eq!(mesh.uvs[..4], [Vec2::ZERO; 4]);
    assert_eq!(mesh.uvs[4..], [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]);
}

#[test]
fn embedded_external_and_glb_files_give_identical_meshes() {
    let dir = out_dir("gltf-containers");
    let mut f = GltfFile::default();
    let rest = textured_quad(&mut f);
    let external = load_gltf(&f.write_external(&dir, "quad", &rest)).unwrap();
    let embedded = load_gltf(&f.write_embedded(&dir, "quad-embedded", &rest)).unwrap();
    let glb = load_gltf(&f.write_glb(&dir, "quad", &rest)).unwrap();
    assert_eq!(external.positions[2], vec3(1.0, 1.0, -1.0));
    assert_eq!(external.uvs[2], Vec2::ONE);
    assert_eq!(external.triangle_materials, [0, 0]);
    assert_eq!(external.materials[0].name, "paint");
    assert_eq!(glb.source, dir.join("quad.glb"));
    assert_same_mesh(&external, &embedded);
    assert_same_mesh(&external, &glb);
}

#[test]
fn strips_and_fans_make_the_spec_triangles_and_points_and_lines_are_skipped() {
    let dir = out_dir("gltf-topologies");
    let mut f = GltfFile::default();
    let xs: Vec<f32> = (0..5)
        .flat_map(|i| [i as f32, (i % 2) as f32, 0.0])
        .collect();
    f.floats("VEC3", &xs);
    f.indices(5121, &[4, 3, 2, 1]);
    let rest = r#""nodes":[{"mesh":0}],"meshes":[{"primitives":[
        {"attributes":{"POSITION":0},"mode":5},
        {"attributes":{"POSITION":0},"mode":6,"indices":1},
        {"attributes":{"POSITION":0},"mode":0},
        {"attributes":{"POSITION":0},"mode":1},
        {"attributes":{"POSITION":0},"mode":3}]}]"#;
    let mesh = load_gltf(&f.write_glb(&dir, "topologies", rest)).unwrap();
    assert_eq!(mesh.positions.len(), 10);
    // Strip over 0..5: {0,1,2}, {1,3,2}, {2,3,4}; fan over 4,3,2,1 (vertices 5..10): {3,2,4}, {2,1,4}.
    let expected = [[0, 1, 2], [1, 3, 2], [2, 3, 4], [8, 7, 9], [7, 6, 9]];
    assert_eq!(mesh.triangles, expected);
}

#[test]
fn materials_map_metal_roughness_transmission_ior_and_texture() {
    let dir = out_dir("gltf-materials");
    let mut f = GltfFile::default();
    f.floats("VEC3", &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    let image = f.view(b"\x89PNG not really");
    let rest = format!(
        r#""extensionsUsed":["KHR_materials_transmission","KHR_materials_ior"],
        "extensionsRequired":["KHR_materials_transmission"],
        "nodes":[{{"mesh":0}}],
        "images":[{{"uri":"water%20ripples.png"}},{{"bufferView":{image},"mimeType":"image/png"}}],
        "textures":[{{"source":0}},{{"source":1}}],
        "materials":[
          {{"name":"water","pbrMetallicRoughness":{{"baseColorFactor":[0.2,0.4,0.6,1],"metallicFactor":0,
            "roughnessFactor":0.5,"baseColorTexture":{{"index":0}}}},
            "extensions":{{"KHR_materials_transmission":{{"transmissionFactor":0.9}},"KHR_materials_ior":{{"ior":1.33}}}}}},
          {{"pbrMetallicRoughness":{{"baseColorFactor":[1,0.5,0.25,1],"roughnessFactor":0,
            "baseColorTexture":{{"index":1}}}}}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":1}},
          {{"attributes":{{"POSITION":0}}}},{{"attributes":{{"POSITION":0}},"material":0}}]}}]"#
    );
    let mesh = load_gltf(&f.write_external(&dir, "materials", &rest)).unwrap();
    assert_eq!(mesh.triangle_materials, [1, 2, 0]);
    let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
    let water = &mesh.materials[0];
    // Dielectric of roughness 0.5: its base colour, the 4 % specular lobe as GGX of roughness
    // 0.5 (α = 0.25), and a rough interface.
    assert!(close(water.kd, vec3(0.2, 0.4, 0.6)) && close(water.ks, Vec3::splat(0.04)));
    assert_eq!(
        (water.roughness, water.transparency, water.ior),
        (0.5, 0.9, 1.33)
    );
    // The base colour texture is carried with the factors it scales, the image a file beside
    // the glTF file.
    let pbr = water.pbr.as_ref().expect("a textured material");
    assert_eq!(
        pbr.base_colour_texture,
        Some(ImageSource::File(dir.join("water ripples.png")))
    );
    assert!(close(pbr.base_colour, vec3(0.2, 0.4, 0.6)));
    assert_eq!((pbr.metallic, pbr.roughness), (0.0, 0.5));
    assert_eq!(water.texture, None, "kd's own texture is OBJ's");
    let metal = &mesh.materials[1];
    // A smooth metal mirrors its base colour and has no diffuse lobe; its image is embedded:
    // the buffer view's bytes, decoded by the scene build.
    let expected = MeshMaterial {
        name: "material 1".to_owned(),
        kd: Vec3::ZERO,
        ks: vec3(1.0, 0.5, 0.25),
        shininess: 10_000.0,
        transparency: 0.0,
        ior: 1.5,
        absorption: glam::Vec3::ZERO,
        roughness: 0.0,
        texture: None,
        emission: Vec3::ZERO,
        pbr: Some(MeshPbr {
            base_colour: vec3(1.0, 0.5, 0.25),
            metallic: 1.0,
            roughness: 0.0,
            base_colour_texture: Some(ImageSource::Embedded {
                file: dir.join("materials.gltf"),
                image: 1,
                bytes: std::sync::Arc::from(&b"\x89PNG not really"[..]),
            }),
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
        }),
    };
    assert_eq!(*metal, expected);
    // The glTF default material (white, metallic 1, roughness 1) is a white conductor of
    // roughness 1, with no diffuse lobe.
    let default = &mesh.materials[2];
    assert_eq!(
        (default.kd, default.ks, default.roughness),
        (Vec3::ZERO, Vec3::ONE, 1.0)
    );
    assert_eq!((default.transparency, default.ior), (0.0, 1.5));
}

/// `KHR_materials_volume` (issue 35): the attenuation colour kept after the attenuation distance
/// becomes the absorption coefficient `σ = −ln(colour)/distance` per channel (Beer–Lambert); a
/// channel kept whole absorbs nothing, a missing distance (infinite) leaves the volume clear, and
/// a distance of zero or below is an error naming the material.
#[test]
fn gltf_volume_attenuation_becomes_absorption() {
    let dir = out_dir("gltf-volume");
    let file = |name: &str, volume: &str| {
        let mut f = GltfFile::default();
        f.floats("VEC3", &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        let rest = format!(
            r#""extensionsUsed":["KHR_materials_transmission","KHR_materials_volume"],
            "nodes":[{{"mesh":0}}],
            "materials":[{{"name":"sea","extensions":{{"KHR_materials_transmission":{{"transmissionFactor":1}},
              "KHR_materials_volume":{{{volume}}}}}}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"material":0}}]}}]"#
        );
        f.write_embedded(&dir, name, &rest)
    };
    let sea = file(
        "sea",
        r#""thicknessFactor":0.1,"attenuationColor":[0.5,0.8,1],"attenuationDistance":2"#,
    );
    let mesh = load_gltf(&sea).unwrap();
    let a = mesh.materials[0].absorption;
    let want = vec3(-(0.5f32.ln()) / 2.0, -(0.8f32.ln()) / 2.0, 0.0);
    assert!((a - want).abs().max_element() < 1e-6, "{a} against {want}");
    let clear = file("clear", r#""attenuationColor":[0.5,0.8,1]"#);
    assert_eq!(
        load_gltf(&clear).unwrap().materials[0].absorption,
        Vec3::ZERO
    );
    let bad = file(
        "bad",
        r#""attenuationColor":[0.5,0.8,1],"attenuationDistance":0"#,
    );
    let e = load_gltf(&bad).unwrap_err().to_string();
    assert!(
        e.contains("sea") && e.contains("attenuationDistance"),
        "{e}"
    );
}

/// Returns the error message parsing `bytes` as `path` gives; panics on success.
fn parse_error(bytes: &[u8], path: &Path) -> String {
    match parse_gltf(bytes, path) {
        Ok(_) => panic!("should be rejected: {}", String::from_utf8_lossy(bytes)),
        Err(e) => e.to_string(),
    }
}

#[test]
fn corrupt_truncated_and_unsupported_files_are_errors_naming_the_file() {
    let dir = out_dir("gltf-faults");
    let path = dir.join("bad.gltf");
    let body = format!(r#""nodes":[{{"mesh":0}}],{TRIANGLE_MESH}"#);
    let payload = {
        use base64::Engine;
        base64::engine::general_purpose::STANDARD.encode(unit_triangle().bin)
    };
    let uri = format!("data:application/octet-stream;base64,{payload}");
    let good = unit_triangle().json(Some(&uri), &body);
    assert!(parse_gltf(good.as_bytes(), &path).is_ok());
    let glb = unit_triangle().glb(&body);
    let with_bin = |bin: Vec<u8>| {
        let mut f = unit_triangle();
        f.bin = bin;
        f.glb(&body)
    };
    let mut nan = unit_triangle().bin;
    nan[4..8].copy_from_slice(&f32::NAN.to_le_bytes());
    let mut inf = unit_triangle().bin;
    inf[0..4].copy_from_slice(&f32::INFINITY.to_le_bytes());
    let index_mesh = TRIANGLE_MESH.replace(r#""NORMAL":1}"#, r#""NORMAL":1},"indices":2"#);
    let mut f = unit_triangle();
    f.indices(5123, &[0, 1, 3]);
    let bad_index = f.glb(&format!(r#""nodes":[{{"mesh":0}}],{index_mesh}"#));
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (
            b"{".to_vec(),
            "invalid glTF JSON: EOF while parsing an object at line 1 column 1",
        ),
        (b"glTF\x02\0\0\0".to_vec(), "truncated GLB file"),
        (
            glb[..glb.len() / 2].to_vec(),
            "truncated GLB file: header says",
        ),
        (
            good.replace(&payload, "").into_bytes(),
            "buffer 0 declares 72 bytes but holds only 0",
        ),
        (
            good.replace("base64,", "base64,@@").into_bytes(),
            "buffer 0: bad base64",
        ),
        (
            good.replace(&uri, "gone.bin").into_bytes(),
            "buffer 0: cannot read",
        ),
        (
            good.replace(";base64", "").into_bytes(),
            "buffer 0: data URI is not base64",
        ),
        (
            good.replace(r#""count":3"#, r#""count":4"#).into_bytes(),
            "runs past the end of buffer view",
        ),
        (
            good.replace(r#""POSITION":0"#, r#""POSITION":7"#)
                .into_bytes(),
            "POSITION accessor 7 does not exist",
        ),
        (
            good.replace(r#""NORMAL":1"#, r#""NORMAL":7"#).into_bytes(),
            "Index out of bounds",
        ),
        (
            good.replace(
                r#""nodes":[{"mesh":0}]"#,
                r#""scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,"children":[0]}]"#,
            )
            .into_bytes(),
            "node 0 is reached twice",
        ),
        (
            good.replace(
                r#""asset""#,
                r#""extensionsRequired":["KHR_draco_mesh_compression"],"asset""#,
            )
            .into_bytes(),
            "unsupported: required extension KHR_draco_mesh_compression",
        ),
        (
            with_bin(nan),
            "mesh 0 primitive 0: position 0 of accessor 0 is not finite",
        ),
        (with_bin(inf), "position 0 of accessor 0 is not finite"),
        (
            bad_index,
            "mesh 0 primitive 0: index 3 out of range (3 vertices)",
        ),
    ];
    for (bytes, message) in cases {
        let e = parse_error(&bytes, &path);
        assert!(e.starts_with(&format!("{}: ", path.display())), "{e}");
        assert!(e.contains(message), "expected `{message}` in: {e}");
    }
    let missing = dir.join("missing.glb");
    let e = load_gltf(&missing).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!("{}: cannot read: ", missing.display())),
        "{e}"
    );
}

#[test]
fn mangled_glb_files_never_panic() {
    let mut f = GltfFile::default();
    let rest = textured_quad(&mut f);
    let valid = f.glb(&rest);
    let path = Path::new("mangled.glb");
    let mut rng = caustic::sampling::Rng::new(7, caustic::sampling::Pass::Pixel, 0);
    let mut next = |bound: usize| rng.next_u32() as usize % bound;
    let mut rejected = 0;
    for round in 0..3000 {
        let mut bytes = valid.clone();
        for _ in 0..1 + round % 3 {
            let at = next(bytes.len().max(1));
            match next(3) {
                0 if at < bytes.len() => bytes[at] = next(256) as u8,
                1 if at < bytes.len() => bytes[at] ^= 1 << next(8),
                _ => bytes.truncate(at),
            }
        }
        match parse_gltf(&bytes, path) {
            Ok(mesh) => assert!(
                mesh.triangles
                    .iter()
                    .flatten()
                    .all(|&i| (i as usize) < mesh.positions.len())
            ),
            Err(e) => {
                assert!(e.to_string().starts_with("mangled.glb: "), "{e}");
                rejected += 1;
            }
        }
    }
    assert!(
        (300..3000).contains(&rejected),
        "{rejected} of 3000 rejected"
    );
}

// ---- OBJ materials from MTL ----

use caustic::io::obj::load_obj;

/// Writes `colours.mtl` and an OBJ quad `name.obj` naming it; returns the OBJ's path.
fn obj_with_mtl(dir: &Path, name: &str, faces: &str) -> std::path::PathBuf {
    let mtl = "# two materials\nnewmtl red\nKd 0.8 0.2 0.1\nKs 0 0 0\nNs 20\nd 1\nNi 1.5\n\
               map_Kd -s 1 1 1 tex/red.png\n\nnewmtl glass\nKd 0 0 0\nTr 0.9\nNi 1.33\n";
    std::fs::write(dir.join("colours.mtl"), mtl).unwrap();
    let path = dir.join(format!("{name}.obj"));
    let quad = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n";
    std::fs::write(&path, format!("mtllib colours.mtl\n{quad}{faces}")).unwrap();
    path
}

#[test]
fn obj_mtl_materials_fill_per_triangle_materials() {
    let dir = out_dir("obj-mtl");
    let faces = "f 1 2 3\nusemtl red\nf 1 3 4\nusemtl glass\nf 2 3 4\nusemtl nowhere\nf 1 2 4\n";
    let mesh = load_obj(&obj_with_mtl(&dir, "shapes", faces)).unwrap();
    // Faces before any usemtl, or naming an unknown material, get the renderer's grey.
    assert_eq!(mesh.triangle_materials, [2, 0, 1, 2]);
    let red = MeshMaterial {
        name: "red".to_owned(),
        kd: vec3(0.8, 0.2, 0.1),
        ks: Vec3::ZERO,
        shininess: 20.0,
        transparency: 0.0,
        ior: 1.5,
        absorption: glam::Vec3::ZERO,
        roughness: 0.0,
        texture: Some(dir.join("tex/red.png")),
        emission: Vec3::ZERO,
        pbr: None,
    };
    let glass = MeshMaterial {
        name: "glass".to_owned(),
        kd: Vec3::ZERO,
        ks: Vec3::ZERO,
        shininess: 0.0,
        transparency: 0.9,
        ior: 1.33,
        absorption: glam::Vec3::ZERO,
        roughness: 0.0,
        texture: None,
        emission: Vec3::ZERO,
        pbr: None,
    };
    let grey = MeshMaterial {
        name: "(no usemtl)".to_owned(),
        kd: Vec3::splat(0.6),
        ks: Vec3::ZERO,
        shininess: 0.0,
        transparency: 0.0,
        ior: 1.0,
        absorption: glam::Vec3::ZERO,
        roughness: 0.0,
        texture: None,
        emission: Vec3::ZERO,
        pbr: None,
    };
    assert_eq!(mesh.materials, [red, glass, grey]);

    // Without usemtl, or with the library missing, the mesh carries no materials.
    let plain = load_obj(&obj_with_mtl(&dir, "plain", "f 1 2 3\n")).unwrap();
    assert!(plain.materials.is_empty() && plain.triangle_materials.is_empty());
    let lost = dir.join("lost.obj");
    std::fs::write(
        &lost,
        "mtllib gone.mtl\nusemtl red\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let lost = load_obj(&lost).unwrap();
    assert!(lost.materials.is_empty() && lost.triangle_materials.is_empty());

    // A malformed library is an error naming the .mtl file and line.
    std::fs::write(dir.join("bad.mtl"), "newmtl x\nKd 0.5\n").unwrap();
    let bad = dir.join("bad.obj");
    std::fs::write(&bad, "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let e = load_obj(&bad).unwrap_err().to_string();
    let mtl = dir.join("bad.mtl");
    assert_eq!(
        e,
        format!("{}:2: `Kd` needs 3 numbers, found 1", mtl.display())
    );
}

// ---- Mesh materials in scenes, and gr.mesh's choice of loader ----

use crate::common::{render_films, render_films_with, run_lua_in, whitted};

#[test]
fn render_shows_the_mtl_colour_unless_the_script_sets_a_material() {
    let dir = out_dir("obj-mtl-render");
    obj_with_mtl(&dir, "red", "usemtl red\nf 1 2 3\nf 1 3 4\n");
    std::fs::write(
        dir.join("bare.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n",
    )
    .unwrap();
    // Ambient light only (the light is behind the quads): each quad pixel is exactly its kd.
    let script = r#"
        root = gr.node('root')
        own = gr.mesh('own', 'red.obj')               -- the MTL's red
        own:translate(-3, 0, 0)
        root:add_child(own)
        painted = gr.mesh('painted', 'red.obj')       -- the script's green wins
        painted:set_material(gr.material({0.1, 0.7, 0.2}, {0, 0, 0}, 0))
        root:add_child(painted)
        bare = gr.mesh('bare', 'bare.obj')            -- no material anywhere: grey
        bare:translate(3, 0, 0)
        root:add_child(bare)
        gr.render(root, 'x.png', 96, 32, {0, 0, 8}, {0, 0, -1}, {0, 1, 0}, 50, {1, 1, 1},
                  {gr.light({0, 0, -100}, {1, 1, 1}, {1, 0, 0})})
    "#;
    let films = render_films(script.as_bytes(), "mtl.lua", &dir).unwrap();
    let (_, camera, film) = &films[0];
    let pixel_at = |x: f32| {
        // The pixel whose ray crosses z = 0 nearest to (x, 0).
        let (px, _) = (0..film.width)
            .map(|px| (px, camera.ray(px as f32 + 0.5, 16.5)))
            .min_by(|a, b| {
                let at = |r: &caustic::geometry::Ray| (r.at(-r.origin.z / r.dir.z).x - x).abs();
                at(&a.1).total_cmp(&at(&b.1))
            })
            .unwrap();
        film.get(px, 16)
    };
    assert_eq!(pixel_at(-3.0), glam::Vec3A::new(0.8, 0.2, 0.1));
    assert_eq!(pixel_at(0.0), glam::Vec3A::new(0.1, 0.7, 0.2));
    assert_eq!(pixel_at(3.0), glam::Vec3A::splat(0.6));
}

/// A glTF metal of roughness r is the one BSDF's GGX conductor of colour `baseColor` and
/// roughness r (issue 37): the file's material renders bit for bit as the script's
/// `gr.material` with `gr.roughness`, where the Phong approximation it replaced did not.
#[test]
fn gltf_roughness_renders_as_the_ggx_conductor_of_gr_roughness() {
    let dir = out_dir("gltf-rough-render");
    let mut f = GltfFile::default();
    f.floats(
        "VEC3",
        &[
            -1.0, 0.0, -1.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0, -1.0, 0.0, 1.0,
        ],
    );
    f.indices(5125, &[0, 2, 1, 0, 3, 2]);
    let rest = r#""nodes":[{"mesh":0}],
        "materials":[{"pbrMetallicRoughness":{"baseColorFactor":[0.95,0.64,0.54,1],
          "metallicFactor":1,"roughnessFactor":0.4}}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"material":0}]}]"#;
    f.write_glb(&dir, "copper", rest);
    let render = |material: &str| {
        let script = format!(
            r#"
            root = gr.node('root')
            floor = gr.mesh('floor', 'copper.glb')
            {material}
            root:add_child(floor)
            gr.render(root, 'x.png', 24, 24, {{0, 1.5, 2.5}}, {{0, -1.5, -2.5}}, {{0, 1, 0}}, 50,
                      {{0, 0, 0}}, {{gr.light({{0.4, 2, -0.6}}, {{1, 1, 1}}, {{1, 0, 0}})}})
        "#
        );
        let films = render_films_with(script.as_bytes(), "rough.lua", &dir, &whitted()).unwrap();
        films.into_iter().next().unwrap().2
    };
    let file = render("");
    let script = render(
        "m = gr.material({0, 0, 0}, {0.95, 0.64, 0.54}, 10000)
         gr.roughness(m, 0.4)
         floor:set_material(m)",
    );
    let pixels = |film: &caustic::film::Film| {
        (0..film.height)
            .flat_map(|y| (0..film.width).map(move |x| (x, y)))
            .map(|(x, y)| film.get(x, y))
            .collect::<Vec<_>>()
    };
    let (a, b) = (pixels(&file), pixels(&script));
    let lit = a.iter().filter(|p| p.max_element() > 1e-3).count();
    assert!(
        lit > 50,
        "the rough floor should show the light's lobe: {lit} lit pixels"
    );
    assert_eq!(a, b);
}

#[test]
fn gr_mesh_picks_the_loader_by_extension() {
    let dir = out_dir("lua-mesh-formats");
    let mut f = GltfFile::default();
    let rest = textured_quad(&mut f);
    std::fs::write(dir.join("QUAD.GLB"), f.glb(&rest)).unwrap();
    f.write_external(&dir, "quad", &rest);
    std::fs::write(dir.join("quad.ply"), "ply\n").unwrap();
    std::fs::write(dir.join("bad.gltf"), "{\"asset\":").unwrap();
    let d = run_lua_in(
        "a = gr.mesh('a', 'QUAD.GLB')\nb = gr.mesh('b', 'quad.gltf')",
        &dir,
    )
    .unwrap();
    let meshes = load_meshes(&d).unwrap();
    assert_same_mesh(&meshes[0], &meshes[1]);
    assert_eq!(meshes[0].triangle_count(), 2);
    let error = |src: &str| run_lua_in(src, &dir).unwrap_err().to_string();
    let ply = run_lua_in("m = gr.mesh('m', 'quad.ply')", &dir).unwrap_err();
    assert_eq!(ply.fault(), Some(caustic::Fault::MeshLoad), "{ply}");
    assert_eq!(
        error("\nm = gr.mesh('m', 'quad.ply')"),
        "test.lua:2: cannot load mesh 'quad.ply': unsupported format '.ply' (caustic reads .obj, .gltf and .glb)"
    );
    // The format is checked by gr.mesh; the file is read when a scene is built.
    let d = run_lua_in("m = gr.mesh('m', 'bad.gltf')", &dir).unwrap();
    let e = load_meshes(&d).unwrap_err();
    assert_eq!(e.fault(), Some(caustic::Fault::MeshLoad), "{e}");
    let e = e.to_string();
    let file = dir.join("bad.gltf");
    let prefix = format!(
        "test.lua:1: cannot load mesh 'bad.gltf': {}: invalid glTF JSON",
        file.display()
    );
    assert!(e.starts_with(&prefix), "{e}");
}

// ---- The water generator, and one mesh through OBJ and glTF ----

use caustic::geometry::water::{WaveField, WaveParams, wave_mesh};
use caustic::io::gltf::write_gltf;
use caustic::io::obj::write_obj;

fn waves(n: u32, seed: u64) -> WaveParams {
    WaveParams {
        n,
        seed,
        ..Default::default()
    }
}

#[test]
fn wave_mesh_counts_normals_and_uvs_match_the_analytic_surface() {
    let p = waves(33, 7);
    let mesh = wave_mesh(&p);
    assert_eq!(
        (mesh.positions.len(), mesh.triangle_count()),
        (33 * 33, 2 * 32 * 32)
    );
    assert_eq!((mesh.normals.len(), mesh.uvs.len()), (33 * 33, 33 * 33));
    let field = WaveField::new(&p);
    let h = 1e-4;
    for ((v, n), uv) in mesh.positions.iter().zip(&mesh.normals).zip(&mesh.uvs) {
        let (x, z) = (v.x as f64, v.z as f64);
        assert!((n.length() - 1.0).abs() < 1e-6, "{n}");
        assert!(v.y.abs() <= p.amplitude);
        assert_eq!(v.y, field.height(x, z) as f32);
        // Central differences of the height give the same normal.
        let dx = (field.height(x + h, z) - field.height(x - h, z)) / (2.0 * h);
        let dz = (field.height(x, z + h) - field.height(x, z - h)) / (2.0 * h);
        let numeric = glam::DVec3::new(-dx, 1.0, -dz).normalize().as_vec3();
        assert!((*n - numeric).length() < 1e-6, "{n} vs {numeric}");
        assert!((*n - field.normal(x, z)).length() < 1e-6);
        // The uv is the grid position scaled to [0, 1]².
        let expected = (Vec2::new(v.x, v.z) / p.size + 0.5).clamp(Vec2::ZERO, Vec2::ONE);
        assert!(
            (*uv - expected).abs().max_element() < 1e-6,
            "{uv} vs {expected}"
        );
    }
    // Every triangle faces up, like the vertex normals.
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
        assert!((b - a).cross(c - a).y > 0.0);
    }
    assert_eq!(
        wave_mesh(&p).positions,
        mesh.positions,
        "same seed, same mesh"
    );
    assert_ne!(wave_mesh(&waves(33, 8)).positions, mesh.positions);
}

#[test]
fn one_wave_mesh_as_obj_and_gltf_loads_and_renders_identically() {
    let dir = out_dir("water-formats");
    let mesh = wave_mesh(&waves(65, 3));
    let files = ["water.obj", "water.gltf", "water.glb"];
    write_obj(&mesh, &dir.join(files[0])).unwrap();
    write_gltf(&mesh, &dir.join(files[1])).unwrap();
    write_gltf(&mesh, &dir.join(files[2])).unwrap();
    assert_same_mesh(&mesh, &load_obj(&dir.join(files[0])).unwrap());
    assert_same_mesh(&mesh, &load_gltf(&dir.join(files[1])).unwrap());
    assert_same_mesh(&mesh, &load_gltf(&dir.join(files[2])).unwrap());
    let images: Vec<_> = files
        .iter()
        .map(|file| {
            let script = format!(
                r#"
                water = gr.mesh('water', '{file}')
                water:set_material(gr.material({{0.1, 0.3, 0.5}}, {{0.4, 0.4, 0.4}}, 40))
                light = gr.light({{2, 4, 3}}, {{0.9, 0.9, 0.8}}, {{1, 0, 0}})
                gr.render(water, 'x.png', 48, 32, {{0, 4, 7}}, {{0, -4, -7}}, {{0, 1, 0}}, 50,
                          {{0.1, 0.1, 0.1}}, {{light}})
                "#
            );
            let films = render_films(script.as_bytes(), "water.lua", &dir).unwrap();
            films.into_iter().next().unwrap().2.pixels
        })
        .collect();
    assert_eq!(images[0], images[1], "OBJ and glTF render alike");
    assert_eq!(images[0], images[2], "OBJ and GLB render alike");
    // The waves show: the lit surface is not one flat colour.
    let distinct = images[0]
        .iter()
        .filter(|&&p| p != images[0][images[0].len() / 2])
        .count();
    assert!(distinct > images[0].len() / 2, "{distinct}");
}

/// A GLB on disk is read in runs of a few MiB (its BIN chunk is never read whole, see
/// `io::gltf`'s buffer module); what it gives must be what the same bytes give in memory, and
/// what the file holds: here an interleaved view (positions and normals 24 bytes apart) of 6 MB
/// and 6 MB of `u32` indices, each read in two runs whose edges fall inside an element's
/// stride; and a container that lies about its size on disk is refused as in memory.
#[test]
fn glb_files_stream_in_runs_and_read_as_in_memory() {
    let n = 500u32;
    let (vertices, cells) = (n * n, (n - 1) * (n - 1));
    let mut bin = Vec::new();
    let position = |i: u32| {
        vec3(
            (i % n) as f32 * 0.01,
            ((i * 7) % 13) as f32 * 0.001,
            (i / n) as f32 * 0.01,
        )
    };
    let normal = |i: u32| vec3(0.0, 1.0, (i % 3) as f32).normalize();
    for i in 0..vertices {
        for v in [position(i), normal(i)] {
            bin.extend(v.to_array().iter().flat_map(|f| f.to_le_bytes()));
        }
    }
    let mut triangles = Vec::new();
    for c in 0..cells {
        let (x, z) = (c % (n - 1), c / (n - 1));
        let a = z * n + x;
        triangles.extend([[a, a + n, a + 1], [a + 1, a + n, a + n + 1]]);
    }
    bin.extend(triangles.iter().flatten().flat_map(|i| i.to_le_bytes()));
    let vbytes = vertices as usize * 24;
    let max = position(vertices - 1);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2}}]}}],
        "buffers":[{{"byteLength":{}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{vbytes},"byteStride":24}},
                       {{"buffer":0,"byteOffset":{vbytes},"byteLength":{}}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":{vertices},"type":"VEC3","min":[0,0,0],"max":[{},0.012,{}]}},
                     {{"bufferView":0,"byteOffset":12,"componentType":5126,"count":{vertices},"type":"VEC3"}},
                     {{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}]}}"#,
        bin.len(),
        bin.len() - vbytes,
        max.x,
        max.z,
        triangles.len() * 3
    );
    let bytes = crate::common::glb(&json, &bin);
    assert!(
        vbytes > 4 << 20 && bin.len() - vbytes > 4 << 20,
        "each accessor spans two runs"
    );
    let dir = out_dir("glb_streaming");
    let path = dir.join("grid.glb");
    std::fs::write(&path, &bytes).unwrap();
    let from_file = load_gltf(&path).unwrap();
    let from_memory = parse_gltf(&bytes, &path).unwrap();
    assert_same_mesh(&from_file, &from_memory);
    assert_eq!(from_file.triangles, triangles);
    assert_eq!(from_file.positions.len(), vertices as usize);
    for i in [0, 1, 174_761, 174_762, 174_763, vertices / 2, vertices - 1] {
        assert_eq!(from_file.positions[i as usize], position(i), "position {i}");
        assert_eq!(from_file.normals[i as usize], normal(i), "normal {i}");
    }
    // The container's faults, on disk as in memory.
    let cut = dir.join("cut.glb");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    let e = load_gltf(&cut).unwrap_err().to_string();
    assert!(
        e.starts_with(&format!(
            "{}: truncated GLB file: header says",
            cut.display()
        )),
        "{e}"
    );
    // A whole container whose BIN chunk holds 8 bytes of the buffer's 12 MB.
    let bin_len_at = 12 + 8 + u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut short_chunk = bytes[..bin_len_at + 16].to_vec();
    short_chunk[bin_len_at..bin_len_at + 4].copy_from_slice(&8u32.to_le_bytes());
    let total = (short_chunk.len() as u32).to_le_bytes();
    short_chunk[8..12].copy_from_slice(&total);
    let lying = dir.join("lying.glb");
    std::fs::write(&lying, &short_chunk).unwrap();
    let e = load_gltf(&lying).unwrap_err().to_string();
    assert!(e.contains("buffer 0 declares"), "{e}");
}

/// An OBJ file is streamed line by line (never held whole); it must read as the same text
/// parsed in memory does: a byte-order mark, CRLF and bare LF endings, bytes that are not
/// UTF-8 in a comment and a group name, no final newline, normals and uvs, and a fault's line
/// number, found by reading the file again.
#[test]
fn obj_files_stream_and_read_as_in_memory() {
    use caustic::io::obj::parse_obj;
    let dir = out_dir("obj_streaming");
    let mut text = b"\xEF\xBB\xBFv 0 0 0\r\nv 1 0 0\nv 0 1 0\r\n# caf\xE9 \xFF\xFE\n".to_vec();
    for i in 0..2000 {
        text.extend(format!("v {} {} 0.5\n", i as f32 * 0.001, (i % 7) as f32 * 0.1).as_bytes());
    }
    text.extend(b"vt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\ng gr\xC3\x28oup\r\n");
    for i in 4..2000 {
        text.extend(format!("f {}/1/1 {}/2/1 {}/3/1\n", i, i + 1, i + 2).as_bytes());
    }
    text.extend(b"f 1/1/1 2/2/1 3/3/1");
    let path = dir.join("streamed.obj");
    std::fs::write(&path, &text).unwrap();
    let from_file = load_obj(&path).unwrap();
    let from_memory = parse_obj(&String::from_utf8_lossy(&text), &path).unwrap();
    assert_same_mesh(&from_file, &from_memory);
    assert_eq!(from_file.triangles.len(), 1997);
    assert_eq!(from_file.positions.len(), from_file.normals.len());
    // The last vertex a face uses (the 1998th `v` of the loop; vertices no face uses are dropped).
    let last = Vec3::new(1997.0 * 0.001, (1997 % 7) as f32 * 0.1, 0.5);
    assert!(from_file.positions.contains(&last));
    // A fault on the last line, which tobj reports and a third pass over the file locates.
    let mut bad = text.clone();
    bad.extend(b"\nf 1 2 99999\n");
    std::fs::write(&path, &bad).unwrap();
    let error = |r: Result<_, caustic::io::obj::ObjError>| match r {
        Ok(_) => panic!("an out-of-range face index was accepted"),
        Err(e) => e.to_string(),
    };
    let on_disk = error(load_obj(&path));
    let in_memory = error(parse_obj(&String::from_utf8_lossy(&bad), &path));
    assert_eq!(on_disk, in_memory);
    let line = bad.iter().filter(|&&b| b == b'\n').count();
    assert!(
        on_disk.starts_with(&format!("{}:{line}: ", path.display())),
        "{on_disk}"
    );
}
