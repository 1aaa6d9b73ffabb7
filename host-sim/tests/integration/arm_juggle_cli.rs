//! The one-motor juggle (`scenes/arm-juggle.toml`) and the bang-bang move to the catch.
//!
//! Expected values are physics, not the code under test: the arm must be at rest at the
//! catching angle when the square comes down (read off the trace, not the plan), the move
//! from the release must first decelerate at the brake's bound (the trace's joint
//! acceleration), and a cycle's landing error must stay inside the goal tolerance and not
//! grow from the first cycles to the last.

use crate::common;

use common::{ok, scene, scratch};
use serde_json::Value;

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn chain_errors(c: &Value) -> Vec<f64> {
    c["cycles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|y| f(&y["landing_error_m"]))
        .collect()
}

/// Ten cycles in a row, exact and tracked (SIL), each caught, the landing error bounded by
/// the goal tolerance (0.01 m) and the last five no worse than the first five by more
/// than a millimetre; every cycle starts where the last catch of its chain left the
/// square, a quarter turn on.
#[test]
fn ten_throw_catch_cycles_in_a_row_with_a_landing_error_that_does_not_grow() {
    let out = ok(&["run", &scene("arm-juggle"), "--json"]);
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    let g = &j["juggle"];
    assert_eq!(g["cycles"], 10);
    for name in ["exact", "tracked"] {
        let c = &g[name];
        assert_eq!(c["completed"], 10, "{name}: {}", c["cycles"]);
        let cycles = c["cycles"].as_array().unwrap();
        let e = chain_errors(c);
        assert!(e.iter().all(|e| e.abs() < 0.01), "{name}: {e:?}");
        let worst = |s: &[f64]| s.iter().fold(0.0_f64, |m, e| m.max(e.abs()));
        assert!(worst(&e[5..]) <= worst(&e[..5]) + 1e-3, "{name}: {e:?}");
        for w in cycles.windows(2) {
            let caught = f(&w[0]["catch_position_m"]);
            assert_eq!(f(&w[1]["start_position_m"]), caught, "{name}: {w:?}");
            assert_eq!(
                (w[0]["start_edge"].as_u64().unwrap() + 3) % 4,
                w[1]["start_edge"]
            );
        }
        for y in cycles {
            assert_eq!(f(&y["mu"]), 0.45);
            assert!(f(&y["mu_required"]) <= 0.45, "{y}");
            assert!(f(&y["catch_cop_margin_m"]) >= 0.0, "{y}");
            assert!(f(&y["catch_friction_ratio"]) <= 0.45, "{y}");
        }
    }
}

/// The trace of the single throw and catch: after the release the joint first decelerates
/// at `arm.brake_accel_radps2` (30 rad/s^2), and when the square comes down it is at rest
/// at `task.catch_angle_rad` (0.2 rad).
#[test]
fn the_arm_reaches_the_catch_by_braking_first_and_waits_there_at_rest() {
    let dir = scratch("arm-bang-bang");
    let trace_path = dir.join("trace.csv");
    ok(&[
        "run",
        &scene("arm-throw-catch"),
        "--trace",
        trace_path.to_str().unwrap(),
    ]);
    let trace = std::fs::read_to_string(&trace_path).unwrap();
    let mut lines = trace.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (kind, th, w, a) = (
        col("kind"),
        col("arm_angle_rad"),
        col("arm_velocity_radps"),
        col("arm_accel_radps2"),
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let num = |r: &Vec<&str>, c: usize| r[c].parse::<f64>().unwrap();
    let release = rows.iter().position(|r| r[kind] == "release").unwrap();
    let after = &rows[release + 1];
    assert!(num(after, w) > 0.0, "the throw releases moving forward");
    assert_eq!(
        num(after, a),
        -30.0,
        "the first arc is the brake: {after:?}"
    );
    let catch = rows.iter().find(|r| r[kind] == "catch").unwrap();
    assert!((num(catch, th) - 0.2).abs() < 1e-12, "{catch:?}");
    assert_eq!(num(catch, w), 0.0);
}
