//! A UART adapter for any board, generic over `embedded_hal_nb::serial::{Read, Write}`
//! (what a HAL's serial receiver and transmitter implement): the receive interrupt's body
//! into a [`ByteRing`] ([`on_receive`]), and the two ways the main code reads it:
//! [`RingLink`], a byte stream (`embedded_io::{Read, ReadReady, Write}`) for the protocol
//! server on the host link, and [`RingReader`], a non-blocking
//! `embedded_hal_nb::serial::Read<u8>` for a sensor's parser (the ball camera's).
//!
//! A UART such as the STM32's USART holds one received byte: at 921 600 Bd a byte arrives
//! every 11 us, so the receive interrupt (the highest priority in the app, a few dozen
//! cycles) moves each byte into the ring at once, and nothing else has to keep up with the
//! line.

use crate::ring::{ByteRing, Consumer, Producer};
use core::sync::atomic::{AtomicU32, Ordering};
use embedded_hal_nb::nb;
use embedded_hal_nb::serial::{ErrorKind, Read as NbRead, Write as NbWrite};

/// Receive ring length, bytes (power of two; one slot stays free).
pub const RX_RING_LEN: usize = 256;
/// Most bytes (or errors) one receive interrupt handles before returning.
const MAX_BYTES_PER_INTERRUPT: usize = 16;

/// Counts a UART's receive errors (overrun, framing, noise, parity).
#[derive(Default)]
pub struct ErrorCount(AtomicU32);

impl ErrorCount {
    /// Zero.
    pub const fn new() -> Self {
        Self(AtomicU32::new(0))
    }

    /// Errors so far.
    pub fn get(&self) -> u32 {
        self.0.load(Ordering::Relaxed)
    }
}

/// The receive interrupt's body: move what the USART holds into the ring; count errors
/// (reading the data register after the status clears them). Returns the last byte moved.
pub fn on_receive<R: NbRead<u8>>(
    rx: &mut R,
    ring: &mut Producer<'static, RX_RING_LEN>,
    errors: &ErrorCount,
) -> Option<u8> {
    let mut last = None;
    for _ in 0..MAX_BYTES_PER_INTERRUPT {
        match rx.read() {
            Ok(byte) => {
                ring.push(byte);
                last = Some(byte);
            }
            Err(nb::Error::WouldBlock) => break,
            Err(nb::Error::Other(_)) => {
                errors.0.fetch_add(1, Ordering::Relaxed);
            }
        }
    }
    last
}

/// The protocol server's link: the ring's consumer, and the UART's transmitter.
pub struct RingLink<T> {
    rx: Consumer<'static, RX_RING_LEN>,
    tx: T,
}

impl<T: NbWrite<u8>> RingLink<T> {
    /// The link from its two halves.
    pub fn new(rx: Consumer<'static, RX_RING_LEN>, tx: T) -> Self {
        Self { rx, tx }
    }
}

/// A transmitter's error as an `embedded_io` error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LinkError(pub ErrorKind);

impl embedded_io::Error for LinkError {
    fn kind(&self) -> embedded_io::ErrorKind {
        embedded_io::ErrorKind::Other
    }
}

fn link_error<E: embedded_hal_nb::serial::Error>(e: E) -> LinkError {
    LinkError(e.kind())
}

impl<T: NbWrite<u8>> embedded_io::ErrorType for RingLink<T> {
    type Error = LinkError;
}

impl<T: NbWrite<u8>> embedded_io::Read for RingLink<T> {
    /// Blocks, sleeping in `wfi`, until at least one byte arrived.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, LinkError> {
        Ok(self.rx.read_waiting(buf, true))
    }
}

impl<T: NbWrite<u8>> embedded_io::ReadReady for RingLink<T> {
    fn read_ready(&mut self) -> Result<bool, LinkError> {
        Ok(!self.rx.is_empty())
    }
}

impl<T: NbWrite<u8>> embedded_io::Write for RingLink<T> {
    /// Writes every byte, waiting for the transmitter (a HAL's own `embedded_io::Write`
    /// may return `Ok(0)` while it is busy, which the server counts as a dead link).
    fn write(&mut self, buf: &[u8]) -> Result<usize, LinkError> {
        for &b in buf {
            nb::block!(NbWrite::write(&mut self.tx, b)).map_err(link_error)?;
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), LinkError> {
        nb::block!(NbWrite::flush(&mut self.tx)).map_err(link_error)
    }
}

/// A non-blocking reader of the ring for a byte parser: a byte, `WouldBlock`, or one
/// `Overrun` error for each receive error the interrupt counted since the last read.
pub struct RingReader {
    rx: Consumer<'static, RX_RING_LEN>,
    errors: &'static ErrorCount,
    errors_reported: u32,
}

impl RingReader {
    /// The reader of `rx`, reporting the errors `errors` counts.
    pub fn new(rx: Consumer<'static, RX_RING_LEN>, errors: &'static ErrorCount) -> Self {
        Self {
            rx,
            errors,
            errors_reported: errors.get(),
        }
    }
}

impl embedded_hal_nb::serial::ErrorType for RingReader {
    type Error = ErrorKind;
}

impl NbRead<u8> for RingReader {
    fn read(&mut self) -> nb::Result<u8, ErrorKind> {
        if self.errors_reported != self.errors.get() {
            self.errors_reported = self.errors_reported.wrapping_add(1);
            return Err(nb::Error::Other(ErrorKind::Overrun));
        }
        self.rx.pop().ok_or(nb::Error::WouldBlock)
    }
}

/// The receive ring of a UART, split once into its interrupt's producer and its reader's
/// consumer; `None` if it was split before.
pub fn split(
    ring: &'static ByteRing<RX_RING_LEN>,
) -> Option<(
    Producer<'static, RX_RING_LEN>,
    Consumer<'static, RX_RING_LEN>,
)> {
    ring.split()
}
