//! Summary statistics of a groom, for `coif info` and for reports.
use serde::Serialize;

use crate::groom::{AttributeRate, CurveBasis, Groom};

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Stats {
    pub min: f32,
    pub mean: f32,
    pub median: f32,
    pub max: f32,
}

impl Stats {
    /// Statistics of a list of values; all zero for an empty list.
    pub fn of(mut values: Vec<f32>) -> Stats {
        if values.is_empty() {
            return Stats { min: 0.0, mean: 0.0, median: 0.0, max: 0.0 };
        }
        values.sort_by(f32::total_cmp);
        let n = values.len();
        let median = if n % 2 == 1 { values[n / 2] } else { 0.5 * (values[n / 2 - 1] + values[n / 2]) };
        // Sum in f64 so the mean of millions of values keeps its digits.
        let mean = (values.iter().map(|&v| v as f64).sum::<f64>() / n as f64) as f32;
        Stats { min: values[0], mean, median, max: values[n - 1] }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AttributeInfo {
    pub name: String,
    pub rate: AttributeRate,
    pub components: usize,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GroomInfo {
    pub strands: usize,
    pub vertices: usize,
    pub basis: CurveBasis,
    /// `[min, max]` corners of the axis-aligned bounding box, metres.
    pub bounds: Option<[[f32; 3]; 2]>,
    /// Strand arc lengths, metres.
    pub strand_length: Stats,
    pub vertices_per_strand: Stats,
    /// Per-vertex diameters, metres.
    pub width: Stats,
    pub root_uvs: bool,
    pub guides: usize,
    pub attributes: Vec<AttributeInfo>,
    /// Named curve groups (empty for a groom of one unnamed group).
    pub groups: Vec<GroupInfo>,
    /// Meshes the file brought beside the curves (scalp, head).
    pub meshes: Vec<MeshInfo>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeshInfo {
    pub path: String,
    pub points: usize,
    pub faces: usize,
    /// Hidden in its file.
    pub invisible: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GroupInfo {
    pub name: String,
    pub basis: CurveBasis,
    pub wrap: crate::groom::CurveWrap,
    pub strands: usize,
    /// USD `purpose`, when not `default` (`"guide"` for guide curves).
    pub purpose: Option<String>,
    /// The prim (or an ancestor) is invisible.
    pub invisible: bool,
}

impl GroomInfo {
    pub fn of(groom: &Groom) -> GroomInfo {
        GroomInfo {
            strands: groom.strand_count(),
            vertices: groom.vertex_count(),
            basis: groom.basis,
            bounds: groom.bounds().map(|(lo, hi)| [lo.to_array(), hi.to_array()]),
            strand_length: Stats::of((0..groom.strand_count()).map(|s| groom.strand_length(s)).collect()),
            vertices_per_strand: Stats::of(groom.vertex_counts().map(|c| c as f32).collect()),
            width: Stats::of(groom.widths.clone()),
            root_uvs: groom.root_uvs.is_some(),
            guides: groom.guides.as_ref().map_or(0, |g| g.iter().filter(|&&x| x).count()),
            attributes: groom
                .attributes
                .iter()
                .map(|a| AttributeInfo { name: a.name.clone(), rate: a.rate, components: a.components })
                .collect(),
            groups: groom
                .groups
                .iter()
                .enumerate()
                .map(|(g, group)| GroupInfo {
                    name: group.name.clone(),
                    basis: group.basis,
                    wrap: group.wrap,
                    strands: groom.group_ids.iter().filter(|&&id| id as usize == g).count(),
                    purpose: group.purpose.clone(),
                    invisible: group.invisible,
                })
                .collect(),
            meshes: groom
                .meshes
                .iter()
                .map(|m| MeshInfo {
                    path: m.path.clone(),
                    points: m.points.len(),
                    faces: m.face_counts.len(),
                    invisible: m.invisible,
                })
                .collect(),
        }
    }
}

impl std::fmt::Display for GroomInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "strands      {}", self.strands)?;
        writeln!(f, "vertices     {} ({:?} basis)", self.vertices, self.basis)?;
        if let Some([lo, hi]) = self.bounds {
            writeln!(
                f,
                "bounds       [{:.4}, {:.4}, {:.4}] .. [{:.4}, {:.4}, {:.4}] m",
                lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
            )?;
        }
        let s = &self.strand_length;
        writeln!(
            f,
            "length       min {:.4}  mean {:.4}  median {:.4}  max {:.4} m",
            s.min, s.mean, s.median, s.max
        )?;
        let v = &self.vertices_per_strand;
        writeln!(f, "vertices/strand  min {}  mean {:.2}  max {}", v.min, v.mean, v.max)?;
        let w = &self.width;
        writeln!(f, "width        min {:.2} µm  max {:.2} µm", w.min * 1e6, w.max * 1e6)?;
        writeln!(f, "root UVs     {}", if self.root_uvs { "yes" } else { "no" })?;
        if self.guides > 0 {
            writeln!(f, "guides       {}", self.guides)?;
        }
        for g in &self.groups {
            let purpose = g.purpose.as_ref().map(|p| format!(", purpose {p}")).unwrap_or_default();
            let invisible = if g.invisible { ", invisible" } else { "" };
            writeln!(
                f,
                "group        {} ({} strands, {:?} {:?}{purpose}{invisible})",
                g.name, g.strands, g.basis, g.wrap
            )?;
        }
        for m in &self.meshes {
            let invisible = if m.invisible { ", invisible" } else { "" };
            writeln!(f, "mesh         {} ({} points, {} faces{invisible})", m.path, m.points, m.faces)?;
        }
        for a in &self.attributes {
            writeln!(
                f,
                "attribute    {} ({:?}, {} component{})",
                a.name,
                a.rate,
                a.components,
                if a.components == 1 { "" } else { "s" }
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_of_odd_and_even_lists() {
        assert_eq!(Stats::of(vec![3.0, 1.0, 2.0]), Stats { min: 1.0, mean: 2.0, median: 2.0, max: 3.0 });
        assert_eq!(Stats::of(vec![4.0, 1.0, 2.0, 3.0]).median, 2.5);
    }
}
