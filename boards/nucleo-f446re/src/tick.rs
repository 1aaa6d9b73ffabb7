//! The control period's clock on this board: TIM2's update event is the tick (its
//! interrupt runs the period's task), its update flag says whether the next tick has come,
//! and the DWT cycle counter measures the work (`dexter_firmware::board::DwtCycles`).
//! The core's step is measured inside an RTIC lock whose ceiling is the receive
//! interrupts' priority (the app's `step_window`), not with every interrupt masked.

use cortex_m::peripheral::DWT;
use dexter_firmware::board::{DwtCycles, StepTimer};
use dexter_rig::periodic::PeriodClock;
use stm32f4xx_hal::pac::TIM2;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::timer::{CounterHz, Flag};

/// One period's view of the clock, made when the tick's task starts.
pub struct TickClock<'a, W> {
    entry_cycles: u32,
    steps: &'a DwtCycles,
    tick: &'a CounterHz<TIM2>,
    window: &'a mut W,
}

impl<'a, W: rtic::Mutex<T = ()>> TickClock<'a, W> {
    /// Take the tick: note the cycle count and clear TIM2's update flag, so that a flag set
    /// again by the end of the work means the next tick came during it; `window` is the
    /// lock the step is measured in.
    pub fn take(steps: &'a DwtCycles, tick: &'a mut CounterHz<TIM2>, window: &'a mut W) -> Self {
        let entry_cycles = DWT::cycle_count();
        tick.clear_flags(Flag::Update);
        Self {
            entry_cycles,
            steps,
            tick,
            window,
        }
    }
}

impl<W: rtic::Mutex<T = ()>> PeriodClock for TickClock<'_, W> {
    /// The core's step inside the `step_window` lock (RTIC raises BASEPRI to the receive
    /// interrupts' priority), so a receive interrupt that lands inside the window is not
    /// counted as control work; faults and NMI are never masked.
    fn measure<T>(&mut self, f: impl FnOnce() -> T) -> (T, u32) {
        let steps = self.steps;
        self.window.lock(|()| steps.measure(f))
    }

    fn work_cycles(&self) -> u32 {
        DWT::cycle_count().wrapping_sub(self.entry_cycles)
    }

    fn next_tick_pending(&self) -> bool {
        self.tick.flags().contains(Flag::Update)
    }
}
