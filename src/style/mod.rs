//! Styling: recipes (TOML timelines of stages) and, once the simulation core lands, the
//! driver that runs them on a groom.
pub mod recipe;
