//! Files as other tools write them, built with coif's low-level archive writer in their layouts:
//! Xform hierarchies, several curves objects, cubic bases, widths in every scope, indexed
//! parameters and Epic's `groom_*` attributes. Expected grooms are computed by hand.
mod common;
use common::*;

use std::f64::consts::FRAC_PI_2;
use std::io::Cursor;

use coif::groom::{attr, AttributeRate, CurveBasis};
use coif::io::alembic::archive_write::{ArchiveWriter, CompoundId, ObjectId};
use coif::io::alembic::types::{MetaData, Pod, TimeSampling};
use coif::io::alembic::{self, CurvesArchive};
use glam::{DMat4, DVec3, Vec3};

type Writer = ArchiveWriter<Cursor<Vec<u8>>>;

fn f32s(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn param_md(scope: &str, pod: Pod, extent: u8) -> MetaData {
    MetaData::new()
        .with("geoScope", scope)
        .with("isGeomParam", "true")
        .with("podName", pod.name())
        .with("podExtent", &extent.to_string())
        .with("arrayExtent", "1")
}

fn xform(
    w: &mut Writer,
    parent: ObjectId,
    name: &str,
    ops: &[u8],
    vals: &[f64],
    inherits: Option<bool>,
) -> ObjectId {
    let md =
        MetaData::new().with("schema", "AbcGeom_Xform_v3").with("schemaObjTitle", "AbcGeom_Xform_v3:.xform");
    let object = w.add_object(parent, name, md);
    let top = w.properties(object);
    let x = w.add_compound(top, ".xform", MetaData::new().with("schema", "AbcGeom_Xform_v3"));
    if let Some(inherits) = inherits {
        let p = w.add_scalar(x, ".inherits", MetaData::new(), Pod::Bool, 1, 0);
        w.set_sample(p, &[inherits as u8], 1).unwrap();
    }
    if !ops.is_empty() {
        let p = w.add_scalar(x, ".ops", MetaData::new(), Pod::U8, ops.len() as u8, 0);
        w.set_sample(p, ops, 1).unwrap();
        let p = w.add_scalar(x, ".vals", MetaData::new(), Pod::F64, vals.len() as u8, 0);
        w.set_sample(p, &vals.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<_>>(), 1).unwrap();
    }
    object
}

/// A curves object with the mandatory properties; returns `.geom` for optional ones.
fn curves(
    w: &mut Writer,
    parent: ObjectId,
    name: &str,
    counts: &[i32],
    points: &[Vec3],
    basis: [u8; 4],
) -> CompoundId {
    let md = MetaData::new()
        .with("schema", "AbcGeom_Curve_v2")
        .with("schemaBaseType", "AbcGeom_GeomBase_v1")
        .with("schemaObjTitle", "AbcGeom_Curve_v2:.geom");
    let object = w.add_object(parent, name, md);
    let top = w.properties(object);
    let geom = w.add_compound(
        top,
        ".geom",
        MetaData::new().with("schema", "AbcGeom_Curve_v2").with("schemaBaseType", "AbcGeom_GeomBase_v1"),
    );
    let b = w.add_scalar(geom, ".selfBnds", MetaData::new().with("interpretation", "box"), Pod::F64, 6, 0);
    w.set_sample(b, &[0u8; 48], 1).unwrap();
    let p = w.add_array(
        geom,
        "P",
        MetaData::new().with("geoScope", "vtx").with("interpretation", "point"),
        Pod::F32,
        3,
        0,
    );
    w.set_sample(p, bytemuck::cast_slice(points), points.len() as u64).unwrap();
    let n = w.add_array(geom, "nVertices", MetaData::new(), Pod::I32, 1, 0);
    w.set_sample(n, bytemuck::cast_slice(counts), counts.len() as u64).unwrap();
    let t = w.add_scalar(geom, "curveBasisAndType", MetaData::new(), Pod::U8, 4, 0);
    w.set_sample(t, &basis, 1).unwrap();
    geom
}

fn line(x: f32, n: usize) -> Vec<Vec3> {
    (0..n).map(|k| Vec3::new(x, -(k as f32) * 0.1, 0.0)).collect()
}

#[test]
fn xform_hierarchies_are_applied_and_curves_objects_merged() {
    let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
    let top = w.top();
    // /rig: translate (0, 0, 5); /rig/head: rotate 90° about Y, then scale 2 (ops outermost first).
    let rig = xform(&mut w, top, "rig", &[0x10], &[0.0, 0.0, 5.0], None);
    let head = xform(&mut w, rig, "head", &[0x50, 0x00], &[90.0, 2.0, 2.0, 2.0], Some(true));
    let a_points = [line(1.0, 3), line(2.0, 4)].concat();
    let a = curves(&mut w, head, "hairA", &[3, 4], &a_points, [1, 0, 0, 0]);
    let width = w.add_array(a, "width", param_md("con", Pod::F32, 1), Pod::F32, 1, 0);
    w.set_sample(width, &f32s(&[0.01]), 1).unwrap();
    // /loose: a matrix op that does not inherit from above (here: nothing above anyway).
    let matrix = DMat4::from_translation(DVec3::new(10.0, 0.0, 0.0));
    let loose = xform(&mut w, rig, "loose", &[0x30], &matrix.to_cols_array(), Some(false));
    let b_points = [line(0.0, 2), line(0.5, 5)].concat();
    let b = curves(&mut w, loose, "hairB", &[2, 5], &b_points, [1, 0, 0, 0]);
    let width = w.add_array(b, "width", param_md("uni", Pod::F32, 1), Pod::F32, 1, 0);
    w.set_sample(width, &f32s(&[0.02, 0.03]), 2).unwrap();
    let bytes = w.finish().unwrap().into_inner();

    let groom = alembic::read(&bytes, std::path::Path::new("rig.abc"), None, false).unwrap().0;
    assert_eq!(groom.strand_offsets, vec![0, 3, 7, 9, 14]);
    let head_world = DMat4::from_translation(DVec3::new(0.0, 0.0, 5.0))
        * DMat4::from_rotation_y(FRAC_PI_2)
        * DMat4::from_scale(DVec3::splat(2.0));
    // By hand: (1, 0, 0) → scale (2, 0, 0) → rotate about Y (0, 0, −2) → translate (0, 0, 3).
    assert!((groom.points[0] - Vec3::new(0.0, 0.0, 3.0)).length() < 1e-6);
    for (got, p) in groom.points[..7].iter().zip(&a_points) {
        assert!((*got - head_world.transform_point3(p.as_dvec3()).as_vec3()).length() < 1e-5);
    }
    // `.inherits = false`: only its own matrix applies, not /rig's translation.
    for (got, p) in groom.points[7..].iter().zip(&b_points) {
        assert!((*got - (*p + Vec3::new(10.0, 0.0, 0.0))).length() < 1e-6);
    }
    // Widths are lengths in their object's space, as points are: /rig/head's scale 2 doubles
    // hairA's (Blender draws them so, and the USD reader scales them alike).
    let expected_widths = [vec![0.02; 7], vec![0.02; 2], vec![0.03; 5]].concat();
    assert_eq!(groom.widths, expected_widths);
    assert_eq!(groom.strand_ids, vec![0, 1, 2, 3]);
}

#[test]
fn epic_groom_attributes_and_indexed_params() {
    let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
    let top = w.top();
    let points = [line(0.0, 3), line(1.0, 3), line(2.0, 2)].concat();
    let geom = curves(&mut w, top, "groom", &[3, 3, 2], &points, [1, 0, 0, 0]);
    let arb = w.add_compound(geom, ".arbGeomParams", MetaData::new());
    let p = w.add_array(arb, "groom_width", param_md("uni", Pod::F32, 1), Pod::F32, 1, 0);
    w.set_sample(p, &f32s(&[0.5, 0.25, 0.125]), 3).unwrap();
    let p = w.add_array(arb, "groom_guide", param_md("uni", Pod::I8, 1), Pod::I8, 1, 0);
    w.set_sample(p, &[1, 0, 1], 3).unwrap();
    let p = w.add_array(arb, "groom_group_id", param_md("uni", Pod::I32, 1), Pod::I32, 1, 0);
    w.set_sample(p, bytemuck::cast_slice(&[0i32, 0, 1]), 3).unwrap();
    let p = w.add_array(arb, "groom_id", param_md("uni", Pod::I32, 1), Pod::I32, 1, 0);
    w.set_sample(p, bytemuck::cast_slice(&[7i32, 8, 9]), 3).unwrap();
    let p = w.add_array(arb, "groom_root_uv", param_md("uni", Pod::F64, 2), Pod::F64, 2, 0);
    let uvs = [0.1f64, 0.2, 0.3, 0.4, 0.5, 0.75];
    w.set_sample(p, bytemuck::cast_slice(&uvs), 3).unwrap();
    let p = w.add_array(arb, "groom_color", param_md("vtx", Pod::F32, 3), Pod::F32, 3, 0);
    let colors: Vec<f32> = (0..24).map(|i| i as f32 / 32.0).collect();
    w.set_sample(p, &f32s(&colors), 8).unwrap();
    // An indexed parameter: two values, chosen per curve by `.indices`.
    let clump = w.add_compound(arb, "clump", param_md("uni", Pod::F32, 1));
    let vals = w.add_array(clump, ".vals", param_md("uni", Pod::F32, 1), Pod::F32, 1, 0);
    w.set_sample(vals, &f32s(&[10.0, 20.0]), 2).unwrap();
    let indices = w.add_array(clump, ".indices", MetaData::new(), Pod::U32, 1, 0);
    w.set_sample(indices, bytemuck::cast_slice(&[1u32, 0, 1]), 3).unwrap();
    // Epic's groom spec version on the curves' .userProperties: the file is in centimetres.
    let user = w.add_compound(geom, ".userProperties", MetaData::new());
    let v = w.add_scalar(user, "groom_version_major", MetaData::new(), Pod::I16, 1, 0);
    w.set_sample(v, &1i16.to_le_bytes(), 1).unwrap();
    let bytes = w.finish().unwrap().into_inner();

    let path = std::path::Path::new("epic.abc");
    let groom = alembic::read(&bytes, path, None, true).unwrap().0;
    assert_eq!(groom.widths, vec![0.5, 0.5, 0.5, 0.25, 0.25, 0.25, 0.125, 0.125], "groom_width per curve");
    assert_eq!(groom.guides, Some(vec![true, false, true]));
    assert_eq!(groom.strand_ids, vec![7, 8, 9]);
    assert_eq!(groom.root_uvs, Some(vec![[0.1, 0.2], [0.3, 0.4], [0.5, 0.75]]));
    let color = groom.attribute(attr::COLOR).unwrap();
    assert_eq!((color.rate, color.components, &color.floats()[..]), (AttributeRate::Vertex, 3, &colors[..]));
    let group = groom.attribute("groom_group_id").unwrap();
    assert_eq!((group.rate, &group.floats()[..]), (AttributeRate::Strand, &[0.0, 0.0, 1.0][..]));
    assert_eq!(groom.attribute("clump").unwrap().floats(), vec![20.0, 10.0, 20.0]);
    groom.validate().unwrap();
}

/// Epic's `groom_group_id` the same for a whole object (a guides object and a strands object of
/// one Unreal group, 3): the reader took it for the object itself and dropped it, so the groups
/// were renumbered on writing. Stored as int32 (Epic's type) or float32, it reads back as 3.
#[test]
fn an_objects_constant_group_id_is_kept() {
    for pod in [Pod::I32, Pod::F32] {
        let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
        let top = w.top();
        let root = xform(&mut w, top, "groom", &[], &[], None);
        for (k, name) in ["guides", "hair"].into_iter().enumerate() {
            let points = [line(k as f32, 3), line(k as f32 + 0.5, 3)].concat();
            let geom = curves(&mut w, root, name, &[3, 3], &points, [1, 0, 0, 0]);
            let arb = w.add_compound(geom, ".arbGeomParams", MetaData::new());
            let ids = w.add_array(arb, "groom_group_id", param_md("uni", pod, 1), pod, 1, 0);
            let bytes = match pod {
                Pod::I32 => bytemuck::cast_slice(&[3i32, 3]).to_vec(),
                _ => f32s(&[3.0, 3.0]),
            };
            w.set_sample(ids, &bytes, 2).unwrap();
        }
        let bytes = w.finish().unwrap().into_inner();
        let groom = alembic::read(&bytes, std::path::Path::new("unreal.abc"), None, false).unwrap().0;
        let ids = groom.attribute("groom_group_id").unwrap_or_else(|| panic!("{pod:?}: group ids dropped"));
        assert_eq!((ids.rate, &ids.floats()[..]), (AttributeRate::Strand, &[3.0; 4][..]), "{pod:?}");
    }
}

#[test]
fn epic_spec_on_an_xform_means_centimetres() {
    let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
    let top = w.top();
    let root = xform(&mut w, top, "groom", &[], &[], None);
    let props = w.properties(root);
    let user = w.add_compound(props, ".userProperties", MetaData::new());
    let v = w.add_scalar(user, "groom_version_major", MetaData::new(), Pod::I16, 1, 0);
    w.set_sample(v, &1i16.to_le_bytes(), 1).unwrap();
    let points = line(0.0, 3).iter().map(|p| *p * 100.0).collect::<Vec<_>>();
    let geom = curves(&mut w, root, "hair", &[3], &points, [1, 0, 0, 0]);
    let width = w.add_array(geom, "width", param_md("vtx", Pod::F32, 1), Pod::F32, 1, 0);
    w.set_sample(width, &f32s(&[0.008, 0.006, 0.004]), 3).unwrap();
    let bytes = w.finish().unwrap().into_inner();
    let groom = alembic::read(&bytes, std::path::Path::new("cm.abc"), None, false).unwrap().0;
    for (got, expected) in groom.points.iter().zip(line(0.0, 3)) {
        assert!((*got - expected).length() < 1e-6);
    }
    assert!((groom.widths[0] - 80e-6).abs() < 1e-10);
}

#[test]
fn the_basis_byte_decides_the_curve_kind() {
    // Blender's hair says [1, 0, 3, 3] (linear type, Catmull-Rom basis); the C++ library's
    // default for linear curves is [1, 0, 1, 1] (Bézier basis).
    for (bytes, expected) in [
        ([1u8, 0, 3, 3], CurveBasis::CatmullRom),
        ([1, 0, 1, 1], CurveBasis::Bezier),
        ([0, 0, 2, 2], CurveBasis::BSpline),
        ([1, 0, 0, 0], CurveBasis::Linear),
    ] {
        let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
        let top = w.top();
        curves(&mut w, top, "c", &[4], &line(0.0, 4), bytes);
        let file = w.finish().unwrap().into_inner();
        let groom = alembic::read(&file, std::path::Path::new("b.abc"), None, false).unwrap().0;
        assert_eq!(groom.basis, expected, "{bytes:?}");
    }
}

/// Maya's AbcExport writes every nurbsCurve with the B-spline basis and its degree in the type
/// byte (`MayaNurbsCurveWriter`: cubic for degree 3, linear for degree 1, variable order with
/// `.orders` otherwise); Maya's AbcImport and Blender's reader take the order from the type, so a
/// "linear" B-spline is a polyline through its points. An order coif cannot simulate exits 2
/// naming the object and the order.
#[test]
fn maya_nurbs_curves_take_their_order_from_the_type_byte() {
    let read = |bytes: [u8; 4], orders: Option<&[u8]>| {
        let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
        let top = w.top();
        let geom = curves(&mut w, top, "nurbsCurve1", &[4, 4], &[line(0.0, 4), line(1.0, 4)].concat(), bytes);
        if let Some(orders) = orders {
            let property = w.add_array(geom, ".orders", MetaData::new(), Pod::U8, 1, 0);
            w.set_sample(property, orders, orders.len() as u64).unwrap();
        }
        let file = w.finish().unwrap().into_inner();
        alembic::read(&file, std::path::Path::new("maya.abc"), None, false)
    };
    for (bytes, orders, expected) in [
        ([1u8, 0, 2, 2], None, CurveBasis::Linear),
        ([0, 0, 2, 2], None, CurveBasis::BSpline),
        ([2, 0, 2, 2], Some(&[2u8, 2][..]), CurveBasis::Linear),
        ([2, 0, 2, 2], Some(&[4, 4][..]), CurveBasis::BSpline),
        // No `.orders`: order 2 in Maya's AbcImport and Blender's reader.
        ([2, 0, 2, 2], None, CurveBasis::Linear),
    ] {
        assert_eq!(read(bytes, orders).unwrap().0.basis, expected, "{bytes:?} orders {orders:?}");
    }
    for (orders, named) in [(&[4u8, 3][..], "order 3"), (&[2, 4][..], "one degree per object")] {
        let message = read([2, 0, 2, 2], Some(orders)).unwrap_err().to_string();
        assert!(message.contains("nurbsCurve1") && message.contains(named), "{orders:?}: {message}");
    }
}

#[test]
fn animated_foreign_file_reads_frames_on_the_union_of_its_samplings() {
    // Positions on 24 fps from frame 1; an Xform sampled at 7 fps moving +1 in x per sample.
    let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
    let fast = w.add_time_sampling(TimeSampling::uniform(24.0, 1.0 / 24.0));
    let slow = w.add_time_sampling(TimeSampling::uniform(7.0, 1.0 / 7.0));
    let top = w.top();
    let md = MetaData::new().with("schema", "AbcGeom_Xform_v3");
    let object = w.add_object(top, "mover", md);
    let props = w.properties(object);
    let x = w.add_compound(props, ".xform", MetaData::new().with("schema", "AbcGeom_Xform_v3"));
    let ops = w.add_scalar(x, ".ops", MetaData::new(), Pod::U8, 1, 0);
    w.set_sample(ops, &[0x10], 1).unwrap();
    let vals = w.add_scalar(x, ".vals", MetaData::new(), Pod::F64, 3, slow);
    for s in 0..3 {
        w.set_sample(vals, &[s as f64, 0.0, 0.0].iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<_>>(), 1)
            .unwrap();
    }
    let md =
        MetaData::new().with("schema", "AbcGeom_Curve_v2").with("schemaObjTitle", "AbcGeom_Curve_v2:.geom");
    let curve = w.add_object(object, "c", md);
    let props = w.properties(curve);
    let geom = w.add_compound(props, ".geom", MetaData::new().with("schema", "AbcGeom_Curve_v2"));
    let b = w.add_scalar(geom, ".selfBnds", MetaData::new().with("interpretation", "box"), Pod::F64, 6, fast);
    let p = w.add_array(geom, "P", MetaData::new(), Pod::F32, 3, fast);
    let n = w.add_array(geom, "nVertices", MetaData::new(), Pod::I32, 1, fast);
    let t = w.add_scalar(geom, "curveBasisAndType", MetaData::new(), Pod::U8, 4, fast);
    for f in 0..6 {
        let points: Vec<Vec3> = line(0.0, 2).iter().map(|q| *q + Vec3::new(0.0, 0.0, f as f32)).collect();
        w.set_sample(b, &[0u8; 48], 1).unwrap();
        w.set_sample(p, bytemuck::cast_slice(&points), 2).unwrap();
        w.set_sample(n, &2i32.to_le_bytes(), 1).unwrap();
        w.set_sample(t, &[1, 0, 0, 0], 1).unwrap();
    }
    let bytes = w.finish().unwrap().into_inner();
    let archive = CurvesArchive::open(&bytes).unwrap();
    // The timeline is the union of both samplings (6 + 3 times); frames count at the positions'
    // 24 fps (the first animated property's cycle: the file declares no rate).
    assert_eq!(archive.frame_count(), 9);
    assert_eq!(archive.frames_per_second(), 24.0);
    // Frame f is at f/24 s: positions sample f - 1; the Xform holds its first sample before 1/7 s,
    // then moves linearly (+1 per 1/7 s), and holds its last after 3/7 s — by hand:
    // x = clamp((f/24 − 1/7)·7, 0, 2).
    for f in [1.0f64, 2.0, 3.0, 4.0, 5.0, 6.0, 11.0, 12.0] {
        let groom = archive.read_at_frame(f).unwrap();
        let x = ((f / 24.0 - 1.0 / 7.0) * 7.0).clamp(0.0, 2.0) as f32;
        let expected = Vec3::new(x, 0.0, (f.min(6.0) - 1.0) as f32);
        assert!((groom.points[0] - expected).length() < 1e-6, "frame {f}: {} vs {expected}", groom.points[0]);
    }
    assert!(archive.read_at_frame(0.5).is_err(), "before the first sample");
}

/// A width whose count fits neither its `geoScope` nor, without one, any rate exits 2 naming the
/// object and the property, with the count and what the scope needs.
#[test]
fn a_width_count_that_fits_no_scope_names_object_and_property() {
    let cases: [(&str, &[f32], &str); 4] = [
        ("uni", &[0.1, 0.2, 0.3], "3 values, its scope needs 2"),
        ("con", &[0.1, 0.2], "2 values, its scope needs 1"),
        ("vtx", &[0.1; 6], "6 values, its scope needs 7"),
        ("", &[0.1; 5], "5 values and no geoScope: coif reads 7 (one per vertex), 2 (one per curve) or 1"),
    ];
    for (scope, widths, needs) in cases {
        let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
        let top = w.top();
        let rig = xform(&mut w, top, "rig", &[0x10], &[0.0, 0.0, 0.0], None);
        let points = [line(1.0, 3), line(2.0, 4)].concat();
        let hair = curves(&mut w, rig, "hair", &[3, 4], &points, [1, 0, 0, 0]);
        let metadata = if scope.is_empty() { MetaData::new() } else { param_md(scope, Pod::F32, 1) };
        let width = w.add_array(hair, "width", metadata, Pod::F32, 1, 0);
        w.set_sample(width, &f32s(widths), widths.len() as u64).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("widths.abc");
        std::fs::write(&path, w.finish().unwrap().into_inner()).unwrap();
        let out = coif(&["info", path_str(&path)]);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "scope {scope:?}: {message}");
        assert!(message.contains("widths.abc"), "scope {scope:?}: {message}");
        assert!(message.contains(&format!("/rig/hair/.geom/width: {needs}")), "scope {scope:?}: {message}");
    }
}

#[test]
fn curves_missing_mandatory_properties_are_rejected() {
    for missing in [".selfBnds", "curveBasisAndType"] {
        let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
        let top = w.top();
        let md = MetaData::new().with("schema", "AbcGeom_Curve_v2");
        let object = w.add_object(top, "c", md);
        let props = w.properties(object);
        let geom = w.add_compound(props, ".geom", MetaData::new().with("schema", "AbcGeom_Curve_v2"));
        if missing != ".selfBnds" {
            let b = w.add_scalar(geom, ".selfBnds", MetaData::new(), Pod::F64, 6, 0);
            w.set_sample(b, &[0u8; 48], 1).unwrap();
        }
        let p = w.add_array(geom, "P", MetaData::new(), Pod::F32, 3, 0);
        w.set_sample(p, bytemuck::cast_slice(&line(0.0, 2)), 2).unwrap();
        let n = w.add_array(geom, "nVertices", MetaData::new(), Pod::I32, 1, 0);
        w.set_sample(n, &2i32.to_le_bytes(), 1).unwrap();
        if missing != "curveBasisAndType" {
            let t = w.add_scalar(geom, "curveBasisAndType", MetaData::new(), Pod::U8, 4, 0);
            w.set_sample(t, &[1, 0, 0, 0], 1).unwrap();
        }
        let bytes = w.finish().unwrap().into_inner();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("missing.abc");
        std::fs::write(&path, bytes).unwrap();
        let out = coif(&["info", path_str(&path)]);
        assert_eq!(out.status.code(), Some(2));
        assert!(stderr(&out).contains(missing), "{}", stderr(&out));
    }
}

/// `.arbGeomParams` of a foreign file keep what they are through coif: an int32 and a bool
/// flag stay int32 and bool, a normal, a vector and a point (interpretation metadata) turn with
/// the Xform above the curves (a 90° turn about Z and a ×2 scale: points and vectors scale,
/// normals stay unit), and a param coif knows nothing about passes through with its values;
/// written back to `.abc` each keeps its POD and interpretation, and USD output gets the
/// matching types (`int[]`, `bool[]`, `normal3f[]`, `vector3f[]`, `point3f[]`).
#[test]
fn geom_params_keep_types_and_turn_with_the_transform() {
    let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
    let top = w.top();
    // rotateZ 90° (op 6), then scale 2 (op 0).
    let rig = xform(&mut w, top, "rig", &[0x60, 0x00], &[90.0, 2.0, 2.0, 2.0], Some(true));
    let geom = curves(&mut w, rig, "hair", &[2, 2], &[line(0.0, 2), line(1.0, 2)].concat(), [1, 0, 0, 0]);
    let arb = w.add_compound(geom, ".arbGeomParams", MetaData::new());
    let mut param =
        |name: &str, pod: Pod, extent: u8, scope: &str, interpretation: &str, bytes: Vec<u8>, n: u64| {
            let mut md = param_md(scope, pod, extent);
            if !interpretation.is_empty() {
                md = md.with("interpretation", interpretation);
            }
            let p = w.add_array(arb, name, md, pod, extent, 0);
            w.set_sample(p, &bytes, n).unwrap();
        };
    param("clump_id", Pod::I32, 1, "uni", "", [7i32, -3].iter().flat_map(|v| v.to_le_bytes()).collect(), 2);
    param("is_long", Pod::Bool, 1, "uni", "", vec![1, 0], 2);
    param("N", Pod::F32, 3, "uni", "normal", f32s(&[1.0, 0.0, 0.0, 0.0, 0.6, 0.8]), 2);
    param("comb", Pod::F32, 3, "vtx", "vector", f32s(&[1.0, 0.0, 0.0].repeat(4)), 4);
    param("anchor", Pod::F32, 3, "uni", "point", f32s(&[1.0, 0.0, 0.0, 0.0, 0.0, 1.0]), 2);
    param("mystery", Pod::F32, 2, "uni", "", f32s(&[0.25, 0.5, 0.75, 1.0]), 2);
    let bytes = w.finish().unwrap().into_inner();
    let dir = tempfile::tempdir().unwrap();
    let source = dir.path().join("params.abc");
    std::fs::write(&source, &bytes).unwrap();
    let groom = coif::io::read_groom(&source, &Default::default()).unwrap().groom;

    use coif::groom::AttributeKind;
    let attribute =
        |g: &coif::Groom, name: &str| g.attribute(name).unwrap_or_else(|| panic!("no {name}")).clone();
    let close = |a: &[f32], b: &[f32], what: &str| {
        assert_eq!(a.len(), b.len(), "{what}");
        assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6), "{what}: {a:?} vs {b:?}");
    };
    // Rotate Z by 90°: (x, y, z) → (−y, x, z); scale 2 first.
    assert_eq!(
        (attribute(&groom, "clump_id").kind, attribute(&groom, "clump_id").ints()),
        (AttributeKind::Int, Some(&[7, -3][..]))
    );
    assert_eq!(
        (attribute(&groom, "is_long").kind, &attribute(&groom, "is_long").floats()[..]),
        (AttributeKind::Bool, &[1.0, 0.0][..])
    );
    assert_eq!(attribute(&groom, "N").kind, AttributeKind::Normal);
    close(&attribute(&groom, "N").floats(), &[0.0, 1.0, 0.0, -0.6, 0.0, 0.8], "N turned, unit length");
    assert_eq!(attribute(&groom, "comb").kind, AttributeKind::Vector);
    close(&attribute(&groom, "comb").floats(), &[0.0, 2.0, 0.0].repeat(4), "comb turned and scaled");
    assert_eq!(attribute(&groom, "anchor").kind, AttributeKind::Point);
    close(
        &attribute(&groom, "anchor").floats(),
        &[0.0, 2.0, 0.0, 0.0, 0.0, 2.0],
        "anchor placed like the points",
    );
    assert_eq!(
        attribute(&groom, "mystery").floats(),
        vec![0.25, 0.5, 0.75, 1.0],
        "unknown params pass through"
    );
    // `--up z` turns them with the points too: (x, y, z) → (x, z, −y).
    let options = coif::io::ImportOptions { up_axis: Some(coif::io::UpAxis::Z), ..Default::default() };
    let z_up = coif::io::read_groom(&source, &options).unwrap().groom;
    let turned: Vec<f32> =
        attribute(&groom, "N").floats().chunks_exact(3).flat_map(|n| [n[0], n[2], -n[1]]).collect();
    close(&attribute(&z_up, "N").floats(), &turned, "N turned from Z up");

    // Written back: the same PODs and interpretations; read again, the same groom.
    let out = dir.path().join("back.abc");
    coif::io::write_groom(&out, &groom).unwrap();
    let written = std::fs::read(&out).unwrap();
    let archive = coif::io::alembic::archive_read::Archive::open(&written).unwrap();
    let curves = &archive.top.children[0].children[0];
    let geom = curves.properties.compound(".geom").unwrap();
    let arb = geom.compound(".arbGeomParams").unwrap();
    for (name, pod, interpretation) in [
        ("clump_id", Pod::I32, None),
        ("is_long", Pod::Bool, None),
        ("N", Pod::F32, Some("normal")),
        ("comb", Pod::F32, Some("vector")),
        ("anchor", Pod::F32, Some("point")),
    ] {
        let p = arb.sampled(name).unwrap_or_else(|| panic!("{name} not written"));
        assert_eq!((p.pod, p.metadata.get("interpretation")), (pod, interpretation), "{name}");
    }
    assert_eq!(coif::io::read_groom(&out, &Default::default()).unwrap().groom, groom);
    let usda = dir.path().join("params.usda");
    coif::io::write_groom(&usda, &groom).unwrap();
    let text = std::fs::read_to_string(&usda).unwrap();
    for declaration in [
        "int[] primvars:clump_id",
        "bool[] primvars:is_long",
        "normal3f[] primvars:N",
        "vector3f[] primvars:comb",
        "point3f[] primvars:anchor",
    ] {
        assert!(text.contains(declaration), "{declaration} missing from the .usda");
    }
}

/// An archive with one cubic curves object `/hair` (curves of 5 and 4 points, `basis` bytes)
/// whose `width` has `geoScope = var` and `widths`; written to `dir/name`.
fn varying_widths_file(
    dir: &std::path::Path,
    name: &str,
    basis: [u8; 4],
    counts: &[i32],
    widths: &[f32],
    scope: &str,
) -> std::path::PathBuf {
    let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
    let top = w.top();
    let points: Vec<Vec3> =
        counts.iter().enumerate().flat_map(|(i, &n)| line(i as f32, n as usize)).collect();
    let hair = curves(&mut w, top, "hair", counts, &points, basis);
    let metadata = if scope.is_empty() { MetaData::new() } else { param_md(scope, Pod::F32, 1) };
    let width = w.add_array(hair, "width", metadata, Pod::F32, 1, 0);
    w.set_sample(width, &f32s(widths), widths.len() as u64).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, w.finish().unwrap().into_inner()).unwrap();
    path
}

#[test]
fn varying_widths_on_cubic_curves_are_per_segment_end_or_per_vertex() {
    // `var` on cubic curves: a RenderMan-style writer gives one value per segment end (a
    // nonperiodic B-spline of n points: n - 2; a Bézier: (n - 1)/3 + 1), Houdini one per point.
    // Segment-end widths must reach USD as `varying` with the same values (pxr counts the segment
    // ends itself) and come back in coif's .abc under `var` (ogawa-rs); per-point ones as vertex
    // widths; any other count exits 2 naming the file, object, property and both counts. Without
    // a scope (Blender's Bézier curves) a count of segment ends is read as `var`.
    let dir = tempfile::tempdir().unwrap();
    let bspline = [0, 0, 2, 1];
    let bezier = [0, 0, 1, 3];
    // (file, basis bytes, counts, widths, scope in the file, USD interpolation, Alembic scope
    // written back)
    type Case<'a> = (&'a str, [u8; 4], &'a [i32], Vec<f32>, &'a str, &'a str, &'a str);
    let cases: [Case; 4] = [
        ("ends.abc", bspline, &[5, 4], vec![0.01, 0.02, 0.03, 0.04, 0.05], "var", "varying", "var"),
        ("bezier.abc", bezier, &[7, 4], vec![0.01, 0.02, 0.03, 0.04, 0.05], "var", "varying", "var"),
        ("unscoped.abc", bezier, &[7, 4], vec![0.01, 0.02, 0.03, 0.04, 0.05], "", "varying", "var"),
        ("points.abc", bspline, &[5, 4], (1..=9).map(|i| i as f32 * 0.01).collect(), "var", "vertex", "vtx"),
    ];
    for (name, basis, counts, widths, scope_in, usd, scope) in cases {
        let source = varying_widths_file(dir.path(), name, basis, counts, &widths, scope_in);
        let usda = dir.path().join(format!("{name}.usda"));
        let run = coif(&["convert", path_str(&source), path_str(&usda)]);
        assert!(run.status.success(), "{name}: {}", stderr(&run));
        let dump = common::usd::pxr_dump(&usda, None);
        let prim = &dump["curves"][0];
        assert_eq!(prim["widthsInterpolation"], usd, "{name}");
        assert_eq!(common::usd::f32s(&prim["widths"]), widths, "{name}");
        if usd == "varying" {
            assert_eq!(prim["segmentEnds"].as_u64(), Some(widths.len() as u64), "{name}: pxr's segment ends");
        }
        let abc = dir.path().join(format!("back_{name}"));
        let run = coif(&["convert", path_str(&source), path_str(&abc)]);
        assert!(run.status.success(), "{name}: {}", stderr(&run));
        let read = curve_widths_via_ogawa_rs(&abc);
        assert_eq!(read, vec![("/hair".to_string(), scope.to_string(), widths.clone())], "{name}");
    }
    for (scope, needs) in [
        ("var", "6 values, its scope needs 9 (one per vertex) or 5"),
        ("", "6 values and no geoScope: coif reads 9 (one per vertex), 5 (one per segment end of the BSpline curves), 2 (one per curve) or 1"),
    ] {
        let bad = varying_widths_file(dir.path(), "bad.abc", bspline, &[5, 4], &[0.01; 6], scope);
        let out = coif(&["info", path_str(&bad)]);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{message}");
        assert!(message.contains("bad.abc"), "{message}");
        assert!(message.contains(&format!("/hair/.geom/width: {needs}")), "{scope:?}: {message}");
    }
}

/// A geometry parameter of more values per element than a groom attribute holds (a 3 × 3 matrix
/// per curve, as Houdini writes a `matrix3` attribute) is left out with a warning naming the
/// file, object and property, as the USD reader warns for such a primvar; the others are read.
/// It was dropped without a word.
#[test]
fn a_parameter_of_more_than_four_values_per_element_is_left_out_with_a_warning() {
    let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
    let top = w.top();
    let rig = xform(&mut w, top, "rig", &[], &[], None);
    let geom = curves(&mut w, rig, "hair", &[3, 3], &[line(0.0, 3), line(1.0, 3)].concat(), [1, 0, 0, 0]);
    let arb = w.add_compound(geom, ".arbGeomParams", MetaData::new());
    let frames = w.add_array(arb, "frames", param_md("uni", Pod::F32, 9), Pod::F32, 9, 0);
    w.set_sample(frames, &f32s(&[0.5; 18]), 2).unwrap();
    let clump = w.add_array(arb, "clump", param_md("uni", Pod::F32, 1), Pod::F32, 1, 0);
    w.set_sample(clump, &f32s(&[1.0, 2.0]), 2).unwrap();
    let bytes = w.finish().unwrap().into_inner();

    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("matrices.abc");
    std::fs::write(&input, &bytes).unwrap();
    let (groom, warnings) = alembic::read(&bytes, &input, None, false).unwrap();
    assert_eq!(groom.attribute("clump").unwrap().floats(), vec![1.0, 2.0]);
    assert!(groom.attribute("frames").is_none());
    let expected = format!(
        "{}: /rig/hair/.geom/.arbGeomParams/frames is left out: 9 values per element, more than the 4 \
         a groom attribute holds",
        input.display()
    );
    assert_eq!(warnings, vec![expected.clone()]);
    // The command line shows it.
    let out = dir.path().join("out.usda");
    let converted = coif(&["convert", path_str(&input), path_str(&out)]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    assert!(stderr(&converted).contains(&format!("warning: {expected}")), "{}", stderr(&converted));
}

/// Curves of NURBS order 5 (degree 4) in one object of several: coif cannot simulate them and
/// does not read the file without them (a groom written back without some of its hair would pass
/// unnoticed); it exits 2 naming the file, the object and the orders it reads, and says what to
/// do. pxr and Blender read order 5; Blender's NURBS hair is order 4 by default.
#[test]
fn an_object_of_order_5_nurbs_refuses_the_file_naming_it_and_the_remedy() {
    let mut w = ArchiveWriter::new(Cursor::new(Vec::new()), MetaData::new()).unwrap();
    let top = w.top();
    curves(&mut w, top, "guides", &[4, 4], &[line(0.0, 4), line(1.0, 4)].concat(), [0, 0, 3, 3]);
    let odd = curves(&mut w, top, "eyebrows", &[5], &line(2.0, 5), [2, 0, 2, 2]);
    let orders = w.add_array(odd, ".orders", MetaData::new(), Pod::U8, 1, 0);
    w.set_sample(orders, &[5], 1).unwrap();
    let bytes = w.finish().unwrap().into_inner();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("groom.abc");
    std::fs::write(&input, &bytes).unwrap();
    let out = dir.path().join("out.usda");
    let refused = coif(&["convert", path_str(&input), path_str(&out)]);
    assert_eq!(refused.status.code(), Some(2), "{}", stderr(&refused));
    let message = stderr(&refused);
    for named in ["groom.abc", "/eyebrows", "order 5 (degree 4)", "give these curves order 4"] {
        assert!(message.contains(named), "{named}: {message}");
    }
    assert!(!message.contains("/guides"), "{message}");
    assert_eq!(dir_listing(dir.path()), vec!["groom.abc".to_string()]);
}
