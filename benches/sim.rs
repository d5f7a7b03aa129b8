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

fn main() {
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    println!("cores available: {cores}");
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
                        for _ in 0..steps {
                            sim.step();
                        }
                        start.elapsed().as_nanos() as f64 / (work_per_step * steps as f64)
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
