//! The 1JOC feeder through the `dexter` binary (`[feeder]` scenes, issue 16 item 5).
//!
//! What the binary claims is checked here independently of the planner: the goal edge from
//! the part's hull by the paper's rule (sec. 3.2), computed in this file; "ends on the goal
//! edge" from the trace's last pose (both ends of that hull edge on the fence line at 0, every
//! other vertex above it); the drift phase against the belt's velocity; the infeasibility
//! figures against a run just past them.

use crate::common;

use common::{dexter, ok, scene, scratch};
use serde_json::Value;
use std::f64::consts::{PI, TAU};

const SCENES: [&str; 4] = [
    "1joc-square",
    "1joc-l-part",
    "1joc-triangle",
    "1joc-parallelogram",
];

fn json(args: &[&str]) -> Value {
    let mut a = args.to_vec();
    a.push("--json");
    common::json(&a)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn hull(j: &Value) -> Vec<(f64, f64)> {
    j["hull_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| (f(&p[0]), f(&p[1])))
        .collect()
}

/// Stable hull edges by hand: the center of mass (the body origin) projects strictly
/// inside the edge.
fn stable_edges(h: &[(f64, f64)]) -> Vec<usize> {
    let n = h.len();
    (0..n)
        .filter(|&i| {
            let (a, b) = (h[i], h[(i + 1) % n]);
            let (dx, dy) = (b.0 - a.0, b.1 - a.1);
            let t = (-a.0 * dx - a.1 * dy) / (dx * dx + dy * dy);
            t > 0.02 && t < 0.98
        })
        .collect()
}

/// The paper's goal edge (sec. 3.2): one whose counter-clockwise rotation to the next
/// stable edge is 180 deg or more; else the largest such gap (lowest index on ties).
fn paper_goal(h: &[(f64, f64)]) -> usize {
    let n = h.len();
    let dir = |i: usize| {
        let (a, b) = (h[i], h[(i + 1) % n]);
        (b.1 - a.1).atan2(b.0 - a.0)
    };
    let st = stable_edges(h);
    let gap = |s: usize| {
        st.iter()
            .filter(|&&o| o != s)
            .map(|&o| {
                let d = (dir(s) - dir(o)).rem_euclid(TAU);
                if d < 1e-12 {
                    TAU
                } else {
                    d
                }
            })
            .fold(TAU, f64::min)
    };
    if let Some(&s) = st.iter().find(|&&s| gap(s) >= PI - 1e-6) {
        return s;
    }
    st.iter()
        .copied()
        .fold((f64::NEG_INFINITY, 0), |b, s| {
            if gap(s) > b.0 + 1e-12 {
                (gap(s), s)
            } else {
                b
            }
        })
        .1
}

/// The last row of a trace CSV as (column -> value).
fn last_row(csv: &str) -> std::collections::HashMap<String, String> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let last: Vec<&str> = lines.last().unwrap().split(',').collect();
    header
        .iter()
        .zip(last)
        .map(|(h, v)| (h.to_string(), v.to_string()))
        .collect()
}

#[test]
fn every_scene_is_fed_to_the_paper_goal_edge_and_ends_flush_on_it() {
    let dir = scratch("feeder-run");
    for name in SCENES {
        let trace = dir.join(format!("{name}.csv"));
        let j = json(&["run", &scene(name), "--trace", trace.to_str().unwrap()]);
        for key in common::feeder::SUMMARY_KEYS {
            assert!(j.get(key).is_some(), "{name}: no {key}");
        }
        let h = hull(&j);
        let goal = paper_goal(&h);
        assert_eq!(j["goal_edge"].as_u64(), Some(goal as u64), "{name}");
        assert_eq!(j["reached_goal"], Value::Bool(true), "{name}");
        assert_eq!(j["final_edge"].as_u64(), Some(goal as u64), "{name}");
        let err = f(&j["final_contact_radius_m"]) - f(&j["goal_radius_m"]);
        assert!((err - f(&j["radius_error_m"])).abs() < 1e-12 && err.abs() <= 1e-3);
        let plan_time: f64 = j["plan"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| f(&p["duration_s"]))
            .sum();
        assert!((plan_time - f(&j["plan_time_s"])).abs() < 1e-9, "{name}");
        // The trace's last pose: the goal edge's two ends on the fence line y = 0 (the fence
        // at 0), every other hull vertex above it, the COM at the goal radius.
        let row = last_row(&std::fs::read_to_string(&trace).unwrap());
        let num = |k: &str| row[k].parse::<f64>().unwrap();
        assert_eq!(num("fence_angle_rad"), 0.0, "{name}");
        let (cx, cy, th) = (num("com_x_m"), num("com_y_m"), num("part_angle_rad"));
        let world: Vec<(f64, f64)> = h
            .iter()
            .map(|&(x, y)| {
                (
                    cx + x * th.cos() - y * th.sin(),
                    cy + x * th.sin() + y * th.cos(),
                )
            })
            .collect();
        let n = h.len();
        for (i, p) in world.iter().enumerate() {
            let on_goal = i == goal || i == (goal + 1) % n;
            match on_goal {
                true => assert!(p.1.abs() < 1e-6, "{name}: vertex {i} at y = {}", p.1),
                false => assert!(p.1 > 1e-4, "{name}: vertex {i} at y = {}", p.1),
            }
        }
        assert!(
            (cx - f(&j["final_contact_radius_m"])).abs() < 1e-9,
            "{name}"
        );
    }
}

#[test]
fn the_convergent_turn_is_planned_exactly_for_the_parallelogram_and_needed_there() {
    for name in SCENES {
        let j = json(&["run", &scene(name)]);
        let h = hull(&j);
        let st = stable_edges(&h);
        let parallel = st.len() == 2 && {
            let d = |i: usize| {
                let (a, b) = (h[i], h[(i + 1) % h.len()]);
                (b.1 - a.1).atan2(b.0 - a.0)
            };
            ((d(st[0]) - d(st[1])).rem_euclid(TAU) - PI).abs() < 1e-9
        };
        assert_eq!(parallel, name == "1joc-parallelogram");
        let conv = j["plan"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|p| p["primitive"] == "convergent_turn")
            .count();
        assert_eq!(conv, usize::from(parallel), "{name}");
        assert_eq!(j["convergent_turns"].as_u64(), Some(conv as u64));
    }
    let out = dexter(&[
        "run",
        &scene("1joc-parallelogram"),
        "--set",
        "feeder.planner.allow_convergent=false",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no feeding plan") && err.contains("convergent turn"),
        "{err}"
    );
}

#[test]
fn the_drift_before_the_catch_moves_with_the_belt() {
    // Until the part touches the fence it moves with the belt: x and the angle constant, y
    // falling at v_b = 0.05 m/s (the scene's belt speed).
    let dir = scratch("feeder-drift");
    let trace = dir.join("t.csv");
    ok(&[
        "run",
        &scene("1joc-square"),
        "--trace",
        trace.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&trace).unwrap();
    let rows: Vec<Vec<String>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(String::from).collect())
        .take_while(|r: &Vec<String>| r[3] == "free")
        .collect();
    assert!(rows.len() > 10);
    let n = |r: &Vec<String>, i: usize| r[i].parse::<f64>().unwrap();
    for w in rows.windows(2) {
        let dt = n(&w[1], 0) - n(&w[0], 0);
        assert!((n(&w[1], 7) - n(&w[0], 7) + 0.05 * dt).abs() < 1e-12);
        assert_eq!(n(&w[1], 6), n(&w[0], 6));
        assert_eq!(n(&w[1], 8), n(&w[0], 8));
    }
    assert_eq!(
        text.lines().next().unwrap(),
        "t_s,step,primitive,mode,fence_angle_rad,fence_rate_radps,com_x_m,com_y_m,part_angle_rad,fence_coordinate_m"
    );
}

#[test]
fn infeasibility_names_the_limit_and_a_value_just_past_it_works() {
    let sq = scene("1joc-square");
    let near = ["--set", "feeder.arrival.x_m=0.05"];
    let out = dexter(&[
        "run",
        &sq,
        near[0],
        near[1],
        "--set",
        "feeder.fence.length_m=0.1",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        err.contains("fence too short") && err.contains("feeder.fence.length_m >="),
        "{err}"
    );
    let need = number_after(&err, "length_m >= ");
    let longer = format!("feeder.fence.length_m={}", need + 0.005);
    let j = json(&["run", &sq, near[0], near[1], "--set", &longer]);
    assert_eq!(j["reached_goal"], Value::Bool(true));
    let x = ["--set", "feeder.arrival.x_m=0.06"];
    let out = dexter(&["run", &sq, x[0], x[1], "--set", "feeder.belt.width_m=0.3"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        err.contains("belt too narrow") && err.contains("feeder.belt.width_m >="),
        "{err}"
    );
    let need = number_after(&err, "width_m >= ");
    let wider = format!("feeder.belt.width_m={}", need + 0.01);
    let j = json(&["run", &sq, x[0], x[1], "--set", &wider]);
    assert_eq!(j["reached_goal"], Value::Bool(true));
}

#[test]
fn bad_values_exit_2_naming_the_dotted_key() {
    let sq = scene("1joc-square");
    for (set, key) in [
        ("feeder.belt.speed_mps=-0.05", "feeder.belt.speed_mps"),
        ("feeder.fence.mu=-0.1", "feeder.fence.mu"),
        ("feeder.fence.lenght=2.0", "feeder.fence.lenght"),
        (
            "feeder.fence.max_angle_deg=95.0",
            "feeder.fence.max_angle_deg",
        ),
        ("feeder.arrival.y_m=0.01", "feeder.arrival.y_m"),
        ("feeder.arrival.x_m=0.5", "feeder.arrival.x_m"),
        ("feeder.arrival.x_m=\"far\"", "feeder.arrival.x_m"),
        (
            "feeder.goal.contact_radius_m=-1.0",
            "feeder.goal.contact_radius_m",
        ),
        (
            "feeder.noise.fence_mu_rel=-1.0",
            "feeder.noise.fence_mu_rel",
        ),
        (
            "feeder.part.vertices_m=[[0.0, 0.0], [1.0, 0.0]]",
            "feeder.part.vertices_m",
        ),
        (
            "feeder.arrival.x_range_m=[0.3, 0.1]",
            "feeder.arrival.x_range_m",
        ),
    ] {
        let mut args = vec!["run", sq.as_str(), "--set", set];
        if key == "feeder.arrival.x_range_m" {
            args.extend(["--set", "feeder.arrival.seed=3"]);
        }
        let out = dexter(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{set}: {err}");
        assert!(err.contains(key), "{set}: {err}");
    }
    for extra in [["--impacts", "3"], ["--duration", "2"]] {
        let out = dexter(&["run", &sq, extra[0], extra[1]]);
        assert_eq!(out.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&out.stderr).contains(extra[0]));
    }
}

#[test]
fn the_plot_draws_a_filmstrip_and_two_charts() {
    let dir = scratch("feeder-plot");
    let out = ok(&[
        "run",
        &scene("1joc-triangle"),
        "--plot",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    for stem in ["filmstrip", "fence", "radius"] {
        for ext in ["svg", "png"] {
            let p = dir.join(format!("1joc-triangle-{stem}.{ext}"));
            assert!(
                std::fs::metadata(&p).is_ok_and(|m| m.len() > 1000),
                "{}",
                p.display()
            );
        }
    }
    let svg = std::fs::read_to_string(dir.join("1joc-triangle-filmstrip.svg")).unwrap();
    assert!(svg.contains("arrival") && svg.contains("turn: catch") && svg.contains("jog: end"));
}

#[test]
fn a_sweep_over_arrival_seeds_feeds_every_one_in_serial_order() {
    let dir = scratch("feeder-sweep");
    let csv = dir.join("s.csv");
    let out = ok(&[
        "sweep",
        &scene("1joc-l-part"),
        "--range",
        "feeder.arrival.seed=1:6:6",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(rows.len(), 6);
    for (i, r) in rows.iter().enumerate() {
        assert_eq!(r[0], (i + 1).to_string());
        assert_eq!(r[6], "fed", "{r:?}");
    }
    let angles: Vec<&str> = rows.iter().map(|r| r[3]).collect();
    assert!(
        angles.windows(2).all(|w| w[0] != w[1]),
        "random arrivals differ"
    );
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains("fraction fed: 6/6 = 1.0000"), "{summary}");
    let out = dexter(&[
        "sweep",
        &scene("1joc-l-part"),
        "--range",
        "hopper.cycles=1:2:2",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("hopper.cycles"));
}

#[test]
fn noise_perturbs_the_execution_not_the_plan() {
    let tri = scene("1joc-triangle");
    let clean = json(&["run", &tri]);
    let noisy = json(&[
        "run",
        &tri,
        "--set",
        "feeder.noise.belt_speed_rel=0.05",
        "--set",
        "feeder.noise.seed=4",
    ]);
    assert_eq!(
        clean["plan"], noisy["plan"],
        "the plan uses the nominal values"
    );
    let v = f(&noisy["actual"]["belt_speed_mps"]);
    assert!(v != 0.05 && (v - 0.05).abs() < 0.05 * 0.05 * 6.0, "{v}");
    assert_eq!(f(&clean["actual"]["belt_speed_mps"]), 0.05);
    assert_eq!(noisy["noise"], Value::Bool(true));
}

/// The number that follows `marker` in `text` (the size an infeasibility message asks for).
fn number_after(text: &str, marker: &str) -> f64 {
    let rest = text
        .split(marker)
        .nth(1)
        .unwrap_or_else(|| panic!("no {marker:?}: {text}"));
    let word = rest.split(' ').next().unwrap();
    word.parse()
        .unwrap_or_else(|e| panic!("{word:?} after {marker:?}: {e}"))
}
