//! Settling (model.md §6): (a) a static solve — the equilibrium of elasticity, gravity and
//! contacts, reached to a stated residual or reported as not reached; (b) the zero-stress rest
//! curve of each strand, integrated from its root frame through the bonds' rest Darboux vectors;
//! and export of both, with the bond rates, as groom attributes.
//!
//! **The static solve** is dynamic relaxation with kinetic damping: the stepper runs with light
//! frames first (a conditioning choice; at unconverged iterations it moves the fixed point, see
//! `settle_with`), and whenever the kinetic energy
//! passes a peak every velocity is zeroed, so the groom slides down its potential energy instead
//! of oscillating about the minimum. Frames carry no angular velocity, so a bend or twist creeps
//! at a rate no reset changes; while settling each frame keeps most of its last step's turn as
//! momentum ([`FrameMomentum`]), so a long helix turning its tip gets there in seconds rather than
//! minutes. The step taken right after a reset starts from rest (no momentum), so its
//! displacement is the net force of the configuration: `F_i = m_i·Δx_i/Δt²` (gravity, elasticity,
//! contacts, hair–hair and water forces, whatever the step includes), and each frame's rotation
//! is its net torque `τ = θ/(w_q·Δt²)`. The residuals are their norms relative to gravity's. The
//! force residual is the worst strand's: the norm of its vertices' net forces over that of their
//! weights (`‖m·g‖`), so a strand far from rest is not diluted by the rest of the groom (as one
//! norm over N strands would, by about √N: a blow-dried strand sliding 5 mm when simulated again
//! read 8e-4 among 300). The torque residual is over the groom: per edge, the net torque against
//! the largest moment gravity can exert on the strand beyond it (`‖g·Σ_j m_j·|p_j − p_e|‖`).
//! Counted per strand, one strand's slow twist creep kept the water set and the bed-head from
//! converging (2.8e-3, moving the strand 0.15 mm in 2 s); over the groom the same creep goes
//! unseen where it matters more (a blow-dried strand moving 1.5 mm in 2 s): a known gap. Standard
//! gravity is the scale when gravity is off. The solve is converged when both are at most the
//! tolerance. Where the stepper relaxes a strand as an overdamped creep (quasi-static frames drag
//! bends open geometrically, with no kinetic-energy peak to reset at), the state sampled every
//! `PROBE_INTERVAL` gives the creep's rate and decay time, and the rest of it is added at once
//! (`Creep`): a jump changes where the solve starts, not the equilibrium it converges to. A state
//! that cannot get there (a solver limit cycle, contacts that fight each other) is reported with
//! the residual it reached. Strands a probe finds well within the tolerance sleep: the stepper
//! skips their work units (a lane group sleeps only whole) and the callers' hair–hair contacts
//! treat them as held ([`Simulation::idle_vertices`]). A held sleeper does not feel a moving
//! strand pressing on it, so one that a still-moving strand touches wakes at the next probe. The
//! residual is then the awake strands', and when it reaches the tolerance every strand wakes for
//! one more probe that measures them all, so "converged" always speaks for the whole groom. The
//! velocities are zero when the solve ends. The solve runs twice: with light frames, then with
//! the simulation's own frames, so that the result is also at rest for the stepper that
//! simulates it next; each phase starts with every strand awake.
use glam::{Quat, Vec3};
use serde::Serialize;

use super::bonds::BondKind;
use super::constraints::{darboux_canonical, director3, turn_of};
use super::sag_free::{MATERIAL_FRAME, REST_CURVES, REST_DARBOUX};
use super::{Hooks, Simulation};
use crate::error::{Error, Result};
use crate::groom::{Attribute, AttributeRate, Groom};

/// When the static solve counts as done.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SettleOptions {
    /// Largest accepted force and torque residual, relative to gravity's (see the module docs).
    pub tolerance: f32,
    /// Give up after this many seconds of simulated time (at least two probes' worth, ~22 ms,
    /// so the report has residuals to give).
    pub max_seconds: f32,
    /// Solver iterations while settling (`None`: the simulation's own). Static shapes of stiff,
    /// finely cut strands need more than a dynamic step does.
    pub iterations: Option<u32>,
}

impl Default for SettleOptions {
    fn default() -> Self {
        SettleOptions { tolerance: DEFAULT_TOLERANCE, max_seconds: 30.0, iterations: None }
    }
}

/// Default relative residual: the net force on every strand is a thousandth of its weight.
pub const DEFAULT_TOLERANCE: f32 = 1e-3;

/// Accepted range of tolerances: below 1e-5 f32 round-off of the positions dominates the
/// measured residual ([`PROBE_TIME`]), above 0.5 the groom is nowhere near rest.
pub const TOLERANCE_RANGE: (f32, f32) = (1e-5, 0.5);

/// Accepted range of settle budgets, simulated seconds.
pub const MAX_SECONDS_RANGE: (f32, f32) = (0.0, 3600.0);

impl SettleOptions {
    /// Checks the values against their physical ranges; `key` prefixes name where they came from
    /// (`--settle-` for the CLI, `stage 5 (settle): ` for a recipe).
    pub fn check(&self, tolerance_key: &str, seconds_key: &str) -> Result<()> {
        let (lo, hi) = TOLERANCE_RANGE;
        if !(self.tolerance >= lo && self.tolerance <= hi) {
            return Err(Error::Usage(format!(
                "{tolerance_key} = {} is outside the range [{lo:e}, {hi}] (relative force residual)",
                self.tolerance
            )));
        }
        let (lo, hi) = MAX_SECONDS_RANGE;
        if !(self.max_seconds > lo && self.max_seconds <= hi) {
            return Err(Error::Usage(format!(
                "{seconds_key} = {} is outside the range ({lo}, {hi}] seconds",
                self.max_seconds
            )));
        }
        if let Some(iterations) = self.iterations {
            crate::validate::flag("settle iterations", iterations, crate::validate::ITERATIONS)?;
        }
        Ok(())
    }
}

/// What the static solve achieved.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SettleReport {
    /// Both residuals at most the tolerance.
    pub converged: bool,
    pub tolerance: f32,
    /// The largest net force norm of a strand relative to its weight's, at the last probe.
    pub force_residual: f32,
    /// Net torque norm on the frames relative to gravity's moment over the edges.
    pub torque_residual: f32,
    pub steps: u64,
    pub seconds: f32,
    /// Velocity resets (kinetic-energy peaks).
    pub resets: u64,
    /// Strand steps skipped: strands found at rest sleep until the rest of the groom is (see
    /// [`SLEEP_FRACTION`]).
    pub strand_steps_asleep: u64,
    /// Largest vertex speed at the end, m/s (zero once converged).
    pub max_speed: f32,
}

impl SettleReport {
    /// What a settle that did not reach its tolerance achieved, for warnings and errors (`None`
    /// once converged).
    pub fn shortfall(&self) -> Option<String> {
        (!self.converged).then(|| {
            format!(
                "settling did not reach its tolerance {:.1e} within {:.2} s (force residual {:.2e}, \
                 torque residual {:.2e})",
                self.tolerance, self.seconds, self.force_residual, self.torque_residual
            )
        })
    }
}

/// Frame inertia factor while settling ([`super::SimParams::frame_inertia_factor`]): large enough
/// that every frame's inverse inertia sits at its conditioning cap, the bending compliance
/// `α/Δt²`. Frames are quasi-static, so their inertia acts as a drag on every bend (`I/Δt` per
/// edge); heavy frames made released curls creep open for many seconds. With converged
/// iterations static shapes would not depend on it; at a few Gauss–Seidel sweeps they do (see
/// `settle_with`).
const SETTLE_FRAME_INERTIA_FACTOR: f32 = 1e6;

/// Longest run between probes, seconds: a slow creep with no kinetic-energy peak is still
/// measured.
const PROBE_INTERVAL: f32 = 0.25;

/// How long a probe runs from rest, seconds: long enough that the displacement of a residual at
/// the tolerance stands well above f32 round-off of the positions at any time step. One step
/// from rest moves a vertex by `a·Δt²` (4.7 µm·a/g at Δt = 1/1440 s), while a coordinate near
/// 0.2 m rounds to ~15 nm: single-step probes could not resolve residuals below ~3e-3 there.
/// Four steps' worth at 1/360 s resolve ~2e-5 at every Δt.
const PROBE_TIME: f32 = 4.0 / 360.0;

/// Steps a probe takes at Δt `dt`.
fn probe_steps(dt: f32) -> u64 {
    (PROBE_TIME / dt).round().max(1.0) as u64
}

/// Standard gravity, the residual's scale when gravity is off.
const STANDARD_GRAVITY: f32 = 9.80665;

/// The static solve over any stepper: `sim` reaches the simulation inside `context`, and `step`
/// advances the context by one step (the rod solver plus whatever forces and contacts the caller
/// applies). `touched` marks, one flag per strand, the strands that vertices of the strands its
/// predicate picks touch now (the caller's hair–hair contacts; a caller without them leaves the
/// flags empty). Calls `tick` with the report so far after every step (progress).
pub fn settle_with<C, E>(
    context: &mut C,
    sim: impl Fn(&mut C) -> &mut Simulation,
    mut step: impl FnMut(&mut C) -> Result<(), E>,
    mut touched: impl FnMut(&mut C, &(dyn Fn(usize) -> bool + Sync), &mut Vec<bool>),
    options: &SettleOptions,
    mut tick: impl FnMut(&SettleReport),
) -> Result<SettleReport, E> {
    let s = sim(context);
    let dt = s.params().dt;
    let own_iterations = s.params().iterations;
    let own_frame_factor = s.params().frame_inertia_factor;
    if let Some(iterations) = options.iterations.filter(|&n| n >= 1) {
        s.params.iterations = iterations;
    }
    let mut report = SettleReport {
        converged: false,
        tolerance: options.tolerance,
        force_residual: f32::INFINITY,
        torque_residual: f32::INFINITY,
        steps: 0,
        seconds: 0.0,
        resets: 0,
        strand_steps_asleep: 0,
        max_speed: 0.0,
    };
    // At least one probe in each phase: a shorter settle measured nothing and reported its
    // residuals as infinite (`null` in JSON).
    let max_steps = (options.max_seconds / dt).ceil().max(2.0 * probe_steps(dt) as f32) as u64;
    // Light frames get there fast; the simulation's own frames then move the state to a rest
    // state of the stepper the groom will be simulated with. With unconverged iterations the two
    // rest states differ, and not slightly: every strand of seed_200 hanging under gravity moves
    // 31 mm at the median (62 mm at worst) in this second phase, which takes most of the steps.
    // The light phase may take half the budget: the second phase always runs, since the light
    // frames' state is no rest of the stepper the groom is simulated with (a blow-dry whose light
    // phase never converged wrote that state, which moved 14 mm in 2 s when simulated again).
    let phases = [(SETTLE_FRAME_INERTIA_FACTOR, max_steps.div_ceil(2)), (own_frame_factor, max_steps)];
    for (factor, until) in phases {
        let s = sim(context);
        s.set_frame_inertia_factor(factor).expect("a positive, finite factor");
        // A strand asleep at the light frames' rest is not at the own frames' rest, and a phase
        // checks only the sleepers it put to sleep itself: strands left asleep by a light phase
        // that ran out were never relaxed with the own frames (on a 60 cm full-head perm they
        // moved 9.6 mm in 2 s when simulated again).
        s.wake_all();
        relax(context, &sim, &mut step, &mut touched, &mut tick, options.tolerance, until, &mut report)?;
    }
    let s = sim(context);
    s.wake_all();
    if report.converged {
        s.rods.velocities_mut().iter_mut().for_each(|v| *v = Vec3::ZERO);
    }
    report.seconds = report.steps as f32 * dt;
    report.max_speed = s.max_speed();
    s.params.iterations = own_iterations;
    s.set_frame_inertia_factor(own_frame_factor).expect("the factor the run started with");
    Ok(report)
}

/// Kinetic damping until a probe reaches `tolerance` or the report counts `max_steps`.
#[allow(clippy::too_many_arguments)]
fn relax<C, E>(
    context: &mut C,
    sim: &impl Fn(&mut C) -> &mut Simulation,
    step: &mut impl FnMut(&mut C) -> Result<(), E>,
    touched: &mut impl FnMut(&mut C, &(dyn Fn(usize) -> bool + Sync), &mut Vec<bool>),
    tick: &mut impl FnMut(&SettleReport),
    tolerance: f32,
    max_steps: u64,
    report: &mut SettleReport,
) -> Result<(), E> {
    let dt = sim(context).params().dt;
    let probe_every = (PROBE_INTERVAL / dt).ceil().max(2.0) as u64;
    let probe_steps = probe_steps(dt);
    report.converged = false;
    let mut probe: Option<(Vec<Vec3>, Vec<Quat>)> = None;
    let mut since_reset = 0u64;
    let mut kinetic = f64::INFINITY;
    // Start from rest: the first steps are a probe.
    let mut reset = true;
    let mut creep = Creep::default();
    let mut per_strand = Vec::new();
    let mut disturbed = Vec::new();
    let mut asleep = 0;
    let mut momentum = FrameMomentum::default();
    while report.steps < max_steps {
        if reset {
            let s = sim(context);
            creep.sample(s, report.steps, probe_every);
            s.rods.velocities_mut().iter_mut().for_each(|v| *v = Vec3::ZERO);
            probe = Some((s.rods.positions().to_vec(), s.rods.frames().to_vec()));
            report.resets += 1;
            since_reset = 0;
            kinetic = 0.0;
            momentum.stop();
        }
        // A probe's steps are the stepper's own, from rest: they measure its residual.
        let pushed = since_reset >= probe_steps;
        if pushed {
            momentum.before_step(sim(context));
        }
        step(context)?;
        if pushed {
            momentum.after_step(sim(context));
        }
        report.steps += 1;
        tick(report);
        report.strand_steps_asleep += asleep as u64;
        since_reset += 1;
        let s = sim(context);
        let mut verify = false;
        if since_reset == probe_steps {
            if let Some((positions, frames)) = probe.take() {
                (report.force_residual, report.torque_residual) =
                    s.residuals(&positions, &frames, probe_steps, &mut per_strand);
                if report.force_residual.is_infinite() {
                    // Diverged: no number of steps brings it back (the caller says so).
                    return Ok(());
                }
                if report.force_residual <= tolerance && report.torque_residual <= tolerance {
                    if asleep == 0 {
                        report.converged = true;
                        return Ok(());
                    }
                    // Sleeping strands read zero; the next probe measures every strand.
                    s.wake_all();
                    verify = true;
                    asleep = 0;
                } else {
                    // A sleeper that a restless strand touches would feel its push change: it
                    // wakes (else the check at the end finds it pushed out of its rest).
                    let at_rest = |strand: usize| per_strand[strand] <= tolerance * SLEEP_FRACTION;
                    touched(context, &|strand| !at_rest(strand), &mut disturbed);
                    let disturbed = |strand: usize| disturbed.get(strand).copied().unwrap_or(false);
                    asleep = sim(context).put_to_sleep(at_rest, disturbed);
                }
            }
        }
        let s = sim(context);
        let now = s.kinetic_energy();
        reset = verify || since_reset >= probe_steps && (now < kinetic || since_reset >= probe_every);
        kinetic = now;
    }
    Ok(())
}

/// Vertices beyond an edge whose distances from it [`Levers`] sums one by one.
const LEVER_WINDOW: usize = 256;

/// Gravity's lever arm on the part of a strand beyond each edge, at most, whatever gravity's
/// direction: `Σ_{j>e} m_j |p_j − p_e|` over the vertices after the edge's first. Exact over the
/// next [`LEVER_WINDOW`] vertices (every strand of the presets); beyond them each distance is
/// bounded by the distance to the window's last vertex plus the arc length from there, from
/// running sums. Summed over every vertex beyond, a probe cost the strand's length squared: a
/// 100,000-vertex strand spent 76 % of its settle on 5·10⁹ distances a probe.
#[derive(Default)]
struct Levers {
    /// Per edge of the strand measured last, its lever.
    levers: Vec<f64>,
    /// Scratch, per vertex and one past the tip: the arc length from the root, and the mass and
    /// the mass-weighted arc length of the vertices from there to the tip.
    arc: Vec<f64>,
    mass_beyond: Vec<f64>,
    moment_beyond: Vec<f64>,
}

impl Levers {
    /// Measures the levers of the strand through `points`, vertex `k` of mass `mass(k)`.
    fn measure(&mut self, points: &[Vec3], mass: impl Fn(usize) -> f64) {
        let n = points.len();
        self.levers.clear();
        if n > LEVER_WINDOW + 1 {
            self.arc.clear();
            self.arc.push(0.0);
            for w in points.windows(2) {
                self.arc.push(self.arc.last().unwrap() + w[0].distance(w[1]) as f64);
            }
            self.mass_beyond.clear();
            self.mass_beyond.resize(n + 1, 0.0);
            self.moment_beyond.clear();
            self.moment_beyond.resize(n + 1, 0.0);
            for k in (0..n).rev() {
                self.mass_beyond[k] = self.mass_beyond[k + 1] + mass(k);
                self.moment_beyond[k] = self.moment_beyond[k + 1] + mass(k) * self.arc[k];
            }
        }
        for e in 0..n.saturating_sub(1) {
            let window = e + 1..n.min(e + 1 + LEVER_WINDOW);
            let near: f64 = window.clone().map(|j| mass(j) * points[j].distance(points[e]) as f64).sum();
            let far = match window.end < n {
                true => {
                    let (last, beyond) = (window.end - 1, window.end);
                    let reach = points[last].distance(points[e]) as f64;
                    let mass = self.mass_beyond[beyond];
                    (reach - self.arc[last]) * mass + self.moment_beyond[beyond]
                }
                false => 0.0,
            };
            self.levers.push(near + far);
        }
    }

    /// The lever of edge `e` of the strand measured last.
    fn of_edge(&self, e: usize) -> f64 {
        self.levers[e]
    }
}

/// Momentum kept by the frames' turns while settling: each step adds this fraction of the last
/// step's turn (heavy-ball). See [`FrameMomentum`].
const FRAME_MOMENTUM: f32 = 0.98;

/// Heavy-ball momentum for the quasi-static frames while settling. Frames carry no angular
/// velocity, so under a steady torque a strand's frames turn by the same small amount every step:
/// a soft twist (a long permed helix turning its tip about its axis) relaxed as a gradient flow
/// that no velocity reset speeds up, its rate set by the frames' inertia (60 cm scene-3 perm: the
/// tips circled ~3 cm in 180 s of settling, undamped or with rarer resets alike). Each step here
/// adds `β` times the frame's last turn, so a steady turn runs `1/(1 − β)` times faster; a strand
/// whose torque turns against its momentum (the summed turns' dot product is negative) restarts
/// from its plain step. The steps of a probe run without it, from rest, so a converged state is a
/// rest state of the stepper itself.
#[derive(Default)]
struct FrameMomentum {
    /// Frames before the step.
    before: Vec<Quat>,
    /// Per edge, the last step's turn in the frame's own axes (scaled axis; empty: at rest).
    turn: Vec<Vec3>,
    /// Per edge, this step's turn by the stepper alone (awake strands only).
    plain: Vec<Vec3>,
}

impl FrameMomentum {
    fn stop(&mut self) {
        self.turn.clear();
    }

    fn before_step(&mut self, s: &Simulation) {
        self.before.clear();
        self.before.extend_from_slice(s.rods.frames());
    }

    fn after_step(&mut self, s: &mut Simulation) {
        let edges = s.rods.frames().len();
        if self.turn.len() != edges {
            self.turn.clear();
            self.turn.resize(edges, Vec3::ZERO);
        }
        self.plain.resize(edges, Vec3::ZERO);
        for strand in 0..s.rods.strand_count() {
            let range = s.rods.strand_range(strand);
            let edges = range.start..range.end - 1;
            if s.asleep(strand) {
                self.turn[edges].fill(Vec3::ZERO);
                continue;
            }
            for e in edges.clone() {
                let (now, was) = (s.rods.frames()[e], self.before[e]);
                let was = if was.dot(now) < 0.0 { -was } else { was };
                self.plain[e] = (was.conjugate() * now).to_scaled_axis();
            }
            let power: f64 = edges.clone().map(|e| self.plain[e].dot(self.turn[e]) as f64).sum();
            let restart = power < 0.0;
            for e in edges {
                if restart || s.rods.frame_inv_inertia()[e] <= 0.0 {
                    self.turn[e] = self.plain[e];
                    continue;
                }
                let push = FRAME_MOMENTUM * self.turn[e];
                let frame = s.rods.frames()[e];
                s.rods.frames_mut()[e] = (frame * Quat::from_scaled_axis(push)).normalize();
                self.turn[e] = self.plain[e] + push;
            }
        }
    }
}

/// A strand whose residuals are both at most this fraction of the tolerance at a probe sleeps
/// (the stepper skips it) until the rest of the groom reaches the tolerance; then every strand
/// wakes and one more probe measures them all. Most of a settle's steps wait for a few slow
/// strands: in the demo's settle (500 guides), from 30 % of its steps on at most 20 strands were
/// above the tolerance and the median strand at a sixtieth of it; for the last half, 1 to 3.
pub const SLEEP_FRACTION: f32 = 0.1;

/// Largest jump along a creep, in steps' worth of its last displacement rate.
const MAX_CREEP_STEPS: f64 = 5000.0;

/// Extrapolation of a monotone creep (an overdamped mode the stepper relaxes geometrically): the
/// state is sampled at resets at least `every` steps apart; when a strand's displacements over two
/// successive samples point the same way and their rates fall like `e^(−t/τ)`, the rest of the
/// creep, `τ` times the rate now, is added at once. A strand that moves faster over the interval
/// after its jump than before it is put back and its later jumps are shorter.
#[derive(Default)]
struct Creep {
    /// State and step count at the last sample.
    last: Option<(Vec<Vec3>, Vec<Quat>, u64)>,
    /// Displacement per step over the interval before and that interval's length.
    rate: Option<(Vec<Vec3>, u64)>,
    /// The state before the last jumps, and per strand the squared rate before its jump (zero:
    /// it did not jump).
    undo: Option<(Vec<Vec3>, Vec<Quat>, Vec<f64>)>,
    /// Per strand, the largest jump in steps' worth of its displacement rate.
    cap: Vec<f64>,
}

impl Creep {
    fn sample(&mut self, s: &mut Simulation, step: u64, every: u64) {
        let strands = s.rods.strand_count();
        if self.cap.len() != strands {
            self.cap = vec![MAX_CREEP_STEPS; strands];
        }
        if self.last.as_ref().is_some_and(|l| step - l.2 < every) {
            return;
        }
        let Some((last_positions, last_frames, at)) = self.last.take() else {
            self.last = Some((s.rods.positions().to_vec(), s.rods.frames().to_vec(), step));
            return;
        };
        let length = step - at;
        let inv = 1.0 / length as f32;
        let rate: Vec<Vec3> =
            s.rods.positions().iter().zip(&last_positions).map(|(&a, &b)| (a - b) * inv).collect();
        let norm2 = |v: &[Vec3], range: std::ops::Range<usize>| -> f64 {
            v[range].iter().map(|d| d.as_dvec3().length_squared()).sum()
        };
        if let Some((positions, frames, before)) = self.undo.take() {
            for (strand, &before) in before.iter().enumerate() {
                let range = s.rods.strand_range(strand);
                if before > 0.0 && norm2(&rate, range.clone()) > before {
                    s.rods.positions_mut()[range.clone()].copy_from_slice(&positions[range.clone()]);
                    s.rods.frames_mut()[range.clone()].copy_from_slice(&frames[range]);
                    self.cap[strand] *= 0.25;
                }
            }
            self.last = Some((s.rods.positions().to_vec(), s.rods.frames().to_vec(), step));
            return;
        }
        let mut jumps = vec![0.0f64; strands];
        let undo = (s.rods.positions().to_vec(), s.rods.frames().to_vec());
        if let Some((before, before_length)) = self.rate.take() {
            let gap = 0.5 * (length + before_length) as f64;
            for (strand, jump) in jumps.iter_mut().enumerate() {
                let range = s.rods.strand_range(strand);
                let (mut dot, mut bb) = (0.0f64, 0.0f64);
                for i in range.clone() {
                    dot += rate[i].as_dvec3().dot(before[i].as_dvec3());
                    bb += before[i].as_dvec3().length_squared();
                }
                let nn = norm2(&rate, range.clone());
                if nn <= 0.0 || bb <= 0.0 {
                    continue;
                }
                let cos = dot / (nn * bb).sqrt();
                let ratio = dot / bb;
                if cos < 0.99 || !(ratio > 0.0 && ratio < 0.99) {
                    continue;
                }
                let tau = -gap / ratio.ln();
                // The rate at the end of the last interval, times τ.
                let steps = (tau * ratio.powf(0.5 * length as f64 / gap)).min(self.cap[strand]);
                let factor = steps as f32;
                *jump = nn;
                for i in range.clone() {
                    if !s.rods.kinematic()[i] {
                        s.rods.positions_mut()[i] += factor * rate[i];
                    }
                }
                let per_step = inv * factor;
                for (e, &was) in last_frames.iter().enumerate().take(range.end - 1).skip(range.start) {
                    if s.rods.frame_inv_inertia()[e] <= 0.0 {
                        continue;
                    }
                    let now = s.rods.frames()[e];
                    let mut was = was;
                    if was.dot(now) < 0.0 {
                        was = -was;
                    }
                    s.rods.frames_mut()[e] = (now + (now - was) * per_step).normalize();
                }
            }
        }
        if jumps.iter().any(|&j| j > 0.0) {
            self.undo = Some((undo.0, undo.1, jumps));
            self.rate = None;
        } else {
            self.rate = Some((rate, length));
        }
        self.last = Some((s.rods.positions().to_vec(), s.rods.frames().to_vec(), step));
    }
}

impl Simulation {
    /// The static solve with the rod solver and `hooks` as the stepper ([`settle_with`]).
    pub fn settle(&mut self, options: &SettleOptions, hooks: &dyn Hooks) -> SettleReport {
        let step = |s: &mut Self| -> Result<(), std::convert::Infallible> {
            s.step_with(hooks);
            Ok(())
        };
        match settle_with(self, |s| s, step, |_, _, touched| touched.clear(), options, |_| {}) {
            Ok(report) => report,
            Err(never) => match never {},
        }
    }

    /// Lets the strands `rest` picks sleep (the stepper skips them), with zero velocities, where
    /// every strand of their work unit sleeps then: the stepper runs a unit whole or not at all.
    /// Wakes every unit with a `disturbed` strand, and keeps such units awake. Returns how many
    /// strands sleep.
    fn put_to_sleep(&mut self, rest: impl Fn(usize) -> bool, disturbed: impl Fn(usize) -> bool) -> usize {
        self.asleep.resize(self.rods.strand_count(), false);
        for unit in 0..self.rods.work_units().len() {
            let (first, count, _) = self.rods.work_units()[unit];
            let strands = first..first + count;
            if strands.clone().any(&disturbed) {
                self.asleep[strands].fill(false);
                continue;
            }
            if !strands.clone().all(|strand| self.asleep[strand] || rest(strand)) {
                continue;
            }
            for strand in strands {
                self.asleep[strand] = true;
                let range = self.rods.strand_range(strand);
                self.rods.velocities_mut()[range].iter_mut().for_each(|v| *v = Vec3::ZERO);
            }
        }
        self.asleep.iter().filter(|&&asleep| asleep).count()
    }

    fn wake_all(&mut self) {
        self.asleep.clear();
    }

    fn kinetic_energy(&self) -> f64 {
        let r = &self.rods;
        // Sleepers are still: leaving out their zero terms leaves the sum as it is, bit for bit.
        (0..r.strand_count())
            .filter(|&strand| !self.asleep(strand))
            .flat_map(|strand| r.strand_range(strand))
            .filter(|&i| !r.kinematic()[i])
            .map(|i| (r.mass()[i] * r.mass_scale()[i]) as f64 * r.velocities()[i].as_dvec3().length_squared())
            .sum()
    }

    /// Force and torque residuals of the `steps` steps just taken from rest at `positions`,
    /// `frames`. Under a constant net acceleration `a`, `k` steps from rest move a vertex by
    /// `a·Δt²·k(k+1)/2`; quasi-static frames turn by `τ·w_q·Δt²` per step.
    /// `per_strand` receives each strand's larger residual, its force and its torque each
    /// relative to its own gravity (a strand that sleeps reads zero: it did not move).
    fn residuals(
        &self,
        positions: &[Vec3],
        frames: &[Quat],
        steps: u64,
        per_strand: &mut Vec<f32>,
    ) -> (f32, f32) {
        let r = &self.rods;
        let dt2 = (self.params.dt * self.params.dt) as f64;
        let k = steps as f64;
        let (vertex_scale, frame_scale) = (dt2 * k * (k + 1.0) / 2.0, dt2 * k);
        let g = match self.params.gravity.length() {
            g if g > 0.0 => g,
            _ => STANDARD_GRAVITY,
        } as f64;
        // A diverged state (NaN) is as far from rest as can be, not a zero residual.
        let ratio = |a: f64, b: f64| match a {
            a if a.is_nan() => f32::INFINITY,
            a if b > 0.0 => (a / b).sqrt() as f32,
            _ => 0.0,
        };
        let (mut worst_force, mut torque, mut moment) = (0.0f32, 0.0f64, 0.0f64);
        per_strand.clear();
        let mass = |i: usize| (r.mass()[i] * r.mass_scale()[i]) as f64;
        let mut levers = Levers::default();
        for strand in 0..r.strand_count() {
            let (torque_before, moment_before) = (torque, moment);
            let range = r.strand_range(strand);
            levers.measure(&r.positions()[range.clone()], |k| mass(range.start + k));
            let (mut force, mut weight) = (0.0f64, 0.0f64);
            for i in range.clone() {
                if r.kinematic()[i] {
                    continue;
                }
                force += (mass(i) * (r.positions()[i] - positions[i]).length() as f64 / vertex_scale).powi(2);
                weight += (mass(i) * g).powi(2);
            }
            worst_force = worst_force.max(ratio(force, weight));
            let edges = range.start..range.end - 1;
            for (e, (&before, &now)) in
                frames.iter().zip(r.frames()).enumerate().take(edges.end).skip(edges.start)
            {
                let wq = r.frame_inv_inertia()[e];
                if wq <= 0.0 || (r.kinematic()[e] && r.kinematic()[e + 1]) {
                    continue;
                }
                let turn = darboux_canonical(before, now).length().min(1.0);
                let angle = 2.0 * (turn as f64).asin();
                torque += (angle / (wq as f64 * frame_scale)).powi(2);
                // Gravity's moment on the strand beyond the edge, at most (whatever its direction).
                moment += (g * levers.of_edge(e - range.start)).powi(2);
            }
            let strand_torque = ratio(torque - torque_before, moment - moment_before);
            per_strand.push(ratio(force, weight).max(strand_torque));
        }
        (worst_force, ratio(torque, moment))
    }

    /// Zero-stress Darboux vector of each edge pair (vertex-indexed; zero at roots and tips): the
    /// shape the bonds hold when no force acts. Where every bond is broken the current shape is
    /// stress-free and is used.
    pub fn zero_stress_darboux(&self) -> Vec<Vec3> {
        (0..self.rods.vertex_count())
            .map(|i| {
                if self.rods.is_pair_centre(i) {
                    self.bonds.zero_stress_shape(i).unwrap_or_else(|| self.rods.darboux_at(i))
                } else {
                    Vec3::ZERO
                }
            })
            .collect()
    }

    /// Each strand's zero-stress rest curve: from the root position and root frame, every next
    /// frame turns by the rest Darboux vector (`q̄_{i−1}⊗q_i = (√(1−|Ω0|²), Ω0)`) and every edge
    /// runs its rest length along its frame's third director.
    pub fn rest_curves(&self) -> Vec<Vec3> {
        let r = &self.rods;
        let omega0 = self.zero_stress_darboux();
        let mut points = vec![Vec3::ZERO; r.vertex_count()];
        for strand in 0..r.strand_count() {
            let range = r.strand_range(strand);
            let first = range.start;
            let mut frame = r.frames()[first];
            let mut p = r.positions()[first];
            points[first] = p;
            for i in first..range.end - 1 {
                if i > first {
                    frame = (frame * turn_of(omega0[i])).normalize();
                }
                p += r.rest_lengths()[i] * director3(frame);
                points[i + 1] = p;
            }
        }
        points
    }

    /// Writes the simulated state into `groom` (which must be the groom the simulation was built
    /// from, or one with the same strands): current positions as points, and the
    /// [`Self::state_attributes`].
    pub fn write_to_groom(&self, groom: &mut Groom) {
        groom.points.clear();
        groom.points.extend_from_slice(self.rods.positions());
        for attribute in self.state_attributes() {
            groom.provide_attribute(attribute);
        }
    }

    /// The simulated state beside the positions, as per-vertex attributes: `rest` (zero-stress
    /// rest curves), `rest_darboux` (Ω0), `material_frame` (the edges' frames) and `bond_*`
    /// (rates per kind).
    pub fn state_attributes(&self) -> Vec<Attribute> {
        let flat = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
        let frames = self.rods.frames().iter().flat_map(|q| q.to_array()).collect();
        let mut attributes = vec![
            Attribute::new(REST_CURVES, AttributeRate::Vertex, 3, flat(&self.rest_curves())),
            Attribute::new(REST_DARBOUX, AttributeRate::Vertex, 3, flat(&self.exported_rest_darboux())),
            Attribute::new(MATERIAL_FRAME, AttributeRate::Vertex, 4, frames),
        ];
        for kind in BondKind::ALL {
            attributes.push(Attribute::new(
                kind.attribute_name(),
                AttributeRate::Vertex,
                1,
                self.bonds.rates(kind).to_vec(),
            ));
        }
        attributes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::SimParams;

    /// Gravity's levers are the sum over every vertex beyond an edge, bit for bit, on strands
    /// the window covers; beyond it an upper bound, exact on a straight strand and within the
    /// helix's arc-to-chord ratio on a curl.
    #[test]
    fn levers_are_exact_within_the_window_and_bound_beyond_it() {
        let mass = |k: usize| 1.0 + (k % 7) as f64 * 0.1;
        let every = |points: &[Vec3], e: usize| -> f64 {
            (e + 1..points.len()).map(|j| mass(j) * points[j].distance(points[e]) as f64).sum()
        };
        let helix = |n: usize| -> Vec<Vec3> {
            (0..n)
                .map(|k| k as f32 * 0.3)
                .map(|t| Vec3::new(0.01 * t.cos(), -0.001 * t, 0.01 * t.sin()))
                .collect()
        };
        let mut levers = Levers::default();
        for n in [1, 2, 40, LEVER_WINDOW + 1] {
            let points = helix(n);
            levers.measure(&points, mass);
            for e in 0..n.saturating_sub(1) {
                assert_eq!(
                    levers.of_edge(e).to_bits(),
                    every(&points, e).to_bits(),
                    "{n} vertices, edge {e}"
                );
            }
        }
        let straight: Vec<Vec3> = (0..1500).map(|k| Vec3::new(0.0, -0.001 * k as f32, 0.0)).collect();
        levers.measure(&straight, mass);
        for e in 0..1499 {
            let exact = every(&straight, e);
            assert!((levers.of_edge(e) / exact - 1.0).abs() < 1e-5, "straight, edge {e}");
        }
        let curl = helix(1500);
        levers.measure(&curl, mass);
        // The helix's arc per unit of its axis.
        let ratio = (0.01f64.powi(2) + 0.001f64.powi(2)).sqrt() / 0.001;
        for e in 0..1499 {
            let (bound, exact) = (levers.of_edge(e), every(&curl, e));
            assert!(
                bound >= exact * (1.0 - 1e-6) && bound <= exact * ratio,
                "curl, edge {e}: {bound} vs {exact}"
            );
        }
    }

    /// `count` straight strands of `vertices` vertices hanging in a row, 5 cm apart.
    fn hanging_strands(count: usize, vertices: usize) -> Simulation {
        let strands: Vec<Vec<Vec3>> = (0..count)
            .map(|k| (0..vertices).map(|i| Vec3::new(0.05 * k as f32, -0.01 * i as f32, 0.0)).collect())
            .collect();
        Simulation::new(&Groom::from_strands(&strands, 80e-6), SimParams::default()).unwrap()
    }

    #[test]
    fn a_disturbed_strand_wakes_its_work_unit_and_keeps_it_awake() {
        let mut sim = hanging_strands(16, 8);
        let units: Vec<_> = sim.rods.work_units().iter().map(|&(first, count, _)| (first, count)).collect();
        assert_eq!(units, [(0, 8), (8, 8)], "two lane groups");
        assert_eq!(sim.put_to_sleep(|_| true, |_| false), 16);
        // A moving strand touches strand 3: its unit wakes, the other sleeps on.
        assert_eq!(sim.put_to_sleep(|_| true, |strand| strand == 3), 8);
        assert!((0..8).all(|s| !sim.asleep(s)) && (8..16).all(|s| sim.asleep(s)));
        // While disturbed, a unit stays awake however still it is; then it may sleep again.
        assert_eq!(sim.put_to_sleep(|_| true, |strand| strand == 3), 8);
        assert_eq!(sim.put_to_sleep(|_| true, |_| false), 16);
    }

    #[test]
    fn a_diverged_state_is_neither_converged_nor_at_rest() {
        // A NaN position made every residual read 0 ("converged, residual 0"); it reads infinite,
        // the settle stops at once, and the simulation refuses the state.
        let mut sim = hanging_strands(2, 6);
        assert!(sim.check_diverged(None).is_ok());
        sim.rods.positions_mut()[3] = Vec3::NAN;
        let report = sim.settle(&SettleOptions::default(), &crate::sim::NoHooks);
        assert!(!report.converged && report.force_residual.is_infinite(), "{report:?}");
        assert!(report.seconds < 1.0, "ran on for {} s", report.seconds);
        let e = sim.check_diverged(Some("stage 2 (dry)".into())).unwrap_err().to_string();
        assert!(e.contains("diverged in stage 2 (dry)"), "{e}");
    }
}
