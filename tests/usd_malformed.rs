//! Malformed `.usda` is rejected with exit code 2, a message naming the file and the line at
//! fault, and no output file (not even a temporary).
mod common;
use common::*;

use coif::groom::CurveBasis;
use coif::io::usda::{self, ReadOutcome};

const VALID_HEAD: &str = "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n\ndef Xform \"Groom\"\n{\n    def BasisCurves \"Strands\"\n    {\n        uniform token type = \"linear\"\n";

/// (what, text, line the error must name)
fn cases() -> Vec<(&'static str, String, usize)> {
    let stage = |body: &str| format!("{VALID_HEAD}{body}    }}\n}}\n");
    vec![
        (
            "counts that do not match the points",
            stage("        int[] curveVertexCounts = [3, 2]\n        point3f[] points = [(0, 0, 0), (0, 1, 0), (0, 2, 0), (1, 0, 0)]\n"),
            13,
        ),
        (
            "a bad number",
            stage("        int[] curveVertexCounts = [2]\n        point3f[] points = [(0, 0, 0),\n (0, 1e, 0)]\n"),
            14,
        ),
        ("a number with two points", stage("        int[] curveVertexCounts = [2]\n        point3f[] points = [(0, 0, 0), (0, 1.2.3, 0)]\n"), 13),
        ("unknown syntax in a prim", stage("        int[] curveVertexCounts = [2]\n        $points = 3\n"), 13),
        ("an unknown statement at the top", format!("{VALID_HEAD}    }}\n}}\nundef \"X\" {{}}\n"), 14),
        ("a tuple with two numbers for a point3f", stage("        int[] curveVertexCounts = [2]\n        point3f[] points = [(0, 0, 0), (0, 1)]\n"), 13),
        (
            "widths that do not match the vertex count",
            stage("        int[] curveVertexCounts = [2]\n        point3f[] points = [(0, 0, 0), (0, 1, 0)]\n        float[] widths = [0.1, 0.1, 0.1] (\n            interpolation = \"vertex\"\n        )\n"),
            14,
        ),
        (
            "a primvar index out of range",
            stage("        int[] curveVertexCounts = [2]\n        point3f[] points = [(0, 0, 0), (0, 1, 0)]\n        float[] primvars:wetness = [0.5] (\n            interpolation = \"uniform\"\n        )\n        int[] primvars:wetness:indices = [4]\n"),
            14,
        ),
        ("a negative vertex count", stage("        int[] curveVertexCounts = [-2]\n        point3f[] points = []\n"), 12),
        ("an unterminated string", stage("        uniform token wrap = \"nonperiodic\n"), 12),
        ("a missing header", "def Xform \"Groom\"\n{\n}\n".to_string(), 1),
        ("an unknown curve type", stage("        uniform token type = \"spiral\"\n        int[] curveVertexCounts = [2]\n        point3f[] points = [(0, 0, 0), (0, 1, 0)]\n"), 9),
    ]
}

#[test]
fn malformed_usda_exits_2_with_a_line_number_and_writes_nothing() {
    for (what, text, line) in cases() {
        for output in ["out.hair", "out.usda", "out.usdc"] {
            let dir = tempfile::tempdir().unwrap();
            let input = dir.path().join("bad.usda");
            std::fs::write(&input, &text).unwrap();
            let out = coif(&["convert", path_str(&input), path_str(&dir.path().join(output))]);
            let message = stderr(&out);
            assert_eq!(out.status.code(), Some(2), "{what}: {message}");
            assert!(message.contains("bad.usda"), "{what}: the message names the file: {message}");
            assert!(message.contains(&format!("line {line}:")), "{what}: expected line {line}: {message}");
            assert_eq!(dir_listing(dir.path()), ["bad.usda"], "{what}: no output");
        }
    }
}

#[test]
fn a_truncated_file_fails_at_every_cut_with_its_line() {
    let groom = rich_groom_small();
    let mut bytes = Vec::new();
    usda::write(&groom, &mut bytes).unwrap();
    let path = std::path::Path::new("cut.usda");
    // The last bytes are the closing braces' newlines; any earlier cut leaves the stage open.
    for cut in (0..bytes.len() - 2).step_by(7) {
        let result = usda::read(&bytes[..cut], path, &Default::default(), None);
        match result {
            Err(coif::Error::Format { message, .. }) => {
                let line = bytes[..cut].iter().filter(|&&b| b == b'\n').count() + 1;
                assert!(message.starts_with(&format!("line {line}:")), "cut at {cut}: {message}");
            }
            Err(other) => panic!("cut at {cut}: not a format error: {other}"),
            Ok(ReadOutcome::Groom(..)) => panic!("cut at {cut}: a truncated file read as a groom"),
            Ok(ReadOutcome::NeedsComposition(_)) => panic!("cut at {cut}: composition?"),
        }
    }
}

fn rich_groom_small() -> coif::Groom {
    common::usd::rich_groom(CurveBasis::Linear)
}
