//! Validation of law and controller parameters: one error type that names the parameter.

use crate::math::Real;

/// Why a parameter was rejected by a validated constructor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ParamError {
    /// The named parameter is NaN or infinite.
    NotFinite(&'static str),
    /// The named parameter must be > 0.
    NotPositive(&'static str),
    /// The named parameter must be >= 0.
    Negative(&'static str),
    /// The named parameter is outside the range its doc states.
    OutOfRange(&'static str),
}

impl core::fmt::Display for ParamError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ParamError::NotFinite(p) => write!(f, "{p} must be a finite number"),
            ParamError::NotPositive(p) => write!(f, "{p} must be > 0"),
            ParamError::Negative(p) => write!(f, "{p} must be >= 0"),
            ParamError::OutOfRange(p) => write!(f, "{p} is out of its allowed range"),
        }
    }
}

/// `value` is finite, else [`ParamError::NotFinite`].
pub fn finite<R: Real>(name: &'static str, value: R) -> Result<R, ParamError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(ParamError::NotFinite(name))
    }
}

/// `value` is finite and > 0.
pub fn positive<R: Real>(name: &'static str, value: R) -> Result<R, ParamError> {
    if finite(name, value)? > R::ZERO {
        Ok(value)
    } else {
        Err(ParamError::NotPositive(name))
    }
}

/// `value` is finite and >= 0.
pub fn non_negative<R: Real>(name: &'static str, value: R) -> Result<R, ParamError> {
    if finite(name, value)? >= R::ZERO {
        Ok(value)
    } else {
        Err(ParamError::Negative(name))
    }
}

/// `value` is finite and in `[lo, hi]`.
pub fn within<R: Real>(name: &'static str, value: R, lo: R, hi: R) -> Result<R, ParamError> {
    let v = finite(name, value)?;
    if v >= lo && v <= hi {
        Ok(v)
    } else {
        Err(ParamError::OutOfRange(name))
    }
}
