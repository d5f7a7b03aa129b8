//! coif: offline hair-groom styling. Import groom curves, style them with a Cosserat-rod
//! simulation whose side-chain bonds make deformation plastic, settle the new rest shape, export
//! to USD and Alembic, and preview with an Embree path tracer.
//!
//! Data flows one way: `io` readers produce a [`Groom`], the simulation transforms it, `io`
//! writers and the renderer consume it.
pub mod analysis;
pub mod batch;
pub mod embree;
pub mod error;
pub mod generate;
pub mod groom;
pub mod groups;
pub mod guides;
pub mod head;
pub mod info;
pub mod interact;
pub mod io;
pub mod limits;
pub mod point_attributes;
pub mod primvar_rates;
pub mod progress;
pub mod render;
pub mod sim;
pub mod style;
pub mod surface_mesh;
pub mod validate;

pub use error::{Error, Result};
pub use groom::Groom;
