//! The cases of "what accuracy costs in time: exact events vs numerical integration", shared
//! by the `integration` bench (criterion times) and `examples/accuracy_probe.rs` (the data of
//! `docs/figures/integrator.svg`), so both measure the same runs.
//!
//! - drag 0: the same physics as the exact run (RK4 is exact on a quadratic, so this is the
//!   pure cost of integrating and locating events numerically);
//! - drag 0.1 1/m (a table-tennis ball): the error is measured against the closed form of a
//!   flight with quadratic drag from the impact plane back to it, v_in^2 = v_out^2 / (1 + c
//!   v_out^2 / g) (rise: apex ln(1 + c v^2/g)/(2c); fall from it: v^2 = (g/c)(1 - e^(-2 c H))).

use dexter_sim::scene::parse_set;
use dexter_sim::systems::line::run::{run_scene, RunOptions};
use dexter_sim::systems::line::scene::Scene;
use std::path::PathBuf;

/// Impacts per run.
pub const IMPACTS: u64 = 200;

/// One case: its name (`exact`, `drag{c}_rk4_{step}`, `drag{c}_rk45_{tol}`) and the
/// `--set` overrides that make it from `scenes/line-juggler-ideal.toml`.
pub struct Case {
    /// The case's name.
    pub name: String,
    /// The scene overrides.
    pub sets: Vec<String>,
}

/// Every case: exact, then for drag 0 and 0.1 1/m RK4 at three steps and RK45 at three
/// tolerances.
pub fn cases() -> Vec<Case> {
    let mut cases = vec![Case {
        name: "exact".into(),
        sets: vec![],
    }];
    for c in ["0", "0.1"] {
        let d = format!("drag.coefficient_per_m={c}");
        for step in ["1e-2", "1e-3", "1e-4"] {
            cases.push(Case {
                name: format!("drag{c}_rk4_{step}"),
                sets: vec![d.clone(), format!("drag.step_s={step}")],
            });
        }
        for tol in ["1e-6", "1e-9", "1e-12"] {
            cases.push(Case {
                name: format!("drag{c}_rk45_{tol}"),
                sets: vec![
                    d.clone(),
                    "drag.integrator=rk45".into(),
                    format!("drag.tolerance={tol}"),
                ],
            });
        }
    }
    cases
}

/// The ideal line juggler for [`IMPACTS`] impacts with these overrides.
pub fn scene(sets: &[String]) -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/line-juggler-ideal.toml");
    let mut all = vec![format!("stop.impacts={IMPACTS}")];
    all.extend(sets.iter().cloned());
    let o: Vec<_> = all.iter().map(|s| parse_set(s).unwrap()).collect();
    Scene::load(&path, &o).unwrap()
}

/// Worst relative error of each flight's landing speed against the closed form for its
/// take-off speed (drag coefficient c, 0 = ballistic).
pub fn flight_error(s: &Scene) -> f64 {
    let out = run_scene(
        s,
        &RunOptions {
            record_rows: true,
            ..RunOptions::default()
        },
        None,
    )
    .unwrap();
    let g = s.physics.gravity_mps2;
    let c = s.drag.as_ref().map_or(0.0, |d| d.coefficient_per_m);
    out.rows
        .windows(2)
        .map(|w| {
            let up = w[0].ball_velocity_after_mps;
            let exact = (up * up / (1.0 + c * up * up / g)).sqrt();
            ((-w[1].ball_velocity_before_mps - exact) / exact).abs()
        })
        .fold(0.0, f64::max)
}

/// One run of the scene, as the bench times it: the impacts simulated.
pub fn run_impacts(s: &Scene) -> u64 {
    run_scene(s, &RunOptions::default(), None).unwrap().impacts
}
