//! The control period's clock on this board: TIM2's update event is the tick (its
//! interrupt runs the period's task), its update flag says whether the next tick has come,
//! and the DWT cycle counter measures the work (`dexter_firmware::board::DwtCycles`).

use cortex_m::peripheral::DWT;
use dexter_drivers::periodic::PeriodClock;
use dexter_firmware::board::{DwtCycles, StepTimer};
use stm32f4xx_hal::pac::TIM2;
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::timer::{CounterHz, Flag};

/// One period's view of the clock, made when the tick's task starts.
pub struct TickClock<'a> {
    entry_cycles: u32,
    steps: &'a DwtCycles,
    tick: &'a CounterHz<TIM2>,
}

impl<'a> TickClock<'a> {
    /// Take the tick: note the cycle count and clear TIM2's update flag, so that a flag set
    /// again by the end of the work means the next tick came during it.
    pub fn take(steps: &'a DwtCycles, tick: &'a mut CounterHz<TIM2>) -> Self {
        let entry_cycles = DWT::cycle_count();
        tick.clear_flags(Flag::Update);
        Self {
            entry_cycles,
            steps,
            tick,
        }
    }
}

impl PeriodClock for TickClock<'_> {
    /// The core's step with interrupts masked (as the lock-step server measures it), so a
    /// receive interrupt that lands inside the window is not counted as control work.
    fn measure<T>(&mut self, f: impl FnOnce() -> T) -> (T, u32) {
        cortex_m::interrupt::free(|_| self.steps.measure(f))
    }

    fn work_cycles(&self) -> u32 {
        DWT::cycle_count().wrapping_sub(self.entry_cycles)
    }

    fn next_tick_pending(&self) -> bool {
        self.tick.flags().contains(Flag::Update)
    }
}
