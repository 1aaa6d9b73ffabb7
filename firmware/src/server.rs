//! The protocol server: the firmware's main loop, generic over the plant link
//! (`embedded_io::{Read, Write}`) and the [`StepTimer`], for every hosted controller kind
//! ([`Hosted`]).
//!
//! In lock-step the host owns time: it sends one [`HostMessage::Sensor`] frame per control
//! period and waits for the answer, so "fixed rate" means one control step per received
//! frame, and the link clock is the frame stream itself: every frame delimiter the
//! firmware receives is one control period. A period whose frame is rejected (CRC,
//! framing, overlong, payload) is a period without a valid frame; after
//! [`LOCKSTEP_TIMEOUT_PERIODS`] such periods the firmware answers with the configured
//! controller's safe command, `safe(seq, Fault::LinkTimeout)`, where `seq` continues the
//! last valid sequence number. A rejected frame's bytes never reach the controller.
//!
//! Every non-empty frame gets exactly one answer (until the timeout is reached), which lets
//! the host predict the answers from the bytes it sent:
//!
//! | frame | answer |
//! | --- | --- |
//! | `Configure` | `Configured { kind, ok }`, or `Rejected(NotHosted)` |
//! | `Sensor` of the configured kind | `Output` (the control step) |
//! | `Sensor` of another kind | `Rejected(WrongKind)`; the controller is not stepped |
//! | `Sensor` before any accepted `Configure` | `Rejected(NotConfigured)` |
//! | rejected by the link, controller configured | `Output` with the safe command |
//! | rejected by the link, none configured | `Rejected(Undecodable)` |
//! | `Stop` | `Stopped` (steps, stack high-water), then the run ends |
//!
//! A free-running board (no host in lock-step) instead steps on its own timer and counts
//! the link timeout in timer periods ([`FreeRunning`]); see firmware/README.md.
//!
//! Nothing here panics on any input: reads are bounded by the buffer, and writes go through
//! [`write_all`], which turns a link that stops accepting bytes into [`Exit::LinkFailed`].

use crate::board::StepTimer;
use crate::hosted::{Hosted, Params};
use dexter_core::fixed_rate::{Fault, Telemetry};
use dexter_core::protocol::{
    decode_exact, Command, DecodeError, DeviceMessage, Frame, FrameDecoder, HostMessageOf,
    HostVariant, HostedKinds, Kind, Partial, Rejection, RunSummary, MAX_FRAME_LEN,
};

/// A host message as this image decodes it: the wire form of
/// [`dexter_core::protocol::HostMessage`], with `Configure` decoded for the hosted kinds
/// only (a kind the image leaves out costs it no parameter decoder; it is answered
/// `NotHosted`).
pub type HostMessage = HostMessageOf<Partial<Params>, Frame>;

/// Control periods without a valid frame after which the firmware answers with the safe
/// command (lock-step: one period per received frame).
pub const LOCKSTEP_TIMEOUT_PERIODS: u32 = 1;
/// Bytes read from the link at a time.
const READ_CHUNK: usize = 64;

/// How a server run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum Exit {
    /// The host sent [`HostMessage::Stop`].
    Stop,
    /// The host closed the link.
    EndOfStream,
    /// The link reported an error, or accepted no more bytes.
    LinkFailed,
}

/// Figures a run reports at its end.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, defmt::Format)]
pub struct RunStats {
    /// Control steps run.
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

/// Write all of `bytes`; a link that accepts nothing (`Ok(0)`) or fails is an error. Never
/// panics (embedded-io's `write_all` panics on `Ok(0)`).
pub fn write_all<L: embedded_io::Write>(link: &mut L, mut bytes: &[u8]) -> Result<(), Exit> {
    while !bytes.is_empty() {
        match link.write(bytes) {
            Ok(n) if n > 0 => bytes = bytes.get(n..).unwrap_or(&[]),
            _ => return Err(Exit::LinkFailed),
        }
    }
    Ok(())
}

/// What a board does when a host's `Configure` is accepted: the NUCLEO-F446RE ends its
/// stand-alone juggling loop there (a valid decoded `Configure`, not any byte or a UART
/// error, starts a host session). `()` does nothing (the QEMU image).
pub trait SessionHook {
    /// A `Configure` of `kind` was accepted; called before the answer is sent.
    fn configured(&mut self, kind: Kind);
}

impl SessionHook for () {
    #[inline(always)]
    fn configured(&mut self, _: Kind) {}
}

/// Where the server decodes what the host sends: each message into its own slot, so that
/// no message is moved after it is decoded (a [`HostMessage`] is as large as the largest
/// parameter set; a sensor frame is a fraction of it).
struct Inbox {
    /// The last `Configure`'s parameters.
    config: Partial<Params>,
    /// The last `Sensor` frame.
    frame: Frame,
}

impl Inbox {
    /// Decode a frame's payload into its slot; which message it was.
    fn decode(&mut self, payload: &[u8]) -> Result<HostVariant, DecodeError> {
        let (variant, body) = HostVariant::split(payload)?;
        match variant {
            HostVariant::Sensor => self.frame.decode_from(body)?,
            HostVariant::Configure => self.decode_config(body)?,
            HostVariant::Stop if body.is_empty() => {}
            HostVariant::Stop => return Err(DecodeError::Payload),
        }
        Ok(variant)
    }

    /// `Configure`'s parameters, out of line: it is rare, and its decoder is large.
    #[inline(never)]
    fn decode_config(&mut self, body: &[u8]) -> Result<(), DecodeError> {
        self.config = decode_exact(body)?;
        Ok(())
    }
}

/// The server state.
pub struct Server<L, T, H = ()> {
    link: L,
    timer: T,
    hook: H,
    decoder: FrameDecoder<MAX_FRAME_LEN>,
    inbox: Inbox,
    controller: Option<Hosted>,
    last_seq: u32,
    missed: u32,
    stats: RunStats,
    /// The answer being sent (kept here so it is not zeroed on every send).
    tx: [u8; MAX_FRAME_LEN],
}

impl<L, T> Server<L, T>
where
    L: embedded_io::Read + embedded_io::Write,
    T: StepTimer,
{
    /// A server on `link`, unconfigured until the host sends [`HostMessage::Configure`].
    pub fn new(link: L, timer: T) -> Self {
        Self::with_hook(link, timer, ())
    }
}

impl<L, T, H> Server<L, T, H>
where
    L: embedded_io::Read + embedded_io::Write,
    T: StepTimer,
    H: SessionHook,
{
    /// [`Server::new`], calling `hook` at each accepted `Configure`.
    pub fn with_hook(link: L, timer: T, hook: H) -> Self {
        Self {
            link,
            timer,
            hook,
            decoder: FrameDecoder::new(),
            inbox: Inbox {
                config: Partial::NotHosted(Kind::Line),
                frame: Frame::Line(Default::default()),
            },
            controller: None,
            last_seq: 0,
            missed: 0,
            tx: [0; MAX_FRAME_LEN],
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

    /// Serve in lock-step until the host stops the run or the link ends.
    pub fn run(&mut self) -> Exit {
        let mut buf = [0u8; READ_CHUNK];
        loop {
            let n = match self.link.read(&mut buf) {
                Ok(0) => return Exit::EndOfStream,
                Ok(n) => n,
                Err(_) => return Exit::LinkFailed,
            };
            let mut bytes = buf.get(..n).unwrap_or(&[]);
            while !bytes.is_empty() {
                let (used, received) = self.receive(bytes);
                bytes = bytes.get(used..).unwrap_or(&[]);
                if let Some(exit) = received.and_then(|r| self.handle(r)) {
                    return exit;
                }
            }
        }
    }

    /// Feed `bytes` to the decoder up to the first frame's end: the bytes used and, if a
    /// frame ended, which message it was (decoded into the inbox) or why it was rejected.
    #[inline(never)] // not part of `run`, the wait for a frame (scripts/hil-guest-count.sh)
    fn receive(&mut self, bytes: &[u8]) -> (usize, Option<Result<HostVariant, DecodeError>>) {
        let inbox = &mut self.inbox;
        self.decoder.feed(bytes, |payload| inbox.decode(payload))
    }

    /// Answer one frame (see the table in the module docs).
    #[inline(never)] // not part of `run`, the wait for a frame (scripts/hil-guest-count.sh)
    fn handle(&mut self, received: Result<HostVariant, DecodeError>) -> Option<Exit> {
        match received {
            Ok(HostVariant::Configure) => self.configure(),
            Ok(HostVariant::Sensor) => match self.check_kind(&self.inbox.frame) {
                Ok(()) => self.step(),
                Err(rejection) => self.send(&DeviceMessage::Rejected(rejection)),
            },
            Ok(HostVariant::Stop) => self.stop(),
            Err(e) => self.period_without_frame(e),
        }
    }

    fn configure(&mut self) -> Option<Exit> {
        // A refused configuration leaves no controller: the host asked for another one.
        self.controller = None;
        let params = match &self.inbox.config {
            Partial::Hosted(params) => params,
            Partial::NotHosted(kind) => {
                defmt::warn!("controller kind {} is not hosted by this image", kind);
                return self.send(&DeviceMessage::Rejected(Rejection::NotHosted(*kind)));
            }
        };
        let kind = params.kind();
        let answer = match Hosted::configure(params) {
            Err(e) => {
                defmt::warn!("configuration of {} rejected: {}", kind, e);
                DeviceMessage::Configured { kind, ok: false }
            }
            Ok(controller) => {
                defmt::info!("configured: {}", kind);
                self.hook.configured(kind);
                self.controller = Some(controller);
                self.missed = 0;
                DeviceMessage::Configured { kind, ok: true }
            }
        };
        self.send(&answer)
    }

    /// Whether `frame` can be stepped: a controller of its kind is configured.
    fn check_kind(&self, frame: &Frame) -> Result<(), Rejection> {
        match &self.controller {
            None => Err(Rejection::NotConfigured),
            Some(c) if c.kind() != frame.kind() => Err(Rejection::WrongKind {
                configured: c.kind(),
                received: frame.kind(),
            }),
            Some(_) => Ok(()),
        }
    }

    /// One control step on the inbox's frame, of the configured kind, answered with its
    /// command.
    fn step(&mut self) -> Option<Exit> {
        let controller = self.controller.as_mut()?;
        let (command, instructions) = controller.step(&self.inbox.frame, &self.timer).ok()?;
        self.last_seq = command.reply().0;
        self.missed = 0;
        self.record(instructions);
        self.output(command, instructions)
    }

    /// A period whose frame the link rejected: the safe command after the timeout.
    fn period_without_frame(&mut self, e: DecodeError) -> Option<Exit> {
        defmt::debug!("frame rejected: {}", e);
        let Some(controller) = self.controller.as_mut() else {
            return self.send(&DeviceMessage::Rejected(Rejection::Undecodable(e)));
        };
        self.missed = self.missed.saturating_add(1);
        if self.missed < LOCKSTEP_TIMEOUT_PERIODS {
            return None;
        }
        let seq = self.last_seq.wrapping_add(self.missed);
        let (command, instructions) = controller.safe(seq, Fault::LinkTimeout, &self.timer);
        self.stats.link_timeouts = self.stats.link_timeouts.saturating_add(1);
        self.output(command, instructions)
    }

    /// Answer `Stop` with the run's summary and end the run.
    fn stop(&mut self) -> Option<Exit> {
        let stack = crate::stack::usage();
        let summary = RunSummary {
            steps: self.stats.steps,
            link_timeouts: self.stats.link_timeouts,
            stack_used_bytes: stack.used_bytes,
            stack_size_bytes: stack.size_bytes,
        };
        defmt::info!(
            "stopped after {=u32} steps; stack high-water {=u32} of {=u32} bytes",
            summary.steps,
            summary.stack_used_bytes,
            summary.stack_size_bytes
        );
        Some(
            self.send(&DeviceMessage::Stopped(summary))
                .unwrap_or(Exit::Stop),
        )
    }

    fn record(&mut self, instructions: u32) {
        let s = &mut self.stats;
        s.steps = s.steps.saturating_add(1);
        s.step_instructions_min = s.step_instructions_min.min(instructions);
        s.step_instructions_max = s.step_instructions_max.max(instructions);
        s.step_instructions_sum = s
            .step_instructions_sum
            .saturating_add(u64::from(instructions));
    }

    fn output(&mut self, command: Command, instructions: u32) -> Option<Exit> {
        let link = self.decoder.stats();
        let telemetry = Telemetry {
            step_instructions: instructions,
            link_errors: link.errors(),
            frames_ok: link.frames_ok,
            ..self
                .controller
                .as_ref()
                .map(Hosted::telemetry)
                .unwrap_or_default()
        };
        self.send(&DeviceMessage::Output { command, telemetry })
    }

    fn send(&mut self, message: &DeviceMessage) -> Option<Exit> {
        let Ok(n) = message.encode(&mut self.tx) else {
            defmt::error!("reply does not fit a frame");
            return Some(Exit::LinkFailed);
        };
        write_all(&mut self.link, self.tx.get(..n).unwrap_or(&[])).err()
    }
}

/// Free-running fixed-rate mode, for a board with no host in lock-step: the firmware steps
/// every `period_ticks` of its own clock (`now` ticks, 24-bit down counter like SysTick)
/// with the latest sensor frame received in that period; the link timeout counts periods:
/// after `timeout_periods` periods without a valid sensor frame each period answers with
/// the safe command, `safe(seq, Fault::LinkTimeout)`. Frames are drained without blocking
/// (`embedded_io::ReadReady`), so a silent link never stalls the control loop. A frame of
/// the wrong kind is answered with `Rejected` at once and never stepped.
pub struct FreeRunning {
    /// Control period in clock ticks (SysTick on mps2-an386: 25 MHz, so 2 ms = 50 000).
    pub period_ticks: u32,
    /// Periods without a valid sensor frame before the safe state.
    pub timeout_periods: u32,
}

/// What the free-running loop carries from one period to the next.
struct Period {
    latest: Option<Frame>,
    missed: u32,
    start: u32,
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
        let mut period = Period {
            latest: None,
            missed: 0,
            start: clock(),
        };
        loop {
            if let Some(exit) = Self::drain(server, &mut period, &clock) {
                return exit;
            }
            if period.start.wrapping_sub(clock()) & MASK < self.period_ticks {
                continue;
            }
            period.start = period.start.wrapping_sub(self.period_ticks) & MASK;
            if let Some(exit) = self.tick(server, &mut period) {
                return exit;
            }
        }
    }

    /// Read what the link holds without blocking; keep the latest valid sensor frame.
    fn drain<L, T>(
        server: &mut Server<L, T>,
        period: &mut Period,
        clock: &impl Fn() -> u32,
    ) -> Option<Exit>
    where
        L: embedded_io::Read + embedded_io::ReadReady + embedded_io::Write,
        T: StepTimer,
    {
        let mut buf = [0u8; READ_CHUNK];
        while matches!(server.link.read_ready(), Ok(true)) {
            let n = match server.link.read(&mut buf) {
                Ok(0) => return Some(Exit::EndOfStream),
                Ok(n) => n,
                Err(_) => return Some(Exit::LinkFailed),
            };
            let mut bytes = buf.get(..n).unwrap_or(&[]);
            while !bytes.is_empty() {
                let (used, received) = server.receive(bytes);
                bytes = bytes.get(used..).unwrap_or(&[]);
                let exit = match received {
                    Some(Ok(HostVariant::Sensor)) => match server.check_kind(&server.inbox.frame) {
                        Ok(()) => {
                            period.latest = Some(server.inbox.frame);
                            None
                        }
                        Err(r) => server.send(&DeviceMessage::Rejected(r)),
                    },
                    Some(Ok(HostVariant::Stop)) => server.stop(),
                    Some(Ok(HostVariant::Configure)) => {
                        period.start = clock();
                        server.configure()
                    }
                    Some(Err(e)) => {
                        defmt::debug!("frame rejected: {}", e);
                        None
                    }
                    None => None,
                };
                if exit.is_some() {
                    return exit;
                }
            }
        }
        None
    }

    /// One control period: step the latest frame, or count a period without one.
    fn tick<L, T>(&self, server: &mut Server<L, T>, period: &mut Period) -> Option<Exit>
    where
        L: embedded_io::Read + embedded_io::ReadReady + embedded_io::Write,
        T: StepTimer,
    {
        match period.latest.take() {
            Some(frame) => {
                period.missed = 0;
                server.inbox.frame = frame;
                server.step()
            }
            None => {
                let controller = server.controller.as_mut()?;
                period.missed = period.missed.saturating_add(1);
                if period.missed < self.timeout_periods {
                    return None; // the actuator holds the last command
                }
                let seq = server.last_seq.wrapping_add(period.missed);
                server.stats.link_timeouts = server.stats.link_timeouts.saturating_add(1);
                let (command, instructions) =
                    controller.safe(seq, Fault::LinkTimeout, &server.timer);
                server.output(command, instructions)
            }
        }
    }
}
