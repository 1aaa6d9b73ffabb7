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
//! (the second makes the "backend" source micromath instead of libm). The runs are in
//! `support/tilt_accuracy.rs`, shared with `examples/accuracy_probe.rs`.

use dexter_core::tilt_control::sincos::{BackendSinCos, PolySinCos, SeparatePolySinCos, SinCos};

#[path = "support/tilt_accuracy.rs"]
mod tilt_accuracy;
use tilt_accuracy::accuracy;

fn rows<T: SinCos>() {
    for n in 1..=4u8 {
        let a = accuracy::<T>(n, 20);
        println!(
            "| {} | {n} | {:.1e} | {:.1e} | {:.1e} | {:.2} % | {} / 20 |",
            T::NAME,
            a.solver_rms_s,
            a.realistic_rms_s,
            a.realistic_worst_s,
            100.0 * a.mean_late_energy_error,
            a.upright,
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
