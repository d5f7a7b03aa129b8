//! Solver accuracy (issue 15), as figures rather than pass/fail, so the solver's progress can be
//! followed and compared between branches:
//! - `invariance`: the bed-head, water-set and perm presets on thin seed grooms (every 20th strand
//!   of `seed_200x24cm.hair`, every 10th of `seed_100x48cm.hair`) styled at Δt 1/240 … 1/1440 and
//!   5, 10, 20 iterations (the direct solver also at 1 and 2: `cargo bench --bench sim` finds its
//!   single iteration as accurate per step; FILTER may name one preset). Mean and largest
//!   distance of the settled shape and of the `rest` curves to the finest run (Δt 1/1440, 20
//!   iterations), in % of the strand length, and the strand and vertex of the shape's largest
//!   (`strand:vertex` of the thinned groom); the largest collider penetration of any stage.
//! - `cantilever`: a clamped horizontal hair of 8 segments of 2 mm … 3 cm, settled under a gravity
//!   scaled to a small deflection (0.5 % of its length), at the simulation's own iterations. Tip
//!   sag over Euler–Bernoulli `q·L⁴/(8·E·I)` for the clamp at the root (`L`) and at the first
//!   frame, half an edge out (`L − l/2`).
//! - `stretch`: straight and curly strands hanging from the root, simulated 2 s at Δt 1/30 and
//!   1/360: the largest edge stretch.
//! - `hold`: the production perm through guides (a generated 6,000 × 32 head, 300 guides), its
//!   output simulated again for 2 s under the world's gravity against the recipe's colliders, as a
//!   shot starts from it, once with each solver: how far its guides and its children move
//!   (median, 99th percentile and largest, mm; issue 15 asks for under 1 mm). The guides are
//!   settled by the style's solver, the children's rest shapes are solved for the elastic
//!   equilibrium.
//! - `survey`: every preset on generated heads (20 strands; 5, 24 and 60 cm; straight and curly),
//!   its output simulated again for 2 s under the world's gravity against the recipe's colliders
//!   (as `tests/sag_free.rs`): whether the last settle converged, its residuals and simulated
//!   seconds, and the largest distance a vertex moved (issue 15 asks for under 1 mm). `SURVEY`
//!   picks the rows whose label (`preset length cm style`) has all its words.
//!
//! `cargo bench --bench accuracy [-- FILTER] [--direct]`; `cargo test --locked --bench accuracy --
//! FILTER` runs it in the (optimised) test profile without a release build. `--direct` runs every
//! figure with the direct strand solver (`StrandSolver::Direct`) instead of Gauss–Seidel.

use std::path::Path;
use std::time::Instant;

use coif::generate::{generate, GenerateParams, Style};
use coif::sim::{Cuticle, Material, NoHooks, SettleOptions, SimParams, Simulation, StrandSolver};
use coif::style::{recipe, style, StyleOptions};
use coif::Groom;
use glam::Vec3;

fn main() {
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let run = |name: &str| filter.as_deref().is_none_or(|f| name.contains(f));
    let solver = if std::env::args().any(|a| a == "--direct") {
        StrandSolver::Direct
    } else {
        StrandSolver::GaussSeidel
    };
    println!("solver: {solver:?}");
    invariance(solver, &run);
    if run("cantilever") {
        cantilever(solver);
    }
    if run("stretch") {
        stretch(solver);
    }
    if run("hold") {
        hold(solver);
    }
    if run("survey") {
        survey(solver);
    }
}

fn survey(solver: StrandSolver) {
    use coif::sim::driver::{simulate, HairContactSettings, SimulateOptions};
    use coif::style::placement;
    let pick = std::env::var("SURVEY").unwrap_or_default();
    let presets = ["bedhead_scene1", "water_set", "blowdry_scene2", "perm_scene3", "perm_full_head"];
    println!("survey: 20 generated strands; last settle and mm moved in 2 s when simulated again");
    println!(
        "  preset          length style     converged  force      torque     settle s  moved mm  wall s"
    );
    for (length, vertices) in [(0.05f32, 8usize), (0.24, 32), (0.60, 64)] {
        for (style_name, style_kind) in
            [("straight", Style::Straight), ("curly", Style::Curly { radius: 0.01, pitch: 0.03 })]
        {
            let groom = generate(&GenerateParams {
                strands: 20,
                vertices_per_strand: vertices,
                length,
                seed: 5,
                style: style_kind,
                ..GenerateParams::default()
            })
            .expect("groom");
            for preset in presets {
                let label = format!("{preset:<15} {:>4.0} cm {style_name:<8}", length * 100.0);
                if !pick.split_whitespace().all(|word| label.split_whitespace().any(|w| w == word)) {
                    continue;
                }
                let path =
                    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("grooms/recipes/{preset}.toml"));
                let text = std::fs::read_to_string(&path).expect("preset");
                let text = match solver {
                    StrandSolver::Direct => text.replace("[settings]", "[settings]\nsolver = \"direct\""),
                    StrandSolver::GaussSeidel => text,
                };
                let recipe = recipe::parse(&text, &path).expect("recipe");
                let start = Instant::now();
                let styled = style(&groom, &recipe, &StyleOptions::default()).expect("style");
                let settle = styled.report.stages.last().and_then(|s| s.settle).expect("a last settle");
                let frame = placement::head_frame(&recipe, &groom, None).expect("head frame");
                let placed = placement::place(&recipe, &groom, None, frame).expect("placed recipe");
                let pressed = |name: &str| {
                    recipe.stages.iter().any(
                        |s| matches!(s.get_ref(), recipe::Stage::Press { obstacle, .. } if obstacle == name),
                    )
                };
                let colliders = placed
                    .shapes
                    .iter()
                    .zip(&recipe.obstacles)
                    .filter(|(_, o)| !pressed(o.get_ref().name()))
                    .map(|(s, _)| s.clone())
                    .collect();
                let hair_contacts: Option<HairContactSettings> =
                    recipe.contacts.hair_hair.then(|| recipe.contacts.hair_contact_settings());
                let params = SimParams {
                    gravity: Vec3::new(0.0, -9.8, 0.0),
                    ..coif::style::run::sim_params(&placed.recipe)
                };
                let options = SimulateOptions {
                    params,
                    seconds: 2.0,
                    settle: None,
                    sag_free: false,
                    colliders,
                    hair_contacts,
                };
                let (again, _) = simulate(&styled.groom, &options).expect("simulate");
                let moved = styled
                    .groom
                    .points
                    .iter()
                    .zip(&again.points)
                    .map(|(a, b)| a.distance(*b))
                    .fold(0.0, f32::max);
                println!(
                    "  {label} {:<9}  {:.2e}   {:.2e}   {:>7.1}  {:>8.2}  {:>6.1}",
                    settle.converged,
                    settle.force_residual,
                    settle.torque_residual,
                    settle.seconds,
                    moved * 1e3,
                    start.elapsed().as_secs_f64()
                );
            }
        }
    }
}

/// Every `step`-th strand of a groom, with its widths (as `tests/common::thin`).
fn thin(groom: &Groom, step: usize) -> Groom {
    let strands: Vec<usize> = (0..groom.strand_count()).step_by(step).collect();
    coif::groups::assemble(&[(groom, &strands)]).expect("a selection of a valid groom is valid")
}

fn vec3_attribute(groom: &Groom, name: &str) -> Vec<Vec3> {
    groom
        .attribute(name)
        .expect("styled attribute")
        .floats()
        .chunks(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect()
}

/// Mean and largest distance between two point sets, in % of `length`, and the index of the
/// point at the largest.
fn difference(a: &[Vec3], b: &[Vec3], length: f32) -> (f32, f32, usize) {
    let d: Vec<f32> = a.iter().zip(b).map(|(p, q)| p.distance(*q)).collect();
    let mean = d.iter().sum::<f32>() / d.len().max(1) as f32;
    let (worst, max) =
        d.iter().copied().enumerate().fold((0, 0.0), |w, (i, x)| if x > w.1 { (i, x) } else { w });
    (100.0 * mean / length, 100.0 * max / length, worst)
}

/// The presets the invariance figures style: recipe, groom and which strands of it (every n-th).
const INVARIANCE_PRESETS: [(&str, &str, usize); 3] = [
    ("bedhead_scene1", "seed_200x24cm.hair", 20),
    ("water_set", "seed_200x24cm.hair", 20),
    ("perm_scene3", "seed_100x48cm.hair", 10),
];

fn invariance(solver: StrandSolver, run: &dyn Fn(&str) -> bool) {
    for (name, groom, step) in INVARIANCE_PRESETS {
        if run("invariance") || run(name) {
            invariance_of(solver, name, groom, step);
        }
    }
}

fn invariance_of(solver: StrandSolver, name: &str, groom_file: &str, step: usize) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let recipe_path = root.join(format!("grooms/recipes/{name}.toml"));
    let preset = std::fs::read_to_string(&recipe_path).expect("preset");
    let dt_key = preset.lines().find(|l| l.starts_with("dt = ")).expect("the preset sets dt").to_owned();
    let iterations_key = preset
        .lines()
        .find(|l| l.starts_with("iterations = "))
        .expect("the preset sets iterations")
        .to_owned();
    let groom = coif::io::read_groom(&root.join("grooms").join(groom_file), &Default::default())
        .expect("seed groom")
        .groom;
    let groom = thin(&groom, step);
    let length: f32 = groom.strand_points(0).windows(2).map(|w| w[0].distance(w[1])).sum();
    println!(
        "invariance: {name} on {} strands of {:.3} m; distances to Δt 1/1440 × 20 iterations, \
         % of the strand length",
        groom.strand_count(),
        length
    );
    let styled = |rate: u32, iterations: u32| {
        let text = preset
            .replace(&dt_key, &format!("dt = {}", 1.0 / rate as f64))
            .replace(&iterations_key, &format!("iterations = {iterations}"));
        let text = match solver {
            StrandSolver::Direct => text.replace("[settings]", "[settings]\nsolver = \"direct\""),
            StrandSolver::GaussSeidel => text,
        };
        let recipe = recipe::parse(&text, &recipe_path).expect("recipe");
        let start = Instant::now();
        let out = style(&groom, &recipe, &StyleOptions::default()).expect("style");
        (out, start.elapsed().as_secs_f64())
    };
    let (reference, _) = styled(1440, 20);
    let (ref_shape, ref_rest) = (reference.groom.points.clone(), vec3_attribute(&reference.groom, "rest"));
    println!(
        "  Δt      iter  shape mean/max %  at s:v    rest mean/max %   deepest mm  settle (converged, s)  wall s"
    );
    let counts: &[u32] = match solver {
        StrandSolver::Direct => &[1, 2, 5, 10, 20],
        StrandSolver::GaussSeidel => &[5, 10, 20],
    };
    for rate in [240u32, 360, 720, 1440] {
        for &iterations in counts {
            let fresh;
            let (out, wall) = if (rate, iterations) == (1440, 20) {
                (&reference, 0.0)
            } else {
                let (styled, wall) = styled(rate, iterations);
                fresh = styled;
                (&fresh, wall)
            };
            let shape = difference(&out.groom.points, &ref_shape, length);
            let rest = difference(&vec3_attribute(&out.groom, "rest"), &ref_rest, length);
            let deepest = out.report.stages.iter().map(|s| s.max_penetration).fold(0.0, f32::max);
            let settle =
                out.report.stages.last().and_then(|s| s.settle.as_ref().map(|r| (r.converged, r.seconds)));
            // Where the shape differs most, to look at that strand (the thinned groom's numbering).
            let (strand, vertex) = groom.strand_and_vertex(shape.2);
            println!(
                "  1/{rate:<5} {iterations:>3}   {:>6.2} / {:>6.2}  {:>8}    {:>6.2} / {:>6.2}   {:>8.2}   {settle:?}  {wall:.1}",
                shape.0,
                shape.1,
                format!("{strand}:{vertex}"),
                rest.0,
                rest.1,
                deepest * 1e3
            );
        }
    }
}

fn cantilever(solver: StrandSolver) {
    let width = 80e-6f32;
    // No cuticle gradient, so E·I is uniform.
    let material = Material { cuticle: Cuticle { share: 0.0, ..Cuticle::default() }, ..Material::default() };
    let r = 0.5 * width as f64;
    let ei = material.youngs_modulus as f64 * std::f64::consts::PI * r.powi(4) / 4.0;
    let weight = material.density as f64 * std::f64::consts::PI * r * r;
    println!("cantilever: 8 segments, gravity scaled to a 0.5 % deflection; sag / beam theory");
    println!("  segment   iter  g m/s²     sag/EB(L)  sag/EB(L−l/2)  settled (converged, s)");
    for segment in [0.002f32, 0.005, 0.01, 0.03] {
        let vertices = 9usize;
        let length = segment * (vertices - 1) as f32;
        let points: Vec<Vec3> = (0..vertices).map(|i| Vec3::new(segment * i as f32, 0.0, 0.0)).collect();
        let groom = Groom::from_strands(&[points], width);
        // δ = ρ·A·g·L⁴/(8·E·I) = 0.005·L.
        let g = 0.005 * length as f64 * 8.0 * ei / (weight * (length as f64).powi(4));
        let beam = |l: f64| weight * g * l.powi(4) / (8.0 * ei);
        for iterations in [5u32, 10, 20] {
            let params = SimParams {
                material,
                iterations,
                gravity: Vec3::new(0.0, -g as f32, 0.0),
                damping: 20.0,
                solver,
                ..SimParams::default()
            };
            let mut sim = Simulation::new(&groom, params).expect("cantilever");
            let report =
                sim.settle(&SettleOptions { tolerance: 1e-5, max_seconds: 40.0, iterations: None }, &NoHooks);
            let sag = -sim.rods().positions().last().expect("tip").y as f64;
            println!(
                "  {:>5.1} mm  {iterations:>3}  {g:>8.3}   {:>8.3}   {:>8.3}      ({}, {:.2})",
                segment * 1e3,
                sag / beam(length as f64),
                sag / beam(length as f64 - 0.5 * segment as f64),
                report.converged,
                report.seconds
            );
        }
    }
}

fn stretch(solver: StrandSolver) {
    println!("stretch: 20 strands × 32 vertices, 24 cm, hanging 2 s; largest edge strain (stretch > 0)");
    for (name, style_kind) in
        [("straight", Style::Straight), ("curly", Style::Curly { radius: 0.01, pitch: 0.03 })]
    {
        let groom = generate(&GenerateParams {
            strands: 20,
            vertices_per_strand: 32,
            length: 0.24,
            style: style_kind,
            seed: 3,
            ..GenerateParams::default()
        })
        .expect("groom");
        for rate in [30u32, 360] {
            let params = SimParams { dt: 1.0 / rate as f32, solver, ..SimParams::default() };
            let mut sim = Simulation::new(&groom, params).expect("sim");
            for _ in 0..2 * rate {
                sim.step();
            }
            let p = sim.rods().positions();
            let rest = &groom.points;
            let worst = (0..groom.strand_count())
                .flat_map(|s| {
                    let range = groom.strand_range(s);
                    (range.start..range.end - 1)
                        .map(move |v| p[v].distance(p[v + 1]) / rest[v].distance(rest[v + 1]) - 1.0)
                })
                .fold(f32::NEG_INFINITY, f32::max);
            println!("  {name:<8} Δt 1/{rate:<4} {:>9.4} %", 100.0 * worst);
        }
    }
}

fn hold(solver: StrandSolver) {
    use coif::sim::driver::{simulate, SimulateOptions};
    use coif::style::placement;
    let (strands, guides) = (6000, 300);
    let groom = generate(&GenerateParams {
        strands,
        vertices_per_strand: 32,
        length: 0.24,
        seed: 21,
        ..GenerateParams::default()
    })
    .expect("benchmark groom generates");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("grooms/recipes/perm_full_head.toml");
    let text = std::fs::read_to_string(&path).expect("preset");
    let text = match solver {
        StrandSolver::Direct => text.replace("[settings]", "[settings]\nsolver = \"direct\""),
        StrandSolver::GaussSeidel => text,
    };
    let recipe = recipe::parse(&format!("{text}\n[guides]\ncount = {guides}\n"), &path).expect("recipe");
    let start = Instant::now();
    let styled = style(&groom, &recipe, &StyleOptions::default()).expect("style").groom;
    println!(
        "hold: perm_full_head on {strands} × 32 strands through {guides} guides, styled in {:.1} s; \
         moved in 2 s when simulated again, mm",
        start.elapsed().as_secs_f64()
    );
    let frame = placement::head_frame(&recipe, &groom, None).expect("head frame");
    let placed = placement::place(&recipe, &groom, None, frame).expect("placed recipe");
    let flags = styled.guides.as_deref().expect("the output flags guides");
    let (guide_ids, child_ids): (Vec<usize>, Vec<usize>) =
        (0..styled.strand_count()).partition(|&s| flags[s]);
    println!("  simulated again with   strands    median      99 %   largest   wall s");
    for again in [StrandSolver::GaussSeidel, StrandSolver::Direct] {
        for (name, ids) in [("guides", &guide_ids), ("children", &child_ids)] {
            let part = coif::groups::assemble(&[(&styled, ids)]).expect("a selection of a valid groom");
            let options = SimulateOptions {
                params: SimParams { gravity: Vec3::new(0.0, -9.8, 0.0), ..SimParams::for_solver(again) },
                seconds: 2.0,
                settle: None,
                sag_free: false,
                colliders: placed.shapes.clone(),
                hair_contacts: None,
            };
            let start = Instant::now();
            let (after, _) = simulate(&part, &options).expect("simulate");
            let mut moved: Vec<f32> = (0..part.strand_count())
                .map(|s| {
                    part.strand_range(s).map(|i| part.points[i].distance(after.points[i])).fold(0.0, f32::max)
                })
                .collect();
            moved.sort_by(f32::total_cmp);
            let at = |q: f32| 1e3 * moved[((moved.len() - 1) as f32 * q) as usize];
            println!(
                "  {:<12} {name:<9} {:>7} {:>9.4} {:>9.3} {:>9.2} {:>8.1}",
                format!("{again:?}"),
                part.strand_count(),
                at(0.5),
                at(0.99),
                at(1.0),
                start.elapsed().as_secs_f64()
            );
        }
    }
}
