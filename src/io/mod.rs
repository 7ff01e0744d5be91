//! Reading and writing files: meshes in, images out.

pub mod exr;
pub mod gltf;
pub mod heatmap;
pub mod image;
pub mod mitsuba;
pub mod obj;
pub mod pfm;
pub mod stitch;
