//! The period-doubling cascade of a one-parameter family of maps x ↦ f(x; a) (Koditschek &
//! Bühler 1991, sec. 2.3 "Bifurcations" and Theorem 1): each doubling aₙ is located by
//! continuation of the 2ⁿ⁻¹-cycle in a to the parameter where its multiplier is −1,
//! solved by Newton's method on the cycle with the multiplier condition,
//!
//! ```text
//! G(x, a) = ( fᵖ(x; a) − x ,  (fᵖ)′(x; a) + 1 ) = 0,    p = 2ⁿ⁻¹,
//! ```
//!
//! never by counting the period of a settled orbit (which misplaces a doubling: near it the
//! multiplier is close to −1 and transients decay arbitrarily slowly).
//!
//! The continuation of the n-th doubling: at a parameter just past aₙ₋₁ (a tenth of the
//! previous interval), the new cycle is found by iterating the critical point and checked
//! to have period p; it is then followed in steps of a quarter of that offset, Newton's
//! method on fᵖ(x) − x at each step, until its multiplier passes −1; the bracket is
//! bisected on the multiplier, then polished by Newton's method on G in (x, a) with its
//! exact 2×2 Jacobian (derivatives propagated along the orbit).

/// f and the partial derivatives the cascade needs, at (x, a).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FamilyJet {
    /// f(x; a).
    pub f: f64,
    /// ∂f/∂x.
    pub fx: f64,
    /// ∂²f/∂x².
    pub fxx: f64,
    /// ∂f/∂a.
    pub fa: f64,
    /// ∂²f/∂x∂a.
    pub fxa: f64,
}

/// A one-parameter family of unimodal maps.
pub trait Family {
    /// f and its partials at (x, a).
    fn eval(&self, x: f64, a: f64) -> FamilyJet;
    /// The critical point at parameter a.
    fn critical(&self, a: f64) -> f64;
}

/// The orbit of x0 over p steps: (x_p, ∂x_p/∂x0, ∂x_p/∂a, M, ∂M/∂x0, ∂M/∂a) with
/// M = (fᵖ)′(x0) = ∏ f_x(x_k).
fn orbit<F: Family>(fam: &F, x0: f64, a: f64, p: usize) -> [f64; 6] {
    let (mut x, mut dx, mut da) = (x0, 1.0, 0.0);
    let (mut m, mut mx, mut ma) = (1.0, 0.0, 0.0);
    for _ in 0..p {
        let j = fam.eval(x, a);
        // the multiplier's derivatives use the previous dx, da (chain rule at x_k)
        mx = mx * j.fx + m * j.fxx * dx;
        ma = ma * j.fx + m * (j.fxx * da + j.fxa);
        m *= j.fx;
        da = j.fx * da + j.fa;
        dx *= j.fx;
        x = j.f;
    }
    [x, dx, da, m, mx, ma]
}

/// Newton's method on fᵖ(x; a) − x at fixed a from `x`; the cycle point and its multiplier.
fn cycle_at<F: Family>(fam: &F, mut x: f64, a: f64, p: usize) -> Option<(f64, f64)> {
    for _ in 0..100 {
        let [y, dx, ..] = orbit(fam, x, a, p);
        let step = (y - x) / (dx - 1.0);
        if !step.is_finite() {
            return None;
        }
        x -= step;
        if step.abs() <= 1e-15 * (1.0 + x.abs()) {
            break;
        }
    }
    let [y, _, _, m, ..] = orbit(fam, x, a, p);
    ((y - x).abs() <= 1e-11 * (1.0 + x.abs())).then_some((x, m))
}

/// One located doubling.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Doubling {
    /// The period of the cycle that loses stability (2ⁿ⁻¹); a 2p-cycle is born.
    pub period: usize,
    /// The parameter aₙ.
    pub parameter: f64,
    /// A point of the p-cycle there.
    pub x: f64,
    /// |fᵖ(x) − x| there.
    pub residual: f64,
    /// (fᵖ)′(x) + 1 there.
    pub multiplier_residual: f64,
    /// Newton iterations of the final polish on (x, a).
    pub newton_iterations: usize,
}

/// Why the cascade stopped early.
#[derive(Clone, Debug, PartialEq)]
pub struct CascadeError(pub String);

/// The first `count` period doublings of `fam`, starting from `a_start`, a parameter where
/// the fixed point attracts (its orbit from the critical point is checked to settle on
/// period 1), and `step`, the first continuation step in a.
pub fn doublings<F: Family>(
    fam: &F,
    a_start: f64,
    step: f64,
    count: usize,
) -> Result<Vec<Doubling>, CascadeError> {
    let mut out: Vec<Doubling> = Vec::with_capacity(count);
    let (mut a, mut h) = (a_start, step);
    let mut x = settled(fam, a, 1).ok_or_else(|| {
        CascadeError(format!(
            "the orbit of the critical point at a = {a_start} does not settle on a fixed point"
        ))
    })?;
    for n in 0..count {
        let p = 1usize << n;
        if n > 0 {
            // just past the previous doubling: the new p-cycle, from the critical orbit
            let prev = out[n - 1];
            let gap = if n >= 2 {
                prev.parameter - out[n - 2].parameter
            } else {
                prev.parameter - a_start
            };
            let mut offset = gap / 10.0;
            let mut found = None;
            for _ in 0..20 {
                if let Some(xs) = settled(fam, prev.parameter + offset, p) {
                    found = Some(xs);
                    break;
                }
                offset /= 2.0;
            }
            x = found.ok_or_else(|| {
                CascadeError(format!(
                    "no period-{p} cycle settled just past a = {}",
                    prev.parameter
                ))
            })?;
            a = prev.parameter + offset;
            h = offset / 4.0;
        }
        out.push(flip(fam, x, a, h, p)?);
    }
    Ok(out)
}

/// The settled p-cycle point of the critical orbit at a (least period exactly p), polished.
fn settled<F: Family>(fam: &F, a: f64, p: usize) -> Option<f64> {
    let mut x = fam.critical(a);
    for _ in 0..200_000 {
        x = fam.eval(x, a).f;
        if !x.is_finite() {
            return None;
        }
    }
    let (x, m) = cycle_at(fam, x, a, p)?;
    // least period p: no proper divisor (a power of 2: p/2) returns
    let least = p == 1 || {
        let [y, ..] = orbit(fam, x, a, p / 2);
        (y - x).abs() > 1e-9 * (1.0 + x.abs())
    };
    (least && m.abs() < 1.0).then_some(x)
}

/// Follow the p-cycle through (x, a) in steps h until its multiplier passes −1; locate it.
fn flip<F: Family>(fam: &F, x: f64, a: f64, h: f64, p: usize) -> Result<Doubling, CascadeError> {
    let err = |what: String| CascadeError(format!("period {p}: {what}"));
    let (mut x_lo, mut a_lo) = (x, a);
    let (mut x_hi, mut a_hi);
    let mut steps = 0;
    loop {
        let a_next = a_lo + h;
        let (xn, m) = cycle_at(fam, x_lo, a_next, p)
            .ok_or_else(|| err(format!("the cycle was lost at a = {a_next}")))?;
        if m <= -1.0 {
            (x_hi, a_hi) = (xn, a_next);
            break;
        }
        (x_lo, a_lo) = (xn, a_next);
        steps += 1;
        if steps > 10_000 {
            return Err(err("the multiplier did not reach -1".into()));
        }
    }
    // bisect on the multiplier (monotone through −1 across the bracket)
    for _ in 0..30 {
        let am = 0.5 * (a_lo + a_hi);
        let (xm, m) = cycle_at(fam, x_lo, am, p).ok_or_else(|| err(format!("lost at a = {am}")))?;
        if m <= -1.0 {
            (x_hi, a_hi) = (xm, am);
        } else {
            (x_lo, a_lo) = (xm, am);
        }
    }
    let _ = x_hi;
    // Newton on G(x, a) = (f^p(x) − x, M + 1)
    let (mut x, mut a) = (x_lo, 0.5 * (a_lo + a_hi));
    let mut iterations = 0;
    for _ in 0..50 {
        iterations += 1;
        let [y, dx, da, m, mx, ma] = orbit(fam, x, a, p);
        let (g1, g2) = (y - x, m + 1.0);
        let (j11, j12, j21, j22) = (dx - 1.0, da, mx, ma);
        let det = j11 * j22 - j12 * j21;
        let sx = (g1 * j22 - j12 * g2) / det;
        let sa = (j11 * g2 - j21 * g1) / det;
        if !(sx.is_finite() && sa.is_finite()) {
            return Err(err(format!("singular Newton step at a = {a}")));
        }
        x -= sx;
        a -= sa;
        if sa.abs() <= 1e-15 * a.abs() && sx.abs() <= 1e-15 * (1.0 + x.abs()) {
            break;
        }
    }
    let [y, _, _, m, ..] = orbit(fam, x, a, p);
    if !(a > a_lo - 1e-9 * a.abs() && a < a_hi + 1e-9 * a.abs()) {
        return Err(err(format!(
            "Newton left the bracket [{a_lo}, {a_hi}] (to a = {a})"
        )));
    }
    Ok(Doubling {
        period: p,
        parameter: a,
        x,
        residual: (y - x).abs(),
        multiplier_residual: m + 1.0,
        newton_iterations: iterations,
    })
}

/// Feigenbaum's ratio estimates (aₙ − aₙ₋₁)/(aₙ₊₁ − aₙ) from consecutive doublings.
pub fn ratios(d: &[Doubling]) -> Vec<f64> {
    d.windows(3)
        .map(|w| (w[1].parameter - w[0].parameter) / (w[2].parameter - w[1].parameter))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The logistic family a x (1 − x).
    struct Logistic;
    impl Family for Logistic {
        fn eval(&self, x: f64, a: f64) -> FamilyJet {
            FamilyJet {
                f: a * x * (1.0 - x),
                fx: a * (1.0 - 2.0 * x),
                fxx: -2.0 * a,
                fa: x * (1.0 - x),
                fxa: 1.0 - 2.0 * x,
            }
        }
        fn critical(&self, _: f64) -> f64 {
            0.5
        }
    }

    #[test]
    fn logistic_doublings_are_three_and_one_plus_root_six() {
        // closed forms: a1 = 3, a2 = 1 + sqrt(6); a3 = 3.5440903595519 (literature value)
        let d = doublings(&Logistic, 2.5, 0.05, 3).unwrap();
        assert!((d[0].parameter - 3.0).abs() < 1e-12, "{d:?}");
        assert!((d[1].parameter - (1.0 + 6f64.sqrt())).abs() < 1e-12);
        assert!((d[2].parameter - 3.544_090_359_551_9).abs() < 1e-10);
        assert_eq!([d[0].period, d[1].period, d[2].period], [1, 2, 4]);
    }
}
