//! The line scenes through the `dexter` binary, where a run could be silently wrong or
//! unbounded: a sensor faster than the controller simulates the whole requested time,
//! rates and integrator settings with no bound are refused naming the key and the bound,
//! a controller in its safe state is reported (and a run mostly in it fails), and every
//! summary says which limit ended the run.

use crate::common;

use common::{dexter, json, scene};
use serde_json::Value;

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A sensor sampling 5000 times per control period (1 MHz against 200 Hz): the run
/// simulates the whole second asked for, every control period whole (the run used to stop
/// each period after 2048 samples, so half the time went missing without a word).
#[test]
fn a_sensor_faster_than_the_controller_simulates_the_whole_time() {
    let v = json(&[
        "run",
        &scene("line-juggler"),
        "--set",
        "control.rate_hz=200",
        "--set",
        "sensor.rate_hz=1e6",
        "--duration",
        "1",
        "--json",
    ]);
    assert_eq!(v["sim_time_s"], 1.0, "{v}");
    assert_eq!(v["control_steps"], 200);
    assert_eq!(v["end"], "duration");
    // and the time a run simulates is the time asked for at the default rates too
    let v = json(&["run", &scene("line-juggler"), "--duration", "7", "--json"]);
    assert_eq!(
        (v["sim_time_s"].as_f64(), v["control_steps"].as_u64()),
        (Some(7.0), Some(3500))
    );
}

/// Settings whose run would make no progress, or no bounded one, are refused with the key
/// and the bound (exit 2, before anything runs).
#[test]
fn unbounded_rates_and_integrator_settings_are_refused_naming_the_bound() {
    let juggler = scene("line-juggler");
    let ideal = scene("line-juggler-ideal");
    let cases: [(&str, &[&str], &str, &str); 6] = [
        (
            &juggler,
            &["sensor.rate_hz=2e6"],
            "sensor.rate_hz",
            "must be <= 1e6",
        ),
        (
            &juggler,
            &["sensor.rate_hz=1e9"],
            "sensor.rate_hz",
            "must be <= 1e6",
        ),
        (
            &juggler,
            &["control.rate_hz=1e9"],
            "control.rate_hz",
            "must be <= 100000",
        ),
        (
            &juggler,
            &["sensor.rate_hz=1e5", "sensor.latency_s=0.1"],
            "sensor.latency_s",
            "more than the 4096",
        ),
        (
            &ideal,
            &["drag.step_s=1e-12"],
            "drag.step_s",
            "must be >= 1e-6",
        ),
        (
            &ideal,
            &["drag.integrator=\"rk45\"", "drag.tolerance=1e-300"],
            "drag.tolerance",
            "must be >= 1e-12",
        ),
    ];
    for (s, sets, key, bound) in cases {
        let mut args = vec!["run", s];
        for set in sets {
            args.extend(["--set", set]);
        }
        let out = dexter(&args);
        let err = stderr(&out);
        assert_eq!(out.status.code(), Some(2), "{sets:?}: {err}");
        assert!(err.contains(key) && err.contains(bound), "{sets:?}: {err}");
    }
    // the bounds themselves are accepted
    let ok = dexter(&["run", &ideal, "--set", "drag.step_s=1e-6", "--impacts", "2"]);
    assert!(ok.status.success(), "{}", stderr(&ok));
}

/// A sensor so noisy that every frame is implausible: the controller sits in its safe
/// state. The summary counts the safe steps by fault, the terminal says so, and a run
/// spent mostly safe exits 1 (it did not juggle).
#[test]
fn a_controller_in_its_safe_state_is_reported() {
    let out = dexter(&[
        "run",
        &scene("line-juggler"),
        "--set",
        "sensor.noise_sigma_m=1e6",
        "--json",
    ]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("warning: the controller was in its safe state"),
        "{err}"
    );
    assert!(
        err.contains("more than half of the run in its safe state"),
        "{err}"
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("the summary is still printed");
    let steps = v["control_steps"].as_u64().unwrap();
    assert!(steps > 0);
    assert_eq!(v["safe_steps"].as_u64(), Some(steps));
    assert_eq!(v["faults"]["out_of_range"].as_u64(), Some(steps), "{v}");
    // a noisy sensor that trips the plausibility check now and then: counted, warned,
    // exit 0 (the text summary names the faults too)
    let out = dexter(&[
        "run",
        &scene("line-juggler"),
        "--set",
        "sensor.noise_sigma_m=0.3",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("safe state") && text.contains("out_of_range"),
        "{text}"
    );
    assert!(stderr(&out).contains("warning: the controller was in its safe state"));
    // a clean run: no safe steps, an empty fault map, no warning
    let out = dexter(&["run", &scene("line-juggler"), "--json"]);
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (
            v["safe_steps"].as_u64(),
            v["faults"].as_object().map(|m| m.len())
        ),
        (Some(0), Some(0))
    );
    assert!(!stderr(&out).contains("warning"));
}

/// Every summary says which limit ended the run.
#[test]
fn the_summary_names_what_ended_the_run() {
    let ideal = scene("line-juggler-ideal");
    assert_eq!(json(&["run", &ideal, "--json"])["end"], "impacts");
    let v = json(&["run", &ideal, "--duration", "3", "--json"]);
    assert_eq!(v["end"], "duration");
    assert_eq!(v["sim_time_s"], 3.0);
    assert_eq!(
        json(&["run", &scene("passive-bounce"), "--json"])["end"],
        "resting"
    );
    // a resting contact forced by the Zeno cap says so; a detected one does not
    let v = json(&[
        "run",
        &scene("line-juggler"),
        "--set",
        "zeno.max_impacts_per_segment=1",
        "--json",
    ]);
    assert_eq!(v["resting_forced"], true, "{v}");
    assert!(json(&["run", &scene("passive-bounce"), "--json"])
        .get("resting_forced")
        .is_none());
    let text = String::from_utf8(common::ok(&["run", &ideal, "--duration", "3"]).stdout).unwrap();
    assert!(
        text.contains("ended            at the time limit"),
        "{text}"
    );
}

/// The line sweep says, per value, the period the run settled to and which limit ended it:
/// just below the first doubling of eq. 8 (beta v*^2 = 1) a run cut short by its time
/// limit is still settling, and is reported as not settled, never period 2; well inside
/// the windows on either side the period is the attractor's.
#[test]
fn the_line_sweep_reports_settled_periods_and_the_end() {
    // beta v*^2 = 0.9 kappa1 19.62: 1 at kappa1 = 0.056632
    let kappa1 = |c: f64| c / (0.9 * 2.0 * 9.81);
    let range = format!("control.kappa1_s2pm2={}:{}:3", kappa1(0.7), kappa1(0.998));
    let out = common::ok(&[
        "sweep",
        &scene("line-juggler-chaotic"),
        "--range",
        &range,
        "--set",
        "stop.duration_s=100",
        "--keep",
        "8",
    ]);
    let csv = String::from_utf8(out.stdout).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("control.kappa1_s2pm2,period,end,apex_height_m")
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(rows.len(), 3 * 8);
    // the time limit (100 s, about 110 impacts) ends every run before its 400 impacts
    assert!(rows.iter().all(|r| r[2] == "duration"), "{csv}");
    assert_eq!(rows[0][1], "1", "c = 0.7 settles fast: {csv}");
    let near = &rows[16][1];
    assert!(
        near.is_empty(),
        "c = 0.998 is still settling, not period {near}: {csv}"
    );
}

/// A long run shows a progress bar on a terminal (here a pseudo-terminal from `script`),
/// towards the first of its limits; in a pipe it draws nothing. The bar's delay is set to
/// 0 ms, so the test does not depend on how long the run takes on this machine.
#[test]
fn a_long_run_shows_a_progress_bar_on_a_terminal() {
    let cmd = format!(
        "DEXTER_PROGRESS_REVEAL_MS=0 {} run {} --impacts 20000",
        env!("CARGO_BIN_EXE_dexter"),
        scene("line-juggler")
    );
    let out = std::process::Command::new("script")
        .args(["-qec", &cmd, "/dev/null"])
        .output()
        .expect("`script` (util-linux) runs");
    let tty = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{tty}");
    assert!(
        tty.contains("% ") && tty.contains(" impacts, ") && tty.contains(" s simulated"),
        "no progress bar on the terminal: {tty}"
    );
    let piped = dexter(&["run", &scene("line-juggler"), "--impacts", "20000"]);
    assert!(stderr(&piped).is_empty(), "{}", stderr(&piped));
}

/// Impact-timing jitter of sigma 1 s (clamped to 4 s) on the ideal mirror: the jittered
/// paddle velocity sends the ball down at -3.9 m/s from a paddle moving up at 1.1 m/s, into
/// the paddle. That is no impact at all: the run fails naming the key, where it used to go
/// on and report a Zeno rest "on the table" of a scene with no table. The shipped 10 ms
/// jitter stays physical.
#[test]
fn jitter_that_makes_an_impact_unphysical_fails_the_run_naming_the_key() {
    let out = dexter(&[
        "run",
        &scene("line-juggler-ideal"),
        "--set",
        "jitter.sigma_s=1",
        "--impacts",
        "50",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    assert!(
        err.contains("unphysical impact") && err.contains("slower than the paddle"),
        "{err}"
    );
    assert!(err.contains("jitter.sigma_s"), "{err}");
    assert!(!String::from_utf8_lossy(&out.stdout).contains("resting"));
    for sigma in ["0.01", "0.05"] {
        let v = json(&[
            "run",
            &scene("line-juggler-jitter"),
            "--set",
            &format!("jitter.sigma_s={sigma}"),
            "--json",
        ]);
        assert_eq!(v["end"], "impacts", "sigma {sigma}: {v}");
    }
}
