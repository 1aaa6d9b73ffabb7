//! # dexter-sim
//!
//! The host simulator: scenes that switch effects on, exact event-driven impact physics,
//! software-in-the-loop (the core linked in) and hardware-in-the-loop (the firmware in QEMU)
//! runs, traces and plots.
//!
//! | module | what it holds |
//! | --- | --- |
//! | [`systems`] | every simulated system behind one trait, and the registry the CLI dispatches on |
//! | [`verbs`] | the CLI's `run` and `sweep`, written once for every system |
//! | [`scene`] | scene files read once, TOML errors with line and column, `--set`, key paths in errors |
//! | [`sweep`] | sweep ranges and the parallel, order-keeping sweep engine |
//! | [`output`] | output files written whole or not at all; the CSV number format; JSON |
//! | [`period`] | the period a late orbit has provably settled to |
//! | [`plot`] | SVG + PNG plots |
//! | [`filmstrip`] | a motion as a grid of panels in one world window (arm, feeder, tilt table) |
//! | [`stream`] | constant-memory views of a run: last values, decimated plot points |
//! | [`progress`] | progress bars (on a terminal only) |
//! | [`controller`] | [`controller::StepController`]: a plant closes its loop through SIL or HIL alike |
//! | [`external`] | `--hil`: the system's controller on the target (the one seam to [`hil`]) |
//! | [`hil`] | the firmware in QEMU, lock-stepped with the plant |
//! | [`engine`] | closed-form flight, robust contact roots, impacts, Zeno, drag integrators |
//! | [`effects`] | one module per switchable effect: actuator, sensor, jitter |
//! | [`model`] | the physics of each system (line, planar, hopper) |
#![warn(missing_docs)]

pub mod cli;
pub mod controller;
pub mod effects;
pub mod engine;
pub mod filmstrip;
pub mod grid;
pub mod hil;
pub mod model;
pub mod output;
pub mod period;
pub mod plot;
pub mod progress;
pub mod scene;
pub mod stream;
pub mod system;
pub mod systems;
pub mod verbs;
