//! The time stepper: per strand, rest shapes and forces (`begin_step`) → prediction of positions
//! and frames → per iteration one direct solve of every constraint of the strand together →
//! velocity and angular-velocity update.
//!
//! # The direct solve (Deul, Kugelstadt, Weiler, Bender 2018)
//! Each iteration is an XPBD Newton step over the whole strand: the multiplier increments `Δλ`
//! solve `(J·W·Jᵀ + α̃)·Δλ = −C − α̃·λ` exactly, with `C` the stretch–shear (hard) and bend–twist
//! (compliance `α̃ = α/Δt²`) constraints and `W` the inverse masses and frame inertias; then
//! `Δx = W·Jᵀ·Δλ`. Ordering the constraints edge by edge (bend–twist of the pair ending at edge
//! `e`, then stretch–shear of edge `e`) makes the matrix block-tridiagonal with 6 × 6 blocks, so
//! a block Thomas (block Cholesky) elimination solves it in time linear in the strand's length.
//! A step therefore reaches the implicit solution in a few iterations whatever the stiffness,
//! segment length or Δt; Gauss–Seidel passed a correction one edge per sweep and left stiff,
//! finely cut strands soft. The root edge is solved with the rest, so nothing sweeps after it and
//! vertex 1 stays on the clamp.
//!
//! Frames rotate by a world angular increment `δθ`: `q ← q + ½·(0,δθ)⊗q`. With `d3` the edge's
//! third director and `r = q̄₁⊗q₂`, the Jacobians are `∂C_ss/∂θ = [d3]×` and
//! `∂Ω/∂θ₂ = −∂Ω/∂θ₁ = ½·(r_w·I − [r_v]×)·R₁ᵀ`.
//!
//! Strands run in parallel on rayon by recursively splitting every array at strand boundaries
//! (`split_at_mut`): safe code only, and each strand's arithmetic is the same at any thread count
//! and any split, so results are bit-identical.
// Small dense blocks read most plainly as index loops.
#![allow(clippy::needless_range_loop)]

use std::cell::RefCell;

use glam::{DMat3, DVec3, Quat, Vec3};

use super::constraints::darboux_canonical;
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

/// Declares `Span`: every rod array restricted to a run of whole strands, which can be split in
/// two at a strand boundary without unsafe code.
macro_rules! span {
    (mutable { $($m:ident: $mt:ty),* $(,)? } shared { $($r:ident: $rt:ty),* $(,)? }) => {
        struct Span<'a> {
            /// Absolute vertex offsets of the span's strands (one more than strands).
            offsets: &'a [u32],
            first_strand: usize,
            $($m: &'a mut [$mt],)*
            $($r: &'a [$rt],)*
        }

        impl<'a> Span<'a> {
            /// The first `strands` strands and the rest.
            fn split(self, strands: usize) -> (Span<'a>, Span<'a>) {
                let at = (self.offsets[strands] - self.offsets[0]) as usize;
                $(let $m = self.$m.split_at_mut(at);)*
                $(let $r = self.$r.split_at(at);)*
                (
                    Span { offsets: &self.offsets[..=strands], first_strand: self.first_strand, $($m: $m.0,)* $($r: $r.0,)* },
                    Span {
                        offsets: &self.offsets[strands..],
                        first_strand: self.first_strand + strands,
                        $($m: $m.1,)*
                        $($r: $r.1,)*
                    },
                )
            }

            /// Every array holds exactly the span's vertices.
            fn consistent(&self) -> bool {
                let n = (self.offsets[self.offsets.len() - 1] - self.offsets[0]) as usize;
                true $(&& self.$m.len() == n)* $(&& self.$r.len() == n)*
            }
        }
    };
}

span! {
    mutable {
        x: Vec3, v: Vec3, x_prev: Vec3, q: Quat, q_prev: Quat, omega: Vec3, rest: Vec3, lambda: Vec3,
    }
    shared {
        w: f32, wq: f32, kinematic: bool, targets: Vec3, external: Vec3, length: f32,
        compliance: Vec3, bonded: Vec3, broken: f32,
    }
}

impl Span<'_> {
    fn strands(&self) -> usize {
        self.offsets.len() - 1
    }

    fn vertices(&self) -> usize {
        (self.offsets[self.offsets.len() - 1] - self.offsets[0]) as usize
    }
}

/// Strands below this many vertices in a span are stepped on one thread (work-splitting grain).
const GRAIN_VERTICES: usize = 4096;

/// Advances every strand by one step.
pub(crate) fn step_all(
    rods: &mut Rods,
    bonded: &[Vec3],
    broken: &[f32],
    k: &StepConstants,
    hooks: &dyn Hooks,
) {
    let parts = rods.solver_parts();
    let span = Span {
        offsets: parts.offsets,
        first_strand: 0,
        x: parts.x,
        v: parts.v,
        x_prev: parts.x_prev,
        q: parts.q,
        q_prev: parts.q_prev,
        omega: parts.omega,
        rest: parts.rest,
        lambda: parts.lambda,
        w: parts.w,
        wq: parts.wq,
        kinematic: parts.kinematic,
        targets: parts.targets,
        external: parts.external,
        length: parts.length,
        compliance: parts.compliance,
        bonded,
        broken,
    };
    assert!(span.consistent(), "bond arrays must cover every vertex");
    step_span(span, k, hooks);
}

fn step_span(span: Span<'_>, k: &StepConstants, hooks: &dyn Hooks) {
    let strands = span.strands();
    if strands > 1 && span.vertices() > GRAIN_VERTICES {
        let (a, b) = span.split(strands / 2);
        rayon::join(|| step_span(a, k, hooks), || step_span(b, k, hooks));
        return;
    }
    SCRATCH.with(|scratch| {
        let mut scratch = scratch.borrow_mut();
        let mut remaining = span;
        while remaining.strands() > 0 {
            let (mut one, rest) = remaining.split(1);
            step_strand(&mut one, k, hooks, &mut scratch);
            remaining = rest;
        }
    });
}

/// A 6 × 6 block, rows/columns `(bend–twist xyz, stretch–shear xyz)`.
type Block = [[f64; 6]; 6];

/// What the forward elimination keeps per edge for back substitution and the position update.
#[derive(Clone, Copy, Default)]
struct Row {
    /// Cholesky factor `C_e` of the eliminated diagonal block `D_e = C_e·C_eᵀ` (lower triangle)…
    factor: Block,
    /// …and the inverses of its diagonal.
    inverse_diagonal: [f64; 6],
    /// `V_e = C_{e−1}⁻¹·L_eᵀ`, the coupling to the previous edge through the previous factor.
    v: Block,
    /// `C_e⁻¹·g_e` (the eliminated right-hand side), then `Δλ_e` after back substitution.
    h: [f64; 6],
    /// Third director of edge `e` at the start of the iteration.
    d: DVec3,
    /// `∂Ω_e/∂θ_e` (zero for the root, which has no pair).
    b: DMat3,
}

thread_local! {
    /// Per-thread elimination rows, grown to the longest strand seen (no allocation afterwards).
    static SCRATCH: RefCell<Vec<Row>> = const { RefCell::new(Vec::new()) };
}

fn skew(a: DVec3) -> DMat3 {
    DMat3::from_cols(DVec3::new(0.0, a.z, -a.y), DVec3::new(-a.z, 0.0, a.x), DVec3::new(a.y, -a.x, 0.0))
}

fn put(block: &mut Block, row: usize, col: usize, m: DMat3) {
    for i in 0..3 {
        for j in 0..3 {
            block[row + i][col + j] = m.col(j)[i];
        }
    }
}

/// In-place Cholesky factor (lower triangle, inverse diagonal in `inv`) of a symmetric positive
/// semi-definite block. A pivot that vanishes (a constraint on kinematic vertices and a pinned
/// frame only) decouples its component: it gets increment 0.
fn cholesky(m: &mut Block, inv: &mut [f64; 6]) {
    for j in 0..6 {
        let diagonal = m[j][j];
        let mut s = diagonal;
        for k in 0..j {
            s -= m[j][k] * m[j][k];
        }
        inv[j] = if s > 1e-12 * diagonal && s > 0.0 { 1.0 / s.sqrt() } else { 0.0 };
        for i in j + 1..6 {
            let mut t = m[i][j];
            for k in 0..j {
                t -= m[i][k] * m[j][k];
            }
            m[i][j] = t * inv[j];
        }
    }
}

/// `x ← C⁻¹·x` with a factor from [`cholesky`].
fn forward_substitute(c: &Block, inv: &[f64; 6], x: &mut [f64; 6]) {
    for i in 0..6 {
        let mut t = x[i];
        for k in 0..i {
            t -= c[i][k] * x[k];
        }
        x[i] = t * inv[i];
    }
}

/// `x ← C⁻ᵀ·x` with a factor from [`cholesky`].
fn back_substitute(c: &Block, inv: &[f64; 6], x: &mut [f64; 6]) {
    for i in (0..6).rev() {
        let mut t = x[i];
        for k in i + 1..6 {
            t -= c[k][i] * x[k];
        }
        x[i] = t * inv[i];
    }
}

/// `∂Ω/∂θ₂` of the pair `(q1, q2)`.
fn pair_jacobian(q1: Quat, q2: Quat) -> DMat3 {
    let r = q1.conjugate() * q2;
    let g =
        DMat3::from_diagonal(DVec3::splat(r.w as f64)) - skew(DVec3::new(r.x as f64, r.y as f64, r.z as f64));
    let r1 = DMat3::from_quat(q1.as_dquat());
    0.5 * g * r1.transpose()
}

/// This step's rest shapes, fresh multipliers and forces of one strand.
fn begin_step(s: &mut Span<'_>, k: &StepConstants, hooks: &dyn Hooks) {
    let n = s.x.len();
    for i in 1..n.saturating_sub(1) {
        let omega = darboux_canonical(s.q[i - 1], s.q[i]);
        s.rest[i] = s.bonded[i] + s.broken[i] * omega;
        s.lambda[i] = Vec3::ZERO;
    }
    for i in 0..n {
        s.v[i] += (k.gravity + s.external[i]) * k.dt;
    }
    hooks.accelerate(s.first_strand, s.offsets[0] as usize, s.x, s.v, k.dt);
}

fn step_strand(s: &mut Span<'_>, k: &StepConstants, hooks: &dyn Hooks, rows: &mut Vec<Row>) {
    let n = s.x.len();
    if n < 2 {
        return;
    }
    let edges = n - 1;
    if rows.len() < edges {
        rows.resize(edges, Row::default());
    }
    let rows = &mut rows[..edges];
    begin_step(s, k, hooks);
    let dt = k.dt;
    // Prediction: vertices and frames move on with their velocities (frames carry angular
    // momentum, so turning them costs no drag that depends on Δt); kinematic ones follow targets.
    for i in 0..n {
        s.x_prev[i] = s.x[i];
        s.x[i] = if s.kinematic[i] { s.targets[i] } else { s.x[i] + s.v[i] * dt };
    }
    for e in 0..edges {
        s.q_prev[e] = s.q[e];
        if s.wq[e] > 0.0 {
            let spin = Quat::from_xyzw(s.omega[e].x, s.omega[e].y, s.omega[e].z, 0.0) * s.q[e];
            s.q[e] = (s.q[e] + spin * (0.5 * dt)).normalize();
        }
    }
    let first = s.offsets[0] as usize;
    let inv_dt2 = 1.0 / (dt as f64 * dt as f64);
    for _ in 0..k.iterations {
        solve_strand(s, rows, inv_dt2);
        hooks.project(s.first_strand, first, s.x, s.w);
    }
    s.q[edges] = s.q[edges - 1];
    // Velocities from the positions and frames actually reached.
    let scale = k.velocity_keep / dt;
    for i in 0..n {
        s.v[i] = (s.x[i] - s.x_prev[i]) * scale;
    }
    for e in 0..edges {
        let turn = s.q[e] * s.q_prev[e].conjugate();
        let turn = if turn.w < 0.0 { -turn } else { turn };
        s.omega[e] = Vec3::new(turn.x, turn.y, turn.z) * (2.0 * scale);
    }
}

/// One Newton step of every constraint of the strand (see the module docs).
fn solve_strand(s: &mut Span<'_>, rows: &mut [Row], inv_dt2: f64) {
    let edges = rows.len();
    let w = |i: usize| s.w[i] as f64;
    let wq = |e: usize| s.wq[e] as f64;
    // Row e's coupling to row e − 1, `L_e`, is built while row e − 1 is eliminated.
    for e in 0..edges {
        let d = s.q[e] * Vec3::Z;
        rows[e].d = d.as_dvec3();
        rows[e].b = if e > 0 { pair_jacobian(s.q[e - 1], s.q[e]) } else { DMat3::ZERO };
    }
    for e in 0..edges {
        let (d, b) = (rows[e].d, rows[e].b);
        let l = s.length[e] as f64;
        let se = skew(d);
        // Diagonal block A_ee and right-hand side r_e.
        let mut m: Block = [[0.0; 6]; 6];
        let a = (w(e) + w(e + 1)) / (l * l);
        let shear = DMat3::IDENTITY * a + (DMat3::IDENTITY - outer(d, d)) * wq(e);
        put(&mut m, 3, 3, shear);
        let mut rhs = [0.0; 6];
        let gamma = (s.x[e + 1] - s.x[e]).as_dvec3() / l - d;
        for i in 0..3 {
            rhs[3 + i] = -gamma[i];
        }
        if e > 0 {
            let alpha = s.compliance[e].as_dvec3() * inv_dt2;
            let bend = b * b.transpose() * (wq(e - 1) + wq(e)) + DMat3::from_diagonal(alpha);
            put(&mut m, 0, 0, bend);
            let cross = b * se.transpose() * wq(e);
            put(&mut m, 0, 3, cross);
            put(&mut m, 3, 0, cross.transpose());
            // Bend–twist residual against the rest shape on the same side of the double cover.
            let relative = s.q[e - 1].conjugate() * s.q[e];
            let omega = Vec3::new(relative.x, relative.y, relative.z);
            let rest = s.rest[e];
            let w0 = (1.0 - rest.length_squared()).max(0.0).sqrt();
            let rest = if relative.w * w0 + omega.dot(rest) < 0.0 { -rest } else { rest };
            let c = (omega - rest).as_dvec3() + alpha * s.lambda[e].as_dvec3();
            for i in 0..3 {
                rhs[i] = -c[i];
            }
            // Eliminate the previous edge: D_e = A_ee − VᵀV, g_e = r_e − Vᵀ·h_{e−1} with
            // V = C_{e−1}⁻¹·L_eᵀ (column j of L_eᵀ is row j of L_e).
            let coupling = coupling(rows, s, e);
            let (previous, current) = rows.split_at_mut(e);
            let previous = &previous[e - 1];
            let mut v: Block = [[0.0; 6]; 6];
            for j in 0..6 {
                let mut column = coupling[j];
                forward_substitute(&previous.factor, &previous.inverse_diagonal, &mut column);
                for i in 0..6 {
                    v[i][j] = column[i];
                }
            }
            for i in 0..6 {
                for j in 0..=i {
                    let mut t = 0.0;
                    for k in 0..6 {
                        t += v[k][i] * v[k][j];
                    }
                    m[i][j] -= t;
                }
                let mut t = 0.0;
                for k in 0..6 {
                    t += v[k][i] * previous.h[k];
                }
                rhs[i] -= t;
            }
            current[0].v = v;
        }
        let row = &mut rows[e];
        cholesky(&mut m, &mut row.inverse_diagonal);
        forward_substitute(&m, &row.inverse_diagonal, &mut rhs);
        row.factor = m;
        row.h = rhs;
    }
    // Back substitution: Δλ_e = C_e⁻ᵀ·(h_e − V_{e+1}·Δλ_{e+1}).
    for e in (0..edges).rev() {
        let (current, next) = rows.split_at_mut(e + 1);
        let row = &mut current[e];
        if let Some(next) = next.first() {
            for i in 0..6 {
                let mut t = 0.0;
                for j in 0..6 {
                    t += next.v[i][j] * next.h[j];
                }
                row.h[i] -= t;
            }
        }
        back_substitute(&row.factor, &row.inverse_diagonal, &mut row.h);
    }
    // Δx = W·Jᵀ·Δλ.
    for e in 0..edges {
        let z = rows[e].h;
        let twist = DVec3::new(z[0], z[1], z[2]);
        let stretch = DVec3::new(z[3], z[4], z[5]);
        let l = s.length[e] as f64;
        s.lambda[e] += twist.as_vec3();
        if !s.kinematic[e] {
            let mut dx = -stretch / l;
            if e > 0 {
                let before = rows[e - 1].h;
                dx += DVec3::new(before[3], before[4], before[5]) / s.length[e - 1] as f64;
            }
            s.x[e] += (dx * w(e)).as_vec3();
        }
        if wq(e) > 0.0 {
            let mut dtheta = stretch.cross(rows[e].d) + rows[e].b.transpose() * twist;
            if e + 1 < edges {
                let after = rows[e + 1].h;
                dtheta -= rows[e + 1].b.transpose() * DVec3::new(after[0], after[1], after[2]);
            }
            let dtheta = (dtheta * wq(e)).as_vec3();
            let q = s.q[e];
            s.q[e] = (q + Quat::from_xyzw(dtheta.x, dtheta.y, dtheta.z, 0.0) * q * 0.5).normalize();
        }
    }
    let last = edges;
    if !s.kinematic[last] {
        let before = rows[last - 1].h;
        let dx = DVec3::new(before[3], before[4], before[5]) / s.length[last - 1] as f64;
        s.x[last] += (dx * w(last)).as_vec3();
    }
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// `L_e = A_{e,e−1}` (rows of edge `e`, columns of edge `e − 1`); needs rows `e − 1` and `e`'s
/// director and pair Jacobian.
fn coupling(rows: &[Row], s: &Span<'_>, e: usize) -> Block {
    let mut c: Block = [[0.0; 6]; 6];
    let wq = s.wq[e - 1] as f64;
    if e >= 1 && wq > 0.0 {
        let b = rows[e].b;
        if e >= 2 {
            put(&mut c, 0, 0, -(b * rows[e - 1].b.transpose()) * wq);
        }
        put(&mut c, 0, 3, -(b * skew(rows[e - 1].d).transpose()) * wq);
    }
    let shared = -(s.w[e] as f64) / (s.length[e] as f64 * s.length[e - 1] as f64);
    for i in 0..3 {
        c[3 + i][3 + i] = shared;
    }
    c
}
