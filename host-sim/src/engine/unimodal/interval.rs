//! Closed intervals of reals with outward rounding, for proof-grade bounds (the sign of a
//! Schwarzian derivative over a whole interval, [`super::certify`]).
//!
//! Every operation returns an interval that contains the exact result of the operation on
//! every pair of reals in its operands: the floating-point bounds are moved one ulp outward
//! (`f64::next_down` / `f64::next_up`) after each correctly rounded operation (+, −, ×, ÷,
//! √), and two ulps after `exp` and `ln`, whose libm results are within one ulp of the
//! exact value (glibc's documented bound) but not correctly rounded. A result that is not a
//! number (∞ − ∞, 0 × ∞, or division by an interval containing 0) is the whole line
//! [`Interval::ENTIRE`], which proves nothing: a check on it fails rather than passes.

use core::ops::{Add, Mul, Neg, Sub};

/// A closed interval [lo, hi] of reals (lo <= hi; the bounds may be infinite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    lo: f64,
    hi: f64,
}

fn down(x: f64) -> f64 {
    x.next_down()
}
fn up(x: f64) -> f64 {
    x.next_up()
}

impl Interval {
    /// The whole real line: what an operation returns when it cannot bound its result.
    pub const ENTIRE: Interval = Interval {
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };

    /// [lo, hi]; [`Interval::ENTIRE`] if either bound is NaN or lo > hi.
    pub fn new(lo: f64, hi: f64) -> Self {
        if lo.is_nan() || hi.is_nan() || lo > hi {
            Self::ENTIRE
        } else {
            Self { lo, hi }
        }
    }

    /// The degenerate interval [x, x] (x is exact: it is the real number the float is).
    pub fn point(x: f64) -> Self {
        Self::new(x, x)
    }

    /// Outward-rounded [lo, hi] from bounds computed with one rounding each.
    fn rounded(lo: f64, hi: f64) -> Self {
        Self::new(down(lo), up(hi))
    }

    /// Lower bound.
    pub fn lo(&self) -> f64 {
        self.lo
    }
    /// Upper bound.
    pub fn hi(&self) -> f64 {
        self.hi
    }
    /// The midpoint (rounded; for reporting and splitting).
    pub fn mid(&self) -> f64 {
        0.5 * self.lo + 0.5 * self.hi
    }
    /// hi − lo (rounded up).
    pub fn width(&self) -> f64 {
        up(self.hi - self.lo)
    }
    /// True if every element is < 0.
    pub fn is_negative(&self) -> bool {
        self.hi < 0.0
    }
    /// True if every element is > 0.
    pub fn is_positive(&self) -> bool {
        self.lo > 0.0
    }
    /// True if 0 is an element.
    pub fn contains_zero(&self) -> bool {
        self.lo <= 0.0 && self.hi >= 0.0
    }
    /// True if `x` is an element.
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }
    /// The smallest interval holding both.
    pub fn hull(&self, other: &Interval) -> Interval {
        Interval::new(self.lo.min(other.lo), self.hi.max(other.hi))
    }
    /// The enclosure of |x| over the interval.
    pub fn abs(&self) -> Interval {
        if self.lo >= 0.0 {
            *self
        } else if self.hi <= 0.0 {
            -*self
        } else {
            Interval::new(0.0, (-self.lo).max(self.hi))
        }
    }
    /// x² (tight: never negative).
    pub fn sqr(&self) -> Interval {
        let a = self.abs();
        Interval::new(down(a.lo * a.lo).max(0.0), up(a.hi * a.hi))
    }
    /// 1/x; [`Interval::ENTIRE`] if 0 is an element.
    pub fn recip(&self) -> Interval {
        if self.contains_zero() {
            return Self::ENTIRE;
        }
        Interval::rounded(1.0 / self.hi, 1.0 / self.lo)
    }
    /// e^x (monotone; two ulps outward, never below 0).
    pub fn exp(&self) -> Interval {
        let lo = down(down(self.lo.exp())).max(0.0);
        let hi = up(up(self.hi.exp()));
        Interval::new(lo, hi)
    }
    /// atan x (monotone; two ulps outward).
    pub fn atan(&self) -> Interval {
        Interval::new(down(down(self.lo.atan())), up(up(self.hi.atan())))
    }

    /// sin x: the end values two ulps and 1e−300 outward, widened to ±1 wherever a
    /// maximum π/2 + 2kπ or a minimum −π/2 + 2kπ may lie in the interval (tested against
    /// an enclosure of those points, since π is not a float).
    pub fn sin(&self) -> Interval {
        self.periodic(f64::sin, core::f64::consts::FRAC_PI_2)
    }

    /// cos x, as [`Interval::sin`] with the maximum at 2kπ.
    pub fn cos(&self) -> Interval {
        self.periodic(f64::cos, 0.0)
    }

    /// A 2π-periodic function with its maximum at `peak` + 2kπ and minimum at `peak` + π +
    /// 2kπ, monotone between.
    fn periodic(&self, f: fn(f64) -> f64, peak: f64) -> Interval {
        use core::f64::consts::PI;
        let (l, h) = (self.lo, self.hi);
        if !(l.is_finite() && h.is_finite()) || h - l >= 6.0 {
            return Interval::new(-1.0, 1.0);
        }
        // does some t0 + k pi (k even: a maximum, odd: a minimum) lie in [l, h]? The float
        // t0 + k PI is within 4 (|k| + 1) ulps of the exact point: test a widened interval.
        let k_lo = ((l - peak) / PI).floor() as i64 - 1;
        let k_hi = ((h - peak) / PI).ceil() as i64 + 1;
        let (mut top, mut bottom) = (false, false);
        for k in k_lo..=k_hi {
            let t = peak + k as f64 * PI;
            let slack = 1e-15 * (1.0 + t.abs());
            if t + slack >= l && t - slack <= h {
                if k.rem_euclid(2) == 0 {
                    top = true;
                } else {
                    bottom = true;
                }
            }
        }
        let (a, b) = (f(l), f(h));
        let margin = |x: f64| 4.0 * f64::EPSILON * x.abs() + 1e-300;
        let lo = if bottom {
            -1.0
        } else {
            a.min(b) - margin(a.min(b))
        };
        let hi = if top {
            1.0
        } else {
            a.max(b) + margin(a.max(b))
        };
        Interval::new(lo.max(-1.0), hi.min(1.0))
    }

    /// ln x (monotone; two ulps outward); [`Interval::ENTIRE`] unless every element is > 0.
    pub fn ln(&self) -> Interval {
        if self.lo.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return Self::ENTIRE;
        }
        Interval::new(down(down(self.lo.ln())), up(up(self.hi.ln())))
    }
}

impl Add for Interval {
    type Output = Interval;
    fn add(self, o: Interval) -> Interval {
        Interval::rounded(self.lo + o.lo, self.hi + o.hi)
    }
}

impl Sub for Interval {
    type Output = Interval;
    fn sub(self, o: Interval) -> Interval {
        Interval::rounded(self.lo - o.hi, self.hi - o.lo)
    }
}

impl Neg for Interval {
    type Output = Interval;
    fn neg(self) -> Interval {
        Interval::new(-self.hi, -self.lo)
    }
}

impl Mul for Interval {
    type Output = Interval;
    fn mul(self, o: Interval) -> Interval {
        let p = [
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        ];
        if p.iter().any(|v| v.is_nan()) {
            return Interval::ENTIRE;
        }
        let lo = p.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Interval::rounded(lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_tenth_sums_are_enclosed() {
        // 0.1 is not a float: ten additions of the float nearest it, rounded outward, must
        // still enclose the float sum computed exactly (here: contain the naive sum)
        let t = Interval::point(0.1);
        let mut s = Interval::point(0.0);
        for _ in 0..10 {
            s = s + t;
        }
        assert!(s.contains(1.0) && s.lo() < 1.0 && s.hi() > 1.0);
    }

    #[test]
    fn products_and_squares_keep_signs() {
        let x = Interval::new(-2.0, 3.0);
        assert_eq!(x.sqr().lo(), 0.0);
        assert!(x.sqr().contains(9.0));
        let p = x * Interval::new(-1.0, 1.0);
        assert!(p.contains(-3.0) && p.contains(3.0));
        assert!(Interval::new(1.0, 2.0).recip().contains(0.5));
        assert_eq!(x.recip(), Interval::ENTIRE);
        assert_eq!(Interval::new(-1.0, 1.0).ln(), Interval::ENTIRE);
    }

    #[test]
    fn exp_and_ln_enclose_known_values() {
        let e = Interval::point(1.0).exp();
        assert!(e.lo() < std::f64::consts::E && e.hi() > std::f64::consts::E);
        let l = Interval::point(std::f64::consts::E).ln();
        assert!(l.contains(1.0));
        assert!(Interval::point(-800.0).exp().lo() >= 0.0);
    }

    #[test]
    fn sin_and_cos_enclose_samples_and_their_extremes() {
        for (l, h) in [
            (0.0, 0.3),
            (1.0, 2.0),
            (-4.0, -1.0),
            (3.0, 3.2),
            (-0.1, 6.0),
        ] {
            let (s, c) = (Interval::new(l, h).sin(), Interval::new(l, h).cos());
            for i in 0..=100 {
                let x = l + (h - l) * i as f64 / 100.0;
                assert!(s.contains(x.sin()) && c.contains(x.cos()), "{x}");
            }
        }
        assert_eq!(Interval::new(1.0, 2.0).sin().hi(), 1.0);
        assert_eq!(Interval::new(3.0, 3.2).cos().lo(), -1.0);
        assert!(Interval::new(0.1, 0.2).sin().hi() < 0.2);
        assert!(Interval::point(1.0)
            .atan()
            .contains(core::f64::consts::FRAC_PI_4));
    }

    #[test]
    fn nan_is_the_entire_line() {
        let inf = Interval::new(f64::INFINITY, f64::INFINITY);
        assert_eq!(inf - inf, Interval::ENTIRE);
        assert_eq!(Interval::point(0.0) * inf, Interval::ENTIRE);
        assert_eq!(Interval::new(f64::NAN, 1.0), Interval::ENTIRE);
    }
}
