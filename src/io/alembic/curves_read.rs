//! Reading grooms from Alembic: every Curves object in the archive (under any Xform
//! hierarchy, transforms applied) merged into one groom, at one sample time or at all of them.
//! Accepts what coif writes and what other tools write: cubic bases, widths per file / curve /
//! segment end / vertex, plain or indexed geometry parameters, Epic's `groom_*` attributes.
use glam::{DMat4, DVec3, Vec3};
use rayon::prelude::*;

use super::archive_read::{Archive, Compound, Object, Property, Sampled};
use super::curves_write::{epic, CURVE_SCHEMA, VISIBILITY_HIDDEN, VISIBLE, XFORM_SCHEMA};
use super::ogawa::{OgawaError, OgawaReader, OgawaResult};
use super::types::Pod;
use crate::groom::{
    Attribute, AttributeData, AttributeKind, AttributeRate, CurveBasis, CurveGroup, CurveWrap, Groom,
};
use crate::groups::Interpolation;
use crate::surface_mesh::{MeshInterpolation, MeshPrimvar, SurfaceMesh};
use crate::{point_attributes, primvar_rates};

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
/// Sample times closer than this many frames are the same time (rounding in the samplings).
const SAME_TIME_IN_FRAMES: f64 = 1e-6;
/// The timeline may hold this many sample times beyond one per byte of the file (a constant
/// tail of samples is stored once but still counted).
const MAX_TIMELINE_SAMPLES: u64 = 1 << 20;
/// Frame rate of an archive that says none and has no cyclic sampling (film's rate).
const DEFAULT_FRAMES_PER_SECOND: f64 = 24.0;

/// Curves found in an archive, ready to be read at any sample.
pub struct CurvesArchive<'a> {
    archive: Archive<'a>,
    /// Paths of the curves objects, each with the paths of the Xforms above it (root first).
    curves: Vec<(String, Vec<String>)>,
    /// Paths of the polygon meshes (scalp, head), likewise.
    meshes: Vec<(String, Vec<String>)>,
    /// The archive's timeline: the times (seconds, ascending) of every sample of anything that
    /// moves the curves or meshes (positions and the transforms above them); empty when static.
    times: Vec<f64>,
    /// Frames per second of the file's timeline (see [`frame_rate`]).
    fps: f64,
    /// The file follows Epic's groom spec (it declares `groom_version_major`): centimetres.
    pub epic_groom: bool,
    /// Warnings for the parameters no groom attribute holds (see [`Self::left_out`]).
    left_out: Vec<String>,
}

/// The points and widths of every curves object read so far, one object after another.
struct Placed {
    points: Vec<Vec3>,
    widths: Vec<f32>,
}

/// One curves object's strands as its parameters count them: vertex offsets from 0, and basis.
struct Strands<'s> {
    offsets: &'s [u32],
    basis: CurveBasis,
}

impl Strands<'_> {
    fn strand_count(&self) -> usize {
        self.offsets.len() - 1
    }

    fn vertex_count(&self) -> usize {
        *self.offsets.last().expect("starts with 0") as usize
    }

    fn vertex_counts(&self) -> impl Iterator<Item = usize> + '_ {
        self.offsets.windows(2).map(|w| (w[1] - w[0]) as usize)
    }
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
        // An object whose positions hold no sample has no curves (Blender's importer makes it a
        // hair object of none): it is skipped, as the USD reader skips a prim without points.
        let (empty, found): (Vec<_>, Vec<_>) = found.into_iter().partition(|(path, _)| {
            let positions =
                find(&archive.top, path).and_then(|o| o.properties.compound(".geom")?.sampled("P"));
            positions.is_some_and(Sampled::holds_no_sample)
        });
        if let (Some((path, _)), true) = (empty.first(), found.is_empty()) {
            return fail(format!(
                "{path}/.geom/P: the property holds no sample: its writer left the object empty"
            ));
        }
        let mut result = CurvesArchive {
            archive,
            curves: found,
            meshes,
            times: Vec::new(),
            fps: 0.0,
            epic_groom,
            left_out: Vec::new(),
        };
        result.left_out = result.parameters_left_out()?;
        let animated = result.animated_properties()?;
        let declared: u64 = animated.iter().map(|p| p.num_samples as u64).sum();
        if declared > result.archive.ogawa.len() + MAX_TIMELINE_SAMPLES {
            return fail(format!(
                "the animated properties declare {declared} samples, more than the file can hold"
            ));
        }
        let mut times = Vec::new();
        for property in &animated {
            let sampling = &result.archive.time_samplings[property.time_sampling as usize];
            times.extend((0..property.num_samples as u64).map(|i| sampling.sample_time(i)));
        }
        times.sort_by(f64::total_cmp);
        result.fps = frame_rate(&result.archive, &animated);
        // Times one millionth of a frame apart are one sample written through different samplings.
        let tolerance = SAME_TIME_IN_FRAMES / result.fps;
        times.dedup_by(|b, a| *b - *a <= tolerance);
        result.times = times;
        Ok(result)
    }

    /// Every property with more than one sample that places the curves or meshes: their
    /// positions and the transforms above them; and every `visible` on them or above them whose
    /// value changes (Blender's keyframed hide; a writer may sample a still one every frame).
    /// A single sample holds at every time.
    fn animated_properties(&self) -> OgawaResult<Vec<&Sampled<'a>>> {
        let mut animated = Vec::new();
        for (path, xform_paths) in self.curves.iter().chain(&self.meshes) {
            let object = self.resolve_path(path, xform_paths)?;
            let positions = object.geom.sampled("P").into_iter();
            let transforms = object.xforms.iter().filter_map(|x| x.sampled(".vals"));
            animated.extend(positions.chain(transforms).filter(|p| p.num_samples > 1));
            let visible = self.visibilities(path).into_iter().map(|(_, v)| v);
            animated.extend(visible.filter(|v| v.num_samples > 1 && v.last_changed > 0));
        }
        Ok(animated)
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

    /// Warnings, one per parameter of a curves or mesh object that reading leaves out because
    /// its elements hold more values than a groom attribute (the same at every frame: the count
    /// is the property's extent), each naming the object and property.
    pub fn left_out(&self) -> &[String] {
        &self.left_out
    }

    /// See [`Self::left_out`]: the parameters [`held_extent`] turns away for their extent.
    fn parameters_left_out(&self) -> OgawaResult<Vec<String>> {
        let mut warnings = Vec::new();
        for (path, xform_paths) in self.curves.iter().chain(&self.meshes) {
            let object = self.resolve_path(path, xform_paths)?;
            let own = ["N", ".velocities", "uv"].into_iter().filter_map(|name| object.geom.get(name));
            let arb = object.geom.compound(".arbGeomParams");
            let members = arb.map(|c| c.members.iter()).into_iter().flatten();
            for (property, compound) in own.map(|p| (p, "")).chain(members.map(|p| (p, ".arbGeomParams/"))) {
                let extent = param_extent(property).unwrap_or(0) as usize;
                if extent > Attribute::MAX_COMPONENTS {
                    let what = format!("{path}/.geom/{compound}{}", property.name());
                    warnings.push(Attribute::left_out(&what, extent));
                }
            }
        }
        Ok(warnings)
    }

    /// Number of distinct sample times on the archive's timeline (1 for a static file).
    pub fn frame_count(&self) -> u32 {
        self.times.len().max(1) as u32
    }

    /// Time in seconds of the `index`-th sample time of the timeline (0 = first).
    pub fn frame_time(&self, index: u32) -> f64 {
        self.times.get(index as usize).copied().unwrap_or(0.0)
    }

    /// Frames per second of the file's timeline: frame number `n` is at `n / fps` seconds.
    pub fn frames_per_second(&self) -> f64 {
        self.fps
    }

    /// The first and last whole frames the samples span (equal for a static file). Motion-blur
    /// sub-samples (Blender's shutter of ±0.25 frame puts them at 0.75, 1.25, …, 5.25) span
    /// frames 1 to 5, not 0.75 to 4.75; samples that span no whole frame give their own range.
    pub fn frame_range(&self) -> (f64, f64) {
        let first = self.frame_time(0) * self.fps;
        let last = self.frame_time(self.frame_count() - 1) * self.fps;
        let (whole_first, whole_last) =
            ((first - SAME_TIME_IN_FRAMES).ceil(), (last + SAME_TIME_IN_FRAMES).floor());
        if whole_first <= whole_last {
            // `+ 0.0` turns the -0 that rounding up a hair below zero gives into frame 0.
            (whole_first + 0.0, whole_last + 0.0)
        } else {
            (first, last)
        }
    }

    /// Every curves object merged into one groom, at frame number `frame` of the file's
    /// timeline (time `frame / fps`; see [`Self::read_at_time`]).
    pub fn read_at_frame(&self, frame: f64) -> OgawaResult<Groom> {
        let time = frame / self.fps;
        if let Some(&first) = self.times.first() {
            if time < first - SAME_TIME_IN_FRAMES / self.fps {
                return fail(format!(
                    "frame {frame} is before the file's first sample (frame {}; {} frames per second)",
                    (first * self.fps * 1e6).round() / 1e6,
                    self.fps
                ));
            }
        }
        self.read_at_time(time)
    }

    /// The `index`-th sample time of the timeline (0 = first).
    pub fn read_frame(&self, index: u32) -> OgawaResult<Groom> {
        if index >= self.frame_count() {
            return fail(format!("sample {index} does not exist; the file has {}", self.frame_count()));
        }
        self.read_at_time(self.frame_time(index))
    }

    /// Every curves object merged into one groom at `time` seconds: positions and transforms
    /// interpolated linearly between the samples around it, everything else from the latest
    /// sample at or before it; before a property's first sample its first holds, after its
    /// last its last.
    pub fn read_at_time(&self, time: f64) -> OgawaResult<Groom> {
        let mut parts = Vec::with_capacity(self.curves.len());
        let mut paths = Vec::with_capacity(self.curves.len());
        let objects: Vec<CurvesObject<'_, 'a>> =
            (0..self.curves.len()).map(|index| self.resolve(index)).collect::<OgawaResult<_>>()?;
        // Every object's points and widths go straight into the whole groom's arrays, sized
        // once from the sizes of the samples (a hint: a wrong one only costs a reallocation).
        let vertices: usize = objects.iter().map(|o| self.vertex_count_hint(o, time)).sum();
        let mut placed =
            Placed { points: Vec::with_capacity(vertices), widths: Vec::with_capacity(vertices) };
        crate::io::input::advise_huge_pages(placed.points.spare_capacity_mut());
        crate::io::input::advise_huge_pages(placed.widths.spare_capacity_mut());
        let mut ids_given = Vec::with_capacity(objects.len());
        for object in &objects {
            let (groom, given) = self.read_object(object, time, &mut placed)?;
            ids_given.push(given);
            parts.push(groom);
            paths.push(object.path.clone());
        }
        let ids: Vec<(usize, Option<&[u32]>)> = parts
            .iter()
            .zip(&ids_given)
            .map(|(part, &given)| (part.strand_count(), given.then_some(part.strand_ids.as_slice())))
            .collect();
        let ids = crate::groom::merged_strand_ids(&ids);
        let mut groom = Groom::concat_placed(parts, placed.points, placed.widths).map_err(|(index, e)| {
            OgawaError(format!("{}: does not fit the curves objects before it: {e}", paths[index]))
        })?;
        groom.strand_ids = ids;
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
        let mut points = Vec::new();
        self.points_at(required(object, "P")?, time, &mut points)?;
        let indices = |name: &str| -> OgawaResult<Vec<u32>> {
            let property = required(object, name)?;
            property.expect(&[Pod::I32, Pod::U32], 1)?;
            property
                .read_u32(ogawa, self.index_at(property, time))
                .map_err(|e| OgawaError(format!("{path}: {}", e.0)))
        };
        let face_counts = indices(".faceCounts")?;
        let face_indices = indices(".faceIndices")?;
        if face_counts.is_empty() {
            return Ok(None);
        }
        let matrix = self.world_matrix(object, time)?;
        let mut mesh = SurfaceMesh {
            path: path.clone(),
            points,
            face_counts,
            face_indices,
            primvars: Vec::new(),
            invisible: false,
            holes: Vec::new(),
        };
        mesh.invisible = self.hidden(path, time)?;
        let arb = object.geom.compound(".arbGeomParams");
        let arb_members = arb.map(|c| c.members.as_slice()).unwrap_or(&[]);
        // The UV set keeps the name its `sourceName` gives (Blender writes its map's, `UVMap`).
        let uv = object.geom.get("uv").map(|p| {
            let named = uv_source_name(p)
                .filter(|n| *n != MeshPrimvar::NORMALS && arb_members.iter().all(|m| m.name() != *n));
            (p, named.unwrap_or(MeshPrimvar::UV).to_string(), Some(AttributeKind::TexCoord))
        });
        let normals =
            object.geom.get("N").map(|p| (p, MeshPrimvar::NORMALS.to_string(), Some(AttributeKind::Normal)));
        let params =
            normals.into_iter().chain(uv).chain(arb_members.iter().map(|m| (m, m.name().to_string(), None)));
        for (property, name, kind) in params {
            if let Some(primvar) = self.mesh_primvar(property, name, kind, &mesh, time)? {
                mesh.primvars.push(primvar);
            }
        }
        mesh.check().map_err(|problem| OgawaError(format!("{path}: {problem}")))?;
        mesh.transform(matrix);
        // Clockwise in the file; a mirroring transform turns the winding once more.
        if matrix.determinant() >= 0.0 {
            mesh.flip_winding();
        }
        Ok(Some(mesh))
    }

    /// A PolyMesh geometry parameter (plain array or `.vals`/`.indices` compound) at `time`, kept
    /// indexed, its interpolation from `geoScope` or else from its count on `mesh`, its kind
    /// `kind` or else from its POD and interpretation; `None` for data no mesh primvar holds
    /// (strings, more than 4 components).
    fn mesh_primvar(
        &self,
        property: &Property<'a>,
        name: String,
        kind: Option<AttributeKind>,
        mesh: &SurfaceMesh,
        time: f64,
    ) -> OgawaResult<Option<MeshPrimvar>> {
        let ogawa = &self.archive.ogawa;
        let Some(extent) = held_extent(property) else { return Ok(None) };
        let (vals, indices, scope) = match property {
            Property::Sampled(s) => (s, None, s.metadata.get("geoScope")),
            Property::Compound(c) => {
                let Some(vals) = c.sampled(".vals") else { return Ok(None) };
                let scope = c.metadata.get("geoScope").or_else(|| vals.metadata.get("geoScope"));
                (vals, c.sampled(".indices"), scope)
            }
        };
        let fail_here =
            |message: String| OgawaError(format!("{}: geometry parameter '{name}': {message}", mesh.path));
        vals.expect(NUMERIC, extent)?;
        let kind = kind.unwrap_or_else(|| param_kind(property, extent));
        let index = self.index_at(vals, time);
        let values = if kind.is_integer() {
            AttributeData::Int(vals.read_i64(ogawa, index)?)
        } else {
            AttributeData::Float(vals.read_f32(ogawa, index)?)
        };
        let indices = match indices {
            None => None,
            Some(indices) => {
                Some(indices.read_u32(ogawa, self.index_at(indices, time)).map_err(|e| fail_here(e.0))?)
            }
        };
        let count = indices.as_ref().map_or(values.len() / extent as usize, Vec::len);
        let interpolation = match scope {
            Some(scope) => MeshInterpolation::from_alembic_scope(scope)
                .ok_or_else(|| fail_here(format!("unknown geoScope \"{scope}\"")))?,
            // No scope: the first interpolation the count fits (`check` names a count that fits none).
            None => [
                MeshInterpolation::Vertex,
                MeshInterpolation::FaceVarying,
                MeshInterpolation::Uniform,
                MeshInterpolation::Constant,
            ]
            .into_iter()
            .find(|i| i.count(mesh) == count)
            .unwrap_or(MeshInterpolation::Vertex),
        };
        Ok(Some(MeshPrimvar { name, kind, components: extent as usize, interpolation, values, indices }))
    }

    /// Every frame, in order; refuses files that would expand far beyond their size.
    pub fn read_all_frames(&self) -> OgawaResult<Vec<Groom>> {
        let first = self.read_frame(0)?;
        let frames = self.frame_count();
        let total = first.vertex_count() as u64 * frames as u64;
        let limit = self.archive.ogawa.len() * MAX_VERTICES_PER_FILE_BYTE + (1 << 20);
        if total > limit {
            return fail(format!(
                "{frames} frames of {} vertices would expand the {}-byte file to {total} vertices; read one frame instead",
                first.vertex_count(),
                self.archive.ogawa.len()
            ));
        }
        // Frames are independent: read them on every core (the order of the result is fixed).
        let rest: Vec<Groom> =
            (1..frames).into_par_iter().map(|f| self.read_frame(f)).collect::<OgawaResult<_>>()?;
        let mut all = Vec::with_capacity(frames as usize);
        all.push(first);
        all.extend(rest);
        Ok(all)
    }

    /// The latest sample of `property` at or before `time` (else its first).
    fn index_at(&self, property: &Sampled<'a>, time: f64) -> u32 {
        self.samples_around(property, time).0
    }

    /// The samples of `property` around `time` and the weight of the later one: `(i, i, 0)` on
    /// a sample, before the first or after the last.
    fn samples_around(&self, property: &Sampled<'a>, time: f64) -> (u32, u32, f64) {
        let sampling = &self.archive.time_samplings[property.time_sampling as usize];
        let count = property.num_samples.max(1) as u64;
        let tolerance = SAME_TIME_IN_FRAMES / self.fps;
        // The first sample after `time` (times increase with the index).
        let (mut lo, mut hi) = (0u64, count);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            if sampling.sample_time(mid) <= time + tolerance {
                lo = mid + 1;
            } else {
                hi = mid;
            }
        }
        if lo == 0 || lo == count {
            let held = lo.saturating_sub(1) as u32;
            return (held, held, 0.0);
        }
        let (t0, t1) = (sampling.sample_time(lo - 1), sampling.sample_time(lo));
        let weight = if time - t0 <= tolerance || t1 <= t0 { 0.0 } else { (time - t0) / (t1 - t0) };
        ((lo - 1) as u32, lo as u32, weight)
    }

    /// A float property at `time`, interpolated linearly between the samples around it when
    /// they have the same length (else the earlier one).
    fn read_f64_at(&self, property: &Sampled<'a>, time: f64) -> OgawaResult<Vec<f64>> {
        let ogawa = &self.archive.ogawa;
        let (i0, i1, weight) = self.samples_around(property, time);
        let mut values = property.read_f64(ogawa, i0)?;
        if weight > 0.0 {
            let later = property.read_f64(ogawa, i1)?;
            if later.len() == values.len() {
                values.iter_mut().zip(&later).for_each(|(a, b)| *a += (b - *a) * weight);
            }
        }
        Ok(values)
    }

    /// Positions (`P`, float or double) at `time`, interpolated as [`Self::read_f64_at`],
    /// appended to `out`.
    fn points_at(&self, positions: &Sampled<'a>, time: f64, out: &mut Vec<Vec3>) -> OgawaResult<()> {
        positions.expect(&[Pod::F32, Pod::F64], 3)?;
        let (i0, _, weight) = self.samples_around(positions, time);
        if positions.pod == Pod::F32 && weight == 0.0 {
            return positions.append_f32_as(&self.archive.ogawa, i0, out);
        }
        let flat = self.read_f64_at(positions, time)?;
        out.extend(flat.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2]).as_vec3()));
        Ok(())
    }

    /// How many points a curves object has at `time`, from the size of its `P` sample (0 when
    /// that cannot be told; reading says what is wrong).
    fn vertex_count_hint(&self, object: &CurvesObject<'_, 'a>, time: f64) -> usize {
        let Some(positions) = object.geom.sampled("P") else { return 0 };
        let bytes = positions.sample_bytes(&self.archive.ogawa, self.index_at(positions, time));
        bytes.map_or(0, |b| b.len() / (positions.pod.size() * 3).max(1))
    }

    /// One curves object at `time`: its points and widths appended to `placed`, the rest as a
    /// one-group groom whose own points and widths are empty (for [`Groom::concat_placed`]), and
    /// whether the file gave its strand ids (`groom_id`).
    fn read_object(
        &self,
        object: &CurvesObject<'_, 'a>,
        time: f64,
        placed: &mut Placed,
    ) -> OgawaResult<(Groom, bool)> {
        let ogawa = &self.archive.ogawa;
        let path = &object.path;
        let bounds = required(object, ".selfBnds")?;
        bounds.expect(&[Pod::F64, Pod::F32], 6)?;
        let basis_property = required(object, "curveBasisAndType")?;
        basis_property.expect(&[Pod::U8], 4)?;
        let basis_bytes = basis_property.sample_bytes(ogawa, self.index_at(basis_property, time))?;
        // Without `.orders`, Maya and Blender read variable-order curves as order 2.
        let orders = || -> OgawaResult<Vec<f64>> {
            match object.geom.sampled(".orders") {
                Some(orders) => orders.read_f64(ogawa, self.index_at(orders, time)),
                None => Ok(Vec::new()),
            }
        };
        let basis = curve_basis(basis_bytes, path, orders)?;

        let first = placed.points.len();
        self.points_at(required(object, "P")?, time, &mut placed.points)?;
        let point_count = placed.points.len() - first;
        let counts_property = required(object, "nVertices")?;
        counts_property.expect(&[Pod::I32, Pod::U32, Pod::I16, Pod::U16], 1)?;
        let counts = counts_property
            .read_u32(ogawa, self.index_at(counts_property, time))
            .map_err(|e| OgawaError(format!("{path}: {}", e.0)))?;
        let mut offsets = Vec::with_capacity(counts.len() + 1);
        offsets.push(0u32);
        let mut total = 0u64;
        for &count in &counts {
            total += count as u64;
            if total > point_count as u64 {
                return fail(format!("{path}: nVertices add up to more than the {point_count} points of P"));
            }
            offsets.push(total as u32);
        }
        if total != point_count as u64 {
            return fail(format!("{path}: nVertices add up to {total}, P has {point_count} points"));
        }
        let strands = Strands { offsets: &offsets, basis };
        let matrix = self.world_matrix(object, time)?;
        if matrix != DMat4::IDENTITY {
            let points = &mut placed.points[first..];
            points.iter_mut().for_each(|p| *p = matrix.transform_point3(p.as_dvec3()).as_vec3());
        }

        let arb = object.geom.compound(".arbGeomParams");
        let epic_width = arb.and_then(|c| c.get(epic::WIDTH));
        let mut width_interpolation = None;
        match epic_width.or_else(|| object.geom.get("width")) {
            Some(p) => {
                let (rate, interpolation) =
                    self.expand_into(p, time, &strands, 1, path, &mut placed.widths)?;
                width_interpolation = interpolation;
                if rate != Rate::Vertex {
                    let start =
                        placed.widths.len() - if rate == Rate::Constant { 1 } else { strands.strand_count() };
                    let values = placed.widths.split_off(start);
                    let param = Param { values, extent: 1, rate };
                    placed.widths.extend(param.into_vertices(&strands));
                }
                // Widths are lengths in the object's space, as its points are.
                if matrix != DMat4::IDENTITY {
                    let scale = crate::io::width_scale(matrix);
                    placed.widths[first..].iter_mut().for_each(|w| *w *= scale);
                }
            }
            None => placed.widths.extend(std::iter::repeat_n(
                DEFAULT_WIDTH * if self.epic_groom { epic::UNITS_PER_METRE } else { 1.0 },
                point_count,
            )),
        }
        let mut groom = Groom { basis, ..Default::default() };
        groom.strand_ids = (0..counts.len() as u32).collect();
        let mut ids_given = false;

        let uv = arb.and_then(|c| c.get(epic::ROOT_UV)).or_else(|| object.geom.get("uv"));
        if let Some(p) = uv {
            let param = self.expand(p, time, &strands, 2, path)?;
            groom.root_uvs =
                Some(param.to_strand_roots(&strands).chunks_exact(2).map(|c| [c[0], c[1]]).collect());
        }
        // The curves' own normals and velocities (Houdini's `N` and `v`), then the parameters.
        let own = [("N", point_attributes::NORMALS), (".velocities", point_attributes::VELOCITIES)]
            .into_iter()
            .filter_map(|(property, name)| object.geom.get(property).map(|p| (p, name)));
        let members = arb.map(|c| c.members.as_slice()).unwrap_or(&[]);
        for (member, name) in own.chain(members.iter().map(|m| (m, m.name()))) {
            if name == epic::WIDTH || name == epic::ROOT_UV {
                continue;
            }
            let Some(extent) = held_extent(member) else { continue };
            if name == epic::ID {
                ids_given = true;
                if let Some(ids) = self.strand_ids(member, time, &strands) {
                    groom.strand_ids = ids;
                    continue;
                }
            }
            let kind = param_kind(member, extent);
            if kind.is_integer() && !matches!(name, epic::ID | epic::GUIDE) {
                // Integers stay integers (the file's ids): past 2^24 `f32` rounds them.
                let param = self.expand::<i64>(member, time, &strands, extent, path)?;
                let canonical = crate::io::unreal::attribute_for_epic_name(name);
                let (rate, data) = param.into_attribute(&strands);
                groom.set_attribute(Attribute::integers(canonical, rate, extent as usize, data, kind));
                continue;
            }
            let param = self.expand::<f32>(member, time, &strands, extent, path)?;
            match name {
                epic::ID => groom.strand_ids = param.to_strands(&strands).iter().map(|&v| v as u32).collect(),
                epic::GUIDE => {
                    groom.guides = Some(param.to_strands(&strands).iter().map(|&v| v != 0.0).collect())
                }
                _ => {
                    let canonical = crate::io::unreal::attribute_for_epic_name(name);
                    let (rate, data) = param.into_attribute(&strands);
                    let mut attribute =
                        Attribute::new(canonical, rate, extent as usize, data).with_kind(kind);
                    crate::io::transform_attributes(std::slice::from_mut(&mut attribute), matrix);
                    groom.set_attribute(attribute);
                }
            }
        }
        groom.strand_offsets = offsets;
        let mut group = CurveGroup::new(path.clone(), basis, wrap_of(basis));
        group.width_interpolation = width_interpolation;
        group.invisible = self.hidden(path, time)?;
        groom.set_single_group(group);
        Ok((groom, ids_given))
    }

    /// The `visible` properties of the object at `path` and of the objects above it, the
    /// topmost first, each with its object's path.
    fn visibilities(&self, path: &str) -> Vec<(String, &Sampled<'a>)> {
        let names: Vec<&str> = path.split('/').filter(|p| !p.is_empty()).collect();
        (1..=names.len())
            .filter_map(|depth| {
                let at = names[..depth].join("/");
                let visible = find(&self.archive.top, &at)?.properties.sampled(VISIBLE)?;
                Some((at, visible))
            })
            .collect()
    }

    /// Whether the object at `path` is hidden at `time` by AbcGeom's `visible` property: its own
    /// value, or while that is deferred (-1) or absent, its nearest ancestor's.
    fn hidden(&self, path: &str, time: f64) -> OgawaResult<bool> {
        for (at, visible) in self.visibilities(path).into_iter().rev() {
            let value = visible
                .read_f64(&self.archive.ogawa, self.index_at(visible, time))
                .map_err(|e| OgawaError(format!("/{at}: {}", e.0)))?;
            match value.first() {
                Some(&v) if v == VISIBILITY_HIDDEN as f64 => return Ok(true),
                Some(&v) if v > 0.0 => return Ok(false),
                _ => {}
            }
        }
        Ok(false)
    }

    /// Epic's `groom_id` as integers, one per strand (no detour through floats: ids past 2^24
    /// stay exact); `None` when it is not a plain per-strand integer array (then it is read as
    /// any parameter).
    fn strand_ids(&self, property: &Property<'a>, time: f64, strands: &Strands<'_>) -> Option<Vec<u32>> {
        let Property::Sampled(ids) = property else { return None };
        let integer = matches!(ids.pod, Pod::I32 | Pod::U32);
        let scope = ids.metadata.get("geoScope");
        if !integer || ids.extent != 1 || !matches!(scope, None | Some("uni")) {
            return None;
        }
        // Negative or out-of-range ids fall back to the float reading too.
        let values = ids.read_u32(&self.archive.ogawa, self.index_at(ids, time)).ok();
        values.filter(|v| v.len() == strands.strand_count())
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

    /// An Xform's local matrix at `time`: between two samples, the two matrices blended as
    /// Blender's importer does (scale and translation linearly, rotation along the shortest arc).
    fn local_matrix(&self, xform: &Compound<'a>, time: f64) -> OgawaResult<DMat4> {
        let ogawa = &self.archive.ogawa;
        let Some(ops) = xform.sampled(".ops") else { return Ok(DMat4::IDENTITY) };
        let ops = ops.sample_bytes(ogawa, 0)?;
        let Some(vals) = xform.sampled(".vals") else { return compose_ops(xform, ops, &[]) };
        let (i0, i1, weight) = self.samples_around(vals, time);
        let earlier = compose_ops(xform, ops, &vals.read_f64(ogawa, i0)?)?;
        if weight == 0.0 {
            return Ok(earlier);
        }
        let later = compose_ops(xform, ops, &vals.read_f64(ogawa, i1)?)?;
        Ok(blend_matrices(earlier, later, weight))
    }

    /// A geometry parameter (plain array or indexed `.vals`/`.indices` compound) at `time`,
    /// expanded through its indices, with its rate from `geoScope` or, failing that, its count.
    fn expand<T: ParamNumber>(
        &self,
        property: &Property<'a>,
        time: f64,
        strands: &Strands<'_>,
        extent: u8,
        path: &str,
    ) -> OgawaResult<Param<T>> {
        let mut values = Vec::new();
        let (rate, _) = self.expand_into(property, time, strands, extent, path, &mut values)?;
        Ok(Param { values, extent: extent as usize, rate })
    }

    /// [`Self::expand`] with the values appended to `out` (per vertex when the rate is
    /// [`Rate::Vertex`], `var` values spread onto the vertices), so a reader can put them where
    /// they belong without a second copy; with the rate the file gave, when not per vertex
    /// (what a writer gives back).
    fn expand_into<T: ParamNumber>(
        &self,
        property: &Property<'a>,
        time: f64,
        strands: &Strands<'_>,
        extent: u8,
        path: &str,
        out: &mut Vec<T>,
    ) -> OgawaResult<(Rate, Option<Interpolation>)> {
        let ogawa = &self.archive.ogawa;
        let start = out.len();
        let (metadata_scope, name) = match property {
            Property::Sampled(s) => {
                s.expect(NUMERIC, extent)?;
                T::append(s, ogawa, self.index_at(s, time), out)?;
                (s.metadata.get("geoScope").map(str::to_string), s.name.clone())
            }
            Property::Compound(c) => {
                let vals = c
                    .sampled(".vals")
                    .ok_or_else(|| OgawaError(format!("{path}: {} has no .vals", c.name)))?;
                vals.expect(NUMERIC, extent)?;
                let mut raw = Vec::new();
                T::append(vals, ogawa, self.index_at(vals, time), &mut raw)?;
                match c.sampled(".indices") {
                    Some(indices) => {
                        let indices = indices
                            .read_u32(ogawa, self.index_at(indices, time))
                            .map_err(|e| OgawaError(format!("{path}: {}: {}", c.name, e.0)))?;
                        let e = extent as usize;
                        out.reserve(indices.len() * e);
                        for &i in &indices {
                            let at = i as usize * e;
                            match raw.get(at..at + e) {
                                Some(v) => out.extend_from_slice(v),
                                None => return fail(format!("{path}: {} index {i} is out of range", c.name)),
                            }
                        }
                    }
                    None => out.extend_from_slice(&raw),
                }
                let scope =
                    c.metadata.get("geoScope").or_else(|| vals.metadata.get("geoScope")).map(str::to_string);
                (scope, format!("{path}/{}", c.name))
            }
        };
        let count = (out.len() - start) / extent as usize;
        let (strand_count, vertices) = (strands.strand_count(), strands.vertex_count());
        // `var` is one value per segment end (RenderMan's rule: Alembic has no pinned curves);
        // Houdini writes point attributes under `var` too, so a per-vertex count is per vertex.
        let varying_count = |n: usize| primvar_rates::varying_count(strands.basis, CurveWrap::Nonperiodic, n);
        let varying: usize = strands.vertex_counts().map(varying_count).sum();
        let (rate, interpolation) = match metadata_scope.as_deref() {
            Some("var") if count == varying => (Rate::Vertex, Some(Interpolation::Varying)),
            Some("var") if count != vertices => {
                return fail(format!(
                    "{name}: {count} values, its scope needs {vertices} (one per vertex) or {varying} \
                     (one per segment end of the {:?} curves)",
                    strands.basis
                ));
            }
            Some("vtx") | Some("var") | Some("fvr") => (Rate::Vertex, None),
            Some("uni") => (Rate::Strand, Some(Interpolation::Uniform)),
            Some("con") => (Rate::Constant, Some(Interpolation::Constant)),
            // No scope (Blender writes none; or "unk"): the rate whose count it has. A Bézier
            // curve's widths from Blender are one per knot, i.e. per segment end.
            _ if count == vertices => (Rate::Vertex, None),
            _ if count == varying => (Rate::Vertex, Some(Interpolation::Varying)),
            _ if count == strand_count => (Rate::Strand, Some(Interpolation::Uniform)),
            _ if count == 1 => (Rate::Constant, Some(Interpolation::Constant)),
            _ => {
                let varying = if varying == vertices {
                    String::new()
                } else {
                    format!(", {varying} (one per segment end of the {:?} curves)", strands.basis)
                };
                let scope = metadata_scope.map_or("no geoScope".into(), |s| format!("geoScope \"{s}\""));
                return fail(format!(
                    "{name}: {count} values and {scope}: coif reads {vertices} (one per vertex){varying}, \
                     {strand_count} (one per curve) or 1 (one for all)"
                ));
            }
        };
        let expected = match (rate, interpolation) {
            (Rate::Vertex, Some(Interpolation::Varying)) => varying,
            (Rate::Vertex, _) => vertices,
            (Rate::Strand, _) => strand_count,
            (Rate::Constant, _) => 1,
        };
        if count != expected {
            return fail(format!("{name}: {count} values, its scope needs {expected}"));
        }
        if interpolation == Some(Interpolation::Varying) && varying != vertices {
            let values = out.split_off(start);
            out.extend(primvar_rates::varying_to_vertex(
                strands.basis,
                CurveWrap::Nonperiodic,
                strands.vertex_counts(),
                &values,
                extent as usize,
            ));
        }
        Ok((rate, interpolation))
    }
}

/// The matrix of an Xform's operations `ops` (one byte each, outermost first) with values `vals`.
fn compose_ops(xform: &Compound<'_>, ops: &[u8], vals: &[f64]) -> OgawaResult<DMat4> {
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

/// `a` and `b` blended by `weight` (0 = `a`): scale and translation linearly, rotation by slerp;
/// matrices that are not scale-rotation-translation (shear, beyond `f32` rounding) are blended
/// entry by entry.
fn blend_matrices(a: DMat4, b: DMat4, weight: f64) -> DMat4 {
    let decompose = |m: DMat4| {
        let (scale, rotation, translation) = m.to_scale_rotation_translation();
        let exact = DMat4::from_scale_rotation_translation(scale, rotation, translation)
            .abs_diff_eq(m, 1e-5 * m.to_cols_array().iter().fold(1.0f64, |acc, v| acc.max(v.abs())));
        exact.then_some((scale, rotation, translation))
    };
    match (decompose(a), decompose(b)) {
        (Some((sa, ra, ta)), Some((sb, rb, tb))) => DMat4::from_scale_rotation_translation(
            sa.lerp(sb, weight),
            ra.slerp(rb, weight),
            ta.lerp(tb, weight),
        ),
        _ => a * (1.0 - weight) + b * weight,
    }
}

/// Frames per second of an archive's timeline: the `FramesPerTimeUnit` Blender writes in the
/// archive's metadata; else one frame per cycle of the first animated property's cyclic
/// sampling (uniform, or several samples per frame for motion blur); else 24.
fn frame_rate(archive: &Archive<'_>, animated: &[&Sampled<'_>]) -> f64 {
    let sensible = |fps: f64| (fps.is_finite() && (1e-3..=1e6).contains(&fps)).then_some(fps);
    let declared = archive.metadata.get("FramesPerTimeUnit").and_then(|v| v.trim().parse().ok());
    declared
        .and_then(sensible)
        .or_else(|| {
            animated.iter().find_map(|p| {
                let sampling = &archive.time_samplings[p.time_sampling as usize];
                (!sampling.is_acyclic()).then(|| 1.0 / sampling.time_per_cycle).and_then(sensible)
            })
        })
        .unwrap_or(DEFAULT_FRAMES_PER_SECOND)
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

/// Numbers a geometry parameter is read as: floats (any numeric POD converted), or integers
/// exactly (integer PODs).
trait ParamNumber: primvar_rates::Spread {
    fn append(
        property: &Sampled<'_>,
        ogawa: &OgawaReader<'_>,
        index: u32,
        out: &mut Vec<Self>,
    ) -> OgawaResult<()>;
}

impl ParamNumber for f32 {
    fn append(
        property: &Sampled<'_>,
        ogawa: &OgawaReader<'_>,
        index: u32,
        out: &mut Vec<f32>,
    ) -> OgawaResult<()> {
        property.append_f32(ogawa, index, out)
    }
}

impl ParamNumber for i64 {
    fn append(
        property: &Sampled<'_>,
        ogawa: &OgawaReader<'_>,
        index: u32,
        out: &mut Vec<i64>,
    ) -> OgawaResult<()> {
        out.extend(property.read_i64(ogawa, index)?);
        Ok(())
    }
}

struct Param<T = f32> {
    /// Per-vertex values when `rate` is `Vertex` (`var` values spread onto the vertices).
    values: Vec<T>,
    extent: usize,
    rate: Rate,
}

impl<T: Copy> Param<T> {
    /// A groom attribute's rate and values: per vertex, else per strand.
    fn into_attribute(self, strands: &Strands<'_>) -> (AttributeRate, Vec<T>) {
        match self.rate {
            Rate::Vertex => (AttributeRate::Vertex, self.values),
            _ => (AttributeRate::Strand, self.to_strands(strands)),
        }
    }

    fn into_vertices(self, strands: &Strands<'_>) -> Vec<T> {
        match self.rate {
            Rate::Vertex => self.values,
            Rate::Constant => self.values.repeat(strands.vertex_count()),
            Rate::Strand => strands
                .vertex_counts()
                .enumerate()
                .flat_map(|(s, n)| self.values[s * self.extent..(s + 1) * self.extent].repeat(n))
                .collect(),
        }
    }

    fn to_strands(&self, strands: &Strands<'_>) -> Vec<T> {
        match self.rate {
            Rate::Strand => self.values.clone(),
            Rate::Constant => self.values.repeat(strands.strand_count()),
            Rate::Vertex => self.to_strand_roots(strands),
        }
    }

    /// Per-strand values, taking a per-vertex parameter at each strand's root.
    fn to_strand_roots(&self, strands: &Strands<'_>) -> Vec<T> {
        match self.rate {
            Rate::Vertex => (0..strands.strand_count())
                .flat_map(|s| {
                    let root = strands.offsets[s] as usize * self.extent;
                    self.values.get(root..root + self.extent).unwrap_or(&[]).to_vec()
                })
                .collect(),
            _ => self.to_strands(strands),
        }
    }
}

/// The name a PolyMesh's `uv` parameter gives its UV set in `sourceName` metadata (what
/// Blender's exporter writes and its importer names the map by), when it is a plain identifier.
fn uv_source_name<'p>(property: &'p Property<'_>) -> Option<&'p str> {
    let name = match property {
        Property::Sampled(s) => s.metadata.get("sourceName"),
        Property::Compound(c) => c
            .metadata
            .get("sourceName")
            .or_else(|| c.sampled(".vals").and_then(|v| v.metadata.get("sourceName"))),
    }?;
    crate::surface_mesh::is_identifier(name).then_some(name)
}

/// What a geometry parameter's values are, from its POD and `interpretation`, so writers give
/// the same type back and transforms move points and directions: integer and bool PODs, float
/// triples interpreted as a point, normal or vector, colours, and float pairs interpreted as
/// vectors (Alembic's texture coordinates).
fn param_kind(property: &Property<'_>, extent: u8) -> AttributeKind {
    let (pod, interpretation) = match property {
        Property::Sampled(s) => (s.pod, s.metadata.get("interpretation").map(str::to_string)),
        Property::Compound(c) => match c.sampled(".vals") {
            Some(v) => (
                v.pod,
                c.metadata.get("interpretation").or(v.metadata.get("interpretation")).map(str::to_string),
            ),
            None => return AttributeKind::Float,
        },
    };
    let kind = match (pod, interpretation.as_deref(), extent) {
        (Pod::Bool, _, 1) => AttributeKind::Bool,
        (Pod::I8 | Pod::U8 | Pod::I16 | Pod::U16 | Pod::I32, _, _) => AttributeKind::Int,
        (Pod::U32, _, _) => AttributeKind::UInt,
        (Pod::I64, _, _) => AttributeKind::Int64,
        (Pod::U64, _, _) => AttributeKind::UInt64,
        (Pod::F16 | Pod::F32 | Pod::F64, Some("point"), 3) => AttributeKind::Point,
        (Pod::F16 | Pod::F32 | Pod::F64, Some("normal"), 3) => AttributeKind::Normal,
        (Pod::F16 | Pod::F32 | Pod::F64, Some("vector"), 3) => AttributeKind::Vector,
        (Pod::F16 | Pod::F32 | Pod::F64, Some("vector"), 2) => AttributeKind::TexCoord,
        (Pod::F16 | Pod::F32 | Pod::F64, Some("rgb" | "rgba"), 3 | 4) => AttributeKind::Color,
        _ => AttributeKind::Float,
    };
    // What coif's writer gives a plain float attribute of this name reads back as plain floats.
    let (name, plain) = (property.name(), AttributeKind::Float);
    let name = crate::io::unreal::attribute_for_epic_name(name);
    let written_plain = super::curves_write::pod(plain, &name) == pod
        && super::curves_write::interpretation(plain, &name, extent as usize)
            == interpretation.as_deref().unwrap_or("");
    if written_plain {
        AttributeKind::Float
    } else {
        kind
    }
}

/// The values per element of a numeric parameter.
fn param_extent(property: &Property<'_>) -> Option<u8> {
    match property {
        Property::Sampled(s) if s.pod.size() > 0 => Some(s.extent),
        Property::Compound(c) => c.sampled(".vals").filter(|v| v.pod.size() > 0).map(|v| v.extent),
        _ => None,
    }
}

/// The values per element of a parameter a groom attribute can hold; `None` for strings and for
/// more values than [`Attribute::MAX_COMPONENTS`] (which [`CurvesArchive::left_out`] names).
fn held_extent(property: &Property<'_>) -> Option<u8> {
    param_extent(property).filter(|&extent| (1..=Attribute::MAX_COMPONENTS).contains(&(extent as usize)))
}

fn required<'o, 'a>(object: &CurvesObject<'o, 'a>, name: &str) -> OgawaResult<&'o Sampled<'a>> {
    object
        .geom
        .sampled(name)
        .ok_or_else(|| OgawaError(format!("{}: curves without the required '{name}' property", object.path)))
}

/// The wrap of open curves of `basis`, which Alembic does not record: Catmull-Rom passes
/// through its end points (`pinned`), as Blender evaluates it and as its USD exporter writes the
/// same curves; the other bases are read as their files' open curves (`nonperiodic`).
pub fn wrap_of(basis: CurveBasis) -> CurveWrap {
    match basis {
        CurveBasis::CatmullRom => CurveWrap::Pinned,
        _ => CurveWrap::Nonperiodic,
    }
}

/// The curve kind from `curveBasisAndType`. The basis byte decides, as in Blender and Houdini
/// (Blender's own hair says "linear" with a Catmull-Rom basis), except that a B-spline is a NURBS
/// curve whose order the type byte gives: Maya's AbcExport writes every nurbsCurve with the
/// B-spline basis and its degree in the type (variable order: `.orders`), and Maya and Blender
/// both read order 2 as a polyline.
fn curve_basis(
    bytes: &[u8],
    path: &str,
    orders: impl FnOnce() -> OgawaResult<Vec<f64>>,
) -> OgawaResult<CurveBasis> {
    let [curve_type, wrap, basis, _] =
        bytes.try_into().map_err(|_| OgawaError(format!("{path}: curveBasisAndType is empty")))?;
    if wrap != 0 {
        return fail(format!("{path}: periodic (closed) curves are not hair"));
    }
    Ok(match (basis, curve_type) {
        (0, _) => CurveBasis::Linear,
        (1, _) => CurveBasis::Bezier,
        (2, LINEAR_TYPE) => CurveBasis::Linear,
        (2, VARIABLE_ORDER_TYPE) => {
            let bases = orders()?
                .into_iter()
                .map(|order| {
                    CurveBasis::of_nurbs_order(order).map_err(|m| format!("{path}: NURBS curves {m}"))
                })
                .collect::<Result<Vec<_>, _>>()
                .map_err(OgawaError)?;
            // No orders: Maya and Blender read variable-order curves as order 2.
            let first = bases.first().copied().unwrap_or(CurveBasis::Linear);
            if bases.iter().any(|&basis| basis != first) {
                return fail(format!(
                    "{path}: NURBS curves of degree 1 and 3 mixed: coif needs one degree per object"
                ));
            }
            first
        }
        (2, _) => CurveBasis::BSpline,
        (3, _) => CurveBasis::CatmullRom,
        (other, _) => {
            return fail(format!("{path}: curve basis {other} (hermite or power) is not supported"))
        }
    })
}

/// `curveBasisAndType`'s type byte: 0 cubic, 1 linear, 2 variable order.
const LINEAR_TYPE: u8 = 1;
const VARIABLE_ORDER_TYPE: u8 = 2;

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
