//! `coif simulate`: run a groom for some seconds (optionally settle it), then export the state and
//! the rest-shape attributes. The library entry the CLI calls; recipes will drive
//! [`Simulation`] directly.
use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

use super::settle::settle_with;
use super::{Energy, SettleOptions, SettleReport, SimParams, Simulation};
use crate::error::{Error, Result};
use crate::groom::{AttributeRate, Groom};
use crate::interact::hair_contacts::HairContacts;
use crate::interact::obstacles::{ContactHooks, Friction, ObstacleCulling, Shape, StepContacts, Threaded};
use crate::interact::wetness::{carry_water, WetnessParams, WETNESS};

#[derive(Clone, Debug, PartialEq)]
pub struct SimulateOptions {
    pub params: SimParams,
    /// Simulated seconds before settling.
    pub seconds: f32,
    /// Relax to static equilibrium afterwards.
    pub settle: Option<SettleOptions>,
    /// Solve for the rest shape that holds the groom's current shape under gravity
    /// (`sim::sag_free`) instead of taking its shape (or its exported `rest_darboux`) as rest.
    pub sag_free: bool,
    /// Solid colliders the hair cannot enter (e.g. coif's default head).
    pub colliders: Vec<Shape>,
    /// Hair–hair contacts (S1-18), as styling applies them: a styled groom whose strands rest on
    /// each other is at rest only with them.
    pub hair_contacts: Option<HairContactSettings>,
}

/// How strands push each other apart: `stiffness` is α of S1-18 (m/s²); edges are cut into
/// pieces `spacing` metres long to find candidates (speed only). Recipes' `[contacts]` hold the
/// defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HairContactSettings {
    pub stiffness: f32,
    pub spacing: f32,
}

#[derive(Clone, Debug, Serialize)]
pub struct SimulateSummary {
    pub steps: u64,
    pub seconds: f32,
    pub settle: Option<SettleReport>,
    /// Where the rest shape came from: "shape" (the groom as drawn), "rest_darboux" (a styled
    /// groom's exported rest state) or "sag_free" (solved to hold the shape under gravity).
    pub rest: &'static str,
    pub max_speed: f32,
    pub energy: Energy,
    /// The file's point attributes the simulation could not carry (`point_attributes`), and
    /// strands a sag-free rest shape did not hold (`Simulation::unheld_warning`).
    pub warnings: Vec<String>,
}

/// Parses a time step given as seconds (`0.0027`) or a fraction (`1/360`).
pub fn parse_time_step(text: &str) -> Result<f32> {
    let bad = || {
        Error::Usage(format!(
            "time step '{text}' is not a positive number of seconds or a fraction like 1/360"
        ))
    };
    let value = match text.split_once('/') {
        Some((a, b)) => {
            let a: f32 = a.trim().parse().map_err(|_| bad())?;
            let b: f32 = b.trim().parse().map_err(|_| bad())?;
            a / b
        }
        None => text.trim().parse().map_err(|_| bad())?,
    };
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(bad())
    }
}

/// Simulates `groom` and returns it with simulated positions and the attributes `rest`,
/// `rest_darboux` and `bond_*`.
pub fn simulate(groom: &Groom, options: &SimulateOptions) -> Result<(Groom, SimulateSummary)> {
    if !(options.seconds.is_finite() && options.seconds >= 0.0) {
        return Err(Error::Usage(format!(
            "simulate: --seconds {} must be a non-negative number",
            options.seconds
        )));
    }
    if let Some(settle) = &options.settle {
        settle.check("--settle-tolerance", "--settle-seconds")?;
    }
    let mut sim = Simulation::new(groom, options.params.clone())?;
    carry_groom_water(&mut sim, groom);
    let rest = if options.sag_free {
        sim.make_sag_free();
        "sag_free"
    } else if sim.adopt_rest_state(groom)? {
        "rest_darboux"
    } else {
        "shape"
    };
    let mut stepper = Stepper::new(sim, groom, &options.colliders, options.hair_contacts);
    let steps = (options.seconds / options.params.dt).round().max(0.0) as u64;
    for _ in 0..steps {
        stepper.step()?;
    }
    let settle = match &options.settle {
        Some(settle) => {
            Some(settle_with(&mut stepper, |s| &mut s.sim, Stepper::step, Stepper::touched, settle, |_| {})?)
        }
        None => None,
    };
    let sim = stepper.sim;
    sim.check_diverged(None)?;
    // A sag-free groom is meant to hold its shape: say so when it did not.
    let simulated = steps as f32 * options.params.dt + settle.as_ref().map_or(0.0, |s| s.seconds);
    let mut warnings: Vec<String> = match options.sag_free {
        true => sim.unheld_warning(groom, simulated).into_iter().collect(),
        false => Vec::new(),
    };
    let mut out = groom.clone();
    sim.write_to_groom(&mut out);
    // The simulation's own velocities replace the file's; its accelerations are not kept.
    warnings.extend(crate::point_attributes::follow_new_shape(
        groom,
        &mut out,
        Some(sim.rods().velocities()),
    ));
    let summary = SimulateSummary {
        steps: sim.steps_taken(),
        seconds: steps as f32 * options.params.dt,
        settle,
        rest,
        max_speed: sim.max_speed(),
        energy: sim.energy(),
        warnings,
    };
    Ok((out, summary))
}

/// Wet hair is heavier: a groom that carries `wetness` (a styled output still damp, or a wet
/// groom) is simulated with the water's weight, as styling simulated it, so its exported rest
/// state holds it still. Readers refuse non-finite values; `mass_scale` clamps to [0, 1].
pub(crate) fn carry_groom_water(sim: &mut Simulation, groom: &Groom) {
    if let Some(wetness) = groom.attribute(WETNESS) {
        if wetness.rate == AttributeRate::Vertex && wetness.components == 1 {
            carry_water(sim, &wetness.floats(), &WetnessParams::default());
        }
    }
}

/// The rod solver with contacts against fixed colliders and, if asked, between strands.
struct Stepper {
    sim: Simulation,
    colliders: Vec<Shape>,
    /// Hair–hair contacts and their velocity changes.
    hair_contacts: Option<(HairContacts, Vec<Vec3>)>,
    /// Scratch: the vertices the next step leaves where they are (no contact forces needed).
    idle: Vec<bool>,
    offsets: Vec<u32>,
    radii: Vec<f32>,
    max_radius: f32,
    contacts: StepContacts,
    culling: ObstacleCulling,
}

impl Stepper {
    fn new(
        sim: Simulation,
        groom: &Groom,
        colliders: &[Shape],
        hair_contacts: Option<HairContactSettings>,
    ) -> Stepper {
        let radii = groom.contact_radii();
        let hair_contacts = hair_contacts.map(|c| {
            let contacts = HairContacts::new(&groom.strand_offsets, &radii, c.spacing, c.stiffness);
            (contacts, vec![Vec3::ZERO; groom.vertex_count()])
        });
        Stepper {
            colliders: colliders.to_vec(),
            hair_contacts,
            idle: Vec::new(),
            offsets: groom.strand_offsets.clone(),
            max_radius: radii.iter().copied().fold(0.0, f32::max),
            radii,
            contacts: StepContacts::default(),
            culling: ObstacleCulling::default(),
            sim,
        }
    }

    fn step(&mut self) -> Result<()> {
        if let Some((contacts, dv)) = &mut self.hair_contacts {
            let dt = self.sim.params().dt;
            dv.par_iter_mut().for_each(|v| *v = Vec3::ZERO);
            self.sim.idle_vertices(&mut self.idle);
            contacts.apply(self.sim.rods.positions(), &self.radii, &self.idle, dv, dt)?;
            let accel = self.sim.external_acceleration_mut();
            accel.par_iter_mut().zip(dv.par_iter()).for_each(|(a, &dv)| *a = dv / dt);
        }
        let params = self.sim.params();
        self.contacts.start(
            self.sim.rods.positions(),
            params.dt,
            params.solver.judges_friction_over_the_step(),
        );
        self.culling.update(&self.colliders, &self.offsets, self.contacts.previous(), self.max_radius);
        let hooks = ContactHooks {
            shapes: &self.colliders,
            culling: &self.culling,
            contacts: &self.contacts,
            radii: &self.radii,
            friction: Friction::default(),
            threaded: &Threaded::default(),
            first_threaded: 0,
        };
        self.sim.step_with(&hooks);
        Ok(())
    }

    /// The strands that vertices of `from` strands touch now (none without hair–hair contacts).
    fn touched(&mut self, from: &(dyn Fn(usize) -> bool + Sync), touched: &mut Vec<bool>) {
        match &self.hair_contacts {
            Some((contacts, _)) => {
                contacts.strands_touched(self.sim.rods.positions(), &self.radii, from, touched)
            }
            None => touched.clear(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_steps_parse() {
        assert_eq!(parse_time_step("1/360").unwrap(), 1.0 / 360.0);
        assert_eq!(parse_time_step("0.5").unwrap(), 0.5);
        assert!(parse_time_step("0").is_err());
        assert!(parse_time_step("1/0").is_err());
        assert!(parse_time_step("fast").is_err());
    }
}
