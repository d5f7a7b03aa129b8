//! Running one task: the effective recipe (file plus overrides), styling, outputs written
//! atomically, an optional preview, and last the completion sidecar. A task whose sidecar proves
//! its outputs complete for the same inputs is skipped, so re-running a batch resumes it and a
//! task killed half-way (no sidecar yet) simply runs again.
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::manifest::{apply_override, Manifest, Task};
use super::sidecar::{digest_parts, remove_stale_temporaries, Sidecar};
use crate::error::{Error, Result};
use crate::style::{recipe, style, StyleOptions};

/// What running a task did.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "lowercase", tag = "status")]
pub enum Outcome {
    /// Outputs were already complete for these inputs.
    Skipped,
    Done {
        seconds: f64,
    },
}

/// The sidecar beside a task's first output (or its preview).
pub fn sidecar_path(task: &Task) -> PathBuf {
    let first =
        task.outputs.first().or(task.preview.as_ref()).expect("manifests reject tasks without outputs");
    first.parent().unwrap_or(Path::new(".")).join(format!("{}.task.json", task.name))
}

fn all_outputs(task: &Task) -> Vec<PathBuf> {
    task.outputs.iter().chain(task.preview.iter()).cloned().collect()
}

/// The recipe text with the task's overrides applied, and its digest with the bytes of the groom
/// and of every mesh the recipe loads.
fn effective_inputs(task: &Task) -> Result<(String, String)> {
    let effective = effective_recipe(task, crate::io::input::read_text(&task.recipe)?)?;
    crate::io::input::check_regular(&task.groom)?;
    let groom = std::fs::read(&task.groom).map_err(|e| Error::io(&task.groom, e))?;
    let directory = task.recipe.parent().unwrap_or(Path::new("."));
    // A recipe or mesh that cannot be read adds nothing here: the run itself reports it.
    let value: Option<toml::Value> = toml::from_str(&effective).ok();
    let meshes: Vec<Vec<u8>> = value
        .iter()
        .flat_map(mesh_paths)
        .map(|path| std::fs::read(directory.join(path)).unwrap_or_default())
        .collect();
    // How the groom is read is part of the input: another variant or frame is another groom.
    // Requiring convergence decides whether a finished run counts as complete.
    let reading = format!("{:?} {:?} {}", task.import, task.variants, task.require_converged);
    let mut parts: Vec<&[u8]> =
        vec![&groom, effective.as_bytes(), reading.as_bytes(), env!("CARGO_PKG_VERSION").as_bytes()];
    parts.extend(meshes.iter().map(Vec::as_slice));
    let digest = digest_parts(&parts);
    Ok((effective, digest))
}

/// The recipe `text` with the task's overrides applied.
fn effective_recipe(task: &Task, text: String) -> Result<String> {
    if task.overrides.is_empty() {
        return Ok(text);
    }
    let mut value: toml::Value =
        toml::from_str(&text).map_err(|e| Error::format(&task.recipe, e.message()))?;
    for (key, override_value) in &task.overrides {
        apply_override(&mut value, key, override_value.clone())
            .map_err(|m| Error::format(&task.recipe, m))?;
    }
    Ok(toml::to_string(&value).expect("TOML values serialise"))
}

/// The `path`s of a recipe's mesh obstacles.
fn mesh_paths(recipe: &toml::Value) -> impl Iterator<Item = &str> {
    let obstacles = recipe.get("obstacles").and_then(toml::Value::as_array);
    obstacles
        .into_iter()
        .flatten()
        .filter(|o| o.get("shape").and_then(toml::Value::as_str) == Some("mesh"))
        .filter_map(|o| o.get("path").and_then(toml::Value::as_str))
}

/// Checks every task's overrides against its recipe (keys, numbers and rules; not its meshes),
/// so that a bad wedge value is found before any task runs. A recipe that is fine alone but not
/// with a task's overrides is the manifest's error, named at the task's line with the overrides;
/// the recipe's message then has no line (it would be one of the rewritten text). A recipe that
/// fails alone is left to its tasks, which report it (as a missing groom is). Each recipe is read
/// and checked once, however many tasks a wedge makes of it.
pub fn check_overrides(manifest: &Manifest) -> Result<()> {
    let mut recipes: HashMap<&Path, Option<String>> = HashMap::new();
    for task in manifest.tasks.iter().filter(|t| !t.overrides.is_empty()) {
        let original = recipes.entry(&task.recipe).or_insert_with(|| {
            let text = crate::io::input::read_text(&task.recipe).ok()?;
            recipe::parse_unbaked(&text, &task.recipe).is_ok().then_some(text)
        });
        let Some(original) = original else { continue };
        let in_manifest = |e| with_overrides(task, &manifest.path, e);
        let effective = effective_recipe(task, original.clone()).map_err(in_manifest)?;
        recipe::parse_unbaked(&effective, &task.recipe).map_err(in_manifest)?;
    }
    Ok(())
}

/// `error` from the task's recipe under its overrides, as the manifest's error.
fn with_overrides(task: &Task, manifest: &Path, error: Error) -> Error {
    let Error::Format { path, message } = &error else { return error };
    if *path != task.recipe {
        return error;
    }
    let overrides: Vec<String> = task.overrides.iter().map(|(k, v)| format!("{k:?} = {v}")).collect();
    // "line 3, column 2: …" of the rewritten text would point into the wrong file.
    let message = match message.split_once(": ") {
        Some((place, rest)) if place.starts_with("line ") => rest,
        _ => message.as_str(),
    };
    Error::format(
        manifest,
        format!(
            "line {}: task '{}': with {} the recipe {} is refused: {message}",
            task.line,
            task.name,
            overrides.join(", "),
            task.recipe.display()
        ),
    )
}

/// A task's outputs against every file it reads: its recipe, its groom and the layers the
/// groom's stage composes (references, sublayers), which the manifest's own check cannot see:
/// writing over one would change what the task reads, for its re-run and for every task
/// reading that file.
fn refuse_writing_what_it_reads(task: &Task, files: &[PathBuf]) -> Result<()> {
    let layer = format!("a layer its groom {} composes", task.groom.display());
    let mut read: Vec<(String, &Path)> = files
        .iter()
        .enumerate()
        .map(|(i, f)| (if i == 0 { "its groom".to_string() } else { layer.clone() }, f.as_path()))
        .collect();
    read.push(("its recipe".to_string(), &task.recipe));
    let outputs = all_outputs(task);
    let outputs: Vec<&Path> = outputs.iter().map(PathBuf::as_path).collect();
    crate::io::refuse_writing_inputs(&outputs, &read)
        .map_err(|e| Error::Usage(format!("task '{}': {e}", task.name)))
}

/// Whether the task's outputs are complete for its current inputs.
pub fn is_complete(task: &Task) -> bool {
    let Ok((_, inputs)) = effective_inputs(task) else { return false };
    Sidecar::read(&sidecar_path(task))
        .is_some_and(|s| s.proves_complete(&inputs, &task.folder, &all_outputs(task)))
}

/// Runs a task unless its outputs are already complete.
pub fn run(task: &Task) -> Result<Outcome> {
    let start = Instant::now();
    let (effective, inputs) = effective_inputs(task)?;
    let outputs = all_outputs(task);
    let sidecar = sidecar_path(task);
    if Sidecar::read(&sidecar).is_some_and(|s| s.proves_complete(&inputs, &task.folder, &outputs)) {
        return Ok(Outcome::Skipped);
    }
    let recipe = recipe::parse(&effective, &task.recipe)?;
    // A task killed half-way may have left temporaries of any output or of its sidecar.
    remove_stale_temporaries(&sidecar);
    for output in &outputs {
        remove_stale_temporaries(output);
        if let Some(dir) = output.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
    }
    let selection = crate::io::usda::Selection { time: None, variants: task.variants.clone() };
    let loaded = crate::io::read_groom_selected(&task.groom, &task.import, &selection)?;
    refuse_writing_what_it_reads(task, &loaded.files)?;
    let groom = &loaded.groom;
    // A task's stderr is its log (logs/NAME.log, the scheduler's output file): plain lines.
    let options = StyleOptions { progress: crate::progress::ProgressMode::Log, ..Default::default() };
    let styled = style(groom, &recipe, &options).map_err(|e| {
        e.in_file(&task.groom).read_at_units("the manifest's units =", task.import.meters_per_unit)
    })?;
    // The log says what the report would: a farm's artist reads it, not the JSON.
    let unsettled = styled.report.unconverged_settle();
    // Required, an unconverged settle is the task's error instead.
    let unsettled_warning = unsettled.as_ref().filter(|_| !task.require_converged);
    for warning in loaded.warnings.iter().chain(&styled.report.warnings).chain(unsettled_warning) {
        eprintln!("coif: warning: {}: {warning}", task.name);
    }
    for output in &task.outputs {
        crate::io::write_groom(output, &styled.groom)?;
    }
    if let Some(preview) = &task.preview {
        let settings =
            crate::render::RenderSettings { width: 320, height: 240, spp: 16, ..Default::default() };
        let rendered = crate::render::render(&styled.groom, &settings, &|_, _| {})?;
        rendered.image.write(preview)?;
    }
    // Written, but not complete: a re-run does it again (the scheduler sees the failure).
    if let Some(failure) = unsettled.filter(|_| task.require_converged) {
        return Err(Error::NotConverged(format!("task '{}': {failure}", task.name)));
    }
    Sidecar::record(&task.name, inputs, &task.folder, &outputs, loaded.composed_layers())?.write(&sidecar)?;
    Ok(Outcome::Done { seconds: start.elapsed().as_secs_f64() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn editing_a_mesh_the_recipe_loads_changes_the_inputs_digest() {
        let dir = tempfile::tempdir().unwrap();
        let (groom, recipe, mesh) =
            (dir.path().join("g.hair"), dir.path().join("r.toml"), dir.path().join("m.obj"));
        std::fs::write(&groom, b"groom bytes").unwrap();
        std::fs::write(&recipe, "[[obstacles]]\nname = \"m\"\nshape = \"mesh\"\npath = \"m.obj\"\n").unwrap();
        std::fs::write(&mesh, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let task = Task {
            index: 0,
            name: "t".into(),
            groom,
            recipe,
            overrides: Vec::new(),
            outputs: Vec::new(),
            preview: None,
            import: Default::default(),
            variants: Vec::new(),
            require_converged: false,
            wedge_values: Vec::new(),
            line: 1,
            folder: dir.path().to_path_buf(),
        };
        let before = effective_inputs(&task).unwrap().1;
        assert_eq!(before, effective_inputs(&task).unwrap().1);
        std::fs::write(&mesh, "v 0 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let after = effective_inputs(&task).unwrap().1;
        assert_ne!(before, after);
        // Another variant or frame of the same file is another groom.
        let other_variant = Task { variants: vec!["length=long".into()], ..task.clone() };
        let other_frame = Task {
            import: crate::io::ImportOptions { frame: Some(12.0), ..Default::default() },
            ..task.clone()
        };
        let required = Task { require_converged: true, ..task.clone() };
        for other in [other_variant, other_frame, required] {
            assert_ne!(after, effective_inputs(&other).unwrap().1);
        }
    }
}
