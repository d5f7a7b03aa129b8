//! Perm rods laid out over the part of the scalp the roots cover, so a recipe need not list
//! rods for one head: rows around the head's up axis from the crown down, or one spiral from
//! the crown. Each rod lies along its row, touching the scalp (the roots near it), and is two
//! spacings long; rows (and spiral turns) are a spacing apart. Pure and deterministic.
use std::f32::consts::{PI, TAU};

use glam::Vec3;

use super::head_frame::HeadFrame;
use super::ranges::MAX_OBSTACLES;
use super::recipe::Layout;

/// A laid-out rod: its end centres and radius, metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LaidRod {
    pub a: Vec3,
    pub b: Vec3,
    pub radius: f32,
}

/// The most rods a layout `step` head units apart can make on any scalp: a rod takes a step by
/// 1.25 rod lengths (2.5 steps) of the unit sphere's 4π, and each row (or the spiral's end) one
/// more for rounding.
pub fn most_rods(step: f32) -> f64 {
    let (step, pi) = (f64::from(step), std::f64::consts::PI);
    1.6 * pi / (step * step) + pi / step + 2.0
}

/// Why a layout `spacing` apart is refused, if it is: it could make more rods than a recipe may
/// list ([`MAX_OBSTACLES`]; each is tested against every vertex at every iteration). `size` is
/// metres per head unit when `spacing` is in metres, `None` when it is in head units.
pub fn too_many_rods(spacing: f32, size: Option<f32>) -> Option<String> {
    let step = spacing / size.unwrap_or(1.0);
    let most = most_rods(step);
    if most <= MAX_OBSTACLES as f64 {
        return None;
    }
    // The step at which `most_rods` is the limit: the positive root of (L − 2)s² − πs − 1.6π.
    let (limit, pi) = (MAX_OBSTACLES as f64 - 2.0, std::f64::consts::PI);
    let finest = (pi + (pi * pi + 6.4 * pi * limit).sqrt()) / (2.0 * limit);
    // Three significant digits, rounded up (the finest spacing allowed stays allowed).
    let up = |v: f64| {
        let unit = 10f64.powf(v.log10().floor() - 2.0);
        crate::validate::shortest(((v / unit).ceil() * unit) as f32 as f64)
    };
    let (unit, finest) = match size {
        Some(size) => (format!("m ({} head units on this head)", up(step.into())), finest * f64::from(size)),
        None => ("head units".to_string(), finest),
    };
    let finest_unit = if size.is_some() { "m on this head" } else { "head units" };
    Some(format!(
        "spacing = {} {unit} could lay out {} rods, more than the {MAX_OBSTACLES} a recipe may have: \
         the spacing must be at least {} {finest_unit}",
        crate::validate::shortest(spacing.into()),
        up(most),
        up(finest)
    ))
}

/// Rods of `diameter` a `spacing` apart (metres) over the scalp the `roots` cover, in the
/// `pattern` asked for ([`Layout::Nearest`] lays out nothing); refused ([`too_many_rods`]) when
/// they could be more than a recipe may have.
pub fn lay_out(
    frame: &HeadFrame,
    roots: &[Vec3],
    pattern: Layout,
    diameter: f32,
    spacing: f32,
) -> Result<Vec<LaidRod>, String> {
    if pattern != Layout::Nearest {
        if let Some(why) = too_many_rods(spacing, Some(frame.size())) {
            return Err(why);
        }
    }
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
                if theta > last || theta > PI {
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
            // The steps are counted, not summed: an f32 angle summed 0.01 at a time stops
            // growing above 2¹⁸ and the walk never ended.
            let climb = step / TAU;
            let dphi = 0.01;
            let walk = ((last.min(PI) - 0.5 * step) / (climb * dphi)).ceil().max(0.0) as u32;
            let (mut arc, mut next) = (0.0f32, 0.0f32);
            for i in 0..=walk {
                let phi = i as f32 * dphi;
                let theta = 0.5 * step + climb * phi;
                if theta > last || theta > PI {
                    break;
                }
                if arc >= next {
                    let du_dtheta = Vec3::new(theta.cos() * phi.cos(), -theta.sin(), theta.cos() * phi.sin());
                    let tangent = du_dtheta * climb + along_row(phi) * theta.sin();
                    rods.extend(place(on_sphere(theta, phi), tangent));
                    next += 1.25 * length;
                }
                arc += (climb * climb + theta.sin().powi(2)).sqrt() * dphi;
            }
        }
    }
    Ok(rods)
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
            let rods = lay_out(&frame, &roots, pattern, 0.02, 0.03).unwrap();
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
        assert!(lay_out(&frame, &roots, Layout::Nearest, 0.02, 0.03).unwrap().is_empty());
    }

    #[test]
    fn no_layout_makes_more_rods_than_the_bound_and_finer_ones_are_refused_at_once() {
        // Roots all over a unit head (a Fibonacci sphere, 0.03 rad apart): every rod finds roots.
        let n = 15_000;
        let roots: Vec<Vec3> = (0..n)
            .map(|i| {
                let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
                let phi = i as f32 * PI * (3.0 - 5.0f32.sqrt());
                let r = (1.0 - y * y).sqrt();
                Vec3::new(r * phi.cos(), y, r * phi.sin())
            })
            .collect();
        let frame = HeadFrame::new(Vec3::ZERO, Vec3::Y, Vec3::Z, 1.0).unwrap();
        let finest = [0.0726, 0.0727].into_iter().find(|&s| too_many_rods(s, None).is_none()).unwrap();
        for pattern in [Layout::Rows, Layout::Spiral] {
            for step in [finest, 0.1, 0.3, 1.0, 2.5] {
                let rods = lay_out(&frame, &roots, pattern, 0.5 * step, step).unwrap().len() as f64;
                let most = most_rods(step);
                eprintln!("{pattern:?} at {step}: {rods} rods, at most {most:.0}");
                assert!(rods <= most && rods > 0.5 * most - 10.0, "{pattern:?} at {step}: {rods} of {most}");
            }
        }
        assert!(too_many_rods(0.0725, None).is_some() && most_rods(finest) <= MAX_OBSTACLES as f64);
        // A micrometre spacing (the spiral's summed angle stalled, rows scanned 10¹⁰ positions).
        for (spacing, size) in [(2e-5, 1.0), (0.005, 0.1), (f32::MIN_POSITIVE, 1.0)] {
            let frame = HeadFrame::new(Vec3::ZERO, Vec3::Y, Vec3::Z, size).unwrap();
            for pattern in [Layout::Rows, Layout::Spiral] {
                let start = std::time::Instant::now();
                let why = lay_out(&frame, &roots, pattern, 0.5 * spacing, spacing).unwrap_err();
                assert!(why.starts_with(&format!("spacing = {}", crate::validate::shortest(spacing.into()))));
                assert!(why.contains("more than the 1000 a recipe may have"), "{why}");
                assert!(start.elapsed().as_secs_f32() < 0.1, "{why}");
            }
        }
    }
}
