//! Parameter sweeps: run a scene over a range of one key and keep the late apexes
//! (a bifurcation diagram, e.g. over `control.kappa1_s2pm2`).

use crate::run::{run_scene, RunError, RunOptions};
use crate::scene::{apply_set, Scene, SceneError};

/// A sweep range `key.path=FROM:TO:N` (N >= 2 values, inclusive ends; N = 1 runs FROM).
#[derive(Clone, Debug, PartialEq)]
pub struct Range {
    /// Dotted key path.
    pub key: String,
    /// First value.
    pub from: f64,
    /// Last value.
    pub to: f64,
    /// Number of values (>= 1).
    pub count: u32,
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
        let count: u32 = parts[2]
            .trim()
            .parse()
            .ok()
            .filter(|&n| n >= 1)
            .ok_or_else(|| {
                SceneError::new(
                    key,
                    format!("range count `{}` must be an integer >= 1", parts[2]),
                )
            })?;
        Ok(Self {
            key: key.trim().to_string(),
            from: num(parts[0], "start")?,
            to: num(parts[1], "end")?,
            count,
        })
    }

    /// The values of the range.
    pub fn values(&self) -> Vec<f64> {
        if self.count == 1 {
            return vec![self.from];
        }
        let n = self.count - 1;
        (0..=n)
            .map(|i| self.from + (self.to - self.from) * f64::from(i) / f64::from(n))
            .collect()
    }
}

/// Run `base` (a parsed scene table, overrides applied) at every value of `range`, keeping
/// the last `keep` apex heights of each run: (value, apex) points.
pub fn sweep(base: &toml::Table, range: &Range, keep: usize) -> Result<Vec<(f64, f64)>, RunError> {
    let mut points = Vec::new();
    for v in range.values() {
        let mut t = base.clone();
        apply_set(&mut t, &range.key, toml::Value::Float(v))?;
        let scene = Scene::from_table(t)?;
        let out = run_scene(&scene, &RunOptions::default(), None)?;
        let n = out.apexes_m.len();
        points.extend(
            out.apexes_m[n.saturating_sub(keep)..]
                .iter()
                .map(|&a| (v, a)),
        );
    }
    Ok(points)
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
    }
}
