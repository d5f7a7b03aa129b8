//! Writing grooms as AbcGeom Curves (`AbcGeom_Curve_v2`): `P`, `nVertices`,
//! `curveBasisAndType`, `.selfBnds`, `width`, `uv`, `.velocities` when animated, and every groom
//! attribute in `.arbGeomParams`; the groom's meshes as PolyMesh objects (`P`, `.faceIndices`,
//! `.faceCounts`, wound clockwise as Alembic is); optionally under an Xform parent, optionally
//! following Epic's Alembic-for-grooms conventions. Static files hold one sample; animated files
//! one sample per frame on a uniform time sampling, with constant topology.
use std::borrow::Cow;
use std::io::{self, Seek, Write};

use glam::{DMat4, Vec3};
use rayon::prelude::*;

use super::archive_write::{ArchiveWriter, CompoundId, ObjectId, PropertyId};
use super::curves_read::POLYMESH_SCHEMA;
use super::murmur3::sample_key;
use super::types::{MetaData, Pod, TimeSampling};
use crate::groom::{
    attr, Attribute, AttributeData, AttributeKind, AttributeRate, CurveBasis, CurveGroup, CurveWrap, Groom,
    Values,
};
use crate::groups::{Interpolation, Strands};
use crate::surface_mesh::{MeshPrimvar, SurfaceMesh};
use crate::{point_attributes, primvar_rates};

pub const CURVE_SCHEMA: &str = "AbcGeom_Curve_v2";
pub const XFORM_SCHEMA: &str = "AbcGeom_Xform_v3";
const GEOM_BASE: &str = "AbcGeom_GeomBase_v1";
/// The curves object of a groom without groups.
pub const DEFAULT_OBJECT_NAME: &str = "curves";
/// AbcGeom's visibility: an int8 scalar on an object's top compound, -1 deferred to the parent,
/// 0 hidden, 1 visible.
pub const VISIBLE: &str = "visible";
pub const VISIBILITY_HIDDEN: i8 = 0;
pub const VISIBILITY_VISIBLE: i8 = 1;

/// Epic's groom attribute names, and the spec version coif follows in Unreal mode.
pub mod epic {
    pub const WIDTH: &str = "groom_width";
    pub const GUIDE: &str = "groom_guide";
    pub const GROUP_ID: &str = "groom_group_id";
    pub const ROOT_UV: &str = "groom_root_uv";
    pub const COLOR: &str = "groom_color";
    pub const ID: &str = "groom_id";
    pub const PREFIX: &str = "groom_";
    pub const VERSION_MAJOR: &str = "groom_version_major";
    pub const VERSION_MINOR: &str = "groom_version_minor";
    pub const TOOL: &str = "groom_tool";
    pub const SPEC_VERSION: (i16, i16) = (1, 5);
    /// Epic's exporters and importer work in centimetres.
    pub const UNITS_PER_METRE: f32 = 100.0;
}

/// How to write a groom as Alembic.
#[derive(Clone, Debug)]
pub struct AlembicWriteOptions {
    /// Follow Epic's groom conventions: centimetres, `groom_*` attribute names, the groom spec
    /// version on the topmost Xform's `.userProperties` (the groups' own top, else a `groom`
    /// Xform parent).
    pub unreal: bool,
    /// A parent Xform with this matrix (column-vector convention; translation in column 3).
    pub xform: Option<DMat4>,
    /// Frame rate of animated output; sample `i` is at time `(first_frame + i) / fps`.
    pub frames_per_second: f64,
    /// Frame number of an animated output's first sample.
    pub first_frame: f64,
    /// Written as the archive's `_ai_Application`.
    pub application: String,
    /// Name of the curves object.
    pub object_name: String,
    /// Animated output carries `.velocities` (central differences of the frames, units per
    /// second) for motion blur.
    pub velocities: bool,
    /// Which of the groom's objects the file holds.
    pub objects: Objects,
}

/// Which of a groom's objects an Alembic file holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Objects {
    /// The curves and the meshes.
    #[default]
    All,
    /// The curves only (Unreal's groom importer refuses a file holding a PolyMesh).
    Curves,
    /// The meshes only (the sibling file of an Unreal groom).
    Meshes,
}

impl Default for AlembicWriteOptions {
    fn default() -> Self {
        AlembicWriteOptions {
            unreal: false,
            xform: None,
            frames_per_second: 24.0,
            first_frame: 1.0,
            application: format!("coif {}", env!("CARGO_PKG_VERSION")),
            object_name: DEFAULT_OBJECT_NAME.into(),
            velocities: true,
            objects: Objects::All,
        }
    }
}

/// The property handles of one curves object.
struct CurveProperties {
    bounds: PropertyId,
    positions: PropertyId,
    vertex_counts: PropertyId,
    basis: PropertyId,
    velocities: Option<PropertyId>,
    uv: Option<PropertyId>,
    width: PropertyId,
    /// Alembic's `visible`, on objects of groups hidden in some frame only.
    visibility: Visibility,
    /// The rate of `width` (and Unreal's `groom_width`) when not per vertex: the file's, which
    /// the first frame's widths fit (see [`primvar_rates::widths_at`]).
    width_rate: Option<Interpolation>,
    /// `.arbGeomParams` members and what fills them.
    params: Vec<(PropertyId, ParamSource)>,
}

#[derive(Clone)]
enum ParamSource {
    Widths,
    StrandIds,
    Guides,
    RootUvs,
    /// Epic's `groom_group_id`: the group's index, one per strand.
    GroupId(u32),
    Attribute(String),
}

/// The property handles of one PolyMesh object, and which groom mesh fills them.
struct MeshObject {
    mesh: usize,
    bounds: PropertyId,
    positions: PropertyId,
    face_indices: PropertyId,
    face_counts: PropertyId,
    /// The faces wound clockwise (the file's convention), fixed by the first frame.
    clockwise_indices: Vec<i32>,
    /// Alembic's `visible`, on meshes hidden in some frame only.
    visibility: Visibility,
}

/// An object's Alembic `visible`: made with the object when its first frame is hidden, else
/// when a later frame first hides it (the frames before then say visible), so a hide animated
/// in the file read (Blender's keyframed hide) is written frame by frame.
struct Visibility {
    object: ObjectId,
    property: Option<PropertyId>,
}

impl Visibility {
    fn new<W: Write + Seek>(archive: &mut ArchiveWriter<W>, object: ObjectId, hidden: bool, ts: u32) -> Self {
        Visibility { object, property: hidden.then(|| hidden_property(archive, object, ts)) }
    }

    /// The property a frame `hidden` or not samples, after the `written` frames before it
    /// (`None`: visible in every frame so far).
    fn for_frame<W: Write + Seek>(
        &mut self,
        archive: &mut ArchiveWriter<W>,
        hidden: bool,
        written: usize,
        ts: u32,
    ) -> io::Result<Option<PropertyId>> {
        if self.property.is_none() && hidden {
            let id = hidden_property(archive, self.object, ts);
            for _ in 0..written {
                archive.set_sample(id, &[VISIBILITY_VISIBLE as u8], 1)?;
            }
            self.property = Some(id);
        }
        Ok(self.property)
    }
}

/// A frame's `visible` sample.
fn visibility_byte(hidden: bool) -> &'static [u8] {
    const HIDDEN: [u8; 1] = [VISIBILITY_HIDDEN as u8];
    const VISIBLE: [u8; 1] = [VISIBILITY_VISIBLE as u8];
    if hidden {
        &HIDDEN
    } else {
        &VISIBLE
    }
}

/// The curves object of one group: its properties, the group's index and its strands.
struct GroupObject {
    properties: CurveProperties,
    group: usize,
    strands: Strands,
}

/// What one curves object is written from: its group's strands, borrowed from the whole groom
/// when they lie in one run (readers keep each prim's or object's strands together), else
/// gathered — never a copy of the whole groom.
struct GroupPart<'g> {
    group: Cow<'g, CurveGroup>,
    points: Cow<'g, [Vec3]>,
    widths: Cow<'g, [f32]>,
    counts: Vec<i32>,
    strand_ids: Cow<'g, [u32]>,
    guides: Option<Cow<'g, [bool]>>,
    root_uvs: Option<Cow<'g, [[f32; 2]]>>,
    /// The attributes the group carries, with its strands' values.
    attributes: Vec<(&'g Attribute, Values<'g>)>,
}

impl<'g> GroupPart<'g> {
    fn of(groom: &'g Groom, group: usize, strands: &Strands) -> Self {
        let group = groom.group(group);
        let attributes = groom
            .attributes
            .iter()
            .filter(|a| group.carries(&a.name))
            .map(|a| (a, strands.values(groom, a)))
            .collect();
        GroupPart {
            points: strands.per_vertex(groom, &groom.points, 1),
            widths: strands.per_vertex(groom, &groom.widths, 1),
            counts: strands.counts(groom),
            strand_ids: strands.per_strand(&groom.strand_ids, 1),
            guides: groom.guides.as_deref().map(|g| strands.per_strand(g, 1)),
            root_uvs: groom
                .root_uvs
                .as_deref()
                .filter(|_| group.carries(CurveGroup::ROOT_UVS))
                .map(|u| strands.per_strand(u, 1)),
            attributes,
            group,
        }
    }

    fn strand_count(&self) -> usize {
        self.counts.len()
    }

    /// Attribute `name` and its values.
    fn attribute(&self, name: &str) -> Option<(&'g Attribute, &Values<'g>)> {
        self.attributes.iter().find(|(a, _)| a.name == name).map(|(a, data)| (*a, data))
    }
}

/// Writes curves samples into an Alembic stream: one sample for a static groom, or one per
/// frame with [`CurvesWriter::write_frame`]. Velocities of a frame are central differences of
/// its neighbours, so each frame is written when the next one arrives (or at `finish`).
pub struct CurvesWriter<W: Write + Seek> {
    archive: ArchiveWriter<W>,
    /// One curves object per curve group.
    objects: Vec<GroupObject>,
    /// One PolyMesh object per groom mesh.
    meshes: Vec<MeshObject>,
    animated: bool,
    scale: f32,
    frames_per_second: f64,
    /// Topology every frame must share.
    strand_offsets: Vec<u32>,
    basis: CurveBasis,
    /// Points per mesh, which every frame must share.
    mesh_sizes: Vec<usize>,
    attribute_layout: Vec<(String, AttributeRate, usize)>,
    previous_points: Option<Vec<Vec3>>,
    pending: Option<Groom>,
    frames: usize,
    /// Frames whose samples are written (frames lag one behind while velocities need the next).
    written: usize,
    time_sampling: u32,
}

impl<W: Write + Seek> CurvesWriter<W> {
    /// Starts an archive whose layout (attributes, optional data) follows `first`; topology is
    /// fixed by it too. `animated` adds the uniform time sampling and `.velocities`.
    pub fn new(out: W, first: &Groom, options: &AlembicWriteOptions, animated: bool) -> io::Result<Self> {
        let mut archive_metadata = MetaData::new().with("_ai_Application", &options.application);
        if animated {
            archive_metadata.set("_ai_DCC_FPS", &format!("{:.6}", options.frames_per_second));
        }
        let mut archive = ArchiveWriter::new(out, archive_metadata)?;
        let time_sampling = if animated {
            let fps = options.frames_per_second;
            archive.add_time_sampling(TimeSampling::uniform(fps, options.first_frame / fps))
        } else {
            0
        };
        let with_curves = options.objects != Objects::Meshes;
        // One curves object per group with strands (a groom of one plain group gets its object
        // even when it has none).
        let plain = first.groups.len() <= 1 && first.group(0).missing.is_empty();
        let groups: Vec<(usize, Strands)> = if with_curves {
            (0..first.group_count())
                .map(|g| (g, Strands::of_group(first, g)))
                .filter(|(_, strands)| plain || !strands.is_empty())
                .collect()
        } else {
            Vec::new()
        };
        let mut tree = Tree { parent: archive.top(), nodes: Vec::new() };
        if options.unreal && with_curves {
            // Epic's groom-wide properties go on the topmost Xform: the groups' own when they all
            // sit under one (so the groom reads back at the same paths), else a `groom` Xform
            // above them.
            let paths =
                groups.iter().map(|&(g, _)| first.groups.get(g).map_or("", |group| group.name.as_str()));
            match shared_top(paths).filter(|_| options.xform.is_none()) {
                Some(top) => {
                    let object = add_xform(&mut archive, tree.parent, top, None)?;
                    add_groom_version(&mut archive, object)?;
                    tree.nodes.push((format!("/{top}"), object));
                }
                None => {
                    tree.parent = add_xform(&mut archive, tree.parent, "groom", None)?;
                    add_groom_version(&mut archive, tree.parent)?;
                }
            }
        }
        if let Some(matrix) = options.xform {
            tree.parent = add_xform(&mut archive, tree.parent, "xform", Some(matrix))?;
        }
        let several = groups.len() > 1;
        // Ids are written for every object or none: a reader numbers objects without ids after
        // the ids it was given, so one object's plain 0, 1, 2, … would read back elsewhere.
        let write_ids = has_custom_ids(&first.strand_ids);
        let mut objects = Vec::with_capacity(groups.len());
        for (group, strands) in groups {
            let part = GroupPart::of(first, group, &strands);
            // A group's path becomes Xforms above a curves object named after its last part.
            let properties =
                tree.place(&mut archive, &part.group.name, &options.object_name, |a, at, name| {
                    add_curves(
                        a,
                        at,
                        name,
                        &part,
                        (group, several, write_ids),
                        (options.unreal, animated && options.velocities),
                        time_sampling,
                    )
                })?;
            objects.push(GroupObject { properties, group, strands });
        }
        let mut meshes = Vec::new();
        if options.objects != Objects::Curves {
            for (index, mesh) in first.meshes.iter().enumerate() {
                let scale = if options.unreal { epic::UNITS_PER_METRE } else { 1.0 };
                meshes.push(tree.place(&mut archive, &mesh.path, "mesh", |a, at, name| {
                    add_polymesh(a, at, name, (index, mesh, scale), time_sampling)
                })??);
            }
        }
        Ok(CurvesWriter {
            archive,
            objects,
            meshes,
            animated,
            scale: if options.unreal { epic::UNITS_PER_METRE } else { 1.0 },
            frames_per_second: options.frames_per_second,
            strand_offsets: first.strand_offsets.clone(),
            basis: first.basis,
            mesh_sizes: first.meshes.iter().map(|m| m.points.len()).collect(),
            attribute_layout: layout(first),
            previous_points: None,
            pending: None,
            frames: 0,
            written: 0,
            time_sampling,
        })
    }

    /// Adds the next frame. Its topology, basis and attribute layout must match the first (an
    /// `InvalidInput` error when not; any other error is the stream's).
    pub fn write_frame(&mut self, groom: &Groom) -> io::Result<()> {
        let invalid = |message: String| Err(io::Error::new(io::ErrorKind::InvalidInput, message));
        if groom.strand_offsets != self.strand_offsets || groom.basis != self.basis {
            return invalid(format!(
                "frame {} changes the strand layout; Alembic frames share one topology",
                self.frames
            ));
        }
        if layout(groom) != self.attribute_layout {
            return invalid(format!("frame {} has different attributes from the first frame", self.frames));
        }
        if !self.animated && self.frames > 0 {
            return invalid("a static Alembic file holds one frame".into());
        }
        if !groom.meshes.iter().map(|m| m.points.len()).eq(self.mesh_sizes.iter().copied()) {
            return invalid(format!("frame {} has other meshes than the first frame", self.frames));
        }
        if let Some(problem) = overflow_when_scaled(groom, self.scale) {
            return invalid(problem);
        }
        if self.objects.first().is_none_or(|o| o.properties.velocities.is_none()) {
            // Nothing needs the next frame: write this one now, without keeping a copy.
            self.frames += 1;
            return self.write_sample(groom, None);
        }
        if let Some(pending) = self.pending.take() {
            let velocities = velocities(
                self.previous_points.as_deref(),
                &pending.points,
                Some(&groom.points),
                self.frames_per_second,
            );
            self.write_sample(&pending, velocities.as_deref())?;
            self.previous_points = Some(pending.points);
        }
        self.pending = Some(groom.clone());
        self.frames += 1;
        Ok(())
    }

    /// Writes the last frame and closes the archive; returns the stream.
    pub fn finish(mut self) -> io::Result<W> {
        if let Some(pending) = self.pending.take() {
            let velocities =
                velocities(self.previous_points.as_deref(), &pending.points, None, self.frames_per_second);
            self.write_sample(&pending, velocities.as_deref())?;
        }
        self.archive.finish()
    }

    fn write_sample(&mut self, groom: &Groom, velocities: Option<&[Vec3]>) -> io::Result<()> {
        for object in &mut self.meshes {
            let mesh = &groom.meshes[object.mesh];
            let points: Vec<Vec3> = mesh.points.iter().map(|p| *p * self.scale).collect();
            let samples: [(PropertyId, Cow<[u8]>, u64); 4] = [
                (object.bounds, Cow::Owned(bounds_bytes(&points)), 1),
                (object.positions, Cow::Borrowed(bytemuck::cast_slice(&points)), points.len() as u64),
                (
                    object.face_indices,
                    Cow::Borrowed(bytemuck::cast_slice(&object.clockwise_indices)),
                    object.clockwise_indices.len() as u64,
                ),
                (
                    object.face_counts,
                    Cow::Owned(mesh.face_counts.iter().flat_map(|&c| (c as i32).to_le_bytes()).collect()),
                    mesh.face_counts.len() as u64,
                ),
            ];
            for (id, bytes, elements) in samples {
                self.archive.set_sample(id, &bytes, elements)?;
            }
            if let Some(id) = object.visibility.for_frame(
                &mut self.archive,
                mesh.invisible,
                self.written,
                self.time_sampling,
            )? {
                self.archive.set_sample(id, visibility_byte(mesh.invisible), 1)?;
            }
        }
        for k in 0..self.objects.len() {
            let GroupObject { group, strands, .. } = &self.objects[k];
            let part = GroupPart::of(groom, *group, strands);
            let velocities = velocities.map(|v| strands.per_vertex(groom, v, 1));
            self.write_object_sample(k, &part, velocities.as_deref())?;
        }
        self.written += 1;
        Ok(())
    }

    fn write_object_sample(
        &mut self,
        object: usize,
        part: &GroupPart,
        velocities: Option<&[Vec3]>,
    ) -> io::Result<()> {
        let scale = self.scale;
        let points: Cow<[Vec3]> = if scale == 1.0 {
            Cow::Borrowed(&part.points)
        } else {
            Cow::Owned(part.points.iter().map(|p| *p * scale).collect())
        };
        let hidden = part.group.invisible;
        let visible = self.objects[object].properties.visibility.for_frame(
            &mut self.archive,
            hidden,
            self.written,
            self.time_sampling,
        )?;
        let p = &self.objects[object].properties;
        let counts = &part.counts;
        let velocities: Vec<Vec3> = velocities.unwrap_or(&[]).iter().map(|v| *v * scale).collect();
        let mut basis = basis_bytes(part.group.basis);
        basis[1] = (part.group.wrap == CurveWrap::Periodic) as u8;
        // Samples in the order the C++ writer sets them (.arbGeomParams members before the
        // optional schema properties), so files match it byte for byte.
        let mut samples: Vec<(PropertyId, Cow<[u8]>, u64)> = vec![
            (p.bounds, Cow::Owned(bounds_bytes(&points)), 1),
            (p.positions, Cow::Borrowed(bytemuck::cast_slice(&points)), points.len() as u64),
            (p.vertex_counts, Cow::Borrowed(bytemuck::cast_slice(counts)), counts.len() as u64),
            (p.basis, Cow::Owned(basis.to_vec()), 1),
        ];
        let widths: Cow<[f32]> = match p.width_rate {
            None => Cow::Borrowed(&part.widths),
            Some(rate) => match group_widths(part, Some(rate)) {
                Some((_, values)) => Cow::Owned(values),
                None => {
                    return Err(io::Error::new(
                        io::ErrorKind::InvalidInput,
                        format!(
                            "frame {}: the widths of {} no longer fit the rate of the first frame ({})",
                            self.frames,
                            part.group.name,
                            rate.alembic_scope()
                        ),
                    ))
                }
            },
        };
        for (id, source) in &p.params {
            let (bytes, elements) = param_bytes(part, source, &widths, scale);
            samples.push((*id, bytes, elements));
        }
        if let Some(id) = p.velocities {
            samples.push((id, Cow::Borrowed(bytemuck::cast_slice(&velocities)), velocities.len() as u64));
        }
        if let Some(id) = p.uv {
            let (bytes, elements) = param_bytes(part, &ParamSource::RootUvs, &widths, scale);
            samples.push((id, bytes, elements));
        }
        let (bytes, elements) = param_bytes(part, &ParamSource::Widths, &widths, scale);
        samples.push((p.width, bytes, elements));
        if let Some(id) = visible {
            samples.push((id, Cow::Borrowed(visibility_byte(hidden)), 1));
        }
        // Keys are pure functions of the bytes: hash on every core, then write in order.
        let keys: Vec<[u8; 16]> = samples.par_iter().map(|(_, bytes, _)| sample_key(bytes)).collect();
        for ((id, bytes, elements), key) in samples.iter().zip(keys) {
            self.archive.set_sample_keyed(*id, bytes, *elements, key)?;
        }
        Ok(())
    }
}

/// Writes a static groom (one sample).
pub fn write_static<W: Write + Seek>(out: W, groom: &Groom, options: &AlembicWriteOptions) -> io::Result<W> {
    let mut writer = CurvesWriter::new(out, groom, options, false)?;
    writer.write_frame(groom)?;
    writer.finish()
}

fn layout(groom: &Groom) -> Vec<(String, AttributeRate, usize)> {
    let mut layout: Vec<_> =
        groom.attributes.iter().map(|a| (a.name.clone(), a.rate, a.components)).collect();
    layout.push(("(root uvs)".into(), AttributeRate::Strand, groom.root_uvs.is_some() as usize));
    layout.push(("(guides)".into(), AttributeRate::Strand, groom.guides.is_some() as usize));
    layout.push(("(ids)".into(), AttributeRate::Strand, has_custom_ids(&groom.strand_ids) as usize));
    layout
}

/// The `.arbGeomParams` name of a groom attribute (Epic's names with `--unreal`).
fn param_name(unreal: bool, attribute: &str) -> String {
    match (unreal, attribute) {
        (false, name) => name.to_string(),
        (true, attr::COLOR) => epic::COLOR.to_string(),
        (true, name) if name.starts_with(epic::PREFIX) => name.to_string(),
        (true, name) => format!("{}{name}", epic::PREFIX),
    }
}

/// Strand ids are only worth writing when they are not simply 0, 1, 2, …
fn has_custom_ids(ids: &[u32]) -> bool {
    ids.iter().enumerate().any(|(i, &id)| id != i as u32)
}

fn velocities(
    previous: Option<&[Vec3]>,
    current: &[Vec3],
    next: Option<&[Vec3]>,
    fps: f64,
) -> Option<Vec<Vec3>> {
    let fps = fps as f32;
    Some(match (previous, next) {
        (Some(prev), Some(next)) => prev.iter().zip(next).map(|(a, b)| (*b - *a) * (0.5 * fps)).collect(),
        (None, Some(next)) => current.iter().zip(next).map(|(a, b)| (*b - *a) * fps).collect(),
        (Some(prev), None) => prev.iter().zip(current).map(|(a, b)| (*b - *a) * fps).collect(),
        (None, None) => vec![Vec3::ZERO; current.len()],
    })
}

/// The widths of a group at the rate its file gave them, while they fit it (`rate`: the one the
/// first frame chose, which a later frame must fit too); `None`: per vertex.
/// Alembic has no pinned curves: `var` counts segment ends as on nonperiodic ones.
fn group_widths(part: &GroupPart, rate: Option<Interpolation>) -> Option<(Interpolation, Vec<f32>)> {
    let group = &part.group;
    let counts: Vec<usize> = part.counts.iter().map(|&c| c as usize).collect();
    let rate = rate.or(group.width_interpolation);
    primvar_rates::widths_at(rate, group.basis, CurveWrap::Nonperiodic, &counts, &part.widths)
}

fn geom_param_metadata(scope: &str, pod: Pod, extent: u8, interpretation: &str) -> MetaData {
    MetaData::new()
        .with("arrayExtent", "1")
        .with("geoScope", scope)
        .with("isGeomParam", "true")
        .with("podExtent", &extent.to_string())
        .with("podName", pod.name())
        .with("interpretation", interpretation)
}

fn scope(rate: AttributeRate) -> &'static str {
    match rate {
        AttributeRate::Vertex => "vtx",
        AttributeRate::Strand => "uni",
    }
}

/// The `interpretation` an attribute is written with: its kind's, or for plain floats the one
/// coif always gives that name (the reader maps that back to plain floats).
pub(crate) fn interpretation(kind: AttributeKind, name: &str, components: usize) -> &'static str {
    match (kind, name, components) {
        (AttributeKind::Point, _, 3) => "point",
        (AttributeKind::Normal, _, 3) => "normal",
        (AttributeKind::Vector, _, 3) => "vector",
        (AttributeKind::Color, _, 3) | (_, attr::COLOR, 3) => "rgb",
        (AttributeKind::Color, _, 4) | (_, attr::COLOR, 4) => "rgba",
        (_, _, 2) => "vector",
        _ => "",
    }
}

/// The POD an attribute is written as: its integer kind's (int32 also for the names Unreal wants
/// as ints), bool for flags, else float32.
pub(crate) fn pod(kind: AttributeKind, name: &str) -> Pod {
    match kind {
        AttributeKind::Int => Pod::I32,
        AttributeKind::UInt => Pod::U32,
        AttributeKind::Int64 => Pod::I64,
        AttributeKind::UInt64 => Pod::U64,
        AttributeKind::Bool => Pod::Bool,
        _ if written_as_int32(name) => Pod::I32,
        _ => Pod::F32,
    }
}

/// A geometry object of `schema` with what every such schema starts with: its `.geom` compound,
/// `.selfBnds` and `P` (returned in that order after the object).
fn add_geom_object<W: Write + Seek>(
    archive: &mut ArchiveWriter<W>,
    parent: ObjectId,
    name: &str,
    schema: &str,
    ts: u32,
) -> (ObjectId, CompoundId, PropertyId, PropertyId) {
    let object_metadata = MetaData::new()
        .with("schema", schema)
        .with("schemaBaseType", GEOM_BASE)
        .with("schemaObjTitle", &format!("{schema}:.geom"));
    let object = archive.add_object(parent, name, object_metadata);
    let top = archive.properties(object);
    let geom_metadata = MetaData::new().with("schema", schema).with("schemaBaseType", GEOM_BASE);
    let geom = archive.add_compound(top, ".geom", geom_metadata);
    let bounds =
        archive.add_scalar(geom, ".selfBnds", MetaData::new().with("interpretation", "box"), Pod::F64, 6, ts);
    let point_metadata = MetaData::new().with("geoScope", "vtx").with("interpretation", "point");
    let positions = archive.add_array(geom, "P", point_metadata, Pod::F32, 3, ts);
    (object, geom, bounds, positions)
}

fn add_curves<W: Write + Seek>(
    archive: &mut ArchiveWriter<W>,
    parent: ObjectId,
    name: &str,
    part: &GroupPart,
    (group, several_groups, write_ids): (usize, bool, bool),
    (unreal, with_velocities): (bool, bool),
    ts: u32,
) -> (ObjectId, CurveProperties) {
    let (object, geom, bounds, positions) = add_geom_object(archive, parent, name, CURVE_SCHEMA, ts);
    let vertex_counts = archive.add_array(geom, "nVertices", MetaData::new(), Pod::I32, 1, ts);
    let basis = archive.add_scalar(geom, "curveBasisAndType", MetaData::new(), Pod::U8, 4, ts);

    // Unreal reads widths per file, strand or vertex, but not per segment end.
    let width_rate = group_widths(part, None)
        .map(|(rate, _)| rate)
        .filter(|&rate| !(unreal && rate == Interpolation::Varying));
    let width_scope = width_rate.map_or("vtx", Interpolation::alembic_scope);
    let mut sources = Vec::new();
    if unreal {
        sources.push((epic::WIDTH.to_string(), ParamSource::Widths));
    }
    if unreal || write_ids {
        sources.push((epic::ID.to_string(), ParamSource::StrandIds));
    }
    if part.guides.is_some() {
        sources.push((epic::GUIDE.to_string(), ParamSource::Guides));
    }
    // A groom's own `groom_group_id` (a file's Unreal groups) is written as it is, not replaced.
    let own_group_ids = part.attributes.iter().any(|(a, _)| param_name(unreal, &a.name) == epic::GROUP_ID);
    if (unreal || several_groups) && !own_group_ids {
        sources.push((epic::GROUP_ID.to_string(), ParamSource::GroupId(group as u32)));
    }
    if unreal && part.root_uvs.is_some() {
        sources.push((epic::ROOT_UV.to_string(), ParamSource::RootUvs));
    }
    for (attribute, _) in &part.attributes {
        sources.push((param_name(unreal, &attribute.name), ParamSource::Attribute(attribute.name.clone())));
    }
    // The curves' own normals and velocities go where AbcGeom keeps them, `N` and `.velocities`
    // (animated output's `.velocities` come from the frames instead).
    let own_property = |source: &ParamSource| -> Option<&'static str> {
        let ParamSource::Attribute(name) = source else { return None };
        let (a, _) = part.attribute(name)?;
        if !point_attributes::is_schema_attribute(name, a.rate, a.components) {
            return None;
        }
        match name.as_str() {
            point_attributes::NORMALS => Some("N"),
            point_attributes::VELOCITIES => Some(".velocities"),
            _ => None, // accelerations: AbcGeom's curves have no place of their own for them
        }
    };
    sources.retain(|(_, source)| !(with_velocities && own_property(source) == Some(".velocities")));
    let mut params = Vec::new();
    let mut arb = None;
    for (name, source) in sources {
        let own = own_property(&source);
        let (pod, extent, rate, interp) = match &source {
            ParamSource::Widths => (Pod::F32, 1, AttributeRate::Vertex, ""),
            ParamSource::StrandIds | ParamSource::Guides | ParamSource::GroupId(_) => {
                (Pod::I32, 1, AttributeRate::Strand, "")
            }
            ParamSource::RootUvs => (Pod::F32, 2, AttributeRate::Strand, "vector"),
            ParamSource::Attribute(a) => {
                let (a, _) = part.attribute(a).expect("listed from the group");
                let pod = pod(a.kind, &a.name);
                (pod, a.components as u8, a.rate, interpretation(a.kind, &a.name, a.components))
            }
        };
        let scope = match source {
            ParamSource::Widths => width_scope,
            _ => scope(rate),
        };
        let id = match own {
            Some(".velocities") => {
                let metadata = MetaData::new().with("interpretation", "vector");
                archive.add_array(geom, ".velocities", metadata, pod, extent, ts)
            }
            Some(own) => {
                let metadata = geom_param_metadata(scope, pod, extent, "normal");
                archive.add_array(geom, own, metadata, pod, extent, ts)
            }
            None => {
                let arb =
                    *arb.get_or_insert_with(|| archive.add_compound(geom, ".arbGeomParams", MetaData::new()));
                archive.add_array(
                    arb,
                    &name,
                    geom_param_metadata(scope, pod, extent, interp),
                    pod,
                    extent,
                    ts,
                )
            }
        };
        params.push((id, source));
    }
    let velocities = with_velocities.then(|| {
        archive.add_array(
            geom,
            ".velocities",
            MetaData::new().with("interpretation", "vector"),
            Pod::F32,
            3,
            ts,
        )
    });
    let uv = part.root_uvs.is_some().then(|| {
        let metadata = geom_param_metadata("uni", Pod::F32, 2, "vector");
        archive.add_array(geom, "uv", metadata, Pod::F32, 2, ts)
    });
    let width =
        archive.add_array(geom, "width", geom_param_metadata(width_scope, Pod::F32, 1, ""), Pod::F32, 1, ts);
    let visibility = Visibility::new(archive, object, part.group.invisible, ts);
    let properties = CurveProperties {
        bounds,
        positions,
        vertex_counts,
        basis,
        velocities,
        uv,
        width,
        visibility,
        width_rate,
        params,
    };
    (object, properties)
}

/// The objects placed so far under the writer's parent: a path becomes Xforms above a leaf
/// object (an object already at a path on the way serves as the parent instead).
struct Tree {
    parent: ObjectId,
    /// Every object made, by path.
    nodes: Vec<(String, ObjectId)>,
}

impl Tree {
    /// Makes a leaf object at `path` (`/root/Head/HeadMesh`) with `make(archive, parent,
    /// name)`, Xforms made on the way, its name made unique; `fallback` names an object whose
    /// path is empty.
    fn place<W: Write + Seek, T>(
        &mut self,
        archive: &mut ArchiveWriter<W>,
        path: &str,
        fallback: &str,
        make: impl FnOnce(&mut ArchiveWriter<W>, ObjectId, &str) -> (ObjectId, T),
    ) -> io::Result<T> {
        let components: Vec<&str> = path.split('/').filter(|c| !c.is_empty()).collect();
        let (last, above) = components.split_last().map_or((fallback, &[][..]), |(l, a)| (*l, a));
        let mut at = self.parent;
        let mut prefix = String::new();
        for component in above {
            prefix.push('/');
            prefix.push_str(component);
            at = match self.nodes.iter().find(|(p, _)| *p == prefix) {
                Some((_, id)) => *id,
                None => {
                    let id = add_xform(archive, at, component, None)?;
                    self.nodes.push((prefix.clone(), id));
                    id
                }
            };
        }
        // Sibling names are unique in Alembic: a second object at a path gets a suffix.
        let mut name = last.to_string();
        let mut n = 1;
        while self.nodes.iter().any(|(p, _)| *p == format!("{prefix}/{name}")) {
            n += 1;
            name = format!("{last}_{n}");
        }
        let (object, made) = make(archive, at, &name);
        self.nodes.push((format!("{prefix}/{name}"), object));
        Ok(made)
    }
}

/// The first part of every path (`/root/Hair/HairData` → `root`) when they all share it and it is
/// an Xform above each (not an object of its own); `None` for no paths.
fn shared_top<'a>(paths: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let mut top = None;
    for path in paths {
        let mut components = path.split('/').filter(|c| !c.is_empty());
        let (first, below) = (components.next()?, components.next());
        below?;
        if *top.get_or_insert(first) != first {
            return None;
        }
    }
    top
}

/// What of `groom` scaling by `scale` (Epic's centimetres) takes beyond f32: a point, a width or
/// a mesh point over 3.4e36 m would be written as infinity.
fn overflow_when_scaled(groom: &Groom, scale: f32) -> Option<String> {
    if scale == 1.0 {
        return None;
    }
    let overflows = |v: f32| !(v * scale).is_finite();
    let beyond = |what: String, v: f32| {
        Some(format!(
            "{what} is {} m, beyond what a float holds in Unreal's centimetres",
            crate::validate::shortest(v.into())
        ))
    };
    if let Some(i) = groom.points.iter().position(|p| p.to_array().into_iter().any(overflows)) {
        let (strand, vertex) = groom.strand_and_vertex(i);
        let coordinate = groom.points[i].abs().max_element();
        return beyond(format!("strand {strand}, vertex {vertex}: a coordinate"), coordinate);
    }
    if let Some(i) = groom.widths.iter().position(|&w| overflows(w)) {
        let (strand, vertex) = groom.strand_and_vertex(i);
        return beyond(format!("strand {strand}, vertex {vertex}: the width"), groom.widths[i]);
    }
    // `rest` is a position too, scaled with the points.
    if let Some(v) = groom.attribute("rest").and_then(|a| a.floats().iter().copied().find(|&v| overflows(v)))
    {
        return beyond("attribute 'rest': a coordinate".into(), v.abs());
    }
    for mesh in &groom.meshes {
        if let Some(p) = mesh.points.iter().find(|p| p.to_array().into_iter().any(overflows)) {
            return beyond(format!("mesh {}: a point's coordinate", mesh.path), p.abs().max_element());
        }
    }
    None
}

/// A PolyMesh object for groom mesh `index` (points scaled by `scale` when written), its
/// properties in the C++ writer's order, its primvars written once (they do not move).
fn add_polymesh<W: Write + Seek>(
    archive: &mut ArchiveWriter<W>,
    parent: ObjectId,
    name: &str,
    (index, mesh, scale): (usize, &SurfaceMesh, f32),
    ts: u32,
) -> (ObjectId, io::Result<MeshObject>) {
    let (object, geom, bounds, positions) = add_geom_object(archive, parent, name, POLYMESH_SCHEMA, ts);
    let face_indices = archive.add_array(geom, ".faceIndices", MetaData::new(), Pod::I32, 1, ts);
    let face_counts = archive.add_array(geom, ".faceCounts", MetaData::new(), Pod::I32, 1, ts);
    // coif's meshes are wound counter-clockwise; Alembic's clockwise.
    let mut clockwise = mesh.clone();
    clockwise.flip_winding();
    clockwise.transform(DMat4::from_scale(glam::DVec3::splat(scale as f64)));
    let clockwise_indices = clockwise.face_indices.iter().map(|&i| i as i32).collect();
    let mut arb = None;
    let main_uv = clockwise.main_uv();
    let written = clockwise.primvars.iter().enumerate().try_for_each(|(index, primvar)| {
        let (parent, name) = match primvar.name.as_str() {
            MeshPrimvar::NORMALS => (geom, "N"),
            _ if Some(index) == main_uv => (geom, "uv"),
            other => (
                *arb.get_or_insert_with(|| archive.add_compound(geom, ".arbGeomParams", MetaData::new())),
                other,
            ),
        };
        add_mesh_param(archive, parent, name, primvar)
    });
    let visibility = Visibility::new(archive, object, mesh.invisible, ts);
    let made = written.map(|()| MeshObject {
        mesh: index,
        bounds,
        positions,
        face_indices,
        face_counts,
        clockwise_indices,
        visibility,
    });
    (object, made)
}

/// An object's `visible` property, beside `.geom` as AbcGeom's `CreateVisibilityProperty`
/// places it.
fn hidden_property<W: Write + Seek>(archive: &mut ArchiveWriter<W>, object: ObjectId, ts: u32) -> PropertyId {
    let top = archive.properties(object);
    archive.add_scalar(top, VISIBLE, MetaData::new(), Pod::I8, 1, ts)
}

/// One mesh primvar as a geometry parameter with one sample: a plain array, or a `.vals` /
/// `.indices` compound when indexed; its interpolation as `geoScope`.
fn add_mesh_param<W: Write + Seek>(
    archive: &mut ArchiveWriter<W>,
    parent: CompoundId,
    name: &str,
    primvar: &MeshPrimvar,
) -> io::Result<()> {
    let pod = pod(primvar.kind, &primvar.name);
    let extent = primvar.components as u8;
    let metadata = geom_param_metadata(
        primvar.interpolation.alembic_scope(),
        pod,
        extent,
        interpretation(primvar.kind, &primvar.name, primvar.components),
    );
    let bytes: Vec<u8> = match &primvar.values {
        AttributeData::Int(values) => int_bytes(values, pod),
        AttributeData::Float(values) => match pod {
            Pod::I32 => values.iter().flat_map(|&v| (v as i32).to_le_bytes()).collect(),
            Pod::Bool => values.iter().map(|&v| (v != 0.0) as u8).collect(),
            _ => bytemuck::cast_slice(values).to_vec(),
        },
    };
    // The UV set's name goes where Blender writes and reads it (its importer names the map so).
    let metadata = if name == "uv" && crate::surface_mesh::is_identifier(&primvar.name) {
        metadata.with("sourceName", &primvar.name)
    } else {
        metadata
    };
    let elements = (primvar.values.len() / primvar.components) as u64;
    // The C++ library and ogawa-rs read a PolyMesh's `uv` as an indexed compound (Blender
    // writes it so), so it always gets indices.
    let identity: Vec<u32>;
    let indices = match &primvar.indices {
        None if name == "uv" => {
            identity = (0..elements as u32).collect();
            Some(&identity)
        }
        indices => indices.as_ref(),
    };
    match indices {
        None => {
            let id = archive.add_array(parent, name, metadata, pod, extent, 0);
            archive.set_sample(id, &bytes, elements)
        }
        Some(indices) => {
            let compound = archive.add_compound(parent, name, metadata.clone());
            let vals = archive.add_array(compound, ".vals", metadata, pod, extent, 0);
            archive.set_sample(vals, &bytes, elements)?;
            let ids = archive.add_array(compound, ".indices", MetaData::new(), Pod::U32, 1, 0);
            archive.set_sample(ids, bytemuck::cast_slice(indices), indices.len() as u64)
        }
    }
}

/// An Xform object; `matrix` `None` is the identity (an empty `.xform`).
fn add_xform<W: Write + Seek>(
    archive: &mut ArchiveWriter<W>,
    parent: ObjectId,
    name: &str,
    matrix: Option<DMat4>,
) -> io::Result<ObjectId> {
    let metadata = MetaData::new()
        .with("schema", XFORM_SCHEMA)
        .with("schemaObjTitle", &format!("{XFORM_SCHEMA}:.xform"));
    let object = archive.add_object(parent, name, metadata);
    let top = archive.properties(object);
    let xform = archive.add_compound(top, ".xform", MetaData::new().with("schema", XFORM_SCHEMA));
    if let Some(matrix) = matrix.filter(|m| *m != DMat4::IDENTITY) {
        let inherits = archive.add_scalar(xform, ".inherits", MetaData::new(), Pod::Bool, 1, 0);
        archive.set_sample(inherits, &[1], 1)?;
        let ops = archive.add_scalar(xform, ".ops", MetaData::new(), Pod::U8, 1, 0);
        archive.set_sample(ops, &[0x30], 1)?; // one 4×4 matrix op
        let vals = archive.add_scalar(xform, ".vals", MetaData::new(), Pod::F64, 16, 0);
        // Imath stores the row-vector matrix row by row: glam's columns, in order.
        let values = matrix.to_cols_array();
        archive.set_sample(vals, bytemuck::cast_slice(&values), 1)?;
        let not_identity =
            archive.add_scalar(xform, "isNotConstantIdentity", MetaData::new(), Pod::Bool, 1, 0);
        archive.set_sample(not_identity, &[1], 1)?;
    }
    Ok(object)
}

/// Epic's groom-wide properties on the top Xform's `.userProperties`.
fn add_groom_version<W: Write + Seek>(archive: &mut ArchiveWriter<W>, object: ObjectId) -> io::Result<()> {
    let top = archive.properties(object);
    let user: CompoundId = archive.add_compound(top, ".userProperties", MetaData::new());
    let major = archive.add_scalar(user, epic::VERSION_MAJOR, MetaData::new(), Pod::I16, 1, 0);
    archive.set_sample(major, &epic::SPEC_VERSION.0.to_le_bytes(), 1)?;
    let minor = archive.add_scalar(user, epic::VERSION_MINOR, MetaData::new(), Pod::I16, 1, 0);
    archive.set_sample(minor, &epic::SPEC_VERSION.1.to_le_bytes(), 1)?;
    let tool = archive.add_scalar(user, epic::TOOL, MetaData::new(), Pod::String, 1, 0);
    let mut text = format!("coif {}", env!("CARGO_PKG_VERSION")).into_bytes();
    text.push(0);
    archive.set_sample(tool, &text, 1)
}

fn bounds_bytes(points: &[Vec3]) -> Vec<u8> {
    let (mut lo, mut hi) = ([f64::MAX; 3], [-f64::MAX; 3]);
    for p in points {
        for axis in 0..3 {
            lo[axis] = lo[axis].min(p[axis] as f64);
            hi[axis] = hi[axis].max(p[axis] as f64);
        }
    }
    lo.iter().chain(&hi).flat_map(|v| v.to_le_bytes()).collect()
}

/// Curve type, wrap, basis, basis. Blender and Houdini take the kind from the basis byte, so
/// linear curves say "no basis" (0), not the library's default Bézier.
pub fn basis_bytes(basis: CurveBasis) -> [u8; 4] {
    match basis {
        CurveBasis::Linear => [1, 0, 0, 0],
        CurveBasis::Bezier => [0, 0, 1, 1],
        CurveBasis::BSpline => [0, 0, 2, 2],
        CurveBasis::CatmullRom => [0, 0, 3, 3],
    }
}

/// Attributes held as floats that Alembic readers want as int32: Unreal's Alembic groom spec
/// gives `groom_closest_guides` as int32×3 (its importer also takes float32×3, other readers may
/// not).
fn written_as_int32(name: &str) -> bool {
    name == crate::guides::CLOSEST_GUIDES
}

/// The bytes and element count of a parameter; `widths` are the groom's at the rate written.
fn param_bytes<'g>(
    part: &'g GroupPart,
    source: &ParamSource,
    widths: &'g [f32],
    scale: f32,
) -> (Cow<'g, [u8]>, u64) {
    fn floats<'g>(values: &'g [f32], factor: f32) -> Cow<'g, [u8]> {
        if factor == 1.0 {
            Cow::Borrowed(bytemuck::cast_slice(values))
        } else {
            Cow::Owned(values.iter().flat_map(|v| (v * factor).to_le_bytes()).collect())
        }
    }
    match source {
        ParamSource::Widths => (floats(widths, scale), widths.len() as u64),
        ParamSource::StrandIds => (
            Cow::Owned(part.strand_ids.iter().flat_map(|&id| (id as i32).to_le_bytes()).collect()),
            part.strand_ids.len() as u64,
        ),
        ParamSource::Guides => {
            let guides = part.guides.as_deref().unwrap_or(&[]);
            (Cow::Owned(guides.iter().flat_map(|&g| (g as i32).to_le_bytes()).collect()), guides.len() as u64)
        }
        ParamSource::GroupId(group) => {
            let count = part.strand_count();
            (Cow::Owned(group.to_le_bytes().repeat(count)), count as u64)
        }
        ParamSource::RootUvs => {
            let uvs = part.root_uvs.as_deref().unwrap_or(&[]);
            (floats(bytemuck::cast_slice(uvs), 1.0), uvs.len() as u64)
        }
        ParamSource::Attribute(name) => {
            let (a, data) = part.attribute(name).expect("layout is fixed by the first frame");
            // Positions (`rest`) and vectors (velocities) follow the unit change.
            let factor = match crate::io::direction_kind(a.kind, name) {
                Some(AttributeKind::Point | AttributeKind::Vector) if a.components == 3 => scale,
                _ => 1.0,
            };
            let elements = (data.len() / a.components.max(1)) as u64;
            let data = match data {
                Values::Int(values) => return (Cow::Owned(int_bytes(values, pod(a.kind, name))), elements),
                Values::Float(data) => data,
            };
            match pod(a.kind, name) {
                Pod::I32 => {
                    (Cow::Owned(data.iter().flat_map(|&v| (v as i32).to_le_bytes()).collect()), elements)
                }
                Pod::Bool => (Cow::Owned(data.iter().map(|&v| (v != 0.0) as u8).collect()), elements),
                _ => (floats(data, factor), elements),
            }
        }
    }
}

/// Integers as an integer kind stores them, as the bytes of its POD ([`pod`]); the kind holds
/// each value (`Groom::validate` checks), so none is cut.
fn int_bytes(values: &[i64], pod: Pod) -> Vec<u8> {
    match pod {
        Pod::I32 => values.iter().flat_map(|&v| (v as i32).to_le_bytes()).collect(),
        Pod::U32 => values.iter().flat_map(|&v| (v as u32).to_le_bytes()).collect(),
        Pod::I64 | Pod::U64 => values.iter().flat_map(|&v| v.to_le_bytes()).collect(),
        _ => unreachable!("integer attributes are written as integer PODs"),
    }
}
