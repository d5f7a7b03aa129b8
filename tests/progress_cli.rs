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
