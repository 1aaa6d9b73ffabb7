//! What the juggling loop reports once a second (defmt over RTT): the period's counts and
//! cycle figures, the controller's mode and estimate, the rig's sensor counts.

use crate::rig::BoardRig;
use crate::CONTROL_RATE_HZ;
use dexter_core::control::Controller;
use dexter_core::fixed_rate::FixedRate;
use dexter_core::fixed_rate::{Fault, Mode};
use dexter_core::protocol::ActuatorCommand;
use dexter_drivers::actuator::Drive;
use dexter_drivers::camera::CameraStats;
use dexter_rig::periodic::{PeriodOutcome, PeriodStats, Periodic};

/// A snapshot of the loop, copied out of the period's task.
#[derive(Clone, Copy, Default)]
pub struct Report {
    stats: PeriodStats,
    period_cycles: u32,
    mode: Mode,
    fault: Fault,
    estimate: [f32; 2],
    estimate_valid: bool,
    paddle_height_m: f32,
    drive: Option<Drive>,
    camera: CameraStats,
    host_link_errors: u32,
}

impl Report {
    /// The snapshot after a period.
    pub fn new(
        periodic: &Periodic<Controller>,
        rig: &BoardRig,
        out: &PeriodOutcome<ActuatorCommand>,
        host_link_errors: u32,
    ) -> Self {
        let t = periodic.controller().telemetry();
        let [h, v, _] = t.estimate;
        Self {
            stats: periodic.stats(),
            period_cycles: periodic.period_cycles(),
            mode: out.command.mode,
            fault: out.command.fault,
            estimate: [h, v],
            estimate_valid: t.estimate_valid,
            paddle_height_m: rig.paddle().height_m,
            drive: rig.last_drive(),
            camera: rig.camera_stats(),
            host_link_errors,
        }
    }

    /// Log the snapshot (three lines).
    pub fn log(&self) {
        let s = &self.stats;
        let mean = s.step_cycles_sum / u64::from(s.periods.max(1));
        defmt::info!(
            "t={=u32} s: mode {} fault {}; ball {=f32} m {=f32} m/s (valid {=bool}); paddle {=f32} m, drive {}",
            s.periods / CONTROL_RATE_HZ,
            self.mode,
            self.fault,
            self.estimate[0],
            self.estimate[1],
            self.estimate_valid,
            self.paddle_height_m,
            self.drive
        );
        defmt::info!(
            "step cycles min {=u32} mean {=u64} max {=u32}; period work max {=u32} of {=u32}; overruns {=u32} (ticks lost {=u32}); safe periods {=u32}; drive errors {=u32}",
            s.step_cycles_min,
            mean,
            s.step_cycles_max,
            s.work_cycles_max,
            self.period_cycles,
            s.overruns,
            s.ticks_lost,
            s.safe_periods,
            s.drive_errors
        );
        let stack = dexter_firmware::stack::usage();
        defmt::info!(
            "camera {}; host link UART errors {=u32}; stack high-water {=u32} of {=u32} B",
            self.camera,
            self.host_link_errors,
            stack.used_bytes,
            stack.size_bytes
        );
    }
}
