//! Runs a recipe on a groom: the timeline of stages drives the simulation core (`crate::sim`)
//! and the interactions (`crate::interact`) — wetness and water, rods and pressing, chemistry
//! that breaks and re-forms bonds, the dryer — and ends with a settled groom carrying its new
//! rest shape, bond rates and wetness, plus a report per stage.
//!
//! Every step is: forces from a snapshot (wind, hair–hair penalty, water) → the rod solver with
//! obstacle contacts projected each iteration → wetness update (uptake, wicking, evaporation),
//! whose changes re-form or break hydrogen bonds (S1-16) and change strand mass.
use std::sync::Arc;
use std::time::Instant;

use glam::{Quat, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use super::head_frame::HeadFrame;
use super::placement::place;
use super::recipe::{Mask, Recipe, Stage, DEFAULT_FALLOFF};
use crate::analysis::{curl_radius, mean_curvature, resample_groom};
use crate::error::{Error, Result};
use crate::groom::{Attribute, AttributeRate, Groom};
use crate::interact::hair_contacts::HairContacts;
use crate::interact::mesh_sdf::TriangleMesh;
use crate::interact::obstacles::{
    segment_distance, ContactHooks, Friction, ObstacleCulling, Shape, StepContacts, Threaded, Threading,
};
use crate::interact::water::{Droplets, WaterParams};
use crate::interact::wetness::{self, WetnessParams};
use crate::interact::wind::Dryer;
use crate::progress::{Progress, ProgressMode};
use crate::sim::settle::settle_with;
use crate::sim::{
    BondInfluences, BondKind, Cuticle, Material, SettleOptions, SettleReport, SimParams, Simulation,
};

/// Options of a styling run that are not part of the recipe.
#[derive(Clone, Debug, Default)]
pub struct StyleOptions {
    /// Capture the groom this many times per simulated second (0: only the result).
    pub frames_per_second: f32,
    /// How to report progress on stderr.
    pub progress: ProgressMode,
    /// The groom's own scalp or head mesh: `shape = "scalp"` obstacles collide with it and the
    /// head frame is fitted to it. Readers of groom files that carry a mesh fill it in.
    pub scalp: Option<Arc<TriangleMesh>>,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BondRates {
    pub hydrogen: f32,
    pub ionic: f32,
    pub disulfide: f32,
    pub peptide: f32,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StageReport {
    pub index: usize,
    pub kind: &'static str,
    /// Simulated seconds.
    pub seconds: f32,
    pub steps: u64,
    pub wall_seconds: f64,
    /// Mean over strands of total turning angle per length, 1/m.
    pub mean_curvature: f32,
    /// Median curl radius of the strands that were wound on rods (else of all strands), metres.
    pub curl_radius: Option<f32>,
    /// The same median over the zero-stress rest curves (the exported `rest`): the curl the bonds
    /// hold free of gravity and contacts, which hanging curls stretch narrower.
    pub rest_curl_radius: Option<f32>,
    /// Mean bond rates per kind at the stage's end.
    pub bond_rates: BondRates,
    /// Mean wetness at the stage's end.
    pub wetness: f32,
    pub settle: Option<SettleReport>,
    /// Deepest any vertex went inside an active obstacle or rod after any step of the stage,
    /// metres (0: never inside; a vertex's radius counts). A vertex a rod appeared around counts
    /// how far it lies inside the rod as put in place so far (see `threaded_max_depth`).
    pub max_penetration: f32,
    /// Deepest a vertex a rod appeared around was inside that rod after any step of the stage
    /// (metres, 0 for none): it leaves at [`ROD_PLACING_SPEED`].
    pub threaded_max_depth: f32,
    /// On the stage the last such vertex left its rod: simulated seconds from the rods appearing.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub threaded_exit_seconds: Option<f32>,
}

/// How fast hair a curler rod is put in place around is moved out of it (m/s): across the water
/// set's 2.5 cm rods in a quarter to half a second. A speed, so the way out takes the same time at
/// any Δt and any number of iterations.
pub const ROD_PLACING_SPEED: f32 = 0.1;

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StyleReport {
    pub strands: usize,
    /// Strands simulated as guides when the rest were interpolated from them (`crate::guides`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub guides: Option<usize>,
    pub vertices: usize,
    pub steps: u64,
    /// The head frame the recipe was placed in, when it needed one.
    pub head_frame: Option<HeadFrameReport>,
    pub stages: Vec<StageReport>,
    /// What in the recipe, as placed on this groom, is likely not what its author meant.
    pub warnings: Vec<String>,
}

impl StyleReport {
    /// The first settle stage that did not reach its tolerance, named, with what it reached.
    pub fn unconverged_settle(&self) -> Option<String> {
        self.stages.iter().find_map(|stage| {
            let shortfall = stage.settle?.shortfall()?;
            Some(format!("stage {} ({}): {shortfall}", stage.index + 1, stage.kind))
        })
    }
}

/// A fitted head frame as the report shows it (world coordinates, metres).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HeadFrameReport {
    pub center: [f32; 3],
    pub up: [f32; 3],
    pub front: [f32; 3],
    /// Metres per head unit.
    pub size: f32,
}

/// The outcome of a styling run.
pub struct Styled {
    /// The settled groom with `rest`, `rest_darboux`, `bond_*` and `wetness` attributes.
    pub groom: Groom,
    pub report: StyleReport,
    /// Captured positions, one array per frame (empty unless frames were asked for).
    pub frames: Vec<Vec<Vec3>>,
    /// The attributes styling changes (`rest`, `rest_darboux`, `bond_*`, `wetness`) at each
    /// captured frame, as the groom holds them at the end.
    pub frame_attributes: Vec<Vec<Attribute>>,
    pub frames_per_second: f32,
    /// The colliders as they were at each captured frame (a press where it had moved to, the rods
    /// while strands were wound), for children interpolated into that frame to be pushed out of.
    pub(crate) frame_colliders: Vec<Arc<[Shape]>>,
    /// The colliders at the end (the ones the groom settled against: no pressing obstacle after a
    /// `release`), for children interpolated into the final state.
    pub(crate) colliders: Vec<Shape>,
    /// The water droplets among the hair each time they were dried off (and at the end if still
    /// there), for children interpolated from these strands to clump by the same adhesion.
    pub(crate) droplets: Vec<DropletSnapshot>,
}

/// Water droplets and the strands they held, as they were when the droplets went.
pub(crate) struct DropletSnapshot {
    pub droplets: Vec<Vec3>,
    /// The strands' points at that moment.
    pub hair: Vec<Vec3>,
    /// How many captured frames came before.
    pub frames_before: usize,
    pub params: WaterParams,
    /// Steps the droplets spent among the hair.
    pub steps: u64,
}

/// Styles a groom with a recipe: every strand, or the guides and children interpolated from them.
/// Without a scalp in `options`, the groom's own mesh under its roots is the scalp
/// ([`crate::surface_mesh::scalp_of`]); the result keeps the groom's meshes.
pub fn style(groom: &Groom, recipe: &Recipe, options: &StyleOptions) -> Result<Styled> {
    style_part(groom, groom, recipe, options)
}

/// [`style`] for `part`, strands selected from `whole` (`coif style --group`): placed in the head
/// frame of the whole groom and colliding with its scalp, as the README promises, so a recipe
/// means the same head whichever groups it styles (fitted to a fringe alone, its front turned
/// to the back of the head).
pub fn style_part(whole: &Groom, part: &Groom, recipe: &Recipe, options: &StyleOptions) -> Result<Styled> {
    let groom = part;
    crate::sim::rod::check_simulable(groom)?;
    let own_scalp;
    let options = match options.scalp.is_none().then(|| crate::surface_mesh::scalp_of(whole)).flatten() {
        Some(mesh) => {
            own_scalp = StyleOptions { scalp: Some(Arc::new(mesh)), ..options.clone() };
            &own_scalp
        }
        None => options,
    };
    // One head frame for the run, fitted to the whole groom as it comes (its scalp mesh, else
    // all its roots), whether every strand or only the guides are simulated.
    let frame = super::placement::head_frame(recipe, whole, options.scalp.as_deref())?;
    // A recipe without `max_segment` still gets the resolution its head and rods need.
    let resolved;
    let recipe = match super::placement::default_max_segment(recipe, groom, frame)? {
        Some(max) if recipe.settings.max_segment.is_none() => {
            resolved = {
                let mut r = recipe.clone();
                r.settings.max_segment = Some(max);
                r
            };
            &resolved
        }
        _ => recipe,
    };
    crate::limits::check_style(groom, recipe, options.frames_per_second)?;
    let mut styled = if crate::guides::wanted(groom, recipe) {
        crate::guides::style(groom, recipe, options, frame)?
    } else {
        style_strands(groom, recipe, options, frame, WaterSnapshots::Drop)?
    };
    styled.groom.meshes.clone_from(&groom.meshes);
    let warnings = crate::point_attributes::follow_new_shape(groom, &mut styled.groom, None);
    styled.report.warnings.extend(warnings);
    // Captured frames hold the state attributes of each moment; normals follow each frame's shape.
    if styled.frame_attributes.len() == styled.frames.len() {
        if let Some(normals) =
            crate::point_attributes::normals_in_frames(groom, &styled.groom, &styled.frames)
        {
            styled.frame_attributes.iter_mut().zip(normals).for_each(|(frame, n)| frame.push(n));
        }
    }
    Ok(styled)
}

/// Whether a styling run keeps [`DropletSnapshot`]s: only a guide run, whose children clump by
/// them, needs them (each holds a copy of every strand's points).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum WaterSnapshots {
    Keep,
    Drop,
}

/// Styles every strand of a groom with a recipe.
pub(crate) fn style_strands(
    groom: &Groom,
    recipe: &Recipe,
    options: &StyleOptions,
    frame: Option<HeadFrame>,
    snapshots: WaterSnapshots,
) -> Result<Styled> {
    let mut session = Session::new(groom, recipe, options, frame)?;
    session.keep_snapshots = snapshots == WaterSnapshots::Keep;
    let mut stages = Vec::with_capacity(recipe.stages.len());
    let total_steps: u64 = recipe.stages.iter().map(|s| session.steps_for(s.get_ref().duration())).sum();
    let progress = Progress::new(options.progress, "style", total_steps);
    // A settle ends once at rest, usually long before its budget: the ETA gives it as a range.
    let settle_budget: u64 = (recipe.stages.iter())
        .filter(|s| matches!(s.get_ref(), Stage::Settle { .. }))
        .map(|s| session.steps_for(s.get_ref().duration()))
        .sum();
    progress.add_open(settle_budget);
    // The stages placed on this groom (head-frame lengths in metres, layouts as rods).
    let placed_stages = session.recipe.stages.clone();
    for (index, spanned) in placed_stages.iter().enumerate() {
        let stage = spanned.get_ref();
        progress.set_message(&format!("stage {}/{} {}", index + 1, placed_stages.len(), stage.kind()));
        let start = Instant::now();
        session.penetration = 0.0;
        session.threaded_depth = 0.0;
        session.threaded_exit = None;
        let steps_before = session.sim.steps_taken();
        let settle = session.run_stage(index, stage, &progress)?;
        session.sim.check_diverged(Some(format!("stage {} ({})", index + 1, stage.kind())))?;
        let steps = session.sim.steps_taken() - steps_before;
        stages.push(session.stage_report(index, stage, steps, start.elapsed().as_secs_f64(), settle));
    }
    progress.finish();
    let report = StyleReport {
        strands: session.groom.strand_count(),
        guides: None,
        vertices: session.groom.vertex_count(),
        steps: session.sim.steps_taken(),
        head_frame: session.head_frame.map(|f| HeadFrameReport {
            center: f.center().to_array(),
            up: f.up().to_array(),
            front: f.front().to_array(),
            size: f.size(),
        }),
        stages,
        warnings: std::mem::take(&mut session.warnings),
    };
    if session.steps_per_frame.is_some()
        && session.frames.last().map(Vec::as_slice) != Some(session.sim.rods().positions())
    {
        session.capture_frame();
    }
    let mut out = session.groom.clone();
    out.points = session.sim.rods().positions().to_vec();
    for attribute in session.state() {
        out.provide_attribute(attribute);
    }
    out.validate()?;
    session.snapshot_droplets();
    Ok(Styled {
        groom: out,
        report,
        frames: session.frames,
        frame_attributes: session.frame_attributes,
        frame_colliders: session.frame_colliders,
        colliders: session.active,
        frames_per_second: options.frames_per_second,
        droplets: session.droplet_snapshots,
    })
}

/// The helix a strand is wound onto: around `axis` through `origin`, starting at `e1`.
#[derive(Clone, Copy)]
struct Helix {
    origin: Vec3,
    axis: Vec3,
    e1: Vec3,
    /// `e2` times the winding direction (±1).
    e2: Vec3,
    radius: f32,
    /// Advance along the axis per radian.
    advance: f32,
}

impl Helix {
    fn point(&self, phi: f32) -> Vec3 {
        self.origin
            + self.axis * (self.advance * phi)
            + self.radius * (phi.cos() * self.e1 + phi.sin() * self.e2)
    }

    fn tangent(&self, phi: f32) -> Vec3 {
        (self.axis * self.advance + self.radius * (phi.cos() * self.e2 - phi.sin() * self.e1)).normalize()
    }
}

/// A strand wound on a rod, from its vertex `first` to the tip.
struct Winding {
    /// The rod (index into the session's rods) it is wound on.
    rod: usize,
    first: usize,
    end: usize,
    /// Positions when the stage began.
    start: Vec<Vec3>,
    /// Arc length from `first` and helix angle (chords keep the rest lengths) of each vertex.
    arc: Vec<f32>,
    phi: Vec<f32>,
    helix: Helix,
}

impl Winding {
    /// Where vertex `k` of the wound part is at stage time `t ∈ [0, 1]`. The first fifth lays the
    /// tail straight along the rod's tangent at the contact; the rest rolls it onto the rod, so
    /// every edge only turns about the rod's axis — moving vertices straight to the helix would
    /// sweep the edges through unrelated directions and leave a spurious twist in the frames.
    fn pose(&self, k: usize, t: f32) -> Vec3 {
        const LAY: f32 = 0.2;
        let line = |s: f32| self.helix.point(0.0) + self.helix.tangent(0.0) * s;
        if t < LAY {
            return self.start[k].lerp(line(self.arc[k]), smoothstep(t / LAY));
        }
        let rolled = smoothstep((t - LAY) / (1.0 - LAY)) * self.arc[self.arc.len() - 1];
        if self.arc[k] <= rolled {
            return self.helix.point(self.phi[k]);
        }
        // The angle where rolling has reached, interpolated between vertices.
        let j = self.arc.partition_point(|&a| a <= rolled).max(1);
        let span = self.arc[j] - self.arc[j - 1];
        let phi = self.phi[j - 1] + (self.phi[j] - self.phi[j - 1]) * ((rolled - self.arc[j - 1]) / span);
        self.helix.point(phi) + self.helix.tangent(phi) * (self.arc[k] - rolled)
    }
}

/// Where the line from `root` touches the circle of `radius` around `axis` (both relative to
/// the circle's centre, in the plane across `axis`), on the side away from `head`: the unit
/// direction to that point, and the winding direction (±1 about `axis`) that carries the strand on
/// from the root around the circle. `None` when the root lies inside the circle.
fn outer_tangent(root: Vec3, axis: Vec3, radius: f32, head: Vec3) -> Option<(Vec3, f32)> {
    let across = root - axis * root.dot(axis);
    let distance = across.length();
    if distance <= radius * (1.0 + 1e-3) {
        return None;
    }
    let u = across / distance;
    let v = axis.cross(u);
    let (cos, sin) = (radius / distance, (1.0 - (radius / distance).powi(2)).sqrt());
    let touch = |side: f32| cos * u + side * sin * v;
    let side = if touch(1.0).dot(head) <= touch(-1.0).dot(head) { 1.0 } else { -1.0 };
    let e1 = touch(side);
    // The strand arrives along the tangent, `e1·radius − root`, and winds on the same way.
    let arriving = e1 * radius - across;
    Some((e1, if arriving.dot(axis.cross(e1)) >= 0.0 { 1.0 } else { -1.0 }))
}

/// Where a recipe obstacle is during a style.
#[derive(Clone, Copy, Debug)]
enum ObstaclePose {
    /// Where the recipe placed it.
    AtRest,
    /// Moved by a `press` stage (metres, world).
    Pressed(Vec3),
    /// Taken away by a `release`: a pressing obstacle is a styling tool, like the rods. Left at
    /// its start it held hair longer than the preset was tuned for (the blow-dry's floor under
    /// 30 cm hair), which fell as soon as a shot simulated the groom without it.
    Withdrawn,
}

struct Session {
    /// The recipe placed on the groom: world coordinates, layouts laid out as rods.
    recipe: Recipe,
    /// The groom being styled (resampled if the recipe asks), for topology and attributes.
    groom: Groom,
    sim: Simulation,
    /// Unit direction from the head centre to each strand's root (for masks).
    root_dirs: Vec<Vec3>,
    /// The head's centre (world): curlers are wound on their side away from it.
    head_center: Vec3,
    /// The rotation from coif's head axes (X side, Y up, Z front) to the head's: what is random
    /// in a direction is drawn in the head's axes, so a turned groom gets the same style.
    head_rotation: Quat,
    radii: Vec<f32>,
    /// The recipe's obstacles, where each is (pressing, or withdrawn by a `release`), and the
    /// rods.
    obstacles: Vec<Shape>,
    poses: Vec<ObstaclePose>,
    rods: Vec<Shape>,
    /// The vertices, of strands no rod winds, that were inside a rod when the rods appeared and
    /// leave it at [`ROD_PLACING_SPEED`]. Pushed out at once, a vertex 2 cm deep shot out at 2 cm
    /// per step, a speed that depended on Δt, and which side it left by was a coin flip: strands
    /// hanging through a water set's rods landed in other places at other steps (issue 15).
    threaded: Threaded,
    /// The step the rods appeared at, while vertices are leaving them.
    threaded_since: Option<u64>,
    /// Deepest a threaded vertex is inside its rod in the current stage so far (metres).
    threaded_depth: f32,
    /// Simulated seconds the last threaded vertex took to leave, once it has (for the report).
    threaded_exit: Option<f32>,
    /// Where the rods start in `active`.
    first_rod: usize,
    rods_active: bool,
    active: Vec<Shape>,
    held: Vec<usize>,
    /// Strands wound on a rod, by their first wound vertex (for curl measurements).
    wound: Vec<Option<usize>>,
    wetness: Vec<f32>,
    wetness_before: Vec<f32>,
    wetness_params: WetnessParams,
    droplets: Droplets,
    droplet_snapshots: Vec<DropletSnapshot>,
    keep_snapshots: bool,
    /// The step the droplets were scattered at.
    droplets_since: u64,
    contacts: Option<HairContacts>,
    dryer: Option<Dryer>,
    /// Evaporation multiplier while drying (0 when not drying).
    heat: f32,
    friction: Friction,
    /// The largest strand radius (for obstacle culling).
    max_radius: f32,
    // Per-step scratch.
    culling: ObstacleCulling,
    step_contacts: StepContacts,
    dv: Vec<Vec3>,
    /// Scratch: the vertices the next step leaves where they are (no contact forces needed).
    idle: Vec<bool>,
    wind_dv: Vec<f32>,
    frames: Vec<Vec<Vec3>>,
    frame_attributes: Vec<Vec<Attribute>>,
    frame_colliders: Vec<Arc<[Shape]>>,
    /// `active` as captured frames share it, until the obstacles next change.
    captured_active: Option<Arc<[Shape]>>,
    /// Steps between `--frames` frames (any real number), when frames are asked for.
    steps_per_frame: Option<f64>,
    /// Deepest penetration of the current stage so far (metres).
    penetration: f32,
    /// What the report warns of (rods that trap wound hair).
    warnings: Vec<String>,
    head_frame: Option<HeadFrame>,
}

impl Session {
    fn new(
        input: &Groom,
        recipe: &Recipe,
        options: &StyleOptions,
        frame: Option<HeadFrame>,
    ) -> Result<Session> {
        let groom = match recipe.settings.max_segment {
            Some(max) => resample_groom(input, max),
            None => input.clone(),
        };
        groom.validate()?;
        let placed = place(recipe, &groom, options.scalp.as_deref(), frame)?;
        let recipe = placed.recipe;
        let settings = &recipe.settings;
        let mut sim = Simulation::new(&groom, sim_params(&recipe))?;
        let mut warnings = Vec::new();
        if settings.sag_free {
            sim.make_sag_free();
            warnings.extend(sim.unstable_warning(&groom));
        } else {
            sim.adopt_rest_state(&groom)?;
        }

        let obstacles = placed.shapes;
        let rods = recipe
            .rods
            .iter()
            .map(|r| {
                let r = r.get_ref();
                Shape::Capsule { a: Vec3::from(r.a), b: Vec3::from(r.b), radius: r.radius }
            })
            .collect();
        // Masks see each root's direction along the head's axes (coif's X side, Y up, Z front).
        let to_head = placed.mask_rotation.inverse();
        let root_dirs = (0..groom.strand_count())
            .map(|s| (to_head * (groom.strand_points(s)[0] - placed.mask_center)).normalize_or_zero())
            .collect();
        let radii = groom.contact_radii();
        let n = groom.vertex_count();
        let wetness = match groom.attribute(wetness::WETNESS) {
            Some(a) if a.rate == AttributeRate::Vertex && a.components == 1 => a.floats().into_owned(),
            _ => vec![0.0; n],
        };
        let contacts = recipe.contacts.hair_hair.then(|| {
            let c = &recipe.contacts;
            HairContacts::new(&groom.strand_offsets, &radii, c.sample_spacing, c.hair_stiffness)
        });
        let steps_per_frame = (options.frames_per_second > 0.0)
            .then(|| 1.0 / (f64::from(options.frames_per_second) * f64::from(settings.dt)));
        let poses = vec![ObstaclePose::AtRest; obstacles.len()];
        let friction = Friction {
            static_friction: recipe.contacts.static_friction,
            dynamic_friction: recipe.contacts.dynamic_friction,
        };
        let wetness_params = recipe.wetness;
        let mut session = Session {
            recipe,
            sim,
            root_dirs,
            head_center: placed.mask_center,
            head_rotation: placed.mask_rotation,
            obstacles,
            poses,
            rods,
            rods_active: false,
            threaded: Threaded::default(),
            threaded_since: None,
            threaded_depth: 0.0,
            threaded_exit: None,
            first_rod: 0,
            active: Vec::new(),
            held: Vec::new(),
            wound: vec![None; groom.strand_count()],
            wetness_before: wetness.clone(),
            wetness,
            wetness_params,
            droplets: Droplets::default(),
            droplet_snapshots: Vec::new(),
            keep_snapshots: false,
            droplets_since: 0,
            contacts,
            dryer: None,
            heat: 0.0,
            friction,
            max_radius: radii.iter().copied().fold(0.0, f32::max),
            culling: ObstacleCulling::default(),
            step_contacts: StepContacts::default(),
            dv: vec![Vec3::ZERO; n],
            idle: Vec::new(),
            wind_dv: vec![0.0; n],
            frames: Vec::new(),
            frame_attributes: Vec::new(),
            frame_colliders: Vec::new(),
            captured_active: None,
            steps_per_frame,
            penetration: 0.0,
            head_frame: placed.frame,
            warnings,
            radii,
            groom,
        };
        session.refresh_obstacles();
        if session.wetness.iter().any(|&w| w > 0.0) {
            session.apply_mass();
        }
        if steps_per_frame.is_some() {
            session.capture_frame();
        }
        Ok(session)
    }

    /// Records a frame of `--frames` output: the positions and the [`Self::state`].
    fn capture_frame(&mut self) {
        self.frames.push(self.sim.rods().positions().to_vec());
        self.frame_attributes.push(self.state());
        let active = self.captured_active.get_or_insert_with(|| self.active.as_slice().into());
        self.frame_colliders.push(Arc::clone(active));
    }

    /// What styling changes beside the positions: the simulation's state attributes and wetness.
    fn state(&self) -> Vec<Attribute> {
        let mut state = self.sim.state_attributes();
        state.push(Attribute::new(wetness::WETNESS, AttributeRate::Vertex, 1, self.wetness.clone()));
        state
    }

    fn steps_for(&self, seconds: f32) -> u64 {
        (seconds / self.recipe.settings.dt).round().max(0.0) as u64
    }

    fn refresh_obstacles(&mut self) {
        self.active = (self.obstacles.iter().zip(&self.poses))
            .filter_map(|(shape, pose)| match *pose {
                ObstaclePose::AtRest => Some(shape.clone()),
                ObstaclePose::Pressed(offset) => Some(shape.translated(offset)),
                ObstaclePose::Withdrawn => None,
            })
            .collect();
        self.captured_active = None;
        self.first_rod = self.active.len();
        if self.rods_active {
            self.active.extend(self.rods.iter().cloned());
        } else {
            self.threaded = Threaded::default();
            self.threaded_since = None;
        }
    }

    /// Strands a mask selects, decided per strand with the recipe's seed and the stage index.
    fn masked(&self, mask: &Mask, stage: usize) -> Vec<bool> {
        let seed = self.recipe.settings.seed;
        self.root_dirs
            .iter()
            .enumerate()
            .map(|(s, &dir)| {
                mask.region.contains(dir) && unit_hash(seed, stage as u64, s as u64) < mask.fraction
            })
            .collect()
    }

    fn vertex_mask(&self, strands: &[bool]) -> Vec<bool> {
        let mut out = vec![false; self.groom.vertex_count()];
        for (s, &on) in strands.iter().enumerate() {
            if on {
                out[self.groom.strand_range(s)].fill(true);
            }
        }
        out
    }

    /// One simulation step with forces, contacts and wetness.
    fn step(&mut self) -> Result<()> {
        self.step_with(true)
    }

    /// One step of a settle: the static solve finds the rest shape of the bonds and water the
    /// hair has when it starts, so wicking and drying wait. Damp hair left to them keeps changing
    /// its hydrogen bonds, and with them its shape: the blow-dry's settle never reached its
    /// residual in its 10 s.
    fn settle_step(&mut self) -> Result<()> {
        self.step_with(false)
    }

    fn step_with(&mut self, chemistry: bool) -> Result<()> {
        let dt = self.sim.params().dt;
        self.compute_forces(dt)?;
        self.contact_step();
        if chemistry {
            self.update_wetness(dt);
        }
        // Frame k is the state at the first step at or past its time k/fps (a fixed, rounded
        // number of steps a frame played 25 fps at 25.7 and anything past 1/dt at 1/dt); above one
        // frame a step, a step's state fills the frames up to it. The slack absorbs `dt`'s f32
        // rounding, so a frame that falls on a step is that step's.
        if let Some(per) = self.steps_per_frame {
            let reached = self.sim.steps_taken() as f64;
            while self.frames.len() as f64 * per <= reached * (1.0 + 1e-6) + 1e-3 {
                self.capture_frame();
            }
        }
        Ok(())
    }

    /// The rod solver with the active obstacles' contacts.
    fn contact_step(&mut self) {
        let params = self.sim.params();
        self.step_contacts.start(
            self.sim.rods().positions(),
            params.dt,
            params.solver.judges_friction_over_the_step(),
        );
        self.culling.update(
            &self.active,
            &self.groom.strand_offsets,
            self.step_contacts.previous(),
            self.max_radius,
        );
        self.threaded.advance(ROD_PLACING_SPEED * self.sim.params().dt);
        let hooks = ContactHooks {
            shapes: &self.active,
            culling: &self.culling,
            contacts: &self.step_contacts,
            radii: &self.radii,
            friction: self.friction,
            threaded: &self.threaded,
            first_threaded: self.first_rod,
        };
        self.sim.step_with(&hooks);
        self.release_threaded();
        self.penetration = self.penetration.max(self.deepest_penetration());
    }

    /// Marks the free vertices of unwound strands whose centres lie inside a rod as it appears as
    /// leaving it, away from the head.
    fn thread_through_rods(&mut self) {
        let positions = self.sim.rods().positions();
        let mut free: Vec<bool> = self.sim.rods().kinematic().iter().map(|&k| !k).collect();
        // A wound strand is held at both ends of its free part, the root and its winding, which
        // starts where the line from the root touches the rod's outside: a vertex of that part
        // inside the rod cannot leave by passing through and stayed there, bending the rest shape
        // the perm set (the full-head perm's rods lie a vertex above the scalp: 444 of its 2,000
        // guides' first free vertices 0.3-5.7 mm deep, and their settle stalled). Held between
        // the two, its push out cannot fling the strand: it is pushed out.
        for (s, wound) in self.wound.iter().enumerate() {
            if wound.is_some() {
                free[self.groom.strand_range(s)].fill(false);
            }
        }
        let threads: Vec<Threading> = (0..positions.len())
            .into_par_iter()
            .filter(|&i| free[i])
            .filter_map(|i| {
                let p = positions[i];
                // Deeper than touching: a vertex that only overlaps a rod by less than its radius
                // is pushed out slowly (< its radius a step).
                let rod = self.rods.iter().position(|rod| rod.signed_distance(p) < 0.0)?;
                let Shape::Capsule { a, b, radius } = self.rods[rod] else {
                    unreachable!("rods are capsules")
                };
                let axis = (b - a).normalize();
                let foot = a + axis * (p - a).dot(axis).clamp(0.0, a.distance(b));
                let across = |v: Vec3| v - axis * v.dot(axis);
                // Out along the line from the rod's edge nearest the head through the vertex:
                // about the shortest way for hair on the rod's outer half, always away from the
                // head, and turning smoothly with the vertex's place. Straight out from the axis, the side
                // was a coin flip for hair hanging through the rod near its axis (the water set's
                // direct solve: one strand 1 mm from it), and the rest curves at Δt 1/240 lay
                // 7.0 % of the strand length from 1/1440's at worst.
                let outward = across(foot - self.head_center)
                    .try_normalize()
                    .unwrap_or_else(|| axis.any_orthonormal_vector());
                let origin = foot - outward * radius;
                let exit = across(p - origin).try_normalize().unwrap_or(outward);
                Some(Threading { vertex: i, rod, origin, exit, floor: (p - origin).dot(exit) })
            })
            .collect();
        self.threaded = Threaded::new(positions.len(), threads);
        self.threaded_since = (!self.threaded.is_empty()).then(|| self.sim.steps_taken());
    }

    /// A threaded vertex that has left its rod, or that the floor has carried out of it, collides
    /// with it from then on. Measures how deep the others are.
    fn release_threaded(&mut self) {
        let Some(since) = self.threaded_since else { return };
        let positions = self.sim.rods().positions();
        let (rods, radii) = (&self.rods, &self.radii);
        let depth = |t: &Threading| radii[t.vertex] - rods[t.rod].signed_distance(positions[t.vertex]);
        // The floor past the rod's far side (a diameter from the origin on its edge).
        let full = |t: &Threading| match rods[t.rod] {
            Shape::Capsule { radius, .. } => 2.0 * radius + radii[t.vertex],
            _ => unreachable!("rods are capsules"),
        };
        self.threaded.release(|t| depth(t) <= 0.0 || t.floor >= full(t));
        self.threaded_depth = self.threaded.iter().map(depth).fold(self.threaded_depth, f32::max);
        if self.threaded.is_empty() {
            let steps = self.sim.steps_taken() - since;
            self.threaded_exit = Some(steps as f32 * self.sim.params().dt);
            self.threaded_since = None;
        }
    }

    /// How deep the deepest vertex is inside an active obstacle now (a vertex leaving a rod, how
    /// far inside the rod as put in place so far). Strands a settle lets sleep are left out: they
    /// have not moved since a step measured them.
    fn deepest_penetration(&self) -> f32 {
        let positions = &self.sim.rods().positions();
        (0..self.groom.strand_count())
            .into_par_iter()
            .filter(|&strand| !self.sim.asleep(strand))
            .map(|strand| {
                let mut deepest = 0.0f32;
                for i in self.groom.strand_range(strand) {
                    let (p, radius) = (positions[i], self.radii[i]);
                    // The culling mask, looked up once and only if a shape's clearance test leaves it.
                    let mut mask = None;
                    let threading = self.threaded.get(i);
                    let passes = threading.map_or(usize::MAX, |t| self.first_rod + t.rod);
                    for (k, shape) in self.active.iter().enumerate() {
                        if k == passes {
                            deepest = deepest.max(threading.unwrap().behind(p));
                        } else if !self.culling.clear_of(k, p, radius)
                            && ObstacleCulling::tests(
                                *mask.get_or_insert_with(|| self.culling.mask(strand, p)),
                                k,
                            )
                        {
                            deepest = deepest.max(radius - shape.signed_distance(p));
                        }
                    }
                }
                deepest
            })
            .reduce(|| 0.0, f32::max)
    }

    /// Wind, hair–hair penalty and water adhesion from this step's starting positions, handed to
    /// the solver as per-vertex accelerations.
    fn compute_forces(&mut self, dt: f32) -> Result<()> {
        let positions = &self.sim.rods().positions();
        self.dv.iter_mut().for_each(|v| *v = Vec3::ZERO);
        self.wind_dv.iter_mut().for_each(|w| *w = 0.0);
        if let Some(dryer) = &self.dryer {
            let groom = &self.groom;
            self.dv.par_iter_mut().zip(self.wind_dv.par_iter_mut()).enumerate().for_each(
                |(i, (dv, wind))| {
                    let end = groom.strand_range(groom.strand_of(i)).end;
                    let tangent = if i + 1 < end {
                        positions[i + 1] - positions[i]
                    } else {
                        positions[i] - positions[i - 1]
                    };
                    let push = dryer.velocity_change(positions[i], tangent, dt);
                    *dv += push;
                    *wind = push.length();
                },
            );
        }
        if let Some(contacts) = &mut self.contacts {
            self.sim.idle_vertices(&mut self.idle);
            contacts.apply(positions, &self.radii, &self.idle, &mut self.dv, dt)?;
        }
        if let Some(water) = &self.recipe.water {
            let gravity = self.sim.params().gravity;
            // Drying hair takes up no more water: the droplets evaporate with it.
            let drying = self.heat > 0.0 || self.dryer.is_some();
            let wetness = (!drying).then_some(&mut self.wetness[..]);
            self.droplets.step(positions, &mut self.dv, wetness, gravity, dt, &water.params);
        }
        let accel = self.sim.external_acceleration_mut();
        accel.par_iter_mut().zip(self.dv.par_iter()).for_each(|(a, &dv)| *a = dv / dt);
        Ok(())
    }

    /// Evaporation (while drying) and wicking, then the bonds and masses that follow wetness.
    fn update_wetness(&mut self, dt: f32) {
        if self.heat > 0.0 || self.dryer.is_some() {
            wetness::evaporate(&mut self.wetness, &self.wind_dv, self.heat, dt, &self.wetness_params);
        }
        if self.wetness_params.diffusion > 0.0 && self.wetness.iter().any(|&w| w > 0.0) {
            wetness::diffuse_strands(
                &mut self.wetness,
                self.sim.rods().positions(),
                &self.groom.strand_offsets,
                dt,
                self.wetness_params.diffusion,
            );
        }
        self.apply_wetness_change();
    }

    /// Wetter hair loses hydrogen bonds, drier hair re-forms them in its current shape (S1-16);
    /// mass follows the water.
    fn apply_wetness_change(&mut self) {
        if self.wetness == self.wetness_before {
            return;
        }
        let (now, before) = (&self.wetness, &self.wetness_before);
        self.sim.change_bond_rates_with(BondKind::Hydrogen, |v| before[v] - now[v]);
        self.wetness_before.clone_from(&self.wetness);
        self.apply_mass();
    }

    fn apply_mass(&mut self) {
        wetness::carry_water(&mut self.sim, &self.wetness, &self.wetness_params);
    }

    fn run_steps(
        &mut self,
        steps: u64,
        progress: &Progress,
        mut each: impl FnMut(&mut Self, u64),
    ) -> Result<()> {
        for k in 0..steps {
            each(self, k);
            self.step()?;
            progress.inc(1);
        }
        Ok(())
    }

    fn run_stage(
        &mut self,
        index: usize,
        stage: &Stage,
        progress: &Progress,
    ) -> Result<Option<SettleReport>> {
        let steps = self.steps_for(stage.duration());
        match stage {
            Stage::Wet { amount, mask, .. } => {
                let vertices = self.vertex_mask(&self.masked(mask, index));
                if let Some(water) = &self.recipe.water {
                    if self.droplets.positions.is_empty() {
                        self.scatter_droplets(
                            water.droplets,
                            &vertices,
                            water.params.r_min,
                            water.params.r_max,
                        );
                    }
                }
                let increment = amount / steps.max(1) as f32;
                let amount = *amount;
                let wet = |session: &mut Self| {
                    for (w, &on) in session.wetness.iter_mut().zip(&vertices) {
                        if on && *w < amount {
                            *w = (*w + increment).min(amount);
                        }
                    }
                    session.apply_wetness_change();
                };
                if steps == 0 {
                    for w in self.wetness.iter_mut().zip(&vertices).filter(|(_, &on)| on).map(|(w, _)| w) {
                        *w = w.max(amount);
                    }
                    self.apply_wetness_change();
                }
                self.run_steps(steps, progress, |s, _| wet(s))?;
            }
            Stage::Wrap { rods, mask, .. } => {
                let strands = self.masked(mask, index);
                let chosen: Vec<usize> = if rods.is_empty() {
                    (0..self.rods.len()).collect()
                } else {
                    rods.iter()
                        .map(|name| self.recipe.rods.iter().position(|r| &r.get_ref().name == name).unwrap())
                        .collect()
                };
                let windings = self.windings(&strands, &chosen)?;
                self.warn_of_overlapping_rods(index, &windings, &chosen);
                if !self.rods_active {
                    self.rods_active = true;
                    self.thread_through_rods();
                }
                self.refresh_obstacles();
                let total = steps.max(1) as f32;
                self.run_steps(steps, progress, |s, k| {
                    s.drive(&windings, smoothstep((k + 1) as f32 / total))
                })?;
                self.drive(&windings, 1.0);
            }
            Stage::Lotion { breaks, mask, .. } => {
                let vertices = self.vertex_mask(&self.masked(mask, index));
                self.chemistry(steps, progress, breaks, -1.0, Some(&vertices))?;
            }
            Stage::Neutralise { reform, .. } => self.chemistry(steps, progress, reform, 1.0, None)?,
            Stage::Rinse { reform, .. } => {
                let amounts =
                    reform.unwrap_or(super::recipe::BondAmounts { ionic: Some(1.0), ..Default::default() });
                self.chemistry(steps, progress, &amounts, 1.0, None)?;
            }
            Stage::Process { .. } => self.run_steps(steps, progress, |_, _| {})?,
            Stage::Dry { dryer, heat, .. } => {
                self.dryer = dryer.map(|d| Dryer {
                    position: Vec3::from(d.position),
                    target: Vec3::from(d.target),
                    strength: d.strength,
                    falloff: d.falloff.unwrap_or(DEFAULT_FALLOFF),
                    cone_half_angle: d.cone_degrees.map(f32::to_radians),
                    heat: *heat,
                });
                self.heat = *heat;
                self.run_steps(steps, progress, |_, _| {})?;
                self.dryer = None;
                self.heat = 0.0;
                // Dry hair holds no droplets.
                self.snapshot_droplets();
                self.droplets = Droplets::default();
            }
            Stage::Press { obstacle, travel, direction, .. } => {
                let which =
                    self.recipe.obstacles.iter().position(|o| o.get_ref().name() == obstacle).unwrap();
                let direction = match (direction, &self.obstacles[which]) {
                    (Some(d), _) => Vec3::from(*d).normalize(),
                    (None, Shape::Plane { normal, .. }) => *normal,
                    (None, _) => Vec3::Y,
                };
                let total = steps.max(1) as f32;
                let travel = *travel;
                self.run_steps(steps, progress, |s, k| {
                    s.poses[which] =
                        ObstaclePose::Pressed(direction * travel * smoothstep((k + 1) as f32 / total));
                    s.refresh_obstacles();
                })?;
                self.poses[which] = ObstaclePose::Pressed(direction * travel);
                self.refresh_obstacles();
            }
            Stage::Release { .. } => {
                for &vertex in &self.held {
                    self.sim.detach(vertex);
                }
                self.held.clear();
                self.rods_active = false;
                for pose in &mut self.poses {
                    if let ObstaclePose::Pressed(_) = pose {
                        *pose = ObstaclePose::Withdrawn;
                    }
                }
                self.refresh_obstacles();
                self.run_steps(steps, progress, |_, _| {})?;
            }
            Stage::Settle { max_seconds, tolerance, gravity } => {
                if *gravity == Some(false) {
                    let p = self.sim.params().clone();
                    self.sim.set_step_params(p.dt, p.iterations, Vec3::ZERO, p.damping)?;
                }
                let options =
                    SettleOptions { tolerance: *tolerance, max_seconds: *max_seconds, iterations: None };
                let stage = format!("stage {}/{} settle", index + 1, self.recipe.stages.len());
                return Ok(Some(self.settle(&options, &stage, progress)?));
            }
        }
        Ok(None)
    }

    /// Changes bond rates by `sign · amount` per kind, spread evenly over the stage's steps.
    fn chemistry(
        &mut self,
        steps: u64,
        progress: &Progress,
        amounts: &super::recipe::BondAmounts,
        sign: f32,
        vertices: Option<&[bool]>,
    ) -> Result<()> {
        let kinds = [
            (BondKind::Hydrogen, amounts.hydrogen),
            (BondKind::Ionic, amounts.ionic),
            (BondKind::Disulfide, amounts.disulfide),
            (BondKind::Peptide, amounts.peptide),
        ];
        let parts = steps.max(1) as f32;
        let apply = |s: &mut Self| {
            for (kind, amount) in kinds {
                if let Some(amount) = amount {
                    let delta = sign * amount / parts;
                    s.sim.change_bond_rates_with(kind, |v| {
                        if vertices.is_none_or(|m| m[v]) {
                            delta
                        } else {
                            0.0
                        }
                    });
                }
            }
        };
        if steps == 0 {
            apply(self);
        }
        self.run_steps(steps, progress, |s, _| apply(s))
    }

    /// The static solve (`sim::settle`) with this session's forces and contacts, its chemistry
    /// held ([`Self::settle_step`]). Its progress names `stage` and the residual reached so far.
    fn settle(&mut self, options: &SettleOptions, stage: &str, progress: &Progress) -> Result<SettleReport> {
        let budget = self.steps_for(options.max_seconds);
        let mut shown = f32::NAN;
        let mut show = |report: &SettleReport| {
            let residual = report.force_residual.max(report.torque_residual);
            if residual.is_finite() && residual != shown {
                shown = residual;
                progress
                    .set_message(&format!("{stage}, residual {residual:.1e} of {:.0e}", report.tolerance));
            }
        };
        let tick = |report: &SettleReport| {
            show(report);
            progress.inc_open(1);
        };
        let report = settle_with(self, |s| &mut s.sim, Self::settle_step, Self::touched, options, tick)?;
        // The last probe's residual: the one the settle ended on.
        show(&report);
        progress.inc_open(budget.saturating_sub(report.steps));
        Ok(report)
    }

    /// The strands that vertices of `from` strands touch now (none without hair–hair contacts).
    fn touched(&mut self, from: &(dyn Fn(usize) -> bool + Sync), touched: &mut Vec<bool>) {
        match &self.contacts {
            Some(contacts) => {
                contacts.strands_touched(self.sim.rods().positions(), &self.radii, from, touched)
            }
            None => touched.clear(),
        }
    }

    /// Poses every wound strand at stage time `t ∈ [0, 1]`. The path from the strand's shape to
    /// the rod may cross the head or other rods: poses are pushed out of every active obstacle
    /// and rod (the finished helix lies on its own rod's surface, where the push is zero).
    fn drive(&mut self, windings: &[Winding], t: f32) {
        // A pose outside a shape's box grown by the radius and a margin far above the rounding
        // of `distance` is clear of it: skipping it changes no target. (Every vertex against
        // every rod was most of a full-head wrap's step.)
        const CLEAR: f32 = 1e-4;
        let solids: Vec<(&Shape, Option<(Vec3, Vec3)>)> =
            self.active.iter().map(|shape| (shape, shape.bounds())).collect();
        let radii = &self.radii;
        // Every winding's targets in winding order, in one buffer.
        let targets: Vec<Vec3> = windings
            .par_iter()
            .flat_map_iter(|w| {
                (w.first..w.end).enumerate().map(|(k, vertex)| {
                    let mut target = w.pose(k, t);
                    let reach = radii[vertex] + CLEAR;
                    for (shape, bounds) in &solids {
                        if bounds.is_some_and(|(lo, hi)| {
                            target.cmplt(lo - reach).any() || target.cmpgt(hi + reach).any()
                        }) {
                            continue;
                        }
                        let (distance, normal) = shape.distance(target);
                        let depth = radii[vertex] - distance;
                        if depth > 0.0 {
                            target += normal * depth;
                        }
                    }
                    target
                })
            })
            .collect();
        let vertices = windings.iter().flat_map(|w| w.first..w.end);
        for (vertex, target) in vertices.zip(targets) {
            self.sim.attach(vertex, target);
        }
    }

    /// Assigns each selected strand to the nearest of `rods` and lays its vertices, from the one
    /// nearest the rod to the tip, on a tight helix around it (chords keep the rest lengths).
    fn windings(&mut self, strands: &[bool], rods: &[usize]) -> Result<Vec<Winding>> {
        let mut windings = Vec::new();
        let positions = self.sim.rods().positions().to_vec();
        for (s, _) in strands.iter().enumerate().filter(|(_, &on)| on) {
            let range = self.groom.strand_range(s);
            // Nearest rod and the strand's vertex nearest to it (never the root).
            let mut best: Option<(f32, usize, usize)> = None;
            for &r in rods {
                for (v, &p) in positions.iter().enumerate().take(range.end).skip(range.start + 1) {
                    let d = self.rods[r].distance(p).0;
                    if best.is_none_or(|(bd, _, _)| d < bd) {
                        best = Some((d, r, v));
                    }
                }
            }
            let Some((_, r, mut first)) = best else { continue };
            let Shape::Capsule { a, b, radius } = self.rods[r] else { unreachable!("rods are capsules") };
            let axis = (b - a).normalize();
            // Directions away from the rod's axis (not from a foot on an end cap, which would tilt
            // the helix into the cap).
            let length = a.distance(b);
            let away = |p: Vec3| {
                let d = p - a;
                (d - axis * d.dot(axis)).try_normalize().unwrap_or_else(|| axis.any_orthonormal_vector())
            };
            // The winding starts where the line from the root touches the rod on its outer side
            // (away from the head) and turns on from there: where it starts and which way it
            // turns depend on the root and the rod alone. Taken from the strand's pre-wound shape
            // (the side of the rod it passes, the way it heads there) they were coin flips for a
            // strand hanging through the rod near its axis, and a flip moved its tip by the
            // curl's diameter between runs at different Δt.
            let root = range.start;
            let along = (positions[first] - a).dot(axis).clamp(0.0, length);
            let centre = a + axis * along;
            let winding_radius = radius + self.radii[first];
            let (e1, turn) =
                outer_tangent(positions[root] - centre, axis, winding_radius, self.head_center - centre)
                    .unwrap_or_else(|| {
                        // A root inside the winding circle: the side and the way the strand heads.
                        let e1 = away(positions[first]);
                        let heading = positions[(first + 1).min(range.end - 1)] - positions[first];
                        (e1, if heading.dot(axis.cross(e1)) >= 0.0 { 1.0 } else { -1.0 })
                    });
            let contact = centre + e1 * winding_radius;
            // The free part between root and rod must reach the rod: start winding further
            // along the strand until its rest length spans the gap (else the vertices between
            // a pinned root and a held winding are pulled apart and shake).
            while first + 1 < range.end {
                let slack: f32 = self.sim.rods().rest_lengths()[root..first].iter().sum();
                if positions[root].distance(contact) <= 0.95 * slack {
                    break;
                }
                first += 1;
            }
            if first + 1 >= range.end {
                continue; // only the tip reaches the rod: nothing to wind
            }
            let e2 = axis.cross(e1);
            let advance = if along < 0.5 * length { 1.0 } else { -1.0 };
            // Turns a few hair widths apart: a tight, nearly planar curl.
            let pitch = 8.0 * self.radii[first];
            let helix = Helix {
                origin: a + axis * along,
                axis: axis * advance,
                e1,
                e2: e2 * turn,
                radius: winding_radius,
                advance: pitch / std::f32::consts::TAU,
            };
            let (mut arc, mut phi) = (vec![0.0f32], vec![0.0f32]);
            for v in first + 1..range.end {
                let chord = self.sim.rods().rest_lengths()[v - 1];
                if chord >= 2.0 * winding_radius {
                    return Err(Error::Usage(format!(
                        "strand {s}: a {chord:.4} m segment cannot wrap a rod of radius {radius} m; \
                         set [settings] max_segment below the rod's diameter"
                    )));
                }
                arc.push(arc[arc.len() - 1] + chord);
                phi.push(phi[phi.len() - 1] + 2.0 * (chord / (2.0 * winding_radius)).asin());
            }
            let start = positions[first..range.end].to_vec();
            self.held.extend(first..range.end);
            self.wound[s] = Some(first);
            windings.push(Winding { rod: r, first, end: range.end, start, arc, phi, helix });
        }
        Ok(windings)
    }

    /// Curlers are solid, but a recipe may let two rods overlap (a ring of rods closed at its
    /// ends). A strand whose finished helix runs into another rod is held inside one of the two
    /// (the full-head perm's rods once overlapped by up to 9 mm and held strands 6.7 mm inside):
    /// each such pair of rods is a warning with the overlap and the strands it traps.
    fn warn_of_overlapping_rods(&mut self, stage: usize, windings: &[Winding], rods: &[usize]) {
        // Deeper than contact round-off: the push out of the other rod moves the pose.
        const SLOP: f32 = 1e-4;
        let mut trapped = std::collections::BTreeMap::<(usize, usize), usize>::new();
        for w in windings {
            let finished: Vec<(Vec3, f32)> =
                (0..w.end - w.first).map(|k| (w.pose(k, 1.0), self.radii[w.first + k])).collect();
            let others = rods.iter().filter(|&&o| o != w.rod);
            let into = others
                .filter(|&&o| finished.iter().any(|&(p, radius)| self.rods[o].distance(p).0 < radius - SLOP));
            for &o in into {
                *trapped.entry((w.rod, o)).or_default() += 1;
            }
        }
        for ((rod, other), strands) in trapped {
            let (Shape::Capsule { a, b, radius }, Shape::Capsule { a: c, b: d, radius: r }) =
                (&self.rods[rod], &self.rods[other])
            else {
                unreachable!("rods are capsules")
            };
            let gap = segment_distance(*a, *b, *c, *d) - radius - r;
            let between = if gap < 0.0 {
                format!("overlapping it by {:.1} mm", -gap * 1e3)
            } else {
                format!("{:.1} mm from it", gap * 1e3)
            };
            let name = |k: usize| &self.recipe.rods[k].get_ref().name;
            self.warnings.push(format!(
                "stage {} (wrap): strands wound on rod '{}' that run into rod '{}' ({between}): \
                 {strands}; they are held inside one of the two; shorten or move a rod",
                stage + 1,
                name(rod),
                name(other),
            ));
        }
    }

    /// Keeps the droplets and the hair they hold, for children to clump by (`crate::guides`).
    fn snapshot_droplets(&mut self) {
        if !self.keep_snapshots {
            return;
        }
        if let (Some(water), false) = (&self.recipe.water, self.droplets.positions.is_empty()) {
            let hair = self.sim.rods().positions().to_vec();
            // A frame captured at this very moment comes after the snapshot (it shows the clumps).
            let now = self.frames.last() == Some(&hair);
            self.droplet_snapshots.push(DropletSnapshot {
                droplets: self.droplets.positions.clone(),
                hair,
                frames_before: self.frames.len() - now as usize,
                params: water.params,
                steps: self.sim.steps_taken() - self.droplets_since,
            });
        }
    }

    /// Droplets at random masked vertices, nudged off the strand by a seeded offset.
    fn scatter_droplets(&mut self, count: usize, vertices: &[bool], r_min: f32, r_max: f32) {
        let candidates: Vec<usize> = (0..vertices.len()).filter(|&v| vertices[v]).collect();
        if candidates.is_empty() {
            return;
        }
        let seed = self.recipe.settings.seed;
        let positions = (0..count as u64)
            .map(|k| {
                let v = candidates
                    [(unit_hash(seed, 0xD809, k) * candidates.len() as f32) as usize % candidates.len()];
                let dir = Vec3::new(unit_hash(seed, 1, k), unit_hash(seed, 2, k), unit_hash(seed, 3, k))
                    * 2.0
                    - 1.0;
                let dir = self.head_rotation * dir.normalize_or_zero();
                self.sim.rods().positions()[v] + dir * (0.5 * (r_min + r_max))
            })
            .collect();
        self.droplets = Droplets::new(positions);
        self.droplets_since = self.sim.steps_taken();
    }

    fn stage_report(
        &self,
        index: usize,
        stage: &Stage,
        steps: u64,
        wall_seconds: f64,
        settle: Option<SettleReport>,
    ) -> StageReport {
        let positions = &self.sim.rods().positions();
        let strands = self.groom.strand_count();
        let curvature: f32 =
            (0..strands).map(|s| mean_curvature(&positions[self.groom.strand_range(s)])).sum::<f32>()
                / strands.max(1) as f32;
        let any_wound = self.wound.iter().any(Option::is_some);
        let median_curl = |points: &[Vec3]| {
            let mut radii: Vec<f32> = (0..strands)
                .filter_map(|s| {
                    let range = self.groom.strand_range(s);
                    match self.wound[s] {
                        Some(first) => curl_radius(&points[first..range.end]),
                        None if !any_wound => curl_radius(&points[range]),
                        None => None,
                    }
                })
                .collect();
            radii.sort_by(f32::total_cmp);
            radii.get(radii.len() / 2).copied()
        };
        let mean = |kind: BondKind| {
            let rates = self.sim.bonds.rates(kind);
            let centres: Vec<f32> = self.sim.rods().pair_centres().map(|v| rates[v]).collect();
            // Strands of one segment have no bonds: none is broken (an empty sum is -0.0).
            match centres.len() {
                0 => 1.0,
                n => centres.iter().sum::<f32>() / n as f32,
            }
        };
        StageReport {
            index,
            kind: stage.kind(),
            seconds: steps as f32 * self.sim.params().dt,
            steps,
            wall_seconds,
            mean_curvature: curvature,
            curl_radius: median_curl(positions),
            rest_curl_radius: median_curl(&self.sim.rest_curves()),
            bond_rates: BondRates {
                hydrogen: mean(BondKind::Hydrogen),
                ionic: mean(BondKind::Ionic),
                disulfide: mean(BondKind::Disulfide),
                peptide: mean(BondKind::Peptide),
            },
            wetness: self.wetness.iter().sum::<f32>() / self.wetness.len().max(1) as f32,
            max_penetration: self.penetration,
            threaded_max_depth: self.threaded_depth,
            threaded_exit_seconds: self.threaded_exit,
            settle,
        }
    }
}

/// The simulation settings a recipe asks for (also for simulating its output again).
pub fn sim_params(recipe: &Recipe) -> SimParams {
    let settings = &recipe.settings;
    let b = &recipe.bonds;
    SimParams {
        dt: settings.dt,
        iterations: settings.iterations,
        gravity: Vec3::from(settings.gravity),
        damping: settings.damping,
        material: Material {
            density: settings.density,
            youngs_modulus: settings.youngs_modulus,
            shear_modulus: settings.shear_modulus,
            cuticle: Cuticle { peel_per_metre: settings.cuticle_peel_per_metre, ..Cuticle::default() },
            ..Material::default()
        },
        influences: BondInfluences([b.hydrogen, b.ionic, b.disulfide, b.peptide]),
        ..SimParams::for_solver(settings.solver)
    }
}

/// The recipe's obstacles as collider shapes at rest (no pressing offsets, no rods), placed on
/// `groom` in `frame` exactly as a styling run places them (the groom's scalp).
pub fn obstacle_shapes(
    recipe: &Recipe,
    groom: &Groom,
    scalp: Option<&TriangleMesh>,
    frame: Option<HeadFrame>,
) -> Result<Vec<Shape>> {
    Ok(place(recipe, groom, scalp, frame)?.shapes)
}

fn smoothstep(t: f32) -> f32 {
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// A number in [0, 1) from a seed and two indices (SplitMix64), the same on every machine.
fn unit_hash(seed: u64, a: u64, b: u64) -> f32 {
    let mut z = seed ^ a.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ b.wrapping_mul(0xD1B5_4A32_D192_ED03);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 40) as f32 / (1u64 << 24) as f32
}
