//! The simulation core: strands as Cosserat rods solved with position-based dynamics
//! (Kugelstadt & Schömer 2016; model.md §1), side-chain bond plasticity (§2), cuticle stiffness
//! gradient, and settling (§6).
//!
//! ```text
//! Groom ──Simulation::new──▶ Rods + Bonds ──step()…──▶ settle() ──write_to_groom()──▶ Groom
//! ```
//!
//! * [`rod`]: state from a groom (positions, velocities, masses, edge frames parallel-transported
//!   from a root frame, rest lengths, rest Darboux vectors of the imported shape).
//! * [`constraints`]: stretch–shear and bend–twist projections.
//! * [`bonds`]: the four bond kinds, S1-15 rest shape, S1-16 breaking and re-forming.
//! * [`cuticle`]: S1-13/14 stiffness gradient.
//! * [`solver`]: the stepper: per iteration a direct (block-tridiagonal) solve of every edge's
//!   stretch–shear along the strand, then Gauss–Seidel sweeps of stretch–shear and
//!   bend–twist along each strand, alternating direction; strands in parallel. With
//!   [`StrandSolver::Direct`] each iteration instead solves both constraints of the free tail
//!   together (`strand_solve`, 6×6 blocks); the held span before it (root to a winding) gets
//!   the direct stretch–shear solve and the sweeps.
//! * [`settle`]: static equilibrium with a convergence report; zero-stress rest curves; export.
//!
//! # Stiffness: XPBD with physical moduli
//! Bend–twist uses the compliance form (`α = l̄/(4·E·I)` from the Young's and shear moduli and the
//! groom's widths, scaled by the cuticle factor); stretch–shear is hard. For converged iterations
//! the static shape then depends only on the moduli, not on Δt or the iteration count
//! (`tests/sim_invariance.rs`). The seed's `k' = 1 − (1 − k)^(1/n)` only removes the
//! iteration-count dependence: its per-step stiffness makes the sag under gravity scale with Δt²
//! (one constraint with per-step stiffness `k` under a pull `g·Δt²` per step settles at an error
//! `g·Δt²·(1 − k)/k`; XPBD's settles at `g·α/w`, independent of Δt).
//!
//! Two further choices keep the static shape independent of the iteration count and of how
//! finely a strand is cut. **Stretch–shear is solved directly** once per iteration: the
//! constraints `x_{e+1} − x_e = l_e·d3(q_e)` of all edges, in the vertices and the edge frames
//! together, form a block-tridiagonal system (3×3 blocks, linear time per strand). Gauss–Seidel
//! alone carries a correction one edge per sweep, so a loaded strand kept a stretch and a shear
//! that fell only like 1/iterations: a cantilever of 2 mm segments sagged 7× beam theory at 5
//! iterations, and strands hanging at Δt 1/30 stretched to 3× their length. Now the cantilever
//! matches Euler–Bernoulli for its discrete clamp (half an edge out, see below) within 2 % for 2 mm
//! to 3 cm segments at 5, 10 and 20 iterations, and hanging strands stretch 2e-6 at Δt 1/30
//! (`cargo bench --bench accuracy`, `tests/sim_invariance.rs`). The solve covers the whole strand,
//! spans held at both ends included (a root and a winding held on a curler rod): such a span can be
//! shorter than its gap, and hard constraints solved exactly would then pull it apart at metres
//! per second, so a span tauter than 0.98 of its rest length (`solver::HELD_SPAN_SLACK`) is
//! stretched evenly for the solve; left to Gauss–Seidel it stretched under its load by an amount
//! that depended on Δt, and the perm baked that into its rest curves. Bend–twist stays
//! Gauss–Seidel: the frame inertia is a conditioning parameter ([`SimParams::frame_inertia_factor`]), capped at
//! the bending compliance `α/Δt²`, which keeps the bend–twist system well conditioned (extra
//! bend–twist sweeps change a cantilever's sag by < 1 %). Frames are quasi-static (no angular
//! velocity): integrating frame angular velocities made resting curls creep.
//!
//! **Limits.** The pinned root frame clamps the whole first edge, so the discrete clamp sits half
//! an edge out (a cantilever of n segments sags `(1 − 1/(2n))⁴` of beam theory for its full
//! length: 0.77 for 8 segments, 0.94 for 32); a bending hinge of half length between the root's
//! orientation and a free first frame would remove it. Quasi-static frames act as a drag on
//! bending; their inertia is scaled with the step ([`FRAME_DRAG_DT`]) so that the drag is a rate
//! per second and dynamic stages (press, wind, blow-dry) bake the same rest shapes at any Δt
//! (`cargo bench --bench accuracy -- invariance`). The direct solve of stretch–shear and
//! bend–twist together (Deul et al. 2018, [`StrandSolver::Direct`]) converges with frames ten
//! times lighter ([`StrandSolver::frame_inertia_factor`]).
//!
//! # Speed
//! Groups of 8 consecutive strands with equal vertex counts are solved together, one strand per
//! SIMD lane (`lanes`, AVX when the CPU has it, same bits as SSE2; a [`Hooks::project`] callback
//! is called one lane at a time); other strands go through the scalar path. With
//! [`StrandSolver::Direct`] such a group's strands are solved 4 at a time in f64 lanes, with the
//! bits of the one-strand solve (`strand_solve`, `lane_algebra`). No allocation happens
//! in a step after the first. `cargo bench --bench sim` prints ns per vertex-iteration, and the cost
//! of a step at a stated accuracy for both solvers (`-- step`).
//!
//! # Extension points (for interactions and recipes)
//! * **External acceleration**: [`Simulation::external_acceleration_mut`] (per vertex, m/s², added to
//!   gravity before prediction: wind, water adhesion, penalty forces computed from a snapshot), and
//!   [`Hooks::accelerate`] (per strand, may read the strand's positions and edit velocities).
//! * **Position projection**: [`Hooks::project`], called once per iteration per strand after the
//!   constraints (head, floor, curler rods). It may only move vertices with non-zero inverse mass.
//!   The direct stretch–shear solve sees touching vertices with their own inverse mass: holding
//!   them in it (inverse mass × 0.01 for the rest of the step) fought the projection every step
//!   and left settles 10× further from rest (`make demo`: force residual 1.06e-1 against 1.02e-2;
//!   × 0.1: 3.0e-2). Hooks run concurrently on different strands; anything they read from other
//!   strands must be a snapshot taken before the step, so results stay independent of thread
//!   count.
//! * **Mass scale**: [`Simulation::set_mass_scale`] (wet hair is heavier).
//! * **Kinematic attachment**: [`Simulation::attach`] / [`Simulation::detach`] pin any vertex to a
//!   moving target (winding on rods); [`Simulation::set_root`] drives root vertex and frame
//!   (an animated head).
//! * **Bond rates**: [`Simulation::change_bond_rate`], [`Simulation::set_bond_rate`] (uniform, per
//!   strand or per vertex via [`BondTarget`]) and [`Simulation::change_bond_rates_with`] (a
//!   per-vertex field such as wetness).
pub mod bonds;
pub mod constraints;
pub mod cuticle;
pub mod driver;
mod lane_algebra;
mod lanes;
pub mod rod;
pub mod sag_free;
pub mod settle;
pub mod solver;
mod strand_solve;

use glam::{Quat, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

pub use bonds::{BondInfluences, BondKind, Bonds};
pub use cuticle::Cuticle;
pub use rod::{Material, Rods};
pub use settle::{SettleOptions, SettleReport};

use crate::error::{Error, Result};
use crate::groom::{AttributeRate, Groom};

/// Simulation settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimParams {
    /// Time step, seconds (Table 1: 1/360).
    pub dt: f32,
    /// Solver iterations per step (Table 1: 5).
    pub iterations: u32,
    /// m/s².
    pub gravity: Vec3,
    /// Velocity damping rate, 1/s (velocities decay as `exp(−damping·t)`).
    pub damping: f32,
    pub material: Material,
    pub influences: BondInfluences,
    /// Frame inverse inertia relative to the vertices' at Δt [`FRAME_DRAG_DT`] (see
    /// [`Rods::update_inverse_masses`]); at other steps it is scaled by `FRAME_DRAG_DT / Δt`.
    pub frame_inertia_factor: f32,
    /// How each iteration solves a strand's constraints.
    #[serde(default)]
    pub solver: StrandSolver,
}

/// The time step at which [`SimParams::frame_inertia_factor`] is the frames' inverse inertia.
/// Frames are quasi-static: a frame turns by `w_q·τ·Δt²` a step under a torque `τ` (until the
/// bending compliance caps it), a turn rate of `w_q·τ·Δt` — a drag on every bend whose rate
/// would shrink with Δt at a fixed inertia. Scaling `w_q` by `FRAME_DRAG_DT / Δt` makes the drag a
/// rate per second, the same at every Δt. At a fixed inertia the water set baked rest curves
/// 2.0 % (mean) of the strand length apart at Δt 1/240 and 1/720, 1.8 % at 1/720 and 1/1440 and 1.3 %
/// at 1/1440 and 1/2880: the look drifted further with every halving of the step.
pub const FRAME_DRAG_DT: f32 = 1.0 / 360.0;

/// How each solver iteration solves a strand's constraints.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StrandSolver {
    /// Stretch–shear solved directly along the strand, then Gauss–Seidel sweeps of both
    /// constraints (SIMD lanes of 8 strands). Bend–twist converges slowly on stiff, finely cut
    /// strands, so their static shape depends on Δt.
    #[default]
    GaussSeidel,
    /// Stretch–shear and bend–twist of the free tail solved together, directly (`strand_solve`):
    /// a Newton step per iteration, so the static shape is the elastic one at any Δt.
    Direct,
}

impl StrandSolver {
    /// The frame inertia each solver runs with by default ([`SimParams::frame_inertia_factor`]).
    /// Frames are quasi-static, so their inertia drags on every bend: the lighter the frames, the
    /// faster a bend relaxes during a dynamic stage. Gauss–Seidel needs heavy frames
    /// to converge (with `1.0` a straight sag-free groom moved 3.9 mm in 2 s instead of < 1 mm);
    /// the direct solve converges with frames as heavy as their edge's vertices. Both at
    /// Δt [`FRAME_DRAG_DT`]; the inertia scales with the step.
    pub fn frame_inertia_factor(self) -> f32 {
        match self {
            StrandSolver::GaussSeidel => 0.1,
            StrandSolver::Direct => 1.0,
        }
    }

    /// Whether obstacle friction is judged on a contact's pushes summed over the step
    /// ([`crate::interact::obstacles::Friction`]) rather than on each iteration's push alone.
    /// The direct solve needs the sum: its later iterations push by almost nothing, and hair
    /// lying on the head crept for ever. Gauss–Seidel keeps the one-iteration rule for now: with
    /// the sum its full-head perm settles a little faster (23.5 s simulated against 24.9 s), but
    /// the guided wavy children of `tests/guides.rs` read +5.1 % looser than their guides (bound
    /// 5 %, +4.7 % with the one-iteration rule), a loosening issue 16 still has open.
    pub fn judges_friction_over_the_step(self) -> bool {
        self == StrandSolver::Direct
    }
}

impl Default for SimParams {
    fn default() -> Self {
        SimParams {
            dt: 1.0 / 360.0,
            iterations: 5,
            gravity: Vec3::new(0.0, -9.8, 0.0),
            damping: 2.0,
            material: Material::default(),
            influences: BondInfluences::default(),
            frame_inertia_factor: StrandSolver::default().frame_inertia_factor(),
            solver: StrandSolver::default(),
        }
    }
}

impl SimParams {
    /// The defaults for `solver`, with its own frame inertia.
    pub fn for_solver(solver: StrandSolver) -> SimParams {
        SimParams { solver, frame_inertia_factor: solver.frame_inertia_factor(), ..SimParams::default() }
    }

    pub fn check(&self) -> Result<()> {
        let bad = |what: String| Err(Error::Usage(format!("simulate: {what}")));
        let m = &self.material;
        // The same ranges recipes and flags are held to (`crate::validate`).
        for (key, value, range) in [
            ("time step", f64::from(self.dt), crate::validate::TIME_STEP),
            ("iterations", f64::from(self.iterations), crate::validate::ITERATIONS),
            ("density", m.density.into(), crate::validate::DENSITY),
            ("Young's modulus", m.youngs_modulus.into(), crate::validate::MODULUS),
            ("shear modulus", m.shear_modulus.into(), crate::validate::MODULUS),
        ] {
            crate::validate::number(key, value, range).or_else(bad)?;
        }
        if !self.gravity.is_finite() {
            return bad("gravity must be finite".into());
        }
        if !(self.damping.is_finite() && self.damping >= 0.0) {
            return bad(format!("damping {} must be a non-negative rate", self.damping));
        }
        if [m.fallback_width, self.frame_inertia_factor].iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return bad("fallback width and frame inertia factor must be positive".into());
        }
        if let Err(message) = self.influences.check() {
            return bad(message);
        }
        Ok(())
    }
}

/// Per-strand (or per-vertex) callbacks inside a step. Both run concurrently for different
/// strands; `first_vertex` is the strand's offset in the groom-wide arrays.
pub trait Hooks: Sync {
    /// Edit velocities after gravity and external acceleration, before prediction.
    fn accelerate(
        &self,
        _strand: usize,
        _first_vertex: usize,
        _positions: &[Vec3],
        _velocities: &mut [Vec3],
        _dt: f32,
    ) {
    }
    /// Project positions onto obstacles, once per solver iteration. Must leave vertices whose
    /// inverse mass is 0 where they are.
    fn project(
        &self,
        _strand: usize,
        _first_vertex: usize,
        _positions: &mut [Vec3],
        _inverse_masses: &[f32],
    ) {
    }
    /// Whether [`project`](Self::project) does anything; solvers skip the call (and, in SIMD
    /// lanes, copying each lane's positions out and back) when it does not.
    fn projects(&self) -> bool {
        true
    }
    /// Regions outside all of which [`project`](Self::project) leaves every vertex where it is,
    /// if the hooks know such (`None`: no promise). SIMD lanes test their vertices against them
    /// at once and call `project` only for strands with a vertex inside one.
    fn exclusions(&self) -> Option<&[Exclusion]> {
        None
    }
}

/// The ellipsoidal region `|to_unit · (p − center)|² ≤ limit`.
#[derive(Clone, Copy, Debug)]
pub struct Exclusion {
    pub center: Vec3,
    pub to_unit: glam::Mat3,
    pub limit: f32,
}

/// No callbacks.
pub struct NoHooks;
impl Hooks for NoHooks {
    fn projects(&self) -> bool {
        false
    }
}

/// Which edge pairs a bond-rate change applies to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BondTarget {
    All,
    Strand(usize),
    Vertex(usize),
}

/// Energies of the current state, joules.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Energy {
    pub kinetic: f64,
    /// Relative to the origin: `−Σ m·g·x`.
    pub gravitational: f64,
    /// Bend–twist energy against the bonds' zero-stress shape.
    pub elastic: f64,
}

impl Energy {
    pub fn total(&self) -> f64 {
        self.kinetic + self.gravitational + self.elastic
    }
}

/// A groom being simulated.
#[derive(Clone, Debug)]
pub struct Simulation {
    params: SimParams,
    rods: Rods,
    pub bonds: Bonds,
    masses_dirty: bool,
    /// Δt the cached projection constants were computed for.
    coefficients_dt: f32,
    steps: u64,
    /// Per strand, whether the settle has found it at rest and lets it sleep: a step leaves the
    /// strands of a work unit (a SIMD lane group or a lone strand) as they are when all of them
    /// sleep. Empty whenever no strand sleeps (always outside a settle).
    asleep: Vec<bool>,
}

/// Refuses per-vertex bond rates and wetness outside [0, 1] up to round-off (both are fractions):
/// a wetness of -10 or a rate of -100 was clamped without a word, simulating a groom other than
/// the file's.
fn check_fractions(groom: &Groom) -> Result<()> {
    let names = BondKind::ALL.iter().map(|k| k.attribute_name()).chain([crate::interact::wetness::WETNESS]);
    for name in names {
        let Some(attribute) = groom.attribute(name) else { continue };
        if attribute.rate != AttributeRate::Vertex || attribute.components != 1 {
            continue;
        }
        // Up to round-off: a blend of rates (children's, interpolated from guides) lands a few
        // ulps past 1, and is clamped as any rate is.
        let values = attribute.floats();
        if let Some(vertex) = values.iter().position(|v| !(-1e-5..=1.0 + 1e-5).contains(v)) {
            let (strand, index) = groom.strand_and_vertex(vertex);
            return Err(Error::Groom(crate::groom::GroomError::BadAttribute {
                name: name.to_string(),
                problem: format!(
                    "strand {strand}, vertex {index}: {} is outside [0, 1] (a fraction)",
                    crate::validate::shortest(values[vertex].into())
                ),
            }));
        }
    }
    Ok(())
}

impl Simulation {
    /// Rods at rest in the groom's shape, all bonds intact and remembering that shape. Bond rates
    /// the groom carries as `bond_*` attributes are applied (as breaking, so shapes stay).
    pub fn new(groom: &Groom, params: SimParams) -> Result<Simulation> {
        params.check()?;
        groom.validate()?;
        let rods = Rods::from_groom(groom, &params.material, params.frame_inertia_factor)?;
        let bonds = Bonds::new(params.influences, rods.rest_darboux());
        let mut sim = Simulation {
            params,
            rods,
            bonds,
            masses_dirty: true,
            coefficients_dt: 0.0,
            steps: 0,
            asleep: Vec::new(),
        };
        check_fractions(groom)?;
        for kind in BondKind::ALL {
            if let Some(attribute) = groom.attribute(kind.attribute_name()) {
                if attribute.rate != AttributeRate::Vertex || attribute.components != 1 {
                    return Err(Error::Groom(crate::groom::GroomError::BadAttribute {
                        name: attribute.name.clone(),
                        problem: "must be one float per vertex to drive bond rates".into(),
                    }));
                }
                let rates = attribute.floats().into_owned();
                sim.set_bond_rates_with(kind, |vertex| rates[vertex]);
            }
        }
        Ok(sim)
    }

    pub fn params(&self) -> &SimParams {
        &self.params
    }

    /// The rods' state (read-only: change it through the methods below).
    pub fn rods(&self) -> &Rods {
        &self.rods
    }

    /// Changes time step, iterations, gravity or damping (material and influences are fixed).
    pub fn set_step_params(&mut self, dt: f32, iterations: u32, gravity: Vec3, damping: f32) -> Result<()> {
        let params = SimParams { dt, iterations, gravity, damping, ..self.params.clone() };
        params.check()?;
        self.params = params;
        Ok(())
    }

    /// Changes the frames' inverse inertia relative to the vertices' ([`SimParams::frame_inertia_factor`]):
    /// a conditioning choice that leaves static shapes unchanged but sets how fast bending relaxes.
    pub fn set_frame_inertia_factor(&mut self, factor: f32) -> Result<()> {
        let params = SimParams { frame_inertia_factor: factor, ..self.params.clone() };
        params.check()?;
        self.params = params;
        self.masses_dirty = true;
        Ok(())
    }

    /// Whether a settle lets `strand` sleep: steps leave it where it is.
    pub fn asleep(&self, strand: usize) -> bool {
        self.asleep.get(strand).copied().unwrap_or(false)
    }

    /// Writes to `idle` whether the next step leaves each vertex where it is: kinematic vertices
    /// and the strands a settle lets sleep (forces on them are not needed).
    pub fn idle_vertices(&self, idle: &mut Vec<bool>) {
        idle.clear();
        idle.extend_from_slice(self.rods.kinematic());
        for (strand, _) in self.asleep.iter().enumerate().filter(|(_, &asleep)| asleep) {
            idle[self.rods.strand_range(strand)].fill(true);
        }
    }

    pub fn steps_taken(&self) -> u64 {
        self.steps
    }

    /// Advances one time step.
    pub fn step(&mut self) {
        self.step_with(&NoHooks);
    }

    /// Advances one time step with callbacks.
    pub fn step_with(&mut self, hooks: &dyn Hooks) {
        if self.masses_dirty || self.coefficients_dt != self.params.dt {
            self.rods
                .update_inverse_masses(self.params.frame_inertia_factor * FRAME_DRAG_DT / self.params.dt);
            self.rods.update_coefficients(self.params.dt);
            self.masses_dirty = false;
            self.coefficients_dt = self.params.dt;
        }
        let constants = solver::StepConstants {
            dt: self.params.dt,
            iterations: self.params.iterations,
            gravity: self.params.gravity,
            velocity_keep: (-self.params.damping * self.params.dt).exp(),
            direct: self.params.solver == StrandSolver::Direct,
        };
        let (bonded, broken) = self.bonds.affine();
        solver::step_all(&mut self.rods, bonded, broken, &self.asleep, &constants, hooks);
        self.steps += 1;
    }

    /// Runs whole steps covering `seconds`; returns the number of steps taken.
    pub fn run(&mut self, seconds: f32, hooks: &dyn Hooks) -> u64 {
        let steps = (seconds / self.params.dt).round().max(0.0) as u64;
        (0..steps).for_each(|_| self.step_with(hooks));
        steps
    }

    /// Moves a strand's root vertex and root frame (kinematic: an animated head drives them).
    /// The frame's third director should point along the first edge.
    pub fn set_root(&mut self, strand: usize, position: Vec3, frame: Quat) {
        let first = self.rods.strand_range(strand).start;
        self.rods.kinematic_targets_mut()[first] = position;
        self.rods.frames_mut()[first] = frame.normalize();
    }

    /// The strand's root frame.
    pub fn root_frame(&self, strand: usize) -> Quat {
        self.rods.frames()[self.rods.strand_range(strand).start]
    }

    /// Makes a vertex kinematic, following `target` from the next step on.
    pub fn attach(&mut self, vertex: usize, target: Vec3) {
        self.rods.kinematic_targets_mut()[vertex] = target;
        if !self.rods.kinematic()[vertex] {
            self.rods.kinematic_mut()[vertex] = true;
            self.masses_dirty = true;
        }
    }

    /// Releases a vertex attached by [`attach`](Self::attach). Roots stay pinned.
    pub fn detach(&mut self, vertex: usize) {
        let strand = self.rods.strand_of(vertex);
        if vertex != self.rods.strand_range(strand).start && self.rods.kinematic()[vertex] {
            self.rods.kinematic_mut()[vertex] = false;
            self.masses_dirty = true;
        }
    }

    /// Scales a vertex's mass (1 = dry hair).
    pub fn set_mass_scale(&mut self, vertex: usize, scale: f32) {
        if scale.is_finite() && scale > 0.0 {
            self.rods.mass_scale_mut()[vertex] = scale;
            self.masses_dirty = true;
        }
    }

    /// Per-vertex external acceleration (m/s²) added before prediction every step until changed.
    pub fn external_acceleration_mut(&mut self) -> &mut [Vec3] {
        self.rods.external_acceleration_mut()
    }

    fn target_vertices(&self, target: BondTarget) -> std::ops::Range<usize> {
        match target {
            BondTarget::All => 0..self.rods.vertex_count(),
            BondTarget::Strand(s) => self.rods.strand_range(s),
            BondTarget::Vertex(v) => v..v + 1,
        }
    }

    /// Changes one kind's bond rate by `delta` (S1-16: positive re-forms in the current shape).
    pub fn change_bond_rate(&mut self, kind: BondKind, target: BondTarget, delta: f32) {
        for vertex in self.target_vertices(target) {
            let current = self.rods.darboux_at(vertex);
            self.bonds.change_rate(kind, vertex, delta, current);
        }
    }

    /// Sets one kind's bond rate (as the change from the present rate).
    pub fn set_bond_rate(&mut self, kind: BondKind, target: BondTarget, rate: f32) {
        for vertex in self.target_vertices(target) {
            let current = self.rods.darboux_at(vertex);
            let delta = rate - self.bonds.rate(kind, vertex);
            self.bonds.change_rate(kind, vertex, delta, current);
        }
    }

    /// Changes one kind's rate at every vertex by `delta(vertex)` (a field: wetness, lotion…).
    pub fn change_bond_rates_with(&mut self, kind: BondKind, delta: impl Fn(usize) -> f32) {
        for vertex in 0..self.rods.vertex_count() {
            let current = self.rods.darboux_at(vertex);
            self.bonds.change_rate(kind, vertex, delta(vertex), current);
        }
    }

    /// Sets one kind's rate at every vertex to `rate(vertex)`.
    pub fn set_bond_rates_with(&mut self, kind: BondKind, rate: impl Fn(usize) -> f32) {
        for vertex in 0..self.rods.vertex_count() {
            let current = self.rods.darboux_at(vertex);
            let delta = rate(vertex) - self.bonds.rate(kind, vertex);
            self.bonds.change_rate(kind, vertex, delta, current);
        }
    }

    /// How long a strand may grow against its rest length before the state counts as diverged:
    /// the stretch constraints hold hair within a few percent, so twice is a runaway, not a pull.
    pub const DIVERGED_STRETCH: f32 = 2.0;

    /// Refuses a state that has diverged: a position or frame no longer finite, or a strand
    /// stretched past [`Self::DIVERGED_STRETCH`] times its rest length (a finite runaway, e.g. a
    /// long strand pushed out from deep inside an obstacle at once). Said as such rather than
    /// written out as garbage or blamed later on the output's "coordinate not finite". Cheap beside
    /// a step: one pass over the state. `stage` names the styling stage for the message.
    pub fn check_diverged(&self, stage: Option<String>) -> Result<(), crate::groom::GroomError> {
        let r = &self.rods;
        let diverged = |how: String| crate::groom::GroomError::Diverged {
            seconds: self.steps_taken() as f64 * self.params.dt as f64,
            stage: stage.clone(),
            how,
        };
        if !(r.positions().iter().all(|p| p.is_finite()) && r.frames().iter().all(|q| q.is_finite())) {
            return Err(diverged("positions no longer finite".into()));
        }
        let stretched = (0..r.strand_count()).into_par_iter().find_map_first(|strand| {
            let length: f32 =
                r.positions()[r.strand_range(strand)].windows(2).map(|e| e[0].distance(e[1])).sum();
            (length > Self::DIVERGED_STRETCH * r.rest_length(strand)).then_some((strand, length))
        });
        match stretched {
            Some((strand, length)) => Err(diverged(format!(
                "simulated strand {strand} stretched to {} m, {:.1} times its rest length",
                crate::validate::shortest(f64::from(length)),
                length / r.rest_length(strand)
            ))),
            None => Ok(()),
        }
    }

    /// Largest vertex speed, m/s.
    pub fn max_speed(&self) -> f32 {
        self.rods.velocities().iter().map(|v| v.length()).fold(0.0, f32::max)
    }

    pub fn energy(&self) -> Energy {
        let r = &self.rods;
        let mut energy = Energy::default();
        for i in 0..r.vertex_count() {
            if r.kinematic()[i] {
                continue;
            }
            let m = (r.mass()[i] * r.mass_scale()[i]) as f64;
            energy.kinetic += 0.5 * m * r.velocities()[i].as_dvec3().length_squared();
            energy.gravitational -= m * self.params.gravity.as_dvec3().dot(r.positions()[i].as_dvec3());
        }
        for i in 0..r.vertex_count() {
            if !r.is_pair_centre(i) {
                continue;
            }
            let omega = r.darboux_at(i);
            let rest = self.bonds.zero_stress_shape(i).unwrap_or(omega);
            let rest =
                if (omega - rest).length_squared() > (omega + rest).length_squared() { -rest } else { rest };
            let c = omega - rest;
            energy.elastic += 0.5 * (c * c / r.compliance()[i]).as_dvec3().element_sum();
        }
        energy
    }
}
