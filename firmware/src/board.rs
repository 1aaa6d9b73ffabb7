//! The board layer: as thin as possible. A board provides
//! - a plant link: a byte stream implementing `embedded_io::{Read, Write}` (plus
//!   `ReadReady` for the free-running mode), and
//! - a [`StepTimer`] that counts what one control step costs.
//!
//! Each board is a crate of its own that links this library: `boards/mps2-an386`, the
//! emulated Cortex-M4F QEMU runs (its UART0 and a semihosting link, SysTick counting
//! instructions under `-icount`), and `boards/nucleo-f446re` (its HAL, its `memory.x`, its
//! probe-rs runner: its USART as the link through [`crate::uart`], [`DwtCycles`] as the
//! timer, and `dexter_drivers` for its sensors and actuator; see firmware/README.md).

use cortex_m::peripheral::DWT;

/// Counts the cost of a piece of code in target instructions (QEMU) or cycles (hardware).
pub trait StepTimer {
    /// A raw timestamp.
    fn now(&self) -> u32;
    /// Instructions (or cycles) between two timestamps, wrapping, minus the cost of the
    /// measurement itself.
    fn elapsed(&self, start: u32, end: u32) -> u32;
    /// Run `f` and return its result with what it cost.
    #[inline(always)]
    fn measure<R>(&self, f: impl FnOnce() -> R) -> (R, u32) {
        let start = self.now();
        let r = core::hint::black_box(f());
        let end = self.now();
        (r, self.elapsed(start, end))
    }
}

/// The DWT cycle counter, for real hardware (it reads 0 in QEMU 7.2, so the emulated
/// board counts instructions with SysTick instead).
pub struct DwtCycles {
    overhead: u32,
}

impl DwtCycles {
    /// Enable tracing and the cycle counter, and calibrate the measurement overhead.
    pub fn new(dcb: &mut cortex_m::peripheral::DCB, dwt: &mut DWT) -> Self {
        dcb.enable_trace();
        dwt.enable_cycle_counter();
        let mut t = Self { overhead: 0 };
        let ((), empty) = t.measure(|| ());
        t.overhead = empty;
        t
    }
}

impl StepTimer for DwtCycles {
    #[inline(always)]
    fn now(&self) -> u32 {
        DWT::cycle_count()
    }

    #[inline(always)]
    fn elapsed(&self, start: u32, end: u32) -> u32 {
        end.wrapping_sub(start).saturating_sub(self.overhead)
    }
}
