//! The real tilt table through the `dexter` binary (issue 11): `scenes/planar-triangle-sil.toml`
//! in SIL and with `--hil` (the firmware in QEMU), the seed sweep against the ideal table,
//! the filmstrip, and scene errors naming their keys.
//!
//! Expected values come from the paper, not from the code: eta* = G * apex (eq. 25's
//! target, 9.81 * 0.25 J/kg), the tip angle atan 4 of the sec. 2.3 triangle, and the ideal
//! table's 16 of 20 seeds of docs/planar.md. The HIL test builds the firmware first; it
//! needs `qemu-system-arm` and the `thumbv7em-none-eabihf` target.

use crate::common;

use common::{dexter, firmware, json, ok, scene, scratch};
use serde_json::Value;
use std::path::Path;

/// eta* of the scene: G times the 25 cm apex, J/kg.
const ETA_STAR: f64 = 9.81 * 0.25;

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number in {v}"))
}

/// The keys issue 11 asks for, and upright for 300 impacts with the late energy within 2 %
/// of eta* (computed here from the late mean, not taken from the error key alone).
fn assert_balanced(v: &Value) {
    assert_eq!(v["table"], "real", "{v}");
    assert_eq!(v["impacts"], 300, "{v}");
    assert_eq!(v["tipped_over"], false, "{v}");
    assert_eq!(v["end"], "completed", "{v}");
    let mean = num(v, "late_mean_energy_jpkg");
    assert!(
        (num(v, "target_energy_jpkg") - ETA_STAR).abs() < 1e-12,
        "{v}"
    );
    let err = (mean - ETA_STAR) / ETA_STAR;
    assert!(err.abs() < 0.02, "late energy {err:+.4} of eta*");
    assert!((num(v, "late_energy_error") - err).abs() < 1e-12, "{v}");
    // upright: far from the tip angle atan 4 = 1.33 rad late in the run
    assert!(num(v, "late_theta_max_rad") < 0.2, "{v}");
    assert_eq!(v["safe_steps"], 0, "{v}");
    assert_eq!(
        num(v, "control_steps"),
        v["control_steps"].as_f64().unwrap()
    );
    for k in [
        "step_instructions_min",
        "step_instructions_mean",
        "step_instructions_max",
        "sil_mismatches",
        "link_errors",
    ] {
        assert!(v.get(k).is_some(), "no key {k} in {v}");
    }
}

#[test]
fn sil_keeps_the_triangle_upright_with_the_energy_at_its_target() {
    let v = json(&["run", &scene("planar-triangle-sil"), "--json"]);
    assert_balanced(&v);
    assert!(v["sil_mismatches"].is_null() && v["step_instructions_max"].is_null());
    // the controller predicted every impact, to well under a control period (2 ms)
    assert_eq!(v["predicted_impacts"], 300);
    assert!(num(&v, "impact_time_error_rms_s") < 1e-3, "{v}");
}

#[test]
fn the_same_triangle_at_one_kilohertz_and_with_ideal_drives_stays_upright() {
    for sets in [
        [
            "real_table.control_rate_hz=1000",
            "real_table.camera.rate_hz=1000",
        ],
        ["real_table.drives=\"ideal\"", "planar.seed=7"],
    ] {
        let mut args = vec![
            "run".to_string(),
            scene("planar-triangle-sil"),
            "--json".into(),
        ];
        for s in sets {
            args.extend(["--set".to_string(), s.to_string()]);
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_balanced(&json(&args));
    }
}

/// The upright count of a seed sweep's CSV (column `end`).
fn upright(csv: &Path) -> usize {
    std::fs::read_to_string(csv)
        .unwrap()
        .lines()
        .skip(1)
        .filter(|l| l.split(',').nth(3) == Some("completed"))
        .count()
}

#[test]
fn over_twenty_seeds_the_real_table_keeps_at_least_as_many_upright_as_the_ideal_one() {
    let dir = scratch("tilt-seeds");
    let mut counts = Vec::new();
    for name in ["planar-triangle-ideal", "planar-triangle-sil"] {
        let csv = dir.join(format!("{name}.csv"));
        let out = ok(&[
            "sweep",
            &scene(name),
            "--range",
            "planar.seed=1:20:20",
            "--csv",
            csv.to_str().unwrap(),
        ]);
        let n = upright(&csv);
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.contains(&format!("{n} of 20 cells")), "{text}");
        counts.push(n);
    }
    // docs/planar.md: the ideal table with 10 ms timing noise keeps 16 of 20
    assert_eq!(counts[0], 16, "ideal");
    assert!(
        counts[1] >= counts[0],
        "real {} < ideal {}",
        counts[1],
        counts[0]
    );
}

#[test]
fn plot_writes_the_filmstrip_of_body_and_table() {
    let dir = scratch("tilt-plot");
    let out = ok(&[
        "run",
        &scene("planar-triangle-sil"),
        "--impacts",
        "40",
        "--plot",
        dir.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    for ext in ["svg", "png"] {
        let f = dir.join(format!("planar-triangle-sil-filmstrip.{ext}"));
        assert!(
            f.metadata().map(|m| m.len() > 1000).unwrap_or(false),
            "{err}"
        );
    }
    let svg = std::fs::read_to_string(dir.join("planar-triangle-sil-filmstrip.svg")).unwrap();
    // 4 first impacts and the last ones, with the flights' apexes: 15 panels
    assert_eq!(svg.matches("impact ").count(), 8, "{svg}");
    assert!(svg.contains("impact 39,") && svg.contains("impact 0,"));
}

#[test]
fn bad_real_table_keys_exit_2_naming_the_key() {
    let s = scene("planar-triangle-sil");
    for (set, key) in [
        ("real_table.camera.noise_m=-1", "real_table.camera.noise_m"),
        (
            "real_table.control_rate_hz=20",
            "real_table.control_rate_hz",
        ),
        ("real_table.tilt.max_rad=-0.8", "real_table.tilt.max_rad"),
        (
            "real_table.stroke.accel_max_mps2=0",
            "real_table.stroke.accel_max_mps2",
        ),
        (
            "real_table.contact_iterations=9",
            "real_table.contact_iterations",
        ),
        ("real_table.max_duration_s=1e9", "real_table.max_duration_s"),
        ("real_table.drives=\"fast\"", "real_table.drives"),
        ("real_table.camera.gain=2", "gain"),
        ("planar.timing_noise_s=0.01", "planar.timing_noise_s"),
        ("planar.friction_mu=0.3", "planar.friction_mu"),
    ] {
        let out = dexter(&["run", &s, "--set", set]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{set}: {err}");
        assert!(err.contains(key), "{set}: {err}");
    }
    // the ideal table has no controller to run on a target
    let out = dexter(&["run", &scene("planar-triangle-ideal"), "--hil"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("real_table"), "{err}");
}

#[test]
fn a_time_limit_before_the_impacts_is_a_failure_that_says_so() {
    let out = dexter(&[
        "run",
        &scene("planar-triangle-sil"),
        "--set",
        "real_table.max_duration_s=5",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("real_table.max_duration_s"), "{err}");
}

/// HIL equals SIL: the same summary, key for key apart from the HIL figures and the wall
/// time, 0 mismatches, 0 link errors, and every step within the 600-instruction budget.
#[test]
fn hil_equals_sil_with_no_mismatch_within_the_step_budget() {
    firmware();
    let s = scene("planar-triangle-sil");
    let sil = json(&["run", &s, "--json"]);
    let hil = json(&["run", &s, "--hil", "--json"]);
    assert_balanced(&hil);
    assert_eq!(hil["sil_mismatches"], 0, "{hil}");
    assert_eq!(hil["link_errors"], 0, "{hil}");
    assert_eq!(hil["over_budget_steps"], 0, "{hil}");
    let max = num(&hil, "step_instructions_max");
    assert!(max > 0.0 && max <= 600.0, "{hil}");
    let hil_only = [
        "step_instructions_min",
        "step_instructions_mean",
        "step_instructions_max",
        "sil_mismatches",
        "link_errors",
        "over_budget_steps",
        "link_timeouts",
        "steps_per_wall_second",
        "wall_time_s",
    ];
    let (a, b) = (sil.as_object().unwrap(), hil.as_object().unwrap());
    assert_eq!(a.len(), b.len());
    for (k, v) in a {
        if !hil_only.contains(&k.as_str()) {
            assert_eq!(Some(v), b.get(k), "{k} differs between SIL and HIL");
        }
    }
}
