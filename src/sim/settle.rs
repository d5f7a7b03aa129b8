//! Settling (model.md §6): (a) relax to static equilibrium, stopping when every vertex is slow
//! enough or reporting that it did not get there; (b) the zero-stress rest curve of each strand,
//! integrated from its root frame through the bonds' rest Darboux vectors; and export of both,
//! with the bond rates, as groom attributes.
use glam::{Quat, Vec3};
use serde::Serialize;

use super::bonds::BondKind;
use super::constraints::director3;
use super::{Hooks, Simulation};
use crate::groom::{Attribute, AttributeRate, Groom};

/// When relaxation counts as done.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SettleOptions {
    /// Every vertex slower than this (m/s)…
    pub max_speed: f32,
    /// …for this long (seconds), so a turning point of an oscillation does not count.
    pub quiet_time: f32,
    /// Give up after this many seconds of simulated time.
    pub max_seconds: f32,
    /// Solver iterations while settling (`None`: the simulation's own). Static shapes of stiff,
    /// finely cut strands need more than a dynamic step does.
    pub iterations: Option<u32>,
}

impl Default for SettleOptions {
    fn default() -> Self {
        SettleOptions { max_speed: 1e-4, quiet_time: 0.1, max_seconds: 30.0, iterations: None }
    }
}

/// What relaxation achieved.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SettleReport {
    pub converged: bool,
    pub steps: u64,
    pub seconds: f32,
    /// Largest vertex speed at the end, m/s.
    pub max_speed: f32,
}

impl Simulation {
    /// Steps until every vertex has stayed below `options.max_speed` for `options.quiet_time`,
    /// or until `options.max_seconds`; the report says which.
    pub fn settle(&mut self, options: &SettleOptions, hooks: &dyn Hooks) -> SettleReport {
        let dt = self.params().dt;
        let own_iterations = self.params().iterations;
        if let Some(iterations) = options.iterations.filter(|&n| n >= 1) {
            self.params.iterations = iterations;
        }
        let max_steps = (options.max_seconds / dt).ceil().max(1.0) as u64;
        let quiet_steps = (options.quiet_time / dt).ceil().max(1.0) as u64;
        let mut quiet = 0;
        let mut steps = 0;
        let mut speed = self.max_speed();
        while steps < max_steps {
            self.step_with(hooks);
            steps += 1;
            speed = self.max_speed();
            quiet = if speed < options.max_speed { quiet + 1 } else { 0 };
            if quiet >= quiet_steps {
                break;
            }
        }
        self.params.iterations = own_iterations;
        SettleReport { converged: quiet >= quiet_steps, steps, seconds: steps as f32 * dt, max_speed: speed }
    }

    /// Zero-stress Darboux vector of each edge pair (vertex-indexed; zero at roots and tips): the
    /// shape the bonds hold when no force acts. Where every bond is broken the current shape is
    /// stress-free and is used.
    pub fn zero_stress_darboux(&self) -> Vec<Vec3> {
        (0..self.rods.vertex_count())
            .map(|i| {
                if self.rods.is_pair_centre(i) {
                    self.bonds.zero_stress_shape(i).unwrap_or_else(|| self.rods.darboux_at(i))
                } else {
                    Vec3::ZERO
                }
            })
            .collect()
    }

    /// Each strand's zero-stress rest curve: from the root position and root frame, every next
    /// frame turns by the rest Darboux vector (`q̄_{i−1}⊗q_i = (√(1−|Ω0|²), Ω0)`) and every edge
    /// runs its rest length along its frame's third director.
    pub fn rest_curves(&self) -> Vec<Vec3> {
        let r = &self.rods;
        let omega0 = self.zero_stress_darboux();
        let mut points = vec![Vec3::ZERO; r.vertex_count()];
        for strand in 0..r.strand_count() {
            let range = r.strand_range(strand);
            let first = range.start;
            let mut frame = r.frames[first];
            let mut p = r.positions[first];
            points[first] = p;
            for i in first..range.end - 1 {
                if i > first {
                    let o = omega0[i].clamp_length_max(1.0);
                    let w = (1.0 - o.length_squared()).max(0.0).sqrt();
                    frame = (frame * Quat::from_xyzw(o.x, o.y, o.z, w)).normalize();
                }
                p += r.rest_lengths[i] * director3(frame);
                points[i + 1] = p;
            }
        }
        points
    }

    /// Writes the simulated state into `groom` (which must be the groom the simulation was built
    /// from, or one with the same strands): current positions as points, and the attributes
    /// `rest` (zero-stress rest curves), `rest_darboux` (Ω0) and `bond_*` (rates per kind).
    pub fn write_to_groom(&self, groom: &mut Groom) {
        groom.points.clone_from(&self.rods.positions);
        let flat = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
        groom.set_attribute(Attribute::new("rest", AttributeRate::Vertex, 3, flat(&self.rest_curves())));
        groom.set_attribute(Attribute::new(
            "rest_darboux",
            AttributeRate::Vertex,
            3,
            flat(&self.zero_stress_darboux()),
        ));
        for kind in BondKind::ALL {
            groom.set_attribute(Attribute::new(
                kind.attribute_name(),
                AttributeRate::Vertex,
                1,
                self.bonds.rates(kind).to_vec(),
            ));
        }
    }
}
