//! The next contact of the body's contact point with the impact height: Zumel & Erdmann
//! eq. 7, in f32, with a fixed number of safeguarded Newton steps.
//!
//! # The equation
//!
//! The controller plans each impact so that the table's line passes through the contact
//! point when that point comes down to the impact height y_imp (sec. 2.1: "impact always
//! occurs at a given height"). With q0 = y - y_imp the centre of mass's height above it,
//! the contact time is the root of eq. 7 (its y_c = 0 is our y_imp):
//!
//! ```text
//! f(t) = q0 + y' t - G t^2 / 2 - l cos(theta + theta' t),
//! f'(t) = y' - G t + l theta' sin(theta + theta' t)
//! ```
//!
//! # Bracket
//!
//! Since |l cos| <= l, f > 0 wherever the parabola q(t) = q0 + y' t - G t^2/2 is above l, and
//! f <= 0 wherever q(t) <= -l. On the descending branch the contact therefore lies in
//! [t_a, t_b]: t_a the later root of q = l (0 if q never reaches l), t_b the later root of
//! q = -l (closed form, one `sqrt` each). If q' (t_a) + l |theta'| < 0, f is strictly
//! decreasing on [t_a, inf) and the root in the bracket is the only one on the descending
//! branch: the first contact there (`unique`). Otherwise (a body spinning faster than
//! |q'(t_a)| / l, about 11 rad/s on the sec. 2.3 triangle) the root found is a contact in the
//! bracket, not provably the first, and the prediction says so. Contacts of the rising
//! body right after an impact (a fast spin swinging the contact point down) are not
//! searched for: the table plans for the descending contact.
//!
//! # Iteration
//!
//! Start from `guess` (the previous step's root, moved by one period) if it lies inside the
//! bracket, else from the later root of q = l cos theta1, theta1 the angle at the later root
//! of q = l cos theta (theta held); the cosines there are Taylor's to x^4, close enough for a
//! start. Each of the
//! `iterations` steps (a fixed count, at most [`MAX_CONTACT_ITERATIONS`]) evaluates f and
//! f' (one sine/cosine pair), shrinks the bracket by the sign of f, and takes the Newton step
//! if it stays inside the (closed) bracket with f' < 0, else bisects. A final pair at the result
//! gives sin and cos of the angle at impact. Work: `iterations + 1` sine/cosine pairs,
//! five `sqrt`, `iterations + 1` divisions; no other loop.

use super::sincos::SinCos;
use crate::math::Real;

/// The most Newton steps per control step the validator accepts.
pub const MAX_CONTACT_ITERATIONS: u8 = 4;

/// The body's vertical flight and rotation now, relative to the impact height.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactInput {
    /// q0 = y - y_imp: centre of mass above the impact height, m.
    pub height_above_m: f32,
    /// y', m/s.
    pub y_dot_mps: f32,
    /// theta, rad.
    pub theta_rad: f32,
    /// theta', rad/s.
    pub theta_dot_radps: f32,
}

/// A predicted contact.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactPrediction {
    /// Time from now to the contact, s (>= 0).
    pub time_s: f32,
    /// sin theta at the contact.
    pub sin_theta: f32,
    /// cos theta at the contact.
    pub cos_theta: f32,
    /// The contact is provably the first on the descending branch (module docs).
    pub unique: bool,
}

/// Gravity and the contact distance, with the reciprocal of gravity precomputed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactGeometry {
    /// G, m/s^2 (> 0).
    pub gravity_mps2: f32,
    /// 1/G, s^2/m.
    pub inv_gravity: f32,
    /// l, m (> 0).
    pub l_m: f32,
}

impl ContactGeometry {
    /// Geometry for gravity `gravity_mps2` (> 0) and contact distance `l_m`.
    pub fn new(gravity_mps2: f32, l_m: f32) -> Self {
        Self {
            gravity_mps2,
            inv_gravity: 1.0 / gravity_mps2,
            l_m,
        }
    }

    /// The later root of q(t) = c, s, or NaN if q never reaches c (negative discriminant).
    #[inline]
    fn later_root(&self, s: &ContactInput, c: f32) -> f32 {
        let disc = s.y_dot_mps * s.y_dot_mps + 2.0 * self.gravity_mps2 * (s.height_above_m - c);
        (s.y_dot_mps + Real::sqrt(disc)) * self.inv_gravity
    }
}

/// cos x to 6.6e-3 for |x| <= 1.3 (Taylor to x^4: the error is below the next term x^6/720;
/// 4e-3 holds to |x| <= 1.19), without a call: only for the start.
#[inline]
fn cos_approx(x: f32) -> f32 {
    let u = x * x;
    1.0 + u * (-0.5 + u * (1.0 / 24.0))
}

/// A contact search in progress: the bracket, the current time and whether the root is
/// provably the first (module docs). Resumable, so the controller can spread the work over
/// control periods: [`ContactSolver::start`], `iterations` x [`ContactSolver::iterate`],
/// [`ContactSolver::finish`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactSolver {
    input: ContactInput,
    ta: f32,
    tb: f32,
    t: f32,
    unique: bool,
}

impl ContactSolver {
    /// Bracket the descending contact and choose the start; `None` if there is none ahead
    /// (the centre of mass is already below y_imp - l on its way down) or an input is not
    /// finite. `guess`: a start time in s (NaN for none). Four `sqrt` (two with a guess
    /// inside the bracket), no loop: [`ContactSolver::bracket`] then, without a usable guess,
    /// [`ContactSolver::cold_start`].
    pub fn start(geo: &ContactGeometry, s: &ContactInput, guess: f32) -> Option<Self> {
        let mut solver = Self::bracket(geo, s, guess)?;
        if solver.needs_start() {
            solver.cold_start(geo);
        }
        Some(solver)
    }

    /// The bracket [t_a, t_b], and `guess` as the start if it lies inside it (else the
    /// start is left unset: [`ContactSolver::needs_start`]). `None` as
    /// [`ContactSolver::start`]. Two `sqrt`.
    pub fn bracket(geo: &ContactGeometry, s: &ContactInput, guess: f32) -> Option<Self> {
        let l = geo.l_m;
        let tb = geo.later_root(s, -l);
        // also rejects NaN: no contact ahead, or non-finite input
        if !(tb > 0.0 && tb.is_finite()) {
            return None;
        }
        let ta_root = geo.later_root(s, l);
        let ta = if ta_root > 0.0 { ta_root } else { 0.0 };
        let unique = s.y_dot_mps - geo.gravity_mps2 * ta + l * s.theta_dot_radps.abs() < 0.0;
        Some(Self {
            input: *s,
            ta,
            tb,
            t: if guess > ta && guess < tb {
                guess
            } else {
                f32::NAN
            },
            unique,
        })
    }

    /// Whether the start is still to be chosen (no usable guess).
    #[inline]
    pub fn needs_start(&self) -> bool {
        self.t.is_nan()
    }

    /// The start without a guess: the contact with theta held at its value now, then with
    /// theta at that time (the midpoint of the bracket if that falls outside). Two `sqrt`.
    pub fn cold_start(&mut self, geo: &ContactGeometry) {
        let (s, l) = (&self.input, geo.l_m);
        let t0 = geo.later_root(s, l * cos_approx(s.theta_rad));
        let start = geo.later_root(s, l * cos_approx(s.theta_rad + s.theta_dot_radps * t0));
        self.t = if start >= self.ta && start <= self.tb {
            start
        } else {
            0.5 * (self.ta + self.tb)
        };
    }

    /// One safeguarded Newton step (one sine/cosine pair, one division).
    pub fn iterate<T: SinCos>(&mut self, geo: &ContactGeometry) {
        let s = &self.input;
        let (l, g, t) = (geo.l_m, geo.gravity_mps2, self.t);
        let (sn, cs) = T::sin_cos(s.theta_rad + s.theta_dot_radps * t);
        let f = s.height_above_m + t * (s.y_dot_mps - 0.5 * g * t) - l * cs;
        let fp = s.y_dot_mps - g * t + l * s.theta_dot_radps * sn;
        if f > 0.0 {
            self.ta = t;
        } else {
            self.tb = t;
        }
        let newton = t - f / fp;
        // inclusive: at convergence the Newton point is t itself, one end of the bracket
        self.t = if fp < 0.0 && newton >= self.ta && newton <= self.tb {
            newton
        } else {
            0.5 * (self.ta + self.tb)
        };
    }

    /// The prediction at the current time (one sine/cosine pair for the angle there).
    pub fn finish<T: SinCos>(&self) -> ContactPrediction {
        let s = &self.input;
        let (sin_theta, cos_theta) = T::sin_cos(s.theta_rad + s.theta_dot_radps * self.t);
        ContactPrediction {
            time_s: self.t,
            sin_theta,
            cos_theta,
            unique: self.unique,
        }
    }

    /// The input this search was started from.
    pub fn input(&self) -> &ContactInput {
        &self.input
    }
}

/// The descending contact of eq. 7 in one call (module docs): start, `iterations` Newton
/// steps (at most [`MAX_CONTACT_ITERATIONS`]), finish. `None` as [`ContactSolver::start`].
pub fn predict_contact<T: SinCos>(
    geo: &ContactGeometry,
    s: &ContactInput,
    guess: f32,
    iterations: u8,
) -> Option<ContactPrediction> {
    let mut solver = ContactSolver::start(geo, s, guess)?;
    for _ in 0..iterations.min(MAX_CONTACT_ITERATIONS) {
        solver.iterate::<T>(geo);
    }
    Some(solver.finish::<T>())
}

#[cfg(test)]
mod tests {
    use super::super::sincos::PolySinCos;
    use super::*;

    /// Independent f64 reference: the first root of eq. 7 from t = 0 by a 10 us scan and
    /// bisection to f64 resolution. With the centre of mass starting above l (every case
    /// here) f > 0 until the parabola comes back below l, so the first root is the
    /// descending contact.
    fn brute_force(s: &ContactInput, l: f64, g: f64) -> f64 {
        let f = |t: f64| {
            f64::from(s.height_above_m) + f64::from(s.y_dot_mps) * t
                - 0.5 * g * t * t
                - l * (f64::from(s.theta_rad) + f64::from(s.theta_dot_radps) * t).cos()
        };
        assert!(f(0.0) > 0.0);
        let h = 1e-5;
        for k in 0..1_000_000 {
            let (t, next) = (h * f64::from(k), h * f64::from(k + 1));
            if f(next) <= 0.0 {
                let (mut lo, mut hi) = (t, next);
                for _ in 0..200 {
                    let mid = 0.5 * (lo + hi);
                    if f(mid) > 0.0 {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return hi;
            }
        }
        panic!("no root within 10 s");
    }

    #[test]
    fn newton_matches_a_brute_force_f64_root() {
        let geo = ContactGeometry::new(9.81, 0.133_33);
        // a deterministic spread of states: heights, rising and falling, spins up to 4 rad/s
        let mut worst = 0.0f64;
        let mut worst_n = [0.0f64; 5];
        let mut cases = 0;
        for i in 0..12 {
            for j in 0..9 {
                for k in 0..7 {
                    let s = ContactInput {
                        height_above_m: 0.16 + 0.02 * i as f32,
                        y_dot_mps: -1.6 + 0.4 * j as f32,
                        theta_rad: -0.45 + 0.15 * k as f32,
                        theta_dot_radps: -4.0 + 0.7 * ((i + j + k) % 12) as f32,
                    };
                    let p = predict_contact::<PolySinCos>(&geo, &s, f32::NAN, 3).unwrap();
                    let t = brute_force(&s, f64::from(geo.l_m), 9.81);
                    for n in 0..=4u8 {
                        let q = predict_contact::<PolySinCos>(&geo, &s, f32::NAN, n).unwrap();
                        if q.unique {
                            let w = &mut worst_n[usize::from(n)];
                            *w = w.max((f64::from(q.time_s) - t).abs());
                        }
                    }
                    if !p.unique {
                        continue;
                    }
                    // sin and cos are those of the angle at the returned time
                    let th =
                        f64::from(s.theta_rad) + f64::from(s.theta_dot_radps) * f64::from(p.time_s);
                    assert!((f64::from(p.sin_theta) - th.sin()).abs() < 1e-6);
                    assert!((f64::from(p.cos_theta) - th.cos()).abs() < 1e-6);
                    worst = worst.max((f64::from(p.time_s) - t).abs());
                    cases += 1;
                }
            }
        }
        assert!(cases > 500, "{cases}");
        // cold start (no guess), measured: N = 0 1.7e-2 s, 1 1.4e-3 s, 2 8.2e-6 s,
        // 3 5.0e-8 s, 4 6.1e-8 s; three steps reach the f32 resolution of t (~3e-8 s plus
        // the rounding of f)
        assert!(worst_n[1] < 5e-3, "{worst_n:?}");
        assert!(worst_n[2] < 5e-5, "{worst_n:?}");
        assert!(worst_n[3] < 2e-7 && worst_n[4] < 2e-7, "{worst_n:?}");
        assert!(worst < 2e-7, "worst time error {worst:e} s");
    }

    #[test]
    fn fewer_iterations_converge_from_a_warm_start() {
        let geo = ContactGeometry::new(9.81, 0.133_33);
        let s = ContactInput {
            height_above_m: 0.25,
            y_dot_mps: 0.8,
            theta_rad: 0.3,
            theta_dot_radps: -1.3,
        };
        let exact = brute_force(&s, f64::from(geo.l_m), 9.81);
        let cold1 = predict_contact::<PolySinCos>(&geo, &s, f32::NAN, 1).unwrap();
        let cold2 = predict_contact::<PolySinCos>(&geo, &s, f32::NAN, 2).unwrap();
        let warm1 = predict_contact::<PolySinCos>(&geo, &s, (exact + 2e-4) as f32, 1).unwrap();
        let e = |p: ContactPrediction| (f64::from(p.time_s) - exact).abs();
        assert!(e(cold2) < e(cold1) || e(cold1) < 1e-6);
        assert!(e(cold2) < 1e-4, "{}", e(cold2));
        // Newton from 0.2 ms off: error ~ f''/(2 f') * 4e-8 s^2, far below 1 us
        assert!(e(warm1) < 1e-6, "{}", e(warm1));
        // zero iterations: the start itself, still inside the bracket
        let zero = predict_contact::<PolySinCos>(&geo, &s, f32::NAN, 0).unwrap();
        assert!(e(zero) < 0.02);
    }

    #[test]
    fn past_contacts_and_bad_input_give_none_and_fast_spin_is_flagged() {
        let geo = ContactGeometry::new(9.81, 0.133_33);
        let below = ContactInput {
            height_above_m: -0.2,
            y_dot_mps: -1.0,
            ..ContactInput::default()
        };
        assert_eq!(
            predict_contact::<PolySinCos>(&geo, &below, f32::NAN, 2),
            None
        );
        let nan = ContactInput {
            height_above_m: f32::NAN,
            ..ContactInput::default()
        };
        assert_eq!(predict_contact::<PolySinCos>(&geo, &nan, f32::NAN, 2), None);
        let spin = ContactInput {
            height_above_m: 0.25,
            y_dot_mps: 0.0,
            theta_rad: 0.0,
            theta_dot_radps: 40.0,
        };
        let p = predict_contact::<PolySinCos>(&geo, &spin, f32::NAN, 4).unwrap();
        assert!(!p.unique);
        // still a contact inside the bracket: f(t) within rounding of 0 or a bracket end
        assert!(p.time_s.is_finite() && p.time_s > 0.0);
    }
}
