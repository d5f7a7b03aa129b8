//! f64 3-vectors and 3×3 matrices over one value ([`f64`]) or one value per strand of a lane
//! group ([`F64x4`]), for the direct strand solve (`strand_solve`). Every operation does glam's
//! `DVec3`/`DMat3` arithmetic in glam's order, so a lane computes the bits the scalar solve
//! computes (Rust never contracts to FMA), and the scalar solve keeps the bits it had with glam.
use std::array::from_fn;
use std::ops::{Add, Mul, Neg, Sub};

use glam::DVec3;

use super::lanes::lanewise;

/// One f64, or one per lane.
pub(crate) trait Real:
    Copy + Default + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    /// Strands solved at once.
    const LANES: usize;
    fn splat(v: f64) -> Self;
    fn abs(self) -> Self;
    /// `f64::max` per lane.
    fn max(self, o: Self) -> Self;
    /// `1.0 / self` per lane.
    fn recip(self) -> Self;
    fn lane(self, l: usize) -> f64;
    fn set_lane(&mut self, l: usize, v: f64);
}

impl Real for f64 {
    const LANES: usize = 1;
    #[inline(always)]
    fn splat(v: f64) -> f64 {
        v
    }
    #[inline(always)]
    fn abs(self) -> f64 {
        f64::abs(self)
    }
    #[inline(always)]
    fn max(self, o: f64) -> f64 {
        f64::max(self, o)
    }
    #[inline(always)]
    fn recip(self) -> f64 {
        1.0 / self
    }
    #[inline(always)]
    fn lane(self, _: usize) -> f64 {
        self
    }
    #[inline(always)]
    fn set_lane(&mut self, _: usize, v: f64) {
        *self = v;
    }
}

/// Four f64, one per strand; plain arrays the compiler turns into SIMD registers.
#[derive(Clone, Copy, Debug, Default)]
#[repr(align(32))]
pub(crate) struct F64x4(pub [f64; 4]);

lanewise!(F64x4, Add, add, +);
lanewise!(F64x4, Sub, sub, -);
lanewise!(F64x4, Mul, mul, *);

impl Neg for F64x4 {
    type Output = F64x4;
    #[inline(always)]
    fn neg(self) -> F64x4 {
        F64x4(from_fn(|l| -self.0[l]))
    }
}

impl Real for F64x4 {
    const LANES: usize = 4;
    #[inline(always)]
    fn splat(v: f64) -> F64x4 {
        F64x4([v; 4])
    }
    #[inline(always)]
    fn abs(self) -> F64x4 {
        F64x4(from_fn(|l| self.0[l].abs()))
    }
    #[inline(always)]
    fn max(self, o: F64x4) -> F64x4 {
        F64x4(from_fn(|l| self.0[l].max(o.0[l])))
    }
    #[inline(always)]
    fn recip(self) -> F64x4 {
        F64x4(from_fn(|l| 1.0 / self.0[l]))
    }
    #[inline(always)]
    fn lane(self, l: usize) -> f64 {
        self.0[l]
    }
    #[inline(always)]
    fn set_lane(&mut self, l: usize, v: f64) {
        self.0[l] = v;
    }
}

/// A 3-vector (glam's `DVec3` arithmetic).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct V3<T> {
    pub x: T,
    pub y: T,
    pub z: T,
}

impl<T: Real> V3<T> {
    #[inline(always)]
    pub fn new(x: T, y: T, z: T) -> Self {
        V3 { x, y, z }
    }
    #[inline(always)]
    pub fn zero() -> Self {
        Self::splat(T::splat(0.0))
    }
    #[inline(always)]
    pub fn splat(v: T) -> Self {
        V3 { x: v, y: v, z: v }
    }
    /// `self * s`.
    #[inline(always)]
    pub fn scale(self, s: T) -> Self {
        V3 { x: self.x * s, y: self.y * s, z: self.z * s }
    }
    /// Componentwise product.
    #[inline(always)]
    pub fn mul(self, o: Self) -> Self {
        V3 { x: self.x * o.x, y: self.y * o.y, z: self.z * o.z }
    }
    #[inline(always)]
    pub fn dot(self, o: Self) -> T {
        (self.x * o.x) + (self.y * o.y) + (self.z * o.z)
    }
    #[inline(always)]
    pub fn length_squared(self) -> T {
        self.dot(self)
    }
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3 { x: self.y * o.z - o.y * self.z, y: self.z * o.x - o.z * self.x, z: self.x * o.y - o.x * self.y }
    }
    /// Lane `l` as a glam vector.
    #[inline(always)]
    pub fn lane(self, l: usize) -> DVec3 {
        DVec3::new(self.x.lane(l), self.y.lane(l), self.z.lane(l))
    }
    #[inline(always)]
    pub fn set_lane(&mut self, l: usize, v: DVec3) {
        self.x.set_lane(l, v.x);
        self.y.set_lane(l, v.y);
        self.z.set_lane(l, v.z);
    }
}

impl<T: Real> Add for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        V3 { x: self.x + o.x, y: self.y + o.y, z: self.z + o.z }
    }
}

impl<T: Real> Sub for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        V3 { x: self.x - o.x, y: self.y - o.y, z: self.z - o.z }
    }
}

impl<T: Real> Neg for V3<T> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3 { x: -self.x, y: -self.y, z: -self.z }
    }
}

/// A 3×3 matrix by columns (glam's `DMat3` arithmetic).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct M3<T> {
    pub x_axis: V3<T>,
    pub y_axis: V3<T>,
    pub z_axis: V3<T>,
}

impl<T: Real> M3<T> {
    #[inline(always)]
    pub fn from_cols(x_axis: V3<T>, y_axis: V3<T>, z_axis: V3<T>) -> Self {
        M3 { x_axis, y_axis, z_axis }
    }
    #[inline(always)]
    pub fn zero() -> Self {
        Self::from_cols(V3::zero(), V3::zero(), V3::zero())
    }
    #[inline(always)]
    pub fn from_diagonal(d: V3<T>) -> Self {
        let z = T::splat(0.0);
        Self::from_cols(V3::new(d.x, z, z), V3::new(z, d.y, z), V3::new(z, z, d.z))
    }
    #[inline(always)]
    pub fn identity() -> Self {
        Self::from_diagonal(V3::splat(T::splat(1.0)))
    }
    /// The rotation of the unit quaternion `(x, y, z, w)`.
    #[inline(always)]
    pub fn from_quat([x, y, z, w]: [T; 4]) -> Self {
        let (x2, y2, z2) = (x + x, y + y, z + z);
        let (xx, xy, xz) = (x * x2, x * y2, x * z2);
        let (yy, yz, zz) = (y * y2, y * z2, z * z2);
        let (wx, wy, wz) = (w * x2, w * y2, w * z2);
        let one = T::splat(1.0);
        Self::from_cols(
            V3::new(one - (yy + zz), xy + wz, xz - wy),
            V3::new(xy - wz, one - (xx + zz), yz + wx),
            V3::new(xz + wy, yz - wx, one - (xx + yy)),
        )
    }
    #[inline(always)]
    pub fn transpose(&self) -> Self {
        Self::from_cols(
            V3::new(self.x_axis.x, self.y_axis.x, self.z_axis.x),
            V3::new(self.x_axis.y, self.y_axis.y, self.z_axis.y),
            V3::new(self.x_axis.z, self.y_axis.z, self.z_axis.z),
        )
    }
    #[inline(always)]
    pub fn scale(&self, s: T) -> Self {
        Self::from_cols(self.x_axis.scale(s), self.y_axis.scale(s), self.z_axis.scale(s))
    }
    /// `self · v`.
    #[inline(always)]
    pub fn mul_vec(&self, v: V3<T>) -> V3<T> {
        self.x_axis.scale(v.x) + self.y_axis.scale(v.y) + self.z_axis.scale(v.z)
    }
    /// `self · o`.
    #[inline(always)]
    pub fn mul_mat(&self, o: &Self) -> Self {
        Self::from_cols(self.mul_vec(o.x_axis), self.mul_vec(o.y_axis), self.mul_vec(o.z_axis))
    }
    /// Sets lane `l` of every entry to `m`'s.
    #[inline(always)]
    pub fn set_lane(&mut self, l: usize, m: &M3<f64>) {
        self.x_axis.set_lane(l, m.x_axis.lane(0));
        self.y_axis.set_lane(l, m.y_axis.lane(0));
        self.z_axis.set_lane(l, m.z_axis.lane(0));
    }
    /// The inverse by cofactors (invalid where the determinant is 0).
    #[inline(always)]
    pub fn inverse(&self) -> Self {
        let tmp0 = self.y_axis.cross(self.z_axis);
        let tmp1 = self.z_axis.cross(self.x_axis);
        let tmp2 = self.x_axis.cross(self.y_axis);
        let inv_det = V3::splat(self.z_axis.dot(tmp2).recip());
        Self::from_cols(tmp0.mul(inv_det), tmp1.mul(inv_det), tmp2.mul(inv_det)).transpose()
    }
}

impl<T: Real> Add for M3<T> {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Self::from_cols(self.x_axis + o.x_axis, self.y_axis + o.y_axis, self.z_axis + o.z_axis)
    }
}

impl<T: Real> Sub for M3<T> {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Self::from_cols(self.x_axis - o.x_axis, self.y_axis - o.y_axis, self.z_axis - o.z_axis)
    }
}

impl<T: Real> Neg for M3<T> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Self::from_cols(-self.x_axis, -self.y_axis, -self.z_axis)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DQuat};

    fn m3(m: DMat3) -> M3<f64> {
        let v = |c: DVec3| V3::new(c.x, c.y, c.z);
        M3::from_cols(v(m.x_axis), v(m.y_axis), v(m.z_axis))
    }

    fn bits(m: M3<f64>) -> [u64; 9] {
        let c = [m.x_axis, m.y_axis, m.z_axis];
        from_fn(|i| [c[i / 3].x, c[i / 3].y, c[i / 3].z][i % 3].to_bits())
    }

    fn glam_bits(m: DMat3) -> [u64; 9] {
        from_fn(|i| m.to_cols_array()[i].to_bits())
    }

    /// The operations give glam's bits, so the solve's results do not change with this module.
    #[test]
    fn operations_round_as_glam_does() {
        let a = DMat3::from_cols_array(&[0.3, -1.7, 2.1, 0.77, 1e-3, -0.4, 5.5, 0.125, -3.3]);
        let b = DMat3::from_cols_array(&[-0.9, 0.31, 1.3, 2.2, -0.07, 0.6, 0.01, 4.4, 1.9]);
        let v = DVec3::new(0.37, -2.9, 1.1);
        let q = DQuat::from_xyzw(0.1, -0.7, 0.3, 0.5).normalize();
        assert_eq!(bits(m3(a).mul_mat(&m3(b))), glam_bits(a * b));
        assert_eq!(bits(m3(a).inverse()), glam_bits(a.inverse()));
        assert_eq!(bits(M3::from_quat([q.x, q.y, q.z, q.w])), glam_bits(DMat3::from_quat(q)));
        assert_eq!(bits(m3(a).scale(0.3) - m3(b).transpose()), glam_bits(a * 0.3 - b.transpose()));
        let w = m3(a).mul_vec(V3::new(v.x, v.y, v.z));
        assert_eq!(w.lane(0), a * v);
        // Four lanes compute each lane's scalar bits.
        let mut lanes = M3::<F64x4>::zero();
        let mats = [a, b, a * b, a + b];
        for (l, m) in mats.iter().enumerate() {
            lanes.x_axis.set_lane(l, m.x_axis);
            lanes.y_axis.set_lane(l, m.y_axis);
            lanes.z_axis.set_lane(l, m.z_axis);
        }
        let inverse = lanes.inverse();
        for (l, m) in mats.iter().enumerate() {
            let lane = M3::from_cols(
                V3::new(inverse.x_axis.x.0[l], inverse.x_axis.y.0[l], inverse.x_axis.z.0[l]),
                V3::new(inverse.y_axis.x.0[l], inverse.y_axis.y.0[l], inverse.y_axis.z.0[l]),
                V3::new(inverse.z_axis.x.0[l], inverse.z_axis.y.0[l], inverse.z_axis.z.0[l]),
            );
            assert_eq!(bits(lane), glam_bits(m.inverse()));
        }
    }
}
