//! The NUCLEO-F446RE image in the loop under emulation: the board crate built with its
//! `qemu-hsi` feature (the same image on the 16 MHz internal oscillator, which QEMU's
//! netduinoplus2 can run: it does not model the RCC, so the HSE-ready poll of the real
//! image never ends there) boots in `qemu-system-arm -machine netduinoplus2` (STM32F405:
//! the same Cortex-M4F core and USARTs), with USART2, the board's host link, on a
//! pseudo-terminal QEMU allocates. `dexter run SCENE --hil --port PTY` then drives the
//! board's RTIC app, the HAL's USART driver, its receive ring, the switch into HIL mode and
//! the lock-step server, for every controller kind the image hosts: the line juggler, the
//! tilt table, the hopper, the one-joint arm (the CLI) and the link check (`Echo`,
//! through the library). Each run must agree with the host's shadow core bit for bit and
//! end with the same summary as the SIL run of the scene. After each host's `Stop` the
//! board resets (`SCB::sys_reset`, which QEMU models), so one emulator serves all runs.
//!
//! What the emulator does not model (firmware/README.md, "Emulation"): DWT's cycle
//! counter reads 0 (so the step figures are 0 and no budget is applied, as on any
//! `--port` run without `--budget`), TIM1 (the motor PWM) and the GPIOs are unimplemented
//! devices, and TIM3 counts freely instead of decoding the encoder.
//!
//! QEMU is stopped by its pid when the test ends, also when it fails.

mod common;

use common::scene;
use dexter_core::echo::{Echo, EchoFrame, EchoParams};
use dexter_core::fixed_rate::Fault;
use dexter_sim::controller::StepController;
use dexter_sim::hil::{HilOptions, LockStep, SerialPortOptions};
use serde_json::Value;
use serialport::SerialPort;
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

const TARGET: &str = "thumbv7em-none-eabihf";
const CRATE: &str = "dexter-nucleo-f446re";
/// How long QEMU may take to announce its pseudo-terminal.
const BOOT_TIMEOUT: Duration = Duration::from_secs(10);

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .canonicalize()
        .unwrap()
}

/// Build the board image with `qemu-hsi` (release) and copy it beside the real image as
/// `dexter-nucleo-f446re-qemu-hsi.elf`, so that a later build of the real image (the size
/// test, `scripts/test.sh`) does not replace it.
fn emulated_board_image() -> PathBuf {
    emulated_image_with("qemu-hsi")
}

/// [`emulated_board_image`] with `features` (`qemu-hsi` among them), copied as
/// `dexter-nucleo-f446re-<features, commas as dashes>.elf`.
fn emulated_image_with(features: &str) -> PathBuf {
    // Every feature set links to the same path: build and copy one at a time (the tests
    // of this file run in parallel threads).
    static BUILD: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one_at_a_time = BUILD.lock().unwrap_or_else(|e| e.into_inner());
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(workspace())
        .args(["build", "-p", CRATE, "--release", "--target", TARGET])
        .args(["--features", features])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "building {CRATE} --features {features} failed (install the target with `rustup target add {TARGET}`):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(|d| workspace().join(d))
        .unwrap_or_else(|| workspace().join("target"));
    let release = target.join(TARGET).join("release");
    let copy = release.join(format!("{CRATE}-{}.elf", features.replace(',', "-")));
    std::fs::copy(release.join(CRATE), &copy).expect("copy the emulated board's image");
    copy
}

/// The address of the static `name` in `elf` (`llvm-objdump -t`).
fn symbol_address(elf: &Path, name: &str) -> u64 {
    let objdump = dexter_sim::hil::llvm_tool("llvm-objdump").unwrap_or_else(|e| panic!("{e}"));
    let out = Command::new(objdump).arg("-t").arg(elf).output().unwrap();
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .find(|l| l.split_whitespace().last() == Some(name))
        .and_then(|l| u64::from_str_radix(l.split_whitespace().next()?, 16).ok())
        .unwrap_or_else(|| panic!("no symbol {name} in {}", elf.display()))
}

/// The emulated board: USART2 (the host link) on a pseudo-terminal, USART1 (the camera's
/// line) and QEMU's monitor on Unix sockets in a private directory. QEMU's pid is killed
/// and waited for on drop, and the directory removed.
struct Emulator {
    qemu: Child,
    port: String,
    dir: PathBuf,
    camera: UnixStream,
}

/// A write QEMU logged to a device it does not model (`-d unimp,guest_errors`): the
/// device's name as QEMU gives it, the register's offset, and the value (none for the
/// system region's unassigned registers, whose writes QEMU logs without it).
#[derive(Debug)]
struct DeviceWrite {
    device: String,
    offset: u64,
    value: Option<u64>,
}

/// One line of QEMU's device log, if it is a write: `NAME: unimplemented device write
/// (size 4, offset 0x034, value 0x00000001)` or `Write of unassigned area of PPB: offset
/// 0x42004`.
fn device_write(line: &str) -> Option<DeviceWrite> {
    let hex = |t: &str| u64::from_str_radix(t.trim().trim_start_matches("0x"), 16).ok();
    if let Some(offset) = line.strip_prefix("Write of unassigned area of PPB: offset ") {
        return Some(DeviceWrite {
            device: "PPB".into(),
            offset: hex(offset)?,
            value: None,
        });
    }
    let (device, rest) = line.split_once(": unimplemented device write (")?;
    let field = |key: &str| {
        let at = rest.find(key)? + key.len();
        hex(rest[at..].split([',', ')']).next()?)
    };
    Some(DeviceWrite {
        device: device.into(),
        offset: field("offset ")?,
        value: Some(field("value ")?),
    })
}

impl Emulator {
    /// Boot `elf` in netduinoplus2; the port is the one QEMU names on stdout ("char device
    /// redirected to /dev/pts/N").
    fn boot(elf: &Path, name: &str) -> Self {
        Self::boot_with(elf, name, &[])
    }

    /// [`Emulator::boot`], with QEMU logging every write to a device it does not model
    /// (TIM1, the GPIOs, the IWDG, DBGMCU) to `devices.log` ([`Emulator::writes_since`]),
    /// and `words` (address, value) written to memory before the core starts (QEMU's
    /// generic `loader` device).
    fn boot_logging_devices(elf: &Path, name: &str, words: &[(u64, u32)]) -> Self {
        let mut extra: Vec<String> = ["-d", "unimp,guest_errors", "-D", "devices.log"]
            .map(String::from)
            .into();
        for (addr, value) in words {
            extra.push("-device".into());
            extra.push(format!("loader,addr={addr:#x},data={value:#x},data-len=4"));
        }
        Self::boot_with(elf, name, &extra)
    }

    fn boot_with(elf: &Path, name: &str, extra: &[String]) -> Self {
        let dir = common::scratch(name);
        let (monitor, camera) = (dir.join("monitor.sock"), dir.join("camera.sock"));
        let unix = |p: &Path| format!("unix:{},server=on,wait=off", p.display());
        let mut qemu = Command::new("qemu-system-arm")
            .current_dir(&dir)
            .args(extra)
            .args(["-machine", "netduinoplus2", "-nographic"])
            .args(["-monitor", &unix(&monitor), "-serial", &unix(&camera)])
            .args(["-serial", "pty", "-kernel"])
            .arg(elf)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("qemu-system-arm runs (apt-get install qemu-system-arm)");
        let stdout = qemu.stdout.take().unwrap();
        let (tx, rx) = mpsc::channel();
        // Reads QEMU's stdout to its end, so QEMU never blocks on a full pipe.
        std::thread::spawn(move || {
            for line in BufReader::new(stdout).lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
        let mut seen = Vec::new();
        let port = loop {
            let Ok(line) = rx.recv_timeout(BOOT_TIMEOUT) else {
                let _ = qemu.kill();
                let _ = qemu.wait();
                panic!("QEMU named no pseudo-terminal within {BOOT_TIMEOUT:?}; it said: {seen:?}");
            };
            if let Some(at) = line.find("/dev/pts/") {
                break line[at..].split_whitespace().next().unwrap().to_string();
            }
            seen.push(line);
        };
        let camera = UnixStream::connect(&camera).expect("QEMU's USART1 socket");
        Emulator {
            qemu,
            port,
            dir,
            camera,
        }
    }

    /// One monitor command's answer (QEMU's human monitor, echo included).
    fn monitor(&self, command: &str) -> String {
        let gone = "QEMU's monitor is gone: QEMU ended (a core lockup, a fault that cannot \
                    be handled, ends it)";
        let mut m = UnixStream::connect(self.dir.join("monitor.sock")).expect(gone);
        m.set_read_timeout(Some(Duration::from_millis(500)))
            .unwrap();
        let mut answer = Vec::new();
        let mut buf = [0u8; 4096];
        let mut read_to_prompt = |m: &mut UnixStream, answer: &mut Vec<u8>| {
            while let Ok(n) = m.read(&mut buf) {
                answer.extend_from_slice(&buf[..n]);
                if n == 0 || answer.ends_with(b"(qemu) ") {
                    break;
                }
            }
        };
        read_to_prompt(&mut m, &mut answer);
        answer.clear();
        m.write_all(format!("{command}\n").as_bytes()).expect(gone);
        read_to_prompt(&mut m, &mut answer);
        String::from_utf8_lossy(&answer).into_owned()
    }

    /// The 32-bit word at physical address `addr` (`xp`).
    fn word(&self, addr: u64) -> u32 {
        let answer = self.monitor(&format!("xp /1wx {addr:#x}"));
        let key = format!("{addr:016x}: 0x");
        let at = answer
            .find(&key)
            .unwrap_or_else(|| panic!("xp: {answer:?}"))
            + key.len();
        u32::from_str_radix(&answer[at..at + 8], 16).unwrap()
    }

    /// The device log's length, bytes: a mark for [`Emulator::writes_since`].
    fn log_mark(&self) -> u64 {
        std::fs::metadata(self.dir.join("devices.log")).map_or(0, |m| m.len())
    }

    /// The device writes QEMU logged after `mark` ([`Emulator::boot_logging_devices`]).
    fn writes_since(&self, mark: u64) -> Vec<DeviceWrite> {
        let log = std::fs::read(self.dir.join("devices.log")).expect("QEMU's device log");
        let from = usize::try_from(mark).unwrap().min(log.len());
        String::from_utf8_lossy(&log[from..])
            .lines()
            .filter_map(device_write)
            .collect()
    }

    /// Poll the word at `addr` until it is `want` (true) or `wait` has passed (false).
    fn word_becomes(&self, addr: u64, want: u32, wait: Duration) -> bool {
        let end = std::time::Instant::now() + wait;
        while std::time::Instant::now() < end {
            if self.word(addr) == want {
                return true;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
        false
    }
}

impl Drop for Emulator {
    fn drop(&mut self) {
        let _ = self.qemu.kill();
        let _ = self.qemu.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Keys whose values differ between a HIL run and its SIL run by design.
fn differs_by_design(key: &str) -> bool {
    [
        "wall",
        "hil",
        "controller",
        "step_instructions",
        "sil_",
        "link_",
        "over_budget",
    ]
    .iter()
    .any(|k| key.contains(k))
}

/// Every key of the SIL summary (outside those that differ by design) has the same value
/// in the HIL summary: the same physics driven by the same commands.
fn assert_same_outcome(name: &str, sil: &Value, hil: &Value) {
    let sil = sil.as_object().expect("an object");
    assert!(sil.len() > 5, "{name}: {sil:?}");
    for (key, value) in sil.iter().filter(|(k, _)| !differs_by_design(k)) {
        assert_eq!(
            Some(value),
            hil.get(key),
            "{name}: `{key}` differs from SIL"
        );
    }
}

fn run(args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_dexter"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "dexter {args:?} failed ({}):\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

/// The HIL figures of a summary: top level (line, planar, hopper) or under `hil` (arm).
fn hil_figures(v: &Value) -> &Value {
    v.get("hil").unwrap_or(v)
}

/// The four kinds with a scene, through the CLI, then the link check through the library.
#[test]
fn every_hosted_kind_runs_on_the_emulated_board_bit_for_bit_against_sil() {
    let elf = emulated_board_image();
    let session = symbol_address(&elf, "DEXTER_HOST_SESSION");
    let board = Emulator::boot(&elf, "board-hil");
    // (scene, events: short runs (an arm scene is one motion), where the summary counts
    // the control steps, the fewest it must count)
    let runs = [
        ("line-juggler", Some("3"), "/control_steps", 500),
        ("planar-triangle-sil", Some("3"), "/control_steps", 200),
        ("hopper-raibert-sil", Some("2"), "/control_steps", 500),
        ("arm-throw", None, "/tracked/steps", 500),
    ];
    for (name, events, steps_at, min_steps) in runs {
        let path = scene(name);
        let mut args = vec!["run", &path, "--json"];
        if let Some(n) = events {
            args.extend(["--impacts", n]);
        }
        let sil = run(&args);
        args.extend(["--hil", "--port", &board.port]);
        let hil = run(&args);
        let figures = hil_figures(&hil);
        assert_eq!(figures["sil_mismatches"], 0, "{name}: {figures}");
        assert_eq!(figures["link_errors"], 0, "{name}: {figures}");
        assert_eq!(figures["link_timeouts"], 0, "{name}: {figures}");
        let steps = hil.pointer(steps_at).and_then(Value::as_u64).unwrap_or(0);
        assert!(steps >= min_steps, "{name}: {steps} steps: {hil}");
        // DWT's cycle counter reads 0 in QEMU 7.2: a non-zero figure means another machine.
        assert_eq!(figures["step_instructions_max"], 0, "{name}: {figures}");
        assert_same_outcome(name, &sil, &hil);
    }
    // Noise on the host link, and a Configure frame with one bit flipped, do not start a
    // host session: only a decoded, accepted Configure does. Written raw, as the HIL link
    // opens the port (a terminal's line discipline would rewrite bytes), after the runs
    // above, which must see a clean link (the firmware counts the noise's link errors).
    let mut configure =
        std::fs::read(workspace().join("boards/nucleo-f446re/scene.configure")).unwrap();
    configure[5] ^= 0x10;
    let mut vcp = serialport::new(board.port.as_str(), 921_600)
        .open_native()
        .expect("the board's pseudo-terminal");
    vcp.write_all(&[0x55, 0xAA, 0x00, 0x13, 0x37, 0x00])
        .unwrap();
    vcp.write_all(&configure).unwrap();
    vcp.flush().unwrap();
    // read the board's answers (refusals) until the line is quiet, so none is left for the
    // next session to take for its own (QEMU notices a reopened pty within a second)
    vcp.set_timeout(Duration::from_millis(300)).unwrap();
    let mut answers = Vec::new();
    let mut buf = [0u8; 256];
    let give_up = std::time::Instant::now() + Duration::from_secs(3);
    loop {
        match vcp.read(&mut buf) {
            Ok(n) => answers.extend_from_slice(&buf[..n]),
            Err(_) if answers.is_empty() && std::time::Instant::now() < give_up => {}
            Err(_) => break,
        }
    }
    assert!(!answers.is_empty(), "the board answers frames it refuses");
    drop(vcp);
    let no_session = board.word(session) & 0xff;
    assert_eq!(no_session, 0, "a host session without a valid Configure");
    let opts = HilOptions {
        serial: Some(SerialPortOptions::new(&board.port)),
        ..HilOptions::default()
    };
    let gain = -2.5f32;
    let mut hil = LockStep::<Echo>::start(EchoParams { gain }, opts).expect("Echo on the board");
    let session_started = board.word(session) & 0xff;
    assert_eq!(
        session_started, 1,
        "the accepted Configure starts the session"
    );
    assert_eq!(
        board.word(session) & 0xff,
        1,
        "the accepted Configure starts the session"
    );
    for seq in 0..200u32 {
        let value = seq as f32 * 0.25 - 7.0;
        let out = hil.step(&EchoFrame { seq, value }).expect("step").command;
        assert_eq!(out.fault, Fault::None, "{seq}");
        assert_eq!(out.value.to_bits(), (gain * value).to_bits(), "{seq}");
    }
    let report = hil.finish().expect("a clean Stop");
    assert_eq!(report.sil_mismatches, 0, "{report:?}");
}

/// TIM1 (the motor's PWM, QEMU's `timer[1]`) and GPIOA (PA8, the driver's PWM input):
/// registers and bits of RM0390 (sec. 8.4, 12.4).
const TIM1: &str = "timer[1]";
const TIM1_CCR1: u64 = 0x34;
const TIM1_BDTR: u64 = 0x44;
const BDTR_MOE: u64 = 1 << 15;
const BDTR_OSSI: u64 = 1 << 10;
const GPIOA: &str = "GPIOA";
const GPIO_MODER: u64 = 0x00;
const GPIO_BSRR: u64 = 0x18;
/// IWDG (RM0390 sec. 19.4): key, prescaler and reload registers, and the keys. QEMU 7.2
/// maps its unimplemented `I2S2ext` at the IWDG's address too, and names the region so.
const IWDG_KR: u64 = 0x0;
const IWDG_PR: u64 = 0x4;
const IWDG_RLR: u64 = 0x8;
const KEY_FEED: u64 = 0xAAAA;
const KEY_UNLOCK: u64 = 0x5555;
const KEY_START: u64 = 0xCCCC;
/// The LSI that clocks the IWDG, nominal, Hz (RM0390 sec. 6.2.5).
const LSI_HZ: f64 = 32_000.0;

fn is_iwdg(device: &str) -> bool {
    device == "IWDG" || device == "I2S2ext"
}

fn is(w: &DeviceWrite, device: &str, offset: u64) -> bool {
    w.device == device && w.offset == offset
}

/// The motor cut among `writes`: PA8 set low (BSRR's BR8) before it becomes a GPIO output
/// (MODER8 = 01), so it never drives high on the way; TIM1's duty 0 and its main output
/// off with OSSI (an off-state output held at its idle level). After the cut, nothing
/// drives the motor again: no duty, no output enable, PA8 not handed back to TIM1.
fn assert_motor_cut(what: &str, writes: &[DeviceWrite]) {
    let find = |device: &str, offset: u64, ok: &dyn Fn(u64) -> bool| {
        writes
            .iter()
            .position(|w| is(w, device, offset) && w.value.is_some_and(ok))
            .unwrap_or_else(|| panic!("{what}: no {device} write at {offset:#x}: {writes:?}"))
    };
    let low = find(GPIOA, GPIO_BSRR, &|v| v == 1 << 24);
    let output = find(GPIOA, GPIO_MODER, &|v| (v >> 16) & 0b11 == 0b01);
    let duty_zero = find(TIM1, TIM1_CCR1, &|v| v == 0);
    let outputs_idle = find(TIM1, TIM1_BDTR, &|v| {
        v & BDTR_MOE == 0 && v & BDTR_OSSI != 0
    });
    assert!(
        low < output,
        "{what}: PA8 became an output before it was set low"
    );
    let cut = low.max(output).max(duty_zero).max(outputs_idle);
    for w in &writes[cut + 1..] {
        let v = w.value.unwrap_or(0);
        let drives = (is(w, TIM1, TIM1_CCR1) && v != 0)
            || (is(w, TIM1, TIM1_BDTR) && v & BDTR_MOE != 0)
            || (is(w, GPIOA, GPIO_MODER) && (v >> 16) & 0b11 != 0b01)
            || (is(w, GPIOA, GPIO_BSRR) && v & (1 << 8) != 0);
        assert!(!drives, "{what}: the motor is driven after the cut: {w:?}");
    }
}

/// The juggling loop's IWDG and motor writes on a board that has just booted: DBGMCU's
/// three registers written, the watchdog started with a 20 ms timeout at the LSI's nominal
/// 32 kHz (`WATCHDOG_MS`) and fed; the duties it commands returned.
fn assert_the_watchdog_runs(writes: &[DeviceWrite]) {
    for register in [0x42004, 0x42008, 0x4200c] {
        assert!(
            writes.iter().any(|w| is(w, "PPB", register)),
            "DBGMCU at {register:#x} is not written at boot"
        );
    }
    let iwdg: Vec<(u64, u64)> = writes
        .iter()
        .filter(|w| is_iwdg(&w.device))
        .map(|w| (w.offset, w.value.unwrap()))
        .collect();
    let at = |want: (u64, u64)| iwdg.iter().position(|&w| w == want);
    let (unlock, start) = (at((IWDG_KR, KEY_UNLOCK)), at((IWDG_KR, KEY_START)));
    assert!(
        unlock.is_some() && start.is_some(),
        "IWDG not started: {iwdg:?}"
    );
    let register = |offset| iwdg.iter().find(|w| w.0 == offset).map(|w| w.1).unwrap();
    let (prescaler, reload) = (register(IWDG_PR), register(IWDG_RLR));
    let timeout_s = (reload + 1) as f64 * (4u64 << prescaler) as f64 / LSI_HZ;
    assert!(
        (timeout_s - 0.020).abs() < 1e-9,
        "IWDG timeout {timeout_s} s"
    );
    assert!(feeds(writes) > 10, "the control task feeds the watchdog");
}

/// How many times `writes` feed the watchdog.
fn feeds(writes: &[DeviceWrite]) -> usize {
    writes
        .iter()
        .filter(|w| is_iwdg(&w.device) && w.offset == IWDG_KR && w.value == Some(KEY_FEED))
        .count()
}

/// The duties (TIM1's CCR1) `writes` command.
fn duties(writes: &[DeviceWrite]) -> Vec<u64> {
    writes
        .iter()
        .filter(|w| is(w, TIM1, TIM1_CCR1))
        .filter_map(|w| w.value)
        .collect()
}

/// Each fault path ends with the motor's outputs at their idle level, read from the writes
/// QEMU logs to TIM1 and GPIOA (devices it does not model, so it logs them):
/// - a HardFault, a panic, a stack overflow, an NMI, an unhandled interrupt and a limit
///   switch's interrupt: a byte `0xF1..=0xF5`, `0xF7` on USART1 provokes one (`fault_hooks.rs`, `qemu-hsi` only), and
///   `fault::DEXTER_MOTOR_OFF` holds its cause. The stack overflow ends in a HardFault
///   only because the MPU guard leaves it room to stack its frame: without the guard the
///   core locks up and the word stays 0;
/// - a hung control task (`0xF6`): the watchdog's feeds and the duties stop. QEMU models
///   neither the IWDG's expiry nor RCC's reset flags; the test boots the image again with
///   the hook's stand-in for RCC's watchdog flag set, and the board keeps the motor parked
///   at duty 0 while it feeds the watchdog again (after a plain boot it drives the motor).
///   Before that, the log shows the watchdog started with a 20 ms timeout and DBGMCU's
///   three registers written (their values: `tests/board.rs`).
///
/// (`tests/board.rs` checks on the linked image that each handler calls the cut first, and
/// that only the control task feeds the watchdog.)
#[test]
fn each_fault_path_on_the_emulated_board_ends_with_the_motor_off() {
    let elf = emulated_board_image();
    let motor_off = symbol_address(&elf, "DEXTER_MOTOR_OFF");
    let mut board = Emulator::boot_logging_devices(&elf, "board-faults", &[]);
    std::thread::sleep(Duration::from_millis(1000));
    let booted = board.writes_since(0);
    assert_the_watchdog_runs(&booted);
    assert!(
        duties(&booted).iter().any(|&d| d != 0),
        "the juggling loop drives the motor after a plain boot"
    );
    board.camera.write_all(&[0xF6]).unwrap();
    std::thread::sleep(Duration::from_millis(200));
    let mark = board.log_mark();
    std::thread::sleep(Duration::from_millis(700));
    let hung = board.writes_since(mark);
    assert_eq!(
        feeds(&hung),
        0,
        "a hung control task still feeds the watchdog"
    );
    assert!(
        duties(&hung).is_empty(),
        "a hung control task still drives the motor"
    );

    // (hook byte, Cause as u32 in boards/nucleo-f446re/src/fault.rs, what)
    let faults = [
        (0xF1, 1, "HardFault from a bus error"),
        (0xF2, 2, "panic"),
        (0xF3, 1, "stack overflow"),
        (0xF4, 3, "NMI"),
        (0xF5, 4, "unhandled interrupt"),
        (0xF7, 5, "limit switch"),
    ];
    for (byte, cause, what) in faults {
        board.monitor("system_reset");
        assert!(
            board.word_becomes(motor_off, 0, BOOT_TIMEOUT),
            "{what}: the board did not boot again"
        );
        std::thread::sleep(Duration::from_millis(300)); // init enables USART1's interrupt
        let mark = board.log_mark();
        board.camera.write_all(&[byte]).unwrap();
        assert!(
            board.word_becomes(motor_off, cause, Duration::from_secs(5)),
            "{what}: DEXTER_MOTOR_OFF is {}, not {cause}",
            board.word(motor_off)
        );
        std::thread::sleep(Duration::from_millis(300));
        assert_motor_cut(what, &board.writes_since(mark));
    }
    drop(board);

    // The watchdog's reset, with RCC's flag as the hook's stand-in (a fresh QEMU: its
    // TIM2 does not tick again after an emulated reset, firmware/README.md, "Emulation").
    let flag = symbol_address(&elf, "DEXTER_EMULATED_WATCHDOG_RESET");
    let board = Emulator::boot_logging_devices(&elf, "board-watchdog", &[(flag, 0x5744_4f47)]);
    std::thread::sleep(Duration::from_millis(1000));
    let parked = board.writes_since(0);
    assert_the_watchdog_runs(&parked);
    let duty = duties(&parked);
    assert!(
        duty.len() > 10,
        "the control task keeps the motor parked: {duty:?}"
    );
    assert!(
        duty.iter().all(|&d| d == 0),
        "after a watchdog reset the motor is driven: duties {duty:?}"
    );
}

/// One camera frame as the camera sends it (firmware/README.md, step 4): `A5 5A seq flags
/// x y crc8`, x and y in 1/16 px (u16 LE), flags bit 0 = ball found, CRC-8/SMBUS (poly
/// 0x07, init 0) over the six bytes from `seq`. Written here from that description, not
/// with the drivers' encoder.
fn camera_frame(seq: u8, found: bool, x_px16: u16, y_px16: u16) -> Vec<u8> {
    let mut body = vec![seq, u8::from(found)];
    body.extend(x_px16.to_le_bytes());
    body.extend(y_px16.to_le_bytes());
    let mut crc = 0u8;
    for &b in &body {
        crc ^= b;
        for _ in 0..8 {
            crc = if crc & 0x80 != 0 {
                (crc << 1) ^ 0x07
            } else {
                crc << 1
            };
        }
    }
    [vec![0xA5, 0x5A], body, vec![crc]].concat()
}

/// The calibration image (`--features calibrate`) reads the camera's frames raw (row and
/// column as sent, in `DEXTER_CALIBRATION`), feeds the watchdog, and never drives the
/// motor: every duty it writes to TIM1 is 0.
#[test]
fn the_calibration_image_reads_the_sensors_raw_and_never_drives_the_motor() {
    let elf = emulated_image_with("qemu-hsi,calibrate");
    let readout = symbol_address(&elf, "DEXTER_CALIBRATION");
    let mut board = Emulator::boot_logging_devices(&elf, "board-calibrate", &[]);
    std::thread::sleep(Duration::from_millis(300)); // init enables USART1's interrupt
    let (x, y) = (5144, 1972); // 321.5 px, 123.25 px
    board
        .camera
        .write_all(&camera_frame(7, true, x, y))
        .unwrap();
    assert!(
        board.word_becomes(readout + 4, 1, Duration::from_secs(5)),
        "the calibration image parsed no frame: {} frames",
        board.word(readout + 4)
    );
    assert_eq!(board.word(readout + 8), u32::from(y), "row, 1/16 px");
    assert_eq!(board.word(readout + 12), u32::from(x), "column, 1/16 px");
    assert_eq!(board.word(readout + 16), 1, "ball found");
    std::thread::sleep(Duration::from_millis(500));
    let writes = board.writes_since(0);
    let duty = duties(&writes);
    assert!(
        feeds(&writes) > 10,
        "the calibration image feeds the watchdog"
    );
    assert!(
        duty.len() > 10,
        "the control task keeps the motor parked: {duty:?}"
    );
    assert!(
        duty.iter().all(|&d| d == 0),
        "the calibration image drives the motor: {duty:?}"
    );
}

/// `dexter board`: the camera the board's stand-alone loop needs for a scene. The line
/// juggler's scene steps at 500 Hz, and the core faults `Stale` after more than
/// `stale_limit_steps` (5 by default, `ControllerParams::default`) periods without a new
/// image: at least 500 / 5 = 100 frames/s; the estimator compensates `sensor.latency_s`
/// (4 ms in the scene). `--write` writes the Configure frame (the checked-in
/// `boards/nucleo-f446re/scene.configure` for this scene, which `tests/board.rs` checks
/// against the image); a scene of another system, or another control rate, is refused
/// naming the key (exit 2).
#[test]
fn board_prints_the_camera_the_scene_needs_and_writes_its_configure() {
    let dir = common::scratch("board-verb");
    let out = dir.join("scene.configure");
    let v = run(&[
        "board",
        &scene("line-juggler"),
        "--json",
        "--write",
        out.to_str().unwrap(),
    ]);
    assert_eq!(v["control_rate_hz"], 500.0, "{v}");
    assert_eq!(v["camera_min_rate_fps"], 100.0, "{v}");
    assert_eq!(v["camera_max_interval_s"], 0.01, "{v}");
    assert!(
        (v["camera_latency_s"].as_f64().unwrap() - 0.004).abs() < 1e-9,
        "{v}"
    );
    let checked_in = workspace().join("boards/nucleo-f446re/scene.configure");
    assert_eq!(
        std::fs::read(&out).unwrap(),
        std::fs::read(checked_in).unwrap()
    );
    assert_eq!(v["configure_bytes"], std::fs::read(&out).unwrap().len());
    // a longer stale limit asks less of the camera: 500 / 20 = 25 frames/s
    let v = run(&[
        "board",
        &scene("line-juggler"),
        "--json",
        "--set",
        "control.stale_limit_steps=20",
    ]);
    assert_eq!(v["camera_min_rate_fps"], 25.0, "{v}");
    for (args, names) in [
        (vec!["--set", "control.rate_hz=400"], "control.rate_hz"),
        (vec![], "arm"),
    ] {
        let path = if names == "arm" {
            scene("arm-throw")
        } else {
            scene("line-juggler")
        };
        let mut all = vec!["board", path.as_str()];
        all.extend(args);
        let out = common::dexter(&all);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains(names), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
