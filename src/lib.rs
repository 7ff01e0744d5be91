//! caustic: a photon-mapping ray tracer for scenes written in the CS488 Lua modelling language.
//!
//! # Data flow
//! Each arrow is one function a test can call without Lua (the picture, and where to add a
//! primitive, a lobe, a light, a flag or an integrator, are in `docs/architecture.md`):
//!
//! ```text
//! Lua script ──lua::run_script──▶ SceneDesc (desc: plain data, every entry tagged with file:line)
//!   ──scene::build_scene──▶ Scene (meshes and textures read, world-space instances, two-level BVH)
//!   ──frame::plan──▶ integrator::plan (which integrator, which effects, why; made once a frame)
//!   ──frame::render──▶ the integrator's phases (photon_map: the prepass — trace photons, build
//!                        maps, precompute irradiance, cache irradiance — then the camera pass,
//!                        render::camera_pass; progressive: the same per pass with shrinking
//!                        radii, averaged; a prepass can be saved and read back,
//!                        integrator::maps_file)
//!                    ──▶ Film + Stats ──io::image::write_image──▶ PNG, EXR, PFM or HDR on disk
//! ```
//!
//! `gr.render` calls the last steps synchronously, as the course's renderer does, so a script
//! may render several images and keeps running after each. The command line ([`cli`]), every
//! test helper and every tool render through [`frame`]; nothing else wires passes together.
//! Eye rays, final-gather rays and photons scatter through one model ([`material::bsdf`]),
//! set up once per hit ([`scene::interaction`]).
//!
//! # Conventions
//! - World space is right-handed, y up by the scenes' convention (the camera's `up` decides).
//! - Directions point *away* from the surface: `wo` towards the viewer, `wi` towards the light.
//! - A ray's `t` is measured in units of its direction's length; rays transformed into object space
//!   keep their `t` (directions are not renormalised).
//! - Colours are linear RGB in `[0, ∞)`, kept as `f32` by the film; an 8-bit image (PNG) clamps
//!   them to `[0, 1]` and truncates as the course's `Image::savePng` does (`--tonemap clamp`, the
//!   default) or applies the sRGB curve after an exposure (`--tonemap srgb`); EXR, PFM and HDR
//!   keep the floats.
//! - Errors: everything that reads user input returns [`Error`], whose message names the script line
//!   or the file at fault. The hot path (traversal, shading) returns values or `Option`, never `Result`.
//!
//! # Glossary
//! - *description*: what the script said ([`desc`]); *scene*: what the renderer traces ([`scene::Scene`]).
//! - *instance*: one placement of a shape in the world, with its transform and material.
//! - *TLAS/BLAS*: the top-level BVH over instances and the per-mesh BVH over triangles ([`accel`]).
//! - *integrator*: how a frame computes light transport ([`integrator::Integrator`]); *plan*: the
//!   decision which one, and which effects, a scene needs ([`mod@integrator::plan`]).
//! - *BSDF*: what a surface does at one hit ([`material::bsdf::Bsdf`]).

pub mod accel;
pub mod budget;
pub mod camera;
pub mod cli;
pub mod desc;
pub mod error;
pub mod files;
pub mod film;
pub mod frame;
pub mod geometry;
pub mod integrator;
pub mod interrupt;
pub mod io;
pub mod light;
pub mod lua;
pub mod material;
pub mod mem;
pub mod metrics;
pub mod photon;
pub mod progress;
pub mod range;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod stats;
pub mod study;

pub use error::{Error, Fault, Loc};
