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
    // A groom released under gravity cannot be still after 0.05 s.
    let report = sim.settle(
        &SettleOptions { max_speed: 1e-4, quiet_time: 0.1, max_seconds: 0.05, iterations: None },
        &NoHooks,
    );
    assert!(!report.converged, "{report:?}");
    assert_eq!(report.steps, 18);
    assert!(report.max_speed >= 1e-4);
    // Given time, it does converge, and every vertex is then slow.
    let report = sim.settle(
        &SettleOptions { max_speed: 1e-3, quiet_time: 0.1, max_seconds: 60.0, iterations: None },
        &NoHooks,
    );
    assert!(report.converged, "{report:?}");
    assert!(sim.max_speed() < 1e-3);
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
    let hydrogen = &out.attribute("bond_hydrogen").unwrap().data;
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
        let (a, b) = (sim.rods.positions[2 * s], sim.rods.positions[2 * s + 1]);
        assert!(a.is_finite() && b.is_finite());
        assert_eq!(a, groom.points[2 * s], "root moved");
        assert!((a.distance(b) - 0.02).abs() < 1e-5, "strand {s} length {}", a.distance(b));
        // The pinned root frame clamps the first edge (shear is hard), so it stays along +X.
        assert!((b - a).normalize().dot(glam::Vec3::X) > 0.999, "strand {s} edge turned: {}", b - a);
    }
}
