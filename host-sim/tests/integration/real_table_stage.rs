//! Issue 22, finding 15: the real table's x range (`[real_table.stage]`) and its horizontal
//! regulation (`real_table.kappa_x_pm`, `real_table.kappa_xdot_spm`), from the command
//! line. Ranges and defaults as docs/planar.md documents them.

use crate::common;

use common::{dexter, scene};

/// `dexter run planar-triangle-sil --json` with `sets`: exit code, the JSON line, stderr.
fn run(sets: &[&str]) -> (Option<i32>, String, String) {
    let s = scene("planar-triangle-sil");
    let mut args = vec!["run", s.as_str(), "--json"];
    for set in sets {
        args.extend(["--set", set]);
    }
    let out = dexter(&args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let json = stdout.lines().last().unwrap_or_default().to_owned();
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    (out.status.code(), json, err)
}

#[test]
fn the_shipped_real_table_keeps_the_body_within_its_two_metres() {
    let (code, json, err) = run(&[]);
    assert_eq!(code, Some(0), "{err}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["end"], "completed", "{json}");
    assert_eq!(v["impacts"], 300);
    let x = v["max_abs_x_m"].as_f64().unwrap();
    assert!(x < 1.0, "{x}");
}

#[test]
fn without_the_regulation_the_body_leaves_the_table_and_the_run_says_so() {
    let (code, json, err) = run(&["real_table.kappa_x_pm=0", "real_table.kappa_xdot_spm=0"]);
    assert_eq!(
        code,
        Some(0),
        "a physical outcome, like tipping over: {err}"
    );
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["end"], "out_of_travel", "{json}");
    assert_eq!(v["stayed_up"], false);
    assert!(v["impacts"].as_u64().unwrap() < 300);
    let s = scene("planar-triangle-sil");
    let out = dexter(&[
        "run",
        &s,
        "--set",
        "real_table.kappa_x_pm=0",
        "--set",
        "real_table.kappa_xdot_spm=0",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("out of travel"), "{text}");
    assert!(text.contains("real_table.stage"), "{text}");
}

#[test]
fn bad_stage_and_regulation_values_are_refused_naming_the_key() {
    for (set, key) in [
        ("real_table.stage.min_m=0.1", "real_table.stage.min_m"),
        ("real_table.stage.max_m=-0.1", "real_table.stage.max_m"),
        ("real_table.stage.max_m=nan", "real_table.stage.max_m"),
        ("real_table.kappa_x_pm=-0.001", "real_table.kappa_x_pm"),
        ("real_table.kappa_x_pm=1.5", "real_table.kappa_x_pm"),
        ("real_table.kappa_xdot_spm=-1", "real_table.kappa_xdot_spm"),
        ("real_table.stage.travel_m=1", "travel_m"),
    ] {
        let (code, _, err) = run(&[set, "planar.impacts=1"]);
        assert_eq!(code, Some(2), "{set}: {err}");
        assert!(err.contains(key), "{set} should name {key}: {err}");
    }
    // the documented edges are accepted
    for set in [
        "real_table.kappa_x_pm=1",
        "real_table.kappa_xdot_spm=0",
        "real_table.stage.min_m=0",
    ] {
        let (code, _, err) = run(&[set, "planar.impacts=1"]);
        assert_ne!(code, Some(2), "{set}: {err}");
    }
}
