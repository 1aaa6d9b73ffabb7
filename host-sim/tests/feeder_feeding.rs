//! The feeding property (issue 16, sec. 3.2 of the paper): for random polygons, every
//! simulated execution of the planned feed from random arrival poses ends on the planned
//! goal edge within 1 mm of the goal radius, and the planner finds a plan for every part
//! the paper says it must.
//!
//! The paper proves the property for an infinitely long fence over an infinitely wide
//! belt with fence angles anywhere in (-90, 90) deg. We use a long fence (3 m) and wide
//! belt (6 m) for parts about 5 cm across, and fence angles within +-80 deg, so "must
//! have a plan" here means: every
//! counter-clockwise gap between consecutive stable edges that a plan may have to cross
//! is at most 150 deg (turns need theta+ - theta- = Psi within +-80 deg), and no hull
//! edge is within 5 % of its length of the stable/unstable boundary (the minimum contact
//! radius grows without bound there). Parts outside these bounds are generated, counted
//! and skipped, never silently passed.
//!
//! Always on: a CI sample of 9 polygons (6 convex, 3 nonconvex) from 4 arrivals each
//! (`cargo test -p dexter-sim --test feeder_feeding`, about 30 s in the dev profile).
//! The full issue-16 sweep (200 convex and 50 nonconvex parts, 20 arrivals each) is ignored
//! by default; run it with
//! `cargo test -p dexter-sim --release --test feeder_feeding -- --ignored feeding_property_full_sweep --nocapture`
//! (8 min of test time plus 2 min of build in the release profile, 49 min in the dev
//! profile, on the shared 2-core machine, 2026-11-29; the same test either way).
//!
//! Last full run (2026-11-29, commit 7f31dfb): **5000 of 5000** feeds end on the planned
//! goal edge within 1 mm of the goal radius; 1 of the 5000 plans uses a push-and-drift
//! jog. Before, 2 of 5000 had no plan (parts 44 and
//! 57, one arrival each): part 44 arrives on an edge whose center-of-mass foot lies 0.57 mm
//! from its end vertex (h = 31 mm). A stable push off theta = 0 there needs a rate below
//! 0.02 rad/s, under the fixed rate floor (2/64 rad/s) the pushes then had, so the least
//! radius for any push was 0.86 m, and the slide jog could not move the part out (it would
//! tip). The cure was the per-edge rate floor of `pushes.rs` (every stable edge can be
//! pushed off theta = 0 at every radius); the paper's push-and-drift jog
//! (`primitives.rs`) is the planner's fallback where the slide jog cannot move a part, but
//! it would not have fed part 44 by jogging out: on that edge an outward step may rest the
//! part at most atan(k b / h) = 0.95 deg below 0, a relative gain of 1.4e-4 per step.
//! The smaller draw `feeding_property(16, 12, 4, 5)`, which had 1 of 80 without a plan, now
//! feeds 80 of 80.

mod common;

use dexter_sim::model::feeder::execute::{execute, sweep_arrivals, SweepSpec, FEED_TOL_M};
use dexter_sim::model::feeder::geometry::Vec2;
use dexter_sim::model::feeder::part::Part;
use dexter_sim::model::feeder::planner::goal::{goal_edge, has_parallel_pair, next_stable};
use dexter_sim::model::feeder::planner::{plan, Feeder, PlanOptions};
use dexter_sim::model::feeder::primitives::Primitive;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use std::f64::consts::PI;

fn cell(part: Part) -> Feeder {
    common::feeder::cell(part, 0.3)
}

/// Random convex polygon: `n` points at random angles on a random ellipse, size ~5 cm.
fn convex(rng: &mut StdRng) -> Vec<Vec2> {
    let n = rng.random_range(3..=8);
    let (a, b) = (
        rng.random_range(0.015..0.035),
        rng.random_range(0.015..0.035),
    );
    let mut th: Vec<f64> = (0..n).map(|_| rng.random_range(0.0..2.0 * PI)).collect();
    th.sort_by(f64::total_cmp);
    th.iter()
        .map(|&t| Vec2::new(0.05 + a * t.cos(), 0.05 + b * t.sin()))
        .collect()
}

/// Random star-shaped (generally nonconvex) polygon with 5..9 vertices.
fn star(rng: &mut StdRng) -> Vec<Vec2> {
    let n = rng.random_range(5..=9);
    (0..n)
        .map(|i| {
            let t = 2.0 * PI * (i as f64 + rng.random_range(-0.3..0.3)) / n as f64;
            let r = rng.random_range(0.012..0.035);
            Vec2::new(0.05 + r * t.cos(), 0.05 + r * t.sin())
        })
        .collect()
}

/// Whether the paper's existence conditions hold within our limits (module doc).
fn plan_must_exist(p: &Part) -> bool {
    let clear = p.edges.iter().all(|e| {
        let m = e.a_m.min(e.b_m()) / e.len_m;
        m.abs() > 0.05
    });
    let goal = goal_edge(p).unwrap();
    let gaps_ok = p.stable_edges().iter().filter(|&&s| s != goal).all(|&s| {
        let gap = next_stable(p, s).0;
        gap <= 150f64.to_radians() || (has_parallel_pair(p) && (gap - PI).abs() < 1e-6)
    });
    clear && gaps_ok
}

struct Tally {
    parts: usize,
    skipped: usize,
    feeds: usize,
    /// Plans with a push-and-drift jog.
    drift_jogs: usize,
}

fn generate(seed: u64, convex_parts: usize, star_parts: usize) -> (Vec<Part>, usize) {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut parts = Vec::new();
    let mut skipped = 0;
    let mut attempts = 0;
    while parts.len() < convex_parts + star_parts && attempts < 100 * (convex_parts + star_parts) {
        attempts += 1;
        let pts = if parts.len() < convex_parts {
            convex(&mut rng)
        } else {
            star(&mut rng)
        };
        // Nonconvex parts count only when their center of mass lies inside (Part::new
        // rejects the others); degenerate draws are redrawn.
        let Ok(p) = Part::new(&pts, None) else {
            continue;
        };
        if p.area_m2 < 2e-4 {
            continue;
        }
        if plan_must_exist(&p) {
            parts.push(p);
        } else {
            skipped += 1;
        }
    }
    assert_eq!(parts.len(), convex_parts + star_parts, "generator starved");
    (parts, skipped)
}

/// Debugging aid: `FEEDER_PART=k [FEEDER_ARRIVAL=i] cargo test --release --test
/// feeder_feeding -- --ignored one_feed --nocapture` plans part k of the full sweep.
#[test]
#[ignore = "debugging aid"]
fn one_feed() {
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<usize>().ok());
    let k = env("FEEDER_PART").unwrap_or(0);
    let (parts, _) = generate(1996, 200, 50);
    let f = cell(parts[k].clone());
    let p = &f.part;
    println!("part {k}: rho {:.5} radius {:.5}", p.rho_m, p.radius_m);
    for e in &p.edges {
        println!(
            "  edge {}: len {:.5} a {:.5} b {:.5} h {:.5} dir {:.2} deg stable {}",
            e.index,
            e.len_m,
            e.a_m,
            e.b_m(),
            e.h_m,
            e.dir_rad.to_degrees(),
            p.is_stable(e.index)
        );
    }
    println!("  goal {:?}", goal_edge(p));
    let spec = SweepSpec {
        trials: 20,
        seed: 1996 + k as u64,
        x_range_m: (0.15, 0.6),
        y_m: 0.1,
    };
    for (i, a) in sweep_arrivals(&spec).into_iter().enumerate() {
        if env("FEEDER_ARRIVAL").is_some_and(|j| j != i) {
            continue;
        }
        match plan(&f, a, &PlanOptions::default()) {
            Ok(pl) => {
                let ex = execute(&f, &pl, a, None);
                println!("arrival {i}: {} {:?}", ex.reached_goal, pl.steps);
            }
            Err(e) => println!("arrival {i}: {e}"),
        }
    }
}

fn feeding_property(seed: u64, convex_parts: usize, star_parts: usize, arrivals: usize) -> Tally {
    let (parts, skipped) = generate(seed, convex_parts, star_parts);
    let outcomes: Vec<(usize, Vec<String>, usize)> = parts
        .into_par_iter()
        .enumerate()
        .map(|(k, p)| feed_part(seed, k, p, arrivals))
        .collect();
    let failures: Vec<String> = outcomes.iter().flat_map(|o| o.1.iter().cloned()).collect();
    assert!(
        failures.is_empty(),
        "{} of {} feeds failed (first ones printed above)",
        failures.len(),
        outcomes.len() * arrivals
    );
    Tally {
        parts: outcomes.len(),
        skipped,
        feeds: outcomes.iter().map(|o| o.0).sum(),
        drift_jogs: outcomes.iter().map(|o| o.2).sum(),
    }
}

/// Plans and executes part `k` from `arrivals` random poses; the feeds that worked, a
/// description of every one that did not, and the plans with a push-and-drift jog.
fn feed_part(seed: u64, k: usize, p: Part, arrivals: usize) -> (usize, Vec<String>, usize) {
    let f = cell(p);
    let spec = SweepSpec {
        trials: arrivals,
        seed: seed + k as u64,
        x_range_m: (0.15, 0.6),
        y_m: 0.1,
    };
    let (mut fed, mut bad, mut drift) = (0, Vec::new(), 0);
    for a in sweep_arrivals(&spec) {
        let pl = match plan(&f, a, &PlanOptions::default()) {
            Ok(pl) => pl,
            Err(e) => {
                bad.push(format!("part {k} {:?} from {a:?}: PLAN {e}", f.part.hull));
                continue;
            }
        };
        drift += usize::from(
            pl.steps
                .iter()
                .any(|s| matches!(s, Primitive::DriftJog { .. })),
        );
        let ex = execute(&f, &pl, a, None);
        let on_goal = ex.failure.is_none() && ex.final_edge == Some(pl.goal_edge);
        if on_goal && ex.radius_error_m.abs() <= FEED_TOL_M && ex.reached_goal {
            fed += 1;
        } else {
            bad.push(format!(
                "part {k} {:?} from {a:?}: EXEC {:?} edge {:?} (goal {}) radius error {:.2e}",
                f.part.hull, ex.failure, ex.final_edge, pl.goal_edge, ex.radius_error_m
            ));
        }
    }
    for b in &bad {
        println!("FAIL {b}");
    }
    (fed, bad, drift)
}

#[test]
fn random_polygons_are_fed_to_the_goal_edge_and_radius() {
    let t = feeding_property(16, 6, 3, 4);
    assert_eq!(t.feeds, 9 * 4);
    println!(
        "{} parts fed from {} arrivals ({} plans with a push-and-drift jog); {} parts outside the existence bounds skipped",
        t.parts, t.feeds, t.drift_jogs, t.skipped
    );
}

#[test]
#[ignore = "issue 16's full sweep, 250 parts x 20 arrivals: 10 min with --release, 49 min in dev (module doc)"]
fn feeding_property_full_sweep() {
    let t = feeding_property(1996, 200, 50, 20);
    println!(
        "{} parts fed from {} arrivals ({} plans with a push-and-drift jog); {} parts outside the existence bounds skipped",
        t.parts, t.feeds, t.drift_jogs, t.skipped
    );
    assert_eq!(t.feeds, 250 * 20);
}
