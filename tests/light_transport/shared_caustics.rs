//! A pixel's samples share caustic estimates where their points lie within a quarter of the
//! estimate's radius (`src/integrator/photon_map.rs` says why): against the closed form of the
//! mirror caustic, the shared estimates leave the image as accurate as separate ones.

use crate::progressive::{SIDE, mirror_scene, mirror_with_reference, mse_and_mean};
use caustic::film::Window;
use caustic::integrator::{GiMode, Settings};
use caustic::progress::NoProgress;
use caustic::render::Sampling;

/// The photon mapper's settings for the mirror scene: 4 stratified samples a pixel, 10,000
/// caustic photons (a radius of about 0.18; a pixel is 0.042 wide), no global map.
fn mirror_settings(seed: u64, share_caustics: bool) -> Settings {
    let mut s = crate::progressive::mirror_settings(seed, Default::default());
    s.progressive = None;
    s.gi = GiMode::On;
    s.sampling = Sampling::Stratified { spp: 4 };
    s.photons.caustic_photons = 10_000;
    s.photons.share_caustics = share_caustics;
    s
}

/// On the mirror scene (a caustic 4.4 wide under a point light's image, closed form), the
/// photon mapper at 4 stratified samples a pixel and 10,000 caustic photons (a radius of about
/// 0.18, a pixel 0.042 wide: most samples share), over 8 seeds: sharing takes at least half
/// the caustic estimates from another sample, its relative RMSE against the closed form is at
/// most 1.05 times that of separate estimates, and its mean is within 0.5% of theirs and within
/// 1% of the closed form's. Sharing across pixels, or estimates from the wrong surface, would
/// move the mean or the error; sharing at a whole radius would blur the caustic's falloff.
#[test]
fn shared_caustic_estimates_leave_the_image_as_accurate() {
    let (mut scene, camera, reference, ref_mean) = mirror_with_reference();
    let seeds = 8;
    // [separate, shared]: mean squared error and mean over seeds; estimates reused.
    let (mut mse, mut mean, mut reused) = ([0.0f64; 2], [0.0f64; 2], [0u64; 2]);
    for (i, share) in [false, true].into_iter().enumerate() {
        for seed in 0..seeds {
            let settings = mirror_settings(seed, share);
            let window = Window::full(SIDE, SIDE);
            let (film, stats) =
                crate::common::render_frame(&mut scene, &camera, window, &settings, &NoProgress);
            let (e, m) = mse_and_mean(&film, &reference);
            mse[i] += e / seeds as f64;
            mean[i] += m / seeds as f64;
            reused[i] += stats.render.reused;
        }
    }
    let rel = mse.map(|e| e.sqrt() / ref_mean);
    let reads = seeds * u64::from(SIDE * SIDE) * 4;
    println!(
        "separate: relative RMSE {:.4}, mean {:.4}; shared: {:.4}, mean {:.4}, {} of {reads} estimates reused",
        rel[0],
        mean[0] / ref_mean,
        rel[1],
        mean[1] / ref_mean,
        reused[1]
    );
    assert_eq!(reused[0], 0);
    assert!(reused[1] * 2 >= reads, "{} of {reads} reused", reused[1]);
    assert!(
        rel[1] <= 1.05 * rel[0],
        "shared {:.4}, separate {:.4}",
        rel[1],
        rel[0]
    );
    assert!((mean[1] / mean[0] - 1.0).abs() < 0.005);
    assert!((mean[1] / ref_mean - 1.0).abs() < 0.01);
}

/// Nothing is shared between pixels: on the mirror scene, where a quarter radius is wider than
/// a pixel, a window rendered alone equals the same window of the full frame, and one thread
/// gives the image two do.
#[test]
fn shared_caustic_estimates_stay_within_their_pixel() {
    let (mut scene, camera) = mirror_scene();
    let settings = mirror_settings(3, true);
    let mut render = |threads: usize, window: Window| {
        crate::common::render_on_threads(threads, &mut scene, &camera, window, &settings)
    };
    let full = Window::full(SIDE, SIDE);
    let (one, stats) = render(1, full);
    assert!(stats.render.reused > 0);
    assert!(
        one.pixels == render(2, full).0.pixels,
        "1 and 2 threads differ"
    );
    let tile = Window {
        x0: 5,
        y0: 7,
        x1: 19,
        y1: 15,
        ..full
    };
    crate::common::assert_window_of(&render(2, tile).0, &one, tile);
}
