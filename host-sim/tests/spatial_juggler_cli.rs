//! The spatial juggler through the `dexter` binary (`[spatial_juggler]` scenes), against
//! closed forms computed here: over the set point, at rest at its apex, the ball's apex
//! heights follow eq. 8's map (the line juggler); the linearization's lateral and vertical
//! eigenvalues are the double integrator's and eq. 8's slope (docs/spatial.md).

mod common;

use common::{dexter, ok, scene, scratch};
use serde_json::Value;

const G: f64 = 9.81;
const ALPHA: f64 = 0.7;
const H_STAR: f64 = 0.5;
const LAWS: [&str; 2] = ["spatial-juggler", "spatial-juggler-modified"];

fn json(args: &[&str]) -> Value {
    let mut a = args.to_vec();
    a.push("--json");
    common::json(&a)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// Issue 28: from an apex 10 cm off the set point horizontally and 20 % high, the
/// horizontal apex error is below 1 mm and the height error below 0.1 % within 30 impacts.
#[test]
fn both_laws_converge_from_ten_centimetres_and_twenty_percent_off() {
    for law in LAWS {
        let s = json(&["run", &scene(law), "--impacts", "30"]);
        assert_eq!(s["end"], "completed", "{law}: {s}");
        let start = &s["first_apex_m"];
        assert!(f(&s["horizontal_apex_error_m"]) < 1e-3, "{law}: {s}");
        assert!(f(&s["apex_height_rel_error"]).abs() < 1e-3, "{law}: {s}");
        assert!(start.is_array(), "{law}");
    }
}

/// Dropped over the set point, the ball stays on the vertical through it and its apexes
/// follow eq. 8 (computed here), for both laws.
#[test]
fn over_the_set_point_the_apexes_follow_eq8() {
    let (k0, k1) = (0.2, 0.03);
    let dir = scratch("sj-eq8");
    for law in LAWS {
        let trace = dir.join(format!("{law}.csv"));
        let t = trace.display().to_string();
        let sets = [
            "spatial_juggler.initial_position_m=[1.0, 0.0, 0.9]",
            "spatial_juggler.kappa0=0.2",
            "spatial_juggler.kappa1_s2pm2=0.03",
        ];
        let file = scene(law);
        let mut args = vec!["run", &file as &str, "--impacts", "20", "--trace", &t];
        for s in &sets {
            args.extend(["--set", s]);
        }
        ok(&args);
        let text = std::fs::read_to_string(&trace).unwrap();
        let mut v = (2.0 * G * 0.9f64).sqrt();
        for row in text.lines().skip(1) {
            let cols: Vec<f64> = row.split(',').map(|c| c.parse().unwrap()).collect();
            let k = k0 + k1 * (G * H_STAR - 0.5 * v * v);
            v *= ALPHA + (1.0 + ALPHA) * k;
            let want = v * v / (2.0 * G);
            let (x, y, z) = (cols[17], cols[18], cols[19]);
            assert!(
                (z - want).abs() < 1e-9 * want,
                "{law}: apex {z} against eq. 8's {want}"
            );
            assert!(
                (x - 1.0).abs() < 1e-9 && y.abs() < 1e-12,
                "{law}: ({x}, {y})"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `dexter analyze`: the lateral pair and the vertical eigenvalue by hand, and the decay
/// measured in simulation within 1 % of the linearization's spectral radius.
#[test]
fn analyze_matches_the_closed_forms_and_the_measured_decay() {
    let v = (2.0 * G * H_STAR).sqrt();
    let t_a = v / G;
    // defaults: kappa21 = -1/(4 v*), kappa20 = -1/(4 v* T): c1 = -1/2, c0 T = -1/2
    let (c0, c1) = (-0.25 / t_a, -0.5);
    for (law, (tr, det)) in [
        ("spatial-juggler", (2.0 + c0 * 2.0 * t_a + c1, 1.0 + c1)),
        (
            "spatial-juggler-modified",
            (2.0 + t_a * c0 + c1, 1.0 + c1 - t_a * c0),
        ),
    ] {
        let a = json(&["analyze", &scene(law)]);
        let eig: Vec<(f64, f64)> = a["eigenvalues"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| (f(&e["re"]), f(&e["im"])))
            .collect();
        let has = |re: f64, im: f64| {
            eig.iter()
                .any(|e| (e.0 - re).abs() + (e.1 - im).abs() < 1e-6)
        };
        let im = (det - 0.25 * tr * tr).sqrt();
        assert!(
            has(0.5 * tr, im) && has(0.5 * tr, -im),
            "{law}: lateral {tr} {det}: {eig:?}"
        );
        assert!(has(0.5, 0.0), "{law}: vertical 1/2: {eig:?}");
        assert!(f(&a["spectral_radius_rel_diff"]) < 0.01, "{law}: {a}");
        assert_eq!(a["verdict"], "asymptotically_stable", "{law}");
    }
    // a flipped lateral gain: unstable
    let a = json(&[
        "analyze",
        &scene("spatial-juggler"),
        "--set",
        "spatial_juggler.kappa21_radspm=0.08",
    ]);
    assert_eq!(a["verdict"], "unstable", "{a}");
}

#[test]
fn trace_and_plots_are_written() {
    let dir = scratch("sj-plots");
    let trace = dir.join("sub").join("bats.csv");
    let (t, d) = (trace.display().to_string(), dir.display().to_string());
    ok(&[
        "run",
        &scene("spatial-juggler"),
        "--impacts",
        "12",
        "--trace",
        &t,
        "--plot",
        &d,
    ]);
    let text = std::fs::read_to_string(&trace).unwrap();
    assert!(text.starts_with("index,time_s,x_m,y_m,z_m,"), "{text}");
    assert_eq!(text.lines().count(), 13);
    for stem in ["apex-plane", "apex-height", "strikes-side", "strikes-top"] {
        for ext in ["svg", "png"] {
            let p = dir.join(format!("spatial-juggler-{stem}.{ext}"));
            assert!(p.metadata().unwrap().len() > 1000, "{}", p.display());
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_values_exit_2_naming_the_key() {
    let s = scene("spatial-juggler");
    for (set, key) in [
        ("spatial_juggler.bogus=1", "spatial_juggler.bogus"),
        (
            "spatial_juggler.restitution=1.5",
            "spatial_juggler.restitution",
        ),
        (
            "spatial_juggler.kappa1_s2pm2=-1",
            "spatial_juggler.kappa1_s2pm2",
        ),
        (
            "spatial_juggler.kappa20_radpm=nan",
            "spatial_juggler.kappa20_radpm",
        ),
        ("spatial_juggler.impacts=0", "spatial_juggler.impacts"),
        (
            "spatial_juggler.target_radius_m=0",
            "spatial_juggler.target_radius_m",
        ),
        (
            "spatial_juggler.initial_position_m=[0.0, 0.0, 1.0]",
            "spatial_juggler.initial_position_m",
        ),
        ("spatial_juggler.law=psychic", "spatial_juggler.law"),
    ] {
        let out = dexter(&["run", &s, "--set", set]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{set}: {err}");
        assert!(err.contains(key), "{set}: {err}");
    }
    for extra in [&["--duration", "1"][..], &["--hil"][..]] {
        let mut args = vec!["run", &s as &str];
        args.extend(extra);
        assert_eq!(dexter(&args).status.code(), Some(2), "{extra:?}");
    }
}
