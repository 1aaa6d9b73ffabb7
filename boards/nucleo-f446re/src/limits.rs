//! The paddle's travel limits: two normally-closed limit switches, each between a pin and
//! ground, read with the pin's pull-up. Closed (the paddle inside its travel) reads low;
//! a switch that opens (the paddle at an end) or a broken wire reads high, and the rising
//! edge interrupts (EXTI0, EXTI1, above every task): the motor is cut as on a fault
//! ([`crate::fault::Cause::LimitSwitch`]), nothing runs any more, and the watchdog,
//! no longer fed, resets the part, which then keeps the motor parked until a person presses
//! reset (`init` reads RCC's watchdog flag). A switch open at reset parks the motor too.
//!
//! | switch | pin (Arduino header) | EXTI line |
//! | --- | --- | --- |
//! | lower end | PC0 (A5) | 0 |
//! | upper end | PC1 (A4) | 1 |
//!
//! These switches are the firmware's stop; the same switches (or a second pair) in series
//! with the driver's supply or enable stop the motor without it (firmware/README.md).

use stm32f4xx_hal::gpio::{Edge, ExtiPin, Input, PC0, PC1};
use stm32f4xx_hal::pac::EXTI;
use stm32f4xx_hal::syscfg::SysCfg;

/// The two switches' pins, interrupts armed.
pub struct LimitSwitches {
    lower: PC0<Input>,
    upper: PC1<Input>,
}

impl LimitSwitches {
    /// Pull both pins up and interrupt on either switch opening (a rising edge).
    pub fn new(lower: PC0, upper: PC1, syscfg: &mut SysCfg, exti: &mut EXTI) -> Self {
        let mut lower = lower.into_pull_up_input();
        let mut upper = upper.into_pull_up_input();
        lower.make_interrupt_source(syscfg);
        upper.make_interrupt_source(syscfg);
        lower.trigger_on_edge(exti, Edge::Rising);
        upper.trigger_on_edge(exti, Edge::Rising);
        lower.enable_interrupt(exti);
        upper.enable_interrupt(exti);
        Self { lower, upper }
    }

    /// Whether either switch is open now (the paddle at an end, or a wire broken).
    pub fn open(&self) -> bool {
        self.lower.is_high() || self.upper.is_high()
    }
}
