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
//! linear time. Bend–twist keeps its XPBD multiplier (`rhs = −C − α̃·λ`), stretch–shear has zero
//! compliance, so the converged state is the same static equilibrium at any Δt and iteration count.
use glam::{DMat3, DVec3, Quat, Vec3};

use super::constraints::{director3, BendTwistCoefficients};

/// A symmetric 6×6 block as 2×2 blocks of 3×3: `[bend–twist, stretch–shear]`.
#[derive(Clone, Copy, Default)]
struct Block([[DMat3; 2]; 2]);

/// Two 3-vectors: `[bend–twist, stretch–shear]`.
type Pair = [DVec3; 2];

impl Block {
    fn zero() -> Block {
        Block([[DMat3::ZERO; 2]; 2])
    }

    fn apply(&self, v: &Pair) -> Pair {
        let m = &self.0;
        [m[0][0] * v[0] + m[0][1] * v[1], m[1][0] * v[0] + m[1][1] * v[1]]
    }

    /// The inverse of a symmetric positive definite block, by the Schur complement of its first
    /// 3×3 block.
    fn inverse(&self) -> Block {
        let [[a, b], [_, c]] = self.0;
        let a_inv = a.inverse();
        let a_inv_b = a_inv * b;
        let schur_inv = (c - b.transpose() * a_inv_b).inverse();
        let top_right = -(a_inv_b * schur_inv);
        Block([
            [a_inv + a_inv_b * schur_inv * a_inv_b.transpose(), top_right],
            [top_right.transpose(), schur_inv],
        ])
    }
}

/// `[v]×`, the cross-product matrix: `[v]×·a = v × a`.
fn cross_matrix(v: DVec3) -> DMat3 {
    DMat3::from_cols(DVec3::new(0.0, v.z, -v.y), DVec3::new(-v.z, 0.0, v.x), DVec3::new(v.y, -v.x, 0.0))
}

/// Per-thread working memory of [`solve`].
#[derive(Default)]
pub(crate) struct Scratch {
    /// Per edge: the eliminated diagonal block's inverse, the block coupling to the next edge,
    /// the eliminated right-hand side (then the solution).
    inverse: Vec<Block>,
    upper: Vec<Block>,
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
// Each edge reads its neighbours' entries of several arrays: index loops say that plainest.
#[allow(clippy::needless_range_loop)]
pub(crate) fn solve(s: &mut StrandState<'_>, start: usize, scratch: &mut Scratch) {
    let n = s.x.len();
    let edges = n - 1;
    if start >= edges {
        return;
    }
    let sc = scratch;
    for v in [&mut sc.inverse, &mut sc.upper] {
        v.clear();
        v.resize(n, Block::zero());
    }
    sc.values.clear();
    sc.values.resize(n, [DVec3::ZERO; 2]);
    sc.g.clear();
    sc.g.resize(n, DMat3::ZERO);
    sc.d.clear();
    sc.d.resize(n, DVec3::ZERO);

    let turn_w = |e: usize| if e >= start { 4.0 * s.wq[e] as f64 } else { 0.0 };
    let has_pair = |e: usize| e >= 1 && e >= start.max(1);
    // Constraint values and Jacobian pieces.
    sc.c_bt.clear();
    sc.c_bt.resize(n, DVec3::ZERO);
    let c_bt = &mut sc.c_bt;
    for e in start..edges {
        let q = s.q[e];
        sc.d[e] = director3(q).as_dvec3();
        if has_pair(e) {
            let u = s.q[e - 1].conjugate() * q;
            let v = DVec3::new(u.x as f64, u.y as f64, u.z as f64);
            let rest = s.rest[e];
            let w0 = (1.0 - rest.length_squared()).max(0.0).sqrt();
            let rest = if u.w * w0 + Vec3::new(u.x, u.y, u.z).dot(rest) < 0.0 { -rest } else { rest };
            c_bt[e] = v - rest.as_dvec3();
            let k = (DMat3::from_diagonal(DVec3::splat(u.w as f64)) - cross_matrix(v)) * 0.5;
            let r_prev = DMat3::from_quat(s.q[e - 1].as_dquat());
            sc.g[e] = k * r_prev.transpose();
        }
    }
    // Assemble and eliminate forward.
    for e in start..edges {
        let l = s.length[e] as f64;
        let d = sc.d[e];
        let we = turn_w(e);
        let (w1, w2) = (s.w[e] as f64, s.w[e + 1] as f64);
        let shear = cross_matrix(d) * l; // ∂C_ss/∂θ_e
        let mut diag = Block::zero();
        let mut rhs: Pair = [DVec3::ZERO, DVec3::ZERO];
        if has_pair(e) {
            let g = sc.g[e];
            let alpha = s.pair_k[e].compliance_dt2.as_dvec3();
            let frames = turn_w(e - 1) + we;
            diag.0[0][0] = g * g.transpose() * frames + DMat3::from_diagonal(alpha);
            diag.0[0][1] = g * shear.transpose() * we;
            diag.0[1][0] = diag.0[0][1].transpose();
            rhs[0] = -c_bt[e] - alpha * s.lambda[e].as_dvec3();
        } else {
            diag.0[0][0] = DMat3::IDENTITY;
        }
        let vertices = (w1 + w2) * (1.0 + 1e-6);
        diag.0[1][1] = DMat3::from_diagonal(DVec3::splat(vertices)) + shear * shear.transpose() * we;
        rhs[1] = (l * d) - (s.x[e + 1] - s.x[e]).as_dvec3();
        // Tiny relative regularisation: a pair between two held frames, or a stiff pair with no
        // compliance, keeps an invertible pivot without changing solvable systems measurably.
        for i in 0..2 {
            let m = &mut diag.0[i][i];
            let scale = m.x_axis.x.abs().max(m.y_axis.y.abs()).max(m.z_axis.z.abs()).max(1e-30);
            *m += DMat3::from_diagonal(DVec3::splat(scale * 1e-9));
        }
        // Coupling to edge e + 1.
        if e + 1 < edges {
            let mut up = Block::zero();
            if has_pair(e + 1) {
                let g_next = sc.g[e + 1];
                if has_pair(e) {
                    up.0[0][0] = -(sc.g[e] * g_next.transpose()) * we;
                }
                up.0[1][0] = -(shear * g_next.transpose()) * we;
            }
            up.0[1][1] = DMat3::from_diagonal(DVec3::splat(-w2));
            sc.upper[e] = up;
        }
        if e > start {
            // diag −= Uᵀ·P⁻¹·U with U = [[A, 0], [B, −w·I]] (bend–twist of the next pair meets
            // only this frame; stretch–shear of the next edge only the shared vertex).
            let [[a, _], [b, w_minus]] = sc.upper[e - 1].0;
            let w_prev = -w_minus.x_axis.x;
            let [[p, q], [_, r]] = sc.inverse[e - 1].0;
            let (x00, x01) = (p * a + q * b, q * -w_prev);
            let (x10, x11) = (q.transpose() * a + r * b, r * -w_prev);
            let (at, bt) = (a.transpose(), b.transpose());
            let m00 = at * x00 + bt * x10;
            let m01 = at * x01 + bt * x11;
            let m11 = x11 * -w_prev;
            diag.0[0][0] -= m00;
            diag.0[0][1] -= m01;
            diag.0[1][0] -= m01.transpose();
            diag.0[1][1] -= m11;
            let y = sc.values[e - 1];
            let py = [p * y[0] + q * y[1], q.transpose() * y[0] + r * y[1]];
            rhs[0] -= at * py[0] + bt * py[1];
            rhs[1] -= py[1] * -w_prev;
        }
        sc.inverse[e] = diag.inverse();
        sc.values[e] = rhs;
    }
    // Back substitution.
    for e in (start..edges).rev() {
        let mut r = sc.values[e];
        if e + 1 < edges {
            let next = sc.upper[e].apply(&sc.values[e + 1]);
            r = [r[0] - next[0], r[1] - next[1]];
        }
        sc.values[e] = sc.inverse[e].apply(&r);
    }
    // Apply: Δx = W·Jᵀ·Δμ, Δθ = 4wq·Jᵀ·Δμ, λ += Δλ.
    for j in start..=edges {
        let before = if j > start { sc.values[j - 1][1] } else { DVec3::ZERO };
        let after = if j < edges { sc.values[j][1] } else { DVec3::ZERO };
        s.x[j] += (s.w[j] as f64 * (before - after)).as_vec3();
    }
    for e in start..edges {
        let we = turn_w(e);
        if has_pair(e) {
            s.lambda[e] += sc.values[e][0].as_vec3();
        }
        if we <= 0.0 {
            continue;
        }
        let l = s.length[e] as f64;
        let mut turn = l * cross_matrix(sc.d[e]).transpose() * sc.values[e][1];
        if has_pair(e) {
            turn += sc.g[e].transpose() * sc.values[e][0];
        }
        if e + 1 < edges && has_pair(e + 1) {
            turn -= sc.g[e + 1].transpose() * sc.values[e + 1][0];
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
