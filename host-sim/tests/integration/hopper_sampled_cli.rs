//! The hopper on the MCU through the `dexter` binary (issue 12): the three sampled scenes in
//! SIL and the Raibert scene in HIL, their JSON keys, trace, timeline plots and key errors.
//!
//! Expected values are computed here, independently of the simulator: the exactly timed
//! thrust's fixed point by integrating the tuned linear model (eq. 10/16) with a fine RK4
//! step ([`exact_apex`]), the servo's target from the scene's E*/g, hand bounds on the
//! valve timing (the bottom prediction opens and closes the valve within half a control
//! period of the exact law's times). The HIL test needs `qemu-system-arm` and the
//! `thumbv7em-none-eabihf` target (it builds the firmware; it fails, never skips).

use crate::common;

use common::svg::Svg;
use common::{csv_rows, dexter, json, ok, scene, scratch};
use serde_json::Value;
use std::path::Path;

const G: f64 = 9.81;
/// The Raibert scene: chi_l, eta1, gamma, tau, delta (scenes/hopper-raibert-sil.toml).
const RAIBERT: (f64, f64, f64, f64, f64) = (0.5, 46.5, 2.33, 41.86, 0.05);

/// The settled apex of the tuned linear hopper (chi_0 = chi_l + g/eta1) with exactly timed
/// thrust tau (replacing the spring, eq. 10) for delta from each bottom, m: each stance integrated by RK4 at 1 us (the
/// bottom and liftoff located to the step), flights ballistic, 80 hops from a 1 m apex.
fn exact_apex((chi_l, eta1, gamma, tau, delta): (f64, f64, f64, f64, f64)) -> f64 {
    let rest = chi_l + G / eta1;
    let dt = 1e-6;
    let mut apex = 1.0;
    for _ in 0..80 {
        let (mut x, mut v) = (chi_l, -(2.0 * G * (apex - chi_l)).sqrt());
        let mut bottom: Option<f64> = None;
        let mut t = 0.0;
        while !(x >= chi_l && v > 0.0) || bottom.is_none() {
            // eq. 10: while the valve is open the thrust tau replaces the spring force
            let force = |t: f64, x: f64| match bottom {
                Some(tb) if t >= tb && t < tb + delta => tau,
                _ => eta1 * (rest - x),
            };
            let acc = |t: f64, x: f64, v: f64| force(t, x) - gamma * v - G;
            let (k1x, k1v) = (v, acc(t, x, v));
            let (k2x, k2v) = (
                v + 0.5 * dt * k1v,
                acc(t + 0.5 * dt, x + 0.5 * dt * k1x, v + 0.5 * dt * k1v),
            );
            let (k3x, k3v) = (
                v + 0.5 * dt * k2v,
                acc(t + 0.5 * dt, x + 0.5 * dt * k2x, v + 0.5 * dt * k2v),
            );
            let (k4x, k4v) = (v + dt * k3v, acc(t + dt, x + dt * k3x, v + dt * k3v));
            let v_new = v + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
            x += dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            t += dt;
            if bottom.is_none() && v < 0.0 && v_new >= 0.0 {
                bottom = Some(t);
            }
            v = v_new;
        }
        apex = x + v * v / (2.0 * G);
    }
    apex
}

fn run_json(name: &str, extra: &[&str]) -> Value {
    let s = scene(name);
    let mut args = vec!["run", s.as_str(), "--json"];
    args.extend_from_slice(extra);
    json(&args)
}

/// The late hops of a trace: the apex heights of its last `n` rows.
fn late_apexes(trace: &Path, n: usize) -> Vec<f64> {
    let rows = csv_rows(trace);
    rows[rows.len() - n..]
        .iter()
        .map(|r| r["apex_height_m"])
        .collect()
}

/// The valve opens and closes within half a control period (and a slack of 1 us) of the
/// exactly timed thrust, at every hop: the bottom prediction's promise.
fn assert_valve_within_half_a_period(j: &Value, dt_s: f64) {
    let e = &j["phase_detection_errors"];
    for key in ["thrust_start_s", "thrust_end_s"] {
        let (lo, hi) = (
            e[key]["min_s"].as_f64().unwrap(),
            e[key]["max_s"].as_f64().unwrap(),
        );
        assert!(
            lo >= -0.5 * dt_s - 1e-6 && hi <= 0.5 * dt_s + 1e-6,
            "{key}: [{lo}, {hi}] s"
        );
    }
    for ev in ["touchdown", "bottom", "liftoff"] {
        let x = &e[ev];
        assert_eq!(x["missed"], 0, "{ev}: {x}");
        assert_eq!(x["spurious"], 0, "{ev}: {x}");
        assert_eq!(x["events"], j["cycles"], "{ev}: {x}");
    }
}

/// Raibert's thrust at 1 kHz settles to period 1 with its apex within 1 % (of the hop
/// height) of the exactly timed thrust's fixed point computed here, and the reported
/// fixed-point error agrees; the valve is within half a period of the exact law.
#[test]
fn raibert_scene_settles_within_1_percent_of_the_exact_fixed_point() {
    let dir = scratch("hop-raibert");
    let trace = dir.join("t.csv");
    let j = run_json("hopper-raibert-sil", &["--trace", trace.to_str().unwrap()]);
    assert_eq!(j["cycles"], 300);
    assert_eq!(j["period"], 1, "{}", j["settle"]);
    assert_eq!(j["end"], "completed");
    assert_eq!(j["safe_steps"], 0);
    let chi_l = RAIBERT.0;
    let h_exact = exact_apex(RAIBERT) - chi_l;
    let h_ref = j["exact_orbit"]["hop_heights_m"][0].as_f64().unwrap();
    assert!(
        (h_ref - h_exact).abs() < 1e-4 * h_exact,
        "eq. 17 {h_ref} vs integrated {h_exact}"
    );
    let fpe = j["fixed_point_error"].as_f64().unwrap();
    assert!(fpe < 0.01, "fixed_point_error {fpe}");
    for a in late_apexes(&trace, 8) {
        let err = (a - chi_l - h_exact).abs() / h_exact;
        assert!(err < 0.01, "apex {a}: {err} of the hop height");
        assert!(err <= fpe + 1e-4, "apex {a}: {err} vs reported {fpe}");
    }
    let apexes = j["late_apex_heights_m"].as_array().unwrap();
    assert_eq!(apexes.len(), 8);
    assert_valve_within_half_a_period(&j, 1e-3);
}

/// The energy servo reaches its target hop E*/g = 1.4715 / 9.81 = 0.15 m from a 1 m apex
/// (hop 0.5 m): the trace's late apexes within 1 % of it. Flipping the servo's sign drives
/// the hop away from the target and fails this.
#[test]
fn servo_scene_reaches_its_target_hop_height() {
    let dir = scratch("hop-servo");
    let trace = dir.join("t.csv");
    let j = run_json("hopper-servo-sil", &["--trace", trace.to_str().unwrap()]);
    let target = 1.4715 / G;
    assert_eq!(j["thrust_law"], "energy_servo");
    assert!((j["target_hop_height_m"].as_f64().unwrap() - target).abs() < 1e-12);
    for a in late_apexes(&trace, 8) {
        let err = (a - 0.5 - target).abs() / target;
        assert!(err < 0.01, "apex {a}: {err} off the target hop");
    }
    assert!(j["period"].is_u64(), "settled: {}", j["settle"]);
    assert!(j["fixed_point_error"].as_f64().unwrap() < 0.01);
    assert!(j["target_hop_error"].as_f64().unwrap() < 0.01);
    assert_valve_within_half_a_period(&j, 1e-3);
}

/// Off its nominal thrust (tau0 10 % low, 42.606 m/s^2) the servo cannot reach its target
/// without steady error (it is proportional), but it must close part of the gap between
/// Raibert's fixed point at tau0 (integrated here) and the target: linearized, h - h_R =
/// k_E g H'(tau) (h* - h) with H' ~ 0.008 m per m/s^2 (the exact apexes at tau 46 and 48),
/// about 28 % of the gap; at least 10 % is asserted. A servo with its sign flipped ends
/// below Raibert's fixed point and fails this.
#[test]
fn servo_off_nominal_moves_the_hop_toward_its_target() {
    let tau0 = 0.9 * 47.34;
    let set = format!("hopper.thrust_tau_mps2={tau0}");
    let j = run_json("hopper-servo-sil", &["--set", &set]);
    let h_raibert = exact_apex((0.5, 46.5, 2.33, tau0, 0.05)) - 0.5;
    let target = 1.4715 / G;
    let late: Vec<f64> = j["late_apex_heights_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_f64().unwrap() - 0.5)
        .collect();
    for h in late {
        let closed = (h - h_raibert) / (target - h_raibert);
        assert!(
            (0.1..1.0).contains(&closed),
            "hop {h}: closes {closed} of the gap from {h_raibert} to {target}"
        );
    }
}

/// Above the doubling the limp persists at 1 kHz: period 2, the trace's late apexes
/// alternate long and short, each branch within 5 % of the exact 2-cycle.
#[test]
fn limp_scene_keeps_its_period_2() {
    let dir = scratch("hop-limp");
    let trace = dir.join("t.csv");
    let j = run_json("hopper-limp-sil", &["--trace", trace.to_str().unwrap()]);
    assert_eq!(j["period"], 2, "{}", j["settle"]);
    let exact: Vec<f64> = j["exact_orbit"]["hop_heights_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(exact.len(), 2);
    let mid = 0.5 + 0.5 * (exact[0] + exact[1]);
    let late = late_apexes(&trace, 40);
    assert!(
        late.windows(2).all(|w| (w[0] > mid) != (w[1] > mid)),
        "{late:?}"
    );
    assert!(j["fixed_point_error"].as_f64().unwrap() < 0.05);
}

/// The timeline plots draw the run's own hops: the valve's open stretches in the phase
/// chart start at the trace's valve-opening times, the phases sit on their levels, and the
/// deepest true compression is the trace's deepest bottom.
#[test]
fn the_timeline_plots_draw_the_last_hops() {
    let dir = scratch("hop-plot");
    let trace = dir.join("t.csv");
    let s = scene("hopper-raibert-sil");
    let t = trace.to_str().unwrap();
    let d = dir.to_str().unwrap();
    ok(&["run", &s, "--impacts", "40", "--trace", t, "--plot", d]);
    let rows = csv_rows(&trace);
    let last3 = &rows[rows.len() - 3..];
    let phase = Svg::read(&dir.join("hopper-raibert-sil-timeline-phase.svg"));
    let valve = phase.line("#0082C8");
    let opens: Vec<f64> = valve
        .windows(2)
        .filter(|w| w[1].1 - w[0].1 > 0.25)
        .map(|w| w[1].0)
        .collect();
    assert_eq!(opens.len(), 3, "{opens:?}");
    for (o, r) in opens.iter().zip(last3) {
        let px = (o - r["valve_open_time_s"]).abs() / phase.x.per_pixel();
        assert!(px < 1.5, "valve opens at {o} vs {}", r["valve_open_time_s"]);
    }
    for colour in ["#E6194B", "#3CB44B"] {
        for p in phase.line(colour) {
            let level = p.1.round();
            assert!(
                (p.1 - level).abs() < 2.0 * phase.y.per_pixel() && (0.0..=3.0).contains(&level)
            );
        }
    }
    let leg = Svg::read(&dir.join("hopper-raibert-sil-timeline-leg.svg"));
    let deepest = leg.line("#E6194B").iter().map(|p| p.1).fold(0.0, f64::max);
    let want = last3
        .iter()
        .map(|r| 0.5 - r["bottom_height_m"])
        .fold(0.0, f64::max);
    assert!(
        (deepest - want).abs() < 2.0 * leg.y.per_pixel(),
        "{deepest} vs {want}"
    );
    assert!(dir.join("hopper-raibert-sil-timeline-leg.png").exists());
}

/// A bad key exits 2 naming it.
#[test]
fn bad_keys_are_refused_by_name() {
    let dir = scratch("hop-bad");
    let s = scene("hopper-raibert-sil");
    let refuse = |sets: &[&str], key: &str| {
        let mut args = vec!["run", s.as_str()];
        for set in sets {
            args.extend(["--set", set]);
        }
        let out = dexter(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{sets:?}: {err}");
        assert!(err.contains(key), "{sets:?}: {err}");
    };
    refuse(&["hopper.control.rate=5"], "hopper.control.rate");
    refuse(&["hopper.control.rate_hz=0"], "hopper.control.rate_hz");
    refuse(&["hopper.control.rate_hz=1e9"], "hopper.control.rate_hz");
    refuse(&["hopper.sensor.latency_s=-1.0"], "hopper.sensor.latency_s");
    refuse(&["hopper.sensor.rate_hz=1e9"], "hopper.sensor.rate_hz");
    refuse(
        &["hopper.control.settle_tolerance=2.0"],
        "hopper.control.settle_tolerance",
    );
    refuse(
        &["hopper.control.debounce_samples=0"],
        "hopper.control.debounce_samples",
    );
    refuse(
        &["hopper.initial_heights_m=[0.3]"],
        "hopper.initial_heights_m",
    );
    refuse(
        &[
            "hopper.model=\"simplified_nonlinear\"",
            "hopper.thrust_delta_s=0.0",
            "hopper.friction_gamma_per_s=0.0",
        ],
        "hopper.model",
    );
    let fig = scene("hopper-fig12");
    let out = dexter(&["run", &fig, "--hil"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("hopper.control"));
    let sweep = dexter(&["sweep", &s, "--range", "hopper.control.rate_hz=500:2000:3"]);
    assert_eq!(sweep.status.code(), Some(2));
    let _ = std::fs::remove_dir_all(dir);
}

/// Everything a run reports but its timing, as JSON without `wall_time_s` and the HIL keys.
fn without_timing(mut j: Value) -> Value {
    let m = j.as_object_mut().unwrap();
    for k in [
        "wall_time_s",
        "step_instructions_min",
        "step_instructions_mean",
        "step_instructions_max",
        "sil_mismatches",
        "link_errors",
        "over_budget_steps",
        "link_timeouts",
        "steps_per_wall_second",
    ] {
        m.remove(k);
    }
    j
}

/// `--hil`: the firmware in QEMU closes the same loop bit for bit: the same trace (every
/// hop's exact event times, 17 digits) and the same summary as SIL, no mismatch or link
/// error, every step within the 300-instruction budget, and the fixed-point error within
/// 1 % of the exact fixed point computed here.
#[test]
fn raibert_scene_in_hil_equals_sil_bit_for_bit() {
    dexter_sim::hil::build_firmware()
        .expect("the firmware builds (rustup target add thumbv7em-none-eabihf)");
    let dir = scratch("hop-hil");
    let (ts, th) = (dir.join("sil.csv"), dir.join("hil.csv"));
    let sil = run_json("hopper-raibert-sil", &["--trace", ts.to_str().unwrap()]);
    let hil = run_json(
        "hopper-raibert-sil",
        &["--hil", "--trace", th.to_str().unwrap()],
    );
    assert_eq!(hil["sil_mismatches"], 0);
    assert_eq!(hil["link_errors"], 0);
    assert_eq!(hil["safe_steps"], 0);
    let max = hil["step_instructions_max"].as_u64().unwrap();
    let min = hil["step_instructions_min"].as_u64().unwrap();
    let mean = hil["step_instructions_mean"].as_f64().unwrap();
    assert!(
        min > 0 && (min as f64) <= mean && mean <= max as f64 && max <= 300,
        "{hil}"
    );
    assert_eq!(
        std::fs::read(&ts).unwrap(),
        std::fs::read(&th).unwrap(),
        "HIL and SIL traces differ"
    );
    assert_eq!(without_timing(hil.clone()), without_timing(sil));
    let h_exact = exact_apex(RAIBERT) - RAIBERT.0;
    for a in hil["late_apex_heights_m"].as_array().unwrap() {
        let err = (a.as_f64().unwrap() - RAIBERT.0 - h_exact).abs() / h_exact;
        assert!(err < 0.01, "HIL apex {a}: {err}");
    }
    assert!(hil["fixed_point_error"].as_f64().unwrap() < 0.01);
}
