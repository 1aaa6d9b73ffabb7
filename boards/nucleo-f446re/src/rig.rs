//! The line juggler's rig on this board: which timer and pin does what, the rig's
//! calibration, and the [`QuadratureCounter`] of the encoder timer. The drivers themselves
//! are board independent (`dexter_drivers`); this module only hands them HAL objects.
//!
//! | function | peripheral | pin (Arduino header) |
//! | --- | --- | --- |
//! | motor driver PWM, 20 kHz | TIM1 CH1 | PA8 (D7) |
//! | motor driver DIR | GPIO | PB5 (D4) |
//! | encoder A / B | TIM3 CH1 / CH2, encoder mode | PA6 (D12) / PA7 (D11) |
//! | camera TX -> board RX, 115 200 Bd 8N1 | USART1 RX | PA10 (D2) |
//! | host link (lock-step HIL), 921 600 Bd | USART2, the ST-LINK's virtual COM port | PA2 / PA3 (no wire) |

use dexter_drivers::actuator::{ActuatorError, MotorModel, PaddleDrive};
use dexter_drivers::camera::{Camera, RowToHeight};
use dexter_drivers::encoder::{PaddleEncoder, QuadratureCounter};
use dexter_drivers::ConfigError;
use dexter_rig::rig::LineRig;
use stm32f4xx_hal::gpio::{Output, PushPull, PB5};
use stm32f4xx_hal::pac::{TIM1, TIM3};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::qei::Qei;
use stm32f4xx_hal::timer::PwmChannel;

use dexter_firmware::uart::RingReader;

/// PWM frequency of the motor driver, Hz (above hearing, within an MD10C's 20 kHz).
pub const PWM_HZ: u32 = 20_000;
/// Camera UART rate, Bd.
pub const CAMERA_BAUD: u32 = 115_200;

/// Paddle travel per encoder count, m: a 1000-line encoder (4000 counts per turn in
/// quadrature) on a belt pulley of 12.5 mm radius: 2 pi 0.0125 / 4000. **Measure yours.**
pub const M_PER_COUNT: f32 = 2.0 * core::f32::consts::PI * 0.0125 / 4000.0;
/// The paddle's height at power-up, m: it must rest at its home height (the controller's
/// `home_height_m`, 0 by default) when the board starts, because the encoder is relative.
pub const PADDLE_HEIGHT_AT_RESET_M: f32 = 0.0;
/// Paddle acceleration at full duty from rest, m/s^2 (see `dexter_drivers::actuator`).
pub const STALL_ACCEL_MPS2: f32 = 150.0;
/// Paddle speed at full duty without load, m/s.
pub const NO_LOAD_SPEED_MPS: f32 = 2.5;
/// The camera image row of the impact plane (height 0), px.
pub const ROW_AT_ZERO_PX: f32 = 460.0;
/// Metres per image row along the ball's line of flight (480 rows over 1.2 m).
pub const M_PER_PX: f32 = 0.0025;

/// TIM3 in encoder mode: a 16-bit up/down counter.
pub struct Tim3Encoder(pub Qei<TIM3>);

impl QuadratureCounter for Tim3Encoder {
    const BITS: u32 = 16;
    fn count(&mut self) -> u32 {
        u32::from(self.0.count())
    }
}

/// The motor driver's PWM channel.
pub type MotorPwm = PwmChannel<TIM1, 0>;
/// The motor driver's direction pin.
pub type MotorDir = PB5<Output<PushPull>>;
/// The line juggler's rig on this board.
pub type BoardRig = LineRig<Tim3Encoder, RingReader, MotorPwm, MotorDir>;

/// The rig from its HAL parts, with this file's calibration, sampled every `dt_s`.
pub fn rig(
    encoder: Tim3Encoder,
    camera: RingReader,
    pwm: MotorPwm,
    dir: MotorDir,
    dt_s: f32,
) -> Result<BoardRig, ConfigError> {
    let encoder = PaddleEncoder::new(encoder, M_PER_COUNT, PADDLE_HEIGHT_AT_RESET_M, dt_s)?;
    let model = MotorModel::new(STALL_ACCEL_MPS2, NO_LOAD_SPEED_MPS)?;
    let drive = match PaddleDrive::new(pwm, dir, model) {
        Ok(d) => d,
        Err(dexter_drivers::actuator::InitError::Config(e)) => return Err(e),
        Err(dexter_drivers::actuator::InitError::Drive(e)) => match e {
            // The HAL's PWM channel and GPIO pin cannot fail (`Infallible`).
            ActuatorError::Pwm(never) => match never {},
            ActuatorError::Direction(never) => match never {},
        },
    };
    let calibration = RowToHeight::new(ROW_AT_ZERO_PX, M_PER_PX)?;
    Ok(LineRig::new(
        encoder,
        Camera::new(camera),
        calibration,
        drive,
    ))
}
