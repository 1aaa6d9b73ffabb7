//! Return maps, periods and bifurcations extracted from simulated hops (sec. 2.3, 4).
//!
//! - [`bottom_heights`] / [`energies`]: the sequences x_n (eq. 15's coordinate) and E_n
//!   (eq. 18/19, or eq. 17's normalized energy for the linear model).
//! - [`return_map`]: the pairs (v_n, v_{n+1}) to plot against the closed forms.
//! - [`detect_period`]: the smallest period of the late orbit within a tolerance.
//! - [`sweep_thrust`]: bifurcation-diagram points (tau, late E_n values) over the thrust.
//! - [`locate_first_doubling`]: the first period doubling, by bisection on the detected
//!   period with a bounded number of steps.
//! - [`Eq15`], [`Eq15InEnergy`], [`Eq19Family`], [`certificate`], [`cascade()`]: the
//!   Singer–Guckenheimer certificate of the simplified nonlinear model (sec. 4.1, Lemmas
//!   1–3, Theorem 1) on the conjugate of eq. 15 by eq. 18, and its doubling cascade.

use super::{Cycle, Hopper, HopperError, RunEnd, RunOptions, Start};
use crate::engine::unimodal::cascade::{self, CascadeError, Family, FamilyJet};
use crate::engine::unimodal::jet::{Jet, Scalar};
use crate::engine::unimodal::{certify, Certificate, Map1d, Options};

/// Most periods [`detect_period`] is asked to look for in a sweep.
pub const MAX_PERIOD: usize = 64;

/// x_n of each cycle, m.
pub fn bottom_heights(cycles: &[Cycle]) -> Vec<f64> {
    cycles.iter().map(|c| c.bottom_height_m).collect()
}

/// E_n of each cycle (see [`Cycle::energy`]).
pub fn energies(cycles: &[Cycle]) -> Vec<f64> {
    cycles.iter().map(|c| c.energy).collect()
}

/// The return-map pairs (v_n, v_{n+1}).
pub fn return_map(values: &[f64]) -> Vec<(f64, f64)> {
    values.windows(2).map(|w| (w[0], w[1])).collect()
}

/// The smallest p in 1..=`max_period` such that every value of the last `2 p` (at least
/// 8) satisfies |v_i - v_{i-p}| <= `tol` (1 + |v_i|); `None` if none does (aperiodic,
/// chaotic, or not yet settled) or the sequence is too short.
pub fn detect_period(values: &[f64], max_period: usize, tol: f64) -> Option<usize> {
    (1..=max_period).find(|&p| {
        let window = (2 * p).max(8);
        if values.len() < window + p {
            return false;
        }
        let n = values.len();
        (n - window..n).all(|i| {
            let (a, b) = (values[i], values[i - p]);
            a.is_finite() && (a - b).abs() <= tol * (1.0 + a.abs())
        })
    })
}

/// One point of a bifurcation diagram.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepPoint {
    /// The thrust tau, m/s^2.
    pub thrust_mps2: f64,
    /// The late-orbit energies E_n (the last `keep` cycles).
    pub values: Vec<f64>,
    /// Their detected period ([`detect_period`] with the sweep's tolerance).
    pub period: Option<usize>,
    /// How the run ended.
    pub end: RunEnd,
}

/// Late-orbit energies of `hopper` with fixed thrust `tau` from `start`: `transient` cycles
/// dropped, then `keep` kept (map-only run: no eq. 9 times).
pub fn late_orbit(
    hopper: &Hopper,
    tau: f64,
    start: Start,
    transient: usize,
    keep: usize,
) -> Result<(Vec<f64>, RunEnd, Option<f64>), HopperError> {
    let h = hopper.with_thrust(tau)?;
    let mut vals = Vec::with_capacity(keep);
    let mut last_x = None;
    let opts = RunOptions {
        times: false,
        samples_per_phase: 0,
    };
    let (end, _) = h.run(start, transient + keep, &opts, &mut |c| {
        if c.index >= transient {
            vals.push(c.energy);
        }
        last_x = Some(c.bottom_height_m);
    })?;
    Ok((vals, end, last_x))
}

/// Bifurcation diagram over the thrust: for each tau in `thrusts` (m/s^2), the late orbit
/// of [`late_orbit`] and its period (tolerance `tol`).
pub fn sweep_thrust(
    hopper: &Hopper,
    start: Start,
    thrusts: &[f64],
    transient: usize,
    keep: usize,
    tol: f64,
) -> Result<Vec<SweepPoint>, HopperError> {
    thrusts
        .iter()
        .map(|&tau| {
            let (values, end, _) = late_orbit(hopper, tau, start, transient, keep)?;
            let period = detect_period(&values, MAX_PERIOD.min(keep / 3).max(1), tol);
            Ok(SweepPoint {
                thrust_mps2: tau,
                values,
                period,
                end,
            })
        })
        .collect()
}

/// The bracket found by [`locate_first_doubling`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Doubling {
    /// Largest thrust classified period 1, m/s^2.
    pub below_mps2: f64,
    /// Smallest thrust classified period >= 2, m/s^2.
    pub above_mps2: f64,
    /// Bisection steps used.
    pub steps: u32,
}

impl Doubling {
    /// The estimate, the bracket's midpoint, m/s^2.
    pub fn estimate_mps2(&self) -> f64 {
        0.5 * (self.below_mps2 + self.above_mps2)
    }
}

/// Relative change of the alternation amplitude over the second half of a probe below which
/// a detected period >= 2 counts as settled.
pub const SETTLED_REL: f64 = 1e-6;

/// Classification of one probe (see [`locate_first_doubling`]): true if period >= 2; and
/// the continuation start for the next probe if period 1.
fn classify(
    hopper: &Hopper,
    tau: f64,
    start: Start,
    cycles: usize,
    tol: f64,
) -> Result<(bool, Option<Start>), HopperError> {
    let h = hopper.with_thrust(tau)?;
    let opts = RunOptions {
        times: false,
        samples_per_phase: 0,
    };
    let cycles = cycles.max(4 * MAX_PERIOD);
    let mut e = Vec::with_capacity(cycles);
    let mut last_x = [f64::NAN; 2];
    let (end, _) = h.run(start, cycles, &opts, &mut |c| {
        e.push(c.energy);
        last_x = [last_x[1], c.bottom_height_m];
    })?;
    if end != RunEnd::Completed {
        return Err(HopperError::Relation {
            param: "hopper.thrust_tau_mps2",
            requirement: "a bisection probe that completes its cycles (it stalled)",
        });
    }
    let n = e.len();
    let half = (n / 2) & !1;
    let amp = |i: usize| (e[i] - e[i - 1]).abs();
    let (a_end, a_mid) = (amp(n - 1), amp(n - 1 - half));
    let doubled = match detect_period(&e[n - 3 * MAX_PERIOD..], MAX_PERIOD, tol) {
        Some(1) => false,
        Some(_) if (a_end / a_mid - 1.0).abs() <= SETTLED_REL => true,
        _ => a_end >= a_mid,
    };
    let next_start = (!doubled).then(|| Start::Bottom {
        height_m: 0.5 * (last_x[0] + last_x[1]),
    });
    Ok((doubled, next_start))
}

/// Locate the first period doubling in thrust between `below_mps2` (period 1) and
/// `above_mps2` (period >= 2) by at most `max_steps` bisection steps; stops early once the
/// bracket is narrower than `resolution_mps2` (m/s^2). Errors if the ends are not
/// classified as claimed.
///
/// Each probe is a map-only run of `cycles` hops (at least 256), classified by its
/// detected period (tolerance `tol`) and, when unsettled, by the trend of its alternation
/// amplitude a = |E_n - E_n-1| between mid-run and the end:
/// - a detected period 1 is period 1;
/// - a detected period p >= 2 whose amplitude held over the second half
///   (|a / a_mid - 1| <= [`SETTLED_REL`]) is period p;
/// - otherwise the orbit has not settled (near the bifurcation the multiplier is close to
///   -1, and a slowly decaying alternation can even pass a period-2 test): a decaying
///   alternation is still converging to the fixed point (period 1), a growing one is being
///   attracted by a period-2 orbit.
///
/// The trend is decisive because probes after the first start near the fixed point: at the
/// midpoint of the last two bottoms of the latest period-1 probe (continuation), where the
/// alternation is smaller than the period-2 orbit that appears above the bifurcation.
#[allow(clippy::too_many_arguments)]
pub fn locate_first_doubling(
    hopper: &Hopper,
    start: Start,
    below_mps2: f64,
    above_mps2: f64,
    max_steps: u32,
    cycles: usize,
    tol: f64,
    resolution_mps2: f64,
) -> Result<Doubling, HopperError> {
    let (lo_doubled, lo_next) = classify(hopper, below_mps2, start, cycles, tol)?;
    if lo_doubled {
        return Err(HopperError::Relation {
            param: "below_mps2",
            requirement: "a period-1 thrust (the lower bracket end)",
        });
    }
    let (hi_doubled, _) = classify(hopper, above_mps2, start, cycles, tol)?;
    if !hi_doubled {
        return Err(HopperError::Relation {
            param: "above_mps2",
            requirement: "a period >= 2 thrust (the upper bracket end)",
        });
    }
    let (mut lo, mut hi) = (below_mps2, above_mps2);
    let mut from = lo_next.unwrap_or(start);
    let mut steps = 0;
    while steps < max_steps && hi - lo > resolution_mps2 {
        let mid = 0.5 * (lo + hi);
        let (doubled, next) = classify(hopper, mid, from, cycles, tol)?;
        if doubled {
            hi = mid;
        } else {
            lo = mid;
            from = next.unwrap_or(from);
        }
        steps += 1;
    }
    Ok(Doubling {
        below_mps2: lo,
        above_mps2: hi,
        steps,
    })
}

/// Eq. 15, the bottom-height return map of the simplified nonlinear model in x (m):
/// g(x) = χ_l exp{−k x ln(χ_l/x)}, k = τμ/η₁ (1/m). Its own Schwarzian is positive near
/// x = 0 (for k χ_l = 14.5, on x < 0.01133 χ_l; mpmath), inside the invariant interval once
/// α = k χ_l exceeds about 11.5: the certificate needs the conjugacy of eq. 18.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eq15 {
    /// k = τμ/η₁, 1/m.
    pub k_per_m: f64,
    /// χ_l, m.
    pub chi_l_m: f64,
}

impl Map1d for Eq15 {
    fn jet<T: Scalar>(&self, x: Jet<T>) -> Jet<T> {
        let ln_ratio = (Jet::cst(self.chi_l_m) * x.recip()).ln();
        (x * ln_ratio)
            .scale(-self.k_per_m)
            .exp()
            .scale(self.chi_l_m)
    }
}

/// Eq. 15 conjugated by eq. 18, h(x) = ln(χ_l/x): f = h ∘ g ∘ h⁻¹ in the energy
/// coordinate E (dimensionless), computed literally through x = h⁻¹(E) = χ_l e^−E, g and h
/// (so that it is the conjugacy, not a formula for its result, that is certified). It
/// equals eq. 19, f(E) = α E e^−E with α = k χ_l (sec. 4.1; checked in the tests).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eq15InEnergy(pub Eq15);

impl Map1d for Eq15InEnergy {
    fn jet<T: Scalar>(&self, e: Jet<T>) -> Jet<T> {
        let chi = self.0.chi_l_m;
        let x = (-e).exp().scale(chi);
        let g = self.0.jet(x);
        (Jet::cst(chi) * g.recip()).ln()
    }
}

impl Eq15InEnergy {
    /// α = τ χ_l μ/η₁ (eq. 19).
    pub fn alpha(&self) -> f64 {
        self.0.k_per_m * self.0.chi_l_m
    }
}

/// Eq. 19 as a family in α: f(E; α) = α E e^−E, critical point E = 1 (Lemma 2), with
/// f_E = α e^−E (1 − E), f_EE = α e^−E (E − 2), f_α = E e^−E, f_Eα = e^−E (1 − E).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Eq19Family;

impl Family for Eq19Family {
    fn eval(&self, e: f64, a: f64) -> FamilyJet {
        let x = (-e).exp();
        FamilyJet {
            f: a * e * x,
            fx: a * x * (1.0 - e),
            fxx: a * x * (e - 2.0),
            fa: e * x,
            fxa: x * (1.0 - e),
        }
    }
    fn critical(&self, _: f64) -> f64 {
        1.0
    }
}

/// The closed-form argument for eq. 19's Schwarzian (Lemma 2, re-derived: f′ = α e^−E (1 −
/// E), f″ = α e^−E (E − 2), f‴ = α e^−E (3 − E), so 2 f′ f‴ − 3 f″² = −α² e^−2E ((E − 2)² +
/// 2) < 0 everywhere).
pub const EQ19_SCHWARZIAN: &str = "S f(E) = -((E - 2)^2 + 2) / (2 (1 - E)^2) < 0 for all E != 1 (eq. 19, Lemma 2; the numerator 2 f' f''' - 3 f''^2 = -alpha^2 e^(-2E) ((E - 2)^2 + 2) < 0 also at E = 1)";

/// Eq. 19's Schwarzian in closed form (Lemma 2), at E ≠ 1 (dimensionless).
pub fn eq19_schwarzian(e: f64) -> f64 {
    -((e - 2.0).powi(2) + 2.0) / (2.0 * (1.0 - e).powi(2))
}

/// The certificate of eq. 15 through eq. 18 on the invariant interval [0, α/e] of E: f
/// maps (0, ∞) into (0, α/e] (its maximum is f(1) = α/e), so every orbit enters it after
/// one hop; 0 is the degenerate zero-height hop (Lemma 1: repelling iff α > 1).
pub fn certificate(map: &Eq15InEnergy) -> Certificate {
    let b = map.alpha() / std::f64::consts::E;
    certify(map, 0.0, b, &Options::default())
}

/// α₁ of eq. 19 in closed form: f′(E*) = 1 − ln α = −1 at α = e².
pub const ALPHA_1: f64 = std::f64::consts::E * std::f64::consts::E;

/// The first `count` period doublings of eq. 19 in α (Theorem 1's cascade), by
/// [`cascade::doublings`] from α = 3 (period 1, multiplier 1 − ln 3 ≈ −0.10).
pub fn cascade(count: usize) -> Result<Vec<cascade::Doubling>, CascadeError> {
    cascade::doublings(&Eq19Family, 3.0, 0.25, count)
}

/// Lemma 4's conjugate of eq. 17 (the tuned linear model, sec. 4.2) in the
/// "normalized-phase-angle-at-end-of-thrust" x = h⁻¹(E) = arctan(ψ̇_t/(√E − ψ_t)) ∈ [0, π/2]
/// (rad): g(x) = arctan(ḡ/(1 − ρ ḡ)), ḡ(x) = sin x e^{β(π − x)}, ρ = ψ_t/ψ̇_t (eq. 21).
///
/// Re-derived (the extracted text lost two symbols): with h(x) = (ψ̇_t/tan x + ψ_t)²,
/// (√E − ψ_t)² + ψ̇_t² = ψ̇_t²/sin²x and eq. 17's exponent −2β(π − x), so
/// f∘h(x) = ψ̇_t²/sin²x · e^{−2β(π − x)} (the text prints e^{+2β(π − x)}), and
/// g = h⁻¹∘f∘h = arctan(sin x e^{β(π−x)} / (1 − (ψ_t/ψ̇_t) sin x e^{β(π−x)})) (the text
/// prints ψ̇_t/ψ_t, against its own ρ = ψ_t/ψ̇_t of eq. 21). The multiplier at a fixed
/// point is the same in every coordinate, so it is f′(E*) of eq. 17.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eq17Conjugate {
    /// β (damping ratio parameter of eq. 16), dimensionless.
    pub beta: f64,
    /// ρ = ψ_t/ψ̇_t, dimensionless.
    pub rho: f64,
}

impl Map1d for Eq17Conjugate {
    fn jet<T: Scalar>(&self, x: Jet<T>) -> Jet<T> {
        let pi = std::f64::consts::PI;
        let gbar = x.sin() * (x.scale(-self.beta) + Jet::cst(self.beta * pi)).exp();
        let den = Jet::cst(1.0) - gbar.scale(self.rho);
        (gbar * den.recip()).atan()
    }
}

impl Eq17Conjugate {
    /// ḡ's critical point c = arctan(1/β) (Lemma 4), rad.
    pub fn critical(&self) -> f64 {
        (1.0 / self.beta).atan()
    }

    /// ḡ(x) = sin x e^{β(π − x)}.
    pub fn gbar(&self, x: f64) -> f64 {
        x.sin() * (self.beta * (std::f64::consts::PI - x)).exp()
    }

    /// True if g is defined on all of [0, π/2]: ρ ḡ(c) < 1 (else some bottom's thrust does
    /// not end in stance, √E ≤ ψ_t: the model leaves its physical domain, Lemma 7).
    pub fn physical(&self) -> bool {
        self.beta > 0.0 && self.rho * self.gbar(self.critical()) < 1.0
    }
}

/// The certificate of eq. 17 through Lemma 4's conjugate, on [0, g(c)]: g maps [0, π/2]
/// into [0, g(c)] (its maximum); 0 (E → ∞) is a repelling fixed point with multiplier
/// e^{βπ} (Lemma 5). `None` if the model is not physical ([`Eq17Conjugate::physical`]).
pub fn certificate_eq17(map: &Eq17Conjugate) -> Option<Certificate> {
    map.physical()
        .then(|| certify(map, 0.0, map.f(map.critical()), &Options::default()))
}
