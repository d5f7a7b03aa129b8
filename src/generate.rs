//! Procedural sample grooms: roots scattered over the scalp of the analytic head, strands grown
//! along the scalp normal, laid along the scalp and drooping under their own weight, with a
//! straight, wavy or curly style. Deterministic: the same parameters give the same groom, on any
//! number of threads (every strand draws from its own seeded generator).
use std::f32::consts::TAU;

use glam::{Quat, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::groom::Groom;
use crate::head::Head;

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", tag = "kind")]
pub enum Style {
    Straight,
    /// A planar wave of the given amplitude and wavelength (metres).
    Wavy {
        amplitude: f32,
        wavelength: f32,
    },
    /// A helix of the given radius and pitch (axial advance per turn, metres).
    Curly {
        radius: f32,
        pitch: f32,
    },
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GenerateParams {
    pub strands: usize,
    /// Mean strand length in metres.
    pub length: f32,
    /// Relative spread of lengths: each strand is `length · (1 ± variation)`.
    pub length_variation: f32,
    pub vertices_per_strand: usize,
    pub style: Style,
    /// Root diameter in metres; strands taper linearly to half of it at the tip.
    pub root_width: f32,
    /// How fast strands turn downwards, in radians per metre of strand.
    pub droop: f32,
    pub seed: u64,
    pub head: Head,
}

impl Default for GenerateParams {
    fn default() -> Self {
        GenerateParams {
            strands: 1000,
            length: 0.24,
            length_variation: 0.0,
            vertices_per_strand: 9,
            style: Style::Straight,
            root_width: 80e-6,
            droop: 14.0,
            seed: 1,
            head: Head::default(),
        }
    }
}

/// Distance above the scalp (metres) that grown strands keep.
const SCALP_CLEARANCE: f32 = 0.002;

impl GenerateParams {
    pub fn check(&self) -> Result<()> {
        let bad = |what: &str| Err(Error::Usage(format!("generate: {what}")));
        if self.strands == 0 {
            return bad("--strands must be at least 1");
        }
        if self.strands > 50_000_000 {
            return bad("--strands must be at most 50,000,000");
        }
        if !(self.length.is_finite() && self.length > 0.0) {
            return bad("--length must be a positive number of metres");
        }
        if !(0.0..1.0).contains(&self.length_variation) {
            return bad("--length-variation must be in [0, 1)");
        }
        if !(2..=10_000).contains(&self.vertices_per_strand) {
            return bad("--vertices must be between 2 and 10,000");
        }
        if !(self.root_width.is_finite() && self.root_width >= 0.0) {
            return bad("--width must be a non-negative number of metres");
        }
        if !(self.droop.is_finite() && self.droop >= 0.0) {
            return bad("--droop must be non-negative");
        }
        match self.style {
            Style::Straight => {}
            Style::Wavy { amplitude, wavelength } => {
                if !(amplitude.is_finite() && amplitude >= 0.0 && wavelength.is_finite() && wavelength > 0.0)
                {
                    return bad("wave amplitude must be >= 0 and wavelength > 0");
                }
            }
            Style::Curly { radius, pitch } => {
                if !(radius.is_finite() && radius > 0.0 && pitch.is_finite() && pitch > 0.0) {
                    return bad("curl radius and pitch must be positive");
                }
            }
        }
        Ok(())
    }
}

/// Generates a groom; fails only on parameters outside their ranges.
pub fn generate(params: &GenerateParams) -> Result<Groom> {
    params.check()?;
    let roots = scatter_roots(&params.head, params.strands, params.seed);
    let strands: Vec<Vec<Vec3>> =
        roots.par_iter().enumerate().map(|(i, &dir)| grow_strand(params, i, dir)).collect();

    let mut groom = Groom::from_strands(&strands, params.root_width);
    for strand in 0..groom.strand_count() {
        let range = groom.strand_range(strand);
        let last = (range.len() - 1) as f32;
        for (k, width) in groom.widths[range].iter_mut().enumerate() {
            *width = params.root_width * (1.0 - 0.5 * k as f32 / last);
        }
    }
    groom.root_uvs = Some(roots.iter().map(|&dir| params.head.scalp_uv(dir)).collect());
    groom.validate()?;
    Ok(groom)
}

/// A generator for one stream of the seed (strand `index`, or the scatter stage), independent of
/// the order in which streams are used.
fn stream(seed: u64, index: u64) -> Pcg64Mcg {
    // SplitMix64 finaliser: decorrelates neighbouring seeds and indices.
    let mut z = seed ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    Pcg64Mcg::seed_from_u64(z ^ (z >> 31))
}

const SCATTER_STREAM: u64 = u64::MAX;

/// Unit directions from the head centre to `count` roots on the scalp: a randomly rotated
/// Fibonacci lattice (stratified, near blue-noise) with a little jitter, clipped to the scalp.
/// The lattice is sized so that at least `count` points land on the scalp; the few extra are
/// dropped at random.
pub fn scatter_roots(head: &Head, count: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = stream(seed, SCATTER_STREAM);
    let rotation = random_rotation(&mut rng);
    let jitter_seed: u64 = rng.random();

    let lattice = |size: usize| -> Vec<Vec3> {
        let spacing = (2.0 * TAU / size as f32).sqrt();
        (0..size)
            .filter_map(|k| {
                let mut jitter = stream(jitter_seed, k as u64);
                let dir = rotation * fibonacci_point(k, size);
                let offset = Vec3::new(jitter.random(), jitter.random(), jitter.random()) - 0.5;
                let dir = (dir + offset * (0.5 * spacing)).normalize();
                head.is_scalp(dir).then_some(dir)
            })
            .collect()
    };

    // The scalp covers a fixed fraction of directions; grow the lattice until it holds enough.
    let probe = 20_000;
    let fraction = (lattice(probe).len() as f64 / probe as f64).max(1e-3);
    let mut size = ((count as f64 / fraction).ceil() as usize).max(count);
    let mut points = lattice(size);
    while points.len() < count {
        size += ((count - points.len()) as f64 / fraction).ceil() as usize;
        points = lattice(size);
    }
    while points.len() > count {
        let victim = rng.random_range(0..points.len());
        points.remove(victim);
    }
    points
}

fn fibonacci_point(k: usize, size: usize) -> Vec3 {
    let golden_angle = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let y = 1.0 - (2 * k + 1) as f32 / size as f32;
    let r = (1.0 - y * y).max(0.0).sqrt();
    let phi = golden_angle * k as f32;
    Vec3::new(r * phi.cos(), y, r * phi.sin())
}

fn random_rotation(rng: &mut Pcg64Mcg) -> Quat {
    // Shoemake's uniform random unit quaternion.
    let (u1, u2, u3): (f32, f32, f32) = (rng.random(), rng.random(), rng.random());
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    Quat::from_xyzw(a * (TAU * u2).sin(), a * (TAU * u2).cos(), b * (TAU * u3).sin(), b * (TAU * u3).cos())
        .normalize()
}

/// Grows one strand from the root in direction `dir` of the head centre.
fn grow_strand(params: &GenerateParams, index: usize, dir: Vec3) -> Vec<Vec3> {
    let head = &params.head;
    let mut rng = stream(params.seed, index as u64);
    let spread: f32 = rng.random_range(-1.0..=1.0);
    let length = params.length * (1.0 + params.length_variation * spread);
    let segments = params.vertices_per_strand - 1;
    let step = length / segments as f32;
    let phase: f32 = rng.random_range(0.0..TAU);

    let root = head.surface_point(dir);
    let normal = head.normal_at(root);
    // Strands fall away from the face: where the normal is vertical, lean them backwards.
    let horizontal = Vec3::new(normal.x, 0.0, normal.z);
    let away = if horizontal.length() > 0.2 { horizontal.normalize() } else { Vec3::NEG_Z };
    let fall = (Vec3::NEG_Y + 0.35 * away).normalize();

    // Centre-line direction and a frame around it, parallel-transported as it turns.
    let mut centre = normal;
    let mut side = centre.any_orthonormal_vector();
    side = Quat::from_axis_angle(centre, phase) * side;

    let mut points = Vec::with_capacity(params.vertices_per_strand);
    points.push(root);
    let mut p = root;
    for k in 0..segments {
        let s = (k as f32 + 0.5) * step;
        let binormal = centre.cross(side);
        let tangent = match params.style {
            Style::Straight => centre,
            Style::Wavy { amplitude, wavelength } => {
                let max_angle = (TAU * amplitude / wavelength).atan();
                let angle = max_angle * (TAU * s / wavelength + phase).sin();
                centre * angle.cos() + side * angle.sin()
            }
            Style::Curly { radius, pitch } => {
                let pitch_angle = (TAU * radius / pitch).atan();
                let theta = s * pitch_angle.sin() / radius + phase;
                centre * pitch_angle.cos() + (binormal * theta.cos() - side * theta.sin()) * pitch_angle.sin()
            }
        };
        let mut next = p + tangent * step;
        let pushed = head.push_out(next, SCALP_CLEARANCE);
        if pushed != next {
            next = p + (pushed - p).normalize() * step;
            // Lay the centre line along the scalp instead of into it.
            let n = head.normal_at(head.push_out(next, 0.0));
            let along = centre - n * centre.dot(n).min(0.0);
            if along.length() > 1e-4 {
                let turn = Quat::from_rotation_arc(centre, along.normalize());
                centre = (turn * centre).normalize();
                side = (turn * side).normalize();
            }
        }
        points.push(next);
        p = next;

        // Droop: turn the centre line towards the fall direction by at most droop·step radians.
        let angle = centre.angle_between(fall);
        if angle > 1e-6 {
            let turn_by = angle.min(params.droop * step);
            let axis = centre.cross(fall);
            let axis = if axis.length() > 1e-6 { axis.normalize() } else { side };
            let turn = Quat::from_axis_angle(axis, turn_by);
            centre = (turn * centre).normalize();
            side = (turn * side).normalize();
        }
        side = (side - centre * side.dot(centre)).normalize();
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn roots_are_exactly_counted_on_the_scalp() {
        let head = Head::default();
        for count in [1, 7, 200, 1000] {
            let roots = scatter_roots(&head, count, 42);
            assert_eq!(roots.len(), count);
            assert!(roots.iter().all(|&d| head.is_scalp(d) && (d.length() - 1.0).abs() < 1e-5));
        }
    }

    #[test]
    fn roots_are_spread_out() {
        // A stratified scatter keeps neighbours apart: no two of 500 roots closer than a fifth
        // of the mean spacing (white noise would put many pairs far closer).
        let head = Head::default();
        let roots = scatter_roots(&head, 500, 3);
        let mean_spacing = (2.0 * std::f32::consts::PI * 0.6 / 500.0).sqrt();
        let mut closest = f32::MAX;
        for i in 0..roots.len() {
            for j in 0..i {
                closest = closest.min(roots[i].distance(roots[j]));
            }
        }
        assert!(closest > 0.2 * mean_spacing, "closest pair {closest}, mean spacing {mean_spacing}");
    }

    #[test]
    fn strands_have_the_requested_length_and_stay_out_of_the_head() {
        for style in [
            Style::Straight,
            Style::Wavy { amplitude: 0.01, wavelength: 0.05 },
            Style::Curly { radius: 0.01, pitch: 0.03 },
        ] {
            let params = GenerateParams { strands: 50, vertices_per_strand: 24, style, ..Default::default() };
            let groom = generate(&params).unwrap();
            for s in 0..groom.strand_count() {
                let length = groom.strand_length(s);
                assert!((length - 0.24).abs() < 0.24 * 1e-3, "{style:?}: strand {s} is {length} m");
                for &p in &groom.strand_points(s)[1..] {
                    assert!(params.head.implicit(p) > 0.98, "{style:?}: strand {s} enters the head");
                }
            }
        }
    }
}
