//! Scalar arithmetic behind one API, with the math backend chosen at compile time.
//!
//! The laws are generic over [`Real`], implemented for `f32` (what the MCU runs) and `f64`
//! (what the simulator's physics and its ideal-controller scenes use).
//!
//! For `f32` the transcendental functions come from one of two backends:
//! - **accurate** (default): `libm` (`sqrtf`, `sinf`, `cosf`, `atan2f`), correctly rounded or
//!   within 1 ulp. On a Cortex-M4F `sinf`/`cosf` cost 1,100–2,100 instructions a call because
//!   libm computes their range reduction in f64, which the M4F does in software; `atan2f` ~83.
//! - **fast** (feature `fast-math`): `micromath`'s approximations: `sin`/`cos` ~27 instructions
//!   at ~1e-3 absolute error, `atan2` ~1e-2 rad worst case, `exp` ~2.4e-3 relative on
//!   [-5, 5], but `ln` up to 0.12 absolute (at x = 0.375; measured over (0, 10]): laws that
//!   need a logarithm (the hopper's maps) should not use this backend for it.
//!
//! `sqrt` is correctly rounded in both backends: on hard-float ARM (`target_abi = "eabihf"`,
//! e.g. the Cortex-M4F) it is the FPU's `vsqrt.f32` (14 cycles), elsewhere `libm::sqrtf`
//! (also correctly rounded), so the host and the target compute bit-identical roots and the
//! simulator stays a bit-exact oracle for the firmware. libm's own `sqrtf` is a software
//! routine on ARM (about 53 instructions a call on the M4F, measured in QEMU; see
//! BENCHMARKS.md) where `vsqrt` costs 5 (with the register moves).
//!
//! Independently of the backend, [`sin_poly_f32`] / [`cos_poly_f32`] give an own f32 odd/even
//! polynomial with a documented error bound, cheap on an FPU, for laws that need sin/cos in the
//! control step. The line-juggler step needs none of them: it is polynomial in the ball state.
//!
//! `f64` always uses `libm` (host only in practice).

use core::fmt::Debug;
use core::ops::{Add, Div, Mul, Neg, Sub};

/// A real scalar: `f32` on the target, `f32` or `f64` on the host.
pub trait Real:
    Copy
    + Debug
    + PartialOrd
    + Default
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// 2.
    const TWO: Self;
    /// 1/2.
    const HALF: Self;
    /// pi.
    const PI: Self;
    /// Conversion from an `f64` constant (rounds to nearest for `f32`).
    fn of(value: f64) -> Self;
    /// Widening to `f64` (exact).
    fn to_f64(self) -> f64;
    /// Square root; NaN for negative input.
    fn sqrt(self) -> Self;
    /// Sine of an angle in rad.
    fn sin(self) -> Self;
    /// Cosine of an angle in rad.
    fn cos(self) -> Self;
    /// Four-quadrant arctangent of `self / x`, rad in (-pi, pi].
    fn atan2(self, x: Self) -> Self;
    /// Natural exponential.
    fn exp(self) -> Self;
    /// Natural logarithm.
    fn ln(self) -> Self;
    /// Absolute value.
    fn abs(self) -> Self;
    /// True unless NaN or infinite.
    fn is_finite(self) -> bool;
    /// The smaller of two values; NaN-free inputs assumed (returns `other` if `self` is NaN).
    #[inline]
    fn min_r(self, other: Self) -> Self {
        if self < other {
            self
        } else {
            other
        }
    }
    /// The larger of two values (returns `other` if `self` is NaN).
    #[inline]
    fn max_r(self, other: Self) -> Self {
        if self > other {
            self
        } else {
            other
        }
    }
    /// Clamp to `[lo, hi]` (`lo <= hi` assumed); NaN maps to `lo`.
    ///
    /// Spelled per target, with the same value for every input (the sign of a zero
    /// included; a test checks the two spellings against each other): [`clamp_three_way`]
    /// is the shorter code on the Cortex-M4, [`clamp_lower_then_upper`] on x86-64, where its
    /// second comparison is one `minss` (the three-way form took twelve instructions there
    /// and was a tenth of the line controller's step in SIL).
    #[inline]
    fn clamp_r(self, lo: Self, hi: Self) -> Self {
        #[cfg(target_arch = "arm")]
        {
            clamp_three_way(self, lo, hi)
        }
        #[cfg(not(target_arch = "arm"))]
        {
            clamp_lower_then_upper(self, lo, hi)
        }
    }
}

/// `x` clamped to `[lo, hi]` (`lo <= hi`) by one three-way comparison: above `hi` gives
/// `hi`, at least `lo` gives `x`, anything else (NaN included) gives `lo`.
#[inline(always)]
pub fn clamp_three_way<R: PartialOrd + Copy>(x: R, lo: R, hi: R) -> R {
    if x > hi {
        hi
    } else if x >= lo {
        x
    } else {
        lo
    }
}

/// The same clamp as [`clamp_three_way`] (for `lo <= hi`, every input): first up to `lo`
/// (NaN gives `lo`), then down to `hi` as `hi < y ? hi : y`.
#[inline(always)]
pub fn clamp_lower_then_upper<R: PartialOrd + Copy>(x: R, lo: R, hi: R) -> R {
    let at_least_lo = if x >= lo { x } else { lo };
    if hi < at_least_lo {
        hi
    } else {
        at_least_lo
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const TWO: Self = 2.0;
    const HALF: Self = 0.5;
    const PI: Self = core::f64::consts::PI;
    #[inline]
    fn of(value: f64) -> Self {
        value
    }
    #[inline]
    fn to_f64(self) -> f64 {
        self
    }
    #[inline]
    fn sqrt(self) -> Self {
        libm::sqrt(self)
    }
    #[inline]
    fn sin(self) -> Self {
        libm::sin(self)
    }
    #[inline]
    fn cos(self) -> Self {
        libm::cos(self)
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        libm::atan2(self, x)
    }
    #[inline]
    fn exp(self) -> Self {
        libm::exp(self)
    }
    #[inline]
    fn ln(self) -> Self {
        libm::log(self)
    }
    #[inline]
    fn abs(self) -> Self {
        libm::fabs(self)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const TWO: Self = 2.0;
    const HALF: Self = 0.5;
    const PI: Self = core::f32::consts::PI;
    #[inline]
    fn of(value: f64) -> Self {
        value as f32
    }
    #[inline]
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        backend::sqrt(self)
    }
    #[inline]
    fn sin(self) -> Self {
        backend::sin(self)
    }
    #[inline]
    fn cos(self) -> Self {
        backend::cos(self)
    }
    #[inline]
    fn atan2(self, x: Self) -> Self {
        backend::atan2(self, x)
    }
    #[inline]
    fn exp(self) -> Self {
        backend::exp(self)
    }
    #[inline]
    fn ln(self) -> Self {
        backend::ln(self)
    }
    #[inline]
    fn abs(self) -> Self {
        libm::fabsf(self)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
}

/// Name of the `f32` backend compiled in: `"libm"` or `"micromath"`.
pub const BACKEND: &str = backend::NAME;

/// The hard-float ARM square root (a module of its own so tools can name it: its body is
/// compiled only for the target).
#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
mod fpu {
    /// Correctly rounded f32 square root: the FPU's `vsqrt.f32` on hard-float ARM.
    ///
    /// The value passes through a core register and the scratch register `s15` (declared
    /// clobbered; it is caller-saved under the eabihf calling convention), because naming an FPU
    /// register class for an operand in `asm!` needs an unstable target feature on ARM. Cost:
    /// `vsqrt.f32` (14 cycles on a Cortex-M4) plus four `vmov`s.
    #[inline]
    #[allow(unsafe_code)]
    pub(crate) fn sqrt_f32(x: f32) -> f32 {
        let bits: u32;
        // SAFETY: the block moves `x` into s15, runs `vsqrt.f32`, moves the result out; s15 is
        // declared clobbered; it touches no memory and no stack, and every eabihf target has a
        // VFP unit with this instruction.
        unsafe {
            core::arch::asm!(
                "vmov s15, {x}",
                "vsqrt.f32 s15, s15",
                "vmov {x}, s15",
                x = inout(reg) x.to_bits() => bits,
                out("s15") _,
                options(pure, nomem, nostack),
            );
        }
        f32::from_bits(bits)
    }
}
#[cfg(all(target_arch = "arm", target_abi = "eabihf"))]
pub(crate) use fpu::sqrt_f32;

/// Correctly rounded f32 square root: `libm::sqrtf` where there is no FPU instruction to use.
#[cfg(not(all(target_arch = "arm", target_abi = "eabihf")))]
#[inline]
pub(crate) fn sqrt_f32(x: f32) -> f32 {
    libm::sqrtf(x)
}

#[cfg(not(feature = "fast-math"))]
mod backend {
    pub(super) const NAME: &str = "libm";
    pub(super) use super::sqrt_f32 as sqrt;
    #[inline]
    pub fn sin(x: f32) -> f32 {
        libm::sinf(x)
    }
    #[inline]
    pub fn cos(x: f32) -> f32 {
        libm::cosf(x)
    }
    #[inline]
    pub fn atan2(y: f32, x: f32) -> f32 {
        libm::atan2f(y, x)
    }
    #[inline]
    pub fn exp(x: f32) -> f32 {
        libm::expf(x)
    }
    #[inline]
    pub fn ln(x: f32) -> f32 {
        libm::logf(x)
    }
}

#[cfg(feature = "fast-math")]
use micromath_backend as backend;

#[cfg(feature = "fast-math")]
mod micromath_backend {
    use micromath::F32Ext;
    pub(super) const NAME: &str = "micromath";
    pub(super) use super::sqrt_f32 as sqrt;
    #[inline]
    pub fn sin(x: f32) -> f32 {
        F32Ext::sin(x)
    }
    #[inline]
    pub fn cos(x: f32) -> f32 {
        F32Ext::cos(x)
    }
    #[inline]
    pub fn atan2(y: f32, x: f32) -> f32 {
        F32Ext::atan2(y, x)
    }
    #[inline]
    pub fn exp(x: f32) -> f32 {
        F32Ext::exp(x)
    }
    #[inline]
    pub fn ln(x: f32) -> f32 {
        F32Ext::ln(x)
    }
}

/// Sine by an odd degree-9 minimax-style polynomial after reduction to [-pi/2, pi/2], f32.
///
/// Valid for |x| <= 1e4 rad (a bounded, loop-free range reduction by rounding to a multiple
/// of pi). Absolute error <= 2e-6 over [-pi, pi] (tested against `f64` sine); no f64 and no
/// loop, ~20 FPU instructions on a Cortex-M4F.
pub fn sin_poly_f32(x: f32) -> f32 {
    const INV_PI: f32 = core::f32::consts::FRAC_1_PI;
    // pi split in two for an accurate reduction x - k*pi
    const PI_HI: f32 = 3.140_625;
    const PI_LO: f32 = 9.676_536e-4;
    let k = libm::roundf(x * INV_PI);
    let r = (x - k * PI_HI) - k * PI_LO;
    // Taylor coefficients to degree 11 on [-pi/2, pi/2]: truncation error < 6e-8 * ...
    let r2 = r * r;
    let p = r
        * (1.0
            + r2 * (-1.666_666_7e-1
                + r2 * (8.333_333e-3
                    + r2 * (-1.984_127e-4 + r2 * (2.755_731_9e-6 + r2 * -2.505_210_8e-8)))));
    // sin(r + k*pi) = (-1)^k sin(r); k is exact in f32 for |x| <= 1e4
    if (k as i32) & 1 == 0 {
        p
    } else {
        -p
    }
}

/// Cosine via [`sin_poly_f32`]: cos x = sin(x + pi/2). Same error bound, f32.
pub fn cos_poly_f32(x: f32) -> f32 {
    sin_poly_f32(x + core::f32::consts::FRAC_PI_2)
}

/// Sine and cosine together, f32: one range reduction, then an odd degree-9 polynomial for
/// the sine and an even degree-8 polynomial for the cosine on [-pi/2, pi/2].
///
/// The coefficients are Chebyshev (near-minimax) fits of sin(r)/r and cos(r) in r^2 on
/// [0, (pi/2)^2] (mpmath `chebyfit`, 4.3e-9 and 4.7e-8 approximation error); with f32
/// rounding (the cosine's cancellation near +-pi/2 dominates) the absolute error is
/// <= 2.5e-7 on [-2 pi, 2 pi] (measured 2.1e-7) and <= 5e-7 on [-1e4, 1e4] rad (tested
/// against `f64`). The
/// reduction is loop-free: k = nearest integer of x / (2 pi) by a saturating f32-to-i32
/// conversion (one `vcvt` on the Cortex-M4F), r = x - 2 pi k with 2 pi split in two parts,
/// then r folded into [-pi/2, pi/2] (sin(pi - r) = sin r, cos(pi - r) = -cos r). No call, no
/// f64, no loop: about 30 FPU instructions and constant loads on the M4F, which is why the
/// tilt controller ships with it ([`crate::tilt_control`]). |x| > 1e4 is clamped to +-1e4
/// first (the reduction stays exact there); NaN gives NaN.
#[inline(never)]
pub fn sin_cos_poly_f32(x: f32) -> (f32, f32) {
    const LIMIT: f32 = 1.0e4;
    const INV_TWO_PI: f32 = 0.159_154_94;
    // 2 pi = TWO_PI_HI + TWO_PI_LO; TWO_PI_HI has 9 significant bits, so k * TWO_PI_HI is
    // exact for |k| < 2^14 (|x| <= 1e4 gives |k| <= 1592)
    const TWO_PI_HI: f32 = 6.281_25;
    const TWO_PI_LO: f32 = 1.935_307_2e-3;
    const PI: f32 = core::f32::consts::PI;
    // pi - PI (the f32 pi is 8.7e-8 above pi): restores the fold's accuracy
    const PI_LO: f32 = -8.742_278e-8;
    const HALF_PI: f32 = core::f32::consts::FRAC_PI_2;
    // NaN stays NaN (clamp returns it); the bounds are constants in order: no panic
    let x = x.clamp(-LIMIT, LIMIT);
    let half = if x >= 0.0 { 0.5 } else { -0.5 };
    let k = (x * INV_TWO_PI + half) as i32 as f32;
    let r = (x - k * TWO_PI_HI) - k * TWO_PI_LO;
    let (r, cos_sign) = if r > HALF_PI {
        ((PI - r) + PI_LO, -1.0)
    } else if r < -HALF_PI {
        ((-PI - r) - PI_LO, -1.0)
    } else {
        (r, 1.0)
    };
    let u = r * r;
    // the fitted coefficients rounded to f32 (the sine's leading 0.9999999957 is 1.0)
    let s = r
        * (1.0
            + u * (-0.166_666_58 + u * (8.333_05e-3 + u * (-1.980_901_7e-4 + u * 2.605_107_7e-6))));
    let c = 0.999_999_94
        + u * (-0.499_999_05 + u * (4.166_357_2e-2 + u * (-1.385_362_9e-3 + u * 2.315_241_7e-5)));
    (s, cos_sign * c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both spellings of the clamp, and so `clamp_r` on any target, give bit for bit the
    /// plain three-way comparison written out here (above `hi`: `hi`; at least `lo`: the
    /// value; else, NaN included: `lo`), for every ordered pair of bounds and value drawn
    /// from zeros of both signs, infinities, NaN, subnormals and ordinary numbers, in f32
    /// and f64.
    #[test]
    fn both_clamp_spellings_are_the_three_way_comparison_bit_for_bit() {
        fn by_hand(x: f64, lo: f64, hi: f64) -> f64 {
            if x > hi {
                return hi;
            }
            if x >= lo {
                return x;
            }
            lo
        }
        fn same(a: f64, b: f64) -> bool {
            a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
        }
        let v32 = [
            0.0f32,
            -0.0,
            1.0,
            -1.0,
            0.5,
            -2.5,
            1e-40,
            -1e-40,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut checked = 0;
        for &lo in &v32 {
            for &hi in &v32 {
                if lo > hi || lo.is_nan() || hi.is_nan() {
                    continue;
                }
                for &x in &v32 {
                    let want = by_hand(f64::from(x), f64::from(lo), f64::from(hi));
                    let got32 = [
                        clamp_three_way(x, lo, hi),
                        clamp_lower_then_upper(x, lo, hi),
                        x.clamp_r(lo, hi),
                    ];
                    for g in got32 {
                        assert!(
                            same(f64::from(g), want),
                            "{x} in [{lo}, {hi}]: {g} vs {want}"
                        );
                    }
                    let (x, lo, hi) = (f64::from(x), f64::from(lo), f64::from(hi));
                    let got64 = [
                        clamp_three_way(x, lo, hi),
                        clamp_lower_then_upper(x, lo, hi),
                        x.clamp_r(lo, hi),
                    ];
                    assert!(got64.iter().all(|&g| same(g, want)), "{x} in [{lo}, {hi}]");
                    checked += 1;
                }
            }
        }
        assert!(checked > 500, "{checked}");
    }

    #[test]
    fn poly_sin_cos_error_bound_holds_over_two_periods() {
        let mut worst = 0.0f64;
        for i in 0..=20_000 {
            let x =
                -2.0 * core::f64::consts::PI + 4.0 * core::f64::consts::PI * (i as f64) / 20_000.0;
            let xs = x as f32;
            let es = (sin_poly_f32(xs) as f64 - (xs as f64).sin()).abs();
            let ec = (cos_poly_f32(xs) as f64 - (xs as f64).cos()).abs();
            worst = worst.max(es).max(ec);
        }
        assert!(worst <= 2e-6, "worst abs error {worst:e}");
    }

    #[test]
    fn backend_sqrt_is_accurate_enough_for_either_backend() {
        for &x in &[1e-6f32, 0.01, 0.5, 2.0, 9.81, 1234.5, 1e6] {
            let rel = ((Real::sqrt(x) as f64) - (x as f64).sqrt()).abs() / (x as f64).sqrt();
            assert!(rel < 1e-7, "sqrt({x}) rel error {rel:e} with {BACKEND}");
        }
        assert_eq!(Real::sqrt(0.0f32), 0.0);
        assert!(Real::sqrt(-1.0f32).is_nan());
    }

    /// Every `Real` function against std's f64 (an independent implementation), at a few
    /// arguments each; the tolerance is the backend's documented accuracy.
    #[test]
    fn real_functions_match_std_for_f32_and_f64() {
        let (tol_trig, tol_atan, tol_exp, tol_ln) = if BACKEND == "libm" {
            (1e-6, 1e-6, 1e-6, 1e-6)
        } else {
            // micromath: ln is far worse than the rest (0.118 at x = 0.375)
            (2e-3, 2e-2, 3e-3, 0.12)
        };
        for &x in &[-2.5f64, -0.3, 0.7, 1.9, 3.0] {
            let xf = x as f32;
            let xe = xf as f64;
            assert!(
                (Real::sin(xf).to_f64() - xe.sin()).abs() < tol_trig,
                "sin {x}"
            );
            assert!(
                (Real::cos(xf).to_f64() - xe.cos()).abs() < tol_trig,
                "cos {x}"
            );
            let a = Real::atan2(xf, 0.8f32).to_f64();
            assert!((a - xe.atan2(0.8f32 as f64)).abs() < tol_atan, "atan2 {x}");
            let ex = Real::exp(xf).to_f64();
            assert!((ex - xe.exp()).abs() < tol_exp * xe.exp(), "exp {x}");
            let ln = Real::ln(xf.abs()).to_f64();
            assert!((ln - xe.abs().ln()).abs() < tol_ln, "ln {x}");
            assert_eq!(Real::abs(xf), xf.abs());
            // f64: always libm
            assert!((Real::sin(x) - x.sin()).abs() < 1e-15);
            assert!((Real::cos(x) - x.cos()).abs() < 1e-15);
            assert!((Real::atan2(x, -0.4) - x.atan2(-0.4)).abs() < 1e-15);
            assert!((Real::exp(x) - x.exp()).abs() < 1e-15 * x.exp());
            assert!((Real::ln(x.abs()) - x.abs().ln()).abs() < 1e-15);
            assert!((Real::sqrt(x.abs()) - x.abs().sqrt()).abs() < 1e-15);
            assert_eq!(Real::abs(x), x.abs());
        }
        assert_eq!(<f32 as Real>::of(0.1), 0.1f32);
        assert_eq!(<f64 as Real>::of(0.1), 0.1f64);
        assert_eq!(0.1f32.to_f64(), 0.1f32 as f64);
        assert_eq!(Real::to_f64(-2.5f64), -2.5);
        for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert!(!Real::is_finite(v));
            assert!(!Real::is_finite(v as f64));
        }
        assert!(Real::is_finite(1.0f32) && Real::is_finite(1.0f64));
    }

    #[test]
    fn min_max_pick_the_right_value_and_nan_yields_the_other() {
        assert_eq!(1.0f32.min_r(2.0), 1.0);
        assert_eq!(2.0f32.min_r(1.0), 1.0);
        assert_eq!(1.0f64.max_r(2.0), 2.0);
        assert_eq!(2.0f64.max_r(1.0), 2.0);
        assert_eq!(f32::NAN.min_r(3.0), 3.0);
        assert_eq!(f32::NAN.max_r(3.0), 3.0);
        assert_eq!((-1.0f32).clamp_r(-1.0, 1.0), -1.0);
        assert_eq!(1.0f32.clamp_r(-1.0, 1.0), 1.0);
        assert_eq!((-2.0f32).clamp_r(-1.0, 1.0), -1.0);
    }

    #[test]
    fn clamp_maps_nan_to_lower_bound() {
        assert_eq!(f32::NAN.clamp_r(-1.0, 1.0), -1.0);
        assert_eq!(5.0f32.clamp_r(-1.0, 1.0), 1.0);
        assert_eq!(0.25f64.clamp_r(-1.0, 1.0), 0.25);
    }
    #[test]
    fn sin_cos_poly_error_bound_holds_over_the_whole_range() {
        let error = |xs: f32| {
            let (s, c) = sin_cos_poly_f32(xs);
            let x = f64::from(xs);
            (f64::from(s) - x.sin())
                .abs()
                .max((f64::from(c) - x.cos()).abs())
        };
        let near = (0..=200_000)
            .map(|i| {
                let x = -2.0 * core::f64::consts::PI
                    + 4.0 * core::f64::consts::PI * f64::from(i) / 200_000.0;
                error(x as f32)
            })
            .chain(
                [
                    0.0f32,
                    -0.0,
                    core::f32::consts::FRAC_PI_2,
                    -core::f32::consts::FRAC_PI_2,
                    core::f32::consts::PI,
                    -core::f32::consts::PI,
                ]
                .into_iter()
                .map(error),
            )
            .fold(0.0f64, f64::max);
        assert!(near <= 2.5e-7, "worst abs error on [-2 pi, 2 pi]: {near:e}");
        // far out the rounding of k * TWO_PI_LO adds up to one f32 ulp of pi
        let far = (0..=200_000)
            .map(|i| error((-1.0e4 + 2.0e4 * f64::from(i) / 200_000.0) as f32))
            .fold(0.0f64, f64::max);
        assert!(far <= 5e-7, "worst abs error on [-1e4, 1e4]: {far:e}");
        // beyond the clamp: the value at +-1e4, finite; NaN propagates
        assert_eq!(sin_cos_poly_f32(3.0e9), sin_cos_poly_f32(1.0e4));
        assert_eq!(
            sin_cos_poly_f32(f32::NEG_INFINITY),
            sin_cos_poly_f32(-1.0e4)
        );
        let (s, c) = sin_cos_poly_f32(f32::NAN);
        assert!(s.is_nan() && c.is_nan());
    }
}
