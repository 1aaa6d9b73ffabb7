//! The tilt controller's sine/cosine sources (`tilt_control::sincos`), by hand: each source
//! against the f64 sine and cosine of std within its documented error bound, exact values
//! at exact angles, and the trait's default `step`/`safe` (what a source defined outside
//! the core runs) against the controller's own step.
//!
//! Written to kill the mutants of `shared/src/tilt_control/sincos.rs` (docs/mutants.md):
//! each source's `sin_cos` replaced by a constant pair, and the default `step`/`safe`
//! replaced by `TiltCommand::default()`.

use core::f64::consts::PI;

use dexter_core::fixed_rate::{Fault, FixedRate, Mode, Reply};
use dexter_core::math::{sin_cos_poly_f32, BACKEND};
use dexter_core::tilt_control::sincos::{BackendSinCos, PolySinCos, SeparatePolySinCos, SinCos};
use dexter_core::tilt_control::{TiltController, TiltControllerWith, TiltParams};

mod common;
use common::tilt::{flight, frame_at, table_after};

/// The largest |sin - f64 sin| and |cos - f64 cos| of source `T` at `n + 1` angles evenly
/// spread over [-r, r] rad (the angle itself rounded to f32 first, so only the source's
/// error counts).
fn worst_error<T: SinCos>(r: f64, n: u32) -> (f64, f64) {
    let (mut es, mut ec) = (0.0f64, 0.0f64);
    for i in 0..=n {
        let x = (-r + 2.0 * r * f64::from(i) / f64::from(n)) as f32;
        let (s, c) = T::sin_cos(x);
        let xd = f64::from(x);
        es = es.max((f64::from(s) - xd.sin()).abs());
        ec = ec.max((f64::from(c) - xd.cos()).abs());
    }
    (es, ec)
}

/// The shipped pair is within its documented 2.5e-7 on [-2 pi, 2 pi] and 5e-7 on
/// [-1e4, 1e4] rad (`sin_cos_poly_f32`'s docs), in both components.
#[test]
fn the_shipped_pair_is_within_its_documented_bound_of_f64_sine_and_cosine() {
    let (es, ec) = worst_error::<PolySinCos>(2.0 * PI, 20_000);
    assert!(es <= 2.5e-7 && ec <= 2.5e-7, "sin {es:e}, cos {ec:e}");
    let (es, ec) = worst_error::<PolySinCos>(1e4, 200_000);
    assert!(es <= 5e-7 && ec <= 5e-7, "sin {es:e}, cos {ec:e}");
}

/// The backend's pair: libm's `sinf`/`cosf` are within an ulp (below 1e-6 on [-2 pi,
/// 2 pi], where |sin|, |cos| <= 1); micromath's (`fast-math`) within the 0.002 its
/// documentation states.
#[test]
fn the_backends_pair_is_within_its_bound_of_f64_sine_and_cosine() {
    let bound = if BACKEND == "micromath" { 2e-3 } else { 1e-6 };
    let (es, ec) = worst_error::<BackendSinCos>(2.0 * PI, 20_000);
    assert!(
        es <= bound && ec <= bound,
        "{BACKEND}: sin {es:e}, cos {ec:e}"
    );
}

/// The separate polynomials: `sin_poly_f32` is within 2e-6 on [-pi, pi]; `cos_poly_f32`
/// is `sin_poly_f32(x + pi/2)`, whose f32 sum adds at most half an ulp of 3 pi/2 (2.4e-7).
#[test]
fn the_separate_polynomials_are_within_their_bound_of_f64_sine_and_cosine() {
    let (es, ec) = worst_error::<SeparatePolySinCos>(PI, 20_000);
    assert!(es <= 2e-6 && ec <= 2.3e-6, "sin {es:e}, cos {ec:e}");
}

/// Exact angles: at 0 the pair is (0, 1); at +-pi/2 and +-pi, +-1 and 0 to the bound;
/// sin is odd and cos even; and sin^2 + cos^2 = 1 to twice the bound. Each of the three
/// sources, each with its own bound.
#[test]
fn every_source_gives_the_exact_values_at_exact_angles_and_the_symmetries() {
    fn check<T: SinCos>(bound: f32) {
        let name = T::NAME;
        let (s, c) = T::sin_cos(0.0);
        assert!(
            s.abs() <= bound && (c - 1.0).abs() <= bound,
            "{name}: ({s}, {c}) at 0"
        );
        let h = core::f32::consts::FRAC_PI_2;
        for (x, want_s, want_c) in [
            (h, 1.0f32, 0.0f32),
            (-h, -1.0, 0.0),
            (2.0 * h, 0.0, -1.0),
            (-2.0 * h, 0.0, -1.0),
        ] {
            let (s, c) = T::sin_cos(x);
            assert!(
                (s - want_s).abs() <= bound && (c - want_c).abs() <= bound,
                "{name}: ({s}, {c}) at {x}"
            );
        }
        for i in 1..=100 {
            let x = 0.061 * i as f32;
            let ((s, c), (sm, cm)) = (T::sin_cos(x), T::sin_cos(-x));
            assert!((s + sm).abs() <= 2.0 * bound, "{name}: sin odd at {x}");
            assert!((c - cm).abs() <= 2.0 * bound, "{name}: cos even at {x}");
            assert!(
                (s * s + c * c - 1.0).abs() <= 3.0 * bound,
                "{name}: s^2 + c^2 at {x}"
            );
        }
    }
    check::<PolySinCos>(2.5e-7);
    check::<BackendSinCos>(if BACKEND == "micromath" { 2e-3 } else { 1e-6 });
    check::<SeparatePolySinCos>(2.3e-6);
}

/// The short names reports print.
#[test]
fn each_source_has_its_report_name() {
    assert_eq!(PolySinCos::NAME, "poly");
    assert_eq!(SeparatePolySinCos::NAME, "poly-separate");
    assert_eq!(BackendSinCos::NAME, BACKEND);
    assert!(BACKEND == "libm" || BACKEND == "micromath");
}

/// A source defined outside the core, with the shipped polynomials and the trait's
/// default `step` and `safe`.
struct PolyByDefault;

impl SinCos for PolyByDefault {
    const NAME: &'static str = "poly-by-default";
    fn sin_cos(x_rad: f32) -> (f32, f32) {
        sin_cos_poly_f32(x_rad)
    }
}

/// The trait's default `step` and `safe` are the controller's: a source outside the core
/// with the same sine and cosine as the shipped one gives, through `FixedRate`, the shipped
/// controller's commands bit for bit over a flight from release to just before its contact
/// (the command answers each frame's sequence number and reaches Track with a plan), and
/// the same safe command (mode Safe, the fault reported, the sequence number answered).
/// Called as `FixedRate::step`: the method syntax would pick the inherent `step`.
#[test]
fn the_default_step_and_safe_of_a_source_outside_the_core_run_the_controller() {
    let p = TiltParams::default();
    let dt = f64::from(p.dt_s);
    let s0 = [0.0, 0.5, 0.15, 0.1, 0.3, -0.8];
    let mut shipped = <TiltController as FixedRate>::new(p).unwrap();
    let mut outside = <TiltControllerWith<PolyByDefault> as FixedRate>::new(p).unwrap();
    let mut table = [0.0f64; 4];
    let (mut tracked, mut planned) = (false, false);
    for k in 0..200u32 {
        let b = flight(s0, f64::from(k) * dt);
        if b[1] < 0.2 {
            break;
        }
        let f = frame_at(k + 1, b, table);
        let want = FixedRate::step(&mut shipped, &f);
        let got = FixedRate::step(&mut outside, &f);
        assert!(got.bit_identical(&want), "period {k}: {got:?} vs {want:?}");
        assert_eq!(got.seq(), k + 1);
        tracked |= got.mode == Mode::Track;
        planned |= got.impact_in_s > 0.0;
        table = table_after(table, &got, dt);
    }
    assert!(tracked && planned, "the run reaches Track with a plan");
    let want = FixedRate::safe(&mut shipped, 4321, Fault::Stale);
    let got = FixedRate::safe(&mut outside, 4321, Fault::Stale);
    assert!(got.bit_identical(&want), "{got:?} vs {want:?}");
    assert_eq!(
        (got.seq(), got.mode(), got.fault()),
        (4321, Mode::Safe, Fault::Stale)
    );
}
