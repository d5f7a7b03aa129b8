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

/// A one-sided rectangular area light (UsdLux `RectLight`): radiance `radiance` leaves its front
/// face, the side its `normal` points to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RectLight {
    center: Vec3,
    /// Half the rectangle's edges (world vectors, perpendicular to each other and to `normal`).
    half_u: Vec3,
    half_v: Vec3,
    normal: Vec3,
    area: f32,
    pub radiance: Vec3,
}

impl RectLight {
    /// A rectangle centred at `center` with edge vectors `2 half_u` and `2 half_v`, emitting to
    /// the side of its plane that `emits_towards` points to. `None` when the edges are
    /// degenerate or `emits_towards` lies in the plane.
    pub fn new(
        center: Vec3,
        half_u: Vec3,
        half_v: Vec3,
        emits_towards: Vec3,
        radiance: Vec3,
    ) -> Option<RectLight> {
        let cross = half_u.cross(half_v);
        let area = 4.0 * cross.length();
        let normal = cross.try_normalize()?;
        let side = normal.dot(emits_towards);
        if !(area.is_finite() && area > 0.0 && side.abs() > 1e-6 && center.is_finite()) {
            return None;
        }
        let normal = normal * side.signum();
        Some(RectLight { center, half_u, half_v, normal, area, radiance })
    }

    /// A point on the rectangle, uniform by area, seen from `from` (zero weight from behind).
    fn sample(&self, from: Vec3, u: [f32; 2]) -> LightSample {
        let point = self.center + self.half_u * (2.0 * u[0] - 1.0) + self.half_v * (2.0 * u[1] - 1.0);
        let offset = point - from;
        let distance = offset.length();
        let direction = offset / distance;
        LightSample::new(direction, distance, self.radiance, self.pdf_at(direction, distance))
    }

    /// Solid-angle density of [`RectLight::sample`] for a point at `distance` along `direction`.
    fn pdf_at(&self, direction: Vec3, distance: f32) -> f32 {
        let cos_light = -self.normal.dot(direction);
        if cos_light <= 0.0 {
            return 0.0;
        }
        distance * distance / (cos_light * self.area)
    }

    /// Where a ray meets the emitting face, if before `t_max`: the distance and the density with
    /// which [`RectLight::sample`] would have chosen that direction.
    pub fn intersect(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<(f32, f32)> {
        let facing = self.normal.dot(direction);
        if facing >= 0.0 {
            return None;
        }
        let t = self.normal.dot(self.center - origin) / facing;
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let local = origin + direction * t - self.center;
        let inside = |half: Vec3| local.dot(half).abs() <= half.length_squared();
        (inside(self.half_u) && inside(self.half_v)).then(|| (t, self.pdf_at(direction, t)))
    }
}

/// A spherical area light (UsdLux `SphereLight`), emitting `radiance` outwards from its surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereLight {
    center: Vec3,
    radius: f32,
    pub radiance: Vec3,
}

impl SphereLight {
    /// `None` unless the centre is finite and the radius positive and finite.
    pub fn new(center: Vec3, radius: f32, radiance: Vec3) -> Option<SphereLight> {
        (center.is_finite() && radius.is_finite() && radius > 0.0).then_some(SphereLight {
            center,
            radius,
            radiance,
        })
    }

    /// `1 − cos θ_max` of the cone the sphere fills seen from `from` (`None` inside it), in the
    /// form that keeps its precision for small, distant spheres.
    fn cone(&self, from: Vec3) -> Option<(Vec3, f32, f32)> {
        let offset = self.center - from;
        let distance_squared = offset.length_squared();
        let sin2 = self.radius * self.radius / distance_squared;
        if sin2.is_nan() || sin2 >= 1.0 {
            return None;
        }
        let cos_max = (1.0 - sin2).sqrt();
        Some((offset / distance_squared.sqrt(), cos_max, sin2 / (1.0 + cos_max)))
    }

    /// A direction uniform in the cone the sphere subtends from `from` (pbrt's sphere sampling
    /// by solid angle); zero weight from inside the sphere.
    fn sample(&self, from: Vec3, u: [f32; 2]) -> LightSample {
        let Some((axis, _, one_minus_cos_max)) = self.cone(from) else {
            return LightSample::new(Vec3::Y, 0.0, Vec3::ZERO, 0.0);
        };
        let one_minus_cos = u[0] * one_minus_cos_max;
        let cos = 1.0 - one_minus_cos;
        let sin = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
        let phi = TAU * u[1];
        let (b1, b2) = axis.any_orthonormal_pair();
        let direction = (axis * cos + (b1 * phi.cos() + b2 * phi.sin()) * sin).normalize();
        let distance = self.hit_distance(from, direction).unwrap_or_else(|| (self.center - from).length());
        LightSample::new(direction, distance, self.radiance, 1.0 / (TAU * one_minus_cos_max))
    }

    /// The nearest distance at which a ray from `origin` meets the sphere.
    fn hit_distance(&self, origin: Vec3, direction: Vec3) -> Option<f32> {
        let oc = origin - self.center;
        let b = oc.dot(direction);
        // The discriminant from the ray's closest approach keeps precision far from the sphere.
        let closest = oc - direction * b;
        let discriminant = self.radius * self.radius - closest.length_squared();
        if discriminant < 0.0 {
            return None;
        }
        let t = -b - discriminant.sqrt();
        (t > 0.0).then_some(t)
    }

    /// Where a ray meets the sphere, if before `t_max`: the distance and the density with which
    /// [`SphereLight::sample`] would have chosen that direction.
    pub fn intersect(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<(f32, f32)> {
        let (_, _, one_minus_cos_max) = self.cone(origin)?;
        let t = self.hit_distance(origin, direction)?;
        (t < t_max).then(|| (t, 1.0 / (TAU * one_minus_cos_max)))
    }
}

/// A light a path samples explicitly (next-event estimation), besides the environment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    Distant(KeyLight),
    Rect(RectLight),
    Sphere(SphereLight),
}

/// A direction towards a light from a shading point, as next-event estimation needs it.
pub struct LightSample {
    pub direction: Vec3,
    /// How far a shadow ray must reach (infinite for a distant light).
    pub distance: f32,
    /// Radiance over the solid-angle density (zero when the light cannot be seen).
    pub weight: Vec3,
    pub pdf: f32,
}

impl LightSample {
    fn new(direction: Vec3, distance: f32, radiance: Vec3, pdf: f32) -> LightSample {
        let weight = if pdf > 0.0 && pdf.is_finite() { radiance / pdf } else { Vec3::ZERO };
        LightSample { direction, distance, weight, pdf }
    }
}

impl Light {
    pub fn sample(&self, from: Vec3, u: [f32; 2]) -> LightSample {
        match self {
            Light::Distant(key) => {
                let (direction, weight) = key.sample(u);
                LightSample { direction, distance: f32::INFINITY, weight, pdf: key.pdf() }
            }
            Light::Rect(rect) => rect.sample(from, u),
            Light::Sphere(sphere) => sphere.sample(from, u),
        }
    }

    /// What a ray from `origin` sees of an area light before `t_max` (area lights are not in
    /// the ray-tracing scene): its radiance and the density of sampling that direction.
    pub fn area_hit(&self, origin: Vec3, direction: Vec3, t_max: f32) -> Option<(Vec3, f32)> {
        match self {
            Light::Distant(_) => None,
            Light::Rect(rect) => {
                rect.intersect(origin, direction, t_max).map(|(_, pdf)| (rect.radiance, pdf))
            }
            Light::Sphere(sphere) => {
                sphere.intersect(origin, direction, t_max).map(|(_, pdf)| (sphere.radiance, pdf))
            }
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

    /// Whether the environment gives no light at all (then nothing samples it).
    pub fn is_black(&self) -> bool {
        matches!(*self, Environment::Constant(c) if c == Vec3::ZERO)
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
    /// A 2-D low-discrepancy point set (R2 sequence) for the estimators below.
    fn r2(i: usize) -> [f32; 2] {
        let (a, b) = (0.754_877_7_f64, 0.569_840_3_f64);
        [((0.5 + a * i as f64) % 1.0) as f32, ((0.5 + b * i as f64) % 1.0) as f32]
    }

    /// Irradiance on a surface at the origin facing +Y, two ways: by sampling the light
    /// (Σ weight · cos / N) and by cosine-sampling the hemisphere and asking `area_hit` what each
    /// direction sees (π · mean radiance). The two must agree: the light's sampler, its density
    /// and its intersection describe the same emitter.
    fn irradiance_both_ways(light: &Light) -> (f64, f64) {
        let n = 1 << 18;
        let (mut by_light, mut by_hemisphere) = (0.0f64, 0.0f64);
        for i in 0..n {
            let sample = light.sample(Vec3::ZERO, r2(i));
            by_light += (sample.weight.x * sample.direction.y.max(0.0)) as f64;
            let [u, v] = r2(i + n);
            let (r, phi) = (u.sqrt(), TAU * v);
            let direction = Vec3::new(r * phi.cos(), (1.0 - u).max(0.0).sqrt(), r * phi.sin());
            if let Some((radiance, pdf)) = light.area_hit(Vec3::ZERO, direction, f32::INFINITY) {
                assert!(pdf > 0.0 && pdf.is_finite());
                by_hemisphere += PI as f64 * radiance.x as f64;
            }
        }
        (by_light / n as f64, by_hemisphere / n as f64)
    }

    #[test]
    fn sphere_light_irradiance_matches_the_analytic_value_both_ways() {
        // A sphere of radiance L seen head-on subtends sin²θ = r²/d²: E = π L r²/d².
        for (centre, radius) in [(Vec3::new(0.0, 2.0, 0.0), 0.5), (Vec3::new(0.0, 40.0, 0.0), 0.3)] {
            let light = Light::Sphere(SphereLight::new(centre, radius, Vec3::splat(3.0)).unwrap());
            let expected = (PI * 3.0 * radius * radius / centre.length_squared()) as f64;
            let (by_light, by_hemisphere) = irradiance_both_ways(&light);
            assert!((by_light / expected - 1.0).abs() < 2e-3, "light sampling {by_light} vs {expected}");
            // Hemisphere sampling finds a small far sphere rarely: a looser check.
            let tolerance = if radius / centre.length() > 0.1 { 0.02 } else { 0.2 };
            assert!((by_hemisphere / expected - 1.0).abs() < tolerance, "{by_hemisphere} vs {expected}");
        }
        // Inside the sphere nothing is sampled (it is one-sided, emitting outwards).
        let light = SphereLight::new(Vec3::ZERO, 1.0, Vec3::ONE).unwrap();
        assert_eq!(Light::Sphere(light).sample(Vec3::new(0.1, 0.0, 0.0), [0.3, 0.3]).weight, Vec3::ZERO);
    }

    #[test]
    fn rect_light_irradiance_agrees_both_ways_and_is_one_sided() {
        // A 1 × 0.6 panel one unit above, tilted 30°, emitting downwards.
        let tilt = 30f32.to_radians();
        let half_u = Vec3::new(0.5 * tilt.cos(), 0.5 * tilt.sin(), 0.0);
        let half_v = Vec3::new(0.0, 0.0, 0.3);
        let centre = Vec3::new(0.2, 1.0, 0.0);
        let light =
            Light::Rect(RectLight::new(centre, half_u, half_v, Vec3::NEG_Y, Vec3::splat(2.0)).unwrap());
        let (by_light, by_hemisphere) = irradiance_both_ways(&light);
        assert!(by_light > 0.1, "the panel lights the point: {by_light}");
        assert!((by_light / by_hemisphere - 1.0).abs() < 0.01, "{by_light} vs {by_hemisphere}");
        // Facing away, it gives nothing either way.
        let away = Light::Rect(RectLight::new(centre, half_u, half_v, Vec3::Y, Vec3::splat(2.0)).unwrap());
        assert_eq!(irradiance_both_ways(&away), (0.0, 0.0));
        assert!(RectLight::new(centre, half_u, half_u, Vec3::Y, Vec3::ONE).is_none(), "degenerate");
    }
}
