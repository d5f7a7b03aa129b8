//! Solid obstacles a strand meets while it is styled — the head, a floor or pillow, perm rods —
//! as signed distance functions, and the position-projection contact with friction the solver
//! applies to every vertex after each constraint iteration.
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

use glam::{Mat3, Quat, Vec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::mesh_sdf::MeshSdf;
use crate::sim::{Exclusion, Hooks};

/// An obstacle's shape. Distances are signed: negative inside the solid.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase", tag = "shape")]
pub enum Shape {
    Sphere {
        center: Vec3,
        radius: f32,
    },
    /// An ellipsoid, e.g. the analytic head (`coif::head::Head`): semi-axes `radii` along the
    /// X, Y, Z axes turned by `rotation`.
    Ellipsoid {
        center: Vec3,
        radii: Vec3,
        #[serde(default)]
        rotation: Quat,
    },
    /// The half-space below the plane through `point` with outward `normal` (a floor).
    Plane {
        point: Vec3,
        normal: Vec3,
    },
    /// A box (a pillow, a table) along the X, Y, Z axes turned by `rotation`.
    Box {
        center: Vec3,
        half_extents: Vec3,
        #[serde(default)]
        rotation: Quat,
    },
    /// A segment `a`–`b` swept by a sphere: a perm rod (curler).
    Capsule {
        a: Vec3,
        b: Vec3,
        radius: f32,
    },
    /// A triangle mesh through its baked signed distance field.
    #[serde(skip)]
    Mesh(Arc<MeshSdf>),
}

/// Shortest distance between the segments `a0`–`a1` and `b0`–`b1`: the closest points are
/// found on the infinite lines, clamped to the segments, and the clamp of one carried over to
/// the other (exact for segments; degenerate segments are points).
pub fn segment_distance(a0: Vec3, a1: Vec3, b0: Vec3, b1: Vec3) -> f32 {
    let (u, v, w) = (a1 - a0, b1 - b0, a0 - b0);
    let (uu, vv, uv, uw, vw) = (u.dot(u), v.dot(v), u.dot(v), u.dot(w), v.dot(w));
    let along = |x: f32| if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 };
    // Parallel (or point) segments: any s works; 0 then the clamps below give the right pair.
    let det = uu * vv - uv * uv;
    let mut s = if det > f32::EPSILON * uu * vv { along((uv * vw - vv * uw) / det) } else { 0.0 };
    let t = along((uv * s + vw) / vv);
    s = along((uv * t - uw) / uu);
    (a0 + u * s).distance(b0 + v * t)
}

impl Shape {
    /// Signed distance from `p` to the surface and the outward unit normal there.
    pub fn distance(&self, p: Vec3) -> (f32, Vec3) {
        match self {
            Shape::Sphere { center, radius } => {
                let d = p - *center;
                let len = d.length();
                (len - radius, if len > 0.0 { d / len } else { Vec3::Y })
            }
            Shape::Ellipsoid { center, radii, rotation } => {
                // Quílez's first-order distance bound: exact on the surface, tight close to it.
                let q = rotation.inverse() * (p - *center);
                let k0 = (q / *radii).length();
                let gradient = q / (*radii * *radii);
                let k1 = gradient.length();
                if k1 == 0.0 {
                    return (-radii.min_element(), *rotation * Vec3::Y);
                }
                (k0 * (k0 - 1.0) / k1, *rotation * (gradient / k1))
            }
            Shape::Plane { point, normal } => {
                let n = normal.normalize();
                ((p - *point).dot(n), n)
            }
            Shape::Box { center, half_extents, rotation } => {
                let (d, n) = box_distance(rotation.inverse() * (p - *center), *half_extents);
                (d, *rotation * n)
            }
            Shape::Capsule { a, b, radius } => {
                let ab = *b - *a;
                let t = ((p - *a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
                let d = p - (*a + ab * t);
                let len = d.length();
                let normal = if len > 0.0 { d / len } else { ab.any_orthonormal_vector() };
                (len - radius, normal)
            }
            Shape::Mesh(sdf) => sdf.distance(p),
        }
    }

    /// Signed distance from the surface alone (the first half of [`Self::distance`], the same
    /// value), for tests that need no normal: a baked mesh's normal costs six extra lookups.
    pub fn signed_distance(&self, p: Vec3) -> f32 {
        match self {
            Shape::Mesh(sdf) => sdf.signed_distance(p),
            _ => self.distance(p).0,
        }
    }

    /// A box holding every point of the solid, or `None` when it is unbounded (or not worth
    /// bounding).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        match self {
            Shape::Sphere { center, radius } => Some((*center - *radius, *center + *radius)),
            Shape::Ellipsoid { center, radii, rotation } => {
                // Half extent along each world axis: the length of that row of R·diag(radii).
                let rows = glam::Mat3::from_quat(*rotation).transpose();
                let half = Vec3::new(
                    (rows.x_axis * *radii).length(),
                    (rows.y_axis * *radii).length(),
                    (rows.z_axis * *radii).length(),
                );
                Some((*center - half, *center + half))
            }
            Shape::Box { center, half_extents, rotation } => {
                // The turned box's corners: per world axis, |row of R| · half extents.
                let rows = glam::Mat3::from_quat(*rotation).transpose();
                let half = Vec3::new(
                    rows.x_axis.abs().dot(*half_extents),
                    rows.y_axis.abs().dot(*half_extents),
                    rows.z_axis.abs().dot(*half_extents),
                );
                Some((*center - half, *center + half))
            }
            Shape::Capsule { a, b, radius } => Some((a.min(*b) - *radius, a.max(*b) + *radius)),
            Shape::Plane { .. } | Shape::Mesh(_) => None,
        }
    }

    /// The same shape moved by `offset` (rods slide along during a stage).
    pub fn translated(&self, offset: Vec3) -> Shape {
        match self {
            Shape::Sphere { center, radius } => Shape::Sphere { center: *center + offset, radius: *radius },
            Shape::Ellipsoid { center, radii, rotation } => {
                Shape::Ellipsoid { center: *center + offset, radii: *radii, rotation: *rotation }
            }
            Shape::Plane { point, normal } => Shape::Plane { point: *point + offset, normal: *normal },
            Shape::Box { center, half_extents, rotation } => {
                Shape::Box { center: *center + offset, half_extents: *half_extents, rotation: *rotation }
            }
            Shape::Capsule { a, b, radius } => {
                Shape::Capsule { a: *a + offset, b: *b + offset, radius: *radius }
            }
            // Unmoved meshes share their field (obstacles are re-placed every step of a press).
            Shape::Mesh(sdf) if offset == Vec3::ZERO => Shape::Mesh(sdf.clone()),
            Shape::Mesh(sdf) => Shape::Mesh(Arc::new(sdf.translated(offset))),
        }
    }
}

fn box_distance(q: Vec3, half: Vec3) -> (f32, Vec3) {
    let d = q.abs() - half;
    let outside = d.max(Vec3::ZERO);
    if outside.length_squared() > 0.0 {
        let len = outside.length();
        return (len, (outside * q.signum()) / len);
    }
    // Inside: the nearest face is the one with the largest (least negative) d.
    let axis = if d.x >= d.y && d.x >= d.z {
        Vec3::X
    } else if d.y >= d.z {
        Vec3::Y
    } else {
        Vec3::Z
    };
    (d.max_element(), axis * q.signum())
}

/// Coulomb friction for position-based contacts (Macklin et al. 2014), judged over the whole
/// step rather than one solver iteration (with the direct solver; Gauss–Seidel keeps
/// [`push_out_once`], see [`crate::sim::StrandSolver::judges_friction_over_the_step`]). Per
/// contact (vertex and shape) the step keeps `pushed`, the contact's normal pushes summed over
/// the step's iterations (the step's normal impulse × Δt / m), and the friction displacement
/// already given ([`ContactSums`]). The slide the vertex
/// would have made since the step's start without friction is held entirely (static) while it is
/// shorter than `static_friction · pushed`; past that cone friction takes `μ · pushed` off it,
/// where μ falls from `static_friction` to `dynamic_friction` as the slip past the cone speeds up
/// ([`Self::STRIBECK_SPEED`]). Judged on one iteration's push instead, a converged (direct) solve,
/// whose later iterations push by almost nothing, let hair below the friction angle creep for
/// ever; a jump straight to the kinetic value past the cone let it creep too.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Friction {
    pub static_friction: f32,
    pub dynamic_friction: f32,
}

impl Default for Friction {
    /// Hair on skin or cotton: μs ≈ 0.4, μk ≈ 0.3.
    fn default() -> Self {
        Friction { static_friction: 0.4, dynamic_friction: 0.3 }
    }
}

impl Friction {
    /// Slip speed past the static cone (m/s) over which the friction coefficient falls by 1/e of
    /// the way from static to kinetic: a speed, so the fall is the same at every Δt.
    pub const STRIBECK_SPEED: f32 = 1e-3;

    /// The friction displacement over the step so far against a frictionless `slide` (tangent to
    /// the surface) of a contact pushed out by `pushed` this step, in a step of `dt` seconds.
    pub fn displacement(&self, slide: Vec3, pushed: f32, dt: f32) -> Vec3 {
        let length = slide.length();
        let cone = self.static_friction * pushed;
        if length <= cone {
            return slide;
        }
        let excess_speed = (length - cone) / dt;
        let fall = (-excess_speed / Self::STRIBECK_SPEED).exp();
        let mu = self.dynamic_friction + (self.static_friction - self.dynamic_friction) * fall;
        // μ ≤ μs, so this is shorter than the slide: friction never turns a slide back.
        slide * (mu * pushed / length)
    }
}

/// One contact's sums over the step so far (see [`Friction`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactSums {
    /// The normal pushes out of the shape, summed over the step's iterations (metres).
    pub pushed: f32,
    /// The friction displacement given so far this step (world, tangent to the shape when given).
    pub given: Vec3,
}

/// How deep a vertex of `radius` at `p` is in `shape` and the way out (the outward normal), or
/// `None` when it does not touch it.
pub fn penetration(shape: &Shape, p: Vec3, radius: f32) -> Option<(f32, Vec3)> {
    if let Shape::Ellipsoid { center, radii, rotation } = shape {
        // Cheap rejection: a point on the ellipsoid scaled by k is at least (k − 1)·r_min from
        // it, and most hair is well clear of the head.
        let clear = 1.0 + radius / radii.min_element();
        if ((rotation.inverse() * (p - *center)) / *radii).length_squared() > clear * clear {
            return None;
        }
    }
    // A mesh's normal costs six lookups of its field: only a vertex that touches it pays them.
    if matches!(shape, Shape::Mesh(_)) && shape.signed_distance(p) >= radius {
        return None;
    }
    let (distance, normal) = shape.distance(p);
    let depth = radius - distance;
    (depth > 0.0).then_some((depth, normal))
}

/// Pushes `p` (a vertex `depth` deep along `normal`, which started the step at `previous`) out,
/// with friction over the step of `dt` seconds given its contact's `sums` so far, which it
/// updates. Returns the corrected position.
pub fn push_out(
    p: Vec3,
    (depth, normal): (f32, Vec3),
    previous: Vec3,
    friction: Friction,
    sums: &mut ContactSums,
    dt: f32,
) -> Vec3 {
    let pushed = p + normal * depth;
    let tangent = |v: Vec3| v - normal * v.dot(normal);
    // What was given before, seen in today's tangent plane (the normal turns along a curved
    // shape; a normal part would push the vertex into or out of the shape).
    let given = tangent(sums.given);
    let slide = tangent(pushed - previous) + given;
    sums.pushed += depth;
    sums.given = friction.displacement(slide, sums.pushed, dt);
    pushed - (sums.given - given)
}

/// Pushes `p` out as [`push_out`] does, with friction judged on this one push alone, the rule
/// Gauss–Seidel keeps for now ([`crate::sim::StrandSolver::judges_friction_over_the_step`]):
/// the vertex keeps still while its slide since the step's start is shorter than
/// `static_friction · depth`, else the slide is shortened by `dynamic_friction · depth`.
pub fn push_out_once(p: Vec3, (depth, normal): (f32, Vec3), previous: Vec3, friction: Friction) -> Vec3 {
    let pushed = p + normal * depth;
    let motion = pushed - previous;
    let slide = motion - normal * motion.dot(normal);
    let slide_length = slide.length();
    let correction = if slide_length < friction.static_friction * depth {
        slide
    } else if slide_length > 0.0 {
        slide * (friction.dynamic_friction * depth / slide_length).min(1.0)
    } else {
        Vec3::ZERO
    };
    pushed - correction
}

/// What the obstacle contacts keep over one step: the positions at its start (friction measures
/// slides from there), and per contact the sums [`Friction`] judges. A contact is a vertex and a
/// shape; each vertex has [`Self::SLOTS`] contacts' room, claimed by shape in the order the
/// vertex meets them this step. A vertex touching two or more shapes in one step is squeezed
/// between them, and has them judged on each iteration's push alone ([`Self::find`]). Slots are
/// written only by the task of the vertex's strand, so the result does not depend on the thread
/// count.
#[derive(Debug, Default)]
pub struct StepContacts {
    previous: Vec<Vec3>,
    dt: f32,
    /// Friction judged over the step; else on each push alone ([`push_out_once`]), no sums kept.
    over_step: bool,
    /// Per vertex, `SLOTS` entries: the shape index or [`Self::FREE`].
    shapes: Vec<AtomicU32>,
    /// Per slot: `pushed` and `given`'s x, y, z, as f32 bits.
    sums: Vec<[AtomicU32; 4]>,
}

impl StepContacts {
    /// Contacts a vertex keeps sums for within a step.
    pub const SLOTS: usize = 2;
    const FREE: u32 = u32::MAX;

    /// Starts a step of `dt` seconds from `positions`: no contact yet. `over_step`: whether
    /// friction is judged over the step ([`crate::sim::StrandSolver::judges_friction_over_the_step`]).
    pub fn start(&mut self, positions: &[Vec3], dt: f32, over_step: bool) {
        self.previous.clear();
        self.previous.extend_from_slice(positions);
        self.dt = dt;
        self.over_step = over_step;
        if !over_step {
            return;
        }
        let slots = positions.len() * Self::SLOTS;
        self.shapes.resize_with(slots, || AtomicU32::new(Self::FREE));
        self.sums.resize_with(slots, Default::default);
        // Only the keys: a slot's sums are written when it is claimed.
        self.shapes.par_iter_mut().for_each(|s| *s.get_mut() = Self::FREE);
    }

    /// The positions at the start of the step.
    pub fn previous(&self) -> &[Vec3] {
        &self.previous
    }

    /// The sums of `vertex`'s contact with `shape` so far, and where to keep them: `Ok` its
    /// slot, `Err` a free slot to claim (none: the vertex's slots are taken by other shapes).
    /// A vertex that has touched another shape this step is squeezed between the two: their
    /// pushes fight each other every iteration, and their sum grows with the iteration count
    /// without any load behind it (held static by it, vertices pinched between a rod and a rising
    /// floor stayed 1.2 mm inside the floor). Its sums are then one iteration's, fresh.
    fn find(&self, vertex: usize, shape: usize) -> (ContactSums, Result<usize, Option<usize>>) {
        let slots = vertex * Self::SLOTS..(vertex + 1) * Self::SLOTS;
        let key = |slot: usize| self.shapes[slot].load(Ordering::Relaxed);
        let own = slots.clone().find(|&slot| key(slot) == shape as u32);
        let squeezed = slots.clone().any(|slot| key(slot) != shape as u32 && key(slot) != Self::FREE);
        let sums = match own {
            Some(slot) if !squeezed => self.load(slot),
            _ => ContactSums::default(),
        };
        (sums, own.ok_or_else(|| slots.clone().find(|&slot| key(slot) == Self::FREE)))
    }

    /// Keeps `sums` where [`Self::find`] said.
    fn keep(&self, place: Result<usize, Option<usize>>, shape: usize, sums: ContactSums) {
        let slot = match place {
            Ok(slot) => slot,
            Err(Some(slot)) => {
                self.shapes[slot].store(shape as u32, Ordering::Relaxed);
                slot
            }
            Err(None) => return,
        };
        self.store(slot, sums);
    }

    fn load(&self, slot: usize) -> ContactSums {
        let [pushed, x, y, z] = self.sums[slot].each_ref().map(|b| f32::from_bits(b.load(Ordering::Relaxed)));
        ContactSums { pushed, given: Vec3::new(x, y, z) }
    }

    fn store(&self, slot: usize, sums: ContactSums) {
        let values = [sums.pushed, sums.given.x, sums.given.y, sums.given.z];
        for (b, v) in self.sums[slot].iter().zip(values) {
            b.store(v.to_bits(), Ordering::Relaxed);
        }
    }
}

/// Which obstacles each strand can touch this step, so a head with dozens of rods costs each
/// vertex only the few shapes near its strand. A strand's box holds its vertices at the start of
/// the step plus a margin; a vertex that leaves the box during the step is tested against every
/// shape, so culling never changes a result.
#[derive(Clone, Debug, Default)]
pub struct ObstacleCulling {
    /// Per strand: the box (min, max) and a bit per shape that overlaps it.
    boxes: Vec<(Vec3, Vec3)>,
    masks: Vec<u128>,
    /// Per shape: a cheap form of its exact rejection test, where it has one.
    clearances: Vec<Option<Clearance>>,
    /// The clearance tests for the largest radius, when every shape has one (see
    /// [`Hooks::exclusions`]).
    exclusions: Option<Vec<Exclusion>>,
}

/// A cheaper, conservative copy of [`resolve_contact`]'s rejection test for an ellipsoid: one
/// matrix instead of a quaternion turn and divisions. It rejects only points the exact test
/// rejects by a relative margin far above both tests' rounding, so it never changes a result;
/// most vertices of a groom are clear of the head and stop here.
#[derive(Clone, Copy, Debug)]
struct Clearance {
    center: Vec3,
    /// World offset from the centre → the ellipsoid's axes, divided by its semi-axes.
    to_unit: Mat3,
    inv_min_radius: f32,
}

impl Clearance {
    /// Relative margin on the squared scaled distance (the tests agree to ~1e-6 relative).
    const MARGIN: f32 = 1e-3;

    fn new(shape: &Shape) -> Option<Clearance> {
        match shape {
            // Near-degenerate ellipsoids would magnify the tests' rounding differences.
            Shape::Ellipsoid { center, radii, rotation }
                if radii.min_element() > 0.0 && radii.max_element() < 100.0 * radii.min_element() =>
            {
                let turn = Mat3::from_quat(rotation.inverse());
                let inv = radii.recip();
                Some(Clearance {
                    center: *center,
                    to_unit: Mat3::from_cols(turn.x_axis * inv, turn.y_axis * inv, turn.z_axis * inv),
                    inv_min_radius: 1.0 / radii.min_element(),
                })
            }
            _ => None,
        }
    }

    /// Whether a vertex of `radius` at `p` certainly cannot touch the ellipsoid.
    #[inline(always)]
    fn clear(&self, p: Vec3, radius: f32) -> bool {
        (self.to_unit * (p - self.center)).length_squared() > self.limit(radius)
    }

    fn limit(&self, radius: f32) -> f32 {
        let clear = 1.0 + radius * self.inv_min_radius;
        clear * clear * (1.0 + Self::MARGIN)
    }

    /// The region [`Self::clear`] leaves for vertices of radius up to `max_radius`, widened by
    /// the margin once more, so that a point outside it is clear however the two evaluations of
    /// the same expression round.
    fn exclusion(&self, max_radius: f32) -> Exclusion {
        Exclusion {
            center: self.center,
            to_unit: self.to_unit,
            limit: self.limit(max_radius) * (1.0 + Self::MARGIN),
        }
    }
}

impl ObstacleCulling {
    /// Shapes beyond the mask's width are always tested.
    const MAX_CULLED: usize = 128;

    /// Recomputes the boxes from `positions` for vertices of radius up to `max_radius`.
    pub fn update(&mut self, shapes: &[Shape], strand_offsets: &[u32], positions: &[Vec3], max_radius: f32) {
        // Hair barely moves a millimetre per step; anything faster falls back to every shape.
        const MARGIN: f32 = 0.01;
        let strands = strand_offsets.len().saturating_sub(1);
        self.boxes.resize(strands, (Vec3::ZERO, Vec3::ZERO));
        self.masks.resize(strands, 0);
        let shape_bounds: Vec<Option<(Vec3, Vec3)>> = shapes.iter().map(Shape::bounds).collect();
        self.clearances.clear();
        self.clearances.extend(shapes.iter().map(Clearance::new));
        self.exclusions = self.clearances.iter().map(|c| c.map(|c| c.exclusion(max_radius))).collect();
        let grow = MARGIN + max_radius;
        self.boxes.par_iter_mut().zip(self.masks.par_iter_mut()).enumerate().for_each(|(s, (bx, mask))| {
            let range = strand_offsets[s] as usize..strand_offsets[s + 1] as usize;
            let (lo, hi) = positions[range]
                .iter()
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
            *bx = (lo - grow, hi + grow);
            *mask = 0;
            for (k, bounds) in shape_bounds.iter().take(Self::MAX_CULLED).enumerate() {
                if bounds.is_none_or(|(a, b)| a.cmple(bx.1).all() && b.cmpge(bx.0).all()) {
                    *mask |= 1 << k;
                }
            }
        });
    }

    /// The shapes vertex position `p` of `strand` must be tested against, for [`Self::tests`].
    #[inline]
    pub fn mask(&self, strand: usize, p: Vec3) -> u128 {
        let (lo, hi) = self.boxes[strand];
        if p.cmpge(lo).all() && p.cmple(hi).all() {
            self.masks[strand]
        } else {
            u128::MAX
        }
    }

    /// Whether a vertex with `mask` must be tested against shape `k`.
    #[inline]
    pub fn tests(mask: u128, k: usize) -> bool {
        k >= Self::MAX_CULLED || mask & (1 << k) != 0
    }

    /// Whether a vertex of `radius` at `p` certainly does not touch shape `k` (of the shapes last
    /// passed to [`Self::update`]): [`resolve_contact`] would return `None` and the shape's
    /// distance is at least `radius`.
    #[inline]
    pub fn clear_of(&self, k: usize, p: Vec3, radius: f32) -> bool {
        matches!(self.clearances.get(k), Some(Some(c)) if c.clear(p, radius))
    }
}

/// Projects vertices out of the active obstacles after each solver iteration.
pub struct ContactHooks<'a> {
    pub shapes: &'a [Shape],
    pub culling: &'a ObstacleCulling,
    /// The step's start positions and contact sums (friction is judged over the step).
    pub contacts: &'a StepContacts,
    pub radii: &'a [f32],
    pub friction: Friction,
    /// Vertices leaving a rod they were inside as it appeared (`style`'s wrap).
    pub threaded: &'a Threaded,
    /// Where the rods start in `shapes` (a [`Threading::rod`] counts from there).
    pub first_threaded: usize,
}

/// A vertex that was inside a curler rod as the rods appeared: the rod is being put in place
/// around it, so it leaves by one side at a set speed instead of at once (pushed out in one step,
/// a vertex 2 cm deep shot out at 2 cm a step, a speed that depended on Δt). Its offset from
/// `origin` along `exit` may not fall below `floor`, which rises at that speed until the vertex
/// is outside; the rest of the rod does not push it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Threading {
    pub vertex: usize,
    /// The rod, counted from the first rod.
    pub rod: usize,
    /// Where the way out is measured from.
    pub origin: Vec3,
    /// The way out: unit, across the rod's axis.
    pub exit: Vec3,
    /// The least offset along `exit` the vertex may have now (metres from `origin`).
    pub floor: f32,
}

impl Threading {
    fn offset(&self, p: Vec3) -> f32 {
        (p - self.origin).dot(self.exit)
    }

    /// `p` moved out to the floor if it lies behind it.
    pub fn hold(&self, p: Vec3) -> Vec3 {
        p + self.exit * self.behind(p)
    }

    /// How far `p` lies behind the floor (0 if not): the depth inside the rod as placed so far.
    pub fn behind(&self, p: Vec3) -> f32 {
        (self.floor - self.offset(p)).max(0.0)
    }
}

/// The vertices passing through a rod, found by vertex.
#[derive(Clone, Debug, Default)]
pub struct Threaded {
    /// Per vertex, 0 or `1 +` its index in `threads`; empty when none is threaded.
    slots: Vec<u32>,
    threads: Vec<Threading>,
}

impl Threaded {
    pub fn new(vertices: usize, threads: Vec<Threading>) -> Threaded {
        if threads.is_empty() {
            return Threaded::default();
        }
        let mut slots = vec![0; vertices];
        for (k, t) in threads.iter().enumerate() {
            slots[t.vertex] = k as u32 + 1;
        }
        Threaded { slots, threads }
    }

    pub fn is_empty(&self) -> bool {
        self.threads.is_empty()
    }

    pub fn get(&self, vertex: usize) -> Option<&Threading> {
        match self.slots.get(vertex) {
            Some(&k) if k > 0 => Some(&self.threads[k as usize - 1]),
            _ => None,
        }
    }

    pub fn iter(&self) -> impl Iterator<Item = &Threading> {
        self.threads.iter()
    }

    /// Raises every floor by `by` metres (a step of the rods being put in place).
    pub fn advance(&mut self, by: f32) {
        self.threads.iter_mut().for_each(|t| t.floor += by);
    }

    /// Drops the threadings `left` says have left their rod (they collide with it from then on).
    pub fn release(&mut self, mut left: impl FnMut(&Threading) -> bool) {
        // Renumbered in place: the threads are few, the vertices many.
        let slots = &mut self.slots;
        self.threads.retain(|t| {
            slots[t.vertex] = 0;
            !left(t)
        });
        if self.threads.is_empty() {
            *self = Threaded::default();
        }
        for (k, t) in self.threads.iter().enumerate() {
            self.slots[t.vertex] = k as u32 + 1;
        }
    }
}

impl Hooks for ContactHooks<'_> {
    fn projects(&self) -> bool {
        !self.shapes.is_empty()
    }

    fn exclusions(&self) -> Option<&[Exclusion]> {
        self.culling.exclusions.as_deref()
    }

    fn project(&self, strand: usize, first_vertex: usize, positions: &mut [Vec3], inverse_masses: &[f32]) {
        for (k, p) in positions.iter_mut().enumerate() {
            if inverse_masses[k] == 0.0 {
                continue;
            }
            let i = first_vertex + k;
            let radius = self.radii[i];
            // The culling mask of the vertex where it started this projection, looked up only for
            // the rare vertex the cheap clearance test leaves.
            let start = *p;
            let mut mask = None;
            let threading = self.threaded.get(i);
            let passes = threading.map_or(usize::MAX, |t| self.first_threaded + t.rod);
            for (s, shape) in self.shapes.iter().enumerate() {
                if s == passes {
                    *p = threading.unwrap().hold(*p);
                    continue;
                }
                if self.culling.clear_of(s, *p, radius)
                    || !ObstacleCulling::tests(
                        *mask.get_or_insert_with(|| self.culling.mask(strand, start)),
                        s,
                    )
                {
                    continue;
                }
                if let Some(contact) = penetration(shape, *p, radius) {
                    let previous = self.contacts.previous[i];
                    if !self.contacts.over_step {
                        *p = push_out_once(*p, contact, previous, self.friction);
                        continue;
                    }
                    let (mut sums, place) = self.contacts.find(i, s);
                    *p = push_out(*p, contact, previous, self.friction, &mut sums, self.contacts.dt);
                    self.contacts.keep(place, s, sums);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`penetration`] then [`push_out`]: the corrected position, or `None` (and `sums` left) when
    /// the vertex does not touch `shape`.
    fn resolve_contact(
        shape: &Shape,
        p: Vec3,
        previous: Vec3,
        radius: f32,
        friction: Friction,
        sums: &mut ContactSums,
        dt: f32,
    ) -> Option<Vec3> {
        penetration(shape, p, radius).map(|contact| push_out(p, contact, previous, friction, sums, dt))
    }

    #[test]
    fn threaded_vertices_are_found_held_behind_their_floor_and_released() {
        let thread = |vertex, floor| Threading { vertex, rod: 0, origin: Vec3::ZERO, exit: Vec3::X, floor };
        let mut threaded = Threaded::new(10, vec![thread(2, -0.5), thread(5, 0.1), thread(7, 0.3)]);
        assert_eq!(threaded.get(5).map(|t| t.vertex), Some(5));
        assert!(threaded.get(3).is_none() && threaded.get(11).is_none());
        threaded.advance(0.25);
        let t = *threaded.get(2).unwrap();
        // Behind the floor (-0.25): moved out along the exit to it; in front: left alone.
        assert_eq!(t.hold(Vec3::new(-1.0, 2.0, 0.0)), Vec3::new(-0.25, 2.0, 0.0));
        assert_eq!(t.hold(Vec3::new(0.5, 2.0, 0.0)), Vec3::new(0.5, 2.0, 0.0));
        assert!((t.behind(Vec3::new(-1.0, 0.0, 0.0)) - 0.75).abs() < 1e-6);
        threaded.release(|t| t.vertex == 5);
        assert!(threaded.get(5).is_none());
        assert_eq!([2, 7].map(|v| threaded.get(v).map(|t| t.vertex)), [Some(2), Some(7)]);
        threaded.release(|_| true);
        assert!(threaded.is_empty() && threaded.get(2).is_none());
    }

    #[test]
    fn clearance_and_exclusions_reject_only_vertices_the_exact_test_rejects() {
        let head = Shape::Ellipsoid {
            center: Vec3::new(0.01, 1.6, -0.02),
            radii: Vec3::new(0.078, 0.1, 0.095),
            rotation: Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.5, 0.2),
        };
        let (center, rotation) = match &head {
            Shape::Ellipsoid { center, rotation, .. } => (*center, *rotation),
            _ => unreachable!(),
        };
        // Points along golden-spiral directions, from inside the head to 20 % beyond it.
        let mut points = Vec::new();
        for i in 0..400 {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / 400.0;
            let phi = i as f32 * 2.399_963;
            let dir = Vec3::new((1.0 - z * z).sqrt() * phi.cos(), z, (1.0 - z * z).sqrt() * phi.sin());
            for k in 0..60 {
                let scale = 0.9 + 0.005 * k as f32;
                points.push(center + rotation * (dir * Vec3::new(0.078, 0.1, 0.095) * scale));
            }
        }
        let max_radius = 0.004;
        let mut culling = ObstacleCulling::default();
        culling.update(std::slice::from_ref(&head), &[0, points.len() as u32], &points, max_radius);
        let exclusion = culling.exclusions.as_ref().expect("an ellipsoid has a clearance")[0];
        let (mut cleared, mut contacts) = (0, 0);
        for &p in &points {
            let outside = (exclusion.to_unit * (p - exclusion.center)).length_squared() > exclusion.limit;
            for radius in [0.0001, 0.001, max_radius] {
                let exact = penetration(&head, p, radius);
                contacts += exact.is_some() as usize;
                if culling.clear_of(0, p, radius) {
                    cleared += 1;
                    assert!(exact.is_none() && head.distance(p).0 >= radius, "{p:?} {radius}");
                }
                assert!(!outside || culling.clear_of(0, p, radius), "{p:?} {radius}");
            }
        }
        // Neither test is vacuous: most points are cleared, and some touch.
        assert!(cleared > points.len() && contacts > 0, "{cleared} {contacts}");
    }

    #[test]
    fn segment_distance_matches_a_dense_search() {
        // Crossing, skew, parallel (overlapping and apart), end-to-end and degenerate pairs,
        // then pseudo-random ones; the reference scans both segments finely.
        let mut pairs = vec![
            [Vec3::ZERO, Vec3::X, Vec3::new(0.5, -1.0, 0.3), Vec3::new(0.5, 1.0, 0.3)],
            [Vec3::ZERO, Vec3::X, Vec3::new(0.2, 0.5, 0.0), Vec3::new(0.8, 0.5, 0.0)],
            [Vec3::ZERO, Vec3::X, Vec3::new(1.5, 0.5, 0.0), Vec3::new(2.5, 0.5, 0.0)],
            [Vec3::ZERO, Vec3::X, Vec3::new(1.2, 0.1, 0.0), Vec3::new(2.0, 1.0, 0.0)],
            [Vec3::ZERO, Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, -1.0, 0.0)],
            [Vec3::Y, Vec3::Y, Vec3::X, Vec3::X],
        ];
        let mut seed = 7u32;
        let mut next = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32 * 2.0 - 1.0
        };
        for _ in 0..200 {
            pairs.push([(); 4].map(|_| Vec3::new(next(), next(), next())));
        }
        for [a0, a1, b0, b1] in pairs {
            let n = 400;
            let mut reference = f32::INFINITY;
            for i in 0..=n {
                let p = a0.lerp(a1, i as f32 / n as f32);
                let v = b1 - b0;
                let t =
                    if v.length_squared() > 0.0 { ((p - b0).dot(v) / v.dot(v)).clamp(0.0, 1.0) } else { 0.0 };
                reference = reference.min(p.distance(b0 + v * t));
            }
            let d = segment_distance(a0, a1, b0, b1);
            // The scan's step along `a` bounds how far above the true distance it can be.
            let slack = a0.distance(a1) / n as f32 + 1e-5;
            assert!(
                d <= reference + 1e-5 && d >= reference - slack,
                "{a0} {a1} {b0} {b1}: {d} vs {reference}"
            );
            assert!((segment_distance(b0, b1, a0, a1) - d).abs() < 1e-5, "not symmetric");
        }
    }

    #[test]
    fn signed_distances_match_geometry() {
        let sphere = Shape::Sphere { center: Vec3::ZERO, radius: 1.0 };
        assert_eq!(sphere.distance(Vec3::new(0.0, 3.0, 0.0)), (2.0, Vec3::Y));
        let plane = Shape::Plane { point: Vec3::new(0.0, -1.0, 0.0), normal: Vec3::Y };
        assert_eq!(plane.distance(Vec3::new(5.0, -1.5, 2.0)).0, -0.5);
        let capsule = Shape::Capsule { a: Vec3::ZERO, b: Vec3::X, radius: 0.1 };
        let (d, n) = capsule.distance(Vec3::new(0.5, 0.0, 0.3));
        assert!((d - 0.2).abs() < 1e-6 && n.abs_diff_eq(Vec3::Z, 1e-6));
        let (d, n) = capsule.distance(Vec3::new(1.5, 0.0, 0.0));
        assert!((d - 0.4).abs() < 1e-6 && n.abs_diff_eq(Vec3::X, 1e-6));
        let bx = Shape::Box {
            center: Vec3::ZERO,
            half_extents: Vec3::new(1.0, 0.5, 2.0),
            rotation: Quat::IDENTITY,
        };
        let (d, n) = bx.distance(Vec3::new(0.2, 0.4, 0.0));
        assert!((d + 0.1).abs() < 1e-6 && n == Vec3::Y);
        assert!((bx.distance(Vec3::new(2.0, 1.5, 0.0)).0 - 2f32.sqrt()).abs() < 1e-6);
        // Turned a quarter about X: its Y half extent lies along Z.
        let rotation = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
        let turned = Shape::Box { center: Vec3::ZERO, half_extents: Vec3::new(1.0, 0.5, 2.0), rotation };
        let (d, n) = turned.distance(Vec3::new(0.0, 0.0, 0.7));
        assert!((d - 0.2).abs() < 1e-6 && n.abs_diff_eq(Vec3::Z, 1e-6), "{d} {n:?}");
        let (lo, hi) = turned.bounds().unwrap();
        assert!(
            lo.abs_diff_eq(Vec3::new(-1.0, -2.0, -0.5), 1e-5)
                && hi.abs_diff_eq(Vec3::new(1.0, 2.0, 0.5), 1e-5)
        );
    }

    #[test]
    fn ellipsoid_distance_is_exact_on_the_axes_and_zero_on_the_surface() {
        let e = Shape::Ellipsoid {
            center: Vec3::ZERO,
            radii: Vec3::new(0.078, 0.1, 0.095),
            rotation: Quat::IDENTITY,
        };
        let (d, n) = e.distance(Vec3::new(0.0, 0.15, 0.0));
        assert!((d - 0.05).abs() < 1e-6 && n.abs_diff_eq(Vec3::Y, 1e-6));
        let surface = Vec3::new(0.078, 0.1, 0.095) * Vec3::new(0.3, 0.8, -0.2).normalize();
        assert!(e.distance(surface).0.abs() < 1e-6);
        assert!(e.distance(Vec3::new(0.01, 0.0, 0.0)).0 < 0.0);
        // Turned a quarter about X: the Y semi-axis lies along Z, and the bounds follow.
        let rotation = Quat::from_rotation_x(std::f32::consts::FRAC_PI_2);
        let turned = Shape::Ellipsoid { center: Vec3::X, radii: Vec3::new(0.078, 0.1, 0.095), rotation };
        let (d, n) = turned.distance(Vec3::new(1.0, 0.0, 0.15));
        assert!((d - 0.05).abs() < 1e-6 && n.abs_diff_eq(Vec3::Z, 1e-6), "{d} {n:?}");
        let (lo, hi) = turned.bounds().unwrap();
        assert!(
            lo.abs_diff_eq(Vec3::new(0.922, -0.095, -0.1), 1e-5)
                && hi.abs_diff_eq(Vec3::new(1.078, 0.095, 0.1), 1e-5)
        );
    }

    #[test]
    fn contact_pushes_out_to_the_radius_and_friction_holds_or_slows_sliding() {
        let floor = Shape::Plane { point: Vec3::ZERO, normal: Vec3::Y };
        let (r, dt) = (0.001, 1.0 / 360.0);
        let fresh = || ContactSums::default();
        let contact = |p, previous, sums: &mut ContactSums| {
            resolve_contact(&floor, p, previous, r, Friction::default(), sums, dt)
        };
        assert!(contact(Vec3::new(0.0, 0.01, 0.0), Vec3::ZERO, &mut fresh()).is_none());
        // Pressed straight down: lands at height r.
        let p = contact(Vec3::new(0.0, -0.01, 0.0), Vec3::ZERO, &mut fresh()).unwrap();
        assert!((p.y - r).abs() < 1e-7 && p.x == 0.0);
        // A small slide with a deep push: static friction holds the vertex in place.
        let previous = Vec3::new(0.0, r, 0.0);
        let p = contact(Vec3::new(0.001, -0.01, 0.0), previous, &mut fresh()).unwrap();
        assert!(p.abs_diff_eq(previous, 1e-7), "{p:?}");
        // A fast slide with a shallow push: kinetic friction shortens it by μk·depth.
        let p = contact(Vec3::new(0.1, 0.0, 0.0), previous, &mut fresh()).unwrap();
        assert!((p.x - (0.1 - 0.3 * r)).abs() < 1e-6 && (p.y - r).abs() < 1e-7, "{p:?}");
    }

    /// Friction is judged on the step's summed push: a vertex slid 0.3 mm and pressed in by
    /// 0.1 mm at each of ten iterations slips while the summed push's cone is smaller than the
    /// slide, and is held back where it started once it covers it (0.4 × 0.8 mm), where each
    /// push alone (0.04 mm of cone) would let it slip; and past the cone the kinetic part takes
    /// μk × the summed push.
    #[test]
    fn friction_is_judged_on_the_pushes_summed_over_the_step() {
        let floor = Shape::Plane { point: Vec3::ZERO, normal: Vec3::Y };
        let (r, dt, depth) = (0.001, 1.0 / 360.0, 1e-4);
        let previous = Vec3::new(0.0, r, 0.0);
        let mut sums = ContactSums::default();
        let mut p = previous + Vec3::X * 0.0003;
        for _ in 0..10 {
            // Each iteration the solver presses the vertex in, where the last one left it.
            p -= Vec3::Y * depth;
            p = resolve_contact(&floor, p, previous, r, Friction::default(), &mut sums, dt).unwrap();
        }
        assert!((sums.pushed - 10.0 * depth).abs() < 1e-7 && p.abs_diff_eq(previous, 1e-7), "{p:?}");
        // A fast slide from rest with ten shallow pushes: kinetic friction sums to μk × 1 mm.
        let mut sums = ContactSums::default();
        let mut p = previous;
        for _ in 0..10 {
            p = resolve_contact(
                &floor,
                p - Vec3::Y * depth + Vec3::X * 0.01,
                previous,
                r,
                Friction::default(),
                &mut sums,
                dt,
            )
            .unwrap();
        }
        assert!((p.x - (0.1 - 0.3 * 10.0 * depth)).abs() < 1e-6, "{p:?}");
        // On a sphere the friction given before is kept in the tangent plane: no push inwards.
        let ball = Shape::Sphere { center: Vec3::ZERO, radius: 1.0 };
        let mut sums = ContactSums { pushed: 0.01, given: Vec3::new(0.001, 0.001, 0.0) };
        let q = resolve_contact(
            &ball,
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0 + r, 0.0),
            r,
            Friction::default(),
            &mut sums,
            dt,
        )
        .unwrap();
        assert!((q.length() - (1.0 + r)).abs() < 1e-6, "{q:?}");
    }
}
