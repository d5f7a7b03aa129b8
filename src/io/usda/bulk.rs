//! Fast path for large numeric arrays (points, widths, primvars): the array's text is taken a
//! window at a time, cut at element boundaries, and the pieces are parsed on all threads, then
//! appended in order; the reading thread meanwhile appends the previous window's numbers and
//! reads and cuts the next window (`Lexer::bulk_array`), so only the parse is on the critical
//! path. Same grammar and errors as the element-by-element path, same values.
//!
//! Each number is read in one pass where it starts: a plain decimal (what every writer emits) is
//! scanned into its digits (eight bytes at a time) and power of ten, and converted exactly
//! (Clinger's fast path) or, for long or extreme spellings, by `fast-float2` (Eisel-Lemire):
//! correctly rounded, as `str::parse` is. Anything else — `inf`, `nan`, a bad token — goes
//! through the token path the element-by-element reader uses, so its value and error message
//! are the same.
use rayon::prelude::*;

use super::integer::IntType;

/// Pieces smaller than this are not worth a thread.
const MIN_PIECE: usize = 64 * 1024;

/// A syntax error at a byte offset of the text handed to [`parse_segment`].
pub struct BulkError {
    pub offset: usize,
    pub message: String,
}

/// Bytes [`Number::written`] may look at from a number's start: the longest spelling it takes
/// (sign, 7 integer digits, point, 15 fraction digits) and the byte after it, with room to spare.
const WRITTEN_WINDOW: usize = 32;

/// A number type an array is read as.
pub trait Number: Copy + Send + Default {
    /// The number at the start of `window` if it is spelled the way writers spell array values
    /// (`-0.0123`: no exponent, at most 19 digits), and its length in bytes; `None` sends it
    /// through [`Number::prefix`], which reads every decimal and gives the same value.
    #[inline(always)]
    fn written(_window: &[u8; WRITTEN_WINDOW]) -> Option<(Self, usize)> {
        None
    }
    /// A plain decimal at the start of `bytes` and its length in bytes; `None` sends the token
    /// through [`Number::token`].
    fn prefix(bytes: &[u8]) -> Option<(Self, usize)>;
    /// A whole token as the element-by-element reader reads it, or the error it gives.
    fn token(token: &str) -> Result<Self, String>;
}

impl Number for f32 {
    /// Straight-line: the integer digits and up to two groups of eight fraction digits, each
    /// found and converted by one [`leading_digits`], then Clinger's fast path. A read of many
    /// numbers waits on where each ends (the next one's loads need it), so the loads depend on
    /// as few earlier results as possible: a one-digit integer part is taken for granted until
    /// shown otherwise, and both fraction groups are loaded at fixed offsets from the point.
    #[inline(always)]
    fn written(window: &[u8; WRITTEN_WINDOW]) -> Option<(f32, usize)> {
        let word_at = |at: usize| u64::from_le_bytes(window[at..at + 8].try_into().unwrap());
        let negative = window[0] == b'-';
        let sign = usize::from(negative);
        // One integer digit (a groom's coordinates in metres) by a predicted branch, so the
        // fraction's loads need not wait for the integer's digits to be counted.
        let (mut mantissa, integer_digits) = if window[sign + 1] == b'.' && window[sign].is_ascii_digit() {
            (u64::from(window[sign] - b'0'), 1)
        } else {
            let integer_word = if negative { word_at(1) } else { word_at(0) };
            leading_digits(integer_word)
        };
        if integer_digits == 8 {
            return None;
        }
        let mut at = sign + integer_digits;
        let mut fraction_digits = 0;
        if window[at] == b'.' {
            let (high, high_count) = leading_digits(word_at(at + 1));
            let (low, low_count) = leading_digits(word_at(at + 9));
            // The second group counts only after eight digits in the first (no branch: a
            // fraction's length varies from number to number, and a branch on it is mispredicted).
            let (low, low_count) = if high_count == 8 { (low, low_count) } else { (0, 0) };
            if low_count == 8 {
                return None;
            }
            // Up to 22 digits: wraps past 19, which is refused below.
            mantissa = (mantissa * POWERS_OF_TEN[high_count] + high)
                .wrapping_mul(POWERS_OF_TEN[low_count])
                .wrapping_add(low);
            fraction_digits = high_count + low_count;
            at += 1 + fraction_digits;
        }
        let digits = integer_digits + fraction_digits;
        // A letter (an exponent, `inf`), a second point or sign: the general path decides.
        if digits == 0 || digits > 19 || continues_token(Some(&window[at])) {
            return None;
        }
        let value = exact_f32(negative, mantissa, -(fraction_digits as i64))?;
        Some((value, at))
    }

    #[inline(always)]
    fn prefix(bytes: &[u8]) -> Option<(f32, usize)> {
        let decimal = Decimal::scan(bytes)?;
        if let Some(value) = decimal.exact_f32() {
            return Some((value, decimal.len));
        }
        // Long or extreme spellings: the full algorithm (correctly rounded too).
        let (value, len) = fast_float2::parse_partial::<f32, _>(bytes).ok()?;
        (len == decimal.len).then_some((value, len))
    }

    fn token(token: &str) -> Result<f32, String> {
        super::lexer::parse_f32(token).ok_or_else(|| format!("bad number '{token}'"))
    }
}

/// A plain decimal (`-12.5e-3`) as its digits read into an integer and a power of ten.
struct Decimal {
    negative: bool,
    /// The digits as one integer (meaningful when `digits` <= 19).
    mantissa: u64,
    digits: usize,
    exponent: i64,
    /// Bytes the spelling takes.
    len: usize,
}

impl Decimal {
    /// The decimal at the start of `bytes`, or `None` if that is not a whole plain decimal
    /// (a word such as `inf`, a lone `.`, `1e`, `1.5.3`): those take the token path.
    #[inline(always)]
    fn scan(bytes: &[u8]) -> Option<Decimal> {
        let (negative, mut at) = match bytes.first()? {
            b'-' => (true, 1),
            // `+1.5` is no USD number: the token path refuses it.
            b'+' => return None,
            _ => (false, 0),
        };
        let mut mantissa = 0u64;
        let mut digits = 0;
        let mut exponent = 0i64;
        let integer_start = at;
        (mantissa, at) = read_digits(bytes, at, mantissa);
        digits += at - integer_start;
        if bytes.get(at) == Some(&b'.') {
            at += 1;
            let fraction_start = at;
            (mantissa, at) = read_digits(bytes, at, mantissa);
            let fraction = at - fraction_start;
            digits += fraction;
            exponent -= fraction as i64;
        }
        if digits == 0 {
            return None;
        }
        if let Some(b'e' | b'E') = bytes.get(at) {
            at += 1;
            let negative_exponent = bytes.get(at) == Some(&b'-');
            if matches!(bytes.get(at), Some(b'-' | b'+')) {
                at += 1;
            }
            let start = at;
            let mut power = 0i64;
            while let Some(digit) = bytes.get(at).map(|b| b.wrapping_sub(b'0')).filter(|&d| d < 10) {
                // Saturates far beyond any float's range; the full algorithm then decides.
                power = (power * 10 + i64::from(digit)).min(1 << 40);
                at += 1;
            }
            if at == start {
                return None;
            }
            exponent += if negative_exponent { -power } else { power };
        }
        if continues_token(bytes.get(at)) {
            return None;
        }
        Some(Decimal { negative, mantissa, digits, exponent, len: at })
    }

    #[inline]
    fn exact_f32(&self) -> Option<f32> {
        if self.digits > 19 {
            return None;
        }
        exact_f32(self.negative, self.mantissa, self.exponent)
    }
}

/// The nearest `f32` to `mantissa` × 10^`exponent` (negated if `negative`; the mantissa at most
/// 19 digits), when one exact `f64` operation and a rounding to `f32` give it (Clinger's fast
/// path): the digits and the power of ten are exact in `f64`, so their product or quotient is
/// the correctly rounded `f64`; rounding that to `f32` is right unless it lands exactly halfway
/// between two `f32`s (then `None`), as every `f32` halfway point is an `f64` and both roundings
/// are monotonic. A quotient is first tried as a product ([`scaled_f32`]).
#[inline(always)]
fn exact_f32(negative: bool, mantissa: u64, exponent: i64) -> Option<f32> {
    const POWERS: [f64; 23] = [
        1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17,
        1e18, 1e19, 1e20, 1e21, 1e22,
    ];
    if mantissa > 1 << 53 || exponent.unsigned_abs() > 22 {
        return None;
    }
    if exponent < 0 {
        if let Some(value) = scaled_f32(negative, mantissa, exponent.unsigned_abs() as usize) {
            return Some(value);
        }
    }
    let power = POWERS[exponent.unsigned_abs() as usize];
    let nearest = if exponent >= 0 { mantissa as f64 * power } else { mantissa as f64 / power };
    // The 29 bits an f64 has below an f32's precision (the value is a normal f32 here:
    // between 1e-22 and 9.1e37, or zero).
    if nearest.to_bits() & 0x1fff_ffff == 0x1000_0000 {
        return None;
    }
    let value = nearest as f32;
    Some(if negative { -value } else { value })
}

/// [`exact_f32`] for `mantissa` / 10^`places` without a division (whose latency a read of
/// millions of numbers waits on): the product of the mantissa (exact) and the `f64` nearest
/// 10^-`places` carries two roundings, so it lies within 2 `f64` ulps of the true quotient; an
/// `f32` halfway point between the two would leave the product's 29 low bits within 2 of the
/// halfway pattern (4 here, to spare), and then (`None`) the exact division decides.
#[inline(always)]
fn scaled_f32(negative: bool, mantissa: u64, places: usize) -> Option<f32> {
    const RECIPROCALS: [f64; 23] = [
        1e0, 1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14, 1e-15,
        1e-16, 1e-17, 1e-18, 1e-19, 1e-20, 1e-21, 1e-22,
    ];
    let near = mantissa as f64 * RECIPROCALS[places];
    if (near.to_bits() & 0x1fff_ffff).abs_diff(0x1000_0000) <= 4 {
        return None;
    }
    let value = near as f32;
    Some(if negative { -value } else { value })
}

/// Appends the decimal digits at `at` to `mantissa` (wrapping: the caller counts the digits);
/// returns it and the offset after the digits.
#[inline(always)]
fn read_digits(bytes: &[u8], mut at: usize, mut mantissa: u64) -> (u64, usize) {
    loop {
        let Some(eight) = bytes.get(at..at + 8) else {
            return tail_digits(bytes, at, mantissa);
        };
        let (value, count) = leading_digits(u64::from_le_bytes(eight.try_into().unwrap()));
        mantissa = mantissa.wrapping_mul(POWERS_OF_TEN[count]).wrapping_add(value);
        at += count;
        // Eight digits usually end a fraction: look at one byte before eight more.
        if count < 8 || !bytes.get(at).is_some_and(u8::is_ascii_digit) {
            return (mantissa, at);
        }
    }
}

/// [`read_digits`] in the last eight bytes of the text, one byte at a time.
#[cold]
fn tail_digits(bytes: &[u8], mut at: usize, mut mantissa: u64) -> (u64, usize) {
    while let Some(digit) = bytes.get(at).map(|b| b.wrapping_sub(b'0')).filter(|&d| d < 10) {
        mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(digit));
        at += 1;
    }
    (mantissa, at)
}

const POWERS_OF_TEN: [u64; 9] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000, 10_000_000, 100_000_000];

/// The decimal digits at the start of eight bytes (little-endian in `word`): their value and
/// how many there are (0 to 8), found and converted eight at a time (SWAR).
#[inline(always)]
fn leading_digits(word: u64) -> (u64, usize) {
    const HIGH: u64 = 0xf0f0_f0f0_f0f0_f0f0;
    const ZEROS: u64 = 0x3030_3030_3030_3030;
    // Non-zero in every byte that is not a digit: its high nibble is not 3, or it is past '9'
    // (adding 6 carries it out of the 3x range). A carry out of a non-digit byte can spoil the
    // test of the bytes after it, never of those before, so the first non-digit is exact.
    let not_digit = ((word & HIGH) ^ ZEROS) | ((word.wrapping_add(0x0606_0606_0606_0606) & HIGH) ^ ZEROS);
    let count = (not_digit.trailing_zeros() / 8) as usize;
    // The digits' values moved to the top bytes (leading zeros in front), then combined in
    // pairs, fours and eights by multiply-and-shift. No branch on the count: with none, two
    // shifts of 32 clear the word.
    let shift = 4 * (8 - count) as u32;
    let mut value = (word.wrapping_sub(ZEROS)) << shift << shift;
    value = value.wrapping_mul(10).wrapping_add(value >> 8) & 0x00ff_00ff_00ff_00ff;
    value = (value.wrapping_mul(1 + (100 << 16)) >> 16) & 0x0000_ffff_0000_ffff;
    value = value.wrapping_mul(1 + (10_000 << 32)) >> 32;
    (value, count)
}

/// A value of the USD integer or flag type whose [`IntType::code`] is `TYPE`, read as pxr reads
/// it ([`IntType::read`]; a `uint64` as its bits).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Integer<const TYPE: u8>(pub i64);

impl<const TYPE: u8> Number for Integer<TYPE> {
    fn prefix(bytes: &[u8]) -> Option<(Self, usize)> {
        let (negative, digits) = match bytes.first()? {
            b'-' => (true, &bytes[1..]),
            _ => (false, bytes),
        };
        // Up to 18 digits cannot overflow; longer numbers take the token path.
        let count = digits.iter().take(19).take_while(|b| b.is_ascii_digit()).count();
        if count == 0 || count > 18 {
            return None;
        }
        let magnitude = digits[..count].iter().fold(0i64, |n, &d| n * 10 + i64::from(d - b'0'));
        let len = count + usize::from(negative);
        let value = if negative { -magnitude } else { magnitude };
        if continues_token(bytes.get(len)) {
            return None;
        }
        // Out of range: the token path says so.
        let value = IntType::from_code(TYPE).take(value)?;
        Some((Integer(value), len))
    }

    fn token(token: &str) -> Result<Self, String> {
        IntType::from_code(TYPE).read(token).map(Integer)
    }
}

/// Whether a byte would still belong to a number token (so a prefix is not the whole token).
#[inline(always)]
fn continues_token(byte: Option<&u8>) -> bool {
    const TABLE: [bool; 256] = {
        let mut table = [false; 256];
        let mut b = 0;
        while b < 256 {
            let c = b as u8;
            table[b] = c.is_ascii_alphanumeric() || matches!(c, b'-' | b'+' | b'.');
            b += 1;
        }
        table
    };
    byte.is_some_and(|&b| TABLE[b as usize])
}

/// Where `#` comments can be: nowhere in most arrays, which spares every cut a look back to the
/// start of its line (an array written on one line is megabytes long).
#[derive(Clone, Copy)]
pub struct Comments(bool);

impl Comments {
    #[cfg(test)]
    pub fn in_text(text: &[u8]) -> Self {
        Comments(memchr::memchr(b'#', text).is_some())
    }

    /// Whether byte `at` sits inside a `#` comment (which runs to the end of its line).
    fn contain(self, text: &[u8], at: usize) -> bool {
        self.0 && {
            let line_start = memchr::memrchr(b'\n', &text[..at]).map_or(0, |i| i + 1);
            memchr::memchr(b'#', &text[line_start..at]).is_some()
        }
    }
}

/// The end of the array in `text`: the offset of its `]`, outside comments.
pub fn find_close(text: &[u8], comments: Comments) -> Option<usize> {
    let mut from = 0;
    while let Some(i) = memchr::memchr(b']', &text[from..]) {
        let at = from + i;
        if !comments.contain(text, at) {
            return Some(at);
        }
        from = at + 1;
    }
    None
}

/// The last element boundary at or before `limit`: just after a tuple's `)` (tuples) or after a
/// `,` (scalars), outside comments. Returns the offset just past it.
pub fn boundary_before(text: &[u8], limit: usize, components: usize, comments: Comments) -> Option<usize> {
    let marker = if components == 1 { b',' } else { b')' };
    let mut end = limit;
    while let Some(i) = memchr::memrchr(marker, &text[..end]) {
        if !comments.contain(text, i) {
            return Some(i + 1);
        }
        end = i;
    }
    None
}

/// Whether the text before a cut made by [`boundary_before`] leaves a separator still to come.
pub fn needs_separator_after_cut(components: usize) -> bool {
    components > 1
}

/// Where a window of an array's text (from just after the `[`, or after the previous cut) ends
/// what can be parsed now.
pub enum Cut {
    /// The first `len` bytes are whole elements; `closed`: the array's `]` is at `len`.
    Elements { len: usize, closed: bool, comments: Comments },
    /// No element ends in the window: a longer window is needed.
    Longer,
    /// The input ended before the `]`.
    Unclosed,
}

/// Where `window` (the input's end if `eof`) is cut for parsing. One pass over the window in
/// the usual case: an array without comments, its `]` the first `#` or `]`.
pub fn cut(window: &[u8], eof: bool, components: usize) -> Cut {
    let comments = match memchr::memchr2(b'#', b']', window) {
        Some(i) if window[i] == b']' => {
            // No comment before the close: none in the elements cut here.
            return Cut::Elements { len: i, closed: true, comments: Comments(false) };
        }
        Some(_) => Comments(true),
        None => Comments(false),
    };
    // Without a `#`, the scan above has shown there is no `]` either.
    match comments.0.then(|| find_close(window, comments)).flatten() {
        Some(i) => Cut::Elements { len: i, closed: true, comments },
        None if eof => Cut::Unclosed,
        None => match boundary_before(window, window.len(), components, comments) {
            Some(len) => Cut::Elements { len, closed: false, comments },
            None => Cut::Longer,
        },
    }
}

/// The numbers of a run of array elements, piece by piece in order (flattened tuples).
pub struct Parsed<N> {
    pub pieces: Vec<Vec<N>>,
    /// Whether a separator is due after the last element.
    pub need_separator: bool,
    /// Newlines in the run's text.
    pub newlines: usize,
}

/// Parses a run of array elements, `need_separator` saying whether a `,` must come before the
/// first element. Big runs are split at element boundaries and the pieces parsed on all
/// threads; the values and the first error (in text order) do not depend on the split.
pub fn parse_segment<N: Number>(
    text: &[u8],
    components: usize,
    need_separator: bool,
    comments: Comments,
) -> Result<Parsed<N>, BulkError> {
    let pieces = (text.len() / MIN_PIECE).clamp(1, 8 * rayon::current_num_threads().max(1));
    let mut cuts = vec![0];
    for k in 1..pieces {
        let target = text.len() * k / pieces;
        if let Some(cut) = boundary_before(text, target, components, comments) {
            if cut > *cuts.last().unwrap() {
                cuts.push(cut);
            }
        }
    }
    cuts.push(text.len());
    let results: Vec<Result<Parsed<N>, BulkError>> = cuts
        .par_windows(2)
        .enumerate()
        .map(|(k, w)| {
            let need = if k == 0 { need_separator } else { needs_separator_after_cut(components) };
            let piece = &text[w[0]..w[1]];
            let (values, need) = parse_piece(piece, components, need)
                .map_err(|e| BulkError { offset: w[0] + e.offset, ..e })?;
            let newlines = memchr::memchr_iter(b'\n', piece).count();
            Ok(Parsed { pieces: vec![values], need_separator: need, newlines })
        })
        .collect();
    let mut parsed = Parsed { pieces: Vec::with_capacity(results.len()), need_separator, newlines: 0 };
    for piece in results {
        let piece = piece?;
        parsed.pieces.extend(piece.pieces);
        parsed.need_separator = piece.need_separator;
        parsed.newlines += piece.newlines;
    }
    Ok(parsed)
}

fn error(offset: usize, message: String) -> BulkError {
    BulkError { offset, message }
}

/// The offset of the first byte at or after `at` that is neither blank nor in a comment.
#[inline]
fn skip_blank(text: &[u8], mut at: usize) -> usize {
    while let Some(&b) = text.get(at) {
        match b {
            b' ' | b'\t' | b'\r' | b'\n' => at += 1,
            b'#' => at = memchr::memchr(b'\n', &text[at..]).map_or(text.len(), |i| at + i),
            _ => break,
        }
    }
    at
}

/// Reads the number at `at` into `values`; returns the offset after it.
#[inline(always)]
fn read_number<N: Number>(text: &[u8], at: usize, values: &mut Vec<N>) -> Result<usize, BulkError> {
    if let Some((value, len)) = N::prefix(&text[at..]) {
        values.push(value);
        return Ok(at + len);
    }
    let len = text[at..].iter().take_while(|&&b| continues_token(Some(&b))).count();
    if len == 0 {
        let found = text.get(at).map_or("the end of the array".into(), |&b| super::lexer::describe(b));
        return Err(error(at, format!("expected a number, found {found}")));
    }
    // Letters, digits and signs only: always UTF-8.
    let token = std::str::from_utf8(&text[at..at + len]).unwrap_or_default();
    match N::token(token) {
        Ok(value) => {
            values.push(value);
            Ok(at + len)
        }
        Err(message) => Err(error(at, message)),
    }
}

/// Reads elements laid out as writers lay them out (see [`written_element`]) from `at` on, as
/// long as they come; returns the offset after the last. `components` from 1 to 4 (`float4`,
/// `quatf`); others go to the general path.
fn written_elements<N: Number>(
    text: &[u8],
    at: usize,
    need_separator: &mut bool,
    components: usize,
    values: &mut Vec<N>,
) -> usize {
    // A constant tuple size, so each tuple is copied out by fixed stores, not a `memmove` call.
    fn run<N: Number, const C: usize>(
        text: &[u8],
        mut at: usize,
        need_separator: &mut bool,
        values: &mut Vec<N>,
    ) -> usize {
        while let Some(end) = written_element::<N, C>(text, at, *need_separator, values) {
            at = end;
            *need_separator = true;
        }
        at
    }
    match components {
        1 => run::<N, 1>(text, at, need_separator, values),
        2 => run::<N, 2>(text, at, need_separator, values),
        3 => run::<N, 3>(text, at, need_separator, values),
        4 => run::<N, 4>(text, at, need_separator, values),
        _ => at,
    }
}

/// The element at `at` if it is laid out as writers lay elements out — `, (x, y, z)` or `, x`
/// (the separator only when one is due), every number [`Number::written`] — appended to
/// `values`; returns the offset after it. `None` (nothing appended) leaves the element to the
/// general path, which reads every layout and gives these values too.
#[inline(always)]
fn written_element<N: Number, const C: usize>(
    text: &[u8],
    mut at: usize,
    need_separator: bool,
    values: &mut Vec<N>,
) -> Option<usize> {
    // Not a closure: a closure called twice was not inlined, and the call cost a fifth of a number.
    #[inline(always)]
    fn number<N: Number>(text: &[u8], at: usize) -> Option<(N, usize)> {
        N::written(text.get(at..at + WRITTEN_WINDOW)?.try_into().unwrap())
    }
    if need_separator {
        if text.get(at..at + 2)? != b", " {
            return None;
        }
        at += 2;
    }
    if C == 1 {
        let (value, len) = number::<N>(text, at)?;
        values.push(value);
        return Some(at + len);
    }
    if text.get(at) != Some(&b'(') {
        return None;
    }
    at += 1;
    let mut tuple = [N::default(); C];
    for (k, slot) in tuple.iter_mut().enumerate() {
        if k > 0 {
            if text.get(at..at + 2)? != b", " {
                return None;
            }
            at += 2;
        }
        let (value, len) = number::<N>(text, at)?;
        *slot = value;
        at += len;
    }
    if text.get(at) != Some(&b')') {
        return None;
    }
    values.extend_from_slice(&tuple);
    Some(at + 1)
}

fn parse_piece<N: Number>(
    text: &[u8],
    components: usize,
    mut need_separator: bool,
) -> Result<(Vec<N>, bool), BulkError> {
    let mut values = Vec::with_capacity(text.len() / 8);
    let mut at = 0;
    loop {
        at = written_elements(text, at, &mut need_separator, components, &mut values);
        // Anything else, one separator or element at a time.
        at = skip_blank(text, at);
        if at == text.len() {
            return Ok((values, need_separator));
        }
        if need_separator {
            if text[at] != b',' {
                return Err(error(
                    at,
                    format!("expected ',' or ']' in an array, found {}", super::lexer::describe(text[at])),
                ));
            }
            at += 1;
            need_separator = false;
            continue;
        }
        if components == 1 {
            at = read_number(text, at, &mut values)?;
        } else {
            let tuple_start = at;
            if text[at] != b'(' {
                return Err(error(
                    at,
                    format!("expected '(' to open a tuple, found {}", super::lexer::describe(text[at])),
                ));
            }
            at += 1;
            let mut count = 0;
            loop {
                at = skip_blank(text, at);
                if count > 0 && text.get(at) == Some(&b')') {
                    at += 1;
                    break;
                }
                at = read_number(text, at, &mut values)?;
                count += 1;
                at = skip_blank(text, at);
                match text.get(at) {
                    Some(b',') => at += 1,
                    Some(b')') => {
                        at += 1;
                        break;
                    }
                    Some(&b) => {
                        return Err(error(
                            at,
                            format!("expected ',' or ')' in a tuple, found {}", super::lexer::describe(b)),
                        ))
                    }
                    None => return Err(error(at, "unexpected end of file inside a tuple".into())),
                }
            }
            if count != components {
                return Err(error(
                    tuple_start,
                    format!("expected {components} numbers in a tuple, found {count}"),
                ));
            }
        }
        need_separator = true;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_all<N: Number>(text: &str, components: usize) -> Result<Vec<N>, String> {
        let comments = Comments::in_text(text.as_bytes());
        parse_segment::<N>(text.as_bytes(), components, false, comments)
            .map(|parsed| parsed.pieces.concat())
            .map_err(|e| format!("at {}: {}", e.offset, e.message))
    }

    /// Eight bytes at a time: every count of leading digits, followed by every kind of byte.
    #[test]
    fn leading_digits_count_and_convert_like_a_byte_loop() {
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(0x2545_f491_4f6c_dd1du64);
        for _ in 0..50_000 {
            let state = rand::Rng::random::<u64>(&mut rng);
            let mut bytes = [0u8; 8];
            let count = (state % 9) as usize;
            for (k, b) in bytes.iter_mut().enumerate() {
                let r = (state >> (8 * k)) as u8;
                *b = if k < count { b'0' + r % 10 } else { r };
            }
            let expected_count = bytes.iter().take_while(|b| b.is_ascii_digit()).count();
            let expected = bytes[..expected_count].iter().fold(0u64, |n, &d| n * 10 + u64::from(d - b'0'));
            assert_eq!(leading_digits(u64::from_le_bytes(bytes)), (expected, expected_count), "{bytes:?}");
        }
    }

    /// Every spelling the one-pass reader takes must give the bits `str::parse` (through the
    /// token path) gives, in the shortest, scientific, long and padded forms writers produce.
    #[test]
    fn one_pass_floats_equal_the_token_path_bit_for_bit() {
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(0x2545_f491_4f6c_dd1du64);
        let mut spellings: Vec<String> = [
            "0",
            "-0",
            "0.0",
            ".5",
            "5.",
            "-.25",
            "1e5",
            "1E5",
            "1e+5",
            "1e-45",
            "1e-46",
            "3.4028235e38",
            "3.4028236e38",
            "1e39",
            "0.000001",
            "1.17549435e-38",
            "16777217",
            "0.30000000000000004",
            "2.0000001192092896",
            "123456789012345678901234567890",
            "00012.5000",
            "7.038531e-26",
        ]
        .map(String::from)
        .to_vec();
        for _ in 0..20_000 {
            let state = rand::Rng::random::<u64>(&mut rng);
            let value = f32::from_bits(state as u32);
            if !value.is_finite() {
                continue;
            }
            spellings.push(zmij::Buffer::new().format_finite(value).to_string());
            spellings.push(format!("{value:e}"));
            spellings.push(format!("{:.12}", value as f64 * 1.000_000_1));
        }
        for spelling in &spellings {
            let expected = super::super::lexer::parse_f32(spelling).unwrap();
            let (value, len) = f32::prefix(spelling.as_bytes()).unwrap_or_else(|| panic!("{spelling}"));
            assert_eq!(len, spelling.len(), "{spelling}");
            assert_eq!(value.to_bits(), expected.to_bits(), "{spelling}");
            let (values, _) = parse_piece::<f32>(format!("{spelling}, {spelling}").as_bytes(), 1, false)
                .unwrap_or_else(|e| panic!("{spelling}: {}", e.message));
            assert_eq!(values.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), [expected.to_bits(); 2]);
        }
    }

    /// The written-spelling reader on `spelling` followed by `after`, in a window as it sees one.
    fn written(spelling: &str, after: &str) -> Option<(f32, usize)> {
        let mut window = [b' '; WRITTEN_WINDOW];
        let text = format!("{spelling}{after}");
        let len = text.len().min(WRITTEN_WINDOW);
        window[..len].copy_from_slice(&text.as_bytes()[..len]);
        f32::written(&window)
    }

    /// Whatever the written-spelling reader takes must be `str::parse`'s value bit for bit:
    /// every count of integer and fraction digits (with leading zeros, past 19 digits, past the
    /// window), signs, what may follow a number, the halfway points Clinger's path must refuse,
    /// and every f32 spelling the writer makes; those below 10^7 without an exponent must not
    /// fall back.
    #[test]
    fn written_spellings_equal_str_parse_bit_for_bit() {
        // The crate's seeded generator, so every run draws the same cases.
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(0x9e37_79b9_7f4a_7c15u64);
        let mut next = move || rand::Rng::random::<u64>(&mut rng);
        let mut spellings: Vec<String> = [
            "0",
            "-0",
            "0.0",
            "-0.0",
            ".5",
            "5.",
            "-.25",
            "0.000001",
            "00012.5000",
            "1234567.1234567",
            "9999999.999999999999",
            "0.0000000000000000001",
            "0.00000000000000000001",
            "8388609.5",
            "-8388609.5",
            "9999999.5",
            "4194304.25",
            "4194304.75",
            "8388609.5000000001",
            "8388609.4999999999",
            "0.30000001192092896",
            "16777217",
            "3.4028235",
            "0.000000000000001",
        ]
        .map(String::from)
        .to_vec();
        for _ in 0..100_000 {
            let r = next();
            let integer_digits = (r % 9) as usize;
            let fraction_digits = ((r >> 8) % 18) as usize;
            let digits = |count: usize, r: u64| {
                (0..count).map(|k| char::from(b'0' + ((r >> (3 * k)) % 10) as u8)).collect::<String>()
            };
            let sign = ["", "-"][((r >> 16) % 2) as usize];
            let point = if (r >> 20) % 8 == 0 { "" } else { "." };
            spellings.push(format!(
                "{sign}{}{point}{}",
                digits(integer_digits, next()),
                if point.is_empty() { String::new() } else { digits(fraction_digits, next()) }
            ));
        }
        // Within a few f64 ulps of f32 halfway points: where the reciprocal must defer to division.
        for _ in 0..100_000 {
            let r = next();
            let value = f32::from_bits(0x3a00_0000 + (r as u32 % 0x1100_0000)); // 4.9e-4 .. 8.4e6
            let halfway = (f64::from(value) + f64::from(f32::from_bits(value.to_bits() + 1))) / 2.0;
            let integer_digits = format!("{}", halfway.trunc()).len();
            let nudged = f64::from_bits(halfway.to_bits().wrapping_add((r >> 40) % 9).wrapping_sub(4));
            spellings.push(format!("{:.*}", 15 - integer_digits.min(15), nudged));
            spellings.push(format!("{:.*}", 17 - integer_digits.min(17), nudged));
        }
        let mut made = Vec::new();
        for _ in 0..200_000 {
            let value = f32::from_bits(next() as u32);
            if value.is_finite() {
                made.push(zmij::Buffer::new().format_finite(value).to_string());
                made.push(zmij::Buffer::new().format_finite(value * 1e-30).to_string());
            }
        }
        let mut taken = 0;
        for spelling in spellings.iter().chain(&made) {
            let Some(expected) = super::super::lexer::parse_f32(spelling) else { continue };
            for after in [", ", ")", " ", "]", "\n", "#"] {
                if let Some((value, len)) = written(spelling, after) {
                    assert_eq!((value.to_bits(), len), (expected.to_bits(), spelling.len()), "{spelling:?}");
                    taken += 1;
                }
            }
        }
        assert!(taken > 100_000, "{taken}");
        // What the writer makes below 10^7 with no exponent (every point and width of a groom in
        // metres or centimetres) is always taken.
        let below_ten_million = |s: &&String| s.trim_start_matches('-').find('.').is_some_and(|i| i < 8);
        for spelling in made.iter().filter(|s| !s.contains('e')).filter(below_ten_million) {
            assert!(written(spelling, ", ").is_some(), "{spelling}");
        }
        for (spelling, after) in [
            ("1.5", "e3"),
            ("1.5", ".3"),
            ("1.5", "-2"),
            ("1", "e5"),
            ("", "inf"),
            ("-", "inf"),
            ("", "nan"),
            ("-", ""),
            (".", ""),
            ("1", "x"),
        ] {
            assert_eq!(written(spelling, after), None, "{spelling}{after}");
        }
    }

    /// Arrays in the writers' layout read the same as in any other layout (which the general
    /// path reads), values the written reader refuses included, at any thread count.
    #[test]
    fn written_layout_reads_as_any_layout_at_any_thread_count() {
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(0x2545_f491_4f6c_dd1du64);
        let mut spellings = Vec::new();
        for k in 0..90_000u32 {
            let state = rand::Rng::random::<u64>(&mut rng);
            let value = f32::from_bits(state as u32) * [1.0, 1e-35, 1e30][k as usize % 3];
            spellings.push(match k % 1000 {
                0 => "inf".to_string(),
                1 => "nan".to_string(),
                2 => "1234567890.5".to_string(),
                3 => "0.000000000000000000012345".to_string(),
                _ if value.is_finite() => zmij::Buffer::new().format_finite(value).to_string(),
                _ => "-0".to_string(),
            });
        }
        let expected: Vec<u32> =
            spellings.iter().map(|s| super::super::lexer::parse_f32(s).unwrap().to_bits()).collect();
        let bits = |values: Vec<f32>| values.into_iter().map(f32::to_bits).collect::<Vec<u32>>();
        let tuples = |open: &str, separator: &str, close: &str| {
            spellings.chunks(3).map(|c| format!("{open}{}{close}", c.join(separator))).collect::<Vec<_>>()
        };
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                assert_eq!(bits(parse_all(&spellings.join(", "), 1).unwrap()), expected);
                assert_eq!(bits(parse_all(&spellings.join(" ,\n"), 1).unwrap()), expected);
                assert_eq!(bits(parse_all(&tuples("(", ", ", ")").join(", "), 3).unwrap()), expected);
                assert_eq!(bits(parse_all(&tuples("( ", " ,", " )").join(",\n"), 3).unwrap()), expected);
            });
        }
        // A tuple one number short is refused in either layout, naming where it starts.
        assert_eq!(
            parse_all::<f32>("(1, 2, 3), (4, 5)", 3).unwrap_err(),
            "at 11: expected 3 numbers in a tuple, found 2"
        );
        assert_eq!(
            parse_all::<f32>("(1, 2, 3), (4, 5, 6, 7)", 3).unwrap_err(),
            "at 11: expected 3 numbers in a tuple, found 4"
        );
    }

    /// Words and bad tokens leave the one-pass reader to the token path: USD's `inf`/`nan` read,
    /// anything else is refused naming the whole token, at its offset.
    #[test]
    fn non_decimal_tokens_take_the_token_path() {
        let read = parse_all::<f32>("[inf, -inf, nan]".trim_matches(['[', ']']), 1).unwrap();
        assert!(read[0] == f32::INFINITY && read[1] == f32::NEG_INFINITY && read[2].is_nan());
        for bad in [
            "1.5e", "1.5.3", "0x10", "infinity", "--5", "1e", "nan5", "+", "-", "1f", "1e5e5", "Inf", "+1.5",
            "+0", "+inf",
        ] {
            let error = parse_all::<f32>(&format!("1, 2,  {bad}, 3"), 1).unwrap_err();
            assert_eq!(error, format!("at 7: bad number '{bad}'"), "{bad}");
            let error = parse_all::<f32>(&format!("(1, 2, 3), (4, {bad}, 6)"), 3).unwrap_err();
            assert_eq!(error, format!("at 15: bad number '{bad}'"), "{bad}");
        }
        assert_eq!(parse_all::<f32>("1, , 2", 1).unwrap_err(), "at 3: expected a number, found ','");
        assert_eq!(
            parse_all::<f32>("1, 2 3", 1).unwrap_err(),
            "at 5: expected ',' or ']' in an array, found '3'"
        );
        assert_eq!(parse_all::<f32>("1, é", 1).unwrap_err(), "at 3: expected a number, found byte 0xc3");
        assert_eq!(
            parse_all::<f32>("(1, 2), (3, 4, 5)", 2).unwrap_err(),
            "at 8: expected 2 numbers in a tuple, found 3"
        );
    }

    /// Each integer type's array values, read in one pass or through the token path, are the
    /// ones `IntType::read` gives, and a value it refuses is refused with its message.
    #[test]
    fn integers_read_in_one_pass_or_through_the_token_path() {
        fn check<const T: u8>() {
            let int_type = IntType::from_code(T);
            let tokens = [
                "0",
                "-7",
                "42",
                "+5",
                "true",
                "false",
                "007",
                "255",
                "256",
                "-1",
                "2.9",
                "-0.5",
                "1e3",
                "2147483648",
                "999999999999999999",
                "-9223372036854775808",
                "9223372036854775808",
                "18446744073709551615",
                "18446744073709551616",
                "99999999999999999999",
                "12a",
                "-",
                "nan",
            ];
            for token in tokens {
                let read = parse_all::<Integer<T>>(&format!("1, {token}"), 1);
                let expected = int_type.read(token);
                match (read, expected) {
                    (Ok(values), Ok(value)) => {
                        assert_eq!(values, [Integer(1), Integer(value)], "{int_type:?} {token}")
                    }
                    (Err(error), Err(message)) => {
                        assert_eq!(error, format!("at 3: {message}"), "{int_type:?}")
                    }
                    (read, expected) => panic!("{int_type:?} '{token}': {read:?}, expected {expected:?}"),
                }
            }
        }
        check::<{ IntType::Bool.code() }>();
        check::<{ IntType::UChar.code() }>();
        check::<{ IntType::Int.code() }>();
        check::<{ IntType::UInt.code() }>();
        check::<{ IntType::Int64.code() }>();
        check::<{ IntType::UInt64.code() }>();
    }

    /// A comment anywhere in a window makes every cut check for comments; a window without one
    /// cuts at the last marker.
    #[test]
    fn cuts_skip_markers_inside_comments() {
        let text = b"(1, 2, 3), (4, 5, 6) # (7, 8, 9),\n";
        let comments = Comments::in_text(text);
        assert_eq!(boundary_before(text, text.len(), 3, comments), Some(20));
        assert_eq!(find_close(b"1, 2 # ]\n, 3]", Comments::in_text(b"1, 2 # ]\n, 3]")), Some(12));
        assert_eq!(boundary_before(b"(1, 2), (3, 4)", 14, 2, Comments::in_text(b"(1, 2), (3, 4)")), Some(14));
    }
}
