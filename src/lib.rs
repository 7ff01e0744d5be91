//! caustic: a photon-mapping ray tracer for scenes written in the CS488 Lua modelling language.
//!
//! # Data flow
//! Each arrow is one function a test can call without Lua:
//!
//! ```text
//! Lua script ──lua::run_script──▶ SceneDesc (plain data, every entry tagged with file:line)
//!            ──scene::build::build_scene──▶ Scene (world-space instances, two-level BVH, materials, lights)
//!            ──render::render──▶ Film (linear RGB) ──io::image::write_png──▶ PNG on disk
//! ```
//!
//! `gr.render` calls the last three steps synchronously, as the course's renderer does, so a
//! script may render several images and keeps running after each.
//!
//! # Conventions
//! - World space is right-handed, y up by the scenes' convention (the camera's `up` decides).
//! - Directions point *away* from the surface: `wo` towards the viewer, `wi` towards the light.
//! - A ray's `t` is measured in units of its direction's length; rays transformed into object space
//!   keep their `t` (directions are not renormalised).
//! - Colours are linear RGB in `[0, ∞)`; the film clamps to `[0, 1]` and truncates to 8 bits as the
//!   course's `Image::savePng` does.
//! - Errors: everything that reads user input returns [`Error`], whose message names the script line
//!   or the file at fault. The hot path (traversal, shading) returns values or `Option`, never `Result`.
//!
//! # Glossary
//! - *description*: what the script said ([`desc`]); *scene*: what the renderer traces ([`scene::Scene`]).
//! - *instance*: one placement of a shape in the world, with its transform and material.
//! - *TLAS/BLAS*: the top-level BVH over instances and the per-mesh BVH over triangles ([`accel`]).

pub mod accel;
pub mod camera;
pub mod cli;
pub mod desc;
pub mod error;
pub mod film;
pub mod frame;
pub mod geometry;
pub mod integrator;
pub mod io;
pub mod light;
pub mod lua;
pub mod material;
pub mod mem;
pub mod photon;
pub mod progress;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod stats;

pub use error::{Error, Fault, Loc};
