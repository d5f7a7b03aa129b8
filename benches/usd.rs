//! USD export/import speed and memory: a 100,000 × 32 groom with widths and style attributes
//! written and read as `.usda` and `.usdc` by coif natively, against usd-core (pxr) writing and
//! reading the same data as `.usdc` (pxr's read copies every array out, as a groom reader must). Every measurement runs in its own process so its peak memory
//! (VmHWM) is its own; figures are medians of `COIF_BENCH_RUNS` (default 3) runs.
//!
//!     cargo bench --bench usd            (or `make bench-usd`)

mod common;
use common::{cpu_seconds, load, median};
use std::path::{Path, PathBuf};
use std::process::Command;

use coif::groom::{Attribute, AttributeRate, Groom};
use glam::Vec3;

const VERTICES: usize = 32;

/// Strands in the benchmark groom: 100,000, or `COIF_BENCH_STRANDS` (e.g. a smaller groom to count
/// instructions under callgrind: `valgrind --tool=callgrind BENCH --child write PATH`, minus the
/// instructions of `--child generate`).
fn strands() -> usize {
    std::env::var("COIF_BENCH_STRANDS").ok().and_then(|v| v.parse().ok()).unwrap_or(100_000)
}

/// A deterministic groom: helical strands with tapering widths, and the style attributes unless
/// `plain` (the groom issue 18's baseline figures were measured with: points and widths only).
fn bench_groom(plain: bool) -> Groom {
    let strands = strands();
    let mut groom = Groom { strand_offsets: Vec::with_capacity(strands + 1), ..Default::default() };
    groom.points.reserve_exact(strands * VERTICES);
    groom.widths.reserve_exact(strands * VERTICES);
    groom.strand_offsets.push(0);
    for s in 0..strands {
        let angle = s as f32 * 2.399_963;
        let root = Vec3::new(angle.cos(), 1.0 + (s as f32 * 0.001).sin() * 0.1, angle.sin()) * 0.09;
        for k in 0..VERTICES {
            let t = k as f32 / (VERTICES - 1) as f32;
            let curl = Vec3::new((t * 20.0 + angle).cos(), 0.0, (t * 20.0 + angle).sin()) * 0.006;
            groom.points.push(root + curl + Vec3::new(0.0, -0.25 * t, 0.0));
            groom.widths.push(80e-6 * (1.0 - 0.5 * t));
        }
        groom.strand_offsets.push(groom.points.len() as u32);
    }
    groom.strand_ids = (0..strands as u32).collect();
    if plain {
        return groom;
    }
    // Style attributes as coif's styling leaves them.
    let n = groom.vertex_count();
    let ramp =
        |count: usize, scale: f32| (0..count).map(|i| (i as f32 * scale).fract()).collect::<Vec<f32>>();
    groom.set_attribute(Attribute::new("wetness", AttributeRate::Vertex, 1, ramp(n, 0.0137)));
    groom.set_attribute(Attribute::new("bond_hydrogen", AttributeRate::Vertex, 1, ramp(n, 0.0071)));
    groom.set_attribute(Attribute::new("rest_darboux", AttributeRate::Vertex, 3, ramp(3 * n, 0.00917)));
    groom.set_attribute(Attribute::new("melanin", AttributeRate::Strand, 1, ramp(strands, 0.29)));
    groom
}

/// Bytes the groom occupies in memory (points, widths, offsets, ids, attributes).
fn groom_bytes(groom: &Groom) -> usize {
    groom.points.len() * 12
        + groom.widths.len() * 4
        + groom.strand_offsets.len() * 4
        + groom.strand_ids.len() * 4
        + groom.attributes.iter().map(|a| a.data.len() * 4).sum::<usize>()
}

fn status_kb(field: &str) -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix(field).and_then(|r| r.trim_start_matches(':').split_whitespace().next()))
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

/// One measurement in this (child) process; prints the same JSON as the pxr script.
fn child(command: &str, path: &Path) {
    // `-plain` commands use the groom without style attributes.
    let (command, plain) = command.strip_suffix("-plain").map_or((command, false), |c| (c, true));
    let baseline = status_kb("VmRSS");
    let mut read_back = None;
    let cpu_start = cpu_seconds();
    let seconds = match command {
        "write" | "write-usdc" => {
            let groom = bench_groom(plain);
            let start = std::time::Instant::now();
            coif::io::write_groom(path, &groom).expect("write");
            start.elapsed().as_secs_f64()
        }
        "format" => {
            // The writer alone: formatting into a sink, no file system.
            let groom = bench_groom(plain);
            let start = std::time::Instant::now();
            coif::io::usda::write(&groom, &mut std::io::sink()).expect("format");
            start.elapsed().as_secs_f64()
        }
        "generate" => {
            // Only the groom: the baseline to subtract from a counted write or read.
            std::hint::black_box(bench_groom(plain));
            0.0
        }
        "read" => {
            let start = std::time::Instant::now();
            read_back = Some(coif::io::read_groom(path, &Default::default()).expect("read").groom);
            start.elapsed().as_secs_f64()
        }
        other => panic!("unknown child command {other}"),
    };
    let cpu = cpu_seconds() - cpu_start;
    let peak = status_kb("VmHWM");
    if let Some(groom) = read_back {
        assert!(groom == bench_groom(plain), "read back exactly what was written");
    }
    println!("{{\"seconds\": {seconds}, \"cpu_seconds\": {cpu}, \"peak_kb\": {peak}, \"baseline_kb\": {baseline}}}");
}

struct Sample {
    seconds: f64,
    cpu_seconds: f64,
    peak_kb: f64,
    baseline_kb: f64,
}

fn run(mut command: Command) -> Sample {
    let output = command.output().expect("benchmark child runs");
    assert!(output.status.success(), "{command:?} failed: {}", String::from_utf8_lossy(&output.stderr));
    let text = String::from_utf8_lossy(&output.stdout);
    let value: serde_json::Value =
        serde_json::from_str(text.trim().lines().last().unwrap()).expect("JSON figures");
    Sample {
        seconds: value["seconds"].as_f64().unwrap(),
        cpu_seconds: value["cpu_seconds"].as_f64().unwrap(),
        peak_kb: value["peak_kb"].as_f64().unwrap(),
        baseline_kb: value["baseline_kb"].as_f64().unwrap(),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("--child") {
        return child(&args[2], Path::new(&args[3]));
    }
    let runs: usize = std::env::var("COIF_BENCH_RUNS").ok().and_then(|v| v.parse().ok()).unwrap_or(3);
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let python =
        std::env::var_os("COIF_PYTHON").map(PathBuf::from).unwrap_or(root.join(".deps/venv/bin/python"));
    let exe = std::env::current_exe().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let groom = bench_groom(false);
    let groom_mb = groom_bytes(&groom) as f64 / 1e6;

    // The same data for pxr, as raw arrays it loads before its timer starts.
    let raw = dir.path().join("raw");
    std::fs::create_dir(&raw).unwrap();
    let bytes_of = |values: &[u8], name: &str| std::fs::write(raw.join(name), values).unwrap();
    bytes_of(bytemuck::cast_slice(&groom.points), "points.f32");
    bytes_of(bytemuck::cast_slice(&groom.widths), "widths.f32");
    let counts: Vec<i32> = groom.vertex_counts().map(|c| c as i32).collect();
    bytes_of(bytemuck::cast_slice(&counts), "counts.i32");
    let ids: Vec<i32> = groom.strand_ids.iter().map(|&i| i as i32).collect();
    bytes_of(bytemuck::cast_slice(&ids), "ids.i32");
    let mut manifest = Vec::new();
    for attribute in &groom.attributes {
        bytes_of(bytemuck::cast_slice(&attribute.floats()[..]), &format!("{}.f32", attribute.name));
        let usd_type = if attribute.components == 3 { "float3[]" } else { "float[]" };
        let interpolation = if attribute.rate == AttributeRate::Vertex { "vertex" } else { "uniform" };
        manifest.push(
            serde_json::json!({"name": attribute.name, "type": usd_type, "interpolation": interpolation}),
        );
    }
    std::fs::write(raw.join("attributes.json"), serde_json::to_string(&manifest).unwrap()).unwrap();
    drop(groom);

    let usda = dir.path().join("coif.usda");
    let pxr_usdc = dir.path().join("pxr.usdc");
    let coif_usdc = dir.path().join("coif.usdc");
    let plain_usda = dir.path().join("plain.usda");
    let script = root.join("benches/usd_pxr.py");
    let ours = |command: &str, path: &Path| {
        let mut c = Command::new(&exe);
        c.args(["--child", command]).arg(path);
        c
    };
    let theirs = |args: &[&Path]| {
        let mut c = Command::new(&python);
        c.arg(&script).args(args);
        c
    };
    type Config<'a> = (&'a str, Box<dyn Fn() -> Command + 'a>, &'a Path);
    let configs: Vec<Config> = vec![
        ("coif .usda write (native)", Box::new(|| ours("write", &usda)), &usda),
        ("coif .usda formatting only (no disk)", Box::new(|| ours("format", &usda)), &usda),
        ("coif .usda read (native)", Box::new(|| ours("read", &usda)), &usda),
        ("pxr .usdc write", Box::new(|| theirs(&[Path::new("write"), &raw, &pxr_usdc])), &pxr_usdc),
        ("pxr .usdc read", Box::new(|| theirs(&[Path::new("read"), &pxr_usdc])), &pxr_usdc),
        ("coif .usdc write (native)", Box::new(|| ours("write-usdc", &coif_usdc)), &coif_usdc),
        ("coif .usdc read (native)", Box::new(|| ours("read", &coif_usdc)), &coif_usdc),
        ("coif .usda write, issue-18 groom", Box::new(|| ours("write-plain", &plain_usda)), &plain_usda),
        ("coif .usda read, issue-18 groom", Box::new(|| ours("read-plain", &plain_usda)), &plain_usda),
    ];
    println!(
        "USD benchmark: {} strands x {VERTICES} vertices, groom in memory {groom_mb:.1} MB, {} threads, median of {runs} runs, load {}",
        strands(),
        rayon::current_num_threads(),
        load()
    );
    println!(
        "{:<38} {:>8} {:>8} {:>8} {:>8} {:>8} {:>10} {:>8}",
        "configuration", "seconds", "MB/s", "CPU s", "peak MB", "data MB", "data/groom", "file MB"
    );
    let mut medians = Vec::new();
    let only = std::env::var("COIF_BENCH_ONLY").unwrap_or_default();
    for (name, command, file) in &configs {
        if !name.contains(only.as_str()) {
            medians.push((f64::NAN, f64::NAN));
            continue;
        }
        let samples: Vec<Sample> = (0..runs).map(|_| run(command())).collect();
        let seconds = median(samples.iter().map(|s| s.seconds).collect());
        let cpu = median(samples.iter().map(|s| s.cpu_seconds).collect());
        let peak = median(samples.iter().map(|s| s.peak_kb).collect()) / 1e3;
        // Peak above the process's resident size before any groom data (interpreter, libraries).
        let data = median(samples.iter().map(|s| s.peak_kb - s.baseline_kb).collect()) / 1e3;
        let file_mb = std::fs::metadata(file).map(|m| m.len() as f64 / 1e6).unwrap_or(0.0);
        println!(
            "{name:<38} {seconds:>8.3} {:>8.1} {cpu:>8.2} {peak:>8.1} {data:>8.1} {:>10.2} {file_mb:>8.1}",
            groom_mb / seconds,
            data / groom_mb
        );
        medians.push((seconds, cpu));
    }
    let ratio =
        |pxr: usize, ours: usize| (medians[pxr].0 / medians[ours].0, medians[pxr].1 / medians[ours].1);
    let (write, read) = (ratio(3, 0), ratio(4, 2));
    println!(
        "native .usda vs pxr .usdc (pxr time / coif time, wall and CPU): write {:.2}x / {:.2}x, read {:.2}x / {:.2}x",
        write.0, write.1, read.0, read.1
    );
    let (write, read) = (ratio(3, 5), ratio(4, 6));
    println!(
        "native .usdc vs pxr .usdc (pxr time / coif time, wall and CPU): write {:.2}x / {:.2}x, read {:.2}x / {:.2}x (target: > 1x)",
        write.0, write.1, read.0, read.1
    );
    println!("load at the end: {}", load());
    // Issue 18 measured the native .usda at 0.69 s write and 0.49 s read (wall) for this groom
    // without style attributes, at commit edb97b9; the issue asks for at least twice as fast.
    let (write, read) = (medians[7].0, medians[8].0);
    println!(
        ".usda, issue-18 groom (points and widths): write {write:.3} s, read {read:.3} s; issue 18's baseline 0.69 s / 0.49 s: {:.2}x / {:.2}x faster (target: >= 2x)",
        0.69 / write,
        0.49 / read
    );
}
