//! Developer tools for caustic: generators, benchmarks and accuracy studies.
//!
//! Each tool is a binary in `src/bin/`; code they share lives here. This package is a workspace
//! member apart from the renderer, so its dependencies never slow the renderer's build or tests:
//! run a tool with `cargo run --release -p caustic-tools --bin NAME -- ARGS`.

pub mod benchfile;
pub mod clock;
