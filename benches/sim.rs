//! Solver speed: ns per vertex-iteration (one stretch–shear, one bend–twist and one direct
//! stretch–shear row per vertex and iteration, plus the per-step prediction and velocity update
//! amortised) for the configurations, on 1 thread and on 2 threads. Prints the median of 3
//! runs, by wall clock and by CPU time of the workers (robust when other processes share the
//! cores). `cargo bench --bench sim [-- FILTER]`, FILTER matching a configuration name.

mod common;
use common::median;
use std::time::Instant;

use coif::generate::{generate, GenerateParams, Style};
use coif::sim::{SimParams, Simulation};

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

/// CPU time of the calling thread in ns (Linux `schedstat`), if available.
fn thread_cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// CPU time of all the pool's workers in ns.
fn pool_cpu_ns(pool: &rayon::ThreadPool) -> Option<u64> {
    pool.broadcast(|_| thread_cpu_ns()).into_iter().sum()
}

fn main() {
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    println!("cores available: {cores}; medians of 3 runs; CPU time from /proc/thread-self/schedstat");
    for config in CONFIGS.iter().filter(|c| filter.as_deref().is_none_or(|f| c.name.contains(f))) {
        let groom = generate(&GenerateParams {
            strands: config.strands,
            vertices_per_strand: config.vertices,
            style: Style::Wavy { amplitude: 0.01, wavelength: 0.08 },
            ..GenerateParams::default()
        })
        .expect("bench groom");
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
