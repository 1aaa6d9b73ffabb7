//! Plane vectors, the polygonal object and the arm's manipulation surfaces.
//!
//! Frames: the world has x right, y up, the joint axis at the origin, gravity along -y.
//! The arm frame turns with the joint angle theta (counterclockwise from +x): its x axis
//! runs along the link. A manipulation surface is a line fixed in the arm frame through
//! `origin` with direction angle `beta` from the link; tangent `t = (cos b, sin b)`,
//! normal `n = (-sin b, cos b)`, and the object lies on the `+n` side. Surface coordinate
//! `sigma` is the distance along `t` from `origin`.

use serde::Serialize;

/// A plane vector, m (or m/s, m/s^2, N/kg as the name says).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct V2 {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
}

impl V2 {
    /// A vector from its components.
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }
    /// Unit vector at angle `a` rad from +x.
    pub fn unit(a: f64) -> Self {
        Self::new(a.cos(), a.sin())
    }
    /// Sum.
    pub fn plus(self, o: Self) -> Self {
        Self::new(self.x + o.x, self.y + o.y)
    }
    /// Difference.
    pub fn minus(self, o: Self) -> Self {
        Self::new(self.x - o.x, self.y - o.y)
    }
    /// Scaled by `k`.
    pub fn scale(self, k: f64) -> Self {
        Self::new(k * self.x, k * self.y)
    }
    /// Dot product.
    pub fn dot(self, o: Self) -> f64 {
        self.x * o.x + self.y * o.y
    }
    /// Planar cross product (z component of self x o).
    pub fn cross(self, o: Self) -> f64 {
        self.x * o.y - self.y * o.x
    }
    /// Rotated by +90 degrees: J v = (-y, x).
    pub fn perp(self) -> Self {
        Self::new(-self.y, self.x)
    }
    /// Rotated by `a` rad.
    pub fn rotate(self, a: f64) -> Self {
        let (s, c) = a.sin_cos();
        Self::new(c * self.x - s * self.y, s * self.x + c * self.y)
    }
    /// Squared length.
    pub fn norm2(self) -> f64 {
        self.dot(self)
    }
    /// Length.
    pub fn norm(self) -> f64 {
        self.norm2().sqrt()
    }
}

/// A convex polygon about its centre of mass, with its mass properties per unit mass.
#[derive(Clone, Debug, PartialEq)]
pub struct Polygon {
    /// Vertices relative to the centre of mass, counterclockwise, m.
    pub vertices: Vec<V2>,
    /// Radius of gyration about the centre of mass, m: I = m rho^2.
    pub rho_m: f64,
}

impl Polygon {
    /// Vertex `i` (indices wrap around).
    pub fn vertex(&self, i: usize) -> V2 {
        self.vertices[i % self.vertices.len()]
    }

    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// True for a polygon without vertices (never built by the validator).
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Index of the vertex before `i`.
    pub fn prev(&self, i: usize) -> usize {
        (i + self.len() - 1) % self.len()
    }

    /// Edge `k` runs from vertex `k` to vertex `k + 1`; its length, m.
    pub fn edge_length_m(&self, k: usize) -> f64 {
        self.vertex(k + 1).minus(self.vertex(k)).norm()
    }

    /// Direction angle of edge `k` in the body frame, rad.
    pub fn edge_angle_rad(&self, k: usize) -> f64 {
        let d = self.vertex(k + 1).minus(self.vertex(k));
        d.y.atan2(d.x)
    }

    /// Exterior angle at vertex `i` (pi minus the interior angle), rad in (0, pi): how far
    /// the body turns rolling over that vertex from one edge to the next.
    pub fn exterior_angle_rad(&self, i: usize) -> f64 {
        let a_in = self.edge_angle_rad(self.prev(i));
        let a_out = self.edge_angle_rad(i);
        wrap_pi(a_out - a_in)
    }

    /// A convex polygon from counterclockwise vertices (any origin): shifted to its area
    /// centroid; `rho_m` as given or, if `None`, that of a uniform plate. `Err` says why
    /// the vertices do not make a convex counterclockwise polygon.
    pub fn new(vertices: &[V2], rho_m: Option<f64>) -> Result<Self, &'static str> {
        if vertices.len() < 3 {
            return Err("needs at least 3 vertices");
        }
        let n = vertices.len();
        let (mut area2, mut c, mut j2) = (0.0, V2::default(), 0.0);
        for i in 0..n {
            let (a, b) = (vertices[i], vertices[(i + 1) % n]);
            let w = a.cross(b); // twice the signed area of triangle (0, a, b)
            area2 += w;
            c = c.plus(a.plus(b).scale(w / 3.0));
            j2 += w * (a.dot(a) + a.dot(b) + b.dot(b)) / 6.0;
        }
        if area2 <= 0.0 {
            return Err("vertices must be counterclockwise (positive area)");
        }
        let c = c.scale(1.0 / area2);
        // plate: J_origin = sum w (a.a + a.b + b.b) / 12 ; per unit area / (area2 / 2)
        let rho2_origin = j2 / area2;
        let rho_plate = (rho2_origin - c.norm2()).max(0.0).sqrt();
        let vertices: Vec<V2> = vertices.iter().map(|v| v.minus(c)).collect();
        for i in 0..n {
            let (a, b, d) = (vertices[i], vertices[(i + 1) % n], vertices[(i + 2) % n]);
            if b.minus(a).cross(d.minus(b)) <= 0.0 {
                return Err("vertices must form a strictly convex counterclockwise polygon");
            }
        }
        Ok(Self {
            vertices,
            rho_m: rho_m.unwrap_or(rho_plate),
        })
    }

    /// A square of side `side_m`, vertices at (±a/2, ±a/2), edge 0 at the bottom.
    pub fn square(side_m: f64, rho_m: Option<f64>) -> Result<Self, &'static str> {
        let h = 0.5 * side_m;
        Self::new(
            &[
                V2::new(-h, -h),
                V2::new(h, -h),
                V2::new(h, h),
                V2::new(-h, h),
            ],
            rho_m,
        )
    }
}

/// Angle wrapped into (-pi, pi], rad.
pub fn wrap_pi(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let r = a - t * (a / t).round();
    if r <= -std::f64::consts::PI {
        r + t
    } else {
        r
    }
}

/// A manipulation surface, fixed in the arm frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Surface {
    /// Point of the line at sigma = 0, arm frame, m.
    pub origin: V2,
    /// Direction of the line from the link, rad.
    pub beta_rad: f64,
    /// Usable length from `origin` along the tangent, m.
    pub length_m: f64,
}

impl Surface {
    /// Tangent in the arm frame.
    pub fn tangent(&self) -> V2 {
        V2::unit(self.beta_rad)
    }
    /// Normal in the arm frame (the object's side).
    pub fn normal(&self) -> V2 {
        self.tangent().perp()
    }
    /// Arm-frame point at surface coordinate `sigma_m`.
    pub fn point(&self, sigma_m: f64) -> V2 {
        self.origin.plus(self.tangent().scale(sigma_m))
    }
    /// Signed height of arm-frame point `p` above the surface line, m.
    pub fn height_m(&self, p: V2) -> f64 {
        p.minus(self.origin).dot(self.normal())
    }
    /// Surface coordinate of the foot of arm-frame point `p`, m.
    pub fn sigma_m(&self, p: V2) -> f64 {
        p.minus(self.origin).dot(self.tangent())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_mass_properties_and_angles() {
        let s = Polygon::square(0.1, None).unwrap();
        // uniform square plate: I = m a^2 / 6
        assert!((s.rho_m.powi(2) - 0.01 / 6.0).abs() < 1e-15);
        for i in 0..4 {
            assert!((s.exterior_angle_rad(i) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
            assert!((s.edge_length_m(i) - 0.1).abs() < 1e-15);
        }
        assert_eq!(s.edge_angle_rad(0), 0.0);
    }

    #[test]
    fn triangle_centroid_and_plate_inertia() {
        // right triangle legs 3, 4 at the origin: centroid (1, 4/3), I_c = m (a^2+b^2)/18
        let t = Polygon::new(
            &[V2::new(0.0, 0.0), V2::new(3.0, 0.0), V2::new(0.0, 4.0)],
            None,
        )
        .unwrap();
        assert!(
            (t.vertices[0].x + 1.0).abs() < 1e-12 && (t.vertices[0].y + 4.0 / 3.0).abs() < 1e-12
        );
        assert!((t.rho_m.powi(2) - 25.0 / 18.0).abs() < 1e-12);
        assert!(Polygon::new(
            &[V2::new(0.0, 0.0), V2::new(0.0, 4.0), V2::new(3.0, 0.0)],
            None
        )
        .is_err());
    }

    #[test]
    fn wrap_and_surface_coordinates() {
        assert!((wrap_pi(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        assert!((wrap_pi(-0.5) + 0.5).abs() < 1e-15);
        let s = Surface {
            origin: V2::new(1.0, 0.05),
            beta_rad: std::f64::consts::FRAC_PI_4,
            length_m: 0.3,
        };
        let p = s.point(0.2).plus(s.normal().scale(0.03));
        assert!((s.height_m(p) - 0.03).abs() < 1e-15 && (s.sigma_m(p) - 0.2).abs() < 1e-15);
    }
}
