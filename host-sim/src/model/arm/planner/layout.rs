//! The design vector (sec. 2.1): free B-spline control points, phase durations, mu.
//!
//! The initial-state constraint (sec. 2.2, manipulator 5: at rest at `theta_0`) holds by
//! construction: the first three control points equal `theta_0`, which gives
//! `theta(0) = theta_0`, `theta'(0) = theta''(0) = 0` (see [`dexter_core::bspline`]).
//! A task that ends at rest has its last three points equal too (a free end angle for a
//! roll, the goal angle for a snatch). Joint-position bounds are bounds on the points
//! (the convex hull holds the curve inside them).

use super::super::task::{Phase, TaskKind};
use super::super::ArmScene;

/// How the spline ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum End {
    /// Moving (a throw's release): the last points are free.
    Free,
    /// At rest at a free angle within bounds, rad.
    Rest(f64, f64),
    /// At rest at a given angle, rad.
    Fixed(f64),
}

/// The map between the design vector and the trajectory.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Control points in total.
    pub knots: usize,
    /// Start angle, rad.
    pub start_rad: f64,
    /// The end condition.
    pub end: End,
    /// The task's phases (one duration each).
    pub phases: &'static [Phase],
    /// Joint-angle bounds, rad.
    pub angle_bounds: (f64, f64),
    /// Phase-duration bounds, s.
    pub time_bounds: (f64, f64),
    /// Largest mu.
    pub mu_max: f64,
}

/// A decoded design vector.
#[derive(Clone, Debug, PartialEq)]
pub struct Design {
    /// All control points, rad.
    pub points_rad: Vec<f64>,
    /// Duration of each phase, s (same order as the phases).
    pub times_s: Vec<f64>,
    /// Segment duration of the spline, s.
    pub segment_s: f64,
    /// The friction coefficient variable.
    pub mu: f64,
}

impl Layout {
    /// The layout of a system's task.
    pub fn new(sys: &ArmScene) -> Self {
        let t = &sys.task;
        let b = &sys.bounds;
        let end = match (t.kind, t.final_angle_rad) {
            (k, _) if k.throws() => End::Free,
            (_, Some(a)) => End::Fixed(a),
            (_, None) => End::Rest(
                t.final_angle_range_rad.0.max(b.min_angle_rad),
                t.final_angle_range_rad.1.min(b.max_angle_rad),
            ),
        };
        Self {
            knots: sys.planner.knots,
            start_rad: t.initial_angle_rad,
            end,
            phases: t.kind.phases(),
            angle_bounds: (b.min_angle_rad, b.max_angle_rad),
            time_bounds: sys.planner.phase_time_s,
            mu_max: sys.planner.mu_max,
        }
    }

    /// Number of free control points.
    pub fn free_points(&self) -> usize {
        match self.end {
            End::Free => self.knots - 3,
            End::Rest(..) => self.knots - 5,
            End::Fixed(_) => self.knots - 6,
        }
    }

    /// Length of the design vector.
    pub fn len(&self) -> usize {
        self.free_points() + self.phases.len() + 1
    }

    /// Always false (there is at least mu).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Lower and upper bounds of every design variable.
    pub fn bounds(&self) -> Vec<(f64, f64)> {
        let mut b = vec![self.angle_bounds; self.free_points()];
        if let End::Rest(lo, hi) = self.end {
            if let Some(last) = b.last_mut() {
                *last = (lo, hi);
            }
        }
        b.extend(std::iter::repeat_n(self.time_bounds, self.phases.len()));
        b.push((0.0, self.mu_max));
        b
    }

    /// The trajectory a design vector describes.
    pub fn decode(&self, x: &[f64]) -> Design {
        let nf = self.free_points();
        let mut pts = vec![self.start_rad; 3];
        match self.end {
            End::Free => pts.extend_from_slice(&x[..nf]),
            End::Rest(..) => {
                pts.extend_from_slice(&x[..nf - 1]);
                pts.extend_from_slice(&[x[nf - 1]; 3]);
            }
            End::Fixed(a) => {
                pts.extend_from_slice(&x[..nf]);
                pts.extend_from_slice(&[a; 3]);
            }
        }
        let times: Vec<f64> = x[nf..nf + self.phases.len()].to_vec();
        let moving: f64 = self
            .phases
            .iter()
            .zip(&times)
            .filter(|(p, _)| **p != Phase::Flight)
            .map(|(_, t)| t)
            .sum();
        Design {
            segment_s: moving / (self.knots - 3) as f64,
            points_rad: pts,
            times_s: times,
            mu: x[nf + self.phases.len()],
        }
    }

    /// The design vector of a full control polygon (its fixed points ignored), phase
    /// times and mu, clamped into the bounds.
    pub fn encode(&self, points_rad: &[f64], times_s: &[f64], mu: f64) -> Vec<f64> {
        let n = self.knots;
        let mut x: Vec<f64> = match self.end {
            End::Free => points_rad[3..n].to_vec(),
            End::Rest(..) => {
                let mut v = points_rad[3..n - 3].to_vec();
                v.push(points_rad[n - 1]);
                v
            }
            End::Fixed(_) => points_rad[3..n - 3].to_vec(),
        };
        x.extend_from_slice(times_s);
        x.push(mu);
        x.iter()
            .zip(self.bounds())
            .map(|(v, (lo, hi))| v.clamp(lo, hi))
            .collect()
    }

    /// Initial guess number `k`: a windup of `w` rad opposite to a swing of `a` rad,
    /// the swing's sign alternating between guesses; phases of a few tenths of a second.
    pub fn guess(&self, kind: TaskKind, k: usize) -> Vec<f64> {
        let sign = if k.is_multiple_of(2) { 1.0 } else { -1.0 };
        let windup = [0.15, 0.3, 0.0, 0.45][(k / 2) % 4];
        let swing = match kind {
            TaskKind::Throw | TaskKind::RollingThrow | TaskKind::ThrowCatch => 0.8,
            _ => 0.5,
        };
        let nf = self.free_points();
        let (lo, hi) = self.angle_bounds;
        let clamp = |v: f64| v.clamp(lo + 1e-3, hi - 1e-3);
        let mut x: Vec<f64> = (0..nf)
            .map(|i| {
                let u = (i + 1) as f64 / nf as f64;
                // dip back by `windup` first, then swing forward
                let dip = -windup * (std::f64::consts::PI * u).sin() * (1.0 - u);
                clamp(self.start_rad + sign * (dip * 2.0 + swing * u * u))
            })
            .collect();
        match self.end {
            End::Rest(lo, hi) => {
                if let Some(last) = x.last_mut() {
                    *last = (self.start_rad + 0.3 * sign * swing).clamp(lo, hi);
                }
            }
            End::Fixed(a) => {
                // ease from the start toward the goal angle
                for (i, v) in x.iter_mut().enumerate() {
                    let u = (i + 1) as f64 / (nf + 1) as f64;
                    *v = clamp(self.start_rad + (a - self.start_rad) * u);
                }
            }
            End::Free => {}
        }
        for p in self.phases {
            x.push(match p {
                Phase::Grasp => 0.6,
                Phase::Roll => 0.25,
                Phase::Flight => 0.4,
            });
        }
        x.push(0.5 * self.mu_max);
        x
    }
}
