//! Issue 22, findings 12 to 14: validation that refused documented values, and error
//! messages in internal names. Expected ranges come from the docs (docs/planar.md,
//! docs/hopper.md, docs/scenes.md), never from the code under test.

use crate::common;

use common::{dexter, scene};

/// `dexter args`: exit code and stderr.
fn run(args: &[&str]) -> (Option<i32>, String) {
    let out = dexter(args);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// A bad scene: exit 2, and the message names `key`.
fn refused(args: &[&str], key: &str) -> String {
    let (code, err) = run(args);
    assert_eq!(code, Some(2), "{args:?}: {err}");
    assert!(err.contains(key), "{args:?} should name {key}: {err}");
    err
}

/// A run of the real table with `sets`, one impact.
fn real_table(sets: &[String]) -> (Option<i32>, String) {
    let s = scene("planar-triangle-sil");
    let mut args = vec!["run", s.as_str(), "--impacts", "1"];
    for set in sets {
        args.extend(["--set", set.as_str()]);
    }
    run(&args)
}

/// A run of the real table with `sets`, one impact, refused naming `key`.
fn real_table_refused(sets: &[&str], key: &str) -> String {
    let s = scene("planar-triangle-sil");
    let mut args = vec!["run", s.as_str(), "--impacts", "1"];
    for set in sets {
        args.extend(["--set", set]);
    }
    refused(&args, key)
}

/// Finding 12: the whole documented range of `real_table.control_rate_hz` is accepted
/// where the documented joint rule holds (rate > (contact_iterations + 8) / (0.2 s -
/// camera.latency_s)), and a rate the rule refuses is refused in the scene's own keys.
#[test]
fn real_table_control_rates_in_the_documented_range_are_accepted() {
    // the documented lower end, 50 Hz, with one Newton step: (1 + 8) / 0.2 = 45 Hz
    for (rate, iterations) in [(50.0, 1), (60.0, 2), (100.0, 2), (400.0, 2), (10_000.0, 4)] {
        let (code, err) = real_table(&[
            format!("real_table.control_rate_hz={rate:?}"),
            format!("real_table.contact_iterations={iterations}"),
        ]);
        assert_ne!(code, Some(2), "{rate} Hz, {iterations} steps: {err}");
    }
    // 50 Hz with the default 2 steps and 4 ms: (2 + 8) / 0.196 = 51.02 Hz needed
    let err = real_table_refused(
        &["real_table.control_rate_hz=50.0"],
        "real_table.control_rate_hz",
    );
    assert!(!err.contains("commit_s"), "an internal name: {err}");
    assert!(err.contains("51.02"), "the lowest rate: {err}");
}

/// Finding 12: camera latencies the docs allow (0 <= latency < 0.1 s) are accepted; 0.1 s
/// is refused naming `real_table.camera.latency_s` and its range, not an internal field.
#[test]
fn real_table_camera_latencies_in_the_documented_range_are_accepted() {
    for latency in [0.0, 0.01, 0.03, 0.05, 0.09] {
        let (code, err) = real_table(&[format!("real_table.camera.latency_s={latency:?}")]);
        assert_ne!(code, Some(2), "latency {latency} s: {err}");
    }
    for latency in ["0.1", "1.0"] {
        let set = format!("real_table.camera.latency_s={latency}");
        let err = real_table_refused(&[&set], "real_table.camera.latency_s");
        assert!(!err.contains("estimator"), "an internal name: {err}");
        assert!(err.contains("0.1"), "the range: {err}");
    }
}

/// A camera holds 4 096 samples in flight (docs/planar.md): at 100 kHz that is 40.96 ms of
/// latency; 50 ms (5 000 in flight) is refused naming the latency and the count, where it
/// used to drop the oldest samples silently; 40.96 ms is accepted.
#[test]
fn real_table_camera_samples_in_flight_are_bounded_by_what_it_holds() {
    let rate = "real_table.camera.rate_hz=100000.0".to_string();
    let (code, err) = real_table(&[rate.clone(), "real_table.camera.latency_s=0.04096".into()]);
    assert_ne!(code, Some(2), "{err}");
    let err = real_table_refused(
        &[&rate, "real_table.camera.latency_s=0.05"],
        "real_table.camera.latency_s",
    );
    assert!(err.contains("4096") && err.contains("5000"), "{err}");
}

/// A run of `name` with `sets`.
fn with_sets(name: &str, extra: &[&str], sets: &[&str]) -> (Option<i32>, String) {
    let s = scene(name);
    let mut args = vec!["run", s.as_str()];
    args.extend(extra);
    for set in sets {
        args.extend(["--set", set]);
    }
    run(&args)
}

/// Finding 13, from the CLI: 16 x the control rate is the documented sensor maximum.
#[test]
fn the_sampled_hopper_accepts_a_sensor_at_exactly_16_times_the_control_rate() {
    let (code, err) = with_sets(
        "hopper-raibert-sil",
        &["--impacts", "3"],
        &["hopper.sensor.rate_hz=16000.0"],
    );
    assert_eq!(code, Some(0), "{err}");
    let (code, err) = with_sets(
        "hopper-raibert-sil",
        &["--impacts", "3"],
        &["hopper.sensor.rate_hz=16000.000000001"],
    );
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("hopper.sensor.rate_hz") && err.contains("16000"),
        "{err}"
    );
}

/// Finding 14: a `[hopper.control]` key on an exact-hopper scene says what the sampled
/// hopper needs (its own table in the file), not "unknown field".
#[test]
fn a_sampled_hopper_key_on_an_exact_hopper_scene_says_what_it_needs() {
    let s = scene("hopper-fig08");
    let err = refused(
        &["run", &s, "--set", "hopper.control.rate_hz=1000.0"],
        "hopper.control",
    );
    assert!(!err.contains("unknown field"), "{err}");
    assert!(err.contains("[hopper.control]"), "{err}");
}

/// Finding 14: an arm plan failure is in words: no `Some(..)`, `None` or empty status.
#[test]
fn an_arm_plan_failure_is_in_words() {
    for sets in [&["planner.max_evaluations=1"][..], &["planner.knots=5"][..]] {
        let (code, err) = with_sets("arm-throw", &[], sets);
        assert_ne!(code, Some(0), "{sets:?}: {err}");
        for bad in ["Some(", "None", "status )", "Goal"] {
            assert!(!err.contains(bad), "{sets:?}: {bad} in {err}");
        }
    }
}

/// Finding 14: the feeder's radius outside the fence is a readable number, not 300 digits.
#[test]
fn a_feeder_radius_far_out_is_a_short_number() {
    let s = scene("1joc-triangle");
    let err = refused(
        &["run", &s, "--set", "feeder.goal.contact_radius_m=1e300"],
        "feeder.goal.contact_radius_m",
    );
    assert!(err.len() < 300, "{err}");
    assert!(err.contains("1.0000e300"), "{err}");
}

/// Finding 14: the core's field names never stand in for the scene's keys.
#[test]
fn core_field_names_are_reported_as_scene_keys() {
    let cases: [(&str, &str, &str); 5] = [
        ("arm-throw", "arm.inertia_kgm2=1e300", "`arm.inertia_kgm2`"),
        (
            "arm-throw",
            "arm.torque_max_nm=1e300",
            "`arm.torque_max_nm`",
        ),
        (
            "hopper-servo-sil",
            "hopper.servo.target_energy_jpkg=1e300",
            "`hopper.servo.target_energy_jpkg`",
        ),
        (
            "planar-juggler",
            "planar_juggler.gravity_mps2=1e-320",
            "`planar_juggler.gravity_mps2`",
        ),
        (
            "spatial-juggler",
            "spatial_juggler.gravity_mps2=1e-320",
            "`spatial_juggler.gravity_mps2`",
        ),
    ];
    for (name, set, key) in cases {
        let (code, err) = with_sets(name, &[], &[set]);
        assert_eq!(code, Some(2), "{set}: {err}");
        assert!(err.contains(key), "{set} should name {key}: {err}");
        for internal in [
            "thrust.",
            "limits.",
            "core's arm controller rejects",
            "kappa1 must",
        ] {
            assert!(!err.contains(internal), "{set}: {internal} in {err}");
        }
    }
}

/// Finding 14: hopper analyze does not blame `hopper.initial_heights_m` (which the user did
/// not set) when the thrust drives the probed orbit out of the model's domain.
#[test]
fn hopper_analyze_blames_the_orbit_not_the_start() {
    let s = scene("hopper-fig11");
    let (code, err) = run(&["analyze", &s, "--set", "hopper.thrust_tau_mps2=1.0"]);
    assert_eq!(code, Some(1), "{err}");
    assert!(err.contains("hopper.thrust_tau_mps2"), "{err}");
    assert!(err.contains("not hopper.initial_heights_m"), "{err}");
    assert!(!err.contains("000000000000"), "{err}");
}

/// Finding 14: an integer beyond i64 is reported as out of range, not as a string.
#[test]
fn an_integer_beyond_i64_is_out_of_range() {
    let err = refused(
        &[
            "run",
            &scene("line-juggler"),
            "--set",
            "sensor.seed=99999999999999999999",
        ],
        "sensor.seed",
    );
    assert!(!err.contains("invalid type: string"), "{err}");
    assert!(err.contains("9223372036854775807"), "{err}");
}

/// Finding 14: a line sweep takes an integer key as the other systems do.
#[test]
fn a_line_sweep_takes_an_integer_key() {
    let s = scene("line-juggler");
    let out = dexter(&["sweep", &s, "--range", "sensor.seed=1:4:4"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(!err.contains("expected u64"), "{err}");
}

/// Finding 14: a bad `scene.name` is refused before the run, exit 2 naming `scene.name`.
#[test]
fn a_bad_scene_name_is_refused_before_the_run() {
    let dir = common::scratch("bad-scene-name");
    let plot = dir.display().to_string();
    let long = format!("scene.name={}", "x".repeat(300));
    for set in [
        "scene.name=a/b",
        "scene.name=\"\"",
        long.as_str(),
        "scene.name=..",
    ] {
        let (code, err) = with_sets("line-juggler", &["--plot", &plot], &[set]);
        assert_eq!(code, Some(2), "{set}: {err}");
        assert!(err.contains("scene.name"), "{set}: {err}");
    }
    // nothing was plotted
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}
