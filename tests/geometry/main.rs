//! Geometry: what rays hit and where. Parts: `csg` (CSG through the whole pipeline),
//! `surfaces` (points, normals and texture coordinates at known places), `traversal` (the BVH
//! against brute force, watertightness), `self_intersection` and `spawned_rays` (rays that
//! leave a surface never hit it again), `coincident_faces` (touching objects) and `precision`
//! (numbers beyond single precision).

#[path = "../common/mod.rs"]
mod common;

mod coincident_faces;
mod csg;
mod precision;
mod self_intersection;
mod spawned_rays;
mod surfaces;
mod traversal;
