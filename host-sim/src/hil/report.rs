//! What a HIL run counts, and the reports built from the counts.

use crate::controller::HilReport;
use dexter_core::fixed_rate::Telemetry;
use std::time::Duration;

/// The link's frame counts, on both ends: what the host sent and predicted (without a
/// decoder, see `inject.rs`), and what the firmware says it accepted and rejected.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkCounts {
    /// Frames the host sent uncorrupted (`Configure`, and sensor frames at rate 0).
    pub host_intact: u64,
    /// Non-empty frames the firmware received that were not what the host encoded (the
    /// ones it must reject).
    pub host_corrupt: u64,
    /// Frames the firmware's decoder accepted (its telemetry, at the last answer).
    pub device_accepted: u64,
    /// Frames the firmware's decoder rejected (its telemetry, at the last answer).
    pub device_rejected: u64,
    /// Corrupt frames the firmware accepted: `host_corrupt - device_rejected` when the
    /// counts disagree (expected 0; a weak CRC or a decoder bug shows here).
    pub corrupted_accepted: u64,
    /// Answers whose firmware counts disagreed with the host's.
    pub count_mismatches: u64,
    /// Steps for which no frame delimiter reached the firmware (the previous command was
    /// held by the plant).
    pub unanswered_steps: u64,
}

/// Counters of a run.
#[derive(Clone, Copy, Debug)]
pub(super) struct Counters {
    pub steps: u64,
    pub outputs: u64,
    pub instructions_sum: u64,
    pub instructions_min: u32,
    pub instructions_max: u32,
    pub sil_mismatches: u64,
    pub over_budget_steps: u64,
    pub link_timeouts: u64,
    pub host_link_errors: u64,
    pub time_in_steps: Duration,
    pub link: LinkCounts,
}

impl Default for Counters {
    fn default() -> Self {
        Self {
            steps: 0,
            outputs: 0,
            instructions_sum: 0,
            instructions_min: u32::MAX,
            instructions_max: 0,
            sil_mismatches: 0,
            over_budget_steps: 0,
            link_timeouts: 0,
            host_link_errors: 0,
            time_in_steps: Duration::ZERO,
            link: LinkCounts::default(),
        }
    }
}

impl Counters {
    /// Record one answer's timing.
    pub(super) fn record_instructions(&mut self, instructions: u32) {
        self.outputs += 1;
        self.instructions_sum += u64::from(instructions);
        self.instructions_min = self.instructions_min.min(instructions);
        self.instructions_max = self.instructions_max.max(instructions);
    }

    /// Compare the firmware's link counts with the host's; true if they agree.
    pub(super) fn record_link_counts(&mut self, telemetry: &Telemetry) -> bool {
        let l = &mut self.link;
        l.device_accepted = u64::from(telemetry.frames_ok);
        l.device_rejected = u64::from(telemetry.link_errors);
        l.corrupted_accepted = l.host_corrupt.saturating_sub(l.device_rejected);
        let agree = l.device_accepted == l.host_intact && l.device_rejected == l.host_corrupt;
        if !agree {
            l.count_mismatches += 1;
        }
        agree
    }

    /// The `--json` figures.
    pub(super) fn report(&self) -> HilReport {
        let secs = self.time_in_steps.as_secs_f64();
        let answered = self.outputs > 0;
        HilReport {
            step_instructions_min: if answered { self.instructions_min } else { 0 },
            step_instructions_mean: if answered {
                self.instructions_sum as f64 / self.outputs as f64
            } else {
                0.0
            },
            step_instructions_max: self.instructions_max,
            sil_mismatches: self.sil_mismatches,
            link_errors: self.link.device_rejected + self.host_link_errors,
            over_budget_steps: self.over_budget_steps,
            link_timeouts: self.link_timeouts,
            steps_per_wall_second: if secs > 0.0 {
                self.steps as f64 / secs
            } else {
                0.0
            },
        }
    }
}
