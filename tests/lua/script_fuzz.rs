//! Fuzzing scene scripts from the `gr` grammar (not byte mutation): random programs of `gr`
//! calls with hostile values, DAGs and cycles, loops that repeat calls, and sandbox escapes,
//! each run under the sandbox and its scene built for every `gr.render`. The property is "a
//! located error or a scene, never a panic"; `tools/fuzz.sh` runs the `fuzz_` properties for a
//! long campaign under a memory limit, which turns an allocation the budget missed into a
//! failure. CI runs 32 cases per property (`PROPTEST_CASES` raises it).

use crate::common::{out_dir, proptest_config};
use caustic::lua::{ScriptOptions, run_source_with};
use caustic::scene::build::build_scene;
use proptest::prelude::*;
use std::time::Duration;

/// A number a hostile or careless script might pass.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => (-20i32..20).prop_map(|i| format!("{}", i as f64 / 4.0)),
        1 => prop::sample::select(vec![
            "0", "-0.0", "1e-30", "-1e-30", "1e8", "1e9", "1e30", "3.4e38", "3.5e38", "1e300",
            "0/0", "math.huge", "-math.huge", "2^53", "2^63", "math.maxinteger",
            "math.mininteger", "'7'", "'x'", "nil", "{}", "true",
        ])
        .prop_map(str::to_string),
    ]
}

/// A 3-tuple, sometimes of the wrong arity or kind.
fn triple() -> impl Strategy<Value = String> {
    prop_oneof![
        8 => (number(), number(), number()).prop_map(|(a, b, c)| format!("{{{a}, {b}, {c}}}")),
        1 => (number(), number()).prop_map(|(a, b)| format!("{{{a}, {b}}}")),
        1 => number(),
    ]
}

/// A colour in [0, 1], sometimes hostile.
fn colour() -> impl Strategy<Value = String> {
    prop_oneof![
        6 => (0u8..=10, 0u8..=10, 0u8..=10)
            .prop_map(|(r, g, b)| format!("{{{}, {}, {}}}", r as f32 / 10.0, g as f32 / 10.0, b as f32 / 10.0)),
        1 => triple(),
    ]
}

/// A node reference: one of the names made so far (possibly not yet made, or nil).
fn node_ref() -> impl Strategy<Value = String> {
    prop_oneof![
        9 => (0usize..8).prop_map(|i| format!("n{i}")),
        1 => Just("nil".to_string()),
    ]
}

/// One statement of a scene script.
fn statement() -> impl Strategy<Value = String> {
    let make = prop_oneof![
        Just("gr.node('n')".to_string()),
        Just("gr.sphere('s')".to_string()),
        Just("gr.cube('c')".to_string()),
        Just("gr.cylinder('y')".to_string()),
        Just("gr.cone('k')".to_string()),
        (triple(), number()).prop_map(|(c, r)| format!("gr.nh_sphere('h', {c}, {r})")),
        (triple(), number()).prop_map(|(c, r)| format!("gr.nh_box('b', {c}, {r})")),
        (triple(), triple(), triple()).prop_map(|(a, b, c)| {
            format!("gr.mesh('m', {{{a}, {b}, {c}}}, {{{{1, 2, 3}}, {{0, 1, 2}}}})")
        }),
        (node_ref(), node_ref(), 0usize..3).prop_map(|(a, b, op)| {
            let op = ["union", "intersection", "difference"][op];
            format!("gr.{op}('g', {a}, {b})")
        }),
        (1u32..40, number()).prop_map(|(n, amp)| {
            format!("gr.water_mesh('w', {{n = {n}, size = 1, amplitude = {amp}}})")
        }),
    ];
    prop_oneof![
        4 => ((0usize..8), make).prop_map(|(i, m)| format!("n{i} = {m}")),
        3 => (node_ref(), node_ref()).prop_map(|(a, b)| format!("{a}:add_child({b})")),
        2 => (node_ref(), triple()).prop_map(|(a, t)| format!("{a}:translate(table.unpack({t}))")),
        2 => (node_ref(), triple()).prop_map(|(a, t)| format!("{a}:scale(table.unpack({t}))")),
        2 => (node_ref(), prop::sample::select(vec!["'x'", "'Y'", "'z'", "'w'", "1"]), number())
            .prop_map(|(a, ax, d)| format!("{a}:rotate({ax}, {d})")),
        3 => ((0usize..4), colour(), colour(), number(), number(), number()).prop_map(
            |(i, kd, ks, p, t, ior)| format!("m{i} = gr.material({kd}, {ks}, {p}, {t}, {ior})")
        ),
        2 => (node_ref(), 0usize..4).prop_map(|(a, i)| format!("{a}:set_material(m{i})")),
        2 => ((0usize..3), triple(), colour(), triple()).prop_map(|(i, p, c, f)| {
            format!("l{i} = gr.light({p}, {c}, {f})")
        }),
        1 => ((0usize..3), triple(), colour(), number()).prop_map(|(i, p, c, r)| {
            format!("l{i} = gr.sphere_light({p}, {c}, {{1, 0, 0}}, 1, {r})")
        }),
        1 => ((0usize..3), triple(), triple(), colour(), number(), number()).prop_map(
            |(i, p, d, c, inner, outer)| {
                format!("l{i} = gr.spot_light({p}, {d}, {c}, {inner}, {outer}, 1)")
            }
        ),
        1 => ((0usize..3), triple(), colour()).prop_map(|(i, d, c)| {
            format!("l{i} = gr.directional_light({d}, {c}, 1)")
        }),
        // Repetition: the DAGs and counts a five-line script can make.
        1 => (node_ref(), node_ref(), 1u32..200_000).prop_map(|(a, b, n)| {
            format!("for _ = 1, {n} do {a}:add_child({b}) end")
        }),
        1 => (1u32..40).prop_map(|d| {
            format!("local p = gr.node('d') n0 = p for _ = 1, {d} do local q = gr.node('d') \
                     q:add_child(p) q:add_child(p) p = q end n1 = p")
        }),
        1 => prop::sample::select(vec![
            "os.execute('true')", "io.open('x', 'w')", "require('../x')",
            "load(string.char(27) .. 'Lua')", "collectgarbage('stop')",
            "string.rep('x', 2^40)", "local t = {} for i = 1, 2^40 do t[i] = i end",
            "gr.nonexistent()", "setmetatable({}, {__gc = print})", "debug.sethook()",
            "n0 = gr.node(string.rep('n', 1e6))",
        ])
        .prop_map(str::to_string),
    ]
}

/// A whole script: statements, then a render of one of the nodes with the lights made.
fn script() -> impl Strategy<Value = String> {
    (
        prop::collection::vec(statement(), 1..24),
        node_ref(),
        1u32..24,
        1u32..24,
        triple(),
    )
        .prop_map(|(body, root, w, h, eye)| {
            let mut s = String::new();
            for line in body {
                // Each statement in its own pcall, so one bad call does not hide the rest.
                s.push_str(&format!("pcall(function() {line} end)\n"));
            }
            s.push_str(&format!(
                "gr.render({root}, 'out.png', {w}, {h}, {eye}, {{0, 0, -1}}, {{0, 1, 0}}, 50, \
                 {{0.1, 0.1, 0.1}}, {{l0, l1, l2}})\n"
            ));
            s
        })
}

/// Runs `src` in `dir` with a small memory limit and time budget, building the scene of every
/// `gr.render`; returns nothing: a panic fails the case.
fn run_and_build(src: &str, dir: &std::path::Path) {
    let options = ScriptOptions {
        memory_limit: Some(256 << 20),
        script_time: Some(Duration::from_secs(5)),
        ..ScriptOptions::default()
    };
    let hook = Box::new(
        |desc: &caustic::desc::SceneDesc, r: &caustic::desc::RenderDesc| {
            build_scene(desc, r).map(|_| ())
        },
    );
    let _ = run_source_with(src.as_bytes(), "fuzz.lua", dir, hook, options);
}

proptest! {
    #![proptest_config(proptest_config(32))]

    #[test]
    fn fuzz_generated_scene_scripts_fail_cleanly_or_build(src in script()) {
        let dir = out_dir("fuzz-scenes");
        run_and_build(&src, &dir);
    }
}

/// A glTF document's structure drawn at random over a small buffer: accessors with hostile
/// counts, offsets, strides and component types; meshes whose primitives share accessors;
/// nodes with children (cycles included), transforms and mesh references; scenes.
#[derive(Clone, Debug)]
struct GltfShape {
    floats: Vec<f32>,
    accessors: Vec<(usize, u32, u32, u32)>,
    primitives: Vec<Vec<(usize, Option<usize>, u8)>>,
    nodes: Vec<(Option<usize>, Vec<usize>, [f32; 3])>,
    glb: bool,
}

fn gltf_shape() -> impl Strategy<Value = GltfShape> {
    let float = prop_oneof![
        8 => (-100i32..100).prop_map(|i| i as f32 / 10.0),
        1 => prop::sample::select(vec![f32::NAN, f32::INFINITY, 3.4e38, -1e30, 1e-40, 0.0]),
    ];
    let count = prop_oneof![
        4 => 0u32..12,
        1 => prop::sample::select(vec![u32::MAX, 1 << 30, 1 << 20, 65_536]),
    ];
    (
        prop::collection::vec(float, 0..48),
        prop::collection::vec((0usize..4, count, 0u32..64, 0u32..4), 1..6),
        prop::collection::vec(
            prop::collection::vec((0usize..6, prop::option::of(0usize..6), 0u8..8), 0..6),
            1..4,
        ),
        prop::collection::vec(
            (
                prop::option::of(0usize..4),
                prop::collection::vec(0usize..8, 0..4),
                prop::array::uniform3(
                    prop_oneof![4 => Just(1.0f32), 1 => Just(1e20f32), 1 => Just(0.0f32)],
                ),
            ),
            1..8,
        ),
        any::<bool>(),
    )
        .prop_map(|(floats, accessors, primitives, nodes, glb)| GltfShape {
            floats,
            accessors,
            primitives,
            nodes,
            glb,
        })
}

impl GltfShape {
    /// Returns the file's bytes: the JSON over one buffer of the floats.
    fn bytes(&self) -> Vec<u8> {
        let bin: Vec<u8> = self.floats.iter().flat_map(|f| f.to_le_bytes()).collect();
        let components = [5126, 5125, 5123, 5121];
        let types = ["VEC3", "SCALAR", "VEC2", "VEC4"];
        let accessors: Vec<String> = self
            .accessors
            .iter()
            .map(|&(kind, count, offset, stride)| {
                format!(
                    r#"{{"bufferView":{},"byteOffset":{},"componentType":{},"count":{count},"type":"{}"}}"#,
                    stride as usize % 2,
                    offset * 4,
                    components[kind],
                    types[kind]
                )
            })
            .collect();
        let meshes: Vec<String> = self
            .primitives
            .iter()
            .map(|prims| {
                let p: Vec<String> = prims
                    .iter()
                    .map(|&(pos, idx, mode)| {
                        let idx = idx.map_or(String::new(), |i| format!(r#","indices":{i}"#));
                        format!(r#"{{"attributes":{{"POSITION":{pos}}}{idx},"mode":{mode}}}"#)
                    })
                    .collect();
                format!(r#"{{"primitives":[{}]}}"#, p.join(","))
            })
            .collect();
        let nodes: Vec<String> = self
            .nodes
            .iter()
            .map(|(mesh, children, scale)| {
                let mesh = mesh.map_or(String::new(), |m| format!(r#""mesh":{m},"#));
                format!(
                    r#"{{{mesh}"children":{children:?},"scale":[{},{},{}]}}"#,
                    scale[0], scale[1], scale[2]
                )
            })
            .collect();
        let len = bin.len();
        let views = format!(
            r#"[{{"buffer":0,"byteLength":{len}}},{{"buffer":0,"byteLength":{len},"byteStride":12}}]"#
        );
        let rest = format!(
            r#""scenes":[{{"nodes":[0]}}],"scene":0,"nodes":[{}],"meshes":[{}],"accessors":[{}],"bufferViews":{views}"#,
            nodes.join(","),
            meshes.join(","),
            accessors.join(",")
        );
        if self.glb {
            let json = format!(
                r#"{{"asset":{{"version":"2.0"}},{rest},"buffers":[{{"byteLength":{len}}}]}}"#
            );
            crate::common::glb(&json, &bin)
        } else {
            use base64::Engine;
            let data = base64::engine::general_purpose::STANDARD.encode(&bin);
            format!(
                r#"{{"asset":{{"version":"2.0"}},{rest},"buffers":[{{"uri":"data:application/octet-stream;base64,{data}","byteLength":{len}}}]}}"#
            )
            .into_bytes()
        }
    }
}

proptest! {
    #![proptest_config(proptest_config(32))]

    #[test]
    fn fuzz_gltf_structures_load_cleanly_or_fail_with_a_message(shape in gltf_shape()) {
        let dir = out_dir("fuzz-gltf");
        let name = if shape.glb { "m.glb" } else { "m.gltf" };
        std::fs::write(dir.join(name), shape.bytes()).unwrap();
        let src = format!(
            "m = gr.mesh('m', '{name}') m:set_material(gr.material({{1, 1, 1}}, {{0, 0, 0}}, 1))
             r = gr.node('r') r:add_child(m)
             gr.render(r, 'o.png', 8, 8, {{0, 0, 5}}, {{0, 0, -1}}, {{0, 1, 0}}, 50, {{0, 0, 0}}, {{}})"
        );
        run_and_build(&src, &dir);
    }
}
