//! The one fixed-rate closed loop: a [`SampledPlant`] closed through a [`StepController`]
//! (the core linked in, [`crate::controller::Sil`], or the firmware behind a link).
//!
//! Control step k happens at t_k = k dt ([`SampledPlant::time_s`]): the plant hands out the
//! sensor frame of t_k (after taking the samples due), the controller answers with a
//! command, the plant holds it over [t_k, t_k+1) (zero-order hold) and advances exactly to
//! t_k+1, taking its own events and sensor samples in between. [`drive`] owns k, the step
//! cap and the safe-state count ([`SafeSteps`], the one counter every closed-loop summary
//! reports); a controller error ends the run as an error. The HIL figures are not read
//! here: the caller that started the target gets them when it stops it
//! (`crate::external::Target::finish`).
//!
//! A plant declares its three methods (frame, apply, advance) and how its run ends; that
//! is all a new closed-loop system writes. [`drive`] is `#[inline(always)]` and generic
//! over the controller's type, so a loop closed through [`crate::controller::Sil`] is
//! monomorphized: no dynamic call, no telemetry built ([`StepController::command`]).

use crate::controller::{ControllerError, SafeSteps, StepController};
use dexter_core::fixed_rate::FixedRate;
use std::ops::ControlFlow;

/// A plant sampled and commanded at the fixed rate of a controller of kind `C`.
pub trait SampledPlant<C: FixedRate> {
    /// How a run of this plant ends before its step cap (e.g. the requested impacts or
    /// cycles happened, the body tipped over).
    type End;
    /// Why a run fails (the plant cannot go on, or the controller failed).
    type Error: From<ControllerError>;

    /// The time of control step `k` with period `dt_s`, s. Each plant keeps the float
    /// expression its outputs were blessed with: `k as f64 * dt_s` by default.
    #[inline(always)]
    fn time_s(k: u64, dt_s: f64) -> f64 {
        k as f64 * dt_s
    }

    /// Before step `k`: `Some` if the run is over already (checked before every step).
    #[inline(always)]
    fn done(&self) -> Option<Self::End> {
        None
    }

    /// The sensor frame of step `k` at `t_k_s`, after taking the samples due by then.
    fn frame(&mut self, k: u64, t_k_s: f64) -> C::Frame;

    /// Apply `command`, held over the period that starts at step `k` (`t_k_s`).
    fn apply(&mut self, k: u64, t_k_s: f64, command: &C::Command);

    /// Advance exactly to the end of step `k`'s period, `t_next_s`: `Break` ends the run.
    fn advance(&mut self, k: u64, t_next_s: f64) -> Result<ControlFlow<Self::End>, Self::Error>;
}

/// How a driven run ended.
#[derive(Clone, Debug, PartialEq)]
pub struct Driven<E> {
    /// The plant's end (`None`: the step cap was reached).
    pub end: Option<E>,
    /// Control steps taken and those answered in the safe state, by fault.
    pub safe: SafeSteps,
}

/// Close `plant`'s loop through `ctrl` at period `dt_s` for at most `max_steps` steps.
#[inline(always)]
pub fn drive<C, K, P>(
    ctrl: &mut K,
    plant: &mut P,
    dt_s: f64,
    max_steps: u64,
) -> Result<Driven<P::End>, P::Error>
where
    C: FixedRate,
    K: StepController<C> + ?Sized,
    P: SampledPlant<C>,
{
    let mut safe = SafeSteps::default();
    let mut end = None;
    let mut t_k = P::time_s(0, dt_s);
    for k in 0..max_steps {
        if let Some(e) = plant.done() {
            end = Some(e);
            break;
        }
        let frame = plant.frame(k, t_k);
        let command = ctrl.command(&frame)?;
        plant.apply(k, t_k, &command);
        safe.record(&command);
        let t_next = P::time_s(k + 1, dt_s);
        if let ControlFlow::Break(e) = plant.advance(k, t_next)? {
            end = Some(e);
            break;
        }
        t_k = t_next;
    }
    Ok(Driven { end, safe })
}
