//! Parameter validation that records the first failed check and carries on, one call per
//! check: the same checks and errors as [`crate::params`] (`finite`, `positive`,
//! `non_negative`, `within`), for the tilt and hopper controllers' large parameter sets.
//!
//! Validation is cold code (it runs at `Configure`), but the firmware must hold it: with an
//! early return per check each one is about 40 bytes of Cortex-M code, and with a call
//! that cannot fail (nothing to test or copy at the call site) about 20, which is what
//! the 32 KiB flash budget needs. Every check runs; the result is the first failure in
//! check order, so "the error names the first bad parameter" holds as with `?`.

use crate::params::{self, ParamError};

/// The first failed check so far.
#[derive(Debug, Default)]
pub(crate) struct Checks {
    first: Option<ParamError>,
}

impl Checks {
    /// Record `result`'s error unless an earlier check failed.
    #[inline]
    pub(crate) fn note<T>(&mut self, result: Result<T, ParamError>) {
        if let (Err(e), None) = (result, &self.first) {
            self.first = Some(e);
        }
    }

    /// [`params::finite`].
    #[inline(never)]
    pub(crate) fn finite(&mut self, name: &'static str, value: f32) {
        self.note(params::finite(name, value));
    }

    /// [`params::positive`].
    #[inline(never)]
    pub(crate) fn positive(&mut self, name: &'static str, value: f32) {
        self.note(params::positive(name, value));
    }

    /// [`params::non_negative`].
    #[inline(never)]
    pub(crate) fn non_negative(&mut self, name: &'static str, value: f32) {
        self.note(params::non_negative(name, value));
    }

    /// [`params::within`].
    #[inline(never)]
    pub(crate) fn within(&mut self, name: &'static str, value: f32, lo: f32, hi: f32) {
        self.note(params::within(name, value, lo, hi));
    }

    /// [`ParamError::OutOfRange`]`(name)` unless `ok`.
    #[inline(never)]
    pub(crate) fn in_range(&mut self, ok: bool, name: &'static str) {
        if !ok {
            self.note::<()>(Err(ParamError::OutOfRange(name)));
        }
    }

    /// [`ParamError::NotPositive`]`(name)` unless `ok`.
    #[inline(never)]
    pub(crate) fn positive_count(&mut self, ok: bool, name: &'static str) {
        if !ok {
            self.note::<()>(Err(ParamError::NotPositive(name)));
        }
    }

    /// `Ok` if every check passed, else the first failure.
    #[inline]
    pub(crate) fn result(self) -> Result<(), ParamError> {
        match self.first {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_failure_is_kept_and_later_ones_do_not_replace_it() {
        let mut c = Checks::default();
        c.positive("a", 1.0);
        c.within("b", 2.0, 0.0, 1.0);
        c.finite("c", f32::NAN);
        c.in_range(false, "d");
        assert_eq!(c.result(), Err(ParamError::OutOfRange("b")));
        let mut c = Checks::default();
        c.non_negative("e", -1.0);
        c.positive_count(false, "f");
        assert_eq!(c.result(), Err(ParamError::Negative("e")));
        let mut c = Checks::default();
        c.finite("g", 3.0);
        c.in_range(true, "h");
        c.positive_count(true, "i");
        assert_eq!(c.result(), Ok(()));
        // each check gives the error its `params` counterpart gives
        let mut c = Checks::default();
        c.within("j", f32::NAN, 0.0, 1.0);
        assert_eq!(c.result(), Err(ParamError::NotFinite("j")));
    }
}
