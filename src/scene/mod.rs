//! Scenes: the step that turns a [`crate::desc::SceneDesc`] into the render-ready [`Scene`], and
//! the per-ray queries on it.
//!
//! - [`types`]: what the renderer traces ([`Scene`], [`Instance`], the primitive enum [`Shape`]);
//! - [`build`]: description → scene (flattening, instancing, CSG trees, the two-level BVH), reading
//!   files through [`meshes`] (mesh files) and [`images`] (textures and normal maps);
//! - [`query`]: closest hit, any hit and the surface at a hit;
//! - [`emitters`]: the lights that a mesh file's emissive surfaces make where it is placed;
//! - [`media`]: which media a point lies in (the camera's, a light's) and what they absorb;
//! - [`interaction`]: the per-hit set-up every path shares (surface + BSDF);
//! - [`mitsuba`]: a built scene written as a Mitsuba 3 scene (`caustic export-mitsuba`), for
//!   validation against its path tracer.

pub mod build;
pub mod emitters;
pub mod images;
pub mod interaction;
pub mod media;
pub mod meshes;
pub mod mitsuba;
pub mod query;
pub mod types;

pub use build::build_scene;
pub use types::{Features, Instance, MAX_DEPTH, Scene, Shape};
