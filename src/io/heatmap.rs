//! `--heatmap nodes|triangles|time`: a picture of what each pixel cost (BVH nodes visited,
//! triangles tested, or thread time, over every ray its shading cast: camera, shadow and
//! gather rays), with a colour-scale legend beneath it.
//!
//! The scale is linear from 0 to the 99.9th percentile of the pixels (brighter pixels are
//! drawn at the top colour, and the legend says "≥"), so a handful of extreme pixels (a ray
//! grazing a mesh) does not leave the rest of the picture dark. The colours follow matplotlib's
//! *inferno* (perceptually uniform, readable in grey), through five of its stops. The legend's
//! text needs a font found at run time ([`crate::study::plot`]); without one the bar is drawn
//! without labels and the caller prints the scale.

use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;

/// What a heatmap shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Measure {
    Nodes,
    Triangles,
    Time,
}

impl Measure {
    /// Returns the measure's column in a pixel's heat (`[nodes, triangles, ns]`).
    fn column(self) -> usize {
        self as usize
    }

    /// Returns the measure's name, as `--heatmap` spells it.
    pub fn name(self) -> &'static str {
        ["nodes", "triangles", "time"][self as usize]
    }

    /// Returns the legend's caption and the value shown for `v` (time in microseconds).
    fn caption(self, v: f32) -> (&'static str, String) {
        match self {
            Measure::Nodes => ("BVH nodes visited per pixel", format!("{v:.0}")),
            Measure::Triangles => ("triangles tested per pixel", format!("{v:.0}")),
            Measure::Time => ("thread time per pixel", format!("{:.0} µs", v / 1000.0)),
        }
    }
}

/// Height of the legend strip under the picture, in pixels.
const LEGEND: u32 = 56;

/// Inferno's colours at 0, 1/4, 1/2, 3/4 and 1.
const STOPS: [[f32; 3]; 5] = [
    [0.0, 0.0, 4.0],
    [87.0, 16.0, 110.0],
    [188.0, 55.0, 84.0],
    [249.0, 142.0, 9.0],
    [252.0, 255.0, 164.0],
];

/// Returns the colour of `x` in [0, 1] (clamped).
fn colour(x: f32) -> [u8; 3] {
    let x = if x.is_finite() {
        x.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let f = x * (STOPS.len() - 1) as f32;
    let i = (f as usize).min(STOPS.len() - 2);
    let t = f - i as f32;
    std::array::from_fn(|c| (STOPS[i][c] + t * (STOPS[i + 1][c] - STOPS[i][c]) + 0.5) as u8)
}

/// Returns the 99.9th percentile of `values` (0 for none).
fn top(mut values: Vec<f32>) -> f32 {
    if values.is_empty() {
        return 0.0;
    }
    let k = ((values.len() - 1) as f64 * 0.999) as usize;
    let (_, v, _) = values.select_nth_unstable_by(k, f32::total_cmp);
    *v
}

/// Writes the heatmap of `measure` over `heat` (`width × height`, row-major) to `path` as a
/// PNG; returns the value the top colour stands for and whether the legend has text.
pub fn write(
    path: &Path,
    heat: &[[f32; 3]],
    (width, height): (u32, u32),
    measure: Measure,
) -> Result<(f32, bool)> {
    let values: Vec<f32> = heat.iter().map(|h| h[measure.column()]).collect();
    write_values(path, values, (width, height), |v| measure.caption(v))
}

/// Writes `values` (`width × height`, row-major; non-finite ones drawn as 0) to `path` as a
/// PNG on the same scale and legend as a heatmap, `caption` giving the legend's caption and
/// the label of a value; returns the value the top colour stands for and whether the legend
/// has text. `--error-map` draws with it too.
pub fn write_values(
    path: &Path,
    values: Vec<f32>,
    (width, height): (u32, u32),
    caption: impl Fn(f32) -> (&'static str, String),
) -> Result<(f32, bool)> {
    let finite: Vec<f32> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let max = top(finite).max(f32::MIN_POSITIVE);
    let full = (width, height + LEGEND);
    let mut rgb = vec![0u8; 3 * full.0 as usize * full.1 as usize];
    for (i, v) in values.iter().enumerate() {
        rgb[3 * i..3 * i + 3].copy_from_slice(&colour(v / max));
    }
    let text = crate::io::font::font_ready();
    legend(&mut rgb, full, caption(max), text)
        .map_err(|e| Error::Usage(format!("drawing the picture's legend: {e}")))?;
    crate::io::image::write_rgb8_png(path, full.0, full.1, &rgb)?;
    Ok((max, text))
}

/// Draws the legend strip (a white band with the colour bar and, with `text`, its labels: the
/// caption and the top colour's value) at the bottom of `rgb`.
fn legend(
    rgb: &mut [u8],
    (w, h): (u32, u32),
    (caption, top): (&str, String),
    text: bool,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = BitMapBackend::with_buffer(rgb, (w, h)).into_drawing_area();
    let strip = root.margin(h - LEGEND, 0, 0, 0);
    strip.fill(&WHITE)?;
    let (x0, x1) = ((w / 10) as i32, (w - w / 10) as i32);
    let (y0, y1) = ((h - LEGEND + 6) as i32, (h - LEGEND + 22) as i32);
    for x in x0..x1 {
        let [r, g, b] = colour((x - x0) as f32 / (x1 - x0 - 1).max(1) as f32);
        root.draw(&Rectangle::new(
            [(x, y0), (x + 1, y1)],
            RGBColor(r, g, b).filled(),
        ))?;
    }
    if text {
        let style = (crate::io::font::FAMILY, 13).into_font().color(&BLACK);
        let y = y1 + 4;
        root.draw(&Text::new("0", (x0, y), style.clone()))?;
        let label = format!("≥ {top}");
        let (lw, _) = root.estimate_text_size(&label, &style)?;
        root.draw(&Text::new(label, (x1 - lw as i32, y), style.clone()))?;
        let (cw, _) = root.estimate_text_size(caption, &style)?;
        root.draw(&Text::new(
            caption,
            ((w as i32 - cw as i32) / 2, y + 14),
            style,
        ))?;
    }
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scale_runs_from_inferno_black_to_its_yellow_and_clamps() {
        assert_eq!(colour(0.0), [0, 0, 4]);
        assert_eq!(colour(1.0), [252, 255, 164]);
        assert_eq!(colour(0.5), [188, 55, 84]);
        assert_eq!(colour(7.0), colour(1.0));
        assert_eq!(colour(f32::NAN), colour(0.0));
        // Brightness (the sum of channels) rises along the scale.
        let sum = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
        let sums: Vec<u32> = (0..=20).map(|i| sum(colour(i as f32 / 20.0))).collect();
        assert!(sums.windows(2).all(|w| w[0] <= w[1]), "{sums:?}");
    }

    #[test]
    fn the_top_colour_stands_for_the_999th_permille() {
        let v: Vec<f32> = (0..10_000).map(|i| i as f32).collect();
        assert_eq!(top(v), 9989.0);
        assert_eq!(top(Vec::new()), 0.0);
    }
}
