//! Byte-level checks against the worked example of the Alembic format note (§7): a file the
//! reference C++ library writes for two linear curves with per-vertex widths. coif writing the
//! same data must produce the same 1158 bytes (layout, sample keys, metadata table, hashes).
use std::io::Cursor;

use coif::io::alembic::curves_write::{write_static, AlembicWriteOptions};
use coif::io::alembic::{CurvesArchive, MAGIC};
use coif::Groom;
use glam::Vec3;

fn golden() -> Vec<u8> {
    let text = include_str!("data/alembic_worked_example.hex");
    let hex: String = text.lines().map(|l| l.split_once(':').unwrap().1.replace(' ', "")).collect();
    (0..hex.len()).step_by(2).map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap()).collect()
}

fn example_groom() -> Groom {
    let strand = |x: f32| vec![Vec3::new(x, 0.0, 0.0), Vec3::new(x, 1.0, 0.0), Vec3::new(x, 2.0, 0.0)];
    let mut groom = Groom::from_strands(&[strand(0.0), strand(1.0)], 0.0);
    groom.widths = vec![0.25, 0.125, 0.0625, 0.25, 0.125, 0.0625];
    groom
}

fn example_options() -> AlembicWriteOptions {
    AlembicWriteOptions { application: "groom-proto".into(), ..Default::default() }
}

#[test]
fn writes_the_worked_example_byte_for_byte() {
    let expected = golden();
    assert_eq!(expected.len(), 1158);
    let written =
        write_static(Cursor::new(Vec::new()), &example_groom(), &example_options()).unwrap().into_inner();
    assert_eq!(written.len(), expected.len(), "file size");
    // Name the first differing offset, so a failure says which block is wrong.
    if let Some(at) = written.iter().zip(&expected).position(|(a, b)| a != b) {
        panic!(
            "first difference at offset {at}: wrote {:02x?}, expected {:02x?}",
            &written[at..(at + 16).min(written.len())],
            &expected[at..(at + 16).min(expected.len())]
        );
    }
}

#[test]
fn reads_the_worked_example() {
    let bytes = golden();
    assert!(bytes.starts_with(MAGIC));
    let archive = CurvesArchive::open(&bytes).unwrap();
    assert_eq!(archive.frame_count(), 1);
    let groom = archive.read_frame(0).unwrap();
    assert_eq!(groom, example_groom());
}

#[test]
fn worked_example_landmarks() {
    // Independent of the writer: offsets and words the note's table lists.
    let bytes = golden();
    let u64_at = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
    assert_eq!(&bytes[..8], b"Ogawa\xff\x00\x01");
    assert_eq!(u64_at(8), 1102, "root group offset");
    assert_eq!(u64_at(1102), 6, "the root has six children");
    // `.geom` headers: the first header word is .selfBnds, scalar f64×6, constant, metadata 1.
    assert_eq!(u32::from_le_bytes(bytes[428..432].try_into().unwrap()), 0x0010_6CB1);
}
