//! The CLI's and the library's integration tests, one module per former test file, in one
//! binary: 36 test binaries each linked the whole of dexter-sim and its dependencies, which
//! was much of a fresh `cargo test`'s build (BENCHMARKS.md, "Building"). Tests that docs or
//! scripts run by name (`--test documented_commands`, `--test slurm`, ...) stay their own
//! binaries beside this one. Run one module with `cargo test -p dexter-sim --test integration
//! line_cli::`.

#[path = "../common/mod.rs"]
mod common;

mod arm_catch_cli;
mod arm_cli;
mod arm_impact;
mod arm_juggle_cli;
mod arm_model;
mod arm_tasks;
mod arm_verify;
mod cli;
mod feeder_cli;
mod feeder_drift_jog;
mod feeder_mechanics;
mod feeder_primitives;
mod hil_conditions;
mod hopper_cli;
mod hopper_sampled;
mod hopper_sampled_cli;
mod hopper_sampled_plant;
mod io_conditions;
mod line_cli;
mod non_finite_outputs;
mod on_target_cli;
mod planar;
mod planar_cli;
mod planar_juggler_cli;
mod planar_real_table;
mod planar_real_table_cli;
mod plot;
mod plot_data;
mod progress_cli;
mod real_table_stage;
mod shard_cli;
mod shared_cli;
mod spatial_juggler_cli;
mod stability_cli;
mod tradeoff_figure;
mod validation_messages;
