//! Writes a groom as a USD text stage: `/Groom` (Xform) with one `BasisCurves` prim `Strands`.
//! Large arrays are formatted in fixed-size chunks on all threads and written in order, so the
//! output is the same at any thread count and memory stays bounded. Floats are written in their
//! shortest form that reads back to the same `f32`.
use std::io::Write;
use std::path::Path;

use glam::Vec3;
use rayon::prelude::*;

use super::names;
use crate::error::{Error, Result};
use crate::groom::{AttributeRate, CurveBasis, Groom};

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

/// Checks what `.usda` cannot store: cubic strands with too few control points for their basis.
pub fn check_writable(groom: &Groom, path: &Path) -> Result<()> {
    if groom.basis == CurveBasis::Linear {
        return Ok(());
    }
    for (strand, count) in groom.vertex_counts().enumerate() {
        let valid = match groom.basis {
            CurveBasis::Bezier => count >= 4 && (count - 1) % 3 == 0,
            _ => count >= 4,
        };
        if !valid {
            let rule = if groom.basis == CurveBasis::Bezier { "3k + 1 (at least 4)" } else { "at least 4" };
            return Err(Error::Usage(format!(
                "{}: strand {strand} has {count} control points; {:?} curves in USD need {rule}",
                path.display(),
                groom.basis
            )));
        }
    }
    Ok(())
}

/// What the writer renames or drops, as warnings for the user.
pub fn unsupported(groom: &Groom) -> Vec<String> {
    plan_primvars(groom).1
}

/// Writes a groom as one stage with default (untimed) values.
pub fn write(groom: &Groom, out: &mut dyn Write) -> std::io::Result<()> {
    write_head(groom, out, None)?;
    write_label(out, "        point3f[] points = ")?;
    write_vec3s(out, &groom.points)?;
    out.write_all(b"\n")?;
    if let Some(extent) = extent(&groom.points, &groom.widths) {
        write_label(out, "        float3[] extent = ")?;
        write_vec3s(out, &extent)?;
        out.write_all(b"\n")?;
    }
    write_tail(out)
}

/// Streams an animated stage: everything but the points is written once from the groom given to
/// [`AnimationWriter::begin`]; each [`AnimationWriter::frame`] appends one time sample of the
/// points (same topology). Extents per frame follow the points at [`AnimationWriter::finish`].
pub struct AnimationWriter<W: Write> {
    out: W,
    path: std::path::PathBuf,
    vertices: usize,
    half_width: f32,
    extents: Vec<(f64, [Vec3; 2])>,
}

impl<W: Write> AnimationWriter<W> {
    /// Writes the stage up to the points; `path` names the output in errors.
    pub fn begin(mut out: W, groom: &Groom, times: TimeCodes, path: &Path) -> Result<Self> {
        if !(times.start.is_finite()
            && times.end.is_finite()
            && times.start <= times.end
            && times.per_second > 0.0)
        {
            return Err(Error::Usage(format!("{}: bad time codes {times:?}", path.display())));
        }
        write_head(groom, &mut out, Some(times)).map_err(|e| Error::io(path, e))?;
        write_label(&mut out, "        point3f[] points.timeSamples = {\n")
            .map_err(|e| Error::io(path, e))?;
        Ok(AnimationWriter {
            out,
            path: path.to_path_buf(),
            vertices: groom.vertex_count(),
            half_width: groom.widths.iter().fold(0.0f32, |m, &w| m.max(w)) * 0.5,
            extents: Vec::new(),
        })
    }

    /// Appends the points at `time` (time codes must increase from frame to frame).
    pub fn frame(&mut self, time: f64, points: &[Vec3]) -> Result<()> {
        if points.len() != self.vertices {
            return Err(Error::Usage(format!(
                "{}: frame at time {time} has {} points; the groom has {} (topology must stay constant)",
                self.path.display(),
                points.len(),
                self.vertices
            )));
        }
        if !time.is_finite() || self.extents.last().is_some_and(|&(last, _)| time <= last) {
            return Err(Error::Usage(format!(
                "{}: time {time} does not follow the previous frame",
                self.path.display()
            )));
        }
        let io = |e| Error::io(&self.path, e);
        let mut label = String::from("            ");
        push_f64(&mut label, time);
        label.push_str(": ");
        write_label(&mut self.out, &label).map_err(io)?;
        write_vec3s(&mut self.out, points).map_err(io)?;
        self.out.write_all(b",\n").map_err(io)?;
        if let Some((lo, hi)) = bounds(points) {
            self.extents.push((time, [lo - Vec3::splat(self.half_width), hi + Vec3::splat(self.half_width)]));
        }
        Ok(())
    }

    /// Closes the stage and returns the output.
    pub fn finish(mut self) -> Result<W> {
        if self.extents.is_empty() && self.vertices > 0 {
            return Err(Error::Usage(format!(
                "{}: an animated stage needs at least one frame",
                self.path.display()
            )));
        }
        let path = self.path.clone();
        let io = |e| Error::io(&path, e);
        self.out.write_all(b"        }\n").map_err(io)?;
        if !self.extents.is_empty() {
            self.out.write_all(b"        float3[] extent.timeSamples = {\n").map_err(io)?;
            for (time, extent) in &self.extents {
                let mut label = String::from("            ");
                push_f64(&mut label, *time);
                label.push_str(": ");
                write_label(&mut self.out, &label).map_err(io)?;
                write_vec3s(&mut self.out, extent).map_err(io)?;
                self.out.write_all(b",\n").map_err(io)?;
            }
            self.out.write_all(b"        }\n").map_err(io)?;
        }
        write_tail(&mut self.out).map_err(io)?;
        Ok(self.out)
    }
}

fn write_label(out: &mut (impl Write + ?Sized), text: &str) -> std::io::Result<()> {
    out.write_all(text.as_bytes())
}

/// Stage metadata, the Xform, and the curve prim's topology, widths and primvars.
fn write_head(
    groom: &Groom,
    out: &mut (impl Write + ?Sized),
    times: Option<TimeCodes>,
) -> std::io::Result<()> {
    let mut head = String::new();
    head.push_str("#usda 1.0\n(\n    defaultPrim = \"Groom\"\n");
    head.push_str(concat!("    doc = \"Written by coif ", env!("CARGO_PKG_VERSION"), "\"\n"));
    if let Some(t) = times {
        head.push_str("    endTimeCode = ");
        push_f64(&mut head, t.end);
        head.push('\n');
    }
    head.push_str("    metersPerUnit = 1\n");
    if let Some(t) = times {
        head.push_str("    startTimeCode = ");
        push_f64(&mut head, t.start);
        head.push_str("\n    timeCodesPerSecond = ");
        push_f64(&mut head, t.per_second);
        head.push('\n');
    }
    head.push_str(
        "    upAxis = \"Y\"\n)\n\ndef Xform \"Groom\"\n{\n    def BasisCurves \"Strands\"\n    {\n",
    );
    let (curve_type, basis) = curve_type_and_basis(groom.basis);
    if let Some(basis) = basis {
        head.push_str(&format!("        uniform token basis = \"{basis}\"\n"));
    }
    head.push_str(&format!("        uniform token type = \"{curve_type}\"\n"));
    head.push_str("        uniform token wrap = \"nonperiodic\"\n");
    head.push_str("        int[] curveVertexCounts = ");
    out.write_all(head.as_bytes())?;
    let counts: Vec<u32> = groom.vertex_counts().map(|c| c as u32).collect();
    write_array(out, &counts, |buf, &c| buf.extend_from_slice(itoa::Buffer::new().format(c).as_bytes()))?;
    out.write_all(b"\n        float[] widths = ")?;
    write_floats(out, &groom.widths)?;
    out.write_all(b" (\n            interpolation = \"vertex\"\n        )\n")?;

    for primvar in plan_primvars(groom).0 {
        write_label(out, &format!("        {} primvars:{} = ", primvar.usd_type, primvar.name))?;
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
            &format!(" (\n            interpolation = \"{}\"\n        )\n", primvar.interpolation),
        )?;
    }
    Ok(())
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

fn write_tail(out: &mut (impl Write + ?Sized)) -> std::io::Result<()> {
    out.write_all(b"    }\n}\n\n")
}

/// The primvars a groom becomes, and warnings for attributes renamed or dropped.
pub(crate) fn plan_primvars(groom: &Groom) -> (Vec<Primvar<'_>>, Vec<String>) {
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
    for attribute in &groom.attributes {
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
        let usd_type = match (attribute.name.as_str(), attribute.components) {
            (_, 1) if integer => "int[]",
            (_, 2) if integer => "int2[]",
            (_, 3) if integer => "int3[]",
            (_, _) if integer => "int4[]",
            (crate::groom::attr::COLOR, 3) => "color3f[]",
            (names::REST, 3) => "point3f[]",
            (_, 1) => "float[]",
            (_, 2) => "float2[]",
            (_, 3) => "float3[]",
            _ => "float4[]",
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
            data: if integer {
                PrimvarData::IntTuples { values: &attribute.data, components: attribute.components }
            } else {
                PrimvarData::Floats { values: &attribute.data, components: attribute.components }
            },
        });
    }
    (primvars, warnings)
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
