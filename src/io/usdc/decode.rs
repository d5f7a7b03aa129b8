//! Reading a crate file: the table of contents and structural sections are parsed and checked
//! (every count against the bytes that could hold it, every index against its table, the path
//! tree for repeats and cycles), then specs become the `.usda` parser's layer model and the
//! `.usda` reader builds the groom. Only the values the groom uses are decoded, and of time
//! samples only those the requested time needs.
use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;

use super::compress::{decompress_ints, lz4_decompress, CodedInt};
use super::format::{
    rep, SpecType, Type, BOOTSTRAP_SIZE, MAGIC, MIN_COMPRESSED_ARRAY, SPECIFIER_CLASS, SPECIFIER_DEF,
};
use crate::error::{Error, Result};
use crate::io::usd_compose::arcs::{self, Arcs, AssetArc, LayerOffset, ListOp, SubLayer};
use crate::io::usda::{self, Attribute, Layer, LayerTimeline, Prim, Specifier, Value};
use crate::io::ImportOptions;

pub use crate::io::usda::ReadOutcome;

type Checked<T> = std::result::Result<T, String>;

/// Prim nesting deeper than this is refused (the tree is walked recursively).
const MAX_DEPTH: usize = 512;

pub fn read(
    bytes: &[u8],
    file: Option<&std::fs::File>,
    path: &Path,
    options: &ImportOptions,
    time: Option<f64>,
) -> Result<ReadOutcome> {
    let bad = |message: String| Error::format(path, format!("crate file: {message}"));
    let mut crate_file = Crate::parse(bytes).map_err(bad)?;
    crate_file.file = file;
    // Points and widths stay in the file until the groom has a place for them, so they are
    // copied once, from the file, however many prims there are.
    crate_file.leave_in_file = true;
    let layer = crate_file.layer(time).map_err(bad)?;
    if layer.composes() {
        // Composition reads the layer as any other: with every value decoded.
        crate_file.leave_in_file = false;
        return Ok(ReadOutcome::NeedsComposition(Box::new(crate_file.layer(time).map_err(bad)?)));
    }
    usda::groom_from_layer_in(layer, Some(&crate_file), path, options, time)
        .map(|(groom, warnings)| ReadOutcome::Groom(groom, warnings))
        .map_err(unline)
}

/// The layer model's line numbers mean nothing in a binary file.
pub(crate) fn unline(error: Error) -> Error {
    match error {
        Error::Format { path, message } => {
            Error::Format { message: message.strip_prefix("line 0: ").unwrap_or(&message).to_string(), path }
        }
        other => other,
    }
}

/// The layer model of crate-file bytes, composition arcs recorded, not resolved.
pub(crate) fn read_layer(
    bytes: &[u8],
    file: Option<&std::fs::File>,
    path: &Path,
    time: Option<f64>,
) -> Result<Layer> {
    let bad = |message: String| Error::format(path, format!("crate file: {message}"));
    let mut crate_file = Crate::parse(bytes).map_err(bad)?;
    crate_file.file = file;
    crate_file.layer(time).map_err(bad)
}

/// The timeline metadata of a crate file's layer.
pub(crate) fn read_timeline(bytes: &[u8], path: &Path) -> Result<LayerTimeline> {
    let bad = |message: String| Error::format(path, format!("crate file: {message}"));
    Crate::parse(bytes).map_err(bad)?.timeline().map_err(bad)
}

/// A path: its parent path (`None` for the pseudo-root), its last element, whether a property.
#[derive(Clone, Copy, Debug)]
struct PathEntry {
    parent: Option<u32>,
    token: u32,
    property: bool,
}

struct Spec {
    path: u32,
    fieldset: u32,
    kind: u32,
}

struct Crate<'a> {
    bytes: &'a [u8],
    /// The file `bytes` maps, if any: large arrays are read from it straight into the groom's
    /// memory, so their pages never enter the map (half the peak memory, no page faults).
    file: Option<&'a std::fs::File>,
    /// Attributes' plain `points` (`float3` kinds) and `widths` (`float`) arrays are left in the
    /// file as [`Value::InFile`], for the groom reader to read into place.
    leave_in_file: bool,
    version: (u8, u8, u8),
    tokens: Vec<String>,
    strings: Vec<u32>,
    fields: Vec<(u32, u64)>,
    fieldsets: Vec<u32>,
    paths: Vec<Option<PathEntry>>,
    specs: Vec<Spec>,
}

/// Bounded reads within one section; errors name it.
struct Section<'a> {
    name: &'static str,
    data: &'a [u8],
    at: usize,
}

impl<'a> Section<'a> {
    fn take(&mut self, n: usize, what: &str) -> Checked<&'a [u8]> {
        if n > self.data.len() - self.at {
            return Err(format!(
                "{}: {what} needs {n} bytes at offset {}, the section has {}",
                self.name,
                self.at,
                self.data.len()
            ));
        }
        let slice = &self.data[self.at..self.at + n];
        self.at += n;
        Ok(slice)
    }

    fn u64(&mut self, what: &str) -> Checked<u64> {
        Ok(u64::from_le_bytes(self.take(8, what)?.try_into().unwrap()))
    }

    /// A count that must fit in `usize` and whose elements of `size` bytes (at least one) could
    /// fit in the rest of the section's compressed or raw data.
    fn count(&mut self, what: &str) -> Checked<usize> {
        let n = self.u64(what)?;
        usize::try_from(n).map_err(|_| format!("{}: {what} {n} is too large", self.name))
    }

    /// A `u64` size then that many bytes.
    fn blob(&mut self, what: &str) -> Checked<&'a [u8]> {
        let n = self.count(what)?;
        self.take(n, what)
    }

    fn ints<T: CodedInt>(&mut self, count: usize, what: &str) -> Checked<Vec<T>> {
        let blob = self.blob(what)?;
        decompress_ints(blob, count).map_err(|e| format!("{}: {what}: {e}", self.name))
    }
}

impl<'a> Crate<'a> {
    fn parse(bytes: &'a [u8]) -> Checked<Crate<'a>> {
        if bytes.len() < BOOTSTRAP_SIZE || &bytes[..8] != MAGIC {
            return Err("bootstrap: not a USD crate file or shorter than its 88-byte header".into());
        }
        let version = (bytes[8], bytes[9], bytes[10]);
        if version.0 != 0 || !(4..=12).contains(&version.1) {
            return Err(format!(
                "bootstrap: crate version {}.{}.{} is not supported (0.4.0 to 0.12.x)",
                version.0, version.1, version.2
            ));
        }
        let toc_at = u64::from_le_bytes(bytes[16..24].try_into().unwrap());
        let toc = usize::try_from(toc_at)
            .ok()
            .filter(|&t| t >= BOOTSTRAP_SIZE && t <= bytes.len())
            .ok_or_else(|| format!("bootstrap: table of contents offset {toc_at} is outside the file"))?;
        let mut toc = Section { name: "TOC", data: &bytes[toc..], at: 0 };
        let count = toc.count("section count")?;
        if count > 64 || count * 32 > toc.data.len() - 8 {
            return Err(format!("TOC: {count} sections do not fit"));
        }
        let mut sections: HashMap<String, &'a [u8]> = HashMap::new();
        for _ in 0..count {
            let raw = toc.take(16, "section name")?;
            let name = String::from_utf8_lossy(raw.split(|&b| b == 0).next().unwrap_or(raw)).into_owned();
            let start = toc.u64("section start")?;
            let size = toc.u64("section size")?;
            let end = start.checked_add(size).filter(|&e| e <= bytes.len() as u64).ok_or_else(|| {
                format!("TOC: section {name} ({size} bytes at {start}) is outside the file")
            })?;
            sections.insert(name, &bytes[start as usize..end as usize]);
        }
        let mut section = |name: &'static str| -> Checked<Section<'a>> {
            let data = sections.remove(name).ok_or_else(|| format!("TOC: no {name} section"))?;
            Ok(Section { name, data, at: 0 })
        };

        let mut s = section("TOKENS")?;
        let count = s.count("token count")?;
        let raw_size = s.count("token bytes")?;
        let blob = s.blob("compressed tokens")?;
        let raw = lz4_decompress(blob, raw_size).map_err(|e| format!("TOKENS: {e}"))?;
        if raw.len() != raw_size || raw.last().is_some_and(|&b| b != 0) {
            return Err(format!(
                "TOKENS: {} bytes decompressed, {raw_size} announced, or not NUL-ended",
                raw.len()
            ));
        }
        let tokens: Vec<String> = match raw.split_last() {
            None => Vec::new(),
            Some((_, body)) => {
                body.split(|&b| b == 0).map(|t| String::from_utf8_lossy(t).into_owned()).collect()
            }
        };
        if tokens.len() != count {
            return Err(format!("TOKENS: {count} tokens announced, {} found", tokens.len()));
        }

        let mut s = section("STRINGS")?;
        let count = s.count("string count")?;
        let raw = s.take(count.checked_mul(4).ok_or("STRINGS: count overflows")?, "string indices")?;
        let strings: Vec<u32> =
            raw.chunks_exact(4).map(|c| u32::from_le_bytes(c.try_into().unwrap())).collect();
        if let Some(bad) = strings.iter().find(|&&t| t as usize >= tokens.len()) {
            return Err(format!("STRINGS: token index {bad} beyond the {} tokens", tokens.len()));
        }

        let mut s = section("FIELDS")?;
        let count = s.count("field count")?;
        let names: Vec<u32> = s.ints(count, "field names")?;
        let blob = s.blob("field values")?;
        let raw = lz4_decompress(blob, count.saturating_mul(8)).map_err(|e| format!("FIELDS: {e}"))?;
        if raw.len() != count * 8 {
            return Err(format!("FIELDS: {} value bytes for {count} fields", raw.len()));
        }
        let reps = raw.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().unwrap()));
        let fields: Vec<(u32, u64)> = names.into_iter().zip(reps).collect();
        if let Some((bad, _)) = fields.iter().find(|(t, _)| *t as usize >= tokens.len()) {
            return Err(format!("FIELDS: name token {bad} beyond the {} tokens", tokens.len()));
        }

        let mut s = section("FIELDSETS")?;
        let count = s.count("field set length")?;
        let fieldsets: Vec<u32> = s.ints(count, "field sets")?;
        if let Some(bad) = fieldsets.iter().find(|&&f| f != u32::MAX && f as usize >= fields.len()) {
            return Err(format!("FIELDSETS: field {bad} beyond the {} fields", fields.len()));
        }

        let mut s = section("PATHS")?;
        let path_count = s.count("path count")?;
        let nodes = s.count("node count")?;
        // The table may hold paths outside the tree (pxr indexes the empty path of a reference
        // to a layer's default prim), never many: the bound keeps a hostile count from allocating.
        if path_count > nodes.saturating_mul(2).saturating_add(1) {
            return Err(format!("PATHS: {path_count} paths but only {nodes} tree nodes"));
        }
        let path_indices: Vec<u32> = s.ints(nodes, "path indices")?;
        let element_tokens: Vec<i32> = s.ints(nodes, "element tokens")?;
        let jumps: Vec<i32> = s.ints(nodes, "jumps")?;
        let paths = build_paths(&path_indices, &element_tokens, &jumps, path_count, tokens.len())?;

        let mut s = section("SPECS")?;
        let count = s.count("spec count")?;
        let spec_paths: Vec<u32> = s.ints(count, "spec paths")?;
        let spec_sets: Vec<u32> = s.ints(count, "spec field sets")?;
        let spec_kinds: Vec<u32> = s.ints(count, "spec types")?;
        let mut specs = Vec::with_capacity(count);
        for i in 0..count {
            let (path, fieldset, kind) = (spec_paths[i], spec_sets[i], spec_kinds[i]);
            if paths.get(path as usize).is_none_or(Option::is_none) {
                return Err(format!(
                    "SPECS: spec {i} names path {path}, which the PATHS section does not hold"
                ));
            }
            let set_ok =
                (fieldset as usize) < fieldsets.len() && fieldsets[fieldset as usize..].contains(&u32::MAX);
            if !set_ok {
                return Err(format!(
                    "SPECS: spec {i} names field set {fieldset}, which is outside FIELDSETS or unterminated"
                ));
            }
            if kind == 0 || kind > 11 {
                return Err(format!("SPECS: spec {i} has unknown type {kind}"));
            }
            specs.push(Spec { path, fieldset, kind });
        }
        Ok(Crate {
            bytes,
            file: None,
            leave_in_file: false,
            version,
            tokens,
            strings,
            fields,
            fieldsets,
            paths,
            specs,
        })
    }

    fn token(&self, index: u64) -> Checked<&str> {
        self.tokens
            .get(index as usize)
            .map(String::as_str)
            .ok_or_else(|| format!("token index {index} is out of range"))
    }

    /// The fields of a spec, as (name, value representation).
    fn spec_fields(&self, spec: &Spec) -> impl Iterator<Item = (&str, u64)> {
        self.fieldsets[spec.fieldset as usize..]
            .iter()
            .take_while(|&&f| f != u32::MAX)
            .map(|&f| self.fields[f as usize])
            .map(|(name, value)| (self.tokens[name as usize].as_str(), value))
    }

    fn path_text(&self, index: u32) -> String {
        let mut parts = Vec::new();
        let mut at = Some(index);
        while let Some(entry) = at.and_then(|i| self.paths[i as usize]) {
            if entry.parent.is_none() || parts.len() > MAX_DEPTH {
                break;
            }
            let token = &self.tokens[entry.token as usize];
            let sep = if entry.property {
                "."
            } else if token.starts_with('{') {
                ""
            } else {
                "/"
            };
            parts.push(format!("{sep}{token}"));
            at = entry.parent;
        }
        parts.reverse();
        let text = parts.concat();
        if text.is_empty() {
            "/".into()
        } else {
            text
        }
    }

    /// The timeline the pseudo-root's metadata authors (no prim is decoded).
    fn timeline(&self) -> Checked<LayerTimeline> {
        let mut timeline = LayerTimeline::default();
        for spec in self.specs.iter().filter(|s| s.kind == SpecType::PseudoRoot as u32) {
            for (field, value) in self.spec_fields(spec) {
                if matches!(field, "startTimeCode" | "endTimeCode" | "timeCodesPerSecond" | "framesPerSecond")
                {
                    if let Some(v) = self.number(value).map_err(|e| format!("{field}: {e}"))? {
                        timeline.set(field, v);
                    }
                }
            }
        }
        Ok(timeline)
    }

    /// The layer model: prims (and variant bodies) with their attributes and arcs.
    fn layer(&self, time: Option<f64>) -> Checked<Layer> {
        let mut layer = Layer::default();
        let mut prims: HashMap<u32, Prim> = HashMap::new();
        let mut children: HashMap<u32, Vec<u32>> = HashMap::new();
        // Variant bodies of a prim: (set, path of the variant spec).
        let mut variants: HashMap<u32, Vec<(String, u32)>> = HashMap::new();
        let mut order: HashMap<u32, Vec<String>> = HashMap::new();
        let mut attributes: Vec<(u32, Attribute)> = Vec::new();
        for spec in &self.specs {
            let entry = self.paths[spec.path as usize].expect("checked in parse");
            let name = self.tokens[entry.token as usize].clone();
            let at = || self.path_text(spec.path);
            if spec.kind == SpecType::PseudoRoot as u32 {
                let mut offsets = Vec::new();
                for (field, value) in self.spec_fields(spec) {
                    let fail = |e: String| format!("layer metadata {field}: {e}");
                    match field {
                        "metersPerUnit" => layer.meters_per_unit = self.number(value).map_err(fail)?,
                        "upAxis" => layer.up_axis = Some(self.text(value).map_err(fail)?),
                        "defaultPrim" => layer.default_prim = Some(self.text(value).map_err(fail)?),
                        "subLayers" => {
                            layer.sub_layers = self
                                .string_vector(value)
                                .map_err(fail)?
                                .into_iter()
                                .map(|asset| SubLayer { asset, offset: LayerOffset::default() })
                                .collect()
                        }
                        "subLayerOffsets" => offsets = self.layer_offsets(value).map_err(fail)?,
                        "relocates" | "layerRelocates" => layer.refused = Some((0, field.to_string())),
                        "startTimeCode" | "endTimeCode" | "timeCodesPerSecond" | "framesPerSecond" => {
                            if let Some(v) = self.number(value).map_err(|e| format!("{field}: {e}"))? {
                                layer.timeline.set(field, v);
                            }
                        }
                        "primChildren" => {
                            order.insert(spec.path, self.token_vector(value).map_err(fail)?);
                        }
                        _ => {}
                    }
                }
                for (sub_layer, offset) in layer.sub_layers.iter_mut().zip(offsets) {
                    sub_layer.offset = offset;
                }
            } else if spec.kind == SpecType::Prim as u32 || spec.kind == SpecType::Variant as u32 {
                let variant = spec.kind == SpecType::Variant as u32;
                let mut prim = Prim { name, specifier: Specifier::Over, ..Default::default() };
                let mut arcs = Arcs::default();
                for (field, value) in self.spec_fields(spec) {
                    let fail = |e: String| format!("<{}> {field}: {e}", at());
                    match field {
                        "specifier" => {
                            prim.specifier = match rep::payload(value) {
                                SPECIFIER_DEF => Specifier::Def,
                                SPECIFIER_CLASS => Specifier::Class,
                                _ => Specifier::Over,
                            }
                        }
                        "typeName" => prim.type_name = self.text(value).map_err(fail)?,
                        "active" => prim.active = Some(rep::payload(value) & 0xffff_ffff != 0),
                        "primChildren" | "properties" => {
                            let names = self.token_vector(value).map_err(fail)?;
                            order.entry(spec.path).or_default().extend(names);
                        }
                        "references" => arcs.references = self.asset_arcs(value).map_err(fail)?,
                        "payload" => arcs.payloads = self.asset_arcs(value).map_err(fail)?,
                        "inheritPaths" => arcs.inherits = self.path_list_op(value).map_err(fail)?,
                        "variantSetNames" => {
                            arcs.variant_set_names = self.string_list_op(value).map_err(fail)?
                        }
                        "variantSelection" => arcs.selections = self.selections(value).map_err(fail)?,
                        "specializes" | "relocates" => arcs.refused = Some(field.to_string()),
                        arcs::VALUE_CLIPS if !self.dictionary_is_empty(value).map_err(fail)? => {
                            arcs.refused.get_or_insert(field.to_string());
                        }
                        _ => {}
                    }
                }
                if !arcs.is_empty() {
                    prim.arcs = Some(Box::new(arcs));
                }
                // A crafted file may put a prim spec on the pseudo-root's path.
                let parent = entry.parent.ok_or("a prim spec on the pseudo-root path")?;
                if variant {
                    let (set, selection) = variant_element(&prim.name)
                        .map(|(set, selection)| (set.to_string(), selection.to_string()))
                        .ok_or_else(|| format!("<{}>: a variant spec whose path names no variant", at()))?;
                    prim.name = selection;
                    variants.entry(parent).or_default().push((set, spec.path));
                } else {
                    if prim.name.starts_with('{') {
                        return Err(format!("<{}>: a prim spec on a variant path", at()));
                    }
                    children.entry(parent).or_default().push(spec.path);
                }
                prims.insert(spec.path, prim);
            } else if spec.kind == SpecType::Attribute as u32 {
                let attribute = self.attribute(name, spec, time).map_err(|e| format!("<{}>: {e}", at()))?;
                let owner = entry.parent.ok_or("an attribute spec on the pseudo-root path")?;
                attributes.push((owner, attribute));
            }
        }
        for (owner, attribute) in attributes {
            if let Some(prim) = prims.get_mut(&owner) {
                prim.attributes.push(attribute);
            }
        }
        // Children in the order their parent lists them, then any it does not list.
        let rank = |parent: u32, name: &str| {
            order.get(&parent).and_then(|names| names.iter().position(|n| n == name)).unwrap_or(usize::MAX)
        };
        for (path, prim) in prims.iter_mut() {
            prim.attributes.sort_by_key(|a| rank(*path, &a.name));
        }
        let root = self.paths.iter().position(|p| p.is_some_and(|e| e.parent.is_none())).unwrap_or(0) as u32;
        let tree = Tree { children: &children, variants: &variants, rank: &rank };
        layer.prims = self.assemble(root, &mut prims, &tree, 0)?;
        Ok(layer)
    }

    fn assemble(
        &self,
        parent: u32,
        prims: &mut HashMap<u32, Prim>,
        tree: &Tree,
        depth: usize,
    ) -> Checked<Vec<Prim>> {
        if depth > MAX_DEPTH {
            return Err(format!("PATHS: prims nest deeper than {MAX_DEPTH}"));
        }
        let mut found: Vec<(u32, Prim)> = Vec::new();
        for &child in tree.children.get(&parent).map(Vec::as_slice).unwrap_or_default() {
            if let Some(mut prim) = prims.remove(&child) {
                self.fill(child, &mut prim, prims, tree, depth)?;
                found.push((child, prim));
            }
        }
        found.sort_by_key(|(_, p)| (tree.rank)(parent, &p.name));
        Ok(found.into_iter().map(|(_, p)| p).collect())
    }

    /// A prim's children and its variant bodies (with theirs).
    fn fill(
        &self,
        path: u32,
        prim: &mut Prim,
        prims: &mut HashMap<u32, Prim>,
        tree: &Tree,
        depth: usize,
    ) -> Checked<()> {
        prim.children = self.assemble(path, prims, tree, depth + 1)?;
        for (set, variant_path) in tree.variants.get(&path).map(Vec::as_slice).unwrap_or_default() {
            if let Some(mut variant) = prims.remove(variant_path) {
                self.fill(*variant_path, &mut variant, prims, tree, depth + 1)?;
                prim.arcs.get_or_insert_default().variant_set(set).variants.push(variant);
            }
        }
        Ok(())
    }

    /// A cursor at the out-of-line value `value` points to.
    fn cursor(&self, value: u64) -> Cursor<'_, 'a> {
        Cursor { file: self, at: rep::payload(value) }
    }

    fn string_at(&self, index: u32) -> Checked<String> {
        let token = self
            .strings
            .get(index as usize)
            .ok_or_else(|| format!("string index {index} is out of range"))?;
        self.token(*token as u64).map(String::from)
    }

    /// A path's text; the empty path (which the path tree does not hold) is "".
    fn path_at(&self, index: u32) -> Checked<String> {
        match self.paths.get(index as usize) {
            Some(Some(_)) => Ok(self.path_text(index)),
            Some(None) => Ok(String::new()),
            None => Err(format!("path index {index} is out of range")),
        }
    }

    fn expect_kind(value: u64, kind: Type) -> Checked<()> {
        if Self::kind(value)? != kind || rep::is_inline(value) || rep::is_array(value) {
            return Err(format!("expected a {kind:?} value"));
        }
        Ok(())
    }

    /// Whether a dictionary value holds no entry (its count leads it).
    fn dictionary_is_empty(&self, value: u64) -> Checked<bool> {
        if Self::kind(value)? != Type::Dictionary || rep::is_array(value) {
            return Err("expected a Dictionary value".into());
        }
        Ok(rep::is_inline(value) || self.cursor(value).u64()? == 0)
    }

    fn string_vector(&self, value: u64) -> Checked<Vec<String>> {
        Self::expect_kind(value, Type::StringVector)?;
        let mut cursor = self.cursor(value);
        cursor.vector(4, |c| c.string())
    }

    fn layer_offsets(&self, value: u64) -> Checked<Vec<LayerOffset>> {
        Self::expect_kind(value, Type::LayerOffsetVector)?;
        let mut cursor = self.cursor(value);
        cursor.vector(16, Cursor::layer_offset)
    }

    fn selections(&self, value: u64) -> Checked<Vec<(String, String)>> {
        Self::expect_kind(value, Type::VariantSelectionMap)?;
        let mut cursor = self.cursor(value);
        cursor.vector(8, |c| Ok((c.string()?, c.string()?)))
    }

    fn path_list_op(&self, value: u64) -> Checked<ListOp<String>> {
        Self::expect_kind(value, Type::PathListOp)?;
        self.cursor(value).list_op(4, |c| {
            let index = c.u32()?;
            self.path_at(index)
        })
    }

    fn string_list_op(&self, value: u64) -> Checked<ListOp<String>> {
        Self::expect_kind(value, Type::StringListOp)?;
        self.cursor(value).list_op(4, Cursor::string)
    }

    /// References (`ReferenceListOp`) or payloads (`PayloadListOp`, or one `Payload` in old files).
    fn asset_arcs(&self, value: u64) -> Checked<ListOp<AssetArc>> {
        let kind = Self::kind(value)?;
        // Payloads carry a layer offset since 0.8.
        let payload_offset = self.version.1 >= 8;
        match kind {
            Type::ReferenceListOp => {
                Self::expect_kind(value, kind)?;
                self.cursor(value).list_op(28, |c| c.asset_arc(true, true))
            }
            Type::PayloadListOp => {
                Self::expect_kind(value, kind)?;
                self.cursor(value).list_op(8, |c| c.asset_arc(payload_offset, false))
            }
            Type::Payload => {
                Self::expect_kind(value, kind)?;
                let arc = self.cursor(value).asset_arc(payload_offset, false)?;
                Ok(ListOp { explicit: Some(vec![arc]), ..Default::default() })
            }
            other => Err(format!("expected references or payloads, found {other:?}")),
        }
    }

    fn attribute(&self, name: String, spec: &Spec, time: Option<f64>) -> Checked<Attribute> {
        let keep = usda::wanted(&name);
        let mut attribute = Attribute { name, ..Default::default() };
        let declared = match self.spec_fields(spec).find(|(field, _)| *field == "typeName") {
            Some((_, value)) => Some(self.text(value).map_err(|e| format!("typeName: {e}"))?),
            None => None,
        };
        for (field, value) in self.spec_fields(spec) {
            let fail = |e: String| format!("{field}: {e}");
            match field {
                // The layer model holds the element type, as `.usda` declares it before `[]`.
                "typeName" => {
                    let name = self.text(value).map_err(fail)?;
                    attribute.array = name.ends_with("[]");
                    attribute.type_name = name.strip_suffix("[]").unwrap_or(&name).to_string();
                }
                "interpolation" => attribute.interpolation = Some(self.text(value).map_err(fail)?),
                "elementSize" => attribute.element_size = self.number(value).map_err(fail)?.map(|n| n as i64),
                "default" => {
                    if let Some(declared) = &declared {
                        Self::held_as_declared(declared, value).map_err(fail)?;
                    }
                    let in_file =
                        self.leave_in_file && matches!(attribute.name.as_str(), "points" | "widths");
                    attribute.default = Some(if !keep {
                        Value::Ignored
                    } else if in_file {
                        self.value_or_in_file(value).map_err(fail)?
                    } else {
                        self.value(value).map_err(fail)?
                    })
                }
                "timeSamples" if keep => {
                    attribute.samples = self.time_samples(value, time, declared.as_deref()).map_err(fail)?
                }
                _ => {}
            }
        }
        Ok(attribute)
    }

    /// Bytes `offset..offset + len` of the file.
    fn at(&self, offset: u64, len: usize) -> Checked<&'a [u8]> {
        let start = usize::try_from(offset).map_err(|_| format!("offset {offset} is outside the file"))?;
        match start.checked_add(len) {
            Some(end) if end <= self.bytes.len() => Ok(&self.bytes[start..end]),
            _ => Err(format!(
                "{len} bytes at offset {offset} run past the end of the file ({} bytes)",
                self.bytes.len()
            )),
        }
    }

    fn u64_at(&self, offset: u64) -> Checked<u64> {
        Ok(u64::from_le_bytes(self.at(offset, 8)?.try_into().unwrap()))
    }

    fn kind(value: u64) -> Checked<Type> {
        Type::from_u8(rep::type_byte(value))
            .ok_or_else(|| format!("value type {} is not one coif reads", rep::type_byte(value)))
    }

    fn text(&self, value: u64) -> Checked<String> {
        match self.value(value)? {
            Value::Text(mut t) if t.len() == 1 => Ok(t.remove(0)),
            _ => Err("expected a token or string".into()),
        }
    }

    fn number(&self, value: u64) -> Checked<Option<f64>> {
        Ok(self.value(value)?.to_f64().and_then(|v| v.first().copied()))
    }

    fn token_vector(&self, value: u64) -> Checked<Vec<String>> {
        if Self::kind(value)? != Type::TokenVector {
            return Err("expected a token list".into());
        }
        let count = self.u64_at(rep::payload(value))?;
        let bytes =
            self.at(rep::payload(value) + 8, usize::try_from(count).unwrap_or(usize::MAX).saturating_mul(4))?;
        bytes
            .chunks_exact(4)
            .map(|c| self.token(u32::from_le_bytes(c.try_into().unwrap()) as u64).map(String::from))
            .collect()
    }

    /// Time samples: the ones `time` needs (see [`usda::offer_sample`]), decoded.
    fn time_samples(
        &self,
        value: u64,
        time: Option<f64>,
        declared: Option<&str>,
    ) -> Checked<Vec<(f64, Value)>> {
        if Self::kind(value)? != Type::TimeSamples || rep::is_inline(value) {
            return Err("expected time samples".into());
        }
        let start = rep::payload(value);
        let times_at = start.wrapping_add(self.u64_at(start)?);
        let times_rep = self.u64_at(times_at)?;
        let times = match (Self::kind(times_rep)?, rep::is_array(times_rep)) {
            (Type::DoubleVector, _) | (Type::Double, true) => self.f64s(times_rep)?,
            _ => return Err("sample times are not doubles".into()),
        };
        let jump_at = times_at.checked_add(8).ok_or("offset overflow")?;
        let values_at = jump_at.wrapping_add(self.u64_at(jump_at)?);
        let count = self.u64_at(values_at)?;
        if count != times.len() as u64 {
            return Err(format!("{} sample times but {count} values", times.len()));
        }
        let reps = self.at(values_at + 8, times.len() * 8)?;
        let mut kept = Vec::new();
        for (k, &t) in times.iter().enumerate() {
            usda::offer_sample(&mut kept, time, t, Value::Int(vec![k as i64]));
        }
        kept.into_iter()
            .map(|(t, index)| {
                let Value::Int(k) = index else { unreachable!("placeholders are indices") };
                let k = k[0] as usize;
                let sample = u64::from_le_bytes(reps[8 * k..8 * k + 8].try_into().unwrap());
                if Self::kind(sample)? == Type::TimeSamples {
                    return Err("time samples nested in time samples".into());
                }
                if let Some(declared) = declared {
                    Self::held_as_declared(declared, sample)
                        .map_err(|e| format!("the sample at {t}: {e}"))?;
                }
                Ok((t, self.value(sample)?))
            })
            .collect()
    }

    /// Refuses a number-typed attribute's value stored as another type: a crate holds each value
    /// with its own type, and pxr's typed reads find nothing in a `curveVertexCounts` declared
    /// `int[]` that holds `int64[]` or `uint[]` values (no curves), in `points` declared
    /// `point3f[]` holding `double3[]` or `half3[]` (no points), in `widths` declared `float[]`
    /// holding `double[]` or `half[]` (no widths: the extent pxr computes leaves them out); coif
    /// read them as if they were the declared type.
    fn held_as_declared(declared: &str, value: u64) -> Checked<()> {
        let (base, array) = match declared.strip_suffix("[]") {
            Some(base) => (base, true),
            None => (declared, false),
        };
        // Each type's own name first (the name a held value is given), then its roles'.
        const NUMBERS: [(&str, Type); 43] = [
            ("bool", Type::Bool),
            ("uchar", Type::Uchar),
            ("int", Type::Int),
            ("uint", Type::Uint),
            ("int64", Type::Int64),
            ("uint64", Type::Uint64),
            ("int2", Type::Vec2i),
            ("int3", Type::Vec3i),
            ("int4", Type::Vec4i),
            ("half", Type::Half),
            ("float", Type::Float),
            ("double", Type::Double),
            ("half2", Type::Vec2h),
            ("half3", Type::Vec3h),
            ("half4", Type::Vec4h),
            ("float2", Type::Vec2f),
            ("float3", Type::Vec3f),
            ("float4", Type::Vec4f),
            ("double2", Type::Vec2d),
            ("double3", Type::Vec3d),
            ("double4", Type::Vec4d),
            ("quath", Type::Quath),
            ("quatf", Type::Quatf),
            ("quatd", Type::Quatd),
            ("matrix2d", Type::Matrix2d),
            ("matrix3d", Type::Matrix3d),
            ("matrix4d", Type::Matrix4d),
            ("frame4d", Type::Matrix4d),
            ("point3h", Type::Vec3h),
            ("point3f", Type::Vec3f),
            ("point3d", Type::Vec3d),
            ("normal3h", Type::Vec3h),
            ("normal3f", Type::Vec3f),
            ("normal3d", Type::Vec3d),
            ("vector3h", Type::Vec3h),
            ("vector3f", Type::Vec3f),
            ("vector3d", Type::Vec3d),
            ("color3f", Type::Vec3f),
            ("color3d", Type::Vec3d),
            ("color4f", Type::Vec4f),
            ("texCoord2h", Type::Vec2h),
            ("texCoord2f", Type::Vec2f),
            ("texCoord2d", Type::Vec2d),
        ];
        let Some(&(_, expected)) = NUMBERS.iter().find(|(name, _)| *name == base) else {
            return Ok(());
        };
        let held = Self::kind(value)?;
        if held == Type::ValueBlock || (held == expected && rep::is_array(value) == array) {
            return Ok(());
        }
        let held_name =
            NUMBERS.iter().find(|(_, t)| *t == held).map_or(format!("{held:?}"), |(n, _)| n.to_string());
        let brackets = if rep::is_array(value) { "[]" } else { "" };
        Err(format!(
            "declared {declared} but holds {held_name}{brackets} values (pxr reads no value from it)"
        ))
    }

    fn f64s(&self, value: u64) -> Checked<Vec<f64>> {
        match self.value(value)? {
            Value::F64(v) => Ok(v),
            _ => Err("expected doubles".into()),
        }
    }

    fn value(&self, value: u64) -> Checked<Value> {
        let kind = Self::kind(value)?;
        self.value_as(value, kind)
    }

    /// [`Crate::value`], but a plain (uncompressed) array of `float`s or `float3`s stays in the
    /// file as a [`Value::InFile`].
    fn value_or_in_file(&self, value: u64) -> Checked<Value> {
        let kind = Self::kind(value)?;
        let components = match kind {
            Type::Float => 1,
            Type::Vec3f => 3,
            _ => return self.value_as(value, kind),
        };
        // Compressed arrays are decoded, once, as any other value.
        if !rep::is_array(value) || rep::is_inline(value) || rep::is_compressed(value) {
            return self.value_as(value, kind);
        }
        match self.array(value, Elem::F32, components)? {
            ArrayData::Raw(bytes) if !bytes.is_empty() => {
                let offset = (bytes.as_ptr() as usize - self.bytes.as_ptr() as usize) as u64;
                Ok(Value::InFile(usda::FileArray { offset, bytes: bytes.len(), components }))
            }
            _ => self.value_as(value, kind),
        }
    }

    /// Decodes `value`, whose element type is `kind` (a double vector reads as doubles).
    fn value_as(&self, value: u64, kind: Type) -> Checked<Value> {
        use Type::*;
        let components = match kind {
            ValueBlock => return Ok(Value::Blocked),
            Vec2d | Vec2f | Vec2h | Vec2i => 2,
            Vec3d | Vec3f | Vec3h | Vec3i => 3,
            Vec4d | Vec4f | Vec4h | Vec4i | Quatd | Quatf | Quath | Matrix2d => 4,
            Matrix3d => 9,
            Matrix4d => 16,
            Bool | Uchar | Int | Uint | Int64 | Uint64 | Half | Float | Double | TimeCode | Token
            | String | AssetPath | DoubleVector => 1,
            _ => return Ok(Value::Ignored),
        };
        let elem = Elem::of(kind);
        let array = rep::is_array(value) || kind == DoubleVector;
        let mut raw: Vec<Scalar> = if rep::is_inline(value) {
            self.inline(value, kind, elem, components)
        } else if !array {
            let bytes = self.at(rep::payload(value), elem.size() * components)?;
            bytes.chunks_exact(elem.size()).map(|c| elem.read(c)).collect()
        } else {
            match self.array(value, elem, components)? {
                ArrayData::Scalars(scalars) => scalars,
                ArrayData::Floats(values) => return Ok(Value::F32(values)),
                ArrayData::Ints(values) => return Ok(Value::Int(values)),
                // Plain float arrays (points, widths, primvars) are copied as they lie.
                ArrayData::Raw(bytes) if elem == Elem::F32 && !matches!(kind, Quatf) => {
                    return Ok(if components == 3 {
                        Value::Vec3(self.copy_out(bytes)?)
                    } else {
                        Value::F32(self.copy_out(bytes)?)
                    });
                }
                // Integers (mesh faces, indices, ids) straight to the layer model's, no `Scalar`s.
                ArrayData::Raw(bytes) if matches!(elem, Elem::U8 | Elem::I32 | Elem::U32 | Elem::I64) => {
                    return Ok(Value::Int(
                        bytes.chunks_exact(elem.size()).map(|c| elem.read(c).i64()).collect(),
                    ));
                }
                ArrayData::Raw(bytes) => bytes.chunks_exact(elem.size()).map(|c| elem.read(c)).collect(),
            }
        };
        if matches!(kind, Quatd | Quatf | Quath) {
            // Stored imaginary part first; the layer model holds (real, i, j, k) like `.usda`.
            for q in raw.chunks_exact_mut(4) {
                q.rotate_right(1);
            }
        }
        Ok(match elem {
            Elem::Half | Elem::F32 if array && components == 3 => Value::Vec3(
                raw.chunks_exact(3).map(|c| Vec3::new(c[0].f32(), c[1].f32(), c[2].f32())).collect(),
            ),
            Elem::Half | Elem::F32 => Value::F32(raw.iter().map(Scalar::f32).collect()),
            Elem::F64 => Value::F64(raw.iter().map(Scalar::f64).collect()),
            Elem::U8 | Elem::I32 | Elem::U32 | Elem::I64 => Value::Int(raw.iter().map(Scalar::i64).collect()),
            Elem::Token | Elem::Str => {
                let names = raw.iter().map(|s| match *s {
                    Scalar::Str(i) => self
                        .strings
                        .get(i as usize)
                        .ok_or_else(|| format!("string index {i} is out of range"))
                        .and_then(|&t| self.token(t as u64)),
                    other => self.token(other.i64() as u64),
                });
                Value::Text(names.map(|n| n.map(str::to_string)).collect::<Checked<_>>()?)
            }
        })
    }

    /// A value held in the representation itself.
    fn inline(&self, value: u64, kind: Type, elem: Elem, components: usize) -> Vec<Scalar> {
        let bits = rep::payload(value).to_le_bytes();
        if components > 1 {
            // Vectors of small integers, or matrices by their diagonal.
            let side = match kind {
                Type::Matrix2d => 2,
                Type::Matrix3d => 3,
                Type::Matrix4d => 4,
                _ => return (0..components).map(|i| elem.small_int(bits[i] as i8)).collect(),
            };
            return (0..side * side)
                .map(|i| elem.small_int(if i % (side + 1) == 0 { bits[i / (side + 1)] as i8 } else { 0 }))
                .collect();
        }
        let low = u32::from_le_bytes(bits[..4].try_into().unwrap());
        vec![match elem {
            // Doubles a float holds exactly are stored as that float.
            Elem::F64 => Scalar::F64(f32::from_bits(low) as f64),
            Elem::I64 => Scalar::I64(low as i32 as i64),
            Elem::Str => Scalar::Str(low),
            // Asset paths inline are token indices.
            Elem::Token => Scalar::Token(low),
            other => other.read(&bits[..other.size()]),
        }]
    }

    /// An array's scalars (`components` per element).
    fn array(&self, value: u64, elem: Elem, components: usize) -> Checked<ArrayData<'a>> {
        let offset = rep::payload(value);
        if offset == 0 {
            return Ok(ArrayData::Scalars(Vec::new()));
        }
        let mut at = offset;
        if self.version.1 < 5 {
            at += 4;
        }
        let count = if self.version.1 < 7 {
            let n = u32::from_le_bytes(self.at(at, 4)?.try_into().unwrap()) as u64;
            at += 4;
            n
        } else {
            let n = self.u64_at(at)?;
            at += 8;
            n
        };
        let too_large = || format!("array of {count} elements at offset {offset} is larger than the file");
        let scalars =
            usize::try_from(count).ok().and_then(|c| c.checked_mul(components)).ok_or_else(too_large)?;
        let compressed = rep::is_compressed(value) && scalars >= MIN_COMPRESSED_ARRAY;
        let ints = |at: u64, elem: Elem| -> Checked<Vec<i64>> {
            let n = self.u64_at(at)?;
            let bytes = self.at(at + 8, usize::try_from(n).unwrap_or(usize::MAX))?;
            Ok(match elem {
                Elem::I32 => decompress_ints::<i32>(bytes, scalars)?.into_iter().map(i64::from).collect(),
                Elem::U32 => decompress_ints::<u32>(bytes, scalars)?.into_iter().map(i64::from).collect(),
                _ => decompress_ints::<i64>(bytes, scalars)?,
            })
        };
        let integer = matches!(elem, Elem::I32 | Elem::U32 | Elem::I64) && components == 1;
        let float = matches!(elem, Elem::Half | Elem::F32 | Elem::F64) && components == 1;
        if compressed && integer {
            return Ok(ArrayData::Ints(ints(at, elem)?));
        }
        if compressed && float && self.version.1 >= 6 {
            return Ok(ArrayData::Scalars(match self.at(at, 1)?[0] {
                b'i' => {
                    let from = |i: i64| {
                        if elem == Elem::F64 {
                            Scalar::F64(i as f64)
                        } else {
                            Scalar::F32(i as f32)
                        }
                    };
                    ints(at + 1, Elem::I32)?.into_iter().map(from).collect()
                }
                b't' if elem == Elem::F32 => {
                    // Widths and float primvars: straight to floats, no wider intermediate.
                    let lut_len = u32::from_le_bytes(self.at(at + 1, 4)?.try_into().unwrap()) as usize;
                    let lut: Vec<f32> = self.copy_out(self.at(at + 5, lut_len * 4)?)?;
                    let packed_at = at + 5 + lut_len as u64 * 4;
                    let n = self.u64_at(packed_at)?;
                    let bytes = self.at(packed_at + 8, usize::try_from(n).unwrap_or(usize::MAX))?;
                    let indices = decompress_ints::<u32>(bytes, scalars)?;
                    if let Some(i) = indices.iter().copied().max().filter(|&i| i as usize >= lut_len) {
                        return Err(format!("lookup index {i} beyond the table of {lut_len}"));
                    }
                    // Collected in place: the indices' memory becomes the floats'.
                    return Ok(ArrayData::Floats(indices.into_iter().map(|i| lut[i as usize]).collect()));
                }
                b't' => {
                    let lut_len = u32::from_le_bytes(self.at(at + 1, 4)?.try_into().unwrap()) as usize;
                    let lut_bytes = self.at(at + 5, lut_len * elem.size())?;
                    let lut: Vec<Scalar> =
                        lut_bytes.chunks_exact(elem.size()).map(|c| elem.read(c)).collect();
                    ints(at + 5 + lut_bytes.len() as u64, Elem::U32)?
                        .into_iter()
                        .map(|i| {
                            lut.get(i as usize)
                                .copied()
                                .ok_or_else(|| format!("lookup index {i} beyond the table of {lut_len}"))
                        })
                        .collect::<Checked<_>>()?
                }
                other => return Err(format!("unknown float array compression code {other}")),
            }));
        }
        let len = scalars.checked_mul(elem.size()).ok_or_else(too_large)?;
        self.at(at, len).map(ArrayData::Raw).map_err(|_| too_large())
    }
}

/// An array as stored uncompressed, or decoded.
enum ArrayData<'a> {
    Raw(&'a [u8]),
    Floats(Vec<f32>),
    /// A compressed integer array, decoded.
    Ints(Vec<i64>),
    Scalars(Vec<Scalar>),
}

/// One decoded number, or a token or string index.
#[derive(Clone, Copy, Debug)]
enum Scalar {
    F32(f32),
    F64(f64),
    I64(i64),
    Token(u32),
    Str(u32),
}

impl Scalar {
    fn f32(&self) -> f32 {
        match *self {
            Scalar::F32(v) => v,
            Scalar::F64(v) => v as f32,
            Scalar::I64(v) => v as f32,
            Scalar::Token(v) | Scalar::Str(v) => v as f32,
        }
    }
    fn f64(&self) -> f64 {
        match *self {
            Scalar::F32(v) => v as f64,
            Scalar::F64(v) => v,
            Scalar::I64(v) => v as f64,
            Scalar::Token(v) | Scalar::Str(v) => v as f64,
        }
    }
    fn i64(&self) -> i64 {
        match *self {
            Scalar::F32(v) => v as i64,
            Scalar::F64(v) => v as i64,
            Scalar::I64(v) => v,
            Scalar::Token(v) | Scalar::Str(v) => v as i64,
        }
    }
}

/// How one scalar of an element is stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Elem {
    Half,
    F32,
    F64,
    U8,
    I32,
    U32,
    I64,
    Token,
    Str,
}

impl Elem {
    fn of(kind: Type) -> Elem {
        use Type::*;
        match kind {
            Half | Vec2h | Vec3h | Vec4h | Quath => Elem::Half,
            Float | Vec2f | Vec3f | Vec4f | Quatf => Elem::F32,
            Double | TimeCode | Vec2d | Vec3d | Vec4d | Quatd | Matrix2d | Matrix3d | Matrix4d
            | DoubleVector => Elem::F64,
            Bool | Uchar => Elem::U8,
            Int | Vec2i | Vec3i | Vec4i => Elem::I32,
            Uint => Elem::U32,
            Int64 | Uint64 => Elem::I64,
            String => Elem::Str,
            _ => Elem::Token,
        }
    }

    fn size(self) -> usize {
        match self {
            Elem::U8 => 1,
            Elem::Half => 2,
            Elem::F32 | Elem::I32 | Elem::U32 | Elem::Token | Elem::Str => 4,
            Elem::F64 | Elem::I64 => 8,
        }
    }

    /// Decodes one scalar from exactly [`Elem::size`] bytes.
    fn read(self, b: &[u8]) -> Scalar {
        match self {
            Elem::Half => Scalar::F32(half_to_f32(u16::from_le_bytes([b[0], b[1]]))),
            Elem::F32 => Scalar::F32(f32::from_le_bytes(b.try_into().unwrap())),
            Elem::F64 => Scalar::F64(f64::from_le_bytes(b.try_into().unwrap())),
            Elem::U8 => Scalar::I64(b[0] as i64),
            Elem::I32 => Scalar::I64(i32::from_le_bytes(b.try_into().unwrap()) as i64),
            Elem::U32 => Scalar::I64(u32::from_le_bytes(b.try_into().unwrap()) as i64),
            Elem::I64 => Scalar::I64(i64::from_le_bytes(b.try_into().unwrap())),
            Elem::Token => Scalar::Token(u32::from_le_bytes(b.try_into().unwrap())),
            Elem::Str => Scalar::Str(u32::from_le_bytes(b.try_into().unwrap())),
        }
    }

    /// A small integer (inline vectors and matrices) as this element's scalar.
    fn small_int(self, x: i8) -> Scalar {
        match self {
            Elem::Half | Elem::F32 => Scalar::F32(x as f32),
            Elem::F64 => Scalar::F64(x as f64),
            _ => Scalar::I64(x as i64),
        }
    }
}

impl Crate<'_> {
    /// Plain little-endian elements copied out of `bytes`, a part of the file (which need not
    /// be aligned), read from the file itself when there is one.
    fn copy_out<T: bytemuck::Pod>(&self, bytes: &[u8]) -> Checked<Vec<T>> {
        // Zeroed by the allocator (fresh pages, untouched until the copy), not element by element.
        let mut out: Vec<T> = bytemuck::zeroed_vec(bytes.len() / std::mem::size_of::<T>());
        let target = bytemuck::cast_slice_mut::<T, u8>(&mut out);
        crate::io::input::advise_huge_pages(target);
        match self.file {
            Some(file) => {
                use std::os::unix::fs::FileExt;
                let offset = bytes.as_ptr() as usize - self.bytes.as_ptr() as usize;
                file.read_exact_at(target, offset as u64).map_err(|e| format!("reading an array: {e}"))?;
            }
            None => target.copy_from_slice(bytes),
        }
        Ok(out)
    }
}

impl usda::FileArrays for Crate<'_> {
    fn append_floats(&self, array: &usda::FileArray, out: &mut Vec<f32>) -> Checked<()> {
        let bytes = self.at(array.offset, array.bytes)?;
        let count = bytes.len() / 4;
        if bytes.len() != count * 4 {
            return Err(format!("an array of {} bytes is not a whole number of floats", bytes.len()));
        }
        // Straight into the spare capacity: the pages of a large reserved array are touched once,
        // by the copy, not zeroed first.
        out.reserve(count);
        let target = out.spare_capacity_mut()[..count].as_mut_ptr().cast::<u8>();
        match self.file {
            Some(file) => {
                use std::os::fd::AsRawFd;
                let mut done = 0;
                while done < bytes.len() {
                    let at = (array.offset + done as u64) as libc::off_t;
                    // SAFETY: writes at most the `bytes.len() - done` bytes left of the `count`
                    // spare floats reserved above, which nothing else refers to.
                    let read = unsafe {
                        libc::pread(file.as_raw_fd(), target.add(done).cast(), bytes.len() - done, at)
                    };
                    match read {
                        0 => return Err("reading an array: the file ends early".into()),
                        n if n > 0 => done += n as usize,
                        _ => {
                            let error = std::io::Error::last_os_error();
                            if error.kind() != std::io::ErrorKind::Interrupted {
                                return Err(format!("reading an array: {error}"));
                            }
                        }
                    }
                }
            }
            // SAFETY: `bytes` (a borrow of the map) and the spare floats reserved above do not
            // overlap, and the spare capacity holds `bytes.len()` bytes.
            None => unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), target, bytes.len()) },
        }
        // SAFETY: every byte of the first `count` spare floats was written above; an f32 takes
        // any bits.
        unsafe { out.set_len(out.len() + count) };
        Ok(())
    }
}

/// IEEE half to single precision.
fn half_to_f32(h: u16) -> f32 {
    let sign = ((h >> 15) as u32) << 31;
    let exp = ((h >> 10) & 0x1f) as u32;
    let mant = (h & 0x3ff) as u32;
    let bits = match (exp, mant) {
        (0, 0) => sign,
        (0, m) => {
            // Subnormal: normalise.
            let shift = m.leading_zeros() - 21;
            sign | ((113 - shift) << 23) | ((m << (shift + 13)) & 0x7f_ffff)
        }
        (31, m) => sign | 0x7f80_0000 | (m << 13),
        (e, m) => sign | ((e + 112) << 23) | (m << 13),
    };
    f32::from_bits(bits)
}

/// Where a prim's children and variant bodies are, and the order its parent lists them in.
struct Tree<'t> {
    children: &'t HashMap<u32, Vec<u32>>,
    variants: &'t HashMap<u32, Vec<(String, u32)>>,
    rank: &'t dyn Fn(u32, &str) -> usize,
}

/// `{set=variant}` → (set, variant).
fn variant_element(token: &str) -> Option<(&str, &str)> {
    let inner = token.strip_prefix('{')?.strip_suffix('}')?;
    let (set, variant) = inner.split_once('=')?;
    (!set.is_empty() && !variant.is_empty()).then_some((set, variant))
}

/// Sequential reads of an out-of-line value (list ops, vectors, references), every one checked
/// against the file.
struct Cursor<'c, 'a> {
    file: &'c Crate<'a>,
    at: u64,
}

impl Cursor<'_, '_> {
    fn bytes(&mut self, n: usize) -> Checked<&[u8]> {
        let bytes = self.file.at(self.at, n)?;
        self.at += n as u64;
        Ok(bytes)
    }

    fn u32(&mut self) -> Checked<u32> {
        Ok(u32::from_le_bytes(self.bytes(4)?.try_into().unwrap()))
    }

    fn u64(&mut self) -> Checked<u64> {
        Ok(u64::from_le_bytes(self.bytes(8)?.try_into().unwrap()))
    }

    fn f64(&mut self) -> Checked<f64> {
        Ok(f64::from_le_bytes(self.bytes(8)?.try_into().unwrap()))
    }

    fn string(&mut self) -> Checked<String> {
        let index = self.u32()?;
        self.file.string_at(index)
    }

    fn layer_offset(&mut self) -> Checked<LayerOffset> {
        Ok(LayerOffset { offset: self.f64()?, scale: self.f64()? })
    }

    /// `u64` count, then that many items of at least `min_size` bytes each (checked against
    /// the file before anything is allocated).
    fn vector<T>(&mut self, min_size: u64, mut item: impl FnMut(&mut Self) -> Checked<T>) -> Checked<Vec<T>> {
        let count = self.u64()?;
        let room = (self.file.bytes.len() as u64).saturating_sub(self.at);
        if count.checked_mul(min_size).is_none_or(|need| need > room) {
            return Err(format!("{count} items do not fit in the file"));
        }
        (0..count).map(|_| item(self)).collect()
    }

    /// A list op: a header byte (explicit, then which item lists follow), then the lists in the
    /// order explicit, added, prepended, appended, deleted, ordered.
    fn list_op<T>(
        mut self,
        min_size: u64,
        mut item: impl FnMut(&mut Self) -> Checked<T>,
    ) -> Checked<ListOp<T>> {
        const EXPLICIT: u8 = 1;
        const EXPLICIT_ITEMS: u8 = 1 << 1;
        const ADDED: u8 = 1 << 2;
        const DELETED: u8 = 1 << 3;
        const ORDERED: u8 = 1 << 4;
        const PREPENDED: u8 = 1 << 5;
        const APPENDED: u8 = 1 << 6;
        let header = self.bytes(1)?[0];
        let mut op = ListOp::default();
        if header & EXPLICIT != 0 {
            op.explicit = Some(Vec::new());
        }
        if header & EXPLICIT_ITEMS != 0 {
            op.explicit = Some(self.vector(min_size, &mut item)?);
        }
        let mut added = Vec::new();
        if header & ADDED != 0 {
            added = self.vector(min_size, &mut item)?;
        }
        if header & PREPENDED != 0 {
            op.prepended = self.vector(min_size, &mut item)?;
        }
        if header & APPENDED != 0 {
            op.appended = self.vector(min_size, &mut item)?;
        }
        if header & DELETED != 0 {
            op.deleted = self.vector(min_size, &mut item)?;
        }
        let _ordered = header & ORDERED != 0; // orders only; nothing follows that coif needs
        op.appended.extend(added);
        Ok(op)
    }

    /// A reference (asset, prim path, layer offset, custom data) or a payload (asset, prim
    /// path, and a layer offset in newer files).
    fn asset_arc(&mut self, offset: bool, custom_data: bool) -> Checked<AssetArc> {
        let asset = self.string()?;
        let path = self.u32()?;
        // The empty path (no prim named: the default prim) has its own index.
        let prim_path = self.file.path_at(path)?;
        let prim_path = (!prim_path.is_empty() && prim_path != "/").then_some(prim_path);
        let offset = if offset { self.layer_offset()? } else { LayerOffset::default() };
        if custom_data {
            // A dictionary: count, then per entry a string index and an 8-byte jump to its value.
            self.vector(12, |c| c.bytes(12).map(|_| ()))?;
        }
        Ok(AssetArc { asset, prim_path, offset })
    }
}

/// Rebuilds path entries from the depth-first tree, refusing repeats, cycles and bad indices.
fn build_paths(
    path_indices: &[u32],
    element_tokens: &[i32],
    jumps: &[i32],
    path_count: usize,
    token_count: usize,
) -> Checked<Vec<Option<PathEntry>>> {
    let nodes = path_indices.len();
    let mut paths: Vec<Option<PathEntry>> = vec![None; path_count];
    if nodes == 0 {
        return Ok(paths);
    }
    let mut visited = vec![false; nodes];
    let mut pending: Vec<(usize, Option<u32>)> = vec![(0, None)];
    while let Some((mut i, mut parent)) = pending.pop() {
        loop {
            if i >= nodes || visited[i] {
                return Err(format!("PATHS: the tree reaches node {i} twice or beyond its {nodes} nodes"));
            }
            visited[i] = true;
            let index = path_indices[i];
            let slot = paths
                .get_mut(index as usize)
                .ok_or_else(|| format!("PATHS: path index {index} beyond the {path_count} paths"))?;
            if slot.is_some() {
                return Err(format!("PATHS: path index {index} appears twice"));
            }
            if parent.is_none() && i != 0 {
                return Err("PATHS: more than one root".into());
            }
            let token = element_tokens[i];
            let token_index = (token as i64).unsigned_abs();
            if parent.is_some() && token_index as usize >= token_count {
                return Err(format!("PATHS: element token {token} beyond the {token_count} tokens"));
            }
            *slot = Some(PathEntry { parent, token: token_index as u32, property: token < 0 });
            let jump = jumps[i];
            let has_child = jump > 0 || jump == -1;
            let has_sibling = jump >= 0;
            if jump < -2 {
                return Err(format!("PATHS: bad jump {jump} at node {i}"));
            }
            if has_child && has_sibling {
                pending.push((i + jump as usize, parent));
            }
            if has_child {
                parent = Some(index);
            } else if !has_sibling {
                break;
            }
            i += 1;
        }
    }
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_well_formed_tree_rebuilds() {
        // / -> A (-> A.x), B: root child-only, A child and sibling 2 ahead, A.x leaf, B leaf.
        let paths = build_paths(&[0, 1, 3, 2], &[0, 1, -3, 2], &[-1, 2, -2, -2], 4, 4).unwrap();
        let entry = |i: usize| paths[i].unwrap();
        assert!(entry(0).parent.is_none());
        assert_eq!((entry(1).parent, entry(1).token), (Some(0), 1));
        assert_eq!((entry(3).parent, entry(3).token, entry(3).property), (Some(1), 3, true));
        assert_eq!(entry(2).parent, Some(0));
    }

    #[test]
    fn repeats_cycles_and_bad_indices_are_refused() {
        // A sibling jump landing on the child that follows: the node is reached twice.
        let twice = build_paths(&[0, 1, 2], &[0, 1, 2], &[-1, 1, -2], 3, 3).unwrap_err();
        assert!(twice.contains("twice"), "{twice}");
        let repeated = build_paths(&[0, 1, 1], &[0, 1, 2], &[-1, 0, -2], 3, 3).unwrap_err();
        assert!(repeated.contains("appears twice"), "{repeated}");
        let beyond = build_paths(&[0, 1], &[0, 1], &[-1, 5], 2, 3).unwrap_err();
        assert!(beyond.contains("beyond"), "{beyond}");
        let token = build_paths(&[0, 1], &[0, -9], &[-1, -2], 2, 3).unwrap_err();
        assert!(token.contains("element token"), "{token}");
        let index = build_paths(&[0, 7], &[0, 1], &[-1, -2], 2, 3).unwrap_err();
        assert!(index.contains("path index 7"), "{index}");
        let root_sibling = build_paths(&[0, 1], &[0, 1], &[0, -2], 2, 3).unwrap_err();
        assert!(root_sibling.contains("root"), "{root_sibling}");
        assert!(build_paths(&[0], &[i32::MIN], &[-3], 1, 1).is_err(), "bad jump");
    }

    #[test]
    fn halves_convert_exactly() {
        assert_eq!(half_to_f32(0x3c00), 1.0);
        assert_eq!(half_to_f32(0xc000), -2.0);
        assert_eq!(half_to_f32(0x0001), 2f32.powi(-24));
        assert_eq!(half_to_f32(0x7bff), 65504.0);
        assert!(half_to_f32(0x7e00).is_nan());
        assert_eq!(half_to_f32(0xfc00), f32::NEG_INFINITY);
    }
}
