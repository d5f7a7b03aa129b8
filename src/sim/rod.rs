//! Rod state built from a [`Groom`]: struct-of-arrays, all strands in one array each, indexed like
//! the groom's points. Per-edge data (edge `i` runs from vertex `i` to `i + 1`) sits at the edge's
//! first vertex, per-edge-pair data (edges `i − 1`, `i`) at its centre vertex `i`; the unused slots
//! (tip for edges, root and tip for pairs) keep neutral values. One layout for everything keeps
//! per-strand slices trivially aligned.
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use super::constraints::{darboux_canonical, director3, E3};
use super::cuticle::Cuticle;
use crate::groom::Groom;

/// Physical material of hair. Moduli are SI; the rod radius comes from the groom's widths.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// kg/m³ (keratin ≈ 1300).
    pub density: f32,
    /// Young's modulus, Pa (hair ≈ 3.9 GPa): bending stiffness `E·π r⁴/4`.
    pub youngs_modulus: f32,
    /// Shear modulus, Pa: twisting stiffness `G·π r⁴/2`.
    pub shear_modulus: f32,
    /// Diameter used where the groom's width is zero, metres.
    pub fallback_width: f32,
    pub cuticle: Cuticle,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            density: 1300.0,
            youngs_modulus: 3.9e9,
            shear_modulus: 1.3e9,
            fallback_width: 70e-6,
            cuticle: Cuticle::default(),
        }
    }
}

/// The rods' state. Public fields are read freely; change state through the
/// [`Simulation`](super::Simulation) methods so kinematic flags and masses stay consistent.
#[derive(Clone, Debug)]
pub struct Rods {
    pub strand_offsets: Vec<u32>,
    // Per vertex.
    pub positions: Vec<Vec3>,
    pub velocities: Vec<Vec3>,
    /// Inverse mass the solver uses: 0 for kinematic vertices, else `1/(mass·mass_scale)`.
    pub inv_mass: Vec<f32>,
    /// Mass from the material and widths, kg.
    pub mass: Vec<f32>,
    /// Multiplier on `mass` (wet hair is heavier).
    pub mass_scale: Vec<f32>,
    /// Kinematic vertices follow `kinematic_targets` and are not moved by constraints.
    pub kinematic: Vec<bool>,
    pub kinematic_targets: Vec<Vec3>,
    /// Extra acceleration per vertex, m/s², added to gravity before prediction.
    pub external_acceleration: Vec<Vec3>,
    // Per edge.
    pub frames: Vec<Quat>,
    /// Inverse rotational inertia of the edge frame; 0 for a pinned (root) frame.
    pub frame_inv_inertia: Vec<f32>,
    pub rest_lengths: Vec<f32>,
    // Per edge pair.
    /// Rest Darboux vector `Ω0` the bend–twist constraint uses this step (S1-15).
    pub rest_darboux: Vec<Vec3>,
    /// Bend–twist compliance `α` per component (bend, bend, twist), 1/(N·m).
    pub compliance: Vec<Vec3>,
    // Solver state, kept here so a step allocates nothing.
    pub(crate) previous_positions: Vec<Vec3>,
    pub(crate) previous_frames: Vec<Quat>,
    /// Angular velocity of each edge frame (world, rad/s).
    pub(crate) angular_velocities: Vec<Vec3>,
    /// Bend–twist multipliers accumulated in the current step.
    pub(crate) lambdas: Vec<Vec3>,
}

/// Largest frame inverse-inertia factor the solver uses. Frames carry angular velocity; nearly
/// massless ones spin up from round-off and give the Newton step wild starting points, and the
/// direct solve needs no light frames for conditioning (the Gauss–Seidel solver did).
pub const FRAME_INERTIA_FACTOR_MAX: f32 = 1.0;

/// Frame whose third director is `t`, turned from `e3` by the shortest arc (deterministic).
pub fn frame_along(t: Vec3) -> Quat {
    Quat::from_rotation_arc(E3, t.normalize())
}

/// The arrays the strand solver works on, borrowed together.
pub(crate) struct SolverParts<'a> {
    pub offsets: &'a [u32],
    pub x: &'a mut [Vec3],
    pub v: &'a mut [Vec3],
    pub x_prev: &'a mut [Vec3],
    pub q: &'a mut [Quat],
    pub q_prev: &'a mut [Quat],
    pub omega: &'a mut [Vec3],
    pub rest: &'a mut [Vec3],
    pub lambda: &'a mut [Vec3],
    pub w: &'a [f32],
    pub wq: &'a [f32],
    pub kinematic: &'a [bool],
    pub targets: &'a [Vec3],
    pub external: &'a [Vec3],
    pub length: &'a [f32],
    pub compliance: &'a [Vec3],
}

impl Rods {
    /// Builds rods at rest in the groom's shape: frames parallel-transported from a root frame
    /// along the edges (so the imported shape has no twist), rest lengths and Darboux vectors
    /// taken from it. The groom must be valid (`Groom::validate`).
    pub fn from_groom(groom: &Groom, material: &Material, frame_inertia_factor: f32) -> Rods {
        let n = groom.vertex_count();
        let mut rods = Rods {
            strand_offsets: groom.strand_offsets.clone(),
            positions: groom.points.clone(),
            velocities: vec![Vec3::ZERO; n],
            inv_mass: vec![0.0; n],
            mass: vec![0.0; n],
            mass_scale: vec![1.0; n],
            kinematic: vec![false; n],
            kinematic_targets: groom.points.clone(),
            external_acceleration: vec![Vec3::ZERO; n],
            frames: vec![Quat::IDENTITY; n],
            frame_inv_inertia: vec![0.0; n],
            rest_lengths: vec![0.0; n],
            rest_darboux: vec![Vec3::ZERO; n],
            compliance: vec![Vec3::ZERO; n],
            previous_positions: groom.points.clone(),
            previous_frames: vec![Quat::IDENTITY; n],
            angular_velocities: vec![Vec3::ZERO; n],
            lambdas: vec![Vec3::ZERO; n],
        };
        let radius = |i: usize| {
            let w = groom.widths.get(i).copied().unwrap_or(0.0);
            0.5 * if w > 0.0 { w } else { material.fallback_width }
        };
        for strand in 0..groom.strand_count() {
            let range = groom.strand_range(strand);
            let (first, last) = (range.start, range.end - 1);
            let p = &groom.points;
            for i in first..last {
                rods.rest_lengths[i] = p[i].distance(p[i + 1]);
            }
            // Frames: root frame along the first edge, then parallel transport.
            let mut frame = frame_along(p[first + 1] - p[first]);
            rods.frames[first] = frame;
            for i in first + 1..last {
                let t0 = (p[i] - p[i - 1]).normalize();
                let t1 = (p[i + 1] - p[i]).normalize();
                frame = (Quat::from_rotation_arc(t0, t1) * frame).normalize();
                // Re-align exactly with the edge so round-off does not accumulate as shear.
                frame = (Quat::from_rotation_arc(director3(frame), t1) * frame).normalize();
                rods.frames[i] = frame;
                rods.rest_darboux[i] = darboux_canonical(rods.frames[i - 1], frame);
            }
            rods.frames[last] = rods.frames[last - 1];
            // Masses: each vertex carries half of each adjacent edge.
            let mut distance = 0.0;
            for i in first..=last {
                let left = if i > first { rods.rest_lengths[i - 1] } else { 0.0 };
                let right = if i < last { rods.rest_lengths[i] } else { 0.0 };
                let r = radius(i);
                rods.mass[i] = material.density * std::f32::consts::PI * r * r * 0.5 * (left + right);
                if i > first && i < last {
                    let mean_length = 0.5 * (left + right);
                    distance += left;
                    let factor = material.cuticle.stiffness_factor(distance);
                    let r4 = r * r * r * r;
                    let bend = factor * material.youngs_modulus * std::f32::consts::PI * r4 / 4.0;
                    let twist = factor * material.shear_modulus * std::f32::consts::PI * r4 / 2.0;
                    // Ω ≈ half the turning angle, so energy ½·EI·κ²·l̄ = ½·Ω²/α with α = l̄/(4·EI).
                    rods.compliance[i] = Vec3::new(
                        mean_length / (4.0 * bend),
                        mean_length / (4.0 * bend),
                        mean_length / (4.0 * twist),
                    );
                }
            }
            rods.kinematic[first] = true;
        }
        rods.update_inverse_masses(frame_inertia_factor);
        rods
    }

    /// Recomputes inverse masses from masses, scales and kinematic flags, and the frames' inverse
    /// inertia. The frame inertia is a conditioning choice, not physics: hair's true rotational
    /// inertia is so small that frames would swallow every stretch–shear correction and bending
    /// would reach the vertices only after many iterations. `wq = factor·w̄/l²` balances the two;
    /// the static shape does not depend on it.
    pub fn update_inverse_masses(&mut self, frame_inertia_factor: f32) {
        for i in 0..self.positions.len() {
            self.inv_mass[i] =
                if self.kinematic[i] { 0.0 } else { 1.0 / (self.mass[i] * self.mass_scale[i]).max(1e-30) };
        }
        for strand in 0..self.strand_count() {
            let range = self.strand_range(strand);
            let (first, last) = (range.start, range.end - 1);
            for i in first..last {
                let l = self.rest_lengths[i];
                let w = 2.0 / (self.mass[i] * self.mass_scale[i] + self.mass[i + 1] * self.mass_scale[i + 1]);
                let factor = frame_inertia_factor.min(FRAME_INERTIA_FACTOR_MAX);
                self.frame_inv_inertia[i] = if i == first { 0.0 } else { factor * w / (l * l) };
            }
        }
    }

    /// Every array the solver reads, split into the parts it writes and reads.
    pub(crate) fn solver_parts(&mut self) -> SolverParts<'_> {
        SolverParts {
            offsets: &self.strand_offsets,
            x: &mut self.positions,
            v: &mut self.velocities,
            x_prev: &mut self.previous_positions,
            q: &mut self.frames,
            q_prev: &mut self.previous_frames,
            omega: &mut self.angular_velocities,
            rest: &mut self.rest_darboux,
            lambda: &mut self.lambdas,
            w: &self.inv_mass,
            wq: &self.frame_inv_inertia,
            kinematic: &self.kinematic,
            targets: &self.kinematic_targets,
            external: &self.external_acceleration,
            length: &self.rest_lengths,
            compliance: &self.compliance,
        }
    }

    pub fn strand_count(&self) -> usize {
        self.strand_offsets.len().saturating_sub(1)
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn strand_range(&self, strand: usize) -> std::ops::Range<usize> {
        self.strand_offsets[strand] as usize..self.strand_offsets[strand + 1] as usize
    }

    /// Current Darboux vector of the edge pair centred on `vertex` (zero at roots and tips).
    pub fn darboux_at(&self, vertex: usize) -> Vec3 {
        if self.is_pair_centre(vertex) {
            darboux_canonical(self.frames[vertex - 1], self.frames[vertex])
        } else {
            Vec3::ZERO
        }
    }

    /// Whether `vertex` is the centre of an edge pair (neither a root nor a tip).
    pub fn is_pair_centre(&self, vertex: usize) -> bool {
        let strand = self.strand_of(vertex);
        let range = self.strand_range(strand);
        vertex > range.start && vertex + 1 < range.end
    }

    /// The strand a vertex belongs to.
    pub fn strand_of(&self, vertex: usize) -> usize {
        self.strand_offsets.partition_point(|&o| o as usize <= vertex) - 1
    }

    /// Length of a strand at rest.
    pub fn rest_length(&self, strand: usize) -> f32 {
        let range = self.strand_range(strand);
        self.rest_lengths[range.start..range.end - 1].iter().sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_follow_edges_without_twist() {
        // A helix: curvature and torsion, but parallel transport must give no material twist.
        let points: Vec<Vec3> = (0..40)
            .map(|i| {
                let t = i as f32 * 0.3;
                Vec3::new(0.01 * t.cos(), -0.004 * t, 0.01 * t.sin())
            })
            .collect();
        let groom = Groom::from_strands(std::slice::from_ref(&points), 80e-6);
        let rods = Rods::from_groom(&groom, &Material::default(), 1.0);
        for i in 0..points.len() - 1 {
            let t = (points[i + 1] - points[i]).normalize();
            assert!((director3(rods.frames[i]) - t).length() < 1e-5, "edge {i}");
            assert!((rods.rest_lengths[i] - points[i].distance(points[i + 1])).abs() < 1e-7);
        }
        for i in 1..points.len() - 1 {
            let omega = rods.rest_darboux[i];
            assert!(omega.z.abs() < 1e-5, "pair {i} has twist {}", omega.z);
            // |Ω| = sin(θ/2) for the turning angle θ between the edges.
            let t0 = (points[i] - points[i - 1]).normalize();
            let t1 = (points[i + 1] - points[i]).normalize();
            let half_angle = 0.5 * t0.dot(t1).clamp(-1.0, 1.0).acos();
            assert!((omega.length() - half_angle.sin()).abs() < 1e-5, "pair {i}");
        }
        assert!(rods.kinematic[0] && !rods.kinematic[1]);

        // Constant width: bending compliance grows towards the tip exactly as the cuticle factor
        // (S1-14) falls, and matches α = l̄/(4·E·π r⁴/4) at the first pair.
        let material = Material::default();
        let l = rods.rest_lengths[0];
        let r = 40e-6f32;
        let at_root = l
            / (4.0
                * material.cuticle.stiffness_factor(l)
                * material.youngs_modulus
                * 0.25
                * std::f32::consts::PI
                * r.powi(4));
        assert!((rods.compliance[1].x / at_root - 1.0).abs() < 1e-4);
        let last = points.len() - 2;
        let distance: f32 = rods.rest_lengths[..last].iter().sum();
        let ratio = rods.compliance[last].x / rods.compliance[1].x;
        let expected = material.cuticle.stiffness_factor(l) / material.cuticle.stiffness_factor(distance);
        assert!((ratio - expected).abs() < 1e-4, "tip/root compliance {ratio}, expected {expected}");
        assert_eq!(rods.frame_inv_inertia[0], 0.0);
    }
}
