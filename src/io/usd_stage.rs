//! The USD stage coif writes, planned once from a [`Groom`] and serialized by both writers
//! (`usda::writer` as text, `usdc` as a crate file), so the two formats always hold the same
//! prims, properties, values, metadata and time samples. A prim or property added here appears
//! in both.
//!
//! The stage: layer metadata (`defaultPrim`, `doc`, `metersPerUnit`, `upAxis`, and the time codes
//! when animated), then one `BasisCurves` prim per curve group at the group's path
//! (`/Groom/Strands` for a groom without groups) with `Xform`s above. Each curve prim holds
//! `basis` (cubic only), `purpose` (when the group has one), `visibility` (when invisible; sampled
//! when that changes over an animation),
//! `type`, `wrap`,
//! `curveVertexCounts`, `widths` (per vertex, or at the rate the file gave them while they fit
//! it), the primvars, `points` and `extent` — default values, or time samples of `points`, `extent` and of every primvar that changes when animated. Then
//! one `Mesh` prim per groom mesh (a scalp, head or body) at the path it was read from: its faces,
//! `points` (time-sampled when they move) and `extent`, wound counter-clockwise as
//! `rightHanded` says, `subdivisionScheme = "none"` (coif collides with the polygons as they
//! are). Everything is in the stage's space (metres, Y up); transforms were applied on reading.
//!
//! Large arrays are borrowed from the groom (and from the animation's frames) whenever a group's
//! strands are contiguous, which they are for every groom a reader built; only small per-strand
//! integer arrays are converted.
use std::borrow::Cow;
use std::path::Path;

use glam::Vec3;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::groom::{
    Attribute, AttributeKind, AttributeRate, CurveBasis, CurveGroup, CurveWrap, Groom, Values,
};
use crate::groups::{Interpolation, Strands};
use crate::io::usda::names;
use crate::surface_mesh::{MeshPrimvar, SurfaceMesh};
use crate::{point_attributes, primvar_rates};

/// Where a groom without a group table goes: `/Groom` (Xform) holding the `Strands` curves.
pub const DEFAULT_PRIM_PATH: &str = "/Groom/Strands";

/// Points per parallel task when computing bounds.
const CHUNK: usize = 16 * 1024;

/// Stage timing for animated output (`startTimeCode`, `endTimeCode`, `timeCodesPerSecond`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeCodes {
    pub start: f64,
    pub end: f64,
    pub per_second: f64,
}

/// What an animated stage samples: frame `k` at time code `times.start + k`. Everything not
/// listed here is written once, from the groom.
pub struct Animation<'g> {
    pub times: TimeCodes,
    /// Every frame's curve points (as many as the groom's).
    pub points: Vec<&'g [Vec3]>,
    /// Every frame's mesh points, one slice per groom mesh; empty when the meshes stand still.
    pub meshes: Vec<Vec<&'g [Vec3]>>,
    /// Every frame's values of the attributes that change over the animation (each frame
    /// lists the same names, each as the groom's attribute of that name is laid out); empty
    /// when none does.
    pub attributes: Vec<Vec<&'g Attribute>>,
    /// Every frame's widths (per vertex, as the groom's) when they change over the animation
    /// (Houdini samples a `pscale` that grows); empty when they do not.
    pub widths: Vec<&'g [f32]>,
    /// Every frame's hidden curve groups and meshes when any changes over the animation; empty
    /// when none does (each prim is then as the groom has it).
    pub hidden: Vec<Hidden>,
}

/// Which curve groups (by index) and meshes are hidden in one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Hidden {
    pub groups: Vec<bool>,
    pub meshes: Vec<bool>,
}

impl Hidden {
    pub fn of(groom: &Groom) -> Self {
        Hidden {
            groups: (0..groom.group_count()).map(|g| groom.group(g).invisible).collect(),
            meshes: groom.meshes.iter().map(|m| m.invisible).collect(),
        }
    }
}

impl<'g> Animation<'g> {
    /// Only the curve points move.
    pub fn of_points(times: TimeCodes, frames: &'g [Vec<Vec3>]) -> Self {
        Animation {
            times,
            points: frames.iter().map(Vec::as_slice).collect(),
            meshes: Vec::new(),
            attributes: Vec::new(),
            widths: Vec::new(),
            hidden: Vec::new(),
        }
    }

    fn time(&self, frame: usize) -> f64 {
        self.times.start + frame as f64
    }

    /// Frame `k`'s value of the sampled attribute `name`, if it is one.
    fn attribute(&self, frame: usize, name: &str) -> Option<&'g Attribute> {
        self.attributes.get(frame)?.iter().copied().find(|a| a.name == name)
    }
}

/// A whole stage: layer metadata and the prim tree.
pub struct Stage<'g> {
    pub default_prim: String,
    pub doc: String,
    pub meters_per_unit: f64,
    pub up_axis: &'static str,
    /// Set for animated stages.
    pub times: Option<TimeCodes>,
    pub roots: Vec<Prim<'g>>,
}

/// A `def` prim: its schema type, properties (in the order they are written) and children.
pub struct Prim<'g> {
    pub name: String,
    pub type_name: &'static str,
    pub properties: Vec<Property<'g>>,
    pub children: Vec<Prim<'g>>,
}

/// An attribute: USD type name (`point3f[]`, `token`…), variability, value, interpolation.
pub struct Property<'g> {
    pub name: String,
    pub type_name: &'static str,
    pub uniform: bool,
    pub value: Value<'g>,
    pub interpolation: Option<&'static str>,
    /// `elementSize`: values per element of a scalar array (a file's array attribute).
    pub element_size: Option<usize>,
}

pub enum Value<'g> {
    Default(Data<'g>),
    /// Samples in increasing time.
    TimeSamples(Vec<(f64, Data<'g>)>),
}

/// A value's data; tuples are flattened (`components` numbers per element).
pub enum Data<'g> {
    Token(Cow<'g, str>),
    Ints {
        values: Cow<'g, [i32]>,
        components: usize,
    },
    /// `uint[]`, `int64[]` or `uint64[]` (scalars; `int[]` are [`Data::Ints`]): values as
    /// integer kind `kind` stores them.
    WideInts {
        values: Cow<'g, [i64]>,
        kind: AttributeKind,
    },
    /// `bool[]` (written as 0 and 1 in text, one byte each in a crate file).
    Bools(Vec<bool>),
    /// One `int` (not an array).
    Int(i32),
    Floats {
        values: Cow<'g, [f32]>,
        components: usize,
    },
}

impl<'g> Property<'g> {
    fn new(name: impl Into<String>, type_name: &'static str, value: Value<'g>) -> Self {
        Property {
            name: name.into(),
            type_name,
            uniform: false,
            value,
            interpolation: None,
            element_size: None,
        }
    }

    fn uniform_token(name: &str, token: impl Into<Cow<'g, str>>) -> Self {
        Property { uniform: true, ..Property::new(name, "token", Value::Default(Data::Token(token.into()))) }
    }

    fn interpolated(mut self, interpolation: &'static str) -> Self {
        self.interpolation = Some(interpolation);
        self
    }
}

/// Unreal's groom-level properties on every root prim (Epic's USD groom importer reads
/// `userProperties:groom_*` on the prim the groom is imported from): the groom spec version.
pub fn add_unreal_groom_properties(stage: &mut Stage) {
    let (major, minor) = crate::io::alembic::curves_write::epic::SPEC_VERSION;
    for root in &mut stage.roots {
        for (name, value) in [("groom_version_major", major), ("groom_version_minor", minor)] {
            let data = Data::Int(value as i32);
            root.properties.push(Property::new(
                format!("userProperties:{name}"),
                "int",
                Value::Default(data),
            ));
        }
    }
}

/// Checks what USD cannot store: strand ids past `int` (`groom_id`), cubic strands with too few
/// control points for their basis.
pub fn check_writable(groom: &Groom, path: &Path) -> Result<()> {
    // `groom_id` is USD's `int` (what Unreal's importer reads): a larger id would be written
    // negative, and coif's own reader refuses negative ids.
    if let Some((strand, id)) =
        groom.strand_ids.iter().enumerate().find(|(_, &id)| i32::try_from(id).is_err())
    {
        return Err(Error::Usage(format!(
            "{}: strand {strand} has groom_id {id}; USD's int primvar holds ids up to {}",
            path.display(),
            i32::MAX
        )));
    }
    if groom.groups.is_empty() && groom.basis == CurveBasis::Linear {
        return Ok(());
    }
    for (strand, count) in groom.vertex_counts().enumerate() {
        let group = groom.group(groom.group_of(strand));
        if !primvar_rates::is_whole_curve(group.basis, group.wrap, count) {
            return Err(Error::Usage(format!(
                "{}: strand {strand} has {count} control points; {:?} curves in USD need {}",
                path.display(),
                group.basis,
                primvar_rates::whole_curve_rule(group.basis)
            )));
        }
    }
    Ok(())
}

/// Checks an animation before any output: sane time codes, at least one frame, constant topology
/// (curve points, mesh points) and attribute layout.
pub fn check_animation(groom: &Groom, animation: &Animation, path: &Path) -> Result<()> {
    let times = animation.times;
    if !(times.start.is_finite()
        && times.end.is_finite()
        && times.start <= times.end
        && times.per_second.is_finite()
        && times.per_second > 0.0)
    {
        return Err(Error::Usage(format!("{}: bad time codes {times:?}", path.display())));
    }
    let frames = &animation.points;
    if frames.is_empty() {
        return Err(Error::Usage(format!("{}: an animated stage needs at least one frame", path.display())));
    }
    let changed = |k: usize, what: String| {
        Err(Error::Usage(format!(
            "{}: frame {k} has {what} (topology and attributes must stay constant)",
            path.display()
        )))
    };
    if let Some(k) = frames.iter().position(|f| f.len() != groom.vertex_count()) {
        return changed(k, format!("{} points; the groom has {}", frames[k].len(), groom.vertex_count()));
    }
    for (k, meshes) in animation.meshes.iter().enumerate() {
        let same = meshes.len() == groom.meshes.len()
            && meshes.iter().zip(&groom.meshes).all(|(p, m)| p.len() == m.points.len());
        if !same {
            return changed(k, "other meshes than the groom".into());
        }
    }
    if !animation.meshes.is_empty() && animation.meshes.len() != frames.len() {
        return changed(animation.meshes.len(), "no mesh points".into());
    }
    if !animation.widths.is_empty() && animation.widths.len() != frames.len() {
        return changed(animation.widths.len(), "no widths".into());
    }
    if let Some(k) = animation.widths.iter().position(|w| w.len() != groom.vertex_count()) {
        return changed(
            k,
            format!("{} widths; the groom has {} points", animation.widths[k].len(), groom.vertex_count()),
        );
    }
    if !animation.hidden.is_empty() && animation.hidden.len() != frames.len() {
        return changed(animation.hidden.len(), "no visibility".into());
    }
    let prims = Hidden::of(groom);
    if let Some(k) = animation
        .hidden
        .iter()
        .position(|h| (h.groups.len(), h.meshes.len()) != (prims.groups.len(), prims.meshes.len()))
    {
        return changed(k, "the visibility of other prims than the groom's".into());
    }
    if !animation.attributes.is_empty() && animation.attributes.len() != frames.len() {
        return changed(animation.attributes.len(), "no attribute values".into());
    }
    for (k, attributes) in animation.attributes.iter().enumerate() {
        for a in attributes {
            let same = groom.attribute(&a.name).is_some_and(|g| {
                (g.rate, g.components, g.data.len(), g.kind) == (a.rate, a.components, a.data.len(), a.kind)
            });
            if !same {
                return changed(k, format!("attribute '{}' laid out unlike the groom's", a.name));
            }
        }
    }
    Ok(())
}

/// What the writers rename or drop, as warnings for the user.
pub fn unsupported(groom: &Groom) -> Vec<String> {
    let strands = Strands::Range(0..groom.strand_count());
    let mut warnings = primvars(groom, &CurveGroup::default(), &strands, None).1;
    warnings.sort();
    warnings.dedup();
    warnings
}

/// Plans the stage for `groom`, with its meshes; with `animation`, frame `k` at time code
/// `times.start + k`.
pub fn plan<'g>(groom: &'g Groom, animation: Option<&Animation<'g>>) -> Result<Stage<'g>> {
    let mut stage = plan_curves(groom, animation)?;
    add_meshes(&mut stage, &groom.meshes, animation)?;
    Ok(stage)
}

/// A stage of meshes only (`--unreal` output's sibling file); `animation`'s mesh points index
/// `meshes`.
pub fn plan_meshes<'g>(meshes: &'g [SurfaceMesh], animation: Option<&Animation<'g>>) -> Result<Stage<'g>> {
    let mut stage = Stage {
        default_prim: String::new(),
        doc: concat!("Written by coif ", env!("CARGO_PKG_VERSION")).to_string(),
        meters_per_unit: 1.0,
        up_axis: "Y",
        times: animation.map(|a| a.times),
        roots: Vec::new(),
    };
    add_meshes(&mut stage, meshes, animation)?;
    stage.default_prim = stage.roots.first().map(|p| p.name.clone()).unwrap_or_else(|| "Meshes".into());
    Ok(stage)
}

/// One `Mesh` prim per mesh at its own path (made unique: a mesh never takes another prim's
/// place, nor that of an Xform above curves).
fn add_meshes<'g>(
    stage: &mut Stage<'g>,
    meshes: &'g [SurfaceMesh],
    animation: Option<&Animation<'g>>,
) -> Result<()> {
    for (index, mesh) in meshes.iter().enumerate() {
        let mut components = prim_components(&mesh.path);
        let Some(last) = components.last().cloned() else {
            return Err(Error::Usage(format!("mesh '{}' has no prim name", mesh.path)));
        };
        let mut n = 1;
        while find(&stage.roots, &components) {
            n += 1;
            *components.last_mut().unwrap() = format!("{last}_{n}");
        }
        insert(&mut stage.roots, &components, mesh_prim(mesh, index, animation));
    }
    Ok(())
}

/// The prim names of a path (`/root/Head/HeadMesh`), each made a valid USD name.
fn prim_components(path: &str) -> Vec<String> {
    path.split('/').filter(|c| !c.is_empty()).map(|c| valid_name(c).replace(':', "_")).collect()
}

/// Whether a prim exists at `path` (prim names) under `nodes`.
fn find(nodes: &[Prim], path: &[String]) -> bool {
    let Some((first, rest)) = path.split_first() else { return false };
    nodes.iter().find(|n| n.name == *first).is_some_and(|n| rest.is_empty() || find(&n.children, rest))
}

/// The stage without meshes: one curves prim per group.
fn plan_curves<'g>(groom: &'g Groom, animation: Option<&Animation<'g>>) -> Result<Stage<'g>> {
    let mut roots: Vec<Prim<'g>> = Vec::new();
    let mut taken: Vec<Vec<String>> = Vec::new();
    for g in 0..groom.group_count() {
        let strands = Strands::of_group(groom, g);
        if strands.is_empty() && groom.group_count() > 1 {
            continue;
        }
        let group = groom.group(g);
        let path = if group.name.is_empty() { DEFAULT_PRIM_PATH } else { group.name.as_str() };
        let mut components = prim_components(path);
        let Some(last) = components.last().cloned() else {
            return Err(Error::Usage(format!("curve group '{}' has no prim name", group.name)));
        };
        // Two groups at one path (possible only for grooms built in memory) keep both prims.
        let mut n = 1;
        while taken.contains(&components) {
            n += 1;
            *components.last_mut().unwrap() = format!("{last}_{n}");
        }
        taken.push(components.clone());
        let curves = curves_prim(groom, g, &strands, animation);
        insert(&mut roots, &components, curves);
    }
    let default_prim = roots.first().map(|p| p.name.clone()).unwrap_or_else(|| "Groom".into());
    Ok(Stage {
        default_prim,
        doc: concat!("Written by coif ", env!("CARGO_PKG_VERSION")).to_string(),
        meters_per_unit: 1.0,
        up_axis: "Y",
        times: animation.map(|a| a.times),
        roots,
    })
}

/// Puts `leaf` at `path` (prim names) under `nodes`, creating `Xform`s on the way. A group whose
/// path names an existing prim takes that prim's place and keeps its children.
fn insert<'g>(nodes: &mut Vec<Prim<'g>>, path: &[String], leaf: Prim<'g>) {
    let Some((first, rest)) = path.split_first() else { return };
    let index = match nodes.iter().position(|n| n.name == *first) {
        Some(i) => i,
        None => {
            nodes.push(Prim {
                name: first.clone(),
                type_name: "Xform",
                properties: Vec::new(),
                children: Vec::new(),
            });
            nodes.len() - 1
        }
    };
    if rest.is_empty() {
        let node = &mut nodes[index];
        node.type_name = leaf.type_name;
        node.properties = leaf.properties;
    } else {
        insert(&mut nodes[index].children, rest, leaf);
    }
}

fn floats(values: Cow<'_, [f32]>, components: usize) -> Data<'_> {
    Data::Floats { values, components }
}

fn vec3s(points: Cow<'_, [Vec3]>) -> Cow<'_, [f32]> {
    match points {
        Cow::Borrowed(p) => Cow::Borrowed(bytemuck::cast_slice(p)),
        Cow::Owned(p) => Cow::Owned(bytemuck::cast_slice(&p).to_vec()),
    }
}

/// One group's `BasisCurves` prim.
fn curves_prim<'g>(
    groom: &'g Groom,
    index: usize,
    strands: &Strands,
    animation: Option<&Animation<'g>>,
) -> Prim<'g> {
    let group = &groom.group(index);
    let mut properties = Vec::new();
    let (curve_type, basis) = curve_type_and_basis(group.basis);
    if let Some(basis) = basis {
        properties.push(Property::uniform_token("basis", basis));
    }
    if let Some(purpose) = &group.purpose {
        properties.push(Property::uniform_token("purpose", purpose.clone()));
    }
    properties.extend(visibility(group.invisible, animation, |h| h.groups[index]));
    let wrap = match group.wrap {
        CurveWrap::Nonperiodic => "nonperiodic",
        CurveWrap::Pinned => "pinned",
        CurveWrap::Periodic => "periodic",
    };
    properties.push(Property::uniform_token("type", curve_type));
    properties.push(Property::uniform_token("wrap", wrap));
    let vertex_counts = strands.counts(groom);
    let counts: Vec<usize> = vertex_counts.iter().map(|&c| c as usize).collect();
    let vertex_counts = Data::Ints { values: Cow::Owned(vertex_counts), components: 1 };
    properties.push(Property::new("curveVertexCounts", "int[]", Value::Default(vertex_counts)));
    let sampled = animation.filter(|a| !a.widths.is_empty());
    let frames: Vec<Cow<[f32]>> = match sampled {
        Some(a) => a.widths.iter().map(|w| strands.per_vertex(groom, w, 1)).collect(),
        None => vec![strands.per_vertex(groom, &groom.widths, 1)],
    };
    let half_widths: Vec<f32> =
        frames.iter().map(|w| w.iter().fold(0.0f32, |m, &w| m.max(w)) * 0.5).collect();
    // The file's rate while every frame's widths fit it, else per vertex.
    let at_rate: Option<Vec<(Interpolation, Vec<f32>)>> = frames
        .iter()
        .map(|w| primvar_rates::widths_at(group.width_interpolation, group.basis, group.wrap, &counts, w))
        .collect();
    let (interpolation, frames) = match at_rate {
        Some(rated) => (rated[0].0.usd_name(), rated.into_iter().map(|(_, w)| Cow::Owned(w)).collect()),
        None => ("vertex", frames),
    };
    let widths = match sampled {
        Some(a) => Value::TimeSamples(
            frames.into_iter().enumerate().map(|(k, w)| (a.time(k), floats(w, 1))).collect(),
        ),
        None => Value::Default(floats(frames.into_iter().next().expect("one frame"), 1)),
    };
    properties.push(Property::new("widths", "float[]", widths).interpolated(interpolation));
    properties.extend(primvars(groom, group, strands, animation).0);

    let positions = match animation {
        Some(a) => Positions::Frames(a, a.points.iter().map(|f| strands.per_vertex(groom, f, 1)).collect()),
        None => Positions::Still(strands.per_vertex(groom, &groom.points, 1)),
    };
    properties.extend(points_and_extent(positions, &half_widths));
    Prim { name: String::new(), type_name: "BasisCurves", properties, children: Vec::new() }
}

/// A prim's points: one set, or one per frame of an animation.
enum Positions<'a, 'g> {
    Still(Cow<'g, [Vec3]>),
    Frames(&'a Animation<'g>, Vec<Cow<'g, [Vec3]>>),
}

/// `points` and `extent` (the bounds grown by half the widest width, `half_widths` of each
/// frame, the last holding for the frames after it): default values, or a time sample per frame.
fn points_and_extent<'g>(positions: Positions<'_, 'g>, half_widths: &[f32]) -> Vec<Property<'g>> {
    let extent = |points: &[Vec3], k: usize| -> Option<Data<'g>> {
        let half_width = half_widths[k.min(half_widths.len() - 1)];
        let (lo, hi) = bounds(points)?;
        let grown = [lo - Vec3::splat(half_width), hi + Vec3::splat(half_width)];
        Some(floats(Cow::Owned(bytemuck::cast_slice(&grown).to_vec()), 3))
    };
    let mut properties = Vec::with_capacity(2);
    match positions {
        Positions::Still(still) => {
            let extent = extent(&still, 0);
            properties.push(Property::new("points", "point3f[]", Value::Default(floats(vec3s(still), 3))));
            if let Some(extent) = extent {
                properties.push(Property::new("extent", "float3[]", Value::Default(extent)));
            }
        }
        Positions::Frames(animation, frames) => {
            let mut points = Vec::with_capacity(frames.len());
            let mut extents = Vec::with_capacity(frames.len());
            for (k, frame) in frames.into_iter().enumerate() {
                extents.extend(extent(&frame, k).map(|e| (animation.time(k), e)));
                points.push((animation.time(k), floats(vec3s(frame), 3)));
            }
            properties.push(Property::new("points", "point3f[]", Value::TimeSamples(points)));
            if !extents.is_empty() {
                properties.push(Property::new("extent", "float3[]", Value::TimeSamples(extents)));
            }
        }
    }
    properties
}

/// One groom mesh's `Mesh` prim (mesh `index` of the groom, for its animated points).
fn mesh_prim<'g>(mesh: &'g SurfaceMesh, index: usize, animation: Option<&Animation<'g>>) -> Prim<'g> {
    let ints = |values: &'g [u32]| Data::Ints {
        values: Cow::Owned(values.iter().map(|&v| v as i32).collect()),
        components: 1,
    };
    let mut properties = vec![
        Property::new("faceVertexCounts", "int[]", Value::Default(ints(&mesh.face_counts))),
        Property::new("faceVertexIndices", "int[]", Value::Default(ints(&mesh.face_indices))),
    ];
    if !mesh.holes.is_empty() {
        properties.push(Property::new("holeIndices", "int[]", Value::Default(ints(&mesh.holes))));
    }
    let positions = match animation.filter(|a| !a.meshes.is_empty()) {
        Some(a) => Positions::Frames(a, a.meshes.iter().map(|f| Cow::Borrowed(f[index])).collect()),
        None => Positions::Still(Cow::Borrowed(&mesh.points)),
    };
    properties.extend(points_and_extent(positions, &[0.0]));
    properties.extend(mesh.primvars.iter().flat_map(mesh_primvar));
    properties.push(Property::uniform_token("orientation", "rightHanded"));
    properties.push(Property::uniform_token("subdivisionScheme", "none"));
    properties.extend(visibility(mesh.invisible, animation, |h| h.meshes[index]));
    Prim { name: String::new(), type_name: "Mesh", properties, children: Vec::new() }
}

/// `visibility`: `"invisible"` for a prim hidden in the file it came from (`hidden`), nothing
/// for a visible one; time samples (`"invisible"` / `"inherited"`, held as pxr holds tokens) when
/// the animation hides it in some frames only (`of` picks the prim's flag from a frame's).
fn visibility<'g>(
    hidden: bool,
    animation: Option<&Animation<'g>>,
    of: impl Fn(&Hidden) -> bool,
) -> Option<Property<'g>> {
    let token = |hidden: bool| Data::Token(if hidden { "invisible" } else { "inherited" }.into());
    let frames = animation.map_or(&[][..], |a| a.hidden.as_slice());
    if frames.iter().any(|h| of(h) != hidden) {
        let animation = animation.expect("frames come from an animation");
        let samples = frames.iter().enumerate().map(|(k, h)| (animation.time(k), token(of(h)))).collect();
        return Some(Property::new("visibility", "token", Value::TimeSamples(samples)));
    }
    hidden.then(|| Property::new("visibility", "token", Value::Default(token(true))))
}

/// A mesh primvar as USD properties: `primvars:NAME` (the mesh's plain `normals` attribute for
/// unindexed normals), typed by its role, and its `:indices`.
fn mesh_primvar(primvar: &MeshPrimvar) -> Vec<Property<'_>> {
    // Integers of a type without tuples go as a scalar array with `elementSize`.
    let element_size = (!has_tuples(primvar.kind) && primvar.components > 1).then_some(primvar.components);
    let type_name = usd_type(primvar.kind, &primvar.name, element_size.map_or(primvar.components, |_| 1));
    let components = if element_size.is_some() { 1 } else { primvar.components };
    let data = typed_data(primvar.values.values(), primvar.kind, type_name, components);
    let name = match (primvar.name.as_str(), &primvar.indices) {
        (MeshPrimvar::NORMALS, None) => MeshPrimvar::NORMALS.to_string(),
        (name, _) => format!("primvars:{}", valid_name(name)),
    };
    let property = Property::new(name.clone(), type_name, Value::Default(data))
        .interpolated(primvar.interpolation.usd_name());
    let mut properties = vec![Property { element_size, ..property }];
    if let Some(indices) = &primvar.indices {
        let values = Cow::Owned(indices.iter().map(|&i| i as i32).collect());
        properties.push(Property::new(
            format!("{name}:indices"),
            "int[]",
            Value::Default(Data::Ints { values, components: 1 }),
        ));
    }
    properties
}

/// USD's `type` and `basis` tokens for a curve basis.
pub(crate) fn curve_type_and_basis(basis: CurveBasis) -> (&'static str, Option<&'static str>) {
    match basis {
        CurveBasis::Linear => ("linear", None),
        CurveBasis::Bezier => ("cubic", Some("bezier")),
        CurveBasis::BSpline => ("cubic", Some("bspline")),
        CurveBasis::CatmullRom => ("cubic", Some("catmullRom")),
    }
}

/// The primvars a group's strands become, and warnings for attributes renamed or dropped.
fn primvars<'g>(
    groom: &'g Groom,
    group: &CurveGroup,
    strands: &Strands,
    animation: Option<&Animation<'g>>,
) -> (Vec<Property<'g>>, Vec<String>) {
    let mut primvars = Vec::new();
    let mut warnings = Vec::new();
    // Names the reader gives a meaning of their own are never taken by attributes: `st` is the
    // root UVs where the group has them, and reads back as them at one value per strand; per
    // vertex (Houdini's `uv` along each curve, written as `st`) it is an attribute like others.
    let writes_root_uvs = groom.root_uvs.is_some() && group.carries(CurveGroup::ROOT_UVS);
    let mut used: Vec<String> = [names::GROOM_ID, names::GROOM_GUIDE].map(String::from).to_vec();
    let reads_as_root_uvs = |a: &Attribute| a.rate == AttributeRate::Strand && a.components == 2;
    if writes_root_uvs || groom.attribute(names::ST).is_some_and(reads_as_root_uvs) {
        used.push(names::ST.into());
    }
    let uniform_ints = |name: &str, values: Vec<i32>| {
        let data = Data::Ints { values: Cow::Owned(values), components: 1 };
        Property::new(format!("primvars:{name}"), "int[]", Value::Default(data)).interpolated("uniform")
    };
    let ids = strands.per_strand(&groom.strand_ids, 1);
    // `check_writable` refused ids past `i32::MAX`.
    primvars.push(uniform_ints(names::GROOM_ID, ids.iter().map(|&i| i as i32).collect()));
    if let Some(guides) = &groom.guides {
        let guides = strands.per_strand(guides, 1);
        primvars.push(uniform_ints(names::GROOM_GUIDE, guides.iter().map(|&g| g as i32).collect()));
    }
    if let Some(uvs) = groom.root_uvs.as_ref().filter(|_| writes_root_uvs) {
        let uvs = strands.per_strand(bytemuck::cast_slice::<_, f32>(uvs), 2);
        let name = format!("primvars:{}", names::ST);
        primvars.push(
            Property::new(name, "texCoord2f[]", Value::Default(floats(uvs, 2))).interpolated("uniform"),
        );
    }
    for attribute in groom.attributes.iter().filter(|a| group.carries(&a.name)) {
        let wanted = names::primvar_for_attribute(&attribute.name);
        let name = valid_name(wanted);
        // A primvar that reads back as another attribute would not round-trip (`displayColor`
        // is where `color` goes), so such names are dropped like clashes.
        if used.contains(&name) || (name == wanted && names::attribute_for_primvar(&name) != attribute.name) {
            warnings.push(format!(
                "attribute '{}' clashes with primvar '{name}' and is not written",
                attribute.name
            ));
            continue;
        }
        if name != wanted {
            warnings.push(format!(
                "attribute '{}' is written as primvar '{name}' (a valid USD name)",
                attribute.name
            ));
        }
        // A scalar array with `elementSize` where the file gave one (Houdini's array attributes):
        // `int[]` with three per curve stays so, not `float3[]`.
        // Integers of a type without tuples (`uint`, `int64`, `uint64`) go so too.
        let element_size = ((group.element_sized.contains(&attribute.name) || !has_tuples(attribute.kind))
            && attribute.components > 1)
            .then_some(attribute.components);
        let type_name =
            usd_type(attribute.kind, &attribute.name, element_size.map_or(attribute.components, |_| 1));
        let sampled = animation.filter(|a| a.attribute(0, &attribute.name).is_some());
        // The file's own interpolation where the values still fit it (one value for the prim;
        // varying = vertex on linear and pinned curves); else the rate's.
        // (Per-curve and constant values made per vertex to merge with another group's
        // per-vertex ones go back as they came while every strand's vertices still agree.)
        let components = attribute.components;
        let all_equal = |values: &Values, run: std::ops::Range<usize>| match values {
            Values::Float(v) => equal_elements(&v[run], components),
            Values::Int(v) => equal_elements(&v[run], components),
        };
        let fits = |interpolation| match (interpolation, attribute.rate) {
            (Interpolation::Constant, _) => {
                let values = strands.values(groom, attribute);
                sampled.is_none() && all_equal(&values, 0..values.len())
            }
            (Interpolation::Uniform, AttributeRate::Vertex) => {
                let values = strands.values(groom, attribute);
                let mut runs = strands.counts(groom).into_iter().scan(0, |at, count| {
                    let run = *at..*at + count as usize * components;
                    *at = run.end;
                    Some(run)
                });
                sampled.is_none() && runs.all(|run| all_equal(&values, run))
            }
            (Interpolation::Varying, AttributeRate::Vertex) => {
                group.basis == CurveBasis::Linear
                    || (group.wrap == CurveWrap::Pinned && group.basis != CurveBasis::Bezier)
            }
            _ => false,
        };
        let interpolation = match (group.interpolation(&attribute.name).filter(|&i| fits(i)), attribute.rate)
        {
            (Some(interpolation), _) => interpolation.usd_name(),
            (None, AttributeRate::Vertex) => "vertex",
            (None, AttributeRate::Strand) => "uniform",
        };
        let take = match (interpolation, attribute.rate) {
            ("constant", _) => Take::First,
            ("uniform", AttributeRate::Vertex) => Take::EachStrandsFirst,
            _ => Take::Every,
        };
        let flat = element_size.is_some();
        let data = |attribute: &'g Attribute| primvar_data(groom, strands, attribute, type_name, take, flat);
        let value = match sampled {
            Some(a) => Value::TimeSamples(
                (0..a.points.len())
                    .map(|k| (a.time(k), data(a.attribute(k, &attribute.name).unwrap_or(attribute))))
                    .collect(),
            ),
            None => Value::Default(data(attribute)),
        };
        used.push(name.clone());
        // The curves' own normals, velocities and accelerations go back where USD keeps them;
        // velocities and accelerations are per point and take no interpolation.
        let property = if point_attributes::is_schema_attribute(&name, attribute.rate, attribute.components) {
            match name.as_str() {
                point_attributes::NORMALS => {
                    Property::new(name.clone(), "normal3f[]", value).interpolated(interpolation)
                }
                _ => Property::new(name.clone(), "vector3f[]", value),
            }
        } else {
            Property::new(format!("primvars:{name}"), type_name, value).interpolated(interpolation)
        };
        primvars.push(Property { element_size, ..property });
    }
    (primvars, warnings)
}

/// Which of a group's values of an attribute a primvar holds.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Take {
    Every,
    /// The first element's (a `constant` primvar).
    First,
    /// Each strand's first vertex's (a `uniform` primvar of per-vertex values).
    EachStrandsFirst,
}

/// A group's values of an attribute, as `type_name` holds them. `flat`: as a scalar array (its
/// components are the `elementSize`).
fn primvar_data<'g>(
    groom: &Groom,
    strands: &Strands,
    attribute: &'g Attribute,
    type_name: &str,
    take: Take,
    flat: bool,
) -> Data<'g> {
    let components = attribute.components;
    let values = match strands.values(groom, attribute) {
        Values::Float(values) => Values::Float(taken(values, groom, strands, take, components)),
        Values::Int(values) => Values::Int(taken(values, groom, strands, take, components)),
    };
    typed_data(values, attribute.kind, type_name, if flat { 1 } else { components })
}

/// `take` of a group's values.
fn taken<'g, T: Clone>(
    mut values: Cow<'g, [T]>,
    groom: &Groom,
    strands: &Strands,
    take: Take,
    components: usize,
) -> Cow<'g, [T]> {
    match take {
        Take::Every => {}
        Take::First => values.to_mut().truncate(components),
        Take::EachStrandsFirst => {
            let mut at = 0;
            let firsts = strands.counts(groom).into_iter().flat_map(|count| {
                let first = at;
                at += count as usize * components;
                values[first..first + components].to_vec()
            });
            values = Cow::Owned(firsts.collect());
        }
    }
    values
}

/// Whether every element (`components` values) equals the first.
fn equal_elements<T: PartialEq>(values: &[T], components: usize) -> bool {
    values.chunks_exact(components).all(|v| v == &values[..v.len()])
}

/// Values of kind `kind` as `type_name` (see [`usd_type`]) holds them: integers exactly in their
/// own type (each in its range: `Groom::validate` checks), flags as bools, else floats.
fn typed_data<'g>(values: Values<'g>, kind: AttributeKind, type_name: &str, components: usize) -> Data<'g> {
    match values {
        Values::Int(values) => match kind {
            AttributeKind::UInt | AttributeKind::Int64 | AttributeKind::UInt64 => {
                Data::WideInts { values, kind }
            }
            _ if type_name.starts_with("int") => {
                Data::Ints { values: Cow::Owned(values.iter().map(|&v| v as i32).collect()), components }
            }
            // coif's guide binding goes as floats (see `usd_type`).
            _ => floats(Values::Int(values).floats(kind), components),
        },
        // Bool tuples have no USD type: they go as floats (see `usd_type`).
        Values::Float(values) if kind == AttributeKind::Bool && type_name == "bool[]" => {
            Data::Bools(values.iter().map(|&v| v != 0.0).collect())
        }
        Values::Float(values) => floats(values, components),
    }
}

/// Whether USD has tuples of the kind's type (`int3`, `float3`; no `uint3`, `int64_3`).
fn has_tuples(kind: AttributeKind) -> bool {
    !matches!(kind, AttributeKind::UInt | AttributeKind::Int64 | AttributeKind::UInt64)
}

/// The USD array type an attribute is written as: its kind's, or for plain floats the type coif
/// always gives that name (the reader maps that type back to plain floats).
pub(crate) fn usd_type(kind: AttributeKind, name: &str, components: usize) -> &'static str {
    const FLOATS: [&str; 4] = ["float[]", "float2[]", "float3[]", "float4[]"];
    let by_size = |types: [&'static str; 4]| types[components.clamp(1, 4) - 1];
    match kind {
        AttributeKind::Int if components == 1 => "int[]",
        AttributeKind::UInt => "uint[]",
        AttributeKind::Int64 => "int64[]",
        AttributeKind::UInt64 => "uint64[]",
        // A file's int pairs to quadruples stay ints. coif's guide binding goes as `float3[]`
        // whatever came in: Blender and Unreal's USD importers drop `int3[]` (README).
        AttributeKind::Int if name != crate::guides::CLOSEST_GUIDES => {
            by_size(["int[]", "int2[]", "int3[]", "int4[]"])
        }
        AttributeKind::Bool if components == 1 => "bool[]",
        AttributeKind::Point if components == 3 => "point3f[]",
        AttributeKind::Normal if components == 3 => "normal3f[]",
        AttributeKind::Vector if components == 3 => "vector3f[]",
        AttributeKind::Color if components >= 3 => by_size(["", "", "color3f[]", "color4f[]"]),
        AttributeKind::TexCoord if components >= 2 => by_size(["", "texCoord2f[]", "texCoord3f[]", ""]),
        _ => match (name, components) {
            (crate::groom::attr::COLOR, 3) => "color3f[]",
            (names::REST, 3) => "point3f[]",
            _ => by_size(FLOATS),
        },
    }
}

/// A USD property or prim name (identifier segments joined by ':') made from any name.
fn valid_name(name: &str) -> String {
    let segments: Vec<String> = name
        .split(':')
        .map(|segment| {
            let mut s: String = segment
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' })
                .collect();
            if s.is_empty() || s.starts_with(|c: char| c.is_ascii_digit()) {
                s.insert(0, '_');
            }
            s
        })
        .collect();
    segments.join(":")
}

fn bounds(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let first = *points.first()?;
    Some(
        points
            .par_chunks(CHUNK)
            .map(|c| c.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))))
            .reduce(|| (first, first), |a, b| (a.0.min(b.0), a.1.max(b.1))),
    )
}
