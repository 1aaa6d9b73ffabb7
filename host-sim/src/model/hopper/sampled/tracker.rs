//! Assembles the plant's true events and the controller's commands into cycles, timing
//! statistics and (optionally) per-cycle records and timeline rows.

use super::super::valve::TrueEvent;
use super::sensor::Truth;
use super::stats::{PhaseDetectionErrors, SETTLE_WINDOW};
use super::{SampledConfig, TimelineWindow, LATE_APEXES, MAX_CYCLE_RECORDS, MAX_TIMELINE_ROWS};
use dexter_core::fixed_rate::Mode;
use dexter_core::hop::StancePhase;
use dexter_core::hop_control::HopCommand;
use serde::Serialize;
use std::collections::VecDeque;

/// One hop of a sampled run: touchdown to the next touchdown. Times in s, heights in m,
/// velocities in m/s; NaN where the cycle had no such event.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SampledCycle {
    /// Cycle index (0 = the first touchdown).
    pub index: usize,
    /// True touchdown.
    pub touchdown_time_s: f64,
    /// Touchdown velocity (<= 0).
    pub touchdown_velocity_mps: f64,
    /// First true bottom of the stance.
    pub bottom_time_s: f64,
    /// Its height x_n.
    pub bottom_height_m: f64,
    /// First valve opening in the cycle (a control-step time).
    pub valve_open_time_s: f64,
    /// First valve closing after it.
    pub valve_close_time_s: f64,
    /// Thrust while open, m/s^2.
    pub thrust_mps2: f64,
    /// True liftoff.
    pub liftoff_time_s: f64,
    /// Liftoff velocity after the pickup of eq. 7.
    pub liftoff_velocity_mps: f64,
    /// The flight apex.
    pub apex_time_s: f64,
    /// Apex height.
    pub apex_height_m: f64,
    /// The next touchdown (the end of the cycle).
    pub next_touchdown_time_s: f64,
    /// First detected touchdown in the cycle (control-step time).
    pub detected_touchdown_s: f64,
    /// First detected bottom.
    pub detected_bottom_s: f64,
    /// First detected liftoff.
    pub detected_liftoff_s: f64,
    /// True if the leg extended with the valve open.
    pub early_liftoff: bool,
}

/// One control step, for a timeline plot.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TimelineRow {
    /// Control-step time, s.
    pub time_s: f64,
    /// Cycle index (0 before the first touchdown too).
    pub cycle: usize,
    /// True leg compression, m.
    pub compression_m: f64,
    /// The compression in the frame the controller got, m (NaN if none).
    pub measured_compression_m: f64,
    /// True foot contact.
    pub contact: bool,
    /// The true phase at the step, as the exactly timed law has it: flight, compression
    /// until the true bottom, thrust for delta from it, decompression until liftoff.
    pub true_phase: StancePhase,
    /// The phase the controller reports.
    pub detected_phase: StancePhase,
    /// The valve as applied.
    pub valve_open: bool,
    /// The controller's mode.
    pub mode: Mode,
}

/// First time and count of a detected transition.
#[derive(Clone, Copy, Debug, Default)]
struct Detections {
    count: u32,
    first_s: Option<f64>,
}

impl Detections {
    fn push(&mut self, t: f64) {
        self.count += 1;
        self.first_s.get_or_insert(t);
    }
    fn first(&self) -> f64 {
        self.first_s.unwrap_or(f64::NAN)
    }
}

/// The cycle being assembled.
#[derive(Clone, Copy, Debug)]
struct Open {
    index: usize,
    touchdown: (f64, f64),
    bottom: Option<(f64, f64)>,
    liftoff: Option<(f64, f64, bool)>,
    apex: Option<(f64, f64)>,
    valve_open: Option<f64>,
    valve_close: Option<f64>,
    thrust: f64,
    touchdowns: Detections,
    bottoms: Detections,
    liftoffs: Detections,
}

/// What the tracker hands back at the end.
pub(super) struct Parts {
    pub completed: usize,
    pub late_apexes: Vec<f64>,
    pub errors: PhaseDetectionErrors,
    pub records: Vec<SampledCycle>,
    pub timeline: Vec<TimelineRow>,
    pub early_liftoffs: u64,
}

pub(super) struct Tracker<'a> {
    sink: &'a mut dyn FnMut(&SampledCycle),
    chi_l: f64,
    g: f64,
    delta_s: f64,
    open: Option<Open>,
    completed: usize,
    recent: VecDeque<f64>,
    late: VecDeque<f64>,
    errors: PhaseDetectionErrors,
    records: Option<Vec<SampledCycle>>,
    timeline_window: Option<TimelineWindow>,
    timeline: Vec<TimelineRow>,
    early_liftoffs: u64,
    last_phase: StancePhase,
    last_valve: bool,
}

impl<'a> Tracker<'a> {
    pub fn new(cfg: &SampledConfig, sink: &'a mut dyn FnMut(&SampledCycle)) -> Self {
        Self {
            sink,
            chi_l: cfg.model.liftoff_m(),
            g: cfg.model.gravity_mps2(),
            delta_s: f64::from(cfg.control.thrust_duration_s),
            open: None,
            completed: 0,
            recent: VecDeque::with_capacity(2 * SETTLE_WINDOW + 1),
            late: VecDeque::with_capacity(LATE_APEXES + 1),
            errors: PhaseDetectionErrors::default(),
            records: cfg.record_cycles.then(Vec::new),
            timeline_window: cfg.timeline,
            timeline: Vec::new(),
            early_liftoffs: 0,
            last_phase: StancePhase::Flight,
            last_valve: false,
        }
    }

    pub fn completed(&self) -> usize {
        self.completed
    }

    /// Hop heights of the last 2 windows of cycles, m.
    pub fn recent_hop_heights(&self) -> Vec<f64> {
        self.recent.iter().copied().collect()
    }

    pub fn on_event(&mut self, e: TrueEvent) {
        match e {
            TrueEvent::Touchdown {
                time_s,
                velocity_mps,
            } => {
                if let Some(c) = self.open.take() {
                    self.close(c, time_s);
                }
                self.open = Some(Open {
                    index: self.completed,
                    touchdown: (time_s, velocity_mps),
                    bottom: None,
                    liftoff: None,
                    apex: None,
                    valve_open: None,
                    valve_close: None,
                    thrust: f64::NAN,
                    touchdowns: Detections::default(),
                    bottoms: Detections::default(),
                    liftoffs: Detections::default(),
                });
            }
            TrueEvent::Bottom { time_s, height_m } => {
                if let Some(c) = &mut self.open {
                    c.bottom.get_or_insert((time_s, height_m));
                }
            }
            TrueEvent::Liftoff {
                time_s,
                velocity_mps,
                during_thrust,
                ..
            } => {
                self.early_liftoffs += u64::from(during_thrust);
                if let Some(c) = &mut self.open {
                    c.liftoff
                        .get_or_insert((time_s, velocity_mps, during_thrust));
                }
            }
            TrueEvent::Apex { time_s, height_m } => {
                if let Some(c) = &mut self.open {
                    c.apex.get_or_insert((time_s, height_m));
                }
            }
        }
    }

    /// One control step at `t`: the command, whether the valve was applied open, the truth
    /// and the true phase before the command, and the measured compression of the frame.
    pub fn on_command(
        &mut self,
        t: f64,
        cmd: &HopCommand,
        applied_open: bool,
        truth: Truth,
        true_phase: StancePhase,
        measured_compression_m: Option<f64>,
    ) {
        use StancePhase::*;
        let (from, to) = (self.last_phase, cmd.phase);
        let safe = cmd.mode == Mode::Safe;
        if let Some(c) = &mut self.open {
            match (from, to) {
                (Flight, Compression) => c.touchdowns.push(t),
                (Compression, Thrust | Decompression) => c.bottoms.push(t),
                (Compression | Thrust | Decompression, Flight) if !safe => c.liftoffs.push(t),
                _ => {}
            }
            if applied_open && !self.last_valve {
                c.valve_open.get_or_insert(t);
                c.thrust = if c.thrust.is_nan() {
                    f64::from(cmd.thrust_mps2)
                } else {
                    c.thrust
                };
            }
            if !applied_open && self.last_valve && c.valve_open.is_some() {
                c.valve_close.get_or_insert(t);
            }
        }
        self.errors.steps += 1;
        if (to != Flight) != truth.contact {
            self.errors.phase_mismatch_steps += 1;
        }
        self.last_phase = to;
        self.last_valve = applied_open;
        let true_phase = self.exact_phase(t, true_phase);
        self.timeline_row(
            t,
            cmd,
            applied_open,
            truth,
            true_phase,
            measured_compression_m,
        );
    }

    /// The exactly timed law's phase at `t`, from the plant's (flight or stance) and the
    /// cycle's true bottom.
    fn exact_phase(&self, t: f64, plant: StancePhase) -> StancePhase {
        if plant == StancePhase::Flight {
            return StancePhase::Flight;
        }
        match self.open.and_then(|c| c.bottom) {
            Some((t_b, _)) if t >= t_b && t < t_b + self.delta_s => StancePhase::Thrust,
            Some((t_b, _)) if t >= t_b => StancePhase::Decompression,
            _ => StancePhase::Compression,
        }
    }

    fn timeline_row(
        &mut self,
        t: f64,
        cmd: &HopCommand,
        open: bool,
        truth: Truth,
        true_phase: StancePhase,
        measured: Option<f64>,
    ) {
        let Some(w) = self.timeline_window else {
            return;
        };
        let cycle = self.open.map_or(0, |c| c.index);
        if cycle < w.first_cycle
            || cycle >= w.first_cycle.saturating_add(w.cycles)
            || self.timeline.len() >= MAX_TIMELINE_ROWS
        {
            return;
        }
        self.timeline.push(TimelineRow {
            time_s: t,
            cycle,
            compression_m: truth.compression_m,
            measured_compression_m: measured.unwrap_or(f64::NAN),
            contact: truth.contact,
            true_phase,
            detected_phase: cmd.phase,
            valve_open: open,
            mode: cmd.mode,
        });
    }

    /// The cycle `c` ended with the touchdown at `next_s`.
    fn close(&mut self, c: Open, next_s: f64) {
        let e = &mut self.errors;
        e.touchdown.cycle(
            Some(c.touchdown.0),
            c.touchdowns.count,
            c.touchdowns.first(),
        );
        e.bottom
            .cycle(c.bottom.map(|b| b.0), c.bottoms.count, c.bottoms.first());
        e.liftoff
            .cycle(c.liftoff.map(|l| l.0), c.liftoffs.count, c.liftoffs.first());
        if let (Some((t_b, _)), Some(open)) = (c.bottom, c.valve_open) {
            e.thrust_start_s.push(open - t_b);
            if let Some(close) = c.valve_close {
                e.thrust_end_s.push(close - (t_b + self.delta_s));
            }
        }
        let v_l = c.liftoff.map_or(f64::NAN, |l| l.1);
        let hop_m = v_l * v_l / (2.0 * self.g);
        let apex = c.apex.unwrap_or((f64::NAN, self.chi_l + hop_m));
        push_capped(&mut self.recent, hop_m, 2 * SETTLE_WINDOW);
        push_capped(&mut self.late, apex.1, LATE_APEXES);
        self.completed += 1;
        let nan2 = (f64::NAN, f64::NAN);
        let record = SampledCycle {
            index: c.index,
            touchdown_time_s: c.touchdown.0,
            touchdown_velocity_mps: c.touchdown.1,
            bottom_time_s: c.bottom.unwrap_or(nan2).0,
            bottom_height_m: c.bottom.unwrap_or(nan2).1,
            valve_open_time_s: c.valve_open.unwrap_or(f64::NAN),
            valve_close_time_s: c.valve_close.unwrap_or(f64::NAN),
            thrust_mps2: c.thrust,
            liftoff_time_s: c.liftoff.map_or(f64::NAN, |l| l.0),
            liftoff_velocity_mps: v_l,
            apex_time_s: apex.0,
            apex_height_m: apex.1,
            next_touchdown_time_s: next_s,
            detected_touchdown_s: c.touchdowns.first(),
            detected_bottom_s: c.bottoms.first(),
            detected_liftoff_s: c.liftoffs.first(),
            early_liftoff: c.liftoff.is_some_and(|l| l.2),
        };
        (self.sink)(&record);
        if let Some(r) = &mut self.records {
            if r.len() < MAX_CYCLE_RECORDS {
                r.push(record);
            }
        }
    }

    pub fn into_parts(self) -> Parts {
        Parts {
            completed: self.completed,
            late_apexes: self.late.into_iter().collect(),
            errors: self.errors,
            records: self.records.unwrap_or_default(),
            timeline: self.timeline,
            early_liftoffs: self.early_liftoffs,
        }
    }
}

fn push_capped(q: &mut VecDeque<f64>, v: f64, cap: usize) {
    q.push_back(v);
    while q.len() > cap {
        q.pop_front();
    }
}
