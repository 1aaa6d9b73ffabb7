//! The tilt controller's accuracy for one sine/cosine source and one contact-solver cap, on
//! the host (the core in SIL is the firmware's arithmetic bit for bit): shared by
//! `tests/planar_real_table_figures.rs` (BENCHMARKS.md's table) and
//! `examples/accuracy_probe.rs` (the data of `docs/figures/tilt-newton-cap.svg`).

use dexter_core::tilt_control::sincos::SinCos;
use dexter_core::tilt_control::TiltControllerWith;
use dexter_sim::controller::Sil;
use dexter_sim::model::planar::real_table::{
    controller_params_for, run_real_table, RealTable, TableRunConfig,
};
use dexter_sim::model::planar::table_run::TableRun;
use dexter_sim::model::planar::PlanarParams;

/// Impacts per run.
pub const IMPACTS: usize = 300;

/// Zumel & Erdmann sec. 2.3's triangle, 25 cm apex, for [`IMPACTS`] impacts.
pub fn triangle() -> PlanarParams {
    PlanarParams {
        kappa_e_s2pm2: 0.165,
        target_apex_m: Some(0.25),
        impacts: IMPACTS,
        tip_angle_rad: 4f64.atan(),
        ..PlanarParams::default()
    }
}

/// One run of the triangle on `table` with the controller's Newton cap at `iterations`.
pub fn run<T: SinCos>(mut table: RealTable, iterations: u8) -> TableRun {
    let p = triangle();
    let model = p.build().unwrap();
    table.controller =
        controller_params_for(&model, &table.controller, table.camera.as_ref()).unwrap();
    table.controller.contact_iterations = iterations;
    let cfg = TableRunConfig {
        model,
        start: p.start().unwrap(),
        impacts: IMPACTS,
        record: vec![],
    };
    let mut sil = Sil::<TiltControllerWith<T>>::new(table.controller).unwrap();
    run_real_table(&cfg, &table, &mut sil).unwrap()
}

/// What one source and cap achieve.
pub struct Accuracy {
    /// Impact-time prediction error rms with perfect sensing and the paper's law (the
    /// solver alone), s.
    pub solver_rms_s: f64,
    /// Impact-time prediction error rms on the realistic table over every seed, s.
    pub realistic_rms_s: f64,
    /// Its worst, s.
    pub realistic_worst_s: f64,
    /// Mean |late energy error| of the seeds that stayed up.
    pub mean_late_energy_error: f64,
    /// Seeds that stayed up.
    pub upright: u32,
}

/// [`Accuracy`] of source `T` with cap `iterations`, the realistic table over camera seeds
/// 1 to `seeds`.
pub fn accuracy<T: SinCos>(iterations: u8, seeds: u64) -> Accuracy {
    // the solver alone: perfect camera and drives, the paper's law (no tilt-rate term and
    // no horizontal regulation: with the regulation's gains and no rate term the body tips
    // over within ten impacts)
    let mut perfect = RealTable::realistic(1);
    perfect.camera = None;
    perfect.tilt = None;
    perfect.stroke = None;
    perfect.controller.kappa_rate_s = 0.0;
    perfect.controller.kappa_x_pm = 0.0;
    perfect.controller.kappa_xdot_spm = 0.0;
    let s = run::<T>(perfect, iterations).summary;
    assert!(
        s.stayed_up,
        "the solver-alone run (cap {iterations}) ended {:?} after {} impacts: its error would not be the solver's",
        s.end,
        s.impacts
    );
    let solver_rms_s = s.impact_time_error_rms_s.unwrap_or(f64::NAN);
    let (mut up, mut energy, mut sq, mut count, mut worst) = (0, 0.0, 0.0, 0usize, 0.0f64);
    for seed in 1..=seeds {
        let run = run::<T>(RealTable::realistic(seed), iterations);
        let s = &run.summary;
        if s.stayed_up {
            up += 1;
            energy += s.late_energy_error.abs();
        }
        for r in &run.impacts {
            if let Some(p) = r.predicted_time_s {
                let e = r.time_s - p;
                sq += e * e;
                count += 1;
                worst = worst.max(e.abs());
            }
        }
    }
    Accuracy {
        solver_rms_s,
        realistic_rms_s: (sq / count as f64).sqrt(),
        realistic_worst_s: worst,
        mean_late_energy_error: energy / f64::from(up.max(1)),
        upright: up,
    }
}
