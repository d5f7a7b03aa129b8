//! The two Cosserat-rod constraints of model.md §1 (Kugelstadt & Schömer 2016), as projections on
//! plain values so they can be tested in isolation and inlined into the strand solver.
//!
//! **Stretch–shear** is projected with zero compliance (hair barely stretches). Its quaternion
//! correction carries the factor 2 of the gradient of `R(q)e` with respect to `q`:
//! perturbing `q` by `c·(0,γ)⊗q⊗ē` changes `R(q)e` by `2c·γ`, so the gradient norm squared is 4
//! (the `4·wq·l²` in the denominator) and the mass-weighted step along it is
//! `Δq = 2·wq·l²/(w1 + w2 + 4·wq·l²) · (0,γ)⊗q⊗ē`. With this factor one projection removes the
//! linearised error completely; the seed's `wq·l²` would leave `2·wq·l²/D` of it (see tests).
//! One refinement over the paper: a rotation moves `d3` only perpendicular to itself, so the
//! stretch part of `γ` (along `d3`) is corrected by the vertices alone, with denominator `w1 + w2`;
//! in the paper's form the frame absorbs part of it and normalisation throws that part away, so
//! stretch converges at only `(w1 + w2)/D` per iteration and hanging strands visibly lengthen.
//!
//! **Bend–twist** is projected in XPBD form with a per-component compliance (bend, bend, twist):
//! `Δλ = (−C − α̃λ)/(wq1 + wq2 + α̃)`, `α̃ = α/Δt²`, `Δq1 = −wq1·q2⊗(0,Δλ)`, `Δq2 = +wq2·q1⊗(0,Δλ)`.
//! To first order this changes `Ω = Im(q̄1⊗q2)` by exactly `(wq1 + wq2)·Δλ`, so with `α = 0` it is
//! the seed's S1-10/11 projection with `k = 1`.
use glam::{Quat, Vec3};

/// `e = (0,0,1)`: the material direction that should follow the edge.
pub const E3: Vec3 = Vec3::Z;

/// A pure quaternion `(0, v)`.
#[inline(always)]
pub fn pure(v: Vec3) -> Quat {
    Quat::from_xyzw(v.x, v.y, v.z, 0.0)
}

/// Third director `d3 = R(q)e` of a unit quaternion, without forming the whole matrix.
#[inline(always)]
pub fn director3(q: Quat) -> Vec3 {
    let (x, y, z, w) = (q.x, q.y, q.z, q.w);
    Vec3::new(2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y))
}

/// `q ⊗ ē` with `ē = (0,0,0,−1)` written out: the quaternion product with a fixed axis.
#[inline(always)]
pub(crate) fn times_e_bar(q: Quat) -> Quat {
    // q ⊗ (0,0,−1,0 as xyz) : Hamilton product with (x,y,z,w) = (0,0,−1,0).
    Quat::from_xyzw(-q.y, q.x, -q.w, q.z)
}

/// Darboux vector of an edge pair, `Ω = Im(q̄1 ⊗ q2)` (S1-8).
#[inline(always)]
pub fn darboux(q1: Quat, q2: Quat) -> Vec3 {
    let r = q1.conjugate() * q2;
    Vec3::new(r.x, r.y, r.z)
}

/// Per-step constants of one edge's stretch–shear projection (the masses do not change within a
/// step, so the divisions are done once per step instead of once per iteration).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StretchShearCoefficients {
    pub inv_length: f32,
    /// `w·l/D` for the shear part, per vertex.
    pub shear1: f32,
    pub shear2: f32,
    /// `w·l/(w1 + w2)` for the stretch part, per vertex.
    pub stretch1: f32,
    pub stretch2: f32,
    /// `factor·wq·l²/D` for the frame.
    pub frame: f32,
}

impl StretchShearCoefficients {
    /// `factor` is the numerator factor of `Δq`: 2 from the derivation (see the module docs).
    pub fn new(w1: f32, w2: f32, wq: f32, l: f32, factor: f32) -> Self {
        let denominator = w1 + w2 + 4.0 * wq * l * l;
        if denominator <= 0.0 {
            return StretchShearCoefficients { inv_length: 1.0 / l, ..Default::default() };
        }
        let vertex_share = w1 + w2;
        let stretch = if vertex_share > 0.0 { l / vertex_share } else { 0.0 };
        StretchShearCoefficients {
            inv_length: 1.0 / l,
            shear1: w1 * l / denominator,
            shear2: w2 * l / denominator,
            stretch1: w1 * stretch,
            stretch2: w2 * stretch,
            frame: factor * wq * l * l / denominator,
        }
    }
}

/// The Darboux vector of the shortest rotation from `q1` to `q2`: `Im(q̄1 ⊗ q2)` taken from the
/// representative with non-negative real part. Stored shapes (rest, bond memories) use this, so
/// that which of `±q` a frame happens to be does not flip the sign of what is remembered.
#[inline(always)]
pub fn darboux_canonical(q1: Quat, q2: Quat) -> Vec3 {
    let r = q1.conjugate() * q2;
    let v = Vec3::new(r.x, r.y, r.z);
    if r.w < 0.0 {
        -v
    } else {
        v
    }
}

/// The turn with non-negative real part whose Darboux vector is `omega` (the inverse of
/// [`darboux_canonical`]; lengths beyond 1 are clamped).
pub fn turn_of(omega: Vec3) -> Quat {
    let o = omega.clamp_length_max(1.0);
    Quat::from_xyzw(o.x, o.y, o.z, (1.0 - o.length_squared()).max(0.0).sqrt())
}

/// Projects the stretch–shear constraint of one edge. `w1`, `w2` are the vertices' inverse masses,
/// `wq` the edge frame's inverse inertia, `l` its rest length.
#[inline(always)]
pub fn project_stretch_shear(p1: &mut Vec3, p2: &mut Vec3, q: &mut Quat, w1: f32, w2: f32, wq: f32, l: f32) {
    project_stretch_shear_with(p1, p2, q, &StretchShearCoefficients::new(w1, w2, wq, l, 2.0));
}

/// The projection with precomputed coefficients.
#[inline(always)]
pub fn project_stretch_shear_with(p1: &mut Vec3, p2: &mut Vec3, q: &mut Quat, k: &StretchShearCoefficients) {
    let d3 = director3(*q);
    let gamma = (*p2 - *p1) * k.inv_length - d3;
    // Rotating q moves d3 only perpendicular to itself, so the stretch part of γ (along d3) can
    // only be fixed by the vertices: it gets its own denominator w1 + w2.
    let stretch = gamma.dot(d3) * d3;
    let shear = gamma - stretch;
    *p1 += k.shear1 * shear + k.stretch1 * stretch;
    *p2 -= k.shear2 * shear + k.stretch2 * stretch;
    if k.frame > 0.0 {
        let dq = pure(shear) * times_e_bar(*q);
        *q = (*q + dq * k.frame).normalize();
    }
}

/// A symmetric 3×3 matrix (the pivot blocks of the direct stretch–shear solve), as its six
/// distinct entries. The SIMD lanes use the same formulas, so both paths round alike.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Sym3 {
    pub xx: f32,
    pub xy: f32,
    pub xz: f32,
    pub yy: f32,
    pub yz: f32,
    pub zz: f32,
}

impl Sym3 {
    /// `diagonal·I − s·d·dᵀ`.
    #[inline(always)]
    pub fn identity_minus_outer(diagonal: f32, s: f32, d: Vec3) -> Sym3 {
        Sym3 {
            xx: diagonal - s * d.x * d.x,
            xy: -(s * d.x * d.y),
            xz: -(s * d.x * d.z),
            yy: diagonal - s * d.y * d.y,
            yz: -(s * d.y * d.z),
            zz: diagonal - s * d.z * d.z,
        }
    }

    /// `self − s·o`.
    #[inline(always)]
    pub fn minus_scaled(self, o: Sym3, s: f32) -> Sym3 {
        Sym3 {
            xx: self.xx - s * o.xx,
            xy: self.xy - s * o.xy,
            xz: self.xz - s * o.xz,
            yy: self.yy - s * o.yy,
            yz: self.yz - s * o.yz,
            zz: self.zz - s * o.zz,
        }
    }

    /// The inverse by cofactors (the caller keeps the matrix positive definite).
    #[inline(always)]
    pub fn inverse(self) -> Sym3 {
        let Sym3 { xx: a, xy: b, xz: c, yy: d, yz: e, zz: f } = self;
        let (ca, cb, cc) = (d * f - e * e, c * e - b * f, b * e - c * d);
        let inv_det = 1.0 / (a * ca + b * cb + c * cc);
        Sym3 {
            xx: ca * inv_det,
            xy: cb * inv_det,
            xz: cc * inv_det,
            yy: (a * f - c * c) * inv_det,
            yz: (b * c - a * e) * inv_det,
            zz: (a * d - b * b) * inv_det,
        }
    }

    #[inline(always)]
    pub fn times(self, v: Vec3) -> Vec3 {
        Vec3::new(
            self.xx * v.x + self.xy * v.y + self.xz * v.z,
            self.xy * v.x + self.yy * v.y + self.yz * v.z,
            self.xz * v.x + self.yz * v.y + self.zz * v.z,
        )
    }
}

/// Per-step constants of one edge pair's bend–twist projection: `α̃ = α/Δt²` per component and
/// `1/(wq1 + wq2 + α̃)`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BendTwistCoefficients {
    pub compliance_dt2: Vec3,
    pub inv_denominator: Vec3,
}

impl BendTwistCoefficients {
    pub fn new(wq1: f32, wq2: f32, compliance_dt2: Vec3) -> Self {
        let wsum = wq1 + wq2;
        if wsum <= 0.0 {
            return BendTwistCoefficients::default();
        }
        BendTwistCoefficients {
            compliance_dt2,
            inv_denominator: Vec3::ONE / (Vec3::splat(wsum) + compliance_dt2),
        }
    }
}

/// Bend–twist's constraint `Ω − Ω0` (vector parts) measures a joint's error in a way whose change
/// can turn the joint's axis but hardly shrink its angle once the joint is far from rest (at half
/// a turn, not at all), and there the side of the double cover flips between projections: a joint
/// folded or twisted that far stayed stuck, chattering. Below this alignment `|⟨r, r0⟩|` of the
/// relative rotation with the rest rotation (the cosine of half the angle between them: errors
/// beyond 90°) the correction also moves the scalar part of `r` towards `w0`, with a weight rising
/// from 0 at this alignment to 1 at half a turn: continuous, and nothing changes nearer rest.
pub const FAR_ALIGNMENT: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// The scalar part of the bend–twist correction of a joint with `alignment` (see
/// [`FAR_ALIGNMENT`]), relative scalar part `w` and rest `w0` on the chosen side of the cover;
/// `stiffest` is the smallest component of the joint's `1/(wq1 + wq2 + α̃)`.
#[inline(always)]
pub fn far_scalar_correction(alignment: f32, w: f32, w0: f32, stiffest: f32) -> f32 {
    let weight = far_weight(alignment);
    if weight > 0.0 {
        weight * (w0 - w) * stiffest
    } else {
        0.0
    }
}

/// How far past [`FAR_ALIGNMENT`] a joint's `alignment` with its rest is: 0 nearer rest, rising
/// linearly to 1 at half a turn. Both solvers' treatment of far joints fades in by it.
#[inline(always)]
pub fn far_weight(alignment: f32) -> f32 {
    ((FAR_ALIGNMENT - alignment.abs()) / FAR_ALIGNMENT).max(0.0)
}

/// Where the direct strand solve (`strand_solve`) aims a joint far from rest: the rotation on the
/// arc from the relative rotation `u` towards its rest rotation `rest` (unit quaternions, `rest`
/// on `u`'s side of the double cover, further apart than [`FAR_ALIGNMENT`]) at the alignment
/// [`FAR_ALIGNMENT`] from `u`, a 90° turn away. Its error is measured as the turn `t̄⊗u`, whose
/// scalar part is `FAR_ALIGNMENT`, so a Newton step can shrink every part of it, and the pull
/// towards rest keeps its strength at a 90° error however far the joint is.
#[inline(always)]
pub fn far_target(u: Quat, rest: Quat) -> Quat {
    // Spherical interpolation: `rest` is at the angle ψ from `u` (as 4-vectors), the target at π/4.
    let psi = u.dot(rest).clamp(0.0, FAR_ALIGNMENT).acos();
    let quarter = std::f32::consts::FRAC_PI_4;
    ((u * (psi - quarter).sin() + rest * quarter.sin()) * (1.0 / psi.sin())).normalize()
}

/// Projects the bend–twist constraint of one edge pair in XPBD form. `rest` is `Ω0`,
/// `compliance_dt2` is `α/Δt²` per component, `lambda` the multiplier accumulated this step.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn project_bend_twist(
    q1: &mut Quat,
    q2: &mut Quat,
    wq1: f32,
    wq2: f32,
    rest: Vec3,
    compliance_dt2: Vec3,
    lambda: &mut Vec3,
) {
    let k = BendTwistCoefficients::new(wq1, wq2, compliance_dt2);
    project_bend_twist_with(q1, q2, wq1, wq2, rest, &k, lambda);
}

/// The projection with precomputed coefficients.
#[inline(always)]
pub fn project_bend_twist_with(
    q1: &mut Quat,
    q2: &mut Quat,
    wq1: f32,
    wq2: f32,
    rest: Vec3,
    k: &BendTwistCoefficients,
    lambda: &mut Vec3,
) {
    if wq1 + wq2 <= 0.0 {
        return;
    }
    let relative = q1.conjugate() * *q2;
    let omega = Vec3::new(relative.x, relative.y, relative.z);
    // Quaternion double cover: compare the whole relative rotation (w, Ω) with ±(w0, Ω0).
    // Comparing vector parts alone (Ω·Ω0 < 0) accepts (w > 0, −Ω0) — the mirrored bend — as a
    // second rest state, and a released curl can settle into it joint by joint.
    let w0 = (1.0 - rest.length_squared()).max(0.0).sqrt();
    let alignment = relative.w * w0 + omega.dot(rest);
    let (rest, w0) = if alignment < 0.0 { (-rest, -w0) } else { (rest, w0) };
    let c = omega - rest;
    let dl = (-c - k.compliance_dt2 * *lambda) * k.inv_denominator;
    *lambda += dl;
    // `r` changes by the correction times each frame's inverse inertia: `q1` takes its conjugate.
    let dw = far_scalar_correction(alignment, relative.w, w0, k.inv_denominator.min_element());
    let new_q1 = *q1 - (*q2 * Quat::from_xyzw(dl.x, dl.y, dl.z, 0.0 - dw)) * wq1;
    let new_q2 = *q2 + (*q1 * Quat::from_xyzw(dl.x, dl.y, dl.z, dw)) * wq2;
    *q1 = new_q1.normalize();
    *q2 = new_q2.normalize();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn director_matches_rotation() {
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 0.7);
        assert!((director3(q) - q * E3).length() < 1e-6);
        assert!((times_e_bar(q) - q * Quat::from_xyzw(0.0, 0.0, -1.0, 0.0)).length() < 1e-6);
    }

    /// One projection of an isolated, slightly sheared edge (unit direction off the frame's d3;
    /// rotation can fix all of it) should remove the error up to second order with the derived
    /// factor 2, and leave a first-order remainder `2·wq·l²/D` with the seed's factor 1. This is
    /// the test that decides the factor in `Δq`.
    #[test]
    fn stretch_shear_factor_two_removes_shear_in_one_projection() {
        for (w1, w2, wq) in [(1.0, 1.0, 1.0), (0.0, 1.0, 10.0), (2.0, 0.5, 0.1), (1.0, 1.0, 1e4)] {
            let l = 0.01;
            let project = |factor: f32| {
                let mut p1 = Vec3::ZERO;
                let mut p2 = l * Vec3::new(0.02, -0.01, 1.0).normalize();
                let mut q = Quat::from_rotation_x(0.01);
                let before = ((p2 - p1) / l - director3(q)).length();
                let k = StretchShearCoefficients::new(w1, w2, wq, l, factor);
                project_stretch_shear_with(&mut p1, &mut p2, &mut q, &k);
                (before, ((p2 - p1) / l - director3(q)).length())
            };
            let (before, derived) = project(2.0);
            assert!(derived < 0.02 * before, "w=({w1},{w2},{wq}): error {before} -> {derived}");
            let (_, seed) = project(1.0);
            let d = w1 + w2 + 4.0 * wq * l * l;
            let expected_left = 2.0 * wq * l * l / d;
            assert!((seed / before - expected_left).abs() < 0.02, "seed factor leaves {seed}");
        }
    }

    /// A stretched and sheared edge is fixed by one projection too (stretch through the vertices).
    #[test]
    fn stretch_shear_error_falls_every_iteration() {
        let l = 0.01;
        let mut p1 = Vec3::ZERO;
        let mut p2 = Vec3::new(0.004, 0.002, 0.008);
        let mut q = Quat::IDENTITY;
        let mut last = f32::INFINITY;
        for _ in 0..6 {
            project_stretch_shear(&mut p1, &mut p2, &mut q, 1.0, 1.0, 1.0 / (l * l), l);
            let error = ((p2 - p1) / l - director3(q)).length();
            assert!(error < 0.2 * last || error < 1e-6, "error {error} did not fall well below {last}");
            last = error;
        }
        assert!(last < 1e-6, "final error {last}");
    }

    #[test]
    fn bend_twist_reaches_rest_with_zero_compliance() {
        let mut q1 = Quat::IDENTITY;
        let mut q2 = Quat::from_rotation_y(0.2);
        let rest = Vec3::new(0.05, 0.0, 0.01);
        let mut lambda = Vec3::ZERO;
        project_bend_twist(&mut q1, &mut q2, 1.0, 1.0, rest, Vec3::ZERO, &mut lambda);
        let after = darboux(q1, q2);
        assert!((after - rest).length() < 0.01 * (Vec3::new(0.0, (0.1f32).sin(), 0.0) - rest).length());
    }

    /// With compliance, XPBD lands on the same point whether one or many iterations are used: the
    /// stiffness of an isolated constraint does not depend on the iteration count.
    #[test]
    fn bend_twist_compliance_is_iteration_invariant() {
        let run = |iterations: usize| {
            let mut q1 = Quat::IDENTITY;
            let mut q2 = Quat::from_rotation_y(0.02);
            let mut lambda = Vec3::ZERO;
            for _ in 0..iterations {
                project_bend_twist(&mut q1, &mut q2, 0.0, 1.0, Vec3::ZERO, Vec3::splat(3.0), &mut lambda);
            }
            darboux(q1, q2)
        };
        let one = run(1);
        let many = run(20);
        assert!((one.y - 0.75 * (0.01f32).sin()).abs() < 1e-4, "{one}");
        assert!((one - many).length() < 1e-4 * one.length().max(1e-6), "{one} vs {many}");
    }

    /// A joint turned far from its rest rotation (a 40° bend at rest, twisted 90–185° more)
    /// loses most of its error in one stiff projection, on either side of half a turn. The
    /// vector-part update alone left 138° of 179° (its change turns the joint's axis, hardly its
    /// angle), 68° of 150°; within 90° of rest nothing changed (15° of 90° either way).
    #[test]
    fn a_joint_far_from_rest_comes_back() {
        let rest = Vec3::new((20f32).to_radians().sin(), 0.0, 0.0);
        let rest_turn = turn_of(rest);
        let k = BendTwistCoefficients::new(0.0, 1.0, Vec3::splat(0.05));
        let error = |q1: Quat, q2: Quat| {
            2.0 * (rest_turn.conjugate() * (q1.conjugate() * q2)).w.abs().min(1.0).acos().to_degrees()
        };
        for degrees in [90.0f32, 120.0, 150.0, 175.0, 179.0, 181.0, 185.0] {
            let q1 = Quat::from_rotation_y(0.3);
            let mut q2 = q1 * rest_turn * Quat::from_rotation_z(degrees.to_radians());
            let before = error(q1, q2);
            let (mut pinned, mut lambda) = (q1, Vec3::ZERO);
            project_bend_twist_with(&mut pinned, &mut q2, 0.0, 1.0, rest, &k, &mut lambda);
            assert_eq!(pinned, q1, "a pinned frame does not turn");
            let after = error(q1, q2);
            assert!(after < 0.25 * before, "{degrees}°: {before:.1}° from rest, {after:.1}° after");
        }
    }
}
