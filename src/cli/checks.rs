//! Every number a flag carries, checked (through `coif::validate`) before a command reads or
//! computes anything: a refusal names the flag, the value and the accepted range (exit code 2).
//! Also refused here, as early: an output that is one of the run's inputs.
use coif::validate::{
    flag, flag_direction, flag_vector, Range, COORDINATE, FRACTION, FRAME, ITERATIONS, SECONDS, TIME_STEP,
    UNITS,
};
use coif::Result;
use std::path::{Path, PathBuf};

use super::args::{GenerateArgs, ImportArgs, RenderArgs, SimulateArgs, StyleArgs};

const RATE: Range = Range::closed(0.0, 1e4);

/// Also run by `ImportArgs::options`, so every command that reads a groom checks these.
pub(crate) fn import(args: &ImportArgs) -> Result<()> {
    if let Some(units) = args.units {
        flag("--units", units, UNITS)?;
    }
    if let Some(frame) = args.frame {
        flag("--frame", frame, FRAME)?;
    }
    if let Some(seconds) = args.time {
        // A year either way; the frame it makes is checked against the file's timeline.
        flag("--time", seconds, Range::closed(-3.2e7, 3.2e7))?;
    }
    Ok(())
}

pub(crate) fn style(args: &StyleArgs) -> Result<()> {
    if let Some(fps) = args.frames {
        // A frame a second (a long settle's time-lapse) to slow motion. At 0 no animation was
        // written without a word; at 1e-9 a timeline of 1e-9 time codes per second.
        flag("--frames", fps, Range::closed(1.0, 1e4))?;
    }
    if let Some(guides) = args.guides {
        // At least one; more than the groom's strands is refused once it is read.
        flag("--guides", guides as f64, Range::closed(1.0, 1e9))?;
    }
    // An empty name matched the one unnamed group of a .hair file (every strand), so
    // `--group "$GROUP"` with an unset variable styled the whole groom.
    if args.groups.iter().any(|name| name.trim().is_empty()) {
        return Err(coif::Error::Usage(
            "--group \"\": a group is named by its prim or object path or its last name, never empty".into(),
        ));
    }
    let inputs = [
        ("--groom", Some(&args.groom)),
        ("the recipe", Some(&args.recipe)),
        ("--scalp", args.scalp.as_ref()),
    ];
    not_an_input(&args.output, &inputs)
}

/// Refuses an output that is one of the run's inputs (the same file, however named): the run
/// would replace what it read, and running it again would work on its own result.
fn not_an_input(output: &Path, inputs: &[(&str, Option<&PathBuf>)]) -> Result<()> {
    let inputs: Vec<(String, &Path)> =
        inputs.iter().filter_map(|(what, path)| path.map(|p| (what.to_string(), p.as_path()))).collect();
    coif::io::refuse_writing_inputs(&[output], &inputs)
}

/// [`not_an_input`] once the groom is read: every file written (the output, and `--unreal`'s
/// meshes beside it) against every file read (the groom's, the layers its stage composes, and
/// `others`, such as the recipe).
pub(crate) fn nothing_read_is_written(
    output: &Path,
    loaded: &coif::io::Loaded,
    export: &coif::io::ExportOptions,
    others: &[(&str, Option<&PathBuf>)],
) -> Result<()> {
    // Styled and simulated grooms keep the meshes of the groom read.
    let meshes = coif::io::meshes_output(output, &loaded.groom, export);
    let outputs: Vec<&Path> = std::iter::once(output).chain(meshes.as_deref()).collect();
    let mut inputs: Vec<(String, &Path)> = loaded
        .files
        .iter()
        .enumerate()
        .map(|(i, file)| {
            let what = if i == 0 {
                "the groom it reads".to_string()
            } else {
                "a layer the groom's stage composes".to_string()
            };
            (what, file.as_path())
        })
        .collect();
    inputs.extend(others.iter().filter_map(|(what, path)| path.map(|p| (what.to_string(), p.as_path()))));
    coif::io::refuse_writing_inputs(&outputs, &inputs)
}

pub(crate) fn simulate(args: &SimulateArgs) -> Result<()> {
    not_an_input(&args.output, &[("the input", Some(&args.input))])?;
    flag("--seconds", args.seconds, SECONDS)?;
    flag("--gravity", args.gravity, COORDINATE)?;
    flag("--dt", args.dt, TIME_STEP)?;
    flag("--iterations", args.iterations, ITERATIONS)?;
    flag("--damping", args.damping, RATE)?;
    if args.influences.len() != 4 {
        return Err(coif::Error::Usage(format!(
            "--influences takes 4 values (hydrogen,ionic,disulfide,peptide), got {}",
            args.influences.len()
        )));
    }
    for (name, value) in ["hydrogen", "ionic", "disulfide", "peptide"].iter().zip(&args.influences) {
        flag(&format!("--influences {name}"), *value, Range::closed(0.0, 1e3))?;
    }
    flag("--youngs-modulus", args.youngs_modulus, coif::validate::MODULUS)?;
    // The settle's own budget range (`sim::settle::MAX_SECONDS_RANGE`), one source for both.
    let (_, max_settle) = coif::sim::settle::MAX_SECONDS_RANGE;
    flag("--settle-seconds", args.settle_seconds, Range::above(0.0, max_settle as f64))?;
    if let Some(iterations) = args.settle_iterations {
        flag("--settle-iterations", iterations, ITERATIONS)?;
    }
    Ok(())
}

pub(crate) fn render(args: &RenderArgs) -> Result<()> {
    flag("--spp", args.spp, Range::closed(1.0, 1e6))?;
    flag("--fov", args.fov, coif::render::camera::FOV_DEGREES)?;
    flag("--width-scale", args.width_scale, Range::above(0.0, 1e4))?;
    flag("--min-pixel-width", args.min_pixel_width, Range::closed(0.0, 1e3))?;
    flag("--max-depth", args.max_depth, Range::closed(0.0, 1e3))?;
    flag("--exposure", args.exposure, Range::closed(-40.0, 40.0))?;
    flag("--light-intensity", args.light_intensity, Range::closed(0.0, 1e6))?;
    if let Some(threads) = args.threads {
        // Beyond a thousand worker threads is a typo: each one takes its stack and scratch.
        flag("--threads", threads as f64, Range::closed(1.0, 1024.0))?;
    }
    if let Some(seconds) = args.time_budget {
        // Up to a fortnight: beyond, a budget is a typo (and past ~1e19 s no Duration holds it).
        flag("--time-budget", seconds, Range::above(0.0, 1.2e6))?;
    }
    if let Some(radiance) = args.environment {
        flag("--environment", radiance, Range::closed(0.0, 1e6))?;
    }
    if let Some(color) = &args.color {
        flag_vector("--color", coif::render::parse_vec3(color, "--color")?.into(), FRACTION)?;
    }
    if let Some(direction) = &args.light_dir {
        flag_direction("--light-dir", coif::render::parse_vec3(direction, "--light-dir")?.into())?;
    }
    if let Some(height) = args.floor_height {
        flag("--floor-height", height, COORDINATE)?;
    }
    if let Some(size) = args.floor_size {
        flag("--floor-size", size, Range::above(0.0, 1e4))?;
    }
    if let Some(albedo) = &args.floor_albedo {
        flag_vector("--floor-albedo", coif::render::parse_vec3(albedo, "--floor-albedo")?.into(), FRACTION)?;
    }
    Ok(())
}

pub(crate) fn generate(args: &GenerateArgs) -> Result<()> {
    let vertices = args.strands as f64 * args.vertices as f64;
    coif::limits::check_memory(
        &format!("--strands {} × --vertices {}", args.strands, args.vertices),
        vertices * coif::limits::GROOM_BYTES_PER_VERTEX,
    )?;
    // From a tenth of a millimetre: shorter, a strand's segments round to zero length in f32
    // at a head's distance from the origin.
    flag("--length", args.length, Range::closed(1e-4, 100.0))?;
    flag("--length-variation", args.length_variation, Range::below(0.0, 1.0))?;
    // Hair to cord (0: the simulation's fallback width), and curls and waves of a head's scale.
    flag("--width", args.width, Range::closed(0.0, 0.01))?;
    flag("--curl-radius", args.curl_radius, Range::above(0.0, 1.0))?;
    flag("--curl-pitch", args.curl_pitch, Range::above(0.0, 10.0))?;
    flag("--wave-amplitude", args.wave_amplitude, Range::closed(0.0, 1.0))?;
    flag("--wavelength", args.wavelength, Range::above(0.0, 10.0))?;
    flag("--droop", args.droop, Range::closed(0.0, 1e3))?;
    Ok(())
}
