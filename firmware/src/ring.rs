//! A fixed-capacity single-producer single-consumer byte ring: the UART receive interrupt
//! pushes, the main loop pops. Lock free (two atomic indices), no allocation.

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicUsize, Ordering};

/// SPSC byte ring with `N` slots (`N` a power of two; one slot is kept free).
pub struct ByteRing<const N: usize> {
    buf: UnsafeCell<[u8; N]>,
    head: AtomicUsize,
    tail: AtomicUsize,
    dropped: AtomicUsize,
}

// Safety: one producer (the ISR) writes slots between tail and head-1 only, one consumer
// (the main loop) reads slots between head and tail only; the indices are atomics.
unsafe impl<const N: usize> Sync for ByteRing<N> {}

impl<const N: usize> Default for ByteRing<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> ByteRing<N> {
    const MASK: usize = {
        assert!(N.is_power_of_two() && N >= 2);
        N - 1
    };

    /// An empty ring.
    pub const fn new() -> Self {
        Self {
            buf: UnsafeCell::new([0; N]),
            head: AtomicUsize::new(0),
            tail: AtomicUsize::new(0),
            dropped: AtomicUsize::new(0),
        }
    }

    /// Producer side: append a byte; counts it as dropped when the ring is full.
    pub fn push(&self, byte: u8) {
        let tail = self.tail.load(Ordering::Relaxed);
        let next = (tail + 1) & Self::MASK;
        if next == self.head.load(Ordering::Acquire) {
            self.dropped.fetch_add(1, Ordering::Relaxed);
            return;
        }
        // Safety: slot `tail` is owned by the producer until `tail` is published.
        unsafe { (*self.buf.get())[tail] = byte };
        self.tail.store(next, Ordering::Release);
    }

    /// Consumer side: take the oldest byte.
    pub fn pop(&self) -> Option<u8> {
        let head = self.head.load(Ordering::Relaxed);
        if head == self.tail.load(Ordering::Acquire) {
            return None;
        }
        // Safety: slot `head` was published by the producer and is not written until
        // `head` moves past it.
        let byte = unsafe { (*self.buf.get())[head] };
        self.head.store((head + 1) & Self::MASK, Ordering::Release);
        Some(byte)
    }

    /// Whether a byte is waiting.
    pub fn is_empty(&self) -> bool {
        self.head.load(Ordering::Acquire) == self.tail.load(Ordering::Acquire)
    }

    /// Bytes lost because the ring was full.
    pub fn dropped(&self) -> usize {
        self.dropped.load(Ordering::Relaxed)
    }
}
