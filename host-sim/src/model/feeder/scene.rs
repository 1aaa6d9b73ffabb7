//! The feeder scene's tables (serde, unknown keys rejected) and their validation into a
//! [`Feeder`], an arrival pose, planner options and noise. Errors name the dotted key.
//!
//! ```toml
//! [part]
//! vertices_m = [[0.0, 0.0], [0.04, 0.0], [0.04, 0.04], [0.0, 0.04]]  # simple polygon, m
//! center_of_mass_m = [0.02, 0.02]   # optional (area centroid); must lie inside
//! [belt]
//! speed_mps = 0.05                  # v_b > 0, the belt moves in -y
//! width_m = 0.8                     # pivot on the center line; the right half is used
//! [fence]
//! length_m = 0.4
//! mu = 0.3                          # part-fence Coulomb friction
//! push_rate_radps = 2.0             # stable pushes and catches
//! max_rate_radps = 6.0              # dropping away from a drifting part
//! max_angle_deg = 80.0              # |fence angle| limit, < 90
//! jog_tilt_deg = 31.7               # optional: atan(mu) + 15 deg, capped at max_angle_deg
//! [arrival]
//! x_m = 0.15                        # COM position and angle of the arriving part
//! y_m = 0.1
//! angle_deg = 30.0
//! [goal]
//! contact_radius_m = 0.2            # optional: planner's default
//! [noise]                           # optional: perturbs the execution (seeded)
//! seed = 1
//! belt_speed_rel = 0.0
//! fence_mu_rel = 0.0
//! arrival_xy_m = 0.0
//! arrival_angle_deg = 0.0
//! [planner]
//! allow_convergent = true
//! [sweep]                           # optional: random arrivals for `sweep`
//! trials = 100
//! seed = 7
//! x_range_m = [0.1, 0.25]           # default: a quarter to 3/4 of the belt's half width
//! ```

use super::execute::{Noise, SweepSpec};
use super::geometry::{Pose, Vec2};
use super::part::Part;
use super::planner::{Feeder, PlanOptions};
use super::primitives::Drive;
use super::quasistatic::Medium;
use super::sim::Setup;
use super::FeederError;
use serde::Deserialize;

/// `[part]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartTable {
    /// Polygon vertices `[x, y]`, m (either orientation, simple, >= 3).
    pub vertices_m: Vec<[f64; 2]>,
    /// Center of mass `[x, y]`, m; default the area centroid.
    pub center_of_mass_m: Option<[f64; 2]>,
}

/// `[belt]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeltTable {
    /// Belt speed, m/s (> 0; motion in -y).
    pub speed_mps: f64,
    /// Belt width, m (> 0; the pivot is on the center line).
    pub width_m: f64,
}

/// `[fence]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FenceTable {
    /// Length from the pivot, m (> 0).
    pub length_m: f64,
    /// Part-fence friction (>= 0).
    pub mu: f64,
    /// Fence rate of stable pushes, rad/s (> 0). Default 2.
    #[serde(default = "default_push_rate")]
    pub push_rate_radps: f64,
    /// Fence rate when dropping away from a drifting part, rad/s (>= push rate).
    /// Default 6.
    #[serde(default = "default_max_rate")]
    pub max_rate_radps: f64,
    /// Largest |fence angle|, deg (0 < . < 90). Default 80.
    #[serde(default = "default_max_angle")]
    pub max_angle_deg: f64,
    /// Jog tilt, deg (atan(mu) < . <= max_angle_deg). Default atan(mu) + 15, capped.
    pub jog_tilt_deg: Option<f64>,
}

impl FenceTable {
    /// The fence's rates and angle limits, validated (the jog tilt must exceed the
    /// friction angle atan mu so the part slides).
    pub fn drive(&self) -> Result<Drive, FeederError> {
        let push = check(
            "fence.push_rate_radps",
            self.push_rate_radps,
            |v| v > 0.0,
            "must be > 0",
        )?;
        let max_rate = check(
            "fence.max_rate_radps",
            self.max_rate_radps,
            |v| v >= push,
            "must be >= fence.push_rate_radps",
        )?;
        let max_angle = check(
            "fence.max_angle_deg",
            self.max_angle_deg,
            |v| v > 0.0 && v < 90.0,
            "must be in (0, 90)",
        )?
        .to_radians();
        let friction_angle = check("fence.mu", self.mu, |v| v >= 0.0, "must be >= 0")?.atan();
        let tilt_default = (friction_angle + 15f64.to_radians()).min(max_angle);
        let jog_tilt_rad = match self.jog_tilt_deg {
            Some(d) => check(
                "fence.jog_tilt_deg",
                d.to_radians(),
                |v| v > friction_angle && v <= max_angle,
                "must exceed atan(fence.mu) and not exceed fence.max_angle_deg",
            )?,
            None if tilt_default > friction_angle + 1e-3 => tilt_default,
            None => {
                let why = "must exceed atan(fence.mu) so the jogs can slide the part";
                return Err(FeederError::param("fence.max_angle_deg", why));
            }
        };
        Ok(Drive {
            push_rate_radps: push,
            max_rate_radps: max_rate,
            max_angle_rad: max_angle,
            jog_tilt_rad,
        })
    }
}

fn default_push_rate() -> f64 {
    2.0
}
fn default_max_rate() -> f64 {
    6.0
}
fn default_max_angle() -> f64 {
    80.0
}

/// `[arrival]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArrivalTable {
    /// COM x, m (the part within the belt's right half).
    pub x_m: f64,
    /// COM y, m (the part wholly above the fence line y = 0).
    pub y_m: f64,
    /// Part angle, deg. Default 0.
    #[serde(default)]
    pub angle_deg: f64,
}

/// `[goal]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GoalTable {
    /// Goal contact radius, m (> 0). Default: the planner's choice.
    pub contact_radius_m: Option<f64>,
}

/// `[noise]` (standard deviations).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NoiseTable {
    /// Seed. Default 0.
    #[serde(default)]
    pub seed: u64,
    /// Belt speed, relative (>= 0).
    #[serde(default)]
    pub belt_speed_rel: f64,
    /// Fence mu, relative (>= 0).
    #[serde(default)]
    pub fence_mu_rel: f64,
    /// Arrival x and y, m (>= 0).
    #[serde(default)]
    pub arrival_xy_m: f64,
    /// Arrival angle, deg (>= 0).
    #[serde(default)]
    pub arrival_angle_deg: f64,
}

/// `[planner]`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannerTable {
    /// Allow convergent turns. Default true.
    #[serde(default = "yes")]
    pub allow_convergent: bool,
}

impl Default for PlannerTable {
    fn default() -> Self {
        PlannerTable {
            allow_convergent: true,
        }
    }
}

fn yes() -> bool {
    true
}

/// `[sweep]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepTable {
    /// Arrivals (>= 1). Default 100.
    pub trials: Option<usize>,
    /// Seed. Default 0.
    #[serde(default)]
    pub seed: u64,
    /// Arrival x range `[lo, hi]`, m. Default a quarter to three quarters of the half width.
    pub x_range_m: Option<[f64; 2]>,
}

/// A whole feeder scene.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeederScene {
    /// `[part]`.
    pub part: PartTable,
    /// `[belt]`.
    pub belt: BeltTable,
    /// `[fence]`.
    pub fence: FenceTable,
    /// `[arrival]`.
    pub arrival: ArrivalTable,
    /// `[goal]`.
    #[serde(default)]
    pub goal: GoalTable,
    /// `[noise]`.
    pub noise: Option<NoiseTable>,
    /// `[planner]`.
    #[serde(default)]
    pub planner: PlannerTable,
    /// `[sweep]`.
    #[serde(default)]
    pub sweep: SweepTable,
}

/// Everything a validated scene yields.
#[derive(Clone, Debug, PartialEq)]
pub struct Built {
    /// The cell.
    pub feeder: Feeder,
    /// Arrival pose.
    pub arrival: Pose,
    /// Planner options.
    pub options: PlanOptions,
    /// Execution noise.
    pub noise: Option<Noise>,
    /// Sweep of arrivals.
    pub sweep: SweepSpec,
}

fn check(key: &str, v: f64, ok: impl Fn(f64) -> bool, req: &str) -> Result<f64, FeederError> {
    if v.is_finite() && ok(v) {
        Ok(v)
    } else {
        Err(FeederError::param(key, req))
    }
}

impl FeederScene {
    /// Parses TOML text; unknown or mistyped keys are errors naming the dotted key.
    pub fn from_toml_str(text: &str) -> Result<Self, FeederError> {
        let de = toml::Deserializer::parse(text)
            .map_err(|e| FeederError::param("scene", &format!("is not valid TOML: {e}")))?;
        serde_path_to_error::deserialize(de).map_err(|e| {
            FeederError::param(&e.path().to_string(), &format!("is invalid: {}", e.inner()))
        })
    }

    /// Validates every value and builds the cell.
    pub fn build(&self) -> Result<Built, FeederError> {
        let pts: Vec<Vec2> = self
            .part
            .vertices_m
            .iter()
            .map(|p| Vec2::new(p[0], p[1]))
            .collect();
        let part = Part::new(
            &pts,
            self.part.center_of_mass_m.map(|c| Vec2::new(c[0], c[1])),
        )?;
        let pos = |v: f64| v > 0.0;
        let speed = check(
            "belt.speed_mps",
            self.belt.speed_mps,
            pos,
            "must be > 0 (the belt moves in -y)",
        )?;
        let width = check("belt.width_m", self.belt.width_m, pos, "must be > 0")?;
        let length = check("fence.length_m", self.fence.length_m, pos, "must be > 0")?;
        let mu = check("fence.mu", self.fence.mu, |v| v >= 0.0, "must be >= 0")?;
        let feeder = Feeder {
            part,
            setup: Setup {
                medium: Medium {
                    belt_speed_mps: speed,
                    fence_mu: mu,
                },
                fence_length_m: length,
                belt_edge_m: width / 2.0,
            },
            drive: self.fence.drive()?,
        };
        let arrival = self.arrival_pose(&feeder)?;
        let goal = match self.goal.contact_radius_m {
            Some(r) => Some(check("goal.contact_radius_m", r, pos, "must be > 0")?),
            None => None,
        };
        let options = PlanOptions {
            allow_convergent: self.planner.allow_convergent,
            goal_radius_m: goal,
            ..PlanOptions::default()
        };
        let noise = self.noise.as_ref().map(noise_of).transpose()?;
        let sweep = self.sweep_spec(&feeder)?;
        Ok(Built {
            feeder,
            arrival,
            options,
            noise,
            sweep,
        })
    }

    fn arrival_pose(&self, f: &Feeder) -> Result<Pose, FeederError> {
        let a = &self.arrival;
        let x = check("arrival.x_m", a.x_m, |_| true, "must be finite")?;
        let y = check("arrival.y_m", a.y_m, |_| true, "must be finite")?;
        let ang = check("arrival.angle_deg", a.angle_deg, |_| true, "must be finite")?.to_radians();
        let pose = Pose {
            com_m: Vec2::new(x, y),
            angle_rad: ang,
        };
        let hull: Vec<Vec2> = f.part.hull.iter().map(|&v| pose.to_world(v)).collect();
        if hull.iter().any(|p| p.y <= 0.0) {
            return Err(FeederError::param(
                "arrival.y_m",
                "must place the whole part above the fence (y > 0)",
            ));
        }
        if hull
            .iter()
            .any(|p| p.x <= 0.0 || p.x >= f.setup.belt_edge_m)
        {
            return Err(FeederError::param(
                "arrival.x_m",
                "must place the whole part on the belt's right half (0 < x < belt.width_m / 2)",
            ));
        }
        Ok(pose)
    }

    fn sweep_spec(&self, f: &Feeder) -> Result<SweepSpec, FeederError> {
        let s = &self.sweep;
        let trials = s.trials.unwrap_or(100);
        if trials == 0 {
            return Err(FeederError::param("sweep.trials", "must be >= 1"));
        }
        let half = f.setup.belt_edge_m;
        let [lo, hi] = s.x_range_m.unwrap_or([0.25 * half, 0.75 * half]);
        let lo = check(
            "sweep.x_range_m",
            lo,
            |v| v - f.part.radius_m > 0.0,
            "must keep the part on the belt's right half",
        )?;
        check(
            "sweep.x_range_m",
            hi,
            |v| v >= lo && v + f.part.radius_m < half,
            "must be [lo, hi] with the part on the belt's right half",
        )?;
        Ok(SweepSpec {
            trials,
            seed: s.seed,
            x_range_m: (lo, hi),
            y_m: 2.0 * f.part.radius_m,
        })
    }
}

fn noise_of(n: &NoiseTable) -> Result<Noise, FeederError> {
    let nn = |k: &str, v: f64| check(k, v, |v| v >= 0.0, "must be >= 0");
    Ok(Noise {
        seed: n.seed,
        belt_speed_rel: nn("noise.belt_speed_rel", n.belt_speed_rel)?,
        fence_mu_rel: nn("noise.fence_mu_rel", n.fence_mu_rel)?,
        arrival_xy_m: nn("noise.arrival_xy_m", n.arrival_xy_m)?,
        arrival_angle_rad: nn("noise.arrival_angle_deg", n.arrival_angle_deg)?.to_radians(),
    })
}
