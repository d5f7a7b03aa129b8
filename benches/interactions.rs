//! Interactions speed: ms per styling step with hair–hair contacts and water droplets, through
//! the same driver `coif style` uses (forces from a snapshot, solver with obstacle contacts,
//! wetness update). Configurations from issue 4: seed 2's groom (10,000 strands × 6 vertices,
//! 4 iterations) with 0, 100 and 1,000 droplets and contacts on (and, for reference, none and contacts off); a production groom
//! (100,000 × 32, 5 iterations) with contacts on and off, falling from its generated shape (every
//! step rebuilds the lists) and, as a shot starting from a settled groom, held in that shape by a
//! sag-free rest shape ("held", dry). Medians of 3 runs, 1 and 2 threads:
//! wall ms per step of the `process` stage, and CPU ms (all threads) per step of the whole
//! `style` call (set-up and the first list build included), which stays comparable under load.
//! Each configuration's checksum of the styled points (the same at any thread count, or the
//! line says it differs) shows whether a change altered the physics.
//! `cargo bench --bench interactions [-- FILTER]`.

mod common;
use common::{cpu_seconds, load, median};
use std::path::Path;

use coif::generate::{generate, GenerateParams};
use coif::style::{recipe, style, StyleOptions};

struct Config {
    name: &'static str,
    strands: usize,
    vertices: usize,
    iterations: u32,
    droplets: usize,
    contacts: bool,
    /// `[contacts] sample_spacing`: seed 2's sparse 4.8 cm segments favour longer pieces.
    spacing: f32,
    /// `[settings] sag_free`: the groom holds its shape under gravity from the start, as a shot
    /// starting from a settled groom does, instead of falling from its generated shape. Held
    /// grooms stay dry: wetting them after their rest shape is found makes them heavier and
    /// softer than it holds, and they fell (median 0.5 mm a step after 15 steps).
    sag_free: bool,
    steps: u32,
}

const CONFIGS: [Config; 10] = [
    Config {
        name: "seed2-10000x6x4-no-contacts",
        strands: 10_000,
        vertices: 6,
        iterations: 4,
        droplets: 0,
        contacts: false,
        spacing: 0.005,
        sag_free: false,
        steps: 60,
    },
    Config {
        name: "seed2-10000x6x4-water0",
        strands: 10_000,
        vertices: 6,
        iterations: 4,
        droplets: 0,
        contacts: true,
        spacing: 0.005,
        sag_free: false,
        steps: 60,
    },
    Config {
        name: "seed2-10000x6x4-water100",
        strands: 10_000,
        vertices: 6,
        iterations: 4,
        droplets: 100,
        contacts: true,
        spacing: 0.005,
        sag_free: false,
        steps: 60,
    },
    Config {
        name: "seed2-10000x6x4-water1000",
        strands: 10_000,
        vertices: 6,
        iterations: 4,
        droplets: 1000,
        contacts: true,
        spacing: 0.005,
        sag_free: false,
        steps: 60,
    },
    Config {
        name: "full-head-20000x32-contacts",
        strands: 20_000,
        vertices: 32,
        iterations: 5,
        droplets: 0,
        contacts: true,
        spacing: 0.002,
        sag_free: false,
        steps: 30,
    },
    Config {
        name: "full-head-20000x32-no-contacts",
        strands: 20_000,
        vertices: 32,
        iterations: 5,
        droplets: 0,
        contacts: false,
        spacing: 0.002,
        sag_free: false,
        steps: 30,
    },
    Config {
        name: "production-100000x32-contacts",
        strands: 100_000,
        vertices: 32,
        iterations: 5,
        droplets: 0,
        contacts: true,
        spacing: 0.002,
        sag_free: false,
        steps: 6,
    },
    Config {
        name: "production-100000x32-no-contacts",
        strands: 100_000,
        vertices: 32,
        iterations: 5,
        droplets: 0,
        contacts: false,
        spacing: 0.002,
        sag_free: false,
        steps: 6,
    },
    Config {
        name: "production-100000x32-held-contacts",
        strands: 100_000,
        vertices: 32,
        iterations: 5,
        droplets: 0,
        contacts: true,
        spacing: 0.002,
        sag_free: true,
        steps: 18,
    },
    Config {
        name: "production-100000x32-held-no-contacts",
        strands: 100_000,
        vertices: 32,
        iterations: 5,
        droplets: 0,
        contacts: false,
        spacing: 0.002,
        sag_free: true,
        steps: 18,
    },
];

fn main() {
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    println!("cores available: {cores}; ms per step, median of 3 runs; load {}", load());
    for config in CONFIGS.iter().filter(|c| filter.as_deref().is_none_or(|f| c.name.contains(f))) {
        let groom = generate(&GenerateParams {
            strands: config.strands,
            vertices_per_strand: config.vertices,
            length: 0.24,
            ..GenerateParams::default()
        })
        .expect("benchmark grooms generate");
        let water = if config.droplets > 0 {
            format!("[water]\ndroplets = {}\n", config.droplets)
        } else {
            String::new()
        };
        let seconds = config.steps as f32 / 360.0;
        let wet = if config.sag_free { "" } else { "[[stages]]\nkind = \"wet\"\nduration = 0.0\n" };
        let text = format!(
            "[settings]\niterations = {}\nsag_free = {}\n[contacts]\nhair_hair = {}\nsample_spacing = {}\n{water}\
             [[obstacles]]\nname = \"head\"\nshape = \"head\"\n\
             {wet}[[stages]]\nkind = \"process\"\nduration = {seconds}\n",
            config.iterations, config.sag_free, config.contacts, config.spacing
        );
        let recipe = recipe::parse(&text, Path::new("bench.toml")).expect("benchmark recipe parses");
        let mut checksums = Vec::new();
        for threads in [1, cores.min(2)] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let (mut wall, mut cpu) = (Vec::new(), Vec::new());
            for _ in 0..3 {
                let cpu_before = cpu_seconds();
                let styled = pool.install(|| style(&groom, &recipe, &StyleOptions::default())).unwrap();
                let process = styled.report.stages.last().expect("the process stage");
                wall.push(1e3 * process.wall_seconds / process.steps as f64);
                cpu.push(1e3 * (cpu_seconds() - cpu_before) / process.steps as f64);
                checksums.push(checksum(&styled.groom.points));
            }
            println!(
                "{:<36} {threads} thread(s): {:8.2} ms/step wall, {:8.2} ms/step CPU",
                config.name,
                median(wall),
                median(cpu)
            );
        }
        let same = checksums.iter().all(|c| c.to_bits() == checksums[0].to_bits());
        println!(
            "{:<36} checksum {:.9}{}",
            config.name,
            checksums[0],
            if same { "" } else { " (DIFFERS between runs or thread counts)" }
        );
    }
}

/// A weighted sum of the styled points' coordinates: any change in any vertex shows.
fn checksum(points: &[glam::Vec3]) -> f64 {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| (i % 97) as f64 * (p.x as f64 + 2.0 * p.y as f64 + 3.0 * p.z as f64))
        .sum()
}
