//! `coif generate` and `coif info`: the groom has exactly what was asked for, every time.
mod common;
use common::*;

#[test]
fn generate_then_info_reports_what_was_asked() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.hair");
    for (strands, vertices, length, style) in
        [(200, 9, 0.24, "straight"), (100, 17, 0.48, "wavy"), (333, 24, 0.3, "curly")]
    {
        let generated = coif(&[
            "generate",
            "-o",
            path_str(&out),
            "--strands",
            &strands.to_string(),
            "--vertices",
            &vertices.to_string(),
            "--length",
            &length.to_string(),
            "--style",
            style,
        ]);
        assert!(generated.status.success(), "{}", stderr(&generated));

        let info = stdout_json(&coif(&["info", "--json", path_str(&out)]));
        let groom = &info["groom"];
        assert_eq!(groom["strands"], strands);
        assert_eq!(groom["vertices"], strands * vertices);
        assert_eq!(groom["vertices_per_strand"]["min"], vertices as f64);
        assert_eq!(groom["vertices_per_strand"]["max"], vertices as f64);
        for key in ["min", "mean", "max"] {
            let measured = groom["strand_length"][key].as_f64().unwrap();
            assert!(
                (measured - length).abs() < 0.01 * length,
                "{style}: {key} length {measured} vs {length}"
            );
        }
    }
}

#[test]
fn length_variation_spreads_lengths_within_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.hair");
    let args = ["generate", "-o", path_str(&out), "--strands", "400", "--length-variation", "0.2"];
    assert!(coif(&args).status.success());
    let info = stdout_json(&coif(&["info", "--json", path_str(&out)]));
    let lengths = &info["groom"]["strand_length"];
    let (min, max, mean) = (
        lengths["min"].as_f64().unwrap(),
        lengths["max"].as_f64().unwrap(),
        lengths["mean"].as_f64().unwrap(),
    );
    assert!(min >= 0.24 * 0.8 - 1e-4 && max <= 0.24 * 1.2 + 1e-4, "{min}..{max}");
    assert!(max - min > 0.24 * 0.3, "lengths barely vary: {min}..{max}");
    assert!((mean - 0.24).abs() < 0.24 * 0.03, "mean {mean}");
}

#[test]
fn same_seed_same_bytes_other_seed_other_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, seed: &str| {
        let out = dir.path().join(name);
        let args = ["generate", "-o", path_str(&out), "--strands", "500", "--style", "curly", "--seed", seed];
        assert!(coif(&args).status.success());
        std::fs::read(out).unwrap()
    };
    let a = run("a.hair", "7");
    assert_eq!(a, run("b.hair", "7"));
    assert_ne!(a, run("c.hair", "8"));
}

#[test]
fn same_seed_same_bytes_on_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, threads: &str| {
        let out = dir.path().join(name);
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_coif"))
            .args(["generate", "-o", path_str(&out), "--strands", "3000", "--seed", "5"])
            .env("RAYON_NUM_THREADS", threads)
            .status()
            .unwrap();
        assert!(status.success());
        std::fs::read(out).unwrap()
    };
    assert_eq!(run("one.hair", "1"), run("two.hair", "2"));
}

#[test]
fn bad_usage_exits_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("g.hair");
    for args in [
        vec!["generate", "-o", path_str(&out), "--strands", "0"],
        vec!["generate", "-o", path_str(&out), "--length", "-1"],
        vec!["generate", "-o", path_str(&out), "--vertices", "1"],
        vec!["generate", "-o", path_str(&out), "--style", "frizzy"],
        vec!["generate", "-o", "groom.unknownext"],
        vec!["info", "does/not/exist.hair"],
    ] {
        let output = coif(&args);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {}", stderr(&output));
        assert!(!stderr(&output).is_empty());
    }
    assert!(dir_listing(dir.path()).is_empty());
}
