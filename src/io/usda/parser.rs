//! Recursive-descent parser for `.usda` layers: layer metadata, prims (`def`/`over`/`class`)
//! with their metadata, attributes (default values and time samples), relationships and
//! dictionaries. Values coif can use (numbers, tokens) are kept typed by their declared USD type;
//! everything else is parsed for syntax and dropped. Composition arcs (sublayers, references,
//! payloads, inherits, variant sets and selections) are recorded for `io::usd_compose`.
use std::io::Read;

use glam::Vec3;

use super::bulk::Integer;
use super::integer::IntType;
use super::lexer::{describe, LexError, LexResult, Lexer};
use crate::io::usd_compose::arcs::{self, Arcs, AssetArc, LayerOffset, ListEdit, SubLayer};

/// A value of a declared type, flattened (tuples and matrices become runs of numbers).
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    F32(Vec<f32>),
    /// Arrays of 3-component float tuples (points, colours…), kept in the groom's own layout.
    Vec3(Vec<Vec3>),
    F64(Vec<f64>),
    Int(Vec<i64>),
    Text(Vec<String>),
    /// `None`: a blocked value.
    Blocked,
    /// A value coif does not read (parsed for syntax only).
    Ignored,
    /// A plain float array still in a crate file; the groom is read from such arrays straight
    /// into its own (see [`FileArrays`]). Only the crate reader's groom path makes these.
    InFile(FileArray),
}

/// Where a [`Value::InFile`] array lies in its file: `bytes` bytes at `offset`, `components`
/// `f32`s per element.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FileArray {
    pub offset: u64,
    pub bytes: usize,
    pub components: usize,
}

impl FileArray {
    pub fn elements(&self) -> usize {
        self.bytes / (4 * self.components.max(1))
    }
}

/// The file [`Value::InFile`] arrays are read from.
pub trait FileArrays {
    /// Appends `array`'s floats to `out`; an error says why it could not (`out` is then as it
    /// was).
    fn append_floats(&self, array: &FileArray, out: &mut Vec<f32>) -> std::result::Result<(), String>;
}

impl Value {
    /// Numbers as f32 (integers and doubles converted).
    pub fn to_f32(&self) -> Option<Vec<f32>> {
        match self {
            Value::F32(v) => Some(v.clone()),
            Value::Vec3(v) => Some(v.iter().flat_map(|p| p.to_array()).collect()),
            Value::F64(v) => Some(v.iter().map(|&x| x as f32).collect()),
            Value::Int(v) => Some(v.iter().map(|&x| x as f32).collect()),
            _ => None,
        }
    }

    /// [`Value::to_f32`], moving floats and vectors rather than copying them.
    pub fn into_f32(self) -> Option<Vec<f32>> {
        match self {
            Value::F32(v) => Some(v),
            Value::Vec3(v) => Some(bytemuck::allocation::cast_vec(v)),
            other => other.to_f32(),
        }
    }

    pub fn to_f64(&self) -> Option<Vec<f64>> {
        match self {
            Value::F32(v) => Some(v.iter().map(|&x| x as f64).collect()),
            Value::Vec3(v) => Some(v.iter().flat_map(|p| p.to_array()).map(f64::from).collect()),
            Value::F64(v) => Some(v.clone()),
            Value::Int(v) => Some(v.iter().map(|&x| x as f64).collect()),
            _ => None,
        }
    }
}

/// Element kind and component count of a USD value type (`point3f` → F32 × 3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    F32,
    /// IEEE half precision, held as `f32`s rounded to it (`half 70000` is `inf`, as pxr reads it).
    Half,
    F64,
    /// An integer or flag type (a `uint64` is stored as `i64` bits).
    Int(IntType),
    Text,
    Other,
}

pub fn type_info(type_name: &str) -> (Kind, usize) {
    // A trailing 2–4 is a tuple size only after a tuple's base: `int64` is one 64-bit integer,
    // not four `int6`s.
    let (base, components) = match type_name.as_bytes().last() {
        Some(&d @ b'2'..=b'4') if !matches!(type_name, "int64" | "uint64") => {
            (&type_name[..type_name.len() - 1], (d - b'0') as usize)
        }
        _ => (type_name, 1),
    };
    match (base, components) {
        ("float", _) => (Kind::F32, components),
        ("half", _) => (Kind::Half, components),
        ("double" | "timecode", _) => (Kind::F64, components),
        ("int" | "uint" | "int64" | "uint64" | "uchar" | "bool", _) => {
            (Kind::Int(IntType::of(base).expect("an integer type")), components)
        }
        ("string" | "token" | "asset", 1) => (Kind::Text, 1),
        ("quatf", 1) => (Kind::F32, 4),
        ("quath", 1) => (Kind::Half, 4),
        ("quatd", 1) => (Kind::F64, 4),
        ("matrix2d", 1) => (Kind::F64, 4),
        ("matrix3d", 1) => (Kind::F64, 9),
        ("matrix4d" | "frame4d", 1) => (Kind::F64, 16),
        _ => {
            // Roles over a float/double/half tuple: point3f, normal3d, color4h, texCoord2f…
            let roles = ["point", "normal", "vector", "color", "texCoord"];
            for role in roles {
                if let Some(rest) = type_name.strip_prefix(role) {
                    let bytes = rest.as_bytes();
                    if bytes.len() == 2 && (b'2'..=b'4').contains(&bytes[0]) {
                        let n = (bytes[0] - b'0') as usize;
                        match bytes[1] {
                            b'f' => return (Kind::F32, n),
                            b'h' => return (Kind::Half, n),
                            b'd' => return (Kind::F64, n),
                            _ => {}
                        }
                    }
                }
            }
            (Kind::Other, 1)
        }
    }
}

/// Where a spec was authored, for error messages: a line of a layer. On a composed stage the
/// specs come from several layers: `layer` indexes [`Layer::sources`] (0: the file read).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Site {
    pub layer: u16,
    /// 0 where lines mean nothing (a crate file).
    pub line: u32,
}

impl Site {
    /// A line of the file being read.
    pub fn line(line: u32) -> Site {
        Site { layer: 0, line }
    }
}

#[derive(Clone, Debug, Default)]
pub struct Attribute {
    pub name: String,
    /// The element type, as declared before any `[]`.
    pub type_name: String,
    /// Declared an array (`int[]`), not a scalar (`int`).
    pub array: bool,
    /// The declaration.
    pub site: Site,
    pub default: Option<Value>,
    /// The time samples kept (see [`KeptSamples`]): at most the two around the requested
    /// time, or the earliest one when no time was requested, or those of a span of time.
    pub samples: Vec<(f64, Value)>,
    pub interpolation: Option<String>,
    pub element_size: Option<i64>,
}

/// How a prim spec is introduced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Specifier {
    Def,
    /// Opinions only: defines nothing unless a weaker layer does.
    #[default]
    Over,
    /// Abstract: never part of the groom, only inherited from.
    Class,
}

#[derive(Clone, Debug, Default)]
pub struct Prim {
    pub type_name: String,
    pub name: String,
    pub site: Site,
    pub specifier: Specifier,
    /// The `active` opinion, if authored.
    pub active: Option<bool>,
    pub attributes: Vec<Attribute>,
    pub children: Vec<Prim>,
    /// Composition arcs the spec authors (none on a flattened or composed stage).
    pub arcs: Option<Box<Arcs>>,
}

impl Prim {
    pub fn attribute(&self, name: &str) -> Option<&Attribute> {
        self.attributes.iter().find(|a| a.name == name)
    }

    /// Part of the stage: `def`, and not deactivated.
    pub fn is_defined_and_active(&self) -> bool {
        self.specifier == Specifier::Def && self.active != Some(false)
    }

    /// Whether this spec or one below it authors composition.
    pub fn composes(&self) -> bool {
        self.arcs.is_some() || self.children.iter().any(Prim::composes)
    }
}

#[derive(Clone, Debug, Default)]
pub struct Layer {
    /// Lines in the file (the last line), for errors about the stage as a whole.
    pub lines: u32,
    /// The files a composed stage's specs come from ([`Site::layer`]); the first is the root
    /// layer. Empty for a layer as read: its sites are all in its own file.
    pub sources: Vec<std::path::PathBuf>,
    pub meters_per_unit: Option<f64>,
    pub up_axis: Option<String>,
    pub default_prim: Option<String>,
    pub sub_layers: Vec<SubLayer>,
    /// Layer metadata coif does not compose (`relocates`), named, with its line.
    pub refused: Option<(u32, String)>,
    /// The stage's frame range and rate (`startTimeCode`, `endTimeCode`, `timeCodesPerSecond`).
    pub timeline: LayerTimeline,
    pub prims: Vec<Prim>,
}

impl Layer {
    /// Whether the layer needs `io::usd_compose` before a groom can be read from it.
    pub fn composes(&self) -> bool {
        !self.sub_layers.is_empty() || self.refused.is_some() || self.prims.iter().any(Prim::composes)
    }
}

/// The timeline metadata a layer authors (each `None` when not authored).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LayerTimeline {
    pub start: Option<f64>,
    pub end: Option<f64>,
    pub per_second: Option<f64>,
    /// `framesPerSecond`: the time codes' rate where `timeCodesPerSecond` is not authored.
    pub frames_per_second: Option<f64>,
}

/// Time codes per second of a stage that authors no rate (pxr's fallback).
const USD_DEFAULT_TIME_CODES_PER_SECOND: f64 = 24.0;

impl LayerTimeline {
    /// Records one layer metadata field, if it is a timeline field.
    pub fn set(&mut self, key: &str, value: f64) {
        match key {
            "startTimeCode" => self.start = Some(value),
            "endTimeCode" => self.end = Some(value),
            "timeCodesPerSecond" => self.per_second = Some(value),
            "framesPerSecond" => self.frames_per_second = Some(value),
            _ => {}
        }
    }

    /// The authored frame range, when both ends are finite and `startTimeCode` < `endTimeCode`:
    /// without one a stage has no timeline to play, whatever its time samples.
    pub fn frame_range(&self) -> Option<(f64, f64)> {
        match (self.start, self.end) {
            (Some(start), Some(end)) if start.is_finite() && end.is_finite() && start < end => {
                Some((start, end))
            }
            _ => None,
        }
    }

    /// Time codes per second as USD resolves them: `timeCodesPerSecond`, else `framesPerSecond`,
    /// else 24; or, when the authored rate that applies is not a positive number, its key and
    /// value.
    pub fn checked_codes_per_second(&self) -> Result<f64, (&'static str, f64)> {
        let authored = match (self.per_second, self.frames_per_second) {
            (Some(rate), _) => ("timeCodesPerSecond", rate),
            (None, Some(rate)) => ("framesPerSecond", rate),
            (None, None) => return Ok(USD_DEFAULT_TIME_CODES_PER_SECOND),
        };
        if authored.1.is_finite() && authored.1 > 0.0 {
            Ok(authored.1)
        } else {
            Err(authored)
        }
    }

    /// [`checked_codes_per_second`](Self::checked_codes_per_second), with 24 where the authored
    /// rate is not a positive number (composition retimes by it, and pxr would divide by it).
    pub fn codes_per_second(&self) -> f64 {
        self.checked_codes_per_second().unwrap_or(USD_DEFAULT_TIME_CODES_PER_SECOND)
    }
}

#[derive(Debug)]
pub enum ParseError {
    Syntax(LexError),
    Io(std::io::Error),
}

impl From<LexError> for ParseError {
    fn from(error: LexError) -> Self {
        ParseError::Syntax(error)
    }
}

type ParseResult<T> = Result<T, ParseError>;

/// Metadata keys of composition, recorded in [`Arcs`] (or the layer's sublayers).
const COMPOSITION_KEYS: &[&str] = &[
    "references",
    "payload",
    "inherits",
    "specializes",
    "variantSets",
    "variants",
    "subLayers",
    "relocates",
];

/// A metadata value coif looks at.
enum Meta {
    Number(f64),
    Text(String),
    /// `{ … }`, and whether it holds no entry.
    Dictionary {
        empty: bool,
    },
    Other,
}

pub struct Parser<'a> {
    lexer: Lexer<'a>,
    kept: KeptSamples,
    /// Prims and bracketed values open around the current position: bounded by
    /// [`MAX_NESTING`], so no file can overflow the stack of this recursive-descent parser.
    depth: usize,
    /// Where the metadata being parsed records composition: a prim's arcs, the layer's
    /// sublayers, or nowhere (attribute metadata: parsed and dropped).
    arcs: Option<Arcs>,
    sub_layers: Option<Vec<SubLayer>>,
    refused: Option<(u32, String)>,
}

/// Nesting of prims and of bracketed values a layer may have (real stages nest a few dozen).
pub const MAX_NESTING: usize = 1000;

/// Which time samples a parse keeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum KeptSamples {
    /// The ones value resolution at a time needs (`None`: the earliest; see [`offer_sample`]).
    At(Option<f64>),
    /// Every one from the first time to the last, with the latest before them and the earliest
    /// after: what resolution at any time between needs (see [`Layer::at_time`]).
    Between(f64, f64),
}

/// Parses a whole layer. `time` selects which time samples are kept.
pub fn parse<'a>(input: impl Read + 'a, time: Option<f64>) -> ParseResult<Layer> {
    parse_layer(input, KeptSamples::At(time), false)
}

/// Parses a whole layer, keeping the time samples `kept` selects.
pub fn parse_keeping<'a>(input: impl Read + 'a, kept: KeptSamples) -> ParseResult<Layer> {
    parse_layer(input, kept, false)
}

/// Parses only the layer's metadata (units, up axis, timeline, sublayers), not its prims.
pub fn parse_header<'a>(input: impl Read + 'a) -> ParseResult<Layer> {
    parse_layer(input, KeptSamples::At(None), true)
}

fn parse_layer<'a>(input: impl Read + 'a, kept: KeptSamples, header_only: bool) -> ParseResult<Layer> {
    let mut parser =
        Parser { lexer: Lexer::new(input), kept, depth: 0, arcs: None, sub_layers: None, refused: None };
    let result = parser.layer(header_only);
    if let Some(error) = parser.lexer.take_read_error() {
        return Err(ParseError::Io(error));
    }
    result
}

impl Parser<'_> {
    fn layer(&mut self, header_only: bool) -> ParseResult<Layer> {
        if !self.lexer.starts_with(b"#usda ") {
            return Err(self.syntax("not a .usda file: the first line must be '#usda 1.0'"));
        }
        self.lexer.skip_line();
        let mut layer = Layer::default();
        if self.lexer.next_byte() == Some(b'(') {
            self.sub_layers = Some(Vec::new());
            self.metadata(|key, value, _| match (key, value) {
                ("metersPerUnit", Meta::Number(v)) => layer.meters_per_unit = Some(v),
                ("upAxis", Meta::Text(v)) => layer.up_axis = Some(v),
                ("defaultPrim", Meta::Text(v)) => layer.default_prim = Some(v),
                (key, Meta::Number(v)) => layer.timeline.set(key, v),
                _ => {}
            })?;
            layer.sub_layers = self.sub_layers.take().unwrap_or_default();
            layer.refused = self.refused.take();
        }
        while !header_only && !self.lexer.at_eof() {
            self.lexer.skip_ws();
            if self.lexer.at_eof() {
                break;
            }
            let word = self.lexer.identifier()?;
            match word.as_str() {
                "def" | "over" | "class" => layer.prims.push(self.prim(&word)?),
                _ => return Err(self.unknown(&word, "a prim ('def', 'over' or 'class')")),
            }
        }
        layer.lines = self.lexer.line;
        Ok(layer)
    }

    fn unknown(&self, word: &str, expected: &str) -> ParseError {
        ParseError::Syntax(LexError {
            line: self.lexer.line,
            message: format!("unknown syntax '{word}': expected {expected}"),
        })
    }

    fn syntax(&self, message: impl Into<String>) -> ParseError {
        ParseError::Syntax(LexError { line: self.lexer.line, message: message.into() })
    }

    /// A composition key's value, recorded where the current metadata keeps arcs.
    fn composition(&mut self, key: &str, edit: ListEdit) -> ParseResult<()> {
        let line = self.lexer.line;
        self.lexer.expect(b'=', &format!("'=' after '{key}'"))?;
        match key {
            "references" | "payload" => {
                let items = self.list(Self::asset_arc)?;
                if let Some(arcs) = self.arcs.as_mut() {
                    let op = if key == "payload" { &mut arcs.payloads } else { &mut arcs.references };
                    op.set(edit, items);
                }
            }
            "inherits" => {
                let items = self.list(|p| Ok(p.lexer.path()?))?;
                if let Some(arcs) = self.arcs.as_mut() {
                    arcs.inherits.set(edit, items);
                }
            }
            "variantSets" => {
                let items = self.list(|p| Ok(p.lexer.string()?))?;
                if let Some(arcs) = self.arcs.as_mut() {
                    arcs.variant_set_names.set(edit, items);
                }
            }
            "variants" => {
                let selections = self.selections()?;
                if let Some(arcs) = self.arcs.as_mut() {
                    arcs.selections = selections;
                }
            }
            "subLayers" => {
                let items = self.list(|p| {
                    let asset = p.lexer.asset()?;
                    let offset = if p.lexer.next_byte() == Some(b'(') {
                        p.layer_offset()?
                    } else {
                        Default::default()
                    };
                    Ok(SubLayer { asset, offset })
                })?;
                if let Some(sub_layers) = self.sub_layers.as_mut() {
                    *sub_layers = items;
                }
            }
            _ => {
                // `specializes`, `relocates`: parsed, and refused if the stage is composed.
                self.skip_value()?;
                let what = key.to_string();
                if let Some(arcs) = self.arcs.as_mut() {
                    arcs.refused.get_or_insert(what);
                } else if self.sub_layers.is_some() {
                    self.refused.get_or_insert((line, what));
                }
            }
        }
        Ok(())
    }

    /// `None`, one item, or `[item, …]`.
    fn list<T>(&mut self, mut item: impl FnMut(&mut Self) -> ParseResult<T>) -> ParseResult<Vec<T>> {
        if self.lexer.at_identifier() {
            let word = self.lexer.identifier()?;
            return if word == "None" {
                Ok(Vec::new())
            } else {
                Err(self.unknown(&word, "a list or 'None'"))
            };
        }
        if !self.lexer.eat(b'[') {
            return Ok(vec![item(self)?]);
        }
        let start = self.lexer.line;
        let mut items = Vec::new();
        loop {
            match self.lexer.next_byte() {
                Some(b']') => {
                    self.lexer.bump();
                    return Ok(items);
                }
                Some(b',') => self.lexer.bump(),
                None => {
                    return Err(self.syntax(format!(
                        "unexpected end of file: the list opened on line {start} is not closed"
                    )))
                }
                Some(_) => items.push(item(self)?),
            }
        }
    }

    /// `@asset@</Prim> (offset = 1; scale = 2)`, `@asset@` or `</Prim>`.
    fn asset_arc(&mut self) -> ParseResult<AssetArc> {
        let asset = if self.lexer.next_byte() == Some(b'@') { self.lexer.asset()? } else { String::new() };
        let prim_path = if asset.is_empty() || self.lexer.next_byte() == Some(b'<') {
            Some(self.lexer.path()?)
        } else {
            None
        };
        let offset =
            if self.lexer.next_byte() == Some(b'(') { self.layer_offset()? } else { Default::default() };
        Ok(AssetArc { asset, prim_path, offset })
    }

    /// `( offset = 1; scale = 2; customData = {…} )`: the offset and scale.
    fn layer_offset(&mut self) -> ParseResult<LayerOffset> {
        let mut offset = LayerOffset::default();
        self.lexer.expect(b'(', "'('")?;
        loop {
            match self.lexer.next_byte() {
                Some(b')') => {
                    self.lexer.bump();
                    return Ok(offset);
                }
                Some(b';' | b',') => self.lexer.bump(),
                None => return Err(self.syntax("unexpected end of file in a layer offset ('(' not closed)")),
                Some(_) => {
                    let key = self.lexer.identifier()?;
                    self.lexer.expect(b'=', &format!("'=' after '{key}'"))?;
                    match key.as_str() {
                        "offset" => offset.offset = self.lexer.f64()?,
                        "scale" => offset.scale = self.lexer.f64()?,
                        _ => self.skip_value()?,
                    }
                }
            }
        }
    }

    /// `{ string set = "variant" … }`.
    fn selections(&mut self) -> ParseResult<Vec<(String, String)>> {
        let start = self.lexer.line;
        self.lexer.expect(b'{', "'{' to open variant selections")?;
        let mut selections = Vec::new();
        loop {
            match self.lexer.next_byte() {
                Some(b'}') => {
                    self.lexer.bump();
                    return Ok(selections);
                }
                Some(b';' | b',') => self.lexer.bump(),
                None => {
                    return Err(self.syntax(format!(
                        "unexpected end of file: variant selections opened on line {start} are not closed"
                    )))
                }
                Some(_) => {
                    let kind = self.lexer.identifier()?;
                    if kind != "string" {
                        return Err(self.unknown(&kind, "'string' before a variant set name"));
                    }
                    let set = if matches!(self.lexer.next_byte(), Some(b'"' | b'\'')) {
                        self.lexer.string()?
                    } else {
                        self.lexer.identifier()?
                    };
                    self.lexer.expect(b'=', "'=' after the variant set name")?;
                    let variant = self.lexer.string()?;
                    selections.push((set, variant));
                }
            }
        }
    }

    /// `( key = value … )`: calls `seen` with every key and the value when it is a number or text.
    fn metadata(&mut self, mut seen: impl FnMut(&str, Meta, u32)) -> ParseResult<()> {
        self.lexer.expect(b'(', "'('")?;
        loop {
            match self.lexer.next_byte() {
                Some(b')') => {
                    self.lexer.bump();
                    return Ok(());
                }
                Some(b';') => self.lexer.bump(),
                Some(b'"' | b'\'') => {
                    self.lexer.string()?; // a bare string is the doc string
                }
                None => return Err(self.syntax("unexpected end of file in metadata ('(' not closed)")),
                Some(_) => {
                    let mut key = self.lexer.identifier()?;
                    let mut edit = ListEdit::Explicit;
                    if let Some(qualifier) = ListEdit::from_word(&key) {
                        edit = qualifier;
                        key = self.lexer.identifier()?;
                    }
                    if COMPOSITION_KEYS.contains(&key.as_str()) {
                        self.composition(&key, edit)?;
                        continue;
                    }
                    let line = self.lexer.line;
                    self.lexer.expect(b'=', &format!("'=' after '{key}'"))?;
                    let value = self.meta_value()?;
                    seen(&key, value, line);
                }
            }
        }
    }

    /// A metadata value: numbers and text are returned, anything else is skipped.
    fn meta_value(&mut self) -> ParseResult<Meta> {
        match self.lexer.next_byte() {
            Some(b'"' | b'\'') => Ok(Meta::Text(self.lexer.string()?)),
            _ if self.lexer.at_number() => Ok(Meta::Number(self.lexer.f64()?)),
            _ if self.lexer.at_identifier() => Ok(Meta::Text(self.lexer.identifier()?)),
            Some(b'{') => {
                let entries = self.nested(|parser| parser.skip_bracketed(b'{'))?;
                Ok(Meta::Dictionary { empty: entries == 0 })
            }
            _ => {
                self.skip_value()?;
                Ok(Meta::Other)
            }
        }
    }

    /// Runs `inner` one nesting level deeper, refusing more than [`MAX_NESTING`] levels.
    fn nested<T>(&mut self, inner: impl FnOnce(&mut Self) -> ParseResult<T>) -> ParseResult<T> {
        if self.depth >= MAX_NESTING {
            return Err(self.syntax(format!("prims or values nested deeper than {MAX_NESTING} levels")));
        }
        self.depth += 1;
        let result = inner(self);
        self.depth -= 1;
        result
    }

    /// Skips any value: number, word, string, path, asset, list, tuple or dictionary.
    fn skip_value(&mut self) -> ParseResult<()> {
        self.nested(Self::skip_value_inner)
    }

    fn skip_value_inner(&mut self) -> ParseResult<()> {
        match self.lexer.next_byte() {
            Some(b'"' | b'\'') => {
                self.lexer.string()?;
            }
            Some(b'<') => {
                self.lexer.path()?;
            }
            Some(b'@') => {
                self.lexer.asset()?;
            }
            Some(open @ (b'[' | b'(' | b'{')) => {
                self.skip_bracketed(open)?;
            }
            _ if self.lexer.at_number() => {
                self.lexer.f64()?;
            }
            _ if self.lexer.at_identifier() => {
                self.lexer.identifier()?;
            }
            Some(b) => return Err(self.syntax(format!("unknown syntax: unexpected {}", describe(b)))),
            None => return Err(self.syntax("unexpected end of file: expected a value")),
        }
        Ok(())
    }

    /// Skips a list, tuple or dictionary opening with `open`; how many values it held.
    fn skip_bracketed(&mut self, open: u8) -> ParseResult<usize> {
        let close = match open {
            b'[' => b']',
            b'(' => b')',
            _ => b'}',
        };
        let start = self.lexer.line;
        self.lexer.bump();
        let mut values = 0;
        loop {
            match self.lexer.next_byte() {
                Some(b) if b == close => {
                    self.lexer.bump();
                    return Ok(values);
                }
                // A dictionary's `double[] name = [1, 2]`: the type's `[]` is skipped as an
                // empty list, the value as a list.
                Some(b',' | b'=' | b':' | b';') => self.lexer.bump(),
                None => {
                    return Err(self.syntax(format!(
                        "unexpected end of file: '{}' opened on line {start} is not closed",
                        open as char
                    )))
                }
                Some(_) => {
                    self.skip_value()?;
                    values += 1;
                }
            }
        }
    }

    /// After `def`/`over`/`class`: `[Type] "name" [( metadata )] { body }`.
    fn prim(&mut self, specifier: &str) -> ParseResult<Prim> {
        self.nested(|parser| parser.prim_inner(specifier))
    }

    fn prim_inner(&mut self, specifier: &str) -> ParseResult<Prim> {
        let line = self.lexer.line;
        let specifier = match specifier {
            "def" => Specifier::Def,
            "class" => Specifier::Class,
            _ => Specifier::Over,
        };
        let mut prim = Prim { site: Site::line(line), specifier, ..Default::default() };
        if self.lexer.at_identifier() {
            prim.type_name = self.lexer.identifier()?;
        }
        prim.name = self.lexer.string()?;
        self.spec_body(&mut prim)?;
        Ok(prim)
    }

    /// `[( metadata )] { statements }` of a prim or a variant.
    fn spec_body(&mut self, prim: &mut Prim) -> ParseResult<()> {
        let line = self.lexer.line;
        if self.lexer.next_byte() == Some(b'(') {
            let mut active = None;
            let mut clips = false;
            let outer = self.arcs.replace(Arcs::default());
            let result = self.metadata(|key, value, _| {
                if key == "active" {
                    active = Some(
                        !matches!(value, Meta::Text(ref t) if t == "false")
                            && !matches!(value, Meta::Number(n) if n == 0.0),
                    );
                }
                if key == arcs::VALUE_CLIPS && !matches!(value, Meta::Dictionary { empty: true }) {
                    clips = true;
                }
            });
            let mut arcs = std::mem::replace(&mut self.arcs, outer).unwrap_or_default();
            result?;
            if clips {
                arcs.refused.get_or_insert(arcs::VALUE_CLIPS.to_string());
            }
            prim.active = active;
            if !arcs.is_empty() {
                prim.arcs = Some(Box::new(arcs));
            }
        }
        self.lexer.expect(b'{', &format!("'{{' to open prim \"{}\"", prim.name))?;
        loop {
            match self.lexer.next_byte() {
                Some(b'}') => {
                    self.lexer.bump();
                    return Ok(());
                }
                Some(b';') => self.lexer.bump(),
                None => {
                    return Err(self.syntax(format!(
                        "unexpected end of file: prim \"{}\" opened on line {line} is not closed",
                        prim.name
                    )))
                }
                Some(_) => self.prim_statement(prim)?,
            }
        }
    }

    fn prim_statement(&mut self, prim: &mut Prim) -> ParseResult<()> {
        let mut word = self.lexer.identifier()?;
        match word.as_str() {
            "def" | "over" | "class" => {
                let child = self.prim(&word)?;
                prim.children.push(child);
                return Ok(());
            }
            "variantSet" => return self.nested(|parser| parser.variant_set(prim)),
            "reorder" => {
                self.lexer.identifier()?;
                self.lexer.expect(b'=', "'='")?;
                return self.skip_value();
            }
            _ => {}
        }
        while matches!(
            word.as_str(),
            "custom" | "uniform" | "varying" | "config" | "add" | "prepend" | "append" | "delete"
        ) {
            word = self.lexer.identifier()?;
        }
        if word == "rel" {
            self.lexer.identifier()?;
            if self.lexer.eat(b'.') {
                self.lexer.identifier()?;
            }
            if self.lexer.eat(b'=') {
                self.skip_value()?;
            }
            if self.lexer.next_byte() == Some(b'(') {
                self.metadata(|_, _, _| {})?;
            }
            return Ok(());
        }
        self.attribute(prim, word)
    }

    /// After `variantSet`: `"set" = { "variant" [( metadata )] { body } … }`.
    fn variant_set(&mut self, prim: &mut Prim) -> ParseResult<()> {
        let start = self.lexer.line;
        let name = self.lexer.string()?;
        self.lexer.expect(b'=', "'=' after the variant set name")?;
        self.lexer.expect(b'{', "'{' to open the variant set")?;
        let mut variants = Vec::new();
        loop {
            match self.lexer.next_byte() {
                Some(b'}') => {
                    self.lexer.bump();
                    break;
                }
                None => {
                    return Err(self.syntax(format!(
                        "unexpected end of file: variant set \"{name}\" opened on line {start} is not closed"
                    )))
                }
                Some(_) => {
                    let line = self.lexer.line;
                    let mut variant =
                        Prim { site: Site::line(line), name: self.lexer.string()?, ..Default::default() };
                    self.spec_body(&mut variant)?;
                    variants.push(variant);
                }
            }
        }
        prim.arcs.get_or_insert_default().variant_set(&name).variants.extend(variants);
        Ok(())
    }

    /// After the type name: `[[]] name[.timeSamples|.connect|.spline] [= value] [( metadata )]`.
    fn attribute(&mut self, prim: &mut Prim, type_name: String) -> ParseResult<()> {
        let line = self.lexer.line;
        let array = if self.lexer.eat(b'[') {
            self.lexer.expect(b']', "']' after '['")?;
            true
        } else {
            false
        };
        if !self.lexer.at_identifier() {
            let found = self.lexer.next_byte();
            return Err(match found {
                Some(b) => {
                    self.unknown(&format!("{type_name} {}", describe(b)), "an attribute name after the type")
                }
                None => self.syntax("unexpected end of file: expected an attribute name"),
            });
        }
        let name = self.lexer.identifier()?;
        let suffix = if self.lexer.peek() == Some(b'.') {
            self.lexer.bump();
            Some(self.lexer.identifier()?)
        } else {
            None
        };
        let (kind, components) = type_info(&type_name);
        let keep = wanted(&name);
        let index = match prim.attributes.iter().position(|a| a.name == name) {
            Some(index) => index,
            None => {
                prim.attributes.push(Attribute {
                    name: name.clone(),
                    type_name: type_name.clone(),
                    array,
                    site: Site::line(line),
                    ..Default::default()
                });
                prim.attributes.len() - 1
            }
        };
        if self.lexer.eat(b'=') {
            // A value's errors name its attribute (an out-of-range `uchar` among many).
            let named = |error| match error {
                ParseError::Syntax(LexError { line, message }) => {
                    ParseError::Syntax(LexError { line, message: format!("attribute '{name}': {message}") })
                }
                other => other,
            };
            match suffix.as_deref() {
                None | Some("default") => {
                    let reserve = if keep { vertex_hint(prim) } else { 0 };
                    let value = self.typed_value(kind, components, array, keep, reserve).map_err(named)?;
                    prim.attributes[index].default = Some(value);
                    prim.attributes[index].site = Site::line(line);
                }
                Some("timeSamples") => {
                    let reserve = if keep { vertex_hint(prim) } else { 0 };
                    self.time_samples(&mut prim.attributes[index], kind, components, array, keep, reserve)
                        .map_err(named)?
                }
                Some("connect") | Some("spline") => self.skip_value()?,
                Some(other) => {
                    return Err(
                        self.unknown(&format!("{name}.{other}"), "'.timeSamples', '.connect' or '.spline'")
                    )
                }
            }
        }
        if self.lexer.next_byte() == Some(b'(') {
            let attribute = &mut prim.attributes[index];
            let mut element_size = None;
            self.metadata(|key, value, line| match (key, value) {
                ("interpolation", Meta::Text(v)) => attribute.interpolation = Some(v),
                ("elementSize", Meta::Number(n)) => element_size = Some((n, line)),
                _ => {}
            })?;
            if let Some((n, line)) = element_size {
                // An `int`, read as pxr reads one (1e12 and nan refuse the layer).
                let size = IntType::Int.truncated(n).ok_or_else(|| {
                    let message = format!(
                        "attribute '{name}': elementSize = {} is not an int",
                        crate::validate::shortest(n)
                    );
                    ParseError::Syntax(LexError { line, message })
                })?;
                prim.attributes[index].element_size = Some(size);
            }
        }
        Ok(())
    }

    /// `{ time: value, … }`, keeping only the samples the requested time needs.
    fn time_samples(
        &mut self,
        attribute: &mut Attribute,
        kind: Kind,
        components: usize,
        array: bool,
        keep: bool,
        reserve: usize,
    ) -> ParseResult<()> {
        let start = self.lexer.line;
        self.lexer.expect(b'{', "'{' to open time samples")?;
        loop {
            match self.lexer.next_byte() {
                Some(b'}') => {
                    self.lexer.bump();
                    return Ok(());
                }
                Some(b',') => self.lexer.bump(),
                None => {
                    return Err(self.syntax(format!(
                        "unexpected end of file: time samples opened on line {start} are not closed"
                    )))
                }
                Some(_) => {
                    let time = self.lexer.f64()?;
                    self.lexer.expect(b':', "':' after the sample time")?;
                    let value = self.typed_value(kind, components, array, keep, reserve)?;
                    if keep {
                        match self.kept {
                            KeptSamples::At(at) => offer_sample(&mut attribute.samples, at, time, value),
                            KeptSamples::Between(first, last) => {
                                offer_sample_between(&mut attribute.samples, first, last, time, value)
                            }
                        }
                    }
                }
            }
        }
    }

    /// A value of the declared type: a scalar or tuple, or an array of them, or `None`.
    /// `reserve`: elements the array is likely to hold (so large arrays are allocated once).
    fn typed_value(
        &mut self,
        kind: Kind,
        components: usize,
        array: bool,
        keep: bool,
        reserve: usize,
    ) -> ParseResult<Value> {
        if kind == Kind::Half {
            let line = self.lexer.line;
            let value = self.typed_value(Kind::F32, components, array, keep, reserve)?;
            let value = match value {
                Value::F32(v) => Value::F32(v.into_iter().map(round_to_half).collect()),
                Value::Vec3(v) => Value::Vec3(v.into_iter().map(|p| p.map(round_to_half)).collect()),
                other => other,
            };
            // pxr reads these as inf, which coif refuses in any attribute: say why here.
            let floats = match &value {
                Value::F32(v) => v.as_slice(),
                Value::Vec3(v) => bytemuck::cast_slice(v),
                _ => &[],
            };
            if floats.iter().any(|x| x.is_infinite()) {
                return Err(ParseError::Syntax(LexError {
                    line,
                    message: "a half value is beyond half's range, ±65504 (pxr reads it as inf)".into(),
                }));
            }
            return Ok(value);
        }
        if self.lexer.at_identifier() && !self.lexer.at_number() {
            let word = self.lexer.identifier()?;
            if word == "None" {
                return Ok(Value::Blocked);
            }
            if kind == Kind::Text && !array {
                return Ok(Value::Text(vec![word]));
            }
            if kind == Kind::Int(IntType::Bool) && !array && (word == "true" || word == "false") {
                return Ok(Value::Int(vec![(word == "true") as i64]));
            }
            if kind == Kind::Other {
                return Ok(Value::Ignored);
            }
            return Err(self.unknown(&word, "a value"));
        }
        if kind == Kind::Other || (kind == Kind::Text && !keep) {
            self.skip_value()?;
            return Ok(Value::Ignored);
        }
        if array && components <= 4 && matches!(kind, Kind::F32 | Kind::Int(_)) {
            self.lexer.expect(b'[', "'[' to open an array")?;
            let value = match (kind, components) {
                (Kind::F32, 3) => {
                    let mut data = Vec::with_capacity(reserve);
                    self.lexer
                        .bulk_array(3, |v: Vec<f32>| data.extend(v.chunks_exact(3).map(Vec3::from_slice)))?;
                    data.shrink_to_fit();
                    Value::Vec3(data)
                }
                (Kind::F32, _) => {
                    let mut data = Vec::with_capacity(reserve * components);
                    self.lexer.bulk_array(components, |v: Vec<f32>| data.extend_from_slice(&v))?;
                    data.shrink_to_fit();
                    Value::F32(data)
                }
                (Kind::Int(int_type), _) => Value::Int(self.integer_array(int_type, components)?),
                _ => unreachable!("only floats and integers are read in bulk"),
            };
            return Ok(if keep { value } else { Value::Ignored });
        }
        let value = match kind {
            Kind::F32 => {
                let mut data = Vec::with_capacity(if array { reserve * components } else { components });
                self.numbers(components, array, &mut |lexer| {
                    data.push(lexer.f32()?);
                    Ok(())
                })?;
                data.shrink_to_fit();
                Value::F32(data)
            }
            Kind::F64 => {
                let mut data = Vec::new();
                self.numbers(components, array, &mut |lexer| {
                    data.push(lexer.f64()?);
                    Ok(())
                })?;
                Value::F64(data)
            }
            Kind::Int(int_type) => {
                let mut data = Vec::new();
                self.numbers(components, array, &mut |lexer| {
                    data.push(lexer.integer(int_type)?);
                    Ok(())
                })?;
                Value::Int(data)
            }
            Kind::Text => {
                let mut data = Vec::new();
                if array {
                    self.lexer.expect(b'[', "'[' to open an array")?;
                    loop {
                        match self.lexer.next_byte() {
                            Some(b']') => {
                                self.lexer.bump();
                                break;
                            }
                            Some(b',') => self.lexer.bump(),
                            Some(b'@') => data.push(self.lexer.asset()?),
                            _ => data.push(self.lexer.string()?),
                        }
                    }
                } else if self.lexer.next_byte() == Some(b'@') {
                    data.push(self.lexer.asset()?);
                } else {
                    data.push(self.lexer.string()?);
                }
                Value::Text(data)
            }
            Kind::Other | Kind::Half => unreachable!("handled above"),
        };
        Ok(if keep { value } else { Value::Ignored })
    }

    /// After an array's `[`: its values of integer type `int_type`, read in bulk.
    fn integer_array(&mut self, int_type: IntType, components: usize) -> ParseResult<Vec<i64>> {
        fn read<const T: u8>(lexer: &mut Lexer, components: usize) -> LexResult<Vec<i64>> {
            let mut data = Vec::new();
            lexer.bulk_array(components, |v: Vec<Integer<T>>| data.extend(v.iter().map(|i| i.0)))?;
            Ok(data)
        }
        let lexer = &mut self.lexer;
        Ok(match int_type {
            IntType::Bool => read::<{ IntType::Bool.code() }>(lexer, components),
            IntType::UChar => read::<{ IntType::UChar.code() }>(lexer, components),
            IntType::Int => read::<{ IntType::Int.code() }>(lexer, components),
            IntType::UInt => read::<{ IntType::UInt.code() }>(lexer, components),
            IntType::Int64 => read::<{ IntType::Int64.code() }>(lexer, components),
            IntType::UInt64 => read::<{ IntType::UInt64.code() }>(lexer, components),
        }?)
    }

    /// Numbers of a value with `components` per element, as a scalar/tuple or an array of them.
    fn numbers(
        &mut self,
        components: usize,
        array: bool,
        read: &mut impl FnMut(&mut Lexer) -> LexResult<()>,
    ) -> ParseResult<()> {
        if !array {
            return self.element(components, read);
        }
        let start = self.lexer.line;
        self.lexer.expect(b'[', "'[' to open an array")?;
        if self.lexer.eat(b']') {
            return Ok(());
        }
        loop {
            self.element(components, read)?;
            self.lexer.skip_ws();
            match self.lexer.peek() {
                Some(b',') => {
                    self.lexer.bump();
                    if self.lexer.eat(b']') {
                        return Ok(());
                    }
                }
                Some(b']') => {
                    self.lexer.bump();
                    return Ok(());
                }
                Some(b) => {
                    return Err(self.syntax(format!(
                        "expected ',' or ']' in the array opened on line {start}, found {}",
                        describe(b)
                    )))
                }
                None => {
                    return Err(self.syntax(format!(
                        "unexpected end of file: the array opened on line {start} is not closed"
                    )))
                }
            }
        }
    }

    /// One element: a number, or a tuple of exactly `components` numbers (nested for matrices).
    fn element(
        &mut self,
        components: usize,
        read: &mut impl FnMut(&mut Lexer) -> LexResult<()>,
    ) -> ParseResult<()> {
        if components == 1 {
            read(&mut self.lexer)?;
            return Ok(());
        }
        let line = self.lexer.line;
        let count = self.tuple(read)?;
        if count != components {
            return Err(ParseError::Syntax(LexError {
                line,
                message: format!("expected {components} numbers in a tuple, found {count}"),
            }));
        }
        Ok(())
    }

    /// `( n, n, … )` or nested tuples; returns how many numbers it held.
    fn tuple(&mut self, read: &mut impl FnMut(&mut Lexer) -> LexResult<()>) -> ParseResult<usize> {
        self.lexer.expect(b'(', "'(' to open a tuple")?;
        let mut count = 0;
        loop {
            if self.lexer.next_byte() == Some(b'(') {
                count += self.nested(|parser| parser.tuple(read))?;
            } else {
                read(&mut self.lexer)?;
                count += 1;
            }
            self.lexer.skip_ws();
            match self.lexer.peek() {
                Some(b',') => {
                    self.lexer.bump();
                    if self.lexer.eat(b')') {
                        return Ok(count);
                    }
                }
                Some(b')') => {
                    self.lexer.bump();
                    return Ok(count);
                }
                Some(b) => {
                    return Err(self.syntax(format!("expected ',' or ')' in a tuple, found {}", describe(b))))
                }
                None => return Err(self.syntax("unexpected end of file inside a tuple")),
            }
        }
    }
}

/// `x` rounded to the nearest IEEE half (ties to even), as pxr reads a `half` value: past
/// 65504 by half a step or more it is infinite; below 2^-14 a multiple of 2^-24.
fn round_to_half(x: f32) -> f32 {
    const SMALLEST_NORMAL: f32 = 6.103_515_6e-5; // 2^-14
    const SUBNORMAL_STEP: f32 = 5.960_464_5e-8; // 2^-24
    if !x.is_finite() {
        x
    } else if x.abs() >= 65520.0 {
        f32::INFINITY.copysign(x)
    } else if x.abs() < SMALLEST_NORMAL {
        (x / SUBNORMAL_STEP).round_ties_even() * SUBNORMAL_STEP
    } else {
        // Keep 10 of the 23 fraction bits, rounding the 13 dropped ties to even.
        let bits = x.to_bits();
        let rounding = 0x0fff + ((bits >> 13) & 1);
        f32::from_bits((bits + rounding) & !0x1fff)
    }
}

/// Vertices the prim's `curveVertexCounts` announce (0 if not read yet), capped so a hostile
/// count cannot make the parser reserve more than a plausible array.
fn vertex_hint(prim: &Prim) -> usize {
    const CAP: usize = 1 << 25;
    match prim.attribute("curveVertexCounts").and_then(|a| a.default.as_ref()) {
        Some(Value::Int(counts)) => {
            counts.iter().map(|&c| c.clamp(0, CAP as i64) as usize).sum::<usize>().min(CAP)
        }
        _ => 0,
    }
}

/// Attributes whose values coif uses (the groom's curves, and the cameras and lights a render
/// reads: `UsdGeom.Camera` lens attributes, `UsdLux` `inputs:`); others are checked for syntax and
/// dropped.
pub fn wanted(name: &str) -> bool {
    matches!(
        name,
        "curveVertexCounts"
            | "points"
            | "widths"
            | "type"
            | "basis"
            | "wrap"
            // NurbsCurves (Maya's USD export of nurbsCurves).
            | "order"
            | "knots"
            | "pointWeights"
            | "purpose"
            | "visibility"
            | "velocities"
            | "accelerations"
            | "xformOpOrder"
            // Meshes (a scalp or head beside the curves).
            | "faceVertexCounts"
            | "faceVertexIndices"
            | "holeIndices"
            | "orientation"
            | "normals"
            // Cameras (the render's shot).
            | "projection"
            | "focalLength"
            | "horizontalAperture"
            | "verticalAperture"
            | "horizontalApertureOffset"
            | "verticalApertureOffset"
    ) || name.starts_with("primvars:")
        || name.starts_with("xformOp:")
        || name.starts_with("inputs:")
}

/// Keeps, among all samples offered, the ones value resolution at `requested` needs: with no
/// requested time the earliest sample; otherwise the latest at or before it and the earliest after.
/// Of samples at equal times the last offered is kept, as in pxr (a later key replaces an
/// earlier one).
pub fn offer_sample(kept: &mut Vec<(f64, Value)>, requested: Option<f64>, time: f64, value: Value) {
    match requested {
        None => {
            if kept.first().is_none_or(|(t, _)| time <= *t) {
                kept.clear();
                kept.push((time, value));
            }
        }
        Some(at) => {
            let before = |t: f64| t <= at;
            let slot = kept.iter().position(|(t, _)| before(*t) == before(time));
            match slot {
                None => kept.push((time, value)),
                Some(i) => {
                    let better = if before(time) { time >= kept[i].0 } else { time <= kept[i].0 };
                    if better {
                        kept[i] = (time, value);
                    }
                }
            }
            kept.sort_by(|a, b| a.0.total_cmp(&b.0));
        }
    }
}

/// Keeps, among all samples offered, every one from `first` to `last` (in the order offered),
/// the latest before `first` and the earliest after `last` (the last offered of equal times).
fn offer_sample_between(kept: &mut Vec<(f64, Value)>, first: f64, last: f64, time: f64, value: Value) {
    if first <= time && time <= last {
        kept.push((time, value));
        return;
    }
    let before = time < first;
    match kept.iter().position(|(t, _)| if before { *t < first } else { *t > last || t.is_nan() }) {
        None => kept.push((time, value)),
        Some(i) => {
            let better = if before { time >= kept[i].0 } else { time <= kept[i].0 };
            if better {
                kept[i] = (time, value);
            }
        }
    }
}

impl Attribute {
    /// This attribute with the samples value resolution at `time` needs, chosen by
    /// [`offer_sample`] (offered their indices, so only the chosen values are cloned).
    fn at_time(&self, time: f64) -> Attribute {
        let mut chosen = Vec::new();
        for (k, (t, _)) in self.samples.iter().enumerate() {
            offer_sample(&mut chosen, Some(time), *t, Value::Int(vec![k as i64]));
        }
        let samples = chosen
            .into_iter()
            .map(|(_, index)| {
                let Value::Int(k) = index else { unreachable!("placeholders are indices") };
                self.samples[k[0] as usize].clone()
            })
            .collect();
        Attribute {
            name: self.name.clone(),
            type_name: self.type_name.clone(),
            array: self.array,
            site: self.site,
            default: self.default.clone(),
            samples,
            interpolation: self.interpolation.clone(),
            element_size: self.element_size,
        }
    }
}

impl Prim {
    fn at_time(&self, time: f64) -> Prim {
        Prim {
            type_name: self.type_name.clone(),
            name: self.name.clone(),
            site: self.site,
            specifier: self.specifier,
            active: self.active,
            attributes: self.attributes.iter().map(|a| a.at_time(time)).collect(),
            children: self.children.iter().map(|c| c.at_time(time)).collect(),
            arcs: self.arcs.clone(),
        }
    }
}

impl Layer {
    /// This layer as a parse for `time` would give it, from one that kept the samples of a span
    /// holding `time` ([`KeptSamples::Between`]): the frames of an animation are read from one
    /// parse of the file, not one each.
    pub fn at_time(&self, time: f64) -> Layer {
        Layer {
            lines: self.lines,
            sources: self.sources.clone(),
            meters_per_unit: self.meters_per_unit,
            up_axis: self.up_axis.clone(),
            default_prim: self.default_prim.clone(),
            sub_layers: self.sub_layers.clone(),
            refused: self.refused.clone(),
            timeline: self.timeline,
            prims: self.prims.iter().map(|p| p.at_time(time)).collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn type_info_reads_64_bit_integers_as_one_integer() {
        assert_eq!(type_info("int64"), (Kind::Int(IntType::Int64), 1));
        assert_eq!(type_info("uint64"), (Kind::Int(IntType::UInt64), 1));
        assert_eq!(type_info("int4"), (Kind::Int(IntType::Int), 4));
        assert_eq!(type_info("half2"), (Kind::Half, 2));
        assert_eq!(type_info("point3f"), (Kind::F32, 3));
    }

    /// A stage whose points span many read windows, with comments holding `)`, `,` and `]`.
    fn big_stage(bad_at: Option<usize>) -> (String, Vec<Vec3>, usize) {
        let mut text = String::from("#usda 1.0\ndef BasisCurves \"C\"\n{\n    point3f[] points = [");
        let mut points = Vec::new();
        let mut bad_line = 0;
        for i in 0..200_000 {
            let p = Vec3::new(i as f32 * 0.001, -(i as f32) / 3.0, 1.0 / (i as f32 + 1.0));
            points.push(p);
            if i > 0 {
                text.push_str(", ");
            }
            if i % 1000 == 0 {
                text.push_str("# a comment with ), ] and , inside\n");
            }
            if Some(i) == bad_at {
                bad_line = text.matches('\n').count() + 1;
                text.push_str("(1, 2, 3x)");
            } else {
                text.push_str(&format!("({}, {}, {})", p.x, p.y, p.z));
            }
        }
        text.push_str("]\n    float x = 1\n}\n");
        (text, points, bad_line)
    }

    #[test]
    fn large_arrays_parse_across_windows_and_threads_exactly() {
        let (text, points, _) = big_stage(None);
        assert!(text.len() > 4 * super::super::lexer::tests_window());
        let layer = parse(text.as_bytes(), None).unwrap();
        let attribute = layer.prims[0].attribute("points").unwrap();
        assert_eq!(attribute.default, Some(Value::Vec3(points)));
        assert_eq!(layer.lines, text.matches('\n').count() as u32 + 1);
    }

    #[test]
    fn an_error_deep_in_a_large_array_names_its_line() {
        let (text, _, line) = big_stage(Some(150_001));
        match parse(text.as_bytes(), None) {
            Err(ParseError::Syntax(e)) => {
                assert_eq!(e.line as usize, line, "{}", e.message);
                assert!(e.message.contains("3x"), "{}", e.message);
            }
            other => panic!("expected a syntax error, got {other:?}"),
        }
    }

    #[test]
    fn time_samples_keep_only_what_the_requested_time_needs() {
        let mut kept = Vec::new();
        for t in [3.0, 1.0, 4.0, 2.0] {
            offer_sample(&mut kept, Some(2.5), t, Value::F32(vec![t as f32]));
        }
        assert_eq!(kept.iter().map(|(t, _)| *t).collect::<Vec<_>>(), vec![2.0, 3.0]);
        let mut earliest = Vec::new();
        for t in [3.0, 1.0, 4.0] {
            offer_sample(&mut earliest, None, t, Value::F32(vec![t as f32]));
        }
        assert_eq!(earliest.iter().map(|(t, _)| *t).collect::<Vec<_>>(), vec![1.0]);
    }

    /// A layer parsed once for a span of time, read at a time within it, is the layer a parse for
    /// that time gives (the control): samples out of order, at equal times, before and after the
    /// span, on points, widths and a transform; times on, between and at the ends of samples.
    #[test]
    fn a_layer_kept_for_a_span_reads_at_each_time_as_a_parse_for_that_time() {
        let points = |x: f32| format!("[({x}, 0, 0), ({x}, 1, 0)]");
        let text = format!(
            "#usda 1.0\n(\n    startTimeCode = 1\n    endTimeCode = 9\n)\n\n\
             def Xform \"G\"\n{{\n    double3 xformOp:translate.timeSamples = {{ 8: (0, 2, 0), -1: (0, 1, 0) }}\n    \
             uniform token[] xformOpOrder = [\"xformOp:translate\"]\n    \
             def BasisCurves \"C\"\n    {{\n        int[] curveVertexCounts = [2]\n        \
             point3f[] points.timeSamples = {{ 7: {}, -3: {}, 2.5: {}, 2.5: {}, 12: {}, 4: {}, 20: {}, 0.5: {}, 9: {} }}\n        \
             float[] widths = [0.1, 0.1]\n        float[] widths.timeSamples = {{ 5: [0.2, 0.3] }}\n    }}\n}}\n",
            points(7.0),
            points(-3.0),
            points(2.5),
            points(2.6),
            points(12.0),
            points(4.0),
            points(20.0),
            points(0.5),
            points(9.0)
        );
        let span = parse_keeping(text.as_bytes(), KeptSamples::Between(1.0, 9.0)).unwrap();
        let kept = &span.prims[0].children[0].attribute("points").unwrap().samples;
        let mut times: Vec<f64> = kept.iter().map(|(t, _)| *t).collect();
        times.sort_by(f64::total_cmp);
        assert_eq!(times, [0.5, 2.5, 2.5, 4.0, 7.0, 9.0, 12.0], "the span's samples, and one on each side");
        for time in [1.0, 1.5, 2.5, 3.0, 4.0, 5.0, 6.9, 7.0, 8.0, 8.99, 9.0] {
            let at = parse(text.as_bytes(), Some(time)).unwrap();
            assert_eq!(format!("{:?}", span.at_time(time)), format!("{at:?}"), "time {time}");
        }
    }
}
