//! The vertical hopper (issue 6) against the closed forms of Koditschek & Bühler (1991)
//! from `dexter_core::hop` and against computations written here from the paper's
//! equations (eq. 12/13 energy integrals, eq. 17 from eq. 23–25, a brute-force RK4 of the
//! stance ODEs). No expected value is copied from the simulator's own output.

use dexter_core::hop::{
    energy_fixed_point, energy_of_bottom, energy_return_map, leg_mass_factor, nonlinear_return_map,
    EnergyServoThrust, RaibertThrust,
};
use dexter_core::params::ParamError;
use dexter_sim::engine::ode::Integrator;
use dexter_sim::model::hopper::analysis::{
    bottom_heights, detect_period, energies, locate_first_doubling, return_map, sweep_thrust,
};
use dexter_sim::model::hopper::nonlinear::dawson;
use dexter_sim::model::hopper::{
    FullNonlinear, Hopper, HopperError, HopperModel, HopperParams, LinearSpring, RunEnd,
    RunOptions, SimplifiedNonlinear, Start, ThrustLaw,
};
use std::f64::consts::{E, PI};

const E2: f64 = E * E;
const MAP_ONLY: RunOptions = RunOptions {
    times: false,
    samples_per_phase: 0,
};

/// Table 1, fig. 11: chi_l = 0.5 m, eta1 = 5.81 m^2/s^2, tau = 41.86 m/s^2, g = 0/10.
fn eq9(leg: f64) -> SimplifiedNonlinear {
    SimplifiedNonlinear::new(0.5, 5.81, leg, 10.0).unwrap()
}

fn raibert(tau: f64, delta: f64) -> ThrustLaw {
    ThrustLaw::Raibert(RaibertThrust::new(tau, delta).unwrap())
}

fn eq9_hopper(leg: f64, tau: f64) -> Hopper {
    Hopper::new(
        HopperModel::SimplifiedNonlinear(eq9(leg)),
        raibert(tau, 0.0),
    )
    .unwrap()
}

fn scene(fig: &str) -> HopperParams {
    let path = format!(
        "{}/../scenes/hopper-fig{fig}.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(&path).unwrap();
    let first = text.lines().next().unwrap();
    assert!(
        first.starts_with("# Fig. ") && first.contains(fig.trim_start_matches('0')),
        "{path}: first line names the figure"
    );
    HopperParams::from_toml_str(&text).unwrap()
}

// ---------------------------------------------------------------------------------------
// eq. 9 / 15 / 19

#[test]
fn eq9_simulated_return_map_equals_eq15_and_eq19() {
    let mut worst_x: f64 = 0.0;
    let mut worst_e: f64 = 0.0;
    for &(leg, alpha) in &[
        (0.0, 3.602_41),
        (0.0, 6.0),
        (0.25, 5.0),
        (0.0, 9.0),
        (0.5, 14.0),
        (0.0, 20.0),
    ] {
        let m = eq9(leg);
        let mu = leg_mass_factor(leg);
        let tau = alpha * 5.81 / (0.5 * mu);
        let h = eq9_hopper(leg, tau);
        for start in [
            Start::Flight {
                height_m: 1.15,
                velocity_mps: 0.0,
            },
            Start::Flight {
                height_m: 0.5 + 1e-3,
                velocity_mps: 0.3,
            },
            Start::Bottom { height_m: 0.02 },
            Start::Bottom { height_m: 0.45 },
        ] {
            let run = h.simulate(start, 200, &RunOptions::default()).unwrap();
            assert_eq!(run.end, RunEnd::Completed);
            let x = bottom_heights(&run.cycles);
            for (a, b) in return_map(&x) {
                let g = nonlinear_return_map(a, tau, mu, m.spring_eta1(), 0.5);
                worst_x = worst_x.max((b - g).abs());
            }
            let e = energies(&run.cycles);
            for (n, (a, b)) in return_map(&e).into_iter().enumerate() {
                worst_e = worst_e.max((b - energy_return_map(a, alpha)).abs() / (1.0 + a));
                // E_n is eq. 18's h(x_n)
                assert!((e[n] - energy_of_bottom(x[n], 0.5)).abs() < 1e-9 * (1.0 + e[n]));
            }
        }
    }
    println!("eq. 15: max |x_n+1 - g(x_n)| = {worst_x:e} m; eq. 19: max rel |E_n+1 - f(E_n)| = {worst_e:e}");
    assert!(worst_x <= 1e-10, "{worst_x}");
    assert!(worst_e <= 1e-10, "{worst_e}");
}

/// Dawson's integral against its Maclaurin series D(a) = sum (-1)^k 2^k a^(2k+1) / (2k+1)!!
/// and, for large a, its asymptotic series 1/(2a) (1 + 1/(2a^2) + 3/(4a^4) + 15/(8a^6)).
#[test]
fn dawson_integral_matches_its_series() {
    for &a in &[0.05, 0.3, 1.0, 1.5, 2.5] {
        let (mut term, mut sum) = (a, a);
        for k in 1..200 {
            term *= -2.0 * a * a / (2 * k + 1) as f64;
            sum += term;
        }
        assert!(
            (dawson(a) - sum).abs() < 1e-14,
            "a {a}: {} vs {sum}",
            dawson(a)
        );
    }
    // (the next term, 105/(16 a^8) relative, is below 1e-14 from a = 100 on)
    for &a in &[100.0, 1e3, 1e4] {
        let x = 1.0 / (a * a);
        let asym = 0.5 / a * (1.0 + x / 2.0 + 0.75 * x * x + 1.875 * x * x * x);
        assert!((dawson(a) - asym).abs() < 1e-13 * asym, "a {a}");
    }
    assert_eq!(dawson(0.0), 0.0);
}

/// A brute-force RK4 of chi'' = eta / chi from (chi0, v0) until `stop(chi, v)`, with the
/// last step refined by bisection; returns (time, chi, v).
fn rk4_until(
    acc: impl Fn(f64, f64) -> f64,
    mut y: (f64, f64),
    h: f64,
    stop: impl Fn(f64, f64) -> bool,
) -> (f64, f64, f64) {
    let step = |y: (f64, f64), h: f64| {
        let k1 = (y.1, acc(y.0, y.1));
        let k2 = (
            y.1 + 0.5 * h * k1.1,
            acc(y.0 + 0.5 * h * k1.0, y.1 + 0.5 * h * k1.1),
        );
        let k3 = (
            y.1 + 0.5 * h * k2.1,
            acc(y.0 + 0.5 * h * k2.0, y.1 + 0.5 * h * k2.1),
        );
        let k4 = (y.1 + h * k3.1, acc(y.0 + h * k3.0, y.1 + h * k3.1));
        (
            y.0 + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
            y.1 + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
        )
    };
    let mut t = 0.0;
    for _ in 0..10_000_000 {
        let y1 = step(y, h);
        if stop(y1.0, y1.1) {
            let (mut lo, mut hi) = (0.0, h);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if stop(step(y, mid).0, step(y, mid).1) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let yh = step(y, hi);
            return (t + hi, yh.0, yh.1);
        }
        y = y1;
        t += h;
    }
    panic!("no event");
}

#[test]
fn eq9_stance_times_and_samples_match_direct_integration() {
    // fig. 11 from an apex of 1.15 m: touchdown speed sqrt(2 g (1.15 - 0.5)) = sqrt(13)
    let h = eq9_hopper(0.0, 41.86);
    let opts = RunOptions {
        times: true,
        samples_per_phase: 16,
    };
    let run = h
        .simulate(
            Start::Flight {
                height_m: 1.15,
                velocity_mps: 0.0,
            },
            3,
            &opts,
        )
        .unwrap();
    let c = run.cycles[0];
    let td = c.touchdown.unwrap();
    assert!((td.velocity_mps + 13f64.sqrt()).abs() < 1e-14);
    assert!((td.time_s - (2.0 * 0.65 / 10.0f64).sqrt()).abs() < 1e-14);
    // compression: chi'' = eta1 / chi until chi' = 0
    let (tc, xb, _) = rk4_until(|x, _| 5.81 / x, (0.5, -13f64.sqrt()), 1e-5, |_, v| v >= 0.0);
    assert!(
        (c.bottom.height_m - xb).abs() < 1e-9,
        "{} vs {xb}",
        c.bottom.height_m
    );
    assert!(
        ((c.bottom.time_s - td.time_s) - tc).abs() < 1e-8,
        "compression {} vs {tc}",
        c.bottom.time_s - td.time_s
    );
    // decompression: chi'' = tau x_b / chi until chi = chi_l
    let eta2 = 41.86 * c.bottom_height_m;
    let (td2, _, vl) = rk4_until(
        |x, _| eta2 / x,
        (c.bottom_height_m, 0.0),
        1e-5,
        |x, _| x >= 0.5,
    );
    assert!(((c.liftoff.time_s - c.bottom.time_s) - td2).abs() < 1e-8);
    assert!((c.liftoff.velocity_mps - vl).abs() < 1e-8);
    // flight: apex chi_l + v^2 / 2g, next touchdown after 2 v / g
    let v = c.liftoff.velocity_mps;
    assert!((c.apex.height_m - (0.5 + v * v / 20.0)).abs() < 1e-14);
    assert!((c.next_touchdown.time_s - c.liftoff.time_s - v / 5.0).abs() < 1e-14);
    // every stance sample lies on the eq. 12 curve chi'^2 = 2 eta ln(chi / x_b), and time
    // runs forward
    for w in run.samples.windows(2) {
        assert!(w[1].state.time_s >= w[0].state.time_s - 1e-12);
    }
    for s in run.samples.iter().filter(|s| s.cycle == 0) {
        let eta = match s.phase {
            dexter_core::hop::StancePhase::Compression => 5.81,
            dexter_core::hop::StancePhase::Decompression => eta2,
            _ => continue,
        };
        let st = s.state;
        let rhs = 2.0 * eta * (st.height_m / c.bottom_height_m).ln();
        assert!((st.velocity_mps.powi(2) - rhs).abs() < 1e-10);
    }
    assert!(run.samples.len() <= 3 * 4 * 17 + 17);
}

// ---------------------------------------------------------------------------------------
// Theorem 1: period 1 below e^2, period 2 above, the doubling cascade

#[test]
fn period_one_below_e_squared_period_two_above() {
    let m = eq9(0.0);
    let start = Start::Flight {
        height_m: 1.15,
        velocity_mps: 0.0,
    };
    for &alpha in &[1.5, 2.5, 3.602_41, 5.0, 6.5, 7.0] {
        let h = eq9_hopper(0.0, m.thrust_for_alpha(alpha));
        let run = h.simulate(start, 600, &MAP_ONLY).unwrap();
        let x = bottom_heights(&run.cycles);
        assert_eq!(detect_period(&x, 8, 1e-10), Some(1), "alpha {alpha}");
        // sec. 4.1: x* = chi_l / alpha, E* = ln alpha
        assert!(
            (x.last().unwrap() - 0.5 / alpha).abs() < 1e-10,
            "alpha {alpha}"
        );
        let e = run.cycles.last().unwrap().energy;
        assert!((e - energy_fixed_point(alpha).unwrap()).abs() < 1e-9);
    }
    for &alpha in &[7.6, 8.0, 8.983, 11.0] {
        let h = eq9_hopper(0.0, m.thrust_for_alpha(alpha));
        let run = h.simulate(start, 1500, &MAP_ONLY).unwrap();
        let e = energies(&run.cycles);
        assert_eq!(detect_period(&e, 8, 1e-9), Some(2), "alpha {alpha}");
        // the 2-cycle {p, q} of eq. 19: q = alpha p e^-p, p = alpha q e^-q multiply to
        // p + q = 2 ln alpha; p and q straddle E* = ln alpha
        let (p, q) = (e[e.len() - 1], e[e.len() - 2]);
        assert!((p + q - 2.0 * alpha.ln()).abs() < 1e-9, "alpha {alpha}");
        assert!(p.min(q) < alpha.ln() && p.max(q) > alpha.ln());
    }
}

/// Period of the late orbit of eq. 19 iterated directly with the core's closed form.
fn map_period(alpha: f64, transient: usize) -> Option<usize> {
    let mut e = 1.0;
    for _ in 0..transient {
        e = energy_return_map(e, alpha);
    }
    let mut v = Vec::new();
    for _ in 0..200 {
        e = energy_return_map(e, alpha);
        v.push(e);
    }
    detect_period(&v, 64, 1e-9)
}

#[test]
fn thrust_sweep_shows_the_doubling_cascade() {
    let m = eq9(0.0);
    let h = eq9_hopper(0.0, 41.86);
    let rs = [1.2, 1.9, 2.1, 2.3, 2.45, 2.55, 2.6, 2.65, 2.665, 2.675, 3.0];
    let thrusts: Vec<f64> = rs
        .iter()
        .map(|r| m.thrust_for_alpha(f64::exp(*r)))
        .collect();
    let start = Start::Bottom {
        height_m: 0.5 * (-1.0f64).exp(),
    };
    let pts = sweep_thrust(&h, start, &thrusts, 20_000, 200, 1e-9).unwrap();
    let periods: Vec<Option<usize>> = pts.iter().map(|p| p.period).collect();
    println!("ln(alpha) {rs:?}\nperiods {periods:?}");
    for (p, r) in pts.iter().zip(rs) {
        assert_eq!(p.period, map_period(r.exp(), 20_000), "ln alpha {r}");
        assert_eq!(p.values.len(), 200);
    }
    // 1 -> 2 -> 4 -> 8, then no period (chaos) at ln alpha = 3
    let seen: Vec<usize> = periods.iter().flatten().copied().collect();
    for want in [1, 2, 4, 8] {
        assert!(seen.contains(&want), "period {want} missing: {periods:?}");
    }
    assert!(seen.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(*periods.last().unwrap(), None);
}

#[test]
fn first_doubling_is_located_within_1e4_of_e_squared() {
    for (leg, start, res_alpha) in [
        (
            0.0,
            Start::Flight {
                height_m: 1.15,
                velocity_mps: 0.0,
            },
            2e-5,
        ),
        (0.25, Start::Bottom { height_m: 0.02 }, 1e-6),
    ] {
        let m = eq9(leg);
        let h = Hopper::new(HopperModel::SimplifiedNonlinear(m), raibert(41.86, 0.0)).unwrap();
        let (lo, hi) = (m.thrust_for_alpha(6.0), m.thrust_for_alpha(9.0));
        let res = m.thrust_for_alpha(res_alpha);
        let d = locate_first_doubling(&h, start, lo, hi, 30, 100_000, 1e-10, res).unwrap();
        let alpha = m.alpha(d.estimate_mps2());
        println!(
            "mu' {leg}: first doubling at alpha = {alpha:.9} (e^2 = {E2:.9}, diff {:e}), bracket [{:.9}, {:.9}], {} steps",
            alpha - E2,
            m.alpha(d.below_mps2),
            m.alpha(d.above_mps2),
            d.steps
        );
        assert!(d.steps <= 30);
        assert!(m.alpha(d.below_mps2) <= E2 + 1e-9 && m.alpha(d.above_mps2) >= E2 - 1e-9);
        assert!((alpha - E2).abs() <= 1e-4, "{alpha} vs {E2}");
    }
}

#[test]
fn alpha_exactly_e_squared_converges_slowly_and_stays_on_eq15() {
    // at alpha = e^2 the multiplier is -1: the fixed point attracts only algebraically
    let m = eq9(0.0);
    let tau = m.thrust_for_alpha(E2);
    assert!((m.alpha(tau) - E2).abs() < 1e-14);
    let h = eq9_hopper(0.0, tau);
    let run = h
        .simulate(
            Start::Flight {
                height_m: 1.15,
                velocity_mps: 0.0,
            },
            6000,
            &MAP_ONLY,
        )
        .unwrap();
    let x = bottom_heights(&run.cycles);
    for (a, b) in return_map(&x) {
        assert!((b - nonlinear_return_map(a, tau, 1.0, 5.81, 0.5)).abs() <= 1e-10);
    }
    let e = energies(&run.cycles);
    let amp = |n: usize| (e[n] - e[n - 1]).abs();
    // amplitude shrinks like n^-1/2 (normal form a' = a - c a^3): sqrt(10) from 600 to 6000
    assert!(amp(5999) < 0.5 * amp(599), "{} vs {}", amp(5999), amp(599));
    assert!(amp(5999) > 1e-6, "not exponentially fast");
    // and around E* = 2, |E_n - 2| never grows over a double step
    for n in (100..5998).step_by(2) {
        assert!((e[n + 2] - 2.0).abs() <= (e[n] - 2.0).abs() + 1e-12);
    }
    assert_ne!(detect_period(&e, 8, 1e-9), Some(2));
}

// ---------------------------------------------------------------------------------------
// hard cases

#[test]
fn dissipation_regime_loses_energy_and_stays_on_eq19() {
    // Deep bottoms x_n < eta1 / tau: the spring force at bottom exceeds the thrust, so the
    // decompression (spring tau x_b / chi) returns less energy than the compression stored.
    let h = eq9_hopper(0.0, 41.86);
    let alpha = 41.86 * 0.5 / 5.81;
    for &e_b in &[2.0, 5.0, 50.0, 700.0] {
        // apex giving touchdown speed^2 = 2 eta1 E_b
        let apex = 0.5 + 2.0 * 5.81 * e_b / 20.0;
        let run = h
            .simulate(
                Start::Flight {
                    height_m: apex,
                    velocity_mps: 0.0,
                },
                800,
                &MAP_ONLY,
            )
            .unwrap();
        assert_eq!(run.end, RunEnd::Completed);
        let c = run.cycles[0];
        assert!(
            c.bottom_height_m < 5.81 / 41.86 && c.dissipating,
            "E_b {e_b}"
        );
        let v_td = c.touchdown.unwrap().velocity_mps;
        assert!(c.liftoff.velocity_mps.abs() < v_td.abs(), "energy lost");
        assert!((c.energy - e_b).abs() < 1e-9 * e_b);
        let e = energies(&run.cycles);
        for (a, b) in return_map(&e) {
            assert!(b.is_finite());
            assert!((b - energy_return_map(a, alpha)).abs() <= 1e-10 * (1.0 + a));
        }
        // and it recovers (from E_1 = f(700) ~ 1e-301 the hop grows by alpha = 3.6 per
        // cycle): back on the fixed point x* = chi_l / alpha (Theorem 1)
        assert!((run.cycles.last().unwrap().bottom_height_m - 0.5 / alpha).abs() < 1e-10);
    }
    // A huge thrust (alpha = 1e6, chaotic): E_1 = f(0.1) = 9e4, a bottom chi_l e^-9e4 that
    // underflows x_n to 0, and a liftoff speed (v^2 = 2 eta1 f(E_1), f(E_1) underflows to 0)
    // that is 0: the hopper does not leave the ground again. Every recorded cycle matches
    // the core's f64 iteration of eq. 19, and the run ends where that iteration reaches 0.
    let m = eq9(0.0);
    let alpha = m.alpha(m.thrust_for_alpha(1e6));
    let big = eq9_hopper(0.0, m.thrust_for_alpha(1e6));
    let mut map = vec![0.1];
    while *map.last().unwrap() != 0.0 {
        map.push(energy_return_map(*map.last().unwrap(), alpha));
    }
    // the cycle from the last nonzero E is the one that does not lift off
    let hops = map.len() - 2;
    let start = Start::Bottom {
        height_m: 0.5 * (-0.1f64).exp(),
    };
    let run = big.simulate(start, 40, &MAP_ONLY).unwrap();
    assert_eq!(run.end, RunEnd::NoLiftoff);
    assert_eq!(run.cycles.len(), hops);
    for (c, e_map) in run.cycles.iter().zip(&map) {
        assert!(c.energy.is_finite() && c.bottom_height_m >= 0.0);
        assert!(
            (c.energy - e_map).abs() <= 1e-9 * (1.0 + e_map),
            "{} vs {e_map}",
            c.energy
        );
    }
    // with times asked for, the same end (the decompression from an underflowed bottom
    // would take forever), not an infinite time
    let timed = big.simulate(start, 40, &RunOptions::default()).unwrap();
    assert_eq!(timed.end, RunEnd::NoLiftoff);
    assert!(timed
        .cycles
        .iter()
        .all(|c| c.next_touchdown.time_s.is_finite()));
}

#[test]
fn a_zero_height_hop_is_no_liftoff_in_every_model() {
    // touchdown with zero speed: eq. 9's fixed point E = 0 (Lemma 1), x_n = chi_l. The body
    // rests on its extended leg: a cycle would take no time and leave at 0 m/s, which is
    // not a hop, so the run ends with no liftoff and no cycles (not 50 zero-time cycles of
    // "period 1")
    let h = eq9_hopper(0.0, 41.86);
    let at_rest = |chi_l: f64| Start::Flight {
        height_m: chi_l,
        velocity_mps: 0.0,
    };
    let run = h
        .simulate(at_rest(0.5), 50, &RunOptions::default())
        .unwrap();
    assert_eq!(run.end, RunEnd::NoLiftoff);
    assert!(run.cycles.is_empty());
    // the zero hop repels (alpha > 1): a 1e-9 m hop grows to the period-1 orbit x* = chi_l/alpha
    let run = h
        .simulate(
            Start::Flight {
                height_m: 0.5 + 1e-9,
                velocity_mps: 0.0,
            },
            400,
            &MAP_ONLY,
        )
        .unwrap();
    assert_eq!(run.end, RunEnd::Completed);
    let alpha = 41.86 * 0.5 / 5.81;
    assert!((run.cycles.last().unwrap().bottom_height_m - 0.5 / alpha).abs() < 1e-10);
    // linear (eq. 16, touchdown at the spring's equilibrium) and full (eq. 8) models: the
    // body starts at rest at chi_l, the thrust finds the leg already extended: no hop
    let lin = LinearSpring::from_eq16(20.0, 0.2, 9.81).unwrap();
    let hl = Hopper::new(
        HopperModel::Linear(lin),
        raibert(lin.eq16_thrust(1.0), 0.01),
    )
    .unwrap();
    let full =
        FullNonlinear::new(0.5, 5.81, 2.33, 0.0, 10.0, Integrator::rk4(1e-4).unwrap()).unwrap();
    let hf = Hopper::new(HopperModel::Full(full), raibert(41.86, 0.01)).unwrap();
    for (hop, chi_l) in [(hl, 0.0), (hf, 0.5)] {
        let run = hop
            .simulate(at_rest(chi_l), 20, &RunOptions::default())
            .unwrap();
        assert_eq!(run.end, RunEnd::NoLiftoff);
        assert!(run.cycles.is_empty());
    }
}

#[test]
fn a_leg_mass_that_leaves_no_hop_height_stops_the_run_as_the_closed_form_says() {
    // eq. 7 scales the liftoff speed by 1 / (1 + mu'): with mu' = 1e300 the hop height
    // v^2 / 2g underflows to 0, and eq. 14's mu = (1 + mu')^-2 makes alpha = 0 <= 1: no
    // hopping fixed point. The trajectory must agree: no liftoff, not 60 cycles of period 1
    let h = eq9_hopper(1e300, 41.86);
    let run = h
        .simulate(
            Start::Flight {
                height_m: 1.15,
                velocity_mps: 0.0,
            },
            60,
            &RunOptions::default(),
        )
        .unwrap();
    assert_eq!(run.end, RunEnd::NoLiftoff);
    assert!(run.cycles.is_empty());
    // a merely heavy leg still hops: mu' = 1 halves the liftoff speed (eq. 7)
    let run = eq9_hopper(1.0, 41.86)
        .simulate(
            Start::Flight {
                height_m: 1.15,
                velocity_mps: 0.0,
            },
            3,
            &RunOptions::default(),
        )
        .unwrap();
    let c = &run.cycles[0];
    assert_eq!(c.liftoff.velocity_mps, 0.5 * c.liftoff_velocity_before_mps);
}

#[test]
fn bad_values_give_named_errors() {
    let base =
        "[hopper]\nmodel = \"simplified_nonlinear\"\nspring_eta1 = 5.81\nthrust_tau_mps2 = 41.86\n";
    assert!(HopperParams::from_toml_str(base).unwrap().build().is_ok());
    let err = |extra: &str, replace: Option<(&str, &str)>| {
        let mut t = format!("{base}{extra}");
        if let Some((a, b)) = replace {
            t = t.replace(a, b);
        }
        match HopperParams::from_toml_str(&t) {
            Ok(p) => p
                .build()
                .and_then(|h| {
                    for s in p.starts()? {
                        h.simulate(s, 2, &RunOptions::default())?;
                    }
                    Ok(h)
                })
                .unwrap_err()
                .to_string(),
            Err(e) => e.to_string(),
        }
    };
    assert_eq!(
        err("", Some(("spring_eta1 = 5.81", "spring_eta1 = 0.0"))),
        "hopper.spring_eta1 must be > 0"
    );
    assert_eq!(
        err(
            "",
            Some(("thrust_tau_mps2 = 41.86", "thrust_tau_mps2 = -1.0"))
        ),
        "hopper.thrust_tau_mps2 must be >= 0"
    );
    assert_eq!(
        err("thrust_delta_s = nan\n", None),
        "hopper.thrust_delta_s must be a finite number"
    );
    assert!(err("thrust_delta_s = 0.01\n", None)
        .starts_with("hopper.thrust_delta_s must satisfy delta = 0"));
    assert!(err("friction_gamma_per_s = 1.0\n", None).starts_with("hopper.friction_gamma_per_s"));
    assert_eq!(
        err("leg_mass_ratio = -0.1\n", None),
        "hopper.leg_mass_ratio must be >= 0"
    );
    assert_eq!(
        err("liftoff_height_m = 0.0\n", None),
        "hopper.liftoff_height_m must be > 0"
    );
    assert_eq!(
        err("gravity_mps2 = inf\n", None),
        "hopper.gravity_mps2 must be a finite number"
    );
    assert_eq!(err("cycles = 0\n", None), "hopper.cycles must be > 0");
    assert_eq!(
        err("initial_heights_m = [nan]\n", None),
        "hopper.initial_heights_m must be a finite number"
    );
    assert!(err(
        "initial_heights_m = [0.1]\ninitial_velocity_mps = 1.0\n",
        None
    )
    .starts_with("hopper.initial_velocity_mps must satisfy"));
    // unknown keys, in [hopper] and beside it
    let e = err("spring_eta2 = 1.0\n", None);
    assert!(e.contains("spring_eta2"), "{e}");
    let e = err("[physics]\ngravity_mps2 = 9.81\n", None);
    assert!(e.contains("physics"), "{e}");
    assert!(err("", Some(("simplified_nonlinear", "quadratic"))).contains("quadratic"));
    // model relations
    let lin = "[hopper]\nmodel = \"linear\"\nspring_eta1 = 46.5\nthrust_tau_mps2 = 41.86\nthrust_delta_s = 0.05\n";
    let e = HopperParams::from_toml_str(&format!("{lin}friction_gamma_per_s = 14.0\n"))
        .unwrap()
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            HopperError::Relation {
                param: "hopper.friction_gamma_per_s",
                ..
            }
        ),
        "{e}"
    );
    let e = HopperParams::from_toml_str(&lin.replace("41.86", "5.0"))
        .unwrap()
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            HopperError::Relation {
                param: "hopper.thrust_tau_mps2",
                ..
            }
        ),
        "{e}"
    );
    let e = HopperParams::from_toml_str(
        &format!("{lin}integrator = \"rk4\"\nstep_s = 0.0\n").replace("linear", "full"),
    )
    .unwrap()
    .build()
    .unwrap_err();
    assert_eq!(
        e,
        HopperError::Param(ParamError::NotPositive("hopper.step_s"))
    );
    let e =
        HopperParams::from_toml_str(&format!("{lin}[hopper.servo]\ntarget_energy_jpkg = -1.0\n"))
            .unwrap()
            .build()
            .unwrap_err();
    assert_eq!(e.to_string(), "hopper.servo.target_energy_jpkg must be > 0");
    // a bottom start at or above chi_l
    let h = eq9_hopper(0.0, 41.86);
    let e = h
        .simulate(Start::Bottom { height_m: 0.5 }, 3, &MAP_ONLY)
        .unwrap_err();
    assert!(matches!(
        e,
        HopperError::Relation {
            param: "hopper.initial_heights_m",
            ..
        }
    ));
}

// ---------------------------------------------------------------------------------------
// the linear model, eq. 16 / 17, Theorem 2

/// Eq. 17 for omega, beta, delta, tau, written from eq. 23–25 (with eq. 24 integrated
/// directly: chi_t = tau / gamma^2 (gamma delta - 1 + e^-gamma delta), gamma = 2 omega beta).
struct Eq17 {
    beta: f64,
    psi: f64,
    psi_dot: f64,
}

impl Eq17 {
    fn new(omega: f64, beta: f64, delta: f64, tau: f64) -> Self {
        let gamma = 2.0 * omega * beta;
        let chi_t = tau / (gamma * gamma) * (gamma * delta - 1.0 + (-gamma * delta).exp());
        let chi_dot_t = tau / gamma * (1.0 - (-gamma * delta).exp());
        let s = (1.0 + beta * beta).sqrt();
        Self {
            beta,
            psi: omega * s * chi_t + beta / s * chi_dot_t,
            psi_dot: chi_dot_t / s,
        }
    }
    fn f(&self, e: f64) -> f64 {
        let r = e.sqrt();
        ((self.psi - r).powi(2) + self.psi_dot.powi(2))
            * (-2.0 * self.beta * (PI - (self.psi_dot / (r - self.psi)).atan())).exp()
    }
}

fn eq16_hopper() -> (LinearSpring, Hopper) {
    let lin = LinearSpring::from_eq16(20.0, 0.2, 9.81).unwrap();
    let h = Hopper::new(
        HopperModel::Linear(lin),
        raibert(lin.eq16_thrust(1.0), 0.01),
    )
    .unwrap();
    (lin, h)
}

/// A bottom of normalized energy `e` in eq. 16's coordinates: chi_b = -sqrt(e / eta1).
fn bottom_of(lin: &LinearSpring, e: f64) -> Start {
    Start::Bottom {
        height_m: -(e / lin.spring_eta1()).sqrt(),
    }
}

#[test]
fn linear_model_matches_eq17() {
    let (lin, h) = eq16_hopper();
    let f = Eq17::new(20.0, 0.2, 0.01, 1.0);
    assert!((lin.omega() - 20.0).abs() < 1e-12 && (lin.beta() - 0.2).abs() < 1e-14);
    let mut worst: f64 = 0.0;
    for k in 0..12 {
        let e0 = f.psi * f.psi * 1.5 * 3f64.powi(k);
        let run = h
            .simulate(bottom_of(&lin, e0), 30, &RunOptions::default())
            .unwrap();
        assert_eq!(run.end, RunEnd::Completed);
        assert!(run.cycles.iter().all(|c| !c.early_liftoff));
        let e = energies(&run.cycles);
        assert!((e[0] - e0).abs() < 1e-12 * e0);
        for (a, b) in return_map(&e) {
            worst = worst.max((b - f.f(a)).abs() / b);
        }
    }
    println!("eq. 17: max relative |E_n+1 - f(E_n)| = {worst:e}");
    assert!(worst < 1e-9, "{worst}");
}

#[test]
fn linear_stance_matches_brute_force_integration() {
    // fig. 8's untuned eq. 10 (chi_0 = 1, chi_l = 0.5): one stance from a 0.91 m apex
    let p = scene("08");
    let h = p.build().unwrap();
    let run = h
        .simulate(p.starts().unwrap()[0], 2, &RunOptions::default())
        .unwrap();
    let c = run.cycles[0];
    let (eta, gamma, x0, g, tau) = (46.5, 2.33, 1.0, 10.0, 41.86);
    let spring = |x: f64, v: f64| eta * (x0 - x) - gamma * v - g;
    let v_td = -(2.0 * g * (0.91 - 0.5f64)).sqrt();
    let (tc, xb, _) = rk4_until(spring, (0.5, v_td), 1e-5, |_, v| v >= 0.0);
    let td = c.touchdown.unwrap();
    assert!((c.bottom.height_m - xb).abs() < 1e-9);
    assert!((c.bottom.time_s - td.time_s - tc).abs() < 1e-8);
    // thrust for delta = 0.05 s, no spring: chi'' = tau - gamma chi' - g
    let steps = 50_000;
    let hstep = 0.05 / steps as f64;
    let mut y = (xb, 0.0);
    for _ in 0..steps {
        let a = |v: f64| tau - gamma * v - g;
        let k1 = (y.1, a(y.1));
        let k2 = (y.1 + 0.5 * hstep * k1.1, a(y.1 + 0.5 * hstep * k1.1));
        let k3 = (y.1 + 0.5 * hstep * k2.1, a(y.1 + 0.5 * hstep * k2.1));
        let k4 = (y.1 + hstep * k3.1, a(y.1 + hstep * k3.1));
        y = (
            y.0 + hstep / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
            y.1 + hstep / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
        );
    }
    assert!((c.end_of_thrust.height_m - y.0).abs() < 1e-9);
    assert!((c.end_of_thrust.velocity_mps - y.1).abs() < 1e-9);
    let (tl, _, vl) = rk4_until(spring, y, 1e-5, |x, _| x >= 0.5);
    assert!((c.liftoff.time_s - c.end_of_thrust.time_s - tl).abs() < 1e-8);
    assert!((c.liftoff.velocity_mps - vl).abs() < 1e-8);
}

#[test]
fn linear_model_theorem2_one_fixed_point_from_many_starts() {
    let (lin, h) = eq16_hopper();
    let f = Eq17::new(20.0, 0.2, 0.01, 1.0);
    // the interior fixed point of eq. 17, by bisection on f(E) - E (Lemma 5: unique)
    let (mut lo, mut hi) = (f.psi * f.psi * 1.0001, 1.0);
    assert!(f.f(lo) > lo && f.f(hi) < hi);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f.f(mid) > mid {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let e_star = 0.5 * (lo + hi);
    // Corollary 8: 2 beta e^(beta pi) < 1 holds; delta < beta / ((1 + beta^2) omega) =
    // 0.009615 is (narrowly) violated by delta = 0.01, yet every hop stays valid
    assert!(2.0 * 0.2 * (0.2 * PI).exp() < 1.0);
    let mut lates = Vec::new();
    let mut starts: Vec<Start> = (0..30)
        .map(|k| bottom_of(&lin, f.psi * f.psi * 1.01 * 1.4f64.powi(k)))
        .collect();
    for apex in [1e-6, 1e-4, 1e-2, 1.0, 10.0] {
        starts.push(Start::Flight {
            height_m: apex,
            velocity_mps: 0.0,
        });
    }
    for s in starts {
        let run = h.simulate(s, 150, &MAP_ONLY).unwrap();
        assert_eq!(run.end, RunEnd::Completed);
        assert!(run.cycles.iter().skip(1).all(|c| !c.early_liftoff));
        lates.push(run.cycles.last().unwrap().energy);
    }
    for e in &lates {
        assert!((e - e_star).abs() < 1e-12 * e_star, "{e} vs {e_star}");
    }
    println!(
        "eq. 17 fixed point E* = {e_star:e} m^2/s^2, reached from {} starts",
        lates.len()
    );
}

// ---------------------------------------------------------------------------------------
// Table 1 scenes, the full model, the energy servo

#[test]
fn table1_scenes_settle_into_periodic_hopping() {
    for (fig, want) in [
        ("08", 1),
        ("09", 1),
        ("10", 1),
        ("11", 1),
        ("12", 1),
        ("13", 2),
    ] {
        let p = scene(fig);
        let h = p.build().unwrap();
        let starts = p.starts().unwrap();
        assert!(!starts.is_empty());
        let mut lasts = Vec::new();
        for s in starts {
            let run = h.simulate(s, p.cycles, &p.run_options()).unwrap();
            assert_eq!(run.end, RunEnd::Completed, "fig {fig}");
            let x = bottom_heights(&run.cycles);
            assert_eq!(detect_period(&x, 8, 1e-8), Some(want), "fig {fig}");
            assert!(run.cycles.iter().all(|c| !c.early_liftoff), "fig {fig}");
            lasts.push(*x.last().unwrap());
        }
        // both initial conditions reach the same orbit (Theorems 1, 2)
        for l in &lasts {
            assert!((l - lasts[0]).abs() < 1e-7 || want == 2, "fig {fig}");
        }
    }
    // fig. 11: x* = chi_l / alpha = 0.5 / (41.86 * 0.5 / 5.81) (sec. 4.1)
    let p = scene("11");
    let run = p
        .build()
        .unwrap()
        .simulate(p.starts().unwrap()[0], 60, &MAP_ONLY)
        .unwrap();
    assert!((run.cycles.last().unwrap().bottom_height_m - 5.81 / 41.86).abs() < 1e-12);
    // fig. 13: the limping gait is eq. 15's 2-cycle, found by iterating g directly
    let p = scene("13");
    let run = p
        .build()
        .unwrap()
        .simulate(p.starts().unwrap()[0], 80, &MAP_ONLY)
        .unwrap();
    let mut x = 0.02;
    for _ in 0..79 {
        x = nonlinear_return_map(x, 41.86, 1.0, 2.33, 0.5);
    }
    let last = run.cycles.last().unwrap().bottom_height_m;
    assert!((last - x).abs() < 1e-10, "{last} vs {x}");
    assert!((nonlinear_return_map(x, 41.86, 1.0, 2.33, 0.5) - x).abs() > 0.1);
}

/// Eq. 8 with gamma = 0, delta = 0 has the energy integrals
/// chi'^2/2 = eta ln(chi / chi_b) - g (chi - chi_b) + chi_b'^2/2, so its bottom-to-bottom map
/// solves eta1 ln(chi_l/x') - g (chi_l - x') = mu [tau x ln(chi_l/x) - g (chi_l - x)].
fn full_energy_map(x: f64, tau: f64, eta1: f64, g: f64, chi_l: f64, mu: f64) -> f64 {
    let ke = mu * (tau * x * (chi_l / x).ln() - g * (chi_l - x));
    let phi = |y: f64| eta1 * (chi_l / y).ln() - g * (chi_l - y) - ke;
    // phi decreases in y on (0, chi_l) while eta1 / y > g
    let (mut lo, mut hi) = (1e-9, chi_l);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if phi(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

fn full_hopper(integrator: Integrator, leg: f64, gamma: f64, delta: f64) -> Hopper {
    let m = FullNonlinear::new(0.5, 5.81, gamma, leg, 10.0, integrator).unwrap();
    Hopper::new(HopperModel::Full(m), raibert(41.86, delta)).unwrap()
}

#[test]
fn full_model_integration_converges_to_the_energy_integral() {
    // accuracy against cost: the error of the integrated eq. 8 (gamma = 0, delta = 0,
    // leg mass mu' = 0.25) vs the energy-integral map, and the steps it took
    let start = Start::Flight {
        height_m: 0.9,
        velocity_mps: 0.0,
    };
    let mu = leg_mass_factor(0.25);
    let err_steps = |integ: Integrator| {
        let run = full_hopper(integ, 0.25, 0.0, 0.0)
            .simulate(start, 8, &RunOptions::default())
            .unwrap();
        assert_eq!(run.end, RunEnd::Completed);
        let x = bottom_heights(&run.cycles);
        let err = return_map(&x)
            .into_iter()
            .map(|(a, b)| (b - full_energy_map(a, 41.86, 5.81, 10.0, 0.5, mu)).abs())
            .fold(0.0, f64::max);
        (err, run.steps)
    };
    let rk4: Vec<(f64, u64)> = [2e-3, 1e-3, 5e-4]
        .iter()
        .map(|&h| err_steps(Integrator::rk4(h).unwrap()))
        .collect();
    let rk45: Vec<(f64, u64)> = [1e-6, 1e-9, 1e-12]
        .iter()
        .map(|&t| err_steps(Integrator::rk45(t, 1e-3).unwrap()))
        .collect();
    println!("rk4 h = 2e-3, 1e-3, 5e-4: (max error m, steps) {rk4:?}");
    println!("rk45 tol = 1e-6, 1e-9, 1e-12: {rk45:?}");
    // RK4: halving the step doubles the cost and divides the error by ~16 (>= 8 here)
    for w in rk4.windows(2) {
        assert!(w[1].0 < w[0].0 / 8.0 && w[1].1 > w[0].1);
    }
    assert!(rk45[2].0 < 1e-9, "{:?}", rk45[2]);
    assert!(rk45[0].0 > rk45[2].0 && rk45[2].1 > rk45[0].1);
}

#[test]
fn full_model_with_leg_mass_settles_and_applies_eq7() {
    for leg in [0.0, 0.1, 0.3] {
        let h = full_hopper(Integrator::rk45(1e-10, 1e-4).unwrap(), leg, 2.33, 0.01);
        let run = h
            .simulate(
                Start::Flight {
                    height_m: 0.8,
                    velocity_mps: 0.0,
                },
                60,
                &RunOptions::default(),
            )
            .unwrap();
        assert_eq!(run.end, RunEnd::Completed, "mu' {leg}");
        let x = bottom_heights(&run.cycles);
        assert_eq!(detect_period(&x, 8, 1e-8), Some(1), "mu' {leg}");
        for c in &run.cycles {
            assert!(
                (c.liftoff.velocity_mps - c.liftoff_velocity_before_mps / (1.0 + leg)).abs()
                    < 1e-15
            );
            assert!(c.bottom.time_s > c.touchdown.unwrap().time_s);
            assert!((c.end_of_thrust.time_s - c.bottom.time_s - 0.01).abs() < 1e-12);
        }
    }
}

#[test]
fn energy_servo_thrust_is_applied_per_stance() {
    let servo = EnergyServoThrust::new(41.86, 2.0, 6.0, 80.0, 0.0).unwrap();
    let h = Hopper::new(
        HopperModel::SimplifiedNonlinear(eq9(0.0)),
        ThrustLaw::EnergyServo(servo),
    )
    .unwrap();
    let run = h
        .simulate(
            Start::Flight {
                height_m: 1.4,
                velocity_mps: 0.0,
            },
            200,
            &MAP_ONLY,
        )
        .unwrap();
    for c in &run.cycles {
        let e_td = 0.5 * c.touchdown.unwrap().velocity_mps.powi(2);
        assert!((c.thrust_mps2 - servo.thrust_mps2(e_td)).abs() < 1e-12);
        // eq. 15 with this stance's thrust
        let next = nonlinear_return_map(c.bottom_height_m, c.thrust_mps2, 1.0, 5.81, 0.5);
        let v = c.liftoff.velocity_mps;
        assert!((next - 0.5 * (-v * v / (2.0 * 5.81)).exp()).abs() < 1e-12);
    }
    let x = bottom_heights(&run.cycles);
    assert_eq!(detect_period(&x, 8, 1e-9), Some(1));
}

#[test]
fn energy_servo_on_the_full_model_and_a_weak_thrust_is_named() {
    let full = FullNonlinear::new(
        0.5,
        5.81,
        2.33,
        0.0,
        10.0,
        Integrator::rk45(1e-10, 1e-4).unwrap(),
    )
    .unwrap();
    let mild = EnergyServoThrust::new(41.86, 1.0, 3.4, 80.0, 0.01).unwrap();
    let h = Hopper::new(HopperModel::Full(full), ThrustLaw::EnergyServo(mild)).unwrap();
    let start = Start::Flight {
        height_m: 0.9,
        velocity_mps: 0.0,
    };
    let run = h.simulate(start, 80, &RunOptions::default()).unwrap();
    assert_eq!(run.end, RunEnd::Completed);
    for c in &run.cycles {
        let e_td = 0.5 * c.touchdown.unwrap().velocity_mps.powi(2);
        assert!((c.thrust_mps2 - mild.thrust_mps2(e_td)).abs() < 1e-12);
    }
    assert_eq!(
        detect_period(&bottom_heights(&run.cycles), 8, 1e-8),
        Some(1)
    );
    // a stiff servo asks for no thrust after a 3 m fall: the body would sink during the
    // thrust phase, a named end
    let stiff = EnergyServoThrust::new(41.86, 5.0, 2.0, 80.0, 0.01).unwrap();
    let h = Hopper::new(HopperModel::Full(full), ThrustLaw::EnergyServo(stiff)).unwrap();
    let run = h
        .simulate(
            Start::Flight {
                height_m: 3.0,
                velocity_mps: 0.0,
            },
            5,
            &RunOptions::default(),
        )
        .unwrap();
    assert_eq!(run.end, RunEnd::WeakThrust);
    assert!(run.cycles.is_empty());
}

#[test]
fn dense_samples_are_bounded_and_ordered() {
    use dexter_core::hop::StancePhase::*;
    let mut p = scene("12");
    p.samples_per_phase = 5;
    let h = p.build().unwrap();
    for (hop, n) in [(h, 10usize), (scene("08").build().unwrap(), 10)] {
        let run = hop
            .simulate(
                Start::Flight {
                    height_m: 0.9,
                    velocity_mps: 0.0,
                },
                n,
                &RunOptions {
                    times: true,
                    samples_per_phase: 5,
                },
            )
            .unwrap();
        assert!(
            run.samples.len() <= (n + 1) * 4 * 7,
            "{}",
            run.samples.len()
        );
        for ph in [Flight, Compression, Thrust, Decompression] {
            assert!(run.samples.iter().any(|s| s.phase == ph), "{ph:?}");
        }
        for w in run.samples.windows(2) {
            assert!(w[1].state.time_s >= w[0].state.time_s - 1e-12);
            assert!(w[1].cycle >= w[0].cycle);
        }
        // stance samples lie below chi_l, flight samples at or above it
        for s in &run.samples {
            let chi_l = if s.state.height_m.abs() < 10.0 {
                hop.model.liftoff_m()
            } else {
                0.0
            };
            match s.phase {
                Flight => assert!(s.state.height_m >= chi_l - 1e-12),
                _ => assert!(s.state.height_m <= chi_l + 1e-9, "{s:?}"),
            }
        }
    }
}
