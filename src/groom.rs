//! The one in-memory groom model every reader produces, every writer consumes and the simulator
//! reads and writes. Struct-of-arrays: all strands' points in one array, cut into strands by
//! `strand_offsets`. Units are metres, Y is up.
use std::borrow::Cow;
use std::ops::Range;

use glam::Vec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::surface_mesh::SurfaceMesh;

pub use crate::groups::{CurveGroup, CurveWrap};

/// Canonical names of the attributes coif itself reads or writes. Format modules map them to
/// their own conventions (`displayColor` in USD, `groom_color` in Alembic…).
pub mod attr {
    /// Hair colour, linear RGB, per vertex or per strand.
    pub const COLOR: &str = "color";
    /// Cem Yuksel `.hair` per-vertex transparency.
    pub const TRANSPARENCY: &str = "transparency";
}

/// How the control points of a strand are interpolated.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CurveBasis {
    #[default]
    Linear,
    Bezier,
    BSpline,
    CatmullRom,
}

impl CurveBasis {
    /// The basis that draws NURBS curves of `order` (degree + 1) as Maya's and Blender's readers
    /// draw them: order 2 a polyline, order 4 a cubic B-spline. Other orders are refused with
    /// what to do: the whole file, not just the object, because a groom written back without
    /// some of its hair, or with its curves reshaped, would pass unnoticed down a pipeline.
    pub fn of_nurbs_order(order: f64) -> std::result::Result<CurveBasis, String> {
        match order {
            2.0 => Ok(CurveBasis::Linear),
            4.0 => Ok(CurveBasis::BSpline),
            _ => Err(format!(
                "of order {order} (degree {}): coif reads degree 1 and 3 (orders 2 and 4); give these \
                 curves order 4 or export them as Catmull-Rom or poly curves (Blender: the curves' \
                 type or NURBS order; Maya: rebuild them as degree 3)",
                order - 1.0
            )),
        }
    }
}

/// Whether an attribute holds one value per vertex or one per strand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AttributeRate {
    Vertex,
    Strand,
}

/// What an attribute's numbers are, when a file said more than "floats" (a USD value type or
/// role), so writers give the same type back and conversions move directions with the points.
/// The integer kinds are held as integers ([`AttributeData::Int`]), the others as floats.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AttributeKind {
    /// Plain numbers (the writer picks the type it always has for the name).
    #[default]
    Float,
    /// 32-bit signed integers (USD `int`, `int2`…`int4`, `uchar`).
    Int,
    /// 32-bit unsigned integers (USD `uint`).
    UInt,
    /// 64-bit signed integers (USD `int64`).
    Int64,
    /// 64-bit unsigned integers (USD `uint64`), held as their bits in an `i64`.
    UInt64,
    Bool,
    /// Positions: transformed like the points.
    Point,
    /// Unit directions: rotated with the points and kept unit length.
    Normal,
    /// Directions or velocities: rotated and scaled with the points.
    Vector,
    Color,
    TexCoord,
}

impl AttributeKind {
    /// Whether the kind's values are integers, held exactly.
    pub fn is_integer(self) -> bool {
        matches!(
            self,
            AttributeKind::Int | AttributeKind::UInt | AttributeKind::Int64 | AttributeKind::UInt64
        )
    }

    /// An integer kind's value of `stored` (a `UInt64`'s bits read unsigned).
    pub fn integer(self, stored: i64) -> i128 {
        match self {
            AttributeKind::UInt64 => i128::from(stored as u64),
            _ => i128::from(stored),
        }
    }

    /// Whether an integer kind holds `value`.
    pub fn holds(self, value: i128) -> bool {
        match self {
            AttributeKind::Int => i32::try_from(value).is_ok(),
            AttributeKind::UInt => u32::try_from(value).is_ok(),
            AttributeKind::Int64 => i64::try_from(value).is_ok(),
            AttributeKind::UInt64 => u64::try_from(value).is_ok(),
            _ => false,
        }
    }

    /// The narrowest integer kind of `kinds` (integer kinds) that holds every one of `values`;
    /// `None` when none does (a `uint64` past 2^63 beside a negative value).
    pub fn widest_integer(
        kinds: &[AttributeKind],
        values: impl Iterator<Item = i128>,
    ) -> Option<AttributeKind> {
        let (mut low, mut high) = (0i128, 0i128);
        for v in values {
            (low, high) = (low.min(v), high.max(v));
        }
        // The kinds given first (the file's), then the wider ones.
        let candidates = kinds.iter().copied().chain([AttributeKind::Int64, AttributeKind::UInt64]);
        let fits = |k: AttributeKind| k.holds(low) && k.holds(high);
        let width = |k: AttributeKind| match k {
            AttributeKind::Int | AttributeKind::UInt => 32,
            _ => 64,
        };
        candidates.filter(|&k| k.is_integer() && fits(k)).min_by_key(|&k| width(k))
    }
}

/// An attribute's values: floats, or, for an integer [`AttributeKind`], integers held exactly
/// (ids past 2^24 do not survive `f32`).
#[derive(Clone, Debug, PartialEq)]
pub enum AttributeData {
    Float(Vec<f32>),
    Int(Vec<i64>),
}

impl AttributeData {
    pub fn len(&self) -> usize {
        match self {
            AttributeData::Float(v) => v.len(),
            AttributeData::Int(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The values as numbers for what computes with them: floats as they are, integers (of
    /// integer kind `kind`) converted.
    pub fn floats(&self, kind: AttributeKind) -> Cow<'_, [f32]> {
        self.values().floats(kind)
    }

    /// The values borrowed (see [`Values`]).
    pub fn values(&self) -> Values<'_> {
        match self {
            AttributeData::Float(v) => Values::Float(Cow::Borrowed(v)),
            AttributeData::Int(v) => Values::Int(Cow::Borrowed(v)),
        }
    }

    /// An empty array of the same number type.
    pub fn empty_like(&self, capacity: usize) -> AttributeData {
        match self {
            AttributeData::Float(_) => AttributeData::Float(Vec::with_capacity(capacity)),
            AttributeData::Int(_) => AttributeData::Int(Vec::with_capacity(capacity)),
        }
    }

    /// Appends `from[range]` `times` times; `from` holds the same number type.
    pub fn extend_from(&mut self, from: &AttributeData, range: Range<usize>, times: usize) {
        match (self, from) {
            (AttributeData::Float(to), AttributeData::Float(from)) => {
                (0..times).for_each(|_| to.extend_from_slice(&from[range.clone()]))
            }
            (AttributeData::Int(to), AttributeData::Int(from)) => {
                (0..times).for_each(|_| to.extend_from_slice(&from[range.clone()]))
            }
            _ => unreachable!("attribute data of one number type extended by another"),
        }
    }

    /// Appends `count` zeros.
    pub fn extend_zeros(&mut self, count: usize) {
        match self {
            AttributeData::Float(v) => v.resize(v.len() + count, 0.0),
            AttributeData::Int(v) => v.resize(v.len() + count, 0),
        }
    }
}

impl From<Vec<f32>> for AttributeData {
    fn from(values: Vec<f32>) -> Self {
        AttributeData::Float(values)
    }
}

/// [`AttributeData`] borrowed, or gathered for some strands.
#[derive(Clone, Debug, PartialEq)]
pub enum Values<'a> {
    Float(Cow<'a, [f32]>),
    Int(Cow<'a, [i64]>),
}

impl<'a> Values<'a> {
    /// See [`AttributeData::floats`].
    pub fn floats(self, kind: AttributeKind) -> Cow<'a, [f32]> {
        match self {
            Values::Float(v) => v,
            Values::Int(v) => Cow::Owned(v.iter().map(|&x| kind.integer(x) as f32).collect()),
        }
    }

    pub fn len(&self) -> usize {
        match self {
            Values::Float(v) => v.len(),
            Values::Int(v) => v.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A named attribute with 1–4 components per element (bond rates, wetness, rest positions,
/// ids…): floats, or integers for an integer kind.
#[derive(Clone, Debug, PartialEq)]
pub struct Attribute {
    pub name: String,
    pub rate: AttributeRate,
    pub components: usize,
    pub data: AttributeData,
    pub kind: AttributeKind,
}

impl Attribute {
    /// Values per element an attribute holds at most (a colour with alpha, a quaternion).
    pub const MAX_COMPONENTS: usize = 4;

    /// The warning for a file's attribute that readers leave out because its elements hold
    /// `components` values, more than [`Self::MAX_COMPONENTS`]; `what` names it in the file.
    pub fn left_out(what: &str, components: usize) -> String {
        format!(
            "{what} is left out: {components} values per element, more than the {} a groom attribute holds",
            Self::MAX_COMPONENTS
        )
    }

    /// A float attribute.
    pub fn new(name: impl Into<String>, rate: AttributeRate, components: usize, data: Vec<f32>) -> Self {
        Attribute {
            name: name.into(),
            rate,
            components,
            data: AttributeData::Float(data),
            kind: AttributeKind::Float,
        }
    }

    /// An integer attribute of integer kind `kind`.
    pub fn integers(
        name: impl Into<String>,
        rate: AttributeRate,
        components: usize,
        data: Vec<i64>,
        kind: AttributeKind,
    ) -> Self {
        debug_assert!(kind.is_integer());
        Attribute { name: name.into(), rate, components, data: AttributeData::Int(data), kind }
    }

    /// The kind of a float attribute (a role, or `Bool`).
    pub fn with_kind(mut self, kind: AttributeKind) -> Self {
        debug_assert!(!kind.is_integer(), "integer attributes are made by Attribute::integers");
        self.kind = kind;
        self
    }

    /// The values as numbers for what computes with them (rates, wetness, frames): floats as
    /// they are, integers converted.
    pub fn floats(&self) -> Cow<'_, [f32]> {
        self.data.floats(self.kind)
    }

    /// A float attribute's values, to change in place; `None` for integers.
    pub fn floats_mut(&mut self) -> Option<&mut Vec<f32>> {
        match &mut self.data {
            AttributeData::Float(v) => Some(v),
            AttributeData::Int(_) => None,
        }
    }

    /// An integer attribute's values as stored (see [`AttributeKind::integer`]).
    pub fn ints(&self) -> Option<&[i64]> {
        match &self.data {
            AttributeData::Int(v) => Some(v),
            AttributeData::Float(_) => None,
        }
    }

    /// Number of elements (vertices or strands) the data covers.
    pub fn len(&self) -> usize {
        self.data.len() / self.components.max(1)
    }

    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }
}

/// Ways a groom can break the model's invariants; each names the strand or attribute at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GroomError {
    #[error("strand offsets are malformed: {0}")]
    BadOffsets(String),
    #[error("strand {strand} has {count} vertices; a strand needs at least 2")]
    TooFewVertices { strand: usize, count: usize },
    #[error("strand {strand}, vertex {vertex}: coordinate is not finite")]
    NonFinite { strand: usize, vertex: usize },
    #[error(
        "strand {strand}, segment {segment}: zero-length segment (its points are within {} m: a \
         duplicated point, or the file's units are another unit's)",
        crate::validate::shortest(f64::from(MIN_SEGMENT_LENGTH))
    )]
    ZeroLengthSegment { strand: usize, segment: usize },
    #[error(
        "strand {strand}, vertex {vertex}: width {} m (the file's units converted to metres) is negative \
         or not finite",
        crate::validate::shortest(f64::from(*width))
    )]
    BadWidth { strand: usize, vertex: usize, width: f32 },
    #[error(
        "strand {strand}, vertex {vertex}: width {} m is too wide to simulate as a hair (at most \
         {max} m); are the file's widths, or its units, another unit's?",
        crate::validate::shortest(f64::from(*width))
    )]
    TooWide { strand: usize, vertex: usize, width: f32, max: f32 },
    #[error(
        "strand {strand}, vertex {vertex}: width {} m is too thin to simulate as a hair (at least \
         {} m; a width of 0 takes the default); are the file's widths, or its units, another unit's?",
        crate::validate::shortest(f64::from(*width)),
        crate::validate::shortest(f64::from(*min))
    )]
    TooThin { strand: usize, vertex: usize, width: f32, min: f32 },
    #[error(
        "the simulation diverged{} ({how}) by {seconds:.3} s of simulated time: \
         the groom's widths, lengths or rest shape, or the settings (dt, iterations, moduli, \
         gravity), are beyond what the solver holds",
        stage.as_ref().map_or(String::new(), |s| format!(" in {s}"))
    )]
    Diverged { seconds: f64, stage: Option<String>, how: String },
    #[error(
        "the recipe is written in the head frame, but {reason}; give the head in the recipe's [head] \
         table (center, up, front, size)"
    )]
    NoHeadFrame { reason: String },
    /// The scalp mesh given with the groom (its own, or `--scalp`) does not fit a head frame.
    #[error(
        "the recipe is written in the head frame, but the scalp mesh has no curved surface near the \
         groom's roots; give the head in the recipe's [head] table (center, up, front, size)"
    )]
    ScalpNotFitted,
    /// The file's guide bindings (`groom_closest_guides`, `groom_guide_weights`) are unusable.
    #[error("{0}")]
    Binding(String),
    /// The guides asked for do not fit the groom: more than its strands, or children beyond
    /// their reach.
    #[error("{0}")]
    Guides(String),
    #[error(
        "strand {strand}, vertex {vertex}: a coordinate of {} m is beyond the {max} m from the origin \
         a groom is simulated in; are the file's units another unit's?",
        crate::validate::shortest(f64::from(*coordinate))
    )]
    TooFar { strand: usize, vertex: usize, coordinate: f32, max: f32 },
    #[error(
        "strand {strand} is {length:.2} m long, longer than the {max} m a hair is simulated at (the longest \
         on record is 5.6 m); are the file's units another unit's?"
    )]
    TooLong { strand: usize, length: f32, max: f32 },
    #[error("{what} has {found} entries, expected {expected}")]
    Length { what: String, expected: usize, found: usize },
    #[error("attribute '{name}' has {components} components; 1 to 4 are allowed")]
    AttributeComponents { name: String, components: usize },
    #[error("attribute '{name}' appears twice")]
    DuplicateAttribute { name: String },
    /// A value the simulation cannot take (a rest state or frame it reads back).
    #[error("attribute '{name}': {problem}")]
    BadAttribute { name: String, problem: String },
    #[error("mesh <{path}>: {problem}")]
    Mesh { path: String, problem: String },
}

impl GroomError {
    /// Whether the error is a size no hair has (a width, length or distance), which the units
    /// the file was read in may explain.
    pub fn is_a_size(&self) -> bool {
        matches!(
            self,
            GroomError::ZeroLengthSegment { .. }
                | GroomError::TooWide { .. }
                | GroomError::TooThin { .. }
                | GroomError::TooFar { .. }
                | GroomError::TooLong { .. }
        )
    }

    /// The strand at fault, for the errors that name one.
    pub fn strand(&self) -> Option<usize> {
        match *self {
            GroomError::TooFewVertices { strand, .. }
            | GroomError::NonFinite { strand, .. }
            | GroomError::ZeroLengthSegment { strand, .. }
            | GroomError::BadWidth { strand, .. }
            | GroomError::TooWide { strand, .. }
            | GroomError::TooThin { strand, .. }
            | GroomError::TooFar { strand, .. }
            | GroomError::TooLong { strand, .. } => Some(strand),
            _ => None,
        }
    }
}

/// Strand ids of curve objects (prims) merged into one groom, in object order: `parts` gives each
/// object's strand count and its ids from the file, `None` when it has none. A file's ids are what
/// its guide bindings (`groom_closest_guides`) name, so they are kept; only an object whose ids
/// repeat ones taken by an earlier object (objects numbered each from 0) is moved past the
/// largest id so far, and objects without ids are numbered after every given id.
pub fn merged_strand_ids(parts: &[(usize, Option<&[u32]>)]) -> Vec<u32> {
    let mut taken = std::collections::HashSet::new();
    let mut next: u32 = 0;
    let mut ids: Vec<Option<Vec<u32>>> = Vec::with_capacity(parts.len());
    for (_, given) in parts {
        ids.push(given.map(|given| {
            let shift = if given.iter().any(|id| taken.contains(id)) { next } else { 0 };
            let kept: Vec<u32> = given.iter().map(|&id| id.wrapping_add(shift)).collect();
            for &id in &kept {
                taken.insert(id);
                next = next.max(id.wrapping_add(1));
            }
            kept
        }));
    }
    parts
        .iter()
        .zip(ids)
        .flat_map(|(&(count, _), kept)| {
            kept.unwrap_or_else(|| {
                let first = next;
                next = next.wrapping_add(count as u32);
                (0..count as u32).map(|i| first.wrapping_add(i)).collect()
            })
        })
        .collect()
}

/// A groom: many strands, each a polyline (or cubic control polygon) rooted on the scalp.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Groom {
    /// All strands' points, root first within each strand.
    pub points: Vec<Vec3>,
    /// `strand_offsets[i]..strand_offsets[i + 1]` are strand `i`'s points; starts with 0.
    pub strand_offsets: Vec<u32>,
    /// Per-vertex diameter in metres.
    pub widths: Vec<f32>,
    /// Per-strand stable identifier (Epic's `groom_id`).
    pub strand_ids: Vec<u32>,
    /// Per-strand root position on the scalp's UV layout, when known.
    pub root_uvs: Option<Vec<[f32; 2]>>,
    /// Per-strand guide flag, when the groom distinguishes guides from rendered strands.
    pub guides: Option<Vec<bool>>,
    /// The basis of a groom without a group table; with one, the first group's (each group
    /// has its own, see [`crate::groups`]).
    pub basis: CurveBasis,
    /// Named curve groups (one per curve prim / curves object); empty: one unnamed group.
    pub groups: Vec<CurveGroup>,
    /// Per-strand index into `groups`; empty when `groups` is.
    pub group_ids: Vec<u32>,
    /// Named attributes, sorted by name (use [`Groom::set_attribute`] to add one).
    pub attributes: Vec<Attribute>,
    /// Scalp, head or body meshes the file brought beside the curves (see [`crate::surface_mesh`]).
    pub meshes: Vec<SurfaceMesh>,
}

impl Groom {
    /// Builds a groom from strands given as point lists, with one width for every vertex.
    pub fn from_strands<S: AsRef<[Vec3]>>(strands: &[S], width: f32) -> Self {
        let mut groom = Groom { strand_offsets: vec![0], ..Default::default() };
        for strand in strands {
            groom.points.extend_from_slice(strand.as_ref());
            groom.strand_offsets.push(groom.points.len() as u32);
        }
        groom.widths = vec![width; groom.points.len()];
        groom.strand_ids = (0..strands.len() as u32).collect();
        groom
    }

    /// Per-vertex radii the colliders and hair–hair contacts see: half the width, at least
    /// 0.5 µm (a zero width still collides).
    pub fn contact_radii(&self) -> Vec<f32> {
        self.widths.iter().map(|w| 0.5 * w.max(1e-6)).collect()
    }

    pub fn strand_count(&self) -> usize {
        self.strand_offsets.len().saturating_sub(1)
    }

    pub fn vertex_count(&self) -> usize {
        self.points.len()
    }

    /// Index range of strand `strand`'s vertices in the per-vertex arrays.
    pub fn strand_range(&self, strand: usize) -> Range<usize> {
        self.strand_offsets[strand] as usize..self.strand_offsets[strand + 1] as usize
    }

    /// The strand vertex `vertex` belongs to.
    pub fn strand_of(&self, vertex: usize) -> usize {
        self.strand_offsets.partition_point(|&o| o as usize <= vertex) - 1
    }

    /// The strand a vertex index falls in, and the vertex's index within it (for messages).
    pub fn strand_and_vertex(&self, vertex: usize) -> (usize, usize) {
        let strand = self.strand_of(vertex);
        (strand, vertex - self.strand_offsets[strand] as usize)
    }

    pub fn strand_points(&self, strand: usize) -> &[Vec3] {
        &self.points[self.strand_range(strand)]
    }

    /// Vertex count of each strand, in order.
    pub fn vertex_counts(&self) -> impl Iterator<Item = usize> + '_ {
        self.strand_offsets.windows(2).map(|w| (w[1] - w[0]) as usize)
    }

    /// Arc length of a strand's control polygon.
    pub fn strand_length(&self, strand: usize) -> f32 {
        polyline_length(self.strand_points(strand))
    }

    /// Axis-aligned bounds of all points, or `None` for an empty groom.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.points.first()?;
        Some(self.points.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))))
    }

    pub fn attribute(&self, name: &str) -> Option<&Attribute> {
        self.attributes.iter().find(|a| a.name == name)
    }

    pub fn attribute_mut(&mut self, name: &str) -> Option<&mut Attribute> {
        self.attributes.iter_mut().find(|a| a.name == name)
    }

    /// Adds an attribute, replacing one of the same name. Attributes stay sorted by name, so
    /// grooms compare equal and files come out the same whatever order attributes were set in.
    /// Groups that miss it (`CurveGroup::missing`) still do ([`Self::provide_attribute`]).
    pub fn set_attribute(&mut self, attribute: Attribute) {
        match self.attributes.binary_search_by(|a| a.name.as_str().cmp(&attribute.name)) {
            Ok(index) => self.attributes[index] = attribute,
            Err(index) => self.attributes.insert(index, attribute),
        }
    }

    /// [`Self::set_attribute`] for an attribute computed for every strand (a simulated state, a
    /// guide binding): every group carries it, so writers put it on every prim or object, not
    /// only on those whose file had it.
    pub fn provide_attribute(&mut self, attribute: Attribute) {
        for group in &mut self.groups {
            group.missing.retain(|name| *name != attribute.name);
        }
        self.set_attribute(attribute);
    }

    pub fn remove_attribute(&mut self, name: &str) -> Option<Attribute> {
        let index = self.attributes.iter().position(|a| a.name == name)?;
        Some(self.attributes.remove(index))
    }

    /// Elements an attribute of the given rate must have.
    pub fn element_count(&self, rate: AttributeRate) -> usize {
        match rate {
            AttributeRate::Vertex => self.vertex_count(),
            AttributeRate::Strand => self.strand_count(),
        }
    }

    /// Scales all positions and widths (unit conversion at import/export), and the attributes
    /// that are positions or vectors (`rest`, velocities) with them.
    pub fn scale(&mut self, factor: f32) {
        self.points.iter_mut().for_each(|p| *p *= factor);
        self.widths.iter_mut().for_each(|w| *w *= factor);
        let scale = glam::DMat4::from_scale(glam::DVec3::splat(factor as f64));
        self.meshes.iter_mut().for_each(|m| m.transform(scale));
        crate::io::transform_attributes(&mut self.attributes, scale);
    }

    /// Checks every invariant of the model, and that every segment has a direction (a strand can
    /// be simulated and rendered); the first violation is returned.
    pub fn validate(&self) -> Result<(), GroomError> {
        self.check(Segments::Directed)
    }

    /// [`Self::validate`] but for segment lengths: what a file may hold and coif reads, converts
    /// and writes. DCC tools write coincident consecutive points (a duplicated root), and pxr and
    /// Blender read them; only simulating or rendering such a strand needs a direction there.
    pub fn validate_stored(&self) -> Result<(), GroomError> {
        self.check(Segments::Any)
    }

    fn check(&self, segments: Segments) -> Result<(), GroomError> {
        self.validate_offsets()?;
        let strands = self.strand_count();
        let vertices = self.vertex_count();
        check_len("widths", vertices, self.widths.len())?;
        check_len("strand ids", strands, self.strand_ids.len())?;
        if let Some(uvs) = &self.root_uvs {
            check_len("root UVs", strands, uvs.len())?;
        }
        if let Some(guides) = &self.guides {
            check_len("guide flags", strands, guides.len())?;
        }
        crate::groups::validate(self)?;
        // Branch-free passes over the whole arrays first, on all threads (a read groom is checked
        // whole, so this is on every import's path; the passes give booleans and counts, which
        // do not depend on the split); only a groom that fails one is searched for the first fault.
        const CHUNK: usize = 1 << 16;
        let finite = bytemuck::cast_slice::<Vec3, f32>(&self.points).par_chunks(CHUNK).all(all_finite);
        // Finite and not negative: below +inf's bits, or -0.
        let widths_ok = self
            .widths
            .par_chunks(CHUNK)
            .all(|chunk| chunk.iter().fold(true, |ok, &w| ok & ((w.to_bits() < 0x7f80_0000) | (w == 0.0))));
        let counts_ok = self.strand_offsets.windows(2).fold(true, |ok, w| ok & (w[1] - w[0] >= 2));
        let min_squared = MIN_SEGMENT_LENGTH * MIN_SEGMENT_LENGTH;
        let short = |a: &Vec3, b: &Vec3| (a.distance_squared(*b) <= min_squared) as usize;
        // Segments are all long when the only short pairs of consecutive points are pairs that
        // straddle two strands (a strand's tip and the next one's root).
        let long = strands == 0
            || (counts_ok && segments == Segments::Any)
            || (counts_ok && {
                // Each chunk with the next one's first point: every pair is counted once.
                let pairs: usize = (0..vertices.div_ceil(CHUNK))
                    .into_par_iter()
                    .map(|k| {
                        short_pairs(&self.points[k * CHUNK..((k + 1) * CHUNK + 1).min(vertices)], min_squared)
                    })
                    .sum();
                let straddling = self.strand_offsets[1..strands]
                    .iter()
                    .map(|&o| short(&self.points[o as usize - 1], &self.points[o as usize]))
                    .sum::<usize>();
                pairs == straddling
            });
        if !(finite & widths_ok & long) {
            self.find_fault(segments)?;
        }
        for (i, attribute) in self.attributes.iter().enumerate() {
            if !(1..=Attribute::MAX_COMPONENTS).contains(&attribute.components) {
                return Err(GroomError::AttributeComponents {
                    name: attribute.name.clone(),
                    components: attribute.components,
                });
            }
            if self.attributes[..i].iter().any(|a| a.name == attribute.name) {
                return Err(GroomError::DuplicateAttribute { name: attribute.name.clone() });
            }
            let expected = self.element_count(attribute.rate) * attribute.components;
            check_len(&format!("attribute '{}'", attribute.name), expected, attribute.data.len())?;
            check_numbers(attribute)?;
        }
        for mesh in &self.meshes {
            mesh.check().map_err(|problem| GroomError::Mesh { path: mesh.path.clone(), problem })?;
        }
        Ok(())
    }

    /// Where strand `strand` came from in a file of several curve prims or objects: "curve 1 of
    /// </groom/b>" (the groom's strand index counts across all of them, which alone does not find
    /// the curve in a file of many prims). `None` for a groom of one unnamed group.
    pub fn strand_origin(&self, strand: usize) -> Option<String> {
        let group = *self.group_ids.get(strand)?;
        let name = &self.groups.get(group as usize)?.name;
        let curve = self.group_ids[..strand].iter().filter(|&&g| g == group).count();
        Some(format!("curve {curve} of <{name}>"))
    }

    /// The first bad strand: too few vertices, a point not finite, a zero-length segment (when
    /// `segments` asks for directions) or a bad width, in strand order.
    fn find_fault(&self, segments: Segments) -> Result<(), GroomError> {
        for strand in 0..self.strand_count() {
            let range = self.strand_range(strand);
            let points = &self.points[range.clone()];
            if points.len() < 2 {
                return Err(GroomError::TooFewVertices { strand, count: points.len() });
            }
            for (vertex, p) in points.iter().enumerate() {
                if !p.is_finite() {
                    return Err(GroomError::NonFinite { strand, vertex });
                }
            }
            for (segment, pair) in points.windows(2).enumerate() {
                if segments == Segments::Directed
                    && pair[0].distance_squared(pair[1]) <= MIN_SEGMENT_LENGTH * MIN_SEGMENT_LENGTH
                {
                    return Err(GroomError::ZeroLengthSegment { strand, segment });
                }
            }
            for (vertex, &width) in self.widths[range].iter().enumerate() {
                if !(width.is_finite() && width >= 0.0) {
                    return Err(GroomError::BadWidth { strand, vertex, width });
                }
            }
        }
        Ok(())
    }

    fn validate_offsets(&self) -> Result<(), GroomError> {
        match self.strand_offsets.first() {
            None => {
                return if self.points.is_empty() {
                    Ok(())
                } else {
                    Err(GroomError::BadOffsets("points without strand offsets".into()))
                }
            }
            Some(&first) if first != 0 => {
                return Err(GroomError::BadOffsets(format!("first offset is {first}, not 0")))
            }
            Some(_) => {}
        }
        if let Some(strand) = self.strand_offsets.windows(2).position(|w| w[1] < w[0]) {
            return Err(GroomError::BadOffsets(format!("strand {strand} ends before it starts")));
        }
        let last = *self.strand_offsets.last().unwrap() as usize;
        if last != self.points.len() {
            return Err(GroomError::BadOffsets(format!(
                "offsets cover {last} points but the groom has {}",
                self.points.len()
            )));
        }
        Ok(())
    }
}

/// How many pairs of consecutive points lie within `min_squared` of each other (squared
/// distance), in blocks whose squared differences are computed as flat arrays (vectorized).
fn short_pairs(points: &[Vec3], min_squared: f32) -> usize {
    const BLOCK: usize = 64;
    let flat: &[f32] = bytemuck::cast_slice(points);
    let pairs = points.len().saturating_sub(1);
    let mut count = 0;
    let mut first = 0;
    while first + BLOCK <= pairs {
        let from = &flat[3 * first..3 * (first + BLOCK)];
        let to = &flat[3 * first + 3..3 * (first + BLOCK) + 3];
        let mut squares = [0f32; 3 * BLOCK];
        for ((square, a), b) in squares.iter_mut().zip(from).zip(to) {
            *square = (b - a) * (b - a);
        }
        count += squares.chunks_exact(3).map(|s| u32::from(s[0] + s[1] + s[2] <= min_squared)).sum::<u32>()
            as usize;
        first += BLOCK;
    }
    count + (first..pairs).filter(|&i| points[i].distance_squared(points[i + 1]) <= min_squared).count()
}

/// What [`Groom`]'s checks ask of segment lengths.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Segments {
    /// Every segment at least [`MIN_SEGMENT_LENGTH`] long.
    Directed,
    /// Any length.
    Any,
}

/// Segments shorter than this (metres) count as zero-length: a solver cannot give them a direction.
pub const MIN_SEGMENT_LENGTH: f32 = 1e-9;

/// Whether every value is finite: exponent bits not all set, tested without a branch per value
/// so the loop vectorizes.
pub fn all_finite(values: &[f32]) -> bool {
    values.chunks(4096).all(|chunk| {
        chunk.iter().map(|v| u32::from(v.to_bits() & 0x7f80_0000 == 0x7f80_0000)).sum::<u32>() == 0
    })
}

/// Integers for the integer kinds, each in its kind's range; floats for the others.
fn check_numbers(attribute: &Attribute) -> Result<(), GroomError> {
    let problem = match (&attribute.data, attribute.kind) {
        (AttributeData::Int(values), kind) if kind.is_integer() => values
            .iter()
            .map(|&v| kind.integer(v))
            .find(|&v| !kind.holds(v))
            .map(|v| format!("{v} is out of the range of its type ({kind:?})")),
        (AttributeData::Float(_), kind) if !kind.is_integer() => None,
        (_, kind) => Some(format!("{kind:?} values held as the wrong number type")),
    };
    match problem {
        Some(problem) => Err(GroomError::BadAttribute { name: attribute.name.clone(), problem }),
        None => Ok(()),
    }
}

fn check_len(what: &str, expected: usize, found: usize) -> Result<(), GroomError> {
    if expected == found {
        Ok(())
    } else {
        Err(GroomError::Length { what: what.to_string(), expected, found })
    }
}

/// Sum of segment lengths of a polyline.
pub fn polyline_length(points: &[Vec3]) -> f32 {
    points.windows(2).map(|w| w[0].distance(w[1])).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merged_strand_ids_keep_a_files_ids_and_number_the_rest_after_them() {
        // Ids given on some objects are kept; objects without come after the largest.
        let ids = merged_strand_ids(&[(2, Some(&[1000, 1007][..])), (3, None), (1, Some(&[5][..]))]);
        assert_eq!(ids, vec![1000, 1007, 1008, 1009, 1010, 5]);
        // Objects numbered each from 0: later ones move past the ids taken.
        let ids = merged_strand_ids(&[(2, Some(&[0, 1][..])), (2, Some(&[0, 1][..])), (1, None)]);
        assert_eq!(ids, vec![0, 1, 2, 3, 4]);
        // No ids anywhere: 0, 1, 2, … in object order.
        assert_eq!(merged_strand_ids(&[(2, None), (1, None)]), vec![0, 1, 2]);
    }

    fn two_strands() -> Groom {
        Groom::from_strands(
            &[vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)], vec![Vec3::Y, Vec3::new(0.0, 2.0, 0.0)]],
            1e-4,
        )
    }

    #[test]
    fn accessors_follow_offsets() {
        let groom = two_strands();
        assert_eq!(groom.strand_count(), 2);
        assert_eq!(groom.vertex_count(), 5);
        assert_eq!(groom.strand_points(1), &[Vec3::Y, Vec3::new(0.0, 2.0, 0.0)]);
        assert_eq!(groom.vertex_counts().collect::<Vec<_>>(), vec![3, 2]);
        assert_eq!(groom.strand_length(0), 2.0);
        assert!(groom.validate().is_ok());
    }

    #[test]
    fn validation_names_the_culprit() {
        let mut groom = two_strands();
        groom.points[3] = Vec3::new(f32::NAN, 0.0, 0.0);
        assert_eq!(groom.validate(), Err(GroomError::NonFinite { strand: 1, vertex: 0 }));

        let mut groom = two_strands();
        groom.points[2] = groom.points[1];
        assert_eq!(groom.validate(), Err(GroomError::ZeroLengthSegment { strand: 0, segment: 1 }));

        let mut groom = two_strands();
        groom.strand_offsets = vec![0, 4, 5];
        assert_eq!(groom.validate(), Err(GroomError::TooFewVertices { strand: 1, count: 1 }));

        let mut groom = two_strands();
        groom.set_attribute(Attribute::new("wetness", AttributeRate::Vertex, 1, vec![0.0; 4]));
        assert!(matches!(groom.validate(), Err(GroomError::Length { what, .. }) if what.contains("wetness")));

        let mut groom = two_strands();
        groom.set_attribute(Attribute::new("big", AttributeRate::Strand, 5, vec![0.0; 10]));
        assert!(matches!(groom.validate(), Err(GroomError::AttributeComponents { .. })));

        let mut groom = two_strands();
        groom.widths[4] = -1.0;
        assert!(matches!(groom.validate(), Err(GroomError::BadWidth { strand: 1, vertex: 1, .. })));

        let mut groom = two_strands();
        groom.strand_offsets = vec![0, 3, 6];
        assert!(matches!(groom.validate(), Err(GroomError::BadOffsets(_))));
    }

    /// The whole-array checks against the strand-by-strand search, on grooms long enough for the
    /// blocked pass (64 segments a block) and with faults at every position of a block.
    #[test]
    fn whole_array_checks_agree_with_the_strand_by_strand_search() {
        let strands: Vec<Vec<Vec3>> =
            (0..7).map(|s| (0..40).map(|k| Vec3::new(s as f32, k as f32 * 0.01, 0.0)).collect()).collect();
        let groom = Groom::from_strands(&strands, 1e-4);
        assert!(groom.validate().is_ok());
        // A strand starting where the previous one ends is fine: that pair is no segment.
        let mut touching = groom.clone();
        touching.points[40] = touching.points[39];
        assert!(touching.validate().is_ok());
        for vertex in 1..groom.vertex_count() {
            let (strand, k) = (vertex / 40, vertex % 40);
            if k == 0 {
                continue;
            }
            let mut bad = groom.clone();
            bad.points[vertex] = bad.points[vertex - 1];
            assert_eq!(bad.validate(), Err(GroomError::ZeroLengthSegment { strand, segment: k - 1 }));
            let mut bad = groom.clone();
            bad.points[vertex].z = f32::INFINITY;
            assert_eq!(bad.validate(), Err(GroomError::NonFinite { strand, vertex: k }));
            let mut bad = groom.clone();
            bad.widths[vertex] = f32::NAN;
            assert!(
                matches!(bad.validate(), Err(GroomError::BadWidth { strand: s, vertex: v, .. }) if (s, v) == (strand, k))
            );
        }
        // Zero widths, of either sign, are allowed; the smallest negative is not.
        let mut zero = groom.clone();
        zero.widths[5] = -0.0;
        zero.widths[6] = 0.0;
        assert!(zero.validate().is_ok());
        zero.widths[7] = -f32::from_bits(1);
        assert!(matches!(zero.validate(), Err(GroomError::BadWidth { strand: 0, vertex: 7, .. })));
    }

    /// The whole-array checks run in chunks of 2^16 points on all threads: a zero-length
    /// segment across a chunk's end is found, a strand's root touching the previous tip there
    /// is no segment.
    #[test]
    fn whole_array_checks_see_segments_across_chunk_ends() {
        const CHUNK: usize = 1 << 16;
        // 48 vertices a strand: the chunk's end falls inside strand 1365 (its vertex 16).
        let strands: Vec<Vec<Vec3>> =
            (0..1400).map(|s| (0..48).map(|k| Vec3::new(s as f32, k as f32 * 0.01, 0.0)).collect()).collect();
        let groom = Groom::from_strands(&strands, 1e-4);
        assert!(groom.validate().is_ok());
        for (vertex, strand, segment) in [(CHUNK, 1365, 15), (CHUNK + 1, 1365, 16)] {
            let mut bad = groom.clone();
            bad.points[vertex] = bad.points[vertex - 1];
            assert_eq!(bad.validate(), Err(GroomError::ZeroLengthSegment { strand, segment }));
        }
        // 64 vertices a strand: the chunk's end is a strand's end.
        let strands: Vec<Vec<Vec3>> =
            (0..1040).map(|s| (0..64).map(|k| Vec3::new(s as f32, k as f32 * 0.01, 0.0)).collect()).collect();
        let mut touching = Groom::from_strands(&strands, 1e-4);
        touching.points[CHUNK] = touching.points[CHUNK - 1];
        assert!(touching.validate().is_ok());
    }

    #[test]
    fn set_attribute_replaces_by_name() {
        let mut groom = two_strands();
        groom.set_attribute(Attribute::new("w", AttributeRate::Strand, 1, vec![0.0, 0.0]));
        groom.set_attribute(Attribute::new("w", AttributeRate::Strand, 1, vec![1.0, 1.0]));
        assert_eq!(groom.attributes.len(), 1);
        assert_eq!(groom.attribute("w").unwrap().floats(), vec![1.0, 1.0]);
        assert!(groom.validate().is_ok());
    }
}
