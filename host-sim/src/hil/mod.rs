//! Hardware in the loop: the firmware in QEMU behind [`crate::controller::StepController`],
//! for every controller kind the core's protocol carries.
//!
//! [`LockStep::<C>::start`](LockStep::start) boots the firmware ELF in `qemu-system-arm
//! -machine mps2-an386` with `-icount shift=10` (one target instruction = 1.024 us of
//! virtual time, so the firmware's SysTick measurements are exact and repeatable),
//! configures it with `HostMessage::Configure(C::config(params))` and then, for every
//! [`StepController::step`](crate::controller::StepController::step), sends the frame, waits for the firmware's `Output`, steps a
//! shadow `C` (the same code [`crate::controller::Sil`] runs) with the same input and
//! compares the two commands bit for bit (`Reply::bit_identical`). The command returned is
//! the firmware's.
//!
//! ```no_run
//! use dexter_core::control::{Controller, ControllerParams};
//! use dexter_sim::controller::StepController;
//! use dexter_sim::hil::{HilOptions, LockStep};
//! # fn main() -> Result<(), dexter_sim::controller::ControllerError> {
//! let elf = dexter_sim::hil::build_firmware()?; // or a path to a prebuilt ELF
//! let opts = HilOptions { firmware_elf: elf, ..HilOptions::default() };
//! let mut hil = LockStep::<Controller>::start(ControllerParams::default(), opts)?;
//! let plant: &mut dyn StepController<Controller> = &mut hil; // what a system's run takes
//! # let _ = plant;
//! let report = hil.finish()?; // Stop, wait for QEMU's exit, the HilReport (--json keys)
//! # let _ = report; Ok(()) }
//! ```
//!
//! ## Modules
//! - [`qemu`]: the QEMU process (toolchain checks, building the firmware, the private
//!   working directory, exit status, the defmt log);
//! - `link`: the host end of the byte link: the semihosting files or the UART's TCP
//!   socket, read with `poll(2)` on the calling thread (no reader thread, no allocation
//!   per frame);
//! - `semihosting`: the semihosting link's files, its doorbell and the frame file's bound;
//! - `inject`: byte corruption, and the independent prediction of which frames reach the
//!   firmware intact;
//! - `lockstep`: [`LockStep`];
//! - `report`: counters, [`HilReport`](crate::controller::HilReport), [`LinkCounts`].
//!
//! ## Links
//! - [`LinkKind::Semihosting`]: files in a private working directory that the firmware
//!   opens with semihosting `SYS_OPEN` ([`SEMIHOSTING_LINK_FILES`]): frames in through a
//!   regular file the firmware polls (QEMU never sleeps between steps), frames out through
//!   a FIFO, and a doorbell FIFO the firmware sleeps on when no frame comes for a while;
//!   fast (one host system call per frame each way).
//! - [`LinkKind::Uart`]: the board's CMSDK UART0 (the real driver path, receive interrupt
//!   into a ring buffer), attached by QEMU to a loopback TCP socket this process listens on.
//!
//! - A real board on a serial port ([`HilOptions::serial`], [`serial`]): no QEMU; the
//!   board's USART (e.g. the NUCLEO-F446RE's ST-LINK virtual COM port), read with `poll`
//!   like the FIFO. The CLI: `dexter run SCENE --hil --port /dev/ttyACM0`.
//!
//! ## Link faults
//! With [`HilOptions::corrupt_rate`] > 0 each host-to-device byte of a sensor frame
//! (including the extra delimiter the host sends after each frame to flush a partial frame
//! in the firmware's decoder) is dropped or has one bit flipped with that probability
//! (seeded RNG, [`CORRUPTION_SEED`]). The firmware answers every non-empty frame it
//! delimits (see `firmware/src/server.rs`): a valid sensor frame with its control step, a
//! rejected one with the safe command, `safe(seq, Fault::LinkTimeout)` (lock-step timeout:
//! one period without a valid frame). The host predicts which frames the firmware must
//! reject **without a decoder**: it splits the bytes it sent at the `0x00` delimiters and
//! calls a frame intact only if it is byte for byte the frame it encoded. Each answer,
//! safe ones included, is checked against the shadow bit for bit, and the firmware's own
//! counts of rejected and accepted frames (telemetry) against the host's
//! ([`LockStep::link_counts`]): a decoder that let a corrupted frame through (a weakened
//! CRC, say) shows up as a mismatch and as `corrupted_accepted > 0`. `Configure` and
//! `Stop` are sent uncorrupted.
//!
//! ## Adding a controller kind
//! 1. Implement `dexter_core::fixed_rate::FixedRate` for it (with its
//!    `STEP_INSTRUCTION_BUDGET` and the argument for it).
//! 2. Its variants appended to `Kind`, `Config`, `Frame` and `Command` and its `Wire` impl
//!    (`wire!`) in `shared/src/protocol/kinds.rs` (`dexter_core::protocol`, "Adding a
//!    controller kind").
//! 3. One line `Name(path::Controller)` in the `hosted!` list in `firmware/src/hosted.rs`.
//!
//! Then `LockStep::<path::Controller>::start(params, opts)` runs it in QEMU, and a system
//! closes its loop through `&mut dyn StepController<path::Controller>` exactly as in SIL.
//! Nothing in this module changes.

mod inject;
mod link;
mod lockstep;
pub mod qemu;
mod report;
mod semihosting;
pub mod serial;

pub use lockstep::LockStep;
pub use qemu::{
    build_firmware, build_firmware_image, build_firmware_with_features, check_qemu,
    check_toolchain, decode_defmt_log, default_firmware_elf, kill_all, llvm_tool, workspace_root,
};
pub use report::LinkCounts;
pub use serial::SerialPortOptions;

use std::path::PathBuf;
use std::time::Duration;

/// The firmware's compilation target.
pub const TARGET: &str = "thumbv7em-none-eabihf";
/// The emulator binary.
pub const QEMU: &str = "qemu-system-arm";
/// The emulated board.
pub const QEMU_MACHINE: &str = "mps2-an386";
/// `-icount shift`: one instruction is 2^10 ns of virtual time.
pub const ICOUNT_SHIFT: u32 = 10;
/// Seed of the byte-corruption RNG.
pub const CORRUPTION_SEED: u64 = 0x00de_c7e2_5eed;
/// Periods without a valid frame before the firmware answers with its safe command
/// (must equal `dexter_firmware::server::LOCKSTEP_TIMEOUT_PERIODS`).
pub const LOCKSTEP_TIMEOUT_PERIODS: u32 = 1;
/// File names of the semihosting link inside QEMU's working directory: frames in (a
/// regular file the firmware polls), the doorbell FIFO, frames out (a FIFO); the
/// firmware's `link::{HOST_TO_DEVICE_PATH, DOORBELL_PATH, DEVICE_TO_HOST_PATH}`.
pub const SEMIHOSTING_LINK_FILES: [&str; 3] = ["dexter-h2d", "dexter-bell", "dexter-d2h"];

/// Which plant link connects the host and the firmware.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LinkKind {
    /// Semihosting file I/O: a polled frame file in, a FIFO out (fast).
    #[default]
    Semihosting,
    /// The board's UART0 on a loopback TCP socket (the real driver path; slow in QEMU).
    Uart,
}

impl LinkKind {
    /// The firmware boot mode word (`-append`).
    fn boot_word(self) -> &'static str {
        match self {
            LinkKind::Semihosting => "semihosting",
            LinkKind::Uart => "uart",
        }
    }
}

/// The instruction budget a HIL run holds every control step to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StepBudget {
    /// The controller kind's own budget, `FixedRate::STEP_INSTRUCTION_BUDGET`.
    #[default]
    OfController,
    /// At most this many instructions.
    Instructions(u32),
    /// No check (the figures are still reported).
    Unchecked,
}

impl From<Option<u32>> for StepBudget {
    /// `Some(n)`: at most `n`; `None`: unchecked.
    fn from(budget: Option<u32>) -> Self {
        budget.map_or(StepBudget::Unchecked, StepBudget::Instructions)
    }
}

impl StepBudget {
    /// The limit for a controller whose own budget is `of_controller`.
    fn limit(self, of_controller: u32) -> Option<u32> {
        match self {
            StepBudget::OfController => Some(of_controller),
            StepBudget::Instructions(n) => Some(n),
            StepBudget::Unchecked => None,
        }
    }
}

/// How to run the firmware in the loop.
#[derive(Clone, Debug, PartialEq)]
pub struct HilOptions {
    /// The firmware ELF ([`default_firmware_elf`]; [`build_firmware`] builds it). A
    /// relative path is taken relative to the current directory.
    pub firmware_elf: PathBuf,
    /// The plant link.
    pub link: LinkKind,
    /// Most instructions one control step may take; a step over it fails the run.
    pub instruction_budget: StepBudget,
    /// Fraction of host-to-device bytes dropped or bit-flipped (seeded RNG), in [0, 1].
    pub corrupt_rate: f64,
    /// Longest wait for one answer from the firmware (and for QEMU to start or exit).
    pub timeout: Duration,
    /// A real board on this serial port instead of QEMU (`firmware_elf` and `link` are then
    /// unused; the step figures are DWT cycles, see [`serial`]).
    pub serial: Option<SerialPortOptions>,
}

impl Default for HilOptions {
    fn default() -> Self {
        Self {
            firmware_elf: default_firmware_elf(),
            link: LinkKind::Semihosting,
            instruction_budget: StepBudget::OfController,
            corrupt_rate: 0.0,
            timeout: Duration::from_secs(10),
            serial: None,
        }
    }
}
