//! A small safe layer over `embree4-sys` (Embree 4 from the `embreex` wheel). `embree4-rs` has no
//! curve geometry and hides its device handle, so coif talks to the C API directly and keeps the
//! unsafe code here: a device, a scene of round curves and triangle meshes, and closest-hit and
//! occlusion queries one ray at a time or in packets of eight (coherent camera rays).
use std::ptr;

use embree4_sys as sys;
use glam::Vec3;

use crate::error::{Error, Result};

/// An Embree device: the library instance that owns scenes and geometry.
pub struct Device {
    raw: sys::RTCDevice,
}

// Embree devices and committed scenes are thread-safe for queries.
unsafe impl Send for Device {}
unsafe impl Sync for Device {}

impl Device {
    pub fn new() -> Result<Device> {
        Device::with_config("verbose=0")
    }

    /// A device with an Embree configuration string (e.g. `threads=1` for the BVH builder).
    pub fn with_config(config: &str) -> Result<Device> {
        let config = std::ffi::CString::new(config)
            .map_err(|_| Error::Usage("Embree configuration contains a NUL byte".into()))?;
        // SAFETY: a valid NUL-terminated config string; a null result is checked.
        let raw = unsafe { sys::rtcNewDevice(config.as_ptr()) };
        if raw.is_null() {
            return Err(Error::External("Embree: could not create a device".into()));
        }
        Ok(Device { raw })
    }

    fn check(&self, what: &str) -> Result<()> {
        // SAFETY: the device is valid for our lifetime.
        let code = unsafe { sys::rtcGetDeviceError(self.raw) };
        if code == sys::RTCError::NONE {
            return Ok(());
        }
        Err(Error::External(format!("Embree: {what} failed: {code:?}")))
    }

    pub fn raw(&self) -> sys::RTCDevice {
        self.raw
    }
}

impl Drop for Device {
    fn drop(&mut self) {
        // SAFETY: we own one reference to the device.
        unsafe { sys::rtcReleaseDevice(self.raw) }
    }
}

/// How a round curve's control points are interpolated (Embree's round curve types).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveType {
    /// Segments between consecutive vertices: 2 points per segment.
    Linear,
    /// Cubic Bézier: 4 control points per segment, consecutive segments share one point.
    Bezier,
    /// Uniform cubic B-spline: 4 control points per segment, segments advance by one point.
    BSpline,
    /// Catmull–Rom: 4 points per segment (passes through the middle two).
    CatmullRom,
}

impl CurveType {
    fn geometry_type(self) -> sys::RTCGeometryType {
        match self {
            CurveType::Linear => sys::RTCGeometryType::ROUND_LINEAR_CURVE,
            CurveType::Bezier => sys::RTCGeometryType::ROUND_BEZIER_CURVE,
            CurveType::BSpline => sys::RTCGeometryType::ROUND_BSPLINE_CURVE,
            CurveType::CatmullRom => sys::RTCGeometryType::ROUND_CATMULL_ROM_CURVE,
        }
    }

    /// Control points one segment reads, starting at its index-buffer entry.
    pub fn points_per_segment(self) -> usize {
        match self {
            CurveType::Linear => 2,
            _ => 4,
        }
    }
}

/// A ray hit: distance along the ray, geometry and primitive ids, surface parameters, and the
/// geometric normal Embree reports (for curves, a vector towards the ray origin across the tube;
/// not normalised).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub geometry: u32,
    pub primitive: u32,
    pub u: f32,
    pub v: f32,
    pub normal: Vec3,
}

/// A ray for a packet query: origin, direction, the `[t_near, t_far]` interval and an id that
/// hit filters see.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub direction: Vec3,
    pub t_near: f32,
    pub t_far: f32,
    pub id: u32,
}

/// Decides during traversal whether a candidate hit on a primitive counts for the ray with the
/// given id (`false` lets the ray pass, as through a transparent strand).
pub type HitFilter = Box<dyn Fn(u32, u32) -> bool + Send + Sync>;

/// Embree's filter callback for curves: drops hits on a curve's far side, then asks the
/// geometry's [`HitFilter`], if any, about every lane still valid.
///
/// Round curves are solid tubes to Embree, which reports a ray leaving a tube as a hit on its
/// inside. Coif's hair BSDFs account for the whole walk through a fibre at the entry point (the
/// near-field model of Chiang et al.), so a ray leaving a fibre, through its far side or back the
/// way it came, must not meet that fibre again: hits where the ray runs along the outward normal
/// are dropped (Mitsuba culls curve back faces likewise). Without this a fibre shadowed its own
/// transmitted light and the light reached the camera after extra, absorbing walks through the
/// same fibre.
unsafe extern "C" fn curve_filter(args: *const sys::RTCFilterFunctionNArguments) {
    // SAFETY: Embree passes valid arguments; the user pointer is the `Option<HitFilter>` the
    // scene owns; RTCRayN / RTCHitN are structs of arrays of N 4-byte fields in the documented
    // order (ray: org xyz, tnear, dir xyz = fields 4-6, time, tfar, mask, id = field 10;
    // hit: Ng xyz = fields 0-2, u, v, primID = field 5).
    let args = &*args;
    let filter = &*(args.geometryUserPtr as *const Option<HitFilter>);
    let n = args.N as usize;
    let ray = args.ray as *const u32;
    let hit = args.hit as *const u32;
    let float = |base: *const u32, field: usize, lane: usize| f32::from_bits(*base.add(field * n + lane));
    for lane in 0..n {
        let valid = args.valid.add(lane);
        if *valid == 0 {
            continue;
        }
        let direction = Vec3::new(float(ray, 4, lane), float(ray, 5, lane), float(ray, 6, lane));
        let normal = Vec3::new(float(hit, 0, lane), float(hit, 1, lane), float(hit, 2, lane));
        let leaving = direction.dot(normal) > 0.0;
        let seen = !leaving
            && filter.as_ref().is_none_or(|filter| {
                let id = *ray.add(10 * n + lane);
                let primitive = *hit.add(5 * n + lane);
                filter(primitive, id)
            });
        if !seen {
            *valid = 0;
        }
    }
}

/// Lanes in a ray packet.
pub const PACKET: usize = 8;

/// A ray-hit struct as the bundled headers declare it, followed by room for the `instPrimID`
/// field that Embree ≥ 4.3 built with instance arrays (the library we load) appends to its hit
/// structs and writes on every hit. Without the room it overwrites the caller's stack.
#[repr(C)]
struct WithInstPrimId<T, const N: usize> {
    value: T,
    inst_prim_id: [u32; N],
}

/// A committed Embree scene.
pub struct Scene<'d> {
    raw: sys::RTCScene,
    device: &'d Device,
    /// Hit filters Embree calls back into; boxed twice so Embree holds a thin pointer.
    #[allow(clippy::vec_box)]
    filters: Vec<Box<Option<HitFilter>>>,
}

unsafe impl Send for Scene<'_> {}
unsafe impl Sync for Scene<'_> {}

impl<'d> Scene<'d> {
    pub fn new(device: &'d Device) -> Result<Scene<'d>> {
        // SAFETY: valid device; result checked.
        let raw = unsafe { sys::rtcNewScene(device.raw) };
        device.check("creating a scene")?;
        Ok(Scene { raw, device, filters: Vec::new() })
    }

    /// Asks for a higher-quality BVH (slower to build, faster to trace): worth it for many rays.
    pub fn set_high_quality(&mut self) {
        // SAFETY: valid scene.
        unsafe { sys::rtcSetSceneBuildQuality(self.raw, sys::RTCBuildQuality::HIGH) }
    }

    /// Adds round linear curves: `points` carries (x, y, z, radius) per vertex, each segment
    /// starts at the vertex index in `segment_starts`. Returns the geometry id.
    pub fn add_round_linear_curves(&mut self, points: &[[f32; 4]], segment_starts: &[u32]) -> Result<u32> {
        self.add_round_curves(CurveType::Linear, points, segment_starts, None)
    }

    /// Adds round curves of any basis: `points` carries (x, y, z, radius) per control point and
    /// segment `i` reads [`CurveType::points_per_segment`] points from `segment_starts[i]`.
    /// `filter`, if given, is asked about every candidate hit (primitive = segment index). Rays
    /// never see a curve from inside: see [`curve_filter`].
    pub fn add_round_curves(
        &mut self,
        kind: CurveType,
        points: &[[f32; 4]],
        segment_starts: &[u32],
        filter: Option<HitFilter>,
    ) -> Result<u32> {
        let per_segment = kind.points_per_segment();
        if let Some(bad) = segment_starts.iter().position(|&s| s as usize + per_segment > points.len()) {
            return Err(Error::Usage(format!("curve segment {bad} reads past the last control point")));
        }
        let device = self.device;
        // SAFETY: buffers are allocated by Embree with the sizes we pass and filled in bounds;
        // every index was checked to address whole segments inside the vertex buffer.
        unsafe {
            let geometry = sys::rtcNewGeometry(device.raw, kind.geometry_type());
            device.check("creating curve geometry")?;
            let vertex = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::VERTEX,
                0,
                sys::RTCFormat::FLOAT4,
                16,
                points.len(),
            ) as *mut [f32; 4];
            device.check("allocating curve vertices")?;
            ptr::copy_nonoverlapping(points.as_ptr(), vertex, points.len());
            let index = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::INDEX,
                0,
                sys::RTCFormat::UINT,
                4,
                segment_starts.len(),
            ) as *mut u32;
            device.check("allocating curve segments")?;
            ptr::copy_nonoverlapping(segment_starts.as_ptr(), index, segment_starts.len());
            let boxed = Box::new(filter);
            sys::rtcSetGeometryUserData(
                geometry,
                &*boxed as *const Option<HitFilter> as *mut std::ffi::c_void,
            );
            sys::rtcSetGeometryIntersectFilterFunction(geometry, Some(curve_filter));
            sys::rtcSetGeometryOccludedFilterFunction(geometry, Some(curve_filter));
            self.filters.push(boxed);
            self.attach(geometry, "adding curves")
        }
    }

    /// Adds a triangle mesh. Returns the geometry id.
    pub fn add_triangle_mesh(&mut self, vertices: &[Vec3], triangles: &[[u32; 3]]) -> Result<u32> {
        if let Some(bad) = triangles.iter().position(|t| t.iter().any(|&i| i as usize >= vertices.len())) {
            return Err(Error::Usage(format!("triangle {bad} names a vertex past the last one")));
        }
        let device = self.device;
        // SAFETY: as for curves; indices were checked against the vertex count.
        unsafe {
            let geometry = sys::rtcNewGeometry(device.raw, sys::RTCGeometryType::TRIANGLE);
            device.check("creating a triangle mesh")?;
            let vertex = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::VERTEX,
                0,
                sys::RTCFormat::FLOAT3,
                12,
                vertices.len(),
            ) as *mut [f32; 3];
            device.check("allocating mesh vertices")?;
            for (i, v) in vertices.iter().enumerate() {
                *vertex.add(i) = v.to_array();
            }
            let index = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::INDEX,
                0,
                sys::RTCFormat::UINT3,
                12,
                triangles.len(),
            ) as *mut [u32; 3];
            device.check("allocating mesh triangles")?;
            ptr::copy_nonoverlapping(triangles.as_ptr(), index, triangles.len());
            self.attach(geometry, "adding a triangle mesh")
        }
    }

    /// Commits a filled geometry, attaches it and drops our reference.
    unsafe fn attach(&mut self, geometry: sys::RTCGeometry, what: &str) -> Result<u32> {
        sys::rtcCommitGeometry(geometry);
        let id = sys::rtcAttachGeometry(self.raw, geometry);
        sys::rtcReleaseGeometry(geometry);
        self.device.check(what)?;
        Ok(id)
    }

    /// Builds the acceleration structure; call before any query.
    pub fn commit(&mut self) -> Result<()> {
        // SAFETY: valid scene.
        unsafe { sys::rtcCommitScene(self.raw) };
        self.device.check("building the scene")
    }

    /// The closest hit along a ray in `[t_near, t_far]`.
    pub fn intersect(&self, origin: Vec3, direction: Vec3, t_near: f32, t_far: f32) -> Option<Hit> {
        self.intersect_ray(&Ray { origin, direction, t_near, t_far, id: 0 })
    }

    /// The closest hit along a ray (its id goes to hit filters).
    pub fn intersect_ray(&self, ray: &Ray) -> Option<Hit> {
        let mut padded = WithInstPrimId {
            value: sys::RTCRayHit {
                ray: raw_ray(ray),
                hit: sys::RTCHit {
                    Ng_x: 0.0,
                    Ng_y: 0.0,
                    Ng_z: 0.0,
                    u: 0.0,
                    v: 0.0,
                    primID: sys::RTC_INVALID_GEOMETRY_ID,
                    geomID: sys::RTC_INVALID_GEOMETRY_ID,
                    instID: [sys::RTC_INVALID_GEOMETRY_ID],
                },
            },
            inst_prim_id: [0],
        };
        // SAFETY: committed scene; rayhit is a valid, aligned struct followed by room for the
        // instPrimID field the library writes; null args use defaults.
        unsafe { sys::rtcIntersect1(self.raw, &mut padded.value, ptr::null_mut()) };
        let rayhit = padded.value;
        let hit = rayhit.hit;
        (hit.geomID != sys::RTC_INVALID_GEOMETRY_ID).then(|| Hit {
            t: rayhit.ray.tfar,
            geometry: hit.geomID,
            primitive: hit.primID,
            u: hit.u,
            v: hit.v,
            normal: Vec3::new(hit.Ng_x, hit.Ng_y, hit.Ng_z),
        })
    }

    /// Whether anything lies along the ray in `[t_near, t_far]` (shadow rays).
    pub fn occluded(&self, origin: Vec3, direction: Vec3, t_near: f32, t_far: f32) -> bool {
        self.occluded_ray(&Ray { origin, direction, t_near, t_far, id: 0 })
    }

    /// Whether anything lies along the ray (its id goes to hit filters).
    pub fn occluded_ray(&self, ray: &Ray) -> bool {
        let mut ray = raw_ray(ray);
        // SAFETY: committed scene; valid ray struct; null args use defaults.
        unsafe { sys::rtcOccluded1(self.raw, &mut ray, ptr::null_mut()) };
        // Embree marks an occluded ray by setting tfar to -inf.
        ray.tfar < 0.0
    }

    /// Closest hits of up to [`PACKET`] rays traced together (`None` lanes are inactive). Pays
    /// for coherent rays such as neighbouring camera rays.
    pub fn intersect_packet(&self, rays: &[Option<Ray>; PACKET]) -> [Option<Hit>; PACKET] {
        // Embree reads the valid mask with vector loads: it must be 32-byte aligned.
        #[repr(C, align(32))]
        struct Valid([i32; PACKET]);
        let mut valid = Valid([0; PACKET]);
        let mut padded = WithInstPrimId {
            value: sys::RTCRayHit8 {
                ray: sys::RTCRay8 {
                    org_x: [0.0; PACKET],
                    org_y: [0.0; PACKET],
                    org_z: [0.0; PACKET],
                    tnear: [0.0; PACKET],
                    dir_x: [0.0; PACKET],
                    dir_y: [0.0; PACKET],
                    dir_z: [1.0; PACKET],
                    time: [0.0; PACKET],
                    tfar: [0.0; PACKET],
                    mask: [u32::MAX; PACKET],
                    id: [0; PACKET],
                    flags: [0; PACKET],
                },
                hit: sys::RTCHit8 {
                    Ng_x: [0.0; PACKET],
                    Ng_y: [0.0; PACKET],
                    Ng_z: [0.0; PACKET],
                    u: [0.0; PACKET],
                    v: [0.0; PACKET],
                    primID: [sys::RTC_INVALID_GEOMETRY_ID; PACKET],
                    geomID: [sys::RTC_INVALID_GEOMETRY_ID; PACKET],
                    instID: [[sys::RTC_INVALID_GEOMETRY_ID; PACKET]],
                },
            },
            inst_prim_id: [0; PACKET],
        };
        let rh = &mut padded.value;
        for (lane, ray) in rays.iter().enumerate() {
            let Some(ray) = ray else { continue };
            valid.0[lane] = -1;
            rh.ray.org_x[lane] = ray.origin.x;
            rh.ray.org_y[lane] = ray.origin.y;
            rh.ray.org_z[lane] = ray.origin.z;
            rh.ray.dir_x[lane] = ray.direction.x;
            rh.ray.dir_y[lane] = ray.direction.y;
            rh.ray.dir_z[lane] = ray.direction.z;
            rh.ray.tnear[lane] = ray.t_near;
            rh.ray.tfar[lane] = ray.t_far;
            rh.ray.id[lane] = ray.id;
        }
        // SAFETY: committed scene; `valid` and the 32-byte aligned packet live across the call.
        // Default (null) query arguments: the bundled headers' `RTCIntersectArguments` layout
        // does not match the 4.4 library's, and passing one crashes.
        unsafe { sys::rtcIntersect8(valid.0.as_ptr(), self.raw, rh, ptr::null_mut()) };
        std::array::from_fn(|lane| {
            (valid.0[lane] != 0 && rh.hit.geomID[lane] != sys::RTC_INVALID_GEOMETRY_ID).then(|| Hit {
                t: rh.ray.tfar[lane],
                geometry: rh.hit.geomID[lane],
                primitive: rh.hit.primID[lane],
                u: rh.hit.u[lane],
                v: rh.hit.v[lane],
                normal: Vec3::new(rh.hit.Ng_x[lane], rh.hit.Ng_y[lane], rh.hit.Ng_z[lane]),
            })
        })
    }
}

fn raw_ray(ray: &Ray) -> sys::RTCRay {
    sys::RTCRay {
        org_x: ray.origin.x,
        org_y: ray.origin.y,
        org_z: ray.origin.z,
        tnear: ray.t_near,
        dir_x: ray.direction.x,
        dir_y: ray.direction.y,
        dir_z: ray.direction.z,
        time: 0.0,
        tfar: ray.t_far,
        mask: u32::MAX,
        id: ray.id,
        flags: 0,
    }
}

impl Drop for Scene<'_> {
    fn drop(&mut self) {
        // SAFETY: we own one reference to the scene.
        unsafe { sys::rtcReleaseScene(self.raw) }
    }
}
