//! A fixed-capacity single-producer single-consumer byte ring: the UART receive interrupt
//! pushes, the main loop pops. `heapless::spsc`'s lock-free queue (two atomic indices, no
//! allocation), with what a receive path adds: a count of the bytes dropped when it was full,
//! and ends that can be taken from a shared `static` once.
//!
//! The single-producer, single-consumer contract is in the types: the ring itself offers
//! no way to push or pop. [`ByteRing::split`] hands out the one [`Producer`] and the one
//! [`Consumer`], once (a second call returns `None`); neither handle is `Clone`, and each
//! operation takes `&mut self`, so there is exactly one writer of the tail index and one
//! of the head index, whatever the caller does.

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use heapless::spsc;

/// SPSC byte ring with `N` slots (`N` a power of two; one slot is kept free, so it holds
/// `N - 1` bytes).
pub struct ByteRing<const N: usize> {
    queue: UnsafeCell<spsc::Queue<u8, N>>,
    dropped: AtomicUsize,
    split: AtomicBool,
}

// Safety: the queue is only reached through the one `Producer` and the one `Consumer` that
// `split` hands out once; `heapless::spsc` makes those two ends safe to use from two
// contexts at once (the producer owns the tail index, the consumer the head).
unsafe impl<const N: usize> Sync for ByteRing<N> {}

impl<const N: usize> Default for ByteRing<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ByteRing<N> {
    /// An empty ring.
    pub const fn new() -> Self {
        const { assert!(N.is_power_of_two() && N >= 2) };
        Self {
            queue: UnsafeCell::new(spsc::Queue::new()),
            dropped: AtomicUsize::new(0),
            split: AtomicBool::new(false),
        }
    }

    /// The producer and consumer ends; `None` if they were handed out before.
    pub fn split(&self) -> Option<(Producer<'_, N>, Consumer<'_, N>)> {
        if self.split.swap(true, Ordering::AcqRel) {
            return None;
        }
        // Safety: the flag above lets this run once, so this is the only `&mut` to the
        // queue ever made; after it the queue is reached only through the two ends.
        let (tx, rx) = unsafe { &mut *self.queue.get() }.split();
        Some((
            Producer {
                tx,
                dropped: &self.dropped,
            },
            Consumer { rx },
        ))
    }

    /// Bytes lost because the ring was full.
    pub fn dropped(&self) -> usize {
        self.dropped.load(Ordering::Relaxed)
    }
}

/// The writing end (the receive interrupt).
pub struct Producer<'a, const N: usize> {
    tx: spsc::Producer<'a, u8>,
    dropped: &'a AtomicUsize,
}

impl<const N: usize> Producer<'_, N> {
    /// Append a byte; counts it as dropped when the ring is full.
    pub fn push(&mut self, byte: u8) {
        if self.tx.enqueue(byte).is_err() {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
    }
}

/// The reading end (the main loop).
pub struct Consumer<'a, const N: usize> {
    rx: spsc::Consumer<'a, u8>,
}

impl<const N: usize> Consumer<'_, N> {
    /// Take the oldest byte.
    pub fn pop(&mut self) -> Option<u8> {
        self.rx.dequeue()
    }

    /// Whether no byte is waiting.
    pub fn is_empty(&self) -> bool {
        !self.rx.ready()
    }

    /// Fill `buf` with the waiting bytes, at least one: a blocking `embedded_io::Read::read`
    /// of a link fed by a receive interrupt. While the ring is empty it sleeps in `wfi` if
    /// `sleep` (else it spins). Returns 0 only for an empty `buf`.
    pub fn read_waiting(&mut self, buf: &mut [u8], sleep: bool) -> usize {
        if buf.is_empty() {
            return 0;
        }
        loop {
            let mut n = 0;
            for slot in buf.iter_mut() {
                let Some(b) = self.pop() else { break };
                *slot = b;
                n += 1;
            }
            if n > 0 {
                return n;
            }
            // Masked, so a byte that arrives between the check and `wfi` still wakes it
            // (a pending interrupt ends `wfi` even while masked).
            if sleep {
                cortex_m::interrupt::free(|_| {
                    if self.is_empty() {
                        cortex_m::asm::wfi();
                    }
                });
            }
        }
    }
}
