//! # dexter-firmware
//!
//! The board-neutral firmware library: the shared control core ([`dexter_core`]) on a
//! Cortex-M4F behind a thin board layer ([`board`]): a byte link that implements
//! `embedded_io::{Read, Write}` and a step timer ([`board::StepTimer`]); a board with a
//! HAL gets that link from [`uart`], generic over `embedded_hal_nb::serial`, and its
//! receive ring from [`ring`] (heapless's SPSC queue). The protocol server ([`server`]),
//! the controllers it hosts ([`hosted`]) and the stack measurement ([`stack`]) are the
//! same on every board.
//!
//! The boards are crates of their own, each with its binary, `memory.x`, defmt global
//! logger, panic and fault handlers: `boards/mps2-an386` (the emulated board QEMU runs:
//! UART0, a semihosting link, the smoke run and the math benchmarks, an exit status for
//! every run) and `boards/nucleo-f446re` (RTIC, defmt over RTT, and fault handlers that cut
//! the motor first). Linking this library pulls in neither semihosting nor a logger.
#![no_std]
#![warn(missing_docs)]
#![deny(unsafe_op_in_unsafe_fn)]

pub mod board;
pub mod hosted;
pub mod ring;
pub mod server;
pub mod stack;
pub mod uart;
