//! The user's shot in a render: a `UsdGeom.Camera` and `UsdLux` lights read from a stage, checked
//! against what usd-core (pxr) itself predicts for the same stage (`tests/usd/pxr_shot.py`), and
//! bad camera or light values refused with exit 2 naming the prim and the attribute.
mod common;

use std::path::Path;
use std::process::Command;

use common::usd::python;
use common::{coif, dir_listing, path_str, stderr};

/// Runs the pxr shot script and parses the JSON it prints.
fn pxr_shot(args: &[&str]) -> serde_json::Value {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/usd/pxr_shot.py");
    let output = Command::new(python()).arg(script).args(args).output().expect("the project's Python runs");
    assert!(output.status.success(), "pxr_shot {args:?}: {}", String::from_utf8_lossy(&output.stderr));
    serde_json::from_slice(&output.stdout).expect("pxr_shot prints JSON")
}

/// An EXR's channel `name`, row-major.
fn channel(path: &Path, name: &str) -> (usize, usize, Vec<f32>) {
    let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
    let layer = &image.layer_data[0];
    let size = layer.size;
    let channel = layer.channel_data.list.iter().find(|c| c.name.to_string() == name).expect("the channel");
    (size.0, size.1, channel.sample_data.values_as_f32().collect())
}

/// A camera nested under a rotated parent, rolled, in a Z-up centimetre stage, with a 4:3 aperture
/// rendered at 2:1 and at 2:3: the hair tufts pxr projects to given pixels cover those pixels in
/// coif's render (alpha-weighted centroid within 0.75 px), and nothing else is covered.
#[test]
fn usd_camera_frames_points_where_pxr_projects_them() {
    let dir = tempfile::tempdir().unwrap();
    for (width, height, extension) in [(96, 48, "usda"), (40, 60, "usdc")] {
        let authored = dir.path().join(format!("shot_{width}x{height}.usda"));
        let predicted = pxr_shot(&["camera", path_str(&authored), &width.to_string(), &height.to_string()]);
        let stage = dir.path().join(format!("shot_{width}x{height}.{extension}"));
        if extension == "usdc" {
            common::usd::probe(&["export", path_str(&authored), path_str(&stage)]);
        }
        let exr = dir.path().join(format!("render_{width}x{height}.exr"));
        let res = format!("{width}x{height}");
        let out = coif(&[
            "render",
            path_str(&stage),
            "--scene",
            path_str(&stage),
            "-o",
            path_str(&exr),
            "--res",
            &res,
            "--spp",
            "64",
            "--no-floor",
            "--head",
            "off",
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let (w, h, alpha) = channel(&exr, "A");
        assert_eq!((w, h), (width, height));
        let pixels: Vec<[f64; 2]> = predicted["pixels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()])
            .collect();
        let window = 5.0;
        let mut claimed = 0.0;
        for [px, py] in &pixels {
            let (mut sum, mut sx, mut sy) = (0.0, 0.0, 0.0);
            for y in 0..h {
                for x in 0..w {
                    let (cx, cy) = (x as f64 + 0.5, y as f64 + 0.5);
                    if (cx - px).abs() <= window && (cy - py).abs() <= window {
                        let a = alpha[y * w + x] as f64;
                        sum += a;
                        sx += a * cx;
                        sy += a * cy;
                    }
                }
            }
            assert!(sum > 0.05, "{res}: nothing covers the tuft pxr puts at ({px:.2}, {py:.2})");
            let (cx, cy) = (sx / sum, sy / sum);
            let miss = ((cx - px).powi(2) + (cy - py).powi(2)).sqrt();
            eprintln!("{res}: pxr ({px:.2}, {py:.2}), coif ({cx:.2}, {cy:.2}), {miss:.3} px");
            assert!(miss < 0.75, "{res}: the tuft at pxr's ({px:.2}, {py:.2}) renders at ({cx:.2}, {cy:.2})");
            claimed += sum;
        }
        let total: f64 = alpha.iter().map(|&a| a as f64).sum();
        assert!(total - claimed < 1e-3 * total.max(1.0), "{res}: coverage away from every tuft");
    }
}

/// Mean luminance of the left and right halves of an RGB EXR.
fn half_luminances(path: &Path) -> (f64, f64) {
    let (w, h, r) = channel(path, "R");
    let (_, _, g) = channel(path, "G");
    let (_, _, b) = channel(path, "B");
    let (mut left, mut right) = (0.0, 0.0);
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let l = 0.2126 * r[i] as f64 + 0.7152 * g[i] as f64 + 0.0722 * b[i] as f64;
            if x < w / 2 {
                left += l;
            } else {
                right += l;
            }
        }
    }
    (left, right)
}

/// A distant light and a sphere light, placed by pxr to one side and then the other of a Z-up
/// centimetre stage, light the side of the head and hair that pxr's own camera projection puts
/// them on; mirrored placements light the other side.
#[test]
fn usd_lights_light_the_side_pxr_puts_them_on() {
    let dir = tempfile::tempdir().unwrap();
    for kind in ["distant", "sphere"] {
        for side in ["1", "-1"] {
            let stage = dir.path().join(format!("{kind}{side}.usda"));
            let predicted = pxr_shot(&["light", path_str(&stage), kind, side])["side"].as_i64().unwrap();
            let exr = dir.path().join(format!("{kind}{side}.exr"));
            let out = coif(&[
                "render",
                "grooms/sample_wavy.hair",
                "--scene",
                path_str(&stage),
                "-o",
                path_str(&exr),
                "--res",
                "48x48",
                "--spp",
                "16",
                "--no-floor",
            ]);
            assert!(out.status.success(), "{}", stderr(&out));
            let (left, right) = half_luminances(&exr);
            eprintln!("{kind} towards {side}: pxr says side {predicted}; left {left:.2}, right {right:.2}");
            let (lit, unlit) = if predicted > 0 { (right, left) } else { (left, right) };
            assert!(lit > 1.5 * unlit, "{kind} {side}: lit half {lit:.3} vs unlit {unlit:.3}");
        }
    }
}

/// A TOML shot with every light type (distant, sphere, rect, dome) renders bit-identically on one
/// and two threads.
#[test]
fn scene_file_lights_are_bit_identical_on_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("shot.toml");
    std::fs::write(
        &scene,
        r#"
[camera]
position = [0.1, 0.05, 0.7]
target = [0, -0.05, 0]
fov = 30
[[lights]]
type = "distant"
direction = [-0.5, 0.8, 0.4]
[[lights]]
type = "sphere"
position = [0.4, 0.2, 0.4]
radius = 0.05
intensity = 30
[[lights]]
type = "rect"
position = [-0.3, 0.5, 0.3]
target = [0, 0, 0]
width = 0.3
height = 0.2
intensity = 8
[[lights]]
type = "dome"
intensity = 0.3
[floor]
height = -0.3
albedo = [0.2, 0.3, 0.4]
"#,
    )
    .unwrap();
    let mut images = Vec::new();
    for threads in ["1", "2"] {
        let exr = dir.path().join(format!("t{threads}.exr"));
        let out = coif(&[
            "render",
            "grooms/sample_curly.hair",
            "--scene",
            path_str(&scene),
            "-o",
            path_str(&exr),
            "--res",
            "40x30",
            "--spp",
            "8",
            "--lobe",
            "chiang",
            "--threads",
            threads,
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        images.push(std::fs::read(&exr).unwrap());
    }
    assert_eq!(images[0], images[1], "one and two threads differ");
}

/// Bad cameras and lights: exit 2 naming the prim and the attribute, nothing written.
#[test]
fn bad_camera_and_light_values_exit_2_naming_prim_and_attribute() {
    let dir = tempfile::tempdir().unwrap();
    let cases: &[(&str, &str, &str)] = &[
        ("def Camera \"cam\" { float focalLength = -35 }", "/shot/cam", "focalLength"),
        ("def Camera \"cam\" { float focalLength = nan }", "/shot/cam", "focalLength"),
        ("def Camera \"cam\" { float verticalAperture = inf }", "/shot/cam", "verticalAperture"),
        ("def Camera \"cam\" { token projection = \"orthographic\" }", "/shot/cam", "projection"),
        ("def Camera \"cam\" { float horizontalApertureOffset = 2 }", "/shot/cam", "horizontalApertureOffset"),
        ("def DistantLight \"key\" { float inputs:intensity = -1 }", "/shot/key", "inputs:intensity"),
        ("def DistantLight \"key\" { float inputs:intensity = nan }", "/shot/key", "inputs:intensity"),
        ("def DistantLight \"key\" { float inputs:angle = 400 }", "/shot/key", "inputs:angle"),
        ("def DistantLight \"key\" { float inputs:exposure = 1e6 }", "/shot/key", "inputs:exposure"),
        ("def DistantLight \"key\" { color3f inputs:color = (1, -0.5, 1) }", "/shot/key", "inputs:color"),
        ("def SphereLight \"bulb\" { float inputs:radius = 0 }", "/shot/bulb", "inputs:radius"),
        ("def SphereLight \"bulb\" { float inputs:radius = -2 }", "/shot/bulb", "inputs:radius"),
        (
            "def SphereLight \"bulb\" { float3 xformOp:scale = (1, 2, 1)\n uniform token[] xformOpOrder = [\"xformOp:scale\"] }",
            "/shot/bulb",
            "scales",
        ),
        ("def RectLight \"box\" { float inputs:width = 0 }", "/shot/box", "inputs:width"),
        ("def DomeLight \"sky\" { asset inputs:texture:file = @sky.exr@ }", "/shot/sky", "inputs:texture:file"),
        ("def DomeLight \"sky\" { float inputs:intensity = inf }", "/shot/sky", "inputs:intensity"),
        ("def DiskLight \"disk\" { }", "/shot/disk", "DiskLight"),
        ("def CylinderLight \"tube\" { }", "/shot/tube", "CylinderLight"),
    ];
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    let image = out_dir.join("x.png");
    for (index, (prim, path, attribute)) in cases.iter().enumerate() {
        let stage = dir.path().join(format!("bad{index}.usda"));
        std::fs::write(&stage, format!("#usda 1.0\n\ndef Xform \"shot\"\n{{\n    {prim}\n}}\n")).unwrap();
        let out = coif(&[
            "render",
            "grooms/sample_wavy.hair",
            "--scene",
            path_str(&stage),
            "-o",
            path_str(&image),
            "--res",
            "8x8",
            "--spp",
            "1",
        ]);
        let message = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{prim}: {message}");
        assert!(
            message.contains(path) && message.contains(attribute),
            "{prim}: should name {path} and {attribute}: {message}"
        );
    }
    assert!(dir_listing(&out_dir).is_empty(), "nothing written");
}

/// A shot split over layers as pipelines keep it: the lights in a sublayer, the camera rig
/// referenced from a `.usdc` with an `over` of its lens in a variant the stage selects. coif's own
/// composer must give the same render, bit for bit, as the stage pxr flattens; with the other
/// variant flattened the render differs, so the selection is what decides the lens.
#[test]
fn composed_scene_renders_as_the_stage_pxr_flattens() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name);
    std::fs::write(
        path("rig.usda"),
        r#"#usda 1.0
(
    defaultPrim = "rig"
)

def Xform "rig"
{
    double3 xformOp:translate = (0.04, -0.06, 0.75)
    uniform token[] xformOpOrder = ["xformOp:translate"]

    def Camera "cam"
    {
        float focalLength = 35
        float horizontalAperture = 24
        float verticalAperture = 18
    }
}
"#,
    )
    .unwrap();
    std::fs::write(
        path("lights.usda"),
        r#"#usda 1.0

def Xform "shot"
{
    def DistantLight "key"
    {
        float inputs:intensity = 3
        float inputs:angle = 1
        float3 xformOp:rotateXYZ = (-40, 30, 0)
        uniform token[] xformOpOrder = ["xformOp:rotateXYZ"]
    }

    def DomeLight "sky"
    {
        float inputs:intensity = 0.4
        color3f inputs:color = (0.6, 0.7, 1)
    }
}
"#,
    )
    .unwrap();
    common::usd::probe(&["export", path_str(&path("rig.usda")), path_str(&path("rig.usdc"))]);
    std::fs::write(
        path("shot.usda"),
        r#"#usda 1.0
(
    subLayers = [@./lights.usda@]
)

over "shot" (
    variants = {
        string lens = "tele"
    }
    prepend variantSets = "lens"
)
{
    def Xform "camera" (
        prepend references = @./rig.usdc@
    )
    {
    }

    variantSet "lens" = {
        "tele" {
            over "camera"
            {
                over "cam"
                {
                    float focalLength = 85
                }
            }
        }
        "wide" {
            over "camera"
            {
                over "cam"
                {
                    float focalLength = 24
                }
            }
        }
    }
}
"#,
    )
    .unwrap();
    let jobs = path("jobs.json");
    let flat = |name: &str, lens: &str| {
        serde_json::json!([
            "flatten",
            path_str(&path("shot.usda")),
            path_str(&path(name)),
            format!("lens={lens}")
        ])
    };
    std::fs::write(
        &jobs,
        serde_json::json!([flat("tele.usda", "tele"), flat("wide.usda", "wide")]).to_string(),
    )
    .unwrap();
    common::usd::probe(&["batch", path_str(&jobs)]);
    let render = |scene: &str| {
        let exr = path(&format!("{scene}.exr"));
        let out = coif(&[
            "render",
            "grooms/sample_curly.hair",
            "--scene",
            path_str(&path(scene)),
            "-o",
            path_str(&exr),
            "--res",
            "48x36",
            "--spp",
            "4",
            "--no-floor",
        ]);
        assert!(out.status.success(), "render --scene {scene}: {}", stderr(&out));
        channel(&exr, "R").2
    };
    let composed = render("shot.usda");
    assert!(composed.iter().any(|&v| v > 0.0), "the composed shot renders black");
    assert!(composed == render("tele.usda"), "coif's composition renders unlike pxr's flattened stage");
    assert!(
        composed != render("wide.usda"),
        "the lens variant changes nothing: the test would not see a wrong one"
    );
}
