//! Alembic (Ogawa) curves: coif's own reader and writer, layered like the reference library.
//!
//! - [`ogawa`]: the container (header, groups, data blocks), streaming writer, checked reader;
//! - [`murmur3`], [`spooky`]: the sample keys and the informational object/property hashes;
//! - [`archive_write`], [`archive_read`]: AbcCoreOgawa objects, properties, samples, metadata;
//! - [`curves_write`], [`curves_read`]: the AbcGeom Curves schema and Xforms ⇄ [`Groom`].
//!
//! Facts come from `docs/alembic-ogawa.md` (the team's format note); files are byte-identical to
//! the C++ library's for the same calls.
#[cfg(target_endian = "big")]
compile_error!("the Alembic writer stores samples in host byte order, which must be little-endian");

pub mod archive_read;
pub mod archive_write;
pub mod curves_read;
pub mod curves_write;
pub mod murmur3;
pub mod ogawa;
pub mod spooky;
pub mod types;

use std::io::BufWriter;
use std::path::{Path, PathBuf};

pub use curves_read::CurvesArchive;
pub use curves_write::{AlembicWriteOptions, CurvesWriter, Objects};

use super::atomic;
use crate::error::{Error, Result};
use crate::groom::Groom;

/// The first bytes of every Alembic (Ogawa) file.
pub const MAGIC: &[u8] = ogawa::MAGIC;

fn format_error(path: &Path) -> impl Fn(ogawa::OgawaError) -> Error + '_ {
    move |e| Error::format(path, e.0)
}

/// Converts a groom read from a file in Epic's centimetres to metres.
fn centimetres_to_metres(groom: &mut Groom) {
    groom.scale(1.0 / curves_write::epic::UNITS_PER_METRE);
}

/// Reads an Alembic file's curves at frame number `frame` of the file's own timeline (time
/// `frame / fps`, see [`CurvesArchive::read_at_frame`]; `None`: its first sample), all curves
/// objects merged, transforms applied. Files that declare Epic's groom spec are in centimetres
/// and are converted to metres unless `keep_file_units` (the caller converts them itself).
/// Returns warnings, naming `path`, about what the reading left out.
pub fn read(
    bytes: &[u8],
    path: &Path,
    frame: Option<f64>,
    keep_file_units: bool,
) -> Result<(Groom, Vec<String>)> {
    let archive = CurvesArchive::open(bytes).map_err(format_error(path))?;
    let groom = match frame {
        Some(frame) => archive.read_at_frame(frame),
        None => archive.read_frame(0),
    };
    let mut groom = groom.map_err(format_error(path))?;
    if archive.epic_groom && !keep_file_units {
        centimetres_to_metres(&mut groom);
    }
    let warnings = archive.left_out().iter().map(|w| format!("{}: {w}", path.display())).collect();
    Ok((groom, warnings))
}

/// Reads every frame of an Alembic file (see [`read`]).
pub fn read_all_frames(bytes: &[u8], path: &Path, keep_file_units: bool) -> Result<Vec<Groom>> {
    let archive = CurvesArchive::open(bytes).map_err(format_error(path))?;
    let mut frames = archive.read_all_frames().map_err(format_error(path))?;
    if archive.epic_groom && !keep_file_units {
        frames.iter_mut().for_each(centimetres_to_metres);
    }
    Ok(frames)
}

/// What an Alembic file cannot say about the groom, as warnings: the wrap of a cubic group
/// whose wrap Alembic readers take otherwise ([`curves_read::wrap_of`]).
pub fn unsupported(groom: &Groom) -> Vec<String> {
    let mut warnings = Vec::new();
    for g in 0..groom.group_count() {
        let group = groom.group(g);
        let read_back = curves_read::wrap_of(group.basis);
        if group.basis != crate::groom::CurveBasis::Linear
            && group.wrap != crate::groom::CurveWrap::Periodic
            && group.wrap != read_back
        {
            warnings.push(format!(
                "curve group '{}': Alembic records no {:?} wrap for {:?} curves; its readers (Blender, coif) take them as {:?}",
                group.name, group.wrap, group.basis, read_back
            ));
        }
    }
    for mesh in groom.meshes.iter().filter(|m| !m.holes.is_empty()) {
        warnings.push(format!(
            "mesh '{}': Alembic's PolyMesh has no holes; its {} hole faces are written as faces",
            mesh.path,
            mesh.holes.len()
        ));
    }
    warnings
}

/// Writes a static groom (one sample) atomically.
pub fn write(path: &Path, groom: &Groom, options: &AlembicWriteOptions) -> Result<()> {
    let mut writer = AnimationWriter::create(path, groom, options, false)?;
    writer.write_frame(groom)?;
    writer.finish()
}

/// Writes an animated groom frame by frame (uniform time sampling at the options' frame rate,
/// one sample per frame, constant topology), streaming each frame to disk. The file appears
/// under its name only when [`AnimationWriter::finish`] succeeds. With `--unreal` the meshes
/// stream to their own file ([`crate::io::unreal::meshes_path`]), committed with the groom's (both
/// or neither).
pub struct AnimationWriter {
    path: PathBuf,
    writer: CurvesWriter<BufWriter<atomic::TempFile>>,
    /// The meshes' own file and its writer, in Unreal layout.
    meshes: Option<(PathBuf, CurvesWriter<BufWriter<atomic::TempFile>>)>,
}

impl AnimationWriter {
    /// Starts the file; `first` fixes the topology and attribute layout (it is not written:
    /// pass it to [`AnimationWriter::write_frame`] too). `animated` false makes a static file.
    pub fn create(path: &Path, first: &Groom, options: &AlembicWriteOptions, animated: bool) -> Result<Self> {
        first.validate_stored()?;
        let start = |path: &Path, options: &AlembicWriteOptions| -> Result<CurvesWriter<_>> {
            let out = atomic::create_beside(path)?;
            CurvesWriter::new(out, first, options, animated).map_err(|e| Error::io(path, e))
        };
        let sibling = options.unreal && !first.meshes.is_empty();
        let meshes = match sibling {
            true => {
                let meshes_path = crate::io::unreal::meshes_path(path);
                let options = AlembicWriteOptions { objects: Objects::Meshes, ..options.clone() };
                Some((meshes_path.clone(), start(&meshes_path, &options)?))
            }
            false => None,
        };
        let objects = if sibling { Objects::Curves } else { options.objects };
        let writer = start(path, &AlembicWriteOptions { objects, ..options.clone() })?;
        Ok(AnimationWriter { path: path.to_path_buf(), writer, meshes })
    }

    pub fn write_frame(&mut self, groom: &Groom) -> Result<()> {
        groom.validate_stored()?;
        self.writer.write_frame(groom).map_err(|e| frame_error(&self.path, e))?;
        if let Some((path, writer)) = &mut self.meshes {
            writer.write_frame(groom).map_err(|e| frame_error(path, e))?;
        }
        Ok(())
    }

    pub fn finish(self) -> Result<()> {
        let groom = self.writer.finish().map_err(|e| Error::io(&self.path, e))?;
        let mut files = vec![(self.path, groom)];
        if let Some((path, writer)) = self.meshes {
            let meshes = writer.finish().map_err(|e| Error::io(&path, e))?;
            files.push((path, meshes));
        }
        // The groom file and the meshes file together: both or neither.
        atomic::commit_together(files)
    }
}

/// A frame the writer refused is bad input; anything else (a full disk, a failing device) is
/// the environment.
fn frame_error(path: &Path, e: std::io::Error) -> Error {
    match e.kind() {
        std::io::ErrorKind::InvalidInput => Error::Usage(format!("{}: {e}", path.display())),
        _ => Error::io(path, e),
    }
}
