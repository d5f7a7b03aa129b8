//! Grooms that hold their shape when a simulation starts.
//!
//! * **Styled grooms** carry their zero-stress shape (`rest_darboux`, Ω0 per edge pair, in the
//!   frames a reader rebuilds: [`Simulation::exported_rest_darboux`]), their material frames
//!   (`material_frame`: a reader that takes them is in the simulated state, twist and shear
//!   included), bond rates (`bond_*`) and zero-stress curves (`rest`, whose edges are the rest
//!   lengths: the settled shape is strained by its load). [`Simulation::adopt_rest_state`] takes
//!   the rest lengths and makes every bond kind remember Ω0:
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
use super::constraints::{darboux_canonical, director3, turn_of};
use super::rod::transport_frames;
use super::Simulation;
use crate::error::{Error, Result};
use crate::groom::{Attribute, AttributeRate, Groom, GroomError};

/// The attribute that carries the zero-stress Darboux vectors (written by `write_to_groom`).
pub const REST_DARBOUX: &str = "rest_darboux";

/// The attribute that carries each strand's zero-stress rest curve (written by `write_to_groom`).
pub use crate::io::usda::names::REST as REST_CURVES;

/// How far, relative to its own length, a written rest curve's edge may be from the strand's for
/// the curve to give the strand its rest lengths: a settled strand's edges are strained by
/// 1e-3 or so, a curve that differs by more is not its rest.
const REST_LENGTH_MATCH: f32 = 0.01;

/// The attribute that carries each edge's material frame, a unit quaternion `(x, y, z, w)` whose
/// third director runs along the edge (per vertex; the tip repeats the last edge's).
pub const MATERIAL_FRAME: &str = "material_frame";

/// How far a vertex of a sag-free groom may move before the run is said not to have held it:
/// straight strands hold to 0.4 mm and coarse curls to 8 mm (module docs).
pub const HELD: f32 = 0.01;

/// What becomes of strands that rise above their root under a sag-free rest shape.
const UNSTABLE: &str = "a sag-free rest shape holds a strand up there in an unstable balance, and it falls \
                        (settle the groom first, or lay those strands down)";

/// Greenhill's self-buckling length of a hair of `radius` (metres) under `gravity` (m/s²):
/// 1.99·(E·I/(ρ·g·A))^⅓ with I = π r⁴/4 and A = π r² (9.9 cm for an 80 µm hair).
fn self_buckling_length(material: &crate::sim::Material, gravity: f32, radius: f32) -> f32 {
    let load = material.density * gravity;
    if load <= 0.0 {
        return f32::INFINITY;
    }
    1.99 * (material.youngs_modulus * radius * radius / (4.0 * load)).cbrt()
}

/// Arc length from a strand's root to its highest point along `up`.
fn rising_length(points: &[Vec3], up: Vec3) -> f32 {
    let highest =
        (0..points.len()).fold(0, |best, i| if points[i].dot(up) > points[best].dot(up) { i } else { best });
    points[..=highest].windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// Cosine of the largest angle between a written frame's third director and its edge for the
/// frame to be taken (5°; a settled strand's shear is a fraction of a degree).
const MAX_FRAME_TILT_COS: f32 = 0.996_194_7;

/// A groom attribute the simulation cannot read back (the caller names the file it came from).
fn bad_attribute(name: &str, problem: String) -> Error {
    Error::Groom(GroomError::BadAttribute { name: name.to_string(), problem })
}

impl Simulation {
    /// Uses the groom's exported zero-stress shape (`rest_darboux`) as every bond kind's memory,
    /// keeping the bond rates. Returns whether the groom had one. `groom` must be the groom the
    /// simulation was built from.
    pub fn adopt_rest_state(&mut self, groom: &Groom) -> Result<bool> {
        let Some(attribute) =
            self.per_vertex(groom, REST_DARBOUX, 3, "three floats per vertex to give the rest shape")?
        else {
            return Ok(false);
        };
        let values = attribute.floats();
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(bad_attribute(REST_DARBOUX, format!("vertex {} is not finite", i / 3)));
        }
        // The vector part of a unit turn (`darboux_canonical`): at most 1 long, up to round-off
        // (1e30 once went into the bonds' memory and the rods overflowed within a step).
        let length = |c: &[f32]| Vec3::from_slice(c).as_dvec3().length();
        if let Some((i, c)) = values.chunks_exact(3).enumerate().find(|(_, c)| length(c) > 1.0 + 1e-3) {
            return Err(bad_attribute(
                REST_DARBOUX,
                format!(
                    "vertex {i} is {} long; a rest_darboux is the vector part of a unit quaternion (the turn \
                     between neighbouring edge frames), at most 1",
                    crate::validate::shortest(length(c))
                ),
            ));
        }
        let mut shape: Vec<Vec3> = values
            .chunks_exact(3)
            .enumerate()
            .map(|(i, c)| if self.rods.is_pair_centre(i) { Vec3::new(c[0], c[1], c[2]) } else { Vec3::ZERO })
            .collect();
        if let Some(frames) = self.written_frames(groom)? {
            self.adopt_frames(&frames, &mut shape);
        }
        self.remember_shape(&shape);
        self.adopt_rest_lengths(groom);
        Ok(true)
    }

    /// Takes each strand's rest lengths from its written zero-stress curve (`rest`, whose edges
    /// run the rest lengths: [`Self::rest_curves`]) rather than from its shape: a settled strand
    /// is stretched or pressed by its load, and read as rest lengths that strain was gone. A
    /// blow-dried strand folded against the head (`tests/style_settle.rs`) has edges 1.5e-3 off
    /// their rest lengths at the fold; read back without them, its root vertex (held by friction
    /// near the edge of the static cone) felt forces the settle never had, and with friction
    /// summed over the step it broke loose and moved 1.9 mm. A strand whose curve's edges are not
    /// all within [`REST_LENGTH_MATCH`] of its own keeps its own (the curve is not this shape's
    /// rest: rescaled, resampled or edited since), as does a groom without a `rest` of a point per
    /// vertex.
    fn adopt_rest_lengths(&mut self, groom: &Groom) {
        let Some(rest) = groom.attribute(REST_CURVES) else { return };
        if rest.rate != AttributeRate::Vertex
            || rest.components != 3
            || rest.data.len() != 3 * groom.vertex_count()
        {
            return;
        }
        let rest: Vec<Vec3> = rest.floats().chunks_exact(3).map(Vec3::from_slice).collect();
        let mut lengths = self.rods.rest_lengths().to_vec();
        let mut adopted = false;
        for strand in 0..self.rods.strand_count() {
            let edges = self.rods.strand_range(strand).start..self.rods.strand_range(strand).end - 1;
            let written = |e: usize| rest[e].distance(rest[e + 1]);
            let matches = edges.clone().all(|e| {
                let own = lengths[e];
                (written(e) - own).abs() <= REST_LENGTH_MATCH * own
            });
            if matches {
                edges.for_each(|e| lengths[e] = written(e));
                adopted = true;
            }
        }
        if adopted {
            let factor = self.params.frame_inertia_factor;
            self.rods.adopt_rest_lengths(groom, &self.params.material, &lengths, factor);
            self.masses_dirty = true;
        }
    }

    /// The groom's attribute `name`, checked to hold `components` values per vertex (`what` says
    /// what they are); `None` without one.
    fn per_vertex<'g>(
        &self,
        groom: &'g Groom,
        name: &str,
        components: usize,
        what: &str,
    ) -> Result<Option<&'g Attribute>> {
        let Some(attribute) = groom.attribute(name) else { return Ok(None) };
        if attribute.rate != AttributeRate::Vertex
            || attribute.components != components
            || attribute.data.len() != components * self.rods.vertex_count()
        {
            return Err(bad_attribute(name, format!("must be {what}")));
        }
        Ok(Some(attribute))
    }

    /// The groom's `material_frame` attribute as unit quaternions, checked; `None` without one.
    fn written_frames(&self, groom: &Groom) -> Result<Option<Vec<Quat>>> {
        let Some(attribute) =
            self.per_vertex(groom, MATERIAL_FRAME, 4, "a quaternion (four floats) per vertex")?
        else {
            return Ok(None);
        };
        attribute
            .floats()
            .chunks_exact(4)
            .enumerate()
            .map(|(i, c)| {
                let q = Quat::from_xyzw(c[0], c[1], c[2], c[3]);
                // A written unit quaternion is within f32 round-off of length 1.
                if !(q.is_finite() && (q.length() - 1.0).abs() < 1e-3) {
                    return Err(bad_attribute(
                        MATERIAL_FRAME,
                        format!("vertex {i} is not a unit quaternion ({c:?})"),
                    ));
                }
                Ok(q.normalize())
            })
            .collect::<Result<Vec<Quat>>>()
            .map(Some)
    }

    /// Takes each strand's written material frames, and turns the rest shape `shape` (written in
    /// the frames a reader rebuilds) into those frames: the inverse of
    /// [`Self::exported_rest_darboux`], `u0 = z̄_{i−1}⊗u0'⊗z_i` with `z = p̄⊗q`. A strand whose
    /// frames do not follow its edges (the curve was edited after they were written) keeps the
    /// rebuilt frames, which `shape` is already measured in.
    fn adopt_frames(&mut self, frames: &[Quat], shape: &mut [Vec3]) {
        let mut transported = vec![Quat::IDENTITY; self.rods.vertex_count()];
        for strand in 0..self.rods.strand_count() {
            let range = self.rods.strand_range(strand);
            let points = &self.rods.positions()[range.clone()];
            let follows_edges = (range.start..range.end - 1).all(|e| {
                let edge = (points[e + 1 - range.start] - points[e - range.start]).normalize();
                director3(frames[e]).dot(edge) >= MAX_FRAME_TILT_COS
            });
            if !follows_edges {
                continue;
            }
            transport_frames(points, &mut transported[range.clone()]);
            let twist = |e: usize| transported[e].conjugate() * frames[e];
            for (i, omega) in shape.iter_mut().enumerate().take(range.end - 1).skip(range.start + 1) {
                let turn = twist(i - 1).conjugate() * turn_of(*omega) * twist(i);
                *omega = darboux_canonical(Quat::IDENTITY, turn.normalize());
            }
            self.rods.frames_mut()[range.clone()].copy_from_slice(&frames[range]);
        }
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
                let turn = twist(i - 1) * turn_of(*omega) * twist(i).conjugate();
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

    /// A warning when a sag-free run did not hold the shape: strands whose vertices moved more
    /// than [`HELD`] from `initial` (the groom the simulation was built from) after `seconds`.
    /// Strands that rise above their root before hanging are balanced by their sag-free rest
    /// shape in an unstable equilibrium: 16 crown strands of `coif generate`'s default groom
    /// fell 10–20 cm in 2 s, while its other strands moved under 2.2 cm (most under 1 mm).
    pub fn unheld_warning(&self, initial: &Groom, seconds: f32) -> Option<String> {
        let r = &self.rods;
        let (mut moved, mut rising, mut worst) = (0usize, 0usize, (0usize, 0.0f32));
        for strand in 0..r.strand_count() {
            let range = r.strand_range(strand);
            let now = &r.positions()[range.clone()];
            let before = &initial.points[range.clone()];
            let drift = now.iter().zip(before).map(|(a, b)| a.distance(*b)).fold(0.0, f32::max);
            if drift > HELD {
                moved += 1;
                rising += usize::from(self.rises_above_root(before));
                if drift > worst.1 {
                    worst = (strand, drift);
                }
            }
        }
        (moved > 0).then(|| {
            format!(
                "--sag-free did not hold {moved} of {} strands in {seconds} s (strand {}: {:.1} cm), {rising} of \
                 them rising above their root: {UNSTABLE}",
                r.strand_count(),
                worst.0,
                worst.1 * 100.0
            )
        })
    }

    /// [`unheld_warning`](Self::unheld_warning) foretold, for a run that moves the hair by design
    /// (styling, where a fall cannot be told from the style): the strands of `initial` (the groom
    /// the simulation was built from) that rise above their root along more than hair's
    /// self-buckling length, which no rest shape holds standing. On `coif generate`'s default
    /// groom, 18 of its 1,000 (23 fell more than 1 cm in 2 s of `simulate --sag-free`); none of
    /// the 8 cm groom that holds.
    pub fn unstable_warning(&self, initial: &Groom) -> Option<String> {
        let material = &self.params.material;
        let gravity = self.params.gravity.length();
        let buckling = |strand: usize| {
            let range = initial.strand_range(strand);
            let width = match initial.widths[range.start] {
                w if w > 0.0 => w,
                _ => material.fallback_width,
            };
            self_buckling_length(material, gravity, 0.5 * width)
        };
        let mut unstable = (0..initial.strand_count()).filter_map(|strand| {
            let points = initial.strand_points(strand);
            let length = buckling(strand);
            (self.rises_above_root(points) && rising_length(points, self.up()) > length)
                .then_some((strand, length))
        });
        let (first, length) = unstable.next()?;
        Some(format!(
            "sag_free: {} of {} strands rise above their root along more than hair's self-buckling length \
             ({:.1} cm at strand {first}'s width), which no rest shape holds standing: {UNSTABLE}",
            1 + unstable.count(),
            initial.strand_count(),
            length * 100.0
        ))
    }

    /// The way up: against gravity (zero without it).
    fn up(&self) -> Vec3 {
        -self.params.gravity.normalize_or_zero()
    }

    /// Whether a strand's points rise more than [`HELD`] above its root, against gravity.
    fn rises_above_root(&self, points: &[Vec3]) -> bool {
        let up = self.up();
        let root = points[0].dot(up);
        points.iter().any(|p| p.dot(up) > root + HELD)
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
    use crate::sim::{NoHooks, SettleOptions, SimParams, StrandSolver};

    /// `groom` read back with its exported rest state and simulated `steps` steps.
    fn read_back_and_step(groom: &Groom, params: &SimParams, steps: usize) -> Vec<glam::Vec3> {
        let mut sim = Simulation::new(groom, params.clone()).unwrap();
        assert!(sim.adopt_rest_state(groom).unwrap());
        (0..steps).for_each(|_| sim.step());
        sim.rods.positions().to_vec()
    }

    fn farthest(a: &[glam::Vec3], b: &[glam::Vec3]) -> f32 {
        a.iter().zip(b).map(|(a, b)| a.distance(*b)).fold(0.0, f32::max)
    }

    /// A settled strand's edges are strained by its load, and its written `rest` curve carries
    /// the rest lengths: a groom stretched 0.2 % along its strands, written and read back, pulls
    /// back as the simulation itself does (the same positions ten steps on, to round-off). With
    /// rest lengths measured on the stretched shape it stayed stretched: the two lay as far apart
    /// as the simulation pulled back. A `rest` curve that is not the shape's (twice its size) is
    /// not taken.
    #[test]
    fn a_strained_groom_is_read_back_with_its_rest_lengths() {
        let groom = generate(&GenerateParams {
            strands: 4,
            vertices_per_strand: 16,
            seed: 2,
            ..GenerateParams::default()
        })
        .unwrap();
        let params = SimParams { gravity: Vec3::ZERO, ..SimParams::default() };
        let mut sim = Simulation::new(&groom, params.clone()).unwrap();
        for strand in 0..sim.rods.strand_count() {
            let range = sim.rods.strand_range(strand);
            let root = sim.rods.positions()[range.start];
            for p in &mut sim.rods.positions_mut()[range] {
                *p = root + (*p - root) * 1.002;
            }
        }
        let mut written = groom.clone();
        sim.write_to_groom(&mut written);
        let mut read = Simulation::new(&written, params.clone()).unwrap();
        assert!(read.adopt_rest_state(&written).unwrap());
        for (i, (a, b)) in sim.rods.rest_lengths().iter().zip(read.rods.rest_lengths()).enumerate() {
            assert!((a - b).abs() <= 1e-5 * a, "edge {i}: rest length {a} m, read back {b} m");
        }
        for _ in 0..10 {
            sim.step();
            read.step();
        }
        let pulled = farthest(&written.points, sim.rods.positions());
        let apart = farthest(sim.rods.positions(), read.rods.positions());
        eprintln!("pulled back {:.2} µm; read back, {:.4} µm from that", pulled * 1e6, apart * 1e6);
        assert!(pulled > 10e-6, "the stretched groom pulls back {pulled} m");
        assert!(apart < 0.01 * pulled, "read back, the groom lies {apart} m from the simulation's");

        let mut scaled = written.clone();
        let rest = scaled.attributes.iter_mut().find(|a| a.name == REST_CURVES).unwrap();
        rest.floats_mut().unwrap().iter_mut().for_each(|v| *v *= 2.0);
        let mut other = Simulation::new(&scaled, params).unwrap();
        let own = other.rods.rest_lengths().to_vec();
        assert!(other.adopt_rest_state(&scaled).unwrap());
        assert_eq!(other.rods.rest_lengths(), &own[..]);
    }

    /// How far a settled curly groom moves in 1 s with `solver`, read back with its exported
    /// rest state — with its written `material_frame`, without it (the reader rebuilds
    /// the frames from the shape), and without it but with the rest Darboux vectors in the
    /// simulation's own frames (the control).
    struct ReadBack {
        with_frames: f32,
        without_frames: f32,
        untransformed: f32,
    }

    /// Measures [`ReadBack`] for `solver`, and checks what holds for both solvers: read back with
    /// its written frames the groom moves as little as going on (at most twice, plus 10 µm).
    fn settled_curls_read_back(solver: StrandSolver) -> ReadBack {
        let groom = generate(&GenerateParams {
            strands: 6,
            vertices_per_strand: 24,
            style: Style::Curly { radius: 0.01, pitch: 0.03 },
            seed: 3,
            ..GenerateParams::default()
        })
        .unwrap();
        let params = SimParams::for_solver(solver);
        let mut sim = Simulation::new(&groom, params.clone()).unwrap();
        let options = SettleOptions { tolerance: 1e-4, max_seconds: 30.0, iterations: None };
        let report = sim.settle(&options, &NoHooks);
        assert!(report.converged, "{solver:?}: {report:?}");
        let mut written = groom.clone();
        sim.write_to_groom(&mut written);
        let start = sim.rods.positions().to_vec();
        let steps = 360;
        (0..steps).for_each(|_| sim.step());
        let continued = farthest(&start, sim.rods.positions());
        let with_frames = farthest(&start, &read_back_and_step(&written, &params, steps));

        let mut rebuilt = written.clone();
        rebuilt.attributes.retain(|a| a.name != MATERIAL_FRAME);
        let without_frames = farthest(&start, &read_back_and_step(&rebuilt, &params, steps));
        let own_frames: Vec<f32> = sim.zero_stress_darboux().iter().flat_map(|v| v.to_array()).collect();
        let mut control = rebuilt.clone();
        control.set_attribute(crate::groom::Attribute::new(
            REST_DARBOUX,
            AttributeRate::Vertex,
            3,
            own_frames,
        ));
        let untransformed = farthest(&start, &read_back_and_step(&control, &params, steps));
        eprintln!(
            "{solver:?}: in 1 s the settled groom moves {:.4} mm, read back {:.4} mm; without its \
             frames {:.4} mm, with the rest state in the simulation's frames {:.2} mm",
            continued * 1e3,
            with_frames * 1e3,
            without_frames * 1e3,
            untransformed * 1e3
        );
        // With its written frames the groom read back is in the simulation's own state.
        assert!(
            with_frames <= 2.0 * continued + 1e-5,
            "{solver:?}: read back, the settled groom moves {with_frames} m in 1 s; going on, {continued} m"
        );
        ReadBack { with_frames, without_frames, untransformed }
    }

    /// Curls hanging under gravity twist their frames; a reader rebuilds untwisted frames from
    /// the written shape. With the written `material_frame`, a settled groom read back is in the
    /// simulation's own state and moves as little as the simulation does when it goes on. A reader
    /// without the frames measures the exported rest state in the frames it rebuilds: the groom
    /// read back moves less than with the rest state in the simulation's frames (the control),
    /// though not as little, since the frames' shear against their edges carries part of
    /// gravity's moment in a settled strand (measured: 0.75 mm in 1 s without the frames, 13.6 mm
    /// for the control, 0.012 mm read back with the frames as going on). These figures are
    /// Gauss–Seidel's, whose heavy frames lag their edges; the direct solve has its own test
    /// (`the_direct_solvers_rest_state_is_written_with_its_frames`).
    #[test]
    fn the_rest_state_is_written_with_the_frames_it_is_measured_in() {
        let r = settled_curls_read_back(StrandSolver::GaussSeidel);
        assert!(
            r.without_frames < 0.25 * r.untransformed,
            "read back without its frames, the settled groom moves {} m in 1 s; {} m with the \
             simulation's frames",
            r.without_frames,
            r.untransformed
        );
    }

    /// The same groom settled by the direct solve: read back with its written frames it moves as
    /// little as the simulation going on (0.0047 and 0.0046 mm in 1 s), and without them it moves
    /// far more (0.87 mm), so the frames are what holds it. The Gauss–Seidel test's control does
    /// not separate here: the rest state in the simulation's frames moves about as far (0.73 mm)
    /// as in the rebuilt ones, and that comparison was the one that failed when the direct solve
    /// became the default.
    #[test]
    fn the_direct_solvers_rest_state_is_written_with_its_frames() {
        let r = settled_curls_read_back(StrandSolver::Direct);
        assert!(
            r.with_frames < 0.1 * r.without_frames,
            "read back with its frames, the settled groom moves {} m in 1 s; without them {} m",
            r.with_frames,
            r.without_frames
        );
    }

    /// Frames that no longer follow their edges (a curve edited after it was written) are not
    /// taken: the strand keeps the frames a reader rebuilds. Frames that are not unit
    /// quaternions are an error naming the vertex.
    #[test]
    fn written_frames_are_checked() {
        let groom =
            generate(&GenerateParams { strands: 2, vertices_per_strand: 8, ..GenerateParams::default() })
                .unwrap();
        let sim = Simulation::new(&groom, SimParams::default()).unwrap();
        let mut edited = groom.clone();
        sim.write_to_groom(&mut edited);
        let frames = edited.attributes.iter_mut().find(|a| a.name == MATERIAL_FRAME).unwrap();
        // Every frame twisted about its edge (still a valid state), then strand 0's second edge
        // frame turned a quarter turn off its edge.
        let data = frames.floats_mut().unwrap();
        for q in data.chunks_exact_mut(4) {
            let twisted = Quat::from_slice(q) * Quat::from_rotation_z(0.3);
            q.copy_from_slice(&twisted.to_array());
        }
        let twisted: Vec<Quat> = data.chunks_exact(4).map(Quat::from_slice).collect();
        let turned = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2) * twisted[1];
        data[4..8].copy_from_slice(&turned.to_array());
        let mut read = Simulation::new(&edited, SimParams::default()).unwrap();
        assert!(read.adopt_rest_state(&edited).unwrap());
        let edited_strand = read.rods.strand_range(0);
        assert_eq!(&read.rods.frames()[edited_strand.clone()], &sim.rods.frames()[edited_strand]);
        let other = read.rods.strand_range(1);
        for e in other {
            assert!(read.rods.frames()[e].angle_between(twisted[e]) < 1e-3, "edge {e}");
        }

        let frames = edited.attributes.iter_mut().find(|a| a.name == MATERIAL_FRAME).unwrap();
        frames.floats_mut().unwrap()[12] = 2.0;
        let message = Simulation::new(&edited, SimParams::default())
            .unwrap()
            .adopt_rest_state(&edited)
            .unwrap_err()
            .to_string();
        assert!(message.contains("material_frame") && message.contains("vertex 3"), "{message}");
    }
}
