//! The head frame a recipe can be written in: the centre, up and front of the head a groom grows
//! on, and its size, fitted to the groom itself, so one recipe fits heads of any size, position
//! and up axis.
//!
//! Convention (README "Recipes that fit any head"):
//! - **centre and size**: the sphere that best fits the scalp — the triangles of the scalp mesh
//!   near the roots when there is a mesh, else the roots themselves (least squares). One head
//!   unit is that sphere's radius (≈ 0.1 m on coif's own head).
//! - **up**: against the direction the tips hang (the mean direction from two thirds along each
//!   strand to its tip: hair hangs under gravity, and a curl's turns cancel); when the tips do not point clearly one way (short or
//!   radial hair), the mean direction from the centre to the roots (the crown).
//! - **front**: away from where the roots reach lowest — the hairline is higher on the forehead
//!   than on the nape, so the lowest quarter of the roots lies behind the head. When it does not lean
//!   (hair all around), the world's +Z, or −Y when up is near ±Z (Blender's front view).
//! - The third axis is `up × front` (+X on coif's head). Head coordinates `[x, y, z]` are along
//!   (`up × front`, up, front), in head units, from the centre.
//!
//! A recipe's `[head]` table overrides any of these.
use glam::{Quat, Vec3};

use crate::groom::Groom;
use crate::interact::mesh_sdf::TriangleMesh;

/// Why no head frame fits: the groom (its roots or tips), or the scalp mesh it was given, which
/// has no curved surface near the roots.
#[derive(Clone, Debug, PartialEq)]
pub enum FitError {
    Groom(String),
    Scalp,
}

impl From<String> for FitError {
    fn from(reason: String) -> Self {
        FitError::Groom(reason)
    }
}

impl From<&str> for FitError {
    fn from(reason: &str) -> Self {
        FitError::Groom(reason.to_owned())
    }
}

impl std::fmt::Display for FitError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FitError::Groom(reason) => f.write_str(reason),
            FitError::Scalp => f.write_str("the scalp mesh has no curved surface near the groom's roots"),
        }
    }
}

/// A fitted head frame. Its axes are orthonormal and its size positive (checked on creation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HeadFrame {
    center: Vec3,
    up: Vec3,
    front: Vec3,
    size: f32,
    /// The ellipsoid fitted to the roots of the groom the frame was fitted to (head
    /// coordinates; a sphere of the frame's size clear of its strands when they do not determine
    /// one), so that a run styling some of the strands (the guides) collides with the
    /// head the whole groom grows on.
    roots_head: Option<Ellipsoid>,
}

/// Values a recipe sets instead of fitting them (world coordinates, metres).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameOverrides {
    pub center: Option<Vec3>,
    pub up: Option<Vec3>,
    pub front: Option<Vec3>,
    pub size: Option<f32>,
}

/// The sine of the angle under which a front is parallel to up: its part across up would be
/// f32 rounding, pointing anywhere (up [1, 1, 0] and front [2, 2, 0] made a front opposite up).
const PARALLEL: f32 = 1e-3;

/// `front` made perpendicular to `up`, unit length; `None` when they are parallel (within
/// [`PARALLEL`]), or either is zero or not finite.
pub fn front_across(up: Vec3, front: Vec3) -> Option<Vec3> {
    let up = up.try_normalize()?;
    let across = front - up * front.dot(up);
    if across.length() >= PARALLEL * front.length() {
        across.try_normalize()
    } else {
        None
    }
}

impl HeadFrame {
    /// A frame from a centre, an up and a front direction (made perpendicular to up) and a size.
    pub fn new(center: Vec3, up: Vec3, front: Vec3, size: f32) -> Result<HeadFrame, String> {
        let up = up.try_normalize().ok_or("the head's up direction is zero")?;
        let front =
            front_across(up, front).ok_or("the head's front direction is parallel to its up direction")?;
        if !(center.is_finite() && size.is_finite() && size > 0.0) {
            return Err(format!("a head frame needs a finite centre and a positive size, not {size}"));
        }
        Ok(HeadFrame { center, up, front, size, roots_head: None })
    }

    pub fn center(&self) -> Vec3 {
        self.center
    }

    pub fn up(&self) -> Vec3 {
        self.up
    }

    pub fn front(&self) -> Vec3 {
        self.front
    }

    /// The third axis, `up × front`.
    pub fn side(&self) -> Vec3 {
        self.up.cross(self.front)
    }

    /// Metres per head unit.
    pub fn size(&self) -> f32 {
        self.size
    }

    /// The rotation taking coif's head axes (X side, Y up, Z front) to this frame's.
    pub fn rotation(&self) -> Quat {
        Quat::from_mat3(&glam::Mat3::from_cols(self.side(), self.up, self.front))
    }

    /// A point given in head coordinates, in the world.
    pub fn point(&self, head: Vec3) -> Vec3 {
        self.center + self.direction(head) * self.size
    }

    /// A direction given along the head axes, in the world (not scaled).
    pub fn direction(&self, head: Vec3) -> Vec3 {
        self.side() * head.x + self.up * head.y + self.front * head.z
    }

    /// A world point in head coordinates.
    pub fn to_head(&self, world: Vec3) -> Vec3 {
        let d = (world - self.center) / self.size;
        Vec3::new(d.dot(self.side()), d.dot(self.up), d.dot(self.front))
    }

    /// Fits the frame to a groom's roots and tips, and to its scalp mesh when there is one.
    pub fn fit(
        groom: &Groom,
        scalp: Option<&TriangleMesh>,
        overrides: &FrameOverrides,
    ) -> Result<HeadFrame, FitError> {
        let strands = groom.strand_count();
        let roots: Vec<Vec3> = (0..strands).map(|s| groom.points[groom.strand_range(s).start]).collect();
        // Where the tips point: hair hangs there under gravity, whatever the head's tilt.
        let hang: Vec3 = (0..strands)
            .map(|s| {
                let range = groom.strand_range(s);
                let tail = range.start + (range.len() * 2 / 3).min(range.len() - 2);
                (groom.points[range.end - 1] - groom.points[tail]).normalize_or_zero()
            })
            .sum::<Vec3>()
            / strands.max(1) as f32;

        let fitted_sphere = || -> Result<(Vec3, f32), FitError> {
            let from_roots = fit_sphere(roots.iter().map(|&p| (p, 1.0))).ok_or_else(|| {
                format!("cannot fit a head to the groom's {strands} roots: they do not span a curved scalp")
            })?;
            let Some(mesh) = scalp else { return Ok(from_roots) };
            // Only the part of the mesh the hair grows on: a full head's face and neck would pull
            // the sphere away from the scalp the recipe is written against.
            let near = NearRoots::new(&roots, 0.25 * from_roots.1);
            fit_sphere(mesh.area_samples().filter(|&(c, _)| near.contains(c))).ok_or(FitError::Scalp)
        };
        let (center, size) = match (overrides.center, overrides.size) {
            (Some(c), Some(s)) => (c, s),
            (c, s) => {
                let (fc, fs) = fitted_sphere()?;
                (c.unwrap_or(fc), s.unwrap_or(fs))
            }
        };
        let crown: Vec3 =
            roots.iter().map(|&r| (r - center).normalize_or_zero()).sum::<Vec3>() / strands as f32;
        let up = overrides.up.unwrap_or(if hang.length() > 0.5 { -hang } else { crown });
        let up = up.try_normalize().ok_or("cannot tell the head's up direction from the groom")?;
        let front = overrides.front.unwrap_or_else(|| {
            // The lowest quarter of the roots: the nape, behind the head.
            let mut heights: Vec<f32> = roots.iter().map(|&r| (r - center).dot(up)).collect();
            heights.sort_by(f32::total_cmp);
            let low = heights[heights.len() / 4];
            let nape: Vec3 = roots
                .iter()
                .filter(|&&r| (r - center).dot(up) <= low)
                .map(|&r| (r - center).normalize_or_zero())
                .sum::<Vec3>()
                / (heights.len() / 4 + 1) as f32;
            let lean = nape - up * nape.dot(up);
            if lean.length() > 0.1 {
                -lean
            } else if up.z.abs() > 0.9 {
                Vec3::NEG_Y
            } else {
                Vec3::Z
            }
        });
        let mut frame = HeadFrame::new(center, up, front, size)?;
        // Roots that determine no ellipsoid (a handful of strands) leave the fitted sphere, a
        // guess: the strands, not only their roots, say where the head is not (a sphere through
        // five roots held the hair hanging at its sides 9 mm inside it before any stage ran). A
        // fitted ellipsoid is the head, though: hair a DCC tool left under it is pushed out.
        let head = frame
            .fit_ellipsoid(&roots)
            .unwrap_or_else(|| frame.clear_of(Ellipsoid::UNIT_SPHERE, &groom.points, 0.75));
        frame.roots_head = Some(head);
        Ok(frame)
    }

    /// The head as an ellipsoid in head coordinates: the one fitted to the whole groom's roots
    /// with the frame, else (a frame made with [`HeadFrame::new`]) the one fitted to `roots`.
    pub fn head_ellipsoid(&self, roots: &[Vec3]) -> Option<Ellipsoid> {
        self.roots_head.or_else(|| self.fit_ellipsoid(roots))
    }

    /// The ellipsoid that best fits `points` (the roots), in head coordinates, shrunk (by at most
    /// 10 %) so that no point lies inside it: a general quadric when the points determine a
    /// head-like ellipsoid (they do on an ellipsoidal scalp, whatever its tilt), else one along
    /// the frame's axes.
    pub fn fit_ellipsoid(&self, points: &[Vec3]) -> Option<Ellipsoid> {
        let local: Vec<Vec3> = points.iter().map(|&p| self.to_head(p)).collect();
        let head_like = |e: &Ellipsoid| {
            e.center.length() < 1.0 && e.radii.min_element() > 0.3 && e.radii.max_element() < 3.0
        };
        let fitted = fit_quadric(&local).filter(head_like).or_else(|| fit_aligned(&local))?;
        Some(self.clear_of(fitted, points, 0.9))
    }

    /// `head` (head coordinates) shrunk about its centre so that no point of `points` (world)
    /// lies inside it, to no less than `smallest` of its size (a stray point near the centre
    /// must not make the head vanish).
    fn clear_of(&self, head: Ellipsoid, points: &[Vec3], smallest: f32) -> Ellipsoid {
        let innermost =
            points.iter().map(|&p| head.implicit(self.to_head(p)).sqrt()).fold(f32::INFINITY, f32::min);
        Ellipsoid { radii: head.radii * innermost.clamp(smallest, 1.0), ..head }
    }
}

/// An ellipsoid: semi-axes `radii` along the axes turned by `rotation`, around `center`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ellipsoid {
    pub center: Vec3,
    pub radii: Vec3,
    pub rotation: Quat,
}

impl Ellipsoid {
    /// The sphere of one head unit about the centre: the head when nothing else fits.
    pub const UNIT_SPHERE: Ellipsoid =
        Ellipsoid { center: Vec3::ZERO, radii: Vec3::ONE, rotation: Quat::IDENTITY };

    /// < 1 inside, 1 on the surface, > 1 outside.
    pub fn implicit(&self, p: Vec3) -> f32 {
        ((self.rotation.inverse() * (p - self.center)) / self.radii).length_squared()
    }
}

/// `pᵀAp + b·p = 1` by least squares (the origin inside), as an ellipsoid when it is one.
fn fit_quadric(points: &[Vec3]) -> Option<Ellipsoid> {
    let rows = points.iter().map(|p| {
        let row = [
            p.x * p.x,
            p.y * p.y,
            p.z * p.z,
            2.0 * p.x * p.y,
            2.0 * p.x * p.z,
            2.0 * p.y * p.z,
            p.x,
            p.y,
            p.z,
        ]
        .map(f64::from);
        (row, 1.0, 1.0)
    });
    let k = least_squares::<9>(rows)?;
    let a = glam::DMat3::from_cols_array(&[k[0], k[3], k[4], k[3], k[1], k[5], k[4], k[5], k[2]]);
    let b = glam::DVec3::new(k[6], k[7], k[8]);
    if a.determinant().abs() < 1e-12 {
        return None;
    }
    let center = -0.5 * (a.inverse() * b);
    let scale = 1.0 + center.dot(a * center);
    let (values, vectors) = symmetric_eigen(a / scale);
    if values.iter().any(|&v| v.is_nan() || v <= 0.0) {
        return None;
    }
    let mut axes = vectors;
    if axes.determinant() < 0.0 {
        axes.z_axis = -axes.z_axis;
    }
    let radii = Vec3::new(values[0] as f32, values[1] as f32, values[2] as f32).map(|v| 1.0 / v.sqrt());
    let rotation = Quat::from_mat3(&axes.as_mat3()).normalize();
    Some(Ellipsoid { center: center.as_vec3(), radii, rotation })
        .filter(|e| e.center.is_finite() && e.radii.is_finite())
}

/// `a·x² + b·y² + c·z² + d·x + e·y + f·z = 1` by least squares: an ellipsoid along the axes.
fn fit_aligned(points: &[Vec3]) -> Option<Ellipsoid> {
    let rows =
        points.iter().map(|p| ([p.x * p.x, p.y * p.y, p.z * p.z, p.x, p.y, p.z].map(f64::from), 1.0, 1.0));
    let k = least_squares::<6>(rows)?;
    if k[..3].iter().any(|&q| q <= 0.0) {
        return None;
    }
    let centre = [0, 1, 2].map(|i| -k[i + 3] / (2.0 * k[i]));
    let g = 1.0 + (0..3).map(|i| k[i + 3] * k[i + 3] / (4.0 * k[i])).sum::<f64>();
    let center = Vec3::new(centre[0] as f32, centre[1] as f32, centre[2] as f32);
    let radii = Vec3::new(k[0] as f32, k[1] as f32, k[2] as f32).map(|q| (g as f32 / q).sqrt());
    (center.is_finite() && radii.is_finite()).then_some(Ellipsoid { center, radii, rotation: Quat::IDENTITY })
}

/// Eigenvalues and eigenvectors (columns) of a symmetric 3×3 matrix, by cyclic Jacobi rotations.
fn symmetric_eigen(m: glam::DMat3) -> ([f64; 3], glam::DMat3) {
    let mut a = [m.x_axis.to_array(), m.y_axis.to_array(), m.z_axis.to_array()];
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..50 {
        let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        let diagonal = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
        if off <= 1e-30 * diagonal {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q] == 0.0 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in a.iter_mut() {
                let (kp, kq) = (row[p], row[q]);
                (row[p], row[q]) = (c * kp - s * kq, s * kp + c * kq);
            }
            let (row_p, row_q) = (a[p], a[q]);
            for (k, (&pk, &qk)) in row_p.iter().zip(&row_q).enumerate() {
                (a[p][k], a[q][k]) = (c * pk - s * qk, s * pk + c * qk);
            }
            for row in v.iter_mut() {
                let (kp, kq) = (row[p], row[q]);
                (row[p], row[q]) = (c * kp - s * kq, s * kp + c * kq);
            }
        }
    }
    // `v` holds the eigenvectors as columns, stored row by row.
    let vectors = glam::DMat3::from_cols_array_2d(&v).transpose();
    ([a[0][0], a[1][1], a[2][2]], vectors)
}

/// The least-squares sphere through weighted points: `|p|² = 2c·p + k` is linear in `c` and `k`.
fn fit_sphere(points: impl Iterator<Item = (Vec3, f32)>) -> Option<(Vec3, f32)> {
    let points: Vec<(Vec3, f32)> = points.collect();
    let weight: f32 = points.iter().map(|p| p.1).sum();
    if points.len() < 4 || weight <= 0.0 {
        return None;
    }
    // Relative to the weighted mean, for conditioning.
    let mean = points.iter().map(|&(p, w)| p * w).sum::<Vec3>() / weight;
    let rows = points.iter().map(|&(p, w)| {
        let q = (p - mean).as_dvec3();
        ([2.0 * q.x, 2.0 * q.y, 2.0 * q.z, 1.0], q.length_squared(), f64::from(w))
    });
    let [cx, cy, cz, k] = least_squares::<4>(rows)?;
    let radius = (k + cx * cx + cy * cy + cz * cz).sqrt() as f32;
    let center = mean + Vec3::new(cx as f32, cy as f32, cz as f32);
    (radius.is_finite() && radius > 0.0 && center.is_finite()).then_some((center, radius))
}

/// Solves weighted least squares `Σ w (row·x − b)²` through the normal equations (Gaussian
/// elimination with partial pivoting); `None` when the rows do not determine `x`.
fn least_squares<const N: usize>(rows: impl Iterator<Item = ([f64; N], f64, f64)>) -> Option<[f64; N]> {
    let mut a = [[0.0f64; N]; N];
    let mut b = [0.0f64; N];
    for (row, rhs, w) in rows {
        for i in 0..N {
            for j in 0..N {
                a[i][j] += w * row[i] * row[j];
            }
            b[i] += w * row[i] * rhs;
        }
    }
    let scale = (0..N).map(|i| a[i][i].abs()).fold(0.0, f64::max);
    for col in 0..N {
        let pivot = (col..N).max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))?;
        if a[pivot][col].is_nan() || a[pivot][col].abs() <= 1e-12 * scale {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let pivot_row = a[col];
        for r in col + 1..N {
            let f = a[r][col] / pivot_row[col];
            for (x, &p) in a[r].iter_mut().zip(&pivot_row).skip(col) {
                *x -= f * p;
            }
            b[r] -= f * b[col];
        }
    }
    let mut x = [0.0f64; N];
    for i in (0..N).rev() {
        let s: f64 = (i + 1..N).map(|j| a[i][j] * x[j]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Whether a point lies within about one cell of some root (a hash of occupied cells).
struct NearRoots {
    cell: f32,
    cells: std::collections::HashSet<[i32; 3]>,
}

impl NearRoots {
    fn new(roots: &[Vec3], cell: f32) -> NearRoots {
        NearRoots { cell, cells: roots.iter().map(|&r| Self::key(r, cell)).collect() }
    }

    fn key(p: Vec3, cell: f32) -> [i32; 3] {
        let c = (p / cell).floor();
        [c.x as i32, c.y as i32, c.z as i32]
    }

    fn contains(&self, p: Vec3) -> bool {
        let [x, y, z] = Self::key(p, self.cell);
        (-1..=1).any(|i| (-1..=1).any(|j| (-1..=1).any(|k| self.cells.contains(&[x + i, y + j, z + k]))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::{generate, GenerateParams};
    use crate::head::Head;

    fn groom() -> Groom {
        generate(&GenerateParams { strands: 200, vertices_per_strand: 9, seed: 5, ..Default::default() })
            .unwrap()
    }

    /// Moves a groom rigidly and scales it.
    fn transformed(groom: &Groom, rotation: Quat, scale: f32, offset: Vec3) -> Groom {
        let mut out = groom.clone();
        out.points.iter_mut().for_each(|p| *p = rotation * (*p * scale) + offset);
        out
    }

    #[test]
    fn coif_head_frame_is_centred_upright_and_faces_plus_z() {
        let frame = HeadFrame::fit(&groom(), None, &FrameOverrides::default()).unwrap();
        eprintln!("{frame:?}");
        assert!(frame.up().dot(Vec3::Y) > 0.97, "up {:?}", frame.up());
        assert!(frame.front().dot(Vec3::Z) > 0.97, "front {:?}", frame.front());
        assert!(frame.center().length() < 0.02, "centre {:?}", frame.center());
        assert!((0.08..0.11).contains(&frame.size()), "size {}", frame.size());
    }

    #[test]
    fn the_frame_moves_scales_and_turns_with_the_groom() {
        let base = groom();
        let frame = HeadFrame::fit(&base, None, &FrameOverrides::default()).unwrap();
        // Z up (Y → Z), twice the size, moved.
        let rotation = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
        let offset = Vec3::new(0.3, -1.0, 2.0);
        let moved =
            HeadFrame::fit(&transformed(&base, rotation, 2.0, offset), None, &FrameOverrides::default())
                .unwrap();
        assert!(moved.up().abs_diff_eq(rotation * frame.up(), 1e-4), "{moved:?}");
        assert!(moved.front().abs_diff_eq(rotation * frame.front(), 1e-4));
        assert!(moved.center().abs_diff_eq(rotation * (frame.center() * 2.0) + offset, 1e-4));
        assert!((moved.size() - 2.0 * frame.size()).abs() < 1e-5);
        let p = Vec3::new(0.3, -1.2, 0.8);
        assert!(moved.point(p).abs_diff_eq(rotation * (frame.point(p) * 2.0) + offset, 1e-4));
        assert!(moved.to_head(moved.point(p)).abs_diff_eq(p, 1e-5));
    }

    #[test]
    fn a_scalp_mesh_fits_the_same_head_as_its_roots() {
        let base = groom();
        let head = Head::default();
        let (points, triangles) = crate::interact::mesh_sdf::uv_sphere(Vec3::ZERO, 1.0, 32, 64);
        let mesh =
            TriangleMesh { points: points.iter().map(|&p| head.surface_point(p)).collect(), triangles };
        let from_roots = HeadFrame::fit(&base, None, &FrameOverrides::default()).unwrap();
        let from_mesh = HeadFrame::fit(&base, Some(&mesh), &FrameOverrides::default()).unwrap();
        eprintln!("roots {from_roots:?}\nmesh {from_mesh:?}");
        assert!(from_mesh.center().distance(from_roots.center()) < 0.01);
        assert!((from_mesh.size() / from_roots.size() - 1.0).abs() < 0.05);
        // The analytic head is recovered by the ellipsoid fit to the roots, though the frame's
        // axes lean off the head's.
        let roots: Vec<Vec3> = (0..base.strand_count()).map(|s| base.strand_points(s)[0]).collect();
        let e = from_roots.fit_ellipsoid(&roots).unwrap();
        let (centre, radii) = (from_roots.point(e.center), e.radii * from_roots.size());
        let axes = from_roots.rotation() * e.rotation;
        eprintln!("ellipsoid centre {centre:?} radii {radii:?} axes {axes:?}");
        assert!(centre.length() < 1e-3, "{centre:?}");
        for (k, axis) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
            // The fitted semi-axis nearest to each of the head's axes has its length.
            let nearest = (0..3).max_by(|&i, &j| {
                let along = |n: usize| (axes * Vec3::AXES[n]).dot(axis).abs();
                along(i).total_cmp(&along(j))
            });
            let r = radii[nearest.unwrap()];
            assert!((r / head.radii[k] - 1.0).abs() < 0.01, "axis {k}: {r} vs {}", head.radii[k]);
        }
    }

    #[test]
    fn overrides_win_and_bad_frames_are_refused() {
        let overrides =
            FrameOverrides { up: Some(Vec3::Z), front: Some(Vec3::new(0.0, 1.0, 1.0)), ..Default::default() };
        let frame = HeadFrame::fit(&groom(), None, &overrides).unwrap();
        assert_eq!(frame.up(), Vec3::Z);
        assert!(frame.front().abs_diff_eq(Vec3::Y, 1e-6));
        assert!(HeadFrame::new(Vec3::ZERO, Vec3::Y, Vec3::Y, 1.0).is_err());
        assert!(HeadFrame::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::new(2.0, 2.0, 0.0), 1.0).is_err());
        assert!(HeadFrame::new(Vec3::ZERO, Vec3::Y, Vec3::Z, 0.0).is_err());
        let mut flat = groom();
        flat.points.iter_mut().for_each(|p| p.y = 0.0);
        assert!(HeadFrame::fit(&flat, None, &FrameOverrides::default()).is_err());
    }
}
