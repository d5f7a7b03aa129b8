//! Grooms that hold their shape when a simulation starts.
//!
//! * **Styled grooms** carry their zero-stress shape (`rest_darboux`, Ω0 per edge pair, in the
//!   frames a reader rebuilds: [`Simulation::exported_rest_darboux`]) and bond rates (`bond_*`). [`Simulation::adopt_rest_state`] makes every bond kind remember Ω0:
//!   with all kinds equal, S1-15's zero-stress shape is Ω0 at any rates, and the bend–twist
//!   constraint `C = (1 − β)·(Ω − Ω0)` is exactly the one the styled groom was settled with, so
//!   its settled shape is again an equilibrium.
//! * **Grooms fresh from a DCC tool** are drawn as they should look under gravity.
//!   [`Simulation::make_sag_free`] solves for the rest shape that holds the current shape in
//!   static equilibrium (Hsu et al. 2023, "Sag-free initialization for strand-based hybrid hair
//!   simulation"). With stretch–shear hard, the strand beyond vertex `i` is a rigid body hinged
//!   at `p_i` by the bend–twist pair `i`; turning it by a small world rotation `δθ` changes
//!   `Ω_i = Im(q̄_{i−1}⊗q_i)` by `J·δθ_loc`, `J = ½(w·I − [Ω]×)` (`δθ_loc` in frame `i−1`,
//!   `w` the real part), and gravity does work `δθ·M_i`, `M_i = Σ_{j>i} (p_j − p_i) × m_j·g`.
//!   Equilibrium is `Jᵀ·(C/α) = M_loc`, so `C = α ⊙ J⁻ᵀ·M_loc` and
//!   `Ω0 = Ω − C/(1 − β)`. The stretch is hard, so rest lengths stay.
//!
//!   The stepper's own static shape equals this energy minimum only where its iterations
//!   converge: with Gauss–Seidel sweeps straight strands hold to ~0.4 mm, while 1 cm curls cut in
//!   1 cm segments move 8 mm in 2 s at Δt 1/180 (bending too soft there, more so at large Δt);
//!   with the direct strand solve (`StrandSolver::Direct`) they hold to 0.006 mm at any Δt.
use glam::{Mat3, Quat, Vec3};

use super::bonds::{BondKind, Bonds};
use super::constraints::darboux_canonical;
use super::rod::transport_frames;
use super::Simulation;
use crate::error::{Error, Result};
use crate::groom::{AttributeRate, Groom};

/// The attribute that carries the zero-stress Darboux vectors (written by `write_to_groom`).
pub const REST_DARBOUX: &str = "rest_darboux";

impl Simulation {
    /// Uses the groom's exported zero-stress shape (`rest_darboux`) as every bond kind's memory,
    /// keeping the bond rates. Returns whether the groom had one. `groom` must be the groom the
    /// simulation was built from.
    pub fn adopt_rest_state(&mut self, groom: &Groom) -> Result<bool> {
        let Some(attribute) = groom.attribute(REST_DARBOUX) else { return Ok(false) };
        if attribute.rate != AttributeRate::Vertex
            || attribute.components != 3
            || attribute.data.len() != 3 * self.rods.vertex_count()
        {
            return Err(Error::Usage(format!(
                "attribute '{REST_DARBOUX}' must be three floats per vertex to give the rest shape"
            )));
        }
        if let Some(i) = attribute.data.iter().position(|v| !v.is_finite()) {
            return Err(Error::Usage(format!("attribute '{REST_DARBOUX}': vertex {} is not finite", i / 3)));
        }
        let shape: Vec<Vec3> = attribute
            .data
            .chunks_exact(3)
            .enumerate()
            .map(|(i, c)| if self.rods.is_pair_centre(i) { Vec3::new(c[0], c[1], c[2]) } else { Vec3::ZERO })
            .collect();
        self.remember_shape(&shape);
        Ok(true)
    }

    /// The zero-stress Darboux vectors measured in the frames a reader rebuilds from the current
    /// shape (`rod::transport_frames`), which is how a written groom gets its rest state back.
    /// The simulation's own frames `q` carry twist the written shape does not: a reader's frames
    /// are `p = q⊗z̄` with `z = p̄⊗q` a turn about each edge. The same change of frames applied
    /// to the rest turn of a pair, `u0 = q̄_{i−1}⊗q_i` at rest, gives `z_{i−1}⊗u0⊗z̄_i`, so the
    /// read-back groom is bent and twisted away from its rest shape as the simulated one was.
    pub fn exported_rest_darboux(&self) -> Vec<Vec3> {
        let r = &self.rods;
        let mut omega0 = self.zero_stress_darboux();
        let mut transported = vec![Quat::IDENTITY; r.vertex_count()];
        for strand in 0..r.strand_count() {
            let range = r.strand_range(strand);
            transport_frames(&r.positions()[range.clone()], &mut transported[range.clone()]);
            let twist = |e: usize| transported[e].conjugate() * r.frames()[e];
            for (i, omega) in omega0.iter_mut().enumerate().take(range.end - 1).skip(range.start + 1) {
                let o = omega.clamp_length_max(1.0);
                let rest_turn = Quat::from_xyzw(o.x, o.y, o.z, (1.0 - o.length_squared()).max(0.0).sqrt());
                let turn = twist(i - 1) * rest_turn * twist(i).conjugate();
                *omega = darboux_canonical(Quat::IDENTITY, turn.normalize());
            }
        }
        omega0
    }

    /// Makes the current shape the static equilibrium under gravity by solving for the rest
    /// Darboux vectors (module docs). Pairs whose bonds are all broken cannot hold anything and
    /// keep following the shape.
    pub fn make_sag_free(&mut self) {
        let r = &self.rods;
        let g = self.params.gravity;
        let mut shape: Vec<Vec3> = (0..r.vertex_count()).map(|i| r.darboux_at(i)).collect();
        for strand in 0..r.strand_count() {
            let range = r.strand_range(strand);
            // Walking from the tip: weight beyond `i` and its first moment, so
            // M_i = (Σ m_j p_j − p_i Σ m_j) × g.
            let (mut mass, mut moment) = (0.0f64, glam::DVec3::ZERO);
            for i in (range.start + 1..range.end).rev() {
                let bonded = self.bonded_fraction(i);
                if r.is_pair_centre(i) && bonded > 1e-6 {
                    let p = r.positions()[i].as_dvec3();
                    let torque = ((moment - p * mass).cross(g.as_dvec3())).as_vec3();
                    let frame = r.frames()[i - 1];
                    let relative = frame.conjugate() * r.frames()[i];
                    let (w, omega) = if relative.w < 0.0 {
                        (-relative.w, -relative.xyz())
                    } else {
                        (relative.w, relative.xyz())
                    };
                    let local = frame.conjugate() * torque;
                    // Jᵀ = ½(w·I + [Ω]×).
                    let jt = Mat3::from_cols(
                        Vec3::new(w, omega.z, -omega.y),
                        Vec3::new(-omega.z, w, omega.x),
                        Vec3::new(omega.y, -omega.x, w),
                    ) * 0.5;
                    let stress = jt.inverse() * local;
                    shape[i] = omega - r.compliance()[i] * stress / bonded;
                }
                let m = (r.mass()[i] * r.mass_scale()[i]) as f64;
                mass += m;
                moment += r.positions()[i].as_dvec3() * m;
            }
        }
        self.remember_shape(&shape);
    }

    /// `1 − β`: the influence-weighted share of intact bonds at a pair.
    fn bonded_fraction(&self, pair: usize) -> f32 {
        let f = self.bonds.influences().0;
        let intact: f32 = BondKind::ALL.iter().map(|&k| f[k as usize] * self.bonds.rate(k, pair)).sum();
        intact / self.bonds.influences().total()
    }

    /// Every bond kind remembers `shape`; rates stay.
    fn remember_shape(&mut self, shape: &[Vec3]) {
        let rates: Vec<Vec<f32>> = BondKind::ALL.iter().map(|&k| self.bonds.rates(k).to_vec()).collect();
        self.bonds = Bonds::new(self.bonds.influences(), shape);
        for (kind, rates) in BondKind::ALL.into_iter().zip(rates) {
            self.set_bond_rates_with(kind, |v| rates[v]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::{generate, GenerateParams, Style};
    use crate::sim::{NoHooks, SettleOptions, SimParams};

    /// `groom` read back with its exported rest state and simulated `steps` steps.
    fn read_back_and_step(groom: &Groom, steps: usize) -> Vec<glam::Vec3> {
        let mut sim = Simulation::new(groom, SimParams::default()).unwrap();
        assert!(sim.adopt_rest_state(groom).unwrap());
        (0..steps).for_each(|_| sim.step());
        sim.rods.positions().to_vec()
    }

    fn farthest(a: &[glam::Vec3], b: &[glam::Vec3]) -> f32 {
        a.iter().zip(b).map(|(a, b)| a.distance(*b)).fold(0.0, f32::max)
    }

    /// Curls hanging under gravity twist their frames; a reader rebuilds untwisted frames from
    /// the written shape. Measured in those frames, the exported rest state keeps a settled
    /// groom read back nearly still; in the simulation's own frames (the control) it turns
    /// its remembered bends and moves. Not yet still: the frames' shear against their edges,
    /// which carries part of gravity's moment in a settled strand, is not written (measured:
    /// 2.2 mm in 1 s against the control's 14.6 mm; the settled simulation moves 0.03 mm).
    #[test]
    fn the_rest_state_is_written_in_the_frames_a_reader_rebuilds() {
        let groom = generate(&GenerateParams {
            strands: 6,
            vertices_per_strand: 24,
            style: Style::Curly { radius: 0.01, pitch: 0.03 },
            seed: 3,
            ..GenerateParams::default()
        })
        .unwrap();
        let mut sim = Simulation::new(&groom, SimParams::default()).unwrap();
        let options = SettleOptions { tolerance: 1e-4, max_seconds: 30.0, iterations: None };
        let report = sim.settle(&options, &NoHooks);
        assert!(report.converged, "{report:?}");
        let mut written = groom.clone();
        sim.write_to_groom(&mut written);
        let start = sim.rods.positions().to_vec();
        let steps = 360;
        (0..steps).for_each(|_| sim.step());
        let continued = farthest(&start, sim.rods.positions());
        let exported = farthest(&start, &read_back_and_step(&written, steps));

        let own_frames: Vec<f32> = sim.zero_stress_darboux().iter().flat_map(|v| v.to_array()).collect();
        let mut control = written.clone();
        control.set_attribute(crate::groom::Attribute::new(
            REST_DARBOUX,
            AttributeRate::Vertex,
            3,
            own_frames,
        ));
        let untransformed = farthest(&start, &read_back_and_step(&control, steps));
        eprintln!(
            "in 1 s the settled groom moves {:.4} mm, read back {:.4} mm, with the simulation's \
             frames {:.2} mm",
            continued * 1e3,
            exported * 1e3,
            untransformed * 1e3
        );
        assert!(
            exported < 0.25 * untransformed,
            "read back, the settled groom moves {exported} m in 1 s; {untransformed} m with the \
             simulation's frames"
        );
    }
}
