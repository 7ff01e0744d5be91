//! Scenes: the step that turns a [`crate::desc::SceneDesc`] into the render-ready [`Scene`]
//! (flattening, loading mesh files and images, building the two-level BVH) and the per-ray
//! queries on it.

pub mod build;
pub mod images;
pub mod meshes;

pub use build::{Instance, Scene, Shape, build_scene};
