//! The photon viewer (`caustic photons`): the stored photons drawn from the scene's camera.
//!
//! The scene is drawn dimly in grey (its surfaces lit head-on from the camera) so the photons
//! stand out. Every stored photon visible from the camera is drawn where it projects, in the
//! colour of its power (normalised by its map's mean power): global photons as single pixels,
//! caustic photons as small crosses, brighter, so the two maps are told apart.

use crate::camera::Camera;
use crate::film::{Film, Window};
use crate::geometry::Ray;
use crate::photon::{PhotonId, PhotonMap};
use crate::scene::Scene;
use glam::Vec3A;
use rayon::prelude::*;

/// Returns the picture of the `global` and `caustic` maps' photons over a dim view of `scene`.
pub fn photon_image(
    scene: &Scene,
    camera: &Camera,
    global: &PhotonMap,
    caustic: Option<&PhotonMap>,
    width: u32,
    height: u32,
) -> Film {
    let mut pixels: Vec<Vec3A> = (0..width * height)
        .into_par_iter()
        .map(|i| {
            let ray = camera.ray((i % width) as f32 + 0.5, (i / width) as f32 + 0.5);
            match scene.intersect(&ray) {
                Some(hit) => {
                    let s = scene.surface(&ray, &hit);
                    Vec3A::splat(0.12 * s.ng.dot(ray.dir).abs())
                }
                None => Vec3A::splat(0.02),
            }
        })
        .collect();
    let mut draw = |map: &PhotonMap, gain: f32, cross: bool| {
        let mean = (0..map.len())
            .map(|i| map.get(PhotonId(i as u32)).power.element_sum())
            .sum::<f32>()
            / (3.0 * map.len().max(1) as f32);
        let points: Vec<(u32, u32, Vec3A)> = (0..map.len() as u32)
            .into_par_iter()
            .filter_map(|i| {
                let ph = map.get(PhotonId(i));
                let (x, y) = camera.project(ph.position)?;
                if !(x >= 0.0 && y >= 0.0 && x < width as f32 && y < height as f32) {
                    return None;
                }
                // Visible from the eye: nothing between the camera and the photon.
                let to = ph.position - camera.eye;
                if scene.occluded(&Ray::new(camera.eye, to).with_tmax(1.0 - 1e-3)) {
                    return None;
                }
                let c = (ph.power / mean.max(f32::MIN_POSITIVE) * gain).min(Vec3A::ONE);
                Some((x as u32, y as u32, c))
            })
            .collect();
        for (x, y, c) in points {
            let offsets: &[(i32, i32)] = if cross {
                &[(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)]
            } else {
                &[(0, 0)]
            };
            for &(dx, dy) in offsets {
                let (px, py) = (x as i32 + dx, y as i32 + dy);
                if px >= 0 && py >= 0 && (px as u32) < width && (py as u32) < height {
                    let p = &mut pixels[(py as u32 * width + px as u32) as usize];
                    *p = p.max(c);
                }
            }
        }
    };
    draw(global, 0.5, false);
    if let Some(c) = caustic {
        draw(c, 1.0, true);
    }
    let film = Film {
        width,
        height,
        samples: vec![1; pixels.len()],
        pixels,
        window: Window::full(width, height),
    };
    crate::film::log::record(&film);
    film
}
