//! `dexter run`, for every system.

use super::{print_result, RunRequest};
use crate::controller::StepController;
use crate::output::{note, Batch, TraceFile, TraceRow};
use crate::scene::{parse_sets, SceneFile};
use crate::system::{unsupported, Failure, HilRequest, OnTarget, Outcome, Plots, Setup, System};

/// `dexter run` on a scene of system `S`: parse, run (streaming the trace and the plots'
/// points), and, if the run succeeded, commit the trace and draw the plots (renamed into
/// place together: [`Batch`]); then print the summary. A run that fails (exit 1, or an
/// error before its end) writes no output file: a previous trace or plot stays as it was.
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
    let (warning, verdict) = verdict(&outcome);
    let batch = Batch::begin();
    let mut written = Vec::new();
    if verdict.is_ok() {
        if let Some(t) = trace {
            t.commit()?; // held back by the batch
        }
        if let (Some(p), Some(dir)) = (plots, &req.plot) {
            written = p.write(&cfg, &outcome, dir)?;
        }
    } else if trace.is_some() || plots.is_some() {
        drop(trace); // its temporary file is removed: the old trace stays
        note(not_written(req));
    }
    // the summary before the renames: a run whose summary cannot be printed (a full
    // stdout) fails, and writes nothing
    print_result(req.json, || outcome.text(), || outcome.json())?;
    batch.commit()?;
    for f in written {
        note(format_args!("wrote {}", f.display()));
    }
    if let Some(w) = warning {
        note(format_args!("warning: {w}"));
    }
    verdict
}

/// What a failed run did not write (`--trace`, `--plot`), for stderr.
fn not_written(req: &RunRequest) -> String {
    let mut what = Vec::new();
    if let Some(t) = &req.trace {
        what.push(format!("the trace {}", t.display()));
    }
    if let Some(p) = &req.plot {
        what.push(format!("the plots in {}", p.display()));
    }
    format!(
        "note: the run failed, so {} {} not written (any previous file is left as it was)",
        what.join(" and "),
        if what.len() > 1 { "were" } else { "was" }
    )
}

/// The verdict on a run whose summary is printed: a controller mostly in its safe state,
/// or a run cut short, is a failure; and the warning for any safe state (printed after the
/// summary).
fn verdict(outcome: &impl Outcome) -> (Option<String>, Result<(), Failure>) {
    let mut warning = None;
    if let Some(safe) = outcome.safe_steps() {
        warning = safe.warning();
        if safe.mostly_safe() {
            let f =
                Failure::run("the controller spent more than half of the run in its safe state");
            return (warning, Err(f));
        }
    }
    let result = match outcome.shortfall() {
        Some(why) => Err(Failure::run(format!("the run stopped early: {why}"))),
        None => Ok(()),
    };
    (warning, result)
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
