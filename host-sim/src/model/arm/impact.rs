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
//! **Vertex first** (a flying object caught with edge `e` tilted by `psi != 0` from flat:
//! the lower end `w` of `e` touches alone, [`Rig::vertex_impact`]): the same impulse at
//! `w`, plastic and sticking, evaluated in the tilted pose, `r - w = -R(alpha_0 + psi) b_w`
//! (`b_w` the vertex in the body frame). The object then turns about `w` at `omega+` from
//! `psi`, as a roll over `w` off `e` (the pivot of [`Rig::pivot`] in the direction
//! `sign(psi)`, the side `e` is tilted to). A solid square (`rho^2 = a^2/6`) tilted by
//! `0 < psi < pi/4` and dropped without rotation at `u` along the surface's normal onto
//! its corner has `(r - w) x v = -u (a/2) (cos psi - sin psi)`, so `omega+ = -(3 u / 4 a)
//! (cos psi - sin psi)`: it turns back toward flat, and the edge comes down on the
//! surface as a roll's fall back. The verifier uses this law for a catch tilted beyond
//! `simulate::phases::FLAT_TOL_RAD`, and the whole edge's impact below it.
//!
//! **Friction.** The impulse must lie in its Coulomb cone, `|Pi_t| <= mu Pi_n`, or the
//! contact slips during the impact (not modelled: the run fails saying so).

use super::contact::{Pivot, Placement, Rig};
use super::geometry::V2;
use serde::{Deserialize, Serialize};

/// Speed below which a rock's lifting vertex counts as at rest, m/s: the impact then
/// settles the object on the edge (the rocks shrink geometrically; this ends the series).
pub const SETTLE_SPEED_MPS: f64 = 1e-3;

/// Which impact law the verifier applies (`object.impact_law`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ImpactLaw {
    /// `"one_sided"`: impulses only push; a stop they cannot make rocks the object onto
    /// the striking vertex (module docs).
    #[default]
    OneSided,
    /// `"no_rebound"`: the paper's assumption, every impact stops the object outright on
    /// the struck edge, with a pull where pushing cannot do it; each such impact is
    /// flagged (`pulls` in the JSON, `pulling_impacts` in the summary).
    NoRebound,
}

/// What a one-sided impact of an edge did to the object.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Stopped outright on the edge (the stop's centre of pressure on the edge, or a rock
    /// too slow to count): a dynamic grasp on the edge if the grasp's conditions hold.
    Grasp,
    /// Rocking onto vertex `vertex`: a roll over it starts from the edge at rate
    /// `rate_radps` relative to the arm (counterclockwise positive).
    ///
    /// A vertex-first strike ([`Rig::vertex_impact`]) is a rock too, from `psi_rad` (the
    /// tilt it struck at) rather than from the edge lying flat.
    Rock {
        /// The striking vertex, now the pivot.
        vertex: usize,
        /// +1: the rock turns counterclockwise, -1 clockwise (for a vertex-first strike:
        /// the side the edge is tilted to, the roll's `Pivot::dir`; it may turn back
        /// toward flat at once, `rate_radps` of the other sign).
        dir: f64,
        /// Rate after the impact, rad/s.
        rate_radps: f64,
        /// Roll angle the rock starts from, rad: 0 after an edge's impact, the tilt from
        /// flat after a vertex-first strike (`dir psi_rad > 0`).
        psi_rad: f64,
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
    /// A stop outright's impulse per unit mass along the normal and the tangent, m/s
    /// (`Pi = -v`: what the paper's no-rebound law applies).
    pub stop_impulse_mps: (f64, f64),
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

    /// The same impact under the paper's no-rebound law ([`ImpactLaw::NoRebound`]): the
    /// object stopped outright on the edge, whatever the impulse had to do; its centre of
    /// pressure off the edge ([`pulls`](Self::pulls)) is a pull.
    pub fn stopped_outright(self) -> Self {
        let (pn, pt) = self.stop_impulse_mps;
        Self {
            outcome: Outcome::Grasp,
            impulse_normal_mps: pn,
            impulse_tangential_mps: pt,
            cop_m: self.stop_cop_m,
            rate_after_radps: 0.0,
            ..self
        }
    }

    /// Whether the impulse's resultant lies off the edge: impulses that only push cannot
    /// put it there, so it needed a pull (only under [`ImpactLaw::NoRebound`]).
    pub fn pulls(&self) -> bool {
        !(0.0..=self.edge_length_m).contains(&self.cop_m)
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
                stop_impulse_mps: (pn, pt),
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
        let (after, pi) = about_vertex(rho2, r.minus(w), v, omega);
        let (pn, pt) = axes(pi);
        let lift = after.abs() * l;
        let outcome = if lift < SETTLE_SPEED_MPS || after * dir <= 0.0 {
            Outcome::Grasp
        } else {
            Outcome::Rock {
                vertex,
                dir,
                rate_radps: after,
                psi_rad: 0.0,
            }
        };
        EdgeImpact {
            outcome,
            impulse_normal_mps: pn,
            impulse_tangential_mps: pt,
            cop_m,
            stop_cop_m,
            stop_impulse_mps: axes(stop),
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

    /// Edge `edge` tilted by `psi_rad` from flat (the object at arm-frame angle
    /// `alpha_rad(edge) + psi_rad`), its centre of mass at `com_arm`: the placement of
    /// that edge were it turned flat about its lower end (vertex `edge` if `psi_rad >= 0`,
    /// else `edge + 1`), and the pivot over that end, so that the roll's pose at
    /// `psi = psi_rad` ([`Rig::rolling_state`]) is this one, with the lower end at its
    /// foot on the surface.
    pub fn tilted(&self, edge: usize, psi_rad: f64, com_arm: V2) -> (Placement, Pivot) {
        let dir = if psi_rad >= 0.0 { 1.0 } else { -1.0 };
        let low = if dir > 0.0 {
            edge
        } else {
            (edge + 1) % self.body.len()
        };
        let w = com_arm.plus(self.body.vertex(low).rotate(self.alpha_rad(edge) + psi_rad));
        let sigma_w = self.surface.sigma_m(w);
        let p = Placement {
            edge,
            sigma_m: if dir > 0.0 {
                sigma_w
            } else {
                sigma_w - self.body.edge_length_m(edge)
            },
        };
        (p, self.pivot(&p, dir))
    }

    /// The one-sided impact of the object striking with a vertex first (module docs):
    /// edge `p` tilted by `psi_rad` (`pv.dir psi_rad > 0`) with its lower end, the pivot
    /// `pv` ([`Rig::tilted`]), on the surface, the object's relative twist `v` (centre of
    /// mass, arm frame, m/s) and `omega` (rad/s). The impulse acts at that vertex alone;
    /// the outcome is always a [`Outcome::Rock`] from `psi_rad` (the roll it starts falls
    /// back onto `p`, tips on, or leaves). `cop_m` is the vertex (0 or L along `p`);
    /// `stop_cop_m` is where on the surface line, from `p`'s first vertex, a stop outright
    /// would need its resultant (at the vertex alone only by chance).
    pub fn vertex_impact(
        &self,
        pv: &Pivot,
        p: &Placement,
        psi_rad: f64,
        v: V2,
        omega: f64,
    ) -> EdgeImpact {
        let s = &self.surface;
        let (t, n) = (s.tangent(), s.normal());
        let w = s.point(pv.sigma_m);
        let r = w.plus(self.pivot_to_com_arm(pv, psi_rad));
        let l = self.body.edge_length_m(p.edge);
        let rho2 = self.body.rho_m * self.body.rho_m;
        let speed_mps = (-v.plus(w.minus(r).perp().scale(omega)).dot(n)).max(0.0);
        let stop = v.scale(-1.0);
        let stop_sigma = (r.minus(s.origin).cross(stop) - rho2 * omega) / stop.dot(n);
        let (after, pi) = about_vertex(rho2, r.minus(w), v, omega);
        EdgeImpact {
            outcome: Outcome::Rock {
                vertex: pv.vertex,
                dir: pv.dir,
                rate_radps: after,
                psi_rad,
            },
            impulse_normal_mps: pi.dot(n),
            impulse_tangential_mps: pi.dot(t),
            cop_m: pv.sigma_m - p.sigma_m,
            stop_cop_m: stop_sigma - p.sigma_m,
            stop_impulse_mps: (stop.dot(n), stop.dot(t)),
            edge_length_m: l,
            speed_mps,
            rate_before_radps: omega,
            rate_after_radps: after,
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

/// The plastic, sticking impulse at vertex `w` (`rw = r - w`) on an object of twist
/// `(v, omega)`: angular momentum about `w` conserved, `omega+ = (rho^2 omega + (r - w) x
/// v) / (rho^2 + |r - w|^2)`, then `v+ = omega+ J (r - w)`; the rate after and `Pi = v+ - v`.
fn about_vertex(rho2: f64, rw: V2, v: V2, omega: f64) -> (f64, V2) {
    let after = (rho2 * omega + rw.cross(v)) / (rho2 + rw.norm2());
    (after, rw.perp().scale(after).minus(v))
}
