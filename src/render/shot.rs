//! The user's shot: the camera, the lights and the floor a preview is rendered with, from a small
//! scene file (TOML) or from a USD stage's `UsdGeom.Camera` and `UsdLux` lights — so a preview
//! matches the shot's framing, and two renderers can be compared on the same scene.
//!
//! Scene file (every table optional; unknown keys are refused):
//!
//! ```toml
//! [camera]
//! position = [0.0, 0.1, 0.9]   # metres, Y up
//! target = [0.0, 0.0, 0.0]
//! up = [0.0, 1.0, 0.0]         # optional roll
//! fov = 30                     # vertical field of view, degrees
//!
//! [[lights]]
//! type = "distant"             # a sun: direction towards it, irradiance, angular diameter
//! direction = [-0.5, 0.8, 0.4]
//! color = [1.0, 0.95, 0.88]
//! intensity = 2.6              # irradiance on a surface facing the light
//! angle = 6                    # degrees
//!
//! [[lights]]
//! type = "rect"                # a one-sided soft box facing `target`
//! position = [0.5, 0.5, 0.5]
//! target = [0.0, 0.0, 0.0]
//! width = 0.4
//! height = 0.3
//! intensity = 5                # radiance
//!
//! [[lights]]
//! type = "sphere"              # a bulb: centre, radius, radiance
//! position = [-0.4, 0.6, 0.5]
//! radius = 0.05
//! intensity = 40
//!
//! [[lights]]
//! type = "dome"                # uniform environment radiance (or type = "sky": coif's sky)
//! intensity = 0.5
//!
//! [floor]
//! enabled = true
//! height = -0.35               # metres (world Y)
//! size = 4                     # edge length, metres
//! albedo = [0.35, 0.35, 0.35]
//! ```
//!
//! USD (`.usda`, `.usdc`): the stage's `Camera` prim (`--scene-camera PATH` picks one of several;
//! perspective, `focalLength` and apertures, the aperture expanded to the image's aspect) and its
//! `DistantLight`, `SphereLight`, `RectLight` and `DomeLight` prims with `inputs:intensity`,
//! `inputs:exposure`, `inputs:color`, `inputs:normalize`, `inputs:angle`, `inputs:radius`,
//! `inputs:width`/`height`, placed by their `xformOp`s (distant and rect lights emit along their
//! local −Z), in metres and Y up like the groom. `treatAsPoint` is a hint UsdLux lets area-light
//! renderers ignore: a sphere light stays a sphere. Other light types (disk, cylinder, portal,
//! geometry, mesh, volume, plugin lights), textured dome or rect lights, IES profiles and colour
//! temperatures are refused, naming the prim: coif renders a preview with what it can show
//! faithfully, not an approximation of a light it does not have. A stage with lights but no
//! dome light has a black environment. Area lights light the scene but the camera does not see
//! them, and they cast no shadow.
use std::path::Path;

use glam::{DMat4, DVec3, Vec3};
use serde::Deserialize;

use super::camera::CameraSpec;
use super::light::{Environment, KeyLight, Light, RectLight, SphereLight};
use super::RenderSettings;
use crate::error::{Error, Result};
use crate::io::usda::{self, Layer, Prim, SiteFiles, Value};
use crate::io::ImportOptions;
use crate::validate::{self, Range, COORDINATE};

/// The floor of a shot; unset fields keep the render's defaults.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FloorSpec {
    pub enabled: Option<bool>,
    pub height: Option<f32>,
    pub size: Option<f32>,
    pub albedo: Option<Vec3>,
}

/// What a scene file or USD stage says about the shot.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shot {
    pub camera: Option<CameraSpec>,
    /// The lights and the environment, replacing the default key light and sky (`None`: the
    /// scene names no lights).
    pub lights: Option<(Vec<Light>, Environment)>,
    pub floor: FloorSpec,
}

/// Radiance and irradiance a light may have (a USD sun of 10⁵ nits fits; NaN and inf do not).
const EMISSION: Range = Range::closed(0.0, MAX_EMISSION);
const MAX_EMISSION: f64 = 1e9;
/// UsdLux `inputs:exposure`, stops.
const EXPOSURE: Range = Range::closed(-60.0, 60.0);
/// A distant light's angular diameter, degrees (UsdLux allows [0, 360); a hemisphere is plenty).
const ANGLE: Range = Range::closed(0.0, 180.0);
/// Sizes of lights and the floor, metres.
const SIZE: Range = Range::above(0.0, 1e4);
/// Lights a shot may have: each is sampled at every bounce of every path.
const MAX_LIGHTS: usize = 64;

fn check_light_count(count: usize) -> std::result::Result<(), String> {
    if count > MAX_LIGHTS {
        return Err(format!(
            "{count} lights: coif samples every light at every bounce and takes at most {MAX_LIGHTS}"
        ));
    }
    Ok(())
}

impl Shot {
    /// Reads a scene file (`.toml`) or a USD stage (`.usda`, `.usdc`, `.usd`). `camera_prim`
    /// picks a camera by path on a stage with several; `aspect` (width / height) conforms a USD
    /// camera's aperture.
    pub fn load(path: &Path, camera_prim: Option<&str>, aspect: f32) -> Result<Shot> {
        let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("toml") => {
                if camera_prim.is_some() {
                    return Err(Error::Usage("--scene-camera needs a USD scene (.usda, .usdc)".into()));
                }
                let text = crate::io::input::read_text(path)?;
                from_toml(&text).map_err(|m| Error::format(path, m))
            }
            Some("usda" | "usdc" | "usd") => {
                let layer = read_layer(path)?;
                from_layer(&layer, path, camera_prim, aspect)
            }
            _ => Err(Error::Usage(format!(
                "--scene {}: expected a scene file (.toml) or a USD stage (.usda, .usdc, .usd)",
                path.display()
            ))),
        }
    }

    /// Puts the shot into render settings.
    pub fn apply(&self, settings: &mut RenderSettings) {
        if let Some(camera) = self.camera {
            settings.camera = Some(camera);
        }
        if let Some((lights, environment)) = &self.lights {
            settings.lights = Some(lights.clone());
            settings.environment = *environment;
        }
        let floor = &self.floor;
        if let Some(enabled) = floor.enabled {
            settings.scene.floor = enabled;
        }
        settings.scene.floor_height = floor.height.or(settings.scene.floor_height);
        settings.scene.floor_size = floor.size.or(settings.scene.floor_size);
        if let Some(albedo) = floor.albedo {
            settings.scene.floor_albedo = albedo;
        }
    }
}

fn read_layer(path: &Path) -> Result<Layer> {
    crate::io::usd_compose::read_stage(path, &Default::default())
}

// ---- The scene file -------------------------------------------------------------------------

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    camera: Option<CameraTable>,
    lights: Option<Vec<LightTable>>,
    floor: Option<FloorTable>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraTable {
    #[serde(deserialize_with = "crate::validate::three")]
    position: [f32; 3],
    #[serde(deserialize_with = "crate::validate::three")]
    target: [f32; 3],
    #[serde(default, deserialize_with = "crate::validate::optional_three")]
    up: Option<[f32; 3]>,
    fov: Option<f32>,
}

#[derive(Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
enum LightTable {
    Distant {
        #[serde(deserialize_with = "crate::validate::three")]
        direction: [f32; 3],
        #[serde(default, deserialize_with = "crate::validate::optional_three")]
        color: Option<[f32; 3]>,
        intensity: Option<f32>,
        angle: Option<f32>,
    },
    Rect {
        #[serde(deserialize_with = "crate::validate::three")]
        position: [f32; 3],
        #[serde(deserialize_with = "crate::validate::three")]
        target: [f32; 3],
        #[serde(default, deserialize_with = "crate::validate::optional_three")]
        up: Option<[f32; 3]>,
        width: f32,
        height: f32,
        #[serde(default, deserialize_with = "crate::validate::optional_three")]
        color: Option<[f32; 3]>,
        intensity: Option<f32>,
    },
    Sphere {
        #[serde(deserialize_with = "crate::validate::three")]
        position: [f32; 3],
        radius: f32,
        #[serde(default, deserialize_with = "crate::validate::optional_three")]
        color: Option<[f32; 3]>,
        intensity: Option<f32>,
    },
    Dome {
        #[serde(default, deserialize_with = "crate::validate::optional_three")]
        color: Option<[f32; 3]>,
        intensity: Option<f32>,
    },
    Sky {
        intensity: Option<f32>,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FloorTable {
    enabled: Option<bool>,
    height: Option<f32>,
    size: Option<f32>,
    #[serde(default, deserialize_with = "crate::validate::optional_three")]
    albedo: Option<[f32; 3]>,
}

/// The default key light's irradiance and angular diameter, for a scene file's distant light.
fn default_key() -> (Vec3, f32) {
    let key = super::KeySettings::default();
    (key.irradiance, 2.0 * key.angular_radius_degrees)
}

fn from_toml(text: &str) -> std::result::Result<Shot, String> {
    let file: SceneFile = toml::from_str(text).map_err(|e| crate::style::recipe::toml_message(&e, text))?;
    let mut shot = Shot::default();
    if let Some(c) = file.camera {
        validate::vector("[camera] position", c.position, COORDINATE)?;
        validate::vector("[camera] target", c.target, COORDINATE)?;
        if let Some(up) = c.up {
            validate::direction("[camera] up", up)?;
        }
        if let Some(fov) = c.fov {
            validate::number("[camera] fov", fov, super::camera::FOV_DEGREES)?;
        }
        let (position, target) = (Vec3::from(c.position), Vec3::from(c.target));
        if position.distance(target) < 1e-6 {
            return Err("[camera] position and target coincide".into());
        }
        shot.camera = Some(CameraSpec { position, target, up: c.up.map(Vec3::from), fov_degrees: c.fov });
    }
    if let Some(tables) = file.lights {
        let mut lights = Vec::new();
        let mut environment: Option<Environment> = None;
        for (index, table) in tables.into_iter().enumerate() {
            let key = |name: &str| format!("[[lights]] {} {name}", index + 1);
            let color = |c: Option<[f32; 3]>| -> std::result::Result<Vec3, String> {
                let c = c.unwrap_or([1.0; 3]);
                validate::vector(&key("color"), c, EMISSION)?;
                Ok(Vec3::from(c))
            };
            let intensity = |i: Option<f32>, default: f32| -> std::result::Result<f32, String> {
                let i = i.unwrap_or(default);
                validate::number(&key("intensity"), i, EMISSION)?;
                Ok(i)
            };
            let mut set_environment = |e: Environment| {
                if environment.replace(e).is_some() {
                    return Err(format!("{}: a scene has at most one dome or sky light", key("type")));
                }
                Ok(())
            };
            match table {
                LightTable::Distant { direction, color: c, intensity: i, angle } => {
                    validate::direction(&key("direction"), direction)?;
                    let (irradiance, default_angle) = default_key();
                    let angle = angle.unwrap_or(default_angle);
                    validate::number(&key("angle"), angle, ANGLE)?;
                    let irradiance = match (c, i) {
                        (None, None) => irradiance,
                        _ => color(c)? * intensity(i, 1.0)?,
                    };
                    lights.push(Light::Distant(KeyLight::new(direction.into(), irradiance, 0.5 * angle)));
                }
                LightTable::Rect { position, target, up, width, height, color: c, intensity: i } => {
                    validate::vector(&key("position"), position, COORDINATE)?;
                    validate::vector(&key("target"), target, COORDINATE)?;
                    validate::number(&key("width"), width, SIZE)?;
                    validate::number(&key("height"), height, SIZE)?;
                    if let Some(up) = up {
                        validate::direction(&key("up"), up)?;
                    }
                    let (position, target) = (Vec3::from(position), Vec3::from(target));
                    let facing = (target - position)
                        .try_normalize()
                        .ok_or_else(|| format!("{}: position and target coincide", key("target")))?;
                    // Local −Z faces the target, +Y towards `up`, as a UsdLux RectLight's frame.
                    let up = up.map(Vec3::from).filter(|u| facing.cross(*u).length_squared() > 1e-6);
                    let up = up.unwrap_or(if facing.cross(Vec3::Y).length_squared() > 1e-6 {
                        Vec3::Y
                    } else {
                        Vec3::Z
                    });
                    let x = facing.cross(up).normalize();
                    let y = x.cross(facing);
                    let radiance = color(c)? * intensity(i, 1.0)?;
                    let rect =
                        RectLight::new(position, x * (0.5 * width), y * (0.5 * height), facing, radiance)
                            .ok_or_else(|| format!("{}: the rectangle is degenerate", key("width")))?;
                    lights.push(Light::Rect(rect));
                }
                LightTable::Sphere { position, radius, color: c, intensity: i } => {
                    validate::vector(&key("position"), position, COORDINATE)?;
                    validate::number(&key("radius"), radius, SIZE)?;
                    let radiance = color(c)? * intensity(i, 1.0)?;
                    let sphere = SphereLight::new(position.into(), radius, radiance)
                        .ok_or_else(|| format!("{}: the sphere is degenerate", key("radius")))?;
                    lights.push(Light::Sphere(sphere));
                }
                LightTable::Dome { color: c, intensity: i } => {
                    set_environment(Environment::Constant(color(c)? * intensity(i, 1.0)?))?
                }
                LightTable::Sky { intensity: i } => {
                    let scale = intensity(i, 1.0)?;
                    let Environment::Sky { zenith, horizon, ground } = Environment::default() else {
                        unreachable!("the default environment is the sky")
                    };
                    set_environment(Environment::Sky {
                        zenith: zenith * scale,
                        horizon: horizon * scale,
                        ground: ground * scale,
                    })?
                }
            }
        }
        check_light_count(lights.len())?;
        shot.lights = Some((lights, environment.unwrap_or(Environment::Constant(Vec3::ZERO))));
    }
    if let Some(f) = file.floor {
        if let Some(height) = f.height {
            validate::number("[floor] height", height, COORDINATE)?;
        }
        if let Some(size) = f.size {
            validate::number("[floor] size", size, SIZE)?;
        }
        if let Some(albedo) = f.albedo {
            validate::vector("[floor] albedo", albedo, validate::FRACTION)?;
        }
        shot.floor = FloorSpec {
            enabled: f.enabled,
            height: f.height,
            size: f.size,
            albedo: f.albedo.map(Vec3::from),
        };
    }
    Ok(shot)
}

// ---- USD stages -----------------------------------------------------------------------------

/// Light prim types coif renders.
const SUPPORTED_LIGHTS: [&str; 5] = ["DistantLight", "SphereLight", "RectLight", "DomeLight", "DomeLight_1"];
/// UsdLux light prim types it refuses (see the module notes).
const UNSUPPORTED_LIGHTS: [&str; 7] =
    ["DiskLight", "CylinderLight", "PortalLight", "GeometryLight", "MeshLight", "VolumeLight", "PluginLight"];

/// A prim found on the stage, with its path and world transform (in coif's space).
struct Found<'a> {
    prim: &'a Prim,
    path: String,
    world: DMat4,
}

fn collect<'a>(
    prim: &'a Prim,
    parent_path: &str,
    parent: DMat4,
    files: SiteFiles,
    found: &mut Vec<Found<'a>>,
) -> Result<()> {
    if !prim.is_defined_and_active() {
        return Ok(());
    }
    let path = format!("{parent_path}/{}", prim.name);
    let (local, reset) = usda::local_transform(prim, None)
        .map_err(|(site, m)| files.error(site, format!("prim {path}: {m}")))?;
    let world = if reset { local } else { parent * local };
    if prim.type_name == "Camera"
        || SUPPORTED_LIGHTS.contains(&prim.type_name.as_str())
        || UNSUPPORTED_LIGHTS.contains(&prim.type_name.as_str())
    {
        found.push(Found { prim, path: path.clone(), world });
    }
    for child in &prim.children {
        collect(child, &path, world, files, found)?;
    }
    Ok(())
}

/// One attribute's numbers, or its fallback; errors name the prim and the attribute.
struct PrimValues<'a> {
    found: &'a Found<'a>,
    files: SiteFiles<'a>,
}

impl PrimValues<'_> {
    fn error(&self, message: impl std::fmt::Display) -> Error {
        let prim = self.found.prim;
        self.files.error(prim.site, format!("{} {}: {message}", prim.type_name, self.found.path))
    }

    fn numbers(&self, name: &str) -> Result<Option<Vec<f64>>> {
        let Some(attribute) = self.found.prim.attribute(name) else { return Ok(None) };
        match usda::value_at(attribute, None) {
            None | Some(Value::Blocked) => Ok(None),
            Some(value) => {
                value.to_f64().map(Some).ok_or_else(|| self.error(format!("{name} is not a number")))
            }
        }
    }

    fn number(&self, name: &str, fallback: f64, range: Range) -> Result<f64> {
        let value = match self.numbers(name)? {
            None => fallback,
            Some(v) if v.len() == 1 => v[0],
            Some(v) => return Err(self.error(format!("{name} has {} numbers, expected one", v.len()))),
        };
        validate::number(name, value, range).map_err(|m| self.error(m))?;
        Ok(value)
    }

    fn color(&self) -> Result<Vec3> {
        match self.numbers("inputs:color")? {
            None => Ok(Vec3::ONE),
            Some(v) if v.len() == 3 => {
                let c = [v[0] as f32, v[1] as f32, v[2] as f32];
                validate::vector("inputs:color", c, EMISSION).map_err(|m| self.error(m))?;
                Ok(Vec3::from(c))
            }
            Some(v) => Err(self.error(format!("inputs:color has {} numbers, expected three", v.len()))),
        }
    }

    fn flag(&self, name: &str) -> Result<bool> {
        Ok(self.numbers(name)?.is_some_and(|v| v.first().is_some_and(|&x| x != 0.0)))
    }

    fn text(&self, name: &str) -> Option<String> {
        match self.found.prim.attribute(name).and_then(|a| usda::value_at(a, None)) {
            Some(Value::Text(t)) => t.into_iter().next(),
            _ => None,
        }
    }

    /// UsdLux's scalar emission `intensity · 2^exposure`, with `fallback_intensity`.
    fn emission(&self, fallback_intensity: f64) -> Result<Vec3> {
        for refused in ["inputs:texture:file", "inputs:shaping:ies:file"] {
            if self.text(refused).is_some_and(|t| !t.is_empty()) {
                return Err(self.error(format!("{refused} is not supported (coif lights are untextured)")));
            }
        }
        if self.flag("inputs:enableColorTemperature")? {
            return Err(
                self.error("inputs:enableColorTemperature is not supported: give the colour as inputs:color")
            );
        }
        let intensity = self.number("inputs:intensity", fallback_intensity, EMISSION)?;
        let exposure = self.number("inputs:exposure", 0.0, EXPOSURE)?;
        let scalar = intensity * exposure.exp2();
        if scalar.is_nan() || scalar > MAX_EMISSION {
            return Err(
                self.error(format!("inputs:intensity · 2^inputs:exposure = {scalar:e} is too bright"))
            );
        }
        Ok(self.color()? * scalar as f32)
    }
}

fn from_layer(layer: &Layer, file: &Path, camera_prim: Option<&str>, aspect: f32) -> Result<Shot> {
    let stage = usda::stage_transform(layer, file, &ImportOptions::default())?;
    let files = SiteFiles::new(file, &layer.sources);
    let mut found = Vec::new();
    for prim in &layer.prims {
        collect(prim, "", DMat4::IDENTITY, files, &mut found)?;
    }
    let mut shot = Shot::default();

    let cameras: Vec<&Found> = found.iter().filter(|f| f.prim.type_name == "Camera").collect();
    let camera = match camera_prim {
        Some(wanted) => Some(*cameras.iter().find(|f| f.path == wanted).ok_or_else(|| {
            let names: Vec<&str> = cameras.iter().map(|f| f.path.as_str()).collect();
            Error::Usage(format!(
                "--scene-camera {wanted}: {} has no Camera prim there (it has: {})",
                file.display(),
                if names.is_empty() { "none".into() } else { names.join(", ") }
            ))
        })?),
        None if cameras.len() > 1 => {
            let names: Vec<&str> = cameras.iter().map(|f| f.path.as_str()).collect();
            return Err(Error::Usage(format!(
                "{} has {} cameras ({}); pick one with --scene-camera PATH",
                file.display(),
                cameras.len(),
                names.join(", ")
            )));
        }
        None => cameras.first().copied(),
    };
    if let Some(found) = camera {
        shot.camera = Some(usd_camera(&PrimValues { found, files }, stage, aspect)?);
    }

    let mut lights = Vec::new();
    let mut environment = None;
    let mut any_light = false;
    for found in found.iter().filter(|f| f.prim.type_name != "Camera") {
        let values = PrimValues { found, files };
        any_light = true;
        let world = stage * found.world;
        match found.prim.type_name.as_str() {
            "DistantLight" => {
                let angle = values.number("inputs:angle", 0.53, ANGLE)?;
                let mut emission = values.emission(50_000.0)?;
                let key_direction = world.transform_vector3(DVec3::Z).normalize();
                let radius = 0.5 * angle as f32;
                // Unnormalised, intensity is the disk's radiance; normalised, the irradiance.
                if !values.flag("inputs:normalize")? {
                    let key = KeyLight::new(Vec3::Z, Vec3::ONE, radius);
                    emission /= key.pdf();
                }
                if !key_direction.is_finite() {
                    return Err(values.error("the transform collapses the light's direction"));
                }
                lights.push(Light::Distant(KeyLight::new(key_direction.as_vec3(), emission, radius)));
            }
            "RectLight" => {
                let width = values.number("inputs:width", 1.0, SIZE)?;
                let height = values.number("inputs:height", 1.0, SIZE)?;
                let center = world.transform_point3(DVec3::ZERO).as_vec3();
                let half_u = world.transform_vector3(DVec3::X * 0.5 * width).as_vec3();
                let half_v = world.transform_vector3(DVec3::Y * 0.5 * height).as_vec3();
                let mut radiance = values.emission(1.0)?;
                if values.flag("inputs:normalize")? {
                    radiance /= 4.0 * half_u.cross(half_v).length();
                }
                // Emission leaves along the light's local −Z.
                let facing = world.transform_vector3(DVec3::NEG_Z).as_vec3();
                let rect = RectLight::new(center, half_u, half_v, facing, radiance)
                    .filter(|_| radiance.is_finite())
                    .ok_or_else(|| values.error("the light's rectangle is degenerate after its transform"))?;
                lights.push(Light::Rect(rect));
            }
            "SphereLight" => {
                let radius = values.number("inputs:radius", 0.5, SIZE)?;
                let center = world.transform_point3(DVec3::ZERO).as_vec3();
                // A sphere stays a sphere only under a uniform scale.
                let axes = [DVec3::X, DVec3::Y, DVec3::Z].map(|a| world.transform_vector3(a).length());
                let (smallest, largest) =
                    (axes.iter().copied().fold(f64::INFINITY, f64::min), axes[0].max(axes[1]).max(axes[2]));
                if !(smallest > 0.0 && largest <= smallest * (1.0 + 1e-4)) {
                    return Err(values.error(format!(
                        "its transform scales the sphere unevenly ({:.4}, {:.4}, {:.4}); coif renders round sphere lights",
                        axes[0], axes[1], axes[2]
                    )));
                }
                let radius = (radius * largest) as f32;
                let mut radiance = values.emission(1.0)?;
                // `treatAsPoint` is a hint renderers with area lights may ignore: coif keeps the sphere.
                if values.flag("inputs:normalize")? {
                    radiance /= 4.0 * std::f32::consts::PI * radius * radius;
                }
                let sphere = SphereLight::new(center, radius, radiance)
                    .filter(|_| radiance.is_finite())
                    .ok_or_else(|| values.error("the sphere is degenerate after its transform"))?;
                lights.push(Light::Sphere(sphere));
            }
            "DomeLight" | "DomeLight_1" => {
                let radiance = values.emission(1.0)?;
                if environment.replace(Environment::Constant(radiance)).is_some() {
                    return Err(values.error("a second DomeLight: coif renders one environment"));
                }
            }
            other => {
                return Err(values.error(format!(
                    "{other} is not supported; coif renders {} (see README)",
                    SUPPORTED_LIGHTS.join(", ")
                )))
            }
        }
    }
    if any_light {
        check_light_count(lights.len()).map_err(|m| Error::format(file, m))?;
        shot.lights = Some((lights, environment.unwrap_or(Environment::Constant(Vec3::ZERO))));
    }
    Ok(shot)
}

/// A `UsdGeom.Camera`: looks down its local −Z with +Y up; the field of view from the focal
/// length and the apertures (same units), the aperture expanded to the image's aspect.
fn usd_camera(values: &PrimValues, stage: DMat4, aspect: f32) -> Result<CameraSpec> {
    if let Some(projection) = values.text("projection") {
        if projection != "perspective" {
            return Err(
                values.error(format!("projection \"{projection}\" is not supported (perspective only)"))
            );
        }
    }
    let positive = Range::above(0.0, 1e6);
    let focal = values.number("focalLength", 50.0, positive)?;
    let horizontal = values.number("horizontalAperture", 20.955, positive)?;
    let vertical = values.number("verticalAperture", 15.2908, positive)?;
    for offset in ["horizontalApertureOffset", "verticalApertureOffset"] {
        if values.number(offset, 0.0, Range::closed(-1e6, 1e6))? != 0.0 {
            return Err(values.error(format!("{offset} is not supported (centred lenses only)")));
        }
    }
    let half_tan_y = if (aspect as f64) >= horizontal / vertical {
        0.5 * vertical / focal
    } else {
        0.5 * horizontal / focal / aspect as f64
    };
    let fov = (2.0 * half_tan_y.atan()).to_degrees() as f32;
    validate::number("the camera's vertical field of view", fov, super::camera::FOV_DEGREES)
        .map_err(|m| values.error(m))?;
    let world = stage * values.found.world;
    let position = world.transform_point3(DVec3::ZERO);
    let forward = world.transform_vector3(DVec3::NEG_Z).normalize();
    let up = world.transform_vector3(DVec3::Y).normalize();
    if !(position.is_finite() && forward.is_finite() && up.is_finite()) {
        return Err(values.error("the camera's transform is degenerate"));
    }
    validate::vector("the camera's position", position.as_vec3().into(), COORDINATE)
        .map_err(|m| values.error(m))?;
    Ok(CameraSpec {
        position: position.as_vec3(),
        target: (position + forward).as_vec3(),
        up: Some(up.as_vec3()),
        fov_degrees: Some(fov),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scene_file_reads_camera_lights_and_floor() {
        let shot = from_toml(
            r#"
            [camera]
            position = [0, 0.1, 1]
            target = [0, 0, 0]
            fov = 35
            [[lights]]
            type = "distant"
            direction = [0, 1, 0]
            intensity = 3
            angle = 4
            [[lights]]
            type = "rect"
            position = [0, 1, 0]
            target = [0, 0, 0]
            width = 0.5
            height = 0.2
            intensity = 10
            [[lights]]
            type = "dome"
            color = [0.1, 0.2, 0.3]
            [floor]
            height = -0.4
            size = 3
            albedo = [0.5, 0.5, 0.5]
            "#,
        )
        .unwrap();
        let camera = shot.camera.unwrap();
        assert_eq!((camera.position, camera.fov_degrees), (Vec3::new(0.0, 0.1, 1.0), Some(35.0)));
        let (lights, environment) = shot.lights.unwrap();
        assert_eq!(lights.len(), 2);
        let Light::Distant(key) = lights[0] else { panic!("a distant light first") };
        assert_eq!((key.direction, key.irradiance), (Vec3::Y, Vec3::splat(3.0)));
        let Light::Rect(rect) = lights[1] else { panic!("a rect light second") };
        // It faces down, towards the target: a ray from below meets its face, one from above not.
        assert!(rect.intersect(Vec3::ZERO, Vec3::Y, 10.0).is_some());
        assert!(rect.intersect(Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y, 10.0).is_none());
        assert_eq!(environment, Environment::Constant(Vec3::new(0.1, 0.2, 0.3)));
        assert_eq!(shot.floor.height, Some(-0.4));
    }

    #[test]
    fn scene_file_refusals_name_the_key() {
        for (text, key) in [
            ("[camera]\nposition = [0,0,1]\ntarget = [0,0,0]\nfov = 400", "[camera] fov"),
            ("[[lights]]\ntype = \"distant\"\ndirection = [0,0,0]", "[[lights]] 1 direction"),
            ("[[lights]]\ntype = \"dome\"\nintensity = nan", "[[lights]] 1 intensity"),
            ("[[lights]]\ntype = \"dome\"\ncolor = [1, -1, 1]", "[[lights]] 1 color"),
            ("[[lights]]\ntype = \"disk\"\nradius = 1", "disk"),
            ("[floor]\nalbedo = [2, 0, 0]", "[floor] albedo"),
            ("[floor]\nsize = inf", "[floor] size"),
            ("[floor]\nwidth = 1", "width"),
        ] {
            let error = from_toml(text).unwrap_err();
            assert!(error.contains(key), "{text:?}: {error}");
        }
    }
}
