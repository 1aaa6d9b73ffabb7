//! The semihosting plant link: file I/O through the debugger (QEMU) instead of a UART.
//!
//! A plant link is any byte stream implementing `embedded_io::{Read, Write}`; the
//! protocol server (`dexter_firmware::server`) is generic over it. This board offers two:
//! UART0 ([`crate::uart0::Uart0`], the real driver path) and the semihosting files here
//! (fast: one host system call per chunk, no emulated UART).
//!
//! The semihosting link opens three host paths relative to QEMU's working directory:
//! - [`HOST_TO_DEVICE_PATH`], a regular file the host appends frames to. Reading it never
//!   blocks (at its end `SYS_READ` returns no bytes), so the firmware polls it while it
//!   waits for a frame and QEMU never sleeps in the host kernel between two control
//!   steps: the wake-up a blocking read costs on every round trip is gone.
//! - [`DOORBELL_PATH`], a FIFO: after [`POLLS_BEFORE_SLEEP`] empty polls the firmware
//!   writes a lone `0x00` on the device-to-host stream (an empty frame, which every
//!   decoder ignores) and blocks reading one byte here; the host answers each such marker
//!   with one byte. So a host that is slow to send costs a few hundred microseconds of
//!   polling, not a core, and a host that is gone ends the run: the FIFO reads end of
//!   file once no writer is left.
//! - [`DEVICE_TO_HOST_PATH`], a FIFO the firmware writes frames to.
//!
//! defmt logs go to semihosting stdout, a different host file, so logs and link frames
//! never mix.

use core::ffi::CStr;
use cortex_m_semihosting::{nr, syscall};

/// Host path the firmware reads frames from (relative to QEMU's working directory).
pub const HOST_TO_DEVICE_PATH: &CStr = c"dexter-h2d";
/// Host path the firmware writes frames to.
pub const DEVICE_TO_HOST_PATH: &CStr = c"dexter-d2h";
/// Host path of the doorbell FIFO the firmware sleeps on when no frame comes.
pub const DOORBELL_PATH: &CStr = c"dexter-bell";
/// Empty polls of [`HOST_TO_DEVICE_PATH`] before the firmware sleeps on the doorbell: in
/// QEMU 7.2 one poll (a semihosting trap and a host `read`) takes about a microsecond, so
/// the firmware stays awake for a few hundred microseconds, far longer than the host's
/// own work between an answer and the next frame.
pub const POLLS_BEFORE_SLEEP: u32 = 256;

/// Why a link operation failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, defmt::Format)]
pub enum LinkError {
    /// The host file could not be opened.
    Open,
    /// The host reported an I/O error.
    Io,
}

impl embedded_io::Error for LinkError {
    fn kind(&self) -> embedded_io::ErrorKind {
        match self {
            LinkError::Open => embedded_io::ErrorKind::NotFound,
            LinkError::Io => embedded_io::ErrorKind::Other,
        }
    }
}

/// A host file opened through semihosting.
pub struct SemihostingFile {
    handle: usize,
}

impl SemihostingFile {
    /// Open `path` with a semihosting `SYS_OPEN` mode (`nr::open::*`).
    #[inline(never)] // one copy for the link's three files: flash is tight
    pub fn open(path: &CStr, mode: usize) -> Result<Self, LinkError> {
        let len = path.to_bytes().len();
        // Safety: SYS_OPEN reads `len` bytes of the NUL-terminated path.
        let handle = unsafe { syscall!(OPEN, path.as_ptr(), mode, len) };
        if handle as isize == -1 {
            Err(LinkError::Open)
        } else {
            Ok(Self { handle })
        }
    }
}

impl embedded_io::ErrorType for SemihostingFile {
    type Error = LinkError;
}

impl embedded_io::Read for SemihostingFile {
    /// What one host `read` gives: on a FIFO it blocks until at least one byte (or end of
    /// file) is available; on a regular file it returns no bytes at its end.
    #[inline(never)] // one copy for the link's polled file and its doorbell
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        if buf.is_empty() {
            return Ok(0);
        }
        // Safety: SYS_READ writes at most `buf.len()` bytes into `buf`.
        let not_read = unsafe { syscall!(READ, self.handle, buf.as_mut_ptr(), buf.len()) };
        if not_read > buf.len() {
            return Err(LinkError::Io);
        }
        Ok(buf.len() - not_read)
    }
}

impl embedded_io::Write for SemihostingFile {
    fn write(&mut self, buf: &[u8]) -> Result<usize, LinkError> {
        // Safety: SYS_WRITE reads `buf.len()` bytes from `buf`.
        let not_written = unsafe { syscall!(WRITE, self.handle, buf.as_ptr(), buf.len()) };
        if not_written > buf.len() {
            return Err(LinkError::Io);
        }
        Ok(buf.len() - not_written)
    }

    fn flush(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
}

/// The semihosting plant link: a polled file in, a doorbell, a FIFO out (module docs).
pub struct SemihostingLink {
    rx: SemihostingFile,
    bell: SemihostingFile,
    tx: SemihostingFile,
}

impl SemihostingLink {
    /// Open the three host files (the host made and opened its FIFOs read-write first, so
    /// no open blocks).
    pub fn open() -> Result<Self, LinkError> {
        let rx = SemihostingFile::open(HOST_TO_DEVICE_PATH, nr::open::R_BINARY)?;
        let bell = SemihostingFile::open(DOORBELL_PATH, nr::open::R_BINARY)?;
        let tx = SemihostingFile::open(DEVICE_TO_HOST_PATH, nr::open::W_APPEND_BINARY)?;
        Ok(Self { rx, bell, tx })
    }
}

impl embedded_io::ErrorType for SemihostingLink {
    type Error = LinkError;
}

impl embedded_io::Read for SemihostingLink {
    /// Poll for bytes, sleeping on the doorbell between rounds of polls; `Ok(0)` only for
    /// an empty `buf` or once the host has closed the doorbell.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        let mut polls: u32 = 0;
        loop {
            let n = self.rx.read(buf)?;
            if n > 0 || buf.is_empty() {
                return Ok(n);
            }
            polls = polls.wrapping_add(1);
            if polls.is_multiple_of(POLLS_BEFORE_SLEEP) {
                // Tell the host this side sleeps (an empty frame), then wait for its ring.
                if embedded_io::Write::write(&mut self.tx, &[0])? == 0 {
                    return Err(LinkError::Io);
                }
                if self.bell.read(&mut [0])? == 0 {
                    return Ok(0);
                }
            }
        }
    }
}

impl embedded_io::ReadReady for SemihostingLink {
    /// Semihosting has no poll: a read waits for bytes itself (polling, then the
    /// doorbell), so this always says ready.
    fn read_ready(&mut self) -> Result<bool, LinkError> {
        Ok(true)
    }
}

impl embedded_io::Write for SemihostingLink {
    fn write(&mut self, buf: &[u8]) -> Result<usize, LinkError> {
        self.tx.write(buf)
    }

    fn flush(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
}

/// The semihosting command line (QEMU: the kernel path and `-append` words), NUL-free,
/// copied into `buf`; empty if the host does not provide one.
pub fn command_line(buf: &mut [u8]) -> &[u8] {
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // Safety: SYS_GET_CMDLINE writes at most `buf.len()` bytes into `buf` and the length
    // into `block[1]`.
    let r = unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if r != 0 {
        return &[];
    }
    let line = buf.get(..block[1]).unwrap_or(&[]);
    line.split(|&b| b == 0).next().unwrap_or(&[])
}
