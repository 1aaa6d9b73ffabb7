//! Locating an event inside an interval by bisection: the one bisection loop of every
//! event the simulator finds between two instants where it has no closed form (an ODE
//! step's witnesses in [`super::ode`], the arm's grasp and roll conditions).

/// Bisect `[lo, hi]`, where the event has not happened at `lo` and has at `hi` (`at_hi` is
/// what `fired` said there), for at most `halvings` halvings (fewer once the midpoint
/// rounds onto an end, where a further halving would change nothing): the earliest `hi`
/// found and what `fired` returned there. `fired(x)` is `Some` if the event has happened
/// by `x`. Calls `fired` at most `halvings` times.
#[inline]
pub fn bisect<T>(
    (mut lo, mut hi): (f64, f64),
    mut at_hi: T,
    halvings: u32,
    mut fired: impl FnMut(f64) -> Option<T>,
) -> (f64, T) {
    for _ in 0..halvings {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        match fired(mid) {
            Some(v) => (hi, at_hi) = (mid, v),
            None => lo = mid,
        }
    }
    (hi, at_hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_first_point_to_the_resolution_asked() {
        // the event "x >= 1/3" on [0, 1]: 40 halvings bracket 1/3 within 2^-40
        let mut calls = 0;
        let (x, v) = bisect((0.0, 1.0), 1.0, 40, |x| {
            calls += 1;
            (x >= 1.0 / 3.0).then_some(x)
        });
        assert_eq!(calls, 40);
        assert!(x >= 1.0 / 3.0 && x - 1.0 / 3.0 < 2f64.powi(-40), "{x}");
        assert_eq!(v, x, "the value is the one at the returned point");
    }

    #[test]
    fn stops_when_the_interval_cannot_shrink() {
        // 60 halvings of [1, 1 + 2^-40] run out of representable midpoints after about 12
        let mut calls = 0;
        let hi = 1.0 + 2f64.powi(-40);
        let (x, _) = bisect((1.0, hi), (), 60, |x| {
            calls += 1;
            (x > 1.0).then_some(())
        });
        assert!(calls < 20, "{calls}");
        assert_eq!(x, 1.0 + f64::EPSILON, "the first double past 1");
    }

    #[test]
    fn an_event_at_the_end_keeps_the_end() {
        let (x, v) = bisect((0.0, 1.0), 'e', 40, |x| (x >= 1.0).then_some('m'));
        assert_eq!((x, v), (1.0, 'e'));
    }
}
