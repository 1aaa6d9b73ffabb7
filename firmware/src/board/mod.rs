//! The board layer: as thin as possible. A board provides
//! - a plant link: a byte stream implementing `embedded_io::{Read, Write}` (plus
//!   `ReadReady` for the free-running mode), and
//! - a [`StepTimer`] that counts what one control step costs.
//!
//! [`mps2_an386`] is the emulated Cortex-M4F QEMU runs. A real board is a crate of its own
//! (`boards/nucleo-f446re`: it needs its HAL, its `memory.x` and its probe-rs runner) that
//! links this library: its USART as the link, [`DwtCycles`] as the timer, and
//! `dexter_drivers` for its sensors, actuator and fixed-rate tick (see firmware/README.md).

pub mod mps2_an386;

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::{DWT, SYST};

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

/// SysTick as a free-running 24-bit down counter on the core clock. Under QEMU with
/// `-icount shift=10` one instruction is 1.024 us of virtual time, so on mps2-an386
/// (25 MHz SysTick) one instruction is exactly 25.6 ticks (checked by the smoke run with a
/// run of `nop`s): instructions = ticks * 5 / 128. A measured window must stay under
/// 2^24 ticks (655 k instructions).
pub struct SysTickInstructions {
    /// Cost of an empty measurement, instructions (subtracted).
    overhead: u32,
}

/// SysTick ticks per instruction under `-icount shift=10` at 25 MHz, as the fraction
/// `TICKS_PER_INSTRUCTION_NUM / TICKS_PER_INSTRUCTION_DEN` (= 25.6).
pub const TICKS_PER_INSTRUCTION_NUM: u32 = 128;
/// See [`TICKS_PER_INSTRUCTION_NUM`].
pub const TICKS_PER_INSTRUCTION_DEN: u32 = 5;
const SYST_MASK: u32 = 0x00ff_ffff;

impl SysTickInstructions {
    /// Start SysTick free running (no interrupt) and calibrate the measurement overhead.
    /// Takes `SYST` so nothing else reprograms it; the counter keeps running after this
    /// (reads use `SYST::get_current`, which needs no ownership).
    pub fn new(mut syst: SYST) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(SYST_MASK);
        syst.clear_current();
        syst.disable_interrupt();
        syst.enable_counter();
        let mut t = Self { overhead: 0 };
        let ((), empty) = t.measure(|| ());
        t.overhead = empty;
        t
    }

    /// Raw SysTick ticks between two timestamps (down counter, wrapping at 2^24).
    pub fn ticks(start: u32, end: u32) -> u32 {
        start.wrapping_sub(end) & SYST_MASK
    }

    /// The calibrated cost of an empty measurement, instructions.
    pub fn overhead(&self) -> u32 {
        self.overhead
    }
}

impl StepTimer for SysTickInstructions {
    #[inline(always)]
    fn now(&self) -> u32 {
        SYST::get_current()
    }

    #[inline(always)]
    fn elapsed(&self, start: u32, end: u32) -> u32 {
        let ticks = Self::ticks(start, end);
        let instr = (ticks * TICKS_PER_INSTRUCTION_DEN + TICKS_PER_INSTRUCTION_NUM / 2)
            / TICKS_PER_INSTRUCTION_NUM;
        instr.saturating_sub(self.overhead)
    }
}

/// The DWT cycle counter, for real hardware (it reads 0 in QEMU 7.2, so QEMU runs use
/// [`SysTickInstructions`]).
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
