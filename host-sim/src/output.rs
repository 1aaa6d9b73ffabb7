//! Output files, the same for every system: written **whole or not at all**, and the CSV
//! number format.
//!
//! An [`AtomicFile`] is a temporary file in the target's directory; [`AtomicFile::commit`]
//! flushes it, syncs it to disk (so a full disk is reported here, not later) and renames it
//! into place. If anything fails first, or the file is dropped without a commit, the
//! temporary file is removed and the target is left as it was: a failed run leaves no
//! partial trace, CSV or plot.
//!
//! A missing parent directory of an output file (`--trace`, `--csv`) is created, as
//! `--plot DIR` creates its directory, for every system.

use std::fmt;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Why an output file could not be written.
#[derive(Debug)]
pub struct OutputError {
    /// The file (or directory) concerned.
    pub path: PathBuf,
    /// The underlying error.
    pub source: std::io::Error,
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

/// A file being written: a buffered temporary file beside its target, renamed into place by
/// [`AtomicFile::commit`].
pub struct AtomicFile {
    path: PathBuf,
    writer: BufWriter<tempfile::NamedTempFile>,
}

impl AtomicFile {
    /// Start writing `path` (its missing parent directories are created).
    pub fn create(path: &Path) -> Result<Self, OutputError> {
        let err = |source| OutputError {
            path: path.to_path_buf(),
            source,
        };
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        std::fs::create_dir_all(dir).map_err(|source| OutputError {
            path: dir.to_path_buf(),
            source,
        })?;
        let name = path
            .file_name()
            .map_or("output".into(), |n| n.to_string_lossy());
        let prefix = format!(".{name}.");
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        // the mode a new file gets from File::create (0o666 less the umask), not 0o600
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let tmp = builder.tempfile_in(dir).map_err(err)?;
        Ok(Self {
            path: path.to_path_buf(),
            writer: BufWriter::with_capacity(1 << 16, tmp),
        })
    }

    /// The target path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Where to write (buffered).
    pub fn writer(&mut self) -> &mut impl Write {
        &mut self.writer
    }

    /// An I/O error of this file as an [`OutputError`].
    pub fn error(&self, source: std::io::Error) -> OutputError {
        OutputError {
            path: self.path.clone(),
            source,
        }
    }

    /// Flush, sync and rename into place.
    pub fn commit(self) -> Result<(), OutputError> {
        let path = self.path;
        let err = |source| OutputError {
            path: path.clone(),
            source,
        };
        let tmp = self.writer.into_inner().map_err(|e| err(e.into_error()))?;
        tmp.as_file().sync_all().map_err(err)?;
        tmp.persist(&path).map_err(|e| err(e.error))?;
        Ok(())
    }
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

    /// Append a row (the first write error is kept and reported by [`TraceFile::commit`]).
    pub fn push<R: TraceRow>(&mut self, row: &R) {
        if self.error.is_none() {
            if let Err(e) = row.write_csv(self.file.writer()) {
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
    fn sig17_round_trips() {
        for x in [0.1 + 0.2, -1e-300, std::f64::consts::PI, 123456.789] {
            assert_eq!(Sig17(x).to_string().parse::<f64>().unwrap(), x);
        }
        assert_eq!(Sig17(2.0).to_string(), "2.0000000000000000e0");
    }
}
