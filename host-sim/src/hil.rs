//! Hardware in the loop: the firmware in QEMU behind [`crate::controller::StepController`].
//!
//! [`LockStep::start`] boots the firmware ELF in `qemu-system-arm -machine mps2-an386`
//! with `-icount shift=10` (one target instruction = 1.024 us of virtual time, so the
//! firmware's SysTick measurements are exact and repeatable), configures it with
//! [`HostMessage::Configure`] and then, for every [`StepController::step`], sends the
//! sensor frame, waits for the firmware's [`DeviceMessage::Output`], steps a shadow copy
//! of the core (the same code [`crate::controller::Sil`] runs) with the same input and
//! compares the two commands bit for bit. The command returned is the firmware's.
//!
//! ## Links
//! - [`LinkKind::Semihosting`]: two FIFOs in a private working directory that the firmware
//!   opens with semihosting `SYS_OPEN` (`dexter-h2d`, `dexter-d2h`); fast (one host system
//!   call per frame).
//! - [`LinkKind::Uart`]: the board's CMSDK UART0 (the real driver path, receive interrupt
//!   into a ring buffer), attached by QEMU to a loopback TCP socket this process listens on.
//!
//! defmt logs travel on semihosting stdout (QEMU's stdout), never on the link;
//! [`LockStep::firmware_log`] returns the raw defmt bytes and
//! [`LockStep::firmware_log_text`] decodes them with the ELF ([`decode_defmt_log`]).
//!
//! ## Link faults
//! With [`HilOptions::corrupt_rate`] > 0 each host-to-device byte of a sensor frame
//! (including the extra delimiter the host sends after each frame to flush a partial frame
//! in the firmware's decoder) is dropped or has one bit flipped with that probability
//! (seeded RNG, [`CORRUPTION_SEED`]). The firmware answers every non-empty frame it
//! delimits (see `firmware/src/server.rs`): a valid sensor frame with its control step, a
//! rejected one with `Controller::safe(seq, Fault::LinkTimeout)` (lock-step timeout: one
//! period without a valid frame). The host runs the same [`FrameDecoder`] over the bytes it
//! actually sent, so it knows exactly which answers to expect and mirrors each of them on
//! the shadow core — safe commands included — so every answer is checked bit for bit.
//! `Configure` and `Stop` are sent uncorrupted.

use crate::controller::{ControllerError, HilReport, StepController, StepOutput};
use dexter_core::control::{Controller, ControllerParams};
use dexter_core::protocol::{
    encode, ActuatorCommand, DeviceMessage, Fault, FrameDecoder, HostMessage, SensorFrame,
    MAX_FRAME_LEN,
};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use std::collections::VecDeque;
use std::fs::{File, OpenOptions};
use std::io::{Read, Write};
use std::net::{Shutdown, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// The firmware's compilation target.
pub const TARGET: &str = "thumbv7em-none-eabihf";
/// The emulator binary.
pub const QEMU: &str = "qemu-system-arm";
/// The emulated board.
pub const QEMU_MACHINE: &str = "mps2-an386";
/// `-icount shift`: one instruction is 2^10 ns of virtual time.
pub const ICOUNT_SHIFT: u32 = 10;
/// Default per-step instruction budget (the line-juggler goal).
pub const DEFAULT_INSTRUCTION_BUDGET: u32 = 300;
/// Seed of the byte-corruption RNG.
pub const CORRUPTION_SEED: u64 = 0x00de_c7e2_5eed;
/// Periods without a valid frame before the firmware answers with its safe command
/// (must equal `dexter_firmware::server::LOCKSTEP_TIMEOUT_PERIODS`).
pub const LOCKSTEP_TIMEOUT_PERIODS: u32 = 1;
/// File names of the semihosting link inside QEMU's working directory.
pub const SEMIHOSTING_LINK_FILES: [&str; 2] = ["dexter-h2d", "dexter-d2h"];

/// Which plant link connects the host and the firmware.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LinkKind {
    /// Semihosting file I/O on two FIFOs (fast).
    #[default]
    Semihosting,
    /// The board's UART0 on a loopback TCP socket (the real driver path; slow in QEMU).
    Uart,
}

impl LinkKind {
    /// The firmware boot mode word (`-append`).
    fn boot_word(self) -> &'static str {
        match self {
            LinkKind::Semihosting => "semihosting",
            LinkKind::Uart => "uart",
        }
    }
}

/// How to run the firmware in the loop.
#[derive(Clone, Debug, PartialEq)]
pub struct HilOptions {
    /// The firmware ELF ([`default_firmware_elf`]; [`build_firmware`] builds it).
    pub firmware_elf: PathBuf,
    /// The plant link.
    pub link: LinkKind,
    /// Most instructions one control step may take; a step over it fails the run.
    pub instruction_budget: Option<u32>,
    /// Fraction of host-to-device bytes dropped or bit-flipped (seeded RNG), in [0, 1].
    pub corrupt_rate: f64,
    /// Longest wait for one answer from the firmware.
    pub timeout: Duration,
}

impl Default for HilOptions {
    fn default() -> Self {
        Self {
            firmware_elf: default_firmware_elf(),
            link: LinkKind::Semihosting,
            instruction_budget: Some(DEFAULT_INSTRUCTION_BUDGET),
            corrupt_rate: 0.0,
            timeout: Duration::from_secs(10),
        }
    }
}

/// The workspace root (where `.cargo/config.toml` and `memory.x` live).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

fn target_dir() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(dir) => workspace_root().join(dir),
        None => workspace_root().join("target"),
    }
}

/// Where `cargo build -p dexter-firmware --release --target thumbv7em-none-eabihf` puts
/// the firmware ELF.
pub fn default_firmware_elf() -> PathBuf {
    target_dir()
        .join(TARGET)
        .join("release")
        .join("dexter-firmware")
}

/// Check that the emulator and the firmware target are installed; the error says what to
/// install.
pub fn check_toolchain() -> Result<(), ControllerError> {
    let qemu = Command::new(QEMU)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    if !matches!(qemu, Ok(s) if s.success()) {
        return Err(ControllerError::Link(format!(
            "{QEMU} not found: install it with `apt-get install qemu-system-arm` (QEMU >= 7.2 for {QEMU_MACHINE})"
        )));
    }
    let sysroot = Command::new(std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into()))
        .args(["--print", "sysroot"])
        .output()
        .map_err(|e| ControllerError::Link(format!("cannot run rustc: {e}")))?;
    let sysroot = PathBuf::from(String::from_utf8_lossy(&sysroot.stdout).trim());
    if !sysroot.join("lib/rustlib").join(TARGET).is_dir() {
        return Err(ControllerError::Link(format!(
            "the Rust target {TARGET} is not installed: run `rustup target add {TARGET}`"
        )));
    }
    Ok(())
}

/// Build the firmware (`cargo build -p dexter-firmware --release --target
/// thumbv7em-none-eabihf` in the workspace root) and return the ELF's path.
pub fn build_firmware() -> Result<PathBuf, ControllerError> {
    build_firmware_with_features(&[])
}

/// [`build_firmware`] with cargo features of `dexter-firmware` (e.g. `fast-math`, `bench`);
/// the ELF is written to the same path.
pub fn build_firmware_with_features(features: &[&str]) -> Result<PathBuf, ControllerError> {
    check_toolchain()?;
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(workspace_root()).args([
        "build",
        "-p",
        "dexter-firmware",
        "--release",
        "--target",
        TARGET,
    ]);
    if !features.is_empty() {
        cmd.args(["--features", &features.join(",")]);
    }
    let out = cmd.output().map_err(|e| {
        ControllerError::Link(format!("cannot run cargo to build the firmware: {e}"))
    })?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = err.lines().rev().take(30).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        return Err(ControllerError::Link(format!(
            "building the firmware failed ({}):\n{}",
            out.status,
            tail.join("\n")
        )));
    }
    Ok(default_firmware_elf())
}

/// A chunk of bytes from the device, or the end of the link.
type Chunk = Result<Vec<u8>, String>;

/// The host end of a plant link.
struct Transport {
    writer: Box<dyn Write + Send>,
    /// Unblocks the reader thread (called after QEMU is gone).
    closer: Box<dyn FnMut() + Send>,
}

/// Counters of a run.
#[derive(Clone, Copy, Debug, Default)]
struct Counters {
    steps: u64,
    outputs: u64,
    instructions_sum: u64,
    instructions_min: u32,
    instructions_max: u32,
    sil_mismatches: u64,
    over_budget_steps: u64,
    link_timeouts: u64,
    device_link_errors: u64,
    host_link_errors: u64,
    corrupted_accepted: u64,
    unanswered_steps: u64,
    time_in_steps: Duration,
}

/// The firmware in QEMU, stepped in lock-step with the plant.
pub struct LockStep {
    child: Child,
    transport: Transport,
    rx: mpsc::Receiver<Chunk>,
    threads: Vec<JoinHandle<()>>,
    closing: Arc<AtomicBool>,
    log: Arc<Mutex<Vec<u8>>>,
    stderr: Arc<Mutex<Vec<u8>>>,
    /// QEMU's private working directory (the FIFOs); removed on drop.
    _workdir: WorkDir,
    replies: VecDeque<DeviceMessage>,
    reply_decoder: FrameDecoder<MAX_FRAME_LEN>,
    /// Decodes the bytes the host sent exactly as the firmware will.
    mirror: FrameDecoder<MAX_FRAME_LEN>,
    mirror_last_seq: u32,
    mirror_missed: u32,
    shadow: Controller,
    rng: StdRng,
    opts: HilOptions,
    counters: Counters,
    last_output: Option<StepOutput>,
    first_mismatch: Option<String>,
}

/// A directory removed when dropped.
struct WorkDir(PathBuf);

impl Drop for WorkDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

static RUN_ID: AtomicU64 = AtomicU64::new(0);

fn link_err(msg: impl Into<String>) -> ControllerError {
    ControllerError::Link(msg.into())
}

fn spawn_reader(
    mut source: Box<dyn Read + Send>,
    tx: mpsc::Sender<Chunk>,
    closing: Arc<AtomicBool>,
) -> JoinHandle<()> {
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        loop {
            match source.read(&mut buf) {
                Ok(0) => {
                    let _ = tx.send(Err("the link was closed".into()));
                    return;
                }
                Ok(n) => {
                    if closing.load(Ordering::Acquire) {
                        return;
                    }
                    if tx.send(Ok(buf[..n].to_vec())).is_err() {
                        return;
                    }
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => {
                    let _ = tx.send(Err(format!("reading the link failed: {e}")));
                    return;
                }
            }
        }
    })
}

fn spawn_collector(
    mut source: impl Read + Send + 'static,
    into: Arc<Mutex<Vec<u8>>>,
) -> JoinHandle<()> {
    std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while let Ok(n) = source.read(&mut buf) {
            if n == 0 {
                break;
            }
            if let Ok(mut v) = into.lock() {
                v.extend_from_slice(&buf[..n]);
            }
        }
    })
}

fn make_fifo(path: &Path) -> Result<(), ControllerError> {
    let status = Command::new("mkfifo")
        .arg(path)
        .status()
        .map_err(|e| link_err(format!("cannot run mkfifo: {e}")))?;
    if !status.success() {
        return Err(link_err(format!(
            "mkfifo {} failed ({status})",
            path.display()
        )));
    }
    Ok(())
}

/// Open a FIFO read-write: never blocks, whether or not QEMU has opened its end yet.
fn open_fifo(path: &Path) -> Result<File, ControllerError> {
    OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .map_err(|e| link_err(format!("cannot open {}: {e}", path.display())))
}

impl LockStep {
    /// Boot the firmware in QEMU, configure it with `params` and wait for its answer (the
    /// one untimed round trip before any timing).
    pub fn start(params: ControllerParams, opts: HilOptions) -> Result<LockStep, ControllerError> {
        let shadow = Controller::new(params).map_err(ControllerError::Params)?;
        if !(0.0..=1.0).contains(&opts.corrupt_rate) {
            return Err(link_err(format!(
                "corrupt_rate must be within [0, 1], got {}",
                opts.corrupt_rate
            )));
        }
        check_toolchain()?;
        if !opts.firmware_elf.is_file() {
            return Err(link_err(format!(
                "firmware ELF {} not found: build it with `cargo fw-build` \
                 (cargo build -p dexter-firmware --release --target {TARGET}) or call hil::build_firmware()",
                opts.firmware_elf.display()
            )));
        }
        let workdir = std::env::temp_dir().join(format!(
            "dexter-hil-{}-{}",
            std::process::id(),
            RUN_ID.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&workdir);
        std::fs::create_dir_all(&workdir)
            .map_err(|e| link_err(format!("cannot create {}: {e}", workdir.display())))?;
        let workdir = WorkDir(workdir);

        let closing = Arc::new(AtomicBool::new(false));
        let (chunk_tx, chunk_rx) = mpsc::channel::<Chunk>();
        let mut threads = Vec::new();

        let mut qemu = Command::new(QEMU);
        qemu.current_dir(&workdir.0)
            .args(["-machine", QEMU_MACHINE, "-nographic", "-monitor", "none"])
            .args(["-icount", &format!("shift={ICOUNT_SHIFT}")])
            .args(["-semihosting-config", "enable=on,target=native"])
            .arg("-kernel")
            .arg(&opts.firmware_elf)
            .args(["-append", opts.link.boot_word()])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());

        // Set up the host end of the link before QEMU starts.
        let pending = match opts.link {
            LinkKind::Semihosting => {
                let h2d = workdir.0.join(SEMIHOSTING_LINK_FILES[0]);
                let d2h = workdir.0.join(SEMIHOSTING_LINK_FILES[1]);
                make_fifo(&h2d)?;
                make_fifo(&d2h)?;
                qemu.args(["-serial", "null"]);
                Pending::Fifo(open_fifo(&h2d)?, open_fifo(&d2h)?)
            }
            LinkKind::Uart => {
                let listener = TcpListener::bind("127.0.0.1:0")
                    .map_err(|e| link_err(format!("cannot listen on loopback: {e}")))?;
                let port = listener
                    .local_addr()
                    .map_err(|e| link_err(format!("no local address: {e}")))?
                    .port();
                // nodelay: QEMU writes one byte per send(); with Nagle on, each answer would
                // wait for the host's delayed ACK (~40 ms).
                qemu.args([
                    "-chardev",
                    &format!("socket,id=uart0,host=127.0.0.1,port={port},nodelay=on"),
                    "-serial",
                    "chardev:uart0",
                ]);
                Pending::Tcp(listener)
            }
        };

        let mut child = qemu
            .spawn()
            .map_err(|e| link_err(format!("cannot start {QEMU}: {e}")))?;
        let log = Arc::new(Mutex::new(Vec::new()));
        let stderr = Arc::new(Mutex::new(Vec::new()));
        if let Some(out) = child.stdout.take() {
            threads.push(spawn_collector(out, log.clone()));
        }
        if let Some(err) = child.stderr.take() {
            threads.push(spawn_collector(err, stderr.clone()));
        }

        let transport = match connect(
            pending,
            &mut child,
            &mut threads,
            chunk_tx,
            &closing,
            opts.timeout,
        ) {
            Ok(t) => t,
            Err(e) => {
                let _ = child.kill();
                let _ = child.wait();
                closing.store(true, Ordering::Release);
                return Err(e);
            }
        };

        let mut hil = LockStep {
            child,
            transport,
            rx: chunk_rx,
            threads,
            closing,
            log,
            stderr,
            _workdir: workdir,
            replies: VecDeque::new(),
            reply_decoder: FrameDecoder::new(),
            mirror: FrameDecoder::new(),
            mirror_last_seq: 0,
            mirror_missed: 0,
            shadow,
            rng: StdRng::seed_from_u64(CORRUPTION_SEED),
            opts,
            counters: Counters {
                instructions_min: u32::MAX,
                ..Counters::default()
            },
            last_output: None,
            first_mismatch: None,
        };
        hil.configure(params)?;
        Ok(hil)
    }

    fn configure(&mut self, params: ControllerParams) -> Result<(), ControllerError> {
        self.send_clean(&HostMessage::Configure(params))?;
        let deadline = Instant::now() + self.opts.timeout;
        loop {
            if let Some(reply) = self.replies.pop_front() {
                return match reply {
                    DeviceMessage::Configured { ok: true } => Ok(()),
                    DeviceMessage::Configured { ok: false } => {
                        Err(link_err("the firmware rejected the controller parameters"))
                    }
                    other => Err(link_err(format!(
                        "expected the firmware's Configured answer, got {other:?}"
                    ))),
                };
            }
            self.pump(deadline, "the answer to Configure")?;
        }
    }

    /// Send a message without fault injection (through the mirror decoder too).
    fn send_clean(&mut self, message: &HostMessage) -> Result<(), ControllerError> {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode(message, &mut buf)
            .map_err(|e| link_err(format!("cannot encode {message:?}: {e:?}")))?;
        for &b in &buf[..n] {
            if let Some(Ok(HostMessage::Configure(_))) = self.mirror.push::<HostMessage>(b) {
                self.mirror_missed = 0;
            }
        }
        self.write(&buf[..n])
    }

    fn write(&mut self, bytes: &[u8]) -> Result<(), ControllerError> {
        let r = self
            .transport
            .writer
            .write_all(bytes)
            .and_then(|()| self.transport.writer.flush());
        r.map_err(|e| self.dead_or(format!("writing to the firmware failed: {e}")))
    }

    /// Receive bytes until `deadline`, decoding answers into `self.replies`.
    fn pump(&mut self, deadline: Instant, waiting_for: &str) -> Result<(), ControllerError> {
        // Wait in slices so an emulator that exited (panic, HardFault) is reported at once
        // rather than after the whole timeout.
        const SLICE: Duration = Duration::from_millis(50);
        let received = loop {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left.min(SLICE)) {
                Err(mpsc::RecvTimeoutError::Timeout) if !left.is_zero() => {
                    if let Ok(Some(_)) = self.child.try_wait() {
                        return Err(self.dead_or(format!(
                            "the firmware stopped while waiting for {waiting_for}"
                        )));
                    }
                }
                other => break other,
            }
        };
        match received {
            Ok(Ok(chunk)) => {
                for b in chunk {
                    match self.reply_decoder.push::<DeviceMessage>(b) {
                        Some(Ok(m)) => self.replies.push_back(m),
                        Some(Err(_)) => self.counters.host_link_errors += 1,
                        None => {}
                    }
                }
                Ok(())
            }
            Ok(Err(e)) => Err(self.dead_or(format!("{e} while waiting for {waiting_for}"))),
            Err(mpsc::RecvTimeoutError::Timeout) => Err(self.dead_or(format!(
                "timeout: no answer from the firmware within {:?} while waiting for {waiting_for} \
                 ({:?} link, QEMU still running)",
                self.opts.timeout, self.opts.link
            ))),
            Err(mpsc::RecvTimeoutError::Disconnected) => Err(self.dead_or(format!(
                "the link reader stopped while waiting for {waiting_for}"
            ))),
        }
    }

    /// A link error; if QEMU has exited, say so (with its status and stderr).
    fn dead_or(&mut self, msg: String) -> ControllerError {
        match self.child.try_wait() {
            Ok(Some(status)) => {
                std::thread::sleep(Duration::from_millis(50));
                let stderr = self
                    .stderr
                    .lock()
                    .map(|v| String::from_utf8_lossy(&v).into_owned())
                    .unwrap_or_default();
                link_err(format!(
                    "QEMU exited ({}) — {msg}; QEMU stderr: {}",
                    describe_exit(status),
                    stderr.trim()
                ))
            }
            _ => link_err(msg),
        }
    }

    fn next_output(&mut self, seq: u32) -> Result<StepOutput, ControllerError> {
        let deadline = Instant::now() + self.opts.timeout;
        loop {
            match self.replies.pop_front() {
                Some(DeviceMessage::Output { command, telemetry }) => {
                    return Ok(StepOutput { command, telemetry })
                }
                Some(other) => {
                    return Err(link_err(format!(
                        "expected an Output answer for sensor frame {seq}, got {other:?}"
                    )))
                }
                None => self.pump(deadline, &format!("the answer to sensor frame {seq}"))?,
            }
        }
    }

    fn corrupt(&mut self, bytes: &[u8]) -> Vec<u8> {
        let rate = self.opts.corrupt_rate;
        if rate <= 0.0 {
            return bytes.to_vec();
        }
        let mut out = Vec::with_capacity(bytes.len());
        for &b in bytes {
            if self.rng.random::<f64>() < rate {
                if self.rng.random_bool(0.5) {
                    continue; // dropped
                }
                out.push(b ^ (1u8 << self.rng.random_range(0..8u32)));
            } else {
                out.push(b);
            }
        }
        out
    }

    /// Record one firmware answer against the shadow core's command.
    fn check(
        &mut self,
        expected: ActuatorCommand,
        got: &StepOutput,
    ) -> Result<(), ControllerError> {
        let c = &mut self.counters;
        c.outputs += 1;
        let instr = got.telemetry.step_instructions;
        c.instructions_sum += u64::from(instr);
        c.instructions_min = c.instructions_min.min(instr);
        c.instructions_max = c.instructions_max.max(instr);
        c.device_link_errors = u64::from(got.telemetry.link_errors);
        if got.command.fault == Fault::LinkTimeout {
            c.link_timeouts += 1;
        }
        if !bit_identical(&expected, &got.command) {
            c.sil_mismatches += 1;
            if self.first_mismatch.is_none() {
                self.first_mismatch =
                    Some(format!("firmware {:?} vs SIL {:?}", got.command, expected));
            }
        }
        if let Some(budget) = self.opts.instruction_budget {
            if instr > budget {
                c.over_budget_steps += 1;
                return Err(link_err(format!(
                    "control step for seq {} took {instr} instructions on the target, over the budget of {budget}",
                    got.command.seq
                )));
            }
        }
        Ok(())
    }

    /// The first firmware/SIL disagreement, described.
    pub fn first_mismatch(&self) -> Option<&str> {
        self.first_mismatch.as_deref()
    }

    /// Sensor frames that the firmware accepted although they were corrupted (a CRC
    /// collision; expected 0).
    pub fn corrupted_frames_accepted(&self) -> u64 {
        self.counters.corrupted_accepted
    }

    /// Steps for which no frame delimiter reached the firmware (the previous command was
    /// held).
    pub fn unanswered_steps(&self) -> u64 {
        self.counters.unanswered_steps
    }

    /// The raw defmt log so far (semihosting stdout); decode with the firmware ELF.
    pub fn firmware_log(&self) -> Vec<u8> {
        self.log.lock().map(|v| v.clone()).unwrap_or_default()
    }

    /// The firmware log so far, decoded (see [`decode_defmt_log`]).
    pub fn firmware_log_text(&self) -> Result<String, ControllerError> {
        decode_defmt_log(&self.opts.firmware_elf, &self.firmware_log())
    }

    /// Process id of the QEMU instance (it is killed when the `LockStep` is dropped).
    pub fn qemu_pid(&self) -> u32 {
        self.child.id()
    }

    /// The options this run uses.
    pub fn options(&self) -> &HilOptions {
        &self.opts
    }

    fn report(&self) -> HilReport {
        let c = &self.counters;
        let secs = c.time_in_steps.as_secs_f64();
        HilReport {
            step_instructions_min: if c.outputs == 0 {
                0
            } else {
                c.instructions_min
            },
            step_instructions_mean: if c.outputs == 0 {
                0.0
            } else {
                c.instructions_sum as f64 / c.outputs as f64
            },
            step_instructions_max: c.instructions_max,
            sil_mismatches: c.sil_mismatches,
            link_errors: c.device_link_errors + c.host_link_errors,
            over_budget_steps: c.over_budget_steps,
            link_timeouts: c.link_timeouts,
            steps_per_wall_second: if secs > 0.0 {
                c.steps as f64 / secs
            } else {
                0.0
            },
        }
    }

    /// Stop the firmware ([`HostMessage::Stop`]), wait for QEMU to exit and return the
    /// report; an exit status other than success (a panic or HardFault) is an error.
    pub fn finish(mut self) -> Result<HilReport, ControllerError> {
        self.send_clean(&HostMessage::Stop)?;
        let deadline = Instant::now() + self.opts.timeout;
        loop {
            match self.child.try_wait() {
                Ok(Some(status)) if status.success() => return Ok(self.report()),
                Ok(Some(status)) => {
                    return Err(link_err(format!(
                        "the firmware ended the run with a failure ({})",
                        describe_exit(status)
                    )))
                }
                Ok(None) if Instant::now() < deadline => {
                    std::thread::sleep(Duration::from_millis(2))
                }
                Ok(None) => {
                    return Err(link_err(format!(
                        "timeout: QEMU did not exit within {:?} after Stop",
                        self.opts.timeout
                    )))
                }
                Err(e) => return Err(link_err(format!("cannot wait for QEMU: {e}"))),
            }
        }
    }
}

/// The host end of the link before QEMU starts.
enum Pending {
    Fifo(File, File),
    Tcp(TcpListener),
}

fn connect(
    pending: Pending,
    child: &mut Child,
    threads: &mut Vec<JoinHandle<()>>,
    chunk_tx: mpsc::Sender<Chunk>,
    closing: &Arc<AtomicBool>,
    timeout: Duration,
) -> Result<Transport, ControllerError> {
    Ok(match pending {
        Pending::Fifo(h2d, d2h) => {
            let reader = d2h
                .try_clone()
                .map_err(|e| link_err(format!("cannot clone the FIFO handle: {e}")))?;
            threads.push(spawn_reader(Box::new(reader), chunk_tx, closing.clone()));
            let mut unblock = d2h;
            Transport {
                writer: Box::new(h2d),
                // We hold the FIFO read-write: one byte wakes our own reader thread.
                closer: Box::new(move || {
                    let _ = unblock.write_all(&[0]);
                }),
            }
        }
        Pending::Tcp(listener) => {
            let stream = accept_with_deadline(&listener, child, timeout)?;
            let _ = stream.set_nodelay(true);
            let reader = stream
                .try_clone()
                .map_err(|e| link_err(format!("cannot clone the socket: {e}")))?;
            threads.push(spawn_reader(Box::new(reader), chunk_tx, closing.clone()));
            let closer = stream
                .try_clone()
                .map_err(|e| link_err(format!("cannot clone the socket: {e}")))?;
            Transport {
                writer: Box::new(stream),
                closer: Box::new(move || {
                    let _ = closer.shutdown(Shutdown::Both);
                }),
            }
        }
    })
}

fn describe_exit(status: ExitStatus) -> String {
    match status.code() {
        Some(0) => "status 0, success".into(),
        Some(1) => {
            "status 1: the firmware reported a failure (panic, HardFault or link error)".into()
        }
        Some(c) => format!("status {c}"),
        None => "killed by a signal".into(),
    }
}

fn accept_with_deadline(
    listener: &TcpListener,
    child: &mut Child,
    timeout: Duration,
) -> Result<TcpStream, ControllerError> {
    listener
        .set_nonblocking(true)
        .map_err(|e| link_err(format!("cannot poll the listener: {e}")))?;
    let deadline = Instant::now() + timeout;
    loop {
        match listener.accept() {
            Ok((stream, _)) => {
                stream
                    .set_nonblocking(false)
                    .map_err(|e| link_err(format!("socket: {e}")))?;
                return Ok(stream);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                if let Ok(Some(status)) = child.try_wait() {
                    return Err(link_err(format!(
                        "QEMU exited ({}) before connecting its UART",
                        describe_exit(status)
                    )));
                }
                if Instant::now() >= deadline {
                    return Err(link_err(format!(
                        "timeout: QEMU did not connect its UART within {timeout:?}"
                    )));
                }
                std::thread::sleep(Duration::from_millis(5));
            }
            Err(e) => return Err(link_err(format!("accept failed: {e}"))),
        }
    }
}

/// Decode a defmt byte stream (the firmware's semihosting stdout) with the ELF's defmt
/// table into one `LEVEL message` line per log frame.
pub fn decode_defmt_log(elf: &Path, bytes: &[u8]) -> Result<String, ControllerError> {
    let data =
        std::fs::read(elf).map_err(|e| link_err(format!("cannot read {}: {e}", elf.display())))?;
    let table = defmt_decoder::Table::parse(&data)
        .map_err(|e| link_err(format!("bad defmt table in {}: {e}", elf.display())))?
        .ok_or_else(|| link_err(format!("{} has no defmt data", elf.display())))?;
    let mut decoder = table.new_stream_decoder();
    decoder.received(bytes);
    let mut out = String::new();
    loop {
        match decoder.decode() {
            Ok(frame) => {
                let level = frame
                    .level()
                    .map(|l| format!("{l:?}").to_uppercase())
                    .unwrap_or_else(|| "PRINT".into());
                out.push_str(&format!("{level} {}\n", frame.display_message()));
            }
            Err(defmt_decoder::DecodeError::UnexpectedEof) => break,
            Err(defmt_decoder::DecodeError::Malformed) => {
                out.push_str("(malformed defmt frame: the rest of the log is not decoded)\n");
                break;
            }
        }
    }
    Ok(out)
}

/// Whether two commands are identical bit for bit (f32 via `to_bits`).
pub fn bit_identical(a: &ActuatorCommand, b: &ActuatorCommand) -> bool {
    a.seq == b.seq
        && a.paddle_accel_mps2.to_bits() == b.paddle_accel_mps2.to_bits()
        && a.paddle_height_ref_m.to_bits() == b.paddle_height_ref_m.to_bits()
        && a.paddle_velocity_ref_mps.to_bits() == b.paddle_velocity_ref_mps.to_bits()
        && a.mode == b.mode
        && a.fault == b.fault
}

impl StepController for LockStep {
    fn step(&mut self, frame: &SensorFrame) -> Result<StepOutput, ControllerError> {
        let t0 = Instant::now();
        let mut buf = [0u8; MAX_FRAME_LEN + 1];
        let n = encode(&HostMessage::Sensor(*frame), &mut buf)
            .map_err(|e| link_err(format!("cannot encode sensor frame {}: {e:?}", frame.seq)))?;
        buf[n] = 0; // flush delimiter: ends a partial frame left by a lost delimiter
        let sent = self.corrupt(&buf[..n + 1]);
        // What the firmware will decode from these bytes, in order.
        let mut expected = Vec::new();
        for &b in &sent {
            if let Some(r) = self.mirror.push::<HostMessage>(b) {
                expected.push(r);
            }
        }
        self.write(&sent)?;
        let mut answer: Option<StepOutput> = None;
        let mut last: Option<StepOutput> = None;
        for result in expected {
            match result {
                Ok(HostMessage::Sensor(decoded)) => {
                    let got = self.next_output(decoded.seq)?;
                    if decoded != *frame {
                        self.counters.corrupted_accepted += 1;
                    }
                    // The shadow gets what the plant really sent: a corrupted frame that
                    // the firmware applied shows up as a mismatch.
                    let expected_cmd = self.shadow.step(frame);
                    self.mirror_last_seq = decoded.seq;
                    self.mirror_missed = 0;
                    self.check(expected_cmd, &got)?;
                    if decoded.seq == frame.seq {
                        answer = Some(got);
                    }
                    last = Some(got);
                }
                Ok(other) => {
                    return Err(link_err(format!(
                        "fault injection turned sensor frame {} into a valid {other:?}",
                        frame.seq
                    )))
                }
                Err(_) => {
                    self.mirror_missed = self.mirror_missed.saturating_add(1);
                    if self.mirror_missed < LOCKSTEP_TIMEOUT_PERIODS {
                        continue;
                    }
                    let seq = self.mirror_last_seq.wrapping_add(self.mirror_missed);
                    let got = self.next_output(seq)?;
                    let expected_cmd = self.shadow.safe(seq, Fault::LinkTimeout);
                    self.check(expected_cmd, &got)?;
                    last = Some(got);
                }
            }
        }
        let output = match answer.or(last) {
            Some(out) => out,
            None => {
                // No delimiter reached the firmware: the previous command stays applied.
                self.counters.unanswered_steps += 1;
                self.last_output.ok_or_else(|| {
                    link_err(format!(
                        "sensor frame {} was lost before any answer",
                        frame.seq
                    ))
                })?
            }
        };
        self.last_output = Some(output);
        self.counters.steps += 1;
        self.counters.time_in_steps += t0.elapsed();
        Ok(output)
    }

    fn hil_report(&self) -> Option<HilReport> {
        Some(self.report())
    }
}

impl Drop for LockStep {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.closing.store(true, Ordering::Release);
        (self.transport.closer)();
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}
