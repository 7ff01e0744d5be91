//! `caustic stitch` on crafted tiles: window records with huge, inverted or inconsistent
//! numbers, and files that are no PNG, give an error naming the tile, never a panic or an abort
//! allocating the image they claim.

mod common;

use caustic::io::image::{WINDOW_KEY, stitch};
use common::out_dir;
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
