//! Contact forces and phase conditions of a polygon on a one-joint arm (Akella, Huang,
//! Lynch & Mason, sec. 2: dynamic grasp, roll, free flight; the roll's end).
//!
//! The paper states these phases and their constraints (sec. 2.2) in words; the equations
//! below are derived here from Newton-Euler for a rigid body of mass m and radius of
//! gyration rho under gravity g, touched by the arm. Everything is per unit object mass
//! (forces in N/kg = m/s^2); `J v = (-v_y, v_x)`, `a x b = a_x b_y - a_y b_x`.
//!
//! **Arm points.** A point fixed at arm-frame position `p` is at `R(theta) p` and has
//! acceleration `a_p = theta'' J R p - theta'^2 R p`.
//!
//! **Dynamic grasp** (edge `k` flat on the surface, the object fixed to the arm). The
//! centre of mass moves with the arm: `a = a_p(r)`, `phi'' = theta''`. The arm's contact
//! force is `f = a + g y^`. With surface tangent `t` and normal `n` (world), write
//! `f_n = f . n`, `f_t = f . t`. The force is spread along the edge; its resultant acts at
//! the centre of pressure `c = p_k + s t`, where the moment about the centre of mass must
//! equal `rho^2 phi''`: `(c - r) x f = rho^2 theta''`, and since `t x f = f_n`,
//!
//! ```text
//! s = (rho^2 theta'' - (p_k - r) x f) / f_n
//! ```
//!
//! The grasp holds iff `f_n > 0` (unilateral), `|f_t| <= mu f_n` (Coulomb) and
//! `0 <= s <= L_k` (the centre of pressure on the edge; otherwise the object starts to
//! roll over vertex `k` (s < 0) or `k + 1` (s > L_k)). Hand checks: a horizontal surface
//! accelerating straight up at `a` needs `f_n = g + a` and `f_t = 0`; a surface tilted by
//! `b` at rest needs `mu >= tan b`.
//!
//! **Roll** about vertex `v` held at a fixed surface point `P` (no slip, no separation).
//! One freedom, the object's angle relative to the arm `psi`; `phi = theta + alpha_0 +
//! psi`. With `d = r - P` (pivot to centre of mass, world), `r'' = a_P + phi'' J d -
//! phi'^2 d`, and the moment of the contact force about the centre of mass
//! `rho^2 phi'' = (P - r) x f = -d x (r'' + g y^)`. Using `d x J d = |d|^2`:
//!
//! ```text
//! (rho^2 + |d|^2) phi'' = -d x (a_P + g y^),     psi'' = phi'' - theta''
//! f = a_P + phi'' J d - phi'^2 d + g y^
//! ```
//!
//! The roll holds iff `f_n > 0` and `|f_t| <= mu f_n`, and `psi` stays between 0 (the old
//! edge back on the surface) and the exterior angle `gamma` at `v` (the next edge lands):
//! the paper's roll-angle constraint, beyond which the object would penetrate the arm.
//! At `psi = psi' = 0` the roll equation gives `psi'' = 0` exactly when the grasp's
//! centre of pressure sits on `v` (`s = 0` or `s = L`): the two phases meet continuously.
//!
//! **Roll end.** When `|psi|` reaches `gamma` the next edge strikes the surface (or, at
//! `psi = 0`, the old edge falls back). The impact is one-sided and plastic
//! ([`super::impact`]): stopped outright only where that impulse's centre of pressure lies
//! on the edge, else the object rocks onto the striking vertex (a square always does); the
//! impulse must lie in its friction cone. The impact speed is the normal speed of the
//! striking vertex, `|psi'| L_new`.
//!
//! **Flight.** `r(t) = r_0 + v_0 t - g t^2 y^ / 2`, `phi(t) = phi_0 + omega_0 t`.
//!
//! **Joint torque.** The arm feels the reaction of the contact force. With `J_a` the arm's
//! inertia about the joint and `tau_g(theta)` its gravity torque,
//! `tau = J_a theta'' + tau_g(theta) + m (r x f + rho^2 phi'')` (no object term in flight).

use super::geometry::{Polygon, Surface, V2};
use serde::Serialize;

/// Joint angle, velocity and acceleration at one instant.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Joint {
    /// theta, rad (counterclockwise from +x).
    pub angle_rad: f64,
    /// theta', rad/s.
    pub velocity_radps: f64,
    /// theta'', rad/s^2.
    pub accel_radps2: f64,
}

impl Joint {
    /// World position of arm-frame point `p`, m.
    pub fn position(&self, p: V2) -> V2 {
        p.rotate(self.angle_rad)
    }
    /// World velocity of the arm's material point at arm-frame `p`, m/s.
    pub fn point_velocity(&self, p: V2) -> V2 {
        self.position(p).perp().scale(self.velocity_radps)
    }
    /// World acceleration of the arm's material point at arm-frame `p`, m/s^2.
    pub fn point_accel(&self, p: V2) -> V2 {
        let w = self.position(p);
        w.perp()
            .scale(self.accel_radps2)
            .minus(w.scale(self.velocity_radps * self.velocity_radps))
    }
}

/// The arm's contact force on the object per unit object mass, N/kg, in surface axes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct ContactForce {
    /// Along the surface normal (> 0 pushes the object away from the arm).
    pub normal: f64,
    /// Along the surface tangent.
    pub tangential: f64,
}

impl ContactForce {
    /// Friction the force needs, `|f_t| / f_n`; infinite if `f_n <= 0`.
    pub fn friction_ratio(&self) -> f64 {
        if self.normal > 0.0 {
            self.tangential.abs() / self.normal
        } else {
            f64::INFINITY
        }
    }
    /// Within the Coulomb cone of `mu` (and pushing).
    pub fn in_cone(&self, mu: f64) -> bool {
        self.normal > 0.0 && self.tangential.abs() <= mu * self.normal
    }
}

/// Gravity vector g y^ read as the force that balances it: (0, g).
fn up(g: f64) -> V2 {
    V2::new(0.0, g)
}

/// Split a world force into the surface axes at joint angle `theta`.
fn surface_axes(s: &Surface, theta: f64, f: V2) -> ContactForce {
    ContactForce {
        normal: f.dot(s.normal().rotate(theta)),
        tangential: f.dot(s.tangent().rotate(theta)),
    }
}

/// How the object sits on the surface with edge `edge` flat on it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Placement {
    /// Edge index k (vertex k to k + 1), lying along the surface tangent.
    pub edge: usize,
    /// Surface coordinate of vertex k, m.
    pub sigma_m: f64,
}

/// The object on a surface of the arm: geometry and the world's gravity.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// The object.
    pub body: Polygon,
    /// The surface it lies on.
    pub surface: Surface,
    /// Gravity, m/s^2 (> 0).
    pub gravity_mps2: f64,
}

/// The dynamic-grasp requirement at one instant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Grasp {
    /// Contact force, N/kg.
    pub force: ContactForce,
    /// Centre of pressure along the edge from vertex k, m (in [0, L] while the grasp holds).
    pub cop_m: f64,
    /// Edge length L, m.
    pub edge_length_m: f64,
    /// Centre of mass, world, m.
    pub com: V2,
    /// Contact force, world, N/kg.
    pub force_world: V2,
}

/// A roll's pivot: which vertex, where, and which way.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Pivot {
    /// Vertex index.
    pub vertex: usize,
    /// Surface coordinate of the vertex, m.
    pub sigma_m: f64,
    /// Body orientation in the arm frame at psi = 0, rad.
    pub alpha0_rad: f64,
    /// +1 rolling counterclockwise (psi grows), -1 clockwise.
    pub dir: f64,
    /// Exterior angle at the vertex: |psi| at which the roll ends, rad.
    pub gamma_rad: f64,
}

/// The roll's acceleration and force at one instant.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RollRate {
    /// psi'', rad/s^2.
    pub psi_accel_radps2: f64,
    /// phi'' (world angular acceleration), rad/s^2.
    pub phi_accel_radps2: f64,
    /// Contact force at the pivot, N/kg.
    pub force: ContactForce,
    /// Centre of mass (world) and its acceleration, for the torque.
    pub com: V2,
    /// Acceleration of the centre of mass, m/s^2.
    pub com_accel: V2,
}

impl Rig {
    /// Body orientation in the arm frame with edge `k` flat on the surface, rad.
    pub fn alpha_rad(&self, edge: usize) -> f64 {
        self.surface.beta_rad - self.body.edge_angle_rad(edge)
    }

    /// Centre of mass in the arm frame for a placement, m.
    pub fn com_arm(&self, p: &Placement) -> V2 {
        let v = self.body.vertex(p.edge).rotate(self.alpha_rad(p.edge));
        self.surface.point(p.sigma_m).minus(v)
    }

    /// The dynamic-grasp force and centre of pressure (module docs).
    pub fn grasp(&self, p: &Placement, j: &Joint) -> Grasp {
        let r_arm = self.com_arm(p);
        let r = j.position(r_arm);
        let f = j.point_accel(r_arm).plus(up(self.gravity_mps2));
        let force = surface_axes(&self.surface, j.angle_rad, f);
        let pk = j.position(self.surface.point(p.sigma_m));
        let rho2 = self.body.rho_m * self.body.rho_m;
        let cop_m = (rho2 * j.accel_radps2 - pk.minus(r).cross(f)) / force.normal;
        Grasp {
            force,
            cop_m,
            edge_length_m: self.body.edge_length_m(p.edge),
            com: r,
            force_world: f,
        }
    }

    /// The pivot for rolling off placement `p` in direction `dir` (+1 counterclockwise
    /// over vertex k, -1 clockwise over vertex k + 1).
    pub fn pivot(&self, p: &Placement, dir: f64) -> Pivot {
        let (vertex, sigma_m) = if dir > 0.0 {
            (p.edge, p.sigma_m)
        } else {
            (
                (p.edge + 1) % self.body.len(),
                p.sigma_m + self.body.edge_length_m(p.edge),
            )
        };
        Pivot {
            vertex,
            sigma_m,
            alpha0_rad: self.alpha_rad(p.edge),
            dir: dir.signum(),
            gamma_rad: self.body.exterior_angle_rad(vertex),
        }
    }

    /// Pivot to centre of mass in the arm frame at relative angle `psi`, m.
    pub fn pivot_to_com_arm(&self, pv: &Pivot, psi_rad: f64) -> V2 {
        self.body
            .vertex(pv.vertex)
            .rotate(pv.alpha0_rad + psi_rad)
            .scale(-1.0)
    }

    /// The roll equation and its contact force (module docs).
    pub fn roll(&self, pv: &Pivot, psi_rad: f64, psi_dot_radps: f64, j: &Joint) -> RollRate {
        let p_arm = self.surface.point(pv.sigma_m);
        let a_p = j.point_accel(p_arm);
        let d = j.position(self.pivot_to_com_arm(pv, psi_rad));
        let rho2 = self.body.rho_m * self.body.rho_m;
        let phi_dd = -d.cross(a_p.plus(up(self.gravity_mps2))) / (rho2 + d.norm2());
        let phi_d = j.velocity_radps + psi_dot_radps;
        let com_accel = a_p
            .plus(d.perp().scale(phi_dd))
            .minus(d.scale(phi_d * phi_d));
        let f = com_accel.plus(up(self.gravity_mps2));
        RollRate {
            psi_accel_radps2: phi_dd - j.accel_radps2,
            phi_accel_radps2: phi_dd,
            force: surface_axes(&self.surface, j.angle_rad, f),
            com: j.position(p_arm).plus(d),
            com_accel,
        }
    }

    /// The placement after a completed roll over `pv`: the next edge flat, its first vertex
    /// where it lands.
    pub fn landed(&self, pv: &Pivot) -> Placement {
        if pv.dir > 0.0 {
            let edge = self.body.prev(pv.vertex);
            Placement {
                edge,
                sigma_m: pv.sigma_m - self.body.edge_length_m(edge),
            }
        } else {
            Placement {
                edge: pv.vertex,
                sigma_m: pv.sigma_m,
            }
        }
    }

    /// Normal speed of the striking vertex when a roll with rate `psi_dot` ends, m/s.
    pub fn impact_speed_mps(&self, pv: &Pivot, psi_dot_radps: f64) -> f64 {
        psi_dot_radps.abs() * self.body.edge_length_m(self.landed(pv).edge)
    }
}

/// Object state in the world: centre of mass, angle and their rates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct BodyState {
    /// Centre of mass, m.
    pub com: V2,
    /// Velocity of the centre of mass, m/s.
    pub velocity: V2,
    /// Orientation phi (body frame to world), rad.
    pub angle_rad: f64,
    /// phi', rad/s.
    pub angular_velocity_radps: f64,
}

impl BodyState {
    /// Free flight for `t_s` seconds under gravity `g` (closed form).
    pub fn flown(&self, t_s: f64, g: f64) -> Self {
        Self {
            com: self
                .com
                .plus(self.velocity.scale(t_s))
                .minus(V2::new(0.0, 0.5 * g * t_s * t_s)),
            velocity: self.velocity.minus(V2::new(0.0, g * t_s)),
            angle_rad: self.angle_rad + self.angular_velocity_radps * t_s,
            angular_velocity_radps: self.angular_velocity_radps,
        }
    }

    /// World position of body-frame point `b`, m.
    pub fn point(&self, b: V2) -> V2 {
        self.com.plus(b.rotate(self.angle_rad))
    }
}

impl Rig {
    /// World state of an object grasped at `p`.
    pub fn grasped_state(&self, p: &Placement, j: &Joint) -> BodyState {
        let r_arm = self.com_arm(p);
        BodyState {
            com: j.position(r_arm),
            velocity: j.point_velocity(r_arm),
            angle_rad: j.angle_rad + self.alpha_rad(p.edge),
            angular_velocity_radps: j.velocity_radps,
        }
    }

    /// World state of an object rolling over `pv` at (psi, psi').
    pub fn rolling_state(
        &self,
        pv: &Pivot,
        psi_rad: f64,
        psi_dot_radps: f64,
        j: &Joint,
    ) -> BodyState {
        let p_arm = self.surface.point(pv.sigma_m);
        let d = j.position(self.pivot_to_com_arm(pv, psi_rad));
        let phi_d = j.velocity_radps + psi_dot_radps;
        BodyState {
            com: j.position(p_arm).plus(d),
            velocity: j.point_velocity(p_arm).plus(d.perp().scale(phi_d)),
            angle_rad: j.angle_rad + pv.alpha0_rad + psi_rad,
            angular_velocity_radps: phi_d,
        }
    }
}

/// The arm's own rigid-body dynamics (without the object).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ArmInertia {
    /// Inertia about the joint, kg m^2.
    pub inertia_kgm2: f64,
    /// Gravity torque with the centre of mass level, N m (m_a g r_a).
    pub gravity_torque_nm: f64,
    /// Angle of the arm's centre of mass above the link, rad.
    pub gravity_phase_rad: f64,
}

impl ArmInertia {
    /// Torque to move the bare arm with joint state `j`, N m.
    pub fn torque_nm(&self, j: &Joint) -> f64 {
        self.inertia_kgm2 * j.accel_radps2
            + self.gravity_torque_nm * (j.angle_rad + self.gravity_phase_rad).cos()
    }

    /// The object's reaction torque on the joint, N m, for an object of `mass_kg` and
    /// radius of gyration `rho_m` at centre of mass `com` (world), taking the contact force
    /// `f` (N/kg, world) and angular acceleration `phi_dd`: `m (r x f + rho^2 phi'')`.
    pub fn load_torque_nm(mass_kg: f64, rho_m: f64, com: V2, f: V2, phi_dd: f64) -> f64 {
        mass_kg * (com.cross(f) + rho_m * rho_m * phi_dd)
    }
}

/// Gravity's balancing force `(0, g)` plus `a`: the contact force per unit mass for a
/// centre-of-mass acceleration `a`, N/kg.
pub fn contact_force_world(a: V2, g: f64) -> V2 {
    a.plus(up(g))
}
