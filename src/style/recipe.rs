//! Styling recipes: TOML files that describe a perm, a water set, a blow-dry or a bed-head as
//! global settings, obstacles, perm rods and an ordered timeline of stages.
//!
//! Parsing is strict, because a recipe that silently ignores a misspelt key styles the wrong
//! hair on a farm at night: unknown keys, wrong types, impossible values, references to rods or
//! obstacles that do not exist and impossible stage orders are all errors that name the line.
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;
use serde::Deserialize;
use toml::Spanned;

use crate::error::{Error, Result};
use crate::interact::mesh_sdf::{MeshSdf, TriangleMesh};
use crate::interact::water::WaterParams;
use crate::interact::wetness::WetnessParams;

/// A parsed and checked recipe.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Recipe {
    /// The coordinates positions are given in, unless an item says otherwise (see [`Frame`]).
    #[serde(default)]
    pub frame: Frame,
    /// Overrides of the fitted head frame.
    #[serde(default)]
    pub head: HeadSpec,
    #[serde(default)]
    pub settings: Settings,
    #[serde(default)]
    pub bonds: BondInfluences,
    #[serde(default)]
    pub contacts: Contacts,
    #[serde(default)]
    pub wetness: WetnessParams,
    #[serde(default)]
    pub water: Option<WaterSpec>,
    #[serde(default)]
    pub obstacles: Vec<Spanned<Obstacle>>,
    #[serde(default)]
    pub rods: Vec<Spanned<Rod>>,
    /// Simulate only guides and interpolate the other strands (`crate::guides`).
    #[serde(default)]
    pub guides: Option<crate::guides::GuideSpec>,
    pub stages: Vec<Spanned<Stage>>,
}

#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Settings {
    /// Time step, seconds (Table 1: 1/360).
    pub dt: f32,
    /// Solver iterations per step (Table 1: 5).
    pub iterations: u32,
    /// m/s², Y up.
    #[serde(deserialize_with = "crate::validate::three")]
    pub gravity: [f32; 3],
    /// Young's modulus of hair, Pa (bending); coif's rods use physical moduli (XPBD), so the
    /// look does not change with `dt` or `iterations`.
    pub youngs_modulus: f32,
    /// Shear modulus, Pa (twisting).
    pub shear_modulus: f32,
    /// kg/m³.
    pub density: f32,
    /// Cuticle peel rate per metre from the root (Table 1: 0.33 %/cm = 0.33 /m).
    pub cuticle_peel_per_metre: f32,
    /// Resample strands so no segment is longer than this (metres) before styling: curls on a
    /// rod need several vertices per turn. Unset keeps the groom's vertices.
    pub max_segment: Option<f32>,
    /// Velocity damping per second.
    pub damping: f32,
    /// Seed for every random choice the recipe makes (masks, droplet placement).
    pub seed: u64,
    /// Start from a rest shape that holds the groom's shape under gravity (`sim::sag_free`), so
    /// the style is the only change. Off: the groom's shape, or a styled groom's exported
    /// `rest_darboux`, is the rest shape.
    pub sag_free: bool,
    /// `"gauss-seidel"` (default) or `"direct"`: how each iteration solves a strand
    /// (`sim::StrandSolver`).
    pub solver: crate::sim::StrandSolver,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            dt: 1.0 / 360.0,
            iterations: 5,
            gravity: [0.0, -9.8, 0.0],
            youngs_modulus: 3.9e9,
            shear_modulus: 1.3e9,
            density: 1300.0,
            cuticle_peel_per_metre: 0.33,
            max_segment: None,
            damping: 2.0,
            seed: 1,
            sag_free: false,
            solver: crate::sim::StrandSolver::default(),
        }
    }
}

/// Each bond kind's share of the rest shape (S1-15's `f_j`).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct BondInfluences {
    pub hydrogen: f32,
    pub ionic: f32,
    pub disulfide: f32,
    pub peptide: f32,
}

impl Default for BondInfluences {
    /// Table 1, scene 3 ([`crate::sim::BondInfluences::SCENE_3`]).
    fn default() -> Self {
        let [hydrogen, ionic, disulfide, peptide] = crate::sim::BondInfluences::SCENE_3.0;
        BondInfluences { hydrogen, ionic, disulfide, peptide }
    }
}

/// Bond amounts per kind for a chemistry stage: the fraction broken by a lotion, or re-formed by
/// a neutraliser or rinse. Kinds left out are untouched.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BondAmounts {
    pub hydrogen: Option<f32>,
    pub ionic: Option<f32>,
    pub disulfide: Option<f32>,
    pub peptide: Option<f32>,
}

impl BondAmounts {
    fn entries(&self) -> [(&'static str, Option<f32>); 4] {
        [
            ("hydrogen", self.hydrogen),
            ("ionic", self.ionic),
            ("disulfide", self.disulfide),
            ("peptide", self.peptide),
        ]
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Contacts {
    /// S1-18 hair–hair penalty.
    pub hair_hair: bool,
    /// α of S1-18, m/s².
    pub hair_stiffness: f32,
    /// Edges are cut into pieces this long (metres) to find contact candidates. Only speed
    /// depends on it: shorter pieces mean fewer candidates per vertex but more pieces to sort
    /// (dense grooms with short segments favour ~2 mm, sparse long-segment ones ~5 mm).
    pub sample_spacing: f32,
    pub static_friction: f32,
    pub dynamic_friction: f32,
}

impl Contacts {
    /// The hair–hair contact settings, for a simulation of the styled groom that goes on from
    /// where the style left it.
    pub fn hair_contact_settings(&self) -> crate::sim::driver::HairContactSettings {
        crate::sim::driver::HairContactSettings {
            stiffness: self.hair_stiffness,
            spacing: self.sample_spacing,
        }
    }
}

impl Default for Contacts {
    fn default() -> Self {
        Contacts {
            hair_hair: false,
            hair_stiffness: 50.0,
            sample_spacing: 0.002,
            static_friction: 0.4,
            dynamic_friction: 0.3,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WaterSpec {
    /// Droplets scattered among the hair when a `wet` stage starts.
    pub droplets: usize,
    #[serde(default, flatten)]
    pub params: WaterParams,
}

/// What the coordinates of a position are.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Frame {
    /// Metres in the groom's own space (Y up).
    #[default]
    World,
    /// The head frame fitted to the groom (`super::head_frame`): head units (the fitted scalp
    /// sphere's radius) from the head's centre, along (`up × front`, up, front). Lengths (radii,
    /// half extents, travel, falloff) are in head units too; directions (normals, gravity) along
    /// the head's axes.
    Head,
}

/// The largest distance from the head's centre, and the largest length, a head-frame recipe may
/// give, in head units: farther is a mistake (metres written as head units, or the reverse).
pub const MAX_HEAD_UNITS: f32 = 8.0;

/// `[head]`: values that replace the fitted head frame's (world coordinates, metres), and the
/// mesh obstacle to fit it to.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HeadSpec {
    #[serde(default, deserialize_with = "crate::validate::optional_three")]
    pub center: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "crate::validate::optional_three")]
    pub up: Option<[f32; 3]>,
    #[serde(default, deserialize_with = "crate::validate::optional_three")]
    pub front: Option<[f32; 3]>,
    pub size: Option<f32>,
    /// A `shape = "mesh"` obstacle that is the scalp: the frame is fitted to it.
    pub scalp: Option<String>,
}

/// A solid the hair meets, named so stages can refer to it.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "shape", rename_all = "lowercase", deny_unknown_fields)]
pub enum Obstacle {
    /// The analytic head the groom grows on (`coif::head::Head`), optionally moved or resized.
    /// In the head frame, left without `center` and `radii`, it is the ellipsoid fitted to the
    /// groom's roots along the head's axes.
    Head {
        name: String,
        #[serde(default, deserialize_with = "crate::validate::optional_three")]
        center: Option<[f32; 3]>,
        #[serde(default, deserialize_with = "crate::validate::optional_three")]
        radii: Option<[f32; 3]>,
        frame: Option<Frame>,
    },
    /// The groom's own scalp or head mesh (given to the run with the groom, see
    /// [`super::StyleOptions::scalp`]), collided through a baked distance field; when the groom
    /// brings none, the ellipsoid fitted to its roots along the head frame's axes.
    Scalp {
        name: String,
        /// Cell of the baked field, metres (default 2 mm).
        resolution: Option<f32>,
        /// Width of the band of exact distances, metres (default 4 cells).
        band: Option<f32>,
    },
    Sphere {
        name: String,
        #[serde(deserialize_with = "crate::validate::three")]
        center: [f32; 3],
        radius: f32,
        frame: Option<Frame>,
    },
    /// A floor: the half-space below the plane.
    Plane {
        name: String,
        #[serde(deserialize_with = "crate::validate::three")]
        point: [f32; 3],
        #[serde(deserialize_with = "crate::validate::three")]
        normal: [f32; 3],
        frame: Option<Frame>,
    },
    /// A box along the frame's axes: a pillow, a table.
    Box {
        name: String,
        #[serde(deserialize_with = "crate::validate::three")]
        center: [f32; 3],
        #[serde(deserialize_with = "crate::validate::three")]
        half_extents: [f32; 3],
        frame: Option<Frame>,
    },
    /// A closed triangle mesh from a Wavefront OBJ file (a scanned head), collided through a
    /// signed distance field baked when the recipe is loaded.
    Mesh {
        name: String,
        /// The OBJ file, relative to the recipe's directory.
        path: PathBuf,
        /// Cell of the baked field, metres (default 2 mm).
        resolution: Option<f32>,
        /// Width of the band of exact distances around the surface, metres (default 4 cells).
        band: Option<f32>,
        /// The baked field and the triangles (filled in by [`load`] and [`parse`]).
        #[serde(skip)]
        sdf: Option<Arc<MeshSdf>>,
        #[serde(skip)]
        mesh: Option<Arc<TriangleMesh>>,
    },
}

/// Default cell of a mesh obstacle's distance field: fine enough for hair-width contacts on a
/// head-sized mesh, a few MB of grid.
pub const MESH_RESOLUTION: f32 = 0.002;

impl Obstacle {
    pub fn name(&self) -> &str {
        match self {
            Obstacle::Head { name, .. }
            | Obstacle::Scalp { name, .. }
            | Obstacle::Sphere { name, .. }
            | Obstacle::Plane { name, .. }
            | Obstacle::Box { name, .. }
            | Obstacle::Mesh { name, .. } => name,
        }
    }
}

/// A perm rod (curler): a capsule strands are wound onto.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rod {
    pub name: String,
    /// The rod's two end centres, metres.
    #[serde(deserialize_with = "crate::validate::three")]
    pub a: [f32; 3],
    #[serde(deserialize_with = "crate::validate::three")]
    pub b: [f32; 3],
    pub radius: f32,
    #[serde(default)]
    pub frame: Option<Frame>,
}

/// Which strands a stage acts on.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Mask {
    pub region: Region,
    /// Keep this fraction of the region's strands, chosen with the recipe's seed.
    pub fraction: f32,
}

impl Default for Mask {
    fn default() -> Self {
        Mask { region: Region::All, fraction: 1.0 }
    }
}

/// A scalp region, by the direction from the head centre to the strand's root.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Region {
    #[default]
    All,
    Crown,
    Front,
    Sides,
    Back,
    Nape,
}

impl Region {
    /// Whether a root whose unit direction from the head centre is `dir` lies in the region.
    pub fn contains(self, dir: Vec3) -> bool {
        match self {
            Region::All => true,
            Region::Crown => dir.y > 0.7,
            Region::Front => dir.z > 0.3 && dir.y <= 0.7,
            Region::Sides => dir.x.abs() > 0.6 && dir.y <= 0.7,
            Region::Back => dir.z < -0.3 && dir.y <= 0.7 && dir.y > 0.0,
            Region::Nape => dir.z < -0.3 && dir.y <= 0.0,
        }
    }
}

/// Which rods a `wrap` stage winds onto. Each strand goes to the rod nearest to it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Layout {
    /// The recipe's `[[rods]]` (those the stage names, or all).
    #[default]
    Nearest,
    /// Rods laid out over the scalp the roots cover, in rows around the head's up axis from the
    /// crown down, `spacing` apart, each two spacings long (`super::layout`).
    Rows,
    /// Rods laid end to end along a spiral from the crown, its turns `spacing` apart.
    Spiral,
}

#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DryerSpec {
    #[serde(deserialize_with = "crate::validate::three")]
    pub position: [f32; 3],
    #[serde(deserialize_with = "crate::validate::three")]
    pub target: [f32; 3],
    /// α of S1-17, m/s².
    pub strength: f32,
    /// Distance from the jet's axis over which the push halves (default 5 cm).
    #[serde(default)]
    pub falloff: Option<f32>,
    /// Degrees off the axis beyond which the jet does not reach.
    pub cone_degrees: Option<f32>,
    #[serde(default)]
    pub frame: Option<Frame>,
}

/// A dryer's falloff when the recipe gives none, metres.
pub const DEFAULT_FALLOFF: f32 = 0.05;

fn one() -> f32 {
    1.0
}

/// One stage of the timeline. Durations are seconds of simulated time.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum Stage {
    /// Soak the hair: wetness rises to `amount` (breaking hydrogen bonds).
    Wet {
        duration: f32,
        #[serde(default = "one")]
        amount: f32,
        #[serde(default)]
        mask: Mask,
    },
    /// Wind strands onto rods over the duration, then hold them there.
    Wrap {
        duration: f32,
        /// Rods to use (all when empty).
        #[serde(default)]
        rods: Vec<String>,
        #[serde(default)]
        layout: Layout,
        /// Rod diameter and row spacing of a `rows` or `spiral` layout.
        #[serde(default)]
        diameter: Option<f32>,
        #[serde(default)]
        spacing: Option<f32>,
        #[serde(default)]
        mask: Mask,
    },
    /// Apply a lotion that breaks bonds by kind (e.g. ionic 1.0, disulfide 0.2).
    Lotion {
        duration: f32,
        #[serde(rename = "break")]
        breaks: BondAmounts,
        #[serde(default)]
        mask: Mask,
    },
    /// Wait (the lotion works, the hair relaxes).
    Process { duration: f32 },
    /// Oxidising neutraliser: re-form bonds by kind at the current shape.
    #[serde(alias = "neutralize")]
    Neutralise { duration: f32, reform: BondAmounts },
    /// Rinse: restores pH, re-forming ionic bonds unless told otherwise; leaves hair wet.
    Rinse {
        duration: f32,
        #[serde(default)]
        reform: Option<BondAmounts>,
    },
    /// Dry in still air, or under a dryer.
    Dry {
        duration: f32,
        #[serde(default)]
        dryer: Option<DryerSpec>,
        #[serde(default = "one")]
        heat: f32,
    },
    /// Press an obstacle (a floor, a pillow) into the hair: it moves `travel` metres along
    /// `direction` (default: the plane's normal, or up for a box) over the duration, then holds.
    /// Both are in the pressed obstacle's frame.
    Press {
        duration: f32,
        obstacle: String,
        #[serde(default = "default_travel")]
        travel: f32,
        #[serde(default, deserialize_with = "crate::validate::optional_three")]
        direction: Option<[f32; 3]>,
    },
    /// Let go of rods and withdraw the pressed obstacles.
    Release { duration: f32 },
    /// Relax to static equilibrium and bake the new rest shape (model.md §6).
    Settle {
        #[serde(default = "default_settle_seconds")]
        max_seconds: f32,
        /// Largest accepted net force (per strand) and torque residual (`sim::settle`).
        #[serde(default = "default_settle_tolerance")]
        tolerance: f32,
        /// Settle without gravity (to measure the free curl).
        #[serde(default)]
        gravity: Option<bool>,
    },
}

fn default_travel() -> f32 {
    0.1
}

fn default_settle_seconds() -> f32 {
    10.0
}

fn default_settle_tolerance() -> f32 {
    crate::sim::settle::DEFAULT_TOLERANCE
}

impl Stage {
    pub fn kind(&self) -> &'static str {
        match self {
            Stage::Wet { .. } => "wet",
            Stage::Wrap { .. } => "wrap",
            Stage::Lotion { .. } => "lotion",
            Stage::Process { .. } => "process",
            Stage::Neutralise { .. } => "neutralise",
            Stage::Rinse { .. } => "rinse",
            Stage::Dry { .. } => "dry",
            Stage::Press { .. } => "press",
            Stage::Release { .. } => "release",
            Stage::Settle { .. } => "settle",
        }
    }

    /// Simulated seconds the stage lasts (a settle's is its cap).
    pub fn duration(&self) -> f32 {
        match self {
            Stage::Wet { duration, .. }
            | Stage::Wrap { duration, .. }
            | Stage::Lotion { duration, .. }
            | Stage::Process { duration }
            | Stage::Neutralise { duration, .. }
            | Stage::Rinse { duration, .. }
            | Stage::Dry { duration, .. }
            | Stage::Press { duration, .. }
            | Stage::Release { duration } => *duration,
            Stage::Settle { max_seconds, .. } => *max_seconds,
        }
    }
}

/// Reads and checks a recipe file.
pub fn load(path: &Path) -> Result<Recipe> {
    parse(&crate::io::input::read_text(path)?, path)
}

/// Parses and checks recipe text; `path` names it in errors, and mesh obstacles' files are found
/// relative to its directory.
pub fn parse(text: &str, path: &Path) -> Result<Recipe> {
    let mut recipe = parse_unbaked(text, path)?;
    bake_meshes(&mut recipe, text, path)?;
    Ok(recipe)
}

/// [`parse`] without reading and baking the mesh obstacles: every key, number and rule of the
/// recipe checked, cheaply (a batch checks each task's recipe before running any).
pub fn parse_unbaked(text: &str, path: &Path) -> Result<Recipe> {
    let recipe: Recipe = toml::from_str(text)
        .map_err(|e| Error::format(path, entry_error(text).unwrap_or_else(|| toml_message(&e, text))))?;
    check(&recipe, text).map_err(|message| Error::format(path, message))?;
    Ok(recipe)
}

/// Reads every mesh obstacle's OBJ file and bakes its distance field. A missing or malformed
/// mesh is bad input: the error names the recipe, its line and the mesh file.
fn bake_meshes(recipe: &mut Recipe, text: &str, recipe_path: &Path) -> Result<()> {
    let directory = recipe_path.parent().unwrap_or(Path::new(""));
    let lines = super::ranges::Lines::new(text);
    for obstacle in &mut recipe.obstacles {
        let line = lines.line_column(text, obstacle.span().start).0;
        if let Obstacle::Mesh { name, path, resolution, band, sdf, mesh } = obstacle.get_mut() {
            let file = directory.join(&*path);
            let fail = |what: String| {
                Error::format(recipe_path, format!("line {line}: mesh obstacle '{name}': {what}"))
            };
            let (points, triangles) =
                crate::io::obj::read_triangles(&file).map_err(|e| fail(e.to_string()))?;
            let triangles = TriangleMesh { points, triangles };
            let baked = bake_mesh(&triangles, *resolution, *band)
                .map_err(|e| fail(format!("{}: {e}", file.display())))?;
            *sdf = Some(Arc::new(baked));
            *mesh = Some(Arc::new(triangles));
        }
    }
    Ok(())
}

/// Bakes a mesh obstacle's field with the recipe's resolution and band, or the defaults.
pub fn bake_mesh(
    mesh: &TriangleMesh,
    resolution: Option<f32>,
    band: Option<f32>,
) -> std::result::Result<MeshSdf, String> {
    let cell = resolution.unwrap_or(MESH_RESOLUTION);
    mesh.bake(cell, band.unwrap_or(4.0 * cell))
}

/// The first `[[stages]]` or `[[obstacles]]` entry that does not read, with the line of the key at
/// fault (else of the entry) and which entry it is. Entries are tagged by `kind` / `shape`, and
/// serde reads such an entry through a buffer that loses its place: toml's own error pointed at the
/// first entry of the list, whichever was wrong.
fn entry_error(text: &str) -> Option<String> {
    #[derive(Deserialize)]
    struct Entries {
        #[serde(default)]
        obstacles: Vec<Spanned<toml::Table>>,
        #[serde(default)]
        stages: Vec<Spanned<toml::Table>>,
    }
    fn first_failure<T: serde::de::DeserializeOwned>(
        entries: &[Spanned<toml::Table>],
        what: &str,
        text: &str,
    ) -> Option<String> {
        entries.iter().enumerate().find_map(|(index, entry)| {
            let error = toml::Value::Table(entry.get_ref().clone()).try_into::<T>().err()?;
            let message = error.message().trim().to_string();
            // The entry's text: from its header to the next table header (toml's span of an
            // array-of-tables entry may be its header alone).
            let start = entry.span().start;
            let rest = &text[start..];
            let end = rest.get(1..).and_then(|r| r.find("\n[")).map_or(rest.len(), |i| i + 1);
            let within = &rest[..end];
            let as_key = |key: &str| {
                within.match_indices(key).map(|(i, _)| i).find(|&i| {
                    let before = within[..i].chars().next_back();
                    let after = within[i + key.len()..].trim_start();
                    !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
                        && (after.starts_with('=') || after.starts_with('.'))
                })
            };
            // Where the entry spells what the message quotes: a key (`travle`), else a value
            // (`kind = "curl"`, `duration = "long"`).
            let named = message.split('`').nth(1).filter(|k| !k.is_empty());
            let quoted = message.split('"').nth(1).filter(|v| !v.is_empty());
            let at = named
                .and_then(as_key)
                .or_else(|| named.or(quoted).and_then(|v| within.find(&format!("\"{v}\""))));
            let Some(at) = at else {
                return Some(format!("line {}: {what} {}: {message}", line_column(text, start).0, index + 1));
            };
            // A value's message does not say whose: the key on its line does.
            let line_text = within[..at].rsplit('\n').next().unwrap_or("");
            let key = line_text
                .split('=')
                .next()
                .map(str::trim)
                .filter(|k| line_text.contains('=') && !k.is_empty());
            let whose = key.filter(|k| !message.contains(*k)).map(|k| format!("{k}: ")).unwrap_or_default();
            let line = line_column(text, start + at).0;
            Some(format!("line {line}: {what} {}: {whose}{message}", index + 1))
        })
    }
    let entries: Entries = toml::from_str(text).ok()?;
    first_failure::<Obstacle>(&entries.obstacles, "obstacle", text)
        .or_else(|| first_failure::<Stage>(&entries.stages, "stage", text))
}

/// "line N, column M: what" from a TOML error, on one line.
pub(crate) fn toml_message(error: &toml::de::Error, text: &str) -> String {
    let what = error.message().trim();
    match error.span() {
        Some(span) => {
            let (line, column) = line_column(text, span.start);
            format!("line {line}, column {column}: {what}")
        }
        None => what.to_string(),
    }
}

fn line_column(text: &str, offset: usize) -> (usize, usize) {
    super::ranges::Lines::new(text).line_column(text, offset)
}

/// Semantic checks the types cannot express; each failure names its line.
fn check(recipe: &Recipe, text: &str) -> std::result::Result<(), String> {
    super::ranges::check_numbers(recipe, text)?;
    let lines = super::ranges::Lines::new(text);
    let line_of = |span: std::ops::Range<usize>| lines.line_column(text, span.start).0;
    let settings = &recipe.settings;
    let positive = |value: f32| value.is_finite() && value > 0.0;
    if !positive(settings.dt) || settings.dt > 0.1 {
        return Err(format!("[settings] dt = {} must be a positive time step of at most 0.1 s", settings.dt));
    }
    if ![settings.youngs_modulus, settings.shear_modulus, settings.density].iter().all(|&v| positive(v)) {
        return Err("[settings] youngs_modulus, shear_modulus and density must be positive".into());
    }
    if settings.max_segment.is_some_and(|m| !positive(m)) {
        return Err("[settings] max_segment must be a positive length".into());
    }
    if !(settings.cuticle_peel_per_metre >= 0.0 && settings.damping >= 0.0) {
        return Err("[settings] cuticle_peel_per_metre and damping must not be negative".into());
    }
    if !positive(recipe.contacts.sample_spacing) {
        return Err("[contacts] sample_spacing must be a positive length".into());
    }
    let b = &recipe.bonds;
    let influences = [b.hydrogen, b.ionic, b.disulfide, b.peptide];
    if influences.iter().any(|f| !(f.is_finite() && *f >= 0.0)) || influences.iter().sum::<f32>() <= 0.0 {
        return Err("[bonds] influences must be non-negative and not all zero".into());
    }

    if let Some(scalp) = &recipe.head.scalp {
        if !recipe
            .obstacles
            .iter()
            .any(|o| o.get_ref().name() == scalp && matches!(o.get_ref(), Obstacle::Mesh { .. }))
        {
            return Err(format!("[head] scalp = '{scalp}' names no mesh obstacle"));
        }
    }
    let head = &recipe.head;
    if head.size.is_some_and(|s| !positive(s)) {
        return Err("[head] size must be a positive length".into());
    }
    // `[head]` only replaces values of a fitted head frame: a recipe with nothing in the head
    // frame fits none, and its `[head]` changed nothing (masks' regions stayed around the analytic
    // head's centre) without a word.
    if *head != HeadSpec::default() && !super::placement::needs_frame(recipe) {
        let line = text
            .lines()
            .position(|l| l.trim() == "[head]")
            .map_or(String::new(), |i| format!("line {}: ", i + 1));
        return Err(format!(
            "{line}[head] is given, but nothing in this recipe is in the head frame (frame = \"world\", \
             no scalp obstacle, no rows or spiral layout), so no head frame is fitted and [head] \
             would change nothing: write frame = \"head\" at the top to place the recipe on the \
             head, or remove [head]"
        ));
    }

    let mut names: Vec<&str> = Vec::new();
    for obstacle in &recipe.obstacles {
        let line = line_of(obstacle.span());
        let name = obstacle.get_ref().name();
        // Stages name what they use: an empty name is a key left blank.
        if name.trim().is_empty() {
            return Err(format!("line {line}: an obstacle's name = \"{name}\" is blank; name it"));
        }
        if names.contains(&name) {
            return Err(format!("line {line}: a second obstacle or rod named '{name}'"));
        }
        names.push(name);
        let meshed = |resolution: &Option<f32>, band: &Option<f32>| {
            resolution.is_some_and(|r| !positive(r))
                || band.is_some_and(|b| !positive(b) || b < resolution.unwrap_or(MESH_RESOLUTION))
        };
        let bad = match obstacle.get_ref() {
            Obstacle::Sphere { radius, .. } => !positive(*radius),
            Obstacle::Head { radii: Some(r), .. } => !r.iter().all(|&x| positive(x)),
            Obstacle::Plane { normal, .. } => Vec3::from(*normal).length() < 1e-6,
            Obstacle::Box { half_extents, .. } => !half_extents.iter().all(|&x| positive(x)),
            Obstacle::Head { .. } => false,
            Obstacle::Mesh { resolution, band, .. } | Obstacle::Scalp { resolution, band, .. } => {
                meshed(resolution, band)
            }
        };
        if bad {
            return Err(format!("line {line}: obstacle '{name}' has a zero or negative size"));
        }
        // An empty path is the recipe's own folder: it was refused as ": No such file or
        // directory", or as a directory, without saying which key.
        if let Obstacle::Mesh { path, .. } = obstacle.get_ref() {
            if path.as_os_str().is_empty() {
                return Err(format!(
                    "line {line}: mesh obstacle '{name}': path = \"\": give its OBJ file, relative to the recipe"
                ));
            }
        }
        let in_head = |frame: &Option<Frame>| frame.unwrap_or(recipe.frame) == Frame::Head;
        let what = format!("line {line}: obstacle '{name}'");
        match obstacle.get_ref() {
            Obstacle::Head { center, radii, frame, .. } if in_head(frame) => {
                center.map_or(Ok(()), |c| head_position(&what, "center", c))?;
                radii.map_or(Ok(()), |r| head_lengths(&what, "radii", &r))?;
            }
            Obstacle::Sphere { center, radius, frame, .. } if in_head(frame) => {
                head_position(&what, "center", *center)?;
                head_lengths(&what, "radius", &[*radius])?;
            }
            Obstacle::Plane { point, frame, .. } if in_head(frame) => head_position(&what, "point", *point)?,
            Obstacle::Box { center, half_extents, frame, .. } if in_head(frame) => {
                head_position(&what, "center", *center)?;
                head_lengths(&what, "half_extents", half_extents)?;
            }
            _ => {}
        }
    }
    for rod in &recipe.rods {
        let line = line_of(rod.span());
        let r = rod.get_ref();
        if r.name.trim().is_empty() {
            return Err(format!("line {line}: a rod's name = \"{}\" is blank; name it", r.name));
        }
        if names.contains(&r.name.as_str()) {
            return Err(format!("line {line}: a second obstacle or rod named '{}'", r.name));
        }
        names.push(&r.name);
        if !positive(r.radius) || Vec3::from(r.a).distance(Vec3::from(r.b)) < 1e-6 {
            return Err(format!(
                "line {line}: rod '{}' needs a positive radius and two distinct ends",
                r.name
            ));
        }
        if r.frame.unwrap_or(recipe.frame) == Frame::Head {
            let what = format!("line {line}: rod '{}'", r.name);
            head_position(&what, "a", r.a)?;
            head_position(&what, "b", r.b)?;
            head_lengths(&what, "radius", &[r.radius])?;
        }
    }

    if recipe.stages.is_empty() {
        return Err("the recipe has no [[stages]]".into());
    }
    let (mut held, mut lotion_applied) = (None::<&str>, false);
    let last = recipe.stages.len() - 1;
    for (index, spanned) in recipe.stages.iter().enumerate() {
        let line = line_of(spanned.span());
        let stage = spanned.get_ref();
        let kind = stage.kind();
        let fail = |what: String| Err(format!("line {line}: stage {} ({kind}): {what}", index + 1));
        let duration = stage.duration();
        if !(duration.is_finite() && duration >= 0.0) {
            return fail(format!("duration {duration} must be zero or more seconds"));
        }
        let check_mask = |mask: &Mask| (0.0..=1.0).contains(&mask.fraction);
        match stage {
            Stage::Wet { amount, mask, .. } => {
                if !(0.0..=1.0).contains(amount) || !check_mask(mask) {
                    return fail("amount and mask fraction must be in [0, 1]".into());
                }
            }
            Stage::Wrap { rods, mask, layout, diameter, spacing, .. } => {
                if let Some(holder) = held {
                    return fail(format!("the hair is still held by the earlier {holder}; release it first"));
                }
                if *layout == Layout::Nearest {
                    if recipe.rods.is_empty() {
                        return fail(
                            "there are no [[rods]] to wrap onto (or lay them out: layout = \"rows\")".into(),
                        );
                    }
                    if diameter.is_some() || spacing.is_some() {
                        return fail("diameter and spacing belong to a rows or spiral layout".into());
                    }
                } else {
                    if !rods.is_empty() {
                        return fail("a rows or spiral layout makes its own rods: leave out rods".into());
                    }
                    let (Some(diameter), Some(spacing)) = (diameter, spacing) else {
                        return fail("a rows or spiral layout needs a diameter and a spacing".into());
                    };
                    if !(positive(*diameter) && positive(*spacing) && spacing > diameter) {
                        return fail(format!(
                            "diameter {diameter} and spacing {spacing} must be positive, the spacing the larger"
                        ));
                    }
                    if recipe.frame == Frame::Head {
                        head_lengths(
                            &format!("line {line}: stage {} (wrap)", index + 1),
                            "spacing",
                            &[*spacing],
                        )
                        .or_else(fail)?;
                        // In metres the rods' count waits for the fitted head (placement).
                        if let Some(why) = super::layout::too_many_rods(*spacing, None) {
                            return fail(why);
                        }
                    }
                }
                if let Some(missing) =
                    rods.iter().find(|r| !recipe.rods.iter().any(|x| &x.get_ref().name == *r))
                {
                    return fail(format!("there is no rod named '{missing}'"));
                }
                // Each listed rod is an obstacle of every vertex: a million "r" took 14 s a step.
                // (Every name is a rod's, and a recipe has at most 1000: found within 1001 entries.)
                if let Some((second, twice)) = rods.iter().enumerate().find(|(i, r)| rods[..*i].contains(r)) {
                    let first = rods.iter().position(|r| r == twice).unwrap_or(0);
                    return fail(format!(
                        "rods lists '{twice}' twice (entries {} and {})",
                        first + 1,
                        second + 1
                    ));
                }
                if !check_mask(mask) {
                    return fail("mask fraction must be in [0, 1]".into());
                }
                held = Some("wrap");
            }
            Stage::Lotion { breaks, mask, .. } => {
                check_amounts(breaks).or_else(fail)?;
                if breaks.peptide.is_some_and(|x| x > 0.0) {
                    return fail("peptide bonds do not break (model.md §2)".into());
                }
                if !check_mask(mask) {
                    return fail("mask fraction must be in [0, 1]".into());
                }
                lotion_applied = true;
            }
            Stage::Neutralise { reform, .. } => {
                check_amounts(reform).or_else(fail)?;
                if !lotion_applied {
                    return fail("nothing to neutralise: no lotion stage comes before it".into());
                }
            }
            Stage::Rinse { reform: Some(reform), .. } => check_amounts(reform).or_else(fail)?,
            Stage::Dry { dryer, heat, .. } => {
                if !(heat.is_finite() && *heat >= 0.0) {
                    return fail(format!("heat {heat} must not be negative"));
                }
                if let Some(d) = dryer {
                    if !(d.strength.is_finite() && d.strength >= 0.0 && d.falloff.is_none_or(positive)) {
                        return fail("dryer strength must be >= 0 and falloff > 0".into());
                    }
                    if Vec3::from(d.position).distance(Vec3::from(d.target)) < 1e-6 {
                        return fail("dryer position and target must differ".into());
                    }
                    if d.frame.unwrap_or(recipe.frame) == Frame::Head {
                        let what = format!("line {line}: stage {} (dry): dryer", index + 1);
                        head_position(&what, "position", d.position).or_else(fail)?;
                        head_position(&what, "target", d.target).or_else(fail)?;
                        d.falloff.map_or(Ok(()), |f| head_lengths(&what, "falloff", &[f])).or_else(fail)?;
                    }
                }
            }
            Stage::Press { obstacle, travel, direction, .. } => {
                if let Some(holder) = held {
                    return fail(format!("the hair is still held by the earlier {holder}; release it first"));
                }
                let frame = match recipe.obstacles.iter().find(|o| o.get_ref().name() == obstacle) {
                    None => return fail(format!("there is no obstacle named '{obstacle}'")),
                    Some(o) => match o.get_ref() {
                        Obstacle::Plane { frame, .. } | Obstacle::Box { frame, .. } => {
                            frame.unwrap_or(recipe.frame)
                        }
                        _ => return fail(format!("'{obstacle}' is not a plane or box to press onto")),
                    },
                };
                if frame == Frame::Head {
                    head_lengths(&format!("line {line}: stage {} (press)", index + 1), "travel", &[*travel])
                        .or_else(fail)?;
                }
                if !(travel.is_finite() && *travel >= 0.0) {
                    return fail(format!("travel {travel} must be zero or more metres"));
                }
                if direction.is_some_and(|d| Vec3::from(d).length() < 1e-6) {
                    return fail("direction must not be zero".into());
                }
                held = Some("press");
            }
            Stage::Release { .. } => {
                if held.is_none() {
                    return fail("nothing to release: no wrap or press stage holds the hair".into());
                }
                held = None;
            }
            Stage::Settle { max_seconds, tolerance, .. } => {
                // First, it hangs the groom at rest before the style (so the style does not
                // depend on how a groom out of balance falls); last, it relaxes the styled hair.
                if index != 0 && index != last {
                    return fail("settle must be the first or the last stage".into());
                }
                if let Some(holder) = held {
                    return fail(format!("the hair is still held by the earlier {holder}; release it first"));
                }
                let options = crate::sim::SettleOptions {
                    tolerance: *tolerance,
                    max_seconds: *max_seconds,
                    iterations: None,
                };
                if let Err(e) = options.check("tolerance", "max_seconds") {
                    return fail(e.to_string());
                }
            }
            Stage::Process { .. } | Stage::Rinse { reform: None, .. } => {}
        }
    }
    Ok(())
}

/// A head-frame position must lie within [`MAX_HEAD_UNITS`] of the head's centre.
fn head_position(what: &str, key: &str, position: [f32; 3]) -> std::result::Result<(), String> {
    let distance = Vec3::from(position).length();
    if distance.is_finite() && distance <= MAX_HEAD_UNITS {
        return Ok(());
    }
    Err(format!(
        "{what}: {key} = {position:?} lies {distance} head units from the head's centre; head-frame \
         positions are in head units (≈ 0.1 m on an adult head), at most {MAX_HEAD_UNITS} — \
         metres belong in frame = \"world\""
    ))
}

/// Head-frame lengths must be at most [`MAX_HEAD_UNITS`].
fn head_lengths(what: &str, key: &str, lengths: &[f32]) -> std::result::Result<(), String> {
    match lengths.iter().find(|l| !(l.is_finite() && l.abs() <= MAX_HEAD_UNITS)) {
        None => Ok(()),
        Some(l) => Err(format!(
            "{what}: {key} {l} is more than {MAX_HEAD_UNITS} head units (≈ 0.1 m each on an adult head)"
        )),
    }
}

fn check_amounts(amounts: &BondAmounts) -> std::result::Result<(), String> {
    for (kind, value) in amounts.entries() {
        if let Some(v) = value {
            if !(0.0..=1.0).contains(&v) {
                return Err(format!("{kind} = {v} must be a fraction in [0, 1]"));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const PERM: &str = r#"
[settings]
dt = 0.0027777778
iterations = 5

[bonds]
hydrogen = 0.33
ionic = 0.30
disulfide = 0.20
peptide = 0.17

[[rods]]
name = "rod"
a = [-0.1, -0.2, 0.1]
b = [0.1, -0.2, 0.1]
radius = 0.01

[[stages]]
kind = "wrap"
duration = 2.0

[[stages]]
kind = "lotion"
duration = 1.0
break = { ionic = 1.0, disulfide = 0.2 }

[[stages]]
kind = "neutralise"
duration = 1.0
reform = { ionic = 1.0, disulfide = 1.0 }

[[stages]]
kind = "release"
duration = 0.5

[[stages]]
kind = "settle"
"#;

    fn error_of(text: &str) -> String {
        parse(text, Path::new("r.toml")).unwrap_err().to_string()
    }

    #[test]
    fn a_perm_recipe_parses() {
        let recipe = parse(PERM, Path::new("perm.toml")).unwrap();
        assert_eq!(recipe.stages.len(), 5);
        assert_eq!(recipe.stages[1].get_ref().kind(), "lotion");
        assert!(
            matches!(recipe.stages[4].get_ref(), Stage::Settle { max_seconds, .. } if *max_seconds == 10.0)
        );
        assert_eq!(recipe.rods[0].get_ref().radius, 0.01);
    }

    #[test]
    fn mistakes_name_their_line() {
        let unknown = PERM.replace("iterations = 5", "iterations = 5\nsubsteps = 3");
        let e = error_of(&unknown);
        assert!(e.contains("line 5") && e.contains("substeps"), "{e}");

        let wrong_type = PERM.replace("iterations = 5", "iterations = \"five\"");
        assert!(error_of(&wrong_type).contains("line 4"), "{}", error_of(&wrong_type));

        let negative = PERM.replace("duration = 2.0", "duration = -2.0");
        let e = error_of(&negative);
        assert!(e.contains("line 18") && e.contains("duration"), "{e}");

        let missing_rod = PERM.replace("duration = 2.0", "duration = 2.0\nrods = [\"curler\"]");
        let e = error_of(&missing_rod);
        assert!(e.contains("line 18") && e.contains("no rod named 'curler'"), "{e}");

        let no_release = PERM.replace("kind = \"release\"", "kind = \"process\"");
        let e = error_of(&no_release);
        assert!(e.contains("settle") && e.contains("release it first"), "{e}");

        // A settle may hang the groom at rest first, but not interrupt the style.
        let hang_first = PERM.replace(
            "[[stages]]\nkind = \"wrap\"",
            "[[stages]]\nkind = \"settle\"\n\n[[stages]]\nkind = \"wrap\"",
        );
        assert_eq!(parse(&hang_first, Path::new("r.toml")).unwrap().stages.len(), 6);
        let settle_between = PERM.replace(
            "[[stages]]\nkind = \"lotion\"",
            "[[stages]]\nkind = \"settle\"\n\n[[stages]]\nkind = \"lotion\"",
        );
        assert!(
            error_of(&settle_between).contains("first or the last stage"),
            "{}",
            error_of(&settle_between)
        );

        let neutralise_first = PERM.replace(
            "kind = \"lotion\"\nduration = 1.0\nbreak = { ionic = 1.0, disulfide = 0.2 }",
            "kind = \"process\"\nduration = 1.0",
        );
        assert!(
            error_of(&neutralise_first).contains("nothing to neutralise"),
            "{}",
            error_of(&neutralise_first)
        );

        let peptide = PERM.replace("disulfide = 0.2 }", "peptide = 0.5 }");
        assert!(error_of(&peptide).contains("peptide bonds do not break"));

        // Head-frame recipes: positions and lengths in head units, at most MAX_HEAD_UNITS.
        let head = format!("frame = \"head\"\n{PERM}");
        assert!(parse(&head, Path::new("r.toml")).is_ok());
        let far = head.replace("a = [-0.1, -0.2, 0.1]", "a = [-10.0, -0.2, 0.1]");
        let e = error_of(&far);
        assert!(e.contains("line 13") && e.contains("rod 'rod'") && e.contains("head units"), "{e}");
        let world_rod = far.replace("radius = 0.01", "radius = 0.01\nframe = \"world\"");
        assert!(parse(&world_rod, Path::new("r.toml")).is_ok(), "a world item may be anywhere");
        let no_spacing = PERM.replace("duration = 2.0", "duration = 2.0\nlayout = \"rows\"\ndiameter = 0.02");
        assert!(
            error_of(&no_spacing).contains("needs a diameter and a spacing"),
            "{}",
            error_of(&no_spacing)
        );
        let laid = PERM.replace(
            "duration = 2.0",
            "duration = 2.0\nlayout = \"spiral\"\ndiameter = 0.02\nspacing = 0.03",
        );
        assert!(parse(&laid, Path::new("r.toml")).is_ok());

        let unknown_stage = PERM.replace("kind = \"release\"", "kind = \"curl\"");
        assert!(error_of(&unknown_stage).contains("line 33"), "{}", error_of(&unknown_stage));
    }

    /// A mistake inside the n-th `[[stages]]` or `[[obstacles]]` entry names its own line and
    /// entry (toml's error gave the line of the first entry of the list, whichever was wrong).
    #[test]
    fn a_mistake_in_a_later_entry_names_its_own_line() {
        let line_of = |text: &str, needle: &str| text[..text.find(needle).unwrap()].lines().count() + 1;
        let typo = PERM.replace("kind = \"release\"", "kind = \"release\"\ndurtion = 1.0");
        let e = error_of(&typo);
        let line = line_of(&typo, "durtion");
        assert!(e.contains(&format!("line {line}: stage 4")) && e.contains("durtion"), "{e}");
        let obstacles = format!(
            "[[obstacles]]\nname = \"head\"\nshape = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 0.1\n\n\
             [[obstacles]]\nname = \"floor\"\nshape = \"plane\"\npoint = [0.0, -1.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\n\
             nromal = [0.0, 1.0, 0.0]\n\n{PERM}"
        );
        let e = error_of(&obstacles);
        let line = line_of(&obstacles, "nromal");
        assert!(e.contains(&format!("line {line}: obstacle 2")) && e.contains("nromal"), "{e}");
        let wrong_type =
            PERM.replace("kind = \"release\"\nduration = 0.5", "kind = \"release\"\nduration = \"long\"");
        let e = error_of(&wrong_type);
        assert!(e.contains("stage 4") && e.contains("duration"), "{e}");
    }
}
