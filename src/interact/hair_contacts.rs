//! Hair–hair contact by S1-18's penalty: a vertex closer than `2r` to an edge of another strand
//! is pushed away along the line to the edge's closest point,
//! `Δv = α · (2r − d)/(2r) · (p − p_j)/d · Δt`, summed over its contacts and limited to what
//! parts the pair by its deepest overlap in a step (see `limit_push`).
//!
//! Finding the pairs is the whole cost: `2r` is a hair's width, far smaller than the segments and
//! the spacing of strands. So candidates are kept in Verlet lists: each movable vertex lists the
//! edges of other strands within `2r + skin`, and the lists are reused until the pairs that could
//! touch may have closed by `skin` since they were built, or until the set of movable vertices
//! changes. Each step only re-measures the listed pairs, exactly.
//!
//! A pair closes only by the motion of its vertex *relative* to the edge's ends (the distance
//! to a segment moves by at most the larger of the two relative displacements). So the lists'
//! age is measured by how far apart the displacements of nearby vertices are — any vertex and
//! edge that touch now lie within a segment length of each other — not by how far any vertex
//! moved: hair swinging or falling as a lock keeps its lists. The bound is kept per vertex, so
//! when a few vertices' bounds reach their skin only their lists are built again; the others keep
//! theirs, with what the motion has left of their skin (when more than an eighth must be built
//! again, all are). The skin follows the relative motion: thick while hair creeps or is held
//! (lists last many steps), thin while it springs or in dense hair (cheap rebuilds, short lists).
//! Projections apart (`project_apart`) move a few vertices far and the rest hardly: their bound
//! singles out the fast movers' edges (see `tighten_for_projections`) and their skin stays.
//!
//! Lists are built from a neighbour grid over pieces of the edges (at most `spacing` long), so
//! a query searches the contact distance and skin plus half a piece however long the segments
//! are (in cells twice that wide, see `cell_size`). A
//! vertex–edge pair is listed once, through the piece that holds the closest point. Queries run
//! in the grid's spatial order, and while most vertices are held only edges near movable ones
//! are cut into pieces.
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::grid::{NeighbourGrid, NeighbourSpread, Occupancy};
use crate::error::{Error, Result};

/// Movable vertices handled per parallel task while building lists (fixed, so lists do not
/// depend on the thread count).
const BUILD_CHUNK: usize = 2048;

/// Queries a list build makes between adding their pairs to the memory budget's count.
const BUDGET_FLUSH: usize = 64;

/// How far past its ends (in half-lengths) a piece still claims an edge's closest point, so that
/// rounding never leaves a point at the joint of two pieces unclaimed.
const PIECE_JOINT: f32 = 1e-3;

/// A piece as a query reads it, all in one record, so that a query reads one run of memory per
/// cell and the build writes one record per piece: its middle and half its length as a vector
/// (the closest point and which piece holds it need no other data), the edge's mean radius, and
/// the edge's first vertex with whether this is the edge's first or last piece. Half a cache line.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(32))]
struct Piece {
    mid: Vec3,
    radius: f32,
    half: Vec3,
    /// The edge's first vertex (below 2^30), and the `FIRST` and `LAST` flags.
    edge: u32,
}

impl Piece {
    const FIRST: u32 = 1 << 31;
    const LAST: u32 = 1 << 30;
    const EDGE: u32 = Self::LAST - 1;
}

/// A query as its search reads it: the vertex's point, its search distance (radius plus skin),
/// and the vertices of its strand (edges starting there are its own). Packed in the order the
/// queries run (the grid's), so a query reads its own data from the run of the one before
/// instead of from three per-vertex arrays (at 100,000 strands those loads miss the caches).
#[derive(Clone, Copy, Debug, Default)]
struct Query {
    point: Vec3,
    near: f32,
    own: [u32; 2],
}

/// The penalty `push` (a velocity change) a vertex feels, at most what moves it out by half its
/// deepest overlap in the next step: the other strand is pushed back too, so the pair parts by
/// at most the overlap. The penalty alone overshoots where `α·Δt²` exceeds the contact distance
/// (5× at Δt = 1/360 for a 77 µm contact): an overlapping vertex left its contact at several
/// times the speed that would end the overlap and flew on (a generated 100,000-strand groom's
/// initial overlaps launched 1 % of its strands at 0.1–0.26 m/s), and each bounce gained energy.
/// A slower push (finer steps, shallow overlaps) is the penalty itself.
fn limit_push(push: Vec3, deepest: f32, dt: f32) -> Vec3 {
    push.clamp_length_max(0.5 * deepest / dt)
}

/// How the hair moved between two uses of the lists, which sets how their staleness is bounded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Motion {
    /// Steps of a simulation: smooth over neighbourhoods, at a pace.
    Stepped,
    /// Projections apart: each vertex by its overlaps, a few far, most hardly.
    Projected,
}

/// Which edges a build cuts into pieces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PieceSet {
    /// Those that may be candidates of the given number of queried vertices (flagged in
    /// `queried`): all, or while those are few only edges near them.
    NearQueried(usize),
    /// Those with an end flagged in `queried` (fast vertices of a projection's bound).
    FastEdges,
}

pub struct HairContacts {
    /// α, m/s²: the push at full overlap.
    pub stiffness: f32,
    /// Most vertex–edge pairs the lists may hold (the memory limit's share for them).
    max_pairs: u64,
    skin: f32,
    spacing: f32,
    max_radius: f32,
    /// Where each strand's vertices start (and the last one's end), the strand of each vertex,
    /// and whether the edge a vertex starts is followed by another of the same strand.
    strand_offsets: Vec<u32>,
    strand_of: Vec<u32>,
    edge_continues: Vec<bool>,
    /// First vertex of every edge.
    edges: Vec<u32>,
    // Build scratch: each edge's first piece, the middles of the pieces in edge order, their
    // grid, and the pieces in the grid's order.
    first_piece: Vec<u32>,
    piece_mids: Vec<Vec3>,
    grid: NeighbourGrid,
    sorted_pieces: Vec<Piece>,
    /// Movable vertices to query, as (bucket << 32 | vertex), sorted, and each one's query.
    queries: Vec<u64>,
    packed: Vec<Query>,
    // Verlet lists: `list_edges[list_starts[i]..list_starts[i + 1]]` are vertex i's candidates.
    list_starts: Vec<u32>,
    list_edges: Vec<u32>,
    built_positions: Vec<Vec3>,
    built_fixed: Vec<bool>,
    /// Per movable vertex: how far beyond contact every edge missing from its list was at the
    /// last build — the skin it was listed with, less the relative motion it has outlived since.
    skin_left: Vec<f32>,
    /// Scratch: each vertex's displacement since the last build and a bound on how much its
    /// pairs have closed since then.
    displacements: Vec<Vec3>,
    closing: Vec<f32>,
    spread: NeighbourSpread,
    /// Scratch: the movable vertices and the held ones that have moved since the last build;
    /// whether each vertex is queried in this build (or, while a projection's staleness is
    /// bounded, is one of its fast movers).
    moved: Vec<u32>,
    queried: Vec<bool>,
    /// Scratch: the lists before this build, kept for the vertices it does not query.
    kept_starts: Vec<u32>,
    kept_edges: Vec<u32>,
    built: bool,
    builds: u64,
    queries_made: u64,
    /// Steps since the last build.
    lifetime: u32,
    /// Where the queried vertices are, to skip edges far from all of them.
    queried_cells: Occupancy,
}

impl HairContacts {
    /// Prepares contacts for a groom's topology; `radii` are per-vertex strand radii. Edges are cut
    /// into pieces at most `spacing` metres long to build the lists (a few millimetres suit most
    /// grooms: it trades pieces for candidates per query, never accuracy).
    pub fn new(strand_offsets: &[u32], radii: &[f32], spacing: f32, stiffness: f32) -> Self {
        let vertices = *strand_offsets.last().unwrap_or(&0) as usize;
        assert!(vertices <= Piece::EDGE as usize, "hair contacts number vertices in 30 bits");
        let mut strand_of = vec![0u32; vertices];
        let mut starts_edge = vec![true; vertices];
        let mut edge_continues = vec![true; vertices];
        for (s, w) in strand_offsets.windows(2).enumerate() {
            let range = w[0] as usize..w[1] as usize;
            strand_of[range.clone()].fill(s as u32);
            if !range.is_empty() {
                starts_edge[range.end - 1] = false;
                edge_continues[range.end - 1] = false;
            }
            if range.len() >= 2 {
                edge_continues[range.end - 2] = false;
            }
        }
        let edges = (0..vertices as u32).filter(|&j| starts_edge[j as usize]).collect();
        let max_radius = radii.iter().copied().fold(0.0, f32::max);
        let spacing = spacing.max(2.0 * max_radius).max(1e-5);
        let skin = Self::DEFAULT_SKIN;
        HairContacts {
            stiffness,
            max_pairs: crate::limits::contact_pairs_allowed(vertices as f64),
            skin,
            spacing,
            max_radius,
            strand_offsets: strand_offsets.to_vec(),
            strand_of,
            edge_continues,
            grid: NeighbourGrid::new(Self::cell_size(max_radius, skin, spacing)),
            edges,
            first_piece: Vec::new(),
            piece_mids: Vec::new(),
            sorted_pieces: Vec::new(),
            queries: Vec::new(),
            packed: Vec::new(),
            list_starts: Vec::new(),
            list_edges: Vec::new(),
            built_positions: Vec::new(),
            built_fixed: Vec::new(),
            skin_left: Vec::new(),
            displacements: Vec::new(),
            closing: Vec::new(),
            spread: NeighbourSpread::default(),
            moved: Vec::new(),
            queried: Vec::new(),
            kept_starts: Vec::new(),
            kept_edges: Vec::new(),
            built: false,
            builds: 0,
            queries_made: 0,
            lifetime: 0,
            queried_cells: Occupancy::default(),
        }
    }

    /// The most pieces an edge is cut into: a stray edge metres long must not take the memory of
    /// millions.
    const MAX_PIECES: u32 = u16::MAX as u32;

    /// Starting slack of the lists, metres. It adapts as the hair moves (see `adapt_skin`).
    pub const DEFAULT_SKIN: f32 = 0.0005;
    const MAX_SKIN: f32 = 0.002;

    /// Sets the lists' starting slack.
    pub fn with_skin(mut self, skin: f32) -> Self {
        self.set_skin(skin);
        self.built = false;
        self
    }

    fn set_skin(&mut self, skin: f32) {
        self.skin = skin.clamp(0.0, Self::MAX_SKIN);
        self.grid.reset(Self::cell_size(self.max_radius, self.skin, self.spacing));
    }

    /// Sets the skin for the next lists from the motion the last ones saw (pairs closing by
    /// `closing` over their `lifetime` steps): thick enough that lists last about eight steps at
    /// that pace (growing at most twofold at a time), but thinner than before while lists run
    /// long (dense hair: there a thicker skin costs more candidates than the rebuilds it saves)
    /// or when hair outruns the skin within a step (fast motion: lists are rebuilt every step
    /// anyway, and thinner ones build faster). Depends only on the simulation's history, so
    /// runs stay deterministic.
    fn adapt_skin(&mut self, closing: f32) {
        let listed = self.built_fixed.iter().filter(|&&f| !f).count();
        let pairs_per_query = self.list_edges.len() as f32 / listed.max(1) as f32;
        let per_step = closing / self.lifetime.max(1) as f32;
        let skin = if pairs_per_query > 4.0 || per_step > self.skin {
            0.5 * self.skin
        } else {
            (8.0 * per_step).min(2.0 * self.skin)
        };
        // Never below the contact distance: growing back needs lists that outlast a step.
        self.set_skin(skin.max(2.0 * self.max_radius));
    }

    /// How far from a vertex the middle of a piece it may be listed with lies at most.
    fn search_distance(max_radius: f32, skin: f32, spacing: f32) -> f32 {
        2.0 * max_radius + skin + 0.5 * spacing + 1e-6
    }

    /// The grid's cells are twice the search distance wide: a query then reads the few cells its
    /// search reaches (5 on average), not the 21 of cells as wide as the search. Cells hold few
    /// pieces (2 on average at 100,000 × 32), so looking cells up cost more than the pieces in
    /// them: twice as many pieces read, 22 % less time per query (1.5 and 2.5 widths did worse).
    fn cell_size(max_radius: f32, skin: f32, spacing: f32) -> f32 {
        2.0 * Self::search_distance(max_radius, skin, spacing)
    }

    /// How many times the lists have been built, wholly or in part.
    pub fn builds(&self) -> u64 {
        self.builds
    }

    /// How many vertices' lists have been built, over all builds.
    pub fn queries_made(&self) -> u64 {
        self.queries_made
    }

    /// Adds the penalty velocity change to every movable vertex (not `fixed`) touching another
    /// strand, limited by [`limit_push`]. Lists that would hold more pairs than the memory limit
    /// leaves them (strands piled at one place) are an error (exit 2), before they are allocated.
    pub fn apply(
        &mut self,
        points: &[Vec3],
        radii: &[f32],
        fixed: &[bool],
        velocities: &mut [Vec3],
        dt: f32,
    ) -> Result<()> {
        if self.max_radius <= 0.0 {
            return Ok(());
        }
        self.update_lists(points, radii, fixed, Motion::Stepped)?;
        let stiffness = self.stiffness;
        self.add_over_contacts(
            points,
            radii,
            velocities,
            |offset, d, contact| offset / d * (stiffness * (contact - d) / contact * dt),
            |push, deepest| limit_push(push, deepest, dt),
        );
        Ok(())
    }

    /// Moves every movable vertex (not `fixed`) out of the edges of other strands it lies within
    /// the contact distance of: by how deep it is, summed over them, along the line from each
    /// edge's closest point. One Jacobi projection of positions, not a force: a few of them
    /// separate strands that were placed among each other rather than simulated. Each vertex that
    /// moves is put at `placed(index, moved position)`. Returns how many vertices moved; lists
    /// over the memory limit are an error (see [`apply`](Self::apply)).
    pub fn project_apart(
        &mut self,
        points: &mut [Vec3],
        radii: &[f32],
        fixed: &[bool],
        placed: impl Fn(usize, Vec3) -> Vec3 + Sync,
    ) -> Result<usize> {
        if self.max_radius <= 0.0 {
            return Ok(0);
        }
        self.update_lists(points, radii, fixed, Motion::Projected)?;
        let mut moves = vec![Vec3::ZERO; points.len()];
        self.add_over_contacts(
            points,
            radii,
            &mut moves,
            |offset, d, contact| offset / d * (contact - d),
            |sum, _| sum,
        );
        points.par_iter_mut().zip(&moves).enumerate().for_each(|(i, (p, &m))| {
            if m != Vec3::ZERO {
                *p = placed(i, *p + m);
            }
        });
        Ok(moves.par_iter().filter(|m| **m != Vec3::ZERO).count())
    }

    /// Builds the lists, wholly or in part, where the pairs they miss may have closed by their
    /// skin since they were built (or the movable vertices changed).
    fn update_lists(&mut self, points: &[Vec3], radii: &[f32], fixed: &[bool], motion: Motion) -> Result<()> {
        if !self.built || fixed != self.built_fixed.as_slice() {
            self.build(points, radii, fixed, false)?;
        } else {
            let closing = self.closing_since_build(points, fixed);
            if motion == Motion::Projected {
                self.tighten_for_projections(points, radii, fixed);
            }
            let this = &*self;
            let stale = (0..points.len())
                .into_par_iter()
                .with_min_len(4096)
                .filter(|&i| !fixed[i] && this.closing[i] >= this.skin_left[i])
                .count();
            if stale > 0 {
                // A projection's lists are long by nature (they hold every overlap) and its
                // moves do not follow a pace: its skin stays as it started.
                if motion == Motion::Stepped {
                    self.adapt_skin(closing);
                }
                // Every build cuts the pieces near the vertices it queries: where much of the
                // hair moves, a whole build costs little more and gives every list a whole skin.
                // Where little of it may move (most strands asleep), a build costs about the same
                // whatever it queries (cutting and gathering go over every edge and vertex), so
                // it queries every movable vertex: lists renewed one at a time would each run out
                // on their own step.
                let movable = fixed.iter().filter(|&&f| !f).count();
                self.build(points, radii, fixed, stale * 8 < movable && !Self::few(movable, points.len()))?;
            }
        }
        self.lifetime += 1;
        Ok(())
    }

    /// Sums `response(offset, distance, contact)` over the edges each listed vertex touches
    /// (closer than the contact distance), in list order, and adds `finish(sum, deepest overlap)`
    /// to its `out`.
    fn add_over_contacts(
        &self,
        points: &[Vec3],
        radii: &[f32],
        out: &mut [Vec3],
        response: impl Fn(Vec3, f32, f32) -> Vec3 + Sync,
        finish: impl Fn(Vec3, f32) -> Vec3 + Sync,
    ) {
        out.par_iter_mut().enumerate().with_min_len(1024).for_each(|(i, v)| {
            let listed = self.list_starts[i] as usize..self.list_starts[i + 1] as usize;
            let (mut sum, mut deepest) = (Vec3::ZERO, 0.0f32);
            for &j in &self.list_edges[listed] {
                let Some((offset, contact)) = self.offset_from_edge(points, radii, i, j as usize) else {
                    continue;
                };
                let d = offset.length();
                if d < contact && d > 0.0 {
                    sum += response(offset, d, contact);
                    deepest = deepest.max(contact - d);
                }
            }
            if deepest > 0.0 {
                *v += finish(sum, deepest);
            }
        });
    }

    /// Vertex `i`'s offset from the closest point of edge `j`, and their contact distance; `None`
    /// beyond the edge's end where the closest point is the joint with the next edge, which that
    /// edge (also listed) counts.
    #[inline(always)]
    fn offset_from_edge(&self, points: &[Vec3], radii: &[f32], i: usize, j: usize) -> Option<(Vec3, f32)> {
        let (p, a, b) = (points[i], points[j], points[j + 1]);
        let ab = b - a;
        let t = (p - a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE);
        if t > 1.0 && self.edge_continues[j] {
            return None;
        }
        Some((p - (a + ab * t.clamp(0.0, 1.0)), radii[i] + 0.5 * (radii[j] + radii[j + 1])))
    }

    /// Marks in `touched` (one flag per strand) the strands that a vertex of a strand `from`
    /// touches now: an edge within the contact distance of it. Only vertices that were movable at
    /// the last build have lists, so held vertices touch nothing here (their strands may still be
    /// touched). Reads the lists as [`apply`](Self::apply) left them; before any, marks none.
    pub fn strands_touched(
        &self,
        points: &[Vec3],
        radii: &[f32],
        from: impl Fn(usize) -> bool + Sync,
        touched: &mut Vec<bool>,
    ) {
        touched.clear();
        touched.resize(self.strand_offsets.len().saturating_sub(1), false);
        if !self.built {
            return;
        }
        let hits: Vec<u32> = (0..points.len())
            .into_par_iter()
            .with_min_len(1024)
            .filter(|&i| from(self.strand_of[i] as usize))
            .flat_map_iter(|i| {
                let listed = self.list_starts[i] as usize..self.list_starts[i + 1] as usize;
                self.list_edges[listed].iter().copied().filter(move |&j| {
                    self.offset_from_edge(points, radii, i, j as usize)
                        .is_some_and(|(offset, contact)| offset.length_squared() < contact * contact)
                })
            })
            .collect();
        for j in hits {
            touched[self.strand_of[j as usize] as usize] = true;
        }
    }

    /// Bounds, per vertex, how much it has closed since the last build on any edge now within
    /// its contact distance plus skin (`closing`), and returns the largest bound. The distance
    /// from a point to a segment changes by at most the larger of the point's displacements
    /// relative to the segment's ends, and such an edge's ends lie within the contact distance,
    /// the skin and the edge's length of the vertex: cells that wide bound the relative
    /// displacements that matter.
    ///
    /// Only movable vertices' bounds are set. Where few vertices have moved (most strands
    /// asleep), only those are binned, every other vertex's displacement being zero.
    fn closing_since_build(&mut self, points: &[Vec3], fixed: &[bool]) -> f32 {
        let longest_edge = self.longest_edge(points);
        // Slightly wider than needed, so rounding never splits a touching pair across cells
        // that are not neighbours.
        let cell = (2.0 * self.max_radius + Self::MAX_SKIN + longest_edge) * 1.001 + 1e-6;
        self.displacements.resize(points.len(), Vec3::ZERO);
        self.displacements
            .par_iter_mut()
            .zip(points.par_iter().zip(self.built_positions.par_iter()))
            .for_each(|(d, (p, q))| *d = *p - *q);
        self.closing.resize(points.len(), 0.0);
        let displacements = &self.displacements;
        self.moved.clear();
        // Where many have moved, the list stops short (past the last count that is few): all
        // vertices are binned then. A few moved implies a few movable, so builds are whole then
        // and no list keeps a skin worked out from a bound left unset.
        self.moved.extend(
            (0..points.len() as u32)
                .filter(|&i| !fixed[i as usize] || displacements[i as usize] != Vec3::ZERO)
                .take(points.len() / 8 + 1),
        );
        if Self::few(self.moved.len(), points.len()) {
            self.spread.bound_nonzero(cell, points, &self.displacements, &self.moved, &mut self.closing)
        } else {
            self.spread.bound(cell, points, &self.displacements, &mut self.closing)
        }
    }

    /// Tightens, for projections, the bound `closing_since_build` left on the vertices whose
    /// lists it would have built again. A projection moves a few vertices by up to their
    /// deepest overlaps and most by micrometres, all over the hair: a spread over
    /// neighbourhoods an edge long (a centimetre) then reaches a fast mover almost everywhere.
    /// So a second bound, with two levels. A pair closes by at most the vertex's displacement
    /// plus the larger of the edge's ends' (a point of an edge moves no more than its ends).
    /// The fastest vertices (one in `FAST_SHARE`) are singled out: every edge without one of
    /// them at an end moved by at most `slow`, the largest displacement of the rest, so the
    /// vertex's pairs with those closed by at most its own displacement plus `slow`. The edges
    /// with a fast end are searched for directly: a vertex within its contact distance and what
    /// would be left of its skin of one of them now keeps its stale bound (its list is built
    /// again); one that is not keeps that skin left against them too.
    fn tighten_for_projections(&mut self, points: &[Vec3], radii: &[f32], fixed: &[bool]) {
        let (closing, skin_left) = (&self.closing, &self.skin_left);
        let stale: Vec<u32> = (0..points.len() as u32)
            .into_par_iter()
            .with_min_len(4096)
            .filter(|&i| !fixed[i as usize] && closing[i as usize] >= skin_left[i as usize])
            .collect();
        if stale.is_empty() {
            return;
        }
        // Lengths compare as their bits (non-negative floats), so the split is exact.
        let mut lengths: Vec<u32> = self.displacements.par_iter().map(|d| d.length().to_bits()).collect();
        let fast_count = points.len() / Self::FAST_SHARE;
        let slow = f32::from_bits(*lengths.select_nth_unstable_by(fast_count, |a, b| b.cmp(a)).1);
        let displacements = &self.displacements;
        self.queried.resize(points.len(), false);
        self.queried
            .par_iter_mut()
            .enumerate()
            .for_each(|(i, fast)| *fast = displacements[i].length() > slow);
        // The edges with a fast end, alone in the grid.
        self.cut_pieces(points, radii, PieceSet::FastEdges);
        let this = &*self;
        let tightened: Vec<Option<f32>> = stale
            .par_iter()
            .with_min_len(256)
            .map_init(
                || (Vec::new(), Vec::new()),
                |(edges, within), &i| {
                    let i = i as usize;
                    let bound = this.displacements[i].length() + slow;
                    let left = this.skin_left[i] - bound;
                    if left <= 0.0 {
                        return None;
                    }
                    let strand = this.strand_of[i] as usize;
                    let query = Query {
                        point: points[i],
                        near: radii[i] + left,
                        own: [this.strand_offsets[strand], this.strand_offsets[strand + 1]],
                    };
                    edges.clear();
                    this.candidates_of(&query, edges, within);
                    edges.is_empty().then_some(bound)
                },
            )
            .collect();
        for (&i, bound) in stale.iter().zip(tightened) {
            if let Some(bound) = bound {
                self.closing[i as usize] = bound;
            }
        }
    }

    /// One vertex in this many, the fastest since the last build, has its edges searched for
    /// directly by a projection's bound; the rest bound the others' closing by their largest
    /// displacement.
    const FAST_SHARE: usize = 256;

    /// Whether `count` of `vertices` are few enough that work over all vertices, not over
    /// them, sets the cost of a step's contacts (most strands asleep).
    fn few(count: usize, vertices: usize) -> bool {
        count * 8 < vertices
    }

    fn longest_edge(&self, points: &[Vec3]) -> f32 {
        self.edges
            .par_iter()
            .map(|&j| points[j as usize].distance_squared(points[j as usize + 1]))
            .reduce(|| 0.0, f32::max)
            .sqrt()
    }

    /// How many pieces edge `j` is cut into: at most `spacing` long, so a query searches half a
    /// piece beyond the contact distance and skin, and at most `MAX_PIECES`.
    fn pieces_of(&self, points: &[Vec3], j: usize) -> u32 {
        ((points[j].distance(points[j + 1]) / self.spacing).ceil() as u32).clamp(1, Self::MAX_PIECES)
    }

    fn piece_mid(a: Vec3, b: Vec3, index: u32, count: u32) -> Vec3 {
        a.lerp(b, (index as f32 + 0.5) / count as f32)
    }

    /// Cuts the edges of `set` into pieces and sorts them into the grid. While most vertices are
    /// not queried (held on rods, or their lists still good), only edges near a queried vertex
    /// are cut: no other can be a candidate.
    fn cut_pieces(&mut self, points: &[Vec3], radii: &[f32], set: PieceSet) {
        let longest_edge = self.longest_edge(points);
        // Edges longer than `MAX_PIECES` spacings get longer pieces, and the grid's cells grow
        // with them.
        if longest_edge > self.spacing * Self::MAX_PIECES as f32 {
            self.spacing = longest_edge / Self::MAX_PIECES as f32 * 1.001;
            self.set_skin(self.skin);
        }
        let cull = matches!(set, PieceSet::NearQueried(queried) if queried < points.len() / 2);
        let fast_only = set == PieceSet::FastEdges;
        if cull {
            // An edge can hold a candidate only if a queried vertex lies within the edge's length
            // plus the query's reach of both its ends on every axis: with cells wider than that,
            // a lookup of each end's neighbourhood tells.
            let reach = 2.0 * self.max_radius + self.skin;
            let cell = (longest_edge + reach) * 1.01 + 1e-6;
            self.queried_cells.mark(cell, points, |i| self.queried[i]);
        }
        let this = &*self;
        let counts: Vec<u32> = this
            .edges
            .par_iter()
            .map(|&j| {
                let j = j as usize;
                if cull && !(this.queried_cells.near(points[j]) && this.queried_cells.near(points[j + 1])) {
                    return 0;
                }
                if fast_only && !(this.queried[j] || this.queried[j + 1]) {
                    return 0;
                }
                this.pieces_of(points, j)
            })
            .collect();
        self.first_piece.clear();
        self.first_piece.push(0);
        for c in counts {
            self.first_piece.push(self.first_piece.last().unwrap() + c);
        }
        let total = *self.first_piece.last().unwrap() as usize;
        // The grid sorts the pieces' middles, and each piece is written to its place in the
        // grid's order as the sort meets it, in edge order.
        let mut mids = std::mem::take(&mut self.piece_mids);
        mids.resize(total, Vec3::ZERO);
        let this = &*self;
        mids.par_chunks_mut(BUILD_CHUNK).enumerate().for_each(|(c, mids)| {
            let first = c * BUILD_CHUNK;
            let mut e = this.first_piece.partition_point(|&f| f as usize <= first) - 1;
            for (k, mid) in (first..).zip(mids) {
                while this.first_piece[e + 1] as usize <= k {
                    e += 1;
                }
                let j = this.edges[e] as usize;
                let (index, count) =
                    (k as u32 - this.first_piece[e], this.first_piece[e + 1] - this.first_piece[e]);
                *mid = Self::piece_mid(points[j], points[j + 1], index, count);
            }
        });
        let mut sorted = std::mem::take(&mut self.sorted_pieces);
        sorted.resize(total, Piece::default());
        let (first_piece, edges) = (&self.first_piece, &self.edges);
        // Each thread's state is the edge of the last piece it wrote (pieces come in edge order).
        self.grid.rebuild_into(&mids, &mut sorted, |e: &mut usize, k| {
            while first_piece[*e + 1] as usize <= k {
                *e += 1;
            }
            let j = edges[*e] as usize;
            let (a, b) = (points[j], points[j + 1]);
            let (index, count) = (k as u32 - first_piece[*e], first_piece[*e + 1] - first_piece[*e]);
            let first = if index == 0 { Piece::FIRST } else { 0 };
            let last = if index + 1 == count { Piece::LAST } else { 0 };
            Piece {
                mid: mids[k],
                radius: 0.5 * (radii[j] + radii[j + 1]),
                half: (b - a) * (0.5 / count as f32),
                edge: j as u32 | first | last,
            }
        });
        (self.piece_mids, self.sorted_pieces) = (mids, sorted);
    }

    /// Builds the lists of every movable vertex, or (`partial`) only of those whose pairs may
    /// have closed by their skin left; the others keep their lists, with the skin they have left.
    fn build(&mut self, points: &[Vec3], radii: &[f32], fixed: &[bool], partial: bool) -> Result<()> {
        let n = points.len();
        self.skin_left.resize(n, 0.0);
        self.queried.resize(n, false);
        let (closing, skin_left) = (&self.closing, &self.skin_left);
        self.queried.par_iter_mut().enumerate().for_each(|(i, q)| {
            *q = !fixed[i] && (!partial || closing[i] >= skin_left[i]);
        });
        let count = self.queried.iter().filter(|&&q| q).count();
        self.cut_pieces(points, radii, PieceSet::NearQueried(count));
        // Query in the grid's spatial order, so consecutive queries read the same buckets.
        let grid = &self.grid;
        let queried = &self.queried;
        // A key per vertex (those not queried marked above any bucket), then the marked ones
        // dropped: a parallel filter would gather its output in pieces of unknown length,
        // which cost more than the sort.
        const UNQUERIED: u64 = u64::MAX;
        self.queries.clear();
        self.queries.par_extend((0..n as u32).into_par_iter().map(|i| {
            if queried[i as usize] {
                (grid.bucket_of(points[i as usize]) as u64) << 32 | i as u64
            } else {
                UNQUERIED
            }
        }));
        self.queries.retain(|&key| key != UNQUERIED);
        self.queries.par_sort_unstable();
        let (strand_of, strand_offsets, skin) = (&self.strand_of, &self.strand_offsets, self.skin);
        self.packed.clear();
        self.packed.par_extend(self.queries.par_iter().map(|&query| {
            let i = query as u32 as usize;
            let strand = strand_of[i] as usize;
            Query {
                point: points[i],
                near: radii[i] + skin,
                own: [strand_offsets[strand], strand_offsets[strand + 1]],
            }
        }));
        let this = &*self;
        // Pairs listed so far, the kept lists included: past the budget every chunk stops. The
        // sum only grows, so whether it passes the budget does not depend on the threads. Each
        // chunk adds its count every [`BUDGET_FLUSH`] queries, not at every one: both threads
        // writing one counter per query would pass its cache line to and fro.
        let listed = AtomicU64::new(if partial { self.list_edges.len() as u64 } else { 0 });
        let chunks: Vec<(Vec<u32>, Vec<u32>)> = this
            .packed
            .par_chunks(BUILD_CHUNK)
            .map(|queries| {
                let mut counts = Vec::with_capacity(queries.len());
                let mut edges = Vec::new();
                let mut within = Vec::new();
                let mut unflushed = 0u64;
                for (k, query) in queries.iter().enumerate() {
                    let before = edges.len();
                    this.candidates_of(query, &mut edges, &mut within);
                    // By edge, not grid order: contact forces are summed in list order, and
                    // the result must not depend on how the grid lays out its buckets.
                    edges[before..].sort_unstable();
                    dedup_tail(&mut edges, before);
                    let count = (edges.len() - before) as u64;
                    unflushed += count;
                    if (k + 1) % BUDGET_FLUSH == 0 || unflushed > this.max_pairs {
                        let total = listed.fetch_add(unflushed, Ordering::Relaxed) + unflushed;
                        unflushed = 0;
                        if total > this.max_pairs {
                            break;
                        }
                    }
                    counts.push(count as u32);
                }
                listed.fetch_add(unflushed, Ordering::Relaxed);
                (counts, edges)
            })
            .collect();
        if listed.into_inner() > self.max_pairs {
            return Err(self.too_dense(points));
        }
        // Gather the lists by vertex: the new ones, and the kept ones of a partial build.
        std::mem::swap(&mut self.list_starts, &mut self.kept_starts);
        std::mem::swap(&mut self.list_edges, &mut self.kept_edges);
        self.list_starts.clear();
        self.list_starts.resize(n + 1, 0);
        if partial {
            for i in 0..n {
                if !self.queried[i] {
                    self.list_starts[i + 1] = self.kept_starts[i + 1] - self.kept_starts[i];
                }
            }
        }
        for (queries, (counts, _)) in self.queries.chunks(BUILD_CHUNK).zip(&chunks) {
            for (&query, &count) in queries.iter().zip(counts) {
                self.list_starts[query as u32 as usize + 1] = count;
            }
        }
        for i in 0..n {
            self.list_starts[i + 1] += self.list_starts[i];
        }
        self.list_edges.clear();
        self.list_edges.resize(self.list_starts[n] as usize, 0);
        if partial {
            for i in (0..n).filter(|&i| !self.queried[i]) {
                let kept = self.kept_starts[i] as usize..self.kept_starts[i + 1] as usize;
                let start = self.list_starts[i] as usize;
                self.list_edges[start..start + kept.len()].copy_from_slice(&self.kept_edges[kept]);
            }
        }
        for (queries, (counts, edges)) in self.queries.chunks(BUILD_CHUNK).zip(&chunks) {
            let mut read = 0;
            for (&query, &count) in queries.iter().zip(counts) {
                let start = self.list_starts[query as u32 as usize] as usize;
                let count = count as usize;
                self.list_edges[start..start + count].copy_from_slice(&edges[read..read + count]);
                read += count;
            }
        }
        // New lists have the whole skin; kept ones what their pairs' closing left of theirs.
        let skin = self.skin;
        let (queried, closing) = (&self.queried, &self.closing);
        self.skin_left.par_iter_mut().enumerate().for_each(|(i, left)| {
            if queried[i] {
                *left = skin;
            } else if partial {
                *left -= closing[i];
            }
        });
        self.built_positions.clear();
        self.built_positions.extend_from_slice(points);
        self.built_fixed.clear();
        self.built_fixed.extend_from_slice(fixed);
        self.built = true;
        self.builds += 1;
        self.queries_made += count as u64;
        self.lifetime = 0;
        Ok(())
    }

    /// The error of lists that would hold more than `max_pairs` pairs: strands piled at one
    /// place, named by its densest queried vertex (the most pieces within its search; the first
    /// such in vertex order).
    fn too_dense(&self, points: &[Vec3]) -> Error {
        let search = Self::search_distance(self.max_radius, self.skin, self.spacing);
        let (pieces, vertex) = self
            .queries
            .par_iter()
            .map(|&query| {
                let i = query as u32 as usize;
                let mut pieces = 0;
                self.grid.for_each_run_within(points[i], search, |run| pieces += run.len());
                (pieces, std::cmp::Reverse(i))
            })
            .max()
            .map_or((0, 0), |(pieces, i)| (pieces, i.0));
        let p = points.get(vertex).copied().unwrap_or_default();
        Error::Usage(format!(
            "hair–hair contacts: strands lie too densely for the memory limit: their contact lists \
             need more than {} vertex–edge pairs (about {}), more than the limit of {} \
             (--max-memory) leaves beside the simulation; the densest place is at ({}, {}, {}) m, \
             with {pieces} pieces of hair within {:.2} mm (strands piled at one place?)",
            self.max_pairs,
            crate::limits::memory_text(self.max_pairs as f64 * crate::limits::CONTACT_BYTES_PER_PAIR),
            crate::limits::memory_text(crate::limits::max_memory() as f64),
            shortest(p.x),
            shortest(p.y),
            shortest(p.z),
            search * 1e3,
        ))
    }

    /// Appends the edges of other strands within the query's search distance plus their radius,
    /// each once, in the grid's order. `within` is scratch.
    fn candidates_of(&self, query: &Query, out: &mut Vec<u32>, within: &mut Vec<u32>) {
        let (p, near) = (query.point, query.near);
        let own = query.own[0]..query.own[1];
        // No piece reaches farther from its middle than the widest radius and half the spacing
        // (as the search distance assumes): a middle beyond that, with a margin for rounding, is
        // rejected by one comparison, before the piece's own bound below is worked out. So the
        // lists are those of that bound alone.
        let farthest = (near + self.max_radius + 0.5 * self.spacing) * (1.0 + 1e-3);
        let farthest_squared = farthest * farthest;
        // The runs of pieces to read, each one's first line asked for at once, so that their
        // cache misses overlap instead of each waiting for the one before.
        let mut runs = [(0, 0); 27];
        let mut count = 0;
        let search = Self::search_distance(self.max_radius, self.skin, self.spacing);
        self.grid.for_each_run_within(p, search, |run| {
            prefetch(&self.sorted_pieces[run.start]);
            runs[count] = (run.start, run.end);
            count += 1;
        });
        // Two passes, both without branches that depend on the data: most pieces fall beyond
        // `farthest`, and those that do not mostly fail the exact test, both at random, so
        // deciding piece by piece mispredicts (that cost three quarters of the query).
        // First the slots of the pieces within `farthest`, each written and kept by a count.
        let total = runs[..count].iter().map(|&(start, end)| end - start).sum::<usize>();
        if within.len() < total {
            within.resize(total, 0);
        }
        let mut kept = 0;
        for &(start, end) in &runs[..count] {
            for run in self.without_own(start..end, &own) {
                for (slot, piece) in run.clone().zip(&self.sorted_pieces[run]) {
                    within[kept] = slot as u32;
                    kept += ((p - piece.mid).length_squared() < farthest_squared) as usize;
                }
            }
        }
        // Then the exact test of those, every condition worked out.
        for &slot in &within[..kept] {
            let piece = &self.sorted_pieces[slot as usize];
            let d = p - piece.mid;
            let edge = piece.edge & Piece::EDGE;
            // Beyond reach of the middle: |d| ≥ reach + |half|, tested without a root as
            // d² − reach² − half² ≥ 2 reach |half|.
            let reach = near + piece.radius;
            let half_squared = piece.half.length_squared();
            let beyond = d.length_squared() - reach * reach - half_squared;
            let far = (beyond >= 0.0) & (beyond * beyond >= 4.0 * reach * reach * half_squared);
            // The closest point of the piece, `u` half-lengths from its middle. List the pair
            // through the piece that holds the edge's closest point: its `u` is within [-1, 1],
            // or beyond at the edge's ends. Neighbouring pieces may both claim a point at their
            // joint (rounding), never neither; lists drop repeats.
            let u = d.dot(piece.half) / half_squared.max(f32::MIN_POSITIVE);
            let inside = ((u >= -1.0 - PIECE_JOINT) | (piece.edge & Piece::FIRST != 0))
                & ((u <= 1.0 + PIECE_JOINT) | (piece.edge & Piece::LAST != 0));
            let touches = (d - piece.half * u.clamp(-1.0, 1.0)).length_squared() < reach * reach;
            let other = (edge < own.start) | (edge >= own.end);
            if other & !far & inside & touches {
                out.push(edge);
            }
        }
    }
}

impl HairContacts {
    /// A run of the grid's pieces without those of the strand whose edges start at `own`
    /// (never candidates), as the runs before and after them. A run holds its pieces in edge
    /// order, so a strand's are consecutive there: where its vertices lie closer together than
    /// the search reaches (a 100,000-vertex strand of 10 µm segments: 300 of its own pieces
    /// around each vertex), they are found by bisection instead of read. Short runs are read
    /// whole (the exact test drops their own pieces): bisecting them costs more than it saves.
    #[inline(always)]
    fn without_own(&self, run: Range<usize>, own: &Range<u32>) -> [Range<usize>; 2] {
        const BISECTED: usize = 32;
        if run.len() < BISECTED {
            return [run, 0..0];
        }
        let pieces = &self.sorted_pieces[run.clone()];
        let from = run.start + pieces.partition_point(|piece| piece.edge & Piece::EDGE < own.start);
        let to = run.start + pieces.partition_point(|piece| piece.edge & Piece::EDGE < own.end);
        [run.start..from, to..run.end]
    }
}

/// Asks for the cache line holding `item` ahead of its use.
#[inline(always)]
fn prefetch<T>(item: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is a hint that never faults, and SSE is part of x86_64.
    unsafe {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        _mm_prefetch::<_MM_HINT_T0>(item as *const T as *const i8);
    }
    // Elsewhere no hint: the reads that follow are the same.
    #[cfg(not(target_arch = "x86_64"))]
    let _ = item;
}

/// A coordinate or distance with the digits it needs.
fn shortest(value: f32) -> String {
    crate::validate::shortest(f64::from(value))
}

/// Drops repeats from the sorted `list[from..]`.
fn dedup_tail(list: &mut Vec<u32>, from: usize) {
    let mut kept = from;
    for k in from..list.len() {
        if kept == from || list[k] != list[kept - 1] {
            list[kept] = list[k];
            kept += 1;
        }
    }
    list.truncate(kept);
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

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
        let fixed = vec![false; points.len()];
        let mut contacts = HairContacts::new(&offsets, &radii, 0.02, 100.0);
        let mut v = vec![Vec3::ZERO; points.len()];
        // At Δt = 1/3600 the push is the penalty: the crossing vertex of strand 1 is pushed +Z
        // by α (2r − 0.5r)/(2r) Δt.
        let dt = 1.0 / 3600.0;
        contacts.apply(&points, &radii, &fixed, &mut v, dt).unwrap();
        let expected = 100.0 * 0.75 * dt;
        assert!((v[3].z - expected).abs() < 1e-7 && v[3].x.abs() < 1e-9, "{:?}", v[3]);
        // At 1/360 the penalty would carry it 3.9 overlaps in a step: it is limited to half the
        // overlap, 1.5 r, per step.
        let dt = 1.0 / 360.0;
        let mut v = vec![Vec3::ZERO; points.len()];
        contacts.apply(&points, &radii, &fixed, &mut v, dt).unwrap();
        let expected = 0.5 * 1.5 * r / dt;
        assert!((v[3].z - expected).abs() < 1e-6 && v[3].x.abs() < 1e-9, "{:?}", v[3]);
        // Vertices far from other strands feel nothing.
        for i in [0, 1, 2, 4, 5, 6] {
            assert_eq!(v[i], Vec3::ZERO, "vertex {i}");
        }
        // A held vertex is not pushed.
        let mut held = fixed.clone();
        held[3] = true;
        let mut v = vec![Vec3::ZERO; points.len()];
        contacts.apply(&points, &radii, &held, &mut v, dt).unwrap();
        assert_eq!(v[3], Vec3::ZERO);
    }

    #[test]
    fn strands_touched_names_the_strands_a_chosen_strand_touches() {
        // Strand 1 crosses strand 0 at 0.5 r, vertex on vertex (touching both ways), strand 2
        // lies 1 mm above strand 0 (within a thick skin: listed, not touching), strand 3 is far.
        let r = 1e-4;
        let points = vec![
            Vec3::new(-0.01, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.01, 0.0, 0.0),
            Vec3::new(0.0, -0.01, 0.5 * r),
            Vec3::new(0.0, 0.0, 0.5 * r),
            Vec3::new(0.0, 0.01, 0.5 * r),
            Vec3::new(-0.01, 0.0, 0.001),
            Vec3::new(0.01, 0.0, 0.001),
            Vec3::new(0.0, 0.0, 0.1),
            Vec3::new(0.0, 0.01, 0.1),
        ];
        let offsets = [0, 3, 6, 8, 10];
        let radii = vec![r; points.len()];
        let mut contacts = HairContacts::new(&offsets, &radii, 0.02, 100.0).with_skin(0.002);
        let mut touched = vec![true; 7];
        // No lists yet: nothing is known to touch.
        contacts.strands_touched(&points, &radii, |_| true, &mut touched);
        assert_eq!(touched, [false; 4]);
        let mut v = vec![Vec3::ZERO; points.len()];
        contacts.apply(&points, &radii, &vec![false; points.len()], &mut v, 1.0 / 360.0).unwrap();
        contacts.strands_touched(&points, &radii, |strand| strand == 1, &mut touched);
        assert_eq!(touched, [true, false, false, false], "strand 1 touches strand 0 only");
        contacts.strands_touched(&points, &radii, |strand| strand == 0, &mut touched);
        assert_eq!(touched, [false, true, false, false], "strand 0 touches strand 1, not 2 a skin away");
        contacts.strands_touched(&points, &radii, |strand| strand >= 2, &mut touched);
        assert_eq!(touched, [false; 4]);
        // Held vertices have no lists: a held strand 1 touches nothing, and is still touched.
        let mut held = vec![false; points.len()];
        held[3..6].fill(true);
        contacts.apply(&points, &radii, &held, &mut v, 1.0 / 360.0).unwrap();
        contacts.strands_touched(&points, &radii, |strand| strand == 1, &mut touched);
        assert_eq!(touched, [false; 4]);
        contacts.strands_touched(&points, &radii, |strand| strand == 0, &mut touched);
        assert_eq!(touched, [false, true, false, false]);
    }

    #[test]
    fn edges_of_more_pieces_than_an_edge_may_have_keep_their_contacts() {
        // A 20 m edge cut at the 0.2 mm spacing asked for would need 100,000 pieces, more than
        // `MAX_PIECES`: its pieces grow (and the grid's cells with them), and strands crossing it
        // anywhere still touch it exactly once.
        let r = 1e-4;
        // Crossings every 1.37 mm over 27 cm: at every position along a piece.
        let crossings: Vec<f32> = (0..200).map(|k| -0.1 + 0.001_37 * k as f32).collect();
        let (points, offsets) = edge_crossed_at(10.0, &crossings, r);
        let radii = vec![r; points.len()];
        let fixed = vec![false; points.len()];
        let mut contacts = HairContacts::new(&offsets, &radii, 2.0 * r, 100.0);
        let touching = matches_brute_force(&mut contacts, &offsets, &points, &radii, &fixed, 0);
        // Each crossing vertex; the long edge's ends are 10 m away.
        assert_eq!(touching, 200);
    }

    /// A one-edge strand along X from `−half_length` to `half_length`, and a 3-vertex strand along Y
    /// crossing it at each `x` of `crossings`, its middle vertex `r/2` above the edge.
    fn edge_crossed_at(half_length: f32, crossings: &[f32], r: f32) -> (Vec<Vec3>, Vec<u32>) {
        let mut points = vec![Vec3::new(-half_length, 0.0, 0.0), Vec3::new(half_length, 0.0, 0.0)];
        let mut offsets = vec![0, 2];
        for &x in crossings {
            points.extend([
                Vec3::new(x, -0.01, 0.5 * r),
                Vec3::new(x, 0.0, 0.5 * r),
                Vec3::new(x, 0.01, 0.5 * r),
            ]);
            offsets.push(points.len() as u32);
        }
        (points, offsets)
    }

    #[test]
    fn strands_crossing_at_the_joints_of_pieces_touch_the_edge_once() {
        // A 16 mm edge along X cut into 8 pieces of 2 mm; strands cross it at every joint (where
        // two pieces both hold the closest point up to rounding), at its ends and just beyond
        // them, each pushed once, as an all-pairs search finds.
        let r = 1e-4;
        let crossings: Vec<f32> =
            (0..=8).map(|k| -0.008 + 0.002 * k as f32).chain([-0.00805, 0.00805]).collect();
        let (points, offsets) = edge_crossed_at(0.008, &crossings, r);
        let radii = vec![r; points.len()];
        let fixed = vec![false; points.len()];
        let mut contacts = HairContacts::new(&offsets, &radii, 0.002, 100.0);
        let touching = matches_brute_force(&mut contacts, &offsets, &points, &radii, &fixed, 0);
        // Not vacuous: every crossing's middle vertex touches the edge.
        assert!(touching >= crossings.len(), "{touching} vertices touch");
    }

    /// The penalty every vertex feels, by testing it against every edge of every other strand,
    /// with each edge's closest point counted once per strand corner (as the lists do).
    fn brute_force(offsets: &[u32], points: &[Vec3], radii: &[f32], stiffness: f32, dt: f32) -> Vec<Vec3> {
        let strand_of = |i: usize| offsets.partition_point(|&o| o as usize <= i) - 1;
        (0..points.len())
            .map(|i| {
                let (mut dv, mut deepest) = (Vec3::ZERO, 0.0f32);
                for j in 0..points.len() - 1 {
                    let s = strand_of(j);
                    if s == strand_of(i) || j + 1 >= offsets[s + 1] as usize {
                        continue;
                    }
                    let (a, b) = (points[j], points[j + 1]);
                    let t = (points[i] - a).dot(b - a) / (b - a).length_squared();
                    if t > 1.0 && j + 2 < offsets[s + 1] as usize {
                        continue;
                    }
                    // The closest point as the lists compute it: a deep contact's direction is
                    // sensitive to rounding.
                    let offset = points[i] - (a + (b - a) * t.clamp(0.0, 1.0));
                    let contact = radii[i] + 0.5 * (radii[j] + radii[j + 1]);
                    let d = offset.length();
                    if d < contact && d > 0.0 {
                        dv += offset / d * (stiffness * (contact - d) / contact * dt);
                        deepest = deepest.max(contact - d);
                    }
                }
                dv.clamp_length_max(0.5 * deepest / dt)
            })
            .collect()
    }

    /// Applies one step of `contacts` and checks every vertex's push against [`brute_force`] (held
    /// vertices feel none); returns how many vertices touch another strand.
    fn matches_brute_force(
        contacts: &mut HairContacts,
        offsets: &[u32],
        points: &[Vec3],
        radii: &[f32],
        fixed: &[bool],
        step: usize,
    ) -> usize {
        let dt = 1.0 / 360.0;
        let mut v = vec![Vec3::ZERO; points.len()];
        contacts.apply(points, radii, fixed, &mut v, dt).unwrap();
        let expected = brute_force(offsets, points, radii, contacts.stiffness, dt);
        let mut touching = 0;
        for i in 0..points.len() {
            let want = if fixed[i] { Vec3::ZERO } else { expected[i] };
            assert!(v[i].abs_diff_eq(want, 1e-6), "step {step}, vertex {i}: {:?} vs {want:?}", v[i]);
            touching += (want != Vec3::ZERO) as usize;
        }
        touching
    }

    /// A random offset, each coordinate in [-0.5, 0.5).
    fn jitter(rng: &mut rand_pcg::Pcg64Mcg) -> Vec3 {
        Vec3::new(rng.random(), rng.random(), rng.random()) - Vec3::splat(0.5)
    }

    /// `strands` random walks of `per_strand` vertices, each starting anywhere in the box from
    /// the origin to `extent` and stepping by `step` times a [`jitter`]; and their offsets.
    /// 200 random-walk strands of 2 mm steps along a 40 × 1 × 1 cm bar, with random radii.
    fn walks_along_a_bar(rng: &mut rand_pcg::Pcg64Mcg, per_strand: usize) -> (Vec<Vec3>, Vec<u32>, Vec<f32>) {
        let (points, offsets) = random_walks(rng, 200, per_strand, Vec3::new(0.4, 0.01, 0.01), 0.002);
        let radii = (0..points.len()).map(|_| rng.random_range(1e-4..4e-4)).collect();
        (points, offsets, radii)
    }
    fn random_walks(
        rng: &mut rand_pcg::Pcg64Mcg,
        strands: usize,
        per_strand: usize,
        extent: Vec3,
        step: f32,
    ) -> (Vec<Vec3>, Vec<u32>) {
        let (mut points, mut offsets) = (Vec::new(), vec![0u32]);
        for _ in 0..strands {
            let mut p = Vec3::new(rng.random(), rng.random(), rng.random()) * extent;
            for _ in 0..per_strand {
                points.push(p);
                p += jitter(rng) * step;
            }
            offsets.push(points.len() as u32);
        }
        (points, offsets)
    }

    #[test]
    fn crossing_strands_part_by_their_overlap_and_do_not_fly_apart() {
        // Two hairs of 38.5 µm radius (a 77 µm contact) crossing at right angles, their axes
        // `gap` apart, held at their ends; the middle vertices move by the pushes alone, as a
        // symplectic step moves them, at Δt = 1/360 and the recipes' α = 50 m/s². The pair must
        // part by at most its overlap in a step and leave no faster than that: the bare penalty
        // gives each 0.12 m/s a step and the pair flies apart at 0.24 m/s, 0.67 mm a step.
        let (dt, radius, stiffness) = (1.0 / 360.0, 38.5e-6, 50.0);
        let contact = 2.0 * radius;
        for gap in [5e-6, 20e-6, 40e-6, 70e-6] {
            let mut points = vec![
                Vec3::new(-1e-3, 0.0, 0.0),
                Vec3::ZERO,
                Vec3::new(1e-3, 0.0, 0.0),
                Vec3::new(0.0, -1e-3, gap),
                Vec3::new(0.0, 0.0, gap),
                Vec3::new(0.0, 1e-3, gap),
            ];
            let (offsets, radii) = ([0, 3, 6], vec![radius; 6]);
            let fixed = [true, false, true, true, false, true];
            let mut contacts = HairContacts::new(&offsets, &radii, 0.002, stiffness);
            let mut velocities = vec![Vec3::ZERO; 6];
            let mut gaps = Vec::new();
            for _ in 0..20 {
                contacts.apply(&points, &radii, &fixed, &mut velocities, dt).unwrap();
                points.iter_mut().zip(&velocities).for_each(|(p, v)| *p += *v * dt);
                gaps.push(points[4].z - points[1].z);
            }
            let overlap = contact - gap;
            let speed = (velocities[4] - velocities[1]).z;
            eprintln!("gap {gap:e}: after one step {:e}, leaving at {speed:.4} m/s", gaps[0]);
            assert!(gaps[0] <= contact * 1.0001, "gap {gap:e}: one step parted the pair to {:e} m", gaps[0]);
            // (A little faster where the bent edges still graze the vertices after a step.)
            assert!(speed > 0.0 && speed <= overlap / dt * 1.01, "gap {gap:e}: leaving at {speed} m/s");
        }
    }

    #[test]
    fn reused_lists_find_exactly_the_contacts_of_a_full_search_while_strands_move() {
        // 200 random-walk strands crammed into a 2 cm box, thick enough to touch often; they
        // drift each step by up to a quarter of the starting skin, so lists are reused and rebuilt.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(4);
        let (mut points, offsets) = random_walks(&mut rng, 200, 8, Vec3::splat(0.02), 0.006);
        let radii: Vec<f32> = (0..points.len()).map(|_| rng.random_range(1e-4..4e-4)).collect();
        let fixed: Vec<bool> = (0..points.len()).map(|i| i % 11 == 0).collect();
        let mut contacts = HairContacts::new(&offsets, &radii, 0.002, 50.0);
        let mut touching = 0;
        for step in 0..20 {
            touching += matches_brute_force(&mut contacts, &offsets, &points, &radii, &fixed, step);
            for p in points.iter_mut() {
                *p += jitter(&mut rng) * (0.3 * HairContacts::DEFAULT_SKIN);
            }
        }
        let builds = contacts.builds();
        assert!(touching > 100, "too few contacts to test: {touching}");
        eprintln!("{touching} contacts, lists built {builds} times in 20 steps");
        assert!(builds > 1 && builds < 20, "lists built {builds} times in 20 steps");
    }

    #[test]
    fn pushes_equal_an_all_pairs_search_bit_for_bit_at_any_thread_count() {
        // 300 thick random-walk strands in a 20 × 1.5 × 1.5 cm box: the grid's table wraps along
        // x every few centimetres, so buckets mix far cells. Lists are summed by edge, as the
        // all-pairs search sums, so each vertex's push must equal it exactly: a pair missed or
        // listed twice shows; and every thread count must give the same bits. After three steps
        // of drift only the hair that strayed below x = 0 moves, fast, so lists are rebuilt in
        // part, cutting only the edges whose two ends lie near a queried vertex; a few long
        // strands (edges up to 1 cm, which set the cut's cells) cross the box.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(16);
        let extent = Vec3::new(0.2, 0.015, 0.015);
        let (mut start, mut offsets) = random_walks(&mut rng, 300, 10, extent, 0.005);
        let (long, long_offsets) = random_walks(&mut rng, 20, 4, extent, 0.01);
        offsets.extend(long_offsets[1..].iter().map(|&o| o + start.len() as u32));
        start.extend(long);
        let radii: Vec<f32> = (0..start.len()).map(|_| rng.random_range(2e-4..6e-4)).collect();
        let fixed: Vec<bool> = (0..start.len()).map(|i| i % 10 == 0).collect();
        let drift: Vec<Vec<Vec3>> = (0..6)
            .map(|step| {
                (0..start.len())
                    .map(|i| match step {
                        0..3 => jitter(&mut rng) * HairContacts::DEFAULT_SKIN,
                        _ if start[i].x < 0.0 => jitter(&mut rng) * (4.0 * HairContacts::DEFAULT_SKIN),
                        _ => Vec3::ZERO,
                    })
                    .collect()
            })
            .collect();
        let dt = 1.0 / 360.0;
        // Each step's points, and the pushes at them.
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut contacts = HairContacts::new(&offsets, &radii, 0.001, 50.0);
                let mut points = start.clone();
                let mut steps = Vec::new();
                for moves in &drift {
                    let mut v = vec![Vec3::ZERO; points.len()];
                    contacts.apply(&points, &radii, &fixed, &mut v, dt).unwrap();
                    steps.push((points.clone(), v));
                    points.iter_mut().zip(moves).for_each(|(p, m)| *p += *m);
                }
                (steps, contacts.builds(), contacts.queries_made())
            })
        };
        let bits = |v: &[Vec3]| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        let (one, builds, queries) = run(1);
        let movable = fixed.iter().filter(|&&f| !f).count() as u64;
        eprintln!("{builds} builds, {queries} queries of {movable} movable vertices");
        assert!(queries < builds * movable, "no list was rebuilt in part");
        let mut touching = 0;
        for (step, (points, pushes)) in one.iter().enumerate() {
            let mut expected = brute_force(&offsets, points, &radii, 50.0, dt);
            expected.iter_mut().zip(&fixed).filter(|(_, &f)| f).for_each(|(e, _)| *e = Vec3::ZERO);
            assert_eq!(bits(pushes), bits(&expected), "step {step}");
            touching += expected.iter().filter(|&&e| e != Vec3::ZERO).count();
        }
        assert!(touching > 300, "too few contacts to test: {touching}");
        for threads in [2, 3] {
            let (other, _, _) = run(threads);
            assert!(
                one.iter().zip(&other).all(|(a, b)| bits(&a.1) == bits(&b.1)),
                "{threads} threads differ"
            );
        }
    }

    #[test]
    fn with_most_strands_held_every_build_renews_every_movable_list() {
        // 200 random-walk strands in a 40 × 1 × 1 cm box, all held but 12 (as in a settle's
        // tail, most asleep). One of the 12 jitters fast, the others slowly: each build must
        // query all their vertices, so that the lists run out together rather than one strand's
        // at a step, and every step still finds exactly the contacts of a full search.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(11);
        let per_strand = 8;
        let (mut points, offsets, radii) = walks_along_a_bar(&mut rng, per_strand);
        let fixed: Vec<bool> =
            (0..points.len()).map(|i| i / per_strand >= 12 || i % per_strand == 0).collect();
        let movable = fixed.iter().filter(|&&f| !f).count() as u64;
        let mut contacts = HairContacts::new(&offsets, &radii, 0.002, 50.0);
        let mut touching = 0;
        let steps = 40;
        for step in 0..steps {
            touching += matches_brute_force(&mut contacts, &offsets, &points, &radii, &fixed, step);
            for (i, p) in points.iter_mut().enumerate().filter(|&(i, _)| !fixed[i]) {
                let pace = if i < per_strand { 0.5 } else { 0.02 };
                *p += jitter(&mut rng) * (pace * HairContacts::DEFAULT_SKIN);
            }
        }
        let (builds, queries) = (contacts.builds(), contacts.queries_made());
        eprintln!("{touching} contacts; {builds} builds queried {queries} of {movable} vertices");
        assert!(touching > 20, "too few contacts to test: {touching}");
        assert!((2..steps as u64).contains(&builds), "{builds} builds in {steps} steps");
        assert_eq!(queries, builds * movable, "a build left some movable vertices' lists as they were");
    }

    #[test]
    fn lists_follow_relative_motion_only_and_rebuild_where_hair_moves() {
        // 200 random-walk strands along a 40 × 1 × 1 cm box. The whole groom moves as one by
        // 3 mm a step (six times the skin): no pair closes, so the lists must survive it. Then
        // the strands rooted in the first 5 mm also jitter, and only the vertices near them may
        // be queried again, while every step still finds exactly the contacts of a full search.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(7);
        let per_strand = 8;
        let (mut points, offsets, radii) = walks_along_a_bar(&mut rng, per_strand);
        let fixed: Vec<bool> = (0..points.len()).map(|i| i % 13 == 0).collect();
        let movable = fixed.iter().filter(|&&f| !f).count() as u64;
        let jittering: Vec<bool> =
            (0..points.len()).map(|i| points[offsets[i / per_strand] as usize].x < 0.005).collect();
        let mut contacts = HairContacts::new(&offsets, &radii, 0.002, 50.0);
        let mut touching = 0;
        for step in 0..20 {
            touching += matches_brute_force(&mut contacts, &offsets, &points, &radii, &fixed, step);
            if step < 8 {
                assert_eq!(contacts.builds(), 1, "a rigid motion rebuilt the lists at step {step}");
            }
            for (p, &jitters) in points.iter_mut().zip(&jittering) {
                *p += Vec3::new(0.003, -0.001, 0.0);
                if step >= 8 && jitters {
                    *p += jitter(&mut rng) * (0.5 * HairContacts::DEFAULT_SKIN);
                }
            }
        }
        let (builds, queries) = (contacts.builds(), contacts.queries_made());
        eprintln!("{touching} contacts; {builds} builds queried {queries} of {movable} vertices each time");
        assert!(touching > 100, "too few contacts to test: {touching}");
        assert!(builds > 2, "the jitter never rebuilt the lists ({builds} builds)");
        assert!(
            queries < movable + (builds - 1) * movable / 2,
            "rebuilt far from the jitter: {queries} queries"
        );
    }

    #[test]
    fn lists_outlive_hair_swaying_from_held_roots_and_stay_exact() {
        // 300 random-walk strands of edges about a centimetre long above a "scalp" at y = 0 in
        // a 3 × 2 × 3 cm box, thick enough to touch often. Each step every vertex sways along x by an amount
        // growing with its height (held ones, below 2 mm, not at all), by 0.02 to 1.5 skins at
        // the top (a smooth field, as hair swinging or falling from its roots): pairs close only
        // by the field's change across a contact, far less than across an edge. Every step must
        // find exactly the contacts of an all-pairs search, and lists must last several steps.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(21);
        let extent = Vec3::new(0.03, 0.02, 0.03);
        let (mut points, offsets) = random_walks(&mut rng, 300, 6, extent, 0.02);
        let radii: Vec<f32> = (0..points.len()).map(|_| rng.random_range(1e-4..3e-4)).collect();
        let fixed: Vec<bool> = points.iter().map(|p| p.y < 0.002).collect();
        let mut contacts = HairContacts::new(&offsets, &radii, 0.002, 50.0);
        let (steps, mut touching) = (40, 0);
        for step in 0..steps {
            touching += matches_brute_force(&mut contacts, &offsets, &points, &radii, &fixed, step);
            let top = [0.02, 0.1, 0.3, 1.5][step % 4] * HairContacts::DEFAULT_SKIN;
            for (p, _) in points.iter_mut().zip(&fixed).filter(|(_, &f)| !f) {
                p.x += top * (p.y / extent.y).clamp(0.0, 1.0);
            }
        }
        let (builds, queries) = (contacts.builds(), contacts.queries_made());
        let movable = fixed.iter().filter(|&&f| !f).count() as u64;
        eprintln!("{touching} contacts, lists built {builds} times in {steps} steps, {queries} queries of {movable} movable vertices");
        assert!(touching > 200, "too few contacts to test: {touching}");
        assert!(builds <= steps as u64 / 4, "lists built {builds} times in {steps} steps");
    }

    #[test]
    fn projections_apart_keep_their_lists_where_a_few_vertices_move_far_and_stay_exact() {
        // 2,400 random-walk strands of 5 mm steps packed along a 24 × 0.5 × 0.5 cm bar, thick
        // enough that an eighth of the vertices overlap, moved apart by eight projections (a fifth
        // of the vertices held, as roots). The first moves a few vertices by more than half the
        // skin and most by micrometres: a spread of displacements over neighbourhoods an edge
        // long reaches a fast mover almost everywhere, so each later pass rebuilt most lists.
        // Every pass must move every vertex exactly as lists built afresh for it do (bit for
        // bit; those match an all-pairs search, see above), at any thread count, while at most
        // one of the seven later passes builds every list again (the spread's bound made two,
        // 2.0 builds' worth of queries in all, where the two-level bound makes 1.0): the fast
        // movers are one in 256, and each lies within a contact and a skin of a few dozen
        // other vertices at most, so the partial builds are small, until the slow movers'
        // displacements have spent the kept lists' skin.
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(44);
        let (start, offsets) = random_walks(&mut rng, 2400, 8, Vec3::new(0.24, 0.005, 0.005), 0.005);
        let radii: Vec<f32> = (0..start.len()).map(|_| rng.random_range(5e-5..1.2e-4)).collect();
        let fixed: Vec<bool> = (0..start.len()).map(|i| i % 5 == 0).collect();
        let movable = fixed.iter().filter(|&&f| !f).count() as u64;
        let passes = 8;
        let project = |contacts: &mut HairContacts, points: &mut Vec<Vec3>| {
            contacts.project_apart(points, &radii, &fixed, |_, p| p).unwrap()
        };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut contacts = HairContacts::new(&offsets, &radii, 0.002, 50.0);
                let mut points = start.clone();
                let (mut each, mut queried) = (vec![points.clone()], Vec::new());
                for _ in 0..passes {
                    let before = contacts.queries_made();
                    project(&mut contacts, &mut points);
                    queried.push(contacts.queries_made() - before);
                    each.push(points.clone());
                }
                (each, contacts.builds(), queried)
            })
        };
        let bits = |v: &[Vec3]| v.iter().map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        let (one, builds, queried) = run(1);
        let (mut overlapping, mut farthest) = (Vec::new(), 0.0f32);
        for (pass, step) in one.windows(2).enumerate() {
            let mut fresh = step[0].clone();
            overlapping.push(project(&mut HairContacts::new(&offsets, &radii, 0.002, 50.0), &mut fresh));
            assert_eq!(bits(&step[1]), bits(&fresh), "pass {pass}");
            if pass == 0 {
                farthest = step[0].iter().zip(&step[1]).map(|(a, b)| a.distance(*b)).fold(0.0, f32::max);
            }
        }
        eprintln!(
            "of {movable} movable vertices {overlapping:?} overlapped in each pass, the farthest moved \
             {:.0} µm in the first; {builds} builds queried {queried:?}",
            farthest * 1e6
        );
        let whole = queried[1..].iter().filter(|&&q| q == movable).count();
        assert!(overlapping[0] as u64 * 8 > movable, "too few overlaps to test: {overlapping:?}");
        assert!(overlapping[passes - 1] > 0, "the passes ran out of overlaps: {overlapping:?}");
        assert!(
            farthest > 0.5 * HairContacts::DEFAULT_SKIN,
            "no vertex moved past half the skin: {farthest}"
        );
        assert!(builds > 1, "no pass rebuilt a list: the fast movers' search is untested");
        assert!(whole <= 1, "{whole} of the later passes built every list again: {queried:?}");
        assert!(queried[1..].iter().sum::<u64>() < movable * 3 / 2, "the later passes queried {queried:?}");
        for threads in [2, 3] {
            assert!(
                run(threads).0.iter().zip(&one).all(|(a, b)| bits(a) == bits(b)),
                "{threads} threads differ"
            );
        }
    }
}
