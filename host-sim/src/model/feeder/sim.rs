//! Time-stepping the part under a commanded fence motion with the quasistatic solver.
//!
//! The fence follows a [`Schedule`] (piecewise-constant rate). Each step finds the hull
//! vertices touching the fence (within [`CONTACT_TOL`] of its line, between pivot and
//! tip), solves [`quasistatic::solve`], and advances the pose:
//! - a stable push (line stick) and drift are integrated **exactly** (rigid rotation with
//!   the fence about the pivot; translation with the belt);
//! - the other modes (pivoting, sliding) with the explicit midpoint rule and small steps.
//!
//! A step that would carry a free vertex through the fence is shortened (secant on the
//! signed distance) so contacts are located, and any residual penetration is removed by a
//! normal projection. The run stops at the schedule's end or at the first [`Failure`].

use super::geometry::{Pose, Vec2};
use super::part::Part;
use super::quasistatic::{self, Fence, Medium, Mode, Motion};
use serde::Serialize;

/// Contact tolerance as a fraction of the part's radius.
pub const CONTACT_TOL: f64 = 1e-5;
/// Largest fence or part rotation per step while a point contact pivots, rad.
const PIVOT_STEP_RAD: f64 = 0.002;
/// Largest fence rotation per step otherwise, rad.
const FENCE_STEP_RAD: f64 = 0.01;
/// Largest displacement of the COM per step, as a fraction of the part's radius.
const MOVE_STEP: f64 = 0.02;
/// Cap on the steps of one run (bounds memory and time for every accepted scene).
pub const MAX_STEPS: usize = 2_000_000;

/// A commanded fence motion: knots `(t_s, angle_rad)` joined by constant rates.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Schedule {
    /// Knot times, s (non-decreasing) and angles, rad.
    pub knots: Vec<(f64, f64)>,
}

impl Schedule {
    /// The fence at `angle_rad` from `t_s`.
    pub fn starting(t_s: f64, angle_rad: f64) -> Self {
        Self {
            knots: vec![(t_s, angle_rad)],
        }
    }
    /// Time of the last knot, s.
    pub fn end_s(&self) -> f64 {
        self.knots.last().map_or(0.0, |k| k.0)
    }
    /// Angle of the last knot, rad.
    pub fn end_angle(&self) -> f64 {
        self.knots.last().map_or(0.0, |k| k.1)
    }
    /// Holds the last angle for `dur_s`.
    pub fn hold(&mut self, dur_s: f64) {
        let (t, a) = (self.end_s(), self.end_angle());
        self.knots.push((t + dur_s.max(0.0), a));
    }
    /// Turns to `angle_rad` at `|rate_radps|`.
    pub fn move_to(&mut self, angle_rad: f64, rate_radps: f64) {
        let (t, a) = (self.end_s(), self.end_angle());
        self.knots
            .push((t + (angle_rad - a).abs() / rate_radps.abs(), angle_rad));
    }
    /// Appends the knots of `other` (which must start at this schedule's end).
    pub fn extend(&mut self, other: &Schedule) {
        self.knots.extend(other.knots.iter().skip(1).copied());
    }
    /// The fence at `t_s`: the angle, and the rate of the segment that starts at or
    /// before `t_s` (0 past the end).
    pub fn at(&self, t_s: f64) -> Fence {
        let k = &self.knots;
        let i = k.partition_point(|kn| kn.0 <= t_s);
        if i == 0 {
            return Fence {
                angle_rad: k[0].1,
                rate_radps: 0.0,
            };
        }
        if i >= k.len() {
            return Fence {
                angle_rad: k[k.len() - 1].1,
                rate_radps: 0.0,
            };
        }
        let ((t0, a0), (t1, a1)) = (k[i - 1], k[i]);
        let rate = if t1 > t0 { (a1 - a0) / (t1 - t0) } else { 0.0 };
        Fence {
            angle_rad: a0 + rate * (t_s - t0),
            rate_radps: rate,
        }
    }
    /// First knot time strictly after `t_s`.
    pub fn next_knot(&self, t_s: f64) -> Option<f64> {
        self.knots.iter().map(|k| k.0).find(|&t| t > t_s)
    }
}

/// The world a run happens in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setup {
    /// Belt speed and fence friction.
    pub medium: Medium,
    /// Fence length from the pivot, m.
    pub fence_length_m: f64,
    /// Right edge of the belt, x, m (the belt's half width; the pivot is on its center
    /// line and only x > 0 is used).
    pub belt_edge_m: f64,
}

/// Why a run stopped early.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "kind")]
pub enum Failure {
    /// A part vertex crossed the belt's right edge.
    OffBelt {
        /// When, s.
        t_s: f64,
    },
    /// A part vertex crossed x = 0, the line through the pivot (only the right half of the
    /// belt is used).
    PastPivot {
        /// When, s.
        t_s: f64,
    },
    /// The part rests on the fence with its contact edge overhanging the tip.
    OffFenceTip {
        /// When, s.
        t_s: f64,
    },
    /// The run hit [`MAX_STEPS`].
    TooLong {
        /// When, s.
        t_s: f64,
    },
}

impl std::fmt::Display for Failure {
    /// The failure in words, with its time in ms.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (what, t_s) = match *self {
            Self::OffBelt { t_s } => ("the part left the belt over its right edge", t_s),
            Self::PastPivot { t_s } => ("the part crossed the line through the pivot", t_s),
            Self::OffFenceTip { t_s } => ("the part rests overhanging the fence's tip", t_s),
            Self::TooLong { t_s } => ("the push took too many steps", t_s),
        };
        write!(f, "{what} at t = {t_s:.4} s")
    }
}

/// Where a run ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// Time, s.
    pub t_s: f64,
    /// Final pose.
    pub pose: Pose,
    /// The last motion solved.
    pub motion: Motion,
    /// The first failure, if any (the run stopped there).
    pub failure: Option<Failure>,
    /// Steps taken (bounded by [`MAX_STEPS`]).
    pub steps: usize,
}

/// Signed distances of the hull vertices from the fence line (> 0 on the part's side)
/// and their fence coordinates.
fn distances(part: &Part, pose: &Pose, fence: &Fence) -> Vec<(f64, f64)> {
    let (n, t) = (fence.normal(), fence.tangent());
    part.hull
        .iter()
        .map(|&v| {
            let p = pose.to_world(v);
            (n.dot(p), t.dot(p))
        })
        .collect()
}

/// Hull vertices touching the fence segment, nearest first (at most 2).
pub fn touching(part: &Part, pose: &Pose, fence: &Fence, fence_length_m: f64) -> Vec<usize> {
    let tol = CONTACT_TOL * part.radius_m;
    let mut c: Vec<(usize, f64)> = distances(part, pose, fence)
        .into_iter()
        .enumerate()
        .filter(|(_, (d, s))| *d <= tol && *s >= -tol && *s <= fence_length_m + tol)
        .map(|(i, (d, _))| (i, d))
        .collect();
    c.sort_by(|a, b| a.1.total_cmp(&b.1));
    c.truncate(2);
    c.into_iter().map(|(i, _)| i).collect()
}

/// Hull edge lying flush on the fence (both ends within tolerance), if any.
pub fn flush_edge(part: &Part, pose: &Pose, fence: &Fence, fence_length_m: f64) -> Option<usize> {
    let t = touching(part, pose, fence, fence_length_m);
    let n = part.hull.len();
    match t.as_slice() {
        [a, b] if (a + 1) % n == *b => Some(*a),
        [a, b] if (b + 1) % n == *a => Some(*b),
        _ => None,
    }
}

fn advance(pose: &Pose, m: &Motion, fence: &Fence, dt: f64) -> Pose {
    if matches!(m.mode, Mode::LineStick(..)) {
        // Rigid with the fence: exact rotation about the pivot.
        let da = fence.rate_radps * dt;
        return Pose {
            com_m: pose.com_m.rotate(da),
            angle_rad: pose.angle_rad + da,
        };
    }
    Pose {
        com_m: pose.com_m + m.com_mps.scale(dt),
        angle_rad: pose.angle_rad + m.omega_radps * dt,
    }
}

fn step_limit(part: &Part, m: &Motion, fence: &Fence) -> f64 {
    let speed = m.com_mps.norm() + m.omega_radps.abs() * part.radius_m;
    let mut dt = MOVE_STEP * part.radius_m / speed.max(1e-12);
    let pivoting = matches!(m.mode, Mode::PointStick(_) | Mode::PointSlide(..));
    let rot = if pivoting {
        PIVOT_STEP_RAD
    } else {
        FENCE_STEP_RAD
    };
    dt = dt.min(rot / fence.rate_radps.abs().max(1e-12));
    if pivoting {
        dt = dt.min(PIVOT_STEP_RAD / m.omega_radps.abs().max(1e-12));
        dt = dt.min(0.1 * MOVE_STEP * part.radius_m / speed.max(1e-12));
    }
    dt
}

/// Runs the part from `start` at `t0_s` under `schedule` until `t1_s`, calling
/// `observe(t_s, pose, motion)` after every step.
pub fn run(
    part: &Part,
    setup: &Setup,
    schedule: &Schedule,
    start: Pose,
    t0_s: f64,
    t1_s: f64,
    observe: impl FnMut(f64, &Pose, &Motion),
) -> Outcome {
    run_until(
        part,
        setup,
        schedule,
        (start, t0_s, t1_s),
        observe,
        |_, _| false,
    )
}

/// [`run`] that also stops, before stepping, as soon as `stop(pose, motion)` holds. A
/// later [`run`] from the same start to the returned time takes the very same steps, so
/// a planner that finds an event time this way and an execution replaying the schedule
/// agree exactly.
pub fn run_until(
    part: &Part,
    setup: &Setup,
    schedule: &Schedule,
    (start, t0_s, t1_s): (Pose, f64, f64),
    mut observe: impl FnMut(f64, &Pose, &Motion),
    mut stop: impl FnMut(&Pose, &Motion) -> bool,
) -> Outcome {
    let (mut t, mut pose) = (t0_s, start);
    let mut motion = Motion {
        com_mps: Vec2::default(),
        omega_radps: 0.0,
        mode: Mode::Free,
        normal_force: 0.0,
        tangential_force: 0.0,
    };
    let end = |t_s, pose, motion, failure, steps| Outcome {
        t_s,
        pose,
        motion,
        failure,
        steps,
    };
    for steps in 0..MAX_STEPS {
        if let Some(f) = check(part, setup, &pose, &schedule.at(t), t) {
            return end(t, pose, motion, Some(f), steps);
        }
        if t >= t1_s {
            return end(t, pose, motion, None, steps);
        }
        let fence = schedule.at(t);
        let touch = touching(part, &pose, &fence, setup.fence_length_m);
        motion = quasistatic::solve(part, &pose, fence, &setup.medium, &touch);
        if stop(&pose, &motion) {
            return end(t, pose, motion, None, steps);
        }
        let mut dt = step_limit(part, &motion, &fence).min(t1_s - t);
        if let Some(k) = schedule.next_knot(t) {
            dt = dt.min(k - t);
        }
        (t, pose) = step(part, setup, schedule, &pose, &motion, &touch, t, dt);
        observe(t, &pose, &motion);
    }
    end(
        t,
        pose,
        motion,
        Some(Failure::TooLong { t_s: t }),
        MAX_STEPS,
    )
}

/// One step of at most `dt`: midpoint rule for pivoting/sliding modes, shortened so no
/// free vertex passes through the fence, then projected out of the fence.
#[allow(clippy::too_many_arguments)]
fn step(
    part: &Part,
    setup: &Setup,
    schedule: &Schedule,
    pose: &Pose,
    motion: &Motion,
    touch: &[usize],
    t: f64,
    mut dt: f64,
) -> (f64, Pose) {
    let tol = CONTACT_TOL * part.radius_m;
    let exact = matches!(motion.mode, Mode::LineStick(..) | Mode::Free);
    let fence0 = schedule.at(t);
    for _ in 0..8 {
        let m = if exact {
            *motion
        } else {
            let mid = advance(pose, motion, &fence0, dt / 2.0);
            let fm = schedule.at(t + dt / 2.0);
            quasistatic::solve(part, &mid, fm, &setup.medium, touch)
        };
        let new = advance(pose, &m, &fence0, dt);
        let fence1 = schedule.at(t + dt);
        let d = distances(part, &new, &fence1);
        let worst = d
            .iter()
            .enumerate()
            .filter(|(i, (_, s))| !touch.contains(i) && *s >= 0.0 && *s <= setup.fence_length_m)
            .map(|(_, (d, _))| *d)
            .fold(f64::INFINITY, f64::min);
        if worst < -tol {
            let before = distances(part, pose, &fence0)
                .iter()
                .zip(&d)
                .filter(|((_, s), _)| *s >= 0.0 && *s <= setup.fence_length_m)
                .map(|((d0, _), (d1, _))| (d0, d1))
                .filter(|(_, d1)| **d1 < -tol)
                .map(|(d0, d1)| d0 / (d0 - d1))
                .fold(1.0, f64::min);
            dt *= before.clamp(0.05, 0.95);
            continue;
        }
        return (t + dt, project(part, &new, &fence1, setup.fence_length_m));
    }
    let new = advance(pose, motion, &fence0, dt);
    let fence1 = schedule.at(t + dt);
    (t + dt, project(part, &new, &fence1, setup.fence_length_m))
}

/// Moves the part along the fence normal so no vertex over the fence segment is behind it.
fn project(part: &Part, pose: &Pose, fence: &Fence, fence_length_m: f64) -> Pose {
    let pen = distances(part, pose, fence)
        .into_iter()
        .filter(|(_, s)| *s >= 0.0 && *s <= fence_length_m)
        .map(|(d, _)| d)
        .fold(0.0, f64::min);
    Pose {
        com_m: pose.com_m - fence.normal().scale(pen),
        angle_rad: pose.angle_rad,
    }
}

fn check(part: &Part, setup: &Setup, pose: &Pose, fence: &Fence, t: f64) -> Option<Failure> {
    let tol = CONTACT_TOL * part.radius_m;
    let xs = part.hull.iter().map(|&v| pose.to_world(v).x);
    let (lo, hi) = xs.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
        (l.min(x), h.max(x))
    });
    if hi > setup.belt_edge_m {
        return Some(Failure::OffBelt { t_s: t });
    }
    if lo < 0.0 {
        return Some(Failure::PastPivot { t_s: t });
    }
    // Resting on the fence (a vertex touching between pivot and tip) while another
    // touching vertex lies beyond the tip: the contact edge overhangs the fence's end.
    let d = distances(part, pose, fence);
    let len = setup.fence_length_m;
    let on = d
        .iter()
        .any(|(d, s)| d.abs() <= tol && (0.0..=len).contains(s));
    let over = d.iter().any(|(d, s)| d.abs() <= tol && *s > len + tol);
    (on && over).then_some(Failure::OffFenceTip { t_s: t })
}

#[cfg(test)]
mod failure_words {
    use super::Failure;

    /// A failure reads as words with its time, not as a Debug dump.
    #[test]
    fn failures_read_as_words() {
        for (f, words) in [
            (
                Failure::TooLong { t_s: 600.0 },
                "too many steps at t = 600.0000 s",
            ),
            (
                Failure::PastPivot { t_s: 1.25 },
                "line through the pivot at t = 1.2500 s",
            ),
            (Failure::OffBelt { t_s: 0.5 }, "left the belt"),
            (Failure::OffFenceTip { t_s: 0.5 }, "fence's tip"),
        ] {
            let text = f.to_string();
            assert!(text.contains(words), "{text}");
            assert!(!text.contains('{') && !text.contains("t_s"), "{text}");
        }
    }
}
