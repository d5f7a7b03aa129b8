//! Production scale through guides: the full-head perm (`grooms/recipes/perm_full_head.toml`)
//! on a generated 100,000 × 32 head, simulated on guides and interpolated to every strand, end
//! to end (generate, style, interpolate, export USD). Prints wall seconds per phase and the peak
//! resident memory. One run per configuration by default (each takes minutes on 2 cores);
//! `COIF_BENCH_RUNS=3` for medians. `cargo bench --bench guides [-- FILTER]`.
mod common;
use common::median;
use std::path::Path;
use std::time::Instant;

use coif::generate::{generate, GenerateParams};
use coif::style::{recipe, style, StyleOptions};

struct Config {
    name: &'static str,
    strands: usize,
    guides: usize,
}

const CONFIGS: [Config; 3] = [
    Config { name: "perm-20000x32-from-1000", strands: 20_000, guides: 1_000 },
    Config { name: "perm-100000x32-from-2000", strands: 100_000, guides: 2_000 },
    Config { name: "perm-100000x32-from-5000", strands: 100_000, guides: 5_000 },
];

/// Peak resident memory of this process so far, MB (Linux), if known.
fn peak_rss_mb() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1024.0)
}

fn main() {
    let filter = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let runs: usize = std::env::var("COIF_BENCH_RUNS").ok().and_then(|r| r.parse().ok()).unwrap_or(1);
    let mut recipe = recipe::load(Path::new("grooms/recipes/perm_full_head.toml")).unwrap();
    let out = tempfile::tempdir().unwrap();
    for config in CONFIGS.iter().filter(|c| filter.as_deref().is_none_or(|f| c.name.contains(f))) {
        recipe.guides = Some(coif::guides::GuideSpec { count: Some(config.guides), ..Default::default() });
        let (mut styling, mut totals) = (Vec::new(), Vec::new());
        for _ in 0..runs {
            let start = Instant::now();
            let groom = generate(&GenerateParams {
                strands: config.strands,
                vertices_per_strand: 32,
                length: 0.24,
                seed: 21,
                ..GenerateParams::default()
            })
            .unwrap();
            let styled_at = Instant::now();
            let styled = style(&groom, &recipe, &StyleOptions::default()).unwrap();
            styling.push(styled_at.elapsed().as_secs_f64());
            coif::io::write_groom(&out.path().join("permed.usda"), &styled.groom).unwrap();
            totals.push(start.elapsed().as_secs_f64());
        }
        println!(
            "{:<28} style+interpolate {:>7.1} s   end to end {:>7.1} s   peak memory {:>6.0} MB   ({} run(s))",
            config.name,
            median(styling),
            median(totals),
            peak_rss_mb().unwrap_or(f64::NAN),
            runs
        );
    }
}
