//! The analytic head coif's sample grooms grow on: an ellipsoid with a scalp region bounded by a
//! hairline that sits high on the forehead, over the ears, and low on the nape. Simulation uses
//! the same shape as a collider; the renderer meshes it.
use glam::Vec3;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Head {
    pub center: Vec3,
    /// Semi-axes in metres: half width (X), half height (Y), half depth (Z, the face looks +Z).
    pub radii: Vec3,
}

impl Default for Head {
    /// An adult head: 15.6 cm wide, 20 cm tall, 19 cm deep, centred at the origin.
    fn default() -> Self {
        Head { center: Vec3::ZERO, radii: Vec3::new(0.078, 0.100, 0.095) }
    }
}

impl Head {
    /// The point of the surface in the direction `dir` (unit) from the centre, as a unit sphere
    /// direction stretched onto the ellipsoid.
    pub fn surface_point(&self, dir: Vec3) -> Vec3 {
        self.center + dir * self.radii
    }

    /// Outward unit normal at a surface point.
    pub fn normal_at(&self, point: Vec3) -> Vec3 {
        ((point - self.center) / (self.radii * self.radii)).normalize()
    }

    /// Whether a sphere direction lies on the scalp: the hairline rises from the nape
    /// (dir.y > -0.2 at the back) to the forehead (dir.y > 0.4 at the front).
    pub fn is_scalp(&self, dir: Vec3) -> bool {
        dir.y > 0.1 + 0.3 * dir.z
    }

    /// The ellipsoid's implicit value: < 1 inside, 1 on the surface, > 1 outside.
    pub fn implicit(&self, point: Vec3) -> f32 {
        ((point - self.center) / self.radii).length_squared()
    }

    /// Pushes a point that lies inside the ellipsoid grown by `margin` out along the radial
    /// direction onto that grown surface; points outside are returned unchanged.
    pub fn push_out(&self, point: Vec3, margin: f32) -> Vec3 {
        let grown = Head { center: self.center, radii: self.radii + Vec3::splat(margin) };
        let value = grown.implicit(point);
        if value >= 1.0 || value == 0.0 {
            return point;
        }
        grown.center + (point - grown.center) / value.sqrt()
    }

    /// Scalp UV of a sphere direction: u around the head, v from nape (0) to crown (1).
    pub fn scalp_uv(&self, dir: Vec3) -> [f32; 2] {
        let u = dir.x.atan2(dir.z) / std::f32::consts::TAU + 0.5;
        let v = (dir.y * 0.5 + 0.5).clamp(0.0, 1.0);
        [u, v]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_points_are_on_the_surface_and_push_out_lands_on_it() {
        let head = Head::default();
        let dir = Vec3::new(0.3, 0.8, -0.2).normalize();
        let p = head.surface_point(dir);
        assert!((head.implicit(p) - 1.0).abs() < 1e-5);
        let inside = head.center + (p - head.center) * 0.5;
        let pushed = head.push_out(inside, 0.0);
        assert!((head.implicit(pushed) - 1.0).abs() < 1e-5);
        let outside = p * 2.0;
        assert_eq!(head.push_out(outside, 0.0), outside);
    }

    #[test]
    fn crown_is_scalp_and_face_is_not() {
        let head = Head::default();
        assert!(head.is_scalp(Vec3::Y));
        assert!(head.is_scalp(Vec3::new(0.0, 0.0, -1.0))); // back of the head
        assert!(!head.is_scalp(Vec3::Z)); // face
        assert!(!head.is_scalp(-Vec3::Y)); // chin
    }
}
