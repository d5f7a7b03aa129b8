//! Lights: a key light (a distant disk such as the sun, soft-shadowed by its angular size) and an
//! environment (constant or a simple sky). The key light is reached only by explicit light
//! sampling and the environment only by escaping paths, so neither is counted twice.
use std::f32::consts::TAU;

use glam::Vec3;

/// A distant light of angular radius `angle`, from `direction` (unit, towards the light).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeyLight {
    pub direction: Vec3,
    /// Irradiance on a surface facing the light (linear RGB).
    pub irradiance: Vec3,
    cos_max: f32,
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
        }
    }
}
