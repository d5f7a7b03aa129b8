//! A batch on one machine: every task runs as its own `coif batch MANIFEST --task I` process,
//! `jobs` at a time, its output in a per-task log — the same invocation a farm array job makes,
//! so a task behaves the same here and there, and one failing or crashing task cannot take the
//! others down. Tasks already complete are skipped without starting a process. Each task gets
//! the batch's `--max-memory` and `--max-steps`.
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde::Serialize;

use super::contact_sheet;
use super::manifest::Manifest;
use super::task;
use crate::error::{Error, Result};

#[derive(Clone, Debug, Serialize)]
pub struct TaskReport {
    pub index: usize,
    pub name: String,
    /// "done", "skipped" or "failed".
    pub status: &'static str,
    pub exit_code: Option<i32>,
    pub seconds: f64,
    pub log: PathBuf,
}

#[derive(Clone, Debug, Serialize)]
pub struct BatchReport {
    pub tasks: Vec<TaskReport>,
    pub done: usize,
    pub skipped: usize,
    pub failed: usize,
    pub seconds: f64,
    pub contact_sheet: Option<PathBuf>,
    /// Why the contact sheet could not be made, when it could not.
    pub contact_sheet_error: Option<String>,
}

impl BatchReport {
    /// The exit code for the whole batch: 0 if every task succeeded, else 2 when every failure
    /// was bad input, 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        let failures: Vec<i32> =
            self.tasks.iter().filter(|t| t.status == "failed").map(|t| t.exit_code.unwrap_or(1)).collect();
        match failures.as_slice() {
            [] => 0,
            codes if codes.iter().all(|&c| c == 2) => 2,
            _ => 1,
        }
    }
}

/// Refuses `--jobs 0` (as cargo does), which was run as one job at a time without a word: a
/// farm script's `--jobs $NPROC` with an empty variable should fail, not crawl.
pub fn check_jobs(jobs: usize) -> Result<()> {
    if jobs == 0 {
        return Err(Error::Usage("--jobs 0: at least one task must run at a time".into()));
    }
    Ok(())
}

/// Runs every task of the manifest with `coif` (this executable) as child processes.
pub fn run(manifest: &Manifest, coif: &Path, jobs: usize) -> Result<BatchReport> {
    let start = Instant::now();
    check_jobs(jobs)?;
    task::check_overrides(manifest)?;
    // Folders made before any task runs: a sheet's missing folder found after hours of tasks
    // failed the batch then.
    let sheet_folder = manifest.contact_sheet.as_deref().and_then(Path::parent);
    for dir in std::iter::once(manifest.logs.as_path()).chain(sheet_folder) {
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads_per_task = (cores / jobs).max(1);

    let mut reports: Vec<Option<TaskReport>> = vec![None; manifest.tasks.len()];
    let mut running: Vec<(usize, Child, Instant)> = Vec::new();
    let mut queue = manifest.tasks.iter().map(|t| t.index).collect::<Vec<_>>().into_iter();
    let log_of = |index: usize| manifest.logs.join(format!("{}.log", manifest.tasks[index].name));
    loop {
        while running.len() < jobs {
            let Some(index) = queue.next() else { break };
            let task = &manifest.tasks[index];
            if task::is_complete(task) {
                reports[index] = Some(TaskReport {
                    index,
                    name: task.name.clone(),
                    status: "skipped",
                    exit_code: Some(0),
                    seconds: 0.0,
                    log: log_of(index),
                });
                continue;
            }
            let log_path = log_of(index);
            let log = std::fs::File::create(&log_path).map_err(|e| Error::io(&log_path, e))?;
            let err = log.try_clone().map_err(|e| Error::io(&log_path, e))?;
            let mut command = Command::new(coif);
            crate::io::cleanup::die_with_parent(&mut command);
            let child = command
                .args(crate::limits::as_flags())
                .arg("batch")
                .arg(&manifest.path)
                .arg("--task")
                .arg(index.to_string())
                .env("RAYON_NUM_THREADS", threads_per_task.to_string())
                .stdin(Stdio::null())
                .stdout(log)
                .stderr(err)
                .spawn()
                .map_err(|e| Error::External(format!("could not start {}: {e}", coif.display())))?;
            running.push((index, child, Instant::now()));
        }
        if running.is_empty() {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
        let mut k = 0;
        while k < running.len() {
            let status =
                running[k].1.try_wait().map_err(|e| Error::External(format!("waiting for a task: {e}")))?;
            match status {
                None => k += 1,
                Some(status) => {
                    let (index, _, started) = running.swap_remove(k);
                    reports[index] = Some(TaskReport {
                        index,
                        name: manifest.tasks[index].name.clone(),
                        status: if status.success() { "done" } else { "failed" },
                        // Killed by a signal: no code, which counts as a failure of kind 1.
                        exit_code: status.code(),
                        seconds: started.elapsed().as_secs_f64(),
                        log: log_of(index),
                    });
                }
            }
        }
    }
    let tasks: Vec<TaskReport> = reports.into_iter().map(|r| r.expect("every task reports")).collect();
    let count = |status: &str| tasks.iter().filter(|t| t.status == status).count();
    Ok(BatchReport {
        done: count("done"),
        skipped: count("skipped"),
        failed: count("failed"),
        seconds: start.elapsed().as_secs_f64(),
        contact_sheet: None,
        contact_sheet_error: None,
        tasks,
    })
}

/// Assembles the manifest's contact sheet after a batch in which no task failed, and puts where
/// it went, or why it failed, in the report (which is printed either way).
pub fn make_contact_sheet(manifest: &Manifest, report: &mut BatchReport) -> Result<()> {
    let Some(sheet) = &manifest.contact_sheet else { return Ok(()) };
    if report.failed > 0 {
        return Ok(());
    }
    match assemble_sheet(manifest, sheet) {
        Ok(path) => {
            report.contact_sheet = Some(path);
            Ok(())
        }
        Err(e) => {
            report.contact_sheet_error = Some(e.to_string());
            Err(e)
        }
    }
}

/// The labelled grid of every task's preview (parameter values under each tile).
fn assemble_sheet(manifest: &Manifest, sheet: &Path) -> Result<PathBuf> {
    let tiles: Vec<(PathBuf, Vec<String>)> = manifest
        .tasks
        .iter()
        .filter_map(|t| {
            let labels =
                if t.wedge_values.is_empty() { vec![t.name.clone()] } else { t.wedge_values.clone() };
            t.preview.clone().map(|p| (p, labels))
        })
        .collect();
    contact_sheet::assemble(&tiles, sheet)?;
    Ok(sheet.to_path_buf())
}
