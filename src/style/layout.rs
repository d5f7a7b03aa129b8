//! Perm rods laid out over the part of the scalp the roots cover, so a recipe need not list
//! rods for one head: rows around the head's up axis from the crown down, or one spiral from
//! the crown. Each rod lies along its row, touching the scalp (the roots near it), and is two
//! spacings long; rows (and spiral turns) are a spacing apart. Pure and deterministic.
use std::f32::consts::TAU;

use glam::Vec3;

use super::head_frame::HeadFrame;
use super::recipe::Layout;

/// A laid-out rod: its end centres and radius, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LaidRod {
    pub a: Vec3,
    pub b: Vec3,
    pub radius: f32,
}

/// Rods of `diameter` a `spacing` apart (metres) over the scalp the `roots` cover, in the
/// `pattern` asked for ([`Layout::Nearest`] lays out nothing).
pub fn lay_out(
    frame: &HeadFrame,
    roots: &[Vec3],
    pattern: Layout,
    diameter: f32,
    spacing: f32,
) -> Vec<LaidRod> {
    // Everything in head coordinates: the scalp is close to the unit sphere there.
    let local: Vec<Vec3> = roots.iter().map(|&r| frame.to_head(r)).collect();
    let directions: Vec<Vec3> = local.iter().map(|p| p.normalize_or_zero()).collect();
    let step = spacing / frame.size();
    let radius = 0.5 * diameter / frame.size();
    let length = 2.0 * step;
    let lowest = directions.iter().map(|d| d.y.clamp(-1.0, 1.0).acos()).fold(0.0, f32::max);
    let last = lowest + 0.5 * step;
    let near = step.cos();

    // A rod centred over direction `u`, along `tangent`, if roots grow under it.
    let place = |u: Vec3, tangent: Vec3| -> Option<LaidRod> {
        let (sum, count) = local
            .iter()
            .zip(&directions)
            .filter(|(_, d)| d.dot(u) > near)
            .fold((0.0, 0usize), |(s, n), (p, _)| (s + p.length(), n + 1));
        if count == 0 {
            return None;
        }
        let centre = u * (sum / count as f32 + radius);
        let half = tangent.normalize() * (0.5 * length);
        Some(LaidRod {
            a: frame.point(centre - half),
            b: frame.point(centre + half),
            radius: radius * frame.size(),
        })
    };
    let on_sphere =
        |theta: f32, phi: f32| Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
    let along_row = |phi: f32| Vec3::new(-phi.sin(), 0.0, phi.cos());

    let mut rods = Vec::new();
    match pattern {
        Layout::Nearest => {}
        Layout::Rows => {
            let mut row = 0;
            loop {
                let theta = (row as f32 + 0.5) * step;
                if theta > last || theta > std::f32::consts::PI {
                    break;
                }
                // Rods with a half-length gap between them; odd rows staggered like bricks.
                let count = ((TAU * theta.sin() / (1.25 * length)).round() as usize).max(1);
                for k in 0..count {
                    let phi = TAU * (k as f32 + 0.5 * (row % 2) as f32) / count as f32;
                    rods.extend(place(on_sphere(theta, phi), along_row(phi)));
                }
                row += 1;
            }
        }
        Layout::Spiral => {
            // θ grows by one step per turn; walk in small angle steps, a rod every 1.25 lengths.
            let climb = step / TAU;
            let (mut phi, mut arc, mut next) = (0.0f32, 0.0f32, 0.0f32);
            let dphi = 0.01;
            loop {
                let theta = 0.5 * step + climb * phi;
                if theta > last || theta > std::f32::consts::PI {
                    break;
                }
                if arc >= next {
                    let du_dtheta = Vec3::new(theta.cos() * phi.cos(), -theta.sin(), theta.cos() * phi.sin());
                    let tangent = du_dtheta * climb + along_row(phi) * theta.sin();
                    rods.extend(place(on_sphere(theta, phi), tangent));
                    next += 1.25 * length;
                }
                arc += (climb * climb + theta.sin().powi(2)).sqrt() * dphi;
                phi += dphi;
            }
        }
    }
    rods
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::{generate, GenerateParams};
    use crate::style::head_frame::FrameOverrides;

    #[test]
    fn rows_and_spirals_cover_the_scalp_touching_it() {
        let groom = generate(&GenerateParams { strands: 400, seed: 2, ..Default::default() }).unwrap();
        let roots: Vec<Vec3> = (0..groom.strand_count()).map(|s| groom.strand_points(s)[0]).collect();
        let frame = HeadFrame::fit(&groom, None, &FrameOverrides::default()).unwrap();
        let head = crate::head::Head::default();
        for pattern in [Layout::Rows, Layout::Spiral] {
            let rods = lay_out(&frame, &roots, pattern, 0.02, 0.03);
            eprintln!("{pattern:?}: {} rods", rods.len());
            assert!((15..80).contains(&rods.len()), "{pattern:?}: {} rods", rods.len());
            for rod in &rods {
                assert!((rod.a.distance(rod.b) - 0.06).abs() < 1e-4 && (rod.radius - 0.01).abs() < 1e-6);
                // The rod's middle sits about one radius off the analytic head's surface.
                let middle = 0.5 * (rod.a + rod.b);
                let clearance = middle.length() - head.surface_point(middle.normalize()).length();
                assert!((0.0..0.02).contains(&clearance), "{pattern:?}: rod {clearance} m off the head");
            }
            // Every root has a rod within two spacings.
            let far = roots
                .iter()
                .filter(|&&r| rods.iter().all(|rod| (0.5 * (rod.a + rod.b)).distance(r) > 0.06))
                .count();
            assert!(far <= roots.len() / 50, "{pattern:?}: {far} roots far from every rod");
        }
        assert!(lay_out(&frame, &roots, Layout::Nearest, 0.02, 0.03).is_empty());
    }
}
