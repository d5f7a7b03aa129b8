//! Coulomb friction of the obstacle contacts on a tilted plane, at several time steps and
//! iteration counts, against its analytic limit. (Below the friction angle a draped strand should
//! come to rest; with the direct solver it creeps today — issue 15, branch `s46-friction-wip`
//! has that test and a rule that passes it.)
use coif::interact::obstacles::Shape;
use coif::sim::driver::{simulate, SimulateOptions, SimulateSummary};
use coif::sim::{SimParams, StrandSolver};
use coif::Groom;
use glam::Vec3;

const RATES: [u32; 3] = [240, 360, 1440];
const ITERATIONS: [u32; 3] = [5, 10, 20];

/// A plane through the origin tilted `slope` radians about Z: the shape, its outward normal and
/// the direction straight down it.
fn tilted(slope: f32) -> (Shape, Vec3, Vec3) {
    let normal = Vec3::new(-slope.sin(), slope.cos(), 0.0);
    let down = -Vec3::new(slope.cos(), slope.sin(), 0.0);
    (Shape::Plane { point: Vec3::ZERO, normal }, normal, down)
}

/// A straight strand of `vertices` over `length` metres, level across the plane (along Z), its
/// root `height` above where it would rest on it.
fn strand_across(normal: Vec3, vertices: usize, length: f32, width: f32, height: f32) -> Groom {
    let root = normal * (0.5 * width + height);
    let points: Vec<Vec3> =
        (0..vertices).map(|i| root + Vec3::Z * (length * i as f32 / (vertices - 1) as f32)).collect();
    Groom::from_strands(&[points], width)
}

fn run(groom: &Groom, plane: &Shape, params: SimParams, steps: u32) -> (Groom, SimulateSummary) {
    let seconds = steps as f32 * params.dt;
    let options = SimulateOptions {
        params,
        seconds,
        settle: None,
        sag_free: false,
        colliders: vec![plane.clone()],
        hair_contacts: None,
    };
    simulate(groom, &options).expect("simulates")
}

/// Above the friction angle a strand lying across the plane slides down it at the kinetic
/// acceleration g·(sin θ − μk·cos θ), whatever the solver, time step and iteration count: its
/// far half (clear of the pinned root's bending) has, after 1/20 s, slid the distance a constant
/// acceleration gives in that many steps, within 1 %: kinetic friction takes the step's whole
/// normal push, however the solver splits it between its iterations.
#[test]
fn above_the_friction_angle_a_strand_slides_at_the_kinetic_acceleration() {
    let slope = 35f32.to_radians();
    let (plane, normal, down) = tilted(slope);
    let groom = strand_across(normal, 51, 0.5, 40e-6, 0.0);
    let (gravity, dynamic_friction) = (9.8, 0.3);
    let acceleration = gravity * (slope.sin() - dynamic_friction * slope.cos());
    for solver in [StrandSolver::GaussSeidel, StrandSolver::Direct] {
        for rate in RATES {
            for iterations in ITERATIONS {
                let dt = 1.0 / rate as f32;
                let params = SimParams { dt, iterations, damping: 0.0, ..SimParams::for_solver(solver) };
                let steps = rate / 20;
                let (slid, _) = run(&groom, &plane, params, steps);
                // Symplectic Euler from rest: x_n = a·Δt²·n(n+1)/2.
                let expected = acceleration * dt * dt * (steps * (steps + 1)) as f32 / 2.0;
                for i in 25..=50 {
                    let ratio = (slid.points[i] - groom.points[i]).dot(down) / expected;
                    assert!(
                        (ratio - 1.0).abs() < 0.01,
                        "{solver:?} Δt 1/{rate} × {iterations}: vertex {i} slid {ratio:.4} of {:.3} mm",
                        expected * 1e3
                    );
                }
            }
        }
    }
}
