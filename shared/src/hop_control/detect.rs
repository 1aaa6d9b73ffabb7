//! The pieces of phase detection: a debounce counter for touchdown and liftoff, and the
//! bottom search of the compression phase (running maximum of the sampled compression and
//! a parabola through the samples around it).

use crate::math::Real;

/// Counts consecutive fresh samples for which a transition's condition holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Debounce {
    count: u8,
}

impl Debounce {
    /// Feed one sample's condition; true once it has held for `need` samples in a row.
    #[inline]
    pub fn feed(&mut self, holds: bool, need: u8) -> bool {
        self.count = if holds {
            self.count.saturating_add(1)
        } else {
            0
        };
        self.count >= need
    }

    /// Forget the samples counted so far.
    #[inline]
    pub fn reset(&mut self) {
        self.count = 0;
    }
}

/// The bottom search of one compression phase: the largest sampled compression so far, the
/// sample before it and the first sample after it, and the last three samples, with their
/// step indices.
///
/// The true bottom (maximal compression, chi' = 0) lies between the samples around the
/// maximum. Two estimates of its time, both the vertex of a parabola through three samples
/// (exact for a parabolic peak; for a smooth peak sampled at period dt the error is O(dt^2)
/// of the period, from the peak's asymmetry, against up to dt/2 for the maximum sample):
/// - [`BottomSearch::vertex_offset_steps`], after the fact: through the maximum and its two
///   neighbours;
/// - [`BottomSearch::predicted_vertex_steps`], ahead of time: through the last three samples
///   while they still rise, extrapolated to the vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BottomSearch {
    /// Largest compression so far, m.
    pub max_m: f32,
    /// Its step index.
    pub max_step: u32,
    before: (f32, u32),
    has_before: bool,
    after: (f32, u32),
    has_after: bool,
    /// The last three samples, oldest first.
    recent: [(f32, u32); 3],
    recent_len: u8,
}

/// The vertex of the parabola through (a, d0), (0, 0), (b, d2), a < 0 < b (steps), if it
/// curves down: with s0 = d0/a, s2 = d2/b, q = (s2 - s0)/(b - a), p = s2 - q b, the vertex
/// is at -p / (2 q).
#[inline]
fn vertex(a: f32, d0: f32, b: f32, d2: f32) -> Option<f32> {
    let s0 = d0 / a;
    let s2 = d2 / b;
    let q = (s2 - s0) / (b - a);
    if q < 0.0 {
        Some(-(s2 - q * b) / (2.0 * q))
    } else {
        None
    }
}

/// `to - from` in steps, as f32 (wrapping step counters).
#[inline]
fn steps(from: u32, to: u32) -> f32 {
    to.wrapping_sub(from) as i32 as f32
}

impl BottomSearch {
    /// A search starting with the sample `c_m` (m) at step `step`.
    #[inline]
    pub fn start(c_m: f32, step: u32) -> Self {
        Self {
            max_m: c_m,
            max_step: step,
            before: (0.0, step),
            has_before: false,
            after: (0.0, step),
            has_after: false,
            recent: [(c_m, step); 3],
            recent_len: 1,
        }
    }

    /// Take the next fresh sample.
    #[inline]
    pub fn push(&mut self, c_m: f32, step: u32) {
        if c_m > self.max_m {
            self.before = self.recent[2];
            self.has_before = true;
            self.max_m = c_m;
            self.max_step = step;
            self.has_after = false;
        } else if !self.has_after {
            self.after = (c_m, step);
            self.has_after = true;
        }
        self.recent = [self.recent[1], self.recent[2], (c_m, step)];
        self.recent_len = self.recent_len.saturating_add(1);
    }

    /// Where the bottom lies relative to the maximum sample, in control periods (negative =
    /// earlier): the vertex through (before, max, after), clamped to half way to either
    /// neighbour; 0 without both neighbours or without curvature.
    #[inline]
    pub fn vertex_offset_steps(&self) -> f32 {
        if !(self.has_before && self.has_after) {
            return 0.0;
        }
        let a = steps(self.max_step, self.before.1);
        let b = steps(self.max_step, self.after.1);
        vertex(a, self.before.0 - self.max_m, b, self.after.0 - self.max_m)
            .map_or(0.0, |s| s.clamp_r(0.5 * a, 0.5 * b))
    }

    /// Where the bottom will be relative to step `now`, in control periods, predicted from
    /// the last three samples: `None` unless there are three, they rise (c0 <= c1 <= c2,
    /// c0 < c2) and the parabola through them curves down.
    #[inline]
    pub fn predicted_vertex_steps(&self, now: u32) -> Option<f32> {
        let [(c0, k0), (c1, k1), (c2, k2)] = self.recent;
        if self.recent_len < 3 || !(c0 <= c1 && c1 <= c2 && c0 < c2) {
            return None;
        }
        let v = vertex(steps(k1, k0), c0 - c1, steps(k1, k2), c2 - c1)?;
        Some(v + steps(now, k1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn debounce_needs_consecutive_samples() {
        let mut d = Debounce::default();
        assert!(!d.feed(true, 3));
        assert!(!d.feed(true, 3));
        assert!(!d.feed(false, 3), "a gap restarts the count");
        assert!(!d.feed(true, 3));
        assert!(!d.feed(true, 3));
        assert!(d.feed(true, 3));
        assert!(Debounce::default().feed(true, 1));
    }

    #[test]
    fn vertex_of_a_sampled_parabola_is_exact() {
        // c(t) = 0.2 - 5e-4 (t - t_b)^2 sampled at integer steps, t_b = 10.3 steps: sample 10
        // is the largest (0.2 - 4.5e-5), its neighbours 9 and 11 are 0.2 - 8.45e-4 and 0.2 - 2.45e-4
        let t_b = 10.3f32;
        let c = |k: u32| 0.2 - 5e-4 * (k as f32 - t_b) * (k as f32 - t_b);
        let mut s = BottomSearch::start(c(7), 7);
        for k in 8..=12 {
            s.push(c(k), k);
        }
        assert_eq!(s.max_step, 10);
        let est = s.max_step as f32 + s.vertex_offset_steps();
        assert!((est - t_b).abs() < 1e-3, "{est}");
        // uneven spacing (a skipped sample): still the vertex
        let mut s = BottomSearch::start(c(6), 6);
        for k in [8, 10, 11] {
            s.push(c(k), k);
        }
        let est = s.max_step as f32 + s.vertex_offset_steps();
        assert!((est - t_b).abs() < 1e-3, "{est}");
    }

    #[test]
    fn the_bottom_is_predicted_from_rising_samples() {
        // the same parabola, t_b = 10.3: from samples 7, 8, 9 (rising) the vertex is 1.3
        // steps after step 9
        let t_b = 10.3f32;
        let c = |k: u32| 0.2 - 5e-4 * (k as f32 - t_b) * (k as f32 - t_b);
        let mut s = BottomSearch::start(c(7), 7);
        assert_eq!(s.predicted_vertex_steps(7), None, "one sample");
        s.push(c(8), 8);
        assert_eq!(s.predicted_vertex_steps(8), None, "two samples");
        s.push(c(9), 9);
        let v = s.predicted_vertex_steps(9).unwrap();
        assert!((v - 1.3).abs() < 2e-3, "{v}");
        s.push(c(10), 10);
        let v = s.predicted_vertex_steps(10).unwrap();
        assert!((v - 0.3).abs() < 2e-3, "{v}");
        s.push(c(11), 11); // falling: no prediction
        assert_eq!(s.predicted_vertex_steps(11), None);
        // a straight rise has no vertex
        let mut s = BottomSearch::start(0.0, 0);
        s.push(0.01, 1);
        s.push(0.02, 2);
        assert_eq!(s.predicted_vertex_steps(2), None);
    }

    #[test]
    fn vertex_without_neighbours_or_curvature_is_the_max_sample() {
        let mut s = BottomSearch::start(0.1, 3);
        assert_eq!(s.vertex_offset_steps(), 0.0);
        s.push(0.1, 4); // flat: no curvature, and no sample before the max
        assert_eq!(s.vertex_offset_steps(), 0.0);
        let mut s = BottomSearch::start(0.0, 0);
        s.push(0.1, 1);
        s.push(0.1, 2); // flat top: q = -0.05, p = 0.05 -> vertex +0.5, the midpoint
        assert!((s.vertex_offset_steps() - 0.5).abs() < 1e-6);
    }
}
