//! Unit tests of the hopper controller against closed-form sampled trajectories.

use super::*;
use crate::fixed_rate::Reply;

/// A periodic hop in closed form (no thrust: the trajectory does not react to the valve):
/// flight of 2 v / g, then a stance that is half a period of an undamped spring,
/// compression c(s) = (v / w) sin(w s), s in [0, pi / w]. Touchdown of hop n at
/// t = t0 + n P, bottom at pi / (2 w) into the stance.
#[derive(Clone, Copy, Debug)]
struct Synthetic {
    v_mps: f64,
    w_radps: f64,
    g: f64,
    /// Time of the first touchdown, s.
    t0_s: f64,
    chi_l: f64,
}

impl Synthetic {
    fn flight_s(&self) -> f64 {
        2.0 * self.v_mps / self.g
    }
    fn stance_s(&self) -> f64 {
        core::f64::consts::PI / self.w_radps
    }
    fn period_s(&self) -> f64 {
        self.flight_s() + self.stance_s()
    }
    fn touchdown_s(&self, n: usize) -> f64 {
        self.t0_s + n as f64 * self.period_s()
    }
    fn bottom_s(&self, n: usize) -> f64 {
        self.touchdown_s(n) + 0.5 * self.stance_s()
    }
    fn liftoff_s(&self, n: usize) -> f64 {
        self.touchdown_s(n) + self.stance_s()
    }
    /// (compression, contact, body height) at `t`.
    fn at(&self, t: f64) -> (f64, bool, f64) {
        let p = self.period_s();
        let s = (t - self.t0_s).rem_euclid(p);
        if t >= self.t0_s && s < self.stance_s() {
            let c = self.v_mps / self.w_radps * (self.w_radps * s).sin();
            (c, true, self.chi_l - c)
        } else {
            // time since the last liftoff
            let f = if t < self.t0_s {
                t - self.t0_s + self.flight_s()
            } else {
                s - self.stance_s()
            };
            let h = self.chi_l + self.v_mps * f - 0.5 * self.g * f * f;
            (0.0, false, h)
        }
    }
}

fn hop() -> Synthetic {
    // touchdown at 2 m/s, stance 0.1 s (w = 10 pi), flight 0.4077 s; first touchdown at
    // 0.2003 s, an irrational-looking offset so samples fall anywhere in the period
    Synthetic {
        v_mps: 2.0,
        w_radps: 10.0 * core::f64::consts::PI,
        g: 9.81,
        t0_s: 0.200_3,
        chi_l: 0.5,
    }
}

fn params() -> HopParams {
    HopParams {
        dt_s: 0.001,
        thrust_duration_s: 0.02,
        ..HopParams::default()
    }
}

/// One step at control step `k` of the synthetic hop, with the frame built by `frame`.
struct Log {
    commands: Vec<(f64, HopCommand)>,
}

fn run(
    c: &mut HopController,
    h: &Synthetic,
    steps: u32,
    mut frame: impl FnMut(u32, f64, (f64, bool, f64)) -> HopFrame,
) -> Log {
    // the tests run at 1 kHz; time is the step count times 1 ms exactly
    assert_eq!(c.params().dt_s, 1e-3);
    let mut commands = Vec::new();
    for k in 0..steps {
        let t = f64::from(k) * 1e-3;
        let f = frame(k, t, h.at(t));
        commands.push((t, c.step(&f)));
    }
    Log { commands }
}

fn exact(k: u32, _t: f64, (c, contact, _h): (f64, bool, f64)) -> HopFrame {
    HopFrame {
        seq: k,
        leg_compression_m: c as f32,
        contact,
        has_body_height: false,
        body_height_m: 0.0,
    }
}

impl Log {
    /// Times at which the reported phase changed from `from` to `to`.
    fn transitions(&self, from: StancePhase, to: StancePhase) -> Vec<f64> {
        self.commands
            .windows(2)
            .filter(|w| w[0].1.phase == from && w[1].1.phase == to)
            .map(|w| w[1].0)
            .collect()
    }
    /// (open time, close time) of every valve opening.
    fn valve_windows(&self) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        let mut open = None;
        for (t, c) in &self.commands {
            match (open, c.valve_open) {
                (None, true) => open = Some(*t),
                (Some(t0), false) => {
                    out.push((t0, *t));
                    open = None;
                }
                _ => {}
            }
        }
        out
    }
}

#[test]
fn noise_free_phases_are_detected_at_the_first_sample_after_each_event() {
    use StancePhase::*;
    let h = hop();
    let mut c = HopController::new(params()).unwrap();
    let log = run(&mut c, &h, 2400, exact);
    let dt = 1e-3;
    let first_after = |t: f64| (t / dt).floor() * dt + dt;
    let td = log.transitions(Flight, Compression);
    let lo = log.transitions(Decompression, Flight);
    assert_eq!(td.len(), 5, "{td:?}");
    assert_eq!(lo.len(), 5, "{lo:?}");
    for (n, t) in td.iter().enumerate() {
        // the switch closes at the touchdown: the first sample after it
        assert!(
            (t - first_after(h.touchdown_s(n))).abs() < 1e-9,
            "hop {n}: {t}"
        );
    }
    for (n, t) in lo.iter().enumerate() {
        // the first sample after the liftoff has the switch open
        assert!(
            (t - first_after(h.liftoff_s(n))).abs() < 1e-9,
            "hop {n}: {t}"
        );
    }
    // armed by the flight samples before the first touchdown: a thrust in every stance
    assert_eq!(log.valve_windows().len(), 5);
    // a run that starts in stance stays unarmed until its first liftoff
    let mut c = HopController::new(params()).unwrap();
    let late = Synthetic { t0_s: -0.03, ..h };
    let w = run(&mut c, &late, 600, exact).valve_windows();
    assert!(w[0].0 > late.liftoff_s(0), "{w:?}");
}

#[test]
fn the_predicted_opening_is_within_half_a_period_of_the_bottom() {
    let h = hop();
    let mut c = HopController::new(params()).unwrap();
    let w = run(&mut c, &h, 2400, exact).valve_windows();
    assert_eq!(w.len(), 5, "{w:?}");
    for (n, (open, close)) in w.iter().enumerate() {
        let t_b = h.bottom_s(n);
        // the step nearest to the bottom (the vertex prediction error is far below 1 us)
        assert!(
            (open - t_b).abs() <= 0.5e-3 + 1e-6,
            "hop {n}: {open} vs {t_b}"
        );
        assert!((close - open - 0.02).abs() < 1e-9, "held for delta");
    }
}

#[test]
fn a_late_detection_with_shortening_closes_at_the_estimated_bottom_plus_delta() {
    let h = hop();
    let p = HopParams {
        predict_bottom: false,
        end_thrust_at_estimate: true,
        ..params()
    };
    let mut c = HopController::new(p).unwrap();
    let w = run(&mut c, &h, 2400, exact).valve_windows();
    assert_eq!(w.len(), 5, "{w:?}");
    let dt = 1e-3;
    for (n, (open, close)) in w.iter().enumerate() {
        let t_b = h.bottom_s(n);
        // detection: the first sample below the maximum, within (dt/2, 3dt/2] of the bottom
        assert!(*open - t_b > 0.5 * dt - 1e-9 && *open - t_b <= 1.5 * dt + 1e-9);
        // the close is the step boundary nearest to t_b + delta (vertex error << dt/2)
        let target = t_b + 0.02;
        assert!(
            (close - target).abs() <= 0.5 * dt + 1e-6,
            "hop {n}: {close} vs {target}"
        );
    }
}

#[test]
fn a_late_detection_without_shortening_holds_delta_from_the_opening() {
    let h = hop();
    let p = HopParams {
        predict_bottom: false,
        end_thrust_at_estimate: false,
        ..params()
    };
    let mut c = HopController::new(p).unwrap();
    let log = run(&mut c, &h, 2400, exact);
    for (n, (open, close)) in log.valve_windows().into_iter().enumerate() {
        assert!(open - h.bottom_s(n) > 0.5e-3 - 1e-9, "late");
        assert!((close - open - 0.02).abs() < 1e-9, "{open} {close}");
    }
}

#[test]
fn known_latency_moves_the_estimated_bottom_back() {
    // samples 3 periods old: the predicted opening is still the step nearest the bottom,
    // and a late detection's shortened thrust still closes at t_b + delta
    let h = hop();
    for (predict, shorten) in [(true, false), (false, true)] {
        let p = HopParams {
            sensor_latency_s: 0.003,
            predict_bottom: predict,
            end_thrust_at_estimate: shorten,
            ..params()
        };
        let mut c = HopController::new(p).unwrap();
        let log = run(&mut c, &h, 2400, |k, t, _| exact(k, t, h.at(t - 0.003)));
        let w = log.valve_windows();
        assert_eq!(w.len(), 5);
        for (n, (open, close)) in w.iter().enumerate() {
            let t_b = h.bottom_s(n);
            if predict {
                assert!((open - t_b).abs() <= 0.5e-3 + 1e-5, "{open} vs {t_b}");
            } else {
                let target = t_b + 0.02;
                assert!(
                    (close - target).abs() <= 0.5e-3 + 1e-6,
                    "{close} vs {target}"
                );
            }
        }
    }
}

/// A small deterministic Gaussian source (LCG + Box-Muller), for reproducible noise.
struct Gauss(u64);

impl Gauss {
    fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn next(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * core::f64::consts::PI * v).cos()
    }
}

#[test]
fn noisy_samples_do_not_chatter() {
    use StancePhase::*;
    // 0.5 mm noise on the compression; thresholds at 4 and 2 sigma, hysteresis 8 sigma,
    // debounce 3: exactly one touchdown, one bottom and one liftoff per hop
    let sigma = 5e-4;
    let p = HopParams {
        predict_bottom: false,
        touchdown_compression_m: 4.0 * sigma as f32,
        liftoff_compression_m: 2.0 * sigma as f32,
        bottom_hysteresis_m: 8.0 * sigma as f32,
        debounce_samples: 3,
        ..params()
    };
    let h = hop();
    let mut noise = Gauss(7);
    let mut c = HopController::new(p).unwrap();
    let log = run(&mut c, &h, 20_000, |k, _, (x, contact, _)| HopFrame {
        seq: k,
        leg_compression_m: (x + sigma * noise.next()) as f32,
        contact,
        has_body_height: false,
        body_height_m: 0.0,
    });
    // touchdowns detected within the 20 s (3 samples of debounce after each)
    let hops = (0..100)
        .filter(|&n| h.touchdown_s(n) + 0.005 < 20.0)
        .count();
    let td = log.transitions(Flight, Compression).len();
    let lo = log.transitions(Decompression, Flight).len()
        + log.transitions(Compression, Flight).len()
        + log.transitions(Thrust, Flight).len();
    let bottoms = log.transitions(Compression, Thrust).len()
        + log.transitions(Compression, Decompression).len();
    assert_eq!(td, hops);
    assert_eq!(bottoms, td);
    assert!(lo == td || lo + 1 == td, "{lo} liftoffs, {td} touchdowns");
    // no bottom before the true bottom
    for t in log.transitions(Compression, Thrust) {
        let n = ((t - h.t0_s) / h.period_s()).floor() as usize;
        assert!(
            t > h.bottom_s(n),
            "bottom detected at {t} before {}",
            h.bottom_s(n)
        );
    }
}

#[test]
fn debounce_ignores_a_glitch_shorter_than_its_count_and_delays_by_count_minus_one() {
    use StancePhase::*;
    let h = hop();
    let p = HopParams {
        debounce_samples: 4,
        ..params()
    };
    // a 3-sample switch glitch (open) in the middle of every stance's decompression
    let glitch = |t: f64| {
        let s = (t - h.t0_s).rem_euclid(h.period_s());
        s > 0.07 && s < 0.07 + 0.0029
    };
    let mut c = HopController::new(p).unwrap();
    let log = run(&mut c, &h, 2400, |k, t, (x, contact, _)| HopFrame {
        seq: k,
        leg_compression_m: x as f32,
        contact: contact && !glitch(t),
        has_body_height: false,
        body_height_m: 0.0,
    });
    let dt = 1e-3;
    let first_after = |t: f64| (t / dt).floor() * dt + dt;
    let lo = log.transitions(Decompression, Flight);
    assert_eq!(
        lo.len(),
        5,
        "a 3-sample glitch must not end the stance: {lo:?}"
    );
    for (n, t) in lo.iter().enumerate() {
        let expect = first_after(h.liftoff_s(n)) + 3.0 * dt;
        assert!((t - expect).abs() < 1e-9, "{t} vs {expect}");
    }
    let td = log.transitions(Flight, Compression);
    for (n, t) in td.iter().enumerate() {
        let expect = first_after(h.touchdown_s(n)) + 3.0 * dt;
        assert!((t - expect).abs() < 1e-9, "{t} vs {expect}");
    }
}

#[test]
fn flight_time_gives_the_touchdown_energy() {
    // E = v^2 / 2 = 2 J/kg; T = 0.4077 s: relative error below 2 dt / T = 0.5 %
    let h = hop();
    let mut c = HopController::new(params()).unwrap();
    let dt = 1e-3;
    let mut seen = 0;
    for k in 0..2400u32 {
        let t = f64::from(k) * dt;
        let before = c.phase();
        c.step(&exact(k, t, h.at(t)));
        let e = c.touchdown_energy_jpkg();
        let touchdown = before == StancePhase::Flight && c.phase() == StancePhase::Compression;
        if touchdown && k > 500 {
            let rel = (f64::from(e) - 2.0).abs() / 2.0;
            assert!(rel < 2.0 * dt / h.flight_s(), "E = {e}");
            seen += 1;
        }
    }
    assert_eq!(seen, 4);
}

#[test]
fn the_flight_time_is_corrected_for_the_detection_thresholds() {
    // touchdown at c >= 2 mm, liftoff at c < 1 mm: the counted flight is 1 + 0.5 ms too long
    // (c ~ v s near the ends), E 0.74 % too high uncorrected; corrected, the mean over 30
    // hops is within 0.25 % of v^2/2 = 2 (the per-hop sampling error, up to 2 dt / T =
    // 0.5 %, averages out over the hops' varying sample phases)
    let h = hop();
    let p = HopParams {
        touchdown_compression_m: 2e-3,
        liftoff_compression_m: 1e-3,
        ..params()
    };
    let mut c = HopController::new(p).unwrap();
    let mut energies = Vec::new();
    for k in 0..16_000u32 {
        let t = f64::from(k) * 1e-3;
        let before = c.phase();
        c.step(&exact(k, t, h.at(t)));
        if before == StancePhase::Flight && c.phase() == StancePhase::Compression && k > 500 {
            energies.push(f64::from(c.touchdown_energy_jpkg()));
        }
    }
    assert!(energies.len() >= 30, "{}", energies.len());
    let mean = energies.iter().sum::<f64>() / energies.len() as f64;
    assert!((mean - 2.0).abs() < 0.0025 * 2.0, "mean {mean}");
}

#[test]
fn first_hop_energy_comes_from_the_body_height_when_there_is_one() {
    // E = g (apex - chi_l); the synthetic apex is chi_l + v^2 / 2g, so E = v^2/2 = 2
    let h = hop();
    let mut c = HopController::new(params()).unwrap();
    for k in 0..240u32 {
        let t = f64::from(k) * 1e-3;
        let (x, contact, height) = h.at(t);
        c.step(&HopFrame {
            seq: k,
            leg_compression_m: x as f32,
            contact,
            has_body_height: true,
            body_height_m: height as f32,
        });
    }
    // the run starts after the apex (at 0.2003 - T/2 < 0 s), so the highest sample is the
    // first one, s = T/2 - 0.2003 s past the apex: h - chi_l = (v^2 - (g s)^2) / 2g
    let e = f64::from(c.touchdown_energy_jpkg());
    let expect = 2.0 - 0.5 * (9.81f64 * (h.flight_s() / 2.0 - 0.2003)).powi(2);
    assert!((e - expect).abs() < 1e-5, "{e} vs {expect}");
    // without a height sensor: none (the servo would apply its nominal thrust)
    let mut c = HopController::new(params()).unwrap();
    for k in 0..240u32 {
        let t = f64::from(k) * 1e-3;
        c.step(&exact(k, t, h.at(t)));
    }
    assert!(c.touchdown_energy_jpkg().is_nan());
    assert_eq!(c.phase(), StancePhase::Compression);
}

#[test]
fn servo_thrust_rises_when_the_hop_is_low() {
    // tau = clamp(40 + 5 (2.5 - E), 0, 60): E = 2 (the synthetic hop) -> 42.5 by hand
    let p = HopParams {
        thrust: HopThrust {
            nominal_thrust_mps2: 40.0,
            gain_per_m: 5.0,
            target_energy_jpkg: 2.5,
            max_thrust_mps2: 60.0,
        },
        ..params()
    };
    let h = hop();
    let mut c = HopController::new(p).unwrap();
    let log = run(&mut c, &h, 1400, exact);
    let open: Vec<f32> = log
        .commands
        .iter()
        .filter(|(t, c)| c.valve_open && *t > h.liftoff_s(0))
        .map(|(_, c)| c.thrust_mps2)
        .collect();
    assert!(!open.is_empty());
    // the first stance, before any measured flight, has the nominal thrust
    assert!(log
        .commands
        .iter()
        .filter(|(t, c)| c.valve_open && *t < h.liftoff_s(0))
        .all(|(_, c)| c.thrust_mps2 == 40.0));
    for tau in open {
        assert!((tau - 42.5).abs() < 5.0 * 2.0 * 0.005 + 1e-3, "{tau}");
    }
}

#[test]
fn bad_samples_give_the_safe_state_and_recovery_waits_for_a_flight() {
    let mut c = HopController::new(params()).unwrap();
    let ok = |seq| HopFrame {
        seq,
        leg_compression_m: 0.0,
        contact: false,
        has_body_height: false,
        body_height_m: 0.0,
    };
    let stance = |seq| HopFrame {
        seq,
        leg_compression_m: 0.01,
        contact: true,
        has_body_height: false,
        body_height_m: 0.0,
    };
    assert_eq!(
        c.step(&stance(0)).mode,
        Mode::Hold,
        "a stance not seen from its start"
    );
    assert_eq!(c.step(&ok(1)).mode, Mode::Track, "armed by a flight sample");
    let mut f = ok(2);
    f.leg_compression_m = f32::NAN;
    let cmd = c.step(&f);
    assert_eq!(
        (cmd.mode, cmd.fault, cmd.valve_open),
        (Mode::Safe, Fault::NonFinite, false)
    );
    assert_eq!(cmd.thrust_mps2, 0.0);
    f.leg_compression_m = 2.0;
    assert_eq!(c.step(&f).fault, Fault::OutOfRange);
    let mut f = ok(3);
    f.has_body_height = true;
    f.body_height_m = f32::INFINITY;
    assert_eq!(c.step(&f).fault, Fault::NonFinite);
    f.body_height_m = 1e3;
    assert_eq!(c.step(&f).fault, Fault::OutOfRange);
    // recovers unarmed, arms after a flight sample
    assert_eq!(c.step(&stance(4)).mode, Mode::Hold);
    assert_eq!(c.step(&ok(5)).mode, Mode::Track);
    // stale: the same sequence number more than 5 times
    for _ in 0..5 {
        assert_eq!(c.step(&ok(5)).fault, Fault::None);
    }
    assert_eq!(c.step(&ok(5)).fault, Fault::Stale);
    // an external fault closes the valve too
    let cmd = c.safe(6, Fault::LinkTimeout);
    assert_eq!((cmd.mode, cmd.valve_open, cmd.seq), (Mode::Safe, false, 6));
}

#[test]
fn a_fault_mid_thrust_closes_the_valve_and_no_thrust_follows_until_a_new_flight() {
    let h = hop();
    let mut c = HopController::new(params()).unwrap();
    let dt = 1e-3;
    let mut opened_at = None;
    let mut after_fault_open = 0;
    let mut next_stance_open = 0;
    for k in 0..2400u32 {
        let t = f64::from(k) * dt;
        let mut f = exact(k, t, h.at(t));
        let faulted = opened_at.is_some_and(|k0| k == k0 + 3);
        if faulted {
            f.leg_compression_m = f32::NAN;
        }
        let cmd = c.step(&f);
        if faulted {
            assert!(!cmd.valve_open);
        } else if opened_at.is_some_and(|k0| k > k0 + 3) && t < h.liftoff_s(0) {
            after_fault_open += usize::from(cmd.valve_open);
        }
        if cmd.valve_open && opened_at.is_none() {
            opened_at = Some(k);
        }
        if t > h.touchdown_s(1) && t < h.liftoff_s(1) {
            next_stance_open += usize::from(cmd.valve_open);
        }
    }
    assert!(opened_at.is_some());
    assert_eq!(
        next_stance_open, 20,
        "re-armed by the flight: a full thrust next stance"
    );
    assert_eq!(
        after_fault_open, 0,
        "the valve reopened in the faulted stance"
    );
}

#[test]
fn invalid_params_are_named() {
    let bad = |p: HopParams| HopController::new(p).unwrap_err();
    let p = params();
    assert_eq!(
        bad(HopParams { dt_s: 0.0, ..p }),
        ParamError::NotPositive("dt_s")
    );
    assert_eq!(
        bad(HopParams {
            thrust: HopThrust::raibert(-1.0),
            ..p
        }),
        ParamError::Negative("thrust.nominal_thrust_mps2")
    );
    assert_eq!(
        bad(HopParams {
            liftoff_compression_m: 0.1,
            touchdown_compression_m: 0.05,
            ..p
        }),
        ParamError::OutOfRange("liftoff_compression_m")
    );
    assert_eq!(
        bad(HopParams {
            debounce_samples: 0,
            ..p
        }),
        ParamError::OutOfRange("debounce_samples")
    );
    assert_eq!(
        bad(HopParams {
            thrust_duration_s: 2e3,
            ..p
        }),
        ParamError::OutOfRange("thrust_duration_s")
    );
    assert_eq!(
        bad(HopParams {
            thrust: HopThrust {
                nominal_thrust_mps2: 50.0,
                gain_per_m: 1.0,
                target_energy_jpkg: 2.0,
                max_thrust_mps2: 40.0,
            },
            ..p
        }),
        ParamError::OutOfRange("thrust.nominal_thrust_mps2")
    );
}

#[test]
fn wire_round_trip_of_params_frame_and_command() {
    let mut buf = [0u8; 128];
    let p = params();
    let n = postcard::to_slice(&p, &mut buf).unwrap().len();
    // by hand: 11 f32 (44) + the law's 4 f32 (16) + 3 one-byte fields + the stale limit 5
    // as a varint (1) = 64 bytes, whichever law (one shape on the wire)
    assert_eq!(n, 64, "Raibert params take {n} bytes");
    assert_eq!(postcard::from_bytes::<HopParams>(&buf[..n]).unwrap(), p);
    let servo = HopParams {
        thrust: HopThrust {
            nominal_thrust_mps2: 40.0,
            gain_per_m: 5.0,
            target_energy_jpkg: 1.5,
            max_thrust_mps2: 60.0,
        },
        ..p
    };
    assert_eq!(postcard::to_slice(&servo, &mut buf).unwrap().len(), 64);
    let f = HopFrame {
        seq: 9,
        leg_compression_m: 0.01,
        contact: true,
        has_body_height: true,
        body_height_m: 0.4,
    };
    let n = postcard::to_slice(&f, &mut buf).unwrap().len();
    assert_eq!(postcard::from_bytes::<HopFrame>(&buf[..n]).unwrap(), f);
    // seq 9 (1) + f32 (4) + bool (1) + bool (1) + f32 (4)
    assert_eq!(n, 11);
    let c = HopCommand {
        seq: 9,
        valve_open: true,
        thrust_mps2: 41.86,
        phase: StancePhase::Thrust,
        mode: Mode::Track,
        fault: Fault::None,
    };
    let n = postcard::to_slice(&c, &mut buf).unwrap().len();
    assert_eq!(postcard::from_bytes::<HopCommand>(&buf[..n]).unwrap(), c);
    // seq 9 (1) + bool (1) + f32 (4) + phase, mode, fault (1 each)
    assert_eq!(n, 9);
    let mut d = c;
    d.thrust_mps2 = -d.thrust_mps2;
    assert!(c.bit_identical(&c) && !c.bit_identical(&d));
}

#[test]
fn the_params_build_the_core_law_they_name() {
    let p = HopParams {
        thrust: HopThrust {
            nominal_thrust_mps2: 40.0,
            gain_per_m: 5.0,
            target_energy_jpkg: 2.5,
            max_thrust_mps2: 60.0,
        },
        ..params()
    };
    let law = p.thrust_law().unwrap();
    assert_eq!(
        (
            law.nominal_thrust_mps2(),
            law.gain_per_m(),
            law.target_energy_jpkg(),
            law.max_thrust_mps2(),
            law.duration_s()
        ),
        (40.0, 5.0, 2.5, 60.0, 0.02)
    );
    assert_eq!(p.thrust.max_thrust_mps2(), 60.0);
    // Raibert's thrust is a servo without gain: tau whatever the energy
    let r = params().thrust_law().unwrap();
    assert_eq!((r.gain_per_m(), r.max_thrust_mps2()), (0.0, 41.86));
    assert_eq!((r.thrust_mps2(0.0), r.thrust_mps2(1e3)), (41.86, 41.86));
}
