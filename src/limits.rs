//! Resource limits, checked before anything is allocated or simulated: a job estimates the memory
//! and the work its inputs imply (vertices after resampling, droplets, steps) and is refused with
//! the figure when it would exceed them, instead of aborting on an allocation or running for a
//! week on a farm node.
//!
//! The memory limit defaults to half the machine's RAM (`--max-memory` changes it); the step
//! budget bounds simulated steps and vertex-steps. Estimates are deliberately generous per item
//! and only have to be right to a small factor: they catch inputs that are off by orders of
//! magnitude (`droplets = 1e12`, `max_segment = 1e-9`, `dt = 1e-30`).
use std::sync::atomic::{AtomicU64, Ordering};

use crate::error::{Error, Result};
use crate::groom::Groom;

/// Bytes the simulation holds per vertex (positions, velocities, frames, rest shape, bonds,
/// wetness, contact lists and scratch). Measured: peak RSS of `coif style` (wet and dry stages,
/// no water) grows by 412 bytes per vertex from 160,000 to 640,000 vertices; rounded up.
pub const SIM_BYTES_PER_VERTEX: f64 = 512.0;
/// Bytes per water droplet (position, velocity, its list of touched vertices).
pub const DROPLET_BYTES: f64 = 128.0;
/// A captured `--frames` frame, per vertex: the position and the attributes styling changes
/// (`rest` and `rest_darboux` 12 B each, four `bond_*` rates, `wetness`, `material_frame` 16 B:
/// 72 B held), rounded up past the 76 B measured: 6,800 frames of 600 vertices peaked at 311 MB,
/// which a count of the positions alone (12 B) let past a 60 MB limit.
const FRAME_BYTES_PER_VERTEX: f64 = 84.0;
/// Bytes a groom holds per vertex (point, width and a few attributes). Measured: `coif info`'s
/// peak RSS grows by 32 bytes per vertex of a generated groom; attributes add more.
pub const GROOM_BYTES_PER_VERTEX: f64 = 64.0;
/// Bytes a render holds per pixel (sample sums, first hits, the image, its 8-bit copy and
/// AOVs). Measured: peak RSS of a 4096×4096 render of a small groom is 865 MB, 51 per pixel.
pub const RENDER_BYTES_PER_PIXEL: f64 = 64.0;
/// Simulated steps one run may take, whatever the groom's size.
pub const DEFAULT_MAX_STEPS: u64 = 10_000_000;
/// Vertex-steps (vertices × steps) one run may take at [`WORK_ITERATIONS`] solver iterations a
/// step; a step of more iterations counts for more (1,000 iterations are 200 such steps).
pub const DEFAULT_MAX_WORK: f64 = 1e13;
/// The iterations a step of the work budget is counted at (the default).
pub const WORK_ITERATIONS: f64 = 5.0;

static MAX_MEMORY: AtomicU64 = AtomicU64::new(0);
static MAX_STEPS: AtomicU64 = AtomicU64::new(DEFAULT_MAX_STEPS);

/// Sets the memory limit in bytes for this process (0 restores the default).
pub fn set_max_memory(bytes: u64) {
    MAX_MEMORY.store(bytes, Ordering::Relaxed);
}

/// Sets the step budget for this process.
pub fn set_max_steps(steps: u64) {
    MAX_STEPS.store(steps.max(1), Ordering::Relaxed);
}

/// The memory limit: `--max-memory`, else half the machine's RAM (8 GiB when unknown).
pub fn max_memory() -> u64 {
    match MAX_MEMORY.load(Ordering::Relaxed) {
        0 => total_ram().map_or(8 << 30, |ram| ram / 2),
        set => set,
    }
}

pub fn max_steps() -> u64 {
    MAX_STEPS.load(Ordering::Relaxed)
}

/// The limits set for this process as coif's command-line flags, for the coif processes a batch
/// starts (its local tasks, the sbatch script's line): every task runs under the limits the batch
/// was given. Defaults are left out, so that a farm node's memory limit stays half its own RAM.
pub fn as_flags() -> Vec<String> {
    let mut flags = Vec::new();
    if let set @ 1.. = MAX_MEMORY.load(Ordering::Relaxed) {
        flags.extend(["--max-memory".to_string(), set.to_string()]);
    }
    if max_steps() != DEFAULT_MAX_STEPS {
        flags.extend(["--max-steps".to_string(), max_steps().to_string()]);
    }
    flags
}

fn total_ram() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Parses a size like `8G`, `512M`, `1.5GiB` or a plain byte count.
pub fn parse_size(text: &str) -> Result<u64> {
    let bad = || Error::Usage(format!("--max-memory '{text}' is not a size like 8G, 512M or 1073741824"));
    let trimmed = text.trim();
    let split = trimmed.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(trimmed.len());
    let (number, unit) = trimmed.split_at(split);
    let value: f64 = number.parse().map_err(|_| bad())?;
    let scale = match unit.trim().to_ascii_uppercase().trim_end_matches("IB").trim_end_matches('B') {
        "" => 1.0,
        "K" => 1024.0,
        "M" => 1024.0 * 1024.0,
        "G" => 1024.0 * 1024.0 * 1024.0,
        "T" => 1024.0 * 1024.0 * 1024.0 * 1024.0,
        _ => return Err(bad()),
    };
    let bytes = value * scale;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(bad());
    }
    Ok(bytes as u64)
}

/// A memory size in the unit that shows it with a few significant digits ("0.000 GB" hid a
/// one-byte limit).
pub(crate) fn memory_text(bytes: f64) -> String {
    match bytes {
        b if b >= 1e9 => format!("{:.3} GB", b / 1e9),
        b if b >= 1e6 => format!("{:.3} MB", b / 1e6),
        b if b >= 1e3 => format!("{:.3} kB", b / 1e3),
        b => format!("{b:.0} bytes"),
    }
}

/// Caps the memory the process `command` starts may allocate (its data: heap and private maps,
/// `RLIMIT_DATA`) at `bytes`, or its current hard limit if lower: past it, an allocation in the
/// child fails instead of growing until the kernel's OOM killer acts.
pub fn limit_child_memory(command: &mut std::process::Command, bytes: u64) {
    #[cfg(unix)]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: getrlimit and setrlimit are async-signal-safe and touch no memory of the parent.
        unsafe {
            command.pre_exec(move || {
                let mut limit = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
                if libc::getrlimit(libc::RLIMIT_DATA, &mut limit) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                let bytes = (bytes as libc::rlim_t).min(limit.rlim_max);
                if libc::setrlimit(libc::RLIMIT_DATA, &libc::rlimit { rlim_cur: bytes, rlim_max: bytes }) != 0
                {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    #[cfg(not(unix))]
    let _ = (command, bytes);
}

/// Refuses `bytes` of `what` over the memory limit.
pub fn check_memory(what: &str, bytes: f64) -> Result<()> {
    let limit = max_memory() as f64;
    if bytes.is_nan() || bytes > limit {
        return Err(Error::Usage(format!(
            "{what} needs about {} of memory, over the limit of {} (--max-memory)",
            memory_text(bytes),
            memory_text(limit)
        )));
    }
    Ok(())
}

/// Refuses a run of `steps` steps of `iterations` solver iterations over `vertices` vertices
/// beyond the step budget.
pub fn check_steps(what: &str, steps: f64, vertices: f64, iterations: f64) -> Result<()> {
    let max = max_steps() as f64;
    if steps.is_nan() || steps > max {
        return Err(Error::Usage(format!(
            "{what} takes {} simulation steps, over the budget of {max:.0} (--max-steps)",
            crate::validate::shortest(steps)
        )));
    }
    let work = steps * vertices * (iterations / WORK_ITERATIONS).max(1.0);
    if work > DEFAULT_MAX_WORK {
        return Err(Error::Usage(format!(
            "{what} takes {steps:.3e} steps of {vertices:.0} vertices at {iterations} iterations \
             ({work:.3e} vertex-steps of {WORK_ITERATIONS} iterations), over the budget of {DEFAULT_MAX_WORK:.0e}"
        )));
    }
    Ok(())
}

/// Camera samples (pixels × samples per pixel) one render may take without a time budget: about
/// a week of a 2-core node (the demo's preview runs at ~1.5 M samples/s).
pub const DEFAULT_MAX_SAMPLES: f64 = 1e12;

/// Refuses a render of `width` × `height` pixels at `spp` samples each beyond
/// [`DEFAULT_MAX_SAMPLES`], unless a time budget bounds it.
pub fn check_render(width: u32, height: u32, spp: u32, time_budget: bool) -> Result<()> {
    let samples = width as f64 * height as f64 * spp as f64;
    if samples > DEFAULT_MAX_SAMPLES && !time_budget {
        return Err(Error::Usage(format!(
            "rendering {width}x{height} at {spp} spp takes {samples:.3e} camera samples, over the budget of \
             {DEFAULT_MAX_SAMPLES:.0e} (about a week of a 2-core node); lower --res or --spp, or give \
             --time-budget"
        )));
    }
    check_memory(
        &format!("rendering {width}x{height}"),
        width as f64 * height as f64 * RENDER_BYTES_PER_PIXEL,
    )
}

/// Steps a run of `seconds` takes at time step `dt` (as a float: it may be astronomically many).
pub fn steps_for(seconds: f64, dt: f64) -> f64 {
    (seconds / dt).ceil().max(0.0)
}

/// Vertices `groom` has after resampling so no segment is longer than `max_segment`, computed
/// without resampling.
pub fn vertices_after_resampling(groom: &Groom, max_segment: Option<f32>) -> f64 {
    let Some(max) = max_segment else {
        return groom.vertex_count() as f64;
    };
    let max = max as f64;
    let mut total = 0.0;
    for s in 0..groom.strand_count() {
        let points = &groom.points[groom.strand_range(s)];
        let length: f64 = points.windows(2).map(|w| w[0].distance(w[1]) as f64).sum();
        total += (length / max).ceil().max(1.0) + 1.0;
    }
    total
}

/// Bytes hair–hair contacts hold per listed vertex–edge pair while they build lists: the new
/// lists, the build's own copy of them, and the lists kept from before (4 bytes each).
pub const CONTACT_BYTES_PER_PAIR: f64 = 12.0;

/// Vertex–edge pairs the hair–hair contacts of `vertices` simulated vertices may list: what the
/// memory limit leaves beside the simulation's own estimate (which counts a few pairs a vertex,
/// as hair has). Lists grow with how densely strands lie, which no count of vertices sees: 10,000
/// strands piled at one point list 2·10⁸ pairs. Also below 2³², as lists index them in 32 bits.
pub fn contact_pairs_allowed(vertices: f64) -> u64 {
    let left = max_memory() as f64 - vertices * SIM_BYTES_PER_VERTEX;
    ((left.max(0.0) / CONTACT_BYTES_PER_PAIR) as u64).min(u32::MAX as u64)
}

/// A simulation of `vertices` vertices (and `droplets` droplets) for `steps` steps of
/// `iterations` solver iterations.
pub fn check_simulation(what: &str, vertices: f64, droplets: f64, steps: f64, iterations: f64) -> Result<()> {
    check_memory(what, vertices * SIM_BYTES_PER_VERTEX + droplets * DROPLET_BYTES)?;
    check_steps(what, steps, vertices + droplets, iterations)
}

/// Styling `groom` with `recipe`: the resampled groom, its droplets, every stage's steps, and
/// the recorded frames when `frames_per_second` is positive.
pub fn check_style(groom: &Groom, recipe: &crate::style::Recipe, frames_per_second: f32) -> Result<()> {
    let settings = &recipe.settings;
    let vertices = vertices_after_resampling(groom, settings.max_segment);
    let droplets = recipe.water.as_ref().map_or(0.0, |w| w.droplets as f64);
    let seconds: f64 = recipe.stages.iter().map(|s| s.get_ref().duration() as f64).sum();
    let steps: f64 =
        recipe.stages.iter().map(|s| steps_for(s.get_ref().duration().into(), settings.dt.into())).sum();
    let frames = (seconds * frames_per_second as f64).ceil() + 2.0;
    let frame_bytes = if frames_per_second > 0.0 { frames * vertices * FRAME_BYTES_PER_VERTEX } else { 0.0 };
    let what = format!(
        "styling {vertices:.0} vertices with {droplets:.0} droplets for {} s",
        crate::validate::seconds_text(seconds)
    );
    check_memory(&what, vertices * SIM_BYTES_PER_VERTEX + droplets * DROPLET_BYTES + frame_bytes)?;
    check_steps(&what, steps, vertices + droplets, settings.iterations.into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_beyond_the_sample_budget_need_a_time_budget() {
        assert!(check_render(3840, 2160, 4096, false).is_ok());
        let e = check_render(16384, 16384, 1_000_000, false).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("2.684e14") && e.to_string().contains("--time-budget"), "{e}");
        assert!(check_render(4096, 4096, 1_000_000, true).is_ok());
    }

    #[test]
    fn sizes_parse() {
        assert_eq!(parse_size("8G").unwrap(), 8 << 30);
        assert_eq!(parse_size("512MiB").unwrap(), 512 << 20);
        assert_eq!(parse_size("1000").unwrap(), 1000);
        assert!(parse_size("lots").is_err() && parse_size("-1G").is_err() && parse_size("0").is_err());
    }

    #[test]
    fn astronomical_runs_are_refused_with_their_figures() {
        let e = check_steps("style", steps_for(1e9, 1.0 / 360.0), 100.0, 5.0).unwrap_err().to_string();
        assert!(e.contains("3.6e11 simulation steps") && e.contains("budget"), "{e}");
        // Work counts iterations: a day's steps at 5 iterations are 200 days' at 1,000.
        let (steps, vertices) = (1e6, 1e6);
        assert!(check_steps("at 5", steps, vertices, 5.0).is_ok());
        assert!(check_steps("at 1", steps, vertices, 1.0).is_ok());
        let e = check_steps("at 1000", steps, vertices, 1000.0).unwrap_err().to_string();
        assert!(e.contains("1000 iterations") && e.contains("2.000e14"), "{e}");
        let e = check_memory("water", 1e12 * DROPLET_BYTES).unwrap_err().to_string();
        assert!(e.contains("128000.000 GB"), "{e}");
        assert!(check_steps("tiny", 10.0, 10.0, 1000.0).is_ok());
    }

    /// What one captured frame of a style holds per vertex, counted from a real run, fits the
    /// estimate (it counted the positions alone).
    #[test]
    fn a_captured_frame_is_counted_with_its_attributes() {
        let groom = crate::generate::generate(&crate::generate::GenerateParams {
            strands: 4,
            vertices_per_strand: 6,
            ..Default::default()
        })
        .unwrap();
        let recipe = crate::style::recipe::parse(
            "[settings]\ndt = 0.01\n\n[[stages]]\nkind = \"wet\"\nduration = 0.05\n",
            std::path::Path::new("r.toml"),
        )
        .unwrap();
        let options = crate::style::StyleOptions { frames_per_second: 100.0, ..Default::default() };
        let styled = crate::style::style(&groom, &recipe, &options).unwrap();
        let vertices = groom.vertex_count() as f64;
        let attributes: usize = styled.frame_attributes[0].iter().map(|a| a.data.len() * 4).sum();
        let held = (styled.frames[0].len() * 12 + attributes) as f64 / vertices;
        assert!(held > 12.0 && held <= FRAME_BYTES_PER_VERTEX, "a frame holds {held} B per vertex");
    }

    #[test]
    fn resampled_vertices_are_counted_without_resampling() {
        let groom = crate::generate::generate(&crate::generate::GenerateParams {
            strands: 3,
            vertices_per_strand: 5,
            ..Default::default()
        })
        .unwrap();
        let resampled = crate::analysis::resample_groom(&groom, 0.01);
        let estimate = vertices_after_resampling(&groom, Some(0.01));
        assert!((estimate - resampled.vertex_count() as f64).abs() <= 3.0, "{estimate}");
    }
}
