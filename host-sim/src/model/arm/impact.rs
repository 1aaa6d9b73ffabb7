//! One-sided plastic impacts of the object on the arm's surface: an edge landing at the
//! end of a roll (or falling back at its start), and a flying object caught on an edge.
//!
//! Everything is per unit object mass and in the arm frame, relative to the arm: the arm's
//! motion is prescribed (its inertia and motor dwarf a 0.1 kg object), so an impulse
//! changes only the object's twist, and the object's twist less the arm's rigid twist is
//! again a rigid twist `(v, omega)` (velocity of the centre of mass `r`, rate). Impulses
//! `Pi` (N s/kg = m/s) act at points of the landing edge and may only push (`Pi . n >= 0`
//! at every point): they never pull.
//!
//! **Stop outright** (the paper's no-rebound assumption): the object takes the arm's
//! motion, `Pi = -v`, with angular impulse `rho^2 (0 - omega) = (c - r) x Pi` about the
//! centre of mass. Its resultant acts at `c = O + sigma t` on the surface line (`t x Pi =
//! Pi_n`):
//!
//! ```text
//! sigma_c = ((r - O) x Pi - rho^2 omega) / Pi_n
//! ```
//!
//! A set of pushing impulses along the edge has its resultant on the edge, so the stop is
//! feasible only if `sigma_c` lies on the edge; otherwise it needs a pull at the far end.
//!
//! **Rock onto the striking vertex** (when the stop's centre of pressure falls off the
//! edge beyond vertex `w`): the whole impulse acts at `w`, plastic and sticking there, so
//! the angular momentum about `w` is conserved and the object turns about `w` after:
//! `v+ = omega+ J (r - w)`, and from `rho^2 omega + (r - w) x v` before and after,
//!
//! ```text
//! omega+ = (rho^2 omega + (r - w) x v) / (rho^2 + |r - w|^2),     Pi = v+ - v
//! ```
//!
//! For the roll's end, `v = omega J (r - P)` about the old pivot `P`, and since
//! `a x J b = a . b`, `omega+ / omega = (rho^2 + (r - w) . (r - P)) / (rho^2 + |r - w|^2)`.
//! With `s` the centre of mass's coordinate from `P` toward `w` and `h` its height, the
//! stop needs `|sigma_c - sigma_P| = s + (h^2 + rho^2) / s`, which is at most the edge
//! length `L` exactly when that ratio is <= 0: the two outcomes never overlap. A square
//! of side a (`s = h = a/2`) can never be stopped outright (`a + 2 rho^2 / a > a`): it
//! rocks onto the striking vertex at `omega+ = omega rho^2 / (rho^2 + a^2/2)` (2/5 of
//! omega for a thin frame, `rho^2 = a^2/3`), and the old pivot lifts off at
//! `omega+ L`. A rock that falls back strikes again, each time slower, and settles.
//!
//! **Friction.** The impulse must lie in its Coulomb cone, `|Pi_t| <= mu Pi_n`, or the
//! contact slips during the impact (not modelled: the run fails saying so).

use super::contact::{Pivot, Placement, Rig};
use super::geometry::V2;
use serde::Serialize;

/// Speed below which a rock's lifting vertex counts as at rest, m/s: the impact then
/// settles the object on the edge (the rocks shrink geometrically; this ends the series).
pub const SETTLE_SPEED_MPS: f64 = 1e-3;

/// What a one-sided impact of an edge did to the object.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Stopped outright on the edge (the stop's centre of pressure on the edge, or a rock
    /// too slow to count): a dynamic grasp on the edge if the grasp's conditions hold.
    Grasp,
    /// Rocking onto vertex `vertex`: a roll over it starts from the edge at rate
    /// `rate_radps` relative to the arm (counterclockwise positive).
    Rock {
        /// The striking vertex, now the pivot.
        vertex: usize,
        /// +1: the rock turns counterclockwise, -1 clockwise.
        dir: f64,
        /// Rate after the impact, rad/s.
        rate_radps: f64,
    },
}

/// A one-sided plastic impact of an edge on the surface, and the impulse it took.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct EdgeImpact {
    /// What followed.
    pub outcome: Outcome,
    /// Impulse per unit mass along the surface normal, m/s (>= 0: it pushes).
    pub impulse_normal_mps: f64,
    /// Impulse per unit mass along the surface tangent, m/s.
    pub impulse_tangential_mps: f64,
    /// Where the executed impulse's resultant acts, from the edge's vertex k, m (in [0, L]).
    pub cop_m: f64,
    /// Where a stop outright would need it, from vertex k, m (off the edge: it would pull).
    pub stop_cop_m: f64,
    /// Edge length L, m.
    pub edge_length_m: f64,
    /// Normal speed of the fastest-approaching end of the edge before, m/s (>= 0).
    pub speed_mps: f64,
    /// Relative rate before, rad/s.
    pub rate_before_radps: f64,
    /// Relative rate after (0 when grasped), rad/s.
    pub rate_after_radps: f64,
}

impl EdgeImpact {
    /// |Pi_t| / Pi_n, the friction the impulse needs (infinite if it does not push).
    pub fn friction_ratio(&self) -> f64 {
        if self.impulse_normal_mps > 0.0 {
            self.impulse_tangential_mps.abs() / self.impulse_normal_mps
        } else {
            f64::INFINITY
        }
    }

    /// Inside the Coulomb cone of `mu` (and pushing).
    pub fn in_cone(&self, mu: f64) -> bool {
        self.impulse_normal_mps > 0.0
            && self.impulse_tangential_mps.abs() <= mu * self.impulse_normal_mps
    }

    /// The impact at friction `mu`: `Err` if its impulse leaves the friction cone (the
    /// contact slips during the impact; the verifier fails the run there). An impact
    /// slower than [`SETTLE_SPEED_MPS`] is a touch-down whose impulse is negligible: it is
    /// not judged.
    pub fn judged(self, mu: f64) -> Result<Self, Self> {
        if self.speed_mps < SETTLE_SPEED_MPS || self.in_cone(mu) {
            Ok(self)
        } else {
            Err(self)
        }
    }

    /// Distance of the executed impulse's centre of pressure from the nearer end of the
    /// edge, m (negative: off the edge).
    pub fn cop_margin_m(&self) -> f64 {
        self.cop_m.min(self.edge_length_m - self.cop_m)
    }
}

impl Rig {
    /// The one-sided impact of edge `p` (now flat on the surface) struck by the object with
    /// relative twist `v` (centre of mass, arm frame, m/s) and `omega` (rad/s) (module
    /// docs).
    pub fn edge_impact(&self, p: &Placement, v: V2, omega: f64) -> EdgeImpact {
        let s = &self.surface;
        let (t, n) = (s.tangent(), s.normal());
        let r = self.com_arm(p);
        let l = self.body.edge_length_m(p.edge);
        let rho2 = self.body.rho_m * self.body.rho_m;
        let ends = [s.point(p.sigma_m), s.point(p.sigma_m + l)];
        // normal velocity of an edge end: v + omega J (e - r), along n
        let vn = |e: V2| v.plus(e.minus(r).perp().scale(omega)).dot(n);
        let speed_mps = (-vn(ends[0])).max(-vn(ends[1])).max(0.0);
        let stop = v.scale(-1.0);
        let stop_sigma = (r.minus(s.origin).cross(stop) - rho2 * omega) / stop.dot(n);
        let stop_cop_m = stop_sigma - p.sigma_m;
        let axes = |pi: V2| (pi.dot(n), pi.dot(t));
        if (0.0..=l).contains(&stop_cop_m) {
            let (pn, pt) = axes(stop);
            return EdgeImpact {
                outcome: Outcome::Grasp,
                impulse_normal_mps: pn,
                impulse_tangential_mps: pt,
                cop_m: stop_cop_m,
                stop_cop_m,
                edge_length_m: l,
                speed_mps,
                rate_before_radps: omega,
                rate_after_radps: 0.0,
            };
        }
        // the resultant would fall beyond the end nearer to it: rock onto that vertex
        let far = stop_cop_m > l;
        let (vertex, w, cop_m, dir) = if far {
            ((p.edge + 1) % self.body.len(), ends[1], l, -1.0)
        } else {
            (p.edge, ends[0], 0.0, 1.0)
        };
        let rw = r.minus(w);
        let after = (rho2 * omega + rw.cross(v)) / (rho2 + rw.norm2());
        let (pn, pt) = axes(rw.perp().scale(after).minus(v));
        let lift = after.abs() * l;
        let outcome = if lift < SETTLE_SPEED_MPS || after * dir <= 0.0 {
            Outcome::Grasp
        } else {
            Outcome::Rock {
                vertex,
                dir,
                rate_radps: after,
            }
        };
        EdgeImpact {
            outcome,
            impulse_normal_mps: pn,
            impulse_tangential_mps: pt,
            cop_m,
            stop_cop_m,
            edge_length_m: l,
            speed_mps,
            rate_before_radps: omega,
            rate_after_radps: if outcome == Outcome::Grasp {
                0.0
            } else {
                after
            },
        }
    }

    /// The impact that ends a roll over `pv` at relative rate `psi_dot`, onto edge `p`
    /// (the landed edge at `|psi| = gamma`, or the old edge falling back at `psi = 0`).
    pub fn roll_impact(&self, pv: &Pivot, p: &Placement, psi_dot_radps: f64) -> EdgeImpact {
        let pivot = self.surface.point(pv.sigma_m);
        let v = self.com_arm(p).minus(pivot).perp().scale(psi_dot_radps);
        self.edge_impact(p, v, psi_dot_radps)
    }
}
