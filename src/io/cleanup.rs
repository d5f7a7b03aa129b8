//! Temporary outputs are removed when the process is interrupted. Atomic writers (`io::atomic`)
//! and the USD interop folder register their temporary paths here while they exist; on SIGINT or
//! SIGTERM [`install_signal_handlers`]'s thread removes them and exits with 128 + the signal
//! (130, 143), so a killed job leaves neither a half-written file nor a `.NAME.XXXX.tmp`.
//!
//! The removal runs on an ordinary thread (signal-hook forwards the signal), not inside a signal
//! handler, so it may lock and allocate.
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Mutex;

static PENDING: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn pending() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    // A panic while holding the lock cannot leave the list inconsistent: use it anyway.
    PENDING.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Remembers a temporary file or folder to remove if the process is interrupted.
pub fn track(path: &Path) {
    pending().push(path.to_path_buf());
}

/// Forgets a path given to [`track`] (it was committed or removed).
pub fn untrack(path: &Path) {
    let mut list = pending();
    if let Some(i) = list.iter().rposition(|p| p == path) {
        list.swap_remove(i);
    }
}

/// A tracked path, untracked when dropped.
pub struct Tracked(PathBuf);

impl Tracked {
    pub fn new(path: &Path) -> Tracked {
        track(path);
        Tracked(path.to_path_buf())
    }
}

impl Drop for Tracked {
    fn drop(&mut self) {
        untrack(&self.0);
    }
}

/// Removes every tracked path (files and folders).
pub fn remove_tracked() {
    let paths: Vec<PathBuf> = pending().drain(..).collect();
    remove(&paths);
}

fn remove(paths: &[PathBuf]) {
    for path in paths {
        if path.is_dir() {
            let _ = std::fs::remove_dir_all(path);
        } else {
            let _ = std::fs::remove_file(path);
        }
    }
}

/// Starts the thread that, on SIGINT or SIGTERM, removes tracked temporary outputs and exits
/// with 130 or 143. Call once, early in `main`.
pub fn install_signal_handlers() -> std::io::Result<()> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])?;
    std::thread::Builder::new().name("coif-signals".into()).spawn(move || {
        if let Some(signal) = signals.forever().next() {
            remove_tracked();
            std::process::exit(128 + signal);
        }
    })?;
    Ok(())
}

/// Puts a child process (a batch task, usd-core) in its own process group (a signal meant for
/// one task does not reach the others or the parent) and has the kernel send it SIGTERM when the
/// parent dies, so no child outlives an interrupted run; a task's own handler then removes its
/// temporary files.
pub fn die_with_parent(command: &mut Command) {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        let parent = std::process::id() as libc::pid_t;
        command.process_group(0);
        // SAFETY: prctl and getppid are async-signal-safe and touch no memory of the parent.
        unsafe {
            command.pre_exec(move || {
                if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                // The parent may have died before the prctl: then nobody will signal us.
                if libc::getppid() != parent {
                    return Err(std::io::Error::other("coif exited before its child started"));
                }
                Ok(())
            });
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = command;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracked_paths_are_removed_and_untracked_ones_kept() {
        let dir = tempfile::tempdir().unwrap();
        let (file, folder, kept) = (dir.path().join("a.tmp"), dir.path().join("f"), dir.path().join("k"));
        std::fs::write(&file, b"x").unwrap();
        std::fs::create_dir(&folder).unwrap();
        std::fs::write(folder.join("inner"), b"x").unwrap();
        std::fs::write(&kept, b"x").unwrap();
        // The global list is shared with other tests' writers: only look at these paths.
        track(&file);
        track(&folder);
        drop(Tracked::new(&kept));
        let mine: Vec<PathBuf> = pending().iter().filter(|p| p.starts_with(dir.path())).cloned().collect();
        assert_eq!(mine, vec![file.clone(), folder.clone()]);
        untrack(&file);
        untrack(&folder);
        remove(&mine);
        assert!(!file.exists() && !folder.exists() && kept.exists());
    }
}
