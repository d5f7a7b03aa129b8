//! The crate format's two compressions: LZ4 blocks with a chunk-count byte in front (USD's
//! "fast compression"), and the integer coding that turns runs of integers into deltas from the
//! previous value, the most common delta stored once and the others in 1, 2 or 4 bytes (2, 4 or
//! 8 for 64-bit integers), selected by 2-bit codes. Decoders check every size against the bytes
//! they are given and never allocate more than the input can expand to.

/// Largest input of one LZ4 chunk (`LZ4_MAX_INPUT_SIZE`).
const LZ4_MAX_INPUT: usize = 0x7E00_0000;

/// LZ4 cannot expand data by more than this factor (one length byte per 255 output bytes).
const LZ4_MAX_RATIO: usize = 255;

/// LZ4-compresses `input` in USD's framing: a 0 byte then one block, or for inputs over
/// [`LZ4_MAX_INPUT`] the chunk count then `i32` size + block per chunk.
pub fn lz4_compress(input: &[u8]) -> Vec<u8> {
    if input.len() <= LZ4_MAX_INPUT {
        let mut out = vec![0u8; 1 + lz4_flex::block::get_maximum_output_size(input.len())];
        let n = lz4_flex::block::compress_into(input, &mut out[1..]).expect("output sized by the bound");
        out.truncate(1 + n);
        return out;
    }
    let chunks: Vec<&[u8]> = input.chunks(LZ4_MAX_INPUT).collect();
    let mut out = vec![chunks.len() as u8];
    for chunk in chunks {
        let block = lz4_flex::block::compress(chunk);
        out.extend_from_slice(&(block.len() as i32).to_le_bytes());
        out.extend_from_slice(&block);
    }
    out
}

/// Undoes [`lz4_compress`] into at most `max_output` bytes; the error says what is wrong.
pub fn lz4_decompress(input: &[u8], max_output: usize) -> Result<Vec<u8>, String> {
    let (&chunks, mut rest) = input.split_first().ok_or("empty compressed block")?;
    let blocks: Vec<&[u8]> = if chunks == 0 {
        vec![rest]
    } else {
        let mut blocks = Vec::with_capacity(chunks as usize);
        for chunk in 0..chunks {
            if rest.len() < 4 {
                return Err(format!("LZ4 chunk {chunk} of {chunks} is cut short"));
            }
            let size = i32::from_le_bytes(rest[..4].try_into().unwrap());
            let size = usize::try_from(size)
                .ok()
                .filter(|&s| s <= rest.len() - 4)
                .ok_or_else(|| format!("LZ4 chunk {chunk} claims {size} bytes, more than remain"))?;
            blocks.push(&rest[4..4 + size]);
            rest = &rest[4 + size..];
        }
        blocks
    };
    let possible: usize = blocks.iter().map(|b| b.len().saturating_mul(LZ4_MAX_RATIO)).sum();
    let mut out = vec![0u8; max_output.min(possible)];
    let mut filled = 0;
    for block in blocks {
        filled += lz4_flex::block::decompress_into(block, &mut out[filled..])
            .map_err(|e| format!("bad LZ4 data ({e})"))?;
    }
    out.truncate(filled);
    Ok(out)
}

/// An integer type the integer coding handles.
pub trait CodedInt: Copy + Default {
    /// 4 or 8.
    const BYTES: usize;
    fn to_i64(self) -> i64;
    fn from_i64(value: i64) -> Self;
}

macro_rules! coded_int {
    ($($t:ty => $bytes:expr),*) => {$(
        impl CodedInt for $t {
            const BYTES: usize = $bytes;
            fn to_i64(self) -> i64 {
                self as i64
            }
            fn from_i64(value: i64) -> Self {
                value as $t
            }
        }
    )*};
}
coded_int!(i32 => 4, u32 => 4, i64 => 8, u64 => 8);

/// Bytes the integer coding of `count` integers can take at most.
pub fn max_coded_size<T: CodedInt>(count: usize) -> usize {
    if count == 0 {
        0
    } else {
        T::BYTES + count.div_ceil(4) + T::BYTES * count
    }
}

/// Integer-codes `values` (wrapping deltas, as USD does), then LZ4-compresses the result.
pub fn compress_ints<T: CodedInt>(values: &[T]) -> Vec<u8> {
    lz4_compress(&encode_ints(values))
}

/// The deltas the coding stores: from the previous value (0 before the first), wrapping in the
/// integer's width as the decoder's sums do.
fn deltas<T: CodedInt>(values: &[T]) -> impl Iterator<Item = i64> + Clone + '_ {
    let wide = T::BYTES == 8;
    let mut previous = 0i64;
    values.iter().map(move |v| {
        let v = v.to_i64();
        let delta =
            if wide { v.wrapping_sub(previous) } else { (v as i32).wrapping_sub(previous as i32) as i64 };
        previous = v;
        delta
    })
}

fn encode_ints<T: CodedInt>(values: &[T]) -> Vec<u8> {
    if values.is_empty() {
        return Vec::new();
    }
    let wide = T::BYTES == 8;
    let common = most_common(deltas(values));
    let code = |d: i64| -> u8 {
        let fits = |bits: u32| d >= -(1i64 << (bits - 1)) && d < (1i64 << (bits - 1));
        match (d == common, wide) {
            (true, _) => 0,
            (false, false) if fits(8) => 1,
            (false, false) if fits(16) => 2,
            (false, true) if fits(16) => 1,
            (false, true) if fits(32) => 2,
            _ => 3,
        }
    };
    // Every delta is stored as 8 bytes and the end moved by its width (fixed-size stores, no
    // per-value copy of a variable length); the 8 bytes of slack are cut at the end.
    let mut out = vec![0u8; max_coded_size::<T>(values.len()) + 8];
    out[..T::BYTES].copy_from_slice(&common.to_le_bytes()[..T::BYTES]);
    let codes_at = T::BYTES;
    let mut end = codes_at + values.len().div_ceil(4);
    let mut deltas = deltas(values);
    for k in 0..values.len().div_ceil(4) {
        // One code byte per four values; only deltas other than the common one are stored.
        let mut byte = 0;
        for (shift, d) in (0..8).step_by(2).zip(&mut deltas) {
            let c = code(d);
            if c != 0 {
                out[end..end + 8].copy_from_slice(&d.to_le_bytes());
                end += code_width(c, wide);
                byte |= c << shift;
            }
        }
        out[codes_at + k] = byte;
    }
    out.truncate(end);
    out
}

/// Bytes a delta with 2-bit code `code` takes (0 for the common delta).
fn code_width(code: u8, wide: bool) -> usize {
    match (code, wide) {
        (0, _) => 0,
        (1, false) => 1,
        (1, true) | (2, false) => 2,
        (2, true) | (3, false) => 4,
        _ => 8,
    }
}

/// The most frequent delta; ties go to the smaller value so output is deterministic. Counted in
/// a small open-addressed table (deltas of real data take few values); when they take more than
/// it holds, by sorting.
fn most_common(deltas: impl Iterator<Item = i64> + Clone) -> i64 {
    const SLOTS: usize = 1024;
    const MAX_DISTINCT: usize = SLOTS / 2;
    let mut keys = [0i64; SLOTS];
    let mut counts = [0u32; SLOTS];
    let mut distinct = 0;
    for d in deltas.clone() {
        let mut slot = (d as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) as usize >> (64 - 10);
        while counts[slot] != 0 && keys[slot] != d {
            slot = (slot + 1) % SLOTS;
        }
        if counts[slot] == 0 {
            if distinct == MAX_DISTINCT {
                return most_common_sorted(deltas.collect());
            }
            distinct += 1;
            keys[slot] = d;
        }
        counts[slot] += 1;
    }
    let (mut best, mut best_count) = (0, 0);
    for (&key, &count) in keys.iter().zip(&counts) {
        if count > best_count || (count == best_count && count > 0 && key < best) {
            (best, best_count) = (key, count);
        }
    }
    best
}

fn most_common_sorted(mut sorted: Vec<i64>) -> i64 {
    sorted.sort_unstable();
    let (mut best, mut best_count) = (sorted[0], 0);
    for run in sorted.chunk_by(|a, b| a == b) {
        if run.len() > best_count {
            (best, best_count) = (run[0], run.len());
        }
    }
    best
}

/// The deltas of [`decode_ints`] being summed: where the next one is and the running value.
struct Cursor<'d> {
    data: &'d [u8],
    at: usize,
    previous: i64,
    common: i64,
    widths: [usize; 4],
}

impl Cursor<'_> {
    /// The next value: the running sum plus `delta`, wrapping in the integer's width.
    #[inline(always)]
    fn add<T: CodedInt>(&mut self, delta: i64) -> T {
        self.previous = if T::BYTES == 8 {
            self.previous.wrapping_add(delta)
        } else {
            (self.previous as i32).wrapping_add(delta as i32) as i64
        };
        T::from_i64(self.previous)
    }

    /// Values for the 2-bit codes of `byte`, lowest first (the data was checked to hold them).
    #[inline(always)]
    fn decode<T: CodedInt>(&mut self, values: &mut [T], mut byte: u8) {
        let data = self.data;
        for value in values {
            let at = self.at;
            let delta = match (byte & 3, T::BYTES == 8) {
                (0, _) => self.common,
                (1, false) => data[at] as i8 as i64,
                (1, true) | (2, false) => i16::from_le_bytes([data[at], data[at + 1]]) as i64,
                (2, true) | (3, false) => i32::from_le_bytes(data[at..at + 4].try_into().unwrap()) as i64,
                _ => i64::from_le_bytes(data[at..at + 8].try_into().unwrap()),
            };
            self.at += self.widths[byte as usize & 3];
            byte >>= 2;
            *value = self.add::<T>(delta);
        }
    }
}

/// Undoes [`compress_ints`] for exactly `count` integers.
pub fn decompress_ints<T: CodedInt>(input: &[u8], count: usize) -> Result<Vec<T>, String> {
    if count == 0 {
        return Ok(Vec::new());
    }
    // Each integer takes at least its 2-bit code, so the count is bounded by what LZ4 can give.
    let possible = input.len().saturating_mul(LZ4_MAX_RATIO);
    if count.div_ceil(4) > possible {
        return Err(format!("{count} integers cannot come from {} compressed bytes", input.len()));
    }
    let coded = lz4_decompress(input, max_coded_size::<T>(count))?;
    decode_ints(&coded, count)
}

fn decode_ints<T: CodedInt>(coded: &[u8], count: usize) -> Result<Vec<T>, String> {
    let wide = T::BYTES == 8;
    let codes_len = count.div_ceil(4);
    if coded.len() < T::BYTES + codes_len {
        return Err(format!("integer codes for {count} values are cut short"));
    }
    let common = if wide {
        i64::from_le_bytes(coded[..8].try_into().unwrap())
    } else {
        i32::from_le_bytes(coded[..4].try_into().unwrap()) as i64
    };
    let codes = &coded[T::BYTES..T::BYTES + codes_len];
    let data = &coded[T::BYTES + codes_len..];
    // The bytes the codes ask for, checked once, so the loop below reads without running out.
    let widths: [usize; 4] = std::array::from_fn(|c| code_width(c as u8, wide));
    let byte_widths: [u8; 256] =
        std::array::from_fn(|b| (0..4).map(|k| widths[(b >> (2 * k)) & 3] as u8).sum());
    let mut needed: usize = codes.iter().map(|&b| byte_widths[b as usize] as usize).sum();
    // Codes past the last value (in the last byte) are not read.
    let last = codes[codes_len - 1];
    for k in (count - 4 * (codes_len - 1))..4 {
        needed -= widths[(last >> (2 * k)) as usize & 3];
    }
    if data.len() < needed {
        return Err("integer data is cut short".into());
    }
    let mut out = vec![T::default(); count];
    let mut cursor = Cursor { data, at: 0, previous: 0, common, widths };
    // Whole code bytes (four values each), then the values of a last, partial one.
    let mut groups = out.chunks_exact_mut(4);
    for (values, &byte) in (&mut groups).zip(codes) {
        if byte == 0 {
            // Four common deltas (a run of equal steps): the usual case.
            for value in values {
                *value = cursor.add::<T>(common);
            }
        } else {
            cursor.decode(values, byte);
        }
    }
    cursor.decode(groups.into_remainder(), codes[codes_len - 1]);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integers_round_trip_through_every_code_width() {
        let values: Vec<i32> =
            vec![0, 1, 2, 3, 3, 3, 100, -100, 40_000, -40_000, i32::MAX, i32::MIN, 7, 7, 7, 7, 8];
        let packed = compress_ints(&values);
        assert_eq!(decompress_ints::<i32>(&packed, values.len()).unwrap(), values);
        let wide: Vec<i64> = vec![0, 1, i64::MAX, i64::MIN, 1 << 40, -(1 << 20), 5, 5];
        assert_eq!(decompress_ints::<i64>(&compress_ints(&wide), wide.len()).unwrap(), wide);
        let unsigned: Vec<u32> = vec![u32::MAX, 0, 1, u32::MAX];
        assert_eq!(decompress_ints::<u32>(&compress_ints(&unsigned), 4).unwrap(), unsigned);
    }

    /// Data of every shape: few distinct deltas (the counting table), many (the sort), runs,
    /// extremes, and lengths that end in a partial code byte.
    #[test]
    fn random_data_round_trips_and_the_common_delta_is_the_most_frequent() {
        // The crate's seeded generator, so every run draws the same cases.
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(0x9e37_79b9_7f4a_7c15u64);
        let mut next = move || rand::Rng::random::<u64>(&mut rng);
        for case in 0..200 {
            let len = (next() % 3000) as usize + 1;
            let spread = [1, 3, 40, 1000, 1 << 20, u64::MAX][case % 6];
            let values: Vec<i32> = (0..len)
                .map(|i| if next() % 4 == 0 { (next() % spread) as i32 } else { i as i32 * 3 })
                .collect();
            assert_eq!(decompress_ints::<i32>(&compress_ints(&values), len).unwrap(), values, "case {case}");
            let wide: Vec<i64> = values.iter().map(|&v| (i64::from(v) * (next() % 3) as i64) << 20).collect();
            assert_eq!(decompress_ints::<i64>(&compress_ints(&wide), len).unwrap(), wide, "case {case}");
            let deltas: Vec<i64> = super::deltas(&values).collect();
            assert_eq!(most_common(deltas.iter().copied()), most_common_sorted(deltas), "case {case}");
        }
    }

    #[test]
    fn a_known_coding_decodes_as_documented() {
        // common delta 1 (i32), codes: 0 (common), 1 (i8 delta 5), 0, 0.
        let coded = [1, 0, 0, 0, 0b0000_0100, 5];
        assert_eq!(decode_ints::<i32>(&coded, 4).unwrap(), vec![1, 6, 7, 8]);
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let packed = compress_ints(&[1i32, 5, 9, 300, 70_000]);
        for cut in 0..packed.len() {
            let _ = decompress_ints::<i32>(&packed[..cut], 5);
        }
        assert!(decompress_ints::<i32>(&packed, 1 << 40).is_err(), "huge count");
        assert!(lz4_decompress(&[3, 0xff, 0xff, 0xff, 0x7f], 100).is_err(), "chunk beyond the end");
        assert!(lz4_decompress(&[0, 0xf0], 100).is_err());
    }
}
