//! A groom as a crate file: the same stage the `.usda` writer produces (`/Groom` Xform, one
//! `BasisCurves` prim `Strands`, the same primvars, metadata and time samples), with the
//! primvar plan and extent taken from that writer so both formats always agree.
use std::io::{Seek, Write};

use glam::Vec3;

use super::encode::{Encoder, Rep};
use super::format::{rep, SpecType, Type, SPECIFIER_DEF, UNIFORM, VARYING};
use crate::groom::Groom;
use crate::io::usda::{self, PrimvarData, TimeCodes};

/// Points over time: every frame's points and the time codes (frame `k` at `start + k`).
pub struct Animation<'a> {
    pub frames: &'a [Vec<Vec3>],
    pub times: TimeCodes,
}

/// Writes the stage to `out`.
pub fn encode<W: Write + Seek>(groom: &Groom, animation: Option<&Animation>, out: W) -> std::io::Result<W> {
    let mut e = Encoder::new(out)?;
    let mut properties: Vec<(String, Vec<(&'static str, Rep)>)> = Vec::new();
    let mut uniform_token = |e: &mut Encoder<W>, name: &str, value: &str| {
        let value = e.token_value(value);
        let fields = attribute_fields(e, "token", UNIFORM, value, "default", None);
        properties.push((name.to_string(), fields));
    };
    let (curve_type, basis) = usda::curve_type_and_basis(groom.basis);
    if let Some(basis) = basis {
        uniform_token(&mut e, "basis", basis);
    }
    uniform_token(&mut e, "type", curve_type);
    uniform_token(&mut e, "wrap", "nonperiodic");

    let counts: Vec<i32> = groom.vertex_counts().map(|c| c as i32).collect();
    let value = e.int_array(&counts)?;
    properties.push((
        "curveVertexCounts".into(),
        attribute_fields(&mut e, "int[]", VARYING, value, "default", None),
    ));
    let value = e.float_array(&groom.widths)?;
    properties.push((
        "widths".into(),
        attribute_fields(&mut e, "float[]", VARYING, value, "default", Some("vertex")),
    ));

    for primvar in usda::plan_primvars(groom).0 {
        let value = match &primvar.data {
            PrimvarData::Floats { values, components: 1 } => e.float_array(values)?,
            PrimvarData::Floats { values, components } => {
                let kind = [Type::Float, Type::Vec2f, Type::Vec3f, Type::Vec4f][components - 1];
                e.array(kind, values.len() / components, bytemuck::cast_slice(values))?
            }
            PrimvarData::UVs(uvs) => e.array(Type::Vec2f, uvs.len(), bytemuck::cast_slice(uvs))?,
            PrimvarData::Ints(values) => {
                let ints: Vec<i32> = values.iter().map(|&v| v as i32).collect();
                e.int_array(&ints)?
            }
            PrimvarData::IntTuples { values, components: 1 } => {
                let ints: Vec<i32> = values.iter().map(|&v| v.round() as i32).collect();
                e.int_array(&ints)?
            }
            PrimvarData::IntTuples { values, components } => {
                let kind = [Type::Int, Type::Vec2i, Type::Vec3i, Type::Vec4i][components - 1];
                let ints: Vec<i32> = values.iter().map(|&v| v.round() as i32).collect();
                e.array(kind, ints.len() / components, bytemuck::cast_slice(&ints))?
            }
        };
        let fields = attribute_fields(
            &mut e,
            primvar.usd_type,
            VARYING,
            value,
            "default",
            Some(primvar.interpolation),
        );
        properties.push((format!("primvars:{}", primvar.name), fields));
    }

    let vec3s = |e: &mut Encoder<W>, points: &[Vec3]| {
        e.array(Type::Vec3f, points.len(), bytemuck::cast_slice(points))
    };
    match animation {
        None => {
            let value = vec3s(&mut e, &groom.points)?;
            properties.push((
                "points".into(),
                attribute_fields(&mut e, "point3f[]", VARYING, value, "default", None),
            ));
            if let Some(extent) = usda::extent(&groom.points, &groom.widths) {
                let value = vec3s(&mut e, &extent)?;
                properties.push((
                    "extent".into(),
                    attribute_fields(&mut e, "float3[]", VARYING, value, "default", None),
                ));
            }
        }
        Some(animation) => {
            let times: Vec<f64> =
                (0..animation.frames.len()).map(|k| animation.times.start + k as f64).collect();
            let mut points = Vec::with_capacity(times.len());
            let mut extents = Vec::with_capacity(times.len());
            for frame in animation.frames {
                points.push(vec3s(&mut e, frame)?);
                if let Some(extent) = usda::extent(frame, &groom.widths) {
                    extents.push(vec3s(&mut e, &extent)?);
                }
            }
            let value = e.time_samples(&times, &points)?;
            properties.push((
                "points".into(),
                attribute_fields(&mut e, "point3f[]", VARYING, value, "timeSamples", None),
            ));
            if extents.len() == times.len() && !times.is_empty() {
                let value = e.time_samples(&times, &extents)?;
                properties.push((
                    "extent".into(),
                    attribute_fields(&mut e, "float3[]", VARYING, value, "timeSamples", None),
                ));
            }
        }
    }

    // Specs: the pseudo-root with the stage metadata, the Xform, the curves and their attributes.
    let groom_path = e.child_path(0, "Groom", false);
    let strands_path = e.child_path(groom_path, "Strands", false);
    let mut root = vec![("defaultPrim", e.token_value("Groom"))];
    root.push(("documentation", e.string_value(concat!("Written by coif ", env!("CARGO_PKG_VERSION")))));
    root.push(("metersPerUnit", e.double_value(1.0)?));
    root.push(("upAxis", e.token_value("Y")));
    if let Some(animation) = animation {
        let t = animation.times;
        root.push(("startTimeCode", e.double_value(t.start)?));
        root.push(("endTimeCode", e.double_value(t.end)?));
        root.push(("timeCodesPerSecond", e.double_value(t.per_second)?));
    }
    root.push(("primChildren", e.token_vector(&["Groom"])?));
    e.spec(0, SpecType::PseudoRoot, &root);
    let def = rep::inline(Type::Specifier, SPECIFIER_DEF);
    let xform = vec![
        ("specifier", def),
        ("typeName", e.token_value("Xform")),
        ("primChildren", e.token_vector(&["Strands"])?),
    ];
    e.spec(groom_path, SpecType::Prim, &xform);
    let names: Vec<&str> = properties.iter().map(|(n, _)| n.as_str()).collect();
    let curves = vec![
        ("specifier", def),
        ("typeName", e.token_value("BasisCurves")),
        ("properties", e.token_vector(&names)?),
    ];
    e.spec(strands_path, SpecType::Prim, &curves);
    for (name, fields) in &properties {
        let path = e.child_path(strands_path, name, true);
        e.spec(path, SpecType::Attribute, fields);
    }
    e.finish()
}

/// An attribute's fields as usd-core writes them for a `.usda` declaration.
fn attribute_fields<W: Write + Seek>(
    e: &mut Encoder<W>,
    type_name: &str,
    variability: u64,
    value: Rep,
    value_field: &'static str,
    interpolation: Option<&str>,
) -> Vec<(&'static str, Rep)> {
    let mut fields = vec![
        ("typeName", e.token_value(type_name)),
        ("variability", rep::inline(Type::Variability, variability)),
        ("custom", rep::inline(Type::Bool, 0)),
        (value_field, value),
    ];
    if let Some(interpolation) = interpolation {
        fields.push(("interpolation", e.token_value(interpolation)));
    }
    fields
}
