//! Job manifests: the grooms, recipes and parameter wedges a TD wants run, expanded into an
//! ordered list of independent tasks. Task `i` of a manifest is always the same work, so a farm
//! array job can hand out indices and a re-run can resume.
//!
//! ```toml
//! [defaults]
//! groom = "grooms/seed_100x48cm.hair"
//! recipe = "grooms/recipes/perm_scene3.toml"
//! outputs = ["out/{name}/groom.usda"]
//! preview = "out/{name}/preview.png"      # optional
//! # optional, as the CLI's --units, --up, --frame and --variant:
//! # units = 0.01, up = "z", frame = 1001, variants = ["length=long"]
//! # optional, as `style --require-converged`: the task fails if a settle stage does not converge
//! # require_converged = true
//!
//! [[tasks]]
//! name = "perm"
//!
//! [[wedges]]
//! name = "rods"
//! parameters = { "rods.0.radius" = [0.008, 0.012], "stages.1.break.disulfide" = [0.1, 0.2, 0.3] }
//! ```
//! Paths are relative to the manifest's folder. Templates: `{name}`, `{index}`, `{groom}` and
//! `{recipe}` (file stems); any other `{` is refused.
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use toml::Spanned;

use crate::error::{Error, Result};
use crate::io::{ImportOptions, UpAxis};
use crate::validate::{number, FRAME, UNITS};

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestFile {
    #[serde(default)]
    defaults: TaskSpec,
    #[serde(default)]
    tasks: Vec<Spanned<TaskSpec>>,
    #[serde(default)]
    wedges: Vec<Spanned<WedgeSpec>>,
    /// Where per-task logs go (default `logs/` beside the manifest).
    logs: Option<String>,
    /// A labelled grid of the wedges' previews, assembled after a local batch.
    contact_sheet: Option<Spanned<String>>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct TaskSpec {
    name: Option<String>,
    groom: Option<String>,
    recipe: Option<String>,
    outputs: Option<Vec<String>>,
    preview: Option<String>,
    /// Metres per unit of the groom file, for formats that do not say (`--units`).
    units: Option<f32>,
    /// Up axis of the groom file, for formats that do not say (`--up`).
    up: Option<UpAxis>,
    /// Animated groom: the frame to read (`--frame`).
    frame: Option<f64>,
    /// USD groom: variants to select, `SET=NAME` or `/Prim:SET=NAME` (`--variant`).
    variants: Option<Vec<String>>,
    /// The task fails (exit 1, outputs written, not recorded as complete) when a settle stage
    /// does not reach its tolerance (`style --require-converged`).
    require_converged: Option<bool>,
    /// Recipe values replaced for this task: dotted paths into the recipe (`rods.0.radius`).
    #[serde(default)]
    overrides: BTreeMap<String, toml::Value>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct WedgeSpec {
    name: String,
    #[serde(flatten)]
    task: TaskSpec,
    /// Each recipe path with the values to sweep; tasks are the cartesian product.
    parameters: BTreeMap<String, Vec<toml::Value>>,
}

/// One unit of work: a groom styled by a recipe (with overrides), written to outputs.
#[derive(Clone, Debug, PartialEq)]
pub struct Task {
    pub index: usize,
    pub name: String,
    pub groom: PathBuf,
    pub recipe: PathBuf,
    pub overrides: Vec<(String, toml::Value)>,
    pub outputs: Vec<PathBuf>,
    pub preview: Option<PathBuf>,
    /// How the groom file is read (units, up axis, frame) and the USD variants selected.
    pub import: ImportOptions,
    pub variants: Vec<String>,
    /// Fail when a settle stage does not reach its tolerance.
    pub require_converged: bool,
    /// "key = value" for each swept parameter (labels on the contact sheet).
    pub wedge_values: Vec<String>,
    /// The manifest line the task (or its wedge) starts on.
    pub line: usize,
    /// The manifest's folder, as the manifest path was given: sidecars record files relative
    /// to it (see `recorded_name`).
    pub folder: PathBuf,
}

#[derive(Clone, Debug)]
pub struct Manifest {
    pub path: PathBuf,
    pub tasks: Vec<Task>,
    pub logs: PathBuf,
    pub contact_sheet: Option<PathBuf>,
}

/// Reads a manifest and expands its tasks and wedges.
pub fn load(path: &Path) -> Result<Manifest> {
    parse(&crate::io::input::read_text(path)?, path)
}

pub fn parse(text: &str, path: &Path) -> Result<Manifest> {
    let bad = |message: String| Error::format(path, message);
    let file: ManifestFile = toml::from_str(text).map_err(|e| bad(toml_error(&e, text)))?;
    let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
    let resolve = |p: &str| if Path::new(p).is_absolute() { PathBuf::from(p) } else { base.join(p) };

    let mut tasks = Vec::new();
    let mut add = |spec: &TaskSpec,
                   name: String,
                   overrides: Vec<(String, toml::Value)>,
                   wedge_values: Vec<String>,
                   line: usize|
     -> Result<()> {
        check_name(&name).map_err(|m| bad(format!("line {line}: {m}")))?;
        let pick = |field: &Option<String>, default: &Option<String>, what: &str| {
            field.clone().or_else(|| default.clone()).ok_or_else(|| {
                bad(format!("line {line}: task '{name}' has no {what} (and [defaults] gives none)"))
            })
        };
        let groom = pick(&spec.groom, &file.defaults.groom, "groom")?;
        let recipe = pick(&spec.recipe, &file.defaults.recipe, "recipe")?;
        let outputs = spec.outputs.clone().or_else(|| file.defaults.outputs.clone()).unwrap_or_default();
        let preview = spec.preview.clone().or_else(|| file.defaults.preview.clone());
        let defaults = &file.defaults;
        let import = ImportOptions {
            meters_per_unit: spec.units.or(defaults.units),
            up_axis: spec.up.or(defaults.up),
            frame: spec.frame.or(defaults.frame),
        };
        let checks =
            [("units", import.meters_per_unit.map(f64::from), UNITS), ("frame", import.frame, FRAME)];
        for (key, value, range) in checks {
            if let Some(value) = value {
                number(key, value, range).map_err(|m| bad(format!("line {line}: task '{name}': {m}")))?;
            }
        }
        let variants = spec.variants.clone().or_else(|| defaults.variants.clone()).unwrap_or_default();
        if outputs.is_empty() && preview.is_none() {
            return Err(bad(format!("line {line}: task '{name}' writes nothing: give outputs or a preview")));
        }
        let index = tasks.len();
        let stem =
            |p: &str| Path::new(p).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        // In the order of PLACEHOLDERS.
        let values = [name.clone(), index.to_string(), stem(&groom), stem(&recipe)];
        let fill = |template: &str| {
            PLACEHOLDERS
                .iter()
                .zip(&values)
                .fold(template.to_string(), |text, (key, value)| text.replace(&format!("{{{key}}}"), value))
        };
        for template in outputs.iter().chain(preview.iter()) {
            check_placeholders(template).map_err(|m| bad(format!("line {line}: task '{name}': {m}")))?;
            if Path::new(&fill(template)).components().any(|c| c == std::path::Component::ParentDir) {
                return Err(bad(format!(
                    "line {line}: task '{name}': output '{}' climbs out of its folder with '..'",
                    fill(template)
                )));
            }
        }
        // Formats are known now: a typo found after styling left the task's other outputs.
        let at = |e: Error| bad(format!("line {line}: task '{name}': {e}"));
        for output in &outputs {
            crate::io::Format::from_extension(Path::new(&fill(output))).map_err(at)?;
        }
        if let Some(preview) = &preview {
            crate::render::image::ImageFormat::from_path(Path::new(&fill(preview))).map_err(at)?;
        }
        let mut all_overrides: Vec<(String, toml::Value)> =
            file.defaults.overrides.clone().into_iter().collect();
        all_overrides.extend(spec.overrides.clone());
        all_overrides.extend(overrides);
        tasks.push(Task {
            index,
            name: name.clone(),
            groom: resolve(&groom),
            recipe: resolve(&recipe),
            overrides: all_overrides,
            outputs: outputs.iter().map(|o| resolve(&fill(o))).collect(),
            preview: preview.map(|p| resolve(&fill(&p))),
            import,
            variants,
            require_converged: spec.require_converged.or(defaults.require_converged).unwrap_or(false),
            wedge_values,
            line,
            folder: base.clone(),
        });
        Ok(())
    };

    for spanned in &file.tasks {
        let line = line_of(text, spanned.span().start);
        let spec = spanned.get_ref();
        let name = spec.name.clone().ok_or_else(|| bad(format!("line {line}: a task needs a name")))?;
        add(spec, name, Vec::new(), Vec::new(), line)?;
    }
    let mut planned = file.tasks.len();
    for spanned in &file.wedges {
        let line = line_of(text, spanned.span().start);
        let wedge = spanned.get_ref();
        check_name(&wedge.name).map_err(|m| bad(format!("line {line}: wedge {m}")))?;
        if wedge.task.name.is_some() {
            return Err(bad(format!(
                "line {line}: a wedge's tasks are named after the wedge; drop `name` from its task fields"
            )));
        }
        if wedge.parameters.is_empty() || wedge.parameters.values().any(|v| v.is_empty()) {
            return Err(bad(format!(
                "line {line}: wedge '{}' needs parameters, each with at least one value",
                wedge.name
            )));
        }
        // Counted with overflow checks: 2^64 combinations must not wrap to a small number.
        let combinations = wedge
            .parameters
            .values()
            .try_fold(1usize, |n, values| n.checked_mul(values.len()).filter(|&n| n <= MAX_TASKS));
        let Some(combinations) = combinations.filter(|&n| planned + n <= MAX_TASKS) else {
            let exact = wedge.parameters.values().map(|v| v.len() as f64).product::<f64>();
            return Err(bad(format!(
                "line {line}: wedge '{}' expands to {exact:.0} tasks; a manifest may have at most {MAX_TASKS}",
                wedge.name
            )));
        };
        planned += combinations;
        for combination in 0..combinations {
            // Mixed-radix counting over the parameters, last parameter fastest.
            let mut rest = combination;
            let mut chosen = Vec::new();
            for (key, values) in wedge.parameters.iter().rev() {
                chosen.push((key.clone(), values[rest % values.len()].clone()));
                rest /= values.len();
            }
            chosen.reverse();
            let labels = chosen.iter().map(|(k, v)| format!("{k} = {v}")).collect();
            let name = format!("{}-{:03}", wedge.name, combination);
            add(&wedge.task, name, chosen, labels, line)?;
        }
    }
    if tasks.is_empty() {
        return Err(bad("the manifest has no [[tasks]] or [[wedges]]".into()));
    }
    let mut names: Vec<&str> = tasks.iter().map(|t| t.name.as_str()).collect();
    names.sort_unstable();
    if let Some(pair) = names.windows(2).find(|w| w[0] == w[1]) {
        return Err(bad(format!("two tasks are named '{}'", pair[0])));
    }
    // Files are compared by identity, not by spelling: `./a.usda`, `a.usda`, its absolute path
    // and a path through a symbolic link name one file.
    let mut outputs: Vec<(PathBuf, &PathBuf, &str)> = tasks
        .iter()
        .flat_map(|t| t.outputs.iter().chain(t.preview.iter()).map(|p| (p, t.name.as_str())))
        .map(|(p, task)| (file_identity(p), p, task))
        .collect();
    outputs.sort_unstable();
    if let Some(pair) = outputs.windows(2).find(|w| w[0].0 == w[1].0) {
        let ((identity, first, a), (_, second, b)) = (&pair[0], &pair[1]);
        let spelled = if first == second {
            first.display().to_string()
        } else {
            format!("{} (as {} and {})", identity.display(), first.display(), second.display())
        };
        return Err(bad(if a == b {
            format!("task '{a}' writes {spelled} twice: give each output its own file")
        } else {
            format!("two tasks write {spelled}; put {{name}} in the output templates")
        }));
    }
    // A task writing over a groom or recipe (its own or another's) would change the inputs the
    // next run reads: a re-run would style its own output again, and tasks on other nodes would
    // read a file while it is replaced.
    let inputs: std::collections::HashMap<PathBuf, (&str, &str)> = tasks
        .iter()
        .flat_map(|t| [(&t.groom, (t.name.as_str(), "groom")), (&t.recipe, (t.name.as_str(), "recipe"))])
        .map(|(path, owner)| (file_identity(path), owner))
        .collect();
    for task in &tasks {
        for output in task.outputs.iter().chain(task.preview.iter()) {
            if let Some((owner, what)) = inputs.get(&file_identity(output)) {
                return Err(bad(format!(
                    "task '{}' writes {}, task '{owner}''s {what}: a batch does not overwrite its inputs \
                     (a re-run would style its own output)",
                    task.name,
                    output.display()
                )));
            }
        }
    }
    if let Some(spanned) = &file.contact_sheet {
        let line = line_of(text, spanned.span().start);
        let sheet = spanned.get_ref();
        // The sheet is a PNG of the previews, read back as PNGs.
        let previews: Vec<&PathBuf> = tasks.iter().filter_map(|t| t.preview.as_ref()).collect();
        let png = |p: &Path| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
        // Written after the tasks, the sheet would replace a task's file: that task's sidecar
        // would never hold again, so every re-run would style it and replace it again.
        let sheet_path = resolve(sheet);
        let identity = file_identity(&sheet_path);
        let taken = outputs.iter().find(|(written, ..)| *written == identity);
        let problem = if !png(Path::new(sheet)) {
            Some(format!("contact_sheet {sheet}: a contact sheet is written as .png"))
        } else if let Some((_, path, task)) = taken {
            let spelled =
                if **path == sheet_path { String::new() } else { format!(" (as {})", path.display()) };
            Some(format!(
                "contact_sheet {sheet} is a file task '{task}' writes{spelled}: give the sheet its own file"
            ))
        } else if previews.is_empty() {
            Some("a contact sheet needs at least one task with a preview".to_string())
        } else {
            previews.iter().find(|p| !png(p)).map(|p| {
                format!("contact_sheet: the sheet is made of .png previews, and {} is not one", p.display())
            })
        };
        if let Some(problem) = problem {
            return Err(bad(format!("line {line}: {problem}")));
        }
    }
    Ok(Manifest {
        path: path.to_path_buf(),
        logs: resolve(file.logs.as_deref().unwrap_or("logs")),
        contact_sheet: file.contact_sheet.as_ref().map(|sheet| resolve(sheet.get_ref())),
        tasks,
    })
}

/// The `{…}` names an output or preview template may hold.
const PLACEHOLDERS: [&str; 4] = ["name", "index", "groom", "recipe"];

/// Refuses a template with a `{` that opens no known placeholder: `{foo}` (a typo of `{name}`)
/// was written literally, so every task wrote one folder named `{foo}`.
fn check_placeholders(template: &str) -> std::result::Result<(), String> {
    let mut rest = template;
    while let Some(open) = rest.find('{') {
        let after = &rest[open + 1..];
        let known = after.find('}').map(|close| &after[..close]).filter(|key| PLACEHOLDERS.contains(key));
        let Some(key) = known else {
            let shown = after.find('}').map_or(&rest[open..], |close| &rest[open..open + close + 2]);
            let list: Vec<String> = PLACEHOLDERS.iter().map(|p| format!("{{{p}}}")).collect();
            return Err(format!(
                "output template '{template}' has an unknown placeholder '{shown}'; the known ones are {}",
                list.join(", ")
            ));
        };
        rest = &after[key.len() + 1..];
    }
    Ok(())
}

/// Tasks a manifest may expand to.
pub const MAX_TASKS: usize = 100_000;

/// Task and wedge names become file names (logs, sidecars, `{name}` in outputs): one plain path
/// component, so no name can reach outside the folder it is put in.
fn check_name(name: &str) -> std::result::Result<(), String> {
    let plain = !name.is_empty()
        && name != "."
        && name != ".."
        && !name.contains(['/', '\\', '\0'])
        && !name.chars().any(char::is_control)
        && name.len() <= 200;
    if plain {
        Ok(())
    } else {
        Err(format!(
            "task name {name:?} must be a plain file name (no '/', '\\', '..' or control characters, \
             at most 200 bytes)"
        ))
    }
}

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

fn toml_error(error: &toml::de::Error, text: &str) -> String {
    match error.span() {
        Some(span) => format!("line {}: {}", line_of(text, span.start), error.message().trim()),
        None => error.message().trim().to_string(),
    }
}

/// Replaces the value at a dotted path (`stages.1.break.disulfide`) in a parsed recipe. Tables
/// missing along the way are created (the recipe's own checks then reject unknown keys);
/// array indices must exist.
pub fn apply_override(
    root: &mut toml::Value,
    path: &str,
    value: toml::Value,
) -> std::result::Result<(), String> {
    let keys: Vec<&str> = path.split('.').collect();
    if keys.iter().any(|k| k.is_empty()) {
        return Err(format!(
            "override {path:?}: a dotted path of keys (settings.dt, stages.1.duration), none empty"
        ));
    }
    let (last, parents) = keys.split_last().expect("split always yields a key");
    let mut node = root;
    for (depth, key) in parents.iter().enumerate() {
        node = match node {
            toml::Value::Array(items) => list_entry(items, key, path)?,
            toml::Value::Table(table) => {
                table.entry(key.to_string()).or_insert_with(|| toml::Value::Table(Default::default()))
            }
            _ => return Err(not_a_container(path, &keys[..depth])),
        };
    }
    match node {
        toml::Value::Array(items) => *list_entry(items, last, path)? = value,
        toml::Value::Table(table) => {
            table.insert(last.to_string(), value);
        }
        _ => return Err(not_a_container(path, parents)),
    }
    Ok(())
}

fn list_entry<'a>(
    items: &'a mut [toml::Value],
    key: &str,
    path: &str,
) -> std::result::Result<&'a mut toml::Value, String> {
    let index: usize =
        key.parse().map_err(|_| format!("override '{path}': '{key}' is not an index into a list"))?;
    let len = items.len();
    items
        .get_mut(index)
        .ok_or_else(|| format!("override '{path}': index {index} is past the list's {len} entries"))
}

fn not_a_container(path: &str, keys: &[&str]) -> String {
    format!("override '{path}': '{}' is a value, not a table or list", keys.join("."))
}

/// How a sidecar names a file: its identity relative to the manifest's `folder` (absolute when
/// outside it). The same whether the manifest was given as `m.toml`, `./m.toml` or its absolute
/// path, and on a farm node that mounts the project somewhere else.
pub fn recorded_name(folder: &Path, path: &Path) -> PathBuf {
    let folder = if folder.as_os_str().is_empty() { Path::new(".") } else { folder };
    let file = file_identity(path);
    match file.strip_prefix(file_identity(folder)) {
        Ok(relative) => relative.to_path_buf(),
        Err(_) => file,
    }
}

/// What names a file whatever the spelling of its path: absolute, without `.` and `..`, and
/// through symbolic links where the file or its folder exists (outputs usually do not yet).
fn file_identity(path: &Path) -> PathBuf {
    if let Ok(canonical) = std::fs::canonicalize(path) {
        return canonical;
    }
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut lexical = PathBuf::new();
    for component in absolute.components() {
        match component {
            std::path::Component::CurDir => {}
            std::path::Component::ParentDir => {
                lexical.pop();
            }
            other => lexical.push(other),
        }
    }
    match (lexical.parent().map(std::fs::canonicalize), lexical.file_name()) {
        (Some(Ok(folder)), Some(name)) => folder.join(name),
        _ => lexical,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MANIFEST: &str = r#"
[defaults]
groom = "grooms/a.hair"
recipe = "recipes/perm.toml"
outputs = ["out/{name}/groom.usda", "out/{name}/{groom}.abc"]

[[tasks]]
name = "plain"
overrides = { "settings.seed" = 3 }

[[wedges]]
name = "w"
preview = "out/{name}.png"
parameters = { "rods.0.radius" = [0.008, 0.012], "stages.1.break.disulfide" = [0.1, 0.2, 0.3] }
"#;

    #[test]
    fn wedges_expand_to_the_cartesian_product_in_a_stable_order() {
        let manifest = parse(MANIFEST, Path::new("/jobs/m.toml")).unwrap();
        assert_eq!(manifest.tasks.len(), 1 + 6);
        let plain = &manifest.tasks[0];
        assert_eq!(
            plain.outputs,
            vec![PathBuf::from("/jobs/out/plain/groom.usda"), PathBuf::from("/jobs/out/plain/a.abc")]
        );
        assert_eq!(plain.overrides, vec![("settings.seed".to_string(), toml::Value::Integer(3))]);
        let names: Vec<_> = manifest.tasks.iter().map(|t| t.name.as_str()).collect();
        assert_eq!(names, ["plain", "w-000", "w-001", "w-002", "w-003", "w-004", "w-005"]);
        // Keys sorted: rods.0.radius first (slowest), then the disulfide amount.
        assert_eq!(
            manifest.tasks[2].wedge_values,
            vec!["rods.0.radius = 0.008", "stages.1.break.disulfide = 0.2"]
        );
        assert_eq!(
            manifest.tasks[4].wedge_values,
            vec!["rods.0.radius = 0.012", "stages.1.break.disulfide = 0.1"]
        );
        assert_eq!(manifest.tasks[4].preview, Some(PathBuf::from("/jobs/out/w-003.png")));
        assert_eq!(manifest.logs, PathBuf::from("/jobs/logs"));
    }

    #[test]
    fn manifest_mistakes_are_reported_with_lines() {
        let e = parse(&MANIFEST.replace("name = \"plain\"", "nmae = \"plain\""), Path::new("m.toml"))
            .unwrap_err();
        assert!(e.to_string().contains("line 8"), "{e}");
        let clash = MANIFEST.replace("out/{name}/groom.usda\", \"out/{name}/{groom}.abc", "out/groom.usda");
        let e = parse(&clash, Path::new("m.toml")).unwrap_err();
        assert!(e.to_string().contains("two tasks write"), "{e}");
        let e = parse("[defaults]\n", Path::new("m.toml")).unwrap_err();
        assert!(e.to_string().contains("no [[tasks]]"), "{e}");
    }

    #[test]
    fn overrides_reach_into_tables_and_lists() {
        let mut recipe: toml::Value = toml::from_str(
            "[settings]\ndt = 0.01\n[[rods]]\nname = \"r\"\nradius = 0.01\n[[stages]]\nkind = \"wet\"\n",
        )
        .unwrap();
        apply_override(&mut recipe, "rods.0.radius", toml::Value::Float(0.02)).unwrap();
        apply_override(&mut recipe, "settings.iterations", toml::Value::Integer(8)).unwrap();
        apply_override(&mut recipe, "bonds.ionic", toml::Value::Float(0.4)).unwrap();
        assert_eq!(recipe["rods"][0]["radius"].as_float(), Some(0.02));
        assert_eq!(recipe["settings"]["iterations"].as_integer(), Some(8));
        assert_eq!(recipe["bonds"]["ionic"].as_float(), Some(0.4));
        assert!(apply_override(&mut recipe, "rods.3.radius", toml::Value::Float(1.0))
            .unwrap_err()
            .contains("index 3"));
        assert!(apply_override(&mut recipe, "settings.dt.x", toml::Value::Float(1.0)).is_err());
    }
}
