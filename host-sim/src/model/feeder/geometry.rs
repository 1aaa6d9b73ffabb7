//! Plane geometry of a polygonal part: vectors, poses, area moments and the convex hull.
//!
//! Conventions (used by every feeder module): the world frame has its origin at the
//! fence pivot, the belt moves in -y, angles are radians counter-clockwise from +x. A
//! part's body frame has its origin at the part's **center of mass**; a [`Pose`] places
//! that frame in the world.

use serde::Serialize;

/// A plane vector, m (or m/s where a velocity).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Vec2 {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
}

impl Vec2 {
    /// `(x, y)`.
    pub const fn new(x: f64, y: f64) -> Self {
        Self { x, y }
    }
    /// Unit vector at `angle_rad` from +x.
    pub fn from_angle(angle_rad: f64) -> Self {
        Self::new(angle_rad.cos(), angle_rad.sin())
    }
    /// Dot product.
    pub fn dot(self, o: Self) -> f64 {
        self.x * o.x + self.y * o.y
    }
    /// z component of the cross product `self x o`.
    pub fn cross(self, o: Self) -> f64 {
        self.x * o.y - self.y * o.x
    }
    /// Euclidean length.
    pub fn norm(self) -> f64 {
        self.x.hypot(self.y)
    }
    /// `self` rotated by `angle_rad` counter-clockwise.
    pub fn rotate(self, angle_rad: f64) -> Self {
        let (s, c) = angle_rad.sin_cos();
        Self::new(c * self.x - s * self.y, s * self.x + c * self.y)
    }
    /// `self` rotated by +90 degrees: `(-y, x)`; `w.perp() * omega` is the velocity of
    /// the point `w` of a body spinning at `omega` about the origin.
    pub fn perp(self) -> Self {
        Self::new(-self.y, self.x)
    }
    /// `k * self`.
    pub fn scale(self, k: f64) -> Self {
        Self::new(k * self.x, k * self.y)
    }
}

impl core::ops::Add for Vec2 {
    type Output = Vec2;
    fn add(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x + o.x, self.y + o.y)
    }
}

impl core::ops::Sub for Vec2 {
    type Output = Vec2;
    fn sub(self, o: Vec2) -> Vec2 {
        Vec2::new(self.x - o.x, self.y - o.y)
    }
}

impl core::ops::Neg for Vec2 {
    type Output = Vec2;
    fn neg(self) -> Vec2 {
        Vec2::new(-self.x, -self.y)
    }
}

/// Placement of a part: its center of mass at `com_m` (world, m), its body frame turned
/// by `angle_rad`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Pose {
    /// Center of mass, world frame, m.
    pub com_m: Vec2,
    /// Body frame orientation, rad (counter-clockwise).
    pub angle_rad: f64,
}

impl Pose {
    /// World position of the body-frame point `p`.
    pub fn to_world(&self, p: Vec2) -> Vec2 {
        self.com_m + p.rotate(self.angle_rad)
    }
}

/// Signed area (> 0 counter-clockwise), m^2, of the closed polygon `v`.
pub fn signed_area(v: &[Vec2]) -> f64 {
    let n = v.len();
    (0..n).map(|i| v[i].cross(v[(i + 1) % n])).sum::<f64>() / 2.0
}

/// Area centroid of a simple polygon (either orientation).
pub fn centroid(v: &[Vec2]) -> Vec2 {
    let n = v.len();
    let a = signed_area(v);
    let mut c = Vec2::default();
    for i in 0..n {
        let (p, q) = (v[i], v[(i + 1) % n]);
        c = c + (p + q).scale(p.cross(q));
    }
    c.scale(1.0 / (6.0 * a))
}

/// Convex hull, counter-clockwise, without collinear points (Andrew's monotone chain).
pub fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let mut p: Vec<Vec2> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let turn = |o: Vec2, a: Vec2, b: Vec2| (a - o).cross(b - o);
    let mut hull: Vec<Vec2> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Vec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 1e-15
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

/// True when the closed polygon `v` has no two non-adjacent edges that intersect (O(n^2)).
pub fn is_simple(v: &[Vec2]) -> bool {
    let n = v.len();
    let seg_cross = |a: Vec2, b: Vec2, c: Vec2, d: Vec2| {
        let o = |p: Vec2, q: Vec2, r: Vec2| (q - p).cross(r - p);
        let (d1, d2) = (o(a, b, c), o(a, b, d));
        let (d3, d4) = (o(c, d, a), o(c, d, b));
        d1 * d2 < 0.0 && d3 * d4 < 0.0
    };
    for i in 0..n {
        for j in i + 2..n {
            if i == 0 && j == n - 1 {
                continue;
            }
            if seg_cross(v[i], v[(i + 1) % n], v[j], v[(j + 1) % n]) {
                return false;
            }
        }
    }
    true
}

/// True when `p` lies strictly inside the closed polygon `v` (crossing number).
pub fn contains(v: &[Vec2], p: Vec2) -> bool {
    let n = v.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (v[i], v[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if p.x < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Triangles `(a, b, c)` covering a simple polygon (ear clipping, counter-clockwise
/// input), for area integrals over nonconvex parts.
pub fn triangulate(v: &[Vec2]) -> Vec<[Vec2; 3]> {
    let mut idx: Vec<usize> = (0..v.len()).collect();
    let mut out = Vec::with_capacity(v.len().saturating_sub(2));
    let mut guard = 0;
    while idx.len() > 3 && guard < 10 * v.len() * v.len() {
        guard += 1;
        let m = idx.len();
        let ear = (0..m).find(|&k| {
            let (a, b, c) = (v[idx[(k + m - 1) % m]], v[idx[k]], v[idx[(k + 1) % m]]);
            (b - a).cross(c - b) > 0.0
                && idx
                    .iter()
                    .filter(|&&j| v[j] != a && v[j] != b && v[j] != c)
                    .all(|&j| !point_in_triangle(v[j], a, b, c))
        });
        let Some(k) = ear else { break };
        out.push([v[idx[(k + m - 1) % m]], v[idx[k]], v[idx[(k + 1) % m]]]);
        idx.remove(k);
    }
    if idx.len() == 3 {
        out.push([v[idx[0]], v[idx[1]], v[idx[2]]]);
    }
    out
}

fn point_in_triangle(p: Vec2, a: Vec2, b: Vec2, c: Vec2) -> bool {
    let s1 = (b - a).cross(p - a);
    let s2 = (c - b).cross(p - b);
    let s3 = (a - c).cross(p - c);
    s1 >= 0.0 && s2 >= 0.0 && s3 >= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square() -> Vec<Vec2> {
        vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(2.0, 0.0),
            Vec2::new(2.0, 2.0),
            Vec2::new(0.0, 2.0),
        ]
    }

    #[test]
    fn square_area_centroid_hull() {
        assert!((signed_area(&square()) - 4.0).abs() < 1e-12);
        assert_eq!(centroid(&square()), Vec2::new(1.0, 1.0));
        let mut pts = square();
        pts.push(Vec2::new(1.0, 1.0));
        pts.push(Vec2::new(1.0, 0.0)); // collinear, dropped
        assert_eq!(convex_hull(&pts).len(), 4);
        assert!(signed_area(&convex_hull(&pts)) > 0.0);
    }

    #[test]
    fn l_shape_triangulates_to_its_area() {
        let l = [
            (0.0, 0.0),
            (3.0, 0.0),
            (3.0, 1.0),
            (1.0, 1.0),
            (1.0, 3.0),
            (0.0, 3.0),
        ]
        .map(|(x, y)| Vec2::new(x, y));
        let tris = triangulate(&l);
        let a: f64 = tris.iter().map(|t| signed_area(t)).sum();
        assert!((a - 5.0).abs() < 1e-12, "{a}");
        assert!(is_simple(&l));
        assert!(contains(&l, Vec2::new(0.5, 0.5)) && !contains(&l, Vec2::new(2.0, 2.0)));
    }
}
