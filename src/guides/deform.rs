//! Moving children with their guides. Each guide carries a rotation-minimising (parallel
//! transport) frame along its length, before and after styling; at each fraction of length the
//! change of frame is the guide's local rotation. A child's edges turn by its guides' rotations
//! at the same fraction and are chained from its root, so a child beside a curl curls with it
//! at the same curvature — instead of averaging world positions of guides at different phases,
//! which flattens curls, or carrying offsets from the guide, which swing out into loops when
//! the child's shape differs from the guide's.
use glam::{Quat, Vec2, Vec3};
use rayon::prelude::*;

use super::binding::Binding;

/// Guide curves with what sampling needs: arc-length fractions of the vertices, and a frame
/// per edge placed at the edge's middle (the last vertex repeats the last edge's).
pub struct Curves {
    points: Vec<Vec3>,
    offsets: Vec<u32>,
    fractions: Vec<f32>,
    /// Fraction of length at each edge's middle (1 for the last vertex).
    middles: Vec<f32>,
    frames: Vec<Quat>,
    /// Per vertex, how the strand turns there per unit length ([`strand_bends`]).
    bends: Vec<Vec3>,
}

impl Curves {
    /// Frames are parallel-transported from the root. `root_frames` gives each guide's frame at
    /// its root: `None` derives one from the first edge (for the curves before styling); after
    /// styling pass [`Curves::carried_root_frames`] of the unstyled curves so both agree.
    pub fn new(points: Vec<Vec3>, offsets: Vec<u32>, root_frames: Option<&[Quat]>) -> Curves {
        let strands = offsets.len() - 1;
        let mut fractions = vec![0.0; points.len()];
        let mut frames = vec![Quat::IDENTITY; points.len()];
        // Disjoint per-strand slices, filled in parallel.
        let mut frac_parts = split_mut(&mut fractions, &offsets);
        let mut bends = vec![Vec3::ZERO; points.len()];
        let mut frame_parts = split_mut(&mut frames, &offsets);
        let mut bend_parts = split_mut(&mut bends, &offsets);
        frac_parts
            .par_iter_mut()
            .zip(frame_parts.par_iter_mut())
            .zip(bend_parts.par_iter_mut())
            .enumerate()
            .for_each(|(s, ((fr, fm), bd))| {
                let p = &points[offsets[s] as usize..offsets[s + 1] as usize];
                strand_fractions(p, fr);
                let root = root_frames.map_or_else(|| initial_frame(p[1] - p[0]), |r| r[s]);
                strand_frames(p, root, fm);
                strand_bends(p, fm, bd);
            });
        debug_assert_eq!(frac_parts.len(), strands);
        let middles = (0..points.len())
            .map(|i| match offsets.binary_search(&(i as u32 + 1)) {
                Ok(_) => 1.0, // the strand's last vertex
                Err(_) => 0.5 * (fractions[i] + fractions[i + 1]),
            })
            .collect();
        Curves { points, offsets, fractions, middles, frames, bends }
    }

    /// Each guide's root frame after its first edge turned from `self`'s to `posed`'s by the
    /// smallest rotation (roots are pinned; a twist about the first edge is not tracked).
    pub fn carried_root_frames(&self, posed_points: &[Vec3]) -> Vec<Quat> {
        (0..self.offsets.len() - 1)
            .map(|s| {
                let i = self.offsets[s] as usize;
                let before = (self.points[i + 1] - self.points[i]).normalize();
                let after = (posed_points[i + 1] - posed_points[i]).normalize();
                (Quat::from_rotation_arc(before, after) * self.frames[i]).normalize()
            })
            .collect()
    }

    fn range(&self, guide: usize) -> std::ops::Range<usize> {
        self.offsets[guide] as usize..self.offsets[guide + 1] as usize
    }

    /// Index of the vertex that starts the span containing fraction `u`, and where in it `u` is.
    fn locate(&self, guide: usize, u: f32) -> (usize, f32) {
        let range = self.range(guide);
        let f = &self.fractions[range.clone()];
        let j = f.partition_point(|&x| x <= u).clamp(1, f.len() - 1);
        let span = f[j] - f[j - 1];
        let t = if span > 0.0 { ((u - f[j - 1]) / span).clamp(0.0, 1.0) } else { 0.0 };
        (range.start + j - 1, t)
    }

    /// The guide's frame at fraction `u` of its length, between the frames of the edges whose
    /// middles surround `u` (exactly an edge's frame at its middle).
    fn frame(&self, guide: usize, u: f32) -> Quat {
        let range = self.range(guide);
        let m = &self.middles[range.clone()];
        let j = m.partition_point(|&x| x <= u).clamp(1, m.len() - 1);
        let span = m[j] - m[j - 1];
        let t = if span > 0.0 { ((u - m[j - 1]) / span).clamp(0.0, 1.0) } else { 0.0 };
        self.frames[range.start + j - 1].slerp(self.frames[range.start + j], t)
    }

    /// The guide's frame at its root.
    fn root_frame(&self, guide: usize) -> Quat {
        self.frames[self.offsets[guide] as usize]
    }

    /// The guide's root (pinned: the same in every pose).
    fn root(&self, guide: usize) -> Vec3 {
        self.points[self.offsets[guide] as usize]
    }

    /// The guide's bend per unit length at fraction `u`, in its frame there.
    fn bend(&self, guide: usize, u: f32) -> Vec3 {
        let (i, t) = self.locate(guide, u);
        self.bends[i].lerp(self.bends[i + 1], t)
    }

    /// A per-vertex scalar of the guide (`values` indexed like the points) at fraction `u`.
    fn sample_scalar(&self, values: &[f32], components: usize, guide: usize, u: f32, out: &mut [f32]) {
        let (i, t) = self.locate(guide, u);
        for (c, o) in out.iter_mut().enumerate().take(components) {
            *o = values[i * components + c] * (1.0 - t) + values[(i + 1) * components + c] * t;
        }
    }
}

/// Children to move: their points before styling, strand offsets and bindings.
pub struct Children<'a> {
    pub points: &'a [Vec3],
    pub offsets: &'a [u32],
    pub bindings: &'a [Binding],
}

impl Children<'_> {
    fn strands(&self) -> usize {
        self.bindings.len()
    }

    fn fractions(&self, child: usize) -> Vec<f32> {
        let p = &self.points[self.offsets[child] as usize..self.offsets[child + 1] as usize];
        let mut f = vec![0.0; p.len()];
        strand_fractions(p, &mut f);
        f
    }
}

/// The children's points after their guides moved from `before` to `after`. A child's first
/// edge turns by its guides' rotations at the root (weighted). Along the rest of it the child
/// bends as its guides do after, less the part of their bend before that `after` kept, plus
/// that kept part of its own bend before ([`kept_fraction`]): bends are read in each guide's
/// transport frame, turned about the child's first edge into the child's frame, and chained from
/// the child's root with the child's edge lengths. So a child curls with the curvature and twist
/// of its guides' curls whatever the phase of its own input curl (a perm keeps only part of it),
/// and keeps the part of its own shape the style kept.
pub fn deform(children: &Children, before: &Curves, after: &Curves) -> Vec<Vec3> {
    let kept = kept_fraction(children.bindings, before, after);
    let mut out = vec![Vec3::ZERO; children.points.len()];
    let mut parts = split_mut(&mut out, children.offsets);
    parts.par_iter_mut().enumerate().for_each(|(c, out)| {
        let start = children.offsets[c] as usize;
        let rest = &children.points[start..start + out.len()];
        out[0] = rest[0];
        if out.len() < 2 {
            return;
        }
        let fractions = children.fractions(c);
        let binding = &children.bindings[c];
        let weighted = || binding.guides.iter().zip(&binding.weights).filter(|(_, &w)| w != 0.0);
        let first = rest[1] - rest[0];
        let u = 0.5 * fractions[1];
        let turned: Vec3 = weighted()
            .map(|(&g, &w)| w * (after.frame(g as usize, u) * before.frame(g as usize, u).inverse() * first))
            .sum();
        let tangent = turned.try_normalize().unwrap_or_else(|| first.normalize());
        // The child's frames: after, its heaviest guide's root frame turned onto its first edge;
        // before, that frame turned back onto its first edge before.
        let heaviest = weighted().max_by(|a, b| a.1.total_cmp(b.1)).map_or(binding.guides[0], |(&g, _)| g);
        let frame_after = aligned(after.root_frame(heaviest as usize), tangent);
        let frame_before = Quat::from_rotation_arc(tangent, first.normalize()) * frame_after;
        let mut frames = vec![Quat::IDENTITY; rest.len()];
        let mut own = vec![Vec3::ZERO; rest.len()];
        strand_frames(rest, frame_before, &mut frames);
        strand_bends(rest, &frames, &mut own);
        // Each weighted guide's style bend at the child's inner vertices, in the child's frame:
        // the guide's frame turned onto the child's first edge differs from the child's by a turn
        // about that edge.
        let styles: Vec<(f32, Vec<Vec3>)> = weighted()
            .map(|(&g, &w)| {
                let turn = frame_after.inverse() * aligned(after.root_frame(g as usize), tangent);
                let bends = fractions[1..fractions.len() - 1]
                    .iter()
                    .map(|&u| turn * (after.bend(g as usize, u) - kept * before.bend(g as usize, u)))
                    .collect();
                (w, bends)
            })
            .collect();
        let draw = handedness_draw(rest[0], weighted().map(|(&g, _)| before.root(g as usize)));
        let style = blend_curls(&styles, draw);
        let mut frame = frame_after;
        out[1] = out[0] + tangent * first.length();
        for k in 1..out.len() - 1 {
            let bend = style[k - 1] + kept * own[k];
            let (previous, next) = (rest[k].distance(rest[k - 1]), rest[k + 1].distance(rest[k]));
            frame = (frame * Quat::from_scaled_axis(bend * 0.5 * (previous + next))).normalize();
            out[k + 1] = out[k] + frame * Vec3::X * next;
        }
    });
    out
}

/// How high each child's weight may hang from its root: no higher than its guides' weight
/// hangs from theirs (the elevation of the mean of a strand's points less its root, weighted
/// over the child's guides), `up` against gravity. A child carried in its guides' frames from a
/// root up on the crown, where the scalp turns fastest, came out tilted back against its fall
/// and pushed out of the head higher still: its weight hung 10–30 mm higher and farther out
/// than its guides', balanced on its arch, and simulated again it fell (on 2,000 strands through
/// 100 guides, bed-head: 28 children moved 7–272 mm in 2 s; every child whose weight hung more
/// than ~62 mm out fell). The guides were settled, so how high theirs hang is a balance that holds.
pub struct HangCeilings {
    up: Vec3,
    ceilings: Vec<Option<f32>>,
}

impl HangCeilings {
    pub fn new(bindings: &[Binding], guides: &Curves, up: Vec3) -> HangCeilings {
        let elevations: Vec<Option<f32>> = (0..guides.offsets.len() - 1)
            .map(|g| elevation(hang(&guides.points[guides.range(g)]), up))
            .collect();
        let ceilings = bindings
            .par_iter()
            .map(|binding| {
                let (mut sum, mut total) = (0.0, 0.0);
                for (&g, &w) in binding.guides.iter().zip(&binding.weights) {
                    if let (Some(elevation), true) = (elevations[g as usize], w != 0.0) {
                        sum += w * elevation;
                        total += w;
                    }
                }
                (total > 0.0).then(|| sum / total)
            })
            .collect();
        HangCeilings { up, ceilings }
    }

    /// Child `child` (its points, root first) turned down about its root, about the horizontal
    /// axis across where its weight hangs, until its weight hangs no higher than its ceiling;
    /// whether it was more than [`LOWER_START`] above it (and turned), or once `started`, more
    /// than [`LOWER_TOLERANCE`].
    pub fn lower(&self, child: usize, strand: &mut [Vec3], started: bool) -> bool {
        let hang = hang(strand);
        let (Some(ceiling), Some(elevation)) = (self.ceilings[child], elevation(hang, self.up)) else {
            return false;
        };
        let Some(axis) = self.up.cross(hang).try_normalize() else { return false };
        if elevation <= ceiling + if started { LOWER_TOLERANCE } else { LOWER_START } {
            return false;
        }
        let turn = Quat::from_axis_angle(axis, elevation - ceiling);
        let root = strand[0];
        for p in &mut strand[1..] {
            *p = root + turn * (*p - root);
        }
        true
    }
}

/// How far (radians) above its ceiling a child's weight may hang before [`HangCeilings::lower`]
/// turns it: the scatter of interpolation, which does not tip a child over (on bed-head's crown
/// children 2.7° above their guides held, 6° above fell). Turning children down moves permed
/// children's curls where the push out lays their loops on the head (median curl radius over the
/// guides' on a curly head, `tests/guides.rs`: −2.6 % unturned, +4.6 % turning every child
/// above its guides, +3.9 % from this start).
const LOWER_START: f32 = 4.0 * std::f32::consts::PI / 180.0;

/// How far above its ceiling a child's weight may stay once turned down (the push out of the
/// head lifts a lowered child a little, so they take turns).
const LOWER_TOLERANCE: f32 = 0.25 * std::f32::consts::PI / 180.0;

/// Where a strand's weight hangs from its root: the mean of its points less the root.
fn hang(points: &[Vec3]) -> Vec3 {
    points.iter().map(|&p| p - points[0]).sum::<Vec3>() / points.len() as f32
}

/// How far above the horizontal (radians) a strand's weight hangs from its root, given its
/// [`hang`].
fn elevation(hang: Vec3, up: Vec3) -> Option<f32> {
    Some(hang.try_normalize()?.dot(up).clamp(-1.0, 1.0).asin())
}

/// The most a blend of bends is scaled up to the weighted mean of their sizes.
const MAX_BEND_GAIN: f32 = 3.0;

/// A bend's part across the tangent (the transport frame's y and z) as a complex number: a turn
/// about the tangent multiplies it by a unit one, a mirror image conjugates it.
fn across(bend: Vec3) -> Vec2 {
    Vec2::new(bend.y, bend.z)
}

fn complex_product(a: Vec2, b: Vec2) -> Vec2 {
    Vec2::new(a.x * b.x - a.y * b.y, a.x * b.y + a.y * b.x)
}

/// Which way a strand's bends turn about its tangent, and how far: the sum over its steps of
/// the turn's sine times the bend's size (a nearly straight stretch turns at random and counts
/// little). A right-handed curl's bend turns one way in transport frames, a left-handed one's the
/// other, at the curl's torsion.
fn handedness(bends: &[Vec3]) -> f32 {
    bends
        .windows(2)
        .map(|w| across(w[0]).perp_dot(across(w[1])) / across(w[0]).length().max(f32::MIN_POSITIVE))
        .sum()
}

/// Weighted guides' bends along a child (`(weight, bends at the child's inner vertices)`, in
/// the child's transport frames), blended so that the child bends as much as its guides and
/// twists one way. A sum of a left- and a right-handed curl's bends swings to and fro instead of
/// turning (such children lost 15–22 % of their guides' torsion and curled looser: median curl
/// radius +8.8 % over the guides' on a wavy head, +10.3 % on a straight one), so the child takes
/// one handedness and guides curled the other way are mirrored first (their bends reflected about
/// the tangent, in the phase that agrees best with the others').
///
/// Which handedness: right-handed with the probability of the right-handed guides' share of the
/// weighted handedness, drawn with `draw` (uniform in [0, 1), the child's own). Where all of a
/// child's guides curl one way it does too; where they differ, neighbouring children differ as
/// simulated strands do (in a simulated perm 45 % of strands curl against their nearest guide).
/// Taking the weighted majority instead switched every child at once where that majority flips,
/// on the line where the children's first guide changes: a seam (mean distance at mid-length
/// between neighbouring children bound to different first guides over that of neighbours of the
/// same one 1.54 on a straight head, 0.99 when every strand is simulated).
///
/// The blend is the weighted sum's direction at the weighted mean of the sizes: a plain sum of
/// guides curling in different phases cancels in part and flattens the child's curl; where they
/// nearly cancel the direction is uncertain, so the sum is scaled up at most [`MAX_BEND_GAIN`]
/// times. A child of one guide bends as it does.
fn blend_curls(guides: &[(f32, Vec<Vec3>)], draw: f32) -> Vec<Vec3> {
    let len = guides.first().map_or(0, |g| g.1.len());
    let hands: Vec<f32> = guides.iter().map(|(_, bends)| handedness(bends)).collect();
    let right: f32 = guides.iter().zip(&hands).map(|((w, _), h)| w * h.max(0.0)).sum();
    let all: f32 = guides.iter().zip(&hands).map(|((w, _), h)| w * h.abs()).sum();
    // Right-handed takes [0, right / all) of the draws: never a handedness none of the guides has.
    let hand = if draw * all < right { 1.0 } else { -1.0 };
    let mirrored: Vec<bool> = hands.iter().map(|&h| h * hand < 0.0).collect();
    let agreeing_bends: Vec<Vec2> = (0..len)
        .map(|k| guides.iter().zip(&mirrored).filter(|(_, &m)| !m).map(|((w, b), _)| *w * across(b[k])).sum())
        .collect();
    let (mut sum, mut size) = (vec![Vec3::ZERO; len], vec![0.0f32; len]);
    for ((w, bends), &mirror) in guides.iter().zip(&mirrored) {
        // Mirrored bends are phase × conjugate(bend); the phase that maximises their agreement
        // with the unmirrored guides' (a), Σ Re(phase × conjugate(bend × a)), is Σ bend × a.
        let phase = match mirror {
            true => {
                bends.iter().zip(&agreeing_bends).map(|(b, m)| complex_product(across(*b), *m)).sum::<Vec2>()
            }
            false => Vec2::X,
        }
        .normalize_or(Vec2::X);
        for (k, b) in bends.iter().enumerate() {
            let turned =
                if mirror { complex_product(phase, across(*b) * Vec2::new(1.0, -1.0)) } else { across(*b) };
            sum[k] += *w * Vec3::new(b.x, turned.x, turned.y);
            size[k] += w * b.length();
        }
    }
    sum.iter()
        .zip(&size)
        .map(|(&s, &size)| match s.length() {
            length if length > 0.0 => s * (size / length).min(MAX_BEND_GAIN),
            _ => s,
        })
        .collect()
}

/// A child's own number in [0, 1) for [`blend_curls`]'s choice of handedness, from where its
/// root lies among its guides' roots: the shares of its distances to them (nearest first) through
/// a steep ramp that wraps. So it is the same in every pose (roots are pinned) and at any thread
/// count, whatever order the file lists the strands in and whatever their ids (a draw from the
/// child's place in the list flipped ~40 % of the children of a groom listed in another order;
/// one from its id, those of a renumbered groom). Moved, turned or scaled, the draw changes only
/// by the rounding of the moved roots (about 1e-4 of the guides' spacing 2 m from the origin, so
/// a few children in a hundred sit close enough to their threshold to flip), where a hash of the
/// coordinates flipped half of them; neighbouring children a twentieth of the guides' spacing
/// apart draw independently.
fn handedness_draw(root: Vec3, guide_roots: impl Iterator<Item = Vec3>) -> f32 {
    // Steep and incommensurate: with two guides the draw turns over 31 times between them, with
    // three along two directions.
    const RAMP: [f64; 3] = [0.0, 30.9, 70.7];
    let mut distances: Vec<f64> = guide_roots.map(|g| f64::from(root.distance(g))).collect();
    distances.sort_by(f64::total_cmp);
    let total: f64 = distances.iter().sum();
    if total <= 0.0 {
        return 0.5;
    }
    let phase: f64 = distances.iter().zip(RAMP).map(|(d, ramp)| d / total * ramp).sum();
    phase.rem_euclid(1.0) as f32
}

/// How much of the differences between neighbouring guides' bends before survives in their bends
/// after, from 0 (the style sets the shape: a perm on rods) to 1 (the style adds to it: hair
/// that only moved): the least-squares factor over pairs of guides that share a child, sampled
/// along their length, each pair compared in the first guide's frames.
pub fn kept_fraction(bindings: &[Binding], before: &Curves, after: &Curves) -> f32 {
    const SAMPLES: usize = 32;
    let pairs: std::collections::BTreeSet<(u32, u32)> = bindings
        .iter()
        .flat_map(|b| {
            let first = b.guides[0];
            b.guides
                .iter()
                .zip(&b.weights)
                .filter(move |(&g, &w)| w != 0.0 && g != first)
                .map(move |(&g, _)| (first.min(g), first.max(g)))
        })
        .collect();
    let (mut along, mut across) = (0.0f64, 0.0f64);
    for &(g, h) in &pairs {
        let (g, h) = (g as usize, h as usize);
        let to_g = |curves: &Curves| {
            let root = curves.root_frame(g);
            root.inverse() * aligned(curves.root_frame(h), root * Vec3::X)
        };
        let (before_h, after_h) = (to_g(before), to_g(after));
        for j in 0..SAMPLES {
            let u = (j as f32 + 0.5) / SAMPLES as f32;
            let was = before.bend(g, u) - before_h * before.bend(h, u);
            let is = after.bend(g, u) - after_h * after.bend(h, u);
            along += was.dot(is) as f64;
            across += was.length_squared() as f64;
        }
    }
    if across > 0.0 {
        (along / across).clamp(0.0, 1.0) as f32
    } else {
        1.0
    }
}

/// `frame` turned by the smallest rotation that brings its x axis onto `tangent`.
fn aligned(frame: Quat, tangent: Vec3) -> Quat {
    (Quat::from_rotation_arc((frame * Vec3::X).normalize(), tangent) * frame).normalize()
}

/// A per-vertex attribute of the guides (`components` floats per vertex) carried to the
/// children: the weighted guides' values at the same fraction of length.
pub fn blend_attribute(children: &Children, guides: &Curves, values: &[f32], components: usize) -> Vec<f32> {
    let mut out = vec![0.0; children.points.len() * components];
    let scaled: Vec<u32> = children.offsets.iter().map(|&o| o * components as u32).collect();
    let mut parts = split_mut(&mut out, &scaled);
    parts.par_iter_mut().enumerate().for_each(|(c, out)| {
        let fractions = children.fractions(c);
        let binding = &children.bindings[c];
        let mut value = [0.0f32; 4];
        for (k, o) in out.chunks_exact_mut(components).enumerate() {
            for (&g, &w) in binding.guides.iter().zip(&binding.weights) {
                if w == 0.0 {
                    continue;
                }
                guides.sample_scalar(values, components, g as usize, fractions[k], &mut value);
                for (o, v) in o.iter_mut().zip(&value) {
                    *o += w * v;
                }
            }
        }
    });
    debug_assert_eq!(parts.len(), children.strands());
    out
}

/// Arc-length fraction of every vertex of a strand (0 at the root, 1 at the tip).
fn strand_fractions(points: &[Vec3], out: &mut [f32]) {
    out[0] = 0.0;
    for i in 1..points.len() {
        out[i] = out[i - 1] + points[i - 1].distance(points[i]);
    }
    let length = out[points.len() - 1];
    if length > 0.0 {
        out.iter_mut().for_each(|f| *f /= length);
    }
}

/// A frame whose x axis is `tangent` (any roll: only the same frame before and after matters).
fn initial_frame(tangent: Vec3) -> Quat {
    Quat::from_rotation_arc(Vec3::X, tangent.normalize())
}

/// Parallel transport of `root` (x axis along the first edge) down the strand: each edge's
/// frame is the previous one turned by the smallest rotation between their tangents.
fn strand_frames(points: &[Vec3], root: Quat, out: &mut [Quat]) {
    let n = points.len();
    out[0] = root;
    let mut previous_tangent = (points[1] - points[0]).normalize();
    for i in 1..n - 1 {
        let tangent = (points[i + 1] - points[i]).normalize();
        out[i] = (Quat::from_rotation_arc(previous_tangent, tangent) * out[i - 1]).normalize();
        previous_tangent = tangent;
    }
    out[n - 1] = out[n - 2];
}

/// Per vertex of a strand, the turn from the edge before it to the edge after it per unit length
/// (the mean of the two edges' lengths), as a rotation vector in the frame of the edge before
/// (`frames` from [`strand_frames`]); zero at the root and the tip. A frame turned by each bend
/// times the length in turn, edge by edge, rebuilds the strand.
fn strand_bends(points: &[Vec3], frames: &[Quat], out: &mut [Vec3]) {
    let n = points.len();
    out[0] = Vec3::ZERO;
    out[n - 1] = Vec3::ZERO;
    for i in 1..n - 1 {
        let (a, b) = (points[i] - points[i - 1], points[i + 1] - points[i]);
        let length = 0.5 * (a.length() + b.length());
        out[i] = match (a.try_normalize(), b.try_normalize()) {
            (Some(a), Some(b)) if length > 0.0 => {
                frames[i - 1].inverse() * Quat::from_rotation_arc(a, b).to_scaled_axis() / length
            }
            _ => Vec3::ZERO,
        };
    }
}

/// Cuts `data` into the per-strand slices `offsets` describes.
pub(crate) fn split_mut<'a, T>(mut data: &'a mut [T], offsets: &[u32]) -> Vec<&'a mut [T]> {
    let mut parts = Vec::with_capacity(offsets.len().saturating_sub(1));
    for w in offsets.windows(2) {
        let (head, tail) = data.split_at_mut((w[1] - w[0]) as usize);
        parts.push(head);
        data = tail;
    }
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(origin: Vec3, n: usize, step: f32) -> Vec<Vec3> {
        (0..n).map(|i| origin + Vec3::Y * (i as f32 * step)).collect()
    }

    /// A straight guide wound into a circle: a child beside it, bound only to it, winds into a
    /// helix of the same pitch around the same axis — radius changed by at most its offset.
    #[test]
    fn a_child_follows_a_curl_in_the_guides_frame() {
        let n = 40;
        let step = 0.005;
        let guide = line(Vec3::ZERO, n, step);
        let child = line(Vec3::new(0.0, 0.0, 0.002), n, step);
        let radius = 0.01;
        // The circle the guide winds into, with chords as long as its edges.
        let dphi = 2.0 * (step / (2.0 * radius)).asin();
        let helix: Vec<Vec3> = (0..n)
            .map(|i| {
                let phi = i as f32 * dphi;
                Vec3::new(radius * (1.0 - phi.cos()), radius * phi.sin(), 0.0)
            })
            .collect();
        let before = Curves::new(guide.clone(), vec![0, n as u32], None);
        let roots = before.carried_root_frames(&helix);
        let after = Curves::new(helix.clone(), vec![0, n as u32], Some(&roots));
        let bindings = [Binding { guides: [0, 0, 0], weights: [1.0, 0.0, 0.0] }];
        let offsets = [0, n as u32];
        let children = Children { points: &child, offsets: &offsets, bindings: &bindings };
        let moved = deform(&children, &before, &after);
        assert_eq!(moved[0], child[0], "roots stay");
        // The offset is along the curl's axis (z): the child is the guide's helix shifted by it.
        for (m, h) in moved.iter().zip(&helix) {
            assert!((*m - (*h + Vec3::new(0.0, 0.0, 0.002))).length() < 1e-5, "{m} vs {h}");
        }
        // Scalars follow the fraction of length.
        let values: Vec<f32> = (0..n).map(|i| i as f32).collect();
        let blended = blend_attribute(&children, &before, &values, 1);
        assert!(blended.iter().zip(&values).all(|(a, b)| (a - b).abs() < 1e-3));
    }

    /// A helix about the y axis with edges `step` long along it, right-handed or its mirror image.
    fn helix(n: usize, step: f32, radius: f32, pitch: f32, right: bool) -> Vec<Vec3> {
        let rise = pitch / std::f32::consts::TAU;
        let dphi = step / radius.hypot(rise);
        let hand = if right { 1.0 } else { -1.0 };
        (0..n)
            .map(|i| {
                let phi = i as f32 * dphi;
                Vec3::new(radius * (1.0 - phi.cos()), rise * phi, -hand * radius * phi.sin())
            })
            .collect()
    }

    /// Two straight guides of `n` points `step` apart, 4 mm apart from `origin`, before and after
    /// they are wound into helices of 1 cm radius and 3 cm pitch, the first right-handed and the
    /// second left-handed; and the wound points.
    fn guides_wound_both_ways(origin: Vec3, n: usize, step: f32) -> (Curves, Curves, Vec<Vec3>) {
        let apart = Vec3::new(0.004, 0.0, 0.0);
        let guides: Vec<Vec3> = [line(origin, n, step), line(origin + apart, n, step)].concat();
        let wound: Vec<Vec3> = [true, false]
            .iter()
            .enumerate()
            .flat_map(|(g, &right)| {
                let root = origin + apart * g as f32;
                helix(n, step, 0.01, 0.03, right).into_iter().map(move |p| p + root)
            })
            .collect();
        let offsets = vec![0, n as u32, 2 * n as u32];
        let before = Curves::new(guides, offsets.clone(), None);
        let roots = before.carried_root_frames(&wound);
        let after = Curves::new(wound.clone(), offsets, Some(&roots));
        (before, after, wound)
    }

    /// Two straight guides wound into helices of one radius and pitch, one right-handed and one
    /// left-handed: a child bound to both curls as tightly as they do. Summed, their bends swung
    /// to and fro instead of turning, and the child lost the curls' torsion.
    #[test]
    fn a_child_of_guides_curled_both_ways_curls_like_them() {
        let (n, step) = (60, 0.004);
        let child = line(Vec3::new(0.002, 0.0, 0.0), n, step);
        let (before, after, wound) = guides_wound_both_ways(Vec3::ZERO, n, step);
        let guide_radius = crate::analysis::curl_radius(&wound[..n]).unwrap();
        assert!((guide_radius - 0.01).abs() < 1e-4, "{guide_radius}");
        for weights in [[0.5, 0.5, 0.0], [0.7, 0.3, 0.0], [0.3, 0.7, 0.0]] {
            let bindings = [Binding { guides: [0, 1, 0], weights }];
            let child_offsets = [0, n as u32];
            let children = Children { points: &child, offsets: &child_offsets, bindings: &bindings };
            let moved = deform(&children, &before, &after);
            let radius = crate::analysis::curl_radius(&moved).unwrap();
            assert!((radius / guide_radius - 1.0).abs() < 0.02, "weights {weights:?}: curl radius {radius}");
        }
    }

    /// Sign of a strand's summed torsion: which way its curl turns.
    fn twists_positive(points: &[Vec3]) -> bool {
        let torsion: f32 = points.windows(4).map(|w| (w[1] - w[0]).cross(w[2] - w[1]).dot(w[3] - w[2])).sum();
        torsion > 0.0
    }

    /// Children between a right- and a left-handed guide, bound 0.7 / 0.3: about 70 % of them
    /// curl right-handed and 30 % left-handed (each as tightly as the guides), not all of them
    /// the majority's way, which lined every switch up on the line where the first guide changes.
    /// Each child's choice is its own: the same whatever children are beside it and in whatever
    /// order they are listed, and nearly all the same when the whole groom is moved 3 m.
    #[test]
    fn children_of_guides_curled_both_ways_take_each_handedness_by_weight() {
        let (n, step, count) = (60, 0.004, 400);
        let bindings = vec![Binding { guides: [0, 1, 0], weights: [0.7, 0.3, 0.0] }; count];
        // The guides 4 mm apart on x, straight, then wound opposite ways; the children's roots on
        // a 20 × 20 grid about them (0.18 mm by 0.5 mm), listed in the order given; all moved by
        // `shift`.
        let root = |c: usize| Vec3::new(2e-4 + 1.8e-4 * (c % 20) as f32, 0.0, 5e-4 * (c / 20) as f32);
        let styled = |shift: Vec3, children: &[usize]| {
            let (before, after, wound) = guides_wound_both_ways(shift, n, step);
            let points: Vec<Vec3> = children.iter().flat_map(|&c| line(shift + root(c), n, step)).collect();
            let offsets: Vec<u32> = (0..=children.len() as u32).map(|c| c * n as u32).collect();
            let bindings = &bindings[..children.len()];
            (deform(&Children { points: &points, offsets: &offsets, bindings }, &before, &after), wound)
        };
        let all: Vec<usize> = (0..count).collect();
        let (moved, wound) = styled(Vec3::ZERO, &all);
        let first_way = twists_positive(&wound[..n]);
        assert_ne!(first_way, twists_positive(&wound[n..]), "the guides curl opposite ways");
        let guide_radius = crate::analysis::curl_radius(&wound[..n]).unwrap();
        let strand = |c: usize| &moved[c * n..(c + 1) * n];
        let like_first = (0..count).filter(|&c| twists_positive(strand(c)) == first_way).count();
        let share = like_first as f32 / count as f32;
        // Binomial: 400 independent draws at 0.7 are within ±0.07 but one time in ~4,000.
        assert!((share - 0.7).abs() < 0.07, "{share} of the children curl like the first guide");
        for c in 0..count {
            let radius = crate::analysis::curl_radius(strand(c)).unwrap();
            assert!((radius / guide_radius - 1.0).abs() < 0.02, "child {c}: curl radius {radius}");
        }
        // A child alone curls as it did among the others, and every child the same when they are
        // listed the other way round (a draw from the place in the list flipped 40 % of them).
        for c in [0, 5, 398] {
            assert_eq!(styled(Vec3::ZERO, &[c]).0, strand(c), "child {c} alone");
        }
        let reversed: Vec<usize> = all.iter().rev().copied().collect();
        let (backwards, _) = styled(Vec3::ZERO, &reversed);
        for (place, &c) in reversed.iter().enumerate() {
            assert_eq!(&backwards[place * n..(place + 1) * n], strand(c), "child {c} listed at {place}");
        }
        // Moved 3 m, the roots are rounded to 2.4e-7 m; the draw moves by about 1e-4 of its range
        // at most, so a child flips only when its draw lies that close to its threshold.
        let (far, _) = styled(Vec3::new(3.0, -1.0, 2.0), &all);
        let flipped: Vec<usize> = (0..count)
            .filter(|&c| twists_positive(&far[c * n..(c + 1) * n]) != twists_positive(strand(c)))
            .collect();
        eprintln!("moved 3 m: {} of {count} children turn the other way: {flipped:?}", flipped.len());
        assert!(flipped.len() <= count / 100, "moved 3 m, children {flipped:?} turn the other way");
    }

    /// A child whose weight hangs higher than its guide's is turned down about its root to the
    /// guide's elevation, keeping its root, its edges and which way it leans; one hanging lower
    /// is left alone.
    #[test]
    fn a_child_hangs_no_higher_than_its_guide() {
        let straight = |root: Vec3, degrees: f32, azimuth: f32| -> Vec<Vec3> {
            let (e, a) = (degrees.to_radians(), azimuth.to_radians());
            let direction = Vec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin());
            (0..10).map(|i| root + direction * (0.01 * i as f32)).collect()
        };
        let guide = Curves::new(straight(Vec3::ZERO, -30.0, 0.0), vec![0, 10], None);
        let binding = Binding { guides: [0; 3], weights: [1.0, 0.0, 0.0] };
        let ceilings = HangCeilings::new(&[binding], &guide, Vec3::Y);
        let root = Vec3::new(0.0, 0.1, 0.02);
        let mut high = straight(root, 10.0, 40.0);
        assert!(ceilings.lower(0, &mut high, false));
        let want = straight(root, -30.0, 40.0);
        let apart = high.iter().zip(&want).map(|(p, q)| p.distance(*q)).fold(0.0, f32::max);
        assert!(apart < 1e-6, "{apart:e} m from the guide's elevation: {high:?}");
        let mut low = straight(root, -50.0, 40.0);
        let before = low.clone();
        assert!(!ceilings.lower(0, &mut low, false));
        assert_eq!(low, before);
    }
}
