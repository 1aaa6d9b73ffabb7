//! The host end of the semihosting link (`boards/mps2-an386/src/semihosting.rs` is the other end): three
//! files in QEMU's private working directory.
//!
//! - `dexter-h2d`, a regular file the host appends frames to and the firmware polls: a read
//!   at its end returns no bytes instead of blocking, so QEMU stays awake between control
//!   steps and a round trip costs no wake-up on the firmware's side.
//! - `dexter-bell`, a FIFO: a firmware that polled for a while without finding a frame
//!   writes a lone `0x00` (an empty frame, ignored by every decoder) on the device-to-host
//!   stream and blocks reading this FIFO; [`SemihostingFiles::notice`] answers each such
//!   marker with one byte. When the host exits, the FIFO has no writer left, the blocked
//!   read ends, and so does the firmware.
//! - `dexter-d2h`, a FIFO the firmware writes its frames to; the host waits on it with
//!   `poll(2)` (`super::link`).
//!
//! The frame file only grows, so the host frees what the firmware has read: every
//! [`PUNCH_EVERY`] bytes it punches a hole (`fallocate(2)`) over everything older than the
//! last [`KEEP`] bytes. In lock-step the host writes a step's bytes only after the answers
//! to the previous step's delimiters arrived (or after predicting that none reached the
//! firmware, `super::inject`), so at most one step's bytes and one partial frame are
//! unread: fewer than `2 * MAX_FRAME_LEN + 2` bytes, far inside [`KEEP`]. The file's disk
//! use stays below `PUNCH_EVERY + KEEP` however long the run.

use super::qemu::{link_err, WorkDir};
use crate::controller::ControllerError;
use dexter_core::protocol::MAX_FRAME_LEN;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::os::fd::AsRawFd;
use std::path::Path;

use super::SEMIHOSTING_LINK_FILES as FILES;

/// Bytes written between two hole punches.
pub const PUNCH_EVERY: u64 = 1 << 20;
/// Bytes at the end of the frame file that a punch never touches.
pub const KEEP: u64 = 64 << 10;
const _: () = assert!(KEEP >= 4 * (MAX_FRAME_LEN as u64 + 1));

/// Punches start and end on this boundary (the file system frees whole blocks).
const BLOCK: u64 = 4096;

/// The host's three semihosting files, and what it has written and freed.
pub(super) struct SemihostingFiles {
    h2d: File,
    bell: File,
    pub(super) d2h: File,
    written: u64,
    punched: u64,
    /// Whether the last byte from the firmware was a delimiter (true at the start): a
    /// `0x00` after a delimiter is the firmware's "sleeping" marker.
    after_delimiter: bool,
    rings: u64,
}

impl SemihostingFiles {
    /// Make the files in `dir` and open them (the FIFOs read-write, so no open blocks,
    /// whether or not QEMU has opened its ends yet).
    pub(super) fn create(dir: &WorkDir) -> Result<Self, ControllerError> {
        let [h2d, bell, d2h] = FILES.map(|name| dir.path().join(name));
        make_fifo(&bell)?;
        make_fifo(&d2h)?;
        let h2d = OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&h2d)
            .map_err(|e| link_err(format!("cannot create {}: {e}", h2d.display())))?;
        Ok(Self {
            h2d,
            bell: open_fifo(&bell)?,
            d2h: open_fifo(&d2h)?,
            written: 0,
            punched: 0,
            after_delimiter: true,
            rings: 0,
        })
    }

    /// Append `bytes` to the frame file (one system call), then free what the firmware has
    /// surely read (module docs).
    pub(super) fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.h2d.write_all(bytes)?;
        self.written += bytes.len() as u64;
        if self.written - self.punched >= PUNCH_EVERY {
            let end = (self.written - KEEP) / BLOCK * BLOCK;
            punch_hole(&self.h2d, self.punched, end - self.punched)?;
            self.punched = end;
        }
        Ok(())
    }

    /// Look at bytes the firmware sent: ring the doorbell once for each "sleeping" marker.
    pub(super) fn notice(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        for &b in bytes {
            if b == 0 && self.after_delimiter {
                self.bell.write_all(&[1])?;
                self.rings += 1;
            }
            self.after_delimiter = b == 0;
        }
        Ok(())
    }

    /// Times the firmware went to sleep on the doorbell and was woken.
    pub(super) fn rings(&self) -> u64 {
        self.rings
    }
}

fn punch_hole(file: &File, offset: u64, len: u64) -> std::io::Result<()> {
    if len == 0 {
        return Ok(());
    }
    let (Ok(offset), Ok(len)) = (libc::off_t::try_from(offset), libc::off_t::try_from(len)) else {
        return Err(std::io::Error::other("frame file offset out of range"));
    };
    let mode = libc::FALLOC_FL_PUNCH_HOLE | libc::FALLOC_FL_KEEP_SIZE;
    // Safety: a valid open file descriptor and a range inside the file.
    if unsafe { libc::fallocate(file.as_raw_fd(), mode, offset, len) } != 0 {
        let e = std::io::Error::last_os_error();
        return Err(std::io::Error::new(
            e.kind(),
            format!(
                "cannot free the semihosting frame file's read part (fallocate punch hole: \
                 {e}); put TMPDIR on a file system that can (tmpfs, ext4, xfs, btrfs)"
            ),
        ));
    }
    Ok(())
}

fn make_fifo(path: &Path) -> Result<(), ControllerError> {
    use std::os::unix::ffi::OsStrExt;
    let c_path = std::ffi::CString::new(path.as_os_str().as_bytes())
        .map_err(|_| link_err(format!("{} contains a NUL byte", path.display())))?;
    // Safety: `c_path` is a valid NUL-terminated string for the duration of the call.
    if unsafe { libc::mkfifo(c_path.as_ptr(), 0o600) } != 0 {
        return Err(link_err(format!(
            "mkfifo {} failed: {}",
            path.display(),
            std::io::Error::last_os_error()
        )));
    }
    Ok(())
}

/// Open a FIFO read-write: never blocks, whether or not QEMU has opened its end yet.
fn open_fifo(path: &Path) -> Result<File, ControllerError> {
    OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)
        .map_err(|e| link_err(format!("cannot open {}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;
    use std::os::unix::fs::MetadataExt;

    #[test]
    fn the_frame_file_keeps_its_unread_end_and_frees_the_rest() {
        let dir = WorkDir::create().unwrap();
        let mut files = SemihostingFiles::create(&dir).unwrap();
        // 40-byte frames, as the line juggler's: 8 MiB in all.
        let frame: Vec<u8> = (1..=40).collect();
        let total = 8u64 << 20;
        for _ in 0..total / 40 {
            files.write_all(&frame).unwrap();
        }
        let path = dir.path().join(FILES[0]);
        let meta = std::fs::metadata(&path).unwrap();
        assert_eq!(
            meta.len(),
            total / 40 * 40,
            "the apparent size is every byte"
        );
        let on_disk = meta.blocks() * 512;
        assert!(
            on_disk <= PUNCH_EVERY + KEEP + BLOCK,
            "{on_disk} bytes on disk after writing {total}"
        );
        let mut bytes = Vec::new();
        File::open(&path).unwrap().read_to_end(&mut bytes).unwrap();
        let tail = &bytes[bytes.len() - KEEP as usize..];
        let start = (bytes.len() - KEEP as usize) % 40;
        assert!(
            tail.iter()
                .enumerate()
                .all(|(i, &b)| b == frame[(start + i) % 40]),
            "the last KEEP bytes are what was written"
        );
        assert!(bytes[..4096].iter().all(|&b| b == 0), "the start was freed");
    }

    #[test]
    fn each_sleeping_marker_rings_the_doorbell_once() {
        let dir = WorkDir::create().unwrap();
        let mut files = SemihostingFiles::create(&dir).unwrap();
        // A marker at the start, two frames, a marker after a frame (split across two
        // reads), and a marker after a marker.
        files.notice(&[0, 5, 6, 0]).unwrap();
        files.notice(&[0]).unwrap();
        files.notice(&[7, 0, 0, 0]).unwrap();
        assert_eq!(files.rings(), 4);
        let mut bell = File::open(dir.path().join(FILES[1])).unwrap();
        let mut got = [0u8; 8];
        assert_eq!(bell.read(&mut got).unwrap(), 4, "one byte per marker");
    }
}
