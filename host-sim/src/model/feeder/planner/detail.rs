//! Turning a sequence's parameters into fence schedules, each checked (and, for jogs and
//! convergent turns, tuned) by simulating the mechanics from the state the previous step
//! left: what the execution will do, noise aside.

use super::super::geometry::{Pose, Vec2};
use super::super::primitives::{
    drift_landing_limit_rad, drift_pivot_limit_rad, drift_rest_limit_rad, jog_tilts,
    slide_speed_mps, turn_drift_m, turn_landing_radius_m, turn_schedule, Primitive, TurnPushes,
    MAX_DRIFT_STEPS, SETTLE_S,
};
use super::super::pushes::extend;
use super::super::quasistatic::{Mode, Motion};
use super::super::sim::{flush_edge, run, run_until, Schedule};
use super::super::stability::ANGLE_GRID_RAD;
use super::Feeder;
use std::cell::Cell;

/// The part at rest, flush on the fence at angle 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State {
    /// Time, s.
    pub t_s: f64,
    /// Pose.
    pub pose: Pose,
    /// Hull edge on the fence.
    pub edge: usize,
    /// Contact radius, m (the COM's x, the fence being at 0).
    pub r_m: f64,
}

/// Radius tolerance of a planned jog, m (well inside the 1 mm feeding tolerance).
pub const JOG_TOL_M: f64 = 2e-5;

/// A planned piece: its primitive, schedule and the state it leaves.
pub type Piece = (State, Primitive, Schedule);

/// Simulates `sched` from `st` to its end; the resulting rest state, or why not.
pub fn settle_on(f: &Feeder, st: &State, sched: &Schedule) -> Result<State, String> {
    let out = run(
        &f.part,
        &f.setup,
        sched,
        st.pose,
        st.t_s,
        sched.end_s(),
        |_, _, _| {},
    );
    if let Some(fail) = out.failure {
        return Err(fail.to_string());
    }
    let fence = sched.at(out.t_s);
    let edge = flush_edge(&f.part, &out.pose, &fence, f.setup.fence_length_m)
        .ok_or("part not flush on the fence")?;
    Ok(State {
        t_s: out.t_s,
        pose: out.pose,
        edge,
        r_m: out.pose.com_m.x,
    })
}

/// Whether `m` is the part at rest flush on a fence at rest.
fn resting(m: &Motion) -> bool {
    matches!(m.mode, Mode::LineStick(..)) && m.com_mps.norm() < 1e-9 && m.omega_radps.abs() < 1e-9
}

/// The arriving part drifts onto the fence held at 0 and settles: simulated until it is
/// at rest flush on an edge (at most `max_s`), stopping at the exact step the execution
/// will reach too ([`run_until`]).
pub fn arrive(f: &Feeder, arrival: Pose, max_s: f64) -> Result<Piece, String> {
    let mut sched = Schedule::starting(0.0, 0.0);
    let resting = |_: &Pose, m: &Motion| resting(m);
    let out = run_until(
        &f.part,
        &f.setup,
        &sched,
        (arrival, 0.0, max_s),
        |_, _, _| {},
        resting,
    );
    if let Some(fail) = out.failure {
        return Err(format!("arrival: {fail}"));
    }
    if !resting(&out.pose, &out.motion) {
        return Err(format!(
            "arrival: the part did not come to rest on the fence within {max_s} s"
        ));
    }
    let (t, pose) = (out.t_s, out.pose);
    let fence = sched.at(t);
    let edge =
        flush_edge(&f.part, &pose, &fence, f.setup.fence_length_m).ok_or("arrival: not flush")?;
    sched.hold(t);
    let st = State {
        t_s: t,
        pose,
        edge,
        r_m: pose.com_m.x,
    };
    let prim = Primitive::Catch {
        edge,
        contact_radius_m: st.r_m,
        duration_s: t,
    };
    Ok((st, prim, sched))
}

/// Schedule of a jog from `st` with tilt `tilt` (> 0 inward) held `hold_s`, ending near
/// `target_m`: the tilt up (inward) is a stable push at the starting radius, the return
/// from -tilt (outward) one at the target radius, each with its rate profile
/// ([`Feeder::push_profile`]); the moves down are slow enough for the part to follow.
fn jog_schedule(
    f: &Feeder,
    st: &State,
    tilt: f64,
    hold_s: f64,
    target_m: f64,
) -> Result<Schedule, String> {
    let e = &f.part.edges[st.edge];
    let vb = f.setup.medium.belt_speed_mps;
    // A fence turning down keeps the part in contact while omega (r + b) < v_b cos tilt.
    let reach = st.r_m.max(target_m) + e.b_m() + f.part.radius_m;
    let down = f.drive.push_rate_radps.min(0.5 * vb * tilt.cos() / reach);
    let no_push = |r: f64| format!("jog on edge {}: no stable push at r = {r:.4} m", st.edge);
    let mut s = Schedule::starting(st.t_s, 0.0);
    if tilt > 0.0 {
        let up = f
            .push_profile(st.edge, st.r_m, 0.0, tilt)
            .ok_or_else(|| no_push(st.r_m))?;
        extend(&mut s, &up);
        s.hold(hold_s);
        s.move_to(0.0, down);
    } else {
        let back = f
            .push_profile(st.edge, target_m, tilt, 0.0)
            .ok_or_else(|| no_push(target_m))?;
        s.move_to(tilt, down);
        s.hold(hold_s);
        extend(&mut s, &back);
    }
    s.hold(SETTLE_S);
    Ok(s)
}

/// A simulated jog outcome: the rest state and the schedule.
type Tried = Result<(State, Schedule), String>;

/// Plans a jog from `st` to radius `target_m` on the same edge: the slide jog
/// ([`slide_jog`]) where it works, else the paper's push-and-drift jog ([`drift_jog`]).
pub fn jog(f: &Feeder, st: &State, target_m: f64) -> Result<Piece, String> {
    slide_jog(f, st, target_m).or_else(|slide| {
        drift_jog(f, st, target_m).map_err(|drift| format!("{slide}; push-and-drift: {drift}"))
    })
}

/// Plans the slide jog from `st` to radius `target_m` on the same edge: for each tilt of
/// [`jog_tilts`] (steepest first, the ones the optimizer allowed for), the hold time by a
/// secant iteration on simulated outcomes; failing those, the steepest tilt bisected with
/// no hold (for changes smaller than the tilt alone makes).
pub fn slide_jog(f: &Feeder, st: &State, target_m: f64) -> Result<Piece, String> {
    let dr = target_m - st.r_m;
    let outcome = |tilt: f64, hold: f64| -> Tried {
        let s = jog_schedule(f, st, tilt, hold, target_m)?;
        let end = settle_on(f, st, &s)?;
        if end.edge != st.edge {
            return Err(format!(
                "jog tipped the part from edge {} to {}",
                st.edge, end.edge
            ));
        }
        Ok((end, s))
    };
    let sign = if dr < 0.0 { 1.0 } else { -1.0 };
    let mut best = None;
    for t in jog_tilts(&f.drive, f.setup.medium.fence_mu) {
        let tilt = sign * t;
        let Ok(b) = outcome(tilt, 0.0) else { continue };
        if (b.0.r_m - target_m) * dr.signum() >= 0.0 {
            break; // the tilt alone reaches: bisect the tilt below
        }
        let speed = slide_speed_mps(f.setup.medium.belt_speed_mps, f.setup.medium.fence_mu, tilt);
        let Ok((hold, b)) = secant_hold(&outcome, b, tilt, target_m, speed) else {
            continue;
        };
        let done = (b.0.r_m - target_m).abs() <= 25.0 * JOG_TOL_M;
        best = Some((tilt, hold, b));
        if done {
            break;
        }
    }
    let reached = |b: &Option<(f64, f64, (State, Schedule))>| {
        b.as_ref()
            .is_some_and(|b| (b.2 .0.r_m - target_m).abs() <= 25.0 * JOG_TOL_M)
    };
    if !reached(&best) {
        let tilt = sign * f.drive.jog_tilt_rad;
        if let Some((t, b)) = bisect_tilt(&outcome, tilt, target_m, dr) {
            if reached(&Some((t, 0.0, b.clone()))) || best.is_none() {
                best = Some((t, 0.0, b));
            }
        }
    }
    let (tilt_used, hold, best) =
        best.ok_or_else(|| format!("jog on edge {} found no workable tilt", st.edge))?;
    let (end, sched) = best;
    if (end.r_m - target_m).abs() > 25.0 * JOG_TOL_M {
        return Err(format!(
            "jog on edge {} missed its radius by {:.2e} m",
            st.edge,
            end.r_m - target_m
        ));
    }
    let prim = Primitive::Jog {
        edge: st.edge,
        tilt_rad: tilt_used,
        hold_s: hold,
        from_radius_m: st.r_m,
        to_radius_m: end.r_m,
        duration_s: end.t_s - st.t_s,
    };
    Ok((end, prim, sched))
}

/// The tilt alone falls short: slide longer, secant on the hold time from the first
/// guess |remaining| / slide speed.
fn secant_hold(
    outcome: &impl Fn(f64, f64) -> Tried,
    at_zero: (State, Schedule),
    tilt: f64,
    target_m: f64,
    speed: f64,
) -> Result<(f64, (State, Schedule)), String> {
    let mut prev = (0.0, at_zero.0.r_m - target_m);
    let mut hold = (target_m - at_zero.0.r_m).abs() / speed;
    let mut best = (0.0, at_zero);
    for _ in 0..8 {
        let b = outcome(tilt, hold)?;
        let err = b.0.r_m - target_m;
        best = (hold, b);
        if err.abs() < JOG_TOL_M {
            break;
        }
        let slope = (err - prev.1) / (hold - prev.0);
        prev = (hold, err);
        hold = (hold - err / slope).max(0.0);
    }
    Ok(best)
}

/// The tilt alone overshoots (or slides off the fence): bisect the tilt with no hold.
fn bisect_tilt(
    outcome: &impl Fn(f64, f64) -> Tried,
    tilt: f64,
    target_m: f64,
    dr: f64,
) -> Option<(f64, (State, Schedule))> {
    let (mut lo, mut hi) = (0.0, tilt.abs());
    let mut best = None;
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        match outcome(mid * tilt.signum(), 0.0) {
            Ok(b) => {
                let err = b.0.r_m - target_m;
                if err * dr.signum() > 0.0 {
                    hi = mid
                } else {
                    lo = mid
                }
                best = Some((mid * tilt.signum(), b));
                if err.abs() < JOG_TOL_M {
                    break;
                }
            }
            Err(_) => hi = mid,
        }
    }
    best
}

/// A turn (or, with `via`, a convergent turn) from `st` onto `to_edge` with catch angle
/// `theta_minus`, whose catch lands on `catch_edge` (= `to_edge` for a plain turn).
pub fn turn(
    f: &Feeder,
    st: &State,
    catch_edge: usize,
    to_edge: usize,
    theta_minus: f64,
    via: bool,
) -> Result<Piece, String> {
    let p = &f.part;
    let vb = f.setup.medium.belt_speed_mps;
    let psi = p.rotation_between(st.edge, catch_edge);
    let tp = theta_minus + psi;
    let d = turn_drift_m(
        &p.edges[st.edge],
        &p.edges[catch_edge],
        st.r_m,
        psi,
        theta_minus,
    );
    let pushes = if via {
        let up = f
            .push_profile(st.edge, st.r_m, 0.0, tp)
            .ok_or("convergent turn: no stable push to theta+")?;
        TurnPushes {
            up,
            ..TurnPushes::fixed(f.drive.push_rate_radps, tp)
        }
    } else {
        let r2 = turn_landing_radius_m(
            &p.edges[st.edge],
            &p.edges[catch_edge],
            st.r_m,
            psi,
            theta_minus,
        );
        f.turn_pushes((st.edge, st.r_m, tp), (catch_edge, r2, theta_minus))?
    };
    let (sched, _) = turn_schedule(st.t_s, &f.drive, vb, theta_minus, d, &pushes)
        .ok_or("no time to drop the fence and rise again")?;
    let end = settle_on(f, st, &sched)?;
    if end.edge != to_edge {
        return Err(format!(
            "turn from edge {} ended on edge {} instead of {to_edge}",
            st.edge, end.edge
        ));
    }
    let duration_s = end.t_s - st.t_s;
    let prim = if via {
        Primitive::ConvergentTurn {
            from_edge: st.edge,
            via_edge: catch_edge,
            to_edge,
            theta_plus_rad: tp,
            theta_minus_rad: theta_minus,
            from_radius_m: st.r_m,
            to_radius_m: end.r_m,
            duration_s,
        }
    } else {
        Primitive::Turn {
            from_edge: st.edge,
            to_edge,
            theta_plus_rad: tp,
            theta_minus_rad: theta_minus,
            from_radius_m: st.r_m,
            to_radius_m: end.r_m,
            duration_s,
        }
    };
    Ok((end, prim, sched))
}

/// Longest a push-and-drift step waits for the part to land and settle, s.
const MAX_REST_S: f64 = 120.0;

/// Runs `sched` (its moves done, the fence then held) from `pose` at `t_s` until the part
/// rests flush on the fence, stopping at the exact step the execution will reach too
/// ([`run_until`]); the schedule is extended by the hold up to that instant.
fn rest_after(
    f: &Feeder,
    (pose, t_s): (Pose, f64),
    mut sched: Schedule,
) -> Result<(Pose, Schedule), String> {
    let moves_end = sched.end_s();
    let mut probe = sched.clone();
    probe.hold(MAX_REST_S);
    let now = Cell::new(t_s);
    let out = run_until(
        &f.part,
        &f.setup,
        &probe,
        (pose, t_s, probe.end_s()),
        |t, _, _| now.set(t),
        |_, m| now.get() >= moves_end && resting(m),
    );
    if let Some(fail) = out.failure {
        return Err(format!("push-and-drift step: {fail}"));
    }
    if !resting(&out.motion) || out.t_s < moves_end {
        return Err(format!(
            "push-and-drift step: the part did not land and settle within {MAX_REST_S} s"
        ));
    }
    sched.hold(out.t_s - moves_end);
    Ok((out.pose, sched))
}

/// One push-and-drift step from `st` (flush at fence angle 0), simulated: `angle` > 0 is
/// an inward step (stable push 0 -> angle, the fence drops back to 0 at its top rate,
/// the part drifts onto it and settles), `angle` < 0 an outward one (the fence drops to
/// `angle` at its top rate, the part drifts onto it and settles, stable push back to 0,
/// the settle hold); see [`super::super::primitives`].
pub fn drift_step(f: &Feeder, st: &State, angle: f64) -> Result<(State, Schedule), String> {
    let no_push = |r: f64| {
        format!(
            "push-and-drift step on edge {}: no stable push at r = {r:.4} m",
            st.edge
        )
    };
    let mut s = Schedule::starting(st.t_s, 0.0);
    let sched = if angle > 0.0 {
        let up = f
            .push_profile(st.edge, st.r_m, 0.0, angle)
            .ok_or_else(|| no_push(st.r_m))?;
        extend(&mut s, &up);
        s.move_to(0.0, f.drive.max_rate_radps);
        rest_after(f, (st.pose, st.t_s), s)?.1
    } else {
        s.move_to(angle, f.drive.max_rate_radps);
        let (landed, mut s) = rest_after(f, (st.pose, st.t_s), s)?;
        let r_landed = landed.com_m.dot(Vec2::from_angle(angle));
        let back = f
            .push_profile(st.edge, r_landed, angle, 0.0)
            .ok_or_else(|| no_push(r_landed))?;
        extend(&mut s, &back);
        s.hold(SETTLE_S);
        s
    };
    let end = settle_on(f, st, &sched)?;
    if end.edge != st.edge {
        return Err(format!(
            "push-and-drift step tipped the part from edge {} to {}",
            st.edge, end.edge
        ));
    }
    Ok((end, sched))
}

/// The bound on a push-and-drift step's angle on `edge` before any push is checked, rad:
/// the jog tilt, the fence's angle range, the landing on the start vertex
/// ([`drift_landing_limit_rad`]), and outward the rest at -delta
/// ([`drift_rest_limit_rad`]), inward the turn back onto the edge
/// ([`drift_pivot_limit_rad`]).
pub(super) fn drift_step_cap_rad(f: &Feeder, edge: usize, outward: bool) -> f64 {
    let e = &f.part.edges[edge];
    let side = if outward {
        drift_rest_limit_rad(e, f.setup.medium.fence_mu)
    } else {
        drift_pivot_limit_rad(e)
    };
    f.drive
        .jog_tilt_rad
        .min(f.drive.max_angle_rad)
        .min(drift_landing_limit_rad(&f.part, edge))
        .min(side)
}

/// Largest step angle, rad (a multiple of the angle grid, at most the jog tilt), of a
/// push-and-drift step on `edge` at contact radius `r_m`: outward, the part must rest at
/// -delta ([`drift_rest_limit_rad`]) and be pushed back from there; inward, pushed from 0
/// to delta and turn back onto the edge as it lands ([`drift_pivot_limit_rad`]). 0 when
/// none. Pushes are stable at larger radii too, so `r_m` is the least
/// radius the steps see (the start of an outward jog, the end of an inward one). Every
/// step also lands on the edge's start vertex ([`drift_landing_limit_rad`]).
pub fn drift_step_limit_rad(f: &Feeder, edge: usize, r_m: f64, outward: bool) -> f64 {
    let cap = drift_step_cap_rad(f, edge, outward);
    let n = (cap / ANGLE_GRID_RAD).floor() as usize;
    let mut best = 0.0;
    for i in 1..=n {
        let d = i as f64 * ANGLE_GRID_RAD;
        let ok = if outward {
            f.push_profile(edge, r_m, -d, 0.0).is_some()
        } else {
            f.push_profile(edge, r_m, 0.0, d).is_some()
        };
        if !ok {
            break;
        }
        best = d;
    }
    best
}

/// Plans the push-and-drift jog from `st` to `target_m`: steps of equal closed-form ratio
/// (at most [`drift_step_limit_rad`]), each simulated from the state the last one left,
/// then a last step whose angle is tuned by a secant on its simulated outcome.
pub fn drift_jog(f: &Feeder, st: &State, target_m: f64) -> Result<Piece, String> {
    let e = &f.part.edges[st.edge];
    let outward = target_m > st.r_m;
    let (u0, ut) = (st.r_m - e.a_m, target_m - e.a_m);
    let vb = f.setup.medium.belt_speed_mps;
    if f.drive.max_rate_radps * u0.min(ut) < 1.3 * vb {
        return Err(format!(
            "the fence cannot drop away from the part this near the pivot (r = {:.4} m)",
            st.r_m.min(target_m)
        ));
    }
    let dmax = drift_step_limit_rad(f, st.edge, st.r_m.min(target_m), outward);
    if dmax <= 0.0 {
        return Err(format!("no stable push-and-drift step on edge {}", st.edge));
    }
    let sign = if outward { -1.0 } else { 1.0 };
    let mut cur = *st;
    let mut sched = Schedule::starting(st.t_s, 0.0);
    let mut angles = Vec::new();
    while angles.len() < MAX_DRIFT_STEPS && (target_m - cur.r_m) * sign < -JOG_TOL_M {
        let u = cur.r_m - e.a_m;
        // The closed form's cos delta for the whole remaining change, split evenly.
        let ratio = if outward { u / ut } else { ut / u };
        let steps_left = ((1.0 / ratio).ln().abs() / (1.0 / dmax.cos()).ln())
            .ceil()
            .max(1.0);
        let delta = ratio
            .clamp(0.0, 1.0)
            .powf(1.0 / steps_left)
            .acos()
            .min(dmax);
        let (next, s, d) = if steps_left <= 1.0 {
            last_drift_step(f, &cur, sign, delta, dmax, target_m)?
        } else {
            let (n, s) = drift_step(f, &cur, sign * delta)?;
            (n, s, delta)
        };
        if (next.r_m - cur.r_m) * (target_m - st.r_m) <= 0.0 {
            return Err(format!(
                "a push-and-drift step on edge {} did not move the part toward r = {target_m:.4} m",
                st.edge
            ));
        }
        sched.extend(&s);
        angles.push(sign * d);
        cur = next;
    }
    if (cur.r_m - target_m).abs() > 25.0 * JOG_TOL_M {
        return Err(format!(
            "push-and-drift jog on edge {} ended {:.2e} m from its radius after {} steps",
            st.edge,
            cur.r_m - target_m,
            angles.len()
        ));
    }
    let prim = Primitive::DriftJog {
        edge: st.edge,
        step_angles_rad: angles,
        from_radius_m: st.r_m,
        to_radius_m: cur.r_m,
        duration_s: cur.t_s - st.t_s,
    };
    Ok((cur, prim, sched))
}

/// The step expected to finish the jog: its angle by a secant on the simulated end
/// radius from the closed form's `delta0` (within `(0, dmax]`).
fn last_drift_step(
    f: &Feeder,
    cur: &State,
    sign: f64,
    delta0: f64,
    dmax: f64,
    target_m: f64,
) -> Result<(State, Schedule, f64), String> {
    let e = &f.part.edges[cur.edge];
    let err = |d: f64| -> Result<(f64, (State, Schedule)), String> {
        let out = drift_step(f, cur, sign * d)?;
        Ok((out.0.r_m - target_m, out))
    };
    let mut best = err(delta0)?;
    let mut best_d = delta0;
    let (mut d0, mut e0) = (delta0, best.0);
    // Second point: the closed form aimed past the miss.
    let aim = target_m - e0;
    let want = if sign < 0.0 {
        (cur.r_m - e.a_m) / (aim - e.a_m)
    } else {
        (aim - e.a_m) / (cur.r_m - e.a_m)
    };
    let mut d1 = want.clamp(0.0, 1.0).acos().clamp(1e-6, dmax);
    for _ in 0..8 {
        if best.0.abs() < JOG_TOL_M || (d1 - d0).abs() < 1e-12 {
            break;
        }
        let Ok((e1, out)) = err(d1) else { break };
        if e1.abs() < best.0.abs() {
            best = (e1, out);
            best_d = d1;
        }
        let slope = (e1 - e0) / (d1 - d0);
        (d0, e0) = (d1, e1);
        if slope == 0.0 || !slope.is_finite() {
            break;
        }
        d1 = (d1 - e1 / slope).clamp(1e-6, dmax);
    }
    Ok((best.1 .0, best.1 .1, best_d))
}
