//! The feeder scene: one top-level `[feeder]` table (the table that selects the feeder
//! system, `docs/feeder.md`) with sub-tables, deserialized with unknown keys rejected and
//! validated into a [`Feeder`], an arrival pose, planner options and noise. Every error
//! names the dotted key (`feeder.belt.speed_mps`).
//!
//! ```toml
//! [feeder.part]
//! vertices_m = [[0.0, 0.0], [0.04, 0.0], [0.04, 0.04], [0.0, 0.04]]  # simple polygon, m
//! center_of_mass_m = [0.02, 0.02]   # optional (area centroid); must lie inside
//! [feeder.belt]
//! speed_mps = 0.05                  # v_b > 0, the belt moves in -y
//! width_m = 0.8                     # pivot on the center line; the right half is used
//! [feeder.fence]
//! length_m = 0.4
//! mu = 0.3                          # part-fence Coulomb friction
//! push_rate_radps = 2.0             # stable pushes and catches
//! max_rate_radps = 6.0              # dropping away from a drifting part
//! max_angle_deg = 80.0              # |fence angle| limit, < 90
//! jog_tilt_deg = 31.7               # optional: atan(mu) + 15 deg, capped at max_angle_deg
//! [feeder.arrival]
//! x_m = 0.15                        # COM position and angle of the arriving part
//! y_m = 0.1
//! angle_deg = 30.0
//! seed = 7                          # optional: draw x and the angle at random instead
//! x_range_m = [0.1, 0.25]           # with seed: x uniform in it (default: 1/4..3/4 of the half width)
//! [feeder.goal]
//! contact_radius_m = 0.2            # optional: planner's default
//! [feeder.noise]                    # optional: perturbs the execution (seeded)
//! seed = 1
//! belt_speed_rel = 0.0
//! fence_mu_rel = 0.0
//! arrival_xy_m = 0.0
//! arrival_angle_deg = 0.0
//! [feeder.planner]
//! allow_convergent = true
//! ```

use crate::model::feeder::execute::Noise;
use crate::model::feeder::geometry::{Pose, Vec2};
use crate::model::feeder::part::Part;
use crate::model::feeder::planner::{Feeder, PlanOptions};
use crate::model::feeder::primitives::Drive;
use crate::model::feeder::quasistatic::Medium;
use crate::model::feeder::sim::Setup;
use crate::model::feeder::FeederError;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// `[feeder.part]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PartTable {
    /// Polygon vertices `[x, y]`, m (either orientation, simple, >= 3).
    pub vertices_m: Vec<[f64; 2]>,
    /// Center of mass `[x, y]`, m; default the area centroid.
    pub center_of_mass_m: Option<[f64; 2]>,
}

/// `[feeder.belt]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BeltTable {
    /// Belt speed, m/s (> 0; motion in -y).
    pub speed_mps: f64,
    /// Belt width, m (> 0; the pivot is on the center line).
    pub width_m: f64,
}

/// `[feeder.fence]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
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
            "feeder.fence.push_rate_radps",
            self.push_rate_radps,
            |v| v > 0.0,
            "must be > 0",
        )?;
        let max_rate = check(
            "feeder.fence.max_rate_radps",
            self.max_rate_radps,
            |v| v >= push,
            "must be >= feeder.fence.push_rate_radps",
        )?;
        let max_angle = check(
            "feeder.fence.max_angle_deg",
            self.max_angle_deg,
            |v| v > 0.0 && v < 90.0,
            "must be in (0, 90)",
        )?
        .to_radians();
        let friction_angle =
            check("feeder.fence.mu", self.mu, |v| v >= 0.0, "must be >= 0")?.atan();
        let tilt_default = (friction_angle + 15f64.to_radians()).min(max_angle);
        let jog_tilt_rad = match self.jog_tilt_deg {
            Some(d) => check(
                "feeder.fence.jog_tilt_deg",
                d.to_radians(),
                |v| v > friction_angle && v <= max_angle,
                "must exceed atan(feeder.fence.mu) and not exceed feeder.fence.max_angle_deg",
            )?,
            None if tilt_default > friction_angle + 1e-3 => tilt_default,
            None => {
                let why = "must exceed atan(feeder.fence.mu) so the jogs can slide the part";
                return Err(FeederError::param("feeder.fence.max_angle_deg", why));
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

/// `[feeder.arrival]`: where the part is when the feed starts (the fence at 0).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ArrivalTable {
    /// COM x, m (the part within the belt's right half). Required unless `seed` is given.
    pub x_m: Option<f64>,
    /// COM y, m (the part wholly above the fence line y = 0).
    pub y_m: f64,
    /// Part angle, deg. Default 0.
    #[serde(default)]
    pub angle_deg: f64,
    /// When given, x and the angle are drawn at random from this seed instead of `x_m`
    /// and `angle_deg` (x uniform in `x_range_m`, the angle uniform in [0, 360) deg): a
    /// sweep over it (`--range feeder.arrival.seed=1:200:200`) feeds random arrivals.
    pub seed: Option<u64>,
    /// The x range of drawn arrivals `[lo, hi]`, m. Default a quarter to three quarters
    /// of the belt's half width.
    pub x_range_m: Option<[f64; 2]>,
}

/// `[feeder.goal]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GoalTable {
    /// Goal contact radius, m (> 0). Default: the planner's choice.
    pub contact_radius_m: Option<f64>,
}

/// `[feeder.noise]` (standard deviations).
#[derive(Clone, Debug, Default, PartialEq, Deserialize, Serialize)]
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

/// `[feeder.planner]`.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
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

/// The `[feeder]` table.
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct FeederScene {
    /// `[feeder.part]`.
    pub part: PartTable,
    /// `[feeder.belt]`.
    pub belt: BeltTable,
    /// `[feeder.fence]`.
    pub fence: FenceTable,
    /// `[feeder.arrival]`.
    pub arrival: ArrivalTable,
    /// `[feeder.goal]`.
    #[serde(default)]
    pub goal: GoalTable,
    /// `[feeder.noise]`.
    pub noise: Option<NoiseTable>,
    /// `[feeder.planner]`.
    #[serde(default)]
    pub planner: PlannerTable,
}

/// A feeder scene file: only a `[feeder]` table.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeederFile {
    /// `[feeder]`.
    pub feeder: FeederScene,
}

/// Everything a validated scene yields.
#[derive(Clone, Debug, PartialEq)]
pub struct Built {
    /// The cell.
    pub feeder: Feeder,
    /// Arrival pose (drawn when `feeder.arrival.seed` is given).
    pub arrival: Pose,
    /// The seed the arrival was drawn from, if it was.
    pub arrival_seed: Option<u64>,
    /// Planner options.
    pub options: PlanOptions,
    /// Execution noise (its seed already combined with the arrival's, see [`noise_seed`]).
    pub noise: Option<Noise>,
}

fn check(key: &str, v: f64, ok: impl Fn(f64) -> bool, req: &str) -> Result<f64, FeederError> {
    if v.is_finite() && ok(v) {
        Ok(v)
    } else {
        Err(FeederError::param(key, req))
    }
}

/// The seed of the noise draws: `feeder.noise.seed`, combined with the arrival's seed when
/// the arrival is drawn, so each random arrival of a sweep gets its own perturbation.
pub fn noise_seed(noise_seed: u64, arrival_seed: Option<u64>) -> u64 {
    match arrival_seed {
        Some(s) => noise_seed ^ s.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        None => noise_seed,
    }
}

impl FeederScene {
    /// Parses a whole scene file's TOML text (a `[feeder]` table); unknown or mistyped
    /// keys are errors naming the dotted key.
    pub fn from_toml_str(text: &str) -> Result<Self, FeederError> {
        let de = toml::Deserializer::parse(text)
            .map_err(|e| FeederError::param("scene", &format!("is not valid TOML: {e}")))?;
        serde_path_to_error::deserialize::<_, FeederFile>(de)
            .map(|f| f.feeder)
            .map_err(|e| {
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
            "feeder.belt.speed_mps",
            self.belt.speed_mps,
            pos,
            "must be > 0 (the belt moves in -y)",
        )?;
        let width = check("feeder.belt.width_m", self.belt.width_m, pos, "must be > 0")?;
        let length = check(
            "feeder.fence.length_m",
            self.fence.length_m,
            pos,
            "must be > 0",
        )?;
        let mu = check(
            "feeder.fence.mu",
            self.fence.mu,
            |v| v >= 0.0,
            "must be >= 0",
        )?;
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
            Some(r) => Some(check(
                "feeder.goal.contact_radius_m",
                r,
                pos,
                "must be > 0",
            )?),
            None => None,
        };
        let options = PlanOptions {
            allow_convergent: self.planner.allow_convergent,
            goal_radius_m: goal,
            ..PlanOptions::default()
        };
        let noise = self
            .noise
            .as_ref()
            .map(|n| noise_of(n, self.arrival.seed))
            .transpose()?;
        Ok(Built {
            feeder,
            arrival,
            arrival_seed: self.arrival.seed,
            options,
            noise,
        })
    }

    /// The arrival pose: given, or drawn from `feeder.arrival.seed`; checked to lie above
    /// the fence on the belt's right half.
    fn arrival_pose(&self, f: &Feeder) -> Result<Pose, FeederError> {
        let a = &self.arrival;
        let y = check("feeder.arrival.y_m", a.y_m, |_| true, "must be finite")?;
        let (x, ang) = match a.seed {
            Some(seed) => self.drawn_arrival(f, seed)?,
            None => {
                let x = a.x_m.ok_or_else(|| {
                    FeederError::param(
                        "feeder.arrival.x_m",
                        "is required unless feeder.arrival.seed is given",
                    )
                })?;
                let x = check("feeder.arrival.x_m", x, |_| true, "must be finite")?;
                let ang = check(
                    "feeder.arrival.angle_deg",
                    a.angle_deg,
                    |_| true,
                    "must be finite",
                )?;
                (x, ang.to_radians())
            }
        };
        let pose = Pose {
            com_m: Vec2::new(x, y),
            angle_rad: ang,
        };
        let hull: Vec<Vec2> = f.part.hull.iter().map(|&v| pose.to_world(v)).collect();
        if hull.iter().any(|p| p.y <= 0.0) {
            return Err(FeederError::param(
                "feeder.arrival.y_m",
                "must place the whole part above the fence (y > 0)",
            ));
        }
        if hull
            .iter()
            .any(|p| p.x <= 0.0 || p.x >= f.setup.belt_edge_m)
        {
            let key = match a.seed {
                Some(_) => "feeder.arrival.x_range_m",
                None => "feeder.arrival.x_m",
            };
            return Err(FeederError::param(
                key,
                "must place the whole part on the belt's right half (0 < x < feeder.belt.width_m / 2)",
            ));
        }
        if hull.iter().any(|p| p.x >= f.setup.fence_length_m) {
            let key = match a.seed {
                Some(_) => "feeder.arrival.x_range_m",
                None => "feeder.arrival.x_m",
            };
            return Err(FeederError::param(
                key,
                "must place the whole part over the fence (x < feeder.fence.length_m), or it drifts past the fence's tip",
            ));
        }
        Ok(pose)
    }

    /// (x, angle) drawn from `seed`: x uniform in the range, the angle uniform in [0, 2 pi).
    fn drawn_arrival(&self, f: &Feeder, seed: u64) -> Result<(f64, f64), FeederError> {
        let half = f.setup.belt_edge_m;
        let key = "feeder.arrival.x_range_m";
        let [lo, hi] = self.arrival.x_range_m.unwrap_or([0.25 * half, 0.75 * half]);
        let lo = check(key, lo, |v| v > 0.0, "must be [lo, hi] with 0 < lo <= hi")?;
        let hi = check(key, hi, |v| v >= lo, "must be [lo, hi] with 0 < lo <= hi")?;
        let mut rng = StdRng::seed_from_u64(seed);
        let x = rng.random_range(lo..=hi);
        Ok((x, rng.random_range(0.0..std::f64::consts::TAU)))
    }
}

fn noise_of(n: &NoiseTable, arrival_seed: Option<u64>) -> Result<Noise, FeederError> {
    let nn = |k: &str, v: f64| check(k, v, |v| v >= 0.0, "must be >= 0");
    Ok(Noise {
        seed: noise_seed(n.seed, arrival_seed),
        belt_speed_rel: nn("feeder.noise.belt_speed_rel", n.belt_speed_rel)?,
        fence_mu_rel: nn("feeder.noise.fence_mu_rel", n.fence_mu_rel)?,
        arrival_xy_m: nn("feeder.noise.arrival_xy_m", n.arrival_xy_m)?,
        arrival_angle_rad: nn("feeder.noise.arrival_angle_deg", n.arrival_angle_deg)?.to_radians(),
    })
}
