//! Impact traces: one row per impact, written as CSV with 17 significant digits.

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
    /// Paddle velocity at impact, m/s (positive up).
    pub paddle_velocity_mps: f64,
    /// Apex height of the flight that follows this impact, m (ballistic, without drag it is
    /// `h + v+^2 / (2 g)`; with drag it is the simulated apex).
    pub apex_height_m: f64,
}
