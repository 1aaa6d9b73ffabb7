//! The line juggler's `--plot` pictures: apex per impact (with the target), the return map
//! of impact speeds, and the phase portrait; each keeps at most
//! [`crate::stream::PLOT_MAX_POINTS`] points however long the run. The sweep's bifurcation
//! diagram ([`bifurcation`]) is drawn here too. The figures are the line system's own; the
//! charting under them is [`crate::plot`]'s.

use super::scene::Scene;
use super::trace::ImpactRow;
use super::{LineOutcome, LineSystem};
use crate::plot::{
    chart, finite_segments, fmt_num, legend, mesh, render, span, DrawResult, Figure, PlotError,
};
use crate::stream::Decimator;
use crate::system::Failure;
use crate::system::Plots;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Flights of a run without a controller drawn in its phase portrait.
pub const PHASE_FLIGHTS: usize = 4000;
/// Points per flight in that portrait.
const PER_FLIGHT: usize = 24;

/// What the line plots keep of a run.
pub struct LinePlots {
    apexes: Decimator<ImpactRow>,
    speeds: Decimator<(f64, f64)>,
    previous_speed: Option<f64>,
    first_rows: Vec<ImpactRow>,
    target_m: f64,
    stem: String,
}

impl Plots<LineSystem> for LinePlots {
    fn new(cfg: &Scene) -> Self {
        Self {
            apexes: Decimator::default(),
            speeds: Decimator::default(),
            previous_speed: None,
            first_rows: Vec::new(),
            target_m: cfg.control.target_apex_m.unwrap_or(f64::NAN),
            stem: cfg.name().to_string(),
        }
    }

    fn push(&mut self, row: &ImpactRow) {
        self.apexes.push(*row);
        let speed = -row.ball_velocity_before_mps;
        if let Some(p) = self.previous_speed.replace(speed) {
            self.speeds.push((p, speed));
        }
        if self.first_rows.len() <= PHASE_FLIGHTS {
            self.first_rows.push(*row);
        }
    }

    fn write(self, _: &Scene, outcome: &LineOutcome, dir: &Path) -> Result<Vec<PathBuf>, Failure> {
        let stem = &self.stem;
        let mut written = Vec::new();
        if !self.apexes.values().is_empty() {
            let apex_stem = format!("{stem}-apex");
            written.extend(apex_per_impact(
                self.apexes.values(),
                self.target_m,
                dir,
                &apex_stem,
            )?);
            if !self.speeds.values().is_empty() {
                let map_stem = format!("{stem}-return-map");
                written.extend(return_map_points(
                    self.speeds.into_values(),
                    dir,
                    &map_stem,
                )?);
            }
        }
        let phase = match outcome.phase.is_empty() {
            true => phase_from_rows(&self.first_rows, outcome.gravity_mps2),
            false => outcome.phase.clone(),
        };
        if !phase.is_empty() {
            written.extend(phase_portrait(&phase, dir, &format!("{stem}-phase"))?);
        }
        Ok(written)
    }
}

/// (b, b') along the ballistic flights between the first recorded impacts (for runs
/// without a controller, whose plant is not sampled per step).
fn phase_from_rows(rows: &[ImpactRow], g: f64) -> Vec<(f64, f64)> {
    let mut pts = Vec::new();
    for w in rows.windows(2).take(PHASE_FLIGHTS) {
        let (a, b) = (&w[0], &w[1]);
        let dt = b.time_s - a.time_s;
        for i in 0..=PER_FLIGHT {
            let t = dt * i as f64 / PER_FLIGHT as f64;
            pts.push((
                a.ball_height_m + a.ball_velocity_after_mps * t - 0.5 * g * t * t,
                a.ball_velocity_after_mps - g * t,
            ));
        }
    }
    pts
}

/// Apex height per impact index, with the target apex as a dashed horizontal line: the picture
/// of the controller's convergence.
///
/// Rows whose apex height is not finite are skipped (the line is broken there); the target line
/// is left out if the target is not finite.
pub fn apex_per_impact(
    rows: &[ImpactRow],
    target_apex_m: f64,
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    const WHAT: &str = "apex height per impact";
    if rows.is_empty() {
        return Err(PlotError::EmptyInput { what: WHAT });
    }
    let segments = finite_segments(rows.iter().map(|r| (r.index as f64, r.apex_height_m)));
    if segments.is_empty() {
        return Err(PlotError::NoFiniteData {
            what: WHAT,
            points: rows.len(),
        });
    }
    let target = target_apex_m.is_finite().then_some(target_apex_m);
    let x_range = span(segments.iter().flatten().map(|p| p.0), "impact index range")?;
    let y_range = span(
        segments.iter().flatten().map(|p| p.1).chain(target),
        "apex height range",
    )?;
    let fig = ApexFigure {
        segments,
        target,
        x_range,
        y_range,
    };
    render(&fig, dir, stem)
}

/// Phase portrait of the ball: height b (m) on x, velocity b′ (m/s) on y, drawn as a line
/// through the samples in order. A non-finite sample breaks the line.
pub fn phase_portrait(
    samples: &[(f64, f64)],
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    const WHAT: &str = "phase portrait samples";
    if samples.is_empty() {
        return Err(PlotError::EmptyInput { what: WHAT });
    }
    let segments = finite_segments(samples.iter().copied());
    if segments.is_empty() {
        return Err(PlotError::NoFiniteData {
            what: WHAT,
            points: samples.len(),
        });
    }
    let x_range = span(segments.iter().flatten().map(|p| p.0), "height range")?;
    let y_range = span(segments.iter().flatten().map(|p| p.1), "velocity range")?;
    let fig = PhaseFigure {
        segments,
        x_range,
        y_range,
    };
    render(&fig, dir, stem)
}

/// Return map of successive impact speeds: the points (v_n, v_{n+1}) with the identity line
/// v_{n+1} = v_n (the paper's eq. 8 cubic return map picture). A fixed point of the map lies on
/// the identity line.
///
/// Pairs where either speed is not finite are skipped; fewer than two speeds is an error.
pub fn return_map(speeds: &[f64], dir: &Path, stem: &str) -> Result<Vec<PathBuf>, PlotError> {
    if speeds.len() < 2 {
        return Err(PlotError::EmptyInput { what: RETURN_MAP });
    }
    let pairs = speeds.windows(2).map(|w| (w[0], w[1])).collect();
    return_map_points(pairs, dir, stem)
}

const RETURN_MAP: &str = "return map speeds (need at least two successive finite speeds)";

/// [`return_map`] of the pairs (v_n, v_{n+1}) themselves (e.g. a decimated subset).
pub fn return_map_points(
    pairs: Vec<(f64, f64)>,
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    let total = pairs.len();
    if total == 0 {
        return Err(PlotError::EmptyInput { what: RETURN_MAP });
    }
    let points: Vec<(f64, f64)> = pairs
        .into_iter()
        .filter(|&(a, b)| a.is_finite() && b.is_finite())
        .collect();
    if points.is_empty() {
        return Err(PlotError::NoFiniteData {
            what: RETURN_MAP,
            points: total + 1,
        });
    }
    // One range for both axes, so that the identity line is the diagonal.
    let range = span(points.iter().flat_map(|p| [p.0, p.1]), "speed range")?;
    let fig = ReturnMapFigure { points, range };
    render(&fig, dir, stem)
}

/// Bifurcation diagram: a scatter of (parameter value, late apex height) as many small dots.
///
/// `param_name` is the x axis label and should name the parameter with its unit, e.g.
/// `"paddle amplitude A (m)"`. Points with a non-finite coordinate are skipped.
pub fn bifurcation(
    points: &[(f64, f64)],
    param_name: &str,
    dir: &Path,
    stem: &str,
) -> Result<Vec<PathBuf>, PlotError> {
    const WHAT: &str = "bifurcation points";
    if points.is_empty() {
        return Err(PlotError::EmptyInput { what: WHAT });
    }
    let finite: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|&(p, a)| p.is_finite() && a.is_finite())
        .collect();
    if finite.is_empty() {
        return Err(PlotError::NoFiniteData {
            what: WHAT,
            points: points.len(),
        });
    }
    let x_range = span(finite.iter().map(|p| p.0), "parameter range")?;
    let y_range = span(finite.iter().map(|p| p.1), "apex height range")?;
    let param_name = param_name.trim();
    let param_name = if param_name.is_empty() {
        "parameter".to_string()
    } else {
        param_name.to_string()
    };
    let fig = BifurcationFigure {
        points: finite,
        param_name,
        x_range,
        y_range,
    };
    render(&fig, dir, stem)
}

struct ApexFigure {
    segments: Vec<Vec<(f64, f64)>>,
    target: Option<f64>,
    x_range: (f64, f64),
    y_range: (f64, f64),
}

impl Figure for ApexFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let mut chart = chart(root, "Apex height per impact", self.x_range, self.y_range)?;
        mesh(&mut chart, "impact index n", "apex height (m)")?;
        // The target first, so the apex line is drawn over it.
        if let Some(target) = self.target {
            let (x0, x1) = self.x_range;
            let style = RED.stroke_width(2);
            chart
                .draw_series(DashedLineSeries::new(
                    [(x0, target), (x1, target)],
                    10,
                    6,
                    style,
                ))?
                .label(format!("target {} m", fmt_num(target)))
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], RED.stroke_width(2)));
        }
        let total: usize = self.segments.iter().map(Vec::len).sum();
        // Markers on every impact while they can be told apart.
        let marker = if total <= 200 { 3 } else { 0 };
        for (i, segment) in self.segments.iter().enumerate() {
            let radius = if segment.len() == 1 {
                marker.max(2)
            } else {
                marker
            };
            let annotated = chart.draw_series(
                LineSeries::new(segment.iter().copied(), BLUE.filled().stroke_width(2))
                    .point_size(radius),
            )?;
            if i == 0 {
                annotated
                    .label("apex height after impact n")
                    .legend(|(x, y)| {
                        PathElement::new(vec![(x, y), (x + 24, y)], BLUE.stroke_width(2))
                    });
            }
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight)
    }
}

struct PhaseFigure {
    segments: Vec<Vec<(f64, f64)>>,
    x_range: (f64, f64),
    y_range: (f64, f64),
}

impl Figure for PhaseFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let mut chart = chart(root, "Ball phase portrait", self.x_range, self.y_range)?;
        mesh(&mut chart, "ball height b (m)", "ball velocity b′ (m/s)")?;
        for segment in &self.segments {
            let radius = if segment.len() == 1 { 3 } else { 0 };
            chart.draw_series(
                LineSeries::new(segment.iter().copied(), BLUE.filled().stroke_width(2))
                    .point_size(radius),
            )?;
        }
        Ok(())
    }
}

struct ReturnMapFigure {
    points: Vec<(f64, f64)>,
    range: (f64, f64),
}

impl Figure for ReturnMapFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let mut chart = chart(root, "Return map of impact speeds", self.range, self.range)?;
        mesh(
            &mut chart,
            "impact speed v(n) (m/s)",
            "next impact speed v(n+1) (m/s)",
        )?;
        let (lo, hi) = self.range;
        chart
            .draw_series(LineSeries::new(
                [(lo, lo), (hi, hi)],
                BLACK.mix(0.6).stroke_width(2),
            ))?
            .label("identity v(n+1) = v(n)")
            .legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], BLACK.mix(0.6).stroke_width(2))
            });
        let radius = if self.points.len() > 2000 { 1 } else { 3 };
        chart
            .draw_series(
                self.points
                    .iter()
                    .map(|&p| Circle::new(p, radius, RED.mix(0.8).filled())),
            )?
            .label("(v(n), v(n+1))")
            .legend(|(x, y)| Circle::new((x + 12, y), 4, RED.filled()));
        // The identity line runs from lower left to upper right: keep the legend off it.
        legend(&mut chart, SeriesLabelPosition::UpperLeft)
    }
}

struct BifurcationFigure {
    points: Vec<(f64, f64)>,
    param_name: String,
    x_range: (f64, f64),
    y_range: (f64, f64),
}

impl Figure for BifurcationFigure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB> {
        let title = "Bifurcation diagram of the late apex height";
        let mut chart = chart(root, title, self.x_range, self.y_range)?;
        mesh(&mut chart, &self.param_name, "late apex height (m)")?;
        let dot = BLACK.mix(0.5).filled();
        let radius = if self.points.len() > 2000 { 1 } else { 2 };
        chart.draw_series(self.points.iter().map(|&p| Circle::new(p, radius, dot)))?;
        Ok(())
    }
}
