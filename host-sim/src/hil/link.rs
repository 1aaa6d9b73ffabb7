//! The host end of the byte link to the firmware: the semihosting files
//! ([`super::semihosting`]), the TCP socket QEMU attaches the UART to, or a real board's
//! serial port. Reads wait with
//! `poll(2)` on the calling thread ([`WaitPolicy`]: at once, or after a spin), in slices,
//! so an emulator that died is noticed at once;
//! one `write` per frame, one `poll` and one `read` per answer, no thread hand-off and no
//! allocation per frame.
//!
//! [`Peer`] is what runs at the other end: a QEMU process, or a board (no process to
//! watch: its port is all the host knows of it).

use super::qemu::{describe_exit, link_err, Qemu, WorkDir};
use super::semihosting::SemihostingFiles;
use super::serial::{self, SerialPortOptions};
use super::LinkKind;
use crate::controller::ControllerError;
use serialport::TTYPort;
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::os::fd::{AsRawFd, RawFd};
use std::time::{Duration, Instant};

/// How long a wait for the firmware's answer looks without sleeping, under
/// [`WaitPolicy::Spin`] and [`WaitPolicy::Adaptive`] (see `Link::receive`).
const SPIN: Duration = Duration::from_micros(200);

/// Under [`WaitPolicy::Adaptive`], the waits that block at once after a spin found nothing.
const BLOCKING_AFTER_MISS: u32 = 64;

/// The environment variable that picks the host's [`WaitPolicy`] (`block`, `spin`,
/// `adaptive`), for measuring them against each other (`scripts/hil-load.sh`).
pub const WAIT_POLICY_VAR: &str = "DEXTER_HIL_WAIT";

/// How the host waits for the firmware's answer. A spinning wait answers within
/// microseconds when a core is free for it, and takes the core from QEMU when none is: on
/// a busy host the emulator then runs only when the spin's time slice ends, and the loop
/// falls 4 to 15 times (BENCHMARKS.md, "HIL on a busy host"). A blocking `poll` costs a
/// wake-up per answer wherever the processes run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WaitPolicy {
    /// Sleep in `poll(2)` at once (the default: its rate does not collapse under load).
    #[default]
    Block,
    /// Look without sleeping for [`SPIN`] first.
    Spin,
    /// Spin while spinning finds the answer; after a spin that found nothing, block for
    /// the next [`BLOCKING_AFTER_MISS`] waits, then try again.
    Adaptive,
}

impl WaitPolicy {
    /// The policy named by [`WAIT_POLICY_VAR`], or the default if it is unset.
    pub fn from_env() -> Result<Self, ControllerError> {
        match std::env::var(WAIT_POLICY_VAR) {
            Err(std::env::VarError::NotPresent) => Ok(Self::default()),
            Ok(v) => Self::parse(&v),
            Err(e) => Err(link_err(format!("{WAIT_POLICY_VAR}: {e}"))),
        }
    }

    /// The policy named `name`; an error naming [`WAIT_POLICY_VAR`] and the choices.
    pub fn parse(name: &str) -> Result<Self, ControllerError> {
        match name {
            "block" => Ok(Self::Block),
            "spin" => Ok(Self::Spin),
            "adaptive" => Ok(Self::Adaptive),
            _ => Err(link_err(format!(
                "{WAIT_POLICY_VAR} = {name:?}: expected block, spin or adaptive"
            ))),
        }
    }
}

/// Bytes read from the link at a time.
const READ_CHUNK: usize = 4096;

/// The host end before QEMU starts.
pub(super) enum Pending {
    Semihosting(SemihostingFiles),
    Tcp(TcpListener),
}

/// Make the host end of `kind` in `workdir`; returns it with the QEMU arguments that
/// attach the firmware's side.
pub(super) fn prepare(
    kind: LinkKind,
    workdir: &WorkDir,
) -> Result<(Pending, Vec<String>), ControllerError> {
    match kind {
        LinkKind::Semihosting => {
            let files = SemihostingFiles::create(workdir)?;
            Ok((
                Pending::Semihosting(files),
                vec!["-serial".into(), "null".into()],
            ))
        }
        LinkKind::Uart => {
            let listener = TcpListener::bind("127.0.0.1:0")
                .map_err(|e| link_err(format!("cannot listen on loopback: {e}")))?;
            let port = listener
                .local_addr()
                .map_err(|e| link_err(format!("no local address: {e}")))?
                .port();
            // nodelay: QEMU writes one byte per send(); with Nagle on, each answer would
            // wait for the host's delayed ACK (~40 ms).
            let args = vec![
                "-chardev".into(),
                format!("socket,id=uart0,host=127.0.0.1,port={port},nodelay=on"),
                "-serial".into(),
                "chardev:uart0".into(),
            ];
            Ok((Pending::Tcp(listener), args))
        }
    }
}

enum Io {
    Semihosting(SemihostingFiles),
    Tcp(TcpStream),
    Serial(TTYPort),
}

/// A connected link.
pub(super) struct Link {
    io: Io,
    buf: Box<[u8; READ_CHUNK]>,
    wait: WaitPolicy,
    /// Waits left that block at once ([`WaitPolicy::Adaptive`]).
    blocking_waits: u32,
}

/// What a wait for bytes found.
pub(super) enum Received<'a> {
    /// Bytes from the firmware.
    Bytes(&'a [u8]),
    /// Nothing within the wait.
    Nothing,
}

impl Link {
    /// Finish connecting once QEMU runs (the UART socket waits for QEMU to connect).
    pub(super) fn connect(
        pending: Pending,
        qemu: &mut Qemu,
        timeout: Duration,
    ) -> Result<Link, ControllerError> {
        let io = match pending {
            Pending::Semihosting(files) => Io::Semihosting(files),
            Pending::Tcp(listener) => {
                let stream = accept_with_deadline(&listener, qemu, timeout)?;
                let _ = stream.set_nodelay(true);
                Io::Tcp(stream)
            }
        };
        Ok(Link {
            io,
            buf: Box::new([0; READ_CHUNK]),
            wait: WaitPolicy::from_env()?,
            blocking_waits: 0,
        })
    }

    /// Open a board's serial port and clear the line ([`serial::resync`]).
    pub(super) fn serial(
        opts: &SerialPortOptions,
        timeout: Duration,
    ) -> Result<Link, ControllerError> {
        let mut port = serial::open(opts)?;
        serial::resync(&mut port, timeout)?;
        Ok(Link {
            io: Io::Serial(port),
            buf: Box::new([0; READ_CHUNK]),
            wait: WaitPolicy::from_env()?,
            blocking_waits: 0,
        })
    }

    /// Write all of `bytes` (one system call for a frame).
    pub(super) fn write_all(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        match &mut self.io {
            Io::Semihosting(files) => files.write_all(bytes),
            Io::Tcp(s) => s.write_all(bytes),
            Io::Serial(p) => p.write_all(bytes),
        }
    }

    /// Times the firmware slept on the semihosting doorbell and was rung awake (0 for the
    /// other links).
    pub(super) fn doorbell_rings(&self) -> u64 {
        match &self.io {
            Io::Semihosting(files) => files.rings(),
            Io::Tcp(_) | Io::Serial(_) => 0,
        }
    }

    fn read_fd(&self) -> RawFd {
        match &self.io {
            Io::Semihosting(files) => files.d2h.as_raw_fd(),
            Io::Tcp(s) => s.as_raw_fd(),
            Io::Serial(p) => p.as_raw_fd(),
        }
    }

    /// How long the next wait looks without sleeping ([`WaitPolicy`]).
    fn spin(&mut self) -> Duration {
        match self.wait {
            WaitPolicy::Block => Duration::ZERO,
            WaitPolicy::Spin => SPIN,
            WaitPolicy::Adaptive if self.blocking_waits > 0 => {
                self.blocking_waits -= 1;
                Duration::ZERO
            }
            WaitPolicy::Adaptive => SPIN,
        }
    }

    /// Wait up to `wait` for bytes and return what one read got.
    pub(super) fn receive(&mut self, wait: Duration) -> std::io::Result<Received<'_>> {
        let mut fds = libc::pollfd {
            fd: self.read_fd(),
            events: libc::POLLIN,
            revents: 0,
        };
        // Round up, so a wait shorter than 1 ms still waits instead of spinning.
        let ms = wait.as_micros().div_ceil(1000).min(i32::MAX as u128) as libc::c_int;
        let spin = self.spin();
        let spin_until = Instant::now() + spin;
        let mut ready = 0;
        while ready == 0 && Instant::now() < spin_until {
            // Safety: `fds` is one valid pollfd for the duration of the call.
            ready = unsafe { libc::poll(&mut fds, 1, 0) };
        }
        if ready == 0 && !spin.is_zero() && self.wait == WaitPolicy::Adaptive {
            self.blocking_waits = BLOCKING_AFTER_MISS;
        }
        if ready == 0 {
            // Safety: as above.
            ready = unsafe { libc::poll(&mut fds, 1, ms) };
        }
        if ready < 0 {
            let e = std::io::Error::last_os_error();
            return match e.kind() {
                std::io::ErrorKind::Interrupted => Ok(Received::Nothing),
                _ => Err(e),
            };
        }
        if ready == 0 {
            return Ok(Received::Nothing);
        }
        let n = match &mut self.io {
            Io::Semihosting(files) => {
                let n = files.d2h.read(&mut self.buf[..])?;
                files.notice(&self.buf[..n])?;
                n
            }
            Io::Tcp(s) => s.read(&mut self.buf[..])?,
            Io::Serial(p) => p.read(&mut self.buf[..])?,
        };
        if n == 0 {
            return Err(std::io::Error::new(
                std::io::ErrorKind::UnexpectedEof,
                "the link was closed",
            ));
        }
        Ok(Received::Bytes(&self.buf[..n]))
    }
}

fn accept_with_deadline(
    listener: &TcpListener,
    qemu: &mut Qemu,
    timeout: Duration,
) -> Result<TcpStream, ControllerError> {
    listener
        .set_nonblocking(true)
        .map_err(|e| link_err(format!("cannot poll the listener: {e}")))?;
    let deadline = Instant::now() + timeout;
    loop {
        match listener.accept() {
            Ok((stream, _)) => {
                stream
                    .set_nonblocking(false)
                    .map_err(|e| link_err(format!("socket: {e}")))?;
                return Ok(stream);
            }
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                if let Some(status) = qemu.exited() {
                    return Err(link_err(format!(
                        "QEMU exited ({}) before connecting its UART",
                        describe_exit(status)
                    )));
                }
                if Instant::now() >= deadline {
                    return Err(link_err(format!(
                        "timeout: QEMU did not connect its UART within {timeout:?}"
                    )));
                }
                std::thread::sleep(Duration::from_millis(5));
            }
            Err(e) => return Err(link_err(format!("accept failed: {e}"))),
        }
    }
}

/// What answers at the other end of the link.
pub(super) enum Peer {
    /// The firmware in QEMU.
    Qemu(Qemu),
    /// A board on a serial port.
    Board(SerialPortOptions),
}

impl Peer {
    /// The exit status, if the peer is a process that has exited (a board never does).
    pub(super) fn exited(&mut self) -> Option<std::process::ExitStatus> {
        match self {
            Peer::Qemu(q) => q.exited(),
            Peer::Board(_) => None,
        }
    }

    /// A link error, with what is known of the peer's state.
    pub(super) fn dead_or(&mut self, msg: String) -> ControllerError {
        match self {
            Peer::Qemu(q) => q.dead_or(msg),
            Peer::Board(opts) => link_err(format!(
                "{msg} (board on {} at {} Bd)",
                opts.path.display(),
                opts.baud_rate
            )),
        }
    }

    /// After `Stop`: QEMU must exit with success; a board resets by itself.
    pub(super) fn wait_success(&mut self, timeout: Duration) -> Result<(), ControllerError> {
        match self {
            Peer::Qemu(q) => q.wait_success(timeout),
            Peer::Board(_) => Ok(()),
        }
    }

    /// The raw defmt log so far (a board logs over RTT instead: empty).
    pub(super) fn log(&self) -> Vec<u8> {
        match self {
            Peer::Qemu(q) => q.log(),
            Peer::Board(_) => Vec::new(),
        }
    }

    /// QEMU's process id; 0 for a board.
    pub(super) fn pid(&self) -> u32 {
        match self {
            Peer::Qemu(q) => q.pid(),
            Peer::Board(_) => 0,
        }
    }

    /// The peer in words, for a timeout message.
    pub(super) fn describe(&self, link: LinkKind) -> String {
        match self {
            Peer::Qemu(_) => format!("{link:?} link, QEMU still running"),
            Peer::Board(opts) => format!("board on {}", opts.path.display()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_wait_policy_is_named_or_refused_by_name() {
        assert_eq!(WaitPolicy::parse("block").unwrap(), WaitPolicy::Block);
        assert_eq!(WaitPolicy::parse("spin").unwrap(), WaitPolicy::Spin);
        assert_eq!(WaitPolicy::parse("adaptive").unwrap(), WaitPolicy::Adaptive);
        assert_eq!(WaitPolicy::default(), WaitPolicy::Block);
        let e = WaitPolicy::parse("Spin").unwrap_err().to_string();
        assert!(
            e.contains("DEXTER_HIL_WAIT") && e.contains("\"Spin\""),
            "{e}"
        );
    }

    #[test]
    fn the_adaptive_wait_blocks_after_a_miss_and_then_tries_again() {
        let files = || {
            let dir = WorkDir::create().unwrap();
            SemihostingFiles::create(&dir).map(|f| (dir, f))
        };
        let (_dir, f) = files().unwrap();
        let mut link = Link {
            io: Io::Semihosting(f),
            buf: Box::new([0; READ_CHUNK]),
            wait: WaitPolicy::Adaptive,
            blocking_waits: 0,
        };
        assert_eq!(link.spin(), SPIN);
        // nothing comes: the spin missed, so the next waits block at once
        assert!(matches!(
            link.receive(Duration::ZERO).unwrap(),
            Received::Nothing
        ));
        for _ in 0..BLOCKING_AFTER_MISS {
            assert_eq!(link.spin(), Duration::ZERO);
        }
        assert_eq!(link.spin(), SPIN);
        link.wait = WaitPolicy::Block;
        assert_eq!(link.spin(), Duration::ZERO);
    }
}
