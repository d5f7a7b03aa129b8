//! Reading grooms from Alembic: every Curves object in the archive (under any Xform
//! hierarchy, transforms applied) merged into one groom, at one sample time or at all of them.
//! Accepts what coif writes and what other tools write: cubic bases, widths per file / curve /
//! vertex, plain or indexed geometry parameters, Epic's `groom_*` attributes.
use glam::{DMat4, DVec3, Vec3};
use rayon::prelude::*;

use super::archive_read::{Archive, Compound, Object, Property, Sampled};
use super::curves_write::{epic, CURVE_SCHEMA, XFORM_SCHEMA};
use super::ogawa::{OgawaError, OgawaResult};
use super::types::{Pod, TimeSampling};
use crate::groom::{attr, Attribute, AttributeRate, CurveBasis, CurveGroup, CurveWrap, Groom};
use crate::surface_mesh::SurfaceMesh;

/// Alembic's polygon-mesh schema (a scalp or head beside the curves).
pub const POLYMESH_SCHEMA: &str = "AbcGeom_PolyMesh_v1";

fn fail<T>(message: impl Into<String>) -> OgawaResult<T> {
    Err(OgawaError(message.into()))
}

/// Width used when a file has none (the `coif generate` root width), in metres.
pub const DEFAULT_WIDTH: f32 = 80e-6;
/// A file may expand to at most this many vertices (all frames together) per byte it holds,
/// plus a fixed allowance: constant samples are stored once but expand per frame.
const MAX_VERTICES_PER_FILE_BYTE: u64 = 64;

/// Curves found in an archive, ready to be read at any sample.
pub struct CurvesArchive<'a> {
    archive: Archive<'a>,
    /// Paths of the curves objects, each with the paths of the Xforms above it (root first).
    curves: Vec<(String, Vec<String>)>,
    /// Paths of the polygon meshes (scalp, head), likewise.
    meshes: Vec<(String, Vec<String>)>,
    /// Samples of the first curves object's positions: the archive's frames.
    frames: u32,
    frame_sampling: TimeSampling,
    /// The file follows Epic's groom spec (it declares `groom_version_major`): centimetres.
    pub epic_groom: bool,
}

struct CurvesObject<'o, 'a> {
    path: String,
    geom: &'o Compound<'a>,
    xforms: Vec<&'o Compound<'a>>,
}

impl<'a> CurvesArchive<'a> {
    pub fn open(bytes: &'a [u8]) -> OgawaResult<Self> {
        let archive = Archive::open(bytes)?;
        // The object tree lives inside `archive`; collect paths first, then resolve references.
        let mut found = Found::default();
        collect(&archive.top, &mut Vec::new(), &mut found)?;
        let Found { curves: found, meshes, epic_groom } = found;
        if found.is_empty() {
            return fail("the archive holds no curves (no AbcGeom_Curve_v2 object)");
        }
        let mut result = CurvesArchive {
            archive,
            curves: found,
            meshes,
            frames: 1,
            frame_sampling: TimeSampling::identity(),
            epic_groom,
        };
        let first = result.resolve(0)?;
        let positions = required(&first, "P")?;
        let (frames, sampling) = (positions.num_samples.max(1), positions.time_sampling as usize);
        result.frames = frames;
        result.frame_sampling = result.archive.time_samplings[sampling].clone();
        Ok(result)
    }

    /// The `index`-th curves object with its `.geom` and the `.xform` compounds above it.
    fn resolve(&self, index: usize) -> OgawaResult<CurvesObject<'_, 'a>> {
        let (path, xform_paths) = &self.curves[index];
        self.resolve_path(path, xform_paths)
    }

    /// The object at `path` with its `.geom` and the `.xform` compounds of `xform_paths`.
    fn resolve_path(&self, path: &str, xform_paths: &[String]) -> OgawaResult<CurvesObject<'_, 'a>> {
        let top = &self.archive.top;
        let object = find(top, path).expect("collected from this tree");
        let geom = object
            .properties
            .compound(".geom")
            .ok_or_else(|| OgawaError(format!("{path}: no .geom compound")))?;
        let xforms = xform_paths
            .iter()
            .filter_map(|p| find(top, p).and_then(|o| o.properties.compound(".xform")))
            .collect();
        Ok(CurvesObject { path: path.to_string(), geom, xforms })
    }

    /// Number of samples (frames) of the positions.
    pub fn frame_count(&self) -> u32 {
        self.frames
    }

    /// Time in seconds of frame `frame`.
    pub fn frame_time(&self, frame: u32) -> f64 {
        self.frame_sampling.sample_time(frame as u64)
    }

    /// Every curves object merged into one groom, at frame `frame` (in file units).
    pub fn read_frame(&self, frame: u32) -> OgawaResult<Groom> {
        if frame >= self.frames {
            return fail(format!(
                "frame {frame} does not exist; the file has {} (0 to {})",
                self.frames,
                self.frames - 1
            ));
        }
        let time = self.frame_time(frame);
        let mut merged: Option<Groom> = None;
        for index in 0..self.curves.len() {
            let object = self.resolve(index)?;
            let groom = self.read_object(&object, time)?;
            merged = Some(match merged {
                None => groom,
                Some(acc) => merge(acc, groom, &object.path)?,
            });
        }
        let mut groom = merged.expect("at least one curves object");
        groom.drop_default_group_named(super::curves_write::DEFAULT_OBJECT_NAME);
        for (path, xform_paths) in &self.meshes {
            let object = self.resolve_path(path, xform_paths)?;
            if let Some(mesh) = self.read_mesh(&object, time)? {
                groom.meshes.push(mesh);
            }
        }
        Ok(groom)
    }

    /// A `PolyMesh` object (a scalp or head) at `time`, transformed, wound counter-clockwise
    /// (Alembic winds clockwise); `None` when it has no faces.
    fn read_mesh(&self, object: &CurvesObject<'_, 'a>, time: f64) -> OgawaResult<Option<SurfaceMesh>> {
        let ogawa = &self.archive.ogawa;
        let path = &object.path;
        let positions = required(object, "P")?;
        positions.expect(&[Pod::F32, Pod::F64], 3)?;
        let index = self.index_at(positions, time);
        let points: Vec<Vec3> = if positions.pod == Pod::F32 {
            positions.read_f32_as(ogawa, index)?
        } else {
            positions.read_f32(ogawa, index)?.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect()
        };
        let indices = |name: &str| -> OgawaResult<Vec<u32>> {
            let property = required(object, name)?;
            property.expect(&[Pod::I32, Pod::U32], 1)?;
            let values = property.read_f64(ogawa, self.index_at(property, time))?;
            values
                .iter()
                .enumerate()
                .map(|(i, &v)| {
                    if (0.0..=u32::MAX as f64).contains(&v) {
                        Ok(v as u32)
                    } else {
                        fail(format!("{path}: {name} entry {i} is {v}"))
                    }
                })
                .collect()
        };
        let face_counts = indices(".faceCounts")?;
        let face_indices = indices(".faceIndices")?;
        if face_counts.is_empty() {
            return Ok(None);
        }
        let matrix = self.world_matrix(object, time)?;
        let mut mesh = SurfaceMesh {
            path: path.clone(),
            points: points.iter().map(|p| matrix.transform_point3(p.as_dvec3()).as_vec3()).collect(),
            face_counts,
            face_indices,
        };
        // Clockwise in the file; a mirroring transform turns the winding once more.
        if matrix.determinant() >= 0.0 {
            mesh.flip_winding();
        }
        mesh.check().map_err(|problem| OgawaError(format!("{path}: {problem}")))?;
        Ok(Some(mesh))
    }

    /// Every frame, in order; refuses files that would expand far beyond their size.
    pub fn read_all_frames(&self) -> OgawaResult<Vec<Groom>> {
        let first = self.read_frame(0)?;
        let total = first.vertex_count() as u64 * self.frames as u64;
        let limit = self.archive.ogawa.len() * MAX_VERTICES_PER_FILE_BYTE + (1 << 20);
        if total > limit {
            return fail(format!(
                "{} frames of {} vertices would expand the {}-byte file to {total} vertices; read one frame instead",
                self.frames,
                first.vertex_count(),
                self.archive.ogawa.len()
            ));
        }
        // Frames are independent: read them on every core (the order of the result is fixed).
        let rest: Vec<Groom> =
            (1..self.frames).into_par_iter().map(|f| self.read_frame(f)).collect::<OgawaResult<_>>()?;
        let mut frames = Vec::with_capacity(self.frames as usize);
        frames.push(first);
        frames.extend(rest);
        Ok(frames)
    }

    fn index_at(&self, property: &Sampled<'a>, time: f64) -> u32 {
        let sampling = &self.archive.time_samplings[property.time_sampling as usize];
        sampling.nearest_index(time, property.num_samples as u64) as u32
    }

    fn read_object(&self, object: &CurvesObject<'_, 'a>, time: f64) -> OgawaResult<Groom> {
        let ogawa = &self.archive.ogawa;
        let path = &object.path;
        let bounds = required(object, ".selfBnds")?;
        bounds.expect(&[Pod::F64, Pod::F32], 6)?;
        let basis_property = required(object, "curveBasisAndType")?;
        basis_property.expect(&[Pod::U8], 4)?;
        let basis_bytes = basis_property.sample_bytes(ogawa, self.index_at(basis_property, time))?;
        let basis = curve_basis(basis_bytes, path)?;

        let positions = required(object, "P")?;
        positions.expect(&[Pod::F32, Pod::F64], 3)?;
        let index = self.index_at(positions, time);
        let mut points: Vec<Vec3> = if positions.pod == Pod::F32 {
            positions.read_f32_as(ogawa, index)?
        } else {
            positions.read_f32(ogawa, index)?.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect()
        };
        let counts_property = required(object, "nVertices")?;
        counts_property.expect(&[Pod::I32, Pod::U32, Pod::I16, Pod::U16], 1)?;
        let counts = counts_property.read_f64(ogawa, self.index_at(counts_property, time))?;
        let mut offsets = Vec::with_capacity(counts.len() + 1);
        offsets.push(0u32);
        let mut total = 0u64;
        for (curve, &count) in counts.iter().enumerate() {
            if count < 0.0 {
                return fail(format!("{path}: curve {curve} has {count} vertices"));
            }
            total += count as u64;
            if total > points.len() as u64 {
                return fail(format!(
                    "{path}: nVertices add up to more than the {} points of P",
                    points.len()
                ));
            }
            offsets.push(total as u32);
        }
        if total != points.len() as u64 {
            return fail(format!("{path}: nVertices add up to {total}, P has {} points", points.len()));
        }
        let strands = counts.len();
        let matrix = self.world_matrix(object, time)?;
        if matrix != DMat4::IDENTITY {
            points.iter_mut().for_each(|p| *p = matrix.transform_point3(p.as_dvec3()).as_vec3());
        }
        let mut groom = Groom { points, strand_offsets: offsets, basis, ..Default::default() };

        let arb = object.geom.compound(".arbGeomParams");
        let epic_width = arb.and_then(|c| c.get(epic::WIDTH));
        let width = match epic_width.or_else(|| object.geom.get("width")) {
            Some(p) => Some(self.expand(p, time, &groom, 1, path)?),
            None => None,
        };
        groom.widths = match width {
            Some(param) => param.into_vertices(&groom),
            None => vec![
                DEFAULT_WIDTH * if self.epic_groom { epic::UNITS_PER_METRE } else { 1.0 };
                groom.vertex_count()
            ],
        };
        groom.strand_ids = (0..strands as u32).collect();

        let uv = arb.and_then(|c| c.get(epic::ROOT_UV)).or_else(|| object.geom.get("uv"));
        if let Some(p) = uv {
            let param = self.expand(p, time, &groom, 2, path)?;
            groom.root_uvs =
                Some(param.to_strand_roots(&groom).chunks_exact(2).map(|c| [c[0], c[1]]).collect());
        }
        for member in arb.map(|c| c.members.as_slice()).unwrap_or(&[]) {
            let name = member.name();
            if name == epic::WIDTH || name == epic::ROOT_UV {
                continue;
            }
            let Some(extent) = param_extent(member) else { continue };
            if !(1..=4).contains(&extent) {
                continue; // not something a groom attribute can hold
            }
            let param = self.expand(member, time, &groom, extent, path)?;
            match name {
                epic::ID => groom.strand_ids = param.to_strands(&groom).iter().map(|&v| v as u32).collect(),
                epic::GUIDE => {
                    groom.guides = Some(param.to_strands(&groom).iter().map(|&v| v != 0.0).collect())
                }
                // One value for the whole object: the object is the group (coif writes that).
                epic::GROUP_ID if param.values.windows(2).all(|w| w[0] == w[1]) => {}
                _ => {
                    let canonical = match name {
                        epic::COLOR => attr::COLOR.to_string(),
                        n => n.strip_prefix(epic::PREFIX).unwrap_or(n).to_string(),
                    };
                    let (rate, data) = match param.rate {
                        Rate::Vertex => (AttributeRate::Vertex, param.values),
                        _ => (AttributeRate::Strand, param.to_strands(&groom)),
                    };
                    let mut attribute = Attribute::new(canonical, rate, extent as usize, data);
                    if attribute.name == "rest" && attribute.components == 3 && matrix != DMat4::IDENTITY {
                        for c in attribute.data.chunks_exact_mut(3) {
                            let p =
                                matrix.transform_point3(DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64));
                            c.copy_from_slice(&p.as_vec3().to_array());
                        }
                    }
                    groom.set_attribute(attribute);
                }
            }
        }
        groom.set_single_group(CurveGroup::new(path.clone(), basis, CurveWrap::Nonperiodic));
        Ok(groom)
    }

    /// The product of the Xform chain above a curves object, at `time`.
    fn world_matrix(&self, object: &CurvesObject<'_, 'a>, time: f64) -> OgawaResult<DMat4> {
        let mut world = DMat4::IDENTITY;
        for xform in &object.xforms {
            let local = self.local_matrix(xform, time)?;
            let inherits = match xform.sampled(".inherits") {
                Some(p) => {
                    p.read_f64(&self.archive.ogawa, self.index_at(p, time))?.first().copied().unwrap_or(1.0)
                        != 0.0
                }
                None => true,
            };
            world = if inherits { world * local } else { local };
        }
        Ok(world)
    }

    fn local_matrix(&self, xform: &Compound<'a>, time: f64) -> OgawaResult<DMat4> {
        let ogawa = &self.archive.ogawa;
        let Some(ops) = xform.sampled(".ops") else { return Ok(DMat4::IDENTITY) };
        let ops = ops.sample_bytes(ogawa, 0)?;
        let vals = match xform.sampled(".vals") {
            Some(v) => v.read_f64(ogawa, self.index_at(v, time))?,
            None => Vec::new(),
        };
        let mut matrix = DMat4::IDENTITY;
        let mut at = 0usize;
        for &op in ops {
            let channels = match op >> 4 {
                0 | 1 => 3,
                2 => 4,
                3 => 16,
                4..=6 => 1,
                other => return fail(format!("xform {}: unknown operation type {other}", xform.name)),
            };
            let Some(v) = vals.get(at..at + channels) else {
                return fail(format!("xform {}: {} values for its operations", xform.name, vals.len()));
            };
            at += channels;
            let op_matrix = match op >> 4 {
                0 => DMat4::from_scale(DVec3::new(v[0], v[1], v[2])),
                1 => DMat4::from_translation(DVec3::new(v[0], v[1], v[2])),
                2 => {
                    let axis = DVec3::new(v[0], v[1], v[2]);
                    if axis.length_squared() == 0.0 {
                        DMat4::IDENTITY
                    } else {
                        DMat4::from_axis_angle(axis.normalize(), v[3].to_radians())
                    }
                }
                3 => DMat4::from_cols_array(v.try_into().unwrap()),
                4 => DMat4::from_rotation_x(v[0].to_radians()),
                5 => DMat4::from_rotation_y(v[0].to_radians()),
                _ => DMat4::from_rotation_z(v[0].to_radians()),
            };
            // Operations are listed outermost first: the last one touches the point first.
            matrix *= op_matrix;
        }
        Ok(matrix)
    }

    /// A geometry parameter (plain array or indexed `.vals`/`.indices` compound) at `time`,
    /// expanded through its indices, with its rate from `geoScope` or, failing that, its count.
    fn expand(
        &self,
        property: &Property<'a>,
        time: f64,
        groom: &Groom,
        extent: u8,
        path: &str,
    ) -> OgawaResult<Param> {
        let ogawa = &self.archive.ogawa;
        let (values, metadata_scope, name) = match property {
            Property::Sampled(s) => {
                s.expect(NUMERIC, extent)?;
                (
                    s.read_f32(ogawa, self.index_at(s, time))?,
                    s.metadata.get("geoScope").map(str::to_string),
                    s.name.clone(),
                )
            }
            Property::Compound(c) => {
                let vals = c
                    .sampled(".vals")
                    .ok_or_else(|| OgawaError(format!("{path}: {} has no .vals", c.name)))?;
                vals.expect(NUMERIC, extent)?;
                let raw = vals.read_f32(ogawa, self.index_at(vals, time))?;
                let values = match c.sampled(".indices") {
                    Some(indices) => {
                        let indices = indices.read_f64(ogawa, self.index_at(indices, time))?;
                        let e = extent as usize;
                        let mut out = Vec::with_capacity(indices.len() * e);
                        for &i in &indices {
                            let at = i as usize * e;
                            match raw.get(at..at + e) {
                                Some(v) if i >= 0.0 => out.extend_from_slice(v),
                                _ => return fail(format!("{path}: {} index {i} is out of range", c.name)),
                            }
                        }
                        out
                    }
                    None => raw,
                };
                let scope =
                    c.metadata.get("geoScope").or_else(|| vals.metadata.get("geoScope")).map(str::to_string);
                (values, scope, format!("{path}/{}", c.name))
            }
        };
        let count = values.len() / extent as usize;
        let (strands, vertices) = (groom.strand_count(), groom.vertex_count());
        let rate = match metadata_scope.as_deref() {
            Some("vtx") | Some("var") | Some("fvr") => Rate::Vertex,
            Some("uni") => Rate::Strand,
            Some("con") => Rate::Constant,
            _ if count == vertices => Rate::Vertex,
            _ if count == strands => Rate::Strand,
            _ => Rate::Constant,
        };
        let expected = match rate {
            Rate::Vertex => vertices,
            Rate::Strand => strands,
            Rate::Constant => 1,
        };
        if count != expected {
            return fail(format!("{name}: {count} values, its scope needs {expected}"));
        }
        Ok(Param { values, extent: extent as usize, rate })
    }
}

const NUMERIC: &[Pod] = &[
    Pod::F32,
    Pod::F64,
    Pod::F16,
    Pod::I32,
    Pod::U32,
    Pod::I16,
    Pod::U16,
    Pod::I8,
    Pod::U8,
    Pod::Bool,
    Pod::I64,
    Pod::U64,
];

#[derive(Clone, Copy, PartialEq)]
enum Rate {
    Constant,
    Strand,
    Vertex,
}

struct Param {
    values: Vec<f32>,
    extent: usize,
    rate: Rate,
}

impl Param {
    fn into_vertices(self, groom: &Groom) -> Vec<f32> {
        match self.rate {
            Rate::Vertex => self.values,
            Rate::Constant => self.values.repeat(groom.vertex_count()),
            Rate::Strand => groom
                .vertex_counts()
                .enumerate()
                .flat_map(|(s, n)| self.values[s * self.extent..(s + 1) * self.extent].repeat(n))
                .collect(),
        }
    }

    fn to_strands(&self, groom: &Groom) -> Vec<f32> {
        match self.rate {
            Rate::Strand => self.values.clone(),
            Rate::Constant => self.values.repeat(groom.strand_count()),
            Rate::Vertex => self.to_strand_roots(groom),
        }
    }

    /// Per-strand values, taking a per-vertex parameter at each strand's root.
    fn to_strand_roots(&self, groom: &Groom) -> Vec<f32> {
        match self.rate {
            Rate::Vertex => (0..groom.strand_count())
                .flat_map(|s| {
                    let root = groom.strand_offsets[s] as usize * self.extent;
                    self.values.get(root..root + self.extent).unwrap_or(&[]).to_vec()
                })
                .collect(),
            _ => self.to_strands(groom),
        }
    }
}

fn param_extent(property: &Property<'_>) -> Option<u8> {
    match property {
        Property::Sampled(s) if s.pod.size() > 0 => Some(s.extent),
        Property::Compound(c) => c.sampled(".vals").filter(|v| v.pod.size() > 0).map(|v| v.extent),
        _ => None,
    }
}

fn required<'o, 'a>(object: &CurvesObject<'o, 'a>, name: &str) -> OgawaResult<&'o Sampled<'a>> {
    object
        .geom
        .sampled(name)
        .ok_or_else(|| OgawaError(format!("{}: curves without the required '{name}' property", object.path)))
}

/// The curve kind from `curveBasisAndType`: the basis byte decides, as in Blender and Houdini.
fn curve_basis(bytes: &[u8], path: &str) -> OgawaResult<CurveBasis> {
    let [_, wrap, basis, _] =
        bytes.try_into().map_err(|_| OgawaError(format!("{path}: curveBasisAndType is empty")))?;
    if wrap != 0 {
        return fail(format!("{path}: periodic (closed) curves are not hair"));
    }
    Ok(match basis {
        0 => CurveBasis::Linear,
        1 => CurveBasis::Bezier,
        2 => CurveBasis::BSpline,
        3 => CurveBasis::CatmullRom,
        other => return fail(format!("{path}: curve basis {other} (hermite or power) is not supported")),
    })
}

fn has_schema(object: &Object<'_>, schema: &str, title: &str) -> bool {
    object.metadata.get("schema") == Some(schema)
        || object.metadata.get("schemaObjTitle") == Some(&format!("{schema}:{title}"))
}

/// What [`collect`] finds in the object tree.
#[derive(Default)]
struct Found {
    /// Curves and polygon-mesh objects, each with the Xform paths above it (root first).
    curves: Vec<(String, Vec<String>)>,
    meshes: Vec<(String, Vec<String>)>,
    /// The archive declares Epic's groom version.
    epic_groom: bool,
}

/// Finds curves and polygon-mesh objects (paths) and the Xform paths above each; notes Epic's
/// groom version.
fn collect(object: &Object<'_>, xforms: &mut Vec<String>, found: &mut Found) -> OgawaResult<()> {
    if let Some(user) = object.properties.compound(".userProperties") {
        found.epic_groom |= user.get(epic::VERSION_MAJOR).is_some();
    }
    let is_xform =
        has_schema(object, XFORM_SCHEMA, ".xform") && object.properties.compound(".xform").is_some();
    if is_xform {
        xforms.push(object.full_name.clone());
    }
    if has_schema(object, CURVE_SCHEMA, ".geom") {
        found.curves.push((object.full_name.clone(), xforms.clone()));
    } else if has_schema(object, POLYMESH_SCHEMA, ".geom") {
        found.meshes.push((object.full_name.clone(), xforms.clone()));
    }
    for child in &object.children {
        collect(child, xforms, found)?;
    }
    if is_xform {
        xforms.pop();
    }
    Ok(())
}

fn find<'o, 'a>(top: &'o Object<'a>, path: &str) -> Option<&'o Object<'a>> {
    let mut object = top;
    for part in path.split('/').filter(|p| !p.is_empty()) {
        object = object.children.iter().find(|c| c.name == part)?;
    }
    Some(object)
}

/// Appends `b`'s strands (one more curves object, its own group) to `a`.
fn merge(mut a: Groom, mut b: Groom, path: &str) -> OgawaResult<Groom> {
    // Later objects' ids continue after the earlier ones' (ids from a file may be anything).
    let next_id = a.strand_ids.iter().max().map_or(0, |m| m.wrapping_add(1));
    b.strand_ids.iter_mut().for_each(|id| *id = id.wrapping_add(next_id));
    a.append(&b)
        .map_err(|e| OgawaError(format!("{path}: does not fit the curves objects before it: {e}")))?;
    Ok(a)
}
