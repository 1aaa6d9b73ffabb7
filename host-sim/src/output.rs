//! Output files, the same for every system: written **whole or not at all**, and the CSV
//! number format.
//!
//! Where an output goes ([`AtomicFile::create`]):
//!
//! - a regular file, or a path that does not exist yet: an [`AtomicFile`] is a temporary
//!   file in the target's directory (`.NAME.XXXXXX.tmp`); [`AtomicFile::commit`] flushes
//!   it, syncs it to disk (so a full disk is reported here, not later) and renames it into
//!   place. If anything fails first, or the file is dropped without a commit, the
//!   temporary file is removed and the target is left as it was: a failed run leaves no
//!   partial trace, CSV or plot;
//! - a symbolic link is followed: the temporary file and the rename go to the file the link
//!   names (in that file's directory), and the link itself stays;
//! - `-`, `/dev/stdout` (`/dev/fd/1`, `/proc/self/fd/1`) is the process's standard output,
//!   and `/dev/stderr` (`/dev/fd/2`, `/proc/self/fd/2`) its standard error;
//! - a character or block device (`/dev/null`), a FIFO or a socket is opened and written
//!   directly, streamed as the run goes (a FIFO waits for its reader). Such an output
//!   cannot be held back: what was written before a failure stays written.
//!
//! A [`Batch`] holds back the renames of every file committed while it is open, so that
//! the outputs of one command appear together when it succeeds ([`Batch::commit`]) and not
//! at all when it fails (the batch is dropped).
//!
//! Every temporary file is listed in a registry until it is renamed or removed, so that an
//! interrupted command (SIGINT, SIGTERM, SIGHUP) removes them all before it exits
//! ([`remove_unfinished`], called by the CLI's signal handler).
//!
//! A missing parent directory of an output file (`--trace`, `--csv`) is created, as
//! `--plot DIR` creates its directory, for every system.

use std::fmt;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// Why an output file could not be written.
#[derive(Debug)]
pub struct OutputError {
    /// The file (or directory) concerned.
    pub path: PathBuf,
    /// The underlying error.
    pub source: std::io::Error,
}

impl OutputError {
    /// True if the output was a pipe whose reader has gone (EPIPE): `dexter run | head`.
    pub fn is_broken_pipe(&self) -> bool {
        self.source.kind() == std::io::ErrorKind::BrokenPipe
    }
}

impl fmt::Display for OutputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "cannot write {}: {}", self.path.display(), self.source)
    }
}

impl std::error::Error for OutputError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.source)
    }
}

/// Lock `m`, whatever a panicking holder left (the data are lists of paths).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Temporary files not yet renamed or removed, and the targets they are for.
static UNFINISHED: Mutex<Vec<(PathBuf, PathBuf)>> = Mutex::new(Vec::new());

/// Remove every temporary output file, and keep any other from being created, renamed or
/// removed until the process exits: for a signal handler about to exit. Returns the targets
/// that were not written.
pub fn remove_unfinished() -> Vec<PathBuf> {
    let guard = lock(&UNFINISHED);
    let mut targets = Vec::new();
    for (tmp, target) in guard.iter() {
        let _ = std::fs::remove_file(tmp);
        if !targets.contains(target) {
            targets.push(target.clone());
        }
    }
    // held until exit: no file is committed or created after its temporary was removed
    std::mem::forget(guard);
    targets
}

/// A temporary file beside its target, listed in [`UNFINISHED`] while it exists.
struct Temp {
    file: Option<tempfile::NamedTempFile>,
}

impl Temp {
    /// A new temporary file in `dir` for `target`.
    fn create(dir: &Path, target: &Path) -> std::io::Result<Self> {
        let name = target
            .file_name()
            .map_or("output".into(), |n| n.to_string_lossy());
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        // the mode a new file gets from File::create (0o666 less the umask), not 0o600
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let mut list = lock(&UNFINISHED);
        let file = builder.tempfile_in(dir)?;
        list.push((file.path().to_path_buf(), target.to_path_buf()));
        Ok(Self { file: Some(file) })
    }

    fn file(&mut self) -> &mut tempfile::NamedTempFile {
        self.file
            .as_mut()
            .expect("a Temp holds its file until it is dropped")
    }

    /// Rename onto `target` (and unlist it).
    fn persist(mut self, target: &Path) -> std::io::Result<()> {
        let mut list = lock(&UNFINISHED);
        let file = self
            .file
            .take()
            .expect("a Temp holds its file until it is dropped");
        let tmp = file.path().to_path_buf();
        let r = file.persist(target).map(|_| ()).map_err(|e| e.error);
        // on an error, the temporary file was removed when `e.file` was dropped
        list.retain(|(p, _)| *p != tmp);
        r
    }
}

impl Drop for Temp {
    fn drop(&mut self) {
        if let Some(file) = self.file.take() {
            let mut list = lock(&UNFINISHED);
            let tmp = file.path().to_path_buf();
            drop(file); // removes it
            list.retain(|(p, _)| *p != tmp);
        }
    }
}

impl Write for Temp {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.file().write(buf)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.file().flush()
    }
}

/// A file whose rename a [`Batch`] holds back.
struct Staged {
    temp: Temp,
    target: PathBuf,
    path: PathBuf,
}

thread_local! {
    /// The renames held back by this thread's open [`Batch`], if one is open (a command
    /// writes its outputs on its main thread).
    static STAGED: std::cell::RefCell<Option<Vec<Staged>>> = const { std::cell::RefCell::new(None) };
}

/// The outputs of one command, renamed into place together by [`Batch::commit`]; every
/// [`AtomicFile::commit`] while a batch is open is held back until then (module docs).
/// Dropped without a commit, the held-back files are removed and their targets left as
/// they were. Outputs written directly (a device, a FIFO, stdout) are not held back.
pub struct Batch {
    _open: (),
}

impl Batch {
    /// Hold back every commit on this thread until [`Batch::commit`] (one batch at a time).
    pub fn begin() -> Self {
        STAGED.with(|s| *s.borrow_mut() = Some(Vec::new()));
        Self { _open: () }
    }

    /// Rename every held-back file into place, in the order they were committed. A failed
    /// rename stops there: the files not yet renamed are removed.
    pub fn commit(self) -> Result<(), OutputError> {
        let staged = STAGED.with(|s| s.borrow_mut().take()).unwrap_or_default();
        for s in staged {
            s.temp.persist(&s.target).map_err(|source| OutputError {
                path: s.path,
                source,
            })?;
        }
        Ok(())
    }
}

impl Drop for Batch {
    fn drop(&mut self) {
        let staged = STAGED.with(|s| s.borrow_mut().take());
        drop(staged); // each Temp removes its file
    }
}

/// The paths that name the process's standard output.
const STDOUT_NAMES: [&str; 4] = ["-", "/dev/stdout", "/dev/fd/1", "/proc/self/fd/1"];
/// The paths that name the process's standard error.
const STDERR_NAMES: [&str; 3] = ["/dev/stderr", "/dev/fd/2", "/proc/self/fd/2"];

/// True if `path` names standard output (`-`, `/dev/stdout`, ...): written directly.
pub fn is_stdout(path: &Path) -> bool {
    STDOUT_NAMES.iter().any(|n| path == Path::new(n))
}

/// Where an output goes (module docs).
enum Destination {
    Stdout,
    Stderr,
    /// A device, FIFO or socket: opened and written directly.
    Direct,
    /// A regular file or a new path (symbolic links followed): a temporary file and a
    /// rename onto this path.
    Replace(PathBuf),
}

/// Most symbolic links followed from one output path (as the kernel's limit).
const MAX_LINKS: usize = 40;

fn destination(path: &Path) -> std::io::Result<Destination> {
    if is_stdout(path) {
        return Ok(Destination::Stdout);
    }
    if STDERR_NAMES.iter().any(|n| path == Path::new(n)) {
        return Ok(Destination::Stderr);
    }
    if let Ok(m) = std::fs::metadata(path) {
        // metadata follows links: what the path names in the end
        if !m.is_file() && !m.is_dir() {
            return Ok(Destination::Direct);
        }
    }
    let mut target = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&target) {
            Ok(m) if m.file_type().is_symlink() => {
                let to = std::fs::read_link(&target)?;
                target = match target.parent() {
                    Some(dir) if to.is_relative() => dir.join(to),
                    _ => to,
                };
            }
            _ => return Ok(Destination::Replace(target)),
        }
    }
    Err(std::io::Error::other(format!(
        "more than {MAX_LINKS} symbolic links"
    )))
}

/// Where an [`AtomicFile`]'s bytes go.
enum Sink {
    Temp {
        writer: BufWriter<Temp>,
        target: PathBuf,
    },
    Direct(BufWriter<Box<dyn Write + Send>>),
}

/// The writer of an [`AtomicFile`] (buffered).
pub struct Writer(Option<Sink>);

impl Write for Writer {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match &mut self.0 {
            Some(Sink::Temp { writer, .. }) => writer.write(buf),
            Some(Sink::Direct(w)) => w.write(buf),
            None => Err(std::io::Error::other("the output was already committed")),
        }
    }
    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        match &mut self.0 {
            Some(Sink::Temp { writer, .. }) => writer.write_all(buf),
            Some(Sink::Direct(w)) => w.write_all(buf),
            None => Err(std::io::Error::other("the output was already committed")),
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        match &mut self.0 {
            Some(Sink::Temp { writer, .. }) => writer.flush(),
            Some(Sink::Direct(w)) => w.flush(),
            None => Ok(()),
        }
    }
}

/// A file being written: a buffered temporary file beside its target, renamed into place by
/// [`AtomicFile::commit`]; or, for a device, a FIFO or stdout, the output itself (module
/// docs).
pub struct AtomicFile {
    path: PathBuf,
    writer: Writer,
}

impl AtomicFile {
    /// Start writing `path` (its missing parent directories are created).
    pub fn create(path: &Path) -> Result<Self, OutputError> {
        let err = |source| OutputError {
            path: path.to_path_buf(),
            source,
        };
        let direct = |w: Box<dyn Write + Send>| Sink::Direct(BufWriter::with_capacity(1 << 16, w));
        let mut name = path.to_path_buf();
        let sink = match destination(path).map_err(err)? {
            Destination::Stdout => {
                name = PathBuf::from(STDOUT);
                direct(Box::new(std::io::stdout()))
            }
            Destination::Stderr => direct(Box::new(std::io::stderr())),
            Destination::Direct => {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(err)?;
                direct(Box::new(f))
            }
            Destination::Replace(target) => {
                let dir = match target.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
                    _ => PathBuf::from("."),
                };
                std::fs::create_dir_all(&dir).map_err(|source| OutputError {
                    path: dir.clone(),
                    source,
                })?;
                let tmp = Temp::create(&dir, &target).map_err(err)?;
                Sink::Temp {
                    writer: BufWriter::with_capacity(1 << 16, tmp),
                    target,
                }
            }
        };
        Ok(Self {
            path: name,
            writer: Writer(Some(sink)),
        })
    }

    /// The target path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Where to write (buffered).
    pub fn writer(&mut self) -> &mut Writer {
        &mut self.writer
    }

    /// An I/O error of this file as an [`OutputError`].
    pub fn error(&self, source: std::io::Error) -> OutputError {
        OutputError {
            path: self.path.clone(),
            source,
        }
    }

    /// Flush, sync and rename into place (held back while a [`Batch`] is open); a direct
    /// output is flushed.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let path = std::mem::take(&mut self.path);
        let err = |source| OutputError {
            path: path.clone(),
            source,
        };
        match self.writer.0.take() {
            None => Ok(()),
            Some(Sink::Direct(mut w)) => w.flush().map_err(err),
            Some(Sink::Temp { writer, target }) => {
                let mut temp = writer.into_inner().map_err(|e| err(e.into_error()))?;
                temp.file().as_file().sync_all().map_err(err)?;
                let staged = Staged { temp, target, path };
                // held back by an open batch, else renamed now
                let now = STAGED.with(|s| match s.borrow_mut().as_mut() {
                    Some(list) => {
                        list.push(staged);
                        None
                    }
                    None => Some(staged),
                });
                match now {
                    Some(s) => s.temp.persist(&s.target).map_err(|source| OutputError {
                        path: s.path,
                        source,
                    }),
                    None => Ok(()),
                }
            }
        }
    }
}

/// The name standard output goes by in an [`OutputError`].
pub const STDOUT: &str = "stdout";

/// Write `text` to standard output and flush it: an error (a closed pipe, a full disk) is
/// returned, never a panic.
pub fn print_stdout(text: &str) -> Result<(), OutputError> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|_| out.flush())
        .map_err(|source| OutputError {
            path: PathBuf::from(STDOUT),
            source,
        })
}

/// Write `text` to standard error; a failure to write it (a closed or full stderr) is
/// ignored: it never changes what the command does or its exit status.
pub fn print_stderr(text: &str) {
    let _ = std::io::stderr().lock().write_all(text.as_bytes());
}

/// Write one line to standard error ([`print_stderr`]: failures ignored).
pub fn note(line: impl fmt::Display) {
    print_stderr(&format!("{line}\n"));
}

/// Write `bytes` to `path` whole or not at all.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let mut f = AtomicFile::create(path)?;
    f.writer().write_all(bytes).map_err(|e| f.error(e))?;
    f.commit()
}

/// A float in a CSV: 17 significant digits (`{:.16e}`), which round-trip exactly to f64.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sig17(pub f64);

impl fmt::Display for Sig17 {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:.16e}", self.0)
    }
}

/// What ends the command when a streamed trace's reader has gone ([`on_broken_pipe`]).
static BROKEN_PIPE: std::sync::OnceLock<fn(&Path) -> !> = std::sync::OnceLock::new();

/// Have `stop` end the command as soon as a trace written to a pipe (stdout, a FIFO) finds
/// its reader gone, instead of running to the end for nobody (`dexter run ... --trace - |
/// head`). The CLI sets it (clean up, exit 141); a library caller gets the error from
/// [`TraceFile::commit`].
pub fn on_broken_pipe(stop: fn(&Path) -> !) {
    let _ = BROKEN_PIPE.set(stop);
}

/// One row of a system's `--trace` CSV.
pub trait TraceRow {
    /// The CSV header, column names in order.
    const HEADER: &'static str;
    /// Write the row (with its newline).
    fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()>;
}

/// A `--trace` CSV streamed as rows are produced: header first, then one line per row,
/// committed whole at the end of a successful run.
pub struct TraceFile {
    file: AtomicFile,
    error: Option<std::io::Error>,
}

impl TraceFile {
    /// Start the trace at `path` with `header`.
    pub fn create(path: &Path, header: &str) -> Result<Self, OutputError> {
        let mut file = AtomicFile::create(path)?;
        writeln!(file.writer(), "{header}").map_err(|e| file.error(e))?;
        Ok(Self { file, error: None })
    }

    /// Append a row (the first write error is kept and reported by [`TraceFile::commit`];
    /// a closed pipe ends the command at once if the CLI said how: [`on_broken_pipe`]).
    pub fn push<R: TraceRow>(&mut self, row: &R) {
        if self.error.is_none() {
            if let Err(e) = row.write_csv(self.file.writer()) {
                if e.kind() == std::io::ErrorKind::BrokenPipe {
                    if let Some(stop) = BROKEN_PIPE.get() {
                        stop(self.file.path());
                    }
                }
                self.error = Some(e);
            }
        }
    }

    /// Commit the trace, or report the first write error (the partial file is removed).
    pub fn commit(self) -> Result<(), OutputError> {
        match self.error {
            Some(e) => Err(self.file.error(e)),
            None => self.file.commit(),
        }
    }
}

/// How `--json` objects are printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JsonStyle {
    /// One line.
    Compact,
    /// Indented, one key per line.
    Pretty,
}

/// One JSON object as text.
pub fn json_text(value: &impl serde::Serialize, style: JsonStyle) -> Result<String, String> {
    match style {
        JsonStyle::Compact => serde_json::to_string(value),
        JsonStyle::Pretty => serde_json::to_string_pretty(value),
    }
    .map_err(|e| format!("json: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("dexter-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_file_appears_only_when_committed_and_whole() {
        let dir = scratch("commit");
        let path = dir.join("sub").join("t.csv");
        let mut f = AtomicFile::create(&path).unwrap();
        f.writer().write_all(b"a,b\n1,2\n").unwrap();
        assert!(!path.exists(), "nothing at the target before the commit");
        f.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "a,b\n1,2\n");
        assert_eq!(entries(&dir.join("sub")), ["t.csv"], "no temporary left");
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&path).unwrap().permissions().mode();
            let plain = std::fs::metadata(dir.join("sub"))
                .unwrap()
                .permissions()
                .mode();
            // readable as a file made by File::create is (the umask permitting)
            assert_eq!(mode & 0o444, plain & 0o444, "{mode:o}");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn an_abandoned_file_leaves_the_old_one_and_no_temporary() {
        let dir = scratch("abandon");
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.csv");
        std::fs::write(&path, "old\n").unwrap();
        {
            let mut f = AtomicFile::create(&path).unwrap();
            f.writer().write_all(&[b'x'; 100_000]).unwrap();
        }
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old\n");
        assert_eq!(entries(&dir), ["t.csv"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_failed_rename_leaves_no_temporary() {
        let dir = scratch("rename");
        let target = dir.join("is-a-dir");
        std::fs::create_dir_all(target.join("inside")).unwrap();
        let r = write_atomic(&target, b"data");
        assert!(r.unwrap_err().to_string().contains("is-a-dir"));
        assert_eq!(entries(&dir), ["is-a-dir"]);
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_batch_renames_its_files_together_or_removes_them_all() {
        let dir = scratch("batch");
        std::fs::create_dir_all(&dir).unwrap();
        let (a, b) = (dir.join("a.csv"), dir.join("b.svg"));
        std::fs::write(&a, "old a\n").unwrap();
        {
            let _batch = Batch::begin();
            write_atomic(&a, b"new a\n").unwrap();
            write_atomic(&b, b"new b\n").unwrap();
            assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a\n", "held back");
            assert!(!b.exists());
        } // dropped: a failed command
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a\n");
        assert_eq!(entries(&dir), ["a.csv"], "no temporary left");
        let batch = Batch::begin();
        write_atomic(&a, b"new a\n").unwrap();
        write_atomic(&b, b"new b\n").unwrap();
        assert_eq!(entries(&dir).len(), 3, "a.csv and two temporaries");
        batch.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new a\n");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "new b\n");
        assert_eq!(entries(&dir), ["a.csv", "b.svg"]);
        // no batch open: renamed at once
        write_atomic(&b, b"newer b\n").unwrap();
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "newer b\n");
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_destination_of_a_path_follows_links_and_spares_devices_and_fifos() {
        let dir = scratch("destination");
        std::fs::create_dir_all(dir.join("d")).unwrap();
        for p in ["-", "/dev/stdout", "/dev/fd/1", "/proc/self/fd/1"] {
            assert!(
                matches!(destination(Path::new(p)).unwrap(), Destination::Stdout),
                "{p}"
            );
        }
        assert!(matches!(
            destination(Path::new("/dev/stderr")).unwrap(),
            Destination::Stderr
        ));
        let new = dir.join("new.csv");
        assert!(matches!(destination(&new).unwrap(), Destination::Replace(p) if p == new));
        // a chain of two links, one relative, one absolute, the last dangling
        let end = dir.join("d").join("end.csv");
        std::os::unix::fs::symlink(&end, dir.join("d").join("mid")).unwrap();
        std::os::unix::fs::symlink("d/mid", dir.join("first")).unwrap();
        assert!(
            matches!(destination(&dir.join("first")).unwrap(), Destination::Replace(p) if p == end)
        );
        // a loop is an error, not a hang
        std::os::unix::fs::symlink("loop2", dir.join("loop1")).unwrap();
        std::os::unix::fs::symlink("loop1", dir.join("loop2")).unwrap();
        assert!(destination(&dir.join("loop1")).is_err());
        let fifo = dir.join("fifo");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: a valid NUL-terminated path
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
        assert!(matches!(destination(&fifo).unwrap(), Destination::Direct));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn sig17_round_trips() {
        for x in [0.1 + 0.2, -1e-300, std::f64::consts::PI, 123456.789] {
            assert_eq!(Sig17(x).to_string().parse::<f64>().unwrap(), x);
        }
        assert_eq!(Sig17(2.0).to_string(), "2.0000000000000000e0");
    }
}
