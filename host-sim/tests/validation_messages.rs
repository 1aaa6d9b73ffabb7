//! Issue 22, findings 12 to 14: validation that refused documented values, and error
//! messages in internal names. Expected ranges come from the docs (docs/planar.md,
//! docs/hopper.md, docs/scenes.md), never from the code under test.

mod common;

use common::{dexter, scene};

/// `dexter args`: exit code and stderr.
fn run(args: &[&str]) -> (Option<i32>, String) {
    let out = dexter(args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A bad scene: exit 2, and the message names `key`.
fn refused(args: &[&str], key: &str) -> String {
    let (code, err) = run(args);
    assert_eq!(code, Some(2), "{args:?}: {err}");
    assert!(err.contains(key), "{args:?} should name {key}: {err}");
    err
}

/// A run of the real table with `sets`, one impact.
fn real_table(sets: &[String]) -> (Option<i32>, String) {
    let s = scene("planar-triangle-sil");
    let mut args = vec!["run", s.as_str(), "--impacts", "1"];
    for set in sets {
        args.extend(["--set", set.as_str()]);
    }
    run(&args)
}

/// Finding 12: the whole documented range of `real_table.control_rate_hz` is accepted
/// where the documented joint rule holds (rate > (contact_iterations + 8) / (0.2 s -
/// camera.latency_s)), and a rate the rule refuses is refused in the scene's own keys.
#[test]
fn real_table_control_rates_in_the_documented_range_are_accepted() {
    // the documented lower end, 50 Hz, with one Newton step: (1 + 8) / 0.2 = 45 Hz
    for (rate, iterations) in [(50.0, 1), (60.0, 2), (100.0, 2), (400.0, 2), (10_000.0, 4)] {
        let (code, err) = real_table(&[
            format!("real_table.control_rate_hz={rate:?}"),
            format!("real_table.contact_iterations={iterations}"),
        ]);
        assert_ne!(code, Some(2), "{rate} Hz, {iterations} steps: {err}");
    }
    // 50 Hz with the default 2 steps and 4 ms: (2 + 8) / 0.196 = 51.02 Hz needed
    let s = scene("planar-triangle-sil");
    let err = refused(
        &[
            "run",
            &s,
            "--impacts",
            "1",
            "--set",
            "real_table.control_rate_hz=50.0",
        ],
        "real_table.control_rate_hz",
    );
    assert!(!err.contains("commit_s"), "an internal name: {err}");
    assert!(err.contains("51.02"), "the lowest rate: {err}");
}

/// Finding 12: camera latencies the docs allow (0 <= latency < 0.1 s) are accepted; 0.1 s
/// is refused naming `real_table.camera.latency_s` and its range, not an internal field.
#[test]
fn real_table_camera_latencies_in_the_documented_range_are_accepted() {
    for latency in [0.0, 0.01, 0.03, 0.05, 0.09] {
        let (code, err) = real_table(&[format!("real_table.camera.latency_s={latency:?}")]);
        assert_ne!(code, Some(2), "latency {latency} s: {err}");
    }
    let s = scene("planar-triangle-sil");
    for latency in ["0.1", "1.0"] {
        let set = format!("real_table.camera.latency_s={latency}");
        let err = refused(
            &["run", &s, "--impacts", "1", "--set", &set],
            "real_table.camera.latency_s",
        );
        assert!(!err.contains("estimator"), "an internal name: {err}");
        assert!(err.contains("0.1"), "the range: {err}");
    }
}
