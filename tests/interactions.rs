//! Interactions measured against controls: water clumps wet hair, a dryer dries hair near its
//! axis first, obstacles keep vertices out, and the S1-18 penalty keeps crossing strands apart.
use std::path::Path;

use coif::generate::{generate, GenerateParams};
use coif::interact::hair_contacts::HairContacts;
use coif::interact::obstacles::Shape;
use coif::sim::{NoHooks, SimParams, Simulation};
use coif::style::{recipe, style, StyleOptions};
use coif::Groom;
use glam::Vec3;

fn run(groom: &Groom, text: &str) -> Groom {
    let recipe = recipe::parse(text, Path::new("test.toml")).expect("a valid recipe");
    style(groom, &recipe, &StyleOptions::default()).expect("styling runs").groom
}

/// Mean distance from each strand's mid-length vertex to the nearest mid-length vertex of another.
fn mean_mid_spacing(groom: &Groom) -> f32 {
    let mids: Vec<Vec3> = (0..groom.strand_count())
        .map(|s| {
            let p = groom.strand_points(s);
            p[p.len() / 2]
        })
        .collect();
    let nearest = |i: usize| {
        mids.iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, q)| mids[i].distance(*q))
            .fold(f32::MAX, f32::min)
    };
    (0..mids.len()).map(nearest).sum::<f32>() / mids.len() as f32
}

#[test]
fn water_droplets_clump_wet_hair() {
    let groom = generate(&GenerateParams {
        strands: 1500,
        length: 0.2,
        vertices_per_strand: 9,
        seed: 4,
        ..Default::default()
    })
    .unwrap();
    let common = "[settings]\nseed = 2\n[[obstacles]]\nname = \"head\"\nshape = \"head\"\n";
    let stages =
        "[[stages]]\nkind = \"wet\"\nduration = 0.1\n[[stages]]\nkind = \"process\"\nduration = 1.0\n";
    let wet_only = run(&groom, &format!("{common}{stages}"));
    let with_water = run(&groom, &format!("{common}[water]\ndroplets = 1000\n{stages}"));
    let (plain, clumped) = (mean_mid_spacing(&wet_only), mean_mid_spacing(&with_water));
    eprintln!(
        "mid-length spacing to the nearest strand: {plain:.5} m wet, {clumped:.5} m with 1000 droplets"
    );
    assert!(clumped < 0.9 * plain, "no clumping: {clumped} vs {plain}");
}

#[test]
fn a_dryer_dries_hair_near_its_axis_first() {
    let groom = coif::io::read_groom(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("grooms/seed_200x24cm.hair"),
        &Default::default(),
    )
    .unwrap()
    .groom;
    // No drying in still air: only the jet dries (S1-19). It blows at the back of the head.
    let text = r#"
[wetness]
evaporation = 0.0
[[obstacles]]
name = "head"
shape = "head"
[[stages]]
kind = "wet"
duration = 0.05
[[stages]]
kind = "dry"
duration = 0.3
dryer = { position = [0.0, -0.05, -0.5], target = [0.0, -0.05, 0.0], strength = 300.0, falloff = 0.05 }
"#;
    let dried = run(&groom, text);
    let hydrogen = &dried.attribute("bond_hydrogen").unwrap().floats();
    let axis_distance = |p: Vec3| Vec3::new(p.x, p.y + 0.05, 0.0).length();
    let (mut near, mut far) = (Vec::new(), Vec::new());
    for (v, &p) in dried.points.iter().enumerate() {
        if p.z > -0.02 {
            continue; // the face side: in the head's shadow
        }
        match axis_distance(p) {
            d if d < 0.04 => near.push(hydrogen[v]),
            d if d > 0.10 => far.push(hydrogen[v]),
            _ => {}
        }
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len() as f32;
    eprintln!(
        "hydrogen bond rate after 0.3 s of wind: {:.3} near the axis ({} vertices), {:.3} far ({})",
        mean(&near),
        near.len(),
        mean(&far),
        far.len()
    );
    assert!(near.len() > 10 && far.len() > 10);
    assert!(mean(&near) > 1.5 * mean(&far) && mean(&near) > 0.05, "{} vs {}", mean(&near), mean(&far));
}

#[test]
fn obstacles_keep_vertices_out() {
    // Hair hangs onto a floor that rises under the head while a rod sits in it: after the run no
    // vertex is inside the head, the floor or the rod by more than 0.5 mm.
    let groom = generate(&GenerateParams {
        strands: 300,
        length: 0.3,
        vertices_per_strand: 16,
        seed: 9,
        ..Default::default()
    })
    .unwrap();
    let text = r#"
[[obstacles]]
name = "head"
shape = "head"
[[obstacles]]
name = "floor"
shape = "plane"
point = [0.0, -0.3, 0.0]
normal = [0.0, 1.0, 0.0]
[[obstacles]]
name = "bar"
shape = "sphere"
center = [0.0, -0.16, -0.1]
radius = 0.03
[[stages]]
kind = "press"
obstacle = "floor"
travel = 0.12
duration = 1.0
"#;
    // Press holds the floor at y = -0.18 at the end of the run.
    let styled = run(&groom, text);
    let head = Shape::Ellipsoid {
        center: Vec3::ZERO,
        radii: coif::head::Head::default().radii,
        rotation: glam::Quat::IDENTITY,
    };
    let floor = Shape::Plane { point: Vec3::new(0.0, -0.18, 0.0), normal: Vec3::Y };
    let bar = Shape::Sphere { center: Vec3::new(0.0, -0.16, -0.1), radius: 0.03 };
    for (name, shape) in [("head", &head), ("floor", &floor), ("bar", &bar)] {
        let deepest = styled.points.iter().map(|&p| shape.distance(p).0).fold(f32::MAX, f32::min);
        eprintln!("{name}: deepest vertex at signed distance {deepest:.6} m");
        assert!(deepest > -5e-4, "{name}: a vertex is {deepest} m inside");
    }
}

#[test]
fn the_penalty_keeps_crossing_strands_apart() {
    // Strand A: a fixed bar along X at y = 0. Strand B, a soft cantilever along Z just above it,
    // sags under gravity onto A with its tip right over A's edge. The S1-18 penalty must hold the
    // tip at least half the contact distance 2r from A. Thick (2 mm) strands, so the contact is
    // resolved by the 5 mm vertex spacing (the penalty acts between vertices and edges).
    let width = 0.002;
    let a: Vec<Vec3> = (0..11).map(|i| Vec3::new(-0.025 + 0.005 * i as f32, 0.0, 0.0)).collect();
    let b: Vec<Vec3> = (0..6).map(|i| Vec3::new(0.0, 0.0021, -0.025 + 0.005 * i as f32)).collect();
    let groom = Groom::from_strands(&[a.clone(), b], width);
    let mut params = SimParams::default();
    params.material.youngs_modulus = 1e6;
    params.material.shear_modulus = 4e5;
    let mut sim = Simulation::new(&groom, params).unwrap();
    for (v, &p) in a.iter().enumerate() {
        sim.attach(v, p);
    }
    let radii = vec![0.5 * width; groom.vertex_count()];
    let mut contacts = HairContacts::new(&groom.strand_offsets, &radii, 0.005, 100.0);
    let dt = sim.params().dt;
    let mut dv = vec![Vec3::ZERO; groom.vertex_count()];
    let crossing = 11 + 5;
    let mut closest = f32::MAX;
    for step in 0..720 {
        dv.iter_mut().for_each(|v| *v = Vec3::ZERO);
        contacts.apply(sim.rods().positions(), &radii, sim.rods().kinematic(), &mut dv, dt).unwrap();
        for (a, dv) in sim.external_acceleration_mut().iter_mut().zip(&dv) {
            *a = *dv / dt;
        }
        sim.step_with(&NoHooks);
        if step > 180 {
            let p = sim.rods().positions()[crossing];
            closest = closest.min(p.distance(Vec3::new(p.x.clamp(-0.025, 0.025), 0.0, 0.0)));
        }
    }
    let y = sim.rods().positions()[crossing].y;
    let middle = sim.rods().positions()[11 + 3].y;
    eprintln!("crossing: closest approach {closest:.6} m (2r = {width}), tip y {y:.6}, middle y {middle:.6}");
    assert!(closest < width, "B never pressed onto A (closest {closest} m)");
    assert!(y > 0.0 && closest > 0.5 * width, "strands {closest} m apart, less than r");
}

/// Hair–hair contacts cost in proportion to the strands near each vertex, not to the vertices
/// of its own strand there: on a single strand of 100,000 vertices (10 µm segments, coiled on
/// itself in 1 mm turns) a build of the lists finds no pair and costs about a step of the
/// solver (0.8× measured; 15× before). Each query read the ~300 pieces of its own strand within its
/// search, and lists were built every step of a settle: 0.3 s a step.
#[test]
fn contacts_on_a_long_strand_cost_about_a_step() {
    use std::time::Instant;
    let points: Vec<Vec3> = (0..100_000)
        .map(|k| {
            let turn = k as f32 * 0.01;
            Vec3::new(0.001 * turn.cos(), -0.0002 * turn, 0.001 * turn.sin())
        })
        .collect();
    let groom = Groom::from_strands(&[points], 8e-5);
    let radii = groom.contact_radii();
    let mut sim = Simulation::new(&groom, SimParams::default()).unwrap();
    let rounds = 4;
    let start = Instant::now();
    (0..rounds).for_each(|_| sim.step());
    let stepping = start.elapsed();
    let fixed = vec![false; groom.vertex_count()];
    let mut dv = vec![Vec3::ZERO; groom.vertex_count()];
    let start = Instant::now();
    for _ in 0..rounds {
        // A new set of lists each time: every call builds them for every vertex.
        let mut contacts = HairContacts::new(&groom.strand_offsets, &radii, 0.002, 50.0);
        contacts.apply(sim.rods().positions(), &radii, &fixed, &mut dv, 1.0 / 360.0).unwrap();
    }
    let building = start.elapsed();
    eprintln!("{rounds} builds {building:?}, {rounds} steps {stepping:?}");
    assert!(dv.iter().all(|v| *v == Vec3::ZERO), "a strand pushed itself");
    // Timed beside the binary's other tests: a wide margin, still a third of what it was.
    assert!(building < stepping * 5, "{rounds} builds took {building:?}, {rounds} solver steps {stepping:?}");
}
