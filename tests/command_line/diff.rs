//! `caustic diff`: the metrics of an image against a reference, on images with closed-form
//! answers, and clear errors for images that cannot be compared.

use crate::common::{caustic, out_dir};
use std::path::Path;

fn write_exr(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> f32) {
    let mut img = image::Rgb32FImage::new(w, h);
    for (x, y, p) in img.enumerate_pixels_mut() {
        *p = image::Rgb([f(x, y); 3]);
    }
    image::DynamicImage::ImageRgb32F(img).save(path).unwrap();
}

/// A uniform +25% offset is 1.25 in mean ratio, +0.25 in mean error, relative RMSE and block
/// bias; a ±1 checkerboard on 4 has RMSE 1 and no block bias (noise averages out of a block).
#[test]
fn diff_prints_closed_form_metrics() {
    let dir = out_dir("diff");
    let (r, a, c) = (dir.join("r.exr"), dir.join("a.exr"), dir.join("c.exr"));
    write_exr(&r, 16, 16, |_, _| 4.0);
    write_exr(&a, 16, 16, |_, _| 5.0);
    write_exr(&c, 16, 16, |x, y| if (x + y) % 2 == 0 { 5.0 } else { 3.0 });
    let run = |img: &Path, extra: &[&str]| {
        let out = caustic()
            .arg("diff")
            .arg(img)
            .arg(&r)
            .args(extra)
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        text
    };
    let text = run(&a, &["-o", dir.join("d.png").to_str().unwrap()]);
    for want in [
        "mean ratio 1.25000",
        "mean error +0.25000",
        "relative RMSE 0.25000",
        "block bias 0.25000",
    ] {
        assert!(text.contains(want), "missing '{want}':\n{text}");
    }
    let d = image::open(dir.join("d.png")).unwrap().to_rgb8();
    assert_eq!(d.get_pixel(3, 3)[0], 255, "brighter is red");
    let text = run(&c, &["--region", "0,0,16,8"]);
    assert!(
        text.contains("RMSE 1.000000") && text.contains("block bias 0.00000"),
        "{text}"
    );
}

/// Images of different sizes, a region outside the image and a missing file are errors that
/// name what is wrong.
#[test]
fn diff_refuses_what_it_cannot_compare() {
    let dir = out_dir("diff_errors");
    let (r, small) = (dir.join("r.exr"), dir.join("s.exr"));
    write_exr(&r, 16, 16, |_, _| 1.0);
    write_exr(&small, 8, 8, |_, _| 1.0);
    for (args, want) in [
        (vec![small.clone(), r.clone()], "is 8x8 but".to_string()),
        (
            vec![dir.join("none.exr"), r.clone()],
            "none.exr".to_string(),
        ),
    ] {
        let out = caustic().arg("diff").args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && err.contains(&want), "{err}");
    }
    let out = caustic()
        .arg("diff")
        .arg(&r)
        .arg(&r)
        .args(["--region", "0,0,20,4"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("inside the 16x16 image"),
        "{err}"
    );
}
