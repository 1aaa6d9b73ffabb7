//! The line plant's two run loops: impact to impact without a controller (table, ideal
//! mirror), and at the controller's fixed rate with a sensor frame per step and the command
//! held for the period.

use super::run::{Recorder, RunError, RunOptions, MAX_PHASE_SAMPLES};
use super::scene::Scene;
use crate::controller::StepController;
use crate::effects::jitter::Jitter;
use crate::effects::sensor::Sensor;
use crate::engine::Flight;
use crate::model::line::{Advance, LinePlant};
use crate::model::surface::Surface;
use crate::progress;
use dexter_core::protocol::SensorFrame;
use std::time::Instant;

/// Impacts between progress updates of an event-driven run.
const CHUNK_IMPACTS: u64 = 10_000;
/// Runs shorter than this many impacts show no progress bar.
const PROGRESS_MIN_IMPACTS: u64 = 10_000;

fn bar(o: &RunOptions, total: u64) -> indicatif::ProgressBar {
    progress::bar(total, "impacts", o.progress && total > PROGRESS_MIN_IMPACTS)
}

/// The plant's counters into the outcome.
fn finish<F: Flight, S: Surface, J: Jitter>(
    rec: &mut Recorder,
    plant: &LinePlant<F, S, J>,
    start: Instant,
) {
    let out = &mut rec.out;
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
pub(super) fn free_run<F: Flight, S: Surface, J: Jitter>(
    s: &Scene,
    o: &RunOptions,
    mut plant: LinePlant<F, S, J>,
    rec: &mut Recorder,
) {
    let start = Instant::now();
    let total = s.stop.impacts;
    let pb = bar(o, total);
    // every iteration either adds CHUNK_IMPACTS impacts or ends the run
    for _ in 0..=(total / CHUNK_IMPACTS + 1) {
        let goal = (plant.impacts + CHUNK_IMPACTS).min(total);
        match plant.advance_to(s.stop.duration_s, goal, &mut |r| rec.push(r)) {
            Advance::ImpactLimit if plant.impacts < total => pb.set_position(plant.impacts),
            Advance::SegmentCap => pb.set_position(plant.impacts),
            _ => break,
        }
    }
    pb.finish_and_clear();
    finish(rec, &plant, start);
}

/// Advance `plant` to the end of control period `t_next_s`, taking the sensor's samples
/// at their times; true if the impact limit `total` was reached.
fn advance_period<F: Flight, S: Surface, J: Jitter, Z: Sensor>(
    plant: &mut LinePlant<F, S, J>,
    sensor: &mut Z,
    t_next_s: f64,
    total: u64,
    rec: &mut Recorder,
) -> bool {
    // sub-segments end at sample times; at most a bounded number per step
    for _ in 0..4096 {
        let ts = sensor.next_sample_time_s();
        if ts <= plant.time_s {
            sensor.sample(plant.time_s, plant.ball.height_m);
            continue;
        }
        let target = ts.min(t_next_s);
        let mut adv = Advance::SegmentCap;
        for _ in 0..64 {
            adv = plant.advance_to(target, total, &mut |r| rec.push(r));
            if adv != Advance::SegmentCap {
                break;
            }
        }
        if adv == Advance::ImpactLimit {
            return true;
        }
        if plant.time_s >= t_next_s {
            break;
        }
    }
    false
}

/// The frame of control step `k` at `t_k_s`, after taking the samples due now.
fn frame<F: Flight, S: Surface, J: Jitter, Z: Sensor>(
    plant: &LinePlant<F, S, J>,
    sensor: &mut Z,
    k: u64,
    t_k_s: f64,
) -> SensorFrame {
    let mut guard = 0;
    while sensor.next_sample_time_s() <= plant.time_s && guard < 1024 {
        sensor.sample(plant.time_s, plant.ball.height_m);
        guard += 1;
    }
    let paddle = plant.surface.state(&plant.ball);
    let (seq, z) = sensor.frame(k, t_k_s, plant.ball.height_m);
    SensorFrame {
        seq,
        ball_height_m: z,
        paddle_height_m: paddle.height_m as f32,
        paddle_velocity_mps: paddle.velocity_mps as f32,
    }
}

/// Fixed-rate run: a sensor frame at every control step, the command held for the period.
pub(super) fn stepped_run<F: Flight, S: Surface, J: Jitter, Z: Sensor>(
    s: &Scene,
    o: &RunOptions,
    ctrl: &mut dyn StepController,
    mut plant: LinePlant<F, S, J>,
    mut sensor: Z,
    rec: &mut Recorder,
) -> Result<(), RunError> {
    let start = Instant::now();
    let dt = 1.0 / s.control.rate_hz;
    let total = s.stop.impacts;
    let max_steps = (s.stop.duration_s / dt).ceil() as u64;
    let pb = bar(o, total);
    let phase_every = (max_steps / MAX_PHASE_SAMPLES as u64).max(1);
    let mut steps = 0u64;
    for k in 0..max_steps {
        if plant.impacts >= total {
            break;
        }
        let frame = frame(&plant, &mut sensor, k, k as f64 * dt);
        let step = ctrl.step(&frame)?;
        steps += 1;
        plant
            .surface
            .command(f64::from(step.command.paddle_accel_mps2));
        let phase = &mut rec.out.phase;
        if o.record_phase && k % phase_every == 0 && phase.len() < MAX_PHASE_SAMPLES {
            phase.push((plant.ball.height_m, plant.ball.velocity_mps));
        }
        if advance_period(&mut plant, &mut sensor, (k + 1) as f64 * dt, total, rec) {
            break;
        }
        if k % 1000 == 0 {
            pb.set_position(plant.impacts);
        }
    }
    pb.finish_and_clear();
    finish(rec, &plant, start);
    rec.out.control_steps = steps;
    rec.out.hil = ctrl.hil_report();
    Ok(())
}
