//! SysTick as the emulated board's step timer: under QEMU's `-icount shift=10` it counts
//! instructions exactly.

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;
use dexter_firmware::board::StepTimer;

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
