//! Packaged USD (`.usdz`), through usd-core: coif runs `pipeline/usd_interop.py` with the
//! project's Python to flatten a package into a temporary `.usda` it then reads natively, or to
//! turn the `.usda` it wrote into `.usdz`. (`.usda` and `.usdc`, composed or not, never come
//! here: see `io::usd_compose`.)
//!
//! Python is found as `$COIF_PYTHON`, else `.deps/venv/bin/python` in the project folder (the
//! nearest ancestor of the executable holding `pipeline/usd_interop.py`, or the folder coif was
//! built from), else `python3` on the `PATH`. `$COIF_PIPELINE` may point at the scripts' folder.
//!
//! usd-core is bounded as coif is: the child may allocate `--max-memory` besides what Python and
//! usd-core take themselves, and a package's root layer, when it is a crate file, passes coif's
//! own `.usdc` reader before usd-core reads it (usd-core allocates an array's count before it
//! finds that the bytes cannot hold it).
use std::ffi::{OsStr, OsString};
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::error::{Error, Result};
use crate::groom::Groom;
use crate::io::{atomic, input, usda, usdc, ImportOptions};
use crate::limits;

const SCRIPT: &str = "usd_interop.py";

/// Data memory (what `RLIMIT_DATA` counts) Python and usd-core hold before reading anything.
/// Measured: 85 MB flattening a small package with one usd-core thread, about 7 MB more for each
/// further thread (usd-core starts one a CPU); both rounded up.
const INTERPRETER_BYTES: u64 = 128 << 20;
const BYTES_PER_THREAD: u64 = 16 << 20;

/// What the usd-core child may allocate: `--max-memory`, plus the interpreter's own.
fn child_memory() -> u64 {
    // usd-core starts a thread a CPU it may run on, as the standard library counts them.
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64;
    limits::max_memory().saturating_add(INTERPRETER_BYTES + BYTES_PER_THREAD * cpus)
}

/// The project folder holding `pipeline/`, searched from the executable's location upwards,
/// then the folder the crate was built from.
fn project_root() -> Option<PathBuf> {
    let from_exe = std::env::current_exe().ok().and_then(|exe| exe.canonicalize().ok());
    let candidates = from_exe
        .iter()
        .flat_map(|exe| exe.ancestors().skip(1).map(Path::to_path_buf).collect::<Vec<_>>())
        .chain(std::iter::once(PathBuf::from(env!("CARGO_MANIFEST_DIR"))));
    candidates.into_iter().find(|dir| dir.join("pipeline").join(SCRIPT).is_file())
}

/// The interop script to run.
pub fn script() -> Result<PathBuf> {
    if let Some(dir) = std::env::var_os("COIF_PIPELINE") {
        let script = PathBuf::from(dir).join(SCRIPT);
        return if script.is_file() {
            Ok(script)
        } else {
            Err(Error::External(format!("COIF_PIPELINE is set but {} does not exist", script.display())))
        };
    }
    project_root().map(|root| root.join("pipeline").join(SCRIPT)).ok_or_else(|| {
        Error::External(format!(
            "cannot find pipeline/{SCRIPT} (needed for .usdz); set COIF_PIPELINE to its folder"
        ))
    })
}

/// The Python interpreter that has usd-core.
pub fn python() -> PathBuf {
    if let Some(python) = std::env::var_os("COIF_PYTHON") {
        return PathBuf::from(python);
    }
    project_root()
        .map(|root| root.join(".deps/venv/bin/python"))
        .filter(|python| python.exists())
        .unwrap_or_else(|| PathBuf::from("python3"))
}

/// Runs the interop script; `input` is the user's file its errors name (read or written).
fn run(args: &[&OsStr], command: &str, input: &Path) -> Result<()> {
    let script = script()?;
    let python = python();
    let mut child = Command::new(&python);
    child.arg(&script).arg(command).args(args);
    // Killed with coif: an orphaned usd-core must not write into a folder coif has removed.
    super::cleanup::die_with_parent(&mut child);
    limits::limit_child_memory(&mut child, child_memory());
    let output = child.output().map_err(|e| {
        Error::External(format!(
            "cannot run Python ({}) for USD interop: {e}; run `make setup` or set COIF_PYTHON to a Python with usd-core",
            python.display()
        ))
    })?;
    if output.status.success() {
        return Ok(());
    }
    let stderr = String::from_utf8_lossy(&output.stderr);
    // The script's messages name the file too, for when it is run by hand.
    let message = stderr.trim().strip_prefix("usd_interop: ").unwrap_or(stderr.trim());
    let message = message.strip_prefix(&format!("{}: ", input.display())).unwrap_or(message);
    // usd-core reports an allocation that failed inside its reader as a corrupt value, so every
    // failure to read says what it had.
    let memory = format!(
        "usd-core may use {} of memory here: --max-memory",
        limits::memory_text(limits::max_memory() as f64)
    );
    #[cfg(unix)]
    let signal = std::os::unix::process::ExitStatusExt::signal(&output.status);
    #[cfg(not(unix))]
    let signal: Option<i32> = None;
    Err(match (output.status.code(), signal) {
        (Some(2), _) => Error::format(input, format!("{message} ({memory})")),
        (Some(3), _) => Error::External(format!(
            "usd-core (pxr) is missing from {}: run `make setup` or set COIF_PYTHON to a Python with usd-core ({message})",
            python.display()
        )),
        (Some(4), _) => Error::format(input, format!("usd-core ran out of memory: {memory}")),
        // Killed or crashed reading the user's file: an allocation past the limit that usd-core
        // did not survive, or a corruption it did not check.
        (None, Some(signal)) if command == "flatten" => {
            Error::format(input, format!("usd-core died of signal {signal} reading it ({memory}): {message}"))
        }
        _ => Error::External(format!("{SCRIPT} {command} failed ({}): {message}", output.status)),
    })
}

/// Refuses a package whose root layer is a crate file coif's own reader refuses, as it would
/// the same bytes as a `.usdc`: usd-core would first allocate what the file's counts ask (one
/// changed byte in a 3 KB package asks for 4 GB). Values are checked at their first time
/// sample; usd-core reads the rest within its memory limit. The root layer is the package's first
/// entry, stored uncompressed as the usdz format requires; one laid out otherwise, or a text
/// root layer, is left to usd-core.
fn check_root_layer(path: &Path) -> Result<()> {
    let bytes = input::map_file(path)?;
    let Some((name, layer)) = first_entry(&bytes).map_err(|message| Error::format(path, message))? else {
        return Ok(());
    };
    if !layer.starts_with(usdc::MAGIC) {
        return Ok(());
    }
    match usdc::read_layer(layer, path) {
        Ok(_) => Ok(()),
        Err(Error::Format { message, .. }) => {
            Err(Error::format(path, format!("{name} (the package's root layer): {message}")))
        }
        Err(other) => Err(other),
    }
}

/// The name and bytes of a zip archive's first entry, when it is stored whole (not compressed,
/// encrypted, with its sizes after the data, or zip64).
fn first_entry(bytes: &[u8]) -> std::result::Result<Option<(String, &[u8])>, String> {
    const HEADER: usize = 30;
    let Some(header) = bytes.get(..HEADER).filter(|h| h.starts_with(b"PK\x03\x04")) else {
        return Ok(None);
    };
    let u16_at = |at: usize| u16::from_le_bytes([header[at], header[at + 1]]) as usize;
    let size = u32::from_le_bytes(header[18..22].try_into().unwrap());
    // Flag bit 0: encrypted; bit 3: sizes follow the data.
    if u16_at(6) & 0b1001 != 0 || u16_at(8) != 0 || size == u32::MAX {
        return Ok(None);
    }
    let name_end = HEADER + u16_at(26);
    let start = name_end + u16_at(28);
    let name = bytes.get(HEADER..name_end).map(String::from_utf8_lossy).unwrap_or_default().into_owned();
    match bytes.get(start..).and_then(|rest| rest.get(..size as usize)) {
        Some(entry) => Ok(Some((name, entry))),
        None => Err(format!(
            "the package's first entry ({name:?}, {size} bytes at offset {start}) runs past its end ({} bytes)",
            bytes.len()
        )),
    }
}

/// A stage usd-core flattened into a temporary `.usda`, removed when this is dropped (or when
/// coif is interrupted).
pub struct Flattened {
    _tracked: super::cleanup::Tracked,
    folder: tempfile::TempDir,
}

impl Flattened {
    /// The flattened `.usda`.
    pub fn path(&self) -> PathBuf {
        self.folder.path().join("flattened.usda")
    }
}

/// Flattens any USD stage usd-core can open (with `variants` selected) into a temporary `.usda`.
pub fn flatten(path: &Path, variants: &[String]) -> Result<Flattened> {
    check_root_layer(path)?;
    let folder = tempfile::tempdir().map_err(|e| Error::io(Path::new("temporary folder"), e))?;
    let flattened = Flattened { _tracked: super::cleanup::Tracked::new(folder.path()), folder };
    let flat = flattened.path();
    let variant_args: Vec<OsString> = variants.iter().map(|v| format!("--variant={v}").into()).collect();
    let mut args: Vec<&OsStr> = vec![path.as_os_str(), flat.as_os_str()];
    args.extend(variant_args.iter().map(OsString::as_os_str));
    run(&args, "flatten", path)?;
    Ok(flattened)
}

/// Reads any USD stage usd-core can open, flattened through a temporary `.usda`, with the
/// warnings of reading it (see `usda::ReadOutcome`).
pub fn read(
    path: &Path,
    options: &ImportOptions,
    time: Option<f64>,
    variants: &[String],
) -> Result<(Groom, Vec<String>)> {
    read_flattened(&flatten(path, variants)?, path, options, time)
}

/// Reads `path`'s stage from its flattening at `time` (so that the frames of a package are read
/// from one flattening). Errors and warnings name `path`.
pub fn read_flattened(
    flattened: &Flattened,
    path: &Path,
    options: &ImportOptions,
    time: Option<f64>,
) -> Result<(Groom, Vec<String>)> {
    let flat = flattened.path();
    let file = std::fs::File::open(&flat).map_err(|e| Error::io(&flat, e))?;
    // Errors name the user's file; line numbers refer to the flattened text.
    let rename = |error: Error| match error {
        Error::Format { message, .. } => {
            Error::format(path, format!("{message} (in the stage usd-core flattened)"))
        }
        other => other,
    };
    match usda::read(file, path, options, time).map_err(rename)? {
        usda::ReadOutcome::Groom(groom, warnings) => Ok((groom, warnings)),
        usda::ReadOutcome::NeedsComposition(_) => {
            Err(Error::External("usd-core left composition arcs in a flattened stage".into()))
        }
    }
}

/// Writes `.usdc` or `.usdz`: coif's `.usda`, converted by usd-core, renamed into place.
pub fn write(path: &Path, groom: &Groom) -> Result<()> {
    write_usd(path, |w| usda::write(groom, w).map_err(|e| Error::io(path, e)))
}

/// Writes a USD file of any kind from the `.usda` text `fill` produces: `.usda` directly,
/// `.usdc`/`.usdz` through usd-core. Atomic either way. For animated output:
///
/// ```no_run
/// # use coif::io::{usd_interop, usda::{self, TimeCodes}};
/// # let (groom, path) = (coif::Groom::default(), std::path::Path::new("out.usdc"));
/// # let frames: Vec<Vec<glam::Vec3>> = Vec::new();
/// let times = TimeCodes { start: 1.0, end: frames.len() as f64, per_second: 24.0 };
/// usd_interop::write_usd(path, |w| usda::write_animated(&groom, &frames, times, w, path))?;
/// # Ok::<(), coif::Error>(())
/// ```
pub fn write_usd<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn std::io::Write) -> Result<()>,
{
    let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    if extension == "usda" {
        return atomic::write_atomically(path, fill);
    }
    let dir = match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    };
    // The temporary folder sits beside the output so the final rename is atomic.
    let folder =
        tempfile::Builder::new().prefix(".coif-usd.").tempdir_in(dir).map_err(|e| Error::io(path, e))?;
    let _interrupted = super::cleanup::Tracked::new(folder.path());
    let text = folder.path().join("groom.usda");
    atomic::write_atomically(&text, fill)?;
    let converted = folder.path().join(format!("groom.{extension}"));
    run(&[text.as_os_str(), converted.as_os_str()], "export", path)?;
    let file = std::fs::File::open(&converted).map_err(|e| Error::io(&converted, e))?;
    file.sync_all().map_err(|e| Error::io(&converted, e))?;
    std::fs::rename(&converted, path).map_err(|e| Error::io(path, e))
}
