//! Switchable effects, one module each. Each effect is a trait with an "off" type that
//! compiles to nothing, so a plant assembled without it pays nothing on the hot path.

pub mod actuator;
pub mod jitter;
pub mod sensor;
