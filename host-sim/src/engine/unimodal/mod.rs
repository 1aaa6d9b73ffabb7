//! Singer–Guckenheimer certificates for one-dimensional return maps (Koditschek & Bühler
//! 1991, sec. 2.3 and 4; Rizzi & Koditschek 1994, sec. 2.2).
//!
//! For a C³ map f of a compact interval I = [a, b] into itself, [`certify`] establishes,
//! each with a proof-grade argument (interval arithmetic, [`interval`], over an adaptive
//! subdivision, on the jets of [`jet`]):
//!
//! - **invariance**: f(I) ⊆ I (the image of each monotone branch is the hull of its end
//!   values; at a critical point the enclosure of f over its bracket);
//! - **critical points** (unimodality): every zero of f′ in I, each in a bracket on which
//!   f″ has one sign (so the zero is simple and unique there), or the place where they
//!   could not be resolved;
//! - **the sign of the Schwarzian derivative** (eq. 5) Sf = f‴/f′ − (3/2)(f″/f′)² over the
//!   whole of I, through its numerator N = 2 f′ f‴ − 3 f″² = 2 f′² Sf: N < 0 on a cell
//!   proves S < 0 there (and, at a critical point, that it is non-degenerate, f″ ≠ 0), N > 0
//!   proves S > 0 there; a cell where neither holds at the finest subdivision is reported as
//!   undetermined. A grid of samples is never used as a proof;
//! - **fixed points** (zeros of f(x) − x, each bracketed like the critical points) with
//!   their multipliers f′(x*) and rigorous bounds on them;
//! - **the endpoints' roles**: a repelling fixed point, the critical value f(c), or mapped
//!   onto a repelling fixed point;
//! - **the verdict** ([`Verdict`]).
//!
//! The theorem applied (Singer 1978; Guckenheimer 1979; Collet & Eckmann 1980, II.5.7 and
//! III; de Melo & van Strien 1993, thm. II.6.1): if Sf < 0 on I (except at critical points),
//! the immediate basin of every attracting periodic orbit contains a critical point or an
//! endpoint of I. So if I is invariant, f has at most one critical point in I, and each
//! endpoint is a repelling fixed point, the critical value, or maps onto a repelling fixed
//! point, then f has **at most one attracting periodic orbit**, and when it has one its
//! basin has full Lebesgue measure in I (Guckenheimer: no wandering intervals for S < 0
//! with a non-flat critical point). A locally stable fixed point is then **essentially
//! globally asymptotically stable**; past a flip, the unique attracting cycle (if any) is the
//! limit of the critical orbit, which [`certify`] follows and names. The sign of S is
//! invariant under projective (Möbius) changes of coordinates but not under others: a map
//! whose own S is not negative may still be certified through a conjugate (eq. 18/19), and
//! the certificate then names the conjugate's coordinate.
//!
//! [`cascade`] locates the period doublings of a one-parameter family by continuation of
//! each 2ⁿ-cycle to multiplier −1 (Theorem 1's cascade).

pub mod cascade;
pub mod interval;
pub mod jet;
pub mod pictures;

use interval::Interval;
use jet::{Jet, Scalar};
use serde_json::{json, Value};

/// A C³ map of the line, written once over any [`Scalar`] so that it gives point jets
/// (values and derivatives) and interval jets (enclosures over an interval).
pub trait Map1d {
    /// (f, f′, f″, f‴) at `x` (the jet of the variable, [`Jet::var`]).
    fn jet<T: Scalar>(&self, x: Jet<T>) -> Jet<T>;

    /// f(x).
    fn f(&self, x: f64) -> f64 {
        self.jet(Jet::var(x)).v
    }
    /// (f, f′, f″, f‴) at the point x.
    fn at(&self, x: f64) -> Jet<f64> {
        self.jet(Jet::var(x))
    }
    /// Enclosures of (f, f′, f″, f‴) over the interval `x`.
    fn over(&self, x: Interval) -> Jet<Interval> {
        self.jet(Jet::var(x))
    }
}

/// The Schwarzian derivative of eq. 5 at a point from its jet: f‴/f′ − (3/2)(f″/f′)²
/// (±∞ or NaN at a critical point, where it is not defined).
pub fn schwarzian(j: &Jet<f64>) -> f64 {
    let r = j.d2 / j.d1;
    j.d3 / j.d1 - 1.5 * r * r
}

/// N = 2 f′ f‴ − 3 f″² = 2 f′² Sf: the Schwarzian's sign where f′ ≠ 0, and −3 f″² < 0 at
/// a non-degenerate critical point.
pub fn schwarzian_numerator<T: Scalar>(j: &Jet<T>) -> T {
    T::cst(2.0) * j.d1 * j.d3 - T::cst(3.0) * j.d2 * j.d2
}

/// Limits of the adaptive subdivision.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Deepest bisection of a cell (a cell of I is at least (b − a) 2^−depth wide).
    pub max_depth: u32,
    /// Most cells examined by one scan (a scan that would exceed it reports the rest as
    /// undetermined).
    pub max_cells: usize,
    /// Longest period looked for in the critical orbit's limit.
    pub max_period: usize,
    /// Iterations of the critical orbit before its limit cycle is looked for.
    pub transient: usize,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            max_depth: 40,
            max_cells: 400_000,
            max_period: 64,
            transient: 20_000,
        }
    }
}

/// A zero of a function φ on I, in a bracket on which φ′ has one sign.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Zero {
    /// Its location (the bracket's midpoint after bisection to rounding).
    pub x: f64,
    /// An interval that contains the zero (rigorously, when φ changes sign strictly across
    /// it; a degenerate bracket at a point where φ's enclosure contains 0 is to rounding).
    pub bracket: Interval,
    /// The sign of φ′ across the bracket (+1 or −1).
    pub slope_sign: f64,
}

/// Every zero of φ on [lo, hi], and the ranges where they could not be resolved.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ZeroScan {
    /// The zeros, in order.
    pub zeros: Vec<Zero>,
    /// Ranges where φ's enclosure contains 0 but φ′'s does too at the finest subdivision.
    pub unresolved: Vec<(f64, f64)>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Cell {
    Clear,
    Mono(f64),
    Unresolved,
}

/// The zeros of φ on [lo, hi]; `enclose(X)` returns enclosures of (φ, φ′) over X.
fn scan_zeros(
    lo: f64,
    hi: f64,
    enclose: &dyn Fn(Interval) -> (Interval, Interval),
    opts: &Options,
) -> ZeroScan {
    // depth-first, left cell first: the cells come out in order and tile [lo, hi]
    let mut stack = vec![(lo, hi, 0u32)];
    let mut cells: Vec<(f64, f64, Cell)> = Vec::new();
    let mut examined = 0usize;
    while let Some((l, r, depth)) = stack.pop() {
        examined += 1;
        let (p, dp) = enclose(Interval::new(l, r));
        let m = 0.5 * l + 0.5 * r;
        let kind = if !p.contains_zero() {
            Cell::Clear
        } else if dp.is_positive() {
            Cell::Mono(1.0)
        } else if dp.is_negative() {
            Cell::Mono(-1.0)
        } else if depth >= opts.max_depth || examined >= opts.max_cells || m <= l || m >= r {
            Cell::Unresolved
        } else {
            stack.push((m, r, depth + 1));
            stack.push((l, m, depth + 1));
            continue;
        };
        cells.push((l, r, kind));
    }
    let mut scan = ZeroScan::default();
    let value = |x: f64| enclose(Interval::point(x)).0;
    let mut i = 0;
    while i < cells.len() {
        let (gl, mut gh, kind) = cells[i];
        i += 1;
        match kind {
            Cell::Clear => continue,
            Cell::Unresolved => {
                // merge touching unresolved cells into one range
                while i < cells.len() && cells[i].2 == Cell::Unresolved {
                    gh = cells[i].1;
                    i += 1;
                }
                scan.unresolved.push((gl, gh));
                continue;
            }
            Cell::Mono(s) => {
                // φ is strictly monotone on the union of touching cells with one φ′ sign
                while i < cells.len() && cells[i].2 == Cell::Mono(s) {
                    gh = cells[i].1;
                    i += 1;
                }
                let (pl, ph) = (value(gl), value(gh));
                let push = |scan: &mut ZeroScan, z: Zero| {
                    if scan.zeros.last().is_none_or(|last| last.x != z.x) {
                        scan.zeros.push(z);
                    }
                };
                if pl.contains_zero() {
                    push(&mut scan, point_zero(gl, s));
                } else if ph.contains_zero() {
                    push(&mut scan, point_zero(gh, s));
                } else if pl.is_negative() != ph.is_negative() {
                    push(&mut scan, bisect(gl, gh, pl.is_negative(), s, &value));
                }
            }
        }
    }
    scan
}

fn point_zero(x: f64, s: f64) -> Zero {
    Zero {
        x,
        bracket: Interval::point(x),
        slope_sign: s,
    }
}

/// Bisect [l, r] (φ(l) < 0 iff `left_negative`, φ(r) of the other strict sign) while the
/// midpoint's enclosure has a sign.
fn bisect(
    mut l: f64,
    mut r: f64,
    left_negative: bool,
    s: f64,
    value: &dyn Fn(f64) -> Interval,
) -> Zero {
    let mut x = 0.5 * l + 0.5 * r;
    for _ in 0..2100 {
        let m = 0.5 * l + 0.5 * r;
        if m <= l || m >= r {
            break;
        }
        let v = value(m);
        if v.contains_zero() {
            // m is a zero to rounding: tighten the bracket around it to strict signs
            x = m;
            let mut d = m.abs().max(f64::MIN_POSITIVE) * f64::EPSILON;
            while d < r - l {
                let (lo, hi) = ((m - d).max(l), (m + d).min(r));
                let (vl, vh) = (value(lo), value(hi));
                let strict = |v: Interval| !v.contains_zero();
                if strict(vl)
                    && strict(vh)
                    && vl.is_negative() == left_negative
                    && vh.is_negative() != left_negative
                {
                    return Zero {
                        x,
                        bracket: Interval::new(lo, hi),
                        slope_sign: s,
                    };
                }
                d *= 2.0;
            }
            break;
        }
        if v.is_negative() == left_negative {
            l = m;
        } else {
            r = m;
        }
        x = 0.5 * l + 0.5 * r;
    }
    Zero {
        x,
        bracket: Interval::new(l, r),
        slope_sign: s,
    }
}

/// The Schwarzian's sign over [lo, hi], by interval arithmetic on N = 2 f′ f‴ − 3 f″².
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SchwarzianScan {
    /// Cells examined.
    pub cells: usize,
    /// Ranges on which S > 0 is proven (touching cells merged).
    pub positive: Vec<(f64, f64)>,
    /// Ranges on which the sign is not decided at the finest subdivision.
    pub undetermined: Vec<(f64, f64)>,
}

impl SchwarzianScan {
    /// True if S < 0 is proven on the whole interval (except at critical points, where
    /// N < 0 still proves them non-degenerate).
    pub fn negative(&self) -> bool {
        self.positive.is_empty() && self.undetermined.is_empty()
    }
}

/// Scan the sign of N over [lo, hi].
pub fn scan_schwarzian<M: Map1d>(map: &M, lo: f64, hi: f64, opts: &Options) -> SchwarzianScan {
    let mut out = SchwarzianScan::default();
    let mut stack = vec![(lo, hi, 0u32)];
    let merge = |v: &mut Vec<(f64, f64)>, l: f64, r: f64| match v.last_mut() {
        Some(last) if last.1 == l => last.1 = r,
        _ => v.push((l, r)),
    };
    while let Some((l, r, depth)) = stack.pop() {
        out.cells += 1;
        let n = schwarzian_numerator(&map.over(Interval::new(l, r)));
        if n.is_negative() {
            continue;
        }
        let m = 0.5 * l + 0.5 * r;
        if n.is_positive() {
            merge(&mut out.positive, l, r);
        } else if depth >= opts.max_depth || out.cells >= opts.max_cells || m <= l || m >= r {
            merge(&mut out.undetermined, l, r);
        } else {
            stack.push((m, r, depth + 1));
            stack.push((l, m, depth + 1));
        }
    }
    out
}

/// A critical point of f in I.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CriticalPoint {
    /// Location.
    pub x: f64,
    /// True for a maximum (f″ < 0 across its bracket), false for a minimum.
    pub maximum: bool,
    /// f(x), the critical value.
    pub value: f64,
    /// An enclosure of f over the bracket (rigorous bound on the critical value).
    pub value_bounds: Interval,
}

/// Stability of a fixed point from the bounds on its multiplier.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stability {
    /// |f′(x*)| < 1 on the whole bracket.
    Attracting,
    /// |f′(x*)| > 1 on the whole bracket.
    Repelling,
    /// The bounds straddle ±1 (a bifurcation point, to rounding).
    Undetermined,
}

impl Stability {
    /// Its JSON name.
    pub fn name(self) -> &'static str {
        match self {
            Stability::Attracting => "attracting",
            Stability::Repelling => "repelling",
            Stability::Undetermined => "undetermined (|multiplier| = 1 to rounding)",
        }
    }
}

/// A fixed point of f in I.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedPoint {
    /// Location.
    pub x: f64,
    /// f′(x).
    pub multiplier: f64,
    /// f′ enclosed over the fixed point's bracket.
    pub multiplier_bounds: Interval,
    /// From the bounds.
    pub stability: Stability,
    /// True unless it is an endpoint of I.
    pub interior: bool,
}

/// What an endpoint of I is, for Singer's count of attracting orbits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EndpointRole {
    /// A fixed point with |f′| > 1: no attracting orbit's basin contains it.
    RepellingFixedPoint,
    /// The critical value f(c) (to rounding): its orbit is the critical orbit.
    CriticalValue,
    /// f maps it onto the other endpoint, a repelling fixed point (to rounding).
    MapsToRepellingFixedPoint,
    /// None of these: it may pull an attracting orbit of its own.
    Free,
}

impl EndpointRole {
    /// Its JSON name.
    pub fn name(self) -> &'static str {
        match self {
            EndpointRole::RepellingFixedPoint => "repelling fixed point",
            EndpointRole::CriticalValue => "critical value f(c)",
            EndpointRole::MapsToRepellingFixedPoint => "maps onto a repelling fixed point",
            EndpointRole::Free => "free (may attract an orbit of its own)",
        }
    }
}

/// A periodic orbit.
#[derive(Clone, Debug, PartialEq)]
pub struct Cycle {
    /// Its (least) period.
    pub period: usize,
    /// Its points in orbit order, starting from the smallest.
    pub points: Vec<f64>,
    /// (fᵖ)′ = ∏ f′ along the orbit.
    pub multiplier: f64,
}

/// The certificate's conclusion.
#[derive(Clone, Debug, PartialEq)]
pub enum Verdict {
    /// Every hypothesis holds and an interior fixed point attracts: it is essentially
    /// globally asymptotically stable (Singer–Guckenheimer).
    Certified {
        /// The fixed point.
        fixed_point: f64,
        /// Its multiplier.
        multiplier: f64,
    },
    /// A fixed point attracts, but a hypothesis failed (named in `failed`).
    LocallyStable {
        /// The fixed point.
        fixed_point: f64,
        /// Its multiplier.
        multiplier: f64,
    },
    /// No fixed point attracts. With every hypothesis holding, the attracting cycle (if
    /// one was found) is unique and attracts almost every point.
    Unstable {
        /// The limit cycle of the critical orbit, if it settled.
        cycle: Option<Cycle>,
        /// True if every hypothesis held (the cycle is then the unique attractor).
        unique: bool,
    },
}

impl Verdict {
    /// A short code: `egas`, `locally_stable_no_certificate`, `unstable`.
    pub fn code(&self) -> &'static str {
        match self {
            Verdict::Certified { .. } => "egas",
            Verdict::LocallyStable { .. } => "locally_stable_no_certificate",
            Verdict::Unstable { .. } => "unstable",
        }
    }
}

/// Everything [`certify`] found.
#[derive(Clone, Debug)]
pub struct Certificate {
    /// I = [a, b].
    pub interval: (f64, f64),
    /// A rigorous enclosure of f(I) (valid when the critical points were all resolved).
    pub image: Interval,
    /// f(I) ⊆ I (to a rounding tolerance of [`INVARIANCE_TOL`] (b − a)).
    pub invariant: bool,
    /// The critical points in I.
    pub critical_points: Vec<CriticalPoint>,
    /// Ranges where critical points were not resolved.
    pub critical_unresolved: Vec<(f64, f64)>,
    /// The Schwarzian's sign over I.
    pub schwarzian: SchwarzianScan,
    /// The fixed points in I.
    pub fixed_points: Vec<FixedPoint>,
    /// Ranges where fixed points were not resolved.
    pub fixed_unresolved: Vec<(f64, f64)>,
    /// The roles of a and b.
    pub endpoints: [EndpointRole; 2],
    /// The hypotheses that failed, each in words with the place.
    pub failed: Vec<String>,
    /// The conclusion.
    pub verdict: Verdict,
}

/// Relative tolerance of the invariance test: an interval whose endpoint is the critical
/// value f(c), computed in floating point, may be exceeded by rounding.
pub const INVARIANCE_TOL: f64 = 1e-12;

/// Relative tolerance for recognising an endpoint as the critical value or a fixed point's
/// image ("to rounding").
pub const ROLE_TOL: f64 = 1e-12;

/// Certify f on I = [a, b] (a < b, finite; any other interval gets no certificate, with
/// that reason in [`Certificate::failed`]).
pub fn certify<M: Map1d>(map: &M, a: f64, b: f64, opts: &Options) -> Certificate {
    if !(a.is_finite() && b.is_finite() && a < b) {
        return Certificate {
            interval: (a, b),
            image: Interval::ENTIRE,
            invariant: false,
            critical_points: vec![],
            critical_unresolved: vec![],
            schwarzian: SchwarzianScan::default(),
            fixed_points: vec![],
            fixed_unresolved: vec![],
            endpoints: [EndpointRole::Free; 2],
            failed: vec![format!(
                "the interval [{a}, {b}] is empty or not finite: nothing to certify"
            )],
            verdict: Verdict::Unstable {
                cycle: None,
                unique: false,
            },
        };
    }
    let scale = (b - a).abs().max(f64::MIN_POSITIVE);
    let crit = scan_zeros(
        a,
        b,
        &|x| {
            let j = map.over(x);
            (j.d1, j.d2)
        },
        opts,
    );
    let critical_points: Vec<CriticalPoint> = crit
        .zeros
        .iter()
        .map(|z| CriticalPoint {
            x: z.x,
            maximum: z.slope_sign < 0.0,
            value: map.f(z.x),
            value_bounds: map.over(z.bracket).v,
        })
        .collect();
    let schwarzian = scan_schwarzian(map, a, b, opts);
    let fixed = scan_zeros(
        a,
        b,
        &|x| {
            let j = map.over(x);
            let one = Interval::point(1.0);
            (j.v - x, j.d1 - one)
        },
        opts,
    );
    let fixed_points: Vec<FixedPoint> = fixed
        .zeros
        .iter()
        .map(|z| {
            let mb = map.over(z.bracket).d1;
            let stability = if mb.abs().hi() < 1.0 {
                Stability::Attracting
            } else if mb.abs().lo() > 1.0 {
                Stability::Repelling
            } else {
                Stability::Undetermined
            };
            FixedPoint {
                x: z.x,
                multiplier: map.at(z.x).d1,
                multiplier_bounds: mb,
                stability,
                interior: z.x != a && z.x != b,
            }
        })
        .collect();

    // the image: the hull of the end values and the critical values' enclosures
    let mut image = map
        .over(Interval::point(a))
        .v
        .hull(&map.over(Interval::point(b)).v);
    for c in &critical_points {
        image = image.hull(&c.value_bounds);
    }
    let tol = INVARIANCE_TOL * scale;
    let invariant = crit.unresolved.is_empty() && image.lo() >= a - tol && image.hi() <= b + tol;

    let near = |x: f64, y: f64| (x - y).abs() <= ROLE_TOL * scale;
    let repelling_at = |e: f64| {
        fixed_points
            .iter()
            .any(|p| near(p.x, e) && p.stability == Stability::Repelling)
    };
    let role = |e: f64, other: f64| {
        if repelling_at(e) {
            EndpointRole::RepellingFixedPoint
        } else if critical_points.iter().any(|c| near(c.value, e)) {
            EndpointRole::CriticalValue
        } else if repelling_at(other) && near(map.f(e), other) {
            EndpointRole::MapsToRepellingFixedPoint
        } else {
            EndpointRole::Free
        }
    };
    let endpoints = [role(a, b), role(b, a)];

    let mut failed = Vec::new();
    if !invariant {
        failed.push(if crit.unresolved.is_empty() {
            format!(
                "the interval [{a}, {b}] is not invariant: f maps it into [{}, {}]",
                image.lo(),
                image.hi()
            )
        } else {
            format!(
                "invariance not established: critical points unresolved on {}",
                ranges(&crit.unresolved)
            )
        });
    }
    if !crit.unresolved.is_empty() {
        failed.push(format!(
            "unimodality not established: critical points unresolved on {}",
            ranges(&crit.unresolved)
        ));
    }
    if critical_points.len() > 1 {
        failed.push(format!(
            "not unimodal: {} critical points, at x = {}",
            critical_points.len(),
            critical_points
                .iter()
                .map(|c| format!("{}", c.x))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if !schwarzian.positive.is_empty() {
        let (l, r) = schwarzian.positive[0];
        let m = 0.5 * (l + r);
        failed.push(format!(
            "the Schwarzian is positive on {} (S({m}) = {:e})",
            ranges(&schwarzian.positive),
            self::schwarzian(&map.at(m))
        ));
    }
    if !schwarzian.undetermined.is_empty() {
        failed.push(format!(
            "the Schwarzian's sign is undetermined on {}",
            ranges(&schwarzian.undetermined)
        ));
    }
    let slots = critical_points.len()
        + endpoints
            .iter()
            .filter(|r| **r == EndpointRole::Free)
            .count();
    if slots > 1 {
        let free: Vec<String> = [a, b]
            .iter()
            .zip(endpoints.iter())
            .filter(|(_, r)| **r == EndpointRole::Free)
            .map(|(e, _)| format!("{e}"))
            .collect();
        failed.push(format!(
            "endpoint(s) {} neither a repelling fixed point, the critical value nor mapped onto a repelling fixed point: Singer's theorem allows a second attracting orbit",
            free.join(", ")
        ));
    }
    if !fixed.unresolved.is_empty() {
        failed.push(format!(
            "fixed points unresolved on {}",
            ranges(&fixed.unresolved)
        ));
    }

    let stable = fixed_points
        .iter()
        .find(|p| p.stability == Stability::Attracting);
    let verdict = match stable {
        Some(p) if failed.is_empty() => Verdict::Certified {
            fixed_point: p.x,
            multiplier: p.multiplier,
        },
        Some(p) => Verdict::LocallyStable {
            fixed_point: p.x,
            multiplier: p.multiplier,
        },
        None => {
            let start = critical_points.first().map_or(0.5 * (a + b), |c| c.x);
            Verdict::Unstable {
                cycle: limit_cycle(map, start, a, b, opts),
                unique: failed.is_empty(),
            }
        }
    };
    Certificate {
        interval: (a, b),
        image,
        invariant,
        critical_points,
        critical_unresolved: crit.unresolved,
        schwarzian,
        fixed_points,
        fixed_unresolved: fixed.unresolved,
        endpoints,
        failed,
        verdict,
    }
}

fn ranges(v: &[(f64, f64)]) -> String {
    let shown: Vec<String> = v
        .iter()
        .take(4)
        .map(|(l, r)| format!("[{l}, {r}]"))
        .collect();
    let more = if v.len() > 4 {
        format!(" and {} more", v.len() - 4)
    } else {
        String::new()
    };
    format!("{}{more}", shown.join(", "))
}

/// The attracting cycle the orbit of `x0` settles on within I: `transient` iterations,
/// then the least period p ≤ `max_period` over which it repeats (relative 1e-9), polished
/// by Newton's method on fᵖ(x) − x; `None` if it leaves I, does not settle, or the
/// polished cycle does not attract.
pub fn limit_cycle<M: Map1d>(map: &M, x0: f64, a: f64, b: f64, opts: &Options) -> Option<Cycle> {
    let scale = (b - a).abs();
    let mut x = x0;
    for _ in 0..opts.transient {
        x = map.f(x);
        if !(x.is_finite() && x >= a - scale && x <= b + scale) {
            return None;
        }
    }
    let n = 4 * opts.max_period;
    let mut orbit = Vec::with_capacity(n);
    for _ in 0..n {
        x = map.f(x);
        orbit.push(x);
    }
    let p = (1..=opts.max_period).find(|&p| {
        (n - 2 * p..n).all(|i| (orbit[i] - orbit[i - p]).abs() <= 1e-9 * (1.0 + scale))
    })?;
    let mut x = orbit[n - 1];
    let mut multiplier = f64::NAN;
    for _ in 0..50 {
        let (mut y, mut m) = (x, 1.0);
        for _ in 0..p {
            let j = map.at(y);
            m *= j.d1;
            y = j.v;
        }
        multiplier = m;
        let dx = (y - x) / (m - 1.0);
        if !dx.is_finite() {
            break;
        }
        x -= dx;
        if dx.abs() <= 1e-15 * (1.0 + x.abs()) {
            break;
        }
    }
    let mut points = Vec::with_capacity(p);
    let mut y = x;
    for _ in 0..p {
        points.push(y);
        y = map.f(y);
    }
    let k = (0..p)
        .min_by(|&i, &j| points[i].total_cmp(&points[j]))
        .unwrap_or(0);
    points.rotate_left(k);
    (multiplier.abs() < 1.0).then_some(Cycle {
        period: p,
        points,
        multiplier,
    })
}

/// A finite number, or JSON null (never NaN or ∞ in JSON).
pub fn num(x: f64) -> Value {
    if x.is_finite() {
        json!(x)
    } else {
        Value::Null
    }
}

fn pair(i: &Interval) -> Value {
    json!([num(i.lo()), num(i.hi())])
}

impl Certificate {
    /// The verdict in words.
    pub fn verdict_text(&self) -> String {
        match &self.verdict {
            Verdict::Certified { .. } => {
                "essentially globally asymptotically stable (Singer-Guckenheimer)".into()
            }
            Verdict::LocallyStable { .. } => {
                format!("locally stable, no certificate: {}", self.failed.join("; "))
            }
            Verdict::Unstable { cycle, unique } => {
                let c = match cycle {
                    Some(c) => format!(
                        "the {}attracting cycle has period {}: {} (multiplier {:.6})",
                        if *unique { "unique " } else { "" },
                        c.period,
                        c.points
                            .iter()
                            .map(|p| format!("{p:.9}"))
                            .collect::<Vec<_>>()
                            .join(", "),
                        c.multiplier
                    ),
                    None => format!(
                        "no attracting cycle of period <= {} found from the critical point",
                        Options::default().max_period
                    ),
                };
                if *unique {
                    format!("unstable; {c}")
                } else {
                    format!("unstable; {c}; no certificate: {}", self.failed.join("; "))
                }
            }
        }
    }

    /// The certificate as JSON (keys in docs/stability.md).
    pub fn json(&self) -> Value {
        let cycle = match &self.verdict {
            Verdict::Unstable { cycle: Some(c), .. } => json!({
                "period": c.period,
                "points": c.points.iter().map(|p| num(*p)).collect::<Vec<_>>(),
                "multiplier": num(c.multiplier),
            }),
            _ => Value::Null,
        };
        let sign = if self.schwarzian.negative() {
            "negative"
        } else if !self.schwarzian.positive.is_empty() {
            "positive somewhere"
        } else {
            "undetermined"
        };
        let rs = |v: &[(f64, f64)]| {
            v.iter()
                .map(|(l, r)| json!([num(*l), num(*r)]))
                .collect::<Vec<_>>()
        };
        json!({
            "invariant_interval": [num(self.interval.0), num(self.interval.1)],
            "image": pair(&self.image),
            "invariant": self.invariant,
            "critical_points": self.critical_points.iter().map(|c| json!({
                "x": num(c.x),
                "kind": if c.maximum { "maximum" } else { "minimum" },
                "value": num(c.value),
            })).collect::<Vec<_>>(),
            "critical_unresolved": rs(&self.critical_unresolved),
            "unimodal": self.critical_points.len() <= 1 && self.critical_unresolved.is_empty(),
            "schwarzian_sign": sign,
            "schwarzian_interval_arithmetic": {
                "cells": self.schwarzian.cells,
                "positive_on": rs(&self.schwarzian.positive),
                "undetermined_on": rs(&self.schwarzian.undetermined),
            },
            "fixed_points": self.fixed_points.iter().map(|p| json!({
                "x": num(p.x),
                "multiplier": num(p.multiplier),
                "multiplier_bounds": pair(&p.multiplier_bounds),
                "stability": p.stability.name(),
                "interior": p.interior,
            })).collect::<Vec<_>>(),
            "fixed_unresolved": rs(&self.fixed_unresolved),
            "endpoints": [
                {"x": num(self.interval.0), "role": self.endpoints[0].name()},
                {"x": num(self.interval.1), "role": self.endpoints[1].name()},
            ],
            "failed_conditions": self.failed,
            "attracting_cycle": cycle,
            "verdict_code": self.verdict.code(),
            "verdict": self.verdict_text(),
        })
    }

    /// The certificate as indented report lines.
    pub fn text(&self) -> String {
        let (a, b) = self.interval;
        let mut s = format!(
            "  invariant interval [{a:.9}, {b:.9}]: f maps it into [{:.9}, {:.9}] ({})\n",
            self.image.lo(),
            self.image.hi(),
            if self.invariant {
                "invariant"
            } else {
                "NOT invariant"
            }
        );
        s += &format!(
            "  critical points: {}\n",
            if self.critical_points.is_empty() {
                "none (monotone)".to_string()
            } else {
                self.critical_points
                    .iter()
                    .map(|c| {
                        format!(
                            "{} at {:.9} (value {:.9})",
                            if c.maximum { "maximum" } else { "minimum" },
                            c.x,
                            c.value
                        )
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            }
        );
        s += &format!(
            "  Schwarzian by interval arithmetic on 2f'f''' - 3f''^2 over {} cells: {}\n",
            self.schwarzian.cells,
            if self.schwarzian.negative() {
                "negative on the whole interval".to_string()
            } else if !self.schwarzian.positive.is_empty() {
                format!("POSITIVE on {}", ranges(&self.schwarzian.positive))
            } else {
                format!("undetermined on {}", ranges(&self.schwarzian.undetermined))
            }
        );
        for p in &self.fixed_points {
            s += &format!(
                "  fixed point {:.12}: multiplier {:.12} in [{:.12}, {:.12}], {}\n",
                p.x,
                p.multiplier,
                p.multiplier_bounds.lo(),
                p.multiplier_bounds.hi(),
                p.stability.name()
            );
        }
        s += &format!(
            "  endpoints: {a:.9} {}, {b:.9} {}\n",
            self.endpoints[0].name(),
            self.endpoints[1].name()
        );
        s += &format!("  certificate: {}\n", self.verdict_text());
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The logistic map r x (1 − x): S = −6/(1 − 2x)² < 0 (a polynomial whose derivative
    /// has a real root, Singer's criterion).
    struct Logistic(f64);
    impl Map1d for Logistic {
        fn jet<T: Scalar>(&self, x: Jet<T>) -> Jet<T> {
            (x * (Jet::cst(1.0) - x)).scale(self.0)
        }
    }

    #[test]
    fn logistic_below_three_is_certified_at_one_minus_one_over_r() {
        let c = certify(&Logistic(2.8), 0.0, 1.0, &Options::default());
        match c.verdict {
            Verdict::Certified {
                fixed_point,
                multiplier,
            } => {
                assert!((fixed_point - (1.0 - 1.0 / 2.8)).abs() < 1e-14);
                assert!((multiplier - (2.0 - 2.8)).abs() < 1e-13);
            }
            v => panic!("{v:?} {:?}", c.failed),
        }
        assert_eq!(c.critical_points.len(), 1);
        assert!((c.critical_points[0].x - 0.5).abs() < 1e-15);
        assert_eq!(
            c.endpoints,
            [
                EndpointRole::RepellingFixedPoint,
                EndpointRole::MapsToRepellingFixedPoint
            ]
        );
    }

    #[test]
    fn an_empty_or_infinite_interval_gets_no_certificate() {
        for (a, b) in [(1.0, 1.0), (0.0, f64::INFINITY), (f64::NAN, 1.0)] {
            let c = certify(&Logistic(2.8), a, b, &Options::default());
            assert_eq!(c.verdict.code(), "unstable");
            assert!(c.failed[0].contains("nothing to certify"));
            assert!(c.json()["invariant_interval"][1].is_null() || b.is_finite());
        }
    }

    #[test]
    fn logistic_at_3_2_names_its_two_cycle() {
        // the 2-cycle of r x (1 − x): x = (r + 1 ± sqrt((r − 3)(r + 1))) / (2 r)
        let r: f64 = 3.2;
        let c = certify(&Logistic(r), 0.0, 1.0, &Options::default());
        let Verdict::Unstable {
            cycle: Some(cy),
            unique: true,
        } = &c.verdict
        else {
            panic!("{:?}", c.verdict)
        };
        let d = ((r - 3.0) * (r + 1.0)).sqrt();
        assert_eq!(cy.period, 2);
        assert!((cy.points[0] - (r + 1.0 - d) / (2.0 * r)).abs() < 1e-12);
        assert!((cy.points[1] - (r + 1.0 + d) / (2.0 * r)).abs() < 1e-12);
        // its multiplier: 4 + 2r − r² (the standard closed form)
        assert!((cy.multiplier - (4.0 + 2.0 * r - r * r)).abs() < 1e-10);
    }
}
