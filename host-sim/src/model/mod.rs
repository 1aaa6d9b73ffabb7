//! Models: the physics of each system (plants, exact events, analysis), free of scenes,
//! files and the CLI. A system in [`crate::systems`] assembles its plant from a scene with
//! only the enabled effects (the line juggler: [`crate::systems::line::assemble`]); a new
//! system adds its module here (`docs/adding-a-system.md`).

pub mod arm;
pub mod feeder;
pub mod hopper;
pub mod impact;
pub mod line;
pub mod planar;
pub mod spatial;
pub mod surface;
