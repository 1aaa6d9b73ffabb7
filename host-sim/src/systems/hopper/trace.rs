//! The hopper run's `--trace`: one CSV row per cycle, every start (columns in
//! `docs/hopper.md`; NaN where a time is not computed).

use crate::model::hopper::Cycle;
use crate::output::{Sig17, TraceRow};
use std::io::Write;

/// One cycle of one start.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HopperRow {
    /// The start, 1-based.
    pub trajectory: usize,
    /// The cycle.
    pub cycle: Cycle,
}

impl TraceRow for HopperRow {
    const HEADER: &'static str = "trajectory,cycle,thrust_mps2,touchdown_time_s,touchdown_velocity_mps,touchdown_energy_jpkg,\
bottom_time_s,bottom_height_m,energy,end_of_thrust_time_s,end_of_thrust_height_m,\
end_of_thrust_velocity_mps,liftoff_time_s,liftoff_velocity_before_mps,liftoff_velocity_mps,\
apex_time_s,apex_height_m,next_touchdown_time_s,early_liftoff,dissipating";

    fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let c = &self.cycle;
        write!(
            w,
            "{},{},{},",
            self.trajectory,
            c.index,
            Sig17(c.thrust_mps2)
        )?;
        match c.touchdown {
            Some(td) => write!(w, "{},{},", Sig17(td.time_s), Sig17(td.velocity_mps))?,
            None => write!(w, ",,")?,
        }
        let nums = [
            c.touchdown_energy_jpkg,
            c.bottom.time_s,
            c.bottom_height_m,
            c.energy,
            c.end_of_thrust.time_s,
            c.end_of_thrust.height_m,
            c.end_of_thrust.velocity_mps,
            c.liftoff.time_s,
            c.liftoff_velocity_before_mps,
            c.liftoff.velocity_mps,
            c.apex.time_s,
            c.apex.height_m,
            c.next_touchdown.time_s,
        ];
        for v in nums {
            write!(w, "{},", Sig17(v))?;
        }
        writeln!(w, "{},{}", c.early_liftoff, c.dissipating)
    }
}
