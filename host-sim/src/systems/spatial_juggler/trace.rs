//! The spatial juggler's `--trace`: one CSV row per bat (columns in `docs/spatial.md`).

use crate::model::spatial::SpatialBat;
use crate::output::{Sig17, TraceRow};
use std::io::Write;

/// One bat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpatialRow(pub SpatialBat);

impl TraceRow for SpatialRow {
    const HEADER: &'static str = "index,time_s,x_m,y_m,z_m,x_dot_mps,y_dot_mps,z_dot_mps,x_dot_after_mps,y_dot_after_mps,z_dot_after_mps,q1_rad,q2_rad,q3_rad,q1_dot_radps,q2_dot_radps,q3_dot_radps,apex_x_m,apex_y_m,apex_z_m,energy_jpkg";

    fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let b = &self.0;
        write!(w, "{},{}", b.index, Sig17(b.time_s))?;
        let nums = b
            .before
            .iter()
            .chain(&b.after[3..])
            .chain(&b.joints_rad)
            .chain(&b.joint_rates_radps)
            .chain(&b.apex_m)
            .chain([&b.energy_jpkg]);
        for v in nums {
            write!(w, ",{}", Sig17(*v))?;
        }
        writeln!(w)
    }
}
