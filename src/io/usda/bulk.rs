//! Fast path for large numeric arrays (points, widths, primvars): the array's text is taken a
//! window at a time, cut at element boundaries, and the pieces are parsed on all threads, then
//! appended in order. Same grammar and errors as the element-by-element path, same values.
use rayon::prelude::*;

/// Pieces smaller than this are not worth a thread.
const MIN_PIECE: usize = 64 * 1024;

/// A syntax error at a byte offset of the text handed to [`parse_segment`].
pub struct BulkError {
    pub offset: usize,
    pub message: String,
}

/// Whether byte `at` sits inside a `#` comment (which runs to the end of its line).
pub fn in_comment(text: &[u8], at: usize) -> bool {
    let line_start = memchr::memrchr(b'\n', &text[..at]).map_or(0, |i| i + 1);
    memchr::memchr(b'#', &text[line_start..at]).is_some()
}

/// The end of the array in `text`: the offset of its `]`, outside comments.
pub fn find_close(text: &[u8]) -> Option<usize> {
    let mut from = 0;
    while let Some(i) = memchr::memchr(b']', &text[from..]) {
        let at = from + i;
        if !in_comment(text, at) {
            return Some(at);
        }
        from = at + 1;
    }
    None
}

/// The last element boundary at or before `limit`: just after a tuple's `)` (tuples) or after a
/// `,` (scalars), outside comments. Returns the offset just past it.
pub fn boundary_before(text: &[u8], limit: usize, components: usize) -> Option<usize> {
    let marker = if components == 1 { b',' } else { b')' };
    let mut end = limit;
    while let Some(i) = memchr::memrchr(marker, &text[..end]) {
        if !in_comment(text, i) {
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

/// Parses a run of array elements, `need_separator` saying whether a `,` must come before the
/// first element. Splits big runs across threads. Returns the numbers (flattened) and whether a
/// separator is due after the last element.
pub fn parse_segment<N: Copy + Send>(
    text: &[u8],
    components: usize,
    need_separator: bool,
    number: fn(&str) -> Option<N>,
) -> Result<(Vec<N>, bool), BulkError> {
    let pieces = (text.len() / MIN_PIECE).clamp(1, 2 * rayon::current_num_threads().max(1));
    let mut cuts = vec![0];
    for k in 1..pieces {
        let target = text.len() * k / pieces;
        if let Some(cut) = boundary_before(text, target, components) {
            if cut > *cuts.last().unwrap() {
                cuts.push(cut);
            }
        }
    }
    cuts.push(text.len());
    let results: Vec<Result<(Vec<N>, bool), BulkError>> = cuts
        .par_windows(2)
        .enumerate()
        .map(|(k, w)| {
            let need = if k == 0 { need_separator } else { needs_separator_after_cut(components) };
            parse_piece(&text[w[0]..w[1]], components, need, number)
                .map_err(|e| BulkError { offset: w[0] + e.offset, ..e })
        })
        .collect();
    let mut values = Vec::new();
    let mut need = need_separator;
    for result in results {
        let (piece, piece_need) = result?;
        if values.is_empty() {
            values = piece;
        } else {
            values.extend_from_slice(&piece);
        }
        need = piece_need;
    }
    Ok((values, need))
}

fn parse_piece<N: Copy>(
    text: &[u8],
    components: usize,
    mut need_separator: bool,
    number: fn(&str) -> Option<N>,
) -> Result<(Vec<N>, bool), BulkError> {
    let mut values = Vec::with_capacity(text.len() / 8);
    let mut at = 0;
    let error = |offset: usize, message: String| BulkError { offset, message };
    // Checked once per piece (pieces are cut at ASCII bytes), so tokens slice it for free.
    let text_str = std::str::from_utf8(text)
        .map_err(|e| error(e.valid_up_to(), "the text is not valid UTF-8".into()))?;
    let skip_blank = |at: &mut usize| {
        while *at < text.len() {
            match text[*at] {
                b' ' | b'\t' | b'\r' | b'\n' => *at += 1,
                b'#' => *at = memchr::memchr(b'\n', &text[*at..]).map_or(text.len(), |i| *at + i),
                _ => break,
            }
        }
    };
    let read_number = |at: &mut usize, values: &mut Vec<N>| -> Result<(), BulkError> {
        let start = *at;
        while *at < text.len()
            && (text[*at].is_ascii_alphanumeric() || matches!(text[*at], b'-' | b'+' | b'.'))
        {
            *at += 1;
        }
        if start == *at {
            let found = text.get(start).map_or("the end of the array".into(), |&b| super::lexer::describe(b));
            return Err(error(start, format!("expected a number, found {found}")));
        }
        let token = &text_str[start..*at];
        match number(token) {
            Some(value) => {
                values.push(value);
                Ok(())
            }
            None => Err(error(start, format!("bad number '{token}'"))),
        }
    };
    loop {
        skip_blank(&mut at);
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
            read_number(&mut at, &mut values)?;
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
                skip_blank(&mut at);
                if count > 0 && at < text.len() && text[at] == b')' {
                    at += 1;
                    break;
                }
                read_number(&mut at, &mut values)?;
                count += 1;
                skip_blank(&mut at);
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
