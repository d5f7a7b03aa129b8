//! Shape measurements of strands, for reports and for tests that check styling against analytic
//! predictions: curvature, the radius of a curl, and resampling.
use glam::{DVec3, Vec3};

use crate::groom::{Attribute, AttributeRate, Groom};

/// Mean curvature of a polyline: total turning angle over length (1/m).
pub fn mean_curvature(points: &[Vec3]) -> f32 {
    if points.len() < 3 {
        return 0.0;
    }
    let mut turning = 0.0;
    for w in points.windows(3) {
        turning += (w[1] - w[0]).angle_between(w[2] - w[1]);
    }
    let length: f32 = points.windows(2).map(|w| w[0].distance(w[1])).sum();
    // Turning happens at interior vertices; measure over the span between the first and last.
    let span = length
        - 0.5 * (points[0].distance(points[1]) + points[points.len() - 2].distance(points[points.len() - 1]));
    if span > 0.0 {
        turning / span
    } else {
        0.0
    }
}

/// Radius of the curl a polyline makes: the points are projected on the plane across the curl's
/// axis (the mean binormal, which for a helix points along its axis) and a circle is fitted to
/// them by least squares (Kåsa). `None` for a polyline too short or too straight to tell: one
/// whose fitted circle turns less than [`STRAIGHT_TURN`] along its length (a straight strand's
/// rounding errors fitted a radius of 10¹⁰ m).
pub fn curl_radius(points: &[Vec3]) -> Option<f32> {
    if points.len() < 4 {
        return None;
    }
    let p: Vec<DVec3> = points.iter().map(|p| p.as_dvec3()).collect();
    let mut axis = DVec3::ZERO;
    for w in p.windows(3) {
        axis += (w[1] - w[0]).cross(w[2] - w[1]);
    }
    let axis = axis.try_normalize()?;
    let u = axis.any_orthonormal_vector();
    let v = axis.cross(u);
    let mean = p.iter().copied().sum::<DVec3>() / p.len() as f64;
    // Minimise Σ (x² + y² + D·x + E·y + F)² over the projected, centred points.
    let mut m = [[0.0f64; 3]; 3];
    let mut rhs = [0.0f64; 3];
    for q in &p {
        let (x, y) = ((*q - mean).dot(u), (*q - mean).dot(v));
        let row = [x, y, 1.0];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] += row[i] * row[j];
            }
            rhs[i] -= row[i] * (x * x + y * y);
        }
    }
    let [d, e, f] = solve3(m, rhs)?;
    let r2 = (d * d + e * e) / 4.0 - f;
    let length: f64 = p.windows(2).map(|w| w[0].distance(w[1])).sum();
    (r2 > 0.0 && length > STRAIGHT_TURN * r2.sqrt()).then(|| r2.sqrt() as f32)
}

/// The turn, radians, below which a strand's curl is no curl: a hundredth of a radian along a
/// 24 cm strand is a radius of 24 m.
pub const STRAIGHT_TURN: f64 = 0.01;

#[allow(clippy::needless_range_loop)] // index loops read clearest for Gaussian elimination
fn solve3(mut m: [[f64; 3]; 3], mut b: [f64; 3]) -> Option<[f64; 3]> {
    for col in 0..3 {
        let pivot = (col..3).max_by(|&a, &c| m[a][col].abs().total_cmp(&m[c][col].abs()))?;
        if m[pivot][col].abs() < 1e-300 {
            return None;
        }
        m.swap(col, pivot);
        b.swap(col, pivot);
        for row in col + 1..3 {
            let factor = m[row][col] / m[col][col];
            for k in col..3 {
                m[row][k] -= factor * m[col][k];
            }
            b[row] -= factor * b[col];
        }
    }
    let mut x = [0.0; 3];
    for row in (0..3).rev() {
        let sum: f64 = (row + 1..3).map(|k| m[row][k] * x[k]).sum();
        x[row] = (b[row] - sum) / m[row][row];
    }
    Some(x)
}

/// Resamples every strand at equal arc-length steps no longer than `max_segment`, keeping root
/// and tip, in a count of points its basis takes (3k + 1 for Bézier curves). Widths and
/// per-vertex attributes are interpolated along the arc; strands already fine enough are
/// resampled too, so spacing is uniform.
pub fn resample_groom(groom: &Groom, max_segment: f32) -> Groom {
    let mut out = Groom {
        strand_offsets: vec![0],
        strand_ids: groom.strand_ids.clone(),
        root_uvs: groom.root_uvs.clone(),
        guides: groom.guides.clone(),
        basis: groom.basis,
        groups: groom.groups.clone(),
        group_ids: groom.group_ids.clone(),
        meshes: groom.meshes.clone(),
        ..Default::default()
    };
    let vertex_attributes: Vec<&Attribute> =
        groom.attributes.iter().filter(|a| a.rate == AttributeRate::Vertex).collect();
    let sources: Vec<std::borrow::Cow<[f32]>> = vertex_attributes.iter().map(|a| a.floats()).collect();
    let mut data: Vec<Vec<f32>> = vec![Vec::new(); vertex_attributes.len()];
    for strand in 0..groom.strand_count() {
        let range = groom.strand_range(strand);
        let points = &groom.points[range.clone()];
        let mut arc = vec![0.0f32; points.len()];
        for i in 1..points.len() {
            arc[i] = arc[i - 1] + points[i - 1].distance(points[i]);
        }
        let length = arc[points.len() - 1];
        // Still a whole curve of its basis: a Bézier strand keeps 3k + 1 points, a cubic one 4.
        let group = groom.group(groom.group_of(strand));
        // A hundredth of a percent of slack: a strand of a round length (48 cm at 4 mm: 120
        // segments) would otherwise get 120 or 121 by the float noise of where it sits (moved
        // 1 m, or read in centimetres), and its curls with them.
        let mut segments = ((length / max_segment * (1.0 - 1e-4)).ceil() as usize).max(1);
        while !crate::primvar_rates::is_whole_curve(group.basis, group.wrap, segments + 1) {
            segments += 1;
        }
        let mut edge = 0;
        for k in 0..=segments {
            let s = length * k as f32 / segments as f32;
            while edge + 2 < points.len() && arc[edge + 1] < s {
                edge += 1;
            }
            let span = arc[edge + 1] - arc[edge];
            let t = if span > 0.0 { ((s - arc[edge]) / span).clamp(0.0, 1.0) } else { 0.0 };
            let (a, b) = (range.start + edge, range.start + edge + 1);
            let point =
                if k == segments { points[points.len() - 1] } else { points[edge].lerp(points[edge + 1], t) };
            out.points.push(point);
            out.widths.push(groom.widths[a] + (groom.widths[b] - groom.widths[a]) * t);
            for ((attribute, source), values) in vertex_attributes.iter().zip(&sources).zip(&mut data) {
                let c = attribute.components;
                for j in 0..c {
                    let (x, y) = (source[a * c + j], source[b * c + j]);
                    values.push(x + (y - x) * t);
                }
            }
        }
        out.strand_offsets.push(out.points.len() as u32);
    }
    for attribute in &groom.attributes {
        if attribute.rate == AttributeRate::Strand {
            out.set_attribute(attribute.clone());
        }
    }
    for (attribute, values) in vertex_attributes.into_iter().zip(data) {
        out.set_attribute(Attribute::new(
            attribute.name.clone(),
            AttributeRate::Vertex,
            attribute.components,
            values,
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strand of a round length (48 cm at 4 mm, 120 segments) resamples to 121 vertices
    /// wherever it sits and in whatever unit it came: moved up to 10 m, or read in centimetres
    /// and scaled, its measured length lands a few ulps either side of 120 segments.
    #[test]
    fn a_round_length_resamples_to_the_same_count_anywhere() {
        let strand: Vec<Vec3> =
            (0..=24).map(|i| Vec3::new(0.003 * (i % 2) as f32, -0.02 * i as f32, 0.1)).collect();
        let length: f32 = strand.windows(2).map(|w| w[0].distance(w[1])).sum();
        let max_segment = length / 120.0;
        let mut counts = std::collections::BTreeSet::new();
        for k in 0..200 {
            let offset = Vec3::new(0.37 * k as f32, 0.05 * k as f32, -0.11 * k as f32) * 0.13;
            let scale = if k % 2 == 0 { 1.0 } else { 100.0 };
            let points: Vec<Vec3> = strand.iter().map(|&p| (p + offset) * scale).collect();
            let groom = Groom {
                widths: vec![1e-4; points.len()],
                strand_offsets: vec![0, points.len() as u32],
                strand_ids: vec![0],
                points,
                ..Default::default()
            };
            counts.insert(resample_groom(&groom, max_segment * scale).points.len());
        }
        assert_eq!(counts.into_iter().collect::<Vec<_>>(), vec![121]);
    }

    fn helix(radius: f32, pitch: f32, turns: f32, n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let phi = std::f32::consts::TAU * turns * i as f32 / (n - 1) as f32;
                Vec3::new(radius * phi.cos(), pitch * phi / std::f32::consts::TAU, radius * phi.sin())
            })
            .collect()
    }

    #[test]
    fn curl_radius_of_helices_and_arcs() {
        let r = curl_radius(&helix(0.02, 0.004, 3.0, 200)).unwrap();
        assert!((r - 0.02).abs() < 2e-4, "{r}");
        // Half a turn of a circle.
        let r = curl_radius(&helix(0.05, 0.0, 0.5, 30)).unwrap();
        assert!((r - 0.05).abs() < 1e-4, "{r}");
        let straight: Vec<Vec3> = (0..10).map(|i| Vec3::X * i as f32).collect();
        assert_eq!(curl_radius(&straight), None);
        // Straight but for f32 rounding (a generated strand, resampled): no curl of 10¹⁰ m.
        let rounded: Vec<Vec3> = (0..100)
            .map(|i| Vec3::new(0.013, 0.101, -0.047) + Vec3::new(0.3, -0.9, 0.1) * (0.0024 * i as f32))
            .collect();
        assert_eq!(curl_radius(&rounded), None);
        // An arc of 0.02 rad is a curl; one of 0.005 rad is not.
        let r = curl_radius(&helix(10.0, 0.0, 0.02 / std::f32::consts::TAU, 30)).unwrap();
        assert!((r - 10.0).abs() < 0.5, "{r}");
        assert_eq!(curl_radius(&helix(10.0, 0.0, 0.005 / std::f32::consts::TAU, 30)), None);
    }

    #[test]
    fn mean_curvature_of_a_circle_is_one_over_its_radius() {
        let k = mean_curvature(&helix(0.05, 0.0, 1.0, 400));
        assert!((k - 20.0).abs() < 0.1, "{k}");
    }

    #[test]
    fn resampling_keeps_ends_length_and_interpolates_attributes() {
        let mut groom =
            Groom::from_strands(&[vec![Vec3::ZERO, Vec3::X * 0.1, Vec3::new(0.1, 0.07, 0.0)]], 1e-4);
        groom.widths = vec![1e-4, 0.5e-4, 0.0];
        groom.set_attribute(Attribute::new("w", AttributeRate::Vertex, 1, vec![0.0, 1.0, 1.0]));
        let out = resample_groom(&groom, 0.01);
        assert!(out.validate().is_ok());
        assert_eq!(out.vertex_count(), 17 + 1);
        assert_eq!(out.points[0], Vec3::ZERO);
        assert_eq!(*out.points.last().unwrap(), Vec3::new(0.1, 0.07, 0.0));
        assert!((out.strand_length(0) - 0.17).abs() < 1e-5);
        for w in out.points.windows(2) {
            assert!(w[0].distance(w[1]) <= 0.01 + 1e-6);
        }
        // 0.05 m along the first edge: halfway in width and attribute.
        let mid = out.points.iter().position(|p| (p.x - 0.05).abs() < 1e-4).unwrap();
        assert!((out.widths[mid] - 0.75e-4).abs() < 1e-9);
        assert!((out.attribute("w").unwrap().floats()[mid] - 0.5).abs() < 1e-5);
    }
}
