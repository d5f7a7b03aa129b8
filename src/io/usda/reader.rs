//! From a parsed `.usda` layer to a [`Groom`]: walks the prim tree, composes `xformOp`
//! transforms, gathers every `BasisCurves` prim (merging several into one groom), resolves
//! primvar interpolation and indices, and converts to metres and Y up.
use std::cell::RefCell;
use std::path::Path;

use glam::{DMat4, DQuat, DVec3, DVec4, Vec3};

use super::parser::{Attribute, FileArray, FileArrays, Layer, Prim, Site, Value};
use super::{names, SiteFiles, DEFAULT_WIDTH};
use crate::error::{Error, Result};
use crate::groom::{
    Attribute as GroomAttribute, AttributeData, AttributeKind, AttributeRate, CurveBasis, CurveGroup,
    CurveWrap, Groom,
};
use crate::groups::Interpolation;
use crate::io::alembic::curves_write::epic;
use crate::io::{ImportOptions, UpAxis};
use crate::surface_mesh::{MeshInterpolation, MeshPrimvar, SurfaceMesh};
use crate::{point_attributes, primvar_rates};

/// The curves' widths as a primvar: read as their widths, before `widths`.
const WIDTHS_PRIMVAR: &str = "primvars:widths";

/// USD's fallback when a stage does not author `metersPerUnit` (UsdGeom: centimetres).
const FALLBACK_METERS_PER_UNIT: f64 = 0.01;

/// One `BasisCurves` prim's curves, transformed to coif's space (metres, Y up).
struct Curves {
    path: String,
    site: Site,
    basis: CurveBasis,
    wrap: CurveWrap,
    purpose: Option<String>,
    invisible: bool,
    counts: Vec<u32>,
    /// In the file's space until [`merge`] puts them in coif's with `to_coif`.
    points: Bulk<Vec3>,
    /// Per vertex; `None`: not authored (coif's default width).
    widths: Option<Bulk<f32>>,
    to_coif: DMat4,
    strand_ids: Option<Vec<u32>>,
    root_uvs: Option<Vec<[f32; 2]>>,
    guides: Option<Vec<bool>>,
    attributes: Vec<GroomAttribute>,
    /// Attributes read from `constant` or exactly-per-vertex `varying` primvars.
    interpolations: Vec<(String, Interpolation)>,
    /// Attributes read from scalar arrays with an `elementSize` above 1.
    element_sized: Vec<String>,
    width_interpolation: Option<Interpolation>,
}

/// A prim's points or widths: read, or still in a crate file (read by [`merge`] straight into
/// their place in the groom).
enum Bulk<T> {
    Read(Vec<T>),
    InFile(FileArray),
}

impl<T> Bulk<T> {
    fn len(&self) -> usize {
        match self {
            Bulk::Read(values) => values.len(),
            Bulk::InFile(array) => array.elements(),
        }
    }
}

/// The transform from a layer's space to coif's (metres, Y up), applied after each prim's world
/// transform: rotate Z up to Y up, then scale to metres. `options` apply where the layer does
/// not say.
pub(crate) fn stage_transform(layer: &Layer, path: &Path, options: &ImportOptions) -> Result<DMat4> {
    let meters_per_unit = match layer.meters_per_unit {
        Some(m) => {
            crate::validate::number("metersPerUnit", m, crate::validate::UNITS)
                .map_err(|message| Error::format(path, message))?;
            m
        }
        None => options.meters_per_unit.map(f64::from).unwrap_or(FALLBACK_METERS_PER_UNIT),
    };
    let up_axis = match layer.up_axis.as_deref() {
        Some("Y") => UpAxis::Y,
        Some("Z") => UpAxis::Z,
        Some(other) => {
            return Err(Error::format(path, format!("upAxis is \"{other}\"; USD allows \"Y\" or \"Z\"")))
        }
        None => options.up_axis.unwrap_or_default(),
    };
    let mut stage = DMat4::from_scale(DVec3::splat(meters_per_unit));
    if up_axis == UpAxis::Z {
        stage *=
            DMat4::from_cols(DVec3::X.extend(0.0), DVec3::NEG_Z.extend(0.0), DVec3::Y.extend(0.0), DVec4::W);
    }
    Ok(stage)
}

/// Whether anything that places or shows a curve or mesh prim (its points, the transforms
/// above it, its or an ancestor's `visibility`: a keyframed hide) has time samples: a stage
/// whose `startTimeCode`…`endTimeCode` is only the scene's frame range holds one moment.
pub fn places_with_time_samples(layer: &Layer) -> bool {
    fn visit(prim: &Prim, sampled_above: bool) -> bool {
        if !prim.is_defined_and_active() {
            return false;
        }
        let sampled = |a: &Attribute| !a.samples.is_empty();
        let shows = Imageable::is_imageable(&prim.type_name);
        let inherited = prim
            .attributes
            .iter()
            .filter(|a| a.name.starts_with("xformOp") || (shows && a.name == "visibility"));
        let moved = sampled_above || inherited.into_iter().any(sampled);
        let placed = matches!(prim.type_name.as_str(), "BasisCurves" | "NurbsCurves" | "Mesh")
            && (moved || prim.attribute("points").is_some_and(sampled));
        placed || prim.children.iter().any(|child| visit(child, moved))
    }
    layer.prims.iter().any(|prim| visit(prim, false))
}

/// Builds the groom a layer describes, at `time` (see [`value_at`]), with warnings about what the
/// reading left out.
pub fn groom_from_layer(
    layer: Layer,
    path: &Path,
    options: &ImportOptions,
    time: Option<f64>,
) -> Result<(Groom, Vec<String>)> {
    groom_from_layer_in(layer, None, path, options, time)
}

/// [`groom_from_layer`] of a layer whose [`Value::InFile`] arrays are in `arrays`.
pub fn groom_from_layer_in(
    mut layer: Layer,
    arrays: Option<&dyn FileArrays>,
    path: &Path,
    options: &ImportOptions,
    time: Option<f64>,
) -> Result<(Groom, Vec<String>)> {
    let stage = stage_transform(&layer, path, options)?;
    let layer_lines = layer.lines;
    let authored_start = layer.timeline.start;
    let ranged = layer.timeline.frame_range().is_some();
    let sources = std::mem::take(&mut layer.sources);
    let files = SiteFiles::new(path, &sources);
    let mut walker = Walker {
        files,
        arrays,
        time,
        stage,
        found: Vec::new(),
        meshes: Vec::new(),
        first_sample: None,
        first_visibility: None,
        left_out: RefCell::new(Vec::new()),
    };
    for prim in layer.prims {
        walker.visit(prim, "", DMat4::IDENTITY, None, Imageable::default())?;
    }
    // A frame before the first time sample of everything that places the curves and meshes
    // (their points, the transforms above them) is a frame the animation never reached (0
    // when it starts at 1): refused, not clamped, as for Alembic — unless the stage's own range
    // (`startTimeCode`) holds it: a shot's range may start before its groom's first sample, and
    // there the first value holds, as pxr reads it. After the last sample the last value holds
    // too: a shot often runs past a groom's final sample.
    if let (Some(at), Some(first)) = (time, &walker.first_sample) {
        if at < first.time && authored_start.is_none_or(|start| at < start) {
            return Err(files.error(
                first.site,
                format!(
                    "frame {} is before the first time sample ({}) of '{}' and of everything else that \
                     places the groom",
                    crate::validate::shortest(at),
                    crate::validate::shortest(first.time),
                    first.attribute
                ),
            ));
        }
    }
    // Time samples without a frame range: every reader sees one moment (`coif convert` writes a
    // static file, `info` finds no frames), which the user should hear about.
    let mut warnings = Vec::new();
    let sampled = walker.first_sample.as_ref().or(walker.first_visibility.as_ref());
    if let (None, false, Some(first)) = (time, ranged, sampled) {
        warnings.push(format!(
            "{}: '{}' is time-sampled but the stage authors no frame range (startTimeCode < \
             endTimeCode): read as one moment, each value's default or else its earliest sample; \
             --frame N reads another, and `coif convert --frame-range FIRST:LAST` the animation",
            path.display(),
            first.attribute
        ));
    }
    warnings.extend(walker.left_out.take());
    let mut groom = merge(walker.found, arrays, files, path, layer_lines)?;
    groom.meshes = walker.meshes;
    Ok((groom, warnings))
}

struct Walker<'a> {
    files: SiteFiles<'a>,
    arrays: Option<&'a dyn FileArrays>,
    time: Option<f64>,
    stage: DMat4,
    found: Vec<Curves>,
    meshes: Vec<SurfaceMesh>,
    /// The earliest time sample kept of anything that places a curve or mesh prim read.
    first_sample: Option<FirstSample>,
    /// The earliest time sample of an imageable prim's `visibility` (it shows or hides, but
    /// does not place, what is below it).
    first_visibility: Option<FirstSample>,
    /// Warnings: primvars whose elements hold more values than a groom attribute can.
    left_out: RefCell<Vec<String>>,
}

/// The earliest time sample (kept by the parser) of an attribute, and which attribute it is.
#[derive(Clone)]
struct FirstSample {
    time: f64,
    attribute: String,
    site: Site,
}

impl FirstSample {
    /// The earlier of `a` and the first sample of `prim_path`'s attribute `attribute`.
    fn earlier(a: Option<FirstSample>, prim_path: &str, attribute: &Attribute) -> Option<FirstSample> {
        let Some(&(time, _)) = attribute.samples.first() else { return a };
        match a {
            Some(a) if a.time <= time => Some(a),
            _ => Some(FirstSample {
                time,
                attribute: format!("{prim_path}.{}", attribute.name),
                site: attribute.site,
            }),
        }
    }
}

/// What a prim inherits from its imageable ancestors (UsdGeomImageable): the `purpose` of the
/// nearest one that authors it (a prim's own, when authored, wins), and whether any of them is
/// `invisible` (no descendant can be visible again). As pxr computes them, prims that are not
/// imageable (typeless, materials) neither set nor stop either.
#[derive(Clone, Debug, Default)]
struct Imageable {
    purpose: Option<String>,
    invisible: bool,
}

impl Imageable {
    /// Prim types of UsdGeom and UsdSkel that are imageable and may hold or group curves.
    fn is_imageable(type_name: &str) -> bool {
        matches!(
            type_name,
            "Xform"
                | "Scope"
                | "BasisCurves"
                | "NurbsCurves"
                | "HermiteCurves"
                | "Mesh"
                | "Points"
                | "PointInstancer"
                | "SkelRoot"
                | "Skeleton"
                | "Capsule"
                | "Cone"
                | "Cube"
                | "Cylinder"
                | "Sphere"
                | "Plane"
                | "Camera"
        )
    }
}

impl Walker<'_> {
    /// `chain_first`: the earliest time sample of the transforms above `prim`; `inherited`: the
    /// purpose and visibility its ancestors give it.
    fn visit(
        &mut self,
        mut prim: Prim,
        parent_path: &str,
        parent: DMat4,
        chain_first: Option<FirstSample>,
        inherited: Imageable,
    ) -> Result<()> {
        if !prim.is_defined_and_active() {
            return Ok(());
        }
        let prim_path = format!("{parent_path}/{}", prim.name);
        let imageable = if Imageable::is_imageable(&prim.type_name) {
            let purpose = self.token(&prim, &prim_path, "purpose")?;
            let visibility = self.token(&prim, &prim_path, "visibility")?;
            if let Some(sampled) = prim.attribute("visibility") {
                self.first_visibility =
                    FirstSample::earlier(self.first_visibility.take(), &prim_path, sampled);
            }
            Imageable {
                purpose: purpose.or(inherited.purpose),
                invisible: inherited.invisible || visibility.as_deref() == Some("invisible"),
            }
        } else {
            inherited
        };
        let (local, reset) =
            local_transform(&prim, self.time).map_err(|(site, m)| self.error(&prim_path, site, m))?;
        // `!resetXformStack!`: the ancestors' transforms do not apply to this prim.
        let world = if reset { local } else { parent * local };
        let transforms = prim.attributes.iter().filter(|a| a.name.starts_with("xformOp"));
        let chain_first = transforms.fold(if reset { None } else { chain_first }, |first, a| {
            FirstSample::earlier(first, &prim_path, a)
        });
        let children = std::mem::take(&mut prim.children);
        let placed = |prim: &Prim| {
            let points = prim.attribute("points");
            points.map_or(chain_first.clone(), |p| FirstSample::earlier(chain_first.clone(), &prim_path, p))
        };
        let mut first_here = None;
        if matches!(prim.type_name.as_str(), "BasisCurves" | "NurbsCurves") {
            first_here = placed(&prim);
            if let Some(curves) = self.curves(&mut prim, &prim_path, world, &imageable)? {
                self.found.push(curves);
            }
        } else if prim.type_name == "HermiteCurves" && prim.attribute("points").is_some() {
            // Curves coif would otherwise leave out without a word.
            return Err(self.error(
                &prim_path,
                prim.site,
                "a HermiteCurves prim: coif reads hair from BasisCurves (linear, Bézier, B-spline, \
                 Catmull-Rom) and NurbsCurves of degree 1 or 3; export these curves as one of those",
            ));
        } else if prim.type_name == "Mesh" {
            first_here = placed(&prim);
            if let Some(mesh) = self.mesh(&mut prim, &prim_path, world)? {
                self.meshes.push(SurfaceMesh { invisible: imageable.invisible, ..mesh });
            }
        }
        if let Some(first) = first_here {
            if self.first_sample.as_ref().is_none_or(|f| first.time < f.time) {
                self.first_sample = Some(first);
            }
        }
        for child in children {
            self.visit(child, &prim_path, world, chain_first.clone(), imageable.clone())?;
        }
        Ok(())
    }

    /// The value of `prim`'s token attribute `name` at the walker's time, when authored.
    fn token(&self, prim: &Prim, prim_path: &str, name: &str) -> Result<Option<String>> {
        match prim.attribute(name).and_then(|a| value_at(a, self.time).map(|v| (a.site, v))) {
            None => Ok(None),
            Some((_, Value::Text(t))) if t.len() == 1 => Ok(Some(t[0].clone())),
            Some((site, _)) => Err(self.error(prim_path, site, format!("'{name}' must be a token"))),
        }
    }

    fn error(&self, prim_path: &str, site: Site, message: impl std::fmt::Display) -> Error {
        self.files.error(site, format!("prim <{prim_path}>: {message}"))
    }

    /// Warns that a primvar is left out: its elements hold more values than a groom attribute.
    fn leave_out(&self, site: Site, prim_path: &str, primvar: &str, components: usize) {
        let message = format!("prim <{prim_path}>: {}", GroomAttribute::left_out(primvar, components));
        self.left_out.borrow_mut().push(self.files.error(site, message).to_string());
    }

    /// `value`, read from the file if it is still there.
    fn read(&self, value: Value) -> std::result::Result<Value, String> {
        let Value::InFile(array) = value else { return Ok(value) };
        let mut floats = Vec::with_capacity(array.bytes / 4);
        append_array(self.arrays, &array, &mut floats)?;
        Ok(match array.components {
            3 => Value::Vec3(vec3s(floats)),
            _ => Value::F32(floats),
        })
    }

    /// Reads one `Mesh` prim (a scalp, head or body) in coif's space, wound counter-clockwise;
    /// `None` when it has no points or faces (an empty placeholder).
    fn mesh(&self, prim: &mut Prim, prim_path: &str, world: DMat4) -> Result<Option<SurfaceMesh>> {
        let time = self.time;
        let at_prim = |site: Site, message: String| self.error(prim_path, site, message);
        let Some(points_attr) = prim.attributes.iter_mut().find(|a| a.name == "points") else {
            return Ok(None);
        };
        let points_site = points_attr.site;
        let points = take_value(points_attr, time).map(|v| self.read(v)).transpose();
        let points: Vec<Vec3> = match points.map_err(|m| at_prim(points_site, format!("points: {m}")))? {
            None => return Ok(None),
            Some(Value::Vec3(points)) => points,
            Some(other) => match other.to_f32() {
                Some(flat) if flat.len() % 3 == 0 => flat.chunks_exact(3).map(Vec3::from_slice).collect(),
                _ => return Err(at_prim(points_site, "'points' must be a point3f[] array".into())),
            },
        };
        // Taken, not copied, from the layer (the scalp's indices are the mesh's bulk); every
        // value is checked before any is narrowed.
        let mut ints = |name: &str| -> Result<Option<Vec<u32>>> {
            let Some(attribute) = prim.attributes.iter_mut().find(|a| a.name == name) else {
                return Ok(None);
            };
            declared_int_array(attribute).map_err(|m| at_prim(attribute.site, m))?;
            match take_value(attribute, time) {
                None => Ok(None),
                // Branch-free: a negative value is above u32::MAX as u64 too.
                Some(Value::Int(values))
                    if values.iter().fold(0, |high, &v| high.max(v as u64)) <= u32::MAX as u64 =>
                {
                    Ok(Some(values.into_iter().map(|v| v as u32).collect()))
                }
                Some(Value::Int(_)) => {
                    Err(at_prim(attribute.site, format!("'{name}' holds a negative value")))
                }
                Some(_) => Err(at_prim(attribute.site, format!("'{name}' must be an int[] array"))),
            }
        };
        let face_counts = ints("faceVertexCounts")?;
        let face_indices = ints("faceVertexIndices")?;
        let (Some(face_counts), Some(face_indices)) = (face_counts, face_indices) else {
            return Ok(None);
        };
        if face_counts.is_empty() {
            return Ok(None);
        }
        let to_coif = self.stage * world;
        let mut mesh = SurfaceMesh {
            path: prim_path.to_string(),
            points,
            face_counts,
            face_indices,
            primvars: Vec::new(),
            invisible: false,
            holes: ints("holeIndices")?.unwrap_or_default(),
        };
        let (primvars, left_out) = mesh_primvars(prim, time).map_err(|(site, m)| at_prim(site, m))?;
        mesh.primvars = primvars;
        for (site, name, components) in left_out {
            self.leave_out(site, prim_path, &format!("primvars:{name}"), components);
        }
        let left_handed = match prim.attribute("orientation").and_then(|a| value_at(a, time)) {
            Some(Value::Text(t)) if t.len() == 1 => t[0] == "leftHanded",
            _ => false,
        };
        mesh.check().map_err(|problem| at_prim(prim.site, format!("mesh: {problem}")))?;
        mesh.transform(to_coif);
        // A mirroring transform turns the winding too.
        if left_handed != (to_coif.determinant() < 0.0) {
            mesh.flip_winding();
        }
        Ok(Some(mesh))
    }

    /// The basis and wrap that draw a `NurbsCurves` prim's curves (Maya's USD
    /// export writes every nurbsCurve so), as for Maya's Alembic curves: degree 1 (order 2) is a
    /// polyline, degree 3 (order 4) a cubic B-spline, `pinned` where every curve's knots are
    /// clamped (as Maya writes them: the curve starts at its first control point, the root) and
    /// `nonperiodic` where none is. Interior knot spacing is not kept (a uniform B-spline takes
    /// its place). Other degrees, mixed degrees, mixed clamping and rational curves (weights other
    /// than 1) exit 2 naming the prim.
    fn nurbs_shape(&self, prim: &Prim, prim_path: &str) -> Result<(CurveBasis, CurveWrap)> {
        let time = self.time;
        let fail = |name: &str, message: String| {
            let site = prim.attribute(name).map_or(prim.site, |a| a.site);
            self.error(prim_path, site, format!("NurbsCurves {message}"))
        };
        let ints = |name: &str| match prim.attribute(name).and_then(|a| value_at(a, time)) {
            Some(Value::Int(values)) => Some(values),
            _ => None,
        };
        if let Some(attribute) = prim.attribute("order") {
            declared_int_array(attribute).map_err(|m| fail("order", m))?;
        }
        let Some(orders) = ints("order") else {
            return Err(fail("order", "without an int[] 'order' (the degree of each curve + 1)".into()));
        };
        let Some(&order) = orders.first() else {
            return Err(fail("order", "with an empty 'order'".into()));
        };
        if let Some(other) = orders.iter().find(|&&o| o != order) {
            return Err(fail(
                "order",
                format!("of orders {order} and {other} mixed: coif needs one degree per prim"),
            ));
        }
        let basis = CurveBasis::of_nurbs_order(order as f64).map_err(|m| fail("order", m))?;
        let doubles = |name: &str| -> Result<Option<Vec<f64>>> {
            match prim.attribute(name).and_then(|a| value_at(a, time)) {
                None => Ok(None),
                Some(value) => match self.read(value).map(|v| v.to_f64()) {
                    Ok(Some(values)) => Ok(Some(values)),
                    _ => Err(fail(name, format!("'{name}' must be a double[] array"))),
                },
            }
        };
        if let Some(weights) = doubles("pointWeights")? {
            if let Some(w) = weights.iter().find(|&&w| w != 1.0) {
                return Err(fail(
                    "pointWeights",
                    format!("with a point weight of {w}: rational curves are not hair"),
                ));
            }
        }
        if basis == CurveBasis::Linear {
            return Ok((basis, CurveWrap::Nonperiodic));
        }
        let counts = ints("curveVertexCounts").unwrap_or_default();
        let knots = doubles("knots")?.unwrap_or_default();
        let needed = counts.iter().fold(0i64, |sum, &c| sum.saturating_add(c.max(0).saturating_add(order)));
        let clamped = if knots.is_empty() {
            // No knots: USD's fallback is a uniform knot vector.
            false
        } else if knots.len() as i64 != needed {
            return Err(fail(
                "knots",
                format!("with {} knots where its curves need {needed} (vertices + order each)", knots.len()),
            ));
        } else {
            let order = order as usize;
            let mut at = 0;
            let clamped_curves = counts
                .iter()
                .filter(|&&count| {
                    let curve = &knots[at..at + count.max(0) as usize + order];
                    at += curve.len();
                    let (first, last) = (curve[0], curve[curve.len() - 1]);
                    curve[..order].iter().all(|&k| k == first)
                        && curve[curve.len() - order..].iter().all(|&k| k == last)
                })
                .count();
            match clamped_curves {
                0 => false,
                n if n == counts.len() => true,
                _ => return Err(fail("knots", "whose curves are clamped and not clamped mixed".into())),
            }
        };
        let wrap = if clamped { CurveWrap::Pinned } else { CurveWrap::Nonperiodic };
        Ok((basis, wrap))
    }

    /// Reads one `BasisCurves` or `NurbsCurves` prim; `None` when it has no points (an empty
    /// placeholder).
    fn curves(
        &self,
        prim: &mut Prim,
        prim_path: &str,
        world: DMat4,
        imageable: &Imageable,
    ) -> Result<Option<Curves>> {
        let time = self.time;
        let at_prim = |site: Site, message: String| self.error(prim_path, site, message);
        let token = |prim: &Prim, name: &str, fallback: &str| -> Result<String> {
            Ok(self.token(prim, prim_path, name)?.unwrap_or_else(|| fallback.to_string()))
        };
        let (basis, wrap) = if prim.type_name == "NurbsCurves" {
            self.nurbs_shape(prim, prim_path)?
        } else {
            let curve_type = token(prim, "type", "cubic")?;
            let basis_name = token(prim, "basis", "bezier")?;
            let wrap = token(prim, "wrap", "nonperiodic")?;
            let basis = match (curve_type.as_str(), basis_name.as_str()) {
                ("linear", _) => CurveBasis::Linear,
                ("cubic", "bezier") => CurveBasis::Bezier,
                ("cubic", "bspline") => CurveBasis::BSpline,
                ("cubic", "catmullRom") => CurveBasis::CatmullRom,
                ("cubic", other) => {
                    return Err(at_prim(prim.site, format!("unsupported cubic basis \"{other}\"")))
                }
                (other, _) => return Err(at_prim(prim.site, format!("unknown curve type \"{other}\""))),
            };
            let wrap =
                match wrap.as_str() {
                    "nonperiodic" => CurveWrap::Nonperiodic,
                    "pinned" => CurveWrap::Pinned,
                    "periodic" => return Err(at_prim(
                        prim.site,
                        "wrap \"periodic\" (closed curves) is not supported: coif cannot simulate closed \
                         strands"
                            .into(),
                    )),
                    other => return Err(at_prim(prim.site, format!("unknown wrap \"{other}\""))),
                };
            (basis, wrap)
        };
        let purpose = imageable.purpose.clone().filter(|p| p != "default");

        let Some(points_attr) = prim.attributes.iter_mut().find(|a| a.name == "points") else {
            return Ok(None);
        };
        let points_site = points_attr.site;
        let points = match take_value(points_attr, time) {
            None => return Ok(None),
            Some(Value::InFile(array)) if array.components == 3 => Bulk::InFile(array),
            Some(Value::Vec3(points)) => Bulk::Read(points),
            // point3d[] and other numeric spellings of 3-vectors.
            Some(other) => {
                match self.read(other).map_err(|m| at_prim(points_site, format!("points: {m}")))?.to_f32() {
                    Some(flat) if flat.len() % 3 == 0 => {
                        Bulk::Read(flat.chunks_exact(3).map(Vec3::from_slice).collect())
                    }
                    _ => return Err(at_prim(points_site, "'points' must be a point3f[] array".into())),
                }
            }
        };
        let counts_attr = prim.attribute("curveVertexCounts");
        let counts_site = counts_attr.map_or(prim.site, |a| a.site);
        if let Some(attribute) = counts_attr {
            declared_int_array(attribute).map_err(|m| at_prim(counts_site, m))?;
        }
        let counts: Vec<u32> = match counts_attr.and_then(|a| value_at(a, time)) {
            Some(Value::Int(counts)) => counts
                .iter()
                .map(|&c| u32::try_from(c).ok().filter(|&c| c > 0))
                .collect::<Option<_>>()
                .ok_or_else(|| {
                    at_prim(counts_site, "curveVertexCounts holds a count that is not positive".into())
                })?,
            Some(_) => return Err(at_prim(counts_site, "'curveVertexCounts' must be an int[] array".into())),
            None => return Err(at_prim(points_site, "points without curveVertexCounts".into())),
        };
        let total: u64 = counts.iter().map(|&c| c as u64).sum();
        if total != points.len() as u64 {
            return Err(at_prim(
                points_site,
                format!("curveVertexCounts add up to {total} points but 'points' has {}", points.len()),
            ));
        }
        if let Some((curve, &count)) =
            counts.iter().enumerate().find(|&(_, &c)| !primvar_rates::is_whole_curve(basis, wrap, c as usize))
        {
            return Err(at_prim(
                counts_site,
                format!(
                    "curve {curve} has {count} control points; {basis:?} curves need {}",
                    primvar_rates::whole_curve_rule(basis)
                ),
            ));
        }
        let layout = Layout { counts: &counts, points: points.len(), basis, wrap };

        let mut width_interpolation = None;
        // `primvars:widths` wins over `widths`, as in USD; as a primvar it may be indexed, and its
        // fallback interpolation is `constant`.
        let width_name = if prim.attribute(WIDTHS_PRIMVAR).is_some() { WIDTHS_PRIMVAR } else { "widths" };
        let width_indices = prim
            .attribute(&format!("{WIDTHS_PRIMVAR}:indices"))
            .filter(|_| width_name == WIDTHS_PRIMVAR)
            .and_then(|a| value_at(a, time))
            .map(|v| v.to_f64());
        let widths = match prim.attributes.iter_mut().find(|a| a.name == width_name) {
            None => None,
            Some(attr) => {
                let site = attr.site;
                let fallback = if width_name == WIDTHS_PRIMVAR { "constant" } else { "vertex" };
                let interpolation = attr.interpolation.clone().unwrap_or_else(|| fallback.into());
                match take_value(attr, time) {
                    None => None,
                    // Per-vertex widths in a crate file: read by `merge`, straight into place.
                    Some(Value::InFile(array))
                        if interpolation == "vertex"
                            && width_indices.is_none()
                            && array.components == 1
                            && array.elements() == points.len() =>
                    {
                        Some(Bulk::InFile(array))
                    }
                    Some(value) => {
                        let value =
                            self.read(value).map_err(|m| at_prim(site, format!("{width_name}: {m}")))?;
                        let mut values = value.into_f32().ok_or_else(|| {
                            at_prim(site, format!("'{width_name}' must be a float[] array"))
                        })?;
                        if let Some(indices) = width_indices {
                            let indices = indices.ok_or_else(|| {
                                at_prim(site, format!("{WIDTHS_PRIMVAR}:indices must be int[]"))
                            })?;
                            values = expand_indices(&values, &indices, 1)
                                .map_err(|m| at_prim(site, format!("{WIDTHS_PRIMVAR}:indices: {m}")))?;
                        }
                        let (rate, data) = layout
                            .resolve(values, 1, &interpolation)
                            .map_err(|m| at_prim(site, format!("{width_name}: {m}")))?;
                        // Kept per vertex; the file's rate goes back out with them.
                        width_interpolation = match interpolation.as_str() {
                            "constant" => Some(Interpolation::Constant),
                            "uniform" => Some(Interpolation::Uniform),
                            "varying" => Some(Interpolation::Varying),
                            _ => None,
                        };
                        Some(Bulk::Read(layout.to_vertex(rate, 1, data)))
                    }
                }
            }
        };

        let mut curves = Curves {
            path: prim_path.to_string(),
            site: prim.site,
            basis,
            wrap,
            purpose,
            invisible: imageable.invisible,
            counts: counts.clone(),
            points,
            widths,
            to_coif: self.stage * world,
            strand_ids: None,
            root_uvs: None,
            guides: None,
            attributes: Vec::new(),
            interpolations: Vec::new(),
            element_sized: Vec::new(),
            width_interpolation,
        };
        // Primvars, and the curves' own `normals`, `velocities` and `accelerations` read as the
        // attributes of those names (`primvars:normals` wins over `normals`, as in USD).
        let mut primvar_names: Vec<(String, String)> = prim
            .attributes
            .iter()
            .filter(|a| a.name != WIDTHS_PRIMVAR)
            .filter_map(|a| a.name.strip_prefix("primvars:"))
            .filter(|n| !n.ends_with(":indices"))
            .map(|n| (format!("primvars:{n}"), n.to_string()))
            .collect();
        for name in point_attributes::SCHEMA_NAMES {
            if prim.attribute(name).is_some() && primvar_names.iter().all(|(_, n)| n != name) {
                primvar_names.push((name.to_string(), name.to_string()));
            }
        }
        let has_st = prim.attribute(&format!("primvars:{}", names::ST)).is_some();
        for (full_name, name) in primvar_names {
            let is_primvar = full_name.starts_with("primvars:");
            let indices_attribute =
                prim.attribute(&format!("primvars:{name}:indices")).filter(|_| is_primvar);
            if let Some(attribute) = indices_attribute {
                declared_int_array(attribute).map_err(|m| at_prim(attribute.site, m))?;
            }
            let indices = indices_attribute.and_then(|a| value_at(a, time)).map(|v| v.to_f64());
            let attr = prim.attributes.iter_mut().find(|a| a.name == full_name).unwrap();
            let site = attr.site;
            let type_name = attr.type_name.trim_end_matches("[]").to_string();
            // USD's fallbacks: `constant` for primvars; the others are per point.
            let fallback = if is_primvar { "constant" } else { "vertex" };
            let interpolation = attr.interpolation.clone().unwrap_or_else(|| fallback.into());
            let (kind_components, element_size) =
                (super::parser::type_info(&attr.type_name).1, attr.element_size);
            let Some(value) = take_value(attr, time) else { continue };
            let value = self.read(value).map_err(|m| at_prim(site, format!("{full_name}: {m}")))?;
            let Some(values) = attribute_data(value, &type_name) else { continue }; // strings, tokens

            if !is_primvar && values.is_empty() {
                continue; // an empty `velocities` or `normals`: none, as pxr reads it
            }
            let components = element_components(kind_components, element_size, values.len())
                .map_err(|m| at_prim(site, format!("{full_name}: {m}")))?;
            if components > GroomAttribute::MAX_COMPONENTS {
                // Left out, but only when its count fits the curves: else the file is wrong.
                let elements = values.len() / components;
                layout
                    .resolve(vec![0i64; elements], 1, &interpolation)
                    .map_err(|m| at_prim(site, format!("{full_name}: {m}")))?;
                self.leave_out(site, prim_path, &full_name, components);
                continue;
            }
            let mut values = values;
            if let Some(indices) = indices {
                let indices =
                    indices.ok_or_else(|| at_prim(site, format!("primvars:{name}:indices must be int[]")))?;
                values = match values {
                    AttributeData::Float(v) => {
                        expand_indices(&v, &indices, components).map(AttributeData::Float)
                    }
                    AttributeData::Int(v) => expand_indices(&v, &indices, components).map(AttributeData::Int),
                }
                .map_err(|m| at_prim(site, format!("primvars:{name}:indices: {m}")))?;
            }
            let (rate, data) = match values {
                AttributeData::Float(v) => {
                    layout.resolve(v, components, &interpolation).map(|(r, d)| (r, d.into()))
                }
                AttributeData::Int(v) => {
                    layout.resolve(v, components, &interpolation).map(|(r, d)| (r, AttributeData::Int(d)))
                }
            }
            .map_err(|m| at_prim(site, format!("{full_name}: {m}")))?;
            let floats = || data.floats(integer_kind(&type_name).unwrap_or_default());
            match (name.as_str(), rate, components) {
                (names::ST, AttributeRate::Strand, 2) => {
                    curves.root_uvs = Some(floats().chunks_exact(2).map(|c| [c[0], c[1]]).collect());
                }
                (names::GROOM_ID, AttributeRate::Strand, 1) => {
                    let ids = match &data {
                        AttributeData::Int(ids) => {
                            ids.iter().map(|&v| u32::try_from(v).ok()).collect::<Option<_>>()
                        }
                        AttributeData::Float(ids) => {
                            ids.iter().map(|&v| (v >= 0.0 && v.fract() == 0.0).then_some(v as u32)).collect()
                        }
                    };
                    curves.strand_ids = Some(ids.ok_or_else(|| {
                        at_prim(site, "groom_id values must be non-negative integers".into())
                    })?);
                }
                (names::GROOM_GUIDE, AttributeRate::Strand, 1) => {
                    curves.guides = Some(floats().iter().map(|&v| v != 0.0).collect());
                }
                // Unreal's root UVs (`--unreal` writes them beside `st`, which wins).
                (epic::ROOT_UV, AttributeRate::Strand, 2) => {
                    if !has_st {
                        curves.root_uvs = Some(floats().chunks_exact(2).map(|c| [c[0], c[1]]).collect());
                    }
                }
                _ => {
                    // Epic's names as in Alembic: a `--unreal` stage reads back as coif wrote it.
                    let groom_name =
                        crate::io::unreal::attribute_for_epic_name(&names::attribute_for_primvar(&name));
                    let kind = attribute_kind(&type_name, &groom_name, components);
                    let interpolation = match interpolation.as_str() {
                        "constant" => Some(Interpolation::Constant),
                        "varying" if layout.varying_is_vertex() => Some(Interpolation::Varying),
                        _ => None,
                    };
                    if let Some(interpolation) = interpolation {
                        curves.interpolations.push((groom_name.clone(), interpolation));
                    }
                    if kind_components == 1 && components > 1 {
                        curves.element_sized.push(groom_name.clone());
                    }
                    curves.attributes.push(GroomAttribute { name: groom_name, rate, components, data, kind });
                }
            }
        }

        // World transform composed with the stage's units and up axis (points and widths follow
        // in `merge`).
        if curves.to_coif != DMat4::IDENTITY {
            crate::io::transform_attributes(&mut curves.attributes, curves.to_coif);
        }
        Ok(Some(curves))
    }
}

/// A `Mesh` prim's primvars (and its `normals`, as the primvar `normals`; `primvars:normals`
/// wins over them, as in USD), in file space. Strings and tokens are not mesh data and are left
/// out. Errors carry the line.
/// Also returns the primvars left out (their site, name and values per element): those with more
/// values per element than coif's data model holds.
#[allow(clippy::type_complexity)]
fn mesh_primvars(
    prim: &Prim,
    time: Option<f64>,
) -> std::result::Result<(Vec<MeshPrimvar>, Vec<(Site, String, usize)>), (Site, String)> {
    let mut primvars: Vec<MeshPrimvar> = Vec::new();
    let mut left_out = Vec::new();
    let has_primvar_normals = prim.attribute("primvars:normals").is_some();
    for attribute in &prim.attributes {
        let name = match attribute.name.strip_prefix("primvars:") {
            Some(name) if !name.ends_with(":indices") => name,
            None if attribute.name == MeshPrimvar::NORMALS && !has_primvar_normals => MeshPrimvar::NORMALS,
            _ => continue,
        };
        let site = attribute.site;
        let fail = |message: String| (site, format!("primvar '{name}': {message}"));
        // USD's fallbacks: `constant` for primvars, `vertex` for a point-based prim's normals.
        let fallback = if attribute.name == MeshPrimvar::NORMALS { "vertex" } else { "constant" };
        let token = attribute.interpolation.as_deref().unwrap_or(fallback);
        let interpolation = MeshInterpolation::from_usd(token)
            .ok_or_else(|| fail(format!("unknown interpolation \"{token}\"")))?;
        let Some(value) = value_at(attribute, time) else { continue };
        let type_name = attribute.type_name.trim_end_matches("[]");
        let Some(values) = attribute_data(value, type_name) else { continue };
        let components = element_components(
            super::parser::type_info(&attribute.type_name).1,
            attribute.element_size,
            values.len(),
        )
        .map_err(fail)?;
        if components > GroomAttribute::MAX_COMPONENTS {
            left_out.push((site, name.to_string(), components));
            continue;
        }
        let indices_attribute = prim.attribute(&format!("primvars:{name}:indices"));
        if let Some(attribute) = indices_attribute {
            declared_int_array(attribute).map_err(fail)?;
        }
        let indices = match indices_attribute.and_then(|a| value_at(a, time)) {
            None => None,
            Some(Value::Int(indices)) => Some(
                indices
                    .iter()
                    .map(|&i| u32::try_from(i).ok())
                    .collect::<Option<Vec<u32>>>()
                    .ok_or_else(|| fail("an index is negative".into()))?,
            ),
            Some(_) => return Err(fail("its indices must be int[]".into())),
        };
        primvars.push(MeshPrimvar {
            name: name.to_string(),
            kind: attribute_kind(type_name, name, components),
            components,
            interpolation,
            values,
            indices,
        });
    }
    Ok((primvars, left_out))
}

/// Values per element of a primvar of `values` values: its type's tuple (`float3`: 3) times its
/// `elementSize`. pxr refuses to author an `elementSize` below 1, and the values must make whole
/// elements: else the file is wrong, and the error says so (an `elementSize = 1e9` primvar was
/// dropped without a word).
fn element_components(
    tuple: usize,
    element_size: Option<i64>,
    values: usize,
) -> std::result::Result<usize, String> {
    let size = element_size.unwrap_or(1);
    if size < 1 {
        return Err(format!("elementSize = {size} must be at least 1"));
    }
    let components = usize::try_from(size).ok().and_then(|s| s.checked_mul(tuple)).unwrap_or(usize::MAX);
    if values % components != 0 {
        let per_value = if tuple > 1 { format!(" × {tuple} numbers per value") } else { String::new() };
        return Err(format!(
            "{values} numbers do not make whole elements of elementSize = {size}{per_value} ({components} numbers each)"
        ));
    }
    Ok(components)
}

/// The integer kind of a USD integer type (held exactly), `None` for others (`bool` is a flag).
fn integer_kind(type_name: &str) -> Option<AttributeKind> {
    match type_name {
        "int" | "int2" | "int3" | "int4" | "uchar" => Some(AttributeKind::Int),
        "uint" => Some(AttributeKind::UInt),
        "int64" => Some(AttributeKind::Int64),
        "uint64" => Some(AttributeKind::UInt64),
        _ => None,
    }
}

/// Refuses a topology attribute (`curveVertexCounts`, a mesh's face lists, NURBS `order`, a
/// primvar's `:indices`) declared other than `int[]`, the schemas' type: pxr reads no value of
/// another type from it (a `uint[]` or `int64[]` `curveVertexCounts` gives it no curves, a
/// scalar `int` none either; `int64[]` indices are "no indices authored").
fn declared_int_array(attribute: &Attribute) -> std::result::Result<(), String> {
    // An `over` may leave the type to the layer that declares it.
    if attribute.type_name.is_empty() || (attribute.type_name == "int" && attribute.array) {
        return Ok(());
    }
    let brackets = if attribute.array { "[]" } else { "" };
    Err(format!(
        "'{}' is declared {}{brackets}; USD reads it only as int[] (pxr finds no value in it)",
        attribute.name, attribute.type_name
    ))
}

/// A value of USD type `type_name` as groom data: integer types as integers (ids past 2^24 do
/// not survive `f32`), other numbers as floats; `None` for text.
fn attribute_data(value: Value, type_name: &str) -> Option<AttributeData> {
    match value {
        Value::Int(values) if integer_kind(type_name).is_some() => Some(AttributeData::Int(values)),
        value => value.into_f32().map(AttributeData::Float),
    }
}

/// The kind a primvar's USD type gives an attribute; plain floats when the type is the one
/// coif's writer would choose for that name anyway, so what coif writes reads back unchanged.
fn attribute_kind(type_name: &str, name: &str, components: usize) -> AttributeKind {
    if let Some(kind) = integer_kind(type_name) {
        return kind;
    }
    let kind = match type_name {
        "bool" => AttributeKind::Bool,
        t if t.starts_with("point3") => AttributeKind::Point,
        t if t.starts_with("normal3") => AttributeKind::Normal,
        t if t.starts_with("vector3") => AttributeKind::Vector,
        t if t.starts_with("color") => AttributeKind::Color,
        t if t.starts_with("texCoord") => AttributeKind::TexCoord,
        _ => AttributeKind::Float,
    };
    let written_as_float = crate::io::usd_stage::usd_type(AttributeKind::Float, name, components);
    if written_as_float.trim_end_matches("[]") == type_name {
        AttributeKind::Float
    } else {
        kind
    }
}

/// How many values each interpolation needs, and how to turn them into per-vertex values.
struct Layout<'a> {
    counts: &'a [u32],
    points: usize,
    basis: CurveBasis,
    wrap: CurveWrap,
}

impl Layout<'_> {
    /// Values per curve for `varying` interpolation (one per segment end).
    fn varying_count(&self, vertices: u32) -> usize {
        primvar_rates::varying_count(self.basis, self.wrap, vertices as usize)
    }

    /// Whether `varying` values are one per vertex (linear or pinned non-Bézier curves).
    fn varying_is_vertex(&self) -> bool {
        self.counts.iter().all(|&c| self.varying_count(c) == c as usize)
    }

    /// Checks the value count against the interpolation and returns per-strand or per-vertex data.
    fn resolve<T: primvar_rates::Spread>(
        &self,
        values: Vec<T>,
        components: usize,
        interpolation: &str,
    ) -> std::result::Result<(AttributeRate, Vec<T>), String> {
        let strands = self.counts.len();
        let found = values.len() / components;
        let expect = |n: usize| {
            if found == n {
                Ok(())
            } else {
                Err(format!("{interpolation} interpolation needs {n} values, found {found}"))
            }
        };
        match interpolation {
            "constant" => {
                expect(1)?;
                Ok((AttributeRate::Strand, values.repeat(strands)))
            }
            "uniform" => {
                expect(strands)?;
                Ok((AttributeRate::Strand, values))
            }
            "vertex" => {
                expect(self.points)?;
                Ok((AttributeRate::Vertex, values))
            }
            "varying" | "faceVarying" => {
                let needed: usize = self.counts.iter().map(|&c| self.varying_count(c)).sum();
                expect(needed)?;
                if needed == self.points {
                    return Ok((AttributeRate::Vertex, values));
                }
                let counts = self.counts.iter().map(|&c| c as usize);
                let spread =
                    primvar_rates::varying_to_vertex(self.basis, self.wrap, counts, &values, components);
                Ok((AttributeRate::Vertex, spread))
            }
            other => Err(format!("unknown interpolation \"{other}\"")),
        }
    }

    /// Per-vertex values from per-strand or per-vertex ones.
    fn to_vertex(&self, rate: AttributeRate, components: usize, data: Vec<f32>) -> Vec<f32> {
        match rate {
            AttributeRate::Vertex => data,
            AttributeRate::Strand => {
                let mut out = Vec::with_capacity(self.points * components);
                for (s, &count) in self.counts.iter().enumerate() {
                    for _ in 0..count {
                        out.extend_from_slice(&data[s * components..(s + 1) * components]);
                    }
                }
                out
            }
        }
    }
}

/// Appends `array`'s floats, read from `arrays`, to `out`.
fn append_array(
    arrays: Option<&dyn FileArrays>,
    array: &FileArray,
    out: &mut Vec<f32>,
) -> std::result::Result<(), String> {
    match arrays {
        Some(arrays) => arrays.append_floats(array, out),
        None => Err(format!("an array of {} bytes left in a file coif does not have", array.bytes)),
    }
}

fn expand_indices<T: Copy>(
    values: &[T],
    indices: &[f64],
    components: usize,
) -> std::result::Result<Vec<T>, String> {
    let available = values.len() / components;
    let mut out = Vec::with_capacity(indices.len() * components);
    for &index in indices {
        if !(index >= 0.0 && (index as usize) < available) {
            return Err(format!("index {index} is outside the {available} values"));
        }
        let i = index as usize;
        out.extend_from_slice(&values[i * components..(i + 1) * components]);
    }
    Ok(out)
}

/// The value an attribute has at `time`: with a time, the time samples around it (linearly
/// interpolated between two, held before the first and after the last) or else the default;
/// without a time, the default or else the earliest sample. `None` when blocked or unauthored.
pub fn value_at(attribute: &Attribute, time: Option<f64>) -> Option<Value> {
    let from_samples = |samples: &[(f64, Value)]| -> Option<Value> {
        match sample_at(samples, time)? {
            SampleAt::Held(i) => Some(samples[i].1.clone()),
            SampleAt::Between(i) => {
                let ((t0, a), (t1, b)) = (&samples[i], &samples[i + 1]);
                Some(lerp(a, b, (time? - t0) / (t1 - t0)))
            }
        }
    };
    let value = match time {
        Some(_) if !attribute.samples.is_empty() => from_samples(&attribute.samples),
        _ => attribute.default.clone().or_else(|| from_samples(&attribute.samples)),
    }?;
    (value != Value::Blocked).then_some(value)
}

/// Which of an attribute's samples (sorted by time) give its value at `time`.
enum SampleAt {
    /// This sample's value as it is.
    Held(usize),
    /// Interpolated between this sample and the next.
    Between(usize),
}

/// The latest sample at or before `time` (else the first; the first with no time), and whether
/// the value lies between it and the next. A time equal to a sample's takes that sample: a
/// composed time maps a layer's sample onto the stage's frame exactly where pxr finds it.
fn sample_at(samples: &[(f64, Value)], time: Option<f64>) -> Option<SampleAt> {
    if samples.is_empty() {
        return None;
    }
    let Some(t) = time else { return Some(SampleAt::Held(0)) };
    Some(match samples.iter().rposition(|(s, _)| *s <= t) {
        Some(i) if i + 1 < samples.len() && samples[i].0 < t => SampleAt::Between(i),
        Some(i) => SampleAt::Held(i),
        None => SampleAt::Held(0),
    })
}

/// Like [`value_at`] but moves large values out of the attribute instead of copying them
/// (only an interpolated value is computed afresh).
fn take_value(attribute: &mut Attribute, time: Option<f64>) -> Option<Value> {
    let use_default = match time {
        Some(_) => attribute.samples.is_empty(),
        None => attribute.default.is_some(),
    };
    let value = if use_default {
        attribute.default.take()?
    } else {
        match sample_at(&attribute.samples, time)? {
            SampleAt::Between(_) => return value_at(attribute, time),
            SampleAt::Held(i) => std::mem::take(&mut attribute.samples).into_iter().nth(i)?.1,
        }
    };
    (value != Value::Blocked).then_some(value)
}

fn lerp(a: &Value, b: &Value, t: f64) -> Value {
    if t == 0.0 {
        return a.clone();
    }
    match (a, b) {
        (Value::Vec3(a), Value::Vec3(b)) if a.len() == b.len() => {
            Value::Vec3(a.iter().zip(b).map(|(a, b)| a.as_dvec3().lerp(b.as_dvec3(), t).as_vec3()).collect())
        }
        (Value::F32(a), Value::F32(b)) if a.len() == b.len() => Value::F32(
            a.iter().zip(b).map(|(&a, &b)| (a as f64 + (b as f64 - a as f64) * t) as f32).collect(),
        ),
        (Value::F64(a), Value::F64(b)) if a.len() == b.len() => {
            Value::F64(a.iter().zip(b).map(|(&a, &b)| a + (b - a) * t).collect())
        }
        _ => a.clone(),
    }
}

/// Prim types of UsdGeom, UsdSkel and UsdLux that derive from `UsdGeomXformable`.
fn is_xformable(type_name: &str) -> bool {
    (Imageable::is_imageable(type_name) && type_name != "Scope")
        || type_name.ends_with("Light")
        || type_name.ends_with("Light_1")
}

/// A prim's local transform from its `xformOpOrder`, and whether it resets the parent stack.
/// Only xformable prims have one: ops authored on a `Scope`, a typeless prim or a material are
/// not part of any transform, in pxr as here.
pub(crate) fn local_transform(
    prim: &Prim,
    time: Option<f64>,
) -> std::result::Result<(DMat4, bool), (Site, String)> {
    if !is_xformable(&prim.type_name) {
        return Ok((DMat4::IDENTITY, false));
    }
    let Some(order_attribute) = prim.attribute("xformOpOrder") else { return Ok((DMat4::IDENTITY, false)) };
    let Some(order) = value_at(order_attribute, time) else { return Ok((DMat4::IDENTITY, false)) };
    let Value::Text(order) = order else {
        return Err((order_attribute.site, "xformOpOrder must be a token[] array".into()));
    };
    let mut matrix = DMat4::IDENTITY;
    let mut reset = false;
    for op in &order {
        if op == "!resetXformStack!" {
            reset = true;
            matrix = DMat4::IDENTITY;
            continue;
        }
        let (name, invert) = match op.strip_prefix("!invert!") {
            Some(name) => (name, true),
            None => (op.as_str(), false),
        };
        let attribute = prim.attribute(name).ok_or_else(|| {
            (order_attribute.site, format!("xformOpOrder names '{name}' but the prim has no such attribute"))
        })?;
        let values = value_at(attribute, time)
            .and_then(|v| v.to_f64())
            .ok_or_else(|| (attribute.site, format!("'{name}' has no numeric value")))?;
        let mut op_matrix =
            xform_op(name, &values).map_err(|m| (attribute.site, format!("'{name}': {m}")))?;
        if invert {
            op_matrix = op_matrix.inverse();
        }
        // The first op in the order is the outermost (applied last to points).
        matrix *= op_matrix;
    }
    if !matrix.is_finite() {
        return Err((prim.site, "the transform is not finite".into()));
    }
    Ok((matrix, reset))
}

fn xform_op(name: &str, v: &[f64]) -> std::result::Result<DMat4, String> {
    let kind =
        name.strip_prefix("xformOp:").and_then(|rest| rest.split(':').next()).ok_or("not an xformOp")?;
    let need = |n: usize| {
        if v.len() == n {
            Ok(())
        } else {
            Err(format!("expected {n} numbers, found {}", v.len()))
        }
    };
    let axis_rotation = |axis: u8, degrees: f64| {
        let radians = degrees.to_radians();
        match axis {
            b'X' => DMat4::from_rotation_x(radians),
            b'Y' => DMat4::from_rotation_y(radians),
            _ => DMat4::from_rotation_z(radians),
        }
    };
    Ok(match kind {
        "translate" => {
            need(3)?;
            DMat4::from_translation(DVec3::from_slice(v))
        }
        "scale" => {
            need(3)?;
            DMat4::from_scale(DVec3::from_slice(v))
        }
        "rotateX" | "rotateY" | "rotateZ" => {
            need(1)?;
            axis_rotation(kind.as_bytes()[6], v[0])
        }
        "orient" => {
            need(4)?;
            // USD writes quaternions real part first.
            DMat4::from_quat(DQuat::from_xyzw(v[1], v[2], v[3], v[0]).normalize())
        }
        "transform" => {
            need(16)?;
            // USD matrices are row-major for row vectors; read as columns they are the
            // column-vector matrix glam uses.
            DMat4::from_cols_slice(v)
        }
        _ if kind.len() == 9 && kind.starts_with("rotate") => {
            need(3)?;
            // rotateABC: about A first, then B, then C; angles given as (x, y, z).
            let mut m = DMat4::IDENTITY;
            for &axis in &kind.as_bytes()[6..] {
                let angle = match axis {
                    b'X' => v[0],
                    b'Y' => v[1],
                    b'Z' => v[2],
                    _ => return Err(format!("unknown rotation order '{kind}'")),
                };
                m = axis_rotation(axis, angle) * m;
            }
            m
        }
        other => return Err(format!("unknown transform operation '{other}'")),
    })
}

/// One groom from all curve prims, one group per prim, points and widths in coif's space.
/// Strand ids are renumbered unless every prim has them; a lone prim named as coif writes it
/// gets no group table. Arrays still in a crate file are read straight into their place in the
/// groom, so its bulk is copied once, from the file.
fn merge(
    found: Vec<Curves>,
    arrays: Option<&dyn FileArrays>,
    files: SiteFiles,
    path: &Path,
    lines: u32,
) -> Result<Groom> {
    if found.is_empty() {
        return Err(Error::format(
            path,
            format!("line {lines}: the stage ends without a BasisCurves prim with points"),
        ));
    }
    let ids: Vec<(usize, Option<&[u32]>)> =
        found.iter().map(|c| (c.counts.len(), c.strand_ids.as_deref())).collect();
    let ids = crate::groom::merged_strand_ids(&ids);
    let sites: Vec<(String, Site)> = found.iter().map(|c| (c.path.clone(), c.site)).collect();
    let in_file = found
        .iter()
        .any(|c| matches!(c.points, Bulk::InFile(_)) || matches!(c.widths, Some(Bulk::InFile(_))));
    let joined = if in_file {
        let total: usize = found.iter().map(|c| c.points.len()).sum();
        let (mut points, mut widths) = (Vec::with_capacity(3 * total), Vec::with_capacity(total));
        crate::io::input::advise_huge_pages(points.spare_capacity_mut());
        crate::io::input::advise_huge_pages(widths.spare_capacity_mut());
        for curves in &found {
            curves.append_vertices(&mut points, &mut widths, arrays).map_err(|m| {
                files.error(curves.site, format!("prim <{}>: reading its points or widths: {m}", curves.path))
            })?;
        }
        let parts = found.into_iter().map(|c| c.into_groom(Vec::new(), Vec::new())).collect();
        Groom::concat_placed(parts, vec3s(points), widths)
    } else {
        let parts = found.into_iter().map(|mut c| {
            let mut points = match std::mem::replace(&mut c.points, Bulk::Read(Vec::new())) {
                Bulk::Read(points) => points,
                Bulk::InFile(_) => unreachable!("no array is in a file"),
            };
            let (mut widths, authored) = match c.widths.take() {
                Some(Bulk::Read(widths)) => (widths, true),
                None => (vec![DEFAULT_WIDTH; points.len()], false),
                Some(Bulk::InFile(_)) => unreachable!("no array is in a file"),
            };
            to_coif_space(c.to_coif, &mut points, &mut widths, authored);
            c.into_groom(points, widths)
        });
        Groom::concat(parts.collect())
    };
    let mut groom = joined.map_err(|(index, e)| {
        let (prim_path, site) = &sites[index];
        files.error(*site, format!("prim <{prim_path}> does not fit the prims before it: {e}"))
    })?;
    groom.strand_ids = ids;
    groom.drop_default_group(super::DEFAULT_PRIM_PATH);
    Ok(groom)
}

/// Points and widths in coif's space: transformed by `to_coif`, authored widths (`authored`)
/// by its scale (coif's default width is not scaled).
fn to_coif_space(to_coif: DMat4, points: &mut [Vec3], widths: &mut [f32], authored: bool) {
    if to_coif != DMat4::IDENTITY {
        let transform = |p: Vec3| to_coif.transform_point3(p.as_dvec3()).as_vec3();
        points.iter_mut().for_each(|p| *p = transform(*p));
        if authored {
            let width_scale = crate::io::width_scale(to_coif);
            widths.iter_mut().for_each(|w| *w *= width_scale);
        }
    }
}

/// Floats three by three as points (moved when the allocation allows, else copied).
fn vec3s(floats: Vec<f32>) -> Vec<Vec3> {
    bytemuck::allocation::try_cast_vec(floats)
        .unwrap_or_else(|(_, floats)| floats.chunks_exact(3).map(Vec3::from_slice).collect())
}

impl Curves {
    /// Appends the prim's points (three floats each) and widths, in coif's space, to `points`
    /// and `widths`, reading what is still in the file from `arrays`.
    fn append_vertices(
        &self,
        points: &mut Vec<f32>,
        widths: &mut Vec<f32>,
        arrays: Option<&dyn FileArrays>,
    ) -> std::result::Result<(), String> {
        let first = widths.len();
        match &self.points {
            Bulk::Read(read) => points.extend_from_slice(bytemuck::cast_slice(read)),
            Bulk::InFile(array) => append_array(arrays, array, points)?,
        }
        let authored = match &self.widths {
            None => {
                widths.resize(first + self.points.len(), DEFAULT_WIDTH);
                false
            }
            Some(Bulk::Read(read)) => {
                widths.extend_from_slice(read);
                true
            }
            Some(Bulk::InFile(array)) => {
                append_array(arrays, array, widths)?;
                true
            }
        };
        let placed: &mut [Vec3] = bytemuck::cast_slice_mut(&mut points[3 * first..]);
        to_coif_space(self.to_coif, placed, &mut widths[first..], authored);
        Ok(())
    }

    /// The prim as a groom of one group, with these points and widths.
    fn into_groom(self, points: Vec<Vec3>, widths: Vec<f32>) -> Groom {
        let mut groom = Groom { strand_offsets: vec![0], ..Default::default() };
        let mut offset = 0u32;
        groom.strand_offsets.extend(self.counts.iter().map(|&c| {
            offset += c;
            offset
        }));
        groom.strand_ids = self.strand_ids.unwrap_or_else(|| (0..self.counts.len() as u32).collect());
        groom.points = points;
        groom.widths = widths;
        groom.root_uvs = self.root_uvs;
        // Houdini marks guide curves by the prim's purpose rather than a per-strand flag.
        groom.guides = self
            .guides
            .or_else(|| (self.purpose.as_deref() == Some("guide")).then(|| vec![true; self.counts.len()]));
        for attribute in self.attributes {
            groom.set_attribute(attribute);
        }
        let mut group = CurveGroup::new(self.path, self.basis, self.wrap);
        group.purpose = self.purpose;
        group.invisible = self.invisible;
        group.interpolations = self.interpolations;
        group.element_sized = self.element_sized;
        group.width_interpolation = self.width_interpolation;
        groom.set_single_group(group);
        groom
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::usda::{read, ReadOutcome};

    fn read_text(text: &str) -> Groom {
        match read(text.as_bytes(), Path::new("t.usda"), &ImportOptions::default(), None).unwrap() {
            ReadOutcome::Groom(groom, _) => groom,
            ReadOutcome::NeedsComposition(_) => panic!("no composition here"),
        }
    }

    #[test]
    fn a_prim_that_does_not_fit_the_ones_before_it_is_named_with_its_line() {
        let prim = |name: &str, rest: &str| {
            format!(
                "def BasisCurves \"{name}\"\n{{\n    uniform token type = \"linear\"\n    int[] curveVertexCounts = [2]\n    \
                 point3f[] points = [(0, 0, 0), (0, 1, 0)]\n    {rest}\n}}\n"
            )
        };
        let text = format!(
            "#usda 1.0\n{}{}{}",
            prim("A", "float3[] primvars:rest = [(0, 0, 0), (0, 1, 0)] (interpolation = \"vertex\")"),
            prim("B", ""),
            prim("C", "float[] primvars:rest = [0, 1] (interpolation = \"vertex\")")
        );
        let line = text.lines().position(|l| l.contains("def BasisCurves \"C\"")).unwrap() + 1;
        let error = read(text.as_bytes(), Path::new("t.usda"), &ImportOptions::default(), None)
            .err()
            .expect("prim C's rest has 1 component, A's 3")
            .to_string();
        assert!(
            error.contains(&format!("line {line}: prim </C> does not fit the prims before it")),
            "{error}"
        );
    }

    /// A stage whose points, widths and two primvars each span many read windows, numbers
    /// spelled as writers spell them and otherwise (exponents, `-0`, 25 digits, integers), a
    /// comment holding `)`, `]` and `,` between elements now and then. Returns the text and
    /// the values each array must read as (by `str::parse`); `bad`: a bad number at that index
    /// of the scalar primvar, and the line it is on.
    fn big_arrays_stage(bad: Option<usize>) -> (String, [Vec<f32>; 4], usize) {
        const VERTICES: usize = 60_000;
        let mut rng = <rand_pcg::Pcg64Mcg as rand::SeedableRng>::seed_from_u64(0x05ee_d0fa_11a7_7a75);
        let mut text = String::from(
            "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\ndef BasisCurves \"C\"\n{\n    uniform token type = \"linear\"\n",
        );
        text += &format!("    int[] curveVertexCounts = [{}]\n", vec!["30"; VERTICES / 30].join(", "));
        let mut expected: [Vec<f32>; 4] = Default::default();
        let mut bad_line = 0;
        let arrays = [
            ("point3f[] points", 3, ""),
            ("float[] widths", 1, " (interpolation = \"vertex\")"),
            ("float3[] primvars:bias", 3, " (interpolation = \"vertex\")"),
            ("float[] primvars:wetness", 1, " (interpolation = \"vertex\")"),
        ];
        for (k, (declaration, components, metadata)) in arrays.into_iter().enumerate() {
            text += &format!("    {declaration} = [");
            for i in 0..VERTICES * components {
                if i > 0 {
                    text += ", ";
                }
                if i % components == 0 && i % 5_001 == 17 {
                    text += "# a comment with ), ] and , inside\n        ";
                }
                if components > 1 && i % components == 0 {
                    text += "(";
                }
                let value = rand::Rng::random_range(&mut rng, -2.0f32..2.0);
                let spelling = match i % 211 {
                    0 => format!("{value:e}"),
                    1 => "-0".to_string(),
                    2 => format!("{:.25}", f64::from(value)),
                    3 => format!("{}", value.round()),
                    _ => format!("{value}"),
                };
                if k == 3 && Some(i) == bad {
                    bad_line = text.matches('\n').count() + 1;
                    text += "0.5x";
                } else {
                    expected[k].push(spelling.parse().unwrap());
                    text += &spelling;
                }
                if components > 1 && i % components == components - 1 {
                    text += ")";
                }
            }
            text += &format!("]{metadata}\n");
        }
        text += "}\n";
        (text, expected, bad_line)
    }

    fn read_on_threads(text: &str, threads: usize) -> crate::error::Result<ReadOutcome> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| read(text.as_bytes(), Path::new("t.usda"), &ImportOptions::default(), None))
    }

    #[test]
    fn large_arrays_read_to_the_same_bits_and_errors_at_any_thread_count() {
        let (text, expected, _) = big_arrays_stage(None);
        // The smallest array (widths) spans two windows, the others many.
        assert!(text.len() > 20 * crate::io::usda::lexer::tests_bulk_window(), "{} bytes", text.len());
        let bits = |values: &[f32]| values.iter().map(|v| v.to_bits()).collect::<Vec<u32>>();
        let mut reads = Vec::new();
        for threads in [1, 3] {
            let Ok(ReadOutcome::Groom(groom, _)) = read_on_threads(&text, threads) else {
                panic!("a groom on {threads} threads");
            };
            let attribute = |name: &str| bits(&groom.attribute(name).expect(name).floats());
            let read = [
                bits(bytemuck::cast_slice(&groom.points)),
                bits(&groom.widths),
                attribute("bias"),
                attribute("wetness"),
            ];
            for (array, (read, expected)) in read.iter().zip(&expected).enumerate() {
                assert!(*read == bits(expected), "array {array} on {threads} threads");
            }
            reads.push(read);
        }
        assert!(reads[0] == reads[1]);

        // A bad number deep in the last array: the same message, naming its line, whatever
        // the thread count.
        let (text, _, line) = big_arrays_stage(Some(47_011));
        let errors: Vec<String> = [1, 3]
            .map(|threads| read_on_threads(&text, threads).err().expect("a bad number").to_string())
            .into();
        assert!(
            errors[0].contains(&format!("line {line}: attribute 'primvars:wetness': bad number '0.5x'")),
            "{}",
            errors[0]
        );
        assert_eq!(errors[0], errors[1]);
    }

    #[test]
    fn varying_values_on_cubic_curves_go_to_the_control_points_at_their_segment_ends() {
        // A 4-point B-spline has 2 segment ends, next to points 1 and 2: 0.1 there and on the
        // point before (which no segment reaches), 0.4 there and on the point after.
        let groom = read_text(
            "#usda 1.0\n(\n    metersPerUnit = 1\n)\ndef BasisCurves \"C\"\n{\n    uniform token type = \"cubic\"\n    uniform token basis = \"bspline\"\n    int[] curveVertexCounts = [4]\n    point3f[] points = [(0, 0, 0), (0, 1, 0), (0, 2, 0), (0, 3, 0)]\n    float[] widths = [0.1, 0.4] (\n        interpolation = \"varying\"\n    )\n}\n",
        );
        assert_eq!(groom.basis, CurveBasis::BSpline);
        let expected = [0.1f32, 0.1, 0.4, 0.4];
        for (w, e) in groom.widths.iter().zip(expected) {
            assert!((w - e).abs() < 1e-6, "{:?}", groom.widths);
        }
    }

    #[test]
    fn unauthored_units_follow_usd_and_curve_type_falls_back_to_cubic_bezier() {
        // No metersPerUnit: USD's fallback is centimetres. No type: cubic Bezier, per the schema.
        let groom = read_text(
            "#usda 1.0\ndef BasisCurves \"C\"\n{\n    int[] curveVertexCounts = [4]\n    point3f[] points = [(0, 0, 0), (0, 100, 0), (0, 200, 0), (0, 300, 0)]\n}\n",
        );
        assert_eq!(groom.basis, CurveBasis::Bezier);
        assert_eq!(groom.points[3], Vec3::new(0.0, 3.0, 0.0));
        assert_eq!(groom.widths, vec![crate::io::usda::DEFAULT_WIDTH; 4]);
    }

    #[test]
    fn xform_ops_compose_outermost_first() {
        let values = |v: &[f64]| v.to_vec();
        let translate = xform_op("xformOp:translate", &values(&[1.0, 0.0, 0.0])).unwrap();
        let rotate = xform_op("xformOp:rotateZ", &values(&[90.0])).unwrap();
        // ["translate", "rotateZ"]: rotate first, then translate.
        let p = (translate * rotate).transform_point3(DVec3::X);
        assert!((p - DVec3::new(1.0, 1.0, 0.0)).length() < 1e-12, "{p}");
        let xyz = xform_op("xformOp:rotateXYZ", &values(&[90.0, 0.0, 90.0])).unwrap();
        // X first: Y goes to Z; then Z about Z stays Z.
        assert!((xyz.transform_point3(DVec3::Y) - DVec3::Z).length() < 1e-12);
        let matrix = xform_op(
            "xformOp:transform",
            &values(&[1., 0., 0., 0., 0., 1., 0., 0., 0., 0., 1., 0., 5., 6., 7., 1.]),
        )
        .unwrap();
        assert_eq!(
            matrix.transform_point3(DVec3::ZERO),
            DVec3::new(5.0, 6.0, 7.0),
            "translation in the last row"
        );
    }
}
