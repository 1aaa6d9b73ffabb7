//! # dexter-sim
//!
//! The host simulator: scenes that switch effects on, exact event-driven impact physics,
//! software-in-the-loop (the core linked in) and hardware-in-the-loop (the firmware in QEMU)
//! runs, traces and plots.
//!
//! The modules, top layer first: each imports only those below it, and none imports a module
//! that imports it back (`scripts/layers.py` checks both).
//!
//! | module | what it holds |
//! | --- | --- |
//! | [`cli`] | the `dexter` command line (clap on the verbs' requests) and the registry of systems |
//! | [`verbs`] | `run`, `sweep` and `analyze`, written once for every system |
//! | [`systems`] | each system's scene layout, summary, trace rows, plots, sweep axes and analysis |
//! | [`system`] | what a system is to the verbs: the [`system::System`] trait, its run length, failures and exit codes, `--hil` targets |
//! | [`model`] | the physics of each system (line, planar, hopper, arm, feeder) and its parameters |
//! | [`engine`] | closed-form flight, robust contact roots, impacts, Zeno; the one ODE engine (RK4, Dormand–Prince 5(4), events as witness functions) and its drag flight |
//! | [`effects`] | one module per switchable effect: actuator, the one sampled sensor, jitter |
//! | [`closed_loop`] | [`closed_loop::drive`]: the one fixed-rate loop, any [`closed_loop::SampledPlant`] through any controller |
//! | [`hil`] | the firmware in QEMU (or a board on a serial port), lock-stepped with the plant |
//! | [`controller`] | [`controller::StepController`]: a plant closes its loop through SIL or HIL alike |
//! | [`scene`] | scene files read once, TOML errors with line and column, `--set`, key paths in errors |
//! | [`grid`] | sweep ranges and the parallel, order-keeping evaluation of their grid |
//! | [`shard`] | `--shard K/N`: which points a shard runs, the shard CSV it writes and `dexter merge` reads |
//! | [`output`] | output files written whole or not at all; the CSV number format; JSON |
//! | [`period`] | the period a late orbit has provably settled to |
//! | [`plot`] | SVG + PNG charts |
//! | [`filmstrip`] | a motion as a grid of panels in one world window (arm, feeder, tilt table) |
//! | [`stream`] | constant-memory views of a run: last values, decimated plot points |
//! | [`progress`] | progress bars (on a terminal only) |
#![warn(missing_docs)]

pub mod cli;
pub mod closed_loop;
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
pub mod shard;
pub mod stream;
pub mod system;
pub mod systems;
pub mod verbs;
