//! Event-driven physics of a ball on a vertical line: closed-form flight between events,
//! robust contact roots, the restitution map, Zeno detection, and numerical integration
//! (with event location) only for effects without a closed form.

pub mod flight;
pub mod integrate;
pub mod roots;
pub mod zeno;

pub use flight::{Ballistic, Flight, FlightEnd, Poly};
