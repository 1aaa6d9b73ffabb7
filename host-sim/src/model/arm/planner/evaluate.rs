//! The nonlinear program's functions: objective and the constraints of sec. 2.2, all in
//! the form `c(x) <= 0`, each scaled to be dimensionless and of order one.
//!
//! | constraint (sec. 2.2) | how it is sampled |
//! | --- | --- |
//! | joint position (manipulator 1) | bounds on the control points (convex hull) |
//! | joint velocity (2) | on the differences of control points (hull of the derivative) |
//! | joint acceleration (the tracker's limit, not the paper's) | on the second differences (exact: the acceleration is piecewise linear) |
//! | joint torque (3) | at every phase sample, arm + object reaction |
//! | torque derivative (4) | between consecutive samples of one phase |
//! | initial state (5) | by construction ([`super::layout`]) |
//! | dynamic grasp (object 1) | friction cone, unilateral, centre of pressure on the edge and `planner.cop_margin` of its length inside it |
//! | rolling friction (2) | friction cone and unilateral at every RK4 node of the roll |
//! | roll angle (3) | `0 <= dir psi <= gamma` at every RK4 node |
//! | roll completed (4) | `dir psi(t_g1 + t_roll) = gamma` (within 1e-3 rad) |
//! | release state (5) | goal pose after `t_flight` within a tenth of its tolerance, falling; release separates under the move to rest's first arc; that move's braking stop lies within the joint limits |
//! | catch (a throw and catch) | the bang-bang move after the release is at rest at the catching angle at least `CATCH_LEAD_S` before the object arrives; the goal pose is the object lying on its catching edge there |
//!
//! The torque rate is not checked across a phase change: the roll's end is an impact and
//! a throw's release a deliberate maximal deceleration (sec. 2.5), both jumps in torque.

use super::super::contact::{BodyState, Joint, Pivot, Placement};
use super::super::geometry::V2;
use super::super::motion::{ArmMotion, PlannedMotion};
use super::super::task::Phase;
use super::super::ArmScene;
use super::layout::{Design, Layout};
use crate::engine::ode::{Method, Rk4, State};
use serde::Serialize;

/// How long the arm must be at rest at the catching angle before the object arrives, s.
pub const CATCH_LEAD_S: f64 = 0.02;

/// What a constraint row constrains (for reporting the ones a plan violates).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// Joint speed.
    Velocity,
    /// Joint acceleration (what the tracker can follow).
    Accel,
    /// Joint torque.
    Torque,
    /// Joint torque rate.
    TorqueRate,
    /// Friction cone of a grasp.
    GraspFriction,
    /// Unilateral contact of a grasp.
    GraspNormal,
    /// Centre of pressure within the edge.
    CentreOfPressure,
    /// Friction cone of the roll.
    RollFriction,
    /// Unilateral contact of the roll.
    RollNormal,
    /// Roll angle bounds.
    RollAngle,
    /// Roll completed at its time.
    RollCompleted,
    /// Separation at release.
    Release,
    /// Goal pose reached (and falling).
    Goal,
    /// Brake stops within the joint limits.
    BrakeStop,
    /// A catch: the arm is at rest at the catching angle before the object comes down.
    Catch,
}

impl std::fmt::Display for Kind {
    /// The constraint in words, for error messages.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Velocity => "the joint speed limit",
            Self::Accel => "the joint acceleration limit",
            Self::Torque => "the joint torque limit",
            Self::TorqueRate => "the joint torque-rate limit",
            Self::GraspFriction => "the grasp's friction cone",
            Self::GraspNormal => "the grasp's unilateral contact",
            Self::CentreOfPressure => "the grasp's centre of pressure",
            Self::RollFriction => "the roll's friction cone",
            Self::RollNormal => "the roll's unilateral contact",
            Self::RollAngle => "the roll angle's bounds",
            Self::RollCompleted => "the roll's completion on time",
            Self::Release => "separation at the release",
            Self::Goal => "the goal pose",
            Self::BrakeStop => "the brake stop within the joint limits",
            Self::Catch => {
                "the catch (the arm at rest at the catching angle before the object arrives)"
            }
        })
    }
}

/// One sample of the plan's own prediction (for plots of fig. 2-3).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PlanSample {
    /// Time, s.
    pub t_s: f64,
    /// Phase.
    pub phase: Phase,
    /// Friction the contact needs, |f_t|/f_n.
    pub friction_ratio: f64,
    /// Joint torque, N m.
    pub torque_nm: f64,
}

/// The program's functions at one design vector.
#[derive(Clone, Debug, PartialEq)]
pub struct Eval {
    /// Objective: mu + w v_impact^2.
    pub objective: f64,
    /// Constraint values, feasible where <= 0.
    pub constraints: Vec<f64>,
    /// What each constraint row is.
    pub kinds: Vec<Kind>,
    /// The plan's samples (only when asked for).
    pub trace: Vec<PlanSample>,
    /// Normal speed of the roll's impact, m/s (0 without a roll end).
    pub impact_speed_mps: f64,
    /// The largest `(1 + margin) |f_t| / f_n` over the samples: the mu these samples need.
    pub mu_needed: f64,
}

struct Sink {
    c: Vec<f64>,
    k: Vec<Kind>,
    trace: Option<Vec<PlanSample>>,
    mu_needed: f64,
}

impl Sink {
    fn push(&mut self, kind: Kind, v: f64) {
        // a NaN (e.g. a degenerate state) counts as a large violation
        self.c.push(if v.is_nan() { 1e3 } else { v });
        self.k.push(kind);
    }
    /// `lo <= v <= hi` as two rows scaled by `scale`.
    fn within(&mut self, kind: Kind, v: f64, lo: f64, hi: f64, scale: f64) {
        self.push(kind, (lo - v) / scale);
        self.push(kind, (v - hi) / scale);
    }
}

/// The program for one system.
pub struct Problem<'a> {
    /// The system.
    pub sys: &'a ArmScene,
    /// Its design-vector layout.
    pub layout: Layout,
    /// Extra grasp samples per phase, as fractions of the phase's duration in (0, 1):
    /// where the verifier found friction peaks between the regular samples
    /// ([`super::refine`]).
    pub extra: Vec<Vec<f64>>,
    /// Called at every evaluation (the planning's progress bar), if set.
    pub watch: Option<&'a dyn Fn()>,
}

/// Torque samples of one phase: (t, tau).
type Torques = Vec<(f64, f64)>;

impl<'a> Problem<'a> {
    /// The program of a system's task.
    pub fn new(sys: &'a ArmScene) -> Self {
        let layout = Layout::new(sys);
        Self {
            extra: vec![Vec::new(); layout.phases.len()],
            sys,
            layout,
            watch: None,
        }
    }

    /// The planned motion of a design.
    pub fn motion(&self, d: &Design) -> PlannedMotion {
        PlannedMotion::new(d.points_rad.clone(), d.segment_s, &self.sys.rest_move())
    }

    /// Objective and constraints at `x`; with `trace`, the plan's samples too.
    pub fn evaluate(&self, x: &[f64], trace: bool) -> Eval {
        if let Some(watch) = self.watch {
            watch();
        }
        let d = self.layout.decode(x);
        let m = self.motion(&d);
        let mut sink = Sink {
            c: Vec::new(),
            k: Vec::new(),
            trace: trace.then(Vec::new),
            mu_needed: 0.0,
        };
        self.knot_velocities(&d, &mut sink);
        self.knot_accels(&d, &mut sink);
        let phases = self.layout.phases;
        let (mut t0, mut place, mut impact) = (0.0, self.sys.start, 0.0);
        let mut leaving: Option<(BodyState, Vec<(V2, V2)>)> = None;
        for (i, &phase) in phases.iter().enumerate() {
            let dur = d.times_s[i];
            let next = phases.get(i + 1).copied();
            match phase {
                Phase::Grasp => {
                    let u = self.fractions(i, next);
                    let tq = self.grasp_phase(&m, &place, t0, dur, &u, d.mu, &mut sink);
                    self.torque_rates(&tq, &mut sink);
                    let j = m.joint(t0 + dur);
                    leaving = Some((
                        self.sys.rig.grasped_state(&place, &j),
                        self.edge_points(&place),
                    ));
                }
                Phase::Roll => {
                    let pv = self.sys.rig.pivot(&place, self.sys.task.roll_dir);
                    let (psi, psi_d) = self.roll_phase(&m, &pv, t0, dur, d.mu, next, &mut sink);
                    if next == Some(Phase::Grasp) {
                        impact = self.sys.rig.impact_speed_mps(&pv, psi_d);
                        place = self.sys.rig.landed(&pv);
                    }
                    let j = m.joint(t0 + dur);
                    let p_arm = self.sys.rig.surface.point(pv.sigma_m);
                    let b = self.sys.rig.body.vertex(pv.vertex);
                    leaving = Some((
                        self.sys.rig.rolling_state(&pv, psi, psi_d, &j),
                        vec![(b, p_arm)],
                    ));
                }
                Phase::Flight => {
                    if let Some((s0, pts)) = &leaving {
                        self.flight(&m, s0, pts, t0, dur, &mut sink);
                    }
                }
            }
            if phase != Phase::Flight {
                t0 += dur;
            }
        }
        Eval {
            objective: d.mu + self.sys.task.impact_weight_s2pm2 * impact * impact,
            constraints: sink.c,
            kinds: sink.k,
            trace: sink.trace.unwrap_or_default(),
            impact_speed_mps: impact,
            mu_needed: sink.mu_needed,
        }
    }

    /// Joint speed bounded through the control points' differences.
    fn knot_velocities(&self, d: &Design, sink: &mut Sink) {
        let v = self.sys.bounds.velocity_max_radps;
        for w in d.points_rad.windows(2) {
            let rate = (w[1] - w[0]) / d.segment_s;
            sink.within(Kind::Velocity, rate, -v, v, v);
        }
    }

    /// Joint acceleration within what the tracker can follow: the spline's acceleration
    /// is piecewise linear with the values `(P_i - 2 P_i+1 + P_i+2) / h^2` at the knots
    /// (`crate::bspline`), so bounding these bounds it everywhere, exactly.
    fn knot_accels(&self, d: &Design, sink: &mut Sink) {
        let a = self.sys.planner.accel_max_radps2;
        if !a.is_finite() {
            return;
        }
        let h2 = d.segment_s * d.segment_s;
        for w in d.points_rad.windows(3) {
            let acc = (w[0] - 2.0 * w[1] + w[2]) / h2;
            sink.within(Kind::Accel, acc, -a, a, a);
        }
    }

    /// The contact points of a grasped edge: (body-frame vertex, arm-frame point).
    fn edge_points(&self, p: &Placement) -> Vec<(V2, V2)> {
        let r = &self.sys.rig;
        let l = r.body.edge_length_m(p.edge);
        vec![
            (r.body.vertex(p.edge), r.surface.point(p.sigma_m)),
            (r.body.vertex(p.edge + 1), r.surface.point(p.sigma_m + l)),
        ]
    }

    /// Torque within its limit; records the sample.
    fn torque(&self, t: f64, tau: f64, sink: &mut Sink, tq: &mut Torques) {
        let tm = self.sys.bounds.torque_max_nm;
        sink.within(Kind::Torque, tau, -tm, tm, tm);
        tq.push((t, tau));
    }

    fn torque_rates(&self, tq: &Torques, sink: &mut Sink) {
        let r = self.sys.bounds.torque_rate_max_nmps;
        for w in tq.windows(2) {
            let rate = (w[1].1 - w[0].1) / (w[1].0 - w[0].0).max(1e-9);
            sink.within(Kind::TorqueRate, rate, -r, r, r);
        }
    }

    /// Friction cone and unilateral contact, scaled by g.
    fn cone(&self, kinds: (Kind, Kind), f_n: f64, f_t: f64, mu: f64, sink: &mut Sink) {
        let g = self.sys.rig.gravity_mps2;
        let k = 1.0 + self.sys.planner.friction_margin;
        if f_n > 0.0 {
            sink.mu_needed = sink.mu_needed.max(k * f_t.abs() / f_n);
        }
        sink.push(kinds.0, (k * f_t - mu * f_n) / g);
        sink.push(kinds.0, (-k * f_t - mu * f_n) / g);
        sink.push(kinds.1, (self.sys.planner.normal_force_min_mps2 - f_n) / g);
    }

    /// Sample fractions of grasp phase `i`: `samples_per_phase` even steps, its start
    /// included, its end excluded when a roll follows (the roll's own start is that
    /// instant), and the refinement's extra fractions.
    fn fractions(&self, i: usize, next: Option<Phase>) -> Vec<f64> {
        let k = self.sys.planner.samples_per_phase;
        let last = if next == Some(Phase::Roll) { k - 1 } else { k };
        let mut u: Vec<f64> = (0..=last).map(|j| j as f64 / k as f64).collect();
        let top = if next == Some(Phase::Roll) {
            1.0
        } else {
            1.0 + 1e-12
        };
        u.extend(self.extra[i].iter().filter(|&&f| f > 0.0 && f < top));
        u.sort_by(f64::total_cmp);
        u
    }

    /// Dynamic-grasp constraints at the sample fractions `u` of the phase.
    #[allow(clippy::too_many_arguments)]
    fn grasp_phase(
        &self,
        m: &PlannedMotion,
        place: &Placement,
        t0: f64,
        dur: f64,
        u: &[f64],
        mu: f64,
        sink: &mut Sink,
    ) -> Torques {
        let rig = &self.sys.rig;
        let mut tq = Vec::with_capacity(u.len());
        for &f in u {
            let t = t0 + dur * f;
            let j = m.joint(t);
            let g = rig.grasp(place, &j);
            self.cone(
                (Kind::GraspFriction, Kind::GraspNormal),
                g.force.normal,
                g.force.tangential,
                mu,
                sink,
            );
            let l = g.edge_length_m;
            let inset = self.sys.planner.cop_margin * l;
            sink.within(Kind::CentreOfPressure, g.cop_m, inset, l - inset, l);
            let tau = self.sys.arm.torque_nm(&j) + self.load(g.com, g.force_world, j.accel_radps2);
            self.torque(t, tau, sink, &mut tq);
            if let Some(tr) = sink.trace.as_mut() {
                tr.push(PlanSample {
                    t_s: t,
                    phase: Phase::Grasp,
                    friction_ratio: g.force.friction_ratio(),
                    torque_nm: tau,
                });
            }
        }
        tq
    }

    fn load(&self, com: V2, f: V2, phi_dd: f64) -> f64 {
        super::super::contact::ArmInertia::load_torque_nm(
            self.sys.mass_kg,
            self.sys.rig.body.rho_m,
            com,
            f,
            phi_dd,
        )
    }

    /// The roll by RK4 from psi = psi' = 0 with its constraints at every node; returns
    /// (psi, psi') at its end.
    #[allow(clippy::too_many_arguments)]
    fn roll_phase(
        &self,
        m: &PlannedMotion,
        pv: &Pivot,
        t0: f64,
        dur: f64,
        mu: f64,
        next: Option<Phase>,
        sink: &mut Sink,
    ) -> (f64, f64) {
        let rig = &self.sys.rig;
        let n = self.sys.planner.roll_steps;
        let h = dur / n as f64;
        let acc = |t: f64, y: State| rig.roll(pv, y.0, y.1, &m.joint(t)).psi_accel_radps2;
        let (mut psi, mut w) = (0.0, 0.0);
        let mut tq = Vec::with_capacity(n + 1);
        for i in 0..=n {
            let t = t0 + h * i as f64;
            if i > 0 {
                (psi, w) = Rk4.step(&acc, t - h, (psi, w), h).0;
            }
            let j = m.joint(t);
            let r = rig.roll(pv, psi, w, &j);
            self.cone(
                (Kind::RollFriction, Kind::RollNormal),
                r.force.normal,
                r.force.tangential,
                mu,
                sink,
            );
            if i > 0 {
                sink.within(
                    Kind::RollAngle,
                    pv.dir * psi,
                    0.0,
                    pv.gamma_rad,
                    pv.gamma_rad,
                );
            }
            let f = r.com_accel.plus(V2::new(0.0, rig.gravity_mps2));
            let tau = self.sys.arm.torque_nm(&j) + self.load(r.com, f, r.phi_accel_radps2);
            self.torque(t, tau, sink, &mut tq);
            if let Some(tr) = sink.trace.as_mut() {
                tr.push(PlanSample {
                    t_s: t,
                    phase: Phase::Roll,
                    friction_ratio: r.force.friction_ratio(),
                    torque_nm: tau,
                });
            }
        }
        self.torque_rates(&tq, sink);
        if next == Some(Phase::Grasp) {
            let eps = 1e-3;
            sink.within(
                Kind::RollCompleted,
                pv.dir * psi,
                pv.gamma_rad - eps,
                pv.gamma_rad + eps,
                pv.gamma_rad,
            );
        }
        (psi, w)
    }

    /// Release under the move to rest, its braking stop, and the goal after `dur` of flight.
    fn flight(
        &self,
        m: &PlannedMotion,
        s0: &BodyState,
        pts: &[(V2, V2)],
        t_rel: f64,
        dur: f64,
        sink: &mut Sink,
    ) {
        let sys = self.sys;
        let g = sys.rig.gravity_mps2;
        let jr = m.joint(t_rel);
        // the move after the release starts by braking (for a catch, a constraint below
        // keeps the catching angle behind the braking stop, so its first arc is the brake)
        let a_b = sys.bounds.brake_accel_radps2;
        let brake = Joint {
            accel_radps2: -jr.velocity_radps.signum() * a_b,
            ..jr
        };
        let n = sys.rig.surface.normal().rotate(jr.angle_rad);
        for (b, p_arm) in pts {
            let u = b.rotate(s0.angle_rad);
            let w = s0.angular_velocity_radps;
            let a_obj = V2::new(0.0, -g).minus(u.scale(w * w));
            let sep = a_obj.minus(brake.point_accel(*p_arm)).dot(n);
            sink.push(Kind::Release, (1.0 - sep) / g);
        }
        let stop = m.joint(m.settled_s()).angle_rad;
        // a hundredth of a radian inside the limits: the controller checks the same
        // extremes in f32
        let (lo, hi) = self.layout.angle_bounds;
        sink.within(Kind::BrakeStop, stop, lo + 0.01, hi - 0.01, hi - lo);
        let mut goal = sys.task.goal;
        if let (Some(c), Some(g)) = (sys.task.catch, goal.as_mut()) {
            // the bang-bang move brakes first (the catching angle behind the braking stop:
            // its switch sign opposes the release velocity), so it overshoots to the
            // braking stop before it comes back: that stop within the limits too
            let w = jr.velocity_radps;
            let braking = jr.angle_rad + w * w.abs() / (2.0 * a_b);
            sink.within(Kind::BrakeStop, braking, lo + 0.01, hi - 0.01, hi - lo);
            sink.push(Kind::Catch, (c.angle_rad - braking) * w.signum() / 0.1);
            // the bang-bang move reaches the catching configuration (sec. 2.5), a little
            // before the object arrives; the goal is the object lying there on its
            // catching edge
            let at = Joint {
                angle_rad: stop,
                ..Default::default()
            };
            let pose = sys.rig.grasped_state(&c.place, &at);
            let turns = ((g.angle_rad - c.angle_rad - sys.rig.alpha_rad(c.place.edge))
                / std::f64::consts::TAU)
                .round();
            (g.x_m, g.y_m) = (pose.com.x, pose.com.y);
            g.angle_rad = pose.angle_rad + std::f64::consts::TAU * turns;
            let early = m.settled_s() - (t_rel + dur) + CATCH_LEAD_S;
            sink.push(Kind::Catch, early / 0.1);
        }
        if let Some(goal) = goal {
            let f = s0.flown(dur, g);
            let tol = 0.1 * goal.tolerance_m;
            sink.within(Kind::Goal, f.com.x, goal.x_m - tol, goal.x_m + tol, tol);
            sink.within(Kind::Goal, f.com.y, goal.y_m - tol, goal.y_m + tol, tol);
            let ta = 0.1 * goal.angle_tolerance_rad;
            sink.within(
                Kind::Goal,
                f.angle_rad,
                goal.angle_rad - ta,
                goal.angle_rad + ta,
                ta,
            );
            sink.push(Kind::Goal, f.velocity.y + 0.1);
        }
    }
}
