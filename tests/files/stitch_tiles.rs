//! `caustic stitch` on crafted tiles: window records with huge, inverted or inconsistent
//! numbers, and files that are no PNG, give an error naming the tile, never a panic or an abort
//! allocating the image they claim.

use crate::common::out_dir;
use caustic::io::image::WINDOW_KEY;
use caustic::io::stitch::stitch;
use std::path::{Path, PathBuf};

/// Writes a `width × height` grey RGB PNG at `dir/name` with `record` as its window record
/// (none when `None`); returns its path.
fn tile(dir: &Path, name: &str, width: u32, height: u32, record: Option<&str>) -> PathBuf {
    let path = dir.join(name);
    let file = std::fs::File::create(&path).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    if let Some(text) = record {
        enc.add_text_chunk(WINDOW_KEY.to_string(), text.to_string())
            .unwrap();
    }
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&vec![128; (width * height * 3) as usize])
        .unwrap();
    w.finish().unwrap();
    path
}

/// Each of 8 crafted tiles (4×4 pixels) is refused with an error naming its file and the fault:
/// full sizes of 4e9 × 4e9 (a capacity-overflow panic), 60000 × 60000 (an abort allocating
/// 57 GB), inverted, out-of-image and size-mismatched windows, a window past `u32`, a missing
/// record, and bytes that are no PNG. Two good tiles still stitch (so the check can pass).
#[test]
fn crafted_tile_headers_are_refused_naming_the_tile() {
    let dir = out_dir("stability_stitch");
    let out = dir.join("out.png");
    let cases: [(&str, Option<&str>, &str); 7] = [
        (
            "huge.png",
            Some("0 0 4 4 4000000000 4000000000"),
            "larger than",
        ),
        ("big.png", Some("0 0 4 4 60000 60000"), "larger than"),
        ("inverted.png", Some("4 0 0 4 8 8"), "does not match"),
        ("outside.png", Some("6 0 10 4 8 8"), "does not match"),
        ("mismatch.png", Some("0 0 5 4 8 8"), "does not match"),
        ("past_u32.png", Some("0 0 4 4 4294967296 8"), "malformed"),
        ("bare.png", None, "--crop"),
    ];
    for (name, record, fault) in cases {
        let path = tile(&dir, name, 4, 4, record);
        let err = stitch(std::slice::from_ref(&path), &out)
            .err()
            .unwrap_or_else(|| panic!("{name} was stitched"))
            .to_string();
        assert!(
            err.contains(&path.display().to_string()) && err.contains(fault),
            "{name}: expected the path and '{fault}' in: {err}"
        );
    }
    let junk = dir.join("junk.png");
    std::fs::write(&junk, b"\x89PNG\r\n\x1a\nnot really").unwrap();
    let err = stitch(std::slice::from_ref(&junk), &out)
        .unwrap_err()
        .to_string();
    assert!(err.contains("junk.png") && err.contains("PNG"), "{err}");
    assert!(!out.exists(), "no output from refused tiles");

    let good = [
        tile(&dir, "left.png", 4, 4, Some("0 0 4 4 8 4")),
        tile(&dir, "right.png", 4, 4, Some("4 0 8 4 8 4")),
    ];
    stitch(&good, &out).unwrap();
    let img = image::open(&out).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (8, 4));
    assert!(img.pixels().all(|p| p.0 == [128; 3]));
}

/// Writes a 4×4 grey EXR at `dir/name` whose data window starts at `at` inside a display window
/// of `display` pixels from the origin; returns its path.
fn exr_tile(dir: &Path, name: &str, at: (i32, i32), display: (usize, usize)) -> PathBuf {
    use exr::prelude::*;
    let path = dir.join(name);
    let attributes = LayerAttributes {
        layer_position: Vec2(at.0, at.1),
        ..LayerAttributes::default()
    };
    let channels = SpecificChannels::rgb(|_: Vec2<usize>| (0.5f32, 0.5f32, 0.5f32));
    let layer = Layer::new((4, 4), attributes, Encoding::default(), channels);
    let image = Image::new(
        ImageAttributes::new(IntegerBounds::from_dimensions(display)),
        layer,
    );
    image.write().to_file(&path).unwrap();
    path
}

/// Crafted EXR tiles are refused naming the tile and the fault: a data window outside the
/// display window, a display window of 3.6e9 pixels, and bytes that are no EXR. Two good EXR
/// tiles stitch, their values kept.
#[test]
fn crafted_exr_tiles_are_refused_naming_the_tile() {
    let dir = out_dir("stability_stitch_exr");
    let out = dir.join("out.exr");
    let cases = [
        (exr_tile(&dir, "outside.exr", (6, 0), (8, 4)), "not inside"),
        (exr_tile(&dir, "before.exr", (-1, 0), (8, 4)), "not inside"),
        (
            exr_tile(&dir, "huge.exr", (0, 0), (60000, 60000)),
            "larger than",
        ),
    ];
    for (path, fault) in &cases {
        let err = stitch(std::slice::from_ref(path), &out)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&path.display().to_string()) && err.contains(fault),
            "expected the path and '{fault}' in: {err}"
        );
    }
    let junk = dir.join("junk.exr");
    std::fs::write(&junk, b"v/1\x01not really").unwrap();
    let err = stitch(std::slice::from_ref(&junk), &out)
        .unwrap_err()
        .to_string();
    assert!(err.contains("junk.exr") && err.contains("EXR"), "{err}");
    assert!(!out.exists(), "no output from refused tiles");

    let good = [
        exr_tile(&dir, "left.exr", (0, 0), (8, 4)),
        exr_tile(&dir, "right.exr", (4, 0), (8, 4)),
    ];
    let s = stitch(&good, &out).unwrap();
    assert_eq!((s.width, s.height, s.tiles), (8, 4, 2));
    let img = caustic::io::image::read_rgb(&out).unwrap();
    assert_eq!((img.width, img.height), (8, 4));
    assert!(img.pixels.iter().all(|p| p.to_array() == [0.5; 3]));
}

/// One band covering the whole image (a farm of one node, `--crop 0,0,W,H`) is a tile `caustic
/// stitch` takes, and stitches into the very file the render wrote; a render's PNG names its
/// window even when it is the whole image (it had no record, and the stitch refused it).
#[test]
fn one_band_covering_the_image_stitches_into_itself() {
    let dir = out_dir("stitch-one-band");
    let scene = "
        s = gr.sphere('s'); s:set_material(gr.material({0.7, 0.5, 0.3}, {0, 0, 0}, 0))
        gr.render(s, 'x.png', 12, 10, {0, 0, 4}, {0, 0, -1}, {0, 1, 0}, 50, {0.2, 0.2, 0.2},
                  {gr.light({2, 3, 4}, {1, 1, 1}, {1, 0, 0})})";
    std::fs::write(dir.join("s.lua"), scene).unwrap();
    let run = |args: &[&str]| {
        crate::common::run_ok(crate::common::caustic().current_dir(&dir).args(args));
    };
    run(&[
        "render",
        "s.lua",
        "-q",
        "--crop",
        "0,0,12,10",
        "-o",
        "band.png",
    ]);
    run(&["stitch", "band.png", "-o", "whole.png"]);
    let (band, whole) = (dir.join("band.png"), dir.join("whole.png"));
    assert!(std::fs::read(band).unwrap() == std::fs::read(whole).unwrap());
    // A PNG that no render wrote (no window record) is still refused, naming the file.
    let plain = tile(&dir, "plain.png", 4, 4, None);
    let e = stitch(std::slice::from_ref(&plain), &dir.join("x.png"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("plain.png") && e.contains("--crop"), "{e}");
}
