//! Per-call instruction counts of the math kernels the core can use (feature `bench`,
//! boot word `bench`): `libm::sinf`, `micromath` `sin`, `dexter_core::math::sin_poly_f32`,
//! `libm::sqrtf`, measured with the same SysTick/icount method as the control step; where
//! the control step's instructions go; and what the wire protocol costs per frame.

use crate::systick::SysTickInstructions;
use core::hint::black_box;
use dexter_firmware::board::StepTimer;

/// Arguments spread over a few periods (the cost of range reduction depends on them).
const ARGS: [f32; 8] = [0.1, 0.7, 1.3, 2.9, -0.4, -2.2, 5.5, 12.0];

/// Accuracy grid: `ACCURACY_POINTS + 1` arguments evenly spread over +-`ACCURACY_RANGE`.
const ACCURACY_POINTS: u32 = 4000;
const ACCURACY_RANGE: f32 = 2.0 * core::f32::consts::PI;

fn cost(timer: &SysTickInstructions, f: impl Fn(f32) -> f32) -> (u32, u32, u32) {
    let (mut min, mut max, mut sum) = (u32::MAX, 0, 0);
    for &x in &ARGS {
        let x = black_box(x);
        let (_, n) = timer.measure(|| f(x));
        min = min.min(n);
        max = max.max(n);
        sum += n;
    }
    (min, sum / ARGS.len() as u32, max)
}

/// Log the cost of each kernel; returns true.
pub fn run(timer: &SysTickInstructions) -> bool {
    use micromath::F32Ext;
    let kernels: [(&str, &dyn Fn(f32) -> f32); 5] = [
        ("identity (the indirect call itself)", &|x| x),
        ("libm::sinf", &|x| libm::sinf(x)),
        ("micromath sin", &|x| F32Ext::sin(x)),
        ("dexter_core::math::sin_poly_f32", &|x| {
            dexter_core::math::sin_poly_f32(x)
        }),
        ("libm::sqrtf", &|x| libm::sqrtf(x.abs())),
    ];
    for (i, (name, f)) in kernels.into_iter().enumerate() {
        let (min, mean, max) = cost(timer, f);
        // accuracy against libm (sinf within 1 ulp; sqrtf correctly rounded) on a grid
        let reference: fn(f32) -> f32 = if i == 0 {
            |x| x
        } else if i == 4 {
            |x| libm::sqrtf(x.abs())
        } else {
            libm::sinf
        };
        let mut max_err = 0.0f32;
        for k in 0..=ACCURACY_POINTS {
            let x = -ACCURACY_RANGE + 2.0 * ACCURACY_RANGE * (k as f32) / (ACCURACY_POINTS as f32);
            max_err = max_err.max((f(x) - reference(x)).abs());
        }
        defmt::info!(
            "bench {=str}: instructions per call min {=u32} mean {=u32} max {=u32}; max abs error vs libm {=f32} on [-{=f32}, {=f32}]",
            name,
            min,
            mean,
            max,
            max_err,
            ACCURACY_RANGE,
            ACCURACY_RANGE
        );
    }
    step_breakdown(timer);
    protocol_costs(timer);
    true
}

/// Instructions the firmware spends on the wire protocol per lock-step period: decoding
/// the host's sensor frame byte by byte (COBS, CRC-32C, postcard) and encoding its answer,
/// for each controller kind; and the CRC alone per byte.
pub fn protocol_costs(timer: &SysTickInstructions) {
    use dexter_core::fixed_rate::Telemetry;
    use dexter_core::protocol::{
        encode, Command, DeviceMessage, Frame, FrameDecoder, HostMessage, Kind, MAX_FRAME_LEN,
    };
    use dexter_firmware::server::HostMessage as Decoded;
    for &kind in Kind::ALL {
        // A kind this image leaves off the wire has no frame to measure.
        let (Some(frame), Some(command)) = (Frame::default_for(kind), Command::default_for(kind))
        else {
            continue;
        };
        let sensor = HostMessage::Sensor(frame);
        let mut frame = [0u8; MAX_FRAME_LEN];
        let n = encode(&sensor, &mut frame).unwrap_or(0);
        let mut decoder = FrameDecoder::<MAX_FRAME_LEN>::new();
        let body = frame.get(..n.saturating_sub(1)).unwrap_or(&[]);
        let (_, bytes) = timer.measure(|| {
            let mut completed = 0u32;
            for &b in black_box(body) {
                completed += u32::from(decoder.push::<Decoded>(b).is_some());
            }
            completed
        });
        let (_, delimiter) = timer.measure(|| decoder.push::<Decoded>(0));
        let answer = DeviceMessage::Output {
            command,
            telemetry: Telemetry::default(),
        };
        let mut out = [0u8; MAX_FRAME_LEN];
        let (m, encode_cost) = timer.measure(|| encode(black_box(&answer), &mut out).unwrap_or(0));
        defmt::info!(
            "bench protocol {}: decode sensor frame ({=usize} B) {=u32} instructions ({=u32} for the bytes, {=u32} at the delimiter: CRC, postcard, result), encode output ({=usize} B) {=u32} instructions",
            kind,
            n,
            bytes + delimiter,
            bytes,
            delimiter,
            m,
            encode_cost
        );
    }
}

/// Where the control step's instructions go: the Track-mode pipeline of
/// `Controller::step` (estimator update, mirror law, reference clamp, tracking law) measured
/// piece by piece on a parallel copy fed the same frames as a real controller, over the
/// smoke run's ball drop. The remainder is input validation, mode logic and moves.
pub fn step_breakdown(timer: &SysTickInstructions) {
    use dexter_core::control::{Controller, ControllerParams};
    use dexter_core::estimate::BallEstimator;
    use dexter_core::fixed_rate::{FixedRate, Mode};
    use dexter_core::mirror::MirrorLaw;
    use dexter_core::protocol::SensorFrame;
    use dexter_core::state::PaddleState;
    use dexter_core::track::Tracker;

    let p = ControllerParams::default();
    let (Ok(mut controller), Ok(mut estimator), Ok(law), Ok(tracker)) = (
        Controller::new(p),
        BallEstimator::new(p.estimator, p.dt_s, p.gravity_mps2),
        MirrorLaw::new(p.kappa0, p.kappa1_s2pm2, p.target_apex_m, p.gravity_mps2),
        Tracker::new(p.kp_per_s2, p.kd_per_s, p.limits, p.dt_s),
    ) else {
        defmt::error!("default parameters rejected");
        return;
    };
    let (dt, g, e) = (p.dt_s, p.gravity_mps2, p.estimator.restitution);
    let (mut b, mut vb, mut pz, mut vp) = (0.6f32, 0.0f32, p.home_height_m, 0.0f32);
    let mut sums = [0u32; 5];
    let mut n = 0u32;
    for seq in 0..super::smoke::SMOKE_STEPS {
        let frame = SensorFrame {
            seq,
            ball_height_m: b,
            paddle_height_m: pz,
            paddle_velocity_mps: vp,
        };
        let paddle = PaddleState::new(pz, vp);
        let (cmd, whole) = timer.measure(|| controller.step(&frame));
        let (est, t_est) = timer.measure(|| estimator.update(frame.ball_height_m, &paddle));
        let (r, t_law) = timer.measure(|| law.reference(&est.ball));
        let (r, t_clamp) = timer.measure(|| tracker.clamp_reference(r));
        let (_, t_track) = timer.measure(|| tracker.command(&r, &paddle));
        if cmd.mode == Mode::Track && est.valid {
            for (s, t) in sums.iter_mut().zip([whole, t_est, t_law, t_clamp, t_track]) {
                *s += t;
            }
            n += 1;
        }
        let u = cmd.paddle_accel_mps2;
        b += vb * dt - 0.5 * g * dt * dt;
        vb -= g * dt;
        pz += vp * dt + 0.5 * u * dt * dt;
        vp += u * dt;
        if b <= pz && vb < vp {
            vb = vp + e * (vp - vb);
            b = pz;
        }
    }
    let n = n.max(1);
    let [whole, est, law_t, clamp, track] = sums.map(|s| s / n);
    defmt::info!(
        "step breakdown over {=u32} Track steps (mean instructions): whole step {=u32}; estimator update {=u32}; mirror law reference {=u32}; reference clamp {=u32}; tracking law {=u32}; rest (validation, mode, moves) {=i32}",
        n,
        whole,
        est,
        law_t,
        clamp,
        track,
        whole as i32 - (est + law_t + clamp + track) as i32
    );
}
