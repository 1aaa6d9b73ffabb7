//! The controller side of a closed-loop run, behind one trait so the same plant can be
//! closed through the core linked in (SIL) or through the firmware in QEMU (HIL).
//!
//! [`StepController`] is generic over the core's controller kind ([`FixedRate`]): a plant
//! sends that controller's frames and applies its commands, whether the controller is the
//! core linked in ([`Sil`]) or the firmware behind a link (`crate::hil`).

use dexter_core::control::Controller;
use dexter_core::fixed_rate::{Fault, FixedRate, Mode, Reply, Telemetry};
use dexter_core::params::ParamError;
use serde::Serialize;
use std::collections::BTreeMap;

/// What one control step returns: a command of the controller kind `C`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepOutput<Cmd = dexter_core::protocol::ActuatorCommand> {
    /// The command to apply for the next control period.
    pub command: Cmd,
    /// Telemetry, when the controller reports it (the firmware does; SIL fills what the core knows).
    pub telemetry: Telemetry,
}

/// Why a controller could not be stepped.
#[derive(Debug)]
pub enum ControllerError {
    /// The parameters were rejected.
    Params(ParamError),
    /// The link to an external controller failed (I/O, timeout, emulator exited).
    Link(String),
}

impl std::fmt::Display for ControllerError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ControllerError::Params(e) => write!(f, "controller parameter error: {e}"),
            ControllerError::Link(e) => write!(f, "controller link error: {e}"),
        }
    }
}

impl std::error::Error for ControllerError {}

/// Timing and link figures of a hardware-in-the-loop run (the `--json` keys HIL adds).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct HilReport {
    /// Fewest instructions one control step took on the target.
    pub step_instructions_min: u32,
    /// Mean instructions per control step on the target.
    pub step_instructions_mean: f64,
    /// Most instructions one control step took on the target.
    pub step_instructions_max: u32,
    /// Steps whose firmware command differed (bit for bit) from the SIL core's.
    pub sil_mismatches: u64,
    /// Frames rejected on the link, both directions (CRC, framing, decode).
    pub link_errors: u64,
    /// Control steps that exceeded the instruction budget.
    pub over_budget_steps: u64,
    /// Steps the firmware answered in its safe state because of a link timeout.
    pub link_timeouts: u64,
    /// Control steps per wall-clock second over the link.
    pub steps_per_wall_second: f64,
}

impl HilReport {
    /// The `HIL` line of a text summary (the same for every system).
    pub fn text(&self) -> String {
        format!(
            "HIL              {} mismatches, {} link errors, {} timeouts, {} over budget, steps/s {:.0}, instr min/mean/max {}/{:.1}/{}\n",
            self.sil_mismatches,
            self.link_errors,
            self.link_timeouts,
            self.over_budget_steps,
            self.steps_per_wall_second,
            self.step_instructions_min,
            self.step_instructions_mean,
            self.step_instructions_max
        )
    }
}

/// A controller of kind `C` stepped once per control period with the plant's sensor frame.
pub trait StepController<C: FixedRate = Controller> {
    /// One control step.
    fn step(&mut self, frame: &C::Frame) -> Result<StepOutput<C::Command>, ControllerError>;
    /// One control step, the command only: for a loop that does not read the telemetry
    /// ([`Sil`] then skips building it). The same step as [`step`](StepController::step).
    #[inline]
    fn command(&mut self, frame: &C::Frame) -> Result<C::Command, ControllerError> {
        self.step(frame).map(|out| out.command)
    }
    /// Replace the controller by a new one of `params` (a new `Configure`): the next
    /// frame is its first. A run that plans anew between runs of the loop (the arm's
    /// juggle, one plan per cycle) uses it.
    fn reconfigure(&mut self, params: C::Params) -> Result<(), ControllerError>;
}

/// A controller whose steps move a run's progress bar: every [`Paced::EVERY`] steps the bar
/// learns the simulated time (steps x period) and the count of what else ends the run
/// (`events`: impacts, cycles, kept by whoever sees them). So a run shows where it is even
/// when nothing but time advances (a stalled hopper completes no cycle), against the bounds
/// the bar was made with.
pub struct Paced<'a, C: FixedRate> {
    inner: &'a mut dyn StepController<C>,
    bar: crate::progress::Progress,
    events: &'a std::cell::Cell<u64>,
    dt_s: f64,
    steps: u64,
}

impl<'a, C: FixedRate> Paced<'a, C> {
    /// Steps between updates of the bar.
    pub const EVERY: u64 = 4096;

    /// `inner`, stepped at period `dt_s` (s), moving `bar` (limits: events, then seconds).
    pub fn new(
        inner: &'a mut dyn StepController<C>,
        bar: crate::progress::Progress,
        events: &'a std::cell::Cell<u64>,
        dt_s: f64,
    ) -> Self {
        Self {
            inner,
            bar,
            events,
            dt_s,
            steps: 0,
        }
    }

    /// The run ended: clear the bar.
    pub fn finish(&self) {
        self.bar.finish();
    }

    #[inline]
    fn tick(&mut self) {
        self.steps += 1;
        if self.steps.is_multiple_of(Self::EVERY) {
            let t = self.steps as f64 * self.dt_s;
            self.bar.update([self.events.get() as f64, t]);
        }
    }
}

impl<C: FixedRate> StepController<C> for Paced<'_, C> {
    fn step(&mut self, frame: &C::Frame) -> Result<StepOutput<C::Command>, ControllerError> {
        self.tick();
        self.inner.step(frame)
    }
    fn command(&mut self, frame: &C::Frame) -> Result<C::Command, ControllerError> {
        self.tick();
        self.inner.command(frame)
    }
    fn reconfigure(&mut self, params: C::Params) -> Result<(), ControllerError> {
        self.inner.reconfigure(params)
    }
}

/// Software in the loop: the shared core, linked in, f32, the same code the firmware runs.
pub struct Sil<C = Controller> {
    controller: C,
}

impl<C: FixedRate> Sil<C> {
    /// A SIL controller from parameters.
    pub fn new(params: C::Params) -> Result<Self, ControllerError> {
        Ok(Self {
            controller: C::new(params).map_err(ControllerError::Params)?,
        })
    }

    /// The controller inside.
    pub fn controller(&self) -> &C {
        &self.controller
    }
}

impl<C: FixedRate> StepController<C> for Sil<C> {
    fn step(&mut self, frame: &C::Frame) -> Result<StepOutput<C::Command>, ControllerError> {
        let command = self.controller.step(frame);
        Ok(StepOutput {
            command,
            telemetry: self.controller.telemetry(),
        })
    }
    #[inline]
    fn command(&mut self, frame: &C::Frame) -> Result<C::Command, ControllerError> {
        Ok(self.controller.step(frame))
    }
    fn reconfigure(&mut self, params: C::Params) -> Result<(), ControllerError> {
        self.controller = C::new(params).map_err(ControllerError::Params)?;
        Ok(())
    }
}

/// Control steps a controller answered in its safe state, by fault: the `safe_steps` and
/// `faults` keys of every closed-loop system's summary (`#[serde(flatten)]` it in, or
/// [`SafeSteps::every_fault`] for a summary that lists every fault code). Counted once per
/// step by the one fixed-rate loop, [`crate::closed_loop::drive`], in SIL and HIL alike.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SafeSteps {
    /// Control steps whose command was the safe state ([`Mode::Safe`]).
    pub safe_steps: u64,
    /// Those steps by fault code (`non_finite`, `out_of_range`, `stale`, `link_timeout`,
    /// `overrun`); only the faults that occurred.
    pub faults: BTreeMap<&'static str, u64>,
    /// Control steps in all (not serialized: each summary has its own count).
    #[serde(skip)]
    pub steps: u64,
}

/// A fault code's name in the summary (snake_case, as in `dexter_core::fixed_rate::Fault`).
pub fn fault_name(f: Fault) -> &'static str {
    match f {
        Fault::None => "none",
        Fault::NonFinite => "non_finite",
        Fault::OutOfRange => "out_of_range",
        Fault::Stale => "stale",
        Fault::LinkTimeout => "link_timeout",
        Fault::Overrun => "overrun",
    }
}

impl SafeSteps {
    /// Count one command.
    #[inline]
    pub fn record(&mut self, command: &impl Reply) {
        self.steps += 1;
        if command.mode() == Mode::Safe {
            self.record_safe(command.fault());
        }
    }

    /// Out of line, so the Track path reads only the mode byte (loading mode and fault
    /// together as one word, right after the controller stored them as two bytes, stalled
    /// the store-to-load forwarding of every SIL step).
    #[cold]
    #[inline(never)]
    fn record_safe(&mut self, fault: Fault) {
        self.safe_steps += 1;
        *self.faults.entry(fault_name(fault)).or_insert(0) += 1;
    }

    /// Steps answered in the safe state with fault `f`.
    pub fn count(&self, f: Fault) -> u64 {
        self.faults.get(fault_name(f)).copied().unwrap_or(0)
    }

    /// Every fault code with its count (0 for those that did not occur), for a summary
    /// whose `faults` object lists them all.
    pub fn every_fault(&self) -> EveryFault<'_> {
        EveryFault(self)
    }

    /// True if the controller answered more than half of its steps in the safe state (the
    /// run then exits with status 1: `docs/scenes.md`, "Safe state").
    pub fn mostly_safe(&self) -> bool {
        2 * self.safe_steps > self.steps
    }

    /// The terminal warning for a run with safe steps (`None` without).
    pub fn warning(&self) -> Option<String> {
        (self.safe_steps > 0).then(|| {
            let by: Vec<String> = self
                .faults
                .iter()
                .map(|(k, n)| format!("{k} {n}"))
                .collect();
            format!(
                "the controller was in its safe state for {} of {} control steps ({:.1} %; {})",
                self.safe_steps,
                self.steps,
                100.0 * self.safe_steps as f64 / self.steps.max(1) as f64,
                by.join(", ")
            )
        })
    }

    /// The safe-state lines of a text summary (empty without safe steps).
    pub fn text(&self) -> String {
        match self.safe_steps {
            0 => String::new(),
            n => {
                let by: Vec<String> = self
                    .faults
                    .iter()
                    .map(|(k, c)| format!("{k} {c}"))
                    .collect();
                format!(
                    "safe state       {n} of {} control steps ({})\n",
                    self.steps,
                    by.join(", ")
                )
            }
        }
    }
}

/// The safe steps by every fault code, serialized as an object with one key per code in
/// the order of [`EVERY_FAULT`] ([`SafeSteps::every_fault`]).
#[derive(Clone, Copy, Debug)]
pub struct EveryFault<'a>(&'a SafeSteps);

/// The fault codes a safe step can carry, in the order [`EveryFault`] lists them.
pub const EVERY_FAULT: [Fault; 5] = [
    Fault::NonFinite,
    Fault::OutOfRange,
    Fault::Stale,
    Fault::LinkTimeout,
    Fault::Overrun,
];

impl Serialize for EveryFault<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(EVERY_FAULT.len()))?;
        for f in EVERY_FAULT {
            m.serialize_entry(fault_name(f), &self.0.count(f))?;
        }
        m.end()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dexter_core::protocol::ActuatorCommand;

    #[test]
    fn safe_steps_are_counted_by_fault() {
        let mut s = SafeSteps::default();
        let cmd = |mode, fault| ActuatorCommand {
            mode,
            fault,
            ..ActuatorCommand::default()
        };
        s.record(&cmd(Mode::Track, Fault::None));
        s.record(&cmd(Mode::Hold, Fault::None));
        for _ in 0..3 {
            s.record(&cmd(Mode::Safe, Fault::OutOfRange));
        }
        s.record(&cmd(Mode::Safe, Fault::Stale));
        assert_eq!((s.steps, s.safe_steps), (6, 4));
        assert_eq!(s.faults.get("out_of_range"), Some(&3));
        assert_eq!(s.faults.get("stale"), Some(&1));
        assert!(s.mostly_safe());
        let json = serde_json::to_string(&s).unwrap();
        assert_eq!(
            json,
            r#"{"safe_steps":4,"faults":{"out_of_range":3,"stale":1}}"#
        );
        assert!(s.warning().unwrap().contains("4 of 6"));
        assert_eq!(
            (s.count(Fault::OutOfRange), s.count(Fault::Overrun)),
            (3, 0)
        );
        assert_eq!(
            serde_json::to_string(&s.every_fault()).unwrap(),
            r#"{"non_finite":0,"out_of_range":3,"stale":1,"link_timeout":0,"overrun":0}"#
        );
        assert!(SafeSteps::default().warning().is_none());
    }
}
