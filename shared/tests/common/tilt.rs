//! The kappa-tilt tests' f64 truth: the body's ballistic flight, its descending contact with
//! the table (Zumel & Erdmann eq. 7), and the frame a perfect camera and table sensors send, and the table's
//! exact axes under a held command.

use dexter_core::tilt_control::{TiltCommand, TiltFrame};

/// Gravity of the tilt tests, m/s^2 (`TiltParams::default()`'s).
pub const G: f64 = 9.81;

/// The body in flight, f64 truth: (x, y, theta, x', y', theta') at `t` s from `s0` at 0
/// (t < 0: before).
pub fn flight(s0: [f64; 6], t: f64) -> [f64; 6] {
    [
        s0[0] + s0[3] * t,
        s0[1] + s0[4] * t - 0.5 * G * t * t,
        s0[2] + s0[5] * t,
        s0[3],
        s0[4] - G * t,
        s0[5],
    ]
}

/// The frame with the body at `b` and the table at (angle rad, rate rad/s, height m,
/// velocity m/s).
pub fn frame_at(seq: u32, b: [f64; 6], table: [f64; 4]) -> TiltFrame {
    TiltFrame {
        seq,
        body_x_m: b[0] as f32,
        body_y_m: b[1] as f32,
        body_theta_rad: b[2] as f32,
        table_angle_rad: table[0] as f32,
        table_rate_radps: table[1] as f32,
        table_height_m: table[2] as f32,
        table_velocity_mps: table[3] as f32,
    }
}

/// The table's exact axes (angle rad, rate rad/s, height m, velocity m/s) `s` seconds on,
/// as double integrators under the command's held accelerations.
pub fn table_after(table: [f64; 4], cmd: &TiltCommand, s: f64) -> [f64; 4] {
    let (ua, uh) = (
        f64::from(cmd.tilt_accel_radps2),
        f64::from(cmd.stroke_accel_mps2),
    );
    [
        table[0] + table[1] * s + 0.5 * ua * s * s,
        table[1] + ua * s,
        table[2] + table[3] * s + 0.5 * uh * s * s,
        table[3] + uh * s,
    ]
}

/// The descending contact of eq. 7 (the contact point y - l cos theta reaches `y_imp` m)
/// of the true flight from `s0`, s: a 10 us scan, then bisection in f64.
pub fn true_contact(s0: [f64; 6], l: f64, y_imp: f64) -> f64 {
    let f = |t: f64| {
        let b = flight(s0, t);
        b[1] - l * b[2].cos() - y_imp
    };
    let mut t = 0.0;
    while f(t + 1e-5) > 0.0 {
        t += 1e-5;
    }
    let (mut lo, mut hi) = (t, t + 1e-5);
    for _ in 0..100 {
        let m = 0.5 * (lo + hi);
        if f(m) > 0.0 {
            lo = m;
        } else {
            hi = m;
        }
    }
    hi
}
