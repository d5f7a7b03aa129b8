//! Strands wound on rods close to the scalp: the free part between the pinned root and the held
//! winding must be able to reach the rod, or its vertices are pulled apart every step and shake
//! for as long as the strand is held. Nor may that free part stay inside the rod.
use std::path::Path;

use coif::generate::{generate, GenerateParams};
use coif::interact::obstacles::Shape;
use coif::style::placement::{head_frame, place};
use coif::style::{recipe, style, StyleOptions};

#[test]
fn strands_held_on_the_full_head_rods_stay_still() {
    let groom = generate(&GenerateParams {
        strands: 300,
        vertices_per_strand: 32,
        length: 0.24,
        seed: 21,
        ..GenerateParams::default()
    })
    .unwrap();
    // The production perm's rods and head, with a short wrap and hold.
    let preset = std::fs::read_to_string("grooms/recipes/perm_full_head.toml").unwrap();
    let setup = &preset[..preset.find("[[stages]]").unwrap()];
    let text = format!(
        "{}[[stages]]\nkind = \"wrap\"\nduration = 0.2\n[[stages]]\nkind = \"process\"\nduration = 0.2\n",
        setup.replace("hair_hair = true", "hair_hair = false")
    );
    let recipe = recipe::parse(&text, Path::new("perm_full_head.toml")).unwrap();
    let dt = recipe.settings.dt;
    let options = StyleOptions { frames_per_second: 1.0 / dt, ..Default::default() };
    let styled = style(&groom, &recipe, &options).unwrap();
    // The second half of the hold: the hair still creeps after the wrap (~5 cm/s), but nothing
    // shakes (a vertex pulled between root and rod jumps about at metres per second).
    let frames = &styled.frames[styled.frames.len() * 3 / 4..];
    let fastest = frames
        .windows(2)
        .flat_map(|w| w[0].iter().zip(&w[1]).map(|(a, b)| a.distance(*b) / dt))
        .fold(0.0f32, f32::max);
    eprintln!("fastest vertex while held: {fastest:.5} m/s over {} frames", frames.len());
    assert!(fastest < 0.2, "a held strand moves at {fastest} m/s");
}

/// The full-head perm's rods lie a vertex above the scalp: as they appear, the first free vertex
/// of many strands wound on them is inside its own rod (0.3–5.7 mm deep on the 100k benchmark's
/// guides). Held between the pinned root and the winding, it cannot leave the rod by passing
/// through it: when it was let pass, it stayed inside through the whole perm, the rest shape set
/// there kinked, and the guides' settle stalled just above its tolerance. It is pushed out.
#[test]
fn the_free_part_of_a_wound_strand_lies_outside_the_rods() {
    let groom = generate(&GenerateParams {
        strands: 300,
        vertices_per_strand: 32,
        length: 0.24,
        seed: 21,
        ..GenerateParams::default()
    })
    .unwrap();
    let preset = std::fs::read_to_string("grooms/recipes/perm_full_head.toml").unwrap();
    let setup = &preset[..preset.find("[[stages]]").unwrap()];
    let text = format!(
        "{}[[stages]]\nkind = \"wrap\"\nduration = 0.2\n[[stages]]\nkind = \"process\"\nduration = 0.1\n",
        setup.replace("hair_hair = true", "hair_hair = false")
    );
    let recipe = recipe::parse(&text, Path::new("perm_full_head.toml")).unwrap();
    let frame = head_frame(&recipe, &groom, None).unwrap();
    let rods: Vec<Shape> = place(&recipe, &groom, None, frame)
        .unwrap()
        .recipe
        .rods
        .iter()
        .map(|r| {
            let r = r.get_ref();
            Shape::Capsule { a: r.a.into(), b: r.b.into(), radius: r.radius }
        })
        .collect();
    // Control: the rods do appear around hair (else this tests nothing).
    let inside = |points: &[glam::Vec3]| {
        let depths =
            points.iter().map(|&p| rods.iter().map(|r| -r.signed_distance(p)).fold(0.0f32, f32::max));
        let deep: Vec<f32> = depths.filter(|&d| d > 1e-4).collect();
        (deep.len(), deep.iter().copied().fold(0.0f32, f32::max))
    };
    let (before, _) = inside(&groom.points);
    assert!(before > 30, "only {before} vertices lie inside a rod before the wrap");
    let styled = style(&groom, &recipe, &StyleOptions::default()).unwrap();
    let (count, deepest) = inside(&styled.groom.points);
    eprintln!("vertices inside a rod: {before} before the wrap, {count} after (deepest {deepest:.5} m)");
    assert!(count == 0, "{count} vertices stay inside a rod after the wrap, {deepest} m deep at most");
}
