//! A small safe layer over `embree4-sys` (Embree 4 from the `embreex` wheel). `embree4-rs` has no
//! curve geometry and hides its device handle, so coif talks to the C API directly and keeps the
//! unsafe code here.
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
        let config = c"verbose=0";
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

/// A ray hit: distance along the ray, geometry and primitive ids, curve parameter, and the
/// geometric normal Embree reports (for curves, a vector towards the ray origin across the tube).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub geometry: u32,
    pub primitive: u32,
    pub u: f32,
    pub normal: Vec3,
}

/// A committed Embree scene.
pub struct Scene<'d> {
    raw: sys::RTCScene,
    device: &'d Device,
}

unsafe impl Send for Scene<'_> {}
unsafe impl Sync for Scene<'_> {}

impl<'d> Scene<'d> {
    pub fn new(device: &'d Device) -> Result<Scene<'d>> {
        // SAFETY: valid device; result checked.
        let raw = unsafe { sys::rtcNewScene(device.raw) };
        device.check("creating a scene")?;
        Ok(Scene { raw, device })
    }

    /// Adds round linear curves: `points` carries (x, y, z, radius) per vertex, each segment
    /// starts at the vertex index in `segment_starts`. Returns the geometry id.
    pub fn add_round_linear_curves(&mut self, points: &[[f32; 4]], segment_starts: &[u32]) -> Result<u32> {
        let device = self.device;
        // SAFETY: buffers are allocated by Embree with the sizes we pass and filled in bounds.
        unsafe {
            let geometry = sys::rtcNewGeometry(device.raw, sys::RTCGeometryType::ROUND_LINEAR_CURVE);
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
            sys::rtcCommitGeometry(geometry);
            let id = sys::rtcAttachGeometry(self.raw, geometry);
            sys::rtcReleaseGeometry(geometry);
            device.check("adding curves")?;
            Ok(id)
        }
    }

    /// Builds the acceleration structure; call before any query.
    pub fn commit(&mut self) -> Result<()> {
        // SAFETY: valid scene.
        unsafe { sys::rtcCommitScene(self.raw) };
        self.device.check("building the scene")
    }

    /// The closest hit along a ray in `[t_near, t_far]`.
    pub fn intersect(&self, origin: Vec3, direction: Vec3, t_near: f32, t_far: f32) -> Option<Hit> {
        let mut rayhit = sys::RTCRayHit {
            ray: sys::RTCRay {
                org_x: origin.x,
                org_y: origin.y,
                org_z: origin.z,
                tnear: t_near,
                dir_x: direction.x,
                dir_y: direction.y,
                dir_z: direction.z,
                time: 0.0,
                tfar: t_far,
                mask: u32::MAX,
                id: 0,
                flags: 0,
            },
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
        };
        // SAFETY: committed scene; rayhit is a valid, aligned struct; null args use defaults.
        unsafe { sys::rtcIntersect1(self.raw, &mut rayhit, ptr::null_mut()) };
        let hit = rayhit.hit;
        (hit.geomID != sys::RTC_INVALID_GEOMETRY_ID).then(|| Hit {
            t: rayhit.ray.tfar,
            geometry: hit.geomID,
            primitive: hit.primID,
            u: hit.u,
            normal: Vec3::new(hit.Ng_x, hit.Ng_y, hit.Ng_z),
        })
    }
}

impl Drop for Scene<'_> {
    fn drop(&mut self) {
        // SAFETY: we own one reference to the scene.
        unsafe { sys::rtcReleaseScene(self.raw) }
    }
}
