//! The part: a polygon with its center of mass, its convex hull (what a straight fence
//! touches) and its hull edges with the quantities that decide stability.

use super::geometry::{centroid, contains, convex_hull, is_simple, signed_area, triangulate, Vec2};
use super::support::mean_distance_m;
use super::FeederError;

/// One edge of the part's convex hull, in the body frame (origin at the center of mass).
///
/// With the edge flush on a fence the part lies on the fence's +normal side and the edge
/// runs along the fence direction from `start` ("left", nearer the pivot at fence angle 0)
/// to `end`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HullEdge {
    /// Index of the start vertex in [`Part::hull`]; the edge ends at the next one.
    pub index: usize,
    /// Direction angle of `end - start` in the body frame, rad.
    pub dir_rad: f64,
    /// Length, m.
    pub len_m: f64,
    /// Distance along the edge from `start` to the foot of the perpendicular from the
    /// center of mass, m (the COM projects inside the edge when `0 < a_m < len_m`).
    pub a_m: f64,
    /// Height of the center of mass above the edge's line, m (> 0).
    pub h_m: f64,
}

impl HullEdge {
    /// Distance from the COM's foot to the `end` vertex, m.
    pub fn b_m(&self) -> f64 {
        self.len_m - self.a_m
    }
    /// Part orientation, rad, that lays this edge flush on a fence at `fence_rad`.
    pub fn part_angle_on(&self, fence_rad: f64) -> f64 {
        fence_rad - self.dir_rad
    }
}

/// A rigid polygonal part lying on the belt.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// Polygon vertices, body frame (center of mass at the origin), counter-clockwise, m.
    pub vertices: Vec<Vec2>,
    /// Convex hull of `vertices`, counter-clockwise, no collinear points, m.
    pub hull: Vec<Vec2>,
    /// Hull edges; `edges[i]` runs from `hull[i]` to `hull[i + 1]`.
    pub edges: Vec<HullEdge>,
    /// Area, m^2.
    pub area_m2: f64,
    /// rho = m_max / f_max of the ellipsoidal limit surface, m (see [`super::support`]).
    pub rho_m: f64,
    /// Largest distance of a vertex from the center of mass, m.
    pub radius_m: f64,
}

/// Fraction of an edge's length the COM's foot must keep from either end for the edge
/// to count as stable (the paper's "stable at zero degrees plus or minus a small angle").
pub const STABLE_MARGIN: f64 = 0.02;

impl Part {
    /// Builds a part from its vertices (either orientation, simple polygon, >= 3 points)
    /// and center of mass (default: the area centroid), both in any common frame, m.
    /// Errors name the scene keys `feeder.part.vertices_m` and `feeder.part.center_of_mass_m`.
    pub fn new(vertices: &[Vec2], com: Option<Vec2>) -> Result<Part, FeederError> {
        let bad = |key: &str, why: &str| Err(FeederError::param(key, why));
        if vertices.len() < 3 {
            return bad("feeder.part.vertices_m", "needs at least 3 vertices");
        }
        if vertices
            .iter()
            .any(|v| !v.x.is_finite() || !v.y.is_finite())
        {
            return bad("feeder.part.vertices_m", "must be finite numbers");
        }
        let mut v = vertices.to_vec();
        if signed_area(&v) < 0.0 {
            v.reverse();
        }
        let area = signed_area(&v);
        let diam = v
            .iter()
            .flat_map(|p| v.iter().map(move |q| (*p - *q).norm()))
            .fold(0.0, f64::max);
        if area.is_nan() || area <= 1e-6 * diam * diam || !is_simple(&v) {
            return bad(
                "feeder.part.vertices_m",
                "must form a simple polygon with non-zero area",
            );
        }
        let com = com.unwrap_or_else(|| centroid(&v));
        if !com.x.is_finite() || !com.y.is_finite() || !contains(&v, com) {
            return bad(
                "feeder.part.center_of_mass_m",
                "must lie inside the polygon",
            );
        }
        let body: Vec<Vec2> = v.iter().map(|&p| p - com).collect();
        Ok(Self::from_body(body, area))
    }

    fn from_body(vertices: Vec<Vec2>, area_m2: f64) -> Part {
        let hull = convex_hull(&vertices);
        let n = hull.len();
        let edges = (0..n)
            .map(|i| {
                let (s, e) = (hull[i], hull[(i + 1) % n]);
                let d = e - s;
                let len = d.norm();
                let u = d.scale(1.0 / len);
                HullEdge {
                    index: i,
                    dir_rad: d.y.atan2(d.x),
                    len_m: len,
                    a_m: u.dot(-s),
                    h_m: u.cross(-s),
                }
            })
            .collect();
        let rho_m = mean_distance_m(&triangulate(&vertices), Vec2::default());
        let radius_m = vertices.iter().map(|p| p.norm()).fold(0.0, f64::max);
        Part {
            vertices,
            hull,
            edges,
            area_m2,
            rho_m,
            radius_m,
        }
    }

    /// Whether hull edge `i` is stable: resting on a fence at 0 with the belt dragging the
    /// part in -y, the drag acts at the COM straight down, so the fence must hold it with
    /// a force straight up through the COM: the COM's foot lies inside the edge (with
    /// [`STABLE_MARGIN`]).
    pub fn is_stable(&self, i: usize) -> bool {
        let e = &self.edges[i];
        e.a_m > STABLE_MARGIN * e.len_m && e.b_m() > STABLE_MARGIN * e.len_m
    }

    /// Indices of the stable hull edges, in counter-clockwise order.
    pub fn stable_edges(&self) -> Vec<usize> {
        (0..self.edges.len())
            .filter(|&i| self.is_stable(i))
            .collect()
    }

    /// Counter-clockwise rotation of the part, rad in (0, 2 pi], that takes edge `from`
    /// flush on a fence to edge `to` flush on the same fence: a turn's Psi. Rotating the
    /// part counter-clockwise brings edges of *lower* index down (the hull is CCW), so
    /// Psi = dir(from) - dir(to) mod 2 pi.
    pub fn rotation_between(&self, from: usize, to: usize) -> f64 {
        let tau = std::f64::consts::TAU;
        let d = (self.edges[from].dir_rad - self.edges[to].dir_rad).rem_euclid(tau);
        if d < 1e-12 {
            tau
        } else {
            d
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(p: &[(f64, f64)]) -> Vec<Vec2> {
        p.iter().map(|&(x, y)| Vec2::new(x, y)).collect()
    }

    #[test]
    fn square_edges_all_stable_and_quarter_turns() {
        let p = Part::new(
            &v(&[(0.0, 0.0), (0.02, 0.0), (0.02, 0.02), (0.0, 0.02)]),
            None,
        )
        .unwrap();
        assert_eq!(p.stable_edges(), vec![0, 1, 2, 3]);
        for e in &p.edges {
            assert!((e.a_m - 0.01).abs() < 1e-12 && (e.h_m - 0.01).abs() < 1e-12);
        }
        let q = std::f64::consts::FRAC_PI_2;
        assert!((p.rotation_between(1, 0) - q).abs() < 1e-12);
        assert!((p.rotation_between(0, 3) - q).abs() < 1e-12);
    }

    #[test]
    fn leaning_parallelogram_has_two_parallel_stable_edges() {
        // COM (2.5, 0.5). Short edge (4,0)->(5,1): the COM's foot lies at
        // ((-1.5, 0.5) . (1, 1)/sqrt 2) = -1/sqrt 2 < 0, before the edge: unstable; the other
        // short edge likewise by symmetry. The long edges are stable, 180 degrees apart.
        let p = Part::new(&v(&[(0.0, 0.0), (4.0, 0.0), (5.0, 1.0), (1.0, 1.0)]), None).unwrap();
        assert_eq!(p.stable_edges(), vec![0, 2]);
        assert!((p.rotation_between(0, 2) - std::f64::consts::PI).abs() < 1e-12);
        assert!((p.edges[1].a_m + 0.5f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn bad_input_names_the_key() {
        let e = Part::new(&v(&[(0.0, 0.0), (1.0, 0.0)]), None).unwrap_err();
        assert!(e.to_string().contains("feeder.part.vertices_m"), "{e}");
        let sq = v(&[(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]);
        let e = Part::new(&sq, Some(Vec2::new(2.0, 0.5))).unwrap_err();
        assert!(
            e.to_string().contains("feeder.part.center_of_mass_m"),
            "{e}"
        );
        let bow = v(&[(0.0, 0.0), (1.0, 1.0), (1.0, 0.0), (0.0, 1.0)]);
        assert!(Part::new(&bow, None).is_err());
    }
}
