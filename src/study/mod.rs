//! Accuracy studies: what each setting buys, as error against a reference versus time
//! (`caustic study`). This module owns the data: the grid of settings ([`grid`]), the measured
//! rows, their summary per setting over seeds ([`summarise`]), the Pareto front, fitted
//! convergence slopes, and the CSV and Markdown they are written as; [`plot`] draws them. The
//! command line ([`crate::cli`]) renders each point through [`crate::frame`].
//!
//! A setting is a list of `caustic render` flags (`--photons 100000 --gather-rays 64`), so any
//! render flag can be swept. Each setting is rendered once per seed; the errors are the
//! [`crate::metrics`] ones, against the truth as estimated from two references when a second
//! is given. Over seeds, a setting's relative RMSE is the root of the mean squared error, and its
//! *seed-pair bias* is the block error between two seeds' images and the two references
//! ([`crate::metrics::pair_block_bias`]): noise drops out of it, the bias that more of the same
//! setting would not remove stays.
//!
//! ```text
//! caustic study scenes/validate/cornell_glass.lua --reference tools/validate/refs/cornell_glass.exr \
//!     --second tools/validate/refs/cornell_glass.second.exr \
//!     --sweep caustic-photons=2e5,2e6 --sweep gather-rays=4,16 --seeds 2 -o study/
//! ```

pub mod plot;

use crate::error::{Error, Result};
use std::fmt::Write;

/// Most settings one study may render (the product of the sweeps' lengths).
pub const MAX_POINTS: usize = 4096;

/// Most seeds per setting.
pub const MAX_SEEDS: u32 = 64;

/// One swept flag: `--sweep KEY=V1,V2,...`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    /// The render flag without its dashes (`photons`, `gather-rays`, `integrator`).
    pub key: String,
    pub values: Vec<String>,
}

impl Sweep {
    /// Parses `KEY=V1,V2,...`; numbers written like `1e5` become integers when they are whole.
    pub fn parse(s: &str) -> Result<Sweep> {
        let usage = |m: String| Error::Usage(format!("--sweep {s}: {m}"));
        let (key, values) = s
            .split_once('=')
            .ok_or_else(|| usage("expected KEY=V1,V2,...".into()))?;
        let key = key.trim().trim_start_matches("--").to_string();
        if key.is_empty() || !key.chars().all(|c| c.is_ascii_alphanumeric() || c == '-') {
            return Err(usage(format!("'{key}' is not a render flag name")));
        }
        let values: Vec<String> = values
            .split(',')
            .map(|v| normalise_number(v.trim()))
            .collect();
        if values.iter().any(String::is_empty) {
            return Err(usage("an empty value".into()));
        }
        Ok(Sweep { key, values })
    }
}

/// Returns `v` with a whole number in exponent form (`1e5`) written as an integer.
fn normalise_number(v: &str) -> String {
    match v.parse::<f64>() {
        Ok(x) if v.contains(['e', 'E']) && x.fract() == 0.0 && x.abs() < 1e18 => {
            format!("{}", x as i64)
        }
        _ => v.to_string(),
    }
}

/// One setting of a study: its swept values, in the order of the sweeps.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    pub index: usize,
    pub values: Vec<(String, String)>,
}

impl Point {
    /// Returns the render flags of this setting (`--key value` for each swept value).
    pub fn flags(&self) -> Vec<String> {
        self.values
            .iter()
            .flat_map(|(k, v)| [format!("--{k}"), v.clone()])
            .collect()
    }

    /// Returns the setting as text: `key=value` pairs joined by spaces.
    pub fn label(&self) -> String {
        let parts: Vec<String> = self
            .values
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        parts.join(" ")
    }

    /// Returns the label without the first sweep's value: the series the point belongs to (a
    /// curve along the first sweep in the plot).
    pub fn series(&self) -> String {
        let parts: Vec<String> = self.values[1.min(self.values.len())..]
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        parts.join(" ")
    }
}

/// Returns every combination of the sweeps' values (the first sweep varying slowest), or a
/// usage error when there are more than [`MAX_POINTS`].
pub fn grid(sweeps: &[Sweep]) -> Result<Vec<Point>> {
    let count = sweeps
        .iter()
        .try_fold(1usize, |n, s| n.checked_mul(s.values.len()))
        .filter(|&n| n <= MAX_POINTS)
        .ok_or_else(|| {
            Error::Usage(format!(
                "the sweeps make more than {MAX_POINTS} settings; sweep fewer values"
            ))
        })?;
    let mut points = Vec::with_capacity(count);
    for index in 0..count {
        let mut rest = index;
        let mut values = vec![(String::new(), String::new()); sweeps.len()];
        for (i, s) in sweeps.iter().enumerate().rev() {
            values[i] = (s.key.clone(), s.values[rest % s.values.len()].clone());
            rest /= s.values.len();
        }
        points.push(Point { index, values });
    }
    Ok(points)
}

/// One render of a study: a setting at a seed, its times and its errors.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub point: usize,
    pub seed: u64,
    /// The setting's label ([`Point::label`]).
    pub setting: String,
    /// CPU time of the process during the render (all threads), and wall time, in seconds.
    pub cpu_s: f64,
    pub wall_s: f64,
    pub metrics: crate::metrics::Metrics,
    /// The image written, relative to the study's folder.
    pub image: String,
}

/// The CSV header [`csv`] writes.
pub const CSV_HEADER: &str =
    "point,seed,setting,cpu_s,wall_s,mean_ratio,mean_error,rmse,rel_rmse,block_bias,image";

/// Returns the rows as CSV, one line per render, under [`CSV_HEADER`].
pub fn csv(rows: &[Row]) -> String {
    let mut s = format!("{CSV_HEADER}\n");
    for r in rows {
        let m = &r.metrics;
        let _ = writeln!(
            s,
            "{},{},\"{}\",{:.6},{:.6},{:.8},{:.8},{:.8},{:.8},{:.8},{}",
            r.point,
            r.seed,
            r.setting,
            r.cpu_s,
            r.wall_s,
            m.mean_ratio,
            m.mean_error,
            m.rmse,
            m.rel_rmse,
            m.block_bias,
            r.image
        );
    }
    s
}

/// A setting's results over its seeds.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    pub point: usize,
    pub setting: String,
    pub series: String,
    pub seeds: usize,
    /// Means over seeds.
    pub cpu_s: f64,
    pub wall_s: f64,
    pub mean_error: f64,
    /// Root of the mean over seeds of the squared relative RMSE and block error.
    pub rel_rmse: f64,
    pub block_bias: f64,
    /// Block error between two seeds' images (`None` with one seed).
    pub pair_bias: Option<f64>,
    /// Whether no other setting is both faster and more accurate.
    pub pareto: bool,
}

/// Returns one summary per point from `rows`, with `pair_bias[point]` from the caller (it needs
/// the images), and marks the Pareto front of CPU time against relative RMSE.
pub fn summarise(points: &[Point], rows: &[Row], pair_bias: &[Option<f64>]) -> Vec<Summary> {
    let mut out: Vec<Summary> = points
        .iter()
        .map(|p| {
            let mine: Vec<&Row> = rows.iter().filter(|r| r.point == p.index).collect();
            let n = mine.len().max(1) as f64;
            let mean = |f: &dyn Fn(&Row) -> f64| mine.iter().map(|r| f(r)).sum::<f64>() / n;
            Summary {
                point: p.index,
                setting: p.label(),
                series: p.series(),
                seeds: mine.len(),
                cpu_s: mean(&|r| r.cpu_s),
                wall_s: mean(&|r| r.wall_s),
                mean_error: mean(&|r| r.metrics.mean_error),
                rel_rmse: mean(&|r| r.metrics.rel_rmse.powi(2)).sqrt(),
                block_bias: mean(&|r| r.metrics.block_bias.powi(2)).sqrt(),
                pair_bias: pair_bias.get(p.index).copied().flatten(),
                pareto: false,
            }
        })
        .collect();
    mark_pareto(&mut out);
    out
}

/// Marks the summaries no other one dominates (at most the time and less error, or less time
/// and at most the error).
fn mark_pareto(s: &mut [Summary]) {
    for i in 0..s.len() {
        let (t, e) = (s[i].cpu_s, s[i].rel_rmse);
        s[i].pareto = e.is_finite()
            && !s
                .iter()
                .any(|o| (o.cpu_s <= t && o.rel_rmse < e) || (o.cpu_s < t && o.rel_rmse <= e));
    }
}

/// Returns the least-squares slope of `ln y` against `ln x` over the points with both positive,
/// or `None` with fewer than two such points or no spread in `x`.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// Returns each series' fitted slope of relative RMSE against CPU time (the convergence rate
/// along the first sweep), in the order the series first appear.
pub fn slopes(summaries: &[Summary]) -> Vec<(String, Option<f64>)> {
    let mut names: Vec<String> = Vec::new();
    for s in summaries {
        if !names.contains(&s.series) {
            names.push(s.series.clone());
        }
    }
    names
        .into_iter()
        .map(|name| {
            let pts: Vec<(f64, f64)> = summaries
                .iter()
                .filter(|s| s.series == name)
                .map(|s| (s.cpu_s, s.rel_rmse))
                .collect();
            (name, log_log_slope(&pts))
        })
        .collect()
}

/// A curve from another renderer or study to draw beside this one's (`--compare LABEL=FILE`).
#[derive(Clone, Debug, PartialEq)]
pub struct Curve {
    pub label: String,
    /// (CPU seconds, relative RMSE), in the file's order.
    pub points: Vec<(f64, f64)>,
}

impl Curve {
    /// Reads a CSV with a header naming at least `cpu_s` and `rel_rmse` columns (a study's own
    /// CSV, or one written by another renderer's harness); rows of the same `point`, when
    /// there is such a column, are averaged as [`summarise`] does.
    pub fn read(label: &str, path: &std::path::Path) -> Result<Curve> {
        let file_err = |message: String| Error::File {
            path: path.to_path_buf(),
            message,
        };
        let mut bytes = crate::files::read_regular(path).map_err(|e| file_err(e.to_string()))?;
        // Spreadsheets save "CSV UTF-8" with a byte-order mark, which would rename the first column.
        bytes.drain(..bytes.len() - crate::io::strip_bom(&bytes).len());
        let text = String::from_utf8(bytes).map_err(|_| file_err("not UTF-8 text".into()))?;
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
        let col = |name: &str| header.iter().position(|h| h.trim() == name);
        let (Some(cpu), Some(err)) = (col("cpu_s"), col("rel_rmse")) else {
            return Err(file_err(
                "the header has no cpu_s and rel_rmse columns".into(),
            ));
        };
        let point = col("point");
        let mut groups: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
        for (i, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
            let cells = split_csv(line);
            let num = |c: usize| {
                cells
                    .get(c)
                    .and_then(|v| v.trim().parse::<f64>().ok())
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        file_err(format!("line {}: no number in column {}", i + 2, c + 1))
                    })
            };
            let (t, e) = (num(cpu)?, num(err)?);
            let key = point
                .and_then(|c| cells.get(c).cloned())
                .unwrap_or(i.to_string());
            match groups.iter_mut().find(|g| g.0 == key) {
                Some(g) => g.1.push((t, e)),
                None => groups.push((key, vec![(t, e)])),
            }
            if groups.len() > MAX_POINTS {
                return Err(file_err(format!("more than {MAX_POINTS} points")));
            }
        }
        let points = groups
            .into_iter()
            .map(|(_, v)| {
                let n = v.len() as f64;
                let t = v.iter().map(|p| p.0).sum::<f64>() / n;
                let e = (v.iter().map(|p| p.1 * p.1).sum::<f64>() / n).sqrt();
                (t, e)
            })
            .collect();
        Ok(Curve {
            label: label.to_string(),
            points,
        })
    }
}

/// Splits one CSV line at commas outside double quotes, dropping the quotes.
fn split_csv(line: &str) -> Vec<String> {
    let (mut cells, mut cell, mut quoted) = (Vec::new(), String::new(), false);
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ',' if !quoted => cells.push(std::mem::take(&mut cell)),
            c => cell.push(c),
        }
    }
    cells.push(cell);
    cells
}

/// Returns the study as Markdown: what was rendered, one table row per setting (Pareto
/// settings in bold), the fitted slopes and the curves compared.
pub fn markdown(
    title: &str,
    summaries: &[Summary],
    curves: &[Curve],
    plot: Option<&str>,
) -> String {
    let mut s = format!("## {title}\n\n");
    if let Some(p) = plot {
        let _ = writeln!(s, "![error against time]({p})\n");
    }
    s.push_str("| setting | seeds | CPU s | wall s | rel. RMSE | mean error | block error | seed-pair bias | Pareto |\n");
    s.push_str("|---|---|---|---|---|---|---|---|---|\n");
    for m in summaries {
        let bias = m.pair_bias.map_or("–".to_string(), |b| format!("{b:.4}"));
        let star = if m.pareto { "yes" } else { "" };
        let name = if m.pareto {
            format!("**{}**", m.setting)
        } else {
            m.setting.clone()
        };
        let _ = writeln!(
            s,
            "| {name} | {} | {:.2} | {:.2} | {:.4} | {:+.4} | {:.4} | {bias} | {star} |",
            m.seeds, m.cpu_s, m.wall_s, m.rel_rmse, m.mean_error, m.block_bias
        );
    }
    s.push_str("\nFitted slope of relative RMSE against CPU time, along the first sweep:\n\n");
    for (series, slope) in slopes(summaries) {
        let name = if series.is_empty() { "all" } else { &series };
        let slope = slope.map_or("–".to_string(), |v| format!("{v:.3}"));
        let _ = writeln!(s, "- {name}: {slope}");
    }
    for c in curves {
        let slope = log_log_slope(&c.points).map_or("–".to_string(), |v| format!("{v:.3}"));
        let pts: Vec<String> = c
            .points
            .iter()
            .map(|(t, e)| format!("{t:.2} s: {e:.4}"))
            .collect();
        let _ = writeln!(
            s,
            "- compared, {}: slope {slope} ({})",
            c.label,
            pts.join(", ")
        );
    }
    s
}
