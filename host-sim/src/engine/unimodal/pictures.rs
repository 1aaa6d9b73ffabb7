//! The pictures of a certificate: the return map on its invariant
//! interval with the diagonal and a cobweb from a few starts, the Schwarzian along the
//! interval with the ranges interval arithmetic proved, and a family's bifurcation diagram
//! with the located doublings marked. Each is `{dir}/{stem}-*.svg` and `.png`.

use super::cascade::{Doubling, Family};
use super::{schwarzian, Certificate, Map1d};
use crate::plot::{Chart, PlotError};
use std::path::{Path, PathBuf};

/// Samples of a curve along the interval.
const SAMPLES: usize = 400;

/// Cobweb steps drawn per start.
const COBWEB_STEPS: usize = 40;

/// The return map with the diagonal and a cobweb from three starts (a quarter, a half and
/// nine tenths along the interval), in `coordinate` (the axis label, with its unit).
pub fn return_map<M: Map1d>(
    map: &M,
    cert: &Certificate,
    coordinate: &str,
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    let (a, b) = cert.interval;
    let xs: Vec<f64> = (0..=SAMPLES)
        .map(|i| a + (b - a) * i as f64 / SAMPLES as f64)
        .collect();
    let mut chart = Chart::new(
        format!(
            "return map on its invariant interval: {}",
            cert.verdict.code()
        ),
        format!("{coordinate}, n"),
        format!("{coordinate}, n+1"),
    )
    .line("f", xs.iter().map(|&x| (x, map.f(x))).collect())
    .line("diagonal", vec![(a, a), (b, b)]);
    for frac in [0.25, 0.5, 0.9] {
        let mut x = a + frac * (b - a);
        let mut path = vec![(x, a)];
        for _ in 0..COBWEB_STEPS {
            let y = map.f(x);
            if !(y.is_finite() && y >= a - (b - a) && y <= b + (b - a)) {
                break;
            }
            path.push((x, y));
            path.push((y, y));
            x = y;
        }
        chart = chart.line(format!("cobweb from {:.4}", a + frac * (b - a)), path);
    }
    chart.draw(dir, &format!("{stem}-return-map"))
}

/// S f along the interval (clipped to ±`clip`; it is −∞ at a critical point), with the
/// ranges proven positive or undetermined by interval arithmetic drawn on the zero line.
pub fn schwarzian_sign<M: Map1d>(
    map: &M,
    cert: &Certificate,
    coordinate: &str,
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    const CLIP: f64 = 50.0;
    let (a, b) = cert.interval;
    let pts: Vec<(f64, f64)> = (0..=SAMPLES)
        .map(|i| {
            let x = a + (b - a) * i as f64 / SAMPLES as f64;
            (x, schwarzian(&map.at(x)).clamp(-CLIP, CLIP))
        })
        .collect();
    let proven = if cert.schwarzian.negative() {
        "S < 0 proven on the whole interval"
    } else {
        "S < 0 not proven"
    };
    let mut chart = Chart::new(
        format!("Schwarzian derivative (clipped to +-{CLIP}): {proven}"),
        coordinate.to_string(),
        "S f",
    )
    .line("S f", pts)
    .line("0", vec![(a, 0.0), (b, 0.0)]);
    let segs = |v: &[(f64, f64)]| -> Vec<(f64, f64)> {
        v.iter()
            .flat_map(|&(l, r)| [(l, 0.0), (r, 0.0), (f64::NAN, f64::NAN)])
            .collect()
    };
    if !cert.schwarzian.positive.is_empty() {
        chart = chart.line("S > 0 proven", segs(&cert.schwarzian.positive));
    }
    if !cert.schwarzian.undetermined.is_empty() {
        chart = chart.line("undetermined", segs(&cert.schwarzian.undetermined));
    }
    chart.draw(dir, &format!("{stem}-schwarzian"))
}

/// The bifurcation diagram of `fam` over `params` (late orbit of the critical point:
/// `transient` iterations dropped, `keep` kept), with each located doubling marked by a
/// vertical line.
pub fn bifurcation<F: Family>(
    fam: &F,
    params: &[f64],
    doublings: &[Doubling],
    labels: (&str, &str),
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    let (transient, keep) = (2000, 128);
    let mut dots = Vec::with_capacity(params.len() * keep);
    let mut top = 0.0f64;
    for &a in params {
        let mut x = fam.critical(a);
        for _ in 0..transient {
            x = fam.eval(x, a).f;
        }
        for _ in 0..keep {
            x = fam.eval(x, a).f;
            if x.is_finite() {
                dots.push((a, x));
                top = top.max(x);
            }
        }
    }
    let mut chart = Chart::new(
        "bifurcation diagram, doublings located by continuation to multiplier -1",
        labels.0,
        labels.1,
    )
    .dots("late orbit of the critical point", dots);
    let marks: Vec<(f64, f64)> = doublings
        .iter()
        .flat_map(|d| [(d.parameter, 0.0), (d.parameter, top), (f64::NAN, f64::NAN)])
        .collect();
    chart = chart.line("located doublings", marks);
    chart.draw(dir, &format!("{stem}-bifurcation"))
}
