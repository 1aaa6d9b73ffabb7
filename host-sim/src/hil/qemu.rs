//! The QEMU side of a HIL run: toolchain checks, building the firmware, the emulator
//! process in a private working directory, its exit status, and its defmt log.

use super::{LinkKind, ICOUNT_SHIFT, QEMU, QEMU_MACHINE, TARGET};
use crate::controller::ControllerError;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

pub(super) fn link_err(msg: impl Into<String>) -> ControllerError {
    ControllerError::Link(msg.into())
}

/// The workspace root (where `.cargo/config.toml` lives).
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

/// Where `cargo build -p dexter-mps2-an386 --release --target thumbv7em-none-eabihf` puts
/// the firmware ELF.
pub fn default_firmware_elf() -> PathBuf {
    target_dir()
        .join(TARGET)
        .join("release")
        .join("dexter-mps2-an386")
}

/// Check that the emulator runs; the error says what to install.
pub fn check_qemu() -> Result<(), ControllerError> {
    let qemu = Command::new(QEMU)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    if matches!(qemu, Ok(s) if s.success()) {
        return Ok(());
    }
    Err(link_err(format!(
        "{QEMU} not found: install it with `apt-get install qemu-system-arm` \
         (QEMU >= 7.2 for {QEMU_MACHINE})"
    )))
}

/// Check that the emulator and the firmware's Rust target are installed (what building
/// and running the firmware needs); the error says what to install.
pub fn check_toolchain() -> Result<(), ControllerError> {
    check_qemu()?;
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let sysroot = Command::new(&rustc)
        .args(["--print", "sysroot"])
        .output()
        .map_err(|e| {
            link_err(format!(
                "cannot run `{rustc}` to find the Rust sysroot: {e}"
            ))
        })?;
    let sysroot = PathBuf::from(String::from_utf8_lossy(&sysroot.stdout).trim());
    if !sysroot.join("lib/rustlib").join(TARGET).is_dir() {
        return Err(link_err(format!(
            "the Rust target {TARGET} is not installed: run `rustup target add {TARGET}`"
        )));
    }
    Ok(())
}

/// An LLVM tool (`llvm-objdump`, `llvm-nm`) for inspecting a firmware image: `$LLVM_OBJDUMP`
/// / `$LLVM_NM`, else on `PATH` (Debian's `llvm`), else rustup's `llvm-tools` in the
/// sysroot (the search `scripts/wcet.py` makes); the error says what to install.
pub fn llvm_tool(name: &str) -> Result<PathBuf, ControllerError> {
    let var = format!("LLVM_{}", name.trim_start_matches("llvm-").to_uppercase());
    if let Some(p) = std::env::var_os(var) {
        return Ok(PathBuf::from(p));
    }
    let on_path = std::env::var_os("PATH")
        .into_iter()
        .flat_map(|p| std::env::split_paths(&p).collect::<Vec<_>>())
        .map(|d| d.join(name))
        .find(|p| p.is_file());
    if let Some(p) = on_path {
        return Ok(p);
    }
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let sysroot = Command::new(&rustc).args(["--print", "sysroot"]).output();
    let sysroot = sysroot.map(|o| PathBuf::from(String::from_utf8_lossy(&o.stdout).trim()));
    let bin = sysroot.ok().and_then(|s| {
        let lib = s.join("lib/rustlib");
        std::fs::read_dir(lib).ok()?.flatten().find_map(|host| {
            let p = host.path().join("bin").join(name);
            p.is_file().then_some(p)
        })
    });
    bin.ok_or_else(|| {
        link_err(format!(
            "{name} not found: install Debian's llvm (`apt-get install llvm`) or \
             `rustup component add llvm-tools`"
        ))
    })
}

/// Build the firmware (`cargo build -p dexter-mps2-an386 --release --target
/// thumbv7em-none-eabihf` in the workspace root) and return the ELF's path.
pub fn build_firmware() -> Result<PathBuf, ControllerError> {
    build_firmware_with_features(&[])
}

/// [`build_firmware`] with cargo features of `dexter-mps2-an386` (e.g. `fast-math`, `bench`);
/// the ELF is written to the same path.
pub fn build_firmware_with_features(features: &[&str]) -> Result<PathBuf, ControllerError> {
    cargo_build_firmware(features, true)
}

/// An image with its own selection of hosted kinds (`dexter-mps2-an386` built with
/// `--no-default-features --features <features>`, e.g. `["arm"]`: firmware/README.md,
/// "Images"), copied beside the default ELF as `dexter-mps2-an386-<name>.elf`, so that a
/// later build of another image does not replace it; returns the copy's path.
pub fn build_firmware_image(name: &str, features: &[&str]) -> Result<PathBuf, ControllerError> {
    let elf = cargo_build_firmware(features, false)?;
    let copy = elf.with_file_name(format!("dexter-mps2-an386-{name}.elf"));
    std::fs::copy(&elf, &copy).map_err(|e| {
        link_err(format!(
            "cannot copy the {name} image {} to {}: {e}",
            elf.display(),
            copy.display()
        ))
    })?;
    Ok(copy)
}

fn cargo_build_firmware(
    features: &[&str],
    default_features: bool,
) -> Result<PathBuf, ControllerError> {
    check_toolchain()?;
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.current_dir(workspace_root()).args([
        "build",
        "-p",
        "dexter-mps2-an386",
        "--release",
        "--target",
        TARGET,
    ]);
    if !default_features {
        cmd.arg("--no-default-features");
    }
    if !features.is_empty() {
        cmd.args(["--features", &features.join(",")]);
    }
    let out = cmd
        .output()
        .map_err(|e| link_err(format!("cannot run cargo to build the firmware: {e}")))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = err.lines().collect();
        let tail = lines[lines.len().saturating_sub(30)..].join("\n");
        return Err(link_err(format!(
            "building the firmware failed ({}):\n{tail}",
            out.status
        )));
    }
    Ok(default_firmware_elf())
}

/// The firmware ELF as an absolute path (QEMU runs in a private directory), or an error
/// that says how to build it.
pub(super) fn resolve_firmware(elf: &Path) -> Result<PathBuf, ControllerError> {
    std::fs::canonicalize(elf)
        .ok()
        .filter(|p| p.is_file())
        .ok_or_else(|| {
            link_err(format!(
                "firmware ELF {} not found: build it with `cargo fw-build` \
                 (cargo build -p dexter-mps2-an386 --release --target {TARGET}) \
                 or call hil::build_firmware()",
                elf.display()
            ))
        })
}

/// A directory removed when dropped.
pub(super) struct WorkDir(PathBuf);

static RUN_ID: AtomicU64 = AtomicU64::new(0);

impl WorkDir {
    /// A fresh private directory under the system's temporary directory.
    pub(super) fn create() -> Result<Self, ControllerError> {
        let dir = std::env::temp_dir().join(format!(
            "dexter-hil-{}-{}",
            std::process::id(),
            RUN_ID.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir)
            .map_err(|e| link_err(format!("cannot create {}: {e}", dir.display())))?;
        Ok(WorkDir(dir))
    }

    pub(super) fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for WorkDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Every QEMU this process runs and has not yet waited for: its pid and working directory,
/// for [`kill_all`].
static RUNNING: Mutex<Vec<(u32, PathBuf)>> = Mutex::new(Vec::new());

fn running() -> std::sync::MutexGuard<'static, Vec<(u32, PathBuf)>> {
    RUNNING.lock().unwrap_or_else(|e| e.into_inner())
}

/// Kill every QEMU this process runs (SIGKILL, by pid) and remove their working
/// directories, for a signal handler about to exit; none is started or waited for after
/// this (a pid is never killed after it was reaped). Returns how many were killed.
pub fn kill_all() -> usize {
    let list = running();
    for (pid, dir) in list.iter() {
        if let Ok(pid) = libc::pid_t::try_from(*pid) {
            // SAFETY: kill(2) on a child this process has not reaped: no memory is touched
            unsafe { libc::kill(pid, libc::SIGKILL) };
        }
        let _ = std::fs::remove_dir_all(dir);
    }
    let n = list.len();
    std::mem::forget(list); // held until exit
    n
}

/// A running QEMU: killed, waited for and its working directory removed when dropped.
pub(super) struct Qemu {
    child: Child,
    log: Arc<Mutex<Vec<u8>>>,
    stderr: Arc<Mutex<Vec<u8>>>,
    collectors: Vec<JoinHandle<()>>,
    /// Dropped after the child is gone (the link files live here).
    _workdir: WorkDir,
}

impl Qemu {
    /// Boot `elf` (absolute) in `workdir` with the boot word of `link` and the link's extra
    /// arguments (`-serial ...`).
    pub(super) fn spawn(
        elf: &Path,
        link: LinkKind,
        workdir: WorkDir,
        link_args: &[String],
    ) -> Result<Self, ControllerError> {
        let mut cmd = Command::new(QEMU);
        cmd.current_dir(workdir.path())
            .args(["-machine", QEMU_MACHINE, "-nographic", "-monitor", "none"])
            .args(["-icount", &format!("shift={ICOUNT_SHIFT}")])
            .args(["-semihosting-config", "enable=on,target=native"])
            .arg("-kernel")
            .arg(elf)
            .args(["-append", link.boot_word()])
            .args(link_args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut list = running();
        let mut child = cmd
            .spawn()
            .map_err(|e| link_err(format!("cannot start {QEMU}: {e}")))?;
        list.push((child.id(), workdir.path().to_path_buf()));
        drop(list);
        let log = Arc::new(Mutex::new(Vec::new()));
        let stderr = Arc::new(Mutex::new(Vec::new()));
        let mut collectors = Vec::new();
        if let Some(out) = child.stdout.take() {
            collectors.push(spawn_collector(out, log.clone()));
        }
        if let Some(err) = child.stderr.take() {
            collectors.push(spawn_collector(err, stderr.clone()));
        }
        Ok(Qemu {
            child,
            log,
            stderr,
            collectors,
            _workdir: workdir,
        })
    }

    pub(super) fn pid(&self) -> u32 {
        self.child.id()
    }

    /// The exit status, if QEMU has exited.
    pub(super) fn exited(&mut self) -> Option<ExitStatus> {
        self.try_wait().ok().flatten()
    }

    /// `Child::try_wait`, and QEMU leaves [`RUNNING`] once it is reaped.
    fn try_wait(&mut self) -> std::io::Result<Option<ExitStatus>> {
        let mut list = running();
        let status = self.child.try_wait();
        if let Ok(Some(_)) = status {
            let pid = self.child.id();
            list.retain(|(p, _)| *p != pid);
        }
        status
    }

    /// A link error; if QEMU has exited, say so (with its status and stderr).
    pub(super) fn dead_or(&mut self, msg: String) -> ControllerError {
        let Some(status) = self.exited() else {
            return link_err(msg);
        };
        std::thread::sleep(Duration::from_millis(50)); // let the stderr collector finish
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

    /// Wait until QEMU exits: success, or an error naming the status (a panic or HardFault
    /// in the firmware ends the run with status 1).
    pub(super) fn wait_success(&mut self, timeout: Duration) -> Result<(), ControllerError> {
        let deadline = Instant::now() + timeout;
        loop {
            match self.try_wait() {
                Ok(Some(status)) if status.success() => return Ok(()),
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
                        "timeout: QEMU did not exit within {timeout:?} after Stop"
                    )))
                }
                Err(e) => return Err(link_err(format!("cannot wait for QEMU: {e}"))),
            }
        }
    }

    /// The raw defmt log so far (QEMU's stdout, the firmware's semihosting stdout).
    pub(super) fn log(&self) -> Vec<u8> {
        self.log.lock().map(|v| v.clone()).unwrap_or_default()
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let mut list = running();
        let _ = self.child.kill();
        let _ = self.child.wait();
        let pid = self.child.id();
        list.retain(|(p, _)| *p != pid);
        drop(list);
        for t in self.collectors.drain(..) {
            let _ = t.join();
        }
    }
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

/// QEMU's exit status in words.
pub(super) fn describe_exit(status: ExitStatus) -> String {
    match status.code() {
        Some(0) => "status 0, success".into(),
        Some(1) => {
            "status 1: the firmware reported a failure (panic, HardFault or link error)".into()
        }
        Some(c) => format!("status {c}"),
        None => "killed by a signal".into(),
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
