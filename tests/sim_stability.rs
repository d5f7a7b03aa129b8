//! Long runs: an imported curly groom with no forces stays exactly as imported; a 1,000-strand
//! groom under gravity for 10,000 steps stays finite with bounded energy and gives bit-identical
//! results on 1 and 2 threads, with either strand solver.
use coif::generate::{generate, GenerateParams, Style};
use coif::sim::{NoHooks, SimParams, Simulation};
use glam::Vec3;

/// The exact bits of `points`, for bit-identity checks.
fn bits(points: &[Vec3]) -> Vec<[u32; 3]> {
    points.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
}

#[test]
fn imported_curly_groom_without_forces_stays_put() {
    let groom = generate(&GenerateParams {
        strands: 100,
        vertices_per_strand: 32,
        length: 0.24,
        style: Style::Curly { radius: 0.008, pitch: 0.03 },
        seed: 3,
        ..GenerateParams::default()
    })
    .unwrap();
    let params = SimParams { gravity: Vec3::ZERO, ..SimParams::default() };
    let mut sim = Simulation::new(&groom, params).unwrap();
    sim.run(10.0, &NoHooks);
    assert_eq!(sim.steps_taken(), 3600);
    for strand in 0..groom.strand_count() {
        let length = groom.strand_length(strand);
        let range = groom.strand_range(strand);
        let drift = groom.points[range.clone()]
            .iter()
            .zip(&sim.rods().positions()[range])
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f32::max);
        assert!(drift < 1e-4 * length, "strand {strand} drifted {drift} m of {length} m");
    }
}

fn run_large(threads: usize) -> (Vec<Vec3>, Vec<f64>) {
    let groom = generate(&GenerateParams {
        strands: 1000,
        vertices_per_strand: 4,
        length: 0.2,
        style: Style::Wavy { amplitude: 0.01, wavelength: 0.08 },
        seed: 11,
        ..GenerateParams::default()
    })
    .unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        let params = SimParams { iterations: 3, ..SimParams::default() };
        let mut sim = Simulation::new(&groom, params).unwrap();
        let mut energies = vec![sim.energy().total()];
        for step in 1..=10_000 {
            sim.step();
            if step % 500 == 0 {
                energies.push(sim.energy().total());
            }
        }
        (sim.rods().positions().to_vec(), energies)
    })
}

#[test]
fn ten_thousand_steps_are_finite_bounded_and_thread_count_independent() {
    let (one, energies) = run_large(1);
    assert!(one.iter().all(|p| p.is_finite()), "NaN or infinity in positions");
    let start = energies[0];
    let lowest = energies.iter().copied().fold(f64::INFINITY, f64::min);
    eprintln!("energies: {energies:?}");
    // Released under gravity with damping, the groom can only lose energy: it never rises above
    // the start by more than round-off of the start's magnitude.
    assert!(energies.iter().all(|e| e.is_finite()));
    assert!(
        energies.iter().all(|&e| e <= start + 1e-6 * start.abs().max(1e-12)),
        "energy rose above its start {start}: {energies:?}"
    );
    assert!(lowest < start, "gravity did nothing");
    let (two, _) = run_large(2);
    assert!(bits(&one) == bits(&two), "1 and 2 threads disagree");
}

/// Hooks that declare a projection (doing nothing) force the one-strand-at-a-time scalar path.
struct ScalarOnly;
impl coif::sim::Hooks for ScalarOnly {}

#[test]
fn simd_lanes_match_the_scalar_solver() {
    // 19 strands of 12 vertices: two lane groups of 8 and three strands alone.
    let groom = generate(&GenerateParams {
        strands: 19,
        vertices_per_strand: 12,
        length: 0.2,
        style: Style::Curly { radius: 0.01, pitch: 0.04 },
        seed: 5,
        ..GenerateParams::default()
    })
    .unwrap();
    let mut lanes = Simulation::new(&groom, SimParams::default()).unwrap();
    let mut scalar = lanes.clone();
    let difference = |a: &Simulation, b: &Simulation| {
        a.rods().positions().iter().zip(b.rods().positions()).map(|(p, q)| p.distance(*q)).fold(0.0, f32::max)
    };
    // One step: the same arithmetic up to the order of a few roundings (coordinates ~0.1 m,
    // f32 spacing ~1e-8 m).
    lanes.step();
    scalar.step_with(&ScalarOnly);
    let first = difference(&lanes, &scalar);
    assert!(first < 1e-7, "after one step lanes and scalar differ by {first} m");
    // Falling and bouncing curls amplify round-off, but it stays far below anything visible.
    for _ in 1..400 {
        lanes.step();
        scalar.step_with(&ScalarOnly);
    }
    let moved =
        groom.points.iter().zip(scalar.rods().positions()).map(|(a, b)| a.distance(*b)).fold(0.0, f32::max);
    assert!(moved > 0.01, "the groom should fall under gravity (moved {moved} m)");
    let last = difference(&lanes, &scalar);
    assert!(last < 5e-5 * 0.2, "after 400 steps lanes and scalar differ by {last} m");
}

/// The direct strand solver on curly hair falling under gravity (issue 15's opt-in solver): every
/// step stays finite, the energy never rises above its start, and 1 and 2 threads agree bit for bit.
#[test]
fn direct_solver_runs_are_finite_energy_bounded_and_thread_count_independent() {
    let groom = generate(&GenerateParams {
        strands: 40,
        vertices_per_strand: 16,
        length: 0.2,
        style: Style::Curly { radius: 0.01, pitch: 0.03 },
        seed: 5,
        ..GenerateParams::default()
    })
    .unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let params =
                SimParams { iterations: 2, ..SimParams::for_solver(coif::sim::StrandSolver::Direct) };
            let mut sim = Simulation::new(&groom, params).unwrap();
            let mut energies = vec![sim.energy().total()];
            for step in 1..=720 {
                sim.step();
                if step % 60 == 0 {
                    energies.push(sim.energy().total());
                }
            }
            (sim.rods().positions().to_vec(), energies)
        })
    };
    let (one, energies) = run(1);
    eprintln!("energies: {energies:?}");
    assert!(one.iter().all(|p| p.is_finite()) && energies.iter().all(|e| e.is_finite()));
    let start = energies[0];
    assert!(
        energies.iter().all(|&e| e <= start + 1e-6 * start.abs().max(1e-12)),
        "energy rose above its start {start}: {energies:?}"
    );
    assert!(energies.last().unwrap() < &start, "gravity did nothing");
    let (two, _) = run(2);
    assert!(bits(&one) == bits(&two), "1 and 2 threads disagree");
}

/// The direct solver gives a strand held at both ends — its pinned root and a vertex attached
/// further on, as a winding on a curler holds it — the same bits in a SIMD lane group of 8 strands
/// as simulated alone (one strand: the scalar path): the held span's stretch–shear solve and the
/// free tail's lane solve run alike on both paths.
#[test]
fn direct_solver_gives_held_spans_the_same_bits_in_lanes_as_alone() {
    let groom = generate(&GenerateParams {
        strands: 8,
        vertices_per_strand: 16,
        length: 0.2,
        style: Style::Curly { radius: 0.01, pitch: 0.04 },
        seed: 7,
        ..GenerateParams::default()
    })
    .unwrap();
    let held = 10;
    let run = |groom: &coif::Groom| {
        let mut sim = Simulation::new(groom, SimParams::for_solver(coif::sim::StrandSolver::Direct)).unwrap();
        for strand in 0..groom.strand_count() {
            let vertex = groom.strand_range(strand).start + held;
            sim.attach(vertex, groom.points[vertex]);
        }
        for _ in 0..200 {
            sim.step();
        }
        sim.rods().positions().to_vec()
    };
    let together = run(&groom);
    let moved = groom.points.iter().zip(&together).map(|(a, b)| a.distance(*b)).fold(0.0, f32::max);
    assert!(moved > 0.005, "the held spans should sag under gravity (moved {moved} m)");
    for strand in 0..groom.strand_count() {
        let alone = run(&coif::groups::assemble(&[(&groom, &[strand])]).unwrap());
        assert_eq!(bits(&alone), bits(&together[groom.strand_range(strand)]), "strand {strand}");
    }
}
