//! Robust first contact of a quadratic gap: the earliest time in `(0, h]` at which
//! `gap(t) = c0 + c1 t + c2 t^2` reaches zero from above.
//!
//! The gap is ball height minus paddle height (m) over one segment in which both move as
//! polynomials in the segment-local time `t` (s). Roots come from the numerically stable
//! form of the quadratic formula (no cancellation: `q = -(c1 + sign(c1) sqrt(disc))/2`,
//! roots `q/c2` and `c0/q`), polished by one Newton step. A grazing contact, whose
//! discriminant may round to a small negative number, is caught by checking the gap's
//! minimum against its own rounding error, so tangencies are never missed.

/// Relative rounding allowance (in units of f64 epsilon) for grazing detection.
const GRAZE_ULPS: f64 = 16.0;

/// A contact found in a segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Segment-local time of the contact, s, in `[0, h]`.
    pub time_s: f64,
    /// True if the gap only touches zero (double root): zero relative velocity.
    pub grazing: bool,
}

/// Value of `c0 + c1 t + c2 t^2` (Horner).
#[inline]
pub fn eval(c0: f64, c1: f64, c2: f64, t: f64) -> f64 {
    c0 + t * (c1 + t * c2)
}

/// The earliest contact of `gap(t) = c0 + c1 t + c2 t^2` in `[0, h]` (s, `h >= 0`).
///
/// - `c0 > 0` (separated): the smallest root in `(0, h]`, or a grazing touch there.
/// - `c0 <= 0` (touching, or penetrating by rounding): contact at `t = 0` if the gap is
///   closing there (`c1 < 0`, or `c1 == 0` and `c2 < 0`), else the ball separates and the
///   next root, if any, is returned.
///
/// Non-finite coefficients yield `None`. A caller that expects most gaps to stay clear of
/// zero can ask [`clearly_apart`] first (no square root, no division).
pub fn first_contact(c0: f64, c1: f64, c2: f64, h: f64) -> Option<Contact> {
    if !(c0.is_finite() && c1.is_finite() && c2.is_finite() && h.is_finite()) || h < 0.0 {
        return None;
    }
    if c0 <= 0.0 {
        if c1 < 0.0 || (c1 == 0.0 && c2 < 0.0) {
            return Some(Contact {
                time_s: 0.0,
                grazing: c1 == 0.0,
            });
        }
        // separating from a touch: gap = t (c1 + c2 t) (+ c0, which is <= 0 and tiny);
        // the other root is -c1/c2 when the gap curves back down.
        if c2 < 0.0 && c1 > 0.0 {
            let t = second_root_from_touch(c0, c1, c2);
            if t > 0.0 && t <= h {
                return Some(Contact {
                    time_s: t,
                    grazing: false,
                });
            }
        }
        return None;
    }
    // c0 > 0: separated.
    if c2 == 0.0 {
        if c1 < 0.0 {
            let t = -c0 / c1;
            return (t <= h).then_some(Contact {
                time_s: t,
                grazing: false,
            });
        }
        return None;
    }
    let disc = c1 * c1 - 4.0 * c0 * c2;
    let scale = c1 * c1 + (4.0 * c0 * c2).abs();
    let tol = GRAZE_ULPS * f64::EPSILON * scale;
    if disc < -tol {
        return None;
    }
    if disc <= tol {
        // double root (tangency) within rounding: only possible from above when c2 > 0
        let t = -c1 / (2.0 * c2);
        if c2 > 0.0 && t > 0.0 && t <= h {
            return Some(Contact {
                time_s: t,
                grazing: true,
            });
        }
        if c2 < 0.0 {
            // concave gap from c0 > 0 with a (near) double root cannot touch from above
            // unless rounding: fall through to the regular roots with disc clamped at 0.
        } else {
            return None;
        }
    }
    let sq = disc.max(0.0).sqrt();
    let q = -0.5 * (c1 + c1.signum() * sq);
    let (mut r1, mut r2) = if q != 0.0 {
        (q / c2, c0 / q)
    } else {
        // c1 == 0 and disc == 0 with c0 > 0: impossible unless c2 == 0 (handled above)
        return None;
    };
    if r1 > r2 {
        std::mem::swap(&mut r1, &mut r2);
    }
    for r in [r1, r2] {
        if r > 0.0 && r <= h {
            return Some(Contact {
                time_s: polish(c0, c1, c2, r, h),
                grazing: false,
            });
        }
    }
    None
}

/// How far, relative to the size of the gap's terms over the window, a lower bound of the
/// gap must stay above zero for [`clearly_apart`] to answer without the roots: 1e-9 is
/// some 4.5e6 ulps, far beyond the grazing allowance ([`GRAZE_ULPS`]) and the rounding of
/// the roots, so the shortcut never answers differently from the full computation.
const CLEAR_GAP: f64 = 1e-9;

/// True if `c0 + c1 t + c2 t^2` provably stays above zero on `[0, h]`: `c0 > 0` and each
/// term at its lowest over the window (`c1 t >= min(0, c1 h)`, `c2 t^2 >= min(0, c2 h^2)`)
/// still leaves a margin of `CLEAR_GAP` (1e-9) times the terms' size. Then [`first_contact`]
/// returns `None`, and a caller may skip it: the common case of a ball well above the
/// paddle over a short segment (a control period) costs no square root or division.
/// In [`first_contact`] a contact needs the gap within rounding of zero somewhere in
/// `[0, h]` (a root there, or a minimum within `GRAZE_ULPS` ulps of it), which the margin
/// excludes. Non-finite input gives false.
#[inline]
pub fn clearly_apart(c0: f64, c1: f64, c2: f64, h: f64) -> bool {
    if c0.is_nan() || c0 <= 0.0 {
        return false;
    }
    let linear = c1 * h;
    let quadratic = c2 * h * h;
    let lower = c0 + linear.min(0.0) + quadratic.min(0.0);
    lower > CLEAR_GAP * (c0 + linear.abs() + quadratic.abs())
}

/// Margin of [`apart_by_margin`]: a thousand times [`CLEAR_GAP`], so rounding in either
/// test cannot make it answer true where [`clearly_apart`] answers false.
const APART_MARGIN: f64 = 1e-6;

/// True if `c0 + c1 t + c2 t^2` stays above zero on `[0, h]` (`h >= 0`) by a wide margin:
/// `c0 (1 - 1e-6) > |c1| h + |c2| h^2`. A cheaper, stricter form of [`clearly_apart`] for a
/// loop that takes most segments without a contact: where it is true, so is
/// `clearly_apart` (the gap's lower bound `c0 - |c1| h - |c2| h^2` is then above
/// `1e-6 c0`, while `clearly_apart` asks for `1e-9 (c0 + |c1| h + |c2| h^2) < 2e-9 c0`;
/// rounding moves either side by a few ulps of `c0`). Non-finite input gives false.
#[inline(always)]
pub fn apart_by_margin(c0: f64, c1: f64, c2: f64, h: f64) -> bool {
    apart_by_margin_of(c0, c1.abs(), c2.abs() * h, h)
}

/// [`apart_by_margin`] given `|c1|` and `|c2| h` (a loop whose `h` is fixed computes the
/// product once): the same test, rounding for rounding.
#[inline(always)]
pub fn apart_by_margin_of(c0: f64, c1_abs: f64, c2_abs_h: f64, h: f64) -> bool {
    c0 * (1.0 - APART_MARGIN) > h * (c1_abs + c2_abs_h)
}

/// The positive root of `c0 + c1 t + c2 t^2` for `c0 <= 0` tiny, `c1 > 0`, `c2 < 0`.
fn second_root_from_touch(c0: f64, c1: f64, c2: f64) -> f64 {
    if c0 == 0.0 {
        // a take-off from the surface (every bounce on a table or the ideal mirror): the
        // roots are 0 and -c1/c2 exactly, so the correctly rounded quotient is the answer at
        // any scale. It is also what the general formula gives wherever c1^2 neither
        // overflows nor underflows (the square root of c1^2 is then c1 exactly, q = -c1);
        // beyond that range the formula is wrong (a subnormal c1 squares to 0 and halves
        // the return time), and the square root, the longest step of the impact-to-impact
        // chain, is not needed either way
        return -c1 / c2;
    }
    let disc = (c1 * c1 - 4.0 * c0 * c2).max(0.0);
    let q = -0.5 * (c1 + disc.sqrt());
    // roots q/c2 (the far one, positive) and c0/q (the near one, ~0)
    q / c2
}

/// One Newton step, kept only if it does not increase |gap| and stays in `[0, h]`.
fn polish(c0: f64, c1: f64, c2: f64, t: f64, h: f64) -> f64 {
    let f = eval(c0, c1, c2, t);
    let df = c1 + 2.0 * c2 * t;
    if df == 0.0 || f == 0.0 {
        return t;
    }
    let t2 = t - f / df;
    if t2 >= 0.0 && t2 <= h && eval(c0, c1, c2, t2).abs() < f.abs() {
        t2
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20000))]
        /// Where the wide margin holds, so does the short test's (and the roots find no
        /// contact): gaps from touching to far, both signs of the linear and quadratic
        /// terms, segments up to a second, at the wide margin's edge.
        #[test]
        fn the_wide_margin_implies_clearly_apart(
            c0_exp in -12.0f64..3.0,
            c1 in -100.0f64..100.0,
            c2 in -500.0f64..500.0,
            h_exp in -7.0f64..0.0,
            edge in 0.0f64..=1.0,
        ) {
            let h = 10f64.powf(h_exp);
            // from anywhere, or at the wide margin's boundary
            let need = h * (c1.abs() + c2.abs() * h) / (1.0 - 1e-6);
            let c0 = if edge < 0.5 { 10f64.powf(c0_exp) } else { need * (1.0 + (edge - 0.75) * 1e-12) };
            if apart_by_margin(c0, c1, c2, h) {
                prop_assert!(clearly_apart(c0, c1, c2, h));
                prop_assert!(first_contact(c0, c1, c2, h).is_none());
            }
        }
    }

    #[test]
    fn the_wide_margin_by_hand() {
        // 1 m above, closing at 10 m/s, 1 ms: 1 (1 - 1e-6) > 0.01 + ...
        assert!(apart_by_margin(1.0, -10.0, -4.9, 1e-3));
        // 1 cm above, closing at 10 m/s over 1 ms: 0.01 (1 - 1e-6) < 0.01 + 4.9e-6
        assert!(!apart_by_margin(0.01, -10.0, -4.9, 1e-3));
        assert!(!apart_by_margin(0.0, 0.0, 0.0, 1e-3), "touching");
        assert!(!apart_by_margin(f64::NAN, 0.0, 0.0, 1e-3));
        assert!(!apart_by_margin(1.0, f64::INFINITY, 0.0, 1e-3));
        assert_eq!(
            apart_by_margin(0.5, -3.0, 2.0, 0.01),
            apart_by_margin_of(0.5, 3.0, 2.0 * 0.01, 0.01)
        );
    }

    #[test]
    fn falling_ball_on_fixed_table() {
        // b = 1 - g t^2 / 2 hits 0 at sqrt(2/g)
        let g = 9.81;
        let c = first_contact(1.0, 0.0, -0.5 * g, 10.0).unwrap();
        assert!((c.time_s - (2.0f64 / g).sqrt()).abs() < 1e-15);
        assert!(!c.grazing);
    }

    #[test]
    fn ball_leaving_surface_returns_after_flight() {
        // just bounced: gap 0, relative velocity 3, gap'' = -g: back after 2 * 3 / g
        let g = 9.81;
        let c = first_contact(0.0, 3.0, -0.5 * g, 10.0).unwrap();
        assert!((c.time_s - 6.0 / g).abs() < 1e-15);
        // not within a shorter window
        assert_eq!(first_contact(0.0, 3.0, -0.5 * g, 0.5), None);
    }

    #[test]
    fn exact_tangency_is_a_grazing_contact() {
        // gap = (t - 0.3)^2 = 0.09 - 0.6 t + t^2
        let c = first_contact(0.09, -0.6, 1.0, 1.0).unwrap();
        assert!(c.grazing);
        assert!((c.time_s - 0.3).abs() < 1e-12);
        // slightly separated: no contact
        assert_eq!(first_contact(0.09 + 1e-9, -0.6, 1.0, 1.0), None);
    }

    #[test]
    fn closing_at_touch_is_immediate_contact() {
        assert_eq!(first_contact(0.0, -1.0, 0.0, 1.0).unwrap().time_s, 0.0);
        assert_eq!(first_contact(-1e-18, -1.0, 5.0, 1.0).unwrap().time_s, 0.0);
        // resting with paddle accelerating down faster than g: separates, never returns
        assert_eq!(first_contact(0.0, 0.0, 1.0, 1.0), None);
    }

    #[test]
    fn cancellation_prone_roots_are_accurate() {
        // roots 1e-9 and 1e3 of (t - 1e-9)(t - 1e3) = t^2 - (1e3 + 1e-9) t + 1e-6
        let c = first_contact(1e-6, -(1e3 + 1e-9), 1.0, 1.0).unwrap();
        assert!((c.time_s - 1e-9).abs() <= 1e-9 * 1e-14, "{}", c.time_s);
    }

    #[test]
    fn non_finite_input_is_no_contact() {
        assert_eq!(first_contact(f64::NAN, 0.0, -1.0, 1.0), None);
        assert_eq!(first_contact(1.0, f64::INFINITY, -1.0, 1.0), None);
    }

    /// Brute force: the first sample where the gap is negative, on a fine grid.
    fn brute_first_negative(c0: f64, c1: f64, c2: f64, h: f64, n: usize) -> Option<f64> {
        (0..=n)
            .map(|i| h * i as f64 / n as f64)
            .find(|&t| eval(c0, c1, c2, t) < 0.0)
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2000))]
        /// No contact is missed (no tunnelling) and none is invented: compare with a
        /// fine grid search over the segment, across scales from mm to 100 m.
        #[test]
        fn never_misses_a_contact(
            d0 in 0.0f64..1.0,
            v in -10.0f64..10.0,
            a in -50.0f64..50.0,
            scale_exp in -3i32..3,
            h in 1e-3f64..2.0,
        ) {
            let s = 10f64.powi(scale_exp);
            let (c0, c1, c2) = (d0 * s, v * s, a * s);
            let n = 20_000;
            let found = first_contact(c0, c1, c2, h);
            let brute = brute_first_negative(c0, c1, c2, h, n);
            let grid = h / n as f64;
            if let Some(tb) = brute {
                let c = found.expect("brute force found a penetration the solver missed");
                prop_assert!(c.time_s <= tb + 1e-12 * h, "contact {} after first penetration {}", c.time_s, tb);
                // no earlier penetration than the reported contact (on the grid)
                if let Some(tb) = brute {
                    prop_assert!(tb + grid >= c.time_s);
                }
            }
            if let Some(c) = found {
                // the gap really is zero there (to rounding), and positive just before on the grid
                let g = eval(c0, c1, c2, c.time_s);
                let mag = c0.abs() + (c1 * c.time_s).abs() + (c2 * c.time_s * c.time_s).abs();
                prop_assert!(g.abs() <= 64.0 * f64::EPSILON * mag.max(f64::MIN_POSITIVE), "gap {} at contact", g);
                let before = (0..n).map(|i| c.time_s * i as f64 / n as f64)
                    .map(|t| eval(c0, c1, c2, t)).fold(f64::INFINITY, f64::min);
                prop_assert!(before >= -64.0 * f64::EPSILON * mag.max(f64::MIN_POSITIVE));
            }
        }

        /// The shortcut answers as the roots do: whenever it says "clear", the full
        /// computation finds no contact either, for gaps built to pass close to zero (a
        /// double root at `t0` lifted by `lift`, near and beyond the window's end) as well
        /// as arbitrary ones.
        #[test]
        fn the_shortcut_agrees_with_the_roots(
            t0 in -1.0f64..3.0,
            a in -50.0f64..50.0,
            lift_exp in -16i32..1,
            v in -10.0f64..10.0,
            scale_exp in -3i32..3,
            h in 0.0f64..2.0,
        ) {
            let s = 10f64.powi(scale_exp);
            let lift = 10f64.powi(lift_exp);
            // a (t - t0)^2 + lift, and a gap with an arbitrary slope
            let tangent = (s * (a * t0 * t0 + lift), -2.0 * a * t0 * s, a * s);
            let sloped = (s * lift, v * s, a * s);
            for (c0, c1, c2) in [tangent, sloped] {
                if clearly_apart(c0, c1, c2, h) {
                    prop_assert_eq!(first_contact(c0, c1, c2, h), None, "{} {} {} {}", c0, c1, c2, h);
                }
            }
        }

        /// A take-off from the surface (c0 = 0) is answered without the square root: the
        /// far root -c1/c2 at every scale, bit for bit the general formula's where that is
        /// exact (the square root of a normal c1^2 is c1 exactly).
        #[test]
        fn take_off_roots_match_the_square_root(
            mantissa in 1.0f64..2.0,
            exp in -520i32..520,
            a in 1e-3f64..1e3,
            negative_zero in proptest::bool::ANY,
        ) {
            let c1 = mantissa * 2f64.powi(exp);
            let c0 = if negative_zero { -0.0 } else { 0.0 };
            let c2 = -a;
            let t = second_root_from_touch(c0, c1, c2);
            // the roots of c1 t + c2 t^2 are 0 and -c1/c2: the correctly rounded quotient
            prop_assert_eq!(t.to_bits(), (-c1 / c2).to_bits());
            // and where c1^2 is normal and finite, bit for bit the general formula's root
            let square = c1 * c1;
            if square.is_normal() && square.is_finite() {
                let q = -0.5 * (c1 + (square - 4.0 * c0 * c2).max(0.0).sqrt());
                prop_assert_eq!(t.to_bits(), (q / c2).to_bits());
            }
        }

        /// Tangent gaps (exact double roots, built from the root) are never missed.
        #[test]
        fn never_misses_a_grazing_touch(t0 in 1e-3f64..1.0, a in 0.1f64..100.0, scale_exp in -3i32..3) {
            let s = 10f64.powi(scale_exp);
            // gap = a s (t - t0)^2
            let (c0, c1, c2) = (a * s * t0 * t0, -2.0 * a * s * t0, a * s);
            let c = first_contact(c0, c1, c2, 1.0).expect("tangency missed");
            prop_assert!((c.time_s - t0).abs() <= 1e-6 * t0.max(1.0), "{} vs {}", c.time_s, t0);
        }
    }
}
