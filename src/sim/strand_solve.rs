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
//!   changes nothing). A joint more than 90° from rest fades over to the error towards a nearer
//!   target on the way to rest, which a Newton step can shrink ([`bend_twist`]).
//!
//! Constraints of neighbouring edges share a vertex or a frame and nothing else, so
//! `J·W·Jᵀ + α̃` is block tridiagonal in 6×6 blocks and block Thomas elimination solves it in
//! linear time (each eliminated block factored as `L·D·Lᵀ` in 3×3 blocks, [`Eliminated`]).
//! Bend–twist keeps its XPBD multiplier (`rhs = −C − α̃·λ`), stretch–shear has zero compliance, so
//! the converged state is the same static equilibrium at any Δt and iteration count.
//!
//! Speed: groups of 4 strands with equal vertex counts and free tails run in f64×4 lanes
//! ([`solve_lanes`], AVX when the CPU has it), one strand per lane, the rest one at a time: the same
//! generic code does both ([`Real`]), and each lane rounds exactly as the scalar solve, so a strand
//! gets the same bits either way. The f32 parts (directors, relative turns, the final frame update)
//! run per strand with glam while the lanes are gathered and scattered. Per edge and iteration:
//! assembly builds `G` and three 3×3 products, the elimination two 3×3 inverses and seven
//! products, and it is a serial chain along the strand. Callgrind, a step of one iteration: 2,155
//! instructions per vertex one strand at a time, 1,055 in lanes (of which ~800 the lane solve,
//! half of that loads and stores of 3×3 lane matrices: 16 AVX registers hold less than two).
use glam::{Quat, Vec3};

use super::constraints::{director3, far_target, far_weight, BendTwistCoefficients};
use super::lane_algebra::{F64x4, Real, M3, V3};

/// Two 3-vectors: `[bend–twist, stretch–shear]`.
type Pair<T> = [V3<T>; 2];

/// `[v]×`, the cross-product matrix: `[v]×·a = v × a`.
#[inline(always)]
fn cross_matrix<T: Real>(v: V3<T>) -> M3<T> {
    let z = T::splat(0.0);
    M3::from_cols(V3::new(z, v.z, -v.y), V3::new(-v.z, z, v.x), V3::new(v.y, -v.x, z))
}

/// `[d]×·m`, column by column (the same products as the matrix product, without its zeros).
#[inline(always)]
fn cross_columns<T: Real>(d: V3<T>, m: M3<T>) -> M3<T> {
    M3::from_cols(d.cross(m.x_axis), d.cross(m.y_axis), d.cross(m.z_axis))
}

/// One edge's eliminated diagonal block `P = [[P00, P10ᵀ], [P10, P11]]` as `L·D·Lᵀ` with
/// `L = [[I, 0], [F, I]]`, `D = diag(P00, S)`, `S = P11 − F·P10ᵀ` (3×3 blocks: two 3×3 inverses
/// instead of a 6×6 one), and its coupling `U = [[A, 0], [B, −w·I]]` to the next edge eliminated,
/// `D⁻¹·L⁻¹·U = [[X, 0], [Y, −w·S⁻¹]]` (bend–twist of the next pair meets only this frame;
/// stretch–shear of the next edge only the shared vertex).
#[derive(Clone, Copy, Default)]
struct Eliminated<T> {
    f: M3<T>,
    p00_inv: M3<T>,
    s_inv: M3<T>,
    x: M3<T>,
    y: M3<T>,
    /// The shared vertex's inverse mass.
    w: T,
}

impl<T: Real> Eliminated<T> {
    /// `L⁻¹·v`.
    #[inline(always)]
    fn lower_solve(&self, v: Pair<T>) -> Pair<T> {
        [v[0], v[1] - self.f.mul_vec(v[0])]
    }

    /// `D⁻¹·v`.
    #[inline(always)]
    fn pivot_solve(&self, v: Pair<T>) -> Pair<T> {
        [self.p00_inv.mul_vec(v[0]), self.s_inv.mul_vec(v[1])]
    }

    /// `L⁻ᵀ·v`.
    #[inline(always)]
    fn upper_solve(&self, v: Pair<T>) -> Pair<T> {
        [v[0] - self.f.transpose().mul_vec(v[1]), v[1]]
    }

    /// `(D⁻¹·L⁻¹·U)·v`.
    #[inline(always)]
    fn coupling(&self, v: Pair<T>) -> Pair<T> {
        [self.x.mul_vec(v[0]), self.y.mul_vec(v[0]) - self.s_inv.mul_vec(v[1]).scale(self.w)]
    }

    /// `(D⁻¹·L⁻¹·U)ᵀ·v`.
    #[inline(always)]
    fn coupling_transposed(&self, v: Pair<T>) -> Pair<T> {
        [
            self.x.transpose().mul_vec(v[0]) + self.y.transpose().mul_vec(v[1]),
            self.s_inv.mul_vec(v[1]).scale(-self.w),
        ]
    }
}

/// Grows `v` to `n` entries; entries are written before they are read, so none is cleared.
fn reserve<T: Clone + Default>(v: &mut Vec<T>, n: usize) {
    if v.len() < n {
        v.resize(n, T::default());
    }
}

/// What the solve reads of one vertex and the edge (and pair) starting at it, widened to f64:
/// the f32 arithmetic (directors, relative turns, edge vectors) is done per strand with glam.
#[derive(Clone, Copy, Default)]
struct Input<T> {
    /// Inverse mass of the vertex.
    w: T,
    /// Edge: `d3` of its frame, rest length, `4·wq` (the frame's inverse inertia as a rotation),
    /// and `x_{e+1} − x_e`.
    d: V3<T>,
    length: T,
    wq4: T,
    dx: V3<T>,
    /// Pair ending at the edge: the bend–twist constraint's value and `K` ([`bend_twist`]), the
    /// previous frame, `α/Δt²` and the multiplier.
    c: V3<T>,
    k: M3<T>,
    q_prev: [T; 4],
    alpha: V3<T>,
    lambda: V3<T>,
}

/// Working memory of one lane width.
#[derive(Default)]
struct Work<T> {
    input: Vec<Input<T>>,
    /// Per edge: the eliminated diagonal block and coupling; the forward-eliminated right-hand
    /// side `L⁻¹·(…)` (then the solution).
    eliminated: Vec<Eliminated<T>>,
    values: Vec<Pair<T>>,
    /// Per edge: `G` of the pair ending at it; per pair: the bend–twist constraint's value.
    g: Vec<M3<T>>,
    c_bt: Vec<V3<T>>,
    /// Per vertex its move, per edge its frame's turn (a rotation vector).
    moved: Vec<V3<T>>,
    turn: Vec<V3<T>>,
}

/// Per-thread working memory of [`solve`] and [`solve_lanes`].
#[derive(Default)]
pub(crate) struct Scratch {
    one: Work<f64>,
    lanes: Work<F64x4>,
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
pub(crate) fn solve(s: &mut StrandState<'_>, start: usize, scratch: &mut Scratch) {
    solve_group(std::slice::from_mut(s), start, &mut scratch.one);
}

/// [`solve`] for 4 strands of equal vertex count and free tail at once, one per f64 lane, with the
/// same results bit for bit.
///
/// On x86-64 CPUs with AVX the same code is compiled a second time with 256-bit registers; AVX
/// without FMA rounds every lane operation exactly as SSE2 does.
pub(crate) fn solve_lanes(strands: &mut [StrandState<'_>; 4], start: usize, scratch: &mut Scratch) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU supports AVX (checked just above).
        unsafe { solve_lanes_avx(strands, start, &mut scratch.lanes) };
        return;
    }
    solve_group(strands, start, &mut scratch.lanes);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn solve_lanes_avx(strands: &mut [StrandState<'_>; 4], start: usize, work: &mut Work<F64x4>) {
    solve_group(strands, start, work);
}

/// Gathers `T::LANES` strands into lanes, solves, scatters.
#[inline(always)]
fn solve_group<T: Real>(strands: &mut [StrandState<'_>], start: usize, work: &mut Work<T>) {
    assert_eq!(strands.len(), T::LANES);
    let n = strands[0].x.len();
    // Every array of every strand as long as the first strand, stated once, lets the compiler drop
    // bounds checks.
    for s in strands.iter() {
        assert!([s.x.len(), s.q.len(), s.lambda.len(), s.w.len(), s.wq.len(), s.length.len()]
            .iter()
            .chain(&[s.rest.len(), s.pair_k.len()])
            .all(|&len| len == n));
    }
    let edges = n - 1;
    if start >= edges {
        return;
    }
    reserve(&mut work.values, n);
    reserve(&mut work.input, n);
    reserve(&mut work.eliminated, n);
    reserve(&mut work.g, n);
    for v in [&mut work.c_bt, &mut work.moved, &mut work.turn] {
        reserve(v, n);
    }
    gather(strands, start, &mut work.input[..n]);
    eliminate(start, work, n);
    scatter(strands, start, work, n);
}

/// Whether edge `e` ends a pair of the free tail.
#[inline(always)]
fn has_pair(e: usize, start: usize) -> bool {
    e >= 1 && e >= start.max(1)
}

/// Each lane's strand into `input`, with the f32 arithmetic of the scalar solve.
#[inline(always)]
fn gather<T: Real>(strands: &[StrandState<'_>], start: usize, input: &mut [Input<T>]) {
    let n = input.len();
    let edges = n - 1;
    for (l, s) in strands.iter().enumerate() {
        let (x, q) = (&s.x[..n], &s.q[..n]);
        for e in start..n {
            let i = &mut input[e];
            i.w.set_lane(l, s.w[e] as f64);
            if e == edges {
                break;
            }
            let qe = q[e];
            i.d.set_lane(l, director3(qe).as_dvec3());
            i.length.set_lane(l, s.length[e] as f64);
            i.wq4.set_lane(l, 4.0 * s.wq[e] as f64);
            i.dx.set_lane(l, (x[e + 1] - x[e]).as_dvec3());
            if has_pair(e, start) {
                let (c, k) = bend_twist(q[e - 1].conjugate() * qe, s.rest[e]);
                i.c.set_lane(l, c.lane(0));
                i.k.set_lane(l, &k);
                let p = q[e - 1].as_dquat();
                for (c, v) in i.q_prev.iter_mut().zip([p.x, p.y, p.z, p.w]) {
                    c.set_lane(l, v);
                }
                i.alpha.set_lane(l, s.pair_k[e].compliance_dt2.as_dvec3());
                i.lambda.set_lane(l, s.lambda[e].as_dvec3());
            }
        }
    }
}

/// The bend–twist constraint of a joint with relative rotation `u = q̄_{e−1}⊗q_e` and rest `Ω0`,
/// linearised: its value `C` and `K` with `∂C/∂θ_e = K·R_{e−1}ᵀ` (see the module docs).
///
/// A joint further from rest than [`super::constraints::FAR_ALIGNMENT`] (a 90° error) fades
/// over, by [`far_weight`], to the error `t̄⊗u` towards the nearer target of [`far_target`]:
/// linearised about a joint near half a turn from rest, `Ω − Ω0` can turn the joint's axis but
/// hardly shrink its angle, and there the side of the double cover flips between iterations, so a
/// fold or twist the blow-dry pressed in stayed, chattering, and the bonds set it.
/// (`∂(t̄⊗u)/∂θ_e` is that of `Ω` with `(v, s)` of `t̄⊗u`, seen from `R_{e−1}·R_t`.)
fn bend_twist(u: Quat, rest: Vec3) -> (V3<f64>, M3<f64>) {
    let linearised = |v: Vec3, s: f32, rest: Vec3| {
        let v = V3::new(v.x as f64, v.y as f64, v.z as f64);
        let rest = V3::new(rest.x as f64, rest.y as f64, rest.z as f64);
        (v - rest, (M3::from_diagonal(V3::splat(s as f64)) - cross_matrix(v)).scale(0.5))
    };
    let v = Vec3::new(u.x, u.y, u.z);
    let w0 = (1.0 - rest.length_squared()).max(0.0).sqrt();
    let alignment = u.w * w0 + v.dot(rest);
    let (rest, w0) = if alignment < 0.0 { (-rest, -w0) } else { (rest, w0) };
    let near = linearised(v, u.w, rest);
    let weight = far_weight(alignment);
    if weight <= 0.0 {
        return near;
    }
    let target = far_target(u, Quat::from_xyzw(rest.x, rest.y, rest.z, w0));
    let error = target.conjugate() * u;
    let (c, k) = linearised(Vec3::new(error.x, error.y, error.z), error.w, Vec3::ZERO);
    let t = target.as_dquat();
    let k = k.mul_mat(&M3::from_quat([t.x, t.y, t.z, t.w]).transpose());
    let (near_share, far_share) = (1.0 - weight as f64, weight as f64);
    (near.0.scale(near_share) + c.scale(far_share), near.1.scale(near_share) + k.scale(far_share))
}

/// Assembly, block `L·D·Lᵀ` elimination along the strand ([`Eliminated`]), back substitution, and
/// the moves and turns: everything in f64, lane by lane.
// Each edge reads its neighbours' entries of several arrays: index loops say that plainest.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn eliminate<T: Real>(start: usize, work: &mut Work<T>, n: usize) {
    let edges = n - 1;
    let input = &work.input[..n];
    let (eliminated, values) = (&mut work.eliminated[..n], &mut work.values[..n]);
    let (g, c_bt) = (&mut work.g[..n], &mut work.c_bt[..n]);
    let (moved, turns) = (&mut work.moved[..n], &mut work.turn[..n]);
    let zero = T::splat(0.0);
    let turn_w = |e: usize| if e >= start { input[e].wq4 } else { zero };
    let has_pair = |e: usize| has_pair(e, start);
    // Constraint values and Jacobian pieces.
    for e in start..edges {
        if has_pair(e) {
            let i = &input[e];
            c_bt[e] = i.c;
            let r_prev = M3::from_quat(i.q_prev);
            g[e] = i.k.mul_mat(&r_prev.transpose());
        }
    }
    // Assemble, factor and eliminate forward. `schur` is what the previous edge's elimination
    // takes off this edge's diagonal block, `Uᵀ·P⁻¹·U` of the previous edge, as 00, 01 (bend–twist
    // rows, stretch–shear columns) and 11 blocks.
    let mut schur = [M3::zero(); 3];
    for e in start..edges {
        let i = &input[e];
        let l = i.length;
        let d = i.d;
        let we = turn_w(e);
        let (w1, w2) = (i.w, input[e + 1].w);
        let (mut p00, mut p10);
        let mut rhs: Pair<T> = [V3::zero(), V3::zero()];
        if has_pair(e) {
            let g_e = g[e];
            let alpha = i.alpha;
            let frames = turn_w(e - 1) + we;
            p00 = g_e.mul_mat(&g_e.transpose()).scale(frames) + M3::from_diagonal(alpha);
            p10 = cross_columns(d, g_e.transpose()).scale(l * we); // ∂C_ss/∂θ_e = l·[d]×
            rhs[0] = -c_bt[e] - alpha.mul(i.lambda);
        } else {
            p00 = M3::identity();
            p10 = M3::zero();
        }
        let vertices = (w1 + w2) * T::splat(1.0 + 1e-6);
        // l²·[d]×·[d]×ᵀ = l²·(|d|²·I − d·dᵀ).
        let frame = l * l * we;
        let mut p11 = M3::from_diagonal(V3::splat(vertices + frame * d.length_squared()))
            - M3::from_cols(d.scale(d.x), d.scale(d.y), d.scale(d.z)).scale(frame);
        rhs[1] = d.scale(l) - i.dx;
        // Tiny relative regularisation: a pair between two held frames, or a stiff pair with no
        // compliance, keeps an invertible pivot without changing solvable systems measurably.
        // Added to the diagonal only: the off-diagonal entries are never −0 here (each is a sum
        // with +0 or a difference from +0), so adding the +0 of a diagonal matrix kept them.
        for m in [&mut p00, &mut p11] {
            let scale = m.x_axis.x.abs().max(m.y_axis.y.abs()).max(m.z_axis.z.abs()).max(T::splat(1e-30));
            let add = scale * T::splat(1e-9);
            m.x_axis.x = m.x_axis.x + add;
            m.y_axis.y = m.y_axis.y + add;
            m.z_axis.z = m.z_axis.z + add;
        }
        if e > start {
            let previous = &eliminated[e - 1];
            p00 = p00 - schur[0];
            p10 = p10 - schur[1].transpose();
            p11 = p11 - schur[2];
            let carried = previous.coupling_transposed(values[e - 1]);
            rhs = [rhs[0] - carried[0], rhs[1] - carried[1]];
        }
        let p00_inv = p00.inverse();
        let f = p10.mul_mat(&p00_inv);
        let s_inv = (p11 - f.mul_mat(&p10.transpose())).inverse();
        let mut el = Eliminated { f, p00_inv, s_inv, x: M3::zero(), y: M3::zero(), w: w2 };
        values[e] = el.lower_solve(rhs);
        // The coupling to edge e + 1: U = [[A, 0], [B, −w·I]], L⁻¹·U = [[A, 0], [B − F·A, −w·I]].
        if e + 1 < edges {
            let (a, b) = if has_pair(e + 1) {
                let g_next_t = g[e + 1].transpose();
                let a = if has_pair(e) { (-g[e].mul_mat(&g_next_t)).scale(we) } else { M3::zero() };
                (a, cross_columns(d, g_next_t).scale(-l * we))
            } else {
                (M3::zero(), M3::zero())
            };
            let b = b - f.mul_mat(&a);
            el.x = p00_inv.mul_mat(&a);
            el.y = s_inv.mul_mat(&b);
            // (L⁻¹·U)ᵀ·D⁻¹·(L⁻¹·U), with P00⁻¹ and S⁻¹ symmetric.
            schur = [
                a.transpose().mul_mat(&el.x) + b.transpose().mul_mat(&el.y),
                el.y.transpose().scale(-w2),
                s_inv.scale(w2 * w2),
            ];
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
    // Δx = W·Jᵀ·Δμ, Δθ = 4wq·Jᵀ·Δμ.
    for j in start..=edges {
        let before = if j > start { stretch_shear(j - 1) } else { V3::zero() };
        let after = if j < edges { stretch_shear(j) } else { V3::zero() };
        moved[j] = (before - after).scale(input[j].w);
    }
    for e in start..edges {
        let we = turn_w(e);
        let l = input[e].length;
        let mut turn = cross_matrix(input[e].d).transpose().scale(l).mul_vec(stretch_shear(e));
        if has_pair(e) {
            turn = turn + g[e].transpose().mul_vec(bend_twist(e));
        }
        if e + 1 < edges && has_pair(e + 1) {
            turn = turn - g[e + 1].transpose().mul_vec(bend_twist(e + 1));
        }
        turns[e] = turn.scale(we);
    }
}

/// Applies each lane's moves, turns and multiplier increments to its strand, with the f32
/// arithmetic of the scalar solve; frames that cannot turn keep their bits.
#[inline(always)]
fn scatter<T: Real>(strands: &mut [StrandState<'_>], start: usize, work: &Work<T>, n: usize) {
    let edges = n - 1;
    let (input, values) = (&work.input[..n], &work.values[..n]);
    let (moved, turns) = (&work.moved[..n], &work.turn[..n]);
    for (l, s) in strands.iter_mut().enumerate() {
        let (x, q, lambda) = (&mut s.x[..n], &mut s.q[..n], &mut s.lambda[..n]);
        for j in start..=edges {
            x[j] += moved[j].lane(l).as_vec3();
        }
        for e in start..edges {
            if has_pair(e, start) {
                lambda[e] += values[e][0].lane(l).as_vec3();
            }
            if input[e].wq4.lane(l) <= 0.0 {
                continue;
            }
            let turn = turns[e].lane(l).as_vec3();
            let qe = q[e];
            let dq = Quat::from_xyzw(turn.x, turn.y, turn.z, 0.0) * qe;
            q[e] = (qe + dq * 0.5).normalize();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::rod::transport_frames;

    /// A strand's arrays, owned.
    #[derive(Clone)]
    struct Strand {
        rest_points: Vec<Vec3>,
        x: Vec<Vec3>,
        q: Vec<Quat>,
        lambda: Vec<Vec3>,
        w: Vec<f32>,
        wq: Vec<f32>,
        length: Vec<f32>,
        rest: Vec<Vec3>,
        pair_k: Vec<BendTwistCoefficients>,
    }

    impl Strand {
        /// A helix of `n` vertices at rest (turning `turn` radians a vertex), rigid, started bent
        /// and stretched: every vertex but the root pushed sideways and down by `push` a vertex.
        fn bent(n: usize, turn: f32, push: Vec3) -> Strand {
            let rest_points: Vec<Vec3> = (0..n)
                .map(|i| {
                    let a = i as f32 * turn;
                    Vec3::new(0.01 * a.sin(), -0.008 * i as f32, 0.01 * a.cos())
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
            let x = rest_points.iter().enumerate().map(|(i, p)| *p + push * i as f32).collect();
            let mut w = vec![1.0e6f32; n];
            w[0] = 0.0;
            let mut wq: Vec<f32> = (0..n).map(|i| 0.1 * 1.0e6 / (length[i] * length[i]).max(1e-12)).collect();
            wq[0] = 0.0;
            Strand {
                rest_points,
                x,
                q: frames,
                lambda: vec![Vec3::ZERO; n],
                w,
                wq,
                length,
                rest,
                pair_k: vec![BendTwistCoefficients::default(); n],
            }
        }

        fn state(&mut self) -> StrandState<'_> {
            StrandState {
                x: &mut self.x,
                q: &mut self.q,
                lambda: &mut self.lambda,
                w: &self.w,
                wq: &self.wq,
                length: &self.length,
                rest: &self.rest,
                pair_k: &self.pair_k,
            }
        }
    }

    /// With zero compliance a free strand has as many constraints as freedoms (three per vertex,
    /// three per frame), so Newton steps of the direct solve reach a state where every edge runs
    /// its rest length along its frame and every pair has its rest turn, from a start far from
    /// it.
    #[test]
    fn newton_steps_satisfy_every_constraint_of_a_strand() {
        let n = 12;
        let mut s = Strand::bent(n, 0.7, Vec3::new(0.003, -0.002, 0.0));
        let mut scratch = Scratch::default();
        let (length, rest) = (s.length.clone(), s.rest.clone());
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
        let before = residual(&s.x, &s.q);
        for _ in 0..6 {
            solve(&mut s.state(), 0, &mut scratch);
        }
        let after = residual(&s.x, &s.q);
        assert!(before > 0.1, "the start is far from rest: {before}");
        assert!(after < 1e-4, "relative residual after 6 Newton steps: {after} (from {before})");
        // The root stays put.
        assert_eq!(s.x[0], s.rest_points[0]);
    }

    /// Four different strands solved in lanes end with the bits each gets solved alone: compliant
    /// and rigid pairs, multipliers carried between Newton steps, a held frame in the middle, and
    /// free tails starting at the root and further out.
    #[test]
    fn lanes_give_each_strand_the_bits_of_its_own_solve() {
        let n = 9;
        let strands: Vec<Strand> = (0..4)
            .map(|k| {
                let k = k as f32;
                let mut s = Strand::bent(n, 0.4 + 0.3 * k, Vec3::new(0.002 * k, -0.003, 0.001 * (k - 1.5)));
                if k >= 2.0 {
                    for (i, c) in s.pair_k.iter_mut().enumerate() {
                        *c = BendTwistCoefficients::new(
                            1e4,
                            2e4,
                            Vec3::new(1e-6, 2e-6, 3e-6) * (1.0 + i as f32),
                        );
                    }
                }
                if k == 3.0 {
                    s.wq[4] = 0.0;
                }
                s
            })
            .collect();
        for start in [0, 1, 3] {
            let mut alone = strands.clone();
            let mut lanes = strands.clone();
            let mut scratch = Scratch::default();
            for _ in 0..3 {
                for s in alone.iter_mut() {
                    solve(&mut s.state(), start, &mut scratch);
                }
                let mut states = lanes.iter_mut().map(Strand::state);
                let mut states: [_; 4] = std::array::from_fn(|_| states.next().unwrap());
                solve_lanes(&mut states, start, &mut scratch);
            }
            for ((a, l), original) in alone.iter().zip(&lanes).zip(&strands) {
                let bits = |s: &Strand| {
                    let mut b: Vec<u32> = s.x.iter().flat_map(|v| v.to_array()).map(f32::to_bits).collect();
                    b.extend(s.q.iter().flat_map(|q| q.to_array()).map(f32::to_bits));
                    b.extend(s.lambda.iter().flat_map(|v| v.to_array()).map(f32::to_bits));
                    b
                };
                assert_ne!(a.x, original.x, "the solve moved the strand");
                assert_eq!(bits(a), bits(l), "free tail from edge {start}");
            }
        }
    }
}
