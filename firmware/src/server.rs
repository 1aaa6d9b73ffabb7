//! The lock-step protocol server: the firmware's main loop, generic over the plant link
//! (`embedded_io::{Read, Write}`) and the [`StepTimer`].
//!
//! In lock-step the host owns time: it sends one [`HostMessage::Sensor`] frame per control
//! period and waits for the answer, so "fixed rate" means one control step per received
//! frame, and the link clock is the frame stream itself: every frame delimiter the
//! firmware receives is one control period. A period whose frame is rejected (CRC,
//! framing, overlong, payload) is a period without a valid frame; after
//! [`LOCKSTEP_TIMEOUT_PERIODS`] such periods the firmware answers with the core's safe
//! command, `Controller::safe(seq, Fault::LinkTimeout)`, where `seq` continues the last
//! valid sequence number. A rejected frame's bytes never reach the controller. Every
//! non-empty frame therefore gets exactly one answer (until the timeout is reached), which
//! lets the host predict the answers from the bytes it sent.
//!
//! A free-running board (no host in lock-step) instead steps on its own timer and counts
//! the link timeout in SysTick periods; see firmware/README.md.

use crate::board::StepTimer;
use dexter_core::control::Controller;
use dexter_core::protocol::{
    encode, ActuatorCommand, DecodeError, DeviceMessage, Fault, FrameDecoder, HostMessage,
    Telemetry, MAX_FRAME_LEN,
};

/// Control periods without a valid frame after which the firmware answers with the safe
/// command (lock-step: one period per received frame).
pub const LOCKSTEP_TIMEOUT_PERIODS: u32 = 1;

/// Measure `f` with interrupts masked, so a receive interrupt that lands inside the
/// window is not counted as part of the control step (it runs right after).
#[inline(always)]
fn measure_masked<T: StepTimer, R>(timer: &T, f: impl FnOnce() -> R) -> (R, u32) {
    cortex_m::interrupt::free(|_| timer.measure(f))
}

/// How a server run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum Exit {
    /// The host sent [`HostMessage::Stop`].
    Stop,
    /// The host closed the link.
    EndOfStream,
    /// The link reported an error.
    LinkFailed,
}

/// Figures a run reports at its end.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, defmt::Format)]
pub struct RunStats {
    /// Control steps (`Controller::step`) run.
    pub steps: u32,
    /// Safe commands sent because of a link timeout.
    pub link_timeouts: u32,
    /// Fewest instructions of one control step.
    pub step_instructions_min: u32,
    /// Most instructions of one control step.
    pub step_instructions_max: u32,
    /// Sum of the instructions of all control steps (for the mean).
    pub step_instructions_sum: u64,
}

/// The lock-step server state.
pub struct Server<L, T> {
    link: L,
    timer: T,
    decoder: FrameDecoder<MAX_FRAME_LEN>,
    controller: Option<Controller>,
    last_seq: u32,
    missed: u32,
    stats: RunStats,
}

impl<L, T> Server<L, T>
where
    L: embedded_io::Read + embedded_io::Write,
    T: StepTimer,
{
    /// A server on `link`, unconfigured until the host sends [`HostMessage::Configure`].
    pub fn new(link: L, timer: T) -> Self {
        Self {
            link,
            timer,
            decoder: FrameDecoder::new(),
            controller: None,
            last_seq: 0,
            missed: 0,
            stats: RunStats {
                step_instructions_min: u32::MAX,
                ..RunStats::default()
            },
        }
    }

    /// Figures so far.
    pub fn stats(&self) -> RunStats {
        self.stats
    }

    /// Serve until the host stops the run or the link ends.
    pub fn run(&mut self) -> Exit {
        let mut buf = [0u8; 64];
        loop {
            let n = match self.link.read(&mut buf) {
                Ok(0) => return Exit::EndOfStream,
                Ok(n) => n,
                Err(_) => return Exit::LinkFailed,
            };
            for &byte in &buf[..n] {
                if let Some(result) = self.decoder.push::<HostMessage>(byte) {
                    if let Some(exit) = self.handle(result) {
                        return exit;
                    }
                }
            }
        }
    }

    fn handle(&mut self, result: Result<HostMessage, DecodeError>) -> Option<Exit> {
        match result {
            Ok(HostMessage::Configure(params)) => {
                let ok = match Controller::new(params) {
                    Ok(c) => {
                        defmt::info!(
                            "configured: dt_s={=f32} target_apex_m={=f32}",
                            params.dt_s,
                            params.target_apex_m
                        );
                        self.controller = Some(c);
                        self.missed = 0;
                        true
                    }
                    Err(e) => {
                        defmt::warn!("configuration rejected: {}", e);
                        false
                    }
                };
                self.send(&DeviceMessage::Configured { ok })
            }
            Ok(HostMessage::Sensor(frame)) => {
                let Some(controller) = self.controller.as_mut() else {
                    defmt::warn!(
                        "sensor frame {=u32} before configuration: ignored",
                        frame.seq
                    );
                    return None;
                };
                let (command, instructions) =
                    measure_masked(&self.timer, || controller.step(&frame));
                self.last_seq = frame.seq;
                self.missed = 0;
                self.record(instructions);
                self.output(command, instructions)
            }
            Ok(HostMessage::Stop) => Some(Exit::Stop),
            Err(e) => {
                defmt::debug!("frame rejected: {}", e);
                self.missed = self.missed.saturating_add(1);
                if self.missed < LOCKSTEP_TIMEOUT_PERIODS {
                    return None;
                }
                let seq = self.last_seq.wrapping_add(self.missed);
                let controller = self.controller.as_mut()?;
                let (command, instructions) =
                    measure_masked(&self.timer, || controller.safe(seq, Fault::LinkTimeout));
                self.stats.link_timeouts = self.stats.link_timeouts.saturating_add(1);
                self.output(command, instructions)
            }
        }
    }

    fn record(&mut self, instructions: u32) {
        let s = &mut self.stats;
        s.steps = s.steps.saturating_add(1);
        s.step_instructions_min = s.step_instructions_min.min(instructions);
        s.step_instructions_max = s.step_instructions_max.max(instructions);
        s.step_instructions_sum += u64::from(instructions);
    }

    fn output(&mut self, command: ActuatorCommand, instructions: u32) -> Option<Exit> {
        let link = self.decoder.stats();
        let telemetry = Telemetry {
            step_instructions: instructions,
            link_errors: link.errors(),
            frames_ok: link.frames_ok,
            ..self
                .controller
                .as_ref()
                .map(Controller::telemetry)
                .unwrap_or_default()
        };
        self.send(&DeviceMessage::Output { command, telemetry })
    }

    fn send(&mut self, message: &DeviceMessage) -> Option<Exit> {
        let mut out = [0u8; MAX_FRAME_LEN];
        let Ok(n) = encode(message, &mut out) else {
            defmt::error!("reply does not fit a frame");
            return Some(Exit::LinkFailed);
        };
        match self.link.write_all(&out[..n]) {
            Ok(()) => None,
            Err(_) => Some(Exit::LinkFailed),
        }
    }
}

/// Free-running fixed-rate mode, for a board with no host in lock-step: the firmware steps
/// every `period_ticks` of its own clock (`now` ticks, 24-bit down counter like SysTick)
/// with the latest sensor frame received in that period; the link timeout counts periods:
/// after `timeout_periods` periods without a valid sensor frame each period answers with
/// `Controller::safe(seq, Fault::LinkTimeout)`. Frames are drained without blocking
/// (`embedded_io::ReadReady`), so a silent link never stalls the control loop.
pub struct FreeRunning {
    /// Control period in clock ticks (SysTick on mps2-an386: 25 MHz, so 2 ms = 50 000).
    pub period_ticks: u32,
    /// Periods without a valid sensor frame before the safe state.
    pub timeout_periods: u32,
}

impl FreeRunning {
    /// Serve until [`HostMessage::Stop`] or a link error. `clock` returns raw ticks of a
    /// down counter masked to 24 bits (SysTick).
    pub fn run<L, T>(&self, server: &mut Server<L, T>, clock: impl Fn() -> u32) -> Exit
    where
        L: embedded_io::Read + embedded_io::ReadReady + embedded_io::Write,
        T: StepTimer,
    {
        const MASK: u32 = 0x00ff_ffff;
        let mut latest = None;
        let mut missed = 0u32;
        let mut period_start = clock();
        let mut buf = [0u8; 64];
        loop {
            while matches!(server.link.read_ready(), Ok(true)) {
                let n = match server.link.read(&mut buf) {
                    Ok(0) => return Exit::EndOfStream,
                    Ok(n) => n,
                    Err(_) => return Exit::LinkFailed,
                };
                for &byte in &buf[..n] {
                    match server.decoder.push::<HostMessage>(byte) {
                        Some(Ok(HostMessage::Sensor(frame))) => latest = Some(frame),
                        Some(Ok(HostMessage::Stop)) => return Exit::Stop,
                        Some(Ok(other)) => {
                            if let Some(exit) = server.handle(Ok(other)) {
                                return exit;
                            }
                            period_start = clock();
                        }
                        Some(Err(e)) => defmt::debug!("frame rejected: {}", e),
                        None => {}
                    }
                }
            }
            if period_start.wrapping_sub(clock()) & MASK < self.period_ticks {
                continue;
            }
            period_start = period_start.wrapping_sub(self.period_ticks) & MASK;
            let Some(controller) = server.controller.as_mut() else {
                continue;
            };
            let (command, instructions) = match latest.take() {
                Some(frame) => {
                    missed = 0;
                    server.last_seq = frame.seq;
                    let r = measure_masked(&server.timer, || controller.step(&frame));
                    server.record(r.1);
                    r
                }
                None => {
                    missed = missed.saturating_add(1);
                    if missed < self.timeout_periods {
                        continue; // the actuator holds the last command
                    }
                    let seq = server.last_seq.wrapping_add(missed);
                    server.stats.link_timeouts = server.stats.link_timeouts.saturating_add(1);
                    measure_masked(&server.timer, || controller.safe(seq, Fault::LinkTimeout))
                }
            };
            if let Some(exit) = server.output(command, instructions) {
                return exit;
            }
        }
    }
}
