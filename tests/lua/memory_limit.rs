//! A script that exhausts memory: the Lua state's limit turns it into a Lua error at the script
//! line, instead of the process growing until the system aborts it.

use caustic::lua::{ScriptOptions, run_source_with};
use std::path::Path;

/// Runs `src` as `test.lua` with a Lua state of at most 64 MiB; returns its error message.
fn error_with_small_limit(src: &str) -> String {
    let options = ScriptOptions {
        memory_limit: Some(64 << 20),
        ..ScriptOptions::default()
    };
    let no_render = Box::new(|_: &_, _: &_| Ok(()));
    match run_source_with(
        src.as_bytes(),
        "test.lua",
        Path::new("."),
        no_render,
        options,
    ) {
        Ok(_) => panic!("the script was expected to run out of memory:\n{src}"),
        Err(e) => e.to_string(),
    }
}

/// An ever-growing table of small tables, and one of 1 KB strings, each fail with a memory
/// error naming the line that ran out and the limit; a string that doubles until it fails (one
/// sudden huge allocation, within the first thousand instructions, before any line sample) names
/// the script. The next script then runs normally. Three scripts, 64 MiB each.
#[test]
fn exhausting_memory_is_a_located_lua_error() {
    let cases = [
        (
            "t = {}\nlocal i = 0\nwhile true do i = i + 1; t[i] = {i} end\n",
            "test.lua:3:",
        ),
        (
            "t = {}\nwhile true do t[#t + 1] = string.rep('x', 1000) .. #t end\n",
            "test.lua:2:",
        ),
        ("s = 'x'\nwhile true do s = s .. s end\n", "test.lua:"),
    ];
    for (src, at) in cases {
        let err = error_with_small_limit(src);
        assert!(
            err.starts_with(at)
                && err.contains("not enough memory")
                && err.contains(&format!("limit of {} bytes", 64 << 20)),
            "expected a memory error at {at}, got: {err}"
        );
    }
    let desc = caustic::lua::run_source(
        b"s = gr.sphere('s')",
        "next.lua",
        Path::new("."),
        Box::new(|_, _| Ok(())),
    )
    .unwrap();
    assert_eq!(desc.nodes.len(), 1);
}
