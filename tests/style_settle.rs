//! The `settle` stage reaches a static equilibrium: a groom released from rollers comes to rest
//! within the preset's cap, and settling on for longer afterwards moves nothing measurably.
mod common;
use common::*;

use std::path::{Path, PathBuf};

use coif::Groom;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// Runs `coif style`, returns the settle stage's report and the settled groom.
fn style(recipe: &Path, groom: &Path, output: &Path) -> (serde_json::Value, Groom) {
    let out =
        coif(&["style", path_str(recipe), "--groom", path_str(groom), "-o", path_str(output), "--json"]);
    let report = stdout_json(&out);
    let settle = report["report"]["stages"].as_array().unwrap().last().unwrap()["settle"].clone();
    let groom = coif::io::read_groom(output, &Default::default()).unwrap().groom;
    (settle, groom)
}

#[test]
fn water_set_settles_within_its_cap_to_a_shape_that_no_longer_moves() {
    // The water set's 24 cm strands come off 2.5 cm rollers with their curls far from the shape
    // their bonds now hold; the static solve must reach its residual (net force and torque
    // 2.5e-4 of gravity's) within 16 s (the preset allows 90 s for slower grooms; measured 12.3 s,
    // 4.7 s to the 1e-3 the preset asked before 60 cm hair needed more). Before
    // settling used light frames, they crept open at ~1 cm/s for the whole 8 s.
    let dir = tempfile::tempdir().unwrap();
    let groom = repo("grooms/seed_200x24cm.hair");
    let text = std::fs::read_to_string(repo("grooms/recipes/water_set.toml")).unwrap();
    let text = text.replace("max_seconds = 90.0", "max_seconds = 16.0");
    assert!(text.contains("max_seconds = 16.0") && text.contains("tolerance = 2.5e-4"));
    let recipe = dir.path().join("water_set.toml");
    std::fs::write(&recipe, &text).unwrap();
    let (settle, settled) = style(&recipe, &groom, &dir.path().join("settled.usda"));
    eprintln!("water set settle: {settle}");
    assert_eq!(settle["converged"], true, "{settle}");
    assert!(settle["force_residual"].as_f64().unwrap() <= 2.5e-4, "{settle}");
    assert!(settle["torque_residual"].as_f64().unwrap() <= 2.5e-4, "{settle}");

    // An equilibrium also stays put: simulated again for 2 s with its exported rest state and the
    // recipe's head, no strand moves 1 mm (measured: the worst 0.4 mm; 9 mm when the force
    // residual was one norm over the groom, which let two strands stop short of rest).
    let parsed = coif::style::recipe::load(&recipe).unwrap();
    // The recipe as the run placed it on the input groom: its head frame turns the preset's
    // gravity and colliders into world coordinates.
    let input = coif::io::read_groom(&groom, &Default::default()).unwrap().groom;
    let frame = coif::style::placement::head_frame(&parsed, &input, None).unwrap();
    let placed = coif::style::placement::place(&parsed, &input, None, frame).unwrap();
    let options = coif::sim::driver::SimulateOptions {
        params: coif::style::run::sim_params(&placed.recipe),
        seconds: 2.0,
        settle: None,
        sag_free: false,
        colliders: placed.shapes,
        hair_contacts: None,
    };
    let (again, summary) = coif::sim::driver::simulate(&settled, &options).unwrap();
    assert_eq!(summary.rest, "rest_darboux");
    let moved: Vec<f32> = (0..settled.strand_count())
        .map(|s| {
            settled.strand_range(s).map(|i| settled.points[i].distance(again.points[i])).fold(0.0, f32::max)
        })
        .collect();
    let still = moved.iter().filter(|&&m| m < 1e-3).count();
    eprintln!(
        "simulated again: {still} of {} strands move < 1 mm, worst {:.4} m",
        moved.len(),
        moved.iter().fold(0.0f32, |a, &b| a.max(b))
    );
    assert_eq!(still, moved.len(), "only {still} strands hold still");
}

/// A settle finds the rest shape of the chemistry the hair has when it starts: damp hair whose
/// water would wick towards the roots leaves the settle with the wetness (and so the hydrogen
/// bonds and weight) it came in with. Left to wick, the blow-dry's damp hair kept changing its
/// bonds, and its settle never reached the residual within its 10 s.
#[test]
fn a_settle_holds_the_chemistry_it_starts_with() {
    use coif::generate::{generate, GenerateParams};
    use coif::groom::{Attribute, AttributeRate};
    use coif::interact::wetness::WETNESS;
    let mut groom =
        generate(&GenerateParams { strands: 12, vertices_per_strand: 12, seed: 3, ..Default::default() })
            .unwrap();
    // Wet tips, dry roots: wicking would move water along every strand.
    let mut wetness = vec![0.0f32; groom.vertex_count()];
    for s in 0..groom.strand_count() {
        let range = groom.strand_range(s);
        let n = range.len() as f32;
        for (k, i) in range.enumerate() {
            wetness[i] = k as f32 / (n - 1.0);
        }
    }
    groom.set_attribute(Attribute::new(WETNESS, AttributeRate::Vertex, 1, wetness.clone()));
    let text = r#"
frame = "head"
[settings]
gravity = [0.0, -9.8, 0.0]
[wetness]
diffusion = 0.001
[[stages]]
kind = "settle"
max_seconds = 4.0
"#;
    let recipe = coif::style::recipe::parse(text, Path::new("settle.toml")).unwrap();
    let styled = coif::style::style(&groom, &recipe, &Default::default()).unwrap();
    let settle = styled.report.stages.last().unwrap().settle.unwrap();
    assert!(settle.converged, "{settle:?}");
    assert!(styled.groom.points.iter().all(|p| p.is_finite()));
    let after = &styled.groom.attribute(WETNESS).unwrap().floats();
    let changed = after.iter().zip(&wetness).filter(|(a, b)| a != b).count();
    assert_eq!(changed, 0, "{changed} of {} vertices changed wetness while settling", wetness.len());
}

/// A settle as the first stage hangs the groom at rest before it is styled: the stages after it
/// start from a groom that no longer moves (a `process` stage, which only waits, leaves it within
/// 1 mm), while the same groom not hung first falls during that wait.
#[test]
fn a_first_settle_hangs_the_groom_at_rest_before_the_style() {
    use coif::generate::{generate, GenerateParams};
    let groom =
        generate(&GenerateParams { strands: 12, vertices_per_strand: 12, seed: 5, ..Default::default() })
            .unwrap();
    let run = |stages: &str| {
        let text = format!(
            "frame = \"head\"\n[settings]\ngravity = [0.0, -9.8, 0.0]\n\n[[obstacles]]\nname = \"head\"\n\
             shape = \"scalp\"\n{stages}"
        );
        let recipe = coif::style::recipe::parse(&text, Path::new("hang.toml")).unwrap();
        coif::style::style(&groom, &recipe, &Default::default()).unwrap()
    };
    let hang = "\n[[stages]]\nkind = \"settle\"\nmax_seconds = 10.0\n";
    let wait = "\n[[stages]]\nkind = \"process\"\nduration = 0.5\n";
    let hung = run(hang);
    let hung_then_waited = run(&format!("{hang}{wait}"));
    let waited = run(wait);
    let first = hung_then_waited.report.stages[0].settle.expect("the first stage settles");
    assert!(first.converged, "{first:?}");
    let largest = |a: &Groom, b: &Groom| {
        a.points.iter().zip(&b.points).map(|(p, q)| p.distance(*q)).fold(0.0, f32::max)
    };
    let still = largest(&hung.groom, &hung_then_waited.groom);
    let fell = largest(&groom, &waited.groom);
    eprintln!("after the hang, a 0.5 s wait moves the hair {still:.2e} m; without it {fell:.2e} m");
    assert!(hung_then_waited.groom.points.iter().all(|p| p.is_finite()));
    assert!(still < 1e-3, "the hung groom moved {still} m while the style waited");
    assert!(fell > 10e-3, "control: the groom out of balance should fall, moved {fell} m");
}

/// The blow-dry presses longer hair (`sample_wavy.hair`, 30 cm, which reaches the floor) up by
/// 10 cm while drying it. A crown strand drawn up and out from its root (209 of the file) is
/// folded and twisted at its first joint to nearly half a turn from the joint's rest rotation,
/// where bend–twist's vector-part correction can turn the joint's axis but hardly its angle: the
/// joint chattered across the double cover and the settle never converged (force residual
/// 0.36 and 0.055 on these two selections after the preset's 10 s, the strand's first edge
/// stretched 1.1 %). Now both settle, no root edge is stretched, and the output stays put.
#[test]
fn a_blow_dry_that_folds_a_strand_at_its_root_settles() {
    use coif::style::{placement, recipe, run::sim_params};
    let path = repo("grooms/recipes/blowdry_scene2.toml");
    let parsed = recipe::load(&path).unwrap();
    let file = coif::io::read_groom(&repo("grooms/sample_wavy.hair"), &Default::default()).unwrap().groom;
    for (first, step) in [(5, 6), (1, 4)] {
        let input = thin_from(&file, first, step);
        let styled = coif::style::style(&input, &parsed, &Default::default()).unwrap();
        let settle = styled.report.stages.last().unwrap().settle.unwrap();
        eprintln!("every {step}th strand from {first}: {settle:?}");
        assert!(settle.converged, "every {step}th strand from {first}: {settle:?}");
        let (a, b) = (&input, &styled.groom);
        for s in 0..a.strand_count() {
            let r = a.strand_range(s);
            let drawn = a.points[r.start].distance(a.points[r.start + 1]);
            let now = b.points[r.start].distance(b.points[r.start + 1]);
            assert!((now / drawn - 1.0).abs() < 1e-4, "strand {s}'s first edge is {now} m, drawn {drawn} m");
        }
        let frame = placement::head_frame(&parsed, &input, None).unwrap();
        let placed = placement::place(&parsed, &input, None, frame).unwrap();
        let options = coif::sim::driver::SimulateOptions {
            params: sim_params(&placed.recipe),
            seconds: 2.0,
            settle: None,
            sag_free: false,
            colliders: shot_colliders(&parsed, placed.shapes),
            hair_contacts: None,
        };
        let (again, _) = coif::sim::driver::simulate(b, &options).unwrap();
        let worst = b.points.iter().zip(&again.points).map(|(p, q)| p.distance(*q)).fold(0.0, f32::max);
        eprintln!("simulated again for 2 s: moves {:.3} mm", worst * 1e3);
        assert!(worst < 1e-3, "every {step}th strand from {first}: the output moves {worst} m in 2 s");
    }
}
