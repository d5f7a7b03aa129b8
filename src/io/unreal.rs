//! Epic's groom conventions for Unreal's importers (`--unreal`), as far as they are the same
//! for both formats: which strand data becomes which `groom_*` attribute. The Alembic writer
//! names its parameters itself (`alembic::curves_write`); USD output is this groom written as
//! usual, plus the groom spec version as `userProperties:groom_*` on the root prim.
//!
//! What Unreal reads (its Alembic and USD groom translators): only names with the `groom_`
//! prefix; per strand `groom_guide`, `groom_group_id`, `groom_id` (int), `groom_root_uv`
//! (float2); per vertex `groom_color` (float3); widths from Alembic `width`/`groom_width` or USD
//! `widths`, scaled to centimetres by the file's units.
use std::path::{Path, PathBuf};

use crate::groom::{attr, Attribute, AttributeData, AttributeKind, AttributeRate, CurveGroup, Groom};

use super::alembic::curves_write::epic;

/// Blender's per-curve surface UV (USD export), the root UV Unreal wants when a groom has none.
pub const SURFACE_UV: &str = "surface_uv_coordinate";

/// Root UVs from the surface UV when the groom has none of its own (both formats).
pub fn with_root_uvs(groom: &Groom) -> Option<Groom> {
    let uv = groom.attribute(SURFACE_UV)?;
    if groom.root_uvs.is_some() || uv.rate != AttributeRate::Strand || uv.components != 2 {
        return None;
    }
    let mut out = groom.clone();
    out.root_uvs = Some(uv.floats().chunks_exact(2).map(|c| [c[0], c[1]]).collect());
    for group in out.groups.iter_mut().filter(|g| !g.carries(SURFACE_UV)) {
        group.missing.push(CurveGroup::ROOT_UVS.to_string());
    }
    Some(out)
}

/// An attribute under the name Unreal's USD importer reads: `color` as `groom_color`, every other
/// name prefixed `groom_` unless it has the prefix.
pub fn renamed_for_usd(mut attribute: Attribute) -> Attribute {
    // The roles coif's own names give their USD types (`rest` is `point3f[]`, `color`
    // `color3f[]`) go with them, so a renamed `groom_rest` still moves with the points.
    if attribute.kind == AttributeKind::Float && attribute.components == 3 {
        match attribute.name.as_str() {
            crate::io::usda::names::REST => attribute.kind = AttributeKind::Point,
            attr::COLOR => attribute.kind = AttributeKind::Color,
            _ => {}
        }
    }
    attribute.name = name_for_usd(&attribute.name);
    attribute
}

fn name_for_usd(name: &str) -> String {
    match name {
        attr::COLOR => epic::COLOR.to_string(),
        name if name.starts_with(epic::PREFIX) => name.to_string(),
        name => format!("{}{name}", epic::PREFIX),
    }
}

/// The groom attribute a file's attribute of Epic's groom names is, as both readers take it:
/// `groom_X` is `X` (`groom_color` is `color`), except the names coif uses itself, which keep
/// their prefix: Unreal's interpolation names and `groom_group_id` (a file's Unreal groups, which
/// every writer then writes under that name). Other names are themselves.
pub fn attribute_for_epic_name(name: &str) -> String {
    match name {
        epic::COLOR => attr::COLOR.to_string(),
        epic::GROUP_ID => name.to_string(),
        n if n == crate::guides::CLOSEST_GUIDES || n == crate::guides::GUIDE_WEIGHTS => n.to_string(),
        n => n.strip_prefix(epic::PREFIX).unwrap_or(n).to_string(),
    }
}

/// Where `--unreal` output puts the groom's meshes (a scalp, head or body): Unreal's groom
/// importers refuse a file that holds a mesh, so they go to a sibling file in the same format,
/// `NAME_meshes.EXT` beside `NAME.EXT` (import it as a static or skeletal mesh).
pub fn meshes_path(groom_path: &Path) -> PathBuf {
    let stem = groom_path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let name = match groom_path.extension() {
        Some(ext) => format!("{stem}_meshes.{}", ext.to_string_lossy()),
        None => format!("{stem}_meshes"),
    };
    groom_path.with_file_name(name)
}

/// The groom as Unreal's USD importer wants its primvars: `groom_group_id` (int per strand),
/// `groom_root_uv` (float2 per strand), `color` as `groom_color`, every other attribute
/// prefixed `groom_` (the importer ignores other names). `groom_id` and `groom_guide` are the
/// names coif writes anyway; widths stay USD `widths`, which the importer reads itself, per
/// vertex (the rate its documentation and coif's tests know it reads).
pub fn for_usd(groom: &Groom) -> Groom {
    let mut out = with_root_uvs(groom).unwrap_or_else(|| groom.clone());
    // Unreal's attribute types are tuples (`groom_guide_weights` float×3), never arrays with an
    // `elementSize`.
    out.groups.iter_mut().for_each(|g| (g.width_interpolation, g.element_sized) = (None, Vec::new()));
    out.attributes = std::mem::take(&mut out.attributes).into_iter().map(renamed_for_usd).collect();
    // Unreal's USD importer reads int, float, float2 and float3 primvars: int tuples go as floats.
    for attribute in out.attributes.iter_mut().filter(|a| a.kind == AttributeKind::Int && a.components > 1) {
        attribute.data = AttributeData::Float(attribute.floats().into_owned());
        attribute.kind = AttributeKind::Float;
    }
    // What a group misses, it misses under the new names too.
    for group in &mut out.groups {
        for name in group.missing.iter_mut().filter(|n| *n != CurveGroup::ROOT_UVS) {
            *name = name_for_usd(name);
        }
    }
    // A groom's own `groom_group_id` (a file's Unreal groups) stays; else each curve group is
    // one (a groom without a group table has no `group_ids`: all its strands are group 0).
    if out.attribute(epic::GROUP_ID).is_none() {
        let group_ids = (0..out.strand_count()).map(|s| out.group_of(s) as i64).collect();
        let kind = AttributeKind::Int;
        out.set_attribute(Attribute::integers(epic::GROUP_ID, AttributeRate::Strand, 1, group_ids, kind));
    }
    if let Some(uvs) = &out.root_uvs {
        let data = uvs.iter().flatten().copied().collect();
        out.set_attribute(Attribute::new(epic::ROOT_UV, AttributeRate::Strand, 2, data));
        // Groups without root UVs get none under Unreal's name either.
        for group in out.groups.iter_mut().filter(|g| !g.carries(CurveGroup::ROOT_UVS)) {
            group.missing.push(epic::ROOT_UV.to_string());
        }
    }
    out
}
