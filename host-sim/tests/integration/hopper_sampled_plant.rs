//! The valve-driven hopper plant (`model::hopper::valve`) against closed forms and the exact
//! event-driven simulator: expected values never come from the plant itself.

use dexter_core::hop::RaibertThrust;
use dexter_sim::engine::ode::Integrator;
use dexter_sim::model::hopper::valve::{TrueEvent, ValveModel, ValvePlant};
use dexter_sim::model::hopper::{
    FullNonlinear, Hopper, HopperModel, LinearSpring, RunOptions, Start, ThrustLaw,
};
use std::f64::consts::PI;

fn events(plant: &mut ValvePlant, until_s: f64) -> Vec<TrueEvent> {
    let mut out = Vec::new();
    plant.advance_to(until_s, &mut |e| out.push(e)).unwrap();
    out
}

#[test]
fn flight_and_a_lossless_linear_stance_in_closed_form() {
    // tuned, no friction: omega = sqrt(eta1), the stance is half a period of y = -v/w sin(wt)
    let (g, eta1, chi_l) = (9.81, 40.0, 0.5);
    let m = LinearSpring::new(chi_l, eta1, 0.0, chi_l + g / eta1, 0.0, g).unwrap();
    let mut p = ValvePlant::new(ValveModel::Linear(m), 1.0, 0.0);
    let ev = events(&mut p, 3.0);
    let (t_fall, v) = ((2.0 * 0.5 / g).sqrt(), (2.0 * g * 0.5).sqrt());
    let w = eta1.sqrt();
    let expect = [
        (t_fall, "touchdown"),
        (t_fall + PI / (2.0 * w), "bottom"),
        (t_fall + PI / w, "liftoff"),
        (t_fall + PI / w + v / g, "apex"),
        (t_fall + PI / w + 2.0 * v / g, "touchdown"),
    ];
    for (e, (t, name)) in ev.iter().zip(expect) {
        let (te, ne, check) = match *e {
            TrueEvent::Touchdown {
                time_s,
                velocity_mps,
            } => (time_s, "touchdown", (velocity_mps + v).abs()),
            TrueEvent::Bottom { time_s, height_m } => {
                (time_s, "bottom", (height_m - (chi_l - v / w)).abs())
            }
            TrueEvent::Liftoff {
                time_s,
                velocity_mps,
                during_thrust,
                ..
            } => {
                assert!(!during_thrust);
                (time_s, "liftoff", (velocity_mps - v).abs())
            }
            TrueEvent::Apex { time_s, height_m } => (time_s, "apex", (height_m - 1.0).abs()),
        };
        assert_eq!(ne, name, "{ev:?}");
        assert!((te - t).abs() < 1e-12, "{name}: {te} vs {t}");
        assert!(check < 1e-12, "{name}: {check}");
    }
}

/// From rest at a bottom, the valve open for delta then closed, against the exact simulator's
/// cycle from the same bottom (eq. 8 / 10 with exactly timed thrust).
fn bottom_cycle_matches_exact(model: ValveModel, hm: HopperModel, x_b: f64, tol: f64) {
    let (tau, delta) = (41.86, 0.05);
    let exact = Hopper::new(
        hm,
        ThrustLaw::Raibert(RaibertThrust::new(tau, delta).unwrap()),
    )
    .unwrap()
    .simulate(Start::Bottom { height_m: x_b }, 1, &RunOptions::default())
    .unwrap();
    let c = exact.cycles[0];
    let mut p = ValvePlant::in_stance(model, x_b, 0.0);
    p.set_valve(true, tau);
    let mut ev = events(&mut p, delta);
    let s = *p.state();
    assert!(
        (s.height_m - c.end_of_thrust.height_m).abs() < tol,
        "end of thrust"
    );
    assert!((s.velocity_mps - c.end_of_thrust.velocity_mps).abs() < tol);
    p.set_valve(false, 0.0);
    ev.extend(events(&mut p, c.next_touchdown.time_s + 1e-3));
    let liftoff = ev
        .iter()
        .find_map(|e| match *e {
            TrueEvent::Liftoff {
                time_s,
                velocity_mps,
                ..
            } => Some((time_s, velocity_mps)),
            _ => None,
        })
        .unwrap();
    let touchdown = ev
        .iter()
        .find_map(|e| match *e {
            TrueEvent::Touchdown { time_s, .. } => Some(time_s),
            _ => None,
        })
        .unwrap();
    assert!(
        (liftoff.0 - c.liftoff.time_s).abs() < tol,
        "{liftoff:?} vs {:?}",
        c.liftoff
    );
    assert!((liftoff.1 - c.liftoff.velocity_mps).abs() < tol);
    assert!((touchdown - c.next_touchdown.time_s).abs() < tol);
}

#[test]
fn linear_thrust_and_decompression_match_the_exact_simulator() {
    let g = 9.81;
    let m = LinearSpring::new(0.5, 46.5, 2.33, 0.5 + g / 46.5, 0.0, g).unwrap();
    bottom_cycle_matches_exact(ValveModel::Linear(m), HopperModel::Linear(m), 0.2, 1e-11);
}

#[test]
fn full_thrust_sealing_and_decompression_match_the_exact_simulator() {
    // eq. 8: closing the valve seals the gas at eta2 = tau chi_et, as the exact model does
    let m = FullNonlinear::new(
        0.5,
        5.81,
        2.33,
        0.25,
        10.0,
        Integrator::rk45(1e-11, 1e-4).unwrap(),
    )
    .unwrap();
    bottom_cycle_matches_exact(ValveModel::Full(m), HopperModel::Full(m), 0.15, 1e-7);
}

#[test]
fn pieces_compose_and_an_open_valve_in_flight_does_nothing() {
    let g = 9.81;
    let m = LinearSpring::new(0.5, 46.5, 2.33, 0.5 + g / 46.5, 0.0, g).unwrap();
    let mut one = ValvePlant::new(ValveModel::Linear(m), 1.0, 0.0);
    let mut many = ValvePlant::new(ValveModel::Linear(m), 1.0, 0.0);
    // touchdown at sqrt(2 * 0.5 / g) = 0.3193 s: until 0.31 s both fly, one with the valve open
    many.set_valve(true, 41.86);
    events(&mut one, 0.31);
    for k in 1..=310 {
        events(&mut many, f64::from(k) * 1e-3);
    }
    assert!((one.state().height_m - many.state().height_m).abs() < 1e-12);
    assert!(!many.state().contact);
    many.set_valve(false, 0.0);
    // then through touchdown, bottom and liftoff: one call against 1 ms pieces
    let ev_one = events(&mut one, 1.2);
    let mut ev_many = Vec::new();
    for k in 311..=1200 {
        ev_many.extend(events(&mut many, f64::from(k) * 1e-3));
    }
    let (a, b) = (one.state(), many.state());
    assert!((a.height_m - b.height_m).abs() < 1e-12, "{a:?} {b:?}");
    assert!((a.velocity_mps - b.velocity_mps).abs() < 1e-12);
    assert_eq!(ev_one.len(), ev_many.len());
    assert!(ev_one.len() >= 3, "{ev_one:?}");
}

#[test]
fn a_weak_thrust_that_still_reaches_full_extension_lifts_off() {
    // 1 mm below chi_l rising at 1 m/s, the valve open with tau = g/2 (net a = -g/2), no
    // friction: chi reaches chi_l at the smaller root of a/2 t^2 + v t - 1e-3 = 0 and the
    // leg leaves the ground there, although chi would fall back below chi_l within the span
    let g = 9.81;
    let m = LinearSpring::new(0.5, 46.5, 0.0, 0.5 + g / 46.5, 0.0, g).unwrap();
    let mut p = ValvePlant::in_stance(ValveModel::Linear(m), 0.499, 1.0);
    p.set_valve(true, 0.5 * g);
    let ev = events(&mut p, 0.5);
    let a = -0.5 * g;
    let t = (-1.0 + (1.0f64 + 2.0 * a * 1e-3).sqrt()) / a;
    let lift = ev.iter().find_map(|e| match *e {
        TrueEvent::Liftoff {
            time_s,
            during_thrust,
            ..
        } => Some((time_s, during_thrust)),
        _ => None,
    });
    let (tl, during) = lift.expect("no liftoff");
    assert!((tl - t).abs() < 1e-12, "{tl} vs {t}");
    assert!(during, "an early liftoff, during the thrust");
    assert!(!p.state().contact || p.state().time_s > 0.2);
}
