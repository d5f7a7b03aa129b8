//! Water in the hair as a per-vertex field `w ∈ [0, 1]` (model.md §6): taken up when wetted,
//! wicking along the strand, evaporating with time, air flow and heat. Wetness sets the hydrogen
//! bond rate (`b_hyd = 1 − w`: wet hair has its hydrogen bonds broken, drying re-forms them at
//! the current shape through S1-16) and the strand's mass.
use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::sim::Simulation;

/// The per-vertex attribute a groom carries its wetness in (0 dry … 1 soaked).
pub const WETNESS: &str = "wetness";

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WetnessParams {
    /// Wicking along the strand, m²/s.
    pub diffusion: f32,
    /// Evaporation in still, room-temperature air, fraction per second.
    pub evaporation: f32,
    /// Drying per unit of wind velocity change (S1-19's 0.003, per m/s of |Δv_w|).
    pub airflow_drying: f32,
    /// Extra mass of fully wet hair, as a fraction of its dry mass (hair takes up ~30 % of its
    /// weight in water, and a surface film carries as much again).
    pub mass_gain: f32,
}

impl Default for WetnessParams {
    fn default() -> Self {
        WetnessParams { diffusion: 1e-4, evaporation: 1.0 / 1800.0, airflow_drying: 0.003, mass_gain: 0.6 }
    }
}

/// The hydrogen bond rate wetness implies.
pub fn hydrogen_rate(wetness: f32) -> f32 {
    1.0 - wetness.clamp(0.0, 1.0)
}

/// Mass multiplier of a vertex with this wetness.
pub fn mass_scale(wetness: f32, params: &WetnessParams) -> f32 {
    1.0 + params.mass_gain * wetness.clamp(0.0, 1.0)
}

/// Gives every vertex of `sim` the weight of the water it holds (`wetness` per vertex).
pub fn carry_water(sim: &mut Simulation, wetness: &[f32], params: &WetnessParams) {
    for (vertex, &w) in wetness.iter().enumerate() {
        sim.set_mass_scale(vertex, mass_scale(w, params));
    }
}

/// One step of evaporation: ambient drying scaled by heat, plus S1-19's drying by wind, where
/// `wind_dv[i]` is the wind's velocity change |Δv_w| at vertex i this step.
pub fn evaporate(wetness: &mut [f32], wind_dv: &[f32], heat: f32, dt: f32, params: &WetnessParams) {
    for (w, &dv) in wetness.iter_mut().zip(wind_dv) {
        let loss = heat * (params.evaporation * dt + params.airflow_drying * dv);
        *w = (*w - loss).max(0.0);
    }
}

/// One step of wicking along every strand, strands in parallel (see [`diffuse`]).
pub fn diffuse_strands(
    wetness: &mut [f32],
    points: &[Vec3],
    strand_offsets: &[u32],
    dt: f32,
    diffusivity: f32,
) {
    let mut strands = Vec::with_capacity(strand_offsets.len());
    let mut rest = wetness;
    for w in strand_offsets.windows(2) {
        let (strand, tail) = rest.split_at_mut((w[1] - w[0]) as usize);
        strands.push((w[0] as usize, strand));
        rest = tail;
    }
    strands.into_par_iter().for_each_init(Vec::new, |scratch, (first, w)| {
        let n = w.len();
        diffuse(w, &points[first..first + n], dt, diffusivity, scratch)
    });
}

/// One step of wicking along a strand: diffusion on the polyline (each edge conducts as 1/length²,
/// no flux through root or tip), taken implicitly (backward Euler, one tridiagonal solve): stable
/// for any edge, so the work is one pass per step however short an edge is. The explicit scheme
/// it replaces needed a substep per `0.4·l²/D` of the shortest edge: a single 2 µm edge (a
/// duplicated root nudged by a micron) made a wet stage ~170,000 substeps per step, hours for a
/// groom. Water is conserved (the matrix's columns sum to one) and stays within [0, 1] (an
/// M-matrix: no new extremes). `scratch` is reused between calls.
pub fn diffuse(w: &mut [f32], p: &[Vec3], dt: f32, diffusivity: f32, scratch: &mut Vec<f64>) {
    // An even strand stays as it is (the solve returns its values to the bit): a soaked or dry
    // groom skips the solve, which was 2 % of a wet step of seed 2's 10,000 × 6.
    if w.iter().all(|&x| x == w[0]) {
        return;
    }
    solve_wicking(w, p, dt, diffusivity, scratch);
}

/// [`diffuse`]'s implicit step, solved whatever the values.
fn solve_wicking(w: &mut [f32], p: &[Vec3], dt: f32, diffusivity: f32, scratch: &mut Vec<f64>) {
    let n = w.len();
    if n < 2 || diffusivity <= 0.0 {
        return;
    }
    let edges = n - 1;
    // Scratch (f64, so that water is conserved to rounding over thousands of steps): each edge's
    // conductance × Δt, then the sweep's modified upper diagonal, then its right-hand side.
    scratch.clear();
    let step = f64::from(diffusivity) * f64::from(dt);
    scratch.extend(p.windows(2).map(|s| step / f64::from(s[0].distance(s[1]).max(1e-6)).powi(2)));
    // Thomas algorithm on (I + Δt·D·L)·w' = w; rows are diagonally dominant, so no pivoting.
    let (mut upper, mut value) = (0.0f64, 0.0f64);
    for i in 0..n {
        let left = if i > 0 { scratch[i - 1] } else { 0.0 };
        let right = if i < edges { scratch[i] } else { 0.0 };
        let pivot = 1.0 + left + right + left * upper;
        value = (f64::from(w[i]) + left * value) / pivot;
        upper = -right / pivot;
        scratch.push(upper);
        scratch.push(value);
    }
    let solved = |i: usize| scratch[edges + 2 * i + 1];
    let mut next = solved(edges);
    w[edges] = next.clamp(0.0, 1.0) as f32;
    for i in (0..edges).rev() {
        next = solved(i) - scratch[edges + 2 * i] * next;
        w[i] = next.clamp(0.0, 1.0) as f32;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evaporation_follows_s1_19_and_stops_at_dry() {
        let params = WetnessParams { evaporation: 0.0, ..Default::default() };
        let mut w = vec![1.0, 1.0, 0.001];
        evaporate(&mut w, &[0.0, 2.0, 2.0], 1.0, 1.0 / 360.0, &params);
        assert_eq!(w[0], 1.0);
        assert!((w[1] - (1.0 - 0.006)).abs() < 1e-7);
        assert_eq!(w[2], 0.0);
        assert!((hydrogen_rate(w[1]) - 0.006).abs() < 1e-6);
    }

    #[test]
    fn wicking_conserves_water_and_evens_it_out() {
        let points: Vec<Vec3> = (0..10).map(|i| Vec3::new(0.0, -0.01 * i as f32, 0.0)).collect();
        let mut w = vec![0.0; 10];
        w[0] = 1.0;
        let mut scratch = Vec::new();
        let total = |w: &[f32]| w.iter().sum::<f32>();
        for _ in 0..2000 {
            diffuse(&mut w, &points, 0.05, 1e-4, &mut scratch);
        }
        assert!((total(&w) - 1.0).abs() < 1e-4, "water lost: {}", total(&w));
        assert!(w.iter().all(|&x| (x - 0.1).abs() < 0.01), "{w:?}");
    }

    #[test]
    fn an_even_strand_is_left_as_the_solve_leaves_it_to_the_bit() {
        // `diffuse` skips strands whose wetness is even: the solve must return them unchanged,
        // whatever the value and however uneven the edges.
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
        let mut scratch = Vec::new();
        for _ in 0..2000 {
            let n = rng.random_range(2..40);
            let points: Vec<Vec3> = (0..n)
                .map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * rng.random_range(1e-6..0.1))
                .collect();
            let value = match rng.random_range(0..4) {
                0 => 0.0,
                1 => 1.0,
                _ => rng.random::<f32>(),
            };
            let mut w = vec![value; n];
            let dt = rng.random_range(1e-4..0.1);
            solve_wicking(&mut w, &points, dt, rng.random_range(1e-6..1e-3), &mut scratch);
            assert!(w.iter().all(|x| x.to_bits() == value.to_bits()), "{value} became {w:?}");
        }
    }

    /// Against the continuous solution: water put in the middle of a long strand spreads as a
    /// Gaussian of variance 2·D·t; a 1 µm edge beside it neither slows nor upsets that.
    #[test]
    fn wicking_spreads_as_diffusion_does_whatever_the_edges() {
        let (spacing, d, dt, steps) = (0.001f32, 1e-4f32, 1.0 / 360.0, 360);
        for short in [false, true] {
            let mut points: Vec<Vec3> = (0..401).map(|i| Vec3::new(0.0, -spacing * i as f32, 0.0)).collect();
            if short {
                // A duplicated vertex a micron apart, away from the water.
                points.insert(350, points[350] + Vec3::new(1e-6, 0.0, 0.0));
            }
            let mut w = vec![0.0; points.len()];
            w[200] = 0.5;
            let mut scratch = Vec::new();
            for _ in 0..steps {
                diffuse(&mut w, &points, dt, d, &mut scratch);
            }
            let total: f32 = w.iter().sum();
            let variance: f32 =
                w.iter().enumerate().map(|(i, &x)| x * ((i as f32 - 200.0) * spacing).powi(2)).sum::<f32>()
                    / total;
            let expected = 2.0 * d * dt * steps as f32;
            assert!((total - 0.5).abs() < 1e-4, "water {total}");
            assert!((variance / expected - 1.0).abs() < 0.02, "variance {variance:e}, expected {expected:e}");
        }
    }
}
