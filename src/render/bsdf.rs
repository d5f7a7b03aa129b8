//! Scattering functions: Kajiya–Kay for hair (model.md §4), Lambert for the head and the floor.
//!
//! A hair fibre is a thin cylinder with unit tangent `t`. Directions are described by their
//! longitudinal angle θ to the fibre's normal plane (`sin θ = t·ω`) and an azimuth φ around it.
//! Light leaving towards `ωo` is `∫ S(ωi, ωo) L(ωi) cos θi dωi`, so a BSDF here returns the
//! product `S · cos θi` ("value") together with the density its sampler draws `ωi` from.
//!
//! Kajiya–Kay has two terms (both ω pointing away from the fibre):
//! - diffuse `∝ sin(t, ωi) = cos θi`: a constant `S = ρd / π²`, whose `∫ S cos θi dω` is exactly
//!   `ρd`. It is sampled exactly: `sin θi` is the x coordinate of a uniform point in the unit disk
//!   (density `(2/π)√(1 − s²)`), φ is uniform, so the sample weight is `ρd` itself.
//! - specular `max(0, cos θi cos θo − sin θi sin θo)^p = cos^p(θi + θo)`: largest on the mirror
//!   cone `θi = −θo`. coif uses it, shifted by a tilt α, as a normalised longitudinal lobe
//!   `g(δ) = cos^p(δ) / ∫cos^p`, `δ = θi + θo − α`, uniform in azimuth:
//!   `S = ρs g(δ) / (2π cos² θi)`, whose integral is `ρs` less what falls past the poles. It is
//!   sampled from a tabulated inverse CDF of `g`.
//!
//! Two specular lobes give the familiar look: a white primary highlight (surface reflection,
//! tilted towards the root) and a coloured, broader secondary one (light through the fibre,
//! tilted towards the tip). Lobe weights sum to at most 1 per channel, so energy is conserved.
use std::f32::consts::{FRAC_PI_2, PI, TAU};

use glam::Vec3;

use super::hair_bsdf::ChiangHair;

/// Bins of the tabulated specular lobe over δ ∈ [−π/2, π/2].
const LOBE_BINS: usize = 1024;

/// A normalised `cos^p` lobe over [−π/2, π/2] with a tabulated sampler.
#[derive(Clone, Debug)]
pub struct CosPowerLobe {
    exponent: f32,
    norm: f32,
    /// Cumulative bin weights, last = 1.
    cdf: Vec<f32>,
    /// Piecewise-constant density per bin (per radian).
    density: Vec<f32>,
}

impl CosPowerLobe {
    pub fn new(exponent: f32) -> CosPowerLobe {
        let width = PI / LOBE_BINS as f32;
        // Integrate each bin with Simpson's rule in f64 so the table is accurate for sharp lobes.
        let f = |d: f64| d.cos().max(0.0).powf(exponent as f64);
        let weights: Vec<f64> = (0..LOBE_BINS)
            .map(|i| {
                let a = -std::f64::consts::FRAC_PI_2 + i as f64 * width as f64;
                let b = a + width as f64;
                (b - a) / 6.0 * (f(a) + 4.0 * f(0.5 * (a + b)) + f(b))
            })
            .collect();
        let total: f64 = weights.iter().sum();
        let mut running = 0.0;
        let cdf = weights
            .iter()
            .map(|w| {
                running += w / total;
                running as f32
            })
            .collect();
        let density = weights.iter().map(|w| (w / total / width as f64) as f32).collect();
        CosPowerLobe { exponent, norm: (1.0 / total) as f32, cdf, density }
    }

    /// The normalised lobe `cos^p(δ) / ∫cos^p` (zero outside [−π/2, π/2]).
    pub fn eval(&self, delta: f32) -> f32 {
        if delta.abs() >= FRAC_PI_2 {
            return 0.0;
        }
        delta.cos().powf(self.exponent) * self.norm
    }

    /// Density with which [`CosPowerLobe::sample`] draws δ.
    pub fn pdf(&self, delta: f32) -> f32 {
        if delta.abs() >= FRAC_PI_2 {
            return 0.0;
        }
        let bin = (((delta + FRAC_PI_2) / PI) * LOBE_BINS as f32) as usize;
        self.density[bin.min(LOBE_BINS - 1)]
    }

    /// Draws δ from the tabulated lobe.
    pub fn sample(&self, u: f32) -> f32 {
        let bin = self.cdf.partition_point(|&c| c <= u).min(LOBE_BINS - 1);
        let lo = if bin == 0 { 0.0 } else { self.cdf[bin - 1] };
        let hi = self.cdf[bin];
        let within = if hi > lo { ((u - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
        -FRAC_PI_2 + (bin as f32 + within) * (PI / LOBE_BINS as f32)
    }
}

/// Shape parameters of the hair lobes, shared by every fibre in a render.
#[derive(Clone, Debug)]
pub struct HairLobes {
    pub primary: CosPowerLobe,
    pub secondary: CosPowerLobe,
    /// Tilt of the primary highlight (radians; negative = towards the root).
    pub primary_shift: f32,
    pub secondary_shift: f32,
    /// Weight of the white primary highlight.
    pub primary_weight: f32,
    /// Fraction of the remaining (coloured) energy in the secondary highlight.
    pub secondary_fraction: f32,
}

impl Default for HairLobes {
    fn default() -> Self {
        HairLobes {
            primary: CosPowerLobe::new(120.0),
            secondary: CosPowerLobe::new(24.0),
            primary_shift: (-5.0f32).to_radians(),
            secondary_shift: 8.0f32.to_radians(),
            primary_weight: 0.06,
            secondary_fraction: 0.25,
        }
    }
}

/// The result of evaluating or sampling a BSDF for one pair of directions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    pub direction: Vec3,
    /// `value / pdf`: the throughput factor.
    pub weight: Vec3,
    pub pdf: f32,
}

/// A Kajiya–Kay fibre: tangent, colour (albedo) and the shared lobes.
#[derive(Clone, Copy, Debug)]
pub struct KajiyaKay<'a> {
    pub tangent: Vec3,
    pub diffuse: Vec3,
    pub primary: f32,
    pub secondary: Vec3,
    pub lobes: &'a HairLobes,
}

/// Longitudinal angle of a direction to the fibre's normal plane.
#[inline]
fn theta(tangent: Vec3, w: Vec3) -> (f32, f32) {
    let s = tangent.dot(w).clamp(-1.0, 1.0);
    (s.asin(), (1.0 - s * s).max(0.0).sqrt())
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Shortest cosine of θi in a specular lobe's denominator: keeps a grazing evaluation finite.
const MIN_COS: f32 = 1e-3;

impl<'a> KajiyaKay<'a> {
    /// A fibre of linear-RGB `color` (each channel in [0, 1]): the white primary highlight takes
    /// its share first, the rest is split between diffuse and the coloured secondary highlight.
    pub fn new(tangent: Vec3, color: Vec3, lobes: &'a HairLobes) -> KajiyaKay<'a> {
        let color = color.clamp(Vec3::ZERO, Vec3::ONE);
        let rest = 1.0 - lobes.primary_weight;
        KajiyaKay {
            tangent,
            diffuse: color * rest * (1.0 - lobes.secondary_fraction),
            primary: lobes.primary_weight,
            secondary: color * rest * lobes.secondary_fraction,
            lobes,
        }
    }

    fn lobe_probabilities(&self) -> [f32; 3] {
        let w = [luminance(self.diffuse), self.primary, luminance(self.secondary)];
        let total = w[0] + w[1] + w[2];
        if total <= 0.0 {
            return [1.0, 0.0, 0.0];
        }
        [w[0] / total, w[1] / total, w[2] / total]
    }

    /// `S · cos θi` and the sampling density of `wi`, for light arriving from `wi` and leaving
    /// towards `wo`.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let (theta_o, _) = theta(self.tangent, wo);
        let (theta_i, cos_i) = theta(self.tangent, wi);
        let p = self.lobe_probabilities();
        let spec_denominator = TAU * cos_i.max(MIN_COS);
        let delta1 = theta_i + theta_o - self.lobes.primary_shift;
        let delta2 = theta_i + theta_o - self.lobes.secondary_shift;
        let value = self.diffuse * (cos_i / (PI * PI))
            + Vec3::splat(self.primary * self.lobes.primary.eval(delta1) / spec_denominator)
            + self.secondary * (self.lobes.secondary.eval(delta2) / spec_denominator);
        let pdf = p[0] * cos_i / (PI * PI)
            + p[1] * self.lobes.primary.pdf(delta1) / spec_denominator
            + p[2] * self.lobes.secondary.pdf(delta2) / spec_denominator;
        (value, pdf)
    }

    /// Draws an incoming direction for outgoing `wo` from the lobe mixture; `u_lobe` picks the
    /// lobe and the azimuth, `u` the longitudinal angle.
    pub fn sample(&self, wo: Vec3, u_lobe: [f32; 2], u: [f32; 2]) -> Option<BsdfSample> {
        let p = self.lobe_probabilities();
        let phi = TAU * u_lobe[1];
        let sin_theta_i = if u_lobe[0] < p[0] {
            // x of a uniform point in the unit disk: density ∝ √(1 − s²).
            u[0].sqrt() * (TAU * u[1]).cos()
        } else {
            let (theta_o, _) = theta(self.tangent, wo);
            let (lobe, shift) = if u_lobe[0] < p[0] + p[1] {
                (&self.lobes.primary, self.lobes.primary_shift)
            } else {
                (&self.lobes.secondary, self.lobes.secondary_shift)
            };
            let theta_i = lobe.sample(u[0]) - theta_o + shift;
            if theta_i.abs() >= FRAC_PI_2 {
                return None;
            }
            theta_i.sin()
        };
        let cos_theta_i = (1.0 - sin_theta_i * sin_theta_i).max(0.0).sqrt();
        let (b1, b2) = self.tangent.any_orthonormal_pair();
        let direction =
            (self.tangent * sin_theta_i + (b1 * phi.cos() + b2 * phi.sin()) * cos_theta_i).normalize();
        let (value, pdf) = self.eval(wo, direction);
        if pdf <= 0.0 {
            return None;
        }
        Some(BsdfSample { direction, weight: value / pdf, pdf })
    }
}

/// A Lambertian surface with shading normal `normal` (either side scatters).
#[derive(Clone, Copy, Debug)]
pub struct Lambert {
    pub normal: Vec3,
    pub albedo: Vec3,
}

impl Lambert {
    /// The normal flipped to the side `wo` lies on.
    fn facing(&self, wo: Vec3) -> Vec3 {
        if self.normal.dot(wo) >= 0.0 {
            self.normal
        } else {
            -self.normal
        }
    }

    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let cos = self.facing(wo).dot(wi);
        if cos <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        (self.albedo * (cos / PI), cos / PI)
    }

    /// Cosine-weighted hemisphere sampling on `wo`'s side: the weight is the albedo.
    pub fn sample(&self, wo: Vec3, u: [f32; 2]) -> Option<BsdfSample> {
        let n = self.facing(wo);
        let r = u[0].sqrt();
        let phi = TAU * u[1];
        let z = (1.0 - u[0]).max(0.0).sqrt();
        let (b1, b2) = n.any_orthonormal_pair();
        let direction = (n * z + b1 * (r * phi.cos()) + b2 * (r * phi.sin())).normalize();
        let pdf = n.dot(direction) / PI;
        (pdf > 0.0).then_some(BsdfSample { direction, weight: self.albedo, pdf })
    }
}

/// A surface's scattering: hair (Kajiya–Kay or Chiang) or diffuse.
#[derive(Clone, Copy, Debug)]
pub enum Bsdf<'a> {
    Hair(KajiyaKay<'a>),
    Chiang(ChiangHair<'a>),
    Diffuse(Lambert),
}

impl Bsdf<'_> {
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        match self {
            Bsdf::Hair(b) => b.eval(wo, wi),
            Bsdf::Chiang(b) => b.eval(wo, wi),
            Bsdf::Diffuse(b) => b.eval(wo, wi),
        }
    }

    pub fn sample(&self, wo: Vec3, u_lobe: [f32; 2], u: [f32; 2]) -> Option<BsdfSample> {
        match self {
            Bsdf::Hair(b) => b.sample(wo, u_lobe, u),
            Bsdf::Chiang(b) => b.sample(wo, u_lobe, u),
            Bsdf::Diffuse(b) => b.sample(wo, u),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::{Sampler, SamplerKind};

    fn uniform_sphere(u: [f32; 2]) -> Vec3 {
        let z = 1.0 - 2.0 * u[0];
        let r = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new(r * (TAU * u[1]).cos(), r * (TAU * u[1]).sin(), z)
    }

    /// Albedo `∫ S cos θi dωi` by uniform sphere sampling (independent of the BSDF's sampler)
    /// and by the BSDF's own importance sampling.
    fn albedos(bsdf: &KajiyaKay, wo: Vec3, n: u32) -> (Vec3, Vec3) {
        let mut uniform = Vec3::ZERO;
        let mut importance = Vec3::ZERO;
        for i in 0..n {
            let mut s = Sampler::new(SamplerKind::Sobol, 7, i, n);
            let wi = uniform_sphere(s.get_2d());
            uniform += bsdf.eval(wo, wi).0 * (4.0 * PI);
            let (a, b) = (s.get_2d(), s.get_2d());
            if let Some(sample) = bsdf.sample(wo, a, b) {
                importance += sample.weight;
            }
        }
        (uniform / n as f32, importance / n as f32)
    }

    #[test]
    fn lobe_table_is_normalised_and_samples_its_own_density() {
        let lobe = CosPowerLobe::new(40.0);
        let n = 20000;
        let step = PI / n as f32;
        let integral: f32 = (0..n).map(|i| lobe.eval(-FRAC_PI_2 + (i as f32 + 0.5) * step) * step).sum();
        assert!((integral - 1.0).abs() < 1e-3, "∫g = {integral}");
        let mean_sq: f32 =
            (0..n).map(|i| lobe.sample((i as f32 + 0.5) / n as f32).powi(2)).sum::<f32>() / n as f32;
        let expected: f32 = (0..n)
            .map(|i| {
                let d = -FRAC_PI_2 + (i as f32 + 0.5) * step;
                d * d * lobe.eval(d) * step
            })
            .sum();
        assert!((mean_sq - expected).abs() < 0.02 * expected, "E[δ²] {mean_sq} vs {expected}");
    }

    /// White furnace: a white fibre (colour 1) reflects all light but what its specular lobes
    /// lose past the poles, never more; a fibre seen side-on loses almost nothing.
    #[test]
    fn white_furnace_energy_is_conserved() {
        let lobes = HairLobes::default();
        let tangent = Vec3::new(0.3, 0.9, 0.1).normalize();
        let white = KajiyaKay::new(tangent, Vec3::ONE, &lobes);
        let (b1, _) = tangent.any_orthonormal_pair();
        for angle in [0.0f32, 20.0, 45.0, 70.0, 85.0] {
            let a = angle.to_radians();
            let wo = (b1 * a.cos() + tangent * a.sin()).normalize();
            let (uniform, importance) = albedos(&white, wo, 1 << 16);
            for c in [uniform.x, uniform.y, uniform.z] {
                assert!(c <= 1.0 + 0.01, "θo = {angle}°: albedo {c} > 1");
            }
            if angle <= 45.0 {
                assert!(uniform.x > 0.97, "θo = {angle}°: albedo {} loses energy", uniform.x);
            }
            assert!(
                (importance - uniform).abs().max_element() < 0.02,
                "θo = {angle}°: {importance} vs {uniform}"
            );
        }
        // The diffuse part alone is exact: its weight is the albedo for every sample.
        let diffuse = KajiyaKay {
            tangent,
            diffuse: Vec3::splat(0.5),
            primary: 0.0,
            secondary: Vec3::ZERO,
            lobes: &lobes,
        };
        let sample = diffuse.sample(b1, [0.3, 0.6], [0.2, 0.9]).unwrap();
        assert!((sample.weight - Vec3::splat(0.5)).abs().max_element() < 1e-5);
    }

    /// model.md §4: the highlight sits on the mirror cone θi = −θo (shifted by its tilt).
    #[test]
    fn highlight_sits_on_the_mirror_cone() {
        let lobes = HairLobes { primary_shift: 0.0, ..Default::default() };
        let bsdf = KajiyaKay {
            tangent: Vec3::Y,
            diffuse: Vec3::ZERO,
            primary: 1.0,
            secondary: Vec3::ZERO,
            lobes: &lobes,
        };
        let theta_o = 30f32.to_radians();
        let wo = Vec3::new(theta_o.cos(), theta_o.sin(), 0.0);
        let best = (-89..=89)
            .map(|deg| {
                let t = (deg as f32).to_radians();
                // Light on the opposite azimuth; the value is azimuth-independent anyway. The value
                // is the response to a distant light of unit irradiance.
                let wi = Vec3::new(-t.cos(), t.sin(), 0.0);
                (deg, bsdf.eval(wo, wi).0.x)
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        assert_eq!(best.0, -30, "the highlight should peak at θi = −θo");
    }

    #[test]
    fn lambert_is_energy_conserving() {
        let lambert = Lambert { normal: Vec3::Y, albedo: Vec3::ONE };
        let n = 1 << 14;
        let mut total = 0.0;
        for i in 0..n {
            let mut s = Sampler::new(SamplerKind::Sobol, 3, i, n);
            let wi = uniform_sphere(s.get_2d());
            total += lambert.eval(Vec3::Y, wi).0.x * 4.0 * PI;
        }
        assert!((total / n as f32 - 1.0).abs() < 0.01);
    }
}
