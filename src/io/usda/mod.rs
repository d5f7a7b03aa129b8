//! USD text (`.usda`), read and written natively. See `/work/shared/docs/usd-curves.md` for the
//! conventions: an `Xform` holding `BasisCurves`, widths and primvars with explicit
//! interpolation, `extent`, stage metadata, time-sampled points for animation.
//!
//! Writing: [`write`] for one groom, [`write_animated`] for time-sampled points with constant
//! topology; the stage is planned by `io::usd_stage` (shared with the `.usdc` writer): one
//! `BasisCurves` prim per curve group. Reading: [`read`] parses a layer (streaming, never the whole file in memory) and
//! builds one groom from all its curve prims; a layer that needs composition (references,
//! variants…) is reported as [`ReadOutcome::NeedsComposition`] so the caller can flatten it
//! through usd-core first.
mod bulk;
mod lexer;
mod parser;
mod reader;
mod writer;

use std::io::Read;
use std::path::Path;

use crate::error::{Error, Result};
use crate::groom::Groom;
use crate::io::ImportOptions;

pub use crate::io::usd_stage::{check_writable, unsupported, TimeCodes, DEFAULT_PRIM_PATH};
pub use writer::{write, write_animated, write_stage};
// The crate-file module writes the same stage and reads into the same layer model.
pub(crate) use parser::{offer_sample, wanted, Attribute, Layer, LayerTimeline, Prim, Value};
pub(crate) use reader::{
    groom_from_layer, local_transform, places_with_time_samples, stage_transform, value_at,
};

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

/// What reading a `.usda` layer gave.
// Returned once per file: boxing the groom would buy nothing.
#[allow(clippy::large_enum_variant)]
pub enum ReadOutcome {
    Groom(Groom),
    /// The layer composes other layers or variants (the arc named, on that line); coif's own
    /// reader only reads flattened stages.
    NeedsComposition {
        line: u32,
        what: String,
    },
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
    let layer = match parser::parse(input, time) {
        Ok(layer) => layer,
        Err(parser::ParseError::Syntax(e)) => {
            return Err(Error::format(path, format!("line {}: {}", e.line, e.message)))
        }
        Err(parser::ParseError::Io(e)) => return Err(Error::io(path, e)),
        Err(parser::ParseError::Composition { line, what }) => {
            return Ok(ReadOutcome::NeedsComposition { line, what })
        }
    };
    reader::groom_from_layer(layer, path, options, time).map(ReadOutcome::Groom)
}

/// Parses a `.usda` file into the layer model (for the prims a render reads besides curves:
/// cameras and lights). A layer that needs composition is an error naming the arc.
pub(crate) fn read_layer_file(path: &Path, time: Option<f64>) -> Result<Layer> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    match parser::parse(file, time) {
        Ok(layer) => Ok(layer),
        Err(parser::ParseError::Syntax(e)) => {
            Err(Error::format(path, format!("line {}: {}", e.line, e.message)))
        }
        Err(parser::ParseError::Io(e)) => Err(Error::io(path, e)),
        Err(parser::ParseError::Composition { line, what }) => Err(needs_composition(path, line, &what)),
    }
}

fn needs_composition(path: &Path, line: u32, what: &str) -> Error {
    Error::format(
        path,
        format!(
            "line {line}: '{what}' needs composition; flatten the stage with pipeline/usd_interop.py first"
        ),
    )
}

/// The timeline metadata of a `.usda` layer (its header only; no prim is parsed).
pub fn read_header(input: impl Read, path: &Path) -> Result<parser::LayerTimeline> {
    match parser::parse_header(input) {
        Ok(layer) => Ok(layer.timeline),
        Err(parser::ParseError::Syntax(e)) => {
            Err(Error::format(path, format!("line {}: {}", e.line, e.message)))
        }
        Err(parser::ParseError::Io(e)) => Err(Error::io(path, e)),
        Err(parser::ParseError::Composition { line, what }) => Err(needs_composition(path, line, &what)),
    }
}

/// Whether a `.usda` layer time-samples anything that places its curves or meshes (see
/// [`places_with_time_samples`]); `None` when the layer needs composition to tell.
pub fn is_animated(path: &Path) -> Result<Option<bool>> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    match parser::parse(file, None) {
        Ok(layer) => Ok(Some(places_with_time_samples(&layer))),
        Err(parser::ParseError::Syntax(e)) => {
            Err(Error::format(path, format!("line {}: {}", e.line, e.message)))
        }
        Err(parser::ParseError::Io(e)) => Err(Error::io(path, e)),
        Err(parser::ParseError::Composition { .. }) => Ok(None),
    }
}

/// Reads a `.usda` file that must not need composition.
pub fn read_file(path: &Path, options: &ImportOptions, time: Option<f64>) -> Result<Groom> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    match read(file, path, options, time)? {
        ReadOutcome::Groom(groom) => Ok(groom),
        ReadOutcome::NeedsComposition { line, what } => Err(needs_composition(path, line, &what)),
    }
}
