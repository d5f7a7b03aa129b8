//! Completion records. A task writes its outputs atomically, then a small JSON sidecar with each
//! output's size and SHA-256, a digest of its inputs, and the size and SHA-256 of every layer its
//! groom's stage composed (which only reading the groom tells). A task is complete — and a re-run
//! skips it — only if the sidecar exists, was made from the same inputs, every composed layer
//! still has its recorded bytes, and every output still has the recorded size and checksum. A
//! task killed half-way has no sidecar, so it runs again.
//!
//! Files are recorded relative to the manifest's folder (`manifest::recorded_name`), not as
//! their paths were spelled: a task run as `coif batch m.toml` is complete for
//! `coif farm status /abs/m.toml`, and for a farm node that mounts the project elsewhere.
use std::io::Read;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::manifest::recorded_name;
use crate::error::{Error, Result};
use crate::io::atomic::write_bytes_atomically;

/// A file as it was when the task finished.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FileRecord {
    /// Relative to the manifest's folder (absolute for a file outside it).
    pub path: PathBuf,
    pub size: u64,
    pub sha256: String,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sidecar {
    pub task: String,
    /// SHA-256 over the inputs (groom bytes, effective recipe, coif version).
    pub inputs: String,
    pub outputs: Vec<FileRecord>,
    /// The layers the groom's stage composed besides the groom file itself (its references and
    /// sublayers): a changed cache under an unchanged shot is another input. The groom's bytes
    /// decide which layers it composes, and so do those layers', so the recorded set stays right
    /// until one of them changes.
    #[serde(default)]
    pub layers: Vec<FileRecord>,
}

/// SHA-256 of a file, streamed.
pub fn file_sha256(path: &Path) -> Result<(u64, String)> {
    let mut file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let mut hasher = Sha256::new();
    let mut buffer = vec![0u8; 1 << 20];
    let mut size = 0u64;
    loop {
        let n = file.read(&mut buffer).map_err(|e| Error::io(path, e))?;
        if n == 0 {
            break;
        }
        hasher.update(&buffer[..n]);
        size += n as u64;
    }
    Ok((size, hex(&hasher.finalize())))
}

/// SHA-256 of byte strings, each length-prefixed so that ("ab", "c") and ("a", "bc") differ.
pub fn digest_parts(parts: &[&[u8]]) -> String {
    let mut hasher = Sha256::new();
    for part in parts {
        hasher.update((part.len() as u64).to_le_bytes());
        hasher.update(part);
    }
    hex(&hasher.finalize())
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

impl FileRecord {
    /// The file at `path` as it is now, named relative to the manifest's `folder`.
    fn of(folder: &Path, path: &Path) -> Result<FileRecord> {
        let (size, sha256) = file_sha256(path)?;
        Ok(FileRecord { path: recorded_name(folder, path), size, sha256 })
    }

    /// Whether the file at `path` still has the recorded bytes.
    fn holds_at(&self, path: &Path) -> bool {
        std::fs::metadata(path).is_ok_and(|m| m.len() == self.size)
            && file_sha256(path).is_ok_and(|(_, sha)| sha == self.sha256)
    }
}

impl Sidecar {
    /// Records the current state of `outputs` and of the composed `layers`, named relative to
    /// the manifest's `folder`.
    pub fn record(
        task: &str,
        inputs: String,
        folder: &Path,
        outputs: &[PathBuf],
        layers: &[PathBuf],
    ) -> Result<Sidecar> {
        let of = |path: &PathBuf| FileRecord::of(folder, path);
        let outputs = outputs.iter().map(of).collect::<Result<_>>()?;
        let layers = layers.iter().map(of).collect::<Result<_>>()?;
        Ok(Sidecar { task: task.to_string(), inputs, outputs, layers })
    }

    pub fn write(&self, path: &Path) -> Result<()> {
        let text = serde_json::to_string_pretty(self).expect("sidecars always serialise");
        write_bytes_atomically(path, text.as_bytes())
    }

    pub fn read(path: &Path) -> Option<Sidecar> {
        serde_json::from_slice(&std::fs::read(path).ok()?).ok()
    }

    /// Whether this record proves the task done for these inputs and outputs, the manifest
    /// being in `folder`.
    pub fn proves_complete(&self, inputs: &str, folder: &Path, outputs: &[PathBuf]) -> bool {
        self.inputs == inputs
            && self.layers.iter().all(|record| record.holds_at(&folder.join(&record.path)))
            && self.outputs.len() == outputs.len()
            && self
                .outputs
                .iter()
                .zip(outputs)
                .all(|(record, path)| record.path == recorded_name(folder, path) && record.holds_at(path))
    }
}

/// Removes temporary files an interrupted atomic write left beside `output` (`.<name>.*.tmp`).
pub fn remove_stale_temporaries(output: &Path) {
    let (Some(dir), Some(name)) = (output.parent(), output.file_name()) else { return };
    let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    let prefix = format!(".{}.", name.to_string_lossy());
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        if file.starts_with(&prefix) && file.ends_with(".tmp") {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sidecar_proves_completion_until_an_output_changes() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.bin");
        std::fs::write(&out, b"styled hair").unwrap();
        let outputs = vec![out.clone()];
        let layer = dir.path().join("cache.usda");
        std::fs::write(&layer, b"#usda 1.0\n").unwrap();
        let folder = dir.path();
        let sidecar =
            Sidecar::record("t", "inputs-1".into(), folder, &outputs, std::slice::from_ref(&layer)).unwrap();
        let path = dir.path().join("t.task.json");
        sidecar.write(&path).unwrap();
        let read = Sidecar::read(&path).unwrap();
        assert!(read.proves_complete("inputs-1", folder, &outputs));
        assert!(!read.proves_complete("inputs-2", folder, &outputs), "other inputs must re-run");
        std::fs::write(&layer, b"#usda 1.1\n").unwrap();
        assert!(!read.proves_complete("inputs-1", folder, &outputs), "a changed composed layer must re-run");
        std::fs::write(&layer, b"#usda 1.0\n").unwrap();
        assert!(read.proves_complete("inputs-1", folder, &outputs));
        std::fs::write(&out, b"styled hairX").unwrap();
        assert!(!read.proves_complete("inputs-1", folder, &outputs), "a changed output must re-run");
        std::fs::write(&out, b"styled hairs").unwrap();
        assert!(!read.proves_complete("inputs-1", folder, &outputs), "same size, other bytes must re-run");
    }

    #[test]
    fn digests_separate_their_parts() {
        assert_ne!(digest_parts(&[b"ab", b"c"]), digest_parts(&[b"a", b"bc"]));
        assert_eq!(digest_parts(&[b"x"]), digest_parts(&[b"x"]));
    }

    #[test]
    fn stale_temporaries_are_removed_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("g.usda");
        std::fs::write(dir.path().join(".g.usda.abc123.tmp"), b"half").unwrap();
        std::fs::write(dir.path().join("keep.txt"), b"x").unwrap();
        remove_stale_temporaries(&out);
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, vec![std::ffi::OsString::from("keep.txt")]);
    }
}
