//! Styling: recipes (TOML timelines of stages) and, once the simulation core lands, the
//! driver that runs them on a groom.
pub mod head_frame;
pub mod layout;
pub mod placement;
pub mod ranges;
pub mod recipe;
pub mod run;

pub use recipe::Recipe;
pub use run::{style, style_part, StyleOptions, StyleReport, Styled};
