//! Moving children with their guides. Each guide carries a rotation-minimising (parallel
//! transport) frame along its length, before and after styling; at each fraction of length the
//! change of frame is the guide's local rotation. A child's edges turn by its guides' rotations
//! at the same fraction and are chained from its root, so a child beside a curl curls with it
//! at the same curvature — instead of averaging world positions of guides at different phases,
//! which flattens curls, or carrying offsets from the guide, which swing out into loops when
//! the child's shape differs from the guide's.
use glam::{Quat, Vec3};
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
        let mut frame_parts = split_mut(&mut frames, &offsets);
        frac_parts.par_iter_mut().zip(frame_parts.par_iter_mut()).enumerate().for_each(|(s, (fr, fm))| {
            let p = &points[offsets[s] as usize..offsets[s + 1] as usize];
            strand_fractions(p, fr);
            let root = root_frames.map_or_else(|| initial_frame(p[1] - p[0]), |r| r[s]);
            strand_frames(p, root, fm);
        });
        debug_assert_eq!(frac_parts.len(), strands);
        let middles = (0..points.len())
            .map(|i| match offsets.binary_search(&(i as u32 + 1)) {
                Ok(_) => 1.0, // the strand's last vertex
                Err(_) => 0.5 * (fractions[i] + fractions[i + 1]),
            })
            .collect();
        Curves { points, offsets, fractions, middles, frames }
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

/// The children's points after their guides moved from `before` to `after`: every edge of a
/// child turns by its guides' frame rotations at the same fraction of length (weighted), keeps
/// its length, and the edges are chained from the child's root. Curvature and twist follow
/// the guides exactly; lengths are kept; a child whose shape differs from its guide's keeps
/// that difference as a turned direction, never as an offset that could swing out.
pub fn deform(children: &Children, before: &Curves, after: &Curves) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; children.points.len()];
    let mut parts = split_mut(&mut out, children.offsets);
    parts.par_iter_mut().enumerate().for_each(|(c, out)| {
        let start = children.offsets[c] as usize;
        let rest = &children.points[start..start + out.len()];
        let fractions = children.fractions(c);
        let binding = &children.bindings[c];
        out[0] = rest[0];
        for k in 1..out.len() {
            let edge = rest[k] - rest[k - 1];
            let u = 0.5 * (fractions[k - 1] + fractions[k]);
            let mut turned = Vec3::ZERO;
            for (&g, &w) in binding.guides.iter().zip(&binding.weights) {
                if w == 0.0 {
                    continue;
                }
                let g = g as usize;
                let rotation = after.frame(g, u) * before.frame(g, u).inverse();
                turned += w * (rotation * edge);
            }
            // Guides turning opposite ways can cancel: keep the rest direction then.
            let direction = turned.try_normalize().unwrap_or_else(|| edge.normalize());
            out[k] = out[k - 1] + direction * edge.length();
        }
    });
    out
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
}
