//! Boots the firmware. The semihosting command line (QEMU `-append`) picks the mode:
//! - nothing: the smoke run ([`smoke`]), what `cargo fw` shows;
//! - `semihosting`: lock-step server on the semihosting file link;
//! - `uart`: lock-step server on UART0;
//! - `freerun`: free-running fixed-rate mode on UART0 (500 Hz on SysTick, link timeout
//!   after 5 periods without a valid frame): a board fed sensor frames over its link;
//! - `fault-panic`, `fault-hardfault`, `fault-stack-overflow`: test hooks that panic,
//!   execute `udf`, or recurse past the reserved stack into the MPU's guard ([`fault`]),
//!   to check that each ends the QEMU run with a failure status;
//! - `bench` (feature `bench`): per-call instruction counts of the math kernels.
//!
//! This binary also holds what a QEMU run needs once (knurling app-template style): the
//! defmt global logger (semihosting stdout), the panic handler and a `HardFault` handler
//! ([`fault`], with the stack's MPU guard) that both end the run with a failure status,
//! and [`exit`]. The board-neutral library
//! (`dexter_firmware`) holds none of them, nor semihosting: a real board links its own.
#![no_std]
#![no_main]
#![deny(unsafe_op_in_unsafe_fn)]

use defmt_semihosting as _; // global logger: defmt frames on semihosting stdout

use cortex_m::peripheral::SYST;
use cortex_m_rt::{entry, exception};
use dexter_firmware::server::{Exit, FreeRunning, Server};
use semihosting::{command_line, LinkError, SemihostingLink};
use systick::SysTickInstructions;
use uart0 as mps2_an386;

#[cfg(feature = "bench")]
mod bench;
mod fault;
mod mem;
mod semihosting;
mod smoke;
mod systick;
mod uart0;

/// Control rate of the free-running mode, Hz.
const FREE_RUNNING_RATE_HZ: u32 = 500;
/// Periods without a valid sensor frame before the free-running mode's safe state.
const FREE_RUNNING_TIMEOUT_PERIODS: u32 = 5;

/// The plant links this board offers, as one type so the server is compiled once.
enum PlantLink {
    Semihosting(SemihostingLink),
    Uart(mps2_an386::Uart0),
}

impl embedded_io::ErrorType for PlantLink {
    type Error = LinkError;
}

impl embedded_io::Read for PlantLink {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        match self {
            PlantLink::Semihosting(l) => l.read(buf),
            PlantLink::Uart(u) => u.read(buf).map_err(|e| match e {}),
        }
    }
}

impl embedded_io::ReadReady for PlantLink {
    fn read_ready(&mut self) -> Result<bool, LinkError> {
        match self {
            PlantLink::Semihosting(l) => l.read_ready(),
            PlantLink::Uart(u) => u.read_ready().map_err(|e| match e {}),
        }
    }
}

impl embedded_io::Write for PlantLink {
    fn write(&mut self, buf: &[u8]) -> Result<usize, LinkError> {
        match self {
            PlantLink::Semihosting(l) => l.write(buf),
            PlantLink::Uart(u) => u.write(buf).map_err(|e| match e {}),
        }
    }

    fn flush(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
}

#[derive(Clone, Copy, PartialEq, Eq, defmt::Format)]
enum BootMode {
    Smoke,
    Semihosting,
    Uart,
    FreeRunning,
    FaultPanic,
    FaultHardFault,
    FaultStackOverflow,
    Bench,
}

fn boot_mode() -> BootMode {
    let mut buf = [0u8; 256];
    let line = command_line(&mut buf);
    let mut mode = BootMode::Smoke;
    for word in line.split(|&b| b == b' ') {
        match word {
            b"semihosting" => mode = BootMode::Semihosting,
            b"uart" => mode = BootMode::Uart,
            b"freerun" => mode = BootMode::FreeRunning,
            b"fault-panic" => mode = BootMode::FaultPanic,
            b"fault-hardfault" => mode = BootMode::FaultHardFault,
            b"fault-stack-overflow" => mode = BootMode::FaultStackOverflow,
            b"bench" => mode = BootMode::Bench,
            _ => {}
        }
    }
    mode
}

#[entry]
fn main() -> ! {
    let Some(mut cp) = cortex_m::Peripherals::take() else {
        exit(false)
    };
    fault::guard_stack(&cp.MPU);
    let timer = SysTickInstructions::new(cp.SYST);
    let mode = boot_mode();
    defmt::info!(
        "dexter-firmware {=str} on mps2-an386: {}",
        env!("CARGO_PKG_VERSION"),
        mode
    );
    let exit_of = |e: Exit, stats: dexter_firmware::server::RunStats| -> ! {
        defmt::info!("link ended: {} after {=u32} steps", e, stats.steps);
        exit(e != Exit::LinkFailed)
    };
    match mode {
        BootMode::Smoke => exit(smoke::run(&timer)),
        BootMode::Semihosting | BootMode::Uart => {
            let link = if mode == BootMode::Uart {
                uart(&mut cp.NVIC)
            } else {
                let Ok(link) = SemihostingLink::open() else {
                    defmt::error!("cannot open the semihosting link files");
                    exit(false)
                };
                PlantLink::Semihosting(link)
            };
            let mut server = Server::new(link, timer);
            let e = server.run();
            exit_of(e, server.stats())
        }
        BootMode::FreeRunning => {
            let mut server = Server::new(uart(&mut cp.NVIC), timer);
            let mode = FreeRunning {
                period_ticks: mps2_an386::SYSTICK_HZ / FREE_RUNNING_RATE_HZ,
                timeout_periods: FREE_RUNNING_TIMEOUT_PERIODS,
            };
            let e = mode.run(&mut server, SYST::get_current);
            exit_of(e, server.stats())
        }
        BootMode::FaultPanic => panic!("fault-panic test hook"),
        BootMode::FaultHardFault => cortex_m::asm::udf(),
        BootMode::FaultStackOverflow => {
            let depth = recurse(u32::MAX);
            defmt::error!("recursed {=u32} frames without a fault", depth);
            exit(false)
        }
        BootMode::Bench => {
            #[cfg(feature = "bench")]
            exit(bench::run(&timer));
            #[cfg(not(feature = "bench"))]
            {
                defmt::error!("built without the `bench` feature");
                exit(false)
            }
        }
    }
}

/// UART0 as the plant link (taken once: the board has one receive ring).
fn uart(nvic: &mut cortex_m::peripheral::NVIC) -> PlantLink {
    match mps2_an386::Uart0::new(nvic) {
        Some(uart) => PlantLink::Uart(uart),
        None => {
            defmt::error!("UART0 was taken twice");
            exit(false)
        }
    }
}

/// Test hook: recursion with a 256-byte frame per call, until the stack overflows into the
/// MPU's guard ([`fault`]).
#[inline(never)]
fn recurse(depth: u32) -> u32 {
    let frame = core::hint::black_box([depth as u8; 256]);
    if depth == 0 {
        return u32::from(frame[0]);
    }
    recurse(depth - 1).wrapping_add(u32::from(core::hint::black_box(frame)[255]))
}

/// Device interrupts: every entry of `vectors::__INTERRUPTS` (below) comes here.
#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    mps2_an386::on_interrupt(irqn);
}

/// The interrupt part of the vector table.
mod vectors {
    extern "C" {
        /// cortex-m-rt's trampoline for the `DefaultHandler` above (it reads the
        /// interrupt number from the ICSR and passes it on).
        fn DefaultHandler();
    }

    /// The AN386's interrupts (QEMU's `mps2-an386` gives its NVIC `num-irq` 32), each to
    /// `DefaultHandler`, which dispatches by number (`mps2_an386::on_interrupt`).
    /// cortex-m-rt without a device crate reserves 240 entries (960 bytes of flash), this
    /// table 32 (128 bytes).
    #[link_section = ".vector_table.interrupts"]
    #[no_mangle]
    static __INTERRUPTS: [unsafe extern "C" fn(); 32] = [DefaultHandler; 32];
}

/// End the run: semihosting `SYS_EXIT` (QEMU exits with status 0 on success, 1 on failure).
fn exit(success: bool) -> ! {
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
