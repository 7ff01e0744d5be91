//! The render passes: trace eye rays for every pixel in parallel and shade them into a [`Film`].
//!
//! The first renderer is a Whitted-style ray tracer ([`shade`]): Phong direct lighting with shadow
//! rays, `ambient·kd`, mirror reflection weighted by `ks`, refraction weighted by the material's
//! transparency, and a background gradient where rays escape.
//!
//! # Pixel sampling ([`aa`])
//! - `spp = 1` (the default): one ray through the pixel centre, as the course renders.
//! - `spp = N`: N jittered samples stratified in x and y, box-filtered.
//! - adaptive (the original project's scheme): rays through the pixel corners; where they differ by
//!   more than a threshold, the pixel is split into four and refined recursively.
//!
//! # Determinism and tiles
//! Rows are shaded in parallel with rayon. Every random number a pixel uses comes from the stream
//! keyed by `(seed, Pass::Pixel, pixel index in the full image)` ([`crate::sampling`]), and
//! adaptive corner rays are deterministic, so the image is bit-identical for any thread count and
//! a cropped window equals the same window of the full render.

pub mod aa;
pub mod film_log;
pub mod gi;
pub mod photon_view;
pub mod plan;
pub mod shade;

use crate::camera::Camera;
use crate::scene::Scene;
use glam::Vec3A;
use rayon::prelude::*;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// A linear-RGB image, row 0 at the top: the whole image or a window (crop) of it.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: u32,
    pub height: u32,
    /// Row-major pixels, `width × height` of them.
    pub pixels: Vec<Vec3A>,
    /// Camera rays traced for each pixel (same layout as `pixels`).
    pub samples: Vec<u32>,
    /// Where this window sits in the full image, and the full image's size.
    pub window: Window,
}

impl Film {
    /// Returns the pixel at column `x`, row `y` of this film (0 = top).
    pub fn get(&self, x: u32, y: u32) -> Vec3A {
        self.pixels[(y * self.width + x) as usize]
    }
}

/// A rectangle `[x0, x1) × [y0, y1)` of an image `full_width × full_height` pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Window {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
    pub full_width: u32,
    pub full_height: u32,
}

impl Window {
    /// Returns the window covering a whole `width × height` image.
    pub fn full(width: u32, height: u32) -> Window {
        Window {
            x0: 0,
            y0: 0,
            x1: width,
            y1: height,
            full_width: width,
            full_height: height,
        }
    }

    /// Returns the window's width and height.
    pub fn size(&self) -> (u32, u32) {
        (self.x1 - self.x0, self.y1 - self.y0)
    }

    /// Returns true when the window is non-empty and inside the full image.
    pub fn is_valid(&self) -> bool {
        self.x0 < self.x1
            && self.y0 < self.y1
            && self.x1 <= self.full_width
            && self.y1 <= self.full_height
    }
}

/// How pixels are sampled.
#[derive(Clone, Debug, PartialEq)]
pub enum Sampling {
    /// `n` stratified jittered samples per pixel (1 = the pixel centre).
    Stratified { spp: u32 },
    /// Corner rays, refined where neighbours differ by more than `threshold` (any channel),
    /// splitting at most `max_depth` times.
    Adaptive { threshold: f32, max_depth: u32 },
}

/// Everything that shapes a render besides the scene and camera.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderOptions {
    pub seed: u64,
    pub sampling: Sampling,
    /// The part of the image to render.
    pub window: Window,
    /// Time material evaluation for `--stats`.
    pub timing: bool,
    /// Shadow-ray samples per area or sphere light at each shaded point.
    pub light_samples: u32,
}

impl RenderOptions {
    /// Returns the course's defaults: one centre ray per pixel over the whole image.
    pub fn new(width: u32, height: u32) -> RenderOptions {
        RenderOptions {
            seed: 0,
            sampling: Sampling::Stratified { spp: 1 },
            window: Window::full(width, height),
            timing: false,
            light_samples: 16,
        }
    }
}

/// Counters from one render, printed by `--stats`.
#[derive(Clone, Debug, Default)]
pub struct RenderStats {
    pub primary_rays: u64,
    pub shadow_rays: u64,
    pub secondary_rays: u64,
    pub time: Duration,
    /// Thread time spent in texture, bump-map and Perlin-noise evaluation (with `timing`).
    pub material_time: Duration,
    /// Photon-map estimates made while rendering, and the photons they found.
    pub lookups: u64,
    pub photons_used: u64,
}

/// Per-thread ray counts, summed into [`RenderStats`] once per row.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayCounts {
    pub primary: u64,
    pub shadow: u64,
    pub secondary: u64,
    /// Whether to time material evaluation (textures, bump maps, noise): `--stats` only, since
    /// reading the clock twice per hit costs time of its own.
    pub timing: bool,
    /// Nanoseconds spent evaluating materials, when `timing`.
    pub material_nanos: u64,
    /// Photon-map lookups and the photons they found.
    pub lookups: u64,
    pub photons_used: u64,
}

impl RayCounts {
    /// Adds `o`'s counts to these.
    pub fn add(&mut self, o: &RayCounts) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.secondary += o.secondary;
        self.material_nanos += o.material_nanos;
        self.lookups += o.lookups;
        self.photons_used += o.photons_used;
    }
}

/// Renders `scene` through `camera` into a `width × height` film with one centre ray per pixel.
pub fn render(scene: &Scene, camera: &Camera, width: u32, height: u32) -> (Film, RenderStats) {
    render_with(
        scene,
        camera,
        None,
        &RenderOptions::new(width, height),
        &|| {},
    )
}

/// Renders the window `opts.window` of the image; `row_done` is called once per finished row.
pub fn render_with(
    scene: &Scene,
    camera: &Camera,
    gi: Option<&gi::Gi>,
    opts: &RenderOptions,
    row_done: &(dyn Fn() + Sync),
) -> (Film, RenderStats) {
    let start = Instant::now();
    let win = opts.window;
    let (w, h) = win.size();
    // Rows add their counts once each (a lock per row costs nothing next to a row of pixels).
    let totals = Mutex::new(RayCounts::default());
    let mut pixels = vec![Vec3A::ZERO; w as usize * h as usize];
    let mut samples = vec![0u32; w as usize * h as usize];
    let tracer = shade::Tracer {
        scene,
        camera,
        light_samples: opts.light_samples,
        gi,
    };
    let sampler = aa::PixelSampler::new(&tracer, opts);
    pixels
        .par_chunks_mut(w as usize)
        .zip(samples.par_chunks_mut(w as usize))
        .enumerate()
        .for_each(|(row, (px_row, count_row))| {
            let y = win.y0 + row as u32;
            let mut counts = RayCounts {
                timing: opts.timing,
                ..RayCounts::default()
            };
            for (i, (px, n)) in px_row.iter_mut().zip(count_row.iter_mut()).enumerate() {
                let before = counts.primary;
                *px = sampler.pixel(win.x0 + i as u32, y, &mut counts);
                *n = (counts.primary - before) as u32
                    + sampler.corner_rays_charged(i as u32, row as u32);
            }
            totals
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .add(&counts);
            row_done();
        });
    let mut t = totals.into_inner().unwrap_or_else(|e| e.into_inner());
    t.add(&sampler.corner_counts());
    let stats = RenderStats {
        primary_rays: t.primary,
        shadow_rays: t.shadow,
        secondary_rays: t.secondary,
        material_time: Duration::from_nanos(t.material_nanos),
        lookups: t.lookups,
        photons_used: t.photons_used,
        time: start.elapsed(),
    };
    let film = Film {
        width: w,
        height: h,
        pixels,
        samples,
        window: win,
    };
    film_log::record(&film);
    (film, stats)
}
