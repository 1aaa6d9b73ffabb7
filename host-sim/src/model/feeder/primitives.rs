//! The 1JOC primitives of sec. 3.1 / fig. 7 as fence schedules, and the closed forms
//! behind them.
//!
//! The extracted paper lost fig. 7; what follows is our realization, consistent with the
//! text of sec. 3.1-3.3 and derived with the mechanics of [`super::quasistatic`].
//!
//! - **Stable push**: the fence turns with an edge flush; the part moves rigidly with it
//!   (contact radius unchanged). The rate is chosen angle by angle inside the window of
//!   stable rates, at most the push rate omega_p ([`super::pushes`]): the radius must be
//!   above the free-rate minimum there.
//! - **Turn** (from stable edge e to stable edge e', counter-clockwise rotation Psi of the
//!   part, 0 < Psi < 180 deg): stable push 0 -> theta+; the fence drops away at its top
//!   rate; the part drifts in -y; the fence, rising again (at the new edge's push rate at
//!   theta-), meets it exactly when edge e' (now at angle theta+ - Psi) lies on the fence
//!   line, so
//!   **theta- = theta+ - Psi** and e' lands flush ("caught at theta-"); stable push
//!   theta- -> 0. A single turn can rotate the part by less than 180 deg only, since
//!   theta+ < 90 deg and theta- > -90 deg: that is why the paper needs another primitive
//!   for 180 deg. Closed forms ([`turn_drift_m`], [`turn_landing_radius_m`]): with the
//!   COM at fence coordinates (r, h) on e and height h' above e',
//!
//!   ```text
//!   D  = (r sin Psi + h cos Psi - h') / cos theta-           (drift distance, m)
//!   r' = r cos Psi - h sin Psi - D sin theta-                (contact radius on e')
//!   ```
//!
//!   (the COM after the push is `R(theta+)(r, h)`; after drifting D it must sit h' above
//!   the line at theta-, and r' is its coordinate along that line).
//! - **Convergent turn** (parallel stable edges e, e', Psi = 180 deg): a turn whose catch
//!   lands flush on an *unstable* hull edge u between them that tips counter-clockwise;
//!   as the fence pushes on toward 0 the part tips over u's start vertex and converges
//!   onto e'. Its outcome is found by simulation.
//! - **Jog** (change r on one edge without changing the part's angle), two kinds:
//!   - the **slide jog** ([`Primitive::Jog`]): the fence tilts to +-theta_j beyond the
//!     friction angle atan mu and holds; the part slides along it, toward the pivot at
//!     +theta_j, away at -theta_j, at `s = v_b (sin theta_j - mu cos theta_j)`
//!     ([`slide_speed_mps`], derived in the mechanics tests), then the fence returns to 0.
//!     Sliding keeps the edge flush only if the resultant, which meets the fence mu h
//!     from the COM's foot on the down-slope side, stays on the edge ([`can_jog`]).
//!   - the **push-and-drift jog** ([`Primitive::DriftJog`]), the paper's: "a sequence of
//!     small stable pushes interleaved with drift". Derivation below; the planner uses it
//!     where the slide jog cannot move the part (the slide would tip it, or its pushes
//!     need a larger radius).
//!
//! ## The push-and-drift jog (ours; the condensed paper gives the idea only)
//!
//! Three facts of the mechanics of [`super::quasistatic`]:
//!
//! 1. A **stable push** turns the part rigidly with the fence: every fence coordinate,
//!    the contact radius r included, is unchanged.
//! 2. **Drift** translates the part by `(0, -v_b t)`: every point keeps its world x. A
//!    point on the fence line at angle theta has fence coordinate `x / cos theta`.
//! 3. **Landing.** A part released flush at fence angle theta1 and caught by the fence at
//!    theta2 < theta1 (the fence is below the drifting part, so it can only meet it at
//!    a smaller angle) first touches the edge's **start vertex** (the fence is turned
//!    clockwise relative to the edge, by less than the exterior angle at that vertex:
//!    [`drift_landing_limit_rad`]), which lies at fence coordinate `u = r - a` while
//!    the edge is flush. The fence's force acts at the vertex, so only the belt's drag
//!    through the COM turns the part about it, clockwise onto the edge iff the COM lies
//!    beyond the vertex in world x: `a cos theta1 - h sin theta1 > 0`, i.e.
//!    `tan theta1 < a / h` (else it turns onto the previous edge;
//!    [`drift_pivot_limit_rad`]). Solving eq. (1) of
//!    [`super::quasistatic`] for a point stick at the vertex (fence at rest, COM at fence
//!    coordinates q = (a, h) from the vertex, `J_a = rho^2 + a^2 + h^2`,
//!    `s2, c2 = sin, cos theta2`):
//!
//!    ```text
//!    Omega = v_b (h s2 - a c2) / J_a   (< 0: onto the edge)
//!    F_t = v_b ((rho^2 + a^2) s2 + a h c2) / J_a,   F_n = v_b (a h s2 + (rho^2 + h^2) c2) / J_a
//!    ```
//!
//!    so the vertex **sticks** while `|F_t| <= mu F_n` ([`landing_sticks`]; at theta2 = 0:
//!    `a h <= mu (rho^2 + h^2)`), and then it keeps its world x through the drift and
//!    its fence coordinate through the pivot.
//!
//! Hence one step, released at theta1 and caught at theta2, maps `u = r - a` to
//!
//! ```text
//! u' = u cos theta1 / cos theta2                 ([`drift_step_radius_m`])
//! ```
//!
//! (the vertex's x, `u cos theta1`, read on the fence at theta2). With the fence at 0
//! before and after, two steps do the job without changing the part's angle:
//!
//! - **inward** (release at +delta, catch at 0): stable push 0 -> delta, the fence drops
//!   back to 0 at its top rate, the part drifts onto it: `u' = u cos delta`;
//! - **outward** (release at 0, catch at -delta): the fence drops to -delta at its top
//!   rate, the part drifts onto it and settles flush at -delta, stable push -delta -> 0:
//!   `u' = u / cos delta`.
//!
//! Both change r by a second-order amount, `|Δr| ≈ u delta^2 / 2` per step, so a jog is
//! a sequence of steps (`ln(u_goal / u) / ln(1 / cos delta)` of them). A sliding landing
//! (`F_t > mu F_n`) slips the vertex toward the pivot (F_t > 0 for theta2 near 0), by an
//! amount first order in delta: it adds to an inward step and eats into an outward one;
//! the planner simulates every step and tunes the last one's delta, so what it plans is
//! what the mechanics do.
//!
//! **Where the steps are stable.** The inward step needs a stable push from 0 to delta
//! at the current radius and, released at delta, a landing that turns the part back onto
//! the edge, `tan delta < a / h` (the outward step releases at 0, where that holds on
//! every stable edge): with the slowest rates of
//! [`super::pushes::EdgePush::floor_radps`] every stable edge can be pushed off theta = 0
//! at every radius, so inward steps exist for small delta on every stable edge. The outward step needs the part to **rest** flush
//! at -delta (the window of [`super::pushes::window`] holds omega = 0:
//! `tan delta <= k min(mu, b / h)`, the friction cone and the resultant, which meets the
//! fence h tan delta beyond the COM's foot, before the end vertex) and a stable push
//! back. That too exists for small delta on every stable edge (b > 0), so **every stable
//! edge whose landing sticks can be jogged both ways from every radius** (with the fence
//! dropping away faster than the part drifts: `omega_max u > v_b`), the paper's "Any
//! stable push may be preceded by jogs to move the object out to the minimum contact
//! radius". Where the landing slips, an outward step gains only where `u delta^2 / 2`
//! beats the (first-order) slip: at large u and wide delta. The other price is speed: an edge whose COM foot lies b from its end vertex at height h steps out by at
//! most `tan delta = k b / h`, a relative gain `≈ (k b / h)^2 / 2` per step (part 44 of the
//! feeding sweep: b = 0.57 mm, h = 31 mm, 1.4e-4 per step); the planner caps the steps
//! ([`MAX_DRIFT_STEPS`]) and such parts turn off that edge directly instead, with slow
//! pushes.

use super::part::{HullEdge, Part};
use super::pushes::{extend, profile_time_s, Profile};
use super::sim::Schedule;
use super::stability::PUSH_MARGIN;
use serde::Serialize;

/// Fence angle run-up before a catch, rad (3 degrees): the fence is already rising at
/// the push rate when the part's new edge meets it.
pub const CATCH_RUN_UP_RAD: f64 = 0.05;

/// Hold at angle 0 that ends every turn and jog, s: the part is at rest on the fence
/// before the next primitive starts (with theta- = 0 the catch is the turn's last
/// instant, and without the hold the next push would start as the part lands).
pub const SETTLE_S: f64 = 0.05;

/// Fence motion limits and the belt's speed: what a schedule may command.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Drive {
    /// omega_p, fence rate during stable pushes and catches, rad/s (> 0).
    pub push_rate_radps: f64,
    /// Fence rate while dropping away from a drifting part, rad/s (>= push rate).
    pub max_rate_radps: f64,
    /// Largest |fence angle|, rad (< pi/2).
    pub max_angle_rad: f64,
    /// Fence tilt during a jog's slide, rad (> atan mu).
    pub jog_tilt_rad: f64,
}

/// One step of a feeding plan, with its parameters (serialized into the summary's
/// `plan`).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "primitive", rename_all = "snake_case")]
pub enum Primitive {
    /// The fence waits at 0 while the arriving part drifts onto it and settles.
    Catch {
        /// Hull edge the part settles on.
        edge: usize,
        /// Contact radius after settling, m.
        contact_radius_m: f64,
        /// Duration, s.
        duration_s: f64,
    },
    /// Slide along the tilted fence: changes the contact radius on `edge`.
    Jog {
        /// Hull edge in contact.
        edge: usize,
        /// Fence tilt during the slide, rad (> 0 moves the part toward the pivot).
        tilt_rad: f64,
        /// Time the tilt is held, s.
        hold_s: f64,
        /// Contact radius before, m.
        from_radius_m: f64,
        /// Contact radius after (planned), m.
        to_radius_m: f64,
        /// Duration, s.
        duration_s: f64,
    },
    /// The paper's jog: push-and-drift steps changing the contact radius on `edge`
    /// (module doc).
    DriftJog {
        /// Hull edge in contact.
        edge: usize,
        /// Each step's angle, rad: > 0 an inward step released at that angle, < 0 an
        /// outward step caught at it.
        step_angles_rad: Vec<f64>,
        /// Contact radius before, m.
        from_radius_m: f64,
        /// Contact radius after (planned), m.
        to_radius_m: f64,
        /// Duration, s.
        duration_s: f64,
    },
    /// Stable push to theta+, drift, catch at theta-, stable push back to 0.
    Turn {
        /// Edge before.
        from_edge: usize,
        /// Edge after.
        to_edge: usize,
        /// theta+, rad.
        theta_plus_rad: f64,
        /// theta-, rad.
        theta_minus_rad: f64,
        /// Contact radius before, m.
        from_radius_m: f64,
        /// Contact radius after (planned), m.
        to_radius_m: f64,
        /// Duration, s.
        duration_s: f64,
    },
    /// A turn caught on unstable edge `via_edge` that tips onto `to_edge` (180 deg).
    ConvergentTurn {
        /// Edge before.
        from_edge: usize,
        /// The unstable hull edge the catch lands on.
        via_edge: usize,
        /// Edge after.
        to_edge: usize,
        /// theta+, rad.
        theta_plus_rad: f64,
        /// theta-, rad (catch angle on `via_edge`).
        theta_minus_rad: f64,
        /// Contact radius before, m.
        from_radius_m: f64,
        /// Contact radius after (planned), m.
        to_radius_m: f64,
        /// Duration, s.
        duration_s: f64,
    },
}

impl Primitive {
    /// The primitive's name as serialized (`catch`, `jog`, `drift_jog`, `turn`,
    /// `convergent_turn`).
    pub fn name(&self) -> &'static str {
        match self {
            Primitive::Catch { .. } => "catch",
            Primitive::Jog { .. } => "jog",
            Primitive::DriftJog { .. } => "drift_jog",
            Primitive::Turn { .. } => "turn",
            Primitive::ConvergentTurn { .. } => "convergent_turn",
        }
    }
    /// Duration, s.
    pub fn duration_s(&self) -> f64 {
        match self {
            Primitive::Catch { duration_s, .. }
            | Primitive::Jog { duration_s, .. }
            | Primitive::DriftJog { duration_s, .. }
            | Primitive::Turn { duration_s, .. }
            | Primitive::ConvergentTurn { duration_s, .. } => *duration_s,
        }
    }
}

/// Drift distance D, m, of a turn (see the module doc); `psi` = Psi, rad.
pub fn turn_drift_m(from: &HullEdge, to: &HullEdge, r_m: f64, psi: f64, theta_minus: f64) -> f64 {
    (r_m * psi.sin() + from.h_m * psi.cos() - to.h_m) / theta_minus.cos()
}

/// Contact radius r' on the new edge after a turn, m (see the module doc).
pub fn turn_landing_radius_m(
    from: &HullEdge,
    to: &HullEdge,
    r_m: f64,
    psi: f64,
    theta_minus: f64,
) -> f64 {
    let d = turn_drift_m(from, to, r_m, psi, theta_minus);
    r_m * psi.cos() - from.h_m * psi.sin() - d * theta_minus.sin()
}

/// The pushes of a turn: the profile up from 0 to theta+ (on the old edge, at the radius
/// before the turn), the fence's rate as it meets the part at theta- (`catch_rate`), and the
/// profile back from theta- to 0 (on the new edge, at the landing radius); see
/// [`super::pushes`].
#[derive(Clone, Debug, PartialEq)]
pub struct TurnPushes {
    /// `(angle, rate)` segments from 0 to theta+.
    pub up: Profile,
    /// Fence rate at the catch, rad/s (> 0).
    pub catch_rate: f64,
    /// `(angle, rate)` segments from theta- to 0.
    pub back: Profile,
}

impl TurnPushes {
    /// Every push at the fixed rate `omega`.
    pub fn fixed(omega: f64, theta_plus: f64) -> Self {
        Self {
            up: vec![(theta_plus, omega)],
            catch_rate: omega,
            back: vec![(0.0, omega)],
        }
    }
}

/// Fence schedule of a (convergent) turn from `t0` starting at fence angle 0, for drift
/// distance `drift_m`; `None` when the fence cannot drop away and rise again within the
/// drift time. Returns the schedule and the catch time.
pub fn turn_schedule(
    t0: f64,
    drive: &Drive,
    v_b: f64,
    theta_minus: f64,
    drift_m: f64,
    pushes: &TurnPushes,
) -> Option<(Schedule, f64)> {
    let mut s = Schedule::starting(t0, 0.0);
    extend(&mut s, &pushes.up);
    let t_catch = drop_and_catch(&mut s, drive, v_b, theta_minus, drift_m, pushes.catch_rate)?;
    extend(&mut s, &pushes.back);
    s.hold(SETTLE_S);
    Some((s, t_catch))
}

/// From the release (the end of `s`, at theta+): the fence drops at its top rate to just
/// below theta-, waits, and rises at `catch_rate` to meet the part at theta- after it has
/// drifted `drift_m`. Returns the catch time; `None` when there is no time for that.
pub fn drop_and_catch(
    s: &mut Schedule,
    drive: &Drive,
    v_b: f64,
    theta_minus: f64,
    drift_m: f64,
    catch_rate: f64,
) -> Option<f64> {
    let t_catch = s.end_s() + drift_m / v_b;
    let run_up = catch_run_up(drive, theta_minus);
    s.move_to(theta_minus - run_up, drive.max_rate_radps);
    let rise_start = t_catch - run_up / catch_rate;
    if s.end_s() > rise_start + 1e-12 {
        return None;
    }
    s.hold(rise_start - s.end_s());
    s.move_to(theta_minus, catch_rate);
    Some(t_catch)
}

/// Fence angle run-up before a catch at `theta_minus`, rad.
fn catch_run_up(drive: &Drive, theta_minus: f64) -> f64 {
    CATCH_RUN_UP_RAD
        .min(theta_minus + drive.max_angle_rad)
        .max(0.0)
}

/// Least drift time, s, for the fence to drop from theta+ and rise again to theta- at
/// `catch_rate`.
pub fn turn_min_drift_s(drive: &Drive, theta_plus: f64, theta_minus: f64, catch_rate: f64) -> f64 {
    let run_up = catch_run_up(drive, theta_minus);
    (theta_plus - theta_minus + run_up) / drive.max_rate_radps + run_up / catch_rate
}

/// Duration of a turn, s: push up, drift, push back.
pub fn turn_duration_s(v_b: f64, theta_minus: f64, drift_m: f64, pushes: &TurnPushes) -> f64 {
    profile_time_s(0.0, &pushes.up) + drift_m / v_b + profile_time_s(theta_minus, &pushes.back)
}

/// Slide speed along a fence held at `tilt_rad` (|tilt| > atan mu), m/s.
pub fn slide_speed_mps(v_b: f64, mu: f64, tilt_rad: f64) -> f64 {
    v_b * (tilt_rad.abs().sin() - mu * tilt_rad.cos())
}

/// Whether `edge` can slide without tipping: outward (`outward`, fence tilted down) the
/// resultant meets the fence mu h beyond the COM's foot, inward mu h before it; it must
/// stay on the edge with [`PUSH_MARGIN`].
pub fn can_jog(edge: &HullEdge, mu: f64, outward: bool) -> bool {
    let room = if outward { edge.b_m() } else { edge.a_m };
    mu * edge.h_m < (1.0 - PUSH_MARGIN) * room
}

/// The jog tilts tried, steepest first: the configured tilt, then 60 % and 30 % of the
/// way from the friction angle atan mu to it. A gentler tilt slides slower but its
/// return push (from -tilt back to 0, outward jogs) and tilt push (inward) need smaller
/// contact radii.
pub fn jog_tilts(drive: &Drive, mu: f64) -> [f64; 3] {
    let fa = mu.atan();
    let t = drive.jog_tilt_rad;
    [t, fa + 0.6 * (t - fa), fa + 0.3 * (t - fa)]
}

/// Approximate duration of a jog changing the radius by `dr_m`, s: the planner's
/// estimate (tilt out and back at the push rate, then slide); 0 for no jog.
pub fn jog_estimate_s(drive: &Drive, v_b: f64, mu: f64, dr_m: f64) -> f64 {
    let s = slide_speed_mps(v_b, mu, drive.jog_tilt_rad);
    let overhead = 2.0 * drive.jog_tilt_rad / drive.push_rate_radps;
    overhead * (dr_m.abs() / 1e-3).min(1.0) + dr_m.abs() / s
}

/// Most steps of one push-and-drift jog (bounds its time and the planner's work).
pub const MAX_DRIFT_STEPS: usize = 100;

/// Contact radius after one push-and-drift step with a sticking landing, m: `edge` flush
/// at contact radius `r_m` is released at fence angle `release_rad` and caught flush at
/// `catch_rad` (< `release_rad`): `a + (r - a) cos(release) / cos(catch)` (module doc).
pub fn drift_step_radius_m(edge: &HullEdge, r_m: f64, release_rad: f64, catch_rad: f64) -> f64 {
    edge.a_m + (r_m - edge.a_m) * release_rad.cos() / catch_rad.cos()
}

/// Whether the start vertex of `edge` sticks as the part, landed on it, turns onto the
/// edge over a fence at rest at `catch_rad` (support rho `rho_m`, fence friction `mu`):
/// `|(rho^2 + a^2) s + a h c| <= mu (a h s + (rho^2 + h^2) c)` (module doc).
pub fn landing_sticks(edge: &HullEdge, rho_m: f64, mu: f64, catch_rad: f64) -> bool {
    let (s, c) = catch_rad.sin_cos();
    let (a, h, r2) = (edge.a_m, edge.h_m, rho_m * rho_m);
    ((r2 + a * a) * s + a * h * c).abs() <= mu * (a * h * s + (r2 + h * h) * c)
}

/// Fraction of the exterior angle at an edge's start vertex a push-and-drift step may
/// tilt the edge against the fence.
pub const DRIFT_LANDING_FRACTION: f64 = 0.8;

/// Widest push-and-drift step, rad, for the landing to be on the start vertex of hull
/// edge `edge`: a step tilts the edge by its angle against the catching fence, and past
/// the exterior angle at that vertex (the turn from the previous hull edge) the previous
/// edge would meet the fence first and the part land on it; [`DRIFT_LANDING_FRACTION`] of
/// that angle.
pub fn drift_landing_limit_rad(part: &Part, edge: usize) -> f64 {
    let n = part.edges.len();
    DRIFT_LANDING_FRACTION * part.rotation_between(edge, (edge + n - 1) % n)
}

/// Widest release angle, rad, of an inward push-and-drift step of `edge` for the landed
/// part to turn back onto the edge: the COM must lie beyond the start vertex in world x,
/// `tan delta < a / h`; with the margin, `atan(k a / h)`, `k = 1 -` [`PUSH_MARGIN`]
/// (module doc).
pub fn drift_pivot_limit_rad(edge: &HullEdge) -> f64 {
    ((1.0 - PUSH_MARGIN) * edge.a_m / edge.h_m).max(0.0).atan()
}

/// Steepest angle, rad, of a push-and-drift step of `edge` the fence may rest the part
/// at (outward steps): `atan(k min(mu, b / h))`, `k = 1 -` [`PUSH_MARGIN`] (module doc).
pub fn drift_rest_limit_rad(edge: &HullEdge, mu: f64) -> f64 {
    ((1.0 - PUSH_MARGIN) * mu.min(edge.b_m() / edge.h_m))
        .max(0.0)
        .atan()
}

/// Estimated duration of one push-and-drift step of angle `delta` at `u = r - a`, s: the
/// fence's drop at its top rate, the drift `u tan delta` (to the vertex's landing), the
/// pivot at `|Omega| = v_b a / J_a` through delta, and the push at the push rate.
pub fn drift_step_estimate_s(
    drive: &Drive,
    v_b: f64,
    edge: &HullEdge,
    rho_m: f64,
    u_m: f64,
    delta: f64,
) -> f64 {
    let j = rho_m * rho_m + edge.a_m * edge.a_m + edge.h_m * edge.h_m;
    let pivot = delta * j / (v_b * edge.a_m.max(1e-6));
    delta / drive.max_rate_radps
        + u_m * delta.tan() / v_b
        + pivot
        + 2.0 * delta / drive.push_rate_radps
}

/// Counter-clockwise sequence of unstable hull edges strictly between stable edges `from`
/// and `to` (in the order a counter-clockwise roll meets them), and whether every one
/// of them tips counter-clockwise (its COM foot lies before its start vertex).
pub fn edges_between(part: &Part, from: usize, to: usize) -> (Vec<usize>, bool) {
    let n = part.edges.len();
    let mut out = Vec::new();
    let mut i = (from + n - 1) % n;
    while i != to && out.len() < n {
        out.push(i);
        i = (i + n - 1) % n;
    }
    let tips = out.iter().all(|&u| part.edges[u].a_m < 0.0);
    (out, tips)
}
