//! Paper reproductions on the line juggler (Rizzi & Koditschek sec. 2) and the passive
//! bounce, against closed forms computed here, independently of the simulator.

use dexter_sim::systems::line::summary::Summary;
use dexter_tests::{load_scene, rel, run_rows};

/// Passive bounce from apex h0 with restitution e: the n-th impact (0-based) happens at
/// t0 + 2 v0 e (1 - e^n) / (g (1 - e)), t0 = sqrt(2 h0 / g), v0 = sqrt(2 g h0), and the
/// apex after it is e^(2(n+1)) h0.
fn passive_closed_form(h0: f64, g: f64, e: f64, n: i32) -> (f64, f64) {
    let t0 = (2.0 * h0 / g).sqrt();
    let v0 = (2.0 * g * h0).sqrt();
    let t = t0 + 2.0 * v0 * e * (1.0 - e.powi(n)) / (g * (1.0 - e));
    (t, e.powi(2 * (n + 1)) * h0)
}

#[test]
fn passive_bounce_matches_closed_form_then_rests() {
    let scene = load_scene("passive-bounce", &[]);
    let (h0, g, e) = (1.0, 9.81, 0.8);
    assert_eq!(
        (
            scene.ball.height_m,
            scene.physics.gravity_mps2,
            scene.physics.restitution
        ),
        (h0, g, e)
    );
    let out = run_rows(&scene);
    assert!(out.rows.len() > 40);
    let mut worst_t = 0.0f64;
    let mut worst_apex = 0.0f64;
    for (n, row) in out.rows.iter().take(40).enumerate() {
        let (t, apex) = passive_closed_form(h0, g, e, n as i32);
        worst_t = worst_t.max(rel(row.time_s, t));
        worst_apex = worst_apex.max(rel(row.apex_height_m, apex));
    }
    println!("passive bounce, 40 impacts: worst relative error time {worst_t:.2e}, apex {worst_apex:.2e}");
    assert!(worst_t <= 1e-12, "impact time error {worst_t}");
    assert!(worst_apex <= 1e-12, "apex error {worst_apex}");
    // then resting contact, at the Zeno limit t0 + 2 e v0 / (g (1 - e))
    let s = Summary::new(&scene, &out);
    assert!(s.resting_contact);
    let v0 = (2.0 * g * h0).sqrt();
    let t_inf = (2.0 * h0 / g).sqrt() + 2.0 * e * v0 / (g * (1.0 - e));
    let t_rest = s.resting_since_s.unwrap();
    println!(
        "Zeno limit {t_rest} s vs closed form {t_inf} s (rel {:.2e})",
        rel(t_rest, t_inf)
    );
    assert!(rel(t_rest, t_inf) <= 1e-12);
    // it rested once the take-off speed e^N v0 fell below the 1e-6 m/s threshold
    let n = out.impacts as i32;
    assert!(
        e.powi(n) * v0 <= 1e-6 && e.powi(n - 1) * v0 > 1e-6,
        "rested after {n} impacts"
    );
}

/// Eq. 8 with beta = (1 + alpha) kappa1 / 2 and v*^2 = 2 g h*.
fn eq8(v: f64, alpha: f64, kappa1: f64, g: f64, target: f64) -> f64 {
    let beta = 0.5 * (1.0 + alpha) * kappa1;
    v * (1.0 - beta * (v * v - 2.0 * g * target))
}

#[test]
fn ideal_juggler_follows_the_cubic_return_map() {
    let scene = load_scene("line-juggler-ideal", &[]);
    let (alpha, kappa1, g, target) = (0.8, 0.05, 9.81, 1.0);
    assert_eq!(scene.control.kappa1_s2pm2, kappa1);
    assert!(
        scene.ball.height_m < 0.5 * target,
        "starts well away from the target"
    );
    let out = run_rows(&scene);
    let speeds: Vec<f64> = out
        .rows
        .iter()
        .map(|r| -r.ball_velocity_before_mps)
        .collect();
    let mut worst = 0.0f64;
    for w in speeds.windows(2) {
        worst = worst.max(rel(w[1], eq8(w[0], alpha, kappa1, g, target)));
    }
    println!(
        "ideal juggler: {} impacts, worst eq. 8 relative error {worst:.2e}",
        speeds.len()
    );
    assert!(worst <= 1e-10, "{worst}");
    // and the fixed point of eq. 8 (v = v*) is reached: apex -> h*
    let s = Summary::new(&scene, &out);
    assert_eq!(s.period, Some(1));
    // (linear rate |1 - 2 beta v*^2| = 0.77 per impact: 0.77^60 ~ 1e-7 of the initial error)
    assert!(rel(*out.apexes_m.last().unwrap(), target) < 1e-5);
}

#[test]
fn ideal_juggler_past_beta_v2_of_one_has_period_two() {
    let (alpha, g, target) = (0.8, 9.81, 1.0);
    // beta v*^2 = 1.05 > 1
    let kappa1 = 2.0 * 1.05 / ((1.0 + alpha) * 2.0 * g * target);
    let set = format!("control.kappa1_s2pm2={kappa1:e}");
    let scene = load_scene("line-juggler-ideal", &[&set, "stop.impacts=400"]);
    let out = run_rows(&scene);
    let s = Summary::new(&scene, &out);
    assert_eq!(
        s.period,
        Some(2),
        "apexes end with {:?}",
        &out.apexes_m[out.apexes_m.len() - 4..]
    );
    // the two impact speeds p, q of the cycle satisfy eq. 8 both ways, and differ
    let n = out.rows.len();
    let p = -out.rows[n - 2].ball_velocity_before_mps;
    let q = -out.rows[n - 1].ball_velocity_before_mps;
    assert!(rel(q, eq8(p, alpha, kappa1, g, target)) <= 1e-10);
    assert!(
        rel(p, eq8(q, alpha, kappa1, g, target)) <= 1e-8,
        "2-cycle not closed"
    );
    assert!(rel(p, q) > 1e-3, "p = {p}, q = {q}: not a 2-cycle");
    // the period-1 orbit v* lies between them (the cycle straddles the unstable fixed point)
    let vstar = (2.0 * g * target).sqrt();
    assert!((p - vstar) * (q - vstar) < 0.0);
}

#[test]
fn realistic_line_juggler_converges_within_one_percent() {
    let scene = load_scene("line-juggler", &[]);
    assert!(scene
        .sensor
        .as_ref()
        .is_some_and(|s| s.noise_sigma_m > 0.0 && s.latency_s > 0.0));
    let out = run_rows(&scene);
    let s = Summary::new(&scene, &out);
    let n = s.converged_after_impacts.expect("converges");
    println!(
        "line-juggler.toml: converged after {n} impacts, final apex {:?}",
        s.final_apex_m
    );
    let target = scene.control.target_apex_m.unwrap();
    for a in &out.apexes_m[n as usize..] {
        assert!(rel(*a, target) <= 0.01, "apex {a}");
    }
    assert!(
        out.apexes_m.len() as u64 >= n + 20,
        "converged for at least 20 impacts"
    );
    assert!(!s.resting_contact);
}

#[test]
fn sweep_over_kappa1_period_doubles_where_beta_v2_passes_one() {
    use dexter_sim::grid::Range;
    use dexter_sim::scene::SceneFile;
    use dexter_sim::systems::line::sweep::sweep;
    let sets = [dexter_sim::scene::parse_set("stop.impacts=600").unwrap()];
    let table = SceneFile::read(&dexter_tests::scenes_dir().join("line-juggler-chaotic.toml"))
        .unwrap()
        .table_with(&sets)
        .unwrap();
    // beta v*^2 = 0.9 * kappa1 * 19.62 crosses 1 at kappa1 = 0.05663
    let range = Range::parse("control.kappa1_s2pm2=0.04:0.06:3").unwrap();
    let points = sweep(&table, &range, 8).unwrap();
    let distinct = |k: f64| {
        let mut v: Vec<f64> = points
            .iter()
            .filter(|p| (p.0 - k).abs() < 1e-12)
            .map(|p| p.1)
            .collect();
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
        v.len()
    };
    assert_eq!(distinct(0.04), 1, "beta v*^2 = 0.71: period 1");
    assert_eq!(distinct(0.05), 1, "beta v*^2 = 0.88: period 1");
    assert_eq!(distinct(0.06), 2, "beta v*^2 = 1.06: period 2");
}

// ---------------------------------------------------------------------------------------
// Period detection near the doublings of eq. 8

/// Eq. 8 in units of v*: x -> x (1 + c - c x^2), c = beta v*^2, and its slope.
fn cubic(x: f64, c: f64) -> f64 {
    x * (1.0 + c - c * x * x)
}
fn cubic_slope(x: f64, c: f64) -> f64 {
    1.0 + c - 3.0 * c * x * x
}

/// The multiplier of the attracting period-`p` orbit of `f` at parameter `c`, found by
/// iterating from `x0` for a long transient, then Newton on f^p(x) = x.
fn multiplier(f: fn(f64, f64) -> f64, df: fn(f64, f64) -> f64, x0: f64, p: usize, c: f64) -> f64 {
    let mut x = x0;
    for _ in 0..200_000 {
        x = f(x, c);
    }
    let cycle = |x: f64| {
        let (mut y, mut d) = (x, 1.0);
        for _ in 0..p {
            d *= df(y, c);
            y = f(y, c);
        }
        (y, d)
    };
    for _ in 0..50 {
        let (y, d) = cycle(x);
        let step = (y - x) / (d - 1.0);
        x -= step;
        if step.abs() < 1e-15 {
            break;
        }
    }
    cycle(x).1
}

/// The parameter in (lo, hi) where the attracting period-`p` orbit's multiplier passes
/// -1 (the doubling to period 2p), by bisection; f64 throughout, independent of dexter.
pub fn doubling(
    f: fn(f64, f64) -> f64,
    df: fn(f64, f64) -> f64,
    x0: f64,
    p: usize,
    (mut lo, mut hi): (f64, f64),
) -> f64 {
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if multiplier(f, df, x0, p, mid) > -1.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// What a naive detector (the last 4p apexes each within `tol` of the one p before)
/// reports: the trap the settled-period detection must not fall into.
fn naive_period(a: &[f64], tol: f64) -> Option<usize> {
    let n = a.len();
    (1..=8).find(|&p| (n - 4 * p..n).all(|i| (a[i] - a[i - p]).abs() <= tol * a[i].abs()))
}

/// The ideal juggler at c = beta v*^2 for `impacts` impacts: its summary's period and its
/// apexes.
fn period_at(c: f64, impacts: u64) -> (Option<u32>, Vec<f64>) {
    let kappa1 = c / (0.9 * 2.0 * 9.81 * 1.0);
    let k = format!("control.kappa1_s2pm2={kappa1:e}");
    let n = format!("stop.impacts={impacts}");
    let scene = load_scene("line-juggler-chaotic", &[&k, &n, "stop.duration_s=1e6"]);
    let out = run_rows(&scene);
    assert_eq!(out.impacts, impacts);
    (Summary::new(&scene, &out).period, out.apexes_m)
}

/// Near each of the first three doublings of eq. 8 (c = 1, then those of the period-2 and
/// period-4 orbits, located here by iterating the closed-form map): a run that has not
/// settled reports no period, one that has reports the attractor's, never the next one.
#[test]
fn period_is_reported_only_once_settled_near_each_doubling() {
    let c1 = doubling(cubic, cubic_slope, 0.9, 1, (0.5, 1.2));
    let c2 = doubling(cubic, cubic_slope, 0.9, 2, (c1 + 1e-6, 1.28));
    let c3 = doubling(cubic, cubic_slope, 0.9, 4, (c2 + 1e-6, 1.295));
    let c4 = doubling(cubic, cubic_slope, 0.9, 8, (c3 + 1e-6, 1.3));
    println!("eq. 8 doublings: c = {c1:.9}, {c2:.9}, {c3:.9}, {c4:.9}");
    assert!((c1 - 1.0).abs() < 1e-9 && (c2 - (5f64.sqrt() - 1.0)).abs() < 1e-9);
    // well inside each window: the period is the attractor's
    let inside = [
        (0.7, 1),
        (0.5 * (c1 + c2), 2),
        (0.5 * (c2 + c3), 4),
        (0.5 * (c3 + c4), 8),
    ];
    for (c, want) in inside {
        let (p, _) = period_at(c, 3000);
        assert_eq!(p, Some(want), "c = {c}");
    }
    // just below and just above each doubling, after a run too short to settle
    let tol = 1e-3; // analysis.period_tolerance
    let mut traps = 0;
    for (k, ck) in [c1, c2, c3].into_iter().enumerate() {
        let below = 1 << k;
        for (c, want) in [(ck - 2e-3, below), (ck + 2e-3, 2 * below)] {
            for impacts in [150, 400, 1500] {
                let (p, apexes) = period_at(c, impacts);
                let naive = naive_period(&apexes, tol);
                println!("c = {c:.6}, {impacts} impacts: period {p:?} (naive {naive:?})");
                assert!(
                    p.is_none() || p == Some(want),
                    "c = {c}, {impacts}: {p:?}, want {want}"
                );
                traps += usize::from(naive.is_some_and(|q| q as u32 != want));
            }
        }
    }
    assert!(
        traps >= 3,
        "the cases include orbits a naive test gets wrong ({traps})"
    );
}
