//! The render scene: the groom as Embree round curves, the analytic head as a triangle mesh and a
//! floor, plus what shading needs at a hit (tangent, colour, opacity, attribute values).
use glam::{Vec3, Vec4};

use crate::embree::{self, CurveType, Device, Hit};
use crate::error::{Error, Result};
use crate::groom::{attr, AttributeRate, CurveBasis, Groom};
use crate::head::Head;
use crate::render::hair_bsdf::MELANIN_RANGE;

/// Whether to put a head under the hair: the groom's own meshes (scalp, head, body from its
/// file), or coif's analytic head.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HeadMode {
    /// The groom's own meshes (those its file shows) when its file brings any; else the analytic
    /// head when the strand roots sit on it (grooms from `coif generate`).
    #[default]
    Auto,
    /// The groom's own meshes, else the analytic head.
    On,
    /// Neither.
    Off,
}

impl HeadMode {
    /// Whether the analytic head is drawn for this groom.
    pub fn analytic_head(self, groom: &Groom) -> bool {
        match self {
            HeadMode::Off => false,
            _ if !groom.meshes.is_empty() => false,
            HeadMode::On => true,
            HeadMode::Auto => roots_on_default_head(groom),
        }
    }

    /// The groom's own meshes that are drawn: those its file shows (a scalp hidden there stays
    /// hidden), or every one when a head is asked for.
    pub fn own_meshes(self, groom: &Groom) -> impl Iterator<Item = &crate::surface_mesh::SurfaceMesh> {
        groom.meshes.iter().filter(move |mesh| match self {
            HeadMode::Off => false,
            HeadMode::On => true,
            HeadMode::Auto => !mesh.invisible,
        })
    }
}

/// Geometry options of a render.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneOptions {
    pub head: HeadMode,
    pub floor: bool,
    /// Multiplies every strand's width: an explicit, visible change of the geometry.
    pub width_scale: f32,
    /// Widens strands thinner than this many pixels to this width, lowering their opacity by the
    /// same factor so each strand still covers the same area on average (0 = off).
    pub min_pixel_width: f32,
    /// Hair colour overriding the groom's `color` attribute.
    pub color: Option<Vec3>,
    /// Eumelanin and pheomelanin concentrations overriding the groom's pigments (Chiang lobe).
    pub melanin: Option<[f32; 2]>,
    pub head_albedo: Vec3,
    pub floor_albedo: Vec3,
    /// Height (world Y, metres) of the floor (default: just below the hair and head).
    pub floor_height: Option<f32>,
    /// Edge length of the square floor, metres, centred under the groom (default: 100 times
    /// the groom's size, a horizon for any view).
    pub floor_size: Option<f32>,
}

/// Hair colour when neither the groom nor the command line gives one: a medium brown.
pub const DEFAULT_HAIR_COLOR: Vec3 = Vec3::new(0.32, 0.19, 0.10);

impl Default for SceneOptions {
    fn default() -> Self {
        SceneOptions {
            head: HeadMode::Auto,
            floor: true,
            width_scale: 1.0,
            min_pixel_width: 0.0,
            color: None,
            melanin: None,
            head_albedo: Vec3::new(0.55, 0.45, 0.40),
            floor_albedo: Vec3::splat(0.35),
            floor_height: None,
            floor_size: None,
        }
    }
}

/// What a ray hit, ready for shading.
#[derive(Clone, Copy, Debug)]
pub enum Surface {
    Hair {
        tangent: Vec3,
        color: Vec3,
        /// Eumelanin and pheomelanin, when the groom or the command line gives them; the Chiang
        /// lobe prefers them to `color`.
        melanin: Option<[f32; 2]>,
        /// Embree's surface normal at the hit (not normalised), for the offset across the fibre.
        normal: Vec3,
        /// Where rays leaving the fibre start (see [`RenderScene::surface`]).
        exit: FibreExit,
        /// Index of the hit segment's first vertex and the fraction towards the next one, for
        /// per-vertex attributes.
        vertex: u32,
        fraction: f32,
        strand: u32,
    },
    Diffuse {
        normal: Vec3,
        albedo: Vec3,
    },
}

/// Where rays leave a fibre hit, measured from the fibre's centre line rather than Embree's hit
/// point (which may lie a fraction of the radius inside or outside a thin tube).
#[derive(Clone, Copy, Debug)]
pub struct FibreExit {
    axis: Vec3,
    /// From the centre line to the surface through the hit: radial direction × radius.
    radial: Vec3,
}

/// How far outside or inside the surface, as a fraction of the radius, rays leaving a fibre start.
const FIBRE_EXIT_MARGIN: f32 = 0.05;

impl FibreExit {
    /// The surface point across from the centre line through the hit.
    pub fn surface(&self) -> Vec3 {
        self.axis + self.radial
    }

    /// The origin of a ray leaving in direction `w`: just outside the surface when `w` points
    /// away from the fibre, just inside when it points into it (the ray then crosses the fibre,
    /// whose far side it does not meet: see `embree::curve_filter`).
    pub fn origin(&self, w: Vec3) -> Vec3 {
        let side = if self.radial.dot(w) >= 0.0 { 1.0 } else { -1.0 };
        self.axis + self.radial * (1.0 + side * FIBRE_EXIT_MARGIN)
    }
}

/// One strand's per-segment lookup: first groom vertex of the segment and owning strand.
#[derive(Clone, Copy, Debug)]
struct Segment {
    start: u32,
    strand: u32,
}

pub struct RenderScene<'d> {
    embree: embree::Scene<'d>,
    hair_geometry: Option<u32>,
    head_geometry: Option<u32>,
    /// The groom's own meshes, shaded like the head.
    mesh_geometries: Vec<u32>,
    curve: CurveType,
    /// (x, y, z, radius) per groom vertex, as given to Embree.
    points: Vec<[f32; 4]>,
    segments: Vec<Segment>,
    /// Per-vertex hair colour, or per-strand, or one for all.
    colors: PerHair<Vec3>,
    melanin: Option<PerHair<[f32; 2]>>,
    /// Per-vertex opacity when any strand is partly transparent (widened or `transparency`).
    opacity: Option<std::sync::Arc<Vec<f32>>>,
    head: Option<Head>,
    head_albedo: Vec3,
    floor_albedo: Vec3,
    /// Bounds of the hair and head (the floor excluded): what the camera frames.
    pub bounds: (Vec3, Vec3),
    /// Segment count of the hair, for statistics.
    pub segment_count: usize,
}

/// A hair property: one for all strands, one per strand or one per vertex.
enum PerHair<T> {
    Uniform(T),
    Strand(Vec<T>),
    Vertex(Vec<T>),
}

impl<T: Copy> PerHair<T> {
    /// The value at a hit `fraction` of the way from vertex `a` to vertex `b` of `strand`.
    fn at(&self, a: u32, b: u32, fraction: f32, strand: u32, lerp: impl Fn(T, T, f32) -> T) -> T {
        match self {
            PerHair::Uniform(c) => *c,
            PerHair::Strand(c) => c[strand as usize],
            PerHair::Vertex(c) => lerp(c[a as usize], c[b as usize], fraction),
        }
    }
}

/// Names of the groom attributes the hair shading reads: readers map USD `displayColor` and
/// Alembic `groom_color` to `color`; `melanin` and `pheomelanin` are read as named.
pub const MELANIN_ATTRIBUTE: &str = "melanin";
pub const PHEOMELANIN_ATTRIBUTE: &str = "pheomelanin";

/// A groom attribute's first `components` values per element, checked to lie in `range`.
fn pigment_values(
    groom: &Groom,
    name: &str,
    components: usize,
    range: (f32, f32),
) -> Result<Option<(AttributeRate, Vec<f32>)>> {
    let Some(a) = groom.attribute(name) else { return Ok(None) };
    if a.components < components {
        return Err(Error::Usage(format!(
            "render: groom attribute '{name}' has {} components, expected {components}",
            a.components
        )));
    }
    let mut values = Vec::with_capacity(a.data.len() / a.components * components);
    for (element, chunk) in a.floats().chunks(a.components).enumerate() {
        for &v in &chunk[..components] {
            if !(v >= range.0 && v <= range.1) {
                let strand = match a.rate {
                    AttributeRate::Strand => element,
                    AttributeRate::Vertex => groom.strand_of(element),
                };
                return Err(Error::Usage(format!(
                    "render: groom attribute '{name}' of strand {strand} is {v}, outside [{}, {}]",
                    range.0, range.1
                )));
            }
            values.push(v);
        }
    }
    Ok(Some((a.rate, values)))
}

fn per_hair<T>(rate: AttributeRate, values: Vec<T>) -> PerHair<T> {
    match rate {
        AttributeRate::Vertex => PerHair::Vertex(values),
        AttributeRate::Strand => PerHair::Strand(values),
    }
}

/// A uniform number in [0, 1) deciding whether ray `ray_id` sees strand `strand`.
pub fn transparency_coin(ray_id: u32, strand: u32) -> f32 {
    let h = crate::render::sampler::mix64(((ray_id as u64) << 32) | strand as u64);
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// The strands a render draws, as a renderer would: curves of invisible prims stay in the groom
/// but are not drawn, and neither are those of `purpose = "guide"` prims (Houdini's guides), which
/// Hydra and render delegates leave out — unless guides are all there is to see (a guides-only
/// file), which a preview then shows. An error when nothing is visible.
pub fn shown_strands(groom: &Groom) -> Result<Vec<usize>> {
    let visible = |guides: bool| -> Vec<usize> {
        let shown: Vec<bool> = (0..groom.group_count())
            .map(|g| {
                let group = groom.group(g);
                !group.invisible && (guides || group.purpose.as_deref() != Some("guide"))
            })
            .collect();
        (0..groom.strand_count()).filter(|&strand| shown[groom.group_of(strand)]).collect()
    };
    let mut shown = visible(false);
    if shown.is_empty() {
        shown = visible(true);
    }
    if shown.is_empty() {
        let why = if groom.strand_count() == 0 { "has no strands" } else { "is all in invisible prims" };
        return Err(Error::Usage(format!("render: the groom {why}; there is nothing to render")));
    }
    Ok(shown)
}

/// Whether most strand roots sit on coif's default head (within a few millimetres).
pub fn roots_on_default_head(groom: &Groom) -> bool {
    let head = Head::default();
    let strands = groom.strand_count();
    if strands == 0 {
        return false;
    }
    let on = (0..strands)
        .filter(|&s| {
            let root = groom.points[groom.strand_offsets[s] as usize];
            (head.implicit(root).sqrt() - 1.0).abs() < 0.08
        })
        .count();
    on * 10 >= strands * 9
}

/// Per-vertex radius a camera-aware minimum width asks for: `min_pixels` pixels at the vertex's
/// distance from the camera.
pub struct WidthFloor {
    pub camera_position: Vec3,
    pub pixel_size_at_unit_distance: f32,
    pub min_pixels: f32,
}

impl<'d> RenderScene<'d> {
    /// Builds the scene. `width_floor` is the camera's view of the minimum pixel width, if any.
    pub fn build(
        device: &'d Device,
        groom: &Groom,
        options: &SceneOptions,
        width_floor: Option<&WidthFloor>,
    ) -> Result<RenderScene<'d>> {
        if !(options.width_scale.is_finite() && options.width_scale > 0.0) {
            return Err(Error::Usage("--width-scale must be a positive number".into()));
        }
        if !(options.min_pixel_width.is_finite() && options.min_pixel_width >= 0.0) {
            return Err(Error::Usage("--min-pixel-width must be zero or a positive number of pixels".into()));
        }
        let mut embree = embree::Scene::new(device)?;
        // Default (medium) BVH quality: high quality builds ~1.5x slower and traced no faster here.

        let curve = match groom.basis {
            CurveBasis::Linear => CurveType::Linear,
            CurveBasis::Bezier => CurveType::Bezier,
            CurveBasis::BSpline => CurveType::BSpline,
            CurveBasis::CatmullRom => CurveType::CatmullRom,
        };
        let transparency = groom
            .attribute(attr::TRANSPARENCY)
            .filter(|a| a.components == 1 && a.rate == AttributeRate::Vertex)
            .map(|a| a.floats());
        let mut opacity_needed = transparency.is_some();
        let mut points = Vec::with_capacity(groom.vertex_count());
        let mut opacity = Vec::with_capacity(groom.vertex_count());
        for (i, (&p, &width)) in groom.points.iter().zip(&groom.widths).enumerate() {
            let true_radius = 0.5 * width * options.width_scale;
            let mut radius = true_radius;
            if let Some(floor) = width_floor.filter(|_| options.min_pixel_width > 0.0) {
                let wanted = 0.5
                    * floor.min_pixels
                    * floor.pixel_size_at_unit_distance
                    * p.distance(floor.camera_position);
                if wanted > radius {
                    radius = wanted;
                    opacity_needed = true;
                }
            }
            let mut alpha = if radius > 0.0 { true_radius / radius } else { 1.0 };
            if let Some(t) = &transparency {
                alpha *= (1.0 - t[i]).clamp(0.0, 1.0);
            }
            points.push([p.x, p.y, p.z, radius]);
            opacity.push(alpha);
        }

        let shown = shown_strands(groom)?;
        let mut segments = Vec::new();
        let mut starts = Vec::new();
        for &strand in &shown {
            let range = groom.strand_range(strand);
            let (first, count) = (range.start, range.len());
            let step = match curve {
                CurveType::Linear | CurveType::BSpline | CurveType::CatmullRom => 1,
                CurveType::Bezier => 3,
            };
            let per = curve.points_per_segment();
            let mut local = 0;
            while local + per <= count {
                starts.push((first + local) as u32);
                segments.push(Segment { start: (first + local) as u32, strand: strand as u32 });
                local += step;
            }
        }
        // Partly transparent strands: Embree asks, for every candidate hit, whether this ray
        // sees this segment, with probability its opacity. The coin is hashed from the ray id and
        // the strand, so a ray sees a strand or not as a whole (entry and exit of a tube, and the
        // overlapping ends of neighbouring segments, agree).
        let opacity = opacity_needed.then_some(std::sync::Arc::new(opacity));
        let filter: Option<embree::HitFilter> = opacity.as_ref().map(|opacity| {
            let opacity = opacity.clone();
            let segments = std::sync::Arc::new(segments.clone());
            Box::new(move |primitive: u32, ray_id: u32| {
                let segment: Segment = segments[primitive as usize];
                let v = segment.start as usize;
                let alpha = 0.5 * (opacity[v] + opacity[v + 1]);
                transparency_coin(ray_id, segment.strand) < alpha
            }) as embree::HitFilter
        });
        let hair_geometry = if starts.is_empty() {
            None
        } else {
            Some(embree.add_round_curves(curve, &points, &starts, filter)?)
        };

        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in shown.iter().flat_map(|&strand| &points[groom.strand_range(strand)]) {
            let r = Vec3::splat(p[3]);
            let c = Vec3::new(p[0], p[1], p[2]);
            lo = lo.min(c - r);
            hi = hi.max(c + r);
        }
        let head = options.head.analytic_head(groom).then(Head::default);
        let head_geometry = match head {
            Some(head) => {
                lo = lo.min(head.center - head.radii);
                hi = hi.max(head.center + head.radii);
                let (vertices, triangles) = ellipsoid_mesh(&head, 96, 48);
                Some(embree.add_triangle_mesh(&vertices, &triangles)?)
            }
            None => None,
        };
        let mut mesh_geometries = Vec::new();
        for mesh in options.head.own_meshes(groom) {
            for p in &mesh.points {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
            mesh_geometries.push(embree.add_triangle_mesh(&mesh.points, &mesh.shown_triangles())?);
        }
        if !lo.is_finite() {
            return Err(Error::Usage("render: the groom has no strands to render".into()));
        }
        if options.floor {
            // Half the edge: by default a horizon for any view, just below the hair and head.
            let default_size = 50.0 * (hi - lo).max_element().max(1e-3);
            let size = options.floor_size.map_or(default_size, |s| 0.5 * s);
            let y = options.floor_height.unwrap_or(lo.y - 1e-4 * default_size);
            let c = 0.5 * (lo + hi);
            let vertices = [
                Vec3::new(c.x - size, y, c.z - size),
                Vec3::new(c.x + size, y, c.z - size),
                Vec3::new(c.x + size, y, c.z + size),
                Vec3::new(c.x - size, y, c.z + size),
            ];
            embree.add_triangle_mesh(&vertices, &[[0, 2, 1], [0, 3, 2]])?;
        }
        embree.commit()?;

        let colors = match (options.color, pigment_values(groom, attr::COLOR, 3, (0.0, 1.0))?) {
            (Some(c), _) => PerHair::Uniform(c),
            (None, Some((rate, v))) => per_hair(rate, v.chunks(3).map(Vec3::from_slice).collect()),
            (None, None) => PerHair::Uniform(DEFAULT_HAIR_COLOR),
        };
        let melanin = match options.melanin {
            Some(m) => Some(PerHair::Uniform(m)),
            // An explicit colour on the command line wins over the groom's melanin.
            None if options.color.is_some() => None,
            None => match pigment_values(groom, MELANIN_ATTRIBUTE, 1, MELANIN_RANGE)? {
                Some((rate, eu)) => {
                    let pheo = match pigment_values(groom, PHEOMELANIN_ATTRIBUTE, 1, MELANIN_RANGE)? {
                        Some((r, p)) if r == rate => p,
                        Some(_) => {
                            return Err(Error::Usage(format!(
                                "render: groom attributes '{MELANIN_ATTRIBUTE}' and \
                                 '{PHEOMELANIN_ATTRIBUTE}' must both be per strand or both per vertex"
                            )))
                        }
                        None => vec![0.0; eu.len()],
                    };
                    Some(per_hair(rate, eu.into_iter().zip(pheo).map(|(e, p)| [e, p]).collect()))
                }
                None => None,
            },
        };

        Ok(RenderScene {
            embree,
            hair_geometry,
            head_geometry,
            mesh_geometries,
            curve,
            segment_count: segments.len(),
            points,
            segments,
            colors,
            melanin,
            opacity,
            head,
            head_albedo: options.head_albedo,
            floor_albedo: options.floor_albedo,
            bounds: (lo, hi),
        })
    }

    pub fn embree(&self) -> &embree::Scene<'d> {
        &self.embree
    }

    /// Whether some hair is partly transparent, so rays must step through hits.
    pub fn has_transparency(&self) -> bool {
        self.opacity.is_some()
    }

    pub fn is_hair(&self, hit: &Hit) -> bool {
        Some(hit.geometry) == self.hair_geometry
    }

    /// The two groom vertices a hit lies between and the fraction from the first to the second.
    fn attribute_vertices(&self, hit: &Hit) -> (u32, u32, f32) {
        let s = self.segments[hit.primitive as usize].start;
        match self.curve {
            CurveType::Linear => (s, s + 1, hit.u),
            CurveType::BSpline | CurveType::CatmullRom => (s + 1, s + 2, hit.u),
            CurveType::Bezier => (s, s + 3, hit.u),
        }
    }

    /// The hit segment's centre line and radius at the hit's curve parameter, as (x, y, z, r).
    fn curve_point(&self, hit: &Hit) -> Vec4 {
        let s = self.segments[hit.primitive as usize].start as usize;
        let p = |k: usize| Vec4::from_array(self.points[s + k]);
        let u = hit.u.clamp(0.0, 1.0);
        let (u2, u3, m) = (u * u, u * u * u, 1.0 - u);
        match self.curve {
            CurveType::Linear => p(0).lerp(p(1), u),
            CurveType::BSpline => {
                (m * m * m * p(0)
                    + (3.0 * u3 - 6.0 * u2 + 4.0) * p(1)
                    + (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) * p(2)
                    + u3 * p(3))
                    / 6.0
            }
            CurveType::Bezier => m * m * m * p(0) + 3.0 * u * m * m * p(1) + 3.0 * u2 * m * p(2) + u3 * p(3),
            CurveType::CatmullRom => {
                0.5 * ((-u3 + 2.0 * u2 - u) * p(0)
                    + (3.0 * u3 - 5.0 * u2 + 2.0) * p(1)
                    + (-3.0 * u3 + 4.0 * u2 + u) * p(2)
                    + (u3 - u2) * p(3))
            }
        }
    }

    fn curve_tangent(&self, hit: &Hit) -> Vec3 {
        let s = self.segments[hit.primitive as usize].start as usize;
        let p = |k: usize| Vec3::new(self.points[s + k][0], self.points[s + k][1], self.points[s + k][2]);
        let u = hit.u;
        let d = match self.curve {
            CurveType::Linear => p(1) - p(0),
            CurveType::BSpline => {
                let m = 1.0 - u;
                (-m * m) * p(0)
                    + (3.0 * u * u - 4.0 * u) * p(1)
                    + (-3.0 * u * u + 2.0 * u + 1.0) * p(2)
                    + (u * u) * p(3)
            }
            CurveType::Bezier => {
                let m = 1.0 - u;
                (m * m) * (p(1) - p(0)) + (2.0 * u * m) * (p(2) - p(1)) + (u * u) * (p(3) - p(2))
            }
            CurveType::CatmullRom => {
                (-3.0 * u * u + 4.0 * u - 1.0) * p(0)
                    + (9.0 * u * u - 10.0 * u) * p(1)
                    + (-9.0 * u * u + 8.0 * u + 1.0) * p(2)
                    + (3.0 * u * u - 2.0 * u) * p(3)
            }
        };
        d.try_normalize().unwrap_or(Vec3::Y)
    }

    /// Shading information at a hit point `position` (on the ray) for a ray of `direction`.
    ///
    /// A hair hit also gives where rays leave the fibre. The hair BSDFs account for the whole
    /// walk through a fibre at the hit, so a ray leaving it must not meet it again; but Embree's
    /// hit point on a thin round curve may lie a fraction of the radius inside or outside the
    /// tube, and a ray starting on it meets the same surface again. So the exit is placed from
    /// the centre line: on the radius through the hit, just outside the surface for rays going
    /// out and just inside for rays going in, which then meet the fibre only from inside (the
    /// curve filter ignores that).
    pub fn surface(&self, hit: &Hit, position: Vec3, direction: Vec3) -> Surface {
        if self.is_hair(hit) {
            let (a, b, fraction) = self.attribute_vertices(hit);
            let segment = self.segments[hit.primitive as usize];
            let strand = segment.strand;
            let color = self.colors.at(a, b, fraction, strand, Vec3::lerp);
            let melanin = self.melanin.as_ref().map(|m| {
                m.at(a, b, fraction, strand, |x, y, f| [x[0] + (y[0] - x[0]) * f, x[1] + (y[1] - x[1]) * f])
            });
            let tangent = self.curve_tangent(hit);
            return Surface::Hair {
                tangent,
                color,
                melanin,
                normal: hit.normal,
                exit: {
                    let centre = self.curve_point(hit);
                    let axis = centre.truncate();
                    let across = position - axis;
                    let radial = (across - tangent * tangent.dot(across))
                        .try_normalize()
                        .or_else(|| hit.normal.try_normalize())
                        .unwrap_or_else(|| tangent.any_orthonormal_vector());
                    FibreExit { axis, radial: radial * centre.w }
                },
                vertex: a,
                fraction,
                strand: segment.strand,
            };
        }
        let head = self.head.filter(|_| Some(hit.geometry) == self.head_geometry);
        let (normal, albedo) = match head {
            Some(head) => (head.normal_at(position), self.head_albedo),
            None if self.mesh_geometries.contains(&hit.geometry) => {
                (hit.normal.normalize_or(Vec3::Y), self.head_albedo)
            }
            None => (hit.normal.normalize_or(Vec3::Y), self.floor_albedo),
        };
        // Face the normal towards the incoming ray so offsets go to the lit side.
        let normal = if normal.dot(direction) > 0.0 { -normal } else { normal };
        Surface::Diffuse { normal, albedo }
    }

    /// A per-vertex scalar attribute interpolated at a hair hit (`vertex`, `fraction` from
    /// [`Surface::Hair`]), or a per-strand one.
    pub fn attribute_value(values: &AttributeView, vertex: u32, fraction: f32, strand: u32) -> f32 {
        match values {
            AttributeView::Vertex(v) => {
                let a = v[vertex as usize];
                let b = v.get(vertex as usize + 1).copied().unwrap_or(a);
                a + (b - a) * fraction
            }
            AttributeView::Strand(v) => v[strand as usize],
        }
    }
}

/// A scalar attribute's values, borrowed from the groom (first component).
pub enum AttributeView {
    Vertex(Vec<f32>),
    Strand(Vec<f32>),
}

impl AttributeView {
    pub fn from_groom(groom: &Groom, name: &str) -> Result<AttributeView> {
        let a = groom.attribute(name).ok_or_else(|| {
            let known: Vec<&str> = groom.attributes.iter().map(|a| a.name.as_str()).collect();
            Error::Usage(format!(
                "render: the groom has no attribute '{name}' (it has: {})",
                if known.is_empty() { "none".to_string() } else { known.join(", ") }
            ))
        })?;
        let first: Vec<f32> = a.floats().chunks(a.components).map(|c| c[0]).collect();
        Ok(match a.rate {
            AttributeRate::Vertex => AttributeView::Vertex(first),
            AttributeRate::Strand => AttributeView::Strand(first),
        })
    }

    /// Smallest and largest value.
    pub fn range(&self) -> (f32, f32) {
        let v = match self {
            AttributeView::Vertex(v) | AttributeView::Strand(v) => v,
        };
        v.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), &x| (lo.min(x), hi.max(x)))
    }
}

/// A UV-sphere mesh of an ellipsoid.
pub fn ellipsoid_mesh(head: &Head, around: u32, rings: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut vertices = Vec::new();
    for ring in 0..=rings {
        let polar = std::f32::consts::PI * ring as f32 / rings as f32;
        for k in 0..around {
            let azimuth = std::f32::consts::TAU * k as f32 / around as f32;
            let dir = Vec3::new(polar.sin() * azimuth.cos(), polar.cos(), polar.sin() * azimuth.sin());
            vertices.push(head.surface_point(dir));
        }
    }
    let mut triangles = Vec::new();
    for ring in 0..rings {
        for k in 0..around {
            let a = ring * around + k;
            let b = ring * around + (k + 1) % around;
            let c = a + around;
            let d = b + around;
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    (vertices, triangles)
}
