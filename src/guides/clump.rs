//! Children clumped by the water that clumped their guides. The guides' simulation keeps its
//! droplets where the water left them (when a dry stage ends, or at the end); the children,
//! interpolated into the guides' pose of that moment, meet the same droplets through the same
//! adhesion and droplet motion ([`Droplets::step`], S2-2), among the guides (which hold still).
//! Each step moves every child vertex by the velocity the adhesion gives it in a step
//! (overdamped: a child has no rod to carry momentum, and chained edges with momentum would
//! whip), then chains the child's edges back to their lengths from the root (follow the leader).
//! It runs as many steps as the droplets spent among the guides (at most [`MAX_STEPS`]), or
//! until nothing moves. Children out of reach of every droplet stay as interpolated.
use glam::Vec3;
use rayon::prelude::*;

use super::deform::split_mut;
use crate::interact::water::Droplets;
use crate::style::run::DropletSnapshot;

/// The most steps a clumping runs.
pub const MAX_STEPS: u64 = 400;

/// Moves `children` (strands by `offsets`) towards the droplets of `water`, among its guides (in
/// the pose the water left them), with the styling's time step `dt`. Roots stay; edges keep their
/// lengths.
pub(crate) fn clump(children: &mut [Vec3], offsets: &[u32], water: &DropletSnapshot, dt: f32) {
    if water.droplets.is_empty() || children.is_empty() {
        return;
    }
    let lengths: Vec<f32> = (0..children.len())
        .map(|i| if i == 0 { 0.0 } else { children[i].distance(children[i - 1]) })
        .collect();
    // The hair the droplets see: the children, then the guides.
    let n = children.len();
    let mut hair = children.to_vec();
    hair.extend_from_slice(&water.hair);
    let mut pulls = vec![Vec3::ZERO; hair.len()];
    let mut droplets = Droplets::new(water.droplets.clone());
    // Settled when no vertex moves a thousandth of a droplet's radius in a step.
    let settled = 1e-3 * water.params.r_min;
    for _ in 0..water.steps.min(MAX_STEPS) {
        pulls.iter_mut().for_each(|p| *p = Vec3::ZERO);
        // No gravity: the guides' pose already holds the droplets' weight.
        droplets.step(&hair, &mut pulls, None, Vec3::ZERO, dt, &water.params);
        let mut strands = split_mut(&mut hair[..n], offsets);
        let largest = strands
            .par_iter_mut()
            .enumerate()
            .map(|(s, strand)| {
                let first = offsets[s] as usize;
                let mut largest = 0.0f32;
                for k in 1..strand.len() {
                    let edge = strand[k] + pulls[first + k] * dt - strand[k - 1];
                    let direction = edge
                        .try_normalize()
                        .unwrap_or_else(|| (strand[k] - strand[k - 1]).normalize_or_zero());
                    let chained = strand[k - 1] + direction * lengths[first + k];
                    largest = largest.max(chained.distance(strand[k]));
                    strand[k] = chained;
                }
                largest
            })
            .reduce(|| 0.0, f32::max);
        if largest < settled {
            break;
        }
    }
    children.copy_from_slice(&hair[..n]);
}
