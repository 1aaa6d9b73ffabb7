//! Shared helpers for the workspace-level tests: loading the shipped scenes and running them.

use dexter_sim::run::{run_scene, RunOptions, RunOutcome};
use dexter_sim::scene::{parse_set, Scene};
use std::path::PathBuf;

/// The workspace's `scenes/` directory.
pub fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenes")
}

/// Load `scenes/<name>.toml` with `key=value` overrides.
pub fn load_scene(name: &str, sets: &[&str]) -> Scene {
    let overrides: Vec<_> = sets
        .iter()
        .map(|s| parse_set(s).expect("override"))
        .collect();
    Scene::load(&scenes_dir().join(format!("{name}.toml")), &overrides).expect("scene loads")
}

/// Run a scene keeping every impact row.
pub fn run_rows(scene: &Scene) -> RunOutcome {
    let opts = RunOptions {
        record_rows: true,
        ..RunOptions::default()
    };
    run_scene(scene, &opts, None).expect("run")
}

/// |a - b| / |b|.
pub fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}
