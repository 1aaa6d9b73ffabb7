//! The kappa-tilt controller's tracker (`dexter_core::tilt_control`, its `mod.rs`) by hand:
//! the safe state's dead reckoning, the fault an out-of-range frame gets, the plausible
//! box's edges with asymmetric travels, the planning pipeline's timing (the first plan
//! `cycle_periods()` after Track is entered, warm-started re-plans one period sooner), the
//! impact window (the references carry on at their impact velocity for latency + 2 dt
//! after the planned impact, then brake), the late restart of a missed plan (latency +
//! 4 dt), the Unreachable and Limited reports, and the public getters.
//!
//! Expected values come from closed forms in f64 (ballistic flight, eq. 7's root by
//! bisection, the braking law, the documented period counts), never from the controller.
//! Where a boundary is compared exactly, the period is a power of two (1/512 s) so that the
//! controller's f32 sums of periods are exact.

use dexter_core::fixed_rate::{Fault, FixedRate, Mode, Reply};
use dexter_core::params::ParamError;
use dexter_core::tilt_control::flight::FlightTuning;
use dexter_core::tilt_control::{PlanStatus, TiltCommand, TiltController, TiltFrame, TiltParams};

mod common;
use common::tilt::{flight, frame_at, table_after, true_contact};

fn close(got: f32, want: f64, tol: f64, what: &str) {
    assert!(
        (f64::from(got) - want).abs() <= tol,
        "{what}: {got} vs {want} (tolerance {tol})"
    );
}

/// The safe state brakes each axis from its last known state, `u = clamp(-v/dt, +-a_max)`,
/// and reports as its reference the state dead-reckoned one period on under that braking,
/// `x + (v + u dt/2) dt` (exact for a held acceleration), period after period.
#[test]
fn the_safe_state_dead_reckons_the_table_under_its_braking() {
    let p = TiltParams::default();
    let dt = f64::from(p.dt_s);
    let mut c = TiltController::new(p).unwrap();
    // measured: tilt 0.2 rad at 3 rad/s, stroke 0.05 m at -1.5 m/s
    let f = frame_at(0, [0.0, 0.3, 0.1, 0.0, 0.0, 0.0], [0.2, 3.0, 0.05, -1.5]);
    assert_eq!(c.step(&f).mode, Mode::Hold);
    let mut axes = [
        (0.2f64, 3.0f64, f64::from(p.tilt.accel_max_radps2)),
        (0.05, -1.5, f64::from(p.stroke.accel_max_mps2)),
    ];
    for k in 1..=20u32 {
        let cmd = c.safe(k, Fault::Stale);
        let mut want = [0.0f64; 4];
        for (i, (x, v, a_max)) in axes.iter_mut().enumerate() {
            let u = (-*v / dt).clamp(-*a_max, *a_max);
            *x += (*v + 0.5 * u * dt) * dt;
            *v += u * dt;
            want[2 * i] = u;
            want[2 * i + 1] = *x;
        }
        // 3 rad/s at 300 rad/s^2 stops in 5 periods, 1.5 m/s at 60 m/s^2 in 12.5; the
        // reference moves 5 mm and 19 mm on the way
        close(cmd.tilt_accel_radps2, want[0], 1e-2, "tilt braking");
        close(cmd.tilt_ref_rad, want[1], 1e-6, "tilt dead-reckoned");
        close(cmd.stroke_accel_mps2, want[2], 1e-2, "stroke braking");
        close(cmd.stroke_ref_m, want[3], 1e-6, "stroke dead-reckoned");
        assert_eq!(
            (cmd.seq, cmd.mode, cmd.fault, cmd.plan, cmd.impact_in_s),
            (k, Mode::Safe, Fault::Stale, PlanStatus::Idle, 0.0)
        );
    }
}

/// A finite frame outside the plausible box is `OutOfRange` whatever its other values
/// (here all non-zero), a non-finite value anywhere is `NonFinite`.
#[test]
fn a_finite_frame_out_of_range_is_out_of_range_whatever_its_values() {
    let inside = [0.5f32, 0.3, 0.1, 0.2, 1.0, 0.02, 0.5];
    // x_max 1000, y in [-0.5, 5], |theta| 1.4, the tilt travel +-0.7 plus 5 % of 1.4,
    // twice 8 rad/s, the stroke travel +-0.1 plus 5 % of 0.2, twice 2 m/s
    let outside = [1500.0f32, 5.5, 1.45, 0.8, 17.0, 0.12, 4.5];
    let set = |v: [f32; 7]| TiltFrame {
        seq: 0,
        body_x_m: v[0],
        body_y_m: v[1],
        body_theta_rad: v[2],
        table_angle_rad: v[3],
        table_rate_radps: v[4],
        table_height_m: v[5],
        table_velocity_mps: v[6],
    };
    let mut c = TiltController::new(TiltParams::default()).unwrap();
    let mut seq = 0u32;
    let mut fault_of = |v: [f32; 7]| {
        seq += 1;
        c.step(&TiltFrame { seq, ..set(v) }).fault
    };
    assert_eq!(fault_of(inside), Fault::None);
    for i in 0..7 {
        for (bad, want) in [
            (outside[i], Fault::OutOfRange),
            (-outside[i], Fault::OutOfRange),
            (f32::NAN, Fault::NonFinite),
            (f32::INFINITY, Fault::NonFinite),
            (f32::NEG_INFINITY, Fault::NonFinite),
        ] {
            let mut v = inside;
            v[i] = bad;
            assert_eq!(fault_of(v), want, "field {i} = {bad}");
            // recovers on the next valid frame
            assert_eq!(fault_of(inside), Fault::None);
        }
    }
}

/// The plausible box is centred on each travel: the tilt and stroke travels plus 5 % of
/// them on each side, y within [y_min, y_max], here with travels not centred on zero.
#[test]
fn the_plausible_box_is_each_travel_plus_five_percent_on_both_sides() {
    let d = TiltParams::default();
    let mut p = d;
    p.tilt.min_rad = -0.2;
    p.tilt.max_rad = 0.7;
    p.stroke.min_m = -0.02;
    p.stroke.max_m = 0.1;
    let (tilt_margin, stroke_margin) = (0.05 * 0.9, 0.05 * 0.12);
    let mut c = TiltController::new(p).unwrap();
    let mut seq = 0u32;
    let mut fault_of = |angle: f64, height: f64, y: f64| {
        seq += 1;
        c.step(&frame_at(
            seq,
            [0.0, y, 0.1, 0.0, 0.0, 0.0],
            [angle, 0.0, height, 0.0],
        ))
        .fault
    };
    let e = 1e-3;
    for (angle, height, y, want) in [
        (0.0, 0.0, 0.3, Fault::None),
        (0.7 + tilt_margin - e, 0.0, 0.3, Fault::None),
        (0.7 + tilt_margin + e, 0.0, 0.3, Fault::OutOfRange),
        (-0.2 - tilt_margin + e, 0.0, 0.3, Fault::None),
        (-0.2 - tilt_margin - e, 0.0, 0.3, Fault::OutOfRange),
        (0.0, 0.1 + stroke_margin - e, 0.3, Fault::None),
        (0.0, 0.1 + stroke_margin + e, 0.3, Fault::OutOfRange),
        (0.0, -0.02 - stroke_margin + e, 0.3, Fault::None),
        (0.0, -0.02 - stroke_margin - e, 0.3, Fault::OutOfRange),
        (0.0, 0.0, 5.0 - e, Fault::None),
        (0.0, 0.0, 5.0 + e, Fault::OutOfRange),
        (0.0, 0.0, -0.5 + e, Fault::None),
        (0.0, 0.0, -0.5 - e, Fault::OutOfRange),
    ] {
        assert_eq!(fault_of(angle, height, y), want, "{angle} {height} {y}");
        assert_eq!(fault_of(0.0, 0.0, 0.3), Fault::None);
    }
}

/// `contact_iterations` is 1 ..= 4: 0 (no Newton step, no prediction) is refused by name.
#[test]
fn zero_or_too_many_contact_iterations_are_refused_by_name() {
    for n in [0u8, 5, 255] {
        let p = TiltParams {
            contact_iterations: n,
            ..TiltParams::default()
        };
        assert_eq!(
            p.validate(),
            Err(ParamError::OutOfRange("contact_iterations")),
            "{n}"
        );
    }
    for n in 1..=4u8 {
        let p = TiltParams {
            contact_iterations: n,
            ..TiltParams::default()
        };
        assert_eq!(p.validate(), Ok(()), "{n}");
    }
}

/// Parameters with a period of 1/512 s and a latency of two periods, so that the
/// controller's sums of periods are exact; l = 1 cm, so that the body falls below the
/// bracket (y_imp - l) soon after a missed contact; no stale limit in the way.
fn exact_params() -> TiltParams {
    let d = TiltParams::default();
    TiltParams {
        dt_s: 1.0 / 512.0,
        l_m: 0.01,
        estimator: FlightTuning {
            latency_s: 2.0 / 512.0,
            ..d.estimator
        },
        stale_limit_steps: 1000,
        ..d
    }
}

/// The missed-impact run: a camera with two periods of latency sees the body fall onto
/// the impact height (contact 5.5 periods after the first snapshot), so the first plan
/// comes when its impact is already past (tau held at one period). From the period after
/// that plan the camera repeats its last sample (the impact is never seen). The table's
/// measurements follow the references (position: the last command's reference; velocity:
/// the last reference step / dt), except three probes: period E + 12 reports the tilt 5
/// rad/s off, E + 13 the stroke 2 m/s off. Returns the commands and E, the first Track
/// period.
fn missed_impact_run() -> (Vec<TiltCommand>, usize) {
    let p = exact_params();
    let dt = f64::from(p.dt_s);
    let latency = f64::from(p.estimator.latency_s);
    let l = f64::from(p.l_m);
    let mut c = TiltController::new(p).unwrap();
    // settle_samples 8: valid, and Track entered, at the 8th sample (k = 7); the snapshot
    // at k = 8; the contact 5.5 periods later
    let t_c = 13.5 * dt;
    let at_contact = [0.0, l * 0.1f64.cos(), 0.1, 0.05, -2.0, 0.3];
    let s0 = flight(at_contact, -t_c);
    let mut cmds: Vec<TiltCommand> = Vec::new();
    let mut entry: Option<usize> = None;
    let mut last_fresh = 0usize;
    for k in 0..48usize {
        let fresh = match entry {
            Some(e) => k <= e + 9,
            None => true,
        };
        if fresh {
            last_fresh = k;
        }
        let body = flight(s0, last_fresh as f64 * dt - latency);
        let table = match (entry, cmds.len()) {
            (Some(e), n) if k >= e + 10 => {
                let (a, b) = (&cmds[n - 1], &cmds[n - 2]);
                let tilt_rate = if k == e + 12 { 5.0 } else { 0.0 };
                let stroke_v = f64::from(a.stroke_ref_m - b.stroke_ref_m) / dt;
                let stroke_v = if k == e + 13 {
                    stroke_v - 2.0
                } else {
                    stroke_v
                };
                [
                    f64::from(a.tilt_ref_rad),
                    tilt_rate,
                    f64::from(a.stroke_ref_m),
                    stroke_v,
                ]
            }
            _ => [0.0; 4],
        };
        let cmd = c.step(&frame_at(last_fresh as u32, body, table));
        assert_eq!(cmd.fault, Fault::None, "period {k}: {cmd:?}");
        if entry.is_none() && cmd.mode == Mode::Track {
            entry = Some(k);
        }
        cmds.push(cmd);
    }
    (cmds, entry.expect("Track entered"))
}

/// The impact window: the plan's cubics end at the planned impact; from there the
/// references carry on at their impact velocity (no feed-forward) for latency + 2 dt,
/// when the estimator should have applied the impact; past it they brake to rest at
/// most at the acceleration limit. The time to the impact counts down by one period a
/// period, through zero. Boundaries are exact: dt = 1/512 s, tau = dt, window 4 dt.
#[test]
fn past_the_planned_impact_the_references_coast_for_the_window_then_brake() {
    let p = exact_params();
    let dt = f64::from(p.dt_s);
    let (cmds, e) = missed_impact_run();
    assert_eq!(e, 7, "Track at the 8th sample (settle_samples)");
    // the first plan, N + 7 periods after entry (no warm start), its impact past: one period
    let a0 = e + usize::from(p.cycle_periods());
    assert!(cmds[e..a0].iter().all(|c| c.plan == PlanStatus::Idle));
    assert_eq!(cmds[a0].impact_in_s, p.dt_s, "{:?}", cmds[a0]);
    // counts down exactly while the plan holds (until it is given up, below)
    for j in 0..=9usize {
        let want = (1.0 - j as f64) * dt;
        assert_eq!(f64::from(cmds[a0 + j].impact_in_s), want, "period a0 + {j}");
    }
    let d = |k: usize| f64::from(cmds[k].stroke_ref_m) - f64::from(cmds[k - 1].stroke_ref_m);
    // the cubic's last period brings the reference to its impact velocity v1 (> 0.05 m/s
    // here: eq. 25 asks for a moving table)
    let v1 = d(a0 + 1) / dt;
    assert!(v1.abs() > 0.05, "impact velocity {v1}");
    // t in [tau, tau + latency + 2 dt) = [dt, 5 dt): periods a0 + 1 ..= a0 + 4 at v1
    for k in a0 + 2..=a0 + 4 {
        assert!(
            (d(k) - v1 * dt).abs() < 1e-7,
            "period {k}: {} vs {}",
            d(k),
            v1 * dt
        );
    }
    // from t = 5 dt on: braking, u = clamp(-v/dt, +-a_max), exact for a held acceleration
    let a_max = f64::from(p.stroke.accel_max_mps2);
    let (mut x, mut v) = (f64::from(cmds[a0 + 4].stroke_ref_m), v1);
    for (k, cmd) in cmds.iter().enumerate().skip(a0 + 5) {
        let u = (-v / dt).clamp(-a_max, a_max);
        x += (v + 0.5 * u * dt) * dt;
        v += u * dt;
        close(
            cmd.stroke_ref_m,
            x,
            1e-6,
            &format!("braking reference, period {k}"),
        );
    }
    assert!(v.abs() < 1e-9, "at rest by the end");
}

/// A committed plan whose impact is not seen is given up once more than latency + 4 dt
/// has passed since its planned time (tau + latency + 4 dt = 7 dt: at the run_stage of
/// period a0 + 8), then a snapshot and a bracket: the body is now below y_imp - l, no
/// contact ahead, Unreachable from a0 + 10 on, without a time to an impact.
#[test]
fn a_missed_plan_is_given_up_latency_plus_four_periods_after_its_time() {
    let p = exact_params();
    let (cmds, e) = missed_impact_run();
    let a0 = e + usize::from(p.cycle_periods());
    for (k, c) in cmds.iter().enumerate().take(a0 + 10).skip(a0) {
        assert!(
            matches!(c.plan, PlanStatus::Committed | PlanStatus::Limited),
            "period {k}: {c:?}"
        );
    }
    for (k, c) in cmds.iter().enumerate().skip(a0 + 10) {
        assert_eq!(
            (c.plan, c.impact_in_s),
            (PlanStatus::Unreachable, 0.0),
            "period {k}"
        );
        assert_eq!(c.mode, Mode::Track);
    }
}

/// The tracker saturating either axis turns a Committed plan's report into Limited; with
/// the table on its references it stays Committed.
#[test]
fn a_saturated_axis_reports_the_plan_limited() {
    let (cmds, e) = missed_impact_run();
    let a0 = e + usize::from(exact_params().cycle_periods());
    assert_eq!(a0, e + 9);
    assert_eq!(
        cmds[e + 11].plan,
        PlanStatus::Committed,
        "on the references"
    );
    assert_eq!(cmds[e + 12].plan, PlanStatus::Limited, "tilt 5 rad/s off");
    assert_eq!(cmds[e + 13].plan, PlanStatus::Limited, "stroke 2 m/s off");
}

/// Before the first plan the status is Idle; a body already below y_imp - l (no
/// descending contact ahead) is Unreachable from its first bracket, two periods after
/// Track is entered (snapshot, bracket), and the references brake.
#[test]
fn no_contact_ahead_is_reported_unreachable_from_the_first_bracket() {
    let p = TiltParams::default();
    let dt = f64::from(p.dt_s);
    let latency = f64::from(p.estimator.latency_s);
    let mut c = TiltController::new(p).unwrap();
    // at its apex 20 cm below the impact height (l = 13.3 cm)
    let s0 = [0.0, -0.2, 0.1, 0.0, 0.0, 0.0];
    let cmds: Vec<TiltCommand> = (0..24u32)
        .map(|k| {
            c.step(&frame_at(
                k,
                flight(s0, f64::from(k) * dt - latency),
                [0.0; 4],
            ))
        })
        .collect();
    let e = cmds.iter().position(|c| c.mode == Mode::Track).unwrap();
    assert_eq!(e, 7);
    assert!(cmds[..e]
        .iter()
        .all(|c| c.mode == Mode::Hold && c.plan == PlanStatus::Idle));
    assert_eq!(
        (cmds[e].plan, cmds[e + 1].plan),
        (PlanStatus::Idle, PlanStatus::Idle)
    );
    for c in &cmds[e + 2..] {
        assert_eq!(
            (c.mode, c.plan, c.impact_in_s),
            (Mode::Track, PlanStatus::Unreachable, 0.0)
        );
    }
}

/// Perfect camera (no latency) and exact table axes (double integrators under the held
/// commands, f64): the commands of `periods` periods of the flight from `s0`, and the
/// controller after them.
fn tracked_run(p: TiltParams, s0: [f64; 6], periods: u32) -> (Vec<TiltCommand>, TiltController) {
    let mut c = TiltController::new(p).unwrap();
    let dt = f64::from(p.dt_s);
    let mut table = [0.0f64; 4];
    let mut cmds = Vec::new();
    for k in 0..periods {
        let cmd = c.step(&frame_at(k, flight(s0, f64::from(k) * dt), table));
        table = table_after(table, &cmd, dt);
        cmds.push(cmd);
    }
    (cmds, c)
}

fn no_latency(p: TiltParams) -> TiltParams {
    TiltParams {
        estimator: FlightTuning {
            latency_s: 0.0,
            ..p.estimator
        },
        ..p
    }
}

/// The pipeline's timing for N = 1 ..= 4 Newton steps: the first plan comes
/// `cycle_periods()` = N + 7 periods after Track is entered (snapshot, bracket, start, N
/// Newton steps, angle, law, motion, apply); every re-plan starts warm from the last
/// contact time moved to its snapshot, so it skips the start: one every N + 6 periods.
/// The plan commits at the first of these applies with the impact within `commit_s`
/// (computed here from the true contact), and predicts eq. 7's contact with the impact
/// height 5 cm above the stroke's zero.
#[test]
fn plans_come_n_plus_seven_then_every_n_plus_six_periods_and_commit_on_time() {
    let s0 = [0.0, 0.5, 0.15, 0.1, 0.3, -0.8];
    for n in 1..=4u8 {
        let p = no_latency(TiltParams {
            contact_iterations: n,
            impact_height_m: 0.05,
            ..TiltParams::default()
        });
        let dt = f64::from(p.dt_s);
        let t_c = true_contact(s0, f64::from(p.l_m), 0.05);
        let (cmds, _) = tracked_run(p, s0, (t_c / dt) as u32 - 2);
        let e = cmds.iter().position(|c| c.mode == Mode::Track).unwrap();
        assert_eq!(e, 7, "N = {n}");
        let a0 = e + usize::from(p.cycle_periods());
        assert_eq!(usize::from(p.cycle_periods()), usize::from(n) + 7);
        let first = cmds
            .iter()
            .position(|c| c.plan != PlanStatus::Idle)
            .unwrap();
        assert_eq!(first, a0, "N = {n}: {:?}", cmds[first]);
        // the committing apply on the warm grid a0 + (N + 6) i
        let commit = f64::from(p.commit_s);
        let cycle = usize::from(n) + 6;
        let mut k_commit = a0;
        while t_c - k_commit as f64 * dt > commit {
            k_commit += cycle;
        }
        let tau = t_c - k_commit as f64 * dt;
        assert!(commit - tau > 1e-4, "N = {n}: tau {tau} too near commit_s");
        assert!(
            k_commit > a0 + cycle,
            "N = {n}: at least two re-plans before the commit"
        );
        let got = cmds.iter().position(|c| c.plan == PlanStatus::Committed);
        assert_eq!(got, Some(k_commit), "N = {n}");
        for (k, c) in cmds.iter().enumerate().take(k_commit).skip(a0) {
            assert_eq!(c.plan, PlanStatus::Planned, "N = {n}, period {k}");
        }
        // the predicted contact with the impact height, from the committing period
        let predicted = k_commit as f64 * dt + f64::from(cmds[k_commit].impact_in_s);
        assert!(
            (predicted - t_c).abs() < 1e-5,
            "N = {n}: {predicted} vs {t_c}"
        );
    }
}

/// The getters: the estimate (the true state now, no latency), valid from the 8th sample
/// (settle_samples), the telemetry's slots (y, y', theta and the flag), the target (alpha
/// = kappa theta at the contact), and the `FixedRate` view runs the same step and safe
/// state bit for bit.
#[test]
fn the_getters_report_the_estimate_the_target_and_the_same_step() {
    let p = no_latency(TiltParams::default());
    let dt = f64::from(p.dt_s);
    let s0 = [0.0, 0.5, 0.15, 0.1, 0.3, -0.8];
    let t_c = true_contact(s0, f64::from(p.l_m), 0.0);
    let mut c = TiltController::new(p).unwrap();
    let mut view = <TiltController as FixedRate>::new(p).unwrap();
    let mut committed = false;
    let mut table = [0.0f64; 4];
    for k in 0..(t_c / dt) as u32 - 2 {
        let b = flight(s0, f64::from(k) * dt);
        let f = frame_at(k, b, table);
        let cmd = c.step(&f);
        table = table_after(table, &cmd, dt);
        assert!(
            cmd.bit_identical(&FixedRate::step(&mut view, &f)),
            "period {k}"
        );
        assert_eq!(c.estimate_valid(), k >= 7, "period {k}");
        let tel = c.telemetry();
        assert_eq!(tel, FixedRate::telemetry(&view));
        assert_eq!(tel.estimate_valid, k >= 7);
        if k >= 7 {
            let est = c.estimate();
            for (i, (got, want)) in [est.x_m, est.y_m, est.theta_rad].iter().zip(b).enumerate() {
                close(*got, want, 1e-5, &format!("estimate {i}, period {k}"));
            }
            let rates = [est.x_dot_mps, est.y_dot_mps, est.theta_dot_radps];
            for (i, (got, want)) in rates.iter().zip(&b[3..]).enumerate() {
                close(*got, *want, 1e-3, &format!("estimate rate {i}, period {k}"));
            }
            assert_eq!(tel.estimate[..3], [est.y_m, est.y_dot_mps, est.theta_rad]);
        }
        if cmd.plan == PlanStatus::Committed {
            committed = true;
            let theta_c = flight(s0, t_c)[2];
            close(
                c.target().alpha_rad,
                f64::from(p.kappa) * theta_c,
                2e-4,
                "alpha",
            );
        }
    }
    assert!(committed);
    let (a, b) = (
        c.safe(9, Fault::Stale),
        FixedRate::safe(&mut view, 9, Fault::Stale),
    );
    assert!(a.bit_identical(&b) && a.mode == Mode::Safe);
    assert!(!c.estimate_valid() && !c.telemetry().estimate_valid);
}

/// The finite guard on the references and the time to the impact trips on an overflow,
/// not on large finite values: a stroke travel reaching f32::MAX (valid, if no table has
/// one) with its home there, and the tilt home at +1.2 rad, hold without a fault.
#[test]
fn large_finite_references_hold_without_a_fault() {
    let d = TiltParams::default();
    let mut p = d;
    p.tilt.min_rad = -1.2;
    p.tilt.max_rad = 1.2;
    p.tilt.home_rad = 1.2;
    p.stroke.max_m = f32::MAX;
    p.stroke.home_m = f32::MAX;
    let mut c = TiltController::new(p).unwrap();
    for k in 0..3u32 {
        let cmd = c.step(&frame_at(
            k,
            [0.0, 0.3, 0.1, 0.0, 0.0, 0.0],
            [1.2, 0.0, 0.0, 0.0],
        ));
        assert_eq!((cmd.mode, cmd.fault), (Mode::Hold, Fault::None), "{cmd:?}");
        assert_eq!((cmd.tilt_ref_rad, cmd.stroke_ref_m), (1.2, f32::MAX));
    }
}

/// The same guard while tracking: a stroke reference of 1e38 m (the table measured there
/// when Track is entered, on a travel reaching 1.1e38 m) and a plan four seconds before
/// its impact (a body falling from 80 m) are both finite, and so is their sum: the
/// controller tracks without a fault.
#[test]
fn a_far_reference_and_a_distant_impact_track_without_a_fault() {
    let d = TiltParams::default();
    let mut p = d;
    p.stroke.max_m = 1.1e38;
    p.y_max_m = 100.0;
    let dt = f64::from(p.dt_s);
    let latency = f64::from(p.estimator.latency_s);
    let mut c = TiltController::new(p).unwrap();
    let s0 = [0.0, 80.0, 0.1, 0.0, 0.0, 0.0];
    let t_c = true_contact(s0, f64::from(p.l_m), 0.0);
    assert!(t_c > 4.0);
    let cmds: Vec<TiltCommand> = (0..24u32)
        .map(|k| {
            let b = flight(s0, f64::from(k) * dt - latency);
            c.step(&frame_at(k, b, [0.0, 0.0, 1e38, 0.0]))
        })
        .collect();
    for (k, cmd) in cmds.iter().enumerate() {
        assert_eq!(cmd.fault, Fault::None, "period {k}: {cmd:?}");
    }
    // the first plan, 16 periods in: its impact about 4 s ahead, the reference still far
    let a0 = 7 + usize::from(p.cycle_periods());
    assert!(cmds[..a0].iter().all(|c| c.impact_in_s == 0.0));
    for cmd in &cmds[a0..] {
        assert_eq!(cmd.mode, Mode::Track);
        assert!(cmd.impact_in_s > 3.9 && cmd.stroke_ref_m > 9e37, "{cmd:?}");
    }
}

/// Sequence numbers move forward with wrapping, as the line juggler's
/// (`sequence_numbers_move_forward_with_wrapping` in `control.rs`): a frame up to
/// u32::MAX / 2 - 1 ahead is new, one exactly u32::MAX / 2 ahead counts as old, and its
/// repeats go stale after `stale_limit_steps` (5).
#[test]
fn sequence_numbers_move_forward_with_wrapping_up_to_half_the_range() {
    let mut c = TiltController::new(TiltParams::default()).unwrap();
    let body = [0.0, 0.3, 0.1, 0.0, 0.0, 0.0];
    let mut fault_at = |seq: u32| c.step(&frame_at(seq, body, [0.0; 4])).fault;
    assert_eq!(fault_at(u32::MAX - 1), Fault::None);
    // wraps forward: u32::MAX, 0, 1 are new samples (the stale count never grows)
    for seq in [u32::MAX, 0, 1] {
        for _ in 0..6 {
            assert_eq!(fault_at(seq), Fault::None, "{seq}");
        }
    }
    let far = 1u32.wrapping_add(u32::MAX / 2 - 1);
    for _ in 0..6 {
        assert_eq!(fault_at(far), Fault::None, "new, then 5 repeats");
    }
    let far = far.wrapping_add(1);
    assert_eq!(fault_at(far), Fault::None);
    let beyond = far.wrapping_add(u32::MAX / 2);
    let faults: Vec<Fault> = (0..6).map(|_| fault_at(beyond)).collect();
    assert_eq!(faults[..5], [Fault::None; 5], "5 repeats are tolerated");
    assert_eq!(faults[5], Fault::Stale);
}
