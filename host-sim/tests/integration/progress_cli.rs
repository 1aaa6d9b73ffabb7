//! Long runs show progress on a terminal, in what advances, with the bound that stops them
//! (issue 22, finding 10): a sampled hopper that stalls completes no cycle, so its bar must
//! move with simulated time. Run under `script(1)` (util-linux), which gives the binary a
//! terminal for stderr.

use crate::common;

use common::{scene, scratch};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The text a terminal shows of `args` during its first `secs` seconds (then it is stopped);
/// `tag` names the test's own scratch directory (tests run in parallel).
fn terminal_text(tag: &str, args: &[&str], secs: u64) -> String {
    let dir = scratch(&format!("progress-tty-{tag}"));
    let typescript = dir.join("typescript");
    let cmd = std::iter::once(env!("CARGO_BIN_EXE_dexter").to_string())
        .chain(args.iter().map(|a| format!("'{a}'")))
        .collect::<Vec<_>>()
        .join(" ");
    let mut child = Command::new("script")
        .args(["-qfec", &cmd])
        .arg(&typescript)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("script(1) runs (util-linux: apt-get install bsdutils)");
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(secs) {
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(100));
    }
    // stop script by PID; the run loses its terminal (SIGHUP) and ends
    let _ = child.kill();
    let _ = child.wait();
    let text = std::fs::read_to_string(&typescript).unwrap_or_default();
    let _ = std::fs::remove_dir_all(dir);
    text
}

#[test]
fn a_stalled_sampled_hopper_shows_simulated_time_and_its_bound() {
    // a thrust too weak to hop: no cycle completes, the run goes on to its time bound
    let text = terminal_text(
        "hopper",
        &[
            "run",
            &scene("hopper-raibert-sil"),
            "--set",
            "hopper.thrust_tau_mps2=10",
            "--set",
            "hopper.thrust_delta_s=0.001",
            "--set",
            "hopper.cycles=1000000",
        ],
        4,
    );
    // both bounds: the cycles asked for, and the time cap (10^9 steps at 1 kHz)
    assert!(text.contains(" of 1000000 cycles"), "{text}");
    assert!(text.contains(" of 1000000 s simulated"), "{text}");
    // and the time moves while the cycles do not
    let times: Vec<f64> = text
        .split(" of 1000000 cycles, ")
        .skip(1)
        .filter_map(|s| s.split(' ').next()?.parse().ok())
        .collect();
    assert!(
        times.len() >= 2 && times.last() > times.first(),
        "{times:?}"
    );
}

#[test]
fn a_long_arm_plan_shows_its_starts_and_evaluations() {
    // the slow plan, 16 knots and fine samples: seconds per start
    let text = terminal_text(
        "arm",
        &[
            "run",
            &scene("arm-roll"),
            "--set",
            "planner.knots=16",
            "--set",
            "planner.samples_per_phase=1000",
            "--set",
            "planner.roll_steps=2000",
            "--set",
            "planner.max_evaluations=100000",
            "--set",
            "planner.starts=8",
        ],
        4,
    );
    assert!(text.contains(" of 8 starts, "), "{text}");
    // the evaluations move while the first start runs
    let counts: Vec<f64> = text
        .split(" of 8 starts, ")
        .skip(1)
        .filter_map(|s| s.split(' ').next()?.parse().ok())
        .collect();
    assert!(
        counts.len() >= 2 && counts.last() > counts.first(),
        "{counts:?}"
    );
    assert!(text.contains("program evaluations"), "{text}");
}
