//! `coif simulate` through the binary: runs, reports, writes; bad options exit 2 and write nothing.
mod common;
use common::{coif, dir_listing, path_str, stderr, stdout_json};

#[test]
fn simulate_writes_the_groom_and_reports_steps() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.hair");
    let output = dir.path().join("out.hair");
    let generated = coif(&["generate", "-o", path_str(&input), "--strands", "20", "--vertices", "8"]);
    assert!(generated.status.success(), "{}", stderr(&generated));
    let json = stdout_json(&coif(&[
        "simulate",
        path_str(&input),
        path_str(&output),
        "--seconds",
        "0.05",
        "--dt",
        "1/360",
        "--json",
    ]));
    assert_eq!(json["simulation"]["steps"], 18);
    assert_eq!(json["groom"]["strands"], 20);
    // The groom fell under gravity: it is no longer the input.
    assert_ne!(std::fs::read(&input).unwrap(), std::fs::read(&output).unwrap());
}

#[test]
fn bad_simulate_options_exit_2_without_output() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.hair");
    assert!(coif(&["generate", "-o", path_str(&input), "--strands", "5"]).status.success());
    let output = dir.path().join("out.hair");
    // Each refusal names what it refuses: the comma form of --influences parses (as the README
    // writes it), so all-zero influences are refused for being zero, not for their syntax.
    for (bad, named) in [
        (vec!["--dt", "0"], "time step"),
        (vec!["--iterations", "0"], "--iterations"),
        (vec!["--influences", "0,0,0,0"], "influence"),
        (vec!["--influences", "0", "0", "0", "0"], "influence"),
        (vec!["--seconds=-1"], "--seconds = -1"),
        (vec!["--youngs-modulus", "0"], "--youngs-modulus = 0"),
        (vec!["--settle", "--settle-tolerance", "nan"], "--settle-tolerance = NaN"),
        (vec!["--settle", "--settle-iterations", "0"], "--settle-iterations = 0"),
    ] {
        let mut args = vec!["simulate", path_str(&input), path_str(&output)];
        args.extend(bad.iter());
        let result = coif(&args);
        assert_eq!(result.status.code(), Some(2), "{bad:?}: {}", stderr(&result));
        assert!(stderr(&result).contains(named), "{bad:?}: {}", stderr(&result));
    }
    assert_eq!(dir_listing(dir.path()), vec!["in.hair".to_string()]);
}

/// A mistyped output directory is refused before the input is even read: found only at the
/// write, it cost the whole run (`simulate` printed its steps, then failed).
#[test]
fn an_output_in_a_missing_directory_exits_2_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.hair");
    assert!(coif(&["generate", "-o", path_str(&input), "--strands", "5"]).status.success());
    let recipe = concat!(env!("CARGO_MANIFEST_DIR"), "/grooms/recipes/perm_full_head.toml");
    for (parent, problem) in
        [(dir.path().join("missing"), "does not exist"), (input.clone(), "is not a directory")]
    {
        let out = |name: &str| parent.join(name).to_str().unwrap().to_owned();
        let (usda, abc, png, hair) = (out("x.usda"), out("x.abc"), out("x.png"), out("x.hair"));
        for args in [
            vec!["simulate", path_str(&input), &usda],
            vec!["style", recipe, "--groom", path_str(&input), "-o", &usda],
            vec!["convert", path_str(&input), &abc],
            vec!["render", path_str(&input), "-o", &png, "--res", "8x8", "--spp", "1"],
            vec!["generate", "-o", &hair, "--strands", "5"],
        ] {
            let result = coif(&args);
            let message = stderr(&result);
            assert_eq!(result.status.code(), Some(2), "{args:?}: {message}");
            let named = format!("the directory {} {problem}", parent.display());
            assert!(message.contains(&named), "{args:?}: {message}");
            assert!(!message.contains("simulated") && !message.contains("wrote"), "{args:?}: {message}");
        }
    }
    assert_eq!(dir_listing(dir.path()), vec!["in.hair".to_string()]);
}

/// A directory that exists but where no file can be made (procfs) is the environment's refusal:
/// exit 1 naming the output, nothing written.
#[test]
fn an_output_where_the_file_system_makes_no_files_exits_1() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.hair");
    assert!(coif(&["generate", "-o", path_str(&input), "--strands", "5"]).status.success());
    for output in ["/proc/self/x.usda", "/proc/self/x.abc", "/proc/self/x.hair"] {
        let result = coif(&["convert", path_str(&input), output]);
        let message = stderr(&result);
        assert_eq!(result.status.code(), Some(1), "{output}: {message}");
        assert!(
            message.contains(output) && message.contains("cannot create files in /proc/self"),
            "{message}"
        );
    }
    let result = coif(&["render", path_str(&input), "-o", "/proc/self/x.png", "--res", "8x8", "--spp", "1"]);
    assert_eq!(result.status.code(), Some(1), "{}", stderr(&result));
    assert_eq!(dir_listing(dir.path()), vec!["in.hair".to_string()]);
}

#[test]
fn the_readme_influences_comma_form_parses() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.hair");
    assert!(coif(&["generate", "-o", path_str(&input), "--strands", "3"]).status.success());
    let output = dir.path().join("out.hair");
    let args = ["--influences", "0.33,0.30,0.2,0.17", "--seconds", "0.01"];
    let result = coif(&[&["simulate", path_str(&input), path_str(&output)][..], &args[..]].concat());
    assert!(result.status.success(), "{}", stderr(&result));
}

/// A styled groom's `material_frame` that is not a unit quaternion exits 2 naming the file, the
/// attribute and the vertex, and writes nothing; the file as written re-simulates.
#[test]
fn a_broken_material_frame_exits_2_naming_the_vertex() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.hair");
    assert!(coif(&["generate", "-o", path_str(&input), "--strands", "4", "--vertices", "6"])
        .status
        .success());
    let settled = dir.path().join("settled.usda");
    let run = coif(&["simulate", path_str(&input), path_str(&settled), "--seconds", "0.05"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let text = std::fs::read_to_string(&settled).unwrap();
    let at = text.find("primvars:material_frame = [").expect("the frames are written");
    let open = at + text[at..].find('(').unwrap();
    let close = open + text[open..].find(')').unwrap();
    let broken = dir.path().join("broken.usda");
    std::fs::write(&broken, format!("{}(2, 0, 0, 0{}", &text[..open], &text[close..])).unwrap();
    let again = dir.path().join("again.usda");
    let result = coif(&["simulate", path_str(&broken), path_str(&again), "--seconds", "0.05"]);
    assert_eq!(result.status.code(), Some(2), "{}", stderr(&result));
    let message = stderr(&result);
    assert!(message.contains("broken.usda: attribute 'material_frame': vertex 0"), "{message}");
    assert!(!again.exists());
    let result = coif(&["simulate", path_str(&settled), path_str(&again), "--seconds", "0.05"]);
    assert!(result.status.success(), "{}", stderr(&result));
}

/// `--hair-contacts`: strands that overlap push each other apart, as a style with hair–hair
/// contacts simulated them; without it they pass through each other. Two equal hanging strands
/// 80 µm wide, 40 µm apart (half a width inside each other), simulated without gravity.
#[test]
fn hair_contacts_push_overlapping_strands_apart() {
    use glam::Vec3;
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("overlap.usda");
    let strand = |x: f32| (0..12).map(|i| Vec3::new(x, -0.01 * i as f32, 0.0)).collect::<Vec<_>>();
    let groom = coif::Groom::from_strands(&[strand(0.0), strand(40e-6)], 80e-6);
    coif::io::write_groom(&input, &groom).unwrap();
    let gap = |extra: &[&str]| {
        let output = dir.path().join("out.usda");
        let args = [
            &["simulate", path_str(&input), path_str(&output), "--seconds", "0.2", "--gravity", "0"][..],
            extra,
        ]
        .concat();
        let run = coif(&args);
        assert!(run.status.success(), "{}", stderr(&run));
        let out = coif::io::read_groom(&output, &Default::default()).unwrap().groom;
        // The tips: the clamped root edges stay where they are.
        out.strand_points(0).last().unwrap().distance(*out.strand_points(1).last().unwrap())
    };
    let (apart, through) = (gap(&["--hair-contacts"]), gap(&[]));
    eprintln!("tips: {:.1} µm with contacts, {:.1} µm without", apart * 1e6, through * 1e6);
    assert!((through - 40e-6).abs() < 1e-6, "without contacts nothing moves them: {through} m");
    assert!(apart > 80e-6, "with contacts the tips are still {apart} m apart");
}

/// `--max-memory` holds for hair–hair contact lists, which grow with how densely strands lie,
/// not with how many vertices there are: 2,000 two-vertex strands piled at one point list 4·10⁶
/// vertex–edge pairs (48 MB while building). Under a 20 MB limit the run exits 2 saying so, with the
/// pairs, the limit and the place, before the lists outgrow it and with nothing written (it ran
/// and wrote the output, as 10,000 such strands took 807 MB under a 300 MB limit); with the
/// default limit the same run succeeds, and so does a groom whose strands lie apart.
#[test]
fn strands_piled_at_one_point_are_refused_before_their_contact_lists_outgrow_the_memory_limit() {
    use glam::Vec3;
    let dir = tempfile::tempdir().unwrap();
    let pile = |spread: f32| {
        let strands: Vec<Vec<Vec3>> = (0..2000)
            .map(|s| (0..2).map(|k| Vec3::new(spread * s as f32, -0.01 * k as f32, 0.0)).collect())
            .collect();
        coif::Groom::from_strands(&strands, 80e-6)
    };
    let (piled, apart) = (dir.path().join("piled.usda"), dir.path().join("apart.usda"));
    coif::io::write_groom(&piled, &pile(0.0)).unwrap();
    coif::io::write_groom(&apart, &pile(0.01)).unwrap();
    let output = dir.path().join("out.usda");
    let run = |input: &std::path::Path, limit: &[&str]| {
        let args = [
            &["simulate", path_str(input), path_str(&output), "--seconds", "0.01", "--hair-contacts"][..],
            limit,
        ]
        .concat();
        coif(&args)
    };
    let refused = run(&piled, &["--max-memory", "20M"]);
    let message = stderr(&refused);
    assert_eq!(refused.status.code(), Some(2), "{message}");
    for name in
        ["hair–hair contacts", "pairs", "--max-memory", "20.972 MB", "densest place is at (0, -0.01, 0) m"]
    {
        assert!(message.contains(name), "no '{name}' in: {message}");
    }
    assert_eq!(dir_listing(dir.path()), vec!["apart.usda".to_string(), "piled.usda".to_string()]);
    let spread = run(&apart, &["--max-memory", "20M"]);
    assert!(spread.status.success(), "{}", stderr(&spread));
    let default = run(&piled, &[]);
    assert!(default.status.success(), "{}", stderr(&default));
}

/// The work budget counts solver iterations: a run the budget takes at the default 5 iterations
/// is refused at 1,000 (200 times the work), with its figures and before any output.
#[test]
fn the_work_budget_counts_iterations() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.hair");
    let generated = coif(&[
        "generate",
        "-o",
        path_str(&input),
        "--strands",
        "100",
        "--vertices",
        "100",
        "--length",
        "0.2",
    ]);
    assert!(generated.status.success(), "{}", stderr(&generated));
    let output = dir.path().join("out.hair");
    // 7.2e6 steps of 1e4 vertices: 7.2e10 vertex-steps at 5 iterations, 1.44e13 at 1,000.
    let run = coif(&[
        "simulate",
        path_str(&input),
        path_str(&output),
        "--seconds",
        "1e4",
        "--dt",
        "1/720",
        "--iterations",
        "1000",
    ]);
    let message = stderr(&run);
    assert_eq!(run.status.code(), Some(2), "{message}");
    assert!(message.contains("1000 iterations") && message.contains("1.440e13"), "{message}");
    assert_eq!(dir_listing(dir.path()), vec!["in.hair".to_string()]);
}

/// Per strand, the farthest any vertex moved from `before` to `after`, as pxr reads both files.
fn strand_drifts(before: &std::path::Path, after: &std::path::Path) -> Vec<f32> {
    use common::usd::{f32s, pxr_dump};
    let (a, b) = (pxr_dump(before, None), pxr_dump(after, None));
    let (a, b) = (&a["curves"][0], &b["curves"][0]);
    let (pa, pb) = (f32s(&a["points"]), f32s(&b["points"]));
    let mut vertex = 0;
    let mut drifts = Vec::new();
    for count in a["counts"].as_array().unwrap() {
        let n = count.as_u64().unwrap() as usize;
        let moved = (vertex..vertex + n).map(|v| {
            let d: Vec<f32> = (0..3).map(|k| pa[3 * v + k] - pb[3 * v + k]).collect();
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        });
        drifts.push(moved.fold(0.0, f32::max));
        vertex += n;
    }
    drifts
}

/// `--sag-free` on `coif generate`'s default groom: its crown strands rise above their root
/// before hanging, a balance their sag-free rest shape holds only unstably, and they fell up to
/// 20 cm in 2 s with nothing said. The run now warns with the number of strands that moved more
/// than 1 cm, the number pxr's reading of the files gives; a groom of 8 cm strands, which hangs,
/// holds (under a millimetre) without a warning.
#[test]
fn a_sag_free_groom_that_falls_is_warned_about_and_one_that_holds_is_not() {
    let dir = tempfile::tempdir().unwrap();
    for (length, falls) in [(None, true), (Some("0.08"), false)] {
        let input = dir.path().join(format!("in{}.usda", length.unwrap_or("")));
        let output = dir.path().join(format!("out{}.usda", length.unwrap_or("")));
        let mut generate = vec!["generate", "-o", path_str(&input)];
        generate.extend(length.map(|l| ["--length", l]).iter().flatten());
        let generated = coif(&generate);
        assert!(generated.status.success(), "{}", stderr(&generated));
        let run = ["simulate", path_str(&input), path_str(&output), "--sag-free", "--seconds", "2", "--json"];
        let json = stdout_json(&coif(&run));
        let drifts = strand_drifts(&input, &output);
        let moved = drifts.iter().filter(|&&d| d > 0.01).count();
        let farthest = drifts.iter().copied().fold(0.0, f32::max);
        let warnings: Vec<&str> =
            json["warnings"].as_array().unwrap().iter().map(|w| w.as_str().unwrap()).collect();
        assert_eq!(json["simulation"]["warnings"], json["warnings"], "one list, in both places");
        if falls {
            assert!(moved >= 10 && farthest > 0.1, "{moved} strands moved > 1 cm, farthest {farthest} m");
            let said = format!("did not hold {moved} of {} strands in 2 s", drifts.len());
            assert!(
                warnings.iter().any(|w| w.contains(&said) && w.contains("rising above their root")),
                "{warnings:?}"
            );
        } else {
            assert!(farthest < 1e-3, "the hanging groom moved {farthest} m");
            assert!(warnings.is_empty(), "{warnings:?}");
        }
    }
}
