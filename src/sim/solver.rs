//! The time stepper: per strand, rest shapes and forces (`begin_step`) → prediction → per
//! iteration a direct solve of the edge lengths and a Gauss–Seidel sweep along the strand
//! (stretch–shear of edge `e`, then bend–twist of the pair ending at `e`; sweeps alternate
//! direction) → velocity update. Lane groups of 8 strands run the same sequence in `lanes`.
//! Strands run in parallel on rayon; each strand's work reads and writes only its own slices, so
//! results are bit-identical at any thread count and any chunking.
use std::cell::RefCell;
use std::ops::Range;

use glam::{Quat, Vec3};
use rayon::prelude::*;

use super::constraints::{
    darboux_canonical, project_bend_twist_with, project_stretch_shear_with, BendTwistCoefficients,
    StretchShearCoefficients,
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
    directions: &'a mut [Vec3],
    upper: &'a mut [f32],
    values: &'a mut [f32],
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
    directions: SharedMut<Vec3>,
    upper: SharedMut<f32>,
    values: SharedMut<f32>,
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
            directions: self.directions.slice(r.clone()),
            upper: self.upper.slice(r.clone()),
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
    static LANE_SCRATCH: RefCell<lanes::Scratch> = RefCell::new(lanes::Scratch::default());
}

/// Advances every strand by one step.
pub(crate) fn step_all(
    rods: &mut Rods,
    bonded: &[Vec3],
    broken: &[f32],
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
        directions: SharedMut::new(a.edge_directions),
        upper: SharedMut::new(a.solve_upper),
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
        // SAFETY: work units cover each strand once (checked in `Rods::from_groom`), and strand
        // ranges are disjoint because the offsets ascend (same check); bounds are checked in
        // `SharedMut::slice`.
        if in_lanes {
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

/// Makes every edge its rest length at once (to first order): the length constraints of a strand
/// form a tridiagonal system `J·W·Jᵀ·λ = −C`, solved exactly by the Thomas algorithm. Gauss–Seidel
/// alone carries a correction one edge per sweep, so under gravity a strand of n edges keeps a
/// stretch that shrinks only like 1/iterations — and the look would depend on the iteration count.
fn solve_lengths(s: &mut Strand<'_>) {
    let edges = s.x.len() - 1;
    for i in 0..edges {
        let d = s.x[i + 1] - s.x[i];
        let length = d.length();
        s.directions[i] = d / length;
        // Right-hand side −C_i, kept in `values` until elimination replaces it.
        s.values[i] = s.length[i] - length;
    }
    // Row i: a_i·λ_{i−1} + b_i·λ_i + c_i·λ_{i+1} = −C_i with b_i = w_i + w_{i+1},
    // a_i = −w_i·(n_{i−1}·n_i), c_i = −w_{i+1}·(n_i·n_{i+1}). Thomas forward elimination:
    let mut upper_prev = 0.0; // c'_{i−1}
    let mut value_prev = 0.0; // d'_{i−1}
    for i in 0..edges {
        let n = s.directions[i];
        let a = if i > 0 { -s.w[i] * n.dot(s.directions[i - 1]) } else { 0.0 };
        let b = s.w[i] + s.w[i + 1];
        let c = if i + 1 < edges { -s.w[i + 1] * n.dot(s.directions[i + 1]) } else { 0.0 };
        let pivot = b - a * upper_prev;
        if pivot > 1e-7 * b && b > 0.0 {
            upper_prev = c / pivot;
            value_prev = (s.values[i] - a * value_prev) / pivot;
        } else {
            // Both ends kinematic: the edge cannot change; decouple its row.
            upper_prev = 0.0;
            value_prev = 0.0;
        }
        s.upper[i] = upper_prev;
        s.values[i] = value_prev;
    }
    // Back substitution: λ_i = d'_i − c'_i·λ_{i+1}.
    let mut next = 0.0;
    for i in (0..edges).rev() {
        next = s.values[i] - s.upper[i] * next;
        s.values[i] = next;
    }
    // Δp_j = w_j·(n_{j−1}·λ_{j−1} − n_j·λ_j).
    for j in 0..=edges {
        let mut dp = Vec3::ZERO;
        if j > 0 {
            dp += s.directions[j - 1] * s.values[j - 1];
        }
        if j < edges {
            dp -= s.directions[j] * s.values[j];
        }
        s.x[j] += s.w[j] * dp;
    }
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
                .chain(&[s.lambda.len(), s.directions.len(), s.upper.len(), s.values.len(), s.edge_k.len()])
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

/// Prediction, iterations and velocity update of one strand.
fn finish_step_scalar(mut s: Strand<'_>, k: &StepConstants, hooks: &dyn Hooks, strand: usize, first: usize) {
    let n = s.x.len();
    let edges = n - 1;
    let dt = k.dt;
    // Prediction.
    for i in 0..n {
        s.x_prev[i] = s.x[i];
        s.x[i] = if s.kinematic[i] { s.targets[i] } else { s.x[i] + s.v[i] * dt };
    }
    // Frames are quasi-static: they carry no angular momentum and start each step where the
    // last ended. (Hair's rotational inertia is negligible, the frame inertia here is only a
    // conditioning choice, and integrating frame angular velocities fed energy into resting curls.)
    // Gauss–Seidel along the strand, alternating root→tip and tip→root sweeps: a one-way sweep
    // passes a correction only one edge against its direction per iteration, and a hanging strand
    // needs tension carried from the tip up as much as positions carried from the root down.
    for iteration in 0..k.iterations {
        solve_lengths(&mut s);
        if iteration % 2 == 0 {
            for e in 0..edges {
                project_edge(&mut s, e);
                if e >= 1 {
                    project_pair(&mut s, e);
                }
            }
        } else {
            for e in (0..edges).rev() {
                project_edge(&mut s, e);
                if e + 1 < edges {
                    project_pair(&mut s, e + 1);
                }
            }
        }
        hooks.project(strand, first, s.x, s.w);
    }

    // Velocities from the positions actually reached.
    let inv_dt = 1.0 / dt;
    for i in 0..n {
        s.v[i] = (s.x[i] - s.x_prev[i]) * (inv_dt * k.velocity_keep);
    }
}
