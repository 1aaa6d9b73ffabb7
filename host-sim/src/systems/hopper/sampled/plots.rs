//! The sampled hopper's `--plot` pictures (SVG + PNG), a timeline of the last
//! `hopper.control.timeline_cycles` hops, one point per control step:
//!
//! - `{scene}-timeline-leg`: the true leg compression chi_l - chi (red), the compression in
//!   the frame the controller got (green: noise, quantization, latency) and, in blue, the
//!   true compression while the commanded valve is open (the thrust, broken where it is
//!   closed);
//! - `{scene}-timeline-phase`: the true phase (red: the exactly timed law's, thrust for
//!   delta from the true bottom) and the phase the controller detected (green) as levels 0 flight, 1 compression, 2 thrust, 3 decompression, and the valve
//!   command (blue) as -1 closed, -0.5 open.
//!
//! The timeline is at most `timeline_cycles` hops of control steps (bounded by
//! [`crate::model::hopper::sampled::MAX_TIMELINE_ROWS`]); nothing else is kept.

use super::scene::SampledHopperConfig;
use super::summary::SampledOutcome;
use super::trace::SampledRow;
use super::SampledHopperSystem;
use crate::model::hopper::sampled::TimelineRow;
use crate::plot::Chart;
use crate::system::Failure;
use crate::system::Plots;
use dexter_core::hop::StancePhase;
use std::path::{Path, PathBuf};

/// The valve's palette slot (blue).
const VALVE_SLOT: usize = 3;
/// Valve levels on the phase chart: closed, open.
pub const VALVE_LEVELS: (f64, f64) = (-1.0, -0.5);

/// The level of a phase on the phase chart.
pub fn phase_level(p: StancePhase) -> f64 {
    match p {
        StancePhase::Flight => 0.0,
        StancePhase::Compression => 1.0,
        StancePhase::Thrust => 2.0,
        StancePhase::Decompression => 3.0,
    }
}

/// The sampled hopper's plots: drawn from the outcome's timeline (the rows carry nothing
/// the pictures need).
pub struct SampledPlots;

impl Plots<SampledHopperSystem> for SampledPlots {
    fn new(_: &SampledHopperConfig) -> Self {
        Self
    }

    fn push(&mut self, _: &SampledRow) {}

    fn write(
        self,
        cfg: &SampledHopperConfig,
        out: &SampledOutcome,
        dir: &Path,
    ) -> Result<Vec<PathBuf>, Failure> {
        let rows = &out.run.timeline;
        if rows.is_empty() {
            crate::output::note(
                "warning: the run completed none of the timeline's hops, no timeline plotted",
            );
            return Ok(Vec::new());
        }
        let hops = format!(
            "{} ({} Hz), hops {}..={}",
            cfg.name(),
            cfg.control.rate_hz,
            rows[0].cycle,
            rows[rows.len() - 1].cycle
        );
        let mut written =
            leg_chart(rows, &hops).draw(dir, &format!("{}-timeline-leg", cfg.name()))?;
        written
            .extend(phase_chart(rows, &hops).draw(dir, &format!("{}-timeline-phase", cfg.name()))?);
        Ok(written)
    }
}

fn leg_chart(rows: &[TimelineRow], hops: &str) -> Chart {
    let truth = rows.iter().map(|r| (r.time_s, r.compression_m)).collect();
    let measured = rows
        .iter()
        .map(|r| (r.time_s, r.measured_compression_m))
        .collect();
    let valve = rows
        .iter()
        .map(|r| {
            let c = if r.valve_open {
                r.compression_m
            } else {
                f64::NAN
            };
            (r.time_s, c)
        })
        .collect();
    Chart::new(
        format!("Leg compression, {hops}"),
        "time, s",
        "leg compression chi_l - chi, m",
    )
    .line("true compression", truth)
    .line("measured (the controller's frame)", measured)
    .line_at(VALVE_SLOT, "valve commanded open", valve)
}

/// A step function through `(t, level)` samples held until the next sample.
fn stairs(points: impl Iterator<Item = (f64, f64)>) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (t, y) in points {
        if let Some(&(_, prev)) = out.last() {
            if prev != y {
                out.push((t, prev));
            }
        }
        out.push((t, y));
    }
    out
}

fn phase_chart(rows: &[TimelineRow], hops: &str) -> Chart {
    let truth = stairs(rows.iter().map(|r| (r.time_s, phase_level(r.true_phase))));
    let detected = stairs(
        rows.iter()
            .map(|r| (r.time_s, phase_level(r.detected_phase))),
    );
    let (closed, open) = VALVE_LEVELS;
    let valve = stairs(
        rows.iter()
            .map(|r| (r.time_s, if r.valve_open { open } else { closed })),
    );
    Chart::new(
        format!("Phases (0 flight, 1 compression, 2 thrust, 3 decompression), {hops}"),
        "time, s",
        "phase level; valve -1 closed, -0.5 open",
    )
    .line("true phase", truth)
    .line("detected phase", detected)
    .line_at(VALVE_SLOT, "valve command", valve)
}
