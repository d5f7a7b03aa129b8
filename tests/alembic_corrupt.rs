//! Corrupt and truncated Alembic files are bad input: exit code 2 and a message naming the file,
//! never a panic, a hang or a runaway allocation. Corruptions are made at known offsets of the
//! format note's worked example (§7), whose block table gives every offset used here.
mod common;
use common::*;

use coif::io::alembic;
use proptest::prelude::*;

fn golden() -> Vec<u8> {
    let text = include_str!("data/alembic_worked_example.hex");
    let hex: String = text.lines().map(|l| l.split_once(':').unwrap().1.replace(' ', "")).collect();
    (0..hex.len()).step_by(2).map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap()).collect()
}

fn put_u64(bytes: &mut [u8], at: usize, value: u64) {
    bytes[at..at + 8].copy_from_slice(&value.to_le_bytes());
}

const DATA: u64 = 1 << 63;

/// Runs `coif info` on the bytes; asserts exit code 2 and that the message names the file.
fn assert_rejected(bytes: &[u8], what: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("corrupt.abc");
    std::fs::write(&path, bytes).unwrap();
    let out = coif(&["info", path_str(&path)]);
    let message = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{what}: {message}");
    assert!(message.contains("corrupt.abc"), "{what}: message does not name the file: {message}");
    assert!(!message.contains("panicked"), "{what}: {message}");
    message
}

#[test]
fn the_uncorrupted_example_reads() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ok.abc");
    std::fs::write(&path, golden()).unwrap();
    let info = stdout_json(&coif(&["info", "--json", path_str(&path)]));
    assert_eq!(info["groom"]["strands"], 2);
    assert_eq!(info["groom"]["vertices"], 6);
}

#[test]
fn bad_magic_version_and_unfrozen_files() {
    let mut bytes = golden();
    bytes[0] = b'o';
    assert_rejected(&bytes, "bad magic");
    let mut bytes = golden();
    bytes[7] = 2;
    assert!(assert_rejected(&bytes, "version").contains("version"));
    let mut bytes = golden();
    bytes[5] = 0;
    assert!(assert_rejected(&bytes, "unfrozen").contains("closed cleanly"));
}

#[test]
fn offsets_past_the_end() {
    let mut bytes = golden();
    put_u64(&mut bytes, 8, 1 << 40); // root group
    assert_rejected(&bytes, "root offset");
    let mut bytes = golden();
    put_u64(&mut bytes, 340, 5000 | DATA); // P's sample block
    assert_rejected(&bytes, "sample offset");
    let mut bytes = golden();
    put_u64(&mut bytes, 1102 + 8 + 2 * 8, 1158 - 4); // top object group straddling the end
    assert_rejected(&bytes, "group at the end");
}

#[test]
fn cyclic_and_shared_groups() {
    let mut bytes = golden();
    // `.geom` (group at 499): its first property points back at the object's top compound (613).
    put_u64(&mut bytes, 507, 613);
    assert!(assert_rejected(&bytes, "cycle").contains("twice"));
    let mut bytes = golden();
    put_u64(&mut bytes, 507, 499); // a group listing itself
    assert_rejected(&bytes, "self reference");
    let mut bytes = golden();
    // The curves object (637) lists the top object's group (712) as its properties.
    put_u64(&mut bytes, 645, 712);
    assert_rejected(&bytes, "object cycle");
}

#[test]
fn counts_overrunning_the_data() {
    let mut bytes = golden();
    bytes[236] = 4; // nVertices = [3, 4] for 6 points
    assert!(assert_rejected(&bytes, "nVertices").contains("nVertices"));
    let mut bytes = golden();
    put_u64(&mut bytes, 1102, 1 << 40); // the root claims 2^40 children
    assert_rejected(&bytes, "group count");
    let mut bytes = golden();
    put_u64(&mut bytes, 420, 10_000); // `.geom` headers block claims more bytes than follow it
    assert_rejected(&bytes, "headers size");
    let mut bytes = golden();
    bytes[448] = 0x70; // P's name length of 112 runs past the headers block
    assert_rejected(&bytes, "name length");
    let mut bytes = golden();
    put_u64(&mut bytes, 112, 95); // P's 18 floats become 79 bytes: not whole elements
    assert_rejected(&bytes, "ragged sample");
}

#[test]
fn absurd_sizes() {
    let mut bytes = golden();
    put_u64(&mut bytes, 112, u64::MAX); // P's data size
    assert_rejected(&bytes, "data size");
    let mut bytes = golden();
    // The time sampling table's stored-time count (779 + 8 + 4 + 8) claims 2^32 − 1 times.
    bytes[799..803].copy_from_slice(&u32::MAX.to_le_bytes());
    assert_rejected(&bytes, "time count");
    let mut bytes = golden();
    // P's header (info word at 443 in the `.geom` block) says 255 changing samples, but one is
    // stored: asking for every frame must fail cleanly.
    assert_eq!(bytes[443..448], [0xa2, 0x38, 0x20, 0x00, 0x01]);
    bytes[444] = 0x30; // drop P's "constant" bit: first = 1, last = 254
    bytes[447] = 255;
    let path = std::path::Path::new("absurd.abc");
    assert!(alembic::read_all_frames(&bytes, path, false).is_err());
}

#[test]
fn every_truncation_is_an_error() {
    let bytes = golden();
    let path = std::path::Path::new("truncated.abc");
    for len in 0..bytes.len() {
        assert!(alembic::read(&bytes[..len], path, None, false).is_err(), "truncated to {len} bytes");
    }
    assert_rejected(&bytes[..700], "truncated");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, ..ProptestConfig::default() })]

    /// Random byte edits never panic: the reader returns a groom or an error.
    #[test]
    fn random_corruption_never_panics(edits in prop::collection::vec((0usize..1158, any::<u8>()), 1..8)) {
        let mut bytes = golden();
        for (at, value) in edits {
            bytes[at] = value;
        }
        let path = std::path::Path::new("fuzzed.abc");
        let _ = alembic::read(&bytes, path, None, false);
        let _ = alembic::read_all_frames(&bytes, path, false);
    }
}
