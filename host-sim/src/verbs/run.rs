//! `dexter run`, for every system.

use super::{print_result, RunRequest};
use crate::controller::StepController;
use crate::output::{TraceFile, TraceRow};
use crate::scene::{parse_sets, SceneFile};
use crate::system::{unsupported, Failure, HilRequest, OnTarget, Outcome, Plots, Setup, System};

/// `dexter run` on a scene of system `S`: parse, run (streaming the trace and the plots'
/// points), commit the trace, draw the plots, print the summary.
pub fn run<S: System>(file: &SceneFile, req: &RunRequest) -> Result<(), Failure> {
    let mut table = file.table_with(&parse_sets(&req.sets)?)?;
    S::LENGTH.apply(S::NAME, &mut table, req.impacts, req.duration)?;
    let cfg = S::parse(file, table)?;
    let mut trace = match &req.trace {
        Some(p) => Some(TraceFile::create(p, <S::Row as TraceRow>::HEADER)?),
        None => None,
    };
    let mut plots = req.plot.as_ref().map(|_| S::Plots::new(&cfg));
    let setup = Setup {
        plot: req.plot.is_some(),
        progress: !req.json,
    };
    let keeps_rows = trace.is_some() || plots.is_some();
    let mut record = |row: &S::Row| {
        if let Some(t) = trace.as_mut() {
            t.push(row);
        }
        if let Some(p) = plots.as_mut() {
            p.push(row);
        }
    };
    let mut ignore = |_: &S::Row| {};
    let rows: &mut dyn FnMut(&S::Row) = match keeps_rows {
        true => &mut record,
        false => &mut ignore,
    };
    let outcome = match req.on_target() {
        None => S::run(&cfg, None, &setup, rows)?,
        Some(h) => run_on_target::<S>(&cfg, h, &setup, rows)?,
    };
    if let Some(t) = trace {
        t.commit()?;
    }
    if let (Some(p), Some(dir)) = (plots, &req.plot) {
        for f in p.write(&cfg, &outcome, dir)? {
            eprintln!("wrote {}", f.display());
        }
    }
    print_result(req.json, || outcome.text(), || outcome.json())?;
    verdict(&outcome)
}

/// The exit status of a run whose summary was printed: a controller mostly in its safe
/// state, or a run cut short, is a failure (after a warning for any safe state).
fn verdict(outcome: &impl Outcome) -> Result<(), Failure> {
    if let Some(safe) = outcome.safe_steps() {
        if let Some(w) = safe.warning() {
            eprintln!("warning: {w}");
        }
        if safe.mostly_safe() {
            return Err(Failure::run(
                "the controller spent more than half of the run in its safe state",
            ));
        }
    }
    match outcome.shortfall() {
        Some(why) => Err(Failure::run(format!("the run stopped early: {why}"))),
        None => Ok(()),
    }
}

/// The run with the system's controller on the target (`--hil`).
fn run_on_target<S: System>(
    cfg: &S::Config,
    req: &HilRequest,
    setup: &Setup,
    rows: &mut dyn FnMut(&S::Row),
) -> Result<S::Outcome, Failure> {
    let params = S::controller_params(cfg)?.ok_or_else(|| unsupported::<S>("--hil"))?;
    let mut target = <S::Controller as OnTarget>::start(params, req)?;
    let ctrl: &mut dyn StepController<S::Controller> = target.as_mut();
    let mut outcome = S::run(cfg, Some(ctrl), setup, rows)?;
    outcome.attach_hil(target.finish().map_err(Failure::run)?);
    Ok(outcome)
}
