//! The preview renderer: an Embree 4 path tracer with Kajiya–Kay hair shading (model.md §4).
//!
//! Laid out like pbrt-v4: [`camera`] (named views with auto-framing, explicit cameras),
//! [`scene`] (groom curves, head, floor), [`bsdf`] (Kajiya–Kay, Lambert), [`light`] (key light,
//! environment), [`sampler`] (per-pixel Owen-scrambled Sobol), [`integrator`] (path tracing and
//! debug views) and [`image`] (PNG / EXR output, comparisons).
//!
//! Determinism: every pixel sample draws from a stream seeded by the pixel, the sample index and
//! the render seed, and a pixel's samples are summed in index order, so the image is
//! bit-identical at any thread count. A time budget only decides how many sample passes run; the
//! image equals an uninterrupted render with the sample count it reports.
//!
//! Thin hair: a strand is 40–80 µm wide, a preview pixel covers a millimetre or more, so a strand
//! covers a few percent of a pixel. coif renders true widths by default and lets the samples
//! average coverage — a sparse groom looks as sparse as it is. `min_pixel_width` widens strands
//! to a pixel footprint and lowers their opacity by the same factor (coverage is kept on average:
//! nothing gets denser, only less aliased); `width_scale` is the explicit "draw it thicker" knob.
pub mod bsdf;
pub mod camera;
pub mod hair_bsdf;
pub mod image;
pub mod integrator;
pub mod light;
pub mod sampler;
pub mod scene;
pub mod shot;

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use glam::Vec3;
use rayon::prelude::*;

use crate::embree::{self, Device, PACKET};
use crate::error::{Error, Result};
use crate::groom::Groom;

use bsdf::HairLobes;
use camera::{Camera, CameraSpec, View, DEFAULT_FOV};
use hair_bsdf::ChiangParams;
use image::{Aov, Image};
use integrator::{Integrator, Lobe, Mode, RayCount};
use light::{Environment, KeyLight, Light};
use sampler::{hash, Sampler, SamplerKind};
use scene::{AttributeView, RenderScene, SceneOptions, WidthFloor};

/// Which extra images (AOVs) to keep besides RGBA.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovSet {
    /// First-hit distance, channel `Z`.
    pub depth: bool,
    /// First-hit hair tangent, channels `tangent.X/Y/Z`.
    pub tangent: bool,
}

/// The key light: a direction (world, towards the light) or the default placement above and to
/// the left of the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KeySettings {
    pub direction: Option<Vec3>,
    pub irradiance: Vec3,
    pub angular_radius_degrees: f32,
}

impl Default for KeySettings {
    fn default() -> Self {
        KeySettings {
            direction: None,
            irradiance: Vec3::new(1.0, 0.95, 0.88) * 2.6,
            angular_radius_degrees: 3.0,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    pub view: View,
    pub camera: Option<CameraSpec>,
    pub fov_degrees: f32,
    pub scene: SceneOptions,
    pub mode: Mode,
    pub max_depth: u32,
    pub sampler: SamplerKind,
    pub seed: u64,
    pub key: KeySettings,
    /// The lights of the user's shot, replacing the key light (`None`: the key light).
    pub lights: Option<Vec<Light>>,
    pub environment: Environment,
    /// Exposure in stops applied to the beauty image.
    pub exposure: f32,
    pub time_budget: Option<Duration>,
    /// Render only this window `(x, y, width, height)` of the full frame (benchmarks).
    pub window: Option<(u32, u32, u32, u32)>,
    pub aovs: AovSet,
    /// The hair scattering model and the Chiang model's shape parameters.
    pub lobe: Lobe,
    pub chiang: ChiangParams,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 640,
            height: 480,
            spp: 32,
            view: View::default(),
            camera: None,
            fov_degrees: DEFAULT_FOV,
            scene: SceneOptions::default(),
            mode: Mode::Beauty,
            max_depth: 8,
            sampler: SamplerKind::Sobol,
            seed: 0,
            key: KeySettings::default(),
            lights: None,
            environment: Environment::default(),
            exposure: 0.0,
            time_budget: None,
            window: None,
            aovs: AovSet::default(),
            lobe: Lobe::default(),
            chiang: ChiangParams::default(),
        }
    }
}

/// Figures about a finished render.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RenderStats {
    /// Samples per pixel actually taken (fewer than asked when a time budget ran out).
    pub spp: u32,
    pub rays: u64,
    pub seconds: f64,
    pub segments: usize,
    pub build_seconds: f64,
}

pub struct Rendered {
    pub image: Image,
    pub stats: RenderStats,
}

impl RenderSettings {
    fn check(&self) -> Result<()> {
        let bad = |m: &str| Err(Error::Usage(format!("render: {m}")));
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return bad("--res must be between 1x1 and 16384x16384");
        }
        if self.spp == 0 || self.spp > 1 << 20 {
            return bad("--spp must be between 1 and 1048576");
        }
        if self.max_depth == 0 {
            return bad("--max-depth must be at least 1");
        }
        crate::validate::number("--fov", self.fov_degrees, camera::FOV_DEGREES).map_err(Error::Usage)?;
        self.chiang.check().map_err(|m| Error::Usage(format!("render: {m}")))?;
        if let Some(c) = self.scene.color {
            if !(c.min_element() >= 0.0 && c.max_element() <= 1.0) {
                return bad(&format!("--color {c} must have every channel in [0, 1]"));
            }
        }
        if let Some([eumelanin, pheomelanin]) = self.scene.melanin {
            let (lo, hi) = hair_bsdf::MELANIN_RANGE;
            for (flag, v) in [("--melanin", eumelanin), ("--pheomelanin", pheomelanin)] {
                if !(v >= lo && v <= hi) {
                    return bad(&format!("{flag} {v} is outside [{lo}, {hi}]"));
                }
            }
        }
        if let Some((x, y, w, h)) = self.window {
            if w == 0 || h == 0 || x + w > self.width || y + h > self.height {
                return bad("the render window must lie inside the image");
            }
        }
        Ok(())
    }
}

/// Parses `WxH`.
pub fn parse_resolution(text: &str) -> Result<(u32, u32)> {
    let bad = || Error::Usage(format!("--res '{text}': expected WIDTHxHEIGHT, e.g. 640x480"));
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 {
        return Err(bad());
    }
    Ok((w, h))
}

/// Camera for a groom's bounds (hair and head).
fn make_camera(settings: &RenderSettings, bounds: (Vec3, Vec3)) -> Camera {
    match settings.camera {
        Some(spec) => Camera::look_at(
            spec.position,
            spec.target,
            spec.up,
            spec.fov_degrees.unwrap_or(settings.fov_degrees),
            settings.width,
            settings.height,
        ),
        None => Camera::frame(
            settings.view,
            bounds.0,
            bounds.1,
            settings.fov_degrees,
            settings.width,
            settings.height,
        ),
    }
}

/// Bounds of the groom's points padded by their radii, and of the head when it will be shown.
fn groom_bounds(groom: &Groom, options: &SceneOptions) -> Result<(Vec3, Vec3)> {
    let shown = scene::shown_strands(groom)?;
    let points = shown.iter().flat_map(|&strand| &groom.points[groom.strand_range(strand)]);
    let (mut lo, mut hi) =
        points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    if options.head.analytic_head(groom) {
        let head = crate::head::Head::default();
        lo = lo.min(head.center - head.radii);
        hi = hi.max(head.center + head.radii);
    }
    for p in options.head.own_meshes(groom).flat_map(|m| &m.points) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    Ok((lo, hi))
}

/// Renders a groom. `progress(done, total)` is called as rows finish a pass (in any order), in
/// samples of rows.
pub fn render(
    groom: &Groom,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Rendered> {
    settings.check()?;
    groom.validate()?;
    let start = Instant::now();
    let device = Device::new()?;

    // The camera depends only on the groom's bounds, so a minimum pixel width can use it.
    let camera = make_camera(settings, groom_bounds(groom, &settings.scene)?);
    let width_floor = WidthFloor {
        camera_position: camera.position,
        pixel_size_at_unit_distance: camera.pixel_size_at_unit_distance(),
        min_pixels: settings.scene.min_pixel_width,
    };
    let scene = RenderScene::build(&device, groom, &settings.scene, Some(&width_floor))?;
    let build_seconds = start.elapsed().as_secs_f64();

    let key_direction = settings.key.direction.unwrap_or_else(|| {
        (camera.right() * -0.55 + camera.up() * 0.8 - camera.forward() * 0.45).normalize()
    });
    let lights = match &settings.lights {
        Some(lights) => lights.clone(),
        None => vec![Light::Distant(KeyLight::new(
            key_direction,
            settings.key.irradiance,
            settings.key.angular_radius_degrees,
        ))],
    };
    let debug_light = lights
        .iter()
        .find_map(|l| if let Light::Distant(key) = l { Some(key.direction) } else { None })
        .unwrap_or(key_direction);

    let attribute = match &settings.mode {
        Mode::Attribute { name, .. } => Some(AttributeView::from_groom(groom, name)?),
        _ => None,
    };
    let attribute_range = match (&settings.mode, &attribute) {
        (Mode::Attribute { range: Some(r), .. }, _) => *r,
        (_, Some(a)) => {
            let (lo, hi) = a.range();
            // Rates and wetness live in [0, 1]: keep that scale so images compare.
            if lo >= 0.0 && hi <= 1.0 {
                (0.0, 1.0)
            } else {
                (lo, hi)
            }
        }
        _ => (0.0, 1.0),
    };
    let (lo, hi) = scene.bounds;
    let corners = (0..8).map(|i| {
        Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    });
    let depth_range = corners.fold((f32::INFINITY, 0.0f32), |(n, f), c| {
        let d = (c - camera.position).dot(camera.forward());
        (n.min(d), f.max(d))
    });
    let lobes = HairLobes::default();
    let integrator = Integrator {
        scene: &scene,
        camera,
        lights: &lights,
        environment: settings.environment,
        debug_light,
        lobes: &lobes,
        lobe: settings.lobe,
        chiang: &settings.chiang,
        max_depth: settings.max_depth,
        mode: &settings.mode,
        attribute: attribute.as_ref(),
        attribute_range,
        depth_range: (depth_range.0.max(0.0), depth_range.1),
        epsilon: 1e-5 * (hi - lo).max_element().max(1e-3),
    };

    let (x0, y0, w, h) = settings.window.unwrap_or((0, 0, settings.width, settings.height));
    let pixels = (w * h) as usize;
    let mut sums = vec![[0f32; 4]; pixels];
    // Per pixel: summed first-hit distance, hit count, summed tangent.
    let mut firsts = vec![(0f32, 0u32, Vec3::ZERO); pixels];
    let rays = AtomicU64::new(0);
    // Under a time budget the samples go in passes sized by the time the ones before took: the
    // first one sample a pixel, each next about half of what the time left holds (a sixteenth of
    // the samples at most, for progress), so the budget is overrun by one small pass at most
    // (fixed sixteenths of a million-sample render ran for hours past a one-second budget). The
    // image at the samples reached is the same as without a budget: each row adds its samples in
    // order, whatever the passes.
    let total_work = u64::from(settings.spp) * u64::from(h);
    let done = AtomicU64::new(0);
    let render_start = Instant::now();
    let mut spp_done = 0;
    while spp_done < settings.spp {
        let pass = match settings.time_budget {
            None => settings.spp,
            Some(_) if spp_done == 0 => 1,
            Some(budget) => {
                let per_sample = render_start.elapsed().as_secs_f64() / f64::from(spp_done);
                let left = budget.saturating_sub(start.elapsed()).as_secs_f64();
                ((0.5 * left / per_sample.max(1e-9)) as u32).clamp(1, (settings.spp / 16).max(1))
            }
        }
        .min(settings.spp - spp_done);
        let samples = spp_done..spp_done + pass;
        sums.par_chunks_mut(w as usize).zip(firsts.par_chunks_mut(w as usize)).enumerate().for_each(
            |(row, (sum_row, first_row))| {
                let y = y0 + row as u32;
                let mut row_rays = RayCount::default();
                render_row(&integrator, settings, x0, y, samples.clone(), sum_row, first_row, &mut row_rays);
                rays.fetch_add(row_rays.0, Ordering::Relaxed);
                progress(done.fetch_add(u64::from(pass), Ordering::Relaxed) + u64::from(pass), total_work);
            },
        );
        spp_done = samples.end;
        if settings.time_budget.is_some_and(|budget| start.elapsed() >= budget) {
            break;
        }
    }
    let seconds = render_start.elapsed().as_secs_f64();

    let scale = if settings.mode == Mode::Beauty { 2f32.powf(settings.exposure) } else { 1.0 };
    let n = spp_done as f32;
    let rgba =
        sums.iter().map(|s| [s[0] / n * scale, s[1] / n * scale, s[2] / n * scale, s[3] / n]).collect();
    let mut aovs = Vec::new();
    if settings.aovs.depth {
        let data = firsts.iter().map(|&(t, k, _)| if k > 0 { t / k as f32 } else { f32::INFINITY }).collect();
        aovs.push(Aov { channels: vec!["Z".into()], data });
    }
    if settings.aovs.tangent {
        let data = firsts.iter().flat_map(|&(_, k, t)| (t / k.max(1) as f32).to_array()).collect();
        aovs.push(Aov { channels: ["tangent.X", "tangent.Y", "tangent.Z"].map(String::from).to_vec(), data });
    }
    Ok(Rendered {
        image: Image { width: w, height: h, rgba, aovs },
        stats: RenderStats {
            spp: spp_done,
            rays: rays.load(Ordering::Relaxed),
            seconds,
            segments: scene.segment_count,
            build_seconds,
        },
    })
}

/// Renders samples `samples` of one row, adding into the row's sums (in sample order).
#[allow(clippy::too_many_arguments)]
fn render_row(
    integrator: &Integrator,
    settings: &RenderSettings,
    x0: u32,
    y: u32,
    samples: std::ops::Range<u32>,
    sums: &mut [[f32; 4]],
    firsts: &mut [(f32, u32, Vec3)],
    rays: &mut RayCount,
) {
    let camera = &integrator.camera;
    for chunk_start in (0..sums.len()).step_by(PACKET) {
        let lanes = (sums.len() - chunk_start).min(PACKET);
        let seeds: [u64; PACKET] = std::array::from_fn(|lane| {
            let x = x0 as u64 + (chunk_start + lane) as u64;
            hash(&[settings.seed, x, y as u64])
        });
        for s in samples.clone() {
            let mut samplers: [Sampler; PACKET] =
                std::array::from_fn(|lane| Sampler::new(settings.sampler, seeds[lane], s, settings.spp));
            let directions: [Vec3; PACKET] = std::array::from_fn(|lane| {
                let [jx, jy] = samplers[lane].get_2d();
                let x = (x0 as usize + chunk_start + lane) as f32 + jx;
                camera.direction(x, y as f32 + jy)
            });
            let coin_seeds: [u64; PACKET] =
                std::array::from_fn(|lane| hash(&[seeds[lane], s as u64, 0x636f_696e]));
            // Camera rays of neighbouring pixels are coherent: trace them as one packet.
            let rays_in: [Option<embree::Ray>; PACKET] = std::array::from_fn(|lane| {
                (lane < lanes).then(|| embree::Ray {
                    origin: camera.position,
                    direction: directions[lane],
                    t_near: 0.0,
                    t_far: f32::INFINITY,
                    id: integrator::ray_id(coin_seeds[lane], 0),
                })
            });
            rays.0 += lanes as u64;
            let first_hits = integrator.scene.embree().intersect_packet(&rays_in);
            for lane in 0..lanes {
                let result = integrator.sample(
                    directions[lane],
                    first_hits[lane],
                    &mut samplers[lane],
                    coin_seeds[lane],
                    rays,
                );
                let sum = &mut sums[chunk_start + lane];
                let r = result.radiance;
                // A non-finite sample would poison the pixel: drop it (it cannot occur by design).
                if r.is_finite() {
                    sum[0] += r.x;
                    sum[1] += r.y;
                    sum[2] += r.z;
                }
                if let Some((t, tangent)) = result.first_hit {
                    sum[3] += 1.0;
                    let f = &mut firsts[chunk_start + lane];
                    f.0 += t;
                    f.1 += 1;
                    f.2 += tangent;
                }
            }
        }
    }
}

/// Parses `x,y,z` (a colour or a direction) for the option `what`.
pub fn parse_vec3(text: &str, what: &str) -> Result<Vec3> {
    let bad = || Error::Usage(format!("{what} '{text}': expected three numbers a,b,c"));
    let v: Vec<f32> =
        text.split(',').map(|v| v.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|_| bad())?;
    if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
        return Err(bad());
    }
    Ok(Vec3::new(v[0], v[1], v[2]))
}

/// Parses `lo,hi` for a false-colour range.
pub fn parse_range(text: &str) -> Result<(f32, f32)> {
    let bad = || Error::Usage(format!("--range '{text}': expected lo,hi with lo < hi"));
    let (a, b) = text.split_once(',').ok_or_else(bad)?;
    let lo: f32 = a.trim().parse().map_err(|_| bad())?;
    let hi: f32 = b.trim().parse().map_err(|_| bad())?;
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return Err(bad());
    }
    Ok((lo, hi))
}

/// Parses a comma-separated AOV list (`depth`, `tangent`).
pub fn parse_aovs(text: &str) -> Result<AovSet> {
    let mut set = AovSet::default();
    for name in text.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        match name {
            "depth" => set.depth = true,
            "tangent" => set.tangent = true,
            other => {
                return Err(Error::Usage(format!("--aov: unknown AOV '{other}'; known: depth, tangent")))
            }
        }
    }
    Ok(set)
}

/// Runs `work` on a pool of `threads` threads (all cores when `None`).
pub fn with_threads<T: Send>(threads: Option<usize>, work: impl FnOnce() -> T + Send) -> Result<T> {
    match threads {
        None => Ok(work()),
        Some(0) => Err(Error::Usage("--threads must be at least 1".into())),
        Some(n) => {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| Error::External(format!("could not start {n} threads: {e}")))?;
            Ok(pool.install(work))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn option_parsers_accept_and_reject() {
        assert_eq!(parse_resolution("160x120").unwrap(), (160, 120));
        assert!(parse_resolution("160").is_err());
        assert!(parse_resolution("0x10").is_err());
        assert_eq!(parse_vec3("0.1, 0.2,0.3", "--color").unwrap(), Vec3::new(0.1, 0.2, 0.3));
        assert!(parse_vec3("1,2", "--color").is_err());
        assert_eq!(parse_range("0,2").unwrap(), (0.0, 2.0));
        assert!(parse_range("2,0").is_err());
        assert_eq!(parse_aovs("depth,tangent").unwrap(), AovSet { depth: true, tangent: true });
        assert!(parse_aovs("normal").is_err());
    }
}
