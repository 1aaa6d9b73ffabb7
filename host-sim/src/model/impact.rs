//! The line juggler's record of one impact, as its plant ([`super::line`]) emits it: the
//! trace row of a line run.

/// One impact of the ball with the paddle (or table), as recorded in a trace.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ImpactRow {
    /// Impact number, counting from 0.
    pub index: u64,
    /// Simulated time of the impact, s.
    pub time_s: f64,
    /// Ball height at impact (equal to the paddle height), m above the impact plane.
    pub ball_height_m: f64,
    /// Ball velocity just before the impact, m/s (positive up).
    pub ball_velocity_before_mps: f64,
    /// Ball velocity just after the impact, m/s (positive up).
    pub ball_velocity_after_mps: f64,
    /// Paddle height at impact, m.
    pub paddle_height_m: f64,
    /// Paddle velocity at impact, m/s (positive up; the value the restitution law used,
    /// including impact-timing jitter when that effect is on).
    pub paddle_velocity_mps: f64,
    /// Apex height of the flight that follows this impact, m (ballistic: `h + v+^2 / (2 g)`;
    /// with drag: the exact quadratic-drag apex; the impact height if the ball does not rise).
    pub apex_height_m: f64,
}
