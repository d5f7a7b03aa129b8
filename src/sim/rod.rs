//! Rod state built from a [`Groom`]: struct-of-arrays, all strands in one array each, indexed like
//! the groom's points. Per-edge data (edge `i` runs from vertex `i` to `i + 1`) sits at the edge's
//! first vertex, per-edge-pair data (edges `i − 1`, `i`) at its centre vertex `i`; the unused slots
//! (tip for edges, root and tip for pairs) keep neutral values. One layout for everything keeps
//! per-strand slices trivially aligned.
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use super::constraints::{
    darboux_canonical, director3, BendTwistCoefficients, StretchShearCoefficients, Sym3, E3,
};
use super::cuticle::Cuticle;
use super::lanes::LANES;
use crate::groom::{Groom, GroomError};

/// The widest strand simulated, metres: a rope-thick dreadlock is a few centimetres; a width
/// of metres (1e30 m read from a file went through every stage before) is a file in another
/// unit, or widths that mean something else, and would give rods of absurd mass and stiffness.
pub const MAX_WIDTH: f32 = 0.1;
/// The thinnest strand simulated, metres (a width of 0 takes [`Material::fallback_width`]): the
/// finest fibres are a few micrometres; below, bending stiffness (∝ r⁴) and mass (∝ r²) reach
/// f32's limits and the rods overflow within a step (0.08 µm widths of a millimetre groom read
/// as metres did).
pub const MIN_WIDTH: f32 = 1e-6;

/// The farthest from the origin a simulated vertex may be, metres (the range recipes place
/// obstacles in, [`crate::validate::COORDINATE`]): f32 positions a kilometre out are 60 µm apart,
/// coarser than a hair is wide, and a coordinate of 1e30 m read from a file made the rods
/// overflow to infinity within a step. Such a file is in another unit, or broken.
pub const MAX_COORDINATE: f32 = 1e3;

/// The longest strand simulated, metres: the longest human hair on record is 5.6 m, a horse's
/// tail a few metres. A strand of tens of metres is a file in another unit (a 24 cm groom read
/// at `--units 1000` was styled as 240 m strands, resampled to thousands of segments each).
pub const MAX_LENGTH: f32 = 10.0;

/// Refuses a groom the rods cannot represent: a strand wider than [`MAX_WIDTH`] or thinner than
/// [`MIN_WIDTH`] (but not 0), a vertex farther than [`MAX_COORDINATE`] from the origin on an
/// axis, or a strand longer than [`MAX_LENGTH`], naming the first. Styling checks the groom as it was read, so that the strand named is
/// the file's (not a resampled vertex or the index of a guide among guides).
pub fn check_simulable(groom: &Groom) -> Result<(), GroomError> {
    if let Some(i) = groom.widths.iter().position(|&w| w > MAX_WIDTH) {
        let (strand, vertex) = groom.strand_and_vertex(i);
        return Err(GroomError::TooWide { strand, vertex, width: groom.widths[i], max: MAX_WIDTH });
    }
    if let Some(i) = groom.widths.iter().position(|&w| w > 0.0 && w < MIN_WIDTH) {
        let (strand, vertex) = groom.strand_and_vertex(i);
        return Err(GroomError::TooThin { strand, vertex, width: groom.widths[i], min: MIN_WIDTH });
    }
    if let Some(i) = groom.points.iter().position(|p| p.abs().max_element() > MAX_COORDINATE) {
        let (strand, vertex) = groom.strand_and_vertex(i);
        let coordinate = groom.points[i].abs().max_element();
        return Err(GroomError::TooFar { strand, vertex, coordinate, max: MAX_COORDINATE });
    }
    for strand in 0..groom.strand_count() {
        let length: f32 = groom.strand_points(strand).windows(2).map(|s| s[0].distance(s[1])).sum();
        if length > MAX_LENGTH {
            return Err(GroomError::TooLong { strand, length, max: MAX_LENGTH });
        }
    }
    Ok(())
}

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

/// The rods' state. Every array has one entry per vertex and `strand_offsets` ascends from 0 to
/// that count with two or more vertices a strand: [`Rods::from_groom`] checks it once, and the
/// fields are private (read through the accessors, write through slices that cannot change length)
/// because the solver's unsafe per-strand slicing relies on it. Change state through the
/// [`Simulation`](super::Simulation) methods so kinematic flags and masses stay consistent.
#[derive(Clone, Debug)]
pub struct Rods {
    strand_offsets: Vec<u32>,
    // Per vertex.
    positions: Vec<Vec3>,
    velocities: Vec<Vec3>,
    /// Inverse mass the solver uses: 0 for kinematic vertices, else `1/(mass·mass_scale)`.
    inv_mass: Vec<f32>,
    /// Mass from the material and widths, kg.
    mass: Vec<f32>,
    /// Multiplier on `mass` (wet hair is heavier).
    mass_scale: Vec<f32>,
    /// Kinematic vertices follow `kinematic_targets` and are not moved by constraints.
    kinematic: Vec<bool>,
    kinematic_targets: Vec<Vec3>,
    /// Extra acceleration per vertex, m/s², added to gravity before prediction.
    external_acceleration: Vec<Vec3>,
    // Per edge.
    frames: Vec<Quat>,
    /// Inverse rotational inertia of the edge frame; 0 for a pinned (root) frame.
    frame_inv_inertia: Vec<f32>,
    rest_lengths: Vec<f32>,
    // Per edge pair.
    /// Rest Darboux vector `Ω0` the bend–twist constraint uses this step (S1-15).
    rest_darboux: Vec<Vec3>,
    /// Bend–twist compliance `α` per component (bend, bend, twist), 1/(N·m).
    compliance: Vec<Vec3>,
    // Scratch, kept here so a step allocates nothing.
    previous_positions: Vec<Vec3>,
    lambdas: Vec<Vec3>,
    /// Per edge, the inverse pivot block and the right-hand side / solution of the direct
    /// stretch–shear solve.
    solve_inverse: Vec<Sym3>,
    solve_values: Vec<Vec3>,
    edge_coefficients: Vec<StretchShearCoefficients>,
    pair_coefficients: Vec<BendTwistCoefficients>,
    /// Units of parallel work: `(first strand, strand count, solved in SIMD lanes)`.
    work_units: Vec<(usize, usize, bool)>,
}

/// The rod arrays of one step, borrowed from [`Rods::step_arrays`]; every slice has one entry
/// per vertex and `offsets`/`work_units` are the checked layout.
pub(super) struct StepArrays<'a> {
    pub offsets: &'a [u32],
    pub work_units: &'a [(usize, usize, bool)],
    pub positions: &'a mut [Vec3],
    pub velocities: &'a mut [Vec3],
    pub previous_positions: &'a mut [Vec3],
    pub frames: &'a mut [Quat],
    pub rest_darboux: &'a mut [Vec3],
    pub lambdas: &'a mut [Vec3],
    pub solve_inverse: &'a mut [Sym3],
    pub solve_values: &'a mut [Vec3],
    pub edge_coefficients: &'a [StretchShearCoefficients],
    pub pair_coefficients: &'a [BendTwistCoefficients],
    pub inv_mass: &'a [f32],
    pub kinematic: &'a [bool],
    pub kinematic_targets: &'a [Vec3],
    pub external_acceleration: &'a [Vec3],
    pub frame_inv_inertia: &'a [f32],
    pub rest_lengths: &'a [f32],
    pub compliance: &'a [Vec3],
}

/// Frame whose third director is `t`, turned from `e3` by the shortest arc (deterministic).
pub fn frame_along(t: Vec3) -> Quat {
    Quat::from_rotation_arc(E3, t.normalize())
}

/// The edge frames of one strand's `points` (one per vertex; the tip repeats the last edge's):
/// the root frame along the first edge, then parallel transport, so the shape has no twist.
/// These are the frames a groom read from a file gets, and what exported rest Darboux vectors
/// are measured in.
pub fn transport_frames(points: &[Vec3], frames: &mut [Quat]) {
    let last = points.len() - 1;
    let mut frame = frame_along(points[1] - points[0]);
    frames[0] = frame;
    for i in 1..last {
        let t0 = (points[i] - points[i - 1]).normalize();
        let t1 = (points[i + 1] - points[i]).normalize();
        frame = (Quat::from_rotation_arc(t0, t1) * frame).normalize();
        // Re-align exactly with the edge so round-off does not accumulate as shear.
        frame = (Quat::from_rotation_arc(director3(frame), t1) * frame).normalize();
        frames[i] = frame;
    }
    frames[last] = frames[last - 1];
}

/// Groups of `LANES` consecutive strands with equal vertex counts run in SIMD lanes, every other
/// strand alone. Depends only on the groom, so results do not depend on threads.
fn work_units(offsets: &[u32]) -> Vec<(usize, usize, bool)> {
    let strands = offsets.len().saturating_sub(1);
    let count = |s: usize| offsets[s + 1] - offsets[s];
    let mut units = Vec::new();
    let mut s = 0;
    while s < strands {
        if s + LANES <= strands && (s..s + LANES).all(|t| count(t) == count(s)) {
            units.push((s, LANES, true));
            s += LANES;
        } else {
            units.push((s, 1, false));
            s += 1;
        }
    }
    units
}

impl Rods {
    /// Builds rods at rest in the groom's shape: frames parallel-transported from a root frame
    /// along the edges (so the imported shape has no twist), rest lengths and Darboux vectors
    /// taken from it. The groom is validated here (offsets, two or more finite, distinct vertices
    /// a strand), so the layout the solver's unsafe slicing trusts holds from construction on.
    pub fn from_groom(
        groom: &Groom,
        material: &Material,
        frame_inertia_factor: f32,
    ) -> Result<Rods, GroomError> {
        groom.validate()?;
        check_simulable(groom)?;
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
            lambdas: vec![Vec3::ZERO; n],
            solve_inverse: vec![Sym3::default(); n],
            solve_values: vec![Vec3::ZERO; n],
            edge_coefficients: vec![StretchShearCoefficients::default(); n],
            pair_coefficients: vec![BendTwistCoefficients::default(); n],
            work_units: Vec::new(),
        };
        for strand in 0..groom.strand_count() {
            let range = groom.strand_range(strand);
            let (first, last) = (range.start, range.end - 1);
            let p = &groom.points;
            for i in first..last {
                rods.rest_lengths[i] = p[i].distance(p[i + 1]);
            }
            transport_frames(&p[range.clone()], &mut rods.frames[range.clone()]);
            for i in first + 1..last {
                rods.rest_darboux[i] = darboux_canonical(rods.frames[i - 1], rods.frames[i]);
            }
            rods.kinematic[first] = true;
        }
        rods.weigh(groom, material);
        rods.work_units = work_units(&groom.strand_offsets);
        rods.update_inverse_masses(frame_inertia_factor);
        rods.assert_layout();
        Ok(rods)
    }

    /// Takes `lengths` (per vertex: the edge it starts; a tip's is unused) as the rest lengths,
    /// with the masses, compliance and frame inertia that follow from them. `groom` is the groom
    /// the rods were built from (its widths).
    pub fn adopt_rest_lengths(
        &mut self,
        groom: &Groom,
        material: &Material,
        lengths: &[f32],
        frame_inertia_factor: f32,
    ) {
        self.rest_lengths.copy_from_slice(lengths);
        self.weigh(groom, material);
        self.update_inverse_masses(frame_inertia_factor);
    }

    /// Masses and bend–twist compliance from the rest lengths, the groom's widths and `material`.
    fn weigh(&mut self, groom: &Groom, material: &Material) {
        let radius = |i: usize| {
            let w = groom.widths.get(i).copied().unwrap_or(0.0);
            0.5 * if w > 0.0 { w } else { material.fallback_width }
        };
        for strand in 0..self.strand_count() {
            let range = self.strand_range(strand);
            let (first, last) = (range.start, range.end - 1);
            // Masses: each vertex carries half of each adjacent edge.
            let mut distance = 0.0;
            for i in first..=last {
                let left = if i > first { self.rest_lengths[i - 1] } else { 0.0 };
                let right = if i < last { self.rest_lengths[i] } else { 0.0 };
                let r = radius(i);
                self.mass[i] = material.density * std::f32::consts::PI * r * r * 0.5 * (left + right);
                if i > first && i < last {
                    let mean_length = 0.5 * (left + right);
                    distance += left;
                    let factor = material.cuticle.stiffness_factor(distance);
                    let r4 = r * r * r * r;
                    let bend = factor * material.youngs_modulus * std::f32::consts::PI * r4 / 4.0;
                    let twist = factor * material.shear_modulus * std::f32::consts::PI * r4 / 2.0;
                    // Ω ≈ half the turning angle, so energy ½·EI·κ²·l̄ = ½·Ω²/α with α = l̄/(4·EI).
                    self.compliance[i] = Vec3::new(
                        mean_length / (4.0 * bend),
                        mean_length / (4.0 * bend),
                        mean_length / (4.0 * twist),
                    );
                }
            }
        }
    }

    /// The layout every unsafe per-strand slice relies on. `Groom::validate` already implies it;
    /// asserting it once here keeps that reliance local to this module, where the arrays are
    /// built and never resized.
    fn assert_layout(&self) {
        let n = self.positions.len();
        let offsets = &self.strand_offsets;
        assert!(
            offsets.first() == Some(&0)
                && offsets.last().map(|&o| o as usize) == Some(n)
                && offsets.windows(2).all(|w| w[1] >= w[0].saturating_add(2)),
            "rod strand offsets must ascend from 0 to the vertex count, two or more vertices a strand"
        );
        let lengths = [
            self.velocities.len(),
            self.inv_mass.len(),
            self.mass.len(),
            self.mass_scale.len(),
            self.kinematic.len(),
            self.kinematic_targets.len(),
            self.external_acceleration.len(),
            self.frames.len(),
            self.frame_inv_inertia.len(),
            self.rest_lengths.len(),
            self.rest_darboux.len(),
            self.compliance.len(),
            self.previous_positions.len(),
            self.lambdas.len(),
            self.solve_inverse.len(),
            self.solve_values.len(),
            self.edge_coefficients.len(),
            self.pair_coefficients.len(),
        ];
        assert!(lengths.iter().all(|&len| len == n), "every rod array must have one entry per vertex");
        let mut next = 0;
        for &(first, count, _) in &self.work_units {
            assert!(first == next && count > 0, "work units must cover the strands in order, once each");
            next = first + count;
        }
        assert!(next == self.strand_count(), "work units must cover every strand");
    }

    /// The arrays one step reads and writes, split so the solver can cut disjoint per-strand views.
    /// Slices cannot change length, so the layout checked at construction still holds.
    pub(super) fn step_arrays(&mut self) -> StepArrays<'_> {
        StepArrays {
            offsets: &self.strand_offsets,
            work_units: &self.work_units,
            positions: &mut self.positions,
            velocities: &mut self.velocities,
            previous_positions: &mut self.previous_positions,
            frames: &mut self.frames,
            rest_darboux: &mut self.rest_darboux,
            lambdas: &mut self.lambdas,
            solve_inverse: &mut self.solve_inverse,
            solve_values: &mut self.solve_values,
            edge_coefficients: &self.edge_coefficients,
            pair_coefficients: &self.pair_coefficients,
            inv_mass: &self.inv_mass,
            kinematic: &self.kinematic,
            kinematic_targets: &self.kinematic_targets,
            external_acceleration: &self.external_acceleration,
            frame_inv_inertia: &self.frame_inv_inertia,
            rest_lengths: &self.rest_lengths,
            compliance: &self.compliance,
        }
    }

    /// First vertex of each strand, then the vertex count.
    pub fn strand_offsets(&self) -> &[u32] {
        &self.strand_offsets
    }

    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    pub fn velocities(&self) -> &[Vec3] {
        &self.velocities
    }

    pub(super) fn positions_mut(&mut self) -> &mut [Vec3] {
        &mut self.positions
    }

    pub(super) fn velocities_mut(&mut self) -> &mut [Vec3] {
        &mut self.velocities
    }

    /// Inverse mass the solver uses: 0 for kinematic vertices, else `1/(mass·mass_scale)`.
    pub fn inv_mass(&self) -> &[f32] {
        &self.inv_mass
    }

    /// Mass from the material and widths, kg.
    pub fn mass(&self) -> &[f32] {
        &self.mass
    }

    /// Multiplier on `mass` (wet hair is heavier).
    pub fn mass_scale(&self) -> &[f32] {
        &self.mass_scale
    }

    pub(super) fn mass_scale_mut(&mut self) -> &mut [f32] {
        &mut self.mass_scale
    }

    /// Units of the solver's work, `(first strand, strand count, solved in SIMD lanes)`: the
    /// strands of a unit are stepped together.
    pub(super) fn work_units(&self) -> &[(usize, usize, bool)] {
        &self.work_units
    }

    /// Kinematic vertices follow their targets and are not moved by constraints.
    pub fn kinematic(&self) -> &[bool] {
        &self.kinematic
    }

    pub(super) fn kinematic_mut(&mut self) -> &mut [bool] {
        &mut self.kinematic
    }

    pub fn kinematic_targets(&self) -> &[Vec3] {
        &self.kinematic_targets
    }

    pub(super) fn kinematic_targets_mut(&mut self) -> &mut [Vec3] {
        &mut self.kinematic_targets
    }

    /// Extra acceleration per vertex, m/s², added to gravity before prediction.
    pub fn external_acceleration(&self) -> &[Vec3] {
        &self.external_acceleration
    }

    pub(super) fn external_acceleration_mut(&mut self) -> &mut [Vec3] {
        &mut self.external_acceleration
    }

    /// Edge frames, stored at each edge's first vertex.
    pub fn frames(&self) -> &[Quat] {
        &self.frames
    }

    pub(super) fn frames_mut(&mut self) -> &mut [Quat] {
        &mut self.frames
    }

    /// Inverse rotational inertia of the edge frame; 0 for a pinned (root) frame.
    pub fn frame_inv_inertia(&self) -> &[f32] {
        &self.frame_inv_inertia
    }

    /// Edge rest lengths, stored at each edge's first vertex (0 at tips).
    pub fn rest_lengths(&self) -> &[f32] {
        &self.rest_lengths
    }

    /// Rest Darboux vector `Ω0` the bend–twist constraint used in the last step (S1-15).
    pub fn rest_darboux(&self) -> &[Vec3] {
        &self.rest_darboux
    }

    /// Bend–twist compliance `α` per component (bend, bend, twist), 1/(N·m).
    pub fn compliance(&self) -> &[Vec3] {
        &self.compliance
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
                self.frame_inv_inertia[i] = if i == first { 0.0 } else { frame_inertia_factor * w / (l * l) };
            }
        }
    }

    /// Recomputes the constraint projections' constants (they depend on masses, frame inertia,
    /// compliance and Δt, none of which changes inside a step).
    pub(crate) fn update_coefficients(&mut self, dt: f32) {
        let inv_dt2 = 1.0 / (dt * dt);
        for strand in 0..self.strand_count() {
            let range = self.strand_range(strand);
            let (first, last) = (range.start, range.end - 1);
            // Stiff pairs (small α/Δt², fine segments) would leave light frames that swallow the
            // shear corrections and pass bending to the vertices only after very many iterations:
            // cap each frame's inverse inertia at the bending compliance α/Δt² of its pairs.
            for e in first + 1..last {
                let mut sum = 0.0;
                let mut count = 0.0;
                for pair in [e, e + 1] {
                    if pair > first && pair < last {
                        sum += self.compliance[pair].x;
                        count += 1.0;
                    }
                }
                if count > 0.0 {
                    let cap = sum / count * inv_dt2;
                    self.frame_inv_inertia[e] = self.frame_inv_inertia[e].min(cap);
                }
            }
            for e in first..last {
                let (w1, w2, wq, l) =
                    (self.inv_mass[e], self.inv_mass[e + 1], self.frame_inv_inertia[e], self.rest_lengths[e]);
                self.edge_coefficients[e] = StretchShearCoefficients::new(w1, w2, wq, l, 2.0);
            }
            for i in first + 1..last {
                let (wq1, wq2) = (self.frame_inv_inertia[i - 1], self.frame_inv_inertia[i]);
                self.pair_coefficients[i] =
                    BendTwistCoefficients::new(wq1, wq2, self.compliance[i] * inv_dt2);
            }
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

    /// Every edge pair's centre vertex (each strand's vertices but its root and tip), in order,
    /// without looking up any vertex's strand.
    pub fn pair_centres(&self) -> impl Iterator<Item = usize> + '_ {
        self.strand_offsets.windows(2).flat_map(|w| w[0] as usize + 1..(w[1] as usize).saturating_sub(1))
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
    fn pair_centres_are_the_vertices_that_are_pair_centres() {
        let strand =
            |n: usize, x: f32| (0..n).map(|i| Vec3::new(x, 0.0, 0.01 * i as f32)).collect::<Vec<_>>();
        let groom = Groom::from_strands(&[strand(2, 0.0), strand(5, 0.1), strand(3, 0.2)], 80e-6);
        let rods = Rods::from_groom(&groom, &Material::default(), 1.0).unwrap();
        let expected: Vec<usize> = (0..rods.vertex_count()).filter(|&v| rods.is_pair_centre(v)).collect();
        assert_eq!(rods.pair_centres().collect::<Vec<_>>(), expected);
        assert_eq!(expected, vec![3, 4, 5, 8]);
    }

    #[test]
    fn rods_refuse_a_layout_the_solver_could_not_slice() {
        let points = vec![Vec3::ZERO, Vec3::X * 0.01, Vec3::X * 0.02];
        let good = Groom::from_strands(std::slice::from_ref(&points), 80e-6);
        // Offsets past the points, out of order, or a one-vertex strand: an error, never rods.
        for offsets in [vec![0, 4], vec![0, 2, 1, 3], vec![0, 1, 3], vec![1, 3]] {
            let mut groom = good.clone();
            groom.strand_offsets = offsets.clone();
            assert!(Rods::from_groom(&groom, &Material::default(), 1.0).is_err(), "{offsets:?}");
        }
        let rods = Rods::from_groom(&good, &Material::default(), 1.0).unwrap();
        assert_eq!((rods.strand_offsets(), rods.positions().len()), (&[0u32, 3][..], 3));
    }

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
        let rods = Rods::from_groom(&groom, &Material::default(), 1.0).unwrap();
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
