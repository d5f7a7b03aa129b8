//! Hair–hair contact by S1-18's penalty: a vertex closer than `2r` to an edge of another strand
//! is pushed away along the line to the edge's closest point,
//! `Δv = α · (2r − d)/(2r) · (p − p_j)/d · Δt`.
//!
//! Candidate edges come from a neighbour grid over points sampled along every edge (at most
//! `spacing` apart), so the grid's cells only need to span the contact distance plus half the
//! spacing, however long the segments are. A vertex–edge pair is handled once, through the edge's
//! sample nearest to the closest point, so no per-query bookkeeping is needed.
use glam::Vec3;
use rayon::prelude::*;

use super::grid::NeighbourGrid;

pub struct HairContacts {
    /// α, m/s²: the push at full overlap.
    pub stiffness: f32,
    grid: NeighbourGrid,
    spacing: f32,
    /// Strand of each vertex, and whether the vertex starts an edge (is not a tip).
    strand_of: Vec<u32>,
    starts_edge: Vec<bool>,
    max_reach: f32,
    // Samples along the edges, rebuilt every step: position, edge (its first vertex), index
    // along the edge, and the edge's sample count.
    samples: Vec<Vec3>,
    sample_edge: Vec<u32>,
    sample_index: Vec<u32>,
    samples_per_edge: Vec<u32>,
}

impl HairContacts {
    /// Prepares contacts for a groom's topology; `radii` are per-vertex strand radii. Edges are
    /// sampled every `spacing` metres at most (a few hair widths to a few millimetres).
    pub fn new(strand_offsets: &[u32], radii: &[f32], spacing: f32, stiffness: f32) -> Self {
        let vertices = *strand_offsets.last().unwrap_or(&0) as usize;
        let mut strand_of = vec![0u32; vertices];
        let mut starts_edge = vec![true; vertices];
        for (s, w) in strand_offsets.windows(2).enumerate() {
            strand_of[w[0] as usize..w[1] as usize].fill(s as u32);
            if w[1] > w[0] {
                starts_edge[w[1] as usize - 1] = false;
            }
        }
        let max_radius = radii.iter().copied().fold(0.0, f32::max);
        let max_reach = 2.0 * max_radius;
        let spacing = spacing.max(max_reach).max(1e-5);
        HairContacts {
            stiffness,
            grid: NeighbourGrid::new(max_reach + 0.5 * spacing + 1e-6),
            spacing,
            strand_of,
            starts_edge,
            max_reach,
            samples: Vec::new(),
            sample_edge: Vec::new(),
            sample_index: Vec::new(),
            samples_per_edge: vec![0; vertices],
        }
    }

    fn resample(&mut self, points: &[Vec3]) {
        self.samples.clear();
        self.sample_edge.clear();
        self.sample_index.clear();
        for j in 0..points.len() {
            if !self.starts_edge[j] {
                continue;
            }
            let (a, b) = (points[j], points[j + 1]);
            let n = ((a.distance(b) / self.spacing).ceil() as u32).max(1);
            self.samples_per_edge[j] = n;
            for k in 0..n {
                self.samples.push(a.lerp(b, (k as f32 + 0.5) / n as f32));
                self.sample_edge.push(j as u32);
                self.sample_index.push(k);
            }
        }
    }

    /// Adds the penalty velocity change to every vertex touching another strand.
    pub fn apply(&mut self, points: &[Vec3], radii: &[f32], velocities: &mut [Vec3], dt: f32) {
        if self.max_reach <= 0.0 {
            return;
        }
        self.resample(points);
        self.grid.rebuild(&self.samples);
        let this = &*self;
        velocities.par_iter_mut().enumerate().for_each(|(i, v)| {
            let p = points[i];
            let strand = this.strand_of[i];
            let mut dv = Vec3::ZERO;
            let near = this.max_reach + 0.5 * this.spacing;
            this.grid.for_each_near(p, |sample| {
                // A sample further than reach + half a spacing cannot stand for a touching edge.
                if p.distance_squared(this.samples[sample as usize]) > near * near {
                    return;
                }
                let j = this.sample_edge[sample as usize] as usize;
                if this.strand_of[j] == strand {
                    return;
                }
                let (a, b) = (points[j], points[j + 1]);
                let ab = b - a;
                let t = ((p - a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
                // Handle the pair once: through the sample whose stretch holds the closest point.
                let n = this.samples_per_edge[j];
                if this.sample_index[sample as usize] != ((t * n as f32) as u32).min(n - 1) {
                    return;
                }
                let closest = a + ab * t;
                let contact = radii[i] + 0.5 * (radii[j] + radii[j + 1]);
                let offset = p - closest;
                let d = offset.length();
                if d < contact && d > 0.0 {
                    dv += offset / d * (this.stiffness * (contact - d) / contact * dt);
                }
            });
            *v += dv;
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_strands_repel_and_far_ones_do_not() {
        // Strand 0 along X at z = 0; strand 1 along Y crossing it at z = 0.5 r.
        let r = 1e-4;
        let points = vec![
            Vec3::new(-0.01, 0.0, 0.0),
            Vec3::new(0.01, 0.0, 0.0),
            Vec3::new(0.0, -0.01, 0.5 * r),
            Vec3::new(0.0, 0.0, 0.5 * r),
            Vec3::new(0.0, 0.01, 0.5 * r),
            // Strand 2 far away.
            Vec3::new(0.0, 0.0, 0.1),
            Vec3::new(0.0, 0.01, 0.1),
        ];
        let offsets = [0, 2, 5, 7];
        let radii = vec![r; points.len()];
        let mut contacts = HairContacts::new(&offsets, &radii, 0.02, 100.0);
        let mut v = vec![Vec3::ZERO; points.len()];
        let dt = 1.0 / 360.0;
        contacts.apply(&points, &radii, &mut v, dt);
        // The crossing vertex of strand 1 is pushed +Z by α (2r − 0.5r)/(2r) Δt.
        let expected = 100.0 * 0.75 * dt;
        assert!((v[3].z - expected).abs() < 1e-6 && v[3].x.abs() < 1e-9, "{:?}", v[3]);
        // Vertices far from other strands feel nothing.
        for i in [0, 1, 2, 4, 5, 6] {
            assert_eq!(v[i], Vec3::ZERO, "vertex {i}");
        }
    }
}
