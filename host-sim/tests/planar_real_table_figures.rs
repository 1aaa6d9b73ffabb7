//! What accuracy costs, on the host: for each sine/cosine source of the tilt controller and
//! each contact-solver iteration cap, the impact-time prediction error, the late energy
//! error and the seeds upright (issue 11's table; the instructions per step come from the
//! firmware in QEMU). Ignored (about a minute in the dev profile); run with
//!
//! ```sh
//! cargo test -p dexter-sim --test planar_real_table_figures -- --ignored --nocapture
//! cargo test -p dexter-sim --features dexter-core/fast-math --test planar_real_table_figures -- --ignored --nocapture
//! ```
//!
//! (the second makes the "backend" source micromath instead of libm).

use dexter_core::tilt_control::sincos::{BackendSinCos, PolySinCos, SeparatePolySinCos, SinCos};
use dexter_core::tilt_control::TiltControllerWith;
use dexter_sim::controller::Sil;
use dexter_sim::model::planar::real_table::{
    controller_params_for, run_real_table, RealTable, TableRunConfig,
};
use dexter_sim::model::planar::table_run::TableRun;
use dexter_sim::model::planar::PlanarParams;

fn triangle() -> PlanarParams {
    PlanarParams {
        kappa_e_s2pm2: 0.165,
        target_apex_m: Some(0.25),
        impacts: 300,
        tip_angle_rad: 4f64.atan(),
        ..PlanarParams::default()
    }
}

fn run<T: SinCos>(mut table: RealTable, iterations: u8) -> TableRun {
    let p = triangle();
    let model = p.build().unwrap();
    table.controller =
        controller_params_for(&model, &table.controller, table.camera.as_ref()).unwrap();
    table.controller.contact_iterations = iterations;
    let cfg = TableRunConfig {
        model,
        start: p.start().unwrap(),
        impacts: 300,
        record: vec![],
    };
    let mut sil = Sil::<TiltControllerWith<T>>::new(table.controller).unwrap();
    run_real_table(&cfg, &table, &mut sil).unwrap()
}

fn rows<T: SinCos>() {
    for n in 1..=4u8 {
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
        let s = run::<T>(perfect, n).summary;
        assert!(
            s.stayed_up,
            "the solver-alone run (cap {n}) ended {:?} after {} impacts: its error would not be the solver's",
            s.end,
            s.impacts
        );
        let solver_rms = s.impact_time_error_rms_s.unwrap_or(f64::NAN);
        // the realistic table over 20 camera seeds
        let (mut up, mut energy, mut sq, mut count, mut worst) = (0, 0.0, 0.0, 0usize, 0.0f64);
        for seed in 1..=20 {
            let run = run::<T>(RealTable::realistic(seed), n);
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
        println!(
            "| {} | {n} | {:.1e} | {:.1e} | {:.1e} | {:.2} % | {up} / 20 |",
            T::NAME,
            solver_rms,
            (sq / count as f64).sqrt(),
            worst,
            100.0 * energy / f64::from(up.max(1)),
        );
    }
}

#[test]
#[ignore]
fn accuracy_by_sin_cos_source_and_contact_iterations() {
    println!(
        "| sin/cos | Newton steps per plan | impact-time error rms, perfect sensing | \
         impact-time error rms, realistic | worst, realistic | mean |late energy error| | upright |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    rows::<PolySinCos>();
    rows::<SeparatePolySinCos>();
    rows::<BackendSinCos>();
}
