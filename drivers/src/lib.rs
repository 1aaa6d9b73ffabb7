//! # dexter-drivers
//!
//! Board-independent drivers written against the embedded-hal 1.0 traits, so a board
//! supplies HAL objects and the control code never names a register. They know nothing of
//! dexter's control core (no dependency on it: the crate could be published on its own);
//! `dexter-rig` (`rig/`) turns their readings into the core's frames and the core's
//! commands into their calls.
//!
//! - [`actuator`]: the paddle's DC motor as PWM duty plus a direction pin
//!   (`embedded_hal::pwm::SetDutyCycle`, `embedded_hal::digital::OutputPin`), driven from
//!   the core's acceleration command through a linear motor model;
//! - [`encoder`]: the paddle's position from a quadrature-encoder timer
//!   ([`encoder::QuadratureCounter`], with wrap handling);
//! - [`camera`]: the ball's measurement from a serial camera's frames
//!   (`embedded_hal_nb::serial::Read<u8>`), a resynchronising byte parser;
//!
//! Everything here is tested on the host against `embedded-hal-mock` (`cargo test -p
//! dexter-drivers`); the board crates (`boards/`) only construct HAL objects and call in.
#![cfg_attr(not(test), no_std)]
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod actuator;
pub mod camera;
pub mod encoder;

pub use actuator::ConfigError;
