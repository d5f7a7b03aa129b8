//! USD text (`.usda`), read and written natively. See `/work/shared/docs/usd-curves.md` for the
//! conventions: an `Xform` holding `BasisCurves`, widths and primvars with explicit
//! interpolation, `extent`, stage metadata, time-sampled points for animation.
//!
//! Writing: [`write`] for one groom, [`write_animated`] for time-sampled points with constant
//! topology; the stage is planned by `io::usd_stage` (shared with the `.usdc` writer): one
//! `BasisCurves` prim per curve group. Reading: [`read`] parses a layer (streaming, never the whole file in memory) and
//! builds one groom from all its curve prims; a layer that needs composition (references,
//! variants…) is reported as [`ReadOutcome::NeedsComposition`] with its parsed layer, which
//! `io::usd_compose` composes natively.
mod bulk;
mod integer;
mod lexer;
mod parser;
mod reader;
mod spell;
mod writer;

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::groom::Groom;
use crate::io::ImportOptions;

pub use crate::io::usd_stage::{check_writable, unsupported, TimeCodes, DEFAULT_PRIM_PATH};
pub use writer::{write, write_animated, write_stage};
// The crate-file module writes the same stage and reads into the same layer model.
pub(crate) use parser::{offer_sample, wanted};
pub use parser::{Attribute, FileArray, FileArrays, Layer, LayerTimeline, Prim, Site, Specifier, Value};
pub(crate) use reader::{
    groom_from_layer, groom_from_layer_in, local_transform, places_with_time_samples, stage_transform,
    value_at,
};

/// Errors about a spec name the file and line where it was authored: on a composed stage, the
/// sublayer or referenced file a value came from, not the root layer.
#[derive(Clone, Copy)]
pub struct SiteFiles<'a> {
    read: &'a Path,
    sources: &'a [PathBuf],
}

impl<'a> SiteFiles<'a> {
    /// `read`: the file the stage was read from; `sources`: its [`Layer::sources`].
    pub fn new(read: &'a Path, sources: &'a [PathBuf]) -> Self {
        SiteFiles { read, sources }
    }

    pub fn error(&self, site: Site, message: impl std::fmt::Display) -> Error {
        let file = self.sources.get(usize::from(site.layer)).map_or(self.read, PathBuf::as_path);
        match site.line {
            0 => Error::format(file, message.to_string()),
            line => Error::format(file, format!("line {line}: {message}")),
        }
    }
}

/// First bytes of every `.usda` file.
pub const MAGIC: &[u8] = b"#usda";

/// Diameter given to strands of a stage that authors no `widths` (metres): a typical hair.
pub const DEFAULT_WIDTH: f32 = 80e-6;

/// How coif's groom data is named in USD.
pub mod names {
    /// Root UV on the scalp, `texCoord2f[]`, uniform.
    pub const ST: &str = "st";
    /// Strand identifier (Epic's groom convention), `int[]`, uniform.
    pub const GROOM_ID: &str = "groom_id";
    /// Guide flag (Epic's groom convention), `int[]`, uniform.
    pub const GROOM_GUIDE: &str = "groom_guide";
    /// Rest positions, `point3f[]` (Houdini's convention); transformed with the points.
    pub const REST: &str = "rest";
    /// The primvar coif's `color` attribute becomes.
    pub const DISPLAY_COLOR: &str = "displayColor";

    /// The groom attribute a primvar becomes.
    pub fn attribute_for_primvar(primvar: &str) -> String {
        match primvar {
            DISPLAY_COLOR => crate::groom::attr::COLOR.to_string(),
            other => other.to_string(),
        }
    }

    /// The primvar a groom attribute becomes (before any renaming to a valid USD name).
    pub fn primvar_for_attribute(attribute: &str) -> &str {
        match attribute {
            crate::groom::attr::COLOR => DISPLAY_COLOR,
            other => other,
        }
    }
}

/// Which state of a USD stage to read.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Selection {
    /// Time code to read time samples at (`None`: default values, else the earliest sample).
    pub time: Option<f64>,
    /// Variant selections, `SET=NAME` (every prim with that set) or `/Prim:SET=NAME`.
    pub variants: Vec<String>,
}

/// What reading a `.usda` or `.usdc` layer gave.
// Returned once per file: boxing the groom would buy nothing.
#[allow(clippy::large_enum_variant)]
pub enum ReadOutcome {
    /// The groom, and warnings about what reading it left out.
    Groom(Groom, Vec<String>),
    /// The layer composes other layers or variants: the parsed layer, for `io::usd_compose`.
    NeedsComposition(Box<Layer>),
}

/// Reads a `.usda` stage. `time` picks time samples (`None`: default values, or the earliest
/// sample of attributes that only have samples). Units and up axis are converted to metres and
/// Y up; `options` only apply where the stage does not say.
pub fn read(
    input: impl Read,
    path: &Path,
    options: &ImportOptions,
    time: Option<f64>,
) -> Result<ReadOutcome> {
    let layer = parse(input, path, time)?;
    if layer.composes() {
        return Ok(ReadOutcome::NeedsComposition(Box::new(layer)));
    }
    reader::groom_from_layer(layer, path, options, time)
        .map(|(groom, warnings)| ReadOutcome::Groom(groom, warnings))
}

fn parse(input: impl Read, path: &Path, time: Option<f64>) -> Result<Layer> {
    parser::parse(input, time).map_err(|error| parse_error(error, path))
}

/// A parse error as the error of reading `path`.
fn parse_error(error: parser::ParseError, path: &Path) -> Error {
    match error {
        parser::ParseError::Syntax(e) => Error::format(path, format!("line {}: {}", e.line, e.message)),
        parser::ParseError::Io(e) => Error::io(path, e),
    }
}

/// Parses a `.usda` file keeping the time samples from `first` to `last` (and those around
/// them), for [`groom_at`] to read any time between from it.
pub(crate) fn read_layer_between(path: &Path, first: f64, last: f64) -> Result<Layer> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    parser::parse_keeping(file, parser::KeptSamples::Between(first, last))
        .map_err(|error| parse_error(error, path))
}

/// The groom a layer without composition arcs (from [`read_layer_between`]) holds at `time`,
/// as [`read`] gives it for that time.
pub(crate) fn groom_at(
    layer: &Layer,
    path: &Path,
    options: &ImportOptions,
    time: f64,
) -> Result<ReadOutcome> {
    reader::groom_from_layer(layer.at_time(time), path, options, Some(time))
        .map(|(groom, warnings)| ReadOutcome::Groom(groom, warnings))
}

/// Parses a `.usda` file into the layer model, composition arcs recorded, not resolved.
pub(crate) fn read_layer_file(path: &Path, time: Option<f64>) -> Result<Layer> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    parse(file, path, time)
}

/// The timeline metadata of a `.usda` layer (its header only; no prim is parsed). The stage's
/// timeline is its root layer's, so sublayers are not read.
pub fn read_header(input: impl Read, path: &Path) -> Result<parser::LayerTimeline> {
    parser::parse_header(input).map(|layer| layer.timeline).map_err(|error| parse_error(error, path))
}

/// Whether a `.usda` stage (composed, if it needs composition) time-samples anything that
/// places its curves or meshes (see [`places_with_time_samples`]).
pub fn is_animated(path: &Path) -> Result<Option<bool>> {
    let layer = crate::io::usd_compose::read_stage(path, &Selection::default())?;
    Ok(Some(places_with_time_samples(&layer)))
}

/// Reads a `.usda` file, composing what it references natively (see `io::usd_compose`).
pub fn read_file(path: &Path, options: &ImportOptions, time: Option<f64>) -> Result<Groom> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    match read(file, path, options, time)? {
        ReadOutcome::Groom(groom, _) => Ok(groom),
        ReadOutcome::NeedsComposition(layer) => crate::io::usd_compose::groom_from_composed(
            *layer,
            path,
            options,
            &Selection { time, variants: vec![] },
        ),
    }
}
