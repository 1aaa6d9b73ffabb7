//! The one sampled sensor: every measurement the controllers see (the line juggler's ball
//! height, the tilt table's camera pose, the hopper's leg compression, foot switch and body
//! height) is taken by [`Sampled`], assembled from four effects, each with a zero-sized
//! "off" type so that a plant assembled without it pays nothing:
//!
//! | effect | off | on |
//! | --- | --- | --- |
//! | rate ([`Clock`]) | [`AtControlSteps`]: one sample at every control step, sequence number = step | [`Periodic`]: samples every `1/rate` s, at their own times (plant events) |
//! | noise and quantization ([`Measure`]) | [`Exact`] | [`Measured`]: per channel, Gaussian noise N(0, sigma) (one seeded generator, [`NoiseRng`], channels drawn in order, a channel with sigma 0 draws nothing), then rounding to a multiple of its step (0 = none) |
//! | latency ([`Delay`]) | [`NoLatency`]: a sample is seen at once | [`Latency`]: seen `latency_s` after it was taken |
//!
//! A control frame carries the newest delivered sample and its sequence number (a repeated
//! number tells the controller nothing new arrived). Until the first sample is delivered it
//! carries the oldest sample taken (the controller sees it as one sample, then as stale
//! repeats); with none taken at all, no sample ([`Sampled::deliver`] returns `None`).
//!
//! Each system reads its frame through a thin adapter of its own measurement: [`Sensor`]
//! (the line's ball height, [`PerfectSensor`], [`SampledSensor`]),
//! `crate::model::planar::camera` (the pose) and `crate::model::hopper::sampled::sensor`
//! (compression, foot switch, height).

use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

/// When samples are taken.
pub trait Clock {
    /// Time of the next sample between control steps, s (infinite: none, samples are taken
    /// at control steps).
    fn next_sample_time_s(&self) -> f64;
    /// True if a sample is taken at every control step.
    fn at_control_steps(&self) -> bool;
    /// Mark the next sample taken; its sequence number.
    fn advance(&mut self) -> u32;
}

/// One sample at every control step (the rate effect off).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AtControlSteps {
    next: u32,
}

impl Clock for AtControlSteps {
    #[inline(always)]
    fn next_sample_time_s(&self) -> f64 {
        f64::INFINITY
    }
    #[inline(always)]
    fn at_control_steps(&self) -> bool {
        true
    }
    #[inline(always)]
    fn advance(&mut self) -> u32 {
        let s = self.next;
        self.next = self.next.wrapping_add(1);
        s
    }
}

/// Samples every `1/rate` s, the first at t = 0, at their own times.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Periodic {
    period_s: f64,
    next_index: u64,
    /// `next_index * period_s`, s (kept: a loop asks for it several times per step).
    next_time_s: f64,
}

impl Periodic {
    /// Samples at `rate_hz` (> 0), the first at t = 0.
    pub fn new(rate_hz: f64) -> Self {
        Self {
            period_s: 1.0 / rate_hz,
            next_index: 0,
            next_time_s: 0.0,
        }
    }
}

impl Clock for Periodic {
    #[inline]
    fn next_sample_time_s(&self) -> f64 {
        self.next_time_s
    }
    #[inline(always)]
    fn at_control_steps(&self) -> bool {
        false
    }
    #[inline]
    fn advance(&mut self) -> u32 {
        let s = self.next_index as u32;
        self.next_index += 1;
        self.next_time_s = index_time_s(self.next_index, self.period_s);
        s
    }
}

/// The time of step or sample `index` at period `period_s`, s: `index as f64 * period_s`
/// exactly (an index below 2^63 converts through `i64` to the same `f64`), in one
/// instruction on x86-64 where a `u64` conversion takes seven.
#[inline]
pub fn index_time_s(index: u64, period_s: f64) -> f64 {
    debug_assert!(index < 1 << 63);
    index as i64 as f64 * period_s
}

/// What a sample measures of the `N` true values.
pub trait Measure<const N: usize> {
    /// The measured values.
    fn measure(&mut self, truth: [f64; N]) -> [f64; N];
}

/// The true values (noise and quantization off).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Exact;

impl<const N: usize> Measure<N> for Exact {
    #[inline(always)]
    fn measure(&mut self, truth: [f64; N]) -> [f64; N] {
        truth
    }
}

/// One channel's noise and quantization.
#[derive(Clone, Copy, Debug)]
struct Channel {
    /// Standard deviation of the noise (0 = none).
    sigma: f64,
    step: f64,
    /// `sigma > 0` and `step > 0`, as flags (a flag is one comparison a sample, a float
    /// test against zero two more).
    noisy: bool,
    quantized: bool,
    /// `1 / step` (0 without quantization): the quantizer multiplies instead of dividing
    /// on every sample (a division was a tenth of the line's SIL loop). The level
    /// boundaries then sit within an ulp of the exact half-multiples of the step.
    per_step: f64,
}

/// The sensors' noise generator: PCG-64 MCG (128-bit multiplicative congruential state,
/// XSL-RR output), seeded through `SeedableRng::seed_from_u64`. One 128-bit multiply per
/// draw, kept inline in the sampling loop; ChaCha12 (`StdRng`, before) cost ~30
/// instructions a draw in its block refills and a call (`BENCHMARKS.md`). Named, not
/// `SmallRng`, so a seed gives the same noise whatever `rand`'s version.
pub type NoiseRng = rand_pcg::Pcg64Mcg;

/// Standard normal draws (`rand_distr`'s ziggurat over a [`NoiseRng`]) taken in order,
/// drawn [`NORMAL_BLOCK`] at a time: the sampling loop reads one from the block (the same
/// sequence as drawing each on its own), the draws run in a loop of their own that keeps
/// the generator and the ziggurat in registers (BENCHMARKS.md, "SIL at 1 kHz").
#[derive(Clone, Debug)]
struct NormalBlock {
    rng: NoiseRng,
    block: [f64; NORMAL_BLOCK],
    /// The next draw's index in `block` (`NORMAL_BLOCK`: drawn out).
    next: usize,
}

/// Draws in a [`NormalBlock`].
const NORMAL_BLOCK: usize = 64;

impl NormalBlock {
    fn new(seed: u64) -> Self {
        Self {
            rng: NoiseRng::seed_from_u64(seed),
            block: [0.0; NORMAL_BLOCK],
            next: NORMAL_BLOCK,
        }
    }

    /// The next draw.
    #[inline(always)]
    fn draw(&mut self) -> f64 {
        if self.next >= NORMAL_BLOCK {
            self.refill();
        }
        let z = self.block[self.next];
        self.next += 1;
        z
    }

    #[inline(never)]
    fn refill(&mut self) {
        // the generator in a local, so its state stays in registers across the block
        let mut rng = self.rng.clone();
        for pair in self.block.chunks_exact_mut(4) {
            pair[0] = StandardNormal.sample(&mut rng);
            pair[1] = StandardNormal.sample(&mut rng);
            pair[2] = StandardNormal.sample(&mut rng);
            pair[3] = StandardNormal.sample(&mut rng);
        }
        self.rng = rng;
        self.next = 0;
    }
}

/// Gaussian noise and quantization per channel, reproducible from a seed.
#[derive(Clone, Debug)]
pub struct Measured<const N: usize> {
    channels: [Channel; N],
    normal: NormalBlock,
}

impl<const N: usize> Measured<N> {
    /// Noise with standard deviations `sigma` (per channel, in its unit; 0, negative or
    /// not finite = none) and quantization steps `step` (per channel; 0 = none), from `seed`.
    pub fn new(sigma: [f64; N], step: [f64; N], seed: u64) -> Self {
        let channels = core::array::from_fn(|i| Channel {
            sigma: if sigma[i] > 0.0 && sigma[i].is_finite() {
                sigma[i]
            } else {
                0.0
            },
            step: step[i],
            per_step: if step[i] > 0.0 { 1.0 / step[i] } else { 0.0 },
            noisy: sigma[i] > 0.0 && sigma[i].is_finite(),
            quantized: step[i] > 0.0,
        });
        Self {
            channels,
            normal: NormalBlock::new(seed),
        }
    }
}

impl<const N: usize> Measure<N> for Measured<N> {
    #[inline(always)]
    fn measure(&mut self, truth: [f64; N]) -> [f64; N] {
        let mut out = truth;
        for (z, c) in out.iter_mut().zip(&self.channels) {
            if c.noisy {
                // N(0, sigma) as sigma z, z ~ N(0, 1) (rand_distr's ziggurat)
                *z += c.sigma * self.normal.draw();
            }
            if c.quantized {
                *z = round_half_away(*z * c.per_step) * c.step;
            }
        }
        out
    }
}

/// `x.round()` (half away from zero, the sign of zero kept), bit for bit, without the
/// library call `f64::round` becomes on x86-64's baseline (no SSE4.1 `roundsd`). Values of
/// magnitude 2^52 and more are integers already (and NaN and infinities are returned as
/// they are).
#[inline]
pub fn round_half_away(x: f64) -> f64 {
    const INTEGRAL: f64 = 4_503_599_627_370_496.0; // 2^52
    let a = x.abs();
    if a < INTEGRAL {
        // Adding 2^52 rounds `a` to an integer (to nearest, ties to even: the spacing of f64
        // in [2^52, 2^53) is 1) and subtracting it again is exact, as is `a - r`. A tie that
        // went down to even is the one case half away from zero rounds otherwise. No branch on
        // the fraction (as random as the sensor noise, a branch on it was mispredicted half the
        // time) and no integer conversion: 15 instructions where the `i64` version took 27
        // (`BENCHMARKS.md`).
        let r = (a + INTEGRAL) - INTEGRAL;
        let r = r + if a - r == 0.5 { 1.0 } else { 0.0 };
        r.copysign(x)
    } else {
        x
    }
}

/// One measured sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample<const N: usize> {
    /// Sequence number.
    pub seq: u32,
    /// The measured values.
    pub values: [f64; N],
}

/// When a sample becomes visible to the controller.
pub trait Delay<const N: usize> {
    /// A sample taken at `t_s`.
    fn push(&mut self, t_s: f64, sample: Sample<N>);
    /// The newest sample visible at `t_s` (before the first is visible: the oldest taken).
    fn latest(&mut self, t_s: f64) -> Option<Sample<N>>;
    /// The delay, s.
    fn latency_s(&self) -> f64;
}

/// A sample is visible at once (the latency effect off).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoLatency<const N: usize> {
    last: Option<Sample<N>>,
}

impl<const N: usize> Delay<N> for NoLatency<N> {
    #[inline(always)]
    fn push(&mut self, _t_s: f64, sample: Sample<N>) {
        self.last = Some(sample);
    }
    #[inline(always)]
    fn latest(&mut self, _t_s: f64) -> Option<Sample<N>> {
        self.last
    }
    #[inline(always)]
    fn latency_s(&self) -> f64 {
        0.0
    }
}

/// Most samples in flight (taken, not yet delivered) that a validator accepts (the line's
/// `sensor.latency_s` x `sensor.rate_hz`, the hopper's likewise).
pub const MAX_PENDING: usize = 4096;

/// Slots of a [`Latency`] ring: twice [`MAX_PENDING`], a power of two. The ring has this
/// size whatever the latency, so its mask is a constant and its index needs no bounds
/// check (a sized ring's mask load and bounds checks cost 3 instructions a SIL step).
const RING_SLOTS: usize = 2 * MAX_PENDING;
const RING_MASK: u64 = RING_SLOTS as u64 - 1;

/// Slack for the rounding of sample and control times, s.
const TIME_SLACK_S: f64 = 1e-9;

/// A sample is visible `latency_s` after it was taken.
///
/// Sequence numbers are those of the clock, which counts its samples from 0 one by one
/// (both clocks do): the ring keeps only each sample's delivery time and values, and a
/// sample's number is its index in the ring's stream.
#[derive(Clone, Debug)]
pub struct Latency<const N: usize> {
    latency_s: f64,
    /// Samples taken and not yet delivered, (delivery time s, values), push `j` in slot
    /// `j & RING_MASK`, so a push and a delivery are an index and a mask (a `VecDeque`
    /// cost ~40 instructions a step).
    pending: Box<[(f64, [f64; N]); RING_SLOTS]>,
    /// Samples pushed.
    pushed: u64,
    /// Index of the oldest undelivered sample (`pushed` if none); the newest delivered one
    /// is the one before it, still in its slot (the ring never holds more than
    /// `RING_MASK` pending samples, so it is not overwritten), which spares a copy of
    /// it on every delivery.
    delivered: u64,
}

impl<const N: usize> Latency<N> {
    /// A delay of `latency_s` (s, >= 0). The ring holds the newest `2 MAX_PENDING`
    /// samples: when more are waiting (samples much faster than control steps), the
    /// oldest is dropped, which never drops the newest sample due, since at most
    /// [`MAX_PENDING`] of them are still in flight for a validated scene.
    pub fn new(latency_s: f64) -> Self {
        Self {
            latency_s,
            pending: vec![(0.0, [0.0; N]); RING_SLOTS]
                .into_boxed_slice()
                .try_into()
                .expect("a ring of RING_SLOTS slots"),
            pushed: 0,
            delivered: 0,
        }
    }

    /// Sample `index` (still in the ring).
    #[inline]
    fn at(&self, index: u64) -> Sample<N> {
        Sample {
            seq: index as u32,
            values: self.pending[(index & RING_MASK) as usize].1,
        }
    }
}

impl<const N: usize> Delay<N> for Latency<N> {
    #[inline(always)]
    fn push(&mut self, t_s: f64, sample: Sample<N>) {
        debug_assert_eq!(
            sample.seq, self.pushed as u32,
            "consecutive sequence numbers"
        );
        if self.pushed - self.delivered >= RING_MASK {
            // full (samples far faster than frames): drop the oldest, keeping the slot of
            // the newest delivered one
            self.delivered += 1;
        }
        self.pending[(self.pushed & RING_MASK) as usize] = (t_s + self.latency_s, sample.values);
        self.pushed += 1;
    }

    #[inline(always)]
    fn latest(&mut self, t_s: f64) -> Option<Sample<N>> {
        // deliver everything due by now (with slack for the rounding of t)
        let due_by = t_s + TIME_SLACK_S;
        let mut d = self.delivered;
        while d < self.pushed && self.pending[(d & RING_MASK) as usize].0 <= due_by {
            d += 1;
        }
        self.delivered = d;
        if d > 0 {
            Some(self.at(d - 1))
        } else if self.pushed > 0 {
            Some(self.at(0))
        } else {
            None
        }
    }

    fn latency_s(&self) -> f64 {
        self.latency_s
    }
}

/// A sample is visible `latency_s` after it was taken, for samples taken one at each
/// control step `k`, at `index_time_s(k, period_s)` ([`AtControlSteps`]): the frame of step
/// `k` carries sample `k - L`, read from its slot, the sample [`Latency`] would find by
/// comparing times (`L` and why: [`StepLatency::new`]). Only the values are kept; with
/// one sample a step and `L` of them in flight the ring never fills.
#[derive(Clone, Debug)]
pub struct StepLatency<const N: usize> {
    latency_s: f64,
    period_s: f64,
    /// `L`, steps.
    lag: u64,
    /// Frames while at most this many samples have been pushed (steps up to `T`, below)
    /// carry sample `k - L`; later frames compare times ([`Self::by_time`]).
    exact_while_pushed: u64,
    /// Sample `j`'s values in slot `j & RING_MASK`.
    values: Box<[[f64; N]; RING_SLOTS]>,
    /// Samples pushed.
    pushed: u64,
    /// After the exact steps: the oldest sample not yet delivered.
    delivered: u64,
}

impl<const N: usize> StepLatency<N> {
    /// A delay of `latency_s` (s, >= 0) for one sample at every control step of period
    /// `period_s` (s, > 0), sample `j` taken at `index_time_s(j, period_s)`: the frame at
    /// step `k` carries sample `k - L`, `L = ceil((latency_s - slack) / period_s)`, exactly
    /// the sample [`Latency`]'s comparison of times gives.
    ///
    /// Why exactly (`dt` the period, `slack` 1e-9 s, `eps` = f64::EPSILON): sample `j` is
    /// due at step `k` when `fl(fl(j dt) + latency)` is at most `fl(fl(k dt) + slack)`. Up to
    /// time `T` each side is within `2 eps (T + latency + 1)` of its exact value (two
    /// roundings of at most half an ulp each), so the comparison is the exact one,
    /// `(k - j) dt >= latency - slack`, whenever the exact sides differ by more than
    /// `4 eps (T + latency + 1)`. For `k - j = L` they differ by `L dt - (latency - slack)`,
    /// at least 0; for `k - j = L - 1` by `(latency - slack) - (L - 1) dt`, above 0. So up
    /// to `T = min(both) / (8 eps) - latency - 1` (twice the bound, for the rounding of the
    /// two differences themselves) sample `k - L` is due at step `k` and `k - L + 1` is not.
    /// Later steps (after some 5.6e5 s for 4 ms at 1 kHz, whose margin is the slack) and a
    /// latency within rounding of a whole number of periods (a negative `T`) compare the
    /// times.
    pub fn new(latency_s: f64, period_s: f64) -> Self {
        let delay = latency_s - TIME_SLACK_S;
        let lag = (delay / period_s).ceil().max(0.0);
        let above = lag * period_s - delay;
        let below = delay - (lag - 1.0) * period_s;
        let until = above.min(below) / (8.0 * f64::EPSILON) - latency_s - 1.0;
        let exact = until.is_finite() && until >= 0.0 && above >= 0.0 && below > 0.0;
        Self {
            latency_s,
            period_s,
            lag: lag as u64,
            exact_while_pushed: if exact {
                last_step_by(until, period_s) + 1
            } else {
                0
            },
            values: vec![[0.0; N]; RING_SLOTS]
                .into_boxed_slice()
                .try_into()
                .expect("a ring of RING_SLOTS slots"),
            pushed: 0,
            delivered: 0,
        }
    }

    /// Sample `index` (still in the ring).
    #[inline(always)]
    fn at(&self, index: u64) -> Sample<N> {
        Sample {
            seq: index as u32,
            values: self.values[(index & RING_MASK) as usize],
        }
    }

    /// The newest sample due at `t_s` by comparing times, as [`Latency`] does (sample `j`
    /// is due at `index_time_s(j, period_s) + latency_s`): the frames after
    /// `T`, each of which delivers what the steps before left.
    #[cold]
    #[inline(never)]
    fn by_time(&mut self, t_s: f64) -> Sample<N> {
        let due_by = t_s + TIME_SLACK_S;
        let mut d = self
            .delivered
            .max((self.pushed - 1).saturating_sub(self.lag));
        while d < self.pushed && index_time_s(d, self.period_s) + self.latency_s <= due_by {
            d += 1;
        }
        self.delivered = d;
        self.at(d.saturating_sub(1))
    }
}

impl<const N: usize> Delay<N> for StepLatency<N> {
    #[inline(always)]
    fn push(&mut self, t_s: f64, sample: Sample<N>) {
        debug_assert_eq!(t_s, index_time_s(self.pushed, self.period_s));
        debug_assert_eq!(sample.seq, self.pushed as u32);
        self.values[(self.pushed & RING_MASK) as usize] = sample.values;
        self.pushed += 1;
    }

    /// The step's own sample has just been pushed (samples at control steps): step `k` is
    /// the one with `k + 1` pushed.
    #[inline(always)]
    fn latest(&mut self, t_s: f64) -> Option<Sample<N>> {
        debug_assert!(self.pushed > 0);
        debug_assert_eq!(t_s, index_time_s(self.pushed - 1, self.period_s));
        Some(if self.pushed <= self.exact_while_pushed {
            self.at((self.pushed - 1).saturating_sub(self.lag))
        } else {
            self.by_time(t_s)
        })
    }

    fn latency_s(&self) -> f64 {
        self.latency_s
    }
}

/// The last step `k` whose time `index_time_s(k, period_s)` is at most `t_s` (s, >= 0;
/// `period_s` > 0).
fn last_step_by(t_s: f64, period_s: f64) -> u64 {
    let mut k = (t_s / period_s).min(9.0e15) as u64;
    while k > 0 && index_time_s(k, period_s) > t_s {
        k -= 1;
    }
    while k < 9_000_000_000_000_000 && index_time_s(k + 1, period_s) <= t_s {
        k += 1;
    }
    k
}

/// A sensor of `N` values: its clock, what it measures, its delay (module docs).
#[derive(Clone, Debug, Default)]
pub struct Sampled<const N: usize, C, M, D> {
    clock: C,
    measure: M,
    delay: D,
}

impl<const N: usize, C: Clock, M: Measure<N>, D: Delay<N>> Sampled<N, C, M, D> {
    /// The sensor of these effects.
    pub fn with(clock: C, measure: M, delay: D) -> Self {
        Self {
            clock,
            measure,
            delay,
        }
    }

    /// Time of the next sample between control steps, s (infinite: none).
    #[inline]
    pub fn next_sample_time_s(&self) -> f64 {
        self.clock.next_sample_time_s()
    }

    /// Take a sample of `truth` at `t_s`.
    #[inline(always)]
    pub fn take(&mut self, t_s: f64, truth: [f64; N]) {
        let seq = self.clock.advance();
        let values = self.measure.measure(truth);
        self.delay.push(t_s, Sample { seq, values });
    }

    /// The sample a control frame at `t_s` carries (taking the step's sample of `truth`
    /// first when the sensor samples at control steps).
    #[inline(always)]
    pub fn deliver(&mut self, t_s: f64, truth: [f64; N]) -> Option<Sample<N>> {
        if self.clock.at_control_steps() {
            self.take(t_s, truth);
        }
        self.delay.latest(t_s)
    }

    /// The delay from a sample to its delivery, s.
    #[inline]
    pub fn latency_s(&self) -> f64 {
        self.delay.latency_s()
    }
}

/// The line juggler's ball sensor: sample events inside the plant, frames at control steps.
pub trait Sensor {
    /// True if the sensor samples only at control steps (then
    /// [`next_sample_time_s`](Sensor::next_sample_time_s) is always infinite): known from the
    /// type, so a loop skips the sample-time tests.
    fn at_control_steps(&self) -> bool;
    /// Time of the next sample, s (infinite if the sensor samples only at control steps).
    fn next_sample_time_s(&self) -> f64;
    /// Take the sample due at `t_s` of the true height `height_m` (m).
    fn sample(&mut self, t_s: f64, height_m: f64);
    /// The frame content at control step `step` (time `t_s`): sequence number and the
    /// measured height (m), given the true height now (NaN before any sample).
    fn frame(&mut self, step: u64, t_s: f64, height_m: f64) -> (u32, f32);
}

impl<C: Clock, M: Measure<1>, D: Delay<1>> Sensor for Sampled<1, C, M, D> {
    #[inline(always)]
    fn at_control_steps(&self) -> bool {
        self.clock.at_control_steps()
    }
    #[inline(always)]
    fn next_sample_time_s(&self) -> f64 {
        Sampled::next_sample_time_s(self)
    }
    /// Inlined: out of line, the call and its saved registers cost ~40 instructions a SIL
    /// step, more than the draw itself (`BENCHMARKS.md`).
    #[inline(always)]
    fn sample(&mut self, t_s: f64, height_m: f64) {
        self.take(t_s, [height_m]);
    }
    #[inline(always)]
    fn frame(&mut self, _step: u64, t_s: f64, height_m: f64) -> (u32, f32) {
        self.deliver(t_s, [height_m])
            .map_or((0, f32::NAN), |s| (s.seq, s.values[0] as f32))
    }
}

/// The true height at every control step, sequence number = step: the sensor off.
pub type PerfectSensor = Sampled<1, AtControlSteps, Exact, NoLatency<1>>;

/// The ball height sampled at a rate with noise, quantization and latency.
pub type SampledSensor = Sampled<1, Periodic, Measured<1>, Latency<1>>;

/// The ball height sampled at every control step with noise, quantization and latency: a
/// [`SampledSensor`] whose rate is the control rate, without scheduling its samples as
/// plant events or comparing delivery times.
pub type SteppedSensor = Sampled<1, AtControlSteps, Measured<1>, StepLatency<1>>;

impl SampledSensor {
    /// A sensor sampling at `rate_hz` (> 0) with noise `sigma_m` (m), latency `latency_s`
    /// (s) and quantization `quantization_m` (m, 0 = none), reproducible from `seed`.
    pub fn new(rate_hz: f64, sigma_m: f64, latency_s: f64, quantization_m: f64, seed: u64) -> Self {
        Sampled::with(
            Periodic::new(rate_hz),
            Measured::new([sigma_m], [quantization_m], seed),
            Latency::new(latency_s),
        )
    }
}

impl SteppedSensor {
    /// A sensor sampling at every control step of period `period_s` (s, > 0) with noise
    /// `sigma_m` (m), latency `latency_s` (s) and quantization `quantization_m` (m, 0 =
    /// none), reproducible from `seed`: the samples of [`SampledSensor::new`] at rate
    /// `1 / period_s`, bit for bit.
    pub fn new(
        period_s: f64,
        sigma_m: f64,
        latency_s: f64,
        quantization_m: f64,
        seed: u64,
    ) -> Self {
        Sampled::with(
            AtControlSteps::default(),
            Measured::new([sigma_m], [quantization_m], seed),
            StepLatency::new(latency_s, period_s),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latency_delays_delivery_and_quantization_rounds() {
        let mut s = SampledSensor::new(100.0, 0.0, 0.02, 0.01, 1);
        // samples at 0, 0.01, 0.02, 0.03 of heights 0.123, 0.234, ...
        for k in 0..4 {
            let t = s.next_sample_time_s();
            assert!((t - 0.01 * k as f64).abs() < 1e-15);
            s.sample(t, 0.123 + 0.111 * k as f64);
        }
        // at t = 0.025 the samples taken at 0 (due 0.02) is delivered, not the one at 0.01 (due 0.03)
        let (seq, z) = s.frame(0, 0.025, 0.0);
        assert_eq!(seq, 0);
        assert!((z - 0.12).abs() < 1e-6, "{z}");
        let (seq, z) = s.frame(1, 0.05, 0.0);
        assert_eq!(seq, 3);
        assert!((z - 0.46).abs() < 1e-6, "{z}"); // 0.456 -> 0.46
    }

    #[test]
    fn rounding_matches_the_standard_library_bit_for_bit() {
        let special = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.5,
            -1.5,
            2.5,
            -2.5,
            0.49999999999999994,
            -0.49999999999999994,
            4503599627370495.5,
            -4503599627370495.5,
            4503599627370496.0,
            1e300,
            -1e300,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let draws = (0..200_000).map(|k| {
            use rand::Rng;
            let x: f64 = rng.random_range(-1e6..1e6);
            match k % 4 {
                0 => x,
                1 => x.trunc() + 0.5,                     // exact halves
                2 => x * 1e-7,                            // small
                _ => f64::from_bits(rng.random::<u64>()), // any bit pattern
            }
        });
        for x in special.into_iter().chain(draws) {
            let (ours, std) = (round_half_away(x), x.round());
            assert!(
                ours.to_bits() == std.to_bits() || (ours.is_nan() && std.is_nan()),
                "{x:e}: {ours:e} vs {std:e}"
            );
        }
        assert!(round_half_away(f64::NAN).is_nan());
    }

    /// Quantizing by multiplying with the reciprocal of the step gives the level that
    /// dividing by the step gives, except within a few ulps of a half-level (where the two
    /// roundings of the quotient may straddle it), for steps that are not powers of two.
    #[test]
    fn quantizing_by_the_reciprocal_matches_dividing() {
        use rand::Rng;
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let mut near_half = 0;
        for q in [1e-4, 1e-3, 3e-4, 0.01, 7.3e-5] {
            let mut s = SampledSensor::new(1000.0, 0.0, 0.0, q, 1);
            for _ in 0..20_000 {
                let z: f64 = rng.random_range(-2.0..2.0);
                let exact = z / q;
                let got = s.measure.measure([z])[0];
                let want = round_half_away(exact) * q;
                if (exact.abs().fract() - 0.5).abs() < 1e-12 * exact.abs().max(1.0) {
                    near_half += 1;
                    assert!((got - want).abs() <= q * (1.0 + 1e-12), "{z} / {q}");
                } else {
                    assert_eq!(got.to_bits(), want.to_bits(), "{z} / {q}");
                }
            }
        }
        assert!(near_half < 10, "{near_half}");
    }

    #[test]
    fn more_samples_than_the_ring_holds_between_frames_still_deliver_the_newest() {
        // 20 000 samples (2.4 rings) between two frames, 1 ms latency at 1 MHz: the frame
        // at t carries the newest sample taken at or before t - latency
        let (rate, latency) = (1e6, 1e-3);
        let mut s: Sampled<1, Periodic, Exact, Latency<1>> =
            Sampled::with(Periodic::new(rate), Exact, Latency::new(latency));
        for _ in 0..20_000 {
            let t = s.next_sample_time_s();
            s.take(t, [t]);
        }
        let now = 0.019_999_5;
        let got = s.deliver(now, [0.0]).unwrap();
        let newest_due = ((now - latency) * rate).floor();
        assert_eq!(got.seq, newest_due as u32);
        assert!((got.values[0] - newest_due / rate).abs() < 1e-15);
    }

    #[test]
    fn before_the_first_delivery_the_frame_carries_the_oldest_sample() {
        let mut s = SampledSensor::new(100.0, 0.0, 0.02, 0.0, 1);
        let (seq, z) = s.frame(0, 0.0, 0.5);
        assert!(seq == 0 && z.is_nan(), "nothing taken yet: no value");
        s.sample(0.0, 0.25);
        s.sample(0.01, 0.75);
        // neither is due (0.02, 0.03) at 0.015: the frame repeats sample 0, not the truth
        assert_eq!(s.frame(1, 0.015, 0.5), (0, 0.25));
        assert_eq!(s.frame(2, 0.02, 0.5), (0, 0.25));
        assert_eq!(s.frame(3, 0.03, 0.5), (1, 0.75));
    }

    #[test]
    fn the_perfect_sensor_is_the_truth_now_and_costs_nothing() {
        let mut s = PerfectSensor::default();
        assert_eq!(s.next_sample_time_s(), f64::INFINITY);
        for k in 0..3u64 {
            let h = 0.1 * k as f64;
            assert_eq!(s.frame(k, 0.002 * k as f64, h), (k as u32, h as f32));
        }
        assert_eq!(std::mem::size_of::<Exact>(), 0);
    }

    #[test]
    fn channels_draw_in_order_and_skip_the_quiet_ones() {
        // channel 1 has no noise: the generator's draws go to channels 0 and 2, in order,
        // so channel 2 of a three-channel sensor gets the second draw of a one-channel one
        let mut three = Measured::new([0.1, 0.0, 0.1], [0.0; 3], 9);
        let mut one = Measured::new([0.1], [0.0], 9);
        let z = three.measure([0.0, 5.0, 0.0]);
        let a = one.measure([0.0])[0];
        let b = one.measure([0.0])[0];
        assert_eq!(z, [a, 5.0, b]);
    }

    /// Frames of `sensor` at `n` control steps of period `dt` over a moving truth, taking
    /// the samples due first as the line plant does (those at the step itself).
    fn frames<C: Clock, D: Delay<1>>(
        mut sensor: Sampled<1, C, Measured<1>, D>,
        dt: f64,
        n: u64,
    ) -> Vec<(u32, u32)> {
        (0..n)
            .map(|k| {
                let t = index_time_s(k, dt);
                let h = (k as f64 * 0.37).sin();
                while sensor.next_sample_time_s() <= t {
                    sensor.sample(t, h);
                }
                let (seq, z) = sensor.frame(k, t, h);
                (seq, z.to_bits())
            })
            .collect()
    }

    /// The stepped sensor gives the frames of the sampled sensor at the control rate, bit
    /// for bit: latencies that are whole periods, that are not, within the slack of a whole
    /// period (above and below), zero, and longer than a hundred periods.
    #[test]
    fn the_stepped_sensor_is_the_sampled_sensor_at_the_control_rate() {
        for (rate, latency) in [
            (1000.0, 0.004),
            (500.0, 0.004),
            (1000.0, 0.0045),
            (1000.0, 0.004 + 1e-9),
            (1000.0, 0.004 - 5e-10),
            (1000.0, 0.004 + 2e-9),
            (1000.0, 0.0),
            (333.0, 0.31),
            (1000.0, 1e-10),
        ] {
            let dt = 1.0 / rate;
            let sampled = SampledSensor::new(rate, 0.001, latency, 1e-4, 5);
            let stepped = SteppedSensor::new(dt, 0.001, latency, 1e-4, 5);
            assert_eq!(
                frames(sampled, dt, 3000),
                frames(stepped, dt, 3000),
                "rate {rate}, latency {latency}"
            );
        }
    }

    /// Past the steps where the lag is proven (forced to the first few here), the stepped
    /// sensor compares times as the sampled sensor does, with the same frames; and where
    /// the latency is within rounding of a whole number of periods it compares them from
    /// the start.
    #[test]
    fn the_stepped_sensor_compares_times_where_the_lag_is_not_proven() {
        for (latency, proven) in [(0.004, 0), (0.004, 7), (0.0045, 1), (0.31, 200)] {
            let (rate, dt) = (1000.0, 1e-3);
            let mut stepped = SteppedSensor::new(dt, 0.001, latency, 1e-4, 5);
            stepped.delay.exact_while_pushed = proven;
            let sampled = SampledSensor::new(rate, 0.001, latency, 1e-4, 5);
            assert_eq!(frames(sampled, dt, 2000), frames(stepped, dt, 2000));
        }
        // 4 ms at 1 kHz: the margin is the slack, 1e-9 s, proven for some 5.6e5 s
        let lag = StepLatency::<1>::new(0.004, 1e-3);
        assert_eq!(lag.lag, 4);
        let proven_s = lag.exact_while_pushed as f64 * 1e-3;
        assert!((5.0e5..6.0e5).contains(&proven_s), "{proven_s}");
        // a latency within rounding of four periods and the slack: nothing is proven
        let at_the_edge = StepLatency::<1>::new(0.004 + 1e-9, 1e-3);
        assert_eq!(at_the_edge.exact_while_pushed, 0);
    }

    /// Normals drawn a block at a time are the ones drawn one at a time.
    #[test]
    fn normals_from_the_block_are_the_draws_in_order() {
        let mut block = NormalBlock::new(17);
        let mut rng = NoiseRng::seed_from_u64(17);
        for _ in 0..3 * NORMAL_BLOCK + 5 {
            let want: f64 = StandardNormal.sample(&mut rng);
            assert_eq!(block.draw().to_bits(), want.to_bits());
        }
    }

    #[test]
    fn noise_has_the_requested_spread() {
        let mut s = SampledSensor::new(1000.0, 0.002, 0.0, 0.0, 3);
        let n = 20_000;
        let xs: Vec<f64> = (0..n)
            .map(|k| {
                let t = s.next_sample_time_s();
                s.sample(t, 1.0);
                f64::from(s.frame(k, t, 1.0).1) - 1.0
            })
            .collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64).sqrt();
        assert!(mean.abs() < 1e-4, "{mean}");
        assert!((sd - 0.002).abs() < 1e-4, "{sd}");
    }
}
