//! # dexter-rig
//!
//! Where the control core ([`dexter_core`]) meets the board-independent drivers
//! ([`dexter_drivers`], which know nothing of the core):
//!
//! - [`rig`]: the sensors and actuators one controller kind closes its loop through
//!   ([`rig::Rig`]: the core's `FixedRate::Frame` in, its `Command` out); [`rig::LineRig`]
//!   for the line juggler (paddle encoder and motor, ball camera);
//! - [`periodic`]: one fixed-rate control period on a hardware tick: the core's
//!   `FixedRate::step`, overrun detection, and the core's safe state on an overrun.
//!
//! Tested on the host against `embedded-hal-mock` (`cargo test -p dexter-rig`); a board
//! crate (`boards/`) constructs the drivers from HAL objects and calls in.
#![cfg_attr(not(test), no_std)]
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod periodic;
pub mod rig;
