//! The controllers this firmware image hosts, as one enum the server dispatches on.
//!
//! Every hosted controller is a [`FixedRate`] controller of the core with a [`Wire`] impl
//! (one line in `dexter_core::protocol`'s kind list). Hosting one more is one line in the
//! `hosted!` list at the end of this file; the server, the links and the host's HIL driver
//! do not change. A kind that is not listed here is refused at `Configure`
//! (`Rejection::NotHosted`), so an image can leave out the controllers a board does not
//! run, to save flash.
//!
//! Timing: [`Hosted::step`] and [`Hosted::safe`] measure the core's `step`/`safe` call
//! only, with interrupts masked; the dispatch on the kind and the wrapping of the command
//! into [`Command`] are outside the measured window.

use crate::board::StepTimer;
use dexter_core::fixed_rate::FixedRate;
use dexter_core::params::ParamError;
use dexter_core::protocol::{Command, Config, Fault, Frame, Kind, Telemetry, Wire};

/// Measure `f` with interrupts masked, so a receive interrupt that lands inside the
/// window is not counted as part of the control step (it runs right after).
#[inline(always)]
fn measure_masked<T: StepTimer, R>(timer: &T, f: impl FnOnce() -> R) -> (R, u32) {
    cortex_m::interrupt::free(|_| timer.measure(f))
}

/// One control step of `controller` on `frame`, if the frame is of its kind: the command
/// and the instructions `C::step` took; else the frame's kind.
#[inline(always)]
fn step_as<C: Wire, T: StepTimer>(
    controller: &mut C,
    frame: &Frame,
    timer: &T,
) -> Result<(Command, u32), Kind> {
    let Some(frame) = C::frame_of(frame) else {
        return Err(frame.kind());
    };
    let (command, instructions) = measure_masked(timer, || controller.step(frame));
    Ok((C::command(command), instructions))
}

/// The safe command of `controller` and the instructions `C::safe` took.
#[inline(always)]
fn safe_as<C: Wire, T: StepTimer>(
    controller: &mut C,
    seq: u32,
    fault: Fault,
    timer: &T,
) -> (Command, u32) {
    let (command, instructions) = measure_masked(timer, || controller.safe(seq, fault));
    (C::command(command), instructions)
}

/// `Hosted`: one variant per hosted controller, and its dispatch.
macro_rules! hosted {
    ($($(#[$doc:meta])* $name:ident($controller:ty)),+ $(,)?) => {
        /// A configured controller of one of the kinds this image hosts.
        ///
        /// Its variants differ in size by design: there is no heap to box the large ones
        /// into, and the server holds exactly one `Hosted` in static RAM, sized by the
        /// largest kind (the linker's RAM budget checks it).
        #[allow(clippy::large_enum_variant)]
        pub enum Hosted {
            $($(#[$doc])* $name($controller),)+
        }

        impl Hosted {
            /// The controller `config` asks for: `None` if this image does not host its
            /// kind, else the controller or the error naming its first invalid parameter.
            pub fn configure(config: &Config) -> Option<Result<Self, ParamError>> {
                $(if let Some(params) = <$controller as Wire>::params_of(config) {
                    return Some(<$controller as FixedRate>::new(*params).map(Hosted::$name));
                })+
                None
            }

            /// The configured controller's kind.
            pub fn kind(&self) -> Kind {
                match self {
                    $(Hosted::$name(_) => <$controller as Wire>::KIND,)+
                }
            }

            /// One control step on `frame`: the command and the instructions the core's
            /// `step` took, or the frame's kind if it is not the configured one.
            pub fn step<T: StepTimer>(
                &mut self,
                frame: &Frame,
                timer: &T,
            ) -> Result<(Command, u32), Kind> {
                match self {
                    $(Hosted::$name(c) => step_as(c, frame, timer),)+
                }
            }

            /// The safe command for an external fault, and the instructions it took.
            pub fn safe<T: StepTimer>(&mut self, seq: u32, fault: Fault, timer: &T) -> (Command, u32) {
                match self {
                    $(Hosted::$name(c) => safe_as(c, seq, fault, timer),)+
                }
            }

            /// What the core reports about its estimate.
            pub fn telemetry(&self) -> Telemetry {
                match self {
                    $(Hosted::$name(c) => c.telemetry(),)+
                }
            }
        }
    };
}

hosted! {
    /// The line juggler (mirror law, estimator, paddle tracker).
    Line(dexter_core::control::Controller),
    /// The link check (echoes a scaled value).
    Echo(dexter_core::echo::Echo),
    /// The one-joint arm (B-spline trajectory tracker with inverse dynamics).
    Arm(dexter_core::arm_control::ArmController),
}
