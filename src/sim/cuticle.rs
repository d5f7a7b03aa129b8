//! Cuticle damage (S1-13, S1-14): the cuticle carries about 58 % of a hair's bending stiffness and
//! wears off towards the tip, so stiffness falls with distance from the root:
//! `k = k_o − k_cut·(1 − c)`, `c = 1 − s·d` while `s·d < 1` (else 0), `k_cut = 0.5764·k_o`.
//! coif applies it as a factor `k/k_o` on the bending and twisting moduli.
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cuticle {
    /// Share of the stiffness the cuticle carries (`k_cut/k_o`, 0.5764 in S1).
    pub share: f32,
    /// Peel rate `s` per metre of strand (Table 1: 0.33 %/cm = 0.33 /m).
    pub peel_per_metre: f32,
}

impl Default for Cuticle {
    fn default() -> Self {
        Cuticle { share: 0.5764, peel_per_metre: 0.33 }
    }
}

impl Cuticle {
    /// Stiffness factor `k/k_o` at distance `d` (metres) from the root.
    pub fn stiffness_factor(&self, distance_from_root: f32) -> f32 {
        let worn = self.peel_per_metre * distance_from_root.max(0.0);
        let intact = if worn < 1.0 { 1.0 - worn } else { 0.0 };
        1.0 - self.share * (1.0 - intact)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn follows_s1_14() {
        let c = Cuticle::default();
        assert_eq!(c.stiffness_factor(0.0), 1.0);
        // 24 cm at 0.33 %/cm: 7.92 % of the cuticle gone, 0.5764 · 0.0792 of the stiffness lost.
        assert!((c.stiffness_factor(0.24) - (1.0 - 0.5764 * 0.0792)).abs() < 1e-6);
        // Past s·d = 1 the cuticle is gone: only the cortex's 42.36 % remains.
        assert!((c.stiffness_factor(5.0) - 0.4236).abs() < 1e-6);
        assert!(c.stiffness_factor(0.1) > c.stiffness_factor(0.2));
    }
}
