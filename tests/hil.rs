//! Hardware in the loop: the firmware in QEMU (`mps2-an386`, Cortex-M4F) stepped in
//! lock-step with a plant on the host, checked bit for bit against the core linked in.
//!
//! These tests never skip: without `qemu-system-arm` or the `thumbv7em-none-eabihf` target
//! they fail and say what to install. The firmware is built once per test binary with
//! `hil::build_firmware()`.
//!
//! The main test runs the shipped scene `scenes/line-juggler.toml` through the simulator's
//! own run loop (noisy delayed sensor, limited actuator) with the firmware closing the loop,
//! and checks it against the same run in SIL. Other tests use a minimal exact plant (closed
//! form per control period: a ballistic ball and a double-integrator paddle driven by the
//! command, impacts with restitution) to exercise links and faults.
//!
//! Golden files: `firmware/expected/smoke.txt` (decoded defmt output of the smoke run that
//! `cargo fw` boots) and `firmware/expected/sizes.txt` (text/data/bss of the release ELF).
//! Regenerate them on purpose with `DEXTER_BLESS=1 cargo test -p dexter-tests --test hil`.

use dexter_core::control::{Controller, ControllerParams};
use dexter_core::protocol::{Fault, Mode, SensorFrame};
use dexter_sim::controller::{StepController, StepOutput};
use dexter_sim::hil::{self, HilOptions, LinkKind, LockStep};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::Duration;

/// Build the firmware once for all tests of this binary (or fail saying what is missing).
fn firmware() -> PathBuf {
    static ELF: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    ELF.get_or_init(|| hil::build_firmware().map_err(|e| e.to_string()))
        .clone()
        .unwrap_or_else(|e| panic!("HIL tests need the firmware: {e}"))
}

fn options(link: LinkKind) -> HilOptions {
    HilOptions {
        firmware_elf: firmware(),
        link,
        timeout: Duration::from_secs(20),
        ..HilOptions::default()
    }
}

/// The shipped realistic scene, run by the simulator's loop with the firmware in QEMU,
/// for at least 100 impacts: it converges to within 1 % of the target apex, every command is
/// bit-identical to the core's (so the whole trajectory equals the SIL run's, bit for bit,
/// since the plant and its seeded noise are deterministic), and every step is within the
/// instruction budget of 300.
#[test]
fn line_juggler_scene_in_hil_converges_and_equals_sil_bit_for_bit() {
    use dexter_sim::report::converged_after;
    use dexter_sim::run::{run_scene, RunOptions};
    use dexter_sim::scene::Scene;

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/line-juggler.toml");
    let overrides = [("stop.impacts".to_string(), toml::Value::Integer(120))];
    let scene = Scene::load(&path, &overrides).expect("the shipped scene loads");
    let run_opts = RunOptions {
        record_rows: true,
        ..RunOptions::default()
    };
    let sil = run_scene(&scene, &run_opts, None).expect("SIL run");

    let params = scene.controller_params().expect("controller params");
    let mut lock = LockStep::start(params, options(LinkKind::Semihosting)).expect("QEMU starts");
    let hil_out = run_scene(
        &scene,
        &run_opts,
        Some(&mut lock as &mut dyn StepController),
    )
    .expect("HIL run");
    let report = lock.finish().expect("firmware ends cleanly");

    assert!(hil_out.impacts >= 100, "only {} impacts", hil_out.impacts);
    let target = f64::from(params.target_apex_m);
    let converged = converged_after(&hil_out.apexes_m, target, 0.01);
    assert!(converged.is_some(), "HIL run never converged within 1 %");
    let tail = &hil_out.apexes_m[converged.unwrap() as usize..];
    assert!(tail.iter().all(|a| (a - target).abs() <= 0.01 * target));

    assert_eq!(
        report.sil_mismatches, 0,
        "firmware commands differ from the core's"
    );
    assert_eq!(report.over_budget_steps, 0);
    assert!(report.step_instructions_max <= 300, "{report:?}");
    assert_eq!(report.link_errors, 0);
    assert_eq!(hil_out.control_steps, sil.control_steps);
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(
        bits(&hil_out.apexes_m),
        bits(&sil.apexes_m),
        "HIL and SIL trajectories differ"
    );
}

/// A ballistic ball over a double-integrator paddle, exact per control period.
struct BallPaddle {
    g: f64,
    restitution: f64,
    ball: (f64, f64),
    paddle: (f64, f64),
    /// Apex predicted at each take-off (closed form `b + v^2 / 2g`).
    apexes: Vec<f64>,
    impacts: u64,
}

impl BallPaddle {
    fn new(params: &ControllerParams, ball_height_m: f64) -> Self {
        Self {
            g: f64::from(params.gravity_mps2),
            restitution: f64::from(params.estimator.restitution),
            ball: (ball_height_m, 0.0),
            paddle: (f64::from(params.home_height_m), 0.0),
            apexes: Vec::new(),
            impacts: 0,
        }
    }

    fn sense(&self, seq: u32) -> SensorFrame {
        SensorFrame {
            seq,
            ball_height_m: self.ball.0 as f32,
            paddle_height_m: self.paddle.0 as f32,
            paddle_velocity_mps: self.paddle.1 as f32,
        }
    }

    /// Advance `dt` with paddle acceleration `u` held.
    fn advance(&mut self, u: f64, dt: f64) {
        let g = self.g;
        let mut left = dt;
        for _ in 0..8 {
            let (b, vb) = self.ball;
            let (p, vp) = self.paddle;
            // gap d(t) = (b - p) + (vb - vp) t - (g + u) t^2 / 2
            let (d0, d1, d2) = (b - p, vb - vp, -(g + u) / 2.0);
            let hit = first_root(d0, d1, d2, left);
            let t = hit.unwrap_or(left);
            self.ball = (b + vb * t - 0.5 * g * t * t, vb - g * t);
            self.paddle = (p + vp * t + 0.5 * u * t * t, vp + u * t);
            left -= t;
            if hit.is_none() {
                return;
            }
            // impact: relative velocity reverses with restitution
            let (_, vb) = self.ball;
            let (p, vp) = self.paddle;
            let vb_plus = vp + self.restitution * (vp - vb);
            self.ball = (p, vb_plus.max(vp));
            self.impacts += 1;
            if vb_plus > 0.0 {
                self.apexes.push(p + vb_plus * vb_plus / (2.0 * g));
            }
            if left <= 0.0 {
                return;
            }
        }
        // resting contact: carry the ball with the paddle for the rest of the period
        let (p, vp) = self.paddle;
        self.paddle = (p + vp * left + 0.5 * u * left * left, vp + u * left);
        self.ball = self.paddle;
    }
}

/// First root in (0, t_max] of d0 + d1 t + d2 t^2 where the gap closes (d0 >= 0).
fn first_root(d0: f64, d1: f64, d2: f64, t_max: f64) -> Option<f64> {
    if d0 < 0.0 {
        return Some(f64::MIN_POSITIVE); // already penetrating: impact now
    }
    let gap = |t: f64| d0 + d1 * t + d2 * t * t;
    if gap(t_max) > 0.0 && !(d2 > 0.0 && d1 < 0.0) {
        return None;
    }
    let roots = if d2.abs() < 1e-300 {
        if d1 == 0.0 {
            vec![]
        } else {
            vec![-d0 / d1]
        }
    } else {
        let disc = d1 * d1 - 4.0 * d2 * d0;
        if disc < 0.0 {
            vec![]
        } else {
            let s = disc.sqrt();
            // numerically stable pair
            let q = -0.5 * (d1 + d1.signum() * s);
            let mut r = vec![q / d2];
            if q != 0.0 {
                r.push(d0 / q);
            }
            r
        }
    };
    roots
        .into_iter()
        .filter(|&t| t > 0.0 && t <= t_max && d1 + 2.0 * d2 * t <= 0.0)
        .fold(None, |best: Option<f64>, t| {
            Some(best.map_or(t, |b| b.min(t)))
        })
        .or_else(|| (d0 == 0.0 && d1 < 0.0).then_some(f64::MIN_POSITIVE))
}

/// Close the loop for `steps` periods.
fn run_plant(
    controller: &mut dyn StepController,
    plant: &mut BallPaddle,
    params: &ControllerParams,
    steps: u32,
) -> Vec<StepOutput> {
    let dt = f64::from(params.dt_s);
    let mut outputs = Vec::with_capacity(steps as usize);
    for seq in 0..steps {
        let out = controller
            .step(&plant.sense(seq))
            .unwrap_or_else(|e| panic!("step {seq}: {e}"));
        plant.advance(f64::from(out.command.paddle_accel_mps2), dt);
        outputs.push(out);
    }
    outputs
}

#[test]
fn firmware_builds_for_the_target() {
    let elf = firmware();
    assert!(elf.is_file(), "{} missing after build", elf.display());
    let bytes = std::fs::read(&elf).unwrap();
    assert_eq!(&bytes[..4], b"\x7fELF");
    assert_eq!(
        u16::from_le_bytes([bytes[18], bytes[19]]),
        40,
        "not an ARM ELF"
    );
}

#[test]
fn lockstep_semihosting_is_bit_exact_and_juggles_to_the_target_apex() {
    let params = ControllerParams::default();
    let mut hil = LockStep::start(params, options(LinkKind::Semihosting)).expect("start HIL");
    let mut plant = BallPaddle::new(&params, 1.2);
    let steps = 10_000; // 20 s at 500 Hz
    let outputs = run_plant(&mut hil, &mut plant, &params, steps);
    if let Some(m) = hil.first_mismatch() {
        panic!("firmware and SIL disagree: {m}");
    }
    // defmt logs come on their own channel and decode with the ELF
    let log = hil.firmware_log_text().expect("decode the firmware log");
    assert!(
        log.contains("INFO dexter-firmware 0.1.0 on mps2-an386: Semihosting\n")
            && log.contains("INFO configured: dt_s=0.002 target_apex_m=1.0\n"),
        "{log}"
    );
    let report = hil.finish().expect("firmware ended the run cleanly");
    eprintln!("semihosting lock-step: {report:?}");
    assert_eq!(report.sil_mismatches, 0);
    assert_eq!(report.over_budget_steps, 0);
    assert_eq!(report.link_errors, 0);
    assert_eq!(report.link_timeouts, 0);
    assert!(report.step_instructions_min > 0);
    assert!(report.step_instructions_max <= hil::DEFAULT_INSTRUCTION_BUDGET);
    assert!(outputs.iter().all(|o| o.command.fault == Fault::None));
    assert_eq!(outputs.last().unwrap().command.mode, Mode::Track);
    assert!(plant.impacts > 20, "only {} impacts", plant.impacts);
    let target = f64::from(params.target_apex_m);
    let settled = &plant.apexes[plant.apexes.len() / 2..];
    for apex in settled {
        assert!(
            (apex - target).abs() <= 0.03 * target,
            "apex {apex:.4} m not within 3 % of {target} m (apexes after settling: {settled:?})"
        );
    }
}

#[test]
fn uart_link_runs_end_to_end() {
    let params = ControllerParams::default();
    let mut hil = LockStep::start(params, options(LinkKind::Uart)).expect("start HIL over UART");
    let mut plant = BallPaddle::new(&params, 1.2);
    let outputs = run_plant(&mut hil, &mut plant, &params, 600);
    let report = hil.finish().expect("firmware ended the run cleanly");
    eprintln!("UART lock-step: {report:?}");
    assert_eq!(report.sil_mismatches, 0);
    assert_eq!(report.over_budget_steps, 0);
    assert_eq!(report.link_errors, 0);
    assert_eq!(outputs.last().unwrap().command.mode, Mode::Track);
    assert!(plant.impacts >= 1);
}

#[test]
fn corrupted_bytes_are_rejected_and_lost_frames_give_the_safe_state() {
    let params = ControllerParams::default();
    let opts = HilOptions {
        corrupt_rate: 0.01,
        ..options(LinkKind::Semihosting)
    };
    let mut hil = LockStep::start(params, opts).expect("start HIL");
    let mut plant = BallPaddle::new(&params, 1.2);
    let outputs = run_plant(&mut hil, &mut plant, &params, 4000);
    let corrupted_accepted = hil.corrupted_frames_accepted();
    if let Some(m) = hil.first_mismatch() {
        panic!("firmware and SIL disagree: {m}");
    }
    let report = hil
        .finish()
        .expect("no panic: the firmware ended the run cleanly");
    eprintln!("1 % corrupted bytes: {report:?}");
    assert!(report.link_errors > 0, "no link errors counted");
    assert_eq!(corrupted_accepted, 0, "a corrupted frame passed the CRC");
    // every answer, including the safe ones, equals the core's bit for bit
    assert_eq!(report.sil_mismatches, 0);
    assert!(report.link_timeouts > 0);
    let safe: Vec<_> = outputs
        .iter()
        .filter(|o| o.command.fault == Fault::LinkTimeout)
        .collect();
    assert!(
        !safe.is_empty(),
        "no LinkTimeout safe command reached the plant"
    );
    assert!(safe.iter().all(|o| o.command.mode == Mode::Safe));
}

#[test]
fn a_host_side_timeout_is_a_link_error_with_a_clear_message() {
    // QEMU cannot boot and connect its UART within 1 ms: the host gives up with a
    // `ControllerError::Link` that says what it waited for (and QEMU is killed).
    let opts = HilOptions {
        timeout: Duration::from_millis(1),
        ..options(LinkKind::Uart)
    };
    match LockStep::start(ControllerParams::default(), opts) {
        Err(e) => {
            let msg = e.to_string();
            assert!(msg.contains("timeout") || msg.contains("QEMU"), "{msg}");
        }
        Ok(_) => panic!("a 1 ms timeout should not be enough to boot and configure"),
    }
}

// ---- golden files -------------------------------------------------------------------------

fn expected_dir() -> PathBuf {
    hil::workspace_root().join("firmware").join("expected")
}

fn bless() -> bool {
    std::env::var_os("DEXTER_BLESS").is_some_and(|v| !v.is_empty() && v != "0")
}

fn check_golden(name: &str, actual: &str) {
    let path = expected_dir().join(name);
    if bless() {
        std::fs::create_dir_all(expected_dir()).unwrap();
        std::fs::write(&path, actual).unwrap();
        eprintln!("blessed {}", path.display());
        return;
    }
    let expected = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; create it with DEXTER_BLESS=1 cargo test -p dexter-tests --test hil",
            path.display()
        )
    });
    if expected != actual {
        panic!(
            "{} differs from this build (regenerate on purpose with DEXTER_BLESS=1):\n--- expected\n{expected}\n--- actual\n{actual}",
            path.display()
        );
    }
}

fn decode_defmt(elf: &Path, bytes: &[u8]) -> String {
    hil::decode_defmt_log(elf, bytes).unwrap_or_else(|e| panic!("{e}"))
}

/// text / data / bss of an ELF32 the way `size` (Berkeley) counts them.
fn elf_sizes(elf: &Path) -> (u64, u64, u64) {
    let b = std::fs::read(elf).unwrap();
    let u16_at = |o: usize| u16::from_le_bytes([b[o], b[o + 1]]) as usize;
    let u32_at = |o: usize| u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]) as u64;
    assert_eq!(b[4], 1, "ELF32 expected");
    let shoff = u32_at(0x20) as usize;
    let (shentsize, shnum) = (u16_at(0x2e), u16_at(0x30));
    let (mut text, mut data, mut bss) = (0, 0, 0);
    for i in 0..shnum {
        let h = shoff + i * shentsize;
        let (sh_type, flags, size) = (u32_at(h + 4), u32_at(h + 8), u32_at(h + 20));
        const ALLOC: u64 = 2;
        const WRITE: u64 = 1;
        const NOBITS: u64 = 8;
        if flags & ALLOC == 0 {
            continue;
        }
        if sh_type == NOBITS {
            bss += size;
        } else if flags & WRITE != 0 {
            data += size;
        } else {
            text += size;
        }
    }
    (text, data, bss)
}

/// Boot `elf` in QEMU as the `cargo fw` runner in .cargo/config.toml does (semihosting on,
/// UART unused, `-icount shift=10`), with an optional boot word, and wait for it to exit.
fn qemu_semihosting(elf: &Path, boot_word: Option<&str>) -> std::process::Output {
    let mut cmd = Command::new(hil::QEMU);
    cmd.args([
        "-machine",
        hil::QEMU_MACHINE,
        "-nographic",
        "-monitor",
        "none",
    ])
    .args(["-serial", "null", "-icount", "shift=10"])
    .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
    .arg(elf);
    if let Some(word) = boot_word {
        cmd.args(["-append", word]);
    }
    cmd.stdin(Stdio::null())
        .output()
        .expect("run qemu-system-arm")
}

#[test]
fn smoke_run_output_and_sizes_match_the_expected_files() {
    let elf = firmware();
    // The same command line as the `cargo fw` runner in .cargo/config.toml.
    let out = qemu_semihosting(&elf, None);
    let mut log = decode_defmt(&elf, &out.stdout);
    log.push_str(&format!(
        "exit status {}\n",
        out.status.code().unwrap_or(-1)
    ));
    let (text, data, bss) = elf_sizes(&elf);
    let sizes = format!(
        "# dexter-firmware release ELF ({}), bytes; flash = text + data, static RAM = data + bss\n\
         text {text}\ndata {data}\nbss {bss}\nflash {}\nstatic_ram {}\n",
        hil::TARGET,
        text + data,
        data + bss
    );
    check_golden("smoke.txt", &log);
    check_golden("sizes.txt", &sizes);
    assert!(out.status.success(), "smoke run failed:\n{log}");
}

// ---- benchmark figures (BENCHMARKS.md, "## Firmware") -----------------------------------

/// Run the lock-step juggle on `elf` and summarise it against the libm core on the host.
fn bench_run(elf: &Path, link: LinkKind, steps: u32) -> String {
    let params = ControllerParams::default();
    let opts = HilOptions {
        firmware_elf: elf.to_path_buf(),
        link,
        instruction_budget: None,
        timeout: Duration::from_secs(20),
        ..HilOptions::default()
    };
    let mut hil = LockStep::start(params, opts).expect("start HIL");
    let mut plant = BallPaddle::new(&params, 1.2);
    let mut max_du = 0.0f64;
    let mut reference = dexter_sim::controller::Sil::<Controller>::new(params).unwrap();
    let dt = f64::from(params.dt_s);
    for seq in 0..steps {
        let frame = plant.sense(seq);
        let out = hil
            .step(&frame)
            .unwrap_or_else(|e| panic!("step {seq}: {e}"));
        let sil = reference.step(&frame).unwrap();
        max_du = max_du
            .max(f64::from(out.command.paddle_accel_mps2 - sil.command.paddle_accel_mps2).abs());
        plant.advance(f64::from(out.command.paddle_accel_mps2), dt);
    }
    let report = hil.finish().expect("clean end");
    let target = f64::from(params.target_apex_m);
    let settled = &plant.apexes[plant.apexes.len() / 2..];
    let apex_err = settled
        .iter()
        .map(|a| (a - target).abs() / target)
        .fold(0.0f64, f64::max);
    format!(
        "{:?} link, {steps} steps: instructions/step min {} mean {:.1} max {}; \
         commands differing from the libm core: {} (max |du| {:.3e} m/s^2); \
         settled apex error max {:.3} %; {:.0} steps per wall second",
        link,
        report.step_instructions_min,
        report.step_instructions_mean,
        report.step_instructions_max,
        report.sil_mismatches,
        max_du,
        100.0 * apex_err,
        report.steps_per_wall_second
    )
}

#[test]
#[ignore = "benchmark figures for BENCHMARKS.md: run scripts/hil-bench.sh (builds the variants)"]
fn bench_figures() {
    let dir = std::env::var_os("DEXTER_BENCH_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| hil::workspace_root().join("target").join("hil-bench"));
    for variant in ["libm", "fast-math"] {
        let elf = dir.join(format!("{variant}.elf"));
        println!(
            "[{variant}] {}",
            bench_run(&elf, LinkKind::Semihosting, 10_000)
        );
        println!("[{variant}] {}", bench_run(&elf, LinkKind::Uart, 2_000));
    }
    let elf = dir.join("bench.elf");
    let out = qemu_semihosting(&elf, Some("bench"));
    print!("[bench]\n{}", decode_defmt(&elf, &out.stdout));
    assert!(out.status.success());
    for variant in ["libm", "fast-math", "bench"] {
        let (text, data, bss) = elf_sizes(&dir.join(format!("{variant}.elf")));
        println!(
            "[{variant}] text {text} data {data} bss {bss}: flash {} static RAM {}",
            text + data,
            data + bss
        );
    }
}

// ---- free-running mode ---------------------------------------------------------------------

#[test]
fn free_running_mode_times_out_to_the_safe_state_on_systick_periods() {
    use dexter_core::protocol::{encode, DeviceMessage, FrameDecoder, HostMessage, MAX_FRAME_LEN};
    use std::io::{Read, Write};
    use std::net::TcpListener;
    let elf = firmware();
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let qemu = Command::new(hil::QEMU)
        .args([
            "-machine",
            hil::QEMU_MACHINE,
            "-nographic",
            "-monitor",
            "none",
        ])
        .args(["-icount", "shift=10"])
        .args(["-semihosting-config", "enable=on,target=native"])
        .args([
            "-chardev",
            &format!("socket,id=u,host=127.0.0.1,port={port},nodelay=on"),
        ])
        .args(["-serial", "chardev:u", "-kernel"])
        .arg(&elf)
        .args(["-append", "freerun"])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("run qemu-system-arm");
    struct Kill(std::process::Child);
    impl Drop for Kill {
        fn drop(&mut self) {
            let _ = self.0.kill();
            let _ = self.0.wait();
        }
    }
    let mut qemu_guard = Kill(qemu);
    let (mut sock, _) = listener.accept().unwrap();
    sock.set_nodelay(true).unwrap();
    sock.set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    let send = |sock: &mut std::net::TcpStream, m: &HostMessage| {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode(m, &mut buf).unwrap();
        sock.write_all(&buf[..n]).unwrap();
    };
    let mut decoder = FrameDecoder::<MAX_FRAME_LEN>::new();
    let mut pending = std::collections::VecDeque::new();
    let mut recv = |sock: &mut std::net::TcpStream| -> DeviceMessage {
        loop {
            if let Some(m) = pending.pop_front() {
                return m;
            }
            let mut buf = [0u8; 512];
            let n = sock.read(&mut buf).expect("firmware answers within 10 s");
            assert!(n > 0, "link closed");
            for &b in &buf[..n] {
                if let Some(r) = decoder.push::<DeviceMessage>(b) {
                    pending.push_back(r.expect("clean device-to-host frame"));
                }
            }
        }
    };
    let params = ControllerParams::default();
    send(&mut sock, &HostMessage::Configure(params));
    assert_eq!(recv(&mut sock), DeviceMessage::Configured { ok: true });
    let frame = |seq| SensorFrame {
        seq,
        ball_height_m: 0.5,
        paddle_height_m: 0.0,
        paddle_velocity_mps: 0.0,
    };
    send(&mut sock, &HostMessage::Sensor(frame(7)));
    // The frame is stepped in the period it arrives in; then, with no more frames, the
    // firmware answers each period after the timeout (5 periods) with the safe command.
    let mut seen_step = false;
    let mut first_safe = None;
    for _ in 0..10_000 {
        let DeviceMessage::Output { command, .. } = recv(&mut sock) else {
            panic!("unexpected message");
        };
        if command.fault == Fault::None && command.seq == 7 {
            seen_step = true;
        } else if command.fault == Fault::LinkTimeout && seen_step {
            // (safe answers before the frame arrived are expected too: the periods run
            // on virtual time, much faster than the host sends)
            assert_eq!(command.mode, Mode::Safe);
            first_safe = Some(command.seq);
            break;
        }
    }
    assert_eq!(
        first_safe,
        Some(7 + 5),
        "first safe command after 5 silent periods"
    );
    send(&mut sock, &HostMessage::Stop);
    let status = qemu_guard.0.wait().unwrap();
    assert!(status.success(), "firmware exit {status:?}");
}

// ---- failure paths -------------------------------------------------------------------------

fn boot(word: &str) -> (std::process::ExitStatus, String) {
    let elf = firmware();
    let out = qemu_semihosting(&elf, Some(word));
    (out.status, decode_defmt(&elf, &out.stdout))
}

#[test]
fn panic_and_hardfault_end_the_qemu_run_with_a_failure_status() {
    let (status, log) = boot("fault-panic");
    assert_eq!(status.code(), Some(1), "{log}");
    assert!(log.contains("ERROR panic at"), "{log}");
    let (status, log) = boot("fault-hardfault");
    assert_eq!(status.code(), Some(1), "{log}");
    assert!(log.contains("ERROR HardFault at pc="), "{log}");
}

#[test]
fn dropping_the_lockstep_kills_qemu() {
    let params = ControllerParams::default();
    let mut hil = LockStep::start(params, options(LinkKind::Semihosting)).expect("start HIL");
    let mut plant = BallPaddle::new(&params, 1.2);
    run_plant(&mut hil, &mut plant, &params, 10);
    let pid = hil.qemu_pid();
    assert!(Path::new(&format!("/proc/{pid}")).exists());
    drop(hil);
    assert!(
        !Path::new(&format!("/proc/{pid}")).exists(),
        "QEMU (pid {pid}) still running after drop"
    );
}

#[test]
fn a_silent_firmware_is_a_link_timeout_with_a_clear_message() {
    let params = ControllerParams::default();
    let opts = HilOptions {
        timeout: Duration::from_millis(500),
        ..options(LinkKind::Semihosting)
    };
    let mut hil = LockStep::start(params, opts).expect("start HIL");
    let pid = hil.qemu_pid();
    // SIGSTOP freezes QEMU: the firmware is alive but silent.
    let stopped = Command::new("kill")
        .args(["-STOP", &pid.to_string()])
        .status()
        .unwrap();
    assert!(stopped.success());
    let err = hil
        .step(&SensorFrame {
            seq: 0,
            ball_height_m: 1.0,
            ..SensorFrame::default()
        })
        .expect_err("a frozen firmware cannot answer");
    let msg = err.to_string();
    assert!(
        msg.contains("timeout: no answer from the firmware within 500ms"),
        "{msg}"
    );
    let _ = Command::new("kill")
        .args(["-CONT", &pid.to_string()])
        .status();
}

#[test]
fn garbage_and_non_finite_input_never_crash_the_firmware() {
    // 5 % of the bytes dropped or flipped (about 2 of 3 frames lost), and every 7th frame carries a NaN or an infinity:
    // the firmware keeps answering bit for bit like the core and ends the run cleanly.
    let params = ControllerParams::default();
    let opts = HilOptions {
        corrupt_rate: 0.05,
        ..options(LinkKind::Semihosting)
    };
    let mut hil = LockStep::start(params, opts).expect("start HIL");
    let mut faults = std::collections::BTreeSet::new();
    for seq in 0..3000u32 {
        let bad = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1e30][(seq / 7 % 4) as usize];
        let frame = SensorFrame {
            seq,
            ball_height_m: if seq % 7 == 0 { bad } else { 0.5 },
            paddle_height_m: 0.0,
            paddle_velocity_mps: if seq % 11 == 0 { bad } else { 0.0 },
        };
        let out = hil
            .step(&frame)
            .unwrap_or_else(|e| panic!("step {seq}: {e}"));
        faults.insert(out.command.fault as u8);
    }
    if let Some(m) = hil.first_mismatch() {
        panic!("firmware and SIL disagree: {m}");
    }
    let report = hil
        .finish()
        .expect("no panic: the firmware ended the run cleanly");
    eprintln!("5 % corrupted bytes, non-finite values: {report:?} faults seen {faults:?}");
    assert_eq!(report.sil_mismatches, 0);
    assert!(report.link_errors > 500);
    assert!(faults.contains(&(Fault::NonFinite as u8)));
    assert!(faults.contains(&(Fault::LinkTimeout as u8)));
}
