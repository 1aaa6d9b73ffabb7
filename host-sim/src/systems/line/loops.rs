//! The line plant's two runs: impact to impact without a controller (table, ideal mirror),
//! and sampled at the controller's fixed rate ([`SampledPlant`]: a sensor frame per step,
//! the command held for the period), closed by the one fixed-rate loop, [`drive`].

use super::outcome::{End, Recorder, RunError, RunOptions, MAX_PHASE_SAMPLES};
use super::scene::Scene;
use crate::closed_loop::{drive, SampledPlant};
use crate::controller::StepController;
use crate::effects::jitter::Jitter;
use crate::effects::sensor::{index_time_s, Sensor};
use crate::engine::Flight;
use crate::model::line::{Advance, LinePlant};
use crate::model::surface::Surface;
use crate::progress;
use dexter_core::control::Controller;
use dexter_core::protocol::{ActuatorCommand, SensorFrame};
use std::ops::ControlFlow;
use std::time::Instant;

/// Impacts between progress updates of an event-driven run.
const CHUNK_IMPACTS: u64 = 10_000;

/// The progress of a run of `s` towards whichever of its limits (impacts, time) it reaches
/// first; shown on a terminal once the run has taken a while ([`progress::Progress`]).
fn bar(o: &RunOptions, s: &Scene) -> progress::Progress {
    progress::Progress::new(
        [
            (s.stop.impacts as f64, "impacts"),
            (s.stop.duration_s, "s simulated"),
        ],
        o.progress,
    )
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
    out.last_row = (plant.impacts > 0).then_some(plant.last_row);
}

/// The general segment loop ([`LinePlant::advance_to`]).
#[inline(always)]
pub(super) fn segments<F: Flight, S: Surface, J: Jitter>(
    plant: &mut LinePlant<F, S, J>,
    t_end_s: f64,
    max_impacts: u64,
    rec: &mut Recorder,
) -> Advance {
    plant.advance_to(t_end_s, max_impacts, &mut |r| rec.push(r))
}

/// Impact-to-impact run without a controller (table, ideal mirror): to the impact limit,
/// the time limit, or resting contact on a table, each stretch advanced by `advance`. Every
/// call of the plant either adds impacts or advances time; one that does neither is an
/// error, never a silent end. `advance` takes the plant to a time or an impact count,
/// recording impacts: [`segments`] (the general loop) or a closed form for the plant's
/// case ([`LinePlant::bounce_to`], the passive bounce); monomorphized, so inlined.
pub(super) fn free_run<F: Flight, S: Surface, J: Jitter, A>(
    s: &Scene,
    o: &RunOptions,
    mut plant: LinePlant<F, S, J>,
    rec: &mut Recorder,
    advance: A,
) -> Result<(), RunError>
where
    A: Fn(&mut LinePlant<F, S, J>, f64, u64, &mut Recorder) -> Advance,
{
    let start = Instant::now();
    let total = s.stop.impacts;
    let mut pb = bar(o, s);
    let end = loop {
        let goal = (plant.impacts + CHUNK_IMPACTS).min(total);
        let before = (plant.impacts, plant.time_s);
        let advance = advance(&mut plant, s.stop.duration_s, goal, rec);
        if J::ON && plant.jitter.unphysical().is_some() {
            return Err(unphysical(&plant));
        }
        match advance {
            Advance::ImpactLimit if plant.impacts >= total => break End::Impacts,
            Advance::ImpactLimit => {}
            Advance::SegmentCap if (plant.impacts, plant.time_s) == before => {
                return Err(stalled(&plant, "the flight makes no progress"));
            }
            Advance::SegmentCap => {}
            Advance::RestForever => break End::Resting,
            Advance::Reached => break End::Duration,
        }
        pb.update([plant.impacts as f64, plant.time_s]);
    };
    pb.finish();
    finish(rec, &plant, start);
    rec.out.end = end;
    Ok(())
}

/// The error of a plant that stopped advancing at its current time.
fn stalled<F: Flight, S: Surface, J: Jitter>(plant: &LinePlant<F, S, J>, why: &str) -> RunError {
    RunError::Stalled(format!(
        "{why} at t = {} s after {} impacts",
        plant.time_s, plant.impacts
    ))
}

/// The error of a plant whose last impact the jitter made unphysical.
fn unphysical<F: Flight, S: Surface, J: Jitter>(plant: &LinePlant<F, S, J>) -> RunError {
    let what = match plant.jitter.unphysical() {
        Some(u) => format!(
            "at t = {:.6} s the ball would leave at {:.4} m/s, slower than the paddle at \
             {:.4} m/s, so it would pass into it",
            u.time_s, u.ball_velocity_mps, u.surface_velocity_mps
        ),
        None => format!(
            "at t = {} s the ball would pass into the paddle",
            plant.time_s
        ),
    };
    RunError::Unphysical(format!(
        "{what}: the jittered paddle velocity made the restitution law's result unphysical \
         (jitter.sigma_s is too large for this paddle's acceleration; lower it)"
    ))
}

/// Most consecutive [`Advance::SegmentCap`] returns (each a million flight segments)
/// within one stretch between sensor samples before the run is declared stalled.
const MAX_SEGMENT_CAPS: u32 = 64;

/// Advance `plant` to `target_s` (or the impact limit `total`); true if that limit was
/// reached. A plant still short of the target after [`MAX_SEGMENT_CAPS`] calls is stalled.
#[inline(always)]
fn advance_stretch<F: Flight, S: Surface, J: Jitter>(
    plant: &mut LinePlant<F, S, J>,
    target_s: f64,
    total: u64,
    rec: &mut Recorder,
) -> Result<bool, RunError> {
    for _ in 0..MAX_SEGMENT_CAPS {
        match plant.advance_to(target_s, total, &mut |r| rec.push(r)) {
            Advance::SegmentCap => continue,
            adv => return Ok(adv == Advance::ImpactLimit),
        }
    }
    Err(stalled(
        plant,
        "a million flight segments did not reach the next sample",
    ))
}

/// Advance `plant` to the end of control period `t_next_s`, taking the sensor's samples at
/// their times (at most `samples` of them fall in one period; the loop is bounded by that
/// and fails rather than end the period early); true if the impact limit `total` was
/// reached.
#[inline(always)]
fn advance_period<F: Flight, S: Surface, J: Jitter, Z: Sensor>(
    plant: &mut LinePlant<F, S, J>,
    sensor: &mut Z,
    (t_next_s, samples): (f64, u64),
    total: u64,
    rec: &mut Recorder,
) -> Result<bool, RunError> {
    // each sample is one pass that takes it and one that advances to it, plus the last
    // stretch to the period's end
    for _ in 0..2 * samples + 4 {
        if plant.time_s >= t_next_s {
            return Ok(false);
        }
        let ts = sensor.next_sample_time_s();
        if ts <= plant.time_s {
            sensor.sample(plant.time_s, plant.ball.height_m);
        } else if advance_stretch(plant, earlier(ts, t_next_s), total, rec)? {
            return Ok(true);
        }
    }
    Err(stalled(plant, "the control period did not complete"))
}

/// The earlier of two times, s, neither NaN (`f64::min`'s NaN handling cost instructions
/// in the SIL loop's every period).
#[inline(always)]
fn earlier(a_s: f64, b_s: f64) -> f64 {
    if a_s < b_s {
        a_s
    } else {
        b_s
    }
}

/// Sensor samples that fall within one control period of `s` (at most; 0 for a sensor
/// that samples only at control steps).
fn samples_per_period(s: &Scene) -> u64 {
    s.sensor.as_ref().map_or(0, |x| {
        let rate = x.rate_hz.unwrap_or(s.control.rate_hz);
        (rate / s.control.rate_hz).ceil() as u64 + 1
    })
}

/// The line plant sampled at the controller's rate: the plant, its sensor, and what the
/// run records (impacts, phase samples, progress). The plant, the sensor and the progress
/// bar are borrowed, not owned: calls take their addresses, and one of a field would keep
/// the limits below in memory instead of registers (9 more instructions per SIL step).
struct Sampled<'r, 'a, F, S, J, Z> {
    plant: &'r mut LinePlant<F, S, J>,
    sensor: &'r mut Z,
    /// Most sensor samples in one control period ([`samples_per_period`]).
    samples: u64,
    /// The impact limit.
    total: u64,
    rec: &'r mut Recorder<'a>,
    /// The next step whose phase sample is recorded (`u64::MAX`: none), then every
    /// `phase_every` steps: one comparison a step.
    next_phase_step: u64,
    phase_every: u64,
    bar: &'r mut progress::Progress,
}

impl<F: Flight, S: Surface, J: Jitter, Z: Sensor> Sampled<'_, '_, F, S, J, Z> {
    /// A period with events (a sample, a contact, a limit): the general path, out of line
    /// so the quiet periods' loop keeps its registers.
    #[inline(never)]
    fn eventful_period(&mut self, t_next_s: f64) -> Result<bool, RunError> {
        let (plant, sensor) = (&mut *self.plant, &mut *self.sensor);
        advance_period(
            plant,
            sensor,
            (t_next_s, self.samples),
            self.total,
            self.rec,
        )
    }
}

impl<F: Flight, S: Surface, J: Jitter, Z: Sensor> SampledPlant<Controller>
    for Sampled<'_, '_, F, S, J, Z>
{
    type End = End;
    type Error = RunError;

    /// The sensor's sample-time expression, so control steps and samples coincide exactly.
    #[inline(always)]
    fn time_s(k: u64, dt_s: f64) -> f64 {
        index_time_s(k, dt_s)
    }

    /// Only before the first step: a period that reaches the impact limit ends the run
    /// from [`advance`](SampledPlant::advance) (every impact is counted against the limit
    /// where it happens, [`LinePlant::advance_to`]), so no later step starts over it, and
    /// the loop does not test it again.
    #[inline(always)]
    fn done(&self) -> Option<End> {
        None
    }

    /// The frame of control step `k` at `t_k_s`, after taking the samples due now.
    #[inline(always)]
    fn frame(&mut self, k: u64, t_k_s: f64) -> SensorFrame {
        let (plant, sensor) = (&*self.plant, &mut *self.sensor);
        // advance_period took every sample before t_k: at most the one at t_k is due
        while !sensor.at_control_steps() && sensor.next_sample_time_s() <= plant.time_s {
            sensor.sample(plant.time_s, plant.ball.height_m);
        }
        let paddle = plant.surface.state(&plant.ball);
        let (seq, z) = sensor.frame(k, t_k_s, plant.ball.height_m);
        // The ball's sample is ready early (it was taken `L` steps ago), the paddle's state
        // late (the end of the last period, which waited on the last command). Stored
        // together, as the compiler would (one 8-byte store of both converted at once), the
        // controller's estimator could not start before the paddle is known: the loop ran a
        // third slower in wall time for the same instructions (0.78 s against 0.57 s for
        // 20 000 s at 1 kHz, BENCHMARKS.md). `black_box` keeps the sample's store apart.
        SensorFrame {
            seq,
            ball_height_m: core::hint::black_box(z),
            paddle_height_m: paddle.height_m as f32,
            paddle_velocity_mps: paddle.velocity_mps as f32,
        }
    }

    #[inline(always)]
    fn apply(&mut self, k: u64, _t_k_s: f64, command: &ActuatorCommand) {
        self.plant
            .surface
            .command(f64::from(command.paddle_accel_mps2));
        if k == self.next_phase_step {
            self.next_phase_step += self.phase_every;
            let phase = &mut self.rec.out.phase;
            if phase.len() < MAX_PHASE_SAMPLES {
                phase.push((self.plant.ball.height_m, self.plant.ball.velocity_mps));
            }
        }
    }

    #[inline(always)]
    fn advance(&mut self, k: u64, t_next_s: f64) -> Result<ControlFlow<End>, RunError> {
        if LinePlant::<F, S, J>::QUIET_PERIODS {
            // most periods are quiet: their closed form inline, the rest out of line
            let no_sample =
                self.sensor.at_control_steps() || self.sensor.next_sample_time_s() >= t_next_s;
            let quiet = no_sample && self.plant.quiet_to(t_next_s);
            if !quiet && self.eventful_period(t_next_s)? {
                return Ok(ControlFlow::Break(End::Impacts));
            }
        } else {
            let (plant, sensor) = (&mut *self.plant, &mut *self.sensor);
            if advance_period(
                plant,
                sensor,
                (t_next_s, self.samples),
                self.total,
                self.rec,
            )? {
                return Ok(ControlFlow::Break(End::Impacts));
            }
        }
        let plant = &mut *self.plant;
        if k.is_multiple_of(1024) {
            // an impact the jitter made unphysical fails the run here (the ball left with
            // the paddle meanwhile): checked with the bar, so a step pays nothing for it
            if J::ON && plant.jitter.unphysical().is_some() {
                return Err(unphysical(plant));
            }
            self.bar.update([plant.impacts as f64, plant.time_s]);
        }
        Ok(ControlFlow::Continue(()))
    }
}

/// True if `plant` has reached the impact limit `total`.
fn plant_done<F: Flight, S: Surface, J: Jitter>(plant: &LinePlant<F, S, J>, total: u64) -> bool {
    plant.impacts >= total
}

/// Fixed-rate run: a sensor frame at every control step, the command held for the period;
/// to the impact limit or the time limit (every period is simulated whole), closed by
/// [`drive`] (which counts the safe-state steps). `C` is [`crate::controller::Sil`] for the
/// core linked in (monomorphized: no dynamic call, no telemetry built) or a
/// `dyn StepController` (the firmware in QEMU or on a board).
pub(super) fn stepped_run<F: Flight, S: Surface, J: Jitter, Z: Sensor, C>(
    s: &Scene,
    o: &RunOptions,
    ctrl: &mut C,
    mut plant: LinePlant<F, S, J>,
    mut sensor: Z,
    rec: &mut Recorder,
) -> Result<(), RunError>
where
    C: StepController + ?Sized,
{
    let start = Instant::now();
    let dt = 1.0 / s.control.rate_hz;
    let max_steps = (s.stop.duration_s / dt).ceil() as u64;
    let mut pb = bar(o, s);
    let mut run = Sampled {
        plant: &mut plant,
        sensor: &mut sensor,
        samples: samples_per_period(s),
        total: s.stop.impacts,
        rec,
        next_phase_step: if o.record_phase { 0 } else { u64::MAX },
        phase_every: (max_steps / MAX_PHASE_SAMPLES as u64).max(1),
        bar: &mut pb,
    };
    // a run whose impact limit is reached before it starts takes no step
    let steps = if plant_done(run.plant, run.total) {
        0
    } else {
        max_steps
    };
    let mut driven = drive(ctrl, &mut run, dt, steps)?;
    if steps == 0 && max_steps > 0 {
        driven.end = Some(End::Impacts);
    }
    pb.finish();
    if J::ON && plant.jitter.unphysical().is_some() {
        return Err(unphysical(&plant));
    }
    finish(rec, &plant, start);
    rec.out.end = driven.end.unwrap_or(End::Duration);
    rec.out.control_steps = driven.safe.steps;
    rec.out.safe = driven.safe;
    Ok(())
}
