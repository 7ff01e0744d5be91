//! The house rules of `src/` (`docs/architecture.md`), checked on the source text: lower floors
//! never import higher ones, every module says what it owns, no function outside tests runs over
//! 100 lines without a reason in its doc, and no lint is allowed where a struct is missing.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The floors of the library, bottom first: a module may import those before it, never one
/// after it (within a folder, files import each other freely). The leaves come first, in an
/// order that keeps them acyclic too; `docs/architecture.md` draws the same picture.
const FLOORS: &[&str] = &[
    // Leaves: every floor may import them.
    "error",
    "range",
    "mem",
    "interrupt",
    "files",
    "film",
    "progress",
    "stats",
    "metrics",
    "sampling",
    "budget",
    // The plain description, what the script said.
    "desc",
    // Shapes, the BVH, and what a scene is made of.
    "geometry",
    "accel",
    "camera",
    "light",
    "material",
    // Files in and out, then the Lua front end that fills the description.
    "io",
    "lua",
    // Description -> scene, then the passes over it.
    "scene",
    "photon",
    "render",
    "integrator",
    // One frame as one call, then the study and the command line on top.
    "frame",
    "study",
    "cli",
];

/// Longest function body, in lines, outside tests without a reason.
const MAX_LINES: usize = 100;

/// The marker of a long function's reason: a doc line starting with it.
const REASON: &str = "/// Long:";

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Returns every `.rs` file under `dir`, sorted.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                todo.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Returns the lines of `text` before its unit-test module (`#[cfg(test)]` or
/// `#[cfg(all(test, …))]` at the start of a line), with `//` comments blanked out.
fn code_lines(text: &str) -> Vec<String> {
    text.lines()
        .take_while(|l| !l.starts_with("#[cfg(test)]") && !l.starts_with("#[cfg(all(test"))
        .map(|l| match l.trim_start().starts_with("//") {
            true => String::new(),
            false => l.to_string(),
        })
        .collect()
}

/// Returns the top-level module a file of `src/` belongs to (`integrator` for
/// `src/integrator/plan.rs`, `frame` for `src/frame.rs`).
fn top_module(rel: &Path) -> String {
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// Returns the top-level modules `crate::…` paths in `lines` name, with the first line of each.
fn imports(lines: &[String]) -> BTreeMap<String, usize> {
    let mut out = BTreeMap::new();
    for (i, l) in lines.iter().enumerate() {
        let mut rest = l.as_str();
        while let Some(at) = rest.find("crate::") {
            rest = &rest[at + "crate::".len()..];
            if rest.starts_with('{') {
                // `use crate::{a::b, c}`: each path in the group.
                let group = &rest[1..rest.find('}').unwrap_or(rest.len())];
                for name in group
                    .split(',')
                    .map(|p| p.trim().split("::").next().unwrap())
                {
                    out.entry(name.trim().to_string()).or_insert(i + 1);
                }
                continue;
            }
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            out.entry(name).or_insert(i + 1);
        }
    }
    out
}

/// No file imports a module on a floor above its own: the check a reader of the picture in
/// `docs/architecture.md` relies on (the photon-map file once imported the integrator that
/// imports it, and the scene imported the integrator's depth).
#[test]
fn no_floor_imports_a_higher_one() {
    let rank = |m: &str| FLOORS.iter().position(|f| *f == m);
    let mut wrong = Vec::new();
    for path in rust_files(&src()) {
        let rel = path.strip_prefix(src()).unwrap();
        let top = top_module(rel);
        if top == "lib" || top == "main" {
            continue;
        }
        let Some(own) = rank(&top) else {
            wrong.push(format!(
                "{}: module {top} is on no floor (FLOORS)",
                rel.display()
            ));
            continue;
        };
        let text = std::fs::read_to_string(&path).unwrap();
        for (name, line) in imports(&code_lines(&text)) {
            match rank(&name) {
                Some(r) if r > own => wrong.push(format!(
                    "{}:{line}: {top} imports {name}, a higher floor",
                    rel.display()
                )),
                _ => {}
            }
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// Every file of `src/` starts with a `//!` doc saying what it owns.
#[test]
fn every_module_says_what_it_owns() {
    let bare: Vec<String> = rust_files(&src())
        .into_iter()
        .filter(|p| {
            let text = std::fs::read_to_string(p).unwrap();
            !text.trim_start().starts_with("//!")
        })
        .map(|p| p.display().to_string())
        .collect();
    assert!(bare.is_empty(), "no module doc: {bare:?}");
}

/// Returns each function of `lines` longer than [`MAX_LINES`] whose doc has no [`REASON`]
/// line: `(line, name, length)`. A function is found by a line holding `fn name(` that ends
/// its signature with `{`, and ends at the first line after it with the same indentation that
/// is `}`.
fn long_functions(lines: &[String]) -> Vec<(usize, String, usize)> {
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim_start();
        let Some(at) = t.find("fn ") else { continue };
        let head = &t[..at];
        let is_fn = head.is_empty()
            || [
                "pub ",
                "pub(crate) ",
                "pub(super) ",
                "const ",
                "unsafe ",
                "extern \"C\" ",
            ]
            .iter()
            .any(|p| head.starts_with(p));
        if !is_fn || t.contains(';') && !t.contains('{') && t.ends_with(';') {
            continue;
        }
        let name: String = t[at + 3..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let indent = &l[..l.len() - t.len()];
        let close = format!("{indent}}}");
        let Some(end) = lines[i..].iter().position(|x| *x == close) else {
            continue;
        };
        if end < MAX_LINES {
            continue;
        }
        let doc = lines[..i]
            .iter()
            .rev()
            .take_while(|x| x.trim_start().starts_with("///") || x.trim_start().starts_with("#["));
        if !doc.into_iter().any(|x| x.trim_start().starts_with(REASON)) {
            out.push((i + 1, name, end + 1));
        }
    }
    out
}

/// No function outside tests is over 100 lines without a `/// Long:` line in its doc saying
/// why it reads best in one piece (STYLE.md: the Rust anchors' p90 is 24–44 lines).
#[test]
fn long_functions_say_why() {
    let mut wrong = Vec::new();
    for path in rust_files(&src()) {
        // The doc lines must survive: blank only `//` comments that are not docs.
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<String> = text
            .lines()
            .take_while(|l| !l.starts_with("#[cfg(test)]") && !l.starts_with("#[cfg(all(test"))
            .map(str::to_string)
            .collect();
        for (line, name, len) in long_functions(&lines) {
            wrong.push(format!(
                "{}:{line}: fn {name} is {len} lines",
                path.display()
            ));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The checker itself finds what it must: a 101-line function without a reason, and not one
/// with a reason or one of 100 lines.
#[test]
fn the_length_check_finds_a_long_function() {
    let body = |n: usize| (0..n - 2).map(|_| "    x();".to_string());
    let func = |doc: &str, n: usize| {
        let mut v = vec![doc.to_string(), "fn f() {".to_string()];
        v.extend(body(n));
        v.push("}".to_string());
        v
    };
    assert_eq!(
        long_functions(&func("/// Does it.", 101)),
        vec![(2, "f".to_string(), 101)]
    );
    assert!(long_functions(&func("/// Long: one match over every case.", 101)).is_empty());
    assert!(long_functions(&func("/// Does it.", 100)).is_empty());
}

/// Allowing clippy's lint against too many arguments is a missing struct (STYLE.md): nowhere in the
/// crate, its tests or its tools.
#[test]
fn no_lint_stands_for_a_missing_struct() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let lint = ["too_many", "_arguments"].concat();
    let mut found = Vec::new();
    for dir in ["src", "tests", "tools"] {
        for path in rust_files(&root.join(dir)) {
            let text = std::fs::read_to_string(&path).unwrap();
            if text.contains(&lint) {
                found.push(path.display().to_string());
            }
        }
    }
    assert!(found.is_empty(), "{lint} allowed in {found:?}");
}

/// The import check sees both forms of a path.
#[test]
fn the_import_check_reads_both_path_forms() {
    let lines = vec![
        "use crate::scene::Scene;".to_string(),
        "use crate::{frame, integrator::Plan};".to_string(),
        "    let x = crate::cli::run();".to_string(),
    ];
    let got: Vec<String> = imports(&lines).into_keys().collect();
    assert_eq!(got, ["cli", "frame", "integrator", "scene"]);
}
