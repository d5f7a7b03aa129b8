//! The planned stage (`io::usd_stage`) as USD text. Large arrays are formatted in fixed-size
//! chunks on all threads and written in order, so the output is the same at any thread count and
//! memory stays bounded. Floats are written in their shortest form that reads back to the same
//! `f32` (`zmij`), integers with `itoa`.
use std::io::Write;
use std::path::Path;

use glam::Vec3;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::groom::Groom;
use crate::io::usd_stage::{self, Data, Prim, Property, Stage, TimeCodes, Value};

/// Text formatted per task, about: large enough that the buffered file takes it without a
/// copy into its 1 MB buffer.
const CHUNK_BYTES: usize = 2 << 20;

/// Writes a groom as one stage with default (untimed) values.
pub fn write(groom: &Groom, out: &mut dyn Write) -> std::io::Result<()> {
    let stage = usd_stage::plan(groom, None).map_err(std::io::Error::other)?;
    write_stage(&stage, out)
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
    let animation = usd_stage::Animation::of_points(times, frames);
    usd_stage::check_animation(groom, &animation, path)?;
    let stage = usd_stage::plan(groom, Some(&animation))?;
    write_stage(&stage, out).map_err(|e| Error::io(path, e))
}

/// Writes a planned stage.
pub fn write_stage(stage: &Stage, out: &mut (impl Write + ?Sized)) -> std::io::Result<()> {
    let mut head = String::new();
    head.push_str("#usda 1.0\n(\n    defaultPrim = \"");
    head.push_str(&stage.default_prim);
    head.push_str("\"\n    doc = \"");
    head.push_str(&stage.doc);
    head.push_str("\"\n");
    if let Some(t) = stage.times {
        head.push_str("    endTimeCode = ");
        push_f64(&mut head, t.end);
        head.push('\n');
    }
    head.push_str("    metersPerUnit = ");
    push_number(&mut head, stage.meters_per_unit);
    head.push('\n');
    if let Some(t) = stage.times {
        head.push_str("    startTimeCode = ");
        push_f64(&mut head, t.start);
        head.push_str("\n    timeCodesPerSecond = ");
        push_f64(&mut head, t.per_second);
        head.push('\n');
    }
    head.push_str("    upAxis = \"");
    head.push_str(stage.up_axis);
    head.push_str("\"\n)\n\n");
    out.write_all(head.as_bytes())?;
    for prim in &stage.roots {
        write_prim(prim, out, 0)?;
    }
    Ok(())
}

fn write_prim(prim: &Prim, out: &mut (impl Write + ?Sized), depth: usize) -> std::io::Result<()> {
    let indent = "    ".repeat(depth);
    out.write_all(format!("{indent}def {} \"{}\"\n{indent}{{\n", prim.type_name, prim.name).as_bytes())?;
    let inner = format!("{indent}    ");
    for property in &prim.properties {
        write_property(property, out, &inner)?;
    }
    for child in &prim.children {
        write_prim(child, out, depth + 1)?;
    }
    out.write_all(format!("{indent}}}\n").as_bytes())?;
    if depth == 0 {
        out.write_all(b"\n")?;
    }
    Ok(())
}

fn write_property(property: &Property, out: &mut (impl Write + ?Sized), indent: &str) -> std::io::Result<()> {
    let uniform = if property.uniform { "uniform " } else { "" };
    let declaration = format!("{indent}{uniform}{} {}", property.type_name, property.name);
    let metadata = property
        .interpolation
        .map(|interpolation| format!(" (\n{indent}    interpolation = \"{interpolation}\"\n{indent})"));
    match &property.value {
        Value::Default(data) => {
            out.write_all(format!("{declaration} = ").as_bytes())?;
            write_data(data, out)?;
            out.write_all(metadata.unwrap_or_default().as_bytes())?;
        }
        Value::TimeSamples(samples) => {
            // Metadata goes on a declaration of its own: a `.timeSamples` line takes none.
            if let Some(metadata) = metadata {
                out.write_all(format!("{declaration}{metadata}\n").as_bytes())?;
            }
            out.write_all(format!("{declaration}.timeSamples = {{\n").as_bytes())?;
            for (time, data) in samples {
                let mut label = format!("{indent}    ");
                push_f64(&mut label, *time);
                label.push_str(": ");
                out.write_all(label.as_bytes())?;
                write_data(data, out)?;
                out.write_all(b",\n")?;
            }
            out.write_all(format!("{indent}}}").as_bytes())?;
        }
    }
    out.write_all(b"\n")
}

fn write_data(data: &Data, out: &mut (impl Write + ?Sized)) -> std::io::Result<()> {
    match data {
        Data::Token(token) => out.write_all(format!("\"{token}\"").as_bytes()),
        Data::Ints { values, components: 1 } => write_array(out, values, |buf, &v| push_int(buf, v)),
        Data::Ints { values, components } => {
            let tuples: Vec<&[i32]> = values.chunks_exact(*components).collect();
            write_array(out, &tuples, |buf, t| push_tuple(buf, t, |buf, &v| push_int(buf, v)))
        }
        Data::Bools(values) => write_array(out, values, |buf, &v| buf.push(if v { b'1' } else { b'0' })),
        Data::Int(value) => out.write_all(value.to_string().as_bytes()),
        Data::Floats { values, components: 1 } => write_array(out, values, |buf, &v| push_f32(buf, v)),
        Data::Floats { values, components: 3 } => {
            let tuples: &[[f32; 3]] = bytemuck::cast_slice(values);
            write_array(out, tuples, |buf, t| push_tuple(buf, t, |buf, &v| push_f32(buf, v)))
        }
        Data::Floats { values, components } => {
            let tuples: Vec<&[f32]> = values.chunks_exact(*components).collect();
            write_array(out, &tuples, |buf, t| push_tuple(buf, t, |buf, &v| push_f32(buf, v)))
        }
    }
}

/// `[a, b, …]`, formatting chunks of elements in parallel and writing them in order. The next
/// batch is formatted on the pool while this thread writes the last one, so disk and formatting
/// overlap.
fn write_array<T: Sync>(
    out: &mut (impl Write + ?Sized),
    items: &[T],
    format: impl Fn(&mut Vec<u8>, &T) + Sync,
) -> std::io::Result<()> {
    out.write_all(b"[")?;
    // A number's text takes about three bytes per byte of its value (`-0.08234567, ` for an f32).
    let text_per_item = 3 * std::mem::size_of::<T>().max(1) + 2;
    let chunk = (CHUNK_BYTES / text_per_item).max(1);
    let batch = chunk * 2 * rayon::current_num_threads().max(1);
    let format_batch = |b: usize, window: &[T]| -> Vec<Vec<u8>> {
        window
            .par_chunks(chunk)
            .enumerate()
            .map(|(c, chunk)| {
                let mut buf = Vec::with_capacity(chunk.len() * (text_per_item + 8));
                for (i, item) in chunk.iter().enumerate() {
                    if b + c + i > 0 {
                        buf.extend_from_slice(b", ");
                    }
                    format(&mut buf, item);
                }
                buf
            })
            .collect()
    };
    let mut written: Vec<Vec<u8>> = Vec::new();
    for (b, window) in items.chunks(batch).enumerate() {
        let mut formatted = Vec::new();
        let result = rayon::in_place_scope(|scope| {
            scope.spawn(|_| formatted = format_batch(b, window));
            written.iter().try_for_each(|text| out.write_all(text))
        });
        result?;
        written = formatted;
    }
    written.iter().try_for_each(|text| out.write_all(text))?;
    out.write_all(b"]")
}

fn push_tuple<T>(buf: &mut Vec<u8>, values: &[T], push: impl Fn(&mut Vec<u8>, &T)) {
    buf.push(b'(');
    for (i, v) in values.iter().enumerate() {
        if i > 0 {
            buf.extend_from_slice(b", ");
        }
        push(buf, v);
    }
    buf.push(b')');
}

fn push_int(buf: &mut Vec<u8>, value: i32) {
    buf.extend_from_slice(itoa::Buffer::new().format(value).as_bytes());
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

/// A layer metadata number: whole numbers without a fraction (`metersPerUnit = 1`).
fn push_number(text: &mut String, value: f64) {
    if value.fract() == 0.0 && value.abs() < 1e15 {
        text.push_str(itoa::Buffer::new().format(value as i64));
    } else {
        push_f64(text, value);
    }
}
