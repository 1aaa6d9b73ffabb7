//! Models: plants assembled from a scene with only the enabled effects.
//!
//! [`assemble`](crate::run::run_scene) matches on the scene's model and effect switches once
//! and calls generic code monomorphized for that combination; new models (planar, hopper)
//! add a variant to [`crate::scene::Model`] and a module here.

pub mod feeder;
pub mod hopper;
pub mod line;
pub mod planar;
pub mod surface;
