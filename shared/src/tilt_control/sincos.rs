//! Where the tilt controller's sine and cosine come from, chosen at compile time.
//!
//! The controller is generic over [`SinCos`] ([`super::TiltControllerWith`]); the type the
//! firmware ships is [`super::TiltController`], with [`PolySinCos`]. The others exist to measure
//! what accuracy costs (BENCHMARKS.md): on the Cortex-M4F a libm `sinf` costs ~1350
//! instructions (its range reduction runs in software f64), so [`BackendSinCos`] under the
//! default `libm` backend cannot meet the step budget; under `fast-math` it is micromath's
//! (~1e-3 absolute error).

use super::{TiltCommand, TiltControllerWith, TiltFrame};
use crate::fixed_rate::Fault;
use crate::math::{cos_poly_f32, sin_cos_poly_f32, sin_poly_f32, Real};

/// A sine/cosine pair, f32, for an angle in rad.
pub trait SinCos: Sized {
    /// Short name for reports (`"poly"`, `"libm"`, `"micromath"`, `"poly-separate"`).
    const NAME: &'static str;
    /// (sin x, cos x).
    fn sin_cos(x_rad: f32) -> (f32, f32);

    /// `controller.step(frame)`, what [`FixedRate::step`](crate::fixed_rate::FixedRate::step)
    /// runs. The sources of this module define it in their own impls (the same body as this
    /// default): a non-generic function is compiled in the crate that defines it, so the
    /// step of each core source is compiled here, with the core's optimisation level,
    /// whichever crate calls it. The firmware builds its own code for size and the core
    /// for speed (`Cargo.toml`, profile sections); a generic step would be compiled in the
    /// firmware crate, for size, and miss its instruction budget.
    fn step(controller: &mut TiltControllerWith<Self>, frame: &TiltFrame) -> TiltCommand {
        controller.step(frame)
    }

    /// `controller.safe(seq, fault)`, what [`FixedRate::safe`](crate::fixed_rate::FixedRate::safe)
    /// runs (see [`SinCos::step`] for why the core's sources define it).
    fn safe(controller: &mut TiltControllerWith<Self>, seq: u32, fault: Fault) -> TiltCommand {
        controller.safe(seq, fault)
    }
}

/// The step and the safe command of the tilt controller with a source of this module,
/// compiled in this crate (see [`SinCos::step`]).
macro_rules! compiled_in_the_core {
    () => {
        fn step(controller: &mut TiltControllerWith<Self>, frame: &TiltFrame) -> TiltCommand {
            controller.step(frame)
        }
        fn safe(controller: &mut TiltControllerWith<Self>, seq: u32, fault: Fault) -> TiltCommand {
            controller.safe(seq, fault)
        }
    };
}

/// The shipped pair: [`sin_cos_poly_f32`], one range reduction and two short polynomials
/// (<= 2.5e-7 absolute error on [-2 pi, 2 pi], ~30 instructions on the M4F).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PolySinCos;

impl SinCos for PolySinCos {
    const NAME: &'static str = "poly";
    #[inline]
    fn sin_cos(x_rad: f32) -> (f32, f32) {
        sin_cos_poly_f32(x_rad)
    }
    compiled_in_the_core!();
}

/// The compile-time math backend ([`crate::math::BACKEND`]): libm by default, micromath with
/// the `fast-math` feature.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BackendSinCos;

impl SinCos for BackendSinCos {
    const NAME: &'static str = crate::math::BACKEND;
    #[inline]
    fn sin_cos(x_rad: f32) -> (f32, f32) {
        (Real::sin(x_rad), Real::cos(x_rad))
    }
    compiled_in_the_core!();
}

/// The core's separate polynomials [`sin_poly_f32`] and [`cos_poly_f32`] (two range
/// reductions with `roundf`, ~53 instructions each on the M4F).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SeparatePolySinCos;

impl SinCos for SeparatePolySinCos {
    const NAME: &'static str = "poly-separate";
    #[inline]
    fn sin_cos(x_rad: f32) -> (f32, f32) {
        (sin_poly_f32(x_rad), cos_poly_f32(x_rad))
    }
    compiled_in_the_core!();
}
