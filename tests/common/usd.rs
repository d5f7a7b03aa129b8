//! Helpers for the USD tests: run usd-core (pxr) through `tests/usd/pxr_probe.py` with the
//! project's Python and read what it reports.
#![allow(dead_code)]
use std::path::{Path, PathBuf};
use std::process::Command;

use coif::groom::{Attribute, AttributeRate, CurveBasis, Groom};
use glam::Vec3;

pub fn python() -> PathBuf {
    std::env::var_os("COIF_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join(".deps/venv/bin/python"))
}

/// Runs the probe script and returns its stdout.
pub fn probe(args: &[&str]) -> String {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/usd/pxr_probe.py");
    let output = Command::new(python()).arg(script).args(args).output().expect("the project's Python runs");
    assert!(
        output.status.success(),
        "pxr_probe {args:?} failed: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).unwrap()
}

/// Runs a usd-core (pxr) script with the project's Python and `arg` as `sys.argv[1]`; returns its
/// stdout, failing the test with its stderr when it fails.
pub fn run_pxr_script(script: &str, arg: &Path) -> Vec<u8> {
    let made =
        Command::new(python()).arg("-c").arg(script).arg(arg).output().expect("the project's Python runs");
    assert!(made.status.success(), "{}", String::from_utf8_lossy(&made.stderr));
    made.stdout
}

/// Packages the stage `root` (and what it references) as the `.usdz` `package`, with usd-core.
pub fn usdz_package(root: &Path, package: &Path) {
    let made = Command::new(python())
        .arg("-c")
        .arg("import sys; from pxr import Sdf, UsdUtils; sys.exit(0 if UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(sys.argv[1]), sys.argv[2]) else 1)")
        .args([root, package])
        .output()
        .expect("the project's Python runs");
    assert!(made.status.success(), "usdz packaging of {root:?}: {}", String::from_utf8_lossy(&made.stderr));
}

/// What pxr sees in a stage (at a time, or the default time).
pub fn pxr_dump(path: &Path, time: Option<f64>) -> serde_json::Value {
    let path = path.to_str().unwrap();
    let time_text = time.map(|t| t.to_string());
    let mut args = vec!["dump", path];
    if let Some(t) = &time_text {
        args.extend(["--time", t]);
    }
    serde_json::from_str(&probe(&args)).expect("pxr_probe prints JSON")
}

/// A JSON array of numbers as f32 (pxr's floats widened to double convert back exactly).
/// pxr's world points of every curve prim (metres, Y up), one list per frame `first..=last`,
/// the prims in path order.
pub fn pxr_frames(path: &Path, first: f64, last: f64) -> Vec<Vec<f32>> {
    let text = probe(&["frames", path.to_str().unwrap(), &first.to_string(), &last.to_string()]);
    let dump: serde_json::Value = serde_json::from_str(&text).unwrap();
    dump["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|frame| frame["curves"].as_object().unwrap().values().flat_map(f32s).collect())
        .collect()
}

pub fn f32s(value: &serde_json::Value) -> Vec<f32> {
    value.as_array().expect("an array").iter().map(|v| v.as_f64().expect("a number") as f32).collect()
}

pub fn flat(points: &[Vec3]) -> Vec<f32> {
    points.iter().flat_map(|p| p.to_array()).collect()
}

/// A groom that uses every part of the model: uneven strands, awkward float values, ids, root
/// UVs, guide flags, and vertex and strand attributes of 1 to 4 components.
pub fn rich_groom(basis: CurveBasis) -> Groom {
    let counts: Vec<usize> = match basis {
        CurveBasis::Linear => vec![2, 5, 3, 8, 4, 6, 7],
        CurveBasis::Bezier => vec![4, 7, 10, 4, 7],
        _ => vec![4, 5, 9, 6, 4, 8],
    };
    let strands: Vec<Vec<Vec3>> = counts
        .iter()
        .enumerate()
        .map(|(s, &n)| {
            (0..n)
                .map(|k| {
                    let (s, k) = (s as f32, k as f32);
                    Vec3::new(0.1 * s + 1e-7 * k, -0.013 * k + (s * 0.7).sin() * 1e-3, 0.3333 * k * k + 1e-9)
                })
                .collect()
        })
        .collect();
    let mut groom = Groom::from_strands(&strands, 70e-6);
    groom.basis = basis;
    let (n, s) = (groom.vertex_count(), groom.strand_count());
    for (i, w) in groom.widths.iter_mut().enumerate() {
        *w = 80e-6 - i as f32 * 1.3e-7;
    }
    groom.strand_ids = (0..s as u32).map(|i| 1000 + 7 * (s as u32 - i)).collect();
    groom.root_uvs = Some((0..s).map(|i| [i as f32 / 7.0, 1.0 - i as f32 / 11.0]).collect());
    groom.guides = Some((0..s).map(|i| i % 3 == 0).collect());
    let ramp =
        |count: usize, scale: f32| (0..count).map(|i| (i as f32 * scale).fract()).collect::<Vec<f32>>();
    let vertex = AttributeRate::Vertex;
    groom.set_attribute(Attribute::new("color", vertex, 3, ramp(3 * n, 0.0371)));
    groom.set_attribute(Attribute::new("transparency", vertex, 1, ramp(n, 0.013)));
    groom.set_attribute(Attribute::new(
        "rest",
        vertex,
        3,
        flat(&groom.points).iter().map(|x| x * 0.5).collect(),
    ));
    groom.set_attribute(Attribute::new("rest_darboux", vertex, 3, ramp(3 * n, 0.00917)));
    for (i, bond) in ["bond_hydrogen", "bond_ionic", "bond_disulfide", "bond_peptide"].iter().enumerate() {
        groom.set_attribute(Attribute::new(*bond, vertex, 1, ramp(n, 0.1 + i as f32 * 0.01)));
    }
    groom.set_attribute(Attribute::new("wetness", vertex, 1, ramp(n, 0.071)));
    groom.set_attribute(Attribute::new("melanin", AttributeRate::Strand, 1, ramp(s, 0.29)));
    groom.set_attribute(Attribute::new("clump_uv", AttributeRate::Strand, 2, ramp(2 * s, 0.17)));
    groom.set_attribute(Attribute::new("tint", AttributeRate::Strand, 4, ramp(4 * s, 0.123)));
    groom.validate().expect("the test groom is valid");
    groom
}

/// Every curve and mesh prim's visibility at frames 1, 2 and 3 as pxr computes it (an
/// ancestor's `invisible` hides it), by prim path: `true` where hidden.
pub fn pxr_hidden_by_frame(path: &Path) -> std::collections::BTreeMap<String, Vec<bool>> {
    let script = r#"
import json, sys
from pxr import Usd, UsdGeom
stage = Usd.Stage.Open(sys.argv[1])
print(json.dumps({str(p.GetPath()): [UsdGeom.Imageable(p).ComputeVisibility(t) == 'invisible' for t in (1, 2, 3)]
                  for p in stage.Traverse() if p.IsA(UsdGeom.BasisCurves) or p.IsA(UsdGeom.Mesh)}))
"#;
    serde_json::from_slice(&run_pxr_script(script, path)).unwrap()
}
