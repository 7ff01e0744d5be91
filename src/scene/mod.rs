//! Scenes: the description a script fills in, the Lua API that fills it, and the step that turns
//! a description into the render-ready [`Scene`].

pub mod args;
pub mod build;
pub mod desc;
pub mod images;
pub mod lua;
pub mod meshes;

pub use build::{Instance, Scene, Shape, build_scene};
