//! Image formats by extension: every format caustic writes reads back with the values written,
//! within the format's stated precision (PFM and EXR exact, Radiance RGBE within 1% of a pixel's
//! largest channel, PNG its 8-bit codes), and the command line writes and compares them.

use crate::common::{caustic, out_dir, run_ok};
use caustic::film::{Film, Window};
use caustic::io::image::{Tonemap, read_rgb, write_image};
use glam::Vec3A;

/// Returns a 7×5 film of distinct values over six orders of magnitude, black included.
fn film() -> Film {
    let (w, h) = (7u32, 5u32);
    let pixels = (0..w * h)
        .map(|i| {
            let v = |k: u32| ((i * 3 + k) as f32 * 0.37).exp() * 1e-3;
            if i == 4 {
                Vec3A::ZERO
            } else {
                Vec3A::new(v(0), v(1), v(2))
            }
        })
        .collect();
    Film {
        width: w,
        height: h,
        pixels,
        samples: vec![1; (w * h) as usize],
        window: Window::full(w, h),
    }
}

/// PFM and EXR keep every f32 bit for bit, row 0 at the top; the PFM file is little-endian
/// (negative scale) and stores the bottom row first.
#[test]
fn float_formats_round_trip_exactly() {
    let dir = out_dir("image_formats_exact");
    let film = film();
    for name in ["f.pfm", "f.exr", "f.PFM"] {
        let path = dir.join(name);
        write_image(&film, &path, Tonemap::Clamp).unwrap();
        let back = read_rgb(&path).unwrap();
        assert_eq!(
            (back.width, back.height),
            (film.width, film.height),
            "{name}"
        );
        for (i, (a, b)) in back.pixels.iter().zip(&film.pixels).enumerate() {
            assert_eq!(a.to_array(), b.to_array(), "{name}: pixel {i}");
        }
    }
    let bytes = std::fs::read(dir.join("f.pfm")).unwrap();
    let header = b"PF\n7 5\n-1.0\n";
    assert_eq!(&bytes[..header.len()], header);
    let bottom_left = film.get(0, 4).x.to_le_bytes();
    assert_eq!(&bytes[header.len()..header.len() + 4], &bottom_left);
}

/// Radiance RGBE shares one 8-bit exponent between the channels: each channel comes back
/// within 1% of the pixel's largest channel, and black stays black.
#[test]
fn radiance_hdr_round_trips_within_one_percent() {
    let dir = out_dir("image_formats_hdr");
    let film = film();
    let path = dir.join("f.hdr");
    write_image(&film, &path, Tonemap::Clamp).unwrap();
    assert!(std::fs::read(&path).unwrap().starts_with(b"#?RADIANCE"));
    let back = read_rgb(&path).unwrap();
    assert_eq!((back.width, back.height), (7, 5));
    for (i, (a, b)) in back.pixels.iter().zip(&film.pixels).enumerate() {
        let tolerance = 0.01 * b.max_element();
        assert!(
            (*a - *b).abs().max_element() <= tolerance,
            "pixel {i}: read {a}, wrote {b}"
        );
    }
    assert_eq!(back.pixels[4], Vec3A::ZERO);
}

/// The command line writes each format by its extension; `caustic diff` reads PFM and HDR
/// (PFM against EXR: no difference at all; HDR within RGBE's precision); a tile must be PNG
/// or EXR, and an unknown extension names the four formats.
#[test]
fn the_command_line_writes_every_format_and_diff_reads_them() {
    let dir = out_dir("image_formats_cli");
    std::fs::write(
        dir.join("s.lua"),
        "s = gr.sphere('s'); s:set_material(gr.material({0.8, 0.5, 0.2}, {0, 0, 0}, 0))
         gr.render(s, 'x.png', 12, 8, {0, 0, 5}, {0, 0, -1}, {0, 1, 0}, 50, {0.1, 0.1, 0.1},
                   {gr.light({2, 2, 5}, {1, 1, 1}, {1, 0, 0})})",
    )
    .unwrap();
    for name in ["out.exr", "out.pfm", "out.hdr"] {
        let out = run_ok(
            caustic()
                .current_dir(&dir)
                .args(["render", "s.lua", "-q", "-o", name]),
        );
        assert!(String::from_utf8_lossy(&out.stderr).contains(name));
    }
    let diff = |a: &str| {
        let out = run_ok(caustic().current_dir(&dir).args(["diff", a, "out.exr"]));
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let exact = diff("out.pfm");
    assert!(exact.contains("RMSE 0.000000"), "{exact}");
    let hdr = diff("out.hdr");
    let rel: f64 = hdr
        .lines()
        .find_map(|l| l.strip_prefix("relative RMSE "))
        .unwrap()
        .parse()
        .unwrap();
    assert!(rel > 0.0 && rel < 0.01, "{hdr}");
    let refused = |args: &[&str], what: &str| {
        let out = caustic().current_dir(&dir).args(args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(what),
            "{args:?}: {err}"
        );
    };
    refused(
        &["render", "s.lua", "-q", "--crop", "0,0,6,8", "-o", "t.pfm"],
        "--crop",
    );
    refused(
        &["render", "s.lua", "-q", "-o", "out.tiff"],
        "'.tiff' (caustic writes .png, .exr, .pfm and .hdr)",
    );
    assert!(!dir.join("t.pfm").exists() && !dir.join("out.tiff").exists());
}
