//! Solver speed: ns per vertex-iteration (one stretch–shear, one bend–twist and one length-solve
//! row per vertex and iteration, plus the per-step prediction and velocity update amortised) for
//! the configurations, on 1 thread and on 2 threads. Prints the median of 3 runs.
//! `cargo bench --bench sim [-- FILTER]`, FILTER matching a configuration name.
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

fn main() {
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    // COIF_BENCH_WALL=1 measures one thread by wall time too (on an otherwise idle machine).
    let use_cpu_time = std::env::var_os("COIF_BENCH_WALL").is_none();
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    println!(
        "cores available: {cores}; 1 thread timed by {}",
        if use_cpu_time { "thread CPU time" } else { "wall clock" }
    );
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
        let mut single = 0.0;
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut runs: Vec<f64> = pool.install(|| {
                let mut sim = Simulation::new(&groom, params.clone()).expect("bench simulation");
                sim.step(); // warm caches and pages
                (0..3)
                    .map(|_| {
                        let start = Instant::now();
                        let cpu_start = thread_cpu_ns();
                        for _ in 0..steps {
                            sim.step();
                        }
                        let wall = start.elapsed().as_nanos() as f64;
                        // On one thread, CPU time of the worker is robust against other load on
                        // the machine; with more threads only wall time says anything.
                        let time = match (threads, cpu_start, thread_cpu_ns()) {
                            (1, Some(a), Some(b)) if use_cpu_time => (b - a) as f64,
                            _ => wall,
                        };
                        time / (work_per_step * steps as f64)
                    })
                    .collect()
            });
            runs.sort_by(f64::total_cmp);
            let median = runs[1];
            if threads == 1 {
                single = median;
            }
            println!(
                "{:<12} threads {threads}: {median:6.1} ns/vertex-iteration (runs {:.1} {:.1} {:.1}; {steps} steps){}",
                config.name,
                runs[0],
                runs[1],
                runs[2],
                if threads > 1 { format!("  speed-up {:.2}x", single / median) } else { String::new() }
            );
        }
    }
}
