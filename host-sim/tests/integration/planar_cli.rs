//! The `dexter` binary on planar scenes (issue 5): `analyze` against the closed form of eq. 11
//! (`dexter_core::tilt`), `run` on the triangle with and without timing noise and with
//! friction, a small `sweep` against the library's `classify`, plots, and named errors.

use crate::common;
use dexter_core::tilt::{kappa_crit, tilt_eigenvalues};
use dexter_sim::model::planar::stats::classify;
use dexter_sim::model::planar::PlanarParams;

use common::dexter;
use serde_json::Value;
use std::path::PathBuf;
use std::process::Output;

const G: f64 = 9.81;
const RHO: f64 = 0.094_28;
const L: f64 = 0.133_333_333_333;

fn scene(name: &str) -> String {
    common::scene(&format!("planar-{name}"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dexter-planar-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn json_of(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "status {:?}, stderr: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is one JSON object")
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("`{key}` missing or not a number in {v}"))
}

#[test]
fn analyze_lossless_matches_eq11_in_all_three_regimes_and_carries_parameters() {
    // lossless scene: dropped from 0.25 m, eta* = G 0.25, y*^2 = 2 G (0.25 - l) (eq. 8)
    let y = -(2.0 * G * (0.25 - L)).sqrt();
    let kc = kappa_crit(G, RHO, L, y, 1.0);
    for (kappa, regime) in [
        (0.8, "below 1"),
        (0.5 * (1.0 + kc), "between 1 and kappa_crit"),
        (kc + 0.2, "above kappa_crit"),
    ] {
        let out = dexter(&[
            "analyze",
            &scene("lossless"),
            "--json",
            "--set",
            &format!("planar.kappa={kappa:.17e}"),
        ]);
        let v = json_of(&out);
        let p = &v["params"];
        assert!((num(p, "rho_m") - RHO).abs() < 1e-15);
        assert!((num(p, "l_m") - L).abs() < 1e-15);
        assert!((num(p, "impact_velocity_mps") - y).abs() < 1e-12);
        assert!((num(p, "kappa") - kappa).abs() < 1e-15);
        assert_eq!(num(p, "kappa_e_s2pm2"), 0.0);
        assert_eq!(num(p, "restitution"), 1.0);
        assert_eq!(num(p, "gravity_mps2"), G);
        let eig: Vec<(f64, f64)> = v["eigenvalues"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| {
                let pair = e.as_array().expect("eigenvalue is an [re, im] pair");
                assert_eq!(pair.len(), 2);
                (pair[0].as_f64().unwrap(), pair[1].as_f64().unwrap())
            })
            .collect();
        assert_eq!(eig.len(), 4);
        for w in tilt_eigenvalues(kappa, G, RHO, L, y) {
            let d = eig
                .iter()
                .map(|e| (e.0 - w.0).hypot(e.1 - w.1))
                .fold(f64::INFINITY, f64::min);
            assert!(d < 1e-6, "{regime}: {w:?} vs {eig:?} ({d:e})");
        }
        let verdict = v["verdict"].as_str().unwrap();
        match regime {
            "between 1 and kappa_crit" => assert_eq!(verdict, "marginal"),
            _ => assert_eq!(verdict, "unstable"),
        }
        assert!((num(&v["closed_form"], "kappa_crit_eq16") - kc).abs() < 1e-12);
        // the human report shows the same numbers beside the closed forms
        let text = dexter(&[
            "analyze",
            &scene("lossless"),
            "--set",
            &format!("planar.kappa={kappa:.17e}"),
        ]);
        assert!(text.status.success());
        let t = String::from_utf8_lossy(&text.stdout);
        assert!(t.contains("eq. 11") && t.contains("eq. 16") && t.contains("eq. 26"));
        assert!(t.contains("verdict") && t.contains("error estimate"));
    }
}

fn run_json(name: &str, extra: &[&str]) -> Value {
    let s = scene(name);
    let mut args = vec!["run", s.as_str(), "--json"];
    args.extend_from_slice(extra);
    json_of(&dexter(&args))
}

#[test]
fn triangle_runs_stay_upright_near_the_target_energy() {
    // docs/planar.md: late mean eta within 1 % of eta* without noise, 3 % with 10 ms noise
    for (name, tol) in [("triangle", 0.01), ("triangle-noise", 0.03)] {
        let v = run_json(name, &[]);
        assert_eq!(v["end"], "completed", "{name}");
        assert_eq!(v["stayed_up"], true, "{name}");
        assert_eq!(num(&v, "impacts"), 300.0, "{name}");
        let eta_star = num(&v, "target_energy_jpkg");
        assert!((eta_star - G * 0.25).abs() < 1e-12);
        let mean = num(&v, "late_mean_energy_jpkg");
        assert!(
            (mean - eta_star).abs() < tol * eta_star,
            "{name}: {mean} vs {eta_star}"
        );
        assert!(num(&v, "max_abs_theta_rad") < 0.45, "{name}");
        assert!(num(&v, "mean_theta_rad").abs() < 0.05, "{name}");
    }
    // --impacts overrides the scene
    let v = run_json("triangle", &["--impacts", "40"]);
    assert_eq!(num(&v, "impacts"), 40.0);
}

#[test]
fn friction_scene_loses_the_triangle() {
    // sec. 2.2.2: with Coulomb friction the tilt law does not keep the body up
    let v = run_json("friction", &[]);
    assert_eq!(v["stayed_up"], false);
    let end = v["end"].as_str().unwrap();
    assert!(matches!(end, "tipped_over" | "no_separation"), "{end}");
    assert!(num(&v, "impacts") < 20.0);
    // the human summary says why and when
    let out = dexter(&["run", &scene("friction")]);
    assert!(out.status.success());
    let t = String::from_utf8_lossy(&out.stdout);
    assert!(
        t.contains("ended after") && t.contains("no separation"),
        "{t}"
    );
}

#[test]
fn run_trace_and_plots_are_written() {
    let trace = tmp("triangle-trace.csv");
    let dir = tmp("plots");
    let out = dexter(&[
        "run",
        &scene("triangle"),
        "--impacts",
        "60",
        "--trace",
        trace.to_str().unwrap(),
        "--plot",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let csv = std::fs::read_to_string(&trace).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header[0], "index");
    assert!(header.contains(&"theta_rad") && header.contains(&"energy_jpkg"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 60);
    assert!(rows.iter().all(|r| r.len() == header.len()));
    // theta at the first impact is theta0 = 0.3 to 17 digits; eta at the first is G * 0.2
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let theta0: f64 = rows[0][col("theta_rad")].parse().unwrap();
    assert_eq!(theta0, 0.3);
    let eta0: f64 = rows[0][col("energy_jpkg")].parse().unwrap();
    assert!((eta0 - G * 0.2).abs() < 1e-12);
    for stem in ["theta", "velocity", "path", "energy"] {
        for ext in ["svg", "png"] {
            let f = dir.join(format!("planar-triangle-{stem}.{ext}"));
            assert!(
                std::fs::metadata(&f)
                    .map(|m| m.len() > 1000)
                    .unwrap_or(false),
                "{}",
                f.display()
            );
        }
    }
}

#[test]
fn small_sweep_matches_the_library_classify() {
    let csv = tmp("sweep.csv");
    let dir = tmp("sweep-plot");
    let (kappas, thetas) = ([0.8, 1.1, 1.4], [0.1, 0.3]);
    let out = dexter(&[
        "sweep",
        &scene("triangle"),
        "--range",
        "planar.kappa=0.8:1.4:3",
        "--range2",
        "planar.initial_theta_rad=0.1:0.3:2",
        "--set",
        "planar.impacts=120",
        "--csv",
        csv.to_str().unwrap(),
        "--plot",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        &header[..3],
        &["planar.kappa", "planar.initial_theta_rad", "class"]
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 6);
    let base =
        PlanarParams::from_toml_str(&std::fs::read_to_string(scene("triangle")).unwrap()).unwrap();
    let mut i = 0;
    for &theta in &thetas {
        for &kappa in &kappas {
            let r = &rows[i];
            i += 1;
            // the CSV's values (17 digits: exact) are the cells' parameters
            let (kappa_cell, theta_cell): (f64, f64) =
                (r[0].parse().unwrap(), r[1].parse().unwrap());
            assert!((kappa_cell - kappa).abs() < 1e-12);
            assert!((theta_cell - theta).abs() < 1e-12);
            let (kappa, theta) = (kappa_cell, theta_cell);
            let p = PlanarParams {
                kappa,
                initial_theta_rad: theta,
                impacts: 120,
                ..base.clone()
            };
            let m = p.build().unwrap();
            let run = m.run(p.start().unwrap(), p.impacts, p.seed);
            let want = serde_json::to_value(classify(&m, &run)).unwrap();
            assert_eq!(
                r[2],
                want.as_str().unwrap(),
                "kappa {kappa}, theta0 {theta}"
            );
            assert_eq!(r[3].parse::<usize>().unwrap(), run.impacts.len());
        }
    }
    // the regimes of sec. 2.3: kappa = 1.1 at theta0 = 0.1 converges
    assert_eq!(rows[1][2], "converges");
    for ext in ["svg", "png"] {
        assert!(dir
            .join(format!("planar-triangle-stability.{ext}"))
            .is_file());
    }
    // a one-range sweep prints the classes along one axis (CSV on stdout without --csv)
    let out = dexter(&[
        "sweep",
        &scene("triangle"),
        "--range",
        "planar.kappa=0.9:1.2:4",
        "--set",
        "planar.impacts=60",
    ]);
    assert!(out.status.success());
    let t = String::from_utf8_lossy(&out.stdout);
    assert!(t.starts_with("planar.kappa,class,"), "{t}");
    assert_eq!(t.lines().count(), 5);
}

fn assert_named_error(args: &[&str], key: &str) {
    let out = dexter(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(err.contains(key), "{args:?}: `{err}` should name {key}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_values_and_unknown_keys_exit_2_naming_the_key() {
    let s = scene("triangle");
    for cmd in ["run", "analyze"] {
        assert_named_error(
            &[cmd, &s, "--set", "planar.restitution=1.5"],
            "planar.restitution",
        );
        assert_named_error(&[cmd, &s, "--set", "planar.kapa=1.1"], "planar.kapa");
        assert_named_error(&[cmd, &s, "--set", "planar.kappa=fast"], "planar.kappa");
        assert_named_error(&[cmd, &s, "--set", "planar.kappa=-1"], "planar.kappa");
        assert_named_error(
            &[cmd, &s, "--set", "planar.initial_height_m=0.05"],
            "planar.initial_height_m",
        );
    }
    assert_named_error(&["run", &s, "--impacts", "0"], "planar.impacts");
    assert_named_error(
        &["sweep", &s, "--range", "planar.kapa=1:2:3"],
        "planar.kapa",
    );
    assert_named_error(
        &["sweep", &s, "--range", "planar.kappa=1:2:x"],
        "planar.kappa",
    );
    assert_named_error(
        &[
            "sweep",
            &s,
            "--range",
            "planar.kappa=1:2:2",
            "--range2",
            "planar.restitution=0.5:2:2",
        ],
        "planar.restitution",
    );
}
