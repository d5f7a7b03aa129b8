//! Polygon meshes that travel with a groom: the scalp, head or body a DCC exports beside the
//! curves (USD `Mesh` prims, Alembic `PolyMesh` objects). Readers bring them into coif's space
//! (metres, Y up) with the curves; styling uses the one the roots sit on as the groom's own
//! scalp ([`scalp_of`]), and writers that can carry meshes give them back at their paths.
use glam::{DMat4, Vec3};

use crate::groom::{AttributeData, AttributeKind, Groom};
use crate::interact::mesh_sdf::TriangleMesh;

/// A polygon mesh as the file holds it: faces of any vertex count, wound counter-clockwise seen
/// from outside (USD's right-handed default; readers convert other conventions).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceMesh {
    /// The prim path or object path it came from (`/root/Head/HeadMesh`).
    pub path: String,
    pub points: Vec<Vec3>,
    /// Vertices per face (each at least 3).
    pub face_counts: Vec<u32>,
    /// Every face's vertex indices, concatenated.
    pub face_indices: Vec<u32>,
    /// The mesh's own data (UVs, normals, rest positions, masks), passed through conversions.
    pub primvars: Vec<MeshPrimvar>,
    /// Hidden in its file (USD `visibility = "invisible"` on it or an ancestor, Alembic
    /// `visible = 0`), as scalp and head meshes often are: still a collider, written back hidden,
    /// left out of previews.
    pub invisible: bool,
    /// Faces the file made holes (USD `holeIndices`: faces not drawn). Kept and written back to
    /// USD, left out of previews; they still collide, as hidden meshes do.
    pub holes: Vec<u32>,
}

/// Where a mesh primvar's values sit (USD interpolation; Alembic `geoScope`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshInterpolation {
    /// One value for the mesh.
    Constant,
    /// One per face.
    Uniform,
    /// One per point, interpolated linearly (USD `varying`; Alembic `var`).
    Varying,
    /// One per point.
    Vertex,
    /// One per face corner, in face order (UVs, split normals).
    FaceVarying,
}

impl MeshInterpolation {
    pub const ALL: [MeshInterpolation; 5] = [
        MeshInterpolation::Constant,
        MeshInterpolation::Uniform,
        MeshInterpolation::Varying,
        MeshInterpolation::Vertex,
        MeshInterpolation::FaceVarying,
    ];

    /// USD's token.
    pub fn usd_name(self) -> &'static str {
        match self {
            MeshInterpolation::Constant => "constant",
            MeshInterpolation::Uniform => "uniform",
            MeshInterpolation::Varying => "varying",
            MeshInterpolation::Vertex => "vertex",
            MeshInterpolation::FaceVarying => "faceVarying",
        }
    }

    /// Alembic's `geoScope`.
    pub fn alembic_scope(self) -> &'static str {
        match self {
            MeshInterpolation::Constant => "con",
            MeshInterpolation::Uniform => "uni",
            MeshInterpolation::Varying => "var",
            MeshInterpolation::Vertex => "vtx",
            MeshInterpolation::FaceVarying => "fvr",
        }
    }

    pub fn from_usd(token: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|i| i.usd_name() == token)
    }

    pub fn from_alembic_scope(scope: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|i| i.alembic_scope() == scope)
    }

    /// How many values this interpolation needs on `mesh`.
    pub fn count(self, mesh: &SurfaceMesh) -> usize {
        match self {
            MeshInterpolation::Constant => 1,
            MeshInterpolation::Uniform => mesh.face_counts.len(),
            MeshInterpolation::Varying | MeshInterpolation::Vertex => mesh.points.len(),
            MeshInterpolation::FaceVarying => mesh.face_indices.len(),
        }
    }
}

/// One named piece of mesh data: `components` numbers per element (integers for an integer
/// kind, else floats, as groom attributes are), optionally indexed.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshPrimvar {
    /// The primvar's name (`st`, `rest_position`); `normals` for the mesh's normals.
    pub name: String,
    /// Its role: whether it moves with the points and which file type it takes.
    pub kind: AttributeKind,
    pub components: usize,
    pub interpolation: MeshInterpolation,
    pub values: AttributeData,
    /// Element `i` is `values[indices[i]]` when present.
    pub indices: Option<Vec<u32>>,
}

impl MeshPrimvar {
    /// The name the mesh's normals go by.
    pub const NORMALS: &'static str = "normals";
    /// The name of the mesh's main UV set (USD's convention; Alembic's `uv`).
    pub const UV: &'static str = "st";

    /// Number of elements (indices when indexed, else values).
    pub fn len(&self) -> usize {
        self.indices.as_ref().map_or(self.values.len() / self.components.max(1), Vec::len)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The values as numbers (see [`AttributeData::floats`]) expanded through the indices.
    pub fn expanded(&self) -> std::borrow::Cow<'_, [f32]> {
        let values = self.values.floats(self.kind);
        match &self.indices {
            None => values,
            Some(indices) => std::borrow::Cow::Owned(
                indices
                    .iter()
                    .flat_map(|&i| {
                        let at = i as usize * self.components;
                        values[at..at + self.components].iter().copied()
                    })
                    .collect(),
            ),
        }
    }

    /// Checks the counts against `mesh`: the first problem, in words naming the primvar.
    fn check(&self, mesh: &SurfaceMesh) -> Result<(), String> {
        let name = &self.name;
        if !(1..=4).contains(&self.components) || self.values.len() % self.components != 0 {
            return Err(format!(
                "primvar '{name}' has {} values of {} components",
                self.values.len(),
                self.components
            ));
        }
        let needed = self.interpolation.count(mesh);
        if self.len() != needed {
            return Err(format!(
                "primvar '{name}': {} interpolation needs {needed} values, found {}",
                self.interpolation.usd_name(),
                self.len()
            ));
        }
        let available = self.values.len() / self.components;
        let indices = self.indices.as_deref().unwrap_or_default();
        if !all_below(indices, available) {
            let i = indices.iter().position(|&i| i as usize >= available).expect("an index is out of range");
            return Err(format!(
                "primvar '{name}': index {i} is {}, but there are {available} values",
                indices[i]
            ));
        }
        let kind_fits = match &self.values {
            AttributeData::Int(values) => {
                self.kind.is_integer() && values.iter().all(|&v| self.kind.holds(self.kind.integer(v)))
            }
            AttributeData::Float(_) => !self.kind.is_integer(),
        };
        if !kind_fits {
            return Err(format!("primvar '{name}': values are not of its type ({:?})", self.kind));
        }
        if let AttributeData::Float(values) = &self.values {
            if !crate::groom::all_finite(values) {
                let i = values.iter().position(|v| !v.is_finite()).expect("a value is not finite");
                return Err(format!("primvar '{name}': value {i} is not finite ({})", values[i]));
            }
        }
        Ok(())
    }
}

impl SurfaceMesh {
    /// The primvar that is the mesh's main UV set (Alembic's `uv`): the one named
    /// [`MeshPrimvar::UV`], else the first pair of texture coordinates (a UV set keeps the name
    /// its file gave it, such as Blender's `UVMap`).
    pub fn main_uv(&self) -> Option<usize> {
        let uv_pair = |p: &MeshPrimvar| p.kind == AttributeKind::TexCoord && p.components == 2;
        self.primvars
            .iter()
            .position(|p| p.name == MeshPrimvar::UV)
            .or_else(|| self.primvars.iter().position(uv_pair))
    }

    /// Checks the topology against the points: the first problem, in words (readers prefix the
    /// file and prim).
    /// Every array is checked whole without a branch per element (a read mesh is checked on
    /// every import); only a failed check searches for the first fault.
    pub fn check(&self) -> Result<(), String> {
        if !crate::groom::all_finite(bytemuck::cast_slice(&self.points)) {
            let i = self.points.iter().position(|p| !p.is_finite()).expect("a point is not finite");
            return Err(format!("point {i} is not finite ({})", self.points[i]));
        }
        let (total, smallest) =
            self.face_counts.iter().fold((0u64, u32::MAX), |(sum, min), &c| (sum + c as u64, min.min(c)));
        if smallest < 3 {
            let face = self.face_counts.iter().position(|&c| c < 3).expect("a face is too small");
            return Err(format!(
                "face {face} has {} vertices; a face needs at least 3",
                self.face_counts[face]
            ));
        }
        if total != self.face_indices.len() as u64 {
            return Err(format!(
                "face vertex counts add up to {total} but there are {} face vertex indices",
                self.face_indices.len()
            ));
        }
        if !all_below(&self.face_indices, self.points.len()) {
            let i = self
                .face_indices
                .iter()
                .position(|&v| v as usize >= self.points.len())
                .expect("out of range");
            return Err(format!(
                "face vertex index {i} is {}, but the mesh has {} points",
                self.face_indices[i],
                self.points.len()
            ));
        }
        if let Some(i) = self.holes.iter().position(|&face| face as usize >= self.face_counts.len()) {
            return Err(format!(
                "hole index {i} is face {}, but the mesh has {} faces",
                self.holes[i],
                self.face_counts.len()
            ));
        }
        self.primvars.iter().try_for_each(|primvar| primvar.check(self))
    }

    /// Moves the mesh by `to` (a file's space to coif's, or a unit change): the points, and the
    /// primvars that are positions or directions as groom attributes move
    /// ([`crate::io::transform_values`]).
    pub fn transform(&mut self, to: DMat4) {
        if to == DMat4::IDENTITY {
            return;
        }
        self.points.iter_mut().for_each(|p| *p = to.transform_point3(p.as_dvec3()).as_vec3());
        for primvar in &mut self.primvars {
            if let AttributeData::Float(values) = &mut primvar.values {
                crate::io::transform_values(primvar.kind, &primvar.name, primvar.components, values, to);
            }
        }
    }

    /// The faces as triangle fans, in face order.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        self.triangles_of(|_| true)
    }

    /// The faces that are drawn (not [`holes`](Self::holes)) as triangle fans, in face order.
    pub fn shown_triangles(&self) -> Vec<[u32; 3]> {
        let mut hole = vec![false; self.face_counts.len()];
        for &face in &self.holes {
            if let Some(h) = hole.get_mut(face as usize) {
                *h = true;
            }
        }
        self.triangles_of(|face| !hole[face])
    }

    fn triangles_of(&self, keep: impl Fn(usize) -> bool) -> Vec<[u32; 3]> {
        let mut triangles = Vec::with_capacity(self.face_indices.len());
        let mut at = 0usize;
        for (index, &count) in self.face_counts.iter().enumerate() {
            let face = self.face_indices.get(at..at + count as usize).unwrap_or(&[]);
            if keep(index) {
                for k in 1..face.len().saturating_sub(1) {
                    triangles.push([face[0], face[k], face[k + 1]]);
                }
            }
            at += count as usize;
        }
        triangles
    }

    /// Reverses every face's winding (for files wound clockwise, as Alembic is), and with it the
    /// order of every face-varying primvar's corners.
    pub fn flip_winding(&mut self) {
        reverse_corners(&self.face_counts, &mut self.face_indices, 1);
        for primvar in &mut self.primvars {
            if primvar.interpolation != MeshInterpolation::FaceVarying
                || primvar.len() != self.face_indices.len()
            {
                continue; // `check` reports the mismatch
            }
            match &mut primvar.indices {
                Some(indices) => reverse_corners(&self.face_counts, indices, 1),
                None => match &mut primvar.values {
                    AttributeData::Float(values) => {
                        reverse_corners(&self.face_counts, values, primvar.components)
                    }
                    AttributeData::Int(values) => {
                        reverse_corners(&self.face_counts, values, primvar.components)
                    }
                },
            }
        }
    }

    /// The mesh as a collider: triangles oriented outwards. A closed mesh's winding decides
    /// inside from outside in the distance field, and files disagree on conventions, so the
    /// orientation is taken from the geometry (the signed volume), not trusted from the file.
    pub fn collider(&self) -> TriangleMesh {
        let mut triangles = self.triangles();
        let centre = self.points.iter().copied().sum::<Vec3>() / self.points.len().max(1) as f32;
        let volume: f32 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| self.points[v as usize] - centre);
                a.dot(b.cross(c))
            })
            .sum();
        if volume < 0.0 {
            triangles.iter_mut().for_each(|t| t.swap(1, 2));
        }
        TriangleMesh { points: self.points.clone(), triangles }
    }
}

/// Whether `name` is a plain identifier (letters, digits, `_`; not starting with a digit): a name
/// a USD primvar and Alembic metadata can both carry as it is.
pub fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Whether every index is below `len`: the largest one, found without a branch per index.
fn all_below(indices: &[u32], len: usize) -> bool {
    indices.is_empty() || (indices.iter().fold(0u32, |max, &i| max.max(i)) as usize) < len
}

/// Reverses the order of each face's corners in `values` (`components` per corner, faces of
/// `face_counts` corners in order), keeping each corner's components in order.
fn reverse_corners<T>(face_counts: &[u32], values: &mut [T], components: usize) {
    let mut at = 0usize;
    for &count in face_counts {
        let corners = count as usize;
        let face = &mut values[at * components..(at + corners) * components];
        face.reverse();
        face.chunks_exact_mut(components).for_each(<[T]>::reverse);
        at += corners;
    }
}

/// The groom's own scalp among its meshes: the one its roots lie closest to (median distance
/// from a spread of roots to the nearest face centre), as a collider. `None` without meshes.
pub fn scalp_of(groom: &Groom) -> Option<TriangleMesh> {
    let strands = groom.strand_count();
    let candidates: Vec<&SurfaceMesh> = groom.meshes.iter().filter(|m| !m.face_counts.is_empty()).collect();
    match candidates.as_slice() {
        [] => None,
        [only] => Some(only.collider()),
        _ if strands == 0 => Some(candidates[0].collider()),
        _ => {
            const SAMPLED_ROOTS: usize = 64;
            let step = strands.div_ceil(SAMPLED_ROOTS).max(1);
            let roots: Vec<Vec3> = (0..strands).step_by(step).map(|s| groom.strand_points(s)[0]).collect();
            let score = |mesh: &SurfaceMesh| {
                let collider = mesh.collider();
                let centres: Vec<Vec3> = collider.area_samples().map(|(c, _)| c).collect();
                let mut distances: Vec<f32> = roots
                    .iter()
                    .map(|r| centres.iter().map(|c| c.distance_squared(*r)).fold(f32::INFINITY, f32::min))
                    .collect();
                distances.sort_by(f32::total_cmp);
                distances[distances.len() / 2]
            };
            // Ties go to the first mesh in file order (deterministic).
            let best = candidates
                .iter()
                .map(|m| score(m))
                .enumerate()
                .fold((0, f32::INFINITY), |best, (i, s)| if s < best.1 { (i, s) } else { best })
                .0;
            Some(candidates[best].collider())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(scale: f32, offset: Vec3) -> SurfaceMesh {
        let points = (0..8)
            .map(|i| offset + scale * Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        // Outward, counter-clockwise quads.
        let faces = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        SurfaceMesh {
            path: "/cube".into(),
            points,
            face_counts: vec![4; 6],
            face_indices: faces.iter().flatten().copied().collect(),
            primvars: Vec::new(),
            invisible: false,
            holes: Vec::new(),
        }
    }

    fn signed_volume(mesh: &TriangleMesh) -> f32 {
        mesh.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| mesh.points[v as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn collider_is_outward_whatever_the_file_winding() {
        let mesh = cube(2.0, Vec3::ZERO);
        assert!((signed_volume(&mesh.collider()) - 8.0).abs() < 1e-4);
        let mut flipped = mesh.clone();
        flipped.flip_winding();
        assert_ne!(flipped.face_indices, mesh.face_indices);
        assert!((signed_volume(&flipped.collider()) - 8.0).abs() < 1e-4);
        assert_eq!(mesh.triangles().len(), 12);
    }

    #[test]
    fn check_names_the_problem() {
        let mut mesh = cube(1.0, Vec3::ZERO);
        assert_eq!(mesh.check(), Ok(()));
        mesh.face_indices[5] = 8;
        assert!(mesh.check().unwrap_err().contains("index 5 is 8"));
        let mut mesh = cube(1.0, Vec3::ZERO);
        mesh.points[3].y = f32::NAN;
        assert!(mesh.check().unwrap_err().contains("point 3"));
        let mut mesh = cube(1.0, Vec3::ZERO);
        mesh.face_counts[0] = 2;
        assert!(mesh.check().unwrap_err().contains("face 0"));
    }

    #[test]
    fn the_scalp_is_the_mesh_under_the_roots() {
        let mut groom =
            Groom::from_strands(&[vec![Vec3::new(0.5, 1.0, 0.5), Vec3::new(0.5, 1.5, 0.5)]], 1e-4);
        groom.meshes = vec![cube(1.0, Vec3::new(5.0, 0.0, 0.0)), cube(1.0, Vec3::ZERO)];
        let scalp = scalp_of(&groom).unwrap();
        assert_eq!(scalp.points[0], Vec3::ZERO);
        assert!(scalp_of(&Groom::default()).is_none());
    }
}
