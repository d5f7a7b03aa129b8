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

/// One step of wicking along a strand (explicit diffusion on the polyline, sub-stepped for
/// stability, with no flux through root or tip). `scratch` is reused between calls.
pub fn diffuse(w: &mut [f32], p: &[Vec3], dt: f32, diffusivity: f32, scratch: &mut Vec<f32>) {
    let n = w.len();
    if n < 2 || diffusivity <= 0.0 {
        return;
    }
    // Scratch: the edges' squared lengths (each vertex's two fluxes and every substep share
    // them), then the substep's starting values.
    scratch.clear();
    scratch.extend(p.windows(2).map(|s| s[0].distance(s[1]).max(1e-6)));
    let min_segment = scratch.iter().copied().fold(f32::MAX, f32::min);
    scratch.iter_mut().for_each(|l| *l *= *l);
    let stable_dt = 0.4 * min_segment * min_segment / diffusivity;
    let substeps = (dt / stable_dt).ceil().max(1.0) as usize;
    let h = dt / substeps as f32;
    let edges = n - 1;
    for _ in 0..substeps {
        scratch.truncate(edges);
        scratch.extend_from_slice(w);
        let (length2, old) = scratch.split_at(edges);
        for i in 0..n {
            let mut flux = 0.0;
            if i > 0 {
                flux += (old[i - 1] - old[i]) / length2[i - 1];
            }
            if i + 1 < n {
                flux += (old[i + 1] - old[i]) / length2[i];
            }
            w[i] = (old[i] + diffusivity * h * flux).clamp(0.0, 1.0);
        }
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
}
