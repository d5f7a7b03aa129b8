//! Atomic file output: write to a temporary file beside the target, flush and fsync it, then
//! rename it over the target. A reader never sees a half-written file under the output name, and
//! a failed or interrupted write leaves nothing behind (the temporary file is removed on drop).
//! While a file is written, the kernel is asked every [`WRITEBACK_STEP`] bytes to start putting it
//! on disk, so the final fsync waits for the last step, not for the whole file (a groom's `.usda`
//! is hundreds of megabytes, and its fsync alone used to take as long as formatting it).
//! An output that is a symbolic link is written through it, as `cp` and a shell's `>` write:
//! the file it points to is replaced (created, if the link dangles) and the link stays.
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

use tempfile::NamedTempFile;

use crate::error::{Error, Result};

/// Writes `path` atomically with the bytes `fill` produces.
pub fn write_atomically<F>(path: &Path, fill: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    let mut writer = create_beside(path)?;
    fill(&mut writer)?;
    commit(path, writer)
}

/// Bytes written between two requests to start write-back.
const WRITEBACK_STEP: usize = 32 << 20;

/// A temporary file being written: starts the kernel's write-back every [`WRITEBACK_STEP`] bytes.
pub struct TempFile {
    file: NamedTempFile,
    since_writeback: usize,
}

impl Write for TempFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let written = self.file.write(buf)?;
        self.since_writeback += written;
        if self.since_writeback >= WRITEBACK_STEP {
            self.since_writeback = 0;
            start_writeback(self.file.as_file());
        }
        Ok(written)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl Seek for TempFile {
    fn seek(&mut self, position: SeekFrom) -> std::io::Result<u64> {
        self.file.seek(position)
    }
}

/// Asks the kernel to start writing the file's dirty pages to disk, without waiting for them.
/// Advisory: a failure here is left for the fsync in [`commit`] to report.
#[cfg(target_os = "linux")]
fn start_writeback(file: &File) {
    use std::os::fd::AsRawFd;
    // SAFETY: a system call on a descriptor `file` keeps open; offset 0 and length 0 name the
    // whole file, and no memory is passed.
    unsafe {
        libc::sync_file_range(file.as_raw_fd(), 0, 0, libc::SYNC_FILE_RANGE_WRITE);
    }
}

#[cfg(not(target_os = "linux"))]
fn start_writeback(_file: &File) {}

/// A buffered temporary file beside `path`, for writers that stream or seek (Ogawa patches its
/// header at the end). Hand it to [`commit`] when complete; dropping it removes it.
pub fn create_beside(path: &Path) -> Result<BufWriter<TempFile>> {
    let target = through_links(path).map_err(|e| Error::io(path, e))?;
    let dir = folder_of(&target);
    let prefix = temp_prefix(&target);
    let mut builder = temp_names(&prefix);
    // Temporary files are private (0600) by default; an output should get the usual 0666 & !umask.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let temp = builder.tempfile_in(dir).map_err(|e| {
        // A directory that exists but makes no files (procfs answers "not found") is the
        // environment refusing, not a path mistyped: exit 1, not 2.
        let e = match e.kind() {
            std::io::ErrorKind::NotFound if dir.is_dir() => {
                std::io::Error::other(format!("cannot create files in {}: {e}", dir.display()))
            }
            _ => e,
        };
        Error::io(path, e)
    })?;
    // Removed by the signal handler if the process is interrupted before `commit`.
    super::cleanup::track(temp.path());
    Ok(BufWriter::with_capacity(1 << 20, TempFile { file: temp, since_writeback: 0 }))
}

/// Symbolic links a path may pass through before it is taken for a loop (Linux's `MAXSYMLINKS`).
const MAX_LINKS: usize = 40;

/// The file writing `path` replaces: `path` itself, or where the symbolic link(s) at `path`
/// lead, whether that file exists or not (the link's folder and the target's may differ). A
/// loop of links is an error.
pub fn through_links(path: &Path) -> std::io::Result<PathBuf> {
    let mut current = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&current) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let target = std::fs::read_link(&current)?;
                // A relative target is relative to the link's folder.
                current = match current.parent() {
                    Some(folder) if target.is_relative() => folder.join(target),
                    _ => target,
                };
            }
            _ => return Ok(current),
        }
    }
    Err(std::io::Error::other(format!("a loop of symbolic links (more than {MAX_LINKS} in a row)")))
}

/// The folder `path` is in (`.` for a bare file name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// The start of temporary names beside `path`: `.NAME.` (then random, then `.tmp`; batch re-runs
/// clear such files away).
fn temp_prefix(path: &Path) -> String {
    format!(".{}.", path.file_name().map(|n| n.to_string_lossy()).unwrap_or_default())
}

fn temp_names(prefix: &str) -> tempfile::Builder<'_, 'static> {
    let mut builder = tempfile::Builder::new();
    builder.prefix(prefix).suffix(".tmp");
    builder
}

/// Flushes and fsyncs a file from [`create_beside`], then renames it over `path`.
pub fn commit(path: &Path, writer: BufWriter<TempFile>) -> Result<()> {
    commit_together(vec![(path.to_path_buf(), writer)])
}

/// Commits files that only make sense together (an Unreal groom and its `_meshes` file), in
/// order: every one is flushed and fsynced before any is renamed, and when a rename fails the
/// files already put in place are taken back — the file each replaced restored, or removed where
/// there was none. A failure leaves the previous files, never a new one beside an old one.
pub fn commit_together(files: Vec<(PathBuf, BufWriter<TempFile>)>) -> Result<()> {
    let temp_paths: Vec<PathBuf> = files.iter().map(|(_, w)| w.get_ref().file.path().to_path_buf()).collect();
    let result = sync_then_rename(files);
    for temp_path in &temp_paths {
        super::cleanup::untrack(temp_path);
    }
    result
}

fn sync_then_rename(files: Vec<(PathBuf, BufWriter<TempFile>)>) -> Result<()> {
    let mut synced = Vec::with_capacity(files.len());
    for (path, mut writer) in files {
        writer.flush().map_err(|e| Error::io(&path, e))?;
        let path = through_links(&path).map_err(|e| Error::io(&path, e))?;
        let temp = writer.into_inner().map_err(|e| Error::io(&path, e.into_error()))?.file;
        temp.as_file().sync_all().map_err(|e| Error::io(&path, e))?;
        synced.push((path, temp));
    }
    let last = synced.len().saturating_sub(1);
    let mut placed: Vec<(PathBuf, Option<Previous>)> = Vec::new();
    for (k, (path, temp)) in synced.into_iter().enumerate() {
        // Only a file with a later one to fail after it may have to be taken back.
        let previous = if k < last { Previous::keep(&path) } else { None };
        if let Err(e) = temp.persist(&path) {
            if let Some(previous) = previous {
                previous.discard();
            }
            for (placed_path, previous) in placed.into_iter().rev() {
                match previous {
                    Some(previous) => previous.restore(&placed_path),
                    None => {
                        let _ = std::fs::remove_file(&placed_path);
                    }
                }
            }
            return Err(Error::io(&path, e.error));
        }
        placed.push((path, previous));
    }
    placed.into_iter().filter_map(|(_, previous)| previous).for_each(Previous::discard);
    Ok(())
}

/// The file an output replaces, kept under a temporary name beside it (a hard link: no copy)
/// until the files committed with it are in place.
struct Previous(NamedTempFile<()>);

impl Previous {
    /// None when there is no file at `path` or it cannot be linked (then a failure removes the
    /// new file instead of restoring the old one).
    fn keep(path: &Path) -> Option<Previous> {
        std::fs::symlink_metadata(path).ok().filter(|m| !m.is_dir())?;
        let prefix = temp_prefix(path);
        let kept =
            temp_names(&prefix).make_in(folder_of(path), |link| std::fs::hard_link(path, link)).ok()?;
        // Removed by the signal handler if the process is interrupted before it is done with.
        super::cleanup::track(kept.path());
        Some(Previous(kept))
    }

    /// Puts the kept file back at `path`.
    fn restore(self, path: &Path) {
        let link = self.0.path().to_path_buf();
        // Best effort: the commit's own error is what is reported.
        let _ = self.0.persist(path);
        super::cleanup::untrack(&link);
    }

    /// Removes the kept name (the file it named is replaced).
    fn discard(self) {
        let link = self.0.path().to_path_buf();
        drop(self.0);
        super::cleanup::untrack(&link);
    }
}

/// Writes a whole byte buffer atomically.
pub fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomically(path, |w| w.write_all(bytes).map_err(|e| Error::io(path, e)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_write_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.bin");
        let result = write_atomically(&target, |w| {
            w.write_all(b"partial").unwrap();
            Err(Error::Usage("stop half-way".into()))
        });
        assert!(result.is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn successful_write_replaces_the_target() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.bin");
        std::fs::write(&target, b"old").unwrap();
        write_bytes_atomically(&target, b"new").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(unix)]
    #[test]
    fn a_symbolic_link_is_written_through_even_when_it_dangles() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("real")).unwrap();
        let link = dir.path().join("out.bin");
        std::os::unix::fs::symlink("real/target.bin", &link).unwrap();
        for bytes in [&b"new"[..], b"newer"] {
            write_bytes_atomically(&link, bytes).unwrap();
            assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
            assert_eq!(std::fs::read(dir.path().join("real/target.bin")).unwrap(), bytes);
            assert_eq!(std::fs::read_dir(dir.path().join("real")).unwrap().count(), 1);
        }
        let looped = dir.path().join("loop.bin");
        std::os::unix::fs::symlink("loop.bin", &looped).unwrap();
        assert!(through_links(&looped).unwrap_err().to_string().contains("loop"));
    }

    #[cfg(unix)]
    #[test]
    fn outputs_are_readable_by_others_like_any_new_file() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("out.bin");
        write_bytes_atomically(&target, b"x").unwrap();
        let plain = dir.path().join("plain.bin");
        std::fs::write(&plain, b"x").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&target), mode(&plain));
    }
}
