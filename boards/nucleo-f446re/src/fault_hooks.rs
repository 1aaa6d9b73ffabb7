//! Emulator test hooks (feature `qemu-hsi` only, never in the real image): a byte
//! `0xF1..=0xF7` on USART1 (the camera's line, which the emulator test attaches to a
//! socket) provokes one fault path, so that `host-sim/tests/board_hil.rs` sees each one end
//! with the motor off. The byte is also in the camera ring, where the camera's parser
//! skips it as noise.
//!
//! **The watchdog.** QEMU's netduinoplus2 does not model the IWDG (its registers are an
//! unimplemented device, whose writes QEMU logs) nor RCC's reset flags. [`HANG`] hangs the
//! control task as a stuck step would (an endless loop above its priority), so the test
//! sees the feeds stop. The reset that follows on a real part the test stands in for by
//! booting the image again with [`DEXTER_EMULATED_WATCHDOG_RESET`] set (QEMU's `loader`
//! device writes it before the core starts), which the image reads at boot as it reads
//! RCC's `WDGRSTF` ([`take_emulated_watchdog_reset`]): the same path as after a real
//! watchdog reset (the motor parked).

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
/// A hung control task: this interrupt (priority 3, above the control task's 2) never
/// returns, so the watchdog is no longer fed.
const HANG: u8 = 0xF6;
/// The lower limit switch opening: its interrupt (EXTI0) set pending, as the pin's rising
/// edge would (QEMU does not model the GPIOs, so no pin can rise).
const LIMIT_SWITCH: u8 = 0xF7;

/// The emulated watchdog reset flag, in RAM the reset handler leaves as it is (`.uninit`:
/// neither loaded nor zeroed), so a value put there before the core starts survives into
/// `init`. Unmangled, for the emulator test to find.
#[no_mangle]
#[link_section = ".uninit.dexter_emulated_watchdog"]
static mut DEXTER_EMULATED_WATCHDOG_RESET: core::mem::MaybeUninit<u32> =
    core::mem::MaybeUninit::uninit();
/// The flag's value ("WDOG"); anything else (RAM at power-up) is no watchdog reset.
const WATCHDOG_MARK: u32 = 0x5744_4f47;

/// Whether the emulated watchdog reset flag is set, and clear it, as the image clears
/// RCC's flags at boot.
pub fn take_emulated_watchdog_reset() -> bool {
    let marker = core::ptr::addr_of_mut!(DEXTER_EMULATED_WATCHDOG_RESET).cast::<u32>();
    // Safety: read and written by `init` alone, before any interrupt runs; a word in RAM
    // whose content at power-up is any value (no invalid value for a u32).
    unsafe {
        let was = core::ptr::read_volatile(marker) == WATCHDOG_MARK;
        core::ptr::write_volatile(marker, 0);
        was
    }
}

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
        Some(LIMIT_SWITCH) => {
            cortex_m::peripheral::NVIC::pend(stm32f4xx_hal::pac::Interrupt::EXTI0)
        }
        Some(HANG) => loop {
            core::hint::spin_loop();
        },
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
