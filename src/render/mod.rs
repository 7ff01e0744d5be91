//! The render passes: trace eye rays for every pixel in parallel and shade them into a [`Film`].
//!
//! The first renderer is a Whitted-style ray tracer ([`shade`]): Phong direct lighting with shadow
//! rays, `ambient·kd`, mirror reflection weighted by `ks`, refraction weighted by the material's
//! transparency, and a background gradient where rays escape. One ray per pixel, through its
//! centre. Rows are shaded in parallel with rayon; the image does not depend on the thread count.

pub mod shade;

use crate::camera::Camera;
use crate::scene::Scene;
use glam::Vec3A;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// A linear-RGB image, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Row-major pixels, `width × height` of them.
    pub pixels: Vec<Vec3A>,
}

impl Film {
    /// Returns the pixel at column `x`, row `y` (0 = top).
    pub fn get(&self, x: u32, y: u32) -> Vec3A {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// Counters from one render, printed by `--stats`.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub primary_rays: u64,
    pub shadow_rays: u64,
    pub secondary_rays: u64,
    pub time: Duration,
}

/// Per-thread ray counts, summed into [`RenderStats`] once per row.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayCounts {
    pub primary: u64,
    pub shadow: u64,
    pub secondary: u64,
}

/// Renders `scene` through `camera` into a `width × height` film.
pub fn render(scene: &Scene, camera: &Camera, width: u32, height: u32) -> (Film, RenderStats) {
    let start = Instant::now();
    let totals = [AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0)];
    let mut pixels = vec![Vec3A::ZERO; width as usize * height as usize];
    pixels
        .par_chunks_mut(width as usize)
        .enumerate()
        .for_each(|(y, row)| {
            let mut counts = RayCounts::default();
            for (x, px) in row.iter_mut().enumerate() {
                let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
                counts.primary += 1;
                *px = shade::radiance(scene, camera, &ray, 0, &mut counts);
            }
            totals[0].fetch_add(counts.primary, Ordering::Relaxed);
            totals[1].fetch_add(counts.shadow, Ordering::Relaxed);
            totals[2].fetch_add(counts.secondary, Ordering::Relaxed);
        });
    let stats = RenderStats {
        primary_rays: totals[0].load(Ordering::Relaxed),
        shadow_rays: totals[1].load(Ordering::Relaxed),
        secondary_rays: totals[2].load(Ordering::Relaxed),
        time: start.elapsed(),
    };
    (
        Film {
            width,
            height,
            pixels,
        },
        stats,
    )
}
