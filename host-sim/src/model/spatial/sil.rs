//! The spatial juggler closed through the core's [`SpatialController`] (SIL: [`Sil`], the
//! same code the firmware runs; or the firmware itself behind the same
//! [`StepController`], `--hil`).
//!
//! # The plant
//!
//! - **Joints:** three double integrators driven by the command's accelerations, held over
//!   each control period (zero-order hold) and saturated at the drive's own limits, so within
//!   a period every joint angle is a quadratic in time, exactly.
//! - **Ball:** ballistic in closed form between impacts.
//! - **Paddle:** the plane through the base with normal n(q) ([`PaddleFrame`]), cut to a
//!   blade of `reach_m` along the bar and `half_width_m` to each side of it.
//! - **Contact:** the first time in a period at which the gap G(s) = n(q(s)) . b(s) falls
//!   from positive to zero, found by [`first_root`] with the curvature bound
//!   `|G''| <= (sum|q_i''| + 2 W^2) B + 2 W V + gamma`, W = sum |q_i'| (the bound on |omega|,
//!   so |n'| <= W and |n''| <= |omega'| + |omega|^2 <= sum|q_i''| + 2 W^2), B and V bounds
//!   on |b| and |b'| over the period. A crossing off the blade is no contact (the ball
//!   passes the plane beside the paddle); at most one impact per period (the ball leaves at
//!   (1 + alpha) times its closing speed).
//! - **Impact:** frictionless unless friction is on ([`super::friction`]), the paddle much
//!   heavier than the ball:
//!   `b'+ = b' - (1 + alpha) (n . (b' - omega x b)) n` ([`PaddleFrame::bounce`]).
//! - **Camera:** the ball's position at every control step with Gaussian noise per axis,
//!   delivered `latency_s` later ([`crate::effects::sensor`]); **encoders:** the joint
//!   angles rounded to `resolution_rad`, and the joint rates, exact, now.
//!
//! The run ends after the requested impacts, when the ball falls `reach_m` below the base
//! (dropped: the paddle missed it), or at the step cap.

use super::{SpatialBat, MAX_BATS};
use crate::closed_loop::{drive, SampledPlant};
use crate::controller::{ControllerError, SafeSteps, Sil, StepController};
use crate::effects::sensor::{AtControlSteps, Latency, Measured, NoLatency, Sampled};
use crate::model::planar::contact::{first_root, ContactError};
use dexter_core::fixed_rate::FixedRate;
use dexter_core::spatial::{cross, dot, PaddleFrame, SpatialBall};
use dexter_core::spatial_control::{SpatialCommand, SpatialController, SpatialFrame};
use serde::Serialize;
use std::ops::ControlFlow;

/// The camera: noise, latency and its generator's seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Standard deviation of each coordinate's noise, m (0 = none).
    pub sigma_m: f64,
    /// Delay from a sample to its delivery, s (>= 0; a multiple of the control period for
    /// a new sample at every step).
    pub latency_s: f64,
    /// Seed of the noise generator.
    pub seed: u64,
}

/// Everything the SIL plant needs besides the controller's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SilPlant {
    /// Ball-paddle restitution alpha, in (0, 1].
    pub restitution: f64,
    /// Gravity gamma, m/s^2.
    pub gravity_mps2: f64,
    /// Control period, s.
    pub dt_s: f64,
    /// The camera.
    pub camera: Camera,
    /// Encoder resolution, rad (0 = exact).
    pub resolution_rad: f64,
    /// The drives' acceleration limits, rad/s^2 (a command beyond is saturated).
    pub accel_max_radps2: [f64; 3],
    /// Length of the blade along the bar, m.
    pub reach_m: f64,
    /// Half the blade's width across the bar, m.
    pub half_width_m: f64,
    /// Coulomb friction at the bats ([`super::friction`]); `None`: off.
    pub friction: Option<f64>,
    /// The ball at t = 0.
    pub ball: SpatialBall<f64>,
    /// The joint angles at t = 0, rad (at rest).
    pub joints_rad: [f64; 3],
}

/// Why a closed-loop run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SilEnd {
    /// All impacts done.
    Completed,
    /// The ball fell past the paddle.
    Dropped,
    /// The contact search hit its cap (an internal limit, not the physics).
    SearchCap,
    /// A value became non-finite.
    NonFinite,
    /// The step cap was reached first.
    StepCap,
}

/// A closed-loop run's figures besides its bats.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SilReport {
    /// Why it ended.
    pub end: SilEnd,
    /// Control steps and those answered in the safe state.
    pub safe: SafeSteps,
    /// Impacts.
    pub impacts: usize,
    /// Largest |reference - joint| over the three joints at the impacts, rad.
    pub max_tracking_error_at_impact_rad: f64,
}

type CameraSensor = Sampled<3, AtControlSteps, Measured<3>, Latency<3>>;
type Encoders = Sampled<3, AtControlSteps, Measured<3>, NoLatency<3>>;

/// The joints over one period under constant accelerations.
#[derive(Clone, Copy, Debug)]
struct Joints {
    q: [f64; 3],
    w: [f64; 3],
}

impl Joints {
    fn at(&self, a: &[f64; 3], s: f64) -> Joints {
        Joints {
            q: core::array::from_fn(|i| self.q[i] + self.w[i] * s + 0.5 * a[i] * s * s),
            w: core::array::from_fn(|i| self.w[i] + a[i] * s),
        }
    }

    fn paddle(&self) -> PaddleFrame<f64> {
        let e = self.q[1] + core::f64::consts::FRAC_PI_2;
        PaddleFrame::from_sin_cos(
            [self.q[0].sin_cos(), e.sin_cos(), self.q[2].sin_cos()],
            self.w,
        )
    }
}

struct Plant<'a> {
    p: SilPlant,
    ball: SpatialBall<f64>,
    joints: Joints,
    accel: [f64; 3],
    refs: [f64; 3],
    t_s: f64,
    camera: CameraSensor,
    encoders: Encoders,
    impacts: usize,
    want: usize,
    worst_error: f64,
    on_bat: &'a mut dyn FnMut(&SpatialBat),
}

impl Plant<'_> {
    /// The first contact in `[0, h]` of this period, s from its start.
    fn contact_s(&self, h: f64) -> Result<Option<f64>, SilEnd> {
        let (ball, j0, a) = (self.ball, self.joints, self.accel);
        let g = self.p.gravity_mps2;
        if j0.paddle().gap_m(&ball.position_m) <= 0.0 {
            return Ok(None);
        }
        let gap = |s: f64| {
            let (b, pf) = (ball.flown(s, g), j0.at(&a, s).paddle());
            (pf.gap_m(&b.position_m), pf.gap_rate_mps(&b))
        };
        let w: f64 = (0..3).map(|i| j0.w[i].abs() + a[i].abs() * h).sum();
        let norm = |v: &[f64; 3]| dot(v, v).sqrt();
        let speed = norm(&ball.velocity_mps) + g * h;
        let reach = norm(&ball.position_m) + speed * h;
        let sum_a: f64 = a.iter().map(|x| x.abs()).sum();
        let bound = (sum_a + 2.0 * w * w) * reach + 2.0 * w * speed + g;
        let tol = 64.0 * f64::EPSILON * (1.0 + reach);
        match first_root(gap, bound, 0.0, h, tol) {
            Ok(c) => Ok(c.map(|c| c.time_s)),
            Err(ContactError::Cap(_)) => Err(SilEnd::SearchCap),
            Err(ContactError::NonFinite) => Err(SilEnd::NonFinite),
        }
    }

    /// Whether `b` (on the paddle's plane) is on the blade.
    fn on_blade(&self, pf: &PaddleFrame<f64>, b: &[f64; 3]) -> bool {
        let along = dot(&pf.bar, b);
        let across = dot(&cross(&pf.bar, &pf.normal), b);
        along > 0.0 && along <= self.p.reach_m && across.abs() <= self.p.half_width_m
    }

    /// Fly and move everything by `s`.
    fn flow(&mut self, s: f64) {
        self.ball = self.ball.flown(s, self.p.gravity_mps2);
        self.joints = self.joints.at(&self.accel, s);
        self.t_s += s;
    }

    /// The impact at the current state, if the ball approaches the blade.
    fn bat(&mut self) {
        let pf = self.joints.paddle();
        if !self.on_blade(&pf, &self.ball.position_m) {
            return;
        }
        let Some(v) = pf.bounce(&self.ball, self.p.restitution) else {
            return;
        };
        let before = self.ball;
        self.ball.velocity_mps = v;
        if let Some(mu) = self.p.friction {
            let v_p = pf.velocity_at_mps(&before.position_m);
            let (b, a) = (&before.velocity_mps, &mut self.ball.velocity_mps);
            super::friction::add_friction(mu, &pf.normal, b, &v_p, self.p.restitution, a);
        }
        let g = self.p.gravity_mps2;
        let top = self.ball.flown((self.ball.velocity_mps[2] / g).max(0.0), g);
        let err = (0..3).map(|i| (self.refs[i] - self.joints.q[i]).abs());
        self.worst_error = err.fold(self.worst_error, f64::max);
        let state = |b: &SpatialBall<f64>| {
            let ([x, y, z], [u, v, w]) = (b.position_m, b.velocity_mps);
            [x, y, z, u, v, w]
        };
        (self.on_bat)(&SpatialBat {
            index: self.impacts,
            time_s: self.t_s,
            before: state(&before),
            after: state(&self.ball),
            joints_rad: self.joints.q,
            joint_rates_radps: self.joints.w,
            apex_m: top.position_m,
            energy_jpkg: self.ball.energy_jpkg(g),
        });
        self.impacts += 1;
    }
}

impl SampledPlant<SpatialController> for Plant<'_> {
    type End = SilEnd;
    type Error = ControllerError;

    fn done(&self) -> Option<SilEnd> {
        (self.impacts >= self.want).then_some(SilEnd::Completed)
    }

    fn frame(&mut self, _k: u64, t_k: f64) -> SpatialFrame {
        let ball = self.camera.deliver(t_k, self.ball.position_m);
        let angles = self.encoders.deliver(t_k, self.joints.q);
        let (seq, b) = ball.map_or((0, [f64::NAN; 3]), |s| (s.seq, s.values));
        let q = angles.map_or(self.joints.q, |s| s.values);
        SpatialFrame {
            seq,
            ball_m: b.map(|x| x as f32),
            joints_rad: q.map(|x| x as f32),
            joint_rates_radps: self.joints.w.map(|x| x as f32),
        }
    }

    fn apply(&mut self, _k: u64, _t_k: f64, cmd: &SpatialCommand) {
        let m = self.p.accel_max_radps2;
        self.accel = core::array::from_fn(|i| f64::from(cmd.accel_radps2[i]).clamp(-m[i], m[i]));
        self.refs = cmd.angle_ref_rad.map(f64::from);
    }

    fn advance(&mut self, _k: u64, t_next: f64) -> Result<ControlFlow<SilEnd>, ControllerError> {
        let h = t_next - self.t_s;
        let end = match self.contact_s(h) {
            Ok(Some(s)) => {
                self.flow(s);
                self.bat();
                self.flow(t_next - self.t_s);
                None
            }
            Ok(None) => {
                self.flow(h);
                None
            }
            Err(e) => Some(e),
        };
        self.t_s = t_next;
        let fell = self.ball.position_m[2] < -self.p.reach_m;
        let lost = !self.ball.position_m.iter().all(|x| x.is_finite());
        Ok(match (end, fell, lost) {
            (Some(e), _, _) => ControlFlow::Break(e),
            (_, _, true) => ControlFlow::Break(SilEnd::NonFinite),
            (_, true, _) => ControlFlow::Break(SilEnd::Dropped),
            _ => ControlFlow::Continue(()),
        })
    }
}

/// Steps allowed per requested impact: ten flights of the set point's height, at least.
fn step_cap(plant: &SilPlant, apex_m: f64, impacts: usize) -> u64 {
    let flight = 2.0 * (2.0 * apex_m / plant.gravity_mps2).sqrt();
    (((impacts + 1) as f64 * 10.0 * flight / plant.dt_s).ceil() as u64).max(1000)
}

/// Close the loop through `ctl` for `impacts` bats (at most [`MAX_BATS`]); every bat goes to
/// `on_bat` as it happens.
pub fn run(
    plant: &SilPlant,
    apex_m: f64,
    ctl: &mut dyn StepController<SpatialController>,
    impacts: usize,
    on_bat: &mut dyn FnMut(&SpatialBat),
) -> Result<SilReport, ControllerError> {
    let c = &plant.camera;
    let camera = Sampled::with(
        AtControlSteps::default(),
        Measured::new([c.sigma_m; 3], [0.0; 3], c.seed),
        Latency::new(c.latency_s),
    );
    let r = plant.resolution_rad;
    let encoders = Sampled::with(
        AtControlSteps::default(),
        Measured::new([0.0; 3], [r; 3], 0),
        NoLatency::default(),
    );
    let want = impacts.min(MAX_BATS);
    let mut p = Plant {
        p: *plant,
        ball: plant.ball,
        joints: Joints {
            q: plant.joints_rad,
            w: [0.0; 3],
        },
        accel: [0.0; 3],
        refs: plant.joints_rad,
        t_s: 0.0,
        camera,
        encoders,
        impacts: 0,
        want,
        worst_error: 0.0,
        on_bat,
    };
    let cap = step_cap(plant, apex_m, want);
    let driven = drive(ctl, &mut p, plant.dt_s, cap)?;
    Ok(SilReport {
        end: driven.end.unwrap_or(SilEnd::StepCap),
        safe: driven.safe,
        impacts: p.impacts,
        max_tracking_error_at_impact_rad: p.worst_error,
    })
}

/// The core linked in (SIL) with `params`.
pub fn sil_controller(
    params: <SpatialController as FixedRate>::Params,
) -> Result<Sil<SpatialController>, ControllerError> {
    Sil::<SpatialController>::new(params)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plant(ball: SpatialBall<f64>, joints: [f64; 3]) -> SilPlant {
        SilPlant {
            restitution: 0.7,
            gravity_mps2: 9.81,
            dt_s: 0.001,
            camera: Camera {
                sigma_m: 0.0,
                latency_s: 0.0,
                seed: 1,
            },
            resolution_rad: 0.0,
            accel_max_radps2: [500.0; 3],
            reach_m: 2.0,
            half_width_m: 0.2,
            friction: None,
            ball,
            joints_rad: joints,
        }
    }

    /// Held (no acceleration) at `w` rad/s from `p.joints_rad`: the bats until `t_end`.
    fn held(p: SilPlant, w: [f64; 3], t_end: f64) -> Vec<SpatialBat> {
        let mut bats = Vec::new();
        let mut on_bat = |b: &SpatialBat| bats.push(*b);
        let mut plant = Plant {
            p,
            ball: p.ball,
            joints: Joints { q: p.joints_rad, w },
            accel: [0.0; 3],
            refs: p.joints_rad,
            t_s: 0.0,
            camera: Sampled::with(
                AtControlSteps::default(),
                Measured::new([0.0; 3], [0.0; 3], 1),
                Latency::new(0.0),
            ),
            encoders: Sampled::with(
                AtControlSteps::default(),
                Measured::new([0.0; 3], [0.0; 3], 1),
                NoLatency::default(),
            ),
            impacts: 0,
            want: 10,
            worst_error: 0.0,
            on_bat: &mut on_bat,
        };
        let steps = (t_end / p.dt_s).round() as u64;
        for k in 0..steps {
            let next = (k + 1) as f64 * p.dt_s;
            if plant.advance(k, next).unwrap().is_break() {
                break;
            }
        }
        bats
    }

    /// A ball dropped from 0.3 m onto the paddle held level (q2 = -pi/2, normal up) meets it
    /// at sqrt(2 h / g), inside a control period, and leaves at alpha times its speed.
    #[test]
    fn a_drop_on_the_level_paddle_meets_the_closed_form() {
        let p = plant(
            SpatialBall::new([1.0, 0.1, 0.3], [0.0; 3]),
            [0.1, -core::f64::consts::FRAC_PI_2, 0.0],
        );
        let bats = held(p, [0.0; 3], 0.3);
        assert_eq!(bats.len(), 1);
        let t = (2.0 * 0.3 / 9.81f64).sqrt();
        assert!((bats[0].time_s - t).abs() < 1e-12, "{} {t}", bats[0].time_s);
        assert!(bats[0].before[2].abs() < 1e-12);
        let v = 9.81 * t;
        assert!((bats[0].after[5] - 0.7 * v).abs() < 1e-9);
    }

    /// The paddle swinging up at 1 rad/s about the shoulder meets a falling ball where the
    /// rotating plane's gap is zero (computed here, not by the plant's root), and adds its
    /// own speed at the contact, omega |b|, to the normal velocity: (1 + alpha) of it.
    #[test]
    fn a_swinging_paddle_meets_the_ball_on_its_plane_and_adds_its_speed() {
        let e0 = -0.3;
        let start = SpatialBall::new([1.0, 0.0, 0.2], [0.0; 3]);
        let p = plant(start, [0.0, e0 - core::f64::consts::FRAC_PI_2, 0.0]);
        let bats = held(p, [0.0, 1.0, 0.0], 0.5);
        assert_eq!(bats.len(), 1);
        let b = &bats[0];
        let e = e0 + b.time_s;
        // in the x-z plane the paddle is the line at elevation e: gap = z cos e - x sin e
        let gap = b.before[2] * e.cos() - b.before[0] * e.sin();
        assert!(gap.abs() < 1e-12, "{gap:e}");
        let n = [-e.sin(), 0.0, e.cos()];
        let r = b.before[0].hypot(b.before[2]);
        let un = n[0] * b.before[3] + n[2] * b.before[5] - r; // paddle speed r omega along n
        let after_n = n[0] * b.after[3] + n[2] * b.after[5] - r;
        assert!((after_n + 0.7 * un).abs() < 1e-9, "{after_n} {un}");
    }
}
