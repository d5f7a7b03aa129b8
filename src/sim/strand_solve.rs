//! One Newton step of a whole strand's constraints, stretch–shear and bend–twist together, solved
//! directly (Deul, Kugelstadt, Weiler, Bender 2018, "Direct Position-Based Solver for Stiff
//! Rods"). Gauss–Seidel passes a correction one pair along the strand per sweep, so a stiff,
//! finely cut strand (1 cm curls in 1 cm segments) is left soft by any affordable number of
//! sweeps, and how soft depends on Δt: its static shape under gravity was not the elastic one.
//!
//! Unknowns are the multipliers' increments of every constraint of the strand's free tail,
//! ordered per edge `e` as `[bend–twist of the pair ending at e; stretch–shear of e]`. Frames turn
//! by world rotation vectors `δθ` with inverse inertia `4·wq` (the quaternion-space inverse
//! inertia `wq` of the Gauss–Seidel projections, seen as a rotation), vertices move with `w`:
//! * stretch–shear `C = x_{e+1} − x_e − l·d3(q_e)`: `∂C/∂x = ∓I`, `∂C/∂θ_e = l·[d3]×`;
//! * bend–twist `C = Im(q̄_{e−1}⊗q_e) − Ω0`: with `u = q̄_{e−1}⊗q_e = (v, s)`,
//!   `∂C/∂θ_e = G = ½(s·I − [v]×)·R_{e−1}ᵀ` and `∂C/∂θ_{e−1} = −G` (turning both frames alike
//!   changes nothing).
//!
//! Constraints of neighbouring edges share a vertex or a frame and nothing else, so
//! `J·W·Jᵀ + α̃` is block tridiagonal in 6×6 blocks and block Thomas elimination solves it in
//! linear time (each eliminated block factored as `L·D·Lᵀ` in 3×3 blocks, [`Eliminated`]).
//! Bend–twist keeps its XPBD multiplier (`rhs = −C − α̃·λ`), stretch–shear has zero compliance, so
//! the converged state is the same static equilibrium at any Δt and iteration count.
//!
//! Speed: one strand at a time in scalar f64, ~2,000 instructions per edge and iteration
//! (callgrind), two thirds of them arithmetic: assembly builds `G` and three 3×3 products, the
//! elimination two 3×3 inverses and seven products, and it is a serial chain along the strand.
//! Groups of strands in SIMD lanes (as `lanes` does for Gauss–Seidel) are the next lever.
use glam::{DMat3, DVec3, Quat, Vec3};

use super::constraints::{director3, BendTwistCoefficients};

/// Two 3-vectors: `[bend–twist, stretch–shear]`.
type Pair = [DVec3; 2];

/// `[v]×`, the cross-product matrix: `[v]×·a = v × a`.
fn cross_matrix(v: DVec3) -> DMat3 {
    DMat3::from_cols(DVec3::new(0.0, v.z, -v.y), DVec3::new(-v.z, 0.0, v.x), DVec3::new(v.y, -v.x, 0.0))
}

/// `[d]×·m`, column by column (the same products as the matrix product, without its zeros).
fn cross_columns(d: DVec3, m: DMat3) -> DMat3 {
    DMat3::from_cols(d.cross(m.x_axis), d.cross(m.y_axis), d.cross(m.z_axis))
}

/// One edge's eliminated diagonal block `P = [[P00, P10ᵀ], [P10, P11]]` as `L·D·Lᵀ` with
/// `L = [[I, 0], [F, I]]`, `D = diag(P00, S)`, `S = P11 − F·P10ᵀ` (3×3 blocks: two 3×3 inverses
/// instead of a 6×6 one), and its coupling `U = [[A, 0], [B, −w·I]]` to the next edge eliminated,
/// `D⁻¹·L⁻¹·U = [[X, 0], [Y, −w·S⁻¹]]` (bend–twist of the next pair meets only this frame;
/// stretch–shear of the next edge only the shared vertex).
#[derive(Clone, Copy, Default)]
struct Eliminated {
    f: DMat3,
    p00_inv: DMat3,
    s_inv: DMat3,
    x: DMat3,
    y: DMat3,
    /// The shared vertex's inverse mass.
    w: f64,
}

impl Eliminated {
    /// `L⁻¹·v`.
    fn lower_solve(&self, v: Pair) -> Pair {
        [v[0], v[1] - self.f * v[0]]
    }

    /// `D⁻¹·v`.
    fn pivot_solve(&self, v: Pair) -> Pair {
        [self.p00_inv * v[0], self.s_inv * v[1]]
    }

    /// `L⁻ᵀ·v`.
    fn upper_solve(&self, v: Pair) -> Pair {
        [v[0] - self.f.transpose() * v[1], v[1]]
    }

    /// `(D⁻¹·L⁻¹·U)·v`.
    fn coupling(&self, v: Pair) -> Pair {
        [self.x * v[0], self.y * v[0] - self.s_inv * v[1] * self.w]
    }

    /// `(D⁻¹·L⁻¹·U)ᵀ·v`.
    fn coupling_transposed(&self, v: Pair) -> Pair {
        [self.x.transpose() * v[0] + self.y.transpose() * v[1], self.s_inv * v[1] * -self.w]
    }
}

/// Grows `v` to `n` entries; entries are written before they are read, so none is cleared.
fn reserve<T: Clone + Default>(v: &mut Vec<T>, n: usize) {
    if v.len() < n {
        v.resize(n, T::default());
    }
}

/// Per-thread working memory of [`solve`].
#[derive(Default)]
pub(crate) struct Scratch {
    /// Per edge: the eliminated diagonal block and coupling; the forward-eliminated right-hand
    /// side `L⁻¹·(…)` (then the solution).
    eliminated: Vec<Eliminated>,
    values: Vec<Pair>,
    /// Per edge: `G` of the pair ending at it, `d3` of its frame.
    g: Vec<DMat3>,
    d: Vec<DVec3>,
    /// Per pair: the bend–twist constraint's value.
    c_bt: Vec<DVec3>,
}

/// One strand's state as the direct solve needs it (slices over the strand's vertices; frames,
/// lengths and `wq` per edge, the rest shape, multiplier and `α/Δt²` per pair centre).
pub(crate) struct StrandState<'a> {
    pub x: &'a mut [Vec3],
    pub q: &'a mut [Quat],
    pub lambda: &'a mut [Vec3],
    pub w: &'a [f32],
    pub wq: &'a [f32],
    pub length: &'a [f32],
    pub rest: &'a [Vec3],
    /// Per pair centre: the bend–twist coefficients (their `α/Δt²`).
    pub pair_k: &'a [BendTwistCoefficients],
}

/// One linearised solve of the constraints from edge `start` on (the free tail: frames and
/// vertices before it are held), applied to positions, frames and bend–twist multipliers.
///
/// Block `L·D·Lᵀ` elimination along the strand ([`Eliminated`]).
// Each edge reads its neighbours' entries of several arrays: index loops say that plainest.
#[allow(clippy::needless_range_loop)]
pub(crate) fn solve(s: &mut StrandState<'_>, start: usize, scratch: &mut Scratch) {
    let n = s.x.len();
    let edges = n - 1;
    if start >= edges {
        return;
    }
    // Every array as long as the strand, stated once, lets the compiler drop bounds checks.
    assert!([s.q.len(), s.lambda.len(), s.w.len(), s.wq.len(), s.length.len(), s.rest.len(), s.pair_k.len()]
        .iter()
        .all(|&len| len == n));
    let sc = scratch;
    reserve(&mut sc.eliminated, n);
    reserve(&mut sc.values, n);
    reserve(&mut sc.g, n);
    reserve(&mut sc.d, n);
    reserve(&mut sc.c_bt, n);
    let (eliminated, values) = (&mut sc.eliminated[..n], &mut sc.values[..n]);
    let (g, d3, c_bt) = (&mut sc.g[..n], &mut sc.d[..n], &mut sc.c_bt[..n]);

    let turn_w = |e: usize| if e >= start { 4.0 * s.wq[e] as f64 } else { 0.0 };
    let has_pair = |e: usize| e >= 1 && e >= start.max(1);
    // Constraint values and Jacobian pieces.
    for e in start..edges {
        let q = s.q[e];
        d3[e] = director3(q).as_dvec3();
        if has_pair(e) {
            let u = s.q[e - 1].conjugate() * q;
            let v = DVec3::new(u.x as f64, u.y as f64, u.z as f64);
            let rest = s.rest[e];
            let w0 = (1.0 - rest.length_squared()).max(0.0).sqrt();
            let rest = if u.w * w0 + Vec3::new(u.x, u.y, u.z).dot(rest) < 0.0 { -rest } else { rest };
            c_bt[e] = v - rest.as_dvec3();
            let k = (DMat3::from_diagonal(DVec3::splat(u.w as f64)) - cross_matrix(v)) * 0.5;
            let r_prev = DMat3::from_quat(s.q[e - 1].as_dquat());
            g[e] = k * r_prev.transpose();
        }
    }
    // Assemble, factor and eliminate forward. `schur` is what the previous edge's elimination
    // takes off this edge's diagonal block, `Uᵀ·P⁻¹·U` of the previous edge, as 00, 01 (bend–twist
    // rows, stretch–shear columns) and 11 blocks.
    let mut schur = [DMat3::ZERO; 3];
    for e in start..edges {
        let l = s.length[e] as f64;
        let d = d3[e];
        let we = turn_w(e);
        let (w1, w2) = (s.w[e] as f64, s.w[e + 1] as f64);
        let (mut p00, mut p10);
        let mut rhs: Pair = [DVec3::ZERO, DVec3::ZERO];
        if has_pair(e) {
            let g_e = g[e];
            let alpha = s.pair_k[e].compliance_dt2.as_dvec3();
            let frames = turn_w(e - 1) + we;
            p00 = g_e * g_e.transpose() * frames + DMat3::from_diagonal(alpha);
            p10 = cross_columns(d, g_e.transpose()) * (l * we); // ∂C_ss/∂θ_e = l·[d]×
            rhs[0] = -c_bt[e] - alpha * s.lambda[e].as_dvec3();
        } else {
            p00 = DMat3::IDENTITY;
            p10 = DMat3::ZERO;
        }
        let vertices = (w1 + w2) * (1.0 + 1e-6);
        // l²·[d]×·[d]×ᵀ = l²·(|d|²·I − d·dᵀ).
        let frame = l * l * we;
        let mut p11 = DMat3::from_diagonal(DVec3::splat(vertices + frame * d.length_squared()))
            - DMat3::from_cols(d * d.x, d * d.y, d * d.z) * frame;
        rhs[1] = (l * d) - (s.x[e + 1] - s.x[e]).as_dvec3();
        // Tiny relative regularisation: a pair between two held frames, or a stiff pair with no
        // compliance, keeps an invertible pivot without changing solvable systems measurably.
        for m in [&mut p00, &mut p11] {
            let scale = m.x_axis.x.abs().max(m.y_axis.y.abs()).max(m.z_axis.z.abs()).max(1e-30);
            *m += DMat3::from_diagonal(DVec3::splat(scale * 1e-9));
        }
        if e > start {
            let previous = &eliminated[e - 1];
            p00 -= schur[0];
            p10 -= schur[1].transpose();
            p11 -= schur[2];
            let carried = previous.coupling_transposed(values[e - 1]);
            rhs = [rhs[0] - carried[0], rhs[1] - carried[1]];
        }
        let p00_inv = p00.inverse();
        let f = p10 * p00_inv;
        let s_inv = (p11 - f * p10.transpose()).inverse();
        let mut el = Eliminated { f, p00_inv, s_inv, x: DMat3::ZERO, y: DMat3::ZERO, w: w2 };
        values[e] = el.lower_solve(rhs);
        // The coupling to edge e + 1: U = [[A, 0], [B, −w·I]], L⁻¹·U = [[A, 0], [B − F·A, −w·I]].
        if e + 1 < edges {
            let (a, b) = if has_pair(e + 1) {
                let g_next_t = g[e + 1].transpose();
                let a = if has_pair(e) { -(g[e] * g_next_t) * we } else { DMat3::ZERO };
                (a, cross_columns(d, g_next_t) * (-l * we))
            } else {
                (DMat3::ZERO, DMat3::ZERO)
            };
            let b = b - f * a;
            el.x = p00_inv * a;
            el.y = s_inv * b;
            // (L⁻¹·U)ᵀ·D⁻¹·(L⁻¹·U), with P00⁻¹ and S⁻¹ symmetric.
            schur = [a.transpose() * el.x + b.transpose() * el.y, el.y.transpose() * -w2, s_inv * (w2 * w2)];
        }
        eliminated[e] = el;
    }
    // Back substitution: y_e = L⁻ᵀ·(D⁻¹·t_e − D⁻¹·L⁻¹·U·y_{e+1}).
    for e in (start..edges).rev() {
        let el = &eliminated[e];
        let mut r = el.pivot_solve(values[e]);
        if e + 1 < edges {
            let next = el.coupling(values[e + 1]);
            r = [r[0] - next[0], r[1] - next[1]];
        }
        values[e] = el.upper_solve(r);
    }
    let bend_twist = |e: usize| values[e][0];
    let stretch_shear = |e: usize| values[e][1];
    // Apply: Δx = W·Jᵀ·Δμ, Δθ = 4wq·Jᵀ·Δμ, λ += Δλ.
    for j in start..=edges {
        let before = if j > start { stretch_shear(j - 1) } else { DVec3::ZERO };
        let after = if j < edges { stretch_shear(j) } else { DVec3::ZERO };
        s.x[j] += (s.w[j] as f64 * (before - after)).as_vec3();
    }
    for e in start..edges {
        let we = turn_w(e);
        if has_pair(e) {
            s.lambda[e] += bend_twist(e).as_vec3();
        }
        if we <= 0.0 {
            continue;
        }
        let l = s.length[e] as f64;
        let mut turn = l * cross_matrix(d3[e]).transpose() * stretch_shear(e);
        if has_pair(e) {
            turn += g[e].transpose() * bend_twist(e);
        }
        if e + 1 < edges && has_pair(e + 1) {
            turn -= g[e + 1].transpose() * bend_twist(e + 1);
        }
        let turn = (turn * we).as_vec3();
        let q = s.q[e];
        let dq = Quat::from_xyzw(turn.x, turn.y, turn.z, 0.0) * q;
        s.q[e] = (q + dq * 0.5).normalize();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::rod::transport_frames;

    /// With zero compliance a free strand has as many constraints as freedoms (three per vertex,
    /// three per frame), so Newton steps of the direct solve reach a state where every edge runs
    /// its rest length along its frame and every pair has its rest turn, from a start far from
    /// it.
    #[test]
    fn newton_steps_satisfy_every_constraint_of_a_strand() {
        let n = 12;
        let rest_points: Vec<Vec3> = (0..n)
            .map(|i| {
                Vec3::new(0.01 * (i as f32 * 0.7).sin(), -0.008 * i as f32, 0.01 * (i as f32 * 0.7).cos())
            })
            .collect();
        let mut frames = vec![Quat::IDENTITY; n];
        transport_frames(&rest_points, &mut frames);
        let length: Vec<f32> = (0..n)
            .map(|i| if i + 1 < n { rest_points[i].distance(rest_points[i + 1]) } else { 0.0 })
            .collect();
        let rest: Vec<Vec3> = (0..n)
            .map(|i| {
                if i >= 1 && i + 1 < n {
                    super::super::constraints::darboux_canonical(frames[i - 1], frames[i])
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        // Start bent and stretched: every vertex but the root pushed sideways and down.
        let mut x: Vec<Vec3> = rest_points
            .iter()
            .enumerate()
            .map(|(i, p)| *p + Vec3::new(0.003, -0.002, 0.0) * i as f32)
            .collect();
        let mut q = frames.clone();
        let mut lambda = vec![Vec3::ZERO; n];
        let mut w = vec![1.0e6f32; n];
        w[0] = 0.0;
        let mut wq: Vec<f32> = (0..n).map(|i| 0.1 * 1.0e6 / (length[i] * length[i]).max(1e-12)).collect();
        wq[0] = 0.0;
        let rigid = vec![BendTwistCoefficients::default(); n];
        let mut scratch = Scratch::default();
        let residual = |x: &[Vec3], q: &[Quat]| {
            let mut worst = 0.0f32;
            for e in 0..n - 1 {
                let c = x[e + 1] - x[e] - length[e] * director3(q[e]);
                worst = worst.max(c.length() / length[e]);
                if e >= 1 {
                    let u = q[e - 1].conjugate() * q[e];
                    let u = if u.w < 0.0 { -u } else { u };
                    worst = worst.max((Vec3::new(u.x, u.y, u.z) - rest[e]).length());
                }
            }
            worst
        };
        let before = residual(&x, &q);
        for _ in 0..6 {
            let mut state = StrandState {
                x: &mut x,
                q: &mut q,
                lambda: &mut lambda,
                w: &w,
                wq: &wq,
                length: &length,
                rest: &rest,
                pair_k: &rigid,
            };
            solve(&mut state, 0, &mut scratch);
        }
        let after = residual(&x, &q);
        assert!(before > 0.1, "the start is far from rest: {before}");
        assert!(after < 1e-4, "relative residual after 6 Newton steps: {after} (from {before})");
        // The root stays put.
        assert_eq!(x[0], rest_points[0]);
    }
}
