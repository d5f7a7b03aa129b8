//! The planned stage (`io::usd_stage`) as USD text. Large arrays are formatted in fixed-size
//! chunks on all threads and written in order, so the output is the same at any thread count and
//! memory stays bounded. Floats are written in their shortest form that reads back to the same
//! `f32` (`io::usda::spell`, zmij's spelling), integers with `itoa`.
use std::io::Write;
use std::path::Path;

use glam::Vec3;
use rayon::prelude::*;

use super::spell::{self, WINDOW};
use crate::error::{Error, Result};
use crate::groom::{AttributeKind, Groom};
use crate::io::usd_stage::{self, Data, Prim, Property, Stage, TimeCodes, Value};

/// Text formatted per task, about: large enough that the buffered file takes it without a
/// copy into its 1 MB buffer.
const CHUNK_BYTES: usize = 2 << 20;

/// Writes a groom as one stage with default (untimed) values.
pub fn write(groom: &Groom, out: &mut dyn Write) -> std::io::Result<()> {
    let stage = usd_stage::plan(groom, None).map_err(std::io::Error::other)?;
    write_stage(&stage, out)
}

/// Writes a groom whose points move: `frames[k]` holds every point at time code
/// `times.start + k` (same topology as `groom`, whose other data is written once).
pub fn write_animated(
    groom: &Groom,
    frames: &[Vec<Vec3>],
    times: TimeCodes,
    out: &mut dyn Write,
    path: &Path,
) -> Result<()> {
    let animation = usd_stage::Animation::of_points(times, frames);
    usd_stage::check_animation(groom, &animation, path)?;
    let stage = usd_stage::plan(groom, Some(&animation))?;
    write_stage(&stage, out).map_err(|e| Error::io(path, e))
}

/// Writes a planned stage.
pub fn write_stage(stage: &Stage, out: &mut (impl Write + ?Sized)) -> std::io::Result<()> {
    let mut head = String::new();
    head.push_str("#usda 1.0\n(\n    defaultPrim = \"");
    head.push_str(&stage.default_prim);
    head.push_str("\"\n    doc = \"");
    head.push_str(&stage.doc);
    head.push_str("\"\n");
    if let Some(t) = stage.times {
        head.push_str("    endTimeCode = ");
        push_f64(&mut head, t.end);
        head.push('\n');
    }
    head.push_str("    metersPerUnit = ");
    push_number(&mut head, stage.meters_per_unit);
    head.push('\n');
    if let Some(t) = stage.times {
        head.push_str("    startTimeCode = ");
        push_f64(&mut head, t.start);
        head.push_str("\n    timeCodesPerSecond = ");
        push_f64(&mut head, t.per_second);
        head.push('\n');
    }
    head.push_str("    upAxis = \"");
    head.push_str(stage.up_axis);
    head.push_str("\"\n)\n\n");
    out.write_all(head.as_bytes())?;
    for prim in &stage.roots {
        write_prim(prim, out, 0)?;
    }
    Ok(())
}

fn write_prim(prim: &Prim, out: &mut (impl Write + ?Sized), depth: usize) -> std::io::Result<()> {
    let indent = "    ".repeat(depth);
    out.write_all(format!("{indent}def {} \"{}\"\n{indent}{{\n", prim.type_name, prim.name).as_bytes())?;
    let inner = format!("{indent}    ");
    for property in &prim.properties {
        write_property(property, out, &inner)?;
    }
    for child in &prim.children {
        write_prim(child, out, depth + 1)?;
    }
    out.write_all(format!("{indent}}}\n").as_bytes())?;
    if depth == 0 {
        out.write_all(b"\n")?;
    }
    Ok(())
}

fn write_property(property: &Property, out: &mut (impl Write + ?Sized), indent: &str) -> std::io::Result<()> {
    let uniform = if property.uniform { "uniform " } else { "" };
    let declaration = format!("{indent}{uniform}{} {}", property.type_name, property.name);
    // Fields in the order usd-core writes them.
    let mut fields = Vec::new();
    if let Some(size) = property.element_size {
        fields.push(format!("{indent}    elementSize = {size}\n"));
    }
    if let Some(interpolation) = property.interpolation {
        fields.push(format!("{indent}    interpolation = \"{interpolation}\"\n"));
    }
    let metadata = (!fields.is_empty()).then(|| format!(" (\n{}{indent})", fields.concat()));
    match &property.value {
        Value::Default(data) => {
            out.write_all(format!("{declaration} = ").as_bytes())?;
            write_data(data, out)?;
            out.write_all(metadata.unwrap_or_default().as_bytes())?;
        }
        Value::TimeSamples(samples) => {
            // Metadata goes on a declaration of its own: a `.timeSamples` line takes none.
            if let Some(metadata) = metadata {
                out.write_all(format!("{declaration}{metadata}\n").as_bytes())?;
            }
            out.write_all(format!("{declaration}.timeSamples = {{\n").as_bytes())?;
            for (time, data) in samples {
                let mut label = format!("{indent}    ");
                push_f64(&mut label, *time);
                label.push_str(": ");
                out.write_all(label.as_bytes())?;
                write_data(data, out)?;
                out.write_all(b",\n")?;
            }
            out.write_all(format!("{indent}}}").as_bytes())?;
        }
    }
    out.write_all(b"\n")
}

fn write_data(data: &Data, out: &mut (impl Write + ?Sized)) -> std::io::Result<()> {
    let stateless = || ();
    match data {
        Data::Token(token) => out.write_all(format!("\"{token}\"").as_bytes()),
        Data::Ints { values, components: 1 } => write_array(out, values, stateless, |(), text, &v| {
            text.push_fixed(SEPARATOR);
            text.push_int(v);
        }),
        Data::Ints { values, components } => {
            let tuples: Vec<&[i32]> = values.chunks_exact(*components).collect();
            write_array(out, &tuples, stateless, |(), text, t| {
                text.push_fixed(SEPARATOR);
                push_tuple(text, t, |text, &v| text.push_int(v));
            })
        }
        // A `uint64`'s bits read unsigned (see `AttributeKind::UInt64`).
        Data::WideInts { values, kind } => write_array(out, values, stateless, |(), text, &v| {
            text.push_fixed(SEPARATOR);
            match kind {
                AttributeKind::UInt64 => text.push_int(v as u64),
                _ => text.push_int(v),
            }
        }),
        Data::Bools(values) => write_array(out, values, stateless, |(), text, &v| {
            text.push_fixed(if v { b", 1" } else { b", 0" });
        }),
        Data::Int(value) => out.write_all(value.to_string().as_bytes()),
        Data::Floats { values, components: 1 } => {
            write_array(out, values, RecentSpellings::new, |recent, text, &v| recent.push_separated(text, v))
        }
        Data::Floats { values, components: 3 } => {
            let points: &[[f32; 3]] = bytemuck::cast_slice(values);
            write_array(out, points, stateless, |(), text, &point| text.push_separated_point(point))
        }
        Data::Floats { values, components } => {
            let tuples: Vec<&[f32]> = values.chunks_exact(*components).collect();
            write_array(out, &tuples, stateless, |(), text, t| {
                text.push_fixed(SEPARATOR);
                push_tuple(text, t, |text, &v| text.push_f32(v));
            })
        }
    }
}

/// What goes before every element of an array but the first.
const SEPARATOR: &[u8; 2] = b", ";

/// `[a, b, …]`, formatting chunks of elements in parallel and writing them in order. The next
/// batch is formatted on the pool while this thread writes the last one, so disk and formatting
/// overlap. Each chunk's formatting starts from a fresh `state()`, so the text does not depend on
/// how the array is split. `format` appends [`SEPARATOR`] and an element (one store for both in
/// the hot cases); the array's first element loses its separator.
fn write_array<T: Sync, S>(
    out: &mut (impl Write + ?Sized),
    items: &[T],
    state: impl Fn() -> S + Sync,
    format: impl Fn(&mut S, &mut Text, &T) + Sync,
) -> std::io::Result<()> {
    out.write_all(b"[")?;
    // A number's text takes about three bytes per byte of its value (`-0.08234567, ` for an f32).
    let text_per_item = 3 * std::mem::size_of::<T>().max(1) + 2;
    let chunk = (CHUNK_BYTES / text_per_item).max(1);
    let batch = chunk * 2 * rayon::current_num_threads().max(1);
    let format_batch = |b: usize, window: &[T]| -> Vec<Vec<u8>> {
        window
            .par_chunks(chunk)
            .enumerate()
            .map(|(c, chunk)| {
                let mut text = Text::with_capacity(chunk.len() * (text_per_item + 8));
                let mut state = state();
                for item in chunk {
                    format(&mut state, &mut text, item);
                }
                let mut bytes = text.into_bytes();
                if b + c == 0 {
                    bytes.drain(..SEPARATOR.len());
                }
                bytes
            })
            .collect()
    };
    let mut written: Vec<Vec<u8>> = Vec::new();
    for (b, window) in items.chunks(batch).enumerate() {
        let mut formatted = Vec::new();
        let result = rayon::in_place_scope(|scope| {
            scope.spawn(|_| formatted = format_batch(b, window));
            written.iter().try_for_each(|text| out.write_all(text))
        });
        result?;
        written = formatted;
    }
    written.iter().try_for_each(|text| out.write_all(text))?;
    out.write_all(b"]")
}

/// A chunk's text, written in fixed-size stores: a piece is stored as a whole window of `N`
/// bytes at the end of the text, of which only its length is kept. Copies of the exact length
/// are calls to `memcpy`, which cost as much as making a spelling.
struct Text {
    /// The text, then at least [`SCRATCH`] bytes that pieces are stored into.
    bytes: Vec<u8>,
    len: usize,
}

/// Bytes after the text that one store may write: a point's, the largest.
const SCRATCH: usize = POINT_STORE;
/// `, (x, y, z)` as three spelling windows and five bytes between and around them.
const POINT_STORE: usize = 3 * WINDOW + 5;

impl Text {
    fn with_capacity(capacity: usize) -> Self {
        Self { bytes: vec![0; capacity + SCRATCH], len: 0 }
    }

    /// Appends the first `write(store)` bytes of what `write` stores into the `N` bytes after
    /// the text: one capacity check however many pieces `write` lays out in them.
    // Always inlined: a call per element costs its register saves (~12 instructions).
    #[inline(always)]
    fn push_with<const N: usize>(&mut self, write: impl FnOnce(&mut [u8; N]) -> usize) {
        const { assert!(N <= SCRATCH) };
        if self.len + N > self.bytes.len() {
            self.bytes.resize(2 * self.bytes.len() + SCRATCH, 0);
        }
        let store = (&mut self.bytes[self.len..self.len + N]).try_into().expect("a store");
        let length = write(store);
        debug_assert!(length <= N);
        self.len += length;
    }

    #[inline]
    fn push_fixed<const N: usize>(&mut self, bytes: &[u8; N]) {
        self.push_with::<N>(|store| {
            store.copy_from_slice(bytes);
            N
        });
    }

    #[inline]
    fn push_f32(&mut self, value: f32) {
        self.push_with(|window| spell::spell(value, window));
    }

    /// Appends `, (x, y, z)` in one store.
    #[inline]
    fn push_separated_point(&mut self, [x, y, z]: [f32; 3]) {
        self.push_with::<POINT_STORE>(|store| {
            store[..3].copy_from_slice(b", (");
            let end = spell_at(store, 3, x);
            store[end..end + 2].copy_from_slice(SEPARATOR);
            let end = spell_at(store, end + 2, y);
            store[end..end + 2].copy_from_slice(SEPARATOR);
            let end = spell_at(store, end + 2, z);
            store[end] = b')';
            end + 1
        });
    }

    fn push_int(&mut self, value: impl itoa::Integer) {
        let mut buffer = itoa::Buffer::new();
        let spelled = buffer.format(value).as_bytes();
        let (spelling, length) = (padded(spelled), spelled.len());
        self.push_with::<24>(|store| {
            *store = spelling;
            length
        });
    }

    fn into_bytes(mut self) -> Vec<u8> {
        self.bytes.truncate(self.len);
        self.bytes
    }
}

/// Stores `value`'s spelling at `at` in `store` and returns where it ends.
#[inline]
fn spell_at<const N: usize>(store: &mut [u8; N], at: usize, value: f32) -> usize {
    let window = (&mut store[at..at + WINDOW]).try_into().expect("a window");
    // A spelling never fills its window; the bound lets the compiler drop the later checks.
    at + spell::spell(value, window).min(WINDOW)
}

fn push_tuple<T>(text: &mut Text, values: &[T], push: impl Fn(&mut Text, &T)) {
    text.push_fixed(b"(");
    for (i, v) in values.iter().enumerate() {
        if i > 0 {
            text.push_fixed(b", ");
        }
        push(text, v);
    }
    text.push_fixed(b")");
}

/// `text` (at most 24 bytes) at the start of 24 bytes, copied as its first and last `N` bytes
/// (overlapping) with `N` the largest of 16, 8, 4, 2 it holds: fixed-size copies, no `memcpy`.
#[inline]
fn padded(text: &[u8]) -> [u8; 24] {
    let mut padded = [0u8; 24];
    match text.len() {
        16..=24 => copy_ends::<16>(&mut padded, text),
        8..=15 => copy_ends::<8>(&mut padded, text),
        4..=7 => copy_ends::<4>(&mut padded, text),
        2..=3 => copy_ends::<2>(&mut padded, text),
        len => padded[..len].copy_from_slice(text),
    }
    padded
}

/// Copies `text`'s first and last `N` bytes (a fixed-size copy each) to the same places of `to`.
#[inline]
fn copy_ends<const N: usize>(to: &mut [u8; 24], text: &[u8]) {
    let len = text.len();
    to[..N].copy_from_slice(&text[..N]);
    to[len - N..len].copy_from_slice(&text[len - N..]);
}

/// The spellings of the scalars a chunk formatted last, by their bits. Scalar arrays such as
/// widths repeat a few values (a taper every strand shares: 30 distinct widths among the 1,120 of
/// Blender's test groom), and copying a spelling takes a fraction of the instructions of making
/// one. A chunk where few values repeat stops looking.
struct RecentSpellings {
    bits: [u32; RECENT_SLOTS],
    /// [`spell::spell`]'s text (at most 17 bytes) and its length in the last byte.
    text: [[u8; 24]; RECENT_SLOTS],
    looked_up: u32,
    found: u32,
}

const RECENT_SLOTS: usize = 256;
/// Values looked up before a chunk decides whether repeats are common enough to keep looking.
const RECENT_TRIAL: u32 = 1024;

impl RecentSpellings {
    fn new() -> Self {
        // Every slot starts as the spelling of 0.0, whose bits are 0.
        let mut zero = [0u8; 24];
        zero[..3].copy_from_slice(b"0.0");
        zero[23] = 3;
        Self { bits: [0; RECENT_SLOTS], text: [zero; RECENT_SLOTS], looked_up: 0, found: 0 }
    }

    /// Appends [`SEPARATOR`] and `value` as [`spell::spell`] spells it, in one store.
    #[inline(always)]
    fn push_separated(&mut self, text: &mut Text, value: f32) {
        if self.looked_up >= RECENT_TRIAL && self.found < RECENT_TRIAL / 8 {
            // Below about one repeat in eight, looking up costs more than it saves.
            return text.push_with::<{ 2 + WINDOW }>(|store| {
                store[..2].copy_from_slice(SEPARATOR);
                spell_at(store, 2, value)
            });
        }
        self.looked_up += 1;
        let bits = value.to_bits();
        // Fibonacci hashing: the top byte of the product mixes every bit of the value.
        let slot = (bits.wrapping_mul(0x9e37_79b9) >> 24) as usize;
        let cached = &mut self.text[slot];
        if self.bits[slot] == bits {
            self.found += 1;
            text.push_with::<{ 2 + WINDOW }>(|store| {
                store[..2].copy_from_slice(SEPARATOR);
                store[2..26].copy_from_slice(cached);
                2 + usize::from(cached[23])
            });
        } else {
            self.bits[slot] = bits;
            text.push_with::<{ 2 + WINDOW }>(|store| {
                store[..2].copy_from_slice(SEPARATOR);
                let end = spell_at(store, 2, value);
                cached.copy_from_slice(&store[2..26]);
                cached[23] = (end - 2) as u8;
                end
            });
        }
    }
}

fn push_f64(text: &mut String, value: f64) {
    text.push_str(zmij::Buffer::new().format(value));
}

/// A layer metadata number: whole numbers without a fraction (`metersPerUnit = 1`).
fn push_number(text: &mut String, value: f64) {
    if value.fract() == 0.0 && value.abs() < 1e15 {
        text.push_str(itoa::Buffer::new().format(value as i64));
    } else {
        push_f64(text, value);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The array as the writer spelled it before spellings were reused and copied in pieces:
    /// every value formatted by `zmij` and appended whole.
    fn spelled_one_by_one(values: &[f32]) -> Vec<u8> {
        let mut text = b"[".to_vec();
        for (i, &v) in values.iter().enumerate() {
            if i > 0 {
                text.extend_from_slice(b", ");
            }
            let spelled = match v {
                v if v.is_nan() => "nan".to_string(),
                f32::INFINITY => "inf".to_string(),
                f32::NEG_INFINITY => "-inf".to_string(),
                v => zmij::Buffer::new().format_finite(v).to_string(),
            };
            text.extend_from_slice(spelled.as_bytes());
        }
        text.push(b']');
        text
    }

    #[test]
    fn padded_copies_keep_every_length() {
        let source: Vec<u8> = (b'a'..=b'z').collect();
        for len in 0..=24 {
            assert_eq!(padded(&source[..len])[..len], source[..len], "length {len}");
        }
    }

    #[test]
    fn text_keeps_pieces_past_its_capacity() {
        let mut text = Text::with_capacity(0);
        let mut expected = Vec::new();
        for i in -300..300 {
            text.push_int(i * 7919);
            text.push_fixed(b", ");
            text.push_f32(i as f32 * 0.37);
            expected.extend(format!("{}, {}", i * 7919, zmij::Buffer::new().format(i as f32 * 0.37)).bytes());
            let point = [i as f32 * -1.7e-4, 0.1, i as f32 * 3.3e5];
            text.push_separated_point(point);
            let [x, y, z] = point.map(|v| zmij::Buffer::new().format(v).to_string());
            expected.extend(format!(", ({x}, {y}, {z})").bytes());
        }
        assert_eq!(text.into_bytes(), expected);
    }

    #[test]
    fn points_are_their_spellings_in_tuples() {
        // More points than a chunk holds, with values spelled longest or oddly.
        let odd =
            [0.0, -0.0, -1.234_567_9e-6, 1e-45, f32::MAX, -f32::MIN_POSITIVE, 1e13, f32::NAN, f32::INFINITY];
        let values: Vec<f32> = (0..200_001u32)
            .map(|i| f32::from_bits(0xbe80_0000u32.wrapping_add(7919 * i)))
            .chain(odd)
            .collect();
        let mut text = Vec::new();
        write_data(&Data::Floats { values: values[..].into(), components: 3 }, &mut text).unwrap();
        let spelled = |v: &f32| {
            let array = spelled_one_by_one(&[*v]);
            String::from_utf8(array[1..array.len() - 1].to_vec()).unwrap()
        };
        let expected: Vec<String> = values
            .chunks(3)
            .map(|t| format!("({})", t.iter().map(spelled).collect::<Vec<_>>().join(", ")))
            .collect();
        assert_eq!(String::from_utf8(text).unwrap(), format!("[{}]", expected.join(", ")));
    }

    fn written(values: &[f32]) -> Vec<u8> {
        let mut text = Vec::new();
        write_data(&Data::Floats { values: values.into(), components: 1 }, &mut text).unwrap();
        text
    }

    #[test]
    fn reused_spellings_are_the_spellings() {
        // A taper every strand repeats, with the values that spell longest or oddly, and values
        // sharing a slot of the recent spellings (same top byte of the hashed bits).
        let mut profile: Vec<f32> = (0..32).map(|k| 80e-6 * (1.0 - 0.5 * k as f32 / 31.0)).collect();
        profile.extend([0.0, -0.0, -1.234_567_9e-6, 1e-45, f32::MAX, -f32::MIN_POSITIVE, 1e13, 16_777_216.0]);
        profile.extend([f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::from_bits(0x7fc0_0001)]);
        let slot = |v: f32| v.to_bits().wrapping_mul(0x9e37_79b9) >> 24;
        let colliding: Vec<f32> = (1..200_000u32)
            .map(|i| f32::from_bits(0x3c00_0000 + i))
            .filter(|&v| slot(v) == slot(0.5))
            .take(8)
            .collect();
        assert_eq!(colliding.len(), 8);
        profile.extend(&colliding);
        profile.push(0.5);
        let repeating: Vec<f32> = profile.iter().copied().cycle().take(300_000).collect();
        assert_eq!(written(&repeating), spelled_one_by_one(&repeating));

        // Few repeats, so chunks stop looking them up, then repeats again; more than one chunk.
        let mut mixed: Vec<f32> = (0..200_000u32).map(|i| f32::from_bits(0x3e80_0000 + 37 * i)).collect();
        mixed.extend(repeating.iter().take(100_000));
        assert_eq!(written(&mixed), spelled_one_by_one(&mixed));
        assert_eq!(written(&[]), b"[]");
    }
}
