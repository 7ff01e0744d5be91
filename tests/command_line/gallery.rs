//! The gallery, `scenes/gallery/`: every scene renders through the command line at a quarter of
//! its size (48 to 64 pixels wide) into a finite, non-uniform image, and the scenes that show an
//! effect show it: the caustic, the penumbra, the adaptive sampler's extra rays at edges, the
//! colour bleeding, the file materials, the instanced mesh stored once; and `docs/gallery.md`
//! shows them all.
//!
//! Regions are fractions of the image `[x0, x1, y0, y1]`, read off the scenes' thumbnails; a scene
//! whose composition changes must update its region here.

use crate::common::{caustic, mesh_cache, out_dir, run_ok};
use image::Rgb32FImage;
use std::path::{Path, PathBuf};

/// Returns the gallery's folder.
fn gallery() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/gallery")
}

/// Returns the names of every `scenes/gallery/*.lua`, sorted.
fn scene_names() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(gallery())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "lua"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A gallery scene rendered as linear floats, with what the command printed.
struct Render {
    image: Rgb32FImage,
    stdout: String,
}

/// Renders `script` at `--scale 0.25` from `dir` into the EXR file `exr`, with `extra` flags.
fn render_file(script: &Path, exr: &Path, dir: &Path, extra: &[&str]) -> Render {
    let out = run_ok(
        caustic()
            .current_dir(dir)
            .arg("render")
            .arg(script)
            .args(["--scale", "0.25", "-q", "-o"])
            .arg(exr)
            .args(extra),
    );
    Render {
        image: image::open(exr).unwrap().to_rgb32f(),
        stdout: String::from_utf8_lossy(&out.stdout).into_owned(),
    }
}

/// Renders `scenes/gallery/NAME.lua` into `dir/FILE.exr` (`FILE` is `name` plus `tag`) with
/// `extra` flags.
fn render_as(name: &str, tag: &str, dir: &Path, extra: &[&str]) -> Render {
    let script = gallery().join(format!("{name}.lua"));
    render_file(&script, &dir.join(format!("{name}{tag}.exr")), dir, extra)
}

/// [`render_as`] with no tag and no extra flags.
fn render(name: &str, dir: &Path) -> Render {
    render_as(name, "", dir, &[])
}

/// Renders scene `name` twice in a fresh folder `gallery-NAME`: as it is, and with `flags`.
fn render_with_and_without(name: &str, flags: &[&str]) -> (Rgb32FImage, Rgb32FImage) {
    let dir = out_dir(&format!("gallery-{name}"));
    let plain = render(name, &dir).image;
    (plain, render_as(name, "-flagged", &dir, flags).image)
}

/// Returns the pixels of the fractional region `[x0, x1, y0, y1]`, row by row.
fn region(img: &Rgb32FImage, [x0, x1, y0, y1]: [f32; 4]) -> Vec<[f32; 3]> {
    let (w, h) = (img.width() as f32, img.height() as f32);
    let xs = (x0 * w) as u32..(x1 * w).ceil() as u32;
    let ys = (y0 * h) as u32..(y1 * h).ceil() as u32;
    let pixels: Vec<[f32; 3]> = ys
        .flat_map(|y| xs.clone().map(move |x| (x, y)))
        .map(|(x, y)| img.get_pixel(x, y).0)
        .collect();
    assert!(!pixels.is_empty(), "empty region");
    pixels
}

/// Returns the mean colour over the fractional region `area`.
fn mean_rgb(img: &Rgb32FImage, area: [f32; 4]) -> [f32; 3] {
    let pixels = region(img, area);
    let n = pixels.len() as f32;
    [0, 1, 2].map(|c| pixels.iter().map(|p| p[c]).sum::<f32>() / n)
}

/// Returns the mean luminance (the channels' mean) over the fractional region `area`.
fn mean_luminance(img: &Rgb32FImage, area: [f32; 4]) -> f32 {
    mean_rgb(img, area).iter().sum::<f32>() / 3.0
}

/// Returns the luminance (the channels' mean) of every pixel, row by row.
fn luminance(img: &Rgb32FImage) -> Vec<f32> {
    img.pixels().map(|p| (p[0] + p[1] + p[2]) / 3.0).collect()
}

/// Returns the luminances of the fractional region `area`, sorted.
fn sorted_luminance(img: &Rgb32FImage, area: [f32; 4]) -> Vec<f32> {
    let mut v: Vec<f32> = region(img, area)
        .iter()
        .map(|p| (p[0] + p[1] + p[2]) / 3.0)
        .collect();
    v.sort_by(f32::total_cmp);
    v
}

/// Every scene starts with a comment saying what it shows and how to render it, and renders at a
/// quarter of its size (48–64 pixels wide: thumbnails are at most 256) into an image whose
/// pixels are all finite and non-negative and which is not uniform (the 5th and 95th
/// luminance percentiles differ by more than 0.05).
#[test]
fn every_gallery_scene_renders_a_finite_varied_image() {
    let dir = out_dir("gallery-all");
    let names = scene_names();
    assert!(names.len() >= 13, "the gallery has {} scenes", names.len());
    for name in &names {
        let script = std::fs::read_to_string(gallery().join(format!("{name}.lua"))).unwrap();
        let header: Vec<&str> = script.lines().take_while(|l| l.starts_with("--")).collect();
        assert!(
            header
                .first()
                .is_some_and(|l| l.starts_with("-- Gallery: ")),
            "{name}.lua: the first line should say '-- Gallery: what it shows'"
        );
        let command = format!("render scenes/gallery/{name}.lua");
        assert!(
            header.iter().any(|l| l.contains(&command)),
            "{name}.lua: the header comment should show `caustic {command}`"
        );
        let img = render(name, &dir).image;
        assert!(
            (48..=64).contains(&img.width()),
            "{name}: {} pixels wide at --scale 0.25",
            img.width()
        );
        let bad = img
            .pixels()
            .flat_map(|p| p.0)
            .filter(|c| !c.is_finite() || *c < 0.0)
            .count();
        assert_eq!(
            bad, 0,
            "{name}: {bad} channel values not finite or negative"
        );
        let mut lum = luminance(&img);
        lum.sort_by(f32::total_cmp);
        let at = |q: f32| lum[((lum.len() - 1) as f32 * q) as usize];
        assert!(
            at(0.95) - at(0.05) > 0.05,
            "{name}: nearly uniform, luminance {} to {}",
            at(0.05),
            at(0.95)
        );
    }
}

/// The glass ball focuses the light into a spot inside its shadow brighter than the lit floor:
/// the mean of the spot's 4 brightest pixels exceeds 1.5 times the lit floor's median and 4
/// times the shadow's median, and the shadow is under half the lit floor.
#[test]
fn caustic_glass_focuses_a_spot_brighter_than_the_lit_floor_inside_the_shadow() {
    let img = render("caustic_glass", &out_dir("gallery-caustic")).image;
    let spot = sorted_luminance(&img, [0.48, 0.64, 0.52, 0.60]);
    let shadow = sorted_luminance(&img, [0.66, 0.81, 0.50, 0.61]);
    let lit = sorted_luminance(&img, [0.0, 1.0, 0.85, 1.0]);
    let median = |v: &[f32]| v[v.len() / 2];
    let brightest = spot.iter().rev().take(4).sum::<f32>() / 4.0;
    let (lit, shadow) = (median(&lit), median(&shadow));
    assert!(shadow < 0.5 * lit, "shadow {shadow}, lit floor {lit}");
    assert!(
        brightest > 1.5 * lit && brightest > 4.0 * shadow,
        "caustic {brightest}, lit floor {lit}, shadow {shadow}"
    );
}

/// The area light's shadows have a penumbra. With one camera ray per pixel (`--spp 1`, so no
/// pixel is partly covered by an edge), on the grey floor (balls and sky are coloured) the
/// shadow fraction `s = (F − A)/(F − U)` of each pixel, with `A` the render, `F` the same scene
/// without the balls and `U` the ambient term alone (kd · ambient = 0.14), lies strictly between
/// 0.1 and 0.9 on at least 40 pixels, and on at most 2 with a point light at the panel's centre.
#[test]
fn soft_shadows_have_a_penumbra_that_a_point_light_lacks() {
    let dir = out_dir("gallery-soft-shadows");
    let script = std::fs::read_to_string(gallery().join("soft_shadows.lua")).unwrap();
    let panel =
        "gr.area_light({0, 3, 0.8}, {0.8, 0.8, 0.8}, {1, 0, 0}, nil, nil, {1, 0, 0}, {0, 0, 1})";
    let balls = "  root:add_child(ball)\n";
    assert!(
        script.contains(panel) && script.contains(balls),
        "soft_shadows.lua's light or balls changed"
    );
    let point = script.replace(panel, "gr.light({0, 3, 0.8}, {0.8, 0.8, 0.8}, {1, 0, 0})");
    let penumbra = |script: &str, tag: &str| {
        let render_text = |text: &str, file: &str| {
            let lua = dir.join(format!("{file}.lua"));
            std::fs::write(&lua, text).unwrap();
            let exr = dir.join(format!("{file}.exr"));
            render_file(&lua, &exr, &dir, &["--spp", "1"]).image
        };
        let shadowed = render_text(script, tag);
        let open = render_text(&script.replace(balls, ""), &format!("{tag}-no-balls"));
        let umbra = 0.7 * 0.2;
        let mut count = 0;
        for (a, f) in shadowed.pixels().zip(open.pixels()) {
            let grey = (a[0] - a[1]).abs() < 1e-4 && (a[1] - a[2]).abs() < 1e-4;
            let s = (f[0] - a[0]) / (f[0] - umbra);
            count += usize::from(grey && f[0] > umbra + 0.05 && s > 0.1 && s < 0.9);
        }
        count
    };
    let (area, point) = (penumbra(&script, "area"), penumbra(&point, "point"));
    assert!(
        area >= 40 && point <= 2,
        "partly shadowed floor pixels: {area} under the panel, {point} under a point light"
    );
}

/// With `gr.settings{adaptive = true}` the ray-count map (`--aa-map`) gives pixels on edges
/// (a neighbour differing by more than 0.2 in luminance) over twice the mean rays of flat pixels
/// (every neighbour within 0.01).
#[test]
fn adaptive_aa_spends_more_rays_on_edges_than_on_flat_areas() {
    let dir = out_dir("gallery-adaptive");
    let map_path = dir.join("map.png");
    let img = render_as(
        "adaptive_aa",
        "",
        &dir,
        &["--aa-map", map_path.to_str().unwrap()],
    )
    .image;
    let map = image::open(&map_path).unwrap().to_luma8();
    assert_eq!(map.dimensions(), img.dimensions());
    let (w, h) = img.dimensions();
    let lum = luminance(&img);
    let (mut edge, mut flat) = ((0.0, 0), (0.0, 0));
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let at = |x: u32, y: u32| lum[(y * w + x) as usize];
            let contrast = [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)]
                .iter()
                .map(|&(u, v)| (at(u, v) - at(x, y)).abs())
                .fold(0.0, f32::max);
            let rays = map.get_pixel(x, y)[0] as f64;
            if contrast > 0.2 {
                edge = (edge.0 + rays, edge.1 + 1);
            } else if contrast < 0.01 {
                flat = (flat.0 + rays, flat.1 + 1);
            }
        }
    }
    assert!(
        edge.1 >= 20 && flat.1 >= 20,
        "{} edge and {} flat pixels",
        edge.1,
        flat.1
    );
    let (edge, flat) = (edge.0 / edge.1 as f64, flat.0 / flat.1 as f64);
    assert!(
        edge > 2.0 * flat,
        "mean map value: edges {edge}, flat {flat}"
    );
}

/// The Cornell box's ceiling, which the downward light cannot reach, is lit by interreflection
/// (mean above 0.05, and black with `--gi off`), and the floor beside the red wall is redder than
/// green by 15 %, beside the green wall greener than red, where direct light alone leaves it grey.
#[test]
fn interreflection_lights_the_ceiling_and_bleeds_the_walls_colour() {
    let (gi, direct) = render_with_and_without("interreflection", &["--gi", "off"]);
    let ceiling = [0.1, 0.3, 0.02, 0.1];
    let (lit, dark) = (
        mean_luminance(&gi, ceiling),
        mean_luminance(&direct, ceiling),
    );
    assert!(
        lit > 0.05 && dark < 1e-4,
        "ceiling {lit}, {dark} with --gi off"
    );
    let (left, right) = ([0.15, 0.3, 0.85, 0.97], [0.7, 0.85, 0.85, 0.97]);
    let [r, g, _] = mean_rgb(&gi, left);
    assert!(r > 1.15 * g, "floor by the red wall: {r} red, {g} green");
    let [r, g, _] = mean_rgb(&gi, right);
    assert!(g > 1.15 * r, "floor by the green wall: {r} red, {g} green");
    let [r, g, _] = mean_rgb(&direct, left);
    assert!(
        (r - g).abs() <= 0.02 * r.max(g),
        "direct light only: {r} red, {g} green"
    );
}

/// The water's floor is lit through the waves: with its caustic map it is over twice as bright
/// as with `--disable caustics`, and `gr.water_mesh` wrote its mesh into `CAUSTIC_CACHE`.
#[test]
fn water_lights_the_pool_floor_through_the_waves() {
    let (with, without) = render_with_and_without("water", &["--disable", "caustics"]);
    let floor = [0.45, 0.7, 0.35, 0.75];
    let (a, b) = (
        mean_luminance(&with, floor),
        mean_luminance(&without, floor),
    );
    assert!(a > 2.0 * b, "pool floor {a} with caustics, {b} without");
    let cached = std::fs::read_dir(mesh_cache())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .any(|f| f.starts_with("water-n257-") && f.ends_with(".glb"));
    assert!(cached, "no water-n257-*.glb in {}", mesh_cache().display());
}

/// The instancing scene stores its 131k-triangle sheet once and places it 36 times (`--stats`).
#[test]
fn instancing_stores_the_large_mesh_once_and_places_it_36_times() {
    let stats = render_as(
        "instancing",
        "",
        &out_dir("gallery-instancing"),
        &["--stats"],
    )
    .stdout;
    let line = stats
        .lines()
        .find(|l| l.trim_start().starts_with("triangles:"))
        .unwrap_or_else(|| panic!("no triangles line in:\n{stats}"));
    let numbers: Vec<u64> = line
        .split(|c: char| !c.is_ascii_digit())
        .filter_map(|s| s.parse().ok())
        .collect();
    let (placed, stored) = (numbers[0], numbers[1]);
    assert_eq!(stored, 2 * 256 * 256, "{line}");
    assert_eq!(placed, 36 * stored, "{line}");
}

/// Meshes without `set_material` wear their file's materials: the OBJ house's roof is red (its
/// MTL's Kd 0.6 0.15 0.1) while the clay copy beside it is grey, and the glTF vase is blue (its
/// base colour 0.12 0.28 0.65).
#[test]
fn imported_meshes_wear_their_files_materials() {
    let dir = out_dir("gallery-imports");
    let obj = render("obj_import", &dir).image;
    let [r, g, b] = mean_rgb(&obj, [0.2, 0.3, 0.22, 0.32]);
    assert!(r > 2.0 * g && r > 2.0 * b, "roof {r} {g} {b}");
    let [r, g, b] = mean_rgb(&obj, [0.69, 0.75, 0.29, 0.35]);
    assert!((r - b).abs() < 0.2 * r.max(b), "clay house {r} {g} {b}");
    let gltf = render("gltf_import", &dir).image;
    let [r, g, b] = mean_rgb(&gltf, [0.46, 0.54, 0.46, 0.54]);
    assert!(b > 2.0 * r && b > 1.5 * g, "vase {r} {g} {b}");
}

/// The Blender scene `gr.gltf` places whole wears the file's embedded checker texture on its
/// box (red and blue squares, each over a tenth of the box's pixels) and is lit by its panel.
#[test]
fn a_blender_scene_placed_whole_wears_its_texture() {
    let dir = out_dir("gallery-gltf-scene");
    let img = render("gltf_scene", &dir).image;
    let pixels = region(&img, [0.3, 0.78, 0.25, 0.9]);
    let n = pixels.len();
    let red = pixels.iter().filter(|p| p[0] > 2.0 * p[2]).count();
    let blue = pixels.iter().filter(|p| p[2] > 2.0 * p[0]).count();
    assert!(
        red > n / 10 && blue > n / 10,
        "{red} red, {blue} blue of {n}"
    );
    assert!(
        mean_luminance(&img, [0.0, 1.0, 0.0, 0.2]) > 0.05,
        "the back wall is lit"
    );
}

/// `docs/gallery.md` (written by `tools/gallery.sh`) shows every scene: it names each one's
/// thumbnail, which exists and is at most 256 pixels wide, and its render command.
#[test]
fn gallery_page_shows_every_scene() {
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("docs");
    let page = std::fs::read_to_string(docs.join("gallery.md")).unwrap();
    for name in scene_names() {
        let thumbnail = format!("gallery/{name}.png");
        let command = format!("caustic render scenes/gallery/{name}.lua");
        assert!(
            page.contains(&thumbnail) && page.contains(&command),
            "docs/gallery.md lacks {name}: run `bash tools/gallery.sh`"
        );
        let (w, _) = image::image_dimensions(docs.join(&thumbnail)).unwrap();
        assert!(w <= 256, "{thumbnail} is {w} pixels wide");
    }
}

/// Coloured water and glass absorb by their colour: the water seen in the glass is blue-green
/// (its red well under its green and blue), and the caustic the amber ball focuses in front of
/// it is amber (red over twice blue) and over 1.5 times as bright as with `--disable caustics`.
#[test]
fn coloured_glass_tints_what_passes_through_it() {
    let (with, without) = render_with_and_without("coloured_glass", &["--disable", "caustics"]);
    let water = mean_rgb(&with, [0.3, 0.45, 0.35, 0.55]);
    assert!(
        water[0] < 0.6 * water[1] && water[0] < 0.6 * water[2],
        "the water is {water:?}"
    );
    let spot = [0.64, 0.74, 0.6, 0.68];
    let caustic = mean_rgb(&with, spot);
    assert!(caustic[0] > 2.0 * caustic[2], "the caustic is {caustic:?}");
    let (a, b) = (mean_luminance(&with, spot), mean_luminance(&without, spot));
    assert!(a > 1.5 * b, "the spot is {a} with caustics, {b} without");
}

/// The spot lights only its cone and the sun everything facing it: without the sun the floor
/// far from the spot (the bottom corners) is dark and the pool under the spot bright; with it
/// the corners are the sun's closed form `kd·rgb·cos θ` (0.7 × the colour's mean 0.683 ×
/// cos θ = 0.531) to 3%, indirect light and noise included.
#[test]
fn spot_and_sun_light_the_cone_and_everything_facing_the_sun() {
    let dir = out_dir("gallery-spot-and-sun");
    let script = std::fs::read_to_string(gallery().join("spot_and_sun.lua")).unwrap();
    let lights = "{spot, sun})";
    assert!(script.contains(lights), "spot_and_sun.lua's lights changed");
    let lua = dir.join("no_sun.lua");
    std::fs::write(&lua, script.replace(lights, "{spot})")).unwrap();
    let spot = render_file(&lua, &dir.join("no_sun.exr"), &dir, &[]).image;
    let both = render("spot_and_sun", &dir).image;
    let corners = [[0.0, 0.15, 0.85, 1.0], [0.85, 1.0, 0.85, 1.0]];
    let pool = [0.36, 0.42, 0.5, 0.6];
    let cos = 0.7 / (1.0f32 + 0.49 + 0.25).sqrt();
    let sun = 0.7 * (0.6 + 0.65 + 0.8) / 3.0 * cos;
    for c in corners {
        let (dark, lit) = (mean_luminance(&spot, c), mean_luminance(&both, c));
        assert!(dark < 0.01, "corner {c:?} without the sun: {dark}");
        assert!(
            (lit / sun - 1.0).abs() < 0.03,
            "corner {c:?} in the sun: {lit}, closed form {sun}"
        );
    }
    let lit = mean_luminance(&spot, pool);
    assert!(lit > 0.3, "the pool under the spot: {lit}");
}

/// Rough metal and frosted glass: the copper ball is copper-coloured (red above green by a
/// fifth), the frosted ball shows the blue wall behind it blurred (blue above red), and the
/// frosted ball's soft caustic lights the floor under it more than four times as much as the
/// floor under the metal ball, which reflects the lamp back up and only shades the floor.
#[test]
fn rough_metal_is_copper_and_frosted_glass_casts_a_soft_caustic() {
    let dir = out_dir("gallery-rough-materials");
    let img = render("rough_materials", &dir).image;
    let copper = mean_rgb(&img, [0.25, 0.4, 0.35, 0.6]);
    assert!(copper[0] > 1.2 * copper[1], "the copper ball is {copper:?}");
    let frosted = mean_rgb(&img, [0.6, 0.75, 0.35, 0.6]);
    assert!(frosted[2] > frosted[0], "the frosted ball is {frosted:?}");
    let under_metal = mean_luminance(&img, [0.25, 0.4, 0.68, 0.74]);
    let under_glass = mean_luminance(&img, [0.6, 0.75, 0.68, 0.74]);
    assert!(
        under_glass > 4.0 * under_metal,
        "under the frosted ball {under_glass}, under the metal ball {under_metal}"
    );
}
