//! The line juggler's trace: one row per impact ([`ImpactRow`], the record the physics
//! emits), written as CSV with 17 significant digits.

pub use crate::model::impact::ImpactRow;

use crate::output::{Sig17, TraceRow};
use std::io::Write;

/// The CSV header, in column order.
pub const CSV_HEADER: &str = "index,time_s,ball_height_m,ball_velocity_before_mps,ball_velocity_after_mps,paddle_height_m,paddle_velocity_mps,apex_height_m";

impl TraceRow for ImpactRow {
    const HEADER: &'static str = CSV_HEADER;

    fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{}",
            self.index,
            Sig17(self.time_s),
            Sig17(self.ball_height_m),
            Sig17(self.ball_velocity_before_mps),
            Sig17(self.ball_velocity_after_mps),
            Sig17(self.paddle_height_m),
            Sig17(self.paddle_velocity_mps),
            Sig17(self.apex_height_m)
        )
    }
}

/// Write `rows` as CSV with a header.
pub fn write_csv(rows: &[ImpactRow], mut w: impl Write) -> std::io::Result<()> {
    writeln!(w, "{CSV_HEADER}")?;
    for r in rows {
        r.write_csv(&mut w)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_round_trips_every_bit() {
        let row = ImpactRow {
            index: 3,
            time_s: 0.1 + 0.2,
            ball_height_m: -1e-17,
            ball_velocity_before_mps: -4.429446918621686,
            ball_velocity_after_mps: std::f64::consts::PI,
            paddle_height_m: 0.0,
            paddle_velocity_mps: 1.0 / 3.0,
            apex_height_m: 123456.789,
        };
        let mut buf = Vec::new();
        write_csv(&[row], &mut buf).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some(CSV_HEADER));
        let cols: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(cols.len(), 8);
        assert_eq!(cols[0], "3");
        let back: Vec<f64> = cols[1..].iter().map(|c| c.parse().unwrap()).collect();
        assert_eq!(back[0].to_bits(), (0.1f64 + 0.2).to_bits());
        assert_eq!(back[3], std::f64::consts::PI);
        assert_eq!(back[5], 1.0 / 3.0);
        // 17 significant digits in the mantissa
        assert_eq!(
            cols[4]
                .split('e')
                .next()
                .unwrap()
                .replace(['.', '-'], "")
                .len(),
            17
        );
    }
}
