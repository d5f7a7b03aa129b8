//! Corrupt, truncated and hostile crate files are bad input: exit code 2 and a message naming
//! the file and the part of it that is wrong, never a panic, a hang or a runaway allocation.
//! Corruptions are made at offsets found through the file's own table of contents (layout in
//! `src/io/usdc/mod.rs`).
mod common;
use common::usd::rich_groom;
use common::*;

use coif::groom::CurveBasis;
use glam::Vec3;
use proptest::prelude::*;
use std::path::Path;

/// A small animated crate file coif wrote (so it holds arrays, compressed ints, time samples).
fn sample() -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("ok.usdc");
    let groom = rich_groom(CurveBasis::Linear);
    let frames = vec![groom.points.clone(), groom.points.iter().map(|p| *p + Vec3::Y).collect()];
    coif::io::write_animated(&path, &groom, &frames, &[], 24.0, &Default::default()).unwrap();
    std::fs::read(path).unwrap()
}

fn u64_at(bytes: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap())
}

fn put_u64(bytes: &mut [u8], at: usize, value: u64) {
    bytes[at..at + 8].copy_from_slice(&value.to_le_bytes());
}

/// Start of a section, from the table of contents.
fn section(bytes: &[u8], name: &str) -> usize {
    let toc = u64_at(bytes, 16) as usize;
    let count = u64_at(bytes, toc) as usize;
    (0..count)
        .map(|i| toc + 8 + 32 * i)
        .find(|&entry| bytes[entry..entry + 16].split(|&b| b == 0).next() == Some(name.as_bytes()))
        .map(|entry| u64_at(bytes, entry + 16) as usize)
        .unwrap_or_else(|| panic!("no {name} section"))
}

/// Reads in-process: the result must be a groom or a bad-input error naming the file.
fn read(bytes: &[u8]) -> Result<(), String> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("corrupt.usdc");
    std::fs::write(&path, bytes).unwrap();
    for time in [None, Some(1.5)] {
        let selection = coif::io::usda::Selection { time, variants: vec![] };
        if let Err(error) = coif::io::read_groom_selected(&path, &Default::default(), &selection) {
            let message = error.to_string();
            assert_eq!(error.exit_code(), 2, "{message}");
            assert!(message.contains("corrupt.usdc"), "the message names the file: {message}");
            return Err(message);
        }
    }
    Ok(())
}

/// Runs `coif info` on the bytes; asserts exit code 2, the file and `what` in the message.
fn assert_rejected(bytes: &[u8], what: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("corrupt.usdc");
    std::fs::write(&path, bytes).unwrap();
    let out = coif(&["info", path_str(&path)]);
    let message = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{what}: {message}");
    assert!(message.contains("corrupt.usdc"), "{what}: message does not name the file: {message}");
    assert!(message.contains(what), "message does not name {what}: {message}");
    assert!(!message.contains("panicked"), "{message}");
}

#[test]
fn the_sample_reads() {
    assert_eq!(read(&sample()), Ok(()));
}

#[test]
fn every_truncation_is_an_error() {
    let bytes = sample();
    for len in (0..bytes.len()).step_by(7).chain([bytes.len() - 1]) {
        assert!(read(&bytes[..len]).is_err(), "truncated to {len} of {} bytes", bytes.len());
    }
    assert_rejected(&bytes[..40], "bootstrap");
    assert_rejected(&bytes[..bytes.len() - 10], "TOC");
}

#[test]
fn bad_magic_version_and_toc_offset() {
    let mut bytes = sample();
    bytes[0] = b'Q';
    assert_rejected(&bytes, "not a USD crate file");
    let mut bytes = sample();
    bytes[9] = 99;
    assert_rejected(&bytes, "version");
    let mut bytes = sample();
    put_u64(&mut bytes, 16, u64::MAX - 3);
    assert_rejected(&bytes, "table of contents offset");
}

#[test]
fn huge_counts_are_refused_before_allocating() {
    let sections = [
        ("TOKENS", 0, "TOKENS"),
        ("TOKENS", 8, "TOKENS"),
        ("STRINGS", 0, "STRINGS"),
        ("FIELDS", 0, "FIELDS"),
        ("FIELDSETS", 0, "FIELDSETS"),
        ("PATHS", 0, "PATHS"),
        ("PATHS", 8, "PATHS"),
        ("SPECS", 0, "SPECS"),
    ];
    for (name, field, what) in sections {
        for count in [u64::MAX, 1 << 62, 1 << 40, 1 << 31] {
            let mut bytes = sample();
            let at = section(&bytes, name) + field;
            put_u64(&mut bytes, at, count);
            assert_rejected(&bytes, what);
        }
    }
    // The points' array count: the first array after the bootstrap is curveVertexCounts (ints,
    // compressed from 16); find a float array by its count instead.
    let groom = rich_groom(CurveBasis::Linear);
    let bytes = sample();
    let count = (groom.vertex_count() as u64).to_le_bytes();
    let at = bytes.windows(8).position(|w| w == count).expect("an array of the vertex count");
    let mut hostile = bytes.clone();
    put_u64(&mut hostile, at, 1 << 45);
    assert!(read(&hostile).unwrap_err().contains("larger than the file"));
}

#[test]
fn section_offsets_outside_the_file() {
    let bytes = sample();
    let toc = u64_at(&bytes, 16) as usize;
    for i in 0..6 {
        let mut hostile = bytes.clone();
        put_u64(&mut hostile, toc + 8 + 32 * i + 16, bytes.len() as u64 - 4);
        assert_rejected(&hostile, "outside the file");
        let mut hostile = bytes.clone();
        put_u64(&mut hostile, toc + 8 + 32 * i + 24, u64::MAX);
        assert_rejected(&hostile, "outside the file");
    }
    let mut hostile = bytes.clone();
    put_u64(&mut hostile, toc, 1 << 50);
    assert_rejected(&hostile, "TOC");
}

#[test]
fn bad_lz4_is_an_error() {
    let bytes = sample();
    // TOKENS: count, raw size, compressed size, then the chunk byte and the LZ4 block.
    let blob = section(&bytes, "TOKENS") + 24;
    let mut hostile = bytes.clone();
    hostile[blob] = 200;
    assert_rejected(&hostile, "TOKENS");
    let mut hostile = bytes.clone();
    hostile[blob + 1] = 0xff;
    hostile[blob + 2] = 0xff;
    assert_rejected(&hostile, "TOKENS");
    let fields = section(&bytes, "FIELDS") + 16;
    let mut hostile = bytes.clone();
    hostile[fields + 1..fields + 5].copy_from_slice(&[0xf0, 0xff, 0xff, 0xff]);
    assert_rejected(&hostile, "FIELDS");
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, ..ProptestConfig::default() })]

    /// Random bit flips and overwritten words anywhere: a groom or a clean error.
    #[test]
    fn flipped_bits_never_panic(flips in prop::collection::vec((any::<usize>(), 0u8..8), 1..4),
                                word in any::<(usize, u64)>()) {
        let mut bytes = sample_cached().to_vec();
        for (at, bit) in flips {
            let at = at % bytes.len();
            bytes[at] ^= 1 << bit;
        }
        let _ = read(&bytes);
        let mut bytes = sample_cached().to_vec();
        let at = word.0 % (bytes.len() - 8);
        put_u64(&mut bytes, at, word.1);
        let _ = read(&bytes);
    }
}

fn sample_cached() -> &'static [u8] {
    static SAMPLE: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    SAMPLE.get_or_init(sample)
}

#[test]
fn a_crate_file_with_a_wrong_extension_is_still_read_by_its_magic() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("groom.bin");
    std::fs::write(&path, sample()).unwrap();
    let loaded = coif::io::read_groom(Path::new(&path), &Default::default()).unwrap();
    assert_eq!(loaded.format, coif::io::Format::Usdc);
}

#[test]
fn an_empty_usdc_is_bad_input() {
    assert_rejected(&[], "bootstrap");
}
