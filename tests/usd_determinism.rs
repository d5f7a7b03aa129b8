//! `.usda` and `.usdc` output is the same bytes at any thread count, and reading it gives the same groom:
//! large arrays are formatted and parsed in pieces on all threads, joined in order.
mod common;
use common::*;

fn run_with_threads(threads: &str, args: &[&str]) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_coif"))
        .args(args)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn usda_bytes_and_read_back_do_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let hair = dir.path().join("g.hair");
    // 60,000 vertices: several formatting chunks and several parse pieces per array.
    let generated = coif(&[
        "generate",
        "-o",
        path_str(&hair),
        "--strands",
        "1500",
        "--vertices",
        "40",
        "--style",
        "curly",
    ]);
    assert!(generated.status.success(), "{}", stderr(&generated));
    let mut outputs = Vec::new();
    for threads in ["1", "2", "5"] {
        let usda = dir.path().join(format!("t{threads}.usda"));
        run_with_threads(threads, &["convert", path_str(&hair), path_str(&usda)]);
        let back = dir.path().join(format!("t{threads}.hair"));
        run_with_threads(threads, &["convert", path_str(&usda), path_str(&back)]);
        assert_eq!(
            std::fs::read(&back).unwrap(),
            std::fs::read(&hair).unwrap(),
            "{threads} threads read back the groom"
        );
        outputs.push(std::fs::read(&usda).unwrap());
    }
    assert!(outputs[0].len() > 1 << 20, "the file spans several read windows");
    assert!(outputs.iter().all(|o| *o == outputs[0]), "same bytes at 1, 2 and 5 threads");
}

#[test]
fn usdc_bytes_do_not_depend_on_the_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let hair = dir.path().join("g.hair");
    let generated = coif(&["generate", "-o", path_str(&hair), "--strands", "1500", "--vertices", "40"]);
    assert!(generated.status.success(), "{}", stderr(&generated));
    // One curve prim, and a stage of several groups.
    let houdini = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/houdini_groom.usda");
    for (k, input) in [hair.as_path(), houdini.as_path()].into_iter().enumerate() {
        let mut outputs = Vec::new();
        for threads in ["1", "2", "5"] {
            let usdc = dir.path().join(format!("{k}_t{threads}.usdc"));
            run_with_threads(threads, &["convert", path_str(input), path_str(&usdc)]);
            outputs.push(std::fs::read(&usdc).unwrap());
        }
        assert!(
            outputs.iter().all(|o| *o == outputs[0]),
            "{}: same bytes at 1, 2 and 5 threads",
            input.display()
        );
    }
}

/// `.usdz` output is the same bytes whenever it is made: the package's zip entry held the
/// temporary crate file's modification time, so two converts two seconds apart differed (DOS
/// times count in 2 s). The entry's time is now 1980-01-01 00:00, in any time zone.
#[test]
fn usdz_bytes_do_not_depend_on_the_clock_or_the_time_zone() {
    let dir = tempfile::tempdir().unwrap();
    let hair = dir.path().join("g.hair");
    let generated = coif(&["generate", "-o", path_str(&hair), "--strands", "20", "--vertices", "8"]);
    assert!(generated.status.success(), "{}", stderr(&generated));
    let mut outputs = Vec::new();
    for (k, zone) in ["UTC", "America/New_York", "Pacific/Kiritimati"].into_iter().enumerate() {
        if k > 0 {
            std::thread::sleep(std::time::Duration::from_millis(2100));
        }
        let usdz = dir.path().join(format!("{k}.usdz"));
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_coif"))
            .args(["convert", path_str(&hair), path_str(&usdz)])
            .env("TZ", zone)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", stderr(&out));
        // Python's zipfile, not usd-core, reads the entry's time.
        let entries = std::process::Command::new("python3")
            .args([
                "-c",
                "import sys, zipfile; print([i.date_time for i in zipfile.ZipFile(sys.argv[1]).infolist()])",
            ])
            .arg(&usdz)
            .output()
            .unwrap();
        assert_eq!(String::from_utf8_lossy(&entries.stdout).trim(), "[(1980, 1, 1, 0, 0, 0)]", "TZ={zone}");
        outputs.push(std::fs::read(&usdz).unwrap());
    }
    assert!(outputs.iter().all(|o| *o == outputs[0]), "the same groom gave other .usdz bytes");
}
