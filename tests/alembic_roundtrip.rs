//! Alembic written by coif reads back exactly: static and animated files, every groom field
//! and attribute, cubic bases, and the Unreal convention (centimetres, `groom_*` names).
mod common;
use common::*;

use coif::groom::{attr, Attribute, AttributeKind, AttributeRate, CurveBasis, CurveGroup, CurveWrap, Groom};
use coif::io::alembic::archive_read::{Archive, Property};
use coif::io::alembic::{self, AlembicWriteOptions, AnimationWriter, CurvesArchive};
use coif::io::{read_groom, write_groom, ImportOptions};
use glam::Vec3;

/// Strands of varying vertex counts with every optional field and a spread of attributes.
fn full_groom() -> Groom {
    let strands: Vec<Vec<Vec3>> = (0..7)
        .map(|s| {
            (0..(2 + s))
                .map(|k| Vec3::new(s as f32 * 0.01, -(k as f32) * 0.013, 0.002 * (k * k) as f32 - 0.1))
                .collect()
        })
        .collect();
    let mut groom = Groom::from_strands(&strands, 0.0);
    let (n, s) = (groom.vertex_count(), groom.strand_count());
    groom.widths = (0..n).map(|i| 40e-6 + i as f32 * 1.5e-7).collect();
    groom.strand_ids = (0..s as u32).map(|i| 1000 + 3 * i).collect();
    groom.root_uvs = Some((0..s).map(|i| [i as f32 / 7.0, 1.0 - i as f32 / 9.0]).collect());
    groom.guides = Some((0..s).map(|i| i % 3 == 0).collect());
    let ramp = |len: usize, k: f32| (0..len).map(|i| (i as f32 * k).sin()).collect::<Vec<f32>>();
    groom.set_attribute(Attribute::new(attr::COLOR, AttributeRate::Vertex, 3, ramp(3 * n, 0.3)));
    groom.set_attribute(Attribute::new("rest", AttributeRate::Vertex, 3, ramp(3 * n, 0.7)));
    groom.set_attribute(Attribute::new("rest_darboux", AttributeRate::Vertex, 3, ramp(3 * n, 1.1)));
    for (j, bond) in ["bond_hydrogen", "bond_ionic", "bond_disulfide", "bond_peptide"].iter().enumerate() {
        groom.set_attribute(Attribute::new(*bond, AttributeRate::Vertex, 1, ramp(n, 0.1 + j as f32)));
    }
    groom.set_attribute(Attribute::new("wetness", AttributeRate::Vertex, 1, ramp(n, 0.05)));
    groom.set_attribute(Attribute::new("clump", AttributeRate::Strand, 2, ramp(2 * s, 0.9)));
    groom.set_attribute(Attribute::new("melanin", AttributeRate::Strand, 4, ramp(4 * s, 0.4)));
    groom.validate().unwrap();
    groom
}

/// Frame `f` of an animation: every point moves with its own constant velocity.
fn frame(groom: &Groom, f: usize) -> (Groom, Vec<Vec3>) {
    let velocity: Vec<Vec3> =
        (0..groom.vertex_count()).map(|i| Vec3::new(0.5, -0.25 * (i % 3) as f32, 0.125)).collect();
    let mut g = groom.clone();
    let t = f as f32 / 24.0;
    for (p, v) in g.points.iter_mut().zip(&velocity) {
        *p += *v * t;
    }
    (g, velocity)
}

#[test]
fn static_round_trip_is_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("groom.abc");
    let groom = full_groom();
    write_groom(&path, &groom).unwrap();
    let loaded = read_groom(&path, &ImportOptions::default()).unwrap();
    assert_eq!(loaded.format, coif::io::Format::Alembic);
    assert_eq!(loaded.groom, groom);
    // Writing what was read gives the same bytes.
    let again = dir.path().join("again.abc");
    write_groom(&again, &loaded.groom).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), std::fs::read(&again).unwrap());
}

#[test]
fn cubic_bases_round_trip_and_set_the_basis_byte() {
    let dir = tempfile::tempdir().unwrap();
    for (basis, byte) in [(CurveBasis::CatmullRom, 3u8), (CurveBasis::BSpline, 2), (CurveBasis::Bezier, 1)] {
        let mut groom = full_groom();
        groom.basis = basis;
        let path = dir.path().join(format!("{basis:?}.abc"));
        write_groom(&path, &groom).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let archive = Archive::open(&bytes).unwrap();
        let geom = archive.top.children[0].properties.compound(".geom").unwrap();
        let sample = geom.sampled("curveBasisAndType").unwrap().sample_bytes(&archive.ogawa, 0).unwrap();
        assert_eq!(sample, [0, 0, byte, byte], "cubic type, non-periodic, basis {basis:?}");
        // Alembic records no pinned wrap; Catmull-Rom reads back pinned (through its end
        // points, as Blender evaluates it), the other bases as they were.
        let mut expected = groom.clone();
        if basis == CurveBasis::CatmullRom {
            expected.set_single_group(CurveGroup::new("/curves", basis, CurveWrap::Pinned));
        }
        assert_eq!(read_groom(&path, &ImportOptions::default()).unwrap().groom, expected);
    }
}

#[test]
fn animated_round_trip_every_frame_and_one_frame() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("anim.abc");
    let base = full_groom();
    let frames: Vec<Groom> = (0..5).map(|f| frame(&base, f).0).collect();
    let options = AlembicWriteOptions::default();
    let mut writer = AnimationWriter::create(&path, &frames[0], &options, true).unwrap();
    for f in &frames {
        writer.write_frame(f).unwrap();
    }
    writer.finish().unwrap();

    // Each frame reads back with the `.velocities` the writer gave it: central differences of
    // its neighbours at 24 fps (one-sided at the ends).
    let fps = 24.0f32;
    let frames: Vec<Groom> = (0..frames.len())
        .map(|f| {
            let at = |k: usize| &frames[k].points;
            let (before, after, scale) = match f {
                0 => (at(0), at(1), fps),
                f if f + 1 == frames.len() => (at(f - 1), at(f), fps),
                f => (at(f - 1), at(f + 1), 0.5 * fps),
            };
            let data = before.iter().zip(after).flat_map(|(a, b)| ((*b - *a) * scale).to_array()).collect();
            let mut expected = frames[f].clone();
            expected.set_attribute(
                Attribute::new("velocities", AttributeRate::Vertex, 3, data).with_kind(AttributeKind::Vector),
            );
            expected
        })
        .collect();
    let bytes = std::fs::read(&path).unwrap();
    let all = alembic::read_all_frames(&bytes, &path, false).unwrap();
    assert_eq!(all, frames);
    // Frame numbers on the file's timeline: coif writes frame 1 at 1/24 s.
    for (f, expected) in frames.iter().enumerate() {
        let options = ImportOptions { frame: Some(f as f64 + 1.0), ..Default::default() };
        assert_eq!(&read_groom(&path, &options).unwrap().groom, expected, "frame {f}");
    }
    let archive = CurvesArchive::open(&bytes).unwrap();
    assert_eq!(archive.frame_count(), 5);
    // Uniform sampling at 24 fps starting at frame 1.
    assert!((archive.frame_time(0) - 1.0 / 24.0).abs() < 1e-12);
    assert!((archive.frame_time(4) - 5.0 / 24.0).abs() < 1e-12);
    assert_eq!((archive.frame_range(), archive.frames_per_second()), ((1.0, 5.0), 24.0));
    // Before the first frame is bad input; past the last, the last holds (as in USD).
    let out = coif(&["info", path_str(&path), "--frame", "0"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("frame 0 is before the file's first sample (frame 1"), "{}", stderr(&out));
    let options = ImportOptions { frame: Some(9.0), ..Default::default() };
    assert_eq!(&read_groom(&path, &options).unwrap().groom, frames.last().unwrap());
}

#[test]
fn animated_files_store_constant_data_once_and_velocities_per_frame() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("anim.abc");
    let base = full_groom();
    let mut writer = AnimationWriter::create(&path, &base, &AlembicWriteOptions::default(), true).unwrap();
    let mut velocity = Vec::new();
    for f in 0..4 {
        let (g, v) = frame(&base, f);
        velocity = v;
        writer.write_frame(&g).unwrap();
    }
    writer.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let archive = Archive::open(&bytes).unwrap();
    assert_eq!(archive.max_samples[1], 4, "time sampling 1 records 4 samples");
    let geom = archive.top.children[0].properties.compound(".geom").unwrap();
    for name in ["P", ".selfBnds", ".velocities"] {
        let p = geom.sampled(name).unwrap();
        assert_eq!((p.num_samples, p.first_changed, p.last_changed, p.time_sampling), (4, 1, 3, 1), "{name}");
    }
    for name in ["nVertices", "curveBasisAndType", "width"] {
        let p = geom.sampled(name).unwrap();
        assert_eq!((p.num_samples, p.first_changed, p.last_changed), (4, 0, 0), "{name} is constant");
    }
    let v = geom.sampled(".velocities").unwrap();
    for f in 0..4 {
        let got = v.read_f32(&archive.ogawa, f).unwrap();
        for (i, expected) in velocity.iter().enumerate() {
            let g = Vec3::new(got[3 * i], got[3 * i + 1], got[3 * i + 2]);
            assert!((g - *expected).length() < 1e-4, "frame {f} vertex {i}: {g} vs {expected}");
        }
    }
}

#[test]
fn frames_must_keep_the_topology() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("anim.abc");
    let base = full_groom();
    let mut writer = AnimationWriter::create(&path, &base, &AlembicWriteOptions::default(), true).unwrap();
    writer.write_frame(&base).unwrap();
    let other = Groom::from_strands(&[vec![Vec3::ZERO, Vec3::X]], 1e-4);
    assert!(writer.write_frame(&other).is_err());
    drop(writer);
    assert!(!path.exists(), "an unfinished animation leaves no file");
    assert_eq!(dir_listing(dir.path()), Vec::<String>::new());
}

#[test]
fn unreal_output_follows_epic_conventions() {
    let dir = tempfile::tempdir().unwrap();
    let hair = dir.path().join("in.abc");
    let out = dir.path().join("unreal.abc");
    let groom = full_groom();
    write_groom(&hair, &groom).unwrap();
    let run = coif(&["convert", path_str(&hair), path_str(&out), "--unreal"]);
    assert!(run.status.success(), "{}", stderr(&run));

    let bytes = std::fs::read(&out).unwrap();
    let archive = Archive::open(&bytes).unwrap();
    let top_xform = &archive.top.children[0];
    assert_eq!(top_xform.full_name, "/groom");
    let user = top_xform.properties.compound(".userProperties").unwrap();
    let read = |name: &str| user.sampled(name).unwrap().read_f64(&archive.ogawa, 0).unwrap();
    assert_eq!(read("groom_version_major"), vec![1.0]);
    assert_eq!(read("groom_version_minor"), vec![5.0]);
    let curves = &top_xform.children[0];
    let geom = curves.properties.compound(".geom").unwrap();
    let arb = geom.compound(".arbGeomParams").unwrap();
    let names: Vec<&str> = arb.members.iter().map(Property::name).collect();
    for expected in
        ["groom_width", "groom_id", "groom_guide", "groom_root_uv", "groom_color", "groom_wetness"]
    {
        assert!(names.contains(&expected), "{expected} missing from {names:?}");
    }
    assert!(names.iter().all(|n| n.starts_with("groom_")), "{names:?}");
    // Centimetres: positions and widths are 100× the metres.
    let p = geom.sampled("P").unwrap().read_f32(&archive.ogawa, 0).unwrap();
    assert!((p[3] - groom.points[1].x * 100.0).abs() < 1e-5);
    let w = arb.sampled("groom_width").unwrap().read_f32(&archive.ogawa, 0).unwrap();
    assert!((w[0] - groom.widths[0] * 100.0).abs() < 1e-9);

    // Read back: coif sees the spec version, converts to metres and restores canonical names.
    let back = read_groom(&out, &ImportOptions::default()).unwrap().groom;
    assert_eq!(back.strand_offsets, groom.strand_offsets);
    assert_eq!(back.strand_ids, groom.strand_ids);
    assert_eq!(back.guides, groom.guides);
    assert_eq!(back.root_uvs, groom.root_uvs);
    // The group id written for Unreal (one group: 0) reads back as the file's own.
    let names: Vec<&str> = back.attributes.iter().map(|a| a.name.as_str()).collect();
    let mut expected: Vec<&str> = groom.attributes.iter().map(|a| a.name.as_str()).collect();
    expected.push("groom_group_id");
    expected.sort();
    assert_eq!(names, expected);
    assert_eq!(back.attribute("groom_group_id").unwrap().floats()[..], vec![0.0; back.strand_count()]);
    for (a, b) in back.points.iter().zip(&groom.points) {
        assert!((*a - *b).length() < 1e-6);
    }
    for (a, b) in
        back.attribute("rest").unwrap().floats().iter().zip(groom.attribute("rest").unwrap().floats().iter())
    {
        assert!((a - b).abs() < 1e-6);
    }
    assert_eq!(back.attribute("wetness"), groom.attribute("wetness"));
}

#[test]
fn cli_converts_hair_to_alembic_and_back() {
    let dir = tempfile::tempdir().unwrap();
    let hair = dir.path().join("g.hair");
    let abc = dir.path().join("g.abc");
    let back = dir.path().join("back.hair");
    let run = coif(&["generate", "-o", path_str(&hair), "--strands", "50", "--vertices", "8"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(coif(&["convert", path_str(&hair), path_str(&abc)]).status.success());
    assert!(coif(&["convert", path_str(&abc), path_str(&back)]).status.success());
    let a = read_groom(&hair, &ImportOptions::default()).unwrap().groom;
    let b = read_groom(&back, &ImportOptions::default()).unwrap().groom;
    assert_eq!(a, b);
    let info = stdout_json(&coif(&["info", "--json", path_str(&abc)]));
    assert_eq!(info["format"], "alembic");
    assert_eq!(info["groom"]["strands"], 50);
}

#[test]
fn velocities_can_be_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("novel.abc");
    let base = full_groom();
    let options = AlembicWriteOptions { velocities: false, ..Default::default() };
    let mut writer = AnimationWriter::create(&path, &base, &options, true).unwrap();
    let frames: Vec<Groom> = (0..6).map(|f| frame(&base, f).0).collect();
    for f in &frames {
        writer.write_frame(f).unwrap();
    }
    writer.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let archive = Archive::open(&bytes).unwrap();
    let geom = archive.top.children[0].properties.compound(".geom").unwrap();
    assert!(geom.get(".velocities").is_none());
    assert_eq!(alembic::read_all_frames(&bytes, &path, false).unwrap(), frames);
    assert_eq!(geom.sampled("P").unwrap().num_samples, 6);
}

#[test]
fn an_xform_parent_is_written_and_applied_on_reading() {
    use glam::{DMat4, DVec3};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("xform.abc");
    let groom = full_groom();
    let matrix = DMat4::from_translation(DVec3::new(0.5, 1.0, -2.0)) * DMat4::from_rotation_x(0.3);
    let options = AlembicWriteOptions { xform: Some(matrix), ..Default::default() };
    alembic::write(&path, &groom, &options).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let archive = Archive::open(&bytes).unwrap();
    assert_eq!(archive.top.children[0].full_name, "/xform");
    assert_eq!(archive.top.children[0].children[0].full_name, "/xform/curves");
    let back = alembic::read(&bytes, &path, None, false).unwrap().0;
    for (got, p) in back.points.iter().zip(&groom.points) {
        let expected = matrix.transform_point3(p.as_dvec3()).as_vec3();
        assert!((*got - expected).length() < 1e-6, "{got} vs {expected}");
    }
    assert_eq!(back.widths, groom.widths);
}

/// Samples off the whole frames (Blender's motion-blur sub-samples at a ±0.25-frame shutter;
/// here a file sampled at frames 0.75, 1.75, …, 4.75) span whole frames 1 to 4: `info` and a
/// default `convert` go by those, each frame interpolated between the samples around it. The
/// range was the samples' own (0.75 to 4.75), so a convert wrote fractional time codes and
/// missed the last frame Blender exported.
#[test]
fn sub_frame_samples_span_the_whole_frames_between_them() {
    use coif::io::timeline::Timeline;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("blur.abc");
    let base = full_groom();
    let frames: Vec<Groom> = (0..5).map(|f| frame(&base, f).0).collect();
    let timeline = Timeline { first: 0.75, last: 4.75, frames_per_second: 24.0 };
    coif::io::write_frames(
        &path,
        std::path::Path::new("a groom cache"),
        &frames[0],
        frames[1..].iter().cloned().map(Ok),
        &timeline,
        &Default::default(),
    )
    .unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let archive = CurvesArchive::open(&bytes).unwrap();
    assert!((archive.frame_time(0) * 24.0 - 0.75).abs() < 1e-9, "the file's samples are off the frames");
    assert_eq!(archive.frame_range(), (1.0, 4.0));
    let out = dir.path().join("out.usda");
    let converted = coif(&["convert", path_str(&path), path_str(&out), "--json"]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    let report: serde_json::Value = serde_json::from_slice(&converted.stdout).unwrap();
    assert_eq!(
        (report["frames"]["first"].as_f64(), report["frames"]["last"].as_f64()),
        (Some(1.0), Some(4.0))
    );
    // Frame 2 lies a quarter of the way from the sample at 1.75 to the one at 2.75.
    let at = |frame: f64| {
        let options = ImportOptions { frame: Some(frame), ..Default::default() };
        read_groom(&out, &options).unwrap().groom.points
    };
    let expected: Vec<Vec3> =
        frames[1].points.iter().zip(&frames[2].points).map(|(a, b)| a.lerp(*b, 0.25)).collect();
    let got = at(2.0);
    assert!(got.iter().zip(&expected).all(|(a, b)| a.distance(*b) < 1e-6), "frame 2");
}
