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
//! | [`closed_loop`] | [`closed_loop::drive`]: the one fixed-rate loop, any [`closed_loop::SampledPlant`] through any controller |
//! | [`controller`] | [`controller::StepController`]: a plant closes its loop through SIL or HIL alike |
//! | [`external`] | `--hil`: the system's controller on the target (the one seam to [`hil`]) |
//! | [`hil`] | the firmware in QEMU, lock-stepped with the plant |
//! | [`engine`] | closed-form flight, robust contact roots, impacts, Zeno, drag integrators |
//! | [`effects`] | one module per switchable effect: actuator, sensor, jitter |
//! | [`model`] | the physics of each system (line, planar, hopper) |
//!
//! The line juggler's run API keeps its earlier paths: [`run`], [`report`] and [`trace`]
//! are [`systems::line`]'s modules.
#![warn(missing_docs)]

pub mod closed_loop;
pub mod controller;
pub mod effects;
pub mod engine;
pub mod external;
pub mod filmstrip;
pub mod hil;
pub mod model;
pub mod output;
pub mod period;
pub mod plot;
pub mod progress;
pub mod scene;
pub mod stream;
pub mod sweep;
pub mod systems;
pub mod verbs;

pub use systems::line::{run, summary as report, trace};
