//! A pinhole camera: named views that frame the groom automatically, or an explicit position,
//! target and field of view.
use std::str::FromStr;

use glam::Vec3;

use crate::error::{Error, Result};

/// The named viewpoints of auto-framing. The face looks +Z, Y is up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum View {
    /// From the front (+Z), slightly above.
    Front,
    /// From the right-hand side (+X).
    Side,
    /// Between front and side, slightly above.
    #[default]
    ThreeQuarter,
    /// From above, the face towards the bottom of the image.
    Top,
    /// From behind (−Z): the back of a long groom.
    Back,
}

impl View {
    /// Unit vector from the framed object towards the camera, and the up hint.
    fn direction(self) -> (Vec3, Vec3) {
        match self {
            View::Front => (Vec3::new(0.0, 0.15, 1.0).normalize(), Vec3::Y),
            View::Side => (Vec3::new(1.0, 0.1, 0.0).normalize(), Vec3::Y),
            View::ThreeQuarter => (Vec3::new(0.8, 0.3, 1.0).normalize(), Vec3::Y),
            View::Top => (Vec3::Y, Vec3::NEG_Z),
            View::Back => (Vec3::new(0.0, 0.15, -1.0).normalize(), Vec3::Y),
        }
    }
}

/// An explicit camera: `px,py,pz,tx,ty,tz[,fov]` (metres, vertical field of view in degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSpec {
    pub position: Vec3,
    pub target: Vec3,
    /// The image's up direction (default: world +Y, or −Z looking straight up or down).
    pub up: Option<Vec3>,
    pub fov_degrees: Option<f32>,
}

impl FromStr for CameraSpec {
    type Err = Error;
    fn from_str(text: &str) -> Result<CameraSpec> {
        let bad = || {
            Error::Usage(format!(
                "--camera '{text}': expected px,py,pz,tx,ty,tz[,fov] (position, target in metres, \
                 vertical field of view in degrees)"
            ))
        };
        let values: Vec<f32> =
            text.split(',').map(|v| v.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|_| bad())?;
        if !(values.len() == 6 || values.len() == 7) || values.iter().any(|v| !v.is_finite()) {
            return Err(bad());
        }
        let position = Vec3::new(values[0], values[1], values[2]);
        let target = Vec3::new(values[3], values[4], values[5]);
        // Where a shot's camera may be (a camera 1e30 m out rendered an empty image, exit 0).
        for (what, point) in [("position", position), ("target", target)] {
            crate::validate::vector(what, point.into(), crate::validate::COORDINATE)
                .map_err(|m| Error::Usage(format!("--camera '{text}': {m} (metres)")))?;
        }
        if position.distance(target) < 1e-6 {
            return Err(Error::Usage(format!("--camera '{text}': position and target coincide")));
        }
        let fov_degrees = values.get(6).copied();
        if let Some(fov) = fov_degrees {
            crate::validate::number("field of view", fov, FOV_DEGREES)
                .map_err(|m| Error::Usage(format!("--camera '{text}': {m} degrees")))?;
        }
        Ok(CameraSpec { position, target, up: None, fov_degrees })
    }
}

/// Default vertical field of view, degrees.
pub const DEFAULT_FOV: f32 = 30.0;

/// The vertical fields of view a camera may have, degrees, wherever it is given (`--fov`,
/// `--camera`, a shot's camera): a pinhole wider than 170° maps most of the image to a sliver.
pub const FOV_DEGREES: crate::validate::Range = crate::validate::Range::open(0.5, 170.0);

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half_y: f32,
    tan_half_x: f32,
    width: u32,
    height: u32,
}

impl Camera {
    /// A camera at `position` looking at `target` with the given vertical field of view; `up`
    /// (default +Y) sets the roll.
    pub fn look_at(
        position: Vec3,
        target: Vec3,
        up: Option<Vec3>,
        fov_y_degrees: f32,
        width: u32,
        height: u32,
    ) -> Camera {
        let forward = (target - position).normalize();
        let usable = |hint: Vec3| forward.cross(hint).length_squared() > 1e-6 * hint.length_squared();
        let hint = match up {
            Some(up) if usable(up) => up,
            _ if usable(Vec3::Y) => Vec3::Y,
            _ => Vec3::NEG_Z,
        };
        Camera::with_up(position, forward, hint, fov_y_degrees, width, height)
    }

    fn with_up(
        position: Vec3,
        forward: Vec3,
        up_hint: Vec3,
        fov_y_degrees: f32,
        width: u32,
        height: u32,
    ) -> Camera {
        let right = forward.cross(up_hint).normalize();
        let up = right.cross(forward);
        let tan_half_y = (fov_y_degrees.to_radians() * 0.5).tan();
        let tan_half_x = tan_half_y * width as f32 / height as f32;
        Camera { position, forward, right, up, tan_half_y, tan_half_x, width, height }
    }

    /// Frames the box `[lo, hi]` from a named view: the closest camera on the view direction that
    /// keeps every corner of the box inside the image, with a small margin.
    pub fn frame(view: View, lo: Vec3, hi: Vec3, fov_y_degrees: f32, width: u32, height: u32) -> Camera {
        let (towards_camera, up_hint) = view.direction();
        let center = 0.5 * (lo + hi);
        let probe = Camera::with_up(center, -towards_camera, up_hint, fov_y_degrees, width, height);
        let margin = 1.08;
        let mut distance: f32 = 1e-3;
        for i in 0..8 {
            let corner = Vec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            ) - center;
            let depth = corner.dot(towards_camera);
            let x = corner.dot(probe.right).abs() * margin;
            let y = corner.dot(probe.up).abs() * margin;
            distance = distance.max(depth + x / probe.tan_half_x).max(depth + y / probe.tan_half_y);
        }
        Camera::with_up(
            center + towards_camera * distance,
            -towards_camera,
            up_hint,
            fov_y_degrees,
            width,
            height,
        )
    }

    /// Unit direction of the ray through continuous pixel coordinates (x right, y down).
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.tan_half_x;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.tan_half_y;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }

    /// Width of one pixel at unit distance along the view axis, metres.
    pub fn pixel_size_at_unit_distance(&self) -> f32 {
        2.0 * self.tan_half_y / self.height as f32
    }

    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    pub fn right(&self) -> Vec3 {
        self.right
    }

    pub fn up(&self) -> Vec3 {
        self.up
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_keeps_the_box_in_view_and_fills_it() {
        let (lo, hi) = (Vec3::new(-0.1, -0.3, -0.1), Vec3::new(0.1, 0.1, 0.12));
        for view in [View::Front, View::Side, View::ThreeQuarter, View::Top, View::Back] {
            let camera = Camera::frame(view, lo, hi, 30.0, 160, 120);
            let mut max_extent: f32 = 0.0;
            for i in 0..8 {
                let corner = Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                );
                let d = corner - camera.position;
                let z = d.dot(camera.forward);
                assert!(z > 0.0, "{view:?}: corner behind the camera");
                let x = d.dot(camera.right) / z / camera.tan_half_x;
                let y = d.dot(camera.up) / z / camera.tan_half_y;
                assert!(x.abs() <= 1.0 && y.abs() <= 1.0, "{view:?}: corner outside ({x}, {y})");
                max_extent = max_extent.max(x.abs()).max(y.abs());
            }
            assert!(max_extent > 0.85, "{view:?}: the box fills only {max_extent} of the frame");
        }
    }

    #[test]
    fn centre_pixel_looks_at_the_target_and_up_is_up() {
        let camera = Camera::look_at(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, None, 40.0, 100, 100);
        assert!((camera.direction(50.0, 50.0) - Vec3::NEG_Z).length() < 1e-6);
        assert!(camera.direction(50.0, 0.0).y > 0.0, "the top row looks up");
        assert!(camera.direction(100.0, 50.0).x > 0.0, "the right column looks right");
    }

    #[test]
    fn camera_spec_parses_and_rejects() {
        let spec: CameraSpec = "0,0.1,1, 0,0,0, 35".parse().unwrap();
        assert_eq!(spec.position, Vec3::new(0.0, 0.1, 1.0));
        assert_eq!(spec.fov_degrees, Some(35.0));
        assert!("1,2,3".parse::<CameraSpec>().is_err());
        assert!("0,0,0,0,0,0".parse::<CameraSpec>().is_err());
        assert!("0,0,1,0,0,0,200".parse::<CameraSpec>().is_err());
    }
}
