//! The floor under the passive bounce: the smallest loop that computes what one impact
//! of `scenes/passive-bounce.toml` must (the return time of a ball leaving a fixed table,
//! its landing speed, the restitution law, the apex), with one division for the flight and
//! one for the apex, and nothing else: no rows, no summary, no limits. `scripts/loop-cost.sh`
//! counts its marginal instructions per bounce beside the CLI's, so their ratio is measured
//! in one run (BENCHMARKS.md, "Instructions per impact").
//!
//! Usage: `bounce_floor IMPACTS [RESTITUTION]`; prints the time of the last impact, s, and
//! the last apex, m (so the loop is not optimized away).

use std::process::ExitCode;

/// `impacts` bounces of a ball leaving a table at 0 m with `v0_mps` (m/s), restitution
/// `e`, gravity `g_mps2` (m/s^2): the time of the last impact, s, and the last apex, m.
fn bounces(impacts: u64, v0_mps: f64, e: f64, g_mps2: f64) -> (f64, f64) {
    let (mut t_s, mut v_mps, mut apex_m) = (0.0, v0_mps, 0.0);
    let half_g = 0.5 * g_mps2;
    let two_g = 2.0 * g_mps2;
    for _ in 0..impacts {
        let dt_s = v_mps / half_g;
        t_s += dt_s;
        v_mps = e * (g_mps2 * dt_s - v_mps);
        apex_m = v_mps * v_mps / two_g;
    }
    (t_s, apex_m)
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let impacts = args.first().and_then(|a| a.parse::<u64>().ok());
    let e = args.get(1).map_or(Some(1.0), |a| a.parse::<f64>().ok());
    let (Some(impacts), Some(e)) = (impacts, e) else {
        eprintln!("usage: bounce_floor IMPACTS [RESTITUTION]: IMPACTS a whole number, RESTITUTION a number");
        return ExitCode::from(2);
    };
    let g = 9.81;
    let (t, apex) = bounces(impacts, (2.0 * g * 1.0f64).sqrt(), e, g);
    println!("{t} {apex}");
    ExitCode::SUCCESS
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_elastic_ball_keeps_its_apex_and_period() {
        // from 1 m at g = 9.81: each flight takes 2 sqrt(2/g), each apex is 1 m
        let g: f64 = 9.81;
        let (t, apex) = bounces(1000, (2.0 * g).sqrt(), 1.0, g);
        assert!((t - 2000.0 * (2.0f64 / g).sqrt()).abs() < 1e-9, "{t}");
        assert!((apex - 1.0).abs() < 1e-12, "{apex}");
        // restitution e scales every apex by e^2
        let (_, apex) = bounces(3, (2.0 * g).sqrt(), 0.5, g);
        assert!((apex - 0.5f64.powi(6)).abs() < 1e-15, "{apex}");
    }
}
