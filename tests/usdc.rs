//! Native crate files (`.usdc`) against usd-core (pxr): every stage coif writes as `.usdc`, pxr
//! sees exactly as the `.usda` coif writes for the same groom (values, types, roles,
//! interpolation, time samples, metadata) and validates without error; every `.usdc` pxr writes
//! from a test stage, coif reads into the same groom as the `.usda` it came from. And no Python
//! is started for any `.usdc` operation.
mod common;
use common::usd::*;
use common::*;

use coif::groom::{Attribute, AttributeKind, AttributeRate, CurveBasis, CurveGroup, CurveWrap, Groom};
use coif::io::usda::TimeCodes;
use glam::Vec3;
use std::path::Path;

fn pxr_export(from: &Path, to: &Path) {
    probe(&["export", path_str(from), path_str(to)]);
}

/// A groom big enough that pxr compresses its arrays: 40 strands (int arrays of 16+ elements),
/// constant widths (a float lookup table) and whole-number floats (floats as integers).
fn compressible_groom() -> Groom {
    let strands: Vec<Vec<Vec3>> = (0..40)
        .map(|s| {
            (0..5 + s % 4)
                .map(|k| Vec3::new(s as f32 * 0.01, k as f32 * 0.02, 0.3 / (1 + k) as f32))
                .collect()
        })
        .collect();
    let mut groom = Groom::from_strands(&strands, 70e-6);
    let s = groom.strand_count();
    groom.set_attribute(Attribute::new(
        "clump_id",
        AttributeRate::Strand,
        1,
        (0..s).map(|i| (i / 3) as f32).collect(),
    ));
    let n = groom.vertex_count();
    groom.set_attribute(Attribute::new(
        "wetness",
        AttributeRate::Vertex,
        1,
        (0..n).map(|i| (i % 4) as f32 * 0.25).collect(),
    ));
    groom.validate().unwrap();
    groom
}

/// A groom whose arrays take every path of the crate writer's coding: 600 strands of 3 to 40
/// vertices (counts with many different steps), tapered widths (a lookup table with index steps
/// of every sign), a vertex attribute of 300 values in a scattered order (a table of 300 whose
/// index steps take more values than the counting table holds, so the most common is found by
/// sorting), scattered strand ids (integer deltas of every width) and a float per strand that
/// never repeats (written plain).
fn coded_groom() -> Groom {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let strands: Vec<Vec<Vec3>> = (0..600)
        .map(|s| {
            let count = 3 + (next() % 38) as usize;
            (0..count)
                .map(|k| Vec3::new(s as f32 * 0.001, -(k as f32) * 0.004, (s % 7) as f32 * 0.01))
                .collect()
        })
        .collect();
    let mut groom = Groom::from_strands(&strands, 80e-6);
    for s in 0..groom.strand_count() {
        let range = groom.strand_range(s);
        let len = range.len() as f32;
        for (k, w) in groom.widths[range].iter_mut().enumerate() {
            *w = 80e-6 * (1.0 - 0.5 * k as f32 / len);
        }
    }
    groom.strand_ids = (0..groom.strand_count()).map(|_| (next() % 2_000_000_000) as u32).collect();
    let n = groom.vertex_count();
    let scattered: Vec<f32> = (0..n).map(|_| (next() % 300) as f32 * 0.01 + 0.005).collect();
    groom.set_attribute(Attribute::new("wetness", AttributeRate::Vertex, 1, scattered));
    let s = groom.strand_count();
    groom.set_attribute(Attribute::new(
        "melanin",
        AttributeRate::Strand,
        1,
        (0..s).map(|i| (i as f32 * 0.6180).fract()).collect(),
    ));
    groom.validate().unwrap();
    groom
}

#[test]
fn pxr_sees_coif_usdc_exactly_as_coif_usda_and_validates_it() {
    let dir = tempfile::tempdir().unwrap();
    let grooms = [
        rich_groom(CurveBasis::Linear),
        rich_groom(CurveBasis::Bezier),
        rich_groom(CurveBasis::BSpline),
        compressible_groom(),
        coded_groom(),
    ];
    for (k, groom) in grooms.iter().enumerate() {
        let (text, binary) = (dir.path().join(format!("{k}.usda")), dir.path().join(format!("{k}.usdc")));
        coif::io::write_groom(&text, groom).unwrap();
        coif::io::write_groom(&binary, groom).unwrap();
        assert!(std::fs::read(&binary).unwrap().starts_with(b"PXR-USDC"));
        let (from_text, from_binary) = (pxr_dump(&text, None), pxr_dump(&binary, None));
        assert_eq!(from_binary["validationErrors"], serde_json::json!([]), "groom {k}");
        assert_eq!(from_text, from_binary, "groom {k}: pxr sees the same stage");
        // And coif reads its own crate file back exactly.
        assert_eq!(&coif::io::read_groom(&binary, &Default::default()).unwrap().groom, groom);
    }
}

fn houdini_groom() -> Groom {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/houdini_groom.usda");
    coif::io::read_groom(&path, &Default::default()).unwrap().groom
}

/// Groups as a groom built in memory may have them: interleaved strands, three bases, a pinned
/// wrap, a purpose, attributes one group lacks, an empty group, a nested and a second root path,
/// and attributes of every kind (int, bool, normal, integer tuples).
fn interleaved_groups_groom() -> Groom {
    let mut groom = rich_groom(CurveBasis::BSpline);
    let (n, s) = (groom.vertex_count(), groom.strand_count());
    let strand = AttributeRate::Strand;
    groom.set_attribute(
        Attribute::new("flag", strand, 1, (0..s).map(|i| (i % 2) as f32).collect())
            .with_kind(AttributeKind::Bool),
    );
    let counts = (0..n as i64).map(|i| i - 3).collect();
    groom.set_attribute(Attribute::integers("count", AttributeRate::Vertex, 1, counts, AttributeKind::Int));
    groom.set_attribute(
        Attribute::new("nrm", AttributeRate::Vertex, 3, (0..3 * n).map(|i| i as f32 * 0.01).collect())
            .with_kind(AttributeKind::Normal),
    );
    groom.set_attribute(Attribute::new(
        coif::guides::CLOSEST_GUIDES,
        strand,
        3,
        (0..3 * s).map(|i| i as f32).collect(),
    ));
    let mut guides = CurveGroup::new("/Groom/guides", CurveBasis::Linear, CurveWrap::Nonperiodic);
    guides.purpose = Some("guide".into());
    guides.missing = vec!["wetness".into(), "tint".into()];
    groom.groups = vec![
        guides,
        CurveGroup::new("/Groom/hair/main", CurveBasis::CatmullRom, CurveWrap::Nonperiodic),
        CurveGroup::new("/Groom/empty", CurveBasis::Linear, CurveWrap::Nonperiodic),
        CurveGroup::new("/Other/fuzz", CurveBasis::BSpline, CurveWrap::Pinned),
    ];
    groom.group_ids = (0..s).map(|i| [0, 1, 3][i % 3]).collect();
    groom.basis = CurveBasis::Linear;
    groom.validate().unwrap();
    groom
}

#[test]
fn pxr_sees_multi_group_usdc_exactly_as_usda_and_coif_reads_it_back() {
    let dir = tempfile::tempdir().unwrap();
    for (k, groom) in [houdini_groom(), interleaved_groups_groom()].iter().enumerate() {
        assert!(groom.groups.len() > 1);
        let (text, binary) = (dir.path().join(format!("{k}.usda")), dir.path().join(format!("{k}.usdc")));
        coif::io::write_groom(&text, groom).unwrap();
        coif::io::write_groom(&binary, groom).unwrap();
        assert!(std::fs::read(&binary).unwrap().starts_with(b"PXR-USDC"));
        let (from_text, from_binary) = (pxr_dump(&text, None), pxr_dump(&binary, None));
        assert_eq!(from_binary["validationErrors"], serde_json::json!([]), "groom {k}");
        assert_eq!(from_text, from_binary, "groom {k}: pxr sees the same stage");
        let paths: Vec<&str> =
            from_binary["curves"].as_array().unwrap().iter().map(|c| c["path"].as_str().unwrap()).collect();
        assert_eq!(
            paths.len(),
            groom.groups.iter().filter(|g| g.name != "/Groom/empty").count(),
            "{paths:?}"
        );
        let read = |path: &Path| coif::io::read_groom(path, &Default::default()).unwrap().groom;
        let back = read(&binary);
        assert_eq!(back, read(&text), "groom {k}: coif reads both formats alike");
        assert_eq!(back.strand_count(), groom.strand_count());
        // One prim per group, in group order: strands come back grouped, each group in order.
        let grouped: Vec<Vec3> = (0..groom.group_count())
            .flat_map(|g| groom.group_strands(g))
            .flat_map(|s| groom.points[groom.strand_range(s)].to_vec())
            .collect();
        assert_eq!(back.points, grouped, "groom {k}: the strands of each group keep their order");
        assert_eq!(back.group_count(), paths.len());
    }
}

#[test]
fn animated_usdc_has_the_time_samples_and_metadata_of_animated_usda() {
    let dir = tempfile::tempdir().unwrap();
    // One curve prim, and several groups (interleaved strands, three bases).
    for groom in [rich_groom(CurveBasis::CatmullRom), interleaved_groups_groom()] {
        animated_usdc_matches_animated_usda(&groom, dir.path());
    }
}

fn animated_usdc_matches_animated_usda(groom: &Groom, dir: &Path) {
    let frames: Vec<Vec<Vec3>> = (1..=3)
        .map(|f| {
            groom.points.iter().map(|p| *p + Vec3::new(0.01 * f as f32, -0.003 * f as f32, 0.0)).collect()
        })
        .collect();
    let (text, binary) = (dir.join("anim.usda"), dir.join("anim.usdc"));
    for path in [&text, &binary] {
        coif::io::write_animated(path, groom, &frames, &[], 30.0, &Default::default()).unwrap();
    }
    for time in [Some(1.0), Some(2.5), Some(3.0)] {
        let (from_text, from_binary) = (pxr_dump(&text, time), pxr_dump(&binary, time));
        assert_eq!(from_binary["validationErrors"], serde_json::json!([]), "time {time:?}");
        assert_eq!(from_text, from_binary, "time {time:?}");
        assert_eq!(from_binary["timeCodesPerSecond"], 30.0);
        assert_eq!(
            (from_binary["startTimeCode"].as_f64(), from_binary["endTimeCode"].as_f64()),
            (Some(1.0), Some(3.0))
        );
        let read = |path: &Path| {
            coif::io::read_groom_selected(
                path,
                &Default::default(),
                &coif::io::usda::Selection { time, variants: vec![] },
            )
            .unwrap()
            .groom
        };
        assert_eq!(read(&binary), read(&text), "coif reads both alike at {time:?}");
    }
    let earliest = |path: &Path| coif::io::read_groom(path, &Default::default()).unwrap().groom;
    assert_eq!(earliest(&binary), earliest(&text), "without a time, the earliest sample");
    let times = TimeCodes { start: 1.0, end: 2.0, per_second: 24.0 };
    let bad =
        coif::io::usdc::write_animated(&binary, groom, &[groom.points[1..].to_vec()], times).unwrap_err();
    assert!(matches!(bad, coif::Error::Usage(_)), "{bad}");
}

/// A stage laid out the way Blender's USD exporter writes hair: Z up, a root Xform with a
/// matrix transform, cubic B-spline curves with varying widths and a UV primvar, a material
/// scope and binding relationship, and a mesh beside the curves.
const BLENDER_STYLE: &str = r#"#usda 1.0
(
    defaultPrim = "root"
    doc = "Blender v5.0.1"
    metersPerUnit = 1
    upAxis = "Z"
)

def Xform "root" (
    customData = {
        dictionary Blender = {
            bool generated = 1
        }
    }
)
{
    def Xform "Curves"
    {
        matrix4d xformOp:transform = ( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0.5, -0.25, 1.5, 1) )
        uniform token[] xformOpOrder = ["xformOp:transform"]

        def BasisCurves "Curves" (
            prepend apiSchemas = ["MaterialBindingAPI"]
        )
        {
            uniform token basis = "bspline"
            int[] curveVertexCounts = [4, 5, 4, 4, 6, 4, 4, 4, 5, 4, 4, 4, 4, 4, 4, 4, 4]
            point3f[] points = [(0, 0, 0), (0, 0, 0.01), (0, 0.001, 0.02), (0, 0.002, 0.03), (0.01, 0, 0), (0.01, 0, 0.01), (0.01, 0.001, 0.02), (0.01, 0.002, 0.03), (0.01, 0.003, 0.04), (0.02, 0, 0), (0.02, 0, 0.01), (0.02, 0, 0.02), (0.02, 0, 0.03), (0.03, 0, 0), (0.03, 0, 0.01), (0.03, 0, 0.02), (0.03, 0, 0.03), (0.04, 0, 0), (0.04, 0, 0.01), (0.04, 0, 0.02), (0.04, 0, 0.03), (0.04, 0, 0.04), (0.04, 0, 0.05), (0.05, 0, 0), (0.05, 0, 0.01), (0.05, 0, 0.02), (0.05, 0, 0.03), (0.06, 0, 0), (0.06, 0, 0.01), (0.06, 0, 0.02), (0.06, 0, 0.03), (0.07, 0, 0), (0.07, 0, 0.01), (0.07, 0, 0.02), (0.07, 0, 0.03), (0.08, 0, 0), (0.08, 0, 0.01), (0.08, 0, 0.02), (0.08, 0, 0.03), (0.08, 0, 0.04), (0.09, 0, 0), (0.09, 0, 0.01), (0.09, 0, 0.02), (0.09, 0, 0.03), (0.1, 0, 0), (0.1, 0, 0.01), (0.1, 0, 0.02), (0.1, 0, 0.03), (0.11, 0, 0), (0.11, 0, 0.01), (0.11, 0, 0.02), (0.11, 0, 0.03), (0.12, 0, 0), (0.12, 0, 0.01), (0.12, 0, 0.02), (0.12, 0, 0.03), (0.13, 0, 0), (0.13, 0, 0.01), (0.13, 0, 0.02), (0.13, 0, 0.03), (0.14, 0, 0), (0.14, 0, 0.01), (0.14, 0, 0.02), (0.14, 0, 0.03), (0.15, 0, 0), (0.15, 0, 0.01), (0.15, 0, 0.02), (0.15, 0, 0.03), (0.16, 0, 0), (0.16, 0, 0.01), (0.16, 0, 0.02), (0.16, 0, 0.03)]
            float[] widths = [0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002, 0.002] (
                interpolation = "uniform"
            )
            float2[] primvars:surface_uv = [(0.1, 0.2), (0.2, 0.2), (0.3, 0.2), (0.4, 0.2), (0.5, 0.2), (0.6, 0.2), (0.7, 0.2), (0.8, 0.2), (0.9, 0.2), (0.1, 0.3), (0.2, 0.3), (0.3, 0.3), (0.4, 0.3), (0.5, 0.3), (0.6, 0.3), (0.7, 0.3), (0.8, 0.3)] (
                interpolation = "uniform"
            )
            uniform token type = "cubic"
            uniform token wrap = "nonperiodic"
            rel material:binding = </root/_materials/Hair>
        }
    }

    def Xform "Head"
    {
        def Mesh "Head"
        {
            int[] faceVertexCounts = [3]
            int[] faceVertexIndices = [0, 1, 2]
            point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
        }
    }

    def Scope "_materials"
    {
        def Material "Hair"
        {
        }
    }
}
"#;

/// Values pxr stores in its compact forms: a small-integer translate inline, a constant colour,
/// half floats, a width lookup table, whole-number floats as integers, compressed counts.
const COMPACT_VALUES: &str = r#"#usda 1.0
(
    defaultPrim = "Groom"
    metersPerUnit = 0.01
    upAxis = "Z"
)

def Xform "Groom"
{
    double3 xformOp:translate = (1, 2, 3)
    uniform token[] xformOpOrder = ["xformOp:translate"]
    def BasisCurves "Strands"
    {
        uniform token type = "linear"
        int[] curveVertexCounts = [2, 3, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2, 2]
        point3f[] points = [(0,0,0),(0,1,0),(1,0,0),(1,1,0),(1,2,0),(2,0,0),(2,1,0),(3,0,0),(3,1,0),(4,0,0),(4,1,0),(5,0,0),(5,1,0),(6,0,0),(6,1,0),(7,0,0),(7,1,0),(8,0,0),(8,1,0),(9,0,0),(9,1,0),(10,0,0),(10,1,0),(11,0,0),(11,1,0),(12,0,0),(12,1,0),(13,0,0),(13,1,0),(14,0,0),(14,1,0),(15,0,0),(15,1,0),(16,0,0),(16,1,0)]
        float[] widths = [0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1] (
            interpolation = "uniform"
        )
        float[] primvars:melanin = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17] (
            interpolation = "uniform"
        )
        color3f[] primvars:displayColor = [(1, 0, 0)] (
            interpolation = "constant"
        )
        half[] primvars:h = [0.5, 0.25, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1] (
            interpolation = "uniform"
        )
    }
}
"#;

#[test]
fn coif_reads_usdc_pxr_wrote_into_the_groom_of_its_usda() {
    let dir = tempfile::tempdir().unwrap();
    let mut sources = Vec::new();
    for (k, groom) in [
        rich_groom(CurveBasis::Linear),
        rich_groom(CurveBasis::CatmullRom),
        compressible_groom(),
        houdini_groom(),
        interleaved_groups_groom(),
    ]
    .iter()
    .enumerate()
    {
        let path = dir.path().join(format!("coif{k}.usda"));
        coif::io::write_groom(&path, groom).unwrap();
        sources.push((path, vec![None]));
    }
    let authored = dir.path().join("authored.usda");
    probe(&["author-transformed", path_str(&authored)]);
    sources.push((authored, vec![None, Some(1.0), Some(1.5), Some(2.0), Some(9.0)]));
    let blender = dir.path().join("blender.usda");
    std::fs::write(&blender, BLENDER_STYLE).unwrap();
    sources.push((blender, vec![None]));
    let compact = dir.path().join("compact.usda");
    std::fs::write(&compact, COMPACT_VALUES).unwrap();
    sources.push((compact, vec![None]));

    for (text, times) in sources {
        let binary = text.with_extension("usdc");
        pxr_export(&text, &binary);
        for time in times {
            let selection = coif::io::usda::Selection { time, variants: vec![] };
            let read = |path: &Path| {
                let loaded = coif::io::read_groom_selected(path, &Default::default(), &selection).unwrap();
                assert_eq!(loaded.format.name(), path.extension().unwrap().to_str().unwrap());
                loaded.groom
            };
            let (want, got) = (read(&text), read(&binary));
            assert!(want.strand_count() > 0);
            assert_eq!(got, want, "{} at {time:?}", binary.display());
        }
    }
}

#[test]
fn no_python_is_started_for_usdc() {
    let dir = tempfile::tempdir().unwrap();
    let hair = Path::new(env!("CARGO_MANIFEST_DIR")).join("grooms/sample_wavy.hair");
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_coif"))
            .args(args)
            .env("COIF_PYTHON", "/nonexistent/python")
            .env("COIF_PIPELINE", "/nonexistent")
            .env("PATH", "/nonexistent")
            .output()
            .unwrap();
        assert!(out.status.success(), "{args:?}: {}", stderr(&out));
        out
    };
    let (a, b, c) = (dir.path().join("a.usdc"), dir.path().join("b.usdc"), dir.path().join("c.usda"));
    run(&["convert", path_str(&hair), path_str(&a)]);
    run(&["convert", path_str(&a), path_str(&b)]);
    run(&["convert", path_str(&b), path_str(&c)]);
    let info = stdout_json(&run(&["info", "--json", path_str(&b)]));
    assert_eq!(info["format"], "usdc");
    let direct = dir.path().join("direct.usda");
    run(&["convert", path_str(&hair), path_str(&direct)]);
    assert_eq!(std::fs::read(&c).unwrap(), std::fs::read(&direct).unwrap(), "same groom through .usdc");
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap(), "the writer is deterministic");

    // A groom of several curve groups, written and read as crate files.
    let houdini = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/houdini_groom.usda");
    let (d, e, f) = (dir.path().join("d.usdc"), dir.path().join("e.usdc"), dir.path().join("f.usda"));
    run(&["convert", path_str(&houdini), path_str(&d)]);
    run(&["convert", path_str(&d), path_str(&e)]);
    run(&["convert", path_str(&e), path_str(&f)]);
    let direct = dir.path().join("direct_groups.usda");
    run(&["convert", path_str(&houdini), path_str(&direct)]);
    assert_eq!(std::fs::read(&f).unwrap(), std::fs::read(&direct).unwrap(), "same groups through .usdc");
    assert_eq!(std::fs::read(&d).unwrap(), std::fs::read(&e).unwrap());
}

#[test]
fn composed_crate_files_are_composed_without_python() {
    let dir = tempfile::tempdir().unwrap();
    probe(&["author-composed", path_str(dir.path())]);
    let (stage, payload) = (dir.path().join("stage.usdc"), dir.path().join("payload.usdc"));
    pxr_export(&dir.path().join("stage.usda"), &stage);
    pxr_export(&dir.path().join("payload.usda"), &payload);
    let plain = dir.path().join("plain.usdc");
    coif::io::write_groom(&plain, &rich_groom(CurveBasis::Linear)).unwrap();
    let out = dir.path().join("out.usda");
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_coif"))
            .args(args)
            .env("COIF_PYTHON", "/nonexistent/python")
            .env("COIF_PIPELINE", "/nonexistent")
            .output()
            .unwrap()
    };
    // The crate stage references the text payload (a variant set), the crate payload is read
    // on its own: the file's selection, or --variant's.
    for (input, variant, tip) in
        [(&stage, None, 1.0), (&stage, Some("length=long"), 3.0), (&payload, None, 1.0)]
    {
        let mut args = vec!["convert", path_str(input), path_str(&out)];
        args.extend(variant.iter().flat_map(|v| ["--variant", v]));
        let result = run(&args);
        assert!(result.status.success(), "{args:?}: {}", stderr(&result));
        let groom = coif::io::read_groom(&out, &Default::default()).unwrap().groom;
        assert_eq!(groom.points, vec![Vec3::ZERO, Vec3::new(0.0, tip, 0.0)], "{args:?}");
    }
    let args = ["convert", "--variant", "length=long", path_str(&plain), path_str(&out)];
    let result = run(&args);
    assert_eq!(result.status.code(), Some(2), "{}", stderr(&result));
    assert!(stderr(&result).contains("no prim has a variant set 'length'"), "{}", stderr(&result));
}
