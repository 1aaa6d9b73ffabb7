//! The arm's `--plot` pictures (SVG + PNG, stem = the scene file's stem), like the paper's
//! figs. 2-3: `-filmstrip` (the arm and the object through the verified motion, with a
//! throw's goal), `-trajectory` (the planned joint angle with its knots at their Greville
//! abscissae, the tracked angle, and the events) and `-friction` (the friction the
//! verified run needs over time, the plan's own samples, every impact's impulse ratio,
//! mu_required and 0.95 mu), `-torque` (the torque the controller commanded, the plan's
//! samples, the limits and the events) and, for a juggle, `-juggle` (each cycle's landing
//! error, exact and tracked).
//!
//! Everything drawn comes from the outcome, whose size is bounded by the run's simulated
//! time (at most a few tens of seconds; `docs/arm.md`); rows are not kept.

use super::execute::MARGIN_FACTOR;
use super::summary::ArmOutcome;
use super::trace::{phase_name, ArmRow};
use super::{ArmRunConfig, ArmSystem};
use crate::filmstrip::{filmstrip, Frame, Ink, Shape, MAX_FRAMES};
use crate::model::arm::geometry::V2;
use crate::model::arm::simulate;
use crate::plot::Chart;
use crate::system::Failure;
use crate::system::Plots;
use std::path::{Path, PathBuf};

/// Panels of the filmstrip (three rows of four).
const PANELS: usize = 12;

/// The arm's plots keep nothing of the rows: they draw from the outcome.
pub struct ArmPlots;

impl Plots<ArmSystem> for ArmPlots {
    fn new(_: &ArmRunConfig) -> Self {
        ArmPlots
    }

    fn push(&mut self, _: &ArmRow) {}

    fn write(
        self,
        cfg: &ArmRunConfig,
        out: &ArmOutcome,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, Failure> {
        let name = &cfg.name;
        let s = &out.json.summary;
        let title = format!(
            "{name}: {} ({}), mu_required {:.4}, executed {}",
            s.task,
            s.phases,
            s.mu_required,
            super::summary::verdict(s.executed)
        );
        let frames = panels(cfg, out);
        let mut written = filmstrip(&title, &frames, dir, &format!("{name}-filmstrip"))?;
        written.extend(trajectory(cfg, out).draw(dir, &format!("{name}-trajectory"))?);
        written.extend(friction(cfg, out).draw(dir, &format!("{name}-friction"))?);
        written.extend(torque(cfg, out).draw(dir, &format!("{name}-torque"))?);
        if let Some(j) = &out.json.juggle {
            written.extend(juggle(cfg, j).draw(dir, &format!("{name}-juggle"))?);
        }
        Ok(written)
    }
}

fn xy(v: V2) -> (f64, f64) {
    (v.x, v.y)
}

/// Up to [`PANELS`] frames, evenly spread over the run from its first to its last.
fn panels(cfg: &ArmRunConfig, out: &ArmOutcome) -> Vec<Frame> {
    let s = &out.json.summary;
    let n = s.frames.len();
    let shown = n.min(PANELS).min(MAX_FRAMES);
    let goal = cfg.scene.task.goal.map(|g| (g.x_m, g.y_m));
    (0..shown)
        .map(|i| {
            let k = match shown {
                1 => 0,
                _ => i * (n - 1) / (shown - 1),
            };
            let f = &s.frames[k];
            let arm: Vec<(f64, f64)> = s
                .arm_outline
                .iter()
                .map(|p| xy(p.rotate(f.arm_angle_rad)))
                .collect();
            let mut shapes = vec![
                Shape::new(vec![(-0.2, 0.0), (0.2, 0.0)], Ink::Trace, 7),
                Shape::new(arm, Ink::Surface, 0),
                Shape::new(vec![(0.0, 0.0)], Ink::Dots, 0),
                Shape::new(f.object.iter().map(|&p| xy(p)).collect(), Ink::Body, 1),
            ];
            if let Some(g) = goal {
                shapes.push(Shape::new(vec![g], Ink::Dots, 3));
            }
            Frame {
                label: format!("t = {:.3} s, {}", f.t_s, phase_name(f.phase)),
                shapes,
            }
        })
        .collect()
}

/// Vertical marks at the events, one series broken between marks.
fn event_marks(out: &ArmOutcome, lo: f64, hi: f64) -> Vec<(f64, f64)> {
    let mut v = Vec::new();
    for e in &out.json.summary.events {
        v.extend([(e.t_s, lo), (e.t_s, hi), (f64::NAN, f64::NAN)]);
    }
    v
}

fn trajectory(cfg: &ArmRunConfig, out: &ArmOutcome) -> Chart {
    let s = &out.json.summary;
    let planned: Vec<(f64, f64)> = s
        .trajectory
        .samples
        .iter()
        .map(|(t, j)| (*t, j.angle_rad))
        .collect();
    let knots = s
        .trajectory
        .knots
        .iter()
        .map(|k| (k.t_s, k.angle_rad))
        .collect();
    let angles = planned.iter().chain(&out.tracked_angle).map(|p| p.1);
    let (lo, hi) = angles.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
        (a.min(y), b.max(y))
    });
    let title = format!(
        "{}: joint trajectory, {} knots, segment {:.4} s",
        cfg.name,
        s.trajectory.knots.len(),
        s.trajectory.segment_s
    );
    Chart::new(title, "t (s)", "joint angle (rad)")
        .line("planned (B-spline, then the move to rest)", planned)
        .line(
            format!("tracked by ArmController ({})", out.json.controller),
            out.tracked_angle.clone(),
        )
        .dots("control points at their Greville abscissae", knots)
        .line("events (verified run)", event_marks(out, lo, hi))
}

fn torque(cfg: &ArmRunConfig, out: &ArmOutcome) -> Chart {
    let s = &out.json.summary;
    let planned = s
        .friction_planned
        .iter()
        .map(|p| (p.t_s, p.torque_nm))
        .collect();
    let m = cfg.scene.bounds.torque_max_nm;
    let tau = out.tracked_torque.iter().map(|p| p.1);
    let (lo, hi) = tau.fold((-m, m), |(a, b), y| (a.min(y), b.max(y)));
    let end = out.tracked_torque.last().map_or(1.0, |p| p.0);
    Chart::new(
        format!("{}: joint torque", cfg.name),
        "t (s)",
        "torque (N m)",
    )
    .line(
        format!("commanded by ArmController ({})", out.json.controller),
        out.tracked_torque.clone(),
    )
    .dots("planner's samples", planned)
    .line(format!("limit +-{m:.0} N m"), vec![(0.0, m), (end, m)])
    .line("-limit", vec![(0.0, -m), (end, -m)])
    .line("events (verified run)", event_marks(out, lo, hi))
}

/// A juggle's landing error per cycle, exact and tracked.
fn juggle(cfg: &ArmRunConfig, j: &super::summary::JuggleSummary) -> Chart {
    let errors = |c: &crate::model::arm::juggle::Chain| {
        c.cycles
            .iter()
            .filter_map(|y| y.landing_error_m.map(|e| (y.cycle as f64, 1e3 * e)))
            .collect()
    };
    Chart::new(
        format!(
            "{}: landing error per cycle (exact {} of {}, tracked {} of {} caught)",
            cfg.name, j.exact.completed, j.cycles, j.tracked.completed, j.cycles
        ),
        "cycle",
        "caught position - catch position (mm)",
    )
    .dots("exact", errors(&j.exact))
    .dots("tracked by ArmController", errors(&j.tracked))
}

fn friction(cfg: &ArmRunConfig, out: &ArmOutcome) -> Chart {
    let s = &out.json.summary;
    let verified = s.friction.iter().map(|f| (f.t_s, f.ratio)).collect();
    let planned = s
        .friction_planned
        .iter()
        .map(|p| (p.t_s, p.friction_ratio))
        .collect();
    let end = s
        .friction
        .last()
        .map_or(simulate::FRAME_S, |f| f.t_s)
        .max(simulate::FRAME_S);
    let mu = s.mu_required;
    Chart::new(
        format!("{}: friction needed, |f_t| / f_n", cfg.name),
        "t (s)",
        "|f_t| / f_n",
    )
    .line("verified run", verified)
    .dots("planner's samples", planned)
    .dots(
        "impacts: the impulse's |Pi_t| / Pi_n (roll ends, rocks, the catch)",
        s.impacts
            .iter()
            .map(|i| (i.t_s, i.friction_ratio))
            .collect(),
    )
    .line(format!("mu_required {mu:.4}"), vec![(0.0, mu), (end, mu)])
    .line(
        format!("{MARGIN_FACTOR} mu_required (the margin check)"),
        vec![(0.0, MARGIN_FACTOR * mu), (end, MARGIN_FACTOR * mu)],
    )
}
