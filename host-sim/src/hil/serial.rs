//! HIL against a real board on a serial port (e.g. a NUCLEO-F446RE's ST-LINK virtual COM
//! port, `/dev/ttyACM0`): the same lock-step protocol as the QEMU links, no emulator.
//!
//! [`SerialPortOptions`] in [`HilOptions::serial`](super::HilOptions::serial) selects it;
//! `LockStep::<C>::start` then opens the port (raw 8N1 at the given rate, exclusive, through
//! the `serialport` crate), clears what the board may still hold from an earlier session
//! (`resync`: a lone frame delimiter, then whatever arrives is discarded), and runs the
//! protocol exactly as over QEMU's UART: the host end is a file descriptor read with
//! `poll(2)`, like the FIFO of the semihosting link.
//!
//! What differs from QEMU: the board logs over RTT (probe-rs prints it), not to the host;
//! `Stop` resets the board instead of ending a process; and the step figures in the
//! telemetry are DWT cycles, not instructions, so the controller's instruction budget is
//! not applied unless a budget is given explicitly (`--budget`, in cycles).

use super::qemu::link_err;
use crate::controller::ControllerError;
use serialport::{ClearBuffer, SerialPort, TTYPort};
use std::io::{ErrorKind, Read, Write};
use std::os::fd::AsRawFd;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// The board firmware's host-link rate, Bd (`boards/nucleo-f446re`: `VCP_BAUD`).
pub const DEFAULT_BAUD_RATE: u32 = 921_600;
/// How long [`resync`] listens for leftovers of an earlier session.
const RESYNC_QUIET: Duration = Duration::from_millis(50);

/// A board on a serial port.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SerialPortOptions {
    /// The port, e.g. `/dev/ttyACM0`.
    pub path: PathBuf,
    /// Line rate, Bd (8N1, no flow control).
    pub baud_rate: u32,
}

impl SerialPortOptions {
    /// `path` at [`DEFAULT_BAUD_RATE`].
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            baud_rate: DEFAULT_BAUD_RATE,
        }
    }
}

/// Open the port raw, exclusive, blocking reads (the link polls before it reads); the error
/// names the port and says what to do.
pub(super) fn open(opts: &SerialPortOptions) -> Result<TTYPort, ControllerError> {
    let name = opts.path.to_string_lossy().into_owned();
    if opts.baud_rate == 0 {
        return Err(link_err(format!(
            "serial port {name}: the baud rate must be positive"
        )));
    }
    let mut port = serialport::new(name.as_str(), opts.baud_rate)
        .timeout(Duration::from_secs(1))
        .open_native()
        .map_err(|e| link_err(describe_open_error(&name, &e)))?;
    port.set_exclusive(true).map_err(|e| {
        link_err(format!(
            "serial port {name}: cannot take it exclusively: {e}"
        ))
    })?;
    Ok(port)
}

fn describe_open_error(name: &str, e: &serialport::Error) -> String {
    let hint = match e.kind() {
        serialport::ErrorKind::NoDevice => {
            " (is the board plugged in? `ls /dev/ttyACM*` lists ST-LINK ports)"
        }
        serialport::ErrorKind::Io(ErrorKind::NotFound) => {
            " (no such port: is the board plugged in? `ls /dev/ttyACM*`)"
        }
        serialport::ErrorKind::Io(ErrorKind::PermissionDenied) => {
            " (permission denied: add yourself to the `dialout` group, then log in again)"
        }
        _ => "",
    };
    format!("cannot open serial port {name}: {e}{hint}")
}

/// Start from a clean line: drop what the OS buffered, send a lone `0x00` (which ends any
/// partial frame the board's decoder holds; an empty frame gets no answer), then discard
/// whatever arrives until the line has been quiet for [`RESYNC_QUIET`] (a board left
/// mid-session answers the flushed partial frame), within `timeout`.
pub(super) fn resync(port: &mut TTYPort, timeout: Duration) -> Result<(), ControllerError> {
    let name = port.name().unwrap_or_default();
    let io = |e: std::io::Error| link_err(format!("serial port {name}: {e}"));
    port.clear(ClearBuffer::All)
        .map_err(|e| link_err(format!("serial port {name}: cannot clear its buffers: {e}")))?;
    port.write_all(&[0]).map_err(io)?;
    port.flush().map_err(io)?;
    let deadline = Instant::now() + timeout;
    let mut buf = [0u8; 256];
    while Instant::now() < deadline {
        if !readable(port.as_raw_fd(), RESYNC_QUIET).map_err(io)? {
            return Ok(());
        }
        port.read(&mut buf).map_err(io)?;
    }
    Err(link_err(format!(
        "serial port {name}: the board kept sending for {timeout:?}: is it running another \
         program than dexter's firmware, at {} Bd?",
        port.baud_rate().unwrap_or(0)
    )))
}

/// Whether `fd` has bytes to read within `wait`.
fn readable(fd: std::os::fd::RawFd, wait: Duration) -> std::io::Result<bool> {
    let mut fds = libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    };
    let ms = wait.as_millis().min(i32::MAX as u128) as libc::c_int;
    // Safety: `fds` is one valid pollfd for the duration of the call.
    let ready = unsafe { libc::poll(&mut fds, 1, ms) };
    match ready {
        r if r < 0 => {
            let e = std::io::Error::last_os_error();
            if e.kind() == ErrorKind::Interrupted {
                Ok(true)
            } else {
                Err(e)
            }
        }
        0 => Ok(false),
        _ => Ok(true),
    }
}

#[cfg(test)]
mod tests;
