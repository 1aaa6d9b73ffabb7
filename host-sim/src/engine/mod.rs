//! Event-driven physics: closed-form flight between events, robust contact roots, the
//! restitution map, Zeno detection, and the one ODE engine ([`ode`]: RK4 or Dormand–Prince
//! 5(4), events as witness functions located by the engine) for every effect without a
//! closed form (the line's drag, [`drag`]; the hopper's stance; the arm's joint and roll).

pub mod drag;
pub mod eigen;
pub mod flight;
pub mod linearize;
pub mod locate;
pub mod ode;
pub mod roots;
pub mod unimodal;
pub mod zeno;

pub use flight::{Ballistic, Flight, FlightEnd, PaddleBound, Poly};
