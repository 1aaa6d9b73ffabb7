//! The serial-port link end to end, without a board: a pseudo-terminal pair stands for the
//! USB virtual COM port, and a stand-in device thread on its master end serves the lock-step
//! protocol with the real core (the answer table of `firmware/src/server.rs`: `Configured`,
//! `Output` with the decoder's counts, the safe command for a frame the link rejected,
//! `Stopped`). `LockStep` opens the slave end by its path through the same code a board
//! takes: `serialport` open, resync, `poll`, lock-step, the bit-for-bit check.

use super::super::{HilOptions, LockStep, SerialPortOptions, StepBudget};
use super::*;
use crate::controller::StepController;
use dexter_core::control::{Controller, ControllerParams};
use dexter_core::echo::{Echo, EchoFrame, EchoParams};
use dexter_core::fixed_rate::{Fault, FixedRate, Reply, Telemetry};
use dexter_core::protocol::{
    encode, DeviceMessage, FrameDecoder, HostMessage, RunSummary, SensorFrame, Wire, MAX_FRAME_LEN,
};
use std::fs::File;
use std::os::fd::{FromRawFd, OwnedFd};
use std::thread::JoinHandle;

/// A pseudo-terminal: the master end (the stand-in device's) and the slave's path (the
/// port the host opens). The slave stays open here too, so the master never sees a hang-up
/// between the host's open and close.
struct Pty {
    master: File,
    _slave: OwnedFd,
    path: PathBuf,
}

fn pty() -> Pty {
    let (mut master, mut slave) = (0, 0);
    // Safety: openpty writes two descriptors; the name, termios and winsize are optional.
    let r = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    assert_eq!(r, 0, "openpty: {}", std::io::Error::last_os_error());
    // Safety: both descriptors were just opened by openpty and are owned here.
    let (master, slave) = unsafe { (File::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) };
    // Raw mode on the slave before anyone writes (no echo, no newline translation).
    // Safety: tcgetattr fills `t`; cfmakeraw and tcsetattr read it.
    unsafe {
        let mut t = std::mem::zeroed::<libc::termios>();
        assert_eq!(libc::tcgetattr(slave.as_raw_fd(), &mut t), 0);
        libc::cfmakeraw(&mut t);
        assert_eq!(libc::tcsetattr(slave.as_raw_fd(), libc::TCSANOW, &t), 0);
    }
    let path = std::fs::read_link(format!("/proc/self/fd/{}", slave.as_raw_fd()))
        .expect("the slave's path");
    Pty {
        master,
        _slave: slave,
        path,
    }
}

/// The stand-in device: the lock-step answers of the firmware's server, for kind `C`.
struct Device<C: Wire> {
    io: File,
    decoder: FrameDecoder<MAX_FRAME_LEN>,
    controller: Option<C>,
    last_seq: u32,
    /// Periods without a valid frame since the last step.
    missed: u32,
    steps: u32,
    timeouts: u32,
}

impl<C: Wire + Send + 'static> Device<C> {
    fn serve(io: File) -> JoinHandle<RunSummary> {
        Self::serve_from(io, |_| {})
    }

    /// Serve from a state `setup` puts the device in (e.g. mid-session).
    fn serve_from(
        io: File,
        setup: impl FnOnce(&mut Self) + Send + 'static,
    ) -> JoinHandle<RunSummary>
    where
        C: Send + 'static,
    {
        std::thread::spawn(move || {
            let mut d = Device::<C> {
                io,
                decoder: FrameDecoder::new(),
                controller: None,
                last_seq: 0,
                missed: 0,
                steps: 0,
                timeouts: 0,
            };
            setup(&mut d);
            d.run()
        })
    }

    fn run(&mut self) -> RunSummary {
        let mut buf = [0u8; 256];
        loop {
            let n = self.io.read(&mut buf).expect("the device reads");
            for &b in &buf[..n] {
                let Some(result) = self.decoder.push::<HostMessage>(b) else {
                    continue;
                };
                if let Some(summary) = self.answer(result) {
                    return summary;
                }
            }
        }
    }

    fn answer(
        &mut self,
        result: Result<HostMessage, dexter_core::protocol::DecodeError>,
    ) -> Option<RunSummary> {
        match result {
            Ok(HostMessage::Configure(config)) => {
                let params = C::params_of(&config).expect("a Configure of the served kind");
                self.controller = C::new(*params).ok();
                let ok = self.controller.is_some();
                self.send(&DeviceMessage::Configured { kind: C::KIND, ok });
            }
            Ok(HostMessage::Sensor(frame)) => {
                let c = self.controller.as_mut().expect("configured");
                let command = c.step(C::frame_of(&frame).expect("a frame of the served kind"));
                self.last_seq = command.seq();
                self.missed = 0;
                self.steps += 1;
                self.output(command);
            }
            Ok(HostMessage::Stop) => {
                let summary = RunSummary {
                    steps: self.steps,
                    link_timeouts: self.timeouts,
                    ..RunSummary::default()
                };
                self.send(&DeviceMessage::Stopped(summary));
                return Some(summary);
            }
            Err(_) => {
                // one period without a valid frame: the safe command (timeout of 1 period),
                // its seq continuing the last valid one by the periods missed
                let c = self.controller.as_mut().expect("configured");
                self.missed += 1;
                let command = c.safe(self.last_seq.wrapping_add(self.missed), Fault::LinkTimeout);
                self.timeouts += 1;
                self.output(command);
            }
        }
        None
    }

    fn output(&mut self, command: C::Command) {
        let stats = self.decoder.stats();
        let telemetry = Telemetry {
            step_instructions: 1234, // a board reports cycles; no budget applies
            link_errors: stats.errors(),
            frames_ok: stats.frames_ok,
            ..self
                .controller
                .as_ref()
                .map(C::telemetry)
                .unwrap_or_default()
        };
        let command = C::command(command);
        self.send(&DeviceMessage::Output { command, telemetry });
    }

    fn send(&mut self, m: &DeviceMessage) {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode(m, &mut buf).expect("fits");
        self.io.write_all(&buf[..n]).expect("the device writes");
    }
}

fn options(path: &std::path::Path) -> HilOptions {
    HilOptions {
        serial: Some(SerialPortOptions::new(path)),
        // no ELF exists at this path: a board needs none
        firmware_elf: PathBuf::from("/nonexistent/firmware.elf"),
        timeout: Duration::from_secs(10),
        ..HilOptions::default()
    }
}

/// A ball dropped onto the paddle, sensed by a plant the test integrates itself.
fn line_frames(n: u32) -> impl Iterator<Item = SensorFrame> {
    let dt = 0.002f32;
    (0..n).map(move |i| {
        let t = i as f32 * dt;
        SensorFrame {
            seq: i,
            ball_height_m: (0.6 - 0.5 * 9.81 * t * t).max(0.0),
            paddle_height_m: 0.0,
            paddle_velocity_mps: 0.0,
        }
    })
}

#[test]
fn lock_step_over_a_serial_port_is_bit_exact_with_the_shadow_core() {
    let pty = pty();
    let device = Device::<Controller>::serve(pty.master.try_clone().unwrap());
    let mut hil = LockStep::<Controller>::start(ControllerParams::default(), options(&pty.path))
        .expect("start over the pty");
    assert_eq!(hil.instruction_budget(), None, "cycles, not instructions");
    assert_eq!(hil.qemu_pid(), 0);
    let mut shadow = Controller::new(ControllerParams::default()).unwrap();
    for frame in line_frames(300) {
        let got = hil.step(&frame).expect("step");
        // an independent shadow, stepped here: the driver returns the device's command
        assert!(got.command.bit_identical(&shadow.step(&frame)));
        assert_eq!(got.telemetry.step_instructions, 1234);
    }
    assert_eq!(hil.first_mismatch(), None);
    assert_eq!(hil.firmware_log_text().unwrap(), "");
    let (report, summary) = hil.finish_with_summary().expect("clean end");
    assert_eq!(summary.steps, 300);
    assert_eq!(report.sil_mismatches, 0);
    assert_eq!(device.join().unwrap().steps, 300);
}

#[test]
fn corrupted_bytes_over_a_serial_port_give_the_safe_state_and_matching_counts() {
    let pty = pty();
    let device = Device::<Echo>::serve(pty.master.try_clone().unwrap());
    let opts = HilOptions {
        corrupt_rate: 0.02,
        ..options(&pty.path)
    };
    let mut hil = LockStep::<Echo>::start(EchoParams::default(), opts).expect("start");
    for seq in 0..400 {
        hil.step(&EchoFrame { seq, value: 0.5 }).expect("step");
    }
    assert_eq!(hil.first_mismatch(), None, "commands and link counts agree");
    let counts = hil.link_counts();
    assert!(counts.host_corrupt > 0, "{counts:?}");
    assert_eq!(counts.corrupted_accepted, 0);
    let (_, summary) = hil.finish_with_summary().expect("clean end");
    assert!(summary.link_timeouts > 0);
    device.join().unwrap();
}

#[test]
fn leftovers_of_an_earlier_session_are_discarded_before_configure() {
    let pty = pty();
    // An answer the board still had in flight from a session the host abandoned.
    let mut stale = [0u8; MAX_FRAME_LEN];
    let n = encode(&DeviceMessage::Stopped(RunSummary::default()), &mut stale).unwrap();
    let mut master = pty.master.try_clone().unwrap();
    master.write_all(&stale[..n]).unwrap();
    let device = Device::<Echo>::serve(pty.master.try_clone().unwrap());
    let mut hil = LockStep::<Echo>::start(EchoParams::default(), options(&pty.path))
        .expect("the stale answer must not be taken for Configured");
    hil.step(&EchoFrame { seq: 1, value: 2.0 }).expect("step");
    hil.finish().expect("clean end");
    device.join().unwrap();
}

#[test]
fn a_board_left_mid_session_answers_the_flush_and_the_answer_is_discarded() {
    let pty = pty();
    // A board whose host died mid-frame: configured, half a frame in its decoder. The
    // host's flush delimiter completes that frame, which the board answers with its safe
    // command, after the host cleared its buffers: resync must drain it.
    let device = Device::<Echo>::serve_from(pty.master.try_clone().unwrap(), |d| {
        d.controller = Echo::new(EchoParams::default()).ok();
        let mut frame = [0u8; MAX_FRAME_LEN];
        let n = encode(
            &HostMessage::Sensor(Echo::frame(EchoFrame { seq: 9, value: 1.0 })),
            &mut frame,
        )
        .unwrap();
        for &b in &frame[..n / 2] {
            assert!(d.decoder.push::<HostMessage>(b).is_none());
        }
    });
    let mut hil = LockStep::<Echo>::start(EchoParams::default(), options(&pty.path))
        .expect("the late safe answer must not be taken for Configured");
    hil.step(&EchoFrame { seq: 1, value: 2.0 }).expect("step");
    hil.finish().expect("clean end");
    assert_eq!(
        device.join().unwrap().link_timeouts,
        1,
        "the flushed partial frame"
    );
}

#[test]
fn an_explicit_budget_applies_to_a_board_in_cycles() {
    let pty = pty();
    let _device = Device::<Echo>::serve(pty.master.try_clone().unwrap());
    let opts = HilOptions {
        instruction_budget: StepBudget::Instructions(1000),
        ..options(&pty.path)
    };
    let mut hil = LockStep::<Echo>::start(EchoParams::default(), opts).expect("start");
    let err = hil.step(&EchoFrame { seq: 1, value: 2.0 }).unwrap_err();
    assert!(err.to_string().contains("1234"), "{err}");
}

#[test]
fn a_missing_port_is_an_error_that_names_it() {
    let err = LockStep::<Echo>::start(
        EchoParams::default(),
        options(std::path::Path::new("/dev/ttyACM-dexter-none")),
    )
    .err()
    .expect("no such port");
    let msg = err.to_string();
    assert!(msg.contains("/dev/ttyACM-dexter-none"), "{msg}");
    assert!(msg.contains("plugged in"), "{msg}");
}

#[test]
fn a_silent_board_times_out_with_the_port_in_the_message() {
    let pty = pty(); // nobody serves the master end
    let opts = HilOptions {
        timeout: Duration::from_millis(300),
        ..options(&pty.path)
    };
    let err = LockStep::<Echo>::start(EchoParams::default(), opts)
        .err()
        .expect("no answer to Configure");
    let msg = err.to_string();
    assert!(
        msg.contains("timeout") && msg.contains(&*pty.path.to_string_lossy()),
        "{msg}"
    );
}
