//! Production scale: simulate a few thousand guides and interpolate the rendered strands (the
//! children) from them, as Houdini, Maya/XGen, Ornatrix and Unreal do.
//!
//! Guides are the groom's own (its per-strand guide flag) or chosen by the recipe's `[guides]`
//! section, spread evenly over the scalp by farthest-point sampling of the roots. The recipe
//! styles the guides with everything it does (rods, wetness, bonds, contacts, colliders); each
//! child is then bound to up to three guides by root distance ([`binding`]) and carried in their
//! frames ([`deform`]), pushed out of the recipe's colliders, and given interpolated rest shapes,
//! bond rates and wetness. The output flags the guides and gives children Unreal's
//! `groom_closest_guides` / `groom_guide_weights`.
pub mod binding;
pub mod clump;
pub mod deform;
pub mod select;
pub mod separate;

use glam::Vec3;
use serde::Deserialize;

use crate::analysis::resample_groom;
use crate::error::{Error, Result};
use crate::groom::{Attribute, AttributeRate, Groom};
use crate::interact::obstacles::{penetration, Shape};
use crate::progress::Progress;
use crate::sim::driver::carry_groom_water;
use crate::sim::rod::transport_frames;
use crate::sim::sag_free::{MATERIAL_FRAME, REST_DARBOUX};
use crate::sim::Simulation;
use crate::style::head_frame::HeadFrame;
use crate::style::placement::place;
use crate::style::recipe::{Recipe, Stage};
use crate::style::run::{sim_params, style_strands, StyleOptions, Styled, WaterSnapshots};
use binding::{Binding, GUIDES_PER_CHILD};
use deform::{Children, Curves, HangCeilings};

/// Per strand, the strand ids (`groom_id`) of a child's guides, as Unreal's groom builder looks
/// them up among the guides' ids: three per strand, written as float×3 in USD (exact integers
/// below 2^24; the only triple Unreal's USD importer reads, and one Blender keeps) and int32×3 in
/// Alembic (Unreal's Alembic spec).
pub const CLOSEST_GUIDES: &str = "groom_closest_guides";
/// Guide ids must be exact in the attribute's f32 data (and in USD's float3).
const EXACT_IDS: u32 = 1 << 24;
/// Per strand, the weights of those guides: float×3, summing to 1.
pub const GUIDE_WEIGHTS: &str = "groom_guide_weights";

/// The recipe's `[guides]` section: how many strands to simulate as guides.
#[derive(Clone, Copy, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GuideSpec {
    /// Number of guides.
    pub count: Option<usize>,
    /// Guides as a fraction of the strands (Unreal's default is 0.1).
    pub fraction: Option<f32>,
    /// How far (metres) a child's root may be from its nearest guide's; default four times the
    /// median spacing of the guides.
    pub reach: Option<f32>,
}

impl GuideSpec {
    /// The number of guides for a groom of `strands` strands; zero or more than the strands is an
    /// error with the numbers.
    pub fn count_for(&self, strands: usize) -> Result<usize> {
        let count = match (self.count, self.fraction) {
            (Some(_), Some(_)) => {
                return Err(Error::Usage("[guides]: give count or fraction, not both".into()))
            }
            (Some(n), None) => n,
            (None, Some(f)) if f.is_finite() && f > 0.0 && f <= 1.0 => {
                ((f * strands as f32).round() as usize).max(1)
            }
            (None, Some(f)) => {
                return Err(Error::Usage(format!("[guides] fraction = {f}: must be in (0, 1]")))
            }
            (None, None) => {
                return Err(Error::Groom(crate::groom::GroomError::Guides(
                    "[guides] gives neither count nor fraction, and the groom has no guides of its own: \
                     give one"
                        .into(),
                )))
            }
        };
        if count == 0 || count > strands {
            // The groom's error: the command names its file.
            return Err(Error::Groom(crate::groom::GroomError::Guides(format!(
                "[guides] (or --guides) asks for {count} guides, but the groom has {strands} strands \
                 (1 to {strands} allowed)"
            ))));
        }
        Ok(count)
    }
}

/// Whether styling goes through guides: the recipe asks for them, or the groom brings both
/// guides and children.
pub fn wanted(groom: &Groom, recipe: &Recipe) -> bool {
    recipe.guides.is_some()
        || groom.guides.as_ref().is_some_and(|g| g.iter().any(|&x| x) && g.iter().any(|&x| !x))
}

/// Styles the guides of a groom with a recipe and interpolates the children from them.
/// `frame` is the head frame fitted to the whole groom ([`crate::style::placement::head_frame`]):
/// the guides are placed in it, not in one fitted to their own roots.
pub fn style(
    input: &Groom,
    recipe: &Recipe,
    options: &StyleOptions,
    frame: Option<HeadFrame>,
) -> Result<Styled> {
    let groom = match recipe.settings.max_segment {
        Some(max) => resample_groom(input, max),
        None => input.clone(),
    };
    groom.validate()?;
    let strands = groom.strand_count();
    let roots: Vec<Vec3> = (0..strands).map(|s| groom.points[groom.strand_range(s).start]).collect();
    let (flags, own_guides) = match &recipe.guides {
        // `[guides]` with only a reach keeps the groom's own guides.
        Some(spec) if spec.count.is_some() || spec.fraction.is_some() || groom.guides.is_none() => {
            let mut flags = vec![false; strands];
            for g in select::farthest_points(&roots, spec.count_for(strands)?) {
                flags[g] = true;
            }
            (flags, false)
        }
        _ => (groom.guides.clone().ok_or_else(|| Error::Usage("the groom has no guides".into()))?, true),
    };
    let guide_ids: Vec<usize> = (0..strands).filter(|&s| flags[s]).collect();
    let child_ids: Vec<usize> = (0..strands).filter(|&s| !flags[s]).collect();
    let guide_roots: Vec<Vec3> = guide_ids.iter().map(|&g| roots[g]).collect();
    // Binds the children `which` (strand indices) as coif chooses, in that order.
    let bind_here = |which: &[usize]| {
        let reach = match recipe.guides.and_then(|g| g.reach) {
            Some(reach) => reach,
            // The groom's own guides are the artist's choice: each child follows its nearest,
            // however sparse they are (Blender binds children 8.5 cm from their nearest guide
            // on a 10 cm head). The default reach guards guides coif chose too few of.
            None if own_guides => f32::INFINITY,
            None => binding::default_reach(&guide_roots),
        };
        let shape = |s: &usize| binding::shape_of(groom.strand_points(*s));
        let guide_shapes: Vec<binding::Shape> = guide_ids.iter().map(shape).collect();
        let child_shapes: Vec<binding::Shape> = which.iter().map(shape).collect();
        let child_roots: Vec<Vec3> = which.iter().map(|&c| roots[c]).collect();
        binding::bind(&child_roots, &child_shapes, which, &guide_roots, &guide_shapes, reach)
    };
    // A file's bindings name its own guides: when coif chooses others (restyling a guided groom
    // with fewer guides), they are dropped, not checked against guides they never named.
    let file = match recipe.guides {
        None => file_bindings(&groom, &guide_ids, &child_ids)?,
        Some(_) => None,
    };
    let bindings = match (&recipe.guides, file) {
        (None, Some(file)) => {
            // Children the file binds to no guide (all weights 0: a curve prim or object without
            // the binding attributes, merged with ones that have them) are bound here.
            let unbound: Vec<usize> =
                child_ids.iter().zip(&file).filter(|(_, b)| b.is_none()).map(|(&c, _)| c).collect();
            let mut own = if unbound.is_empty() { Vec::new() } else { bind_here(&unbound)? }.into_iter();
            let bindings: Vec<Binding> = file
                .into_iter()
                .map(|b| b.or_else(|| own.next()).expect("one binding per unbound child"))
                .collect();
            binding::check(&bindings, &child_ids, guide_ids.len())?;
            bindings
        }
        _ => bind_here(&child_ids)?,
    };

    let guides = subset(&groom, &guide_ids);
    let children = subset(&groom, &child_ids);
    let mut guide_recipe = recipe.clone();
    guide_recipe.settings.max_segment = None; // resampled above, with the children
    guide_recipe.guides = None;
    let styled = style_strands(&guides, &guide_recipe, options, frame, WaterSnapshots::Keep)?;
    // The children's part takes as long as the guides' stages at 100,000 strands (mostly the
    // separation's passes): its own progress, counting the placing, each separation pass, the
    // carried attributes, each rest batch and each frame.
    let passes = if recipe.contacts.hair_hair { separate::PASSES as u64 } else { 0 };
    let batches = child_ids.len().div_ceil(HOLD_BATCH) as u64;
    let progress =
        Progress::new(options.progress, "children", 2 + passes + batches + styled.frames.len() as u64);

    let before = Curves::new(guides.points.clone(), guides.strand_offsets.clone(), None);
    let posed = |points: Vec<Vec3>| {
        let roots = before.carried_root_frames(&points);
        Curves::new(points, guides.strand_offsets.clone(), Some(&roots))
    };
    let bind = |points| Children { points, offsets: &children.strand_offsets, bindings: &bindings };
    // Where the water clumped the guides, the children are carried to that pose and clumped by
    // the same droplets; later poses carry them on from there.
    let mut clumped: Vec<(usize, Vec<Vec3>, Curves)> = Vec::with_capacity(styled.droplets.len());
    for snapshot in &styled.droplets {
        let pose = posed(snapshot.hair.clone());
        let (from, from_pose) = match clumped.last() {
            Some((_, points, pose)) => (points, pose),
            None => (&children.points, &before),
        };
        // Not `bind`: a closure's borrow would outlive this iteration's `clumped.last()`.
        let offsets = &children.strand_offsets;
        let mut points =
            deform::deform(&Children { points: from, offsets, bindings: &bindings }, from_pose, &pose);
        clump::clump(&mut points, offsets, snapshot, recipe.settings.dt);
        clumped.push((snapshot.frames_before, points, pose));
    }
    // The children's points and their guides' pose to deform from, for a frame captured after
    // `frames` others (the last water clumping before it, else the unstyled children).
    let start = |frames: usize| match clumped.iter().rev().find(|(before, _, _)| *before <= frames) {
        Some((_, points, pose)) => (bind(points), pose),
        None => (bind(&children.points), &before),
    };
    let bound = bind(&children.points);
    let after = posed(styled.groom.points.clone());
    let placed = place(recipe, &guides, options.scalp.as_deref(), frame)?;
    let radii = children.contact_radii();
    let (last, last_pose) = start(usize::MAX);
    progress.set_message("placed on their guides");
    let mut child_points = deform::deform(&last, last_pose, &after);
    // Without gravity no balance to keep.
    let up = -sim_params(&placed.recipe).gravity.try_normalize().unwrap_or(Vec3::ZERO);
    let ceilings = |after: &Curves| (up != Vec3::ZERO).then(|| HangCeilings::new(&bindings, after, up));
    push_out(
        &mut child_points,
        &children.strand_offsets,
        &radii,
        &styled.colliders,
        ceilings(&after).as_ref(),
    );
    progress.inc(1);
    // Placed, not settled among each other: moved apart before their rest is solved, so that a
    // shot simulating them with the recipe's contacts finds them at rest.
    if recipe.contacts.hair_hair {
        progress.set_message("moved apart");
        separate::separate(
            &mut child_points,
            &children.strand_offsets,
            &radii,
            &styled.groom.points,
            &guides.strand_offsets,
            &guides.contact_radii(),
            &styled.colliders,
            &recipe.contacts,
            || progress.inc(1),
        )?;
        // Passes it did not need.
        progress.set_done(1 + passes);
    }

    // The styled guides' per-vertex attributes, carried to the children: `rest` deformed like
    // points, the material frames rebuilt along the children's own curves (as a reader would:
    // the guides' frames follow other edges), the others blended; merged with the guides' own
    // over every strand. Integer attributes (ids) are not blended: styling leaves them as they
    // were, the children's their own. The same for each captured frame of `--frames` output,
    // from that frame's guides.
    let is_carried = |a: &Attribute| a.rate == AttributeRate::Vertex && !a.kind.is_integer();
    let carried = |from: &Children,
                   from_pose: &Curves,
                   after: &Curves,
                   child_points: &[Vec3],
                   guide_attributes: &[Attribute]| {
        guide_attributes
            .iter()
            .filter(|a| is_carried(a))
            .map(|attribute| {
                let values = attribute.floats();
                let data = if attribute.name == "rest" && attribute.components == 3 {
                    let rest: Vec<Vec3> = values.chunks_exact(3).map(Vec3::from_slice).collect();
                    deform::deform(from, from_pose, &posed(rest)).iter().flat_map(|p| p.to_array()).collect()
                } else if attribute.name == MATERIAL_FRAME {
                    rebuilt_frames(child_points, &children.strand_offsets)
                } else {
                    deform::blend_attribute(&bound, after, &values, attribute.components)
                };
                let child =
                    Attribute::new(attribute.name.clone(), AttributeRate::Vertex, attribute.components, data);
                merge_vertex_attribute(&groom, &guide_ids, attribute, &child_ids, &child)
            })
            .collect::<Vec<Attribute>>()
    };

    let mut out = groom.clone();
    scatter_points(&mut out, &guide_ids, &styled.groom.points);
    scatter_points(&mut out, &child_ids, &child_points);
    progress.set_message("rest shapes");
    for attribute in carried(&last, last_pose, &after, &child_points, &styled.groom.attributes) {
        out.provide_attribute(attribute);
    }
    progress.inc(1);
    hold_children_up(&mut out, &styled.groom, &guide_ids, &child_ids, &placed.recipe, || progress.inc(1))?;
    let (closest, weights) = binding_attributes(&groom.strand_ids, &guide_ids, &child_ids, &bindings)?;
    out.provide_attribute(closest);
    out.provide_attribute(weights);
    out.guides = Some(flags);
    out.validate()?;

    let mut frames = Vec::with_capacity(styled.frames.len());
    let mut frame_attributes = Vec::with_capacity(styled.frame_attributes.len());
    progress.set_message("frames");
    let count = styled.frames.len();
    for (index, frame) in styled.frames.into_iter().enumerate() {
        // The last frame is the final state: the output itself, children moved apart and held
        // up by their solved rests (placed again, a reader at the last time got the children
        // before both: rests up to 0.26 m off on a 2,000-strand groom, and the overlaps back).
        if index + 1 == count && frame == styled.groom.points {
            frames.push(out.points.clone());
            if let Some(guide_attributes) = styled.frame_attributes.get(index) {
                let final_values = guide_attributes.iter().filter(|a| is_carried(a));
                frame_attributes.push(final_values.filter_map(|a| out.attribute(&a.name).cloned()).collect());
            }
            progress.inc(1);
            continue;
        }
        let (from, from_pose) = start(index);
        let after = posed(frame.clone());
        let mut points = deform::deform(&from, from_pose, &after);
        // The colliders where they were at that frame: a press part-way in, the rods.
        let colliders = styled.frame_colliders.get(index).map_or(styled.colliders.as_slice(), |c| c);
        push_out(&mut points, &children.strand_offsets, &radii, colliders, ceilings(&after).as_ref());
        let mut all = out.points.clone();
        scatter(&mut all, &out, &guide_ids, &frame);
        scatter(&mut all, &out, &child_ids, &points);
        frames.push(all);
        if let Some(guide_attributes) = styled.frame_attributes.get(index) {
            frame_attributes.push(carried(&from, from_pose, &after, &points, guide_attributes));
        }
        progress.inc(1);
    }
    progress.finish();
    let mut report = styled.report;
    report.strands = out.strand_count();
    report.vertices = out.vertex_count();
    report.guides = Some(guide_ids.len());
    Ok(Styled {
        groom: out,
        report,
        frames,
        frame_attributes,
        frame_colliders: styled.frame_colliders,
        colliders: styled.colliders,
        frames_per_second: styled.frames_per_second,
        droplets: Vec::new(),
    })
}

/// Every strand's frames parallel-transported along its points (`sim::rod::transport_frames`),
/// as `material_frame` data.
fn rebuilt_frames(points: &[Vec3], offsets: &[u32]) -> Vec<f32> {
    let mut frames = vec![glam::Quat::IDENTITY; points.len()];
    for strand in offsets.windows(2) {
        let range = strand[0] as usize..strand[1] as usize;
        transport_frames(&points[range.clone()], &mut frames[range]);
    }
    frames.iter().flat_map(|q| q.to_array()).collect()
}

/// The bindings a file brought as `groom_closest_guides` / `groom_guide_weights` (per strand,
/// three components each), for the children; `None` when the file has none. A child's guides are
/// named by their strand ids; a weighted entry naming no guide's id is an error with the
/// child's strand index. A child whose weights are all 0 is bound to nothing (`None`).
fn file_bindings(
    groom: &Groom,
    guides: &[usize],
    children: &[usize],
) -> Result<Option<Vec<Option<Binding>>>> {
    let per_strand = |name| {
        groom.attribute(name).filter(|a| a.rate == AttributeRate::Strand && a.components == GUIDES_PER_CHILD)
    };
    let (Some(closest), Some(weights)) = (per_strand(CLOSEST_GUIDES), per_strand(GUIDE_WEIGHTS)) else {
        return Ok(None);
    };
    let mut by_id = std::collections::HashMap::with_capacity(guides.len());
    for (index, &g) in guides.iter().enumerate() {
        if let Some(other) = by_id.insert(groom.strand_ids[g], index) {
            return Err(binding::file_error(format!(
                "strands {} and {g} are guides with the same groom_id {}: groom_closest_guides cannot tell them apart",
                guides[other], groom.strand_ids[g]
            )));
        }
    }
    let (closest, weights) = (closest.floats(), weights.floats());
    let mut bindings = Vec::with_capacity(children.len());
    for &c in children {
        let mut binding = Binding { guides: [0; GUIDES_PER_CHILD], weights: [0.0; GUIDES_PER_CHILD] };
        for k in 0..GUIDES_PER_CHILD {
            let (id, weight) = (closest[c * GUIDES_PER_CHILD + k], weights[c * GUIDES_PER_CHILD + k]);
            binding.weights[k] = weight;
            // An unweighted entry names nothing (Unreal writes 0 or -1 there).
            if weight == 0.0 {
                continue;
            }
            let guide = (id >= 0.0 && id.fract() == 0.0 && id < EXACT_IDS as f32)
                .then(|| by_id.get(&(id as u32)))
                .flatten();
            binding.guides[k] = match guide {
                Some(&index) => index as u32,
                None => {
                    return Err(binding::file_error(format!(
                        "strand {c}: groom_closest_guides names groom_id {id} with weight {weight}, but none of the \
                         groom's {} guides has that id",
                        guides.len()
                    )))
                }
            };
        }
        // Unweighted slots repeat the first weighted guide, as `binding::bind` writes them.
        let Some(first) = (0..GUIDES_PER_CHILD).find(|&k| binding.weights[k] != 0.0) else {
            bindings.push(None);
            continue;
        };
        let guide = binding.guides[first];
        for k in (0..GUIDES_PER_CHILD).filter(|&k| binding.weights[k] == 0.0) {
            binding.guides[k] = guide;
        }
        bindings.push(Some(binding));
    }
    Ok(Some(bindings))
}

/// The bindings as per-strand attributes, guides named by strand id; guides name themselves with
/// weight 1.
fn binding_attributes(
    strand_ids: &[u32],
    guides: &[usize],
    children: &[usize],
    bindings: &[Binding],
) -> Result<(Attribute, Attribute)> {
    let id = |g: usize| {
        match strand_ids[g] {
        id if id < EXACT_IDS => Ok(id as f32),
        id => Err(binding::file_error(format!(
            "strand {g}: a guide's groom_id {id} is too large for groom_closest_guides (ids below {EXACT_IDS} \
             stay exact in USD's float3)"
        ))),
    }
    };
    let strands = strand_ids.len();
    let mut closest = vec![0.0; strands * GUIDES_PER_CHILD];
    let mut weights = vec![0.0; strands * GUIDES_PER_CHILD];
    for &g in guides {
        closest[g * GUIDES_PER_CHILD..][..GUIDES_PER_CHILD].fill(id(g)?);
        weights[g * GUIDES_PER_CHILD] = 1.0;
    }
    for (b, &c) in bindings.iter().zip(children) {
        for k in 0..GUIDES_PER_CHILD {
            closest[c * GUIDES_PER_CHILD + k] = id(guides[b.guides[k] as usize])?;
            weights[c * GUIDES_PER_CHILD + k] = b.weights[k];
        }
    }
    Ok((
        Attribute::new(CLOSEST_GUIDES, AttributeRate::Strand, GUIDES_PER_CHILD, closest),
        Attribute::new(GUIDE_WEIGHTS, AttributeRate::Strand, GUIDES_PER_CHILD, weights),
    ))
}

/// Children are never simulated: their interpolated shape is not a rest state of their blended
/// bonds, and simulated again they sagged (the demo's permed children: 34 mm in 2 s at the
/// median, 178 mm at worst). Their rest state is solved to hold the shape they were given under
/// the recipe's gravity and the water they carry (`sim::sag_free`), with their bond rates kept;
/// the guides keep the rest state of `styled_guides` (in `guide_ids` order). The solve is per
/// strand, so children go through it in batches of [`HOLD_BATCH`] strands: a rod state for
/// 98,000 children at once took about 1.2 GB of the 100,000-strand run's 1.96 GB peak.
fn hold_children_up(
    out: &mut Groom,
    styled_guides: &Groom,
    guide_ids: &[usize],
    child_ids: &[usize],
    placed: &Recipe,
    batch_done: impl Fn() + Sync,
) -> Result<()> {
    use rayon::prelude::*;
    if child_ids.is_empty() {
        return Ok(());
    }
    let mut params = sim_params(placed);
    if let Some(Stage::Settle { gravity: Some(false), .. }) = placed.stages.last().map(|s| s.get_ref()) {
        params.gravity = Vec3::ZERO;
    }
    let flat = |v: Vec<Vec3>| v.into_iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
    let source: &Groom = out;
    let batches = child_ids
        .par_chunks(HOLD_BATCH)
        .map(|batch| {
            let children = subset(source, batch);
            let mut sim = Simulation::new(&children, params.clone())?;
            carry_groom_water(&mut sim, &children);
            sim.make_sag_free();
            batch_done();
            Ok((flat(sim.rest_curves()), flat(sim.exported_rest_darboux())))
        })
        .collect::<Result<Vec<_>>>()?;
    let (rest, darboux): (Vec<Vec<f32>>, Vec<Vec<f32>>) = batches.into_iter().unzip();
    for (name, parts) in [("rest", rest), (REST_DARBOUX, darboux)] {
        let guide_part = styled_guides.attribute(name).expect("styled guides carry their rest state");
        let child_part = Attribute::new(name, AttributeRate::Vertex, 3, parts.concat());
        let merged = merge_vertex_attribute(out, guide_ids, guide_part, child_ids, &child_part);
        out.provide_attribute(merged);
    }
    Ok(())
}

/// Children per batch of [`hold_children_up`]: a rod state of ~50 MB at 32 vertices per strand.
const HOLD_BATCH: usize = 4096;

/// The strands `which` of a groom (points, widths, ids, UVs and attributes), in that order.
fn subset(groom: &Groom, which: &[usize]) -> Groom {
    let mut out = Groom {
        strand_offsets: vec![0],
        basis: groom.basis,
        root_uvs: groom.root_uvs.as_ref().map(|uvs| which.iter().map(|&s| uvs[s]).collect()),
        ..Default::default()
    };
    for &s in which {
        let range = groom.strand_range(s);
        out.points.extend_from_slice(&groom.points[range.clone()]);
        out.widths.extend_from_slice(&groom.widths[range]);
        out.strand_offsets.push(out.points.len() as u32);
        out.strand_ids.push(groom.strand_ids[s]);
    }
    for attribute in &groom.attributes {
        let c = attribute.components;
        let mut data = attribute.data.empty_like(0);
        for &s in which {
            let range = match attribute.rate {
                AttributeRate::Vertex => groom.strand_range(s),
                AttributeRate::Strand => s..s + 1,
            };
            data.extend_from(&attribute.data, range.start * c..range.end * c, 1);
        }
        let (name, rate, kind) = (attribute.name.clone(), attribute.rate, attribute.kind);
        out.set_attribute(Attribute { name, rate, components: c, data, kind });
    }
    out
}

/// Writes a subset's points back into the full groom's strands `which`.
fn scatter_points(groom: &mut Groom, which: &[usize], points: &[Vec3]) {
    let mut all = std::mem::take(&mut groom.points);
    scatter(&mut all, groom, which, points);
    groom.points = all;
}

fn scatter(all: &mut [Vec3], groom: &Groom, which: &[usize], points: &[Vec3]) {
    let mut at = 0;
    for &s in which {
        let range = groom.strand_range(s);
        let n = range.len();
        all[range].copy_from_slice(&points[at..at + n]);
        at += n;
    }
}

/// A per-vertex attribute of the full groom from its guides' and children's parts.
fn merge_vertex_attribute(
    groom: &Groom,
    guides: &[usize],
    guide_part: &Attribute,
    children: &[usize],
    child_part: &Attribute,
) -> Attribute {
    let c = guide_part.components;
    let mut data = vec![0.0; groom.vertex_count() * c];
    for (which, part) in [(guides, guide_part), (children, child_part)] {
        let part = part.floats();
        let mut at = 0;
        for &s in which {
            let range = groom.strand_range(s);
            let n = range.len() * c;
            data[range.start * c..range.end * c].copy_from_slice(&part[at..at + n]);
            at += n;
        }
    }
    Attribute::new(guide_part.name.clone(), AttributeRate::Vertex, c, data)
}

/// Moves children out of the recipe's colliders, root to tip: each edge keeps its deformed
/// direction from the (possibly pushed) vertex before it, turned back where it would turn from
/// the placed edge before it by more than the deformed child turns there plus [`TURN_SLACK`]. An
/// edge that ends inside a collider turns just enough to end on its surface (see
/// [`lifted_direction`]) and is placed again, [`PUSH_PASSES`] times, then pushed out. So a child
/// that meets the head slides over it, and a curl whose loop dives into the head is laid on the
/// scalp as a curl: pushing each vertex to the nearest surface point folded such loops back
/// (edges turning 134° and 145° where the deformed children turned 35° and 42°), a shape no rod
/// holds at rest (those children fell 34.5 and 18 mm when simulated again). Roots stay.
///
/// With `ceilings`, a child first turns down about its root until its weight hangs no higher
/// than its guides' ([`HangCeilings`]); where that turns it into a collider the push lifts it a
/// little again, so the two take turns, up to [`PLACING_ROUNDS`] times (on bed-head's crown
/// one round left 13 of 28 falling children falling, eight rounds one).
fn push_out(
    points: &mut [Vec3],
    offsets: &[u32],
    radii: &[f32],
    shapes: &[Shape],
    ceilings: Option<&HangCeilings>,
) {
    use rayon::prelude::*;
    let mut strands = deform::split_mut(points, offsets);
    strands.par_iter_mut().enumerate().for_each(|(s, strand)| {
        let radii = &radii[offsets[s] as usize..offsets[s + 1] as usize];
        let mut lowering = false;
        for round in 0..PLACING_ROUNDS {
            let lowered = ceilings.is_some_and(|c| c.lower(s, strand, lowering));
            lowering |= lowered;
            if round > 0 && !lowered {
                break;
            }
            push_strand_out(strand, radii, shapes);
        }
    });
}

/// Times [`push_out`] lowers a child and pushes it out again, at most.
const PLACING_ROUNDS: usize = 8;

/// One strand's part of [`push_out`] (`radii` its own), without the lowering.
fn push_strand_out(strand: &mut [Vec3], radii: &[f32], shapes: &[Shape]) {
    let outside = |p: Vec3, radius: f32| outside(p, radius, shapes);
    let mut previous_deformed = strand[0];
    // The deformed edge into the previous vertex and the placed one, as unit vectors.
    let mut previous_edges: Option<(Vec3, Vec3)> = None;
    for k in 1..strand.len() {
        let deformed = strand[k];
        let edge = deformed - previous_deformed;
        previous_deformed = deformed;
        let (length, radius) = (edge.length(), radii[k]);
        let Some(deformed_direction) = edge.try_normalize() else {
            strand[k] = strand[k - 1];
            continue;
        };
        let turned = |direction: Vec3| match previous_edges {
            Some((deformed_before, placed_before)) => {
                let allowed = deformed_before.angle_between(deformed_direction) + TURN_SLACK;
                turned_at_most(placed_before, direction, allowed)
            }
            None => direction,
        };
        // Where the edge heads straight into a collider, the way the strand came (at the
        // root, the way its next edge goes).
        let course = match previous_edges {
            Some((_, placed_before)) => placed_before,
            None => {
                strand.get(k + 1).map_or(deformed_direction, |&next| (next - deformed).normalize_or_zero())
            }
        };
        let mut direction = deformed_direction;
        for _ in 0..PUSH_PASSES {
            direction = turned(direction);
            let placed = strand[k - 1] + direction * length;
            let pushed = outside(placed, radius);
            let Some(normal) = (pushed - placed).try_normalize() else { break };
            direction = lifted_direction(strand[k - 1], pushed, length, normal, course);
        }
        strand[k] = outside(strand[k - 1] + direction * length, radius);
        let placed = (strand[k] - strand[k - 1]).try_normalize().unwrap_or(direction);
        previous_edges = Some((deformed_direction, placed));
    }
}

/// The direction of an edge from `start` whose end was pushed out of a collider to `pushed` (the
/// surface's `normal` there): turned just enough to end on the surface's tangent plane there,
/// keeping its length and the way it heads across the surface. The turn shrinks to nothing as
/// the end comes out (sliding along the surface whatever the depth jumped by the whole angle into
/// the surface between an end just inside and one just outside). An edge heading straight in
/// heads across the surface by nothing, or by rounding noise (the same child in metres and in
/// centimetres: 1.2 mm apart before the push, 30 mm at the tip after): within [`STRAIGHT_IN`] of
/// it, the way across blends into `course`'s, all the way at straight in.
fn lifted_direction(start: Vec3, pushed: Vec3, length: f32, normal: Vec3, course: Vec3) -> Vec3 {
    let lifted = (pushed - start) / length;
    let across = lifted - normal * lifted.dot(normal);
    let remainder = across.length();
    let along = if remainder >= STRAIGHT_IN {
        across / remainder
    } else {
        let fallback =
            (course - normal * course.dot(normal)).try_normalize().unwrap_or(normal.any_orthonormal_vector());
        (across + fallback * (STRAIGHT_IN - remainder)).try_normalize().unwrap_or(fallback)
    };
    // How far the start lies over that tangent plane, in edge lengths: the edge's drop.
    let drop = (-lifted.dot(normal)).clamp(-1.0, 1.0);
    along * (1.0 - drop * drop).sqrt() - normal * drop
}

/// How far across the surface (as a share of the edge) an edge pushed out of a collider must end
/// for its own direction to say which way it slides (see [`lifted_direction`]).
const STRAIGHT_IN: f32 = 0.1;

/// A point of a strand of `radius` pushed out of every collider in turn, without friction.
fn outside(mut p: Vec3, radius: f32, shapes: &[Shape]) -> Vec3 {
    for shape in shapes {
        if let Some((depth, normal)) = penetration(shape, p, radius) {
            p += normal * depth;
        }
    }
    p
}

/// `direction` turned back towards `from` (unit vectors) so that it is at most `angle` from it.
fn turned_at_most(from: Vec3, direction: Vec3, angle: f32) -> Vec3 {
    if from.angle_between(direction) <= angle {
        return direction;
    }
    let across =
        (direction - from * from.dot(direction)).try_normalize().unwrap_or(from.any_orthonormal_vector());
    from * angle.cos() + across * angle.sin()
}

/// How much more than the deformed child an edge [`push_out`] moves may turn from the edge
/// before it.
const TURN_SLACK: f32 = 15.0 * std::f32::consts::PI / 180.0;

/// Times [`push_out`] brings a pushed vertex back to its edge's length and pushes it out again.
const PUSH_PASSES: usize = 4;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::{generate, GenerateParams, Style};

    /// A curl whose loop dives 8 mm into the head is laid on it: no vertex inside, no edge
    /// longer or shorter by more than 1 %, the root where it was, and no edge turned back on the
    /// one before. Pushing each vertex to the nearest surface point folded the loop (an edge
    /// turned 161°; here the sharpest turn, 65°, is where the curl's steep front meets the head).
    #[test]
    fn a_curl_diving_into_the_head_is_laid_on_it_unfolded() {
        let head = Shape::Sphere { center: Vec3::ZERO, radius: 0.1 };
        let (curl, edges) = (0.01, 24);
        let turn = std::f32::consts::TAU / edges as f32;
        // Down the front of the loop, through its bottom 8 mm inside the head, up and round again.
        let points: Vec<Vec3> = (0..=edges + edges / 2)
            .map(|i| {
                let t = i as f32 * turn;
                Vec3::new(curl * t.sin() + 0.001 * i as f32, 0.102 + curl * t.cos(), 0.0)
            })
            .collect();
        let mut pushed = points.clone();
        let radii = vec![0.0; points.len()];
        push_out(&mut pushed, &[0, points.len() as u32], &radii, std::slice::from_ref(&head), None);
        assert_eq!(pushed[0], points[0]);
        let mut sharpest: f32 = 0.0;
        for k in 1..points.len() {
            assert!(pushed[k].length() > 0.1 - 1e-6, "vertex {k} inside: {:?}", pushed[k]);
            let (was, is) = (points[k].distance(points[k - 1]), pushed[k].distance(pushed[k - 1]));
            assert!((is / was - 1.0).abs() < 0.01, "edge {k}: {was} became {is}");
            if k >= 2 {
                let before = pushed[k - 1] - pushed[k - 2];
                sharpest = sharpest.max(before.angle_between(pushed[k] - pushed[k - 1]));
            }
        }
        assert!(points.iter().any(|p| p.length() < 0.095), "the curl dives into the head");
        assert!(sharpest < std::f32::consts::FRAC_PI_2, "an edge turns {:.1}°", sharpest.to_degrees());
    }

    /// The push is continuous in where a child was placed. A strand lying along the top of the
    /// head turns straight down into it; placed with its lateral coordinates off by rounding
    /// (±1e-7 m), it must come out the same within 1 % of its length at every vertex (it slid
    /// towards the rounding, ±Z, 30 mm apart at the tip). And an edge ending 1 µm inside the
    /// head or 1 µm outside it must give nearly the same strand (sliding removed the whole
    /// angle into the surface in the first, nothing in the second).
    #[test]
    fn pushed_children_are_continuous_in_where_they_were_placed() {
        let head = Shape::Sphere { center: Vec3::ZERO, radius: 0.1 };
        let floor = Shape::Plane { point: Vec3::new(0.0, 0.1, 0.0), normal: Vec3::Y };
        let push_from = |points: &[Vec3], shape: &Shape| {
            let mut pushed = points.to_vec();
            push_out(
                &mut pushed,
                &[0, points.len() as u32],
                &vec![0.0; points.len()],
                std::slice::from_ref(shape),
                None,
            );
            pushed
        };
        let push = |points: &[Vec3]| push_from(points, &head);
        let length = |points: &[Vec3]| points.windows(2).map(|e| e[0].distance(e[1])).sum::<f32>();
        let apart = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).map(|(p, q)| p.distance(*q)).fold(0.0, f32::max);
        // Along the top, then 5 mm edges straight down into the head at its crown, rounded sideways.
        let diving = |dz: f32| -> Vec<Vec3> {
            let mut points: Vec<Vec3> =
                (0..4).map(|k| Vec3::new(0.005 * k as f32 - 0.015, 0.1005, 0.0)).collect();
            points.extend((1..8).map(|k| Vec3::new(dz * k as f32, 0.1005 - 0.005 * k as f32, dz)));
            points
        };
        let reference = push(&diving(0.0));
        for dz in [1e-7, -1e-7] {
            let pushed = push(&diving(dz));
            let worst = apart(&pushed, &reference) / length(&reference);
            assert!(worst < 0.01, "rounded by {dz:e}: {:.1} % of the length apart", 100.0 * worst);
        }
        assert!(reference.iter().all(|p| p.length() > 0.1 - 1e-6), "a vertex inside: {reference:?}");
        // An edge from 1 mm over a floor, heading down at 45°, its end 1 µm either side of it.
        let grazing = |depth: f32| -> Vec<Vec3> {
            let start = Vec3::new(0.0, 0.101, 0.0);
            let reach = 0.001 + depth;
            let down = Vec3::new(1.0, -1.0, 0.0).normalize();
            let end = start + down * (reach * std::f32::consts::SQRT_2);
            vec![start, end, end + Vec3::new(0.005, 0.0, 0.0), end + Vec3::new(0.01, 0.0, 0.0)]
        };
        let (inside, outside) = (push_from(&grazing(1e-6), &floor), push_from(&grazing(-1e-6), &floor));
        let worst = apart(&inside, &outside);
        assert!(worst < 2e-5, "1 µm in or out of the floor: {worst:e} m apart ({inside:?} vs {outside:?})");
    }

    /// The rest-state solve is per strand: children solved in batches get the bits of one solve
    /// over all of them.
    #[test]
    fn childrens_rest_states_do_not_depend_on_the_batches() {
        let mut groom = generate(&GenerateParams {
            strands: HOLD_BATCH + 700,
            vertices_per_strand: 5,
            style: Style::Curly { radius: 0.01, pitch: 0.02 },
            ..Default::default()
        })
        .unwrap();
        let guide_ids: Vec<usize> = (0..groom.strand_count()).step_by(40).collect();
        let child_ids: Vec<usize> = (0..groom.strand_count()).filter(|s| s % 40 != 0).collect();
        let recipe = crate::style::recipe::parse(
            "[[stages]]\nkind = \"settle\"\nmax_seconds = 1.0\n",
            std::path::Path::new("hold.toml"),
        )
        .unwrap();
        let mut styled_guides = subset(&groom, &guide_ids);
        for attribute in Simulation::new(&styled_guides, sim_params(&recipe)).unwrap().state_attributes() {
            styled_guides.set_attribute(attribute);
        }
        hold_children_up(&mut groom, &styled_guides, &guide_ids, &child_ids, &recipe, || {}).unwrap();

        let children = subset(&groom, &child_ids);
        let mut whole = Simulation::new(&children, sim_params(&recipe)).unwrap();
        whole.make_sag_free();
        let expected = whole.state_attributes();
        for name in ["rest", REST_DARBOUX] {
            let got = subset(&groom, &child_ids).attribute(name).unwrap().floats().into_owned();
            let want = &expected.iter().find(|a| a.name == name).unwrap().floats();
            assert!(
                got.len() == want.len()
                    && got.iter().zip(want.iter()).all(|(a, b)| a.to_bits() == b.to_bits()),
                "{name}"
            );
        }
    }
}
