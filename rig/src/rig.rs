//! A rig: the sensors and actuators one controller kind closes its loop through, as the
//! core sees them (its `FixedRate::Frame` in, its `Command` out). [`LineRig`] is the line
//! juggler's: the paddle's encoder and motor, and the ball camera.

use dexter_core::protocol::{ActuatorCommand, SensorFrame};
use dexter_drivers::actuator::{Drive, DriveError, PaddleDrive};
use dexter_drivers::camera::{Camera, CameraFrame, CameraStats, RowToHeight};
use dexter_drivers::encoder::{PaddleEncoder, PaddleSample, QuadratureCounter};
use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;
use embedded_hal_nb::serial::Read;

/// Sensors in, actuators out, for one controller kind.
pub trait Rig {
    /// What the controller steps on (its `FixedRate::Frame`).
    type Frame;
    /// What it commands (its `FixedRate::Command`).
    type Command;
    /// Why an actuator write failed.
    type Error;
    /// Sample every sensor once (called once per control period).
    fn sense(&mut self) -> Self::Frame;
    /// Apply a command.
    fn actuate(&mut self, command: &Self::Command) -> Result<(), Self::Error>;
    /// Stop driving (no torque), e.g. while a host drives the simulated plant instead.
    fn park(&mut self) -> Result<(), Self::Error>;
}

/// The line juggler's rig: paddle encoder, paddle motor, ball camera.
///
/// [`Rig::sense`] builds the core's [`SensorFrame`]: the paddle from the encoder every
/// period; the ball from the newest camera frame. `seq` counts camera images (a new camera
/// `seq`), so between two images the controller sees the sequence number stand still and
/// coasts its estimator, and declares the input stale after `stale_limit_steps` periods
/// without an image, as the core specifies. Until the first image, and whenever the camera
/// reports no ball, the ball height is NaN, which the controller answers with its safe state.
pub struct LineRig<Q, R, P, D> {
    encoder: PaddleEncoder<Q>,
    camera: Camera<R>,
    calibration: RowToHeight,
    drive: PaddleDrive<P, D>,
    seq: u32,
    camera_seq: Option<u8>,
    ball_height_m: f32,
    paddle: PaddleSample,
    last_drive: Option<Drive>,
    last_image: Option<CameraFrame>,
}

impl<Q, R, P, D> LineRig<Q, R, P, D>
where
    Q: QuadratureCounter,
    R: Read<u8>,
    P: SetDutyCycle,
    D: OutputPin,
{
    /// The rig from its parts.
    pub fn new(
        encoder: PaddleEncoder<Q>,
        camera: Camera<R>,
        calibration: RowToHeight,
        drive: PaddleDrive<P, D>,
    ) -> Self {
        Self {
            encoder,
            camera,
            calibration,
            drive,
            seq: 0,
            camera_seq: None,
            ball_height_m: f32::NAN,
            paddle: PaddleSample::default(),
            last_drive: None,
            last_image: None,
        }
    }

    /// The camera parser's counts.
    pub fn camera_stats(&self) -> CameraStats {
        self.camera.stats()
    }

    /// The last paddle sample.
    pub fn paddle(&self) -> PaddleSample {
        self.paddle
    }

    /// The encoder's position at the last [`Rig::sense`], counts from reset.
    pub fn paddle_counts(&self) -> i64 {
        self.encoder.counts()
    }

    /// The newest camera image [`Rig::sense`] has read, raw (row and column in px), for
    /// calibration; none before the first.
    pub fn last_image(&self) -> Option<CameraFrame> {
        self.last_image
    }

    /// The last drive written (direction and duty counts).
    pub fn last_drive(&self) -> Option<Drive> {
        self.last_drive
    }
}

impl<Q, R, P, D> Rig for LineRig<Q, R, P, D>
where
    Q: QuadratureCounter,
    R: Read<u8>,
    P: SetDutyCycle,
    D: OutputPin,
{
    type Frame = SensorFrame;
    type Command = ActuatorCommand;
    type Error = DriveError<P, D>;

    fn sense(&mut self) -> SensorFrame {
        self.paddle = self.encoder.sample();
        if let Some(image) = self.camera.poll() {
            self.last_image = Some(image);
            if self.camera_seq != Some(image.seq) {
                self.camera_seq = Some(image.seq);
                self.seq = self.seq.wrapping_add(1);
                self.ball_height_m = self.calibration.height_m(&image);
            }
        }
        SensorFrame {
            seq: self.seq,
            ball_height_m: self.ball_height_m,
            paddle_height_m: self.paddle.height_m,
            paddle_velocity_mps: self.paddle.velocity_mps,
        }
    }

    /// The commanded acceleration through the motor model, at the paddle's measured
    /// velocity (the back-EMF term).
    fn actuate(&mut self, command: &ActuatorCommand) -> Result<(), Self::Error> {
        let drive = self
            .drive
            .apply(command.paddle_accel_mps2, self.paddle.velocity_mps)?;
        self.last_drive = Some(drive);
        Ok(())
    }

    fn park(&mut self) -> Result<(), Self::Error> {
        self.last_drive = Some(self.drive.park()?);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dexter_drivers::actuator::{Direction, MotorModel};
    use dexter_drivers::camera::CameraFrame;
    use dexter_drivers::encoder::QuadratureCounter;
    use embedded_hal_mock::eh1::digital::{Mock as PinMock, State, Transaction as Pin};
    use embedded_hal_mock::eh1::pwm::{Mock as PwmMock, Transaction as Pwm};
    use embedded_hal_mock::eh1::serial::{Mock as SerialMock, Transaction as Serial};
    use embedded_hal_nb::nb;

    struct Counts(std::vec::IntoIter<u32>);

    impl QuadratureCounter for Counts {
        const BITS: u32 = 16;
        fn count(&mut self) -> u32 {
            self.0.next().expect("a count per read")
        }
    }

    fn image(seq: u8, y_px: f32) -> Vec<u8> {
        CameraFrame {
            seq,
            found: true,
            x_px: 0.0,
            y_px,
        }
        .encode()
        .to_vec()
    }

    #[test]
    fn sense_builds_the_cores_frame_and_actuate_drives_the_motor() {
        // encoder: 0 at start, then +100 counts (10 mm at 0.1 mm/count) each period
        let counts = Counts(vec![0, 100, 200, 300, 400].into_iter());
        let encoder = PaddleEncoder::new(counts, 1e-4, 0.0, 0.002).unwrap();
        // camera: image 5 at row 300 (1 m above row 400 at 1 cm/px), then nothing, then
        // image 5 again (a repeat is not a new image), then image 5 again and image 6
        // without the ball in one poll (the newest counts)
        let mut uart = SerialMock::new(&[
            Serial::read_many(image(5, 300.0)),
            Serial::read_error(nb::Error::WouldBlock),
            Serial::read_error(nb::Error::WouldBlock),
            Serial::read_many(image(5, 300.0)),
            Serial::read_error(nb::Error::WouldBlock),
            Serial::read_many(image(5, 300.0)),
            Serial::read_many(
                CameraFrame {
                    seq: 6,
                    ..CameraFrame::default()
                }
                .encode(),
            ),
            Serial::read_error(nb::Error::WouldBlock),
        ]);
        let mut pwm = PwmMock::new(&[
            Pwm::max_duty_cycle(1000),
            Pwm::set_duty_cycle(0),
            Pwm::set_duty_cycle(750), // 50/200 + 5/10 (v = 5 m/s at v0 = 10)
        ]);
        let mut pin = PinMock::new(&[Pin::set(State::High), Pin::set(State::High)]);
        let drive = PaddleDrive::new(
            pwm.clone(),
            pin.clone(),
            MotorModel::new(200.0, 10.0).unwrap(),
        )
        .unwrap();
        let cal = RowToHeight::new(400.0, 0.01).unwrap();
        let mut rig = LineRig::new(encoder, Camera::new(uart.clone()), cal, drive);

        assert_eq!(rig.last_image(), None);
        let f = rig.sense();
        assert_eq!(f.seq, 1);
        assert!((f.ball_height_m - 1.0).abs() < 1e-6);
        assert!((f.paddle_height_m - 0.01).abs() < 1e-7);
        assert_eq!(rig.paddle_counts(), 100);
        assert_eq!(rig.last_image().map(|i| (i.seq, i.y_px)), Some((5, 300.0)));
        assert!((f.paddle_velocity_mps - 5.0).abs() < 1e-5);
        let command = ActuatorCommand {
            paddle_accel_mps2: 50.0,
            ..ActuatorCommand::default()
        };
        rig.actuate(&command).unwrap();
        assert_eq!(
            rig.last_drive(),
            Some(Drive {
                direction: Direction::Up,
                duty: 750
            })
        );
        let f = rig.sense(); // no new image: seq stands still, the last height stays
        assert_eq!(f.seq, 1);
        assert!((f.ball_height_m - 1.0).abs() < 1e-6);
        let f = rig.sense(); // image 5 repeated: no new sample
        assert_eq!(f.seq, 1);
        let f = rig.sense(); // image 5 repeated, then image 6 without a ball
        assert_eq!(f.seq, 2);
        assert!(f.ball_height_m.is_nan());
        assert_eq!(rig.last_image().map(|i| (i.seq, i.found)), Some((6, false)));
        assert_eq!(rig.paddle_counts(), 400);
        assert_eq!(rig.camera_stats().frames, 4);
        uart.done();
        pwm.done();
        pin.done();
    }
}
