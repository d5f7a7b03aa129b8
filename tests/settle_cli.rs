//! The static solve through the binary: `simulate --settle` reports its residual and whether it
//! converged, `--require-converged` turns a settle that did not converge into exit 1 (the output
//! is still written), and settle options or recipe settle keys outside their physical ranges exit
//! 2 naming the key and the range, writing nothing.
mod common;
use common::{coif, dir_listing, path_str, stderr, stdout_json};

fn groom(dir: &std::path::Path) -> std::path::PathBuf {
    let input = dir.join("in.hair");
    let generated = coif(&["generate", "-o", path_str(&input), "--strands", "12", "--vertices", "12"]);
    assert!(generated.status.success(), "{}", stderr(&generated));
    input
}

#[test]
fn simulate_settle_reports_its_residual_and_can_require_convergence() {
    let dir = tempfile::tempdir().unwrap();
    let input = groom(dir.path());
    let output = dir.path().join("out.hair");
    let args = |extra: &[&'static str]| {
        let mut a =
            vec!["simulate", path_str(&input), path_str(&output), "--seconds", "0", "--settle", "--json"];
        a.extend_from_slice(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let run = |extra: &[&'static str]| {
        let owned = args(extra);
        coif(&owned.iter().map(String::as_str).collect::<Vec<_>>())
    };

    let done = run(&["--require-converged"]);
    assert_eq!(done.status.code(), Some(0), "{}", stderr(&done));
    let settle = stdout_json(&done)["simulation"]["settle"].clone();
    assert_eq!(settle["converged"], true, "{settle}");
    let tolerance = settle["tolerance"].as_f64().unwrap();
    assert!(settle["force_residual"].as_f64().unwrap() <= tolerance, "{settle}");
    assert!(settle["torque_residual"].as_f64().unwrap() <= tolerance, "{settle}");

    // 20 ms cannot bring a released groom to rest: reported, exit 0, unless required.
    std::fs::remove_file(&output).unwrap();
    let short = run(&["--settle-seconds", "0.02"]);
    assert_eq!(short.status.code(), Some(0), "{}", stderr(&short));
    let settle = stdout_json(&short)["simulation"]["settle"].clone();
    assert_eq!(settle["converged"], false, "{settle}");
    assert!(settle["force_residual"].as_f64().unwrap() > tolerance, "{settle}");
    assert!(stderr(&short).contains("did not reach its tolerance"), "{}", stderr(&short));

    // Shorter than one probe (~11 ms): still residuals to report, numbers in the JSON (they were
    // infinite, `null`).
    std::fs::remove_file(&output).unwrap();
    let shortest = run(&["--settle-seconds", "0.005"]);
    assert_eq!(shortest.status.code(), Some(0), "{}", stderr(&shortest));
    let settle = stdout_json(&shortest)["simulation"]["settle"].clone();
    for residual in ["force_residual", "torque_residual"] {
        assert!(settle[residual].as_f64().is_some_and(f64::is_finite), "{residual}: {settle}");
    }

    std::fs::remove_file(&output).unwrap();
    let required = run(&["--settle-seconds", "0.02", "--require-converged"]);
    assert_eq!(required.status.code(), Some(1), "{}", stderr(&required));
    assert!(stderr(&required).contains("force residual"), "{}", stderr(&required));
    assert!(output.exists(), "the unconverged result is still written");
}

#[test]
fn settle_options_out_of_range_exit_2_naming_key_and_range() {
    let dir = tempfile::tempdir().unwrap();
    let input = groom(dir.path());
    let output = dir.path().join("out.hair");
    for (bad, key, range) in [
        (["--settle-tolerance", "0"], "--settle-tolerance", "[1e-5, 0.5]"),
        (["--settle-tolerance", "2"], "--settle-tolerance", "[1e-5, 0.5]"),
        (["--settle-tolerance", "NaN"], "--settle-tolerance", "[1e-5, 0.5]"),
        (["--settle-seconds", "0"], "--settle-seconds", "(0, 3600]"),
        (["--settle-seconds", "1e9"], "--settle-seconds", "(0, 3600]"),
        (["--settle-iterations", "0"], "--settle-iterations", "[1, 1000]"),
        (["--dt", "2"], "--dt", "[1e-6, 0.1]"),
        (["--iterations", "5000"], "--iterations", "[1, 1000]"),
    ] {
        let mut args = vec!["simulate", path_str(&input), path_str(&output), "--settle"];
        args.extend(bad.iter());
        let result = coif(&args);
        let message = stderr(&result);
        assert_eq!(result.status.code(), Some(2), "{bad:?}: {message}");
        assert!(message.contains(key) && message.contains(range), "{bad:?}: {message:?}");
    }
    assert_eq!(dir_listing(dir.path()), vec!["in.hair".to_string()]);
}

#[test]
fn recipe_settle_keys_out_of_range_exit_2_with_key_range_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let input = groom(dir.path());
    let base = "[settings]\ndt = 0.0027777778\n[[stages]]\nkind = \"settle\"\nmax_seconds = 1.0\n";
    for (text, key, range) in [
        (format!("{base}tolerance = 0.0\n"), "tolerance", "[1e-5, 0.5]"),
        (format!("{base}tolerance = 5.0\n"), "tolerance", "[1e-5, 0.5]"),
        (base.replace("max_seconds = 1.0", "max_seconds = 0.0"), "max_seconds", "(0, 3600]"),
        (base.replace("dt = 0.0027777778", "dt = 0.5"), "dt", "[1e-6, 0.1]"),
    ] {
        let recipe = dir.path().join("bad.toml");
        std::fs::write(&recipe, &text).unwrap();
        let output = dir.path().join("out.usda");
        let result =
            coif(&["style", path_str(&recipe), "--groom", path_str(&input), "-o", path_str(&output)]);
        let message = stderr(&result);
        assert_eq!(result.status.code(), Some(2), "{text}: {message}");
        assert!(
            message.contains(key) && message.contains(range) && message.contains("bad.toml"),
            "{message:?}"
        );
        assert!(!output.exists(), "{text}: output written");
    }
}

/// `style` reports an unconverged settle stage by its number (stderr and `--json`); with
/// `--require-converged` it exits 1 and still writes the output, as `simulate` does. A batch task
/// says the same in its log.
#[test]
fn style_names_an_unconverged_settle_and_can_require_convergence() {
    let dir = tempfile::tempdir().unwrap();
    let input = groom(dir.path());
    let recipe = |name: &str, max_seconds: f32| {
        let path = dir.path().join(name);
        let text = format!(
            "[settings]\ndt = 0.0027777778\n[[stages]]\nkind = \"settle\"\nmax_seconds = {max_seconds}\n"
        );
        std::fs::write(&path, text).unwrap();
        path
    };
    let (converging, short) = (recipe("long.toml", 30.0), recipe("short.toml", 0.02));
    let output = dir.path().join("out.usda");
    let style = |recipe: &std::path::Path, require: bool| {
        let _ = std::fs::remove_file(&output);
        let mut args =
            vec!["style", path_str(recipe), "--groom", path_str(&input), "-o", path_str(&output), "--json"];
        if require {
            args.push("--require-converged");
        }
        coif(&args)
    };
    let settle_of = |run: &std::process::Output| stdout_json(run)["report"]["stages"][0]["settle"].clone();

    let done = style(&converging, true);
    assert_eq!(done.status.code(), Some(0), "{}", stderr(&done));
    assert_eq!(settle_of(&done)["converged"], true);

    // 20 ms cannot bring a released groom to rest.
    let reported = style(&short, false);
    assert_eq!(reported.status.code(), Some(0), "{}", stderr(&reported));
    let settle = settle_of(&reported);
    assert_eq!(settle["converged"], false, "{settle}");
    assert!(settle["force_residual"].as_f64().unwrap() > settle["tolerance"].as_f64().unwrap(), "{settle}");
    let message = stderr(&reported);
    assert!(
        message.contains("stage 1 (settle)") && message.contains("did not reach its tolerance"),
        "{message}"
    );

    let required = style(&short, true);
    assert_eq!(required.status.code(), Some(1), "{}", stderr(&required));
    assert!(stderr(&required).contains("stage 1 (settle)") && stderr(&required).contains("force residual"));
    assert!(output.exists(), "the unconverged result is still written");
    let json: serde_json::Value = serde_json::from_slice(&required.stdout).expect("--json still reports");
    assert_eq!(json["report"]["stages"][0]["settle"]["converged"], false);

    // A farm task's log is where its artist reads it.
    let manifest = dir.path().join("m.toml");
    let text = "[defaults]\ngroom = \"in.hair\"\nrecipe = \"short.toml\"\noutputs = [\"b/{name}.usda\"]\n\
                [[tasks]]\nname = \"short\"\n";
    std::fs::write(&manifest, text).unwrap();
    let batch = coif(&["batch", path_str(&manifest), "--jobs", "1"]);
    assert!(batch.status.success(), "{}", stderr(&batch));
    let log = std::fs::read_to_string(dir.path().join("logs/short.log")).unwrap();
    assert!(log.contains("stage 1 (settle)") && log.contains("did not reach its tolerance"), "{log}");

    // `require_converged = true` makes it a failed task: exit 1 for the batch, the output written
    // but not recorded as complete, so a re-run does it again rather than skip it.
    std::fs::write(&manifest, text.replace("[[tasks]]", "require_converged = true\n[[tasks]]")).unwrap();
    let required = coif(&["batch", path_str(&manifest), "--jobs", "1", "--json"]);
    assert_eq!(required.status.code(), Some(1), "{}", stderr(&required));
    let report: serde_json::Value = serde_json::from_slice(&required.stdout).unwrap();
    assert_eq!(report["failed"].as_u64(), Some(1), "{report}");
    assert!(dir.path().join("b/short.usda").exists(), "the unconverged result is still written");
    let log = std::fs::read_to_string(dir.path().join("logs/short.log")).unwrap();
    assert!(log.contains("task 'short': stage 1 (settle)") && log.contains("force residual"), "{log}");
    let again = coif(&["batch", path_str(&manifest), "--jobs", "1", "--json"]);
    let report: serde_json::Value = serde_json::from_slice(&again.stdout).unwrap();
    assert_eq!((report["failed"].as_u64(), report["skipped"].as_u64()), (Some(1), Some(0)), "{report}");
}
