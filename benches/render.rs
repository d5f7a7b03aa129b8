//! Preview-render benchmark (issue 8): a 50,000-strand × 32-vertex groom at 512×512, 64 spp,
//! path depth 8, on 1 thread and on all threads. Prints time to image (BVH build included),
//! rays per second, and the image's noise: RMSE of a 128×128 window against a 1024-spp render of
//! the same window, for coif's Owen-scrambled Sobol sampler and for independent random samples
//! (the sampler Mitsuba's comparison figure used).
//!
//! `cargo bench --bench render` (release build). COIF_BENCH_RUNS (default 3) sets the runs per
//! configuration; medians are printed.

mod common;
use common::median;
use std::time::Instant;

use coif::generate::{generate, GenerateParams, Style};
use coif::render::image::rmse_linear;
use coif::render::sampler::SamplerKind;
use coif::render::{render, with_threads, RenderSettings};

/// CPU seconds (user + system) this process has used so far, from /proc (Linux); 0 elsewhere.
/// Other jobs on a shared machine stretch wall time but hardly this.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else { return 0.0 };
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')').map(|(_, r)| r).unwrap_or("");
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields.get(11..13).map_or(0.0, |f| f.iter().filter_map(|v| v.parse::<f64>().ok()).sum());
    ticks / 100.0 // USER_HZ is 100 on Linux
}

fn main() {
    let runs: usize = std::env::var("COIF_BENCH_RUNS").ok().and_then(|v| v.parse().ok()).unwrap_or(3);
    let all = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let groom = generate(&GenerateParams {
        strands: 50_000,
        vertices_per_strand: 32,
        style: Style::Wavy { amplitude: 0.008, wavelength: 0.06 },
        seed: 1,
        ..Default::default()
    })
    .expect("the benchmark groom generates");
    let settings = RenderSettings { width: 512, height: 512, spp: 64, max_depth: 8, ..Default::default() };
    println!(
        "groom: 50000 strands x 32 vertices; image 512x512, 64 spp, depth 8, {runs} runs per configuration"
    );

    let mut threads_list = vec![1];
    if all > 1 {
        threads_list.push(all);
    }
    let mut full_image = None;
    for &threads in &threads_list {
        let mut times = Vec::new();
        let mut rates = Vec::new();
        let mut builds = Vec::new();
        let mut cpus = Vec::new();
        for _ in 0..runs {
            let start = Instant::now();
            let cpu_start = cpu_seconds();
            let rendered =
                with_threads(Some(threads), || render(&groom, &settings, &|_, _| {})).unwrap().unwrap();
            let seconds = start.elapsed().as_secs_f64();
            cpus.push(cpu_seconds() - cpu_start);
            times.push(seconds);
            rates.push(rendered.stats.rays as f64 / rendered.stats.seconds / 1e6);
            builds.push(rendered.stats.build_seconds);
            full_image = Some(rendered.image);
        }
        let cpu = median(cpus);
        println!(
            "render/512x512/64spp/threads={threads}: time to image {:.2} s (median; runs {:?}), BVH build {:.2} s, \
             {:.2} Mrays/s, {cpu:.1} CPU-s (= {:.1} s on {threads} idle cores)",
            median(times.clone()),
            times.iter().map(|t| (t * 100.0).round() / 100.0).collect::<Vec<_>>(),
            median(builds),
            median(rates),
            cpu / threads as f64
        );
    }

    // Noise: a 128×128 window over the hair, against a 1024-spp render of it.
    let (x0, y0, w, h) = (192, 128, 128, 128);
    let window = Some((x0, y0, w, h));
    let crop = |image: &coif::render::image::Image| -> Vec<[f32; 4]> {
        (y0..y0 + h)
            .flat_map(|y| (x0..x0 + w).map(move |x| (x, y)))
            .map(|(x, y)| image.rgba[(y * 512 + x) as usize])
            .collect()
    };
    let reference_settings = RenderSettings { spp: 1024, window, seed: 12345, ..settings.clone() };
    let reference =
        with_threads(Some(all), || render(&groom, &reference_settings, &|_, _| {})).unwrap().unwrap().image;
    let sobol = rmse_linear(&crop(full_image.as_ref().unwrap()), &reference.rgba);
    let independent_settings =
        RenderSettings { window, sampler: SamplerKind::Independent, ..settings.clone() };
    let independent =
        with_threads(Some(all), || render(&groom, &independent_settings, &|_, _| {})).unwrap().unwrap().image;
    let independent = rmse_linear(&independent.rgba, &reference.rgba);
    println!(
        "noise/64spp: RMSE vs 1024 spp: sobol {sobol:.5}, independent {independent:.5} (ratio {:.2})",
        sobol / independent
    );
}
