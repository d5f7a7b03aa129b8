//! The `.usda` writer's spelling of an `f32`: the shortest decimal that reads back as the same
//! value, byte for byte as `zmij` (1.0.x) spells it (`0.0625`, `-12.5`, `100.0`, `1e-7`, `1e+13`),
//! made in fixed-size stores straight into the output. zmij lays out `0.000ddd` with calls to
//! `memmove` and `memset`, which cost as much as finding the digits; here the common cases — a
//! normal number written without an exponent, decimal exponent −6 to 12 — are laid out with
//! whole-register stores, and everything else (zero, subnormals, powers of two, exponents,
//! non-finite values) is left to zmij itself, so it cannot differ.
//!
//! Finding the digits is Schubfach's: scale the 24-bit significand by the power of ten that
//! leaves eight or nine digits in the integer part of a 64-bit product; either the shorter
//! candidate next to it is inside the rounding interval, or the nearest one-digit-longer decimal
//! is the answer. The decisions are zmij's, including its choice of rounding, and the test
//! `spellings_equal_zmij_for_every_f32` (ignored: ~3.5 CPU minutes) checks all 2³² values.

/// Bytes [`spell`] may store into (its spelling takes at most 17 of them).
pub const WINDOW: usize = 32;

/// What a normal `f32` of one binary exponent needs: the top 64 bits of `10^-(dec_exp + 1)`
/// (rounded down), the shift that puts the significand's point where the product's integer
/// part is the decimal significand, and `dec_exp = floor(log10(2^bin_exp))`.
#[derive(Clone, Copy)]
struct Scale {
    pow10: u64,
    shift: u32,
    dec_exp: i32,
}

/// Bits of the product below the decimal point.
const FRACTION_BITS: u32 = 34;

/// [`Scale`] by the biased exponent field (1 to 254: normal numbers).
const SCALES: [Scale; 256] = {
    let mut table = [Scale { pow10: 0, shift: 0, dec_exp: 0 }; 256];
    let mut biased = 1;
    while biased < 255 {
        let bin_exp = biased - 150;
        // floor(log10(2) · bin_exp), exact over the f32 range.
        let dec_exp = (bin_exp * 315_653) >> 20;
        let (pow10, pow10_exp) = pow10_top(-dec_exp - 1);
        let shift = bin_exp + pow10_exp + 1 + FRACTION_BITS as i32;
        table[biased as usize] = Scale { pow10, shift: shift as u32, dec_exp };
        biased += 1;
    }
    table
};

/// The top 64 bits of `10^e` (rounded down) and `floor(log2(10^e))`, for |e| ≤ 50, in 256-bit
/// arithmetic: `10^e` exactly, or `2^255 / 10^-e` rounded down.
const fn pow10_top(e: i32) -> (u64, i32) {
    let mut x = if e >= 0 { [1, 0, 0, 0] } else { [0, 0, 0, 1 << 63] };
    let mut i = 0;
    while i < e.abs() {
        if e >= 0 {
            multiply_by_10(&mut x);
        } else {
            divide_by_10(&mut x);
        }
        i += 1;
    }
    let mut top = 3;
    while x[top] == 0 {
        top -= 1;
    }
    let length = 64 * top as u32 + 64 - x[top].leading_zeros();
    let bits = if length <= 64 {
        x[0] << (64 - length)
    } else {
        let low = length - 64;
        let (limb, bit) = ((low / 64) as usize, low % 64);
        if bit == 0 {
            x[limb]
        } else {
            (x[limb] >> bit) | (x[limb + 1] << (64 - bit))
        }
    };
    let exponent = length as i32 - 1 - if e >= 0 { 0 } else { 255 };
    (bits, exponent)
}

const fn multiply_by_10(x: &mut [u64; 4]) {
    let mut carry = 0u128;
    let mut i = 0;
    while i < 4 {
        let t = x[i] as u128 * 10 + carry;
        x[i] = t as u64;
        carry = t >> 64;
        i += 1;
    }
}

const fn divide_by_10(x: &mut [u64; 4]) {
    let mut remainder = 0u128;
    let mut i = 4;
    while i > 0 {
        i -= 1;
        let t = (remainder << 64) | x[i] as u128;
        x[i] = (t / 10) as u64;
        remainder = t % 10;
    }
}

/// The eight decimal digits of `x` (< 10⁸) as byte values 0–9, the most significant in the
/// lowest byte: split into 4 + 4, 2 + 2 and 1 + 1 digits, every lane at once.
#[inline]
fn digits8(x: u64) -> u64 {
    let high4 = (x * 109_951_163) >> 40;
    let v = (x << 32).wrapping_sub(high4 * ((10_000 << 32) - 1));
    let high2 = ((v * 5243) >> 19) & 0x0000_007f_0000_007f;
    let v = (v << 16).wrapping_sub(high2 * ((100 << 16) - 1));
    let high1 = ((v * 103) >> 10) & 0x000f_000f_000f_000f;
    (v << 8).wrapping_sub(high1 * ((10 << 8) - 1))
}

const ASCII_ZEROS: u64 = u64::from_le_bytes([b'0'; 8]);

/// Stores `value`'s spelling at the start of `out` and returns its length; bytes after it are
/// scratch.
#[inline]
pub fn spell(value: f32, out: &mut [u8; WINDOW]) -> usize {
    let bits = value.to_bits();
    let biased = (bits >> 23) & 0xff;
    let fraction = bits & 0x7f_ffff;
    if biased == 0 || biased == 0xff || fraction == 0 {
        return spell_by_zmij(value, out);
    }
    let scale = SCALES[biased as usize];
    let significand = u64::from(fraction | 1 << 23);
    let product = ((u128::from(scale.pow10 + 1) * u128::from(significand << scale.shift)) >> 64) as u64;
    let mut integral = product >> FRACTION_BITS;
    let fractional = product & ((1 << FRACTION_BITS) - 1);
    // Half the gap to the neighbouring floats; an even significand owns its interval's ends.
    let half_ulp = (scale.pow10 >> (65 - scale.shift)) + u64::from(!fraction & 1);
    let round_up = (fractional + half_ulp) >> FRACTION_BITS != 0;
    let round_down = half_ulp > fractional;
    integral += u64::from(round_up);
    // Otherwise one more digit, rounded to nearest (a tie, ...25 exactly, to 2).
    let next_digit = if fractional == 1 << (FRACTION_BITS - 2) {
        2
    } else {
        (fractional * 10 + (1 << (FRACTION_BITS - 1))) >> FRACTION_BITS
    };
    let decimal = integral * 10 + if round_up || round_down { 0 } else { next_digit };
    // As nine digits (trailing zeros pad), with the decimal exponent of the first.
    let (nine_digits, exponent) = if integral >= 10_000_000 {
        (decimal, scale.dec_exp + 8)
    } else if integral >= 1_000_000 {
        (decimal * 10, scale.dec_exp + 7)
    } else {
        (decimal * 100, scale.dec_exp + 6)
    };
    if !(-6..=12).contains(&exponent) {
        return spell_by_zmij(value, out);
    }
    let first = nine_digits / 100_000_000;
    let rest = digits8(nine_digits - first * 100_000_000);
    // Significant digits: nine less the trailing zeros (the top bytes of `rest` that are 0).
    let length = 9 - rest.leading_zeros() as usize / 8;
    let mut digits = [0u8; 16];
    digits[..8].copy_from_slice(&((first | rest << 8) + ASCII_ZEROS).to_le_bytes());
    digits[8..].copy_from_slice(&((rest >> 56) + ASCII_ZEROS).to_le_bytes());
    let negative = usize::from(bits >> 31 != 0);
    out[0] = b'-';
    let out = &mut out[negative..];
    if exponent < 0 {
        // 0.000ddd: the zeros, then the digits over the end of them.
        let start = (1 - exponent) as usize;
        out[..8].copy_from_slice(b"0.000000");
        out[start..start + 16].copy_from_slice(&digits);
        negative + start + length
    } else {
        // ddd.ddd and dddd00.0: the digits (zero-padded), then those after the point one on.
        let point = exponent as usize + 1;
        out[..16].copy_from_slice(&digits);
        let after: [u8; 16] = out[point..point + 16].try_into().expect("16 bytes");
        out[point] = b'.';
        out[point + 1..point + 17].copy_from_slice(&after);
        negative + length.max(point + 1) + 1
    }
}

/// zmij's spelling, and USD's of the non-finite values.
#[cold]
fn spell_by_zmij(value: f32, out: &mut [u8; WINDOW]) -> usize {
    let mut buffer = zmij::Buffer::new();
    let text = if value.is_finite() {
        buffer.format_finite(value)
    } else if value.is_nan() {
        "nan"
    } else if value > 0.0 {
        "inf"
    } else {
        "-inf"
    };
    out[..text.len()].copy_from_slice(text.as_bytes());
    text.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn zmij_spelling(value: f32) -> String {
        match value {
            v if v.is_nan() => "nan".into(),
            f32::INFINITY => "inf".into(),
            f32::NEG_INFINITY => "-inf".into(),
            v => zmij::Buffer::new().format_finite(v).into(),
        }
    }

    fn spelled(value: f32) -> String {
        let mut out = [b'#'; WINDOW];
        let length = spell(value, &mut out);
        String::from_utf8(out[..length].to_vec()).unwrap()
    }

    /// The first difference from zmij among `count` values from `start` (bit patterns).
    fn first_difference(start: u64, count: u64) -> Option<(u32, String, String)> {
        let mut out = [0u8; WINDOW];
        let mut buffer = zmij::Buffer::new();
        (start..start + count).find_map(|i| {
            let value = f32::from_bits(i as u32);
            let expected: &str = match value {
                v if v.is_nan() => "nan",
                f32::INFINITY => "inf",
                f32::NEG_INFINITY => "-inf",
                v => buffer.format_finite(v),
            };
            let length = spell(value, &mut out);
            (out[..length] != *expected.as_bytes())
                .then(|| (i as u32, String::from_utf8_lossy(&out[..length]).into(), expected.into()))
        })
    }

    #[test]
    fn spellings_equal_zmij_at_the_edges() {
        let mut values = vec![
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
            f32::EPSILON,
            f32::from_bits(1),
            f32::from_bits(0x007f_ffff),
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            16_777_216.0,
            16_777_215.0,
            8_388_607.5,
            0.1,
            0.2,
            0.3,
            2.5,
            1.0 / 3.0,
            80e-6,
            -0.083_456_78,
            123_456.79,
            9_999_999_000_000.0,
            1e13,
            9.999_999e12,
            1e-6,
            9.99e-7,
        ];
        // Powers of ten and of two and their neighbours, across the fixed-notation range and
        // past it on both sides.
        for k in -46..=39 {
            let p = 10f64.powi(k) as f32;
            values.extend([
                p,
                f32::from_bits(p.to_bits().wrapping_add(1)),
                f32::from_bits(p.to_bits().wrapping_sub(1)),
            ]);
        }
        for k in -149..=127 {
            let p = 2f64.powi(k) as f32;
            values.extend([p, f32::from_bits(p.to_bits() + 1), f32::from_bits(p.to_bits().wrapping_sub(1))]);
        }
        // Halfway cases: decimals with one digit more than an f32 holds, ending in 5.
        for k in 0..2000u32 {
            let d = f64::from(100_000_000 + k * 37_501) * 10.0 + 5.0;
            for scale in [1e-16, 1e-12, 1e-10, 1e-9, 1e-6, 1e-3, 1.0, 1e3] {
                values.push((d * scale) as f32);
            }
        }
        for value in values {
            for v in [value, -value] {
                assert_eq!(spelled(v), zmij_spelling(v), "bits {:#010x}", v.to_bits());
            }
        }
        // A stride through every binade and both signs.
        assert_eq!(first_difference(0, 0), None);
        for start in (0..1u64 << 32).step_by(1 << 24) {
            assert_eq!(first_difference(start + 12_345, 20_000), None);
        }
    }

    #[test]
    fn digits8_splits_every_eight_digit_number() {
        for x in (0..100_000_000u64).step_by(997).chain([0, 1, 9, 10, 99_999_999, 10_000_000]) {
            let expected = format!("{x:08}");
            let digits: Vec<u8> = digits8(x).to_le_bytes().iter().map(|d| d + b'0').collect();
            assert_eq!(digits, expected.as_bytes(), "{x}");
        }
    }

    /// Every f32: `cargo test --release --lib spell -- --ignored`.
    #[test]
    #[ignore = "all 2^32 floats: ~3.5 CPU minutes in release (11 min wall at load), too long for CI; run it after any change to spell's digit logic"]
    fn spellings_equal_zmij_for_every_f32() {
        use rayon::prelude::*;
        let slices = 1u64 << 12;
        let per_slice = (1u64 << 32) / slices;
        let differences: Vec<_> =
            (0..slices).into_par_iter().filter_map(|s| first_difference(s * per_slice, per_slice)).collect();
        assert_eq!(differences.first(), None, "{} slices differ", differences.len());
    }
}
