//! The frames of a groom file's own timeline, as DCC exporters count them: whole frame numbers
//! at the file's frame rate (USD: `startTimeCode`…`endTimeCode` at `timeCodesPerSecond`, or at
//! `framesPerSecond` where a layer authors only that, as pxr counts them; Alembic: the first to
//! the last sample time of what moves the curves or meshes, at the archive's frame rate).
//! `coif convert` writes these frames of an animated input (or a `--frame-range`).
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::io::usda::LayerTimeline;
use crate::io::{alembic, input, usd_interop, usda, usdc, Format};

/// Frames a range may hold (11.5 hours at 24 fps): beyond is a typo, refused before reading.
pub const MAX_FRAMES: u64 = 1_000_000;
/// Largest frame number accepted (as `--frame`).
const MAX_FRAME_NUMBER: f64 = 1e9;

/// Frames `first`, `first + 1`, … up to `last` at `frames_per_second`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Timeline {
    pub first: f64,
    pub last: f64,
    pub frames_per_second: f64,
}

impl Timeline {
    /// How many whole frames the range holds (at least one).
    pub fn frame_count(&self) -> u64 {
        self.frames_spanned() as u64
    }

    /// [`frame_count`](Self::frame_count) as a float, for a range too long to count (1 to 1e300).
    pub fn frames_spanned(&self) -> f64 {
        // A millionth of a frame of rounding in a file's sample times does not drop the last frame.
        (self.last - self.first + 1e-6).floor().max(0.0) + 1.0
    }

    /// The `index`-th frame number.
    pub fn frame(&self, index: u64) -> f64 {
        self.first + index as f64
    }

    pub fn frames(&self) -> impl Iterator<Item = f64> + '_ {
        (0..self.frame_count()).map(|k| self.frame(k))
    }
}

/// Parses `A:B` (frame numbers, `A <= B`), naming `flag` in every refusal.
pub fn parse_range(text: &str, flag: &str) -> Result<(f64, f64)> {
    let bad = |why: &str| Error::Usage(format!("{flag} '{text}': {why}"));
    let (a, b) = text.split_once(':').ok_or_else(|| bad("expected FIRST:LAST, e.g. 1:24"))?;
    let number = |s: &str| -> Result<f64> {
        let v: f64 = s.trim().parse().map_err(|_| bad(&format!("'{s}' is not a frame number")))?;
        if !(v.is_finite() && v.abs() <= MAX_FRAME_NUMBER) {
            let v = crate::validate::shortest(v);
            return Err(bad(&format!("frame {v} is outside -1e9 to 1e9")));
        }
        Ok(v)
    };
    let (first, last) = (number(a)?, number(b)?);
    if first > last {
        return Err(bad("the first frame is after the last"));
    }
    if last - first >= MAX_FRAMES as f64 {
        return Err(bad(&format!("more than {MAX_FRAMES} frames")));
    }
    Ok((first, last))
}

/// The timeline of an animated groom file, `None` when it holds one moment (a static file, a
/// `.hair` file, a USD stage without `startTimeCode` < `endTimeCode` or whose curves, meshes and
/// the transforms above them have no time samples). An animated USD stage whose rate is not a
/// positive number is refused (it was read as one moment without a word).
pub fn read_timeline(path: &Path) -> Result<Option<Timeline>> {
    match super::format_of(path)? {
        Format::Hair => Ok(None),
        Format::Alembic => {
            let bytes = input::map_file(path)?;
            let archive = alembic::CurvesArchive::open(&bytes).map_err(|e| Error::format(path, e.0))?;
            if archive.frame_count() < 2 {
                return Ok(None);
            }
            let (first, last) = archive.frame_range();
            Ok(Some(Timeline { first, last, frames_per_second: archive.frames_per_second() }))
        }
        format => {
            let stage = UsdStageFile::open(path, format)?;
            let layer = stage.layer_timeline(path)?;
            let Some((first, last)) = layer.frame_range() else { return Ok(None) };
            // The range alone may be the scene's; only time samples make the groom move (on the
            // composed stage, for a layer with composition arcs).
            if !stage.is_animated(path)?.unwrap_or(true) {
                return Ok(None);
            }
            Ok(Some(Timeline { first, last, frames_per_second: frame_rate_of(&layer, path)? }))
        }
    }
}

/// The frames per second of a groom file's own timeline, whether or not it moves: USD's
/// time codes per second (`timeCodesPerSecond`, else `framesPerSecond`, else 24, as pxr
/// resolves them), Alembic's frame rate; `None` for `.hair`, which has none.
pub fn frame_rate(path: &Path) -> Result<Option<f64>> {
    match super::format_of(path)? {
        Format::Hair => Ok(None),
        Format::Alembic => {
            let bytes = input::map_file(path)?;
            let archive = alembic::CurvesArchive::open(&bytes).map_err(|e| Error::format(path, e.0))?;
            Ok(Some(archive.frames_per_second()))
        }
        format => {
            let layer = UsdStageFile::open(path, format)?.layer_timeline(path)?;
            Ok(Some(frame_rate_of(&layer, path)?))
        }
    }
}

/// A USD stage's time codes per second; one that is not a positive number is bad input.
fn frame_rate_of(layer: &LayerTimeline, path: &Path) -> Result<f64> {
    layer
        .checked_codes_per_second()
        .map_err(|(key, rate)| Error::format(path, format!("{key} {rate} is not a frame rate")))
}

/// A USD stage as its timeline is read: a crate file's bytes, or a `.usda` — the user's, or
/// usd-core's flattening of a `.usdz` package (kept while this lives). Errors name the user's file.
enum UsdStageFile {
    Crate(input::Input),
    Text { path: PathBuf, _flattened: Option<usd_interop::Flattened> },
}

impl UsdStageFile {
    fn open(path: &Path, format: Format) -> Result<Self> {
        Ok(match format {
            Format::Usdc => UsdStageFile::Crate(input::map_file(path)?),
            Format::Usdz => {
                let flattened = usd_interop::flatten(path, &[])?;
                UsdStageFile::Text { path: flattened.path(), _flattened: Some(flattened) }
            }
            _ => UsdStageFile::Text { path: path.to_path_buf(), _flattened: None },
        })
    }

    /// The root layer's timeline metadata.
    fn layer_timeline(&self, path: &Path) -> Result<LayerTimeline> {
        match self {
            UsdStageFile::Crate(bytes) => usdc::read_timeline(bytes, path),
            UsdStageFile::Text { path: text, .. } => {
                usda::read_header(std::fs::File::open(text).map_err(|e| Error::io(path, e))?, path)
            }
        }
    }

    /// Whether the (composed) stage time-samples what places its curves or meshes.
    fn is_animated(&self, path: &Path) -> Result<Option<bool>> {
        match self {
            UsdStageFile::Crate(bytes) => usdc::is_animated(bytes, path),
            UsdStageFile::Text { path: text, .. } => usda::is_animated(text),
        }
    }
}

/// The frame number `seconds` is on `path`'s own timeline (seconds × its frame rate), refused
/// (naming `flag`) for files without a frame rate, and before the first frame of an animated
/// file (as a frame number is; after the last, the last frame holds).
pub fn frame_at_time(path: &Path, seconds: f64, flag: &str) -> Result<f64> {
    let Some(rate) = frame_rate(path)? else {
        return Err(Error::Usage(format!(
            "{}: {flag} needs the file's frame rate: it applies to USD and Alembic input",
            path.display()
        )));
    };
    let frame = seconds * rate;
    if !(frame.is_finite() && frame.abs() <= MAX_FRAME_NUMBER) {
        return Err(Error::Usage(format!(
            "{flag} {seconds}: frame {} at {rate} fps is outside -1e9 to 1e9",
            crate::validate::shortest(frame)
        )));
    }
    if let Some(timeline) = read_timeline(path)? {
        if frame < timeline.first - 1e-6 {
            return Err(Error::Usage(format!(
                "{}: {flag} {} is frame {} at {} fps, before the file's first frame {} ({} s)",
                path.display(),
                crate::validate::shortest(seconds),
                crate::validate::shortest(frame),
                crate::validate::shortest(rate),
                crate::validate::shortest(timeline.first),
                crate::validate::seconds_text(timeline.first / rate)
            )));
        }
    }
    Ok(frame)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_parse_and_bad_ones_name_the_flag() {
        assert_eq!(parse_range("1:24", "--frame-range").unwrap(), (1.0, 24.0));
        assert_eq!(parse_range("-10:-5", "--frame-range").unwrap(), (-10.0, -5.0));
        for bad in ["24:1", "1", "a:b", "nan:3", "1:inf", "0:1e7", "1:2:3", ":"] {
            let e = parse_range(bad, "--frame-range").unwrap_err().to_string();
            assert!(e.contains("--frame-range"), "{bad}: {e}");
        }
        let t = Timeline { first: 1.0, last: 5.0 - 1e-9, frames_per_second: 24.0 };
        assert_eq!(t.frames().collect::<Vec<_>>(), [1.0, 2.0, 3.0, 4.0, 5.0]);
    }

    #[test]
    fn a_usd_range_is_a_timeline_only_when_something_placing_the_curves_is_sampled() {
        let dir = tempfile::tempdir().unwrap();
        let stage = |name: &str, points: &str, xform: &str| {
            let path = dir.path().join(name);
            let text = format!(
                "#usda 1.0\n(\n    startTimeCode = 101\n    endTimeCode = 148\n    timeCodesPerSecond = 30\n)\n\n\
                 def Xform \"G\"\n{{\n    {xform}\n    def BasisCurves \"C\"\n    {{\n        \
                 int[] curveVertexCounts = [2]\n        {points}\n    }}\n}}\n"
            );
            std::fs::write(&path, text).unwrap();
            read_timeline(&path).unwrap()
        };
        let still = "point3f[] points = [(0, 0, 0), (0, 1, 0)]";
        let moving =
            "point3f[] points.timeSamples = { 101: [(0, 0, 0), (0, 1, 0)], 148: [(1, 0, 0), (1, 1, 0)] }";
        let xform = "double3 xformOp:translate.timeSamples = { 101: (0, 0, 0), 148: (1, 0, 0) }\n    \
                     uniform token[] xformOpOrder = [\"xformOp:translate\"]";
        // The scene's frame range on a groom that does not move: one moment.
        assert_eq!(stage("still.usda", still, ""), None);
        let animated = Some(Timeline { first: 101.0, last: 148.0, frames_per_second: 30.0 });
        assert_eq!(stage("points.usda", moving, ""), animated);
        assert_eq!(stage("xform.usda", still, xform), animated);
    }
}
