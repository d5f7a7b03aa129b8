//! Byte-level scanning of `.usda` text: a refilling window over the input (so a large file is
//! never held whole in memory), whitespace and `#` comments, line counting, and the lexical
//! pieces of the grammar — identifiers, strings, numbers, paths and asset paths.
use std::io::Read;

use super::integer::IntType;

/// Bytes read from the input at a time.
const WINDOW: usize = 1 << 20;
/// A large array's read window: each is cut into pieces for the threads, and a thread left
/// without a piece at a window's end waits, so a window holds many pieces. Tests use small
/// windows so that small files span many.
const BULK_WINDOW: usize = if cfg!(test) { 256 << 10 } else { 4 << 20 };
/// Longest number token accepted; anything longer is a bad number.
const MAX_NUMBER: usize = 64;

/// A lexical error: what went wrong and on which line.
#[derive(Debug)]
pub struct LexError {
    pub line: u32,
    pub message: String,
}

pub type LexResult<T> = Result<T, LexError>;

pub struct Lexer<'a> {
    input: Box<dyn Read + 'a>,
    buffer: Vec<u8>,
    /// The next window of a large array, read while the current one is parsed.
    spare: Vec<u8>,
    pos: usize,
    end: usize,
    eof: bool,
    /// Current line, 1-based.
    pub line: u32,
    read_error: Option<std::io::Error>,
}

impl<'a> Lexer<'a> {
    pub fn new(input: impl Read + 'a) -> Self {
        Lexer {
            input: Box::new(input),
            buffer: vec![0; WINDOW],
            spare: Vec::new(),
            pos: 0,
            end: 0,
            eof: false,
            line: 1,
            read_error: None,
        }
    }

    /// The I/O error that cut the input short, if any (reported instead of a syntax error).
    pub fn take_read_error(&mut self) -> Option<std::io::Error> {
        self.read_error.take()
    }

    /// Makes at least `n` bytes available after `pos`, unless the input ends first.
    fn fill(&mut self, n: usize) {
        if self.end - self.pos >= n || self.eof {
            return;
        }
        self.buffer.copy_within(self.pos..self.end, 0);
        self.end -= self.pos;
        self.pos = 0;
        read_up_to(&mut self.input, &mut self.buffer, &mut self.end, n, &mut self.eof, &mut self.read_error);
    }

    #[inline]
    pub fn peek(&mut self) -> Option<u8> {
        if self.pos == self.end {
            self.fill(1);
            if self.pos == self.end {
                return None;
            }
        }
        Some(self.buffer[self.pos])
    }

    /// The byte `k` places ahead of the current one.
    pub fn peek_at(&mut self, k: usize) -> Option<u8> {
        self.fill(k + 1);
        self.buffer.get(self.pos + k).copied().filter(|_| self.pos + k < self.end)
    }

    /// Consumes one byte (which must not be a newline; newlines go through `skip_ws`).
    #[inline]
    pub fn bump(&mut self) {
        self.pos += 1;
    }

    pub fn error<T>(&self, message: impl Into<String>) -> LexResult<T> {
        Err(LexError { line: self.line, message: message.into() })
    }

    pub fn at_eof(&mut self) -> bool {
        self.peek().is_none()
    }

    /// Skips spaces, newlines (counting them) and `#` comments to the end of their line.
    #[inline]
    pub fn skip_ws(&mut self) {
        while let Some(byte) = self.peek() {
            match byte {
                b' ' | b'\t' | b'\r' => self.pos += 1,
                b'\n' => {
                    self.pos += 1;
                    self.line += 1;
                }
                b'#' => {
                    while let Some(b) = self.peek() {
                        if b == b'\n' {
                            break;
                        }
                        self.pos += 1;
                    }
                }
                _ => break,
            }
        }
    }

    /// Skips whitespace, then consumes `byte` or fails naming what was expected.
    pub fn expect(&mut self, byte: u8, what: &str) -> LexResult<()> {
        self.skip_ws();
        match self.peek() {
            Some(b) if b == byte => {
                self.bump();
                Ok(())
            }
            Some(b) => self.error(format!("expected {what}, found {}", describe(b))),
            None => self.error(format!("unexpected end of file: expected {what}")),
        }
    }

    /// Skips whitespace and consumes `byte` if it comes next.
    pub fn eat(&mut self, byte: u8) -> bool {
        self.skip_ws();
        if self.peek() == Some(byte) {
            self.bump();
            true
        } else {
            false
        }
    }

    /// The next non-blank byte, without consuming it.
    pub fn next_byte(&mut self) -> Option<u8> {
        self.skip_ws();
        self.peek()
    }

    /// Reads exactly `text` (used for the `#usda` header before comments mean anything).
    pub fn starts_with(&mut self, text: &[u8]) -> bool {
        self.fill(text.len());
        self.buffer[self.pos..self.end].starts_with(text)
    }

    /// Consumes the rest of the current line (not the newline).
    pub fn skip_line(&mut self) {
        while let Some(b) = self.peek() {
            if b == b'\n' {
                break;
            }
            self.bump();
        }
    }

    /// An identifier: a letter or `_`, then letters, digits, `_` and `:` (namespaces).
    pub fn identifier(&mut self) -> LexResult<String> {
        self.skip_ws();
        let mut text = String::new();
        match self.peek() {
            Some(b) if b.is_ascii_alphabetic() || b == b'_' => {}
            Some(b) => return self.error(format!("expected a name, found {}", describe(b))),
            None => return self.error("unexpected end of file: expected a name"),
        }
        while let Some(b) = self.peek() {
            if b.is_ascii_alphanumeric() || b == b'_' || b == b':' {
                text.push(b as char);
                self.bump();
            } else {
                break;
            }
        }
        Ok(text)
    }

    /// Whether an identifier starts here (after whitespace).
    pub fn at_identifier(&mut self) -> bool {
        matches!(self.next_byte(), Some(b) if b.is_ascii_alphabetic() || b == b'_')
    }

    /// A quoted string: `"…"`, `'…'` or triple-quoted, with backslash escapes.
    pub fn string(&mut self) -> LexResult<String> {
        self.skip_ws();
        let quote = match self.peek() {
            Some(q @ (b'"' | b'\'')) => q,
            Some(b) => return self.error(format!("expected a quoted string, found {}", describe(b))),
            None => return self.error("unexpected end of file: expected a quoted string"),
        };
        let start_line = self.line;
        let triple = self.peek_at(1) == Some(quote) && self.peek_at(2) == Some(quote);
        self.pos += if triple { 3 } else { 1 };
        let mut bytes = Vec::new();
        loop {
            let Some(b) = self.peek() else {
                return Err(LexError {
                    line: self.line,
                    message: format!("unexpected end of file in the string opened on line {start_line}"),
                });
            };
            if b == quote {
                if !triple {
                    self.bump();
                    break;
                }
                if self.peek_at(1) == Some(quote) && self.peek_at(2) == Some(quote) {
                    self.pos += 3;
                    break;
                }
            }
            if b == b'\n' {
                if !triple {
                    return self.error("newline inside a quoted string");
                }
                self.line += 1;
            }
            self.bump();
            if b == b'\\' {
                let Some(escaped) = self.peek() else { continue };
                if escaped == b'\n' {
                    self.line += 1;
                }
                self.bump();
                bytes.push(match escaped {
                    b'n' => b'\n',
                    b't' => b'\t',
                    b'r' => b'\r',
                    other => other,
                });
            } else {
                bytes.push(b);
            }
        }
        String::from_utf8(bytes).or_else(|_| self.error("string is not valid UTF-8"))
    }

    /// `<…>`: a scene path (relationship targets, connections).
    pub fn path(&mut self) -> LexResult<String> {
        self.expect(b'<', "'<'")?;
        let mut text = String::new();
        loop {
            match self.peek() {
                Some(b'>') => {
                    self.bump();
                    return Ok(text);
                }
                Some(b'\n') | None => return self.error("unterminated path (missing '>')"),
                Some(b) => {
                    text.push(b as char);
                    self.bump();
                }
            }
        }
    }

    /// `@…@` or `@@@…@@@`: an asset path.
    pub fn asset(&mut self) -> LexResult<String> {
        self.skip_ws();
        let triple = self.peek_at(1) == Some(b'@') && self.peek_at(2) == Some(b'@');
        self.pos += if triple { 3 } else { 1 };
        let mut text = String::new();
        loop {
            match self.peek() {
                Some(b'@') if !triple => {
                    self.bump();
                    return Ok(text);
                }
                Some(b'@') if self.peek_at(1) == Some(b'@') && self.peek_at(2) == Some(b'@') => {
                    self.pos += 3;
                    return Ok(text);
                }
                Some(b'\n') | None => return self.error("unterminated asset path (missing '@')"),
                Some(b) => {
                    text.push(b as char);
                    self.bump();
                }
            }
        }
    }

    /// The raw text of a number token (digits, sign, point, exponent, or `inf`/`nan`).
    fn number_token(&mut self) -> LexResult<&str> {
        self.skip_ws();
        self.fill(MAX_NUMBER + 1);
        let window = &self.buffer[self.pos..self.end];
        let len = window
            .iter()
            .position(|b| !(b.is_ascii_alphanumeric() || matches!(b, b'-' | b'+' | b'.')))
            .unwrap_or(window.len());
        if len == 0 {
            return match window.first() {
                Some(&b) => self.error(format!("expected a number, found {}", describe(b))),
                None => self.error("unexpected end of file: expected a number"),
            };
        }
        if len > MAX_NUMBER {
            return self.error("bad number: too long");
        }
        let start = self.pos;
        self.pos += len;
        // Only ASCII bytes were accepted above.
        Ok(std::str::from_utf8(&self.buffer[start..start + len]).unwrap())
    }

    pub fn f32(&mut self) -> LexResult<f32> {
        let token = self.number_token()?;
        match parse_float::<f32>(token) {
            Some(value) => Ok(value),
            None => {
                let message = format!("bad number '{token}'");
                self.error(message)
            }
        }
    }

    pub fn f64(&mut self) -> LexResult<f64> {
        let token = self.number_token()?;
        match parse_float::<f64>(token) {
            Some(value) => Ok(value),
            None => {
                let message = format!("bad number '{token}'");
                self.error(message)
            }
        }
    }

    /// A value of USD integer or flag type `int_type`, as pxr reads it ([`IntType::read`]).
    pub fn integer(&mut self, int_type: IntType) -> LexResult<i64> {
        let token = self.number_token()?;
        match int_type.read(token) {
            Ok(value) => Ok(value),
            Err(message) => self.error(message),
        }
    }

    /// Whether a number starts here (after whitespace).
    pub fn at_number(&mut self) -> bool {
        match self.next_byte() {
            Some(b) if b.is_ascii_digit() || matches!(b, b'-' | b'+' | b'.') => true,
            Some(b'i' | b'n') => {
                // `inf` / `nan`, as opposed to an identifier starting with those letters.
                self.fill(4);
                let window = &self.buffer[self.pos..self.end];
                let word_end = window.iter().position(|b| !b.is_ascii_alphanumeric()).unwrap_or(window.len());
                matches!(&window[..word_end], b"inf" | b"nan")
            }
            _ => false,
        }
    }
}

impl Lexer<'_> {
    /// After an array's `[`: parses numbers with `components` per element up to and including
    /// the closing `]`, a window at a time on all threads, handing each window's numbers to
    /// `append` in order.
    pub fn bulk_array<N: super::bulk::Number>(
        &mut self,
        components: usize,
        mut append: impl FnMut(Vec<N>),
    ) -> LexResult<()> {
        use super::bulk::Cut;
        /// An element longer than this is not a number tuple.
        const MAX_WINDOW: usize = 64 << 20;
        let start_line = self.line;
        let mut need_separator = false;
        // Numbers parsed from the previous window, appended while the next one is parsed.
        let mut pending: Vec<Vec<N>> = Vec::new();
        self.fill(BULK_WINDOW);
        let mut cut = super::bulk::cut(&self.buffer[self.pos..self.end], self.eof, components);
        loop {
            let newlines = |bytes: &[u8]| memchr::memchr_iter(b'\n', bytes).count() as u32;
            let (len, closed, comments) = match cut {
                Cut::Elements { len, closed, comments } => (len, closed, comments),
                Cut::Unclosed => {
                    let line = self.line + newlines(&self.buffer[self.pos..self.end]);
                    return Err(LexError {
                        line,
                        message: format!(
                            "unexpected end of file: the array opened on line {start_line} is not closed"
                        ),
                    });
                }
                Cut::Longer if self.end - self.pos < MAX_WINDOW => {
                    self.fill((2 * (self.end - self.pos)).max(BULK_WINDOW));
                    cut = super::bulk::cut(&self.buffer[self.pos..self.end], self.eof, components);
                    continue;
                }
                Cut::Longer => return self.error("an array element is too long"),
            };
            // Workers parse this window while this thread appends the previous one's numbers,
            // reads the next window and finds where to cut it: only the parse is on the path.
            let segment = &self.buffer[self.pos..self.pos + len];
            let mut parsed = None;
            let mut next = None;
            rayon::in_place_scope(|scope| {
                scope.spawn(|_| {
                    parsed =
                        Some(super::bulk::parse_segment::<N>(segment, components, need_separator, comments))
                });
                pending.drain(..).for_each(&mut append);
                if !closed {
                    let carried = &self.buffer[self.pos + len..self.end];
                    self.spare.resize(self.spare.len().max(carried.len() + BULK_WINDOW), 0);
                    self.spare[..carried.len()].copy_from_slice(carried);
                    let mut end = carried.len();
                    let (eof, error) = (&mut self.eof, &mut self.read_error);
                    read_up_to(
                        &mut self.input,
                        &mut self.spare,
                        &mut end,
                        carried.len() + BULK_WINDOW,
                        eof,
                        error,
                    );
                    next = Some((end, super::bulk::cut(&self.spare[..end], self.eof, components)));
                }
            });
            let parsed = match parsed.expect("the scope waits for the parse") {
                Ok(parsed) => parsed,
                Err(e) => {
                    let line = self.line + newlines(&segment[..e.offset]);
                    return Err(LexError { line, message: e.message });
                }
            };
            self.line += parsed.newlines as u32;
            need_separator = parsed.need_separator;
            pending = parsed.pieces;
            match next {
                None => {
                    self.pos += len + 1;
                    pending.into_iter().for_each(append);
                    return Ok(());
                }
                Some((end, next_cut)) => {
                    std::mem::swap(&mut self.buffer, &mut self.spare);
                    (self.pos, self.end, cut) = (0, end, next_cut);
                }
            }
        }
    }
}

/// Reads from `input` into `buffer[*end..]` until `*end` reaches `n` or the input ends
/// (`eof`; an I/O error is kept in `read_error` and ends the input too).
fn read_up_to(
    input: &mut dyn Read,
    buffer: &mut Vec<u8>,
    end: &mut usize,
    n: usize,
    eof: &mut bool,
    read_error: &mut Option<std::io::Error>,
) {
    if buffer.len() < n {
        buffer.resize(n, 0);
    }
    while *end < n && !*eof {
        match input.read(&mut buffer[*end..]) {
            Ok(0) => *eof = true,
            Ok(count) => *end += count,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => {
                *read_error = Some(e);
                *eof = true;
            }
        }
    }
}

/// `f32` from a number token as USD writes it.
pub fn parse_f32(token: &str) -> Option<f32> {
    parse_float(token)
}

/// `f64` from a number token as USD writes it.
pub fn parse_f64(token: &str) -> Option<f64> {
    parse_float(token)
}

/// USD writes `inf`, `-inf` and `nan`; Rust's parser accepts those and plain decimal forms but
/// also words like `infinity`, which USD does not write — accept only what USD does.
fn parse_float<T: std::str::FromStr>(token: &str) -> Option<T> {
    // A sign is pxr's only prefix, `-`: `+1.5` is a syntax error there (an exponent's `1e+2`
    // is not a prefix).
    if token.starts_with('+') {
        return None;
    }
    // Ending in a digit or '.', only decimal forms (which both accept) remain.
    if token.ends_with(|c: char| c.is_ascii_digit() || c == '.') {
        return token.parse().ok();
    }
    let body = token.strip_prefix(['-', '+']).unwrap_or(token);
    let alphabetic = body.bytes().any(|b| b.is_ascii_alphabetic() && b != b'e' && b != b'E');
    if alphabetic && body != "inf" && body != "nan" {
        return None;
    }
    token.parse().ok()
}

/// A byte as an error message shows it.
pub fn describe(byte: u8) -> String {
    if byte.is_ascii_graphic() {
        format!("'{}'", byte as char)
    } else {
        format!("byte 0x{byte:02x}")
    }
}

/// The read window's size, for tests that must span several windows.
#[cfg(test)]
pub fn tests_window() -> usize {
    WINDOW
}

/// A large array's read window in tests.
#[cfg(test)]
pub fn tests_bulk_window() -> usize {
    BULK_WINDOW
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip_and_bad_ones_name_their_line() {
        let mut lexer = Lexer::new(&b"  1.5e-3\n# comment\n -inf nan 7 1.2.3"[..]);
        assert_eq!(lexer.f32().unwrap(), 1.5e-3);
        assert_eq!(lexer.f32().unwrap(), f32::NEG_INFINITY);
        assert!(lexer.f32().unwrap().is_nan());
        assert_eq!(lexer.integer(IntType::Int).unwrap(), 7);
        let error = lexer.f32().unwrap_err();
        assert_eq!(error.line, 3);
        assert!(error.message.contains("1.2.3"), "{}", error.message);
    }

    #[test]
    fn strings_and_tokens_span_windows() {
        let text = format!("{}\"a\\\"b\" '''x\ny''' name:space", " ".repeat(WINDOW - 2));
        let mut lexer = Lexer::new(text.as_bytes());
        assert_eq!(lexer.string().unwrap(), "a\"b");
        assert_eq!(lexer.string().unwrap(), "x\ny");
        assert_eq!(lexer.identifier().unwrap(), "name:space");
        assert_eq!(lexer.line, 2);
    }
}
