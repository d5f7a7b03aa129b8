//! Children placed among each other, not settled: interpolated from their guides and pushed out
//! of the colliders, a few of their vertices lie closer to other strands than the hair–hair
//! contact distance. A shot that simulates them with contacts starts by pushing those apart (a
//! child of the 3,000-strand perm moved 2.3 mm in 0.5 s), so before the sag-free rest makes
//! their shape the rest, recipes with hair–hair contacts move them apart: a few position
//! projections by the contacts' own measure (`HairContacts::project_apart`) against each other
//! and the styled guides (held), roots held, each followed by the colliders' push out of the
//! vertices it moved. Deterministic, and not a simulation: vertices move by their overlap only.
use glam::Vec3;

use crate::error::Result;
use crate::interact::hair_contacts::HairContacts;
use crate::interact::obstacles::Shape;
use crate::style::recipe::Contacts;

/// How much farther apart than the contact distance the pass leaves strands, as a share of it:
/// the slack a shot's first steps (a child sags by micrometres) need before contacts engage.
pub const MARGIN: f32 = 0.5;

/// Longest pieces the pass's contacts cut strands into, metres (coarser than a simulation's: the
/// pass runs once over every strand).
pub const SPACING: f32 = 0.008;

/// Most projections the pass makes; it stops as soon as one moves nothing.
pub const PASSES: usize = 8;

/// Moves the children (`points`, strands at `offsets`, per-vertex `radii`) apart from each other
/// and from the guides (`guide_points` at `guide_offsets`, `guide_radii`, held), roots held,
/// keeping every moved vertex out of `colliders`, calling `pass_done` after each projection.
/// Returns how many projections moved something; children piled too densely for the memory limit's contact lists
/// are an error.
#[allow(clippy::too_many_arguments)]
pub fn separate(
    points: &mut [Vec3],
    offsets: &[u32],
    radii: &[f32],
    guide_points: &[Vec3],
    guide_offsets: &[u32],
    guide_radii: &[f32],
    colliders: &[Shape],
    contacts: &Contacts,
    mut pass_done: impl FnMut(),
) -> Result<usize> {
    let child_vertices = points.len();
    if child_vertices == 0 {
        return Ok(0);
    }
    // Children first, then the guides, as one groom.
    let mut all_offsets = offsets.to_vec();
    all_offsets.extend(guide_offsets[1..].iter().map(|&o| o + child_vertices as u32));
    let mut all_points = points.to_vec();
    all_points.extend_from_slice(guide_points);
    let widened: Vec<f32> = radii.iter().chain(guide_radii).map(|r| r * (1.0 + MARGIN)).collect();
    let mut fixed = vec![false; all_points.len()];
    fixed[child_vertices..].fill(true);
    for &root in &offsets[..offsets.len() - 1] {
        fixed[root as usize] = true;
    }
    let mut pairs = HairContacts::new(
        &all_offsets,
        &widened,
        contacts.sample_spacing.max(SPACING),
        contacts.hair_stiffness,
    );
    let mut passes = 0;
    // Only children move (guides are held): each moved vertex is pushed out of the colliders.
    let out_of_colliders = |i: usize, p: Vec3| super::outside(p, radii[i], colliders);
    for _ in 0..PASSES {
        let moved = pairs.project_apart(&mut all_points, &widened, &fixed, out_of_colliders)?;
        pass_done();
        if moved == 0 {
            break;
        }
        passes += 1;
    }
    points.copy_from_slice(&all_points[..child_vertices]);
    Ok(passes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every vertex's smallest distance to an edge of another strand, over the contact distance
    /// (radius plus the edge's mean radius), by an all-pairs search.
    fn clearance(points: &[Vec3], offsets: &[u32], radii: &[f32]) -> Vec<f32> {
        let strand = |i: usize| offsets.partition_point(|&o| o as usize <= i) - 1;
        (0..points.len())
            .map(|i| {
                let mut nearest = f32::INFINITY;
                for j in (0..points.len() - 1).filter(|&j| j + 1 < offsets[strand(j) + 1] as usize) {
                    if strand(j) == strand(i) {
                        continue;
                    }
                    let (a, b) = (points[j], points[j + 1]);
                    let t = ((points[i] - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
                    let contact = radii[i] + 0.5 * (radii[j] + radii[j + 1]);
                    nearest = nearest.min(points[i].distance(a + (b - a) * t) / contact);
                }
                nearest
            })
            .collect()
    }

    /// Two children lying 30 µm apart along their length (contact distance 80 µm), one of them
    /// also 20 µm over a guide, and a third pressed between the guide and the head (a sphere)
    /// 50 µm under the guide: every vertex of the first two ends clear of every other strand, no
    /// vertex inside the head (there the head wins: the third child cannot get clear without
    /// sliding), roots where they were, and no vertex moved by more than 0.3 mm.
    #[test]
    fn children_lying_on_each_other_and_a_guide_are_moved_apart_out_of_the_head() {
        let head = Shape::Sphere { center: Vec3::ZERO, radius: 0.1 };
        let r = 40e-6;
        let top = 0.1 + r;
        let strand = |from: Vec3, step: Vec3| (0..9).map(|k| from + step * k as f32).collect::<Vec<Vec3>>();
        let along_z = Vec3::new(0.0, 0.0, 0.005);
        let mut children = strand(Vec3::new(0.0, top + 0.001 + 20e-6, -0.02), along_z);
        children.extend(strand(Vec3::new(30e-6, top + 0.001 + 20e-6, -0.02), along_z));
        children.extend(strand(Vec3::new(0.01, top, -0.02), along_z));
        let offsets = [0, 9, 18, 27];
        let guides = strand(Vec3::new(-0.02, top + 0.001, 0.0), Vec3::new(0.005, 0.0, 0.0));
        let mut under = strand(Vec3::new(-0.02, top + 50e-6, 0.0), Vec3::new(0.005, 0.0, 0.0));
        // The third child runs under the guide's twin laid 50 µm over the head.
        let mut guide_points = guides.clone();
        guide_points.append(&mut under);
        let guide_offsets = [0, 9, 18];
        let radii = vec![r; children.len()];
        let before = children.clone();
        let passes = separate(
            &mut children,
            &offsets,
            &radii,
            &guide_points,
            &guide_offsets,
            &radii[..18],
            std::slice::from_ref(&head),
            &Contacts::default(),
            || {},
        )
        .unwrap();
        assert!(passes > 0, "nothing moved");
        let mut all = children.clone();
        all.extend_from_slice(&guide_points);
        let all_offsets = [0, 9, 18, 27, 36, 45];
        let clear = clearance(&all, &all_offsets, &vec![r; all.len()]);
        for i in 0..children.len() {
            assert!(children[i].length() >= 0.1 + r - 1e-7, "vertex {i} inside the head: {:?}", children[i]);
            let moved = children[i].distance(before[i]);
            assert!(moved < 3e-4, "vertex {i} moved {moved}");
            if i < 18 && i % 9 != 0 {
                assert!(clear[i] >= 1.0, "vertex {i} within {:.2} of the contact distance", clear[i]);
            }
        }
        for root in [0, 9, 18] {
            assert_eq!(children[root], before[root], "root {root} moved");
        }
        // Not vacuous: the children overlapped before.
        let mut was = before.clone();
        was.extend_from_slice(&guide_points);
        let clear_before = clearance(&was, &all_offsets, &vec![r; all.len()]);
        assert!(clear_before[..18].iter().filter(|&&c| c < 1.0).count() >= 14);
    }
}
