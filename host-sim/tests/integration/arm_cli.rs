//! The one-joint arm through the `dexter` binary (`scenes/arm-*.toml`), checked against
//! what is computed here independently of the code under test:
//!
//! - flight: the throw's landing from the release state in the trace, in closed form
//!   (`y(t) = y0 + vy t - g t^2 / 2` crossing the goal height going down);
//! - grasp kinematics: at the release the grasped object moves with the arm,
//!   `v_com = theta' (-y, x)` about the joint;
//! - statics: at rest on the arm tilted by theta the grasp needs exactly tan(theta);
//! - geometry: a square rolled onto its next edge has turned by pi/2 on the arm;
//! - the margin check is the same trajectory at 0.95 `mu_required` and fails.
//!
//! Each shipped scene is run once (JSON, trace and plots) and the results shared.

use crate::common;

use common::{dexter, ok, scene, scratch};
use serde_json::Value;
use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI};
use std::path::PathBuf;
use std::sync::{Mutex, OnceLock};

const G: f64 = 9.81;

/// One shipped scene's run: its JSON, its trace and the files `--plot` wrote.
struct Run {
    json: Value,
    trace: Vec<Row>,
    plots: Vec<PathBuf>,
}

/// A trace row: time, kind, phase and the numeric columns by name.
#[derive(Clone, Debug)]
struct Row {
    t: f64,
    kind: String,
    phase: String,
    v: HashMap<String, f64>,
}

impl Row {
    fn get(&self, col: &str) -> f64 {
        *self.v.get(col).unwrap_or_else(|| panic!("no column {col}"))
    }
}

fn read_trace(path: &PathBuf) -> Vec<Row> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header[..3], ["t_s", "kind", "phase"]);
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), header.len(), "{l}");
            let v = header[3..]
                .iter()
                .zip(&cells[3..])
                .map(|(h, c)| (h.to_string(), c.parse::<f64>().unwrap()))
                .collect();
            Row {
                t: cells[0].parse().unwrap(),
                kind: cells[1].to_string(),
                phase: cells[2].to_string(),
                v,
            }
        })
        .collect()
}

/// The run of `scenes/{name}.toml` (made once per test process).
fn run(name: &str) -> &'static Run {
    static RUNS: OnceLock<Mutex<HashMap<String, &'static Run>>> = OnceLock::new();
    // held while running: a second test asking for the same scene waits for the first
    let mut runs = RUNS
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    if let Some(r) = runs.get(name) {
        return r;
    }
    let dir = scratch(&format!("arm-{name}"));
    let trace = dir.join("trace.csv");
    let out = ok(&[
        "run",
        &scene(name),
        "--json",
        "--trace",
        trace.to_str().unwrap(),
        "--plot",
        dir.to_str().unwrap(),
    ]);
    let json: Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    let mut plots: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "svg" || x == "png"))
        .collect();
    plots.sort();
    let r: &'static Run = Box::leak(Box::new(Run {
        json,
        trace: read_trace(&trace),
        plots,
    }));
    runs.insert(name.to_string(), r);
    r
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn event<'a>(r: &'a Run, kind: &str) -> Option<&'a Row> {
    r.trace.iter().find(|row| row.kind == kind)
}

const TASKS: [&str; 4] = ["arm-snatch", "arm-throw", "arm-roll", "arm-rolling-throw"];

#[test]
fn every_task_executes_ok_needs_its_mu_and_survives_tracking() {
    for name in TASKS {
        let j = &run(name).json;
        assert_eq!(j["executed"], "ok", "{name}: {}", j["reason"]);
        let mu = f(&j["mu_required"]);
        let m = &j["mu_margin_check"];
        assert!((f(&m["mu"]) - 0.95 * mu).abs() < 1e-12, "{name}");
        // only the friction cone depends on mu: the same motion at 0.95 mu must slip
        assert_eq!(
            m["executed"], "slipped",
            "{name} at 0.95 mu: {}",
            m["reason"]
        );
        assert!(m["reason"].as_str().is_some_and(|s| s.contains("slipped")));
        // and at mu the executed motion really leans on that much friction: its sampled
        // peak |f_t| / f_n lies between 0.95 mu and mu
        let peak = run(name)
            .trace
            .iter()
            .map(|w| w.get("friction_ratio"))
            .filter(|x| x.is_finite())
            .fold(0.0, f64::max);
        assert!(
            peak <= mu * (1.0 + 1e-6) && peak > 0.95 * mu,
            "{name}: peak {peak} vs mu {mu}"
        );
        assert!(f(&j["planner_iterations"]) > 0.0 && f(&j["planner_wall_time_s"]) > 0.0);
        // the plan tracked by the core's controller (SIL) still does the task
        let t = &j["tracked"];
        assert_eq!(j["controller"], "sil");
        assert_eq!(t["executed"], "ok", "{name} tracked: {}", t["reason"]);
        assert_eq!(t["fault"], Value::Null);
        assert!(f(&t["max_torque_nm"]) <= 100.0);
        assert!(f(&t["max_tracking_error_rad"]) < 0.01, "{name}");
    }
}

/// The landing of a body released at `row` (trace columns), in closed form: where its
/// centre of mass crosses `y_goal` going down, its angle then, and the flight time.
fn closed_form_landing(row: &Row, y_goal: f64) -> (f64, f64, f64, f64) {
    let (x0, y0) = (row.get("com_x_m"), row.get("com_y_m"));
    let (vx, vy) = (row.get("com_vx_mps"), row.get("com_vy_mps"));
    let t = (vy + (vy * vy + 2.0 * G * (y0 - y_goal)).sqrt()) / G;
    let angle = row.get("object_angle_rad") + row.get("object_rate_radps") * t;
    (x0 + vx * t, y0 + vy * t - 0.5 * G * t * t, angle, t)
}

fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

#[test]
fn throws_land_where_the_closed_form_flight_from_the_release_says() {
    for (name, goal) in [
        ("arm-throw", (-0.5, 0.8, 2.2)),
        ("arm-rolling-throw", (-1.5, 1.0, 2.95)),
    ] {
        let r = run(name);
        let rel = event(r, "release").expect("a release");
        let land = event(r, "landing").expect("a landing");
        let (x, y, angle, t) = closed_form_landing(rel, goal.1);
        assert!((land.t - rel.t - t).abs() < 1e-9, "{name}: flight time");
        assert!((land.get("com_x_m") - x).abs() < 1e-9, "{name}: x");
        assert!((land.get("com_y_m") - y).abs() < 1e-9, "{name}: y");
        let e = &r.json["goal_error"];
        assert!((f(&e["position_m"]) - (x - goal.0).hypot(y - goal.1)).abs() < 1e-9);
        assert!((f(&e["angle_rad"]) - wrap(angle - goal.2)).abs() < 1e-9);
        assert!((x - goal.0).hypot(y - goal.1) <= 0.01 && wrap(angle - goal.2).abs() <= 0.05);
        // in flight after the release, the trace follows the same parabola
        for row in r.trace.iter().filter(|w| w.t > rel.t && w.t < land.t) {
            let s = row.t - rel.t;
            let xs = rel.get("com_x_m") + rel.get("com_vx_mps") * s;
            assert!((row.get("com_x_m") - xs).abs() < 1e-9);
            assert_eq!(row.phase, "flight");
        }
    }
}

#[test]
fn a_grasped_object_moves_with_the_arm_up_to_the_release() {
    let r = run("arm-throw");
    let rel = event(r, "release").unwrap();
    let w = rel.get("arm_velocity_radps");
    let (x, y) = (rel.get("com_x_m"), rel.get("com_y_m"));
    assert!(w > 1.0, "released while swinging up");
    assert!((rel.get("com_vx_mps") + w * y).abs() < 1e-9);
    assert!((rel.get("com_vy_mps") - w * x).abs() < 1e-9);
    assert!((rel.get("object_rate_radps") - w).abs() < 1e-9);
}

#[test]
fn the_snatch_ends_at_rest_at_its_angle_needing_tan_theta() {
    let r = run("arm-snatch");
    let (first, last) = (&r.trace[0], r.trace.last().unwrap());
    assert!((last.get("arm_angle_rad") - 0.3).abs() < 1e-9);
    assert_eq!(last.get("arm_velocity_radps"), 0.0);
    // the object kept its place on the arm: its centre turned by 0.3 rad about the joint
    let (c, s) = (0.3f64.cos(), 0.3f64.sin());
    let (x0, y0) = (first.get("com_x_m"), first.get("com_y_m"));
    assert!((last.get("com_x_m") - (c * x0 - s * y0)).abs() < 1e-9);
    assert!((last.get("com_y_m") - (s * x0 + c * y0)).abs() < 1e-9);
    // statics on a 0.3 rad incline: |f_t| / f_n = tan 0.3; level and still: 0
    assert!((last.get("friction_ratio") - 0.3f64.tan()).abs() < 1e-9);
    assert!(first.get("friction_ratio").abs() < 1e-12);
    assert!(f(&r.json["mu_required"]) >= 0.3f64.tan());
}

#[test]
fn the_nine_knot_roll_winds_up_then_lands_a_quarter_turn_on() {
    let r = run("arm-roll");
    assert_eq!(r.json["knots"], 9);
    assert_eq!(r.json["trajectory"]["knots"].as_array().unwrap().len(), 9);
    let start = event(r, "roll_start_ccw")
        .expect("rolls counterclockwise")
        .t;
    assert!(event(r, "roll_end").is_some());
    // fig. 2: the joint first swings the other way (clockwise), well before the roll
    let first_move = r
        .trace
        .iter()
        .find(|w| w.get("arm_velocity_radps").abs() > 1e-3)
        .unwrap();
    assert!(first_move.get("arm_velocity_radps") < 0.0);
    let low = r
        .trace
        .iter()
        .filter(|w| w.t < start)
        .map(|w| w.get("arm_angle_rad"))
        .fold(f64::INFINITY, f64::min);
    assert!(low < -0.05, "windup only {low} rad");
    // relative to the arm, the square turned by its exterior angle, pi/2
    let rel = |w: &Row| w.get("object_angle_rad") - w.get("arm_angle_rad");
    let (first, last) = (&r.trace[0], r.trace.last().unwrap());
    assert!((wrap(rel(last) - rel(first)) - FRAC_PI_2).abs() < 1e-9);
    assert_eq!(last.phase, "grasp");
}

/// The roll's end is a one-sided impact: the thin frame (side a = 0.1 m, rho = 0.0577 m)
/// cannot be stopped outright (the stop's centre of pressure would be `2 rho^2 / a`
/// beyond the striking vertex), so it rocks onto the striking vertex at
/// `rho^2 / (rho^2 + a^2/2)` of its rate, with an impulse needing friction
/// `(1 - k) / (1 + k)` (tests/integration/arm_impact.rs derives both), and rocks back and forth on
/// its new edge until it settles. Every impulse pushes, acts on the edge and lies inside
/// the cone of `mu_required`.
#[test]
fn the_roll_ends_with_a_one_sided_impact_and_the_rocks_are_reported() {
    let r = run("arm-roll");
    let (a, rho2) = (0.1, 0.0577f64.powi(2));
    let k = rho2 / (rho2 + a * a / 2.0);
    let mu = f(&r.json["mu_required"]);
    let impacts = r.json["impacts"].as_array().expect("impacts");
    assert!(impacts.len() >= 2, "the frame rocks: {impacts:?}");
    let first = &impacts[0];
    assert_eq!(first["outcome"], "rock");
    let end = event(r, "roll_end").unwrap().t;
    assert!((f(&first["t_s"]) - end).abs() < 1e-12);
    assert!((f(&first["rate_after_radps"]) / f(&first["rate_before_radps"]) - k).abs() < 1e-9);
    assert!((f(&first["stop_cop_m"]) + 2.0 * rho2 / a).abs() < 1e-9);
    assert!(f(&first["speed_mps"]) > 0.3, "a real impact: {first}");
    for i in impacts {
        let (cop, l) = (f(&i["cop_m"]), f(&i["edge_length_m"]));
        assert!(
            (0.0..=l).contains(&cop),
            "centre of pressure off the edge: {i}"
        );
        assert!(f(&i["cop_margin_m"]) >= 0.0, "{i}");
        let (pn, pt) = (f(&i["impulse_normal_mps"]), f(&i["impulse_tangential_mps"]));
        assert!(pn > 0.0, "pulls: {i}");
        assert!((pt.abs() / pn - (1.0 - k) / (1.0 + k)).abs() < 1e-9, "{i}");
        assert!(pt.abs() <= mu * pn, "outside the cone of mu_required: {i}");
    }
    // every rock leaves at k of the rate it came in at, each comes in slower than the one
    // before (the arm may still be moving: the rock in between is not exactly reversible)
    for i in impacts.iter().filter(|i| i["outcome"] == "rock") {
        let ratio = f(&i["rate_after_radps"]) / f(&i["rate_before_radps"]);
        assert!((ratio - k).abs() < 1e-9, "{i}");
    }
    let rates: Vec<f64> = impacts
        .iter()
        .map(|i| f(&i["rate_before_radps"]).abs())
        .collect();
    for w in rates.windows(2) {
        assert!(w[1] < w[0], "{rates:?}");
    }
    assert_eq!(impacts.last().unwrap()["outcome"], "grasp");
    let rocks = r.json["events"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["kind"].as_str().unwrap().starts_with("rock_"))
        .count();
    assert_eq!(rocks, impacts.len() - 1);
}

/// The paper's no-rebound law as a named option (`object.impact_law = "no_rebound"`): the
/// roll's end stops the frame outright, which needs the impulse's resultant where a stop
/// puts it, `2 rho^2 / a` behind the edge's first vertex (off the edge: a pull; hand
/// derivation in docs/arm.md, "Impacts"); the run flags it (`pulls`, `pulling_impacts`).
/// Under the default one-sided law nothing pulls.
#[test]
fn the_no_rebound_law_is_a_named_option_and_every_pull_it_needs_is_flagged() {
    let out = ok(&[
        "run",
        &scene("arm-roll"),
        "--json",
        "--set",
        "object.impact_law=\"no_rebound\"",
    ]);
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["impact_law"], "no_rebound");
    let impacts = j["impacts"].as_array().unwrap();
    let first = &impacts[0];
    assert_eq!(first["outcome"], "grasp");
    assert_eq!(first["pulls"], true, "{first}");
    let (a, rho2) = (0.1, 0.0577f64.powi(2));
    assert!(
        (f(&first["cop_m"]) + 2.0 * rho2 / a).abs() < 1e-9,
        "{first}"
    );
    assert!(f(&first["cop_margin_m"]) < 0.0);
    let pulled = impacts.iter().filter(|i| i["pulls"] == true).count();
    assert_eq!(j["pulling_impacts"], pulled);
    assert!(pulled >= 1);
    let text = ok(&[
        "run",
        &scene("arm-roll"),
        "--set",
        "object.impact_law=\"no_rebound\"",
    ]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("only by pulling"));
    let r = run("arm-roll");
    assert_eq!(r.json["impact_law"], "one_sided");
    assert_eq!(r.json["pulling_impacts"], 0);
    let impacts = r.json["impacts"].as_array().unwrap();
    assert!(impacts.iter().all(|i| i["pulls"] == false), "{impacts:?}");
}

/// With the planner's centre-of-pressure margin (`planner.cop_margin`, default 0.02 of
/// the edge) the rolling throw executes exactly its planned phases, grasp, roll, flight;
/// with no margin its plan grazes the vertex, tips early, falls back and tips again
/// (grgrf), and the verifier calls that `missed` although it lands on the goal.
#[test]
fn the_rolling_throw_executes_exactly_its_planned_phases_with_the_cop_margin() {
    let r = run("arm-rolling-throw");
    assert_eq!(r.json["phases"], "grf");
    assert_eq!(r.json["executed_phases"], "grf");
    assert_eq!(r.json["executed"], "ok");
    let kinds: Vec<&str> = r.json["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["kind"].as_str().unwrap())
        .collect();
    assert_eq!(kinds, ["roll_start_cw", "release", "landing"]);
    let out = ok(&[
        "run",
        &scene("arm-rolling-throw"),
        "--json",
        "--set",
        "planner.cop_margin=0",
    ]);
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_ne!(j["executed_phases"], "grf", "{j}");
    assert_eq!(j["executed"], "missed", "{}", j["reason"]);
}

#[test]
fn the_rolling_throw_rolls_clockwise_and_is_released_mid_roll() {
    let r = run("arm-rolling-throw");
    let roll = event(r, "roll_start_cw").expect("rolls clockwise").t;
    let rel = event(r, "release").unwrap();
    assert!(roll < rel.t);
    assert_eq!(rel.phase, "roll");
    assert!(event(r, "roll_end").is_none());
    assert_eq!(r.json["phases"], "grf");
}

#[test]
fn the_trace_has_a_row_every_millisecond_and_every_event_of_the_json() {
    for name in TASKS {
        let r = run(name);
        let samples: Vec<f64> = r
            .trace
            .iter()
            .filter(|w| w.kind == "sample")
            .map(|w| w.t)
            .collect();
        assert_eq!(samples[0], 0.0);
        for w in samples.windows(2) {
            assert!(
                w[1] > w[0] && w[1] - w[0] <= 1e-3 + 2e-4,
                "{name}: gap {w:?}"
            );
        }
        let events: Vec<(String, f64)> = r
            .trace
            .iter()
            .filter(|w| w.kind != "sample")
            .map(|w| (w.kind.clone(), w.t))
            .collect();
        let json: Vec<(String, f64)> = r.json["events"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| (e["kind"].as_str().unwrap().to_string(), f(&e["t_s"])))
            .collect();
        assert_eq!(events, json, "{name}");
        // the verified run never needs more friction than the plan's mu
        let mu = f(&r.json["mu_required"]);
        let peak = r
            .trace
            .iter()
            .map(|w| w.get("friction_ratio"))
            .filter(|x| x.is_finite())
            .fold(0.0, f64::max);
        assert!(peak <= mu, "{name}: {peak} > {mu}");
    }
}

#[test]
fn plots_are_written_a_filmstrip_a_trajectory_the_friction_and_the_torque() {
    for name in TASKS {
        let r = run(name);
        let stems: Vec<String> = r
            .plots
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        let want: Vec<String> = ["filmstrip", "friction", "torque", "trajectory"]
            .iter()
            .flat_map(|k| ["png", "svg"].map(|e| format!("{name}-{k}.{e}")))
            .collect();
        assert_eq!(stems, want);
        for p in &r.plots {
            assert!(
                std::fs::metadata(p).unwrap().len() > 1000,
                "{}",
                p.display()
            );
        }
        let film = std::fs::read_to_string(&r.plots[1]).unwrap();
        assert_eq!(film.matches("t = ").count(), 12, "{name}: twelve panels");
    }
}

/// `dexter run SCENE ARGS`: (exit code, stderr).
fn fails(name: &str, args: &[&str]) -> (i32, String) {
    let s = scene(name);
    let mut a = vec!["run", s.as_str()];
    a.extend(args);
    let out = dexter(&a);
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_scenes_exit_2_naming_the_dotted_key() {
    for (set, key) in [
        ("object.mass_kg=-1.0", "`object.mass_kg`"),
        ("planner.knots=17", "`planner.knots`"),
        ("task.goal_z_m=1.0", "task.goal_z_m"),
        ("tracking.dt_s=1e-6", "`tracking.dt_s`"),
        ("task.hold_s=100.0", "`task.hold_s`"),
        ("arm.brake_accel_radps2=0.5", "`arm.brake_accel_radps2`"),
        ("planner.accel_margin=1.0", "`planner.accel_margin`"),
        ("planner.cop_margin=0.5", "`planner.cop_margin`"),
        ("task.kind=\"juggle\"", "task.kind"),
    ] {
        let (code, err) = fails("arm-throw", &["--set", set]);
        assert_eq!(code, 2, "{set}: {err}");
        assert!(err.contains(key), "{set}: {err}");
    }
    let (code, err) = fails("arm-throw", &["--impacts", "3"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--impacts"), "{err}");
    let (code, err) = fails("arm-throw", &["--set", "physics.gravity_mps2=9.81"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("physics"), "{err}");
}

#[test]
fn an_unreachable_goal_is_a_failed_run_saying_why() {
    let (code, err) = fails(
        "arm-throw",
        &[
            "--set",
            "task.goal_x_m=20.0",
            "--set",
            "planner.starts=1",
            "--set",
            "planner.max_evaluations=100",
        ],
    );
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("arm planner"), "{err}");
}
