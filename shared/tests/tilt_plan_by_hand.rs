//! The tilt controller's impact target and cubic (`tilt_control::plan`), by hand.
//!
//! The target against an f64 evaluation of the module docs' law (Zumel & Erdmann: alpha =
//! kappa theta + kappa_w theta' (sec. 2.1), eta = G l cos theta + y'^2/2 and eq. 25's v_T
//! = -[(1-e)/(1+e) + kappa_E (eta* - eta)] v_c along the normal n = (-sin alpha, cos
//! alpha), the table's line through the contact point), with every term non-zero and each
//! clamp binding alone; the cubic with dyadic coefficients (exact in f32) against its own
//! closed form, and its limit checks at the exact edge of each limit (accepted) and 1/1024
//! inside it (refused).
//!
//! Written to kill the mutants of `shared/src/tilt_control/plan.rs` (docs/mutants.md).

use dexter_core::tilt_control::plan::{
    table_angle, table_motion, AxisLimits, BodyAtImpact, Cubic, LawConstants,
};
use dexter_core::tilt_control::sincos::PolySinCos;

/// kappa 1.1 with a tilt-rate term, eq. 25's feedback towards a quarter metre of apex, a
/// 0.133 m body, impacts 3 cm above the stroke's zero: every term of the law non-zero.
fn law() -> LawConstants {
    LawConstants {
        kappa: 1.1,
        kappa_rate_s: 0.05,
        kappa_x_pm: 0.07,
        kappa_xdot_spm: 0.11,
        kappa_e_s2pm2: 0.165,
        target_energy_jpkg: 9.81 * 0.25,
        compensation: 1.0 / 3.0,
        gravity_mps2: 9.81,
        l_m: 0.1333,
        impact_height_m: 0.03,
    }
}

fn limits(min: f32, max: f32, velocity_max: f32, accel_max: f32) -> AxisLimits {
    AxisLimits {
        min,
        max,
        velocity_max,
        accel_max,
    }
}

/// The body at the impact: theta, x', y', theta' (sin and cos of theta from f64; x half a
/// second of x' from the table's middle, so every term of the tilt law is non-zero).
fn body(theta: f64, xd: f32, yd: f32, wd: f32) -> BodyAtImpact {
    BodyAtImpact {
        theta_rad: theta as f32,
        x_m: 0.5 * xd,
        sin_theta: theta.sin() as f32,
        cos_theta: theta.cos() as f32,
        x_dot_mps: xd,
        y_dot_mps: yd,
        theta_dot_radps: wd,
    }
}

/// The tilt law in f64: alpha = kappa theta + kappa_w theta' - kappa_x x - kappa_x' x' with
/// [`law`]'s constants written out (1.1, 0.05 s, 0.07 /m, 0.11 s/m).
fn law_alpha(b: &BodyAtImpact) -> f64 {
    1.1 * f64::from(b.theta_rad) + 0.05 * f64::from(b.theta_dot_radps)
        - 0.07 * f64::from(b.x_m)
        - 0.11 * f64::from(b.x_dot_mps)
}

/// The law in f64, the table at angle `alpha` (the law's or a clamped one): (eta, gain,
/// v_c, n . v_T, h, h').
struct Truth {
    energy: f64,
    gain: f64,
    vc: [f64; 2],
    vn: f64,
    h: f64,
    hd: f64,
}

fn truth(law: &LawConstants, b: &BodyAtImpact, alpha: f64) -> Truth {
    let f = f64::from;
    let (th, xd, yd, wd) = (
        f(b.theta_rad),
        f(b.x_dot_mps),
        f(b.y_dot_mps),
        f(b.theta_dot_radps),
    );
    let (g, l) = (f(law.gravity_mps2), f(law.l_m));
    let energy = g * l * th.cos() + 0.5 * yd * yd;
    let gain = f(law.compensation) + f(law.kappa_e_s2pm2) * (f(law.target_energy_jpkg) - energy);
    let vc = [xd + l * wd * th.cos(), yd + l * wd * th.sin()];
    // v_T = -gain v_c; its component along n = (-sin alpha, cos alpha)
    let vn = -gain * (-alpha.sin() * vc[0] + alpha.cos() * vc[1]);
    // the line at alpha through the pivot (x, h) meets the contact point (x + l sin th, y_imp)
    let h = f(law.impact_height_m) - alpha.tan() * l * th.sin();
    // the pivot moving with (x', h') has normal velocity cos(alpha) h' - sin(alpha) x'
    let hd = (vn + alpha.sin() * xd) / alpha.cos();
    Truth {
        energy,
        gain,
        vc,
        vn,
        h,
        hd,
    }
}

fn close(got: f32, want: f64, what: &str) {
    assert!(
        (f64::from(got) - want).abs() <= 2e-6 * (1.0 + want.abs()),
        "{what}: {got} vs {want}"
    );
}

/// Inside every limit: alpha = kappa theta + kappa_w theta' - kappa_x x - kappa_x' x', eta, the eq. 25 gain, v_c,
/// sin/cos alpha, n . v_T, h and h' all as the f64 law, and nothing clamped.
#[test]
fn inside_the_limits_the_target_is_the_law_in_f64() {
    let law = law();
    let (tilt, stroke) = (
        limits(-0.7, 0.7, 8.0, 300.0),
        limits(-1.0, 1.0, 10.0, 100.0),
    );
    for b in [
        body(0.25, 0.6, -1.5, 1.1),
        body(-0.3, -0.4, -2.2, -2.0),
        body(0.1, 0.2, -0.8, 3.0),
        body(0.15, 0.2, -4.0, 0.5),
    ] {
        let alpha = law_alpha(&b);
        let t = truth(&law, &b, alpha);
        let a = table_angle::<PolySinCos>(&law, &tilt, &b);
        close(a.alpha_law_rad, alpha, "alpha law");
        close(a.alpha_rad, alpha, "alpha");
        close(a.sin_alpha, alpha.sin(), "sin alpha");
        close(a.cos_alpha, alpha.cos(), "cos alpha");
        close(a.energy_jpkg, t.energy, "eta");
        close(a.gain, t.gain, "gain");
        close(a.contact_velocity_mps[0], t.vc[0], "v_c x");
        close(a.contact_velocity_mps[1], t.vc[1], "v_c y");
        let m = table_motion(&law, &stroke, &b, &a);
        assert!(!m.clamped, "{b:?}");
        assert_eq!(
            (m.alpha_rad, m.sin_alpha, m.cos_alpha),
            (a.alpha_rad, a.sin_alpha, a.cos_alpha)
        );
        close(m.energy_jpkg, t.energy, "eta");
        close(m.normal_velocity_mps, t.vn, "n . v_T");
        close(m.height_m, t.h, "h");
        close(m.velocity_mps, t.hd, "h'");
    }
}

/// The law's alpha beyond the tilt travel, either side: alpha is the travel's end, the
/// law's value is kept beside it, and h, h' and n . v_T follow the clamped alpha; clamped.
#[test]
fn an_angle_beyond_the_tilt_travel_is_its_end_and_the_geometry_follows_it() {
    let law = law();
    let (tilt, stroke) = (
        limits(-0.7, 0.5, 8.0, 300.0),
        limits(-1.0, 1.0, 10.0, 100.0),
    );
    for (b, end) in [
        (body(0.8, 0.3, -1.2, 0.4), 0.5f32),
        (body(-0.8, 0.3, -1.2, -0.4), -0.7),
    ] {
        let a = table_angle::<PolySinCos>(&law, &tilt, &b);
        close(a.alpha_law_rad, law_alpha(&b), "alpha law");
        assert_eq!(a.alpha_rad, end);
        let t = truth(&law, &b, f64::from(end));
        let m = table_motion(&law, &stroke, &b, &a);
        assert!(m.clamped);
        close(m.normal_velocity_mps, t.vn, "n . v_T");
        close(m.height_m, t.h, "h");
        close(m.velocity_mps, t.hd, "h'");
    }
}

/// h* beyond the stroke's travel, above and below, with alpha and h' inside: h is the
/// travel's end, h' and n . v_T are the law's; clamped.
#[test]
fn a_height_beyond_the_stroke_travel_is_its_end_alone() {
    let law = law();
    let tilt = limits(-0.7, 0.7, 8.0, 300.0);
    let b = body(0.25, 0.6, -1.5, 1.1);
    let t = truth(&law, &b, law_alpha(&b));
    assert!(t.h > 0.015 && t.h < 0.024, "{}", t.h);
    for (stroke, end) in [
        (limits(-1.0, 0.01, 10.0, 100.0), 0.01f32),
        (limits(0.025, 1.0, 10.0, 100.0), 0.025),
    ] {
        let a = table_angle::<PolySinCos>(&law, &tilt, &b);
        let m = table_motion(&law, &stroke, &b, &a);
        assert!(m.clamped);
        assert_eq!(m.height_m, end);
        close(m.velocity_mps, t.hd, "h'");
        close(m.normal_velocity_mps, t.vn, "n . v_T");
    }
}

/// h'* beyond the stroke's speed, upward (a falling body) and downward (one with more
/// energy than eta*, where eq. 25's gain is negative): h' is the signed limit and n . v_T
/// is the clamped pivot's, cos(alpha) h' - sin(alpha) x'; h is the law's; clamped.
#[test]
fn a_pivot_speed_beyond_the_stroke_limit_gives_the_normal_velocity_of_the_limit() {
    let law = law();
    let tilt = limits(-0.7, 0.7, 8.0, 300.0);
    for (b, sign) in [
        (body(0.25, 0.6, -1.5, 1.1), 1.0f32),
        (body(0.15, 0.2, -4.0, 0.5), -1.0),
    ] {
        let alpha = law_alpha(&b);
        let t = truth(&law, &b, alpha);
        assert_eq!(t.hd.signum() as f32, sign, "{}", t.hd);
        let vmax = (t.hd.abs() / 2.0) as f32;
        let stroke = limits(-1.0, 1.0, vmax, 100.0);
        let a = table_angle::<PolySinCos>(&law, &tilt, &b);
        let m = table_motion(&law, &stroke, &b, &a);
        assert!(m.clamped);
        assert_eq!(m.velocity_mps, sign * vmax);
        let vn = alpha.cos() * f64::from(sign * vmax) - alpha.sin() * f64::from(b.x_dot_mps);
        close(m.normal_velocity_mps, vn, "n . v at the limit");
        close(m.height_m, t.h, "h");
    }
}

/// p(t) = 1 - 2 t + 3 t^2 - 4 t^3 and its derivatives at dyadic times, exactly.
#[test]
fn the_cubic_evaluates_its_polynomial_exactly() {
    let c = Cubic {
        c0: 1.0,
        c1: -2.0,
        c2: 3.0,
        c3: -4.0,
    };
    assert_eq!(c.position(0.5), 0.25);
    assert_eq!(c.position(-1.0), 10.0);
    assert_eq!(c.velocity(0.5), -2.0);
    assert_eq!(c.velocity(2.0), -38.0);
    // p''(t + dt/2) = 6 - 24 (t + dt/2)
    assert_eq!(c.mean_accel(0.25, 0.5), -6.0);
    assert_eq!(c.mean_accel(1.0, 0.25), -21.0);
}

/// Hermite ends with dyadic data: p, p' at 0 and at tau exactly as asked (evaluated here
/// in f64 from the coefficients).
#[test]
fn the_hermite_cubic_meets_both_ends_exactly() {
    for (p0, v0, p1, v1, tau) in [
        (0.25f32, 1.0f32, -0.5f32, 0.5f32, 0.5f32),
        (-1.0, -0.75, 2.0, 3.0, 0.25),
    ] {
        let c = Cubic::hermite(p0, v0, p1, v1, 1.0 / tau);
        let [a0, a1, a2, a3] = [c.c0, c.c1, c.c2, c.c3].map(f64::from);
        let t = f64::from(tau);
        assert_eq!((a0, a1), (f64::from(p0), f64::from(v0)));
        assert_eq!(a0 + a1 * t + a2 * t * t + a3 * t * t * t, f64::from(p1));
        assert_eq!(a1 + 2.0 * a2 * t + 3.0 * a3 * t * t, f64::from(v1));
    }
}

fn cubic(c0: f32, c1: f32, c2: f32, c3: f32) -> Cubic {
    Cubic { c0, c1, c2, c3 }
}

/// Accepted at the exact edge of a limit and refused 1/1024 inside it, by
/// `within_dynamics` (and `within`): the acceleration at each end, the speed at each end
/// and at the vertex of v(t) inside [0, tau]; a vertex beyond tau is not checked.
#[test]
fn the_dynamic_limits_hold_at_their_exact_edges() {
    let wide = 1e3f32;
    let edge = |c: Cubic, tau: f32, v: f32, a: f32, what: &str| {
        let at = limits(-wide, wide, v, a);
        assert!(
            c.within_dynamics(tau, &at) && c.within(tau, &at),
            "{what}: at the edge"
        );
        let d = 1.0 / 1024.0;
        let inside = if v < wide {
            limits(-wide, wide, v - d, a)
        } else {
            limits(-wide, wide, v, a - d)
        };
        assert!(
            !c.within_dynamics(tau, &inside) && !c.within(tau, &inside),
            "{what}: inside"
        );
    };
    // a(0) = 60, a(0.5) = 30; v <= 22.5
    edge(cubic(0.0, 0.0, 30.0, -10.0), 0.5, wide, 60.0, "a(0)");
    // a(0) = -60
    edge(cubic(0.0, 0.0, -30.0, 10.0), 0.5, wide, 60.0, "a(0) < 0");
    // a(0) = 20, a(0.5) = 80
    edge(cubic(0.0, 0.0, 10.0, 20.0), 0.5, wide, 80.0, "a(tau)");
    edge(cubic(0.0, 0.0, -10.0, -20.0), 0.5, wide, 80.0, "a(tau) < 0");
    // v(0) = 2, v(0.5) = 1, no vertex (c3 = 0)
    edge(cubic(0.0, 2.0, -1.0, 0.0), 0.5, 2.0, wide, "v(0)");
    edge(cubic(0.0, -2.0, 1.0, 0.0), 0.5, 2.0, wide, "v(0) < 0");
    // v(0) = 1, v(0.5) = 2
    edge(cubic(0.0, 1.0, 1.0, 0.0), 0.5, 2.0, wide, "v(tau)");
    edge(cubic(0.0, -1.0, -1.0, 0.0), 0.5, 2.0, wide, "v(tau) < 0");
    // v = 6 t - 6 t^2: 0 at both ends of [0, 1], 1.5 at its vertex t = 1/2
    edge(
        cubic(0.0, 0.0, 3.0, -2.0),
        1.0,
        1.5,
        wide,
        "v at the vertex",
    );
    edge(
        cubic(0.0, 0.0, -3.0, 2.0),
        1.0,
        1.5,
        wide,
        "v at the vertex < 0",
    );
    // the same on [0, 1/4]: the vertex is beyond tau, the largest speed is v(1/4) = 1.125
    let c = cubic(0.0, 0.0, 3.0, -2.0);
    assert!(c.within_dynamics(0.25, &limits(-wide, wide, 1.125, wide)));
}

/// Accepted at the exact edge of the travel and refused 1/1024 inside it, by
/// `within_travel` (and `within`): the position at each end, and at an interior extreme of
/// each root of v(t) = 0 (q/A and C/q, both signs of B).
#[test]
fn the_travel_limits_hold_at_their_exact_edges() {
    let big = 1e3f32;
    let d = 1.0 / 1024.0;
    // `low`: the edge tested is the travel's lower end (else its upper end)
    let check = |c: Cubic, tau: f32, edge: f32, low: bool, what: &str| {
        let (at, tight) = if low {
            (limits(edge, big, big, big), limits(edge + d, big, big, big))
        } else {
            (
                limits(-big, edge, big, big),
                limits(-big, edge - d, big, big),
            )
        };
        assert!(
            c.within_travel(tau, &at) && c.within(tau, &at),
            "{what}: at the edge"
        );
        assert!(
            !c.within_travel(tau, &tight) && !c.within(tau, &tight),
            "{what}: inside"
        );
    };
    // p(0) = 1/4, p(1/2) = 1/2 or 0
    check(cubic(0.25, 0.5, 0.0, 0.0), 0.5, 0.25, true, "p(0) = min");
    check(cubic(0.25, -0.5, 0.0, 0.0), 0.5, 0.25, false, "p(0) = max");
    check(cubic(0.25, 0.5, 0.0, 0.0), 0.5, 0.5, false, "p(tau) = max");
    check(cubic(0.25, -0.5, 0.0, 0.0), 0.5, 0.0, true, "p(tau) = min");
    // p = 3 t^2 - 2 t^3 on [0, 1.25]: p(1.25) = 0.78125, its maximum 1 at t = 1 (B > 0,
    // C = 0: the root q/A)
    check(cubic(0.0, 0.0, 3.0, -2.0), 1.25, 1.0, false, "max at q/A");
    check(
        cubic(0.0, 0.0, -3.0, 2.0),
        1.25,
        -1.0,
        true,
        "min at q/A, B < 0",
    );
    // p = t^3 - 2.25 t^2 + 1.5 t on [0, 1.125]: p(1.125) = 0.263671875, its maximum
    // 0.3125 at t = 1/2 (B < 0: the root C/q), a minimum 0.25 at t = 1
    check(
        cubic(0.0, 1.5, -2.25, 1.0),
        1.125,
        0.3125,
        false,
        "max at C/q",
    );
    check(
        cubic(0.0, -1.5, 2.25, -1.0),
        1.125,
        -0.3125,
        true,
        "min at C/q, B > 0",
    );
}
