//! The study's picture: relative RMSE against CPU time on log-log axes, one curve per series
//! (points along the first sweep), the compared curves dashed, the Pareto front drawn over
//! them, as a PNG drawn with `plotters`.
//!
//! Text needs a font file, found at run time ([`crate::io::font`]). Without one the plot is
//! drawn without text (and [`draw`] says so): the Markdown table carries the numbers either
//! way.

use super::{Curve, Summary};
use crate::error::{Error, Result};
use crate::io::font::{FAMILY, font_ready};
use plotters::prelude::*;
use std::path::Path;

/// Size of the picture in pixels.
const SIZE: (u32, u32) = (900, 600);

/// Draws the study's summaries and the compared curves to `out` (PNG); returns whether the
/// picture has text (a font was found).
pub fn draw(title: &str, summaries: &[Summary], curves: &[Curve], out: &Path) -> Result<bool> {
    let text = font_ready();
    let (w, h) = SIZE;
    let mut buf = vec![255u8; (w * h * 3) as usize];
    draw_into(&mut buf, title, summaries, curves, text).map_err(|e| Error::File {
        path: out.to_path_buf(),
        message: format!("cannot draw the plot: {e}"),
    })?;
    crate::io::image::write_rgb8_png(out, w, h, &buf)?;
    Ok(text)
}

/// Returns the axis range covering `values` (positive ones) with a margin, in log space.
fn range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values
        .filter(|v| *v > 0.0 && v.is_finite())
        .fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
    if lo > hi {
        return 0.01..1.0;
    }
    let (lo, hi) = if hi / lo < 1.5 {
        (lo / 1.5, hi * 1.5)
    } else {
        (lo, hi)
    };
    lo / 1.25..hi * 1.25
}

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// Draws the picture into the RGB buffer `buf` ([`SIZE`]), with its text when `text`.
/// Long: one chart drawn layer by layer (axes, the study's series, the compared curves, the
/// Pareto front, the legend), each layer a few calls on the same `plotters` chart, whose
/// generic type would make a function per layer longer than the layer.
fn draw_into(
    buf: &mut [u8],
    title: &str,
    summaries: &[Summary],
    curves: &[Curve],
    text: bool,
) -> DrawResult {
    let root = BitMapBackend::with_buffer(buf, SIZE).into_drawing_area();
    root.fill(&WHITE)?;
    let times = summaries
        .iter()
        .map(|s| s.cpu_s)
        .chain(curves.iter().flat_map(|c| c.points.iter().map(|p| p.0)));
    let errors = summaries
        .iter()
        .map(|s| s.rel_rmse)
        .chain(curves.iter().flat_map(|c| c.points.iter().map(|p| p.1)));
    let (x, y) = (range(times), range(errors));
    let mut builder = ChartBuilder::on(&root);
    builder.margin(20);
    if text {
        builder
            .caption(title, (FAMILY, 22))
            .x_label_area_size(45)
            .y_label_area_size(70);
    }
    let mut chart = builder.build_cartesian_2d(x.log_scale(), y.log_scale())?;
    let mut mesh = chart.configure_mesh();
    if text {
        mesh.x_desc("CPU time (s)")
            .y_desc("relative RMSE")
            .x_labels(10)
            .y_labels(10)
            .x_label_formatter(&|v| format!("{v:.3}"))
            .y_label_formatter(&|v| format!("{v:.3}"))
            .label_style((FAMILY, 15))
            .axis_desc_style((FAMILY, 17));
    } else {
        mesh.x_labels(0).y_labels(0);
    }
    mesh.draw()?;
    let mut series: Vec<&str> = Vec::new();
    for s in summaries {
        if !series.contains(&s.series.as_str()) {
            series.push(&s.series);
        }
    }
    for (i, name) in series.iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        let pts: Vec<(f64, f64)> = summaries
            .iter()
            .filter(|s| s.series == *name && s.rel_rmse > 0.0)
            .map(|s| (s.cpu_s, s.rel_rmse))
            .collect();
        let label = if name.is_empty() { "caustic" } else { name };
        let line = chart.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))?;
        if text {
            line.label(label).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        }
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, colour.filled())))?;
    }
    for (i, c) in curves.iter().enumerate() {
        let colour = Palette99::pick(series.len() + i).to_rgba();
        let pts: Vec<(f64, f64)> = c.points.iter().copied().filter(|p| p.1 > 0.0).collect();
        let line = chart.draw_series(DashedLineSeries::new(
            pts.clone(),
            8,
            5,
            colour.stroke_width(2),
        ))?;
        if text {
            let label = c.label.clone();
            line.label(label).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        }
        chart.draw_series(
            pts.iter()
                .map(|&p| Cross::new(p, 5, colour.stroke_width(2))),
        )?;
    }
    let mut front: Vec<(f64, f64)> = summaries
        .iter()
        .filter(|s| s.pareto)
        .map(|s| (s.cpu_s, s.rel_rmse))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    let line = chart.draw_series(LineSeries::new(front.clone(), BLACK.stroke_width(1)))?;
    if text {
        line.label("Pareto front")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(1)));
    }
    chart.draw_series(
        front
            .iter()
            .map(|&p| Circle::new(p, 7, BLACK.stroke_width(2))),
    )?;
    if text {
        chart
            .configure_series_labels()
            .label_font((FAMILY, 14))
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()?;
    }
    root.present()?;
    Ok(())
}
