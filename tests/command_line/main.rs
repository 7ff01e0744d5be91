//! The command line and the scenes people run: `caustic render` on the course's A4 scenes
//! (`a4_scenes`), the whole CS488 corpus (`corpus_invariant`), `scenes/` (`scenes`), the gallery
//! (`gallery`) and the user guide's examples (`user_guide`); stopping a render with Ctrl-C
//! (`interrupt`); `caustic study` (`study`) and `caustic diff` (`diff`); traversal profiling
//! (`profiling`); adaptive pixels and the error map (`adaptive_pixels`).
//!
//! `interrupt` and `profiling` share this binary safely: they signal, and count traversals in,
//! the `caustic` processes they start, never this one (the in-process stops go through a
//! `Progress`, not the global interrupt flag).

#[path = "../common/mod.rs"]
mod common;

mod a4_scenes;
mod adaptive_pixels;
mod corpus_invariant;
mod diff;
mod gallery;
mod interrupt;
mod profiling;
mod scenes;
mod study;
mod user_guide;
