//! Emulator test hooks (feature `qemu-hsi` only, never in the real image): a byte
//! `0xF1..=0xF5` on USART1 (the camera's line, which the emulator test attaches to a
//! socket) provokes one fault path, so that `host-sim/tests/board_hil.rs` sees each one end
//! in `fault::DEXTER_MOTOR_OFF`. The byte is also in the camera ring, where the camera's
//! parser skips it as noise.

/// A HardFault from a bus error: a read of an address no device answers.
const HARD_FAULT: u8 = 0xF1;
/// A panic.
const PANIC: u8 = 0xF2;
/// A stack overflow (recursion until the MPU guard faults).
const STACK_OVERFLOW: u8 = 0xF3;
/// An NMI (set pending).
const NMI: u8 = 0xF4;
/// An interrupt without a handler (SPI2, enabled and set pending).
const UNHANDLED_INTERRUPT: u8 = 0xF5;

/// The last byte the camera's receive interrupt put in the ring: a hook's provokes it.
pub fn on_camera_byte(last: Option<u8>) {
    match last {
        Some(HARD_FAULT) => {
            // Safety: a deliberate fault (an unmapped address in the system region).
            let _ = unsafe { core::ptr::read_volatile(0xE010_0000 as *const u32) };
        }
        Some(PANIC) => panic!("fault hook"),
        Some(STACK_OVERFLOW) => {
            let _ = recurse(core::hint::black_box(1_000_000));
        }
        // Safety: ICSR's NMIPENDSET (bit 31): a deliberate NMI.
        Some(NMI) => unsafe { (*cortex_m::peripheral::SCB::PTR).icsr.write(1 << 31) },
        Some(UNHANDLED_INTERRUPT) => {
            use stm32f4xx_hal::pac::Interrupt;
            // Safety: SPI2 has no handler: a deliberate DefaultHandler.
            unsafe { cortex_m::peripheral::NVIC::unmask(Interrupt::SPI2) };
            cortex_m::peripheral::NVIC::pend(Interrupt::SPI2);
        }
        _ => {}
    }
}

/// 64 bytes of stack per level, `n` levels.
#[inline(never)]
fn recurse(n: u32) -> u32 {
    let mut frame = [n; 16];
    core::hint::black_box(&mut frame);
    if n == 0 {
        return frame[1];
    }
    recurse(n - 1).wrapping_add(frame[2])
}
