//! Writes a groom as a USD text stage: one `BasisCurves` prim per curve group at the group's
//! path (`/Groom/Strands` for a groom without groups), `Xform`s above.
//! Large arrays are formatted in fixed-size chunks on all threads and written in order, so the
//! output is the same at any thread count and memory stays bounded. Floats are written in their
//! shortest form that reads back to the same `f32`.
use std::io::Write;
use std::path::Path;

use glam::Vec3;
use rayon::prelude::*;

use super::names;
use crate::error::{Error, Result};
use crate::groom::{AttributeKind, AttributeRate, CurveBasis, CurveGroup, CurveWrap, Groom};

/// Array elements formatted per task.
const CHUNK: usize = 16 * 1024;

/// Stage timing for animated output (`startTimeCode`, `endTimeCode`, `timeCodesPerSecond`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeCodes {
    pub start: f64,
    pub end: f64,
    pub per_second: f64,
}

/// One primvar as it will be written.
pub(crate) struct Primvar<'a> {
    pub usd_type: &'static str,
    pub name: String,
    pub interpolation: &'static str,
    pub data: PrimvarData<'a>,
}

pub(crate) enum PrimvarData<'a> {
    Floats {
        values: &'a [f32],
        components: usize,
    },
    UVs(&'a [[f32; 2]]),
    Ints(Vec<i64>),
    /// Integer tuples kept as floats in the groom model (`groom_closest_guides`: int3).
    IntTuples {
        values: &'a [f32],
        components: usize,
    },
}

/// Where a groom without a group table goes: `/Groom` (Xform) holding the `Strands` curves.
pub const DEFAULT_PRIM_PATH: &str = "/Groom/Strands";

/// Checks what `.usda` cannot store: cubic strands with too few control points for their basis.
pub fn check_writable(groom: &Groom, path: &Path) -> Result<()> {
    if groom.groups.is_empty() && groom.basis == CurveBasis::Linear {
        return Ok(());
    }
    for (strand, count) in groom.vertex_counts().enumerate() {
        let group = groom.group(groom.group_of(strand));
        let valid = match (group.basis, group.wrap) {
            (CurveBasis::Linear, _) => true,
            (CurveBasis::Bezier, _) => count >= 4 && (count - 1) % 3 == 0,
            (_, CurveWrap::Pinned) => count >= 2,
            _ => count >= 4,
        };
        if !valid {
            let rule = if group.basis == CurveBasis::Bezier { "3k + 1 (at least 4)" } else { "at least 4" };
            return Err(Error::Usage(format!(
                "{}: strand {strand} has {count} control points; {:?} curves in USD need {rule}",
                path.display(),
                group.basis
            )));
        }
    }
    Ok(())
}

/// What the writer renames or drops, as warnings for the user.
pub fn unsupported(groom: &Groom) -> Vec<String> {
    let mut warnings = plan_primvars(groom).1;
    warnings.sort();
    warnings.dedup();
    warnings
}

/// Writes a groom as one stage with default (untimed) values.
pub fn write(groom: &Groom, out: &mut dyn Write) -> std::io::Result<()> {
    write_stage(groom, out, None)
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
    if !(times.start.is_finite()
        && times.end.is_finite()
        && times.start <= times.end
        && times.per_second > 0.0)
    {
        return Err(Error::Usage(format!("{}: bad time codes {times:?}", path.display())));
    }
    if frames.is_empty() {
        return Err(Error::Usage(format!("{}: an animated stage needs at least one frame", path.display())));
    }
    if let Some(k) = frames.iter().position(|f| f.len() != groom.vertex_count()) {
        return Err(Error::Usage(format!(
            "{}: frame {k} has {} points; the groom has {} (topology must stay constant)",
            path.display(),
            frames[k].len(),
            groom.vertex_count()
        )));
    }
    write_stage(groom, out, Some((times, frames))).map_err(|e| Error::io(path, e))
}

/// A prim in the tree the groups' paths make: an Xform, or the curves of one group.
struct Node {
    name: String,
    part: Option<usize>,
    children: Vec<Node>,
}

fn insert(nodes: &mut Vec<Node>, components: &[String], part: usize) {
    let Some((first, rest)) = components.split_first() else { return };
    let index = match nodes.iter().position(|n| n.name == *first) {
        Some(i) => i,
        None => {
            nodes.push(Node { name: first.clone(), part: None, children: Vec::new() });
            nodes.len() - 1
        }
    };
    if rest.is_empty() {
        nodes[index].part = Some(part);
    } else {
        insert(&mut nodes[index].children, rest, part);
    }
}

type Animation<'f> = Option<(TimeCodes, &'f [Vec<Vec3>])>;

/// Stage metadata and one prim tree: each group's curves at its own path (coif's default
/// `/Groom/Strands` for a groom without groups), Xforms above them.
fn write_stage(
    groom: &Groom,
    out: &mut (impl Write + ?Sized),
    animation: Animation<'_>,
) -> std::io::Result<()> {
    let parts = groom.split_groups().map_err(std::io::Error::other)?;
    let mut roots = Vec::new();
    for (k, (_, group, _)) in parts.iter().enumerate() {
        let path = if group.name.is_empty() { DEFAULT_PRIM_PATH } else { group.name.as_str() };
        let components: Vec<String> = path.split('/').filter(|c| !c.is_empty()).map(valid_name).collect();
        insert(&mut roots, &components, k);
    }
    let mut head = String::new();
    head.push_str("#usda 1.0\n(\n    defaultPrim = \"");
    head.push_str(&roots[0].name);
    head.push_str("\"\n");
    head.push_str(concat!("    doc = \"Written by coif ", env!("CARGO_PKG_VERSION"), "\"\n"));
    if let Some((t, _)) = animation {
        head.push_str("    endTimeCode = ");
        push_f64(&mut head, t.end);
        head.push('\n');
    }
    head.push_str("    metersPerUnit = 1\n");
    if let Some((t, _)) = animation {
        head.push_str("    startTimeCode = ");
        push_f64(&mut head, t.start);
        head.push_str("\n    timeCodesPerSecond = ");
        push_f64(&mut head, t.per_second);
        head.push('\n');
    }
    head.push_str("    upAxis = \"Y\"\n)\n\n");
    out.write_all(head.as_bytes())?;
    for node in &roots {
        write_node(groom, &parts, node, out, 0, animation)?;
    }
    Ok(())
}

fn write_node(
    groom: &Groom,
    parts: &[(usize, CurveGroup, std::borrow::Cow<'_, Groom>)],
    node: &Node,
    out: &mut (impl Write + ?Sized),
    depth: usize,
    animation: Animation<'_>,
) -> std::io::Result<()> {
    let indent = "    ".repeat(depth);
    let kind = if node.part.is_some() { "BasisCurves" } else { "Xform" };
    out.write_all(format!("{indent}def {kind} \"{}\"\n{indent}{{\n", node.name).as_bytes())?;
    if let Some(k) = node.part {
        let (index, group, part) = &parts[k];
        let frames = match animation {
            None => None,
            Some((times, frames)) if parts.len() == 1 => Some((times, std::borrow::Cow::Borrowed(frames))),
            Some((times, frames)) => {
                let strands = groom.group_strands(*index);
                let gathered: Vec<Vec<Vec3>> = frames
                    .iter()
                    .map(|f| strands.iter().flat_map(|&s| f[groom.strand_range(s)].iter().copied()).collect())
                    .collect();
                Some((times, std::borrow::Cow::Owned(gathered)))
            }
        };
        write_curves(part, group, out, &format!("{indent}    "), frames.as_ref().map(|(t, f)| (*t, &f[..])))?;
    }
    for child in &node.children {
        write_node(groom, parts, child, out, depth + 1, animation)?;
    }
    out.write_all(format!("{indent}}}\n").as_bytes())?;
    if depth == 0 {
        out.write_all(b"\n")?;
    }
    Ok(())
}

/// One `BasisCurves` prim's properties (the group's strands only).
fn write_curves(
    groom: &Groom,
    group: &CurveGroup,
    out: &mut (impl Write + ?Sized),
    indent: &str,
    animation: Animation<'_>,
) -> std::io::Result<()> {
    let mut head = String::new();
    let (curve_type, basis) = curve_type_and_basis(group.basis);
    if let Some(basis) = basis {
        head.push_str(&format!("{indent}uniform token basis = \"{basis}\"\n"));
    }
    if let Some(purpose) = &group.purpose {
        head.push_str(&format!("{indent}uniform token purpose = \"{purpose}\"\n"));
    }
    let wrap = match group.wrap {
        CurveWrap::Nonperiodic => "nonperiodic",
        CurveWrap::Pinned => "pinned",
        CurveWrap::Periodic => "periodic",
    };
    head.push_str(&format!("{indent}uniform token type = \"{curve_type}\"\n"));
    head.push_str(&format!("{indent}uniform token wrap = \"{wrap}\"\n"));
    head.push_str(&format!("{indent}int[] curveVertexCounts = "));
    out.write_all(head.as_bytes())?;
    let counts: Vec<u32> = groom.vertex_counts().map(|c| c as u32).collect();
    write_array(out, &counts, |buf, &c| buf.extend_from_slice(itoa::Buffer::new().format(c).as_bytes()))?;
    write_label(out, &format!("\n{indent}float[] widths = "))?;
    write_floats(out, &groom.widths)?;
    write_label(out, &format!(" (\n{indent}    interpolation = \"vertex\"\n{indent})\n"))?;

    for primvar in plan_group_primvars(groom, group).0 {
        write_label(out, &format!("{indent}{} primvars:{} = ", primvar.usd_type, primvar.name))?;
        match &primvar.data {
            PrimvarData::Floats { values, components: 1 } => write_floats(out, values)?,
            PrimvarData::Floats { values, components } => {
                let tuples: Vec<&[f32]> = values.chunks_exact(*components).collect();
                write_array(out, &tuples, |buf, t| push_tuple(buf, t))?
            }
            PrimvarData::UVs(uvs) => write_array(out, uvs, |buf, uv| push_tuple(buf, uv))?,
            PrimvarData::Ints(values) => write_array(out, values, |buf, &v| {
                buf.extend_from_slice(itoa::Buffer::new().format(v).as_bytes())
            })?,
            PrimvarData::IntTuples { values, components } => {
                let tuples: Vec<&[f32]> = values.chunks_exact(*components).collect();
                write_array(out, &tuples, |buf, t| {
                    let text: Vec<String> = t.iter().map(|&v| (v.round() as i64).to_string()).collect();
                    let text = text.join(", ");
                    match t.len() {
                        1 => buf.extend_from_slice(text.as_bytes()),
                        _ => buf.extend_from_slice(format!("({text})").as_bytes()),
                    }
                })?
            }
        }
        write_label(
            out,
            &format!(" (\n{indent}    interpolation = \"{}\"\n{indent})\n", primvar.interpolation),
        )?;
    }

    let half_width = groom.widths.iter().fold(0.0f32, |m, &w| m.max(w)) * 0.5;
    let grown = |(lo, hi): (Vec3, Vec3)| [lo - Vec3::splat(half_width), hi + Vec3::splat(half_width)];
    match animation {
        None => {
            write_label(out, &format!("{indent}point3f[] points = "))?;
            write_vec3s(out, &groom.points)?;
            out.write_all(b"\n")?;
            if let Some(extent) = bounds(&groom.points).map(grown) {
                write_label(out, &format!("{indent}float3[] extent = "))?;
                write_vec3s(out, &extent)?;
                out.write_all(b"\n")?;
            }
        }
        Some((times, frames)) => {
            let time = |k: usize| times.start + k as f64;
            write_label(out, &format!("{indent}point3f[] points.timeSamples = {{\n"))?;
            for (k, points) in frames.iter().enumerate() {
                let mut label = format!("{indent}    ");
                push_f64(&mut label, time(k));
                label.push_str(": ");
                write_label(out, &label)?;
                write_vec3s(out, points)?;
                out.write_all(b",\n")?;
            }
            write_label(out, &format!("{indent}}}\n"))?;
            if !groom.points.is_empty() {
                write_label(out, &format!("{indent}float3[] extent.timeSamples = {{\n"))?;
                for (k, points) in frames.iter().enumerate() {
                    let mut label = format!("{indent}    ");
                    push_f64(&mut label, time(k));
                    label.push_str(": ");
                    write_label(out, &label)?;
                    write_vec3s(out, &bounds(points).map(grown).unwrap_or_default())?;
                    out.write_all(b",\n")?;
                }
                write_label(out, &format!("{indent}}}\n"))?;
            }
        }
    }
    Ok(())
}

fn write_label(out: &mut (impl Write + ?Sized), text: &str) -> std::io::Result<()> {
    out.write_all(text.as_bytes())
}

/// USD's `type` and `basis` tokens for a curve basis.
pub(crate) fn curve_type_and_basis(basis: CurveBasis) -> (&'static str, Option<&'static str>) {
    match basis {
        CurveBasis::Linear => ("linear", None),
        CurveBasis::Bezier => ("cubic", Some("bezier")),
        CurveBasis::BSpline => ("cubic", Some("bspline")),
        CurveBasis::CatmullRom => ("cubic", Some("catmullRom")),
    }
}

/// The primvars of a groom without groups (the crate-file writer's one prim).
pub(crate) fn plan_primvars(groom: &Groom) -> (Vec<Primvar<'_>>, Vec<String>) {
    plan_group_primvars(groom, &CurveGroup::default())
}

/// The primvars a group's strands become, and warnings for attributes renamed or dropped.
fn plan_group_primvars<'g>(groom: &'g Groom, group: &CurveGroup) -> (Vec<Primvar<'g>>, Vec<String>) {
    let mut primvars = Vec::new();
    let mut warnings = Vec::new();
    // Names the reader gives a meaning of their own are never taken by attributes.
    let mut used: Vec<String> = [names::GROOM_ID, names::GROOM_GUIDE, names::ST].map(String::from).to_vec();
    primvars.push(Primvar {
        usd_type: "int[]",
        name: names::GROOM_ID.into(),
        interpolation: "uniform",
        data: PrimvarData::Ints(groom.strand_ids.iter().map(|&i| i as i64).collect()),
    });
    if let Some(guides) = &groom.guides {
        primvars.push(Primvar {
            usd_type: "int[]",
            name: names::GROOM_GUIDE.into(),
            interpolation: "uniform",
            data: PrimvarData::Ints(guides.iter().map(|&g| g as i64).collect()),
        });
    }
    if let Some(uvs) = &groom.root_uvs {
        primvars.push(Primvar {
            usd_type: "texCoord2f[]",
            name: names::ST.into(),
            interpolation: "uniform",
            data: PrimvarData::UVs(uvs),
        });
    }
    for attribute in groom.attributes.iter().filter(|a| group.carries(&a.name)) {
        let wanted = names::primvar_for_attribute(&attribute.name);
        let name = valid_name(wanted);
        // A primvar that reads back as another attribute would not round-trip (`displayColor`
        // is where `color` goes), so such names are dropped like clashes.
        if used.contains(&name) || (name == wanted && names::attribute_for_primvar(&name) != attribute.name) {
            warnings.push(format!(
                "attribute '{}' clashes with primvar '{name}' and is not written",
                attribute.name
            ));
            continue;
        }
        if name != wanted {
            warnings.push(format!(
                "attribute '{}' is written as primvar '{name}' (a valid USD name)",
                attribute.name
            ));
        }
        let integer = attribute.name == crate::guides::CLOSEST_GUIDES;
        let usd_type = match (integer, attribute.components) {
            (true, 1) => "int[]",
            (true, 2) => "int2[]",
            (true, 3) => "int3[]",
            (true, _) => "int4[]",
            (false, _) => usd_type(attribute.kind, &attribute.name, attribute.components),
        };
        let interpolation = match attribute.rate {
            AttributeRate::Vertex => "vertex",
            AttributeRate::Strand => "uniform",
        };
        used.push(name.clone());
        primvars.push(Primvar {
            usd_type,
            name,
            interpolation,
            data: match attribute.kind {
                _ if integer => {
                    PrimvarData::IntTuples { values: &attribute.data, components: attribute.components }
                }
                AttributeKind::Int | AttributeKind::Bool => {
                    PrimvarData::Ints(attribute.data.iter().map(|&v| v as i64).collect())
                }
                _ => PrimvarData::Floats { values: &attribute.data, components: attribute.components },
            },
        });
    }
    (primvars, warnings)
}

/// The USD array type an attribute is written as: its kind's, or for plain floats the type coif
/// always gives that name (the reader maps that type back to plain floats).
pub(super) fn usd_type(kind: AttributeKind, name: &str, components: usize) -> &'static str {
    const FLOATS: [&str; 4] = ["float[]", "float2[]", "float3[]", "float4[]"];
    let by_size = |types: [&'static str; 4]| types[components.clamp(1, 4) - 1];
    match kind {
        AttributeKind::Int if components == 1 => "int[]",
        AttributeKind::Bool if components == 1 => "bool[]",
        AttributeKind::Point if components == 3 => "point3f[]",
        AttributeKind::Normal if components == 3 => "normal3f[]",
        AttributeKind::Vector if components == 3 => "vector3f[]",
        AttributeKind::Color if components >= 3 => by_size(["", "", "color3f[]", "color4f[]"]),
        AttributeKind::TexCoord if components >= 2 => by_size(["", "texCoord2f[]", "texCoord3f[]", ""]),
        _ => match (name, components) {
            (crate::groom::attr::COLOR, 3) => "color3f[]",
            (names::REST, 3) => "point3f[]",
            _ => by_size(FLOATS),
        },
    }
}

/// A USD property name (identifier segments joined by ':') made from any attribute name.
fn valid_name(name: &str) -> String {
    let segments: Vec<String> = name
        .split(':')
        .map(|segment| {
            let mut s: String = segment
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' })
                .collect();
            if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
                s.insert(0, '_');
            }
            s
        })
        .collect();
    segments.join(":")
}

/// Points' bounds grown by half the widest width: the extent USD expects on curves.
pub(crate) fn extent(points: &[Vec3], widths: &[f32]) -> Option<[Vec3; 2]> {
    let (lo, hi) = bounds(points)?;
    let half = Vec3::splat(widths.iter().fold(0.0f32, |m, &w| m.max(w)) * 0.5);
    Some([lo - half, hi + half])
}

fn bounds(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let first = *points.first()?;
    Some(
        points
            .par_chunks(CHUNK)
            .map(|c| c.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))))
            .reduce(|| (first, first), |a, b| (a.0.min(b.0), a.1.max(b.1))),
    )
}

fn write_floats(out: &mut (impl Write + ?Sized), values: &[f32]) -> std::io::Result<()> {
    write_array(out, values, |buf, &v| push_f32(buf, v))
}

fn write_vec3s(out: &mut (impl Write + ?Sized), values: &[Vec3]) -> std::io::Result<()> {
    write_array(out, values, |buf, p| push_tuple(buf, &p.to_array()))
}

/// `[a, b, …]`, formatting chunks of elements in parallel and writing them in order.
fn write_array<T: Sync>(
    out: &mut (impl Write + ?Sized),
    items: &[T],
    format: impl Fn(&mut Vec<u8>, &T) + Sync,
) -> std::io::Result<()> {
    out.write_all(b"[")?;
    let batch = CHUNK * 2 * rayon::current_num_threads().max(1);
    for (b, window) in items.chunks(batch).enumerate() {
        let texts: Vec<Vec<u8>> = window
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, chunk)| {
                let mut buf = Vec::with_capacity(chunk.len() * 40);
                for (i, item) in chunk.iter().enumerate() {
                    if b + c + i > 0 {
                        buf.extend_from_slice(b", ");
                    }
                    format(&mut buf, item);
                }
                buf
            })
            .collect();
        for text in texts {
            out.write_all(&text)?;
        }
    }
    out.write_all(b"]")
}

fn push_tuple(buf: &mut Vec<u8>, values: &[f32]) {
    buf.push(b'(');
    for (i, &v) in values.iter().enumerate() {
        if i > 0 {
            buf.extend_from_slice(b", ");
        }
        push_f32(buf, v);
    }
    buf.push(b')');
}

/// The shortest decimal that reads back as the same `f32`; USD's spelling of the non-finite.
fn push_f32(buf: &mut Vec<u8>, value: f32) {
    if value.is_finite() {
        buf.extend_from_slice(zmij::Buffer::new().format_finite(value).as_bytes());
    } else if value.is_nan() {
        buf.extend_from_slice(b"nan");
    } else if value > 0.0 {
        buf.extend_from_slice(b"inf");
    } else {
        buf.extend_from_slice(b"-inf");
    }
}

fn push_f64(text: &mut String, value: f64) {
    text.push_str(zmij::Buffer::new().format(value));
}
