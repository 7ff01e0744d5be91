//! Light does not leak through closed walls: a point light sealed in a hollow box lights
//! nothing outside it, whatever the photon maps' search radius (issue 35: final gathering read
//! precomputed irradiance from the box's inside on its outside faces and the floor round it).

use crate::common;

use caustic::camera::Camera;
use caustic::film::Window;
use caustic::integrator::Integrator;
use caustic::progress::NoProgress;
use caustic::scene::build::build_scene;

/// A closed 2 × 2 × 2 box made of six walls 0.1 thick, standing at the origin on a 20 × 20 floor
/// slab (top face y = 0), with a point light emitting 200k photons at its centre `{0, 1, 0}`;
/// the camera looks at the box and the floor round it from outside. The walls are a third of a
/// percent of the scene's diagonal thick, and the global map's search radius (5% of it, 1.4)
/// spans them many times over.
const SEALED_BOX: &str = "
white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
root = gr.node('root')
function slab(name, sx, sy, sz, tx, ty, tz)
  local c = gr.cube(name)
  c:set_material(white); c:scale(sx, sy, sz); c:translate(tx, ty, tz)
  root:add_child(c)
end
slab('floor',  20,  0.1, 20,  -10,  -0.1, -10)
slab('bottom',  2,  0.1,  2,   -1,   0,    -1)
slab('top',     2,  0.1,  2,   -1,   1.9,  -1)
slab('left',    0.1, 1.8, 2,   -1,   0.1,  -1)
slab('right',   0.1, 1.8, 2,    0.9, 0.1,  -1)
slab('back',    1.8, 1.8, 0.1, -0.9, 0.1,  -1)
slab('front',   1.8, 1.8, 0.1, -0.9, 0.1,   0.9)
lamp = gr.light({0, 1, 0}, {1, 1, 1}, {0, 0, 1}, nil, 200000)
gr.render(root, 'sealed.png', 64, 64, {3, 4, 6}, {-3, -3.5, -6}, {0, 1, 0}, 40,
          {0, 0, 0}, {lamp})
";

/// The sealed box rendered with the default photon mapper (final gathering, precomputed
/// irradiance, the irradiance cache), one centre ray a pixel: every pixel whose ray meets a
/// surface sees the box's outside or the floor, which no light reaches, so it is exactly 0.
/// Before the fix (3e3491a, `caustic render --spp 1`), 753 of the 3521 were lit, with a mean
/// of 0.018 and up to 0.26.
#[test]
fn a_light_sealed_in_a_box_lights_nothing_outside_it() {
    let d = common::run_lua(SEALED_BOX).unwrap();
    let r = &d.renders[0];
    let mut scene = build_scene(&d, r).unwrap();
    let camera = Camera::new(&r.camera, r.width, r.height);
    let settings = common::centre_ray();
    let window = Window::full(r.width, r.height);
    let (film, stats) = common::render_frame(&mut scene, &camera, window, &settings, &NoProgress);
    assert_eq!(stats.plan.integrator, Integrator::PhotonMap);
    let gi = stats.photons.expect("the frame traced photons");
    assert!(gi.global.iter().map(|c| c.stored).sum::<u64>() > 100_000);
    let on_surfaces: Vec<f32> = (0..r.height)
        .flat_map(|y| (0..r.width).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            scene.intersect(&ray).is_some()
        })
        .map(|(x, y)| film.pixels[(y * r.width + x) as usize].max_element())
        .collect();
    assert!(on_surfaces.len() > 2000, "{} pixels", on_surfaces.len());
    let lit = on_surfaces.iter().filter(|&&v| v > 1e-6).count();
    let mean = on_surfaces.iter().sum::<f32>() / on_surfaces.len() as f32;
    let max = on_surfaces.iter().fold(0.0f32, |a, &v| a.max(v));
    if lit > 0 {
        let png = common::out_dir("leaks").join("sealed.png");
        caustic::io::image::write_png(&film, &png).unwrap();
        eprintln!("image written to {}", png.display());
    }
    assert!(
        lit == 0,
        "{lit} of {} outside pixels lit: mean {mean}, max {max}",
        on_surfaces.len()
    );
}
