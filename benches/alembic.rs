//! Alembic write and read throughput for 100,000 strands × 32 vertices, static and 24 frames,
//! against usd-core writing and reading the same curves as `.usdc` in the same run.
//! Prints medians of `COIF_BENCH_RUNS` runs (default 3). `COIF_BENCH_STRANDS` shrinks the groom.
//! MB/s counts the curve payload (positions per frame, widths, vertex counts), the same for both.
//!
//! Rows: `write` streams the same data as the usd-core baseline (no velocities) to a plain file,
//! as usd-core's `Save` does (no fsync); `write+vel` adds `.velocities` (coif's default for
//! animation); `write API` is `coif::io`'s atomic path (velocities, fsync, rename), which waits for
//! the disk. `read` maps the file and builds owned grooms (every frame for the animation).
//! Every write starts after `sync`, into a new file, for coif and usd-core alike.

mod common;
use common::median;
use std::path::Path;
use std::process::Command;
use std::time::Instant;

use std::fs::File;
use std::io::BufWriter;

use coif::io::alembic::{self, AlembicWriteOptions, AnimationWriter, CurvesWriter};
use coif::io::{input, read_groom, write_groom, ImportOptions};
use coif::Groom;
use glam::Vec3;

const VERTICES: usize = 32;
const FRAMES: usize = 24;

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// Strands hanging from a grid, gently waved; widths taper.
fn groom(strands: usize) -> Groom {
    let side = (strands as f32).sqrt().ceil() as usize;
    let mut list = Vec::with_capacity(strands);
    for s in 0..strands {
        let root = Vec3::new((s % side) as f32 * 1e-3, 0.0, (s / side) as f32 * 1e-3);
        list.push(
            (0..VERTICES)
                .map(|k| root + Vec3::new((k as f32 * 0.7).sin() * 2e-3, -(k as f32) * 7e-3, 0.0))
                .collect::<Vec<_>>(),
        );
    }
    let mut g = Groom::from_strands(&list, 0.0);
    g.widths = (0..g.vertex_count())
        .map(|i| 80e-6 * (1.0 - 0.5 * (i % VERTICES) as f32 / VERTICES as f32))
        .collect();
    g
}

/// Removes the given files and waits until the kernel has written all dirty pages back.
fn settle(files: &[&Path]) {
    for file in files {
        let _ = std::fs::remove_file(file);
    }
    Command::new("sync").status().unwrap();
}

#[derive(Default)]
struct Figures {
    write: Vec<f64>,
    write_velocities: Vec<f64>,
    write_api: Vec<f64>,
    read: Vec<f64>,
}

/// Streams `frames` (each swapped into `groom` in turn) through a CurvesWriter on a plain file.
fn write_plain(path: &Path, groom: &mut Groom, frames: &mut [Vec<Vec3>], velocities: bool) -> f64 {
    let start = Instant::now();
    let options = AlembicWriteOptions { velocities, ..Default::default() };
    let out = BufWriter::with_capacity(1 << 20, File::create(path).unwrap());
    let mut writer = CurvesWriter::new(out, groom, &options, frames.len() > 1).unwrap();
    for points in frames.iter_mut() {
        std::mem::swap(&mut groom.points, points);
        writer.write_frame(groom).unwrap();
        std::mem::swap(&mut groom.points, points);
    }
    drop(writer.finish().unwrap());
    start.elapsed().as_secs_f64()
}

fn main() {
    let strands = env_usize("COIF_BENCH_STRANDS", 100_000);
    let runs = env_usize("COIF_BENCH_RUNS", 3);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let python = root.join(".deps/venv/bin/python");
    let script = root.join("benches/usd_curves_baseline.py");
    let dir = tempfile::tempdir_in(root.join("target")).unwrap();
    let base = groom(strands);
    let counts: Vec<i32> = base.vertex_counts().map(|c| c as i32).collect();
    std::fs::write(dir.path().join("points.f32"), bytemuck::cast_slice(&base.points)).unwrap();
    std::fs::write(dir.path().join("widths.f32"), bytemuck::cast_slice(&base.widths)).unwrap();
    std::fs::write(dir.path().join("counts.i32"), bytemuck::cast_slice(&counts)).unwrap();
    println!(
        "alembic bench: {strands} strands × {VERTICES} vertices, medians of {runs} runs, {} rayon threads",
        rayon::current_num_threads()
    );

    for frames in [1, FRAMES] {
        let label = if frames == 1 { "static" } else { "24 frames" };
        let payload =
            (base.points.len() * 12 * frames + base.widths.len() * 4 + counts.len() * 4) as f64 / 1e6;
        // Frames are made before the clock starts: frame f = base + f · (0.001, 0, 0).
        let mut frame_points: Vec<Vec<Vec3>> = (0..frames)
            .map(|f| base.points.iter().map(|p| *p + Vec3::new(0.001, 0.0, 0.0) * f as f32).collect())
            .collect();
        let path = dir.path().join("bench.abc");
        let (mut coif, mut usd) = (Figures::default(), Figures::default());
        let mut usd_bytes = 0;
        let usd_path = dir.path().join("baseline.usdc");
        let mut abc_bytes = 0;
        for _ in 0..runs {
            let mut g = base.clone();
            // Every timed write starts from a clean page cache and a new file, for coif and
            // usd-core alike, so one write's dirty pages do not slow down the next.
            settle(&[&path, &usd_path]);
            coif.write.push(write_plain(&path, &mut g, &mut frame_points, false));

            let start = Instant::now();
            let vertices = if frames == 1 {
                read_groom(&path, &ImportOptions::default()).unwrap().groom.vertex_count()
            } else {
                let bytes = input::map_file(&path).unwrap();
                alembic::read_all_frames(&bytes, &path, false).unwrap().iter().map(Groom::vertex_count).sum()
            };
            coif.read.push(start.elapsed().as_secs_f64());
            assert_eq!(vertices, base.vertex_count() * frames);
            abc_bytes = std::fs::metadata(&path).unwrap().len();

            settle(&[&path]);
            coif.write_velocities.push(write_plain(&path, &mut g, &mut frame_points, true));

            settle(&[&path]);
            let start = Instant::now();
            if frames == 1 {
                write_groom(&path, &g).unwrap();
            } else {
                let mut writer =
                    AnimationWriter::create(&path, &g, &AlembicWriteOptions::default(), true).unwrap();
                for points in frame_points.iter_mut() {
                    std::mem::swap(&mut g.points, points);
                    writer.write_frame(&g).unwrap();
                    std::mem::swap(&mut g.points, points);
                }
                writer.finish().unwrap();
            }
            coif.write_api.push(start.elapsed().as_secs_f64());
            settle(&[&path]);

            let out =
                Command::new(&python).arg(&script).arg(dir.path()).arg(frames.to_string()).output().unwrap();
            assert!(
                out.status.success(),
                "usd-core baseline failed: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            let text = String::from_utf8_lossy(&out.stdout);
            let field = |key: &str| -> f64 {
                text.split_whitespace()
                    .find_map(|kv| kv.strip_prefix(key)?.strip_prefix('=')?.parse().ok())
                    .unwrap()
            };
            usd.write.push(field("write_s"));
            usd.read.push(field("read_s"));
            usd_bytes = field("bytes") as u64;
        }
        let (cw, cr, uw, ur) = (median(coif.write), median(coif.read), median(usd.write), median(usd.read));
        let (cv, ca) = (median(coif.write_velocities), median(coif.write_api));
        println!(
            "{label}: payload {payload:.1} MB; .abc {:.1} MB, .usdc {:.1} MB",
            abc_bytes as f64 / 1e6,
            usd_bytes as f64 / 1e6
        );
        println!(
            "  write  coif {:8.1} MB/s ({cw:.3} s)   usd-core {:8.1} MB/s ({uw:.3} s)   speed-up {:.2}x",
            payload / cw,
            payload / uw,
            uw / cw
        );
        println!("  write+vel coif {:8.1} MB/s ({cv:.3} s)", payload / cv);
        println!("  write API coif {:8.1} MB/s ({ca:.3} s, velocities, fsync)", payload / ca);
        println!(
            "  read   coif {:8.1} MB/s ({cr:.3} s)   usd-core {:8.1} MB/s ({ur:.3} s)   speed-up {:.2}x",
            payload / cr,
            payload / ur,
            ur / cr
        );
    }
}
