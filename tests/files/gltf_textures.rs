//! glTF textures (issue 37): base colour (sRGB-decoded, times its factor), metallic-roughness
//! and normal textures looked up per hit, an emissive texture's mean colour as its emitter's
//! radiance, embedded images from buffer views and `data:` URIs as from files, and every bad
//! image an error naming the file, the material and the image.
//!
//! Each scene is a 2 × 2 quad at y = 0 facing up, its texture coordinates `u = (x + 1)/2` and
//! `v = (z + 1)/2`, seen straight down from 3 above and lit by one point light, written by the
//! test itself; renders are Whitted's, one ray through each pixel centre, so a pixel is a
//! closed form of the point its ray meets.

use crate::common::{GltfFile, out_dir, render_scene, whitted};
use caustic::budget::Budget;
use caustic::camera::Camera;
use caustic::film::Film;
use caustic::io::gltf::load_gltf;
use caustic::io::gltf::scene::{View, describe_scene};
use caustic::scene::build::build_scene;
use glam::{Vec3, Vec3A, vec3};
use std::path::{Path, PathBuf};

/// The image's side in pixels.
const SIZE: u32 = 32;

/// Where the point light is: off-centre, so that tilted normals change what a pixel receives.
const LIGHT: Vec3 = vec3(-0.8, 1.2, 0.3);

/// Returns the quad: positions accessor 0, normals 1, texture coordinates 2, indices 3.
fn quad() -> GltfFile {
    let mut f = GltfFile::default();
    f.floats(
        "VEC3",
        &[
            -1.0, 0.0, -1.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0, -1.0, 0.0, 1.0,
        ],
    );
    f.floats("VEC3", &[0.0, 1.0, 0.0].repeat(4));
    f.floats("VEC2", &[0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0]);
    // Counter-clockwise seen from above.
    f.indices(5125, &[0, 2, 1, 0, 3, 2]);
    f
}

/// Returns the glTF members of the quad's scene with `material` as its one material and
/// `textures` (`,"textures":[…],"images":[…]`, or empty) after it.
fn members(material: &str, textures: &str) -> String {
    let s = std::f32::consts::FRAC_1_SQRT_2;
    format!(
        r#""scene":0,"scenes":[{{"nodes":[0,1,2]}}],
        "nodes":[{{"mesh":0}},
          {{"camera":0,"translation":[0,3,0],"rotation":[{},0,0,{s}]}},
          {{"translation":[{},{},{}],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}],
        "cameras":[{{"type":"perspective","perspective":{{"yfov":0.8,"aspectRatio":1.0,"znear":0.1}}}}],
        "extensionsUsed":["KHR_lights_punctual"],
        "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point","intensity":683}}]}}}},
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2}},"indices":3,"material":0}}]}}],
        "materials":[{material}]{textures}"#,
        -s, LIGHT.x, LIGHT.y, LIGHT.z
    )
}

/// Returns the `,"textures":…,"images":…` members of one texture showing image `image` (JSON).
fn one_image(image: &str) -> String {
    format!(r#","textures":[{{"source":0}}],"images":[{image}]"#)
}

/// Returns the PNG of a `width × height` RGB image.
fn png(width: u32, height: u32, texels: &[[u8; 3]]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().unwrap();
    writer.write_image_data(texels.as_flattened()).unwrap();
    writer.finish().unwrap();
    out
}

/// Returns a 4 × 4 PNG of one colour.
fn uniform_png(c: [u8; 3]) -> Vec<u8> {
    png(4, 4, &[c; 16])
}

/// Returns the linear value of an sRGB byte, by the formula (IEC 61966-2-1), in double.
fn srgb(c: u8) -> f32 {
    let c = f64::from(c) / 255.0;
    let linear = if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    };
    linear as f32
}

/// Renders the glTF scene at `path` (`SIZE` square) with Whitted's integrator; returns the
/// film and the camera, or the error building the scene gave.
fn render(path: &Path) -> Result<(Film, Camera), String> {
    let view = View {
        size: Some((SIZE, SIZE)),
        output: "x.png".into(),
        camera: None,
    };
    let desc = describe_scene(path, &view, Budget::machine_default()).map_err(|e| e.to_string())?;
    let r = desc.renders[0].clone();
    let mut scene = build_scene(&desc, &r).map_err(|e| e.to_string())?;
    let camera = Camera::new(&r.camera, r.width, r.height);
    let film = render_scene(&mut scene, &camera, r.width, r.height, &whitted());
    Ok((film, camera))
}

/// Returns the pixels whose centre rays meet the quad at least `margin` inside its edges, with
/// the point each meets.
fn quad_pixels(camera: &Camera, margin: f32) -> Vec<(u32, u32, Vec3)> {
    let mut out = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5);
            let p = Vec3::from(ray.at(-ray.origin.y / ray.dir.y));
            if p.x.abs() < 1.0 - margin && p.z.abs() < 1.0 - margin {
                out.push((x, y, p));
            }
        }
    }
    assert!(out.len() > 100, "{} pixels on the quad", out.len());
    out
}

/// Returns what a Lambertian surface of reflectance `kd` at `p` with normal `n` sends up from
/// the light, in the course's units: `kd · rgb · cos θ / d²`, `rgb = 683 cd / (683 π)`.
fn lambert(kd: Vec3, p: Vec3, n: Vec3) -> Vec3 {
    let to_light = LIGHT - p;
    let cos = n.dot(to_light.normalize()).max(0.0);
    kd / std::f32::consts::PI * cos / to_light.length_squared()
}

/// Writes the quad with `material` and image members `textures` as `name.glb` in `dir`.
fn write(f: &GltfFile, dir: &Path, name: &str, material: &str, textures: &str) -> PathBuf {
    f.write_glb(dir, name, &members(material, textures))
}

/// sRGB 188 is linear 0.5029 (to four places), by the renderer's decoding as by the formula.
#[test]
fn srgb_188_decodes_to_linear_0_5029() {
    assert!((srgb(188) - 0.5029).abs() < 5e-5, "{}", srgb(188));
    let t = caustic::material::texture::Texture::from_rgb(1, 1, vec![[188, 0, 255]]);
    let c = t.srgb_colour(glam::Vec2::new(0.4, 0.6));
    assert!(
        (c - Vec3A::new(0.5029, 0.0, 1.0)).abs().max_element() < 5e-5,
        "{c}"
    );
}

/// A GLB whose base colour is an embedded PNG of sRGB 188 with `baseColorFactor` (1, 0.5,
/// 0.25) renders that colour: against the same quad with a black base colour (the same 4 %
/// specular lobe, so the highlight and the mirrored sky cancel), every pixel on the quad gains
/// `kd · rgb · cos θ / d²` with `kd = 0.50289 · (1, 0.5, 0.25)`, within 1e-4 of the largest.
#[test]
fn an_embedded_base_colour_png_renders_its_colour_times_the_factor() {
    let dir = out_dir("gltf-texture-base-colour");
    let mut f = quad();
    let view = f.view(&uniform_png([188, 188, 188]));
    let textured = write(
        &f,
        &dir,
        "textured",
        r#"{"name":"Paint","pbrMetallicRoughness":{"baseColorFactor":[1,0.5,0.25,1],
            "metallicFactor":0,"roughnessFactor":1,"baseColorTexture":{"index":0}}}"#,
        &one_image(&format!(
            r#"{{"bufferView":{view},"mimeType":"image/png"}}"#
        )),
    );
    let black = write(
        &f,
        &dir,
        "black",
        r#"{"pbrMetallicRoughness":{"baseColorFactor":[0,0,0,1],"metallicFactor":0,"roughnessFactor":1}}"#,
        "",
    );
    let (a, camera) = render(&textured).unwrap();
    let (b, _) = render(&black).unwrap();
    let kd = srgb(188) * vec3(1.0, 0.5, 0.25);
    let mut largest = 0.0f32;
    for (x, y, p) in quad_pixels(&camera, 0.05) {
        let got = Vec3::from(a.get(x, y) - b.get(x, y));
        let want = lambert(kd, p, Vec3::Y);
        largest = largest.max(want.max_element());
        assert!(
            (got - want).abs().max_element() < 1e-4 * want.max_element().max(1e-3),
            "pixel ({x}, {y}) at {p}: gained {got}, closed form {want}"
        );
    }
    assert!(largest > 0.05, "the quad is lit: {largest}");
}

/// One image, three ways: a GLB buffer view, a base64 `data:` URI and a PNG file beside the
/// glTF file render the same image, bit for bit.
#[test]
fn a_data_uri_a_buffer_view_and_a_file_render_alike() {
    use base64::Engine;
    let dir = out_dir("gltf-texture-sources");
    let texels: Vec<[u8; 3]> = (0..64u32)
        .map(|i| {
            [
                (i * 37 % 256) as u8,
                (i * 91 % 256) as u8,
                (i * 13 % 256) as u8,
            ]
        })
        .collect();
    let image = png(8, 8, &texels);
    std::fs::write(dir.join("checker image.png"), &image).unwrap();
    let mut f = quad();
    let view = f.view(&image);
    let material = r#"{"name":"Paint","pbrMetallicRoughness":{"metallicFactor":0,"baseColorTexture":{"index":0}}}"#;
    let data = base64::engine::general_purpose::STANDARD.encode(&image);
    let sources = [
        format!(r#"{{"bufferView":{view},"mimeType":"image/png"}}"#),
        format!(r#"{{"uri":"data:image/png;base64,{data}"}}"#),
        r#"{"uri":"checker%20image.png"}"#.to_owned(),
    ];
    let films: Vec<Film> = sources
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let path = write(&f, &dir, &format!("source{i}"), material, &one_image(s));
            render(&path).unwrap().0
        })
        .collect();
    let plain = r#"{"name":"Paint","pbrMetallicRoughness":{"metallicFactor":0}}"#;
    let (untextured, _) = render(&write(&f, &dir, "plain", plain, "")).unwrap();
    assert!(
        films[0].pixels != untextured.pixels,
        "the texture shows in the render"
    );
    assert!(
        films[0].pixels == films[1].pixels,
        "data URI against buffer view"
    );
    assert!(
        films[0].pixels == films[2].pixels,
        "file against buffer view"
    );
}

/// Returns a PNG whose header claims `side × side` RGB pixels over a 1 × 1 image's data.
fn oversized_png(side: u32) -> Vec<u8> {
    let mut bytes = uniform_png([1, 2, 3]);
    bytes[16..20].copy_from_slice(&side.to_be_bytes());
    bytes[20..24].copy_from_slice(&side.to_be_bytes());
    // The IHDR chunk's CRC covers its type and its 13 bytes of data.
    let crc = crc32fast::hash(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    bytes
}

/// Every bad embedded image is an error naming the file, the material, the texture and the
/// image: a corrupt image, a truncated one, one whose header claims 60000 × 60000 pixels
/// (refused by the budget or the decoder's limit before any pixel is allocated), a buffer view
/// outside its buffer, and `data:` URIs that are not base64 or whose base64 is bad.
#[test]
fn bad_embedded_images_are_errors_naming_the_file_and_the_image() {
    let dir = out_dir("gltf-texture-faults");
    let material = r#"{"name":"Paint","pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}"#;
    let noise: Vec<[u8; 3]> = (0..256u32)
        .map(|i| {
            [
                (i * 97 % 251) as u8,
                (i * 89 % 241) as u8,
                (i * 7 % 256) as u8,
            ]
        })
        .collect();
    let whole = png(16, 16, &noise);
    let embedded: [(&str, Vec<u8>, &str); 3] = [
        (
            "corrupt",
            b"definitely not an image".to_vec(),
            "cannot decode",
        ),
        (
            "truncated",
            whole[..whole.len() / 2].to_vec(),
            "cannot decode",
        ),
        ("oversized", oversized_png(60_000), "60000x60000"),
    ];
    for (name, bytes, why) in embedded {
        let mut f = quad();
        let view = f.view(&bytes);
        let image = format!(r#"{{"bufferView":{view},"mimeType":"image/png"}}"#);
        let path = write(&f, &dir, name, material, &one_image(&image));
        let e = render(&path)
            .err()
            .unwrap_or_else(|| panic!("{name} renders"));
        let file = path.display().to_string();
        assert!(
            e.starts_with(&file)
                && e.contains("material 'Paint': base colour texture, image 0")
                && (e.contains(why) || name == "oversized" && e.contains("limit")),
            "{name}: {e}"
        );
    }
    // Faults in finding the bytes are the loader's, with the image's index and the reason.
    let mut f = quad();
    let outside = f.raw_view(r#"{"buffer":0,"byteOffset":100000,"byteLength":64}"#);
    let located: [(&str, String, &str); 3] = [
        (
            "outside",
            format!(r#"{{"bufferView":{outside},"mimeType":"image/png"}}"#),
            "lies outside buffer 0",
        ),
        (
            "not-base64",
            r#"{"uri":"data:image/png,rawbytes"}"#.to_owned(),
            "data URI is not base64",
        ),
        (
            "bad-base64",
            r#"{"uri":"data:image/png;base64,@@not*base64@@"}"#.to_owned(),
            "bad base64 in data URI",
        ),
    ];
    for (name, image, why) in located {
        let path = write(&f, &dir, name, material, &one_image(&image));
        let e = load_gltf(&path).unwrap_err().to_string();
        let file = path.display().to_string();
        assert!(
            e.starts_with(&file)
                && e.contains("Paint: base colour texture: image 0")
                && e.contains(why),
            "{name}: {e}"
        );
        let e = render(&path)
            .err()
            .unwrap_or_else(|| panic!("{name} renders"));
        assert!(e.contains(&file) && e.contains(why), "{name}: {e}");
    }
}

/// The metallic-roughness texture works texel by texel: on a quad whose texture is metallic 1
/// and roughness 0.2 on its left half (u < 0.5) and metallic 0 and roughness 0.8 on its right,
/// every pixel at least 1.6 texels from the halves' borders renders as the untextured
/// material with those factors does (within 1e-4 of the brightest), and the two differ there.
#[test]
fn metallic_roughness_texels_render_as_the_factors_they_stand_for() {
    let dir = out_dir("gltf-texture-metallic-roughness");
    let mut f = quad();
    // 16 × 16, blue metallic and green roughness; the left eight columns metal.
    let texels: Vec<[u8; 3]> = (0..256)
        .map(|i| {
            if i % 16 < 8 {
                [0, 51, 255]
            } else {
                [0, 204, 0]
            }
        })
        .collect();
    let view = f.view(&png(16, 16, &texels));
    let base = "\"baseColorFactor\":[0.9,0.6,0.3,1]";
    let textured = write(
        &f,
        &dir,
        "textured",
        &format!(
            r#"{{"pbrMetallicRoughness":{{{base},"metallicFactor":1,"roughnessFactor":1,
                "metallicRoughnessTexture":{{"index":0}}}}}}"#
        ),
        &one_image(&format!(r#"{{"bufferView":{view}}}"#)),
    );
    let factors = |name: &str, metallic: f32, roughness: f32| {
        let material = format!(
            r#"{{"pbrMetallicRoughness":{{{base},"metallicFactor":{metallic},"roughnessFactor":{roughness}}}}}"#
        );
        render(&write(&f, &dir, name, &material, "")).unwrap().0
    };
    let metal = factors("metal", 1.0, 51.0 / 255.0);
    let plastic = factors("plastic", 0.0, 204.0 / 255.0);
    let (film, camera) = render(&textured).unwrap();
    let brightest = metal
        .pixels
        .iter()
        .chain(&plastic.pixels)
        .map(|c| c.max_element())
        .fold(0.0, f32::max);
    let (mut left, mut right, mut differ) = (0, 0, 0.0f32);
    for (x, y, p) in quad_pixels(&camera, 0.0) {
        let u = (p.x + 1.0) / 2.0;
        let want = if (0.1..0.4).contains(&u) {
            left += 1;
            &metal
        } else if (0.6..0.9).contains(&u) {
            right += 1;
            &plastic
        } else {
            continue;
        };
        let got = film.get(x, y);
        differ = differ.max((metal.get(x, y) - plastic.get(x, y)).abs().max_element());
        assert!(
            (got - want.get(x, y)).abs().max_element() < 1e-4 * brightest,
            "pixel ({x}, {y}) at u = {u}: {got} against {}",
            want.get(x, y)
        );
    }
    assert!(left > 50 && right > 50, "{left} and {right} pixels");
    assert!(
        differ > 0.2 * brightest,
        "the two materials differ: {differ}"
    );
}

/// A normal texture of one tangent-space normal tilts the quad's shading normal by it: the
/// diffuse light a white quad gains over a black one (the same specular lobe, bent alike) is
/// `kd · rgb · cos θ / d²` about the bent normal `(x, z, −y)` of the decoded
/// `normalize((2c/255 − 1) · (s, s, 1))` (+u is +x, the image's up −z), for scale `s` 1 and 0.4;
/// and it differs from the unbent quad's by more than a tenth.
#[test]
fn a_normal_texture_bends_the_shading_normal_by_its_scale() {
    let dir = out_dir("gltf-texture-normal");
    let mut f = quad();
    let code = [204u8, 100, 220];
    let view = f.view(&uniform_png(code));
    let decoded = Vec3::from_array(code.map(|c| 2.0 * f32::from(c) / 255.0 - 1.0));
    for scale in [1.0f32, 0.4] {
        let material = |base: &str| {
            format!(
                r#"{{"pbrMetallicRoughness":{{"baseColorFactor":[{base},1],"metallicFactor":0}},
                    "normalTexture":{{"index":0,"scale":{scale}}}}}"#
            )
        };
        let image = one_image(&format!(r#"{{"bufferView":{view}}}"#));
        let white = write(&f, &dir, "white", &material("1,1,1"), &image);
        let black = write(&f, &dir, "black", &material("0,0,0"), &image);
        let (a, camera) = render(&white).unwrap();
        let (b, _) = render(&black).unwrap();
        let ts = (decoded * vec3(scale, scale, 1.0)).normalize();
        let bent = vec3(ts.x, ts.z, -ts.y);
        let mut tilt = 0.0f32;
        for (x, y, p) in quad_pixels(&camera, 0.05) {
            let got = Vec3::from(a.get(x, y) - b.get(x, y));
            let want = lambert(Vec3::ONE, p, bent);
            let flat = lambert(Vec3::ONE, p, Vec3::Y);
            tilt = tilt.max((want - flat).abs().max_element() / flat.max_element());
            assert!(
                (got - want).abs().max_element() < 1e-4 * want.max_element().max(1e-3),
                "scale {scale}, pixel ({x}, {y}) at {p}: gained {got}, closed form {want}"
            );
        }
        assert!(
            tilt > 0.1,
            "scale {scale}: the bent normal matters ({tilt})"
        );
    }
}

/// An emissive texture's mean colour, sRGB-decoded, times `emissiveFactor × strength` is the
/// emitter's radiance: texels (255, 188, 0) and (0, 188, 0) average to (0.5, 0.50289, 0).
#[test]
fn an_emissive_texture_stands_in_by_its_mean_colour() {
    let dir = out_dir("gltf-texture-emissive");
    let mut f = quad();
    let view = f.view(&png(2, 1, &[[255, 188, 0], [0, 188, 0]]));
    let rest = format!(
        r#""nodes":[{{"mesh":0}}],
        "extensionsUsed":["KHR_materials_emissive_strength"],
        "materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0,0,0,1]}},
          "emissiveFactor":[1,0.5,1],"emissiveTexture":{{"index":0}},
          "extensions":{{"KHR_materials_emissive_strength":{{"emissiveStrength":4}}}}}}],
        "textures":[{{"source":0}}],"images":[{{"bufferView":{view}}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":2}},"indices":3,"material":0}}]}}]"#
    );
    let path = f.write_glb(&dir, "lamp", &rest);
    let data = load_gltf(&path).unwrap();
    assert_eq!(data.emitters.len(), 1);
    let want = vec3(0.5, srgb(188) * 0.5, 0.0) * 4.0;
    let got = data.emitters[0].radiance;
    assert!(
        (got - want).abs().max_element() < 1e-5,
        "{got} against {want}"
    );
    let desc = describe_scene(&path, &View::default(), Budget::machine_default()).unwrap();
    let all = desc.warnings.join("\n");
    assert!(
        all.contains("material 0: emissive texture: its mean colour stands in"),
        "{all}"
    );
}

/// `caustic info` lists what is still not read (occlusion and transmission textures, alpha)
/// and what stands in (an emissive texture's mean, a second texture coordinate set, samplers),
/// and no longer the textures caustic reads: base colour (embedded), metallic-roughness, normal.
#[test]
fn what_is_read_is_no_longer_listed_and_what_is_not_still_is() {
    let dir = out_dir("gltf-texture-listing");
    let mut f = quad();
    let view = f.view(&uniform_png([9, 9, 9]));
    let material = r#"{"name":"Everything","alphaMode":"MASK",
        "pbrMetallicRoughness":{"baseColorTexture":{"index":0},
          "metallicRoughnessTexture":{"index":0,"texCoord":1}},
        "normalTexture":{"index":0},"occlusionTexture":{"index":0},
        "emissiveTexture":{"index":0},"emissiveFactor":[1,1,1]}"#;
    let textures = format!(
        r#","samplers":[{{"magFilter":9728,"wrapS":33071}}],
        "textures":[{{"source":0,"sampler":0}}],"images":[{{"bufferView":{view}}}]"#
    );
    let path = write(&f, &dir, "everything", material, &textures);
    let desc = describe_scene(&path, &View::default(), Budget::machine_default()).unwrap();
    let all = desc.warnings.join("\n");
    for want in [
        "material 'Everything': occlusion texture, alpha (drawn opaque) not read",
        "material 'Everything': emissive texture: its mean colour stands in",
        "material 'Everything': metallic-roughness texture uses TEXCOORD_1",
        "1 texture asks for nearest filtering: looked up bilinearly",
        "1 texture asks for clamped or mirrored wrapping: drawn repeating",
    ] {
        assert!(all.contains(want), "missing '{want}' in:\n{all}");
    }
    for gone in ["normal texture", "embedded", "base colour texture"] {
        assert!(!all.contains(gone), "'{gone}' still listed in:\n{all}");
    }
}

/// Blender's `textured_box.glb` (a 64 × 64 orange and blue checker PNG in a buffer view, on a
/// box in a grey room) renders its checker: the box shows orange pixels (red well above blue)
/// and blue ones (blue well above red), which a white box in a grey room has none of.
#[test]
fn blenders_textured_box_renders_its_checker() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/gltf/textured_box.glb");
    let view = View {
        size: Some((64, 48)),
        output: "x.png".into(),
        camera: None,
    };
    let desc = describe_scene(&path, &view, Budget::machine_default()).unwrap();
    let r = desc.renders[0].clone();
    let mut scene = build_scene(&desc, &r).unwrap();
    let textured = scene.materials.iter().filter(|m| m.is_textured()).count();
    assert_eq!(textured, 1, "the checker box's material");
    let camera = Camera::new(&r.camera, r.width, r.height);
    let film = render_scene(&mut scene, &camera, r.width, r.height, &whitted());
    let count = |f: fn(Vec3A) -> bool| film.pixels.iter().filter(|&&c| f(c)).count();
    let orange = count(|c| c.x > 0.01 && c.x > 2.0 * c.z);
    let blue = count(|c| c.z > 0.01 && c.z > 2.0 * c.x);
    assert!(
        orange > 40 && blue > 40,
        "{orange} orange and {blue} blue pixels"
    );
}

/// `caustic export-mitsuba` writes a non-metal's base colour texture as a Mitsuba `bitmap`: an
/// EXR of the texels sRGB-decoded times `baseColorFactor`, over `1 − 0.04` for the diffuse
/// lobe's share of the blend with glTF's 4% specular lobe (sRGB 188 and factor (1, 0.5, 0.25):
/// `0.50289 · (1, 0.5, 0.25) / 0.96` in every texel, to 1e-5), read raw and bilinear as caustic
/// looks it up, and the OBJ's texture coordinates with `v` flipped (OBJ's runs up the image).
/// A metal's base colour texture (it colours the specular lobe) stays outside the subset.
#[test]
fn a_base_colour_texture_exports_as_a_mitsuba_bitmap() {
    let dir = out_dir("gltf-texture-mitsuba");
    let mut f = quad();
    let view = f.view(&uniform_png([188, 188, 188]));
    let image = one_image(&format!(
        r#"{{"bufferView":{view},"mimeType":"image/png"}}"#
    ));
    let paint = |metallic: u32| {
        format!(
            r#"{{"name":"Paint","pbrMetallicRoughness":{{"baseColorFactor":[1,0.5,0.25,1],
                "metallicFactor":{metallic},"roughnessFactor":1,"baseColorTexture":{{"index":0}}}}}}"#
        )
    };
    write(&f, &dir, "paint", &paint(0), &image);
    let out = crate::common::run_ok(crate::common::caustic().current_dir(&dir).args([
        "export-mitsuba",
        "paint.glb",
        "-o",
        "paint.xml",
    ]));
    assert!(out.status.success());
    let xml = std::fs::read_to_string(dir.join("paint.xml")).unwrap();
    let bitmap = r#"<texture type="bitmap" name="reflectance"><string name="filename" value=""#;
    let at = xml.find(bitmap).expect("a bitmap reflectance") + bitmap.len();
    let file = &xml[at..at + xml[at..].find('"').unwrap()];
    assert!(
        file.starts_with("paint_kd") && file.ends_with(".exr"),
        "{file}"
    );
    for part in [
        r#"<string name="filter_type" value="bilinear"/>"#,
        r#"<string name="wrap_mode" value="repeat"/>"#,
        r#"<boolean name="raw" value="true"/>"#,
    ] {
        assert!(xml.contains(part), "{part} not in {xml}");
    }
    let exr = image::open(dir.join(file)).unwrap().into_rgb32f();
    let want = srgb(188) * vec3(1.0, 0.5, 0.25) / 0.96;
    for p in exr.pixels() {
        let got = Vec3::from(p.0);
        assert!(
            (got - want).abs().max_element() < 1e-5,
            "{got} against {want}"
        );
    }
    let obj = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|e| e == "obj"))
        .unwrap();
    let obj = std::fs::read_to_string(obj).unwrap();
    let vts: Vec<&str> = obj.lines().filter(|l| l.starts_with("vt ")).collect();
    assert_eq!(vts, ["vt 0 1", "vt 1 1", "vt 1 0", "vt 0 0"]);
    assert!(obj.lines().any(|l| l == "f 1/1/1 3/3/3 2/2/2"), "{obj}");
    write(&f, &dir, "metal", &paint(1), &image);
    let out = crate::common::caustic()
        .current_dir(&dir)
        .args(["export-mitsuba", "metal.glb", "-o", "metal.xml"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("only a non-metal's base colour texture"),
        "{err}"
    );
}
