//! # dexter-firmware
//!
//! The shared control core ([`dexter_core`]) on a Cortex-M4F. The board layer is thin
//! ([`board`]): a byte link that implements `embedded_io::{Read, Write}` and a step timer
//! ([`board::StepTimer`]); a board with a HAL gets that link from [`uart`], generic over
//! `embedded_hal_nb::serial`. Everything else — the protocol server ([`server`]) and the
//! controllers it hosts ([`hosted`]), the smoke run ([`smoke`]), the stack measurement
//! ([`stack`]) and the math benchmarks (`bench`, feature `bench`) — is board independent.
//!
//! This library holds no global singletons: the defmt global logger, the panic handler and
//! the `HardFault` handler belong to each binary (knurling app-template style), because they
//! differ per board: the QEMU image (`src/main.rs`) logs over semihosting and ends the run
//! with an exit status; a real board (`boards/nucleo-f446re`) logs over RTT (`defmt-rtt`)
//! and its own panic handlers, which cut the motor first. Linking this library therefore
//! pulls in neither.
#![no_std]
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

#[cfg(feature = "bench")]
pub mod bench;
pub mod board;
pub mod hosted;
pub mod link;
pub mod ring;
pub mod server;
pub mod smoke;
pub mod stack;
pub mod uart;
