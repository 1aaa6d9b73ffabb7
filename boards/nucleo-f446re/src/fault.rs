//! Every way the core can stop running the control task ends with the motor off first:
//! a HardFault (a bus fault, an undefined instruction, a stack overflow: see below), a
//! panic (`#[panic_handler]`, and defmt's `#[defmt::panic_handler]` for `defmt::panic!`),
//! an NMI, an interrupt without a handler (`DefaultHandler`), and a hung control task (the
//! independent watchdog, fed by the control task only, resets the part; at reset every pin
//! is an input, and the driver's PWM input must have a pull-down, firmware/README.md).
//!
//! [`motor_off`] masks every interrupt (so no task can drive the motor again), turns PA8,
//! the driver's PWM input, into a GPIO output driven low (the idle level, whatever TIM1 is
//! doing), sets TIM1's duty to 0 and clears its main output enable with OSSI set (an
//! off-state output held at its idle level, OIS1 = low, not left floating), and records
//! why in [`DEXTER_MOTOR_OFF`], which a debugger (or the emulator test,
//! `host-sim/tests/board_hil.rs`) reads.
//!
//! **Stack overflow.** The stack sits at the bottom of RAM (`memory.x`, flip-link's
//! layout), so an overflow writes below `0x2000_0000` and faults instead of overwriting the
//! statics. To leave the HardFault room to stack its frame (else the core locks up with
//! the motor driven), the MPU makes the lowest [`STACK_GUARD_BYTES`] of the stack region
//! read-only (the stack measurement still reads it): the overflow's first write faults
//! there, and the HardFault (for which the MPU is off, `HFNMIENA` = 0) stacks its frame
//! into the guard and cuts the motor.

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m_rt::{exception, ExceptionFrame};
use stm32f4xx_hal::pac::{GPIOA, TIM1};

/// Why [`motor_off`] first ran (a [`Cause`] as `u32`; 0: it has not).
#[no_mangle]
pub static DEXTER_MOTOR_OFF: AtomicU32 = AtomicU32::new(0);

/// Bytes at the bottom of the stack region the MPU guards (a power of two, >= 32).
pub const STACK_GUARD_BYTES: u32 = 256;

/// Why the motor was cut.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
#[repr(u32)]
pub enum Cause {
    /// A HardFault (a stack overflow and a panic end here too, after their own cut).
    HardFault = 1,
    /// A panic (`panic!` or `defmt::panic!`).
    Panic = 2,
    /// A non-maskable interrupt.
    Nmi = 3,
    /// An interrupt without a handler.
    UnhandledInterrupt = 4,
    /// A limit switch opened (`limits`).
    LimitSwitch = 5,
}

/// Cut the motor by register (the HAL objects belong to tasks that no longer run), with
/// every interrupt masked; kept out of line so that the image check
/// (`tests/board.rs`) finds each fault handler calling it.
#[inline(never)]
#[no_mangle]
pub extern "C" fn dexter_motor_off(cause: u32) {
    cortex_m::interrupt::disable();
    // Safety: after a fault no task runs any more (interrupts are masked); these writes
    // only lower outputs: PA8 low as a GPIO output, TIM1's duty 0, its outputs at idle.
    let (gpioa, tim1) = unsafe { (&*GPIOA::ptr(), &*TIM1::ptr()) };
    gpioa.bsrr().write(|w| w.br8().set_bit());
    gpioa.moder().modify(|_, w| w.moder8().output());
    tim1.ccr1().write(|w| unsafe { w.bits(0) });
    tim1.bdtr()
        .modify(|_, w| w.ossi().set_bit().moe().clear_bit());
    // The first cause stays (a panic ends in a HardFault too).
    let _ = DEXTER_MOTOR_OFF.compare_exchange(0, cause, Ordering::SeqCst, Ordering::SeqCst);
}

/// [`dexter_motor_off`] for `cause` (inlined: each handler's first call is the cut).
#[inline(always)]
pub fn motor_off(cause: Cause) {
    dexter_motor_off(cause as u32);
}

/// Set at init: TIM1's off-state selection for idle (OSSI), so that clearing MOE drives
/// the output to its idle level (OIS1 = 0, low) instead of releasing the pin.
pub fn idle_level_when_off(tim1: &stm32f4xx_hal::pac::tim1::RegisterBlock) {
    tim1.bdtr().modify(|_, w| w.ossi().set_bit());
    tim1.cr2().modify(|_, w| w.ois1().clear_bit());
}

/// What DBGMCU's `CR`, `APB1_FZ` and `APB2_FZ` (RM0390, sec. 33.16) get at init, in that
/// order: while a debugger holds the core halted, TIM1 (the motor PWM, APB2 bit 0), TIM2
/// (the control tick, APB1 bit 0) and the independent watchdog (APB1 bit 12) stop, so a
/// halted core neither keeps driving the motor nor is reset under the debugger; and the
/// debug port stays up in sleep (`wfi` in `idle`), stop and standby (CR bits 0 to 2).
/// Unmangled, so that `tests/board.rs` reads the values from the linked image (QEMU does
/// not model DBGMCU: the emulator test sees only that the three registers are written).
#[no_mangle]
#[used]
pub static DEXTER_DBGMCU: [u32; 3] = [0b111, 1 | 1 << 12, 1];

/// Set DBGMCU from [`DEXTER_DBGMCU`] (each register's other bits kept).
pub fn freeze_on_halt(dbgmcu: &stm32f4xx_hal::pac::DBGMCU) {
    // Safety: a volatile read of a static, so the values are the image's as linked.
    let [cr, apb1, apb2] = unsafe { core::ptr::read_volatile(&DEXTER_DBGMCU) };
    // Safety: every bit set here is a documented freeze or debug-in-low-power bit.
    unsafe {
        dbgmcu.cr().modify(|r, w| w.bits(r.bits() | cr));
        dbgmcu.apb1_fz().modify(|r, w| w.bits(r.bits() | apb1));
        dbgmcu.apb2_fz().modify(|r, w| w.bits(r.bits() | apb2));
    }
}

/// The MPU guard at the bottom of the stack region (`_stack_end`, the lowest stack
/// address): region 0, read-only, `STACK_GUARD_BYTES` long; the default memory map stays
/// in force elsewhere (PRIVDEFENA), and the MPU is off in HardFault and NMI (HFNMIENA = 0).
pub fn guard_stack(mpu: &mut cortex_m::peripheral::MPU) {
    extern "C" {
        static _stack_end: u32;
    }
    // Only the symbol's address is taken.
    let base = core::ptr::addr_of!(_stack_end) as u32;
    let size_field = STACK_GUARD_BYTES.trailing_zeros() - 1; // SIZE: 2^(SIZE+1) bytes
    const ENABLE: u32 = 1;
    const AP_READ_ONLY: u32 = 0b110 << 24;
    const XN: u32 = 1 << 28;
    const PRIVDEFENA: u32 = 1 << 2;
    // Safety: the region covers the stack's lowest bytes only, which nothing uses while
    // the stack is within bounds; barriers make it take effect before the next access.
    unsafe {
        mpu.rnr.write(0);
        mpu.rbar.write(base & !(STACK_GUARD_BYTES - 1));
        mpu.rasr
            .write(XN | AP_READ_ONLY | (size_field << 1) | ENABLE);
        mpu.ctrl.write(PRIVDEFENA | ENABLE);
    }
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
}

/// Stop the motor, log where, and stay here (a debugger attached sees the HardFault; the
/// watchdog, no longer fed, resets the part).
#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    motor_off(Cause::HardFault);
    defmt::error!("HardFault at pc={=u32:#010x}; motor off", frame.pc());
    loop {
        cortex_m::asm::wfi();
    }
}

/// A limit switch opened: motor off, then stay (interrupts masked: the watchdog, no longer
/// fed, resets the part, which keeps the motor parked after the reset). Called first by
/// the EXTI0 and EXTI1 handlers (`main.rs`).
pub fn limit_switch_opened(which: &str) -> ! {
    motor_off(Cause::LimitSwitch);
    defmt::error!("limit switch ({=str} end) open; motor off", which);
    loop {
        cortex_m::asm::wfi();
    }
}

/// An interrupt nothing handles: motor off, then stay.
#[exception]
unsafe fn DefaultHandler(irqn: i16) -> ! {
    motor_off(Cause::UnhandledInterrupt);
    defmt::error!("unhandled interrupt {=i16}; motor off", irqn);
    loop {
        cortex_m::asm::wfi();
    }
}

/// A non-maskable interrupt (e.g. the clock security system): motor off, then stay.
#[exception]
unsafe fn NonMaskableInt() {
    motor_off(Cause::Nmi);
    defmt::error!("NMI; motor off");
    loop {
        cortex_m::asm::wfi();
    }
}

/// A panic: motor off, the message, then `udf` (a HardFault the probe sees).
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    motor_off(Cause::Panic);
    defmt::error!("panic: {}; motor off", defmt::Display2Format(info));
    cortex_m::asm::udf()
}

/// `defmt::panic!` (its message is already logged): motor off, then `udf`.
#[defmt::panic_handler]
fn defmt_panic() -> ! {
    motor_off(Cause::Panic);
    cortex_m::asm::udf()
}
