//! Impact of the planar body with a much heavier translating table: frictionless (eq. 1, 5,
//! 21 from the core) and Coulomb friction (eq. 27) with sliding, sticking and slip reversal.
//!
//! # Planar rigid-body impulse with friction (derived here)
//!
//! Per unit mass, with the contact point at r = (l sin theta, -l cos theta) from the centre
//! of mass, table normal n = (-sin alpha, cos alpha) and tangent t = (cos alpha, sin alpha),
//! an impulse P = P_n n + P_t t changes the velocity by P and the angular velocity by
//! `(r x P) / rho^2`, where `r x n = l sin beta` and `r x t = l cos beta` (beta = theta - alpha;
//! the moment is eq. 27, `M = P_n l sin beta + P_t l cos beta`). The contact-point velocity
//! relative to the table, u = (u_n, u_t) (eq. 23 minus the table velocity), then changes
//! linearly with the impulse, `u+ = u- + K P`, with the (symmetric, positive definite)
//! inverse effective mass
//!
//! ```text
//! K = [ 1 + a^2/rho^2    a b/rho^2   ]     a = l sin beta,  b = l cos beta
//!     [ a b/rho^2      1 + b^2/rho^2 ]
//! ```
//!
//! (a point mass has K = I). Routh's method follows P along the normal impulse P_n:
//! while sliding with sign s = sgn(u_t), `dP_t = -mu s dP_n` (eq. 27's
//! `P_t = mu P_n sgn(-v_tc)`); when u_t reaches 0 the contact sticks if `|K_tn| <= mu K_tt`
//! (then `dP_t = -K_tn/K_tt dP_n` keeps u_t = 0, inside the friction cone), else slip reverses
//! to s = sgn(K_tn). Compression ends where u_n = 0, at P_n = P_c; restitution follows
//! Poisson's hypothesis, ending at P_n = (1 + e) P_c. With mu = 0 this is exactly eq. 21
//! (`u_n+ = -e u_n-`, tested against the core's [`dexter_core::tilt::impact`]); with e <= 1 and
//! a resting table it never creates energy (tested). If sliding drives u_n away from zero
//! during compression (`K_nn - mu s K_nt <= 0`, Painlevé's jam) the impact is reported as
//! [`ImpactError::Jam`]. At most [`MAX_SEGMENTS`] piecewise-linear segments are followed.

use dexter_core::tilt::{impact, impact_normal};

/// Most piecewise-linear segments of one frictional impact (slide, stick or reverse, then
/// the same in restitution: 6 is the most the case analysis allows).
pub const MAX_SEGMENTS: usize = 8;

/// The tangential regime of a frictional impact at its end.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionMode {
    /// No friction (mu = 0) or no tangential motion: eq. 21.
    Frictionless,
    /// The contact slid throughout: |P_t| = mu P_n.
    Sliding,
    /// Sliding stopped and the contact stuck (u_t+ = 0).
    Sticking,
    /// Slip reversed direction during the impact.
    Reversed,
}

/// Why an impact could not be computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImpactError {
    /// Painlevé jam: sliding friction drives the normal velocity away from zero.
    Jam,
    /// The segment cap [`MAX_SEGMENTS`] was hit.
    Cap,
}

/// The body's geometry for an impact: rho (m) and l (m); rho = l = 0 is a point mass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpactGeometry {
    /// Radius of gyration rho, m.
    pub rho_m: f64,
    /// Contact distance l, m.
    pub l_m: f64,
}

/// Result of one impact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImpactResult {
    /// Velocity after: (x', y', theta'), m/s, m/s, rad/s.
    pub velocity: [f64; 3],
    /// Normal impulse per unit mass P_n, m/s.
    pub normal_impulse_mps: f64,
    /// Tangential impulse per unit mass P_t, m/s (along (cos alpha, sin alpha)).
    pub tangential_impulse_mps: f64,
    /// The tangential regime.
    pub mode: FrictionMode,
}

/// Frictionless impact, eq. 21 via the core (eq. 2 normal): `(x', y', theta')` after, for
/// the body at angle `theta_rad` hitting a table at `alpha_rad` moving with
/// `table_velocity_mps` (m/s), restitution `e`.
pub fn frictionless(
    geo: ImpactGeometry,
    theta_rad: f64,
    velocity: [f64; 3],
    alpha_rad: f64,
    table_velocity_mps: [f64; 2],
    e: f64,
) -> ImpactResult {
    let n = impact_normal(alpha_rad, theta_rad, geo.l_m, geo.rho_m);
    let v = [velocity[0], velocity[1], geo.rho_m * velocity[2]];
    let out = impact(v, table_velocity_mps, n, e);
    let w = if geo.rho_m > 0.0 {
        out[2] / geo.rho_m
    } else {
        velocity[2]
    };
    // normal impulse: the change of the table-normal velocity of the centre of mass
    let (sa, ca) = alpha_rad.sin_cos();
    let pn = -sa * (out[0] - v[0]) + ca * (out[1] - v[1]);
    ImpactResult {
        velocity: [out[0], out[1], w],
        normal_impulse_mps: pn,
        tangential_impulse_mps: 0.0,
        mode: FrictionMode::Frictionless,
    }
}

/// Impact with Coulomb friction `mu` (>= 0) and Poisson restitution `e` in [0, 1], by
/// Routh's method (module docs). Arguments as [`frictionless`]. The caller decides that the
/// contact is closing (u_n < 0); a non-closing contact gets no impulse.
pub fn coulomb(
    geo: ImpactGeometry,
    theta_rad: f64,
    velocity: [f64; 3],
    alpha_rad: f64,
    table_velocity_mps: [f64; 2],
    e: f64,
    mu: f64,
) -> Result<ImpactResult, ImpactError> {
    let (sa, ca) = alpha_rad.sin_cos();
    let nt = [-sa, ca];
    let tt = [ca, sa];
    let (st, ct) = theta_rad.sin_cos();
    let w = velocity[2];
    // contact-point velocity (eq. 23) relative to the table
    let uc = [
        velocity[0] + geo.l_m * w * ct - table_velocity_mps[0],
        velocity[1] + geo.l_m * w * st - table_velocity_mps[1],
    ];
    let un = nt[0] * uc[0] + nt[1] * uc[1];
    let ut = tt[0] * uc[0] + tt[1] * uc[1];
    let beta = theta_rad - alpha_rad;
    let (a, b) = (geo.l_m * beta.sin(), geo.l_m * beta.cos());
    let k = if geo.rho_m > 0.0 {
        let r2 = geo.rho_m * geo.rho_m;
        [1.0 + a * a / r2, a * b / r2, 1.0 + b * b / r2]
    } else {
        [1.0, 0.0, 1.0]
    };
    let (pn, pt, mode) = if un < 0.0 {
        let mut sweep = Routh::start(k, mu, un, ut);
        sweep.run(e)?;
        (sweep.pn, sweep.pt, sweep.mode())
    } else {
        (0.0, 0.0, FrictionMode::Frictionless)
    };
    let p = [pn * nt[0] + pt * tt[0], pn * nt[1] + pt * tt[1]];
    let dw = if geo.rho_m > 0.0 {
        (pn * a + pt * b) / (geo.rho_m * geo.rho_m)
    } else {
        0.0
    };
    Ok(ImpactResult {
        velocity: [velocity[0] + p[0], velocity[1] + p[1], w + dw],
        normal_impulse_mps: pn,
        tangential_impulse_mps: pt,
        mode,
    })
}

/// Routh's sweep along the normal impulse P_n (module docs): the contact-point velocity
/// (u_n, u_t) moves linearly in P_n within a segment of one tangential regime, with the
/// inverse-mass entries `k = [k_nn, k_nt, k_tt]`.
struct Routh {
    knn: f64,
    knt: f64,
    ktt: f64,
    mu: f64,
    /// Sticking can hold: mu k_tt >= |k_nt|.
    stick_ok: bool,
    /// The tangential regime: `Some(s)` sliding with sign s, `None` sticking.
    slide: Option<f64>,
    reversed: bool,
    stuck: bool,
    compression: bool,
    /// P_n at the end of restitution (Poisson), once compression has ended.
    pn_end: f64,
    pn: f64,
    pt: f64,
    un: f64,
    ut: f64,
}

impl Routh {
    fn start(k: [f64; 3], mu: f64, un: f64, ut: f64) -> Self {
        let [knn, knt, ktt] = k;
        let stick_ok = mu * ktt >= knt.abs();
        let slide = if ut != 0.0 {
            Some(ut.signum())
        } else if stick_ok {
            None
        } else {
            Some(knt.signum())
        };
        Routh {
            knn,
            knt,
            ktt,
            mu,
            stick_ok,
            slide,
            reversed: false,
            stuck: slide.is_none() && mu > 0.0,
            compression: true,
            pn_end: f64::INFINITY,
            pn: 0.0,
            pt: 0.0,
            un,
            ut,
        }
    }

    /// Segments until restitution ends, at most `MAX_SEGMENTS`.
    fn run(&mut self, e: f64) -> Result<(), ImpactError> {
        for _ in 0..MAX_SEGMENTS {
            if self.segment(e)? {
                return Ok(());
            }
        }
        Err(ImpactError::Cap)
    }

    /// One segment: to the first of the end of compression, the end of restitution, or the
    /// tangential velocity reaching zero. True when the impact is over.
    fn segment(&mut self, e: f64) -> Result<bool, ImpactError> {
        let q = match self.slide {
            Some(s) => -self.mu * s,
            None => -self.knt / self.ktt,
        };
        let dun = self.knn + self.knt * q;
        let dut = self.knt + self.ktt * q;
        if self.compression && dun <= 0.0 {
            return Err(ImpactError::Jam);
        }
        // candidate step lengths in P_n
        let (to_c, to_end) = if self.compression {
            (-self.un / dun, f64::INFINITY)
        } else {
            (f64::INFINITY, self.pn_end - self.pn)
        };
        let to_stick = match self.slide {
            Some(s) if self.mu > 0.0 && dut * s < 0.0 => -self.ut / dut,
            _ => f64::INFINITY,
        };
        let step = to_c.min(to_end).min(to_stick).max(0.0);
        self.pn += step;
        self.pt += q * step;
        self.un += dun * step;
        self.ut += dut * step;
        if step == to_stick && to_stick <= to_c.min(to_end) {
            self.ut = 0.0;
            if self.stick_ok {
                self.slide = None;
                self.stuck = true;
            } else {
                self.slide = Some(self.knt.signum());
                self.reversed = true;
            }
            return Ok(false);
        }
        if self.compression {
            self.un = 0.0;
            self.compression = false;
            self.pn_end = (1.0 + e) * self.pn;
            return Ok(e == 0.0);
        }
        Ok(true)
    }

    /// The regime the impact ended in.
    fn mode(&self) -> FrictionMode {
        if self.mu == 0.0 || (self.pt == 0.0 && !self.stuck) {
            FrictionMode::Frictionless
        } else if self.reversed {
            FrictionMode::Reversed
        } else if self.stuck {
            FrictionMode::Sticking
        } else {
            FrictionMode::Sliding
        }
    }
}
