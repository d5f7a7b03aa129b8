//! The planned stage (`io::usd_stage`, shared with the `.usda` writer) as a crate file: the same
//! prims, properties, values, metadata and time samples, with the fields usd-core gives each
//! spec when it saves that stage.
use std::io::{Seek, Write};

use super::encode::{Encoder, Rep};
use super::format::{rep, SpecType, Type, SPECIFIER_DEF, UNIFORM, VARYING};
use crate::groom::AttributeKind;
use crate::io::usd_stage::{Data, Prim, Property, Stage, Value};

/// Writes the stage to `out`.
pub fn encode<W: Write + Seek>(stage: &Stage, out: W) -> std::io::Result<W> {
    let mut e = Encoder::new(out)?;
    let mut root = vec![("defaultPrim", e.token_value(&stage.default_prim))];
    root.push(("documentation", e.string_value(&stage.doc)));
    root.push(("metersPerUnit", e.double_value(stage.meters_per_unit)?));
    root.push(("upAxis", e.token_value(stage.up_axis)));
    if let Some(t) = stage.times {
        root.push(("startTimeCode", e.double_value(t.start)?));
        root.push(("endTimeCode", e.double_value(t.end)?));
        root.push(("timeCodesPerSecond", e.double_value(t.per_second)?));
    }
    let names: Vec<&str> = stage.roots.iter().map(|p| p.name.as_str()).collect();
    if !names.is_empty() {
        root.push(("primChildren", e.token_vector(&names)?));
    }
    e.spec(0, SpecType::PseudoRoot, &root);
    for prim in &stage.roots {
        encode_prim(&mut e, 0, prim)?;
    }
    e.finish()
}

fn encode_prim<W: Write + Seek>(e: &mut Encoder<W>, parent: u32, prim: &Prim) -> std::io::Result<()> {
    let path = e.child_path(parent, &prim.name, false);
    let mut properties = Vec::with_capacity(prim.properties.len());
    for property in &prim.properties {
        properties.push(attribute_fields(e, property)?);
    }
    let mut fields = vec![
        ("specifier", rep::inline(Type::Specifier, SPECIFIER_DEF)),
        ("typeName", e.token_value(prim.type_name)),
    ];
    if !prim.properties.is_empty() {
        let names: Vec<&str> = prim.properties.iter().map(|p| p.name.as_str()).collect();
        fields.push(("properties", e.token_vector(&names)?));
    }
    if !prim.children.is_empty() {
        let names: Vec<&str> = prim.children.iter().map(|p| p.name.as_str()).collect();
        fields.push(("primChildren", e.token_vector(&names)?));
    }
    e.spec(path, SpecType::Prim, &fields);
    for (property, fields) in prim.properties.iter().zip(&properties) {
        let property_path = e.child_path(path, &property.name, true);
        e.spec(property_path, SpecType::Attribute, fields);
    }
    for child in &prim.children {
        encode_prim(e, path, child)?;
    }
    Ok(())
}

/// An attribute's fields as usd-core writes them for a `.usda` declaration.
fn attribute_fields<W: Write + Seek>(
    e: &mut Encoder<W>,
    property: &Property,
) -> std::io::Result<Vec<(&'static str, Rep)>> {
    let (field, value) = match &property.value {
        Value::Default(data) => ("default", data_rep(e, data)?),
        Value::TimeSamples(samples) => {
            let times: Vec<f64> = samples.iter().map(|s| s.0).collect();
            let mut values = Vec::with_capacity(samples.len());
            for (_, data) in samples {
                values.push(data_rep(e, data)?);
            }
            ("timeSamples", e.time_samples(&times, &values)?)
        }
    };
    let variability = if property.uniform { UNIFORM } else { VARYING };
    let mut fields = vec![
        ("typeName", e.token_value(property.type_name)),
        ("variability", rep::inline(Type::Variability, variability)),
        ("custom", rep::inline(Type::Bool, 0)),
        (field, value),
    ];
    if let Some(size) = property.element_size {
        fields.push(("elementSize", rep::inline(Type::Int, size as u32 as u64)));
    }
    if let Some(interpolation) = property.interpolation {
        fields.push(("interpolation", e.token_value(interpolation)));
    }
    Ok(fields)
}

fn data_rep<W: Write + Seek>(e: &mut Encoder<W>, data: &Data) -> std::io::Result<Rep> {
    match data {
        Data::Token(token) => Ok(e.token_value(token)),
        Data::Ints { values, components: 1 } => e.int_array(values),
        Data::Ints { values, components } => {
            let kind = [Type::Int, Type::Vec2i, Type::Vec3i, Type::Vec4i][components.clamp(&1, &4) - 1];
            e.array(kind, values.len() / components, bytemuck::cast_slice(values))
        }
        Data::Int(value) => Ok(rep::inline(Type::Int, *value as u32 as u64)),
        Data::WideInts { values, kind } => match kind {
            AttributeKind::UInt => {
                let values: Vec<u32> = values.iter().map(|&v| v as u32).collect();
                e.array(Type::Uint, values.len(), bytemuck::cast_slice(&values))
            }
            AttributeKind::UInt64 => e.array(Type::Uint64, values.len(), bytemuck::cast_slice(&values[..])),
            _ => e.array(Type::Int64, values.len(), bytemuck::cast_slice(&values[..])),
        },
        Data::Bools(values) => {
            let bytes: Vec<u8> = values.iter().map(|&b| b as u8).collect();
            e.array(Type::Bool, bytes.len(), &bytes)
        }
        Data::Floats { values, components: 1 } => e.float_array(values),
        Data::Floats { values, components } => {
            let kind = [Type::Float, Type::Vec2f, Type::Vec3f, Type::Vec4f][components.clamp(&1, &4) - 1];
            e.array(kind, values.len() / components, bytemuck::cast_slice(values))
        }
    }
}
