//! The fixed-rate control period on a hardware tick, board independent: sense, the core's
//! [`FixedRate::step`], actuate, then check the deadline. An overrun (the period's work
//! still running when the next tick came) is detected, counted, and answered at once with
//! the core's safe command, [`FixedRate::safe`]`(seq, `[`OVERRUN_FAULT`]`)`, which the rig
//! applies in place of the late command.
//!
//! The board supplies the tick and the cycle counter through [`PeriodClock`] (on an STM32:
//! a timer's update interrupt, its pending flag, and the DWT cycle counter) and the sensors
//! and actuators through [`Rig`]; nothing here knows a register.
//!
//! Detection has two witnesses, so neither a short nor a very long overrun escapes:
//! - the timer's own flag: the period's task clears it on entry, so if it is set again
//!   when the work ends, the next tick came during the work (exact, whatever delayed the
//!   task: its own work or a higher-priority interrupt);
//! - the cycles since the task's entry: `work / period` ticks went by during the work, and
//!   all but one of them are lost (a timer flag pends once), which the counts report.

use crate::rig::Rig;
use dexter_core::fixed_rate::{Fault, FixedRate, Mode, Reply};

/// The fault code an overrun's safe command carries: [`Fault::Overrun`].
pub const OVERRUN_FAULT: Fault = Fault::Overrun;

/// The tick and the cycle counter of a board.
pub trait PeriodClock {
    /// Run `f` (the core's step) and return its result with the cycles it took (on
    /// hardware: DWT cycles, interrupts masked, measurement overhead subtracted).
    fn measure<T>(&mut self, f: impl FnOnce() -> T) -> (T, u32);
    /// Cycles since the period's task started.
    fn work_cycles(&self) -> u32;
    /// Whether the next tick has already come (the timer's update flag, cleared on entry).
    fn next_tick_pending(&self) -> bool;
}

/// What one period's deadline check found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Deadline {
    /// The work ended before the next tick, with this many cycles to spare.
    Met {
        /// Period minus work, cycles.
        slack_cycles: u32,
    },
    /// The next tick came during the work.
    Overrun {
        /// Ticks that went by during the work beyond the first (their interrupts
        /// coalesced into one pending flag: lost periods).
        ticks_lost: u32,
    },
}

/// Counts and extremes since start.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PeriodStats {
    /// Periods run.
    pub periods: u32,
    /// Periods whose work overran the next tick.
    pub overruns: u32,
    /// Ticks lost to overruns (see [`Deadline::Overrun`]).
    pub ticks_lost: u32,
    /// Periods answered with a safe command (the controller's own faults and overruns).
    pub safe_periods: u32,
    /// Actuator writes that failed.
    pub drive_errors: u32,
    /// Fewest cycles of one core step.
    pub step_cycles_min: u32,
    /// Most cycles of one core step.
    pub step_cycles_max: u32,
    /// Sum of the step cycles (for the mean).
    pub step_cycles_sum: u64,
    /// Most cycles of one period's whole work (sense, step, actuate).
    pub work_cycles_max: u32,
}

/// What one period did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeriodOutcome<Command> {
    /// The command the rig was left with (the safe one after an overrun).
    pub command: Command,
    /// Cycles the core's step took.
    pub step_cycles: u32,
    /// The deadline check.
    pub deadline: Deadline,
}

/// A controller run at a fixed rate on a board's tick.
pub struct Periodic<C> {
    controller: C,
    period_cycles: u32,
    stats: PeriodStats,
}

impl<C: FixedRate> Periodic<C> {
    /// `controller` stepped every `period_cycles` cycles of the clock (e.g. 180 MHz / 500
    /// Hz = 360 000); `None` if the period is 0.
    pub fn new(controller: C, period_cycles: u32) -> Option<Self> {
        (period_cycles > 0).then_some(Self {
            controller,
            period_cycles,
            stats: PeriodStats {
                step_cycles_min: u32::MAX,
                ..PeriodStats::default()
            },
        })
    }

    /// One period, called from the tick's task: sense, step, actuate, check the deadline;
    /// on an overrun, the safe command at once.
    pub fn period<R, K>(&mut self, rig: &mut R, clock: &mut K) -> PeriodOutcome<C::Command>
    where
        R: Rig<Frame = C::Frame, Command = C::Command>,
        K: PeriodClock,
    {
        let frame = rig.sense();
        let controller = &mut self.controller;
        let (mut command, step_cycles) = clock.measure(|| controller.step(&frame));
        self.actuate(rig, &command);
        let deadline = self.check_deadline(clock.work_cycles(), clock.next_tick_pending());
        if let Deadline::Overrun { .. } = deadline {
            command = self.controller.safe(command.seq(), OVERRUN_FAULT);
            self.actuate(rig, &command);
        }
        self.record(step_cycles, &command);
        PeriodOutcome {
            command,
            step_cycles,
            deadline,
        }
    }

    fn actuate<R: Rig<Command = C::Command>>(&mut self, rig: &mut R, command: &C::Command) {
        if rig.actuate(command).is_err() {
            self.stats.drive_errors = self.stats.drive_errors.saturating_add(1);
        }
    }

    /// The deadline of a period whose work took `work_cycles`, with the next tick's flag.
    fn check_deadline(&mut self, work_cycles: u32, next_tick_pending: bool) -> Deadline {
        let s = &mut self.stats;
        s.work_cycles_max = s.work_cycles_max.max(work_cycles);
        let ticks_passed = work_cycles / self.period_cycles;
        if !next_tick_pending && ticks_passed == 0 {
            return Deadline::Met {
                slack_cycles: self.period_cycles - work_cycles,
            };
        }
        let ticks_lost = ticks_passed.saturating_sub(1);
        s.overruns = s.overruns.saturating_add(1);
        s.ticks_lost = s.ticks_lost.saturating_add(ticks_lost);
        Deadline::Overrun { ticks_lost }
    }

    fn record(&mut self, step_cycles: u32, command: &C::Command) {
        let s = &mut self.stats;
        s.periods = s.periods.saturating_add(1);
        s.step_cycles_min = s.step_cycles_min.min(step_cycles);
        s.step_cycles_max = s.step_cycles_max.max(step_cycles);
        s.step_cycles_sum = s.step_cycles_sum.saturating_add(u64::from(step_cycles));
        if command.mode() == Mode::Safe {
            s.safe_periods = s.safe_periods.saturating_add(1);
        }
    }

    /// Counts and extremes since start.
    pub fn stats(&self) -> PeriodStats {
        self.stats
    }

    /// The controller (its telemetry, its parameters).
    pub fn controller(&self) -> &C {
        &self.controller
    }

    /// The period, cycles.
    pub fn period_cycles(&self) -> u32 {
        self.period_cycles
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dexter_core::control::{Controller, ControllerParams};
    use dexter_core::protocol::{ActuatorCommand, SensorFrame};

    /// A rig that plays a ball resting at 0.5 m and a paddle at rest, and records commands.
    #[derive(Default)]
    struct FakeRig {
        seq: u32,
        applied: Vec<ActuatorCommand>,
        fail: bool,
    }

    impl Rig for FakeRig {
        type Frame = SensorFrame;
        type Command = ActuatorCommand;
        type Error = ();
        fn sense(&mut self) -> SensorFrame {
            self.seq += 1;
            SensorFrame {
                seq: self.seq,
                ball_height_m: 0.5,
                paddle_height_m: 0.0,
                paddle_velocity_mps: 0.0,
            }
        }
        fn actuate(&mut self, command: &ActuatorCommand) -> Result<(), ()> {
            self.applied.push(*command);
            if self.fail {
                Err(())
            } else {
                Ok(())
            }
        }
        fn park(&mut self) -> Result<(), ()> {
            Ok(())
        }
    }

    /// A clock whose step costs `step` cycles and whose period's work took `work` cycles.
    struct FakeClock {
        step: u32,
        work: u32,
        pending: bool,
    }

    impl PeriodClock for FakeClock {
        fn measure<T>(&mut self, f: impl FnOnce() -> T) -> (T, u32) {
            (f(), self.step)
        }
        fn work_cycles(&self) -> u32 {
            self.work
        }
        fn next_tick_pending(&self) -> bool {
            self.pending
        }
    }

    fn periodic() -> Periodic<Controller> {
        let c = Controller::new(ControllerParams::default()).unwrap();
        Periodic::new(c, 1000).unwrap()
    }

    fn clock(work: u32, pending: bool) -> FakeClock {
        FakeClock {
            step: 400,
            work,
            pending,
        }
    }

    #[test]
    fn a_period_on_time_applies_the_cores_own_step() {
        let mut p = periodic();
        let mut shadow = Controller::new(ControllerParams::default()).unwrap();
        let mut rig = FakeRig::default();
        let out = p.period(&mut rig, &mut clock(999, false));
        let expected = shadow.step(&SensorFrame {
            seq: 1,
            ball_height_m: 0.5,
            paddle_height_m: 0.0,
            paddle_velocity_mps: 0.0,
        });
        assert!(out.command.bit_identical(&expected));
        assert_eq!(rig.applied, vec![expected]);
        assert_eq!(out.deadline, Deadline::Met { slack_cycles: 1 });
        let s = p.stats();
        assert_eq!((s.periods, s.overruns, s.safe_periods), (1, 0, 0));
        assert_eq!((s.step_cycles_min, s.step_cycles_max), (400, 400));
    }

    #[test]
    fn a_pending_tick_is_an_overrun_answered_with_the_safe_command() {
        let mut p = periodic();
        let mut shadow = Controller::new(ControllerParams::default()).unwrap();
        let mut rig = FakeRig::default();
        // the work fits the period by cycles, but the next tick is already pending (the
        // task started late): an overrun all the same
        let out = p.period(&mut rig, &mut clock(10, true));
        let stepped = shadow.step(&SensorFrame {
            seq: 1,
            ball_height_m: 0.5,
            ..SensorFrame::default()
        });
        let safe = shadow.safe(stepped.seq, OVERRUN_FAULT);
        assert_eq!(out.deadline, Deadline::Overrun { ticks_lost: 0 });
        assert!(out.command.bit_identical(&safe));
        assert_eq!(out.command.mode, Mode::Safe);
        assert_eq!(out.command.fault, Fault::Overrun);
        assert_eq!(rig.applied.len(), 2, "the late command, then the safe one");
        assert!(rig.applied[1].bit_identical(&safe));
        let s = p.stats();
        assert_eq!((s.overruns, s.safe_periods, s.ticks_lost), (1, 1, 0));
    }

    #[test]
    fn work_over_several_periods_counts_the_lost_ticks() {
        let mut p = periodic();
        let mut rig = FakeRig::default();
        // 3.5 periods of work: ticks at 1, 2, 3 went by; one pends, two are lost
        let out = p.period(&mut rig, &mut clock(3500, true));
        assert_eq!(out.deadline, Deadline::Overrun { ticks_lost: 2 });
        // the flag alone can miss nothing the cycles see: exactly one period, flag unset
        // (cleared by a late entry), is still an overrun
        let out = p.period(&mut rig, &mut clock(1000, false));
        assert_eq!(out.deadline, Deadline::Overrun { ticks_lost: 0 });
        let s = p.stats();
        assert_eq!((s.overruns, s.ticks_lost, s.work_cycles_max), (2, 2, 3500));
    }

    #[test]
    fn after_an_overrun_the_next_period_steps_again_and_drive_errors_are_counted() {
        let mut p = periodic();
        let mut rig = FakeRig::default();
        p.period(&mut rig, &mut clock(10, true));
        let out = p.period(&mut rig, &mut clock(10, false));
        assert_ne!(out.command.fault, OVERRUN_FAULT);
        rig.fail = true;
        p.period(&mut rig, &mut clock(10, false));
        let s = p.stats();
        assert_eq!((s.periods, s.overruns, s.drive_errors), (3, 1, 1));
        assert!(Periodic::new(Controller::new(ControllerParams::default()).unwrap(), 0).is_none());
    }
}
