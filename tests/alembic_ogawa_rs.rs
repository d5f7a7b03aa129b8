//! An independent reader, ogawa-rs 0.4.0 (crates.io), opens coif's static Alembic files: it
//! lists the same objects and properties and reads the same positions, counts, widths and
//! bounds. (It mis-maps samples of animated files, whoever wrote them, so only static files.)
use coif::groom::{attr, Attribute, AttributeRate, CurveBasis, Groom};
use coif::io::write_groom;
use glam::Vec3;
use ogawa_rs::{Archive, BasisType, CurveType, FileReader, PropertyReader, Schema};

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
