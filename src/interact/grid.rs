//! Uniform-grid neighbour search (S2 §2.4), shared by hair–hair contacts and water particles.
//!
//! Items are bucketed by the cell their point falls in. A cell's bucket is the low bits of the
//! Morton code interleaving its coordinates (a code that wraps around), in a table of one to two
//! buckets per item: the grid needs no bounds, its memory is linear in the items, and — unlike a
//! scrambling hash — neighbouring cells land in nearby buckets, so queries made in spatial order
//! (see [`NeighbourGrid::bucket_of`]) stay in cache. A query visits those of the 27 cells around a point
//! that come within a cell width of it.
//! Building is a counting sort: linear, allocation-free once the buffers have grown, and its order
//! depends only on the input, never on thread timing.
use glam::Vec3;
use rayon::prelude::*;

#[derive(Clone, Debug, Default)]
pub struct NeighbourGrid {
    cell_size: f32,
    inv_cell_size: f32,
    /// Bits of the bucket index (the table has 2^bits buckets).
    bits: u32,
    /// How many items the grid holds.
    len: usize,
    /// One bit per bucket: whether it holds any item. Items cluster (hair is a shell) and the
    /// table has one to two buckets per item, so many a query visits are empty, and these bits
    /// (a 32nd of `starts`) stay in cache where `starts` does not.
    occupied: Vec<u64>,
    /// `starts[b]..starts[b + 1]` index `items` for bucket `b`.
    starts: Vec<u32>,
    /// Item indices sorted by bucket (and by index within a bucket).
    items: Vec<u32>,
    /// Scratch: each item's bucket, and each bucket's next free slot while scattering.
    buckets: Vec<u32>,
    cursor: Vec<u32>,
}

fn cell_of(p: Vec3, inv_cell_size: f32) -> [i32; 3] {
    let c = p * inv_cell_size;
    [floor_to_i32(c.x), floor_to_i32(c.y), floor_to_i32(c.z)]
}

/// `x.floor() as i32`, inline: without SSE4.1, `f32::floor` is a call into libm, and cells are
/// computed for every item and query (libm's `floorf` was 6 % of the instructions of seed 2's
/// benchmark with contacts and 1,000 droplets).
#[inline]
fn floor_to_i32(x: f32) -> i32 {
    let t = x as i32; // truncates towards zero, saturates, NaN → 0
    t.saturating_sub((t as f32 > x) as i32)
}

/// Spreads the low 10 bits of `v` two bits apart.
fn spread_bits(v: u32) -> u32 {
    let mut v = v & 0x3ff;
    v = (v | (v << 16)) & 0x0300_00ff;
    v = (v | (v << 8)) & 0x0300_f00f;
    v = (v | (v << 4)) & 0x030c_30c3;
    (v | (v << 2)) & 0x0924_9249
}

/// The Morton code of a cell's coordinates modulo 2^bits per axis (two's complement wraps, so
/// negative cells need no offset).
fn bucket_of_cell(cell: [i32; 3], bits: u32) -> u32 {
    morton_low_bits(cell, 3 * bits)
}

/// The low `bits` (at most 30) of the Morton code of a cell's coordinates: x keeps its low
/// ⌈bits/3⌉ bits, y and z one fewer where `bits` is not a multiple of 3, so each axis wraps
/// every 2^⌊bits/3⌋ cells or more.
fn morton_low_bits(cell: [i32; 3], bits: u32) -> u32 {
    let code =
        spread_bits(cell[0] as u32) | spread_bits(cell[1] as u32) << 1 | spread_bits(cell[2] as u32) << 2;
    code & ((1u32 << bits) - 1)
}

impl NeighbourGrid {
    /// A grid whose cells are `cell_size` wide: queries find every item within `cell_size` of the
    /// query point (and some further away, which callers filter by distance).
    pub fn new(cell_size: f32) -> Self {
        assert!(cell_size > 0.0 && cell_size.is_finite(), "grid cell size must be positive");
        NeighbourGrid { cell_size, inv_cell_size: 1.0 / cell_size, ..Default::default() }
    }

    /// Empties the grid and gives it cells `cell_size` wide, keeping its buffers' memory (a
    /// fresh grid would fault in its tables' pages again at the next rebuild).
    pub fn reset(&mut self, cell_size: f32) {
        assert!(cell_size > 0.0 && cell_size.is_finite(), "grid cell size must be positive");
        (self.cell_size, self.inv_cell_size, self.bits, self.len) = (cell_size, 1.0 / cell_size, 0, 0);
        for buffer in [&mut self.starts, &mut self.items, &mut self.buckets, &mut self.cursor] {
            buffer.clear();
        }
        self.occupied.clear();
    }

    pub fn cell_size(&self) -> f32 {
        self.cell_size
    }

    pub fn cell_of(&self, p: Vec3) -> [i32; 3] {
        cell_of(p, self.inv_cell_size)
    }

    fn bucket(&self, cell: [i32; 3]) -> u32 {
        morton_low_bits(cell, self.bits)
    }

    /// The bucket holding point `p`: sorting queries by it makes neighbouring queries consecutive.
    pub fn bucket_of(&self, p: Vec3) -> u32 {
        self.bucket(self.cell_of(p))
    }

    /// Rebuilds the grid over `points` (item `i` sits at `points[i]`).
    pub fn rebuild(&mut self, points: &[Vec3]) {
        let mut items = std::mem::take(&mut self.items);
        items.resize(points.len(), 0);
        self.sort(points, &mut items, |_: &mut (), i| i as u32);
        self.items = items;
    }

    /// Rebuilds the grid over `points` like [`rebuild`](Self::rebuild), but writes
    /// `make(state, i)` for each item `i` to its place in the sorted order in `out` (as long as
    /// `points`) and keeps no [`sorted_items`](Self::sorted_items) (left empty): callers lay out
    /// their own per-item data in that order. Each `state` starts as its default and sees items
    /// in increasing `i` (callers step through their own data alongside), some skipped: the
    /// buckets are split between threads, each reading every item and writing those of its own
    /// buckets. The output is the same at any thread count.
    pub fn rebuild_into<T: Send, S: Default>(
        &mut self,
        points: &[Vec3],
        out: &mut [T],
        make: impl Fn(&mut S, usize) -> T + Sync,
    ) {
        self.items.clear();
        self.sort(points, out, make);
    }

    /// The counting sort behind both rebuilds, in parallel over ranges of buckets (whole words
    /// of `occupied`): each range counts, sums and scatters its own items, so the slots are
    /// those of a serial sort by bucket and then by index.
    fn sort<T: Send, S: Default>(
        &mut self,
        points: &[Vec3],
        out: &mut [T],
        make: impl Fn(&mut S, usize) -> T + Sync,
    ) {
        assert_eq!(out.len(), points.len(), "one output slot per item");
        // One to two buckets per item (2^k ≥ items), at most 2^30; at least 2^6, so every axis
        // wraps every 4 cells or more and a query's 27 cells never share a bucket. (A table of
        // 8^k buckets, up to 8 times the items, made the then serial rebuild half the cost of
        // cutting contact pieces at 20k × 32.)
        self.bits = ((points.len().max(64) as f64).log2().ceil() as u32).min(30);
        self.len = points.len();
        let table = 1usize << self.bits;
        let (inv, bits) = (self.inv_cell_size, self.bits);
        self.buckets.resize(points.len(), 0);
        self.buckets
            .par_iter_mut()
            .zip(points.par_iter())
            .for_each(|(b, &p)| *b = morton_low_bits(cell_of(p, inv), bits));

        self.starts.clear();
        self.starts.resize(table + 1, 0);
        self.occupied.clear();
        self.occupied.resize(table.div_ceil(64), 0);
        self.cursor.clear();
        self.cursor.resize(table, 0);
        // Every range reads all items, so more ranges than threads only add reads; below ~64k
        // items one range is cheaper than handing out work.
        let words = table / 64;
        let parts = if points.len() < 1 << 16 { 1 } else { rayon::current_num_threads().clamp(1, words) };
        let bounds: Vec<usize> = (0..=parts).map(|t| t * words / parts * 64).collect();
        let buckets = &self.buckets;
        // Per range: its buckets' counts (in `starts[b + 1]`), then their running sums.
        let mut counts = split_at_bounds(&mut self.starts[1..], &bounds);
        let occupied =
            split_at_bounds(&mut self.occupied, &bounds.iter().map(|b| b / 64).collect::<Vec<_>>());
        let totals: Vec<u32> = counts
            .par_iter_mut()
            .zip(occupied)
            .zip(bounds.par_windows(2))
            .map(|((counts, occupied), range)| {
                let lo = range[0];
                for &b in buckets {
                    let k = (b as usize).wrapping_sub(lo);
                    if k < counts.len() {
                        counts[k] += 1;
                        occupied[k / 64] |= 1 << (k % 64);
                    }
                }
                for k in 1..counts.len() {
                    counts[k] += counts[k - 1];
                }
                counts.last().copied().unwrap_or(0)
            })
            .collect();
        // Each range's first slot, added to its running sums.
        let firsts: Vec<u32> =
            totals.iter().scan(0, |sum, &t| Some(std::mem::replace(sum, *sum + t))).collect();
        counts
            .par_iter_mut()
            .zip(&firsts)
            .for_each(|(counts, &first)| counts.iter_mut().for_each(|c| *c += first));
        // Scatter in index order: each bucket's cursor walks its next free slot, within its
        // range's part of `out`.
        let starts = &self.starts;
        let slot_bounds: Vec<usize> = bounds.iter().map(|&b| starts[b] as usize).collect();
        let outs = split_at_bounds(out, &slot_bounds);
        let cursors = split_at_bounds(&mut self.cursor, &bounds);
        outs.into_par_iter().zip(cursors).zip(bounds.par_windows(2)).for_each(|((out, cursor), range)| {
            let (lo, base) = (range[0], starts[range[0]] as usize);
            cursor.copy_from_slice(&starts[lo..range[1]]);
            let mut state = S::default();
            for (i, &b) in buckets.iter().enumerate() {
                let k = (b as usize).wrapping_sub(lo);
                if k < cursor.len() {
                    out[cursor[k] as usize - base] = make(&mut state, i);
                    cursor[k] += 1;
                }
            }
        });
    }

    /// Calls `visit(i)` for every item in the cells around `p` that come within `cell_size` of it
    /// (see [`for_each_near_run`](Self::for_each_near_run)), each item at most once. Needs the
    /// item order that [`rebuild`](Self::rebuild) keeps and `rebuild_into` does not.
    pub fn for_each_near(&self, p: Vec3, mut visit: impl FnMut(u32)) {
        assert_eq!(self.items.len(), self.len, "for_each_near after rebuild_into: no item order kept");
        self.for_each_near_run(p, |run| self.items[run].iter().for_each(|&i| visit(i)));
    }

    /// Item indices sorted by cell bucket (after [`rebuild`](Self::rebuild)): [`for_each_near_run`](Self::for_each_near_run) hands
    /// out ranges of this order, so callers can keep per-item data in it and read it contiguously.
    pub fn sorted_items(&self) -> &[u32] {
        &self.items
    }

    /// Calls `visit(range)` for the runs of [`sorted_items`](Self::sorted_items) in the cells
    /// around `p` that come within `cell_size` of it, each run at most once, in a fixed order.
    pub fn for_each_near_run(&self, p: Vec3, visit: impl FnMut(std::ops::Range<usize>)) {
        self.for_each_run_within(p, self.cell_size, visit);
    }

    /// Calls `visit(range)` for the runs of [`sorted_items`](Self::sorted_items) in the cells
    /// that come within `distance` (at most `cell_size`) of `p`, each run at most once, in a
    /// fixed order. With cells twice `distance` wide, a query visits 5 of the 27 cells on
    /// average (21 with cells `distance` wide): where cells hold few items, the lookups of
    /// cells cost more than the items.
    pub fn for_each_run_within(&self, p: Vec3, distance: f32, mut visit: impl FnMut(std::ops::Range<usize>)) {
        debug_assert!(
            distance <= self.cell_size * (1.0 + 1e-6),
            "{distance} beyond a cell of {}",
            self.cell_size
        );
        if self.len == 0 {
            return;
        }
        // The 27 cells have 27 distinct buckets: the code wraps every 2^bits ≥ 4 cells per axis.
        // Of those, the cells whose nearest point lies beyond `cell_size` hold nothing a query
        // wants (about 6 of 27 on average): skipping them changes no result, only the work.
        let scaled = p * self.inv_cell_size;
        let [cx, cy, cz] = cell_of(p, self.inv_cell_size);
        // Where `p` lies in its cell, in [0, 1] cell widths.
        let within = scaled - Vec3::new(cx as f32, cy as f32, cz as f32);
        // Squared distance, in cell widths, from `p` to the slab of the neighbour at offset d.
        let gap = |d: i32, f: f32| match d {
            -1 => f * f,
            1 => (1.0 - f) * (1.0 - f),
            _ => 0.0,
        };
        // Rounding may only keep a cell, never drop one a query needs.
        let reach = {
            let cells = distance * self.inv_cell_size;
            cells * cells * (1.0 + 1e-4)
        };
        // A Morton code is the OR of its axes' spread bits: spread the 9 coordinates of the
        // 27 cells once, not 3 per cell.
        let spread = |c: i32, shift: u32| [c - 1, c, c + 1].map(|c| spread_bits(c as u32) << shift);
        let (sx, sy, sz) = (spread(cx, 0), spread(cy, 1), spread(cz, 2));
        let mask = (1u32 << self.bits) - 1;
        for (dz, &bz) in (-1..=1).zip(&sz) {
            let gz = gap(dz, within.z);
            for (dy, &by) in (-1..=1).zip(&sy) {
                let gyz = gz + gap(dy, within.y);
                if gyz > reach {
                    continue;
                }
                for (dx, &bx) in (-1..=1).zip(&sx) {
                    if gyz + gap(dx, within.x) > reach {
                        continue;
                    }
                    let b = ((bx | by | bz) & mask) as usize;
                    if self.occupied[b / 64] >> (b % 64) & 1 != 0 {
                        visit(self.starts[b] as usize..self.starts[b + 1] as usize);
                    }
                }
            }
        }
    }
}

/// `slice` cut at `bounds` (increasing, from 0 to its length or less): the parts between
/// consecutive bounds.
fn split_at_bounds<'a, T>(mut slice: &'a mut [T], bounds: &[usize]) -> Vec<&'a mut [T]> {
    let mut parts = Vec::with_capacity(bounds.len().saturating_sub(1));
    for w in bounds.windows(2) {
        let (part, rest) = std::mem::take(&mut slice).split_at_mut(w[1] - w[0]);
        parts.push(part);
        slice = rest;
    }
    parts
}

/// A coarse, conservative record of where points are: the cells holding chosen points and every
/// cell next to them are marked in a wrapping table, so [`near`](Self::near) answers for a whole
/// neighbourhood with one lookup. It may answer yes when no point is near (wrapped cells), never
/// the reverse.
#[derive(Clone, Debug, Default)]
pub struct Occupancy {
    inv_cell_size: f32,
    /// One bit per bucket: whether a cell of it holds a chosen point, and whether such a cell or
    /// a neighbour of one does. Bits, not bytes: the table (32 KB) stays in cache where bytes
    /// (256 KB) did not, and `near` is asked once per vertex of a groom.
    holds: Vec<u64>,
    near: Vec<u64>,
    /// Scratch: the cells holding a chosen point, each once (one per bucket).
    held: Vec<[i32; 3]>,
}

impl Occupancy {
    /// Wraps every 64 cells per axis: 2^18 cells.
    const BITS: u32 = 6;

    /// Marks the neighbourhoods (`cell_size` wide cells) of the points `include` selects.
    pub fn mark(&mut self, cell_size: f32, points: &[Vec3], include: impl Fn(usize) -> bool) {
        self.inv_cell_size = 1.0 / cell_size;
        let words = (1 << (3 * Self::BITS)) / 64;
        for marks in [&mut self.holds, &mut self.near] {
            marks.clear();
            marks.resize(words, 0);
        }
        self.held.clear();
        for (i, &p) in points.iter().enumerate() {
            if include(i) {
                let cell = cell_of(p, self.inv_cell_size);
                let b = bucket_of_cell(cell, Self::BITS) as usize;
                if self.holds[b / 64] >> (b % 64) & 1 == 0 {
                    self.holds[b / 64] |= 1 << (b % 64);
                    self.held.push(cell);
                }
            }
        }
        // A cell aliasing a held one (a multiple of 64 cells away on each axis) has aliasing
        // neighbours too, so one cell per bucket marks them all.
        for &[x, y, z] in &self.held {
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let b = bucket_of_cell([x + dx, y + dy, z + dz], Self::BITS) as usize;
                        self.near[b / 64] |= 1 << (b % 64);
                    }
                }
            }
        }
    }

    /// Whether a marked point may lie within `cell_size` of `p` along every axis: true whenever
    /// one does (cells whose indices differ by at most one hold them).
    #[inline]
    pub fn near(&self, p: Vec3) -> bool {
        let b = bucket_of_cell(cell_of(p, self.inv_cell_size), Self::BITS) as usize;
        self.near[b / 64] >> (b % 64) & 1 != 0
    }
}

/// How far apart the values (e.g. displacements) of nearby items can be: items are binned by
/// position into cells of a wrapping table, each cell keeps the box of its items' values, and
/// each item gets the largest distance between a value in its cell and a value in a neighbouring
/// one. So two items less than a cell width apart have values no farther apart than either's
/// bound (aliased cells only loosen the bound, never tighten it).
#[derive(Clone, Debug, Default)]
pub struct NeighbourSpread {
    /// Per cell of the table: the box (min, max) of its items' values and its spread, valid
    /// while `stamp` equals `generation`.
    low: Vec<Vec3>,
    high: Vec<Vec3>,
    spread: Vec<f32>,
    stamp: Vec<u32>,
    generation: u32,
    /// The cells holding items this time, in the order they were first met.
    occupied: Vec<[i32; 3]>,
    buckets: Vec<u32>,
}

impl NeighbourSpread {
    /// Wraps every 64 cells per axis: 2^18 cells.
    const BITS: u32 = 6;

    /// Sets `bounds[i]` to the largest distance between item `i`'s value and the value of any
    /// item in the same or a neighbouring cell (`cell_size` wide), item `i` sitting at
    /// `positions[i]` with value `values[i]`; returns the largest bound.
    pub fn bound(&mut self, cell_size: f32, positions: &[Vec3], values: &[Vec3], bounds: &mut [f32]) -> f32 {
        self.bound_items(cell_size, positions, values, None, bounds)
    }

    /// As [`Self::bound`] where every item not listed in `nonzero` has the value
    /// zero: only the listed items are binned (every cell is taken to hold a zero too), and
    /// only their bounds are set. Where few items have moved, this costs as many as have.
    pub fn bound_nonzero(
        &mut self,
        cell_size: f32,
        positions: &[Vec3],
        values: &[Vec3],
        nonzero: &[u32],
        bounds: &mut [f32],
    ) -> f32 {
        self.bound_items(cell_size, positions, values, Some(nonzero), bounds)
    }

    fn bound_items(
        &mut self,
        cell_size: f32,
        positions: &[Vec3],
        values: &[Vec3],
        listed: Option<&[u32]>,
        bounds: &mut [f32],
    ) -> f32 {
        let inv = 1.0 / cell_size;
        let table = 1 << (3 * Self::BITS);
        if self.stamp.len() != table || self.generation == u32::MAX {
            (self.low, self.high) = (vec![Vec3::ZERO; table], vec![Vec3::ZERO; table]);
            (self.spread, self.stamp, self.generation) = (vec![0.0; table], vec![0; table], 0);
        }
        self.generation += 1;
        let generation = self.generation;
        let item = |k: usize| listed.map_or(k, |l| l[k] as usize);
        let count = listed.map_or(positions.len(), <[u32]>::len);
        self.buckets.resize(count, 0);
        self.buckets
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, b)| *b = bucket_of_cell(cell_of(positions[item(k)], inv), Self::BITS));
        // Boxes are order-independent (min and max are exact), so this serial pass is too.
        // Where unlisted items are zero, every box holds zero.
        let zero = listed.is_some();
        self.occupied.clear();
        for (k, &b) in self.buckets.iter().enumerate() {
            let (b, i) = (b as usize, item(k));
            let v = values[i];
            if self.stamp[b] == generation {
                self.low[b] = self.low[b].min(v);
                self.high[b] = self.high[b].max(v);
            } else {
                let (low, high) = if zero { (v.min(Vec3::ZERO), v.max(Vec3::ZERO)) } else { (v, v) };
                (self.stamp[b], self.low[b], self.high[b]) = (generation, low, high);
                self.occupied.push(cell_of(positions[i], inv));
            }
        }
        let this = &*self;
        let spreads: Vec<(usize, f32)> = this
            .occupied
            .par_iter()
            .map(|&[x, y, z]| {
                let own = bucket_of_cell([x, y, z], Self::BITS) as usize;
                let mut largest = 0.0f32;
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            let other = bucket_of_cell([x + dx, y + dy, z + dz], Self::BITS) as usize;
                            if this.stamp[other] == generation {
                                // The farthest two points of the boxes, axis by axis.
                                let reach =
                                    (this.high[own] - this.low[other]).max(this.high[other] - this.low[own]);
                                largest = largest.max(reach.length_squared());
                            }
                        }
                    }
                }
                (own, largest.sqrt())
            })
            .collect();
        for &(b, spread) in &spreads {
            self.spread[b] = spread;
        }
        let this = &*self;
        match listed {
            None => bounds
                .par_iter_mut()
                .zip(this.buckets.par_iter())
                .for_each(|(bound, &b)| *bound = this.spread[b as usize]),
            Some(listed) => {
                for (&i, &b) in listed.iter().zip(&this.buckets) {
                    bounds[i as usize] = this.spread[b as usize];
                }
            }
        }
        spreads.iter().map(|&(_, s)| s).fold(0.0, f32::max)
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
    fn runs_within_a_distance_hold_every_item_that_near_and_skip_cells_beyond_it() {
        // Cells 1, 2 and 3 times the search distance wide: every point within it is in a run
        // visited, and with wider cells fewer cells are visited per query.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let points: Vec<Vec3> = (0..5000)
            .map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * 0.3 - Vec3::splat(0.15))
            .collect();
        let distance = 0.011;
        let mut cells_per_query = Vec::new();
        for width in [1.0, 2.0, 3.0] {
            let mut grid = NeighbourGrid::new(width * distance);
            grid.rebuild(&points);
            let mut runs = 0;
            for q in points.iter().step_by(13) {
                let mut found: Vec<u32> = Vec::new();
                grid.for_each_run_within(*q, distance, |run| {
                    runs += 1;
                    found.extend(
                        grid.sorted_items()[run]
                            .iter()
                            .filter(|&&i| points[i as usize].distance(*q) <= distance),
                    );
                });
                found.sort();
                let expected: Vec<u32> = (0..points.len() as u32)
                    .filter(|&i| points[i as usize].distance(*q) <= distance)
                    .collect();
                assert_eq!(found, expected, "cells {width} searches wide");
            }
            cells_per_query.push(runs as f64 / points.len().div_ceil(13) as f64);
        }
        assert!(cells_per_query[1] < 0.5 * cells_per_query[0], "{cells_per_query:?} cells per query");
    }

    #[test]
    fn cells_of_a_block_get_distinct_buckets_and_the_code_wraps() {
        assert_eq!(spread_bits(0b1011), 0b1_000_001_001);
        // 4096 items: 2^12 buckets, 16 cells per axis; 4097: 2^13, x wraps every 32.
        for (items, bits, period) in [(4096, 12, [16, 16, 16]), (4097, 13, [32, 16, 16])] {
            let mut grid = NeighbourGrid::new(1.0);
            grid.rebuild(&vec![Vec3::ZERO; items]);
            assert_eq!(grid.bits, bits);
            // Every cell of one period's block has its own bucket; the block wraps onto itself.
            let mut seen = std::collections::HashSet::new();
            let [px, py, pz] = period;
            for x in -px / 2..px / 2 {
                for y in -py / 2..py / 2 {
                    for z in -pz / 2..pz / 2 {
                        assert!(seen.insert(grid.bucket([x, y, z])));
                        assert_eq!(grid.bucket([x, y, z]), grid.bucket([x + px, y - py, z + 2 * pz]));
                    }
                }
            }
            assert_eq!(seen.len(), 1 << bits);
        }
    }

    #[test]
    fn occupancy_finds_every_point_within_a_cell_on_each_axis() {
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let cell = 0.02;
        // Chosen points spread over 3 m, so the 64-cell table wraps.
        let chosen: Vec<Vec3> =
            (0..40).map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * 3.0 - Vec3::ONE).collect();
        let mut occupancy = Occupancy::default();
        occupancy.mark(cell, &chosen, |_| true);
        let (mut far, mut said_far) = (0, 0);
        for _ in 0..20_000 {
            let q = chosen[rng.random_range(0..chosen.len())];
            let p = q + (Vec3::new(rng.random(), rng.random(), rng.random()) - Vec3::splat(0.5)) * 6.0 * cell;
            let nearest = chosen.iter().map(|&c| (c - p).abs().max_element()).fold(f32::MAX, f32::min);
            if nearest <= cell {
                assert!(occupancy.near(p), "{p} is within a cell of a chosen point");
            } else if nearest > 2.0 * cell {
                far += 1;
                said_far += !occupancy.near(p) as usize;
            }
        }
        // Not vacuous: far points are mostly told apart (wrapping aliases a few).
        assert!(far > 1000 && said_far * 10 > far * 9, "{said_far} of {far} far points said far");
        // Points not chosen leave no mark.
        occupancy.mark(cell, &chosen, |_| false);
        assert!(chosen.iter().all(|&c| !occupancy.near(c)));
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

    #[test]
    fn rebuilds_sort_items_by_bucket_then_index_at_any_thread_count() {
        // Enough items (over 2^16) that the buckets are split between threads.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
        let points: Vec<Vec3> =
            (0..140_000).map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * 0.5).collect();
        let mut sorted = NeighbourGrid::new(0.01);
        sorted.rebuild(&points);
        let mut expected: Vec<u32> = (0..points.len() as u32).collect();
        expected.sort_by_key(|&i| (sorted.bucket_of(points[i as usize]), i));
        assert_eq!(sorted.sorted_items(), expected.as_slice());
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut placed = NeighbourGrid::new(0.01);
            let mut out = vec![u32::MAX; points.len()];
            pool.install(|| {
                placed.rebuild_into(&points, &mut out, |last: &mut Option<usize>, i| {
                    assert!(last.is_none_or(|last| last < i), "items come in index order");
                    *last = Some(i);
                    i as u32
                })
            });
            assert_eq!(out, expected, "{threads} threads");
            assert!(placed.sorted_items().is_empty());
            // Both hand out the same runs.
            for q in points.iter().step_by(1001) {
                let (mut a, mut b) = (Vec::new(), Vec::new());
                sorted.for_each_near_run(*q, |run| a.push(run));
                placed.for_each_near_run(*q, |run| b.push(run));
                assert!(!a.is_empty());
                assert_eq!(a, b);
            }
        }
    }

    #[test]
    fn cells_floor_like_f32_floor() {
        for x in [-2.5f32, -2.0, -1.0, -0.5, -1e-30, -0.0, 0.0, 1e-30, 0.5, 1.0, 1.5, 7.999_999, 1e9, -1e9] {
            assert_eq!(floor_to_i32(x), x.floor() as i32, "{x}");
        }
        assert_eq!((floor_to_i32(3e9), floor_to_i32(-3e9), floor_to_i32(f32::NAN)), (i32::MAX, i32::MIN, 0));
    }

    #[test]
    fn spread_over_the_nonzero_values_bounds_them_against_the_zeros_too() {
        // Most items still (value zero, as asleep strands), a tenth moving: the bounds of the
        // moving ones, from them alone, must cover every item within a cell width, still or not.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(4);
        let positions: Vec<Vec3> =
            (0..3000).map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * 0.1).collect();
        let nonzero: Vec<u32> = (0..3000).filter(|i| i % 10 == 3).collect();
        let mut values = vec![Vec3::ZERO; positions.len()];
        for &i in &nonzero {
            values[i as usize] = Vec3::new(0.001, -0.0005, 0.0) + Vec3::splat(rng.random::<f32>() * 2e-4);
        }
        let cell = 0.01;
        let mut spread = NeighbourSpread::default();
        let mut bounds = vec![-1.0; positions.len()];
        let largest = spread.bound_nonzero(cell, &positions, &values, &nonzero, &mut bounds);
        for &i in &nonzero {
            let i = i as usize;
            for j in 0..positions.len() {
                if positions[i].distance(positions[j]) < cell {
                    let apart = values[i].distance(values[j]);
                    assert!(apart <= bounds[i] * (1.0 + 1e-6), "items {i}, {j}: {apart} > {}", bounds[i]);
                }
            }
            // Not loose: no farther than the largest value from zero plus the values' spread.
            assert!(bounds[i] <= largest && largest < 0.0015, "{} of {largest}", bounds[i]);
        }
        // The others are not written.
        assert!((0..positions.len()).filter(|i| i % 10 != 3).all(|i| bounds[i] == -1.0));
    }

    #[test]
    fn spread_bounds_every_pair_of_nearby_values() {
        // Displacements that vary smoothly in space plus a few outliers: the bound of every
        // item must cover its value's distance to the value of every item within a cell width.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(3);
        let positions: Vec<Vec3> =
            (0..2000).map(|_| Vec3::new(rng.random(), rng.random(), rng.random()) * 0.1).collect();
        let values: Vec<Vec3> = positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                Vec3::new(p.y * 0.02, 0.001, 0.0) + if i % 211 == 0 { Vec3::Z * 0.003 } else { Vec3::ZERO }
            })
            .collect();
        let cell = 0.01;
        let mut spread = NeighbourSpread::default();
        let mut bounds = vec![0.0; positions.len()];
        let largest = spread.bound(cell, &positions, &values, &mut bounds);
        let mut tight = 0;
        for i in 0..positions.len() {
            for j in 0..positions.len() {
                if positions[i].distance(positions[j]) < cell {
                    let apart = values[i].distance(values[j]);
                    assert!(apart <= bounds[i] * (1.0 + 1e-6), "items {i}, {j}: {apart} > {}", bounds[i]);
                    tight += (apart > 0.5 * bounds[i]) as usize;
                }
            }
            assert!(bounds[i] <= largest);
        }
        // Not vacuous: far from the outliers, bounds follow the smooth field (a few cells' worth).
        let quiet = bounds.iter().filter(|&&b| b < 0.001).count();
        assert!(quiet > positions.len() / 4 && tight > 0, "{quiet} quiet items, {tight} tight pairs");
        // Reused with other positions, nothing of the previous call remains.
        let moved: Vec<Vec3> = positions.iter().map(|p| *p + Vec3::splat(0.5)).collect();
        let still = vec![Vec3::ONE; positions.len()];
        assert_eq!(spread.bound(cell, &moved, &still, &mut bounds), 0.0);
        assert!(bounds.iter().all(|&b| b == 0.0));
    }
}
