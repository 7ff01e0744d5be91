//! Mesh lights: the emissive surfaces a mesh file carries ([`MeshData::emitters`]) become
//! lights where the mesh is placed, one [`Light::mesh`] per emissive primitive per placement.
//!
//! An emissive surface is both a surface and a light over the same triangles, as glTF and
//! Mitsuba have it: the surface reflects by its material and hides what is behind it (a black
//! panel under a ceiling absorbs the light that reaches it from the room), and the light is
//! seen by camera rays on its front ([`Light::seen_by`], winning over the surface it lies on:
//! [`crate::integrator::eye::EMITTER_ON_SURFACE`]), sampled by shadow rays and left by photons.
//! Before, the surface was a light only: the ceiling behind a Blender panel reflected the
//! room's light that the panel should have absorbed, 2–3% too much light in the glTF
//! validation scenes. What caustic reads of a glTF emissive material is in [`crate::io::gltf`].
//!
//! ```lua
//! lamp = gr.mesh('lamp', 'panel.glb')   -- a quad with emissiveFactor and emissiveStrength
//! lamp:translate(0, 2, 0)               -- placed, it lights the scene where it stands
//! ```

use crate::desc::NodeDesc;
use crate::error::{Error, Result};
use crate::geometry::mesh::MeshData;
use crate::light::{EmitterTriangle, Light};
use glam::{DAffine3, Vec3A};

/// Most emissive triangles one scene places, over all its mesh lights: a camera ray is tested
/// against each triangle of each light whose bounds it crosses.
pub const MAX_PLACED_EMITTER_TRIANGLES: usize = crate::io::gltf::MAX_EMITTER_TRIANGLES;

/// Returns the lights the emitters of `data` make when placed by `world_from_mesh` at `node`,
/// adding their triangles to `placed`; errors name the node when the scene's emitters exceed
/// [`MAX_PLACED_EMITTER_TRIANGLES`] or a placed light is brighter than a light may be.
pub fn place(
    data: &MeshData,
    world_from_mesh: &DAffine3,
    node: &NodeDesc,
    placed: &mut usize,
) -> Result<Vec<Light>> {
    let mut lights = Vec::new();
    let flips = world_from_mesh.matrix3.determinant() < 0.0;
    for emitter in &data.emitters {
        *placed += emitter.triangles.len();
        if *placed > MAX_PLACED_EMITTER_TRIANGLES {
            return Err(Error::at(
                &node.loc,
                format!(
                    "node '{}': the scene's emissive surfaces have more than \
                     {MAX_PLACED_EMITTER_TRIANGLES} triangles in all (at '{}' of {})",
                    node.name,
                    emitter.name,
                    data.source.display()
                ),
            ));
        }
        let world =
            |p: glam::Vec3| Vec3A::from(world_from_mesh.transform_point3(p.as_dvec3()).as_vec3());
        let triangles = emitter
            .triangles
            .iter()
            .map(|&[a, b, c]| {
                // A mirroring placement turns the winding: the front stays the emitting side.
                let (a, b, c) = (world(a), world(b), world(c));
                if flips {
                    EmitterTriangle::new(a, c, b)
                } else {
                    EmitterTriangle::new(a, b, c)
                }
            })
            .collect();
        let Some(light) = Light::mesh(triangles, emitter.radiance.into()) else {
            continue;
        };
        crate::range::within(
            &light.colour.to_array(),
            &format!(
                "node '{}': emissive surface '{}' placed has intensity (radiance × area / π)",
                node.name, emitter.name
            ),
            crate::range::MAX_INTENSITY,
        )
        .map_err(|e| Error::at(&node.loc, e))?;
        lights.push(light);
    }
    Ok(lights)
}
