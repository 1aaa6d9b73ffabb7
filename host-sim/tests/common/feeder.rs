//! The 1JOC feeder cell the feeder tests share.

use dexter_sim::model::feeder::part::Part;
use dexter_sim::model::feeder::planner::Feeder;
use dexter_sim::model::feeder::primitives::Drive;
use dexter_sim::model::feeder::quasistatic::Medium;
use dexter_sim::model::feeder::sim::Setup;

/// A 3 m fence over a 6 m belt at 5 cm/s (issue 16's "wide enough belt"), fence friction
/// `mu`, the jog tilt 15 degrees past the friction angle.
pub fn cell(part: Part, mu: f64) -> Feeder {
    Feeder {
        part,
        setup: Setup {
            medium: Medium {
                belt_speed_mps: 0.05,
                fence_mu: mu,
            },
            fence_length_m: 3.0,
            belt_edge_m: 3.0,
        },
        drive: Drive {
            push_rate_radps: 2.0,
            max_rate_radps: 6.0,
            max_angle_rad: 80f64.to_radians(),
            jog_tilt_rad: (mu.atan() + 15f64.to_radians()).min(80f64.to_radians()),
        },
    }
}

/// The keys issue 16 asks `dexter run --json` of a feeder scene to print.
pub const SUMMARY_KEYS: [&str; 7] = [
    "goal_edge",
    "plan",
    "plan_time_s",
    "reached_goal",
    "final_edge",
    "final_contact_radius_m",
    "radius_error_m",
];
