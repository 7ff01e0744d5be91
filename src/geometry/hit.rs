//! Hit records: where a ray meets a surface ([`Hit`], from traversal) and the world-space surface
//! there ([`SurfaceHit`], computed on demand by `Scene::surface`). Plain data shared by the scene's
//! queries and the scattering model ([`crate::material::bsdf`]), which must not depend on the scene.

use glam::{Vec2, Vec3A};

/// A ray's closest intersection, enough to compute the surface on demand.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    /// Index into the scene's instances (`Scene::instances`).
    pub instance: u32,
    /// Triangle index (BVH order) for meshes; 0 otherwise.
    pub prim: u32,
    pub b1: f32,
    pub b2: f32,
    /// Object-space outward normal for analytic shapes and CSG; unused for meshes.
    pub normal: Vec3A,
    pub material: u32,
    pub face: u8,
}

/// The surface at a hit, in world space.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3A,
    /// Unit geometric normal as the shape orients it (outward for solids).
    pub ng: Vec3A,
    /// Unit shading normal (interpolated vertex normals on meshes), on the same side as `ng`.
    pub ns: Vec3A,
    /// Texture coordinates ([`crate::geometry::uv`] for analytic shapes, interpolated on meshes,
    /// or the barycentrics `(b1, b2)` for meshes without them).
    pub uv: Vec2,
    /// World-space `∂p/∂u`, the tangent that orients normal maps (not normalised; may be zero).
    pub dpdu: Vec3A,
    /// Index into the scene's materials (`Scene::materials`).
    pub material: u32,
}
