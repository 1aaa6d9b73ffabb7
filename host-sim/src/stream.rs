//! Constant-memory views of a stream of values, so a summary or a plot of a run keeps the
//! same memory whatever the run's length.
//!
//! - [`Tail`]: the last `n` values, in order (period detection, late statistics).
//! - [`Decimator`]: at most `cap` evenly spaced values (plots): every value while fewer
//!   than `cap` have come, then every 2nd, 4th, ... (the stride doubles whenever the kept
//!   values reach `cap`), always starting with the first. A run shorter than `cap` is
//!   plotted exactly.

/// Most points one plotted series keeps ([`Decimator`]); longer series are decimated.
pub const PLOT_MAX_POINTS: usize = 50_000;

/// The last `cap` values of a stream, in order: a ring buffer of a power-of-two number of
/// slots, so a push is a store at `seen & mask` and a count (no wrap test, no modulo; the
/// passive bounce pays it once per impact). Value number `i` (from 0) lives in slot
/// `i & mask`; the kept ones are the last `min(seen, cap)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Tail<T> {
    /// Slots, filled in order until there are `mask + 1` of them.
    buf: Vec<T>,
    /// Slots less one (a power of two less one, at least `cap - 1`).
    mask: usize,
    cap: usize,
    seen: u64,
}

impl<T> Tail<T> {
    /// Keep the last `cap` values.
    pub fn new(cap: usize) -> Self {
        let slots = cap.max(1).next_power_of_two();
        Self {
            buf: Vec::with_capacity(slots.min(1 << 16)),
            mask: slots - 1,
            cap,
            seen: 0,
        }
    }

    /// Add a value.
    #[inline]
    pub fn push(&mut self, v: T) {
        let i = self.seen as usize & self.mask;
        if i < self.buf.len() {
            self.buf[i] = v;
        } else {
            self.buf.push(v);
        }
        self.seen += 1;
    }

    /// The slot of the `k`-th kept value (0 = oldest).
    fn slot(&self, k: usize) -> usize {
        (self.seen as usize - self.len() + k) & self.mask
    }

    /// The kept values, oldest first, as a vector.
    pub fn to_vec(&self) -> Vec<T>
    where
        T: Clone,
    {
        self.iter().cloned().collect()
    }

    /// Iterate over the kept values, oldest first.
    pub fn iter(&self) -> impl DoubleEndedIterator<Item = &T> + ExactSizeIterator {
        (0..self.len()).map(move |k| &self.buf[self.slot(k)])
    }

    /// The newest value.
    pub fn last(&self) -> Option<&T> {
        self.len().checked_sub(1).map(|k| &self.buf[self.slot(k)])
    }

    /// How many values were pushed in all.
    pub fn seen(&self) -> u64 {
        self.seen
    }

    /// How many are kept.
    pub fn len(&self) -> usize {
        self.seen.min(self.cap as u64) as usize
    }

    /// True if none is kept.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// At most `cap` evenly spaced values of a stream (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Decimator<T> {
    kept: Vec<T>,
    cap: usize,
    stride: u64,
    seen: u64,
}

impl<T> Default for Decimator<T> {
    fn default() -> Self {
        Self::new(PLOT_MAX_POINTS)
    }
}

impl<T> Decimator<T> {
    /// Keep at most `cap` (>= 2) values.
    pub fn new(cap: usize) -> Self {
        Self {
            kept: Vec::new(),
            cap: cap.max(2),
            stride: 1,
            seen: 0,
        }
    }

    /// Offer a value.
    pub fn push(&mut self, v: T) {
        if self.seen.is_multiple_of(self.stride) {
            if self.kept.len() == self.cap {
                // keep every other value: the kept ones are now multiples of 2 stride
                let mut i = 0;
                self.kept.retain(|_| {
                    i += 1;
                    i % 2 == 1
                });
                self.stride *= 2;
            }
            if self.seen.is_multiple_of(self.stride) {
                self.kept.push(v);
            }
        }
        self.seen += 1;
    }

    /// The kept values, in stream order.
    pub fn values(&self) -> &[T] {
        &self.kept
    }

    /// Take the kept values.
    pub fn into_values(self) -> Vec<T> {
        self.kept
    }

    /// Values offered in all.
    pub fn seen(&self) -> u64 {
        self.seen
    }

    /// Every kept value is the stream's value at a multiple of this stride.
    pub fn stride(&self) -> u64 {
        self.stride
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tail_keeps_the_last_values_in_order() {
        let mut t = Tail::new(3);
        for i in 0..10 {
            t.push(i);
        }
        assert_eq!(t.iter().copied().collect::<Vec<_>>(), [7, 8, 9]);
        assert_eq!(t.iter().rev().copied().collect::<Vec<_>>(), [9, 8, 7]);
        assert_eq!((t.seen(), t.len(), t.last()), (10, 3, Some(&9)));
        assert_eq!(t.to_vec(), [7, 8, 9]);
        t.push(10);
        assert_eq!(t.last(), Some(&10));
        assert_eq!(t.to_vec(), [8, 9, 10]);
        for n in 0..12 {
            let mut r = Tail::new(4);
            for i in 0..n {
                r.push(i);
            }
            let want: Vec<i32> = (0.max(n - 4)..n).collect();
            assert_eq!(r.iter().copied().collect::<Vec<_>>(), want, "{n}");
            assert_eq!(r.last().copied(), want.last().copied(), "{n}");
            assert_eq!(r.to_vec(), want, "{n}");
        }
        let mut short = Tail::new(5);
        short.push(1.0);
        assert_eq!(short.to_vec(), [1.0]);
        let mut none = Tail::new(0);
        none.push(1);
        assert_eq!((none.len(), none.last(), none.to_vec()), (0, None, vec![]));
        for cap in [1, 3, 5, 8, 9] {
            let mut t = Tail::new(cap);
            for i in 0..40 {
                t.push(i);
                let want: Vec<i32> = (0.max(i + 1 - cap as i32)..=i).collect();
                assert_eq!(t.to_vec(), want, "cap {cap} after {i}");
            }
        }
    }

    #[test]
    fn decimator_is_exact_below_its_cap_and_evenly_strided_above() {
        let mut d = Decimator::new(8);
        for i in 0..8u64 {
            d.push(i);
        }
        assert_eq!(d.values(), &[0, 1, 2, 3, 4, 5, 6, 7]);
        for n in [9u64, 100, 1000, 12345] {
            let mut d = Decimator::new(8);
            for i in 0..n {
                d.push(i);
            }
            let s = d.stride();
            assert!(d.values().len() <= 8 && d.values().len() >= 4, "{n}");
            // the kept values are exactly the multiples of the stride, from 0
            let want: Vec<u64> = (0..n).filter(|i| i % s == 0).collect();
            assert_eq!(d.values(), want.as_slice(), "{n}");
        }
    }
}
