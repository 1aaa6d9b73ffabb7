//! Parameter sweeps, the same for every system: the ranges (`--range key.path=FROM:TO:N`,
//! and `--range2` for a two-dimensional map), the grid of points they span, and the engine
//! that evaluates the points on every core ([`rayon`]) and hands their results on **in
//! serial order**, so the output is identical to a serial run (`RAYON_NUM_THREADS=1` is
//! one). Memory stays bounded: points are evaluated in chunks of [`CHUNK_POINTS`] and each
//! chunk's results are consumed before the next is started.
//!
//! A sweep holds at most [`MAX_SWEEP_POINTS`] points (both ranges together); more is
//! refused with a message naming the limit.

use crate::scene::SceneError;
use rayon::prelude::*;

/// Most points one sweep evaluates (`N`, or `N x M` with `--range2`).
pub const MAX_SWEEP_POINTS: u64 = 1_000_000;

/// Points evaluated in parallel before their results are consumed in order.
pub const CHUNK_POINTS: usize = 1024;

/// A sweep range `key.path=FROM:TO:N` (N >= 2 values, inclusive ends; N = 1 runs FROM).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Range {
    /// Dotted key path.
    pub key: String,
    /// First value.
    pub from: f64,
    /// Last value.
    pub to: f64,
    /// Number of values (1 ..= [`MAX_SWEEP_POINTS`]).
    pub count: u32,
}

/// The count of a range: an integer (also written as `5e9`) in 1 ..= [`MAX_SWEEP_POINTS`].
fn parse_count(key: &str, text: &str) -> Result<u32, SceneError> {
    let t = text.trim();
    let value = t
        .parse::<u64>()
        .ok()
        .map(|n| n as f64)
        .or_else(|| t.parse::<f64>().ok())
        .filter(|v| v.is_finite() && *v >= 1.0 && v.fract() == 0.0)
        .ok_or_else(|| {
            SceneError::new(key, format!("range count `{t}` must be an integer >= 1"))
        })?;
    if value > MAX_SWEEP_POINTS as f64 {
        return Err(SceneError::new(
            key,
            format!(
                "range count `{t}` is more than a sweep may hold: at most {MAX_SWEEP_POINTS} points"
            ),
        ));
    }
    Ok(value as u32)
}

impl Range {
    /// Parse `key.path=FROM:TO:N`.
    pub fn parse(arg: &str) -> Result<Self, SceneError> {
        let (key, spec) = arg
            .split_once('=')
            .ok_or_else(|| SceneError::new(arg, "expected key.path=FROM:TO:N"))?;
        let parts: Vec<&str> = spec.split(':').collect();
        if parts.len() != 3 {
            return Err(SceneError::new(key, "range must be FROM:TO:N"));
        }
        let num = |s: &str, what: &str| -> Result<f64, SceneError> {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    SceneError::new(key, format!("range {what} `{s}` is not a finite number"))
                })
        };
        let count = parse_count(key, parts[2])?;
        Ok(Self {
            key: key.trim().to_string(),
            from: num(parts[0], "start")?,
            to: num(parts[1], "end")?,
            count,
        })
    }

    /// The `i`-th value (`i < count`): `from + (to - from) i / (N - 1)`, the last one `to`
    /// exactly (the formula's rounding could step past an inclusive limit), and, where
    /// `to - from` overflows, the same point as `from (1 - t) + to t`, which does not.
    pub fn value(&self, i: u32) -> f64 {
        let n = self.count.saturating_sub(1);
        if i == 0 || n == 0 {
            return self.from;
        }
        if i >= n {
            return self.to;
        }
        let span = self.to - self.from;
        if span.is_finite() {
            self.from + span * f64::from(i) / f64::from(n)
        } else {
            let t = f64::from(i) / f64::from(n);
            self.from * (1.0 - t) + self.to * t
        }
    }

    /// The values of the range.
    pub fn values(&self) -> Vec<f64> {
        (0..self.count).map(|i| self.value(i)).collect()
    }
}

/// The points of a sweep: every value of `x`, for each value of `y` (rows `y`, columns
/// `x`: point `i` is column `i % x.count` of row `i / x.count`).
#[derive(Clone, Debug, PartialEq)]
pub struct Grid {
    /// The first range (`--range`).
    pub x: Range,
    /// The second range (`--range2`), if any.
    pub y: Option<Range>,
}

impl Grid {
    /// A grid of `x` and `y`; refused if `y` sweeps `x`'s key or the grid holds more than
    /// [`MAX_SWEEP_POINTS`] points.
    pub fn new(x: Range, y: Option<Range>) -> Result<Self, SceneError> {
        if let Some(y) = &y {
            if y.key == x.key {
                return Err(SceneError::new(
                    y.key.clone(),
                    "--range2 sweeps the same key as --range",
                ));
            }
            let n = u64::from(x.count) * u64::from(y.count);
            if n > MAX_SWEEP_POINTS {
                return Err(SceneError::new(
                    y.key.clone(),
                    format!(
                        "--range and --range2 span {} x {} = {n} points, more than a sweep may hold: at most {MAX_SWEEP_POINTS}",
                        x.count, y.count
                    ),
                ));
            }
        }
        Ok(Self { x, y })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.x.count as usize * self.y.as_ref().map_or(1, |y| y.count as usize)
    }

    /// True if the grid has no point (never: counts are >= 1).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The values of point `i`: (x, y).
    pub fn point(&self, i: usize) -> (f64, Option<f64>) {
        let n = self.x.count as usize;
        let x = self.x.value((i % n) as u32);
        (x, self.y.as_ref().map(|y| y.value((i / n) as u32)))
    }
}

/// Evaluate `eval(i)` for `i` in `0..n` on every core and pass each result to `consume` in
/// order of `i`; the first error, in that order, ends the sweep. `progress` advances once
/// per point (the caller finishes it).
pub fn map_ordered<T, E>(
    n: usize,
    progress: &indicatif::ProgressBar,
    eval: impl Fn(usize) -> Result<T, E> + Sync,
    mut consume: impl FnMut(usize, T) -> Result<(), E>,
) -> Result<(), E>
where
    T: Send,
    E: Send,
{
    let mut start = 0;
    while start < n {
        let end = (start + CHUNK_POINTS).min(n);
        let results: Vec<Result<T, E>> = (start..end)
            .into_par_iter()
            .map(|i| {
                let r = eval(i);
                progress.inc(1);
                r
            })
            .collect();
        for (i, r) in (start..end).zip(results) {
            consume(i, r?)?;
        }
        start = end;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_parses_and_names_bad_parts() {
        let r = Range::parse("control.kappa1_s2pm2=0.02:0.08:4").unwrap();
        assert_eq!(r.key, "control.kappa1_s2pm2");
        let v = r.values();
        assert_eq!(v.len(), 4);
        assert!((v[1] - 0.04).abs() < 1e-15 && v[3] == 0.08);
        assert_eq!(Range::parse("a.b=1:x:3").unwrap_err().key, "a.b");
        assert!(Range::parse("a.b=1:2:0").is_err());
        assert!(Range::parse("a.b=1:2").is_err());
        assert!(Range::parse("a.b=1:2:2.5").is_err());
        assert_eq!(Range::parse("a.b=1:2:1e3").unwrap().count, 1000);
    }

    #[test]
    fn huge_counts_are_refused_naming_the_limit() {
        for n in ["5e9", "5000000000", "1000001", "1e300"] {
            let e = Range::parse(&format!("a.b=0:1:{n}")).unwrap_err();
            assert_eq!(e.key, "a.b");
            assert!(e.reason.contains("at most 1000000 points"), "{n}: {e}");
        }
        assert_eq!(Range::parse("a.b=0:1:1000000").unwrap().count, 1_000_000);
        let x = Range::parse("a.x=0:1:2000").unwrap();
        let y = Range::parse("a.y=0:1:1000").unwrap();
        let e = Grid::new(x.clone(), Some(y)).unwrap_err();
        assert!(e.reason.contains("2000000 points"), "{e}");
        assert!(Grid::new(x.clone(), Some(x)).is_err());
    }

    #[test]
    fn the_last_value_is_the_end_exactly_and_a_huge_span_does_not_overflow() {
        // 0.1 + 0.9 * 13 / 13 rounds to 1.0000000000000002, past an inclusive limit of 1
        let r = Range::parse("planar.restitution=0.1:1:14").unwrap();
        assert_eq!(r.value(13), 1.0);
        assert_eq!(r.values().len(), 14);
        assert!(r.values().iter().all(|v| (0.1..=1.0).contains(v)));
        let r = Range::parse("planar.tip_angle_rad=0.001:1.5707963267948966:12").unwrap();
        assert_eq!(r.value(11), std::f64::consts::FRAC_PI_2);
        // to - from = 3.4e308 overflows: every value finite, symmetric about 0
        let r = Range::parse("k=-1.7e308:1.7e308:3").unwrap();
        assert_eq!(r.values(), vec![-1.7e308, 0.0, 1.7e308]);
        let r = Range::parse("k=-1.7e308:1.7e308:5").unwrap();
        assert!((r.value(1) / -0.85e308 - 1.0).abs() < 1e-15);
        assert!(r.values().iter().all(|v| v.is_finite()));
    }

    #[test]
    fn grid_points_run_row_by_row() {
        let g = Grid::new(
            Range::parse("a=0:2:3").unwrap(),
            Some(Range::parse("b=10:20:2").unwrap()),
        )
        .unwrap();
        let pts: Vec<_> = (0..g.len()).map(|i| g.point(i)).collect();
        assert_eq!(
            pts,
            [
                (0.0, Some(10.0)),
                (1.0, Some(10.0)),
                (2.0, Some(10.0)),
                (0.0, Some(20.0)),
                (1.0, Some(20.0)),
                (2.0, Some(20.0))
            ]
        );
    }

    #[test]
    fn results_come_in_serial_order_and_the_first_error_wins() {
        let pb = indicatif::ProgressBar::hidden();
        let mut seen = Vec::new();
        map_ordered(
            3000,
            &pb,
            |i| Ok::<usize, String>(i * i),
            |i, v| {
                seen.push((i, v));
                Ok(())
            },
        )
        .unwrap();
        assert!(seen
            .iter()
            .enumerate()
            .all(|(k, &(i, v))| k == i && v == i * i));
        assert_eq!(seen.len(), 3000);
        let mut consumed = 0;
        let r = map_ordered(
            3000,
            &pb,
            |i| if i % 700 == 699 { Err(i) } else { Ok(i) },
            |_, _| {
                consumed += 1;
                Ok(())
            },
        );
        assert_eq!(r, Err(699));
        assert_eq!(consumed, 699);
    }
}
