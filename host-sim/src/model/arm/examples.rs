//! The four shipped tasks as scene text (the intended `scenes/arm-*.toml`): tests,
//! benches and the CLI read the same text.
//!
//! - [`SNATCH`]: lift a 10 cm square off a table on the link (flush at 0 rad) to rest at
//!   0.3 rad within half a second.
//! - [`THROW`]: carry it on the link and throw it up and back to a goal 0.5 m behind the
//!   joint, 0.8 m up, turned 2.2 rad.
//! - [`ROLL`]: fig. 2: roll a square wooden frame over its vertex nearer the joint, nine
//!   knots, minimizing mu plus the squared landing speed, with the joint's travel and
//!   end angle limited (as the paper limited the arm's end angle).
//! - [`ROLLING_THROW`]: start it rolling outward and throw it back over the joint.

/// `scenes/arm-snatch.toml`.
pub const SNATCH: &str = r#"# Snatch (g): lift the square off the table onto the arm, at rest at 0.3 rad.
[object]
side_m = 0.1
position_m = 0.9

[task]
kind = "snatch"
initial_angle_rad = 0.0
final_angle_rad = 0.3

[planner]
phase_time_max_s = 0.5
"#;

/// `scenes/arm-throw.toml`.
pub const THROW: &str = r#"# Throw (gf): carry the square in a dynamic grasp, release it, let it fly to a goal.
[object]
side_m = 0.1
position_m = 0.9

[task]
kind = "throw"
initial_angle_rad = 0.0
goal_x_m = -0.5
goal_y_m = 0.8
goal_angle_rad = 2.2
goal_tolerance_m = 0.01
goal_angle_tolerance_rad = 0.05
"#;

/// `scenes/arm-roll.toml` (fig. 2).
pub const ROLL: &str = r#"# Roll (grg), fig. 2: a square wooden frame rolled over its vertex nearer the joint.
[arm]
max_angle_rad = 0.35

[object]
side_m = 0.1
radius_of_gyration_m = 0.0577   # a thin square frame: side / sqrt(3)
position_m = 0.9

[task]
kind = "roll"
roll_direction = "ccw"
final_angle_min_rad = -0.1
final_angle_max_rad = 0.1
impact_weight_s2pm2 = 1.0

[planner]
knots = 9
"#;

/// `scenes/arm-rolling-throw.toml`.
pub const ROLLING_THROW: &str = r#"# Rolling throw (grf): start the square rolling outward, release it mid-roll.
[object]
side_m = 0.1
position_m = 0.9

[task]
kind = "rolling_throw"
roll_direction = "cw"
goal_x_m = -1.5
goal_y_m = 1.0
goal_angle_rad = 2.95
"#;

/// All four, with their names.
pub const ALL: [(&str, &str); 4] = [
    ("snatch", SNATCH),
    ("throw", THROW),
    ("roll", ROLL),
    ("rolling_throw", ROLLING_THROW),
];
