//! Writing a crate file: values go to the file as they are added (large arrays straight from
//! the groom's memory), specs and their fields are interned, and the structural sections and
//! table of contents follow at [`Encoder::finish`], which also patches the bootstrap header.
use std::collections::HashMap;
use std::io::{Seek, SeekFrom, Write};

use super::compress::{compress_ints, lz4_compress};
use super::format::{rep, SpecType, Type, BOOTSTRAP_SIZE, MAGIC, MIN_COMPRESSED_ARRAY, SECTIONS, VERSION};

/// A value representation: type, flags and a 48-bit payload (inline data or a file offset).
pub type Rep = u64;

/// One path of the layer: the pseudo-root (index 0), a prim or a property.
struct PathNode {
    parent: u32,
    token: u32,
    property: bool,
    children: Vec<u32>,
}

pub struct Encoder<W: Write + Seek> {
    out: W,
    position: u64,
    tokens: Vec<String>,
    token_index: HashMap<String, u32>,
    strings: Vec<u32>,
    fields: Vec<(u32, Rep)>,
    field_index: HashMap<(u32, Rep), u32>,
    fieldsets: Vec<u32>,
    specs: Vec<(u32, u32, u32)>,
    paths: Vec<PathNode>,
}

impl<W: Write + Seek> Encoder<W> {
    /// Starts a file: the bootstrap, its TOC offset patched at [`Encoder::finish`].
    pub fn new(mut out: W) -> std::io::Result<Self> {
        out.write_all(&[0u8; BOOTSTRAP_SIZE])?;
        let root = PathNode { parent: u32::MAX, token: 0, property: false, children: Vec::new() };
        let mut encoder = Encoder {
            out,
            position: BOOTSTRAP_SIZE as u64,
            tokens: Vec::new(),
            token_index: HashMap::new(),
            strings: Vec::new(),
            fields: Vec::new(),
            field_index: HashMap::new(),
            fieldsets: Vec::new(),
            specs: Vec::new(),
            paths: vec![root],
        };
        encoder.token("");
        Ok(encoder)
    }

    pub fn token(&mut self, text: &str) -> u32 {
        if let Some(&i) = self.token_index.get(text) {
            return i;
        }
        let i = self.tokens.len() as u32;
        self.tokens.push(text.to_string());
        self.token_index.insert(text.to_string(), i);
        i
    }

    /// The path of a child prim (`property` false) or property of `parent` (0 = pseudo-root).
    pub fn child_path(&mut self, parent: u32, name: &str, property: bool) -> u32 {
        let token = self.token(name);
        let index = self.paths.len() as u32;
        self.paths.push(PathNode { parent, token, property, children: Vec::new() });
        self.paths[parent as usize].children.push(index);
        index
    }

    /// Adds a spec at `path` with `fields` (name, value).
    pub fn spec(&mut self, path: u32, kind: SpecType, fields: &[(&str, Rep)]) {
        let fieldset = self.fieldsets.len() as u32;
        for &(name, value) in fields {
            let key = (self.token(name), value);
            let next = self.fields.len() as u32;
            let index = *self.field_index.entry(key).or_insert(next);
            if index == next {
                self.fields.push(key);
            }
            self.fieldsets.push(index);
        }
        self.fieldsets.push(u32::MAX);
        self.specs.push((path, fieldset, kind as u32));
    }

    pub fn token_value(&mut self, text: &str) -> Rep {
        rep::inline(Type::Token, self.token(text) as u64)
    }

    pub fn string_value(&mut self, text: &str) -> Rep {
        let token = self.token(text);
        let index = match self.strings.iter().position(|&t| t == token) {
            Some(i) => i,
            None => {
                self.strings.push(token);
                self.strings.len() - 1
            }
        };
        rep::inline(Type::String, index as u64)
    }

    /// A double, inline when a float holds it exactly (as USD does).
    pub fn double_value(&mut self, value: f64) -> std::io::Result<Rep> {
        if (value as f32) as f64 == value || value.is_nan() {
            return Ok(rep::inline(Type::Double, (value as f32).to_bits() as u64));
        }
        let at = self.position;
        self.write(&value.to_le_bytes())?;
        Ok(rep::at(Type::Double, at))
    }

    pub fn token_vector(&mut self, names: &[&str]) -> std::io::Result<Rep> {
        let indices: Vec<u32> = names.iter().map(|n| self.token(n)).collect();
        let at = self.position;
        self.write(&(indices.len() as u64).to_le_bytes())?;
        self.write(bytemuck::cast_slice(&indices))?;
        Ok(rep::at(Type::TokenVector, at))
    }

    /// An array of plain little-endian elements (`bytes` holds `count` of them), 8-aligned.
    pub fn array(&mut self, kind: Type, count: usize, bytes: &[u8]) -> std::io::Result<Rep> {
        if count == 0 {
            return Ok(rep::array_at(kind, 0));
        }
        self.align()?;
        let at = self.position;
        self.write(&(count as u64).to_le_bytes())?;
        self.write(bytes)?;
        Ok(rep::array_at(kind, at))
    }

    /// An `int[]`, integer-compressed from 16 elements on (as USD writes them).
    pub fn int_array(&mut self, values: &[i32]) -> std::io::Result<Rep> {
        if values.len() < MIN_COMPRESSED_ARRAY {
            return self.array(Type::Int, values.len(), bytemuck::cast_slice(values));
        }
        let at = self.position;
        let packed = compress_ints(values);
        self.write(&(values.len() as u64).to_le_bytes())?;
        self.write(&(packed.len() as u64).to_le_bytes())?;
        self.write(&packed)?;
        Ok(rep::compressed(rep::array_at(Type::Int, at)))
    }

    /// A `float[]`: as a lookup table and compressed indices when it holds few distinct values
    /// (widths usually do), else plain — what usd-core writes, without its integer form.
    pub fn float_array(&mut self, values: &[f32]) -> std::io::Result<Rep> {
        match lookup_table(values) {
            None => self.array(Type::Float, values.len(), bytemuck::cast_slice(values)),
            Some((table, indices)) => {
                let at = self.position;
                self.write(&(values.len() as u64).to_le_bytes())?;
                self.write(b"t")?;
                self.write(&(table.len() as u32).to_le_bytes())?;
                self.write(bytemuck::cast_slice(&table))?;
                let packed = compress_ints(&indices);
                self.write(&(packed.len() as u64).to_le_bytes())?;
                self.write(&packed)?;
                Ok(rep::compressed(rep::array_at(Type::Float, at)))
            }
        }
    }

    /// Time samples: the times as a double vector, then one value per time.
    pub fn time_samples(&mut self, times: &[f64], values: &[Rep]) -> std::io::Result<Rep> {
        let times_at = self.position;
        self.write(&(times.len() as u64).to_le_bytes())?;
        self.write(bytemuck::cast_slice(times))?;
        let at = self.position;
        // Each part starts with an offset to it from where that offset is stored.
        self.write(&8i64.to_le_bytes())?;
        self.write(&rep::at(Type::DoubleVector, times_at).to_le_bytes())?;
        self.write(&8i64.to_le_bytes())?;
        self.write(&(values.len() as u64).to_le_bytes())?;
        self.write(bytemuck::cast_slice(values))?;
        Ok(rep::at(Type::TimeSamples, at))
    }

    fn write(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.out.write_all(bytes)?;
        self.position += bytes.len() as u64;
        Ok(())
    }

    fn align(&mut self) -> std::io::Result<()> {
        let pad = (8 - self.position % 8) % 8;
        self.write(&[0u8; 8][..pad as usize])
    }

    /// Writes the structural sections and the table of contents; returns the output.
    pub fn finish(mut self) -> std::io::Result<W> {
        let mut sections = Vec::new();
        let mut token_bytes = Vec::new();
        for token in &self.tokens {
            token_bytes.extend_from_slice(token.as_bytes());
            token_bytes.push(0);
        }
        let mut section = |name: &'static str, encoder: &mut Self, body: Vec<u8>| -> std::io::Result<()> {
            encoder.align()?;
            sections.push((name, encoder.position, body.len() as u64));
            encoder.write(&body)
        };

        let mut tokens = u64s(&[self.tokens.len() as u64, token_bytes.len() as u64]);
        push_blob(&mut tokens, &lz4_compress(&token_bytes));
        section(SECTIONS[0], &mut self, tokens)?;

        let mut strings = u64s(&[self.strings.len() as u64]);
        strings.extend_from_slice(bytemuck::cast_slice(&self.strings));
        section(SECTIONS[1], &mut self, strings)?;

        let mut fields = u64s(&[self.fields.len() as u64]);
        let names: Vec<u32> = self.fields.iter().map(|f| f.0).collect();
        let reps: Vec<u64> = self.fields.iter().map(|f| f.1).collect();
        push_blob(&mut fields, &compress_ints(&names));
        push_blob(&mut fields, &lz4_compress(bytemuck::cast_slice(&reps)));
        section(SECTIONS[2], &mut self, fields)?;

        let mut fieldsets = u64s(&[self.fieldsets.len() as u64]);
        push_blob(&mut fieldsets, &compress_ints(&self.fieldsets));
        section(SECTIONS[3], &mut self, fieldsets)?;

        let (path_indices, element_tokens, jumps) = self.encode_paths();
        let mut paths = u64s(&[self.paths.len() as u64, path_indices.len() as u64]);
        push_blob(&mut paths, &compress_ints(&path_indices));
        push_blob(&mut paths, &compress_ints(&element_tokens));
        push_blob(&mut paths, &compress_ints(&jumps));
        section(SECTIONS[4], &mut self, paths)?;

        let mut specs = u64s(&[self.specs.len() as u64]);
        for column in 0..3 {
            let values: Vec<u32> = self.specs.iter().map(|s| [s.0, s.1, s.2][column]).collect();
            push_blob(&mut specs, &compress_ints(&values));
        }
        section(SECTIONS[5], &mut self, specs)?;

        let toc_at = self.position;
        let mut toc = u64s(&[sections.len() as u64]);
        for (name, start, size) in sections {
            let mut field = [0u8; 16];
            field[..name.len()].copy_from_slice(name.as_bytes());
            toc.extend_from_slice(&field);
            toc.extend_from_slice(&start.to_le_bytes());
            toc.extend_from_slice(&size.to_le_bytes());
        }
        self.write(&toc)?;

        let mut boot = Vec::with_capacity(24);
        boot.extend_from_slice(MAGIC);
        boot.extend_from_slice(&[VERSION.0, VERSION.1, VERSION.2, 0, 0, 0, 0, 0]);
        boot.extend_from_slice(&toc_at.to_le_bytes());
        self.out.seek(SeekFrom::Start(0))?;
        self.out.write_all(&boot)?;
        self.out.seek(SeekFrom::End(0))?;
        Ok(self.out)
    }

    /// The path tree in depth-first order: each node's path index, element token (negated for
    /// properties) and jump (-2 leaf without a next sibling, -1 child only, 0 sibling only,
    /// else the distance to the next sibling, the child following directly).
    fn encode_paths(&self) -> (Vec<u32>, Vec<i32>, Vec<i32>) {
        let mut order = Vec::with_capacity(self.paths.len());
        let mut sibling_after = vec![false; self.paths.len()];
        let mut stack = vec![0u32];
        while let Some(node) = stack.pop() {
            order.push(node);
            let children = &self.paths[node as usize].children;
            for (k, &child) in children.iter().enumerate().rev() {
                sibling_after[child as usize] = k + 1 < children.len();
                stack.push(child);
            }
        }
        let mut position = vec![0usize; self.paths.len()];
        for (i, &node) in order.iter().enumerate() {
            position[node as usize] = i;
        }
        let mut jumps = Vec::with_capacity(order.len());
        for &node in &order {
            let entry = &self.paths[node as usize];
            let has_child = !entry.children.is_empty();
            let jump = match (has_child, sibling_after[node as usize]) {
                (false, false) => -2,
                (true, false) => -1,
                (false, true) => 0,
                (true, true) => {
                    let parent = &self.paths[entry.parent as usize].children;
                    let k = parent.iter().position(|&c| c == node).unwrap();
                    (position[parent[k + 1] as usize] - position[node as usize]) as i32
                }
            };
            jumps.push(jump);
        }
        let tokens = order
            .iter()
            .map(|&n| {
                let e = &self.paths[n as usize];
                if e.property {
                    -(e.token as i32)
                } else {
                    e.token as i32
                }
            })
            .collect();
        (order, tokens, jumps)
    }
}

/// The distinct values (at most a quarter of the count, and 1024) and each value's index, or
/// `None` when there are more. Values are compared bit for bit, so every float reads back exactly.
fn lookup_table(values: &[f32]) -> Option<(Vec<f32>, Vec<u32>)> {
    if values.len() < MIN_COMPRESSED_ARRAY {
        return None;
    }
    let limit = (values.len() / 4).min(1024);
    let mut table = Vec::new();
    let mut index = BitsIndex::default();
    let mut indices = Vec::with_capacity(values.len());
    let mut last = None;
    for &v in values {
        let bits = v.to_bits();
        // Runs of one value (a strand's constant width) skip the lookup.
        let i = match last {
            Some((b, i)) if b == bits => i,
            _ => match index.find_or_add(bits, table.len() as u32) {
                Some(i) => i,
                None if table.len() == limit => return None,
                None => {
                    table.push(v);
                    table.len() as u32 - 1
                }
            },
        };
        last = Some((bits, i));
        indices.push(i);
    }
    Some((table, indices))
}

/// Float bits → table index for [`lookup_table`]: open addressing over 4 × its 1024 entries at
/// most, with a multiplicative hash (SipHash cost more than the rest of the crate writer).
struct BitsIndex {
    keys: Box<[u32; BitsIndex::SLOTS]>,
    /// Index + 1; 0 marks an empty slot.
    values: Box<[u32; BitsIndex::SLOTS]>,
}

impl Default for BitsIndex {
    fn default() -> Self {
        BitsIndex { keys: Box::new([0; Self::SLOTS]), values: Box::new([0; Self::SLOTS]) }
    }
}

impl BitsIndex {
    const SLOTS: usize = 4096;

    /// The index stored for `bits`; if there is none, stores `next` (unless the table is
    /// full at 1024 entries, which [`lookup_table`] never passes) and returns `None`.
    fn find_or_add(&mut self, bits: u32, next: u32) -> Option<u32> {
        let mut slot = (bits.wrapping_mul(0x9E37_79B1) >> 20) as usize;
        loop {
            match self.values[slot] {
                0 => {
                    if next < 1024 {
                        self.keys[slot] = bits;
                        self.values[slot] = next + 1;
                    }
                    return None;
                }
                v if self.keys[slot] == bits => return Some(v - 1),
                _ => slot = (slot + 1) % Self::SLOTS,
            }
        }
    }
}

fn u64s(values: &[u64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// A compressed block behind its byte size.
fn push_blob(out: &mut Vec<u8>, blob: &[u8]) {
    out.extend_from_slice(&(blob.len() as u64).to_le_bytes());
    out.extend_from_slice(blob);
}
