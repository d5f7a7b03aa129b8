//! The curves' own per-point attributes beside their primvars: `normals` (which way a ribbon or
//! flat hair faces: USD `normals`, Alembic `N`), `velocities` (motion blur: USD `velocities`,
//! Alembic `.velocities`) and `accelerations` (USD `accelerations`). Files keep them as
//! attributes of the points, not as primvars; a groom keeps them as attributes of these names,
//! and the writers put them back where they came from.
//!
//! They describe the points they were read with. When styling or a simulation moves the points,
//! [`follow_new_shape`] carries them onto the new shape: each normal turns with its curve, by the
//! smallest rotation taking the old tangent at its vertex to the new one (so a normal across the
//! curve stays across it, and a twisted ribbon keeps its twist), and motion that no longer holds
//! is left out.
use glam::{Quat, Vec3};

use crate::groom::{Attribute, AttributeRate, Groom};

pub const NORMALS: &str = "normals";
pub const VELOCITIES: &str = "velocities";
pub const ACCELERATIONS: &str = "accelerations";

/// The point attributes of USD curves that a groom carries under the same names.
pub const SCHEMA_NAMES: [&str; 3] = [NORMALS, VELOCITIES, ACCELERATIONS];

/// Whether a groom attribute is written as the curves' own attribute of its name rather than as
/// a primvar: three components, one per point (normals may also be one per curve).
pub fn is_schema_attribute(name: &str, rate: AttributeRate, components: usize) -> bool {
    components == 3
        && match name {
            NORMALS => true,
            VELOCITIES | ACCELERATIONS => rate == AttributeRate::Vertex,
            _ => false,
        }
}

/// What a moved groom's point attributes become once its points are `after.points`: normals
/// turn with their curves (`before` is the groom as it was, with the same strands; where its
/// vertices differ, a resampled groom, each normal is made perpendicular to its new tangent
/// instead); `velocities` are replaced by `motion` (the simulation's, one per point) or, with
/// none, left out, as are `accelerations`. Returns a warning for each attribute left out.
pub fn follow_new_shape(before: &Groom, after: &mut Groom, motion: Option<&[Vec3]>) -> Vec<String> {
    let mut warnings = Vec::new();
    let normals = after.attribute(NORMALS).is_some_and(|a| a.components == 3);
    if let Some(mut normals) = normals.then(|| after.remove_attribute(NORMALS)).flatten() {
        let from = (before.strand_offsets == after.strand_offsets).then_some(&before.points[..]);
        turn_normals(&mut normals, &after.strand_offsets, from, &after.points);
        after.set_attribute(normals);
    }
    match (motion, after.attribute(VELOCITIES).is_some()) {
        (Some(velocities), true) => {
            let data = velocities.iter().flat_map(|v| v.to_array()).collect();
            after.set_attribute(
                Attribute::new(VELOCITIES, AttributeRate::Vertex, 3, data)
                    .with_kind(crate::groom::AttributeKind::Vector),
            );
        }
        (None, true) => {
            after.remove_attribute(VELOCITIES);
            warnings.push(format!(
                "the file's '{VELOCITIES}' are left out: they were the motion of the hair before styling, \
                 and the styled hair is at rest"
            ));
        }
        _ => {}
    }
    if after.remove_attribute(ACCELERATIONS).is_some() {
        warnings.push(format!(
            "the file's '{ACCELERATIONS}' are left out: they were the motion of the hair before it moved"
        ));
    }
    warnings
}

/// The normals of a moved groom (`after`, as [`follow_new_shape`] left it) at each of its
/// captured `frames` (points in `after`'s layout): each turned from the shape it was read with
/// (`before`, or `after`'s own where the groom was resampled) onto the frame's, so that an
/// animation's normals follow its points. `None` without normals.
pub fn normals_in_frames(before: &Groom, after: &Groom, frames: &[Vec<Vec3>]) -> Option<Vec<Attribute>> {
    let (source, from) = if before.strand_offsets == after.strand_offsets {
        (before.attribute(NORMALS)?, &before.points)
    } else {
        (after.attribute(NORMALS)?, &after.points)
    };
    (source.components == 3).then(|| {
        frames
            .iter()
            .map(|points| {
                let mut normals = source.clone();
                turn_normals(&mut normals, &after.strand_offsets, Some(from), points);
                normals
            })
            .collect()
    })
}

/// Turns `normals` (per vertex or per strand of the curves `offsets` delimits) from the curves
/// at `from` onto the same curves at `to`: by the smallest rotation taking each old tangent to the
/// new one, or, with no old shape (other vertices), by making each normal perpendicular to its new
/// tangent.
fn turn_normals(normals: &mut Attribute, offsets: &[u32], from: Option<&[Vec3]>, to: &[Vec3]) {
    let tangent = |points: &[Vec3], vertex: usize| {
        let (a, b) = (vertex.saturating_sub(1), (vertex + 1).min(points.len().saturating_sub(1)));
        (points[b] - points[a]).normalize_or_zero()
    };
    let rate = normals.rate;
    let Some(data) = normals.floats_mut() else { return }; // integer "normals" are no directions
    for (strand, range) in offsets.windows(2).map(|w| w[0] as usize..w[1] as usize).enumerate() {
        let elements: Vec<(usize, usize)> = match rate {
            AttributeRate::Vertex => range.clone().map(|i| (i, i - range.start)).collect(),
            AttributeRate::Strand => vec![(strand, 0)],
        };
        for (element, vertex) in elements {
            let new = tangent(&to[range.clone()], vertex);
            let value = &mut data[3 * element..3 * element + 3];
            let n = Vec3::from_slice(value);
            let turned = match from {
                Some(from) => {
                    let old = tangent(&from[range.clone()], vertex);
                    if old == Vec3::ZERO || new == Vec3::ZERO {
                        n
                    } else {
                        Quat::from_rotation_arc(old, new) * n
                    }
                }
                None => {
                    let across = n - new * n.dot(new);
                    across.normalize_or(n) * n.length()
                }
            };
            value.copy_from_slice(&turned.to_array());
        }
    }
}
