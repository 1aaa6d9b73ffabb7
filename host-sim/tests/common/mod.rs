//! Helpers the binary's tests share: running `dexter`, the shipped scenes, scratch
//! directories, the workspace and its firmware image.
#![allow(dead_code)]

pub mod feeder;
pub mod svg;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Run the `dexter` binary with `args`.
pub fn dexter(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dexter"))
        .args(args)
        .output()
        .expect("the dexter binary runs")
}

/// Run it and insist on success (the failure shows stderr).
pub fn ok(args: &[&str]) -> Output {
    let out = dexter(args);
    assert!(
        out.status.success(),
        "dexter {args:?} failed ({:?}): {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The one JSON object a successful run of `args` prints.
pub fn json(args: &[&str]) -> serde_json::Value {
    serde_json::from_slice(&ok(args).stdout).expect("stdout is one JSON object")
}

/// The path of `scenes/{name}.toml`.
pub fn scene(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenes")
        .join(format!("{name}.toml"))
        .display()
        .to_string()
}

/// A fresh, empty scratch directory for this test process.
pub fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dexter-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The columns of a CSV file with a header: each row as a map from column name to value
/// (numbers parsed; a non-number is NaN).
pub fn csv_rows(path: &Path) -> Vec<std::collections::HashMap<String, f64>> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(k, v)| (k.to_string(), v.parse().unwrap_or(f64::NAN)))
                .collect()
        })
        .collect()
}

/// The workspace root (the directory above host-sim/).
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .canonicalize()
        .unwrap()
}

/// Build the firmware (release, thumbv7em-none-eabihf) and return its ELF.
pub fn firmware() -> PathBuf {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(workspace())
        .args([
            "build",
            "-p",
            "dexter-mps2-an386",
            "--release",
            "--target",
            "thumbv7em-none-eabihf",
        ])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "building the firmware failed (install the target with `rustup target add thumbv7em-none-eabihf`):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace().join("target"));
    target.join("thumbv7em-none-eabihf/release/dexter-mps2-an386")
}
