//! Where the tilt controller's sine and cosine come from, chosen at compile time.
//!
//! The controller is generic over [`SinCos`] ([`super::TiltControllerWith`]); the type the
//! firmware ships is [`super::TiltController`], with [`PolySinCos`]. The others exist to measure
//! what accuracy costs (BENCHMARKS.md): on the Cortex-M4F a libm `sinf` costs ~1350
//! instructions (its range reduction runs in software f64), so [`BackendSinCos`] under the
//! default `libm` backend cannot meet the step budget; under `fast-math` it is micromath's
//! (~1e-3 absolute error).

use crate::math::{cos_poly_f32, sin_cos_poly_f32, sin_poly_f32, Real};

/// A sine/cosine pair, f32, for an angle in rad.
pub trait SinCos {
    /// Short name for reports (`"poly"`, `"libm"`, `"micromath"`, `"poly-separate"`).
    const NAME: &'static str;
    /// (sin x, cos x).
    fn sin_cos(x_rad: f32) -> (f32, f32);
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
}
