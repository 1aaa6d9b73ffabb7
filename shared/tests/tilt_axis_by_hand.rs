//! One tilt-controller table axis (`tilt_control::axis`) against hand computations: which
//! limit binds and that it is reported (the speed limit, the stopping-distance limit
//! `sqrt(2 a_max room)`, the acceleration limit), the reference's exact advance under a
//! held acceleration (p + v dt + a dt^2 / 2), and the braking feed-forward that stops the
//! reference within v^2 / (2 a_max) plus one period's slack. A mutation pass over
//! `tilt_control` found these unpinned by the core's own tests.

use dexter_core::state::PaddleState;
use dexter_core::tilt_control::axis::Axis;
use dexter_core::tilt_control::plan::AxisLimits;

const DT: f32 = 0.002;
const A_MAX: f32 = 60.0;
const V_MAX: f32 = 2.0;

fn axis() -> Axis {
    let limits = AxisLimits {
        min: -0.1,
        max: 0.1,
        velocity_max: V_MAX,
        accel_max: A_MAX,
    };
    Axis::new(limits, 2500.0, 100.0, 0.0, DT)
}

/// The axis's reference placed on the measured state, so the command is `a_ff` until a
/// limit binds.
fn on(p: f32, v: f32) -> (Axis, PaddleState<f32>) {
    let mut a = axis();
    a.p = p;
    a.v = v;
    (a, PaddleState::new(p, v))
}

fn close(got: f32, expect: f32, tol: f32) -> bool {
    (got - expect).abs() < tol
}

#[test]
fn inside_every_limit_the_command_is_the_feed_forward_unflagged() {
    let (a, m) = on(0.0, 0.5);
    let (u, limited) = a.command(10.0, &m, DT);
    assert!(close(u, 10.0, 1e-3), "{u}");
    assert!(!limited);
}

#[test]
fn the_speed_limit_alone_binds_and_is_reported() {
    // 1.99 m/s + 10 * 2 ms = 2.01 > 2: the velocity after the period is held at 2, i.e.
    // (2 - 1.99) / 2 ms = 5 m/s^2, well inside the acceleration limit
    let (a, m) = on(0.0, 1.99);
    let (u, limited) = a.command(10.0, &m, DT);
    assert!(close(u, 5.0, 1e-3), "{u}");
    assert!(limited, "the speed limit changed the command");
    // the same downwards
    let (a, m) = on(0.0, -1.99);
    let (u, limited) = a.command(-10.0, &m, DT);
    assert!(close(u, -5.0, 1e-3), "{u}");
    assert!(limited);
}

#[test]
fn the_stopping_distance_limit_binds_near_the_end_of_travel() {
    // 3 mm from the top: the axis can still stop from sqrt(2 * 60 * 0.003) = 0.6 m/s
    // (braking distance v^2 / (2 a) = 3 mm); 0.59 + 10 * 2 ms = 0.61 is held at 0.6
    let (a, m) = on(0.097, 0.59);
    let (u, limited) = a.command(10.0, &m, DT);
    assert!(close(u, 5.0, 2e-2), "{u}");
    assert!(limited);
    // mirrored at the bottom
    let (a, m) = on(-0.097, -0.59);
    let (u, limited) = a.command(-10.0, &m, DT);
    assert!(close(u, -5.0, 2e-2), "{u}");
    assert!(limited);
    // the other side's room does not limit: moving down from near the top is free
    let (a, m) = on(0.097, -0.59);
    let (u, limited) = a.command(-10.0, &m, DT);
    assert!(close(u, -10.0, 1e-3), "{u}");
    assert!(!limited);
}

#[test]
fn the_acceleration_limit_alone_binds_and_is_reported() {
    // 100 m/s^2 for 2 ms from rest is 0.2 m/s, inside every speed limit; the command is
    // held at 60 m/s^2
    let (a, m) = on(0.0, 0.0);
    assert_eq!(a.command(100.0, &m, DT), (A_MAX, true));
    assert_eq!(a.command(-100.0, &m, DT), (-A_MAX, true));
}

#[test]
fn advance_moves_the_reference_exactly_under_the_held_acceleration() {
    let mut a = axis();
    a.p = 0.01;
    a.v = 0.3;
    // p + v dt + a dt^2 / 2 = 0.01 + 0.0006 - 0.00004; v + a dt = 0.3 - 0.04
    let (p, v) = (0.010_56f32, 0.26f32);
    let ahead = a.advanced(-20.0, DT);
    assert!(
        close(ahead.0, p, 1e-8) && close(ahead.1, v, 1e-6),
        "{ahead:?}"
    );
    assert_eq!((a.p, a.v), (0.01, 0.3), "advanced does not move it");
    a.advance(-20.0, DT);
    assert!(close(a.p, p, 1e-8) && close(a.v, v, 1e-6), "{a:?}");
}

#[test]
fn the_brake_reference_stops_the_reference_in_a_period_or_at_the_limit() {
    let mut a = axis();
    // |v| / dt within the limit: stop in one period, -v / dt
    for (v, expect) in [(0.05f32, -25.0f32), (-0.05, 25.0), (0.0, 0.0)] {
        a.v = v;
        let b = a.brake_reference();
        assert!(close(b, expect, 1e-3), "v {v}: {b} vs {expect}");
    }
    // beyond it: the full limit against the motion
    a.v = 1.0;
    assert_eq!(a.brake_reference(), -A_MAX);
    a.v = -1.0;
    assert_eq!(a.brake_reference(), A_MAX);
    // from 1 m/s at 60 m/s^2 and 2 ms: 8 full periods to 0.04 m/s, then one more; the
    // distance is v^2 / (2 a) = 8.33 mm up to a dt^2 / 2 = 0.12 mm (the last period's
    // weaker braking)
    a.p = 0.0;
    a.v = 1.0;
    let mut periods = 0;
    // (f32: -v / dt * dt leaves a residue of ~1e-8 m/s, hence "at rest" within 1e-6)
    while a.v.abs() > 1e-6 && periods < 100 {
        let b = a.brake_reference();
        a.advance(b, DT);
        periods += 1;
    }
    assert_eq!(periods, 9);
    let (d, d_min) = (a.p, 1.0 / (2.0 * A_MAX));
    assert!(
        d >= d_min - 1e-6 && d <= d_min + 0.5 * A_MAX * DT * DT + 1e-6,
        "{d}"
    );
}
