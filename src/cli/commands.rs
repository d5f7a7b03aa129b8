//! What each subcommand does: turn parsed arguments into the library's typed options, call the
//! library, report (text on stderr, `--json` on stdout).
use std::path::Path;

use serde_json::json;

use coif::generate::{generate, GenerateParams, Style};
use coif::info::GroomInfo;
use coif::io;
use coif::progress::Progress;
use coif::validate::shortest;
use coif::{Error, Result};

use super::args::*;

pub(crate) fn run(cli: Cli) -> Result<()> {
    if let Some(size) = &cli.max_memory {
        coif::limits::set_max_memory(coif::limits::parse_size(size)?);
    }
    coif::limits::set_max_steps(cli.max_steps);
    match cli.command {
        Command::Generate(args) => run_generate(args),
        Command::Info { file, import, json } => {
            let loaded = io::read_groom_selected(&file, &import.options(&file)?, &import.selection())?;
            let info = GroomInfo::of(&loaded.groom);
            let timeline = io::timeline::read_timeline(&file)?;
            for warning in &loaded.warnings {
                eprintln!("coif: warning: {warning}");
            }
            if json {
                let frames = timeline.map(|t| frames_json(&t));
                let warnings = &loaded.warnings;
                print_json(
                    json!({ "path": file, "format": loaded.format, "frames": frames, "groom": info, "warnings": warnings }),
                );
            } else {
                let frames = match timeline {
                    Some(t) => format!(
                        "frames       {} to {} ({} frames at {} fps)\n",
                        shortest(t.first),
                        shortest(t.frame(t.frame_count() - 1)),
                        t.frame_count(),
                        shortest(t.frames_per_second)
                    ),
                    // A moving stage without a frame range is one moment too: its warning says so.
                    None if loaded.warnings.is_empty() => {
                        "frames       one moment (not animated)\n".to_string()
                    }
                    None => "frames       one moment (see the warning)\n".to_string(),
                };
                print_stdout(&format!("{} ({})\n{frames}{info}", file.display(), loaded.format.name()));
            }
            Ok(())
        }
        Command::Convert { input, output, import, json, unreal, frame_range } => {
            run_convert(&input, &output, &import, json, &io::ExportOptions { unreal }, frame_range.as_deref())
        }
        Command::Simulate(args) => run_simulate(args),
        Command::Style(args) => run_style(args),
        Command::Render(args) => run_render(*args),
        Command::Batch { manifest, jobs, task, json } => run_batch(&manifest, jobs, task, json),
        Command::Farm { action } => run_farm(action),
    }
}

fn run_style(args: StyleArgs) -> Result<()> {
    super::checks::style(&args)?;
    let mut recipe = coif::style::recipe::load(&args.recipe)?;
    if let Some(count) = args.guides {
        // --guides N replaces the recipe's count or fraction; its reach stays.
        let reach = recipe.guides.and_then(|g| g.reach);
        recipe.guides = Some(coif::guides::GuideSpec { count: Some(count), fraction: None, reach });
    }
    let export = io::ExportOptions { unreal: args.unreal };
    io::check_output(&args.output, &export)?;
    // In range: checked with the other flags.
    let frames_per_second = args.frames.unwrap_or(0.0);
    if frames_per_second > 0.0 {
        io::check_animated_output(&args.output)?;
    }
    let loaded =
        io::read_groom_selected(&args.groom, &args.import.options(&args.groom)?, &args.import.selection())?;
    let others = [("the recipe", Some(&args.recipe)), ("--scalp", args.scalp.as_ref())];
    super::checks::nothing_read_is_written(&args.output, &loaded, &export, &others)?;
    let progress = args.progress.mode(args.quiet, args.json);
    let scalp = match &args.scalp {
        Some(path) => {
            let (points, triangles) = coif::io::obj::read_triangles(path)?;
            Some(std::sync::Arc::new(coif::interact::mesh_sdf::TriangleMesh { points, triangles }))
        }
        None => None,
    };
    let options = coif::style::StyleOptions { progress, frames_per_second, scalp };
    let styled = if args.groups.is_empty() {
        coif::style::style(&loaded.groom, &recipe, &options)
    } else {
        style_groups(&args.groom, &loaded.groom, &args.groups, &recipe, &options)
    }
    .map_err(|e| match (e, &args.scalp) {
        (e @ Error::Groom(coif::groom::GroomError::ScalpNotFitted), Some(scalp)) => e.in_file(scalp),
        (e, _) => e.in_file(&args.groom).read_at_units("--units", args.import.units),
    })?;
    let (groom, report) = (&styled.groom, &styled.report);
    let warnings = io::write_animated(
        &args.output,
        groom,
        &styled.frames,
        &styled.frame_attributes,
        frames_per_second,
        &export,
    )?;
    let meshes_output = io::meshes_output(&args.output, groom, &export);
    let warnings: Vec<String> =
        loaded.warnings.iter().chain(&report.warnings).cloned().chain(warnings).collect();
    for warning in &warnings {
        eprintln!("coif: warning: {warning}");
    }
    report_meshes_output(meshes_output.as_deref());
    let unsettled = report.unconverged_settle();
    if let Some(failure) = unsettled.as_ref().filter(|_| !args.require_converged) {
        eprintln!("coif: warning: {failure}");
    }
    if args.json {
        print_json(json!({
            "output": args.output,
            "meshes_output": meshes_output,
            "report": report,
            "warnings": warnings
        }));
    } else {
        for stage in &report.stages {
            // No median curl: the strands are straight (or too short to tell).
            let cm = |radius: Option<f32>| {
                radius.map_or("straight".to_string(), |r| format!("{:.2} cm", r * 100.0))
            };
            let (curl, rest_curl) = (cm(stage.curl_radius), cm(stage.rest_curl_radius));
            let b = &stage.bond_rates;
            eprintln!(
                "{:>2} {:<10} {:>6.2} s {:>6} steps {:>7.2} s wall  curl {curl:>9} (rest {rest_curl:>8})  bonds H {:.2} I {:.2} S {:.2} P {:.2}  wet {:.2}",
                stage.index + 1,
                stage.kind,
                stage.seconds,
                stage.steps,
                stage.wall_seconds,
                b.hydrogen,
                b.ionic,
                b.disulfide,
                b.peptide,
                stage.wetness
            );
        }
        eprintln!("wrote {}", args.output.display());
    }
    match unsettled {
        Some(failure) if args.require_converged => Err(Error::NotConverged(failure)),
        _ => Ok(()),
    }
}

/// Styles the groups named by `--group` and puts them back among the untouched ones (frames
/// too: the other groups stand still in every frame, with their own attribute values). A name
/// the groom read from `path` has no group of is refused naming the file.
fn style_groups(
    path: &Path,
    groom: &coif::Groom,
    names: &[String],
    recipe: &coif::style::recipe::Recipe,
    options: &coif::style::StyleOptions,
) -> Result<coif::style::Styled> {
    let (selected, selection) = groom.select_groups(names).map_err(|message| Error::format(path, message))?;
    let mut styled = coif::style::style_part(groom, &selected, recipe, options)?;
    let merged = groom.merge_back(&selection, &styled.groom)?;
    let mut frame = styled.groom.clone();
    let frame_attributes = std::mem::take(&mut styled.frame_attributes);
    for (k, points) in std::mem::take(&mut styled.frames).into_iter().enumerate() {
        frame.points = points;
        let attributes = frame_attributes.get(k);
        for attribute in attributes.into_iter().flatten() {
            frame.set_attribute(attribute.clone());
        }
        let whole = groom.merge_back(&selection, &frame)?;
        if let Some(attributes) = attributes {
            let merged_attributes =
                attributes.iter().filter_map(|a| whole.attribute(&a.name).cloned()).collect();
            styled.frame_attributes.push(merged_attributes);
        }
        styled.frames.push(whole.points);
    }
    styled.groom = merged;
    Ok(styled)
}

fn run_simulate(args: SimulateArgs) -> Result<()> {
    use coif::sim::driver::{simulate, SimulateOptions};
    use coif::sim::{BondInfluences, SettleOptions, SimParams};
    super::checks::simulate(&args)?;
    io::check_output(&args.output, &io::ExportOptions::default())?;
    let loaded =
        io::read_groom_selected(&args.input, &args.import.options(&args.input)?, &args.import.selection())?;
    super::checks::nothing_read_is_written(&args.output, &loaded, &io::ExportOptions::default(), &[])?;
    let defaults = SimParams::for_solver(args.solver.into());
    let params = SimParams {
        dt: args.dt,
        iterations: args.iterations,
        gravity: glam::Vec3::new(0.0, -args.gravity, 0.0),
        damping: args.damping,
        influences: BondInfluences([
            args.influences[0],
            args.influences[1],
            args.influences[2],
            args.influences[3],
        ]),
        material: coif::sim::Material { youngs_modulus: args.youngs_modulus, ..defaults.material },
        ..defaults
    };
    let seconds = args.seconds as f64 + if args.settle { args.settle_seconds as f64 } else { 0.0 };
    coif::limits::check_simulation(
        &format!(
            "simulating {} vertices for {} s",
            loaded.groom.vertex_count(),
            coif::validate::seconds_text(seconds)
        ),
        loaded.groom.vertex_count() as f64,
        0.0,
        coif::limits::steps_for(seconds, params.dt.into()),
        params.iterations.max(args.settle_iterations.unwrap_or(0)).into(),
    )?;
    let settle = args.settle.then_some(SettleOptions {
        tolerance: args.settle_tolerance,
        max_seconds: args.settle_seconds,
        iterations: args.settle_iterations,
    });
    let head = coif::head::Head::default();
    let colliders = if args.head {
        vec![coif::interact::obstacles::Shape::Ellipsoid {
            center: head.center,
            radii: head.radii,
            rotation: glam::Quat::IDENTITY,
        }]
    } else {
        Vec::new()
    };
    let hair_contacts =
        args.hair_contacts.then(|| coif::style::recipe::Contacts::default().hair_contact_settings());
    let options = SimulateOptions {
        params,
        seconds: args.seconds,
        settle,
        sag_free: args.sag_free,
        colliders,
        hair_contacts,
    };
    let (groom, summary) = simulate(&loaded.groom, &options)
        .map_err(|e| e.in_file(&args.input).read_at_units("--units", args.import.units))?;
    let unsettled = summary.settle.and_then(|settle| settle.shortfall());
    for warning in loaded.warnings.iter().chain(&summary.warnings) {
        eprintln!("coif: warning: {warning}");
    }
    if let Some(shortfall) = unsettled.as_ref().filter(|_| !args.require_converged) {
        eprintln!("coif: warning: {shortfall}");
    }
    if args.json {
        // All of them, as `style --json` gives them (the simulation's were only under `simulation`).
        let warnings: Vec<String> = loaded
            .warnings
            .iter()
            .chain(&summary.warnings)
            .cloned()
            .chain(io::write_groom(&args.output, &groom)?)
            .collect();
        print_json(
            json!({ "output": args.output, "simulation": summary, "groom": GroomInfo::of(&groom), "warnings": warnings }),
        );
    } else {
        eprintln!("simulated {} steps ({} s)", summary.steps, summary.seconds);
        if let Some(settle) = &summary.settle {
            eprintln!(
                "settle: {} after {:.2} s, force residual {:.2e}, torque residual {:.2e}",
                if settle.converged { "converged" } else { "not converged" },
                settle.seconds,
                settle.force_residual,
                settle.torque_residual
            );
        }
        write_and_report(&args.output, &groom, &[], false, &io::ExportOptions::default())?;
    }
    match unsettled {
        Some(shortfall) if args.require_converged => Err(Error::NotConverged(shortfall)),
        _ => Ok(()),
    }
}

fn run_render(args: RenderArgs) -> Result<()> {
    use coif::render::{self, integrator::Mode, light::Environment, sampler::SamplerKind};
    super::checks::render(&args)?;
    // Fail on a bad output name before reading or rendering anything.
    render::image::ImageFormat::from_path(&args.output)?;
    io::check_output_directory(&args.output)?;
    let (width, height) = render::parse_resolution(&args.res)?;
    coif::limits::check_render(width, height, args.spp, args.time_budget.is_some())?;
    // Checked whatever the mode: `--range nan,1` with `--mode depth` was dropped without a word.
    let range = args.range.as_deref().map(render::parse_range).transpose()?;
    let mode = match (args.mode, &args.attribute) {
        (RenderMode::Beauty | RenderMode::Attribute, Some(name)) => {
            Mode::Attribute { name: name.clone(), range }
        }
        (RenderMode::Attribute, None) => {
            return Err(Error::Usage("--mode attribute needs --attribute NAME".into()))
        }
        (RenderMode::Beauty, None) => Mode::Beauty,
        (RenderMode::Tangent, _) => Mode::Tangent,
        (RenderMode::Depth, _) => Mode::Depth,
    };
    // In range: checked with the other flags.
    let time_budget = args.time_budget.map(std::time::Duration::from_secs_f64);
    let mut settings = render::RenderSettings {
        width,
        height,
        spp: args.spp,
        view: args.view.into(),
        camera: args.camera.as_deref().map(str::parse).transpose()?,
        fov_degrees: args.fov,
        mode,
        max_depth: args.max_depth,
        sampler: match args.sampler {
            SamplerName::Sobol => SamplerKind::Sobol,
            SamplerName::Independent => SamplerKind::Independent,
        },
        seed: args.seed,
        exposure: args.exposure,
        time_budget,
        aovs: render::parse_aovs(&args.aov)?,
        ..Default::default()
    };
    settings.scene.head = args.head.into();
    settings.scene.floor = !args.no_floor;
    settings.scene.width_scale = args.width_scale;
    settings.scene.min_pixel_width = args.min_pixel_width;
    settings.scene.color = args.color.as_deref().map(|c| render::parse_vec3(c, "--color")).transpose()?;
    settings.lobe = match args.lobe {
        LobeArg::Chiang => render::integrator::Lobe::Chiang,
        LobeArg::KajiyaKay => render::integrator::Lobe::KajiyaKay,
    };
    settings.chiang =
        render::hair_bsdf::ChiangParams::new(args.roughness, args.azimuthal_roughness, args.cuticle_tilt);
    if args.melanin.is_some() || args.pheomelanin.is_some() {
        settings.scene.melanin = Some([args.melanin.unwrap_or(0.0), args.pheomelanin.unwrap_or(0.0)]);
    }
    settings.key.direction =
        args.light_dir.as_deref().map(|d| render::parse_vec3(d, "--light-dir")).transpose()?;
    settings.key.irradiance *= args.light_intensity;
    // The shot first; flags given explicitly override its parts.
    if let Some(scene) = &args.scene {
        let shot =
            render::shot::Shot::load(scene, args.scene_camera.as_deref(), width as f32 / height as f32)?;
        if shot.lights.is_some() && args.light_dir.is_some() {
            return Err(Error::Usage(format!(
                "--light-dir moves the default key light, but {} gives the lights",
                scene.display()
            )));
        }
        shot.apply(&mut settings);
        if let Some(camera) = &args.camera {
            settings.camera = Some(camera.parse()?);
        }
        if args.no_floor {
            settings.scene.floor = false;
        }
    } else if args.scene_camera.is_some() {
        return Err(Error::Usage("--scene-camera needs --scene".into()));
    }
    if let Some(radiance) = args.environment {
        settings.environment = Environment::Constant(glam::Vec3::splat(radiance));
    }
    settings.scene.floor_height = args.floor_height.or(settings.scene.floor_height);
    settings.scene.floor_size = args.floor_size.or(settings.scene.floor_size);
    if let Some(albedo) = &args.floor_albedo {
        settings.scene.floor_albedo = render::parse_vec3(albedo, "--floor-albedo")?;
    }

    let loaded =
        io::read_groom_selected(&args.input, &args.import.options(&args.input)?, &args.import.selection())?;
    for warning in &loaded.warnings {
        eprintln!("coif: warning: {warning}");
    }
    let progress = Progress::new(args.progress.mode(args.quiet, false), "render", 1);
    let report = |done: u64, total: u64| {
        progress.set_total(total);
        progress.set_done(done);
    };
    let rendered = render::with_threads(args.threads, || render::render(&loaded.groom, &settings, &report))?
        .map_err(|e| e.in_file(&args.input))?;
    progress.finish();
    rendered.image.write(&args.output)?;
    let stats = rendered.stats;
    if args.json {
        print_json(json!({ "output": args.output, "width": width, "height": height, "stats": stats }));
    } else {
        eprintln!(
            "wrote {} ({width}x{height}, {} spp, {:.1} s, {:.2} Mrays/s)",
            args.output.display(),
            stats.spp,
            stats.seconds,
            stats.rays as f64 / stats.seconds.max(1e-9) / 1e6
        );
    }
    Ok(())
}

fn run_batch(manifest_path: &Path, jobs: usize, task: Option<usize>, json: bool) -> Result<()> {
    use coif::batch::{local, manifest, task as batch_task};
    local::check_jobs(jobs)?;
    let manifest = manifest::load(manifest_path)?;
    if let Some(index) = task {
        let task = manifest.tasks.get(index).ok_or_else(|| {
            Error::Usage(format!(
                "{}: no task {index}; the manifest has {}",
                manifest_path.display(),
                manifest.tasks.len()
            ))
        })?;
        let outcome = batch_task::run(task)?;
        print_json(json!({ "index": index, "task": task.name, "outcome": outcome }));
        return Ok(());
    }
    let coif = std::env::current_exe()
        .map_err(|e| Error::External(format!("cannot find the coif executable: {e}")))?;
    let mut report = local::run(&manifest, &coif, jobs)?;
    // The tasks' report is printed before a failed sheet is reported: they ran.
    let sheet = local::make_contact_sheet(&manifest, &mut report);
    if json {
        print_json(json!(report));
    } else {
        for t in &report.tasks {
            eprintln!(
                "{:>4} {:<24} {:<8} {:>7.1} s  {}",
                t.index,
                t.name,
                t.status,
                t.seconds,
                t.log.display()
            );
        }
        eprintln!(
            "{} done, {} skipped, {} failed in {:.1} s",
            report.done, report.skipped, report.failed, report.seconds
        );
    }
    sheet?;
    match report.exit_code() {
        0 => Ok(()),
        2 => Err(Error::Usage(format!(
            "{} of {} tasks had bad input; see their logs",
            report.failed,
            report.tasks.len()
        ))),
        _ => Err(Error::External(format!(
            "{} of {} tasks failed; see their logs",
            report.failed,
            report.tasks.len()
        ))),
    }
}

fn run_farm(action: FarmAction) -> Result<()> {
    use coif::batch::{manifest, slurm, task as batch_task};
    match action {
        FarmAction::Submit {
            manifest: path,
            scheduler: Scheduler::Slurm,
            partition,
            cpus,
            max_parallel,
            dry_run,
            json,
        } => {
            let manifest = manifest::load(&path)?;
            batch_task::check_overrides(&manifest)?;
            let absolute = std::path::absolute(&path).map_err(|e| Error::io(&path, e))?;
            let coif = std::env::current_exe()
                .map_err(|e| Error::External(format!("cannot find the coif executable: {e}")))?;
            let logs = std::path::absolute(&manifest.logs).map_err(|e| Error::io(&manifest.logs, e))?;
            let options = slurm::SubmitOptions {
                partition,
                cpus_per_task: cpus,
                max_parallel,
                coif_flags: coif::limits::as_flags(),
            };
            let text = slurm::script(&coif, &absolute, manifest.tasks.len(), &logs, &options)?;
            std::fs::create_dir_all(&logs).map_err(|e| Error::io(&logs, e))?;
            let dir = slurm::farm_dir(&absolute);
            let script = slurm::write_script(&dir, &text)?;
            let job = if dry_run { None } else { Some(slurm::submit(&script)?) };
            if let Some(id) = &job {
                coif::io::atomic::write_bytes_atomically(&dir.join("job_id"), id.as_bytes())?;
            }
            if json {
                print_json(json!({ "script": script, "tasks": manifest.tasks.len(), "job_id": job }));
            } else {
                eprintln!("wrote {} ({} tasks)", script.display(), manifest.tasks.len());
                if let Some(id) = job {
                    eprintln!("submitted Slurm job {id}");
                }
            }
            Ok(())
        }
        FarmAction::Status { manifest: path, json } => {
            let manifest = manifest::load(&path)?;
            let done: Vec<bool> = manifest.tasks.iter().map(batch_task::is_complete).collect();
            let complete = done.iter().filter(|&&d| d).count();
            if json {
                let tasks: Vec<_> = manifest
                    .tasks
                    .iter()
                    .zip(&done)
                    .map(|(t, d)| json!({ "index": t.index, "task": t.name, "complete": d }))
                    .collect();
                print_json(json!({ "complete": complete, "total": done.len(), "tasks": tasks }));
            } else {
                for (t, d) in manifest.tasks.iter().zip(&done) {
                    eprintln!("{:>4} {:<24} {}", t.index, t.name, if *d { "complete" } else { "pending" });
                }
                eprintln!("{complete} of {} tasks complete", done.len());
            }
            Ok(())
        }
    }
}

fn run_generate(args: GenerateArgs) -> Result<()> {
    super::checks::generate(&args)?;
    let style = match args.style {
        HairStyle::Straight => Style::Straight,
        HairStyle::Wavy => Style::Wavy { amplitude: args.wave_amplitude, wavelength: args.wavelength },
        HairStyle::Curly => Style::Curly { radius: args.curl_radius, pitch: args.curl_pitch },
    };
    let params = GenerateParams {
        strands: args.strands,
        length: args.length,
        length_variation: args.length_variation,
        vertices_per_strand: args.vertices,
        style,
        root_width: args.width,
        droop: args.droop,
        seed: args.seed,
        ..Default::default()
    };
    // Fail on an unwritable extension or directory before spending time generating.
    io::check_output(&args.output, &io::ExportOptions::default())?;
    let groom = generate(&params)?;
    write_and_report(&args.output, &groom, &[], args.json, &io::ExportOptions::default())
}

/// One frame, or the frames of a `--frame-range` or of an animated input's whole timeline.
fn run_convert(
    input: &Path,
    output: &Path,
    import: &super::args::ImportArgs,
    json: bool,
    export: &io::ExportOptions,
    frame_range: Option<&str>,
) -> Result<()> {
    use io::timeline::{parse_range, read_timeline, Timeline};
    let options = import.options(input)?;
    let range = frame_range.map(|text| parse_range(text, "--frame-range")).transpose()?;
    let output_format = io::check_output(output, export)?;
    let timeline = match range {
        Some((first, last)) => {
            io::check_animated_output(output)?;
            // USD's fallback rate when the input says none (or holds one moment).
            let rate = read_timeline(input)?.map_or(24.0, |t| t.frames_per_second);
            Some(Timeline { first, last, frames_per_second: rate })
        }
        None if import.picks_a_moment() => None,
        None => read_timeline(input)?.filter(|_| {
            output_format != io::Format::Hair || {
                eprintln!("coif: warning: {}: .hair holds one frame: writing the input's first (--frame N picks another)", output.display());
                false
            }
        }),
    };
    let Some(timeline) = timeline else {
        let loaded = io::read_groom_selected(input, &options, &import.selection())?;
        super::checks::nothing_read_is_written(output, &loaded, export, &[])?;
        return write_and_report(output, &loaded.groom, &loaded.warnings, json, export);
    };
    // A file's own range is as unchecked as its samples (an `endTimeCode = 1e15` typo): bounded
    // like a `--frame-range`, before anything is read or written.
    if timeline.frame_count() > io::timeline::MAX_FRAMES {
        return Err(Error::format(
            input,
            format!(
                "its timeline runs from frame {} to {} ({} frames at {} fps), more than the {} a \
                 convert writes; --frame-range FIRST:LAST picks frames, --frame N one",
                shortest(timeline.first),
                shortest(timeline.last),
                shortest(timeline.frames_spanned()),
                shortest(timeline.frames_per_second),
                io::timeline::MAX_FRAMES
            ),
        ));
    }
    let reader =
        io::FrameReader::new(input, options, import.selection().variants, timeline.first, timeline.last)?;
    let read = |frame: f64| reader.read(frame);
    let loaded = read(timeline.first)?;
    super::checks::nothing_read_is_written(output, &loaded, export, &[])?;
    let (first, read_warnings) = (loaded.groom, loaded.warnings);
    let rest = timeline.frames().skip(1).map(|frame| read(frame).map(|loaded| loaded.groom));
    let written = io::write_frames(output, input, &first, rest, &timeline, export)?;
    let warnings: Vec<String> = read_warnings.into_iter().chain(written).collect();
    for warning in &warnings {
        eprintln!("coif: warning: {warning}");
    }
    let info = GroomInfo::of(&first);
    let frames = frames_json(&timeline);
    let meshes_output = io::meshes_output(output, &first, export);
    if json {
        print_json(
            json!({ "output": output, "meshes_output": meshes_output, "groom": info, "frames": frames, "warnings": warnings }),
        );
    } else {
        report_meshes_output(meshes_output.as_deref());
        eprintln!(
            "wrote {} ({} strands, {} vertices, frames {} to {} at {} fps)",
            output.display(),
            info.strands,
            info.vertices,
            timeline.first,
            timeline.frame(timeline.frame_count() - 1),
            shortest(timeline.frames_per_second)
        );
    }
    Ok(())
}

/// A timeline in `--json` output: its first and last whole frames, their count and rate.
fn frames_json(timeline: &io::timeline::Timeline) -> serde_json::Value {
    json!({ "first": timeline.first, "last": timeline.frame(timeline.frame_count() - 1),
        "count": timeline.frame_count(), "frames_per_second": timeline.frames_per_second })
}

/// Writes `groom` and reports it, with the warnings of reading it (`read_warnings`) and writing it.
fn write_and_report(
    output: &Path,
    groom: &coif::Groom,
    read_warnings: &[String],
    json: bool,
    options: &io::ExportOptions,
) -> Result<()> {
    let written = io::write_groom_with(output, groom, options)?;
    let warnings: Vec<String> = read_warnings.iter().cloned().chain(written).collect();
    for warning in &warnings {
        eprintln!("coif: warning: {warning}");
    }
    let info = GroomInfo::of(groom);
    let meshes_output = io::meshes_output(output, groom, options);
    if json {
        print_json(
            json!({ "output": output, "meshes_output": meshes_output, "groom": info, "warnings": warnings }),
        );
    } else {
        report_meshes_output(meshes_output.as_deref());
        eprintln!("wrote {} ({} strands, {} vertices)", output.display(), info.strands, info.vertices);
    }
    Ok(())
}

/// Where `--unreal` output put the meshes (Unreal's groom importers refuse a file holding one).
fn report_meshes_output(path: Option<&Path>) {
    if let Some(path) = path {
        eprintln!(
            "wrote {} (the meshes: Unreal's groom importer refuses a groom file holding a mesh)",
            path.display()
        );
    }
}

fn print_json(value: serde_json::Value) {
    let text = serde_json::to_string_pretty(&value).expect("JSON values always serialise");
    print_stdout(&format!("{text}\n"));
}

/// Prints to stdout; a closed pipe (`coif info x | head`) ends output quietly instead of panicking.
fn print_stdout(text: &str) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

/// The error and its causes, one after another, so the user sees the root cause too.
pub(crate) fn error_chain(error: &Error) -> String {
    let mut text = error.to_string();
    let mut source = std::error::Error::source(error);
    while let Some(cause) = source {
        let cause_text = cause.to_string();
        if !text.contains(&cause_text) {
            text.push_str(": ");
            text.push_str(&cause_text);
        }
        source = cause.source();
    }
    text
}
