//! Grooms of several curve groups (guides and children with different bases, as Houdini and
//! Blender write them): exact counts per group on import, and `coif convert` round trips that
//! pxr sees as the same prims, bases, wraps, segment counts, points and widths.
mod common;
use common::usd::*;
use common::*;

use coif::groom::{CurveBasis, CurveWrap, Groom};
use coif::io::{read_groom, ImportOptions};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn houdini_groom() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/houdini_groom.usda")
}

fn read(path: &Path) -> Groom {
    read_groom(path, &ImportOptions::default()).unwrap().groom
}

/// (name, basis, wrap, strands, vertices) per group.
fn group_summary(groom: &Groom) -> Vec<(String, CurveBasis, CurveWrap, usize, usize)> {
    (0..groom.group_count())
        .map(|g| {
            let group = groom.group(g);
            let strands = groom.group_strands(g);
            let vertices = strands.iter().map(|&s| groom.strand_range(s).len()).sum();
            (group.name.clone(), group.basis, group.wrap, strands.len(), vertices)
        })
        .collect()
}

#[test]
fn houdini_style_stage_imports_with_exact_counts_per_group() {
    let groom = read(&houdini_groom());
    // Counts as authored by scripts/make_test_grooms_pxr.py.
    assert_eq!(
        group_summary(&groom),
        vec![
            ("/groom/guides".into(), CurveBasis::CatmullRom, CurveWrap::Pinned, 3, 18),
            ("/groom/hair".into(), CurveBasis::Linear, CurveWrap::Nonperiodic, 6, 34),
            ("/groom/fuzz".into(), CurveBasis::BSpline, CurveWrap::Nonperiodic, 2, 11),
        ]
    );
    assert_eq!(groom.group(0).purpose.as_deref(), Some("guide"));
    let guides: Vec<bool> = groom.guides.clone().unwrap();
    assert_eq!(guides, [vec![true; 3], vec![false; 8]].concat(), "purpose = guide marks the guides");
    // rest only on the guides, guide_curve_index only on the children.
    assert!(groom.group(0).carries("rest") && !groom.group(1).carries("rest"));
    assert!(groom.group(1).carries("guide_curve_index") && !groom.group(2).carries("guide_curve_index"));
    // Centimetres and the /groom translate (150 cm up) applied.
    let root = groom.strand_points(0)[0];
    assert!((root - glam::Vec3::new(0.0, 1.5, 0.0)).length() < 1e-6, "{root}");
}

fn curves_by_path(dump: &Value) -> Vec<(String, &Value)> {
    dump["curves"].as_array().unwrap().iter().map(|c| (c["path"].as_str().unwrap().to_string(), c)).collect()
}

/// Per-vertex widths from pxr's widths and their interpolation (constant or per vertex here).
fn vertex_widths(curves: &Value) -> Vec<f32> {
    let widths = f32s(&curves["widths"]);
    let vertices = f32s(&curves["points"]).len() / 3;
    match curves["widthsInterpolation"].as_str().unwrap() {
        "constant" => vec![widths[0]; vertices],
        _ => {
            assert_eq!(widths.len(), vertices, "linear varying and vertex widths have one per point");
            widths
        }
    }
}

#[test]
fn unstyled_convert_round_trip_is_exact_in_pxr_and_in_coif() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.usda");
    let result = coif(&["convert", path_str(&houdini_groom()), path_str(&out)]);
    assert!(result.status.success(), "{}", stderr(&result));

    let (source, written) = (pxr_dump(&houdini_groom(), None), pxr_dump(&out, None));
    assert_eq!(written["validationErrors"], serde_json::json!([]), "UsdValidation reports errors");
    let source_mpu = source["metersPerUnit"].as_f64().unwrap() as f32;
    let (source_curves, written_curves) = (curves_by_path(&source), curves_by_path(&written));
    assert_eq!(
        source_curves.iter().map(|c| &c.0).collect::<Vec<_>>(),
        written_curves.iter().map(|c| &c.0).collect::<Vec<_>>(),
        "the same prims at the same paths"
    );
    for ((path, a), (_, b)) in source_curves.iter().zip(&written_curves) {
        for key in ["type", "basis", "wrap", "purpose", "counts", "segmentEnds"] {
            assert_eq!(a[key], b[key], "{path}: {key}");
        }
        for (name, primvar) in a["primvars"].as_object().unwrap() {
            let written = &b["primvars"][name];
            assert_eq!(primvar["type"], written["type"], "{path}: primvar {name} keeps its type and role");
            if primvar["interpolation"] == "uniform" {
                assert_eq!(primvar["interpolation"], written["interpolation"], "{path}: primvar {name}");
            }
        }
        let (pa, pb) = (f32s(&a["world_points"]), f32s(&b["world_points"]));
        assert_eq!(pa.len(), pb.len());
        for (x, y) in pa.iter().zip(&pb) {
            assert!((x * source_mpu - y).abs() <= 1e-6, "{path}: point {x} cm vs {y} m");
        }
        for (x, y) in vertex_widths(a).iter().zip(vertex_widths(b)) {
            assert!((x * source_mpu - y).abs() <= 1e-9, "{path}: width {x} cm vs {y} m");
        }
    }
    let rest = |dump: &Value| f32s(&dump["curves"][0]["primvars"]["rest"]["values"]);
    let (rest_source, rest_written) = (rest(&source), rest(&written));
    assert_eq!(rest_source.len(), rest_written.len());
    for (k, (x, y)) in rest_source.iter().zip(&rest_written).enumerate() {
        // rest is a position: centimetres and the /groom translate apply as to the points.
        let expected = x * source_mpu + if k % 3 == 1 { 1.5 } else { 0.0 };
        assert!((expected - y).abs() <= 1e-6, "rest {k}: {expected} vs {y}");
    }
    assert!(
        written["curves"][2]["primvars"].get("rest").is_none(),
        "a primvar one prim lacks is not invented for it"
    );

    assert_same_meshes(&source, &written, "houdini_groom.usda → .usda");

    // coif reads back the groom it read, group for group, meshes included, and writing again
    // changes nothing.
    let (first, second) = (read(&houdini_groom()), read(&out));
    assert_eq!(first.meshes.len(), 1, "the skin mesh is read");
    assert_eq!(first, second);
    let again = dir.path().join("again.usda");
    assert!(coif(&["convert", path_str(&out), path_str(&again)]).status.success());
    assert_eq!(std::fs::read(&out).unwrap(), std::fs::read(&again).unwrap());
}

/// pxr sees the source's `Mesh` prims in the written stage: the same paths (Blender's Alembic has
/// no `/root`: matched by their ends), faces and world points (metres, Y up in the written
/// stage), wound the same way, with an extent that holds them.
fn assert_same_meshes(source: &Value, written: &Value, label: &str) {
    let mpu = source["metersPerUnit"].as_f64().unwrap() as f32;
    let z_up = source["upAxis"] == "Z";
    let (a, b) = (source["meshes"].as_array().unwrap(), written["meshes"].as_array().unwrap());
    assert_eq!(a.len(), b.len(), "{label}: mesh prims");
    assert!(!a.is_empty(), "{label}: the source has a mesh");
    for m in a {
        let path = m["path"].as_str().unwrap();
        let tail = path.trim_start_matches("/root");
        let w = b
            .iter()
            .find(|w| w["path"].as_str().unwrap().ends_with(tail))
            .unwrap_or_else(|| panic!("{label}: no mesh {tail}"));
        assert_eq!((&m["counts"], &m["indices"]), (&w["counts"], &w["indices"]), "{label} {path}: faces");
        let expected: Vec<f32> = f32s(&m["world_points"])
            .chunks_exact(3)
            .flat_map(|p| {
                if z_up {
                    [p[0] * mpu, p[2] * mpu, -p[1] * mpu]
                } else {
                    [p[0] * mpu, p[1] * mpu, p[2] * mpu]
                }
            })
            .collect();
        let got = f32s(&w["world_points"]);
        assert_eq!(expected.len(), got.len(), "{label} {path}");
        for (x, y) in expected.iter().zip(&got) {
            assert!((x - y).abs() <= 2e-6, "{label} {path}: point {x} vs {y}");
        }
        assert_eq!(
            (w["orientation"].as_str(), w["subdivisionScheme"].as_str()),
            (Some("rightHanded"), Some("none"))
        );
        assert_eq!(w["extent"], w["computedExtent"], "{label} {path}: extent");
    }
}

#[test]
fn alembic_round_trip_keeps_objects_bases_and_counts() {
    let dir = tempfile::tempdir().unwrap();
    let abc = dir.path().join("groups.abc");
    let result = coif(&["convert", path_str(&houdini_groom()), path_str(&abc)]);
    assert!(result.status.success(), "{}", stderr(&result));
    let (source, back) = (read(&houdini_groom()), read(&abc));
    // Wraps too: the pinned Catmull-Rom guides come back pinned, the B-spline nonperiodic.
    assert_eq!(group_summary(&back), group_summary(&source));
    assert_eq!(back.points, source.points);
    assert_eq!(back.widths, source.widths);
    assert_eq!(back.guides, source.guides);
    // The skin comes back as the PolyMesh it was written as: path, points and faces exactly.
    assert_eq!(back.meshes, source.meshes);
}

#[test]
fn a_periodic_prim_exits_2_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("closed.usda");
    std::fs::write(
        &path,
        "#usda 1.0\n(\n    metersPerUnit = 1\n)\ndef BasisCurves \"Open\"\n{\n    uniform token type = \"linear\"\n    int[] curveVertexCounts = [2]\n    point3f[] points = [(0, 0, 0), (0, 1, 0)]\n}\ndef BasisCurves \"Ring\"\n{\n    uniform token type = \"linear\"\n    uniform token wrap = \"periodic\"\n    int[] curveVertexCounts = [3]\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n}\n",
    )
    .unwrap();
    let out = coif(&["info", path_str(&path)]);
    assert_eq!(out.status.code(), Some(2));
    let message = stderr(&out);
    assert!(message.contains("</Ring>") && message.contains("periodic"), "{message}");
}

/// Maya's USD export writes nurbsCurves as `NurbsCurves` prims (they used to exit 2, and before
/// that to be left out without a word). Read as Maya's Alembic curves are: degree 3 as a cubic
/// B-spline (`pinned` where the knots are clamped, as Maya writes them: the curve starts at its
/// root), degree 1 as a polyline, beside BasisCurves hair; in `.usda` and in pxr's `.usdc` of the
/// same stage, pxr finds the control points (in metres), counts and widths it reads in the file,
/// as BasisCurves at the same paths. Other degrees, rational curves and knots that do not fit
/// exit 2 naming the prim, and nothing is written.
#[test]
fn nurbs_curves_are_read_as_b_splines_and_polylines() {
    let dir = tempfile::tempdir().unwrap();
    let stage = |guides_order: &str, guides_knots: &str, extra: &str| {
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 0.01\n    upAxis = \"Y\"\n)\ndef Xform \"groom\"\n{{\n\
             def BasisCurves \"hair\"\n{{\n uniform token type = \"linear\"\n int[] curveVertexCounts = [2]\n\
             point3f[] points = [(0, 0, 0), (0, 1, 0)]\n}}\n\
             def NurbsCurves \"guides\"\n{{\n int[] curveVertexCounts = [4, 5]\n\
             point3f[] points = [(1, 0, 0), (1, 1, 0.5), (1, 2, 0), (1, 3, 0.25), (2, 0, 0), (2, 1, 0), (2, 2, 1), (2.5, 3, 0), (2, 4, 0)]\n\
             float[] widths = [0.008, 0.007, 0.006, 0.005, 0.008, 0.0075, 0.007, 0.0065, 0.006] (interpolation = \"vertex\")\n\
             int[] order = [{guides_order}]\n double[] knots = [{guides_knots}]\n{extra}}}\n\
             def NurbsCurves \"strays\"\n{{\n int[] curveVertexCounts = [3]\n\
             point3f[] points = [(3, 0, 0), (3, 1, 1), (3, 2, 1)]\n int[] order = [2]\n double[] knots = [0, 0, 1, 2, 2]\n}}\n}}\n"
        )
    };
    let clamped = "0, 0, 0, 0, 1, 1, 1, 1, 0, 0, 0, 0, 1, 2, 2, 2, 2";
    let source = dir.path().join("maya.usda");
    std::fs::write(&source, stage("4, 4", clamped, "")).unwrap();
    let usdc = dir.path().join("maya.usdc");
    common::usd::probe(&["export", path_str(&source), path_str(&usdc)]);
    let maya = pxr_dump(&source, None);
    let nurbs: Vec<&Value> = maya["nurbs"].as_array().unwrap().iter().collect();
    assert_eq!(nurbs.len(), 2, "pxr reads both NurbsCurves prims");
    for input in [&source, &usdc] {
        let out = dir.path().join("out.usda");
        let converted = coif(&["convert", path_str(input), path_str(&out)]);
        assert!(converted.status.success(), "{}", stderr(&converted));
        let dump = pxr_dump(&out, None);
        let curves = curves_by_path(&dump);
        for (source, (kind, wrap)) in nurbs.iter().zip([("cubic", "pinned"), ("linear", "nonperiodic")]) {
            let path = source["path"].as_str().unwrap();
            let (_, written) =
                curves.iter().find(|(p, _)| p == path).unwrap_or_else(|| panic!("{path} written"));
            assert_eq!(written["type"], kind, "{path}");
            if kind == "cubic" {
                assert_eq!(written["basis"], "bspline", "{path}");
            }
            assert_eq!(written["wrap"], wrap, "{path}");
            assert_eq!(written["counts"], source["counts"], "{path}");
            let expected: Vec<f32> = f32s(&source["world_points"]).iter().map(|x| x * 0.01).collect();
            let got = f32s(&written["world_points"]);
            assert_eq!(got.len(), expected.len(), "{path}");
            assert!(
                got.iter().zip(&expected).all(|(a, b)| (a - b).abs() < 1e-7),
                "{path}: {got:?} vs {expected:?}"
            );
            if !source["widths"].as_array().unwrap().is_empty() {
                let expected: Vec<f32> = f32s(&source["widths"]).iter().map(|x| x * 0.01).collect();
                let got = vertex_widths(written);
                assert!(got.iter().zip(&expected).all(|(a, b)| (a - b).abs() < 1e-9), "{path} widths");
            }
        }
        assert!(curves.iter().any(|(p, _)| p == "/groom/hair"), "the BasisCurves hair beside them");
    }
    // Animated NurbsCurves (nHair's output cached to USD) stay animated.
    let animated = dir.path().join("animated.usda");
    std::fs::write(
        &animated,
        "#usda 1.0\n(\n    startTimeCode = 1\n    endTimeCode = 2\n    metersPerUnit = 1\n)\n\
         def NurbsCurves \"guides\"\n{\n int[] curveVertexCounts = [4]\n int[] order = [4]\n\
         double[] knots = [0, 0, 0, 0, 1, 1, 1, 1]\n point3f[] points.timeSamples = {\n\
         1: [(0, 0, 0), (0, 1, 0), (0, 2, 0), (0, 3, 0)],\n 2: [(0, 0, 0), (0.1, 1, 0), (0.2, 2, 0), (0.3, 3, 0)],\n}\n}\n",
    )
    .unwrap();
    let out = dir.path().join("animated_out.usda");
    let converted = coif(&["convert", path_str(&animated), path_str(&out)]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    let at_two = pxr_dump(&out, Some(2.0));
    let (_, guides) = curves_by_path(&at_two).into_iter().find(|(p, _)| p == "/guides").unwrap();
    assert_eq!(guides["pointsTimeSamples"], serde_json::json!([1.0, 2.0]), "time samples kept");
    assert_eq!(f32s(&guides["points"])[9], 0.3, "the second sample's tip");

    // Unclamped (uniform) knots: a B-spline that does not start at its first control point.
    std::fs::write(&source, stage("4, 4", "0, 1, 2, 3, 4, 5, 6, 7, 0, 1, 2, 3, 4, 5, 6, 7, 8", "")).unwrap();
    let out = dir.path().join("uniform.usda");
    let converted = coif(&["convert", path_str(&source), path_str(&out)]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    let dump = pxr_dump(&out, None);
    let guides = curves_by_path(&dump).into_iter().find(|(p, _)| p == "/groom/guides").unwrap().1.clone();
    assert_eq!((guides["basis"].as_str(), guides["wrap"].as_str()), (Some("bspline"), Some("nonperiodic")));

    for (order, knots, extra, expected) in [
        ("3, 3", "0, 0, 0, 1, 1, 1, 0, 0, 0, 1, 2, 2, 2", "", "order 3 (degree 2)"),
        ("4, 2", "0, 0, 0, 0, 1, 1, 1, 1, 0, 0, 1, 2, 3, 4, 4", "", "orders 4 and 2 mixed"),
        ("4, 4", "0, 0, 0, 0, 1, 1, 1, 1", "", "8 knots where its curves need 17"),
        ("4, 4", "0, 0, 0, 0, 1, 1, 1, 1, 0, 1, 2, 3, 4, 5, 6, 7, 8", "", "clamped and not clamped mixed"),
        ("4, 4", clamped, " double[] pointWeights = [1, 1, 2, 1, 1, 1, 1, 1, 1]\n", "point weight of 2"),
    ] {
        std::fs::write(&source, stage(order, knots, extra)).unwrap();
        let out = dir.path().join("refused.usda");
        let result = coif(&["convert", path_str(&source), path_str(&out)]);
        assert_eq!(result.status.code(), Some(2), "{expected}: {}", stderr(&result));
        let message = stderr(&result);
        assert!(message.contains("</groom/guides>") && message.contains(expected), "{expected}: {message}");
        assert!(!out.exists());
    }
}

#[test]
fn directions_rotate_with_the_points_from_z_up() {
    // Blender-style Z-up stage: a normal3f primvar and a plain float3 `surface_normal`.
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("zup.usda");
    let normals = [[0.0f32, 0.0, 1.0], [0.0, 0.6, 0.8], [1.0, 0.0, 0.0]];
    let text_normals: Vec<String> =
        normals.iter().map(|n| format!("({}, {}, {})", n[0], n[1], n[2])).collect();
    std::fs::write(
        &source,
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Z\"\n)\ndef BasisCurves \"Hair\"\n{{\n    uniform token type = \"linear\"\n    int[] curveVertexCounts = [2, 2, 2]\n    point3f[] points = [(0, 0, 0), (0, 0, 1), (1, 0, 0), (1, 0, 1), (2, 0, 0), (2, 1, 1)]\n    normal3f[] primvars:N = [{0}] (\n        interpolation = \"uniform\"\n    )\n    float3[] primvars:surface_normal = [{0}] (\n        interpolation = \"uniform\"\n    )\n}}\n",
            text_normals.join(", ")
        ),
    )
    .unwrap();
    let out = dir.path().join("yup.usda");
    let result = coif(&["convert", path_str(&source), path_str(&out)]);
    assert!(result.status.success(), "{}", stderr(&result));
    let written = pxr_dump(&out, None);
    assert_eq!(written["upAxis"], "Y");
    for name in ["N", "surface_normal"] {
        let values = f32s(&written["curves"][0]["primvars"][name]["values"]);
        // Z up to Y up: (x, y, z) -> (x, z, -y).
        let mean_dot: f32 = normals
            .iter()
            .zip(values.chunks_exact(3))
            .map(|(n, w)| n[0] * w[0] + n[2] * w[1] - n[1] * w[2])
            .sum::<f32>()
            / normals.len() as f32;
        assert!(mean_dot >= 0.999, "{name}: mean dot with the rotated source {mean_dot}");
    }
    assert_eq!(written["curves"][0]["primvars"]["N"]["type"], "normal3f[]");
}

#[test]
fn unreal_usd_output_has_epic_groom_attributes_and_no_mesh() {
    // What Unreal's USD groom importer reads: `groom_*` primvars (int per strand for ids, guide
    // flags and group ids, float2 root UVs), `widths` (vertex), and the spec version as
    // `userProperties:groom_version_*` ints on the root prim. Checked in pxr against the input.
    let dir = tempfile::tempdir().unwrap();
    let blender = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/blender_groom.usda");
    for (input, ext) in [(blender.clone(), "usda"), (blender, "usdc"), (houdini_groom(), "usda")] {
        let out = dir.path().join(format!("unreal.{ext}"));
        let run = coif(&["convert", path_str(&input), path_str(&out), "--unreal"]);
        assert!(run.status.success(), "{}", stderr(&run));
        let (source, written) = (pxr_dump(&input, None), pxr_dump(&out, None));
        let label = format!("{} → .{ext}", input.display());
        assert!(
            source["prims"].as_array().unwrap().iter().any(|p| p[1] == "Mesh"),
            "{label}: the input has a mesh"
        );
        assert!(
            !written["prims"].as_array().unwrap().iter().any(|p| p[1] == "Mesh"),
            "{label}: a mesh in the groom file"
        );
        // The meshes go to the sibling file the run reports, as the same Mesh prims a plain
        // convert writes.
        let sibling = dir.path().join(format!("unreal_meshes.{ext}"));
        let meshes = pxr_dump(&sibling, None);
        assert_eq!(meshes["validationErrors"], serde_json::json!([]), "{label}: sibling UsdValidation");
        assert!(meshes["curves"].as_array().unwrap().is_empty(), "{label}: curves in the mesh file");
        assert_same_meshes(&source, &meshes, &format!("{label} (meshes file)"));
        let root = format!("/{}", written["defaultPrim"].as_str().unwrap());
        for (name, value) in [("groom_version_major", 1), ("groom_version_minor", 5)] {
            let property = &written["userProperties"][format!("{root}.userProperties:{name}")];
            assert_eq!(
                (property["type"].as_str(), property["value"].as_i64()),
                (Some("int"), Some(value)),
                "{label}: {name}"
            );
        }
        // Widths as a plain convert writes them (metres, world scale applied; checked against
        // pxr by the round-trip test): --unreal changes names, not values.
        let plain_path = dir.path().join(format!("plain.{ext}"));
        assert!(coif(&["convert", path_str(&input), path_str(&plain_path)]).status.success());
        let plain = pxr_dump(&plain_path, None);
        let plain_curves = curves_by_path(&plain);
        let (source_curves, written_curves) = (curves_by_path(&source), curves_by_path(&written));
        assert_eq!(source_curves.len(), written_curves.len(), "{label}");
        for (group, ((path, src), (out_path, out))) in source_curves.iter().zip(&written_curves).enumerate() {
            assert_eq!(path, out_path, "{label}");
            let strands = src["counts"].as_array().unwrap().len();
            let primvar = |name: &str, ty: &str| -> Vec<f32> {
                let p = &out["primvars"][name];
                assert_eq!(
                    (p["type"].as_str(), p["interpolation"].as_str()),
                    (Some(ty), Some("uniform")),
                    "{label} {path} {name}"
                );
                let values = f32s(&p["values"]);
                assert_eq!(
                    values.len(),
                    strands * if ty.starts_with("float2") { 2 } else { 1 },
                    "{label} {path} {name}"
                );
                values
            };
            assert!(primvar("groom_group_id", "int[]").iter().all(|&g| g == group as f32), "{label} {path}");
            assert_eq!(primvar("groom_id", "int[]").len(), strands);
            let guide = if src["purpose"] == "guide" { 1.0 } else { 0.0 };
            if out["primvars"].get("groom_guide").is_some() {
                assert!(primvar("groom_guide", "int[]").iter().all(|&g| g == guide), "{label} {path}");
            } else {
                assert!(source_curves.iter().all(|(_, c)| c["purpose"] != "guide"), "{label}: guides lost");
            }
            // Root UVs: the file's own, or Blender's surface UV.
            let uv_source = ["st", "surface_uv_coordinate"].iter().find_map(|n| src["primvars"].get(*n));
            if let Some(uv) = uv_source {
                assert_eq!(primvar("groom_root_uv", "float2[]"), f32s(&uv["values"]), "{label} {path}");
            }
            assert_eq!(out["widthsInterpolation"], "vertex", "{label}");
            assert_eq!(vertex_widths(out), vertex_widths(plain_curves[group].1), "{label}: widths");
            assert_eq!(out["points"], plain_curves[group].1["points"], "{label}: points");
            for name in out["primvars"].as_object().unwrap().keys() {
                assert!(
                    name.starts_with("groom_") || name == "st",
                    "{label}: primvar {name} is not Unreal's"
                );
            }
        }
    }
    // Alembic: Unreal refuses a groom .abc holding a PolyMesh; the mesh goes to the sibling
    // file, named in --json, in the groom file's centimetres.
    let abc = dir.path().join("unreal.abc");
    let run = coif(&["convert", "tests/data/blender_groom.usda", path_str(&abc), "--unreal", "--json"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let sibling = dir.path().join("unreal_meshes.abc");
    assert_eq!(stdout_json(&run)["meshes_output"], path_str(&sibling));
    let bytes = std::fs::read(&abc).unwrap();
    assert!(!bytes.windows(18).any(|w| w == b"AbcGeom_PolyMesh_v"), "a PolyMesh in the Unreal .abc");
    let plain_abc = dir.path().join("plain.abc");
    assert!(coif(&["convert", "tests/data/blender_groom.usda", path_str(&plain_abc)]).status.success());
    let plain_mesh = &read(&plain_abc).meshes[0];
    let (points, counts, indices) = polymesh_via_ogawa_rs(&sibling);
    assert_eq!(counts, plain_mesh.face_counts.iter().map(|&c| c as i32).collect::<Vec<_>>());
    assert_eq!(indices.len(), plain_mesh.face_indices.len());
    for (p, q) in points.iter().zip(&plain_mesh.points) {
        assert!((glam::Vec3::from(*p) / 100.0 - *q).length() < 1e-6, "{p:?} cm vs {q} m");
    }
    assert!(
        bytes.windows(14).any(|w| w == b"groom_root_uv\0")
            || bytes.windows(13).any(|w| w == b"groom_root_uv")
    );
    // Formats Unreal does not import are refused, naming the flag.
    let run =
        coif(&["convert", "tests/data/blender_groom.usda", path_str(&dir.path().join("u.hair")), "--unreal"]);
    assert_eq!(run.status.code(), Some(2));
    assert!(stderr(&run).contains("--unreal"), "{}", stderr(&run));
    // `coif style --unreal` writes the same layout (the sibling named in --json), and refuses the
    // same formats before styling, writing nothing.
    let recipe = dir.path().join("brief.toml");
    std::fs::write(&recipe, "[[stages]]\nkind = \"process\"\nduration = 0.01\n").unwrap();
    let style = |out: &Path| {
        let args =
            ["style", path_str(&recipe), "--groom", "tests/data/blender_groom.usda", "-o", path_str(out)];
        coif(&[&args[..], &["--unreal", "--json", "--quiet"]].concat())
    };
    let styled = dir.path().join("styled.abc");
    let run = style(&styled);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(stdout_json(&run)["meshes_output"], path_str(&dir.path().join("styled_meshes.abc")));
    let bytes = std::fs::read(&styled).unwrap();
    assert!(!bytes.windows(18).any(|w| w == b"AbcGeom_PolyMesh_v"), "a PolyMesh in the styled Unreal .abc");
    assert!(bytes.windows(13).any(|w| w == b"groom_root_uv"));
    for ext in ["hair", "usdz"] {
        let out = dir.path().join(format!("styled.{ext}"));
        let run = style(&out);
        assert_eq!(run.status.code(), Some(2), "{ext}: {}", stderr(&run));
        assert!(stderr(&run).contains("--unreal"), "{}", stderr(&run));
        assert!(!out.exists());
    }
}

#[test]
fn unreal_usd_output_of_a_groom_without_groups() {
    // A `.hair` file, or a plain one-prim USD, has no group table: `--unreal` to USD must give
    // every strand group 0 (it panicked indexing the missing table), and `style --unreal` writes
    // the same. Checked in pxr.
    let dir = tempfile::tempdir().unwrap();
    let strands: Vec<Vec<glam::Vec3>> = (0..3)
        .map(|s| (0..5).map(|k| glam::Vec3::new(s as f32 * 0.01, -0.02 * k as f32, 0.0)).collect())
        .collect();
    let hair = dir.path().join("one.hair");
    coif::io::write_groom(&hair, &Groom::from_strands(&strands, 1e-4)).unwrap();
    let plain = dir.path().join("plain.usda");
    assert!(coif(&["convert", path_str(&hair), path_str(&plain)]).status.success());
    let recipe = dir.path().join("brief.toml");
    std::fs::write(&recipe, "[[stages]]\nkind = \"process\"\nduration = 0.01\n").unwrap();
    for ext in ["usda", "usdc"] {
        for (label, input) in [("hair", &hair), ("usda", &plain)] {
            let out = dir.path().join(format!("{label}_unreal.{ext}"));
            let convert = ["convert", path_str(input), path_str(&out), "--unreal"];
            let styled = dir.path().join(format!("{label}_styled.{ext}"));
            let args = ["style", path_str(&recipe), "--groom", path_str(input), "-o", path_str(&styled)];
            let style = [&args[..], &["--unreal", "--quiet"]].concat();
            for (run, written) in [(coif(&convert), &out), (coif(&style), &styled)] {
                let label = format!("{label} → {}", written.display());
                assert!(run.status.success(), "{label}: {}", stderr(&run));
                let dump = pxr_dump(written, None);
                let curves = curves_by_path(&dump);
                assert_eq!(curves.len(), 1, "{label}");
                let group_ids = &curves[0].1["primvars"]["groom_group_id"];
                assert_eq!(group_ids["type"], "int[]", "{label}");
                assert_eq!(f32s(&group_ids["values"]), vec![0.0; 3], "{label}");
                assert_eq!(f32s(&curves[0].1["counts"]), vec![5.0; 3], "{label}");
            }
        }
    }
}

#[test]
fn blender_grooms_convert_round_trips_are_exact_in_pxr() {
    // Blender's USD (centimetres, Z up, a ×100 scale on /root) and its Alembic of the same scene
    // (metres, Y up), converted to .usda and .usdc: pxr must see the same prims, bases, wraps,
    // segment counts, points and widths (in metres, Y up), primvar types and roles, and
    // `surface_normal` turned with the points.
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let usd = data.join("blender_groom.usda");
    let source = pxr_dump(&usd, None);
    let to_coif = |dump: &Value, c: &Value, key: &str| -> Vec<f32> {
        let mpu = dump["metersPerUnit"].as_f64().unwrap() as f32;
        let v = f32s(&c[key]);
        v.chunks_exact(3).flat_map(|p| [p[0] * mpu, p[2] * mpu, -p[1] * mpu]).collect()
    };
    for (input, ext) in [
        (usd.clone(), "usda"),
        (data.join("blender_groom.usdc"), "usdc"),
        (data.join("blender_groom.abc"), "usda"),
    ] {
        let out = dir.path().join(format!("out.{ext}"));
        let run = coif(&["convert", path_str(&input), path_str(&out)]);
        assert!(run.status.success(), "{}", stderr(&run));
        let written = pxr_dump(&out, None);
        let label = format!("{} → .{ext}", input.display());
        assert_eq!(written["validationErrors"], serde_json::json!([]), "{label}: UsdValidation");
        let (sc, wc) = (curves_by_path(&source), curves_by_path(&written));
        assert_eq!(sc.len(), wc.len(), "{label}");
        for (path, a) in &sc {
            // Prim order may differ (Blender's .usdc lists Hair first), and Blender's Alembic has
            // no /root: match by the object and data names.
            let tail = path.trim_start_matches("/root");
            let b =
                wc.iter().find(|(p, _)| p.ends_with(tail)).unwrap_or_else(|| panic!("{label}: no {tail}")).1;
            // Alembic records no `pinned`, but Catmull-Rom read from it is pinned, as Blender
            // means it: the same wraps and pxr segment counts from every input.
            let from_abc = input.extension().unwrap() == "abc";
            let keys = ["type", "basis", "wrap", "counts", "segmentEnds"];
            for key in keys {
                assert_eq!(a[key], b[key], "{label} {path}: {key}");
            }
            let (pa, pb) = (to_coif(&source, a, "world_points"), f32s(&b["world_points"]));
            assert_eq!(pa.len(), pb.len());
            let worst = pa.iter().zip(&pb).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
            assert!(worst < 2e-6, "{label} {path}: points differ by {worst} m");
            // Widths scale with the stage units and /root's ×100 (the ratio of world to local
            // lengths of the first segment).
            let (local, world) = (f32s(&a["points"]), f32s(&a["world_points"]));
            let length =
                |v: &[f32]| ((v[3] - v[0]).powi(2) + (v[4] - v[1]).powi(2) + (v[5] - v[2]).powi(2)).sqrt();
            let scale = length(&world) / length(&local) * source["metersPerUnit"].as_f64().unwrap() as f32;
            for (x, y) in vertex_widths(a).iter().zip(vertex_widths(b)) {
                assert!(
                    (x * scale - y).abs() <= 1e-6 * y.abs().max(1e-6),
                    "{label} {path}: width {x} vs {y} m"
                );
            }
            if !from_abc {
                for (name, primvar) in a["primvars"].as_object().unwrap() {
                    let w = &b["primvars"][name];
                    for key in ["type", "interpolation"] {
                        assert_eq!(primvar[key], w[key], "{label} {path}: primvar {name} {key}");
                    }
                }
                let normals = (
                    to_coif(&source, &a["primvars"]["surface_normal"], "values"),
                    f32s(&b["primvars"]["surface_normal"]["values"]),
                );
                let n = normals.0.len() / 3;
                let mean_dot: f32 = normals
                    .0
                    .chunks_exact(3)
                    .zip(normals.1.chunks_exact(3))
                    .map(|(p, q)| {
                        (p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
                            / (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
                            / (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt()
                    })
                    .sum::<f32>()
                    / n as f32;
                assert!(n > 0 && mean_dot >= 0.999, "{label} {path}: surface_normal mean dot {mean_dot}");
            }
        }
        // The head mesh comes back as a Mesh prim where Blender put it.
        assert_same_meshes(&source, &written, &label);
    }
}

#[test]
fn unreal_meshes_file_is_written_with_the_groom_or_not_at_all() {
    // The groom file cannot be put in place (a directory holds its name): the run fails and
    // leaves neither the meshes file nor a temporary behind.
    for ext in ["usda", "abc"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join(format!("groom.{ext}"));
        std::fs::create_dir(&out).unwrap();
        let run = coif(&["convert", "tests/data/blender_groom.usda", path_str(&out), "--unreal"]);
        assert!(!run.status.success(), ".{ext}: a directory was overwritten");
        assert_eq!(dir_listing(dir.path()), vec![format!("groom.{ext}")], ".{ext}: {}", stderr(&run));
    }
    // A mesh that cannot be written (a face naming a point it lacks) is refused, naming the
    // mesh, with nothing written in any format, Unreal layout or not.
    let mut groom = read(&houdini_groom());
    groom.meshes[0].face_indices[0] = 99;
    let dir = tempfile::tempdir().unwrap();
    for (ext, unreal) in [("usda", false), ("usdc", false), ("abc", false), ("usda", true), ("abc", true)] {
        let path = dir.path().join(format!("bad.{ext}"));
        let error =
            coif::io::write_groom_with(&path, &groom, &coif::io::ExportOptions { unreal }).unwrap_err();
        assert_eq!(error.exit_code(), 2, "{error}");
        assert!(error.to_string().contains("/skin"), ".{ext}: {error}");
        assert!(dir_listing(dir.path()).is_empty(), ".{ext}: {:?}", dir_listing(dir.path()));
    }
}

/// The meshes file cannot be put in place (a directory holds its name; a full disk fails the
/// same way, later): the groom file is not left behind, and a groom file from an earlier run is
/// restored. The groom file was renamed into place first and kept: a new groom beside no (or an
/// old) meshes file, exit 1.
#[test]
fn unreal_groom_file_is_taken_back_when_its_meshes_file_fails() {
    for ext in ["usda", "usdc", "abc"] {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join(format!("groom.{ext}"));
        let meshes = format!("groom_meshes.{ext}");
        std::fs::create_dir(dir.path().join(&meshes)).unwrap();
        let convert = || coif(&["convert", "tests/data/blender_groom.usda", path_str(&out), "--unreal"]);
        let run = convert();
        assert!(!run.status.success(), ".{ext}: a directory was overwritten");
        assert_eq!(dir_listing(dir.path()), vec![meshes.clone()], ".{ext}: {}", stderr(&run));

        let previous = b"the groom file of an earlier run";
        std::fs::write(&out, previous).unwrap();
        let run = convert();
        assert!(!run.status.success(), ".{ext}: a directory was overwritten");
        assert_eq!(std::fs::read(&out).unwrap(), previous, ".{ext}: the earlier groom file was replaced");
        assert_eq!(
            dir_listing(dir.path()),
            vec![format!("groom.{ext}"), meshes.clone()],
            ".{ext}: {}",
            stderr(&run)
        );
    }
}

#[test]
fn nonperiodic_catmull_rom_to_alembic_warns_naming_the_file_and_object() {
    // Alembic records no wrap, and its readers (Blender, coif) take Catmull-Rom as pinned: a
    // nonperiodic Catmull-Rom group cannot survive a write to `.abc`. The run says so, naming
    // the output file and the curve object; linear groups and pinned sources need no warning.
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string("tests/data/blender_groom.usda").unwrap();
    assert_eq!(text.matches("wrap = \"pinned\"").count(), 1, "Blender's guides are pinned");
    let source = dir.path().join("nonperiodic.usda");
    std::fs::write(&source, text.replace("wrap = \"pinned\"", "wrap = \"nonperiodic\"")).unwrap();
    let guides = "/root/Head/Guides/GuidesData";
    assert_eq!(group_summary(&read(&source))[0].2, CurveWrap::Nonperiodic, "{guides} in the source");
    let out = dir.path().join("out.abc");
    let run = coif(&["convert", path_str(&source), path_str(&out)]);
    assert!(run.status.success(), "{}", stderr(&run));
    let text = stderr(&run);
    let warnings: Vec<&str> = text.lines().filter(|l| l.starts_with("coif: warning:")).collect();
    assert_eq!(warnings.len(), 1, "one group changes: {text}");
    for needed in [path_str(&out), &format!("'{guides}'"), "Nonperiodic", "Pinned"] {
        assert!(warnings[0].contains(needed), "the warning names {needed}: {}", warnings[0]);
    }
    // What it warns of is what a reader gets.
    let back = group_summary(&read(&out));
    let guides_back = back.iter().find(|g| g.0.ends_with("Guides/GuidesData")).unwrap();
    assert_eq!(guides_back.2, CurveWrap::Pinned);
    // Control: Blender's own pinned guides convert without a warning.
    let run = coif(&["convert", "tests/data/blender_groom.usda", path_str(&dir.path().join("pinned.abc"))]);
    assert!(run.status.success());
    assert!(!stderr(&run).contains("warning"), "{}", stderr(&run));
}

#[test]
fn constant_and_varying_primvars_keep_their_interpolation_through_convert() {
    // Constant and varying primvars on a linear and a pinned Catmull-Rom prim (where varying is
    // one value per vertex), and varying on a nonperiodic B-spline (fewer segment ends than
    // points: each end's value goes to the point it lies next to, points 1..=3, and the unreached
    // end points repeat their neighbours; written back per vertex). pxr must see the source's
    // interpolation, type and values again in coif's .usda and .usdc.
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("interpolations.usda");
    let prim = |name: &str, head: &str, counts: &str, points: &str, stiffness: f32, clump: &str| {
        format!(
            "    def BasisCurves \"{name}\"\n    {{\n{head}        int[] curveVertexCounts = [{counts}]\n        point3f[] points = [{points}]\n        float[] primvars:stiffness = [{stiffness}] (\n            interpolation = \"constant\"\n        )\n        color3f[] primvars:tint = [(0.1, 0.2, 0.3)] (\n            interpolation = \"constant\"\n        )\n        float[] primvars:clump = [{clump}] (\n            interpolation = \"varying\"\n        )\n    }}\n"
        )
    };
    let text = format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef Xform \"G\"\n{{\n{}{}{}}}\n",
        prim(
            "lin",
            "        uniform token type = \"linear\"\n",
            "3, 4",
            "(0, 0, 0), (0, 1, 0), (0, 2, 0), (1, 0, 0), (1, 1, 0), (1, 2, 0), (1, 3, 0)",
            0.5,
            "0, 1, 2, 3, 4, 5, 6"
        ),
        prim(
            "crom",
            "        uniform token type = \"cubic\"\n        uniform token basis = \"catmullRom\"\n        uniform token wrap = \"pinned\"\n",
            "4",
            "(2, 0, 0), (2, 1, 0), (2, 2, 0), (2, 3, 0)",
            0.25,
            "7, 8, 9, 10"
        ),
        prim(
            "bspl",
            "        uniform token type = \"cubic\"\n        uniform token basis = \"bspline\"\n",
            "5",
            "(3, 0, 0), (3, 1, 0), (3, 2, 0), (3, 3, 0), (3, 4, 0)",
            0.75,
            "1, 2, 3"
        ),
    );
    std::fs::write(&source, text).unwrap();
    let want = pxr_dump(&source, None);
    for ext in ["usda", "usdc"] {
        let out = dir.path().join(format!("out.{ext}"));
        let run = coif(&["convert", path_str(&source), path_str(&out)]);
        assert!(run.status.success(), "{}", stderr(&run));
        let got = pxr_dump(&out, None);
        for w in want["curves"].as_array().unwrap() {
            let path = w["path"].as_str().unwrap();
            let g = got["curves"].as_array().unwrap().iter().find(|c| c["path"] == path).unwrap();
            for name in ["stiffness", "tint", "clump"] {
                let (a, b) = (&w["primvars"][name], &g["primvars"][name]);
                let spread = path.ends_with("bspl") && name == "clump";
                assert_eq!(a["type"], b["type"], ".{ext} {path} {name}");
                if spread {
                    assert_eq!(b["interpolation"], "vertex", ".{ext} {path} {name}");
                    assert_eq!(f32s(&b["values"]), [1.0, 1.0, 2.0, 3.0, 3.0], ".{ext} {path} {name}");
                } else {
                    assert_eq!(a["interpolation"], b["interpolation"], ".{ext} {path} {name}");
                    assert_eq!(f32s(&a["values"]), f32s(&b["values"]), ".{ext} {path} {name}");
                }
            }
        }
    }
}

/// The source's mesh primvars (and normals) as pxr sees them after coif's conversion: names,
/// types, roles, interpolations; values exact, or moved Z up → Y up as the points are
/// (`rest_position` like the points, normals rotated: mean dot with the rotated source).
fn assert_same_mesh_primvars(source: &Value, written: &Value, label: &str) {
    assert_eq!((&source["upAxis"], &written["upAxis"]), (&Value::from("Z"), &Value::from("Y")));
    let (a, b) = (&source["meshes"][0], &written["meshes"][0]);
    let (sp, wp) = (a["primvars"].as_object().unwrap(), b["primvars"].as_object().unwrap());
    for name in ["st", "scalp", "rest_position"] {
        assert!(sp.contains_key(name), "the source has {name}");
    }
    for (name, s) in sp {
        let w = wp.get(name).unwrap_or_else(|| panic!("{label}: primvar {name} is missing"));
        for key in ["type", "role", "interpolation"] {
            assert_eq!(s[key], w[key], "{label}: primvar {name}: {key}");
        }
        let (sv, wv) = (f32s(&s["values"]), f32s(&w["values"]));
        assert_eq!(sv.len(), wv.len(), "{label}: primvar {name}: values");
        // Blender's rest positions are the mesh's points: they must move as the points do.
        let expected: Vec<f32> = if name == "rest_position" {
            assert_eq!(sv, f32s(&a["points"]), "the source's rest positions are its points");
            f32s(&b["points"])
        } else {
            sv
        };
        for (i, (x, y)) in expected.iter().zip(&wv).enumerate() {
            assert!((x - y).abs() <= 2e-6, "{label}: primvar {name} value {i}: {x} vs {y}");
        }
    }
    let (sn, wn) = (&a["normals"], &b["normals"]);
    assert!(sn.is_object(), "the source has normals");
    assert_eq!((&sn["type"], &sn["interpolation"]), (&wn["type"], &wn["interpolation"]), "{label}: normals");
    let (sv, wv) = (f32s(&sn["values"]), f32s(&wn["values"]));
    assert_eq!(sv.len(), wv.len(), "{label}: normals");
    let dots: Vec<f32> = sv
        .chunks_exact(3)
        .zip(wv.chunks_exact(3))
        .map(|(n, w)| n[0] * w[0] + n[2] * w[1] - n[1] * w[2])
        .collect();
    let mean_dot = dots.iter().sum::<f32>() / dots.len() as f32;
    assert!(mean_dot >= 0.999, "{label}: normals' mean dot with the rotated source {mean_dot}");
}

#[test]
fn scalp_mesh_primvars_survive_usd_and_alembic_conversion_to_y_up() {
    // Blender's Z-up centimetre... stage: the head carries `st` (faceVarying texCoord2f),
    // `scalp` (vertex float), `rest_position` (vertex float3) and faceVarying normals.
    let source_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/blender_groom.usda");
    let source = pxr_dump(&source_path, None);
    let dir = tempfile::tempdir().unwrap();
    for ext in ["usda", "usdc"] {
        let out = dir.path().join(format!("converted.{ext}"));
        let result = coif(&["convert", path_str(&source_path), path_str(&out)]);
        assert!(result.status.success(), "{}", stderr(&result));
        assert_same_mesh_primvars(&source, &pxr_dump(&out, None), ext);
    }
    // Through Alembic (PolyMesh `N`, `uv`, `.arbGeomParams`, clockwise faces) and back to USD.
    let abc = dir.path().join("converted.abc");
    let back = dir.path().join("back.usda");
    for (from, to) in [(&source_path, &abc), (&abc, &back)] {
        let result = coif(&["convert", path_str(from), path_str(to)]);
        assert!(result.status.success(), "{}", stderr(&result));
    }
    assert_same_mesh_primvars(&source, &pxr_dump(&back, None), "via .abc");
}

#[test]
fn blender_alembic_head_keeps_its_uvs_and_normals() {
    // Blender's own .abc head: `uv` (sourceName UVMap) and `N`, both face-varying; its USD
    // export of the same scene holds the same UVs (as `st`: Blender's USD exporter renames the
    // active map) and normals, corner for corner. coif's USD output names the set as the .abc did.
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("from_abc.usda");
    let result = coif(&["convert", path_str(&data.join("blender_groom.abc")), path_str(&out)]);
    assert!(result.status.success(), "{}", stderr(&result));
    let (usd, written) = (pxr_dump(&data.join("blender_groom.usda"), None), pxr_dump(&out, None));
    let (a, b) = (&usd["meshes"][0], &written["meshes"][0]);
    assert_eq!(a["indices"], b["indices"], "the same faces in the same winding");
    assert!(b["primvars"].get("st").is_none(), "the set keeps its name: {}", b["primvars"]);
    let st = &b["primvars"]["UVMap"];
    assert_eq!(
        (&st["type"], &st["interpolation"]),
        (&Value::from("texCoord2f[]"), &Value::from("faceVarying"))
    );
    let (su, wu) = (f32s(&a["primvars"]["st"]["values"]), f32s(&st["values"]));
    assert_eq!(su.len(), wu.len());
    assert!(su.iter().zip(&wu).all(|(x, y)| (x - y).abs() <= 1e-6), "UVs corner for corner");
    assert_eq!(b["normals"]["interpolation"], "faceVarying");
    let (sn, wn) = (f32s(&a["normals"]["values"]), f32s(&b["normals"]["values"]));
    // Both exports are Z up; coif's output is Y up: rotate the USD export's normals.
    let mean_dot = sn
        .chunks_exact(3)
        .zip(wn.chunks_exact(3))
        .map(|(n, w)| n[0] * w[0] + n[2] * w[1] - n[1] * w[2])
        .sum::<f32>()
        / (sn.len() / 3) as f32;
    assert!(mean_dot >= 0.999, "normals: mean dot {mean_dot}");
}

#[test]
fn a_mesh_primvar_whose_count_fits_no_interpolation_exits_2_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad_uv.usda");
    std::fs::write(
        &path,
        "#usda 1.0\n(\n    metersPerUnit = 1\n)\ndef BasisCurves \"Hair\"\n{\n    uniform token type = \"linear\"\n    int[] curveVertexCounts = [2]\n    point3f[] points = [(0, 0, 0), (0, 1, 0)]\n}\ndef Mesh \"Scalp\"\n{\n    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 0, 1)]\n    texCoord2f[] primvars:st = [(0, 0), (1, 0)] (\n        interpolation = \"faceVarying\"\n    )\n}\n",
    )
    .unwrap();
    let out = coif(&["info", path_str(&path)]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    let message = stderr(&out);
    assert!(
        message.contains("bad_uv.usda")
            && message.contains("</Scalp>")
            && message.contains("'st'")
            && message.contains("needs 3 values, found 2"),
        "{message}"
    );
}

#[test]
fn widths_keep_their_interpolation_through_convert() {
    // Widths at every rate USD has: constant, uniform (one per curve, on pinned Catmull-Rom),
    // varying (one per segment end, fewer than the points on nonperiodic B-spline and Bézier
    // curves) and vertex. The groom keeps widths per vertex; coif's .usda, .usdc and .abc must give
    // each prim's widths back at the source's rate with the source's values, as pxr (USD) and
    // ogawa-rs (the Alembic `width` and its geoScope) read them, and the .abc read back by coif
    // must give the same USD again.
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("widths.usda");
    let prim = |name: &str, head: &str, counts: &str, points: usize, widths: &str, interpolation: &str| {
        let points: Vec<String> = (0..points).map(|i| format!("({}, {i}, {})", name.len(), i % 2)).collect();
        format!(
            "    def BasisCurves \"{name}\"\n    {{\n{head}        int[] curveVertexCounts = [{counts}]\n        point3f[] points = [{}]\n        float[] widths = [{widths}] (\n            interpolation = \"{interpolation}\"\n        )\n    }}\n",
            points.join(", ")
        )
    };
    let cubic = |basis: &str, wrap: &str| {
        format!("        uniform token type = \"cubic\"\n        uniform token basis = \"{basis}\"\n        uniform token wrap = \"{wrap}\"\n")
    };
    let linear = "        uniform token type = \"linear\"\n";
    let text = format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef Xform \"G\"\n{{\n{}{}{}{}{}}}\n",
        prim("con", linear, "3, 4", 7, "0.01", "constant"),
        prim("uni", &cubic("catmullRom", "pinned"), "4, 5", 9, "0.02, 0.03", "uniform"),
        prim("var", &cubic("bspline", "nonperiodic"), "5, 4", 9, "0.01, 0.02, 0.03, 0.04, 0.05", "varying"),
        prim("bez", &cubic("bezier", "nonperiodic"), "7", 7, "0.01, 0.02, 0.03", "varying"),
        prim("vtx", linear, "2", 2, "0.01, 0.02", "vertex"),
    );
    std::fs::write(&source, text).unwrap();
    let want = pxr_dump(&source, None);
    let want = want["curves"].as_array().unwrap();
    assert_eq!(want.len(), 5);
    for w in want {
        if w["widthsInterpolation"] == "varying" {
            // pxr's own count of segment ends is what the source gives.
            assert_eq!(
                w["segmentEnds"].as_u64().unwrap() as usize,
                f32s(&w["widths"]).len(),
                "{}",
                w["path"]
            );
        }
    }
    let same_widths = |got: &Value, label: &str| {
        for w in want {
            let path = w["path"].as_str().unwrap();
            let g = got["curves"].as_array().unwrap().iter().find(|c| c["path"] == path).unwrap();
            assert_eq!(g["widthsInterpolation"], w["widthsInterpolation"], "{label} {path}");
            assert_eq!(f32s(&g["widths"]), f32s(&w["widths"]), "{label} {path}");
            assert!(
                got["validationErrors"].as_array().unwrap().is_empty(),
                "{label}: {}",
                got["validationErrors"]
            );
        }
    };
    for ext in ["usda", "usdc", "abc"] {
        let out = dir.path().join(format!("out.{ext}"));
        let run = coif(&["convert", path_str(&source), path_str(&out)]);
        assert!(run.status.success(), "{}", stderr(&run));
        if ext == "abc" {
            let scopes = [("constant", "con"), ("uniform", "uni"), ("varying", "var"), ("vertex", "vtx")];
            let read = curve_widths_via_ogawa_rs(&out);
            assert_eq!(read.len(), want.len());
            for w in want {
                let path = w["path"].as_str().unwrap();
                let (_, scope, values) = read.iter().find(|(name, _, _)| name == path).unwrap();
                let usd = w["widthsInterpolation"].as_str().unwrap();
                assert_eq!(scope, scopes.iter().find(|s| s.0 == usd).unwrap().1, ".abc {path}");
                assert_eq!(values, &f32s(&w["widths"]), ".abc {path}");
            }
            let back = dir.path().join("back.usda");
            let run = coif(&["convert", path_str(&out), path_str(&back)]);
            assert!(run.status.success(), "{}", stderr(&run));
            same_widths(&pxr_dump(&back, None), ".abc then .usda");
        } else {
            same_widths(&pxr_dump(&out, None), &format!(".{ext}"));
        }
    }
}

/// A linear `BasisCurves` prim `name` of `groom`'s `strands` (0.1 mm wide), with `extra` lines
/// (primvars) inside it.
fn linear_prim(groom: &Groom, name: &str, strands: &[usize], extra: &str) -> String {
    let counts: Vec<String> = strands.iter().map(|&s| groom.strand_range(s).len().to_string()).collect();
    let points: Vec<String> = strands
        .iter()
        .flat_map(|&s| groom.strand_points(s).iter().map(|p| format!("({}, {}, {})", p.x, p.y, p.z)))
        .collect();
    format!(
        "    def BasisCurves \"{name}\"\n    {{\n        uniform token type = \"linear\"\n        \
         int[] curveVertexCounts = [{}]\n        point3f[] points = [{}]\n        \
         float[] widths = [0.0001] (interpolation = \"constant\")\n{extra}    }}\n",
        counts.join(", "),
        points.join(", ")
    )
}

/// A stage of three curve prims: guides and children with Epic's `groom_id` (1000 + 7·i) and
/// bindings naming the guides' ids, and a prim without ids or bindings (a DCC's extra tuft).
fn stage_with_ids_on_some_prims() -> (String, Vec<u32>) {
    use coif::generate::{generate, GenerateParams};
    let groom =
        generate(&GenerateParams { strands: 45, vertices_per_strand: 6, seed: 5, ..Default::default() })
            .unwrap();
    let id = |s: usize| 1000 + 7 * s as u32;
    let guides: Vec<usize> = (0..40).step_by(4).collect();
    let children: Vec<usize> = (0..40).filter(|s| s % 4 != 0).collect();
    let prim = |name: &str, strands: &[usize], bound: Option<bool>| {
        let mut text = String::new();
        if let Some(guide) = bound {
            let list =
                |f: &dyn Fn(usize) -> String| strands.iter().map(|&s| f(s)).collect::<Vec<_>>().join(", ");
            // Each child follows the guide just before it (strands 4k are the guides).
            let closest = |s: usize| {
                let g = id(s - s % 4);
                format!("({g}, {g}, {g})")
            };
            text += &format!(
                "        int[] primvars:groom_id = [{}] (interpolation = \"uniform\")\n        \
                 int[] primvars:groom_guide = [{}] (interpolation = \"uniform\")\n        \
                 float3[] primvars:groom_closest_guides = [{}] (interpolation = \"uniform\")\n        \
                 float3[] primvars:groom_guide_weights = [{}] (interpolation = \"uniform\")\n",
                list(&|s| id(s).to_string()),
                list(&|_| (guide as u8).to_string()),
                list(&closest),
                list(&|_| "(1, 0, 0)".into()),
            );
        }
        linear_prim(&groom, name, strands, &text)
    };
    let text = format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n\ndef Xform \"groom\"\n{{\n{}{}{}}}\n",
        prim("guides", &guides, Some(true)),
        prim("hair", &children, Some(false)),
        prim("fuzz", &(40..45).collect::<Vec<_>>(), None),
    );
    // Ids in strand order of the merged groom: guides, children, then the tuft after the largest.
    let ids = guides.iter().chain(&children).map(|&s| id(s)).chain(1274..1279).collect();
    (text, ids)
}

/// A file's `groom_id`s are what its bindings name: they are kept through reading, conversion and
/// styling, whatever other prims or objects lack them. The Alembic reader moved every object's
/// ids past the previous object's largest (a styled groom's bindings then named guides that no
/// longer had those ids, and coif refused its own output), and the USD reader renumbered every
/// strand 0, 1, 2, … when one prim had no ids.
#[test]
fn a_files_strand_ids_survive_reading_conversion_and_styling() {
    let dir = tempfile::tempdir().unwrap();
    let (text, expected) = stage_with_ids_on_some_prims();
    let input = dir.path().join("in.usda");
    std::fs::write(&input, text).unwrap();
    assert_eq!(read(&input).strand_ids, expected, "as read");
    // Round trips through both formats, twice (ids drifted further on each pass through .abc).
    let mut previous = input.clone();
    for (step, ext) in ["abc", "usda", "abc", "usdc", "abc"].iter().enumerate() {
        for unreal in [false, true] {
            let out = dir.path().join(format!("step{step}_{unreal}.{ext}"));
            let mut args = vec!["convert", path_str(&previous), path_str(&out)];
            if unreal {
                args.push("--unreal");
            }
            let converted = coif(&args);
            assert!(converted.status.success(), "{args:?}: {}", stderr(&converted));
            assert_eq!(read(&out).strand_ids, expected, "{args:?}");
        }
        previous = dir.path().join(format!("step{step}_false.{ext}"));
    }
    // Styled through the file's own guides and bindings; the tuft's strands, bound to no guide,
    // are bound by coif; the output binds every child to guide ids the output has.
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("grooms/recipes/bedhead_scene1.toml");
    for groom in [&input, &previous] {
        let out = dir.path().join("styled.usda");
        let styled = coif(&["style", path_str(&recipe), "--groom", path_str(groom), "-o", path_str(&out)]);
        assert!(styled.status.success(), "{}: {}", groom.display(), stderr(&styled));
        let styled = read(&out);
        assert_eq!(styled.strand_ids, expected, "{}", groom.display());
        let flags = styled.guides.clone().expect("guide flags");
        let guide_ids: std::collections::HashSet<u32> =
            (0..styled.strand_count()).filter(|&s| flags[s]).map(|s| styled.strand_ids[s]).collect();
        let closest = styled.attribute("groom_closest_guides").expect("bindings");
        assert!(
            closest.floats().iter().all(|&id| guide_ids.contains(&(id as u32))),
            "{}: a binding names no guide",
            groom.display()
        );
        // The file's bindings are kept: the first child (strand 10, after the 10 guides) follows
        // the first guide (id 1000), and the tuft's strands (the last 5) are bound too.
        assert_eq!(closest.floats()[30..33], [1000.0; 3], "{}", groom.display());
        let weights = styled.attribute("groom_guide_weights").expect("weights");
        assert!(weights.floats()[40 * 3..].chunks(3).all(|w| (w.iter().sum::<f32>() - 1.0).abs() < 1e-5));
    }
}

/// What coif computes for every strand is written on every prim: `simulate` of a groom whose
/// guides alone had `rest` wrote the simulated rest state on the guides' prim only (the other
/// prims were written as their file had them, without one).
#[test]
fn a_simulated_state_is_written_on_every_prim() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.usda");
    assert!(read(&houdini_groom()).groups.iter().any(|g| !g.carries("rest")), "the fixture's premise");
    let simulated = coif(&["simulate", path_str(&houdini_groom()), path_str(&out), "--seconds", "0.01"]);
    assert!(simulated.status.success(), "{}", stderr(&simulated));
    let groom = read(&out);
    for name in ["rest", "rest_darboux", "wetness", "bond_hydrogen"] {
        for group in &groom.groups {
            assert!(group.carries(name), "{}: no {name}", group.name);
        }
    }
}

/// `style --group` places the recipe in the head frame of the whole groom, as a run of every
/// strand does (the README's promise): fitted to a fringe alone, the frame's front turned to the
/// back of the head. The other groups pass through untouched.
#[test]
fn a_group_is_styled_in_the_whole_grooms_head_frame() {
    use coif::generate::{generate, GenerateParams};
    let groom =
        generate(&GenerateParams { strands: 60, vertices_per_strand: 8, seed: 11, ..Default::default() })
            .unwrap();
    // The fringe: the strands rooted furthest to the front (+Z on coif's head).
    let mut by_front: Vec<usize> = (0..groom.strand_count()).collect();
    by_front.sort_by(|&a, &b| groom.strand_points(b)[0].z.total_cmp(&groom.strand_points(a)[0].z));
    let (fringe, others) = by_front.split_at(12);
    let prim = |name: &str, strands: &[usize]| linear_prim(&groom, name, strands, "");
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.usda");
    let text = format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n\ndef Xform \"groom\"\n{{\n{}{}}}\n",
        prim("bangs", fringe),
        prim("back", others)
    );
    std::fs::write(&input, text).unwrap();
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("grooms/recipes/bedhead_scene1.toml");
    let run = |group: Option<&str>| {
        let out = dir.path().join("out.usda");
        let mut args =
            vec!["style", path_str(&recipe), "--groom", path_str(&input), "-o", path_str(&out), "--json"];
        args.extend(group.iter().flat_map(|g| ["--group", *g]));
        let styled = coif(&args);
        assert!(styled.status.success(), "{group:?}: {}", stderr(&styled));
        let report: Value = serde_json::from_slice(&styled.stdout).unwrap();
        (report["report"]["head_frame"].clone(), read(&out))
    };
    let (whole_frame, _) = run(None);
    let (fringe_frame, styled) = run(Some("bangs"));
    assert_eq!(fringe_frame, whole_frame, "the fringe alone was placed in another head frame");
    let before = read(&input);
    let back = before.group_strands(1);
    assert!(back.iter().all(|&s| styled.strand_points(s) == before.strand_points(s)), "the back moved");
    let fringe_moved =
        before.group_strands(0).iter().any(|&s| styled.strand_points(s) != before.strand_points(s));
    assert!(fringe_moved, "the fringe was not styled");
}

/// A recipe that resamples strands keeps Bézier curves whole: 3k + 1 points each. The perm's
/// 4 mm segments gave a Bézier groom 32–43 points per strand: a `.usda` output was refused after
/// the whole run, and an `.abc` one was written with curves no reader can split into segments.
#[test]
fn resampled_bezier_strands_stay_whole_bezier_curves() {
    use coif::generate::{generate, GenerateParams};
    let groom =
        generate(&GenerateParams { strands: 10, vertices_per_strand: 7, seed: 3, ..Default::default() })
            .unwrap();
    let points: Vec<String> = groom.points.iter().map(|p| format!("({}, {}, {})", p.x, p.y, p.z)).collect();
    let text = format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef BasisCurves \"hair\"\n{{\n    \
         uniform token type = \"cubic\"\n    uniform token basis = \"bezier\"\n    \
         int[] curveVertexCounts = [{}]\n    point3f[] points = [{}]\n    \
         float[] widths = [0.0001] (interpolation = \"constant\")\n}}\n",
        ["7"; 10].join(", "),
        points.join(", ")
    );
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.usda");
    std::fs::write(&input, text).unwrap();
    let recipe = Path::new(env!("CARGO_MANIFEST_DIR")).join("grooms/recipes/perm_scene3.toml");
    for ext in ["usda", "abc"] {
        let out = dir.path().join(format!("out.{ext}"));
        let styled = coif(&["style", path_str(&recipe), "--groom", path_str(&input), "-o", path_str(&out)]);
        assert!(styled.status.success(), "{ext}: {}", stderr(&styled));
        // pxr reads the curves (converted from .abc by coif, whose USD writer refuses broken ones).
        let usda = dir.path().join(format!("{ext}.usda"));
        let converted = coif(&["convert", path_str(&out), path_str(&usda)]);
        assert!(converted.status.success(), "{ext}: {}", stderr(&converted));
        let dump = pxr_dump(&usda, None);
        let (_, curves) = &curves_by_path(&dump)[0];
        assert_eq!(curves["basis"], "bezier", "{ext}");
        let counts: Vec<u64> =
            curves["counts"].as_array().unwrap().iter().map(|c| c.as_u64().unwrap()).collect();
        assert!(counts.iter().all(|&n| n >= 4 && (n - 1) % 3 == 0), "{ext}: {counts:?}");
        assert!(counts.iter().all(|&n| n > 7), "{ext}: not resampled ({counts:?})");
    }
}

/// A file's own Unreal groups (`groom_group_id` 3, 7, 9 on one prim) are what `--unreal` writes:
/// USD output replaced them with the curve group's index (all 0), and Alembic output wrote two
/// `groom_group_id` properties into one compound (the file's and coif's).
#[test]
fn a_files_own_unreal_group_ids_are_written_once_and_kept() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.usda");
    let points: Vec<String> = (0..6)
        .flat_map(|s| (0..3).map(move |k| format!("({}, {}, 0)", 0.01 * s as f32, -0.01 * k as f32)))
        .collect();
    std::fs::write(
        &input,
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n)\ndef BasisCurves \"hair\"\n{{\n    uniform token type = \"linear\"\n    \
             int[] curveVertexCounts = [3, 3, 3, 3, 3, 3]\n    point3f[] points = [{}]\n    \
             int[] primvars:groom_group_id = [3, 3, 7, 7, 9, 9] (interpolation = \"uniform\")\n}}\n",
            points.join(", ")
        ),
    )
    .unwrap();
    let expected = [3.0, 3.0, 7.0, 7.0, 9.0, 9.0];
    let usda = dir.path().join("u.usda");
    let abc = dir.path().join("u.abc");
    for out in [&usda, &abc] {
        let converted = coif(&["convert", "--unreal", path_str(&input), path_str(out)]);
        assert!(converted.status.success(), "{}", stderr(&converted));
    }
    let dump = pxr_dump(&usda, None);
    let (_, curves) = &curves_by_path(&dump)[0];
    assert_eq!(f32s(&curves["primvars"]["groom_group_id"]["values"]), expected, "{curves}");
    let bytes = std::fs::read(&abc).unwrap();
    let named = bytes.windows(b"groom_group_id".len()).filter(|w| w == b"groom_group_id").count();
    assert_eq!(named, 1, "one groom_group_id property in the Alembic output");
    // Read back as the Epic groom file it is, under Epic's name.
    assert_eq!(read(&abc).attribute("groom_group_id").expect("group ids").floats()[..], expected);
}

/// An Unreal-ready groom whose guides prim and strands prim are one Unreal group
/// (`groom_group_id` 3 on both): the readers took an id that is the same for a whole prim for the
/// prim itself, so `--unreal` renumbered the groups (guides 0, strands 1: Unreal's strands group
/// had no guides) and a plain convert or style dropped the ids. pxr (USD outputs) and ogawa-rs
/// (Alembic outputs) must read 3 on every strand of both, from `.usda` and `.usdc` inputs.
#[test]
fn a_files_group_id_shared_by_its_guides_and_strands_prims_is_kept() {
    let dir = tempfile::tempdir().unwrap();
    let prim = |name: &str, x: &[f32], guide: i32| {
        let points: Vec<String> =
            x.iter().flat_map(|x| (0..4).map(move |k| format!("({x}, {}, 0)", -0.05 * k as f32))).collect();
        let uniform = |v: i32| vec![v.to_string(); x.len()].join(", ");
        format!(
            "    def BasisCurves \"{name}\"\n    {{\n        uniform token type = \"linear\"\n        \
             int[] curveVertexCounts = [{}]\n        point3f[] points = [{}]\n        \
             int[] primvars:groom_group_id = [{}] (interpolation = \"uniform\")\n        \
             int[] primvars:groom_guide = [{}] (interpolation = \"uniform\")\n    }}\n",
            uniform(4),
            points.join(", "),
            uniform(3),
            uniform(guide)
        )
    };
    let usda = dir.path().join("in.usda");
    let stage = format!(
        "#usda 1.0\n(\n    defaultPrim = \"groom\"\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n\
         def Xform \"groom\"\n{{\n{}{}}}\n",
        prim("guides", &[0.0, 0.02], 1),
        prim("hair", &[0.005, 0.01, 0.015], 0)
    );
    std::fs::write(&usda, stage).unwrap();
    let usdc = dir.path().join("in.usdc");
    probe(&["export", path_str(&usda), path_str(&usdc)]);
    let recipe = dir.path().join("brief.toml");
    std::fs::write(&recipe, "[[stages]]\nkind = \"process\"\nduration = 0.01\n").unwrap();
    let expected = [("/groom/guides", 2), ("/groom/hair", 3)];

    for (input, command, unreal, ext) in [
        (&usda, "convert", false, "usda"),
        (&usda, "convert", true, "usda"),
        (&usdc, "convert", false, "usdc"),
        (&usdc, "convert", true, "usdc"),
        (&usda, "convert", false, "abc"),
        (&usdc, "convert", true, "abc"),
        (&usda, "style", false, "usda"),
        (&usda, "style", true, "abc"),
    ] {
        let input_name = input.file_name().unwrap().to_string_lossy().into_owned();
        let label = format!("{command} {input_name}{} → .{ext}", if unreal { " --unreal" } else { "" });
        let out = dir.path().join(format!("{command}_{}_{unreal}.{ext}", input_name.replace('.', "_")));
        let mut args = match command {
            "convert" => vec!["convert", path_str(input), path_str(&out)],
            _ => {
                vec!["style", path_str(&recipe), "--groom", path_str(input), "-o", path_str(&out), "--quiet"]
            }
        };
        if unreal {
            args.push("--unreal");
        }
        let run = coif(&args);
        assert!(run.status.success(), "{label}: {}", stderr(&run));
        let found: Vec<(String, Vec<i32>)> = if ext == "abc" {
            curve_int_param_via_ogawa_rs(&out, "groom_group_id")
                .into_iter()
                .map(|(name, ids)| (name, ids.unwrap_or_default()))
                .collect()
        } else {
            let dump = pxr_dump(&out, None);
            curves_by_path(&dump)
                .into_iter()
                .map(|(path, c)| {
                    let ids =
                        c["primvars"].get("groom_group_id").map(|p| f32s(&p["values"])).unwrap_or_default();
                    (path, ids.iter().map(|&v| v as i32).collect())
                })
                .collect()
        };
        let want: Vec<(String, Vec<i32>)> =
            expected.iter().map(|&(path, n)| (path.to_string(), vec![3; n])).collect();
        assert_eq!(found, want, "{label}");
    }
}

/// `--unreal` Alembic puts Epic's groom version on the topmost Xform, and always added a `groom`
/// Xform for it: every round trip nested the groups one level deeper (`/groom/hair` →
/// `/groom/groom/hair` → …) and `--group /groom/hair` stopped matching. Groups under one top prim
/// keep their paths (the version goes on that prim); groups at the root get the `groom` Xform
/// once. Paths and the version as ogawa-rs reads them, through three round trips.
#[test]
fn unreal_alembic_round_trips_keep_the_group_paths() {
    let dir = tempfile::tempdir().unwrap();
    let curves = |name: &str, x: f32| {
        format!(
            "def BasisCurves \"{name}\" {{\n uniform token type = \"linear\"\n \
             int[] curveVertexCounts = [3, 3]\n point3f[] points = [({x}, 0, 0), ({x}, -0.1, 0), ({x}, -0.2, 0), \
             ({}, 0, 0), ({}, -0.1, 0), ({}, -0.2, 0)]\n}}\n",
            x + 0.01,
            x + 0.01,
            x + 0.01
        )
    };
    let xform =
        |name: &str, children: &[String]| format!("def Xform \"{name}\" {{\n{}}}\n", children.concat());
    let cases = [
        (
            "one top Xform",
            xform("groom", &[curves("guides", 0.0), curves("hair", 0.1)]),
            vec!["/groom/guides", "/groom/hair"],
        ),
        (
            "Blender's layout",
            xform(
                "root",
                &[xform("Hair", &[curves("HairData", 0.0)]), xform("Fuzz", &[curves("FuzzData", 0.1)])],
            ),
            vec!["/root/Fuzz/FuzzData", "/root/Hair/HairData"],
        ),
        ("curves at the root", curves("hair", 0.0), vec!["/groom/hair"]),
    ];
    let recipe = dir.path().join("brief.toml");
    std::fs::write(&recipe, "[[stages]]\nkind = \"process\"\nduration = 0.01\n").unwrap();
    for (case, (label, stage, expected)) in cases.into_iter().enumerate() {
        let mut input = dir.path().join(format!("{case}.usda"));
        std::fs::write(
            &input,
            format!("#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n{stage}"),
        )
        .unwrap();
        for trip in 1..=3 {
            let out = dir.path().join(format!("{case}_{trip}.abc"));
            let run = coif(&["convert", "--unreal", path_str(&input), path_str(&out)]);
            assert!(run.status.success(), "{label}, trip {trip}: {}", stderr(&run));
            let paths: Vec<String> =
                curve_int_param_via_ogawa_rs(&out, "groom_id").into_iter().map(|(path, _)| path).collect();
            assert_eq!(paths, expected, "{label}, trip {trip}");
            let top = expected[0].split('/').nth(1).unwrap();
            assert_eq!(
                top_xform_groom_version_via_ogawa_rs(&out),
                (format!("/{top}"), 1),
                "{label}, trip {trip}"
            );
            input = out;
        }
        // The group is found by the path it was given.
        let first = dir.path().join(format!("{case}_1.abc"));
        let styled = dir.path().join(format!("{case}_styled.abc"));
        let args = ["style", path_str(&recipe), "--groom", path_str(&first), "--group", expected[0]];
        let run = coif(&[&args[..], &["-o", path_str(&styled), "--quiet"]].concat());
        assert!(run.status.success(), "{label}: style --group {}: {}", expected[0], stderr(&run));
    }
}

/// The archive's first top object (its full name) and the `groom_version_major` (int16) on its
/// `.userProperties`, as ogawa-rs reads them.
fn top_xform_groom_version_via_ogawa_rs(path: &Path) -> (String, i16) {
    use ogawa_rs::{Archive, FileReader, PodArray, PropertyReader};
    let mut reader = FileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    let archive = Archive::new(&mut reader).unwrap();
    let root = archive.load_root_object(&mut reader).unwrap();
    let top = root.load_child(0, &mut reader, &archive.indexed_meta_data, &archive.time_samplings).unwrap();
    let properties = top.properties().expect("the top object has properties");
    let Ok(Some(PropertyReader::Compound(user))) =
        properties.load_sub_property_by_name(".userProperties", &mut reader, &archive)
    else {
        panic!("{}: no .userProperties on {}", path.display(), top.header.full_name)
    };
    let Ok(Some(PropertyReader::Scalar(major))) =
        user.load_sub_property_by_name("groom_version_major", &mut reader, &archive)
    else {
        panic!("{}: no groom_version_major on {}", path.display(), top.header.full_name)
    };
    let Ok(PodArray::I16(value)) = major.load_sample(0, &mut reader) else { panic!("not int16") };
    (top.header.full_name.clone(), value[0])
}

/// What one prim has and another lacks is not made up for the other: a prim with root UVs
/// (`st`) and a per-strand `mask` beside a tuft with neither. Written, the tuft's prim held
/// `st = (0, 0)` for every strand (Unreal takes that for real root UVs and skips its own
/// projection), and `--unreal` gave it zero `groom_mask`, `groom_root_uv` too. Checked in pxr,
/// after USD and Alembic round trips.
#[test]
fn a_prims_missing_root_uvs_and_attributes_stay_missing() {
    use coif::generate::{generate, GenerateParams};
    let dir = tempfile::tempdir().unwrap();
    let groom =
        generate(&GenerateParams { strands: 8, vertices_per_strand: 5, seed: 3, ..Default::default() })
            .unwrap();
    let (styled, tuft): (Vec<usize>, Vec<usize>) = ((0..5).collect(), (5..8).collect());
    let uvs: Vec<String> = styled.iter().map(|&s| format!("({}, 0.5)", 0.1 * s as f32)).collect();
    let masks: Vec<String> = styled.iter().map(|&s| (0.25 * s as f32).to_string()).collect();
    let extra = format!(
        "        texCoord2f[] primvars:st = [{}] (interpolation = \"uniform\")\n        \
         float[] primvars:mask = [{}] (interpolation = \"uniform\")\n",
        uvs.join(", "),
        masks.join(", ")
    );
    let text = format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n\ndef Xform \"groom\"\n{{\n{}{}}}\n",
        linear_prim(&groom, "styled", &styled, &extra),
        linear_prim(&groom, "tuft", &tuft, ""),
    );
    let input = dir.path().join("in.usda");
    std::fs::write(&input, text).unwrap();
    let via_abc = dir.path().join("via.abc");
    let via_unreal_abc = dir.path().join("via_unreal.abc");
    for (from, to) in [(&input, &via_abc), (&input, &via_unreal_abc)] {
        let unreal = to == &via_unreal_abc;
        let mut args = vec!["convert", path_str(from), path_str(to)];
        args.extend(unreal.then_some("--unreal"));
        let run = coif(&args);
        assert!(run.status.success(), "{args:?}: {}", stderr(&run));
    }
    let expected_uvs: Vec<f32> = styled.iter().flat_map(|&s| [0.1 * s as f32, 0.5]).collect();
    let expected_masks: Vec<f32> = styled.iter().map(|&s| 0.25 * s as f32).collect();
    for (source, unreal, ext) in [
        (&input, false, "usda"),
        (&input, false, "usdc"),
        (&input, true, "usda"),
        (&via_abc, false, "usda"),
        (&via_unreal_abc, false, "usda"),
    ] {
        let out = dir.path().join(format!("out_{unreal}.{ext}"));
        let mut args = vec!["convert", path_str(source), path_str(&out)];
        args.extend(unreal.then_some("--unreal"));
        let run = coif(&args);
        assert!(run.status.success(), "{args:?}: {}", stderr(&run));
        let written = pxr_dump(&out, None);
        let curves = curves_by_path(&written);
        let prim = |name: &str| &curves.iter().find(|(path, _)| path.ends_with(name)).expect(name).1;
        let label = format!("{args:?}");
        // Unreal's names where --unreal wrote them (the Alembic one is read back by coif, whose
        // reader gives `groom_root_uv` back as root UVs).
        let (uv_name, mask_name) = if unreal { ("groom_root_uv", "groom_mask") } else { ("st", "mask") };
        let styled_prim = prim("styled");
        assert_eq!(f32s(&styled_prim["primvars"][uv_name]["values"]), expected_uvs, "{label}");
        assert_eq!(f32s(&styled_prim["primvars"][mask_name]["values"]), expected_masks, "{label}");
        let tuft_primvars: Vec<&String> =
            prim("tuft")["primvars"].as_object().expect("primvars").keys().collect();
        for name in ["st", "groom_root_uv", "mask", "groom_mask"] {
            assert!(
                !tuft_primvars.iter().any(|n| *n == name),
                "{label}: the tuft got {name}: {tuft_primvars:?}"
            );
        }
    }
}

/// `.hair` holds polylines: every curved basis of a groom of several prims is warned about, not
/// only the first prim's (the B-spline fuzz after linear hair went unmentioned).
#[test]
fn hair_output_warns_about_every_curved_basis() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.hair");
    let run = coif(&["convert", path_str(&houdini_groom()), path_str(&out)]);
    assert!(run.status.success(), "{}", stderr(&run));
    let bases: Vec<CurveBasis> =
        read(&houdini_groom()).groups.iter().map(|g| g.basis).filter(|&b| b != CurveBasis::Linear).collect();
    assert_eq!(bases, [CurveBasis::CatmullRom, CurveBasis::BSpline], "the fixture's curved prims");
    for basis in bases {
        let warning = format!("drops the {basis:?} basis (points are written as polylines)");
        assert!(stderr(&run).contains(&warning), "no {warning:?} in: {}", stderr(&run));
    }
}

/// The PNG bytes of `coif render` of a stage written from `text` as `NAME.usda` in `dir`.
fn render_stage(dir: &Path, text: &str, name: &str) -> Vec<u8> {
    let (usda, png) = (dir.join(format!("{name}.usda")), dir.join(format!("{name}.png")));
    std::fs::write(&usda, text).unwrap();
    let out = coif(&["render", path_str(&usda), "-o", path_str(&png), "--res", "40x30", "--spp", "4"]);
    assert!(out.status.success(), "{}", stderr(&out));
    std::fs::read(&png).unwrap()
}

/// Guides in a prim of `purpose = "guide"` (as Houdini writes them) are not drawn by a preview,
/// as Hydra and render delegates do not draw them; a file of guides alone still shows them.
/// Previews drew every curves prim whatever its purpose.
#[test]
fn previews_leave_out_guide_prims_as_renderers_do() {
    let dir = tempfile::tempdir().unwrap();
    let header =
        "#usda 1.0\n(\n    defaultPrim = \"groom\"\n    metersPerUnit = 0.01\n    upAxis = \"Y\"\n)\n";
    let stage = |guide_purpose: &str, hair: bool| {
        let hair = if hair {
            format!("def BasisCurves \"hair\"\n{{\n{}}}\n", two_curves(0.0))
        } else {
            String::new()
        };
        format!(
            "{header}def Xform \"groom\"\n{{\n{hair}\
             def BasisCurves \"guides\"\n{{\n uniform token purpose = \"{guide_purpose}\"\n{}}}\n}}\n",
            two_curves(3.0)
        )
    };
    let render = |text: &str, name: &str| render_stage(dir.path(), text, name);
    let hair_alone =
        format!("{header}def Xform \"groom\"\n{{\ndef BasisCurves \"hair\"\n{{\n{}}}\n}}\n", two_curves(0.0));
    let with_guides = render(&stage("guide", true), "with_guides");
    assert!(with_guides == render(&hair_alone, "hair_alone"), "guide-purpose curves were drawn");
    assert!(
        with_guides != render(&stage("default", true), "guides_as_hair"),
        "default-purpose curves are drawn"
    );
    // Guides alone: drawn rather than an empty image or an error.
    let guides_alone = render(&stage("guide", false), "guides_alone");
    assert!(guides_alone == render(&stage("default", false), "guides_alone_default"));
}

/// Two linear curves of three points at `x` (centimetres), as a prim body.
fn two_curves(x: f32) -> String {
    let points: Vec<String> = [0.0, 1.0]
        .iter()
        .flat_map(|dz| (0..3).map(move |k| format!("({x}, {}, {dz})", 4.0 * k as f32)))
        .collect();
    format!(
        "uniform token type = \"linear\"\n int[] curveVertexCounts = [3, 3]\n point3f[] points = [{}]\n",
        points.join(", ")
    )
}

/// Purpose and visibility as pxr computes them: inherited from imageable ancestors (a prim's own
/// purpose wins, an invisible ancestor hides every descendant, a typeless prim neither sets nor
/// stops either). coif read only a curves prim's own purpose and no visibility, so guides grouped
/// under an Xform of purpose "guide" became render hair and hidden prims came out visible.
#[test]
fn inherited_purpose_and_visibility_are_read_used_and_written_back() {
    let dir = tempfile::tempdir().unwrap();
    let stage = format!(
        "#usda 1.0\n(\n    defaultPrim = \"groom\"\n    metersPerUnit = 0.01\n    upAxis = \"Y\"\n)\n\
         def Xform \"groom\"\n{{\n\
         def \"typeless\"\n{{\n uniform token purpose = \"guide\"\n token visibility = \"invisible\"\n\
         def BasisCurves \"hair\"\n{{\n{}}}\n}}\n\
         def BasisCurves \"plain\"\n{{\n{}}}\n\
         def Xform \"guides\"\n{{\n uniform token purpose = \"guide\"\n token visibility = \"invisible\"\n\
         def BasisCurves \"long\"\n{{\n{}}}\n\
         def BasisCurves \"own\"\n{{\n uniform token purpose = \"render\"\n{}}}\n}}\n\
         def Scope \"hidden\"\n{{\n token visibility = \"invisible\"\n def \"deep\"\n{{\n\
         def BasisCurves \"fuzz\"\n{{\n{}}}\n}}\n}}\n}}\n",
        two_curves(0.0),
        two_curves(2.0),
        two_curves(4.0),
        two_curves(6.0),
        two_curves(8.0)
    );
    let source = dir.path().join("source.usda");
    std::fs::write(&source, &stage).unwrap();
    let computed = |path: &Path| -> Vec<(String, Value, Value)> {
        let dump = pxr_dump(path, None);
        let curves = curves_by_path(&dump);
        curves
            .into_iter()
            .map(|(p, c)| (p, c["computedPurpose"].clone(), c["computedVisibility"].clone()))
            .collect()
    };
    let expected = computed(&source);
    let invisible: Vec<&str> =
        expected.iter().filter(|(_, _, v)| v == "invisible").map(|(p, _, _)| p.as_str()).collect();
    assert_eq!(invisible, ["/groom/guides/long", "/groom/guides/own", "/groom/hidden/deep/fuzz"], "pxr");

    // coif's reading: the inherited guide purpose flags the guides, and the groups know.
    let groom = read(&source);
    assert_eq!(groom.guides.clone().unwrap(), [vec![false; 4], vec![true; 2], vec![false; 4]].concat());
    let read_invisible: Vec<String> = (0..groom.group_count())
        .filter(|&g| groom.group(g).invisible)
        .map(|g| groom.group(g).name.clone())
        .collect();
    assert_eq!(read_invisible, invisible);

    for name in ["out.usda", "out.usdc"] {
        let out = dir.path().join(name);
        let converted = coif(&["convert", path_str(&source), path_str(&out)]);
        assert!(converted.status.success(), "{}", stderr(&converted));
        assert_eq!(computed(&out), expected, "{name}: purpose and visibility as pxr computes them");
    }
    // Alembic keeps visibility (AbcGeom's `visible`) and the guides (`groom_guide`).
    let abc = dir.path().join("out.abc");
    let back = dir.path().join("back.usda");
    for (from, to) in [(&source, &abc), (&abc, &back)] {
        let converted = coif(&["convert", path_str(from), path_str(to)]);
        assert!(converted.status.success(), "{}", stderr(&converted));
    }
    let visibility = |rows: Vec<(String, Value, Value)>| -> Vec<(String, Value)> {
        rows.into_iter().map(|(p, _, v)| (p, v)).collect()
    };
    assert_eq!(visibility(computed(&back)), visibility(expected.clone()), "through .abc");
    assert_eq!(read(&abc).guides, groom.guides, "through .abc");
    // .hair has no visibility: the hidden prims are named, not silently shown.
    let hair = dir.path().join("out.hair");
    let converted = coif(&["convert", path_str(&source), path_str(&hair)]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    let warning = format!("the invisibility of {}", invisible.join(", "));
    assert!(stderr(&converted).contains(&warning), "no {warning:?} in: {}", stderr(&converted));

    // A preview draws what a renderer would: the same image as the stage without hidden prims
    // (listed last, so the visible strands keep their indices), another one with them shown.
    let render = |text: &str, name: &str| render_stage(dir.path(), text, name);
    let cut = stage.find("def Xform \"guides\"").unwrap();
    let without_hidden = format!("{}}}\n", &stage[..cut]);
    let with_hidden = render(&stage, "with_hidden");
    assert!(with_hidden == render(&without_hidden, "without_hidden"), "hidden prims were drawn");
    assert!(with_hidden != render(&stage.replace("\"invisible\"", "\"inherited\""), "all_shown"));
}

/// A per-vertex `primvars:st` (Houdini's `uv` along each curve, which its USD export names
/// `st`) is an attribute like any other: it was dropped on writing ("clashes with primvar 'st'")
/// because `st` is where root UVs go, although this groom has none.
#[test]
fn a_per_vertex_st_is_kept_where_there_are_no_root_uvs() {
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("uv_along.usda");
    std::fs::write(
        &source,
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef BasisCurves \"c\"\n{\n\
         uniform token type = \"linear\"\n int[] curveVertexCounts = [2, 3]\n\
         point3f[] points = [(0,0,0), (0,0.1,0), (0.1,0,0), (0.1,0.1,0), (0.1,0.2,0)]\n\
         texCoord2f[] primvars:st = [(0.1,0.2), (0.3,0.4), (0.5,0.6), (0.7,0.8), (0.9,1)] (\n\
         interpolation = \"vertex\"\n )\n}\n",
    )
    .unwrap();
    let st = |path: &Path| pxr_dump(path, None)["curves"][0]["primvars"]["st"].clone();
    let expected = st(&source);
    assert_eq!(expected["interpolation"], "vertex");
    for name in ["out.usda", "out.usdc"] {
        let out = dir.path().join(name);
        let converted = coif(&["convert", path_str(&source), path_str(&out)]);
        assert!(converted.status.success(), "{}", stderr(&converted));
        assert!(!stderr(&converted).contains("clashes"), "{name}: {}", stderr(&converted));
        let written = st(&out);
        for key in ["type", "interpolation"] {
            assert_eq!(written[key], expected[key], "{name}: {key}");
        }
        assert_eq!(f32s(&written["values"]), f32s(&expected["values"]), "{name}");
        assert!(read(&out).root_uvs.is_none(), "{name}: per-vertex st is no root UV");
    }
}

/// Scalar arrays with an `elementSize` (how Houdini writes array attributes, such as three guide
/// ids per curve) are written back as they came: `int[] (elementSize = 3)` became `float3[]`.
#[test]
fn element_sized_primvars_keep_their_type_and_element_size() {
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("arrays.usda");
    std::fs::write(
        &source,
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef BasisCurves \"c\"\n{\n\
         uniform token type = \"linear\"\n int[] curveVertexCounts = [2, 3]\n\
         point3f[] points = [(0,0,0), (0,0.1,0), (0.1,0,0), (0.1,0.1,0), (0.1,0.2,0)]\n\
         int[] primvars:guide_ids = [1, 2, 3, 4, 5, 6] (\n interpolation = \"uniform\"\n elementSize = 3\n )\n\
         float[] primvars:guide_weights = [0.5, 0.25, 0.25, 1, 0, 0] (\n interpolation = \"uniform\"\n elementSize = 3\n )\n\
         float[] primvars:along = [0, 1, 2, 3, 4, 5, 6, 7, 8, 9] (\n interpolation = \"vertex\"\n elementSize = 2\n )\n\
         float3[] primvars:tuple = [(1, 2, 3), (4, 5, 6)] (\n interpolation = \"uniform\"\n )\n}\n",
    )
    .unwrap();
    let primvars = |path: &Path| pxr_dump(path, None)["curves"][0]["primvars"].clone();
    let expected = primvars(&source);
    assert_eq!(expected["guide_ids"]["elementSize"], 3, "{expected}");
    for name in ["out.usda", "out.usdc"] {
        let out = dir.path().join(name);
        let converted = coif(&["convert", path_str(&source), path_str(&out)]);
        assert!(converted.status.success(), "{}", stderr(&converted));
        let written = primvars(&out);
        for primvar in ["guide_ids", "guide_weights", "along", "tuple"] {
            for key in ["type", "interpolation", "elementSize"] {
                assert_eq!(written[primvar][key], expected[primvar][key], "{name}: {primvar} {key}");
            }
            assert_eq!(
                f32s(&written[primvar]["values"]),
                f32s(&expected[primvar]["values"]),
                "{name}: {primvar}"
            );
        }
    }
}

/// Converts `source` (a `.usda`) to `.usda`, `.usdc` and `.abc`, and that `.abc` back to `.usda`,
/// each file named after the source; returns the three USD outputs, for pxr to read.
fn usd_outputs_through_every_format(source: &Path) -> Vec<PathBuf> {
    let stem = source.file_stem().unwrap().to_str().unwrap();
    let file = |suffix: &str| source.with_file_name(format!("{stem}{suffix}"));
    let (abc, outputs) = (file(".abc"), vec![file("_out.usda"), file("_out.usdc"), file("_back.usda")]);
    for (from, to) in [(source, &outputs[0]), (source, &outputs[1]), (source, &abc), (&abc, &outputs[2])] {
        let converted = coif(&["convert", path_str(from), path_str(to)]);
        assert!(converted.status.success(), "{}", stderr(&converted));
    }
    outputs
}

/// A scalp mesh hidden in its file (as grooms often bring theirs) stays hidden: it came out
/// visible in every output, and previews drew it.
#[test]
fn a_hidden_scalp_mesh_stays_hidden_and_is_not_drawn() {
    let dir = tempfile::tempdir().unwrap();
    let mesh =
        "def Mesh \"scalp\"\n{\n int[] faceVertexCounts = [4]\n int[] faceVertexIndices = [0, 1, 2, 3]\n\
                point3f[] points = [(-10, -1, -5), (10, -1, -5), (10, 9, -5), (-10, 9, -5)]\n}\n";
    let stage = |body: &str| {
        format!(
            "#usda 1.0\n(\n    defaultPrim = \"groom\"\n    metersPerUnit = 0.01\n    upAxis = \"Y\"\n)\n\
             def Xform \"groom\"\n{{\n def BasisCurves \"hair\"\n{{\n{}}}\n{body}}}\n",
            two_curves(0.0)
        )
    };
    let hidden = format!("def Xform \"hidden\"\n{{\n token visibility = \"invisible\"\n{mesh}}}\n");
    let source = dir.path().join("source.usda");
    std::fs::write(&source, stage(&hidden)).unwrap();
    let visibility = |path: &Path| pxr_dump(path, None)["meshes"][0]["computedVisibility"].clone();
    assert_eq!(visibility(&source), "invisible", "pxr");
    assert!(read(&source).meshes[0].invisible);
    for to in usd_outputs_through_every_format(&source) {
        assert_eq!(visibility(&to), "invisible", "{}", to.display());
    }
    let render = |text: &str, name: &str| render_stage(dir.path(), text, name);
    let with_hidden = render(&stage(&hidden), "hidden");
    assert!(with_hidden == render(&stage(""), "none"), "the hidden mesh was drawn");
    assert!(with_hidden != render(&stage(mesh), "shown"), "a shown mesh is drawn");
}

/// A file's int pairs, triples and quadruples keep their type (they became `float2[]`…`float4[]`),
/// through `.usda`, `.usdc` and Alembic (int32×N); `--unreal` writes them as floats, the types
/// Unreal's USD importer reads.
#[test]
fn int_tuple_primvars_stay_int_tuples() {
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("ints.usda");
    std::fs::write(
        &source,
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef BasisCurves \"c\"\n{\n\
         uniform token type = \"linear\"\n int[] curveVertexCounts = [2, 3]\n\
         point3f[] points = [(0,0,0), (0,0.1,0), (0.1,0,0), (0.1,0.1,0), (0.1,0.2,0)]\n\
         int2[] primvars:pair = [(1, 2), (3, 4)] (\n interpolation = \"uniform\"\n )\n\
         int3[] primvars:cell = [(1, 2, 3), (4, 5, 6), (7, 8, 9), (10, 11, 12), (13, 14, 15)] (\n interpolation = \"vertex\"\n )\n\
         int4[] primvars:quad = [(1, 2, 3, 4), (5, 6, 7, 8)] (\n interpolation = \"uniform\"\n )\n}\n",
    )
    .unwrap();
    let primvars = |path: &Path| pxr_dump(path, None)["curves"][0]["primvars"].clone();
    let expected = primvars(&source);
    for to in usd_outputs_through_every_format(&source) {
        let written = primvars(&to);
        for primvar in ["pair", "cell", "quad"] {
            for key in ["type", "interpolation"] {
                assert_eq!(
                    written[primvar][key],
                    expected[primvar][key],
                    "{}: {primvar} {key}",
                    to.display()
                );
            }
            assert_eq!(f32s(&written[primvar]["values"]), f32s(&expected[primvar]["values"]), "{primvar}");
        }
    }
    let unreal = dir.path().join("unreal.usda");
    let converted = coif(&["convert", "--unreal", path_str(&source), path_str(&unreal)]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    assert_eq!(primvars(&unreal)["groom_cell"]["type"], "float3[]");
}

/// Linear curves with their own `normals`, `velocities` and `accelerations` (not primvars: where
/// Houdini's USD export puts `N`, `v` and `accel`): two horizontal strands of five points along
/// x, whose normals point up, across the strands.
fn stage_with_point_attributes() -> String {
    let points: Vec<String> =
        (0..10).map(|k| format!("({}, 0, {})", 0.02 * (k % 5) as f32, 0.01 * (k / 5) as f32)).collect();
    let list = |each: &dyn Fn(f32) -> String| (0..10).map(|i| each(i as f32)).collect::<Vec<_>>().join(", ");
    let normals = list(&|_| "(0, 1, 0)".to_string());
    let velocities = list(&|i| format!("(0.1, {}, 0)", -0.01 * i));
    let accelerations = list(&|i| format!("(0, -9.8, {})", 0.5 * i));
    format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef BasisCurves \"hair\"\n{{\n\
         uniform token type = \"linear\"\n int[] curveVertexCounts = [5, 5]\n\
         point3f[] points = [{}]\n float[] widths = [0.0001] (\n interpolation = \"constant\"\n )\n\
         normal3f[] normals = [{normals}] (\n interpolation = \"vertex\"\n )\n\
         vector3f[] velocities = [{velocities}]\n vector3f[] accelerations = [{accelerations}]\n}}\n",
        points.join(", ")
    )
}

/// [`stage_with_point_attributes`] and a recipe that lets its strands fall for 0.3 s, written in
/// `dir`: (stage, recipe).
fn falling_strands_with_point_attributes(dir: &Path) -> (PathBuf, PathBuf) {
    let source = dir.join("moving.usda");
    std::fs::write(&source, stage_with_point_attributes()).unwrap();
    let recipe = dir.join("fall.toml");
    std::fs::write(&recipe, "[[stages]]\nkind = \"process\"\nduration = 0.3\n").unwrap();
    (source, recipe)
}

/// The curves' own normals, velocities and accelerations were dropped by every conversion with
/// no warning. They now round-trip through `.usda`, `.usdc` and `.abc` (Alembic `N` and
/// `.velocities`, accelerations as a parameter) as pxr reads them: values, type, interpolation.
#[test]
fn curves_normals_velocities_and_accelerations_survive_conversion() {
    let dir = tempfile::tempdir().unwrap();
    // Per-vertex normals with motion, and a normal per curve (`uniform`) alone.
    let per_curve =
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef BasisCurves \"guides\"\n{\n\
         uniform token type = \"linear\"\n int[] curveVertexCounts = [2, 2]\n\
         point3f[] points = [(0, 0, 0.1), (0.05, 0, 0.1), (0, 0, 0.2), (0.05, 0, 0.2)]\n\
         normal3f[] normals = [(0, 0.6, 0.8), (0, 1, 0)] (\n interpolation = \"uniform\"\n )\n}\n";
    for (name, text) in [("moving", stage_with_point_attributes()), ("per_curve", per_curve.to_string())] {
        let source = dir.path().join(format!("{name}.usda"));
        std::fs::write(&source, text).unwrap();
        let expected = pxr_dump(&source, None);
        assert!(expected["curves"][0]["normals"].is_object(), "the probe reads the source's normals");
        for to in usd_outputs_through_every_format(&source) {
            let written = pxr_dump(&to, None);
            let pairs = curves_by_path(&expected).into_iter().zip(curves_by_path(&written));
            for ((path, source), (written_path, written)) in pairs {
                let label = format!("{} {path}", to.display());
                assert_eq!(path, written_path, "{label}");
                for key in ["velocities", "accelerations"] {
                    assert_eq!(written[key].is_null(), source[key].is_null(), "{label}: {key}");
                    if !source[key].is_null() {
                        assert_eq!(f32s(&written[key]), f32s(&source[key]), "{label}: {key}");
                    }
                }
                assert_eq!(written["normals"]["type"], "normal3f[]", "{label}");
                assert_eq!(
                    written["normals"]["interpolation"], source["normals"]["interpolation"],
                    "{label}"
                );
                assert_eq!(
                    f32s(&written["normals"]["values"]),
                    f32s(&source["normals"]["values"]),
                    "{label}"
                );
                assert!(written["primvars"].get("normals").is_none(), "{label}: normals also as a primvar");
            }
        }
    }
    // An empty array is none (pxr reads no velocities from it); a count that fits no point is
    // bad input naming the prim and the attribute, as for primvars.
    let one_curve = |extra: &str| {
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef BasisCurves \"c\"\n{{\n\
             uniform token type = \"linear\"\n int[] curveVertexCounts = [2]\n\
             point3f[] points = [(0, 0, 0), (0.1, 0, 0)]\n {extra}\n}}\n"
        )
    };
    let (source, out) = (dir.path().join("odd.usda"), dir.path().join("odd_out.usda"));
    std::fs::write(&source, one_curve("vector3f[] velocities = []")).unwrap();
    let converted = coif(&["convert", path_str(&source), path_str(&out)]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    assert!(pxr_dump(&out, None)["curves"][0]["velocities"].is_null());
    std::fs::write(&source, one_curve("vector3f[] velocities = [(1, 2, 3)]")).unwrap();
    let converted = coif(&["convert", path_str(&source), path_str(&out)]);
    assert_eq!(converted.status.code(), Some(2), "{}", stderr(&converted));
    assert!(
        stderr(&converted).contains("prim </c>: velocities: vertex interpolation needs 2 values, found 1"),
        "{}",
        stderr(&converted)
    );
}

/// Tangent at each vertex of a dump's curves (central differences, one-sided at the ends).
fn tangents(curves: &Value) -> Vec<glam::Vec3> {
    let points: Vec<glam::Vec3> = f32s(&curves["points"]).chunks(3).map(glam::Vec3::from_slice).collect();
    let mut out = Vec::new();
    let mut start = 0;
    for count in curves["counts"].as_array().unwrap().iter().map(|c| c.as_u64().unwrap() as usize) {
        for i in 0..count {
            let (a, b) = (start + i.saturating_sub(1), start + (i + 1).min(count - 1));
            out.push((points[b] - points[a]).normalize());
        }
        start += count;
    }
    out
}

/// Styling bends the strands: their normals turn with them (still across the curve, the same
/// length), and the file's velocities and accelerations, the motion of the hair before styling,
/// are left out with a warning. Control: the file's normals are no longer across the styled
/// strands. `coif simulate` writes the simulation's own velocities in their place.
#[test]
fn moved_strands_carry_their_normals_and_drop_or_renew_their_motion() {
    let dir = tempfile::tempdir().unwrap();
    let (source, recipe) = falling_strands_with_point_attributes(dir.path());
    let styled = dir.path().join("styled.usda");
    let run =
        coif(&["style", path_str(&recipe), "--groom", path_str(&source), "-o", path_str(&styled), "--quiet"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let warnings = stderr(&run);
    assert!(
        warnings.contains("'velocities' are left out") && warnings.contains("'accelerations' are left out"),
        "{warnings}"
    );
    let before = pxr_dump(&source, None);
    let after = pxr_dump(&styled, None);
    let hair =
        |dump: &Value| curves_by_path(dump).into_iter().find(|(p, _)| p.ends_with("hair")).unwrap().1.clone();
    let (before, after) = (hair(&before), hair(&after));
    assert!(after["velocities"].is_null() && after["accelerations"].is_null());
    let normals = |c: &Value| -> Vec<glam::Vec3> {
        f32s(&c["normals"]["values"]).chunks(3).map(glam::Vec3::from_slice).collect()
    };
    let (old, new, styled_tangents) = (normals(&before), normals(&after), tangents(&after));
    let across =
        |n: &[glam::Vec3]| n.iter().zip(&styled_tangents).map(|(n, t)| n.dot(*t).abs()).fold(0.0, f32::max);
    eprintln!(
        "largest |n·t| on the styled strands: carried {:.2e}, the file's {:.3}",
        across(&new),
        across(&old)
    );
    assert!(
        across(&old) > 0.1,
        "the strands should bend enough for the file's normals to stop being across them"
    );
    assert!(across(&new) < 1e-3, "carried normals are not across the styled strands");
    for (a, b) in old.iter().zip(&new) {
        assert!((a.length() - b.length()).abs() < 1e-5, "a normal changed length: {a} → {b}");
    }

    // A simulation's output carries its own velocities: close to the motion over the next step.
    let simulated = |seconds: &str, name: &str| {
        let out = dir.path().join(name);
        let run =
            coif(&["simulate", path_str(&source), path_str(&out), "--seconds", seconds, "--dt", "1/360"]);
        assert!(run.status.success(), "{}", stderr(&run));
        hair(&pxr_dump(&out, None))
    };
    let (now, next) = (simulated("0.1", "a.usda"), simulated(&(0.1 + 1.0 / 360.0).to_string(), "b.usda"));
    assert!(now["accelerations"].is_null());
    let points =
        |c: &Value| -> Vec<glam::Vec3> { f32s(&c["points"]).chunks(3).map(glam::Vec3::from_slice).collect() };
    let velocities: Vec<glam::Vec3> =
        f32s(&now["velocities"]).chunks(3).map(glam::Vec3::from_slice).collect();
    let tip = 4;
    let stepped = (points(&next)[tip] - points(&now)[tip]) * 360.0;
    eprintln!("tip velocity written {}, over the next step {stepped}", velocities[tip]);
    assert!(stepped.length() > 0.01, "the strand falls");
    assert!(velocities[tip].distance(stepped) < 0.1 * stepped.length(), "{} vs {stepped}", velocities[tip]);
}

/// `coif style --frames` writes every frame's points: the normals follow each frame's shape
/// (time-sampled, across the strands at every frame), not only the final one's. They were
/// written once, for the final shape, under points that moved.
#[test]
fn normals_follow_the_strands_in_every_styled_frame() {
    let dir = tempfile::tempdir().unwrap();
    let (source, recipe) = falling_strands_with_point_attributes(dir.path());
    let styled = dir.path().join("frames.usda");
    let run = coif(&[
        "style",
        path_str(&recipe),
        "--groom",
        path_str(&source),
        "-o",
        path_str(&styled),
        "--frames",
        "30",
        "--quiet",
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let end = pxr_dump(&styled, Some(1.0))["endTimeCode"].as_f64().unwrap();
    assert!(end >= 8.0, "frames written: {end}");
    let mut seen = Vec::new();
    for time in [1.0, (end / 2.0).round(), end] {
        let dump = pxr_dump(&styled, Some(time));
        let hair = curves_by_path(&dump).into_iter().find(|(p, _)| p.ends_with("hair")).unwrap().1.clone();
        let normals: Vec<glam::Vec3> =
            f32s(&hair["normals"]["values"]).chunks(3).map(glam::Vec3::from_slice).collect();
        let across = normals.iter().zip(tangents(&hair)).map(|(n, t)| n.dot(t).abs()).fold(0.0, f32::max);
        eprintln!("time {time}: largest |n·t| {across:.2e}");
        assert!(across < 1e-3, "time {time}: normals are not across the strands ({across})");
        assert!(normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5), "time {time}");
        seen.push(normals);
    }
    assert!(seen[0] != seen[2], "the normals should turn as the strands fall");
}

/// A mesh's `holeIndices` (faces USD does not draw) were dropped, so a scalp with holes came out
/// whole and previews drew the holes. They are now written back (pxr reads the same faces as
/// holes through `.usda` and `.usdc`; `.abc`, whose PolyMesh has none, warns) and previews leave
/// them out: a render equals the stage without those faces, and differs from it without holes.
#[test]
fn mesh_holes_are_kept_and_not_drawn() {
    let dir = tempfile::tempdir().unwrap();
    // Two quads side by side behind the hair; the second is a hole.
    let mesh = |faces: &str, indices: &str, holes: &str| {
        format!(
            "def Mesh \"scalp\"\n{{\n int[] faceVertexCounts = [{faces}]\n int[] faceVertexIndices = [{indices}]\n\
             point3f[] points = [(-10, -1, -5), (0, -1, -5), (0, 9, -5), (-10, 9, -5), (10, -1, -5), (10, 9, -5)]\n{holes}}}\n"
        )
    };
    let stage = |body: &str| {
        format!(
            "#usda 1.0\n(\n    defaultPrim = \"groom\"\n    metersPerUnit = 0.01\n    upAxis = \"Y\"\n)\n\
             def Xform \"groom\"\n{{\n def BasisCurves \"hair\"\n{{\n{}}}\n{body}}}\n",
            two_curves(0.0)
        )
    };
    let holed = stage(&mesh("4, 4", "0, 1, 2, 3, 1, 4, 5, 2", " int[] holeIndices = [1]\n"));
    let source = dir.path().join("source.usda");
    std::fs::write(&source, &holed).unwrap();
    let holes = |path: &Path| pxr_dump(path, None)["meshes"][0]["holeIndices"].clone();
    assert_eq!(holes(&source), serde_json::json!([1]), "pxr reads the source's hole");
    for name in ["out.usda", "out.usdc"] {
        let to = dir.path().join(name);
        let converted = coif(&["convert", path_str(&source), path_str(&to)]);
        assert!(converted.status.success(), "{}", stderr(&converted));
        assert_eq!(holes(&to), serde_json::json!([1]), "{name}");
    }
    let abc = dir.path().join("out.abc");
    let converted = coif(&["convert", path_str(&source), path_str(&abc)]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    assert!(stderr(&converted).contains("1 hole faces are written as faces"), "{}", stderr(&converted));

    let render = |text: &str, name: &str| render_stage(dir.path(), text, name);
    let with_hole = render(&holed, "holed");
    assert!(with_hole == render(&stage(&mesh("4", "0, 1, 2, 3", "")), "cut"), "the hole was drawn");
    assert!(
        with_hole != render(&stage(&mesh("4, 4", "0, 1, 2, 3, 1, 4, 5, 2", "")), "whole"),
        "a face is drawn"
    );
}

/// An attribute one prim gives per curve (or once) and another per vertex is kept per vertex in
/// the merged groom; it was written back per vertex on every prim. Each prim now gets its own
/// interpolation back while its values allow it (pxr: type, interpolation, flattened values),
/// through `.usda` and `.usdc`.
#[test]
fn per_curve_and_constant_primvars_merged_with_per_vertex_ones_keep_their_interpolation() {
    let dir = tempfile::tempdir().unwrap();
    let prim = |name: &str, z: f32, primvar: &str| {
        format!(
            "def BasisCurves \"{name}\"\n{{\n uniform token type = \"linear\"\n int[] curveVertexCounts = [2, 3]\n\
             point3f[] points = [(0, 0, {z}), (0.1, 0, {z}), (0, 0.1, {z}), (0.1, 0.1, {z}), (0.2, 0.1, {z})]\n{primvar}}}\n"
        )
    };
    let text = format!(
        "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n{}{}{}",
        prim("vertex", 0.0, " float3[] primvars:foo = [(1,2,3), (4,5,6), (7,8,9), (1,1,1), (2,2,2)] (\n interpolation = \"vertex\"\n )\n"),
        prim("uniform", 0.1, " float3[] primvars:foo = [(7,8,9), (3,2,1)] (\n interpolation = \"uniform\"\n )\n"),
        prim("constant", 0.2, " float3[] primvars:foo = [(5,5,5)] (\n interpolation = \"constant\"\n )\n"),
    );
    let source = dir.path().join("mixed.usda");
    std::fs::write(&source, text).unwrap();
    let foo = |path: &Path| -> Vec<(String, Value)> {
        curves_by_path(&pxr_dump(path, None))
            .into_iter()
            .map(|(p, c)| (p, c["primvars"]["foo"].clone()))
            .collect()
    };
    let expected = foo(&source);
    for name in ["out.usda", "out.usdc"] {
        let to = dir.path().join(name);
        let converted = coif(&["convert", path_str(&source), path_str(&to)]);
        assert!(converted.status.success(), "{}", stderr(&converted));
        for ((path, source), (_, written)) in expected.iter().zip(foo(&to)) {
            for key in ["type", "interpolation"] {
                assert_eq!(written[key], source[key], "{name} {path}: {key}");
            }
            assert_eq!(f32s(&written["values"]), f32s(&source["values"]), "{name} {path}");
        }
    }
}

/// Velocities follow the points' units: `--unreal` Alembic (centimetres) held them in metres per
/// second beside points in centimetres, and a file read with `--units` kept them unscaled. In
/// the file they are now 100× the stage's, as the points are, and read back as the stage's.
#[test]
fn velocities_follow_the_points_units() {
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("moving.usda");
    std::fs::write(&source, stage_with_point_attributes()).unwrap();
    let (unreal, raw, back) =
        (dir.path().join("unreal.abc"), dir.path().join("raw.usda"), dir.path().join("back.usda"));
    for args in [
        vec!["convert", "--unreal", path_str(&source), path_str(&unreal)],
        vec!["convert", "--units", "1", path_str(&unreal), path_str(&raw)],
        vec!["convert", path_str(&unreal), path_str(&back)],
    ] {
        let converted = coif(&args);
        assert!(converted.status.success(), "{args:?}: {}", stderr(&converted));
    }
    let hair = |path: &Path| pxr_dump(path, None)["curves"][0].clone();
    let (source, raw, back) = (hair(&source), hair(&raw), hair(&back));
    for key in ["points", "velocities", "accelerations"] {
        let (s, r, b) = (f32s(&source[key]), f32s(&raw[key]), f32s(&back[key]));
        for ((s, r), b) in s.iter().zip(&r).zip(&b) {
            assert!((r - 100.0 * s).abs() <= 1e-4 * (1.0 + r.abs()), "{key}: {r} in the file for {s}");
            assert!((b - s).abs() <= 1e-6 * (1.0 + s.abs()), "{key}: {b} read back for {s}");
        }
    }
}

/// A `--unreal` USD stage reads back as the same groom as the `--unreal` Alembic file and the
/// groom written: Epic's `groom_` names (`groom_rest`, `groom_bond_*`, `groom_color`,
/// `groom_root_uv`) are coif's attributes again, in both formats, and the `groom_group_id` written
/// reads back as the file's own (group 0 for this groom of one group). Read from the USD under
/// their prefixed names, a styled groom lost its rest shape and fell when simulated again.
#[test]
fn unreal_usd_output_reads_back_as_the_groom_written_as_unreal_alembic_does() {
    let dir = tempfile::tempdir().unwrap();
    let groom = rich_groom(CurveBasis::Linear);
    let plain = dir.path().join("plain.usda");
    coif::io::write_groom(&plain, &groom).unwrap();
    let plain = read(&plain);
    for ext in ["usda", "usdc", "abc"] {
        let out = dir.path().join(format!("unreal.{ext}"));
        let run = coif(&["convert", "--unreal", path_str(&dir.path().join("plain.usda")), path_str(&out)]);
        assert!(run.status.success(), "{}", stderr(&run));
        let back = read(&out);
        let names = |g: &Groom| {
            g.attributes.iter().map(|a| a.name.clone()).collect::<std::collections::BTreeSet<_>>()
        };
        let mut written = names(&plain);
        written.insert("groom_group_id".to_string());
        assert_eq!(names(&back), written, ".{ext}");
        let group_ids = back.attribute("groom_group_id").unwrap();
        assert_eq!(group_ids.floats()[..], vec![0.0; back.strand_count()], ".{ext}");
        for attribute in &plain.attributes {
            let read = back.attribute(&attribute.name).unwrap();
            assert_eq!(
                (read.rate, read.components),
                (attribute.rate, attribute.components),
                ".{ext} {}",
                attribute.name
            );
            let worst = read
                .floats()
                .iter()
                .zip(attribute.floats().iter())
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f32::max);
            assert!(worst < 1e-6, ".{ext} {}: {worst}", attribute.name);
        }
        assert_eq!(back.root_uvs, plain.root_uvs, ".{ext}");
        assert_eq!(back.guides, plain.guides, ".{ext}");
        assert_eq!(back.strand_ids, plain.strand_ids, ".{ext}");
    }
}
