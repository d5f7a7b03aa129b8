//! Cem Yuksel `.hair`: exact round trips, and malformed files rejected with exit code 2, a message
//! naming the problem, and no output file.
mod common;
use common::*;

use coif::groom::{attr, Attribute, AttributeRate, Groom};
use glam::Vec3;

fn sample_groom() -> Groom {
    let strands: Vec<Vec<Vec3>> = (0..5)
        .map(|s| {
            (0..(3 + s)).map(|k| Vec3::new(s as f32 * 0.01, -(k as f32) * 0.02, 0.001 * k as f32)).collect()
        })
        .collect();
    let mut groom = Groom::from_strands(&strands, 70e-6);
    for (i, w) in groom.widths.iter_mut().enumerate() {
        *w = 60e-6 + i as f32 * 1e-7;
    }
    let n = groom.vertex_count();
    groom.set_attribute(Attribute::new(
        attr::COLOR,
        AttributeRate::Vertex,
        3,
        (0..3 * n).map(|i| i as f32 / 100.0).collect(),
    ));
    groom.set_attribute(Attribute::new(
        attr::TRANSPARENCY,
        AttributeRate::Vertex,
        1,
        (0..n).map(|i| i as f32 / 50.0).collect(),
    ));
    groom
}

#[test]
fn write_read_is_exact_and_rewrite_is_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let first = dir.path().join("a.hair");
    let groom = sample_groom();
    coif::io::write_groom(&first, &groom).unwrap();
    let read = coif::io::read_groom(&first, &Default::default()).unwrap().groom;
    assert_eq!(read, groom);

    let second = dir.path().join("b.hair");
    let converted = coif(&["convert", path_str(&first), path_str(&second)]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    assert_eq!(std::fs::read(&first).unwrap(), std::fs::read(&second).unwrap());
}

#[test]
fn uniform_arrays_round_trip_through_header_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("u.hair");
    let strands = vec![vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)]; 4]
        .into_iter()
        .enumerate()
        .map(|(i, s)| s.into_iter().map(|p| p + Vec3::Z * i as f32).collect::<Vec<_>>())
        .collect::<Vec<_>>();
    let groom = Groom::from_strands(&strands, 5e-5);
    coif::io::write_groom(&path, &groom).unwrap();
    // Header only plus points: no segments or thickness arrays.
    assert_eq!(std::fs::metadata(&path).unwrap().len(), 128 + 12 * 12);
    assert_eq!(coif::io::read_groom(&path, &Default::default()).unwrap().groom, groom);
}

#[test]
fn units_and_up_axis_are_converted_on_import() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cm.hair");
    let groom = Groom::from_strands(&[vec![Vec3::ZERO, Vec3::new(1.0, 2.0, 30.0)]], 0.008);
    coif::io::write_groom(&path, &groom).unwrap();
    let options = coif::io::ImportOptions {
        meters_per_unit: Some(0.01),
        up_axis: Some(coif::io::UpAxis::Z),
        ..Default::default()
    };
    let read = coif::io::read_groom(&path, &options).unwrap().groom;
    assert!(read.points[1].distance(Vec3::new(0.01, 0.30, -0.02)) < 1e-6, "{:?}", read.points[1]);
    assert!((read.widths[0] - 0.00008).abs() < 1e-9);
}

/// A valid little file to corrupt: 2 strands of 3 points, with a segments array.
fn valid_bytes() -> Vec<u8> {
    let mut bytes = Vec::new();
    bytes.extend_from_slice(b"HAIR");
    bytes.extend_from_slice(&2u32.to_le_bytes()); // strands
    bytes.extend_from_slice(&6u32.to_le_bytes()); // points
    bytes.extend_from_slice(&(1u32 | 2).to_le_bytes()); // segments + points
    bytes.extend_from_slice(&2u32.to_le_bytes()); // default segments
    bytes.extend_from_slice(&1e-4f32.to_le_bytes());
    bytes.extend_from_slice(&0f32.to_le_bytes());
    for _ in 0..3 {
        bytes.extend_from_slice(&0f32.to_le_bytes());
    }
    bytes.resize(128, 0);
    bytes.extend_from_slice(&2u16.to_le_bytes());
    bytes.extend_from_slice(&2u16.to_le_bytes());
    for i in 0..6 {
        for c in [i as f32 * 0.01, -(i % 3) as f32 * 0.05, 0.0] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    bytes
}

fn set_u32(bytes: &mut [u8], at: usize, value: u32) {
    bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
}

#[test]
fn the_valid_fixture_reads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ok.hair");
    std::fs::write(&path, valid_bytes()).unwrap();
    let info = stdout_json(&coif(&["info", "--json", path_str(&path)]));
    assert_eq!(info["groom"]["strands"], 2);
    assert_eq!(info["groom"]["vertices"], 6);
}

#[test]
fn malformed_files_exit_2_with_a_clear_message_and_no_output() {
    let mut cases: Vec<(&str, Vec<u8>, &str)> = Vec::new();
    cases.push(("empty file", Vec::new(), "truncated header"));
    cases.push(("half a header", valid_bytes()[..60].to_vec(), "truncated header"));
    let mut b = valid_bytes();
    b[..4].copy_from_slice(b"HAIX");
    cases.push(("wrong signature", b, "signature"));
    let b = valid_bytes();
    cases.push(("truncated points", b[..b.len() - 7].to_vec(), "truncated"));
    let mut b = valid_bytes();
    set_u32(&mut b, 8, 1_000_000);
    cases.push(("point count overruns the file", b, "truncated"));
    let mut b = valid_bytes();
    set_u32(&mut b, 4, u32::MAX);
    set_u32(&mut b, 8, u32::MAX);
    cases.push(("absurd counts", b, "need"));
    let mut b = valid_bytes();
    b[130..132].copy_from_slice(&3u16.to_le_bytes());
    cases.push(("segments disagree with points", b, "segment counts"));
    let mut b = valid_bytes();
    b[128..130].copy_from_slice(&0u16.to_le_bytes());
    b[130..132].copy_from_slice(&4u16.to_le_bytes());
    cases.push(("strand with no segment", b, "strand 0 has 0 segments"));
    let mut b = valid_bytes();
    set_u32(&mut b, 12, 0x42);
    cases.push(("unknown flags", b, "unknown array flags"));
    let mut b = valid_bytes();
    set_u32(&mut b, 12, 1);
    cases.push(("no points array", b, "no points"));
    let mut b = valid_bytes();
    let at = 128 + 4 + 12 * 4;
    b[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    cases.push(("NaN coordinate", b, "strand 1, vertex 1"));
    let mut b = valid_bytes();
    b.extend_from_slice(&[0; 5]);
    cases.push(("trailing garbage", b, "unexpected bytes"));

    for (what, bytes, expected) in cases {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("bad.hair");
        std::fs::write(&input, &bytes).unwrap();
        let output = dir.path().join("out.hair");
        let result = coif(&["convert", path_str(&input), path_str(&output)]);
        let message = stderr(&result);
        assert_eq!(result.status.code(), Some(2), "{what}: {message}");
        assert!(message.contains(expected), "{what}: message {message:?} lacks {expected:?}");
        assert!(message.contains("bad.hair"), "{what}: message {message:?} does not name the file");
        assert_eq!(dir_listing(dir.path()), vec!["bad.hair"], "{what}: output left behind");
    }
}
