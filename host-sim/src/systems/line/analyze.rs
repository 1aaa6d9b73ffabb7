//! `dexter analyze` on a line-juggler scene: the Singer–Guckenheimer certificate of the
//! mirror law's impact-to-impact return map (Rizzi & Koditschek 1994, sec. 2.1.2 and 2.2,
//! eq. 8/9; docs/stability.md).
//!
//! In the impact speed v = −b′ at b = 0 (m/s, > 0), the ideal mirror law with restitution α
//! (the paper's α, the scene's `physics.restitution`) maps
//!
//! ```text
//! f(v) = v [α + (1 + α) k(v)],   k(v) = κ0 + κ1 (η* − v²/2)        (eq. 8 for matched κ0)
//!      = c1 v − c3 v³,           c1 = α + (1 + α)(κ0 + κ1 η*),   c3 = (1 + α) κ1 / 2,
//! ```
//!
//! η* = g h* (J/kg). Its physical interval is [0, v0] between the cubic's non-negative
//! zeros, v0 = √(c1/c3) (sec. 2.2: "the real interval bounded by the two zeroes of the
//! cubic"): a faster ball is not thrown up again. The critical point is v_c = v0/√3, the
//! critical value f(v_c) = (2/3) c1 v_c, so [0, v0] is invariant iff c1 ≤ 3√3/2. The
//! Schwarzian in closed form: f′ = c1 − 3 c3 v², f″ = −6 c3 v, f‴ = −6 c3, so
//! 2 f′ f‴ − 3 f″² = −12 c3 (c1 + 6 c3 v²) < 0 for c1, c3 > 0 (Singer's criterion: f′ has
//! only the real roots ±v_c). The fixed point v*² = (c1 − 1)/c3 has multiplier
//! 1 − 2 c3 v*² = 3 − 2 c1, −1 at c1 = 2, i.e. the first doubling at
//! κ1 = (1 − (1 + α)(κ0 − κ0m)) / ((1 + α) η*), κ0m = (1 − α)/(1 + α) the matched gain.
//! The multiplier does not depend on the coordinate, so it is eq. 9's in the apex height too.

use super::scene::{ControlMode, Scene};
use crate::engine::unimodal::jet::{Jet, Scalar};
use crate::engine::unimodal::{certify, num, pictures, Certificate, Map1d, Options};
use crate::scene::SceneError;
use crate::system::{Failure, Report};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Eq. 8 as f(v) = c1 v − c3 v³ (impact speed v, m/s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MirrorMap {
    /// c1 = α + (1 + α)(κ0 + κ1 η*), dimensionless.
    pub c1: f64,
    /// c3 = (1 + α) κ1 / 2, s²/m².
    pub c3: f64,
}

impl Map1d for MirrorMap {
    fn jet<T: Scalar>(&self, v: Jet<T>) -> Jet<T> {
        v.scale(self.c1) - (v * v * v).scale(self.c3)
    }
}

/// The closed-form argument for the Schwarzian of [`MirrorMap`].
pub const MIRROR_SCHWARZIAN: &str = "f(v) = c1 v - c3 v^3: 2 f' f''' - 3 f''^2 = -12 c3 (c1 + 6 c3 v^2) < 0 for c1, c3 > 0, so S f < 0 except at the critical point (Singer's criterion: f' has only the real roots +-sqrt(c1/(3 c3)); Rizzi & Koditschek sec. 2.2)";

/// The analysis `dexter analyze` prints for a line scene.
pub struct LineAnalysis<'a> {
    sc: &'a Scene,
    map: MirrorMap,
    alpha: f64,
    kappa0: f64,
    kappa1: f64,
    eta: f64,
    gravity: f64,
    cert: Option<Certificate>,
}

impl LineAnalysis<'_> {
    /// The certificate (`None` with κ1 = 0: a linear map).
    pub fn certificate(&self) -> Option<&Certificate> {
        self.cert.as_ref()
    }

    fn v0(&self) -> Option<f64> {
        (self.map.c3 > 0.0 && self.map.c1 > 0.0).then(|| (self.map.c1 / self.map.c3).sqrt())
    }
    fn fixed_speed(&self) -> Option<f64> {
        (self.map.c3 > 0.0 && self.map.c1 > 1.0).then(|| ((self.map.c1 - 1.0) / self.map.c3).sqrt())
    }
    /// 3 − 2 c1 (the multiplier at v*).
    fn multiplier(&self) -> Option<f64> {
        self.fixed_speed().map(|_| 3.0 - 2.0 * self.map.c1)
    }
    /// κ1 at which the multiplier reaches −1 (c1 = 2), s²/m².
    fn kappa1_doubling(&self) -> f64 {
        let a = self.alpha;
        let matched = (1.0 - a) / (1.0 + a);
        (1.0 - (1.0 + a) * (self.kappa0 - matched)) / ((1.0 + a) * self.eta)
    }
    /// Largest k(v) on [0, v0]: k(0) = κ0 + κ1 η* (the map assumes k < 1, sec. 2.1.2).
    fn max_gain(&self) -> f64 {
        self.kappa0 + self.kappa1 * self.eta
    }

    fn covers(&self) -> &'static str {
        match self.sc.control.mode {
            ControlMode::IdealMirror if self.sc.drag.is_some() => {
                "the ideal mirror law without drag: this scene's [drag] is not in eq. 8"
            }
            ControlMode::IdealMirror => "this scene exactly (the ideal mirror law, eq. 8)",
            _ => {
                "the ideal mirror law (eq. 8) with this scene's gains; the SIL loop's sensor, estimator, actuator and control rate are not covered"
            }
        }
    }

    fn reason(&self) -> String {
        format!(
            "no certificate: kappa1 = {} makes the map linear, v -> {} v (S = 0; every speed is a fixed point or none is)",
            self.kappa1, self.map.c1
        )
    }

    fn json_value(&self) -> Value {
        let mut cert = match &self.cert {
            Some(c) => c.json(),
            None => json!({"verdict_code": null, "reason": self.reason()}),
        };
        cert["map"] = json!(
            "eq. 8: v -> v [alpha + (1 + alpha) k(v)], k(v) = kappa0 + kappa1 (eta* - v^2/2)"
        );
        cert["coordinate"] = json!("impact speed v (m/s)");
        cert["schwarzian_argument"] = json!(MIRROR_SCHWARZIAN);
        json!({
            "scene": self.sc.name(),
            "system": "line",
            "mode": match self.sc.control.mode {
                ControlMode::IdealMirror => "ideal_mirror",
                _ => "sil",
            },
            "covers": self.covers(),
            "params": {
                "restitution": self.alpha,
                "kappa0": self.kappa0,
                "kappa1_s2pm2": self.kappa1,
                "target_apex_m": self.eta / self.gravity,
                "gravity_mps2": self.gravity,
                "c1": num(self.map.c1),
                "c3_s2pm2": num(self.map.c3),
            },
            "zero_speed_mps": self.v0().map(num),
            "fixed_point_speed_mps": self.fixed_speed().map(num),
            "fixed_point_apex_m": self.fixed_speed().map(|v| num(v * v / (2.0 * self.gravity))),
            "multiplier_closed_form": self.multiplier().map(num),
            "kappa1_first_doubling_s2pm2": num(self.kappa1_doubling()),
            "mirror_gain_below_one": self.max_gain() < 1.0,
            "certificate": cert,
        })
    }

    fn human(&self) -> String {
        let mut s = format!(
            "line scene {}: the mirror law's return map in the impact speed (Rizzi & Koditschek eq. 8/9)\n",
            self.sc.name()
        );
        s += &format!(
            "  f(v) = c1 v - c3 v^3, c1 = {:.9}, c3 = {:.9} s^2/m^2 (restitution {}, kappa0 {:.9}, kappa1 {} s^2/m^2, h* = {} m)\n",
            self.map.c1,
            self.map.c3,
            self.alpha,
            self.kappa0,
            self.kappa1,
            self.eta / self.gravity
        );
        s += &format!("  covers: {}\n", self.covers());
        if let (Some(v), Some(m)) = (self.fixed_speed(), self.multiplier()) {
            s += &format!(
                "  closed form: v* = {v:.12} m/s (apex {:.12} m), multiplier 3 - 2 c1 = {m:.12}\n",
                v * v / (2.0 * self.gravity)
            );
        }
        s += &format!(
            "  first doubling at kappa1 = {:.9} s^2/m^2 (multiplier -1, c1 = 2)\n",
            self.kappa1_doubling()
        );
        if self.max_gain() >= 1.0 {
            s += &format!(
                "  warning: the mirror gain k(0) = {:.6} is not < 1 (sec. 2.1.2 assumes k < 1)\n",
                self.max_gain()
            );
        }
        s += &format!("  Schwarzian in closed form: {MIRROR_SCHWARZIAN}\n");
        match &self.cert {
            Some(c) => s += &c.text(),
            None => s += &format!("  {}\n", self.reason()),
        }
        s
    }
}

impl Report for LineAnalysis<'_> {
    fn text(&self) -> String {
        self.human()
    }
    fn json(&self) -> Result<String, String> {
        Ok(self.json_value().to_string())
    }
    /// `{scene}-return-map` (with the diagonal and cobwebs) and `{scene}-schwarzian`.
    fn plot(&self, dir: &Path) -> Result<Vec<PathBuf>, Failure> {
        let Some(cert) = &self.cert else {
            return Err(Failure::usage(format!("--plot: {}", self.reason())));
        };
        let (stem, coord) = (self.sc.name(), "impact speed v (m/s)");
        let mut files = pictures::return_map(&self.map, cert, coord, dir, stem)?;
        files.extend(pictures::schwarzian_sign(
            &self.map, cert, coord, dir, stem,
        )?);
        Ok(files)
    }
}

/// `dexter analyze` on a line scene: the certificate of eq. 8 with its gains. A passive
/// scene (`control.mode = "none"`) has no mirror law to analyze (exit 2, naming the key).
pub fn analyze(sc: &Scene) -> Result<LineAnalysis<'_>, Failure> {
    if sc.control.mode == ControlMode::None {
        return Err(Failure::scene(SceneError::new(
            "control.mode",
            "is \"none\": a passive bounce has no mirror law to analyze (use \"ideal_mirror\" or \"sil\")",
        )));
    }
    let target = sc.control.target_apex_m.ok_or_else(|| {
        Failure::scene(SceneError::new(
            "control.target_apex_m",
            "is required to analyze the mirror law",
        ))
    })?;
    let alpha = sc.physics.restitution;
    let gravity = sc.physics.gravity_mps2;
    let (kappa0, kappa1) = (sc.kappa0(), sc.control.kappa1_s2pm2);
    let eta = gravity * target;
    let map = MirrorMap {
        c1: alpha + (1.0 + alpha) * (kappa0 + kappa1 * eta),
        c3: 0.5 * (1.0 + alpha) * kappa1,
    };
    let mut a = LineAnalysis {
        sc,
        map,
        alpha,
        kappa0,
        kappa1,
        eta,
        gravity,
        cert: None,
    };
    if let Some(v0) = a.v0() {
        a.cert = Some(certify(&map, 0.0, v0, &Options::default()));
    }
    Ok(a)
}
