//! Issue 14's speed figure: writing and reading a groom of several curve groups with a scalp mesh
//! against the same strands as one group, in `.usda`, `.usdc` and `.abc`, through coif's own
//! `write_groom` / `read_groom` (atomic writes with fsync, validated reads).
//!
//! The grouped groom is the single one split as production files come: 2 % of the strands are
//! Catmull-Rom guides (`purpose = "guide"`), the rest linear children in three groups, plus a
//! scalp mesh of 20,000 triangles with normals. Runs alternate between the two grooms; figures
//! are medians of `COIF_BENCH_RUNS` (default 5). `COIF_BENCH_STRANDS` sets the size (default
//! 100,000 × 32); `COIF_BENCH_KEEP=DIR` leaves the files in `DIR` (to profile `coif info` on them).

mod common;
use common::{cpu_seconds, load, median};

use std::path::Path;
use std::time::Instant;

use coif::groom::{AttributeKind, CurveBasis, CurveWrap, Groom};
use coif::groups::CurveGroup;
use coif::io::{read_groom, write_groom, ImportOptions};
use coif::surface_mesh::{MeshInterpolation, MeshPrimvar, SurfaceMesh};
use glam::Vec3;

const VERTICES: usize = 32;

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

/// Strands from a cap of roots, gently curled, tapering.
fn strands(count: usize) -> Vec<(Vec<Vec3>, Vec<f32>)> {
    (0..count)
        .map(|s| {
            let angle = s as f32 * 2.399_963;
            let root = Vec3::new(angle.cos(), 1.0 + (s as f32 * 0.001).sin() * 0.1, angle.sin()) * 0.09;
            (0..VERTICES)
                .map(|k| {
                    let t = k as f32 / (VERTICES - 1) as f32;
                    let curl = Vec3::new((t * 20.0 + angle).cos(), 0.0, (t * 20.0 + angle).sin()) * 0.006;
                    (root + curl + Vec3::new(0.0, -0.25 * t, 0.0), 80e-6 * (1.0 - 0.5 * t))
                })
                .unzip()
        })
        .collect()
}

fn groom_of(strands: &[(Vec<Vec3>, Vec<f32>)], first_id: u32) -> Groom {
    let points: Vec<&[Vec3]> = strands.iter().map(|(p, _)| p.as_slice()).collect();
    let mut groom = Groom::from_strands(&points, 0.0);
    groom.widths = strands.iter().flat_map(|(_, w)| w.iter().copied()).collect();
    groom.strand_ids = (first_id..first_id + strands.len() as u32).collect();
    groom
}

/// A UV sphere of about 20,000 triangles around the roots, with vertex normals.
fn scalp() -> SurfaceMesh {
    let (rings, segments) = (100u32, 100u32);
    let mut mesh = SurfaceMesh { path: "/Groom/Scalp".into(), ..Default::default() };
    for r in 0..=rings {
        let polar = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let azimuth = std::f32::consts::TAU * s as f32 / segments as f32;
            let normal = Vec3::new(polar.sin() * azimuth.cos(), polar.cos(), polar.sin() * azimuth.sin());
            mesh.points.push(normal * 0.088 + Vec3::Y * 0.09);
        }
    }
    for r in 0..rings {
        for s in 0..segments {
            let at = |r: u32, s: u32| r * segments + s % segments;
            mesh.face_counts.extend([3, 3]);
            mesh.face_indices.extend([at(r, s), at(r + 1, s), at(r + 1, s + 1)]);
            mesh.face_indices.extend([at(r, s), at(r + 1, s + 1), at(r, s + 1)]);
        }
    }
    let normals: Vec<f32> =
        mesh.points.iter().flat_map(|p| (*p - Vec3::Y * 0.09).normalize().to_array()).collect();
    mesh.primvars.push(MeshPrimvar {
        name: MeshPrimvar::NORMALS.into(),
        kind: AttributeKind::Normal,
        components: 3,
        interpolation: MeshInterpolation::Vertex,
        values: normals.into(),
        indices: None,
    });
    mesh
}

/// The same strands as guides and three groups of children, with a scalp.
fn grouped(all: &[(Vec<Vec3>, Vec<f32>)]) -> Groom {
    let guides = all.len() / 50;
    let children = all.len() - guides;
    let mut parts = vec![(0, guides, "/Groom/Guides", CurveBasis::CatmullRom)];
    for g in 0..3 {
        let (start, end) = (guides + children * g / 3, guides + children * (g + 1) / 3);
        parts.push((start, end, ["/Groom/Fringe", "/Groom/Crown", "/Groom/Back"][g], CurveBasis::Linear));
    }
    let mut groups = Vec::new();
    for (start, end, name, basis) in parts {
        let mut part = groom_of(&all[start..end], start as u32);
        let mut group = CurveGroup::new(name, basis, CurveWrap::Nonperiodic);
        if basis == CurveBasis::CatmullRom {
            group.wrap = CurveWrap::Pinned;
            group.purpose = Some("guide".into());
        }
        part.set_single_group(group);
        groups.push(part);
    }
    let mut groom = Groom::concat(groups).expect("the groups fit");
    groom.meshes.push(scalp());
    groom
}

struct Figures {
    write_wall: Vec<f64>,
    write_cpu: Vec<f64>,
    read_wall: Vec<f64>,
    read_cpu: Vec<f64>,
}

fn measure(groom: &Groom, path: &Path, figures: &mut Figures) {
    let _ = std::fs::remove_file(path);
    let (wall, cpu) = (Instant::now(), cpu_seconds());
    write_groom(path, groom).expect("write");
    figures.write_wall.push(wall.elapsed().as_secs_f64());
    figures.write_cpu.push(cpu_seconds() - cpu);
    let (wall, cpu) = (Instant::now(), cpu_seconds());
    let loaded = read_groom(path, &ImportOptions::default()).expect("read");
    figures.read_wall.push(wall.elapsed().as_secs_f64());
    figures.read_cpu.push(cpu_seconds() - cpu);
    assert_eq!(loaded.groom.strand_count(), groom.strand_count());
    assert_eq!(loaded.groom.meshes.len(), groom.meshes.len());
}

fn main() {
    let count = env_usize("COIF_BENCH_STRANDS", 100_000);
    let runs = env_usize("COIF_BENCH_RUNS", 5).max(1);
    let all = strands(count);
    let single = groom_of(&all, 0);
    let split = grouped(&all);
    drop(all);
    let temporary = tempfile::tempdir().expect("temporary directory");
    let keep = std::env::var_os("COIF_BENCH_KEEP").map(std::path::PathBuf::from);
    let dir = keep.as_deref().unwrap_or(temporary.path());
    println!("groups + scalp against one group: {count} x {VERTICES}, medians of {runs}, load {}", load());
    println!(
        "{:<6} {:<7} {:>10} {:>10} {:>10} {:>10} {:>9} {:>9}",
        "format", "groom", "write s", "write cpu", "read s", "read cpu", "write ×", "read ×"
    );
    for ext in ["usda", "usdc", "abc"] {
        let new = || Figures { write_wall: vec![], write_cpu: vec![], read_wall: vec![], read_cpu: vec![] };
        let (mut one, mut many) = (new(), new());
        for _ in 0..runs {
            measure(&single, &dir.join(format!("single.{ext}")), &mut one);
            measure(&split, &dir.join(format!("groups.{ext}")), &mut many);
        }
        let row = |name: &str, f: Figures, base: Option<(f64, f64)>| {
            let (write_cpu, read_cpu) = (median(f.write_cpu), median(f.read_cpu));
            let ratio = |a: f64, b: f64| if b > 0.0 { format!("{:.3}", a / b) } else { "-".into() };
            let (w, r) =
                base.map_or(("".into(), "".into()), |(bw, br)| (ratio(write_cpu, bw), ratio(read_cpu, br)));
            println!(
                "{ext:<6} {name:<7} {:>10.3} {:>10.3} {:>10.3} {:>10.3} {w:>9} {r:>9}",
                median(f.write_wall),
                write_cpu,
                median(f.read_wall),
                read_cpu
            );
            (write_cpu, read_cpu)
        };
        let base = row("single", one, None);
        row("groups", many, Some(base));
    }
    println!(
        "(× is CPU time of the grouped groom over the single one; the grouped file also holds the scalp)"
    );
}
