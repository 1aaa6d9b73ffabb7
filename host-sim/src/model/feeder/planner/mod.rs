//! The 1JOC planner (sec. 3.3): from an arrival pose to the goal edge and radius.
//!
//! 1. Simulate the arrival: the fence waits at 0, the part drifts onto it and settles on a
//!    stable edge ([`detail::arrive`]).
//! 2. Choose the goal edge as the paper does ([`goal::goal_edge`]) and the goal radius
//!    (given, or [`default_goal_radius`]).
//! 3. Consider every counter-clockwise sequence of stable edges from the start edge to the
//!    goal rotating at most 360 degrees ([`goal::sequences`]); for each, choose the turn and
//!    jog parameters minimizing the time under the constraints of sec. 3.3
//!    ([`optimize::solve`], COBYLA). A 180-degree hop between parallel stable edges is a
//!    convergent turn, whose parameters come from a small simulated search.
//! 4. Detail the best sequence into fence schedules, simulating each step from the state
//!    the previous one left ([`detail`]); if a step does not do what it should, the next
//!    sequence is tried.
//!
//! No feasible sequence is an [`FeederError::Infeasible`] naming the binding limit
//! (fence length, belt width, fence angle range, convergent turns disabled).

pub mod detail;
pub mod goal;
pub mod optimize;

use super::geometry::Pose;
use super::part::Part;
use super::primitives::{
    can_jog, jog_tilts, turn_landing_radius_m, turn_min_drift_s, Drive, Primitive, TurnPushes,
};
use super::pushes::{EdgePush, Profile};
use super::sim::{Schedule, Setup};
use super::stability::x_range_on_arc;
use super::FeederError;
use detail::{Piece, State};
use goal::{Hop, Sequence};
use optimize::{theta_minus_bounds, RadiusTable};
use serde::Serialize;

/// A part in a 1JOC cell: everything the planner and simulator need.
#[derive(Clone, Debug, PartialEq)]
pub struct Feeder {
    /// The part.
    pub part: Part,
    /// Belt, fence friction and dimensions.
    pub setup: Setup,
    /// Fence rates and angle limits.
    pub drive: Drive,
}

impl Feeder {
    /// The stable pushes of hull edge `edge` under this feeder's drive and medium.
    pub fn pusher(&self, edge: usize) -> EdgePush<'_> {
        EdgePush {
            edge: &self.part.edges[edge],
            rho_m: self.part.rho_m,
            omega_max_radps: self.drive.push_rate_radps,
            v_b_mps: self.setup.medium.belt_speed_mps,
            mu: self.setup.medium.fence_mu,
        }
    }

    /// The rate profile of a counter-clockwise stable push of hull edge `edge` at contact
    /// radius `r_m` from `from_rad` to `to_rad` ([`EdgePush::profile`]); `None` when some
    /// angle has no stable rate up to the push rate.
    pub fn push_profile(
        &self,
        edge: usize,
        r_m: f64,
        from_rad: f64,
        to_rad: f64,
    ) -> Option<Profile> {
        self.pusher(edge).profile(r_m, from_rad, to_rad)
    }

    /// The fence's rate as it meets `edge` at radius `r_m` at `theta_minus` (the first
    /// cell of the push back to 0); `None` when that push has no stable rate there.
    pub fn catch_rate(&self, edge: usize, r_m: f64, theta_minus: f64) -> Option<f64> {
        self.pusher(edge).start_rate(r_m, theta_minus, 0.0)
    }

    /// Estimated time of a stable push of `edge` at `r_m` from `from_rad` to `to_rad`, s
    /// ([`EdgePush::time_estimate_s`]).
    pub fn push_time_s(&self, edge: usize, r_m: f64, from_rad: f64, to_rad: f64) -> f64 {
        self.pusher(edge).time_estimate_s(r_m, from_rad, to_rad)
    }

    /// The pushes of a turn from `from` at radius `r_m` up to `theta_plus` onto `to`,
    /// landing at `r2_m` and pushed back from `theta_minus`; `Err` names the push without a
    /// stable rate.
    pub fn turn_pushes(
        &self,
        (from, r_m, theta_plus): (usize, f64, f64),
        (to, r2_m, theta_minus): (usize, f64, f64),
    ) -> Result<TurnPushes, String> {
        let up = self
            .push_profile(from, r_m, 0.0, theta_plus)
            .ok_or_else(|| format!("no stable push of edge {from} to theta+ at r = {r_m:.4} m"))?;
        let back = self
            .push_profile(to, r2_m, theta_minus, 0.0)
            .ok_or_else(|| format!("no stable push of edge {to} from theta- at r = {r2_m:.4} m"))?;
        let catch_rate = back.first().map_or(self.drive.push_rate_radps, |b| b.1);
        Ok(TurnPushes {
            up,
            catch_rate,
            back,
        })
    }
}

/// Planner switches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanOptions {
    /// Allow the convergent turn (default true; false shows the feed fails without it).
    pub allow_convergent: bool,
    /// Goal contact radius, m; `None`: [`default_goal_radius`].
    pub goal_radius_m: Option<f64>,
    /// Most sequences optimized.
    pub max_sequences: usize,
    /// Longest the arrival may take to settle, s.
    pub max_arrival_s: f64,
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            allow_convergent: true,
            goal_radius_m: None,
            max_sequences: 64,
            max_arrival_s: 600.0,
        }
    }
}

/// A feeding plan for one arrival pose.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Plan {
    /// Stable edge the arriving part settles on.
    pub start_edge: usize,
    /// Goal edge.
    pub goal_edge: usize,
    /// Goal contact radius, m.
    pub goal_radius_m: f64,
    /// The primitives in order, with their parameters.
    pub steps: Vec<Primitive>,
    /// The whole fence schedule (from t = 0, when the part is at its arrival pose).
    pub schedule: Schedule,
    /// Planned duration of the feed, s.
    pub duration_s: f64,
    /// Contact radius the plan predicts at the end, m.
    pub predicted_radius_m: f64,
}

/// Default goal radius on `goal`, m, within the window of radii the fence, the belt and
/// the jogs allow: a quarter of the way up it if the edge can be jogged both ways (the
/// inward jog's tilt is a stable push needing [`RadiusTable::up`]; the outward jog's
/// return one needing [`RadiusTable::down`]; both need [`can_jog`]), near its top if
/// only outward, at its bottom if only inward.
pub fn default_goal_radius(f: &Feeder, t: &RadiusTable, goal: usize) -> f64 {
    let e = &f.part.edges[goal];
    let (tilt, pad) = (f.drive.jog_tilt_rad, 0.5 * f.part.radius_m);
    let hi_fence = f.setup.fence_length_m - e.b_m() - pad;
    let hi_belt = f.setup.belt_edge_m - (x_range_on_arc(&f.part, goal, 0.0, -tilt, tilt).1) - pad;
    let hi = hi_fence.min(hi_belt);
    let mu = f.setup.medium.fence_mu;
    let tilts = jog_tilts(&f.drive, f.setup.medium.fence_mu);
    let up = tilts
        .iter()
        .map(|&a| t.up(goal, a))
        .fold(f64::INFINITY, f64::min)
        + pad;
    let down = tilts
        .iter()
        .map(|&a| t.down(goal, -a))
        .fold(f64::INFINITY, f64::min)
        + pad;
    // The part must stay right of the pivot line x = 0 through the jog's tilts: every hull
    // point's x is r cos(theta) plus its x at r = 0, so x >= r cos(tilt) + lo_0.
    let lo_0 = x_range_on_arc(&f.part, goal, 0.0, -tilt, tilt).0;
    let base = (e.a_m + pad).max((pad - lo_0) / tilt.cos());
    let out_ok = can_jog(e, mu, true) && down.max(base) < hi;
    let in_ok = can_jog(e, mu, false) && up.max(base) < hi;
    match (out_ok, in_ok) {
        (true, true) => {
            let lo = up.max(down).max(base);
            lo + 0.25 * (hi - lo)
        }
        (true, false) => {
            let lo = down.max(base);
            lo + 0.9 * (hi - lo)
        }
        (false, true) => up.max(base),
        (false, false) => 0.5 * (base + hi),
    }
}

/// Plans the feed of the part arriving at `arrival` (fence at 0 from t = 0).
pub fn plan(f: &Feeder, arrival: Pose, opts: &PlanOptions) -> Result<Plan, FeederError> {
    let (st, catch, sched) =
        detail::arrive(f, arrival, opts.max_arrival_s).map_err(FeederError::Infeasible)?;
    let table = RadiusTable::new(f);
    let goal = goal::goal_edge(&f.part)
        .ok_or_else(|| FeederError::Infeasible("the part has no stable edge".into()))?;
    let r_goal = opts
        .goal_radius_m
        .unwrap_or_else(|| default_goal_radius(f, &table, goal));
    let seqs = goal::sequences(
        &f.part,
        st.edge,
        goal,
        opts.allow_convergent,
        opts.max_sequences,
    );
    let mut solved: Vec<(f64, &Sequence, Vec<Piece>)> = Vec::new();
    let mut why = Vec::new();
    for seq in &seqs {
        if solved.iter().any(|s| s.0 <= seq.hops.len() as f64 * 0.0) {
            break;
        }
        match build(f, &table, seq, &st, r_goal) {
            Ok(pieces) => {
                let t_end = pieces.last().map_or(st.t_s, |p| p.0.t_s);
                solved.push((t_end, seq, pieces));
            }
            Err(e) => why.push(e),
        }
    }
    let best = solved.into_iter().min_by(|a, b| a.0.total_cmp(&b.0));
    let Some((_, _, pieces)) = best else {
        return Err(FeederError::Infeasible(diagnose(
            f, &table, &st, goal, r_goal, &seqs, opts, &why,
        )));
    };
    Ok(assemble(st, catch, sched, goal, r_goal, pieces))
}

fn assemble(
    st: State,
    catch: Primitive,
    mut schedule: Schedule,
    goal: usize,
    r_goal: f64,
    pieces: Vec<Piece>,
) -> Plan {
    let mut steps = vec![catch];
    let mut last = st;
    for (s, prim, sch) in pieces {
        schedule.extend(&sch);
        steps.push(prim);
        last = s;
    }
    Plan {
        start_edge: st.edge,
        goal_edge: goal,
        goal_radius_m: r_goal,
        steps,
        duration_s: schedule.end_s(),
        schedule,
        predicted_radius_m: last.r_m,
    }
}

/// Optimizes and details one sequence into pieces.
fn build(
    f: &Feeder,
    t: &RadiusTable,
    seq: &Sequence,
    st: &State,
    r_goal: f64,
) -> Result<Vec<Piece>, String> {
    if let [Hop::Convergent { via }] = seq.hops.as_slice() {
        return convergent(f, t, st, seq.edges[1], *via, r_goal);
    }
    // Slide jogs first (the plans of parts whose edges all slide are unchanged by the
    // push-and-drift jog), then with push-and-drift jogs allowed.
    detail_sequence(f, t, seq, st, r_goal, false).or_else(|slide| {
        detail_sequence(f, t, seq, st, r_goal, true)
            .map_err(|drift| format!("{slide}; with push-and-drift jogs: {drift}"))
    })
}

/// Optimizes `seq` (jogs by sliding only, or also by push-and-drift with `allow_drift`)
/// and details it into pieces.
fn detail_sequence(
    f: &Feeder,
    t: &RadiusTable,
    seq: &Sequence,
    st: &State,
    r_goal: f64,
    allow_drift: bool,
) -> Result<Vec<Piece>, String> {
    let sol = optimize::solve(f, t, seq, (st.r_m, r_goal), allow_drift)
        .map_err(|e| format!("sequence {:?}: {e}", seq.edges))?;
    let mut pieces = Vec::new();
    let mut cur = *st;
    for (k, c) in sol.turns.iter().enumerate() {
        if (c.r_before_m - cur.r_m).abs() > 5.0 * detail::JOG_TOL_M {
            let p = detail::jog(f, &cur, c.r_before_m)?;
            cur = p.0;
            pieces.push(p);
        }
        let to = seq.edges[k + 1];
        let p = detail::turn(f, &cur, to, to, c.theta_minus_rad, false)?;
        cur = p.0;
        pieces.push(p);
    }
    finish(f, cur, r_goal, &mut pieces)?;
    Ok(pieces)
}

fn finish(f: &Feeder, cur: State, r_goal: f64, pieces: &mut Vec<Piece>) -> Result<(), String> {
    if (r_goal - cur.r_m).abs() > detail::JOG_TOL_M {
        pieces.push(detail::jog(f, &cur, r_goal)?);
    }
    Ok(())
}

/// Least contact radius on `from` for a turn catching `catch` at `tm` (push, separation
/// and drift-time bounds), m.
fn turn_lower_radius(f: &Feeder, t: &RadiusTable, from: usize, catch: usize, tm: f64) -> f64 {
    let p = &f.part;
    let (e, e2) = (&p.edges[from], &p.edges[catch]);
    let psi = p.rotation_between(from, catch);
    let (tp, vb) = (tm + psi, f.setup.medium.belt_speed_mps);
    let d_min = vb * (1.05 * turn_min_drift_s(&f.drive, tp, tm, f.drive.push_rate_radps) + 0.02);
    let by_drift = (d_min * tm.cos() - e.h_m * psi.cos() + e2.h_m) / psi.sin().max(1e-9);
    t.up(from, tp)
        .max(e.a_m + 1.3 * vb * tp.cos() / f.drive.max_rate_radps)
        .max(by_drift)
}

/// The convergent turn's parameters by a small simulated search: catch angles across
/// their range, contact radii from the least workable up; the fastest that ends on `to`.
fn convergent(
    f: &Feeder,
    t: &RadiusTable,
    st: &State,
    to: usize,
    via: usize,
    r_goal: f64,
) -> Result<Vec<Piece>, String> {
    let psi1 = f.part.rotation_between(st.edge, via);
    let (lo, hi) = theta_minus_bounds(f.drive.max_angle_rad, psi1)
        .ok_or("convergent turn: catch angle out of range")?;
    let mut best: Option<(f64, Vec<Piece>)> = None;
    let mut last_err = String::from("convergent turn: no catch angle worked");
    for frac in [0.5, 0.25, 0.75, 0.0, 1.0] {
        let tm = lo + frac * (hi - lo);
        let need = turn_lower_radius(f, t, st.edge, via, tm);
        for mult in [1.05, 1.4, 2.0] {
            match convergent_try(f, st, to, via, tm, (need * mult).max(st.r_m), r_goal) {
                Ok(pieces) => {
                    let t_end = pieces.last().map_or(st.t_s, |p| p.0.t_s);
                    if best.as_ref().is_none_or(|b| t_end < b.0) {
                        best = Some((t_end, pieces));
                    }
                    break;
                }
                Err(e) => last_err = e,
            }
        }
    }
    best.map(|b| b.1).ok_or(last_err)
}

fn convergent_try(
    f: &Feeder,
    st: &State,
    to: usize,
    via: usize,
    tm: f64,
    r: f64,
    r_goal: f64,
) -> Result<Vec<Piece>, String> {
    let e = &f.part.edges[st.edge];
    if r + e.b_m() > f.setup.fence_length_m {
        return Err("convergent turn: fence too short".into());
    }
    let mut pieces = Vec::new();
    let mut cur = *st;
    if r > cur.r_m + 5.0 * detail::JOG_TOL_M {
        let p = detail::jog(f, &cur, r)?;
        cur = p.0;
        pieces.push(p);
    }
    let p = detail::turn(f, &cur, via, to, tm, true)?;
    cur = p.0;
    pieces.push(p);
    finish(f, cur, r_goal, &mut pieces)?;
    Ok(pieces)
}

/// Least fence length and belt half width, m, a sequence needs: over each turn, the
/// least radius meeting the push, separation, drift-time and landing bounds, for the
/// best of a few catch angles (r' = A r + B, A = cos theta+ / cos theta-); and the goal
/// edge's jog tilts.
fn sequence_needs(f: &Feeder, t: &RadiusTable, seq: &Sequence, goal: usize) -> (f64, f64) {
    let p = &f.part;
    let (mut fence, mut belt) = (0.0f64, 0.0f64);
    for w in seq.edges.windows(2) {
        let (e, e2) = (&p.edges[w[0]], &p.edges[w[1]]);
        let psi = p.rotation_between(w[0], w[1]);
        let Some((a, b)) = theta_minus_bounds(f.drive.max_angle_rad, psi) else {
            return (f64::INFINITY, f64::INFINITY);
        };
        let best = (0..=4)
            .map(|i| a + (b - a) * f64::from(i) / 4.0)
            .map(|tm| {
                let tp = tm + psi;
                let (aa, bb) = (
                    tp.cos() / tm.cos(),
                    turn_landing_radius_m(e, e2, 0.0, psi, tm),
                );
                let r = turn_lower_radius(f, t, w[0], w[1], tm)
                    .max((t.down(w[1], tm) - bb) / aa.max(1e-9));
                let r2 = aa * r + bb;
                let need = (r + e.b_m()).max(r2 + e2.b_m());
                let x = x_range_on_arc(p, w[0], r, 0.0, tp)
                    .1
                    .max(x_range_on_arc(p, w[1], r2, tm, 0.0).1);
                (need, x)
            })
            .fold((f64::INFINITY, f64::INFINITY), |acc, v| {
                if v.0 < acc.0 {
                    v
                } else {
                    acc
                }
            });
        fence = fence.max(best.0);
        belt = belt.max(best.1);
    }
    let (g, tilt) = (&p.edges[goal], f.drive.jog_tilt_rad);
    fence = fence.max(t.up(goal, tilt).min(t.down(goal, -tilt)) + g.b_m());
    (fence, belt)
}

/// Names the binding limit when no sequence is feasible.
#[allow(clippy::too_many_arguments)]
fn diagnose(
    f: &Feeder,
    t: &RadiusTable,
    st: &State,
    goal: usize,
    r_goal: f64,
    seqs: &[Sequence],
    opts: &PlanOptions,
    why: &[String],
) -> String {
    let p = &f.part;
    let deg = |r: f64| r.to_degrees();
    if seqs.is_empty() {
        let psi = p.rotation_between(st.edge, goal);
        if !opts.allow_convergent && goal::has_parallel_pair(p) {
            return format!("the part settled on edge {} and the goal edge {goal} is 180 deg away: that needs a convergent turn, which is disabled", st.edge);
        }
        return format!(
            "no sequence of turns reaches goal edge {goal} from edge {} ({:.0} deg)",
            st.edge,
            deg(psi)
        );
    }
    let g = &p.edges[goal];
    let (lo, hi) = (g.a_m, f.setup.fence_length_m - g.b_m());
    if !(lo..=hi).contains(&r_goal) {
        return format!(
            "feeder.goal.contact_radius_m = {} m is outside the fence's range [{lo:.4}, {hi:.4}] m for goal edge {goal}",
            metres(r_goal)
        );
    }
    let (mut need_fence, mut need_belt) = (f64::INFINITY, f64::INFINITY);
    for seq in seqs {
        let (fence, belt) = sequence_needs(f, t, seq, goal);
        need_fence = need_fence.min(fence);
        need_belt = need_belt.min(belt);
    }
    if need_fence.is_infinite() {
        return format!("every sequence from edge {} to goal edge {goal} needs a turn beyond feeder.fence.max_angle_deg = {:.1}", st.edge, deg(f.drive.max_angle_rad));
    }
    if need_fence > f.setup.fence_length_m {
        return format!("fence too short: the minimum contact radius for the stable pushes needs feeder.fence.length_m >= {need_fence:.3} m (it is {:.3} m)", f.setup.fence_length_m);
    }
    if need_belt > f.setup.belt_edge_m {
        return format!("belt too narrow: at the minimum contact radius the part reaches x = {need_belt:.3} m, beyond the belt's half width {:.3} m (feeder.belt.width_m >= {:.3} m needed)", f.setup.belt_edge_m, 2.0 * need_belt);
    }
    format!(
        "no sequence from edge {} to goal edge {goal} satisfied every constraint ({})",
        st.edge,
        why.join("; ")
    )
}

/// A length for a message: four decimals, or four significant digits in exponent form when
/// that would be long or show nothing (1e300 m, 1e-9 m).
fn metres(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e4).contains(&v.abs()) {
        format!("{v:.4e}")
    } else {
        format!("{v:.4}")
    }
}
