//! `caustic photons` and `caustic merge`: what the processes of a farm share. The photon-map
//! file (`--save`), a photon pass in parts (`--part`, `--merge`), progressive passes
//! (`--save-passes`, `caustic merge`), and, without `--save`, the picture of the photons. The
//! files themselves are the integrator's (`crate::integrator::maps_file`,
//! `crate::integrator::passes_file`); this module checks the outputs and says what it wrote.

use super::report::Bar;
use super::settings::RenderJob;
use super::{MergeArgs, PhotonsArgs, check_out, job_with_settings, scene_inputs, set_threads};
use crate::camera::Camera;
use crate::desc::{RenderDesc, SceneDesc};
use crate::error::{Error, Result};
use crate::frame;
use crate::io::image::{Tonemap, write_image};
use crate::lua::run_script_with;
use crate::scene::build::build_scene;
use std::cell::Cell;
use std::path::PathBuf;
use std::rc::Rc;
use std::time::Instant;

/// Returns the fingerprint of a progressive render of `r` with `job`, as its pass files carry
/// it: the scene's hash, and the settings that shape its passes, without the range of passes
/// and the rules that stop them (which differ between the parts of one render).
pub(super) fn passes_fingerprint(
    desc: &SceneDesc,
    r: &RenderDesc,
    job: &RenderJob,
) -> Result<crate::integrator::maps_file::Fingerprint> {
    let mut s = job.settings.clone();
    if let Some(p) = s.progressive.as_mut() {
        (p.passes, p.first_pass, p.snapshot_every) = (0, 0, None);
        (p.target_error, p.time_budget) = (None, None);
    }
    (s.timing, s.heatmap, s.maps_file) = (false, false, None);
    Ok(crate::integrator::maps_file::Fingerprint {
        scene: crate::integrator::maps_file::scene_hash(desc, r)?,
        settings: format!(
            "caustic {}; scale {}; {s:?}",
            env!("CARGO_PKG_VERSION"),
            job.scale
        ),
    })
}

/// Writes the pass file `saved` to `path`.
pub(super) fn write_passes(
    path: &std::path::Path,
    saved: &crate::integrator::passes_file::SavedPasses,
) -> Result<()> {
    crate::integrator::passes_file::write(path, saved).map_err(|e| Error::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// Runs `caustic merge`: adds up the pass files and writes their mean (and, with
/// `--save-passes`, their sums), saying how many passes and the estimated error.
pub(super) fn merge_command(args: MergeArgs) -> Result<()> {
    let inputs: Vec<&std::path::Path> = args.parts.iter().map(PathBuf::as_path).collect();
    crate::io::image::output_format(&args.output)?;
    check_out(&args.output, &inputs)?;
    if let Some(p) = &args.save_passes {
        check_out(p, &inputs)?;
    }
    if args.parts.len() > crate::integrator::progressive::MAX_PASSES as usize {
        return Err(Error::Usage(
            "caustic merge: more files than passes a render has".into(),
        ));
    }
    let merged = crate::integrator::passes_file::merge(&args.parts)?;
    let sums = &merged.sums;
    write_image(&sums.mean(), &args.output, Tonemap::Clamp)?;
    if let Some(p) = &args.save_passes {
        write_passes(p, &merged)?;
    }
    let error = sums
        .estimated_error()
        .map_or("none".to_string(), |e| format!("{e:.4}"));
    eprintln!(
        "wrote {} (the mean of passes 0 to {} from {} files); estimated relative RMSE {error}",
        args.output.display(),
        sums.passes - 1,
        args.parts.len()
    );
    Ok(())
}

pub(super) fn photons_command(args: PhotonsArgs) -> Result<()> {
    let a = &args.render;
    super::settings::check_scale(a.scale)?;
    set_threads(a.threads)?;
    if a.photon_maps.is_some() {
        return Err(Error::Usage(
            "--photon-maps: caustic photons traces maps; it does not read them".into(),
        ));
    }
    // With --save the maps are the output; without it, the picture -o names.
    if let Some(out) = args.save.as_ref().or(a.output.as_ref()) {
        check_out(out, &[&a.scene])?;
    }
    let count = Rc::new(Cell::new(0u32));
    let counter = Rc::clone(&count);
    let job = RenderJob::from_args(a)?;
    let (argv, scene, output, save) = (
        a.argv.clone(),
        a.scene.clone(),
        a.output.clone(),
        args.save.clone(),
    );
    let (part, merge) = (args.part, args.merge.clone());
    let hook = Box::new(move |desc: &SceneDesc, r: &RenderDesc| -> Result<()> {
        counter.set(counter.get() + 1);
        let own = job_with_settings(&job, &argv, &scene, r)?;
        let job = own.as_ref().unwrap_or(&job);
        let mut inputs = scene_inputs(desc);
        inputs.push(&scene);
        if let Some(path) = &save {
            if counter.get() > 1 {
                return Err(Error::at(
                    &r.loc,
                    "this script renders more than one image, so --save cannot hold its maps",
                ));
            }
            let merged: Vec<&std::path::Path> = merge.iter().map(PathBuf::as_path).collect();
            inputs.extend(merged);
            check_out(path, &inputs)?;
            let what = match (part, merge.is_empty()) {
                (Some(p), _) => Save::Part(p),
                (None, false) => Save::Merge(merge.clone()),
                (None, true) => Save::Whole,
            };
            return save_maps((desc, r), job, path, &what);
        }
        let out = match &output {
            Some(o) if counter.get() == 1 => o.clone(),
            Some(_) => {
                return Err(Error::at(
                    &r.loc,
                    "this script renders more than one image, so -o cannot name its output",
                ));
            }
            None => {
                let stem = r
                    .output
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                r.output.with_file_name(format!("{stem}_photons.png"))
            }
        };
        crate::io::image::output_format(&out)?;
        check_out(&out, &inputs)?;
        let win = frame::window(r, job.scale, None)?;
        let size = (win.full_width, win.full_height);
        let scene = build_scene(desc, r)?;
        let caustics = crate::integrator::plan(&scene, crate::integrator::GiMode::On).caustics;
        frame::charge_photons(desc, r, &scene, &job.settings.photons, caustics)?;
        let camera = Camera::new(&r.camera, size.0, size.1);
        let bar = Bar::new(job.progress, &out);
        let (film, stats) = frame::photon_view(&scene, &camera, size, &job.settings.photons, &bar);
        bar.finish();
        write_image(&film, &out, Tonemap::Clamp)?;
        eprintln!(
            "wrote {} ({} global, {} caustic photons)",
            out.display(),
            stored(&stats.global),
            stored(&stats.caustic)
        );
        Ok(())
    });
    run_script_with(&a.scene, hook, a.script.options())?;
    Ok(())
}

/// Returns the photons stored over these lights' counts.
fn stored(counts: &[crate::photon::trace::LightCounts]) -> u64 {
    counts.iter().map(|c| c.stored).sum()
}

/// What `caustic photons --save` saves.
enum Save {
    /// The maps of the whole pass.
    Whole,
    /// One part of the pass, as traced (`--part`).
    Part(crate::photon::trace::Part),
    /// The maps the parts saved in these files make (`--merge`).
    Merge(Vec<PathBuf>),
}

/// Traces the photon maps that `caustic render` with `job` would trace for `r` (or the part,
/// or merges the parts, that `what` says) and writes them to `path` (`caustic photons --save`;
/// the caller has checked `path`).
fn save_maps(
    (desc, r): (&SceneDesc, &RenderDesc),
    job: &RenderJob,
    path: &std::path::Path,
    what: &Save,
) -> Result<()> {
    let start = Instant::now();
    let bar = Bar::new(job.progress, path);
    let traced = match what {
        Save::Whole => frame::trace_maps(desc, r, job.scale, &job.settings, &bar),
        Save::Part(part) => {
            let traced = frame::trace_part((desc, r), job.scale, &job.settings, *part, &bar);
            bar.finish();
            return write_part(path, traced?, start);
        }
        Save::Merge(files) => {
            let parts = read_parts(files)?;
            frame::merge_parts((desc, r), job.scale, &job.settings, parts, &bar)
        }
    };
    bar.finish();
    let (maps, stats) = traced?;
    if crate::interrupt::requested() {
        return Err(Error::Interrupted(
            "the photon maps were not written".into(),
        ));
    }
    crate::integrator::maps_file::write(path, &maps).map_err(|e| Error::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let bytes = std::fs::metadata(path).map_or(0, |m| m.len());
    let records = maps.cache.as_ref().map_or(0, |c| c.len());
    eprintln!(
        "wrote {} ({} global, {} caustic photons, {records} irradiance-cache records, {:.1} MB) in {:.2} s",
        path.display(),
        stored(&stats.global),
        stored(&stats.caustic),
        bytes as f64 / 1e6,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Writes the photon-pass part `part` to `path` and says so (`caustic photons --part`).
fn write_part(
    path: &std::path::Path,
    part: crate::integrator::maps_file::parts::SavedPart,
    start: Instant,
) -> Result<()> {
    if crate::interrupt::requested() {
        return Err(Error::Interrupted("the part was not written".into()));
    }
    crate::integrator::maps_file::parts::write(path, &part).map_err(|e| Error::File {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let caustic = part.caustic.as_ref().map_or(0, |c| c.len());
    eprintln!(
        "wrote {} (part {}/{}: {} global, {caustic} caustic photons) in {:.2} s",
        path.display(),
        part.part.index,
        part.part.count,
        part.global.len(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Reads the photon-pass parts `files` name (`caustic photons --merge`), or an error naming the
/// file that is not one.
fn read_parts(
    files: &[PathBuf],
) -> Result<Vec<(PathBuf, crate::integrator::maps_file::parts::SavedPart)>> {
    let most = crate::photon::trace::MAX_PARTS as usize;
    if files.len() > most {
        return Err(Error::Usage(format!(
            "--merge: {} parts, more than a pass is split into ({most})",
            files.len()
        )));
    }
    files
        .iter()
        .map(|f| {
            let part =
                crate::integrator::maps_file::parts::read(f).map_err(|message| Error::File {
                    path: f.clone(),
                    message,
                })?;
            Ok((f.clone(), part))
        })
        .collect()
}
