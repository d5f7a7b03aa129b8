//! Water droplets that clump wet hair (S2 §2.2): each droplet of radius `r_min` attracts hair
//! vertices within its range `r_max` with S2-2's adhesion profile
//! `f_a(d) = 1 − ((2d − r_min − r_max)/(r_min − r_max))²` (zero at `r_min` and `r_max`, strongest
//! between), and is pulled back by the hair in turn. A droplet shared by several strands draws
//! them together: the clumps of wet hair. Droplets also wet the hair they touch.
use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::grid::NeighbourGrid;

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
    grid: Option<NeighbourGrid>,
    hair_grid: Option<NeighbourGrid>,
}

impl Droplets {
    pub fn new(positions: Vec<Vec3>) -> Self {
        let velocities = vec![Vec3::ZERO; positions.len()];
        Droplets { positions, velocities, grid: None, hair_grid: None }
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
        let grid = self.grid.get_or_insert_with(|| NeighbourGrid::new(params.r_max));
        grid.rebuild(&self.positions);
        let (grid, drops) = (&*grid, &self.positions);
        let pull_on_hair = |p: Vec3| -> (Vec3, bool) {
            let mut pull = Vec3::ZERO;
            let mut touched = false;
            grid.for_each_near(p, |j| {
                let offset = drops[j as usize] - p;
                let d = offset.length();
                if d <= params.r_max && d > 0.0 {
                    pull += offset / d * adhesion(d, params.r_min, params.r_max);
                    touched = true;
                }
            });
            (pull, touched)
        };
        match wetness {
            Some(wetness) => {
                hair_velocities.par_iter_mut().zip(wetness.par_iter_mut()).zip(hair.par_iter()).for_each(
                    |((v, w), &p)| {
                        let (pull, touched) = pull_on_hair(p);
                        *v += pull * (params.hair_pull * dt);
                        if touched {
                            *w = (*w + params.uptake * dt).min(1.0);
                        }
                    },
                )
            }
            None => hair_velocities.par_iter_mut().zip(hair.par_iter()).for_each(|(v, &p)| {
                *v += pull_on_hair(p).0 * (params.hair_pull * dt);
            }),
        }

        let hair_grid = self.hair_grid.get_or_insert_with(|| NeighbourGrid::new(params.r_max));
        hair_grid.rebuild(hair);
        let hair_grid = &*hair_grid;
        let damping = (-params.droplet_damping * dt).exp();
        self.positions.par_iter_mut().zip(self.velocities.par_iter_mut()).for_each(|(x, v)| {
            let mut pull = Vec3::ZERO;
            hair_grid.for_each_near(*x, |i| {
                let offset = hair[i as usize] - *x;
                let d = offset.length();
                if d <= params.r_max && d > 0.0 {
                    pull += offset / d * adhesion(d, params.r_min, params.r_max);
                }
            });
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
}
