//! Third-order jets: a value with its first three derivatives, (u, u', u'', u'''), carried
//! through arithmetic by the product rule and through `exp`, `ln` and `1/u` by Faà di
//! Bruno's formula. Over [`Scalar`] = `f64` a jet gives a map's derivatives at a point;
//! over [`Interval`] it gives enclosures of them over a whole interval (each derivative is
//! bounded separately, which is what the Schwarzian's sign test needs).

use super::interval::Interval;
use core::ops::{Add, Mul, Neg, Sub};

/// The number type of a [`Jet`]: `f64` (point values) or [`Interval`] (enclosures).
pub trait Scalar:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self> + Neg<Output = Self>
{
    /// The constant `c` (exactly the float `c`).
    fn cst(c: f64) -> Self;
    /// 1/x.
    fn recip(self) -> Self;
    /// e^x.
    fn exp(self) -> Self;
    /// ln x.
    fn ln(self) -> Self;
    /// sin x.
    fn sin(self) -> Self;
    /// cos x.
    fn cos(self) -> Self;
    /// atan x.
    fn atan(self) -> Self;
}

impl Scalar for f64 {
    fn cst(c: f64) -> Self {
        c
    }
    fn recip(self) -> Self {
        1.0 / self
    }
    fn exp(self) -> Self {
        f64::exp(self)
    }
    fn ln(self) -> Self {
        f64::ln(self)
    }
    fn sin(self) -> Self {
        f64::sin(self)
    }
    fn cos(self) -> Self {
        f64::cos(self)
    }
    fn atan(self) -> Self {
        f64::atan(self)
    }
}

impl Scalar for Interval {
    fn cst(c: f64) -> Self {
        Interval::point(c)
    }
    fn recip(self) -> Self {
        Interval::recip(&self)
    }
    fn exp(self) -> Self {
        Interval::exp(&self)
    }
    fn ln(self) -> Self {
        Interval::ln(&self)
    }
    fn sin(self) -> Self {
        Interval::sin(&self)
    }
    fn cos(self) -> Self {
        Interval::cos(&self)
    }
    fn atan(self) -> Self {
        Interval::atan(&self)
    }
}

/// (u, u', u'', u''') of a function of one variable at a point (or over an interval).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet<T> {
    /// u.
    pub v: T,
    /// u'.
    pub d1: T,
    /// u''.
    pub d2: T,
    /// u'''.
    pub d3: T,
}

impl<T: Scalar> Jet<T> {
    /// The independent variable x at `x`: (x, 1, 0, 0).
    pub fn var(x: T) -> Self {
        Self {
            v: x,
            d1: T::cst(1.0),
            d2: T::cst(0.0),
            d3: T::cst(0.0),
        }
    }
    /// The constant c: (c, 0, 0, 0).
    pub fn cst(c: f64) -> Self {
        let z = T::cst(0.0);
        Self {
            v: T::cst(c),
            d1: z,
            d2: z,
            d3: z,
        }
    }
    /// c u.
    pub fn scale(self, c: f64) -> Self {
        let c = T::cst(c);
        Self {
            v: c * self.v,
            d1: c * self.d1,
            d2: c * self.d2,
            d3: c * self.d3,
        }
    }
    /// φ∘u from (φ, φ', φ'', φ''') at u (Faà di Bruno to third order).
    fn compose(self, p0: T, p1: T, p2: T, p3: T) -> Self {
        let (a, b, c) = (self.d1, self.d2, self.d3);
        let three = T::cst(3.0);
        Self {
            v: p0,
            d1: p1 * a,
            d2: p2 * a * a + p1 * b,
            d3: p3 * a * a * a + three * p2 * a * b + p1 * c,
        }
    }
    /// e^u.
    pub fn exp(self) -> Self {
        let e = self.v.exp();
        self.compose(e, e, e, e)
    }
    /// ln u (u > 0).
    pub fn ln(self) -> Self {
        let r = self.v.recip();
        let r2 = r * r;
        self.compose(self.v.ln(), r, -r2, T::cst(2.0) * r2 * r)
    }
    /// sin u: (sin, cos, −sin, −cos).
    pub fn sin(self) -> Self {
        let (s, c) = (self.v.sin(), self.v.cos());
        self.compose(s, c, -s, -c)
    }
    /// atan u: φ′ = 1/(1 + u²), φ″ = −2u/(1 + u²)², φ‴ = (6u² − 2)/(1 + u²)³.
    pub fn atan(self) -> Self {
        let u = self.v;
        let r = (T::cst(1.0) + u * u).recip();
        let r2 = r * r;
        self.compose(
            u.atan(),
            r,
            T::cst(-2.0) * u * r2,
            (T::cst(6.0) * u * u - T::cst(2.0)) * r2 * r,
        )
    }
    /// 1/u (u ≠ 0).
    pub fn recip(self) -> Self {
        let r = self.v.recip();
        let r2 = r * r;
        self.compose(r, -r2, T::cst(2.0) * r2 * r, T::cst(-6.0) * r2 * r2)
    }
    /// u²  (the product rule, written once so the square's enclosure is the product's).
    pub fn sqr(self) -> Self {
        self * self
    }
}

impl<T: Scalar> Add for Jet<T> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            v: self.v + o.v,
            d1: self.d1 + o.d1,
            d2: self.d2 + o.d2,
            d3: self.d3 + o.d3,
        }
    }
}

impl<T: Scalar> Sub for Jet<T> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self {
            v: self.v - o.v,
            d1: self.d1 - o.d1,
            d2: self.d2 - o.d2,
            d3: self.d3 - o.d3,
        }
    }
}

impl<T: Scalar> Neg for Jet<T> {
    type Output = Self;
    fn neg(self) -> Self {
        Self {
            v: -self.v,
            d1: -self.d1,
            d2: -self.d2,
            d3: -self.d3,
        }
    }
}

impl<T: Scalar> Mul for Jet<T> {
    type Output = Self;
    /// Leibniz: (uw)' = u'w + uw', (uw)'' = u''w + 2u'w' + uw'', (uw)''' = u'''w + 3u''w' +
    /// 3u'w'' + uw'''.
    fn mul(self, o: Self) -> Self {
        let (two, three) = (T::cst(2.0), T::cst(3.0));
        Self {
            v: self.v * o.v,
            d1: self.d1 * o.v + self.v * o.d1,
            d2: self.d2 * o.v + two * self.d1 * o.d1 + self.v * o.d2,
            d3: self.d3 * o.v + three * (self.d2 * o.d1 + self.d1 * o.d2) + self.v * o.d3,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-13 * (1.0 + b.abs())
    }

    #[test]
    fn derivatives_of_x_exp_minus_x_match_the_closed_forms() {
        // f = x e^{-x}: f' = (1 - x) e^{-x}, f'' = (x - 2) e^{-x}, f''' = (3 - x) e^{-x}
        let x = 0.7_f64;
        let j = Jet::var(x) * (-Jet::var(x)).exp();
        let e = (-x).exp();
        assert!(close(j.v, x * e));
        assert!(close(j.d1, (1.0 - x) * e));
        assert!(close(j.d2, (x - 2.0) * e));
        assert!(close(j.d3, (3.0 - x) * e));
    }

    #[test]
    fn ln_and_recip_match_the_closed_forms() {
        let x = 1.7_f64;
        let l = Jet::var(x).ln();
        assert!(close(l.d1, 1.0 / x) && close(l.d2, -1.0 / (x * x)));
        assert!(close(l.d3, 2.0 / (x * x * x)));
        // (1/(1 + x^2))''' at x by the quotient: -24 x (x^2 - 1) / (1 + x^2)^4
        let r = (Jet::cst(1.0) + Jet::var(x).sqr()).recip();
        assert!(close(
            r.d3,
            -24.0 * x * (x * x - 1.0) / (1.0 + x * x).powi(4)
        ));
    }

    #[test]
    fn sin_and_atan_match_the_closed_forms() {
        let x = 0.8_f64;
        let s = Jet::var(x).sin();
        assert!(close(s.d1, x.cos()) && close(s.d2, -x.sin()) && close(s.d3, -x.cos()));
        // atan''' = (6x^2 - 2)/(1 + x^2)^3
        let a = Jet::var(x).atan();
        assert!(close(a.d1, 1.0 / (1.0 + x * x)));
        assert!(close(a.d3, (6.0 * x * x - 2.0) / (1.0 + x * x).powi(3)));
    }

    #[test]
    fn an_interval_jet_encloses_the_point_jets_in_it() {
        let xs = Interval::new(0.5, 0.6);
        let j = Jet::var(xs) * (-Jet::var(xs)).exp();
        for k in 0..=10 {
            let x = 0.5 + 0.01 * k as f64;
            let p = Jet::var(x) * (-Jet::var(x)).exp();
            assert!(j.v.contains(p.v) && j.d1.contains(p.d1));
            assert!(j.d2.contains(p.d2) && j.d3.contains(p.d3));
        }
    }
}
