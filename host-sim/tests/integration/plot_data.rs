//! The plots draw the data they should: each SVG's points are read back, mapped through
//! its axes (fitted to the tick labels) and compared with the run's trace and summary, and
//! closed-form curves with the closed form computed here. A plot that draws no data, the
//! wrong series or a shifted one fails.

use crate::common;

use common::svg::Svg;
use common::{csv_rows, ok, scene, scratch};
use std::path::Path;

/// Pixels a drawn point may be off: SVG coordinates are whole pixels (0.5 each way), and
/// the axes are fitted to rounded tick positions.
const TOL_PX: f64 = 1.5;

fn run_with_plots(name: &str, extra: &[&str], dir: &Path) -> std::path::PathBuf {
    let trace = dir.join("trace.csv");
    let s = scene(name);
    let mut args = vec![
        "run",
        &s,
        "--plot",
        dir.to_str().unwrap(),
        "--trace",
        trace.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    ok(&args);
    trace
}

/// `want` (data) against `got` (data), point by point, within `TOL_PX` pixels.
fn assert_same_line(svg: &Svg, what: &str, got: &[(f64, f64)], want: &[(f64, f64)]) {
    assert_eq!(
        got.len(),
        want.len(),
        "{what}: {} points drawn, {} in the data",
        got.len(),
        want.len()
    );
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        let (gp, wp) = (svg.pixel(*g), svg.pixel(*w));
        let d = (gp.0 - wp.0).hypot(gp.1 - wp.1);
        assert!(
            d <= TOL_PX,
            "{what}, point {i}: drawn {g:?}, data {w:?} ({d:.2} px apart)"
        );
    }
}

/// The apex plot: its line is (n, apex after impact n) of every impact of the trace, and
/// its dashed target line sits at the target apex.
#[test]
fn the_apex_plot_draws_every_apex_of_the_trace() {
    let dir = scratch("plot-data-apex");
    let trace = run_with_plots("line-juggler-ideal", &["--impacts", "40"], &dir);
    let rows = csv_rows(&trace);
    assert_eq!(rows.len(), 40);
    let want: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r["index"], r["apex_height_m"]))
        .collect();
    let svg = Svg::read(&dir.join("line-juggler-ideal-apex.svg"));
    assert_same_line(&svg, "apex", &svg.line("#0000FF"), &want);
    // the target: dashes at y = 1 m (and the legend's sample)
    let dashes = svg.polylines("#FF0000");
    let at_target = |l: &Vec<(f64, f64)>| {
        l.iter()
            .all(|p| (svg.data(*p).1 - 1.0).abs() <= TOL_PX * svg.y.per_pixel())
    };
    assert!(
        dashes.iter().filter(|l| at_target(l)).count() > 5,
        "the target line is dashed"
    );
    assert!(
        dashes.iter().filter(|l| !at_target(l)).count() <= 1,
        "{dashes:?}"
    );
}

/// The return map: a dot at (v_n, v_{n+1}) for every successive pair of impact speeds
/// of the trace, and the identity line.
#[test]
fn the_return_map_draws_every_successive_pair_of_speeds() {
    let dir = scratch("plot-data-return-map");
    let trace = run_with_plots("line-juggler-ideal", &["--impacts", "30"], &dir);
    let v: Vec<f64> = csv_rows(&trace)
        .iter()
        .map(|r| -r["ball_velocity_before_mps"])
        .collect();
    let pairs: Vec<(f64, f64)> = v.windows(2).map(|w| (w[0], w[1])).collect();
    let svg = Svg::read(&dir.join("line-juggler-ideal-return-map.svg"));
    svg.assert_dots("#FF0000", &pairs, TOL_PX);
    assert_eq!(
        svg.circles("#FF0000").len(),
        pairs.len() + 1,
        "one dot per pair, one legend"
    );
}

/// The planar energy plot: eta per impact of the trace, and eta* from the summary.
#[test]
fn the_planar_energy_plot_draws_eta_per_impact() {
    let dir = scratch("plot-data-planar");
    let trace = run_with_plots("planar-triangle", &["--impacts", "60"], &dir);
    let want: Vec<(f64, f64)> = csv_rows(&trace)
        .iter()
        .map(|r| (r["index"], r["energy_jpkg"]))
        .collect();
    let svg = Svg::read(&dir.join("planar-triangle-energy.svg"));
    // series colours: the palette's first (eta), second (eta*), third (late mean)
    assert_same_line(&svg, "eta", &svg.line("#E6194B"), &want);
    let summary: serde_json::Value = serde_json::from_slice(
        &ok(&[
            "run",
            &scene("planar-triangle"),
            "--impacts",
            "60",
            "--json",
        ])
        .stdout,
    )
    .unwrap();
    let eta_star = summary["target_energy_jpkg"].as_f64().unwrap();
    // eq. 25's target, independently: eta* = G y0 for the drop from 0.25 m
    assert!((eta_star - 9.81 * 0.25).abs() < 1e-12);
    for p in svg.line("#3CB44B") {
        assert!(
            (p.1 - eta_star).abs() <= TOL_PX * svg.y.per_pixel(),
            "eta* drawn at {}",
            p.1
        );
    }
    let late = summary["late_mean_energy_jpkg"].as_f64().unwrap();
    for p in svg.line("#FFE119") {
        assert!(
            (p.1 - late).abs() <= TOL_PX * svg.y.per_pixel(),
            "late mean drawn at {}",
            p.1
        );
    }
}

/// The hopper return map: a dot at (x_n, x_{n+1}) for every successive pair of bottoms of
/// each start, in that start's colour, and eq. 15's curve g(x) = chi_l exp(-alpha x/chi_l
/// ln(chi_l/x)) computed here.
#[test]
fn the_hopper_return_map_draws_the_bottoms_and_eq15() {
    let dir = scratch("plot-data-hopper");
    let trace = run_with_plots("hopper-fig11", &["--impacts", "40"], &dir);
    let rows = csv_rows(&trace);
    let svg = Svg::read(&dir.join("hopper-fig11-return-map.svg"));
    for (trajectory, colour) in [(1.0, "#E6194B"), (2.0, "#3CB44B")] {
        let x: Vec<f64> = rows
            .iter()
            .filter(|r| r["trajectory"] == trajectory)
            .map(|r| r["bottom_height_m"])
            .collect();
        assert_eq!(x.len(), 40);
        let pairs: Vec<(f64, f64)> = x.windows(2).map(|w| (w[0], w[1])).collect();
        svg.assert_dots(colour, &pairs, TOL_PX);
    }
    // Table 1, fig. 11: chi_l = 0.5 m, eta1 = 5.81 m^2/s^2, tau = 41.86 m/s^2, mu' = 0
    let g = |x: f64| 0.5 * (-(41.86 / 5.81) * x * (0.5 / x).ln()).exp();
    // palette slot 3 (the closed form), 4 (the identity)
    for p in svg.line("#F58230") {
        assert!(
            (p.0 - p.1).abs() <= TOL_PX * svg.y.per_pixel(),
            "identity at {p:?}"
        );
    }
    let curve = svg.line("#0082C8");
    assert!(curve.len() > 100, "the closed form is drawn");
    for p in &curve {
        let px = svg.pixel(*p);
        // the nearest point of the exact curve, in pixels
        let d = (0..=2000)
            .map(|i| {
                let x = p.0 + (i as f64 / 1000.0 - 1.0) * 3.0 * svg.x.per_pixel();
                let q = svg.pixel((x, g(x)));
                (q.0 - px.0).hypot(q.1 - px.1)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(d <= TOL_PX, "eq. 15 drawn {d:.2} px off at {p:?}");
    }
}
