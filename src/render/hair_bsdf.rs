//! The near-field hair BSDF of Chiang, Bitterli, Tappan and Burley 2016 ("A Practical and
//! Controllable Hair and Fur Model for Production Path Tracing"), beside Kajiya–Kay.
//!
//! A fibre is a dielectric cylinder (IOR 1.55) whose scales tilt its surface by α. Light leaves
//! after p internal segments: R (p = 0, surface reflection, white), TT (p = 1, through the fibre,
//! coloured), TRT (p = 2, one internal bounce, the coloured secondary highlight) and a residual
//! lobe for p ≥ 3. Each lobe is a product of
//! - a longitudinal lobe M_p(θi, θo): d'Eon et al.'s normalised von Mises–Fisher cone around the
//!   mirror direction `θi = −θo`, shifted by the cuticle tilt (−2α, α, 4α) with variance v_p from
//!   the longitudinal roughness β_m (v₁ = v₀/4, v₂ = v₃ = 4 v₀),
//! - an attenuation A_p(θo, h): Fresnel at the cuticle and absorption exp(−σ_a·path) inside,
//! - an azimuthal lobe N_p(φ): a trimmed logistic of scale s(β_n) around the exit azimuth of a
//!   ray entering at offset h, Φ = 2pγt − 2γo + pπ.
//!
//! Conventions as in [`super::bsdf`]: both directions point away from the fibre, `sin θ = t·ω`,
//! and `eval` returns `S · cos θi` per solid angle. With M_p normalised over `cos θ dθ` and N_p
//! over φ, `M_p N_p` is itself a density over solid angle, so `value = Σ A_p M_p N_p` and the
//! sampler (pick p by A_p, draw θ from M_p exactly, φ from N_p exactly) has the pdf
//! `Σ P(p) M_p N_p`. At zero absorption Σ A_p = 1 for every h: a white fibre reflects all light.
//!
//! Absorption σ_a (per unit fibre radius) comes from eumelanin and pheomelanin concentrations or
//! from a colour, by the paper's fit of the multiple-scattering albedo against β_n.
use std::f32::consts::{PI, TAU};

use glam::Vec3;

use super::bsdf::BsdfSample;

/// Index of refraction of keratin.
pub const HAIR_IOR: f32 = 1.55;

/// Valid range of the longitudinal and azimuthal roughness (below it the lobes are too sharp
/// for single-precision evaluation; hair is never that smooth).
pub const ROUGHNESS_RANGE: (f32, f32) = (0.02, 1.0);
/// Valid range of the eumelanin and pheomelanin concentrations (8 is jet black).
pub const MELANIN_RANGE: (f32, f32) = (0.0, 10.0);

/// Absorption per unit radius of one unit of eumelanin and of pheomelanin (Chiang et al. §4.2,
/// from Donner and Jensen's measured spectra reduced to RGB).
const EUMELANIN_SIGMA_A: Vec3 = Vec3::new(0.419, 0.697, 1.37);
const PHEOMELANIN_SIGMA_A: Vec3 = Vec3::new(0.187, 0.4, 1.05);

/// What colours a fibre: a colour to reach after multiple scattering, or melanin concentrations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pigment {
    Color(Vec3),
    Melanin { eumelanin: f32, pheomelanin: f32 },
}

/// σ_a from melanin concentrations.
pub fn sigma_a_from_melanin(eumelanin: f32, pheomelanin: f32) -> Vec3 {
    eumelanin * EUMELANIN_SIGMA_A + pheomelanin * PHEOMELANIN_SIGMA_A
}

/// σ_a whose multiply scattered albedo is about `color` for azimuthal roughness `beta_n`
/// (Chiang et al. eq. 9). Channels are clamped into (0, 1].
pub fn sigma_a_from_color(color: Vec3, beta_n: f32) -> Vec3 {
    let b = beta_n;
    let denominator =
        5.969 - 0.215 * b + 2.532 * b.powi(2) - 10.73 * b.powi(3) + 5.574 * b.powi(4) + 0.245 * b.powi(5);
    let c = color.clamp(Vec3::splat(1e-4), Vec3::ONE);
    let l = Vec3::new(c.x.ln(), c.y.ln(), c.z.ln()) / denominator;
    l * l
}

impl Pigment {
    pub fn sigma_a(&self, beta_n: f32) -> Vec3 {
        match *self {
            Pigment::Color(c) => sigma_a_from_color(c, beta_n),
            Pigment::Melanin { eumelanin, pheomelanin } => sigma_a_from_melanin(eumelanin, pheomelanin),
        }
    }
}

/// The shape parameters shared by every fibre of a render.
#[derive(Clone, Debug, PartialEq)]
pub struct ChiangParams {
    /// Longitudinal roughness β_m and azimuthal roughness β_n, in [0.02, 1].
    pub beta_m: f32,
    pub beta_n: f32,
    /// Cuticle tilt α, degrees (positive tilts the highlight towards the root).
    pub alpha_degrees: f32,
    variance: [f32; 4],
    /// Per lobe, the part of log M_p (narrow lobes) or the divisor of M_p (wide ones) that
    /// depends on its variance alone: see [`longitudinal`].
    longitudinal_norm: [f64; 4],
    logistic_scale: f32,
    /// Mass of the logistic inside [−π, π], the trimmed lobe's normaliser.
    logistic_mass: f32,
    /// sin and cos of 2^k α, k = 0, 1, 2.
    sin_2k_alpha: [f32; 3],
    cos_2k_alpha: [f32; 3],
}

impl Default for ChiangParams {
    fn default() -> Self {
        ChiangParams::new(0.3, 0.3, 2.0)
    }
}

impl ChiangParams {
    /// [`ChiangParams::check`] validates the ranges; the lobes use values clamped into them.
    pub fn new(beta_m_given: f32, beta_n_given: f32, alpha_degrees: f32) -> ChiangParams {
        let clamp = |b: f32| if b.is_nan() { 0.3 } else { b.clamp(ROUGHNESS_RANGE.0, ROUGHNESS_RANGE.1) };
        let (beta_m, beta_n) = (clamp(beta_m_given), clamp(beta_n_given));
        // The paper's fits of lobe variance and logistic scale to perceptually linear roughness.
        let v0 = (0.726 * beta_m + 0.812 * beta_m.powi(2) + 3.7 * beta_m.powi(20)).powi(2);
        let variance = [v0, 0.25 * v0, 4.0 * v0, 4.0 * v0];
        let logistic_scale =
            (PI / 8.0).sqrt() * (0.265 * beta_n + 1.194 * beta_n.powi(2) + 5.372 * beta_n.powi(22));
        let alpha = if alpha_degrees.is_finite() { alpha_degrees.to_radians() } else { 0.0 };
        let angles = [alpha, 2.0 * alpha, 4.0 * alpha];
        ChiangParams {
            beta_m: beta_m_given,
            beta_n: beta_n_given,
            alpha_degrees,
            variance,
            longitudinal_norm: variance.map(longitudinal_norm),
            logistic_scale,
            logistic_mass: logistic_cdf(PI, logistic_scale) - logistic_cdf(-PI, logistic_scale),
            sin_2k_alpha: angles.map(f32::sin),
            cos_2k_alpha: angles.map(f32::cos),
        }
    }

    /// The roughness and tilt as given, each checked against its range; errors name the flag.
    pub fn check(&self) -> Result<(), String> {
        let (lo, hi) = ROUGHNESS_RANGE;
        for (flag, b) in [("--roughness", self.beta_m), ("--azimuthal-roughness", self.beta_n)] {
            if !(b >= lo && b <= hi) {
                return Err(format!("{flag} {b} is outside [{lo}, {hi}]"));
            }
        }
        if self.alpha_degrees.is_nan() || self.alpha_degrees.abs() > 10.0 {
            return Err(format!("--cuticle-tilt {} is outside [-10, 10] degrees", self.alpha_degrees));
        }
        Ok(())
    }

    /// The roughness the lobes use (the given one clamped into range).
    pub fn azimuthal_roughness(&self) -> f32 {
        self.beta_n.clamp(ROUGHNESS_RANGE.0, ROUGHNESS_RANGE.1)
    }

    /// sin and cos of θo rotated by lobe p's cuticle shift (−2α for R, α for TT, 4α for TRT).
    fn shifted(&self, p: usize, sin_o: f32, cos_o: f32) -> (f32, f32) {
        let (s, c) = match p {
            0 => (
                sin_o * self.cos_2k_alpha[1] - cos_o * self.sin_2k_alpha[1],
                cos_o * self.cos_2k_alpha[1] + sin_o * self.sin_2k_alpha[1],
            ),
            1 => (
                sin_o * self.cos_2k_alpha[0] + cos_o * self.sin_2k_alpha[0],
                cos_o * self.cos_2k_alpha[0] - sin_o * self.sin_2k_alpha[0],
            ),
            2 => (
                sin_o * self.cos_2k_alpha[2] + cos_o * self.sin_2k_alpha[2],
                cos_o * self.cos_2k_alpha[2] - sin_o * self.sin_2k_alpha[2],
            ),
            _ => (sin_o, cos_o),
        };
        (s, c.abs())
    }
}

/// Modified Bessel function of the first kind, order 0 (power series; x ≤ ~12 here).
fn bessel_i0(x: f64) -> f64 {
    let q = 0.25 * x * x;
    let mut term = 1.0;
    let mut sum = 1.0;
    for i in 1..=12 {
        term *= q / (i * i) as f64;
        sum += term;
    }
    sum
}

fn log_bessel_i0(x: f64) -> f64 {
    if x > 12.0 {
        // Asymptotic expansion: I0(x) ≈ eˣ / √(2πx) · (1 + 1/(8x)).
        x + 0.5 * (-(std::f64::consts::TAU).ln() + (1.0 / x).ln() + 1.0 / (8.0 * x))
    } else {
        bessel_i0(x).ln()
    }
}

/// Variances at or below this evaluate M_p in logarithms: sinh(1/v) and I0(a) overflow.
const NARROW_LOBE_VARIANCE: f64 = 0.1;

/// The factor of M_p that depends on the variance alone, computed once per render: ln(1/(2v))
/// for narrow lobes, sinh(1/v)·2v for wide ones.
fn longitudinal_norm(v: f32) -> f64 {
    let v = v as f64;
    if v <= NARROW_LOBE_VARIANCE {
        (1.0 / (2.0 * v)).ln()
    } else {
        (1.0 / v).sinh() * 2.0 * v
    }
}

/// The longitudinal lobe M_p (normalised so that `∫ M cos θi dθi = 1`); `norm` is
/// [`longitudinal_norm`] of `v`.
fn longitudinal(cos_i: f32, cos_o: f32, sin_i: f32, sin_o: f32, v: f32, norm: f64) -> f32 {
    let v = v as f64;
    let a = cos_i as f64 * cos_o as f64 / v;
    let b = sin_i as f64 * sin_o as f64 / v;
    let m = if v <= NARROW_LOBE_VARIANCE {
        (log_bessel_i0(a) - b - 1.0 / v + std::f64::consts::LN_2 + norm).exp()
    } else {
        (-b).exp() * bessel_i0(a) / norm
    };
    m as f32
}

fn logistic(x: f32, s: f32) -> f32 {
    let x = x.abs();
    let e = (-x / s).exp();
    e / (s * (1.0 + e) * (1.0 + e))
}

fn logistic_cdf(x: f32, s: f32) -> f32 {
    1.0 / (1.0 + (-x / s).exp())
}

/// The logistic of scale `s` restricted to [−π, π] and renormalised by its `mass` there.
fn trimmed_logistic(x: f32, s: f32, mass: f32) -> f32 {
    logistic(x, s) / mass
}

fn sample_trimmed_logistic(u: f32, s: f32, mass: f32) -> f32 {
    let k = logistic_cdf(-PI, s) + u * mass;
    let x = -s * (1.0 / k - 1.0).ln();
    x.clamp(-PI, PI)
}

/// Exit azimuth of lobe p for entry offset γo and refracted γt.
fn exit_azimuth(p: usize, gamma_o: f32, gamma_t: f32) -> f32 {
    2.0 * p as f32 * gamma_t - 2.0 * gamma_o + p as f32 * PI
}

/// Wraps an angle into [−π, π].
fn wrap_angle(mut phi: f32) -> f32 {
    while phi > PI {
        phi -= TAU;
    }
    while phi < -PI {
        phi += TAU;
    }
    phi
}

/// The azimuthal lobe N_p at relative azimuth φ = φi − φo.
fn azimuthal(phi: f32, p: usize, s: f32, mass: f32, gamma_o: f32, gamma_t: f32) -> f32 {
    trimmed_logistic(wrap_angle(phi - exit_azimuth(p, gamma_o, gamma_t)), s, mass)
}

/// Unpolarised Fresnel reflectance of a dielectric for incidence cosine `cos_i` from outside.
fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin_t = (1.0 - cos_i * cos_i).max(0.0).sqrt() / eta;
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    let parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (parallel * parallel + perpendicular * perpendicular)
}

/// A fibre hit: its frame, entry offset and absorption, and the shared shape parameters.
#[derive(Clone, Copy, Debug)]
pub struct ChiangHair<'a> {
    tangent: Vec3,
    /// b1, b2 complete `tangent` to a right-handed frame; azimuths are measured from b1 to b2.
    b1: Vec3,
    b2: Vec3,
    /// Offset across the fibre in [−1, 1], sin γo.
    h: f32,
    gamma_o: f32,
    sigma_a: Vec3,
    params: &'a ChiangParams,
    /// The outgoing direction a path's vertex evaluates every light sample and its continuation
    /// for, with what depends on it alone (see [`ChiangHair::seen_from`]).
    seen_from: Option<(Vec3, Outgoing)>,
}

/// Per-outgoing-direction quantities both eval and sample need.
#[derive(Clone, Copy, Debug)]
struct Outgoing {
    sin_o: f32,
    cos_o: f32,
    phi_o: f32,
    gamma_t: f32,
    attenuation: [Vec3; 4],
    /// Probabilities of picking each lobe when sampling: proportional to its attenuation.
    probabilities: [f32; 4],
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

impl<'a> ChiangHair<'a> {
    /// A fibre of unit tangent `tangent` hit at offset `h` (sin of the angle between the surface
    /// normal and the viewer, signed about the tangent; see [`offset_across_fibre`]).
    pub fn new(tangent: Vec3, h: f32, sigma_a: Vec3, params: &'a ChiangParams) -> ChiangHair<'a> {
        let b1 = tangent.any_orthonormal_vector();
        let b2 = tangent.cross(b1);
        let h = if h.is_finite() { h.clamp(-0.999, 0.999) } else { 0.0 };
        ChiangHair { tangent, b1, b2, h, gamma_o: h.asin(), sigma_a, params, seen_from: None }
    }

    /// The same fibre with the terms that depend only on the outgoing direction `wo` (angles,
    /// refraction, Fresnel and absorption per lobe, lobe probabilities) computed once: a path
    /// vertex evaluates several light samples and a continuation towards the same `wo`. Results
    /// are bit-identical to computing them per call.
    pub fn seen_from(mut self, wo: Vec3) -> ChiangHair<'a> {
        self.seen_from = Some((wo, self.outgoing(wo)));
        self
    }

    /// The outgoing terms for `wo`: the cached ones when `wo` is the vertex's own direction.
    fn outgoing_for(&self, wo: Vec3) -> Outgoing {
        match self.seen_from {
            Some((cached, out)) if cached == wo => out,
            _ => self.outgoing(wo),
        }
    }

    fn angles(&self, w: Vec3) -> (f32, f32, f32) {
        let sin = self.tangent.dot(w).clamp(-1.0, 1.0);
        let cos = (1.0 - sin * sin).max(0.0).sqrt();
        (sin, cos, self.b2.dot(w).atan2(self.b1.dot(w)))
    }

    fn outgoing(&self, wo: Vec3) -> Outgoing {
        let (sin_o, cos_o, phi_o) = self.angles(wo);
        let eta = HAIR_IOR;
        // Refraction into the fibre: longitudinally by Snell, azimuthally with Bravais' index.
        let sin_t = sin_o / eta;
        let cos_t = (1.0 - sin_t * sin_t).max(1e-12).sqrt();
        let eta_p = (eta * eta - sin_o * sin_o).max(0.0).sqrt() / cos_o.max(1e-6);
        let sin_gamma_t = (self.h / eta_p).clamp(-1.0, 1.0);
        let cos_gamma_t = (1.0 - sin_gamma_t * sin_gamma_t).max(0.0).sqrt();
        let gamma_t = sin_gamma_t.asin();
        let path = 2.0 * cos_gamma_t / cos_t;
        let transmittance = Vec3::new(
            (-self.sigma_a.x * path).exp(),
            (-self.sigma_a.y * path).exp(),
            (-self.sigma_a.z * path).exp(),
        );
        let f = fresnel_dielectric(cos_o * self.gamma_o.cos(), eta);
        let a0 = Vec3::splat(f);
        let a1 = (1.0 - f) * (1.0 - f) * transmittance;
        let a2 = a1 * transmittance * f;
        // The geometric series of all longer paths.
        let tf = transmittance * f;
        let a3 = a2 * tf / (Vec3::ONE - tf).max(Vec3::splat(1e-6));
        let attenuation = [a0, a1, a2, a3];
        Outgoing {
            sin_o,
            cos_o,
            phi_o,
            gamma_t,
            attenuation,
            probabilities: Self::lobe_probabilities(&attenuation),
        }
    }

    /// Probabilities of picking each lobe when sampling: proportional to its attenuation.
    fn lobe_probabilities(attenuation: &[Vec3; 4]) -> [f32; 4] {
        let w = attenuation.map(luminance);
        let total: f32 = w.iter().sum();
        if total <= 0.0 {
            return [1.0, 0.0, 0.0, 0.0];
        }
        w.map(|x| x / total)
    }

    /// `S · cos θi` and the sampling density of `wi`, for light from `wi` leaving towards `wo`.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> (Vec3, f32) {
        let out = self.outgoing_for(wo);
        self.eval_with(&out, wi)
    }

    fn eval_with(&self, out: &Outgoing, wi: Vec3) -> (Vec3, f32) {
        let (sin_i, cos_i, phi_i) = self.angles(wi);
        let phi = phi_i - out.phi_o;
        let probabilities = out.probabilities;
        let (s, mass) = (self.params.logistic_scale, self.params.logistic_mass);
        let mut value = Vec3::ZERO;
        let mut pdf = 0.0;
        for (p, probability) in probabilities.iter().enumerate().take(3) {
            let (sin_op, cos_op) = self.params.shifted(p, out.sin_o, out.cos_o);
            let density = longitudinal(
                cos_i,
                cos_op,
                sin_i,
                sin_op,
                self.params.variance[p],
                self.params.longitudinal_norm[p],
            ) * azimuthal(phi, p, s, mass, self.gamma_o, out.gamma_t);
            value += out.attenuation[p] * density;
            pdf += probability * density;
        }
        let (v3, norm3) = (self.params.variance[3], self.params.longitudinal_norm[3]);
        let residual = longitudinal(cos_i, out.cos_o, sin_i, out.sin_o, v3, norm3) / TAU;
        value += out.attenuation[3] * residual;
        pdf += probabilities[3] * residual;
        (value, pdf)
    }

    /// Draws an incoming direction: `u_lobe[0]` picks the lobe, `u_lobe[1]` the azimuth within
    /// it, `u` the longitudinal angle.
    pub fn sample(&self, wo: Vec3, u_lobe: [f32; 2], u: [f32; 2]) -> Option<BsdfSample> {
        let out = self.outgoing_for(wo);
        let probabilities = out.probabilities;
        let mut p = 0;
        let mut cumulative = probabilities[0];
        while p < 3 && u_lobe[0] >= cumulative {
            p += 1;
            cumulative += probabilities[p];
        }
        let (sin_op, cos_op) = self.params.shifted(p, out.sin_o, out.cos_o);
        // d'Eon et al.'s exact sampling of the von Mises–Fisher cone around −θo'.
        let v = self.params.variance[p];
        let u0 = u[0].max(1e-5);
        let cos_cone = 1.0 + v * (u0 + (1.0 - u0) * (-2.0 / v).exp()).ln();
        let sin_cone = (1.0 - cos_cone * cos_cone).max(0.0).sqrt();
        let sin_i = (-cos_cone * sin_op + sin_cone * (TAU * u[1]).cos() * cos_op).clamp(-1.0, 1.0);
        let cos_i = (1.0 - sin_i * sin_i).max(0.0).sqrt();
        let dphi = if p < 3 {
            exit_azimuth(p, self.gamma_o, out.gamma_t)
                + sample_trimmed_logistic(u_lobe[1], self.params.logistic_scale, self.params.logistic_mass)
        } else {
            TAU * u_lobe[1]
        };
        let phi_i = out.phi_o + dphi;
        let direction =
            (self.tangent * sin_i + (self.b1 * phi_i.cos() + self.b2 * phi_i.sin()) * cos_i).normalize();
        let (value, pdf) = self.eval_with(&out, direction);
        if pdf.is_nan() || pdf <= 0.0 || !value.is_finite() {
            return None;
        }
        Some(BsdfSample { direction, weight: value / pdf, pdf })
    }
}

/// The entry offset h = sin γo of a ray seen from `wo` hitting a round fibre of unit tangent
/// `tangent` where its surface normal is `normal`: the sine of the angle from the normal to the
/// viewer, both projected across the fibre, signed by the right hand about the tangent.
pub fn offset_across_fibre(tangent: Vec3, normal: Vec3, wo: Vec3) -> f32 {
    let n = normal - tangent * tangent.dot(normal);
    let w = wo - tangent * tangent.dot(wo);
    let norms = n.length() * w.length();
    if norms.is_nan() || norms <= 1e-12 {
        return 0.0;
    }
    (tangent.dot(n.cross(w)) / norms).clamp(-1.0, 1.0)
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

    fn tangent() -> Vec3 {
        Vec3::new(0.3, 0.9, 0.1).normalize()
    }

    /// `wo` at longitudinal angle `theta_deg` and some azimuth.
    fn outgoing(theta_deg: f32) -> Vec3 {
        let t = tangent();
        let b1 = t.any_orthonormal_vector();
        let b2 = t.cross(b1);
        let a = theta_deg.to_radians();
        (t * a.sin() + (b1 * 0.6 + b2 * 0.8) * a.cos()).normalize()
    }

    /// ∫ value dω by uniform sphere sampling (independent of the BSDF's sampler), stratified.
    fn albedo_uniform(bsdf: &ChiangHair, wo: Vec3, n: u32) -> (Vec3, f32) {
        let mut value = Vec3::ZERO;
        let mut pdf = 0.0;
        for i in 0..n {
            let wi = uniform_sphere(Sampler::new(SamplerKind::Sobol, 11, i, n).get_2d());
            let (v, p) = bsdf.eval(wo, wi);
            value += v;
            pdf += p;
        }
        let scale = 4.0 * PI / n as f32;
        (value * scale, pdf * scale)
    }

    /// White furnace: at zero absorption the fibre scatters all light, for every roughness,
    /// incident angle and offset (Σ A_p = 1, each M_p N_p a normalised density).
    #[test]
    fn white_furnace_at_zero_absorption_is_within_one_percent() {
        for (beta_m, beta_n) in [(0.2, 0.2), (0.3, 0.3), (0.5, 0.7), (0.9, 0.9)] {
            let params = ChiangParams::new(beta_m, beta_n, 2.0);
            for theta in [-70.0f32, -30.0, 0.0, 25.0, 60.0] {
                for h in [-0.8, -0.2, 0.0, 0.5, 0.9] {
                    let bsdf = ChiangHair::new(tangent(), h, Vec3::ZERO, &params);
                    let (albedo, _) = albedo_uniform(&bsdf, outgoing(theta), 1 << 16);
                    assert!(
                        (albedo - Vec3::ONE).abs().max_element() < 0.01,
                        "β_m {beta_m} β_n {beta_n} θo {theta} h {h}: albedo {albedo}"
                    );
                }
            }
        }
    }

    /// Absorption only removes energy, and blue goes first for melanin.
    #[test]
    fn pigmented_fibres_absorb() {
        let params = ChiangParams::default();
        let bsdf = ChiangHair::new(tangent(), 0.3, sigma_a_from_melanin(1.3, 0.2), &params);
        let (albedo, _) = albedo_uniform(&bsdf, outgoing(20.0), 1 << 14);
        assert!(albedo.max_element() < 1.0 && albedo.x > albedo.y && albedo.y > albedo.z, "{albedo}");
    }

    #[test]
    fn pdf_integrates_to_one() {
        for (beta_m, beta_n) in [(0.25, 0.3), (0.6, 0.5)] {
            let params = ChiangParams::new(beta_m, beta_n, 3.0);
            for theta in [-50.0f32, 10.0, 70.0] {
                let bsdf = ChiangHair::new(tangent(), -0.4, sigma_a_from_melanin(1.0, 0.5), &params);
                let (_, total) = albedo_uniform(&bsdf, outgoing(theta), 1 << 16);
                assert!((total - 1.0).abs() < 0.01, "β_m {beta_m} θo {theta}: ∫pdf = {total}");
            }
        }
    }

    /// A vertex's cached outgoing terms change nothing: eval and sample give the same bits as
    /// the uncached fibre, for its own `wo` and (falling back) for any other.
    #[test]
    fn cached_outgoing_terms_are_bit_identical() {
        let params = ChiangParams::new(0.25, 0.45, 3.0);
        let mut sampler = Sampler::new(SamplerKind::Independent, 11, 0, 1 << 20);
        for h in [-0.8f32, 0.0, 0.55] {
            for theta in [-60.0f32, 5.0, 70.0] {
                let wo = outgoing(theta);
                let plain = ChiangHair::new(tangent(), h, sigma_a_from_melanin(1.1, 0.4), &params);
                let cached = plain.seen_from(wo);
                for _ in 0..64 {
                    let wi = uniform_sphere(sampler.get_2d());
                    let (a, b) = (plain.eval(wo, wi), cached.eval(wo, wi));
                    assert_eq!(
                        (a.0.to_array().map(f32::to_bits), a.1.to_bits()),
                        (b.0.to_array().map(f32::to_bits), b.1.to_bits())
                    );
                    assert_eq!(plain.eval(wi, wo).1.to_bits(), cached.eval(wi, wo).1.to_bits());
                    let (u1, u2) = (sampler.get_2d(), sampler.get_2d());
                    let (x, y) = (plain.sample(wo, u1, u2), cached.sample(wo, u1, u2));
                    assert_eq!(
                        x.map(|s| (s.direction, s.weight, s.pdf)),
                        y.map(|s| (s.direction, s.weight, s.pdf))
                    );
                }
            }
        }
    }

    /// Sampled directions follow the evaluated density: a chi-square test over a grid of
    /// (sin θi, φi) cells, expected counts integrated from `pdf` at fine sub-cell resolution.
    #[test]
    fn sampled_directions_follow_the_density_chi_square() {
        let (rows, cols) = (16usize, 32usize);
        let samples = 200_000u32;
        for (beta_m, beta_n, theta, h) in [(0.3, 0.3, 30.0f32, 0.4f32), (0.15, 0.6, -60.0, -0.7)] {
            let params = ChiangParams::new(beta_m, beta_n, 2.0);
            let bsdf = ChiangHair::new(tangent(), h, sigma_a_from_melanin(0.8, 0.3), &params);
            let wo = outgoing(theta);
            let cell = |w: Vec3| {
                let (s, _, phi) = bsdf.angles(w);
                let r = (((s + 1.0) * 0.5 * rows as f32) as usize).min(rows - 1);
                let c = (((phi + PI) / TAU * cols as f32) as usize).min(cols - 1);
                r * cols + c
            };
            let mut observed = vec![0f64; rows * cols];
            let mut total_weight = Vec3::ZERO;
            for i in 0..samples {
                let mut s = Sampler::new(SamplerKind::Independent, 3, i, samples);
                let (a, b) = (s.get_2d(), s.get_2d());
                if let Some(sample) = bsdf.sample(wo, a, b) {
                    observed[cell(sample.direction)] += 1.0;
                    total_weight += sample.weight;
                }
            }
            // Expected: ∫ pdf dω over each cell; dω = d(sin θ) dφ.
            let sub = 8;
            let mut expected = vec![0f64; rows * cols];
            for r in 0..rows * sub {
                for c in 0..cols * sub {
                    let s = -1.0 + (r as f32 + 0.5) / (rows * sub) as f32 * 2.0;
                    let phi = -PI + (c as f32 + 0.5) / (cols * sub) as f32 * TAU;
                    let cos = (1.0 - s * s).sqrt();
                    let w = bsdf.tangent * s + (bsdf.b1 * phi.cos() + bsdf.b2 * phi.sin()) * cos;
                    let area = (2.0 / (rows * sub) as f64) * (TAU as f64 / (cols * sub) as f64);
                    expected[(r / sub) * cols + c / sub] += bsdf.eval(wo, w).1 as f64 * area;
                }
            }
            // Pool cells expecting fewer than 5 samples, as the chi-square test requires.
            let (mut chi2, mut dof, mut pooled_o, mut pooled_e) = (0.0, 0usize, 0.0, 0.0);
            for (o, e) in observed.iter().zip(&expected) {
                let e = e * samples as f64;
                if e < 5.0 {
                    pooled_o += o;
                    pooled_e += e;
                } else {
                    chi2 += (o - e).powi(2) / e;
                    dof += 1;
                }
            }
            if pooled_e >= 5.0 {
                chi2 += (pooled_o - pooled_e).powi(2) / pooled_e;
                dof += 1;
            }
            dof -= 1;
            // Upper 0.1 % point of chi-square by the Wilson–Hilferty approximation.
            let k = dof as f64;
            let z = 3.09;
            let critical = k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3);
            assert!(chi2 < critical, "β_m {beta_m} θo {theta}: χ² {chi2:.1} > {critical:.1} ({dof} dof)");
            // The mean sample weight estimates the albedo the eval integrates to.
            let (albedo, _) = albedo_uniform(&bsdf, wo, 1 << 16);
            let estimate = total_weight / samples as f32;
            assert!((estimate - albedo).abs().max_element() < 0.01, "{estimate} vs {albedo}");
        }
    }

    /// Reciprocity where the model has it. The longitudinal lobe is symmetric in θi and θo. The
    /// attenuation depends on θo alone (the paper's choice), so the near-field model is not
    /// reciprocal in general; but for |θi| = |θo| and no tilt both directions see the same path
    /// lengths and Fresnel terms, and the h-averaged (far-field) BSDF must be reciprocal.
    #[test]
    fn reciprocal_where_the_model_is() {
        for v in [0.01f32, 0.09, 0.3, 2.0] {
            for (a, b) in [(0.3f32, -0.5f32), (1.2, 0.1), (-0.9, -0.2)] {
                let norm = longitudinal_norm(v);
                let m1 = longitudinal(a.cos(), b.cos(), a.sin(), b.sin(), v, norm);
                let m2 = longitudinal(b.cos(), a.cos(), b.sin(), a.sin(), v, norm);
                assert!((m1 - m2).abs() <= 1e-5 * m1.abs().max(1e-6), "v {v}: {m1} vs {m2}");
            }
        }
        let params = ChiangParams::new(0.35, 0.4, 0.0);
        let sigma = sigma_a_from_melanin(0.5, 0.2);
        let t = tangent();
        let b1 = t.any_orthonormal_vector();
        let b2 = t.cross(b1);
        let dir = |theta: f32, phi: f32| {
            let a = theta.to_radians();
            t * a.sin() + (b1 * phi.cos() + b2 * phi.sin()) * a.cos()
        };
        for (ti, to, dphi) in [(20.0f32, -20.0f32, 1.1f32), (-60.0, 60.0, 2.5), (35.0, 35.0, -0.7)] {
            let (wi, wo) = (dir(ti, dphi), dir(to, 0.0));
            let n = 8192;
            let (mut forward, mut backward) = (Vec3::ZERO, Vec3::ZERO);
            for k in 0..n {
                let h = -1.0 + 2.0 * (k as f32 + 0.5) / n as f32;
                let bsdf = ChiangHair::new(t, h, sigma, &params);
                forward += bsdf.eval(wo, wi).0;
                backward += bsdf.eval(wi, wo).0;
            }
            let rel = ((forward - backward).abs() / forward.max(Vec3::splat(1e-6))).max_element();
            assert!(rel < 0.01, "θi {ti} θo {to}: {forward} vs {backward}");
        }
    }

    #[test]
    fn colour_inversion_orders_channels_and_is_zero_for_white() {
        assert_eq!(sigma_a_from_color(Vec3::ONE, 0.3), Vec3::ZERO);
        let s = sigma_a_from_color(Vec3::new(0.5, 0.3, 0.1), 0.3);
        assert!(s.x < s.y && s.y < s.z && s.x > 0.0);
    }

    #[test]
    fn offset_is_signed_sine_across_the_fibre() {
        let t = Vec3::Y;
        let wo = Vec3::Z;
        // Hit at offset +0.6 along x of a unit circle seen from +z: normal (0.6, 0, 0.8).
        let h = offset_across_fibre(t, Vec3::new(0.6, 0.0, 0.8), wo);
        assert!((h.abs() - 0.6).abs() < 1e-6);
        let h2 = offset_across_fibre(t, Vec3::new(-0.6, 0.0, 0.8), wo);
        assert!((h + h2).abs() < 1e-6);
    }
}
