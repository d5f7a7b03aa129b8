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
