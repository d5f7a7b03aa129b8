//! `--progress log`: farm and CI logs (stderr not a terminal) get plain progress lines with an
//! ETA, in order, ending at 100 % and the total time; the default shows nothing there.
mod common;
use common::*;

/// The percentages of the `LABEL: P% (done/total) ...` lines, checking each line's shape.
fn logged_percentages(stderr: &str, label: &str) -> Vec<u32> {
    let prefix = format!("{label}: ");
    stderr
        .lines()
        .filter_map(|line| line.strip_prefix(prefix.as_str()))
        .filter(|rest| !rest.starts_with("done in"))
        .map(|rest| {
            assert!(rest.contains(", elapsed ") && rest.contains(", eta "), "a progress line: {rest}");
            rest.split('%').next().unwrap().parse().expect("a percentage")
        })
        .collect()
}

/// `recipe` written to `dir`, and a generated groom of `strands` strands of 8 vertices.
fn recipe_and_groom(
    dir: &std::path::Path,
    recipe: &str,
    strands: usize,
) -> (std::path::PathBuf, std::path::PathBuf) {
    let groom = dir.join("g.hair");
    let strands = strands.to_string();
    let made = coif(&["generate", "-o", path_str(&groom), "--strands", &strands, "--vertices", "8"]);
    assert!(made.status.success(), "{}", stderr(&made));
    let path = dir.join("r.toml");
    std::fs::write(&path, recipe).unwrap();
    (path, groom)
}

#[test]
fn style_and_render_log_progress_with_an_eta_only_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let (recipe, groom) = recipe_and_groom(
        dir.path(),
        "[settings]\ndt = 0.01\n\n[[stages]]\nkind = \"process\"\nduration = 0.5\n\n\
         [[stages]]\nkind = \"process\"\nduration = 0.37\n",
        20,
    );
    let styled = dir.path().join("s.usda");
    let args = ["style", path_str(&recipe), "--groom", path_str(&groom), "-o", path_str(&styled)];

    let logged = coif(&[&args[..], &["--progress", "log"]].concat());
    assert!(logged.status.success(), "{}", stderr(&logged));
    let text = stderr(&logged);
    let percentages = logged_percentages(&text, "style");
    // 87 steps: one line per tenth, in order, the last at 100 % in the second stage.
    let tenths: Vec<u32> = percentages.iter().map(|p| p / 10).collect();
    assert_eq!(tenths, (1..=10).collect::<Vec<u32>>(), "{text}");
    assert!(text.contains("style: 10% (9/87) stage 1/2 process, elapsed "), "{text}");
    assert!(text.contains("style: 100% (87/87) stage 2/2 process, elapsed "), "{text}");
    assert!(text.lines().any(|l| l.starts_with("style: done in ")), "{text}");

    let quiet = coif(&args);
    assert!(quiet.status.success());
    assert!(logged_percentages(&stderr(&quiet), "style").is_empty(), "no bar or lines in a log by default");

    let image = dir.path().join("p.png");
    let render = |progress: &[&str]| {
        let args = ["render", path_str(&styled), "-o", path_str(&image), "--res", "64x48", "--spp", "2"];
        coif(&[&args[..], progress].concat())
    };
    let rendered = render(&["--progress", "log"]);
    assert!(rendered.status.success(), "{}", stderr(&rendered));
    let percentages = logged_percentages(&stderr(&rendered), "render");
    assert_eq!(percentages.last(), Some(&100), "{}", stderr(&rendered));
    assert!(percentages.windows(2).all(|w| w[0] < w[1]), "{percentages:?}");

    // `--quiet`, as on `style` (the README and render's help name it; it was a usage error).
    let quiet = render(&["--quiet"]);
    assert!(quiet.status.success(), "{}", stderr(&quiet));
    assert!(logged_percentages(&stderr(&quiet), "render").is_empty(), "{}", stderr(&quiet));

    let bad = coif(&[&args[..], &["--progress", "sometimes"]].concat());
    assert_eq!(bad.status.code(), Some(2));
    assert!(stderr(&bad).contains("--progress"), "{}", stderr(&bad));
}

/// A settle ends once at rest, usually long before its budget: the lines before it give the ETA
/// as a range (the certain stages left, then with the whole budget), the settle's own lines its
/// residual, and the lines come at tenths of the certain work, not of the budget.
#[test]
fn a_settles_budget_is_an_upper_bound_in_the_eta() {
    let dir = tempfile::tempdir().unwrap();
    let (recipe, groom) = recipe_and_groom(
        dir.path(),
        "[settings]\ndt = 0.01\n\n[[stages]]\nkind = \"process\"\nduration = 0.5\n\n\
         [[stages]]\nkind = \"settle\"\nmax_seconds = 60.0\n",
        20,
    );
    let styled = dir.path().join("s.usda");
    let args = ["style", path_str(&recipe), "--groom", path_str(&groom), "-o", path_str(&styled)];
    let logged = coif(&[&args[..], &["--progress", "log", "--json"]].concat());
    assert!(logged.status.success(), "{}", stderr(&logged));
    let report: serde_json::Value = serde_json::from_slice(&logged.stdout).unwrap();
    let settle = &report["report"]["stages"][1]["settle"];
    assert_eq!(settle["converged"], true, "{report}");
    assert!(settle["steps"].as_u64().unwrap() < 3000, "the settle ended early: {report}");
    let text = stderr(&logged);
    let lines: Vec<&str> =
        text.lines().filter(|l| l.starts_with("style: ") && l.contains(", eta ")).collect();
    // 50 certain steps of 6,050: a line at each of their tenths, each with a range.
    let process: Vec<&&str> = lines.iter().filter(|l| l.contains(" stage 1/2 process, ")).collect();
    assert_eq!(process.len(), 10, "{text}");
    for line in &process {
        let eta = line.split(", eta ").nth(1).unwrap();
        let (low, high) = eta.split_once(" to ").unwrap_or_else(|| panic!("a range: {line}"));
        let seconds =
            |clock: &str| clock.split(':').fold(0u64, |t, part| t * 60 + part.parse::<u64>().unwrap());
        assert!(seconds(low) <= seconds(high), "{line}");
    }
    let last = lines.last().unwrap();
    assert!(last.starts_with("style: 100% (6050/6050) stage 2/2 settle, residual "), "{text}");
    assert!(last.contains(" of 1e-3, elapsed "), "{text}");
}

/// A styled groom's children (interpolated, moved apart, given rest shapes) take as long as its
/// guides' stages at 100,000 strands: their part logs its own lines, in order, to 100 %.
#[test]
fn children_of_guides_log_their_own_progress() {
    let dir = tempfile::tempdir().unwrap();
    let (recipe, groom) = recipe_and_groom(
        dir.path(),
        "[settings]\ndt = 0.01\n\n[guides]\ncount = 10\n\n[contacts]\nhair_hair = true\n\n\
         [[stages]]\nkind = \"process\"\nduration = 0.2\n",
        60,
    );
    let styled = dir.path().join("s.usda");
    let args = ["style", path_str(&recipe), "--groom", path_str(&groom), "-o", path_str(&styled)];
    let logged = coif(&[&args[..], &["--progress", "log"]].concat());
    assert!(logged.status.success(), "{}", stderr(&logged));
    let text = stderr(&logged);
    let percentages = logged_percentages(&text, "children");
    assert_eq!(percentages.last(), Some(&100), "{text}");
    assert!(percentages.windows(2).all(|w| w[0] < w[1]), "{percentages:?}");
    assert!(text.contains(" moved apart, elapsed ") || text.contains(" rest shapes, elapsed "), "{text}");
    let done = |label: &str| text.lines().position(|l| l.starts_with(&format!("{label}: done in ")));
    assert!(done("style") < done("children") && done("style").is_some(), "{text}");
}
