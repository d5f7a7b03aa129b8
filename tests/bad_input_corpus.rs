//! A corpus of crafted bad inputs run through the `coif` binary: recipe keys out of range (NaN,
//! infinities, negatives, zero), NaN vectors, astronomical work, CLI flags, truncated and
//! bit-flipped `.hair`, `.usda` and `.abc` files, broken meshes and manifests, directories, FIFOs
//! and undecodable text. Every case must exit with its code (2: bad input), name its culprit on
//! stderr (key, flag, file or line), and leave nothing behind: no output, no temporary file.
//! Cases run in parallel threads, each in its own folder; each fails before any real work.
mod common;

use std::path::Path;
use std::process::Command;
use std::sync::Mutex;

use common::{coif, path_str, stderr};

struct Case {
    name: String,
    /// Files written into the case's folder before running (name, bytes).
    files: Vec<(String, Vec<u8>)>,
    args: Vec<String>,
    code: i32,
    /// Substrings stderr must contain.
    names: Vec<String>,
}

fn case(name: &str, files: Vec<(&str, Vec<u8>)>, args: &[&str], code: i32, names: &[&str]) -> Case {
    Case {
        name: name.to_string(),
        files: files.into_iter().map(|(n, b)| (n.to_string(), b)).collect(),
        args: args.iter().map(|a| a.to_string()).collect(),
        code,
        names: names.iter().map(|n| n.to_string()).collect(),
    }
}

/// A minimal valid recipe: one process stage.
const BASE: &str = "[settings]\ndt = 0.0027777778\n\n[[stages]]\nkind = \"process\"\nduration = 0.01\n";

struct Inputs {
    hair: Vec<u8>,
    usda: Vec<u8>,
    abc: Vec<u8>,
}

fn inputs() -> Inputs {
    let dir = tempfile::tempdir().unwrap();
    let hair = dir.path().join("g.hair");
    let made = coif(&["generate", "-o", path_str(&hair), "--strands", "6", "--vertices", "6"]);
    assert!(made.status.success(), "{}", stderr(&made));
    let read = |ext: &str| {
        let out = dir.path().join(format!("g.{ext}"));
        if ext != "hair" {
            let converted = coif(&["convert", path_str(&hair), path_str(&out)]);
            assert!(converted.status.success(), "{}", stderr(&converted));
        }
        std::fs::read(out).unwrap()
    };
    Inputs { hair: read("hair"), usda: read("usda"), abc: read("abc") }
}

fn style_case(name: &str, recipe: &str, hair: &[u8], names: &[&str]) -> Case {
    case(
        name,
        vec![("r.toml", recipe.as_bytes().to_vec()), ("g.hair", hair.to_vec())],
        &["style", "r.toml", "--groom", "g.hair", "-o", "out.usda"],
        2,
        names,
    )
}

fn recipe_cases(hair: &[u8]) -> Vec<Case> {
    let mut cases = Vec::new();
    // (table, key, bad values): every number a plain table holds.
    let keys: &[(&str, &str, &[&str])] = &[
        ("settings", "dt", &["nan", "inf", "-1", "0", "1e-30", "1"]),
        ("settings", "iterations", &["0", "1001", "4000000000"]),
        ("settings", "youngs_modulus", &["nan", "0", "-inf", "1e-30", "1e13"]),
        ("settings", "shear_modulus", &["nan", "-1", "1e-20"]),
        ("settings", "density", &["inf", "0", "1e-30"]),
        ("settings", "cuticle_peel_per_metre", &["nan", "-1", "inf"]),
        ("settings", "max_segment", &["nan", "1e-9", "-0.01", "inf"]),
        ("settings", "damping", &["nan", "-2", "inf"]),
        ("bonds", "hydrogen", &["nan", "-1", "inf"]),
        ("bonds", "peptide", &["nan", "1e9"]),
        ("contacts", "hair_stiffness", &["nan", "-1", "inf", "1e9"]),
        ("contacts", "sample_spacing", &["nan", "0", "1e-30"]),
        ("contacts", "static_friction", &["nan", "-1", "inf"]),
        ("contacts", "dynamic_friction", &["nan", "-0.5", "inf"]),
        ("wetness", "diffusion", &["nan", "-1", "inf"]),
        ("wetness", "evaporation", &["nan", "-1", "inf"]),
        ("wetness", "airflow_drying", &["nan", "-1", "inf"]),
        ("wetness", "mass_gain", &["nan", "-1", "inf"]),
        ("head", "size", &["nan", "0", "-1", "inf", "1e4"]),
        ("guides", "fraction", &["nan", "0", "-0.5", "2"]),
        ("guides", "count", &["0"]),
    ];
    for (table, key, values) in keys {
        for value in *values {
            let recipe =
                format!("[{table}]\n{key} = {value}\n\n[[stages]]\nkind = \"process\"\nduration = 0.01\n");
            cases.push(style_case(
                &format!("[{table}] {key} = {value}"),
                &recipe,
                hair,
                &["r.toml", "line 2", key],
            ));
        }
    }
    // The [head] table's vectors, named with their line: a NaN centre was blamed on the groom's
    // fitted size, 1e30 was accepted, and up [1, 1, 0] with front [2, 2, 0] made a front
    // opposite up.
    for (keys, culprit) in [
        ("center = [nan, 0.0, 0.0]", "line 3: [head] center = [NaN, 0, 0] must have finite components"),
        (
            "center = [1e30, 0, 0]",
            "line 3: [head] center = [1e30, 0, 0] must have finite components in [-1000, 1000]",
        ),
        ("center = [0, -inf, 0]", "line 3: [head] center = [0, -inf, 0]"),
        ("up = [0, 0, 0]", "line 3: [head] up = [0, 0, 0] is not a direction"),
        ("up = [nan, 1, 0]", "line 3: [head] up = [NaN, 1, 0]"),
        ("front = [0, 1e30, 0]", "line 3: [head] front = [0, 1e30, 0]"),
        (
            "up = [1, 1, 0]\nfront = [2, 2, 0]",
            "line 4: [head] front = [2, 2, 0] is parallel to up = [1, 1, 0]",
        ),
    ] {
        let recipe =
            format!("frame = \"head\"\n[head]\n{keys}\n[[stages]]\nkind = \"wet\"\nduration = 0.01\n");
        cases.push(style_case(&format!("[head] {keys}"), &recipe, hair, &["r.toml", culprit]));
    }
    // [guides] with both count and fraction: named with the recipe's line. (With neither, a
    // groom's own guides are used, or the run says the groom has none.)
    let recipe = "[guides]\ncount = 3\nfraction = 0.5\n\n[[stages]]\nkind = \"process\"\nduration = 0.01\n";
    cases.push(style_case(
        "[guides] count and fraction",
        recipe,
        hair,
        &["r.toml", "line 1", "count and fraction"],
    ));
    let recipe = "[guides]\nreach = 0.1\n\n[[stages]]\nkind = \"process\"\nduration = 0.01\n";
    cases.push(style_case(
        "[guides] reach alone, no guides in the groom",
        recipe,
        hair,
        &["g.hair: [guides] gives neither", "no guides of its own"],
    ));
    // Guides that do not fit the groom: the groom's file was not named.
    let recipe = "[guides]\ncount = 2\nreach = 0.001\n\n[[stages]]\nkind = \"process\"\nduration = 0.01\n";
    cases.push(style_case(
        "[guides] reach shorter than the children's distance",
        recipe,
        hair,
        &["g.hair: strand 1: its nearest guide is", "beyond the reach of 0.001 m"],
    ));
    let recipe = "[guides]\ncount = 7\n\n[[stages]]\nkind = \"process\"\nduration = 0.01\n";
    cases.push(style_case(
        "[guides] count above the strands",
        recipe,
        hair,
        &["g.hair: [guides] (or --guides) asks for 7 guides, but the groom has 6 strands"],
    ));
    for value in ["0", "nan", "-1", "1e4"] {
        let recipe = format!(
            "[guides]\ncount = 3\nreach = {value}\n\n[[stages]]\nkind = \"process\"\nduration = 0.01\n"
        );
        cases.push(style_case(
            &format!("[guides] reach = {value}"),
            &recipe,
            hair,
            &["r.toml", "line 3", "reach"],
        ));
    }
    // A rod or head a few micrometres across asked for micrometre segments: the groom was
    // resampled ten-thousandfold without a word and styling ran for hours.
    let wrap = "[[stages]]\nkind = \"wrap\"\nduration = 0.01\n";
    for (label, recipe, culprit) in [
        ("rod 1e-6 m", format!("[[rods]]\nname = \"r\"\na = [0, 0.05, 0.1]\nb = [0.1, 0.05, 0.1]\nradius = 1e-6\n{wrap}"), "rod 'r'"),
        ("[head] size = 1e-5", format!("frame = \"head\"\n[head]\nsize = 1e-5\n{wrap}layout = \"rows\"\ndiameter = 0.24\nspacing = 0.4\n"), "[head] size"),
        // As written: it said "size = 0.000000000000000000000000000001 m" and "the 0.00001 m".
        ("[head] size = 1e-30", format!("frame = \"head\"\n[head]\nsize = 1e-30\n{wrap}layout = \"rows\"\ndiameter = 0.24\nspacing = 0.4\n"), "[head] size = 1e-30 m"),
    ] {
        cases.push(style_case(&format!("resolution for a {label}"), &recipe, hair, &[culprit, "max_segment"]));
    }
    // A layout that could make more rods than a recipe may list: at a spacing of micrometres the
    // spiral's summed angle stopped growing and rows scanned the roots at 10¹⁰ places, for ever.
    // In the head frame the recipe's line is named; in metres the head's size is needed first.
    for (frame, spacing, culprit) in [
        ("head", "2e-5", "line 4: stage 1 (wrap): spacing = 2e-5 head units could lay out 1.26e10 rods"),
        ("head", "0.07", "line 4: stage 1 (wrap): spacing = 0.07 head units could lay out 1080 rods"),
        ("world", "2e-5", "stage 1 (wrap): spacing = 2e-5 m ("),
    ] {
        for layout in ["rows", "spiral"] {
            let recipe = format!(
                "frame = \"{frame}\"\n[settings]\nmax_segment = 0.004\n{wrap}layout = \"{layout}\"\ndiameter = 1e-5\nspacing = {spacing}\n"
            );
            cases.push(style_case(
                &format!("{layout} layout at spacing {spacing} ({frame} frame)"),
                &recipe,
                hair,
                &[culprit, "more than the 1000 a recipe may have", "the spacing must be at least"],
            ));
        }
    }
    let water: &[(&str, &str)] = &[
        ("r_min", "nan"),
        ("r_min", "-1"),
        ("r_min", "0"),
        ("r_max", "nan"),
        ("r_max", "-1"),
        ("r_max", "0"),
        ("r_max", "0.0005"),
        ("hair_pull", "nan"),
        ("hair_pull", "inf"),
        ("droplet_pull", "-1"),
        ("droplet_damping", "nan"),
        ("uptake", "-1"),
    ];
    for (key, value) in water {
        let recipe = format!(
            "[water]\ndroplets = 10\n{key} = {value}\n\n[[stages]]\nkind = \"wet\"\nduration = 0.01\n"
        );
        cases.push(style_case(&format!("[water] {key} = {value}"), &recipe, hair, &["line 3", key]));
    }
    cases.push(style_case(
        "droplets = 1e12",
        "[water]\ndroplets = 1000000000000\n\n[[stages]]\nkind = \"wet\"\nduration = 0.01\n",
        hair,
        &["1000000000000 droplets", "--max-memory"],
    ));
    // Obstacles, rods and stages: vectors with NaN and infinities.
    let tables: &[(&str, &str, &str)] = &[
        (
            "sphere center",
            "[[obstacles]]\nshape = \"sphere\"\nname = \"s\"\ncenter = [nan, 0, 0]\nradius = 0.1\n",
            "center",
        ),
        (
            "sphere center inf",
            "[[obstacles]]\nshape = \"sphere\"\nname = \"s\"\ncenter = [0, inf, 0]\nradius = 0.1\n",
            "center",
        ),
        (
            "sphere radius",
            "[[obstacles]]\nshape = \"sphere\"\nname = \"s\"\ncenter = [0, 0, 0]\nradius = nan\n",
            "radius",
        ),
        ("head center", "[[obstacles]]\nshape = \"head\"\nname = \"h\"\ncenter = [0, 0, -inf]\n", "center"),
        ("head radii", "[[obstacles]]\nshape = \"head\"\nname = \"h\"\nradii = [0.1, nan, 0.1]\n", "radii"),
        (
            "plane point",
            "[[obstacles]]\nshape = \"plane\"\nname = \"p\"\npoint = [nan, 0, 0]\nnormal = [0, 1, 0]\n",
            "point",
        ),
        (
            "plane normal nan",
            "[[obstacles]]\nshape = \"plane\"\nname = \"p\"\npoint = [0, 0, 0]\nnormal = [0, nan, 0]\n",
            "normal",
        ),
        (
            "plane normal inf",
            "[[obstacles]]\nshape = \"plane\"\nname = \"p\"\npoint = [0, 0, 0]\nnormal = [inf, 1, 0]\n",
            "normal",
        ),
        (
            "plane normal zero",
            "[[obstacles]]\nshape = \"plane\"\nname = \"p\"\npoint = [0, 0, 0]\nnormal = [0, 0, 0]\n",
            "normal",
        ),
        (
            "box center",
            "[[obstacles]]\nshape = \"box\"\nname = \"b\"\ncenter = [0, nan, 0]\nhalf_extents = [1, 1, 1]\n",
            "center",
        ),
        (
            "box half_extents",
            "[[obstacles]]\nshape = \"box\"\nname = \"b\"\ncenter = [0, 0, 0]\nhalf_extents = [1, inf, 1]\n",
            "half_extents",
        ),
        ("rod a nan", "[[rods]]\nname = \"r\"\na = [nan, 0, 0]\nb = [1, 0, 0]\nradius = 0.01\n", "rod 'r'"),
        ("rod b inf", "[[rods]]\nname = \"r\"\na = [0, 0, 0]\nb = [inf, 0, 0]\nradius = 0.01\n", "rod 'r'"),
        ("rod radius", "[[rods]]\nname = \"r\"\na = [0, 0, 0]\nb = [1, 0, 0]\nradius = nan\n", "radius"),
        ("gravity", "[settings]\ngravity = [0, nan, 0]\n", "gravity"),
        ("gravity inf", "[settings]\ngravity = [0, -inf, 0]\n", "gravity"),
    ];
    for (name, table, culprit) in tables {
        let recipe = format!("{table}\n[[stages]]\nkind = \"process\"\nduration = 0.01\n");
        cases.push(style_case(name, &recipe, hair, &[culprit]));
    }
    let stages: &[(&str, &str, &str)] = &[
        ("duration 1e9", "kind = \"process\"\nduration = 1e9", "duration"),
        ("duration nan", "kind = \"process\"\nduration = nan", "duration"),
        ("duration -1", "kind = \"process\"\nduration = -1", "duration"),
        ("duration inf", "kind = \"wet\"\nduration = inf", "duration"),
        ("wet amount", "kind = \"wet\"\nduration = 1\namount = nan", "amount"),
        ("mask fraction", "kind = \"wet\"\nduration = 1\nmask = { fraction = nan }", "fraction"),
        ("heat", "kind = \"dry\"\nduration = 1\nheat = -1", "heat"),
        ("heat nan", "kind = \"dry\"\nduration = 1\nheat = nan", "heat"),
        ("dryer position", "kind = \"dry\"\nduration = 1\ndryer = { position = [nan, 0, 0], target = [0, 0, 0], strength = 1 }", "dryer position"),
        ("dryer target", "kind = \"dry\"\nduration = 1\ndryer = { position = [1, 0, 0], target = [0, inf, 0], strength = 1 }", "dryer target"),
        ("dryer strength", "kind = \"dry\"\nduration = 1\ndryer = { position = [1, 0, 0], target = [0, 0, 0], strength = nan }", "dryer strength"),
        ("dryer falloff", "kind = \"dry\"\nduration = 1\ndryer = { position = [1, 0, 0], target = [0, 0, 0], strength = 1, falloff = 0 }", "dryer falloff"),
        ("cone nan", "kind = \"dry\"\nduration = 1\ndryer = { position = [1, 0, 0], target = [0, 0, 0], strength = 1, cone_degrees = nan }", "cone_degrees"),
        ("cone -1", "kind = \"dry\"\nduration = 1\ndryer = { position = [1, 0, 0], target = [0, 0, 0], strength = 1, cone_degrees = -1 }", "cone_degrees"),
        ("cone 400", "kind = \"dry\"\nduration = 1\ndryer = { position = [1, 0, 0], target = [0, 0, 0], strength = 1, cone_degrees = 400 }", "cone_degrees"),
        ("settle max_seconds", "kind = \"settle\"\nmax_seconds = 1e30", "max_seconds"),
        ("settle tolerance", "kind = \"settle\"\ntolerance = nan", "tolerance"),
        ("lotion nan", "kind = \"lotion\"\nduration = 1\nbreak = { ionic = nan }", "ionic"),
        ("layout spacing 1e30", "kind = \"wrap\"\nduration = 1\nlayout = \"rows\"\ndiameter = 0.02\nspacing = 1e30", "spacing = 1e30"),
        ("layout diameter inf", "kind = \"wrap\"\nduration = 1\nlayout = \"spiral\"\ndiameter = inf\nspacing = 0.03", "diameter = inf"),
    ];
    for (name, stage, culprit) in stages {
        let recipe = format!("[[stages]]\n{stage}\n");
        cases.push(style_case(name, &recipe, hair, &["line 1", culprit]));
    }
    let press = "[[obstacles]]\nshape = \"plane\"\nname = \"floor\"\npoint = [0, -1, 0]\nnormal = [0, 1, 0]\n\n[[stages]]\nkind = \"press\"\nduration = 1\nobstacle = \"floor\"\n";
    for (name, extra, culprit) in [
        ("press direction nan", "direction = [0, nan, 0]\n", "direction"),
        ("press direction inf", "direction = [inf, 0, 0]\n", "direction"),
        ("press direction zero", "direction = [0, 0, 0]\n", "direction"),
        ("press travel", "travel = nan\n", "travel"),
    ] {
        cases.push(style_case(name, &format!("{press}{extra}"), hair, &["line 7", culprit]));
    }
    // Astronomical work: refused with the figure, before running.
    cases.push(style_case(
        "50,000 stages",
        &"[[stages]]\nkind = \"process\"\nduration = 0\n".repeat(50_000),
        hair,
        &["50000 stages"],
    ));
    cases.push(style_case(
        "1e5 s at dt 1e-5",
        "[settings]\ndt = 1e-5\n\n[[stages]]\nkind = \"process\"\nduration = 1e5\n",
        hair,
        &["simulation steps", "--max-steps"],
    ));
    // Vectors of more than three numbers in a plain table: read as their first three, exit 0
    // (three million numbers were walked past); a wrap listing one rod a million times made a
    // million obstacles (14 s a step).
    for (name, recipe, culprit) in [
        (
            "gravity of 4",
            format!("[settings]\ngravity = [0, -9.8, 0, 5]\n{}", BASE.replace("[settings]\n", "")),
            "line 2",
        ),
        ("head center of 4", format!("[head]\ncenter = [0, 0, 0, 1]\n{BASE}"), "line 2"),
        (
            "rod end of 4",
            format!(
                "[[rods]]\nname = \"r\"\na = [0, 0.05, 0.1, 4]\nb = [0.1, 0.05, 0.1]\nradius = 0.01\n{BASE}"
            ),
            "line 3",
        ),
    ] {
        cases.push(style_case(
            name,
            &recipe,
            hair,
            &["r.toml", culprit, "invalid length 4, expected an array of 3 numbers"],
        ));
    }
    // Blank names (press obstacle = "" found one), exit 0.
    for (what, table) in [
        ("obstacle", "[[obstacles]]\nshape = \"sphere\"\nname = \"\"\ncenter = [0, 5, 0]\nradius = 0.1\n"),
        ("rod", "[[rods]]\nname = \" \"\na = [0, 5, 0]\nb = [0.1, 5, 0]\nradius = 0.01\n"),
    ] {
        let recipe = format!("{table}{BASE}");
        cases.push(style_case(
            &format!("blank {what} name"),
            &recipe,
            hair,
            &["r.toml", "line 1", "is blank"],
        ));
    }
    let names = vec!["\"r\""; 1000].join(", ");
    let recipe = format!(
        "[[rods]]\nname = \"r\"\na = [0, 0.05, 0.1]\nb = [0.1, 0.05, 0.1]\nradius = 0.01\n\
         [[stages]]\nkind = \"wrap\"\nduration = 0.01\nrods = [{names}]\n"
    );
    cases.push(style_case(
        "a rod listed 1000 times",
        &recipe,
        hair,
        &["r.toml", "line 6", "rods lists 'r' twice (entries 1 and 2)"],
    ));
    // As many names, none a rod's: searched for a repeat among them first, it ran for minutes.
    let names: Vec<String> = (0..300_000).map(|i| format!("\"x{i}\"")).collect();
    let recipe = recipe.replace(&vec!["\"r\""; 1000].join(", "), &names.join(", "));
    cases.push(style_case(
        "300,000 rod names, none a rod's",
        &recipe,
        hair,
        &["r.toml", "no rod named 'x0'"],
    ));
    // Text that is not a recipe.
    cases.push(style_case("not UTF-8", "", hair, &["r.toml", "UTF-8"]));
    cases.last_mut().unwrap().files[0].1 = b"[settings]\ndt = 0.1\n\xff\xfe\n".to_vec();
    cases.push(style_case("binary recipe", "", hair, &["r.toml"]));
    cases.last_mut().unwrap().files[0].1 = hair.to_vec();
    cases.push(style_case("unknown key", &format!("{BASE}\n[bogus]\nx = 1\n"), hair, &["r.toml", "bogus"]));
    cases.push(style_case("wrong type", "[settings]\ndt = \"fast\"\n", hair, &["r.toml", "line 2"]));
    cases.push(style_case("no stages", "[settings]\ndt = 0.001\n", hair, &["r.toml", "stages"]));
    // Thousands of obstacles or rods: each one tested against every vertex at every iteration.
    let spheres: String = (0..1001)
        .map(|i| {
            format!("[[obstacles]]\nname = \"s{i}\"\nshape = \"sphere\"\ncenter = [0, 5, 0]\nradius = 0.01\n")
        })
        .collect();
    let rods: String = (0..1001)
        .map(|i| format!("[[rods]]\nname = \"r{i}\"\na = [0, 5, 0]\nb = [0.1, 5, 0]\nradius = 0.01\n"))
        .collect();
    // A layout's rods count with the listed ones: all are obstacles while the hair is wrapped.
    let listed = &rods[..rods.match_indices("[[rods]]").nth(1000).unwrap().0];
    let layout =
        "[[stages]]\nkind = \"wrap\"\nduration = 0.01\nlayout = \"rows\"\ndiameter = 0.02\nspacing = 0.03\n";
    cases.push(style_case(
        "1000 rods and a layout",
        &format!("{listed}{layout}"),
        hair,
        &["stage 1 (wrap): the Rows layout's", "a recipe may have at most 1000"],
    ));
    for (what, many) in [("obstacles", spheres), ("rods", rods)] {
        cases.push(style_case(
            &format!("1001 {what}"),
            &format!("{many}{BASE}"),
            hair,
            &["r.toml", &format!("1001 {what}; a recipe may have at most 1000")],
        ));
    }
    cases
}

fn mesh_cases(hair: &[u8]) -> Vec<Case> {
    let cube = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n";
    let flat = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 2 3\nf 1 3 4\n";
    let recipe = |extra: &str| {
        format!("[[obstacles]]\nshape = \"mesh\"\nname = \"m\"\npath = \"m.obj\"\n{extra}\n[[stages]]\nkind = \"process\"\nduration = 0.01\n")
    };
    let mesh_case = |name: &str, obj: &str, extra: &str, culprit: &[&str]| {
        let mut c = style_case(name, &recipe(extra), hair, culprit);
        c.files.push(("m.obj".into(), obj.as_bytes().to_vec()));
        c
    };
    vec![
        mesh_case("mesh vertex 1e30", &cube.replace("v 1 0 0", "v 1e30 0 0"), "", &["m.obj", "vertex 2"]),
        mesh_case("mesh vertex nan", &cube.replace("v 1 0 0", "v nan 0 0"), "", &["m.obj", "vertex 2"]),
        mesh_case("mesh resolution 1e-30", cube, "resolution = 1e-30", &["line 1", "resolution"]),
        mesh_case("mesh resolution nan", cube, "resolution = nan", &["line 1", "resolution"]),
        mesh_case("mesh band 1e30", cube, "band = 1e30", &["line 1", "band"]),
        mesh_case("mesh band nan", cube, "band = nan", &["line 1", "band"]),
        mesh_case("mesh face index", &cube.replace("f 2 3 4", "f 2 3 9"), "", &["m.obj"]),
        mesh_case("mesh no faces", "v 0 0 0\n", "", &["m.obj", "no triangles"]),
        // A line tobj cannot read was not named ("position parse error", no line).
        mesh_case("mesh bad number", &cube.replace("v 0 1 0", "v 0 x 0"), "", &["m.obj: line 3 ('v 0 x 0')"]),
        // Triangles without area (all corners on a line, or on a point) were a mesh with no
        // surface, exit 0.
        mesh_case("mesh collinear", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "", &["m.obj", "no area"]),
        mesh_case("mesh one point", "v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\n", "", &["m.obj", "no area"]),
        mesh_case("mesh binary", "\u{0}\u{1}\u{2}garbage", "", &["m.obj"]),
        // An empty path was the recipe's folder: ": No such file or directory", no key named.
        style_case("mesh path empty", &recipe("").replace("m.obj", ""), hair, &["line 1", "path = \"\""]),
        // A scalp without a curved surface near the roots cannot place a head-frame recipe: the
        // refusal names the mesh (it named the groom's file).
        {
            let recipe = format!("frame = \"head\"\n[head]\nscalp = \"m\"\n{}", recipe(""));
            let mut c = style_case("[head] scalp mesh flat", &recipe, hair, &["scalp = \"m\"", "m.obj"]);
            c.files.push(("m.obj".into(), flat.as_bytes().to_vec()));
            c
        },
        {
            let recipe = format!("[[obstacles]]\nname = \"head\"\nshape = \"scalp\"\n{BASE}");
            let mut c = style_case("--scalp flat", &recipe, hair, &["flat.obj:", "scalp mesh"]);
            c.args.extend(["--scalp".into(), "flat.obj".into()]);
            c.files.push(("flat.obj".into(), flat.as_bytes().to_vec()));
            c
        },
        // A world-frame recipe with a scalp of no area: read and collided with, exit 0.
        {
            let mut c = style_case("--scalp collinear", BASE, hair, &["line.obj: the mesh has no area"]);
            c.args.extend(["--scalp".into(), "line.obj".into()]);
            c.files.push(("line.obj".into(), b"v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n".to_vec()));
            c
        },
    ]
}

fn cli_cases(hair: &[u8]) -> Vec<Case> {
    let g = || vec![("g.hair", hair.to_vec())];
    let mut cases = Vec::new();
    let simulate: &[(&[&str], &str)] = &[
        (&["--seconds", "1e9"], "--seconds"),
        (&["--seconds", "nan"], "--seconds"),
        (&["--dt", "1e-30"], "--dt"),
        (&["--dt", "1e-6", "--seconds", "1e5"], "simulation steps"),
        (&["--dt", "nan"], "time step"),
        (&["--settle", "--settle-seconds", "1e30"], "--settle-seconds"),
        (&["--settle", "--settle-tolerance", "nan"], "--settle-tolerance"),
        (&["--settle", "--settle-iterations", "0"], "--settle-iterations"),
        (&["--youngs-modulus", "0"], "--youngs-modulus = 0"),
        (&["--youngs-modulus", "nan"], "--youngs-modulus"),
        (&["--gravity", "nan"], "--gravity"),
        (&["--damping", "inf"], "--damping"),
        (&["--influences", "nan,1,1,1"], "--influences hydrogen"),
        (&["--influences", "1,1,1"], "--influences"),
        (&["--iterations", "0"], "--iterations"),
        (&["--frame", "nan"], "--frame"),
        (&["--frame=-5e9"], "--frame"),
        (&["--units", "0"], "--units"),
    ];
    for (flags, culprit) in simulate {
        let mut args = vec!["simulate", "g.hair", "out.hair"];
        args.extend(flags.iter());
        cases.push(case(&format!("simulate {flags:?}"), g(), &args, 2, &[culprit]));
    }
    // Values the flag's reading used to blur: `--dt 0` without the flag's name, 1e40 shown as the
    // infinity f32 made of it, a one-byte memory limit as "0.000 GB", and two ranges for one
    // field of view (`--fov 0` was told (0, 180), `--fov 175` and `--camera` (0.5, 170)).
    let as_written: &[(&[&str], &[&str])] = &[
        (&["simulate", "g.hair", "out.hair", "--dt", "0"], &["--dt", "'0'"]),
        (&["simulate", "g.hair", "out.hair", "--youngs-modulus", "1e40"], &["--youngs-modulus", "1e40"]),
        (&["simulate", "g.hair", "out.hair", "--max-memory", "1"], &["over the limit of 1 bytes"]),
        // Not "over the budget of 1", nor 0.009999999776482582 s and 4.000e0 steps.
        (&["simulate", "g.hair", "out.hair", "--max-steps", "0"], &["--max-steps", "'0'"]),
        (
            &["simulate", "g.hair", "out.hair", "--seconds", "0.01", "--max-steps", "3"],
            &["for 0.01 s takes 4 simulation steps"],
        ),
        (&["render", "g.hair", "-o", "out.png", "--fov", "0"], &["--fov", "(0.5, 170)"]),
        (&["render", "g.hair", "-o", "out.png", "--fov", "175"], &["--fov", "(0.5, 170)"]),
        (&["render", "g.hair", "-o", "out.png", "--camera", "0,0,1,0,0,0,175"], &["--camera", "(0.5, 170)"]),
    ];
    // A shot's camera of four numbers was read as its first three.
    let shot = b"[camera]\nposition = [0, 0.1, 1.5, 9]\ntarget = [0, 0, 0]\n".to_vec();
    cases.push(case(
        "shot camera position of 4",
        vec![("g.hair", hair.to_vec()), ("s.toml", shot)],
        &["render", "g.hair", "-o", "out.png", "--scene", "s.toml", "--res", "8x8"],
        2,
        &["s.toml", "invalid length 4, expected an array of 3 numbers"],
    ));
    for (args, culprits) in as_written {
        cases.push(case(&format!("{args:?}"), g(), args, 2, culprits));
    }
    let render: &[(&[&str], &str)] = &[
        (&["--exposure", "nan"], "--exposure"),
        (&["--time-budget", "1e30"], "--time-budget"),
        (&["--time-budget", "0"], "--time-budget"),
        (&["--threads", "0"], "--threads"),
        (&["--threads", "100000"], "--threads"),
        (&["--light-intensity=-1"], "--light-intensity"),
        (&["--environment", "nan"], "--environment"),
        (&["--environment=-1"], "--environment"),
        (&["--color=-1,0,0"], "--color"),
        (&["--color", "2,0,0"], "--color"),
        (&["--light-dir", "0,0,0"], "--light-dir"),
        (&["--light-dir", "nan,1,0"], "--light-dir"),
        // A camera a shot may not have: 1e30 m out rendered an empty image, exit 0.
        (
            &["--camera", "1e30,0,0,0,0,0"],
            "--camera '1e30,0,0,0,0,0': position = [1e30, 0, 0] must have finite components in [-1000, 1000]",
        ),
        (&["--camera", "0,1,1,0,0,-2000"], "target = [0, 0, -2000]"),
        // A false-colour range that is none, or given with nothing to colour: ignored, exit 0.
        (&["--range", "nan,1"], "--range"),
        (&["--range", "1,0", "--attribute", "wetness", "--mode", "depth"], "--range '1,0'"),
        (&["--fov", "0"], "--fov"),
        (&["--width-scale", "nan"], "--width-scale"),
        (&["--spp", "0"], "--spp"),
        // 2.7e14 camera samples, years of a node, with no time budget to stop it.
        (&["--res", "16384x16384", "--spp", "1000000"], "--time-budget"),
    ];
    for (flags, culprit) in render {
        let mut args = vec!["render", "g.hair", "-o", "out.png"];
        args.extend(flags.iter());
        cases.push(case(&format!("render {flags:?}"), g(), &args, 2, &[culprit]));
    }
    let generate: &[(&[&str], &str)] = &[
        (&["--width", "1e30"], "--width"),
        (&["--width=-1e-5"], "--width"),
        (&["--style", "curly", "--curl-radius", "1e30"], "--curl-radius"),
        (&["--style", "curly", "--curl-pitch", "nan"], "--curl-pitch"),
        (&["--style", "wavy", "--wave-amplitude", "1e30"], "--wave-amplitude"),
        (&["--style", "wavy", "--wavelength", "0"], "--wavelength"),
        (&["--droop", "1e30"], "--droop"),
        // Shorter than a tenth of a millimetre: it blamed a zero-length segment of its own groom.
        (&["--length", "1e-9"], "--length"),
        (&["--length", "0"], "--length"),
    ];
    for (flags, culprit) in generate {
        let mut args = vec!["generate", "-o", "out.hair", "--strands", "5"];
        args.extend(flags.iter());
        cases.push(case(&format!("generate {flags:?}"), vec![], &args, 2, &[culprit]));
    }
    cases.push(case(
        "generate 5e7 x 1e4",
        vec![],
        &["generate", "-o", "out.hair", "--strands", "50000000", "--vertices", "10000"],
        2,
        &["--strands 50000000", "--max-memory"],
    ));
    cases.push(case(
        "max-memory",
        g(),
        &["convert", "g.hair", "out.usda", "--max-memory", "lots"],
        2,
        &["--max-memory"],
    ));
    cases.push(case("info --frame nan", g(), &["info", "g.hair", "--frame", "nan"], 2, &["--frame"]));
    // A group the groom does not have: the groom file is named, with the groups it has (a .hair
    // file has none: it read "its groups are ''").
    let one_prim = "#usda 1.0\ndef BasisCurves \"tuft\" {\n  uniform token type = \"linear\"\n  \
                    int[] curveVertexCounts = [2]\n  point3f[] points = [(0, 0, 0), (0, 1, 0)]\n}\n";
    for (groom, bytes, names) in [
        ("g.hair", hair.to_vec(), &["g.hair", "no named groups for --group 'x'"][..]),
        ("g.usda", one_prim.as_bytes().to_vec(), &["g.usda", "no group named 'x'", "'/tuft'"]),
    ] {
        cases.push(case(
            &format!("style --group x of {groom}"),
            vec![("r.toml", BASE.as_bytes().to_vec()), (groom, bytes)],
            &["style", "r.toml", "--groom", groom, "--group", "x", "-o", "out.usda"],
            2,
            names,
        ));
    }
    // An empty group name (`--group "$GROUP"`, the variable unset) matched a .hair file's one
    // unnamed group and styled every strand, exit 0.
    cases.push(case(
        "style --group \"\" of g.hair",
        vec![("r.toml", BASE.as_bytes().to_vec()), ("g.hair", hair.to_vec())],
        &["style", "r.toml", "--groom", "g.hair", "--group", "", "-o", "out.usda"],
        2,
        &["--group \"\"", "never empty"],
    ));
    cases
}

/// Truncations, header bit flips and wrong types of each groom format, read by `convert`.
fn file_cases(inputs: &Inputs) -> Vec<Case> {
    let mut cases = Vec::new();
    let convert = |name: String, file: &str, bytes: Vec<u8>, names: &[&str]| {
        case(&name, vec![(file, bytes)], &["convert", file, "out.usda"], 2, names)
    };
    let hair = &inputs.hair;
    for cut in [0, 3, 4, 40, 127, 128, 129, 200, hair.len() / 2, hair.len() - 1] {
        cases.push(convert(format!(".hair cut at {cut}"), "in.hair", hair[..cut].to_vec(), &["in.hair"]));
    }
    let with_u32 = |offset: usize, value: u32| {
        let mut bytes = hair.clone();
        bytes[offset..offset + 4].copy_from_slice(&value.to_le_bytes());
        bytes
    };
    for (name, bytes) in [
        ("strands 0xffffffff", with_u32(4, u32::MAX)),
        ("strands 0", with_u32(4, 0)),
        ("points 0xffffffff", with_u32(8, u32::MAX)),
        ("points 0", with_u32(8, 0)),
        ("unknown flags", with_u32(12, 0xff00)),
        ("no points flag", with_u32(12, 0)),
        ("bad signature", with_u32(0, 0x52494148 ^ 1)),
    ] {
        cases.push(convert(format!(".hair {name}"), "in.hair", bytes, &["in.hair"]));
    }
    let mut nan_point = hair.clone();
    let first_point =
        128 + if u32::from_le_bytes(hair[12..16].try_into().unwrap()) & 1 != 0 { 12 } else { 0 };
    nan_point[first_point..first_point + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    // A point 1e37 m out is a float, but not in Unreal's centimetres: it was written as infinity.
    let mut far_point = hair.clone();
    far_point[first_point..first_point + 4].copy_from_slice(&1e37f32.to_le_bytes());
    cases.push(case(
        ".hair 1e37 m → --unreal .abc",
        vec![("in.hair", far_point)],
        &["convert", "in.hair", "out.abc", "--unreal"],
        2,
        &["strand 0, vertex 0", "1e37", "centimetres"],
    ));
    cases.push(convert(".hair NaN point".into(), "in.hair", nan_point, &["in.hair", "strand 0"]));
    cases.push(convert(".hair is text".into(), "in.hair", b"HAIR but not really".to_vec(), &["in.hair"]));

    // A bad curve in the second of two prims: the groom's strand index counts across both, so the
    // message also names the prim and the curve's index in it.
    let two_prims = |counts: &str, b_points: &str| {
        format!(
            "#usda 1.0\ndef Xform \"groom\"\n{{\n    def BasisCurves \"a\"\n    {{\n        uniform token type = \"linear\"\n        \
             int[] curveVertexCounts = [3, 3]\n        point3f[] points = [(0,0,0),(0,0.1,0),(0,0.2,0),(1,0,0),(1,0.1,0),(1,0.2,0)]\n    }}\n    \
             def BasisCurves \"b\"\n    {{\n        uniform token type = \"linear\"\n        int[] curveVertexCounts = {counts}\n        \
             point3f[] points = {b_points}\n    }}\n}}\n"
        )
        .into_bytes()
    };
    let b_points = "[(0,0,0),(0,0.1,0),(0,0.2,0),(1,0,0),(1,0.1,0),(1,0.2,0)]";
    cases.push(convert(
        ".usda one-point curve in the second prim".into(),
        "in.usda",
        two_prims("[3, 1, 2]", b_points),
        &["in.usda", "strand 3 has 1 vertices", "curve 1 of </groom/b>"],
    ));
    cases.push(convert(
        ".usda NaN in the second prim".into(),
        "in.usda",
        two_prims("[3, 3]", &b_points.replace("(1,0.1,0)", "(1,nan,0)")),
        &["in.usda", "strand 3, vertex 1", "curve 1 of </groom/b>"],
    ));

    // A `uint64` is 0 to 2^64 − 1, as pxr reads it: `-1` was read as 2^64 − 1 (pxr refuses the
    // layer), in an array and alone.
    for (name, declaration) in [
        ("array", "uint64[] primvars:n = [-1, 2]"),
        ("value", "uint64 m = -1\n    uint64[] primvars:n = [1, 2]"),
    ] {
        let text = two_curves("", &format!("{declaration} (interpolation = \"uniform\")"));
        cases.push(convert(
            format!(".usda uint64 -1 {name}"),
            "in.usda",
            text.into_bytes(),
            &["in.usda", "'-1'"],
        ));
    }
    // A negative width was shown in metres without a unit (-0.000040000003, from -0.004 cm).
    let width = two_curves(
        "(\n    metersPerUnit = 0.01\n)\n",
        "float[] widths = [0.008, 0.008, -0.004, 0.008] (interpolation = \"vertex\")",
    );
    cases.push(convert(
        ".usda negative width in centimetres".into(),
        "in.usda",
        width.as_bytes().to_vec(),
        &["in.usda", "strand 1, vertex 0: width -4", "e-5 m (the file's units converted to metres)"],
    ));
    // A NaN root UV (`st`, per curve) was read and written on into every output, exit 0.
    let uv = two_curves("", "texCoord2f[] primvars:st = [(0, 0), (nan, 0)] (interpolation = \"uniform\")");
    cases.push(convert(
        ".usda NaN root UV".into(),
        "in.usda",
        uv.as_bytes().to_vec(),
        &["in.usda", "root UV of strand 1"],
    ));
    // Guide ids as floats that no int32 holds: Alembic got 2147483647 for 1e30 and 0 for 0.5.
    for (ids, culprit) in [
        ("(1, 2, 3), (1e30, 0, 0)", "strand 1: 1000000000000000000000000000000 is not"),
        ("(0.5, 0, 0), (1, 0, 0)", "strand 0: 0.5 is not"),
    ] {
        let text = two_curves(
            "",
            &format!("float3[] primvars:groom_closest_guides = [{ids}] (interpolation = \"uniform\")"),
        );
        cases.push(case(
            &format!("groom_closest_guides [{ids}] to .abc"),
            vec![("in.usda", text.into_bytes())],
            &["convert", "in.usda", "out.abc", "--unreal"],
            2,
            &["in.usda", "groom_closest_guides", culprit],
        ));
    }
    let usda = &inputs.usda;
    for cut in [9, usda.len() / 4, usda.len() / 2, usda.len() * 3 / 4, usda.len() - 3] {
        cases.push(convert(format!(".usda cut at {cut}"), "in.usda", usda[..cut].to_vec(), &["in.usda"]));
    }
    let text = String::from_utf8(usda.clone()).unwrap();
    for (name, bad) in [
        ("points nan", text.replacen("points = [(", "points = [(nan, ", 1)),
        ("counts negative", text.replacen("curveVertexCounts = [", "curveVertexCounts = [-6, ", 1)),
        ("deep prims", format!("#usda 1.0\n{}", "def Xform \"a\" {\n".repeat(20_000))),
        (
            "deep closed prims",
            format!("#usda 1.0\n{}{}", "def \"a\" {\n".repeat(20_000), "}\n".repeat(20_000)),
        ),
        ("deep values", format!("#usda 1.0\ndef \"a\" (\n x = {}\n)\n{{}}\n", "[".repeat(20_000))),
        ("unclosed", "#usda 1.0\ndef BasisCurves \"c\" {\n".to_string()),
        ("garbage", "#usda 1.0\n@@@\n".to_string()),
    ] {
        cases.push(convert(format!(".usda {name}"), "in.usda", bad.into_bytes(), &["in.usda", "line"]));
    }
    // Cubic curves too short for one segment of their basis are not valid USD: refused where they
    // are read (they were read, and refused only when writing a .usda, naming the output).
    let cubic = |basis: &str, counts: &str, points: usize| {
        let points = vec!["(0, 0, 0)"; points].join(", ");
        format!(
            "#usda 1.0\n(\n    metersPerUnit = 1\n)\ndef BasisCurves \"c\"\n{{\n    uniform token type = \"cubic\"\n    \
             uniform token basis = \"{basis}\"\n    int[] curveVertexCounts = [{counts}]\n    \
             point3f[] points = [{points}]\n}}\n"
        )
    };
    for (name, bad, culprit) in [
        ("3-point B-spline", cubic("bspline", "4, 3", 7), "curve 1 has 3 control points"),
        ("5-point Bézier", cubic("bezier", "5", 5), "curve 0 has 5 control points"),
        ("2-point Catmull-Rom", cubic("catmullRom", "2", 2), "curve 0 has 2 control points"),
    ] {
        cases.push(convert(
            format!(".usda {name}"),
            "in.usda",
            bad.into_bytes(),
            &["in.usda", "line 9", culprit],
        ));
    }
    cases.push(convert(".usda not UTF-8".into(), "in.usda", b"#usda 1.0\n\xff\xfe".to_vec(), &["in.usda"]));

    let abc = &inputs.abc;
    for cut in [0, 8, 16, 32, abc.len() / 4, abc.len() / 2, abc.len() - 8, abc.len() - 1] {
        cases.push(convert(format!(".abc cut at {cut}"), "in.abc", abc[..cut].to_vec(), &["in.abc"]));
    }
    for (name, offset) in [("magic", 0usize), ("version", 5), ("root offset", 8), ("root offset high", 15)] {
        let mut bytes = abc.clone();
        bytes[offset] ^= 0xff;
        cases.push(convert(format!(".abc flip {name}"), "in.abc", bytes, &["in.abc"]));
    }
    cases.push(case(
        ".abc frame before the first sample",
        vec![("in.abc", std::fs::read("tests/data/blender_groom_anim.abc").unwrap())],
        &["convert", "in.abc", "out.usda", "--frame", "0"],
        2,
        &["in.abc", "frame 0", "(frame 1"],
    ));
    let anim = || vec![("in.abc", std::fs::read("tests/data/blender_groom_anim.abc").unwrap())];
    for (name, args, names) in [
        ("reversed", &["--frame-range", "5:1"][..], &["--frame-range", "5:1", "after the last"][..]),
        ("NaN", &["--frame-range", "nan:3"], &["--frame-range", "nan"]),
        ("infinite", &["--frame-range", "1:inf"], &["--frame-range", "inf"]),
        ("huge", &["--frame-range", "1:1e8"], &["--frame-range", "more than"]),
        // Written out in 301 digits.
        ("astronomical", &["--frame-range", "1:1e300"], &["--frame-range '1:1e300': frame 1e300 is outside"]),
        ("not a range", &["--frame-range", "12"], &["--frame-range", "FIRST:LAST"]),
        ("before the first sample", &["--frame-range", "0:3"], &["in.abc", "frame 0"]),
        ("with --frame", &["--frame-range", "1:3", "--frame", "2"], &["--frame"]),
    ] {
        cases.push(case(
            &format!(".abc --frame-range {name}"),
            anim(),
            &[&["convert", "in.abc", "out.usda"], args].concat(),
            2,
            names,
        ));
    }
    cases.push(case(
        ".abc --frame-range to .hair",
        anim(),
        &["convert", "in.abc", "out.hair", "--frame-range", "1:3"],
        2,
        &["out.hair", "time samples"],
    ));
    for (name, mesh, names) in [
        ("index out of range", "[0, 1, 9]", &["index 2 is 9"][..]),
        ("negative index", "[0, 1, -1]", &["negative"][..]),
        ("face of 2", "[0, 1]", &["face 0 has 2"][..]),
    ] {
        let counts = if name == "face of 2" { "[2]" } else { "[3]" };
        let text = usda_with_mesh(counts, mesh, "(0, 0, 0), (1, 0, 0), (0, 1, 0)");
        cases.push(convert(
            format!(".usda mesh {name}"),
            "in.usda",
            text.into_bytes(),
            &[&["in.usda", "/head"], names].concat(),
        ));
    }
    let nan = usda_with_mesh("[3]", "[0, 1, 2]", "(0, 0, 0), (nan, 0, 0), (0, 1, 0)");
    cases.push(convert(
        ".usda mesh NaN point".into(),
        "in.usda",
        nan.into_bytes(),
        &["in.usda", "/head", "point 1"],
    ));
    let huge = usda_with_mesh("[2000000000, 3]", "[0, 1, 2]", "(0, 0, 0), (1, 0, 0), (0, 1, 0)");
    cases.push(convert(
        ".usda mesh huge count".into(),
        "in.usda",
        huge.into_bytes(),
        &["in.usda", "/head", "2000000003"],
    ));
    for (name, bytes, names) in blender_abc_mesh_cases() {
        cases.push(convert(
            format!(".abc mesh {name}"),
            "in.abc",
            bytes,
            &[&["in.abc", "/Head/HeadMesh"], names].concat(),
        ));
    }
    cases.push(case(
        ".usda frame outside",
        vec![("in.usda", animated_usda().into_bytes())],
        &["convert", "in.usda", "out.hair", "--frame", "0"],
        2,
        &["in.usda", "frame 0"],
    ));
    // Strands that change between samples: the input is named (the output was, which was never
    // read), with the frame and the way out.
    let varying = animated_usda()
        .replacen("    2: [(0, 0, 0), (0, 2, 0)],", "    2: [(0, 0, 0), (0, 2, 0), (1, 0, 0)],", 1)
        .replacen(
            "  int[] curveVertexCounts = [2]\n",
            "  int[] curveVertexCounts.timeSamples = {\n    1: [2],\n    2: [3],\n  }\n",
            1,
        )
        .replacen("#usda 1.0\n", "#usda 1.0\n(\n startTimeCode = 1\n endTimeCode = 2\n)\n", 1);
    for out in ["out.usda", "out.abc"] {
        cases.push(case(
            &format!(".usda strands that change between frames → {out}"),
            vec![("in.usda", varying.clone().into_bytes())],
            &["convert", "in.usda", out],
            2,
            &["in.usda: frame 2 has other strands than frame 1", "--frame N"],
        ));
    }
    // A rest shape no turn has (a rest_darboux is the vector part of a unit quaternion): 1e30
    // overflowed the rods and was blamed on the output's coordinates.
    for value in ["1e30", "2"] {
        let text = format!(
            "#usda 1.0\ndef BasisCurves \"c\" {{\n  uniform token type = \"linear\"\n  int[] curveVertexCounts = [3, 3]\n  \
             point3f[] points = [(0, 0.1, 0), (0, 0.09, 0), (0, 0.08, 0), (0.01, 0.1, 0), (0.01, 0.09, 0), (0.01, 0.08, 0)]\n  \
             float3[] primvars:rest_darboux = [(0, 0, 0), (0, 0, 0), (0, 0, 0), (0, 0, 0), ({value}, 0, 0), (0, 0, 0)] (interpolation = \"vertex\")\n}}\n"
        );
        cases.push(case(
            &format!("rest_darboux {value}"),
            vec![("in.usda", text.into_bytes())],
            &["simulate", "in.usda", "out.usda", "--seconds", "0.01"],
            2,
            &["in.usda", "rest_darboux", "vertex 4", "at most 1"],
        ));
    }
    // Output over an input: the run replaced what it read.
    let style_files = || vec![("r.toml", BASE.as_bytes().to_vec()), ("g.hair", inputs.hair.clone())];
    for (args, culprit) in [
        (&["style", "r.toml", "--groom", "g.hair", "-o", "g.hair"][..], "--groom"),
        (&["style", "r.toml", "--groom", "g.hair", "-o", "./r.toml"], "the recipe"),
        (&["simulate", "g.hair", "./g.hair", "--seconds", "0.01"], "the input"),
    ] {
        cases.push(case(
            &format!("output is an input: {}", args.join(" ")),
            style_files(),
            args,
            2,
            &[culprit, "another file"],
        ));
    }
    // Files the run reads that only show once the groom is read: a layer the stage composes (the
    // layer was replaced by the whole groom), and the meshes file `--unreal` writes beside the
    // output (the input was replaced by its meshes).
    let layered = || {
        let root = "#usda 1.0\n(\n    subLayers = [@part.usda@]\n)\n".as_bytes().to_vec();
        vec![("in.usda", root), ("part.usda", inputs.usda.clone())]
    };
    for args in
        [&["convert", "in.usda", "part.usda"][..], &["simulate", "in.usda", "part.usda", "--seconds", "0.01"]]
    {
        cases.push(case(
            &format!("output is a composed layer: {}", args.join(" ")),
            layered(),
            args,
            2,
            &["part.usda", "a layer the groom's stage composes", "another file"],
        ));
    }
    let houdini =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/houdini_groom.usda")).unwrap();
    cases.push(case(
        "--unreal meshes over the input",
        vec![("g_meshes.usda", houdini.clone())],
        &["convert", "--unreal", "g_meshes.usda", "g.usda"],
        2,
        &["g_meshes.usda", "the groom it reads", "another file"],
    ));
    cases.push(case(
        "convert over its input",
        vec![("g.usda", houdini)],
        &["convert", "g.usda", "./g.usda"],
        2,
        &["g.usda", "the groom it reads", "another file"],
    ));
    // Fractions outside [0, 1] were clamped without a word (a wetness of -5, a rate of 1e30).
    for (name, value) in [("wetness", "-5"), ("bond_ionic", "-100"), ("bond_hydrogen", "1e30")] {
        let text = format!(
            "#usda 1.0\ndef BasisCurves \"c\" {{\n  uniform token type = \"linear\"\n  int[] curveVertexCounts = [3, 3]\n  \
             point3f[] points = [(0, 0.1, 0), (0, 0.09, 0), (0, 0.08, 0), (0.01, 0.1, 0), (0.01, 0.09, 0), (0.01, 0.08, 0)]\n  \
             float[] primvars:{name} = [0, 0, 0, 0, {value}, 0] (interpolation = \"vertex\")\n}}\n"
        );
        let runs: [&[&str]; 2] = [
            &["simulate", "in.usda", "out.usda", "--seconds", "0.01"],
            &["style", "r.toml", "--groom", "in.usda", "-o", "out.usda"],
        ];
        for args in runs {
            cases.push(case(
                &format!("{name} {value}: {}", args[0]),
                vec![("in.usda", text.clone().into_bytes()), ("r.toml", BASE.as_bytes().to_vec())],
                args,
                2,
                &["in.usda", name, "strand 1, vertex 1", value, "[0, 1]"],
            ));
        }
    }
    // Roots no head can be fitted to, for a recipe in the head frame: the groom's file is named.
    let in_a_line = "#usda 1.0\ndef BasisCurves \"c\" {\n  uniform token type = \"linear\"\n  int[] curveVertexCounts = [2, 2, 2]\n  \
         point3f[] points = [(0, 0, 0), (0, -0.1, 0), (0.01, 0, 0), (0.01, -0.1, 0), (0.02, 0, 0), (0.02, -0.1, 0)]\n}\n";
    let in_head_frame = format!("frame = \"head\"\n{BASE}");
    cases.push(case(
        "head frame on roots in a line",
        vec![("in.usda", in_a_line.as_bytes().to_vec()), ("r.toml", in_head_frame.into_bytes())],
        &["style", "r.toml", "--groom", "in.usda", "-o", "out.usda"],
        2,
        &["in.usda", "head frame", "[head] table"],
    ));
    // A file's own range runs on without bound (`endTimeCode = 1e15` ran for ever writing frames):
    // refused before anything is written, whatever the output.
    // Its frame count and rate are written as numbers are: 1e300 frames were counted as
    // 18446744073709551615, a rate of 1e-300 printed in 300 digits.
    for (start, end, names) in [
        ("1", "1e15", &["1e15"][..]),
        ("-1e9", "2", &["-1e9"]),
        ("1", "1e300\n timeCodesPerSecond = 1e-300", &["to 1e300 (1e300 frames at 1e-300 fps)"]),
    ] {
        let text = animated_usda().replacen(
            "#usda 1.0\n",
            &format!("#usda 1.0\n(\n startTimeCode = {start}\n endTimeCode = {end}\n)\n"),
            1,
        );
        for out in ["out.abc", "out.usda"] {
            cases.push(case(
                &format!(".usda timeline {start} to {end} → {out}"),
                vec![("in.usda", text.clone().into_bytes())],
                &["convert", "in.usda", out],
                2,
                &[&["in.usda", "--frame-range"], names].concat(),
            ));
        }
    }
    // Widths of metres (1e30 m once went through every stage) and coordinates a kilometre and
    // more out (1e30 m overflowed the rods within a step, and `simulate` then refused its own
    // result naming no file): a file in another unit. Refused where the strands become rods,
    // naming the file's strand even when only guides are simulated. Strand 2's vertex 1 is bad.
    let mut unsimulable = Vec::new();
    for width in ["1", "1e30"] {
        unsimulable.push((format!("width {width} m"), "0".to_string(), width.to_string(), "too wide"));
    }
    // Widths of 0.1 µm and less (a millimetre file read as metres): mass and stiffness beyond
    // f32, and the rods overflowed; the output was then refused as "coordinate is not finite".
    for width in ["1e-7", "1e-45"] {
        unsimulable.push((format!("width {width} m"), "0".to_string(), width.to_string(), "too thin"));
    }
    for far in ["2000", "-1e6", "1e30"] {
        unsimulable.push((
            format!("coordinate {far} m"),
            far.to_string(),
            "1e-4".into(),
            "1000 m from the origin",
        ));
    }
    // A file's own guide bindings that cannot be used are refused naming the file (they named
    // only the strand).
    for (label, closest, weights, expected) in [
        ("weights sum to 0.5", "(0, 0, 0)", "(0.5, 0, 0)", "sum to 0.5"),
        ("a binding names a missing guide", "(7, 7, 7)", "(1, 0, 0)", "groom_id 7"),
        // It read "strand 1 (strand 1)".
        (
            "a weight is NaN",
            "(0, 0, 0)",
            "(nan, 0, 0)",
            "'groom_guide_weights': strand 1 has a non-finite value NaN",
        ),
        ("a weight is negative", "(0, 0, 0)", "(1.5, -0.5, 0)", "groom_guide_weights has weight -0.5"),
        // Strand 1 is a child (groom_guide 0): no guide has its id.
        (
            "a binding names a child",
            "(1, 0, 0)",
            "(1, 0, 0)",
            "groom_id 1 with weight 1, but none of the groom's 1 guides",
        ),
    ] {
        let text = format!(
            "#usda 1.0\n(\n  metersPerUnit = 1\n)\ndef BasisCurves \"c\" {{\n  uniform token type = \"linear\"\n  int[] curveVertexCounts = [2, 2, 2]\n  \
             point3f[] points = [(0, 0, 0), (0, 0.1, 0), (0.01, 0, 0), (0.01, 0.1, 0), (0.02, 0, 0), (0.02, 0.1, 0)]\n  \
             int[] primvars:groom_guide = [1, 0, 0] (interpolation = \"uniform\")\n  \
             float3[] primvars:groom_closest_guides = [(0, 0, 0), {closest}, (0, 0, 0)] (interpolation = \"uniform\")\n  \
             float3[] primvars:groom_guide_weights = [(1, 0, 0), {weights}, (1, 0, 0)] (interpolation = \"uniform\")\n}}\n"
        );
        cases.push(case(
            &format!("bindings: {label}"),
            vec![("in.usda", text.into_bytes()), ("r.toml", BASE.as_bytes().to_vec())],
            &["style", "r.toml", "--groom", "in.usda", "-o", "out.usda"],
            2,
            &["in.usda:", "strand 1", expected],
        ));
    }
    cases.push(case(
        "--guides 0",
        vec![("g.hair", inputs.hair.clone()), ("r.toml", BASE.as_bytes().to_vec())],
        &["style", "r.toml", "--groom", "g.hair", "--guides", "0", "-o", "out.usda"],
        2,
        &["--guides = 0", "[1, 1e9]"],
    ));
    for (label, last_z, last_width, expected) in unsimulable {
        let text = format!(
            "#usda 1.0\n(\n  metersPerUnit = 1\n)\ndef BasisCurves \"c\" {{\n  uniform token type = \"linear\"\n  int[] curveVertexCounts = [2, 2, 2]\n  \
             point3f[] points = [(0, 0, 0), (0, 0.1, 0), (0.01, 0, 0), (0.01, 0.1, 0), (0.02, 0, 0), (0.02, 0.1, {last_z})]\n  \
             float[] widths = [1e-4, 1e-4, 1e-4, 1e-4, 1e-4, {last_width}] (interpolation = \"vertex\")\n}}\n"
        );
        let runs: [&[&str]; 3] = [
            &["simulate", "in.usda", "out.usda", "--seconds", "0.01"],
            &["style", "r.toml", "--groom", "in.usda", "-o", "out.usda"],
            &["style", "r.toml", "--groom", "in.usda", "--guides", "2", "-o", "out.usda"],
        ];
        for args in runs {
            cases.push(case(
                &format!("{label}: {}", args.join(" ")),
                vec![("in.usda", text.clone().into_bytes()), ("r.toml", BASE.as_bytes().to_vec())],
                args,
                2,
                &["in.usda", "strand 2, vertex 1", expected],
            ));
        }
    }
    cases
}

/// A curves prim beside a `Mesh` prim `/head` with the given topology and points.
fn usda_with_mesh(counts: &str, indices: &str, points: &str) -> String {
    format!(
        "#usda 1.0\ndef BasisCurves \"c\" {{\n  uniform token type = \"linear\"\n  int[] curveVertexCounts = [2]\n  \
         point3f[] points = [(0, 0, 0), (0, 1, 0)]\n}}\ndef Mesh \"head\" {{\n  int[] faceVertexCounts = {counts}\n  \
         int[] faceVertexIndices = {indices}\n  point3f[] points = [{points}]\n}}\n"
    )
}

/// Blender's Alembic groom with its head mesh broken: a face index out of range.
/// The arrays are found by their bytes (Alembic stores faces clockwise: coif's reversed).
fn blender_abc_mesh_cases() -> Vec<(&'static str, Vec<u8>, &'static [&'static str])> {
    let path = Path::new("tests/data/blender_groom.abc");
    let bytes = std::fs::read(path).unwrap();
    let groom = coif::io::read_groom(path, &Default::default()).unwrap().groom;
    let mesh = &groom.meshes[0];
    let mut file_order: Vec<u32> = Vec::new();
    let mut at = 0;
    for &count in &mesh.face_counts {
        file_order.extend(mesh.face_indices[at..at + count as usize].iter().rev());
        at += count as usize;
    }
    let indices: Vec<u8> = file_order.iter().flat_map(|&i| (i as i32).to_le_bytes()).collect();
    let find = |needle: &[u8]| {
        bytes.windows(needle.len()).position(|w| w == needle).expect("the face indices are in the file")
    };
    let mut out_of_range = bytes.clone();
    let start = find(&indices);
    out_of_range[start + 4..start + 8].copy_from_slice(&100_000i32.to_le_bytes());
    vec![("index out of range", out_of_range, &["100000"][..])]
}

/// A two-sample animated curves layer (time codes 1 and 2).
fn animated_usda() -> String {
    "#usda 1.0\ndef BasisCurves \"c\" {\n  uniform token type = \"linear\"\n  int[] curveVertexCounts = [2]\n  \
     point3f[] points.timeSamples = {\n    1: [(0, 0, 0), (0, 1, 0)],\n    2: [(0, 0, 0), (0, 2, 0)],\n  }\n}\n"
        .to_string()
}

fn manifest_cases(hair: &[u8]) -> Vec<Case> {
    let files = |manifest: &str| {
        vec![
            ("m.toml", manifest.as_bytes().to_vec()),
            ("r.toml", BASE.as_bytes().to_vec()),
            ("g.hair", hair.to_vec()),
        ]
    };
    let head = "[defaults]\ngroom = \"g.hair\"\nrecipe = \"r.toml\"\noutputs = [\"out/{name}.usda\"]\n\n";
    let mut cases = Vec::new();
    for name in ["..", "../../escape", "a/../../b", "a/b", ".", ""] {
        let manifest = format!("{head}[[tasks]]\nname = \"{name}\"\n");
        cases.push(case(
            &format!("task name {name:?}"),
            files(&manifest),
            &["farm", "status", "m.toml"],
            2,
            &["m.toml", "line 6"],
        ));
        let wedge = format!(
            "{head}[[wedges]]\nname = \"{name}\"\nparameters = {{ \"settings.damping\" = [1.0, 2.0] }}\n"
        );
        cases.push(case(
            &format!("wedge name {name:?}"),
            files(&wedge),
            &["farm", "status", "m.toml"],
            2,
            &["m.toml", "line 6"],
        ));
    }
    // A placeholder coif does not know was written as it stands: every task of the batch wrote
    // into one folder named `{foo}` (and the later ones skipped as complete), exit 0.
    for (template, shown) in [("out/{foo}/g.usda", "'{foo}'"), ("out/{name.usda", "'{name.usda'")] {
        let manifest = format!(
            "[defaults]\ngroom = \"g.hair\"\nrecipe = \"r.toml\"\noutputs = [\"{template}\"]\n\n[[tasks]]\nname = \"t\"\n"
        );
        cases.push(case(
            &format!("output template {template}"),
            files(&manifest),
            &["batch", "m.toml"],
            2,
            &["m.toml", "line 6", shown, "{name}, {index}, {groom}, {recipe}"],
        ));
    }
    // `--jobs 0` ran the batch one task at a time without a word.
    cases.push(case(
        "batch --jobs 0",
        files(&format!("{head}[[tasks]]\nname = \"t\"\n")),
        &["batch", "m.toml", "--jobs", "0"],
        2,
        &["--jobs 0"],
    ));
    cases.push(case(
        "output climbs out",
        files("[defaults]\ngroom = \"g.hair\"\nrecipe = \"r.toml\"\noutputs = [\"../{name}.usda\"]\n\n[[tasks]]\nname = \"t\"\n"),
        &["farm", "status", "m.toml"],
        2,
        &["m.toml", "'..'"],
    ));
    // A wedge value the recipe refuses is the manifest's error, found before any task runs (each
    // task failed in its log, naming the recipe at a line of the rewritten text).
    for (parameters, named) in [
        ("\"settings.dt\" = [0.002, \"fast\"]", &["w-001", "\"settings.dt\" = \"fast\"", "expected f32"][..]),
        ("\"settings.damping\" = [1.0, -2.0]", &["w-001", "damping", "[0, 10000]"]),
        ("\"stages.99.duration\" = [0.01]", &["w-000", "index 99"]),
        ("\"nosuch.key\" = [1]", &["w-000", "nosuch"]),
        ("\"\" = [1]", &["w-000", "none empty"]),
    ] {
        let manifest = format!("{head}[[wedges]]\nname = \"w\"\nparameters = {{ {parameters} }}\n");
        for command in [&["batch", "m.toml"][..], &["farm", "submit", "m.toml", "--dry-run"]] {
            cases.push(case(
                &format!("wedge {parameters}: {}", command.join(" ")),
                files(&manifest),
                command,
                2,
                &[&["m.toml", "line 6", "r.toml"], named].concat(),
            ));
        }
    }
    // Options that would add lines to the array script (`touch INJECTED` ran on the farm), or
    // that sbatch would read as something else: refused before the script or logs are written.
    for (label, args, named) in [
        ("partition with a line break", &["--partition", "x\ntouch INJECTED"][..], "--partition"),
        ("partition with a space", &["--partition", "a b"], "--partition"),
        ("no cpus", &["--cpus", "0"], "--cpus 0"),
        ("no parallel tasks", &["--max-parallel", "0"], "--max-parallel 0"),
        // Written into the script as %4294967297, which Slurm holds in 32 bits.
        (
            "2^32 + 1 parallel tasks",
            &["--max-parallel", "4294967297"],
            "--max-parallel 4294967297 must be 1 to 100000",
        ),
        ("more parallel tasks than a manifest has", &["--max-parallel", "100001"], "--max-parallel 100001"),
    ] {
        cases.push(case(
            &format!("farm submit: {label}"),
            files(&format!("{head}[[tasks]]\nname = \"a\"\n")),
            &[&["farm", "submit", "m.toml", "--dry-run"], args].concat(),
            2,
            &[named],
        ));
    }
    // Formats known before anything runs: a typo found after styling left the other outputs.
    let plain = "[defaults]\ngroom = \"g.hair\"\nrecipe = \"r.toml\"\n";
    for (label, manifest, culprit) in [
        (
            "output .txt",
            format!("{plain}outputs = [\"out/{{name}}.txt\"]\n[[tasks]]\nname = \"a\"\n"),
            &["line 5", "out/a.txt"][..],
        ),
        (
            "preview .jpg",
            format!("{plain}preview = \"p.jpg\"\n[[tasks]]\nname = \"a\"\n"),
            &["line 5", "p.jpg"],
        ),
        (
            "sheet .jpg",
            format!(
                "contact_sheet = \"s.jpg\"\n{plain}preview = \"{{name}}.png\"\n[[tasks]]\nname = \"a\"\n"
            ),
            &["s.jpg", ".png"],
        ),
        (
            "sheet of no previews",
            format!(
                "contact_sheet = \"s.png\"\n{plain}outputs = [\"{{name}}.usda\"]\n[[tasks]]\nname = \"a\"\n"
            ),
            &["contact sheet", "preview"],
        ),
        (
            "sheet of .exr",
            format!(
                "contact_sheet = \"s.png\"\n{plain}preview = \"{{name}}.exr\"\n[[tasks]]\nname = \"a\"\n"
            ),
            &["a.exr", ".png"],
        ),
        // Written after the tasks, the sheet replaced task a's preview; a's sidecar then never
        // held, so every re-run styled a again. Spelled otherwise, the same file.
        (
            "sheet over a preview",
            format!(
                "contact_sheet = \"./out/a/p.png\"\n{plain}preview = \"out/{{name}}/p.png\"\n\
                 [[tasks]]\nname = \"a\"\n[[tasks]]\nname = \"b\"\n"
            ),
            &["line 1", "task 'a'", "out/a/p.png"],
        ),
    ] {
        cases.push(case(
            &format!("batch {label}"),
            files(&manifest),
            &["batch", "m.toml"],
            2,
            &[&["m.toml"], culprit].concat(),
        ));
    }
    // A task writing over an input: a re-run would style its own output again (the batch did).
    for (label, outputs, culprit) in [
        ("its groom", "[\"g.hair\"]", "task 'a''s groom"),
        // Spelled otherwise, the same file (the batch wrote over its groom).
        ("its groom as ./g.hair", "[\"./g.hair\"]", "task 'a''s groom"),
        // One task writing one file twice.
        ("its own other output", "[\"{name}.usda\", \"./{name}.usda\"]", "task 'a' writes"),
        // Two tasks writing one file spelled two ways: the second replaced the first.
        (
            "another task's output spelled otherwise",
            "[\"{name}.usda\"]\n[[tasks]]\nname = \"b\"\noutputs = [\"./a.usda\"]",
            "two tasks write",
        ),
        // Tasks run in any order, on any node: b would read a's output while it is written.
        (
            "another task's groom",
            "[\"{name}.usda\"]\n[[tasks]]\nname = \"b\"\ngroom = \"a.usda\"",
            "task 'b''s groom",
        ),
    ] {
        let manifest = format!(
            "[defaults]\ngroom = \"g.hair\"\nrecipe = \"r.toml\"\noutputs = {outputs}\n\n[[tasks]]\nname = \"a\"\n"
        );
        for command in [&["batch", "m.toml"][..], &["farm", "status", "m.toml"]] {
            cases.push(case(
                &format!("output is {label}: {}", command.join(" ")),
                files(&manifest),
                command,
                2,
                &["m.toml", culprit],
            ));
        }
    }
    let values: Vec<String> = (0..16).map(|v| format!("{v}.0")).collect();
    let parameters: Vec<String> =
        (0..16).map(|k| format!("\"stages.{k}.duration\" = [{}]", values.join(", "))).collect();
    cases.push(case(
        "wedge 2^64",
        files(&format!("{head}[[wedges]]\nname = \"w\"\nparameters = {{ {} }}\n", parameters.join(", "))),
        &["farm", "status", "m.toml"],
        2,
        &["m.toml", "18446744073709551616 tasks"],
    ));
    cases.push(case(
        "manifest not UTF-8",
        vec![("m.toml", b"[defaults]\n\xff".to_vec())],
        &["batch", "m.toml"],
        2,
        &["m.toml", "UTF-8"],
    ));
    cases.push(case(
        "manifest unknown key",
        files("bogus = 1\n"),
        &["batch", "m.toml"],
        2,
        &["m.toml", "bogus"],
    ));
    cases.push(case("manifest no tasks", files(head), &["batch", "m.toml"], 2, &["m.toml"]));
    // How a task's groom is read: the CLI's ranges for --units and --frame, Y or Z up.
    for (what, line, expected) in [
        ("units zero", "units = 0.0", "units = 0 must be"),
        ("units NaN", "units = nan", "units = NaN must be"),
        // A groom collapsed to points, read before.
        ("units 1e-30", "units = 1e-30", "units = 1e-30 must be"),
        ("frame 1e12", "frame = 1e12", "frame = 1e12 must be"),
        ("up x", "up = \"x\"", "unknown variant `x`"),
    ] {
        cases.push(case(
            &format!("manifest {what}"),
            files(&format!("{head}[[tasks]]\nname = \"t\"\n{line}\n")),
            &["farm", "status", "m.toml"],
            2,
            &["m.toml", expected],
        ));
    }
    cases
}

/// Corrupt `.usdz` packages, each a valid package with one change to the crate file of its
/// curves: `primvars:groom_id`'s count 20 made 1073741844 (usd-core allocated 4 GB for it, past
/// `--max-memory`, and failed with exit 1), or its LZ4 block overwritten (usd-core's error was
/// exit 1 and named no file). Either in the package's root layer, which coif's own crate reader
/// checks first, or in a crate the root layer sublayers, which only usd-core reads.
fn usdz_cases() -> Vec<Case> {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    let run = |args: &[&str]| {
        let output =
            Command::new(env!("CARGO_BIN_EXE_coif")).args(args).current_dir(dir.path()).output().unwrap();
        assert!(output.status.success(), "{args:?}: {}", stderr(&output));
    };
    // 20 ids: 16 or more are compressed.
    run(&["generate", "-o", "g.hair", "--strands", "20", "--vertices", "8"]);
    run(&["convert", "g.hair", "crate.usdz"]);
    run(&["convert", "g.hair", "groom.usdc"]);
    std::fs::write(
        path("root.usda"),
        "#usda 1.0\n(\n    defaultPrim = \"Groom\"\n    subLayers = [@groom.usdc@]\n)\n",
    )
    .unwrap();
    common::usd::usdz_package(&path("root.usda"), &path("layered.usdz"));
    let mut cases = Vec::new();
    for (package, where_) in [("crate.usdz", "root crate"), ("layered.usdz", "sublayered crate")] {
        let valid = std::fs::read(path(package)).unwrap();
        // groom_id: u64 count 20, u64 compressed size 12, then the block (a 0 byte, LZ4).
        let ids = [&20u64.to_le_bytes()[..], &12u64.to_le_bytes()].concat();
        let at = valid.windows(ids.len()).rposition(|w| w == ids).expect("groom_id's compressed array");
        let mut huge = valid.clone();
        huge[at + 3] = 0x40;
        let mut damaged = valid.clone();
        damaged[at + 17..at + 28].fill(0xff);
        let info = ["--max-memory", "512M", "info", "bad.usdz"];
        let convert = ["--max-memory", "512M", "convert", "bad.usdz", "out.usda"];
        let huge_names: &[&str] = if package == "crate.usdz" {
            &["bad.usdz", "groom_id", "1073741844 integers"]
        } else {
            &["bad.usdz", "usd-core", "--max-memory"]
        };
        let files = |bytes: &Vec<u8>| vec![("bad.usdz", bytes.clone())];
        cases.push(case(
            &format!(".usdz: count 1073741844 in its {where_}"),
            files(&huge),
            &info,
            2,
            huge_names,
        ));
        for args in [&info[..], &convert[..]] {
            let name = format!(".usdz: damaged LZ4 block in its {where_}, {}", args[2]);
            cases.push(case(&name, files(&damaged), args, 2, &["bad.usdz", "LZ4"]));
        }
    }
    cases
}

/// Directories given as files: refused up front as bad input.
fn directory_cases(hair: &[u8]) -> Vec<Case> {
    let g = || vec![("g.hair", hair.to_vec()), ("r.toml", BASE.as_bytes().to_vec())];
    vec![
        case("groom is a directory", g(), &["convert", ".", "out.usda"], 2, &["directory"]),
        case(
            "recipe is a directory",
            g(),
            &["style", ".", "--groom", "g.hair", "-o", "out.usda"],
            2,
            &["directory"],
        ),
        case("manifest is a directory", g(), &["batch", "."], 2, &["directory"]),
        case("groom is /dev/null", g(), &["convert", "/dev/null", "out.usda"], 2, &["/dev/null", "device"]),
    ]
}

/// Inputs the fuzz targets (fuzz/) found crashing a reader, kept in tests/data/fuzz: each must
/// now be refused with exit 2 naming the file. A groom format is opened by `coif info`; an OBJ
/// as a recipe's mesh obstacle.
fn fuzz_found_cases(hair: &[u8]) -> Vec<Case> {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz");
    let mut cases = Vec::new();
    for entry in std::fs::read_dir(folder).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let bytes = std::fs::read(&path).unwrap();
        let case_name = format!("fuzz-found {name}");
        if name.ends_with(".obj") {
            let recipe =
                format!("[[obstacles]]\nshape = \"mesh\"\nname = \"m\"\npath = \"{name}\"\n\n{BASE}");
            let files =
                vec![(name.as_str(), bytes), ("r.toml", recipe.into_bytes()), ("g.hair", hair.to_vec())];
            let args = ["style", "r.toml", "--groom", "g.hair", "-o", "out.usda"];
            cases.push(case(&case_name, files, &args, 2, &[&name]));
        } else {
            cases.push(case(&case_name, vec![(name.as_str(), bytes)], &["info", &name], 2, &[&name]));
        }
    }
    cases
}

/// Runs one case in a fresh folder; returns a failure description, if any.
fn run(case: &Case) -> Option<String> {
    let dir = tempfile::tempdir().unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_coif"))
        .args(&case.args)
        .current_dir(prepared(case, &dir))
        .output()
        .expect("the coif binary runs");
    judge(case, &output, dir.path())
}

/// Writes a case's files into its folder.
fn prepared<'a>(case: &Case, dir: &'a tempfile::TempDir) -> &'a Path {
    for (name, bytes) in &case.files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    dir.path()
}

/// What is wrong with a case's run: its exit code, a panic, a culprit not named, files left.
fn judge(case: &Case, output: &std::process::Output, dir: &Path) -> Option<String> {
    let err = stderr(output);
    let mut problems = Vec::new();
    if output.status.code() != Some(case.code) {
        problems.push(format!("exit {:?}, expected {}", output.status.code(), case.code));
    }
    if err.contains("panicked") {
        problems.push("panicked".into());
    }
    for name in &case.names {
        if !err.contains(name.as_str()) {
            problems.push(format!("stderr does not name {name:?}"));
        }
    }
    let mut expected: Vec<String> = case.files.iter().map(|(n, _)| n.clone()).collect();
    expected.sort();
    let left = listing(dir);
    if left != expected {
        problems.push(format!("left behind: {left:?}"));
    }
    (!problems.is_empty()).then(|| format!("{}: {} — stderr: {}", case.name, problems.join("; "), err.trim()))
}

fn listing(dir: &Path) -> Vec<String> {
    common::dir_listing(dir)
}

fn all_cases() -> Vec<Case> {
    let inputs = inputs();
    let mut cases = recipe_cases(&inputs.hair);
    cases.extend(mesh_cases(&inputs.hair));
    cases.extend(cli_cases(&inputs.hair));
    cases.extend(file_cases(&inputs));
    cases.extend(manifest_cases(&inputs.hair));
    cases.extend(directory_cases(&inputs.hair));
    cases.extend(fuzz_found_cases(&inputs.hair));
    cases.extend(usdz_cases());
    cases.extend(unit_and_type_cases(&inputs.hair));
    cases.extend(contradiction_cases(&inputs.hair));
    cases
}

/// Inputs that were accepted though they contradict themselves or change nothing: each was
/// read (exit 0), or its data dropped without a word, before.
fn contradiction_cases(hair: &[u8]) -> Vec<Case> {
    let mut cases = Vec::new();
    // Coulomb friction: sliding is held less than rest (μ_k ≤ μ_s); the default μ_s is 0.4.
    for (contacts, names) in [
        (
            "static_friction = 0.2\ndynamic_friction = 0.3",
            &["line 3", "dynamic_friction = 0.3", "static_friction = 0.2"][..],
        ),
        (
            "dynamic_friction = 0.5",
            &["line 2", "dynamic_friction = 0.5", "static_friction = 0.4 (the default)"],
        ),
    ] {
        let recipe = format!("[contacts]\n{contacts}\n{BASE}");
        cases.push(style_case(&format!("friction {contacts}"), &recipe, hair, names));
    }
    // A world-frame recipe fits no head frame: its `[head]` changed nothing.
    for head in ["size = 0.1", "center = [0, 1.7, 0]\nup = [0, 0, 1]"] {
        let recipe = format!("frame = \"world\"\n[head]\n{head}\n{BASE}");
        cases.push(style_case(
            &format!("[head] {head} in a world recipe"),
            &recipe,
            hair,
            &["line 2", "[head]", "frame = \"head\""],
        ));
    }
    // A primvar's `elementSize` must make whole elements of its values (pxr authors any int).
    for (declaration, culprit) in [
        (
            "float[] primvars:foo = [1, 2] (interpolation = \"uniform\"\n elementSize = 1000000000)",
            "elementSize = 1000000000",
        ),
        (
            "float[] primvars:foo = [1, 2] (interpolation = \"uniform\"\n elementSize = -3)",
            "elementSize = -3",
        ),
        (
            "float[] primvars:foo = [1, 2, 3, 4, 5] (interpolation = \"uniform\"\n elementSize = 2)",
            "5 numbers",
        ),
        (
            "float3[] primvars:foo = [(1, 2, 3), (4, 5, 6)] (interpolation = \"uniform\"\n elementSize = 2)",
            "uniform interpolation needs 2",
        ),
    ] {
        let file = vec![("in.usda", two_curves("", declaration).into_bytes())];
        cases.push(case(
            &format!("primvar {declaration}"),
            file,
            &["convert", "in.usda", "out.usda"],
            2,
            &["in.usda", "line 7", "prim </c>", "primvars:foo", culprit],
        ));
    }
    let mesh = two_curves("", "").replace(
        "\n}\n",
        "\n}\ndef Mesh \"m\"\n{\n    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n    \
         point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n    \
         float[] primvars:foo = [1, 2] (interpolation = \"constant\"\n elementSize = 1000000000)\n}\n",
    );
    // The settle's options without --settle did nothing, unchecked: `--settle-tolerance nan` ran.
    for (flag, value) in
        [("--settle-tolerance", "nan"), ("--settle-seconds", "5"), ("--settle-iterations", "3")]
    {
        cases.push(case(
            &format!("{flag} without --settle"),
            vec![("g.hair", hair.to_vec())],
            &["simulate", "g.hair", "out.hair", "--seconds", "0.01", flag, value],
            2,
            &[flag, "--settle"],
        ));
    }
    // One prim of degree-4 NURBS (Blender's NURBS order 5) beside other curves: the whole file
    // is refused naming the prim and what to do, not read without the prim's hair.
    let nurbs = format!(
        "{}def NurbsCurves \"odd\"\n{{\n    int[] curveVertexCounts = [5]\n    int[] order = [5]\n    \
         point3f[] points = [(0, 0, 0), (0, 1, 0), (0, 2, 0), (0, 3, 0), (0, 4, 0)]\n}}\n",
        two_curves("", "")
    );
    cases.push(case(
        "order-5 NurbsCurves beside BasisCurves",
        vec![("in.usda", nurbs.into_bytes())],
        &["convert", "in.usda", "out.usda"],
        2,
        &["in.usda", "line 12", "prim </odd>", "order 5 (degree 4)", "give these curves order 4"],
    ));
    // A floor placed or coloured with --no-floor: the option did nothing.
    for (flag, value) in [("--floor-height", "1"), ("--floor-size", "3"), ("--floor-albedo", "0.5,0.5,0.5")] {
        cases.push(case(
            &format!("{flag} with --no-floor"),
            vec![("g.hair", hair.to_vec())],
            &["render", "g.hair", "-o", "out.png", "--res", "8x8", "--spp", "1", "--no-floor", flag, value],
            2,
            &[flag, "--no-floor"],
        ));
    }
    cases.push(case(
        "mesh primvar elementSize = 1e9",
        vec![("in.usda", mesh.into_bytes())],
        &["convert", "in.usda", "out.usda"],
        2,
        &["in.usda", "prim </m>", "foo", "elementSize = 1000000000"],
    ));
    cases
}

/// Units that collapse or blow up a groom, and numbers and types pxr refuses or cannot read:
/// every one was read (exit 0) before.
fn unit_and_type_cases(hair: &[u8]) -> Vec<Case> {
    let mut cases = Vec::new();
    // At 1e-30 m per unit a 24 cm strand was 2.4e-31 m long, and 1e30 m per unit in a layer was
    // read as well as 1e-40 (a denormal f32) given as a flag.
    for units in ["1e-30", "1e-40", "1e-9", "1e4", "1e30"] {
        let args = ["convert", "g.hair", "out.usda", "--units", units];
        cases.push(case(
            &format!("convert --units {units}"),
            vec![("g.hair", hair.to_vec())],
            &args,
            2,
            &["--units"],
        ));
        let header = format!("(\n    metersPerUnit = {units}\n)\n");
        let file = vec![("in.usda", two_curves(&header, "").into_bytes())];
        let names = ["in.usda", "metersPerUnit", "[1e-6, 1000]"];
        cases.push(case(
            &format!("metersPerUnit {units}"),
            file,
            &["convert", "in.usda", "out.usda"],
            2,
            &names,
        ));
    }
    // A micrometre unit is allowed, but points 1e-4 units apart are 1e-10 m: a simulation was
    // refused for a "zero-length segment" with no hint at the units.
    let tiny = two_curves("(\n    metersPerUnit = 1e-6\n)\n", "").replace("(0, 1, 0)", "(0, 1e-4, 0)");
    let args = ["simulate", "in.usda", "out.usda", "--seconds", "0.01"];
    let names = ["in.usda", "zero-length segment", "within 1e-9 m", "units"];
    cases.push(case("segments of 1e-10 m", vec![("in.usda", tiny.into_bytes())], &args, 2, &names));
    // A groom of 24 cm strands read at --units 1000 (a kilometre a unit) was styled as 240 m
    // strands, each resampled to thousands of segments: refused naming the flag; a file's own
    // 20 m strand (in metres) is refused too, naming its strand.
    let files = || vec![("g.hair", hair.to_vec()), ("r.toml", BASE.as_bytes().to_vec())];
    for (args, names) in [
        (
            &["style", "r.toml", "--groom", "g.hair", "-o", "out.usda", "--units", "1000"][..],
            &["g.hair: strand 0 is 240.00 m long", "10 m", "(read at --units 1000)"][..],
        ),
        (
            &["style", "r.toml", "--groom", "g.hair", "-o", "out.usda", "--units", "100", "--guides", "2"],
            &["g.hair: strand 0 is 24.00 m long", "(read at --units 100)"],
        ),
        (&["simulate", "g.hair", "out.hair", "--units", "1000"], &["strand 0 is 240.00 m", "--units 1000"]),
    ] {
        cases.push(case(&format!("240 m strands: {}", args.join(" ")), files(), args, 2, names));
    }
    // Blender's Alembic groom at --units 1000: 390 m strands 4 to 8 cm wide, all within the
    // widths and coordinates the rods take (styled, exit 0).
    let blender =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/blender_groom.abc")).unwrap();
    cases.push(case(
        "Blender's groom at --units 1000",
        vec![("b.abc", blender), ("r.toml", BASE.as_bytes().to_vec())],
        &["style", "r.toml", "--groom", "b.abc", "-o", "out.usda", "--units", "1000"],
        2,
        &["b.abc: strand 0 is", "m long", "(read at --units 1000)"],
    ));
    let long = two_curves("(\n    metersPerUnit = 1\n)\n", "").replace("(1, 1, 0)", "(1, 20, 0)");
    let args = ["simulate", "in.usda", "out.usda", "--seconds", "0.01"];
    let names = ["in.usda: strand 1 is 20.00 m long"];
    cases.push(case("a 20 m strand", vec![("in.usda", long.into_bytes())], &args, 2, &names));
    // A frame before the first sample, as written: it printed 5e-302 with 300 digits.
    let slow = "#usda 1.0\n(\n    metersPerUnit = 1\n    timeCodesPerSecond = 1e-300\n)\ndef BasisCurves \"c\"\n{\n    \
                uniform token type = \"linear\"\n    int[] curveVertexCounts = [2]\n    point3f[] points.timeSamples = {\n        \
                1: [(0, 0, 0), (0, 1, 0)],\n        2: [(0, 0, 0), (0, 2, 0)],\n    }\n}\n";
    let names = ["in.usda", "frame 5e-302 is before the first time sample (1)"];
    cases.push(case(
        "a frame of 5e-302",
        vec![("in.usda", slow.into())],
        &["info", "in.usda", "--time", "0.05"],
        2,
        &names,
    ));
    // pxr's number has no `+` prefix: `+1` is a syntax error in a point, a width or metadata.
    let plus = [
        ("point", two_curves("", "").replace("(1, 1, 0)", "(1, +1, 0)"), "'+1'"),
        ("width", two_curves("", "float[] widths = [0.1, +0.1] (interpolation = \"uniform\")"), "'+0.1'"),
        ("metersPerUnit", two_curves("(\n    metersPerUnit = +1\n)\n", ""), "+1"),
    ];
    for (what, text, culprit) in plus {
        let file = vec![("in.usda", text.into_bytes())];
        cases.push(case(
            &format!("+ on a {what}"),
            file,
            &["convert", "in.usda", "out.usda"],
            2,
            &["in.usda", culprit],
        ));
    }
    // An elementSize is an `int`: pxr refuses the layer for 1e12 or nan; coif took 1e12 as 1.
    for (size, written) in [("1e12", "1e12"), ("nan", "NaN"), ("-3e9", "-3e9")] {
        let text = two_curves(
            "",
            &format!("float[] primvars:x = [1, 2, 3, 4] (interpolation = \"vertex\"\n elementSize = {size})"),
        );
        let file = vec![("in.usda", text.into_bytes())];
        let names = ["in.usda", "line 8", &format!("elementSize = {written} is not an int")];
        cases.push(case(
            &format!("elementSize {size}"),
            file,
            &["convert", "in.usda", "out.usda"],
            2,
            &names,
        ));
    }
    // Indices declared int64[]: pxr has "no indices authored" and 2 values for 4 vertices.
    let text = two_curves("", "float[] primvars:x = [1, 2] (interpolation = \"vertex\")\n    int64[] primvars:x:indices = [0, 1, 0, 1]");
    let names = ["in.usda", "line 8", "'primvars:x:indices' is declared int64[]"];
    cases.push(case(
        "int64[] indices",
        vec![("in.usda", text.into_bytes())],
        &["convert", "in.usda", "out.usda"],
        2,
        &names,
    ));
    // Frames per second: 0 wrote no animation without a word, 1e-9 a timeline of 1e-9 codes a second.
    for fps in ["0", "1e-9", "0.5"] {
        let files = vec![("r.toml", BASE.as_bytes().to_vec()), ("g.hair", hair.to_vec())];
        let args = ["style", "r.toml", "--groom", "g.hair", "-o", "out.usda", "--frames", fps];
        cases.push(case(&format!("style --frames {fps}"), files, &args, 2, &["--frames", "[1, 10000]"]));
    }
    // Topology declared other than int[]: pxr's GetCurveCount and meshes read nothing from it.
    for declared in [
        "int64[] curveVertexCounts = [2, 2]",
        "uint[] curveVertexCounts = [2, 2]",
        "int curveVertexCounts = 4",
    ] {
        let text = two_curves("", "").replace("int[] curveVertexCounts = [2, 2]", declared);
        let file = vec![("in.usda", text.into_bytes())];
        let names = ["in.usda", "line 5", "'curveVertexCounts' is declared"];
        cases.push(case(&format!("usda {declared}"), file, &["convert", "in.usda", "out.usda"], 2, &names));
    }
    let mesh = usda_with_mesh("[3]", "[0, 1, 2]", "(0, 0, 0), (1, 0, 0), (0, 1, 0)")
        .replace("int[] faceVertexCounts", "uint[] faceVertexCounts");
    let names = ["in.usda", "</head>", "'faceVertexCounts' is declared uint[]"];
    cases.push(case(
        "usda uint[] faceVertexCounts",
        vec![("in.usda", mesh.into_bytes())],
        &["convert", "in.usda", "out.usda"],
        2,
        &names,
    ));
    // The same layers written by pxr as crate files (tests/data/pxr_written_bad/make.py).
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pxr_written_bad");
    for (name, culprit) in [
        ("counts_int64.usdc", "'curveVertexCounts' is declared int64[]"),
        ("counts_uint.usdc", "'curveVertexCounts' is declared uint[]"),
        ("counts_scalar.usdc", "'curveVertexCounts' is declared int;"),
        ("meters_per_unit_1e-30.usdc", "metersPerUnit = 1e-30"),
        (
            "counts_int_holding_int64.usdc",
            "</c.curveVertexCounts>: default: declared int[] but holds int64[] values",
        ),
        (
            "counts_int_holding_uint.usdc",
            "</c.curveVertexCounts>: default: declared int[] but holds uint[] values",
        ),
        // Floats of another float type were converted: pxr reads no widths or points from them.
        (
            "widths_float_holding_double.usdc",
            "</c.widths>: default: declared float[] but holds double[] values",
        ),
        ("widths_float_holding_half.usdc", "</c.widths>: default: declared float[] but holds half[] values"),
        (
            "points_point3f_holding_double3.usdc",
            "</c.points>: default: declared point3f[] but holds double3[] values",
        ),
    ] {
        let file = vec![(name, std::fs::read(folder.join(name)).unwrap())];
        cases.push(case(
            &format!("pxr-written {name}"),
            file,
            &["convert", name, "out.usda"],
            2,
            &[name, culprit],
        ));
    }
    cases
}

/// Runs every case through `run` on a few threads; returns the failures in case order.
fn failures_of(cases: &[Case], run: impl Fn(&Case) -> Option<String> + Sync) -> Vec<String> {
    let next = Mutex::new(cases.iter().enumerate());
    let failures = Mutex::new(Vec::new());
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get()).clamp(2, 8);
    std::thread::scope(|scope| {
        for _ in 0..threads {
            scope.spawn(|| loop {
                let Some((index, case)) = next.lock().unwrap().next() else { break };
                if let Some(failure) = run(case) {
                    failures.lock().unwrap().push((index, failure));
                }
            });
        }
    });
    let mut failures = failures.into_inner().unwrap();
    failures.sort();
    failures.into_iter().map(|(_, failure)| failure).collect()
}

#[test]
fn every_bad_input_exits_2_names_its_culprit_and_leaves_nothing() {
    let cases = all_cases();
    assert!(cases.len() >= 150, "only {} cases", cases.len());
    let failures = failures_of(&cases, run);
    assert!(
        failures.is_empty(),
        "{} of {} cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// A FIFO given as groom, recipe, manifest or mesh is refused at once instead of blocking.
#[cfg(unix)]
#[test]
fn fifos_are_refused_without_blocking() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
    assert!(made.success());
    let recipe = dir.path().join("r.toml");
    std::fs::write(
        &recipe,
        format!("[[obstacles]]\nshape = \"mesh\"\nname = \"m\"\npath = \"pipe\"\n\n{BASE}"),
    )
    .unwrap();
    let hair = inputs().hair;
    let groom = dir.path().join("g.hair");
    std::fs::write(&groom, hair).unwrap();
    let (f, r, g) = (path_str(&fifo), path_str(&recipe), path_str(&groom));
    for args in [
        vec!["info", f],
        vec!["style", f, "--groom", g, "-o", "o.usda"],
        vec!["batch", f],
        vec!["style", r, "--groom", g, "-o", "o.usda"],
    ] {
        let output = coif(&args);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {}", stderr(&output));
        assert!(stderr(&output).contains("FIFO"), "{args:?}: {}", stderr(&output));
    }
}

/// An output that is a symbolic link is written through it, as `cp` and a shell's `>` write: the
/// file it leads to is replaced, or made where the link dangles, and the link stays. One that
/// leads into a missing folder, or round in a loop, is exit 2 naming it, before any work. (A
/// dangling link was replaced by a regular file.)
#[cfg(unix)]
#[test]
fn an_output_that_is_a_symbolic_link_is_written_through_it() {
    use std::os::unix::fs::symlink;
    let dir = tempfile::tempdir().unwrap();
    let groom = dir.path().join("g.hair");
    std::fs::write(&groom, inputs().hair).unwrap();
    std::fs::create_dir(dir.path().join("shots")).unwrap();
    let folder = tempfile::tempdir().unwrap();
    for (target, existing) in [("shots/v1.usda", false), ("shots/v1.usda", true)] {
        let link = dir.path().join("latest.usda");
        let _ = std::fs::remove_file(&link);
        symlink(target, &link).unwrap();
        let written = dir.path().join(target);
        if existing {
            std::fs::write(&written, b"old").unwrap();
        }
        let output = coif(&["convert", path_str(&groom), path_str(&link)]);
        assert!(output.status.success(), "{}", stderr(&output));
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink(), "the link stays a link");
        let through = coif(&["info", path_str(&written)]);
        assert!(through.status.success(), "{target} (existing: {existing}): {}", stderr(&through));
        assert_eq!(listing(&dir.path().join("shots")), vec!["v1.usda".to_string()], "no temporary file left");
        std::fs::remove_file(&written).unwrap();
    }
    // Into a missing folder, and a loop: refused before the groom is read.
    symlink("missing/v1.usda", folder.path().join("dangling.usda")).unwrap();
    symlink("loop.usda", folder.path().join("loop.usda")).unwrap();
    for (name, culprit) in [("dangling.usda", "missing"), ("loop.usda", "loop")] {
        let output = coif(&["convert", path_str(&groom), path_str(&folder.path().join(name))]);
        assert_eq!(output.status.code(), Some(2), "{name}: {}", stderr(&output));
        assert!(stderr(&output).contains(name) && stderr(&output).contains(culprit), "{}", stderr(&output));
        assert!(std::fs::symlink_metadata(folder.path().join(name)).unwrap().file_type().is_symlink());
    }
    assert_eq!(listing(folder.path()), vec!["dangling.usda".to_string(), "loop.usda".to_string()]);
}

/// SIGTERM and SIGINT during a write remove the temporary file and exit 143 and 130.
#[cfg(unix)]
#[test]
fn signals_remove_the_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let groom = dir.path().join("big.hair");
    let made = coif(&["generate", "-o", path_str(&groom), "--strands", "100000", "--vertices", "32"]);
    assert!(made.status.success(), "{}", stderr(&made));
    for (signal, code) in [("TERM", 143), ("INT", 130)] {
        let out = dir.path().join("big.usda");
        let mut child = Command::new(env!("CARGO_BIN_EXE_coif"))
            .args(["convert", path_str(&groom), path_str(&out)])
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        // Wait until the temporary output exists, then interrupt.
        let temporary = || listing(dir.path()).into_iter().any(|n| n.starts_with(".big.usda."));
        let start = std::time::Instant::now();
        while !temporary() && start.elapsed().as_secs() < 60 {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        assert!(temporary(), "the temporary output never appeared");
        let killed =
            Command::new("kill").args([&format!("-{signal}"), &child.id().to_string()]).status().unwrap();
        assert!(killed.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "SIG{signal}");
        assert_eq!(listing(dir.path()), vec!["big.hair".to_string()], "SIG{signal}");
    }
}

/// A write that fails for lack of room (here a file-size limit, as a full disk would) is the
/// environment's fault: exit 1, the output named, nothing left behind — also when it fails in the
/// middle of an animation's frames (it was exit 2, "bad input", there).
#[cfg(unix)]
#[test]
fn a_failing_write_exits_1_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let made = coif(&[
        "generate",
        "-o",
        path_str(&dir.path().join("g.hair")),
        "--strands",
        "5000",
        "--vertices",
        "16",
    ]);
    assert!(made.status.success(), "{}", stderr(&made));
    std::fs::write(dir.path().join("r.toml"), BASE).unwrap();
    // File-size limits in KB: the animation's first frame fits, its third does not; the crate
    // file is compressed, so it gets less room.
    for (args, limit_kb) in [
        ("style r.toml --groom g.hair -o out.abc --frames 8", 1024),
        ("convert g.hair out.abc", 1024),
        ("convert g.hair out.usda", 1024),
        ("convert g.hair out.usdc", 128),
    ] {
        // SIGXFSZ ignored, so the write returns EFBIG instead of killing the process.
        let output = Command::new("sh")
            .arg("-c")
            .arg(format!("trap '' XFSZ; ulimit -f {}; exec \"$0\" {args}", limit_kb * 2))
            .arg(env!("CARGO_BIN_EXE_coif"))
            .current_dir(dir.path())
            .output()
            .unwrap();
        let err = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{args}: {err}");
        let out = args.split(' ').find(|a| a.starts_with("out.")).unwrap();
        assert!(err.contains(out), "{args}: {err}");
        assert_eq!(listing(dir.path()), vec!["g.hair".to_string(), "r.toml".to_string()], "{args}");
    }
}

/// The corrupt packages of [`usdz_cases`] are refused (exit 2, the file named, nothing left)
/// within seconds, coif and usd-core together never holding `--max-memory` (512 MB). Each run is
/// fenced at 6 GB of address space, so that a build that lets usd-core allocate what the file asks
/// fails here rather than meeting the OOM killer.
#[cfg(target_os = "linux")]
#[test]
fn corrupt_usdz_packages_are_refused_quickly_within_the_memory_limit() {
    use std::io::Read;
    use std::os::unix::process::ExitStatusExt;
    for case in usdz_cases() {
        let dir = tempfile::tempdir().unwrap();
        let start = std::time::Instant::now();
        #[allow(clippy::zombie_processes)] // reaped by wait4 below
        let mut child = Command::new("sh")
            .arg("-c")
            .arg("ulimit -v 6000000; exec \"$0\" \"$@\"")
            .arg(env!("CARGO_BIN_EXE_coif"))
            .args(&case.args)
            .current_dir(prepared(&case, &dir))
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let mut err = Vec::new();
        child.stderr.take().unwrap().read_to_end(&mut err).unwrap();
        // wait4, not Child::wait: its peak resident memory covers the children coif waited for.
        let (mut status, mut usage) = (0, unsafe { std::mem::zeroed::<libc::rusage>() });
        let waited = unsafe { libc::wait4(child.id() as libc::pid_t, &mut status, 0, &mut usage) };
        assert_eq!(waited, child.id() as libc::pid_t);
        let seconds = start.elapsed().as_secs_f64();
        let peak = usage.ru_maxrss as f64 * 1024.0;
        let output = std::process::Output {
            status: std::process::ExitStatus::from_raw(status),
            stdout: Vec::new(),
            stderr: err,
        };
        if let Some(failure) = judge(&case, &output, dir.path()) {
            panic!("{failure}");
        }
        assert!(seconds < 30.0, "{}: {seconds:.1} s", case.name);
        assert!(peak < 512.0 * 1024.0 * 1024.0, "{}: peak resident memory {:.0} MB", case.name, peak / 1e6);
    }
}

/// SIGTERM while usd-core converts a `.usdz` export removes the `.coif-usd.*` folder beside the
/// output (and the converter's files in it) and exits 143.
#[cfg(unix)]
#[test]
fn sigterm_during_a_usd_core_export_removes_the_temporary_folder() {
    let dir = tempfile::tempdir().unwrap();
    let groom = dir.path().join("big.hair");
    let made = coif(&["generate", "-o", path_str(&groom), "--strands", "50000", "--vertices", "16"]);
    assert!(made.status.success(), "{}", stderr(&made));
    let out = dir.path().join("big.usdz");
    let mut child = Command::new(env!("CARGO_BIN_EXE_coif"))
        .args(["convert", path_str(&groom), path_str(&out)])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Interrupt once coif's `.usda` is complete inside the folder, that is while usd-core runs.
    let converting = || {
        listing(dir.path())
            .iter()
            .filter(|n| n.starts_with(".coif-usd."))
            .any(|n| dir.path().join(n).join("groom.usda").is_file())
    };
    let start = std::time::Instant::now();
    while !converting() && start.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    assert!(converting(), "the export never reached usd-core");
    let killed = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(143));
    assert_eq!(listing(dir.path()), vec!["big.hair".to_string()]);
    // usd-core, if still running, must not bring the folder or the output back.
    std::thread::sleep(std::time::Duration::from_secs(2));
    assert_eq!(listing(dir.path()), vec!["big.hair".to_string()]);
}

/// The record that the corpus tests something: runs every case against another coif binary
/// (`COIF_CORPUS_BINARY=path`, e.g. a build from before the hardening work) and prints the cases
/// it fails. Each run is capped at 4 GB of address space and 30 s, so the old binary's unbounded
/// allocations abort and its unbounded runs are killed ("no exit").
/// `COIF_CORPUS_BINARY=/path/coif cargo test --test bad_input_corpus -- --ignored --nocapture`
#[cfg(unix)]
#[test]
#[ignore = "a tool: needs COIF_CORPUS_BINARY"]
fn against_another_binary() {
    let binary = std::env::var("COIF_CORPUS_BINARY").expect("COIF_CORPUS_BINARY names a coif binary");
    let cases = all_cases();
    let run_with_limits = |case: &Case| {
        let dir = tempfile::tempdir().unwrap();
        let output = Command::new("sh")
            .arg("-c")
            .arg("ulimit -v 4000000; exec timeout -s KILL 30 \"$0\" \"$@\"")
            .arg(&binary)
            .args(&case.args)
            .current_dir(prepared(case, &dir))
            .output()
            .expect("sh runs");
        judge(case, &output, dir.path())
    };
    let failures = failures_of(&cases, run_with_limits);
    println!("{} of {} cases fail with {binary}:", failures.len(), cases.len());
    for failure in &failures {
        println!("FAILS {}", failure.replace('\n', " | "));
    }
}

/// A `.usda` layer of two linear curves of two vertices each, with `header` (layer metadata,
/// may be empty) and one more property `declaration` on the curves prim.
fn two_curves(header: &str, declaration: &str) -> String {
    format!(
        "#usda 1.0\n{header}def BasisCurves \"c\"\n{{\n    uniform token type = \"linear\"\n    \
         int[] curveVertexCounts = [2, 2]\n    point3f[] points = [(0, 0, 0), (0, 1, 0), (1, 0, 0), (1, 1, 0)]\n    \
         {declaration}\n}}\n"
    )
}
