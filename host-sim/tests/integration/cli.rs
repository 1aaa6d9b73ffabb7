//! The `dexter` binary end to end: bad scenes exit non-zero naming the key and the reason
//! (never a panic); `--json` and `--trace` carry what the docs promise.

use crate::common;

use common::dexter;
use std::path::PathBuf;

fn scene_file(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dexter-cli-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, text).unwrap();
    p
}

fn scenes() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("scenes")
}

#[test]
fn bad_scenes_exit_non_zero_naming_key_and_reason() {
    let cases = [
        (
            "unknown",
            "[physics]\nrestitution = 0.5\nfrction = 0.1\n",
            "physics.frction",
            "unknown field",
        ),
        (
            "wrongtype",
            "[ball]\nheight_m = \"high\"\n",
            "ball.height_m",
            "invalid type",
        ),
        (
            "negative-e",
            "[physics]\nrestitution = -0.2\n",
            "physics.restitution",
            "must be in [0, 1]",
        ),
        (
            "big-e",
            "[physics]\nrestitution = 1.2\n",
            "physics.restitution",
            "must be in [0, 1]",
        ),
        (
            "no-target",
            "[control]\nmode = \"ideal_mirror\"\n",
            "control.target_apex_m",
            "missing",
        ),
        (
            "bad-mode",
            "[control]\nmode = \"psychic\"\n",
            "control.mode",
            "unknown variant",
        ),
        ("not-toml", "[physics\n", "", "not valid TOML"),
    ];
    for (name, text, key, reason) in cases {
        let out = dexter(&["run", scene_file(name, text).to_str().unwrap()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{name}: {err}");
        assert!(err.contains(key), "{name}: key `{key}` not in {err}");
        assert!(
            err.contains(reason),
            "{name}: reason `{reason}` not in {err}"
        );
        assert!(!err.contains("panicked"), "{name}: {err}");
    }
}

#[test]
fn bad_overrides_and_missing_files_are_errors_not_panics() {
    let ideal = scenes().join("line-juggler-ideal.toml");
    let out = dexter(&[
        "run",
        ideal.to_str().unwrap(),
        "--set",
        "control.kappa0=1.5",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        err.contains("control.kappa0") && err.contains("[0, 1)"),
        "{err}"
    );
    let out = dexter(&["run", "/nonexistent/scene.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot read"));
}

#[test]
fn json_summary_has_the_documented_keys() {
    let ideal = scenes().join("line-juggler-ideal.toml");
    let out = dexter(&["run", ideal.to_str().unwrap(), "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    for key in [
        "impacts",
        "sim_time_s",
        "wall_time_s",
        "target_apex_m",
        "final_apex_m",
        "converged_after_impacts",
        "period",
        "resting_contact",
    ] {
        assert!(v.get(key).is_some(), "missing {key} in {v}");
    }
    assert_eq!(v["impacts"], 60);
    assert_eq!(v["target_apex_m"], 1.0);
    assert_eq!(v["period"], 1);
    assert_eq!(v["resting_contact"], false);
    // the passive bounce has no target and never converges: nulls, and it rests
    let passive = scenes().join("passive-bounce.toml");
    let out = dexter(&["run", passive.to_str().unwrap(), "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(v["target_apex_m"].is_null() && v["converged_after_impacts"].is_null());
    assert_eq!(v["resting_contact"], true);
}

#[test]
fn trace_csv_has_header_and_a_row_per_impact() {
    let ideal = scenes().join("line-juggler-ideal.toml");
    let csv = std::env::temp_dir().join(format!("dexter-cli-trace-{}.csv", std::process::id()));
    let out = dexter(&[
        "run",
        ideal.to_str().unwrap(),
        "--impacts",
        "7",
        "--trace",
        csv.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "index,time_s,ball_height_m,ball_velocity_before_mps,ball_velocity_after_mps,paddle_height_m,paddle_velocity_mps,apex_height_m"
    );
    assert_eq!(lines.len(), 8);
    // first impact of a drop from 0.3 m: at sqrt(2 * 0.3 / g), speed sqrt(2 g 0.3)
    let cols: Vec<f64> = lines[1].split(',').map(|c| c.parse().unwrap()).collect();
    assert!((cols[1] - (0.6f64 / 9.81).sqrt()).abs() < 1e-15);
    assert!((cols[3] + (2.0f64 * 9.81 * 0.3).sqrt()).abs() < 1e-14);
}
