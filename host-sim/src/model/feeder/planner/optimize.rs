//! Turn and jog parameters of one edge sequence that minimize the plan's time (sec. 3.3),
//! by COBYLA (derivative-free, inequality constraints: the constraints below are only
//! piecewise smooth, and the paper's GINO is not available).
//!
//! Variables per turn k: the jog target r_k (contact radius on the old edge when the turn
//! starts) and theta-_k (theta+_k = theta-_k + Psi_k). The landing radius r'_k and drift
//! D_k follow in closed form ([`turn_landing_radius_m`]). Objective: total time, jogs by
//! the estimates [`jog_estimate_s`] (slide) and [`drift_jog_slack`] (push-and-drift) (the
//! paper: "an approximation for the time required for the jogs ... Details of the jogs
//! are planned afterwards"). Constraints, one per
//! bullet of sec. 3.3:
//! - contact radius above the minimum for every stable push (up to theta+ on the old
//!   edge, from theta- on the new one, and the jogs' tilts);
//! - fence angles within +-max (variable bounds), theta- <= 0 < theta+;
//! - the part stays on the right half of the belt (exact x range over every push arc);
//! - the contact stays within the fence length (and beyond the pivot);
//! - the fence does not touch the part while it drifts (sampled clearance, the fence
//!   leaving faster than the part, and enough drift time to drop and rise again);
//! - start and goal radii match (the first jog starts at the arrival radius, the final
//!   jog ends at the goal radius); jogs only in directions the edge can slide without
//!   tipping ([`can_jog`]) with its pushes above the minimum radius, or else move by
//!   push-and-drift within its step budget ([`drift_jog_slack`]).

use super::super::geometry::{Pose, Vec2};
use super::super::part::Part;
use super::super::primitives::{
    can_jog, drift_step_estimate_s, drop_and_catch, jog_estimate_s, jog_tilts, turn_drift_m,
    turn_landing_radius_m, turn_min_drift_s, MAX_DRIFT_STEPS, SETTLE_S,
};
use super::super::sim::Schedule;
use super::super::stability::{x_range_on_arc, ANGLE_GRID_RAD};
use super::goal::Sequence;
use super::Feeder;
use cobyla::{minimize, Func, RhoBeg, StopTols};
use std::cell::RefCell;

/// Most objective evaluations of one COBYLA run.
pub const MAX_EVALS: usize = 400;

/// Margin kept from every geometric limit (belt edge, fence ends, pivot line, minimum
/// radius, drift clearance), as a fraction of the part's radius: the optimum sits on its
/// active constraints, and the simulation must not graze them.
pub const PLAN_MARGIN: f64 = 0.05;

/// Cumulative minimum contact radii per edge for pushes at rates up to the push rate
/// ([`super::super::pushes`]), on the angle grid:
/// `up[e][i]` covers fence angles 0..i*grid, `down[e][i]` covers -i*grid..0.
#[derive(Clone, Debug)]
pub struct RadiusTable {
    up: Vec<Vec<f64>>,
    down: Vec<Vec<f64>>,
}

impl RadiusTable {
    /// Tabulates the free-rate minimum radius
    /// ([`super::super::pushes::EdgePush::min_radius_free`]) for every hull edge of `f.part`.
    pub fn new(f: &Feeder) -> Self {
        let n = (f.drive.max_angle_rad / ANGLE_GRID_RAD).ceil() as usize + 1;
        let table = |sign: f64| -> Vec<Vec<f64>> {
            (0..f.part.edges.len())
                .map(|e| {
                    let push = f.pusher(e);
                    let mut acc = 0.0f64;
                    (0..=n)
                        .map(|i| {
                            acc = acc.max(push.min_radius_free(sign * i as f64 * ANGLE_GRID_RAD));
                            acc
                        })
                        .collect()
                })
                .collect()
        };
        RadiusTable {
            up: table(1.0),
            down: table(-1.0),
        }
    }

    fn look(v: &[f64], angle: f64) -> f64 {
        let i = (angle.abs() / ANGLE_GRID_RAD).ceil() as usize;
        v.get(i).copied().unwrap_or(f64::INFINITY)
    }
    /// Minimum contact radius on `edge` for pushes over 0..`angle` (angle >= 0), m.
    pub fn up(&self, edge: usize, angle: f64) -> f64 {
        Self::look(&self.up[edge], angle)
    }
    /// Minimum contact radius on `edge` for pushes over `angle`..0 (angle <= 0), m.
    pub fn down(&self, edge: usize, angle: f64) -> f64 {
        Self::look(&self.down[edge], angle)
    }
}

/// The chosen parameters of one turn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TurnChoice {
    /// Contact radius when the turn starts (jog target), m.
    pub r_before_m: f64,
    /// theta-, rad.
    pub theta_minus_rad: f64,
    /// theta+, rad.
    pub theta_plus_rad: f64,
    /// Contact radius on the new edge, m.
    pub r_after_m: f64,
    /// Drift distance, m.
    pub drift_m: f64,
}

/// The optimum for one sequence.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// One per hop.
    pub turns: Vec<TurnChoice>,
    /// Estimated plan time (jogs estimated), s.
    pub cost_s: f64,
}

struct Ctx<'a> {
    f: &'a Feeder,
    t: &'a RadiusTable,
    seq: &'a Sequence,
    psi: Vec<f64>,
    r0: f64,
    r_goal: f64,
    bounds: Vec<(f64, f64)>,
    allow_drift: bool,
}

/// Interval of theta- for a turn of `psi`: theta- <= 0, theta+ = theta- + psi in
/// (0, max], theta- >= -max. `None` when empty.
pub fn theta_minus_bounds(max_angle: f64, psi: f64) -> Option<(f64, f64)> {
    let lo = (-max_angle).max(-psi + 1e-3);
    let hi = 0.0f64.min(max_angle - psi);
    (lo <= hi).then_some((lo, hi))
}

impl Ctx<'_> {
    fn unpack(&self, x: &[f64]) -> Vec<(f64, f64)> {
        x.chunks(2)
            .zip(self.bounds.chunks(2))
            .map(|(v, b)| {
                (
                    b[0].0 + v[0] * (b[0].1 - b[0].0),
                    b[1].0 + v[1] * (b[1].1 - b[1].0),
                )
            })
            .collect()
    }

    fn choices(&self, x: &[f64]) -> Vec<TurnChoice> {
        let p = &self.f.part;
        self.unpack(x)
            .iter()
            .enumerate()
            .map(|(k, &(r, tm))| {
                let (e, e2) = (&p.edges[self.seq.edges[k]], &p.edges[self.seq.edges[k + 1]]);
                TurnChoice {
                    r_before_m: r,
                    theta_minus_rad: tm,
                    theta_plus_rad: tm + self.psi[k],
                    r_after_m: turn_landing_radius_m(e, e2, r, self.psi[k], tm),
                    drift_m: turn_drift_m(e, e2, r, self.psi[k], tm),
                }
            })
            .collect()
    }

    /// Objective (s) and constraint values (>= 0 feasible).
    fn eval(&self, x: &[f64]) -> (f64, Cons) {
        let turns = self.choices(x);
        let (f, vb) = (self.f, self.f.setup.medium.belt_speed_mps);
        let (mut cost, mut cons) = (0.0, Vec::with_capacity(16 * turns.len() + 8));
        let mut r_prev = self.r0;
        for (k, c) in turns.iter().enumerate() {
            let e = self.seq.edges[k];
            let jog = (e, r_prev, c.r_before_m);
            cost += jog_constraints(f, self.t, jog, self.allow_drift, &mut cons);
            let to = self.seq.edges[k + 1];
            cost += f.push_time_s(e, c.r_before_m, 0.0, c.theta_plus_rad)
                + c.drift_m.max(0.0) / vb
                + f.push_time_s(to, c.r_after_m, c.theta_minus_rad, 0.0);
            turn_constraints(f, self.t, e, to, c, &mut cons);
            r_prev = c.r_after_m;
        }
        let goal = *self.seq.edges.last().unwrap_or(&0);
        let jog = (goal, r_prev, self.r_goal);
        cost += jog_constraints(f, self.t, jog, self.allow_drift, &mut cons);
        (cost, cons)
    }
}

/// Belt slack of `edge` at radius `r` over fence angles between `a` and `b`, scaled by
/// the part radius: >= 0 when the hull stays in 0 <= x <= belt edge.
pub fn belt_slack(f: &Feeder, edge: usize, r: f64, a: f64, b: f64) -> f64 {
    let (lo, hi) = x_range_on_arc(&f.part, edge, r, a, b);
    lo.min(f.setup.belt_edge_m - hi) / f.part.radius_m - PLAN_MARGIN
}

fn fence_slack(f: &Feeder, p: &Part, edge: usize, r: f64) -> f64 {
    let e = &p.edges[edge];
    (f.setup.fence_length_m - r - e.b_m()).min(r - e.a_m) / p.radius_m - PLAN_MARGIN
}

/// Named constraint values (>= 0 feasible).
pub type Cons = Vec<(&'static str, f64)>;

/// Constraints of a jog on `edge` from `from` to `to` (appended to `cons`); returns the
/// jog's estimated time, s. A direction is feasible for the slide jog (no tipping, its
/// pushes above the minimum radius) or, with `allow_drift`, for the push-and-drift jog
/// ([`drift_jog_slack`]); the estimate is the slide's where it works, else the
/// push-and-drift jog's.
pub fn jog_constraints(
    f: &Feeder,
    t: &RadiusTable,
    (edge, from, to): (usize, f64, f64),
    allow_drift: bool,
    cons: &mut Cons,
) -> f64 {
    let (p, mu, tilt) = (&f.part, f.setup.medium.fence_mu, f.drive.jog_tilt_rad);
    let e = &p.edges[edge];
    let scale = p.radius_m;
    let d = (to - from) / scale;
    let slack = 1e-4 / scale;
    let (drift, drift_s) = if allow_drift && d.abs() > slack {
        drift_jog_slack(f, t, edge, from, to)
    } else {
        (f64::NEG_INFINITY, 0.0)
    };
    let (drift_out, drift_in) = if d > 0.0 {
        (drift, f64::NEG_INFINITY)
    } else {
        (f64::NEG_INFINITY, drift)
    };
    let out = if can_jog(e, mu, true) { 1.0 } else { slack - d };
    cons.push((
        "jog: the edge cannot slide outward without tipping (nor push-and-drift)",
        or_drift(out, drift_out),
    ));
    let inward = if can_jog(e, mu, false) {
        1.0
    } else {
        slack + d
    };
    cons.push((
        "jog: the edge cannot slide inward without tipping (nor push-and-drift)",
        or_drift(inward, drift_in),
    ));
    cons.push(("jog: contact beyond the fence", fence_slack(f, p, edge, to)));
    // Inward: the tilt up is a stable push at the starting radius; outward: the return
    // from -tilt is a stable push at the final radius (some tilt of [`jog_tilts`]).
    let tilts = jog_tilts(&f.drive, mu);
    let up = tilts
        .iter()
        .map(|&a| (from - t.up(edge, a)) / scale)
        .fold(f64::NEG_INFINITY, f64::max);
    let up = d.max(up - PLAN_MARGIN);
    cons.push((
        "jog: radius below the minimum for the inward tilt (and no push-and-drift)",
        or_drift(up, drift_in),
    ));
    let down = tilts
        .iter()
        .map(|&a| (to - t.down(edge, -a)) / scale)
        .fold(f64::NEG_INFINITY, f64::max);
    let down = (-d).max(down - PLAN_MARGIN);
    cons.push((
        "jog: radius below the minimum for the outward return (and no push-and-drift)",
        or_drift(down, drift_out),
    ));
    let belt = if d.abs() > 1e-4 / scale {
        belt_slack(f, edge, from, -tilt, tilt).min(belt_slack(f, edge, to, -tilt, tilt))
    } else {
        1.0
    };
    cons.push(("jog: part off the belt", belt));
    let slide_ok = out.min(inward).min(up).min(down) >= 0.0;
    if slide_ok || drift_s == 0.0 {
        jog_estimate_s(&f.drive, f.setup.medium.belt_speed_mps, mu, to - from)
    } else {
        drift_s
    }
}

/// A slide-jog constraint value `slide`, relaxed to the push-and-drift jog's `drift` where
/// the slide fails (where it holds, the slide is what the jog does, so the value stays).
fn or_drift(slide: f64, drift: f64) -> f64 {
    if slide >= 0.0 {
        slide
    } else {
        slide.max(drift)
    }
}

/// The push-and-drift jog on `edge` from `from` to `to` (m): its slack (>= 0 when it
/// takes at most 80 % of [`MAX_DRIFT_STEPS`] steps by the sticking closed form at the
/// largest step angle the radius table allows, and the fence can drop away from the
/// part) and its estimated time, s.
pub fn drift_jog_slack(f: &Feeder, t: &RadiusTable, edge: usize, from: f64, to: f64) -> (f64, f64) {
    let e = &f.part.edges[edge];
    let outward = to > from;
    let vb = f.setup.medium.belt_speed_mps;
    let (u0, u1) = (from - e.a_m, to - e.a_m);
    let sep = (f.drive.max_rate_radps * u0.min(u1) - 1.3 * vb) / vb;
    let delta = drift_delta(f, t, edge, from.min(to), outward);
    if sep < 0.0 || delta <= 0.0 {
        return (sep.min(-1.0), 0.0);
    }
    let steps = (u1 / u0).ln().abs() / (1.0 / delta.cos()).ln();
    let cap = 0.8 * MAX_DRIFT_STEPS as f64;
    let per = drift_step_estimate_s(&f.drive, vb, e, f.part.rho_m, 0.5 * (u0 + u1), delta);
    ((cap - steps) / cap, steps.ceil().max(1.0) * per + SETTLE_S)
}

/// Largest step angle, rad, of a push-and-drift step on `edge` at radius `r_m` by the
/// radius table (the table's version of [`super::detail::drift_step_limit_rad`]).
fn drift_delta(f: &Feeder, t: &RadiusTable, edge: usize, r_m: f64, outward: bool) -> f64 {
    let cap = super::detail::drift_step_cap_rad(f, edge, outward);
    let n = (cap / ANGLE_GRID_RAD).floor() as usize;
    let mut best = 0.0;
    for i in 1..=n {
        let d = i as f64 * ANGLE_GRID_RAD;
        let need = if outward {
            t.down(edge, -d)
        } else {
            t.up(edge, d)
        };
        if need > r_m {
            break;
        }
        best = d;
    }
    best
}

/// Constraints of one turn (appended to `cons`).
pub fn turn_constraints(
    f: &Feeder,
    t: &RadiusTable,
    from: usize,
    to: usize,
    c: &TurnChoice,
    cons: &mut Cons,
) {
    let p = &f.part;
    let (vb, scale) = (f.setup.medium.belt_speed_mps, p.radius_m);
    let up = (c.r_before_m - t.up(from, c.theta_plus_rad)) / scale - PLAN_MARGIN;
    cons.push(("turn: radius below the minimum for the push to theta+", up));
    let down = (c.r_after_m - t.down(to, c.theta_minus_rad)) / scale - PLAN_MARGIN;
    cons.push((
        "turn: landing radius below the minimum for the push from theta-",
        down,
    ));
    cons.push((
        "turn: contact beyond the fence before",
        fence_slack(f, p, from, c.r_before_m),
    ));
    cons.push((
        "turn: contact beyond the fence after landing",
        fence_slack(f, p, to, c.r_after_m),
    ));
    let b1 = belt_slack(f, from, c.r_before_m, 0.0, c.theta_plus_rad);
    cons.push(("turn: part off the belt during the push to theta+", b1));
    let b2 = belt_slack(f, to, c.r_after_m, c.theta_minus_rad, 0.0);
    cons.push(("turn: part off the belt during the push from theta-", b2));
    let catch = catch_rate(f, to, c);
    let min_drift = turn_min_drift_s(&f.drive, c.theta_plus_rad, c.theta_minus_rad, catch);
    cons.push((
        "turn: drift too short to drop the fence and rise again",
        c.drift_m / vb - 1.05 * min_drift - 0.01,
    ));
    let sep = f.drive.max_rate_radps * (c.r_before_m - p.edges[from].a_m)
        - 1.2 * vb * c.theta_plus_rad.cos();
    cons.push((
        "turn: the fence cannot leave the part faster than it drifts",
        sep / (vb.abs() + 1e-12),
    ));
    let clear = drift_clearance(f, from, c, catch) / scale - PLAN_MARGIN;
    cons.push(("turn: the fence touches the part during the drift", clear));
}

/// The fence's rate at the catch of turn `c` onto `to` (the edge's slowest rate where the
/// push back has no stable one: the table's constraint reports that).
pub fn catch_rate(f: &Feeder, to: usize, c: &TurnChoice) -> f64 {
    f.catch_rate(to, c.r_after_m, c.theta_minus_rad)
        .unwrap_or_else(|| f.pusher(to).floor_radps())
}

/// Smallest distance, m, between the fence segment and the drifting part, sampled over
/// the drift (before the catch at `catch` rad/s); negative when they would touch.
pub fn drift_clearance(f: &Feeder, from: usize, c: &TurnChoice, catch: f64) -> f64 {
    let vb = f.setup.medium.belt_speed_mps;
    let mut sched = Schedule::starting(0.0, c.theta_plus_rad);
    let drift = c.drift_m.max(0.0);
    let Some(t_catch) = drop_and_catch(&mut sched, &f.drive, vb, c.theta_minus_rad, drift, catch)
    else {
        return -f.part.radius_m;
    };
    let t_rel = 0.0;
    let e = &f.part.edges[from];
    let release = Pose {
        com_m: Vec2::new(c.r_before_m, e.h_m).rotate(c.theta_plus_rad),
        angle_rad: e.part_angle_on(c.theta_plus_rad),
    };
    const N: usize = 24;
    (1..N)
        .map(|j| {
            let tau = (t_catch - t_rel) * j as f64 / N as f64;
            let fence = sched.at(t_rel + tau);
            let pose = Pose {
                com_m: release.com_m - Vec2::new(0.0, vb * tau),
                angle_rad: release.angle_rad,
            };
            let (n, tt) = (fence.normal(), fence.tangent());
            f.part
                .hull
                .iter()
                .map(|&v| pose.to_world(v))
                .filter(|w| {
                    let s = tt.dot(*w);
                    (0.0..=f.setup.fence_length_m).contains(&s)
                })
                .map(|w| n.dot(w))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Optimizes the regular turns of `seq` from arrival radius `r0` to goal radius
/// `r_goal`, jogs by sliding only or, with `allow_drift`, also by push-and-drift. When no
/// feasible parameters were found: the most violated constraint.
pub fn solve(
    f: &Feeder,
    t: &RadiusTable,
    seq: &Sequence,
    (r0, r_goal): (f64, f64),
    allow_drift: bool,
) -> Result<Solution, String> {
    let p = &f.part;
    let mut bounds = Vec::new();
    let mut psi = Vec::new();
    for w in seq.edges.windows(2) {
        let ps = p.rotation_between(w[0], w[1]);
        let (lo, hi) = theta_minus_bounds(f.drive.max_angle_rad, ps).ok_or_else(|| {
            format!(
                "a {:.0} deg turn needs fence angles beyond feeder.fence.max_angle_deg",
                ps.to_degrees()
            )
        })?;
        let e = &p.edges[w[0]];
        bounds.push((e.a_m, (f.setup.fence_length_m - e.b_m()).max(e.a_m)));
        bounds.push((lo, hi));
        psi.push(ps);
    }
    let ctx = Ctx {
        f,
        t,
        seq,
        psi,
        r0,
        r_goal,
        bounds,
        allow_drift,
    };
    if seq.hops.is_empty() {
        let (cost, cons) = ctx.eval(&[]);
        return match worst(&cons) {
            Some(w) if w.1 < -1e-9 => Err(w.0.to_string()),
            _ => Ok(Solution {
                turns: vec![],
                cost_s: cost,
            }),
        };
    }
    let x0 = greedy_start(&ctx);
    type Cached = Option<(Vec<f64>, (f64, Cons))>;
    let cache: RefCell<Cached> = RefCell::new(None);
    let eval = |x: &[f64]| -> (f64, Cons) {
        if let Some((cx, v)) = cache.borrow().as_ref() {
            if cx.as_slice() == x {
                return v.clone();
            }
        }
        let v = ctx.eval(x);
        *cache.borrow_mut() = Some((x.to_vec(), v.clone()));
        v
    };
    let x_opt = cobyla_run(&eval, &x0);
    let candidates = [x_opt, x0];
    let evals: Vec<(&Vec<f64>, (f64, Cons))> = candidates.iter().map(|x| (x, eval(x))).collect();
    let best = evals
        .iter()
        .filter(|(_, (_, c))| c.iter().all(|v| v.1 >= -1e-7))
        .min_by(|a, b| a.1 .0.total_cmp(&b.1 .0));
    match best {
        Some((x, (cost, _))) => Ok(Solution {
            turns: ctx.choices(x),
            cost_s: *cost,
        }),
        None => Err(evals
            .iter()
            .filter_map(|(_, (_, c))| worst(c))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map_or_else(
                || "no feasible parameters".into(),
                |w| format!("{} (by {:.3} part radii)", w.0, -w.1),
            )),
    }
}

/// COBYLA on the unit box from `x0`, one constraint function per named constraint; the
/// last iterate (feasible or not).
fn cobyla_run(eval: &impl Fn(&[f64]) -> (f64, Cons), x0: &[f64]) -> Vec<f64> {
    let n_cons = eval(x0).1.len();
    let cons_fns: Vec<_> = (0..n_cons)
        .map(|i| move |x: &[f64], _: &mut ()| eval(x).1[i].1)
        .collect();
    let cons: Vec<&dyn Func<()>> = cons_fns.iter().map(|c| c as &dyn Func<()>).collect();
    let unit = vec![(0.0, 1.0); x0.len()];
    let stop = StopTols {
        xtol_abs: vec![1e-5; x0.len()],
        ..StopTols::default()
    };
    let objective = |x: &[f64], _: &mut ()| eval(x).0;
    let result = minimize(
        objective,
        x0,
        &unit,
        &cons,
        (),
        MAX_EVALS,
        RhoBeg::All(0.1),
        Some(stop),
    );
    result.map(|r| r.1).unwrap_or_else(|e| e.1)
}

/// The most violated constraint.
fn worst(cons: &Cons) -> Option<(&'static str, f64)> {
    cons.iter().copied().min_by(|a, b| a.1.total_cmp(&b.1))
}

/// A feasible-leaning start: theta- splits Psi evenly (within bounds); r_k the least
/// radius meeting the lower bounds of its turn (tried over a few theta-).
fn greedy_start(ctx: &Ctx) -> Vec<f64> {
    let mut x = Vec::new();
    let mut r_prev = ctx.r0;
    for (k, b) in ctx.bounds.chunks(2).enumerate() {
        let (rb, tb) = (b[0], b[1]);
        let mut best: Option<(f64, f64, f64)> = None;
        for frac in [0.5, 0.3, 0.7, 0.1, 0.9, 0.0, 1.0] {
            let tm = tb.0 + frac * (tb.1 - tb.0);
            let r = least_radius(ctx, k, tm, r_prev).clamp(rb.0, rb.1);
            let mut probe = x.clone();
            probe.extend([(r - rb.0) / (rb.1 - rb.0).max(1e-12), frac]);
            probe.resize(ctx.bounds.len(), 0.5);
            let (_, cons) = ctx.eval(&probe);
            let worst = cons
                .iter()
                .take(16 * (k + 1))
                .fold(f64::INFINITY, |a, c| a.min(c.1));
            if best.is_none_or(|bb| worst > bb.2) {
                best = Some((r, frac, worst));
            }
        }
        let (r, frac, _) = best.unwrap_or((rb.0, 0.5, 0.0));
        x.extend([(r - rb.0) / (rb.1 - rb.0).max(1e-12), frac]);
        r_prev = ctx.choices(&{
            let mut xx = x.clone();
            xx.resize(ctx.bounds.len(), 0.5);
            xx
        })[k]
            .r_after_m;
    }
    x
}

fn least_radius(ctx: &Ctx, k: usize, tm: f64, r_prev: f64) -> f64 {
    let (f, p) = (ctx.f, &ctx.f.part);
    let (e, e2) = (&p.edges[ctx.seq.edges[k]], &p.edges[ctx.seq.edges[k + 1]]);
    let (psi, vb) = (ctx.psi[k], f.setup.medium.belt_speed_mps);
    let tp = tm + psi;
    let mut r = ctx.t.up(ctx.seq.edges[k], tp);
    r = r.max(e.a_m + 1.3 * vb * tp.cos() / f.drive.max_rate_radps);
    let d_min = vb * (1.05 * turn_min_drift_s(&f.drive, tp, tm, f.drive.push_rate_radps) + 0.02);
    r = r.max((d_min * tm.cos() - e.h_m * psi.cos() + e2.h_m) / psi.sin().max(1e-9));
    // r' = A r + B with A = cos theta+ / cos theta- > 0.
    let a = tp.cos() / tm.cos();
    let b = turn_landing_radius_m(e, e2, 0.0, psi, tm);
    r = r.max((ctx.t.down(ctx.seq.edges[k + 1], tm) * 1.001 - b) / a.max(1e-9));
    let r = r * 1.001 + 1.5 * PLAN_MARGIN * p.radius_m;
    r.max(r_prev)
}
