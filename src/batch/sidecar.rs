//! Completion records. A task writes its outputs atomically, then a small JSON sidecar with each
//! output's size and SHA-256 and a digest of its inputs. A task is complete — and a re-run skips
//! it — only if the sidecar exists, was made from the same inputs, and every output still has
//! the recorded size and checksum. A task killed half-way has no sidecar, so it runs again.
use std::io::Read;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::error::{Error, Result};
use crate::io::atomic::write_bytes_atomically;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct OutputRecord {
    pub path: PathBuf,
    pub size: u64,
    pub sha256: String,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sidecar {
    pub task: String,
    /// SHA-256 over the inputs (groom bytes, effective recipe, coif version).
    pub inputs: String,
    pub outputs: Vec<OutputRecord>,
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

impl Sidecar {
    /// Records the current state of `outputs`.
    pub fn record(task: &str, inputs: String, outputs: &[PathBuf]) -> Result<Sidecar> {
        let outputs = outputs
            .iter()
            .map(|path| {
                let (size, sha256) = file_sha256(path)?;
                Ok(OutputRecord { path: path.clone(), size, sha256 })
            })
            .collect::<Result<_>>()?;
        Ok(Sidecar { task: task.to_string(), inputs, outputs })
    }

    pub fn write(&self, path: &Path) -> Result<()> {
        let text = serde_json::to_string_pretty(self).expect("sidecars always serialise");
        write_bytes_atomically(path, text.as_bytes())
    }

    pub fn read(path: &Path) -> Option<Sidecar> {
        serde_json::from_slice(&std::fs::read(path).ok()?).ok()
    }

    /// Whether this record proves the task done for these inputs and outputs.
    pub fn proves_complete(&self, inputs: &str, outputs: &[PathBuf]) -> bool {
        self.inputs == inputs
            && self.outputs.len() == outputs.len()
            && self.outputs.iter().zip(outputs).all(|(record, path)| {
                &record.path == path
                    && std::fs::metadata(path).is_ok_and(|m| m.len() == record.size)
                    && file_sha256(path).is_ok_and(|(_, sha)| sha == record.sha256)
            })
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
        let sidecar = Sidecar::record("t", "inputs-1".into(), &outputs).unwrap();
        let path = dir.path().join("t.task.json");
        sidecar.write(&path).unwrap();
        let read = Sidecar::read(&path).unwrap();
        assert!(read.proves_complete("inputs-1", &outputs));
        assert!(!read.proves_complete("inputs-2", &outputs), "other inputs must re-run");
        std::fs::write(&out, b"styled hairX").unwrap();
        assert!(!read.proves_complete("inputs-1", &outputs), "a changed output must re-run");
        std::fs::write(&out, b"styled hairs").unwrap();
        assert!(!read.proves_complete("inputs-1", &outputs), "same size, other bytes must re-run");
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
