//! Slurm submission: one sbatch array job whose task `i` runs `coif batch MANIFEST --task i`.
//! Every array task is an independent, idempotent coif invocation, so Slurm's requeueing and a
//! TD's re-submission both just finish what is missing.
use std::path::{Path, PathBuf};
use std::process::Command;

use super::manifest::MAX_TASKS;
use crate::error::{Error, Result};
use crate::io::atomic::write_bytes_atomically;

#[derive(Clone, Debug, Default)]
pub struct SubmitOptions {
    pub partition: Option<String>,
    /// CPUs each task asks for (and the threads coif uses inside it).
    pub cpus_per_task: usize,
    /// Tasks Slurm may run at once (`%N` on the array), if limited.
    pub max_parallel: Option<usize>,
    /// coif's own flags for every task (`--max-memory`, `--max-steps`: `limits::as_flags`).
    pub coif_flags: Vec<String>,
}

/// Where `coif farm submit` keeps the script and the submitted job id, beside the manifest.
pub fn farm_dir(manifest: &Path) -> PathBuf {
    let stem = manifest.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    manifest.parent().unwrap_or(Path::new(".")).join("farm").join(stem)
}

/// CPUs a task may ask for.
pub const MAX_CPUS: usize = 4096;

impl SubmitOptions {
    /// Refuses values sbatch would take as something else: a partition name carrying a line
    /// break would add lines to the script (`--partition $'x\ntouch y'` ran `touch y` on the
    /// farm), `--cpus 0` was silently one.
    fn check(&self) -> Result<()> {
        if let Some(partition) = &self.partition {
            let name_char = |c: char| c.is_ascii_alphanumeric() || "-_.,".contains(c);
            if partition.is_empty() || !partition.chars().all(name_char) {
                return Err(Error::Usage(format!(
                    "--partition {partition:?}: a Slurm partition name is letters, digits, '-', '_' and \
                     '.' (several separated by commas)"
                )));
            }
        }
        if !(1..=MAX_CPUS).contains(&self.cpus_per_task) {
            return Err(Error::Usage(format!("--cpus {} must be 1 to {MAX_CPUS}", self.cpus_per_task)));
        }
        if self.max_parallel == Some(0) {
            return Err(Error::Usage("--max-parallel 0: at least one task must run at a time".into()));
        }
        // Past a manifest's most tasks it limits nothing; past 32 bits sbatch misreads it.
        if let Some(n) = self.max_parallel.filter(|&n| n > MAX_TASKS) {
            return Err(Error::Usage(format!(
                "--max-parallel {n} must be 1 to {MAX_TASKS}, the most tasks a manifest may have"
            )));
        }
        Ok(())
    }
}

/// The sbatch script for a manifest of `tasks` tasks, or the usage error for options or paths
/// it cannot carry (checked before anything is written).
pub fn script(
    coif: &Path,
    manifest: &Path,
    tasks: usize,
    logs: &Path,
    options: &SubmitOptions,
) -> Result<String> {
    options.check()?;
    // `#SBATCH` lines end at a line break, quoted or not.
    for path in [coif, manifest, logs] {
        if path.to_string_lossy().chars().any(char::is_control) {
            return Err(Error::Usage(format!(
                "{:?}: a path with a line break or control character cannot go in a Slurm script",
                path
            )));
        }
    }
    let stem = manifest.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    // The job name is only a label: anything but a plain name character becomes '_'.
    let job_name: String =
        stem.chars().map(|c| if c.is_ascii_alphanumeric() || "-_.".contains(c) { c } else { '_' }).collect();
    let quote = |p: &Path| shell_quote(&p.to_string_lossy());
    let flags: String = options.coif_flags.iter().map(|f| format!(" {}", shell_quote(f))).collect();
    let mut array = format!("0-{}", tasks.saturating_sub(1));
    if let Some(n) = options.max_parallel {
        array.push_str(&format!("%{n}"));
    }
    let mut lines = vec![
        "#!/bin/bash".to_string(),
        format!("#SBATCH --job-name=coif-{job_name}"),
        format!("#SBATCH --array={array}"),
        format!("#SBATCH --cpus-per-task={}", options.cpus_per_task),
        format!(
            "#SBATCH --output={}",
            sbatch_quote(&format!("{}/", logs.to_string_lossy()), "slurm-%A_%a.out")
        ),
    ];
    if let Some(partition) = &options.partition {
        lines.push(format!("#SBATCH --partition={partition}"));
    }
    lines.extend([
        "set -euo pipefail".to_string(),
        format!("export RAYON_NUM_THREADS={}", options.cpus_per_task),
        format!("exec {}{flags} batch {} --task \"$SLURM_ARRAY_TASK_ID\"", quote(coif), quote(manifest)),
        String::new(),
    ]);
    Ok(lines.join("\n"))
}

/// An `#SBATCH` value: `literal` (a path, taken as written) then `pattern` (with Slurm's `%A`-style
/// file-name patterns), in double quotes, which sbatch's directive parser reads as one argument
/// whatever spaces or apostrophes the path has (`\` escapes `"` and `\` there), and with the
/// path's `%` doubled so that Slurm does not expand a folder named `shot%j`.
fn sbatch_quote(literal: &str, pattern: &str) -> String {
    let escaped = literal.replace('\\', "\\\\").replace('"', "\\\"").replace('%', "%%");
    format!("\"{escaped}{pattern}\"")
}

fn shell_quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

/// Writes the script (atomically, executable) and returns its path.
pub fn write_script(dir: &Path, text: &str) -> Result<PathBuf> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let path = dir.join("array.sbatch");
    write_bytes_atomically(&path, text.as_bytes())?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755))
            .map_err(|e| Error::io(&path, e))?;
    }
    Ok(path)
}

/// Runs `sbatch` on the script and returns the job id it reports.
pub fn submit(script: &Path) -> Result<String> {
    let output = Command::new("sbatch").arg("--parsable").arg(script).output().map_err(|e| {
        Error::External(format!("could not run sbatch ({e}); is Slurm installed and on PATH? Use --dry-run to only write the script"))
    })?;
    if !output.status.success() {
        return Err(Error::External(format!(
            "sbatch failed: {}",
            String::from_utf8_lossy(&output.stderr).trim()
        )));
    }
    let text = String::from_utf8_lossy(&output.stdout);
    // --parsable prints "jobid" or "jobid;cluster".
    let id = text.trim().split(';').next().unwrap_or_default().to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(Error::External(format!("sbatch printed no job id: {text:?}")));
    }
    Ok(id)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn script_runs_one_coif_task_per_array_index() {
        let options = SubmitOptions {
            partition: Some("gpu-free".into()),
            cpus_per_task: 2,
            max_parallel: Some(4),
            coif_flags: vec!["--max-steps".into(), "10".into()],
        };
        let text = script(
            Path::new("/opt/coif"),
            Path::new("/jobs/it's.toml"),
            6,
            Path::new("/jobs/logs"),
            &options,
        )
        .unwrap();
        assert!(text.starts_with("#!/bin/bash\n"));
        assert!(text.contains("#SBATCH --array=0-5%4\n"));
        assert!(text.contains("#SBATCH --partition=gpu-free\n"));
        assert!(text.contains("#SBATCH --cpus-per-task=2\n"));
        assert!(
            text.contains(
                r#"exec '/opt/coif' '--max-steps' '10' batch '/jobs/it'\''s.toml' --task "$SLURM_ARRAY_TASK_ID""#
            ),
            "{text}"
        );
        // The job name is a label: a quote in the manifest's name does not reach the script.
        assert!(text.contains("#SBATCH --job-name=coif-it_s\n"), "{text}");
    }

    #[test]
    fn nothing_a_user_gives_adds_lines_to_the_script() {
        let run = |partition: &str, cpus: usize, manifest: &str, logs: &str| {
            let options = SubmitOptions {
                partition: Some(partition.into()),
                cpus_per_task: cpus,
                ..Default::default()
            };
            script(Path::new("/opt/coif"), Path::new(manifest), 2, Path::new(logs), &options)
        };
        assert!(run("a,b-c_d.e", 1, "/jobs/m.toml", "/jobs/logs").is_ok());
        for (partition, cpus, manifest, logs, named) in [
            ("x\ntouch INJECTED", 2, "/jobs/m.toml", "/jobs/logs", "--partition"),
            ("x y", 2, "/jobs/m.toml", "/jobs/logs", "--partition"),
            ("", 2, "/jobs/m.toml", "/jobs/logs", "--partition"),
            ("p", 0, "/jobs/m.toml", "/jobs/logs", "--cpus 0"),
            ("p", 5000, "/jobs/m.toml", "/jobs/logs", "--cpus 5000"),
            ("p", 2, "/jobs/m\ntouch INJECTED.toml", "/jobs/logs", "line break"),
            ("p", 2, "/jobs/m.toml", "/jobs/logs\n#SBATCH --x", "line break"),
        ] {
            let e = run(partition, cpus, manifest, logs).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().contains(named), "{e}");
        }
    }
}
