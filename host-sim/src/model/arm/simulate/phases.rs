//! The runner's step for each contact state, and the records it keeps.

use super::step::{self, GraspEvent, RollEvent};
use super::{
    Executed, Frame, FrictionSample, GoalError, ImpactRecord, Runner, Sample, State, FRAME_S,
    FRICTION_S, SAMPLE_S,
};
use crate::engine::locate::bisect;
use crate::model::arm::contact::{BodyState, Pivot, Placement};
use crate::model::arm::geometry::wrap_pi;
use crate::model::arm::impact::{EdgeImpact, ImpactLaw, Outcome, SETTLE_SPEED_MPS};
use crate::model::arm::task::Phase;

/// How far below the table top the arm may carry the object before the table takes it
/// back, m (a tracked arm sags by microns at the start).
const TABLE_TOLERANCE_M: f64 = 1e-3;

/// Largest angle between the caught edge and the surface at which the edge strikes as a
/// whole, rad (the planner aims at `goal_angle_tolerance_rad / 10`). Further from flat the
/// lower vertex strikes first ([`crate::model::arm::impact::Rig::vertex_impact`]) and the
/// edge comes down after it as a roll falling back. Below it the two impacts are nearly
/// simultaneous (the edge falls back about `tilt / |omega+|` later: 2 ms at 0.02 rad and
/// the 9 rad/s of the shipped scene's tracked catch), and the rigid sequence of a vertex
/// strike and an edge impact does not tend to the edge's strike as a whole as the tilt
/// goes to 0 (a square dropped flat then rocks, where the whole edge stops it outright;
/// `tests/integration/arm_impact.rs`): the rigid model does not resolve the order of nearly
/// simultaneous impacts, and the edge impact is taken for them.
pub const FLAT_TOL_RAD: f64 = 0.02;

/// Events after which a run is called chattering (a roll starting and falling back
/// without end).
const MAX_EVENTS: usize = 1000;

impl Runner<'_> {
    pub(super) fn grasp(&mut self, p: Placement, t1: f64) {
        let (rig, arm) = (&self.sys.rig, self.arm);
        match step::grasp_step(rig, &p, arm, self.mu, self.t, t1) {
            None => {
                self.t = t1;
                self.check_table(&p);
            }
            Some((te, GraspEvent::Slips)) => {
                self.t = te;
                self.event(te, "slip");
                self.fail(
                    Executed::Slipped,
                    format!("the grasp slipped at t = {te:.4} s"),
                );
            }
            Some((te, GraspEvent::Separates)) => {
                self.t = te;
                let s = rig.grasped_state(&p, &arm.joint(te));
                self.leave(te, s);
            }
            Some((te, GraspEvent::Tips(dir))) => {
                self.t = te;
                self.event(
                    te,
                    if dir > 0.0 {
                        "roll_start_ccw"
                    } else {
                        "roll_start_cw"
                    },
                );
                self.state = State::Roll {
                    pivot: rig.pivot(&p, dir),
                    from: p,
                    psi: (0.0, 0.0),
                };
            }
        }
    }

    pub(super) fn roll(&mut self, pv: Pivot, from: Placement, psi: (f64, f64), t1: f64) {
        let (rig, arm) = (&self.sys.rig, self.arm);
        let (te, s, ev) = step::roll_step(rig, &pv, arm, self.mu, self.t, t1, psi);
        self.t = te;
        self.state = State::Roll {
            pivot: pv,
            from,
            psi: s,
        };
        match ev {
            None => {}
            Some(RollEvent::Lands) => {
                self.event(te, "roll_end");
                let onto = rig.landed(&pv);
                if self.out.impact_speed_mps.is_none() {
                    self.out.impact_speed_mps = Some(rig.impact_speed_mps(&pv, s.1));
                }
                self.strike(te, &pv, onto, s.1);
            }
            Some(RollEvent::FallsBack) => {
                self.event(te, "roll_back");
                self.strike(te, &pv, from, s.1);
            }
            Some(RollEvent::Slips) => {
                self.event(te, "slip");
                self.fail(
                    Executed::Slipped,
                    format!("the roll slipped at t = {te:.4} s"),
                );
            }
            Some(RollEvent::Separates) => {
                let st = rig.rolling_state(&pv, s.0, s.1, &arm.joint(te));
                self.leave(te, st);
            }
        }
        if self.out.events.len() > MAX_EVENTS {
            self.fail(
                Executed::Missed,
                "the roll chattered (too many events)".into(),
            );
        }
    }

    /// Edge `onto` strikes the surface, ending a roll over `pv` at relative rate
    /// `psi_dot`: the one-sided impact ([`crate::model::arm::impact`]) grasps the object
    /// on it or rocks it onto the striking vertex; an impulse outside its friction cone
    /// is a slip.
    fn strike(&mut self, te: f64, pv: &Pivot, onto: Placement, psi_dot: f64) {
        let imp = self.sys.rig.roll_impact(pv, &onto, psi_dot);
        self.apply_impact(te, onto, imp);
    }

    /// Record an impact onto edge `onto`, judge its impulse's friction, and go on from
    /// what it did.
    fn apply_impact(&mut self, te: f64, onto: Placement, imp: EdgeImpact) {
        let rig = &self.sys.rig;
        let imp = match self.sys.impact_law {
            ImpactLaw::OneSided => imp,
            ImpactLaw::NoRebound => imp.stopped_outright(),
        };
        self.out.impacts.push(ImpactRecord {
            t_s: te,
            edge: onto.edge,
            impact: imp,
        });
        if imp.judged(self.mu).is_err() {
            self.event(te, "impact_slip");
            self.fail(
                Executed::Slipped,
                format!(
                    "the impact at t = {te:.4} s slipped: its impulse needs friction {:.4}",
                    imp.friction_ratio()
                ),
            );
            return;
        }
        if imp.speed_mps >= SETTLE_SPEED_MPS {
            self.out.peak_friction_ratio = self.out.peak_friction_ratio.max(imp.friction_ratio());
        }
        match imp.outcome {
            Outcome::Grasp => self.state = State::Grasp(onto),
            Outcome::Rock {
                dir,
                rate_radps,
                psi_rad,
                ..
            } => {
                self.event(te, if dir > 0.0 { "rock_ccw" } else { "rock_cw" });
                self.state = State::Roll {
                    pivot: rig.pivot(&onto, dir),
                    from: onto,
                    psi: (psi_rad, rate_radps),
                };
            }
        }
    }

    /// The object leaves the surface: a throw's release at the brake, else a failure.
    fn leave(&mut self, te: f64, s: BodyState) {
        if self.out.catch_index.is_some() {
            // After the catch the contact left at zero normal speed (the impacts are
            // plastic): with a tangential force still on it that is a slide, not a flight,
            // and flying it on would graze the arm again at once. Reported, not flown.
            self.event(te, "bounce");
            self.fail(
                Executed::LostContact,
                format!("the caught object left the arm at t = {te:.4} s (a bounce)"),
            );
        } else if self.sys.task.kind.throws() && te >= self.arm.release_s() - 1e-3 {
            self.event(te, "release");
            self.out.release = Some(s);
            self.state = State::Flight { t0: te, start: s };
        } else {
            self.event(te, "separation");
            self.fail(
                Executed::LostContact,
                format!("the object left the surface at t = {te:.4} s"),
            );
        }
    }

    pub(super) fn flight(&mut self, t0: f64, start: BodyState, t1: f64) {
        let g = self.sys.rig.gravity_mps2;
        let catches = self.sys.task.kind.catches();
        if let Some(goal) = self.sys.task.goal.filter(|_| !catches) {
            let (y0, vy) = (start.com.y, start.velocity.y);
            let disc = vy * vy + 2.0 * g * (y0 - goal.y_m);
            if disc >= 0.0 {
                let tau = (vy + disc.sqrt()) / g; // the later root: going down
                if tau > self.t - t0 && tau <= t1 - t0 {
                    let s = start.flown(tau, g);
                    self.t = t0 + tau;
                    self.event(self.t, "landing");
                    let err = GoalError {
                        position_m: s
                            .com
                            .minus(crate::model::arm::geometry::V2::new(goal.x_m, goal.y_m))
                            .norm(),
                        angle_rad: wrap_pi(s.angle_rad - goal.angle_rad),
                    };
                    self.out.goal_error = Some(err);
                    if err.position_m <= goal.tolerance_m
                        && err.angle_rad.abs() <= goal.angle_tolerance_rad
                    {
                        self.verdict =
                            Some((Executed::Ok, "landed within tolerance of the goal".into()));
                    } else {
                        self.fail(
                            Executed::Missed,
                            format!(
                                "landed {:.4} m and {:.4} rad from the goal",
                                err.position_m, err.angle_rad
                            ),
                        );
                    }
                    return;
                }
            }
        }
        let s1 = start.flown(t1 - t0, g);
        if step::clearance_m(&self.sys.rig, &s1, &self.arm.joint(t1)) < -1e-6 {
            if catches {
                self.catch(t0, start, t1);
                return;
            }
            self.t = t1;
            self.event(t1, "arm_strike");
            self.fail(
                Executed::Missed,
                format!("the flying object struck the arm at t = {t1:.4} s"),
            );
            return;
        }
        self.t = t1;
    }

    /// The flying object meets the surface in `(t, t1]`: located by bisection on the
    /// clearance, then the one-sided impact of the edge nearest flat: within
    /// [`FLAT_TOL_RAD`] of flat it strikes as a whole
    /// ([`crate::model::arm::impact::Rig::edge_impact`]), further from flat its lower
    /// vertex strikes first ([`crate::model::arm::impact::Rig::vertex_impact`]) and the
    /// object rolls about it from the tilt, to fall back onto the edge (another impact:
    /// grasped or rocking), tip on over the vertex, or leave (a bounce, reported). The
    /// catch's first impact is `catch_index`, and the hold runs from it.
    fn catch(&mut self, t0: f64, start: BodyState, t1: f64) {
        let (rig, arm) = (&self.sys.rig, self.arm);
        let g = rig.gravity_mps2;
        let under = |t: f64| {
            let c = step::clearance_m(rig, &start.flown(t - t0, g), &arm.joint(t));
            (c < 0.0).then_some(())
        };
        let (te, ()) = bisect((self.t, t1), (), 40, under);
        self.t = te;
        let s = start.flown(te - t0, g);
        let j = arm.joint(te);
        self.event(te, "catch");
        let rel = s.angle_rad - j.angle_rad;
        let body = &rig.body;
        let (edge, off) = (0..body.len())
            .map(|k| (k, wrap_pi(rel - rig.alpha_rad(k))))
            .min_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .unwrap_or((0, f64::INFINITY));
        self.out.catch_flat_error_rad = Some(off);
        let flat = off.abs() <= FLAT_TOL_RAD;
        let com_arm = s.com.rotate(-j.angle_rad);
        let (onto, pivot) = if flat {
            let v_arm = body.vertex(edge).rotate(s.angle_rad);
            let sigma = rig.surface.sigma_m(s.com.plus(v_arm).rotate(-j.angle_rad));
            let p = Placement {
                edge,
                sigma_m: sigma,
            };
            (p, None)
        } else {
            let (p, pv) = rig.tilted(edge, off, com_arm);
            (p, Some(pv))
        };
        if onto.sigma_m < 0.0 || onto.sigma_m + body.edge_length_m(edge) > rig.surface.length_m {
            self.fail(
                Executed::Missed,
                format!("the object came down off the end of the surface at t = {te:.4} s"),
            );
            return;
        }
        // the twist relative to the arm, in the arm frame
        let v = s
            .velocity
            .minus(s.com.perp().scale(j.velocity_radps))
            .rotate(-j.angle_rad);
        let w = s.angular_velocity_radps - j.velocity_radps;
        let imp = match pivot {
            None => rig.edge_impact(&onto, v, w),
            Some(pv) => rig.vertex_impact(&pv, &onto, off, v, w),
        };
        self.out.catch_index = Some(self.out.impacts.len());
        self.apply_impact(te, onto, imp);
        if self.verdict.is_none() {
            self.deadline = Some(te + self.sys.task.hold_s);
        }
    }

    /// A snatch must lift the object off the table, not push it through.
    fn check_table(&mut self, p: &Placement) {
        if self.sys.task.kind != crate::model::arm::task::TaskKind::Snatch {
            return;
        }
        let s = self.sys.rig.grasped_state(p, &self.arm.joint(self.t));
        let low = self
            .sys
            .rig
            .body
            .vertices
            .iter()
            .map(|&v| s.point(v).y)
            .fold(f64::INFINITY, f64::min);
        if low < self.table_y - TABLE_TOLERANCE_M {
            self.event(self.t, "table");
            self.fail(
                Executed::LostContact,
                "the arm moved down into the table: the object stays on it".into(),
            );
        }
    }

    /// The object's world state now.
    pub(super) fn body(&self) -> BodyState {
        let j = self.arm.joint(self.t);
        let rig = &self.sys.rig;
        match self.state {
            State::Grasp(p) => rig.grasped_state(&p, &j),
            State::Roll { pivot, psi, .. } => rig.rolling_state(&pivot, psi.0, psi.1, &j),
            State::Flight { t0, start } => start.flown(self.t - t0, rig.gravity_mps2),
        }
    }

    fn phase(&self) -> Phase {
        match self.state {
            State::Grasp(_) => Phase::Grasp,
            State::Roll { .. } => Phase::Roll,
            State::Flight { .. } => Phase::Flight,
        }
    }

    /// Friction needed now (None in flight).
    fn ratio(&self) -> Option<f64> {
        let j = self.arm.joint(self.t);
        let rig = &self.sys.rig;
        match self.state {
            State::Grasp(p) => Some(rig.grasp(&p, &j).force.friction_ratio()),
            State::Roll { pivot, psi, .. } => {
                Some(rig.roll(&pivot, psi.0, psi.1, &j).force.friction_ratio())
            }
            State::Flight { .. } => None,
        }
    }

    /// Hand the observer, if any, the run at this instant.
    pub(super) fn observe_now(&mut self, kind: &'static str) {
        if self.observe.is_none() {
            return;
        }
        let sample = Sample {
            t_s: self.t,
            kind,
            phase: self.phase(),
            joint: self.arm.joint(self.t),
            body: self.body(),
            friction_ratio: self.ratio().unwrap_or(f64::NAN),
        };
        if let Some(f) = self.observe.as_mut() {
            f(&sample);
        }
    }

    pub(super) fn record(&mut self) {
        if self.t >= self.next_sample {
            self.observe_now("sample");
            self.next_sample = ((self.t / SAMPLE_S).floor() + 1.0) * SAMPLE_S;
        }
        let ratio = self.ratio();
        let mut new_peak = false;
        if let Some(r) = ratio.filter(|r| r.is_finite()) {
            new_peak = r > self.out.peak_friction_ratio;
            self.out.peak_friction_ratio = self.out.peak_friction_ratio.max(r);
        }
        if !self.opt.record {
            return;
        }
        // every FRICTION_S, and every new peak so that a plot shows the true maximum
        if self.t >= self.next_friction || new_peak {
            if let Some(r) = ratio {
                let phase = self.phase();
                self.out.friction.push(FrictionSample {
                    t_s: self.t,
                    ratio: r,
                    phase,
                });
            }
            if self.t >= self.next_friction {
                self.next_friction += FRICTION_S;
            }
        }
        if self.t >= self.next_frame {
            let b = self.body();
            self.out.frames.push(Frame {
                t_s: self.t,
                arm_angle_rad: self.arm.joint(self.t).angle_rad,
                object: self
                    .sys
                    .rig
                    .body
                    .vertices
                    .iter()
                    .map(|&v| b.point(v))
                    .collect(),
                phase: self.phase(),
            });
            self.next_frame += FRAME_S;
        }
    }
}
