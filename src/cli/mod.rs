//! The command line: clap's arguments ([`args`]), turned into the library's settings
//! ([`settings`]), each command a call into the library ([`crate::frame`]), and what it prints
//! ([`report`]); `caustic study` is [`study`], and `caustic photons` and `caustic merge`, the
//! files a farm's processes share, are [`farm`]. No pass is wired here.

pub mod args;
mod farm;
pub mod report;
pub mod settings;
pub mod study;

use crate::desc::{RenderDesc, SceneDesc};
use crate::error::{Error, Result};
use crate::film::Film;
use crate::frame;
use crate::integrator::progressive::Stop;
use crate::io::image::{Tonemap, write_image, write_sample_map};
use crate::lua::{ScriptOptions, run_script_with};
use crate::metrics::Region;
use crate::render::Sampling;
use crate::scene::build::build_scene;
pub use args::*;
use clap::Parser;
use glam::Vec3A;
use report::Bar;
use settings::RenderJob;
use std::cell::Cell;
use std::path::PathBuf;
use std::rc::Rc;
use std::time::Instant;

/// Returns the job of one `gr.render` call when the scene's `gr.settings` (`r.settings`) change
/// `job`: them under the command line's words `argv` (or, without those, under `scene` alone).
fn job_with_settings(
    job: &RenderJob,
    argv: &[std::ffi::OsString],
    scene: &std::path::Path,
    r: &RenderDesc,
) -> Result<Option<RenderJob>> {
    if r.settings.is_empty() {
        return Ok(None);
    }
    let mut line: Vec<std::ffi::OsString> = r.settings.iter().map(Into::into).collect();
    if argv.is_empty() {
        line.push(scene.into());
    } else {
        line.extend(argv.iter().cloned());
    }
    let parsed = RenderLine::try_parse_from(&line).map_err(|e| {
        let text = e.to_string();
        let first = text
            .lines()
            .next()
            .unwrap_or("bad setting")
            .trim_start_matches("error: ");
        Error::at(&r.loc, format!("gr.settings: {first}"))
    })?;
    let mut with = RenderJob::from_args(&parsed.render)
        .map_err(|e| Error::at(&r.loc, format!("gr.settings: {e}")))?;
    // Counts the scene sets still follow the image; only the command line fixes them.
    with.settings.photons.follow_image = job.settings.photons.follow_image;
    // Likewise a time budget or target error moves what the scene sets, around what the
    // command line typed: the scene's counts are where its effort 1 stands.
    if let Some(request) = &mut with.settings.budget {
        (
            request.fixed_spp,
            request.fixed_photons,
            request.fixed_cache_rays,
        ) = job.typed;
    }
    Ok(Some(with))
}

/// Returns whether `path` names a glTF file, which caustic renders as a whole scene.
fn is_gltf(path: &std::path::Path) -> bool {
    crate::desc::MeshFormat::from_path(path) == Some(crate::desc::MeshFormat::Gltf)
}

/// Runs the scene at `path`, calling `hook` for each image it asks for: a Lua script, or a
/// glTF file read as a whole scene ([`crate::io::gltf::scene`]) viewed as `view` says, which
/// asks for one image. Returns the final description.
fn run_scene(
    path: &std::path::Path,
    mut hook: crate::lua::RenderHook,
    options: ScriptOptions,
    view: crate::io::gltf::scene::View,
) -> Result<SceneDesc> {
    if !is_gltf(path) {
        if view.camera.is_some() || view.size.is_some() {
            return Err(Error::Usage(format!(
                "--camera and --size choose a glTF scene's view; {} is a script, whose gr.render \
                 sets its own",
                path.display()
            )));
        }
        return run_script_with(path, hook, options);
    }
    let dir = path.parent().unwrap_or(std::path::Path::new(""));
    let folders = crate::lua::sandbox::Folders::new(dir, &options.allow_read);
    let mut desc = crate::io::gltf::scene::describe_scene(
        path,
        &view,
        options.budget_within(folders.read_scope()),
    )?;
    desc.missing_textures_warn = options.missing_textures_warn;
    for w in &desc.warnings {
        eprintln!("{}: warning: {w}", path.display());
    }
    let render = desc.renders[0].clone();
    hook(&desc, &render)?;
    Ok(desc)
}

/// Returns the description of the scene at `path` without rendering it: a script run with its
/// renders skipped, or a glTF file at its default view.
fn describe_scene(path: &std::path::Path, options: ScriptOptions) -> Result<SceneDesc> {
    let view = crate::io::gltf::scene::View {
        output: PathBuf::from(path.file_stem().unwrap_or_default()).with_extension("png"),
        ..Default::default()
    };
    run_scene(path, Box::new(|_, _| Ok(())), options, view)
}

/// Returns the view of a glTF scene the render flags choose, writing to `output` (else the
/// file's name with `.png`, in the working directory).
fn gltf_view(args: &RenderArgs) -> Result<crate::io::gltf::scene::View> {
    let size = match args.size.as_deref() {
        None => None,
        Some(&[w, h]) => {
            if w == 0 || h == 0 || u64::from(w) * u64::from(h) > crate::film::MAX_PIXELS {
                return Err(Error::Usage(format!(
                    "--size {w} {h}: each side at least 1 and at most {} pixels in all",
                    crate::film::MAX_PIXELS
                )));
            }
            Some((w, h))
        }
        Some(_) => return Err(Error::Usage("--size takes a width and a height".into())),
    };
    let output = args.output.clone().unwrap_or_else(|| {
        let stem = args.scene.file_stem().unwrap_or_default();
        PathBuf::from(stem).with_extension("png")
    });
    Ok(crate::io::gltf::scene::View {
        camera: args.camera.clone(),
        size,
        output,
    })
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(args) => render_command(args),
        Command::Info(args) => info_command(args),
        Command::Merge(args) => farm::merge_command(args),
        Command::Stitch(args) => {
            let tiles: Vec<&std::path::Path> = args.tiles.iter().map(PathBuf::as_path).collect();
            check_out(&args.output, &tiles)?;
            let s = crate::io::stitch::stitch(&args.tiles, &args.output)?;
            eprintln!(
                "wrote {} ({}x{} from {} tiles)",
                args.output.display(),
                s.width,
                s.height,
                s.tiles
            );
            Ok(())
        }
        Command::Photons(args) => farm::photons_command(args),
        Command::Diff(args) => diff_command(args),
        Command::ExportMitsuba(args) => export_command(args),
        Command::Study(args) => study::study_command(args),
    }
}

/// Starts the worker threads for the whole process (`--threads`, else one per core), with
/// stacks deep paths need, or returns a usage error when the count is out of range.
fn set_threads(n: Option<usize>) -> Result<()> {
    if let Some(n) = n
        && !(1..=MAX_THREADS).contains(&n)
    {
        return Err(Error::Usage(format!(
            "--threads must be in [1, {MAX_THREADS}], got {n:?}"
        )));
    }
    crate::accel::start_workers(n)
        .map(|_| ())
        .map_err(|e| Error::Usage(format!("cannot start the worker threads: {e}")))
}

/// Returns the window `--region x0,y0,x1,y1` names in a `width × height` image (the whole
/// image without one), or a usage error when it is not a non-empty window inside it.
fn parse_region(region: Option<&[u32]>, width: u32, height: u32) -> Result<Region> {
    match region {
        None => Ok(Region::full(width, height)),
        Some(&[x0, y0, x1, y1]) if x0 < x1 && y0 < y1 && x1 <= width && y1 <= height => {
            Ok(Region { x0, y0, x1, y1 })
        }
        Some(v) => Err(Error::Usage(format!(
            "--region {v:?} is not a non-empty window inside the {width}x{height} image"
        ))),
    }
}

/// Returns an error naming `path` when its image `img` has a NaN or infinite value in
/// `region`: how many such pixels, and the first.
pub(crate) fn check_finite(
    img: &crate::metrics::Image,
    path: &std::path::Path,
    region: Region,
) -> Result<()> {
    match img.non_finite(region) {
        None => Ok(()),
        Some((count, (x, y))) => Err(Error::File {
            path: path.to_path_buf(),
            message: format!(
                "{count} pixels are not finite (NaN or infinite), the first at ({x}, {y}): \
                 no error metric can be computed"
            ),
        }),
    }
}

/// Returns an error naming `out` when it cannot be written ([`crate::files::check_output`]: a
/// special file, a folder that does not exist or cannot be written to) or is the same file as
/// one of `inputs` ([`crate::files::check_not_input`]).
fn check_out(out: &std::path::Path, inputs: &[&std::path::Path]) -> Result<()> {
    crate::files::check_output(out)
        .and_then(|_| crate::files::check_not_input(out, inputs))
        .map_err(|message| Error::File {
            path: out.to_path_buf(),
            message,
        })
}

/// Returns the files `desc` names that a render reads: mesh files, textures and normal maps.
fn scene_inputs(desc: &SceneDesc) -> Vec<&std::path::Path> {
    let meshes = desc.meshes.iter().filter_map(|m| match &m.source {
        crate::desc::MeshSource::File { path, .. } => Some(path.as_path()),
        crate::desc::MeshSource::Inline { .. } => None,
    });
    let images = desc
        .materials
        .iter()
        .flat_map(|m| m.texture.iter().chain(&m.bump))
        .map(PathBuf::as_path);
    meshes.chain(images).collect()
}

/// Returns the command line's inputs of a command that runs `scene`: the script, and the
/// photon-map file `maps` when one is read.
fn script_inputs<'a>(
    scene: &'a std::path::Path,
    maps: Option<&'a PathBuf>,
) -> Vec<&'a std::path::Path> {
    std::iter::once(scene)
        .chain(maps.map(PathBuf::as_path))
        .collect()
}

fn render_command(args: RenderArgs) -> Result<()> {
    settings::check_scale(args.scale)?;
    if args.stats || args.heatmap.is_some() {
        crate::accel::counters::enable();
    }
    set_threads(args.threads)?;
    // The flags' own errors first, then the outputs, then the work.
    let job = RenderJob::from_args(&args)?;
    let view = gltf_view(&args)?;
    let inputs = script_inputs(&args.scene, args.photon_maps.as_ref());
    for out in args.output.iter().chain(&args.aa_map) {
        check_out(out, &inputs)?;
    }
    let rendered = Rc::new(Cell::new(0u32));
    let count = Rc::clone(&rendered);
    let output = args.output.clone();
    let (argv, scene) = (args.argv.clone(), args.scene.clone());
    let maps = args.photon_maps.clone();
    let hook = Box::new(move |desc: &SceneDesc, r: &RenderDesc| -> Result<()> {
        count.set(count.get() + 1);
        let out = match &output {
            None => {
                crate::lua::check_scene_output(&scene, &r.output)
                    .map_err(|m| Error::fault_at(crate::error::Fault::Sandbox, &r.loc, m))?;
                r.output.clone()
            }
            Some(o) if count.get() == 1 => o.clone(),
            Some(_) => {
                return Err(Error::at(
                    &r.loc,
                    "this script renders more than one image, so -o cannot name its output; run without -o",
                ));
            }
        };
        let mut inputs = script_inputs(&scene, maps.as_ref());
        inputs.extend(scene_inputs(desc));
        match job_with_settings(&job, &argv, &scene, r)? {
            Some(own) => render_one(desc, r, &own, &out, &inputs),
            None => render_one(desc, r, &job, &out, &inputs),
        }
    });
    // Ctrl-C stops the render and writes what it has (crate::interrupt), unless --no-partial.
    if !args.no_partial {
        crate::interrupt::catch_sigint();
    }
    let options = ScriptOptions {
        missing_textures_warn: args.missing_textures == MissingTextures::Warn,
        interruptible: !args.no_partial,
        ..args.script.options()
    };
    run_scene(&args.scene, hook, options, view)?;
    if crate::interrupt::requested() {
        // Ctrl-C came as the last image was being written, or after: nothing was lost, but
        // the exit status says the run was interrupted, as it always does.
        return Err(Error::Interrupted(
            "after the script's last image was written; nothing was lost".into(),
        ));
    }
    if rendered.get() == 0 {
        eprintln!(
            "warning: {} never called gr.render; no image written",
            args.scene.display()
        );
    }
    Ok(())
}

/// Returns an error unless every file a render of `out` with `job` may write (the image, the
/// ray-count map, the heatmap, the image of an interrupted render) has a format it can be
/// written in, can be written, is none of `inputs` and is no other of them: checked before the
/// render is spent.
fn check_render_outputs(
    job: &RenderJob,
    out: &std::path::Path,
    inputs: &[&std::path::Path],
) -> Result<()> {
    let format = crate::io::image::output_format(out)?;
    if job.crop.is_some()
        && !matches!(
            format,
            crate::io::image::Format::Png | crate::io::image::Format::Exr
        )
    {
        return Err(Error::Usage(format!(
            "--crop: {} cannot record the tile's place in the image; name it .png or .exr",
            out.display()
        )));
    }
    if let Some(map) = &job.aa_map
        && crate::io::image::output_format(map)? != crate::io::image::Format::Png
    {
        return Err(Error::Usage(format!(
            "--aa-map {} : the ray-count map is written as PNG; name it .png",
            map.display()
        )));
    }
    let heat = job.heatmap.map(|m| heatmap_path(out, m));
    let partial = crate::io::image::partial_path(out);
    let outputs: Vec<(&str, &std::path::Path)> = [
        ("the image", Some(out)),
        ("--aa-map", job.aa_map.as_deref()),
        ("--error-map", job.error_map.as_deref()),
        ("--save-passes", job.save_passes.as_deref()),
        ("--heatmap", heat.as_deref()),
        ("an interrupted render's image", Some(&partial)),
    ]
    .into_iter()
    .filter_map(|(what, path)| Some((what, path?)))
    .collect();
    for (i, &(what, path)) in outputs.iter().enumerate() {
        check_out(path, inputs)?;
        if let Some((other, _)) = outputs[..i].iter().find(|(_, p)| same_output(p, path)) {
            return Err(Error::Usage(format!(
                "{what} and {other} would both be written to {}: give each its own file",
                path.display()
            )));
        }
    }
    Ok(())
}

/// Returns whether two output paths name one file: the same absolute path, or (both existing)
/// the same file through links.
fn same_output(a: &std::path::Path, b: &std::path::Path) -> bool {
    let (Ok(x), Ok(y)) = (std::path::absolute(a), std::path::absolute(b)) else {
        return a == b;
    };
    x == y || crate::files::check_not_input(a, &[b]).is_err()
}

/// Renders and writes the image of one `gr.render` call; every file it may write is checked
/// first, against the command's `inputs` too.
fn render_one(
    desc: &SceneDesc,
    r: &RenderDesc,
    job: &RenderJob,
    out: &std::path::Path,
    inputs: &[&std::path::Path],
) -> Result<()> {
    check_render_outputs(job, out, inputs)?;
    let start = Instant::now();
    let bar = Bar::new(job.progress, out);
    let progress = report::Snapshots {
        bar: &bar,
        out,
        tonemap: job.tonemap,
    };
    let frame = frame::render_desc(desc, r, job.scale, job.crop, &job.settings, &progress);
    bar.finish();
    let frame = frame?;
    if let Some(partial) = frame.stats.interrupted {
        return Err(write_partial(&frame.film, partial, out, job.tonemap));
    }
    for note in &frame.stats.plan.notes {
        eprintln!("{note}");
    }
    for d in &frame.stats.plan.decisions {
        if matches!(d.why, crate::integrator::plan::Why::ForcedInVain(_)) {
            eprintln!("warning: {d}");
        }
    }
    // Never a silent loss: paths ended by the safety cap miss the light of longer paths.
    let capped = frame.stats.render.depth_capped;
    if capped > 0 {
        eprintln!(
            "warning: {capped} eye paths stopped at the {}-bounce cap; light that only longer \
             paths carry (many nested glass shells, facing mirrors) is missing from {}",
            crate::integrator::eye::MAX_PATH_DEPTH,
            out.display()
        );
    }
    write_image(&frame.film, out, job.tonemap)?;
    if let (Some(path), Some(p)) = (&job.save_passes, &frame.stats.progressive) {
        let saved = crate::integrator::passes_file::SavedPasses {
            fingerprint: farm::passes_fingerprint(desc, r, job)?,
            sums: p.sums.clone(),
        };
        farm::write_passes(path, &saved)?;
    }
    if let Some(map) = &job.aa_map {
        write_sample_map(&frame.film, map)?;
    }
    if let Some(errors) = &frame.stats.render.error {
        report_noise(&frame.film, errors, &job.settings.sampling);
        if let Some(map) = &job.error_map {
            write_error_map(&frame.film, errors, map)?;
        }
    }
    let traversal = crate::accel::counters::enabled().then(crate::accel::counters::collect);
    if let (Some(measure), Some(heat)) = (job.heatmap, &frame.stats.render.heat) {
        write_heatmap(out, measure, heat, frame.film.window.size())?;
    }
    let (fw, fh) = frame.film.window.size();
    eprintln!(
        "wrote {} ({fw}x{fh}) in {:.2} s",
        out.display(),
        start.elapsed().as_secs_f64()
    );
    if let Some(planned) = frame
        .stats
        .photons
        .as_ref()
        .and_then(|p| p.planned.as_ref())
    {
        eprintln!("planned {planned}");
    }
    if let Some(p) = &frame.stats.progressive {
        let error = p
            .estimated_error
            .map_or("not yet (one pass)".to_string(), |e| format!("{e:.4}"));
        let why = match p.stop {
            Stop::Passes => "the passes asked for",
            Stop::TargetError => "--target-error",
            Stop::TimeBudget => "--time-budget",
            Stop::Interrupted => "an interrupt",
        };
        eprintln!(
            "progressive: {} passes in {:.2} s, stopped by {why}; estimated relative RMSE {error}",
            p.passes,
            p.time.as_secs_f64()
        );
    }
    if job.stats {
        report::print_stats(&frame, r, out, traversal.as_ref());
    }
    Ok(())
}

/// Returns each pixel's relative error as adaptive pixels test it
/// ([`crate::render::noise::relative_error`]; 0 where the pixel has no estimate).
fn relative_errors(errors: &crate::stats::PixelErrors) -> Vec<f32> {
    use crate::render::noise::relative_error;
    errors
        .sample_error
        .iter()
        .map(|&e| match e.is_finite() {
            true => relative_error(e, errors.image_mean),
            false => 0.0,
        })
        .collect()
}

/// Prints the image's relative RMSE estimated from its pixels' half-buffers, and with
/// `--noise-target` how the samples went.
fn report_noise(film: &Film, errors: &crate::stats::PixelErrors, sampling: &Sampling) {
    let estimate = errors
        .relative_rmse(&film.pixels)
        .map_or("none (a black image)".to_string(), |e| format!("{e:.4}"));
    let lit = match errors.lit_pixels() {
        0 => String::new(),
        n => format!("; the {n} pixels that see a light directly left out"),
    };
    let mut line =
        format!("estimated relative RMSE {estimate} (from the pixels' half-buffers{lit})");
    if let Sampling::Noise {
        spp,
        max_spp,
        target,
    } = *sampling
    {
        let n = film.samples.len().max(1) as f64;
        let mean = film.samples.iter().map(|&s| s as f64).sum::<f64>() / n;
        let rel = relative_errors(errors);
        let above = rel.iter().filter(|&&e| e > target).count() as f64 / n;
        let capped = film.samples.iter().filter(|&&s| s >= max_spp).count() as f64 / n;
        line += &format!(
            "; adaptive pixels to {target}: {mean:.1} samples a pixel on average ({spp} to \
             {max_spp}), {:.1}% of pixels at --max-spp, {:.1}% above the target",
            100.0 * capped,
            100.0 * above
        );
    }
    eprintln!("{line}");
}

/// Writes each pixel's estimated relative error to `map`: a colour-scaled PNG with a legend,
/// or an EXR of the values (the same in all three channels).
fn write_error_map(
    film: &Film,
    errors: &crate::stats::PixelErrors,
    map: &std::path::Path,
) -> Result<()> {
    let rel = relative_errors(errors);
    let png = map
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if png {
        let caption = |v: f32| ("estimated relative error per pixel", format!("{v:.3}"));
        let (top, _) = crate::io::heatmap::write_values(map, rel, film.window.size(), caption)?;
        eprintln!("wrote {} (top colour: {top:.3} and above)", map.display());
    } else {
        let values = Film {
            pixels: rel.iter().map(|&e| Vec3A::splat(e)).collect(),
            ..film.clone()
        };
        write_image(&values, map, Tonemap::Clamp)?;
        eprintln!("wrote {}", map.display());
    }
    Ok(())
}

/// Returns where the heatmap of `measure` for the image `out` goes: `NAME.heat-MEASURE.png`
/// beside it.
fn heatmap_path(out: &std::path::Path, measure: crate::io::heatmap::Measure) -> std::path::PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned());
    let name = format!("{}.heat-{}.png", stem.unwrap_or_default(), measure.name());
    out.with_file_name(name)
}

/// Writes the heatmap of `measure` beside `out` as `NAME.heat-MEASURE.png` and says so.
fn write_heatmap(
    out: &std::path::Path,
    measure: crate::io::heatmap::Measure,
    heat: &[[f32; 3]],
    size: (u32, u32),
) -> Result<()> {
    let path = heatmap_path(out, measure);
    let (top, text) = crate::io::heatmap::write(&path, heat, size, measure)?;
    let unit = if measure == crate::io::heatmap::Measure::Time {
        format!("{:.1} µs", top / 1000.0)
    } else {
        format!("{top:.0}")
    };
    let legend = if text {
        ""
    } else {
        " (no font found: the legend has no labels)"
    };
    eprintln!(
        "wrote {} (top colour: {unit} {} per pixel and above){legend}",
        path.display(),
        measure.name()
    );
    Ok(())
}

/// Writes the film of an interrupted render of `out` beside it as `NAME.partial.EXT`, marked
/// with what it holds ([`crate::interrupt`]), and returns the error that ends the run saying
/// what was written; nothing is written when no pixel was rendered.
fn write_partial(
    film: &crate::film::Film,
    partial: crate::integrator::Partial,
    out: &std::path::Path,
    tonemap: Tonemap,
) -> Error {
    if partial.is_empty() {
        return Error::Interrupted(format!(
            "before any pixel of {} was rendered; nothing written",
            out.display()
        ));
    }
    let path = crate::io::image::partial_path(out);
    let note = format!("interrupted: {partial}");
    match crate::io::image::write_image_noted(film, &path, tonemap, Some(&note)) {
        Ok(()) => Error::Interrupted(format!("wrote {partial} to {}", path.display())),
        Err(e) => Error::Interrupted(format!("the image rendered so far was not written: {e}")),
    }
}

fn export_command(args: ExportArgs) -> Result<()> {
    settings::check_scale(args.scale)?;
    if !(1..=1 << 20).contains(&args.spp) {
        return Err(Error::Usage(format!(
            "--spp must be in [1, 1048576], got {}",
            args.spp
        )));
    }
    check_out(&args.output, &[&args.scene])?;
    let desc = describe_scene(&args.scene, args.script.options())?;
    let Some(r) = desc.renders.first() else {
        return Err(Error::Usage(format!(
            "{} never calls gr.render: nothing to export",
            args.scene.display()
        )));
    };
    let scene = build_scene(&desc, r)?;
    let mut inputs = scene_inputs(&desc);
    inputs.push(&args.scene);
    for out in crate::scene::mitsuba::outputs(&scene, &args.output) {
        check_out(&out, &inputs)?;
    }
    let win = frame::window(r, args.scale, None)?;
    let size = (win.full_width, win.full_height);
    crate::scene::mitsuba::export(&desc, r, &scene, size, args.spp, &args.output)?;
    eprintln!(
        "wrote {} ({}x{}, {} spp)",
        args.output.display(),
        size.0,
        size.1,
        args.spp
    );
    Ok(())
}

fn diff_command(args: DiffArgs) -> Result<()> {
    use crate::metrics::{Metrics, difference_image};
    if let Some(out) = &args.output {
        let inputs = [
            Some(&args.image),
            Some(&args.reference),
            args.second.as_ref(),
        ];
        let inputs: Vec<&std::path::Path> =
            inputs.into_iter().flatten().map(PathBuf::as_path).collect();
        check_out(out, &inputs)?;
    }
    let a = crate::io::image::read_rgb(&args.image)?;
    let r1 = crate::io::image::read_rgb(&args.reference)?;
    let r2 = match &args.second {
        Some(p) => crate::io::image::read_rgb(p)?,
        None => r1.clone(),
    };
    let second = args.second.as_ref().unwrap_or(&args.reference);
    for (img, path) in [(&r1, &args.reference), (&r2, second)] {
        if (img.width, img.height) != (a.width, a.height) {
            return Err(Error::Usage(format!(
                "{} is {}x{} but {} is {}x{}",
                args.image.display(),
                a.width,
                a.height,
                path.display(),
                img.width,
                img.height
            )));
        }
    }
    let region = parse_region(args.region.as_deref(), a.width, a.height)?;
    for (img, path) in [(&a, &args.image), (&r1, &args.reference), (&r2, second)] {
        check_finite(img, path, region)?;
    }
    let m = Metrics::against_two(&a, &r1, &r2, region);
    println!("mean ratio {:.5}", m.mean_ratio);
    println!("mean error {:+.5}", m.mean_error);
    println!("RMSE {:.6}", m.rmse);
    println!("relative RMSE {:.5}", m.rel_rmse);
    println!("block bias {:.5}", m.block_bias);
    if let Some(out) = &args.output {
        if !(args.gain.is_finite() && args.gain > 0.0) {
            return Err(Error::Usage("--gain must be positive".into()));
        }
        if crate::io::image::output_format(out)? != crate::io::image::Format::Png {
            return Err(Error::Usage(format!(
                "-o {}: the difference picture is written as PNG; name it .png",
                out.display()
            )));
        }
        let rgb = difference_image(&a, &r1, args.gain);
        crate::io::image::write_rgb8_png(out, a.width, a.height, &rgb)?;
    }
    Ok(())
}

fn info_command(args: InfoArgs) -> Result<()> {
    let desc = describe_scene(&args.scene, args.script.options())?;
    print!(
        "{}",
        report::describe(&args.scene.display().to_string(), &desc)?
    );
    if is_gltf(&args.scene) && !desc.warnings.is_empty() {
        println!("  what caustic ignores or stands in for:");
        for w in &desc.warnings {
            println!("    {w}");
        }
    }
    // The plan each render would follow at the default settings, or under the scene's own
    // gr.settings, with the photon budgets.
    for (i, r) in desc.renders.iter().enumerate() {
        let (settings, which) = if r.settings.is_empty() {
            (crate::integrator::Settings::default(), "default settings")
        } else {
            let base = RenderLine::try_parse_from([args.scene.as_os_str()])
                .map_err(|e| Error::Usage(e.to_string()))?;
            let job = RenderJob::from_args(&base.render)?;
            let scene_job = job_with_settings(&job, &[], &args.scene, r)?;
            let settings = scene_job.map_or(job.settings, |j| j.settings);
            (settings, "the scene's gr.settings")
        };
        let scene = build_scene(&desc, r)?;
        let plan = crate::integrator::plan::plan_for(&scene, &settings);
        println!("  plan of render {} ({which}):", i + 1);
        println!(
            "    camera medium: {}",
            report::camera_medium(&desc, &scene)
        );
        for line in plan.lines() {
            println!("    {line}");
        }
        if plan.integrator == crate::integrator::Integrator::PhotonMap {
            use crate::photon::trace::MapKind;
            for (name, kind, on) in [
                ("global", MapKind::Global, true),
                ("caustic", MapKind::Caustic, plan.caustics),
            ] {
                if on {
                    let budget = settings.photons.budget(&scene.lights, kind);
                    let total: u64 = budget.iter().sum();
                    println!("    {name} photons: {total} (per light: {budget:?})");
                }
            }
        }
    }
    Ok(())
}
