//! Helpers shared by the integration tests: run the `coif` binary and inspect what it did.
#![allow(dead_code)]
use std::path::Path;
use std::process::{Command, Output};

use glam::Vec3;

pub fn coif(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_coif")).args(args).output().expect("the coif binary runs")
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

pub fn stdout_json(output: &Output) -> serde_json::Value {
    assert!(output.status.success(), "coif failed: {}", stderr(output));
    serde_json::from_slice(&output.stdout).expect("stdout is one JSON object")
}

pub fn path_str(path: &Path) -> &str {
    path.to_str().expect("test paths are UTF-8")
}

/// Files in a directory, sorted, to check that nothing (not even a temporary) was left behind.
pub fn dir_listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// The colliders a shot simulates a styled groom with: the recipe's obstacles as placed, but the
/// ones its stages press (a pillow, the blow-dry's floor — styling tools, withdrawn by `release`).
#[allow(dead_code)]
pub fn shot_colliders(
    recipe: &coif::style::recipe::Recipe,
    shapes: Vec<coif::interact::obstacles::Shape>,
) -> Vec<coif::interact::obstacles::Shape> {
    use coif::style::recipe::Stage;
    let pressed = |name: &str| {
        recipe.stages.iter().any(|s| matches!(s.get_ref(), Stage::Press { obstacle, .. } if obstacle == name))
    };
    shapes
        .into_iter()
        .zip(&recipe.obstacles)
        .filter(|(_, o)| !pressed(o.get_ref().name()))
        .map(|(s, _)| s)
        .collect()
}

/// Every `step`-th strand of a groom, with its widths and attributes: a preset's recipe on a few
/// strands, so a test stays fast while still going through every stage.
pub fn thin(groom: &coif::Groom, step: usize) -> coif::Groom {
    thin_from(groom, 0, step)
}

/// Every `step`-th strand from strand `first` on (see [`thin`]).
pub fn thin_from(groom: &coif::Groom, first: usize, step: usize) -> coif::Groom {
    let strands: Vec<usize> = (first..groom.strand_count()).step_by(step).collect();
    coif::groups::assemble(&[(groom, &strands)]).expect("a selection of a valid groom is valid")
}

/// Darboux vectors (S1-8) of `points` taken as the shape of `groom`'s strands, in frames
/// parallel-transported from each root, as coif builds them for an imported groom: the
/// curvature a shape gives the bonds to remember.
pub fn darboux(groom: &coif::Groom, points: &[Vec3]) -> Vec<Vec3> {
    let shape = coif::Groom { points: points.to_vec(), ..groom.clone() };
    coif::sim::Rods::from_groom(&shape, &coif::sim::Material::default(), 1.0)
        .expect("a valid shape")
        .rest_darboux()
        .to_vec()
}

/// The share of the shape hair dried in that its rest shape keeps (model.md §2: hydrogen bonds
/// re-formed in a shape remember it with their influence). `before` is the shape before styling,
/// `drying` the poses while the bonds re-formed (evenly spaced in time: each re-forms the same
/// fraction), `rest` the styled rest curves. The least-squares slope, over the `strands`' edge
/// pairs, of the rest shape's change in Darboux vectors on the mean drying shape's change.
pub fn kept_share(
    groom: &coif::Groom,
    strands: &[usize],
    before: &[Vec3],
    drying: &[Vec<Vec3>],
    rest: &[Vec3],
) -> f64 {
    let original = darboux(groom, before);
    let mut dried = vec![Vec3::ZERO; original.len()];
    for pose in drying {
        for (d, (now, was)) in dried.iter_mut().zip(darboux(groom, pose).iter().zip(&original)) {
            *d += (*now - *was) / drying.len() as f32;
        }
    }
    let kept = darboux(groom, rest);
    let (mut along, mut squared) = (0.0f64, 0.0f64);
    for v in strands.iter().flat_map(|&s| groom.strand_range(s)) {
        along += f64::from((kept[v] - original[v]).dot(dried[v]));
        squared += f64::from(dried[v].length_squared());
    }
    along / squared
}

/// The groom's zero-stress rest curves (its exported `rest` attribute) as a groom: the shape its
/// bonds hold free of gravity and contacts.
pub fn rest_shape(groom: &coif::Groom) -> coif::Groom {
    let rest = groom.attribute("rest").expect("a styled groom carries its rest curves").floats();
    let mut shape = groom.clone();
    shape.points = rest.chunks_exact(3).map(Vec3::from_slice).collect();
    shape
}

/// A recipe's text with its last settle run without gravity (model.md §2: the free shape).
pub fn last_settle_without_gravity(recipe: &str) -> String {
    let at =
        recipe.rfind("kind = \"settle\"").expect("the recipe ends on a settle") + "kind = \"settle\"".len();
    format!("{}\ngravity = false{}", &recipe[..at], &recipe[at..])
}

/// For each of `strands` whose tail lay on a rod's surface in `wound` (a pose while the rods
/// held the hair; rods as `(a, b, radius)`), the radius it was wound at and the radius of the
/// same vertices in `rest` (the rest curves).
pub fn wound_and_rest_curls(
    groom: &coif::Groom,
    strands: &[usize],
    wound: &[Vec3],
    rest: &[Vec3],
    rods: &[(Vec3, Vec3, f32)],
) -> Vec<(f32, f32)> {
    let on_a_rod = |p: Vec3| {
        rods.iter().any(|&(a, b, radius)| {
            let axis = (b - a).normalize();
            let along = (p - a).dot(axis);
            let radial = (p - a - axis * along).length();
            (0.0..=a.distance(b)).contains(&along) && (radial / radius - 1.0).abs() < 0.02
        })
    };
    strands
        .iter()
        .filter_map(|&s| {
            let range = groom.strand_range(s);
            let first = range.clone().rev().take_while(|&v| on_a_rod(wound[v])).last()?;
            let wound_radius = coif::analysis::curl_radius(&wound[first..range.end])?;
            let rest_radius = coif::analysis::curl_radius(&rest[first..range.end])?;
            Some((wound_radius, rest_radius))
        })
        .collect()
}

/// The frame a run captured right after simulation step `step` (`StyleOptions::frames_per_second`
/// frames, at steps of `dt`; frame 0 is the groom before styling).
pub fn frame_after(styled: &coif::style::Styled, dt: f32, step: u64) -> usize {
    let every = (1.0 / (styled.frames_per_second * dt)).round() as u64;
    assert_eq!(step % every, 0, "step {step} falls between frames captured every {every} steps");
    (step / every) as usize
}

/// The head frame a styling run placed its recipe in.
pub fn head_frame(styled: &coif::style::Styled) -> coif::style::head_frame::HeadFrame {
    let f = styled.report.head_frame.expect("the recipe is written in the head frame");
    coif::style::head_frame::HeadFrame::new(f.center.into(), f.up.into(), f.front.into(), f.size).unwrap()
}

/// A head-frame recipe's rods in the world of `frame`, as `(a, b, radius)`.
pub fn rods_in_world(
    recipe: &coif::style::recipe::Recipe,
    frame: &coif::style::head_frame::HeadFrame,
) -> Vec<(Vec3, Vec3, f32)> {
    recipe
        .rods
        .iter()
        .map(|r| r.get_ref())
        .map(|r| (frame.point(r.a.into()), frame.point(r.b.into()), r.radius * frame.size()))
        .collect()
}

/// The hydrogen bonds' influence: their share of a recipe's bonds (S1-15's `f_hyd / Σ f`).
pub fn hydrogen_influence(recipe: &coif::style::recipe::Recipe) -> f32 {
    let b = &recipe.bonds;
    b.hydrogen / (b.hydrogen + b.ionic + b.disulfide + b.peptide)
}

/// Steps a recipe's first dry stage takes to dry hair that is wet through: its evaporation
/// (per second, times the stage's heat) takes the water from 1 to 0 at an even rate.
pub fn drying_steps(recipe: &coif::style::recipe::Recipe) -> u64 {
    let heat = recipe
        .stages
        .iter()
        .find_map(|s| match s.get_ref() {
            coif::style::recipe::Stage::Dry { heat, .. } => Some(*heat),
            _ => None,
        })
        .expect("the recipe dries the hair");
    (1.0 / (recipe.wetness.evaporation * heat * recipe.settings.dt)).round() as u64
}

/// The median of some values.
pub fn median(mut values: Vec<f32>) -> f32 {
    assert!(!values.is_empty(), "no values to take the median of");
    values.sort_by(f32::total_cmp);
    values[values.len() / 2]
}

/// The one PolyMesh of an Alembic file as ogawa-rs (an independent reader) sees it: points,
/// face counts and face indices.
pub fn polymesh_via_ogawa_rs(path: &Path) -> (Vec<[f32; 3]>, Vec<i32>, Vec<i32>) {
    use ogawa_rs::{Archive, FileReader, Schema};
    let mut reader = FileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    let archive = Archive::new(&mut reader).unwrap();
    let mut stack = vec![archive.load_root_object(&mut reader).unwrap()];
    while let Some(object) = stack.pop() {
        if let Ok(Schema::PolyMesh(mesh)) = Schema::parse(&object, &mut reader, &archive) {
            return (
                mesh.load_vertices_sample(0, &mut reader).unwrap(),
                mesh.load_facecounts_sample(0, &mut reader).unwrap(),
                mesh.load_faceindices_sample(0, &mut reader).unwrap(),
            );
        }
        for i in 0..object.child_count() {
            stack.push(
                object
                    .load_child(i, &mut reader, &archive.indexed_meta_data, &archive.time_samplings)
                    .unwrap(),
            );
        }
    }
    panic!("{}: ogawa-rs finds no PolyMesh", path.display());
}

/// Every curves object's `width` as ogawa-rs (an independent Alembic reader) reads it: the
/// object's full name, the `geoScope` metadata and the values of the first sample.
#[allow(dead_code)]
pub fn curve_widths_via_ogawa_rs(path: &Path) -> Vec<(String, String, Vec<f32>)> {
    use ogawa_rs::{PodArray, PropertyReader};
    curves_via_ogawa_rs(path, |name, geom, reader, archive| {
        let PropertyReader::Compound(geom) = geom else { panic!("{name}: .geom is not a compound") };
        let index = geom.find_sub_property_index("width").expect("a width property");
        let scope =
            geom.property_headers[index].meta_data.tokens.get("geoScope").cloned().unwrap_or_default();
        let Ok(PropertyReader::Array(array)) = geom.load_sub_property(index, reader, archive) else {
            panic!("{name}: width is not an array")
        };
        let Ok(PodArray::F32(values)) = array.load_sample(0, reader) else { panic!("width is not float32") };
        (scope, values)
    })
    .into_iter()
    .map(|(name, (scope, values))| (name, scope, values))
    .collect()
}

/// Every curves object's int32 `.arbGeomParams` member `param` (first sample) as ogawa-rs reads
/// it, by the object's full name; `None` for an object without it.
#[allow(dead_code)]
pub fn curve_int_param_via_ogawa_rs(path: &Path, param: &str) -> Vec<(String, Option<Vec<i32>>)> {
    use ogawa_rs::{PodArray, PropertyReader};
    curves_via_ogawa_rs(path, |name, geom, reader, archive| {
        let PropertyReader::Compound(geom) = geom else { panic!("{name}: .geom is not a compound") };
        let Ok(Some(PropertyReader::Compound(arb))) =
            geom.load_sub_property_by_name(".arbGeomParams", reader, archive)
        else {
            return None;
        };
        let index = arb.find_sub_property_index(param)?;
        let Ok(PropertyReader::Array(array)) = arb.load_sub_property(index, reader, archive) else {
            panic!("{name}: {param} is not an array")
        };
        let Ok(PodArray::I32(values)) = array.load_sample(0, reader) else { panic!("{param} is not int32") };
        Some(values)
    })
}

/// What `read` finds in each curves object's `.geom` compound, by the object's full name, in
/// name order, as ogawa-rs walks the archive.
#[allow(dead_code)]
fn curves_via_ogawa_rs<T>(
    path: &Path,
    mut read: impl FnMut(&str, &ogawa_rs::PropertyReader, &mut ogawa_rs::FileReader, &ogawa_rs::Archive) -> T,
) -> Vec<(String, T)> {
    use ogawa_rs::{Archive, FileReader, Schema};
    let mut reader = FileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    let archive = Archive::new(&mut reader).unwrap();
    let mut found = Vec::new();
    let mut stack = vec![archive.load_root_object(&mut reader).unwrap()];
    while let Some(object) = stack.pop() {
        if let Ok(Schema::Curves(_)) = Schema::parse(&object, &mut reader, &archive) {
            let top = object.properties().unwrap();
            let geom = top.load_sub_property(0, &mut reader, &archive).unwrap();
            let name = object.header.full_name.clone();
            found.push((name.clone(), read(&name, &geom, &mut reader, &archive)));
        }
        for i in 0..object.child_count() {
            stack.push(
                object
                    .load_child(i, &mut reader, &archive.indexed_meta_data, &archive.time_samplings)
                    .unwrap(),
            );
        }
    }
    found.sort_by(|a, b| a.0.cmp(&b.0));
    found
}

pub mod usd;

/// Every object's AbcGeom `visible` samples (int8: 0 hidden, 1 visible, -1 deferred) as
/// ogawa-rs (an independent Alembic reader) reads them, by the object's full name, in name
/// order; objects without the property are left out.
#[allow(dead_code)]
pub fn visibility_via_ogawa_rs(path: &Path) -> Vec<(String, Vec<i8>)> {
    use ogawa_rs::{Archive, FileReader, PodArray, PropertyReader};
    let mut reader = FileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    let archive = Archive::new(&mut reader).unwrap();
    let mut found = Vec::new();
    let mut stack = vec![archive.load_root_object(&mut reader).unwrap()];
    while let Some(object) = stack.pop() {
        let top = object.properties();
        if let Some(index) = top.and_then(|p| p.find_sub_property_index("visible")) {
            let property = top.unwrap().load_sub_property(index, &mut reader, &archive).unwrap();
            let PropertyReader::Scalar(mut visible) = property else { panic!("visible is not a scalar") };
            // A header without explicit changes means "every sample after the first changes":
            // Alembic's first changed sample is then 1; ogawa-rs 0.4 takes 0 and reads each
            // sample from the next one's slot.
            let header = &mut visible.header;
            if header.first_changed_index == 0 && header.last_changed_index > 0 {
                header.first_changed_index = 1;
            }
            let samples = (0..visible.sample_count())
                .map(|k| match visible.load_sample(k, &mut reader).unwrap() {
                    PodArray::I8(v) => v[0],
                    other => panic!("{}: visible is {other:?}, not int8", object.header.full_name),
                })
                .collect();
            found.push((object.header.full_name.clone(), samples));
        }
        for i in 0..object.child_count() {
            stack.push(
                object
                    .load_child(i, &mut reader, &archive.indexed_meta_data, &archive.time_samplings)
                    .unwrap(),
            );
        }
    }
    found.sort();
    found
}
