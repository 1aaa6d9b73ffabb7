//! Assembling the line plant from a scene, once: every switch (flight with or without
//! drag, jitter, surface, actuator, sensor) picks a concrete type, so the loops in
//! [`super::loops`] are monomorphized for the enabled effects and an absent effect costs
//! nothing (a zero-sized "off" type, not a per-step `if`).

use super::loops::{free_run, segments, stepped_run};
use super::outcome::{Recorder, RunError, RunOptions};
use super::scene::{ActuatorKind, ControlMode, Integrator, Scene};
use crate::controller::{Sil, StepController};
use crate::effects::actuator::{IdealActuator, SecondOrderActuator};
use crate::effects::jitter::{GaussianJitter, Jitter, NoJitter};
use crate::effects::sensor::{PerfectSensor, SampledSensor, SteppedSensor};
use crate::engine::drag::{DragFlight, Rk4, Rk45};
use crate::engine::zeno::ZenoPolicy;
use crate::engine::{Ballistic, Flight};
use crate::model::line::LinePlant;
use crate::model::surface::{Actuated, IdealMirror, Surface, Table};
use crate::scene::SceneError;
use dexter_core::mirror::MirrorLaw;
use dexter_core::state::BallState;

type Ctrl<'a> = Option<&'a mut dyn StepController>;

/// Assemble the plant of `s` and run it, recording into `rec`.
pub(super) fn run(
    s: &Scene,
    o: &RunOptions,
    c: Ctrl<'_>,
    rec: &mut Recorder,
) -> Result<(), RunError> {
    match &s.drag {
        None if s.jitter.is_none() && s.control.mode == ControlMode::None => table(s, o, rec),
        None => with_jitter(s, o, c, rec, Ballistic),
        Some(d) => match d.integrator {
            Integrator::Rk4 => {
                let f = DragFlight::new(Rk4, d.coefficient_per_m, d.step_s, d.tolerance);
                with_jitter(s, o, c, rec, f)
            }
            Integrator::Rk45 => {
                let f = DragFlight::new(Rk45, d.coefficient_per_m, d.step_s, d.tolerance);
                with_jitter(s, o, c, rec, f)
            }
        },
    }
}

/// The passive bounce (no drag, no jitter, a fixed table): its bounces in closed form.
fn table(s: &Scene, o: &RunOptions, rec: &mut Recorder) -> Result<(), RunError> {
    let table = Table {
        height_m: s.table.height_m,
    };
    let plant = plant(s, Ballistic, table, NoJitter);
    free_run(s, o, plant, rec, |p, t_end_s, max_impacts, rec| {
        p.bounce_to(t_end_s, max_impacts, &mut |r| rec.push(r))
    })
}

fn with_jitter<F: Flight>(
    s: &Scene,
    o: &RunOptions,
    c: Ctrl<'_>,
    rec: &mut Recorder,
    flight: F,
) -> Result<(), RunError> {
    match &s.jitter {
        None => with_surface(s, o, c, rec, flight, NoJitter),
        Some(j) => with_surface(s, o, c, rec, flight, GaussianJitter::new(j.sigma_s, j.seed)),
    }
}

fn zeno_policy(s: &Scene) -> ZenoPolicy {
    ZenoPolicy {
        velocity_threshold_mps: s.zeno.velocity_threshold_mps,
        relative_threshold: s.zeno.relative_threshold,
        max_impacts_per_segment: s.zeno.max_impacts_per_segment,
    }
}

/// The plant of `s` over `surface`.
fn plant<F: Flight, S: Surface, J: Jitter>(
    s: &Scene,
    flight: F,
    surface: S,
    jitter: J,
) -> LinePlant<F, S, J> {
    let ball = BallState::new(s.ball.height_m, s.ball.velocity_mps);
    let (g, e) = (s.physics.gravity_mps2, s.physics.restitution);
    LinePlant::new(g, e, flight, surface, jitter, zeno_policy(s), ball)
}

fn with_surface<F: Flight, J: Jitter>(
    s: &Scene,
    o: &RunOptions,
    c: Ctrl<'_>,
    rec: &mut Recorder,
    flight: F,
    jitter: J,
) -> Result<(), RunError> {
    match s.control.mode {
        ControlMode::None => {
            let table = Table {
                height_m: s.table.height_m,
            };
            free_run(s, o, plant(s, flight, table, jitter), rec, segments)?;
        }
        ControlMode::IdealMirror => {
            let target = s
                .control
                .target_apex_m
                .ok_or_else(|| SceneError::new("control.target_apex_m", "missing"))?;
            let g = s.physics.gravity_mps2;
            let law = MirrorLaw::new(s.kappa0(), s.control.kappa1_s2pm2, target, g)
                .map_err(|e| super::validate::param_error(&e))?;
            let mirror = plant(s, flight, IdealMirror { law }, jitter);
            free_run(s, o, mirror, rec, segments)?;
        }
        ControlMode::Sil => {
            let a = &s.actuator;
            match a.kind {
                ActuatorKind::Ideal => {
                    let surface = Actuated::new(IdealActuator, a.initial_height_m)
                        .quiet_for(quiet_window_s(s), s.physics.gravity_mps2);
                    with_sensor(s, o, c, rec, plant(s, flight, surface, jitter))?;
                }
                ActuatorKind::SecondOrder => {
                    let act = SecondOrderActuator {
                        accel_max_mps2: a.accel_max_mps2,
                        velocity_max_mps: a.velocity_max_mps,
                        min_height_m: a.min_height_m,
                        max_height_m: a.max_height_m,
                    };
                    let surface = Actuated::new(act, a.initial_height_m)
                        .quiet_for(quiet_window_s(s), s.physics.gravity_mps2);
                    with_sensor(s, o, c, rec, plant(s, flight, surface, jitter))?;
                }
            }
        }
    }
    Ok(())
}

/// The longest control period of `s` with its rounding, s: a period's length `t_k+1 - t_k`
/// differs from `1 / rate` by an ulp of `t`, 1e-6 relative until `t` is some 4e6 periods
/// (a longer run takes its later periods through the general segment loop, as exactly).
fn quiet_window_s(s: &Scene) -> f64 {
    (1.0 + 1e-6) / s.control.rate_hz
}

fn with_sensor<F: Flight, S: Surface, J: Jitter>(
    s: &Scene,
    o: &RunOptions,
    c: Ctrl<'_>,
    rec: &mut Recorder,
    plant: LinePlant<F, S, J>,
) -> Result<(), RunError> {
    match c {
        Some(c) => sensed(s, o, c, rec, plant),
        None => sensed(s, o, &mut Sil::new(s.controller_params()?)?, rec, plant),
    }
}

/// The stepped run of `plant` with the sensor of `s`, closed through `ctrl` (the core
/// linked in, or a controller behind a link).
fn sensed<F: Flight, S: Surface, J: Jitter, C: StepController + ?Sized>(
    s: &Scene,
    o: &RunOptions,
    ctrl: &mut C,
    rec: &mut Recorder,
    plant: LinePlant<F, S, J>,
) -> Result<(), RunError> {
    match &s.sensor {
        None => stepped_run(s, o, ctrl, plant, PerfectSensor::default(), rec),
        Some(x) => {
            let rate = x.rate_hz.unwrap_or(s.control.rate_hz);
            let (sigma, latency, step) = (x.noise_sigma_m, x.latency_s, x.quantization_m);
            if rate == s.control.rate_hz {
                // the samples fall on the control steps: the same samples, taken there
                let sensor = SteppedSensor::new(1.0 / rate, sigma, latency, step, x.seed);
                stepped_run(s, o, ctrl, plant, sensor, rec)
            } else {
                let sensor = SampledSensor::new(rate, sigma, latency, step, x.seed);
                stepped_run(s, o, ctrl, plant, sensor, rec)
            }
        }
    }
}
