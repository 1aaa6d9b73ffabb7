//! The arm's `--trace`: the verification of the planned motion at the plan's mu, one CSV
//! row every millisecond of simulated time ([`SAMPLE_S`](crate::model::arm::simulate::SAMPLE_S))
//! and one at every event (columns in `docs/arm.md`, "Trace").

use crate::model::arm::simulate::Sample;
use crate::model::arm::task::Phase;
use crate::output::{Sig17, TraceRow};
use std::io::Write;

/// One instant of the verified run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ArmRow(pub Sample);

/// The phase's name in the trace.
pub fn phase_name(p: Phase) -> &'static str {
    match p {
        Phase::Grasp => "grasp",
        Phase::Roll => "roll",
        Phase::Flight => "flight",
    }
}

impl TraceRow for ArmRow {
    const HEADER: &'static str = "t_s,kind,phase,arm_angle_rad,arm_velocity_radps,arm_accel_radps2,com_x_m,com_y_m,object_angle_rad,com_vx_mps,com_vy_mps,object_rate_radps,friction_ratio";

    fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let s = &self.0;
        let (j, b) = (&s.joint, &s.body);
        write!(w, "{},{},{}", Sig17(s.t_s), s.kind, phase_name(s.phase))?;
        let nums = [
            j.angle_rad,
            j.velocity_radps,
            j.accel_radps2,
            b.com.x,
            b.com.y,
            b.angle_rad,
            b.velocity.x,
            b.velocity.y,
            b.angular_velocity_radps,
            s.friction_ratio,
        ];
        for v in nums {
            write!(w, ",{}", Sig17(v))?;
        }
        writeln!(w)
    }
}
