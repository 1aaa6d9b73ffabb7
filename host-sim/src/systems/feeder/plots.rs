//! The feeder's `--plot` pictures (SVG + PNG, stem = the scene file's stem):
//! - `-filmstrip`: the plan as panels in one world window ([`crate::filmstrip`]): the belt
//!   (its center line under the pivot and its right edge), the fence, the goal contact
//!   point, the part's center-of-mass path so far and the part, at the arrival and at the
//!   key moments of every primitive (a turn's release at theta+, its catch at theta- and
//!   its end; a jog's tilt and its end; a catch's end);
//! - `-fence`: the fence angle against time;
//! - `-radius`: the center of mass's fence coordinate (the contact radius while an edge is
//!   flush) against time, with the goal radius.
//!
//! Each series keeps at most [`crate::stream::PLOT_MAX_POINTS`] points.

use super::summary::FeederOutcome;
use super::trace::FeederRow;
use super::{FeederConfig, FeederSystem};
use crate::filmstrip::{filmstrip, Frame, Ink, Shape, MAX_FRAMES};
use crate::model::feeder::execute::{Frame as Knot, Summary};
use crate::model::feeder::primitives::Primitive;
use crate::plot::Chart;
use crate::stream::Decimator;
use crate::system::Failure;
use crate::system::Plots;
use std::path::{Path, PathBuf};

/// Palette slots of the filmstrip's shapes.
const FENCE: usize = 0;
const PART: usize = 1;
const PATH: usize = 2;
const GOAL: usize = 3;
const BELT: usize = 5;

/// What the feeder's plots keep of a run.
#[derive(Default)]
pub struct FeederPlots {
    /// (t, COM x, COM y).
    path: Decimator<(f64, f64, f64)>,
    /// (t, fence angle in degrees).
    fence: Decimator<(f64, f64)>,
    /// (t, fence coordinate of the COM).
    radius: Decimator<(f64, f64)>,
}

impl Plots<FeederSystem> for FeederPlots {
    fn new(_: &FeederConfig) -> Self {
        Self::default()
    }

    fn push(&mut self, row: &FeederRow) {
        let r = &row.record;
        self.path.push((r.t_s, r.pose.com_m.x, r.pose.com_m.y));
        self.fence.push((r.t_s, r.fence.angle_rad.to_degrees()));
        self.radius.push((r.t_s, row.fence_coordinate_m()));
    }

    fn write(
        self,
        cfg: &FeederConfig,
        out: &FeederOutcome,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, Failure> {
        let s = &out.report.summary;
        let name = &cfg.name;
        let mut written = Vec::new();
        let frames = self.panels(s);
        let title = format!(
            "{name}: edge {} to goal edge {}, belt -y",
            s.start_edge, s.goal_edge
        );
        written.extend(filmstrip(
            &title,
            &frames,
            dir,
            &format!("{name}-filmstrip"),
        )?);
        let t_end = s.plan_time_s;
        let chart = Chart::new(
            format!("{name}: fence angle during the feed"),
            "t (s)",
            "fence angle (deg)",
        )
        .line("fence angle", self.fence.values().to_vec());
        written.extend(chart.draw(dir, &format!("{name}-fence"))?);
        let goal = s.goal_radius_m;
        let chart = Chart::new(
            format!("{name}: contact radius during the feed"),
            "t (s)",
            "COM coordinate along the fence (m)",
        )
        .line(
            "COM along the fence (contact radius while flush)",
            self.radius.values().to_vec(),
        )
        .line(
            format!("goal radius {goal:.4} m on edge {}", s.goal_edge),
            vec![(0.0, goal), (t_end, goal)],
        );
        written.extend(chart.draw(dir, &format!("{name}-radius"))?);
        Ok(written)
    }
}

/// Start time of each primitive, s.
fn starts(plan: &[Primitive]) -> Vec<f64> {
    let mut t = 0.0;
    plan.iter()
        .map(|p| {
            let t0 = t;
            t += p.duration_s();
            t0
        })
        .collect()
}

/// A primitive's name in a panel caption.
fn short(p: &Primitive) -> &'static str {
    match p {
        Primitive::ConvergentTurn { .. } => "conv. turn",
        Primitive::DriftJog { .. } => "drift jog",
        other => other.name(),
    }
}

/// The knots to show with their captions: the arrival, then each primitive's key moments
/// (module docs); only the primitives' ends when that is more than [`MAX_FRAMES`].
pub fn moments(s: &Summary) -> Vec<(usize, String)> {
    let knots = &s.frames;
    let st = starts(&s.plan);
    let mut full = vec![(0, "arrival".to_string())];
    let mut ends = full.clone();
    for (k, p) in s.plan.iter().enumerate() {
        let (t0, t1) = (st[k] - 1e-9, st[k] + p.duration_s() + 1e-9);
        let inside: Vec<usize> = (0..knots.len())
            .filter(|&i| (t0..=t1).contains(&knots[i].t_s))
            .collect();
        let Some(&last) = inside.last() else { continue };
        let extreme = inside.iter().copied().max_by(|&a, &b| {
            let (x, y) = (knots[a].fence_angle_rad, knots[b].fence_angle_rad);
            x.abs().total_cmp(&y.abs())
        });
        let mut add = |i: usize, what: String| full.push((i, what));
        match p {
            Primitive::Jog { .. } | Primitive::DriftJog { .. } => {
                if let Some(i) = extreme.filter(|&i| knots[i].fence_angle_rad != 0.0) {
                    add(i, format!("{k} {}: tilt", short(p)));
                }
            }
            Primitive::Turn {
                theta_plus_rad: tp,
                theta_minus_rad: tm,
                ..
            }
            | Primitive::ConvergentTurn {
                theta_plus_rad: tp,
                theta_minus_rad: tm,
                ..
            } => {
                let at = |a: f64| {
                    inside
                        .iter()
                        .copied()
                        .filter(move |&i| (knots[i].fence_angle_rad - a).abs() < 1e-9)
                };
                if let Some(i) = at(*tp).next() {
                    add(i, format!("{k} {}: release", short(p)));
                }
                if let Some(i) = at(*tm).next_back() {
                    add(i, format!("{k} {}: catch", short(p)));
                }
            }
            Primitive::Catch { .. } => {}
        }
        let end = format!("{k} {}: end", short(p));
        full.push((last, end.clone()));
        ends.push((last, end));
    }
    if full.len() <= MAX_FRAMES {
        return full;
    }
    if ends.len() > MAX_FRAMES {
        let keep_last = ends.pop();
        ends.truncate(MAX_FRAMES - 1);
        ends.extend(keep_last);
    }
    ends
}

impl FeederPlots {
    /// The filmstrip's panels.
    fn panels(&self, s: &Summary) -> Vec<Frame> {
        let chosen = moments(s);
        let ys = chosen
            .iter()
            .flat_map(|(i, _)| {
                let k = &s.frames[*i];
                k.part_m.iter().map(|p| p.y).chain([k.fence_tip_m.y, 0.0])
            })
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
                (a.min(y), b.max(y))
            });
        chosen
            .iter()
            .map(|(i, what)| self.panel(s, &s.frames[*i], what, ys))
            .collect()
    }

    fn panel(&self, s: &Summary, k: &Knot, what: &str, (y0, y1): (f64, f64)) -> Frame {
        let belt = |x: f64| Shape::new(vec![(x, y0), (x, y1)], Ink::Trace, BELT);
        let path: Vec<(f64, f64)> = self
            .path
            .values()
            .iter()
            .filter(|p| p.0 <= k.t_s + 1e-9)
            .map(|p| (p.1, p.2))
            .collect();
        let mut shapes = vec![
            belt(0.0),
            belt(s.stage.belt_edge_m),
            Shape::new(
                vec![(0.0, 0.0), (k.fence_tip_m.x, k.fence_tip_m.y)],
                Ink::Surface,
                FENCE,
            ),
            Shape::new(vec![(s.goal_radius_m, 0.0)], Ink::Dots, GOAL),
        ];
        if path.len() >= 2 {
            shapes.push(Shape::new(path, Ink::Trace, PATH));
        }
        shapes.push(Shape::new(
            k.part_m.iter().map(|p| (p.x, p.y)).collect(),
            Ink::Body,
            PART,
        ));
        Frame {
            label: format!("{:.2} s  {what}", k.t_s),
            shapes,
        }
    }
}
