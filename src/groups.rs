//! Curve groups: a production groom is several named sets of curves (guides and children, one
//! per curve prim or Alembic curves object), each with its own basis and wrap. The groom keeps
//! one struct-of-arrays for all strands; `Groom::groups` is the group table and
//! `Groom::group_ids` each strand's index into it. A groom with an empty table is one unnamed
//! group of `Groom::basis`, nonperiodic (what coif's own generator makes).
//!
//! Every way of combining strands — readers appending prims, `--group` selecting some groups and
//! putting the styled ones back — goes through one function, [`assemble`].
use std::borrow::Cow;
use std::ops::Range;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::groom::{
    Attribute, AttributeData, AttributeKind, AttributeRate, CurveBasis, Groom, GroomError, Values,
};
use crate::surface_mesh::SurfaceMesh;

/// How a curve's ends behave (USD `wrap`; Alembic's periodicity byte).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CurveWrap {
    /// Open curve; a cubic basis does not reach its end points (USD `nonperiodic`).
    #[default]
    Nonperiodic,
    /// Open curve whose cubic segments are extended to pass through the end points (USD
    /// `pinned`, what Blender writes for Catmull-Rom).
    Pinned,
    /// Closed curve. Read and written back, but never simulated.
    Periodic,
}

/// A primvar interpolation a file gave an attribute that its rate alone would not give back, so
/// writers can return the file's choice where the values still fit it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// USD `constant`: one value for the whole prim (read as the same value on every strand).
    Constant,
    /// USD `uniform`, Alembic `uni`: one value per curve (recorded for widths, which the groom
    /// keeps per vertex).
    Uniform,
    /// USD `varying`: one value per segment end (see [`crate::primvar_rates`]). For attributes,
    /// recorded only where that is one per vertex (linear and pinned curves); for widths on
    /// any basis.
    Varying,
}

impl Interpolation {
    /// The USD `interpolation` token.
    pub fn usd_name(self) -> &'static str {
        match self {
            Interpolation::Constant => "constant",
            Interpolation::Uniform => "uniform",
            Interpolation::Varying => "varying",
        }
    }

    /// The Alembic `geoScope`.
    pub fn alembic_scope(self) -> &'static str {
        match self {
            Interpolation::Constant => "con",
            Interpolation::Uniform => "uni",
            Interpolation::Varying => "var",
        }
    }
}

/// One named set of curves sharing a basis.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CurveGroup {
    /// Where the curves came from: the prim path in USD, the object path in Alembic.
    pub name: String,
    pub basis: CurveBasis,
    pub wrap: CurveWrap,
    /// USD `purpose` (`"guide"` for Houdini's guide curves), when authored.
    pub purpose: Option<String>,
    /// USD `visibility = "invisible"` on the prim or an ancestor (an Alembic object's `visible`
    /// property 0): the curves are kept, styled and written back invisible; previews leave them
    /// out, as a renderer would.
    pub invisible: bool,
    /// Groom attributes this group does not carry (the groom pads them with zeros for its
    /// strands; writers leave them out of this group's prim).
    pub missing: Vec<String>,
    /// Attributes this group's file gave an [`Interpolation`] their rate does not say.
    pub interpolations: Vec<(String, Interpolation)>,
    /// Attributes this group's file gave as scalar arrays with an `elementSize` (their
    /// components), as Houdini writes array attributes; writers give them back so.
    pub element_sized: Vec<String>,
    /// How the file gave the widths (`None`: per vertex); the groom keeps them per vertex and
    /// writers give them back at this rate while the values fit it
    /// ([`crate::primvar_rates::widths_at`]).
    pub width_interpolation: Option<Interpolation>,
}

impl CurveGroup {
    pub fn new(name: impl Into<String>, basis: CurveBasis, wrap: CurveWrap) -> Self {
        CurveGroup { name: name.into(), basis, wrap, ..Default::default() }
    }

    /// The interpolation the file gave attribute `name` in this group, when not its rate's.
    pub fn interpolation(&self, name: &str) -> Option<Interpolation> {
        self.interpolations.iter().find(|(n, _)| n == name).map(|&(_, i)| i)
    }

    /// The name `missing` gives the groom's root UVs (`Groom::root_uvs`): a group whose file had
    /// none, merged with groups that have them, has zeros there that are no UVs (Unreal would
    /// take `(0, 0)` for a real root UV and skip its own projection). No file's attribute is
    /// named so.
    pub const ROOT_UVS: &'static str = "(root uvs)";

    /// Whether the group carries attribute `name`.
    pub fn carries(&self, name: &str) -> bool {
        !self.missing.iter().any(|m| m == name)
    }
}

/// The strands `--group` selected, to put back after styling with [`Groom::merge_back`].
#[derive(Clone, Debug, PartialEq)]
pub struct GroupSelection {
    /// The selected strands' indices in the whole groom, in order.
    pub strands: Vec<usize>,
}

impl Groom {
    /// Number of groups (at least one for a groom with strands).
    pub fn group_count(&self) -> usize {
        self.groups.len().max(1)
    }

    /// The group strand `strand` belongs to.
    pub fn group_of(&self, strand: usize) -> usize {
        self.group_ids.get(strand).map_or(0, |&g| g as usize)
    }

    /// Group `index` (the implicit one for a groom without a group table).
    pub fn group(&self, index: usize) -> Cow<'_, CurveGroup> {
        match self.groups.get(index) {
            Some(group) => Cow::Borrowed(group),
            None => Cow::Owned(CurveGroup::new("", self.basis, CurveWrap::Nonperiodic)),
        }
    }

    /// Makes every strand part of the one group `group` (a reader naming a single prim).
    pub fn set_single_group(&mut self, group: CurveGroup) {
        self.basis = group.basis;
        self.groups = vec![group];
        self.group_ids = vec![0; self.strand_count()];
    }

    /// Drops a one-group table that says nothing a writer would not write by default (the
    /// group named `default_name`, nonperiodic, no purpose, every attribute carried), so a file
    /// coif wrote reads back as the groom it was written from.
    pub fn drop_default_group(&mut self, default_name: &str) {
        if let [group] = self.groups.as_slice() {
            let plain = CurveGroup::new(default_name, group.basis, CurveWrap::Nonperiodic);
            if *group == plain {
                self.groups.clear();
                self.group_ids.clear();
            }
        }
    }

    /// [`Groom::drop_default_group`] for formats whose default group sits at any depth (an
    /// Alembic curves object named `object_name` under optional Xforms).
    pub fn drop_default_group_named(&mut self, object_name: &str) {
        if let [group] = self.groups.as_slice() {
            if group.name.rsplit('/').next() == Some(object_name) {
                let name = group.name.clone();
                self.drop_default_group(&name);
            }
        }
    }

    /// Strand indices of group `group`, in order.
    pub fn group_strands(&self, group: usize) -> Vec<usize> {
        if self.groups.len() <= 1 {
            return if group == 0 { (0..self.strand_count()).collect() } else { Vec::new() };
        }
        (0..self.strand_count()).filter(|&s| self.group_of(s) == group).collect()
    }

    /// One groom of every part's strands and groups, in order (a reader joining its prims or
    /// objects); meshes are moved along. The data is copied once however many parts there are.
    /// Attributes a part lacks are padded with zeros and recorded as missing from its groups.
    /// An error names the index of the first part that does not fit the ones before it.
    pub fn concat(parts: Vec<Groom>) -> Result<Groom, (usize, GroomError)> {
        concat_parts(parts, None)
    }

    /// [`Groom::concat`] of parts whose points and widths a reader put straight into `points`
    /// and `widths`, one part after another (the parts' own are left empty): those arrays
    /// become the whole groom's as they are, so the bulk of a file is copied once, from the
    /// file. An error also when the arrays do not hold exactly the parts' vertices.
    pub fn concat_placed(
        parts: Vec<Groom>,
        points: Vec<Vec3>,
        widths: Vec<f32>,
    ) -> Result<Groom, (usize, GroomError)> {
        concat_parts(parts, Some(PlacedVertices { points, widths }))
    }

    /// One groom per group, each with a one-entry group table and only the attributes its group
    /// carries. A groom of one group is borrowed, not copied.
    /// Each entry: the group's index, the group, and its strands.
    pub fn split_groups(&self) -> Result<Vec<(usize, CurveGroup, Cow<'_, Groom>)>, GroomError> {
        if self.groups.len() <= 1 {
            let group = self.group(0).into_owned();
            if group.missing.is_empty() {
                return Ok(vec![(0, group, Cow::Borrowed(self))]);
            }
        }
        let mut parts = Vec::with_capacity(self.group_count());
        for g in 0..self.group_count() {
            let strands = self.group_strands(g);
            if strands.is_empty() {
                continue;
            }
            let mut part = assemble(&[(self, &strands)])?;
            let group = self.group(g).into_owned();
            part.attributes.retain(|a| group.carries(&a.name));
            if !group.carries(CurveGroup::ROOT_UVS) {
                part.root_uvs = None;
            }
            let mut table_entry = group.clone();
            table_entry.missing.clear();
            part.set_single_group(table_entry);
            parts.push((g, group, Cow::Owned(part)));
        }
        Ok(parts)
    }

    /// The strands of the groups named `names` as a groom of their own, and where they came
    /// from. An unknown name is an error listing the groups there are.
    pub fn select_groups(&self, names: &[String]) -> Result<(Groom, GroupSelection), String> {
        let mut wanted = Vec::new();
        for name in names {
            // An empty name names no group (not a .hair file's unnamed one).
            let found = (0..self.group_count()).filter(|_| !name.is_empty()).find(|&g| {
                let group = self.group(g);
                group.name == *name || group.name.rsplit('/').next() == Some(name.as_str())
            });
            match found {
                Some(g) => wanted.push(g),
                None => {
                    let known: Vec<String> = (0..self.group_count())
                        .map(|g| self.group(g).name.clone())
                        .filter(|name| !name.is_empty())
                        .map(|name| format!("'{name}'"))
                        .collect();
                    if known.is_empty() {
                        return Err(format!(
                            "it has no named groups for --group '{name}' to pick (its curves are one \
                             unnamed set, as in every .hair file)"
                        ));
                    }
                    return Err(format!(
                        "it has no group named '{name}'; its groups are {}",
                        known.join(", ")
                    ));
                }
            }
        }
        let strands: Vec<usize> =
            (0..self.strand_count()).filter(|&s| wanted.contains(&self.group_of(s))).collect();
        let mut selected = assemble(&[(self, &strands)]).map_err(|e| e.to_string())?;
        selected.meshes = self.meshes.clone();
        Ok((selected, GroupSelection { strands }))
    }

    /// The whole groom again, with the selected strands replaced by `styled` (the styled
    /// selection: same strands in the same order; vertex counts may differ). Attributes styling
    /// added are recorded as missing from the groups that were not styled.
    pub fn merge_back(&self, selection: &GroupSelection, styled: &Groom) -> Result<Groom, GroomError> {
        if styled.strand_count() != selection.strands.len() {
            return Err(GroomError::Length {
                what: "styled strands".into(),
                expected: selection.strands.len(),
                found: styled.strand_count(),
            });
        }
        // Runs of consecutive strands from the same source, in the original order.
        let mut runs: Vec<(bool, Vec<usize>)> = Vec::new();
        let mut next_styled = 0;
        for strand in 0..self.strand_count() {
            let from_styled = selection.strands.get(next_styled) == Some(&strand);
            let index = if from_styled {
                next_styled += 1;
                next_styled - 1
            } else {
                strand
            };
            match runs.last_mut() {
                Some((source, list)) if *source == from_styled => list.push(index),
                _ => runs.push((from_styled, vec![index])),
            }
        }
        let parts: Vec<(&Groom, &[usize])> = runs
            .iter()
            .map(|(from_styled, list)| (if *from_styled { styled } else { self }, list.as_slice()))
            .collect();
        let mut whole = assemble(&parts)?;
        whole.meshes = self.meshes.clone();
        Ok(whole)
    }
}

/// The strands of one group: a contiguous range (slices are borrowed) or a list (gathered).
pub(crate) enum Strands {
    Range(Range<usize>),
    List(Vec<usize>),
}

impl Strands {
    pub(crate) fn of_group(groom: &Groom, group: usize) -> Strands {
        if groom.groups.len() <= 1 {
            return Strands::Range(if group == 0 { 0..groom.strand_count() } else { 0..0 });
        }
        let list = groom.group_strands(group);
        match (list.first(), list.last()) {
            (Some(&a), Some(&b)) if b + 1 - a == list.len() => Strands::Range(a..b + 1),
            _ => Strands::List(list),
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        match self {
            Strands::Range(r) => r.is_empty(),
            Strands::List(l) => l.is_empty(),
        }
    }

    /// Per-strand data (`components` values per strand).
    pub(crate) fn per_strand<'d, T: Clone>(&self, data: &'d [T], components: usize) -> Cow<'d, [T]> {
        match self {
            Strands::Range(r) => Cow::Borrowed(&data[r.start * components..r.end * components]),
            Strands::List(l) => Cow::Owned(
                l.iter().flat_map(|&s| data[s * components..(s + 1) * components].iter().cloned()).collect(),
            ),
        }
    }

    /// Per-vertex data (`components` values per vertex).
    pub(crate) fn per_vertex<'d, T: Clone>(
        &self,
        groom: &Groom,
        data: &'d [T],
        components: usize,
    ) -> Cow<'d, [T]> {
        let vertices = |r: Range<usize>| r.start * components..r.end * components;
        match self {
            Strands::Range(r) if r.is_empty() => Cow::Borrowed(&data[..0]),
            Strands::Range(r) => {
                let first = groom.strand_range(r.start).start;
                let last = groom.strand_range(r.end - 1).end;
                Cow::Borrowed(&data[vertices(first..last)])
            }
            Strands::List(l) => Cow::Owned(
                l.iter().flat_map(|&s| data[vertices(groom.strand_range(s))].iter().cloned()).collect(),
            ),
        }
    }

    /// An attribute's values on these strands.
    pub(crate) fn values<'d>(&self, groom: &Groom, attribute: &'d Attribute) -> Values<'d> {
        let c = attribute.components;
        match (&attribute.data, attribute.rate) {
            (AttributeData::Float(v), AttributeRate::Strand) => Values::Float(self.per_strand(v, c)),
            (AttributeData::Float(v), AttributeRate::Vertex) => Values::Float(self.per_vertex(groom, v, c)),
            (AttributeData::Int(v), AttributeRate::Strand) => Values::Int(self.per_strand(v, c)),
            (AttributeData::Int(v), AttributeRate::Vertex) => Values::Int(self.per_vertex(groom, v, c)),
        }
    }

    pub(crate) fn counts(&self, groom: &Groom) -> Vec<i32> {
        let count = |s: usize| groom.strand_range(s).len() as i32;
        match self {
            Strands::Range(r) => r.clone().map(count).collect(),
            Strands::List(l) => l.iter().map(|&s| count(s)).collect(),
        }
    }
}

/// Points and widths a reader already laid out for all parts of a [`Groom::concat_placed`].
struct PlacedVertices {
    points: Vec<Vec3>,
    widths: Vec<f32>,
}

fn concat_parts(mut parts: Vec<Groom>, placed: Option<PlacedVertices>) -> Result<Groom, (usize, GroomError)> {
    if parts.len() == 1 {
        let mut whole = parts.pop().expect("one part");
        if let Some(placed) = placed {
            let vertices = whole.strand_offsets.last().copied().unwrap_or(0) as usize;
            if placed.points.len() != vertices || placed.widths.len() != vertices {
                return Err((0, placed_length_error(vertices, &placed)));
            }
            whole.points = placed.points;
            whole.widths = placed.widths;
        }
        return Ok(whole);
    }
    // The one conflict `assemble` refuses: an attribute name with two component counts.
    let mut components: Vec<(&str, usize)> = Vec::new();
    for (index, part) in parts.iter().enumerate() {
        for attribute in &part.attributes {
            match components.iter().find(|(name, _)| *name == attribute.name) {
                Some(&(_, first)) if first != attribute.components => {
                    let name = attribute.name.clone();
                    let components = attribute.components;
                    return Err((index, GroomError::AttributeComponents { name, components }));
                }
                Some(_) => {}
                None => components.push((&attribute.name, attribute.components)),
            }
        }
    }
    let meshes: Vec<SurfaceMesh> = parts.iter_mut().flat_map(|p| std::mem::take(&mut p.meshes)).collect();
    let strands: Vec<Vec<usize>> = parts.iter().map(|p| (0..p.strand_count()).collect()).collect();
    let sources: Vec<(&Groom, &[usize])> =
        parts.iter().zip(&strands).map(|(p, s)| (p, s.as_slice())).collect();
    let mut whole = assemble_with(&sources, placed).map_err(|e| (parts.len() - 1, e))?;
    whole.meshes = meshes;
    Ok(whole)
}

fn placed_length_error(vertices: usize, placed: &PlacedVertices) -> GroomError {
    let (what, found) = if placed.points.len() != vertices {
        ("placed points", placed.points.len())
    } else {
        ("placed widths", placed.widths.len())
    };
    GroomError::Length { what: what.into(), expected: vertices, found }
}

/// A groom made of the listed strands of several grooms, in order. Group tables are merged by
/// group (equal name, basis, wrap and purpose); per-strand data missing from a source is filled
/// (ids renumbered only if some source has none, root UVs zero, not a guide); an attribute a
/// source lacks is zero for its strands and recorded in its groups' `missing`; per-strand and
/// per-vertex versions of one attribute become per-vertex.
pub fn assemble(parts: &[(&Groom, &[usize])]) -> Result<Groom, GroomError> {
    assemble_with(parts, None)
}

/// [`assemble`]; with `placed`, the parts' points and widths are those arrays, laid out already.
fn assemble_with(parts: &[(&Groom, &[usize])], placed: Option<PlacedVertices>) -> Result<Groom, GroomError> {
    let mut out = Groom { strand_offsets: vec![0], ..Default::default() };
    // The output group of each source group, per part.
    let mut group_maps: Vec<Vec<u32>> = Vec::with_capacity(parts.len());
    for (groom, _) in parts {
        let mut map = Vec::with_capacity(groom.group_count());
        for g in 0..groom.group_count() {
            let mut group = groom.group(g).into_owned();
            group.missing.clear();
            let index = match out.groups.iter().position(|o| {
                o.name == group.name
                    && o.basis == group.basis
                    && o.wrap == group.wrap
                    && o.purpose == group.purpose
                    && o.invisible == group.invisible
            }) {
                Some(i) => i,
                None => {
                    out.groups.push(group);
                    out.groups.len() - 1
                }
            };
            map.push(index as u32);
        }
        group_maps.push(map);
    }
    let strand_total: usize = parts.iter().map(|(_, strands)| strands.len()).sum();
    let vertex_total: usize =
        parts.iter().flat_map(|(g, strands)| strands.iter().map(|&s| g.strand_range(s).len())).sum();
    if let Some(placed) = &placed {
        if placed.points.len() != vertex_total || placed.widths.len() != vertex_total {
            return Err(placed_length_error(vertex_total, placed));
        }
    } else {
        out.points.reserve_exact(vertex_total);
        out.widths.reserve_exact(vertex_total);
        crate::io::input::advise_huge_pages(out.points.spare_capacity_mut());
        crate::io::input::advise_huge_pages(out.widths.spare_capacity_mut());
    }
    out.strand_offsets.reserve_exact(strand_total);
    out.strand_ids.reserve_exact(strand_total);
    out.group_ids.reserve_exact(strand_total);
    let any_uvs = parts.iter().any(|(g, _)| g.root_uvs.is_some());
    let any_guides = parts.iter().any(|(g, _)| g.guides.is_some());
    let (mut uvs, mut guides) = (Vec::new(), Vec::new());
    let mut carries_uvs = vec![false; out.groups.len()];
    for ((groom, strands), map) in parts.iter().zip(&group_maps) {
        for run in runs(groom, strands) {
            let (first, last) = (run.start, run.end - 1);
            let vertices = groom.strand_range(first).start..groom.strand_range(last).end;
            let (from, to) = (vertices.start as u32, *out.strand_offsets.last().expect("starts with 0"));
            if placed.is_none() {
                out.points.extend_from_slice(&groom.points[vertices.clone()]);
                out.widths.extend_from_slice(&groom.widths[vertices]);
            }
            out.strand_offsets
                .extend(groom.strand_offsets[first + 1..=run.end].iter().map(|&o| o - from + to));
            match groom.strand_ids.get(run.clone()) {
                Some(ids) => out.strand_ids.extend_from_slice(ids),
                None => out
                    .strand_ids
                    .extend(run.clone().map(|s| groom.strand_ids.get(s).copied().unwrap_or(s as u32))),
            }
            out.group_ids.extend(std::iter::repeat_n(map[groom.group_of(first)], run.len()));
        }
        for &s in strands.iter() {
            if any_uvs {
                uvs.push(groom.root_uvs.as_ref().map_or([0.0; 2], |u| u[s]));
                let group = groom.group_of(s);
                if groom.root_uvs.is_some() && groom.group(group).carries(CurveGroup::ROOT_UVS) {
                    carries_uvs[map[group] as usize] = true;
                }
            }
            if any_guides {
                guides.push(groom.guides.as_ref().is_some_and(|g| g[s]));
            }
        }
    }
    out.root_uvs = any_uvs.then_some(uvs);
    out.guides = any_guides.then_some(guides);
    if any_uvs {
        for (group, carried) in out.groups.iter_mut().zip(carries_uvs) {
            if !carried {
                group.missing.push(CurveGroup::ROOT_UVS.to_string());
            }
        }
    }
    if let Some(placed) = placed {
        out.points = placed.points;
        out.widths = placed.widths;
    }

    let mut names: Vec<&str> =
        parts.iter().flat_map(|(g, _)| g.attributes.iter().map(|a| a.name.as_str())).collect();
    names.sort_unstable();
    names.dedup();
    for name in names {
        let found: Vec<&Attribute> = parts.iter().filter_map(|(g, _)| g.attribute(name)).collect();
        let (kind, alike) = one_kind(name, &found)?;
        let components = found[0].components;
        if let Some(other) = found.iter().find(|a| a.components != components) {
            return Err(GroomError::AttributeComponents {
                name: name.to_string(),
                components: other.components,
            });
        }
        let rate = if found.iter().all(|a| a.rate == AttributeRate::Strand) {
            AttributeRate::Strand
        } else {
            AttributeRate::Vertex
        };
        let per_element = match rate {
            AttributeRate::Strand => strand_total,
            AttributeRate::Vertex => vertex_total,
        };
        let mut data = alike[0].data.empty_like(per_element * components);
        let mut carried = vec![false; out.groups.len()];
        let mut alike = alike.into_iter();
        for ((groom, strands), map) in parts.iter().zip(&group_maps) {
            let attribute =
                groom.attribute(name).map(|_| alike.next().expect("one for each part that has it"));
            let attribute = attribute.as_deref();
            for run in runs(groom, strands) {
                let group_index = groom.group_of(run.start);
                let vertices = groom.strand_range(run.start).start..groom.strand_range(run.end - 1).end;
                let count = match rate {
                    AttributeRate::Strand => run.len(),
                    AttributeRate::Vertex => vertices.len(),
                };
                match attribute {
                    Some(a) if groom.group(group_index).carries(name) => {
                        carried[map[group_index] as usize] = true;
                        match (a.rate, rate) {
                            (AttributeRate::Strand, AttributeRate::Strand) => {
                                data.extend_from(&a.data, run.start * components..run.end * components, 1)
                            }
                            (AttributeRate::Strand, AttributeRate::Vertex) => {
                                // Writers give it back one per curve while the values allow.
                                let group = &mut out.groups[map[group_index] as usize];
                                if group.interpolation(name).is_none() {
                                    group.interpolations.push((name.to_string(), Interpolation::Uniform));
                                }
                                for s in run {
                                    let value = s * components..(s + 1) * components;
                                    data.extend_from(&a.data, value, groom.strand_range(s).len());
                                }
                            }
                            (AttributeRate::Vertex, _) => data.extend_from(
                                &a.data,
                                vertices.start * components..vertices.end * components,
                                1,
                            ),
                        }
                    }
                    _ => data.extend_zeros(count * components),
                }
            }
        }
        for (group, carried) in out.groups.iter_mut().zip(carried) {
            if !carried {
                group.missing.push(name.to_string());
            }
        }
        out.attributes.push(Attribute { name: name.to_string(), rate, components, data, kind });
    }
    if let Some(first) = out.groups.first() {
        out.basis = first.basis;
    }
    out.drop_default_group("");
    // Groups no strand uses (a selection) stay, so group ids keep their meaning.
    Ok(out)
}

/// One attribute's parts (of several grooms) in one number type, and its kind: the first part's
/// when all are floats or all share it; integers of several kinds in the narrowest kind that
/// holds them all; else floats, refused when an integer has no exact float (an id past 2^24
/// beside a float part).
#[allow(clippy::type_complexity)]
fn one_kind<'a>(
    name: &str,
    found: &[&'a Attribute],
) -> Result<(AttributeKind, Vec<Cow<'a, Attribute>>), GroomError> {
    let first = found[0].kind;
    if found.iter().all(|a| a.kind == first || !(a.kind.is_integer() || first.is_integer())) {
        return Ok((first, found.iter().map(|&a| Cow::Borrowed(a)).collect()));
    }
    let bad = |problem: String| GroomError::BadAttribute { name: name.to_string(), problem };
    let values = |a: &'a Attribute| a.ints().unwrap_or(&[]).iter().map(move |&v| a.kind.integer(v));
    if found.iter().all(|a| a.kind.is_integer()) {
        let kinds: Vec<AttributeKind> = found.iter().map(|a| a.kind).collect();
        let kind = AttributeKind::widest_integer(&kinds, found.iter().flat_map(|&a| values(a)))
            .ok_or_else(|| bad("holds values no one integer type holds (past 2^63 and negative)".into()))?;
        let stored = |v: i128| if kind == AttributeKind::UInt64 { v as u64 as i64 } else { v as i64 };
        let alike = found.iter().map(|&a| {
            let data = values(a).map(stored).collect();
            Cow::Owned(Attribute::integers(a.name.clone(), a.rate, a.components, data, kind))
        });
        return Ok((kind, alike.collect()));
    }
    let kind = found.iter().map(|a| a.kind).find(|k| !k.is_integer()).unwrap_or_default();
    let alike = found
        .iter()
        .map(|&a| {
            if let Some(v) = values(a).find(|&v| v as f32 as i128 != v) {
                return Err(bad(format!(
                    "is integers in one curve prim or object and floats in another, and {v} has no exact float"
                )));
            }
            let data = AttributeData::Float(a.floats().into_owned());
            let (name, rate, components) = (a.name.clone(), a.rate, a.components);
            Ok(Cow::Owned(Attribute { name, rate, components, data, kind }))
        })
        .collect::<Result<_, _>>()?;
    Ok((kind, alike))
}

/// `strands` as runs of consecutive strands of one group, so that each run's data is copied as
/// one slice.
fn runs<'a>(groom: &'a Groom, strands: &'a [usize]) -> impl Iterator<Item = std::ops::Range<usize>> + 'a {
    let mut rest = strands;
    std::iter::from_fn(move || {
        let (&first, _) = rest.split_first()?;
        let group = groom.group_of(first);
        let length = 1 + rest
            .windows(2)
            .take_while(|pair| pair[1] == pair[0] + 1 && groom.group_of(pair[1]) == group)
            .count();
        rest = &rest[length..];
        Some(first..first + length)
    })
}

/// Checks the group table against the strands.
pub(crate) fn validate(groom: &Groom) -> Result<(), GroomError> {
    if groom.groups.is_empty() {
        if !groom.group_ids.is_empty() {
            return Err(GroomError::Length {
                what: "group ids".into(),
                expected: 0,
                found: groom.group_ids.len(),
            });
        }
        return Ok(());
    }
    if groom.group_ids.len() != groom.strand_count() {
        return Err(GroomError::Length {
            what: "group ids".into(),
            expected: groom.strand_count(),
            found: groom.group_ids.len(),
        });
    }
    if let Some(strand) = groom.group_ids.iter().position(|&g| g as usize >= groom.groups.len()) {
        return Err(GroomError::BadOffsets(format!(
            "strand {strand} names group {} but the groom has {}",
            groom.group_ids[strand],
            groom.groups.len()
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn prim(name: &str, basis: CurveBasis, strands: usize, with_rest: bool) -> Groom {
        let lines: Vec<Vec<Vec3>> =
            (0..strands).map(|s| (0..4).map(|i| Vec3::new(s as f32, i as f32, 0.0)).collect()).collect();
        let mut groom = Groom::from_strands(&lines, 1e-4);
        if with_rest {
            let data = groom.points.iter().flat_map(|p| p.to_array()).collect();
            groom.set_attribute(Attribute::new("rest", AttributeRate::Vertex, 3, data));
        }
        groom.set_single_group(CurveGroup::new(name, basis, CurveWrap::Pinned));
        groom
    }

    #[test]
    fn append_split_round_trip_keeps_groups_and_missing_attributes() {
        let guides = prim("/Groom/Guides", CurveBasis::CatmullRom, 2, true);
        let children = prim("/Groom/Hair", CurveBasis::Linear, 3, false);
        let groom = Groom::concat(vec![guides.clone(), children.clone()]).unwrap();
        groom.validate().unwrap();
        assert_eq!(groom.strand_count(), 5);
        assert_eq!(groom.group_ids, vec![0, 0, 1, 1, 1]);
        assert_eq!(groom.groups[1].missing, vec!["rest".to_string()]);
        let parts = groom.split_groups().unwrap();
        assert_eq!(parts.len(), 2);
        assert_eq!(*parts[0].2, guides);
        assert_eq!(*parts[1].2, children);
    }

    #[test]
    fn root_uvs_of_some_groups_are_missing_in_the_others() {
        let mut guides = prim("/Groom/Guides", CurveBasis::Linear, 2, false);
        guides.root_uvs = Some(vec![[0.25, 0.5], [0.75, 0.5]]);
        let children = prim("/Groom/Hair", CurveBasis::Linear, 3, false);
        let groom = Groom::concat(vec![guides.clone(), children.clone()]).unwrap();
        assert!(groom.groups[0].carries(CurveGroup::ROOT_UVS));
        assert!(!groom.groups[1].carries(CurveGroup::ROOT_UVS));
        let parts = groom.split_groups().unwrap();
        assert_eq!(
            (*parts[0].2 == guides, *parts[1].2 == children),
            (true, true),
            "split gives the parts back"
        );
        // Merged again (a selection put back), the children still have none.
        let again = Groom::concat(vec![(*parts[1].2).clone(), groom.clone()]).unwrap();
        assert!(!again.groups[again.group_ids[0] as usize].carries(CurveGroup::ROOT_UVS));
        assert!(again.groups[again.group_ids[3] as usize].carries(CurveGroup::ROOT_UVS));
    }

    #[test]
    fn concat_names_the_first_part_that_does_not_fit() {
        let mut third = prim("/C", CurveBasis::Linear, 2, false);
        let rest_as_scalars = vec![0.0; third.vertex_count()];
        third.set_attribute(Attribute::new("rest", AttributeRate::Vertex, 1, rest_as_scalars));
        let parts = vec![
            prim("/A", CurveBasis::CatmullRom, 2, true),
            prim("/B", CurveBasis::Linear, 3, false),
            third,
        ];
        match Groom::concat(parts) {
            Err((2, GroomError::AttributeComponents { name, components: 1 })) => assert_eq!(name, "rest"),
            other => panic!("expected part 2's 'rest' to be refused, got {other:?}"),
        }
        let whole = Groom::concat(vec![
            prim("/A", CurveBasis::CatmullRom, 2, true),
            prim("/B", CurveBasis::Linear, 3, false),
            prim("/A", CurveBasis::CatmullRom, 1, true),
        ])
        .unwrap();
        whole.validate().unwrap();
        assert_eq!(whole.group_ids, vec![0, 0, 1, 1, 1, 0], "equal groups are one group");
    }

    #[test]
    fn selection_merges_back_in_place() {
        let groom = Groom::concat(vec![
            prim("/A", CurveBasis::Linear, 2, false),
            prim("/B", CurveBasis::BSpline, 2, false),
        ])
        .unwrap();
        let (mut selected, selection) = groom.select_groups(&["B".into()]).unwrap();
        assert_eq!(selection.strands, vec![2, 3]);
        selected.points.iter_mut().for_each(|p| p.z += 1.0);
        selected.set_attribute(Attribute::new("wetness", AttributeRate::Strand, 1, vec![1.0, 1.0]));
        let merged = groom.merge_back(&selection, &selected).unwrap();
        merged.validate().unwrap();
        assert_eq!(merged.strand_points(0), groom.strand_points(0), "group A untouched");
        assert_eq!(merged.strand_points(2)[0].z, 1.0);
        assert_eq!(merged.groups[0].missing, vec!["wetness".to_string()]);
        assert!(groom.select_groups(&["C".into()]).unwrap_err().contains("'/A', '/B'"));
    }
}
