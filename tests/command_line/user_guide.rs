//! The user guide (`docs/guide.md`), caustic's one manual, is true to the code: every Lua example
//! in it runs, builds its scenes and renders a tiny image of each; every flag of every command
//! is explained in it, and every flag it (or the README) names exists; its links lead somewhere.

use crate::common::{caustic, guide_dir, guide_examples, render_films_with};
use caustic::integrator::Settings;
use caustic::render::Sampling;
use std::collections::BTreeSet;
use std::path::Path;

/// Every Lua example of the guide (at least 5) runs from a folder holding the files it names
/// (`tri.obj`, `tiles.png`), and each of its `gr.render` calls renders (one ray per pixel, few
/// photons) an image with no NaN and some light.
#[test]
fn every_lua_example_in_the_guide_runs_and_renders() {
    let examples = guide_examples();
    assert!(examples.len() >= 5, "{} examples", examples.len());
    let dir = guide_dir("guide");
    let mut settings = Settings {
        sampling: Sampling::Stratified { spp: 1 },
        ..Settings::default()
    };
    settings.photons.photon_scale = 0.05;
    settings.photons.follow_image = false;
    for (i, src) in examples.iter().enumerate() {
        let name = format!("example{i}.lua");
        let films = render_films_with(src.as_bytes(), &name, &dir, &settings)
            .unwrap_or_else(|e| panic!("example {i} of the guide fails: {e}\n{src}"));
        for (r, _, film) in &films {
            assert!(
                film.pixels.iter().all(|p| p.is_finite()),
                "example {i}: NaN in {}",
                r.output.display()
            );
            assert!(
                film.pixels.iter().any(|p| p.max_element() > 0.0),
                "example {i}: {} is black",
                r.output.display()
            );
        }
    }
}

/// Reads a file of the repository.
fn read(rel: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(rel);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The help text of a command line (`caustic ARGS... --help`).
fn help(args: &[&str]) -> String {
    let out = caustic().args(args).arg("--help").output().unwrap();
    assert!(out.status.success(), "caustic {args:?} --help failed");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The commands `caustic --help` lists (all but `help`).
fn commands() -> Vec<String> {
    let top = help(&[]);
    let list = top
        .split("Commands:")
        .nth(1)
        .expect("caustic --help lists its commands");
    let commands: Vec<String> = list
        .lines()
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(String::from)
        .collect();
    assert!(commands.len() >= 7, "commands: {commands:?}");
    commands
}

/// Every flag a command's help lists, each as its forms, long first (`["--output", "-o"]`,
/// `["-D"]`). A help line that starts with `-` names a flag; its description follows it on the
/// same line or on the next.
fn help_flags(help: &str) -> Vec<Vec<String>> {
    let mut flags = Vec::new();
    for line in help.lines().map(str::trim_start) {
        if !line.starts_with('-') {
            continue;
        }
        let head = line.split("  ").next().unwrap();
        let mut forms: Vec<String> = head
            .split([' ', ','])
            .filter(|w| w.starts_with('-') && w.len() > 1)
            .map(String::from)
            .collect();
        forms.sort_by_key(|f| !f.starts_with("--"));
        flags.push(forms);
    }
    flags
}

/// Every flag (`--name`, or the one-letter `-D`, `-o`, `-q`) a document names, on the lines
/// that run caustic or talk about it: a line naming cargo or Slurm's sbatch gives their flags.
fn named_flags(doc: &str) -> BTreeSet<String> {
    let mut flags = BTreeSet::new();
    for line in doc.lines() {
        let lower = line.to_lowercase();
        if lower.contains("cargo ") || lower.contains("sbatch") {
            continue;
        }
        for (i, _) in line.match_indices('-') {
            let before = line[..i].chars().next_back();
            if before.is_some_and(|c| c.is_alphanumeric() || c == '-' || c == '_') {
                continue;
            }
            let rest = &line[i + 1..];
            let flag = if let Some(long) = rest.strip_prefix('-') {
                let name: String = long
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                    .collect();
                if name.len() < 2 || !name.starts_with(|c: char| c.is_ascii_lowercase()) {
                    continue;
                }
                format!("--{name}")
            } else {
                let mut chars = rest.chars();
                match (chars.next(), chars.next()) {
                    (Some(c), next)
                        if "Doq".contains(c) && next.is_none_or(|n| !n.is_alphanumeric()) =>
                    {
                        format!("-{c}")
                    }
                    _ => continue,
                }
            };
            flags.insert(flag);
        }
    }
    flags
}

/// Every flag the guide or the README names is one some command takes (no flag documented that
/// does not exist, none misspelt).
#[test]
fn every_flag_in_the_guide_and_the_readme_exists() {
    let mut known: BTreeSet<String> = help_flags(&help(&[])).into_iter().flatten().collect();
    for cmd in commands() {
        known.extend(help_flags(&help(&[cmd.as_str()])).into_iter().flatten());
    }
    for doc in ["docs/guide.md", "README.md"] {
        let unknown: Vec<String> = named_flags(&read(doc))
            .into_iter()
            .filter(|f| !known.contains(f))
            .collect();
        assert!(
            unknown.is_empty(),
            "flags in {doc} that no command takes: {unknown:?}"
        );
    }
}

/// The guide is the whole reference: it names every command (`caustic render`, ...) and every
/// flag each command's help lists, so a new flag cannot ship undocumented.
#[test]
fn every_command_and_flag_is_in_the_guide() {
    let guide = read("docs/guide.md");
    let named = named_flags(&guide);
    let mut undocumented = Vec::new();
    for cmd in commands() {
        if !guide.contains(&format!("caustic {cmd}")) {
            undocumented.push(format!("caustic {cmd}"));
        }
        for forms in help_flags(&help(&[cmd.as_str()])) {
            // The long form where there is one (`--output`, which the guide gives beside `-o`).
            let flag = &forms[0];
            if flag != "--help" && !named.contains(flag) {
                undocumented.push(format!("caustic {cmd} {flag}"));
            }
        }
    }
    assert!(
        undocumented.is_empty(),
        "commands and flags docs/guide.md does not explain: {undocumented:?}"
    );
}

/// GitHub's anchor of a heading: lower case, punctuation dropped, spaces as hyphens.
fn anchor(heading: &str) -> String {
    heading
        .trim_start_matches('#')
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of a Markdown file's headings (outside code blocks).
fn anchors(doc: &str) -> BTreeSet<String> {
    prose(doc)
        .filter(|l| l.starts_with('#'))
        .map(anchor)
        .collect()
}

/// The lines of a Markdown file outside fenced code blocks.
fn prose(doc: &str) -> impl Iterator<Item = &str> {
    let mut fenced = false;
    doc.lines().filter(move |l| {
        if l.trim_start().starts_with("```") {
            fenced = !fenced;
            return false;
        }
        !fenced
    })
}

/// Every relative link of the README and the guide (the guide's table of contents, the
/// README's table of what caustic does) leads to a file that exists and, with `#anchor`, to
/// one of its headings.
#[test]
fn every_link_of_the_readme_and_the_guide_leads_somewhere() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut broken = Vec::new();
    for doc in ["README.md", "docs/guide.md"] {
        let text = read(doc);
        let dir = root.join(doc).parent().unwrap().to_path_buf();
        for line in prose(&text) {
            for (i, _) in line.match_indices("](") {
                let target: String = line[i + 2..].chars().take_while(|c| *c != ')').collect();
                if target.contains("://") || target.starts_with('<') {
                    continue;
                }
                let (file, frag) = target.split_once('#').unwrap_or((target.as_str(), ""));
                let path = if file.is_empty() {
                    root.join(doc)
                } else {
                    dir.join(file)
                };
                if !path.exists() {
                    broken.push(format!("{doc}: {target} (no such file)"));
                } else if !frag.is_empty() {
                    let linked = std::fs::read_to_string(&path).unwrap_or_default();
                    if !anchors(&linked).contains(frag) {
                        broken.push(format!("{doc}: {target} (no such heading)"));
                    }
                }
            }
        }
    }
    assert!(broken.is_empty(), "broken links: {broken:#?}");
}
