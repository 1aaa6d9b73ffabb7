//! Outputs under unusual conditions, through the binary (issue 22, items 1, 2, 3, 8, 9):
//!
//! - `--trace` onto a FIFO, a character device or a symbolic link writes through it and
//!   leaves it what it was (a FIFO, a device, a link); `-` is stdout;
//! - a closed stdout ends the command quietly with exit 141, a full one with exit 1 and one
//!   line; a closed stderr never changes the exit status; never a panic;
//! - a `--set` or `--range` key deeper than 16 levels is refused with exit 2;
//! - a failed run leaves the previous trace as it was;
//! - SIGINT, SIGTERM and SIGHUP remove the temporary file and exit 128 + the signal.
//!
//! Nothing here writes to a real `/dev` file: devices are made with mknod(2) inside the
//! test's scratch directory (as root; otherwise the test says it did not exercise them).

use crate::common;

use common::{dexter, scene, scratch};
use std::ffi::CString;
use std::io::Read;
use std::os::unix::ffi::OsStrExt;
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// A short, successful run.
const SHORT: [&str; 3] = ["--impacts", "3", "--set=sensor.seed=1"];

fn short_scene() -> String {
    scene("line-juggler-ideal")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Every name in `dir` (sorted).
fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Temporary output files left in `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    entries(dir)
        .into_iter()
        .filter(|n| n.starts_with('.') && n.ends_with(".tmp"))
        .collect()
}

fn no_panic(out: &Output) {
    let err = text(&out.stderr);
    assert!(
        !err.contains("panicked")
            && !err.contains("RUST_BACKTRACE")
            && out.status.code() != Some(101),
        "a panic ({:?}): {err}",
        out.status
    );
}

fn mkfifo(path: &Path) {
    let c = CString::new(path.as_os_str().as_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0, "mkfifo");
}

/// A character device `major:minor` at `path`, if this process may make one (root).
fn mknod_char(path: &Path, major: u32, minor: u32) -> bool {
    let c = CString::new(path.as_os_str().as_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path
    let r = unsafe {
        libc::mknod(
            c.as_ptr(),
            libc::S_IFCHR | 0o666,
            libc::makedev(major, minor),
        )
    };
    r == 0
}

fn run_dexter(args: &[&str], stdout: Stdio, stderr: Stdio) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dexter"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .output()
        .expect("the dexter binary runs")
}

// ---------------------------------------------------------------- item 1: where output goes

#[test]
fn a_trace_onto_a_fifo_is_streamed_through_it_and_the_fifo_stays() {
    let dir = scratch("io-fifo");
    let fifo = dir.join("trace.fifo");
    mkfifo(&fifo);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut s = String::new();
            std::fs::File::open(&fifo)
                .unwrap()
                .read_to_string(&mut s)
                .unwrap();
            s
        })
    };
    let mut args = vec!["run", "--trace", fifo.to_str().unwrap()];
    let sc = short_scene();
    args.insert(1, &sc);
    args.extend(SHORT);
    let out = dexter(&args);
    no_panic(&out);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let got = reader.join().unwrap();
    assert!(got.starts_with("index,time_s,"), "{got}");
    assert!(got.lines().count() > 3, "a header and rows: {got}");
    let kind = std::fs::symlink_metadata(&fifo).unwrap().file_type();
    assert!(kind.is_fifo(), "the FIFO was replaced: {kind:?}");
    assert_eq!(entries(&dir), ["trace.fifo"], "no temporary file");
}

#[test]
fn a_trace_through_a_symlink_replaces_its_target_and_keeps_the_link() {
    let dir = scratch("io-symlink");
    std::fs::create_dir_all(dir.join("real")).unwrap();
    std::fs::write(dir.join("real").join("t.csv"), "old\n").unwrap();
    std::os::unix::fs::symlink("real/t.csv", dir.join("link.csv")).unwrap();
    let link = dir.join("link.csv");
    let sc = short_scene();
    let mut args = vec!["run", &sc, "--trace", link.to_str().unwrap()];
    args.extend(SHORT);
    let out = dexter(&args);
    no_panic(&out);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let meta = std::fs::symlink_metadata(&link).unwrap();
    assert!(meta.file_type().is_symlink(), "the link was replaced");
    assert_eq!(
        std::fs::read_link(&link).unwrap(),
        PathBuf::from("real/t.csv")
    );
    let trace = std::fs::read_to_string(dir.join("real").join("t.csv")).unwrap();
    assert!(trace.lines().count() > 3 && trace != "old\n", "{trace}");
    assert_eq!(entries(&dir), ["link.csv", "real"]);
    assert_eq!(entries(&dir.join("real")), ["t.csv"], "no temporary file");
    // a dangling link: the file it names is created, the link stays
    std::os::unix::fs::symlink("real/new.csv", dir.join("dangling.csv")).unwrap();
    let dangling = dir.join("dangling.csv");
    let mut args = vec!["run", &sc, "--trace", dangling.to_str().unwrap()];
    args.extend(SHORT);
    let out = dexter(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(std::fs::symlink_metadata(&dangling)
        .unwrap()
        .file_type()
        .is_symlink());
    assert_eq!(
        std::fs::read_to_string(dir.join("real").join("new.csv")).unwrap(),
        trace
    );
}

#[test]
fn a_trace_onto_a_character_device_writes_to_the_device() {
    let dir = scratch("io-chardev");
    let null = dir.join("null");
    if !mknod_char(&null, 1, 3) {
        println!("NOT EXERCISED: mknod needs root; a trace onto a character device was not tested");
        return;
    }
    let sc = short_scene();
    let mut args = vec!["run", &sc, "--trace", null.to_str().unwrap()];
    args.extend(SHORT);
    let out = dexter(&args);
    no_panic(&out);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let kind = std::fs::symlink_metadata(&null).unwrap().file_type();
    assert!(kind.is_char_device(), "the device was replaced: {kind:?}");
    assert_eq!(entries(&dir), ["null"], "no temporary file");
}

#[test]
fn dash_is_stdout_for_a_trace_and_a_sweep_csv() {
    let sc = short_scene();
    let mut args = vec!["run", &sc, "--trace", "-"];
    args.extend(SHORT);
    let out = dexter(&args);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let plain = {
        let mut a = vec!["run", sc.as_str()];
        a.extend(SHORT);
        dexter(&a)
    };
    let timeless = |b: &[u8]| {
        let t = text(b);
        t.lines()
            .filter(|l| !l.starts_with("wall time"))
            .map(|l| format!("{l}\n"))
            .collect::<String>()
    };
    let stdout = timeless(&out.stdout);
    // the trace, then the summary the run prints without --trace
    assert!(stdout.starts_with("index,time_s,"), "{stdout}");
    assert!(stdout.ends_with(&timeless(&plain.stdout)), "{stdout}");
    assert!(stdout.len() > plain.stdout.len() + 100, "{stdout}");
    // sweep: `--csv -` is the CSV on stdout, exactly as without --csv
    let line = scene("line-juggler");
    let sweep = |csv: Option<&str>| {
        let mut a = vec![
            "sweep",
            line.as_str(),
            "--range",
            "sensor.rate_hz=500:1000:2",
        ];
        a.extend(["--set", "stop.impacts=3", "--keep", "2"]);
        if let Some(c) = csv {
            a.extend(["--csv", c]);
        }
        dexter(&a)
    };
    let (with, without) = (sweep(Some("-")), sweep(None));
    assert!(without.status.success(), "{}", text(&without.stderr));
    assert_eq!(with.status.code(), Some(0), "{}", text(&with.stderr));
    assert_eq!(with.stdout, without.stdout);
    assert_eq!(with.stderr, without.stderr);
}

// ---------------------------------------------------------------- item 2: closed and full

/// `args` with a stdout whose reader has gone: the status and stderr.
///
/// The other tests of this file spawn children from other threads at the same time, and a
/// child forked there holds a copy of every descriptor of this process until it execs: if
/// it still holds this pipe's read end when a short run writes its summary, the write
/// succeeds and the run exits 0. So a 0 is retried (a few times); any other status is the
/// answer.
fn with_closed_stdout(args: &[&str]) -> Output {
    let once = || {
        let mut child = Command::new(env!("CARGO_BIN_EXE_dexter"))
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take()); // the reader is gone before anything is written
        child.wait_with_output().unwrap()
    };
    let mut out = once();
    for _ in 0..5 {
        if out.status.code() != Some(0) {
            break;
        }
        std::thread::sleep(Duration::from_millis(50));
        out = once();
    }
    out
}

#[test]
fn a_closed_stdout_ends_quietly_with_141() {
    let sc = short_scene();
    let chaotic = scene("line-juggler-chaotic");
    let line = scene("line-juggler");
    let cases: Vec<Vec<&str>> = vec![
        [vec!["run", sc.as_str()], SHORT.to_vec()].concat(),
        [vec!["run", sc.as_str(), "--json"], SHORT.to_vec()].concat(),
        vec!["run", chaotic.as_str(), "--impacts", "3", "--json"],
        [vec!["run", sc.as_str(), "--trace", "-"], SHORT.to_vec()].concat(),
        vec![
            "sweep",
            line.as_str(),
            "--range",
            "sensor.rate_hz=500:1000:2",
            "--set",
            "stop.impacts=3",
            "--keep",
            "2",
        ],
    ];
    for args in cases {
        let out = with_closed_stdout(&args);
        no_panic(&out);
        assert_eq!(
            out.status.code(),
            Some(141),
            "{args:?}: {}",
            text(&out.stderr)
        );
        assert_eq!(text(&out.stderr), "", "{args:?}: quiet");
    }
}

/// A trace streamed to a closed stdout ends the run at once, not after 10⁸ impacts.
#[test]
fn a_long_trace_to_a_closed_stdout_stops_at_once() {
    let t0 = Instant::now();
    let sc = short_scene();
    let out = with_closed_stdout(&["run", &sc, "--impacts", "100000000", "--trace", "-"]);
    no_panic(&out);
    assert_eq!(out.status.code(), Some(141), "{}", text(&out.stderr));
    assert_eq!(text(&out.stderr), "");
    assert!(t0.elapsed() < Duration::from_secs(60), "{:?}", t0.elapsed());
}

#[test]
fn a_closed_stderr_does_not_change_the_exit_status() {
    let bad = scratch("io-bad-scene").join("bad.toml");
    std::fs::write(&bad, "[physics\n").unwrap();
    let sc = short_scene();
    for (args, code) in [
        (vec!["run", bad.to_str().unwrap()], 2),
        (vec!["run", sc.as_str(), "--set", "nope.key=1"], 2),
        (vec!["run", sc.as_str(), "--impacts", "3"], 0),
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_dexter"))
            .args(&args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stderr.take());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(code), "{args:?}");
    }
}

#[test]
fn a_full_stdout_or_stderr_exits_1_or_keeps_its_status() {
    let dir = scratch("io-full");
    let full = dir.join("full");
    if !mknod_char(&full, 1, 7) {
        println!("NOT EXERCISED: mknod needs root; a full stdout (ENOSPC) was not tested");
        return;
    }
    let open = || std::fs::OpenOptions::new().write(true).open(&full).unwrap();
    let sc = short_scene();
    let mut args = vec!["run", sc.as_str()];
    args.extend(SHORT);
    // a full stdout: exit 1, one line naming it
    let out = run_dexter(&args, Stdio::from(open()), Stdio::piped());
    no_panic(&out);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("stdout") && err.contains("No space left"),
        "{err}"
    );
    // ... and a trace is not written when the summary cannot be printed
    let trace = dir.join("t.csv");
    std::fs::write(&trace, "old\n").unwrap();
    let mut targs = args.clone();
    targs.extend(["--trace", trace.to_str().unwrap()]);
    let out = run_dexter(&targs, Stdio::from(open()), Stdio::piped());
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert_eq!(std::fs::read_to_string(&trace).unwrap(), "old\n");
    std::fs::remove_file(&trace).unwrap();
    // a full stderr: a bad scene still exits 2, a good run 0
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[physics\n").unwrap();
    let out = run_dexter(
        &["run", bad.to_str().unwrap()],
        Stdio::null(),
        Stdio::from(open()),
    );
    assert_eq!(out.status.code(), Some(2));
    let out = run_dexter(&args, Stdio::null(), Stdio::from(open()));
    assert_eq!(out.status.code(), Some(0));
    // a trace onto a full device: exit 1, the device stays
    let mut targs = vec!["run", sc.as_str(), "--trace", full.to_str().unwrap()];
    targs.extend(SHORT);
    let out = run_dexter(&targs, Stdio::null(), Stdio::piped());
    no_panic(&out);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("No space left"),
        "{}",
        text(&out.stderr)
    );
    assert!(std::fs::symlink_metadata(&full)
        .unwrap()
        .file_type()
        .is_char_device());
}

// ---------------------------------------------------------------- item 3: deep keys

#[test]
fn a_key_deeper_than_16_levels_is_refused_with_exit_2() {
    let deep = vec!["a"; 60_000].join(".");
    let set = format!("{deep}=1");
    let range = format!("{deep}=0:1:2");
    let seventeen = format!("{}=1", vec!["a"; 17].join("."));
    let sc = short_scene();
    let line = scene("line-juggler");
    for args in [
        vec!["run", sc.as_str(), "--set", set.as_str()],
        vec!["run", sc.as_str(), "--set", seventeen.as_str()],
        vec!["sweep", line.as_str(), "--range", range.as_str()],
        vec![
            "sweep",
            line.as_str(),
            "--range",
            "sensor.rate_hz=500:1000:2",
            "--set",
            set.as_str(),
        ],
    ] {
        let out = dexter(&args);
        no_panic(&out);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{}: {err}", &args[0]);
        assert!(err.contains("at most 16"), "{err}");
        assert!(
            err.len() < 300,
            "the key is not printed whole: {}",
            err.len()
        );
    }
}

// ---------------------------------------------------------------- item 8: failed runs

#[test]
fn a_failed_run_leaves_the_previous_trace_as_it_was() {
    let dir = scratch("io-failed-run");
    let old = dir.join("old.csv");
    std::fs::write(&old, "old\n").unwrap();
    let line = scene("line-juggler");
    // mostly in the safe state: exit 1
    let out = dexter(&[
        "run",
        &line,
        "--trace",
        old.to_str().unwrap(),
        "--set",
        "sensor.rate_hz=1000.0",
        "--set",
        "sensor.latency_s=4.096",
        "--impacts",
        "3",
    ]);
    no_panic(&out);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(
        text(&out.stderr).contains("not written"),
        "{}",
        text(&out.stderr)
    );
    assert!(!out.stdout.is_empty(), "the summary is still printed");
    assert_eq!(std::fs::read_to_string(&old).unwrap(), "old\n");
    assert_eq!(entries(&dir), ["old.csv"]);
    // a plot directory that cannot be made: the trace is not written either
    let not_a_dir = dir.join("plots");
    std::fs::write(&not_a_dir, "a file\n").unwrap();
    let sc = short_scene();
    let mut args = vec![
        "run",
        sc.as_str(),
        "--trace",
        old.to_str().unwrap(),
        "--plot",
        not_a_dir.to_str().unwrap(),
    ];
    args.extend(SHORT);
    let out = dexter(&args);
    no_panic(&out);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert_eq!(std::fs::read_to_string(&old).unwrap(), "old\n");
    assert_eq!(entries(&dir), ["old.csv", "plots"]);
    // and a run that succeeds writes it
    let mut args = vec!["run", sc.as_str(), "--trace", old.to_str().unwrap()];
    args.extend(SHORT);
    assert!(dexter(&args).status.success());
    assert_ne!(std::fs::read_to_string(&old).unwrap(), "old\n");
}

// ---------------------------------------------------------------- item 9: signals

/// A run that would take hours, writing `dir/t.csv`; returns once its temporary exists.
fn start_long_run(dir: &Path) -> Child {
    let trace = dir.join("t.csv");
    let child = Command::new(env!("CARGO_BIN_EXE_dexter"))
        .args([
            "run",
            &scene("line-juggler-ideal"),
            "--impacts",
            "100000000",
        ])
        .arg("--trace")
        .arg(&trace)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while temporaries(dir).is_empty() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "no temporary file appeared"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300)); // well into the run
    child
}

#[test]
fn a_signal_removes_the_temporary_file_and_exits_128_plus_its_number() {
    for (sig, name) in [
        (libc::SIGINT, "SIGINT"),
        (libc::SIGTERM, "SIGTERM"),
        (libc::SIGHUP, "SIGHUP"),
    ] {
        let dir = scratch(&format!("io-signal-{sig}"));
        std::fs::write(dir.join("t.csv"), "old\n").unwrap();
        let child = start_long_run(&dir);
        let pid = libc::pid_t::try_from(child.id()).unwrap();
        // SAFETY: kill(2) on our own child, not yet waited for
        assert_eq!(unsafe { libc::kill(pid, sig) }, 0);
        let out = child.wait_with_output().unwrap();
        no_panic(&out);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(128 + sig), "{name}: {err}");
        assert!(err.contains(&format!("interrupted by {name}")), "{err}");
        assert_eq!(err.lines().count(), 1, "one line: {err}");
        assert_eq!(
            entries(&dir),
            ["t.csv"],
            "{name}: the temporary file is removed"
        );
        assert_eq!(std::fs::read_to_string(dir.join("t.csv")).unwrap(), "old\n");
    }
}

/// A sweep writing `--csv` is interrupted the same way: no temporary CSV is left.
#[test]
fn a_signal_during_a_sweep_removes_its_temporary_csv() {
    let dir = scratch("io-signal-sweep");
    let csv = dir.join("s.csv");
    let child = Command::new(env!("CARGO_BIN_EXE_dexter"))
        .args([
            "sweep",
            &scene("line-juggler"),
            "--range",
            "sensor.rate_hz=500:1000:4",
        ])
        .args([
            "--set",
            "stop.impacts=100000000",
            "--set",
            "stop.duration_s=1000000",
        ])
        .args(["--keep", "2", "--csv"])
        .arg(&csv)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    while temporaries(&dir).is_empty() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "no temporary file appeared"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300));
    let pid = libc::pid_t::try_from(child.id()).unwrap();
    // SAFETY: kill(2) on our own child, not yet waited for
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    let out = child.wait_with_output().unwrap();
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted by SIGINT: dexter sweep"), "{err}");
    assert!(err.contains("s.csv"), "names what was not written: {err}");
    assert_eq!(entries(&dir), Vec::<String>::new(), "no temporary file");
}

/// A sweep's `--csv` onto a FIFO is streamed through it, and the FIFO stays.
#[test]
fn a_sweep_csv_onto_a_fifo_is_streamed_and_the_fifo_stays() {
    let dir = scratch("io-sweep-fifo");
    let fifo = dir.join("csv.fifo");
    mkfifo(&fifo);
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(&fifo).unwrap())
    };
    let line = scene("line-juggler");
    let out = dexter(&[
        "sweep",
        &line,
        "--range",
        "sensor.rate_hz=500:1000:2",
        "--set",
        "stop.impacts=3",
        "--keep",
        "2",
        "--csv",
        fifo.to_str().unwrap(),
    ]);
    no_panic(&out);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let csv = reader.join().unwrap();
    assert!(csv.lines().count() >= 3, "a header and two points: {csv}");
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    assert_eq!(entries(&dir), ["csv.fifo"]);
}
