//! The four tasks of sec. 2 end to end: each plans, executes `ok` in the event-driven
//! verifier at the planned mu, and fails at 0.95 mu; the nine-knot roll of a square has
//! fig. 2's windup; the plan runs on the core's controller (SIL); scene errors name keys.

use dexter_sim::model::arm::motion::ArmMotion;
use dexter_sim::model::arm::params::ArmConfig;
use dexter_sim::model::arm::simulate::Executed;
use dexter_sim::model::arm::{ArmError, ArmScene};
use dexter_sim::systems::arm::examples;
use dexter_sim::systems::arm::execute::{run, ArmSummary, RunOptions};

fn system(text: &str) -> ArmScene {
    ArmConfig::from_toml_str(text).unwrap().validate().unwrap()
}

fn summary(text: &str, track: bool) -> ArmSummary {
    run(&system(text), RunOptions { track }).unwrap()
}

fn check_task(name: &str, text: &str) -> ArmSummary {
    let s = summary(text, false);
    assert_eq!(s.executed, Executed::Ok, "{name}: {}", s.reason);
    assert_ne!(
        s.mu_margin_check.executed,
        Executed::Ok,
        "{name}: still ok at 0.95 mu = {}",
        s.mu_margin_check.mu
    );
    assert!((s.mu_margin_check.mu - 0.95 * s.mu_required).abs() < 1e-12);
    assert!(s.mu_required > 0.0 && s.mu_required.is_finite());
    // the program's samples see the friction peak: the dense verifier adds little
    assert!(
        s.mu_required <= 1.02 * s.mu_sampled,
        "{name}: dense peak {} vs sampled {}",
        s.mu_required,
        s.mu_sampled
    );
    // the verifier's own peak friction is what the plan claims to need, within 1 %
    let peak = s
        .friction
        .iter()
        .map(|f| f.ratio)
        .filter(|r| r.is_finite())
        .fold(0.0, f64::max);
    assert!(
        peak <= s.mu_required * (1.0 + 1e-9),
        "{name}: peak {peak} above mu"
    );
    assert!(
        peak >= 0.95 * s.mu_required,
        "{name}: peak {peak} far below mu"
    );
    assert!(s.planner_iterations > 0 && s.planner_wall_time_s > 0.0);
    assert!(!s.frames.is_empty() && !s.trajectory.knots.is_empty());
    s
}

#[test]
fn snatch_plans_and_executes_and_needs_its_mu() {
    let s = check_task("snatch", examples::SNATCH);
    assert_eq!(s.phases, "g");
    // at rest on the arm at 0.3 rad the square needs tan(0.3) at least
    assert!(s.mu_required >= 0.3f64.tan());
}

#[test]
fn throw_plans_lands_on_the_goal_and_needs_its_mu() {
    let s = check_task("throw", examples::THROW);
    let e = s.goal_error.unwrap();
    assert!(e.position_m < 0.01 && e.angle_rad.abs() < 0.05);
    assert!(s.events.iter().any(|e| e.kind == "release"));
}

#[test]
fn rolling_throw_rolls_before_the_release() {
    let s = check_task("rolling_throw", examples::ROLLING_THROW);
    let t = |k: &str| s.events.iter().find(|e| e.kind == k).map(|e| e.t_s);
    assert!(t("roll_start_cw").unwrap() < t("release").unwrap());
    assert_eq!(t("roll_end"), None, "released before the roll ends");
}

#[test]
fn roll_of_a_square_with_nine_knots_winds_up_first_as_in_fig_2() {
    let s = check_task("roll", examples::ROLL);
    assert_eq!(s.trajectory.knots.len(), 9);
    let start = s
        .events
        .iter()
        .find(|e| e.kind == "roll_start_ccw")
        .expect("rolls counterclockwise")
        .t_s;
    assert!(s.events.iter().any(|e| e.kind == "roll_end"));
    // the roll is counterclockwise; the joint first moves the other way (clockwise)...
    let samples = &s.trajectory.samples;
    let first_move = samples
        .iter()
        .find(|(_, j)| j.velocity_radps.abs() > 1e-3)
        .unwrap()
        .1;
    assert!(
        first_move.velocity_radps < 0.0,
        "first motion {first_move:?}"
    );
    // ... by a real windup, before the roll begins, and swings back up into the roll
    let low = samples
        .iter()
        .filter(|(t, _)| *t < start)
        .map(|(_, j)| j.angle_rad)
        .fold(f64::INFINITY, f64::min);
    assert!(low < -0.05, "windup only {low} rad");
    let at_start = samples.iter().find(|(t, _)| *t >= start).unwrap().1;
    assert!(at_start.angle_rad > low + 0.1);
}

#[test]
fn the_plan_runs_on_the_cores_controller_and_reports_the_tracking_error() {
    let s = summary(examples::ROLLING_THROW, true);
    let t = s.tracked.unwrap();
    assert_eq!(t.fault, None);
    assert!(t.max_tracking_error_rad > 0.0 && t.max_tracking_error_rad < 0.01);
    assert!(t.max_torque_nm <= 100.0);
    // tracking error changes the friction the motion needs, a little
    assert!((t.mu_needed / s.mu_required - 1.0).abs() < 0.2);
    assert_ne!(t.executed_at_mu_needed, Executed::Slipped);
}

#[test]
fn scene_errors_name_the_key() {
    let err = |text: &str| {
        ArmConfig::from_toml_str(text)
            .and_then(|c| c.validate().map(|_| ()))
            .unwrap_err()
    };
    let e = err("[task]\nkind = \"snatch\"\nfinal_angle_rad = 0.3\n[object]\nmass_kgs = 1.0\n");
    assert!(
        e.to_string().contains("object") && e.to_string().contains("mass_kgs"),
        "{e}"
    );
    let e = err("[task]\nkind = \"snatch\"\nfinal_angle_rad = 0.3\n[object]\nmass_kg = -1.0\n");
    assert_eq!(e.to_string(), "object.mass_kg must be > 0");
    let e = err("[task]\nkind = \"throw\"\ngoal_y_m = 0.0\ngoal_angle_rad = 0.0\n");
    assert!(
        matches!(
            e,
            ArmError::Relation {
                param: "task.goal_x_m",
                ..
            }
        ),
        "{e}"
    );
    let e = err("[task]\nkind = \"snatch\"\n");
    assert!(
        matches!(
            e,
            ArmError::Relation {
                param: "task.final_angle_rad",
                ..
            }
        ),
        "{e}"
    );
    let e = err("[task]\nkind = \"roll\"\n[planner]\nknots = 17\n");
    assert!(
        matches!(
            e,
            ArmError::Relation {
                param: "planner.knots",
                ..
            }
        ),
        "{e}"
    );
    let e = err("[task]\nkind = \"roll\"\n[object]\nposition_m = 1.2\n");
    assert!(
        matches!(
            e,
            ArmError::Relation {
                param: "object.position_m",
                ..
            }
        ),
        "{e}"
    );
    let e = err("[task]\nkind = \"roll\"\n[tracking]\naccel_max_radps2 = 60.0\n");
    assert!(
        matches!(
            e,
            ArmError::Relation {
                param: "tracking.accel_max_radps2",
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn an_impossible_task_says_which_constraint_failed() {
    // a throw to a point no release can reach within the joint's speed limit
    let text = "[task]\nkind = \"throw\"\ngoal_x_m = 20.0\ngoal_y_m = 0.0\ngoal_angle_rad = 0.0\n[planner]\nstarts = 1\nmax_evaluations = 100\n";
    let e = dexter_sim::model::arm::planner::plan(&system(text)).unwrap_err();
    assert!(matches!(e, ArmError::NoPlan(_)));
    assert!(
        e.to_string().contains("the goal pose") || e.to_string().contains("the joint speed limit"),
        "{e}"
    );
}

#[test]
fn the_planned_motion_brakes_to_rest_after_a_throw() {
    let sys = system(examples::THROW);
    let p = dexter_sim::model::arm::planner::plan(&sys).unwrap();
    let m = p.motion(&sys.rest_move());
    let end = m.joint(m.duration_s());
    assert!(end.velocity_radps.abs() > 1.0, "released while moving");
    let after = m.joint(m.settled_s() + 0.1);
    assert_eq!((after.velocity_radps, after.accel_radps2), (0.0, 0.0));
    assert!(after.angle_rad <= sys.bounds.max_angle_rad - 0.01 + 1e-9);
}
