//! The throw and catch (`scenes/arm-throw-catch.toml`) through the `dexter` binary: the
//! catch's impulse is recomputed here from the trace's state at the catch, independently
//! of the code under test.
//!
//! At the catch the object flies with centre of mass `r`, velocity `v` and rate `omega`
//! (the trace's columns), the arm at angle theta with rate theta'. Relative to the arm and
//! in its frame (rotated by -theta), `v_rel = R(-theta) (v - theta' J r)`,
//! `omega_rel = omega - theta'`. A plastic stop takes `Pi = -v_rel`, so the friction it
//! needs is `|v_rel . t| / |v_rel . n|` (the link's surface: t = x, n = y of the arm
//! frame), and its resultant acts where the angular impulse about the centre of mass is
//! `-rho^2 omega_rel`: `sigma_c = ((r - O) x Pi - rho^2 omega_rel) / Pi_n`, O = (0, 0.05)
//! the surface's origin (the link's half thickness), rho^2 = a^2 / 6 for the square plate.
//!
//! The SIL-tracked catch comes down 0.0288 rad from flat: its vertex strikes first
//! (`impact::Rig::vertex_impact`), and that corner's sticking impulse needs friction 0.737
//! (recomputed by hand in `tests/integration/arm_impact.rs`), more than the plan's mu: `tracked` says
//! `slipped` at that impact, no longer "missed" for an unmodelled strike.

use crate::common;

use common::{ok, scene, scratch};
use serde_json::Value;

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// The trace row of event `kind`: column name -> value.
fn row(trace: &str, kind: &str) -> std::collections::HashMap<String, f64> {
    let mut lines = trace.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let line = lines
        .find(|l| l.split(',').nth(1) == Some(kind))
        .unwrap_or_else(|| panic!("no {kind} row"));
    header
        .iter()
        .zip(line.split(','))
        .filter_map(|(h, c)| c.parse::<f64>().ok().map(|v| (h.to_string(), v)))
        .collect()
}

#[test]
fn the_throw_is_caught_on_its_edge_by_a_feasible_one_sided_impact() {
    let dir = scratch("arm-throw-catch");
    let trace_path = dir.join("trace.csv");
    let out = ok(&[
        "run",
        &scene("arm-throw-catch"),
        "--json",
        "--trace",
        trace_path.to_str().unwrap(),
    ]);
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["task"], "throw_catch");
    assert_eq!(j["executed"], "ok", "{}", j["reason"]);
    assert_eq!(j["executed_phases"], "gfg");
    let c = &j["catch"];
    assert_eq!(c["feasible"], true, "{c}");
    assert_eq!(c["outcome"], "grasp");
    assert_eq!(c["edge"], 3);
    let (cop, l) = (f(&c["cop_m"]), f(&c["edge_length_m"]));
    assert!(cop > 0.0 && cop < l, "{c}");
    assert!((f(&c["cop_margin_m"]) - cop.min(l - cop)).abs() < 1e-12);
    let mu = f(&j["mu_required"]);
    assert!(f(&c["friction_ratio"]) <= mu, "{c}");

    // the impulse from the trace's state at the catch (module docs)
    let trace = std::fs::read_to_string(&trace_path).unwrap();
    let at = row(&trace, "catch");
    let (th, thd) = (at["arm_angle_rad"], at["arm_velocity_radps"]);
    let (rx, ry) = (at["com_x_m"], at["com_y_m"]);
    let (vx, vy) = (at["com_vx_mps"] + thd * ry, at["com_vy_mps"] - thd * rx);
    let (s, co) = th.sin_cos();
    let (vt, vn) = (co * vx + s * vy, -s * vx + co * vy);
    let w = at["object_rate_radps"] - thd;
    assert!(vn < 0.0, "coming down onto the surface");
    assert!((f(&c["friction_ratio"]) - vt.abs() / vn.abs()).abs() < 1e-9);
    assert!((f(&c["impulse_normal_mps"]) + vn).abs() < 1e-9);
    assert!((f(&c["impulse_tangential_mps"]) + vt).abs() < 1e-9);
    // where the stop's resultant acts, against the caught edge's first vertex: the
    // square lies flat to within flat_error_rad, so its vertex is at the centre of mass's
    // foot less a/2 (to a/2 flat_error, a fraction of a millimetre)
    let a = 0.1;
    let (rxa, rya) = (co * rx + s * ry, -s * rx + co * ry - 0.05);
    let (pt, pn) = (-vt, -vn);
    let sigma_c = (rxa * pn - rya * pt - a * a / 6.0 * w) / pn;
    let cop_here = sigma_c - (rxa - a / 2.0);
    let slack = a / 2.0 * f(&c["flat_error_rad"]).abs() + 1e-4;
    assert!((cop - cop_here).abs() < 3.0 * slack, "{cop} vs {cop_here}");

    // at 0.95 mu the catch's impulse leaves its cone, and the run says so
    let m = &j["mu_margin_check"];
    assert_eq!(m["executed"], "slipped", "{m}");
    assert!(
        m["reason"].as_str().unwrap().contains("impact"),
        "the run says where: {m}"
    );
}

/// The tracked throw and catch, closed through the catch and the hold: it comes down flat
/// (within the whole-edge tolerance) and is stopped outright, but its impulse needs a
/// little more friction than the plan's own mu, so at that mu it slips at the impact, and
/// with the friction it needs it is caught and held.
#[test]
fn the_tracked_catch_is_flat_and_slips_only_below_the_friction_its_impulse_needs() {
    let out = ok(&["run", &scene("arm-throw-catch"), "--json"]);
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    let t = &j["tracked"];
    let (needed, planned) = (f(&t["mu_needed"]), f(&j["mu_required"]));
    if needed > planned {
        assert_eq!(t["executed"], "slipped", "{t}");
        let why = t["reason"].as_str().unwrap();
        assert!(why.contains("impact") && why.contains("slipped"), "{why}");
    } else {
        assert_eq!(t["executed"], "ok", "{t}");
    }
    assert_eq!(t["executed_at_mu_needed"], "ok", "{t}");
    // the planned run: caught flat, a stop outright
    assert_eq!(j["executed"], "ok");
    assert_eq!(j["catch"]["outcome"], "grasp");
}
