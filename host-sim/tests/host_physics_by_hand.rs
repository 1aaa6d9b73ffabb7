//! Tests that catch physics mutants of the host's event engine (issue 22, "Tests that must
//! fail"): the contact finder's guards and grazing tolerance (`engine/roots.rs`), the cheap
//! contact test's coefficients (`engine/flight.rs`), and the plant's clock across surface
//! segment switches (`model/line.rs`). Expected values are closed forms: ballistic flight,
//! the quadratic's roots, and the documented grazing rule.

use dexter_core::state::{BallState, PaddleState};
use dexter_sim::effects::jitter::NoJitter;
use dexter_sim::engine::roots::first_contact;
use dexter_sim::engine::zeno::ZenoPolicy;
use dexter_sim::engine::{Ballistic, Flight, FlightEnd, Poly};
use dexter_sim::model::line::{Advance, LinePlant};
use dexter_sim::model::surface::Surface;

const G: f64 = 9.81;

/// Any non-finite coefficient or window gives no contact, even where the finite ones alone
/// would give one (a guard weakened to "all non-finite" or "any finite" lets these through).
#[test]
fn a_non_finite_coefficient_or_window_is_never_a_contact() {
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    for (c0, c1, c2, h) in [
        (1.0, -1.0, 0.0, inf), // closing at 1 m/s: t = 1 would be in an infinite window
        (1.0, -1.0, 0.0, nan), // the same, window NaN
        (-1e-12, -1.0, nan, 1.0), // touching and closing, c2 NaN
        (-inf, -1.0, 0.0, 1.0), // c0 -inf
        (0.0, -1.0, inf, 1.0), // c2 inf
        (1.0, -inf, 0.0, 1.0), // c1 -inf
        (1.0, -1.0, -inf, 1.0), // c2 -inf
    ] {
        assert_eq!(first_contact(c0, c1, c2, h), None, "{c0} {c1} {c2} {h}");
    }
}

/// A ball touching the paddle (gap 0) and closing is a contact now, at t = 0: closing at a
/// speed (c1 < 0) is an impact, not a graze; closing by curvature only (c1 = 0, c2 < 0) is
/// a graze.
#[test]
fn touching_and_closing_is_a_contact_at_once_and_a_graze_only_without_speed() {
    let c = first_contact(0.0, -2.0, 1.0, 1.0).expect("closing at 2 m/s");
    assert_eq!((c.time_s, c.grazing), (0.0, false));
    let c = first_contact(-1e-15, -0.5, -4.9, 1.0).expect("closing, penetrating by rounding");
    assert_eq!((c.time_s, c.grazing), (0.0, false));
    let c = first_contact(0.0, 0.0, -4.9, 1.0)
        .expect("at rest relative to the paddle, the gap curving down");
    assert_eq!((c.time_s, c.grazing), (0.0, true));
    // touching and separating with a paddle accelerating up less than gravity: the ball
    // comes back at t = -c1/c2 (the other root of t (c1 + c2 t))
    let c = first_contact(0.0, 2.0, -4.905, 1.0).expect("the ball falls back");
    assert!((c.time_s - 2.0 / 4.905).abs() < 1e-12, "{}", c.time_s);
    assert!(!c.grazing);
}

/// The grazing rule (module docs of `engine/roots.rs`): a tangency whose discriminant
/// rounds below zero by at most 16 ulps of the terms' size, 16 eps (c1^2 + |4 c0 c2|),
/// is a contact at the vertex -c1 / (2 c2); further below it is a miss. Built with
/// c1 = -20, c2 = 1, c0 = 100 + k ulp(100): disc = -4 k ulp(100), tolerance 16 eps 800.
#[test]
fn a_tangency_within_the_documented_tolerance_is_a_graze_and_beyond_it_a_miss() {
    let ulp = 100f64.next_up() - 100.0;
    let tol = 16.0 * f64::EPSILON * 800.0;
    let k_edge = tol / (4.0 * ulp); // 50: disc = -tol
    assert!((k_edge - 50.0).abs() < 1e-9, "{k_edge}");
    for k in [0u32, 10, 40, 48] {
        let c0 = 100.0 + f64::from(k) * ulp;
        let c = first_contact(c0, -20.0, 1.0, 20.0).unwrap_or_else(|| panic!("k = {k}"));
        assert!(c.grazing, "k = {k}");
        assert!((c.time_s - 10.0).abs() < 1e-9, "k = {k}: {}", c.time_s);
    }
    for k in [52u32, 60, 1000] {
        let c0 = 100.0 + f64::from(k) * ulp;
        assert_eq!(first_contact(c0, -20.0, 1.0, 20.0), None, "k = {k}");
    }
}

/// A ball leaving a gap that has underflowed to the smallest subnormal comes back down at
/// t = c1 / |c2| (the other root): the root at -0 of c0/q is not a contact (a window that
/// let t = 0 in would re-impact at once, a Zeno chatter from rounding).
#[test]
fn leaving_a_subnormal_gap_the_next_contact_is_the_return() {
    let c = first_contact(5e-324, 8.0, -1.0, 10.0).expect("the ball comes back");
    assert!((c.time_s - 8.0).abs() < 1e-12, "{}", c.time_s);
}

/// `fly_short` rules contacts out from the same quadratic as `fly`, and both find the
/// contact at its closed-form time:
/// - the paddle accelerating up at 100 m/s^2 under a ball 0.1 m above it and at rest
///   relative to it: gap 0.1 - (g + 100) t^2 / 2, zero at t = sqrt(0.2 / (g + 100));
/// - a paddle in free fall (acceleration -g: no quadratic term) rising at 1 m/s into a
///   ball 0.1 m above it falling at 1 m/s: gap 0.1 - 2 t, zero at t = 0.05 s.
///
/// Both sit a metre up, so a gap taken as a sum of heights, or a closing speed as a sum of
/// speeds, would wrongly rule the contact out.
#[test]
fn the_cheap_contact_test_sees_a_paddle_accelerating_into_the_ball() {
    let cases = [
        (1.1, 1.0, 1.0, 1.0, 100.0, (0.2 / (G + 100.0)).sqrt()),
        (1.1, -1.0, 1.0, 1.0, -G, 0.05),
    ];
    for (ball_h, ball_v, pad_h, pad_v, pad_a, t) in cases {
        let paddle = Poly {
            height_m: pad_h,
            velocity_mps: pad_v,
            accel_mps2: pad_a,
        };
        for short in [false, true] {
            let mut ball = BallState::new(ball_h, ball_v);
            let end = match short {
                true => Ballistic.fly_short(&mut ball, &paddle, 0.1, G),
                false => Ballistic.fly(&mut ball, &paddle, 0.1, G),
            };
            match end {
                FlightEnd::Contact { dt_s, grazing } => {
                    assert!((dt_s - t).abs() < 1e-12, "short {short}: {dt_s} vs {t}");
                    assert!(!grazing);
                }
                other => panic!("short {short}, paddle {pad_a}: {other:?}"),
            }
            assert!((ball.height_m - paddle.height_at(t)).abs() < 1e-12);
        }
    }
}

/// A fixed table at height 0 whose segments end every `every_s` (as an actuator's regime
/// switches would): the plant's clock must add up the segments exactly.
#[derive(Clone, Copy, Debug)]
struct SwitchingTable {
    every_s: f64,
    into_segment_s: f64,
    switches: u64,
}

impl Surface for SwitchingTable {
    fn poly(&self) -> Poly {
        Poly::default()
    }
    fn max_segment_s(&self, _within_s: f64) -> f64 {
        self.every_s - self.into_segment_s
    }
    fn advance(&mut self, dt_s: f64, to_switch: bool) {
        if to_switch {
            self.into_segment_s = 0.0;
            self.switches += 1;
        } else {
            self.into_segment_s += dt_s;
        }
    }
    fn at_impact(&self, _ball: &BallState<f64>, _g: f64) -> (f64, f64) {
        (0.0, 0.0)
    }
    fn state(&self, _ball: &BallState<f64>) -> PaddleState<f64> {
        PaddleState::new(0.0, 0.0)
    }
    fn command(&mut self, _accel_mps2: f64) {}
    fn rest_is_final(&self) -> bool {
        false
    }
}

fn plant(ball: BallState<f64>, restitution: f64) -> LinePlant<Ballistic, SwitchingTable, NoJitter> {
    let table = SwitchingTable {
        every_s: 1e-3,
        into_segment_s: 0.0,
        switches: 0,
    };
    let zeno = ZenoPolicy {
        velocity_threshold_mps: 1e-6,
        relative_threshold: 0.0,
        max_impacts_per_segment: 64,
    };
    LinePlant::new(G, restitution, Ballistic, table, NoJitter, zeno, ball)
}

/// Dropped from 1 m onto a table whose segments switch every millisecond, the ball lands
/// at sqrt(2 / g) and, with e = 0.5, again 2 e sqrt(2 / g) later: the clock adds up the
/// ~450 and ~450 flight segments across the switches exactly, and it ends at the
/// requested time.
#[test]
fn the_clock_adds_up_flight_segments_across_switches() {
    let mut p = plant(BallState::new(1.0, 0.0), 0.5);
    let mut times = Vec::new();
    let end = p.advance_to(1.5, 2, &mut |r| times.push(r.time_s));
    assert_eq!(end, Advance::ImpactLimit);
    let t1 = (2.0 / G).sqrt();
    let t2 = t1 + 2.0 * 0.5 * t1;
    assert!((times[0] - t1).abs() < 1e-9, "{} vs {t1}", times[0]);
    assert!((times[1] - t2).abs() < 1e-9, "{} vs {t2}", times[1]);
    assert!(p.surface.switches >= 900, "{}", p.surface.switches);
    assert_eq!(p.advance_to(2.0, 10, &mut |_| {}), Advance::ImpactLimit);
    let mut q = plant(BallState::new(1.0, 0.0), 0.5);
    assert_eq!(q.advance_to(0.3, 10, &mut |_| {}), Advance::Reached);
    assert_eq!(q.time_s, 0.3);
    assert!((q.ball.height_m - (1.0 - 0.5 * G * 0.09)).abs() < 1e-12);
}

/// A ball at rest on the switching table rides it across every switch: the clock reaches
/// the requested time and the ball stays on the table.
#[test]
fn the_clock_adds_up_a_ride_across_switches() {
    let mut p = plant(BallState::new(0.0, 0.0), 0.0);
    p.resting = true;
    assert_eq!(p.advance_to(0.0105, 10, &mut |_| {}), Advance::Reached);
    assert_eq!(p.time_s, 0.0105);
    assert_eq!(p.surface.switches, 10);
    assert_eq!((p.ball.height_m, p.ball.velocity_mps), (0.0, 0.0));
    assert_eq!(p.impacts, 0);
}

// ---- the sampled cargo-mutants pass over the host physics (docs/mutants.md, issue 22) ----

/// A contact at the window's start is inside a window of length zero (`[0, h]` with h = 0:
/// a ball touching and closing at a segment switch), and a negative window holds none.
#[test]
fn a_zero_length_window_holds_the_contact_at_its_start_and_a_negative_one_none() {
    let c = first_contact(0.0, -1.0, 0.0, 0.0).expect("touching and closing, h = 0");
    assert_eq!((c.time_s, c.grazing), (0.0, false));
    let c = first_contact(0.0, 0.0, -1.0, 0.0).expect("touching, curving in, h = 0");
    assert_eq!((c.time_s, c.grazing), (0.0, true));
    for (c0, c1, c2) in [(0.0, -1.0, 0.0), (1.0, -1.0, 0.0), (0.0, 0.0, -1.0)] {
        assert_eq!(first_contact(c0, c1, c2, -1.0), None, "{c0} {c1} {c2}");
    }
}

/// A take-off at the smallest subnormal speed, 5e-324 m/s relative to a paddle closing at
/// 8 m/s^2 relative: its return, 2 u / 8 ~ 1.2e-324 s later, is not representable after 0,
/// so there is no contact ahead. A contact at t = 0 would be a second impact at the very
/// instant of the first (a rounding chatter).
#[test]
fn a_take_off_whose_return_underflows_is_not_an_immediate_re_impact() {
    assert_eq!(first_contact(0.0, 5e-324, -4.0, 1.0), None);
    // a normal take-off at 2 m/s comes back at 2 u / 8 = 0.5 s
    let c = first_contact(0.0, 2.0, -4.0, 1.0).expect("the return");
    assert_eq!((c.time_s, c.grazing), (0.5, false));
}

/// A subnormal take-off speed still comes back at 2 u / g: u = 2^-1060 m/s against
/// 2 c2 = -8 m/s^2 returns at 2^-1062 s exactly (representable: the smallest subnormal is
/// 2^-1074). Squaring u underflows to 0, so the discriminant formula gave half of that.
#[test]
fn a_subnormal_take_off_returns_after_the_ballistic_time() {
    let u = 2f64.powi(-1060);
    assert!(u > 0.0 && !u.is_normal());
    let c = first_contact(0.0, u, -4.0, 1.0).expect("the return");
    assert_eq!(c.time_s, 2f64.powi(-1062));
    // and a take-off too fast to square (u^2 overflows) as well: 2^600 / 4 = 2^598 s
    let c = first_contact(0.0, 2f64.powi(600), -4.0, f64::MAX).expect("the return");
    assert_eq!(c.time_s, 2f64.powi(598));
}

/// The paddle's velocity over a segment is v + a t (its height's derivative).
#[test]
fn the_paddles_velocity_is_its_start_velocity_plus_acceleration_times_time() {
    let p = Poly {
        height_m: 0.25,
        velocity_mps: -1.5,
        accel_mps2: 4.0,
    };
    for t in [0.0, 0.125, 0.5, 2.0] {
        assert_eq!(p.velocity_at(t), -1.5 + 4.0 * t, "t = {t}");
        // and it is the height's derivative (central difference, exact for a quadratic
        // up to rounding)
        let dh = (p.height_at(t + 1e-3) - p.height_at(t - 1e-3)) / 2e-3;
        assert!((dh - p.velocity_at(t)).abs() < 1e-9, "t = {t}: {dh}");
    }
}

/// Drag-free apex of the drag model (c = 0): h + v^2 / (2 g), as the ballistic one.
#[test]
fn the_drag_models_apex_without_drag_is_the_ballistic_apex() {
    use dexter_sim::engine::drag::{DragFlight, Rk4};
    let fl = DragFlight::new(Rk4, 0.0, 1e-3, 0.0);
    let ball = BallState::new(0.5, 3.0);
    assert_eq!(fl.apex_m(&ball, G), 0.5 + 9.0 / (2.0 * G));
    assert_eq!(Ballistic.apex_m(&ball, G), 0.5 + 9.0 / (2.0 * G));
    assert_eq!(
        fl.apex_m(&BallState::new(0.5, -3.0), G),
        0.5,
        "falling: its height"
    );
}

/// A ball on the paddle, moving with it (same height, same velocity), while the paddle
/// accelerates down at 20 m/s^2 > g: the ball leaves it and flies the whole window. With
/// quadratic drag its rise is the closed form y = (vt^2 / g) ln(cos(th0 - g t / vt) / cos th0),
/// v = vt tan(th0 - g t / vt), vt = sqrt(g / c), th0 = atan(v0 / vt). A contact at once
/// would glue the ball to a paddle that falls away faster than gravity.
#[test]
fn a_ball_moving_with_a_paddle_that_falls_away_faster_than_g_leaves_it() {
    use dexter_sim::engine::drag::{DragFlight, Rk4};
    let (c, v0, h) = (0.01, 1.0, 0.1);
    let paddle = Poly {
        height_m: 0.0,
        velocity_mps: v0,
        accel_mps2: -20.0,
    };
    let mut fl = DragFlight::new(Rk4, c, 1e-3, 0.0);
    let mut ball = BallState::new(0.0, v0);
    assert_eq!(fl.fly(&mut ball, &paddle, h, G), FlightEnd::Reached(h));
    let vt = (G / c).sqrt();
    let th0 = (v0 / vt).atan();
    assert!(th0 * vt / G > h, "still rising at the window's end");
    let th = th0 - G * h / vt;
    let y = vt * vt / G * (th.cos() / th0.cos()).ln();
    let v = vt * th.tan();
    assert!((ball.height_m - y).abs() < 1e-9, "{} vs {y}", ball.height_m);
    assert!(
        (ball.velocity_mps - v).abs() < 1e-9,
        "{} vs {v}",
        ball.velocity_mps
    );
    assert!(ball.height_m > paddle.height_at(h));
}

/// The switching table of the clock tests, flown over without an impact: after 10.5 ms the
/// table has switched exactly 10 times and is 0.5 ms into its 11th segment (the last,
/// partial flight segment is no switch).
#[test]
fn a_flight_ending_inside_a_segment_does_not_switch_the_surface() {
    let mut p = plant(BallState::new(1.0, 0.0), 0.5);
    assert_eq!(p.advance_to(0.0105, 10, &mut |_| {}), Advance::Reached);
    assert_eq!(p.time_s, 0.0105);
    assert_eq!(p.surface.switches, 10);
    assert!(
        (p.surface.into_segment_s - 0.0005).abs() < 1e-12,
        "{}",
        p.surface.into_segment_s
    );
    assert!((p.ball.height_m - (1.0 - 0.5 * G * 0.0105 * 0.0105)).abs() < 1e-12);
}

/// On a driven surface (one whose rest is not final) the ball's impacts within one
/// `advance_to` call are capped (`ZenoPolicy::max_impacts_per_segment`, 64): with Zeno
/// detection off (thresholds 0) a ball dropped from 1 m with e = 1/2 would bounce until its
/// speed underflows; the cap forces resting contact at the 64th impact, at
/// t1 (1 + 2 e (1 - e^63) / (1 - e)) = 3 t1 (to rounding), t1 = sqrt(2 / g).
#[test]
fn impacts_beyond_the_cap_in_one_call_force_resting_contact() {
    let table = SwitchingTable {
        every_s: 1e-3,
        into_segment_s: 0.0,
        switches: 0,
    };
    let zeno = ZenoPolicy {
        velocity_threshold_mps: 0.0,
        relative_threshold: 0.0,
        max_impacts_per_segment: 64,
    };
    let mut p = LinePlant::new(
        G,
        0.5,
        Ballistic,
        table,
        NoJitter,
        zeno,
        BallState::new(1.0, 0.0),
    );
    assert_eq!(p.advance_to(2.0, 100_000, &mut |_| {}), Advance::Reached);
    assert_eq!(p.impacts, 64);
    assert_eq!(p.rest_count, 1);
    let rest = p.rests[0];
    assert!(rest.forced);
    assert_eq!(rest.after_impacts, 64);
    let t1 = (2.0 / G).sqrt();
    assert!(
        (rest.time_s - 3.0 * t1).abs() < 1e-9,
        "{} vs {}",
        rest.time_s,
        3.0 * t1
    );
    assert_eq!((p.ball.height_m, p.ball.velocity_mps), (0.0, 0.0));
}

/// `window(p) = max(4 p, 12)` differences, `values_needed(p) = window(p) + p` values (module
/// docs of `period.rs`), and a sequence of exactly that many values is judged: an exact
/// period-p orbit of `values_needed(p)` values has period p, one value fewer is too short.
#[test]
fn the_period_window_is_max_of_4p_and_12_and_exactly_that_many_values_suffice() {
    use dexter_sim::period::{settled_period, values_needed, window, Tolerance};
    for p in 1..=8usize {
        assert_eq!(window(p), (4 * p).max(12), "p = {p}");
        assert_eq!(values_needed(p), (4 * p).max(12) + p, "p = {p}");
        let orbit: Vec<f64> = (0..values_needed(p))
            .map(|k| 1.0 + 0.25 * (k % p) as f64)
            .collect();
        let tol = Tolerance::Relative(1e-3);
        assert_eq!(settled_period(&orbit, p, tol), Some(p), "p = {p}");
        assert_eq!(
            settled_period(&orbit[1..], p, tol),
            None,
            "p = {p}, one short"
        );
    }
}

/// Rule 1 (module docs of `period.rs`): every one of the last max(4p, 12) differences must
/// be within the tolerance. 1 + 0.5 (1/10)^k for k = 0..12 has converged to 1 by its last
/// value (its geometric tail bound is ~5e-12), but its first difference in the window,
/// 0.45, is not within 1e-3: not settled. Twelve values later the window is clear.
#[test]
fn a_difference_beyond_the_tolerance_in_the_window_is_not_settled() {
    use dexter_sim::period::{settled_period, Tolerance};
    let tol = Tolerance::Relative(1e-3);
    let v: Vec<f64> = (0..13).map(|k| 1.0 + 0.5 * 0.1f64.powi(k)).collect();
    assert_eq!(settled_period(&v, 1, tol), None);
    let v: Vec<f64> = (0..26).map(|k| 1.0 + 0.5 * 0.1f64.powi(k)).collect();
    assert_eq!(settled_period(&v, 1, tol), Some(1));
}

/// Rules 2 and 3 near a flip: 1 + 1e-7 (-0.9999)^k converges to period 1 so slowly that
/// its lag-1 differences (2e-7) bound the remaining motion only by 2e-7 / (1 - 0.9999) =
/// 2e-3 > 1e-3 (not settled to 1), while its lag-2 differences are within 1e-7 of zero:
/// rule 2 alone would call it period 2. Its lag-1 differences still shrink (by 0.9999^14
/// across the window, a relative 1.4e-3 > DIVISOR_DECAY): still converging to period 1,
/// so no period.
#[test]
fn an_orbit_still_converging_to_half_its_period_has_none() {
    use dexter_sim::period::{settled_period, Tolerance};
    let tol = Tolerance::Relative(1e-3);
    for n in [40, 100] {
        let v: Vec<f64> = (0..n).map(|k| 1.0 + 1e-7 * (-0.9999f64).powi(k)).collect();
        assert_eq!(settled_period(&v, 8, tol), None, "n = {n}");
    }
}

/// A genuine period-2 orbit, [1, 1.5] plus a transient 0.3 / 2^k long gone by the window
/// (below 1e-12 of the values there): period 2. Its lag-1 differences over the window repeat
/// (0.5 to 1e-13): not converging to period 1, whatever the transient was before the window.
#[test]
fn a_period_two_orbit_after_a_transient_has_period_two() {
    use dexter_sim::period::{settled_period, Tolerance};
    let tol = Tolerance::Relative(1e-3);
    for n in [40, 60, 100] {
        let v: Vec<f64> = (0..n)
            .map(|k| [1.0, 1.5][k % 2] + 0.3 * 0.5f64.powi(k as i32))
            .collect();
        assert_eq!(settled_period(&v, 8, tol), Some(2), "n = {n}");
    }
}

/// The gap `c0 + c1 t + c2 t^2` at a double `t`, exactly (every f64 is a dyadic rational).
fn exact_gap(c0: f64, c1: f64, c2: f64, t: f64) -> num_rational::BigRational {
    let q = |x: f64| num_rational::BigRational::from_float(x).expect("finite");
    q(c0) + q(c1) * q(t) + q(c2) * q(t) * q(t)
}

/// The time of first contact of a separated, closing gap is its exact root to within one
/// ulp: the exact gap (rational arithmetic, independent of the code's rounding) changes
/// sign between the doubles on either side of the answer. In each case the closed-form root
/// alone is two or more ulps off, so the one Newton step that polishes it is what gets it
/// there (found by a search over random closing gaps against the exact gap).
#[test]
fn a_separated_gaps_first_contact_is_its_exact_root_within_an_ulp() {
    for (c0, c1, c2) in [
        (
            0.10609863217664363,
            -0.10464230983699695,
            -6.974701354411441,
        ),
        (0.8814757455036015, -0.4598314184580483, -3.3700422171601874),
        (
            0.08429224842461425,
            -0.5476335247081249,
            -3.9151087955132313,
        ),
        (1.35696116043066, -3.7843874823911072, -3.75608532459516),
        (0.6216985775224396, -4.920863474458172, -5.568388076304782),
    ] {
        let t = first_contact(c0, c1, c2, 1.0).expect("a contact").time_s;
        let before = sign_of(&exact_gap(c0, c1, c2, t.next_down()));
        let after = sign_of(&exact_gap(c0, c1, c2, t.next_up()));
        assert!(
            before >= 0 && after <= 0,
            "gap ({c0}, {c1}, {c2}): t = {t} is not within an ulp of the root"
        );
        // and the unpolished closed form (q / c2 or c0 / q) is not, which is what makes
        // this a test of the polish
        let q = -0.5 * (c1 - (c1 * c1 - 4.0 * c0 * c2).sqrt());
        let raw = (q / c2).min(c0 / q);
        let raw = if raw > 0.0 { raw } else { (q / c2).max(c0 / q) };
        let (b, a) = (
            sign_of(&exact_gap(c0, c1, c2, raw.next_down())),
            sign_of(&exact_gap(c0, c1, c2, raw.next_up())),
        );
        assert!(
            !(b >= 0 && a <= 0),
            "({c0}, {c1}, {c2}): the closed form is already there"
        );
    }
}

/// -1, 0 or 1: the sign of an exact rational (its denominator is kept positive).
fn sign_of(x: &num_rational::BigRational) -> i32 {
    match x.numer().sign() {
        num_bigint::Sign::Minus => -1,
        num_bigint::Sign::NoSign => 0,
        num_bigint::Sign::Plus => 1,
    }
}
