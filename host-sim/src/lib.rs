//! # dexter-sim
//!
//! The host simulator: scenes that switch effects on, exact event-driven impact physics,
//! software-in-the-loop (the core linked in) and hardware-in-the-loop (the firmware in QEMU)
//! runs, traces and plots.
#![warn(missing_docs)]

pub mod controller;
pub mod hil;
pub mod plot;
pub mod trace;
