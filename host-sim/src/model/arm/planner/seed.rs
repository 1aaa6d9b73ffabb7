//! Initial guesses by shooting. SQP finds a local optimum near its start (sec. 2.4), and
//! a start whose phase times disagree with what its trajectory does to the object (a
//! roll planned at a time the object does not roll) is far from feasible. So each guess
//! is a trajectory shape from a small family (windup, swing, duration, end), played
//! against the object by the verifier with unlimited friction; the phase times are read
//! off the events it finds, and mu off the peak friction ratio. Shapes whose events match
//! the task's phases are ranked (throws by how close the flight passes the goal, then by
//! friction) and the best become the starts.

use super::super::motion::{ArmMotion, PlannedMotion, RestMove};
use super::super::simulate::{execute_with, Execution, SimOptions};
use super::super::task::TaskKind;
use super::evaluate::Problem;
use super::layout::End;

/// One member of the shape family.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Shape {
    duration_s: f64,
    peak_at: f64,
    windup_rad: f64,
    swing_rad: f64,
    sign: f64,
    rest_fraction: f64,
}

fn bump(u: f64, centre: f64, width: f64) -> f64 {
    (-((u - centre) / width).powi(2)).exp()
}

fn smoothstep(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

/// All control points of a shape (the first three at the start angle).
fn points(problem: &Problem, kind: TaskKind, s: &Shape) -> Vec<f64> {
    let l = &problem.layout;
    let n = l.knots;
    let (lo, hi) = l.angle_bounds;
    let mut p: Vec<f64> = (0..n)
        .map(|i| {
            if i < 3 {
                return l.start_rad;
            }
            let u = (i - 2) as f64 / (n - 3) as f64;
            let dip = -s.windup_rad * bump(u, 0.2, 0.15);
            let q = match (kind.throws(), l.end) {
                (true, _) => dip + s.swing_rad * u * u,
                (false, End::Fixed(a)) => {
                    dip + s.swing_rad * bump(u, s.peak_at, 0.25)
                        + s.sign * (a - l.start_rad) * smoothstep(1.4 * u)
                }
                (false, _) => {
                    dip + s.swing_rad * bump(u, s.peak_at, 0.25)
                        + s.rest_fraction * s.swing_rad * smoothstep(1.4 * u)
                }
            };
            (l.start_rad + s.sign * q).clamp(lo + 1e-3, hi - 1e-3)
        })
        .collect();
    // the layout's end: at rest means the last three points are equal
    let end = match l.end {
        End::Free => None,
        End::Rest(elo, ehi) => Some(p[n - 1].clamp(elo, ehi)),
        End::Fixed(a) => Some(a),
    };
    if let Some(e) = end {
        for v in &mut p[n - 3..] {
            *v = e;
        }
    }
    p
}

/// The family: durations x swing peaks x windups x swings x directions x ends
/// (1,800 shapes; throws use one peak position, ending at rest matters only with a free
/// end angle).
fn family(throws: bool, free_end: bool) -> Vec<Shape> {
    let mut v = Vec::new();
    let peaks: &[f64] = if throws { &[1.0] } else { &[0.4, 0.55, 0.7] };
    let rests: &[f64] = if free_end { &[0.0, 0.3, 0.6] } else { &[0.0] };
    for duration_s in [0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.3] {
        for &peak_at in peaks {
            for windup_rad in [0.0, 0.15, 0.3, 0.5] {
                for swing_rad in [0.3, 0.5, 0.7, 1.0, 1.4] {
                    for sign in [1.0, -1.0] {
                        for &rest_fraction in rests {
                            v.push(Shape {
                                duration_s,
                                peak_at,
                                windup_rad,
                                swing_rad,
                                sign,
                                rest_fraction,
                            });
                        }
                    }
                }
            }
        }
    }
    v
}

fn first(e: &Execution, kind: &str) -> Option<f64> {
    e.events.iter().find(|x| x.kind == kind).map(|x| x.t_s)
}

/// The start of the roll under way at `t` (the last roll start before it), if that roll
/// goes the task's way.
fn roll_start_before(e: &Execution, t: f64, dir: f64) -> Option<f64> {
    let want = if dir > 0.0 {
        "roll_start_ccw"
    } else {
        "roll_start_cw"
    };
    let last = e
        .events
        .iter()
        .rfind(|x| x.kind.starts_with("roll_start") && x.t_s < t)?;
    (last.kind == want).then_some(last.t_s)
}

/// Phase times read off an execution, and a score (lower is better), if its events fit
/// the task.
fn times(problem: &Problem, e: &Execution, total_s: f64) -> Option<(Vec<f64>, f64)> {
    let sys = problem.sys;
    let ratio = e.peak_friction_ratio;
    match sys.task.kind {
        TaskKind::Snatch => e
            .executed
            .eq(&super::super::simulate::Executed::Ok)
            .then(|| (vec![total_s], ratio)),
        TaskKind::Roll => {
            let re = first(e, "roll_end")?;
            let rs = roll_start_before(e, re, sys.task.roll_dir)?;
            let ok = e.executed == super::super::simulate::Executed::Ok && re < total_s;
            ok.then(|| (vec![rs, re - rs, total_s - re], ratio))
        }
        TaskKind::Throw | TaskKind::RollingThrow | TaskKind::ThrowCatch => {
            let rel = first(e, "release")?;
            let rolled = roll_start_before(e, rel, sys.task.roll_dir)
                .filter(|&t| !e.events.iter().any(|x| x.kind == "roll_back" && x.t_s > t));
            let landed_before = first(e, "roll_end").is_some_and(|t| t < rel);
            let (dist, tf) = closest_pass(problem, e)?;
            let score = dist / sys.task.goal?.tolerance_m + ratio;
            match (sys.task.kind, rolled) {
                (TaskKind::Throw | TaskKind::ThrowCatch, None) => Some((vec![rel, tf], score)),
                (TaskKind::RollingThrow, Some(rs)) if !landed_before => {
                    Some((vec![rs, rel - rs, tf], score))
                }
                _ => None,
            }
        }
    }
}

/// How close the free flight from the release passes the goal, m, and when, s.
fn closest_pass(problem: &Problem, e: &Execution) -> Option<(f64, f64)> {
    let s0 = e.release?;
    let goal = problem.sys.task.goal?;
    let g = problem.sys.rig.gravity_mps2;
    (1..=300)
        .map(|k| {
            let t = 0.01 * k as f64;
            let s = s0.flown(t, g);
            let d = s
                .com
                .minus(super::super::geometry::V2::new(goal.x_m, goal.y_m))
                .norm();
            (d, t)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

/// Up to `count` starting design vectors, best first.
pub fn seeds(problem: &Problem, count: usize) -> Vec<Vec<f64>> {
    let sys = problem.sys;
    let kind = sys.task.kind;
    let l = &problem.layout;
    let opt = SimOptions {
        step_s: 1e-3,
        record: false,
    };
    let (tmin, tmax) = l.time_bounds;
    let mut found: Vec<(f64, Vec<f64>)> = Vec::new();
    for shape in family(kind.throws(), matches!(l.end, End::Rest(..))) {
        let pts = points(problem, kind, &shape);
        let segment_s = shape.duration_s / (l.knots - 3) as f64;
        let m = PlannedMotion::new(pts.clone(), segment_s, &sys.rest_move());
        let e = execute_with(sys, &m, f64::INFINITY, opt);

        let Some((ts, mut score)) = times(problem, &e, shape.duration_s) else {
            continue;
        };
        if let Some(c) = sys.task.catch {
            // a catch: prefer a release whose brake alone would stop near the catching
            // angle (a short move there, and the object clear of the arm's way back)
            let rest = RestMove {
                catch_angle_rad: None,
                ..sys.rest_move()
            };
            let brake = PlannedMotion::new(pts.clone(), segment_s, &rest);
            score += (brake.joint(brake.settled_s()).angle_rad - c.angle_rad).abs() / 0.02;
        }

        // clamping a grasp or roll time would rescale the spline and change its events;
        // the flight time is the spline's business only through the goal
        let phases = l.phases.iter();
        let moving_ok = phases
            .zip(&ts)
            .all(|(p, t)| *p == super::super::task::Phase::Flight || (tmin..=tmax).contains(t));
        if !moving_ok {
            continue;
        }
        let ts: Vec<f64> = ts.iter().map(|t| t.clamp(tmin, tmax)).collect();
        let mu = (1.02 * e.peak_friction_ratio).min(l.mu_max);
        found.push((score, l.encode(&pts, &ts, mu)));
    }
    found.sort_by(|a, b| a.0.total_cmp(&b.0));
    found.into_iter().take(count).map(|(_, x)| x).collect()
}
