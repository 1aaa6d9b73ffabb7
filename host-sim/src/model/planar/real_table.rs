//! The planar body on a real table: tilt and stroke drives with limits, a camera, and the
//! core's fixed-rate [`TiltController`](dexter_core::tilt_control::TiltController) closing the loop through a [`StepController`] (SIL
//! now, the firmware in QEMU for HIL), with events exact between control steps.
//!
//! # The table
//!
//! A line at angle alpha through a pivot at height h. The pivot is carried horizontally
//! under the body's centre of mass (an ideal x stage within its range; the paper's table is
//! an infinite line, and its law lets the body wander horizontally, ±0.8 m on the
//! noise-free sec. 2.3 triangle, tens of metres with noise, which a fixed pivot would have
//! to meet with tan(alpha) x of stroke). The stage's range is finite
//! ([`RealTable::x_range_m`]): the run ends when the centre of mass leaves it, and the
//! controller's horizontal regulation (`TiltParams::kappa_x_pm`) keeps the body inside. The actuated axes are the tilt (alpha) and the vertical stroke
//! (h): each follows its commanded acceleration, held over the control period, within its
//! drive's limits ([`crate::effects::actuator::SecondOrderActuator`]: acceleration clamp,
//! speed limit, hard travel stops; the tilt's in rad), or exactly
//! ([`crate::effects::actuator::IdealActuator`], the "off" effect). The surface at the
//! contact point moves with the pivot, (x', h'), plus alpha' x (r from the pivot).
//!
//! The stroke coordinate h is the line's height under the centre of mass. When an impact
//! changes the body's x' by dx', the pivot follows it and h' changes by tan(alpha) dx'
//! at that instant: the line does not move (it slides along itself, invisible to a
//! frictionless infinite line; its normal velocity is continuous), only the coordinate's
//! rate jumps. It is a kinematic jump of the coordinate, not a drive acceleration, so the
//! drive limits do not apply to it; the controller sees it in the measured h' (its
//! tracking absorbs it; with the tilt small near balance the jump is small).
//!
//! # Exact events between control steps
//!
//! Within a step each axis's motion is a quadratic in time (constant acceleration between
//! the drive's regime switches, which split the step into segments), the body's flight is
//! closed form, and the gap of the contact point above the line along its normal is
//!
//! ```text
//! G(s) = cos(alpha(s)) (y(s) - h(s)) - l cos(theta(s) - alpha(s))
//! ```
//!
//! (x drops out: the pivot is under the centre of mass; alpha, y - h quadratics, theta
//! linear). Its second derivative is bounded on the segment by
//! `(a'^2 + |a''|) |Y| + 2 |a'| |Y'| + |Y''| + l (p'^2 + |a''|)` with the maxima of |Y| = |y - h|,
//! |Y'|, |alpha'| and |phi'| over the segment, so the contact finder of [`super::contact`]
//! (conservative advancement, bracketing, bisection, every loop capped, never misses the
//! first contact) applies unchanged ([`super::contact::first_root`]). The impact is the
//! model's (eq. 21 frictionless, or Coulomb) with the surface velocity at the contact.
//!
//! # The loop
//!
//! Every control period: camera samples due are taken (sample times are plant events), the
//! frame (newest camera pose, the drives' exact angle, height and rates as f32) goes to the
//! controller, its accelerations are applied for the period. The run records every impact,
//! the controller's predicted impact time (its last prediction made after it could have
//! seen the previous impact), the safe steps by fault and the steps by plan status.

use super::camera::{Camera, CameraConfig, PerfectCamera, SampledCamera};
use super::contact::{first_root, Contact, ContactError};
use super::table_run::{RunCounters, StepSample, SummaryBuilder, TableImpact, TableKind, TableRun};
use super::{Body, PlanarError, PlanarModel, PlanarState, RunEnd, TableCommand};
use crate::closed_loop::{drive, SampledPlant};
use crate::controller::{ControllerError, StepController};
use crate::effects::actuator::{Actuator, IdealActuator, SecondOrderActuator};
use dexter_core::fixed_rate::Mode;
use dexter_core::state::PaddleState;
use dexter_core::tilt_control::sincos::SinCos;
use dexter_core::tilt_control::{
    PlanStatus, TiltCommand, TiltControllerWith, TiltFrame, TiltParams,
};
use serde::{Deserialize, Serialize};
use std::ops::ControlFlow;

/// Most plant segments in one control period (each ends at a drive switch, a camera
/// sample, an impact or the period's end).
pub const MAX_SEGMENTS_PER_STEP: usize = 4096;
/// Most impacts in one control period before the run ends as [`RunEnd::NoSeparation`]
/// (the body is resting on the table).
pub const MAX_IMPACTS_PER_STEP: usize = 64;
/// Most step samples a run keeps.
pub const MAX_SAMPLES: usize = 200_000;
/// The tilt-rate damping [`RealTable::realistic`] uses, s (measured in
/// `tests/integration/planar_real_table.rs`: 0.005 to 0.02 s all keep the triangle up with the
/// realistic camera).
pub const REALISTIC_KAPPA_RATE_S: f32 = 0.01;
/// The horizontal regulation [`RealTable::realistic`] uses: kappa_x, rad/m, and kappa_x',
/// s/m (`TiltParams::kappa_x_pm`; measured in `tests/integration/planar_real_table.rs`).
pub const REALISTIC_KAPPA_X: (f32, f32) = (0.002, 0.005);
/// The x range of [`RealTable::realistic`], m: 2 m of stage travel and table (the
/// sec. 2.3 start, theta0 = 0.3 rad, throws the body up to 0.5 m sideways in its first
/// impacts, with or without the regulation; 0.78 m for camera seed 15).
pub const REALISTIC_X_RANGE_M: [f64; 2] = [-1.0, 1.0];

/// One drive's limits, in its own unit u (rad for the tilt, m for the stroke).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveLimits {
    /// Lower travel stop, u.
    pub min: f64,
    /// Upper travel stop, u (> min).
    pub max: f64,
    /// Speed limit, u/s (> 0).
    pub velocity_max: f64,
    /// Acceleration limit, u/s^2 (> 0).
    pub accel_max: f64,
}

impl DriveLimits {
    fn actuator(&self) -> SecondOrderActuator {
        SecondOrderActuator {
            accel_max_mps2: self.accel_max,
            velocity_max_mps: self.velocity_max,
            min_height_m: self.min,
            max_height_m: self.max,
        }
    }

    fn validate(&self, name: &'static str) -> Result<(), PlanarError> {
        let ok = self.min.is_finite()
            && self.max.is_finite()
            && self.max > self.min
            && self.velocity_max.is_finite()
            && self.velocity_max > 0.0
            && self.accel_max.is_finite()
            && self.accel_max > 0.0;
        if ok {
            Ok(())
        } else {
            Err(PlanarError::Relation {
                param: name,
                requirement: "min < max, velocity_max > 0, accel_max > 0, all finite",
            })
        }
    }
}

/// The real table: the controller's parameters, the drives, the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RealTable {
    /// What the controller (SIL or HIL) is configured with; its `dt_s` is the control
    /// period of the loop.
    pub controller: TiltParams,
    /// The tilt drive (rad); `None`: ideal, any acceleration.
    pub tilt: Option<DriveLimits>,
    /// The stroke drive (m); `None`: ideal.
    pub stroke: Option<DriveLimits>,
    /// The camera; `None`: the true pose every step without latency (the controller's
    /// `estimator.latency_s` should then be 0).
    pub camera: Option<CameraConfig>,
    /// Table angle at t = 0, rad (at rest).
    pub initial_tilt_rad: f64,
    /// Pivot height at t = 0, m (at rest).
    pub initial_height_m: f64,
    /// The run ends ([`RunEnd::TimeLimit`]) after this simulated time, s.
    pub max_duration_s: f64,
    /// The x range (lowest, highest) over which the table can be under the body's centre
    /// of mass, m: its x stage's travel plus the table's half length. The run ends
    /// ([`RunEnd::OutOfTravel`]) at the first control step that finds the centre of mass
    /// outside it. Within it the stage is ideal (module docs: the pivot's place along a
    /// frictionless line does not change the impacts, so the stage's speed and
    /// acceleration limits do not enter while the table is under the body).
    pub x_range_m: [f64; 2],
}

impl RealTable {
    /// The sec. 2.3 triangle on a realistic table: the controller's defaults
    /// ([`TiltParams::default`]: 500 Hz, 4 ms camera latency) with the tilt-rate damping
    /// `kappa_rate_s` = [`REALISTIC_KAPPA_RATE_S`] (the paper's law alone does not survive
    /// this camera's 5 mrad, see [`TiltParams::kappa_rate_s`]), drives with the same limits
    /// as the controller plans with, the [`CameraConfig::realistic`] camera with `seed`.
    pub fn realistic(seed: u64) -> Self {
        let c = TiltParams {
            kappa_rate_s: REALISTIC_KAPPA_RATE_S,
            kappa_x_pm: REALISTIC_KAPPA_X.0,
            kappa_xdot_spm: REALISTIC_KAPPA_X.1,
            ..TiltParams::default()
        };
        Self {
            controller: c,
            tilt: Some(DriveLimits {
                min: f64::from(c.tilt.min_rad),
                max: f64::from(c.tilt.max_rad),
                velocity_max: f64::from(c.tilt.rate_max_radps),
                accel_max: f64::from(c.tilt.accel_max_radps2),
            }),
            stroke: Some(DriveLimits {
                min: f64::from(c.stroke.min_m),
                max: f64::from(c.stroke.max_m),
                velocity_max: f64::from(c.stroke.velocity_max_mps),
                accel_max: f64::from(c.stroke.accel_max_mps2),
            }),
            camera: Some(CameraConfig::realistic(seed)),
            initial_tilt_rad: 0.0,
            initial_height_m: 0.0,
            max_duration_s: 600.0,
            x_range_m: REALISTIC_X_RANGE_M,
        }
    }

    /// Check the table against `model` (a rigid body; the controller's parameters valid;
    /// drives, camera and start sane). The error names the offending part.
    pub fn validate(&self, model: &PlanarModel) -> Result<(), PlanarError> {
        if !matches!(model.body, Body::Rigid { .. }) {
            return Err(PlanarError::Relation {
                param: "planar.body",
                requirement: "body = \"rigid\" (the tilt controller balances a rigid body)",
            });
        }
        self.controller.validate()?;
        if let Some(d) = &self.tilt {
            d.validate("real_table.tilt")?;
        }
        if let Some(d) = &self.stroke {
            d.validate("real_table.stroke")?;
        }
        if let Some(c) = &self.camera {
            let ok = c.rate_hz.is_finite()
                && c.rate_hz > 0.0
                && [
                    c.noise_m,
                    c.noise_rad,
                    c.latency_s,
                    c.quantization_m,
                    c.quantization_rad,
                ]
                .iter()
                .all(|v| v.is_finite() && *v >= 0.0);
            if !ok {
                return Err(PlanarError::Relation {
                    param: "real_table.camera",
                    requirement: "rate_hz > 0 and noise, latency, quantization finite and >= 0",
                });
            }
        }
        let [x_lo, x_hi] = self.x_range_m;
        if !(x_lo <= 0.0 && x_hi >= 0.0 && x_lo < x_hi) {
            return Err(PlanarError::Relation {
                param: "real_table.stage",
                requirement: "min_m <= 0 <= max_m, min_m < max_m",
            });
        }
        let sane = self.initial_tilt_rad.is_finite()
            && self.initial_height_m.is_finite()
            && self.max_duration_s.is_finite()
            && self.max_duration_s > 0.0;
        if !sane {
            return Err(PlanarError::Relation {
                param: "real_table",
                requirement: "initial_tilt_rad, initial_height_m finite, max_duration_s > 0",
            });
        }
        Ok(())
    }
}

/// What to run: the model (body, contact law, gravity, tip angle; its tilt law and energy
/// feedback are the ideal table's, and its eta* is the reference of `late_energy_error`),
/// the start, the impacts, and time windows (s) in which to keep step samples.
#[derive(Clone, Debug, PartialEq)]
pub struct TableRunConfig {
    /// The model.
    pub model: PlanarModel,
    /// The body at t = 0 (in flight, contact point above the table).
    pub start: PlanarState,
    /// Impacts to simulate.
    pub impacts: usize,
    /// Windows [from, to] (s) in which every control step is sampled (at most
    /// [`MAX_SAMPLES`] in all).
    pub record: Vec<(f64, f64)>,
}

/// What a streamed run ([`stream_real_table`]) hands out as it goes.
pub trait TableSink {
    /// Every impact, as it happens.
    fn impact(&mut self, r: &TableImpact);
    /// The plant at every control step (before the step's command is applied).
    fn step(&mut self, s: &StepSample) {
        let _ = s;
    }
}

/// Collecting every impact (what [`run_real_table`] does).
impl TableSink for Vec<TableImpact> {
    fn impact(&mut self, r: &TableImpact) {
        self.push(*r);
    }
}

/// Run the real table with the controller `ctrl` (configured with `table.controller`; any
/// sine/cosine source `T`, the shipped [`TiltController`](dexter_core::tilt_control::TiltController)
/// in SIL and HIL); the effects
/// switched off in `table` cost nothing (the loop is compiled per combination). `Err` only
/// if the controller fails (a link error in HIL); everything the plant does ends the run
/// with a [`RunEnd`]. The result holds every impact ([`stream_real_table`] keeps none).
pub fn run_real_table<T: SinCos>(
    cfg: &TableRunConfig,
    table: &RealTable,
    ctrl: &mut dyn StepController<TiltControllerWith<T>>,
) -> Result<TableRun, ControllerError> {
    let mut impacts = Vec::with_capacity(cfg.impacts.min(1 << 16));
    let mut run = stream_real_table(cfg, table, ctrl, &mut impacts)?;
    run.impacts = impacts;
    Ok(run)
}

/// [`run_real_table`] in constant memory: each impact and each control step goes to `sink`
/// as it happens, the summary is built on the way ([`SummaryBuilder`]), and the result's
/// `impacts` is empty (its `samples` still holds the steps in `cfg.record`).
pub fn stream_real_table<T: SinCos>(
    cfg: &TableRunConfig,
    table: &RealTable,
    ctrl: &mut dyn StepController<TiltControllerWith<T>>,
    sink: &mut dyn TableSink,
) -> Result<TableRun, ControllerError> {
    match table.camera {
        None => with_tilt(cfg, table, ctrl, PerfectCamera::default(), sink),
        Some(c) => with_tilt(cfg, table, ctrl, SampledCamera::new(c), sink),
    }
}

fn with_tilt<T: SinCos, C: Camera>(
    cfg: &TableRunConfig,
    table: &RealTable,
    ctrl: &mut dyn StepController<TiltControllerWith<T>>,
    camera: C,
    sink: &mut dyn TableSink,
) -> Result<TableRun, ControllerError> {
    match table.tilt {
        None => with_stroke(cfg, table, ctrl, (camera, IdealActuator), sink),
        Some(d) => with_stroke(cfg, table, ctrl, (camera, d.actuator()), sink),
    }
}

fn with_stroke<T: SinCos, C: Camera, A: Actuator>(
    cfg: &TableRunConfig,
    table: &RealTable,
    ctrl: &mut dyn StepController<TiltControllerWith<T>>,
    (camera, tilt): (C, A),
    sink: &mut dyn TableSink,
) -> Result<TableRun, ControllerError> {
    match table.stroke {
        None => Loop::new(cfg, table, camera, (tilt, IdealActuator), sink).run(ctrl),
        Some(d) => Loop::new(cfg, table, camera, (tilt, d.actuator()), sink).run(ctrl),
    }
}

/// The gap of the contact point above the table line along its normal over one segment
/// (module docs), m, with s in s from the segment's start:
/// `G(s) = cos(alpha(s)) Y(s) - l cos(theta(s) - alpha(s))`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TableGap {
    /// Y = y - h (centre of mass above the pivot): constant (m), linear (m/s), quadratic
    /// (m/s^2) coefficient.
    pub y: [f64; 3],
    /// alpha: constant (rad), linear (rad/s), quadratic (rad/s^2) coefficient.
    pub a: [f64; 3],
    /// theta: value (rad), rate (rad/s).
    pub th: [f64; 2],
    /// Contact distance l, m.
    pub l: f64,
}

impl TableGap {
    /// (G(s), G'(s)), m and m/s.
    #[inline]
    pub fn value_rate(&self, s: f64) -> (f64, f64) {
        let [y0, y1, y2] = self.y;
        let [a0, a1, a2] = self.a;
        let alpha = a0 + s * (a1 + s * a2);
        let ad = a1 + 2.0 * a2 * s;
        let yy = y0 + s * (y1 + s * y2);
        let yd = y1 + 2.0 * y2 * s;
        let phi = self.th[0] + self.th[1] * s - alpha;
        let (sa, ca) = alpha.sin_cos();
        let (sp, cp) = phi.sin_cos();
        (
            ca * yy - self.l * cp,
            -sa * ad * yy + ca * yd + self.l * sp * (self.th[1] - ad),
        )
    }

    /// A with G'' >= -A on [0, h] (module docs), m/s^2.
    pub fn curvature_bound(&self, h: f64) -> f64 {
        let [y0, y1, y2] = self.y;
        let [_, a1, a2] = self.a;
        let y_max = y0.abs() + y1.abs() * h + y2.abs() * h * h;
        let yd_max = y1.abs() + 2.0 * y2.abs() * h;
        let ad_max = a1.abs() + 2.0 * a2.abs() * h;
        let add = 2.0 * a2.abs();
        let pd_max = self.th[1].abs() + ad_max;
        (ad_max * ad_max + add) * y_max
            + 2.0 * ad_max * yd_max
            + 2.0 * y2.abs()
            + self.l * (pd_max * pd_max + add)
    }

    fn tolerance(&self, h: f64) -> f64 {
        let [y0, y1, y2] = self.y;
        64.0 * f64::EPSILON * (y0.abs() + y1.abs() * h + y2.abs() * h * h + self.l)
    }

    /// The first contact in [0, h] (s), by [`super::contact::first_root`]: never missed, every
    /// loop capped (a cap is an error).
    pub fn first_contact(&self, h: f64) -> Result<Option<Contact>, ContactError> {
        first_root(
            |s| self.value_rate(s),
            self.curvature_bound(h),
            0.0,
            h,
            self.tolerance(h),
        )
    }
}

/// The plant: body, drives, time.
struct Plant<A, B> {
    model: PlanarModel,
    l: f64,
    g: f64,
    time_s: f64,
    body: PlanarState,
    tilt: PaddleState<f64>,
    stroke: PaddleState<f64>,
    tilt_drive: A,
    stroke_drive: B,
    /// Commanded accelerations (rad/s^2, m/s^2).
    command: [f64; 2],
}

impl<A: Actuator, B: Actuator> Plant<A, B> {
    fn pose(&self) -> [f64; 3] {
        [self.body.x_m, self.body.y_m, self.body.theta_rad]
    }

    /// Move everything by `s` seconds with the axes' accelerations `acc`.
    fn advance(&mut self, s: f64, acc: [f64; 2]) {
        self.body = self.body.flown(s, self.g);
        for (axis, a) in [&mut self.tilt, &mut self.stroke].into_iter().zip(acc) {
            axis.height_m += (axis.velocity_mps + 0.5 * a * s) * s;
            axis.velocity_mps += a * s;
        }
        self.time_s += s;
    }

    /// The impact at the current state; `Err` ends the run.
    fn impact(&mut self, index: usize) -> Result<TableImpact, RunEnd> {
        let before = self.body;
        if !(before.theta_rad.is_finite() && before.y_dot_mps.is_finite()) {
            return Err(RunEnd::NonFinite);
        }
        if before.theta_rad.abs() >= self.model.tip_angle_rad {
            return Err(RunEnd::TippedOver);
        }
        let alpha = self.tilt.height_m;
        let omega = self.tilt.velocity_mps;
        let [xc, yc] = before.contact_point(self.l);
        // the surface point at the contact: pivot (x, h) moving with (x', h'), plus rotation
        let r = [xc - before.x_m, yc - self.stroke.height_m];
        let v_surface = [
            before.x_dot_mps - omega * r[1],
            self.stroke.velocity_mps + omega * r[0],
        ];
        let cmd = TableCommand {
            alpha_rad: alpha,
            velocity_mps: v_surface,
        };
        let (after, _) = self.model.collide(&before, &cmd).map_err(|e| match e {
            super::impact::ImpactError::Jam => RunEnd::Jam,
            super::impact::ImpactError::Cap => RunEnd::NonFinite,
        })?;
        // the contact point must leave the table
        let vc = after.body_state().contact_velocity(self.l);
        let (sa, ca) = alpha.sin_cos();
        let rel = -sa * (vc[0] - v_surface[0]) + ca * (vc[1] - v_surface[1]);
        if rel.is_nan() || rel <= 0.0 {
            return Err(RunEnd::NoSeparation);
        }
        self.body = after;
        // the pivot stays under the centre of mass: its horizontal velocity follows the
        // body's new x', and the line's height under the body changes at tan(alpha) x'
        // more; the line itself does not move (it slides along itself, which a
        // frictionless infinite line does not feel)
        self.stroke.velocity_mps += sa / ca * (after.x_dot_mps - before.x_dot_mps);
        let v_after = [
            after.x_dot_mps - omega * r[1],
            self.stroke.velocity_mps + omega * r[0],
        ];
        Ok(TableImpact {
            index,
            time_s: self.time_s,
            before,
            after,
            table_angle_rad: alpha,
            table_velocity_mps: v_surface,
            table_velocity_after_mps: v_after,
            table_rate_radps: omega,
            contact_height_m: yc,
            energy_jpkg: self.model.feedback.energy_jpkg(&before.body_state()),
            predicted_time_s: None,
            grazing: false,
        })
    }

    /// Advance to `t_end_s`, calling `on_impact` for each impact (at most `max_impacts`).
    fn advance_to(
        &mut self,
        t_end_s: f64,
        next_index: usize,
        max_impacts: usize,
        on_impact: &mut impl FnMut(TableImpact),
    ) -> Result<(), RunEnd> {
        let mut index = next_index;
        let mut in_step = 0usize;
        for _ in 0..MAX_SEGMENTS_PER_STEP {
            let window = t_end_s - self.time_s;
            if window <= 0.0 {
                return Ok(());
            }
            let acc = [
                self.tilt_drive.accel(&self.tilt, self.command[0]),
                self.stroke_drive.accel(&self.stroke, self.command[1]),
            ];
            let switch = self
                .tilt_drive
                .time_to_switch(&self.tilt, acc[0])
                .min(self.stroke_drive.time_to_switch(&self.stroke, acc[1]));
            let (h, hits_switch) = if switch < window {
                (switch, true)
            } else {
                (window, false)
            };
            let gap = TableGap {
                y: [
                    self.body.y_m - self.stroke.height_m,
                    self.body.y_dot_mps - self.stroke.velocity_mps,
                    -0.5 * (self.g + acc[1]),
                ],
                a: [self.tilt.height_m, self.tilt.velocity_mps, 0.5 * acc[0]],
                th: [self.body.theta_rad, self.body.theta_dot_radps],
                l: self.l,
            };
            let found = gap.first_contact(h).map_err(|e| match e {
                ContactError::NonFinite => RunEnd::NonFinite,
                ContactError::Cap(_) => RunEnd::SearchCap,
            })?;
            match found {
                Some(c) if c.time_s <= h => {
                    self.advance(c.time_s, acc);
                    let mut rec = self.impact(index)?;
                    rec.grazing = c.grazing;
                    on_impact(rec);
                    index += 1;
                    in_step += 1;
                    if index >= max_impacts {
                        return Ok(());
                    }
                    if in_step >= MAX_IMPACTS_PER_STEP {
                        return Err(RunEnd::NoSeparation);
                    }
                }
                _ => {
                    if hits_switch {
                        self.advance(h, acc);
                        self.tilt_drive.settle(&mut self.tilt);
                        self.stroke_drive.settle(&mut self.stroke);
                    } else {
                        let s = t_end_s - self.time_s;
                        self.advance(s, acc);
                        self.time_s = t_end_s;
                    }
                }
            }
        }
        Err(RunEnd::NoContact)
    }
}

/// The stepped run: plant, camera, records.
struct Loop<'a, C, A, B> {
    cfg: &'a TableRunConfig,
    table: &'a RealTable,
    plant: Plant<A, B>,
    camera: C,
    sink: &'a mut dyn TableSink,
    summary: SummaryBuilder,
    /// Time of the latest impact, s.
    last_impact_s: Option<f64>,
    samples: Vec<StepSample>,
    counters: RunCounters,
    /// The controller's latest prediction of the next impact's time, s.
    prediction: Option<f64>,
    /// The control period, s.
    dt: f64,
}

impl<'a, C: Camera, A: Actuator, B: Actuator> Loop<'a, C, A, B> {
    fn new(
        cfg: &'a TableRunConfig,
        table: &'a RealTable,
        camera: C,
        (tilt, stroke): (A, B),
        sink: &'a mut dyn TableSink,
    ) -> Self {
        let plant = Plant {
            model: cfg.model,
            l: cfg.model.l_m(),
            g: cfg.model.gravity_mps2,
            time_s: 0.0,
            body: cfg.start,
            tilt: PaddleState::new(table.initial_tilt_rad, 0.0),
            stroke: PaddleState::new(table.initial_height_m, 0.0),
            tilt_drive: tilt,
            stroke_drive: stroke,
            command: [0.0, 0.0],
        };
        Self {
            cfg,
            table,
            plant,
            camera,
            sink,
            summary: SummaryBuilder::new(cfg.impacts),
            last_impact_s: None,
            samples: Vec::new(),
            counters: RunCounters::default(),
            prediction: None,
            dt: f64::from(table.controller.dt_s),
        }
    }

    fn run<T: SinCos>(
        mut self,
        ctrl: &mut dyn StepController<TiltControllerWith<T>>,
    ) -> Result<TableRun, ControllerError> {
        let max_steps = (self.table.max_duration_s / self.dt).ceil() as u64;
        let dt = self.dt;
        let driven = drive(ctrl, &mut self, dt, max_steps)?;
        let end = match driven.end {
            Some(e) => e,
            None if self.summary.impacts() >= self.cfg.impacts => RunEnd::Completed,
            None => RunEnd::TimeLimit,
        };
        self.counters.sim_time_s = self.plant.time_s;
        self.counters.control_steps = driven.safe.steps;
        self.counters.safe = driven.safe;
        let summary = self
            .summary
            .finish(TableKind::Real, &self.cfg.model, end, &self.counters);
        Ok(TableRun {
            summary,
            impacts: Vec::new(),
            samples: self.samples,
        })
    }

    /// Camera samples due by now (at the exact pose: sample times are segment ends).
    fn take_samples(&mut self, t_s: f64) {
        for _ in 0..1024 {
            if self.camera.next_sample_time_s() > t_s + 1e-12 {
                break;
            }
            self.camera.sample(self.plant.time_s, self.plant.pose());
        }
    }

    /// Count the command's plan; keep its impact prediction once the controller can have
    /// seen the last impact (camera latency plus two periods after it).
    fn account(&mut self, cmd: &TiltCommand, t_k: f64) {
        let dt = self.dt;
        let p = &mut self.counters.plan_steps;
        match cmd.plan {
            PlanStatus::Idle => p.idle += 1,
            PlanStatus::Planned => p.planned += 1,
            PlanStatus::Committed => p.committed += 1,
            PlanStatus::Limited => p.limited += 1,
            PlanStatus::Unreachable => p.unreachable += 1,
            PlanStatus::Ambiguous => p.ambiguous += 1,
        }
        let planning = cmd.mode == Mode::Track
            && !matches!(cmd.plan, PlanStatus::Idle | PlanStatus::Unreachable);
        let seen_last = self.last_impact_s.unwrap_or(0.0) + self.camera.latency_s() + 2.0 * dt;
        if planning && t_k > seen_last {
            self.prediction = Some(t_k + f64::from(cmd.impact_in_s));
        }
    }

    fn record(&mut self, t_k: f64) {
        let p = &self.plant;
        let sample = StepSample {
            time_s: t_k,
            body: p.pose(),
            table_angle_rad: p.tilt.height_m,
            table_height_m: p.stroke.height_m,
        };
        self.sink.step(&sample);
        let wanted = self.cfg.record.iter().any(|&(a, b)| t_k >= a && t_k <= b);
        if wanted && self.samples.len() < MAX_SAMPLES {
            self.samples.push(sample);
        }
    }

    /// Advance the plant to `t_next`, stopping at camera sample times to take them.
    fn advance_step(&mut self, t_next: f64) -> Result<(), RunEnd> {
        for _ in 0..MAX_SEGMENTS_PER_STEP {
            let ts = self.camera.next_sample_time_s();
            if ts <= self.plant.time_s {
                self.camera.sample(self.plant.time_s, self.plant.pose());
                continue;
            }
            let target = ts.min(t_next);
            let index = self.summary.impacts();
            let prediction = &mut self.prediction;
            let (summary, sink, last) =
                (&mut self.summary, &mut *self.sink, &mut self.last_impact_s);
            self.plant
                .advance_to(target, index, self.cfg.impacts, &mut |mut rec| {
                    rec.predicted_time_s = prediction.take();
                    summary.push(&rec);
                    sink.impact(&rec);
                    *last = Some(rec.time_s);
                })?;
            if self.summary.impacts() >= self.cfg.impacts || self.plant.time_s >= t_next {
                return Ok(());
            }
        }
        Err(RunEnd::NoContact)
    }
}

impl<T: SinCos, C: Camera, A: Actuator, B: Actuator> SampledPlant<TiltControllerWith<T>>
    for Loop<'_, C, A, B>
{
    type End = RunEnd;
    type Error = ControllerError;

    fn done(&self) -> Option<RunEnd> {
        (self.summary.impacts() >= self.cfg.impacts).then_some(RunEnd::Completed)
    }

    fn frame(&mut self, k: u64, t_k: f64) -> TiltFrame {
        self.take_samples(t_k);
        let p = &self.plant;
        let (seq, z) = self.camera.frame(k, t_k, p.pose());
        TiltFrame {
            seq,
            body_x_m: z[0],
            body_y_m: z[1],
            body_theta_rad: z[2],
            table_angle_rad: p.tilt.height_m as f32,
            table_rate_radps: p.tilt.velocity_mps as f32,
            table_height_m: p.stroke.height_m as f32,
            table_velocity_mps: p.stroke.velocity_mps as f32,
        }
    }

    fn apply(&mut self, _k: u64, t_k: f64, command: &TiltCommand) {
        self.account(command, t_k);
        self.record(t_k);
        self.plant.command = [
            f64::from(command.tilt_accel_radps2),
            f64::from(command.stroke_accel_mps2),
        ];
    }

    fn advance(&mut self, _k: u64, t_next: f64) -> Result<ControlFlow<RunEnd>, ControllerError> {
        let [lo, hi] = self.table.x_range_m;
        Ok(match self.advance_step(t_next) {
            Ok(()) if !(lo..=hi).contains(&self.plant.body.x_m) => {
                ControlFlow::Break(RunEnd::OutOfTravel)
            }
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => ControlFlow::Break(e),
        })
    }
}

/// The controller's parameters for `model` on the real table `base`: the body, gravity,
/// restitution and laws (kappa, kappa_E, eta*) from the model, the rest from `base`
/// (`base.estimator.latency_s` is set from the camera, 0 without one). Errors name the key.
pub fn controller_params_for(
    model: &PlanarModel,
    base: &TiltParams,
    camera: Option<&CameraConfig>,
) -> Result<TiltParams, PlanarError> {
    let Body::Rigid { rho_m, l_m } = model.body else {
        return Err(PlanarError::Relation {
            param: "planar.body",
            requirement: "body = \"rigid\" (the tilt controller balances a rigid body)",
        });
    };
    let fb = &model.feedback;
    let mut p = *base;
    p.gravity_mps2 = model.gravity_mps2 as f32;
    p.rho_m = rho_m as f32;
    p.l_m = l_m as f32;
    p.restitution = fb.e() as f32;
    p.kappa = model.tilt.kappa() as f32;
    p.kappa_e_s2pm2 = fb.kappa_e_s2pm2() as f32;
    p.target_apex_m = fb.target_apex_m() as f32;
    p.estimator.latency_s = camera.map_or(0.0, |c| c.latency_s as f32);
    p.validate()?;
    Ok(p)
}
