//! The blow-dryer (S1-17): a jet from `position` towards `target` that pushes each vertex by
//! `Δv = α · sin θ / (d/falloff + 1) · ŵ · Δt`, with θ the angle between the hair edge and the
//! jet and d the vertex's distance to the jet axis. The seed leaves d's unit open; coif measures
//! it in multiples of `falloff` (5 cm by default), so a jet's reach is a stated length.
use glam::Vec3;
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Dryer {
    pub position: Vec3,
    pub target: Vec3,
    /// α, in m/s² at the axis for an edge across the jet.
    pub strength: f32,
    /// Length over which the push halves away from the axis, metres.
    pub falloff: f32,
    /// Optional cone: vertices more than this angle (radians) off the axis feel nothing.
    pub cone_half_angle: Option<f32>,
    /// Heat multiplies drying (1 = a cold jet).
    pub heat: f32,
}

impl Default for Dryer {
    fn default() -> Self {
        Dryer {
            position: Vec3::new(0.0, 0.0, 0.5),
            target: Vec3::ZERO,
            strength: 10.0,
            falloff: 0.05,
            cone_half_angle: None,
            heat: 1.0,
        }
    }
}

impl Dryer {
    /// The velocity change S1-17 gives a vertex at `p` whose edge runs along `tangent`.
    pub fn velocity_change(&self, p: Vec3, tangent: Vec3, dt: f32) -> Vec3 {
        let axis = self.target - self.position;
        let Some(w) = axis.try_normalize() else { return Vec3::ZERO };
        let from_nozzle = p - self.position;
        let along = from_nozzle.dot(w);
        if along <= 0.0 {
            return Vec3::ZERO; // behind the nozzle
        }
        let off_axis = from_nozzle - w * along;
        if let Some(cone) = self.cone_half_angle {
            if off_axis.length().atan2(along) > cone {
                return Vec3::ZERO;
            }
        }
        let sin_theta = tangent.normalize_or_zero().cross(w).length();
        let d = off_axis.length() / self.falloff;
        w * (self.strength * sin_theta / (d + 1.0) * dt)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn push_follows_s1_17() {
        let dryer = Dryer { position: Vec3::new(0.0, 0.0, 1.0), target: Vec3::ZERO, ..Default::default() };
        let dt = 1.0 / 360.0;
        // On the axis, edge across the jet: full strength along the jet.
        let dv = dryer.velocity_change(Vec3::ZERO, Vec3::X, dt);
        assert!(dv.abs_diff_eq(Vec3::NEG_Z * 10.0 * dt, 1e-6));
        // Edge along the jet: no push.
        assert!(dryer.velocity_change(Vec3::ZERO, Vec3::Z, dt).length() < 1e-7);
        // One falloff length off the axis: half; 30° edge: sin 30° = one half.
        let off = dryer.velocity_change(Vec3::new(0.05, 0.0, 0.0), Vec3::X, dt).length();
        assert!((off - 5.0 * dt).abs() < 1e-6);
        let tilted = Vec3::new(30f32.to_radians().sin(), 0.0, 30f32.to_radians().cos());
        assert!((dryer.velocity_change(Vec3::ZERO, tilted, dt).length() - 5.0 * dt).abs() < 1e-6);
        // Behind the nozzle or outside the cone: nothing.
        assert_eq!(dryer.velocity_change(Vec3::new(0.0, 0.0, 2.0), Vec3::X, dt), Vec3::ZERO);
        let coned = Dryer { cone_half_angle: Some(0.2), ..dryer };
        assert_eq!(coned.velocity_change(Vec3::new(0.5, 0.0, 0.0), Vec3::X, dt), Vec3::ZERO);
    }
}
