//! What every system shares, through the `dexter` binary: scenes read once (pipes work),
//! TOML errors with file, line and column, outputs written whole or not at all, missing
//! directories created, sweeps that refuse what they cannot hold and give the same result on
//! one core as on all, options a system does not support refused.

use crate::common;

use common::{dexter, scene, scratch};
use std::io::Write;
use std::path::Path;
use std::process::{Command, Output, Stdio};

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

/// Everything but the wall time.
fn without_wall(s: &str) -> String {
    s.lines()
        .filter(|l| !l.contains("wall"))
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn a_piped_scene_is_read_once_and_runs_as_the_file() {
    for name in ["line-juggler-ideal", "planar-triangle", "hopper-fig11"] {
        let path = scene(name);
        let from_file = dexter(&["run", &path, "--impacts", "20"]);
        let mut child = Command::new(env!("CARGO_BIN_EXE_dexter"))
            .args(["run", "/dev/stdin", "--impacts", "20"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let body = std::fs::read(&path).unwrap();
        child.stdin.take().unwrap().write_all(&body).unwrap();
        let piped = child.wait_with_output().unwrap();
        assert!(piped.status.success(), "{name}: {}", text(&piped).1);
        // the same run, named after the pipe where the scene has no name of its own
        let file_out = without_wall(&text(&from_file).0).replace(name, "stdin");
        let pipe_out = without_wall(&text(&piped).0).replace(name, "stdin");
        assert_eq!(pipe_out, file_out, "{name}");
    }
}

#[test]
fn toml_syntax_errors_name_file_line_and_column() {
    let dir = scratch("toml");
    let p = dir.join("broken.toml");
    std::fs::write(&p, "[physics]\nrestitution = 0.5\ngravity_mps2 = = 9.81\n").unwrap();
    let out = dexter(&["run", p.to_str().unwrap()]);
    let (_, err) = text(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("{}:3:16: not valid TOML", p.display())),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn missing_directories_are_created_for_every_system() {
    let dir = scratch("dirs");
    let cases = [
        ("line-juggler-ideal", "run", "--trace"),
        ("planar-triangle", "run", "--trace"),
        ("hopper-fig11", "run", "--trace"),
        ("planar-juggler", "run", "--trace"),
        ("spatial-juggler", "run", "--trace"),
    ];
    for (name, verb, opt) in cases {
        let file = dir.join(name).join("deeper").join("out.csv");
        let out = dexter(&[verb, &scene(name), opt, file.to_str().unwrap()]);
        assert!(out.status.success(), "{name}: {}", text(&out).1);
        assert!(file.is_file(), "{name}");
    }
    for (name, range) in [
        ("line-juggler-chaotic", "control.kappa1_s2pm2=0.02:0.03:2"),
        ("planar-triangle", "planar.kappa=1:1.1:2"),
        ("hopper-fig11", "hopper.thrust_tau_mps2=60:61:2"),
    ] {
        let file = dir.join(name).join("sweep").join("points.csv");
        let out = dexter(&[
            "sweep",
            &scene(name),
            "--range",
            range,
            "--csv",
            file.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{name}: {}", text(&out).1);
        assert!(file.is_file(), "{name}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Run `args` with the file size limited to `kib` KiB (SIGXFSZ ignored, so a write past
/// it fails with EFBIG as on a full disk).
fn with_file_limit(kib: u32, args: &[&str]) -> Output {
    let script = format!(
        "trap '' XFSZ; ulimit -f {}; exec \"$0\" \"$@\"",
        // POSIX sh counts 512-byte blocks
        kib * 2
    );
    Command::new("sh")
        .arg("-c")
        .arg(script)
        .arg(env!("CARGO_BIN_EXE_dexter"))
        .args(args)
        .output()
        .expect("sh runs")
}

#[test]
fn a_write_that_fails_leaves_no_partial_file() {
    let dir = scratch("full");
    let trace = dir.join("trace.csv");
    // 2000 impacts of 8 columns at 17 digits are ~350 KiB: more than the limit
    let ideal = scene("line-juggler-ideal");
    let args = [
        "run",
        &ideal,
        "--impacts",
        "2000",
        "--trace",
        trace.to_str().unwrap(),
    ];
    let out = with_file_limit(64, &args);
    let (_, err) = text(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cannot write") && err.contains("trace.csv"),
        "{err}"
    );
    assert_eq!(files_in(&dir), Vec::<String>::new(), "{err}");
    // an existing file is left as it was
    std::fs::write(&trace, "old\n").unwrap();
    let _ = with_file_limit(64, &args);
    assert_eq!(std::fs::read_to_string(&trace).unwrap(), "old\n");
    assert_eq!(files_in(&dir), ["trace.csv"]);
    // plots: the same for the PNGs (each ~100 KiB, over a 32 KiB limit)
    let plots = dir.join("plots");
    let out = with_file_limit(
        32,
        &[
            "run",
            &scene("planar-triangle"),
            "--plot",
            plots.to_str().unwrap(),
        ],
    );
    assert_eq!(out.status.code(), Some(1), "{}", text(&out).1);
    assert!(
        files_in(&plots)
            .iter()
            .all(|f| f.ends_with(".svg") && !f.starts_with('.')),
        "{:?}",
        files_in(&plots)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn huge_sweeps_are_refused_naming_the_limit() {
    let s = scene("line-juggler-chaotic");
    for n in ["5e9", "5000000000", "1000001"] {
        let out = dexter(&[
            "sweep",
            &s,
            "--range",
            &format!("control.kappa1_s2pm2=0.02:0.09:{n}"),
        ]);
        let (_, err) = text(&out);
        assert_eq!(out.status.code(), Some(2), "{n}: {err}");
        assert!(err.contains("at most 1000000 points"), "{n}: {err}");
        assert!(
            !err.contains("panicked") && !err.contains("memory"),
            "{err}"
        );
    }
    let out = dexter(&[
        "sweep",
        &scene("planar-triangle"),
        "--range",
        "planar.kappa=1:2:2000",
        "--range2",
        "planar.initial_theta_rad=0:1:1000",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out).1.contains("2000000 points"), "{}", text(&out).1);
    let out = dexter(&[
        "sweep",
        &s,
        "--range",
        "control.kappa1_s2pm2=0.02:0.09:3",
        "--keep",
        "100001",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(text(&out).1.contains("--keep"), "{}", text(&out).1);
}

#[test]
fn options_a_system_does_not_take_are_refused() {
    let cases: [(&[&str], &str); 6] = [
        (
            &[
                "sweep",
                &scene("line-juggler-chaotic"),
                "--range",
                "control.kappa1_s2pm2=0.02:0.03:2",
                "--range2",
                "physics.restitution=0.8:0.9:2",
            ],
            "--range2",
        ),
        (
            &[
                "sweep",
                &scene("hopper-fig11"),
                "--range",
                "hopper.thrust_tau_mps2=60:61:2",
                "--range2",
                "hopper.spring_eta1=5:6:2",
            ],
            "--range2",
        ),
        (
            &["run", &scene("hopper-fig11"), "--duration", "3"],
            "--duration",
        ),
        (&["run", &scene("planar-triangle"), "--hil"], "--hil"),
        (&["analyze", &scene("arm-throw")], "analyze"),
        (
            &[
                "basin",
                &scene("hopper-fig11"),
                "--range",
                "hopper.thrust_tau_mps2=40:41:2",
                "--range2",
                "hopper.spring_eta1=5:6:2",
            ],
            "basin",
        ),
    ];
    for (args, word) in cases {
        let out = dexter(args);
        let (_, err) = text(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(word), "{args:?}: {err}");
    }
    // a sweep whose first point is bad prints no CSV at all
    let out = dexter(&[
        "sweep",
        &scene("hopper-fig11"),
        "--range",
        "hopper.spring_eta1=-1:1:3",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty(), "{}", text(&out).0);
    assert!(
        text(&out).1.contains("hopper.spring_eta1 = -1"),
        "{}",
        text(&out).1
    );
    // --hil on a line scene without a controller: the mode is named, before QEMU starts
    let out = dexter(&["run", &scene("passive-bounce"), "--hil"]);
    let (_, err) = text(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("control.mode") && err.contains("\"none\""),
        "{err}"
    );
}

fn sweep_output(threads: &str, args: &[&str]) -> (String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_dexter"))
        .args(args)
        .env("RAYON_NUM_THREADS", threads)
        .output()
        .unwrap();
    assert!(out.status.success(), "{args:?}: {}", text(&out).1);
    text(&out)
}

#[test]
fn sweeps_on_one_core_and_on_all_agree_byte_for_byte() {
    let cases: [Vec<String>; 3] = [
        vec![
            "sweep".into(),
            scene("line-juggler-chaotic"),
            "--range".into(),
            "control.kappa1_s2pm2=0.02:0.09:40".into(),
            "--keep".into(),
            "16".into(),
        ],
        vec![
            "sweep".into(),
            scene("planar-triangle"),
            "--range".into(),
            "planar.kappa=0.8:1.6:5".into(),
            "--range2".into(),
            "planar.initial_theta_rad=0.05:0.4:4".into(),
            "--set".into(),
            "planar.impacts=60".into(),
        ],
        vec![
            "sweep".into(),
            scene("hopper-fig11"),
            "--range".into(),
            "hopper.thrust_tau_mps2=60:200:30".into(),
            "--keep".into(),
            "16".into(),
        ],
    ];
    for args in cases {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        let serial = sweep_output("1", &a);
        let parallel = sweep_output("4", &a);
        assert_eq!(serial.0, parallel.0, "{a:?}");
        assert_eq!(serial.1, parallel.1, "{a:?}");
        assert!(serial.0.lines().count() > 10, "{a:?}");
    }
}

/// The peak resident memory of `dexter args`, KiB (wait4's rusage of that child alone).
// the child is waited for by wait4 itself, which std's Child cannot do with rusage
#[allow(clippy::zombie_processes)]
fn peak_rss_kib(args: &[&str]) -> i64 {
    let child = Command::new(env!("CARGO_BIN_EXE_dexter"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: an all-zero rusage is a valid value for wait4 to fill in
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: `pid` is our own child, not yet waited for; status and usage are valid
    let waited = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(waited, pid, "wait4 on {args:?}");
    assert!(
        libc::WIFEXITED(status) && libc::WEXITSTATUS(status) == 0,
        "{args:?} failed"
    );
    usage.ru_maxrss
}

/// A run of a thousand times more events keeps the same memory, for every system (the
/// planar body used to keep every impact: about 160 MB for a million).
#[test]
fn a_run_of_any_length_keeps_constant_memory() {
    for name in ["line-juggler-ideal", "planar-triangle", "hopper-fig11"] {
        let s = scene(name);
        let short = peak_rss_kib(&["run", &s, "--impacts", "1000"]);
        let long = peak_rss_kib(&["run", &s, "--impacts", "1000000"]);
        println!("{name}: peak RSS {short} KiB for 1e3 events, {long} KiB for 1e6");
        assert!(long <= short + 4096, "{name}: {short} KiB -> {long} KiB");
    }
}
