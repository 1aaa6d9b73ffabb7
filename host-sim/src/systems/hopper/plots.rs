//! The hopper run's `--plot` pictures (SVG + PNG): `{scene}-return-map` (x_{n+1} against
//! x_n with eq. 15 or eq. 17 and the identity), `{scene}-energy-map` (E_{n+1} against E_n
//! with f(E)) and `{scene}-phase` (chi' against chi, figs. 7-13). The successive pairs of
//! each start keep at most [`crate::stream::PLOT_MAX_POINTS`] points.

use super::closed_forms::ClosedForm;
use super::summary::HopperOutcome;
use super::trace::HopperRow;
use super::{model_equation, start_text, HopperConfig, HopperSystem};
use crate::model::hopper::params::ModelKind;
use crate::plot::Chart;
use crate::stream::Decimator;
use crate::system::Failure;
use crate::system::Plots;
use std::path::{Path, PathBuf};

/// Palette slots ([`crate::plot::series`] colours series by index): simulated dots take
/// the first (red, green), the closed form the fourth (blue), the identity the fifth
/// (orange).
const CURVE_SLOT: usize = 3;
const IDENTITY_SLOT: usize = 4;
/// Points drawn of a closed-form curve.
const CURVE_POINTS: usize = 600;

/// The successive pairs of one start.
#[derive(Default)]
struct Pairs {
    x: Decimator<(f64, f64)>,
    e: Decimator<(f64, f64)>,
    last: Option<(f64, f64)>,
}

/// What the hopper plots keep of a run: per start, its (x_n, x_{n+1}) and (E_n, E_{n+1}).
pub struct HopperPlots {
    starts: Vec<Pairs>,
}

impl Plots<HopperSystem> for HopperPlots {
    fn new(cfg: &HopperConfig) -> Self {
        Self {
            starts: cfg.starts.iter().map(|_| Pairs::default()).collect(),
        }
    }

    fn push(&mut self, row: &HopperRow) {
        let Some(p) = self.starts.get_mut(row.trajectory - 1) else {
            return;
        };
        let now = (row.cycle.bottom_height_m, row.cycle.energy);
        if let Some((x, e)) = p.last.replace(now) {
            p.x.push((x, now.0));
            p.e.push((e, now.1));
        }
    }

    fn write(
        self,
        cfg: &HopperConfig,
        out: &HopperOutcome,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, Failure> {
        let labels: Vec<String> = match cfg.starts.len() {
            1 => vec!["simulated".to_string()],
            _ => cfg
                .starts
                .iter()
                .map(|s| format!("simulated, from {}", start_text(s)))
                .collect(),
        };
        let cf = out.closed.as_ref();
        let mut written = Vec::new();
        let xs = Dots::of(&labels, self.starts.iter().map(|p| &p.x));
        match return_map(cfg, cf, xs) {
            Some(chart) => written.extend(chart.draw(dir, &format!("{}-return-map", cfg.name))?),
            None => crate::output::note("warning: fewer than two cycles, no return map plotted"),
        }
        let es = Dots::of(&labels, self.starts.iter().map(|p| &p.e));
        if let Some(chart) = energy_map(cfg, cf, es) {
            written.extend(chart.draw(dir, &format!("{}-energy-map", cfg.name))?);
        }
        if let Some(chart) = phase(cfg, out, &labels) {
            written.extend(chart.draw(dir, &format!("{}-phase", cfg.name))?);
        }
        Ok(written)
    }
}

/// One dotted series of pairs per start, and the finite range of every coordinate.
struct Dots {
    series: Vec<(String, Vec<(f64, f64)>)>,
    range: Option<(f64, f64)>,
}

impl Dots {
    fn of<'a>(labels: &[String], pairs: impl Iterator<Item = &'a Decimator<(f64, f64)>>) -> Self {
        let series: Vec<(String, Vec<(f64, f64)>)> = labels
            .iter()
            .cloned()
            .zip(pairs.map(|d| d.values().to_vec()))
            .collect();
        let coords = series
            .iter()
            .flat_map(|s| s.1.iter().flat_map(|p| [p.0, p.1]));
        let range = finite_range(coords);
        Self { series, range }
    }

    /// The dots on a new chart.
    fn chart(self, title: String, x: String, y: String) -> Chart {
        self.series
            .into_iter()
            .fold(Chart::new(title, x, y), |c, (label, pts)| {
                c.dots(label, pts)
            })
    }
}

/// `n` points evenly spaced over [a, b].
fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
        .collect()
}

fn finite_range(v: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    (lo <= hi).then_some((lo, hi))
}

fn padded(lo: f64, hi: f64) -> (f64, f64) {
    let pad = 0.15 * (hi - lo).max(1e-3 * hi.abs().max(1e-3));
    (lo - pad, hi + pad)
}

/// The bottom-height return map x_{n+1} against x_n.
fn return_map(cfg: &HopperConfig, cf: Option<&ClosedForm>, dots: Dots) -> Option<Chart> {
    let (lo, hi) = dots.range?;
    let chi_l = cfg.params.liftoff_height_m;
    let (mut a, mut b) = padded(lo, hi);
    let curve_label = match cf {
        Some(ClosedForm::Eq19 { .. }) => {
            // the unimodal map on its whole domain (0, chi_l)
            a = a.min(1e-4 * chi_l).max(1e-6 * chi_l);
            b = b.max(chi_l).min(chi_l);
            Some("eq. 15: g(x) = chi_l exp(-(tau mu / eta1) x ln(chi_l / x))".to_string())
        }
        Some(c @ ClosedForm::Eq17 { .. }) => Some(if c.exact() {
            "eq. 17 (tuned), in x = chi_eq - sqrt(E / eta1)".to_string()
        } else {
            "eq. 17 with this scene's omega, beta, delta, tau - g (scene untuned: approximate)"
                .to_string()
        }),
        None => None,
    };
    let title = format!("{}: return map of bottom heights", cfg.name);
    let mut chart = dots.chart(title, "x(n), bottom height (m)".into(), "x(n+1) (m)".into());
    if let (Some(c), Some(l)) = (cf, curve_label) {
        let curve = linspace(a, b, CURVE_POINTS)
            .iter()
            .map(|&x| (x, c.bottom_map(x)))
            .collect();
        chart = chart.line_at(CURVE_SLOT, l, curve);
    }
    Some(chart.line_at(
        IDENTITY_SLOT,
        "identity x(n+1) = x(n)",
        vec![(a, a), (b, b)],
    ))
}

/// The energy return map E_{n+1} against E_n.
fn energy_map(cfg: &HopperConfig, cf: Option<&ClosedForm>, dots: Dots) -> Option<Chart> {
    let (lo, hi) = dots.range?;
    let (unit, coord) = match cfg.params.model {
        ModelKind::Linear => ("m^2/s^2", "eta1 (x - chi_eq)^2"),
        _ => ("dimensionless", "ln(chi_l / x)"),
    };
    let (a0, b) = padded(lo, hi);
    let mut a = a0.max(0.0);
    let title = format!("{}: energy return map, E = {coord}", cfg.name);
    let mut chart = dots.chart(title, format!("E(n) ({unit})"), format!("E(n+1) ({unit})"));
    let curve = match cf {
        Some(c @ ClosedForm::Eq19 { .. }) => {
            a = 0.0;
            Some((
                c,
                "eq. 19: f(E) = alpha E exp(-E)",
                linspace(a, b, CURVE_POINTS),
            ))
        }
        Some(c @ ClosedForm::Eq17 { map, .. }) => {
            a = a.max(map.domain_start() * (1.0 + 1e-6));
            let label = match c.exact() {
                true => "eq. 17 (tuned)",
                false => "eq. 17 (scene untuned: approximate)",
            };
            Some((c, label, linspace(a, b.max(a * 1.01), CURVE_POINTS)))
        }
        None => None,
    };
    if let Some((c, label, es)) = curve {
        let pts = es.iter().map(|&e| (e, c.energy_map(e))).collect();
        chart = chart.line_at(CURVE_SLOT, label, pts);
    }
    Some(chart.line_at(
        IDENTITY_SLOT,
        "identity E(n+1) = E(n)",
        vec![(a, a), (b, b)],
    ))
}

/// The phase portrait (chi, chi'), one line per start, with chi_l marked.
fn phase(cfg: &HopperConfig, out: &HopperOutcome, labels: &[String]) -> Option<Chart> {
    let title = format!(
        "{}: phase portrait ({})",
        cfg.name,
        model_equation(cfg.params.model)
    );
    let mut chart = Chart::new(title, "body height chi (m)", "body velocity chi' (m/s)");
    for (t, label) in out.trajectories.iter().zip(labels) {
        let pts: Vec<(f64, f64)> = t
            .samples
            .iter()
            .map(|s| (s.state.height_m, s.state.velocity_mps))
            .collect();
        if !pts.is_empty() {
            chart = chart.line(label.clone(), pts);
        }
    }
    let velocities = chart
        .series()
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1));
    let (vlo, vhi) = finite_range(velocities)?;
    let chi_l = cfg.params.liftoff_height_m;
    Some(chart.line_at(
        CURVE_SLOT,
        "chi_l: touchdown / liftoff height",
        vec![(chi_l, vlo), (chi_l, vhi)],
    ))
}
