//! The first contact of a transcendental gap (Zumel & Erdmann eq. 7), never missed.
//!
//! # The gap
//!
//! In flight the centre of mass follows a parabola and the body turns at a constant rate,
//! so the distance of the contact point above a table line with unit normal
//! n = (-sin alpha, cos alpha) has the form
//!
//! ```text
//! g(t) = c0 + c1 t + c2 t^2 - l cos(phi0 + omega t)          (m)
//! ```
//!
//! with `c2 = -G cos(alpha)/2` and `phi0 = theta - alpha` (module docs of
//! [`super`]); eq. 7 is the case alpha = 0, table at rest at y = 0. It is transcendental
//! in t.
//!
//! # Bracket, then refine, with bounded work
//!
//! Since `g'' = 2 c2 + l omega^2 cos(..) >= -A` with `A = -2 c2 + l omega^2`, Taylor's theorem
//! gives the lower bound `g(t + h) >= g(t) + g'(t) h - A h^2 / 2`. Its smallest positive
//! zero, `h = (g' + sqrt(g'^2 + 2 A g)) / A`, is a step that **cannot skip a contact**
//! (conservative advancement, second order: the step is bounded by the fastest possible
//! closing of the gap). Near a transversal root the steps converge quadratically from the
//! safe side; past a near-miss (a local minimum above zero) they lengthen again. Once the
//! gap is within rounding of zero:
//!
//! - if it is closing (`g' < 0`), a bracket `[t, b]` with `g(b) < 0` is found by doubling a
//!   step (capped) and refined by bisection to adjacent floats (capped);
//! - else it is a **grazing** contact (a minimum of the gap at zero, within rounding):
//!   reported with `grazing = true`.
//!
//! Every loop is capped ([`MAX_ADVANCE_STEPS`], [`MAX_BRACKET_DOUBLINGS`],
//! [`MAX_BISECTIONS`]); hitting a cap is an error, never a silent miss. The test
//! `first_contact_is_never_missed` in `tests/integration/planar.rs` checks the result against a
//! brute-force search on a fine grid, grazing cases included.

/// Most conservative-advancement steps per contact search.
pub const MAX_ADVANCE_STEPS: usize = 100_000;
/// Most doublings when bracketing a closing root.
pub const MAX_BRACKET_DOUBLINGS: usize = 64;
/// Most bisection steps (each halves the bracket; 1100 covers any f64 interval).
pub const MAX_BISECTIONS: usize = 1100;
/// Rounding allowance of the gap, in units of f64 epsilon times the gap's scale.
const GAP_ULPS: f64 = 64.0;

/// The gap `c0 + c1 t + c2 t^2 - l cos(phi0 + omega t)`, m, t in s (eq. 7, generalized to a
/// tilted moving table).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gap {
    /// Constant term, m.
    pub c0: f64,
    /// Linear term, m/s.
    pub c1: f64,
    /// Quadratic term, m/s^2 (`-G cos(alpha)/2`, negative for a table tilted less than
    /// 90 degrees).
    pub c2: f64,
    /// Contact distance l, m (0: a point mass, the gap is a quadratic).
    pub l_m: f64,
    /// Phase phi0 = theta - alpha at t = 0, rad.
    pub phi0_rad: f64,
    /// Angular velocity omega = theta', rad/s.
    pub omega_radps: f64,
}

impl Gap {
    /// g(t), m.
    #[inline]
    pub fn value(&self, t: f64) -> f64 {
        self.c0 + t * (self.c1 + t * self.c2)
            - self.l_m * (self.phi0_rad + self.omega_radps * t).cos()
    }

    /// g'(t), m/s.
    #[inline]
    pub fn rate(&self, t: f64) -> f64 {
        self.c1
            + 2.0 * self.c2 * t
            + self.l_m * self.omega_radps * (self.phi0_rad + self.omega_radps * t).sin()
    }

    /// A, m/s^2: g'' >= -A for all t.
    #[inline]
    pub fn curvature_bound(&self) -> f64 {
        (-2.0 * self.c2 + self.l_m * self.omega_radps * self.omega_radps).max(0.0)
    }

    /// A time after which the gap is certainly negative (the quadratic with `+ l` in place
    /// of the cosine has passed its last zero), s; `None` if the gap need not close
    /// (c2 >= 0).
    pub fn horizon_s(&self) -> Option<f64> {
        if self.c2 >= 0.0 {
            return None;
        }
        let (a, b, c) = (self.c2, self.c1, self.c0 + self.l_m.abs());
        let disc = b * b - 4.0 * a * c;
        if disc < 0.0 {
            return Some(0.0);
        }
        // larger root of a t^2 + b t + c (a < 0)
        Some(((-b - disc.sqrt()) / (2.0 * a)).max(0.0))
    }

    /// Magnitude of the gap's terms at time t (for the rounding allowance), m.
    fn scale(&self, t: f64) -> f64 {
        self.c0.abs() + (self.c1 * t).abs() + (self.c2 * t * t).abs() + self.l_m.abs()
    }
}

/// A contact found by [`first_contact`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Time of the contact after the search start, s.
    pub time_s: f64,
    /// True if the gap only touches zero (its rate is not negative there): zero normal
    /// closing speed, within rounding.
    pub grazing: bool,
    /// Gap evaluations used (the cost side of the accuracy/time trade).
    pub evaluations: usize,
}

/// Why a contact search failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ContactError {
    /// A loop hit its cap (the named one).
    Cap(&'static str),
    /// A coefficient or a gap value is not finite.
    NonFinite,
}

/// The earliest t in `[0, horizon]` with g(t) <= 0 (to rounding), see the module docs.
///
/// At t = 0 the gap may be zero (just after an impact): if it is opening (g'(0) > 0) the
/// search starts past it; if it is not opening, the contact is at 0 (`grazing` if g'(0) = 0).
/// If the gap starts negative and opening (below the line, rising), the search starts where
/// the lower bound guarantees g > 0 (`Ok(None)` if it guarantees nothing).
/// `Ok(None)`: no contact before the gap's horizon (only possible for c2 >= 0).
pub fn first_contact(gap: &Gap) -> Result<Option<Contact>, ContactError> {
    let coeffs = [
        gap.c0,
        gap.c1,
        gap.c2,
        gap.l_m,
        gap.phi0_rad,
        gap.omega_radps,
    ];
    if coeffs.iter().any(|c| !c.is_finite()) {
        return Err(ContactError::NonFinite);
    }
    let horizon = match gap.horizon_s() {
        Some(h) => h,
        None => return Ok(None),
    };
    let a = gap.curvature_bound();
    let tol = GAP_ULPS * f64::EPSILON * gap.scale(horizon);
    first_root(|t| (gap.value(t), gap.rate(t)), a, 0.0, horizon, tol)
}

/// The earliest t in `[t0, horizon]` with f(t) <= `tol`, for any smooth f with `f'' >= -a`
/// on the interval; `f` returns (f(t), f'(t)). Same algorithm and start rules as
/// [`first_contact`] (module docs); also used by the planar juggler's transcendental
/// eq. 14.
pub fn first_root<F: Fn(f64) -> (f64, f64)>(
    f: F,
    a: f64,
    t0: f64,
    horizon: f64,
    tol: f64,
) -> Result<Option<Contact>, ContactError> {
    let mut evals = 1usize;
    let mut t = t0;
    // a crossing whose closing speed is within what a rounding-level dip below zero
    // produces (g' = sqrt(2 a tol)) is reported as grazing
    let graze_speed = (2.0 * a * tol).sqrt();
    let mut at_start = true;
    // Start below zero and rising (after an impact below the planned line, timing noise):
    // the search for the next downward crossing starts at h = f'/a, where the lower bound
    // f + f' h - a h^2/2 peaks; if that peak is not above zero, nothing is guaranteed.
    let (g_start, gd_start) = f(t0);
    if !(g_start.is_finite() && gd_start.is_finite()) {
        return Err(ContactError::NonFinite);
    }
    if g_start < -tol && gd_start > 0.0 {
        if a == 0.0 || g_start + gd_start * gd_start / (2.0 * a) <= 0.0 {
            return Ok(None);
        }
        t = t0 + gd_start / a;
        at_start = false;
    }
    for _ in 0..MAX_ADVANCE_STEPS {
        let (g, gd) = f(t);
        evals += 1;
        if !(g.is_finite() && gd.is_finite()) {
            return Err(ContactError::NonFinite);
        }
        if g <= tol && !(at_start && gd > 0.0) {
            if gd < 0.0 {
                return refine(&f, t, g, gd, evals).map(|mut c| {
                    c.grazing |= -f(c.time_s).1 <= graze_speed;
                    Some(c)
                });
            }
            return Ok(Some(Contact {
                time_s: t,
                grazing: true,
                evaluations: evals,
            }));
        }
        at_start = false;
        let g0 = g.max(0.0);
        let h = if a > 0.0 {
            (gd + (gd * gd + 2.0 * a * g0).sqrt()) / a
        } else if gd < 0.0 {
            g0 / -gd
        } else {
            f64::INFINITY
        };
        let next = t + h;
        if next > horizon || !next.is_finite() {
            // the bound says no root lies in (t, horizon); check the end for rounding
            let (gh, _) = f(horizon);
            evals += 1;
            if gh <= 0.0 && g > 0.0 {
                return bisect(&f, t, horizon, evals).map(Some);
            }
            return Ok(None);
        }
        if next == t {
            // the step underflowed: we sit on the root to rounding
            return Ok(Some(Contact {
                time_s: t,
                grazing: gd >= 0.0,
                evaluations: evals,
            }));
        }
        t = next;
    }
    Err(ContactError::Cap("planar contact: advancement steps"))
}

/// From a point `t` just above a closing root: bracket it and bisect to adjacent floats.
fn refine<F: Fn(f64) -> (f64, f64)>(
    f: &F,
    t: f64,
    g: f64,
    gd: f64,
    evals: usize,
) -> Result<Contact, ContactError> {
    let mut evals = evals;
    if g <= 0.0 {
        return Ok(Contact {
            time_s: t,
            grazing: false,
            evaluations: evals,
        });
    }
    let mut step = (2.0 * g / -gd).max(f64::EPSILON * t.abs().max(f64::MIN_POSITIVE));
    for _ in 0..MAX_BRACKET_DOUBLINGS {
        let b = t + step;
        evals += 1;
        let (gb, gdb) = f(b);
        if gb <= 0.0 {
            return bisect(f, t, b, evals);
        }
        if gdb >= 0.0 {
            // the gap turned back up before crossing: a minimum within rounding of zero
            return Ok(Contact {
                time_s: t,
                grazing: true,
                evaluations: evals,
            });
        }
        step *= 2.0;
    }
    Err(ContactError::Cap("planar contact: bracket doublings"))
}

/// Bisection of `[lo, hi]` with f(lo) > 0 >= f(hi), to adjacent floats; returns hi.
fn bisect<F: Fn(f64) -> (f64, f64)>(
    f: &F,
    lo: f64,
    hi: f64,
    evals: usize,
) -> Result<Contact, ContactError> {
    let (mut lo, mut hi, mut evals) = (lo, hi, evals);
    for _ in 0..MAX_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            let (_, gd) = f(hi);
            return Ok(Contact {
                time_s: hi,
                grazing: gd >= 0.0,
                evaluations: evals,
            });
        }
        evals += 1;
        if f(mid).0 > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Err(ContactError::Cap("planar contact: bisections"))
}
