//! The planar juggler's `--trace`: one CSV row per bat (columns in `docs/planar.md`).

use crate::model::planar::juggler::Bat;
use crate::output::{Sig17, TraceRow};
use std::io::Write;

/// One bat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatRow(pub Bat);

impl TraceRow for BatRow {
    const HEADER: &'static str = "index,time_s,x_m,z_m,x_dot_mps,z_dot_mps,x_dot_after_mps,z_dot_after_mps,bar_angle_rad,bar_rate_radps,apex_x_m,apex_z_m,energy_jpkg";

    fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let b = &self.0;
        let nums = [
            b.time_s,
            b.before[0],
            b.before[1],
            b.before[2],
            b.before[3],
            b.after[2],
            b.after[3],
            b.bar_angle_rad,
            b.bar_rate_radps,
            b.apex[0],
            b.apex[1],
            b.energy_jpkg,
        ];
        write!(w, "{}", b.index)?;
        for v in nums {
            write!(w, ",{}", Sig17(v))?;
        }
        writeln!(w)
    }
}
