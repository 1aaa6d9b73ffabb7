//! `dexter run --hil` through the binary: a scene without a controller is refused before
//! anything starts (exit 2, naming the mode), and a relative `--firmware` path runs the
//! firmware in QEMU from any directory, with no `rustc` on PATH.
//!
//! The QEMU test builds the firmware first (as `scripts/test.sh` does); it needs
//! `qemu-system-arm` and the `thumbv7em-none-eabihf` target, and fails naming them.

use crate::common;

use common::{dexter, firmware, scene, scratch};
use std::path::Path;
use std::process::Command;

/// A scene with no controller: `--hil` says so, naming the mode, and exits 2 before QEMU
/// starts (it used to fail on `control.target_apex_m: missing`, exit 1).
#[test]
fn hil_on_a_scene_without_a_controller_names_its_mode() {
    for (name, mode) in [
        ("passive-bounce", "none"),
        ("line-juggler-ideal", "ideal_mirror"),
    ] {
        let out = dexter(&["run", &scene(name), "--hil"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains("no controller to put on the target")
                && err.contains("control.mode")
                && err.contains(&format!("\"{mode}\"")),
            "{name}: {err}"
        );
        assert!(!err.contains("target_apex_m"), "{name}: {err}");
    }
}

/// `--firmware fw.elf`, relative to the current directory, with a PATH that holds QEMU but
/// no Rust toolchain: the firmware runs (QEMU runs in a directory of its own, so the path
/// must be made absolute first) and the run is the SIL run bit for bit.
#[test]
fn a_relative_firmware_path_runs_without_rustc_on_path() {
    let elf = firmware();
    let dir = scratch("relative-firmware");
    std::fs::copy(&elf, dir.join("fw.elf")).unwrap();
    let qemu = Command::new("sh")
        .args(["-c", "command -v qemu-system-arm"])
        .output()
        .expect("sh runs");
    let qemu = String::from_utf8_lossy(&qemu.stdout).trim().to_string();
    assert!(!qemu.is_empty(), "qemu-system-arm is not installed");
    let qemu_dir = Path::new(&qemu).parent().unwrap();
    let path = format!("{}:/bin", qemu_dir.display());
    let rustc_on_path = Command::new("sh")
        .env("PATH", &path)
        .args(["-c", "command -v rustc"])
        .output()
        .unwrap();
    assert!(
        rustc_on_path.stdout.is_empty(),
        "PATH {path} must not hold rustc"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_dexter"))
        .current_dir(&dir)
        .env("PATH", &path)
        .env_remove("RUSTC")
        .args([
            "run",
            &scene("line-juggler"),
            "--hil",
            "--firmware",
            "fw.elf",
            "--impacts",
            "3",
            "--json",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["impacts"], 3, "{v}");
    assert_eq!(v["sil_mismatches"], 0, "{v}");
    assert!(
        v["step_instructions_max"].as_u64().is_some_and(|n| n > 0),
        "{v}"
    );
    // a relative path that does not exist names itself
    let out = Command::new(env!("CARGO_BIN_EXE_dexter"))
        .current_dir(&dir)
        .args([
            "run",
            &scene("line-juggler"),
            "--hil",
            "--firmware",
            "nope.elf",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nope.elf"));
    let _ = std::fs::remove_dir_all(&dir);
}
