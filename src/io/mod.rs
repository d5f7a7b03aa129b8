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
        // A `.usd` file may hold either encoding; written, it is a crate, as pxr writes it.
        (Format::Usdc, "usd"),
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
    /// The files read: the groom's, then the layers a USD stage composes. No output may be one.
    pub files: Vec<std::path::PathBuf>,
    /// What the reading left out that the user should hear about (commands print them).
    pub warnings: Vec<String>,
}

impl Loaded {
    /// The layers a USD stage composes besides the groom's own file (none for other formats).
    pub fn composed_layers(&self) -> &[std::path::PathBuf] {
        self.files.get(1..).unwrap_or_default()
    }
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
    read_groom_from(path, options, selection, &FrameSource::File)
}

/// Reads frames of one groom file, each as [`read_groom_selected`] reads it at that frame, from
/// one reading of the file where it can: a `.usdz` package is flattened by usd-core once, and a
/// `.usda` layer is parsed once, keeping the time samples of the frames asked for (parsing it
/// again for each frame made a long text cache's convert quadratic), as is each `.usda` layer a
/// `.usda` stage composes (a shot layer referencing a cache).
pub struct FrameReader<'a> {
    path: &'a Path,
    options: ImportOptions,
    variants: Vec<String>,
    source: FrameSource,
}

/// What a [`FrameReader`] reads each frame from.
enum FrameSource {
    /// The file, again for each frame.
    File,
    /// usd-core's flattening of a `.usdz`.
    Flattened(usd_interop::Flattened),
    /// A `.usda` layer parsed with the samples from the first frame to the last.
    Parsed { layer: Box<usda::Layer>, first: f64, last: f64 },
    /// A `.usda` root layer that composes others, parsed as `Parsed`, and the `.usda` layers it
    /// composes, each parsed once with all its samples (arcs may retime them anywhere).
    Composed { root: Box<usda::Layer>, layers: usd_compose::SampledLayers, first: f64, last: f64 },
}

impl<'a> FrameReader<'a> {
    /// A reader of frames `first` to `last` of `path` (others are read from the file).
    pub fn new(
        path: &'a Path,
        options: ImportOptions,
        variants: Vec<String>,
        first: f64,
        last: f64,
    ) -> Result<Self> {
        // Kept samples take at most about twice the text's size ("0" is one character, four
        // bytes): past the memory limit, frames are parsed one at a time (and layers the stage
        // composes, past what the limit leaves).
        let memory_left = crate::limits::max_memory().checked_sub(kept_samples_size(path));
        let source = match (format_of(path)?, memory_left) {
            (Format::Usdz, _) => FrameSource::Flattened(usd_interop::flatten(path, &variants)?),
            (Format::Usda, Some(left)) => {
                let layer = Box::new(usda::read_layer_between(path, first, last)?);
                if layer.composes() || !variants.is_empty() {
                    FrameSource::Composed {
                        root: layer,
                        layers: usd_compose::SampledLayers::new(left),
                        first,
                        last,
                    }
                } else {
                    FrameSource::Parsed { layer, first, last }
                }
            }
            _ => FrameSource::File,
        };
        Ok(FrameReader { path, options, variants, source })
    }

    pub fn read(&self, frame: f64) -> Result<Loaded> {
        let options = ImportOptions { frame: Some(frame), ..self.options };
        let selection = usda::Selection { time: Some(frame), variants: self.variants.clone() };
        let source = match &self.source {
            FrameSource::Parsed { first, last, .. } | FrameSource::Composed { first, last, .. }
                if !(*first <= frame && frame <= *last) =>
            {
                &FrameSource::File
            }
            source => source,
        };
        read_groom_from(self.path, &options, &selection, source)
    }
}

/// About what a `.usda` file's samples take in memory once parsed: twice its text (the most when
/// the file cannot be measured).
pub(crate) fn kept_samples_size(path: &Path) -> u64 {
    std::fs::metadata(path).map_or(u64::MAX, |m| m.len().saturating_mul(2))
}

/// [`read_groom_selected`], from what `source` kept of the file.
fn read_groom_from(
    path: &Path,
    options: &ImportOptions,
    selection: &usda::Selection,
    source: &FrameSource,
) -> Result<Loaded> {
    let format = format_of(path)?;
    // One frame for every format: a USD time code is the frame number on the stage's timeline.
    let selection =
        &usda::Selection { time: selection.time.or(options.frame), variants: selection.variants.clone() };
    let mut files = vec![path.to_path_buf()];
    let mut warnings = Vec::new();
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
                _ => {
                    let keep_units = options.meters_per_unit.is_some();
                    let groom;
                    (groom, warnings) = alembic::read(&bytes, path, selection.time, keep_units)?;
                    groom
                }
            };
            apply_import_options(&mut groom, options);
            groom
        }
        // USD stages say their own units and up axis; the options only fill in what they omit.
        // Composition (sublayers, references, payloads, inherits, variants) is native for
        // both formats: no Python is started. A layer without arcs is read in one pass.
        Format::Usda | Format::Usdc
            if !selection.variants.is_empty() || matches!(source, FrameSource::Composed { .. }) =>
        {
            let composed = match (source, selection.time) {
                (FrameSource::Composed { root, layers, .. }, Some(time)) => {
                    usd_compose::groom_and_layers_from_sampled(
                        root.at_time(time),
                        path,
                        options,
                        selection,
                        layers,
                    )?
                }
                _ => usd_compose::read_groom(path, options, selection)?,
            };
            (files, warnings) = (composed.layers, composed.warnings);
            composed.groom
        }
        Format::Usda | Format::Usdc => {
            let outcome = if let (FrameSource::Parsed { layer, .. }, Some(time)) = (source, selection.time) {
                usda::groom_at(layer, path, options, time)?
            } else if format == Format::Usda {
                let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
                usda::read(file, path, options, selection.time)?
            } else {
                usdc::read_file(path, options, selection.time)?
            };
            match outcome {
                usda::ReadOutcome::Groom(groom, read_warnings) => {
                    warnings = read_warnings;
                    groom
                }
                usda::ReadOutcome::NeedsComposition(layer) => {
                    let composed =
                        usd_compose::groom_and_layers_from_composed(*layer, path, options, selection)?;
                    (files, warnings) = (composed.layers, composed.warnings);
                    composed.groom
                }
            }
        }
        Format::Usdz => {
            let groom;
            (groom, warnings) = match source {
                FrameSource::Flattened(flattened) => {
                    usd_interop::read_flattened(flattened, path, options, selection.time)?
                }
                _ => usd_interop::read(path, options, selection.time, &selection.variants)?,
            };
            groom
        }
    };
    groom.validate_stored().map_err(|source| Error::InvalidGroom {
        path: path.to_path_buf(),
        origin: source.strand().and_then(|strand| groom.strand_origin(strand)),
        source,
    })?;
    check_contents(&groom, path)?;
    Ok(Loaded { groom, format, files, warnings })
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
        let crate::groom::AttributeData::Float(data) = &attribute.data else { continue }; // integers are finite
        if crate::groom::all_finite(data) {
            continue;
        }
        if let Some(index) = data.iter().position(|v| !v.is_finite()) {
            let element = index / attribute.components.max(1);
            let place = match attribute.rate {
                crate::groom::AttributeRate::Strand => format!("strand {element}"),
                crate::groom::AttributeRate::Vertex => {
                    let strand =
                        groom.strand_offsets.partition_point(|&o| o as usize <= element).saturating_sub(1);
                    format!("vertex {element} (strand {strand})")
                }
            };
            return Err(Error::format(
                path,
                format!("attribute '{}': {place} has a non-finite value {}", attribute.name, data[index]),
            ));
        }
    }
    // Guide ids held as floats (USD's `float3[]`) are written to Alembic as Unreal's int32×3:
    // 1e30 became 2147483647 and 0.5 became 0 there, without a word.
    if let Some(closest) = groom.attribute(crate::guides::CLOSEST_GUIDES) {
        let int32 = |v: f32| v.fract() == 0.0 && (-2_147_483_648.0..2_147_483_648.0).contains(&v);
        if let Some(index) = closest.floats().iter().position(|&v| !int32(v)) {
            let rate = if closest.rate == crate::groom::AttributeRate::Strand { "strand" } else { "vertex" };
            return Err(Error::format(
                path,
                format!(
                    "attribute '{}' at {rate} {}: {} is not a strand id (a whole number an int32 holds)",
                    closest.name,
                    index / closest.components.max(1),
                    closest.floats()[index]
                ),
            ));
        }
    }
    // Root UVs too: a NaN `st` went on into every output (Unreal's `groom_root_uv`).
    let uvs = groom.root_uvs.as_deref().unwrap_or_default();
    if let Some((strand, uv)) = uvs.iter().enumerate().find(|(_, uv)| !uv.iter().all(|v| v.is_finite())) {
        return Err(Error::format(
            path,
            format!("root UV of strand {strand} is ({}, {}), not finite", uv[0], uv[1]),
        ));
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
        let rotation =
            glam::DMat4::from_cols(glam::DVec4::X, glam::DVec4::NEG_Z, glam::DVec4::Y, glam::DVec4::W);
        groom.meshes.iter_mut().for_each(|m| m.transform(rotation));
        transform_attributes(&mut groom.attributes, rotation);
    }
    if let Some(scale) = options.meters_per_unit {
        groom.scale(scale);
    }
}

/// How a transform scales a curve's width: the cube root of its volume change, so a uniform scale
/// scales widths by itself (as Blender and pxr's hair procedurals do). Every reader uses it on the
/// widths a file authors (coif's default width is not scaled).
pub(crate) fn width_scale(to_coif: glam::DMat4) -> f32 {
    to_coif.determinant().abs().cbrt() as f32
}

/// Moves the attributes that are positions or directions with the points, from a file's space to
/// coif's by `to_coif` (see [`transform_values`]). Every reader uses it.
pub(crate) fn transform_attributes(attributes: &mut [crate::groom::Attribute], to_coif: glam::DMat4) {
    for attribute in attributes.iter_mut() {
        let (kind, components) = (attribute.kind, attribute.components);
        if let crate::groom::AttributeData::Float(data) = &mut attribute.data {
            transform_values(kind, &attribute.name, components, data, to_coif);
        }
    }
}

/// Moves 3-vector data that is a position or direction with the points by `to_coif`: points
/// (`rest`) like the points, normals by the inverse transpose (kept unit length), vectors
/// (velocities) by the linear part — by kind, or for plain float3 data by name (Blender's
/// `surface_normal`, `rest_position`, `N`, `v`, `velocit*`, `rest`). Groom attributes and mesh
/// primvars both move by it.
pub(crate) fn transform_values(
    kind: crate::groom::AttributeKind,
    name: &str,
    components: usize,
    data: &mut [f32],
    to_coif: glam::DMat4,
) {
    use crate::groom::AttributeKind;
    if to_coif == glam::DMat4::IDENTITY || components != 3 {
        return;
    }
    let linear = glam::DMat3::from_mat4(to_coif);
    let map: Box<dyn Fn(Vec3) -> Vec3> = match direction_kind(kind, name) {
        Some(AttributeKind::Point) => {
            Box::new(move |p: Vec3| to_coif.transform_point3(p.as_dvec3()).as_vec3())
        }
        Some(AttributeKind::Normal) => {
            let normal_matrix = linear.inverse().transpose();
            Box::new(move |n: Vec3| (normal_matrix * n.as_dvec3()).normalize_or_zero().as_vec3())
        }
        Some(_) => Box::new(move |v: Vec3| (linear * v.as_dvec3()).as_vec3()),
        None => return,
    };
    for c in data.chunks_exact_mut(3) {
        c.copy_from_slice(&map(Vec3::from_slice(c)).to_array());
    }
}

/// How 3-vector data follows the points from file space to coif's: by its kind, or for plain
/// float3 data by its name; `None`: not at all.
pub(crate) fn direction_kind(
    kind: crate::groom::AttributeKind,
    name: &str,
) -> Option<crate::groom::AttributeKind> {
    use crate::groom::AttributeKind;
    match kind {
        AttributeKind::Point | AttributeKind::Normal | AttributeKind::Vector => Some(kind),
        AttributeKind::Float => {
            let name = name.to_ascii_lowercase();
            if name == usda::names::REST || name == "rest_position" {
                Some(AttributeKind::Point)
            } else if name == "n" || name.contains("normal") {
                Some(AttributeKind::Normal)
            } else if name == "v" || name.starts_with("velocit") {
                Some(AttributeKind::Vector)
            } else {
                None
            }
        }
        _ => None,
    }
}

/// Writes a groom in the format its extension names, atomically. Returns warnings about data
/// the format cannot carry.
pub fn write_groom(path: &Path, groom: &Groom) -> Result<Vec<String>> {
    write_groom_with(path, groom, &ExportOptions::default())
}

/// [`write_groom`] with format-specific choices. USD and Alembic carry the groom's meshes beside
/// the curves; with `--unreal` they go to the sibling file [`unreal::meshes_path`] instead,
/// written together with the groom (both or neither).
pub fn write_groom_with(path: &Path, groom: &Groom, options: &ExportOptions) -> Result<Vec<String>> {
    groom.validate_stored()?;
    let format = check_output(path, options)?;
    match format {
        Format::Hair => {
            hair::check_writable(groom, path)?;
            atomic::write_atomically(path, |w| hair::write(groom, w).map_err(|e| Error::io(path, e)))?;
            let mut warnings: Vec<String> = hair::unsupported(groom)
                .into_iter()
                .map(|what| format!("{}: .hair drops {what}", path.display()))
                .collect();
            warnings.extend(mesh_warning(path, groom));
            Ok(warnings)
        }
        Format::Usda | Format::Usdc | Format::Usdz => write_usd_stage(path, format, groom, None, options),
        Format::Alembic => {
            let abc_options = alembic::AlembicWriteOptions { unreal: options.unreal, ..Default::default() };
            stream_alembic_frames(path, groom, std::iter::empty(), &abc_options, false)?;
            Ok(alembic_warnings(path, groom))
        }
    }
}

/// Refuses (exit 2) when any of `outputs` is, by identity, one of the files read (`inputs`, each
/// with what it is to the run): writing it would replace what the run read.
pub fn refuse_writing_inputs(outputs: &[&Path], inputs: &[(String, &Path)]) -> Result<()> {
    let read: Vec<(&str, &Path, std::path::PathBuf)> = inputs
        .iter()
        .filter_map(|(what, path)| std::fs::canonicalize(path).ok().map(|c| (what.as_str(), *path, c)))
        .collect();
    for output in outputs {
        // A file that does not exist yet is no input; one that does is compared by identity.
        let Ok(written) = std::fs::canonicalize(output) else { continue };
        if let Some((what, path, _)) = read.iter().find(|(_, _, c)| *c == written) {
            return Err(Error::Usage(format!(
                "{}: the run would write over {what} ({}); write the result to another file",
                output.display(),
                path.display()
            )));
        }
    }
    Ok(())
}

/// The format `path` is written in with `options`, or the usage error: `--unreal` writes only
/// the formats Unreal's groom importers read, and the output's directory must exist. Commands
/// check it before any work.
pub fn check_output(path: &Path, options: &ExportOptions) -> Result<Format> {
    let format = Format::from_extension(path)?;
    check_output_directory(path)?;
    if options.unreal && matches!(format, Format::Hair | Format::Usdz) {
        return Err(Error::Usage(format!(
            "{}: --unreal writes .abc, .usda or .usdc (Unreal's groom importers), not .{}",
            path.display(),
            path.extension().and_then(|e| e.to_str()).unwrap_or("")
        )));
    }
    Ok(format)
}

/// The usage error for an output whose directory does not exist, or that is a directory, checked
/// before any work: a mistyped path would otherwise be found only when a long run writes its
/// result.
pub fn check_output_directory(path: &Path) -> Result<()> {
    // An output that is itself a directory, or spelled as one, fails the same way at the end.
    let spelled_as_directory =
        path.as_os_str().as_encoded_bytes().last().is_some_and(|&b| std::path::is_separator(b as char));
    if path.is_dir() || spelled_as_directory {
        return Err(Error::Usage(format!("{}: the output is a directory, not a file", path.display())));
    }
    // A symbolic link is written through (`atomic`): the file it leads to must be writable.
    let target = atomic::through_links(path).map_err(|e| {
        Error::Usage(format!("{}: the output is a symbolic link that leads nowhere: {e}", path.display()))
    })?;
    let through = if target == path {
        String::new()
    } else {
        format!(" (the symbolic link's target {})", target.display())
    };
    match target.parent() {
        Some(dir) if !dir.as_os_str().is_empty() && !dir.is_dir() => {
            let problem = if dir.exists() { "is not a directory" } else { "does not exist" };
            Err(Error::Usage(format!(
                "{}{through}: the directory {} {problem}",
                path.display(),
                dir.display()
            )))
        }
        _ => Ok(()),
    }
}

/// The file a write of `groom` to `path` puts the meshes in when that is not `path` itself: the
/// sibling [`unreal::meshes_path`] of `--unreal` output.
pub fn meshes_output(path: &Path, groom: &Groom, options: &ExportOptions) -> Option<std::path::PathBuf> {
    (options.unreal && !groom.meshes.is_empty()).then(|| unreal::meshes_path(path))
}

/// `.hair` holds curves only: say so rather than drop the meshes silently.
fn mesh_warning(path: &Path, groom: &Groom) -> Option<String> {
    (!groom.meshes.is_empty()).then(|| {
        let names: Vec<&str> = groom.meshes.iter().map(|m| m.path.as_str()).collect();
        format!("{}: .hair holds no meshes (only the curves): {}", path.display(), names.join(", "))
    })
}

fn alembic_warnings(path: &Path, groom: &Groom) -> Vec<String> {
    alembic::unsupported(groom).into_iter().map(|what| format!("{}: {what}", path.display())).collect()
}

fn usd_warnings(path: &Path, groom: &Groom) -> Vec<String> {
    usda::unsupported(groom).into_iter().map(|what| format!("{}: {what}", path.display())).collect()
}

/// Writes a groom whose points move over time: `frames` holds every frame's points (same
/// topology as `groom`, whose other data and meshes are written once) and `attributes`, when not
/// empty, every frame's values of attributes of the groom (the same names in each frame); those
/// whose values change are time-sampled too. `frames_per_second` sets the time codes (frame `k`
/// at time code `k + 1`). USD and Alembic carry time samples; `.hair` cannot.
pub fn write_animated(
    path: &Path,
    groom: &Groom,
    frames: &[Vec<Vec3>],
    attributes: &[Vec<crate::groom::Attribute>],
    frames_per_second: f32,
    options: &ExportOptions,
) -> Result<Vec<String>> {
    groom.validate_stored()?;
    if frames.is_empty() {
        return write_groom_with(path, groom, options);
    }
    if !attributes.is_empty() && attributes.len() != frames.len() {
        return Err(Error::Usage(format!(
            "{}: {} frames of points but {} of attributes",
            path.display(),
            frames.len(),
            attributes.len()
        )));
    }
    // Only what changes is sampled; the rest is the groom's, written once.
    let changing: Vec<Vec<&crate::groom::Attribute>> = match attributes.first() {
        None => Vec::new(),
        Some(first) => {
            let changes = |a: &crate::groom::Attribute| {
                attributes.iter().any(|f| f.iter().any(|b| b.name == a.name && b.data != a.data))
            };
            let names: Vec<&str> = first.iter().filter(|a| changes(a)).map(|a| a.name.as_str()).collect();
            attributes
                .iter()
                .map(|f| f.iter().filter(|a| names.contains(&a.name.as_str())).collect())
                .collect()
        }
    };
    let times =
        usda::TimeCodes { start: 1.0, end: frames.len() as f64, per_second: frames_per_second as f64 };
    check_output(path, options)?;
    let format = check_animated_output(path)?;
    if format == Format::Alembic {
        let abc_options = alembic_options(options, times.per_second, times.start);
        // Frame k: the groom with that frame's points and changing attributes.
        let frame = |k: usize| {
            let mut frame = groom.clone();
            frame.points.clone_from(&frames[k]);
            for &attribute in changing.get(k).into_iter().flatten() {
                frame.set_attribute(attribute.clone());
            }
            Ok(frame)
        };
        let first = frame(0)?;
        stream_alembic_frames(path, &first, (1..frames.len()).map(frame), &abc_options, true)?;
        return Ok(alembic_warnings(path, groom));
    }
    let animation = usd_stage::Animation {
        attributes: if changing.iter().all(Vec::is_empty) { Vec::new() } else { changing },
        ..usd_stage::Animation::of_points(times, frames)
    };
    write_usd_stage(path, format, groom, Some(&animation), options)
}

/// Writes `first` and the frames `rest` yields (with the same topology) at frame numbers
/// `timeline.first`, `+ 1`, …: Alembic streams them to disk one at a time; USD holds what
/// changes (points, mesh points, attributes that differ from the first frame's; checked against
/// the memory limit first) until the stage is written. A frame whose strands differ from the
/// first's is refused, naming `source` (where the frames come from) and its frame number.
pub fn write_frames(
    path: &Path,
    source: &Path,
    first: &Groom,
    rest: impl Iterator<Item = Result<Groom>>,
    timeline: &timeline::Timeline,
    options: &ExportOptions,
) -> Result<Vec<String>> {
    first.validate_stored()?;
    check_output(path, options)?;
    let format = check_animated_output(path)?;
    let count = timeline.frame_count();
    let same_topology = |k: u64, groom: &Groom| -> Result<()> {
        if groom.strand_offsets != first.strand_offsets || groom.group_ids != first.group_ids {
            return Err(Error::Usage(format!(
                "{}: frame {} has other strands than frame {} ({} vs {} vertices); coif writes animation \
                 of constant topology, so {} is not written (--frame N writes one frame)",
                source.display(),
                timeline.frame(k),
                timeline.first,
                groom.vertex_count(),
                first.vertex_count(),
                path.display()
            )));
        }
        let meshes =
            |g: &Groom| g.meshes.iter().map(|m| (m.path.clone(), m.points.len())).collect::<Vec<_>>();
        if meshes(groom) != meshes(first) {
            return Err(Error::Usage(format!(
                "{}: frame {} has other meshes than frame {}; coif writes animation of constant \
                 topology, so {} is not written (--frame N writes one frame)",
                source.display(),
                timeline.frame(k),
                timeline.first,
                path.display(),
            )));
        }
        Ok(())
    };
    let rest = rest.enumerate().map(|(k, groom)| {
        let groom = groom?;
        same_topology(k as u64 + 1, &groom)?;
        Ok(groom)
    });
    if format == Format::Alembic {
        let abc_options = alembic_options(options, timeline.frames_per_second, timeline.first);
        stream_alembic_frames(path, first, rest, &abc_options, true)?;
        return Ok(alembic_warnings(path, first));
    }
    crate::limits::check_memory(
        &format!("holding {count} frames of {} vertices for {}", first.vertex_count(), path.display()),
        count as f64 * first.vertex_count() as f64 * 12.0,
    )?;
    let changes = FrameChanges::collect(first, rest)?;
    let times = usda::TimeCodes {
        start: timeline.first,
        end: timeline.frame(changes.points.len().max(1) as u64 - 1),
        per_second: timeline.frames_per_second,
    };
    write_usd_stage(path, format, first, Some(&changes.animation(first, times)), options)
}

/// What differs from the first frame in each frame of an animation (the first included): the
/// points, the mesh points, the attributes that change anywhere and which prims are hidden.
struct FrameChanges {
    points: Vec<Vec<Vec3>>,
    /// Each frame's mesh points when they differ from the first frame's.
    meshes: Vec<Option<Vec<Vec<Vec3>>>>,
    /// Each frame's attributes whose values differ from the first frame's.
    attributes: Vec<Vec<crate::groom::Attribute>>,
    /// Each frame's widths when they differ from the first frame's.
    widths: Vec<Option<Vec<f32>>>,
    /// Each frame's hidden groups and meshes (a file's animated visibility).
    hidden: Vec<usd_stage::Hidden>,
}

impl FrameChanges {
    fn collect(first: &Groom, rest: impl Iterator<Item = Result<Groom>>) -> Result<Self> {
        let mut changes = FrameChanges {
            points: vec![first.points.clone()],
            meshes: vec![None],
            attributes: vec![Vec::new()],
            widths: vec![None],
            hidden: vec![usd_stage::Hidden::of(first)],
        };
        for groom in rest {
            let mut groom = groom?;
            changes.hidden.push(usd_stage::Hidden::of(&groom));
            let widths = std::mem::take(&mut groom.widths);
            changes.widths.push((widths != first.widths).then_some(widths));
            let moved = groom.meshes.iter().zip(&first.meshes).any(|(a, b)| a.points != b.points);
            changes.meshes.push(
                moved.then(|| groom.meshes.iter_mut().map(|m| std::mem::take(&mut m.points)).collect()),
            );
            let attributes = std::mem::take(&mut groom.attributes);
            changes.attributes.push(
                attributes
                    .into_iter()
                    .filter(|a| first.attribute(&a.name).is_some_and(|f| f.data != a.data))
                    .collect(),
            );
            changes.points.push(groom.points);
        }
        Ok(changes)
    }

    /// The animation to write: every frame lists the same changing attributes and, when any
    /// mesh moves, every mesh (a frame that matches the first borrows the first's values).
    fn animation<'g>(&'g self, first: &'g Groom, times: usda::TimeCodes) -> usd_stage::Animation<'g> {
        let mut names: Vec<&str> = self.attributes.iter().flatten().map(|a| a.name.as_str()).collect();
        names.sort_unstable();
        names.dedup();
        let attributes = self
            .attributes
            .iter()
            .map(|own| {
                let named = |name: &str| {
                    own.iter()
                        .find(|a| a.name == name)
                        .or_else(|| first.attribute(name))
                        .expect("a groom attribute")
                };
                names.iter().map(|name| named(name)).collect()
            })
            .collect();
        let first_meshes: Vec<&[Vec3]> = first.meshes.iter().map(|m| m.points.as_slice()).collect();
        let meshes = if self.meshes.iter().any(Option::is_some) {
            self.meshes
                .iter()
                .map(|own| {
                    own.as_ref()
                        .map_or_else(|| first_meshes.clone(), |m| m.iter().map(Vec::as_slice).collect())
                })
                .collect()
        } else {
            Vec::new()
        };
        usd_stage::Animation {
            times,
            points: self.points.iter().map(Vec::as_slice).collect(),
            meshes,
            attributes: if names.is_empty() { Vec::new() } else { attributes },
            widths: if self.widths.iter().any(Option::is_some) {
                self.widths.iter().map(|w| w.as_deref().unwrap_or(&first.widths)).collect()
            } else {
                Vec::new()
            },
            hidden: if self.hidden.iter().all(|h| *h == self.hidden[0]) {
                Vec::new()
            } else {
                self.hidden.clone()
            },
        }
    }
}

fn alembic_options(
    options: &ExportOptions,
    frames_per_second: f64,
    first_frame: f64,
) -> alembic::AlembicWriteOptions {
    alembic::AlembicWriteOptions {
        unreal: options.unreal,
        frames_per_second,
        first_frame,
        ..Default::default()
    }
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

/// One USD stage (still, or animated) in `format`, with the groom's meshes; `--unreal` adds
/// Epic's layout (see [`unreal`]): `groom_*` primvars and the spec version, and the meshes go
/// to the sibling file [`unreal::meshes_path`], committed with the groom file (both or neither).
fn write_usd_stage(
    path: &Path,
    format: Format,
    groom: &Groom,
    animation: Option<&usd_stage::Animation>,
    options: &ExportOptions,
) -> Result<Vec<String>> {
    if let Some(animation) = animation {
        usd_stage::check_animation(groom, animation, path)?;
    }
    let mut meshes_file = None;
    if options.unreal {
        let mut unreal_groom = unreal::for_usd(groom);
        let meshes = std::mem::take(&mut unreal_groom.meshes);
        usda::check_writable(&unreal_groom, path)?;
        if !meshes.is_empty() {
            let sibling = unreal::meshes_path(path);
            let stage = usd_stage::plan_meshes(&meshes, animation)?;
            meshes_file = Some((sibling.clone(), usd_to_temp(&sibling, format, &stage)?));
        }
        // Unreal's names for the attributes that change, like the groom's own.
        let renamed: Vec<Vec<crate::groom::Attribute>> = animation
            .map(|a| {
                a.attributes
                    .iter()
                    .map(|f| f.iter().map(|&a| unreal::renamed_for_usd(a.clone())).collect())
                    .collect()
            })
            .unwrap_or_default();
        let animation = animation.map(|a| usd_stage::Animation {
            times: a.times,
            points: a.points.clone(),
            meshes: Vec::new(),
            attributes: renamed.iter().map(|f| f.iter().collect()).collect(),
            widths: a.widths.clone(),
            hidden: a.hidden.clone(),
        });
        let mut stage = usd_stage::plan(&unreal_groom, animation.as_ref())?;
        usd_stage::add_unreal_groom_properties(&mut stage);
        let groom_file = (path.to_path_buf(), usd_to_temp(path, format, &stage)?);
        atomic::commit_together(std::iter::once(groom_file).chain(meshes_file).collect())?;
        return Ok(usd_warnings(path, &unreal_groom));
    }
    usda::check_writable(groom, path)?;
    let stage = usd_stage::plan(groom, animation)?;
    if format == Format::Usdz {
        let write_text =
            |out: &mut dyn std::io::Write| usda::write_stage(&stage, out).map_err(|e| Error::io(path, e));
        usd_interop::write_usd(path, write_text)?;
    } else {
        atomic::commit(path, usd_to_temp(path, format, &stage)?)?;
    }
    Ok(usd_warnings(path, groom))
}

/// A planned stage as `.usda` or `.usdc` in a temporary file beside `path`, not yet committed.
fn usd_to_temp(
    path: &Path,
    format: Format,
    stage: &usd_stage::Stage,
) -> Result<std::io::BufWriter<atomic::TempFile>> {
    let mut out = atomic::create_beside(path)?;
    match format {
        Format::Usda => usda::write_stage(stage, &mut out).map_err(|e| Error::io(path, e))?,
        Format::Usdc => out = usdc::write::encode(stage, out).map_err(|e| Error::io(path, e))?,
        _ => unreachable!("only .usda and .usdc are written natively"),
    }
    Ok(out)
}

/// Streams `first` and the frames `rest` yields to an Alembic file, one at a time (`animated`
/// false: `first` alone, as a static file). With `--unreal` the meshes stream to the sibling
/// file [`unreal::meshes_path`], committed after the groom file.
fn stream_alembic_frames(
    path: &Path,
    first: &Groom,
    rest: impl Iterator<Item = Result<Groom>>,
    options: &alembic::AlembicWriteOptions,
    animated: bool,
) -> Result<()> {
    // Unreal's root UVs come from Blender's surface UV when the groom has none.
    let prepare = |groom: &Groom| options.unreal.then(|| unreal::with_root_uvs(groom)).flatten();
    let prepared = prepare(first);
    let first = prepared.as_ref().unwrap_or(first);
    let mut writer = alembic::AnimationWriter::create(path, first, options, animated)?;
    writer.write_frame(first)?;
    for groom in rest {
        let groom = groom?;
        let prepared = prepare(&groom);
        writer.write_frame(prepared.as_ref().unwrap_or(&groom))?;
    }
    writer.finish()
}
