//! The controller kinds on the wire: the one file of the core that names every kind.
//!
//! [`Kind`] lists them; [`Config`], [`Frame`] and [`Command`] have one variant per kind,
//! carrying that controller's [`FixedRate`] parameters, frames and commands; [`Wire`] maps a
//! controller to its variants, so the host's HIL driver and the firmware's server are
//! written once for every kind.
//!
//! The order of the variants is the wire tag (postcard writes the variant index): append a
//! kind at the end of every enum, never reorder. The arm's values are on the wire of every
//! host build and of a bare-metal build only with the core's feature `wire-arm` (a firmware
//! image that hosts the arm): it is last, so the tags before it do not depend on the
//! feature, and an image without it still names the kind (`Rejection::NotHosted(Kind::Arm)`)
//! with no code for its values. That gate costs nothing on the host and saves the other
//! images the arm's encoders (`boards/mps2-an386/memory.x` leaves little flash free). The
//! spatial juggler's values come after the arm's, on a bare-metal build's wire only with
//! `wire-spatial`, which implies `wire-arm` so that its tag does not depend on the arm's
//! feature.

#[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
use crate::arm_control::ArmController;
use crate::control::Controller;
use crate::echo::Echo;
use crate::fixed_rate::{Fault, FixedRate, Mode, Reply};
use crate::hop_control::HopController;
#[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
use crate::spatial_control::SpatialController;
use crate::tilt_control::{sincos::SinCos, TiltController, TiltControllerWith};
use serde::{Deserialize, Serialize};

/// The line juggler's parameters, frames and commands, re-exported where the protocol
/// carries them ([`Config::Line`], [`Frame::Line`], [`Command::Line`]).
pub use crate::control::{ActuatorCommand, ControllerParams, SensorFrame};

/// How a [`FixedRate`] controller travels on the wire: its [`Kind`], and the variants of
/// [`Config`], [`Frame`] and [`Command`] that carry its parameters, frames and commands.
///
/// Implemented in this module, once per kind (see the protocol's "Adding a controller
/// kind").
pub trait Wire: FixedRate {
    /// The controller's kind.
    const KIND: Kind;
    /// The `Configure` payload for `params`.
    fn config(params: Self::Params) -> Config;
    /// This kind's parameters, if `config` is of this kind.
    fn params_of(config: &Config) -> Option<&Self::Params>;
    /// The `Sensor` payload for `frame`.
    fn frame(frame: Self::Frame) -> Frame;
    /// This kind's frame, if `frame` is of this kind.
    fn frame_of(frame: &Frame) -> Option<&Self::Frame>;
    /// The `Output` payload for `command`.
    fn command(command: Self::Command) -> Command;
    /// This kind's command, if `command` is of this kind.
    fn command_of(command: &Command) -> Option<Self::Command>;
}

/// Which controller a configuration, frame or command is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Kind {
    /// The line juggler: mirror law, estimator and paddle tracker ([`Controller`]).
    Line,
    /// The link check: echoes a scaled value, no actuator ([`Echo`]).
    Echo,
    /// The kappa-tilt table with energy feedback ([`TiltController`]).
    Tilt,
    /// The hopper's thrust valve ([`HopController`]).
    Hop,
    /// The one-joint arm: a planned B-spline tracked with torque limits
    /// ([`ArmController`]).
    Arm,
    /// The spatial juggler: eq. 13, a three-axis ball estimator and three joint trackers
    /// (`SpatialController`).
    Spatial,
}

impl Kind {
    /// Every kind, in wire order.
    pub const ALL: &'static [Kind] = &[
        Kind::Line,
        Kind::Echo,
        Kind::Tilt,
        Kind::Hop,
        Kind::Arm,
        Kind::Spatial,
    ];
}

/// A controller kind and its parameters ([`HostMessage::Configure`](super::HostMessage)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Config {
    /// [`Kind::Line`]'s parameters.
    Line(<Controller as FixedRate>::Params),
    /// [`Kind::Echo`]'s parameters.
    Echo(<Echo as FixedRate>::Params),
    /// [`Kind::Tilt`]'s parameters.
    Tilt(<TiltController as FixedRate>::Params),
    /// [`Kind::Hop`]'s parameters.
    Hop(<HopController as FixedRate>::Params),
    /// [`Kind::Arm`]'s parameters (on a bare-metal build only with `wire-arm`).
    #[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
    Arm(<ArmController as FixedRate>::Params),
    /// [`Kind::Spatial`]'s parameters (on a bare-metal build only with `wire-spatial`).
    #[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
    Spatial(<SpatialController as FixedRate>::Params),
}

/// One sample of the plant for a controller kind ([`HostMessage::Sensor`](super::HostMessage)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Frame {
    /// [`Kind::Line`]'s frame.
    Line(<Controller as FixedRate>::Frame),
    /// [`Kind::Echo`]'s frame.
    Echo(<Echo as FixedRate>::Frame),
    /// [`Kind::Tilt`]'s frame.
    Tilt(<TiltController as FixedRate>::Frame),
    /// [`Kind::Hop`]'s frame.
    Hop(<HopController as FixedRate>::Frame),
    /// [`Kind::Arm`]'s frame (on a bare-metal build only with `wire-arm`).
    #[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
    Arm(<ArmController as FixedRate>::Frame),
    /// [`Kind::Spatial`]'s frame (on a bare-metal build only with `wire-spatial`).
    #[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
    Spatial(<SpatialController as FixedRate>::Frame),
}

/// One control period's output of a controller kind
/// ([`DeviceMessage::Output`](super::DeviceMessage::Output)).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Command {
    /// [`Kind::Line`]'s command.
    Line(<Controller as FixedRate>::Command),
    /// [`Kind::Echo`]'s command.
    Echo(<Echo as FixedRate>::Command),
    /// [`Kind::Tilt`]'s command.
    Tilt(<TiltController as FixedRate>::Command),
    /// [`Kind::Hop`]'s command.
    Hop(<HopController as FixedRate>::Command),
    /// [`Kind::Arm`]'s command (on a bare-metal build only with `wire-arm`).
    #[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
    Arm(<ArmController as FixedRate>::Command),
    /// [`Kind::Spatial`]'s command (on a bare-metal build only with `wire-spatial`).
    #[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
    Spatial(<SpatialController as FixedRate>::Command),
}

impl Config {
    /// The kind this configuration is for.
    pub fn kind(&self) -> Kind {
        match self {
            Config::Line(_) => Kind::Line,
            Config::Echo(_) => Kind::Echo,
            Config::Tilt(_) => Kind::Tilt,
            Config::Hop(_) => Kind::Hop,
            #[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
            Config::Arm(_) => Kind::Arm,
            #[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
            Config::Spatial(_) => Kind::Spatial,
        }
    }

    /// The default parameters of `kind` (tests and size checks); `None` for a kind this
    /// build leaves off the wire.
    pub fn default_for(kind: Kind) -> Option<Config> {
        Some(match kind {
            Kind::Line => Config::Line(Default::default()),
            Kind::Echo => Config::Echo(Default::default()),
            Kind::Tilt => Config::Tilt(Default::default()),
            Kind::Hop => Config::Hop(Default::default()),
            #[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
            Kind::Arm => Config::Arm(Default::default()),
            #[cfg(not(any(not(target_os = "none"), feature = "wire-arm")))]
            Kind::Arm => return None,
            #[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
            Kind::Spatial => Config::Spatial(Default::default()),
            #[cfg(not(any(not(target_os = "none"), feature = "wire-spatial")))]
            Kind::Spatial => return None,
        })
    }
}

impl Frame {
    /// The kind this frame is for.
    pub fn kind(&self) -> Kind {
        match self {
            Frame::Line(_) => Kind::Line,
            Frame::Echo(_) => Kind::Echo,
            Frame::Tilt(_) => Kind::Tilt,
            Frame::Hop(_) => Kind::Hop,
            #[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
            Frame::Arm(_) => Kind::Arm,
            #[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
            Frame::Spatial(_) => Kind::Spatial,
        }
    }

    /// A default (all-zero) frame of `kind` (tests and size checks); `None` for a kind this
    /// build leaves off the wire.
    pub fn default_for(kind: Kind) -> Option<Frame> {
        Some(match kind {
            Kind::Line => Frame::Line(Default::default()),
            Kind::Echo => Frame::Echo(Default::default()),
            Kind::Tilt => Frame::Tilt(Default::default()),
            Kind::Hop => Frame::Hop(Default::default()),
            #[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
            Kind::Arm => Frame::Arm(Default::default()),
            #[cfg(not(any(not(target_os = "none"), feature = "wire-arm")))]
            Kind::Arm => return None,
            #[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
            Kind::Spatial => Frame::Spatial(Default::default()),
            #[cfg(not(any(not(target_os = "none"), feature = "wire-spatial")))]
            Kind::Spatial => return None,
        })
    }
}

impl Command {
    /// The kind this command is from.
    pub fn kind(&self) -> Kind {
        match self {
            Command::Line(_) => Kind::Line,
            Command::Echo(_) => Kind::Echo,
            Command::Tilt(_) => Kind::Tilt,
            Command::Hop(_) => Kind::Hop,
            #[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
            Command::Arm(_) => Kind::Arm,
            #[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
            Command::Spatial(_) => Kind::Spatial,
        }
    }

    /// A default command of `kind` (tests and size checks); `None` for a kind this build
    /// leaves off the wire.
    pub fn default_for(kind: Kind) -> Option<Command> {
        Some(match kind {
            Kind::Line => Command::Line(Default::default()),
            Kind::Echo => Command::Echo(Default::default()),
            Kind::Tilt => Command::Tilt(Default::default()),
            Kind::Hop => Command::Hop(Default::default()),
            #[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
            Kind::Arm => Command::Arm(Default::default()),
            #[cfg(not(any(not(target_os = "none"), feature = "wire-arm")))]
            Kind::Arm => return None,
            #[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
            Kind::Spatial => Command::Spatial(Default::default()),
            #[cfg(not(any(not(target_os = "none"), feature = "wire-spatial")))]
            Kind::Spatial => return None,
        })
    }

    /// The command's sequence number, mode and fault, whatever its kind.
    pub fn reply(&self) -> (u32, Mode, Fault) {
        match self {
            Command::Line(c) => (c.seq(), c.mode(), c.fault()),
            Command::Echo(c) => (c.seq(), c.mode(), c.fault()),
            Command::Tilt(c) => (c.seq(), c.mode(), c.fault()),
            Command::Hop(c) => (c.seq(), c.mode(), c.fault()),
            #[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
            Command::Arm(c) => (c.seq(), c.mode(), c.fault()),
            #[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
            Command::Spatial(c) => (c.seq(), c.mode(), c.fault()),
        }
    }
}

/// `impl Wire for $controller` with `Kind::$kind` and the variants `Config::$kind`,
/// `Frame::$kind` and `Command::$kind`. The invocation
/// `wire!(impl<T: SinCos> TiltControllerWith<T> => Tilt)` expands to (`wire!(Echo => Echo)`
/// to the same with no generics)
///
/// ```ignore
/// impl<T: SinCos> Wire for TiltControllerWith<T> {
///     const KIND: Kind = Kind::Tilt;
///     fn config(params: Self::Params) -> Config { Config::Tilt(params) }
///     fn params_of(config: &Config) -> Option<&Self::Params> {
///         match config { Config::Tilt(p) => Some(p), _ => None }
///     }
///     // frame, frame_of, command, command_of: the same with Frame::Tilt, Command::Tilt
/// }
/// ```
macro_rules! wire {
    (impl<$($g:ident: $bound:path)?> $controller:ty => $kind:ident) => {
        impl<$($g: $bound)?> Wire for $controller {
            const KIND: Kind = Kind::$kind;
            fn config(params: Self::Params) -> Config {
                Config::$kind(params)
            }
            #[allow(unreachable_patterns)] // a build with the kinds before the gated ones
            fn params_of(config: &Config) -> Option<&Self::Params> {
                match config {
                    Config::$kind(p) => Some(p),
                    _ => None,
                }
            }
            fn frame(frame: Self::Frame) -> Frame {
                Frame::$kind(frame)
            }
            #[allow(unreachable_patterns)]
            fn frame_of(frame: &Frame) -> Option<&Self::Frame> {
                match frame {
                    Frame::$kind(f) => Some(f),
                    _ => None,
                }
            }
            fn command(command: Self::Command) -> Command {
                Command::$kind(command)
            }
            #[allow(unreachable_patterns)]
            fn command_of(command: &Command) -> Option<Self::Command> {
                match command {
                    Command::$kind(c) => Some(*c),
                    _ => None,
                }
            }
        }
    };
    ($controller:ty => $kind:ident) => {
        wire!(impl<> $controller => $kind);
    };
}

/// Calls `$callback!` with every controller kind, in wire order: its name (the variant of
/// [`Kind`], [`Config`], [`Frame`] and [`Command`]), its controller type and, after `if`, the
/// cargo feature a firmware image enables to host it (none: every image hosts it). The
/// firmware's `Hosted` enum and its dispatch are generated from this list
/// (`firmware/src/hosted.rs`), so an image can host only kinds named here, in this order.
///
/// The feature predicates are evaluated in the crate that expands the callback. For example
/// `for_each_kind!(hosted)` expands to
///
/// ```ignore
/// hosted! {
///     Line($crate::control::Controller),
///     Echo($crate::echo::Echo),
///     Tilt($crate::tilt_control::TiltController) if feature = "tilt",
///     Hop($crate::hop_control::HopController) if feature = "hop",
///     Arm($crate::arm_control::ArmController) if feature = "arm",
///     Spatial($crate::spatial_control::SpatialController) if feature = "spatial",
/// }
/// ```
#[macro_export]
macro_rules! for_each_kind {
    ($callback:ident) => {
        $callback! {
            Line($crate::control::Controller),
            Echo($crate::echo::Echo),
            Tilt($crate::tilt_control::TiltController) if feature = "tilt",
            Hop($crate::hop_control::HopController) if feature = "hop",
            Arm($crate::arm_control::ArmController) if feature = "arm",
            Spatial($crate::spatial_control::SpatialController) if feature = "spatial",
        }
    };
}

wire!(Controller => Line);
wire!(Echo => Echo);
// Every sine/cosine backend of the tilt controller is the Tilt kind: the firmware's
// measurement build (`tilt-backend-sincos`) hosts the backend one in the Tilt slot, with
// the host's one as its shadow.
wire!(impl<T: SinCos> TiltControllerWith<T> => Tilt);
wire!(HopController => Hop);
#[cfg(any(not(target_os = "none"), feature = "wire-arm"))]
wire!(ArmController => Arm);
#[cfg(any(not(target_os = "none"), feature = "wire-spatial"))]
wire!(SpatialController => Spatial);
