//! The tilt controller's eq. 7 contact solver (`tilt_control::contact`) against hand
//! computations: the bracket's edges as closed-form roots of the parabola (q = +l, q = -l),
//! exact in f32 for G = 8 m/s^2 and l = 0.5 m (every intermediate a small dyadic), which
//! guesses count as inside it, when there is no contact ahead, the cold start against the
//! closed-form root of a body that does not spin (within the Taylor remainder x^6/720 of
//! its cosine), the start's fallback to the bracket's midpoint, that no step leaves the
//! bracket, and which side of a zero of f the search keeps. A mutation pass over
//! `tilt_control` found these unpinned by the core's own tests.
//!
//! Zumel & Erdmann eq. 7, with q0 the centre of mass's height above the impact height:
//! f(t) = q0 + y' t - G t^2 / 2 - l cos(theta + theta' t); the contact is f = 0.

use dexter_core::tilt_control::contact::{
    predict_contact, ContactGeometry, ContactInput, ContactSolver,
};
use dexter_core::tilt_control::sincos::{PolySinCos, SinCos};

/// G = 8 m/s^2 (a table inclined so that the body's effective gravity is 8), l = 0.5 m: 1/G,
/// 2 G and every root below are exact in f32.
fn exact_geo() -> ContactGeometry {
    ContactGeometry::new(8.0, 0.5)
}

/// The sec. 2.3 triangle's contact distance under full gravity.
fn real_geo() -> ContactGeometry {
    ContactGeometry::new(9.81, 0.133_33)
}

fn input(q0: f32, y_dot: f32, theta: f32, theta_dot: f32) -> ContactInput {
    ContactInput {
        height_above_m: q0,
        y_dot_mps: y_dot,
        theta_rad: theta,
        theta_dot_radps: theta_dot,
    }
}

/// Later root of q(t) = q0 + y' t - G t^2 / 2 = c in f64 (NaN if q never reaches c).
fn later_root(s: &ContactInput, g: f64, c: f64) -> f64 {
    let (q0, v) = (f64::from(s.height_above_m), f64::from(s.y_dot_mps));
    (v + (v * v + 2.0 * g * (q0 - c)).sqrt()) / g
}

/// The bracket [t_a, t_b] of the module docs in f64: t_a the later root of q = l (0 if
/// that is not ahead), t_b the later root of q = -l.
fn bracket(s: &ContactInput, g: f64, l: f64) -> (f64, f64) {
    let ta = later_root(s, g, l);
    let ta = if ta > 0.0 { ta } else { 0.0 };
    (ta, later_root(s, g, -l))
}

/// Eq. 7's f in f64.
fn f(s: &ContactInput, g: f64, l: f64, t: f64) -> f64 {
    f64::from(s.height_above_m) + f64::from(s.y_dot_mps) * t
        - 0.5 * g * t * t
        - l * (f64::from(s.theta_rad) + f64::from(s.theta_dot_radps) * t).cos()
}

fn time(geo: &ContactGeometry, s: &ContactInput, guess: f32, iterations: u8) -> f32 {
    predict_contact::<PolySinCos>(geo, s, guess, iterations)
        .expect("a contact ahead")
        .time_s
}

#[test]
fn no_contact_ahead_or_no_finite_time_gives_none() {
    let geo = exact_geo();
    // centre of mass already below y_imp - l and falling: t_b = (-3 + sqrt(9 - 1.6)) / 8 < 0
    let below = input(-0.6, -3.0, 0.0, 0.0);
    assert!(later_root(&below, 8.0, -0.5) < 0.0);
    assert!(ContactSolver::start(&geo, &below, f32::NAN).is_none());
    // exactly at y_imp - l, falling, upright: the contact point is 2 l below y_imp, so the
    // contact has passed (t_b = (-1 + sqrt(1)) / 8 = 0 exactly; "ahead" is t > 0)
    let at_edge = input(-0.5, -1.0, 0.0, 0.0);
    assert!(f(&at_edge, 8.0, 0.5, 0.0) < 0.0);
    assert!(ContactSolver::start(&geo, &at_edge, f32::NAN).is_none());
    // infinite inputs: no finite contact time, so no prediction (not an infinite time)
    for s in [
        input(0.3, f32::INFINITY, 0.0, 0.0),
        input(f32::INFINITY, 0.0, 0.0, 0.0),
        // finite, but y'^2 overflows f32
        input(0.3, 1e20, 0.0, 0.0),
    ] {
        assert_eq!(
            predict_contact::<PolySinCos>(&geo, &s, f32::NAN, 4),
            None,
            "{s:?}"
        );
    }
}

#[test]
fn a_guess_is_the_start_only_strictly_inside_the_bracket() {
    let geo = exact_geo();
    // q0 = 17/16: q = l at t_a = sqrt(16 * 9/16) / 8 = 0.375, q = -l at
    // t_b = sqrt(16 * 25/16) / 8 = 0.625, both exact in f32
    let s = input(1.0625, 0.0, 1.0, 0.0);
    assert_eq!(bracket(&s, 8.0, 0.5), (0.375, 0.625));
    // neither edge is a contact: f(t_a) = l (1 - cos 1) > 0, f(t_b) = -l (1 + cos 1) < 0
    assert!(f(&s, 8.0, 0.5, 0.375) > 0.1 && f(&s, 8.0, 0.5, 0.625) < -0.5);
    let cold = time(&geo, &s, f32::NAN, 0);
    // the cold start is near the closed-form root sqrt((q0 - l cos 1) / 4) = 0.445 s
    let root = ((1.0625 - 0.5 * 1.0f64.cos()) / 4.0).sqrt();
    assert!((f64::from(cold) - root).abs() < 1e-3, "{cold} vs {root}");
    // inside: zero iterations return the guess itself
    for guess in [0.376, 0.5, 0.624] {
        assert_eq!(time(&geo, &s, guess, 0), guess);
    }
    // on an edge or outside: ignored, the cold start instead
    for guess in [0.375, 0.625, 0.2, 0.7, -0.1, f32::INFINITY] {
        assert_eq!(time(&geo, &s, guess, 0), cold, "guess {guess}");
    }
    // a guess of "now" while the contact point is still above y_imp (t_a = 0 here: q0 < l;
    // f(0) = 0.4 - 0.5 cos 0.9 > 0) is not the contact either
    let low = input(0.4, -0.5, 0.9, 0.0);
    assert_eq!(bracket(&low, 8.0, 0.5).0, 0.0);
    assert!(f(&low, 8.0, 0.5, 0.0) > 0.0);
    let t = time(&geo, &low, 0.0, 0);
    assert!(t > 0.0 && t == time(&geo, &low, f32::NAN, 0), "{t}");
}

#[test]
fn without_spin_the_cold_start_is_the_closed_form_root_within_the_taylor_remainder() {
    // theta' = 0: eq. 7 is q(t) = l cos theta, whose later root is closed form. The start
    // solves q(t) = l cos4(theta), cos4 Taylor's polynomial to x^4, whose error is at most
    // the next term x^6 / 720 (alternating series); on the descending branch that moves
    // the root by at most l x^6 / 720 / |q'| (q' taken at the earlier root, so at most
    // |q'(t*)|; 1.5x for the curvature and 1 us for f32).
    let geo = real_geo();
    let (g, l) = (9.81, f64::from(geo.l_m));
    let mut cases = 0;
    for q0 in [0.2f32, 0.35, 0.6] {
        for v in [-1.5f32, 0.0, 1.2] {
            for k in 0..=20 {
                let theta = -1.3 + 0.13 * k as f32;
                let s = input(q0, v, theta, 0.0);
                let x = f64::from(theta);
                let root = later_root(&s, g, l * x.cos());
                let slope = f64::from(v) - g * root;
                if slope > -1.0 {
                    continue;
                }
                let tol = 1.5 * l * x.powi(6) / 720.0 / slope.abs() + 1e-6;
                let t = f64::from(time(&geo, &s, f32::NAN, 0));
                assert!((t - root).abs() < tol, "{s:?}: {t} vs {root} (tol {tol:e})");
                cases += 1;
            }
        }
    }
    assert!(cases > 100, "{cases}");
}

#[test]
fn a_start_outside_the_bracket_falls_back_to_the_brackets_midpoint() {
    let geo = real_geo();
    let (g, l) = (9.81, f64::from(geo.l_m));
    // |theta| = 3.6 > sqrt(12): cos4 = 1 - u/2 + u^2/24 = 1.518 > 1, so q = l cos4 is
    // reached before t_a (q0 = 0.5 m is above 1.518 l): outside the bracket
    for theta in [3.6f32, -3.6] {
        let s = input(0.5, 0.0, theta, 0.0);
        assert!(later_root(&s, g, 1.5 * l) < bracket(&s, g, l).0);
        let (ta, tb) = bracket(&s, g, l);
        let t = f64::from(time(&geo, &s, f32::NAN, 0));
        assert!((t - 0.5 * (ta + tb)).abs() < 1e-6, "{t} vs [{ta}, {tb}]");
    }
    // theta = 1.2, at rest at its apex 0.2 mm above the contact height (l cos 1.2 =
    // 48.31 mm): the contact is 6 ms ahead, but the Taylor cosine, larger than cos by about
    // x^6/720, puts the start's level l cos4 = 48.85 mm above the apex: no root at all, so
    // the midpoint of [0, t_b] (t_a = 0: q never reaches l)
    let s = input(0.0486, 0.0, 1.2, 0.0);
    let x = 1.2f64;
    assert!(f(&s, g, l, 0.0) > 0.0 && l * (1.0 - x * x / 2.0 + x.powi(4) / 24.0) > 0.0486);
    let (ta, tb) = bracket(&s, g, l);
    assert_eq!(ta, 0.0);
    let t = f64::from(time(&geo, &s, f32::NAN, 0));
    assert!((t - 0.5 * tb).abs() < 1e-6, "{t} vs [0, {tb}]");
}

#[test]
fn no_step_leaves_the_bracket() {
    // the module docs: Newton only if it stays inside the bracket with f' < 0, else bisect;
    // so after any number of steps the time lies in [t_a, t_b], whatever the spin
    let geo = real_geo();
    let (g, l) = (9.81, f64::from(geo.l_m));
    let mut cases = 0;
    for i in 0..8 {
        for j in 0..7 {
            for k in 0..9 {
                for m in 0..11 {
                    let s = input(
                        0.05 + 0.1 * i as f32,
                        -2.0 + 0.6 * j as f32,
                        -3.0 + 0.75 * k as f32,
                        -50.0 + 10.0 * m as f32,
                    );
                    let (ta, tb) = bracket(&s, g, l);
                    for n in 0..=4 {
                        let t = f64::from(time(&geo, &s, f32::NAN, n));
                        assert!(
                            t >= ta - 1e-6 && t <= tb + 1e-6,
                            "{s:?} n={n}: {t} outside [{ta}, {tb}]"
                        );
                    }
                    cases += 1;
                }
            }
        }
    }
    assert!(cases > 4000, "{cases}");
}

/// An input whose f is exactly 0.0 in f32 at t = 0.5 s (G = 8, l = 0.5, y' = 0: the
/// parabola's part is exactly q0 - 1) with f' > 0 there: the contact point rising through
/// y_imp. Found by scanning theta for a cosine that makes `(q0 - 1) - l cos` exact.
fn rising_zero_at_half_a_second(theta_dot: f32) -> ContactInput {
    for k in 0..7_000 {
        let theta = 1e-3 * k as f32;
        let (sn, cs) = PolySinCos::sin_cos(theta + theta_dot * 0.5);
        let q0 = 1.0 + 0.5 * cs;
        // f'(0.5) = y' - G t + l theta' sin = -4 + 0.5 theta' sin
        let rising = -4.0 + 0.5 * theta_dot * sn > 1.0;
        if rising && cs > -0.9 && (q0 + 0.5 * (0.0 - 0.5 * 8.0 * 0.5)) - 0.5 * cs == 0.0 {
            return input(q0, 0.0, theta, theta_dot);
        }
    }
    panic!("no exact zero found");
}

#[test]
fn at_an_exact_zero_where_f_rises_the_search_keeps_the_earlier_part() {
    // f(t_a) = l (1 - cos) >= 0 and f rises through 0 at t = 0.5: so f came down through 0
    // before 0.5, an earlier contact; the first one is in [t_a, 0.5], and the search must
    // keep that part of the bracket (f = 0 is not "f > 0")
    let geo = exact_geo();
    let s = rising_zero_at_half_a_second(20.0);
    let (ta, tb) = bracket(&s, 8.0, 0.5);
    assert!(ta < 0.5 && 0.5 < tb, "[{ta}, {tb}]");
    assert!(f(&s, 8.0, 0.5, 0.5 - 1e-3) < 0.0 && f(&s, 8.0, 0.5, ta) >= 0.0);
    for n in 1..=4 {
        let t = time(&geo, &s, 0.5, n);
        assert!(t < 0.5 && f64::from(t) >= ta, "n={n}: {t}");
    }
}
