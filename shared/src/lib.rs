//! # dexter-core
//!
//! The `no_std`, allocation-free control core of dexter. The same code runs on a Cortex-M4F
//! (`firmware/`) and inside the host simulator (`host-sim/`, software in the loop), so the
//! simulator is an oracle for the firmware, bit for bit.
//!
//! Units are SI throughout (m, s, m/s, m/s^2, rad, N per kg of payload); field names carry
//! their unit (`height_m`, `dt_s`). The core owns no clock, no I/O and no globals: time comes
//! in as an argument (`dt_s`, sample sequence numbers).
//!
//! | module | what it holds | source |
//! | --- | --- | --- |
//! | [`math`] | the [`Real`](math::Real) scalar trait and the compile-time math backend | — |
//! | [`params`] | validation errors that name the parameter | — |
//! | `checks`, `fields` (crate-private) | the large parameter sets' validation that records the first failure, and their flat-tuple serde form (the tilt and hopper controllers') | — |
//! | [`state`] | ball and paddle states | — |
//! | [`mirror`] | line-juggler mirror law with energy feedback | Rizzi & Koditschek 1994, eq. 5–9 |
//! | [`tilt`] | kappa-tilt law, table-velocity energy feedback, stability limits | Zumel & Erdmann, eq. 3–4, 11, 16, 22–26 |
//! | [`planar`] | planar juggler mirror law and the modified, solvable law | Rizzi & Koditschek 1994, eq. 11–16 |
//! | [`spatial`] | the spatial juggler's mirror law (a three-joint robot's references from the ball's inverse kinematic image) and a modified law with a solvable flight time | Rizzi & Koditschek 1994, sec. 3.1.2, 4.1, eq. 5, 13, 15–16 |
//! | [`hop`] | Raibert's fixed thrust and an energy-servo thrust | Koditschek & Bühler 1991, sec. 1.2, 3.1 |
//! | [`bang_bang`] | the time-optimal bang-bang move of a joint to rest (the arm's release brake and its move to the catch) | Akella, Huang, Lynch & Mason, sec. 2.5 |
//! | [`bspline`] | uniform cubic B-spline joint trajectories: O(1) evaluation, convex-hull bounds | Akella, Huang, Lynch & Mason, sec. 2.1 |
//! | [`estimate`] | fixed-rate ball-state estimator with impact re-initialisation | — |
//! | [`track`] | paddle tracking: PD plus feed-forward within limits | — |
//! | [`fixed_rate`] | the one shape of every controller: [`FixedRate`](fixed_rate::FixedRate), [`Reply`](fixed_rate::Reply), [`Mode`](fixed_rate::Mode), [`Fault`](fixed_rate::Fault), [`Telemetry`](fixed_rate::Telemetry) | — |
//! | [`freshness`] | whether a frame carries a new sample: [`Freshness`](freshness::Freshness), the sequence-number check every controller runs | — |
//! | [`control`] | the fixed-rate line-juggler [`Controller`](control::Controller), its frame, command and safe state | — |
//! | [`echo`] | the link check [`Echo`](echo::Echo): a controller with no plant, for links and HIL tests | — |
//! | [`tilt_control`] | the fixed-rate kappa-tilt [`TiltController`](tilt_control::TiltController): camera flight estimate, eq. 7 contact, eq. 25 table velocity, table tracking | Zumel & Erdmann eq. 2, 7, 21, 25 |
//! | [`hop_control`] | the fixed-rate hopper thrust controller: phases from sampled leg compression, valve timing, safe state | Koditschek & Bühler 1991, sec. 3.1, eq. 8/10 |
//! | [`arm_control`] | the one-joint arm's [`ArmController`](arm_control::ArmController): a planned B-spline tracked with PD plus feed-forward, as a joint torque within the motor's limit | Akella, Huang, Lynch & Mason, sec. 2 |
//! | [`spatial_control`] | the spatial juggler's [`SpatialController`](spatial_control::SpatialController): a camera's ball positions and three encoders in, eq. 13 through a three-axis estimator with the paddle's restitution law, three joint trackers within their limits | Rizzi & Koditschek 1994, sec. 3.1.2, eq. 5, 13 |
//! | [`protocol`] | the wire, in three layers: [`framing`](protocol::framing) (postcard + CRC + COBS, typed decode errors; no message, no controller), [`messages`](protocol::messages) (host and device messages, the partial decode of an image), [`kinds`](protocol::kinds) (the one file naming every controller kind: [`Kind`](protocol::Kind), [`Wire`](protocol::Wire)) | — |
//!
//! Imports go one way, down this table's layers: the laws and helpers; [`fixed_rate`] and
//! [`freshness`]; the controllers; then [`protocol`], whose kinds name the controllers. No
//! controller imports the protocol or another controller.
#![cfg_attr(not(test), no_std)]
#![warn(missing_docs)]
// One `asm!` (the FPU square root in `math.rs`) is the only unsafe code; it is allowed there.
#![deny(unsafe_code)]

pub mod arm_control;
pub mod bang_bang;
pub mod bspline;
pub(crate) mod checks;
pub mod control;
pub mod echo;
pub mod estimate;
pub(crate) mod fields;
pub mod fixed_rate;
pub mod freshness;
pub mod hop;
pub mod hop_control;
pub mod math;
pub mod mirror;
pub mod params;
pub mod planar;
pub mod protocol;
pub mod spatial;
pub mod spatial_control;
pub mod state;
pub mod tilt;
pub mod tilt_control;
pub mod track;

/// Standard gravity, m/s^2 (the default for scenes and controllers).
pub const STANDARD_GRAVITY_MPS2: f32 = 9.806_65;
