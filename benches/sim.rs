//! Solver speed, in two tables. `cargo bench --bench sim [-- FILTER]`, FILTER matching a
//! configuration name (`step` runs only the second table).
//!
//! **Per iteration** (Gauss–Seidel): ns per vertex-iteration (one stretch–shear, one bend–twist and
//! one direct stretch–shear row per vertex and iteration, plus the per-step prediction and velocity
//! update amortised), on 1 thread and on 2 threads. Median of 3 runs, by wall clock and by CPU time
//! of the workers (robust when other processes share the cores).
//!
//! **Per step at a stated accuracy** (issue 15): for both strand solvers and a range of iterations,
//! the CPU time of a step on 1 thread (ns per vertex-step, median of 3 runs) and the accuracy that
//! step reaches, then the cheapest configuration that meets [`TARGET`]. Accuracy is the distance of
//! the positions after [`ACCURACY_STEPS`] steps (0.25 s at Δt 1/360: the wavy groom released at
//! rest falls, swings and bends) from a run of the same solver with many iterations, mean and worst
//! vertex in % of the strand length. Why this and not the XPBD residual `C + α̃·λ`: the residual
//! has no common scale between the solvers (Gauss–Seidel's stretch–shear keeps no multiplier, the
//! direct solve's frames turn with another inertia), it leaves out the momentum equation (XPBD
//! drops it), so it can be small while the motion is wrong, and it says nothing about what a user
//! sees; the distance
//! does, it accumulates a solver's systematic error (softness) the way a style does, and its unit
//! is the one of the invariance target (1 % mean / 3 % worst of the strand length between
//! time steps and iteration counts). The target is a tenth of that. Each solver is measured against
//! its own converged run because the two integrate different frame inertias
//! ([`StrandSolver::frame_inertia_factor`]); the table prints how far apart the two converged runs
//! are, and how far each reference is from one with twice its iterations (its own error). Strands
//! do not interact in this bench, so the accuracy is measured on an evenly spaced sample of ~500
//! of the configuration's strands.

mod common;
use common::median;
use std::time::Instant;

use coif::generate::{generate, GenerateParams, Style};
use coif::sim::{SimParams, Simulation, StrandSolver};
use coif::Groom;
use glam::Vec3;

struct Config {
    name: &'static str,
    strands: usize,
    vertices: usize,
    iterations: u32,
}

const CONFIGS: [Config; 3] = [
    Config { name: "1000x32x5", strands: 1_000, vertices: 32, iterations: 5 },
    Config { name: "10000x6x4", strands: 10_000, vertices: 6, iterations: 4 },
    Config { name: "100000x32x5", strands: 100_000, vertices: 32, iterations: 5 },
];

/// The accuracy a step must reach to count as converged: mean and worst vertex distance to the
/// solver's converged run, % of the strand length (a tenth of the 1 % / 3 %).
const TARGET: (f64, f64) = (0.1, 0.3);
/// Steps before the accuracy is measured: 0.25 s at Δt 1/360.
const ACCURACY_STEPS: usize = 90;
/// The budget for a converged step: today's 5-iteration Gauss–Seidel step on 10,000 × 32,
/// 17 ns per vertex-iteration × 5 on one thread, in ns per vertex-step.
const BUDGET_NS: f64 = 87.0;
/// Strands in the accuracy sample.
const SAMPLE_STRANDS: usize = 500;

struct StepConfig {
    name: &'static str,
    strands: usize,
    vertices: usize,
}

const STEP_CONFIGS: [StepConfig; 4] = [
    StepConfig { name: "step 10000x32", strands: 10_000, vertices: 32 },
    StepConfig { name: "step 1000x32", strands: 1_000, vertices: 32 },
    StepConfig { name: "step 10000x6", strands: 10_000, vertices: 6 },
    StepConfig { name: "step 100000x32", strands: 100_000, vertices: 32 },
];

/// The iteration counts tried with each solver, and the count of its converged reference run.
fn iterations_tried(solver: StrandSolver) -> (&'static [u32], u32) {
    match solver {
        StrandSolver::GaussSeidel => (&[5, 10, 20, 40], 200),
        StrandSolver::Direct => (&[1, 2, 3, 5], 20),
    }
}

/// Positions after [`ACCURACY_STEPS`] steps from rest with `solver`'s defaults and `iterations`.
fn positions_after(groom: &Groom, solver: StrandSolver, iterations: u32) -> Vec<Vec3> {
    positions_with(groom, SimParams { iterations, ..SimParams::for_solver(solver) })
}

/// Positions after [`ACCURACY_STEPS`] steps from rest (on the global pool: results do not depend
/// on the thread count).
fn positions_with(groom: &Groom, params: SimParams) -> Vec<Vec3> {
    let mut sim = Simulation::new(groom, params).expect("bench simulation");
    (0..ACCURACY_STEPS).for_each(|_| sim.step());
    sim.rods().positions().to_vec()
}

/// Mean and worst vertex distance between two runs of `groom`, % of each vertex's strand length.
fn distance(groom: &Groom, a: &[Vec3], b: &[Vec3]) -> (f64, f64) {
    let (mut sum, mut worst) = (0.0f64, 0.0f64);
    for strand in 0..groom.strand_count() {
        let points = groom.strand_points(strand);
        let length: f32 = points.windows(2).map(|w| w[0].distance(w[1])).sum();
        for v in groom.strand_range(strand) {
            let d = 100.0 * (a[v].distance(b[v]) / length) as f64;
            sum += d;
            worst = worst.max(d);
        }
    }
    (sum / a.len() as f64, worst)
}

/// CPU ns per vertex-step of `groom` on one thread, median of 3 runs of about 0.2 s each.
fn step_cpu_ns(groom: &Groom, solver: StrandSolver, iterations: u32) -> (f64, usize) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let params = SimParams { iterations, ..SimParams::for_solver(solver) };
    let mut sim = Simulation::new(groom, params).expect("bench simulation");
    let vertices = groom.points.len() as f64;
    let guess_ns = iterations as f64 * if solver == StrandSolver::Direct { 80.0 } else { 17.0 };
    let steps = ((2e8 / (vertices * guess_ns)).ceil() as usize).max(1);
    pool.install(|| sim.step()); // coefficients, caches and pages
    let runs: Vec<f64> = (0..3)
        .filter_map(|_| {
            let start = pool_cpu_ns(&pool);
            pool.install(|| (0..steps).for_each(|_| sim.step()));
            Some((pool_cpu_ns(&pool)? - start?) as f64 / (vertices * steps as f64))
        })
        .collect();
    (if runs.len() == 3 { median(runs) } else { f64::NAN }, steps)
}

/// The step-cost table of one configuration (see the module doc).
fn step_cost(config: &StepConfig) {
    let groom = bench_groom(config.strands, config.vertices);
    let every = config.strands.div_ceil(SAMPLE_STRANDS);
    let picked: Vec<usize> = (0..config.strands).step_by(every).collect();
    let sample = coif::groups::assemble(&[(&groom, &picked)]).expect("a selection of a valid groom");
    println!(
        "{}: Δt 1/360, CPU time per step on 1 thread; accuracy after {ACCURACY_STEPS} steps on {} strands, \
         distance to the solver's converged run, % of strand length (target mean ≤ {} / worst ≤ {}); load {}",
        config.name,
        picked.len(),
        TARGET.0,
        TARGET.1,
        common::load()
    );
    println!("  solver        iter  ns/vertex-step  × {BUDGET_NS} ns   accuracy mean / worst %   meets");
    let mut references = Vec::new();
    let mut cheapest: Option<(StrandSolver, u32, f64)> = None;
    // Today's step measured here, under the same load as the rest of the table.
    let mut five_sweeps = f64::NAN;
    for solver in [StrandSolver::GaussSeidel, StrandSolver::Direct] {
        let (tried, converged) = iterations_tried(solver);
        let reference = positions_after(&sample, solver, converged);
        let doubled = positions_after(&sample, solver, 2 * converged);
        let (own_mean, own_worst) = distance(&sample, &doubled, &reference);
        for &iterations in tried {
            let (mean, worst) = distance(&sample, &positions_after(&sample, solver, iterations), &reference);
            let (ns, steps) = step_cpu_ns(&groom, solver, iterations);
            let meets = mean <= TARGET.0 && worst <= TARGET.1;
            if (solver, iterations) == (StrandSolver::GaussSeidel, 5) {
                five_sweeps = ns;
            }
            println!(
                "  {:<12} {iterations:>4}  {ns:>10.1}      {:>6.2}      {mean:>8.3} / {worst:>7.3}       {}   ({steps} steps a run)",
                format!("{solver:?}"),
                ns / BUDGET_NS,
                if meets { "yes" } else { "no" },
            );
            if meets && cheapest.is_none_or(|(_, _, best)| ns < best) {
                cheapest = Some((solver, iterations, ns));
            }
        }
        println!(
            "  {:<12} {converged:>4}  (reference; against {} iterations: {own_mean:.4} / {own_worst:.4} %)",
            format!("{solver:?}"),
            2 * converged
        );
        references.push(reference);
    }
    let (mean, worst) = distance(&sample, &references[0], &references[1]);
    // The direct solve converged with Gauss–Seidel's frame inertia: the same equations as the
    // Gauss–Seidel reference, so what is left is the two solvers' own difference.
    let gauss_seidel_frames = StrandSolver::GaussSeidel.frame_inertia_factor();
    let params = SimParams {
        iterations: iterations_tried(StrandSolver::Direct).1,
        frame_inertia_factor: gauss_seidel_frames,
        ..SimParams::for_solver(StrandSolver::Direct)
    };
    let (same_mean, same_worst) = distance(&sample, &positions_with(&sample, params), &references[0]);
    println!(
        "  the two converged runs differ by {mean:.3} / {worst:.3} %; with Gauss–Seidel's frame inertia \
         ({gauss_seidel_frames}) the direct one is {same_mean:.3} / {same_worst:.3} % from Gauss–Seidel's"
    );
    match cheapest {
        Some((solver, iterations, ns)) => println!(
            "  cheapest at the target: {solver:?} × {iterations}: {ns:.1} ns/vertex-step, {:.2}× the budget of \
             {BUDGET_NS} ns, {:.2}× GaussSeidel × 5 measured here",
            ns / BUDGET_NS,
            ns / five_sweeps
        ),
        None => println!("  no configuration tried meets the target"),
    }
}

/// CPU time of the calling thread in ns (Linux `schedstat`), if available.
fn thread_cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// CPU time of all the pool's workers in ns.
fn pool_cpu_ns(pool: &rayon::ThreadPool) -> Option<u64> {
    pool.broadcast(|_| thread_cpu_ns()).into_iter().sum()
}

/// The bench groom: wavy strands of 24 cm on the generator's head.
fn bench_groom(strands: usize, vertices: usize) -> Groom {
    generate(&GenerateParams {
        strands,
        vertices_per_strand: vertices,
        style: Style::Wavy { amplitude: 0.01, wavelength: 0.08 },
        ..GenerateParams::default()
    })
    .expect("bench groom")
}

fn main() {
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let selected = |name: &str| filter.as_deref().is_none_or(|f| name.contains(f));
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    println!(
        "cores available: {cores}; load {}; medians of 3 runs; CPU time from /proc/thread-self/schedstat",
        common::load()
    );
    per_iteration(&selected);
    for config in STEP_CONFIGS.iter().filter(|c| selected(c.name)) {
        step_cost(config);
    }
}

fn per_iteration(selected: &dyn Fn(&str) -> bool) {
    for config in CONFIGS.iter().filter(|c| selected(c.name)) {
        let groom = bench_groom(config.strands, config.vertices);
        let params = SimParams { iterations: config.iterations, ..SimParams::default() };
        let work_per_step = (config.strands * config.vertices) as f64 * config.iterations as f64;
        // About 0.3 s of work per run at 20 ns per vertex-iteration, at least 2 steps.
        let steps = ((1.5e7 / work_per_step).ceil() as usize).max(2);
        let mut single_cpu = 0.0;
        let mut single_wall = 0.0;
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut sim = Simulation::new(&groom, params.clone()).expect("bench simulation");
            pool.install(|| sim.step()); // warm caches and pages
            let mut wall = Vec::new();
            let mut cpu = Vec::new();
            for _ in 0..3 {
                let cpu_start = pool_cpu_ns(&pool);
                let start = Instant::now();
                pool.install(|| (0..steps).for_each(|_| sim.step()));
                let elapsed = start.elapsed().as_nanos() as f64;
                let work = work_per_step * steps as f64;
                wall.push(elapsed / work);
                if let (Some(a), Some(b)) = (cpu_start, pool_cpu_ns(&pool)) {
                    cpu.push((b - a) as f64 / work);
                }
            }
            let wall = median(wall);
            let cpu = if cpu.len() == 3 { median(cpu) } else { f64::NAN };
            if threads == 1 {
                (single_cpu, single_wall) = (cpu, wall);
                println!(
                    "{:<12} threads 1: {cpu:6.1} ns/vertex-iteration CPU time, {wall:6.1} wall ({steps} steps)",
                    config.name
                );
            } else {
                // Wall-clock speed-up is only meaningful on otherwise idle cores; the CPU-time
                // figure shows the parallel overhead (CPU per vertex-iteration summed over workers),
                // and `threads · single CPU / total CPU` is the speed-up idle cores would give.
                println!(
                    "{:<12} threads {threads}: {:6.1} ns/vertex-iteration wall (speed-up {:.2}x), CPU {cpu:6.1} summed over workers (parallel efficiency {:.2}, idle-core speed-up {:.2}x)",
                    config.name,
                    wall,
                    single_wall / wall,
                    single_cpu / cpu,
                    threads as f64 * single_cpu / cpu,
                );
            }
        }
    }
}
