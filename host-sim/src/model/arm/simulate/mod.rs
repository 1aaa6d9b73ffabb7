//! Verification: play a joint motion against the object with the phases simulated event
//! by event (sec. 2.5: "trajectories specified by the planner are directly implemented").
//!
//! The object is grasped, rolling or flying. Each step (0.1 ms, shortened to land on the
//! motion's breaks) checks every condition of the current phase: the friction cone and
//! unilateral contact always, the centre of pressure on the edge in a grasp, the roll
//! angle in a roll; an event inside a step is located by bisection ([`step`]). Flight is
//! closed form until the goal height is crossed going down (located in closed form) or a
//! vertex meets the arm's surface. The run is judged against the task:
//!
//! - `ok`: the goal is reached (thrown within tolerance; at rest on the arm on the right
//!   edge after the motion and a hold);
//! - `slipped`: a contact force left the friction cone;
//! - `lost_contact`: the object left the surface when the task did not release it, or
//!   a snatch pushed it down into the table;
//! - `missed`: every contact held but the goal was not reached (the roll fell back or
//!   never happened, the throw landed outside tolerance or struck the arm).

pub mod step;

use super::contact::{BodyState, Joint, Placement};
use super::geometry::V2;
use super::impact::EdgeImpact;
use super::motion::ArmMotion;
use super::task::Phase;
use super::ArmScene;
use serde::Serialize;

/// Integration step of the verifier, s.
pub const STEP_S: f64 = 1e-4;
/// Interval of filmstrip frames, s.
pub const FRAME_S: f64 = 0.02;
/// Interval of friction samples, s.
pub const FRICTION_S: f64 = 0.002;

/// How an execution ended (`executed` in the JSON).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Executed {
    /// The goal was reached.
    Ok,
    /// The object slipped.
    Slipped,
    /// The object left the surface unplanned.
    LostContact,
    /// Contacts held but the goal was not reached.
    Missed,
}

/// A phase change or failure, in time.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Event {
    /// When, s.
    pub t_s: f64,
    /// What: `roll_start_ccw`, `roll_start_cw`, `roll_end`, `roll_back`, `rock_ccw`,
    /// `rock_cw` (an impact rocked the object onto its striking vertex, or a catch struck
    /// a vertex first: the roll over it from the tilt, named by the side the edge is
    /// tilted to), `release`, `catch`, `bounce` (the caught object left the arm), `slip`,
    /// `impact_slip`, `separation`, `landing`, `arm_strike`, `table`.
    pub kind: &'static str,
}

/// One filmstrip frame.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Frame {
    /// Time, s.
    pub t_s: f64,
    /// Joint angle, rad.
    pub arm_angle_rad: f64,
    /// Object's vertices, world, m.
    pub object: Vec<V2>,
    /// Phase at this instant.
    pub phase: Phase,
}

/// Friction needed at one instant of contact.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FrictionSample {
    /// Time, s.
    pub t_s: f64,
    /// |f_t| / f_n.
    pub ratio: f64,
    /// Grasp or roll.
    pub phase: Phase,
}

/// Distance from the goal when the run ended.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct GoalError {
    /// Centre-of-mass distance, m.
    pub position_m: f64,
    /// Orientation error, rad (wrapped to (-pi, pi]).
    pub angle_rad: f64,
}

/// The record of one execution.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Execution {
    /// The verdict.
    pub executed: Executed,
    /// Why, in words.
    pub reason: String,
    /// The friction coefficient the run had.
    pub mu: f64,
    /// Phase changes and failures.
    pub events: Vec<Event>,
    /// Filmstrip frames.
    pub frames: Vec<Frame>,
    /// Friction needed over time.
    pub friction: Vec<FrictionSample>,
    /// Largest friction ratio met in contact.
    pub peak_friction_ratio: f64,
    /// Distance from the goal at the end (None if the run failed before).
    pub goal_error: Option<GoalError>,
    /// Normal speed of a roll's landing, m/s.
    pub impact_speed_mps: Option<f64>,
    /// The object's state at a throw's release.
    pub release: Option<BodyState>,
    /// Every impact of an edge on the surface, in time order.
    pub impacts: Vec<ImpactRecord>,
    /// Which of `impacts` is the catch (a throw and catch).
    pub catch_index: Option<usize>,
    /// How far from flat the caught edge met the surface, rad.
    pub catch_flat_error_rad: Option<f64>,
    /// The phase letters the run went through ([`judge::executed_phases`]): a run that
    /// reaches its goal through other phases than the task's is `missed`.
    pub phases: String,
    /// Where the object lies on the arm at the end, if it is grasped there.
    pub rest: Option<Placement>,
}

/// One impact of the run.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ImpactRecord {
    /// When, s.
    pub t_s: f64,
    /// The edge that struck.
    pub edge: usize,
    /// The law's result and impulse.
    pub impact: EdgeImpact,
}

/// Integration step and recording of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimOptions {
    /// Step, s.
    pub step_s: f64,
    /// Keep frames and friction samples.
    pub record: bool,
}

impl Default for SimOptions {
    fn default() -> Self {
        Self {
            step_s: STEP_S,
            record: true,
        }
    }
}

/// The object's contact state.
#[derive(Clone, Copy, Debug, PartialEq)]
enum State {
    Grasp(Placement),
    Roll {
        pivot: super::contact::Pivot,
        from: Placement,
        psi: (f64, f64),
    },
    Flight {
        t0: f64,
        start: BodyState,
    },
}

/// Interval of [`Sample`]s handed to an observer ([`execute_observed`]), s: one per
/// millisecond of simulated time (the control period of the shipped scenes), plus one at
/// every event.
pub const SAMPLE_S: f64 = 1e-3;

/// The run at one instant, as an observer ([`execute_observed`]) sees it: a row of the
/// `--trace`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Time, s.
    pub t_s: f64,
    /// `sample` (a regular sample), or the event at this instant ([`Event::kind`]).
    pub kind: &'static str,
    /// The object's phase at this instant (after the event, if any).
    pub phase: Phase,
    /// The joint.
    pub joint: Joint,
    /// The object in the world.
    pub body: BodyState,
    /// Friction the contact needs, |f_t| / f_n (NaN in flight).
    pub friction_ratio: f64,
}

/// Run `motion` against the object with friction coefficient `mu` (0.1 ms steps,
/// frames and friction recorded).
pub fn execute(sys: &ArmScene, motion: &dyn ArmMotion, mu: f64) -> Execution {
    execute_with(sys, motion, mu, SimOptions::default())
}

/// [`execute`] with a chosen step and recording.
pub fn execute_with(sys: &ArmScene, motion: &dyn ArmMotion, mu: f64, opt: SimOptions) -> Execution {
    let mut run = Runner::new(sys, motion, mu, opt);
    run.go();
    run.finish()
}

/// [`execute_with`], handing `observe` a [`Sample`] every [`SAMPLE_S`] and one at every
/// event, as the run goes (the `--trace` streams them).
pub fn execute_observed(
    sys: &ArmScene,
    motion: &dyn ArmMotion,
    mu: f64,
    opt: SimOptions,
    observe: &mut dyn FnMut(&Sample),
) -> Execution {
    let mut run = Runner::new(sys, motion, mu, opt);
    run.observe = Some(observe);
    run.go();
    run.finish()
}

struct Runner<'a> {
    sys: &'a ArmScene,
    arm: &'a dyn ArmMotion,
    mu: f64,
    state: State,
    t: f64,
    out: Execution,
    next_frame: f64,
    next_friction: f64,
    verdict: Option<(Executed, String)>,
    breaks: Vec<f64>,
    table_y: f64,
    opt: SimOptions,
    observe: Option<&'a mut dyn FnMut(&Sample)>,
    next_sample: f64,
    /// The end of a caught run: the catch and the hold after it, s.
    deadline: Option<f64>,
}

impl<'a> Runner<'a> {
    fn new(sys: &'a ArmScene, arm: &'a dyn ArmMotion, mu: f64, opt: SimOptions) -> Self {
        let mut breaks = arm.breaks_s();
        breaks.sort_by(f64::total_cmp);
        let s0 = sys.rig.grasped_state(&sys.start, &arm.joint(0.0));
        let table_y = sys
            .rig
            .body
            .vertices
            .iter()
            .map(|&v| s0.point(v).y)
            .fold(f64::INFINITY, f64::min);
        Self {
            sys,
            arm,
            mu,
            state: State::Grasp(sys.start),
            t: 0.0,
            out: Execution {
                executed: Executed::Missed,
                reason: String::new(),
                mu,
                events: Vec::new(),
                frames: Vec::new(),
                friction: Vec::new(),
                peak_friction_ratio: 0.0,
                goal_error: None,
                impact_speed_mps: None,
                release: None,
                impacts: Vec::new(),
                phases: String::new(),
                catch_index: None,
                catch_flat_error_rad: None,
                rest: None,
            },
            next_frame: 0.0,
            next_friction: 0.0,
            verdict: None,
            breaks,
            table_y,
            opt,
            observe: None,
            next_sample: 0.0,
            deadline: None,
        }
    }

    fn end_s(&self) -> f64 {
        let settle = self.arm.settled_s();
        if let Some(d) = self.deadline {
            return d.max(settle + self.sys.task.hold_s);
        }
        if self.sys.task.kind.throws() {
            settle + 5.0 // flight to the goal; ended by the landing event
        } else {
            settle + self.sys.task.hold_s
        }
    }

    fn event(&mut self, t: f64, kind: &'static str) {
        self.out.events.push(Event { t_s: t, kind });
        self.observe_now(kind);
    }

    fn fail(&mut self, how: Executed, why: String) {
        if self.verdict.is_none() {
            self.verdict = Some((how, why));
        }
    }

    /// The next step's end: `STEP_S` on, or the next break if that comes first.
    fn step_end(&self) -> f64 {
        let t1 = self.t + self.opt.step_s;
        let i = self.breaks.partition_point(|&b| b <= self.t + 1e-12);
        self.breaks.get(i).map_or(t1, |&b| b.min(t1))
    }

    fn go(&mut self) {
        self.record();
        while self.verdict.is_none() && self.t < self.end_s() {
            let t1 = self.step_end().min(self.end_s());
            match self.state {
                State::Grasp(p) => self.grasp(p, t1),
                State::Roll { pivot, from, psi } => self.roll(pivot, from, psi, t1),
                State::Flight { t0, start } => self.flight(t0, start, t1),
            }
            self.record();
        }
        if self.verdict.is_none() {
            self.judge_at_rest();
        }
    }
}

pub mod judge;
mod phases;
