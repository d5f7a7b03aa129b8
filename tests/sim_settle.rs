//! Settling and export: the zero-stress rest curve of an untouched groom is the groom itself;
//! relaxation reports when it cannot converge; the exported attributes use coif's canonical names.
use coif::generate::{generate, GenerateParams, Style};
use coif::groom::AttributeRate;
use coif::sim::{BondKind, BondTarget, NoHooks, SettleOptions, SimParams, Simulation};

fn curly() -> coif::Groom {
    generate(&GenerateParams {
        strands: 24,
        vertices_per_strand: 20,
        style: Style::Curly { radius: 0.01, pitch: 0.03 },
        seed: 9,
        ..GenerateParams::default()
    })
    .unwrap()
}

#[test]
fn rest_curve_of_an_untouched_groom_is_the_groom() {
    let groom = curly();
    let sim = Simulation::new(&groom, SimParams::default()).unwrap();
    let rest = sim.rest_curves();
    for strand in 0..groom.strand_count() {
        let range = groom.strand_range(strand);
        let length = groom.strand_length(strand);
        for i in range {
            let d = rest[i].distance(groom.points[i]);
            assert!(d < 1e-4 * length, "strand {strand} vertex {i}: rest curve {d} m off");
        }
    }
}

#[test]
fn settling_reports_non_convergence() {
    let mut sim = Simulation::new(&curly(), SimParams::default()).unwrap();
    // A groom released under gravity cannot be in equilibrium after 0.05 s.
    let report = sim.settle(&SettleOptions { max_seconds: 0.05, ..SettleOptions::default() }, &NoHooks);
    assert!(!report.converged, "{report:?}");
    assert_eq!(report.steps, 18);
    assert!(report.force_residual > report.tolerance, "{report:?}");
    // Given time, it does converge, to the residual it states.
    let report = sim.settle(&SettleOptions { max_seconds: 60.0, ..SettleOptions::default() }, &NoHooks);
    assert!(report.converged, "{report:?}");
    assert!(report.force_residual <= 1e-3 && report.torque_residual <= 1e-3, "{report:?}");
    assert_eq!(sim.max_speed(), 0.0, "a static solve ends at rest");
}

/// Runs plain damped dynamics from the settled state and returns the largest vertex drift.
fn drift_after(sim: &mut Simulation, seconds: f32) -> f32 {
    let before = sim.rods().positions().to_vec();
    sim.run(seconds, &NoHooks);
    before.iter().zip(sim.rods().positions()).map(|(a, b)| a.distance(*b)).fold(0.0, f32::max)
}

#[test]
fn settling_reaches_a_state_dynamics_leaves_alone_at_every_time_step() {
    // Before the static solve, settles waited for speeds to drop under a frame drag that grows as
    // Δt shrinks: this groom needed ~15 s at 1/360 s and did not settle in 30 s at 1/1440 s.
    for dt in [1.0 / 360.0, 1.0 / 720.0, 1.0 / 1440.0] {
        let params = SimParams { dt, ..SimParams::default() };
        let mut sim = Simulation::new(&curly(), params).unwrap();
        let report = sim.settle(&SettleOptions { max_seconds: 20.0, ..SettleOptions::default() }, &NoHooks);
        eprintln!("dt 1/{:.0}: {report:?}", 1.0 / dt);
        assert!(report.converged, "dt {dt}: {report:?}");
        // Independent check: an equilibrium stays put when simulated on (the groom is 0.24 m
        // long; falling from the unsettled shape moves it centimetres within 0.5 s).
        let drift = drift_after(&mut sim, 0.5);
        assert!(drift < 5e-4, "dt {dt}: the settled groom drifts {drift} m in 0.5 s");
    }
    let mut control = Simulation::new(&curly(), SimParams::default()).unwrap();
    let fall = drift_after(&mut control, 0.5);
    assert!(fall > 1e-2, "the unsettled groom should fall: {fall} m");
}

#[test]
fn export_writes_canonical_attributes() {
    let groom = curly();
    let mut sim = Simulation::new(&groom, SimParams::default()).unwrap();
    sim.set_bond_rate(BondKind::Hydrogen, BondTarget::Strand(3), 0.25);
    sim.run(0.05, &NoHooks);
    let mut out = groom.clone();
    sim.write_to_groom(&mut out);
    out.validate().unwrap();
    for (name, components) in [
        ("rest", 3),
        ("rest_darboux", 3),
        ("bond_hydrogen", 1),
        ("bond_ionic", 1),
        ("bond_disulfide", 1),
        ("bond_peptide", 1),
    ] {
        let attribute = out.attribute(name).unwrap_or_else(|| panic!("missing {name}"));
        assert_eq!((attribute.rate, attribute.components), (AttributeRate::Vertex, components), "{name}");
    }
    let hydrogen = &out.attribute("bond_hydrogen").unwrap().floats();
    let range = groom.strand_range(3);
    assert!(hydrogen[range.clone()].iter().all(|&b| b == 0.25));
    assert!(hydrogen[..range.start].iter().chain(&hydrogen[range.end..]).all(|&b| b == 1.0));
    // Rates round-trip: a simulation built from the exported groom starts with them.
    let again = Simulation::new(&out, SimParams::default()).unwrap();
    assert_eq!(again.bonds.rates(BondKind::Hydrogen), &hydrogen[..]);
}

#[test]
fn shortest_strands_work_in_both_paths() {
    // Two-vertex strands (one edge, no edge pair): 16 of them run in SIMD lanes, a 17th alone.
    let strands: Vec<Vec<glam::Vec3>> = (0..17)
        .map(|i| {
            vec![
                glam::Vec3::new(i as f32 * 0.01, 0.0, 0.0),
                glam::Vec3::new(i as f32 * 0.01 + 0.02, 0.0, 0.0),
            ]
        })
        .collect();
    let groom = coif::Groom::from_strands(&strands, 80e-6);
    let mut sim = Simulation::new(&groom, SimParams::default()).unwrap();
    sim.run(1.0, &NoHooks);
    for s in 0..17 {
        let (a, b) = (sim.rods().positions()[2 * s], sim.rods().positions()[2 * s + 1]);
        assert!(a.is_finite() && b.is_finite());
        assert_eq!(a, groom.points[2 * s], "root moved");
        assert!((a.distance(b) - 0.02).abs() < 1e-5, "strand {s} length {}", a.distance(b));
        // The pinned root frame clamps the first edge (shear is hard), so it stays along +X.
        assert!((b - a).normalize().dot(glam::Vec3::X) > 0.999, "strand {s} edge turned: {}", b - a);
    }
}

/// Strands already at rest sleep (the stepper skips them) while the rest of the groom settles,
/// and the settle still ends with every strand at rest: eight strands hang straight down, eight
/// start horizontal and must swing down. The sleepers save steps; the swinging strands settle to
/// the shape they settle to alone; simulated on, no strand moves.
#[test]
fn strands_at_rest_sleep_while_the_others_settle() {
    let strand = |direction: glam::Vec3, x: f32| -> Vec<glam::Vec3> {
        (0..16).map(|i| glam::Vec3::new(x, 0.0, 0.0) + direction * (0.015 * i as f32)).collect()
    };
    let hanging: Vec<_> = (0..8).map(|k| strand(-glam::Vec3::Y, 0.05 * k as f32)).collect();
    let horizontal: Vec<_> = (0..8).map(|k| strand(glam::Vec3::Z, 0.05 * k as f32)).collect();
    let settle = |strands: &[Vec<glam::Vec3>]| {
        let groom = coif::Groom::from_strands(strands, 80e-6);
        let mut sim = Simulation::new(&groom, SimParams::default()).unwrap();
        let report = sim.settle(&SettleOptions { max_seconds: 60.0, ..SettleOptions::default() }, &NoHooks);
        eprintln!("{} strands: {report:?}", strands.len());
        assert!(report.converged, "{report:?}");
        (sim, report)
    };
    let mixed: Vec<_> = hanging.iter().chain(&horizontal).cloned().collect();
    let (mut sim, report) = settle(&mixed);
    // The hanging strands sleep from the first probes on.
    assert!(report.strand_steps_asleep > 8 * report.steps / 2, "{report:?}");
    let (alone, alone_report) = settle(&horizontal);
    assert_eq!(alone_report.strand_steps_asleep % 8, 0, "whole lane groups sleep");
    let first_swinging = 16 * 8;
    let p = sim.rods().positions();
    for (strand, (a, b)) in
        p[first_swinging..].chunks(16).zip(alone.rods().positions().chunks(16)).enumerate()
    {
        assert!(a[15].y < -0.2, "strand {strand} did not swing down: tip at {}", a[15]);
        let apart = a.iter().zip(b).map(|(a, b)| a.distance(*b)).fold(0.0, f32::max);
        assert!(apart < 1e-3, "strand {strand} settles {apart} m from where it settles alone");
    }
    let drift = drift_after(&mut sim, 0.5);
    assert!(drift < 5e-4, "the settled groom drifts {drift} m in 0.5 s");
}

/// A settle's probes cost in proportion to the strand: a single strand of 100,000 vertices (1 m
/// of 10 µm segments, hanging) settles for 0.05 s in about the time of the same steps without
/// probes (1–2× measured; 22× before). Its probes summed gravity's lever over every pair of its
/// vertices, 5·10⁹ distances each (76 % of such a settle; over 20 s with hair–hair contacts).
#[test]
fn a_long_strands_settle_costs_about_its_steps() {
    use std::time::{Duration, Instant};
    let points: Vec<glam::Vec3> = (0..100_000).map(|k| glam::Vec3::new(0.0, -1e-5 * k as f32, 0.0)).collect();
    let groom = coif::Groom::from_strands(&[points], 8e-5);
    let mut sim = Simulation::new(&groom, SimParams::default()).unwrap();
    let start = Instant::now();
    let report = sim.settle(&SettleOptions { max_seconds: 0.05, ..SettleOptions::default() }, &NoHooks);
    let settling = start.elapsed();
    let mut control = Simulation::new(&groom, SimParams::default()).unwrap();
    let start = Instant::now();
    (0..report.steps).for_each(|_| control.step());
    let stepping = start.elapsed();
    eprintln!("{} steps: settle {settling:?}, plain steps {stepping:?}", report.steps);
    assert!(report.steps >= 18 && report.resets >= 2, "{report:?}");
    assert!(
        // Timed beside the binary's other tests: a wide margin, still a quarter of what it was.
        settling < stepping * 5 + Duration::from_millis(500),
        "settling took {settling:?}, its steps alone {stepping:?}"
    );
}
