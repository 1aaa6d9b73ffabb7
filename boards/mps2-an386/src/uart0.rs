//! Arm MPS2 with the AN386 image (Cortex-M4F), as QEMU's `-machine mps2-an386` emulates
//! it: CMSDK APB UART0 at `0x4000_4000`, its receive interrupt on IRQ 0, SysTick on the
//! 25 MHz core clock.
//!
//! [`Uart0`] is the plant link driver: the receive interrupt moves bytes from the one-byte
//! receive register into a [`ByteRing`]; reads take from the ring (sleeping in `wfi` while
//! it is empty), writes poll the transmit-full flag.

use core::cell::RefCell;
use core::ptr::{read_volatile, write_volatile};
use cortex_m::interrupt::{InterruptNumber, Mutex};
use cortex_m::peripheral::NVIC;
use dexter_firmware::ring::{ByteRing, Consumer, Producer};

const UART0_BASE: usize = 0x4000_4000;
const DATA: *mut u32 = UART0_BASE as *mut u32;
const STATE: *mut u32 = (UART0_BASE + 0x04) as *mut u32;
const CTRL: *mut u32 = (UART0_BASE + 0x08) as *mut u32;
const INTSTATUS: *mut u32 = (UART0_BASE + 0x0c) as *mut u32;
const BAUDDIV: *mut u32 = (UART0_BASE + 0x10) as *mut u32;

const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_RX_INT_EN: u32 = 1 << 3;
const INT_RX: u32 = 1 << 1;
/// The smallest divider the CMSDK UART accepts (25 MHz / 16 = 1.5625 MBd).
const BAUD_DIVIDER: u32 = 16;

/// SysTick (core clock) frequency, Hz.
pub const SYSTICK_HZ: u32 = 25_000_000;

/// Whether a blocking read sleeps in `wfi` (true) or spins on the ring (false). In QEMU
/// sleeping is also ~3.5x faster: a spinning vCPU delays the I/O thread that delivers bytes.
pub const SLEEP_WHILE_WAITING: bool = true;

/// Receive buffer between the interrupt and the main loop, bytes (power of two).
pub const RX_RING_LEN: usize = 256;
static RX_RING: ByteRing<RX_RING_LEN> = ByteRing::new();
/// The ring's producer end, owned by the receive interrupt once [`Uart0::new`] hands it over.
static RX_PRODUCER: Mutex<RefCell<Option<Producer<'static, RX_RING_LEN>>>> =
    Mutex::new(RefCell::new(None));

/// Interrupt lines of the board this firmware uses.
#[derive(Clone, Copy, Debug)]
#[repr(u16)]
pub enum Irq {
    /// UART0 receive.
    Uart0Rx = 0,
}

// Safety: the numbers are the board's NVIC lines.
unsafe impl InterruptNumber for Irq {
    fn number(self) -> u16 {
        self as u16
    }
}

/// Handles the device interrupts this board uses; called from `DefaultHandler` with the
/// interrupt number (cortex-m-rt is used without a device crate).
pub fn on_interrupt(irqn: i16) {
    if irqn != Irq::Uart0Rx as i16 {
        return;
    }
    cortex_m::interrupt::free(|cs| {
        let Ok(mut producer) = RX_PRODUCER.borrow(cs).try_borrow_mut() else {
            return;
        };
        // Safety: MMIO registers of UART0; only this handler reads DATA.
        // Acknowledge first, then drain: a byte that arrives after the last check raises
        // the interrupt again instead of being acknowledged unread.
        unsafe {
            write_volatile(INTSTATUS, INT_RX);
            while read_volatile(STATE) & STATE_RX_FULL != 0 {
                let byte = read_volatile(DATA) as u8;
                if let Some(p) = producer.as_mut() {
                    p.push(byte);
                }
            }
        }
    });
}

/// UART0 as a plant link: it owns the receive ring's consumer end.
pub struct Uart0 {
    rx: Consumer<'static, RX_RING_LEN>,
}

impl Uart0 {
    /// Enable the transmitter, the receiver and its interrupt; `None` if UART0 was taken
    /// before (there is one receive ring, with one consumer).
    pub fn new(nvic: &mut NVIC) -> Option<Self> {
        let (producer, rx) = RX_RING.split()?;
        let handed_over = cortex_m::interrupt::free(|cs| {
            let mut slot = RX_PRODUCER.borrow(cs).try_borrow_mut().ok()?;
            *slot = Some(producer);
            Some(())
        });
        handed_over?;
        // Safety: MMIO registers of UART0, configured once before the interrupt is unmasked.
        unsafe {
            write_volatile(BAUDDIV, BAUD_DIVIDER);
            write_volatile(CTRL, CTRL_TX_EN | CTRL_RX_EN | CTRL_RX_INT_EN);
            nvic.set_priority(Irq::Uart0Rx, 0);
            NVIC::unmask(Irq::Uart0Rx);
        }
        Some(Self { rx })
    }
}

impl embedded_io::ErrorType for Uart0 {
    type Error = core::convert::Infallible;
}

impl embedded_io::Read for Uart0 {
    /// Blocks (sleeping in `wfi` if [`SLEEP_WHILE_WAITING`]) until at least one byte
    /// arrived.
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        Ok(self.rx.read_waiting(buf, SLEEP_WHILE_WAITING))
    }
}

impl embedded_io::ReadReady for Uart0 {
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(!self.rx.is_empty())
    }
}

impl embedded_io::Write for Uart0 {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        for &b in buf {
            // Safety: MMIO registers of UART0; only the main loop writes DATA.
            unsafe {
                while read_volatile(STATE) & STATE_TX_FULL != 0 {}
                write_volatile(DATA, u32::from(b));
            }
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}
