//! The feeder's `--trace`: one CSV row per simulation step of the execution (columns in
//! `docs/feeder.md`, "Trace").

use crate::model::feeder::execute::StepRecord;
use crate::model::feeder::quasistatic::Mode;
use crate::output::{Sig17, TraceRow};
use std::io::Write;

/// One simulation step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeederRow {
    /// The step as the simulator reported it.
    pub record: StepRecord,
    /// Name of the primitive running (`catch`, `jog`, `turn`, `convergent_turn`).
    pub primitive: &'static str,
}

impl FeederRow {
    /// The row of `record`, during primitive `primitive`.
    pub fn new(record: &StepRecord, primitive: &'static str) -> Self {
        Self {
            record: *record,
            primitive,
        }
    }

    /// The COM's coordinate along the fence, m: the contact radius while an edge is flush.
    pub fn fence_coordinate_m(&self) -> f64 {
        self.record.fence.tangent().dot(self.record.pose.com_m)
    }
}

/// The contact mode's name, snake_case.
pub fn mode_name(m: Mode) -> &'static str {
    match m {
        Mode::Free => "free",
        Mode::PointStick(_) => "point_stick",
        Mode::PointSlide(..) => "point_slide",
        Mode::LineStick(..) => "line_stick",
        Mode::LineSlide(..) => "line_slide",
    }
}

impl TraceRow for FeederRow {
    const HEADER: &'static str = "t_s,step,primitive,mode,fence_angle_rad,fence_rate_radps,com_x_m,com_y_m,part_angle_rad,fence_coordinate_m";

    fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let r = &self.record;
        write!(
            w,
            "{},{},{},{}",
            Sig17(r.t_s),
            r.step,
            self.primitive,
            mode_name(r.mode)
        )?;
        let nums = [
            r.fence.angle_rad,
            r.fence.rate_radps,
            r.pose.com_m.x,
            r.pose.com_m.y,
            r.pose.angle_rad,
            self.fence_coordinate_m(),
        ];
        for v in nums {
            write!(w, ",{}", Sig17(v))?;
        }
        writeln!(w)
    }
}
