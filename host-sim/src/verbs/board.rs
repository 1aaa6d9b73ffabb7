//! `dexter board SCENE`: what the NUCLEO-F446RE's stand-alone juggling loop needs of a line
//! scene (boards/nucleo-f446re, firmware/README.md "The scene on the board"): the scene's
//! controller, validated exactly as `dexter run` validates it, as the `Configure` frame the
//! host would send in HIL (`--write FILE`: the file the board's build includes), and the
//! camera the controller then needs: the slowest frame rate before it faults `Stale`, and
//! the latency its estimator compensates.

use crate::output::write_atomic;
use crate::scene::{parse_sets, SceneFile};
use crate::system::{Failure, System};
use crate::systems::line::LineSystem;
use clap::Args;
use dexter_core::control::ControllerParams;
use dexter_core::protocol::{encode, Config, HostMessage, MAX_FRAME_LEN};
use std::path::PathBuf;

/// The board's control rate, Hz (`boards/nucleo-f446re`: `CONTROL_RATE_HZ`, TIM2's tick).
pub const BOARD_CONTROL_RATE_HZ: f64 = 500.0;

/// `dexter board SCENE ...` as parsed from the command line.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct BoardRequest {
    /// The line scene (TOML) whose controller the board's stand-alone loop runs.
    pub scene: PathBuf,
    /// Override a scene key: key.path=value (repeatable).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub sets: Vec<String>,
    /// Write the scene's `Configure` frame to this file (the board build's
    /// `DEXTER_BOARD_CONFIGURE`; boards/nucleo-f446re/scene.configure by default).
    #[arg(long, value_name = "FILE")]
    pub write: Option<PathBuf>,
    /// Print the figures as one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// The `Configure` frame of `params`, exactly as the HIL host sends it.
pub fn configure_frame(params: ControllerParams) -> Result<Vec<u8>, Failure> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode(&HostMessage::Configure(Config::Line(params)), &mut buf)
        .map_err(|e| Failure::run(format!("cannot encode the Configure frame: {e:?}")))?;
    Ok(buf[..n].to_vec())
}

/// `dexter board` on a scene the registry gave to the system `system` (only the line
/// system's scenes run stand-alone on the board).
pub fn board(system: &str, file: &SceneFile, req: &BoardRequest) -> Result<(), Failure> {
    if system != LineSystem::NAME {
        return Err(Failure::usage(format!(
            "dexter board: the board's stand-alone loop runs the line juggler, and this is a \
             scene of the {system} system (run it on the board in HIL: dexter run SCENE --hil --port PORT)"
        )));
    }
    let table = file.table_with(&parse_sets(&req.sets)?)?;
    let scene = LineSystem::parse(file, table)?;
    let Some(params) = LineSystem::controller_params(&scene)? else {
        return Err(Failure::usage("the scene has no controller"));
    };
    let rate_hz = scene.control.rate_hz;
    if rate_hz != BOARD_CONTROL_RATE_HZ {
        return Err(Failure::usage(format!(
            "`control.rate_hz`: the board's control task runs at {BOARD_CONTROL_RATE_HZ} Hz \
             (TIM2), the scene asks for {rate_hz} Hz"
        )));
    }
    let frame = configure_frame(params)?;
    let stale_s = f64::from(params.stale_limit_steps) / rate_hz;
    let figures = serde_json::json!({
        "scene": scene.name(),
        "control_rate_hz": rate_hz,
        "camera_min_rate_fps": 1.0 / stale_s,
        "camera_max_interval_s": stale_s,
        "camera_latency_s": f64::from(params.estimator.latency_s),
        "configure_bytes": frame.len(),
    });
    let text = format!(
        "scene {}: the board's stand-alone loop runs its controller at {rate_hz} Hz\n\
         camera: at least {:.1} frames/s (the controller faults `Stale` after {} periods, \
         {:.1} ms, without a new image)\n\
         camera latency the estimator compensates: {:.1} ms (estimator.latency_s, else \
         sensor.latency_s): measure the camera's and set it in the scene\n",
        scene.name(),
        1.0 / stale_s,
        params.stale_limit_steps,
        stale_s * 1e3,
        f64::from(params.estimator.latency_s) * 1e3,
    );
    super::print_result(req.json, || text, || Ok(format!("{figures:#}")))?;
    if let Some(path) = &req.write {
        write_atomic(path, &frame)?;
        crate::output::note(format_args!(
            "wrote {} ({} bytes): build the board with DEXTER_BOARD_CONFIGURE={}",
            path.display(),
            frame.len(),
            path.display()
        ));
    }
    Ok(())
}
