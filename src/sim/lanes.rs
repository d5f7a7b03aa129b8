//! The same step as the scalar strand solver, for `LANES` strands with equal vertex counts at
//! once: one strand per lane of plain `[f32; LANES]` arrays, which the compiler turns into SIMD
//! registers. Every lane does exactly the operations the scalar path does, in the same order of
//! constraints; whether a strand runs here or in the scalar path depends only on the groom
//! (strand index and vertex counts), never on threads, so results stay deterministic.
use std::array::from_fn;
use std::ops::{Add, Div, Mul, Neg, Sub};

use glam::{Quat, Vec3};

use super::constraints::{far_scalar_correction, BendTwistCoefficients, StretchShearCoefficients};
use super::solver::{sweep_order, Projection};
use super::Hooks;

pub const LANES: usize = 8;

/// One float per lane.
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(32))]
pub struct F(pub [f32; LANES]);

/// A binary operator (its trait in scope) on a lane type `$lanes(pub [_; N])`, lane by lane
/// (`lane_algebra` uses it for its f64 lanes too).
macro_rules! lanewise {
    ($lanes:ident, $trait:ident, $method:ident, $op:tt) => {
        impl $trait for $lanes {
            type Output = $lanes;
            #[inline(always)]
            fn $method(self, rhs: $lanes) -> $lanes {
                $lanes(std::array::from_fn(|l| self.0[l] $op rhs.0[l]))
            }
        }
    };
}
pub(super) use lanewise;
lanewise!(F, Add, add, +);
lanewise!(F, Sub, sub, -);
lanewise!(F, Mul, mul, *);
lanewise!(F, Div, div, /);

impl Neg for F {
    type Output = F;
    #[inline(always)]
    fn neg(self) -> F {
        F(from_fn(|l| -self.0[l]))
    }
}

impl F {
    #[inline(always)]
    pub fn splat(v: f32) -> F {
        F([v; LANES])
    }
    #[inline(always)]
    fn sqrt(self) -> F {
        F(from_fn(|l| self.0[l].sqrt()))
    }
    #[inline(always)]
    fn recip(self) -> F {
        F(from_fn(|l| 1.0 / self.0[l]))
    }
    /// Per lane: `self > 0 ? a : b`.
    #[inline(always)]
    fn positive_select(self, a: F, b: F) -> F {
        F(from_fn(|l| if self.0[l] > 0.0 { a.0[l] } else { b.0[l] }))
    }
}

/// A vector per lane.
#[derive(Clone, Copy, Debug, Default)]
pub struct V3 {
    x: F,
    y: F,
    z: F,
}

impl V3 {
    #[inline(always)]
    fn dot(self, o: V3) -> F {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    #[inline(always)]
    fn scale(self, s: F) -> V3 {
        V3 { x: self.x * s, y: self.y * s, z: self.z * s }
    }
    #[inline(always)]
    fn mul(self, o: V3) -> V3 {
        V3 { x: self.x * o.x, y: self.y * o.y, z: self.z * o.z }
    }
    #[inline(always)]
    fn select(mask: F, a: V3, b: V3) -> V3 {
        V3 {
            x: mask.positive_select(a.x, b.x),
            y: mask.positive_select(a.y, b.y),
            z: mask.positive_select(a.z, b.z),
        }
    }
    fn get(&self, l: usize) -> Vec3 {
        Vec3::new(self.x.0[l], self.y.0[l], self.z.0[l])
    }
    fn set(&mut self, l: usize, v: Vec3) {
        (self.x.0[l], self.y.0[l], self.z.0[l]) = (v.x, v.y, v.z);
    }
}

impl Add for V3 {
    type Output = V3;
    #[inline(always)]
    fn add(self, o: V3) -> V3 {
        V3 { x: self.x + o.x, y: self.y + o.y, z: self.z + o.z }
    }
}

impl Sub for V3 {
    type Output = V3;
    #[inline(always)]
    fn sub(self, o: V3) -> V3 {
        V3 { x: self.x - o.x, y: self.y - o.y, z: self.z - o.z }
    }
}

/// A quaternion per lane.
#[derive(Clone, Copy, Debug, Default)]
pub struct Q {
    x: F,
    y: F,
    z: F,
    w: F,
}

impl Q {
    /// Hamilton product `self ⊗ o`.
    #[inline(always)]
    fn mul(self, o: Q) -> Q {
        Q {
            w: self.w * o.w - self.x * o.x - self.y * o.y - self.z * o.z,
            x: self.w * o.x + self.x * o.w + self.y * o.z - self.z * o.y,
            y: self.w * o.y - self.x * o.z + self.y * o.w + self.z * o.x,
            z: self.w * o.z + self.x * o.y - self.y * o.x + self.z * o.w,
        }
    }
    #[inline(always)]
    fn pure(v: V3) -> Q {
        Q { x: v.x, y: v.y, z: v.z, w: F::splat(0.0) }
    }
    #[inline(always)]
    fn conjugate(self) -> Q {
        Q { x: -self.x, y: -self.y, z: -self.z, w: self.w }
    }
    #[inline(always)]
    fn add_scaled(self, o: Q, s: F) -> Q {
        Q { x: self.x + o.x * s, y: self.y + o.y * s, z: self.z + o.z * s, w: self.w + o.w * s }
    }
    #[inline(always)]
    fn normalize(self) -> Q {
        let inv = (self.x * self.x + self.y * self.y + self.z * self.z + self.w * self.w).sqrt().recip();
        Q { x: self.x * inv, y: self.y * inv, z: self.z * inv, w: self.w * inv }
    }
    #[inline(always)]
    fn vector(self) -> V3 {
        V3 { x: self.x, y: self.y, z: self.z }
    }
    #[inline(always)]
    fn select(mask: F, a: Q, b: Q) -> Q {
        Q {
            x: mask.positive_select(a.x, b.x),
            y: mask.positive_select(a.y, b.y),
            z: mask.positive_select(a.z, b.z),
            w: mask.positive_select(a.w, b.w),
        }
    }
    /// Third director `R(q)e`.
    #[inline(always)]
    fn director3(self) -> V3 {
        let two = F::splat(2.0);
        V3 {
            x: two * (self.x * self.z + self.w * self.y),
            y: two * (self.y * self.z - self.w * self.x),
            z: F::splat(1.0) - two * (self.x * self.x + self.y * self.y),
        }
    }
    /// `self ⊗ ē`, `ē = (0,0,−1; 0)`.
    #[inline(always)]
    fn times_e_bar(self) -> Q {
        Q { x: -self.y, y: self.x, z: -self.w, w: self.z }
    }
    fn get(&self, l: usize) -> Quat {
        Quat::from_xyzw(self.x.0[l], self.y.0[l], self.z.0[l], self.w.0[l])
    }
    fn set(&mut self, l: usize, q: Quat) {
        (self.x.0[l], self.y.0[l], self.z.0[l], self.w.0[l]) = (q.x, q.y, q.z, q.w);
    }
}

/// A symmetric 3×3 matrix per lane, with the formulas of the scalar `Sym3`.
#[derive(Clone, Copy, Debug, Default)]
struct S3 {
    xx: F,
    xy: F,
    xz: F,
    yy: F,
    yz: F,
    zz: F,
}

impl S3 {
    #[inline(always)]
    fn identity_minus_outer(diagonal: F, s: F, d: V3) -> S3 {
        S3 {
            xx: diagonal - s * d.x * d.x,
            xy: -(s * d.x * d.y),
            xz: -(s * d.x * d.z),
            yy: diagonal - s * d.y * d.y,
            yz: -(s * d.y * d.z),
            zz: diagonal - s * d.z * d.z,
        }
    }
    #[inline(always)]
    fn minus_scaled(self, o: S3, s: F) -> S3 {
        S3 {
            xx: self.xx - s * o.xx,
            xy: self.xy - s * o.xy,
            xz: self.xz - s * o.xz,
            yy: self.yy - s * o.yy,
            yz: self.yz - s * o.yz,
            zz: self.zz - s * o.zz,
        }
    }
    #[inline(always)]
    fn inverse(self) -> S3 {
        let S3 { xx: a, xy: b, xz: c, yy: d, yz: e, zz: f } = self;
        let (ca, cb, cc) = (d * f - e * e, c * e - b * f, b * e - c * d);
        let inv_det = (a * ca + b * cb + c * cc).recip();
        S3 {
            xx: ca * inv_det,
            xy: cb * inv_det,
            xz: cc * inv_det,
            yy: (a * f - c * c) * inv_det,
            yz: (b * c - a * e) * inv_det,
            zz: (a * d - b * b) * inv_det,
        }
    }
    #[inline(always)]
    fn times(self, v: V3) -> V3 {
        V3 {
            x: self.xx * v.x + self.xy * v.y + self.xz * v.z,
            y: self.xy * v.x + self.yy * v.y + self.yz * v.z,
            z: self.xz * v.x + self.yz * v.y + self.zz * v.z,
        }
    }
    #[inline(always)]
    fn select(mask: F, a: S3, b: S3) -> S3 {
        S3 {
            xx: mask.positive_select(a.xx, b.xx),
            xy: mask.positive_select(a.xy, b.xy),
            xz: mask.positive_select(a.xz, b.xz),
            yy: mask.positive_select(a.yy, b.yy),
            yz: mask.positive_select(a.yz, b.yz),
            zz: mask.positive_select(a.zz, b.zz),
        }
    }
}

#[derive(Clone, Copy, Debug, Default)]
struct EdgeK {
    inv_length: F,
    length: F,
    shear1: F,
    shear2: F,
    stretch1: F,
    stretch2: F,
    frame: F,
}

#[derive(Clone, Copy, Debug, Default)]
struct PairK {
    compliance_dt2: V3,
    inv_denominator: V3,
    /// `wq1 + wq2`: the pair is skipped where it is 0.
    wsum: F,
}

/// Per-thread working set of one lane group, reused from step to step.
#[derive(Default)]
pub struct Scratch {
    x: Vec<V3>,
    x_prev: Vec<V3>,
    v: Vec<V3>,
    target: Vec<V3>,
    kinematic: Vec<F>,
    w: Vec<F>,
    wq: Vec<F>,
    q: Vec<Q>,
    rest: Vec<V3>,
    lambda: Vec<V3>,
    inverse: Vec<S3>,
    values: Vec<V3>,
    /// Per edge, the stretch the direct stretch–shear solve asks of it (`solver::HeldSpans`).
    stretch: Vec<F>,
    edge_k: Vec<EdgeK>,
    pair_k: Vec<PairK>,
    /// One lane's positions, handed to the obstacle hook.
    lane_x: Vec<Vec3>,
}

/// What the lane solver reads from and writes back to one strand (all slices of equal length).
pub struct LaneStrand<'a> {
    pub x: &'a mut [Vec3],
    pub v: &'a mut [Vec3],
    pub q: &'a mut [Quat],
    pub w: &'a [f32],
    pub wq: &'a [f32],
    pub kinematic: &'a [bool],
    pub targets: &'a [Vec3],
    pub rest: &'a [Vec3],
    pub length: &'a [f32],
    pub edge_k: &'a [StretchShearCoefficients],
    pub pair_k: &'a [BendTwistCoefficients],
    /// The strand's index and first vertex, for the hook.
    pub strand: usize,
    pub first_vertex: usize,
}

fn resize<T: Default + Clone>(v: &mut Vec<T>, n: usize) {
    v.clear();
    v.resize(n, T::default());
}

/// The step's time, iteration count and velocity factor.
#[derive(Clone, Copy, Debug)]
pub struct StepSettings {
    pub dt: f32,
    pub iterations: u32,
    /// Velocity kept per step (damping).
    pub keep: f32,
}

/// Prediction, iterations and velocity update for `LANES` strands of `n` vertices whose
/// velocities already include this step's forces (see the scalar `begin_step`).
///
/// On x86-64 CPUs with AVX the same code is compiled a second time with 256-bit registers. AVX
/// without FMA rounds every lane operation exactly as SSE2 does, so both give identical bits.
pub fn finish_step(
    strands: &mut [LaneStrand<'_>; LANES],
    scratch: &mut Scratch,
    step: StepSettings,
    hooks: &dyn Hooks,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU supports AVX (checked just above).
        unsafe { finish_step_avx(strands, scratch, step, hooks) };
        return;
    }
    finish_step_impl(strands, scratch, step, hooks);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn finish_step_avx(
    strands: &mut [LaneStrand<'_>; LANES],
    scratch: &mut Scratch,
    step: StepSettings,
    hooks: &dyn Hooks,
) {
    finish_step_impl(strands, scratch, step, hooks);
}

#[inline(always)]
fn finish_step_impl(
    strands: &mut [LaneStrand<'_>; LANES],
    scratch: &mut Scratch,
    StepSettings { dt, iterations, keep }: StepSettings,
    hooks: &dyn Hooks,
) {
    let n = strands[0].x.len();
    let edges = n - 1;
    let s = scratch;
    for v in [&mut s.x, &mut s.x_prev, &mut s.v, &mut s.target, &mut s.rest, &mut s.lambda, &mut s.values] {
        resize(v, n);
    }
    resize(&mut s.inverse, n);
    for v in [&mut s.kinematic, &mut s.w, &mut s.wq] {
        resize(v, n);
    }
    resize(&mut s.q, n);
    resize(&mut s.edge_k, n);
    resize(&mut s.pair_k, n);

    // Gather.
    for (l, st) in strands.iter().enumerate() {
        for i in 0..n {
            s.x[i].set(l, st.x[i]);
            s.v[i].set(l, st.v[i]);
            s.target[i].set(l, st.targets[i]);
            s.kinematic[i].0[l] = if st.kinematic[i] { 1.0 } else { 0.0 };
            s.w[i].0[l] = st.w[i];
            s.wq[i].0[l] = st.wq[i];
            s.q[i].set(l, st.q[i]);
            s.rest[i].set(l, st.rest[i]);
            let ek = &st.edge_k[i];
            let k = &mut s.edge_k[i];
            k.inv_length.0[l] = ek.inv_length;
            k.length.0[l] = st.length[i];
            k.shear1.0[l] = ek.shear1;
            k.shear2.0[l] = ek.shear2;
            k.stretch1.0[l] = ek.stretch1;
            k.stretch2.0[l] = ek.stretch2;
            k.frame.0[l] = ek.frame;
            let pk = &st.pair_k[i];
            let k = &mut s.pair_k[i];
            k.compliance_dt2.set(l, pk.compliance_dt2);
            k.inv_denominator.set(l, pk.inv_denominator);
            k.wsum.0[l] = if i > 0 && i < edges { st.wq[i - 1] + st.wq[i] } else { 0.0 };
        }
    }

    // Prediction.
    let dt_f = F::splat(dt);
    for i in 0..n {
        s.x_prev[i] = s.x[i];
        s.x[i] = V3::select(s.kinematic[i], s.target[i], s.x[i] + s.v[i].scale(dt_f));
        s.lambda[i] = V3::default();
    }
    // Kinematic vertices stay where the prediction put them for the whole step.
    resize(&mut s.stretch, n);
    for (l, st) in strands.iter().enumerate() {
        let x = &s.x;
        let clamp = super::solver::pinned_first_edge_end(
            st.kinematic[0],
            st.wq[0],
            x[0].get(l),
            st.length[0],
            s.q[0].get(l),
        );
        let mut spans = super::solver::HeldSpans::new(
            |v| st.kinematic[v],
            |v| x[v].get(l),
            |e| st.length[e],
            edges,
            clamp,
        );
        for e in 0..edges {
            s.stretch[e].0[l] = spans.stretch(e);
        }
    }
    for iteration in 0..iterations {
        solve_stretch_shear(s, edges);
        sweep_order(edges, iteration, |projection| match projection {
            Projection::Edge(e) => project_edge(s, e),
            Projection::Pair(e) => project_pair(s, e),
        });
        if hooks.projects() {
            project_lanes(strands, s, hooks);
        }
    }

    // Velocities, then scatter.
    let inv_dt = F::splat(keep / dt);
    for i in 0..n {
        s.v[i] = (s.x[i] - s.x_prev[i]).scale(inv_dt);
    }
    for (l, st) in strands.iter_mut().enumerate() {
        for i in 0..n {
            st.x[i] = s.x[i].get(l);
            st.v[i] = s.v[i].get(l);
        }
        for e in 0..edges {
            st.q[e] = s.q[e].get(l);
        }
    }
}

/// Obstacle contacts, one lane at a time through the scalar hook (the scalar path calls it at the
/// same point of the iteration).
#[inline(always)]
fn project_lanes(strands: &[LaneStrand<'_>; LANES], s: &mut Scratch, hooks: &dyn Hooks) {
    let n = s.x.len();
    s.lane_x.resize(n, Vec3::ZERO);
    let inside = hooks.exclusions().map(|exclusions| lanes_inside(s, exclusions));
    for (l, st) in strands.iter().enumerate() {
        if inside.is_some_and(|inside| inside.0[l] == 0.0) {
            // The hook would leave every vertex of this lane where it is.
            continue;
        }
        for i in 0..n {
            s.lane_x[i] = s.x[i].get(l);
        }
        hooks.project(st.strand, st.first_vertex, &mut s.lane_x, st.w);
        for i in 0..n {
            s.x[i].set(l, s.lane_x[i]);
        }
    }
}

/// Per lane: 1 where a free vertex lies in one of the `exclusions`, else 0.
#[inline(always)]
fn lanes_inside(s: &Scratch, exclusions: &[super::Exclusion]) -> F {
    let mut inside = F::splat(0.0);
    for e in exclusions {
        let splat = |v: Vec3| V3 { x: F::splat(v.x), y: F::splat(v.y), z: F::splat(v.z) };
        let (center, limit) = (splat(e.center), F::splat(e.limit));
        let m = [splat(e.to_unit.x_axis), splat(e.to_unit.y_axis), splat(e.to_unit.z_axis)];
        for (x, w) in s.x.iter().zip(&s.w) {
            let d = *x - center;
            let u = m[0].scale(d.x) + m[1].scale(d.y) + m[2].scale(d.z);
            let r2 = u.dot(u);
            // Kinematic vertices (w = 0) are never moved by the hook; NaN counts as inside.
            inside = F(from_fn(|l| {
                let clear = r2.0[l] > limit.0[l];
                if !clear && w.0[l] != 0.0 {
                    1.0
                } else {
                    inside.0[l]
                }
            }));
        }
    }
    inside
}

/// The scalar `solve_stretch_shear`, lane by lane.
#[inline(always)]
fn solve_stretch_shear(s: &mut Scratch, edges: usize) {
    let zero = F::splat(0.0);
    let one = F::splat(1.0);
    let w = &s.w;
    for e in 0..edges {
        let d = s.q[e].director3();
        let l = s.edge_k[e].length;
        let target = l * s.stretch[e];
        let vertices = w[e] + w[e + 1];
        let frame = F::splat(4.0) * s.wq[e] * l * l;
        let mut block = S3::identity_minus_outer((vertices + frame) * F::splat(1.0 + 1e-6), frame, d);
        let mut rhs = d.scale(target) - (s.x[e + 1] - s.x[e]);
        if e > 0 {
            block = block.minus_scaled(s.inverse[e - 1], w[e] * w[e]);
            rhs = rhs + s.values[e - 1].scale(w[e]);
        }
        let inv_frame = frame.positive_select(frame, one).recip();
        let frame_only = S3::select(frame, S3::identity_minus_outer(inv_frame, inv_frame, d), S3::default());
        // Lanes where the block is not invertible compute a discarded inverse.
        let safe = S3::select(vertices, block, S3::identity_minus_outer(one, zero, d));
        s.inverse[e] = S3::select(vertices, safe.inverse(), frame_only);
        s.values[e] = s.inverse[e].times(rhs);
    }
    for e in (0..edges.saturating_sub(1)).rev() {
        s.values[e] = s.values[e] + s.inverse[e].times(s.values[e + 1].scale(w[e + 1]));
    }
    for (j, &wj) in w.iter().enumerate().take(edges + 1) {
        let mut dp = V3::default();
        if j > 0 {
            dp = dp + s.values[j - 1];
        }
        if j < edges {
            dp = dp - s.values[j];
        }
        s.x[j] = s.x[j] + dp.scale(wj);
    }
    for e in 0..edges {
        let q = s.q[e];
        let d = q.director3();
        let mu = s.values[e];
        let across = mu - d.scale(mu.dot(d));
        let dq = Q::pure(across).mul(q.times_e_bar());
        let turned = q.add_scaled(dq, -(F::splat(2.0) * s.wq[e] * s.edge_k[e].length)).normalize();
        s.q[e] = Q::select(s.wq[e], turned, q);
    }
}

#[inline(always)]
fn project_edge(s: &mut Scratch, e: usize) {
    let k = s.edge_k[e];
    let (p1, p2, q) = (s.x[e], s.x[e + 1], s.q[e]);
    let d3 = q.director3();
    let gamma = (p2 - p1).scale(k.inv_length) - d3;
    let stretch = d3.scale(gamma.dot(d3));
    let shear = gamma - stretch;
    s.x[e] = p1 + shear.scale(k.shear1) + stretch.scale(k.stretch1);
    s.x[e + 1] = p2 - (shear.scale(k.shear2) + stretch.scale(k.stretch2));
    let dq = Q::pure(shear).mul(q.times_e_bar());
    s.q[e] = Q::select(k.frame, q.add_scaled(dq, k.frame).normalize(), q);
}

#[inline(always)]
fn project_pair(s: &mut Scratch, e: usize) {
    let k = s.pair_k[e];
    let (q1, q2) = (s.q[e - 1], s.q[e]);
    let relative = q1.conjugate().mul(q2);
    let omega = relative.vector();
    let rest = s.rest[e];
    // Double cover: compare the whole relative rotation (w, Ω) with ±(w0, Ω0). Comparing the
    // vector parts alone accepts (w > 0, −Ω0), the mirrored bend, as a second rest state.
    let slack = F::splat(1.0) - rest.dot(rest);
    let w0 = slack.positive_select(slack, F::splat(0.0)).sqrt();
    let alignment = relative.w * w0 + omega.dot(rest);
    let rest = V3::select(-alignment, V3::default() - rest, rest);
    let c = omega - rest;
    let lambda = s.lambda[e];
    let dl = (V3::default() - c - k.compliance_dt2.mul(lambda)).mul(k.inv_denominator);
    s.lambda[e] = lambda + dl;
    let w0 = (-alignment).positive_select(-w0, w0);
    let d = k.inv_denominator;
    let dw = F(from_fn(|l| {
        let stiffest = d.x.0[l].min(d.y.0[l].min(d.z.0[l]));
        far_scalar_correction(alignment.0[l], relative.w.0[l], w0.0[l], stiffest)
    }));
    let to_q1 = Q { x: dl.x, y: dl.y, z: dl.z, w: F::splat(0.0) - dw };
    let to_q2 = Q { x: dl.x, y: dl.y, z: dl.z, w: dw };
    let new_q1 = q1.add_scaled(q2.mul(to_q1), -s.wq[e - 1]).normalize();
    let new_q2 = q2.add_scaled(q1.mul(to_q2), s.wq[e]).normalize();
    s.q[e - 1] = Q::select(k.wsum, new_q1, q1);
    s.q[e] = Q::select(k.wsum, new_q2, q2);
}
