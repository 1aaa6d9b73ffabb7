//! The sampled hopper's `--trace`: one CSV row per hop (touchdown to touchdown), the true
//! events beside the controller's detections and valve times (columns in `docs/hopper.md`;
//! NaN where a cycle had no such event).

use crate::model::hopper::sampled::SampledCycle;
use crate::output::{Sig17, TraceRow};
use std::io::Write;

/// One hop of a sampled run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledRow(pub SampledCycle);

impl TraceRow for SampledRow {
    const HEADER: &'static str = "cycle,touchdown_time_s,touchdown_velocity_mps,bottom_time_s,\
bottom_height_m,valve_open_time_s,valve_close_time_s,thrust_mps2,liftoff_time_s,\
liftoff_velocity_mps,apex_time_s,apex_height_m,next_touchdown_time_s,detected_touchdown_s,\
detected_bottom_s,detected_liftoff_s,early_liftoff";

    fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let c = &self.0;
        write!(w, "{},", c.index)?;
        for v in [
            c.touchdown_time_s,
            c.touchdown_velocity_mps,
            c.bottom_time_s,
            c.bottom_height_m,
            c.valve_open_time_s,
            c.valve_close_time_s,
            c.thrust_mps2,
            c.liftoff_time_s,
            c.liftoff_velocity_mps,
            c.apex_time_s,
            c.apex_height_m,
            c.next_touchdown_time_s,
            c.detected_touchdown_s,
            c.detected_bottom_s,
            c.detected_liftoff_s,
        ] {
            write!(w, "{},", Sig17(v))?;
        }
        writeln!(w, "{}", c.early_liftoff)
    }
}
