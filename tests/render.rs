//! The renderer end to end: energy conservation of the whole path tracer (white furnace),
//! bit-identical images at any thread count, and the `coif render` command line.
mod common;

use coif::generate::{generate, GenerateParams, Style};
use coif::render::integrator::{Lobe, Mode};
use coif::render::light::Environment;
use coif::render::scene::HeadMode;
use coif::render::{render, with_threads, AovSet, RenderSettings};
use common::{coif, dir_listing, path_str, stderr};
use glam::Vec3;

fn small_groom(strands: usize) -> coif::Groom {
    generate(&GenerateParams {
        strands,
        vertices_per_strand: 12,
        style: Style::Curly { radius: 0.008, pitch: 0.03 },
        seed: 3,
        ..Default::default()
    })
    .unwrap()
}

/// A white furnace for the whole integrator: white hair (colour one, so the lobe weights sum to
/// one) alone in a uniform environment of radiance one, no key light. Light is neither created nor
/// lost, so every pixel — hair or not — must come out 1, apart from the little energy the
/// specular lobes lose past the poles.
#[test]
fn white_furnace_image_is_uniformly_one() {
    let groom = small_groom(400);
    let mut settings =
        RenderSettings { width: 40, height: 30, spp: 64, max_depth: 256, ..Default::default() };
    settings.scene.head = HeadMode::Off;
    settings.scene.floor = false;
    settings.scene.width_scale = 20.0; // thick hair: many paths scatter many times
    settings.scene.color = Some(Vec3::ONE);
    settings.key.irradiance = Vec3::ZERO;
    settings.environment = Environment::Constant(Vec3::ONE);
    let image = render(&groom, &settings, &|_, _| {}).unwrap().image;
    let hair: Vec<f32> =
        image.rgba.iter().filter(|p| p[3] > 0.5).map(|p| (p[0] + p[1] + p[2]) / 3.0).collect();
    assert!(hair.len() > 100, "the hair should cover much of the frame ({} pixels)", hair.len());
    let mean = hair.iter().sum::<f32>() / hair.len() as f32;
    assert!((0.97..=1.005).contains(&mean), "mean radiance over hair {mean}, expected 1");
    let worst = hair.iter().fold(0.0f32, |w, &v| w.max((v - 1.0).abs()));
    assert!(worst < 0.1, "a hair pixel is {worst} away from 1");

    // The same fibres absorbing half the light per bounce come out darker: the test can fail.
    settings.scene.color = Some(Vec3::splat(0.5));
    let grey = render(&groom, &settings, &|_, _| {}).unwrap().image;
    let grey_mean = grey.rgba.iter().filter(|p| p[3] > 0.5).map(|p| (p[0] + p[1] + p[2]) / 3.0).sum::<f32>()
        / hair.len() as f32;
    assert!(grey_mean < 0.9, "grey hair in a furnace should darken: {grey_mean}");
}

/// The same furnace with the Chiang lobe: white hair has zero absorption (σa from colour 1), so
/// every fibre passes on all light and the hair vanishes into the uniform environment.
#[test]
fn chiang_white_furnace_image_is_uniformly_one() {
    let groom = small_groom(400);
    let mut settings =
        RenderSettings { width: 40, height: 30, spp: 64, max_depth: 256, ..Default::default() };
    settings.lobe = Lobe::Chiang;
    settings.scene.head = HeadMode::Off;
    settings.scene.floor = false;
    settings.scene.width_scale = 20.0;
    settings.scene.color = Some(Vec3::ONE);
    settings.key.irradiance = Vec3::ZERO;
    settings.environment = Environment::Constant(Vec3::ONE);
    let image = render(&groom, &settings, &|_, _| {}).unwrap().image;
    let hair: Vec<f32> =
        image.rgba.iter().filter(|p| p[3] > 0.5).map(|p| (p[0] + p[1] + p[2]) / 3.0).collect();
    assert!(hair.len() > 100, "the hair should cover much of the frame ({} pixels)", hair.len());
    let mean = hair.iter().sum::<f32>() / hair.len() as f32;
    assert!((0.98..=1.02).contains(&mean), "mean radiance over hair {mean}, expected 1");

    // Melanin absorbs: the furnace darkens, blue most.
    settings.scene.melanin = Some([1.0, 0.0]);
    let dark = render(&groom, &settings, &|_, _| {}).unwrap().image;
    let mean_of =
        |c: usize| dark.rgba.iter().filter(|p| p[3] > 0.5).map(|p| p[c]).sum::<f32>() / hair.len() as f32;
    assert!(mean_of(0) < 0.9 && mean_of(2) < mean_of(0), "{} {}", mean_of(0), mean_of(2));
}

/// One white fibre alone in a uniform environment of radiance one, lit only where the camera sees
/// it: a fibre that absorbs nothing scatters all the light reaching it, so every pixel it covers
/// is 1 — provided nothing shades the fibre but the fibre itself. Rays leaving a fibre used to
/// meet it again (Embree reports the far side of a round curve, and its hit points lie a little
/// inside or outside the tube), so the fibre shadowed its own transmitted light: 0.06 here with
/// the Chiang lobe, and dense hair came out about half as bright as Mitsuba's. Two vertices: the
/// first one's light samples and continuation must find the sky, the second adds nothing unless a
/// ray met the fibre again. Every curve basis (their centre lines are evaluated separately), a
/// wavy fibre, both lobes.
#[test]
fn a_single_white_fibre_scatters_all_light_at_its_first_bounce() {
    use coif::groom::CurveBasis;
    use coif::render::camera::CameraSpec;
    let radius = 0.004;
    // 10 vertices (a whole number of Bézier segments), diagonal, waving by two radii across it.
    let strand: Vec<Vec3> = (0..10)
        .map(|k| {
            let s = k as f32 / 9.0;
            Vec3::new(-0.25 + 0.5 * s, -0.1 + 0.2 * s, 2.0 * radius * (s * 9.0).sin())
        })
        .collect();
    for basis in [CurveBasis::Linear, CurveBasis::BSpline, CurveBasis::CatmullRom, CurveBasis::Bezier] {
        for lobe in [Lobe::Chiang, Lobe::KajiyaKay] {
            let mut groom = coif::Groom::from_strands(std::slice::from_ref(&strand), 2.0 * radius);
            groom.basis = basis;
            let mut settings =
                RenderSettings { width: 48, height: 48, spp: 64, max_depth: 2, lobe, ..Default::default() };
            settings.camera = Some(CameraSpec {
                position: Vec3::new(0.0, 0.0, 1.0),
                target: Vec3::ZERO,
                up: None,
                fov_degrees: Some(2.0),
            });
            settings.scene.head = HeadMode::Off;
            settings.scene.floor = false;
            settings.scene.color = Some(Vec3::ONE);
            settings.key.irradiance = Vec3::ZERO;
            settings.environment = Environment::Constant(Vec3::ONE);
            let image = render(&groom, &settings, &|_, _| {}).unwrap().image;
            let covered: Vec<f32> =
                image.rgba.iter().filter(|p| p[3] > 0.999).map(|p| (p[0] + p[1] + p[2]) / 3.0).collect();
            assert!(
                covered.len() > 100,
                "{basis:?}: the fibre should cross the frame ({} pixels)",
                covered.len()
            );
            let mean = covered.iter().sum::<f32>() / covered.len() as f32;
            assert!(
                (0.985..=1.015).contains(&mean),
                "{basis:?} {lobe:?}: mean radiance over the fibre {mean}, expected 1"
            );
        }
    }
}

/// Pigment attributes out of range stop the render with a usage error naming the attribute and
/// the strand, for either lobe (the groom is checked before anything is shaded).
#[test]
fn bad_pigment_attributes_are_rejected_by_name() {
    use coif::groom::{Attribute, AttributeRate};
    for (name, components, bad) in [("melanin", 1, 12.0f32), ("color", 3, -0.2), ("melanin", 1, f32::NAN)] {
        let mut groom = small_groom(50);
        let n = groom.strand_count();
        let mut data = vec![0.5; n * components];
        data[7 * components] = bad;
        groom.set_attribute(Attribute::new(name, AttributeRate::Strand, components, data));
        let settings =
            RenderSettings { width: 8, height: 8, spp: 1, lobe: Lobe::Chiang, ..Default::default() };
        let error = render(&groom, &settings, &|_, _| {}).err().expect("a bad attribute must fail");
        let message = error.to_string();
        assert!(matches!(error, coif::Error::Usage(_)), "{message}");
        assert!(message.contains(name) && message.contains("strand 7"), "{message}");
    }
}

#[test]
fn image_is_bit_identical_on_one_and_two_threads() {
    let groom = small_groom(1500);
    let mut settings = RenderSettings { width: 64, height: 48, spp: 8, ..Default::default() };
    settings.scene.min_pixel_width = 0.5; // exercise the transparency filter too
    settings.aovs = AovSet { depth: true, tangent: true };
    let chiang = RenderSettings { lobe: Lobe::Chiang, ..settings.clone() };
    let c1 = with_threads(Some(1), || render(&groom, &chiang, &|_, _| {})).unwrap().unwrap();
    let c2 = with_threads(Some(2), || render(&groom, &chiang, &|_, _| {})).unwrap().unwrap();
    assert_eq!(c1.image.encode_png().unwrap(), c2.image.encode_png().unwrap(), "chiang lobe");
    let one = with_threads(Some(1), || render(&groom, &settings, &|_, _| {})).unwrap().unwrap();
    let two = with_threads(Some(2), || render(&groom, &settings, &|_, _| {})).unwrap().unwrap();
    let bits = |i: &coif::render::image::Image| -> Vec<u32> {
        i.rgba
            .iter()
            .flatten()
            .chain(i.aovs.iter().flat_map(|a| a.data.iter()))
            .map(|v| v.to_bits())
            .collect()
    };
    assert_eq!(bits(&one.image), bits(&two.image));
    assert_eq!(one.image.encode_png().unwrap(), two.image.encode_png().unwrap());
    assert!(one.image.rgba.iter().any(|p| p[0] != two.image.rgba[0][0]), "a uniform image proves nothing");
}

/// Widening strands to a pixel with matching transparency keeps their average coverage: the
/// mean image stays close to the true-width render (it does not make hair look denser).
#[test]
fn minimum_pixel_width_keeps_coverage() {
    let groom = small_groom(3000);
    let mut settings = RenderSettings { width: 48, height: 36, spp: 64, ..Default::default() };
    settings.scene.floor = false;
    settings.scene.head = HeadMode::Off;
    settings.mode = Mode::Depth;
    let coverage = |s: &RenderSettings| -> f32 {
        let image = render(&groom, s, &|_, _| {}).unwrap().image;
        image.rgba.iter().map(|p| p[3]).sum::<f32>() / image.rgba.len() as f32
    };
    let true_width = coverage(&settings);
    settings.scene.min_pixel_width = 1.0;
    let widened = coverage(&settings);
    settings.scene.min_pixel_width = 0.0;
    settings.scene.width_scale = 8.0;
    let thicker = coverage(&settings);
    assert!(true_width > 0.01, "some hair in view: {true_width}");
    assert!((widened - true_width).abs() < 0.15 * true_width, "coverage {widened} vs true {true_width}");
    assert!(thicker > 2.0 * true_width, "--width-scale does thicken: {thicker} vs {true_width}");
}

#[test]
fn cli_writes_png_and_exr_with_aovs() {
    let dir = tempfile::tempdir().unwrap();
    let groom = "grooms/sample_curly.hair";
    let png = dir.path().join("preview.png");
    let out =
        coif(&["render", groom, "-o", path_str(&png), "--res", "40x30", "--spp", "4", "--view", "front"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let image = coif::render::image::read_png(&png).unwrap();
    assert_eq!((image.width, image.height), (40, 30));

    let exr_path = dir.path().join("preview.exr");
    let out = coif(&[
        "render",
        groom,
        "-o",
        path_str(&exr_path),
        "--res",
        "40x30",
        "--spp",
        "4",
        "--aov",
        "depth,tangent",
        "--camera",
        "0,0.05,0.8,0,-0.05,0,35",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let exr = exr::prelude::read_all_flat_layers_from_file(&exr_path).unwrap();
    let names: Vec<String> = exr.layer_data[0].channel_data.list.iter().map(|c| c.name.to_string()).collect();
    for name in ["R", "G", "B", "A", "Z", "tangent.X", "tangent.Y", "tangent.Z"] {
        assert!(names.iter().any(|n| n == name), "missing channel {name} in {names:?}");
    }
    assert_eq!(dir_listing(dir.path()), vec!["preview.exr", "preview.png"]);
}

#[test]
fn cli_rejects_bad_requests_without_writing() {
    let dir = tempfile::tempdir().unwrap();
    let out_path = dir.path().join("x.png");
    let groom = "grooms/sample_wavy.hair";
    let cases: &[(&[&str], &str)] = &[
        (&["--res", "40"], "--res"),
        (&["--attribute", "nonexistent"], "nonexistent"),
        (&["--camera", "1,2,3"], "--camera"),
        (&["--spp", "0"], "--spp"),
        (&["--lobe", "chiang", "--melanin", "11"], "--melanin"),
        (&["--lobe", "chiang", "--pheomelanin=-1"], "--pheomelanin"),
        (&["--lobe", "chiang", "--melanin", "NaN"], "--melanin"),
        (&["--lobe", "chiang", "--roughness", "0"], "--roughness"),
        (&["--lobe", "chiang", "--azimuthal-roughness", "1.5"], "--azimuthal-roughness"),
        (&["--lobe", "chiang", "--cuticle-tilt", "45"], "--cuticle-tilt"),
        (&["--color", "0.5,-0.1,0.2"], "--color"),
        (&["--lobe", "phong"], "--lobe"),
    ];
    for (extra, needle) in cases {
        let mut args = vec!["render", groom, "-o", path_str(&out_path), "--spp", "1", "--res", "8x8"];
        args.extend_from_slice(extra);
        let out = coif(&args);
        assert_eq!(out.status.code(), Some(2), "{extra:?}: {}", stderr(&out));
        assert!(stderr(&out).contains(needle), "{extra:?}: message should name {needle}: {}", stderr(&out));
    }
    // An image whose buffers would pass the memory limit is refused before they are made (a
    // 16384² render grew past 7 GB under --max-memory 1G).
    let out =
        coif(&["render", groom, "-o", path_str(&out_path), "--res", "4096x4096", "--max-memory", "100M"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("rendering 4096x4096") && stderr(&out).contains("--max-memory"),
        "{}",
        stderr(&out)
    );
    let jpg = dir.path().join("x.jpg");
    let out = coif(&["render", groom, "-o", path_str(&jpg)]);
    assert_eq!(out.status.code(), Some(2));
    assert!(dir_listing(dir.path()).is_empty());
}

#[test]
fn a_generous_time_budget_changes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.png");
    let b = dir.path().join("b.png");
    let base = ["render", "grooms/sample_wavy.hair", "--res", "32x24", "--spp", "8"];
    let out = coif(&[&base[..], &["-o", path_str(&a)]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    let out = coif(&[&base[..], &["-o", path_str(&b), "--time-budget", "600", "--threads", "1"]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

/// A groom's own mesh (the head or scalp its file brings) is drawn under the hair, and `--head
/// off` leaves it out. A wall 1.5 m in front of the camera must be hit at depth 1.5 by the centre
/// pixel's rays (the depth AOV, to the wall plane), and be lit; without it those rays miss.
#[test]
fn the_grooms_own_mesh_is_drawn_unless_the_head_is_off() {
    // One short strand off to the side, so the centre of the image sees only the wall.
    let mut groom =
        coif::Groom::from_strands(&[vec![Vec3::new(0.3, 0.0, 0.0), Vec3::new(0.3, 0.05, 0.0)]], 1e-3);
    groom.meshes.push(coif::surface_mesh::SurfaceMesh {
        path: "/groom/wall".into(),
        points: vec![
            Vec3::new(-1.0, -1.0, -0.5),
            Vec3::new(1.0, -1.0, -0.5),
            Vec3::new(1.0, 1.0, -0.5),
            Vec3::new(-1.0, 1.0, -0.5),
        ],
        face_counts: vec![4],
        face_indices: vec![0, 1, 2, 3],
        primvars: Vec::new(),
        invisible: false,
        holes: Vec::new(),
    });
    let camera = coif::render::camera::CameraSpec {
        position: Vec3::new(0.0, 0.0, 1.0),
        target: Vec3::ZERO,
        up: None,
        fov_degrees: Some(20.0),
    };
    let mut settings =
        RenderSettings { width: 9, height: 9, spp: 4, camera: Some(camera), ..Default::default() };
    settings.scene.floor = false;
    settings.aovs = AovSet { depth: true, tangent: false };
    let centre = 4 * 9 + 4;
    let shown = render(&groom, &settings, &|_, _| {}).unwrap();
    let depth = shown.image.aovs[0].data[centre];
    assert!((depth - 1.5).abs() < 1e-3, "depth {depth}, the wall is at 1.5");
    assert!(shown.image.rgba[centre][0] > 0.05, "the wall is lit: {:?}", shown.image.rgba[centre]);

    settings.scene.head = HeadMode::Off;
    let hidden = render(&groom, &settings, &|_, _| {}).unwrap();
    assert!(hidden.image.aovs[0].data[centre].is_infinite(), "nothing to hit without the wall");
}

/// A budget bounds a render however many samples are asked for: passes are sized by the time
/// taken (fixed sixteenths of a million samples a pixel ran for hours past a one-second budget),
/// and the image is the render of the samples reached, as a render of that many without a budget
/// (with independent samples: Sobol's are shuffled over the count asked for).
#[test]
fn a_tight_time_budget_bounds_a_huge_render_and_keeps_its_image() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    let base = ["render", "grooms/sample_wavy.hair", "--res", "48x32", "--sampler", "independent"];
    let start = std::time::Instant::now();
    let out = coif(
        &[&base[..], &["--spp", "1000000", "--time-budget", "1", "--json", "-o", path_str(&a)]].concat(),
    );
    let took = start.elapsed().as_secs_f64();
    assert!(out.status.success(), "{}", stderr(&out));
    // Generous for a loaded machine, hours short of the old behaviour.
    assert!(took < 60.0, "a 1 s budget took {took} s");
    let report = common::stdout_json(&out);
    let spp = report["spp"].as_u64().or_else(|| report["stats"]["spp"].as_u64()).expect("spp reported");
    assert!((1..1_000_000).contains(&spp), "{report}");
    let out = coif(&[&base[..], &["--spp", &spp.to_string(), "-o", path_str(&b)]].concat());
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap(), "the budgeted image at {spp} spp");
}
