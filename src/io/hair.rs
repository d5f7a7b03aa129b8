//! Cem Yuksel's binary `.hair` format, used by many public hair data sets.
//!
//! Layout (little endian): a 128-byte header — `"HAIR"`, strand count (u32), point count (u32),
//! array flags (u32), default segment count (u32), default thickness (f32), default transparency
//! (f32), default colour (3 × f32), 88 bytes of free text — then the arrays the flags announce, in
//! this order: segments (u16 per strand), points (3 × f32), thickness (f32), transparency (f32),
//! colour (3 × f32), each per point.
//!
//! Every count is checked against the file's real size before anything is allocated, so a
//! hostile header cannot make the reader reserve gigabytes.
use std::io::Write;
use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::groom::{attr, AttributeRate, Groom};

pub const SIGNATURE: &[u8; 4] = b"HAIR";
const HEADER_SIZE: usize = 128;
const INFO_SIZE: usize = 88;

const HAS_SEGMENTS: u32 = 1 << 0;
const HAS_POINTS: u32 = 1 << 1;
const HAS_THICKNESS: u32 = 1 << 2;
const HAS_TRANSPARENCY: u32 = 1 << 3;
const HAS_COLOR: u32 = 1 << 4;
const KNOWN_FLAGS: u32 = HAS_SEGMENTS | HAS_POINTS | HAS_THICKNESS | HAS_TRANSPARENCY | HAS_COLOR;

struct Header {
    strands: u32,
    points: u32,
    flags: u32,
    default_segments: u32,
    default_thickness: f32,
    default_transparency: f32,
    default_color: [f32; 3],
}

/// A little-endian cursor over the file's bytes; callers have checked the sizes beforehand.
struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let out = self.bytes[self.at..self.at + N].try_into().unwrap();
        self.at += N;
        out
    }
    fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take())
    }
    fn vec3(&mut self) -> Vec3 {
        Vec3::new(self.f32(), self.f32(), self.f32())
    }
}

/// Parses a `.hair` file already read into memory; `path` only names it in errors.
pub fn read(bytes: &[u8], path: &Path) -> Result<Groom> {
    let bad = |message: String| Error::format(path, message);
    if bytes.len() < HEADER_SIZE {
        return Err(bad(format!(
            "truncated header: the file has {} bytes, a .hair header needs {HEADER_SIZE}",
            bytes.len()
        )));
    }
    if &bytes[..4] != SIGNATURE {
        return Err(bad(format!(
            "not a .hair file: signature is {:?}, expected \"HAIR\"",
            String::from_utf8_lossy(&bytes[..4])
        )));
    }
    let mut cursor = Cursor { bytes, at: 4 };
    let header = Header {
        strands: cursor.u32(),
        points: cursor.u32(),
        flags: cursor.u32(),
        default_segments: cursor.u32(),
        default_thickness: cursor.f32(),
        default_transparency: cursor.f32(),
        default_color: [cursor.f32(), cursor.f32(), cursor.f32()],
    };
    cursor.at = HEADER_SIZE;

    if header.flags & !KNOWN_FLAGS != 0 {
        return Err(bad(format!("unknown array flags 0x{:x} in the header", header.flags & !KNOWN_FLAGS)));
    }
    if header.flags & HAS_POINTS == 0 {
        return Err(bad("the header announces no points array".into()));
    }
    let expected = expected_size(&header);
    if expected != bytes.len() as u64 {
        let (strands, points) = (header.strands, header.points);
        return Err(bad(if expected > bytes.len() as u64 {
            format!(
                "truncated or corrupt: {strands} strands and {points} points need {expected} bytes, the file has {}",
                bytes.len()
            )
        } else {
            format!(
                "{} unexpected bytes after the data of {strands} strands and {points} points",
                bytes.len() as u64 - expected
            )
        }));
    }

    // Every strand has at least two points, which the file holds: this bounds the strand count
    // by the file's length even when the header gives no per-strand segment counts.
    if header.strands as u64 * 2 > header.points as u64 {
        return Err(bad(format!(
            "the header's {} strands need at least {} points, it announces {}",
            header.strands,
            header.strands as u64 * 2,
            header.points
        )));
    }
    // Sizes are now known to fit in the file, so allocations are bounded by its length.
    let strands = header.strands as usize;
    let mut strand_offsets = Vec::with_capacity(strands + 1);
    strand_offsets.push(0u32);
    let mut total = 0u64;
    for strand in 0..strands {
        let segments =
            if header.flags & HAS_SEGMENTS != 0 { cursor.u16() as u32 } else { header.default_segments };
        if segments == 0 {
            return Err(bad(format!("strand {strand} has 0 segments; a strand needs at least one")));
        }
        total += segments as u64 + 1;
        if total > header.points as u64 {
            return Err(bad(format!(
                "strand {strand}: segment counts add up to more than the header's {} points",
                header.points
            )));
        }
        strand_offsets.push(total as u32);
    }
    if total != header.points as u64 {
        return Err(bad(format!(
            "segment counts add up to {total} points but the header says {}",
            header.points
        )));
    }

    let vertices = header.points as usize;
    let points: Vec<Vec3> = (0..vertices).map(|_| cursor.vec3()).collect();
    let widths = if header.flags & HAS_THICKNESS != 0 {
        (0..vertices).map(|_| cursor.f32()).collect()
    } else {
        vec![header.default_thickness; vertices]
    };
    let mut groom = Groom {
        points,
        strand_offsets,
        widths,
        strand_ids: (0..header.strands).collect(),
        ..Default::default()
    };
    if header.flags & HAS_TRANSPARENCY != 0 {
        let data = (0..vertices).map(|_| cursor.f32()).collect();
        groom.set_attribute(crate::groom::Attribute::new(attr::TRANSPARENCY, AttributeRate::Vertex, 1, data));
    } else if header.default_transparency != 0.0 {
        let data = vec![header.default_transparency; vertices];
        groom.set_attribute(crate::groom::Attribute::new(attr::TRANSPARENCY, AttributeRate::Vertex, 1, data));
    }
    if header.flags & HAS_COLOR != 0 {
        let data = (0..vertices * 3).map(|_| cursor.f32()).collect();
        groom.set_attribute(crate::groom::Attribute::new(attr::COLOR, AttributeRate::Vertex, 3, data));
    } else if header.default_color != [0.0; 3] {
        let data = header.default_color.repeat(vertices);
        groom.set_attribute(crate::groom::Attribute::new(attr::COLOR, AttributeRate::Vertex, 3, data));
    }
    debug_assert_eq!(cursor.at, bytes.len());
    Ok(groom)
}

fn expected_size(header: &Header) -> u64 {
    let (strands, points) = (header.strands as u64, header.points as u64);
    let mut size = HEADER_SIZE as u64 + 12 * points;
    if header.flags & HAS_SEGMENTS != 0 {
        size += 2 * strands;
    }
    if header.flags & HAS_THICKNESS != 0 {
        size += 4 * points;
    }
    if header.flags & HAS_TRANSPARENCY != 0 {
        size += 4 * points;
    }
    if header.flags & HAS_COLOR != 0 {
        size += 12 * points;
    }
    size
}

/// What the `.hair` format cannot carry of a groom; the caller may warn about it.
pub fn unsupported(groom: &Groom) -> Vec<String> {
    let mut lost: Vec<String> = groom
        .attributes
        .iter()
        .filter(|a| !matches!(a.name.as_str(), attr::COLOR | attr::TRANSPARENCY))
        .map(|a| format!("attribute '{}'", a.name))
        .collect();
    if groom.root_uvs.is_some() {
        lost.push("root UVs".into());
    }
    if groom.guides.is_some() {
        lost.push("guide flags".into());
    }
    // Every group's basis (`groom.basis` is only the first group's): a linear first prim hid
    // the Bézier curves after it.
    let mut curved: Vec<crate::groom::CurveBasis> = Vec::new();
    for basis in (0..groom.group_count()).map(|g| groom.group(g).basis) {
        if basis != crate::groom::CurveBasis::Linear && !curved.contains(&basis) {
            curved.push(basis);
        }
    }
    for basis in curved {
        lost.push(format!("the {basis:?} basis (points are written as polylines)"));
    }
    let hidden: Vec<String> = (0..groom.group_count())
        .filter(|&g| groom.group(g).invisible)
        .map(|g| groom.group(g).name.clone())
        .collect();
    if !hidden.is_empty() {
        lost.push(format!(
            "the invisibility of {} (their curves are written like the others)",
            hidden.join(", ")
        ));
    }
    lost
}

/// Writes a groom as `.hair`. Arrays whose values are all equal are stored as header defaults.
pub fn write(groom: &Groom, out: &mut dyn Write) -> std::io::Result<()> {
    let vertex_values = |name: &str, components: usize| -> Option<Vec<f32>> {
        let attribute = groom.attribute(name).filter(|a| a.components == components)?;
        let data = attribute.floats();
        Some(match attribute.rate {
            AttributeRate::Vertex => data.into_owned(),
            AttributeRate::Strand => (0..groom.strand_count())
                .flat_map(|s| {
                    let value = &data[s * components..(s + 1) * components];
                    std::iter::repeat_n(value, groom.strand_range(s).len()).flatten().copied()
                })
                .collect(),
        })
    };
    let transparency = vertex_values(attr::TRANSPARENCY, 1);
    let color = vertex_values(attr::COLOR, 3);

    let counts: Vec<usize> = groom.vertex_counts().collect();
    let uniform_counts = counts.windows(2).all(|w| w[0] == w[1]);
    let uniform_widths = groom.widths.windows(2).all(|w| w[0] == w[1]);
    let uniform = |values: &Option<Vec<f32>>, n: usize| {
        values.as_ref().is_none_or(|v| v.chunks(n).collect::<Vec<_>>().windows(2).all(|w| w[0] == w[1]))
    };
    let uniform_transparency = uniform(&transparency, 1);
    let uniform_color = uniform(&color, 3);

    let mut flags = HAS_POINTS;
    if !uniform_counts {
        flags |= HAS_SEGMENTS;
    }
    if !uniform_widths {
        flags |= HAS_THICKNESS;
    }
    if !uniform_transparency {
        flags |= HAS_TRANSPARENCY;
    }
    if !uniform_color {
        flags |= HAS_COLOR;
    }

    let mut header = Vec::with_capacity(HEADER_SIZE);
    header.extend_from_slice(SIGNATURE);
    header.extend_from_slice(&(groom.strand_count() as u32).to_le_bytes());
    header.extend_from_slice(&(groom.vertex_count() as u32).to_le_bytes());
    header.extend_from_slice(&flags.to_le_bytes());
    let default_segments = counts.first().map_or(0, |&c| c as u32 - 1);
    header.extend_from_slice(&default_segments.to_le_bytes());
    header.extend_from_slice(&groom.widths.first().copied().unwrap_or(0.0).to_le_bytes());
    let first = |values: &Option<Vec<f32>>, n: usize| {
        values.as_ref().map(|v| v[..n].to_vec()).unwrap_or(vec![0.0; n])
    };
    header.extend_from_slice(&first(&transparency, 1)[0].to_le_bytes());
    for c in first(&color, 3) {
        header.extend_from_slice(&c.to_le_bytes());
    }
    let mut info = [0u8; INFO_SIZE];
    let text = concat!("coif ", env!("CARGO_PKG_VERSION"));
    info[..text.len()].copy_from_slice(text.as_bytes());
    header.extend_from_slice(&info);
    debug_assert_eq!(header.len(), HEADER_SIZE);
    out.write_all(&header)?;

    if flags & HAS_SEGMENTS != 0 {
        let segments: Vec<u8> = counts.iter().flat_map(|&c| (c as u16 - 1).to_le_bytes()).collect();
        out.write_all(&segments)?;
    }
    write_f32s(out, groom.points.iter().flat_map(|p| p.to_array()))?;
    if flags & HAS_THICKNESS != 0 {
        write_f32s(out, groom.widths.iter().copied())?;
    }
    if let (Some(values), true) = (&transparency, flags & HAS_TRANSPARENCY != 0) {
        write_f32s(out, values.iter().copied())?;
    }
    if let (Some(values), true) = (&color, flags & HAS_COLOR != 0) {
        write_f32s(out, values.iter().copied())?;
    }
    Ok(())
}

/// Checks what the format cannot store at all (as opposed to what it drops).
pub fn check_writable(groom: &Groom, path: &Path) -> Result<()> {
    if let Some((strand, count)) = groom.vertex_counts().enumerate().find(|&(_, c)| c - 1 > u16::MAX as usize)
    {
        return Err(Error::Usage(format!(
            "{}: strand {strand} has {} segments; .hair stores at most {}",
            path.display(),
            count - 1,
            u16::MAX
        )));
    }
    if groom.vertex_count() > u32::MAX as usize {
        return Err(Error::Usage(format!("{}: too many points for .hair", path.display())));
    }
    Ok(())
}

fn write_f32s(out: &mut dyn Write, values: impl Iterator<Item = f32>) -> std::io::Result<()> {
    let mut buffer = Vec::with_capacity(64 * 1024);
    for value in values {
        buffer.extend_from_slice(&value.to_le_bytes());
        if buffer.len() >= 64 * 1024 {
            out.write_all(&buffer)?;
            buffer.clear();
        }
    }
    out.write_all(&buffer)
}
