//! Water droplets that clump wet hair (S2 §2.2): each droplet of radius `r_min` attracts hair
//! vertices within its range `r_max` with S2-2's adhesion profile
//! `f_a(d) = 1 − ((2d − r_min − r_max)/(r_min − r_max))²` (zero at `r_min` and `r_max`, strongest
//! between), and is pulled back by the hair in turn. A droplet shared by several strands draws
//! them together: the clumps of wet hair. Droplets also wet the hair they touch.
use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::grid::{NeighbourGrid, Occupancy};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WaterParams {
    /// Droplet radius, metres.
    pub r_min: f32,
    /// Range of adhesion, metres.
    pub r_max: f32,
    /// Acceleration (m/s²) the adhesion gives hair at its peak.
    pub hair_pull: f32,
    /// Acceleration (m/s²) the hair gives a droplet at its peak, per vertex.
    pub droplet_pull: f32,
    /// Velocity damping of droplets per second (surface tension holds them in the hair).
    pub droplet_damping: f32,
    /// Wetness a vertex takes up per second inside a droplet's range.
    pub uptake: f32,
}

impl Default for WaterParams {
    fn default() -> Self {
        WaterParams {
            r_min: 0.001,
            r_max: 0.006,
            hair_pull: 30.0,
            droplet_pull: 200.0,
            droplet_damping: 20.0,
            uptake: 2.0,
        }
    }
}

/// S2-2's adhesion profile at distance `d`; negative inside `r_min` (a droplet is not a sink).
pub fn adhesion(d: f32, r_min: f32, r_max: f32) -> f32 {
    if d > r_max {
        return 0.0;
    }
    let x = (2.0 * d - r_min - r_max) / (r_min - r_max);
    1.0 - x * x
}

#[derive(Clone, Debug, Default)]
pub struct Droplets {
    pub positions: Vec<Vec3>,
    pub velocities: Vec<Vec3>,
    hair_grid: Option<NeighbourGrid>,
    /// Where the droplets are, and the hair vertices near one (the only ones binned) with their
    /// points.
    droplet_cells: Occupancy,
    near_hair: Vec<u32>,
    near_points: Vec<Vec3>,
    /// Per droplet: the hair vertices in range and their adhesion pulls (towards the droplet).
    touches: Vec<Vec<(u32, Vec3)>>,
    /// Hair vertices wetted this step (each takes up water once per step however many droplets
    /// reach it).
    wetted: Vec<bool>,
}

impl Droplets {
    pub fn new(positions: Vec<Vec3>) -> Self {
        let velocities = vec![Vec3::ZERO; positions.len()];
        Droplets { positions, velocities, ..Default::default() }
    }

    /// One step of droplet–hair adhesion: hair velocities and wetness change, then droplets
    /// move (gravity, damping, the hair's pull).
    pub fn step(
        &mut self,
        hair: &[Vec3],
        hair_velocities: &mut [Vec3],
        wetness: Option<&mut [f32]>,
        gravity: Vec3,
        dt: f32,
        params: &WaterParams,
    ) {
        if self.positions.is_empty() {
            return;
        }
        // Droplets are few and hair vertices many: each droplet finds the vertices in its range
        // (in parallel), then the pulls are applied droplet by droplet, in a fixed order. Only
        // the vertices in or next to a droplet's cell are binned (one bit looked up for each of
        // the others, which binning cost most of the step).
        self.droplet_cells.mark(params.r_max, &self.positions, |_| true);
        let cells = &self.droplet_cells;
        self.near_hair.clear();
        self.near_hair.par_extend(
            (0..hair.len() as u32)
                .into_par_iter()
                .with_min_len(4096)
                .filter(|&i| cells.near(hair[i as usize])),
        );
        self.near_points.clear();
        self.near_points.extend(self.near_hair.iter().map(|&i| hair[i as usize]));
        let hair_grid = self.hair_grid.get_or_insert_with(|| NeighbourGrid::new(params.r_max));
        hair_grid.rebuild(&self.near_points);
        let (hair_grid, near_hair) = (&*hair_grid, &self.near_hair);
        self.touches.resize_with(self.positions.len(), Vec::new);
        self.touches.par_iter_mut().zip(self.positions.par_iter()).for_each(|(touches, &x)| {
            touches.clear();
            hair_grid.for_each_near(x, |k| {
                let i = near_hair[k as usize];
                let offset = x - hair[i as usize];
                let d = offset.length();
                if d <= params.r_max && d > 0.0 {
                    touches.push((i, offset / d * adhesion(d, params.r_min, params.r_max)));
                }
            });
            // Pulls are summed in this order: by vertex, whatever the grid's bucket layout.
            touches.sort_unstable_by_key(|&(i, _)| i);
        });
        let mut wetness = wetness;
        if wetness.is_some() {
            self.wetted.clear();
            self.wetted.resize(hair.len(), false);
        }
        for touches in &self.touches {
            for &(i, pull) in touches {
                hair_velocities[i as usize] += pull * (params.hair_pull * dt);
                if let Some(w) = wetness.as_deref_mut() {
                    let i = i as usize;
                    if !self.wetted[i] {
                        self.wetted[i] = true;
                        w[i] = (w[i] + params.uptake * dt).min(1.0);
                    }
                }
            }
        }
        let damping = (-params.droplet_damping * dt).exp();
        self.positions
            .par_iter_mut()
            .zip(self.velocities.par_iter_mut())
            .zip(self.touches.par_iter())
            .for_each(|((x, v), touches)| {
                // The hair pulls the droplet back along each adhesion line.
                let pull: Vec3 = touches.iter().map(|&(_, pull)| -pull).sum();
                *v = (*v + (gravity + pull * params.droplet_pull) * dt) * damping;
                *x += *v * dt;
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adhesion_profile_is_zero_at_both_radii_and_one_between() {
        let (r0, r1) = (0.001, 0.006);
        assert!(adhesion(r0, r0, r1).abs() < 1e-6);
        assert!(adhesion(r1, r0, r1).abs() < 1e-6);
        assert!((adhesion(0.5 * (r0 + r1), r0, r1) - 1.0).abs() < 1e-6);
        assert!(adhesion(0.0005, r0, r1) < 0.0);
        assert_eq!(adhesion(0.01, r0, r1), 0.0);
    }

    #[test]
    fn a_droplet_between_two_strands_pulls_them_together_and_wets_them() {
        let hair = vec![Vec3::new(-0.003, 0.0, 0.0), Vec3::new(0.003, 0.0, 0.0), Vec3::new(0.1, 0.0, 0.0)];
        let mut v = vec![Vec3::ZERO; 3];
        let mut w = vec![0.0; 3];
        let mut drops = Droplets::new(vec![Vec3::ZERO]);
        drops.step(&hair, &mut v, Some(&mut w), Vec3::ZERO, 0.01, &WaterParams::default());
        assert!(v[0].x > 0.0 && v[1].x < 0.0 && (v[0].x + v[1].x).abs() < 1e-6);
        assert_eq!(v[2], Vec3::ZERO);
        assert!(w[0] > 0.0 && w[1] > 0.0 && w[2] == 0.0);
        // Symmetric pulls on the droplet cancel.
        assert!(drops.positions[0].length() < 1e-9);
    }

    /// Every droplet–vertex pair within range, summed as `step` promises (droplets in order, each
    /// one's vertices by index), found by trying all pairs.
    fn all_pairs_step(
        drops: &mut Droplets,
        hair: &[Vec3],
        v: &mut [Vec3],
        w: &mut [f32],
        dt: f32,
        p: &WaterParams,
    ) {
        let mut wetted = vec![false; hair.len()];
        let mut pulls_on_drops = vec![Vec3::ZERO; drops.positions.len()];
        for (d, &x) in drops.positions.iter().enumerate() {
            for (i, &h) in hair.iter().enumerate() {
                let offset = x - h;
                let distance = offset.length();
                if distance <= p.r_max && distance > 0.0 {
                    let pull = offset / distance * adhesion(distance, p.r_min, p.r_max);
                    v[i] += pull * (p.hair_pull * dt);
                    if !wetted[i] {
                        wetted[i] = true;
                        w[i] = (w[i] + p.uptake * dt).min(1.0);
                    }
                    pulls_on_drops[d] -= pull;
                }
            }
        }
        let damping = (-p.droplet_damping * dt).exp();
        for ((x, v), pull) in drops.positions.iter_mut().zip(&mut drops.velocities).zip(pulls_on_drops) {
            *v = (*v + (Vec3::new(0.0, -9.81, 0.0) + pull * p.droplet_pull) * dt) * damping;
            *x += *v * dt;
        }
    }

    #[test]
    fn droplets_find_exactly_the_vertices_an_all_pairs_search_finds_while_they_move() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
        let params = WaterParams::default();
        // A cloud of vertices over 30 cm, most far from every droplet, droplets among some of them.
        let mut hair: Vec<Vec3> =
            (0..20_000).map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * 0.3).collect();
        let droplets: Vec<Vec3> = (0..60)
            .map(|k| hair[k * 97] + Vec3::new(rng.random(), rng.random(), rng.random()) * 0.004)
            .collect();
        let (mut fast, mut slow) = (Droplets::new(droplets.clone()), Droplets::new(droplets));
        let (mut v_fast, mut v_slow) = (vec![Vec3::ZERO; hair.len()], vec![Vec3::ZERO; hair.len()]);
        let (mut w_fast, mut w_slow) = (vec![0.0; hair.len()], vec![0.0; hair.len()]);
        let gravity = Vec3::new(0.0, -9.81, 0.0);
        let mut touched = 0;
        for _ in 0..5 {
            fast.step(&hair, &mut v_fast, Some(&mut w_fast), gravity, 1.0 / 360.0, &params);
            all_pairs_step(&mut slow, &hair, &mut v_slow, &mut w_slow, 1.0 / 360.0, &params);
            assert_eq!(v_fast, v_slow);
            assert_eq!(w_fast, w_slow);
            assert_eq!(fast.positions, slow.positions);
            touched = touched.max(v_fast.iter().filter(|v| **v != Vec3::ZERO).count());
            for p in &mut hair {
                *p += Vec3::new(rng.random(), rng.random(), rng.random()) * 0.002 - 0.001;
            }
        }
        assert!(touched > 100, "the droplets reach {touched} vertices");
    }
}
