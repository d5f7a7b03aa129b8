//! Input files mapped into memory instead of copied: a multi-gigabyte animated Alembic file is
//! read where it lies, and only the samples a reader asks for are paged in.
use std::fs::File;
use std::ops::Deref;
use std::path::Path;

use crate::error::{Error, Result};

/// A file's bytes, mapped read-only (or held in memory when the file is empty).
pub struct Input {
    map: Option<memmap2::Mmap>,
}

impl Deref for Input {
    type Target = [u8];

    fn deref(&self) -> &[u8] {
        self.map.as_deref().unwrap_or(&[])
    }
}

/// Maps `path` for reading. The file must not be truncated while mapped (writers in coif
/// replace files by renaming, which leaves a mapped file intact).
pub fn map_file(path: &Path) -> Result<Input> {
    check_regular(path)?;
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let len = file.metadata().map_err(|e| Error::io(path, e))?.len();
    if len == 0 {
        return Ok(Input { map: None });
    }
    // SAFETY: the map is read-only; coif never writes files in place, and its readers check every
    // offset against the mapped length, so the only hazard is another program truncating the file
    // during the read, as with any mapped input.
    // Populating the whole map up front costs one pass instead of a page fault per 4 KiB.
    let map = unsafe { memmap2::MmapOptions::new().populate().map(&file) }.map_err(|e| Error::io(path, e))?;
    Ok(Input { map: Some(map) })
}

/// Refuses anything but a regular file (or a link to one) before opening it: a directory, a
/// FIFO (which would block forever) or a device is bad input, not something to read.
pub fn check_regular(path: &Path) -> Result<()> {
    let metadata = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    let kind = metadata.file_type();
    if kind.is_file() {
        return Ok(());
    }
    let what = if kind.is_dir() {
        "a directory"
    } else {
        #[cfg(unix)]
        {
            use std::os::unix::fs::FileTypeExt;
            if kind.is_fifo() {
                "a FIFO"
            } else if kind.is_socket() {
                "a socket"
            } else if kind.is_block_device() || kind.is_char_device() {
                "a device"
            } else {
                "not a regular file"
            }
        }
        #[cfg(not(unix))]
        "not a regular file"
    };
    Err(Error::format(path, format!("{what}, not a regular file")))
}

/// Reads a text file (recipe, manifest, mesh): a regular file, valid UTF-8, else bad input.
pub fn read_text(path: &Path) -> Result<String> {
    check_regular(path)?;
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        Error::format(path, format!("line {line}: not UTF-8 text (invalid byte at offset {at})"))
    })
}

/// Asks the kernel to back a large, not yet touched buffer with huge pages: the copy into it
/// then takes one page fault per 2 MB instead of per 4 kB (a third of a read's system time on a
/// 100 MB groom). Advisory; ignored where unsupported. `buffer` may be spare capacity.
#[cfg(target_os = "linux")]
pub(crate) fn advise_huge_pages<T>(buffer: &mut [T]) {
    const HUGE: usize = 2 << 20;
    let start = (buffer.as_ptr() as usize).next_multiple_of(HUGE);
    let end = (buffer.as_ptr() as usize + std::mem::size_of_val(buffer)) / HUGE * HUGE;
    if end > start {
        // SAFETY: the range lies inside `buffer`, which we borrow mutably; MADV_HUGEPAGE changes
        // how pages are backed, never their contents.
        unsafe {
            libc::madvise(start as *mut libc::c_void, end - start, libc::MADV_HUGEPAGE);
        }
    }
}

#[cfg(not(target_os = "linux"))]
pub(crate) fn advise_huge_pages<T>(_buffer: &mut [T]) {}
