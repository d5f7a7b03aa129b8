//! USD crate files (`.usdc`), read and written natively: no Python on the path of a user.
//!
//! Why our own module and not the `openusd` crate: 0.7/0.8 declare Rust 1.96 (these machines
//! have 1.95); 0.6.0 builds here and has a crate writer, but it is a 100k-line general USD
//! library (anyhow, logos, strum, derive_more, regex-lite…) whose reader indexes tables with
//! unchecked file data, `todo!()`s on chunked LZ4 and old versions, and sizes buffers from
//! counts in the file — a hostile file can panic it or make it allocate at will, and its values
//! go through a generic value enum (a copy of every array). coif needs a small, validated subset
//! that writes straight from the groom's arrays, like the Ogawa module.
//!
//! # Format (facts from USD's `crateFile.cpp` / `integerCoding.cpp`; all little-endian)
//!
//! - **Bootstrap** (88 bytes at 0): `PXR-USDC`, version bytes major/minor/patch (+5 unused),
//!   `u64` offset of the table of contents, 8 reserved `u64`.
//! - **TOC**: `u64` section count, then per section a 16-byte NUL-padded name, `u64` start and
//!   `u64` size. Sections: `TOKENS`, `STRINGS`, `FIELDS`, `FIELDSETS`, `PATHS`, `SPECS`.
//! - **TOKENS**: `u64` count, `u64` raw size, `u64` compressed size, LZ4 block of NUL-terminated
//!   strings. **STRINGS**: `u64` count, `u32` token index each.
//! - **FIELDS**: `u64` count, compressed `u32` token indices (the field names), then `u64` size +
//!   LZ4 block of one `u64` value representation per field.
//! - **FIELDSETS**: `u64` count, compressed `u32` field indices, each set ended by `u32::MAX`.
//! - **PATHS**: `u64` path count, `u64` node count, three compressed arrays over the path tree in
//!   depth-first order: path index, element token (negative: a property), jump (-2 no child or
//!   next sibling, -1 child only, 0 next sibling only, n > 0 child next and sibling n ahead).
//! - **SPECS**: `u64` count, three compressed `u32` arrays: path, field set, spec type.
//! - "Compressed" integers: `u64` size, then LZ4 of the integer coding: the most common delta
//!   (`i32`/`i64`), 2-bit codes per value (common, 8/16/32-bit delta; 16/32/64 for 64-bit),
//!   then the deltas. LZ4 framing: a byte 0 and one block, or n chunks each `i32` size + block.
//! - **Value representation** (`u64`): bit 63 array, 62 inline, 61 compressed, bits 48–55 type,
//!   48-bit payload. Inline: scalars of up to 4 bytes, doubles a float holds exactly, tokens and
//!   strings by index, vectors of small integers as `i8` components, matrices by an `i8`
//!   diagonal. Otherwise the payload is an offset: arrays are `u64` count + elements (version
//!   ≥ 0.7), int arrays of 16+ compressed, float arrays compressed as integers (`'i'`) or a lookup
//!   table (`'t'`); time samples are an `i64` jump to the times' representation (a double
//!   vector: `u64` count + `f64`s) followed by an `i64` jump to `u64` count + value reps.
//!
//! - **Composition fields**: list ops (`references`, `payload`, `inherits`, `variantSetNames`)
//!   are a header byte (bit 0 explicit; bits 1–6: explicit, added, deleted, ordered, prepended,
//!   appended items follow) and then those item vectors (`u64` count + items) in the order
//!   explicit, added, prepended, appended, deleted, ordered. A reference is a string index
//!   (asset), a path index (prim), a layer offset (two `f64`: offset, scale) and a dictionary
//!   (`u64` count, then a string index and an 8-byte jump per entry); a payload has no
//!   dictionary and, before 0.8, no offset. `variantSelection` is `u64` count + string-index
//!   pairs; `subLayers` a string vector with `subLayerOffsets` beside it. Variant bodies are
//!   `Variant` specs at paths whose last element is `{set=variant}`.
//!
//! The writer emits version 0.8.0 (what usd-core writes); the reader accepts 0.4.0 to 0.12.x.
//! Reading builds the same layer model as the `.usda` parser, arcs included, so both formats
//! give the same groom and `io::usd_compose` composes either — no Python is ever started for a
//! crate file. A groom read leaves plain `points` and `widths` arrays in the file until the
//! groom's arrays are sized, then reads each prim's into its place: one copy, from the file,
//! however many prims (a composed file decodes every value first, as `.usda` does).
mod compress;
mod decode;
mod encode;
mod format;
pub(crate) mod write;

use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::groom::Groom;
use crate::io::{atomic, usd_stage, usda, ImportOptions};

pub use decode::ReadOutcome;

pub use format::MAGIC;

/// Writes one groom as a crate file, atomically.
pub fn write(path: &Path, groom: &Groom) -> Result<()> {
    write_stage(path, &usd_stage::plan(groom, None)?)
}

/// Writes a groom whose points move: frame `k` at time code `times.start + k`.
pub fn write_animated(
    path: &Path,
    groom: &Groom,
    frames: &[Vec<Vec3>],
    times: usda::TimeCodes,
) -> Result<()> {
    let animation = usd_stage::Animation::of_points(times, frames);
    usd_stage::check_animation(groom, &animation, path)?;
    write_stage(path, &usd_stage::plan(groom, Some(&animation))?)
}

/// Writes a planned stage as a crate file, atomically.
pub fn write_stage(path: &Path, stage: &usd_stage::Stage) -> Result<()> {
    let out = atomic::create_beside(path)?;
    let out = write::encode(stage, out).map_err(|e| Error::io(path, e))?;
    atomic::commit(path, out)
}

/// Reads crate-file bytes into a groom (metres, Y up), or the layer when it needs composition.
pub fn read(bytes: &[u8], path: &Path, options: &ImportOptions, time: Option<f64>) -> Result<ReadOutcome> {
    decode::read(bytes, None, path, options, time)
}

/// The timeline metadata of a crate file's layer (no prim is decoded).
pub fn read_timeline(bytes: &[u8], path: &Path) -> Result<usda::LayerTimeline> {
    decode::read_timeline(bytes, path)
}

/// The layer model of crate-file bytes (each time-sampled value at its first sample), arcs
/// recorded, not resolved.
pub(crate) fn read_layer(bytes: &[u8], path: &Path) -> Result<usda::Layer> {
    decode::read_layer(bytes, None, path, None)
}

/// Whether a crate file's stage (composed, if it needs composition) time-samples anything that
/// places its curves or meshes.
pub fn is_animated(bytes: &[u8], path: &Path) -> Result<Option<bool>> {
    let mut layer = read_layer(bytes, path)?;
    if layer.composes() {
        layer = crate::io::usd_compose::compose(layer, path, &Default::default())?;
    }
    Ok(Some(usda::places_with_time_samples(&layer)))
}

/// The layer model of a crate file, composition arcs recorded, not resolved.
pub(crate) fn read_layer_file(path: &Path, time: Option<f64>) -> Result<usda::Layer> {
    with_file(path, |bytes, file| decode::read_layer(bytes, file, path, time))
}

/// Reads a crate file: the structure through a map, large arrays straight from the file.
pub fn read_file(path: &Path, options: &ImportOptions, time: Option<f64>) -> Result<ReadOutcome> {
    with_file(path, |bytes, file| decode::read(bytes, file, path, options, time))
}

/// Errors of a groom read from composed layers carry no line (they name the prim).
pub(crate) use decode::unline;

/// Runs `read` over the file's bytes (mapped) and the file itself.
fn with_file<T>(path: &Path, read: impl FnOnce(&[u8], Option<&std::fs::File>) -> Result<T>) -> Result<T> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let empty = file.metadata().map_err(|e| Error::io(path, e))?.len() == 0;
    if empty {
        return read(&[], None);
    }
    // SAFETY: read-only map; every offset is checked against its length, and coif replaces
    // files by renaming, never truncating them in place (as for `input::map_file`).
    let map = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| Error::io(path, e))?;
    read(&map, Some(&file))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::groom::{CurveBasis, CurveWrap};
    use crate::groups::{CurveGroup, Interpolation};

    /// Two groups: per-vertex widths of all-different values (a plain array the read leaves in
    /// the file) and uniform ones (decoded with the layer).
    fn two_groups() -> Groom {
        let part = |strands: usize, name: &str, uniform: bool| {
            let lines: Vec<Vec<Vec3>> = (0..strands)
                .map(|s| {
                    (0..5).map(|k| Vec3::new(s as f32 * 0.37, k as f32 * 0.011, 0.25 - s as f32)).collect()
                })
                .collect();
            let mut groom = Groom::from_strands(&lines, 0.0);
            groom.widths = (0..groom.points.len())
                .map(|v| if uniform { 2e-4 + (v / 5) as f32 * 1e-6 } else { 1e-4 + v as f32 * 1.3e-7 })
                .collect();
            let mut group = CurveGroup::new(name, CurveBasis::Linear, CurveWrap::Nonperiodic);
            group.width_interpolation = uniform.then_some(Interpolation::Uniform);
            groom.set_single_group(group);
            groom
        };
        Groom::concat(vec![part(3, "/Groom/A", false), part(4, "/Groom/B", true), part(2, "/Groom/C", false)])
            .unwrap()
    }

    #[test]
    fn points_and_widths_read_into_place_from_the_file_or_its_bytes_equal_the_usda_reading() {
        let groom = two_groups();
        let dir = tempfile::tempdir().unwrap();
        let (usdc, usda) = (dir.path().join("g.usdc"), dir.path().join("g.usda"));
        write(&usdc, &groom).unwrap();
        let mut text = Vec::new();
        usda::write(&groom, &mut text).unwrap();
        let groom_of = |outcome: ReadOutcome| match outcome {
            ReadOutcome::Groom(groom, _) => groom,
            ReadOutcome::NeedsComposition(_) => panic!("nothing to compose"),
        };
        let options = ImportOptions::default();
        let from_file = groom_of(read_file(&usdc, &options, None).unwrap());
        let bytes = std::fs::read(&usdc).unwrap();
        let from_bytes = groom_of(read(&bytes, &usdc, &options, None).unwrap());
        let from_text = groom_of(usda::read(text.as_slice(), &usda, &options, None).unwrap());
        for read in [&from_file, &from_bytes] {
            assert_eq!(*read, from_text);
            assert_eq!(read.points, groom.points);
            assert_eq!(read.widths, groom.widths);
            assert_eq!(read.strand_offsets, groom.strand_offsets);
            let names: Vec<&str> = read.groups.iter().map(|g| g.name.as_str()).collect();
            assert_eq!(names, ["/Groom/A", "/Groom/B", "/Groom/C"]);
        }
    }
}
