//! Native USD composition against usd-core (pxr): stages of sublayers (with layer offsets),
//! references and payloads to `.usda` and `.usdc` files, internal references, inherits and
//! variant sets are composed by coif and read into the same groom as the stage pxr flattens —
//! points, counts, widths, primvars, groups, purposes, time samples (shifted by the offsets) and
//! stage metadata — at several times and with `--variant`; layers of other time code rates are
//! retimed as pxr retimes them; the strength order of sublayers, inherits, variants, references
//! and payloads, ancestral and direct, is pxr's. With the usd-core venv hidden, no Python starts;
//! bad stages exit 2 naming the file, prim and arc.
mod common;
use common::usd::*;
use common::*;

use coif::groom::CurveBasis;
use coif::io::usda::Selection;
use std::path::{Path, PathBuf};

/// The layers of a composed groom, as text; `EXT` is the format the arcs name (`usda`/`usdc`).
/// `groom.usdc` is written by coif (a crate file in both sets).
const LAYERS: &[(&str, &str)] = &[
    (
        "root",
        r#"#usda 1.0
(
    defaultPrim = "Groom"
    metersPerUnit = 0.01
    upAxis = "Z"
    subLayers = [
        @./over.EXT@ (offset = 5),
        @base.EXT@
    ]
)

def Xform "Groom" (
    prepend payload = @variants.EXT@
)
{
    def "Internal" (
        references = </Groom/Extra>
    )
    {
        float3 xformOp:translate = (0, 0, 2)
        uniform token[] xformOpOrder = ["xformOp:translate"]
    }

    def BasisCurves "Extra" (
        inherits = </_Curves>
    )
    {
        uniform token purpose = "guide"
    }

    over "Probe" (
        prepend payload = @anim.EXT@</Anim/Curves>
    )
    {
    }
}

class BasisCurves "_Curves"
{
    uniform token type = "linear"
    int[] curveVertexCounts = [3]
    point3f[] points = [(0, 0, 0), (0, 1, 0), (0, 2, 1)]
    float[] widths = [0.5, 0.25, 0.125] (
        interpolation = "vertex"
    )
    float[] primvars:wetness = [0.75] (
        interpolation = "uniform"
    )
}
"#,
    ),
    (
        "over",
        r#"#usda 1.0

over "Groom"
{
    def Xform "Anim" (
        prepend references = @anim.EXT@ (offset = 10; scale = 2)
    )
    {
    }

    over "Extra"
    {
        float[] widths = [0.5, 0.5, 0.5] (
            interpolation = "vertex"
        )
    }
}
"#,
    ),
    (
        "base",
        r#"#usda 1.0

def Xform "Groom" (
    prepend references = @groom.usdc@
)
{
    over "Extra"
    {
        uniform token purpose = "render"
        float[] widths = [0.1, 0.1, 0.1] (
            interpolation = "vertex"
        )
    }
}
"#,
    ),
    (
        "anim",
        r#"#usda 1.0
(
    defaultPrim = "Anim"
)

def Xform "Anim"
{
    def BasisCurves "Curves"
    {
        uniform token type = "linear"
        int[] curveVertexCounts = [2]
        point3f[] points.timeSamples = {
            1: [(0, 0, 0), (0, 1, 0)],
            3: [(0, 0, 0), (2, 3, 0)],
        }
        float[] widths = [0.01, 0.02] (
            interpolation = "vertex"
        )
    }
}
"#,
    ),
    (
        "variants",
        r#"#usda 1.0
(
    defaultPrim = "Asset"
)

def Xform "Asset" (
    variants = {
        string length = "short"
    }
    prepend variantSets = "length"
)
{
    def BasisCurves "Probe"
    {
        uniform token type = "linear"
        int[] curveVertexCounts = [2]
        point3f[] points = [(5, 0, 0), (5, 1, 0)]
    }

    variantSet "length" = {
        "long" (
            prepend references = @anim.EXT@
        ) {
            def BasisCurves "Tuft"
            {
                uniform token type = "linear"
                int[] curveVertexCounts = [2]
                point3f[] points = [(1, 0, 0), (1, 4, 0)]
            }
        }
        "short" {
            def BasisCurves "Tuft"
            {
                uniform token type = "linear"
                int[] curveVertexCounts = [2]
                point3f[] points = [(1, 0, 0), (1, 1, 0)]
            }
        }
    }
}
"#,
    ),
];

/// Writes the layers naming `ext` files into `dir` (converted by pxr when `ext` is `usdc`),
/// with `groom.usdc` written by coif; returns the root layer.
fn write_layers(dir: &Path, ext: &str, jobs: &mut Vec<Vec<String>>) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    coif::io::write_groom(&dir.join("groom.usdc"), &rich_groom(CurveBasis::Linear)).unwrap();
    for (name, text) in LAYERS {
        let text = text.replace("EXT", ext);
        let target = dir.join(format!("{name}.{ext}"));
        if ext == "usda" {
            std::fs::write(&target, text).unwrap();
        } else {
            let source = dir.join(format!("{name}.source.usda"));
            std::fs::write(&source, text).unwrap();
            jobs.push(vec!["export".into(), source.display().to_string(), target.display().to_string()]);
        }
    }
    dir.join(format!("root.{ext}"))
}

/// The first field in which two grooms differ (the grooms are too large to print whole).
fn difference(a: &coif::groom::Groom, b: &coif::groom::Groom) -> Option<String> {
    let groups = |g: &coif::groom::Groom| {
        g.groups.iter().map(|g| format!("{}:{:?}", g.name, g.purpose)).collect::<Vec<_>>()
    };
    let fields = [
        ("groups", format!("{:?}", groups(a)), format!("{:?}", groups(b))),
        ("strand_offsets", format!("{:?}", a.strand_offsets), format!("{:?}", b.strand_offsets)),
        ("points", format!("{:?}", a.points), format!("{:?}", b.points)),
        ("widths", format!("{:?}", a.widths), format!("{:?}", b.widths)),
        ("group_ids", format!("{:?}", a.group_ids), format!("{:?}", b.group_ids)),
    ];
    for (name, x, y) in fields {
        if x != y {
            return Some(format!("{name}: {x} != {y}"));
        }
    }
    for (x, y) in a.attributes.iter().zip(&b.attributes) {
        if x != y {
            return Some(format!("attribute {}: {:?} != {:?}", x.name, x.floats(), y.floats()));
        }
    }
    (a != b).then(|| "another field (attribute list, guides, uvs, meshes)".to_string())
}

fn read(path: &Path, time: Option<f64>, variants: &[&str]) -> coif::Result<coif::groom::Groom> {
    let selection = Selection { time, variants: variants.iter().map(|v| v.to_string()).collect() };
    coif::io::read_groom_selected(path, &Default::default(), &selection).map(|loaded| loaded.groom)
}

#[test]
fn usda_and_usdc_stages_compose_as_pxr_flattens_them() {
    let dir = tempfile::tempdir().unwrap();
    let mut jobs = Vec::new();
    let roots = [
        write_layers(&dir.path().join("a"), "usda", &mut jobs),
        write_layers(&dir.path().join("c"), "usdc", &mut jobs),
    ];
    let selections: [&[&str]; 3] = [&[], &["length=long"], &["/Groom:length=short"]];
    let mut cases = Vec::new();
    for root in &roots {
        for (k, variants) in selections.iter().enumerate() {
            let flat = root.with_file_name(format!("flat{k}.usda"));
            let mut job = vec!["flatten".to_string(), root.display().to_string(), flat.display().to_string()];
            job.extend(variants.iter().map(|v| v.to_string()));
            jobs.push(job);
            cases.push((root.clone(), *variants, flat));
        }
    }
    let jobs_file = dir.path().join("jobs.json");
    std::fs::write(&jobs_file, serde_json::to_string(&jobs).unwrap()).unwrap();
    probe(&["batch", path_str(&jobs_file)]);

    for (root, variants, flat) in &cases {
        for time in [None, Some(17.0), Some(19.5), Some(40.0)] {
            let native =
                read(root, time, variants).unwrap_or_else(|e| panic!("{root:?} {variants:?} {time:?}: {e}"));
            let pxr = read(flat, time, &[]).unwrap();
            if let Some(field) = difference(&native, &pxr) {
                panic!("{} {variants:?} at {time:?}: {field}", root.display());
            }
            // Not vacuous: the coif groom's groups, the inherited and internally referenced
            // curves, the tuft of the chosen variant and the animated curves all arrive.
            let names: Vec<&str> = native.groups.iter().map(|g| g.name.as_str()).collect();
            for expected in
                ["/Groom/Strands", "/Groom/Extra", "/Groom/Internal", "/Groom/Tuft", "/Groom/Anim/Curves"]
            {
                assert!(names.contains(&expected), "{expected} missing from {names:?}");
            }
            assert_eq!(names.contains(&"/Groom/Curves"), variants.contains(&"length=long"), "{names:?}");
        }
    }
    // A payload authored on /Groom/Probe is stronger than the one /Groom's payload brings to it.
    let probe_points = |time| {
        let groom = read(&roots[0], time, &[]).unwrap();
        let group = groom.groups.iter().position(|g| g.name == "/Groom/Probe").unwrap();
        let strand = groom.group_ids.iter().position(|&g| g as usize == group).unwrap();
        groom.strand_points(strand).to_vec()
    };
    assert_ne!(probe_points(None), probe_points(Some(17.0)), "samples of the direct payload win at a time");
    // The animated curves: samples at 1 and 3 in anim's time, 17 and 21 on the stage.
    let anim = |time| {
        let groom = read(&roots[1], Some(time), &[]).unwrap();
        let group = groom.groups.iter().position(|g| g.name == "/Groom/Anim/Curves").unwrap();
        let strand = groom.group_ids.iter().position(|&g| g as usize == group).unwrap();
        groom.strand_points(strand)[1]
    };
    let (at17, at19, at21) = (anim(17.0), anim(19.0), anim(21.0));
    assert!((at19 - (at17 + at21) * 0.5).length() < 1e-6, "{at17} {at19} {at21}");
    assert!(at17 != at21);
}

/// Runs coif with no way to start Python: no venv, no pipeline scripts, no `PATH`.
fn coif_without_python(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_coif"))
        .args(args)
        .env("COIF_PYTHON", "/nonexistent/python")
        .env("COIF_PIPELINE", "/nonexistent")
        .env("PATH", "/nonexistent")
        .output()
        .unwrap()
}

#[test]
fn composed_stages_need_no_python() {
    let dir = tempfile::tempdir().unwrap();
    let mut jobs = Vec::new();
    let text_root = write_layers(&dir.path().join("a"), "usda", &mut jobs);
    let binary_root = write_layers(&dir.path().join("c"), "usdc", &mut jobs);
    let jobs_file = dir.path().join("jobs.json");
    std::fs::write(&jobs_file, serde_json::to_string(&jobs).unwrap()).unwrap();
    probe(&["batch", path_str(&jobs_file)]);
    let mut outputs = Vec::new();
    for root in [&text_root, &binary_root] {
        for variant in [None, Some("length=long")] {
            let out = dir.path().join(format!("out{}.usda", outputs.len()));
            let mut args = vec!["convert", path_str(root), path_str(&out)];
            if let Some(variant) = variant {
                args.extend(["--variant", variant]);
            }
            let result = coif_without_python(&args);
            assert!(result.status.success(), "{args:?}: {}", stderr(&result));
            outputs.push(std::fs::read(&out).unwrap());
        }
    }
    assert!(outputs[0] == outputs[2], ".usda and .usdc layers compose to the same groom");
    assert!(outputs[1] == outputs[3], "and so with --variant");
    assert!(outputs[0] != outputs[1], "--variant selects another variant");
}

#[test]
fn bad_composition_exits_2_naming_file_prim_and_arc() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, format!("#usda 1.0\n{text}")).unwrap();
        path
    };
    let curves =
        "def BasisCurves \"C\" { int[] curveVertexCounts = [2]\n point3f[] points = [(0,0,0),(0,1,0)] }";
    write("b.usda", "(\n defaultPrim = \"B\"\n)\ndef \"B\" (\n references = @a.usda@</A>\n) {}\n");
    write("nodefault.usda", &format!("def Xform \"N\" {{ {curves} }}\n"));
    write("variants.usda", "def Xform \"V\" (\n variants = { string length = \"short\" }\n prepend variantSets = \"length\"\n) {\n variantSet \"length\" = {\n \"short\" { def BasisCurves \"C\" { int[] curveVertexCounts = [2]\n point3f[] points = [(0,0,0),(0,1,0)] } }\n }\n}\n");
    let cases: Vec<(PathBuf, Vec<&str>, Vec<&str>)> = vec![
        (
            write("a.usda", &format!("def \"A\" (\n references = @b.usda@\n) {{ {curves} }}\n")),
            vec![],
            vec!["cycle", "</A>"],
        ),
        (
            write("missing.usda", "def \"M\" (\n references = @gone.usda@\n) {}\n"),
            vec![],
            vec!["gone.usda", "</M>", "missing.usda"],
        ),
        (
            write("default.usda", "def \"D\" (\n references = @nodefault.usda@\n) {}\n"),
            vec![],
            vec!["defaultPrim", "nodefault.usda", "</D>"],
        ),
        (
            write("noprim.usda", "def \"P\" (\n references = @nodefault.usda@</Nope>\n) {}\n"),
            vec![],
            vec!["</Nope>", "</P>"],
        ),
        (
            write(
                "special.usda",
                &format!("def \"S\" (\n specializes = </T>\n) {{ {curves} }}\ndef \"T\" {{}}\n"),
            ),
            vec![],
            vec!["specializes", "</S>"],
        ),
        (
            write("self.usda", &format!("(\n subLayers = [@self.usda@]\n)\n{curves}\n")),
            vec![],
            vec!["cycle", "self.usda"],
        ),
        (
            write("scale.usda", "def \"O\" (\n references = @nodefault.usda@</N> (scale = -1)\n) {}\n"),
            vec![],
            vec!["scale", "</O>"],
        ),
        (
            write("pick.usda", "def \"P\" (\n references = @variants.usda@</V>\n) {}\n"),
            vec!["--variant", "length=huge"],
            vec!["huge", "short", "</P>"],
        ),
        (dir.path().join("pick.usda"), vec!["--variant", "color=red"], vec!["color"]),
        (
            write("device.usda", "def \"Z\" (\n references = @/dev/null@</Z>\n) {}\n"),
            vec![],
            vec!["/dev/null", "regular file", "</Z>"],
        ),
    ];
    // A diamond of internal references: 2^30 paths through 60 prims, refused at the node limit.
    let mut diamond = String::from("def \"Root\" (\n references = [</A0>, </B0>]\n) {}\n");
    for level in 0..30 {
        let next = if level < 29 {
            format!("references = [</A{}>, </B{}>]", level + 1, level + 1)
        } else {
            String::new()
        };
        for side in ["A", "B"] {
            diamond.push_str(&format!("def \"{side}{level}\" (\n {next}\n) {{}}\n"));
        }
    }
    let mut cases = cases;
    cases.push((write("diamond.usda", &diamond), vec![], vec!["10000 nodes", "</Root>"]));
    // A fan of files: each layer's two prims reference the next layer, 31 deep (2^31 prims).
    // Refused at the stage's work limit (it took 77 s to get there while every derived node
    // copied its whole subtree).
    for level in 0..31 {
        let prim = |name: &str| match level {
            30 => format!(" def Xform \"{name}\" {{}}\n"),
            _ => format!(" def Xform \"{name}\" (\n  references = @fan{}.usda@\n ) {{}}\n", level + 1),
        };
        let text = format!(
            "#usda 1.0\n(\n defaultPrim = \"r\"\n)\ndef Xform \"r\" {{\n{}{}}}\n",
            prim("a"),
            prim("b")
        );
        write(&format!("fan{level}.usda"), &text);
    }
    cases.push((dir.path().join("fan0.usda"), vec![], vec!["more than 5000000 nodes", "</r/a/a/a"]));
    let out = dir.path().join("out.usda");
    for (input, extra, named) in &cases {
        let mut args = vec!["convert", path_str(input), path_str(&out)];
        args.extend(extra);
        let result = coif_without_python(&args);
        let message = stderr(&result);
        assert_eq!(result.status.code(), Some(2), "{args:?}: {message}");
        for name in named {
            assert!(message.contains(name), "{args:?}: {name:?} not in {message}");
        }
        assert!(!out.exists());
    }
}

/// A bad value on a composed stage is named where it was authored: the sublayer or referenced
/// file and its line (a crate file has no lines), not the root layer the user opened.
#[test]
fn bad_values_name_the_layer_and_line_that_author_them() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        path
    };
    // 1-based line of the first line of `text` containing `needle`.
    let line_of = |text: &str, needle: &str| text.lines().position(|l| l.contains(needle)).unwrap() + 1;
    let curves = |extra: &str| {
        format!(
            "#usda 1.0\n(\n    defaultPrim = \"C\"\n)\n\ndef BasisCurves \"C\"\n{{\n    uniform token type = \"linear\"\n    \
             int[] curveVertexCounts = [2]\n    point3f[] points = [(0, 0, 0), (0, 1, 0)]\n{extra}}}\n"
        )
    };
    let bad_widths =
        curves("    float[] widths = [0.1, 0.1, 0.1] (\n        interpolation = \"vertex\"\n    )\n");
    write("widths.usda", &bad_widths);
    let bad_xform = curves(
        "    token xformOp:translate = \"left\"\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n",
    );
    write("xform.usda", &bad_xform);
    let good = write("good.usda", &curves(""));
    let crate_file = dir.path().join("good.usdc");
    let converted = coif_without_python(&["convert", path_str(&good), path_str(&crate_file)]);
    assert!(converted.status.success(), "{}", stderr(&converted));

    let sublayer = |name: &str| format!("#usda 1.0\n(\n    subLayers = [@./{name}@]\n)\n");
    let reference =
        |name: &str| format!("#usda 1.0\n\ndef \"Groom\" (\n    references = @{name}@\n)\n{{\n}}\n");
    // Counts overridden in the root layer against points in the crate file: the points' site.
    let over_counts = "#usda 1.0\n(\n    subLayers = [@good.usdc@]\n)\n\nover \"C\"\n{\n    int[] curveVertexCounts = [3]\n}\n";
    let root_widths = "#usda 1.0\n(\n    subLayers = [@good.usda@]\n)\n\nover \"C\"\n{\n    float[] widths = [1, 2, 3]\n}\n";
    let cases: Vec<(PathBuf, String, Option<usize>)> = vec![
        (
            write("sub_widths.usda", &sublayer("widths.usda")),
            "widths.usda".into(),
            Some(line_of(&bad_widths, "widths")),
        ),
        (
            write("ref_widths.usda", &reference("widths.usda")),
            "widths.usda".into(),
            Some(line_of(&bad_widths, "widths")),
        ),
        (
            write("sub_xform.usda", &sublayer("xform.usda")),
            "xform.usda".into(),
            Some(line_of(&bad_xform, "xformOp:translate =")),
        ),
        (write("over_counts.usda", over_counts), "good.usdc".into(), None),
        (
            write("root_widths.usda", root_widths),
            "root_widths.usda".into(),
            Some(line_of(root_widths, "widths")),
        ),
    ];
    let out = dir.path().join("out.usda");
    for (input, file, line) in &cases {
        let result = coif_without_python(&["convert", path_str(input), path_str(&out)]);
        let message = stderr(&result);
        assert_eq!(result.status.code(), Some(2), "{}: {message}", input.display());
        let expected = match line {
            Some(line) => format!("{file}: line {line}: prim </"),
            None => format!("{file}: prim </"),
        };
        assert!(message.contains(&expected), "{}: {expected:?} not in {message}", input.display());
        assert!(!out.exists());
    }
}

/// A curve whose one strand moves between time codes 0 and 24 of its layer, in a layer of the
/// given timeline metadata.
fn timed_curves_layer(metadata: &str) -> String {
    format!(
        r#"#usda 1.0
(
    defaultPrim = "Curves"
    {metadata}
)

def BasisCurves "Curves"
{{
    uniform token type = "linear"
    int[] curveVertexCounts = [2]
    point3f[] points.timeSamples = {{
        0: [(0, 0, 0), (0, 1, 0)],
        24: [(2, 0, 0), (2, 1, 0)],
    }}
    float[] widths = [0.01, 0.01] (
        interpolation = "vertex"
    )
}}
"#
    )
}

#[test]
fn layers_of_other_time_code_rates_are_retimed_as_pxr_retimes_them() {
    // A 48-per-second stage: a 24-per-second sublayer (with its own offset) that references a
    // 12-per-second layer, and references to layers at 24 per second, at 12 frames per second
    // (no timeCodesPerSecond) and with no rate at all (24), one of them with an offset.
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, text: &str| std::fs::write(dir.path().join(name), text).unwrap();
    write("a.usda", &timed_curves_layer("timeCodesPerSecond = 24"));
    write("f.usda", &timed_curves_layer("framesPerSecond = 12"));
    write("n.usda", &timed_curves_layer(""));
    write("t.usda", &timed_curves_layer("timeCodesPerSecond = 12"));
    write(
        "sub.usda",
        r#"#usda 1.0
(
    timeCodesPerSecond = 24
)

over "Groom"
{
    def "P" (
        references = @t.usda@ (offset = 10)
    )
    {
    }
}
"#,
    );
    write(
        "root.usda",
        r#"#usda 1.0
(
    defaultPrim = "Groom"
    metersPerUnit = 1
    timeCodesPerSecond = 48
    subLayers = [
        @sub.usda@ (offset = 5; scale = 3)
    ]
)

def Xform "Groom"
{
    def "A" (
        references = @a.usda@
    )
    {
    }

    def "F" (
        references = @f.usda@
    )
    {
    }

    def "N" (
        references = @n.usda@
    )
    {
    }

    def "O" (
        references = @a.usda@ (offset = 10; scale = 2)
    )
    {
    }
}
"#,
    );
    let root = dir.path().join("root.usda");
    let flat = dir.path().join("flat.usda");
    let jobs = dir.path().join("jobs.json");
    std::fs::write(&jobs, serde_json::to_string(&[["flatten", path_str(&root), path_str(&flat)]]).unwrap())
        .unwrap();
    probe(&["batch", path_str(&jobs)]);
    for time in [0.0, 10.0, 24.0, 30.0, 57.5, 96.0, 106.0, 200.0, 353.0, 400.0] {
        let native = read(&root, Some(time), &[]).unwrap_or_else(|e| panic!("at {time}: {e}"));
        let pxr = read(&flat, Some(time), &[]).unwrap();
        if let Some(field) = difference(&native, &pxr) {
            panic!("at {time}: {field}");
        }
    }
    // Not vacuous: /Groom/A (24 per second) reaches its last sample at stage time 48, not 24.
    let x_of = |group: &str, time: f64| {
        let groom = read(&root, Some(time), &[]).unwrap();
        let g = groom.groups.iter().position(|g| g.name == group).unwrap_or_else(|| panic!("no {group}"));
        let strand = groom.group_ids.iter().position(|&id| id as usize == g).unwrap();
        groom.strand_points(strand)[0].x
    };
    assert!((x_of("/Groom/A", 24.0) - 1.0).abs() < 1e-6, "halfway at 24");
    assert!((x_of("/Groom/A", 48.0) - 2.0).abs() < 1e-6, "last sample at 48");
    // 12 frames per second: the last sample at 96. Through the 24-per-second sublayer (offset 5,
    // scale 3, rate ×2) and its reference (offset 10, rate ×2), time 24 of the 12-per-second
    // t.usda is 5 + 3 × 2 × (10 + 2 × 24) = 353.
    assert!((x_of("/Groom/F", 48.0) - 1.0).abs() < 1e-6);
    assert!((x_of("/Groom/P", 353.0) - 2.0).abs() < 1e-6);
    assert!(x_of("/Groom/P", 352.0) < 2.0);
}

/// `--variant` picks what every command reads, not only `info` and `convert`: `simulate`, `style`
/// and `render` once read the stage's default variant whatever was asked; a batch manifest's
/// `variants` too (manifests once had no way to ask).
#[test]
fn every_command_that_reads_a_groom_takes_the_variant_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let strands = |height: f32| {
        let points: Vec<String> = [0.0, 0.01]
            .iter()
            .flat_map(|x| [0.0, 0.5, 1.0].map(|t| format!("({x}, {}, 0)", t * height)))
            .collect();
        format!(
            "def BasisCurves \"Strands\" {{\n uniform token type = \"linear\"\n int[] curveVertexCounts = [3, 3]\n \
             point3f[] points = [{}]\n float[] widths = [1e-4, 1e-4, 1e-4, 1e-4, 1e-4, 1e-4] (interpolation = \"vertex\")\n}}",
            points.join(", ")
        )
    };
    let stage = dir.path().join("variants.usda");
    std::fs::write(
        &stage,
        format!(
            "#usda 1.0\n(\n defaultPrim = \"Groom\"\n metersPerUnit = 1\n upAxis = \"Y\"\n)\n\
             def Xform \"Groom\" (\n variants = {{ string length = \"short\" }}\n prepend variantSets = \"length\"\n)\n{{\n\
             variantSet \"length\" = {{\n \"short\" {{\n{}\n }}\n \"long\" {{\n{}\n }}\n }}\n}}\n",
            strands(0.02),
            strands(0.1)
        ),
    )
    .unwrap();
    let recipe = dir.path().join("r.toml");
    std::fs::write(&recipe, "[[stages]]\nkind = \"process\"\nduration = 0.0\n").unwrap();
    let tallest = |path: &Path| {
        let groom = coif::io::read_groom(path, &Default::default()).unwrap().groom;
        groom.points.iter().map(|p| p.y).fold(f32::MIN, f32::max)
    };
    for variant in [None, Some("length=long")] {
        let height = if variant.is_some() { 0.1 } else { 0.02 };
        let (simulated, styled) = (dir.path().join("simulated.usda"), dir.path().join("styled.usda"));
        let runs = [
            vec!["simulate", path_str(&stage), path_str(&simulated), "--seconds", "0"],
            vec!["style", path_str(&recipe), "--groom", path_str(&stage), "-o", path_str(&styled), "--quiet"],
        ];
        for (mut args, out) in runs.into_iter().zip([&simulated, &styled]) {
            args.extend(variant.iter().flat_map(|v| ["--variant", v]));
            let result = coif(&args);
            assert!(result.status.success(), "{args:?}: {}", stderr(&result));
            assert!((tallest(out) - height).abs() < 1e-6, "{args:?}: {} m tall", tallest(out));
        }
        // A farm batch: the manifest's `variants` (none: the stage's default).
        let (manifest, batched) = (dir.path().join("m.toml"), dir.path().join("batched.usda"));
        let variants = variant.map(|v| format!("variants = [\"{v}\"]\n")).unwrap_or_default();
        std::fs::write(
            &manifest,
            format!("[[tasks]]\nname = \"t\"\ngroom = \"variants.usda\"\nrecipe = \"r.toml\"\noutputs = [\"batched.usda\"]\n{variants}"),
        )
        .unwrap();
        let result = coif(&["batch", path_str(&manifest), "--jobs", "1"]);
        assert!(result.status.success(), "batch {variant:?}: {}", stderr(&result));
        assert!((tallest(&batched) - height).abs() < 1e-6, "batch {variant:?}: {} m tall", tallest(&batched));
    }
    // The long variant fills more of the frame: the images differ.
    let images: Vec<Vec<u8>> = [None, Some("length=long")]
        .iter()
        .map(|variant| {
            let image = dir.path().join("image.png");
            let mut args =
                vec!["render", path_str(&stage), "-o", path_str(&image), "--res", "32x32", "--spp", "1"];
            args.extend(variant.iter().flat_map(|v| ["--variant", *v]));
            let result = coif(&args);
            assert!(result.status.success(), "{args:?}: {}", stderr(&result));
            std::fs::read(&image).unwrap()
        })
        .collect();
    assert!(images[0] != images[1], "render read the default variant for --variant length=long");
}

/// A shot whose range starts before its cache's first time sample (frames 101–110, the cache
/// referenced with an offset so that its first sample lands on 102): the stage's own range is
/// read whole, the first sample holding before itself, as pxr evaluates it. coif refused the
/// default convert ("frame 101 is before the first time sample"). A frame outside the stage's
/// range and before every sample is still refused.
#[test]
fn a_stage_range_that_starts_before_the_first_sample_holds_the_first_sample() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("cache.usda"), timed_curves_layer("timeCodesPerSecond = 24")).unwrap();
    let shot = dir.path().join("shot.usda");
    std::fs::write(
        &shot,
        "#usda 1.0\n(\n    metersPerUnit = 1\n    startTimeCode = 101\n    endTimeCode = 110\n    timeCodesPerSecond = 24\n)\n\n\
         def \"Groom\" (\n    references = @cache.usda@ (offset = 102)\n)\n{\n}\n",
    )
    .unwrap();
    let out = dir.path().join("anim.usda");
    let converted = coif(&["convert", path_str(&shot), path_str(&out)]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    for frame in [101.0, 102.0, 105.0, 110.0] {
        let ours = pxr_dump(&out, Some(frame));
        let theirs = pxr_dump(&shot, Some(frame));
        let points = |dump: &serde_json::Value| f32s(&dump["curves"][0]["points"]);
        assert_eq!(points(&ours), points(&theirs), "frame {frame}");
    }
    let refused = coif(&["convert", path_str(&shot), path_str(&dir.path().join("f.usda")), "--frame", "100"]);
    assert_eq!(refused.status.code(), Some(2), "{}", stderr(&refused));
    assert!(stderr(&refused).contains("frame 100 is before the first time sample"), "{}", stderr(&refused));
}

/// A stage whose curves are time-sampled but which authors no frame range (`startTimeCode` <
/// `endTimeCode`) has no timeline to convert, and pxr reads no points at its default time; coif
/// reads one moment, each value's earliest sample. It did so without a word (`convert` wrote a
/// static file, `info` said "not animated"); now every command that reads it warns, naming the
/// file, the sampled attribute and how to read the animation — through a plain layer, a composed
/// one, pxr's `.usdc` of it and a `.usdz` package of it (read through usd-core's flattening, which
/// dropped the warning). A stage with a range, the frames asked for, or nothing sampled get no
/// warning.
#[test]
fn a_moving_stage_without_a_frame_range_is_read_as_one_moment_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    std::fs::write(path("cache.usda"), timed_curves_layer("metersPerUnit = 1")).unwrap();
    std::fs::write(
        path("shot.usda"),
        "#usda 1.0\n(\n    metersPerUnit = 1\n)\n\ndef \"Groom\" (\n    references = @cache.usda@\n)\n{\n}\n",
    )
    .unwrap();
    let jobs = path("jobs.json");
    let (cache, cache_pxr) = (path("cache.usda"), path("cache_pxr.usdc"));
    let flatten = [["flatten", path_str(&cache), path_str(&cache_pxr)]];
    std::fs::write(&jobs, serde_json::to_string(&flatten).unwrap()).unwrap();
    probe(&["batch", path_str(&jobs)]);
    usdz_package(&cache, &path("cache.usdz"));
    let warned = |text: &str, file: &str| {
        text.contains(&format!("{file}: '/"))
            && text.contains(".points' is time-sampled but the stage authors no frame range")
            && text.contains("--frame-range FIRST:LAST")
    };
    for input in ["cache.usda", "shot.usda", "cache_pxr.usdc", "cache.usdz"] {
        let stage = path(input);
        let info = coif(&["info", path_str(&stage)]);
        assert!(info.status.success(), "{input}: {}", stderr(&info));
        assert!(warned(&stderr(&info), input), "{input}: info gave no warning: {}", stderr(&info));
        let text = String::from_utf8_lossy(&info.stdout).to_string();
        assert!(text.contains("one moment (see the warning)") && !text.contains("not animated"), "{text}");
        let info = stdout_json(&coif(&["info", path_str(&stage), "--json"]));
        assert!(info["frames"].is_null(), "{input}: {info}");
        assert!(warned(info["warnings"][0].as_str().unwrap_or(""), input), "{input}: {info}");

        // The moment written is the earliest sample (pxr reads no value at its default time).
        let out = path(&format!("{input}.moment.usda"));
        let converted = coif(&["convert", path_str(&stage), path_str(&out), "--json"]);
        assert!(converted.status.success(), "{input}: {}", stderr(&converted));
        assert!(
            warned(&stderr(&converted), input),
            "{input}: convert gave no warning: {}",
            stderr(&converted)
        );
        let report: serde_json::Value = serde_json::from_slice(&converted.stdout).unwrap();
        assert!(warned(report["warnings"][0].as_str().unwrap_or(""), input), "{input}: {report}");
        let points = |dump: &serde_json::Value| f32s(&dump["curves"][0]["points"]);
        assert_eq!(points(&pxr_dump(&out, None)), points(&pxr_dump(&stage, Some(0.0))), "{input}");
        assert_eq!(points(&pxr_dump(&out, None)), vec![0.0, 0.0, 0.0, 0.0, 1.0, 0.0], "{input}");

        // The animation, when asked for: no warning, and pxr finds the samples.
        let animated = path(&format!("{input}.anim.usda"));
        let converted = coif(&["convert", path_str(&stage), path_str(&animated), "--frame-range", "0:24"]);
        assert!(converted.status.success(), "{input}: {}", stderr(&converted));
        assert!(!stderr(&converted).contains("time-sampled"), "{input}: {}", stderr(&converted));
        assert_eq!(points(&pxr_dump(&animated, Some(24.0)))[0], 2.0, "{input}");
    }
    // Controls: a range makes the stage animated (converted whole, no warning); a static stage
    // is silent.
    std::fs::write(
        path("ranged.usda"),
        timed_curves_layer("metersPerUnit = 1\n    startTimeCode = 0\n    endTimeCode = 24"),
    )
    .unwrap();
    let converted = coif(&["convert", path_str(&path("ranged.usda")), path_str(&path("ranged_out.usda"))]);
    assert!(converted.status.success(), "{}", stderr(&converted));
    assert!(!stderr(&converted).contains("warning"), "{}", stderr(&converted));
    assert_eq!(f32s(&pxr_dump(&path("ranged_out.usda"), Some(24.0))["curves"][0]["points"])[0], 2.0);
    let still = path("still.usda");
    let sampled = "point3f[] points.timeSamples = {\n        0: [(0, 0, 0), (0, 1, 0)],\n        24: [(2, 0, 0), (2, 1, 0)],\n    }";
    let layer = timed_curves_layer("metersPerUnit = 1");
    assert!(layer.contains(sampled));
    std::fs::write(&still, layer.replace(sampled, "point3f[] points = [(0, 0, 0), (0, 1, 0)]")).unwrap();
    let info = coif(&["info", path_str(&still)]);
    assert!(info.status.success() && !stderr(&info).contains("warning"), "{}", stderr(&info));
    assert!(String::from_utf8_lossy(&info.stdout).contains("not animated"));
}

/// The same for a stage whose only time samples are a prim's `visibility` (a hide keyed in a
/// layer without a frame range, as pxr confirms): pxr reads the fallback (`inherited`) at its
/// default time, coif the earliest sample (`invisible`); it did so without a word. Now `info`
/// and `convert` warn naming the attribute and how to read the animation.
#[test]
fn a_keyed_hide_without_a_frame_range_is_read_as_one_moment_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let stage = dir.path().join("hide.usda");
    let script = r#"
import sys
from pxr import Usd, UsdGeom, Gf
stage = Usd.Stage.CreateNew(sys.argv[1])
UsdGeom.SetStageMetersPerUnit(stage, 1)
c = UsdGeom.BasisCurves.Define(stage, '/hair')
c.CreateTypeAttr('linear')
c.CreateCurveVertexCountsAttr([2])
c.CreatePointsAttr([Gf.Vec3f(0, 0, 0), Gf.Vec3f(0, -0.1, 0)])
c.CreateVisibilityAttr().Set('invisible', 1)
c.GetVisibilityAttr().Set('inherited', 2)
stage.Save()
stage = Usd.Stage.Open(sys.argv[1])
assert not stage.HasAuthoredTimeCodeRange()
assert stage.GetPrimAtPath('/hair').GetAttribute('visibility').GetTimeSamples() == [1.0, 2.0]
"#;
    run_pxr_script(script, &stage);
    let warned = |text: &str| {
        text.contains("hide.usda: '/hair.visibility' is time-sampled but the stage authors no frame range")
            && text.contains("--frame-range FIRST:LAST")
    };
    let info = coif(&["info", path_str(&stage)]);
    assert!(info.status.success() && warned(&stderr(&info)), "{}", stderr(&info));
    let converted = coif(&["convert", path_str(&stage), path_str(&dir.path().join("out.usda"))]);
    assert!(converted.status.success() && warned(&stderr(&converted)), "{}", stderr(&converted));
}

/// A stage that authors `framesPerSecond` but no `timeCodesPerSecond` (as some exporters write)
/// counts its time codes at `framesPerSecond` in pxr; coif read it at 24, so `convert` wrote its
/// animation a quarter slower and `--time` picked the wrong frame. Each stage below, as text, as
/// pxr's own `.usdc` and as a `.usdz` package (whose timeline coif did not read at all: "not
/// animated"), must play at the rate pxr gives it: in `info`, in the `.usda` and `.abc` that
/// `convert` writes, and for `--time`.
#[test]
fn a_stage_plays_at_the_time_code_rate_pxr_gives_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let range = "metersPerUnit = 1\n    startTimeCode = 0\n    endTimeCode = 24";
    let stages = [
        ("frames.usda", format!("{range}\n    framesPerSecond = 30"), 30.0),
        ("both.usda", format!("{range}\n    framesPerSecond = 30\n    timeCodesPerSecond = 12"), 12.0),
        ("none.usda", range.to_string(), 24.0),
    ];
    let mut flatten = Vec::new();
    for (name, metadata, _) in &stages {
        std::fs::write(path(name), timed_curves_layer(metadata)).unwrap();
        let binary = path(&name.replace(".usda", "_pxr.usdc"));
        flatten.push([
            "flatten".to_string(),
            path_str(&path(name)).to_string(),
            path_str(&binary).to_string(),
        ]);
    }
    let jobs = path("jobs.json");
    std::fs::write(&jobs, serde_json::to_string(&flatten).unwrap()).unwrap();
    probe(&["batch", path_str(&jobs)]);
    for (name, _, rate) in &stages {
        usdz_package(&path(name), &path(&name.replace(".usda", ".usdz")));
        let inputs = [name.to_string(), name.replace(".usda", "_pxr.usdc"), name.replace(".usda", ".usdz")];
        for input in inputs {
            let stage = path(&input);
            // The independent expectation: pxr's rate for this stage (and the one named above).
            let pxr_rate = pxr_dump(&stage, Some(0.0))["timeCodesPerSecond"].as_f64().unwrap();
            assert_eq!(pxr_rate, *rate, "{input}: pxr");
            let info = stdout_json(&coif(&["info", path_str(&stage), "--json"]));
            assert_eq!(info["frames"]["frames_per_second"].as_f64(), Some(pxr_rate), "{input}: {info}");
            assert_eq!(
                (info["frames"]["first"].as_f64(), info["frames"]["last"].as_f64()),
                (Some(0.0), Some(24.0))
            );

            // The converted animation keeps the frames and their rate.
            let usda = path(&format!("{input}.out.usda"));
            let converted = coif(&["convert", path_str(&stage), path_str(&usda)]);
            assert!(converted.status.success(), "{input}: {}", stderr(&converted));
            let dump = pxr_dump(&usda, Some(12.0));
            assert_eq!(dump["timeCodesPerSecond"].as_f64(), Some(pxr_rate), "{input}: converted .usda");
            assert_eq!(
                f32s(&dump["curves"][0]["points"]),
                f32s(&pxr_dump(&stage, Some(12.0))["curves"][0]["points"])
            );
            let abc = path(&format!("{input}.out.abc"));
            let converted = coif(&["convert", path_str(&stage), path_str(&abc)]);
            assert!(converted.status.success(), "{input}: {}", stderr(&converted));
            let bytes = std::fs::read(&abc).unwrap();
            let archive = coif::io::alembic::CurvesArchive::open(&bytes).unwrap();
            assert_eq!(
                (archive.frames_per_second(), archive.frame_range()),
                (pxr_rate, (0.0, 24.0)),
                "{input}"
            );
            // Frame 0 is printed as 0, not the -0 that rounding a sample time gave.
            let text = String::from_utf8_lossy(&coif(&["info", path_str(&abc)]).stdout).to_string();
            let frames = format!("frames       0 to 24 (25 frames at {pxr_rate} fps)");
            assert!(text.contains(&frames), "{input}: {frames:?} not in\n{text}");

            // Half a second is frame 0.5 × rate, where pxr finds the points.
            let moment = path(&format!("{input}.half.usda"));
            let converted = coif(&["convert", path_str(&stage), path_str(&moment), "--time", "0.5"]);
            assert!(converted.status.success(), "{input}: {}", stderr(&converted));
            assert_eq!(
                f32s(&pxr_dump(&moment, None)["curves"][0]["points"]),
                f32s(&pxr_dump(&stage, Some(0.5 * pxr_rate))["curves"][0]["points"]),
                "{input}: --time 0.5"
            );
        }
    }
    // A rate that is not a positive number cannot turn seconds into frames, nor frames into an
    // animation (such a stage was read as one moment without a word): exit 2, naming the file
    // and the key that authors it.
    for (metadata, key) in
        [("timeCodesPerSecond = 0", "timeCodesPerSecond 0"), ("framesPerSecond = -2", "framesPerSecond -2")]
    {
        let stage = path("bad_rate.usda");
        std::fs::write(&stage, timed_curves_layer(&format!("{range}\n    {metadata}"))).unwrap();
        let converted = path("bad_rate_out.usda");
        for args in [
            vec!["info", path_str(&stage), "--time", "0.5"],
            vec!["info", path_str(&stage)],
            vec!["convert", path_str(&stage), path_str(&converted)],
        ] {
            let out = coif(&args);
            assert_eq!(out.status.code(), Some(2), "{metadata} {args:?}: {}", stderr(&out));
            let message = stderr(&out);
            assert!(
                message.contains("bad_rate.usda") && message.contains(&format!("{key} is not a frame rate")),
                "{args:?}: {message}"
            );
            assert!(!converted.exists());
        }
    }
}

/// `convert` reads an animated `.usda` layer once for all its frames (it parsed the whole text
/// again for each frame: a 100-frame cache of 5,000 strands, 315 MB, took 26 s; now 0.9 s). Each
/// frame written must still be the stage at that frame as pxr evaluates it — samples out of
/// order, at equal times, between frames and beyond the range, a moving transform — and as coif
/// reads that frame alone (`--frame N`, the control).
#[test]
fn an_animated_usda_converts_every_frame_from_one_reading() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let points = |x: f32| {
        format!(
            "[(0, 0, 0), ({x}, 0.1, 0), ({x}, 0.2, 0.01), (0.05, 0, 0), (0.05, 0.1, {x}), (0.05, 0.2, 0)]"
        )
    };
    let samples: Vec<String> =
        [(7.0, 0.07), (-3.0, -0.03), (2.5, 0.025), (2.5, 0.026), (12.0, 0.12), (4.0, 0.04), (0.5, 0.005)]
            .iter()
            .map(|&(t, x)| format!("{t}: {}", points(x)))
            .collect();
    let stage = path("cache.usda");
    std::fs::write(
        &stage,
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n    startTimeCode = 1\n    endTimeCode = 9\n)\n\n\
             def Xform \"G\"\n{{\n    double3 xformOp:translate.timeSamples = {{ 8: (0, 0.2, 0), -1: (0, 0.1, 0) }}\n    \
             uniform token[] xformOpOrder = [\"xformOp:translate\"]\n\n    def BasisCurves \"C\"\n    {{\n        \
             uniform token type = \"linear\"\n        int[] curveVertexCounts = [3, 3]\n        \
             point3f[] points.timeSamples = {{ {} }}\n        float[] widths = [0.001] (interpolation = \"constant\")\n    }}\n}}\n",
            samples.join(", ")
        ),
    )
    .unwrap();
    let whole = path("whole.usda");
    let part = path("part.usda");
    let abc = path("whole.abc");
    for (out, range) in [(&whole, None), (&abc, None), (&part, Some("3:6"))] {
        let mut args = vec!["convert", path_str(&stage), path_str(out)];
        args.extend(range.iter().flat_map(|r| ["--frame-range", *r]));
        let converted = coif(&args);
        assert!(converted.status.success(), "{out:?}: {}", stderr(&converted));
    }
    same_frames(&pxr_frames(&whole, 1.0, 9.0), &pxr_frames(&stage, 1.0, 9.0), "whole.usda");
    same_frames(&pxr_frames(&part, 3.0, 6.0), &pxr_frames(&stage, 3.0, 6.0), "part.usda");
    for frame in 1..=9 {
        let options = coif::io::ImportOptions { frame: Some(frame as f64), ..Default::default() };
        let alone = coif::io::read_groom(&stage, &options).unwrap().groom;
        let written = coif::io::read_groom(&abc, &options).unwrap().groom;
        assert_eq!(written.points, alone.points, "frame {frame} of whole.abc");
    }
}

/// Points of every frame (pxr's reading of a converted file against pxr's of the source) within
/// a micrometre; `what` names the file, frames counted from 0.
fn same_frames(got: &[Vec<f32>], want: &[Vec<f32>], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: frames");
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(g.len(), w.len(), "{what}: frame {k}");
        let worst = g.iter().zip(w).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
        assert!(worst < 1e-6, "{what}: frame {k} is {worst} m from pxr's");
    }
}

/// A shot layer composing animated `.usda` caches — referenced with an offset, one of another
/// time code rate, one a sublayer scaled in time, one chosen by a variant, with samples of the
/// shot's own over them — converts every frame as pxr composes it, and as coif reads each frame
/// alone (`--frame N`, where each layer is parsed for that frame): the layers parsed once for all
/// frames must give what a parse for each frame gives.
#[test]
fn a_shot_composing_animated_usda_caches_converts_every_frame_as_pxr_composes_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let points = |x: f32, z: f32| format!("[(0, 0, {z}), ({x}, 0.1, {z}), ({x}, 0.2, 0.01), (0.05, 0, {z})]");
    // Samples out of order, at equal times, between frames and beyond every range.
    let cache = |name: &str, rate: &str, z: f32| {
        let samples: Vec<String> =
            [(7.0, 0.07), (-3.0, -0.03), (2.5, 0.025), (2.5, 0.026), (30.0, 0.3), (4.0, 0.04)]
                .iter()
                .map(|&(t, x)| format!("{t}: {}", points(x, z)))
                .collect();
        std::fs::write(
            path(name),
            format!(
                "#usda 1.0\n(\n    metersPerUnit = 1\n    startTimeCode = 1\n    endTimeCode = 9\n{rate})\n\n\
                 def Xform \"G\"\n{{\n    def BasisCurves \"C\"\n    {{\n        uniform token type = \"linear\"\n        \
                 int[] curveVertexCounts = [2, 2]\n        point3f[] points.timeSamples = {{ {} }}\n        \
                 float[] widths = [0.001] (interpolation = \"constant\")\n    }}\n}}\n",
                samples.join(", ")
            ),
        )
        .unwrap();
    };
    cache("a.usda", "", 0.0);
    cache("b48.usda", "    timeCodesPerSecond = 48\n", 0.1);
    cache("c.usda", "", 0.2);
    cache("d.usda", "", 0.3);
    std::fs::write(
        path("layout.usda"),
        "#usda 1.0\n(\n    subLayers = [@c.usda@ (offset = 2; scale = 0.5)]\n)\n",
    )
    .unwrap();
    let shot = path("shot.usda");
    std::fs::write(
        &shot,
        "#usda 1.0\n(\n    metersPerUnit = 1\n    startTimeCode = 101\n    endTimeCode = 112\n    \
         subLayers = [@layout.usda@ (offset = 100)]\n)\n\n\
         def Xform \"Shot\" (\n    variants = { string cache = \"d\" }\n    prepend variantSets = \"cache\"\n)\n{\n    \
         def \"A\" (references = @a.usda@</G> (offset = 100))\n    {\n        \
         double3 xformOp:translate.timeSamples = { 104: (0, 0.1, 0), 109.5: (0, 0.3, 0) }\n        \
         uniform token[] xformOpOrder = [\"xformOp:translate\"]\n    }\n    \
         def \"B\" (references = @b48.usda@</G> (offset = 99))\n    {\n    }\n    \
         variantSet \"cache\" = {\n        \"d\" {\n            \
         def \"V\" (references = @d.usda@</G> (offset = 100))\n            {\n            }\n        }\n        \
         \"a\" {\n            def \"V\" (references = @a.usda@</G> (offset = 101))\n            {\n            }\n        }\n    }\n}\n",
    )
    .unwrap();
    let converted = path("converted.usda");
    let abc = path("converted.abc");
    let abc_variant = path("variant.abc");
    for (out, variant) in [(&converted, None), (&abc, None), (&abc_variant, Some("cache=a"))] {
        let mut args = vec!["convert", path_str(&shot), path_str(out)];
        args.extend(variant.iter().flat_map(|v| ["--variant", *v]));
        let run = coif(&args);
        assert!(run.status.success(), "{out:?}: {}", stderr(&run));
    }
    let (got, want) = (pxr_frames(&converted, 101.0, 112.0), pxr_frames(&shot, 101.0, 112.0));
    assert_eq!(got.len(), 12, "frames converted");
    same_frames(&got, &want, "converted.usda (frames from 101)");
    // The frames differ (the test would not see a frame read at the wrong time otherwise).
    assert!(want.windows(2).filter(|w| w[0] != w[1]).count() >= 6, "the shot barely moves");
    for frame in 101..=112 {
        for (out, variants) in [(&abc, vec![]), (&abc_variant, vec!["cache=a".to_string()])] {
            let options = coif::io::ImportOptions { frame: Some(frame as f64), ..Default::default() };
            let selection = Selection { time: Some(frame as f64), variants };
            let alone = coif::io::read_groom_selected(&shot, &options, &selection).unwrap().groom;
            let written = coif::io::read_groom(out, &options).unwrap().groom;
            assert_eq!(written.points, alone.points, "frame {frame} of {out:?}");
        }
    }
}

/// Points with a default (a rest pose, as exporters write it) and time samples over it, reached
/// through a sublayer or a reference, are an animation as pxr plays it: `info` gives its frames
/// and `convert` writes every frame as pxr composes it. Samples authored over a weaker default
/// animate too; a stronger default over weaker samples holds the stage still, in pxr and in coif.
#[test]
fn points_with_a_default_and_time_samples_animate_through_sublayers_and_references() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let points = |x: f32| format!("[(0, 0, 0), ({x}, 0.1, 0), (0.02, 0, 0), ({x}, 0.1, 0.02)]");
    let header = "#usda 1.0\n(\n    metersPerUnit = 1\n    startTimeCode = 1\n    endTimeCode = 4\n";
    let curves = |points: &str| {
        format!(
            "def BasisCurves \"C\"\n{{\n    uniform token type = \"linear\"\n    int[] curveVertexCounts = [2, 2]\n    \
             {points}\n    float[] widths = [0.001] (interpolation = \"constant\")\n}}\n"
        )
    };
    let samples = format!("1: {}, 2.5: {}, 4: {}", points(0.1), points(0.25), points(0.4));
    let animated =
        format!("point3f[] points = {}\n    point3f[] points.timeSamples = {{ {samples} }}", points(0.0));
    std::fs::write(path("cache.usda"), format!("{header})\n\n{}", curves(&animated))).unwrap();
    std::fs::write(
        path("rest.usda"),
        format!("{header})\n\n{}", curves(&format!("point3f[] points = {}", points(0.0)))),
    )
    .unwrap();
    let over = |points: &str| format!("over \"C\"\n{{\n    {points}\n}}\n");
    let stages = [
        ("sublayer.usda", format!("{header}    subLayers = [@cache.usda@]\n)\n"), true),
        (
            "reference.usda",
            format!("{header})\n\ndef \"Shot\" (references = @cache.usda@</C>)\n{{\n}}\n"),
            true,
        ),
        (
            "samples_over_rest.usda",
            format!(
                "{header}    subLayers = [@rest.usda@]\n)\n\n{}",
                over(&format!("point3f[] points.timeSamples = {{ {samples} }}"))
            ),
            true,
        ),
        (
            "rest_over_samples.usda",
            format!(
                "{header}    subLayers = [@cache.usda@]\n)\n\n{}",
                over(&format!("point3f[] points = {}", points(0.3)))
            ),
            false,
        ),
    ];
    for (name, text, moves) in stages {
        let stage = path(name);
        std::fs::write(&stage, text).unwrap();
        let info = coif(&["info", "--json", path_str(&stage)]);
        assert!(info.status.success(), "{name}: {}", stderr(&info));
        let info: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
        assert_eq!(info["frames"]["count"].as_u64(), if moves { Some(4) } else { None }, "{name}: {info}");
        let converted = path(&format!("{name}.converted.usda"));
        let run = coif(&["convert", path_str(&stage), path_str(&converted)]);
        assert!(run.status.success(), "{name}: {}", stderr(&run));
        let (got, want) = (pxr_frames(&converted, 1.0, 4.0), pxr_frames(&stage, 1.0, 4.0));
        assert_eq!(want.windows(2).any(|w| w[0] != w[1]), moves, "{name}: pxr's frames");
        same_frames(&got, &want, &format!("{name} (frames from 1)"));
    }
}

/// Layers listing the next layer twice (with different time offsets, and through a diamond) compose
/// as pxr composes them: a repeat is shadowed by the stronger listing of the same layer. And a chain
/// of 40 such layers (2 KB of files; each level used to double coif's layer stack, 30 levels ran
/// out of memory) reads its two curves at once.
#[test]
fn sublayers_listed_twice_are_taken_once_as_pxr_composes_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let header = "#usda 1.0\n(\n    metersPerUnit = 1\n    startTimeCode = 1\n    endTimeCode = 12\n";
    let points = |x: f32| format!("[(0, 0, 0), ({x}, 0.1, 0), (0.02, 0, 0), ({x}, 0.1, 0.02)]");
    let samples = format!("1: {}, 5: {}, 9: {}", points(0.1), points(0.3), points(0.2));
    std::fs::write(
        path("leaf.usda"),
        format!(
            "{header})\n\ndef BasisCurves \"C\"\n{{\n    uniform token type = \"linear\"\n    \
             int[] curveVertexCounts = [2, 2]\n    point3f[] points.timeSamples = {{ {samples} }}\n    \
             float[] widths = [0.001] (interpolation = \"constant\")\n}}\n"
        ),
    )
    .unwrap();
    // mid.usda lists the leaf twice, at offsets 2 and 0; top.usda lists mid twice and the leaf.
    std::fs::write(
        path("mid.usda"),
        format!("{header}    subLayers = [@leaf.usda@ (offset = 2), @leaf.usda@]\n)\n"),
    )
    .unwrap();
    let top = path("top.usda");
    std::fs::write(
        &top,
        format!(
            "{header}    subLayers = [@mid.usda@ (offset = 1), @leaf.usda@ (offset = 5), @mid.usda@]\n)\n"
        ),
    )
    .unwrap();
    let converted = path("converted.usda");
    let run = coif(&["convert", path_str(&top), path_str(&converted)]);
    assert!(run.status.success(), "{}", stderr(&run));
    let (got, want) = (pxr_frames(&converted, 1.0, 12.0), pxr_frames(&top, 1.0, 12.0));
    same_frames(&got, &want, "the diamond of repeated sublayers");
    assert!(want.windows(2).filter(|w| w[0] != w[1]).count() >= 6, "the stage barely moves");

    let levels = 40;
    for level in 0..levels - 1 {
        let next = format!("chain{}.usda", level + 1);
        std::fs::write(
            path(&format!("chain{level}.usda")),
            format!("{header}    subLayers = [@{next}@, @{next}@]\n)\n"),
        )
        .unwrap();
    }
    std::fs::copy(path("leaf.usda"), path(&format!("chain{}.usda", levels - 1))).unwrap();
    let start = std::time::Instant::now();
    let info = coif(&["info", path_str(&path("chain0.usda")), "--json", "--max-memory", "256M"]);
    assert!(info.status.success(), "{}", stderr(&info));
    let report: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    assert_eq!(report["groom"]["strands"], 2, "{report}");
    eprintln!("a chain of {levels} doubled sublayers read in {:.2} s", start.elapsed().as_secs_f64());
}

/// A shot layout: a 30 tc/s head cache whose transform is sampled every code, referenced with an
/// offset and a scale by a 24 tc/s layer, sublayered at 1000 into a 48 tc/s shot. Some samples
/// land exactly on the shot's frames (1011, 1023): pxr takes the sample there; coif took the
/// one before it (a whole sample step, 9–13 mm here), as the composed time, mapped back into the
/// cache and out again, ended a hair short of the sample.
#[test]
fn transform_samples_that_land_on_a_frame_through_retimed_layers_are_taken_as_pxr_takes_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let samples: Vec<String> = (1..=10).map(|t| format!("{t}: (0, {}, 0)", 0.001 * (t * t) as f64)).collect();
    std::fs::write(
        path("cache.usda"),
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n    timeCodesPerSecond = 30\n    startTimeCode = 1\n    \
             endTimeCode = 10\n)\n\ndef Xform \"G\"\n{{\n    double3 xformOp:translate.timeSamples = {{ {} }}\n    \
             uniform token[] xformOpOrder = [\"xformOp:translate\"]\n\n    def BasisCurves \"hair\"\n    {{\n        \
             uniform token type = \"linear\"\n        int[] curveVertexCounts = [2]\n        \
             point3f[] points = [(0, 0, 0), (0, -0.1, 0)]\n        float[] widths = [0.001] (interpolation = \"constant\")\n    }}\n}}\n",
            samples.join(", ")
        ),
    )
    .unwrap();
    std::fs::write(
        path("sub.usda"),
        "#usda 1.0\n(\n    metersPerUnit = 1\n    timeCodesPerSecond = 24\n)\n\n\
         def Xform \"W\" (references = @cache.usda@</G> (offset = -0.5; scale = 1.5))\n{\n}\n",
    )
    .unwrap();
    let shot = path("shot.usda");
    std::fs::write(
        &shot,
        "#usda 1.0\n(\n    metersPerUnit = 1\n    timeCodesPerSecond = 48\n    startTimeCode = 1001\n    \
         endTimeCode = 1023\n    subLayers = [@sub.usda@ (offset = 1000)]\n)\n",
    )
    .unwrap();
    let want = pxr_frames(&shot, 1001.0, 1023.0);
    assert_eq!(want.len(), 23);
    for (k, frame) in (1001..=1023).enumerate() {
        let options = coif::io::ImportOptions { frame: Some(frame as f64), ..Default::default() };
        let groom = coif::io::read_groom(&shot, &options).unwrap().groom;
        let got: Vec<f32> = groom.points.iter().flat_map(|p| p.to_array()).collect();
        same_frames(&[got], &want[k..=k], &format!("frame {frame}"));
    }
    let converted = path("converted.usda");
    let run = coif(&["convert", path_str(&shot), path_str(&converted)]);
    assert!(run.status.success(), "{}", stderr(&run));
    same_frames(&pxr_frames(&converted, 1001.0, 1023.0), &want, "the whole shot converted");
    assert!(want.windows(2).filter(|w| w[0] != w[1]).count() >= 10, "the shot barely moves");
}

/// Transform ops count only on xformable prims: authored on a `Scope` or a typeless prim they
/// are no part of any transform, in pxr (coif moved such curves by the ops); on an Xform or a
/// curves prim they are. (Prims named in pxr's traversal order, which the dump sorts by path.)
#[test]
fn transform_ops_on_prims_that_are_not_xformable_are_ignored_as_pxr_ignores_them() {
    let dir = tempfile::tempdir().unwrap();
    let stage = dir.path().join("scoped.usda");
    let ops = |x: f32, y: f32, z: f32| {
        format!(
            "    double3 xformOp:translate = ({x}, {y}, {z})\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n"
        )
    };
    let curves = |name: &str| {
        format!(
            "def BasisCurves \"{name}\"\n{{\n{}    uniform token type = \"linear\"\n    int[] curveVertexCounts = [2]\n    \
             point3f[] points = [(0, 0, 0), (0, -0.1, 0)]\n    float[] widths = [0.001] (interpolation = \"constant\")\n}}\n",
            ops(0.0, 0.0, 0.5)
        )
    };
    std::fs::write(
        &stage,
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n\n\
             def Scope \"A\"\n{{\n{}    def Xform \"X\"\n    {{\n{}{}    }}\n}}\n\n\
             def \"B\"\n{{\n{}{}}}\n\n\
             def Xform \"C\"\n{{\n{}    def Scope \"Inner\"\n    {{\n{}{}    }}\n}}\n",
            ops(1.0, 0.0, 0.0),
            ops(0.0, 2.0, 0.0),
            curves("a"),
            ops(0.0, 0.0, 3.0),
            curves("b"),
            ops(4.0, 0.0, 0.0),
            ops(0.0, 5.0, 0.0),
            curves("c"),
        ),
    )
    .unwrap();
    let want = pxr_frames(&stage, 1.0, 1.0);
    let groom = coif::io::read_groom(&stage, &Default::default()).unwrap().groom;
    let got: Vec<f32> = groom.points.iter().flat_map(|p| p.to_array()).collect();
    same_frames(std::slice::from_ref(&got), &want, "prims with and without transforms");
    // Not vacuous: the xformable prims' ops do move the curves.
    assert!(got.contains(&2.0) && got.contains(&4.0), "{got:?}");
}

/// Value clips (a `clips` dictionary, as Houdini's geometry clip sequences and usdstitchclips
/// write it) animate the points in pxr. coif does not compose them: `info` and `convert` exit 2
/// naming the layer and the prim that authors them, for `.usdc` and `.usda` top layers and
/// through a reference (they read as the rest pose with exit 0). An empty `clips` dictionary
/// and the legacy `clipAssetPaths` keys, which pxr does not play, read as pxr reads them.
#[test]
fn value_clips_are_refused_naming_the_layer_and_prim() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let script = r#"
import os, sys
from pxr import Usd, UsdGeom, Sdf, Vt, Gf
os.chdir(sys.argv[1])
def new(name):
    stage = Usd.Stage.CreateNew(name)
    UsdGeom.SetStageMetersPerUnit(stage, 1)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(3)
    return stage
def curves(stage, shift, time=None):
    UsdGeom.Xform.Define(stage, '/G')
    c = UsdGeom.BasisCurves.Define(stage, '/G/hair')
    c.CreateTypeAttr('linear')
    c.CreateCurveVertexCountsAttr([3])
    points = Vt.Vec3fArray([Gf.Vec3f(shift, -0.1 * k, 0) for k in range(3)])
    c.CreatePointsAttr().Set(points, Usd.TimeCode.Default() if time is None else time)
for frame in (1, 2, 3):
    s = new(f'clip.{frame}.usda'); curves(s, 0.1 * frame, frame); s.Save()
s = new('topology.usda'); curves(s, 0.0); s.Save()
for name in ('shot.usdc', 'shot.usda'):
    top = new(name)
    top.GetRootLayer().subLayerPaths.append('./topology.usda')
    g = top.OverridePrim('/G')
    top.SetDefaultPrim(g)
    clips = Usd.ClipsAPI(g)
    clips.SetClipAssetPaths([Sdf.AssetPath(f'./clip.{f}.usda') for f in (1, 2, 3)])
    clips.SetClipPrimPath('/G')
    clips.SetClipActive([(1, 0), (2, 1), (3, 2)])
    clips.SetClipTimes([(1, 1), (2, 2), (3, 3)])
    clips.SetClipManifestAssetPath(Sdf.AssetPath('./clip.1.usda'))
    top.Save()
shot = new('referencing.usda')
shot.DefinePrim('/Shot').GetReferences().AddReference('./shot.usdc')
shot.Save()
"#;
    run_pxr_script(script, dir.path());
    // pxr plays the clips: the stage moves, so its rest pose is not what it holds at frame 2.
    let x = |file: &str, frame: f64| {
        pxr_dump(&path(file), Some(frame))["curves"][0]["points"][0].as_f64().unwrap()
    };
    for file in ["shot.usdc", "shot.usda", "referencing.usda"] {
        assert!((x(file, 2.0) - 0.2).abs() < 1e-6 && (x(file, 3.0) - 0.3).abs() < 1e-6, "{file}");
    }
    let out = path("out.usda");
    for (file, prim) in [("shot.usdc", "/G"), ("shot.usda", "/G"), ("referencing.usda", "/Shot")] {
        let input = path(file);
        for args in [vec!["info"], vec!["convert", "--frame", "2"]] {
            let mut args = args.clone();
            args.push(path_str(&input));
            if args[0] == "convert" {
                args.push(path_str(&out));
            }
            let run = coif(&args);
            assert_eq!(run.status.code(), Some(2), "{args:?}: {}", stderr(&run));
            let message = stderr(&run);
            assert!(message.contains(&format!("prim <{prim}>: value clips are not supported")), "{message}");
            let layer = if file == "referencing.usda" { "shot.usdc" } else { file };
            assert!(message.contains(layer), "the layer authoring the clips: {message}");
            assert!(!out.exists());
        }
    }
    // No clip set: an empty dictionary, or the legacy keys pxr no longer reads.
    let text = std::fs::read_to_string(path("shot.usda")).unwrap();
    let start = text.find("clips = {").unwrap();
    let end = start + text[start..].find("\n    }\n").unwrap() + "\n    }".len();
    for (name, metadata) in [
        ("empty.usda", "clips = {\n    }"),
        ("legacy.usda", "clipAssetPaths = [@./clip.1.usda@, @./clip.2.usda@]\n    clipPrimPath = \"/G\""),
    ] {
        std::fs::write(path(name), format!("{}{metadata}{}", &text[..start], &text[end..])).unwrap();
        let groom = coif::io::read_groom(
            &path(name),
            &coif::io::ImportOptions { frame: Some(2.0), ..Default::default() },
        )
        .unwrap()
        .groom;
        let dump = pxr_dump(&path(name), Some(2.0));
        assert_eq!(flat(&groom.points), f32s(&dump["curves"][0]["points"]), "{name}");
    }
}
