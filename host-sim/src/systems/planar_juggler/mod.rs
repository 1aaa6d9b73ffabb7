//! placeholder
/// The planar juggler system.
#[derive(Clone, Copy, Debug, Default)]
pub struct PlanarJuggler;
