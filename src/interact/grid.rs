//! Uniform-grid neighbour search (S2 §2.4), shared by hair–hair contacts and water particles.
//!
//! Items are bucketed by the cell their point falls in. Cells are hashed into a table sized to
//! the item count, so the grid needs no bounds and its memory is linear in the items; a query
//! visits the 27 cells around a point. Building is a counting sort: linear, allocation-free once
//! the buffers have grown, and its order depends only on the input, never on thread timing.
use glam::Vec3;
use rayon::prelude::*;

#[derive(Clone, Debug, Default)]
pub struct NeighbourGrid {
    cell_size: f32,
    inv_cell_size: f32,
    mask: u32,
    /// `starts[b]..starts[b + 1]` index `items` for bucket `b`.
    starts: Vec<u32>,
    /// Item indices sorted by bucket (and by index within a bucket).
    items: Vec<u32>,
    /// Scratch: each item's bucket, and each bucket's next free slot while scattering.
    buckets: Vec<u32>,
    cursor: Vec<u32>,
}

fn cell_of(p: Vec3, inv_cell_size: f32) -> [i32; 3] {
    let c = (p * inv_cell_size).floor();
    [c.x as i32, c.y as i32, c.z as i32]
}

/// Teschner et al.'s spatial hash: large primes per axis, XOR-combined.
fn hash_cell(cell: [i32; 3]) -> u32 {
    (cell[0] as u32).wrapping_mul(73_856_093)
        ^ (cell[1] as u32).wrapping_mul(19_349_663)
        ^ (cell[2] as u32).wrapping_mul(83_492_791)
}

impl NeighbourGrid {
    /// A grid whose cells are `cell_size` wide: queries find every item within `cell_size` of the
    /// query point (and some further away, which callers filter by distance).
    pub fn new(cell_size: f32) -> Self {
        assert!(cell_size > 0.0 && cell_size.is_finite(), "grid cell size must be positive");
        NeighbourGrid { cell_size, inv_cell_size: 1.0 / cell_size, ..Default::default() }
    }

    pub fn cell_size(&self) -> f32 {
        self.cell_size
    }

    pub fn cell_of(&self, p: Vec3) -> [i32; 3] {
        cell_of(p, self.inv_cell_size)
    }

    fn bucket(&self, cell: [i32; 3]) -> u32 {
        hash_cell(cell) & self.mask
    }

    /// Rebuilds the grid over `points` (item `i` sits at `points[i]`).
    pub fn rebuild(&mut self, points: &[Vec3]) {
        let table = (points.len().max(16) * 2).next_power_of_two();
        self.mask = table as u32 - 1;
        let (inv, mask) = (self.inv_cell_size, self.mask);
        self.buckets.resize(points.len(), 0);
        self.buckets
            .par_iter_mut()
            .zip(points.par_iter())
            .for_each(|(b, &p)| *b = hash_cell(cell_of(p, inv)) & mask);

        self.starts.clear();
        self.starts.resize(table + 1, 0);
        for &b in &self.buckets {
            self.starts[b as usize + 1] += 1;
        }
        for b in 0..table {
            self.starts[b + 1] += self.starts[b];
        }
        // Scatter in index order: each bucket's cursor walks its next free slot.
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.starts[..table]);
        self.items.resize(points.len(), 0);
        for (i, &b) in self.buckets.iter().enumerate() {
            let slot = &mut self.cursor[b as usize];
            self.items[*slot as usize] = i as u32;
            *slot += 1;
        }
    }

    /// Calls `visit(i)` for every item in the 27 cells around `p`, each item at most once.
    pub fn for_each_near(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        if self.items.is_empty() {
            return;
        }
        let [cx, cy, cz] = self.cell_of(p);
        let mut seen = [u32::MAX; 27];
        let mut count = 0;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let b = self.bucket([cx + dx, cy + dy, cz + dz]);
                    // Two neighbour cells can hash to one bucket: visit it once.
                    if seen[..count].contains(&b) {
                        continue;
                    }
                    seen[count] = b;
                    count += 1;
                    let range = self.starts[b as usize] as usize..self.starts[b as usize + 1] as usize;
                    self.items[range].iter().for_each(|&i| visit(i));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    #[test]
    fn finds_exactly_the_brute_force_neighbours() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(9);
        let points: Vec<Vec3> = (0..3000)
            .map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * 0.3 - Vec3::splat(0.15))
            .collect();
        let radius = 0.02;
        let mut grid = NeighbourGrid::new(radius);
        grid.rebuild(&points);
        for q in points.iter().step_by(37) {
            let mut found: Vec<u32> = Vec::new();
            grid.for_each_near(*q, |i| {
                if points[i as usize].distance(*q) <= radius {
                    found.push(i)
                }
            });
            found.sort();
            let expected: Vec<u32> =
                (0..points.len() as u32).filter(|&i| points[i as usize].distance(*q) <= radius).collect();
            assert_eq!(found, expected);
        }
    }

    #[test]
    fn rebuild_is_independent_of_history_and_visits_each_item_once() {
        let points: Vec<Vec3> = (0..500).map(|i| Vec3::new(i as f32 * 1e-3, 0.0, 0.0)).collect();
        let mut fresh = NeighbourGrid::new(0.01);
        fresh.rebuild(&points);
        let mut reused = NeighbourGrid::new(0.01);
        reused.rebuild(&points[..100]);
        reused.rebuild(&points);
        assert_eq!(fresh.items, reused.items);
        let mut visits = vec![0; points.len()];
        fresh.for_each_near(Vec3::new(0.25, 0.0, 0.0), |i| visits[i as usize] += 1);
        assert!(visits.iter().all(|&v| v <= 1));
        assert!(visits.iter().sum::<i32>() >= 20);
    }
}
