//! Tests of the plotting module: every plot writes a non-empty SVG with its axis labels and a
//! PNG of the requested size; bad input gives an error, never a panic.
//!
//! Set `DEXTER_KEEP_PLOTS=1` to keep the output directories (their paths are printed) and look
//! at the pictures.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

use dexter_sim::plot::{PlotError, PLOT_SIZE};
use dexter_sim::systems::line::plots::{apex_per_impact, bifurcation, phase_portrait, return_map};
use dexter_sim::systems::line::trace::ImpactRow;

/// A fresh, unique directory under the system temp dir, removed on drop (unless
/// `DEXTER_KEEP_PLOTS` is set). The directory itself is not created: the plot functions must.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> Self {
        static COUNTER: AtomicU32 = AtomicU32::new(0);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or(0);
        let dir = std::env::temp_dir().join(format!(
            "dexter-plot-test-{}-{}-{}-{}",
            name,
            std::process::id(),
            nanos,
            COUNTER.fetch_add(1, Ordering::Relaxed)
        ));
        TempDir(dir)
    }

    fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        if std::env::var_os("DEXTER_KEEP_PLOTS").is_some() {
            eprintln!("plots kept in {}", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// Width and height from a PNG's signature and IHDR chunk.
fn png_size(bytes: &[u8]) -> (u32, u32) {
    assert!(bytes.len() > 24, "PNG too short: {} bytes", bytes.len());
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "not a PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR", "first chunk is not IHDR");
    let w = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let h = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    (w, h)
}

/// Checks the two files written for `stem` and that the SVG holds every one of `labels`.
fn check_outputs(paths: &[PathBuf], dir: &Path, stem: &str, labels: &[&str]) {
    let svg_path = dir.join(format!("{stem}.svg"));
    let png_path = dir.join(format!("{stem}.png"));
    assert_eq!(paths, [svg_path.clone(), png_path.clone()]);

    let svg = std::fs::read_to_string(&svg_path).expect("read SVG");
    assert!(!svg.is_empty(), "empty SVG");
    assert!(svg.contains("<svg"), "not an SVG");
    for label in labels {
        assert!(svg.contains(label), "SVG lacks the text {label:?}");
    }

    let png = std::fs::read(&png_path).expect("read PNG");
    assert!(!png.is_empty(), "empty PNG");
    assert_eq!(png_size(&png), PLOT_SIZE);
}

fn row(index: u64, apex: f64) -> ImpactRow {
    ImpactRow {
        index,
        time_s: index as f64 * 0.9,
        apex_height_m: apex,
        ..ImpactRow::default()
    }
}

/// Apex heights converging geometrically (and oscillating) onto the target.
fn converging_rows(target: f64, n: u64) -> Vec<ImpactRow> {
    (0..n)
        .map(|i| row(i, target + 0.4 * (-0.7f64).powi(i as i32)))
        .collect()
}

#[test]
fn apex_per_impact_writes_svg_and_png() {
    let tmp = TempDir::new("apex");
    let mut rows = converging_rows(1.0, 40);
    rows[5].apex_height_m = f64::NAN; // skipped, not fatal
    rows[6].apex_height_m = f64::INFINITY;
    let paths = apex_per_impact(&rows, 1.0, tmp.path(), "apex").expect("plot");
    check_outputs(
        &paths,
        tmp.path(),
        "apex",
        &[
            "impact index n",
            "apex height (m)",
            "Apex height per impact",
            "target 1 m",
        ],
    );
}

#[test]
fn apex_per_impact_without_finite_target_still_plots() {
    let tmp = TempDir::new("apex-nan-target");
    let rows = converging_rows(0.5, 10);
    let paths = apex_per_impact(&rows, f64::NAN, tmp.path(), "apex").expect("plot");
    check_outputs(&paths, tmp.path(), "apex", &["apex height (m)"]);
}

#[test]
fn apex_per_impact_rejects_empty_and_nan_input() {
    let tmp = TempDir::new("apex-bad");
    let err = apex_per_impact(&[], 1.0, tmp.path(), "apex").unwrap_err();
    assert!(matches!(err, PlotError::EmptyInput { .. }), "{err:?}");
    let rows: Vec<_> = (0..5).map(|i| row(i, f64::NAN)).collect();
    let err = apex_per_impact(&rows, 1.0, tmp.path(), "apex").unwrap_err();
    assert!(
        matches!(err, PlotError::NoFiniteData { points: 5, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("finite"), "{err}");
    assert!(!tmp.path().join("apex.svg").exists());
}

/// A bouncing ball: flights b(t) = v t - g t^2 / 2 from b = 0, each with 0.8 of the previous
/// take-off speed, sampled every millisecond.
fn bouncing_ball() -> Vec<(f64, f64)> {
    let g = 9.81;
    let mut v0 = 4.0;
    let mut samples = Vec::new();
    for _ in 0..5 {
        let flight = 2.0 * v0 / g;
        let n = (flight / 1e-3) as usize;
        for k in 0..=n {
            let t = k as f64 * 1e-3;
            samples.push((v0 * t - 0.5 * g * t * t, v0 - g * t));
        }
        v0 *= 0.8;
    }
    samples
}

#[test]
fn phase_portrait_writes_svg_and_png() {
    let tmp = TempDir::new("phase");
    let mut samples = bouncing_ball();
    samples.insert(100, (f64::NAN, 1.0)); // breaks the line, not fatal
    samples.insert(200, (0.1, f64::NEG_INFINITY));
    let paths = phase_portrait(&samples, tmp.path(), "phase").expect("plot");
    check_outputs(
        &paths,
        tmp.path(),
        "phase",
        &[
            "ball height b (m)",
            "ball velocity b′ (m/s)",
            "phase portrait",
        ],
    );
}

#[test]
fn phase_portrait_rejects_empty_and_nan_input() {
    let tmp = TempDir::new("phase-bad");
    let err = phase_portrait(&[], tmp.path(), "phase").unwrap_err();
    assert!(matches!(err, PlotError::EmptyInput { .. }), "{err:?}");
    let samples = [(f64::NAN, 0.0), (1.0, f64::INFINITY), (f64::NAN, f64::NAN)];
    let err = phase_portrait(&samples, tmp.path(), "phase").unwrap_err();
    assert!(matches!(err, PlotError::NoFiniteData { .. }), "{err:?}");
}

/// Successive impact speeds from a logistic-like map in the chaotic regime, scaled to 2..4 m/s.
fn logistic_speeds(n: usize) -> Vec<f64> {
    let mut x: f64 = 0.2;
    (0..n)
        .map(|_| {
            x = 3.9 * x * (1.0 - x);
            2.0 + 2.0 * x
        })
        .collect()
}

#[test]
fn return_map_writes_svg_and_png() {
    let tmp = TempDir::new("return");
    let mut speeds = logistic_speeds(400);
    speeds[10] = f64::NAN; // drops the two pairs it is in
    let paths = return_map(&speeds, tmp.path(), "return").expect("plot");
    check_outputs(
        &paths,
        tmp.path(),
        "return",
        &[
            "impact speed v(n) (m/s)",
            "next impact speed v(n+1) (m/s)",
            "Return map",
        ],
    );
}

#[test]
fn return_map_rejects_empty_short_and_nan_input() {
    let tmp = TempDir::new("return-bad");
    let err = return_map(&[], tmp.path(), "r").unwrap_err();
    assert!(matches!(err, PlotError::EmptyInput { .. }), "{err:?}");
    let err = return_map(&[3.0], tmp.path(), "r").unwrap_err();
    assert!(matches!(err, PlotError::EmptyInput { .. }), "{err:?}");
    // Finite speeds, but never two finite ones in a row.
    let err = return_map(&[3.0, f64::NAN, 2.0, f64::NAN], tmp.path(), "r").unwrap_err();
    assert!(matches!(err, PlotError::NoFiniteData { .. }), "{err:?}");
}

/// A period-doubling cascade: late iterates of the logistic map x -> r x (1 - x) for r from 2.8
/// to 4, read as apex heights 0.5 + 0.5 x m.
fn cascade() -> Vec<(f64, f64)> {
    let mut points = Vec::new();
    for i in 0..400 {
        let r = 2.8 + 1.2 * f64::from(i) / 399.0;
        let mut x = 0.5;
        for _ in 0..300 {
            x = r * x * (1.0 - x);
        }
        for _ in 0..60 {
            x = r * x * (1.0 - x);
            points.push((r, 0.5 + 0.5 * x));
        }
    }
    points
}

#[test]
fn bifurcation_writes_svg_and_png() {
    let tmp = TempDir::new("bif");
    let mut points = cascade();
    points.push((f64::NAN, 1.0));
    points.push((3.0, f64::INFINITY));
    let paths = bifurcation(
        &points,
        "paddle gain r (dimensionless)",
        tmp.path(),
        "bifurcation",
    )
    .expect("plot");
    check_outputs(
        &paths,
        tmp.path(),
        "bifurcation",
        &["paddle gain r (dimensionless)", "late apex height (m)"],
    );
}

#[test]
fn bifurcation_rejects_empty_and_nan_input() {
    let tmp = TempDir::new("bif-bad");
    let err = bifurcation(&[], "a (m)", tmp.path(), "b").unwrap_err();
    assert!(matches!(err, PlotError::EmptyInput { .. }), "{err:?}");
    let err = bifurcation(
        &[(f64::NAN, 1.0), (2.0, f64::NAN)],
        "a (m)",
        tmp.path(),
        "b",
    )
    .unwrap_err();
    assert!(
        matches!(err, PlotError::NoFiniteData { points: 2, .. }),
        "{err:?}"
    );
}

#[test]
fn degenerate_ranges_are_widened() {
    let tmp = TempDir::new("degenerate");
    // One point, all points equal, all zero: each still draws.
    apex_per_impact(&[row(3, 0.8)], 0.8, tmp.path(), "apex1").expect("one row");
    phase_portrait(&[(0.0, 0.0); 10], tmp.path(), "phase0").expect("all zero");
    phase_portrait(&[(0.2, -1.5)], tmp.path(), "phase1").expect("one sample");
    return_map(&[2.5; 20], tmp.path(), "fixed").expect("fixed point");
    let paths = bifurcation(&[(1.0, 0.3); 50], "", tmp.path(), "bif1").expect("one value");
    check_outputs(
        &paths,
        tmp.path(),
        "bif1",
        &["parameter", "late apex height (m)"],
    );
}

#[test]
fn bad_stem_and_unwritable_dir_are_errors() {
    let tmp = TempDir::new("io");
    let speeds = logistic_speeds(10);
    for stem in ["", "a/b", ".."] {
        let err = return_map(&speeds, tmp.path(), stem).unwrap_err();
        assert!(matches!(err, PlotError::InvalidArgument { .. }), "{err:?}");
    }
    // A file where the directory should be.
    std::fs::create_dir_all(tmp.path()).unwrap();
    let file = tmp.path().join("not-a-dir");
    std::fs::write(&file, b"x").unwrap();
    let err = return_map(&speeds, &file, "r").unwrap_err();
    match &err {
        PlotError::Io { path, .. } => assert_eq!(path, &file),
        other => panic!("expected an I/O error, got {other:?}"),
    }
    assert!(err.to_string().contains("not-a-dir"), "{err}");
}

#[test]
fn huge_ranges_do_not_panic() {
    let tmp = TempDir::new("huge");
    let result = bifurcation(
        &[(-f64::MAX, 0.0), (f64::MAX, 1.0)],
        "a (m)",
        tmp.path(),
        "h",
    );
    assert!(
        matches!(result, Err(PlotError::InvalidArgument { .. })),
        "{result:?}"
    );
    // Large but drawable values work.
    bifurcation(&[(-1e200, 0.0), (1e200, 1.0)], "a (m)", tmp.path(), "h2").expect("plot");
}

#[test]
fn series_plot_draws_lines_and_dots_with_labels() {
    use dexter_sim::plot::{series, Series, Style};
    let dir = std::env::temp_dir().join(format!("dexter-plot-series-{}", std::process::id()));
    let circle: Vec<(f64, f64)> = (0..200)
        .map(|i| {
            let t = i as f64 * 0.05;
            (t.cos(), t.sin())
        })
        .collect();
    let dots = vec![(0.0, 0.0), (0.5, 0.5), (f64::NAN, 1.0)];
    let files = series(
        "Projection",
        "theta (rad)",
        "theta rate (rad/s)",
        &[
            Series {
                label: "orbit".into(),
                points: circle,
                style: Style::Line,
            },
            Series {
                label: "fixed points".into(),
                points: dots,
                style: Style::Dots,
            },
        ],
        &dir,
        "series",
    )
    .unwrap();
    let svg = std::fs::read_to_string(&files[0]).unwrap();
    assert!(svg.contains("theta (rad)") && svg.contains("fixed points"));
    let png = std::fs::read(&files[1]).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    let empty = series("t", "x", "y", &[], &dir, "empty");
    assert!(matches!(
        empty,
        Err(dexter_sim::plot::PlotError::EmptyInput { .. })
    ));
    std::fs::remove_dir_all(&dir).ok();
}
