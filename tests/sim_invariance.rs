//! The look must not depend on solver settings: a strand rooted horizontally sags under gravity
//! to a shape set by its bending stiffness; that shape must be the same (max vertex distance
//! < 1 % of the strand length) with 5 vs 20 iterations and with Δt 1/360 vs 1/720. Finely cut
//! hair sags as beam theory says at the default iterations, and strands do not stretch at Δt 1/30.
use coif::sim::{NoHooks, SettleOptions, SimParams, Simulation};
use coif::Groom;
use glam::Vec3;

const LENGTH: f32 = 0.24;

fn hanging_shape(dt: f32, iterations: u32) -> Vec<Vec3> {
    let vertices = 25;
    let points: Vec<Vec3> =
        (0..vertices).map(|i| Vec3::new(LENGTH * i as f32 / (vertices - 1) as f32, 0.0, 0.0)).collect();
    let groom = Groom::from_strands(&[points], 80e-6);
    let params = SimParams { dt, iterations, damping: 4.0, ..SimParams::default() };
    let mut sim = Simulation::new(&groom, params).unwrap();
    let report =
        sim.settle(&SettleOptions { tolerance: 1e-4, max_seconds: 40.0, iterations: None }, &NoHooks);
    assert!(report.converged, "dt {dt}, {iterations} iterations: {report:?}");
    sim.rods().positions().to_vec()
}

fn max_distance(a: &[Vec3], b: &[Vec3]) -> f32 {
    a.iter().zip(b).map(|(p, q)| p.distance(*q)).fold(0.0, f32::max)
}

#[test]
fn hanging_strand_shape_does_not_depend_on_iterations_or_time_step() {
    let reference = hanging_shape(1.0 / 360.0, 5);
    // The strand really sags under its bending stiffness (neither rigid nor limp): the tip ends
    // well below the root but not straight down.
    let tip = *reference.last().unwrap();
    eprintln!("tip at {tip}");
    assert!(tip.y < -0.05 * LENGTH && tip.x > 0.05 * LENGTH, "tip at {tip}");

    let more_iterations = hanging_shape(1.0 / 360.0, 20);
    let finer_step = hanging_shape(1.0 / 720.0, 5);
    let d_iter = max_distance(&reference, &more_iterations);
    let d_dt = max_distance(&reference, &finer_step);
    eprintln!("5 vs 20 iterations: {d_iter} m; dt 1/360 vs 1/720: {d_dt} m");
    assert!(d_iter < 0.01 * LENGTH, "5 vs 20 iterations differ by {d_iter} m");
    assert!(d_dt < 0.01 * LENGTH, "dt 1/360 vs 1/720 differ by {d_dt} m");
}

/// The bending stiffness is physical: a short clamped hair sags under its own weight by the
/// beam-theory deflection `δ = q·L⁴/(8·E·I)` (`q = ρ·A·g`, small deflections). The pinned root
/// frame clamps the whole first edge, so the discrete rod's clamp lies between vertex 0 and 1:
/// its sag must fall between beam theory for lengths `L − l` and `L`. Hair this short is stiff
/// against gravity, which Gauss–Seidel resolves only with many iterations (see the module docs).
#[test]
fn short_cantilever_matches_beam_theory() {
    use coif::sim::{Cuticle, Material};
    let (length, vertices, width) = (0.02f32, 21usize, 80e-6f32);
    let points: Vec<Vec3> =
        (0..vertices).map(|i| Vec3::new(length * i as f32 / (vertices - 1) as f32, 0.0, 0.0)).collect();
    let groom = Groom::from_strands(&[points], width);
    // No cuticle gradient, so EI is uniform.
    let material = Material { cuticle: Cuticle { share: 0.0, ..Cuticle::default() }, ..Material::default() };
    let params = SimParams { material, damping: 20.0, ..SimParams::default() };
    let mut sim = Simulation::new(&groom, params).unwrap();
    let settle = SettleOptions { tolerance: 1e-5, max_seconds: 40.0, iterations: Some(1000) };
    let report = sim.settle(&settle, &NoHooks);
    assert_eq!(sim.params().iterations, 5, "settling must restore the simulation's iterations");
    assert!(report.converged, "{report:?}");
    let r = 0.5 * width as f64;
    let ei = material.youngs_modulus as f64 * std::f64::consts::PI * r.powi(4) / 4.0;
    let q = material.density as f64 * std::f64::consts::PI * r * r * 9.8;
    let beam = |l: f64| q * l.powi(4) / (8.0 * ei);
    let edge = length as f64 / (vertices - 1) as f64;
    let (low, high) = (beam(length as f64 - edge), beam(length as f64));
    let sag = -sim.rods().positions().last().unwrap().y as f64;
    assert!(high < 0.02 * length as f64, "not a small deflection");
    assert!(low <= sag && sag <= high, "tip sag {sag:.4e} m outside beam theory [{low:.4e}, {high:.4e}] m");
}

/// Finely cut hair is as stiff as its modulus at the default 5 iterations: a clamped hair of 8
/// segments of 2 mm or 5 mm sags by Euler–Bernoulli's `q·L⁴/(8·E·I)` for the discrete clamp,
/// which the pinned root frame puts half an edge out (`L − l/2`: the first bend–twist pair sits
/// at vertex 1 and stands for the half edges on either side), and the sag does not depend on the
/// iteration count. Gauss–Seidel alone left these strands 7× (2 mm) too soft at 5 iterations.
#[test]
fn finely_cut_cantilever_matches_beam_theory_at_the_default_iterations() {
    use coif::sim::{Cuticle, Material};
    let width = 80e-6f32;
    let material = Material { cuticle: Cuticle { share: 0.0, ..Cuticle::default() }, ..Material::default() };
    let r = 0.5 * width as f64;
    let ei = material.youngs_modulus as f64 * std::f64::consts::PI * r.powi(4) / 4.0;
    let weight = material.density as f64 * std::f64::consts::PI * r * r;
    for segment in [0.002f32, 0.005] {
        let length = 8.0 * segment;
        let points: Vec<Vec3> = (0..9).map(|i| Vec3::new(segment * i as f32, 0.0, 0.0)).collect();
        let groom = Groom::from_strands(&[points], width);
        // Gravity scaled to a small deflection: δ = ρ·A·g·L⁴/(8·E·I) = 0.005·L.
        let g = 0.005 * length as f64 * 8.0 * ei / (weight * (length as f64).powi(4));
        let clamp = length as f64 - 0.5 * segment as f64;
        let beam = weight * g * clamp.powi(4) / (8.0 * ei);
        let sag = |iterations: u32| {
            let gravity = Vec3::new(0.0, -g as f32, 0.0);
            let params = SimParams { material, iterations, gravity, damping: 20.0, ..SimParams::default() };
            let mut sim = Simulation::new(&groom, params).unwrap();
            let settle = SettleOptions { tolerance: 1e-5, max_seconds: 40.0, iterations: None };
            let report = sim.settle(&settle, &NoHooks);
            assert!(report.converged, "{segment} m segments, {iterations} iterations: {report:?}");
            -sim.rods().positions().last().unwrap().y as f64
        };
        let (five, twenty) = (sag(5), sag(20));
        eprintln!(
            "{segment} m segments: sag / beam theory {:.4} (5 iterations), {:.4} (20)",
            five / beam,
            twenty / beam
        );
        assert!((five / beam - 1.0).abs() < 0.05, "{segment} m: sag {five:.4e} m against {beam:.4e} m");
        assert!(
            (five / twenty - 1.0).abs() < 0.03,
            "{segment} m: 5 iterations {five:.4e} m, 20 {twenty:.4e} m"
        );
    }
}

/// Stretch is solved along the whole strand every iteration: strands hanging from the root stay
/// within 1 % of their length even at Δt 1/30 (Gauss–Seidel alone let them stretch to 3×).
#[test]
fn hanging_strands_do_not_stretch_at_a_large_time_step() {
    use coif::generate::{generate, GenerateParams, Style};
    for style in [Style::Straight, Style::Curly { radius: 0.01, pitch: 0.03 }] {
        let groom = generate(&GenerateParams {
            strands: 20,
            vertices_per_strand: 32,
            length: 0.24,
            style,
            seed: 3,
            ..GenerateParams::default()
        })
        .unwrap();
        let mut sim = Simulation::new(&groom, SimParams { dt: 1.0 / 30.0, ..SimParams::default() }).unwrap();
        for _ in 0..60 {
            sim.step();
        }
        let p = sim.rods().positions();
        let strain = (0..groom.strand_count())
            .flat_map(|s| {
                let range = groom.strand_range(s);
                let rest = &groom.points;
                (range.start..range.end - 1)
                    .map(move |v| (p[v].distance(p[v + 1]) / rest[v].distance(rest[v + 1]) - 1.0).abs())
            })
            .fold(0.0f32, f32::max);
        let moved = groom.points.iter().zip(p).map(|(a, b)| a.distance(*b)).fold(0.0f32, f32::max);
        eprintln!("{style:?}: largest edge strain {strain:.2e} at Δt 1/30, moved {moved:.3} m");
        assert!(moved > 0.01, "{style:?}: the strands should fall and swing ({moved} m)");
        assert!(strain < 0.01, "{style:?}: an edge is strained by {strain} at Δt 1/30");
    }
}

/// A preset styled on every `step`-th strand of a seed groom at Δt `1/rate` with the solver
/// `settings` adds to the preset's `[settings]`: the settled points and the `rest` curves, and
/// the strand length (all strands of the seed grooms have one length).
fn styled_preset(
    preset: &str,
    groom: &str,
    step: usize,
    rate: u32,
    settings: &str,
) -> (Vec<Vec3>, Vec<Vec3>, f32) {
    styled_preset_stages(preset, groom, step, rate, settings, usize::MAX)
}

/// [`styled_preset`] with only the preset's first `stages` stages; the points are where the last
/// of them left the hair (settled when it is a settle).
fn styled_preset_stages(
    preset: &str,
    groom: &str,
    step: usize,
    rate: u32,
    settings: &str,
    stages: usize,
) -> (Vec<Vec3>, Vec<Vec3>, f32) {
    use coif::style::{recipe, style, StyleOptions};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join(format!("grooms/recipes/{preset}.toml"));
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.contains("dt = 0.0027777778") && text.contains("[settings]"),
        "{preset}: the variants edit these"
    );
    let seed = coif::io::read_groom(&root.join("grooms").join(groom), &Default::default()).unwrap().groom;
    let strands: Vec<usize> = (0..seed.strand_count()).step_by(step).collect();
    let groom = coif::groups::assemble(&[(&seed, &strands)]).unwrap();
    let length: f32 = groom.strand_points(0).windows(2).map(|w| w[0].distance(w[1])).sum();
    let text = text
        .replace("dt = 0.0027777778", &format!("dt = {}", 1.0 / rate as f64))
        .replace("[settings]", &format!("[settings]\n{settings}"));
    let mut recipe = recipe::parse(&text, &path).unwrap();
    recipe.stages.truncate(stages);
    let out = style(&groom, &recipe, &StyleOptions::default()).unwrap();
    if let Some(settle) = out.report.stages.last().unwrap().settle {
        assert!(settle.converged, "{preset} at Δt 1/{rate}: {settle:?}");
    }
    let rest: Vec<Vec3> = out
        .groom
        .attribute("rest")
        .unwrap()
        .floats()
        .chunks(3)
        .map(|c| Vec3::new(c[0], c[1], c[2]))
        .collect();
    assert!(out.groom.points.iter().chain(&rest).all(|p| p.is_finite()), "{preset} at Δt 1/{rate}");
    (out.groom.points, rest, length)
}

/// The `[settings]` line that picks the Gauss–Seidel solver: its tests name it rather than take
/// the default solver, so they check what their figures were measured with.
const GAUSS_SEIDEL: &str = "solver = \"gauss-seidel\"";

/// Mean and largest distance between matching points, in % of `length`.
fn difference_percent(a: &[Vec3], b: &[Vec3], length: f32) -> (f32, f32) {
    let d: Vec<f32> = a.iter().zip(b).map(|(p, q)| 100.0 * p.distance(*q) / length).collect();
    (d.iter().sum::<f32>() / d.len() as f32, d.iter().copied().fold(0.0, f32::max))
}

/// Styles `preset` at Δt 1/1440 and at each of `rates`, and asserts that the settled shape and
/// the rest curves lie within 1 % of the strand length on average and 3 % at worst of the 1/1440
/// run's (issue 15).
fn assert_time_step_invariant(preset: &str, groom: &str, step: usize, rates: &[u32], settings: &str) {
    assert_invariant_at(preset, groom, step, rates, settings, true);
}

/// [`assert_time_step_invariant`], with the settled shape's check only when `shape_too`.
fn assert_invariant_at(
    preset: &str,
    groom: &str,
    step: usize,
    rates: &[u32],
    settings: &str,
    shape_too: bool,
) {
    let (reference_shape, reference_rest, length) = styled_preset(preset, groom, step, 1440, settings);
    for &rate in rates {
        let (shape, rest, _) = styled_preset(preset, groom, step, rate, settings);
        let shape = difference_percent(&shape, &reference_shape, length);
        let rest = difference_percent(&rest, &reference_rest, length);
        eprintln!(
            "{preset} ({settings}), Δt 1/{rate} vs 1/1440: shape {shape:.2?} %, rest curves {rest:.2?} % (mean, worst)"
        );
        assert!(
            !shape_too || shape.0 < 1.0 && shape.1 < 3.0,
            "{preset}, Δt 1/{rate}: settled shape differs by {shape:?} %"
        );
        assert!(rest.0 < 1.0 && rest.1 < 3.0, "{preset}, Δt 1/{rate}: rest curves differ by {rest:?} %");
    }
}

/// A style does not depend on Δt: the bed-head preset (wet, pressed on a pillow, dried,
/// released, settled) with the direct strand solve settles every 20th strand of the seed groom
/// to the same shape at Δt 1/240 and 1/720 as at 1/1440 — within 1 % of the strand length on
/// average and 3 % at worst — and bakes the same rest curves.
#[test]
fn bed_head_settles_to_the_same_shape_at_any_time_step_with_the_direct_solver() {
    assert_time_step_invariant(
        "bedhead_scene1",
        "seed_200x24cm.hair",
        20,
        &[240, 720],
        "solver = \"direct\"",
    );
}

/// The same with the Gauss–Seidel solver, for the bed-head and the water set, whose
/// rest curves are baked while wet hair moves (pressed, wound, blown): the frames' drag on
/// bending is a rate per second ([`coif::sim::FRAME_DRAG_DT`]). With a frame inertia fixed
/// per step, that drag grew as Δt shrank and the rest curves at Δt 1/240 lay 5.6 % (bed-head) and
/// 2.9 % (water set) of the strand length from the 1/1440 run's, 14 % and 5 % at worst
/// (`cargo bench --bench accuracy -- invariance` prints the table, iterations included).
#[test]
fn bed_head_and_water_set_bake_the_same_rest_curves_at_any_time_step() {
    for preset in ["bedhead_scene1", "water_set"] {
        assert_time_step_invariant(preset, "seed_200x24cm.hair", 20, &[240, 360, 720], GAUSS_SEIDEL);
    }
}

/// The water set bakes the same rest curves at any Δt with the direct solver too (issue 15). Its
/// wet hair, relaxed, hangs into the rods: when they appear, 5 of the 10 strands lie 1.1–2.1 cm
/// deep in one (the Gauss–Seidel solve's wet hair, stiffer, stays 3–15 cm clear). Pushed out in
/// one step, those vertices shot out at depth/Δt and the strands landed elsewhere at each Δt: rest
/// curves 0.38 / 7.07 % (mean, worst) of the strand length from the 1/1440 run's at Δt 1/240,
/// 0.10 / 0.84 % at 1/360. Now a vertex inside a rod as it appears is moved out at
/// `ROD_PLACING_SPEED`, away from the head (straight out from the axis, the side was a coin flip
/// for one strand 1 mm from it: 0.39 / 7.04 %): 0.27 / 0.90 % and 0.03 / 0.20 % (let pass through
/// the rod and left inside it: 0.24 / 0.86 % and 0.03 / 0.20 %). Not asserted: the settled
/// shape's worst vertex at 1/240 (3.45 % when let pass through: seed strand 80 lay on the scalp
/// 7 mm further sideways; its rest curve was within 0.9 %).
#[test]
fn water_set_with_the_direct_solver_bakes_the_same_rest_curves_at_any_time_step() {
    assert_invariant_at("water_set", "seed_200x24cm.hair", 20, &[240, 360], "solver = \"direct\"", false);
}

/// The perm bakes the same rest curves at any Δt with Gauss–Seidel: `perm_scene3` on every 20th
/// strand of the 48 cm seed groom, up to its release (the final settle, under gravity, changes no
/// rest curve and is most of the cost), at Δt 1/240, 1/360 and 1/720 against 1/1440. Two things
/// made them differ: the span between the pinned root and the winding was left to Gauss–Seidel,
/// which stretched it under its load by an amount that depended on Δt (the direct stretch–shear
/// solve now covers spans held at both ends, `sim::solver`), and where a winding started and which
/// way it turned was read off the pre-wound shape, a coin flip for a strand hanging through a rod
/// near its axis (now from the root and the rod alone). Before: 1.35 % of the strand length on
/// average and 4.3 % at worst at Δt 1/240 (every 10th strand,
/// `cargo bench --bench accuracy -- invariance`).
#[test]
fn perm_bakes_the_same_rest_curves_at_any_time_step() {
    assert_perm_bakes_the_same_rest_curves(GAUSS_SEIDEL);
}

/// The same with the direct strand solve. It solves the free tail after the winding; the span
/// between the root and the winding was left to Gauss–Seidel sweeps alone, and stretched under its
/// load by an amount that depended on Δt, as it once did with Gauss–Seidel: strand 1's span (72
/// edges) lay 41 mm from the 1/1440 run's at the wrap's end at Δt 1/240, and the rest curves
/// 1.38 / 3.53 % (mean, worst) at 1/240 and 1.46 / 9.26 % at 1/360. Now the span's stretch–shear
/// is solved directly as Gauss–Seidel's is (`sim::solver`): 0.28 / 1.41 % and 0.29 / 1.37 %.
#[test]
fn perm_bakes_the_same_rest_curves_at_any_time_step_with_the_direct_solver() {
    assert_perm_bakes_the_same_rest_curves("solver = \"direct\"");
}

/// `perm_scene3` up to its release with the solver `settings`: rest curves within 1 % of the
/// strand length on average and 3 % at worst of the 1/1440 run's at Δt 1/240, 1/360 and 1/720.
fn assert_perm_bakes_the_same_rest_curves(settings: &str) {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("grooms/recipes/perm_scene3.toml");
    let recipe = coif::style::recipe::parse(&std::fs::read_to_string(&path).unwrap(), &path).unwrap();
    let release = 1 + recipe
        .stages
        .iter()
        .position(|s| matches!(s.get_ref(), coif::style::recipe::Stage::Release { .. }))
        .unwrap();
    let (_, reference, length) =
        styled_preset_stages("perm_scene3", "seed_100x48cm.hair", 20, 1440, settings, release);
    for rate in [240, 360, 720] {
        let (_, rest, _) =
            styled_preset_stages("perm_scene3", "seed_100x48cm.hair", 20, rate, settings, release);
        let (mean, worst) = difference_percent(&rest, &reference, length);
        eprintln!(
            "perm_scene3 ({settings}), Δt 1/{rate} vs 1/1440: rest curves {mean:.2} / {worst:.2} % (mean, worst)"
        );
        assert!(
            mean < 1.0 && worst < 3.0,
            "perm_scene3 ({settings}), Δt 1/{rate}: rest curves differ by {mean} / {worst} %"
        );
    }
}

/// The root clamp holds at any iteration count: the pinned root frame fixes the first edge, so
/// vertex 1 stays one rest length from the root along it, whatever load the strand puts on it.
/// With Gauss–Seidel alone an iteration ending on a root→tip sweep left vertex 1 where the
/// second edge's projection pulled it (issue 15 measured 148 µm on a 2.5 mm first edge at 5
/// iterations); the direct stretch–shear solve of every iteration holds it. Cases: the issue's
/// horizontal cantilever of 2.5 mm edges, and a strand folded back at vertex 1 as a pressed groom
/// leaves them.
#[test]
fn root_clamp_holds_at_any_iteration_count() {
    let cantilever: Vec<Vec3> = (0..33).map(|i| Vec3::new(0.0025 * i as f32, 0.0, 0.0)).collect();
    let segment = 0.0125f32;
    let mut folded = vec![Vec3::ZERO, Vec3::new(-0.6, 0.8, 0.0) * segment];
    for i in 1..16 {
        folded.push(folded[1] + Vec3::new(0.5, -0.85, 0.2).normalize() * segment * i as f32);
    }
    for points in [cantilever, folded] {
        let first = points[0].distance(points[1]);
        let groom = Groom::from_strands(&[points], 80e-6);
        for iterations in [3, 4, 5, 7] {
            let params = SimParams { iterations, damping: 4.0, ..SimParams::default() };
            let mut sim = Simulation::new(&groom, params).unwrap();
            let mut worst = 0.0f32;
            for _ in 0..360 {
                sim.step_with(&NoHooks);
                let p = sim.rods().positions();
                let held = p[0] + sim.root_frame(0) * Vec3::Z * first;
                worst = worst.max(p[1].distance(held));
            }
            eprintln!(
                "first edge {first} m, {iterations} iterations: vertex 1 off its clamp by {worst:.2e} m"
            );
            assert!(worst < 1e-6, "{iterations} iterations: vertex 1 {worst:.2e} m off its clamp");
        }
    }
}
