//! Which guides move each child, and how much: up to three guides per child, weighted by the
//! distance between roots. Bindings are computed once, on the roots before styling, so they
//! do not change while the guides move (Unreal's `groom_closest_guides` / `groom_guide_weights`).
use glam::Vec3;
use rayon::prelude::*;

use crate::error::{Error, Result};

/// Guides per child.
pub const GUIDES_PER_CHILD: usize = 3;

/// A child's guides (indices into the guide list) and their weights, which sum to 1. Unused
/// slots have weight 0 and repeat the first guide.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Binding {
    pub guides: [u32; GUIDES_PER_CHILD],
    pub weights: [f32; GUIDES_PER_CHILD],
}

/// Keeps weights well defined for a child whose root sits on a guide's root (metres).
const WEIGHT_SOFTENING: f32 = 1e-5;

/// Guides considered per child, nearest roots first, before shape matching picks the best.
const CANDIDATES: usize = 12;

/// Points along a strand, relative to its root, at these fractions of its length: what shape
/// matching compares.
const SHAPE_FRACTIONS: [f32; 4] = [0.25, 0.5, 0.75, 1.0];

/// A strand's shape for matching children to guides.
pub type Shape = [Vec3; SHAPE_FRACTIONS.len()];

/// The strand's points at [`SHAPE_FRACTIONS`] of its length, relative to its root.
pub fn shape_of(points: &[Vec3]) -> Shape {
    let length = crate::groom::polyline_length(points);
    let mut out = [Vec3::ZERO; SHAPE_FRACTIONS.len()];
    let (mut edge, mut walked) = (0, 0.0);
    for (o, &f) in out.iter_mut().zip(&SHAPE_FRACTIONS) {
        let target = f * length;
        while edge + 2 < points.len() && walked + points[edge].distance(points[edge + 1]) < target {
            walked += points[edge].distance(points[edge + 1]);
            edge += 1;
        }
        let span = points[edge].distance(points[edge + 1]);
        let t = if span > 0.0 { ((target - walked) / span).clamp(0.0, 1.0) } else { 0.0 };
        *o = points[edge].lerp(points[edge + 1], t) - points[0];
    }
    out
}

/// How unlike a guide a child is: the distance between roots plus the mean distance between
/// their shapes. Roots alone would bind a child to a guide across a parting or a whorl, whose
/// hair falls the other way: carried in that guide's frame it would swing out of the groom.
fn mismatch(root_distance: f32, a: &Shape, b: &Shape) -> f32 {
    root_distance + a.iter().zip(b).map(|(p, q)| p.distance(*q)).sum::<f32>() / a.len() as f32
}

/// Binds every child to the three guides, among those with the nearest roots, whose shapes
/// match it best. A child whose nearest guide root is farther than `reach` is an error naming
/// the child (`children[i]` is its strand index in the groom).
pub fn bind(
    child_roots: &[Vec3],
    child_shapes: &[Shape],
    children: &[usize],
    guide_roots: &[Vec3],
    guide_shapes: &[Shape],
    reach: f32,
) -> Result<Vec<Binding>> {
    if guide_roots.is_empty() {
        return Err(Error::Usage("no guides to bind children to".into()));
    }
    // Guides sorted along x: a child scans outwards from its own x until the slab is wider than
    // its farthest candidate, so it visits only a slab of the scalp.
    let mut order: Vec<u32> = (0..guide_roots.len() as u32).collect();
    order.sort_by(|&a, &b| guide_roots[a as usize].x.total_cmp(&guide_roots[b as usize].x).then(a.cmp(&b)));
    let xs: Vec<f32> = order.iter().map(|&g| guide_roots[g as usize].x).collect();
    let bindings: Vec<(Binding, f32)> = child_roots
        .par_iter()
        .zip(child_shapes.par_iter())
        .map(|(&root, shape)| {
            let mut near = [(f32::INFINITY, u32::MAX); CANDIDATES];
            let consider = |near: &mut [(f32, u32); CANDIDATES], g: u32| {
                let entry = (guide_roots[g as usize].distance_squared(root), g);
                if entry < near[CANDIDATES - 1] {
                    near[CANDIDATES - 1] = entry;
                    near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                }
            };
            let start = xs.partition_point(|&x| x < root.x);
            let (mut lo, mut hi) = (start, start);
            loop {
                let limit = near[CANDIDATES - 1].0;
                let left = lo > 0 && (xs[lo - 1] - root.x).powi(2) <= limit;
                let right = hi < xs.len() && (xs[hi] - root.x).powi(2) <= limit;
                if !left && !right {
                    break;
                }
                if left {
                    lo -= 1;
                    consider(&mut near, order[lo]);
                }
                if right {
                    consider(&mut near, order[hi]);
                    hi += 1;
                }
            }
            let mut best: Vec<(f32, u32)> = near
                .iter()
                .filter(|&&(_, g)| g != u32::MAX)
                .map(|&(d2, g)| (mismatch(d2.sqrt(), shape, &guide_shapes[g as usize]), g))
                .collect();
            best.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            (weigh(&best[..best.len().min(GUIDES_PER_CHILD)]), near[0].0.sqrt())
        })
        .collect();
    for (&(_, nearest), &strand) in bindings.iter().zip(children) {
        if nearest > reach {
            // The groom's error: the command names its file.
            return Err(Error::Groom(crate::groom::GroomError::Guides(format!(
                "strand {strand}: its nearest guide is {nearest:.4} m away, beyond the reach of {} m \
                 ({} guides for {} children); add guides or raise [guides] reach",
                crate::validate::shortest(reach.into()),
                guide_roots.len(),
                child_roots.len()
            ))));
        }
    }
    Ok(bindings.into_iter().map(|(b, _)| b).collect())
}

/// Inverse-square-mismatch weights of the best guides (the best dominates; a child on a
/// guide's root with its shape copies it).
fn weigh(best: &[(f32, u32)]) -> Binding {
    let mut guides = [best[0].1; GUIDES_PER_CHILD];
    let mut weights = [0.0; GUIDES_PER_CHILD];
    for (k, &(m, g)) in best.iter().enumerate() {
        guides[k] = g;
        weights[k] = 1.0 / (m * m + WEIGHT_SOFTENING * WEIGHT_SOFTENING);
    }
    let total: f32 = weights.iter().sum();
    weights.iter_mut().for_each(|w| *w /= total);
    Binding { guides, weights }
}

/// The reach a child may be from its nearest guide by default: four times the median distance
/// between a guide and its nearest fellow guide.
pub fn default_reach(guide_roots: &[Vec3]) -> f32 {
    if guide_roots.len() < 2 {
        return f32::INFINITY;
    }
    let all: Vec<usize> = (0..guide_roots.len()).collect();
    let mut spacing: Vec<f32> = all
        .par_iter()
        .map(|&g| {
            all.iter()
                .filter(|&&h| h != g)
                .map(|&h| guide_roots[g].distance(guide_roots[h]))
                .fold(f32::INFINITY, f32::min)
        })
        .collect();
    spacing.sort_by(f32::total_cmp);
    4.0 * spacing[spacing.len() / 2]
}

/// Checks bindings a file brought: indices must name guides, weights must be finite,
/// non-negative and sum to 1. Errors name the child's strand index.
pub fn check(bindings: &[Binding], children: &[usize], guide_count: usize) -> Result<()> {
    for (binding, &strand) in bindings.iter().zip(children) {
        for (&g, &w) in binding.guides.iter().zip(&binding.weights) {
            if w != 0.0 && g as usize >= guide_count {
                return Err(file_error(format!(
                    "strand {strand}: groom_closest_guides names guide {g}, but the groom has {guide_count} guides"
                )));
            }
            if !(w.is_finite() && w >= 0.0) {
                return Err(file_error(format!("strand {strand}: groom_guide_weights has weight {w}")));
            }
        }
        let sum: f32 = binding.weights.iter().sum();
        if (sum - 1.0).abs() > 1e-3 {
            return Err(file_error(format!(
                "strand {strand}: groom_guide_weights sum to {sum}, not 1 ({:?})",
                binding.weights
            )));
        }
    }
    Ok(())
}

/// A refusal of the groom file's own bindings: callers name the file ([`Error::in_file`]).
pub(super) fn file_error(message: String) -> Error {
    Error::Groom(crate::groom::GroomError::Binding(message))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_three_by_brute_force() {
        let guides: Vec<Vec3> =
            (0..40).map(|i| Vec3::new((i * 7 % 13) as f32 * 0.01, (i % 5) as f32 * 0.013, 0.0)).collect();
        let children: Vec<Vec3> =
            (0..30).map(|i| Vec3::new((i * 3 % 11) as f32 * 0.011, (i % 4) as f32 * 0.017, 0.001)).collect();
        let ids: Vec<usize> = (0..children.len()).collect();
        // Straight strands of one shape: matching reduces to root distance.
        let same = |n: usize| vec![[Vec3::Y; 4]; n];
        let bindings = bind(&children, &same(30), &ids, &guides, &same(40), 1.0).unwrap();
        for (c, b) in children.iter().zip(&bindings) {
            let mut all: Vec<(f32, u32)> =
                guides.iter().enumerate().map(|(g, p)| (p.distance_squared(*c), g as u32)).collect();
            all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            assert_eq!(b.guides, [all[0].1, all[1].1, all[2].1]);
            assert!((b.weights.iter().sum::<f32>() - 1.0).abs() < 1e-6);
            assert!(b.weights[0] >= b.weights[1] && b.weights[1] >= b.weights[2]);
        }
        let err = bind(&children, &same(30), &ids, &guides, &same(40), 1e-4).unwrap_err().to_string();
        assert!(err.contains("strand 0") && err.contains("40 guides"), "{err}");
    }

    #[test]
    fn a_child_is_not_bound_across_a_parting() {
        // Two guides 1 mm either side of a child; the nearer one's hair falls the other way.
        let guides = [Vec3::new(0.0005, 0.0, 0.0), Vec3::new(-0.0015, 0.0, 0.0)];
        let left = [Vec3::new(-0.05, -0.05, 0.0); 4];
        let right = [Vec3::new(0.05, -0.05, 0.0); 4];
        let b = bind(&[Vec3::ZERO], &[left], &[0], &guides, &[right, left], 1.0).unwrap();
        assert_eq!(b[0].guides[0], 1, "{b:?}");
        assert!(b[0].weights[0] > 0.99, "{b:?}");
    }

    #[test]
    fn file_bindings_are_checked() {
        let good = Binding { guides: [0, 1, 0], weights: [0.5, 0.5, 0.0] };
        assert!(check(&[good], &[7], 2).is_ok());
        let err = check(&[Binding { weights: [0.5, 0.4, 0.0], ..good }], &[7], 2).unwrap_err().to_string();
        assert!(err.contains("strand 7") && err.contains("sum to 0.9"), "{err}");
        let err = check(&[Binding { guides: [0, 5, 0], ..good }], &[9], 2).unwrap_err().to_string();
        assert!(err.contains("strand 9") && err.contains("guide 5"), "{err}");
    }
}
