//! Mesh obstacles in recipes (`shape = "mesh"`, a Wavefront OBJ file): hair settled onto the
//! bundled low-poly head mesh stays outside it; broken mesh files are refused with exit code 2.
mod common;
use common::*;

use std::path::{Path, PathBuf};

use glam::Vec3;

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

/// The face planes `(unit outward normal, offset)` of a convex OBJ mesh, read with a parser of
/// our own (only `v` and triangular `f` lines), independent of the `tobj` reader and of the
/// baked distance field. For a convex solid, `max(n·p − offset)` is the exact signed distance
/// of an inside point `p` to the surface (negative inside).
fn convex_planes(obj: &Path) -> Vec<(Vec3, f32)> {
    let text = std::fs::read_to_string(obj).unwrap();
    let mut vertices = Vec::new();
    let mut planes = Vec::new();
    for line in text.lines() {
        let fields: Vec<&str> = line.split_whitespace().collect();
        match fields.first() {
            Some(&"v") => vertices.push(Vec3::new(
                fields[1].parse().unwrap(),
                fields[2].parse().unwrap(),
                fields[3].parse().unwrap(),
            )),
            Some(&"f") => {
                assert_eq!(fields.len(), 4, "the bundled mesh is triangles only");
                let [a, b, c] = [1, 2, 3].map(|k| vertices[fields[k].parse::<usize>().unwrap() - 1]);
                let n = (b - a).cross(c - a).normalize();
                planes.push((n, n.dot(a)));
            }
            _ => {}
        }
    }
    planes
}

fn depth_inside(planes: &[(Vec3, f32)], p: Vec3) -> f32 {
    -planes.iter().map(|&(n, offset)| n.dot(p) - offset).fold(f32::MIN, f32::max)
}

const SETTLE: &str = "\n[[stages]]\nkind = \"settle\"\nmax_seconds = 3.0\ntolerance = 1e-3\n";

/// Styles the 200-strand seed groom with `obstacles` (TOML) and a 3 s settle under gravity,
/// from a recipe in `dir`; returns the settled points.
fn settle_with(dir: &Path, name: &str, obstacles: &str) -> Vec<Vec3> {
    let recipe = dir.join(format!("{name}.toml"));
    std::fs::write(&recipe, format!("{obstacles}{SETTLE}")).unwrap();
    let out = dir.join(format!("{name}.usda"));
    let groom = repo("grooms/seed_200x24cm.hair");
    let result =
        coif(&["style", path_str(&recipe), "--groom", path_str(&groom), "-o", path_str(&out), "--quiet"]);
    assert!(result.status.success(), "{name}: {}", stderr(&result));
    coif::io::read_groom(&out, &Default::default()).unwrap().groom.points
}

#[test]
fn hair_settled_on_a_mesh_head_stays_outside_it() {
    // The recipe sits in a temporary directory and names the mesh relative to itself.
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("meshes")).unwrap();
    let mesh = dir.path().join("meshes/head.obj");
    std::fs::copy(repo("grooms/meshes/head_lowpoly.obj"), &mesh).unwrap();
    let planes = convex_planes(&mesh);
    assert_eq!(planes.len(), 960);

    let on_mesh = settle_with(
        dir.path(),
        "on_mesh",
        "[[obstacles]]\nname = \"head\"\nshape = \"mesh\"\npath = \"meshes/head.obj\"\n",
    );
    let control = settle_with(dir.path(), "no_obstacle", "");

    let deepest = on_mesh.iter().map(|&p| depth_inside(&planes, p)).fold(f32::MIN, f32::max);
    let resting = on_mesh.iter().filter(|&&p| depth_inside(&planes, p).abs() < 0.002).count();
    let sunk_control = control.iter().filter(|&&p| depth_inside(&planes, p) > 0.01).count();
    eprintln!(
        "mesh head: deepest vertex {deepest:.6} m inside, {resting} vertices within 2 mm of the \
         surface; without the obstacle {sunk_control} vertices end more than 1 cm inside"
    );
    // The field is baked on a 2 mm grid: trilinear interpolation of the distance to a faceted
    // surface errs by well under a tenth of a cell near the surface.
    assert!(deepest < 2e-4, "a vertex ends {deepest} m inside the mesh");
    // The hair really lies on the mesh, and would fall into the head without it.
    assert!(resting >= 100, "only {resting} vertices rest on the mesh");
    assert!(sunk_control >= 20, "without the mesh only {sunk_control} vertices sink into the head");
}

#[test]
fn broken_mesh_files_exit_2_naming_the_file_and_the_recipe_line() {
    let cases: [(&str, Option<&str>, &str); 3] = [
        ("missing.obj", None, "missing.obj"),
        ("points.obj", Some("v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "no triangles"),
        ("garbled.obj", Some("v 0 0 zero\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), "OBJ"),
    ];
    for (file, contents, reason) in cases {
        let dir = tempfile::tempdir().unwrap();
        if let Some(text) = contents {
            std::fs::write(dir.path().join(file), text).unwrap();
        }
        let recipe = dir.path().join("bad.toml");
        let text = format!(
            "[settings]\nseed = 1\n\n[[obstacles]]\nname = \"head\"\nshape = \"mesh\"\npath = \"{file}\"\n{SETTLE}"
        );
        std::fs::write(&recipe, &text).unwrap();
        let output = dir.path().join("out.usda");
        let groom = repo("grooms/seed_200x24cm.hair");
        let result =
            coif(&["style", path_str(&recipe), "--groom", path_str(&groom), "-o", path_str(&output)]);
        let message = stderr(&result);
        assert_eq!(result.status.code(), Some(2), "{file}: {message}");
        assert!(
            message.contains("bad.toml") && message.contains("line 4") && message.contains(file),
            "{file}: {message:?} lacks the recipe, its line or the mesh file"
        );
        assert!(message.contains(reason), "{file}: {message:?} lacks {reason:?}");
        assert!(!output.exists(), "{file}: output written");
    }
}

#[test]
fn a_scalp_given_on_the_command_line_is_the_recipes_scalp_obstacle() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = repo("grooms/meshes/head_lowpoly.obj");
    let planes = convex_planes(&mesh);
    let recipe = dir.path().join("scalp.toml");
    std::fs::write(&recipe, format!("[[obstacles]]\nname = \"head\"\nshape = \"scalp\"\n{SETTLE}")).unwrap();
    let groom = repo("grooms/seed_200x24cm.hair");
    let out = dir.path().join("out.usda");
    let args = ["style", path_str(&recipe), "--groom", path_str(&groom), "-o", path_str(&out), "--quiet"];
    let result = coif(&[&args[..], &["--scalp", path_str(&mesh)]].concat());
    assert!(result.status.success(), "{}", stderr(&result));
    let points = coif::io::read_groom(&out, &Default::default()).unwrap().groom.points;
    let deepest = points.iter().map(|&p| depth_inside(&planes, p)).fold(f32::MIN, f32::max);
    let resting = points.iter().filter(|&&p| depth_inside(&planes, p).abs() < 0.002).count();
    eprintln!("--scalp: deepest vertex {deepest:.6} m inside the mesh, {resting} resting on it");
    assert!(deepest < 2e-4 && resting >= 100, "deepest {deepest} m, {resting} resting");

    // A scalp file that cannot be read is bad input: exit 2 naming it, nothing written.
    let missing = dir.path().join("missing.obj");
    let unwritten = dir.path().join("unwritten.usda");
    let result = coif(&[
        "style",
        path_str(&recipe),
        "--groom",
        path_str(&groom),
        "-o",
        path_str(&unwritten),
        "--scalp",
        path_str(&missing),
    ]);
    assert_eq!(result.status.code(), Some(2), "{}", stderr(&result));
    assert!(stderr(&result).contains("missing.obj"), "{}", stderr(&result));
    assert!(!unwritten.exists(), "output written");
}
