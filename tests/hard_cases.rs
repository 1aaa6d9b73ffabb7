//! Hard numerical cases: grazing contact, Zeno sequences, a lossless ball over a million
//! impacts, and scales from millimetres to 100 m. Expected values are closed forms.

use dexter_core::state::{BallState, PaddleState};
use dexter_sim::effects::actuator::IdealActuator;
use dexter_sim::effects::jitter::NoJitter;
use dexter_sim::engine::zeno::ZenoPolicy;
use dexter_sim::engine::Ballistic;
use dexter_sim::model::line::{Advance, LinePlant};
use dexter_sim::model::surface::{Actuated, Surface};
use dexter_sim::systems::line::run::{run_streaming, RunOptions};
use dexter_sim::systems::line::summary::Summary;
use dexter_sim::systems::line::trace::ImpactRow;
use dexter_tests::{load_scene, rel, run_rows};

const G: f64 = 9.81;

fn zeno() -> ZenoPolicy {
    ZenoPolicy {
        velocity_threshold_mps: 1e-6,
        relative_threshold: 1e-6,
        max_impacts_per_segment: 10_000,
    }
}

/// A ball at its apex 1 m up and a paddle `d0` below it, rising at sqrt(2 g d0) while
/// accelerating down at 2 g: the gap is g/2 (t - t0)^2 with t0 = sqrt(2 d0 / g), touching
/// zero once with zero relative speed.
fn grazing_plant(d0: f64) -> LinePlant<Ballistic, Actuated<IdealActuator>, NoJitter> {
    let mut paddle = Actuated::new(IdealActuator, 1.0 - d0);
    paddle.paddle = PaddleState::new(1.0 - d0, (2.0 * G * d0).sqrt());
    paddle.command(-2.0 * G);
    LinePlant::new(
        G,
        0.8,
        Ballistic,
        paddle,
        NoJitter,
        zeno(),
        BallState::new(1.0, 0.0),
    )
}

#[test]
fn grazing_contact_is_found_not_missed() {
    for d0 in [1e-3, 0.1, 0.5] {
        let t0 = (2.0 * d0 / G).sqrt();
        let mut plant = grazing_plant(d0);
        let mut rows: Vec<ImpactRow> = Vec::new();
        plant.advance_to(2.0 * t0, 1, &mut |r| rows.push(*r));
        assert_eq!(rows.len(), 1, "grazing contact at d0 = {d0} missed");
        // a double root is only determined to ~sqrt(eps) in time
        assert!(
            (rows[0].time_s - t0).abs() <= 1e-7 * t0.max(1.0),
            "{} vs {t0}",
            rows[0].time_s
        );
        // zero relative speed: the restitution law leaves the ball with the paddle's speed
        let rel_speed = rows[0].ball_velocity_before_mps - rows[0].paddle_velocity_mps;
        assert!(rel_speed.abs() < 1e-6, "relative speed {rel_speed}");
    }
}

#[test]
fn a_paddle_closing_by_a_hair_more_is_a_contact_and_never_tunnels() {
    // the paddle rises a little faster than the grazing speed: a real (transversal) contact
    let d0 = 0.1;
    let mut plant = grazing_plant(d0);
    plant.surface.paddle.velocity_mps *= 1.0 + 1e-9;
    let mut rows: Vec<ImpactRow> = Vec::new();
    // step in small windows as a controller would and check the ball is never below the paddle
    for k in 1..=400 {
        plant.advance_to(k as f64 * 1e-3, 1, &mut |r| rows.push(*r));
        let gap = plant.ball.height_m - plant.surface.paddle.height_m;
        assert!(gap >= -1e-12, "tunnelled: gap {gap} at {}", plant.time_s);
        if !rows.is_empty() {
            break;
        }
    }
    assert_eq!(rows.len(), 1);
}

#[test]
fn a_paddle_missing_by_a_hair_is_no_contact() {
    // the paddle rises slower than the grazing speed by a relative 1e-6: it stops 2e-7 d0 short
    let d0 = 0.1;
    let mut plant = grazing_plant(d0);
    plant.surface.paddle.velocity_mps *= 1.0 - 1e-6;
    let mut n = 0;
    plant.advance_to(0.3, 10, &mut |_| n += 1);
    assert_eq!(n, 0);
}

/// Zeno on a fixed table for restitution e: impacts until the take-off speed e^N v0 falls
/// to the threshold, then rest at the Zeno limit t0 + 2 e v0 / (g (1 - e)).
#[test]
fn zeno_sequences_end_in_resting_contact_at_the_closed_form_time() {
    for e in [0.0f64, 0.5, 0.9] {
        let set = format!("physics.restitution={e}");
        let scene = load_scene("passive-bounce", &[&set, "stop.impacts=100000"]);
        let out = run_rows(&scene);
        let s = Summary::new(&scene, &out);
        let h0 = 1.0;
        let v0 = (2.0 * G * h0).sqrt();
        let t_inf = (2.0 * h0 / G).sqrt() + 2.0 * e * v0 / (G * (1.0 - e));
        // impacts N: the first with e^N v0 <= 1e-6 (e = 0: the first impact)
        let expected_n = (1..).find(|&n| e.powi(n) * v0 <= 1e-6).unwrap() as u64;
        println!(
            "e = {e}: rest after {} impacts at {:?} s (closed form {t_inf} s)",
            out.impacts, s.resting_since_s
        );
        assert!(s.resting_contact, "e = {e}");
        assert_eq!(out.impacts, expected_n, "e = {e}");
        assert!(rel(s.resting_since_s.unwrap(), t_inf) <= 1e-12, "e = {e}");
        assert!(out.resting_at_end);
    }
}

#[test]
fn ball_rests_on_a_moving_paddle_and_leaves_when_it_drops_faster_than_g() {
    // a paddle at rest, e = 0.5: Zeno, then resting contact
    let mut paddle = Actuated::new(IdealActuator, 0.0);
    paddle.command(0.0);
    let mut plant = LinePlant::new(
        G,
        0.5,
        Ballistic,
        paddle,
        NoJitter,
        zeno(),
        BallState::new(0.2, 0.0),
    );
    let adv = plant.advance_to(2.0, u64::MAX, &mut |_| {});
    assert_eq!(adv, Advance::Reached);
    assert!(plant.resting);
    // lift the paddle at 5 m/s^2 (> -g): the ball rides along, b = r exactly
    plant.surface.command(5.0);
    plant.advance_to(2.1, u64::MAX, &mut |_| {});
    assert!(plant.resting);
    assert!((plant.ball.height_m - 0.5 * 5.0 * 0.01).abs() < 1e-12);
    assert!((plant.ball.velocity_mps - 0.5).abs() < 1e-12);
    // now drop it at 2 g: the ball leaves and flies ballistically (gap = g t^2 / 2)
    plant.surface.command(-2.0 * G);
    plant.advance_to(2.2, u64::MAX, &mut |_| {});
    assert!(!plant.resting);
    let gap = plant.ball.height_m - plant.surface.paddle.height_m;
    assert!((gap - 0.5 * G * 0.01).abs() < 1e-12, "gap {gap}");
}

#[test]
fn lossless_ball_over_a_million_impacts_keeps_its_energy() {
    let scene = load_scene(
        "passive-bounce",
        &[
            "physics.restitution=1.0",
            "stop.impacts=1000000",
            "stop.duration_s=1e9",
        ],
    );
    // every apex, streamed (the run keeps none of them)
    let (mut lowest, mut highest) = (f64::INFINITY, f64::NEG_INFINITY);
    let out = run_streaming(&scene, &RunOptions::default(), None, &mut |r| {
        lowest = lowest.min(r.apex_height_m);
        highest = highest.max(r.apex_height_m);
    })
    .unwrap();
    assert_eq!(out.impacts, 1_000_000);
    assert!(out.apexes_m.is_empty() && out.rows.is_empty());
    let last = out.last_row.unwrap();
    let e0 = G * 1.0;
    let e1 = 0.5 * last.ball_velocity_before_mps.powi(2);
    let drift = (e1 - e0) / e0;
    let apex_drift = (highest - 1.0).abs().max((lowest - 1.0).abs());
    // closed form: impact n (0-based) at (2 n + 1) sqrt(2 h0 / g)
    let t_last = (2.0 * 999_999.0 + 1.0) * (2.0 / G).sqrt();
    println!(
        "e = 1, 10^6 impacts: energy drift {drift:.3e} (relative), worst apex deviation {apex_drift:.3e} m, last impact time error {:.3e} (relative), wall {:.3} s",
        rel(last.time_s, t_last),
        out.wall_time_s
    );
    assert!(drift.abs() < 1e-9);
    assert!(apex_drift < 1e-9);
    assert!(rel(last.time_s, t_last) < 1e-9);
    assert!(!Summary::new(&scene, &out).resting_contact);
}

#[test]
fn tiny_and_huge_scales_keep_closed_form_accuracy() {
    for h0 in [1e-3, 1.0, 100.0] {
        // passive bounce
        let hs = format!("ball.height_m={h0:e}");
        let scene = load_scene("passive-bounce", &[&hs]);
        let out = run_rows(&scene);
        let e = 0.8f64;
        let v0 = (2.0 * G * h0).sqrt();
        let t0 = (2.0 * h0 / G).sqrt();
        for (n, row) in out.rows.iter().take(30).enumerate() {
            let n = n as i32;
            let t = t0 + 2.0 * v0 * e * (1.0 - e.powi(n)) / (G * (1.0 - e));
            assert!(rel(row.time_s, t) <= 1e-12, "h0 {h0} impact {n}");
            assert!(
                rel(row.apex_height_m, e.powi(2 * (n + 1)) * h0) <= 1e-12,
                "h0 {h0} apex {n}"
            );
        }
        // ideal juggler at the same scale: kappa1 ~ 1/h* keeps beta v*^2 = 0.883
        let kappa1 = 0.05 / h0;
        let sets = [
            format!("control.target_apex_m={h0:e}"),
            format!("ball.height_m={:e}", 0.3 * h0),
            format!("control.kappa1_s2pm2={kappa1:e}"),
        ];
        let refs: Vec<&str> = sets.iter().map(String::as_str).collect();
        let scene = load_scene("line-juggler-ideal", &refs);
        let out = run_rows(&scene);
        let beta = 0.5 * 1.8 * kappa1;
        let v2 = 2.0 * G * h0;
        for w in out.rows.windows(2) {
            let v = -w[0].ball_velocity_before_mps;
            let next = -w[1].ball_velocity_before_mps;
            assert!(
                rel(next, v * (1.0 - beta * (v * v - v2))) <= 1e-10,
                "h* {h0}"
            );
        }
        assert!(rel(*out.apexes_m.last().unwrap(), h0) < 1e-5, "h* {h0}");
    }
}

#[test]
fn drag_flights_match_the_quadratic_drag_closed_form() {
    // ideal juggler with quadratic drag c: a flight leaving the plane at v returns at
    // v_in^2 = v^2 / (1 + c v^2 / g) (rise to ln(1 + c v^2/g)/(2c), fall from there), and the
    // reported apex is that height
    let c = 0.1;
    for (integrator, tol) in [("rk45", 1e-8), ("rk4", 1e-8)] {
        let sets = [
            format!("drag.coefficient_per_m={c}"),
            format!("drag.integrator={integrator}"),
            "drag.tolerance=1e-12".to_string(),
            "drag.step_s=1e-3".to_string(),
            "stop.impacts=40".to_string(),
        ];
        let refs: Vec<&str> = sets.iter().map(String::as_str).collect();
        let out = run_rows(&load_scene("line-juggler-ideal", &refs));
        assert_eq!(out.rows.len(), 40);
        let mut worst = 0.0f64;
        for w in out.rows.windows(2) {
            let up = w[0].ball_velocity_after_mps;
            let exact = (up * up / (1.0 + c * up * up / G)).sqrt();
            worst = worst.max(rel(-w[1].ball_velocity_before_mps, exact));
            let apex = (c * up * up / G).ln_1p() / (2.0 * c);
            assert!(rel(w[0].apex_height_m, apex) < 1e-12);
        }
        println!("drag {c} 1/m, {integrator}: worst landing-speed error {worst:.2e}");
        assert!(worst < tol, "{integrator}: {worst}");
    }
}

#[test]
fn jitter_of_zero_spread_changes_nothing() {
    let a = run_rows(&load_scene("line-juggler-ideal", &[]));
    let b = run_rows(&load_scene("line-juggler-ideal", &["jitter.sigma_s=0"]));
    assert_eq!(a.rows, b.rows);
    // and 10 ms of jitter moves the paddle velocity at impact by r'' delta = k g delta
    let c = run_rows(&load_scene("line-juggler-ideal", &["jitter.sigma_s=0.01"]));
    assert_ne!(a.rows[1..], c.rows[1..]);
}
