//! The controllers this firmware image hosts, as one enum the server dispatches on.
//!
//! Every hosted controller is a [`FixedRate`] controller of the core with a [`Wire`] impl
//! (its variants in `dexter_core::protocol::kinds`). The hosted kinds are not listed here:
//! `Hosted` is generated from the core's one list of kinds (`dexter_core::for_each_kind!`),
//! each behind the cargo feature that list names; the server, the links and the host's HIL driver
//! do not change. A kind this image leaves out is refused at `Configure`
//! (`Rejection::NotHosted`), so an image can leave out the controllers a board does not
//! run, to save flash.
//!
//! Which kinds an image hosts is a cargo feature selection (firmware/Cargo.toml): the line
//! juggler and the link check always; the tilt table (`tilt`), the hopper (`hop`) and the
//! one-joint arm (`arm`) and the spatial juggler (`spatial`) each behind its feature. The default image (`tilt`, `hop`) is the
//! one `memory.x`'s 32 KiB of flash was sized for; the arm image is built with
//! `--no-default-features --features arm` (firmware/README.md, "Images"). A kind's
//! `if <cfg predicate>` in that list gates its variant and every match arm on it.
//!
//! Timing: [`Hosted::step`] and [`Hosted::safe`] measure the core's `step`/`safe` call
//! only, with interrupts masked; the dispatch on the kind and the wrapping of the command
//! into [`Command`] are outside the measured window.

use crate::board::StepTimer;
use dexter_core::fixed_rate::{Fault, FixedRate, Telemetry};
use dexter_core::params::ParamError;
use dexter_core::protocol::{self, Command, Frame, Kind, Wire};
use serde::de::VariantAccess;

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

/// A controller of kind `C` from `params`, or the error naming the first invalid one.
///
/// Not inlined, and generic, so that each kind's constructor and validation (cold code,
/// `#[inline]` in the core) are compiled here, once, with the firmware's size-optimised
/// profile (`Cargo.toml`), rather than with the core's speed-optimised one or into every
/// caller.
#[inline(never)]
fn configure_as<C: Wire>(params: &C::Params) -> Result<C, ParamError> {
    C::new(*params)
}

/// [`protocol::HostedKinds`] for an enum with one variant per hosted kind (`Params`): its
/// kind, and the decoder of each hosted kind's value.
macro_rules! hosted_kinds {
    ($enum:ident { $($(#[cfg($cfg:meta)])? $name:ident($controller:ty)),+ }) => {
        impl protocol::HostedKinds for $enum {
            fn kind(&self) -> Kind {
                match self {
                    $(#[cfg(all($($cfg)?))] $enum::$name(_) => <$controller as Wire>::KIND,)+
                }
            }

            fn decode<'de, A: VariantAccess<'de>>(
                kind: Kind,
                body: A,
            ) -> Result<Result<Self, A>, A::Error> {
                $(#[cfg(all($($cfg)?))]
                if kind == <$controller as Wire>::KIND {
                    return body.newtype_variant().map(|v| Ok($enum::$name(v)));
                })+
                Ok(Err(body))
            }
        }
    };
}

/// `Hosted`: one variant per hosted controller, and its dispatch.
macro_rules! hosted {
    ($($name:ident($core:ty) $(if $cfg:meta)?),+ $(,)?) => {
        /// A configured controller of one of the kinds this image hosts.
        ///
        /// Its variants differ in size by design: there is no heap to box the large ones
        /// into, and the server holds exactly one `Hosted` in static RAM, sized by the
        /// largest kind (the linker's RAM budget checks it).
        #[allow(clippy::large_enum_variant)]
        pub enum Hosted {
            $(#[doc = concat!("The `", stringify!($name), "` kind (`protocol::Kind::", stringify!($name), "`).")]
            #[cfg(all($($cfg)?))] $name(hosted_type!($name, $core)),)+
        }

        /// The parameters of a kind this image hosts, as `Configure` decodes them (the
        /// decoder of a kind it does not host is left out: `protocol::Partial`).
        #[derive(Clone, Copy)]
        pub enum Params {
            $(#[doc = concat!("The `", stringify!($name), "` kind's parameters.")]
            #[cfg(all($($cfg)?))] $name(<$core as FixedRate>::Params),)+
        }

        hosted_kinds!(Params { $($(#[cfg($cfg)])? $name($core)),+ });

        impl Hosted {
            /// The controller `params` ask for, or the error naming its first invalid
            /// parameter.
            pub fn configure(params: &Params) -> Result<Self, ParamError> {
                match params {
                    $(#[cfg(all($($cfg)?))]
                    Params::$name(p) => configure_as::<hosted_type!($name, $core)>(p).map(Hosted::$name),)+
                }
            }

            /// The configured controller's kind.
            pub fn kind(&self) -> Kind {
                match self {
                    $(#[cfg(all($($cfg)?))] Hosted::$name(_) => <$core as Wire>::KIND,)+
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
                    $(#[cfg(all($($cfg)?))] Hosted::$name(c) => step_as(c, frame, timer),)+
                }
            }

            /// The safe command for an external fault, and the instructions it took.
            pub fn safe<T: StepTimer>(&mut self, seq: u32, fault: Fault, timer: &T) -> (Command, u32) {
                match self {
                    $(#[cfg(all($($cfg)?))] Hosted::$name(c) => safe_as(c, seq, fault, timer),)+
                }
            }

            /// What the core reports about its estimate.
            pub fn telemetry(&self) -> Telemetry {
                match self {
                    $(#[cfg(all($($cfg)?))] Hosted::$name(c) => c.telemetry(),)+
                }
            }
        }
    };
}

/// The tilt controller this image hosts: the shipped [`TiltController`] (polynomial sine and
/// cosine), or with the feature `tilt-backend-sincos` (a measurement build, see
/// firmware/Cargo.toml) the one with the math backend's (libm, or micromath with
/// `fast-math`), to measure what accuracy costs on the target.
///
/// [`TiltController`]: dexter_core::tilt_control::TiltController
#[cfg(all(feature = "tilt", not(feature = "tilt-backend-sincos")))]
type HostedTilt = dexter_core::tilt_control::TiltController;
#[cfg(feature = "tilt-backend-sincos")]
type HostedTilt =
    dexter_core::tilt_control::TiltControllerWith<dexter_core::tilt_control::sincos::BackendSinCos>;

/// The type in kind `$name`'s slot: the core's controller `$core`, but [`HostedTilt`] in the
/// tilt slot.
macro_rules! hosted_type {
    (Tilt, $core:ty) => {
        HostedTilt
    };
    ($name:ident, $core:ty) => {
        $core
    };
}

// The hosted kinds are the core's list (`dexter_core::for_each_kind!`, in
// `protocol/kinds.rs`), each behind the image feature the list names.
dexter_core::for_each_kind!(hosted);
