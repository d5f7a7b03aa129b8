//! The path tracer and the debug views. Each pixel sample follows one path: the camera ray
//! (traced in packets of eight neighbouring pixels), then at every hit next-event estimation
//! (a shadow ray to the key light and one to the sky) and a BSDF-sampled continuation, up to a
//! bounce limit. Light found by a shadow ray and light found by an escaping continuation are
//! weighted by the power heuristic (multiple importance sampling), so sharp hair lobes and small
//! lights both converge. Russian roulette by throughput starts only after a few bounces: light
//! in hair travels through several fibres, and cutting those paths early is what made previews
//! noisy.
use glam::Vec3;

use super::bsdf::{Bsdf, HairLobes, KajiyaKay, Lambert};
use super::camera::Camera;
use super::hair_bsdf::{offset_across_fibre, ChiangHair, ChiangParams, Pigment};
use super::light::{power_heuristic, Environment, Light};
use super::sampler::{mix64, Sampler};
use super::scene::{AttributeView, RenderScene, Surface};
use crate::embree::{Hit, Ray};

/// Bounces after which Russian roulette may end a path: the Chiang lobe carries light through
/// several fibres (TT, TRT), so its paths are kept for three bounces; Kajiya–Kay previews keep
/// their earlier, cheaper rule (their light is mostly one bounce deep).
const ROULETTE_AFTER_CHIANG: u32 = 3;
const ROULETTE_AFTER_KAJIYA_KAY: u32 = 1;

/// Which hair scattering model shades the strands.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Lobe {
    /// Chiang et al. 2016: R, TT, TRT and residual lobes from a fibre's optics.
    Chiang,
    /// Kajiya–Kay diffuse plus two shifted highlights: the preview default (smooth at preview
    /// sample counts; see README).
    #[default]
    KajiyaKay,
}

impl Lobe {
    fn roulette_after(self) -> u32 {
        match self {
            Lobe::Chiang => ROULETTE_AFTER_CHIANG,
            Lobe::KajiyaKay => ROULETTE_AFTER_KAJIYA_KAY,
        }
    }
}

/// What a pixel shows.
#[derive(Clone, Debug, PartialEq)]
pub enum Mode {
    /// The path-traced image.
    Beauty,
    /// False colour of a scalar attribute on the hair, blue (low) to red (high).
    Attribute { name: String, range: Option<(f32, f32)> },
    /// Hair tangents as colour (0.5 + 0.5·t).
    Tangent,
    /// Distance to the first hit, white near to black far.
    Depth,
}

/// Everything a path needs that does not change between pixels.
pub struct Integrator<'a> {
    pub scene: &'a RenderScene<'a>,
    pub camera: Camera,
    /// Lights sampled explicitly at every bounce (the key light by default).
    pub lights: &'a [Light],
    pub environment: Environment,
    /// Direction the debug views shade from (towards a light).
    pub debug_light: Vec3,
    pub lobes: &'a HairLobes,
    pub lobe: Lobe,
    pub chiang: &'a ChiangParams,
    pub max_depth: u32,
    pub mode: &'a Mode,
    pub attribute: Option<&'a AttributeView>,
    pub attribute_range: (f32, f32),
    pub depth_range: (f32, f32),
    /// Distance offset for rays leaving a diffuse surface.
    pub epsilon: f32,
}

/// One sample's contribution to a pixel.
#[derive(Clone, Copy, Debug, Default)]
pub struct SampleResult {
    pub radiance: Vec3,
    /// Distance and hair tangent at the first hit, if any.
    pub first_hit: Option<(f32, Vec3)>,
}

/// Rays traced, for statistics.
#[derive(Clone, Copy, Debug, Default)]
pub struct RayCount(pub u64);

/// The id of a path's ray at `depth` (hit filters hash it to decide transparency).
pub fn ray_id(path_seed: u64, depth: u32) -> u32 {
    mix64(path_seed ^ ((depth as u64) << 56)) as u32
}

/// Blue → cyan → green → yellow → red for `x` in [0, 1].
pub fn false_colour(x: f32) -> Vec3 {
    let stops = [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
    ];
    let x = if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 } * 4.0;
    let i = (x as usize).min(3);
    stops[i].lerp(stops[i + 1], x - i as f32)
}

impl Integrator<'_> {
    /// The closest hit; partly transparent hair is resolved by the scene's hit filter using
    /// `ray_id`.
    pub fn closest(
        &self,
        origin: Vec3,
        direction: Vec3,
        t_near: f32,
        ray_id: u32,
        rays: &mut RayCount,
    ) -> Option<Hit> {
        rays.0 += 1;
        self.scene.embree().intersect_ray(&Ray {
            origin,
            direction,
            t_near,
            t_far: f32::INFINITY,
            id: ray_id,
        })
    }

    /// Whether the segment from `origin` along `direction` is unblocked between `t_near` and
    /// `t_far`.
    fn unoccluded(
        &self,
        origin: Vec3,
        direction: Vec3,
        (t_near, t_far): (f32, f32),
        ray_id: u32,
        rays: &mut RayCount,
    ) -> bool {
        rays.0 += 1;
        !self.scene.embree().occluded_ray(&Ray { origin, direction, t_near, t_far, id: ray_id })
    }

    /// A sample through pixel `(px, py)`: the camera ray's direction and its first hit (given
    /// when traced in a packet).
    pub fn sample(
        &self,
        direction: Vec3,
        first: Option<Hit>,
        sampler: &mut Sampler,
        coin_seed: u64,
        rays: &mut RayCount,
    ) -> SampleResult {
        match self.mode {
            Mode::Beauty => self.path(direction, first, sampler, coin_seed, rays),
            _ => self.debug(direction, first),
        }
    }

    fn path(
        &self,
        camera_direction: Vec3,
        first: Option<Hit>,
        sampler: &mut Sampler,
        coin_seed: u64,
        rays: &mut RayCount,
    ) -> SampleResult {
        let mut result = SampleResult::default();
        let mut throughput = Vec3::ONE;
        let mut origin = self.camera.position;
        let mut direction = camera_direction;
        let mut t_near = 0.0;
        let mut hit = first;
        // Density of the BSDF sample that chose `direction` (none for the camera ray).
        let mut bsdf_pdf: Option<f32> = None;
        for depth in 0..self.max_depth {
            let seed = ray_id(coin_seed, depth);
            if depth > 0 {
                hit = self.closest(origin, direction, t_near, seed, rays);
                // Area lights are not in the ray-tracing scene: a continuation finds one when it
                // meets it before the next surface.
                if let Some(pdf) = bsdf_pdf {
                    let t_hit = hit.map_or(f32::INFINITY, |h| h.t);
                    for light in self.lights {
                        if let Some((radiance, light_pdf)) = light.area_hit(origin, direction, t_hit) {
                            result.radiance += throughput * radiance * power_heuristic(pdf, light_pdf);
                        }
                    }
                }
            }
            let Some(h) = hit else {
                let sky = self.environment.radiance(direction);
                result.radiance += throughput
                    * match bsdf_pdf {
                        // The camera sees the sky, not the key's disk.
                        None => sky,
                        Some(pdf) => {
                            let sky_weight = if self.sky_light_samples() {
                                power_heuristic(pdf, self.environment.pdf(direction))
                            } else {
                                1.0
                            };
                            let mut distant = Vec3::ZERO;
                            for light in self.lights {
                                if let Light::Distant(key) = light {
                                    distant += key.radiance(direction) * power_heuristic(pdf, key.pdf());
                                }
                            }
                            sky * sky_weight + distant
                        }
                    };
                break;
            };
            let position = origin + direction * h.t;
            let surface = self.scene.surface(&h, position, direction);
            if depth == 0 {
                let tangent = match surface {
                    Surface::Hair { tangent, .. } => tangent,
                    Surface::Diffuse { .. } => Vec3::ZERO,
                };
                result.first_hit = Some((h.t, tangent));
            }
            let wo = -direction;
            let (bsdf, spawn, spawn_near) = match surface {
                // Rays leave a fibre just beside its surface, placed from its centre line (see
                // `RenderScene::surface`), and never meet it again.
                Surface::Hair { tangent, color, melanin, normal, exit, .. } => {
                    (self.hair_bsdf(tangent, color, melanin, normal, wo), exit.surface(), 0.0)
                }
                Surface::Diffuse { normal, albedo } => {
                    (Bsdf::Diffuse(Lambert { normal, albedo }), position, self.epsilon)
                }
            };
            let offset = |w: Vec3| match surface {
                Surface::Diffuse { normal, .. } => spawn + normal * (self.epsilon * normal.dot(w).signum()),
                Surface::Hair { exit, .. } => exit.origin(w),
            };
            // The last vertex traces no continuation, so its light samples take all the weight.
            let last = depth + 1 == self.max_depth;
            let mis =
                |light_pdf: f32, bsdf_pdf: f32| if last { 1.0 } else { power_heuristic(light_pdf, bsdf_pdf) };

            // Next-event estimation: each light, then the sky.
            for (index, light) in self.lights.iter().enumerate() {
                let sample = light.sample(spawn, sampler.get_2d());
                if sample.weight.max_element() <= 0.0 {
                    continue;
                }
                let (value, pdf) = bsdf.eval(wo, sample.direction);
                // Stop short of an area light's surface (its own plane would not block, but the
                // margin keeps rounding from finding geometry behind it).
                let reach = (spawn_near, sample.distance * (1.0 - 1e-4));
                let shadow_id = seed ^ 0x5bd1_e995u32.wrapping_add(0x9e37_79b9u32.wrapping_mul(index as u32));
                if value.max_element() > 0.0
                    && self.unoccluded(offset(sample.direction), sample.direction, reach, shadow_id, rays)
                {
                    result.radiance += throughput * value * sample.weight * mis(sample.pdf, pdf);
                }
            }
            if self.sky_light_samples() {
                let (wi, sky_pdf) = self.environment.sample(sampler.get_2d());
                let (value, pdf) = bsdf.eval(wo, wi);
                let reach = (spawn_near, f32::INFINITY);
                if value.max_element() > 0.0
                    && self.unoccluded(offset(wi), wi, reach, seed ^ 0x2545_f491, rays)
                {
                    result.radiance +=
                        throughput * value * self.environment.radiance(wi) * (mis(sky_pdf, pdf) / sky_pdf);
                }
            }
            if last {
                break;
            }

            // Continue the path.
            let (u_lobe, u) = (sampler.get_2d(), sampler.get_2d());
            let u_roulette = sampler.get_1d();
            let Some(sample) = bsdf.sample(wo, u_lobe, u) else { break };
            throughput *= sample.weight;
            bsdf_pdf = Some(sample.pdf);
            if depth + 1 >= self.lobe.roulette_after() {
                let survive = throughput.max_element().min(1.0);
                if u_roulette >= survive {
                    break;
                }
                throughput /= survive;
            }
            origin = offset(sample.direction);
            direction = sample.direction;
            t_near = spawn_near;
        }
        result
    }

    /// Whether paths sample the sky explicitly: worth its shadow ray for the Chiang lobe, whose
    /// sharp lobes rarely find the sky by themselves; Kajiya–Kay previews keep the cost of
    /// before (one shadow ray per bounce).
    fn sky_light_samples(&self) -> bool {
        self.lobe == Lobe::Chiang && !self.environment.is_black()
    }

    /// The hair BSDF at a hit, for the render's lobe.
    fn hair_bsdf(
        &self,
        tangent: Vec3,
        color: Vec3,
        melanin: Option<[f32; 2]>,
        normal: Vec3,
        wo: Vec3,
    ) -> Bsdf<'_> {
        match self.lobe {
            Lobe::KajiyaKay => Bsdf::Hair(KajiyaKay::new(tangent, color, self.lobes)),
            Lobe::Chiang => {
                let pigment = match melanin {
                    Some([eumelanin, pheomelanin]) => Pigment::Melanin { eumelanin, pheomelanin },
                    None => Pigment::Color(color),
                };
                let h = offset_across_fibre(tangent, normal, wo);
                Bsdf::Chiang(
                    ChiangHair::new(
                        tangent,
                        h,
                        pigment.sigma_a(self.chiang.azimuthal_roughness()),
                        self.chiang,
                    )
                    .seen_from(wo),
                )
            }
        }
    }

    fn debug(&self, direction: Vec3, first: Option<Hit>) -> SampleResult {
        let background = Vec3::splat(0.02);
        let Some(h) = first else {
            return SampleResult {
                radiance: if *self.mode == Mode::Depth { Vec3::ZERO } else { background },
                first_hit: None,
            };
        };
        let position = self.camera.position + direction * h.t;
        let surface = self.scene.surface(&h, position, direction);
        let light = self.debug_light;
        let (colour, tangent) = match (self.mode, surface) {
            (Mode::Depth, s) => {
                let (near, far) = self.depth_range;
                let g = 1.0 - ((h.t - near) / (far - near).max(1e-6)).clamp(0.0, 1.0);
                let t = if let Surface::Hair { tangent, .. } = s { tangent } else { Vec3::ZERO };
                (Vec3::splat(0.05 + 0.95 * g), t)
            }
            (Mode::Tangent, Surface::Hair { tangent, .. }) => (Vec3::splat(0.5) + 0.5 * tangent, tangent),
            (Mode::Attribute { .. }, Surface::Hair { tangent, vertex, fraction, strand, .. }) => {
                let value =
                    self.attribute.map_or(0.0, |a| RenderScene::attribute_value(a, vertex, fraction, strand));
                let (lo, hi) = self.attribute_range;
                let x = if hi > lo { (value - lo) / (hi - lo) } else { 0.5 };
                // A little Kajiya–Kay diffuse shading keeps the strands' form readable.
                let shade = 0.55 + 0.45 * (1.0 - tangent.dot(light).powi(2)).max(0.0).sqrt();
                (false_colour(x) * shade, tangent)
            }
            (_, Surface::Hair { tangent, .. }) => (Vec3::splat(0.5), tangent),
            // Head and floor stay dark so the false colours stand out.
            (_, Surface::Diffuse { normal, .. }) => {
                (Vec3::splat(0.01 + 0.04 * normal.dot(light).max(0.0)), Vec3::ZERO)
            }
        };
        SampleResult { radiance: colour, first_hit: Some((h.t, tangent)) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn false_colour_runs_blue_to_red() {
        assert_eq!(false_colour(0.0), Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(false_colour(0.5), Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(false_colour(1.0), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(false_colour(7.0), Vec3::new(1.0, 0.0, 0.0));
    }
}
