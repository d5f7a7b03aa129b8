//! Puts a recipe on a groom: fits the head frame when the recipe needs one, turns every
//! head-frame position, length and direction into world coordinates, lays out rods for `rows`
//! and `spiral` wraps, and makes the obstacles' collision shapes — the scalp from the groom's
//! own mesh when it brings one. What comes out is a recipe in world coordinates the run can use
//! as it is.
use std::sync::Arc;

use glam::{Quat, Vec3};
use toml::Spanned;

use super::head_frame::{Ellipsoid, FitError, FrameOverrides, HeadFrame};
use super::layout::lay_out;
use super::ranges::MAX_OBSTACLES;
use super::recipe::{bake_mesh, Frame, Layout, Obstacle, Recipe, Rod, Stage};
use crate::error::{Error, Result};
use crate::groom::{Groom, GroomError};
use crate::head::Head;
use crate::interact::mesh_sdf::TriangleMesh;
use crate::interact::obstacles::Shape;

/// A recipe placed on one groom.
pub struct Placed {
    /// The recipe in world coordinates (every `frame` is `world`, layouts are rods).
    pub recipe: Recipe,
    /// One collision shape per obstacle, in the recipe's order.
    pub shapes: Vec<Shape>,
    /// The head frame, when the recipe needed one.
    pub frame: Option<HeadFrame>,
    /// Where masks' regions are measured from: the head's centre and the rotation from coif's
    /// head axes (X side, Y up, Z front) to the head's.
    pub mask_center: Vec3,
    pub mask_rotation: Quat,
}

/// Whether anything in the recipe is given in, or laid out on, the head frame.
pub fn needs_frame(recipe: &Recipe) -> bool {
    let head = |f: &Option<Frame>| f.unwrap_or(recipe.frame) == Frame::Head;
    recipe.frame == Frame::Head
        || recipe.rods.iter().any(|r| head(&r.get_ref().frame))
        || recipe.obstacles.iter().any(|o| match o.get_ref() {
            Obstacle::Head { frame, .. }
            | Obstacle::Sphere { frame, .. }
            | Obstacle::Plane { frame, .. }
            | Obstacle::Box { frame, .. } => head(frame),
            Obstacle::Scalp { .. } => true,
            Obstacle::Mesh { .. } => false,
        })
        || recipe.stages.iter().any(|s| match s.get_ref() {
            Stage::Wrap { layout, .. } => *layout != Layout::Nearest,
            Stage::Dry { dryer: Some(d), .. } => head(&d.frame),
            _ => false,
        })
}

/// The signed world axis closest to the unit vector `v`.
fn nearest_axis(v: Vec3) -> Vec3 {
    let i = v.abs().max_position();
    let mut axis = Vec3::ZERO;
    axis[i] = v[i].signum();
    axis
}

/// The head frame `recipe` is placed in on `groom` (the whole groom, whose scalp or head mesh
/// is `scalp` if it has one), or `None` when the recipe needs none. Fitted once per styling run,
/// so the guides of a guide run are placed in the same frame as every strand would be.
pub fn head_frame(recipe: &Recipe, groom: &Groom, scalp: Option<&TriangleMesh>) -> Result<Option<HeadFrame>> {
    needs_frame(recipe).then(|| fit_frame(recipe, groom, scalp)).transpose()
}

/// Places `recipe` on `groom` (already resampled; the guides alone in a guide run), whose scalp
/// or head mesh is `scalp` if it has one, in `frame` (from [`head_frame`] on the whole groom).
pub fn place(
    recipe: &Recipe,
    groom: &Groom,
    scalp: Option<&TriangleMesh>,
    frame: Option<HeadFrame>,
) -> Result<Placed> {
    let roots: Vec<Vec3> = (0..groom.strand_count()).map(|s| groom.strand_points(s)[0]).collect();
    if needs_frame(recipe) && frame.is_none() {
        return Err(Error::Usage("the recipe is written in the head frame, but none was fitted".into()));
    }
    let mut out = recipe.clone();
    let world = |f: &mut Option<Frame>| f.replace(Frame::World).unwrap_or(recipe.frame);
    // Converters for items in the head frame (identity for world items).
    let point = |f: Frame, p: [f32; 3]| match (f, &frame) {
        (Frame::Head, Some(fr)) => fr.point(Vec3::from(p)).to_array(),
        _ => p,
    };
    let direction = |f: Frame, d: [f32; 3]| match (f, &frame) {
        (Frame::Head, Some(fr)) => fr.direction(Vec3::from(d)).to_array(),
        _ => d,
    };
    let length = |f: Frame, l: f32| match (f, &frame) {
        (Frame::Head, Some(fr)) => l * fr.size(),
        _ => l,
    };

    if let (Frame::Head, Some(fr)) = (recipe.frame, &frame) {
        // Gravity follows the head's axes (a groom read without its up axis still hangs the
        // right way), but not the lean of its fitted up: that leans with the hair (3.5° on a
        // generated head), and gravity leaning with it styled grooms out of balance under the
        // world's gravity a shot simulates them in (guides moved 3.8 mm in 2 s at the median).
        let untilt = Quat::from_rotation_arc(fr.up(), nearest_axis(fr.up()));
        out.settings.gravity = (untilt * fr.direction(Vec3::from(recipe.settings.gravity))).to_array();
    }
    for rod in &mut out.rods {
        let rod = rod.get_mut();
        let f = world(&mut rod.frame);
        (rod.a, rod.b, rod.radius) = (point(f, rod.a), point(f, rod.b), length(f, rod.radius));
    }
    // Which frame each obstacle was in, for the stages that press them.
    let mut obstacle_frames = Vec::new();
    let mut shapes = Vec::new();
    for obstacle in &mut out.obstacles {
        let (f, shape) = match obstacle.get_mut() {
            Obstacle::Head { center, radii, frame: item, .. } => {
                let f = world(item);
                let shape = match (f, &frame) {
                    (Frame::Head, Some(fr)) if center.is_none() && radii.is_none() => {
                        fitted_head(fr, &roots)?
                    }
                    (Frame::Head, Some(fr)) => {
                        // Along the head's axes; what is left out comes from the fitted head.
                        let fitted = fr.head_ellipsoid(&roots);
                        let c = center.map(Vec3::from).or(fitted.map(|e| e.center)).unwrap_or(Vec3::ZERO);
                        let r = radii.map(Vec3::from).or(fitted.map(|e| e.radii)).unwrap_or(Vec3::ONE);
                        Shape::Ellipsoid {
                            center: fr.point(c),
                            radii: r * fr.size(),
                            rotation: fr.rotation(),
                        }
                    }
                    _ => {
                        let head = Head::default();
                        Shape::Ellipsoid {
                            center: center.map_or(head.center, Vec3::from),
                            radii: radii.map_or(head.radii, Vec3::from),
                            rotation: Quat::IDENTITY,
                        }
                    }
                };
                (f, shape)
            }
            Obstacle::Scalp { name, resolution, band } => {
                let shape = match scalp {
                    Some(mesh) => {
                        Shape::Mesh(Arc::new(bake_mesh(mesh, *resolution, *band).map_err(|e| {
                            Error::Usage(format!("scalp obstacle '{name}': the groom's scalp mesh: {e}"))
                        })?))
                    }
                    None => fitted_head(frame.as_ref().expect("a scalp needs the frame"), &roots)?,
                };
                (Frame::World, shape)
            }
            Obstacle::Sphere { center, radius, frame: item, .. } => {
                let f = world(item);
                (*center, *radius) = (point(f, *center), length(f, *radius));
                (f, Shape::Sphere { center: Vec3::from(*center), radius: *radius })
            }
            Obstacle::Plane { point: p, normal, frame: item, .. } => {
                let f = world(item);
                (*p, *normal) = (point(f, *p), direction(f, *normal));
                (f, Shape::Plane { point: Vec3::from(*p), normal: Vec3::from(*normal).normalize() })
            }
            Obstacle::Box { center, half_extents, frame: item, .. } => {
                let f = world(item);
                let rotation = match (f, &frame) {
                    (Frame::Head, Some(fr)) => fr.rotation(),
                    _ => Quat::IDENTITY,
                };
                *center = point(f, *center);
                *half_extents = half_extents.map(|h| length(f, h));
                let shape = Shape::Box {
                    center: Vec3::from(*center),
                    half_extents: Vec3::from(*half_extents),
                    rotation,
                };
                (f, shape)
            }
            Obstacle::Mesh { name, sdf, .. } => {
                let sdf = sdf.clone().ok_or_else(|| {
                    Error::Usage(format!(
                        "mesh obstacle '{name}' has no baked field: load the recipe with coif::style::recipe::load"
                    ))
                })?;
                (Frame::World, Shape::Mesh(sdf))
            }
        };
        obstacle_frames.push(f);
        shapes.push(shape);
    }

    let mut laid = Vec::new();
    for (index, stage) in out.stages.iter_mut().enumerate() {
        let span = stage.span();
        match stage.get_mut() {
            Stage::Dry { dryer: Some(d), .. } => {
                let f = world(&mut d.frame);
                (d.position, d.target) = (point(f, d.position), point(f, d.target));
                d.falloff = d.falloff.map(|l| length(f, l));
            }
            Stage::Press { obstacle, travel, direction: d, .. } => {
                let which = recipe.obstacles.iter().position(|o| o.get_ref().name() == obstacle);
                let f = which.map_or(Frame::World, |w| obstacle_frames[w]);
                *travel = length(f, *travel);
                *d = d.map(|d| direction(f, d));
                // A box pressed with no direction moves along its frame's up.
                if d.is_none() && matches!(which.map(|w| &shapes[w]), Some(Shape::Box { .. })) {
                    *d = Some(direction(f, [0.0, 1.0, 0.0]));
                }
            }
            Stage::Wrap { rods, layout, diameter, spacing, .. } if *layout != Layout::Nearest => {
                let fr = frame.as_ref().expect("a layout needs the frame");
                let (diameter, spacing) = (
                    length(recipe.frame, diameter.expect("checked")),
                    length(recipe.frame, spacing.expect("checked")),
                );
                let made = lay_out(fr, &roots, *layout, diameter, spacing)
                    .map_err(|why| Error::Usage(format!("stage {} (wrap): {why}", index + 1)))?;
                if made.is_empty() {
                    return Err(Error::Usage(format!(
                        "stage {} (wrap): the {layout:?} layout found no scalp to put rods on",
                        index + 1
                    )));
                }
                // Every rod is an obstacle while the hair is wrapped: laid out or listed, a recipe
                // has at most as many as it may list.
                let total = recipe.rods.len() + laid.len() + made.len();
                if total > MAX_OBSTACLES {
                    return Err(Error::Usage(format!(
                        "stage {} (wrap): the {layout:?} layout's {} rods make the recipe's rods {total}; \
                         a recipe may have at most {MAX_OBSTACLES}",
                        index + 1,
                        made.len()
                    )));
                }
                for (k, rod) in made.into_iter().enumerate() {
                    let name = format!("stage{}_rod{k}", index + 1);
                    rods.push(name.clone());
                    let rod = Rod {
                        name,
                        a: rod.a.to_array(),
                        b: rod.b.to_array(),
                        radius: rod.radius,
                        frame: None,
                    };
                    laid.push(Spanned::new(span.clone(), rod));
                }
                *layout = Layout::Nearest;
            }
            _ => {}
        }
    }
    out.rods.extend(laid);
    out.frame = Frame::World;

    let (mask_center, mask_rotation) = match (&frame, recipe.frame) {
        (Some(fr), Frame::Head) => (fr.center(), fr.rotation()),
        // As before head frames: the (last) analytic head obstacle's centre, coif's axes.
        _ => {
            let center = recipe
                .obstacles
                .iter()
                .filter_map(|o| match o.get_ref() {
                    Obstacle::Head { center, frame: None | Some(Frame::World), .. } => {
                        Some(center.map_or(Head::default().center, Vec3::from))
                    }
                    _ => None,
                })
                .next_back()
                .unwrap_or(Head::default().center);
            (center, Quat::IDENTITY)
        }
    };
    Ok(Placed { recipe: out, shapes, frame, mask_center, mask_rotation })
}

/// Longest segment, in head units, a groom may have to be styled as it comes when the recipe
/// sets no `max_segment`: 3.4 cm on coif's 8.5 cm head, above the seed grooms the presets are
/// tuned on (3 cm segments, whatever the head fitted to their roots). A DCC's coarser guides
/// (Blender: 8 cm segments on a 10 cm head) are resampled to [`DEFAULT_SEGMENT_HEAD_UNITS`].
pub const COARSEST_SEGMENT_HEAD_UNITS: f32 = 0.4;
/// The resolution a too coarse groom is resampled to: 1 cm on a 10 cm head, 2 cm on a head
/// twice as large, about the seed grooms' 3 cm on coif's head relative to the hair's bending
/// length. Finer is not better with today's solver: at 5 mm segments of Blender's 80 µm hair
/// the edge frames lag the centreline, so the bonds remember a quarter less of the shape the
/// hair dried in (0.26 of it kept where the hydrogen share is 0.33; 0.327 at 1 cm and 2 cm).
pub const DEFAULT_SEGMENT_HEAD_UNITS: f32 = 0.1;
/// Longest segment per rod diameter a groom may have to be styled as it comes: a segment must
/// be shorter than the diameter of the rod it winds on (the seed grooms' 3 cm segments wind on
/// the water set's 5 cm rollers).
pub const COARSEST_SEGMENT_ROD_DIAMETERS: f32 = 0.75;
/// Largest typical turn, radians, from one segment of a strand to the next for a groom to be
/// styled as it comes: a quarter turn, four segments to a turn of a curl. A generated 35 cm head
/// of 1 cm curls cut in 2.3 cm segments (three to a turn, 103° at the median vertex) blow-dried
/// to folds of up to 175° per vertex, and its settle never reached rest (residual 2.1e-2 after
/// 90 s, the output moving 18.7 mm in 2 s when simulated again); resampled to 1 cm, it converges
/// after 6.4 s and moves 0.3 mm.
pub const SHARPEST_TYPICAL_TURN: f32 = std::f32::consts::FRAC_PI_2;
/// The turn per segment a groom cut too coarsely for its curls is resampled to: eight segments
/// to a turn of the circle through its vertices.
pub const RESAMPLED_TURN: f32 = std::f32::consts::FRAC_PI_4;

/// The finest segment a groom is styled at, metres (the bottom of `[settings] max_segment`'s
/// range).
pub const MIN_SEGMENT: f32 = 1e-5;

/// The resolution a recipe without `max_segment` styles `groom` at: `None` when the groom is as
/// fine as its head and rods need ([`COARSEST_SEGMENT_HEAD_UNITS`] of the fitted head,
/// [`COARSEST_SEGMENT_ROD_DIAMETERS`] of the thinnest rod), so it is simulated as it comes;
/// else the finer of [`DEFAULT_SEGMENT_HEAD_UNITS`] and that limit, so a preset styles a coarse
/// groom of any head size unchanged, at the same resolution relative to the head. A groom whose
/// curls are cut in fewer segments a turn than the rod needs ([`curl_segment`]) is resampled
/// finer still, as the perm's own `max_segment` resamples its strands. A resolution
/// finer than an explicit `max_segment` may be ([`MIN_SEGMENT`]) is refused, naming the rod or
/// head asking for it: a micrometre rod or head would multiply the groom's vertices ten
/// thousandfold.
pub fn default_max_segment(recipe: &Recipe, groom: &Groom, frame: Option<HeadFrame>) -> Result<Option<f32>> {
    if recipe.settings.max_segment.is_some() {
        return Ok(recipe.settings.max_segment);
    }
    let size = frame.map(|f| f.size());
    let metres = |f: Option<Frame>, l: f32| match (f.unwrap_or(recipe.frame), size) {
        (Frame::Head, Some(size)) => l * size,
        _ => l,
    };
    // Each rod's radius in metres, with what the user wrote it as.
    let rod_radii = recipe.rods.iter().map(|r| {
        let r = r.get_ref();
        (metres(r.frame, r.radius), format!("the recipe's rod '{}'", r.name))
    });
    let layout_radii = recipe.stages.iter().enumerate().filter_map(|(index, s)| match s.get_ref() {
        Stage::Wrap { layout, diameter: Some(d), .. } if *layout != Layout::Nearest => {
            Some((metres(None, 0.5 * d), format!("the rods of the recipe's stage {} (wrap)", index + 1)))
        }
        _ => None,
    });
    let rods: Vec<(f32, String)> = rod_radii
        .chain(layout_radii)
        .map(|(radius, what)| {
            (
                COARSEST_SEGMENT_ROD_DIAMETERS * 2.0 * radius,
                format!("{what} ({} m across)", crate::validate::shortest((2.0 * radius).into())),
            )
        })
        .collect();
    let limit = rods
        .iter()
        .map(|r| r.0)
        .chain(size.map(|s| COARSEST_SEGMENT_HEAD_UNITS * s))
        .fold(f32::INFINITY, f32::min);
    let longest = (0..groom.strand_count())
        .flat_map(|s| groom.strand_points(s).windows(2).map(|w| w[0].distance(w[1])))
        .fold(0.0f32, f32::max);
    let coarse = limit.is_finite() && longest > limit;
    let curls = curl_segment(groom);
    if !coarse && curls.is_none() {
        return Ok(None);
    }
    let (rods, size) = if coarse { (rods, size) } else { (Vec::new(), None) };
    let head = size.map(|s| {
        let what = match recipe.head.size {
            Some(_) => format!("the recipe's [head] size = {} m", crate::validate::shortest(s.into())),
            None => {
                format!("the head fitted to the roots ({} m in size)", crate::validate::shortest(s.into()))
            }
        };
        (DEFAULT_SEGMENT_HEAD_UNITS * s, what)
    });
    let (target, cause) = rods
        .into_iter()
        .chain(head)
        .chain(curls)
        .fold((f32::INFINITY, String::new()), |finest, next| if next.0 < finest.0 { next } else { finest });
    if target < MIN_SEGMENT {
        return Err(Error::Usage(format!(
            "{cause} would have the groom styled at segments of {} m, finer than the {} m \
             [settings] max_segment may be ({} vertices instead of {}); are the recipe's lengths \
             another unit's? Set [settings] max_segment to style it anyway",
            crate::validate::shortest(target.into()),
            crate::validate::shortest(MIN_SEGMENT.into()),
            crate::validate::shortest(crate::limits::vertices_after_resampling(groom, Some(target))),
            groom.vertex_count()
        )));
    }
    Ok(Some(target))
}

/// The segment length a strand whose typical vertex turns more than [`SHARPEST_TYPICAL_TURN`]
/// (its median turn: a lone kink, which resampling cannot smooth, does not count) needs for
/// [`RESAMPLED_TURN`] a segment on the circle through its vertices (radius
/// `l / (2 sin(θ/2))` for segments `l` turning `θ`), the finest over the groom, with the strand
/// that asks for it; `None` when every strand's curls have segments enough.
fn curl_segment(groom: &Groom) -> Option<(f32, String)> {
    (0..groom.strand_count())
        .filter_map(|s| {
            let points = groom.strand_points(s);
            let mut turns: Vec<f32> =
                points.windows(3).map(|w| (w[1] - w[0]).angle_between(w[2] - w[1])).collect();
            if turns.is_empty() {
                return None;
            }
            turns.sort_by(f32::total_cmp);
            let turn = turns[turns.len() / 2];
            if turn.is_nan() || turn <= SHARPEST_TYPICAL_TURN {
                return None;
            }
            let length: f32 = points.windows(2).map(|w| w[0].distance(w[1])).sum();
            let segment = length / (points.len() - 1) as f32;
            let target = segment * (0.5 * RESAMPLED_TURN).sin() / (0.5 * turn).sin();
            Some((
                target,
                format!(
                    "strand {s}'s curls ({:.0}° from one {:.3} m segment to the next)",
                    turn.to_degrees(),
                    segment
                ),
            ))
        })
        .fold(None, |finest: Option<(f32, String)>, next| match finest {
            Some(f) if f.0 <= next.0 => Some(f),
            _ => Some(next),
        })
}

fn fit_frame(recipe: &Recipe, groom: &Groom, scalp: Option<&TriangleMesh>) -> Result<HeadFrame> {
    let head = &recipe.head;
    let named = head.scalp.as_ref().and_then(|name| {
        recipe.obstacles.iter().find_map(|o| match o.get_ref() {
            Obstacle::Mesh { name: n, mesh, path, .. } if n == name => mesh.clone().map(|m| (m, path)),
            _ => None,
        })
    });
    let overrides = FrameOverrides {
        center: head.center.map(Vec3::from),
        up: head.up.map(Vec3::from),
        front: head.front.map(Vec3::from),
        size: head.size,
    };
    // What cannot be fitted is the groom's roots (an error of the groom's file), the recipe's
    // scalp obstacle, or the scalp mesh given with the groom (the caller names its file).
    let mesh = named.as_ref().map(|(mesh, _)| mesh.as_ref()).or(scalp);
    HeadFrame::fit(groom, mesh, &overrides).map_err(|e| match (e, &named) {
        (FitError::Scalp, Some((_, path))) => Error::Usage(format!(
            "the recipe's [head] scalp = \"{}\" ({}) has no curved surface near the groom's roots; give \
             the head in the recipe's [head] table (center, up, front, size)",
            head.scalp.as_deref().unwrap_or_default(),
            path.display()
        )),
        (FitError::Scalp, None) => Error::Groom(GroomError::ScalpNotFitted),
        (FitError::Groom(reason), _) => Error::Groom(GroomError::NoHeadFrame { reason }),
    })
}

/// The head as the ellipsoid fitted to the roots of the whole groom the frame was fitted to (a
/// sphere of the frame's size, clear of the strands, when the roots do not determine one).
fn fitted_head(frame: &HeadFrame, roots: &[Vec3]) -> Result<Shape> {
    let e = frame.head_ellipsoid(roots).unwrap_or(Ellipsoid::UNIT_SPHERE);
    Ok(Shape::Ellipsoid {
        center: frame.point(e.center),
        radii: e.radii * frame.size(),
        rotation: frame.rotation() * e.rotation,
    })
}
