//! Support friction between the part and the belt: the limit surface.
//!
//! The part slides on the belt with relative twist `V_rel = (v, omega)` (velocity of the
//! center of mass relative to the belt, m/s, and angular rate, rad/s). With support
//! pressure `p` and friction `mu_s`, Coulomb friction at every support point gives the
//! friction wrench (force, moment about the COM) on the part (Goyal, Ruina & Papadopoulos
//! 1991):
//!
//! ```text
//! f = -mu_s ∫ p(x) u(x) dA,   m = -mu_s ∫ p(x) (x - c) x u(x) dA,
//! u(x) = (v + omega (x - c)^perp) / |v + omega (x - c)^perp|
//! ```
//!
//! The set of such wrenches over all twists is the limit surface; the twist is normal to
//! it at the wrench (maximum dissipation). We use its **ellipsoidal approximation**
//! (Howe & Cutkosky 1996; Lynch, Maekawa & Tanie 1992), exact at pure translation and
//! pure rotation about the COM:
//!
//! ```text
//! H(f, m) = |f|^2 / f_max^2 + m^2 / m_max^2 = 1,   f_max = mu_s W,
//! m_max = mu_s W rho,   rho = (1/A) ∫ |x - c| dA   (uniform pressure),
//! ```
//!
//! so the friction wrench is `-(f_max) (v, rho^2 omega) / sqrt(|v|^2 + rho^2 omega^2)`:
//! the force is antiparallel to the COM's relative velocity and the moment proportional
//! to rho^2 omega. Uniform pressure is assumed for rho; when a scene's center of mass is
//! not the area centroid, the ellipsoid is still centered on the COM (the belt's drag on
//! a part at rest then acts through the COM, as it must) and rho is the mean distance of
//! the area from the COM: an approximation, stated in the docs. [`exact_wrench`] computes
//! the integral above by quadrature so the approximation is checked in the tests.

use super::geometry::Vec2;

/// Subdivisions per triangle side of the quadrature (N^2 sub-triangles, centroid rule).
const QUAD_N: usize = 24;

/// Visits the quadrature points of `tris`: `(point, area weight)`.
fn quadrature(tris: &[[Vec2; 3]], mut f: impl FnMut(Vec2, f64)) {
    let n = QUAD_N as f64;
    for t in tris {
        let (a, e1, e2) = (
            t[0],
            (t[1] - t[0]).scale(1.0 / n),
            (t[2] - t[0]).scale(1.0 / n),
        );
        let w = 0.5 * e1.cross(e2);
        for i in 0..QUAD_N {
            for j in 0..QUAD_N - i {
                let (fi, fj) = (i as f64, j as f64);
                f(a + e1.scale(fi + 1.0 / 3.0) + e2.scale(fj + 1.0 / 3.0), w);
                if i + j + 1 < QUAD_N {
                    f(a + e1.scale(fi + 2.0 / 3.0) + e2.scale(fj + 2.0 / 3.0), w);
                }
            }
        }
    }
}

/// rho = (1/A) ∫ |x - center| dA over the triangles `tris`, m: `m_max / f_max` of a
/// uniformly pressed part rotating about `center`.
pub fn mean_distance_m(tris: &[[Vec2; 3]], center: Vec2) -> f64 {
    let (mut num, mut area) = (0.0, 0.0);
    quadrature(tris, |x, w| {
        num += w * (x - center).norm();
        area += w;
    });
    num / area
}

/// Friction wrench `(f_x, f_y, m)` on a uniformly pressed part, per unit `mu_s W`
/// (so |f| <= 1, m in m), for the relative twist `(v, omega)` of the body point `center`:
/// the exact limit-surface integral, by quadrature.
pub fn exact_wrench(tris: &[[Vec2; 3]], center: Vec2, v: Vec2, omega: f64) -> (Vec2, f64) {
    let (mut f, mut m, mut area) = (Vec2::default(), 0.0, 0.0);
    quadrature(tris, |x, w| {
        let r = x - center;
        let u = v + r.perp().scale(omega);
        let n = u.norm();
        if n > 0.0 {
            let du = u.scale(-w / n);
            f = f + du;
            m += r.cross(du);
        }
        area += w;
    });
    (f.scale(1.0 / area), m / area)
}

/// The ellipsoidal approximation's friction wrench per unit `mu_s W` for the relative
/// twist `(v, omega)` of the COM: `-(v, rho^2 omega) / sqrt(|v|^2 + rho^2 omega^2)`.
pub fn ellipsoid_wrench(rho_m: f64, v: Vec2, omega: f64) -> (Vec2, f64) {
    let s = (v.dot(v) + rho_m * rho_m * omega * omega).sqrt();
    (v.scale(-1.0 / s), -rho_m * rho_m * omega / s)
}

/// H of the ellipsoid at the wrench `(f, m)` per unit `mu_s W`: 1 on the surface.
pub fn ellipsoid_h(rho_m: f64, f: Vec2, m: f64) -> f64 {
    f.dot(f) + m * m / (rho_m * rho_m)
}

#[cfg(test)]
mod tests {
    use super::super::geometry::triangulate;
    use super::*;

    fn square_tris(s: f64) -> Vec<[Vec2; 3]> {
        let h = s / 2.0;
        let v = [(-h, -h), (h, -h), (h, h), (-h, h)].map(|(x, y)| Vec2::new(x, y));
        triangulate(&v)
    }

    #[test]
    fn square_rho_matches_closed_form() {
        // (1/s^2) ∫∫ |x| over a square of side s about its center
        // = s (sqrt 2 + ln(1 + sqrt 2)) / 6 = 0.38260 s.
        let s = 0.1;
        let want = s * (2f64.sqrt() + (1.0 + 2f64.sqrt()).ln()) / 6.0;
        let got = mean_distance_m(&square_tris(s), Vec2::default());
        assert!((got - want).abs() < 2e-4 * s, "{got} vs {want}");
    }

    #[test]
    fn exact_integral_hits_the_ellipsoid_axes() {
        let tris = square_tris(0.1);
        let rho = mean_distance_m(&tris, Vec2::default());
        let (f, m) = exact_wrench(&tris, Vec2::default(), Vec2::new(0.0, 1.0), 0.0);
        assert!((f.y + 1.0).abs() < 1e-9 && f.x.abs() < 1e-9 && m.abs() < 1e-9);
        let (f, m) = exact_wrench(&tris, Vec2::default(), Vec2::default(), 2.0);
        assert!(f.norm() < 1e-9 && (m + rho).abs() < 1e-9);
    }
}
