//! A HardFault stops the motor before anything else: the PWM timer would otherwise keep
//! driving the paddle with the last duty while the core is stuck. (A panic goes through
//! `panic-probe`, which ends in `udf`, so it lands here too.)

use cortex_m_rt::{exception, ExceptionFrame};
use stm32f4xx_hal::pac::TIM1;

/// Cut the motor driver's PWM: duty 0 and TIM1's main outputs off, by register (the HAL
/// objects belong to tasks that can no longer run).
pub fn motor_off() {
    // Safety: TIM1 is only written here after a fault, when no task runs any more; the two
    // writes only lower outputs.
    let tim1 = unsafe { &*TIM1::ptr() };
    tim1.ccr1().write(|w| unsafe { w.bits(0) });
    tim1.bdtr().modify(|_, w| w.moe().clear_bit());
}

/// Stop the motor, log where, and stay here (a debugger attached sees the HardFault first).
#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    motor_off();
    defmt::error!("HardFault at pc={=u32:#010x}; motor off", frame.pc());
    loop {
        cortex_m::asm::wfi();
    }
}
