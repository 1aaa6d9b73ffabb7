//! The paddle actuator: a DC motor on a PWM + direction H-bridge driver (e.g. a Cytron
//! MD10C or a Pololu G2), behind `embedded_hal::pwm::SetDutyCycle` and
//! `embedded_hal::digital::OutputPin`.
//!
//! The core commands a paddle **acceleration** (`ActuatorCommand::paddle_accel_mps2`); the
//! driver sets a **voltage** (duty). [`MotorModel`] is the linear DC-motor model between
//! the two, for a motor driving the paddle through a pulley or a rack:
//!
//! ```text
//!   d V = R I + k_e v / r          (armature: supply fraction d, back-EMF at paddle speed v)
//!   m a = k_t I / r                (force on the paddle, effective moving mass m)
//! ⇒ a = a_stall (d - v / v_noload),  a_stall = k_t V / (m R r),  v_noload = r V / k_e
//! ⇒ d = a / a_stall + v / v_noload
//! ```
//!
//! so two figures measured on the rig calibrate it: the acceleration at full duty from rest
//! (`stall_accel_mps2`) and the speed at full duty without load (`no_load_speed_mps`).
//! Friction and the inductance's time constant (L / R, well under a 2 ms period for a small
//! motor) are left out.

use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;

/// Why a driver or its calibration was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ConfigError {
    /// The named figure must be finite and greater than zero.
    NotPositive(&'static str),
    /// The PWM reports a maximum duty of 0: it cannot express any duty.
    NoDutyRange,
}

/// The linear DC-motor model of the paddle drive (see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MotorModel {
    /// Paddle acceleration at full duty from rest, m/s^2 (> 0).
    pub stall_accel_mps2: f32,
    /// Paddle speed at full duty without load, m/s (> 0).
    pub no_load_speed_mps: f32,
}

impl MotorModel {
    /// A model; the error names the first figure that is not finite and positive.
    pub fn new(stall_accel_mps2: f32, no_load_speed_mps: f32) -> Result<Self, ConfigError> {
        positive("stall_accel_mps2", stall_accel_mps2)?;
        positive("no_load_speed_mps", no_load_speed_mps)?;
        Ok(Self {
            stall_accel_mps2,
            no_load_speed_mps,
        })
    }

    /// Signed duty in [-1, 1] that gives acceleration `accel_mps2` at paddle velocity
    /// `velocity_mps`: `d = a / a_stall + v / v_noload`, saturated. A non-finite input gives
    /// 0 (no drive), never a NaN duty.
    pub fn duty(&self, accel_mps2: f32, velocity_mps: f32) -> f32 {
        let d = accel_mps2 / self.stall_accel_mps2 + velocity_mps / self.no_load_speed_mps;
        if d.is_finite() {
            d.clamp(-1.0, 1.0)
        } else {
            0.0
        }
    }
}

pub(crate) fn positive(name: &'static str, value: f32) -> Result<(), ConfigError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ConfigError::NotPositive(name))
    }
}

/// Which way the motor pushes the paddle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Direction {
    /// Up (positive acceleration): the direction pin high.
    Up,
    /// Down: the direction pin low.
    Down,
}

/// What the drive was set to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Drive {
    /// The direction pin's state.
    pub direction: Direction,
    /// The duty written to the PWM, in its counts (0 ..= its maximum).
    pub duty: u16,
}

/// A driver error: the PWM's or the direction pin's, as the HAL reported it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ActuatorError<PwmError, PinError> {
    /// Setting the duty failed.
    Pwm(PwmError),
    /// Setting the direction pin failed.
    Direction(PinError),
}

/// The paddle's motor: PWM duty plus a direction pin, driven from an acceleration command.
pub struct PaddleDrive<P, D> {
    pwm: P,
    direction: D,
    model: MotorModel,
    max_duty: u16,
}

/// The drive's error type for a PWM `P` and a direction pin `D`.
pub type DriveError<P, D> = ActuatorError<
    <P as embedded_hal::pwm::ErrorType>::Error,
    <D as embedded_hal::digital::ErrorType>::Error,
>;

impl<P: SetDutyCycle, D: OutputPin> PaddleDrive<P, D> {
    /// The drive, stopped (duty 0, direction up). Fails if the PWM has no duty range.
    pub fn new(mut pwm: P, mut direction: D, model: MotorModel) -> Result<Self, InitError<P, D>> {
        let max_duty = pwm.max_duty_cycle();
        if max_duty == 0 {
            return Err(InitError::Config(ConfigError::NoDutyRange));
        }
        pwm.set_duty_cycle_fully_off()
            .map_err(|e| InitError::Drive(ActuatorError::Pwm(e)))?;
        direction
            .set_high()
            .map_err(|e| InitError::Drive(ActuatorError::Direction(e)))?;
        Ok(Self {
            pwm,
            direction,
            model,
            max_duty,
        })
    }

    /// Drive the paddle for acceleration `accel_mps2` at its measured velocity
    /// `velocity_mps` (the back-EMF term): the direction is set before the duty, so a new
    /// duty never runs the old way.
    pub fn apply(&mut self, accel_mps2: f32, velocity_mps: f32) -> Result<Drive, DriveError<P, D>> {
        let d = self.model.duty(accel_mps2, velocity_mps);
        let direction = if d < 0.0 {
            Direction::Down
        } else {
            Direction::Up
        };
        let counts = f32::from(self.max_duty) * d.abs() + 0.5;
        // `counts` is in [0.5, max + 0.5]: the cast truncates to 0 ..= max (saturating).
        let duty = (counts as u16).min(self.max_duty);
        self.set(Drive { direction, duty })
    }

    /// No drive: duty 0 (the H-bridge coasts or brakes, as the driver board does at 0).
    pub fn park(&mut self) -> Result<Drive, DriveError<P, D>> {
        self.set(Drive {
            direction: Direction::Up,
            duty: 0,
        })
    }

    fn set(&mut self, drive: Drive) -> Result<Drive, DriveError<P, D>> {
        match drive.direction {
            Direction::Up => self.direction.set_high(),
            Direction::Down => self.direction.set_low(),
        }
        .map_err(ActuatorError::Direction)?;
        self.pwm
            .set_duty_cycle(drive.duty)
            .map_err(ActuatorError::Pwm)?;
        Ok(drive)
    }

    /// The model the drive converts with.
    pub fn model(&self) -> &MotorModel {
        &self.model
    }

    /// The PWM's full-scale duty, counts.
    pub fn max_duty(&self) -> u16 {
        self.max_duty
    }
}

/// Why [`PaddleDrive::new`] failed.
pub enum InitError<P: SetDutyCycle, D: OutputPin> {
    /// The PWM cannot express a duty.
    Config(ConfigError),
    /// Stopping the drive failed.
    Drive(DriveError<P, D>),
}

impl<P: SetDutyCycle, D: OutputPin> core::fmt::Debug for InitError<P, D> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            InitError::Config(e) => write!(f, "Config({e:?})"),
            InitError::Drive(e) => write!(f, "Drive({e:?})"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as Pin};
    use embedded_hal_mock::eh1::pwm::{Mock as PwmMock, Transaction as Pwm};

    const MAX: u16 = 1000;

    fn model() -> MotorModel {
        MotorModel::new(200.0, 4.0).unwrap()
    }

    /// Expectations of `new`: read the range, duty off, direction up.
    fn init() -> (Vec<Pwm>, Vec<Pin>) {
        (
            vec![Pwm::max_duty_cycle(MAX), Pwm::set_duty_cycle(0)],
            vec![Pin::set(State::High)],
        )
    }

    fn drive_with(pwm: Vec<Pwm>, pin: Vec<Pin>) -> PaddleDrive<PwmMock, PinMock> {
        PaddleDrive::new(PwmMock::new(&pwm), PinMock::new(&pin), model()).unwrap()
    }

    fn done(mut d: PaddleDrive<PwmMock, PinMock>) {
        d.pwm.done();
        d.direction.done();
    }

    #[test]
    fn the_duty_inverts_the_dc_motor_model() {
        // a = a_stall (d - v / v0) at d = 0.3, v = 1.2 m/s: a = 200 (0.3 - 0.3) = 0.
        let m = model();
        assert_eq!(m.duty(0.0, 1.2), 0.3);
        // from rest, half the stall acceleration takes half the duty
        assert_eq!(m.duty(100.0, 0.0), 0.5);
        // braking a rising paddle: a = -100 at v = 2: d = -0.5 + 0.5 = 0
        assert_eq!(m.duty(-100.0, 2.0), 0.0);
        // round trip through the forward model for a few points
        for (a, v) in [(37.0f32, -0.8f32), (-150.0, 1.0), (12.5, 0.25)] {
            let d = m.duty(a, v);
            let back = m.stall_accel_mps2 * (d - v / m.no_load_speed_mps);
            assert!((back - a).abs() < 1e-4, "{a} -> {d} -> {back}");
        }
    }

    #[test]
    fn the_duty_saturates_and_a_non_finite_command_gives_no_drive() {
        let m = model();
        assert_eq!(m.duty(1e6, 0.0), 1.0);
        assert_eq!(m.duty(-1e6, 0.0), -1.0);
        assert_eq!(m.duty(f32::NAN, 0.0), 0.0);
        assert_eq!(m.duty(0.0, f32::INFINITY), 0.0);
    }

    #[test]
    fn calibration_figures_must_be_finite_and_positive() {
        assert_eq!(
            MotorModel::new(0.0, 1.0),
            Err(ConfigError::NotPositive("stall_accel_mps2"))
        );
        assert_eq!(
            MotorModel::new(1.0, f32::NAN),
            Err(ConfigError::NotPositive("no_load_speed_mps"))
        );
    }

    #[test]
    fn an_upward_command_sets_the_pin_high_then_the_rounded_duty() {
        let (mut pwm, mut pin) = init();
        // 0.25 of stall plus 0.1 of no-load speed: d = 0.35 -> 350 counts
        pin.push(Pin::set(State::High));
        pwm.push(Pwm::set_duty_cycle(350));
        let mut d = drive_with(pwm, pin);
        let got = d.apply(50.0, 0.4).unwrap();
        assert_eq!(
            got,
            Drive {
                direction: Direction::Up,
                duty: 350
            }
        );
        done(d);
    }

    #[test]
    fn a_downward_command_sets_the_pin_low_and_the_magnitude() {
        let (mut pwm, mut pin) = init();
        // d = -0.6 + (-0.1) = -0.7 -> down, 700 counts; then saturation -> 1000
        pin.extend([Pin::set(State::Low), Pin::set(State::Low)]);
        pwm.extend([Pwm::set_duty_cycle(700), Pwm::set_duty_cycle(MAX)]);
        let mut d = drive_with(pwm, pin);
        assert_eq!(d.apply(-120.0, -0.4).unwrap().duty, 700);
        assert_eq!(d.apply(-1e9, 0.0).unwrap().direction, Direction::Down);
        done(d);
    }

    #[test]
    fn park_writes_zero_duty() {
        let (mut pwm, mut pin) = init();
        pin.push(Pin::set(State::High));
        pwm.push(Pwm::set_duty_cycle(0));
        let mut d = drive_with(pwm, pin);
        assert_eq!(d.park().unwrap().duty, 0);
        done(d);
    }

    #[test]
    fn a_pwm_without_range_is_refused_and_hal_errors_are_passed_on() {
        let mut pwm = PwmMock::new(&[Pwm::max_duty_cycle(0)]);
        let mut pin = PinMock::new(&[]);
        let r = PaddleDrive::new(pwm.clone(), pin.clone(), model());
        assert!(matches!(
            r,
            Err(InitError::Config(ConfigError::NoDutyRange))
        ));
        pwm.done();
        pin.done();
        let (mut pwm, mut pin) = init();
        let err = embedded_hal_mock::eh1::MockError::Io(std::io::ErrorKind::Other);
        pin.push(Pin::set(State::High));
        pwm.push(Pwm::set_duty_cycle(500).with_error(err.clone()));
        let mut d = drive_with(pwm, pin);
        assert!(matches!(d.apply(100.0, 0.0), Err(ActuatorError::Pwm(_))));
        done(d);
    }
}
