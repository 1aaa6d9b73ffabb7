//! Plant links that are not tied to a board: semihosting file I/O.
//!
//! A plant link is any byte stream implementing `embedded_io::{Read, Write}`; the
//! protocol server ([`crate::server`]) is generic over it. Two implementations exist: the
//! board's UART (`board::mps2_an386::Uart0`, the real driver path) and the semihosting
//! files here (fast: one host system call per chunk, no emulated UART).
//!
//! The semihosting link opens two host paths relative to QEMU's working directory,
//! [`HOST_TO_DEVICE_PATH`] for reading and [`DEVICE_TO_HOST_PATH`] for writing; the host
//! makes them FIFOs. defmt logs go to semihosting stdout, a different host file, so logs
//! and link frames never mix.

use core::ffi::CStr;
use cortex_m_semihosting::{nr, syscall};

/// Host path the firmware reads frames from (relative to QEMU's working directory).
pub const HOST_TO_DEVICE_PATH: &CStr = c"dexter-h2d";
/// Host path the firmware writes frames to.
pub const DEVICE_TO_HOST_PATH: &CStr = c"dexter-d2h";

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
    /// Blocks in the host until at least one byte (or end of file) is available.
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

/// The semihosting plant link: one host file per direction.
pub struct SemihostingLink {
    rx: SemihostingFile,
    tx: SemihostingFile,
}

impl SemihostingLink {
    /// Open both directions (the read side first; the host opens its FIFOs so that
    /// neither open blocks).
    pub fn open() -> Result<Self, LinkError> {
        let rx = SemihostingFile::open(HOST_TO_DEVICE_PATH, nr::open::R_BINARY)?;
        let tx = SemihostingFile::open(DEVICE_TO_HOST_PATH, nr::open::W_APPEND_BINARY)?;
        Ok(Self { rx, tx })
    }
}

impl embedded_io::ErrorType for SemihostingLink {
    type Error = LinkError;
}

impl embedded_io::Read for SemihostingLink {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        self.rx.read(buf)
    }
}

impl embedded_io::ReadReady for SemihostingLink {
    /// Semihosting has no poll: reads block in the host, so this always says ready.
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
