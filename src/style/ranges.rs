//! The documented range of every number a recipe holds, checked through `crate::validate`
//! before the recipe's other rules run. A refusal names the line, the key, the value and the
//! range. The ranges are wide enough for any real styling job and narrow enough that nothing
//! downstream divides by zero, overflows a grid or allocates without bound:
//!
//! | key | range |
//! |---|---|
//! | `[settings]` `dt` | [1e-6, 0.1] s |
//! | `iterations` | [1, 1000] |
//! | `gravity` | components in [-1000, 1000] m/s² |
//! | `youngs_modulus`, `shear_modulus` | [1e5, 1e12] Pa |
//! | `density` | [1, 1e5] kg/m³ |
//! | `cuticle_peel_per_metre` | [0, 1000] /m |
//! | `max_segment` | [1e-5, 10] m |
//! | `damping` | [0, 1e4] /s |
//! | `[bonds]` each influence | [0, 1000] (only ratios matter) |
//! | `[contacts]` `hair_stiffness` | [0, 1e4] m/s² |
//! | `sample_spacing` | [1e-4, 1] m |
//! | `static_friction`, `dynamic_friction` | [0, 10]; `dynamic_friction` at most `static_friction` |
//! | `[wetness]` `diffusion` | [0, 0.01] m²/s |
//! | `evaporation` | [0, 1000] /s; `airflow_drying` [0, 10] per m/s; `mass_gain` [0, 10] |
//! | `[water]` `r_min` | (0, 0.1] m; `r_max` (r_min, 0.5] m |
//! | `hair_pull`, `droplet_pull` | [0, 1e5], [0, 1e6] m/s²; `droplet_damping` [0, 1e4] /s; `uptake` [0, 1000] /s |
//! | obstacle and rod positions, dryer position and target | components in [-1000, 1000] m |
//! | sphere `radius`, head `radii`, box `half_extents`, rod `radius` | (0, 1000] m |
//! | mesh `resolution` | [1e-4, 1] m; `band` [resolution, 1] m |
//! | plane `normal`, press `direction` | finite, not zero |
//! | stage `duration`, settle `max_seconds` | [0, 1e5] s |
//! | `amount`, mask `fraction`, bond amounts | [0, 1] |
//! | dryer `strength` | [0, 1e5] m/s²; `falloff` (0, 1000] m; `cone_degrees` (0, 180] |
//! | dry `heat` | [0, 100]; press `travel` [0, 1000] m |
//! | `[head]` `size`, `[guides]` `reach` | (0, 1000] m |
//! | `[head]` `center` | components in [-1000, 1000] m; `up`, `front` finite, not zero, not parallel |
//! | layout `diameter`, `spacing` | (0, 1000]; `spacing` fine enough for at most 1,000 rods (`layout::too_many_rods`) |
//! | `[guides]` `fraction` (0, 1]; `count` at least 1 (and at most the strands) | |
//! | stages | at most 10,000 |
//! | obstacles, rods | at most 1,000 each (a layout's rods too) |
use crate::validate::{self, Range, COORDINATE, DENSITY, FRACTION, ITERATIONS, MODULUS, SECONDS, TIME_STEP};

use super::recipe::{Obstacle, Recipe, Stage};

/// Stages a recipe may have.
pub const MAX_STAGES: usize = 10_000;
/// Obstacles, and rods, a recipe may have (each): a perm sets a few dozen rods, and every vertex
/// is tested against every obstacle beyond the first 128 at every iteration (`ObstacleCulling`),
/// so 20,000 spheres made a 0.05 s stage of a 20-strand groom take 4.7 s.
pub const MAX_OBSTACLES: usize = 1_000;
const SIZE: Range = Range::above(0.0, 1e3);

/// Line starts of a text, for line numbers of byte offsets in O(log n).
pub struct Lines {
    starts: Vec<usize>,
}

impl Lines {
    pub fn new(text: &str) -> Lines {
        let starts = std::iter::once(0).chain(text.match_indices('\n').map(|(i, _)| i + 1)).collect();
        Lines { starts }
    }

    /// 1-based line and column of a byte offset.
    pub fn line_column(&self, text: &str, offset: usize) -> (usize, usize) {
        let offset = offset.min(text.len());
        let line = self.starts.partition_point(|&s| s <= offset);
        (line, offset - self.starts[line - 1] + 1)
    }
}

/// The line of `key` inside table `[section]` (for tables without spans), if written there.
fn line_of_key(text: &str, section: &str, key: &str) -> Option<usize> {
    let mut current = String::new();
    for (index, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        if trimmed.starts_with('[') {
            current = trimmed.trim_matches(|c| c == '[' || c == ']').trim().to_string();
        } else if current == section
            && trimmed.strip_prefix(key).is_some_and(|rest| rest.trim_start().starts_with('='))
        {
            return Some(index + 1);
        }
    }
    None
}

/// Checks every number of `recipe` against its documented range.
pub fn check_numbers(recipe: &Recipe, text: &str) -> Result<(), String> {
    let lines = Lines::new(text);
    let line_of = |span: std::ops::Range<usize>| lines.line_column(text, span.start).0;
    // A refusal of a key in a table without spans: "line N: [section] key = …".
    let in_table = |section: &str, key: &str, check: Result<(), String>| {
        check.map_err(|message| match line_of_key(text, section, key) {
            Some(line) => format!("line {line}: {message}"),
            None => message,
        })
    };
    let table = |section: &str, key: &str, value: f64, range: Range| {
        in_table(section, key, validate::number(&format!("[{section}] {key}"), value, range))
    };
    let s = &recipe.settings;
    table("settings", "dt", s.dt.into(), TIME_STEP)?;
    table("settings", "iterations", s.iterations.into(), ITERATIONS)?;
    in_table("settings", "gravity", validate::vector("[settings] gravity", s.gravity, COORDINATE))?;
    table("settings", "youngs_modulus", s.youngs_modulus.into(), MODULUS)?;
    table("settings", "shear_modulus", s.shear_modulus.into(), MODULUS)?;
    table("settings", "density", s.density.into(), DENSITY)?;
    table("settings", "cuticle_peel_per_metre", s.cuticle_peel_per_metre.into(), Range::closed(0.0, 1e3))?;
    if let Some(max) = s.max_segment {
        table(
            "settings",
            "max_segment",
            max.into(),
            Range::closed(super::placement::MIN_SEGMENT.into(), 10.0),
        )?;
    }
    table("settings", "damping", s.damping.into(), Range::closed(0.0, 1e4))?;
    let b = &recipe.bonds;
    for (key, value) in
        [("hydrogen", b.hydrogen), ("ionic", b.ionic), ("disulfide", b.disulfide), ("peptide", b.peptide)]
    {
        table("bonds", key, value.into(), Range::closed(0.0, 1e3))?;
    }
    let c = &recipe.contacts;
    table("contacts", "hair_stiffness", c.hair_stiffness.into(), Range::closed(0.0, 1e4))?;
    table("contacts", "sample_spacing", c.sample_spacing.into(), Range::closed(1e-4, 1.0))?;
    table("contacts", "static_friction", c.static_friction.into(), Range::closed(0.0, 10.0))?;
    table("contacts", "dynamic_friction", c.dynamic_friction.into(), Range::closed(0.0, 10.0))?;
    // Coulomb: a contact that slides is held less than one at rest (μ_k ≤ μ_s). A larger dynamic
    // friction brakes a sliding vertex harder than the static one holds it.
    if c.dynamic_friction > c.static_friction {
        let default =
            if line_of_key(text, "contacts", "static_friction").is_none() { " (the default)" } else { "" };
        let message = format!(
            "[contacts] dynamic_friction = {} exceeds static_friction = {}{default}: sliding friction \
             cannot be more than the friction that holds a contact at rest (μ_k ≤ μ_s)",
            validate::shortest(c.dynamic_friction.into()),
            validate::shortest(c.static_friction.into()),
        );
        return in_table("contacts", "dynamic_friction", Err(message));
    }
    let w = &recipe.wetness;
    table("wetness", "diffusion", w.diffusion.into(), Range::closed(0.0, 0.01))?;
    table("wetness", "evaporation", w.evaporation.into(), Range::closed(0.0, 1e3))?;
    table("wetness", "airflow_drying", w.airflow_drying.into(), Range::closed(0.0, 10.0))?;
    table("wetness", "mass_gain", w.mass_gain.into(), Range::closed(0.0, 10.0))?;
    if let Some(water) = &recipe.water {
        let p = &water.params;
        table("water", "r_min", p.r_min.into(), Range::above(0.0, 0.1))?;
        table("water", "r_max", p.r_max.into(), Range::above(p.r_min.into(), 0.5))?;
        table("water", "hair_pull", p.hair_pull.into(), Range::closed(0.0, 1e5))?;
        table("water", "droplet_pull", p.droplet_pull.into(), Range::closed(0.0, 1e6))?;
        table("water", "droplet_damping", p.droplet_damping.into(), Range::closed(0.0, 1e4))?;
        table("water", "uptake", p.uptake.into(), Range::closed(0.0, 1e3))?;
    }

    let head = &recipe.head;
    if let Some(center) = head.center {
        in_table("head", "center", validate::vector("[head] center", center, COORDINATE))?;
    }
    for (key, direction) in [("up", head.up), ("front", head.front)] {
        if let Some(d) = direction {
            in_table("head", key, validate::direction(&format!("[head] {key}"), d))?;
        }
    }
    if let (Some(up), Some(front)) = (head.up, head.front) {
        if super::head_frame::front_across(up.into(), front.into()).is_none() {
            let (front, up) = (validate::vector_text(front), validate::vector_text(up));
            let message = format!("[head] front = {front} is parallel to up = {up}");
            return in_table("head", "front", Err(message));
        }
    }
    if let Some(size) = head.size {
        table("head", "size", size.into(), SIZE)?;
    }
    if let Some(guides) = recipe.guides {
        if let Some(reach) = guides.reach {
            table("guides", "reach", reach.into(), SIZE)?;
        }
        if let Some(fraction) = guides.fraction {
            table("guides", "fraction", fraction.into(), Range::above(0.0, 1.0))?;
        }
        let header = || text.lines().position(|l| l.trim() == "[guides]").map(|i| i + 1);
        let at = |line: Option<usize>, message: &str| match line {
            Some(line) => format!("line {line}: [guides] {message}"),
            None => format!("[guides] {message}"),
        };
        match (guides.count, guides.fraction) {
            (Some(_), Some(_)) => return Err(at(header(), "gives count and fraction: give one")),
            // The upper bound is the groom's strand count, checked when it is known.
            (Some(0), _) => {
                return Err(at(line_of_key(text, "guides", "count"), "count = 0: at least one guide"))
            }
            _ => {}
        }
    }

    let counts = [
        ("obstacles", recipe.obstacles.get(MAX_OBSTACLES).map(|o| o.span()), recipe.obstacles.len()),
        ("rods", recipe.rods.get(MAX_OBSTACLES).map(|r| r.span()), recipe.rods.len()),
    ];
    for (what, span, count) in counts {
        if let Some(span) = span {
            return Err(format!(
                "line {}: {count} {what}; a recipe may have at most {MAX_OBSTACLES}",
                line_of(span)
            ));
        }
    }
    for obstacle in &recipe.obstacles {
        let at = |message: String| {
            format!("line {}: obstacle '{}': {message}", line_of(obstacle.span()), obstacle.get_ref().name())
        };
        match obstacle.get_ref() {
            Obstacle::Head { center, radii, .. } => {
                center.map_or(Ok(()), |v| validate::vector("center", v, COORDINATE)).map_err(at)?;
                radii.map_or(Ok(()), |v| validate::vector("radii", v, SIZE)).map_err(at)?;
            }
            Obstacle::Sphere { center, radius, .. } => {
                validate::vector("center", *center, COORDINATE).map_err(at)?;
                validate::number("radius", *radius, SIZE).map_err(at)?;
            }
            Obstacle::Plane { point, normal, .. } => {
                validate::vector("point", *point, COORDINATE).map_err(at)?;
                validate::direction("normal", *normal).map_err(at)?;
            }
            Obstacle::Box { center, half_extents, .. } => {
                validate::vector("center", *center, COORDINATE).map_err(at)?;
                validate::vector("half_extents", *half_extents, SIZE).map_err(at)?;
            }
            Obstacle::Scalp { resolution, .. } => {
                let cell = resolution.unwrap_or(super::recipe::MESH_RESOLUTION);
                validate::number("resolution", cell, Range::closed(1e-4, 1.0)).map_err(at)?;
            }
            Obstacle::Mesh { resolution, band, .. } => {
                let cell = resolution.unwrap_or(super::recipe::MESH_RESOLUTION);
                validate::number("resolution", cell, Range::closed(1e-4, 1.0)).map_err(at)?;
                if let Some(band) = band {
                    validate::number("band", *band, Range::closed(cell.into(), 1.0)).map_err(at)?;
                }
            }
        }
    }
    for rod in &recipe.rods {
        let r = rod.get_ref();
        let at = |message: String| format!("line {}: rod '{}': {message}", line_of(rod.span()), r.name);
        validate::vector("a", r.a, COORDINATE).map_err(at)?;
        validate::vector("b", r.b, COORDINATE).map_err(at)?;
        validate::number("radius", r.radius, Range::above(0.0, 1.0)).map_err(at)?;
    }

    if recipe.stages.len() > MAX_STAGES {
        return Err(format!("{} stages; a recipe may have at most {MAX_STAGES}", recipe.stages.len()));
    }
    for (index, spanned) in recipe.stages.iter().enumerate() {
        let stage = spanned.get_ref();
        let at = |message: String| {
            format!("line {}: stage {} ({}): {message}", line_of(spanned.span()), index + 1, stage.kind())
        };
        let duration_key = if matches!(stage, Stage::Settle { .. }) { "max_seconds" } else { "duration" };
        validate::number(duration_key, stage.duration(), SECONDS).map_err(at)?;
        let mask = |m: &super::recipe::Mask| validate::number("mask fraction", m.fraction, FRACTION);
        match stage {
            Stage::Wet { amount, mask: m, .. } => {
                validate::number("amount", *amount, FRACTION).map_err(at)?;
                mask(m).map_err(at)?;
            }
            Stage::Wrap { mask: m, diameter, spacing, .. } => {
                mask(m).map_err(at)?;
                // The lower bound of `spacing` is the layout's rod count (`layout::too_many_rods`).
                diameter.map_or(Ok(()), |d| validate::number("diameter", d, SIZE)).map_err(at)?;
                spacing.map_or(Ok(()), |s| validate::number("spacing", s, SIZE)).map_err(at)?;
            }
            Stage::Lotion { mask: m, .. } => mask(m).map_err(at)?,
            Stage::Dry { dryer, heat, .. } => {
                validate::number("heat", *heat, Range::closed(0.0, 100.0)).map_err(at)?;
                if let Some(d) = dryer {
                    validate::vector("dryer position", d.position, COORDINATE).map_err(at)?;
                    validate::vector("dryer target", d.target, COORDINATE).map_err(at)?;
                    validate::number("dryer strength", d.strength, Range::closed(0.0, 1e5)).map_err(at)?;
                    if let Some(falloff) = d.falloff {
                        validate::number("dryer falloff", falloff, Range::above(0.0, 1e3)).map_err(at)?;
                    }
                    if let Some(cone) = d.cone_degrees {
                        validate::number("dryer cone_degrees", cone, Range::above(0.0, 180.0)).map_err(at)?;
                    }
                }
            }
            Stage::Press { travel, direction, .. } => {
                validate::number("travel", *travel, Range::closed(0.0, 1e3)).map_err(at)?;
                direction.map_or(Ok(()), |d| validate::direction("direction", d)).map_err(at)?;
            }
            // The settle tolerance is checked by the settle itself (`sim::settle::TOLERANCE_RANGE`).
            Stage::Settle { .. } => {}
            Stage::Process { .. }
            | Stage::Neutralise { .. }
            | Stage::Rinse { .. }
            | Stage::Release { .. } => {}
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_numbers_match_a_linear_scan() {
        let text = "a\nbb\n\nccc";
        let lines = Lines::new(text);
        for offset in 0..=text.len() {
            let before = &text[..offset];
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            assert_eq!(lines.line_column(text, offset), (line, column), "offset {offset}");
        }
    }

    #[test]
    fn keys_of_plain_tables_are_found_by_line() {
        let text = "[settings]\ndt = 1\n[water]\ndroplets = 3\nr_max = -1\n";
        assert_eq!(line_of_key(text, "water", "r_max"), Some(5));
        assert_eq!(line_of_key(text, "water", "r_min"), None);
        assert_eq!(line_of_key(text, "settings", "droplets"), None);
    }
}
