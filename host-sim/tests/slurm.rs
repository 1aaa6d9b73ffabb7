//! A sharded sweep on a real SLURM cluster of one node (Debian's `slurm-wlm` and `munge`):
//! munged, slurmctld and slurmd are started on localhost with every file (config, key,
//! state, spool, logs, PIDs, sockets) in a temporary directory, and stopped by PID when
//! the test ends, passed or failed ([`Cluster`]'s `Drop`). The job array is
//! `deploy/slurm/sweep.sbatch`, as a user submits it.
//!
//! 1. a 4-task array of a 200-point SIL sweep of the line juggler and its dependent merge
//!    job: the merged CSV is the unsharded sweep's, byte for byte;
//! 2. the array again with shard 2's output removed, task 2 cancelled mid-run (its
//!    temporary file exists): no shard 2 file and no temporary left, the other tasks were
//!    no-ops ("already complete"), the merge never ran;
//! 3. task 2 resubmitted with a new merge: byte for byte the unsharded sweep again.
//!
//! Without the programs the test fails saying what to install: it never skips.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The programs the test needs, and the Debian package of each.
const PROGRAMS: [(&str, &str); 9] = [
    ("munged", "munge"),
    ("mungekey", "munge"),
    ("slurmctld", "slurmctld (slurm-wlm)"),
    ("slurmd", "slurmd (slurm-wlm)"),
    ("sbatch", "slurm-client (slurm-wlm)"),
    ("scontrol", "slurm-client (slurm-wlm)"),
    ("scancel", "slurm-client (slurm-wlm)"),
    ("sinfo", "slurm-client (slurm-wlm)"),
    ("squeue", "slurm-client (slurm-wlm)"),
];

/// The sweep: 200 points of the SIL line juggler, runs long enough (1000 impacts) that a
/// task can be cancelled mid-run.
const SWEEP: &str =
    "--range control.kappa1_s2pm2=0.02:0.09:200 --set stop.impacts=1000 --set stop.duration_s=2000";

/// How long any one wait may take.
const PATIENCE: Duration = Duration::from_secs(90);

/// The path of `name` on PATH or in the sbin directories, if any.
fn program(name: &str) -> Option<PathBuf> {
    let path = std::env::var("PATH").unwrap_or_default();
    let found = path
        .split(':')
        .chain(["/usr/sbin", "/sbin", "/usr/local/sbin"])
        .map(|d| Path::new(d).join(name))
        .find(|p| p.is_file());
    found
}

/// A free TCP port on localhost (bound, read, released).
fn free_port() -> u16 {
    let l = std::net::TcpListener::bind("127.0.0.1:0").expect("bind a local port");
    l.local_addr().unwrap().port()
}

/// A one-node cluster whose daemons are this process's children, stopped by PID on drop.
struct Cluster {
    dir: tempfile::TempDir,
    daemons: Vec<(&'static str, Child)>,
    /// The `dexter` the tasks run.
    bin: PathBuf,
    /// The sweep's arguments after the scene.
    sweep: String,
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // jobs still running (a failed test) first: their steps are slurmd's, not ours
        if self.daemons.len() == 3 {
            let user = String::from_utf8_lossy(
                &Command::new("id")
                    .arg("-un")
                    .output()
                    .map_or(Vec::new(), |o| o.stdout),
            )
            .trim()
            .to_string();
            let _ = self.client("scancel").args(["-u", &user]).status();
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(10) {
                let q = self.client("squeue").args(["-h", "-o", "%i"]).output();
                if q.is_ok_and(|o| o.stdout.is_empty()) {
                    break;
                }
                std::thread::sleep(Duration::from_millis(100));
            }
        }
        // the reverse of the start order: slurmd, slurmctld, munged
        for (name, child) in self.daemons.iter_mut().rev() {
            let pid = child.id() as libc::pid_t;
            // SAFETY: kill(2) on our own child's PID, which it still is until we wait
            unsafe { libc::kill(pid, libc::SIGTERM) };
            let start = Instant::now();
            while child.try_wait().ok().flatten().is_none() {
                if start.elapsed() > Duration::from_secs(10) {
                    eprintln!("{name} (pid {pid}) ignored SIGTERM: killing it");
                    let _ = child.kill();
                    let _ = child.wait();
                    break;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
        }
    }
}

impl Cluster {
    /// Write the config and start the daemons; wait until the node is idle. The tasks will
    /// run `bin` on the line juggler's sweep `sweep`.
    fn start(bin: PathBuf, sweep: &str) -> Self {
        let missing: Vec<String> = PROGRAMS
            .iter()
            .filter(|(p, _)| program(p).is_none())
            .map(|(p, pkg)| format!("{p} ({pkg})"))
            .collect();
        assert!(
            missing.is_empty(),
            "the SLURM test needs {}: install them (Debian/Ubuntu: `sudo apt-get install slurm-wlm munge`); scripts/test.sh does",
            missing.join(", ")
        );
        let dir = tempfile::Builder::new()
            .prefix("dexter-slurm-")
            .tempdir()
            .expect("a temporary directory");
        let mut c = Self {
            dir,
            daemons: Vec::new(),
            bin,
            sweep: sweep.to_string(),
        };
        let d = c.dir.path().to_path_buf();
        for sub in ["key", "run", "state", "spool", "log", "out"] {
            std::fs::create_dir_all(d.join(sub)).unwrap();
        }
        use std::os::unix::fs::PermissionsExt;
        let mode =
            |p: &Path, m: u32| std::fs::set_permissions(p, std::fs::Permissions::from_mode(m));
        // munged insists: its key private, its socket's directories searchable by all
        mode(&d.join("key"), 0o700).unwrap();
        mode(&d, 0o755).unwrap();
        mode(&d.join("run"), 0o755).unwrap();
        let key = d.join("key").join("munge.key");
        let status = Command::new(program("mungekey").unwrap())
            .arg("--create")
            .arg(format!("--keyfile={}", key.display()))
            .status()
            .expect("mungekey runs");
        assert!(status.success(), "mungekey --create failed");
        let socket = d.join("run").join("munge.sock");
        let mut munged = Command::new(program("munged").unwrap());
        munged
            .arg("--foreground")
            .arg(format!("--socket={}", socket.display()))
            .arg(format!("--key-file={}", key.display()))
            .arg(format!("--pid-file={}", d.join("run/munged.pid").display()))
            .arg(format!("--log-file={}", d.join("log/munged.log").display()))
            .arg(format!(
                "--seed-file={}",
                d.join("key/munged.seed").display()
            ));
        c.spawn("munged", munged, &d.join("log/munged.out"));
        c.wait_for("the munge socket", || socket.exists());

        let conf = d.join("slurm.conf");
        std::fs::write(&conf, config(&d, &socket)).unwrap();
        let mut ctld = Command::new(program("slurmctld").unwrap());
        ctld.args(["-D", "-i", "-f"]).arg(&conf);
        c.spawn("slurmctld", ctld, &d.join("log/slurmctld.out"));
        let mut slurmd = Command::new(program("slurmd").unwrap());
        slurmd.args(["-D", "-N", "dexter-node", "-f"]).arg(&conf);
        c.spawn("slurmd", slurmd, &d.join("log/slurmd.out"));
        c.wait_for("the node to be idle", || {
            let out = c.client("sinfo").args(["-h", "-o", "%t"]).output();
            out.is_ok_and(|o| String::from_utf8_lossy(&o.stdout).trim() == "idle")
        });
        c
    }

    fn spawn(&mut self, name: &'static str, mut cmd: Command, log: &Path) {
        let out = std::fs::File::create(log).unwrap();
        // SAFETY: prctl(2) only, between fork and exec: the daemon is sent SIGTERM if this
        // test's thread dies without its Drop (killed)
        unsafe {
            std::os::unix::process::CommandExt::pre_exec(&mut cmd, || {
                libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM);
                Ok(())
            });
        }
        let child = cmd
            .env("SLURM_CONF", self.dir.path().join("slurm.conf"))
            .stdin(Stdio::null())
            .stdout(out.try_clone().unwrap())
            .stderr(out)
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {name}: {e}"));
        self.daemons.push((name, child));
    }

    /// A SLURM client command for this cluster.
    fn client(&self, name: &str) -> Command {
        let mut cmd = Command::new(program(name).unwrap());
        cmd.env("SLURM_CONF", self.dir.path().join("slurm.conf"));
        cmd
    }

    /// Wait until `ready`, or fail showing the daemons' logs.
    fn wait_for(&self, what: &str, mut ready: impl FnMut() -> bool) {
        let start = Instant::now();
        while !ready() {
            assert!(
                start.elapsed() < PATIENCE,
                "timed out waiting for {what}; logs:\n{}",
                self.logs()
            );
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// The daemons' logs, for a failure message.
    fn logs(&self) -> String {
        let mut s = String::new();
        for f in ["munged.out", "slurmctld.log", "slurmd.log"] {
            let text =
                std::fs::read_to_string(self.dir.path().join("log").join(f)).unwrap_or_default();
            let tail: Vec<&str> = text.lines().rev().take(15).collect();
            s += &format!("== {f}\n");
            for l in tail.into_iter().rev() {
                s += l;
                s.push('\n');
            }
        }
        s
    }

    fn out(&self) -> PathBuf {
        self.dir.path().join("out")
    }

    /// `sbatch` `deploy/slurm/sweep.sbatch` with `args`: the job id.
    fn submit(&self, args: &[&str]) -> String {
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../deploy/slurm/sweep.sbatch");
        let out = self
            .client("sbatch")
            .arg("--parsable")
            .arg(format!("--chdir={}", self.out().display()))
            .arg(format!("--output={}/job-%A_%a.log", self.out().display()))
            .args(args)
            .arg(script)
            .env("DEXTER", &self.bin)
            .env(
                "DEXTER_ARGS",
                format!("sweep {} {}", common::scene("line-juggler"), self.sweep),
            )
            .env("DEXTER_OUT", self.out())
            .env("DEXTER_SHARDS", "4")
            .output()
            .expect("sbatch runs");
        assert!(
            out.status.success(),
            "sbatch {args:?} failed: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let id = String::from_utf8_lossy(&out.stdout).trim().to_string();
        id.split(';').next().unwrap().to_string()
    }

    /// The states of job `id` (one per array task).
    fn states(&self, id: &str) -> Vec<String> {
        let out = self
            .client("scontrol")
            .args(["-o", "show", "job", id])
            .output()
            .expect("scontrol runs");
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|l| {
                l.split_whitespace()
                    .find_map(|w| w.strip_prefix("JobState="))
                    .map(str::to_string)
            })
            .collect()
    }

    /// Wait until every task of job `id` has ended; insist that it completed.
    fn wait_done(&self, id: &str) {
        let ended = |s: &String| {
            !matches!(
                s.as_str(),
                "PENDING" | "RUNNING" | "CONFIGURING" | "COMPLETING"
            )
        };
        self.wait_for(&format!("job {id}"), || {
            let s = self.states(id);
            !s.is_empty() && s.iter().all(ended)
        });
        let s = self.states(id);
        assert!(
            s.iter().all(|s| s == "COMPLETED"),
            "job {id} ended {s:?}; its logs:\n{}\n{}",
            self.job_logs(),
            self.logs()
        );
    }

    fn job_logs(&self) -> String {
        let mut s = String::new();
        for e in std::fs::read_dir(self.out()).unwrap().flatten() {
            let name = e.file_name().to_string_lossy().into_owned();
            if name.ends_with(".log") {
                s += &format!(
                    "== {name}\n{}",
                    std::fs::read_to_string(e.path()).unwrap_or_default()
                );
            }
        }
        s
    }
}

/// slurm.conf for one node on localhost, everything under `d`.
fn config(d: &Path, socket: &Path) -> String {
    let user = String::from_utf8(Command::new("id").arg("-un").output().unwrap().stdout).unwrap();
    let user = user.trim();
    let p = |s: &str| d.join(s).display().to_string();
    format!(
        "ClusterName=dexter
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort={}
SlurmdPort={}
SlurmUser={user}
SlurmdUser={user}
AuthType=auth/munge
AuthInfo=socket={}
CredType=cred/munge
StateSaveLocation={}
SlurmdSpoolDir={}
SlurmctldPidFile={}
SlurmdPidFile={}
SlurmctldLogFile={}
SlurmdLogFile={}
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/builtin
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
KillWait=5
MinJobAge=600
SchedulerParameters=sched_min_interval=100000
NodeName=dexter-node NodeAddr=127.0.0.1 NodeHostname=localhost CPUs=2 RealMemory=1000 State=UNKNOWN
PartitionName=debug Nodes=dexter-node Default=YES MaxTime=INFINITE State=UP
",
        free_port(),
        free_port(),
        socket.display(),
        p("state"),
        p("spool"),
        p("run/slurmctld.pid"),
        p("run/slurmd.pid"),
        p("log/slurmctld.log"),
        p("log/slurmd.log"),
    )
}

/// The files in `dir` whose names start with `prefix`.
fn named(dir: &Path, prefix: &str) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(prefix))
        .collect()
}

/// Run the unsharded sweep `sweep` with `bin` into `csv` (`threads`: RAYON_NUM_THREADS, or
/// every core): its wall time.
fn unsharded(bin: &Path, sweep: &str, csv: &Path, threads: Option<usize>) -> Duration {
    let mut cmd = Command::new(bin);
    cmd.arg("sweep").arg(common::scene("line-juggler"));
    cmd.args(sweep.split(' ')).arg("--csv").arg(csv);
    if let Some(n) = threads {
        cmd.env("RAYON_NUM_THREADS", n.to_string());
    }
    let start = Instant::now();
    let out = cmd.output().expect("dexter runs");
    let took = start.elapsed();
    assert!(
        out.status.success(),
        "the unsharded sweep failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    took
}

/// CPU seconds (user + system) of this process's finished children so far.
fn children_cpu() -> f64 {
    // SAFETY: getrusage(2) fills the struct it is given
    let mut u: libc::rusage = unsafe { std::mem::zeroed() };
    unsafe { libc::getrusage(libc::RUSAGE_CHILDREN, &mut u) };
    let t = |v: libc::timeval| v.tv_sec as f64 + v.tv_usec as f64 * 1e-6;
    t(u.ru_utime) + t(u.ru_stime)
}

/// The 1-minute load average (other work on the machine), as text.
fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|l| l.split_whitespace().next().unwrap_or("?").to_string())
        .unwrap_or_else(|_| "?".into())
}

/// The speed-up of a 4-task array on this machine's CPUs over one serial process
/// (`scripts/slurm-bench.sh`, BENCHMARKS.md "Sweeps on SLURM"): a measurement, not a check
/// (ignored by `cargo test`). `DEXTER_BIN` is the dexter to measure (the release build),
/// `DEXTER_BENCH_SWEEP` the sweep's arguments, `DEXTER_BENCH_REPEATS` the rounds (each:
/// serial, every core, SLURM, in that order; the best of each is compared, the least
/// disturbed by other work on the machine).
#[test]
#[ignore = "a benchmark: run by scripts/slurm-bench.sh"]
fn bench_a_job_array_against_one_serial_process() {
    let bin: PathBuf =
        std::env::var_os("DEXTER_BIN").map_or(env!("CARGO_BIN_EXE_dexter").into(), PathBuf::from);
    let sweep = std::env::var("DEXTER_BENCH_SWEEP").unwrap_or_else(|_| {
        "--range control.kappa1_s2pm2=0.02:0.09:200 --set stop.impacts=5000 --set stop.duration_s=10000".into()
    });
    let repeats: usize = std::env::var("DEXTER_BENCH_REPEATS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(2);
    let cluster = Cluster::start(bin.clone(), &sweep);
    let out = cluster.out();
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    println!("sweep: scenes/line-juggler.toml {sweep}");
    let (mut best_serial, mut best_rayon, mut best_slurm) = (f64::MAX, f64::MAX, f64::MAX);
    for round in 1..=repeats {
        let (l0, c0) = (load(), children_cpu());
        let serial = unsharded(&bin, &sweep, &out.join("serial.csv"), Some(1)).as_secs_f64();
        let c1 = children_cpu();
        let rayon = unsharded(&bin, &sweep, &out.join("rayon.csv"), None).as_secs_f64();
        let c2 = children_cpu();
        for k in 1..=4 {
            let _ = std::fs::remove_file(out.join(format!("shard-{k}-of-4.csv")));
        }
        let _ = std::fs::remove_file(out.join("merged.csv"));
        let start = Instant::now();
        let array = cluster.submit(&["--array=1-4"]);
        let merge = cluster.submit(&[&format!("--dependency=afterok:{array}")]);
        cluster.wait_done(&merge);
        let slurm = start.elapsed().as_secs_f64();
        cluster.wait_done(&array);
        let expected = std::fs::read(out.join("serial.csv")).unwrap();
        assert!(std::fs::read(out.join("merged.csv")).unwrap() == expected);
        assert!(std::fs::read(out.join("rayon.csv")).unwrap() == expected);
        println!(
            "round {round} (load {l0} -> {}): serial {serial:.2} s (cpu {:.2} s), every core ({cpus} threads) {rayon:.2} s (cpu {:.2} s, {:.3} of serial), SLURM 4 tasks + merge {slurm:.2} s ({:.3} of serial)",
            load(),
            c1 - c0,
            c2 - c1,
            rayon / serial,
            slurm / serial
        );
        best_serial = best_serial.min(serial);
        best_rayon = best_rayon.min(rayon);
        best_slurm = best_slurm.min(slurm);
    }
    let ratio = best_slurm / best_serial;
    println!("best of {repeats}: one process, serial (RAYON_NUM_THREADS=1): {best_serial:7.2} s");
    println!(
        "best of {repeats}: one process, every core (rayon, {cpus} threads): {best_rayon:7.2} s  ({:.3} of serial)",
        best_rayon / best_serial
    );
    println!(
        "best of {repeats}: SLURM, 4 array tasks on {cpus} CPUs + merge job: {best_slurm:7.2} s  ({ratio:.3} of serial; goal <= 0.6)"
    );
    println!("merged CSV = serial CSV = rayon CSV, byte for byte, every round");
    assert!(
        ratio <= 0.6,
        "the array took {ratio:.3} of the serial time, more than 0.6"
    );
}

#[test]
fn a_job_array_merges_to_the_unsharded_sweep_and_survives_a_killed_task() {
    let cluster = Cluster::start(env!("CARGO_BIN_EXE_dexter").into(), SWEEP);
    let out = cluster.out();
    // the unsharded sweep, in this process (on every core)
    let full = out.join("full.csv");
    unsharded(&cluster.bin, SWEEP, &full, None);
    let expected = std::fs::read(&full).unwrap();
    let merged = out.join("merged.csv");

    // 1. the array and its merge
    let array = cluster.submit(&["--array=1-4"]);
    let merge = cluster.submit(&[&format!("--dependency=afterok:{array}")]);
    cluster.wait_done(&array);
    cluster.wait_done(&merge);
    assert!(
        std::fs::read(&merged).unwrap() == expected,
        "the merged CSV differs from the unsharded sweep's"
    );

    // 2. again without shard 2; task 2 cancelled while it runs
    let shard2 = out.join("shard-2-of-4.csv");
    std::fs::remove_file(&shard2).unwrap();
    std::fs::remove_file(&merged).unwrap();
    let array = cluster.submit(&["--array=1-4"]);
    let merge = cluster.submit(&[&format!("--dependency=afterok:{array}")]);
    cluster.wait_for("task 2's temporary output (mid-run)", || {
        !named(&out, ".shard-2-of-4.csv.").is_empty()
    });
    let task2 = format!("{array}_2");
    let status = cluster.client("scancel").arg(&task2).status().unwrap();
    assert!(status.success(), "scancel {task2}");
    cluster.wait_for(&format!("task {task2} to end"), || {
        cluster.states(&task2).iter().all(|s| s == "CANCELLED")
    });
    for k in [1, 3, 4] {
        cluster.wait_done(&format!("{array}_{k}"));
        let log = std::fs::read_to_string(out.join(format!("job-{array}_{k}.log"))).unwrap();
        assert!(
            log.contains("already complete: nothing to do"),
            "task {k}: {log}"
        );
    }
    assert!(!shard2.exists(), "a cancelled task left its shard");
    assert!(
        named(&out, ".shard-2-of-4.csv.").is_empty(),
        "a cancelled task left its temporary file"
    );
    // the merge depends on a cancelled task: it never runs
    assert_eq!(cluster.states(&merge), ["PENDING"]);
    cluster.client("scancel").arg(&merge).status().unwrap();
    assert!(!merged.exists());

    // 3. task 2 resubmitted, and a new merge
    let again = cluster.submit(&["--array=2"]);
    let merge = cluster.submit(&[&format!("--dependency=afterok:{again}")]);
    cluster.wait_done(&again);
    cluster.wait_done(&merge);
    assert!(
        std::fs::read(&merged).unwrap() == expected,
        "after the resubmission the merged CSV differs"
    );
}
