//! # dexter-sim
//!
//! The host simulator: scenes that switch effects on, exact event-driven impact physics,
//! software-in-the-loop (the core linked in) and hardware-in-the-loop (the firmware in QEMU)
//! runs, traces and plots.
//!
//! | module | what it holds |
//! | --- | --- |
//! | [`scene`] | TOML schema, `--set` overrides, validation with dotted key paths |
//! | [`engine`] | closed-form flight, robust contact roots, impacts, Zeno, drag integrators |
//! | [`effects`] | one module per switchable effect: actuator, sensor, jitter |
//! | [`model`] | assembling a plant from a scene (only the enabled effects) |
//! | [`run`] | the run loop (event-driven or stepped with a [`controller::StepController`]) |
//! | [`report`] | summary analysis (convergence, period), human and JSON output |
//! | [`sweep`] | parameter sweeps (bifurcation diagrams) |
//! | [`trace`] | one row per impact, CSV |
#![warn(missing_docs)]

pub mod apps;
pub mod controller;
pub mod effects;
pub mod engine;
pub mod hil;
pub mod model;
pub mod plot;
pub mod report;
pub mod run;
pub mod scene;
pub mod sweep;
pub mod trace;
