//! Writes a static and an animated Alembic groom plus the expected strand counts and positions
//! as JSON, for an outside importer to check (`make check-blender` runs Blender's on them).
//!
//! Usage: cargo run --release --example alembic_check_files -- OUT_DIR [STRANDS]
use std::path::PathBuf;

use coif::generate::{generate, GenerateParams, Style};
use coif::io::alembic::{AlembicWriteOptions, AnimationWriter};
use coif::io::write_groom;
use glam::Vec3;
use serde_json::json;

const FRAMES: usize = 24;

fn main() -> coif::Result<()> {
    let out = PathBuf::from(std::env::args().nth(1).expect("usage: alembic_check_files OUT_DIR"));
    std::fs::create_dir_all(&out).map_err(|e| coif::Error::io(&out, e))?;
    let strands = std::env::args().nth(2).and_then(|s| s.parse().ok()).unwrap_or(300);
    let params = GenerateParams {
        strands,
        vertices_per_strand: 12,
        style: Style::Wavy { amplitude: 0.008, wavelength: 0.06 },
        seed: 3,
        ..Default::default()
    };
    let groom = generate(&params)?;
    write_groom(&out.join("static.abc"), &groom)?;

    // Frame f sways every vertex sideways in proportion to its distance from the root.
    let frame = |f: usize| {
        let mut g = groom.clone();
        for s in 0..g.strand_count() {
            let range = g.strand_range(s);
            let n = range.len();
            for (k, i) in range.enumerate() {
                g.points[i] += Vec3::new(0.02 * (f as f32 * 0.4).sin() * k as f32 / n as f32, 0.0, 0.0);
            }
        }
        g
    };
    let animated_path = out.join("animated.abc");
    let mut writer = AnimationWriter::create(&animated_path, &groom, &AlembicWriteOptions::default(), true)?;
    let mut expected_frames = Vec::new();
    for f in 0..FRAMES {
        let g = frame(f);
        writer.write_frame(&g)?;
        expected_frames.push(g.points.iter().map(|p| p.to_array()).collect::<Vec<_>>());
    }
    writer.finish()?;

    let expected = json!({
        "strands": groom.strand_count(),
        "vertices": groom.vertex_count(),
        "vertex_counts": groom.vertex_counts().collect::<Vec<_>>(),
        "widths": groom.widths,
        "static_points": groom.points.iter().map(|p| p.to_array()).collect::<Vec<_>>(),
        "frames": expected_frames,
    });
    let path = out.join("expected.json");
    std::fs::write(&path, serde_json::to_vec(&expected).unwrap()).map_err(|e| coif::Error::io(&path, e))?;
    eprintln!(
        "wrote {}, {} and {}",
        out.join("static.abc").display(),
        animated_path.display(),
        path.display()
    );
    Ok(())
}
