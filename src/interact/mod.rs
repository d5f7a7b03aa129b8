//! Everything a strand meets while it is styled (model.md §3): solid obstacles (head, floor or
//! pillow, perm rods, meshes through a baked distance field), other strands (S1-18 penalty),
//! a blow-dryer's wind (S1-17), water droplets that clump wet hair (S2-2), and the wetness
//! field that drives the hydrogen bonds. Shared by all: a uniform neighbour grid (S2 §2.4).
//!
//! These are pure functions and small state over struct-of-arrays slices; the simulation
//! stepper decides when each runs (forces before prediction, contacts after each iteration).
pub mod grid;
pub mod hair_contacts;
pub mod mesh_sdf;
pub mod obstacles;
pub mod water;
pub mod wetness;
pub mod wind;
