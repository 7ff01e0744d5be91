//! Reading and writing files: meshes in, images out.

pub mod image;
pub mod obj;
