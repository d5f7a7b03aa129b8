//! A signed distance field baked from a closed triangle mesh (a scanned or modelled head), so a
//! mesh collides as cheaply as an analytic shape: one trilinear lookup per vertex.
//!
//! Distances are exact (to the nearest triangle) in a narrow band around the surface; the sign
//! comes from angle-weighted pseudo-normals (Bærentzen & Aanæs 2005), which is correct for any
//! closed, consistently oriented mesh. Beyond the band, outside holds +band (its sign carried
//! along grid lines from the band); inside holds the depth measured on from the band's exact
//! distances (a chamfer distance, at most about 8 % long), so the field points out of the mesh
//! from anywhere within it.
use std::collections::HashMap;

use glam::Vec3;

/// A triangle mesh in coif's space (metres, Y up): a scalp or head that hair collides with and
/// that a recipe's head frame is fitted to. Readers of groom files and of OBJ files produce it.
/// At most this many cell visits (triangle-to-cell distance tests) in one bake: a few minutes
/// at the worst; a 1,000,000-triangle head at 2 mm cells and an 8 mm band needs about 1.3e9.
pub const MAX_BAKE_VISITS: f64 = 2e9;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleMesh {
    pub points: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// Bakes the mesh's distance field (see [`MeshSdf::bake`]).
    pub fn bake(&self, cell: f32, band: f32) -> Result<MeshSdf, String> {
        MeshSdf::bake(&self.points, &self.triangles, cell, band)
    }

    /// Area-weighted samples of the surface: each triangle's centroid and area (triangles that
    /// name a missing vertex are skipped; [`Self::bake`] refuses them).
    pub fn area_samples(&self) -> impl Iterator<Item = (Vec3, f32)> + '_ {
        self.triangles.iter().filter_map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| self.points.get(v as usize).copied());
            let (a, b, c) = (a?, b?, c?);
            Some(((a + b + c) / 3.0, 0.5 * (b - a).cross(c - a).length()))
        })
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct MeshSdf {
    origin: Vec3,
    cell: f32,
    dims: [usize; 3],
    band: f32,
    values: Vec<f32>,
}

/// Which feature of a triangle a closest point lies on.
#[derive(Clone, Copy)]
enum Feature {
    Vertex(usize),
    Edge(usize),
    Face,
}

impl MeshSdf {
    /// Bakes the field on a grid of `cell`-sized cells covering the mesh plus `band`.
    pub fn bake(vertices: &[Vec3], triangles: &[[u32; 3]], cell: f32, band: f32) -> Result<MeshSdf, String> {
        if triangles.is_empty() {
            return Err("the mesh has no triangles".into());
        }
        if !(cell > 0.0 && band >= cell) {
            return Err(format!("cell {cell} must be positive and the band {band} at least one cell"));
        }
        if let Some(t) = triangles.iter().position(|t| t.iter().any(|&v| v as usize >= vertices.len())) {
            return Err(format!("triangle {t} names a vertex beyond the {} given", vertices.len()));
        }
        let (lo, hi) = vertices.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &v| (lo.min(v), hi.max(v)));
        let margin = Vec3::splat(band + cell);
        let origin = lo - margin;
        let extent = hi + margin - origin;
        // Counted in floats first: a huge extent or a tiny cell must not wrap the product.
        let cells = [0, 1, 2].map(|a| (extent[a] as f64 / cell as f64).ceil() + 1.0);
        if !cells.iter().all(|c| c.is_finite()) || cells.iter().product::<f64>() > (64 << 20) as f64 {
            return Err(format!(
                "a {:.0}×{:.0}×{:.0} grid is too large (at most {} cells); use larger cells",
                cells[0],
                cells[1],
                cells[2],
                64 << 20
            ));
        }
        let dims = cells.map(|c| c as usize);
        // The cells each triangle's banded box covers, clamped to the grid (inclusive).
        let cell_box = |[a, b, c]: [Vec3; 3]| {
            let lo = ((a.min(b).min(c) - Vec3::splat(band) - origin) / cell).floor().max(Vec3::ZERO);
            let hi = ((a.max(b).max(c) + Vec3::splat(band) - origin) / cell).ceil();
            let hi = [0, 1, 2].map(|a| (hi[a] as usize).min(dims[a] - 1));
            ([lo.x as usize, lo.y as usize, lo.z as usize], hi)
        };
        // The grid's size alone does not bound the work: many large triangles each visit most
        // of it. Count the visits first (cheap) and refuse a bake that would run for hours.
        let visits: f64 = triangles
            .iter()
            .map(|tri| {
                let (lo, hi) = cell_box(tri.map(|v| vertices[v as usize]));
                (0..3).map(|a| (hi[a] + 1).saturating_sub(lo[a]) as f64).product::<f64>()
            })
            .sum();
        if visits > MAX_BAKE_VISITS {
            return Err(format!(
                "baking would visit {visits:.3e} cells (at most {MAX_BAKE_VISITS:.0e}): the triangles \
                 are too large for cells of {cell} m; use larger cells or a smaller band"
            ));
        }
        let normals = PseudoNormals::new(vertices, triangles);

        let count = dims[0] * dims[1] * dims[2];
        let mut unsigned = vec![f32::INFINITY; count];
        let mut sign = vec![0i8; count];
        for (t, tri) in triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|v| vertices[v as usize]);
            let (lo, hi) = cell_box([a, b, c]);
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    for x in lo[0]..=hi[0] {
                        let p = origin + Vec3::new(x as f32, y as f32, z as f32) * cell;
                        let (closest, feature) = closest_point_on_triangle(p, a, b, c);
                        let distance = p.distance(closest);
                        let index = x + dims[0] * (y + dims[1] * z);
                        if distance < unsigned[index] && distance <= band {
                            unsigned[index] = distance;
                            let n = normals.of(t, tri, feature);
                            sign[index] = if (p - closest).dot(n) < 0.0 { -1 } else { 1 };
                        }
                    }
                }
            }
        }

        // Beyond the band: carry the sign of the nearest banded cell along each x line.
        let mut values = vec![0.0; count];
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                let row = dims[0] * (y + dims[1] * z);
                let mut last_sign = 1i8;
                let mut pending = Vec::new();
                for x in 0..dims[0] {
                    let i = row + x;
                    if sign[i] == 0 {
                        pending.push(i);
                        continue;
                    }
                    // Cells between two banded cells: inside only if both neighbours say so.
                    let fill = if last_sign < 0 && sign[i] < 0 { -band } else { band };
                    pending.drain(..).for_each(|j| values[j] = fill);
                    last_sign = sign[i];
                    values[i] = sign[i] as f32 * unsigned[i];
                }
                pending.drain(..).for_each(|j| values[j] = band);
            }
        }
        deepen_interior(&mut values, &sign, dims, cell);
        Ok(MeshSdf { origin, cell, dims, band, values })
    }

    fn at(&self, x: usize, y: usize, z: usize) -> f32 {
        self.values[x + self.dims[0] * (y + self.dims[1] * z)]
    }

    /// Trilinearly interpolated signed distance; points outside the grid get the distance to the
    /// grid box plus the band.
    fn sample(&self, p: Vec3) -> f32 {
        let g = (p - self.origin) / self.cell;
        let max = Vec3::new(self.dims[0] as f32, self.dims[1] as f32, self.dims[2] as f32) - 1.0;
        let clamped = g.clamp(Vec3::ZERO, max - 1e-4);
        let outside = (g - clamped).length() * self.cell;
        let base = clamped.floor();
        let f = clamped - base;
        let (x, y, z) = (base.x as usize, base.y as usize, base.z as usize);
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let c00 = lerp(self.at(x, y, z), self.at(x + 1, y, z), f.x);
        let c10 = lerp(self.at(x, y + 1, z), self.at(x + 1, y + 1, z), f.x);
        let c01 = lerp(self.at(x, y, z + 1), self.at(x + 1, y, z + 1), f.x);
        let c11 = lerp(self.at(x, y + 1, z + 1), self.at(x + 1, y + 1, z + 1), f.x);
        let d = lerp(lerp(c00, c10, f.y), lerp(c01, c11, f.y), f.z);
        if outside > 0.0 {
            d.max(self.band) + outside
        } else {
            d
        }
    }

    /// Signed distance alone: one lookup, where [`Self::distance`]'s normal takes six more.
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        self.sample(p)
    }

    /// Signed distance and outward unit normal (the field's normalised gradient).
    pub fn distance(&self, p: Vec3) -> (f32, Vec3) {
        let h = 0.5 * self.cell;
        let gradient = Vec3::new(
            self.sample(p + Vec3::X * h) - self.sample(p - Vec3::X * h),
            self.sample(p + Vec3::Y * h) - self.sample(p - Vec3::Y * h),
            self.sample(p + Vec3::Z * h) - self.sample(p - Vec3::Z * h),
        );
        (self.sample(p), gradient.try_normalize().unwrap_or(Vec3::Y))
    }

    pub fn translated(&self, offset: Vec3) -> MeshSdf {
        MeshSdf { origin: self.origin + offset, ..self.clone() }
    }
}

/// Gives the cells inside the mesh beyond the band (`-band` so far) their depth: two chamfer
/// passes (neighbour steps of 1, √2 and √3 cells) carry the band's exact depths inwards. A
/// vertex put far inside at once — a winding pose that cuts through the head, a child chained
/// from its guides along segments longer than the band — is then pushed out the shortest way;
/// a flat field (no gradient) could not say where the surface is.
fn deepen_interior(values: &mut [f32], sign: &[i8], dims: [usize; 3], cell: f32) {
    let deep: Vec<bool> = values.iter().zip(sign).map(|(&v, &s)| s == 0 && v < 0.0).collect();
    let Some(first) = deep.iter().position(|&d| d) else { return };
    let last = deep.iter().rposition(|&d| d).expect("found above");
    // The 13 neighbours that come before a cell in the grid's order (x fastest), as index
    // offsets, and their distances. Deep cells lie inside the mesh, and the grid reaches a band
    // and a cell beyond it, so their neighbours are in the grid.
    let (row, slab) = (dims[0] as isize, (dims[0] * dims[1]) as isize);
    let mut before = Vec::with_capacity(13);
    for dz in -1isize..=1 {
        for dy in -1isize..=1 {
            for dx in -1isize..=1 {
                if (dz, dy, dx) < (0, 0, 0) {
                    let steps = (dx * dx + dy * dy + dz * dz) as f32;
                    before.push((dx + dy * row + dz * slab, cell * steps.sqrt()));
                }
            }
        }
    }
    // Depth inside (positive): exact in the band, unknown (infinite) in the deep cells.
    let mut depth: Vec<f32> =
        values.iter().zip(&deep).map(|(&v, &d)| if d { f32::INFINITY } else { -v }).collect();
    let relax = |depth: &mut [f32], i: usize, direction: isize| {
        let mut best = depth[i];
        for &(offset, length) in &before {
            let neighbour = (i as isize + direction * offset) as usize;
            // Outside cells (negative depth) carry no depth inwards.
            if let Some(&d) = depth.get(neighbour).filter(|d| **d >= 0.0) {
                best = best.min(d + length);
            }
        }
        depth[i] = best;
    };
    for i in (first..=last).filter(|&i| deep[i]) {
        relax(&mut depth, i, 1);
    }
    for i in (first..=last).rev().filter(|&i| deep[i]) {
        relax(&mut depth, i, -1);
    }
    for i in (first..=last).filter(|&i| deep[i] && depth[i].is_finite()) {
        values[i] = -depth[i];
    }
}

/// Angle-weighted vertex normals, edge normals (sum of the two faces) and face normals.
struct PseudoNormals {
    faces: Vec<Vec3>,
    vertices: Vec<Vec3>,
    edges: HashMap<(u32, u32), Vec3>,
}

impl PseudoNormals {
    fn new(vertices: &[Vec3], triangles: &[[u32; 3]]) -> Self {
        let mut faces = Vec::with_capacity(triangles.len());
        let mut vertex_normals = vec![Vec3::ZERO; vertices.len()];
        let mut edges: HashMap<(u32, u32), Vec3> = HashMap::new();
        for tri in triangles {
            let p = tri.map(|v| vertices[v as usize]);
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
            faces.push(n);
            for k in 0..3 {
                let (prev, next) = (p[(k + 2) % 3], p[(k + 1) % 3]);
                let angle = (prev - p[k]).angle_between(next - p[k]);
                if angle.is_finite() {
                    vertex_normals[tri[k] as usize] += angle * n;
                }
                let (i, j) = (tri[k], tri[(k + 1) % 3]);
                *edges.entry((i.min(j), i.max(j))).or_default() += n;
            }
        }
        PseudoNormals { faces, vertices: vertex_normals, edges }
    }

    fn of(&self, face: usize, tri: &[u32; 3], feature: Feature) -> Vec3 {
        match feature {
            Feature::Face => self.faces[face],
            Feature::Vertex(k) => self.vertices[tri[k] as usize],
            Feature::Edge(k) => {
                let (i, j) = (tri[k], tri[(k + 1) % 3]);
                self.edges[&(i.min(j), i.max(j))]
            }
        }
    }
}

/// Closest point on triangle `abc` to `p` and the feature it lies on (Ericson, RTCD §5.1.5).
/// Edge `k` runs from vertex `k` to vertex `k + 1`.
fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> (Vec3, Feature) {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(0));
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (a + ab * (d1 / (d1 - d3)), Feature::Edge(0));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (a + ac * (d2 / (d2 - d6)), Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))), Feature::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    (a + ab * (vb * denom) + ac * (vc * denom), Feature::Face)
}

/// A closed, outward-oriented UV sphere (for tests and as a stand-in head mesh).
pub fn uv_sphere(center: Vec3, radius: f32, rings: u32, segments: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut vertices = vec![center + Vec3::Y * radius];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            vertices.push(
                center + radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()),
            );
        }
    }
    vertices.push(center - Vec3::Y * radius);
    let bottom = vertices.len() as u32 - 1;
    let ring = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([0, ring(1, s + 1), ring(1, s)]);
        triangles.push([bottom, ring(rings - 1, s), ring(rings - 1, s + 1)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (ring(r, s), ring(r, s + 1), ring(r + 1, s), ring(r + 1, s + 1));
            triangles.push([a, b, d]);
            triangles.push([a, d, c]);
        }
    }
    (vertices, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Found by the obj_reader fuzz target: a grid within the cell cap that every one of many
    /// large triangles covers ran for hours; now it is refused at once with the figure.
    #[test]
    fn many_large_triangles_are_refused_before_baking() {
        let vertices =
            vec![Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 4.0, 0.0), Vec3::new(0.0, 0.0, 4.0)];
        let triangles = vec![[1, 2, 3]; 2000];
        // 2,000 × 8.7e6 cells: refused before any cell is touched (it used to run for hours).
        let error = MeshSdf::bake(&vertices, &triangles, 0.02, 0.04).unwrap_err();
        assert!(error.contains("visit") && error.contains("larger cells"), "{error}");
        // The same triangle once is an ordinary bake.
        assert!(MeshSdf::bake(&vertices, &triangles[..1], 0.05, 0.1).is_ok());
    }

    #[test]
    fn sphere_mesh_field_matches_the_analytic_sphere() {
        let (radius, cell) = (0.1, 0.004);
        let (vertices, triangles) = uv_sphere(Vec3::ZERO, radius, 48, 96);
        let sdf = MeshSdf::bake(&vertices, &triangles, cell, 0.02).unwrap();
        // Facets sit inside the true sphere by up to r(1 - cos(π/48)) ≈ 0.2 mm; trilinear
        // interpolation adds a fraction of a cell.
        for dir in [
            Vec3::X,
            Vec3::new(0.3, 0.9, -0.2).normalize(),
            Vec3::NEG_Y,
            Vec3::new(-1.0, 1.0, 1.0).normalize(),
        ] {
            for offset in [-0.012, -0.003, 0.0, 0.005, 0.015] {
                let (d, n) = sdf.distance(dir * (radius + offset));
                // Contacts reject clear vertices on the distance alone: it must be the same value.
                assert_eq!(sdf.signed_distance(dir * (radius + offset)), d);
                assert!((d - offset).abs() < 0.0015, "dir {dir:?} offset {offset}: {d}");
                assert!(n.dot(dir) > 0.98, "normal {n:?} vs {dir:?}");
            }
        }
        // Deeper inside than the band (0.02): the depth (chamfer distances run at most about
        // 8 % long) and a normal that points out.
        for dir in [Vec3::X, Vec3::new(0.3, 0.9, -0.2).normalize(), Vec3::new(-1.0, 1.0, 1.0).normalize()] {
            for depth in [0.03, 0.05, 0.08] {
                let (d, n) = sdf.distance(dir * (radius - depth));
                assert!(d < -0.98 * depth && d > -1.1 * depth, "dir {dir:?} depth {depth}: {d}");
                assert!(n.dot(dir) > 0.95, "dir {dir:?} depth {depth}: normal {n:?}");
            }
        }
        // At the centre: negative. Far outside: positive and growing.
        assert!(sdf.distance(Vec3::ZERO).0 < -0.09);
        assert!(sdf.distance(Vec3::new(0.5, 0.0, 0.0)).0 > 0.3);
    }

    #[test]
    fn bad_meshes_are_refused_with_a_reason() {
        assert!(MeshSdf::bake(&[Vec3::ZERO], &[], 0.01, 0.02).is_err());
        assert!(MeshSdf::bake(&[Vec3::ZERO, Vec3::X, Vec3::Y], &[[0, 1, 3]], 0.01, 0.02)
            .unwrap_err()
            .contains("triangle 0"));
    }
}
