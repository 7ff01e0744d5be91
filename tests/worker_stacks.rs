//! The worker threads get their deep stacks ([`caustic::accel::WORKER_STACK_BYTES`]) whatever
//! starts them first. A camera pass run before any scene is built (a library caller with its
//! own integrator, or a test, as `tests/light_transport/adaptive_pixels.rs` does) used to
//! start rayon's pool at the default 2 MiB, and every later deep eye path in the process (the
//! 1024-bounce mirrors of `deep_paths`) aborted on a stack overflow. This file is its own
//! process, so nothing else starts the workers before the camera pass here.

use caustic::camera::Camera;
use caustic::film::Window;
use caustic::geometry::ray::Ray;
use caustic::progress::NoProgress;
use caustic::render::{PassOptions, Radiance, Sampling, Share, camera_pass};
use caustic::sampling::Rng;
use caustic::stats::RayCounts;
use glam::Vec3A;

/// Recurses `n` times with 4 KiB of frame each: 2000 deep is 8 MiB, four times a default
/// thread's stack and half a worker's.
#[inline(never)]
fn deep(n: u32) -> u32 {
    let frame = std::hint::black_box([n as u8; 4096]);
    match n {
        0 => 1,
        _ => deep(n - 1) + u32::from(frame[n as usize % 4096] == 0),
    }
}

/// An integrator whose every sample recurses as a deep eye path does.
struct DeepPaths;

impl Radiance for DeepPaths {
    fn radiance(&self, _: &Ray, _: Share, _: &mut Rng, _: &mut RayCounts) -> Vec3A {
        Vec3A::splat(deep(2000) as f32)
    }
}

#[test]
fn a_camera_pass_before_any_scene_runs_on_deep_stacks() {
    let desc = caustic::desc::CameraDesc {
        eye: glam::Vec3::ZERO,
        view: glam::Vec3::NEG_Z,
        up: glam::Vec3::Y,
        fov_deg: 40.0,
    };
    let opts = PassOptions {
        seed: 1,
        sampling: Sampling::Stratified { spp: 1 },
        window: Window::full(8, 8),
        timing: false,
        heatmap: false,
        error_estimate: false,
    };
    let (film, _) = camera_pass(&Camera::new(&desc, 8, 8), &DeepPaths, &opts, &NoProgress);
    // deep(2000) counts one for its base and one for each frame whose byte is 0 (n = 256k).
    let expected = 1.0 + (1..=2000).filter(|n| n % 256 == 0).count() as f32;
    assert!(
        film.pixels.iter().all(|p| p.x == expected),
        "{:?}",
        film.pixels[0]
    );
}
