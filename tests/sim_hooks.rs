//! The extension points the interaction and recipe stages use: root driving, obstacle projection,
//! external acceleration, mass scale and kinematic attachment.
use coif::sim::{Hooks, NoHooks, SettleOptions, SimParams, Simulation};
use coif::Groom;
use glam::{Quat, Vec3};

fn horizontal_strand(vertices: usize, length: f32) -> Groom {
    let points: Vec<Vec3> =
        (0..vertices).map(|i| Vec3::new(length * i as f32 / (vertices - 1) as f32, 0.0, 0.0)).collect();
    Groom::from_strands(&[points], 80e-6)
}

fn settle(sim: &mut Simulation, hooks: &dyn Hooks) {
    let report = sim.settle(&SettleOptions { tolerance: 1e-4, max_seconds: 40.0, iterations: None }, hooks);
    assert!(report.converged, "{report:?}");
}

#[test]
fn moving_the_root_carries_the_strand() {
    let groom = horizontal_strand(12, 0.1);
    let params = SimParams { gravity: Vec3::ZERO, damping: 6.0, ..SimParams::default() };
    let mut sim = Simulation::new(&groom, params).unwrap();
    // Turn the root frame a quarter turn about Y and move the root: the unstressed strand follows
    // rigidly, now pointing along −Z from the new root.
    let turn = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let root = Vec3::new(0.0, 0.05, 0.0);
    sim.set_root(0, root, turn * sim.root_frame(0));
    settle(&mut sim, &NoHooks);
    for (i, p) in sim.rods().positions().iter().enumerate() {
        let expected = root + turn * groom.points[i];
        assert!(p.distance(expected) < 1e-3 * 0.1, "vertex {i} at {p}, expected {expected}");
    }
}

/// A floor at y = −0.05 m, projected every iteration.
struct Floor;
impl Hooks for Floor {
    fn project(&self, _strand: usize, _first: usize, positions: &mut [Vec3], inverse_masses: &[f32]) {
        for (p, &w) in positions.iter_mut().zip(inverse_masses) {
            if w > 0.0 && p.y < -0.05 {
                p.y = -0.05;
            }
        }
    }
}

#[test]
fn obstacle_projection_and_heavier_hair() {
    let groom = horizontal_strand(25, 0.24);
    let params = SimParams { damping: 4.0, ..SimParams::default() };
    let mut free = Simulation::new(&groom, params.clone()).unwrap();
    settle(&mut free, &NoHooks);
    let free_low = free.rods().positions().iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
    assert!(free_low < -0.1, "a free strand hangs well below the floor height ({free_low})");

    let mut floored = Simulation::new(&groom, params.clone()).unwrap();
    settle(&mut floored, &Floor);
    let low = floored.rods().positions().iter().map(|p| p.y).fold(f32::INFINITY, f32::min);
    assert!(low >= -0.05 - 1e-6, "strand went through the floor: {low}");

    // Four times the mass (soaked hair) at the same stiffness sags further.
    let mut heavy = Simulation::new(&groom, params).unwrap();
    for v in 0..groom.vertex_count() {
        heavy.set_mass_scale(v, 4.0);
    }
    settle(&mut heavy, &NoHooks);
    let tip = |s: &Simulation| *s.rods().positions().last().unwrap();
    assert!(tip(&heavy).x < tip(&free).x - 0.005, "heavy tip {} vs free tip {}", tip(&heavy), tip(&free));
}

#[test]
fn external_acceleration_and_attachment() {
    let groom = horizontal_strand(12, 0.1);
    let params = SimParams { gravity: Vec3::ZERO, damping: 6.0, ..SimParams::default() };
    let mut sim = Simulation::new(&groom, params).unwrap();
    // A steady wind along +Z bends the strand towards +Z.
    sim.external_acceleration_mut().iter_mut().for_each(|a| *a = Vec3::new(0.0, 0.0, 2.0));
    settle(&mut sim, &NoHooks);
    let tip = *sim.rods().positions().last().unwrap();
    assert!(tip.z > 0.005, "wind did not bend the strand: tip {tip}");
    // Attaching the tip holds it where it is told, against the wind.
    let target = Vec3::new(0.09, 0.0, 0.0);
    sim.attach(11, target);
    settle(&mut sim, &NoHooks);
    assert!(sim.rods().positions()[11].distance(target) < 1e-7);
    sim.detach(11);
    settle(&mut sim, &NoHooks);
    assert!(sim.rods().positions()[11].z > 0.005, "released tip should blow away again");
}
