//! An independent reader, ogawa-rs 0.4.0 (crates.io), opens coif's static Alembic files: it
//! lists the same objects and properties and reads the same positions, counts, widths and
//! bounds. (It mis-maps samples of animated files, whoever wrote them, so only static files.)
use coif::groom::{attr, Attribute, AttributeRate, CurveBasis, Groom};
use coif::io::write_groom;
use glam::Vec3;
use ogawa_rs::{Archive, BasisType, CurveType, FileReader, PropertyReader, Schema};

mod common;

fn groom(basis: CurveBasis) -> Groom {
    let strands: Vec<Vec<Vec3>> = (0..40)
        .map(|s| {
            (0..(3 + s % 5))
                .map(|k| Vec3::new(s as f32 * 0.003, -(k as f32) * 0.01, (s * k) as f32 * 1e-4))
                .collect()
        })
        .collect();
    let mut g = Groom::from_strands(&strands, 0.0);
    g.widths = (0..g.vertex_count()).map(|i| 50e-6 + i as f32 * 1e-8).collect();
    g.root_uvs = Some((0..g.strand_count()).map(|i| [i as f32 * 0.01, 0.5]).collect());
    let n = g.vertex_count();
    g.set_attribute(Attribute::new(attr::COLOR, AttributeRate::Vertex, 3, vec![0.25; 3 * n]));
    g.set_attribute(Attribute::new(
        "wetness",
        AttributeRate::Vertex,
        1,
        (0..n).map(|i| i as f32 / n as f32).collect(),
    ));
    g.basis = basis;
    g
}

/// Names of a compound's sub-properties, recursing into compounds (ogawa-rs's own listing).
fn listing(
    property: &PropertyReader,
    reader: &mut FileReader,
    archive: &Archive,
) -> Vec<(String, Option<Vec<String>>)> {
    let PropertyReader::Compound(compound) = property else { return Vec::new() };
    (0..compound.sub_property_count())
        .map(|i| {
            let name = compound.property_headers[i].name.clone();
            let sub = compound.load_sub_property(i, reader, archive).unwrap();
            let children = matches!(sub, PropertyReader::Compound(_))
                .then(|| listing(&sub, reader, archive).into_iter().map(|(n, _)| n).collect());
            (name, children)
        })
        .collect()
}

#[test]
fn ogawa_rs_reads_coif_static_files() {
    for (basis, expected_type, expected_basis) in [
        (CurveBasis::Linear, CurveType::Linear, BasisType::None),
        (CurveBasis::CatmullRom, CurveType::Cubic, BasisType::Catmullrom),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("static.abc");
        let g = groom(basis);
        write_groom(&path, &g).unwrap();

        let mut reader = FileReader::new(std::fs::File::open(&path).unwrap()).unwrap();
        let archive = Archive::new(&mut reader).unwrap();
        let root = archive.load_root_object(&mut reader).unwrap();
        assert_eq!(root.child_count(), 1);
        assert_eq!(root.children[0].full_name, "/curves");
        let curves =
            root.load_child(0, &mut reader, &archive.indexed_meta_data, &archive.time_samplings).unwrap();
        assert_eq!(curves.child_count(), 0);

        let top = curves.properties().unwrap();
        assert_eq!(top.sub_property_count(), 1);
        assert_eq!(top.property_headers[0].name, ".geom");
        let geom = top.load_sub_property(0, &mut reader, &archive).unwrap();
        let arb = vec![attr::COLOR.to_string(), "wetness".to_string()];
        let expected: Vec<(String, Option<Vec<String>>)> = vec![
            (".selfBnds".into(), None),
            ("P".into(), None),
            ("nVertices".into(), None),
            ("curveBasisAndType".into(), None),
            (".arbGeomParams".into(), Some(arb)),
            ("uv".into(), None),
            ("width".into(), None),
        ];
        assert_eq!(listing(&geom, &mut reader, &archive), expected);

        let Schema::Curves(schema) = Schema::parse(&curves, &mut reader, &archive).unwrap() else {
            panic!("ogawa-rs does not see a curves schema");
        };
        let positions = schema.load_positions_sample(0, &mut reader).unwrap();
        let expected_positions: Vec<[f32; 3]> = g.points.iter().map(|p| p.to_array()).collect();
        assert_eq!(positions, expected_positions);
        let counts = schema.load_n_vertices_sample(0, &mut reader).unwrap();
        assert_eq!(counts, g.vertex_counts().map(|c| c as i32).collect::<Vec<_>>());
        assert_eq!(schema.load_widths_sample(0, &mut reader).unwrap().unwrap(), g.widths);
        let uvs = schema.load_uv_sample(0, &mut reader).unwrap().unwrap();
        assert_eq!(uvs, g.root_uvs.clone().unwrap());
        let (curve_type, _, basis_type) = schema.load_curve_type_sample(0, &mut reader).unwrap();
        assert_eq!((curve_type, basis_type), (expected_type, expected_basis));
        let bounds = schema.load_bounds_sample(0, &mut reader).unwrap();
        let (lo, hi) = g.bounds().unwrap();
        assert_eq!(bounds.min, lo.as_dvec3().to_array());
        assert_eq!(bounds.max, hi.as_dvec3().to_array());
    }
}

/// The interpolation attributes in the types of Unreal's Alembic groom spec, as an independent
/// reader sees them: `groom_closest_guides` int32×3 and `groom_guide_weights` float32×3 per
/// strand (uniform scope), `groom_guide` and `groom_id` int32.
#[test]
fn ogawa_rs_reads_the_interpolation_attributes_in_unreals_types() {
    use coif::guides::{CLOSEST_GUIDES, GUIDE_WEIGHTS};
    let mut g = groom(CurveBasis::Linear);
    let strands = g.strand_count();
    g.guides = Some((0..strands).map(|s| s % 4 == 0).collect());
    g.strand_ids = (0..strands as u32).map(|s| 16_777_215 - 5 * s).collect();
    let closest: Vec<f32> = (0..3 * strands).map(|i| g.strand_ids[(i / 12) * 4] as f32).collect();
    let weights: Vec<f32> = (0..strands).flat_map(|_| [0.5, 0.25, 0.25]).collect();
    g.set_attribute(Attribute::new(CLOSEST_GUIDES, AttributeRate::Strand, 3, closest.clone()));
    g.set_attribute(Attribute::new(GUIDE_WEIGHTS, AttributeRate::Strand, 3, weights.clone()));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("guided.abc");
    write_groom(&path, &g).unwrap();

    let mut reader = FileReader::new(std::fs::File::open(&path).unwrap()).unwrap();
    let archive = Archive::new(&mut reader).unwrap();
    let root = archive.load_root_object(&mut reader).unwrap();
    let curves =
        root.load_child(0, &mut reader, &archive.indexed_meta_data, &archive.time_samplings).unwrap();
    let top = curves.properties().unwrap();
    let PropertyReader::Compound(geom) = top.load_sub_property(0, &mut reader, &archive).unwrap() else {
        panic!(".geom is a compound")
    };
    let PropertyReader::Compound(arb) =
        geom.load_sub_property_by_name(".arbGeomParams", &mut reader, &archive).unwrap().unwrap()
    else {
        panic!(".arbGeomParams is a compound")
    };
    let mut param = |name: &str| {
        let index = arb.find_sub_property_index(name).unwrap_or_else(|| panic!("no {name}"));
        let tokens = arb.property_headers[index].meta_data.tokens.clone();
        let PropertyReader::Array(array) = arb.load_sub_property(index, &mut reader, &archive).unwrap()
        else {
            panic!("{name} is an array")
        };
        (array.load_sample(0, &mut reader).unwrap(), tokens["podExtent"].clone(), tokens["geoScope"].clone())
    };
    let ints = |(values, extent, scope): (ogawa_rs::PodArray, String, String)| match values {
        ogawa_rs::PodArray::I32(v) => (v, extent, scope),
        _ => panic!("not int32"),
    };
    let expected_ids: Vec<i32> = closest.iter().map(|&v| v as i32).collect();
    assert_eq!(ints(param(CLOSEST_GUIDES)), (expected_ids, "3".into(), "uni".into()));
    let ogawa_rs::PodArray::F32(read_weights) = param(GUIDE_WEIGHTS).0 else { panic!("weights not float32") };
    assert_eq!(read_weights, weights);
    assert_eq!(param(GUIDE_WEIGHTS).1, "3");
    let flags: Vec<i32> = g.guides.as_ref().unwrap().iter().map(|&f| f as i32).collect();
    assert_eq!(ints(param("groom_guide")).0, flags);
    assert_eq!(ints(param("groom_id")).0, g.strand_ids.iter().map(|&i| i as i32).collect::<Vec<_>>());

    // And coif reads the ids back exactly (the largest exact in f32, 2^24 - 1, included).
    let back = coif::io::read_groom(&path, &Default::default()).unwrap().groom;
    assert_eq!(back.attribute(CLOSEST_GUIDES).unwrap().floats(), closest);
    assert_eq!(back.strand_ids, g.strand_ids);
}

/// The head mesh of Blender's Alembic, read by coif and written back: ogawa-rs reads coif's
/// PolyMesh as it reads Blender's own (the same points, face counts and clockwise face indices;
/// Blender's Head Xform is the identity), and coif reads back the mesh it wrote.
#[test]
fn ogawa_rs_reads_coif_polymesh_as_blenders() {
    let source = std::path::Path::new("tests/data/blender_groom.abc");
    let groom = coif::io::read_groom(source, &Default::default()).unwrap().groom;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("with_head.abc");
    write_groom(&path, &groom).unwrap();
    let (blender, written) = (common::polymesh_via_ogawa_rs(source), common::polymesh_via_ogawa_rs(&path));
    assert_eq!(written.1, blender.1, "face counts");
    assert_eq!(written.2, blender.2, "face indices (clockwise, as Blender writes them)");
    assert_eq!(written.0.len(), blender.0.len());
    let worst = written
        .0
        .iter()
        .zip(&blender.0)
        .map(|(a, b)| (Vec3::from(*a) - Vec3::from(*b)).length())
        .fold(0.0, f32::max);
    assert!(worst < 1e-6, "points differ by {worst} m");
    let back = coif::io::read_groom(&path, &Default::default()).unwrap().groom;
    assert_eq!(back.meshes, groom.meshes, "coif reads back the mesh it wrote");
}

/// A groom's `normals` and `velocities` (read from USD curves' own attributes, or Houdini's `N`
/// and `v`) are written where AbcGeom's curves schema keeps them, `N` and `.velocities` in the
/// geometry compound, not among the parameters; ogawa-rs reads the velocities back through its
/// curves schema. (ogawa-rs 0.4.0 looks normals up as `n`, so for them only the name is checked.)
#[test]
fn ogawa_rs_finds_normals_and_velocities_where_abcgeom_keeps_them() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("moving.abc");
    let mut g = groom(CurveBasis::Linear);
    let n = g.vertex_count();
    let velocities: Vec<[f32; 3]> = (0..n).map(|i| [0.1, -0.01 * i as f32, 0.5]).collect();
    g.set_attribute(Attribute::new("normals", AttributeRate::Vertex, 3, [0.0, 0.0, 1.0].repeat(n)));
    g.set_attribute(Attribute::new("velocities", AttributeRate::Vertex, 3, velocities.concat()));
    write_groom(&path, &g).unwrap();

    let mut reader = FileReader::new(std::fs::File::open(&path).unwrap()).unwrap();
    let archive = Archive::new(&mut reader).unwrap();
    let root = archive.load_root_object(&mut reader).unwrap();
    let curves =
        root.load_child(0, &mut reader, &archive.indexed_meta_data, &archive.time_samplings).unwrap();
    let geom = curves.properties().unwrap().load_sub_property(0, &mut reader, &archive).unwrap();
    let listed = listing(&geom, &mut reader, &archive);
    let names: Vec<&str> = listed.iter().map(|(name, _)| name.as_str()).collect();
    assert!(names.contains(&"N") && names.contains(&".velocities"), "{names:?}");
    let arb = listed.iter().find(|(name, _)| name == ".arbGeomParams").and_then(|(_, c)| c.clone());
    assert_eq!(arb, Some(vec![attr::COLOR.to_string(), "wetness".to_string()]));
    let Schema::Curves(schema) = Schema::parse(&curves, &mut reader, &archive).unwrap() else {
        panic!("ogawa-rs does not see a curves schema");
    };
    assert_eq!(schema.load_velocities_sample(0, &mut reader).unwrap(), Some(velocities));
}
