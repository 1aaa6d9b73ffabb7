//! Running a scene: assemble the plant once from the scene (only the enabled effects, as
//! concrete types), then either jump from impact to impact (no controller) or step a
//! [`StepController`] at its fixed rate with the firmware's `SensorFrame`/`ActuatorCommand`.

use crate::controller::{ControllerError, HilReport, Sil, StepController};
use crate::effects::actuator::{IdealActuator, SecondOrderActuator};
use crate::effects::jitter::{GaussianJitter, Jitter, NoJitter};
use crate::effects::sensor::{PerfectSensor, SampledSensor, Sensor};
use crate::engine::integrate::{DragFlight, Rk4, Rk45};
use crate::engine::zeno::ZenoPolicy;
use crate::engine::{Ballistic, Flight};
use crate::model::line::{Advance, LinePlant, RestEvent};
use crate::model::surface::{Actuated, IdealMirror, Surface, Table};
use crate::scene::{param_error, ActuatorKind, ControlMode, Integrator, Model, Scene, SceneError};
use crate::trace::ImpactRow;
use dexter_core::mirror::MirrorLaw;
use dexter_core::protocol::SensorFrame;
use dexter_core::state::BallState;
use std::io::IsTerminal;
use std::time::Instant;

/// Most (b, b') samples kept for a phase portrait.
pub const MAX_PHASE_SAMPLES: usize = 200_000;

/// What to record and show during a run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunOptions {
    /// Keep every impact row (for traces, plots and tests). Apex heights are always kept.
    pub record_rows: bool,
    /// Keep (b, b') samples once per control step (SIL) for a phase portrait.
    pub record_phase: bool,
    /// Show a progress bar (only when stdout is a terminal).
    pub progress: bool,
}

/// Why a run failed.
#[derive(Debug)]
pub enum RunError {
    /// The scene cannot be run as asked.
    Scene(SceneError),
    /// The controller failed.
    Controller(ControllerError),
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Scene(e) => write!(f, "scene error: {e}"),
            RunError::Controller(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for RunError {}

impl From<SceneError> for RunError {
    fn from(e: SceneError) -> Self {
        RunError::Scene(e)
    }
}

impl From<ControllerError> for RunError {
    fn from(e: ControllerError) -> Self {
        RunError::Controller(e)
    }
}

/// Everything a run produced.
#[derive(Clone, Debug, Default)]
pub struct RunOutcome {
    /// Impact rows (empty unless [`RunOptions::record_rows`]).
    pub rows: Vec<ImpactRow>,
    /// Apex height after every impact, m.
    pub apexes_m: Vec<f64>,
    /// The last impact, if any.
    pub last_row: Option<ImpactRow>,
    /// Impacts simulated.
    pub impacts: u64,
    /// Simulated time at the end, s.
    pub sim_time_s: f64,
    /// Wall-clock time of the run, s.
    pub wall_time_s: f64,
    /// Control steps taken (0 without a controller).
    pub control_steps: u64,
    /// Resting-contact episodes (first 64).
    pub rests: Vec<RestEvent>,
    /// Resting-contact episodes in total.
    pub rest_count: u64,
    /// True if the ball rests on the paddle at the end.
    pub resting_at_end: bool,
    /// Grazing contacts.
    pub grazing_contacts: u64,
    /// (b, b') samples, m and m/s.
    pub phase: Vec<(f64, f64)>,
    /// Ball state at the end.
    pub final_ball: BallState<f64>,
    /// HIL timing and link figures, if the controller ran on a target.
    pub hil: Option<HilReport>,
}

/// Run `scene` with `options`. For `control.mode = "sil"` the controller is `controller`
/// if given (e.g. a HIL lock-step), else the core linked in ([`Sil`]).
pub fn run_scene(
    scene: &Scene,
    options: &RunOptions,
    controller: Option<&mut dyn StepController>,
) -> Result<RunOutcome, RunError> {
    match scene.scene.model {
        Model::Line => with_flight(scene, options, controller),
    }
}

fn with_flight(
    s: &Scene,
    o: &RunOptions,
    c: Option<&mut dyn StepController>,
) -> Result<RunOutcome, RunError> {
    match &s.drag {
        None => with_jitter(s, o, c, Ballistic),
        Some(d) => match d.integrator {
            Integrator::Rk4 => with_jitter(
                s,
                o,
                c,
                DragFlight::new(Rk4, d.coefficient_per_m, d.step_s, d.tolerance),
            ),
            Integrator::Rk45 => with_jitter(
                s,
                o,
                c,
                DragFlight::new(Rk45, d.coefficient_per_m, d.step_s, d.tolerance),
            ),
        },
    }
}

fn with_jitter<F: Flight>(
    s: &Scene,
    o: &RunOptions,
    c: Option<&mut dyn StepController>,
    flight: F,
) -> Result<RunOutcome, RunError> {
    match &s.jitter {
        None => with_surface(s, o, c, flight, NoJitter),
        Some(j) => with_surface(s, o, c, flight, GaussianJitter::new(j.sigma_s, j.seed)),
    }
}

fn zeno_policy(s: &Scene) -> ZenoPolicy {
    ZenoPolicy {
        velocity_threshold_mps: s.zeno.velocity_threshold_mps,
        relative_threshold: s.zeno.relative_threshold,
        max_impacts_per_segment: s.zeno.max_impacts_per_segment,
    }
}

fn with_surface<F: Flight, J: Jitter>(
    s: &Scene,
    o: &RunOptions,
    c: Option<&mut dyn StepController>,
    flight: F,
    jitter: J,
) -> Result<RunOutcome, RunError> {
    let g = s.physics.gravity_mps2;
    let e = s.physics.restitution;
    let ball = BallState::new(s.ball.height_m, s.ball.velocity_mps);
    let zeno = zeno_policy(s);
    let needs_controller = |what: &str| -> Result<(), RunError> {
        if c.is_some() {
            Err(SceneError::new(
                "control.mode",
                format!("is \"{what}\": an external controller (--hil) needs \"sil\""),
            )
            .into())
        } else {
            Ok(())
        }
    };
    match s.control.mode {
        ControlMode::None => {
            needs_controller("none")?;
            let table = Table {
                height_m: s.table.height_m,
            };
            Ok(free_run(
                s,
                o,
                LinePlant::new(g, e, flight, table, jitter, zeno, ball),
            ))
        }
        ControlMode::IdealMirror => {
            needs_controller("ideal_mirror")?;
            let target = s
                .control
                .target_apex_m
                .ok_or_else(|| SceneError::new("control.target_apex_m", "missing"))?;
            let law = MirrorLaw::new(s.kappa0(), s.control.kappa1_s2pm2, target, g)
                .map_err(|e| param_error(&e))?;
            let surface = IdealMirror { law };
            Ok(free_run(
                s,
                o,
                LinePlant::new(g, e, flight, surface, jitter, zeno, ball),
            ))
        }
        ControlMode::Sil => {
            let a = &s.actuator;
            match a.kind {
                ActuatorKind::Ideal => {
                    let surface = Actuated::new(IdealActuator, a.initial_height_m);
                    with_sensor(
                        s,
                        o,
                        c,
                        LinePlant::new(g, e, flight, surface, jitter, zeno, ball),
                    )
                }
                ActuatorKind::SecondOrder => {
                    let act = SecondOrderActuator {
                        accel_max_mps2: a.accel_max_mps2,
                        velocity_max_mps: a.velocity_max_mps,
                        min_height_m: a.min_height_m,
                        max_height_m: a.max_height_m,
                    };
                    let surface = Actuated::new(act, a.initial_height_m);
                    with_sensor(
                        s,
                        o,
                        c,
                        LinePlant::new(g, e, flight, surface, jitter, zeno, ball),
                    )
                }
            }
        }
    }
}

fn with_sensor<F: Flight, S: Surface, J: Jitter>(
    s: &Scene,
    o: &RunOptions,
    c: Option<&mut dyn StepController>,
    plant: LinePlant<F, S, J>,
) -> Result<RunOutcome, RunError> {
    let mut own;
    let ctrl: &mut dyn StepController = match c {
        Some(c) => c,
        None => {
            own = Sil::new(s.controller_params()?)?;
            &mut own
        }
    };
    match &s.sensor {
        None => stepped_run(s, o, ctrl, plant, PerfectSensor),
        Some(x) => {
            let rate = x.rate_hz.unwrap_or(s.control.rate_hz);
            let sensor =
                SampledSensor::new(rate, x.noise_sigma_m, x.latency_s, x.quantization_m, x.seed);
            stepped_run(s, o, ctrl, plant, sensor)
        }
    }
}

/// Collects impacts into the outcome.
struct Recorder<'a> {
    out: &'a mut RunOutcome,
    keep_rows: bool,
}

impl Recorder<'_> {
    #[inline]
    fn push(&mut self, row: &ImpactRow) {
        self.out.apexes_m.push(row.apex_height_m);
        self.out.last_row = Some(*row);
        if self.keep_rows {
            self.out.rows.push(*row);
        }
    }
}

fn progress_bar(o: &RunOptions, len: u64) -> indicatif::ProgressBar {
    if o.progress && std::io::stdout().is_terminal() && len > 10_000 {
        let pb = indicatif::ProgressBar::new(len);
        pb.set_style(
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} impacts {elapsed}/{eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        pb
    } else {
        indicatif::ProgressBar::hidden()
    }
}

fn finish<F: Flight, S: Surface, J: Jitter>(
    out: &mut RunOutcome,
    plant: &LinePlant<F, S, J>,
    start: Instant,
) {
    out.impacts = plant.impacts;
    out.sim_time_s = plant.time_s;
    out.wall_time_s = start.elapsed().as_secs_f64();
    out.rests = plant.rests.clone();
    out.rest_count = plant.rest_count;
    out.resting_at_end = plant.resting;
    out.grazing_contacts = plant.grazing_contacts;
    out.final_ball = plant.ball;
}

/// Impact-to-impact run without a controller (table, ideal mirror).
fn free_run<F: Flight, S: Surface, J: Jitter>(
    s: &Scene,
    o: &RunOptions,
    mut plant: LinePlant<F, S, J>,
) -> RunOutcome {
    let start = Instant::now();
    let total = s.stop.impacts;
    let mut out = RunOutcome::default();
    let pb = progress_bar(o, total);
    {
        let mut rec = Recorder {
            out: &mut out,
            keep_rows: o.record_rows,
        };
        let chunk = 10_000u64;
        // every iteration either adds `chunk` impacts or ends the run: bounded by total/chunk
        for _ in 0..=(total / chunk + 1) {
            let goal = (plant.impacts + chunk).min(total);
            match plant.advance_to(s.stop.duration_s, goal, &mut |r| rec.push(r)) {
                Advance::ImpactLimit if plant.impacts < total => pb.set_position(plant.impacts),
                Advance::SegmentCap => pb.set_position(plant.impacts),
                _ => break,
            }
        }
    }
    pb.finish_and_clear();
    finish(&mut out, &plant, start);
    out
}

/// Fixed-rate run: a sensor frame at every control step, the command held for the period.
fn stepped_run<F: Flight, S: Surface, J: Jitter, Z: Sensor>(
    s: &Scene,
    o: &RunOptions,
    ctrl: &mut dyn StepController,
    mut plant: LinePlant<F, S, J>,
    mut sensor: Z,
) -> Result<RunOutcome, RunError> {
    let start = Instant::now();
    let dt = 1.0 / s.control.rate_hz;
    let total = s.stop.impacts;
    let max_steps = (s.stop.duration_s / dt).ceil() as u64;
    let mut out = RunOutcome::default();
    let pb = progress_bar(o, total);
    let phase_every = (max_steps / MAX_PHASE_SAMPLES as u64).max(1);
    let mut steps = 0u64;
    {
        let mut rec = Recorder {
            out: &mut out,
            keep_rows: o.record_rows,
        };
        'steps: for k in 0..max_steps {
            if plant.impacts >= total {
                break;
            }
            let t_k = k as f64 * dt;
            // samples due now are taken before the frame is formed
            let mut guard = 0;
            while sensor.next_sample_time_s() <= plant.time_s && guard < 1024 {
                sensor.sample(plant.time_s, plant.ball.height_m);
                guard += 1;
            }
            let paddle = plant.surface.state(&plant.ball);
            let (seq, z) = sensor.frame(k, t_k, plant.ball.height_m);
            let frame = SensorFrame {
                seq,
                ball_height_m: z,
                paddle_height_m: paddle.height_m as f32,
                paddle_velocity_mps: paddle.velocity_mps as f32,
            };
            let step = ctrl.step(&frame)?;
            steps += 1;
            plant
                .surface
                .command(f64::from(step.command.paddle_accel_mps2));
            if o.record_phase && k % phase_every == 0 && rec.out.phase.len() < MAX_PHASE_SAMPLES {
                rec.out
                    .phase
                    .push((plant.ball.height_m, plant.ball.velocity_mps));
            }
            let t_next = (k + 1) as f64 * dt;
            // sub-segments end at sample times; at most a bounded number per step
            for _ in 0..4096 {
                let ts = sensor.next_sample_time_s();
                if ts <= plant.time_s {
                    sensor.sample(plant.time_s, plant.ball.height_m);
                    continue;
                }
                let target = ts.min(t_next);
                let mut adv = Advance::SegmentCap;
                for _ in 0..64 {
                    adv = plant.advance_to(target, total, &mut |r| rec.push(r));
                    if adv != Advance::SegmentCap {
                        break;
                    }
                }
                if adv == Advance::ImpactLimit {
                    break 'steps;
                }
                if plant.time_s >= t_next {
                    break;
                }
            }
            if k % 1000 == 0 {
                pb.set_position(plant.impacts);
            }
        }
    }
    pb.finish_and_clear();
    finish(&mut out, &plant, start);
    out.control_steps = steps;
    out.hil = ctrl.hil_report();
    Ok(out)
}
