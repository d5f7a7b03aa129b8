//! Lights: a key light (a distant disk such as the sun, soft-shadowed by its angular size) and an
//! environment (constant or a simple sky). Both are reached two ways, by explicit light samples
//! and by escaping BSDF-sampled paths; the integrator weights the two with multiple importance
//! sampling, so each light counts once. Each light therefore has a sampler and its density.
use std::f32::consts::{PI, TAU};

use glam::Vec3;

/// A distant light of angular radius `angle`, from `direction` (unit, towards the light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyLight {
    pub direction: Vec3,
    /// Irradiance on a surface facing the light (linear RGB).
    pub irradiance: Vec3,
    cos_max: f32,
}

/// The power heuristic (β = 2) weight of a strategy with density `pdf` against one with `other`.
#[inline]
pub fn power_heuristic(pdf: f32, other: f32) -> f32 {
    let (a, b) = (pdf * pdf, other * other);
    if a + b > 0.0 && a.is_finite() {
        a / (a + b)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

impl KeyLight {
    pub fn new(direction: Vec3, irradiance: Vec3, angular_radius_degrees: f32) -> KeyLight {
        let cos_max = angular_radius_degrees.to_radians().cos().min(1.0 - 1e-7);
        KeyLight { direction: direction.normalize(), irradiance, cos_max }
    }

    /// A direction towards the light, uniform over its disk, and the irradiance it carries
    /// (radiance / pdf).
    pub fn sample(&self, u: [f32; 2]) -> (Vec3, Vec3) {
        let cos = 1.0 - u[0] * (1.0 - self.cos_max);
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let phi = TAU * u[1];
        let (b1, b2) = self.direction.any_orthonormal_pair();
        let w = (self.direction * cos + (b1 * phi.cos() + b2 * phi.sin()) * sin).normalize();
        (w, self.irradiance)
    }

    /// Solid-angle density of [`KeyLight::sample`]: one over the disk's solid angle.
    pub fn pdf(&self) -> f32 {
        1.0 / (TAU * (1.0 - self.cos_max))
    }

    /// Radiance seen looking along `direction` (zero outside the disk).
    pub fn radiance(&self, direction: Vec3) -> Vec3 {
        if direction.dot(self.direction) >= self.cos_max {
            self.irradiance * self.pdf()
        } else {
            Vec3::ZERO
        }
    }
}

/// Light from everywhere else.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Environment {
    /// The same radiance from every direction (a white furnace when 1).
    Constant(Vec3),
    /// A sky: zenith colour blending to the horizon, a darker ground below.
    Sky { zenith: Vec3, horizon: Vec3, ground: Vec3 },
}

impl Default for Environment {
    fn default() -> Self {
        Environment::Sky {
            zenith: Vec3::new(0.30, 0.40, 0.60),
            horizon: Vec3::new(0.62, 0.64, 0.68),
            ground: Vec3::new(0.16, 0.15, 0.14),
        }
    }
}

impl Environment {
    /// A direction for next-event estimation and its solid-angle density: half the samples
    /// cosine-weighted about +Y (where the sky is bright), half uniform over the sphere (the
    /// ground and the furnace).
    pub fn sample(&self, u: [f32; 2]) -> (Vec3, f32) {
        let w = if u[0] < 0.5 {
            let u0 = 2.0 * u[0];
            let r = u0.sqrt();
            let phi = TAU * u[1];
            Vec3::new(r * phi.cos(), (1.0 - u0).max(0.0).sqrt(), r * phi.sin())
        } else {
            let z = 1.0 - 2.0 * (2.0 * u[0] - 1.0);
            let r = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(r * (TAU * u[1]).cos(), z, r * (TAU * u[1]).sin())
        };
        (w, self.pdf(w))
    }

    pub fn pdf(&self, direction: Vec3) -> f32 {
        0.5 / (4.0 * PI) + 0.5 * direction.y.max(0.0) / PI
    }

    pub fn radiance(&self, direction: Vec3) -> Vec3 {
        match *self {
            Environment::Constant(c) => c,
            Environment::Sky { zenith, horizon, ground } => {
                if direction.y >= 0.0 {
                    horizon.lerp(zenith, direction.y.sqrt())
                } else {
                    horizon.lerp(ground, (-direction.y * 4.0).min(1.0))
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_light_samples_stay_in_its_disk() {
        let light = KeyLight::new(Vec3::new(1.0, 1.0, 0.0), Vec3::ONE, 5.0);
        let cos_max = 5f32.to_radians().cos();
        for i in 0..100 {
            let (w, e) = light.sample([i as f32 / 100.0, (i * 37 % 100) as f32 / 100.0]);
            assert!(w.dot(light.direction) >= cos_max - 1e-5);
            assert_eq!(e, Vec3::ONE);
            // Radiance over the disk's solid angle gives back the irradiance.
            assert!((light.radiance(w) / light.pdf() - e).abs().max_element() < 1e-5);
        }
    }

    /// The environment sampler's density integrates to one and matches its samples' histogram
    /// in y (a cheap consistency check of sample against pdf).
    #[test]
    fn environment_pdf_is_normalised_and_matches_its_samples() {
        let env = Environment::default();
        let n = 400;
        let mut total = 0.0;
        for i in 0..n {
            for j in 0..n {
                let y = -1.0 + 2.0 * (i as f32 + 0.5) / n as f32;
                let phi = TAU * (j as f32 + 0.5) / n as f32;
                let r = (1.0 - y * y).sqrt();
                total +=
                    env.pdf(Vec3::new(r * phi.cos(), y, r * phi.sin())) * (2.0 / n as f32) * (TAU / n as f32);
            }
        }
        assert!((total - 1.0).abs() < 1e-3, "∫pdf = {total}");
        let bins = 8;
        let mut counts = vec![0f32; bins];
        let m = 1 << 16;
        for i in 0..m {
            let u = [(i as f32 + 0.5) / m as f32, ((i as u64 * 2654435761) % m as u64) as f32 / m as f32];
            let (w, _) = env.sample(u);
            counts[(((w.y + 1.0) * 0.5 * bins as f32) as usize).min(bins - 1)] += 1.0 / m as f32;
        }
        for (b, c) in counts.iter().enumerate() {
            let (y0, y1) = (-1.0 + 2.0 * b as f32 / bins as f32, -1.0 + 2.0 * (b + 1) as f32 / bins as f32);
            // ∫ pdf over the band y0..y1: 2π · ∫ pdf dy.
            let expected = 0.5 * (y1 - y0) / 2.0 + 0.5 * (y1.max(0.0).powi(2) - y0.max(0.0).powi(2));
            assert!((c - expected).abs() < 0.005, "band {b}: {c} vs {expected}");
        }
    }
}
