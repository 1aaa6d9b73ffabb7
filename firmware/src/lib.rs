//! # dexter-firmware
//!
//! The shared control core ([`dexter_core`]) on a Cortex-M4F. The board layer is thin
//! ([`board`]): a byte link that implements `embedded_io::{Read, Write}` and a step timer
//! ([`board::StepTimer`]). Everything else — the protocol server ([`server`]) and the
//! controllers it hosts ([`hosted`]), the smoke run ([`smoke`]), the stack measurement
//! ([`stack`]) and the math benchmarks (`bench`, feature `bench`) — is board independent.
//!
//! This file holds what every binary needs (knurling app-template style): the defmt global
//! logger (semihosting), the panic handler and a `HardFault` handler that both end a QEMU
//! run with a failure status, and [`exit`].
#![no_std]
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

use defmt_semihosting as _; // global logger: defmt frames on semihosting stdout

#[cfg(feature = "bench")]
pub mod bench;
pub mod board;
pub mod hosted;
pub mod link;
pub mod ring;
pub mod server;
pub mod smoke;
pub mod stack;

/// End the run: semihosting `SYS_EXIT` (QEMU exits with status 0 on success, 1 on failure).
/// On a real board without a debugger attached this parks the core instead.
pub fn exit(success: bool) -> ! {
    use cortex_m_semihosting::debug;
    debug::exit(if success {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    loop {
        cortex_m::asm::bkpt();
    }
}

/// A panic logs its location and ends the run with a failure status.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    match info.location() {
        Some(l) => defmt::error!("panic at {=str}:{=u32}", l.file(), l.line()),
        None => defmt::error!("panic"),
    }
    exit(false)
}

/// defmt's own panics (e.g. `defmt::unwrap!`) go through the same path.
#[defmt::panic_handler]
fn defmt_panic() -> ! {
    exit(false)
}

/// A HardFault ends the run with a failure status instead of spinning.
#[cortex_m_rt::exception]
unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    defmt::error!("HardFault at pc={=u32:#010x}", frame.pc());
    exit(false)
}
