//! The vertical hopper of Koditschek & Bühler, "Analysis of a Simplified Hopping Robot"
//! (1991): a unit-mass body on a springy leg, body height chi (m), forces per unit body
//! mass (m/s^2), advanced cycle by cycle through Raibert's four phases (sec. 3.1):
//! touchdown -> compression -> bottom -> thrust -> end of thrust -> decompression -> liftoff
//! (with the inelastic leg pickup of eq. 7) -> flight -> touchdown.
//!
//! Three models, each a value type with a validated constructor:
//!
//! | model | equation | compression | thrust | decompression | flight |
//! | --- | --- | --- | --- | --- | --- |
//! | [`SimplifiedNonlinear`] | eq. 9 | closed form, eq. 13 | instantaneous (delta = 0) | closed form, eq. 12 | closed form |
//! | [`LinearSpring`] | eq. 10 / 16 | closed form (damped oscillator, eq. 23) | closed form (eq. 24) | closed form (eq. 23) | closed form |
//! | [`FullNonlinear`] | eq. 8 | **integrated**, bottom event located | closed form (eq. 24 with gravity) | **integrated**, liftoff event located | closed form |
//!
//! Only the full model's two pneumatic-spring phases with friction and gravity have no
//! closed form; they are integrated by [`Integrator`] (RK4 fixed step or Dormand-Prince 5(4)
//! adaptive, every loop capped) with event location by bisection on the step length. The
//! stance times of eq. 9 come from an exact quadrature (Dawson's integral, see
//! [`nonlinear`]) and are only computed when [`RunOptions::times`] asks for them.
//!
//! [`Hopper`] joins a model with a thrust law from the core ([`ThrustLaw`]: Raibert's fixed
//! thrust or the energy servo); [`Hopper::run`] / [`Hopper::simulate`] produce one
//! [`Cycle`] per hop (touchdown, bottom, end-of-thrust and liftoff states, the bottom height
//! x_n, the energy E_n, apex and times) and optional dense [`Sample`]s for phase portraits.
//! [`analysis`] extracts return maps, detects periods, sweeps the thrust and locates the first
//! period doubling. [`params::HopperParams`] is the scene's `[hopper]` table.

pub mod analysis;
pub mod eq17;
pub mod full;
pub mod linear;
pub mod nonlinear;
pub mod params;
pub mod sampled;
pub mod valve;

pub use full::FullNonlinear;
pub use linear::LinearSpring;
pub use nonlinear::SimplifiedNonlinear;
pub use params::HopperParams;

use crate::engine::ode::Integrator;

/// Most integrator steps in one stance phase (full model); the run ends with
/// [`RunEnd::StepCap`] beyond.
pub const MAX_STEPS_PER_PHASE: u64 = 10_000_000;

use dexter_core::hop::{flight_energy_jpkg, EnergyServoThrust, RaibertThrust, StancePhase};
use dexter_core::params::ParamError;

/// Most dense samples one run keeps ([`RunOptions::samples_per_phase`] is per phase; the run
/// stops sampling, not simulating, once this many are stored).
pub const MAX_SAMPLES: usize = 200_000;

/// Most samples per phase and hop (`hopper.samples_per_phase`): a run computes at most
/// [`MAX_SAMPLES`] plus one phase's worth of them.
pub const MAX_SAMPLES_PER_PHASE: usize = 10_000;

/// Why a hopper could not be built or run. Parameter errors name the scene key.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum HopperError {
    /// A single parameter is invalid; the name is the `[hopper]` key, e.g.
    /// `hopper.spring_eta1 must be > 0`.
    Param(ParamError),
    /// A parameter violates a relation with others (`param` must satisfy `requirement`).
    Relation {
        /// The `[hopper]` key at fault.
        param: &'static str,
        /// What it must satisfy, in words.
        requirement: &'static str,
    },
    /// The scene text is not valid TOML or does not fit the `[hopper]` schema.
    Toml(String),
}

impl core::fmt::Display for HopperError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            HopperError::Param(e) => write!(f, "{e}"),
            HopperError::Relation { param, requirement } => {
                write!(f, "{param} must satisfy {requirement}")
            }
            HopperError::Toml(m) => write!(f, "hopper scene: {m}"),
        }
    }
}

impl std::error::Error for HopperError {}

impl From<ParamError> for HopperError {
    fn from(e: ParamError) -> Self {
        HopperError::Param(e)
    }
}

/// A state on the vertical line at an instant.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HopEvent {
    /// Time since the start of the run, s (NaN for eq. 9 runs made with
    /// [`RunOptions::times`] off).
    pub time_s: f64,
    /// Body height chi, m.
    pub height_m: f64,
    /// Body velocity chi', m/s, up positive.
    pub velocity_mps: f64,
}

/// One dense sample of the trajectory (for phase portraits, figs. 7–13).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// Hop cycle index (0 = the first).
    pub cycle: usize,
    /// The phase the sample lies in (sec. 3.1).
    pub phase: StancePhase,
    /// Time, s; height chi, m; velocity chi', m/s.
    pub state: HopEvent,
}

/// One hop: from a touchdown (or the initial bottom) to the next touchdown.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cycle {
    /// Cycle index n (0 = the first).
    pub index: usize,
    /// Touchdown at chi_td = chi_l; `None` for a run that starts at a bottom.
    pub touchdown: Option<HopEvent>,
    /// Bottom (chi' = 0, maximal compression): its height is x_n, m.
    pub bottom: HopEvent,
    /// End of thrust, t_b + delta (or the early liftoff, if the leg extended during thrust;
    /// for eq. 9, whose thrust is instantaneous, the bottom itself).
    pub end_of_thrust: HopEvent,
    /// Liftoff, just after the leg pickup of eq. 7 (velocity chi'_l = chi'_l- / (1 + mu')).
    pub liftoff: HopEvent,
    /// Body velocity just before liftoff, chi'_l-, m/s.
    pub liftoff_velocity_before_mps: f64,
    /// Flight apex, m (height chi_l + chi'_l^2 / 2g).
    pub apex: HopEvent,
    /// The next touchdown (the start of cycle n + 1).
    pub next_touchdown: HopEvent,
    /// Bottom height x_n = chi(t_b), m (eq. 15's coordinate).
    pub bottom_height_m: f64,
    /// The model's energy coordinate at the bottom, E_n: eq. 18, ln(chi_l / x_n)
    /// (dimensionless), for the nonlinear models; eq. 17's normalized energy
    /// eta1 (x_n - chi_eq)^2 (m^2/s^2) for the linear model.
    pub energy: f64,
    /// Vertical energy per unit mass at touchdown, J/kg ([`flight_energy_jpkg`], zero
    /// potential at chi_td); NaN for a run that starts at a bottom.
    pub touchdown_energy_jpkg: f64,
    /// Thrust tau applied in this stance, m/s^2.
    pub thrust_mps2: f64,
    /// True if the leg extended during the thrust (the thrust phase was cut short: outside
    /// the paper's physically valid regime, sec. 3.3 / Corollary 8).
    pub early_liftoff: bool,
    /// True if the bottom lies in the dissipation regime: the spring force at bottom exceeds
    /// the thrust (nonlinear models: x_n < eta1 / tau, sec. 4.1; linear: the spring force
    /// eta1 (chi_0 - x_n) exceeds tau).
    pub dissipating: bool,
}

/// Where a run starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start {
    /// In flight at `height_m` (>= chi_l) with `velocity_mps`.
    Flight {
        /// Body height, m (>= chi_l).
        height_m: f64,
        /// Body velocity, m/s, up positive.
        velocity_mps: f64,
    },
    /// At rest at a bottom `height_m` (< chi_l): the run begins with the thrust phase.
    Bottom {
        /// Bottom height x_0, m.
        height_m: f64,
    },
}

impl Start {
    /// The start for a body at rest at `height_m` (Table 1's "initial position"): a flight
    /// apex if at or above `liftoff_m`, else a bottom.
    pub fn at_rest(height_m: f64, liftoff_m: f64) -> Start {
        if height_m >= liftoff_m {
            Start::Flight {
                height_m,
                velocity_mps: 0.0,
            }
        } else {
            Start::Bottom { height_m }
        }
    }
}

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunEnd {
    /// All requested cycles were simulated.
    Completed,
    /// The body turned back down before the leg was extended, nothing drives it out of
    /// the bottom (eq. 9 with no thrust, tau = 0), or it leaves the stance with no speed
    /// (no energy, or a hop height that underflows): no liftoff (the hopper stalls on the
    /// ground; the cycle is not recorded).
    NoLiftoff,
    /// The energy servo asked for a thrust tau_n <= g in a model whose thrust phase has no
    /// spring support (linear with delta > 0, full): the body would sink during the thrust;
    /// the cycle is not recorded.
    WeakThrust,
    /// An integrator hit [`MAX_STEPS_PER_PHASE`] (full model only).
    StepCap,
    /// A state, or a requested time, became non-finite; the cycle is not recorded. (A
    /// bottom deeper than chi_l e^-745, where x_n underflows to 0, keeps E_n exact; its
    /// liftoff speed is then 0 too, which ends the run as [`RunEnd::NoLiftoff`].)
    NonFinite,
}

/// Options of one run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunOptions {
    /// Compute stance times for eq. 9 (exact quadrature; off = faster map-only runs, event
    /// times NaN). The other models always have times.
    pub times: bool,
    /// Dense samples per phase and cycle for phase portraits (0 = none); at most
    /// [`MAX_SAMPLES`] in all.
    pub samples_per_phase: usize,
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            times: true,
            samples_per_phase: 0,
        }
    }
}

/// A finished run.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// One record per hop.
    pub cycles: Vec<Cycle>,
    /// Dense samples (empty unless asked for).
    pub samples: Vec<Sample>,
    /// Why the run ended.
    pub end: RunEnd,
    /// Integrator steps taken, counting rejected adaptive steps and the one-step
    /// re-integrations of event location (full model; 0 for the closed-form models): the
    /// cost side of the accuracy/time trade.
    pub steps: u64,
}

/// The thrust law of each stance, from the core (sec. 1.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ThrustLaw {
    /// Raibert's fixed thrust tau for delta from bottom.
    Raibert(RaibertThrust<f64>),
    /// The energy servo: tau_n from the touchdown energy, for delta from bottom.
    EnergyServo(EnergyServoThrust<f64>),
}

impl ThrustLaw {
    /// The thrust of a stance that began with `touchdown_energy_jpkg` (J/kg; NaN for a run
    /// started at a bottom, which the servo then treats as its nominal thrust's stance).
    pub fn stance(&self, touchdown_energy_jpkg: f64) -> RaibertThrust<f64> {
        match self {
            ThrustLaw::Raibert(r) => *r,
            ThrustLaw::EnergyServo(s) => {
                let e = if touchdown_energy_jpkg.is_finite() {
                    touchdown_energy_jpkg
                } else {
                    s.target_energy_jpkg()
                };
                s.stance_thrust(e)
            }
        }
    }

    /// delta, s.
    pub fn duration_s(&self) -> f64 {
        self.stance(f64::NAN).duration_s()
    }
}

/// One of the three models.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HopperModel {
    /// Eq. 9.
    SimplifiedNonlinear(SimplifiedNonlinear),
    /// Eq. 10 / 16.
    Linear(LinearSpring),
    /// Eq. 8.
    Full(FullNonlinear),
}

/// What a stance produced (shared by the three models).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Stance {
    pub bottom: HopEvent,
    pub end_of_thrust: HopEvent,
    /// Liftoff, velocity before eq. 7.
    pub liftoff: HopEvent,
    pub early_liftoff: bool,
    pub steps: u64,
    /// E_n, computed by the model (eq. 9 keeps it exact when x_n underflows).
    pub energy: f64,
}

/// Outcome of a stance computation.
pub(crate) type StanceResult = Result<Stance, RunEnd>;

/// Sample sink with a global cap.
pub(crate) struct Sampler<'a> {
    pub out: Option<&'a mut Vec<Sample>>,
    pub per_phase: usize,
    pub cycle: usize,
}

impl Sampler<'_> {
    /// True while samples are wanted and room is left for them: a run stops computing
    /// samples, not simulating, once [`MAX_SAMPLES`] are stored.
    pub fn on(&self) -> bool {
        self.per_phase > 0 && self.out.as_ref().is_some_and(|v| v.len() < MAX_SAMPLES)
    }
    pub fn push(&mut self, phase: StancePhase, state: HopEvent) {
        if let Some(v) = self.out.as_deref_mut() {
            if v.len() < MAX_SAMPLES {
                v.push(Sample {
                    cycle: self.cycle,
                    phase,
                    state,
                });
            }
        }
    }
}

impl HopperModel {
    /// chi_l = chi_td, m.
    pub fn liftoff_m(&self) -> f64 {
        match self {
            HopperModel::SimplifiedNonlinear(m) => m.liftoff_m(),
            HopperModel::Linear(m) => m.liftoff_m(),
            HopperModel::Full(m) => m.liftoff_m(),
        }
    }
    /// g in flight, m/s^2.
    pub fn gravity_mps2(&self) -> f64 {
        match self {
            HopperModel::SimplifiedNonlinear(m) => m.gravity_mps2(),
            HopperModel::Linear(m) => m.gravity_mps2(),
            HopperModel::Full(m) => m.gravity_mps2(),
        }
    }
    /// mu', the leg mass as a fraction of the body mass.
    pub fn leg_mass_ratio(&self) -> f64 {
        match self {
            HopperModel::SimplifiedNonlinear(m) => m.leg_mass_ratio(),
            HopperModel::Linear(m) => m.leg_mass_ratio(),
            HopperModel::Full(m) => m.leg_mass_ratio(),
        }
    }
    /// The energy coordinate E of a bottom at `x_m` (see [`Cycle::energy`]).
    pub fn bottom_energy(&self, x_m: f64) -> f64 {
        match self {
            HopperModel::Linear(m) => m.bottom_energy(x_m),
            _ => dexter_core::hop::energy_of_bottom(x_m, self.liftoff_m()),
        }
    }
    fn dissipating(&self, x_m: f64, tau: f64) -> bool {
        match self {
            HopperModel::SimplifiedNonlinear(m) => m.spring_eta1() / x_m > tau,
            HopperModel::Full(m) => m.spring_eta1() / x_m > tau,
            HopperModel::Linear(m) => m.spring_force_mps2(x_m) > tau,
        }
    }
    fn stance(
        &self,
        entry: Entry,
        thrust: RaibertThrust<f64>,
        opts: &RunOptions,
        s: &mut Sampler<'_>,
    ) -> StanceResult {
        match self {
            HopperModel::SimplifiedNonlinear(m) => m.stance(entry, thrust, opts, s),
            HopperModel::Linear(m) => m.stance(entry, thrust, s),
            HopperModel::Full(m) => m.stance(entry, thrust, s),
        }
    }
}

/// How a stance begins.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Entry {
    /// Touchdown at chi_l with this (<= 0) velocity, at this time.
    Touchdown(HopEvent),
    /// At rest at a bottom.
    Bottom(HopEvent),
}

/// A hopper: a model and the thrust law that drives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hopper {
    /// The mechanical model.
    pub model: HopperModel,
    /// The thrust law.
    pub law: ThrustLaw,
}

impl Hopper {
    /// A hopper; eq. 9 requires an instantaneous thrust (delta = 0, sec. 3.1).
    pub fn new(model: HopperModel, law: ThrustLaw) -> Result<Self, HopperError> {
        if matches!(model, HopperModel::SimplifiedNonlinear(_)) && law.duration_s() != 0.0 {
            return Err(HopperError::Relation {
                param: "hopper.thrust_delta_s",
                requirement:
                    "delta = 0 for the simplified nonlinear model (eq. 9: instantaneous thrust)",
            });
        }
        let g = model.gravity_mps2();
        if !matches!(model, HopperModel::SimplifiedNonlinear(_)) {
            let tau_max = match law {
                ThrustLaw::Raibert(r) => r.thrust_mps2(),
                ThrustLaw::EnergyServo(s) => s.thrust_mps2(f64::MIN),
            };
            let needs = law.duration_s() > 0.0 || matches!(model, HopperModel::Full(_));
            if needs && tau_max <= g {
                return Err(HopperError::Relation {
                    param: "hopper.thrust_tau_mps2",
                    requirement: "tau > g (the thrust phase has no spring force, eq. 8/10)",
                });
            }
        }
        Ok(Self { model, law })
    }

    /// The same hopper with Raibert's fixed thrust `thrust_mps2` (same delta): the knob of
    /// a bifurcation sweep.
    pub fn with_thrust(&self, thrust_mps2: f64) -> Result<Self, HopperError> {
        let law = ThrustLaw::Raibert(RaibertThrust::new(thrust_mps2, self.law.duration_s())?);
        Hopper::new(self.model, law)
    }

    /// Simulate `cycles` hops from `start`, collecting every cycle.
    pub fn simulate(
        &self,
        start: Start,
        cycles: usize,
        opts: &RunOptions,
    ) -> Result<Run, HopperError> {
        let mut out = Vec::with_capacity(cycles.min(1 << 16));
        let mut samples = Vec::new();
        let (end, steps) = self.run_inner(start, cycles, opts, Some(&mut samples), &mut |c| {
            out.push(*c)
        })?;
        Ok(Run {
            cycles: out,
            samples,
            end,
            steps,
        })
    }

    /// Simulate `cycles` hops from `start`, passing each cycle to `on_cycle` (no storage:
    /// for long sweeps). Returns why the run ended and the integrator steps taken.
    pub fn run(
        &self,
        start: Start,
        cycles: usize,
        opts: &RunOptions,
        on_cycle: &mut impl FnMut(&Cycle),
    ) -> Result<(RunEnd, u64), HopperError> {
        self.run_inner(start, cycles, opts, None, on_cycle)
    }

    /// [`Hopper::run`], also collecting the dense samples [`RunOptions::samples_per_phase`]
    /// asks for into `samples` (at most [`MAX_SAMPLES`] per run): a run of any length in
    /// bounded memory, with its phase portrait.
    pub fn run_with_samples(
        &self,
        start: Start,
        cycles: usize,
        opts: &RunOptions,
        samples: &mut Vec<Sample>,
        on_cycle: &mut impl FnMut(&Cycle),
    ) -> Result<(RunEnd, u64), HopperError> {
        self.run_inner(start, cycles, opts, Some(samples), on_cycle)
    }

    fn run_inner(
        &self,
        start: Start,
        cycles: usize,
        opts: &RunOptions,
        samples: Option<&mut Vec<Sample>>,
        on_cycle: &mut impl FnMut(&Cycle),
    ) -> Result<(RunEnd, u64), HopperError> {
        let mut sampler = Sampler {
            out: samples,
            per_phase: opts.samples_per_phase,
            cycle: 0,
        };
        let t0 = if opts.times || !matches!(self.model, HopperModel::SimplifiedNonlinear(_)) {
            0.0
        } else {
            f64::NAN
        };
        let mut entry = self.first_entry(start, t0, &mut sampler)?;
        let mut steps = 0;
        for n in 0..cycles {
            sampler.cycle = n;
            match self.cycle(n, entry, opts, &mut sampler, &mut steps) {
                Ok(cycle) => {
                    on_cycle(&cycle);
                    entry = Entry::Touchdown(cycle.next_touchdown);
                }
                Err(end) => return Ok((end, steps)),
            }
        }
        Ok((RunEnd::Completed, steps))
    }

    /// The first cycle's entry event: the touchdown a flight start falls to (closed form),
    /// or the bottom a bottom start is.
    fn first_entry(
        &self,
        start: Start,
        t0: f64,
        sampler: &mut Sampler<'_>,
    ) -> Result<Entry, HopperError> {
        let chi_l = self.model.liftoff_m();
        let g = self.model.gravity_mps2();
        match start {
            Start::Flight {
                height_m,
                velocity_mps,
            } => {
                let h = params::check_finite("hopper.initial_heights_m", height_m)?;
                let v = params::check_finite("hopper.initial_velocity_mps", velocity_mps)?;
                if h < chi_l {
                    return Err(HopperError::Relation {
                        param: "hopper.initial_heights_m",
                        requirement: ">= hopper.liftoff_height_m for a flight start",
                    });
                }
                // closed-form fall to chi_l: chi'_td = -sqrt(v^2 + 2 g (h - chi_l))
                let vtd = -(v * v + 2.0 * g * (h - chi_l)).sqrt();
                let t = (v - vtd) / g;
                if sampler.on() {
                    flight_samples(sampler, t0, h, v, t, g);
                }
                Ok(Entry::Touchdown(HopEvent {
                    time_s: t0 + t,
                    height_m: chi_l,
                    velocity_mps: vtd,
                }))
            }
            Start::Bottom { height_m } => {
                let x = params::check_finite("hopper.initial_heights_m", height_m)?;
                if x >= chi_l || (x <= 0.0 && !matches!(self.model, HopperModel::Linear(_))) {
                    return Err(HopperError::Relation {
                        param: "hopper.initial_heights_m",
                        requirement: "0 < x_0 < hopper.liftoff_height_m for a bottom start",
                    });
                }
                Ok(Entry::Bottom(HopEvent {
                    time_s: t0,
                    height_m: x,
                    velocity_mps: 0.0,
                }))
            }
        }
    }

    /// Cycle `n` from `entry`: the stance under this cycle's thrust, then the closed-form
    /// flight to the next touchdown; `Err` is how the run ends instead. Adds the stance's
    /// integration steps to `steps`.
    fn cycle(
        &self,
        n: usize,
        entry: Entry,
        opts: &RunOptions,
        sampler: &mut Sampler<'_>,
        steps: &mut u64,
    ) -> Result<Cycle, RunEnd> {
        let chi_l = self.model.liftoff_m();
        let g = self.model.gravity_mps2();
        let (touchdown, e_td) = match entry {
            Entry::Touchdown(td) => (Some(td), flight_energy_jpkg(0.0, td.velocity_mps, g)),
            Entry::Bottom(_) => (None, f64::NAN),
        };
        let thrust = self.law.stance(e_td);
        let unsupported = match self.model {
            HopperModel::SimplifiedNonlinear(_) => false,
            HopperModel::Linear(_) => thrust.duration_s() > 0.0,
            HopperModel::Full(_) => true,
        };
        if unsupported && thrust.thrust_mps2() <= g {
            return Err(RunEnd::WeakThrust);
        }
        let st = self.model.stance(entry, thrust, opts, sampler)?;
        *steps += st.steps;
        let v_before = st.liftoff.velocity_mps.max(0.0);
        let v = v_before * (1.0 / (1.0 + self.model.leg_mass_ratio())); // eq. 7
        if v * v / (2.0 * g) == 0.0 {
            // no flight: the liftoff speed is 0 (a touchdown with no energy, e.g. a start
            // at rest at chi_l, E = 0 being eq. 19's fixed point), or so small (a huge leg
            // mass ratio mu') that the hop height underflows: the body stays on its leg
            return Err(RunEnd::NoLiftoff);
        }
        let liftoff = HopEvent {
            velocity_mps: v,
            ..st.liftoff
        };
        let next = HopEvent {
            time_s: liftoff.time_s + 2.0 * v / g,
            height_m: chi_l,
            velocity_mps: -v,
        };
        if sampler.on() {
            flight_samples(sampler, liftoff.time_s, chi_l, v, 2.0 * v / g, g);
        }
        let x = st.bottom.height_m;
        let times_ok = !opts.times || next.time_s.is_finite();
        if !(x.is_finite() && v.is_finite() && st.energy.is_finite() && times_ok) {
            return Err(RunEnd::NonFinite);
        }
        Ok(Cycle {
            index: n,
            touchdown,
            bottom: st.bottom,
            end_of_thrust: st.end_of_thrust,
            liftoff,
            liftoff_velocity_before_mps: v_before,
            apex: HopEvent {
                time_s: liftoff.time_s + v / g,
                height_m: chi_l + v * v / (2.0 * g),
                velocity_mps: 0.0,
            },
            next_touchdown: next,
            bottom_height_m: x,
            energy: st.energy,
            touchdown_energy_jpkg: e_td,
            thrust_mps2: thrust.thrust_mps2(),
            early_liftoff: st.early_liftoff,
            dissipating: self.model.dissipating(x, thrust.thrust_mps2()),
        })
    }
}

/// Uniform-time samples of a ballistic flight from (`h`, `v`) at `t0` over `dur` s.
fn flight_samples(s: &mut Sampler<'_>, t0: f64, h: f64, v: f64, dur: f64, g: f64) {
    let n = s.per_phase;
    for i in 0..=n {
        let t = if n == 0 {
            0.0
        } else {
            dur * i as f64 / n as f64
        };
        let b = dexter_core::state::BallState::new(h, v).flown(t, g);
        s.push(
            StancePhase::Flight,
            HopEvent {
                time_s: t0 + t,
                height_m: b.height_m,
                velocity_mps: b.velocity_mps,
            },
        );
    }
}
