//! Input that real tools write and numbers that are accepted but would render wrong: byte-order
//! marks and CRLF line ends in every text format, the inline `gr.mesh` form's argument errors,
//! and the numeric ranges the renderer enforces (each proved safe by a render at its edge).

mod common;

use caustic::io::gltf::load_gltf;
use caustic::io::obj::load_obj;
use common::{GltfFile, assert_same_mesh, out_dir};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// The UTF-8 byte-order mark.
const BOM: &str = "\u{FEFF}";

/// Writes `text` to `dir/name` and returns the path.
fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Returns `text` with every `\n` turned into `\r\n`, as Windows tools write it.
fn crlf(text: &str) -> String {
    text.replace('\n', "\r\n")
}

// ---- byte-order marks and CRLF ----

/// A quad whose first vertex matters: losing it shifts every face onto other vertices.
const QUAD_OBJ: &str = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nvn 0 0 1\n\
                        mtllib quad.mtl\nusemtl red\nf 1/1/1 2/2/1 3/2/1\nf 1/1/1 3/2/1 4/1/1\n";
const QUAD_MTL: &str = "newmtl red\nKd 0.8 0.1 0.1\nKs 0.2 0.2 0.2\nNs 10\n";

#[test]
fn obj_and_mtl_with_a_byte_order_mark_and_crlf_load_like_plain_files() {
    let dir = out_dir("quirks-obj-bom");
    write(&dir, "quad.mtl", QUAD_MTL);
    let plain = load_obj(&write(&dir, "plain.obj", QUAD_OBJ)).unwrap();
    assert_eq!(plain.positions[0], Vec3::ZERO);
    assert_eq!(plain.materials[0].kd, Vec3::new(0.8, 0.1, 0.1));
    let variants = [
        format!("{BOM}{QUAD_OBJ}"),
        crlf(QUAD_OBJ),
        format!("{BOM}{}", crlf(QUAD_OBJ)),
    ];
    for (i, text) in variants.iter().enumerate() {
        // The MTL gets the same treatment as its OBJ: a BOM would hide its `newmtl`.
        let sub = dir.join(format!("v{i}"));
        std::fs::create_dir_all(&sub).unwrap();
        let mtl = if text.starts_with(BOM) {
            format!("{BOM}{}", crlf(QUAD_MTL))
        } else {
            crlf(QUAD_MTL)
        };
        write(&sub, "quad.mtl", &mtl);
        let mesh = load_obj(&write(&sub, "quad.obj", text)).unwrap();
        assert_same_mesh(&mesh, &plain);
        assert_eq!(mesh.materials[0].name, "red", "variant {i}");
    }
}

#[test]
fn a_byte_order_mark_does_not_shift_the_faces_of_an_obj() {
    // Before the fix tobj dropped `\u{FEFF}v 0 0 0`, so face 1 2 3 used the old vertices 2, 3, 4.
    let dir = out_dir("quirks-obj-bom-shift");
    let text = format!("{BOM}v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\n");
    let mesh = load_obj(&write(&dir, "tri.obj", &text)).unwrap();
    assert_eq!(mesh.positions, [Vec3::ZERO, Vec3::X, Vec3::Y]);
    assert_eq!(mesh.triangles, [[0, 1, 2]]);
    // A bad line is still reported at its own line number.
    let text = format!("{BOM}v 0 0 0\r\nv 1 x 0\r\n");
    let error = load_obj(&write(&dir, "bad.obj", &text)).unwrap_err();
    assert!(
        error
            .to_string()
            .ends_with("bad.obj:2: malformed number `x` in `v` line"),
        "{error}"
    );
}

/// The triangle `(1,0,0), (0,1,0), (0,0,1)` as one glTF node and mesh.
fn gltf_triangle() -> (GltfFile, &'static str) {
    let mut f = GltfFile::default();
    f.floats("VEC3", &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    let rest = r#""scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]"#;
    (f, rest)
}

#[test]
fn gltf_json_with_a_byte_order_mark_and_crlf_loads() {
    let dir = out_dir("quirks-gltf-bom");
    let (f, rest) = gltf_triangle();
    let plain = load_gltf(&f.write_external(&dir, "plain", rest)).unwrap();
    assert_eq!(plain.positions, [Vec3::X, Vec3::Y, Vec3::Z]);
    // A .gltf saved by a Windows editor: BOM and CRLF around the same JSON.
    let json = f.json(Some("plain.bin"), rest);
    let text = format!("{BOM}{}", crlf(&json));
    let mesh = load_gltf(&write(&dir, "bom.gltf", &text)).unwrap();
    assert_same_mesh(&mesh, &plain);
    // The same inside a GLB's JSON chunk: the chunk rebuilt around the marked JSON.
    let plain_glb = f.glb(rest);
    let old_len = u32::from_le_bytes(plain_glb[12..16].try_into().unwrap()) as usize;
    let mut json = format!("{BOM}{}", f.json(None, rest)).into_bytes();
    json.resize(json.len().next_multiple_of(4), b' ');
    let bin_chunk = &plain_glb[20 + old_len..];
    let total = (12 + 8 + json.len() + bin_chunk.len()) as u32;
    let mut glb = [&b"glTF"[..], &2u32.to_le_bytes(), &total.to_le_bytes()].concat();
    glb.extend((json.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(json);
    glb.extend(bin_chunk);
    std::fs::write(dir.join("bom.glb"), &glb).unwrap();
    let mesh = load_gltf(&dir.join("bom.glb")).unwrap();
    assert_same_mesh(&mesh, &plain);
}

#[test]
fn a_study_curve_saved_as_csv_utf8_with_a_byte_order_mark_reads() {
    let dir = out_dir("quirks-csv-bom");
    let text = format!("{BOM}cpu_s,rel_rmse\r\n1.5,0.25\r\n3,0.125\r\n");
    let curve = caustic::study::Curve::read("other", &write(&dir, "curve.csv", &text)).unwrap();
    assert_eq!(curve.points, [(1.5, 0.25), (3.0, 0.125)]);
}

// ---- the inline form of gr.mesh ----

/// Returns the error of `gr.mesh('m', VERTS, FACES)` at line 2 of `test.lua`.
fn inline_error(verts: &str, faces: &str) -> String {
    common::lua_error(&format!("x = 1\nm = gr.mesh('m', {verts}, {faces})"))
}

const TRI: &str = "{{0,0,0},{1,0,0},{0,1,0}}";

#[test]
fn inline_mesh_faults_name_the_line_the_argument_and_the_element() {
    let bad3 = |detail: &str| format!("test.lua:2: bad argument #3 to 'mesh' ({detail})");
    let bad2 = |detail: &str| format!("test.lua:2: bad argument #2 to 'mesh' ({detail})");
    let cases = [
        (
            TRI,
            "{{1,2,'x'}}",
            bad3("face 1, index 3: integer expected, got string"),
        ),
        (
            TRI,
            "{{0,1,2},{0,1,2.5}}",
            bad3("face 2, index 3: integer expected, got 2.5 (no integer representation)"),
        ),
        (
            TRI,
            "{{0,1,1e300}}",
            bad3("face 1, index 3: integer expected, got 1e300 (beyond 64-bit integers)"),
        ),
        (
            TRI,
            "{{0,1,{}}}",
            bad3("face 1, index 3: integer expected, got table"),
        ),
        (
            TRI,
            "{{0,1,nil,2}}",
            bad3("face 1, index 3: integer expected, got nil"),
        ),
        (
            TRI,
            "{{0,1,5}}",
            bad3("face 1: index 5 out of range (0..3)"),
        ),
        (
            TRI,
            "{{0,1,-1}}",
            bad3("face 1: index -1 out of range (0..3)"),
        ),
        (TRI, "{1}", bad3("face 1 is not a table (got number)")),
        (TRI, "{{0,1}}", bad3("face 1 has fewer than 3 vertices")),
        (TRI, "'faces'", bad3("table of faces expected, got string")),
        (TRI, "nil", bad3("table of faces expected, got nil")),
        (
            "{{0,0,0},{1,0,0},{0,1,'y'}}",
            "{{0,1,2}}",
            bad2("vertex 3, entry 3: number expected, got string"),
        ),
        (
            "{{0,0,0},{1,0},{0,1,0}}",
            "{{0,1,2}}",
            bad2("vertex 2: 3-tuple expected, got 2 entries"),
        ),
        (
            "{{0,0,0},{1,0,0,1},{0,1,0}}",
            "{{0,1,2}}",
            bad2("vertex 2: 3-tuple expected, got 4 entries"),
        ),
        (
            "{{0,0,0},7,{0,1,0}}",
            "{{0,1,2}}",
            bad2("vertex 2: 3-tuple expected, got number"),
        ),
        (
            "{{0,0,0},{1,0,0},{0,0/0,0}}",
            "{{0,1,2}}",
            bad2("vertex 3, entry 2: finite number expected, got NaN"),
        ),
        (
            "{{0,0,0},{1,0,0},{0,1,1e300}}",
            "{{0,1,2}}",
            bad2(
                "vertex 3, entry 3: number within single precision (|x| <= 3.4e38) expected, got 1e300",
            ),
        ),
    ];
    for (verts, faces, want) in cases {
        assert_eq!(inline_error(verts, faces), want, "{verts} {faces}");
    }
}

#[test]
fn inline_mesh_accepts_integral_floats_and_numeric_strings_as_lua_does() {
    let d = common::run_lua(&format!("m = gr.mesh('m', {TRI}, {{{{0.0, '1', 2}}}})")).unwrap();
    let meshes = caustic::scene::meshes::load_meshes(&d).unwrap();
    assert_eq!(meshes[0].triangles, [[0, 1, 2]]);
}
