//! The time stepper: per strand, rest shapes and forces (`begin_step`) → prediction → per
//! iteration a direct solve of stretch–shear along the strand and a Gauss–Seidel
//! sweep along the strand
//! (stretch–shear of edge `e`, then bend–twist of the pair ending at `e`; sweeps alternate
//! direction) → velocity update. Lane groups of 8 strands run the same sequence in `lanes`.
//! With `StepConstants::direct` the free tail's stretch–shear and bend–twist are solved together
//! (`strand_solve`), the held span before it (root to winding) gets the direct stretch–shear solve
//! and the sweeps, and a lane group's strands
//! are solved 4 at a time in f64 lanes (`strand_solve::solve_lanes`, the scalar solve's bits).
//! Strands run in parallel on rayon; each strand's work reads and writes only its own slices, so
//! results are bit-identical at any thread count and any chunking.
use std::cell::RefCell;
use std::ops::Range;

use glam::{Quat, Vec3};
use rayon::prelude::*;

use super::constraints::{
    darboux_canonical, director3, project_bend_twist_with, project_stretch_shear_with, pure, times_e_bar,
    BendTwistCoefficients, StretchShearCoefficients, Sym3,
};
use super::lanes;
use super::rod::Rods;
use super::Hooks;

/// Per-step constants shared by every strand.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StepConstants {
    pub dt: f32,
    pub iterations: u32,
    pub gravity: Vec3,
    /// Velocity factor per step, `exp(−damping·Δt)`, so damping per second does not depend on Δt.
    pub velocity_keep: f32,
    /// Bend–twist and stretch–shear of the free tail solved together (`strand_solve`).
    pub direct: bool,
}

/// A raw pointer with its slice's length that may cross threads; strands hand out disjoint
/// slices of it.
#[derive(Clone, Copy)]
struct SharedMut<T> {
    base: *mut T,
    len: usize,
}
// SAFETY: only used to create slices over disjoint per-strand ranges (see `step_all`).
unsafe impl<T: Send> Send for SharedMut<T> {}
unsafe impl<T: Send> Sync for SharedMut<T> {}

impl<T> SharedMut<T> {
    fn new(v: &mut [T]) -> Self {
        SharedMut { base: v.as_mut_ptr(), len: v.len() }
    }

    /// The bounds are checked (once per strand and array, negligible next to the solve), so only
    /// disjointness is left to the caller.
    ///
    /// # Safety
    /// No two live slices may overlap.
    #[allow(clippy::mut_from_ref)]
    unsafe fn slice<'a>(&self, range: Range<usize>) -> &'a mut [T] {
        assert!(range.start <= range.end && range.end <= self.len, "strand range outside the rod arrays");
        std::slice::from_raw_parts_mut(self.base.add(range.start), range.len())
    }
}

/// One strand's view of the rod arrays.
struct Strand<'a> {
    x: &'a mut [Vec3],
    v: &'a mut [Vec3],
    x_prev: &'a mut [Vec3],
    q: &'a mut [Quat],
    rest: &'a mut [Vec3],
    lambda: &'a mut [Vec3],
    inverse: &'a mut [Sym3],
    values: &'a mut [Vec3],
    edge_k: &'a [StretchShearCoefficients],
    pair_k: &'a [BendTwistCoefficients],
    w: &'a [f32],
    kinematic: &'a [bool],
    targets: &'a [Vec3],
    external: &'a [Vec3],
    wq: &'a [f32],
    length: &'a [f32],
    compliance: &'a [Vec3],
    bonded: &'a [Vec3],
    broken: &'a [f32],
}

/// Raw access to the rod arrays, from which disjoint per-strand views are cut.
struct Parts<'a> {
    offsets: &'a [u32],
    x: SharedMut<Vec3>,
    v: SharedMut<Vec3>,
    x_prev: SharedMut<Vec3>,
    q: SharedMut<Quat>,
    rest: SharedMut<Vec3>,
    lambda: SharedMut<Vec3>,
    inverse: SharedMut<Sym3>,
    values: SharedMut<Vec3>,
    edge_k: &'a [StretchShearCoefficients],
    pair_k: &'a [BendTwistCoefficients],
    w: &'a [f32],
    kinematic: &'a [bool],
    targets: &'a [Vec3],
    external: &'a [Vec3],
    wq: &'a [f32],
    length: &'a [f32],
    compliance: &'a [Vec3],
    bonded: &'a [Vec3],
    broken: &'a [f32],
}

impl<'a> Parts<'a> {
    fn range(&self, strand: usize) -> Range<usize> {
        self.offsets[strand] as usize..self.offsets[strand + 1] as usize
    }

    /// # Safety
    /// Each strand's view may be alive only once at a time.
    unsafe fn strand(&self, strand: usize) -> Strand<'a> {
        let r = self.range(strand);
        Strand {
            x: self.x.slice(r.clone()),
            v: self.v.slice(r.clone()),
            x_prev: self.x_prev.slice(r.clone()),
            q: self.q.slice(r.clone()),
            rest: self.rest.slice(r.clone()),
            lambda: self.lambda.slice(r.clone()),
            inverse: self.inverse.slice(r.clone()),
            values: self.values.slice(r.clone()),
            edge_k: &self.edge_k[r.clone()],
            pair_k: &self.pair_k[r.clone()],
            w: &self.w[r.clone()],
            kinematic: &self.kinematic[r.clone()],
            targets: &self.targets[r.clone()],
            external: &self.external[r.clone()],
            wq: &self.wq[r.clone()],
            length: &self.length[r.clone()],
            compliance: &self.compliance[r.clone()],
            bonded: &self.bonded[r.clone()],
            broken: &self.broken[r],
        }
    }
}

thread_local! {
    static STRAND_SCRATCH: RefCell<super::strand_solve::Scratch> = RefCell::new(Default::default());
    static LANE_SCRATCH: RefCell<lanes::Scratch> = RefCell::new(lanes::Scratch::default());
}

/// Advances every strand by one step, except work units whose strands are all `asleep` (per
/// strand; empty: none is), which are left as they are.
pub(crate) fn step_all(
    rods: &mut Rods,
    bonded: &[Vec3],
    broken: &[f32],
    asleep: &[bool],
    k: &StepConstants,
    hooks: &dyn Hooks,
) {
    let a = rods.step_arrays();
    let units = a.work_units;
    let parts = Parts {
        offsets: a.offsets,
        x: SharedMut::new(a.positions),
        v: SharedMut::new(a.velocities),
        x_prev: SharedMut::new(a.previous_positions),
        q: SharedMut::new(a.frames),
        rest: SharedMut::new(a.rest_darboux),
        lambda: SharedMut::new(a.lambdas),
        inverse: SharedMut::new(a.solve_inverse),
        values: SharedMut::new(a.solve_values),
        edge_k: a.edge_coefficients,
        pair_k: a.pair_coefficients,
        w: a.inv_mass,
        kinematic: a.kinematic,
        targets: a.kinematic_targets,
        external: a.external_acceleration,
        wq: a.frame_inv_inertia,
        length: a.rest_lengths,
        compliance: a.compliance,
        bonded,
        broken,
    };
    units.par_iter().with_min_len(16).for_each(|&(first_strand, count, in_lanes)| {
        if !asleep.is_empty() && asleep[first_strand..first_strand + count].iter().all(|&a| a) {
            return;
        }
        // SAFETY: work units cover each strand once (checked in `Rods::from_groom`), and strand
        // ranges are disjoint because the offsets ascend (same check); bounds are checked in
        // `SharedMut::slice`.
        if in_lanes && k.direct {
            let mut views: [Strand<'_>; lanes::LANES] =
                std::array::from_fn(|l| unsafe { parts.strand(first_strand + l) });
            for (l, view) in views.iter_mut().enumerate() {
                let strand = first_strand + l;
                begin_step(view, k, hooks, strand, parts.range(strand).start);
            }
            finish_step_direct_lanes(&mut views, k, hooks, first_strand, |strand| parts.range(strand).start);
        } else if in_lanes {
            let mut views: [Strand<'_>; lanes::LANES] =
                std::array::from_fn(|l| unsafe { parts.strand(first_strand + l) });
            for (l, view) in views.iter_mut().enumerate() {
                let strand = first_strand + l;
                begin_step(view, k, hooks, strand, parts.range(strand).start);
            }
            let mut strand = first_strand;
            let mut lane_views = views.map(|s| {
                let view = lanes::LaneStrand {
                    x: s.x,
                    v: s.v,
                    q: s.q,
                    w: s.w,
                    wq: s.wq,
                    kinematic: s.kinematic,
                    targets: s.targets,
                    rest: s.rest,
                    length: s.length,
                    edge_k: s.edge_k,
                    pair_k: s.pair_k,
                    strand,
                    first_vertex: parts.range(strand).start,
                };
                strand += 1;
                view
            });
            LANE_SCRATCH.with(|scratch| {
                lanes::finish_step(
                    &mut lane_views,
                    &mut scratch.borrow_mut(),
                    lanes::StepSettings { dt: k.dt, iterations: k.iterations, keep: k.velocity_keep },
                    hooks,
                )
            });
        } else {
            for strand in first_strand..first_strand + count {
                let mut view = unsafe { parts.strand(strand) };
                let first = parts.range(strand).start;
                begin_step(&mut view, k, hooks, strand, first);
                finish_step_scalar(view, k, hooks, strand, first);
            }
        }
    });
}

/// Solves the stretch–shear constraints of a whole strand at once, to first order:
/// `C_e = x_{e+1} − x_e − l_e·d3(q_e) = 0` for every edge, in the vertices and the edge frames
/// together. The system `J·W·Jᵀ·μ = −C` is block tridiagonal: each diagonal block is
/// `(w_e + w_{e+1})·I + 4·wq_e·l_e²·(I − d3·d3ᵀ)` (the vertices move the edge every way, its frame
/// only across itself) and the blocks of neighbouring edges are `−w·I` (they share a vertex), so
/// block Thomas elimination solves it in linear time. Gauss–Seidel alone carries a correction one
/// edge per sweep, so under a load the strand keeps a stretch and a shear that shrink only like
/// 1/iterations: finely cut strands sagged several times beam theory at 5 iterations and a strand
/// hanging at Δt 1/30 stretched to three times its length. The solve covers spans held at both
/// ends too (a root and a winding on a curler, [`HeldSpans`]): left to Gauss–Seidel,
/// such a span stretched under its load by an amount that depended on Δt and the iteration count,
/// and the perm baked that into its rest curves. Solves the first `edges` edges: their last
/// vertex must be kinematic or the strand's tip.
fn solve_stretch_shear(s: &mut Strand<'_>, edges: usize) {
    let w: &[f32] = s.w;
    let (x, kinematic, length) = (&*s.x, s.kinematic, s.length);
    let clamp = pinned_first_edge_end(kinematic[0], s.wq[0], x[0], length[0], s.q[0]);
    let mut spans = HeldSpans::new(|v| kinematic[v], |v| x[v], |e| length[e], edges, clamp);
    // Forward elimination: P_e = B_e − w_e²·P_{e−1}⁻¹, z_e = P_e⁻¹·(−C_e + w_e·z_{e−1}).
    for e in 0..edges {
        let d = director3(s.q[e]);
        let l = length[e];
        let target = l * spans.stretch(e);
        let vertices = w[e] + w[e + 1];
        let frame = 4.0 * s.wq[e] * l * l;
        // A span held at both ends has no stretch mode of its own: a relative 1e-6 on the
        // diagonal keeps its pivot invertible without changing any solvable system measurably.
        let mut block = Sym3::identity_minus_outer((vertices + frame) * (1.0 + 1e-6), frame, d);
        let mut rhs = (target * d) - (x[e + 1] - x[e]);
        if e > 0 {
            block = block.minus_scaled(s.inverse[e - 1], w[e] * w[e]);
            rhs += w[e] * s.values[e - 1];
        }
        s.inverse[e] = if vertices > 0.0 {
            block.inverse()
        } else if frame > 0.0 {
            // Both vertices kinematic (their neighbours' rows do not reach this one): only the
            // frame can turn, across itself.
            Sym3::identity_minus_outer(1.0 / frame, 1.0 / frame, d)
        } else {
            Sym3::default()
        };
        s.values[e] = s.inverse[e].times(rhs);
    }
    // Back substitution: μ_e = z_e + w_{e+1}·P_e⁻¹·μ_{e+1}.
    for e in (0..edges.saturating_sub(1)).rev() {
        s.values[e] += s.inverse[e].times(w[e + 1] * s.values[e + 1]);
    }
    // Δx_j = w_j·(μ_{j−1} − μ_j); each frame turns its d3 along the shear part of its μ.
    for (j, &wj) in w.iter().enumerate().take(edges + 1) {
        let before = if j > 0 { s.values[j - 1] } else { Vec3::ZERO };
        let after = if j < edges { s.values[j] } else { Vec3::ZERO };
        s.x[j] += wj * (before - after);
    }
    for e in 0..edges {
        let wq = s.wq[e];
        if wq > 0.0 {
            let d = director3(s.q[e]);
            let mu = s.values[e];
            let across = mu - mu.dot(d) * d;
            let q = s.q[e];
            s.q[e] = (q - pure(across) * times_e_bar(q) * (2.0 * wq * s.length[e])).normalize();
        }
    }
}

/// With the direct strand solve, the stretch–shear of the span held at both ends before the free
/// tail (from the root to the last kinematic vertex: a winding on a curler), solved directly as
/// [`solve_stretch_shear`] solves a whole strand; bend–twist there stays with the sweeps. Left to
/// the sweeps alone, the span stretched under its load by an amount that depended on Δt, as it
/// did with Gauss–Seidel before that solve covered it: perm_scene3's strand 1, whose span from
/// the root to its rod is 72 edges, hung 41 mm lower at the wrap's end at Δt 1/240 than at 1/1440
/// and the perm baked it into its rest curves (3.5 % of the strand length).
fn solve_held_span(s: &mut Strand<'_>, free_from: usize) {
    if free_from > 0 {
        solve_stretch_shear(s, free_from);
    }
}

/// How far apart the ends of a span held at both ends may be, as a share of its rest length,
/// before the direct stretch–shear solve stretches its edges: a span pulled taut or beyond
/// (winding targets pushed out of an obstacle) has no solution with its rest lengths, and a
/// linearised solve of hard constraints nearly straight has a near-singular stretch mode.
pub(super) const HELD_SPAN_SLACK: f32 = 0.98;

/// Where a pinned root frame (a kinematic root whose frame does not turn) holds the end of the
/// first edge, for [`HeldSpans::new`]; `None` when the root frame is free.
pub(super) fn pinned_first_edge_end(
    kinematic_root: bool,
    root_wq: f32,
    root: Vec3,
    first_length: f32,
    root_frame: Quat,
) -> Option<Vec3> {
    (kinematic_root && root_wq == 0.0).then(|| root + first_length * director3(root_frame))
}

/// Walks a strand's edges root to tip and tells for each the stretch the direct stretch–shear
/// solve asks of it: 1, except in a span held at both ends (between two kinematic vertices with
/// free ones between, like a root and the first vertex wound on a curler) whose ends lie further
/// apart than [`HELD_SPAN_SLACK`] of its rest length, where every edge is stretched alike to
/// leave it that slack. A pinned root frame fixes the first edge too, so a span from the root is
/// measured from the first edge's end. Kinematic vertices and pinned frames do not move within a
/// step, so every iteration gets the same factors.
pub(super) struct HeldSpans<K, X, L> {
    kinematic: K,
    x: X,
    length: L,
    edges: usize,
    /// The end of the first edge when the root frame is pinned.
    root_clamp: Option<Vec3>,
    /// The span the last edge asked about ends at this vertex; its edges from `from` on have
    /// this stretch.
    end: usize,
    from: usize,
    factor: f32,
}

impl<K: Fn(usize) -> bool, X: Fn(usize) -> Vec3, L: Fn(usize) -> f32> HeldSpans<K, X, L> {
    /// A strand of `edges` edges: whether vertex `v` is kinematic and where it is, the rest
    /// length of edge `e`, and where a pinned root frame holds the first edge's end.
    pub(super) fn new(kinematic: K, x: X, length: L, edges: usize, root_clamp: Option<Vec3>) -> Self {
        HeldSpans { kinematic, x, length, edges, root_clamp, end: 0, from: 0, factor: 1.0 }
    }

    /// The stretch of edge `e`; edges must be asked about in ascending order.
    pub(super) fn stretch(&mut self, e: usize) -> f32 {
        if e >= self.end {
            // A span starts at vertex `e` and runs to the next kinematic vertex.
            let end = (e + 1..=self.edges).find(|&v| (self.kinematic)(v)).unwrap_or(self.edges);
            self.factor = 1.0;
            let (from, start) = match self.root_clamp {
                Some(clamp) if e == 0 => (1, clamp),
                _ => (e, (self.x)(e)),
            };
            self.from = from;
            if end >= from + 2 && (self.kinematic)(e) && (self.kinematic)(end) {
                let gap = start.distance((self.x)(end));
                let rest: f32 = (from..end).map(|k| (self.length)(k)).sum();
                if gap > HELD_SPAN_SLACK * rest {
                    self.factor = gap / (HELD_SPAN_SLACK * rest);
                }
            }
            self.end = end;
        }
        if e >= self.from {
            self.factor
        } else {
            1.0
        }
    }
}

/// The first edge of the strand's free tail: edges from the last kinematic vertex on, which the
/// direct strand solve (`strand_solve`) covers; the span before it is left to Gauss–Seidel.
pub(super) fn free_tail(kinematic: &[bool]) -> usize {
    kinematic.iter().rposition(|&k| k).unwrap_or(0).min(kinematic.len() - 1)
}

/// Stretch–shear of edge `e`.
#[inline(always)]
fn project_edge(s: &mut Strand<'_>, e: usize) {
    let (mut p1, mut p2, mut q) = (s.x[e], s.x[e + 1], s.q[e]);
    project_stretch_shear_with(&mut p1, &mut p2, &mut q, &s.edge_k[e]);
    s.x[e] = p1;
    s.x[e + 1] = p2;
    s.q[e] = q;
}

/// Bend–twist of the pair of edges `e − 1`, `e`.
#[inline(always)]
fn project_pair(s: &mut Strand<'_>, e: usize) {
    let (mut q1, mut q2) = (s.q[e - 1], s.q[e]);
    project_bend_twist_with(
        &mut q1,
        &mut q2,
        s.wq[e - 1],
        s.wq[e],
        s.rest[e],
        &s.pair_k[e],
        &mut s.lambda[e],
    );
    s.q[e - 1] = q1;
    s.q[e] = q2;
}

/// This step's constants, rest shapes and forces of one strand.
fn begin_step(s: &mut Strand<'_>, k: &StepConstants, hooks: &dyn Hooks, strand: usize, first: usize) {
    let n = s.x.len();
    // Equal lengths stated once let the compiler drop bounds checks in the loops below.
    assert!(
        n >= 2
            && [s.v.len(), s.x_prev.len(), s.q.len(), s.rest.len()]
                .iter()
                .chain(&[s.lambda.len(), s.inverse.len(), s.values.len(), s.edge_k.len()])
                .chain(&[s.pair_k.len(), s.w.len(), s.kinematic.len(), s.targets.len(), s.external.len()])
                .chain(&[s.wq.len(), s.length.len(), s.compliance.len(), s.bonded.len(), s.broken.len()])
                .all(|&len| len == n)
    );
    let edges = n - 1;
    let dt = k.dt;

    // Rest shape by S1-15 from the shape at the start of the step; fresh multipliers.
    for i in 1..edges {
        let omega = darboux_canonical(s.q[i - 1], s.q[i]);
        s.rest[i] = s.bonded[i] + s.broken[i] * omega;
        s.lambda[i] = Vec3::ZERO;
    }

    // External forces act on velocities before prediction.
    for i in 0..n {
        s.v[i] += (k.gravity + s.external[i]) * dt;
    }
    hooks.accelerate(strand, first, s.x, s.v, dt);
}

/// Prediction: kinematic vertices to their targets, the others along their velocities.
fn predict(s: &mut Strand<'_>, dt: f32) {
    for i in 0..s.x.len() {
        s.x_prev[i] = s.x[i];
        s.x[i] = if s.kinematic[i] { s.targets[i] } else { s.x[i] + s.v[i] * dt };
    }
}

/// The direct solve's view of one strand.
fn direct_state<'s>(s: &'s mut Strand<'_>) -> super::strand_solve::StrandState<'s> {
    super::strand_solve::StrandState {
        x: s.x,
        q: s.q,
        lambda: s.lambda,
        w: s.w,
        wq: s.wq,
        length: s.length,
        rest: s.rest,
        pair_k: s.pair_k,
    }
}

/// Gauss–Seidel along the first `edges` edges, alternating root→tip and tip→root sweeps: a
/// one-way sweep passes a correction only one edge against its direction per iteration, and a
/// hanging strand needs tension carried from the tip up as much as positions carried from the root
/// down. With the direct strand solve, Gauss–Seidel only keeps the held span before the free tail.
fn sweep(s: &mut Strand<'_>, edges: usize, iteration: u32) {
    sweep_order(edges, iteration, |projection| match projection {
        Projection::Edge(e) => project_edge(s, e),
        Projection::Pair(e) => project_pair(s, e),
    });
}

/// One constraint projection of a Gauss–Seidel sweep: an edge's stretch–shear, or the bend–twist
/// of the pair centred between edges `e − 1` and `e`.
pub(super) enum Projection {
    Edge(usize),
    Pair(usize),
}

/// The order of [`sweep`]'s projections, shared by the one-strand and the SIMD-lane solvers.
#[inline(always)]
pub(super) fn sweep_order(edges: usize, iteration: u32, mut project: impl FnMut(Projection)) {
    if iteration % 2 == 0 {
        for e in 0..edges {
            project(Projection::Edge(e));
            if e >= 1 {
                project(Projection::Pair(e));
            }
        }
    } else {
        for e in (0..edges).rev() {
            project(Projection::Edge(e));
            if e + 1 < edges {
                project(Projection::Pair(e + 1));
            }
        }
    }
}

/// Velocities from the positions actually reached.
fn update_velocities(s: &mut Strand<'_>, k: &StepConstants) {
    let inv_dt = 1.0 / k.dt;
    for i in 0..s.x.len() {
        s.v[i] = (s.x[i] - s.x_prev[i]) * (inv_dt * k.velocity_keep);
    }
}

/// Prediction, iterations and velocity update of one strand.
fn finish_step_scalar(mut s: Strand<'_>, k: &StepConstants, hooks: &dyn Hooks, strand: usize, first: usize) {
    predict(&mut s, k.dt);
    // Frames are quasi-static: they carry no angular momentum and start each step where the
    // last ended. (Hair's rotational inertia is negligible, the frame inertia here is only a
    // conditioning choice, and integrating frame angular velocities fed energy into resting curls.)
    let free_from = free_tail(s.kinematic);
    let swept_edges = if k.direct { free_from } else { s.x.len() - 1 };
    for iteration in 0..k.iterations {
        if k.direct {
            solve_held_span(&mut s, free_from);
            STRAND_SCRATCH.with(|scratch| {
                super::strand_solve::solve(&mut direct_state(&mut s), free_from, &mut scratch.borrow_mut())
            });
        } else {
            let edges = s.x.len() - 1;
            solve_stretch_shear(&mut s, edges);
        }
        sweep(&mut s, swept_edges, iteration);
        hooks.project(strand, first, s.x, s.w);
    }
    update_velocities(&mut s, k);
}

/// Strands solved at once by the direct solve's lanes.
const DIRECT_LANES: usize = 4;
const _: () = assert!(lanes::LANES % DIRECT_LANES == 0);

/// [`finish_step_scalar`] with the direct solve for a lane group's strands (equal vertex counts):
/// 4 strands whose free tails start at the same edge share one lane solve, others are solved
/// alone; either way each strand gets the bits [`finish_step_scalar`] gives it, and the sweeps and
/// hooks see each strand as they would there.
fn finish_step_direct_lanes(
    views: &mut [Strand<'_>; lanes::LANES],
    k: &StepConstants,
    hooks: &dyn Hooks,
    first_strand: usize,
    first_vertex: impl Fn(usize) -> usize,
) {
    for s in views.iter_mut() {
        predict(s, k.dt);
    }
    let free_from: [usize; lanes::LANES] = std::array::from_fn(|l| free_tail(views[l].kinematic));
    for iteration in 0..k.iterations {
        for (s, &free) in views.iter_mut().zip(&free_from) {
            solve_held_span(s, free);
        }
        STRAND_SCRATCH.with(|scratch| {
            let scratch = &mut scratch.borrow_mut();
            for (group, free) in
                views.chunks_exact_mut(DIRECT_LANES).zip(free_from.chunks_exact(DIRECT_LANES))
            {
                if free.iter().all(|&f| f == free[0]) {
                    let mut states = group.iter_mut().map(direct_state);
                    let mut states: [_; DIRECT_LANES] =
                        std::array::from_fn(|_| states.next().expect("a lane"));
                    super::strand_solve::solve_lanes(&mut states, free[0], scratch);
                } else {
                    for (s, &f) in group.iter_mut().zip(free) {
                        super::strand_solve::solve(&mut direct_state(s), f, scratch);
                    }
                }
            }
        });
        for (l, s) in views.iter_mut().enumerate() {
            sweep(s, free_from[l], iteration);
            let strand = first_strand + l;
            hooks.project(strand, first_vertex(strand), s.x, s.w);
        }
    }
    for s in views.iter_mut() {
        update_velocities(s, k);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stretches asked of a strand of 6 unit edges along x, its root and vertex 4 held: the
    /// span between them is stretched only when its ends lie further apart than 0.98 of its rest
    /// length (measured from the first edge's end when the root frame is pinned), the free tail
    /// never.
    #[test]
    fn only_spans_held_taut_at_both_ends_are_stretched() {
        let kinematic = [true, false, false, false, true, false, false];
        let stretches = |held: Vec3, clamp: Option<Vec3>| {
            let x = |v: usize| if v == 4 { held } else { Vec3::new(v as f32, 0.0, 0.0) };
            let mut spans = HeldSpans::new(|v| kinematic[v], x, |_| 1.0, 6, clamp);
            (0..6).map(|e| spans.stretch(e)).collect::<Vec<f32>>()
        };
        // Slack: 3.5 apart, rest length 4.
        assert_eq!(stretches(Vec3::new(3.5, 0.0, 0.0), None), vec![1.0; 6]);
        // Taut: 4.2 apart; edges 0–3 stretched to leave 2 % slack, the tail not.
        let taut = stretches(Vec3::new(4.2, 0.0, 0.0), None);
        let factor = 4.2 / (0.98 * 4.0);
        assert!(taut[..4].iter().all(|&f| (f - factor).abs() < 1e-6), "{taut:?}");
        assert_eq!(taut[4..], [1.0, 1.0]);
        // A pinned root frame holding vertex 1 at (0, 1, 0): vertex 4 at (3, 1, 0) is 3 from it,
        // the rest length after the first edge is 3, so edges 1–3 stretch by 1/0.98 and edge 0
        // keeps its length.
        let clamped = stretches(Vec3::new(3.0, 1.0, 0.0), Some(Vec3::new(0.0, 1.0, 0.0)));
        assert_eq!(clamped[0], 1.0);
        assert!(clamped[1..4].iter().all(|&f| (f - 1.0 / 0.98).abs() < 1e-6), "{clamped:?}");
        // An edge between two held vertices is no span: nothing to stretch, however far apart.
        let mut spans = HeldSpans::new(|v| v <= 1, |v| Vec3::new(5.0 * v as f32, 0.0, 0.0), |_| 1.0, 2, None);
        assert_eq!([spans.stretch(0), spans.stretch(1)], [1.0, 1.0]);
    }
}
