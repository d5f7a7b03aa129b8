//! Choosing guides: farthest-point sampling over the strands' roots in 3-D, so guides spread
//! evenly over the scalp and isolated strands (strays) become guides of their own rather than
//! being bent by a far-away neighbour.
use glam::Vec3;
use rayon::prelude::*;

/// Indices of `count` roots chosen by farthest-point sampling, in the order they were chosen.
/// Starts from the root nearest the roots' centroid; ties go to the lowest index, so the choice
/// is the same on every machine and thread count. `count` is clamped to `roots.len()`.
pub fn farthest_points(roots: &[Vec3], count: usize) -> Vec<usize> {
    let count = count.min(roots.len());
    if count == 0 {
        return Vec::new();
    }
    let centroid = roots.iter().copied().sum::<Vec3>() / roots.len() as f32;
    let first = argmax(roots.par_iter().map(|r| -r.distance_squared(centroid)));
    let mut chosen = vec![first];
    let mut nearest: Vec<f32> = roots.par_iter().map(|r| r.distance_squared(roots[first])).collect();
    while chosen.len() < count {
        let next = argmax(nearest.par_iter().copied());
        chosen.push(next);
        let p = roots[next];
        nearest.par_iter_mut().zip(roots.par_iter()).for_each(|(d, r)| *d = d.min(r.distance_squared(p)));
    }
    chosen
}

/// Index of the largest value; the lowest index among equals (deterministic under any split).
fn argmax(values: impl IndexedParallelIterator<Item = f32>) -> usize {
    values
        .enumerate()
        .reduce(
            || (usize::MAX, f32::NEG_INFINITY),
            |a, b| match a.1.total_cmp(&b.1) {
                std::cmp::Ordering::Greater => a,
                std::cmp::Ordering::Less => b,
                std::cmp::Ordering::Equal => (a.0.min(b.0), a.1),
            },
        )
        .0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spreads_over_a_line_and_keeps_the_stray() {
        // 101 roots on a 1 m line plus one stray 5 m away: the stray is chosen second (after the
        // root nearest the centroid), then the line's ends and middle.
        let mut roots: Vec<Vec3> = (0..=100).map(|i| Vec3::new(i as f32 * 0.01, 0.0, 0.0)).collect();
        roots.push(Vec3::new(0.5, 5.0, 0.0));
        let chosen = farthest_points(&roots, 4);
        assert_eq!(chosen.len(), 4);
        assert_eq!(chosen[1], 101, "the stray is a guide: {chosen:?}");
        let mut line: Vec<usize> = chosen.iter().copied().filter(|&i| i != 101).collect();
        line.sort();
        assert!(line.contains(&0) && line.contains(&100), "{line:?}");
        assert_eq!(farthest_points(&roots, 1000).len(), roots.len());
    }
}
