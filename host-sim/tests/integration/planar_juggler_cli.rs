//! The planar juggler through the `dexter` binary (`[planar_juggler]` scenes), against
//! closed forms computed here: on the line b_x = b_x*, b_x' = 0 both laws reduce to the
//! line juggler, so the apex heights follow eq. 8's map of impact speeds,
//! v+ = (alpha + (1 + alpha)(kappa0 + kappa1 (eta* - v^2/2))) v, and every run settles on
//! its fixed point eta_fp = eta* - (1 - alpha - (1 + alpha) kappa0)/((1 + alpha) kappa1).

use crate::common;

use common::{dexter, ok, scene, scratch};
use serde_json::Value;
use std::path::PathBuf;

const G: f64 = 9.81;
const ALPHA: f64 = 0.7;
const H_STAR: f64 = 0.5;
const X_STAR: f64 = 1.0;

fn tmp(name: &str) -> PathBuf {
    scratch(&format!("pj-{name}"))
}

fn json(args: &[&str]) -> Value {
    let mut a = args.to_vec();
    a.push("--json");
    common::json(&a)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// The fixed point of eq. 8 in energy, J/kg.
fn eta_fp(kappa0: f64, kappa1: f64) -> f64 {
    G * H_STAR - (1.0 - ALPHA - (1.0 + ALPHA) * kappa0) / ((1.0 + ALPHA) * kappa1)
}

/// The apex heights after each bat from an apex at `z0` on the line b_x = b_x*: eq. 8.
fn eq8_apexes(z0: f64, kappa0: f64, kappa1: f64, n: usize) -> Vec<f64> {
    let mut v = (2.0 * G * z0).sqrt();
    (0..n)
        .map(|_| {
            let k = kappa0 + kappa1 * (G * H_STAR - 0.5 * v * v);
            v *= ALPHA + (1.0 + ALPHA) * k;
            v * v / (2.0 * G)
        })
        .collect()
}

#[test]
fn on_the_line_bx_star_both_laws_follow_eq8() {
    let (k0, k1) = (0.2, 0.03);
    let dir = tmp("eq8");
    for law in ["planar-juggler", "planar-juggler-modified"] {
        let trace = dir.join(format!("{law}.csv"));
        let sets = [
            "planar_juggler.initial_x_m=1.0",
            "planar_juggler.initial_x_dot_mps=0.0",
            "planar_juggler.initial_z_m=0.9",
            "planar_juggler.kappa0=0.2",
            "planar_juggler.kappa1_s2pm2=0.03",
        ];
        let path = scene(law);
        let mut args = vec!["run", &path as &str];
        for s in &sets {
            args.extend(["--set", s]);
        }
        let trace_s = trace.display().to_string();
        args.extend(["--impacts", "60", "--trace", &trace_s]);
        let v = json(&args);
        let text = std::fs::read_to_string(&trace).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        let want = eq8_apexes(0.9, k0, k1, 60);
        assert_eq!(rows.len(), 60, "{law}");
        for (n, (r, w)) in rows.iter().zip(&want).enumerate() {
            // columns: index, ..., apex_x_m (10), apex_z_m (11)
            assert!(
                (r[10] - X_STAR).abs() < 1e-12,
                "{law} bat {n}: apex x {}",
                r[10]
            );
            assert!(
                (r[11] - w).abs() < 1e-9 * w,
                "{law} bat {n}: {} vs eq. 8 {w}",
                r[11]
            );
        }
        // the fixed point is eta_fp, not eta*, with this kappa0, and the run settles on it
        let e = eta_fp(k0, k1);
        assert!((f(&v["fixed_point_energy_jpkg"]) - e).abs() < 1e-12 * e);
        assert!(
            (f(&v["final_energy_jpkg"]) - e).abs() < 1e-9 * e,
            "{law}: {v}"
        );
        let slope = 1.0 - (1.0 + ALPHA) * k1 * 2.0 * e;
        assert!((f(&v["energy_slope"]) - slope).abs() < 1e-12);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_shipped_scenes_settle_on_the_target_apex() {
    let eta_star = G * H_STAR;
    for law in ["planar-juggler", "planar-juggler-modified"] {
        let v = json(&["run", &scene(law)]);
        assert_eq!(v["end"], "completed", "{law}: {v}");
        assert_eq!(v["impacts"], 80);
        // matched kappa0: the fixed point is eta* = gamma h*, at the apex (b_x*, h*)
        assert!((f(&v["fixed_point_energy_jpkg"]) - eta_star).abs() < 1e-12);
        let apex = &v["final_apex_m"];
        assert!((f(&apex[0]) - X_STAR).abs() < 1e-4, "{law}: {apex}");
        assert!((f(&apex[1]) - H_STAR).abs() < 1e-6, "{law}: {apex}");
        assert!((f(&v["final_energy_jpkg"]) - eta_star).abs() < 1e-6 * eta_star);
        // it started far from there
        let first = &v["first_apex_m"];
        assert!((f(&first[0]) - X_STAR).abs() > 0.1, "{law}: {first}");
        assert!(
            v["converged_after_impacts"].as_u64().unwrap() < 40,
            "{law}: {v}"
        );
        let text = String::from_utf8(ok(&["run", &scene(law)]).stdout).unwrap();
        assert!(
            text.contains("80 of 80 bats") && text.contains("eq. 8"),
            "{text}"
        );
    }
}

#[test]
fn trace_and_plots_are_written() {
    let dir = tmp("plots");
    let trace = dir.join("sub").join("bats.csv");
    let (t, d) = (trace.display().to_string(), dir.display().to_string());
    ok(&[
        "run",
        &scene("planar-juggler"),
        "--impacts",
        "30",
        "--trace",
        &t,
        "--plot",
        &d,
    ]);
    let text = std::fs::read_to_string(&trace).unwrap();
    assert!(text.starts_with("index,time_s,x_m,z_m,"), "{text}");
    assert_eq!(text.lines().count(), 31);
    for stem in ["apex", "energy", "energy-map"] {
        for ext in ["svg", "png"] {
            let p = dir.join(format!("planar-juggler-{stem}.{ext}"));
            assert!(p.metadata().unwrap().len() > 1000, "{}", p.display());
        }
    }
    // the apex plot draws every bat: 30 apexes, the first, the target and the fixed point,
    // and a legend marker for each of those four series
    let svg = std::fs::read_to_string(dir.join("planar-juggler-apex.svg")).unwrap();
    assert_eq!(svg.matches("<circle").count(), 30 + 3 + 4, "{svg}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_values_exit_2_naming_the_key() {
    let s = scene("planar-juggler");
    for (set, key) in [
        ("planar_juggler.bogus=1", "planar_juggler.bogus"),
        (
            "planar_juggler.restitution=1.5",
            "planar_juggler.restitution",
        ),
        (
            "planar_juggler.kappa1_s2pm2=-1",
            "planar_juggler.kappa1_s2pm2",
        ),
        ("planar_juggler.impacts=0", "planar_juggler.impacts"),
        (
            "planar_juggler.initial_x_m=-1",
            "planar_juggler.initial_x_m",
        ),
        ("planar_juggler.law=psychic", "planar_juggler.law"),
    ] {
        let out = dexter(&["run", &s, "--set", set]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{set}: {err}");
        assert!(err.contains(key), "{set}: {err}");
    }
    for extra in [&["--duration", "1"][..], &["--hil"][..]] {
        let mut args = vec!["run", &s as &str];
        args.extend(extra);
        let out = dexter(&args);
        assert_eq!(out.status.code(), Some(2), "{extra:?}");
    }
}
