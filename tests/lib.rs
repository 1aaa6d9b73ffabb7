//! Shared helpers for the workspace-level tests: loading the shipped scenes and running them.

use dexter_sim::scene::parse_set;
use dexter_sim::systems::line::run::{run_scene, RunOptions, RunOutcome};
use dexter_sim::systems::line::scene::Scene;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

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

/// The default firmware image, built once per test binary (or a panic saying what is
/// missing: the target, QEMU's toolchain).
pub fn firmware() -> PathBuf {
    static ELF: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    ELF.get_or_init(|| dexter_sim::hil::build_firmware().map_err(|e| e.to_string()))
        .clone()
        .unwrap_or_else(|e| panic!("HIL tests need the firmware: {e}"))
}

/// The static worst case of a step function of the firmware image `elf` (`scripts/wcet.py
/// --json`: the longest path through its compiled code, callees included; for a function
/// with no loop and no indirect call the bound holds for every input and every
/// configuration the validator accepts): (instructions, Cortex-M4 cycles).
pub fn static_worst_case(elf: &Path, symbol: &str) -> (u32, u32) {
    let root = dexter_sim::hil::workspace_root();
    let out = std::process::Command::new("python3")
        .arg(root.join("scripts/wcet.py"))
        .arg(elf)
        .arg(symbol)
        .arg("--json")
        .output()
        .unwrap_or_else(|e| panic!("run python3 scripts/wcet.py (install Python 3): {e}"));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "scripts/wcet.py failed on {symbol}: {}{}",
        text,
        String::from_utf8_lossy(&out.stderr)
    );
    let field = |key: &str| -> u32 {
        let at = text
            .find(key)
            .unwrap_or_else(|| panic!("no {key} in {text}"))
            + key.len();
        text[at..]
            .trim_start_matches(['"', ':', ' '])
            .split(|c: char| !c.is_ascii_digit())
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{key} in {text}"))
    };
    (field("\"worst_instructions\""), field("\"worst_cycles\""))
}

/// The QEMU board's image that hosts `feature`'s controller besides the line juggler and
/// the link check (`--no-default-features --features <feature>`, copied to
/// `dexter-mps2-an386-<feature>.elf`; firmware/README.md, "Images"), built once per test
/// binary. A test that cannot build it fails saying what to install.
pub fn hosted_image(feature: &'static str) -> PathBuf {
    type Built = Vec<(&'static str, Result<PathBuf, String>)>;
    static BUILT: std::sync::Mutex<Built> = std::sync::Mutex::new(Vec::new());
    let mut built = BUILT.lock().unwrap_or_else(|e| e.into_inner());
    let result = match built.iter().find(|(f, _)| *f == feature) {
        Some((_, r)) => r.clone(),
        None => {
            let r = dexter_sim::hil::build_firmware_image(feature, &[feature])
                .map_err(|e| e.to_string());
            built.push((feature, r.clone()));
            r
        }
    };
    result.unwrap_or_else(|e| panic!("HIL tests need the firmware: {e}"))
}
