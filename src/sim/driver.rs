//! `coif simulate`: run a groom for some seconds (optionally settle it), then export the state and
//! the rest-shape attributes. The library entry the CLI calls; recipes will drive
//! [`Simulation`] directly.
use serde::Serialize;

use super::{Energy, NoHooks, SettleOptions, SettleReport, SimParams, Simulation};
use crate::error::{Error, Result};
use crate::groom::Groom;

#[derive(Clone, Debug, PartialEq)]
pub struct SimulateOptions {
    pub params: SimParams,
    /// Simulated seconds before settling.
    pub seconds: f32,
    /// Relax to static equilibrium afterwards.
    pub settle: Option<SettleOptions>,
}

#[derive(Clone, Debug, Serialize)]
pub struct SimulateSummary {
    pub steps: u64,
    pub seconds: f32,
    pub settle: Option<SettleReport>,
    pub max_speed: f32,
    pub energy: Energy,
}

/// Parses a time step given as seconds (`0.0027`) or a fraction (`1/360`).
pub fn parse_time_step(text: &str) -> Result<f32> {
    let bad =
        || Error::Usage(format!("time step '{text}' is not a number of seconds or a fraction like 1/360"));
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
    let steps = sim.run(options.seconds, &NoHooks);
    let settle = options.settle.as_ref().map(|settle| sim.settle(settle, &NoHooks));
    let mut out = groom.clone();
    sim.write_to_groom(&mut out);
    let summary = SimulateSummary {
        steps: sim.steps_taken(),
        seconds: steps as f32 * options.params.dt,
        settle,
        max_speed: sim.max_speed(),
        energy: sim.energy(),
    };
    Ok((out, summary))
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
