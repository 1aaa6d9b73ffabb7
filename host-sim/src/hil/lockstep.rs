//! [`LockStep`]: the firmware in QEMU, or on a board on a serial port, as a
//! [`StepController`] of any controller kind.

use super::inject::{Injector, Segment};
use super::link::{prepare, Link, Peer, Received};
use super::qemu::{check_qemu, decode_defmt_log, link_err, resolve_firmware, Qemu, WorkDir};
use super::report::{Counters, LinkCounts};
use super::{HilOptions, StepBudget, LOCKSTEP_TIMEOUT_PERIODS};
use crate::controller::{ControllerError, HilReport, StepController, StepOutput};
use dexter_core::control::Controller;
use dexter_core::fixed_rate::{Fault, Reply};
use dexter_core::protocol::{
    encode, DeviceMessage, FrameDecoder, HostMessage, Rejection, RunSummary, Wire, MAX_FRAME_LEN,
};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How long one wait for bytes lasts before checking that QEMU still runs.
const WAIT_SLICE: Duration = Duration::from_millis(50);

/// The answer a wait is for (formatted only into an error: no allocation per frame).
#[derive(Clone, Copy, Debug)]
enum Awaited {
    Configured,
    Output(u32),
    Stopped,
}

impl std::fmt::Display for Awaited {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Awaited::Configured => f.write_str("the answer to Configure"),
            Awaited::Output(seq) => write!(f, "the answer to frame {seq}"),
            Awaited::Stopped => f.write_str("the answer to Stop"),
        }
    }
}

/// The firmware in QEMU, stepped in lock-step with the plant, running a controller of kind
/// `C` and checked against a shadow `C` on the host, bit for bit.
pub struct LockStep<C: Wire = Controller> {
    peer: Peer,
    link: Link,
    /// The ELF QEMU runs (absolute).
    elf: PathBuf,
    replies: VecDeque<DeviceMessage>,
    reply_decoder: FrameDecoder<MAX_FRAME_LEN>,
    inject: Injector,
    /// Segments completed by the bytes of the current step (reused, no allocation).
    segments: Vec<Segment>,
    /// Last sequence number the firmware answered, and periods missed since.
    last_seq: u32,
    missed: u32,
    shadow: C,
    budget: Option<u32>,
    opts: HilOptions,
    counters: Counters,
    last_output: Option<StepOutput<C::Command>>,
    first_mismatch: Option<String>,
}

/// Boot QEMU with the link's host end ready, and connect; or open the board's serial port.
fn boot(elf: &std::path::Path, opts: &HilOptions) -> Result<(Peer, Link), ControllerError> {
    if let Some(port) = &opts.serial {
        let link = Link::serial(port, opts.timeout)?;
        return Ok((Peer::Board(port.clone()), link));
    }
    check_qemu()?;
    let workdir = WorkDir::create()?;
    let (pending, link_args) = prepare(opts.link, &workdir)?;
    let mut qemu = Qemu::spawn(elf, opts.link, workdir, &link_args)?;
    let link = Link::connect(pending, &mut qemu, opts.timeout)?; // QEMU is killed on error
    Ok((Peer::Qemu(qemu), link))
}

impl<C: Wire> LockStep<C> {
    /// Boot the firmware in QEMU, configure it with `params` (controller kind `C`) and wait
    /// for its answer (the one untimed round trip before any timing). The error says what
    /// failed: invalid parameters (before QEMU starts), a missing ELF or emulator, a
    /// firmware that does not host `C`, or a timeout.
    pub fn start(params: C::Params, opts: HilOptions) -> Result<Self, ControllerError> {
        let shadow = C::new(params).map_err(ControllerError::Params)?;
        if !(0.0..=1.0).contains(&opts.corrupt_rate) {
            return Err(link_err(format!(
                "corrupt_rate must be within [0, 1], got {}",
                opts.corrupt_rate
            )));
        }
        // A board runs the firmware it was flashed with: no ELF to find.
        let elf = match opts.serial {
            Some(_) => opts.firmware_elf.clone(),
            None => resolve_firmware(&opts.firmware_elf)?,
        };
        let (peer, link) = boot(&elf, &opts)?;
        // A board reports DWT cycles, not instructions: the controller's instruction budget
        // does not apply to them (an explicit budget does, in cycles).
        let budget = match (&opts.serial, opts.instruction_budget) {
            (Some(_), StepBudget::OfController) => None,
            (_, budget) => budget.limit(C::STEP_INSTRUCTION_BUDGET),
        };
        let mut hil = LockStep {
            peer,
            link,
            elf,
            replies: VecDeque::with_capacity(16),
            reply_decoder: FrameDecoder::new(),
            inject: Injector::new(opts.corrupt_rate),
            segments: Vec::with_capacity(MAX_FRAME_LEN),
            last_seq: 0,
            missed: 0,
            shadow,
            budget,
            opts,
            counters: Counters::default(),
            last_output: None,
            first_mismatch: None,
        };
        hil.configure(params)?;
        Ok(hil)
    }

    fn configure(&mut self, params: C::Params) -> Result<(), ControllerError> {
        self.send_clean(&HostMessage::Configure(C::config(params)))?;
        let kind = C::KIND;
        match self.next_message(Awaited::Configured)? {
            DeviceMessage::Configured { kind: k, ok: true } if k == kind => Ok(()),
            DeviceMessage::Configured { ok: false, .. } => Err(link_err(format!(
                "the firmware rejected the {kind:?} controller's parameters \
                 (the host accepted them: is the firmware built from this source?)"
            ))),
            DeviceMessage::Rejected(Rejection::NotHosted(_)) => Err(link_err(format!(
                "this firmware image does not host the {kind:?} controller: its cargo \
                 features select the hosted kinds (firmware/README.md, \"Images\"; the \
                 arm's image: `--no-default-features --features arm`, the spatial \
                 juggler's: `--features spatial`)"
            ))),
            DeviceMessage::Rejected(Rejection::Undecodable(e)) => Err(link_err(format!(
                "the firmware could not decode Configure for the {kind:?} controller ({e}): \
                 it was built from another protocol version; rebuild it with `cargo fw-build`"
            ))),
            other => Err(link_err(format!(
                "expected the firmware's Configured answer for {kind:?}, got {other:?}"
            ))),
        }
    }

    /// Send a message without fault injection; a partial frame the firmware holds is
    /// flushed first (and its safe answer checked).
    fn send_clean(&mut self, message: &HostMessage) -> Result<(), ControllerError> {
        if self.inject.has_partial_frame() {
            self.write(&[0])?;
            self.inject.segments(&[0], &[], |_| {});
            self.answer(Segment::Corrupt, None)?;
        }
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode(message, &mut buf)
            .map_err(|e| link_err(format!("cannot encode {message:?}: {e:?}")))?;
        self.counters.link.host_intact += 1;
        self.write(&buf[..n])
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), ControllerError> {
        self.link.write_all(bytes).map_err(|e| {
            self.peer
                .dead_or(format!("writing to the firmware failed: {e}"))
        })
    }

    /// The next message from the firmware, waiting up to the timeout.
    fn next_message(&mut self, waiting_for: Awaited) -> Result<DeviceMessage, ControllerError> {
        let deadline = Instant::now() + self.opts.timeout;
        loop {
            if let Some(m) = self.replies.pop_front() {
                return Ok(m);
            }
            self.pump(deadline, waiting_for)?;
        }
    }

    /// Receive bytes until some arrive or `deadline`, decoding answers into `replies`.
    fn pump(&mut self, deadline: Instant, waiting_for: Awaited) -> Result<(), ControllerError> {
        loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.link.receive(left.min(WAIT_SLICE)) {
                Ok(Received::Bytes(bytes)) => {
                    for &b in bytes {
                        match self.reply_decoder.push::<DeviceMessage>(b) {
                            Some(Ok(m)) => self.replies.push_back(m),
                            Some(Err(_)) => self.counters.host_link_errors += 1,
                            None => {}
                        }
                    }
                    return Ok(());
                }
                Ok(Received::Nothing) if self.peer.exited().is_some() => {
                    return Err(self.peer.dead_or(format!(
                        "the firmware stopped while waiting for {waiting_for}"
                    )))
                }
                Ok(Received::Nothing) if left.is_zero() => {
                    let peer = self.peer.describe(self.opts.link);
                    return Err(self.peer.dead_or(format!(
                        "timeout: no answer from the firmware within {:?} while waiting for \
                         {waiting_for} ({peer})",
                        self.opts.timeout
                    )));
                }
                Ok(Received::Nothing) => {}
                Err(e) => {
                    return Err(self
                        .peer
                        .dead_or(format!("{e} while waiting for {waiting_for}")))
                }
            }
        }
    }

    /// The firmware's `Output` answering sequence number `seq`.
    fn next_output(&mut self, seq: u32) -> Result<StepOutput<C::Command>, ControllerError> {
        match self.next_message(Awaited::Output(seq))? {
            DeviceMessage::Output { command, telemetry } => match C::command_of(&command) {
                Some(command) => Ok(StepOutput { command, telemetry }),
                None => Err(link_err(format!(
                    "the firmware answered frame {seq} with a {:?} command, not {:?}",
                    command.kind(),
                    C::KIND
                ))),
            },
            DeviceMessage::Rejected(r) => {
                Err(link_err(format!("the firmware refused frame {seq}: {r:?}")))
            }
            other => Err(link_err(format!(
                "expected an Output answer for frame {seq}, got {other:?}"
            ))),
        }
    }

    /// The answer to one segment the firmware delimited: the control step of `frame` if it
    /// is intact, else (after the timeout) the safe command. `None` if no answer is due.
    fn answer(
        &mut self,
        segment: Segment,
        frame: Option<&C::Frame>,
    ) -> Result<Option<StepOutput<C::Command>>, ControllerError> {
        let expected = match (segment, frame) {
            (Segment::Intact, Some(frame)) => {
                self.counters.link.host_intact += 1;
                let command = self.shadow.step(frame);
                self.last_seq = command.seq();
                self.missed = 0;
                command
            }
            _ => {
                self.counters.link.host_corrupt += 1;
                self.missed = self.missed.saturating_add(1);
                if self.missed < LOCKSTEP_TIMEOUT_PERIODS {
                    return Ok(None);
                }
                let seq = self.last_seq.wrapping_add(self.missed);
                self.shadow.safe(seq, Fault::LinkTimeout)
            }
        };
        let got = self.next_output(expected.seq())?;
        self.check(&expected, &got)?;
        Ok(Some(got))
    }

    /// Record one firmware answer against the shadow's command and the host's link counts.
    fn check(
        &mut self,
        expected: &C::Command,
        got: &StepOutput<C::Command>,
    ) -> Result<(), ControllerError> {
        let instructions = got.telemetry.step_instructions;
        self.counters.record_instructions(instructions);
        if got.command.fault() == Fault::LinkTimeout {
            self.counters.link_timeouts += 1;
        }
        if !self.counters.record_link_counts(&got.telemetry) {
            let l = self.counters.link;
            self.note_mismatch(format!(
                "at seq {}: the firmware counts {} frames accepted and {} rejected, \
                 the host sent {} intact and {} corrupt",
                got.command.seq(),
                l.device_accepted,
                l.device_rejected,
                l.host_intact,
                l.host_corrupt
            ));
        }
        if !expected.bit_identical(&got.command) {
            self.counters.sil_mismatches += 1;
            let (fw, sil) = (C::command(got.command), C::command(*expected));
            self.note_mismatch(format!("firmware {fw:?} vs SIL {sil:?}"));
        }
        match self.budget {
            Some(budget) if instructions > budget => {
                self.counters.over_budget_steps += 1;
                Err(link_err(format!(
                    "control step for seq {} took {instructions} instructions on the target, \
                     over the budget of {budget}",
                    got.command.seq()
                )))
            }
            _ => Ok(()),
        }
    }

    fn note_mismatch(&mut self, what: String) {
        self.first_mismatch.get_or_insert(what);
    }

    /// The first disagreement between the firmware and the host (a command that differs
    /// from the shadow's, or link counts that differ from the host's), described.
    pub fn first_mismatch(&self) -> Option<&str> {
        self.first_mismatch.as_deref()
    }

    /// Corrupted frames the firmware accepted (expected 0): see [`LinkCounts`].
    pub fn corrupted_frames_accepted(&self) -> u64 {
        self.counters.link.corrupted_accepted
    }

    /// Steps for which no frame delimiter reached the firmware (the previous command was
    /// held).
    pub fn unanswered_steps(&self) -> u64 {
        self.counters.link.unanswered_steps
    }

    /// The link's frame counts on both ends.
    pub fn link_counts(&self) -> LinkCounts {
        self.counters.link
    }

    /// Times the firmware found no frame for a while, slept on the semihosting link's
    /// doorbell and was rung awake (`hil::semihosting`); 0 on the UART and a board.
    pub fn doorbell_rings(&self) -> u64 {
        self.link.doorbell_rings()
    }

    /// The raw defmt log so far (semihosting stdout); decode with the firmware ELF. Empty
    /// for a board (it logs over RTT: probe-rs prints it).
    pub fn firmware_log(&self) -> Vec<u8> {
        self.peer.log()
    }

    /// The firmware log so far, decoded (see [`decode_defmt_log`]); empty for a board.
    pub fn firmware_log_text(&self) -> Result<String, ControllerError> {
        match self.peer {
            Peer::Board(_) => Ok(String::new()),
            Peer::Qemu(_) => decode_defmt_log(&self.elf, &self.firmware_log()),
        }
    }

    /// Process id of the QEMU instance (it is killed when the `LockStep` is dropped); 0
    /// for a board on a serial port.
    pub fn qemu_pid(&self) -> u32 {
        self.peer.pid()
    }

    /// The options this run uses.
    pub fn options(&self) -> &HilOptions {
        &self.opts
    }

    /// The instruction budget each step is held to (`None`: unchecked).
    pub fn instruction_budget(&self) -> Option<u32> {
        self.budget
    }

    /// Stop the firmware (`HostMessage::Stop`), wait for QEMU to exit and return the
    /// report; an exit status other than success (a panic or HardFault) is an error.
    pub fn finish(self) -> Result<HilReport, ControllerError> {
        self.finish_with_summary().map(|(report, _)| report)
    }

    /// [`finish`](Self::finish), with what the firmware reports at its end: its step
    /// count and its stack high-water mark.
    pub fn finish_with_summary(mut self) -> Result<(HilReport, RunSummary), ControllerError> {
        self.send_clean(&HostMessage::Stop)?;
        let summary = loop {
            match self.next_message(Awaited::Stopped)? {
                DeviceMessage::Stopped(summary) => break summary,
                DeviceMessage::Output { .. } => {} // an answer to a flushed partial frame
                other => {
                    return Err(link_err(format!(
                        "expected the firmware's Stopped answer, got {other:?}"
                    )))
                }
            }
        };
        self.peer.wait_success(self.opts.timeout)?;
        Ok((self.counters.report(), summary))
    }
}

impl<C: Wire> LockStep<C> {
    /// Send `frame` (through the fault injector if `corrupt`) and take the firmware's
    /// answers to the segments it completes: the answer to the intact frame, else the last
    /// answer (a safe command), else `None` (no delimiter reached the firmware).
    fn send_frame(
        &mut self,
        frame: &C::Frame,
        corrupt: bool,
    ) -> Result<Option<StepOutput<C::Command>>, ControllerError> {
        let mut buf = [0u8; MAX_FRAME_LEN + 1];
        let n = encode(&HostMessage::Sensor(C::frame(*frame)), &mut buf)
            .map_err(|e| link_err(format!("cannot encode a {:?} frame: {e:?}", C::KIND)))?;
        buf[n] = 0; // flush delimiter: ends a partial frame left by a lost delimiter
        let mut out = [0u8; MAX_FRAME_LEN + 1];
        let sent = match corrupt {
            true => self.inject.corrupt(&buf[..=n], &mut out),
            false => &buf[..=n],
        };
        let mut segments = std::mem::take(&mut self.segments);
        segments.clear();
        self.inject
            .segments(sent, &buf[..n - 1], |s| segments.push(s));
        self.write(sent)?;
        let mut answer = None;
        let mut last = None;
        for &segment in &segments {
            let intact = segment == Segment::Intact;
            if let Some(got) = self.answer(segment, Some(frame))? {
                if intact {
                    answer = Some(got);
                }
                last = Some(got);
            }
        }
        self.segments = segments;
        Ok(answer.or(last))
    }

    /// The first frame reached the firmware without a delimiter, so there is no command to
    /// hold yet. It is retried as any lost frame is when the next one arrives: a clean
    /// delimiter ends its partial frame, which the firmware rejects and answers with its
    /// safe command (the link timeout is due at once); if not one byte of it arrived, the
    /// frame is sent again, uncorrupted.
    fn retry_first_frame(
        &mut self,
        frame: &C::Frame,
    ) -> Result<StepOutput<C::Command>, ControllerError> {
        if self.inject.has_partial_frame() {
            self.write(&[0])?;
            let mut completed = None;
            self.inject.segments(&[0], &[], |s| completed = Some(s));
            if let Some(segment) = completed {
                if let Some(got) = self.answer(segment, None)? {
                    return Ok(got);
                }
            }
        }
        self.send_frame(frame, false)?
            .ok_or_else(|| link_err("the first sensor frame was not answered, even sent again"))
    }
}

impl<C: Wire> StepController<C> for LockStep<C> {
    fn step(&mut self, frame: &C::Frame) -> Result<StepOutput<C::Command>, ControllerError> {
        let t0 = Instant::now();
        let output = match (self.send_frame(frame, true)?, self.last_output) {
            (Some(out), _) => out,
            (None, Some(held)) => {
                // No delimiter reached the firmware: the previous command stays applied.
                self.counters.link.unanswered_steps += 1;
                held
            }
            (None, None) => self.retry_first_frame(frame)?,
        };
        self.last_output = Some(output);
        self.counters.steps += 1;
        self.counters.time_in_steps += t0.elapsed();
        Ok(output)
    }

    /// A new `Configure` to the firmware, and a new shadow of the same parameters.
    fn reconfigure(&mut self, params: C::Params) -> Result<(), ControllerError> {
        self.shadow = C::new(params).map_err(ControllerError::Params)?;
        self.last_output = None;
        self.configure(params)
    }
}
