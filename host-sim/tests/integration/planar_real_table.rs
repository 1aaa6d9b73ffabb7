//! The planar body on a real table (`model::planar::real_table`): tilt and stroke drives
//! with limits, a camera, the core's fixed-rate `TiltController` in the loop (SIL), against
//! the paper's ideal table (Zumel & Erdmann sec. 2.3).

use dexter_core::fixed_rate::Fault;
use dexter_core::fixed_rate::FixedRate;
use dexter_core::tilt_control::{TiltCommand, TiltController, TiltFrame, TiltParams};
use dexter_sim::controller::{ControllerError, Sil, StepController, StepOutput};
use dexter_sim::model::planar::real_table::{
    controller_params_for, run_real_table, RealTable, TableGap, TableRunConfig,
};
use dexter_sim::model::planar::table_run::{run_ideal_table, TableRun};
use dexter_sim::model::planar::PlanarParams;
use dexter_sim::model::planar::RunEnd;

/// The sec. 2.3 triangle: rho 9.428 cm, l = 2/3 of 20 cm, e 0.5, kappa 1.1, kappa_E 0.165,
/// 25 cm apex, dropped from 20 cm at theta 0.3; tips at atan 4.
fn triangle() -> PlanarParams {
    PlanarParams {
        kappa_e_s2pm2: 0.165,
        target_apex_m: Some(0.25),
        impacts: 300,
        tip_angle_rad: 4f64.atan(),
        ..PlanarParams::default()
    }
}

/// The triangle on `table` (the controller's law and body taken from the model).
fn run_real(p: &PlanarParams, mut table: RealTable, impacts: usize) -> TableRun {
    let model = p.build().unwrap();
    table.controller =
        controller_params_for(&model, &table.controller, table.camera.as_ref()).unwrap();
    table.validate(&model).unwrap();
    let cfg = TableRunConfig {
        model,
        start: p.start().unwrap(),
        impacts,
        record: vec![],
    };
    let mut sil = Sil::<TiltController>::new(table.controller).unwrap();
    run_real_table(&cfg, &table, &mut sil).unwrap()
}

/// `t` with the paper's law alone (no tilt-rate term, no horizontal regulation) on an
/// unlimited x stage (the paper's infinite table).
fn papers_law(mut t: RealTable) -> RealTable {
    t.controller.kappa_rate_s = 0.0;
    t.controller.kappa_x_pm = 0.0;
    t.controller.kappa_xdot_spm = 0.0;
    t.x_range_m = [-1e6, 1e6];
    t
}

/// Perfect sensing and drives, the paper's law.
fn perfect_table() -> RealTable {
    let mut t = papers_law(RealTable::realistic(1));
    t.camera = None;
    t.tilt = None;
    t.stroke = None;
    t
}

#[test]
fn perfect_sensing_and_drives_reproduce_the_papers_ideal_table() {
    let p = triangle();
    let real = run_real(&p, perfect_table(), 300);
    let ideal = run_ideal_table(&p.build().unwrap(), p.start().unwrap(), 300, 1);
    let (r, i) = (&real.summary, &ideal.summary);
    assert_eq!((r.end, i.end), (RunEnd::Completed, RunEnd::Completed));
    // same impacts, one by one, for the first flights (the tilt mode is neutrally stable:
    // f32 control and 2 ms periods make the two drift apart, by 1 ms at impact 15)
    for (a, b) in real.impacts.iter().zip(&ideal.impacts).take(10) {
        assert!(
            (a.time_s - b.time_s).abs() < 1e-3,
            "impact {}: {} vs {}",
            a.index,
            a.time_s,
            b.time_s
        );
        assert!(
            (a.before.theta_rad - b.before.theta_rad).abs() < 5e-3,
            "impact {}",
            a.index
        );
        assert!(
            (a.table_angle_rad - b.table_angle_rad).abs() < 5e-3,
            "impact {}",
            a.index
        );
        // the contact happens where the ideal table puts it: on y = 0
        assert!(
            a.contact_height_m.abs() < 1e-4,
            "impact {}: {}",
            a.index,
            a.contact_height_m
        );
    }
    // and the same statistics: late energy (measured -0.4677 % vs -0.4677 %), late tilt
    assert!(
        (r.late_energy_error - i.late_energy_error).abs() < 1e-3,
        "{} vs {}",
        r.late_energy_error,
        i.late_energy_error
    );
    assert!((r.late_theta_max_rad - i.late_theta_max_rad).abs() < 0.02);
    // the controller predicts each impact to a few microseconds (measured 2e-7 s rms)
    assert!(r.predicted_impacts >= 299, "{}", r.predicted_impacts);
    assert!(r.impact_time_error_rms_s.unwrap() < 1e-5, "{r:?}");
    assert_eq!(r.safe.safe_steps, 0);
}

#[test]
fn realistic_triangle_stays_upright_300_impacts_with_energy_within_two_percent() {
    // 500 Hz (and 1 kHz) control, a camera at the same rate with 1 mm and 5 mrad noise,
    // 4 ms latency, 0.1 mm and 1 mrad quantization; tilt +-0.7 rad, 8 rad/s, 300 rad/s^2;
    // stroke +-10 cm, 2 m/s, 60 m/s^2; tilt-rate damping 0.01 s
    for (seed, rate_hz) in [(1, 500.0), (7, 500.0), (2, 1000.0)] {
        let mut table = RealTable::realistic(seed);
        table.controller.dt_s = (1.0 / rate_hz) as f32;
        if let Some(c) = table.camera.as_mut() {
            c.rate_hz = rate_hz;
        }
        let run = run_real(&triangle(), table, 300);
        let s = &run.summary;
        assert_eq!(s.end, RunEnd::Completed, "seed {seed}: {s:?}");
        assert!(!s.tipped_over && s.impacts == 300);
        assert!(
            s.late_energy_error.abs() < 0.02,
            "seed {seed}: {}",
            s.late_energy_error
        );
        // damped: the body ends up balanced near upright (the paper's law keeps rocking
        // at about 0.35 rad)
        assert!(
            s.late_theta_max_rad < 0.15,
            "seed {seed}: {}",
            s.late_theta_max_rad
        );
        assert!(s.impact_time_error_rms_s.unwrap() < 1e-3, "{s:?}");
        assert!(s.predicted_impacts >= 290);
        assert_eq!(s.safe.safe_steps, 0);
        // every impact meets the table where it was planned: y_imp = 0 (within noise)
        for r in run.impacts.iter().skip(1) {
            assert!(
                r.contact_height_m.abs() < 0.01,
                "impact {}: {}",
                r.index,
                r.contact_height_m
            );
        }
    }
}

#[test]
fn wrong_gains_lose_the_body() {
    // the law's terms matter: kappa below 1 (unstable, eq. 13) tips the triangle; without
    // the energy feedback (kappa_E = 0) eq. 25 only compensates e, the energy stays at the
    // drop's 1.96 J/kg, 20 % below eta*
    let p = PlanarParams {
        kappa: 0.8,
        ..triangle()
    };
    let s = run_real(&p, RealTable::realistic(1), 300).summary;
    assert!(s.end != RunEnd::Completed, "kappa 0.8: {s:?}");
    let p = PlanarParams {
        kappa_e_s2pm2: 0.0,
        ..triangle()
    };
    let s = run_real(&p, RealTable::realistic(1), 300).summary;
    assert!(
        s.late_energy_error.abs() > 0.1,
        "kappa_E 0: {}",
        s.late_energy_error
    );
}

/// Upright counts over seeds 1..=n: the ideal table with 10 ms timing noise (sec. 2.3),
/// the real table with the realistic camera (seeds of its noise), and the real table with
/// the paper's law alone (no tilt-rate term).
fn upright_counts(n: u64) -> (usize, usize, usize) {
    let p = triangle();
    let noisy = PlanarParams {
        timing_noise_s: 0.01,
        ..triangle()
    };
    let model = noisy.build().unwrap();
    let mut counts = (0, 0, 0);
    for seed in 1..=n {
        let ideal = run_ideal_table(&model, noisy.start().unwrap(), 300, seed);
        counts.0 += usize::from(ideal.summary.stayed_up);
        counts.1 += usize::from(
            run_real(&p, RealTable::realistic(seed), 300)
                .summary
                .stayed_up,
        );
        let paper = papers_law(RealTable::realistic(seed));
        counts.2 += usize::from(run_real(&p, paper, 300).summary.stayed_up);
    }
    counts
}

#[test]
fn over_twenty_seeds_the_real_table_keeps_at_least_as_many_upright_as_the_ideal_one() {
    let (ideal, real, paper) = upright_counts(20);
    println!(
        "upright for 300 impacts, seeds 1-20: ideal table with 10 ms timing noise {ideal}, \
         real table {real}, real table with the paper's law alone {paper}"
    );
    // docs/planar.md: the ideal table keeps 16 of 20
    assert_eq!(ideal, 16);
    assert!(real >= ideal, "real {real} < ideal {ideal}");
    // the finding behind kappa_rate_s: with this camera the undamped law loses most seeds
    // (docs/planar.md: 1 of 20, seed 6)
    assert!(paper < ideal, "paper's law alone: {paper}");
    assert_eq!(paper, 1, "docs/planar.md and BENCHMARKS.md say 1 of 20");
}

/// The paper's law does not hold x (its x' eigenvalue is 1): on a table of finite x range
/// the body leaves it. With the horizontal regulation (`TiltParams::kappa_x_pm`, with its
/// minus sign) every seed stays over the realistic 2 m table for 300 impacts and ends its
/// run near the middle; with the sign flipped the regulation drives x' away instead and
/// the body is lost within tens of impacts (the derivation in the parameter's docs).
#[test]
fn the_horizontal_regulation_keeps_the_body_over_a_finite_table() {
    let p = triangle();
    for seed in [1, 6, 15] {
        let table = RealTable::realistic(seed);
        let [lo, hi] = table.x_range_m;
        assert_eq!((lo, hi), (-1.0, 1.0));
        let run = run_real(&p, table, 300);
        let s = &run.summary;
        assert_eq!(s.end, RunEnd::Completed, "seed {seed}: {s:?}");
        assert!(s.max_abs_x_m < hi, "seed {seed}: {}", s.max_abs_x_m);
        let late = run.impacts[250..].iter().map(|r| r.before.x_m.abs());
        let late_max = late.fold(0.0, f64::max);
        // the regulation is slow against the tilt mode: over seeds 1-20 every run completes
        // and the late |x| is 0.17-0.51 m (seed 1 the largest, 0.508; with the sensors' PCG
        // noise; with ChaCha12's, seed 15 measured 0.40 and the bound was 0.5)
        assert!(late_max < 0.55, "seed {seed}: late |x| {late_max}");
        // the paper's law, otherwise the same table: off the table within 20 impacts
        let mut pure = papers_law(RealTable::realistic(seed));
        pure.controller.kappa_rate_s = table.controller.kappa_rate_s;
        pure.x_range_m = [lo, hi];
        let lost = run_real(&p, pure, 300);
        assert_eq!(lost.summary.end, RunEnd::OutOfTravel, "seed {seed}");
        assert!(lost.summary.impacts < 20, "{}", lost.summary.impacts);
    }
}

/// The run ends `OutOfTravel` at the first control step whose centre of mass is outside
/// the range, no later: the last impact before it was inside, and the body cannot cross
/// more than a period's flight past the edge.
#[test]
fn leaving_the_x_range_ends_the_run_at_that_control_step() {
    let mut table = RealTable::realistic(1);
    table.x_range_m = [-0.05, 0.05];
    let run = run_real(&triangle(), table, 300);
    assert_eq!(run.summary.end, RunEnd::OutOfTravel);
    assert!(run.impacts.iter().all(|r| r.before.x_m.abs() <= 0.05));
    assert!(run.summary.impacts < 300);
}

#[test]
fn table_gap_first_contact_is_never_missed() {
    // deterministic pseudo-random segments of the rotating, translating table; the finder
    // against an independent 20 000-point scan of the gap
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = |lo: f64, hi: f64| {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        lo + (hi - lo) * (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut contacts = 0;
    for _ in 0..400 {
        let gap = TableGap {
            y: [uniform(0.0, 0.2), uniform(-3.0, 1.0), uniform(-40.0, 25.0)],
            a: [
                uniform(-0.7, 0.7),
                uniform(-8.0, 8.0),
                uniform(-150.0, 150.0),
            ],
            th: [uniform(-0.8, 0.8), uniform(-15.0, 15.0)],
            l: 0.133,
        };
        let h = uniform(0.002, 0.05);
        // segments start with the contact point above the line (the plant's invariant
        // except right after an impact, where the gap opens from zero)
        if gap.value_rate(0.0).0 <= 1e-9 {
            continue;
        }
        let found = gap.first_contact(h).unwrap();
        let n = 20_000;
        let first = (0..=n)
            .map(|k| h * k as f64 / n as f64)
            .find(|&t| gap.value_rate(t).0 <= 0.0);
        match (found, first) {
            (Some(c), Some(t)) => {
                contacts += 1;
                // never later than the first sampled crossing; no earlier than a grid step
                // before it unless the gap dips between samples
                assert!(
                    c.time_s <= t + 1e-12,
                    "found {} after the scan's {t}",
                    c.time_s
                );
                assert!(gap.value_rate(c.time_s).0 <= 1e-12);
            }
            (None, Some(t)) => panic!("missed a contact at {t} in {gap:?} over {h}"),
            (Some(c), None) => {
                // a dip between grid points: the gap there is within rounding of zero or below
                assert!(gap.value_rate(c.time_s).0 <= 1e-9, "{gap:?}");
            }
            (None, None) => {}
        }
    }
    assert!(contacts > 50, "{contacts}");
}

#[test]
fn table_gap_is_the_normal_distance_to_the_line() {
    // independent geometry: the line through the pivot (x, h) at angle alpha, the contact
    // point (x + l sin theta, y - l cos theta); and the rate against a central difference
    let gap = TableGap {
        y: [0.12, -1.3, -4.0],
        a: [0.3, 2.0, -20.0],
        th: [0.25, -1.7],
        l: 0.133,
    };
    for &s in &[0.0, 0.003, 0.011] {
        let alpha = gap.a[0] + gap.a[1] * s + gap.a[2] * s * s;
        let y_minus_h = gap.y[0] + gap.y[1] * s + gap.y[2] * s * s;
        let theta = gap.th[0] + gap.th[1] * s;
        let p = [gap.l * theta.sin(), y_minus_h - gap.l * theta.cos()]; // from the pivot
        let normal = [-alpha.sin(), alpha.cos()];
        let d = normal[0] * p[0] + normal[1] * p[1];
        let (g, rate) = gap.value_rate(s);
        assert!((g - d).abs() < 1e-15, "{g} vs {d}");
        let e = 1e-6;
        let fd = (gap.value_rate(s + e).0 - gap.value_rate(s - e).0) / (2.0 * e);
        assert!((rate - fd).abs() < 1e-7, "{rate} vs {fd}");
        // the bound holds: -G'' <= A (central second difference)
        let g2 = (gap.value_rate(s + e).1 - gap.value_rate(s - e).1) / (2.0 * e);
        assert!(-g2 <= gap.curvature_bound(0.011) + 1e-6);
    }
}

#[test]
fn every_impact_obeys_eq21_against_the_tables_surface_velocity() {
    // independent check of the plant's impacts: the contact point's velocity relative to
    // the table surface along the normal reverses and scales by e (frictionless), the
    // body's angle is continuous, the line does not move
    let run = run_real(&triangle(), RealTable::realistic(3), 60);
    let l = 0.2 * 2.0 / 3.0;
    for r in &run.impacts {
        let a = r.table_angle_rad;
        let (n, t) = ([-a.sin(), a.cos()], [a.cos(), a.sin()]);
        let rel = |s: &dexter_sim::model::planar::PlanarState| {
            let vc = s.body_state().contact_velocity(l);
            let v = [
                vc[0] - r.table_velocity_mps[0],
                vc[1] - r.table_velocity_mps[1],
            ];
            (n[0] * v[0] + n[1] * v[1], t[0] * v[0] + t[1] * v[1])
        };
        let (vn0, _) = rel(&r.before);
        let (vn1, _) = rel(&r.after);
        assert!(vn0 < 0.0 && vn1 > 0.0, "impact {}", r.index);
        assert!(
            (vn1 + 0.5 * vn0).abs() < 1e-12,
            "impact {}: {vn1} vs {}",
            r.index,
            -0.5 * vn0
        );
        assert_eq!(r.before.theta_rad, r.after.theta_rad);
        // the line does not move at the impact: the surface's normal velocity is the same
        // just after (the pivot follows the body's new x' by sliding the line along itself)
        let [va, vb] = [r.table_velocity_mps, r.table_velocity_after_mps];
        let dn = n[0] * (vb[0] - va[0]) + n[1] * (vb[1] - va[1]);
        assert!(
            dn.abs() < 1e-12,
            "impact {}: the line jumped by {dn} m/s",
            r.index
        );
        assert!(
            (vb[0] - r.after.x_dot_mps).abs() < 1.0,
            "impact {}",
            r.index
        );
    }
}

/// A controller that answers every `every`-th frame with the safe state for a link timeout
/// (what the firmware does when its link times out), else steps the core: shows the plug
/// for HIL and that such steps are counted.
struct Flaky {
    controller: TiltController,
    every: u64,
    steps: u64,
}

impl StepController<TiltController> for Flaky {
    fn step(&mut self, frame: &TiltFrame) -> Result<StepOutput<TiltCommand>, ControllerError> {
        self.steps += 1;
        let command = if self.steps.is_multiple_of(self.every) {
            self.controller.safe(frame.seq, Fault::LinkTimeout)
        } else {
            self.controller.step(frame)
        };
        Ok(StepOutput {
            command,
            telemetry: self.controller.telemetry(),
        })
    }
    fn reconfigure(&mut self, params: TiltParams) -> Result<(), ControllerError> {
        self.controller = TiltController::new(params).map_err(ControllerError::Params)?;
        Ok(())
    }
}

#[test]
fn safe_steps_are_counted_by_fault() {
    let p = triangle();
    let model = p.build().unwrap();
    // the count, not the law, is under test: the realistic table without its horizontal
    // regulation, on an unlimited stage (a lost link every second is harsh on either law:
    // over seeds 1-6 and 60 impacts, 1 tips without it, 2 with it)
    let mut table = RealTable::realistic(1);
    table.controller.kappa_x_pm = 0.0;
    table.controller.kappa_xdot_spm = 0.0;
    table.x_range_m = [-1e6, 1e6];
    table.controller =
        controller_params_for(&model, &table.controller, table.camera.as_ref()).unwrap();
    let cfg = TableRunConfig {
        model,
        start: p.start().unwrap(),
        impacts: 20,
        record: vec![(0.0, 0.1005)],
    };
    let mut flaky = Flaky {
        controller: TiltController::new(table.controller).unwrap(),
        every: 500,
        steps: 0,
    };
    let run = run_real_table(&cfg, &table, &mut flaky).unwrap();
    let s = &run.summary;
    assert_eq!(s.safe.count(Fault::LinkTimeout), s.control_steps / 500);
    assert!(s.safe.count(Fault::LinkTimeout) >= 4, "{s:?}");
    // the recording window: one sample per control step in [0, 0.1005] s
    assert_eq!(run.samples.len(), 51);
    // a camera slower than the stale limit allows: 500 Hz control, 40 Hz camera, stale
    // after 5 repeats
    let mut slow = RealTable::realistic(1);
    if let Some(c) = slow.camera.as_mut() {
        c.rate_hz = 40.0;
    }
    let s = run_real(&p, slow, 5).summary;
    assert!(s.safe.count(Fault::Stale) > 0, "{s:?}");
}

#[test]
fn limits_too_tight_for_the_plan_are_reported() {
    // a tilt drive five times slower in acceleration: the first flight's 0.33 rad in 0.12 s
    // cannot be met, and the controller says so
    let mut table = RealTable::realistic(1);
    table.controller.tilt.accel_max_radps2 = 60.0;
    if let Some(d) = table.tilt.as_mut() {
        d.accel_max = 60.0;
    }
    let s = run_real(&triangle(), table, 10).summary;
    assert!(s.plan_steps.limited > 0, "{s:?}");
}
