//! A fixed-capacity single-producer single-consumer byte ring: the UART receive interrupt
//! pushes, the main loop pops. Lock free (two atomic indices), no allocation.
//!
//! The single-producer, single-consumer contract is in the types: the ring itself offers
//! no way to push or pop. [`ByteRing::split`] hands out the one [`Producer`] and the one
//! [`Consumer`], once (a second call returns `None`); neither handle is `Clone`, and each
//! operation takes `&mut self`, so there is exactly one writer of the tail index and one
//! of the head index, whatever the caller does.

use core::cell::UnsafeCell;
use core::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// SPSC byte ring with `N` slots (`N` a power of two; one slot is kept free).
pub struct ByteRing<const N: usize> {
    buf: UnsafeCell<[u8; N]>,
    head: AtomicUsize,
    tail: AtomicUsize,
    dropped: AtomicUsize,
    split: AtomicBool,
}

// Safety: the buffer is only reached through the one `Producer` and the one `Consumer` that
// `split` hands out once (both need `&mut self`). The producer writes slot `tail` only,
// before publishing it with a release store of `tail`; the consumer reads slot `head` only,
// after an acquire load of `tail` shows it published, and frees it with a release store of
// `head`. No slot is ever accessed from both sides at once.
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
            split: AtomicBool::new(false),
        }
    }

    /// The producer and consumer ends; `None` if they were handed out before.
    pub fn split(&self) -> Option<(Producer<'_, N>, Consumer<'_, N>)> {
        if self.split.swap(true, Ordering::AcqRel) {
            return None;
        }
        Some((Producer { ring: self }, Consumer { ring: self }))
    }

    /// Pointer to slot `index & MASK` (always inside the buffer).
    fn slot(&self, index: usize) -> *mut u8 {
        self.buf.get().cast::<u8>().wrapping_add(index & Self::MASK)
    }

    /// Bytes lost because the ring was full.
    pub fn dropped(&self) -> usize {
        self.dropped.load(Ordering::Relaxed)
    }
}

/// The writing end (the receive interrupt).
pub struct Producer<'a, const N: usize> {
    ring: &'a ByteRing<N>,
}

impl<const N: usize> Producer<'_, N> {
    /// Append a byte; counts it as dropped when the ring is full.
    pub fn push(&mut self, byte: u8) {
        let ring = self.ring;
        let tail = ring.tail.load(Ordering::Relaxed);
        let next = (tail + 1) & ByteRing::<N>::MASK;
        if next == ring.head.load(Ordering::Acquire) {
            ring.dropped.fetch_add(1, Ordering::Relaxed);
            return;
        }
        // Safety: `tail & MASK < N`, so the pointer is in the buffer; that one slot is the
        // producer's until `tail` is published (see `Sync`). Only the slot is accessed, never
        // the whole array, so the consumer's concurrent read of another slot does not alias.
        unsafe { ring.slot(tail).write(byte) };
        ring.tail.store(next, Ordering::Release);
    }
}

/// The reading end (the main loop).
pub struct Consumer<'a, const N: usize> {
    ring: &'a ByteRing<N>,
}

impl<const N: usize> Consumer<'_, N> {
    /// Take the oldest byte.
    pub fn pop(&mut self) -> Option<u8> {
        let ring = self.ring;
        let head = ring.head.load(Ordering::Relaxed);
        if head == ring.tail.load(Ordering::Acquire) {
            return None;
        }
        // Safety: `head & MASK < N`, so the pointer is in the buffer; slot `head` was
        // published by the producer and is not written until `head` moves past it.
        let byte = unsafe { ring.slot(head).read() };
        ring.head
            .store((head + 1) & ByteRing::<N>::MASK, Ordering::Release);
        Some(byte)
    }

    /// Whether no byte is waiting.
    pub fn is_empty(&self) -> bool {
        self.ring.head.load(Ordering::Relaxed) == self.ring.tail.load(Ordering::Acquire)
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
