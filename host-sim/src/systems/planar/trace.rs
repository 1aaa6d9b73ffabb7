//! The planar run's `--trace`: one CSV row per impact (columns in `docs/planar.md`).

use crate::model::planar::ImpactRecord;
use crate::output::{Sig17, TraceRow};
use std::io::Write;

/// One impact and the body's contact distance l, m (for the contact point's height).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanarRow {
    /// The impact.
    pub record: ImpactRecord,
    /// l, m (0 for a point mass).
    pub l_m: f64,
}

/// The tangential regime's name, as in the JSON (`frictionless`, `sliding`, ...).
fn mode_name(r: &ImpactRecord) -> String {
    serde_json::to_value(r.mode)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}

impl TraceRow for PlanarRow {
    const HEADER: &'static str = "index,time_s,x_m,y_m,theta_rad,x_dot_mps,y_dot_mps,theta_dot_radps,x_dot_after_mps,y_dot_after_mps,theta_dot_after_radps,contact_y_m,table_angle_rad,table_vx_mps,table_vy_mps,energy_jpkg,grazing,mode";

    fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let r = &self.record;
        let (b, a) = (&r.before, &r.after);
        let nums = [
            r.time_s,
            b.x_m,
            b.y_m,
            b.theta_rad,
            b.x_dot_mps,
            b.y_dot_mps,
            b.theta_dot_radps,
            a.x_dot_mps,
            a.y_dot_mps,
            a.theta_dot_radps,
            b.contact_point(self.l_m)[1],
            r.table.alpha_rad,
            r.table.velocity_mps[0],
            r.table.velocity_mps[1],
            r.energy_jpkg,
        ];
        write!(w, "{}", r.index)?;
        for v in nums {
            write!(w, ",{}", Sig17(v))?;
        }
        writeln!(w, ",{},{}", u8::from(r.grazing), mode_name(r))
    }
}
