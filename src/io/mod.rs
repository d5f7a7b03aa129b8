//! Reading and writing grooms. One module per format, each a reader and a writer of [`Groom`];
//! the format is chosen by magic bytes when reading and by extension when writing. Units and
//! up-axis are converted here, at the edge, so the rest of coif sees metres and Y up.
pub mod alembic;
pub mod atomic;
pub mod cleanup;
pub mod hair;
pub mod input;
pub mod obj;
pub mod timeline;
pub mod unreal;
pub mod usd_compose;
pub mod usd_interop;
pub mod usd_stage;
pub mod usda;
pub mod usdc;

use std::path::Path;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::groom::Groom;

/// The file formats coif reads and writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// Cem Yuksel's binary `.hair`.
    Hair,
    /// USD text, read and written by coif itself.
    Usda,
    /// USD binary (crate), read and written by coif itself.
    Usdc,
    /// USD zip package, through usd-core.
    Usdz,
    /// Alembic (Ogawa) curves.
    Alembic,
}

impl Format {
    const ALL: &'static [(Format, &'static str)] = &[
        (Format::Hair, "hair"),
        (Format::Usda, "usda"),
        (Format::Usdc, "usdc"),
        (Format::Usdz, "usdz"),
        (Format::Alembic, "abc"),
    ];

    /// The format a file name's extension names.
    pub fn from_extension(path: &Path) -> Result<Format> {
        let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
        Format::ALL.iter().find(|(_, e)| *e == ext).map(|(f, _)| *f).ok_or_else(|| {
            let known: Vec<_> = Format::ALL.iter().map(|(_, e)| format!(".{e}")).collect();
            Error::Usage(format!(
                "{}: unknown groom file extension; coif reads and writes {}",
                path.display(),
                known.join(", ")
            ))
        })
    }

    /// The format a file's first bytes announce, if any.
    pub fn from_magic(head: &[u8]) -> Option<Format> {
        if head.starts_with(hair::SIGNATURE) {
            Some(Format::Hair)
        } else if head.starts_with(usda::MAGIC) {
            Some(Format::Usda)
        } else if head.starts_with(usdc::MAGIC) {
            Some(Format::Usdc)
        } else if head.starts_with(b"PK\x03\x04") {
            Some(Format::Usdz)
        } else if head.starts_with(alembic::MAGIC) {
            Some(Format::Alembic)
        } else {
            None
        }
    }

    pub fn name(self) -> &'static str {
        Format::ALL.iter().find(|(f, _)| *f == self).map(|(_, e)| *e).unwrap()
    }
}

/// Axis that points up in a file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    #[default]
    Y,
    Z,
}

/// How to interpret a file that does not say its own units or up axis (`.hair`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ImportOptions {
    /// Metres per file unit (0.01 for centimetres); `None` keeps the file's own or metres.
    pub meters_per_unit: Option<f32>,
    /// The file's up axis; `None` keeps the file's own or Y.
    pub up_axis: Option<UpAxis>,
    /// The frame number to read from an animated Alembic file, on the file's own timeline (time
    /// = frame / its frame rate); `None` reads its first sample. USD takes its time code from
    /// [`usda::Selection::time`].
    pub frame: Option<f64>,
}

/// Choices for writing a groom that only some formats use.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExportOptions {
    /// Alembic: follow Epic's groom conventions for Unreal (centimetres, `groom_*` names,
    /// groom spec version on a top Xform).
    pub unreal: bool,
}

/// A groom read from disk, with the format it came in.
pub struct Loaded {
    pub groom: Groom,
    pub format: Format,
}

/// Reads a groom file, converts it to metres and Y up, and validates it.
pub fn read_groom(path: &Path, options: &ImportOptions) -> Result<Loaded> {
    read_groom_selected(path, options, &usda::Selection::default())
}

/// [`read_groom`], with a time and variant selection for USD stages.
pub fn read_groom_selected(
    path: &Path,
    options: &ImportOptions,
    selection: &usda::Selection,
) -> Result<Loaded> {
    let format = format_of(path)?;
    // One frame for every format: a USD time code is the frame number on the stage's timeline.
    let selection =
        &usda::Selection { time: selection.time.or(options.frame), variants: selection.variants.clone() };
    let groom = match format {
        Format::Hair | Format::Alembic => {
            if !selection.variants.is_empty() || (format == Format::Hair && selection.time.is_some()) {
                let what = if selection.variants.is_empty() {
                    "a .hair file holds one frame: --frame applies to USD and Alembic input"
                } else {
                    "--variant applies to USD input only"
                };
                return Err(Error::Usage(format!("{}: {what}", path.display())));
            }
            let bytes = input::map_file(path)?;
            let mut groom = match format {
                Format::Hair => hair::read(&bytes, path)?,
                _ => alembic::read(&bytes, path, selection.time, options.meters_per_unit.is_some())?,
            };
            apply_import_options(&mut groom, options);
            groom
        }
        // USD stages say their own units and up axis; the options only fill in what they omit.
        // Composition (sublayers, references, payloads, inherits, variants) is native for
        // both formats: no Python is started. A layer without arcs is read in one pass.
        Format::Usda | Format::Usdc if !selection.variants.is_empty() => {
            usd_compose::read_groom(path, options, selection)?
        }
        Format::Usda | Format::Usdc => {
            let outcome = if format == Format::Usda {
                let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
                usda::read(file, path, options, selection.time)?
            } else {
                usdc::read_file(path, options, selection.time)?
            };
            match outcome {
                usda::ReadOutcome::Groom(groom) => groom,
                usda::ReadOutcome::NeedsComposition(layer) => {
                    usd_compose::groom_from_composed(*layer, path, options, selection)?
                }
            }
        }
        Format::Usdz => usd_interop::read(path, options, selection.time, &selection.variants)?,
    };
    groom.validate().map_err(|source| Error::InvalidGroom { path: path.to_path_buf(), source })?;
    check_contents(&groom, path)?;
    Ok(Loaded { groom, format })
}

/// The format of an existing groom file: its magic bytes, else its extension.
pub fn format_of(path: &Path) -> Result<Format> {
    match Format::from_magic(&read_head(path)?) {
        Some(format) => Ok(format),
        None => Format::from_extension(path),
    }
}

/// What the groom model allows but no job can use: a file without strands, or attribute values
/// (colours, wetness) that are not finite and would flow into every output.
fn check_contents(groom: &Groom, path: &Path) -> Result<()> {
    if groom.strand_count() == 0 {
        return Err(Error::format(path, "the file holds no strands"));
    }
    for attribute in &groom.attributes {
        if crate::groom::all_finite(&attribute.data) {
            continue;
        }
        if let Some(index) = attribute.data.iter().position(|v| !v.is_finite()) {
            let element = index / attribute.components.max(1);
            let (rate, strand) = match attribute.rate {
                crate::groom::AttributeRate::Strand => ("strand", element),
                crate::groom::AttributeRate::Vertex => (
                    "vertex",
                    groom.strand_offsets.partition_point(|&o| o as usize <= element).saturating_sub(1),
                ),
            };
            return Err(Error::format(
                path,
                format!(
                    "attribute '{}': {rate} {element} (strand {strand}) has a non-finite value {}",
                    attribute.name, attribute.data[index]
                ),
            ));
        }
    }
    Ok(())
}

/// The first bytes of a file, enough to recognise every format's magic.
fn read_head(path: &Path) -> Result<Vec<u8>> {
    use std::io::Read;
    input::check_regular(path)?;
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut head = Vec::with_capacity(16);
    file.take(16).read_to_end(&mut head).map_err(|e| Error::io(path, e))?;
    Ok(head)
}

fn apply_import_options(groom: &mut Groom, options: &ImportOptions) {
    if options.up_axis == Some(UpAxis::Z) {
        // Z up to Y up: (x, y, z) -> (x, z, -y), a rotation, so handedness is kept.
        let to_y_up = |p: &mut Vec3| *p = Vec3::new(p.x, p.z, -p.y);
        groom.points.iter_mut().for_each(to_y_up);
        groom.meshes.iter_mut().flat_map(|m| m.points.iter_mut()).for_each(to_y_up);
    }
    if let Some(scale) = options.meters_per_unit {
        groom.scale(scale);
    }
}

/// Writes a groom in the format its extension names, atomically. Returns warnings about data
/// the format cannot carry.
pub fn write_groom(path: &Path, groom: &Groom) -> Result<Vec<String>> {
    write_groom_with(path, groom, &ExportOptions::default())
}

/// [`write_groom`] with format-specific choices.
pub fn write_groom_with(path: &Path, groom: &Groom, options: &ExportOptions) -> Result<Vec<String>> {
    let mut warnings = write_curves(path, groom, options)?;
    warnings.extend(mesh_warning(path, groom));
    Ok(warnings)
}

/// No writer carries meshes yet: say so rather than drop them silently.
fn mesh_warning(path: &Path, groom: &Groom) -> Option<String> {
    (!groom.meshes.is_empty()).then(|| {
        let names: Vec<&str> = groom.meshes.iter().map(|m| m.path.as_str()).collect();
        format!("{}: meshes are not written (only the curves): {}", path.display(), names.join(", "))
    })
}

fn write_curves(path: &Path, groom: &Groom, options: &ExportOptions) -> Result<Vec<String>> {
    groom.validate()?;
    let format = Format::from_extension(path)?;
    if options.unreal && matches!(format, Format::Hair | Format::Usdz) {
        return Err(Error::Usage(format!(
            "{}: --unreal writes .abc, .usda or .usdc (Unreal's groom importers), not .{}",
            path.display(),
            path.extension().and_then(|e| e.to_str()).unwrap_or("")
        )));
    }
    match format {
        Format::Hair => {
            hair::check_writable(groom, path)?;
            atomic::write_atomically(path, |w| hair::write(groom, w).map_err(|e| Error::io(path, e)))?;
            Ok(hair::unsupported(groom)
                .into_iter()
                .map(|what| format!("{}: .hair drops {what}", path.display()))
                .collect())
        }
        Format::Usda | Format::Usdc => write_usd_stage(path, format, groom, None, options),
        Format::Usdz => {
            usda::check_writable(groom, path)?;
            usd_interop::write(path, groom)?;
            Ok(usd_warnings(path, groom))
        }
        Format::Alembic => {
            let prepared = options.unreal.then(|| unreal::with_root_uvs(groom)).flatten();
            let abc_options = alembic::AlembicWriteOptions { unreal: options.unreal, ..Default::default() };
            alembic::write(path, prepared.as_ref().unwrap_or(groom), &abc_options)?;
            Ok(Vec::new())
        }
    }
}

fn usd_warnings(path: &Path, groom: &Groom) -> Vec<String> {
    usda::unsupported(groom).into_iter().map(|what| format!("{}: {what}", path.display())).collect()
}

/// Writes a groom whose points move over time: `frames` holds every frame's points (same
/// topology as `groom`, whose other data is written once), `frames_per_second` sets the time
/// codes (frame `k` at time code `k + 1`). USD and Alembic carry time samples; `.hair` cannot.
pub fn write_animated(
    path: &Path,
    groom: &Groom,
    frames: &[Vec<Vec3>],
    frames_per_second: f32,
    options: &ExportOptions,
) -> Result<Vec<String>> {
    groom.validate()?;
    if frames.is_empty() {
        return write_groom_with(path, groom, options);
    }
    let times =
        usda::TimeCodes { start: 1.0, end: frames.len() as f64, per_second: frames_per_second as f64 };
    let mut warnings = write_animated_curves(path, groom, frames, times, options)?;
    warnings.extend(mesh_warning(path, groom));
    Ok(warnings)
}

/// Writes `first` and the frames `rest` yields (with the same topology) at frame numbers
/// `timeline.first`, `+ 1`, …: Alembic streams them to disk one at a time; USD holds
/// their points (checked against the memory limit first) until the stage is written. Attributes
/// other than the points are written once, from `first`. A frame whose strands differ from the
/// first's is refused, naming its frame number.
pub fn write_frames(
    path: &Path,
    first: &Groom,
    rest: impl Iterator<Item = Result<Groom>>,
    timeline: &timeline::Timeline,
    options: &ExportOptions,
) -> Result<Vec<String>> {
    first.validate()?;
    let format = check_animated_output(path)?;
    let count = timeline.frame_count();
    let same_topology = |k: u64, groom: &Groom| -> Result<()> {
        if groom.strand_offsets != first.strand_offsets || groom.group_ids != first.group_ids {
            return Err(Error::Usage(format!(
                "{}: frame {} has other strands than frame {} ({} vs {} vertices); coif writes animation of constant topology",
                path.display(),
                timeline.frame(k),
                timeline.first,
                groom.vertex_count(),
                first.vertex_count()
            )));
        }
        Ok(())
    };
    let mut warnings = if format == Format::Alembic {
        let abc_options = alembic::AlembicWriteOptions {
            unreal: options.unreal,
            frames_per_second: timeline.frames_per_second,
            first_frame: timeline.first,
            ..Default::default()
        };
        let template =
            options.unreal.then(|| unreal::with_root_uvs(first)).flatten().unwrap_or_else(|| first.clone());
        let points = std::iter::once(Ok(first.points.clone())).chain(rest.enumerate().map(|(k, groom)| {
            let groom = groom?;
            same_topology(k as u64 + 1, &groom)?;
            Ok(groom.points)
        }));
        stream_alembic_frames(path, template, points, &abc_options)?;
        Vec::new()
    } else {
        crate::limits::check_memory(
            &format!("holding {count} frames of {} vertices for {}", first.vertex_count(), path.display()),
            count as f64 * first.vertex_count() as f64 * 12.0,
        )?;
        let mut points = Vec::with_capacity(count as usize);
        points.push(first.points.clone());
        for (k, groom) in rest.enumerate() {
            let groom = groom?;
            same_topology(k as u64 + 1, &groom)?;
            points.push(groom.points);
        }
        let times = usda::TimeCodes {
            start: timeline.first,
            end: timeline.frame(points.len().max(1) as u64 - 1),
            per_second: timeline.frames_per_second,
        };
        write_animated_curves(path, first, &points, times, options)?
    };
    warnings.extend(mesh_warning(path, first));
    Ok(warnings)
}

/// The format of an animated output, refusing one that holds no time samples (`.hair`): callers
/// check this before a long simulation, not only when writing.
pub fn check_animated_output(path: &Path) -> Result<Format> {
    let format = Format::from_extension(path)?;
    if format == Format::Hair {
        return Err(Error::Usage(format!(
            "{}: .hair holds no time samples; write .usda, .usdc, .usdz or .abc for animated output",
            path.display()
        )));
    }
    Ok(format)
}

fn write_animated_curves(
    path: &Path,
    groom: &Groom,
    frames: &[Vec<Vec3>],
    times: usda::TimeCodes,
    options: &ExportOptions,
) -> Result<Vec<String>> {
    let format = check_animated_output(path)?;
    match format {
        Format::Hair => unreachable!("refused by check_animated_output"),
        Format::Usda | Format::Usdc | Format::Usdz => {
            write_usd_stage(path, format, groom, Some((times, frames)), options)
        }
        Format::Alembic => {
            let abc_options = alembic::AlembicWriteOptions {
                unreal: options.unreal,
                frames_per_second: times.per_second,
                first_frame: times.start,
                ..Default::default()
            };
            stream_alembic_frames(path, groom.clone(), frames.iter().map(|p| Ok(p.clone())), &abc_options)?;
            Ok(Vec::new())
        }
    }
}

/// One USD stage (still, or with `animation`'s time-sampled points) in `format`; `--unreal`
/// adds Epic's layout (see [`unreal`]): `groom_*` primvars and the spec version.
fn write_usd_stage(
    path: &Path,
    format: Format,
    groom: &Groom,
    animation: Option<(usda::TimeCodes, &[Vec<Vec3>])>,
    options: &ExportOptions,
) -> Result<Vec<String>> {
    let unreal_groom = options.unreal.then(|| unreal::for_usd(groom));
    let groom = unreal_groom.as_ref().unwrap_or(groom);
    usda::check_writable(groom, path)?;
    if let Some((times, frames)) = animation {
        usd_stage::check_animation(groom, frames, times, path)?;
    }
    let mut stage = usd_stage::plan(groom, animation)?;
    if options.unreal {
        usd_stage::add_unreal_groom_properties(&mut stage);
    }
    let write_text =
        |out: &mut dyn std::io::Write| usda::write_stage(&stage, out).map_err(|e| Error::io(path, e));
    match format {
        Format::Usda => atomic::write_atomically(path, write_text)?,
        Format::Usdc => usdc::write_stage(path, &stage)?,
        _ => usd_interop::write_usd(path, write_text)?,
    }
    Ok(usd_warnings(path, groom))
}

/// Streams frames to an Alembic file, one at a time: each is `template` (the first frame's
/// attributes) with that frame's points.
fn stream_alembic_frames(
    path: &Path,
    mut template: Groom,
    frames: impl Iterator<Item = Result<Vec<Vec3>>>,
    options: &alembic::AlembicWriteOptions,
) -> Result<()> {
    let mut writer = alembic::AnimationWriter::create(path, &template, options, true)?;
    for points in frames {
        template.points = points?;
        writer.write_frame(&template)?;
    }
    writer.finish()
}
