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
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(workspace())
        .args(["build", "-p", CRATE, "--release", "--target", TARGET])
        .args(["--features", "qemu-hsi"])
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "building {CRATE} --features qemu-hsi failed (install the target with `rustup target add {TARGET}`):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(|d| workspace().join(d))
        .unwrap_or_else(|| workspace().join("target"));
    let release = target.join(TARGET).join("release");
    let copy = release.join(format!("{CRATE}-qemu-hsi.elf"));
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

impl Emulator {
    /// Boot `elf` in netduinoplus2; the port is the one QEMU names on stdout ("char device
    /// redirected to /dev/pts/N").
    fn boot(elf: &Path, name: &str) -> Self {
        let dir = common::scratch(name);
        let (monitor, camera) = (dir.join("monitor.sock"), dir.join("camera.sock"));
        let unix = |p: &Path| format!("unix:{},server=on,wait=off", p.display());
        let mut qemu = Command::new("qemu-system-arm")
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

/// Each fault path the emulator can run ends with the motor cut, `fault::DEXTER_MOTOR_OFF`
/// holding its cause: a byte `0xF1..=0xF5` on USART1 provokes one (`fault_hooks.rs`,
/// `qemu-hsi` only), and the monitor resets the board between them. The stack overflow
/// ends in a HardFault only because the MPU guard leaves it room to stack its frame:
/// without the guard the core locks up and the word stays 0. (The motor cut itself writes
/// TIM1 and GPIOA, which QEMU does not model: `tests/board.rs` checks on the linked image
/// that each handler calls it first, and that only the control task feeds the watchdog.)
#[test]
fn each_fault_path_on_the_emulated_board_ends_with_the_motor_off() {
    let elf = emulated_board_image();
    let motor_off = symbol_address(&elf, "DEXTER_MOTOR_OFF");
    let mut board = Emulator::boot(&elf, "board-faults");
    // (hook byte, Cause as u32 in boards/nucleo-f446re/src/fault.rs, what)
    let faults = [
        (0xF1, 1, "HardFault from a bus error"),
        (0xF2, 2, "panic"),
        (0xF3, 1, "stack overflow"),
        (0xF4, 3, "NMI"),
        (0xF5, 4, "unhandled interrupt"),
    ];
    for (byte, cause, what) in faults {
        board.monitor("system_reset");
        // the reset handler zeroes .bss: the word is 0 once the image runs again
        assert!(
            board.word_becomes(motor_off, 0, BOOT_TIMEOUT),
            "{what}: the board did not boot again"
        );
        std::thread::sleep(Duration::from_millis(200)); // init enables USART1's interrupt
        board.camera.write_all(&[byte]).unwrap();
        assert!(
            board.word_becomes(motor_off, cause, Duration::from_secs(5)),
            "{what}: DEXTER_MOTOR_OFF is {}, not {cause}",
            board.word(motor_off)
        );
    }
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
