//! The stable push: when a part with edge `e` flush on the turning fence moves with it,
//! and the minimum contact radius that makes that so (sec. 3.2 of the paper: "A stable
//! push is possible for any stable edge, provided that the contact radius is higher than
//! some minimum ... \[depending\] on the edge, on the object shape, the center of gravity,
//! the angular rate of the fence relative to the conveyor speed, and the coefficient of
//! friction").
//!
//! ## Derivation (ours; the condensed paper gives none)
//!
//! Edge `e` flush on a fence at theta turning at omega > 0 about the pivot, COM at fence
//! coordinates `(r, h)` (`h` = [`HullEdge::h_m`]). Moving with the fence, the part's twist
//! is a rotation about the pivot, so relative to the belt
//! `V_rel = (omega c^perp + (0, v_b), omega)` with `c = r t + h n`. By eq. (1) of
//! [`super::quasistatic`], the fence must supply the wrench `M V_rel`; in fence
//! components (`c^perp = r n - h t`):
//!
//! ```text
//! F_n = omega r + v_b cos theta,     F_t = v_b sin theta - omega h,     m = rho^2 omega
//! ```
//!
//! applied on the fence line at `s = r + o`, `o = (rho^2 omega - h F_t) / F_n` (moment
//! balance `(s - r) F_n + h F_t = m`). A line contact can supply it iff
//!
//! ```text
//! F_n > 0,    |F_t| <= mu F_n,    -a <= o <= b          (a, b: COM foot to edge ends)
//! ```
//!
//! We demand a margin `m` ([`PUSH_MARGIN`]): `|F_t| <= (1-m) mu F_n`,
//! `-(1-m) a <= o <= (1-m) b`. For omega > 0 both `F_n` and the slack grow with r, so
//! each condition is a lower bound on r in closed form ([`min_radius_at`]); the
//! minimum contact radius over a range of fence angles is the largest of these
//! ([`min_contact_radius`]). Faster fences (omega r >> v_b) make `o -> rho^2/r`-ish and
//! `F_t/F_n -> -h/r`, so long radii always work: the paper's "provided that the contact
//! radius is higher than some minimum". At omega = 0 (fence at rest) the conditions
//! reduce to the stable-edge test `|theta| <= atan mu`, `o = h tan theta` inside the
//! edge: at theta = 0 the part rests iff the COM's foot lies on the edge.

use super::part::{HullEdge, Part};

/// Safety margin of every stable push the planner commands (fraction of the friction
/// cone and of the COM foot's distance to each edge end).
pub const PUSH_MARGIN: f64 = 0.1;

/// Step of the angle grid on which range conditions are checked, rad (0.5 degrees).
pub const ANGLE_GRID_RAD: f64 = 0.5 * std::f64::consts::PI / 180.0;

/// The fence wrench a stable push needs, fence components (per unit `mu_s W` of the
/// support friction's scale, m/s units as in [`super::quasistatic`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PushWrench {
    /// F_n, normal component.
    pub normal: f64,
    /// F_t, component along the fence.
    pub tangential: f64,
    /// o, where the resultant meets the fence, measured from the COM's foot, m.
    pub offset_m: f64,
}

/// The wrench the fence must supply to push `edge` stably at contact radius `r_m`, fence
/// angle `angle_rad`, fence rate `omega_radps`, belt speed `v_b_mps`.
pub fn push_wrench(
    edge: &HullEdge,
    rho_m: f64,
    r_m: f64,
    angle_rad: f64,
    omega_radps: f64,
    v_b_mps: f64,
) -> PushWrench {
    let normal = omega_radps * r_m + v_b_mps * angle_rad.cos();
    let tangential = v_b_mps * angle_rad.sin() - omega_radps * edge.h_m;
    let offset_m = (rho_m * rho_m * omega_radps - edge.h_m * tangential) / normal;
    PushWrench {
        normal,
        tangential,
        offset_m,
    }
}

/// Whether the push of [`push_wrench`] is stable with margin `margin`.
#[allow(clippy::too_many_arguments)]
pub fn push_ok(
    edge: &HullEdge,
    rho_m: f64,
    r_m: f64,
    angle_rad: f64,
    omega_radps: f64,
    v_b_mps: f64,
    mu: f64,
    margin: f64,
) -> bool {
    let w = push_wrench(edge, rho_m, r_m, angle_rad, omega_radps, v_b_mps);
    let k = 1.0 - margin;
    w.normal > 0.0
        && w.tangential.abs() <= k * mu * w.normal
        && w.offset_m >= -k * edge.a_m
        && w.offset_m <= k * edge.b_m()
}

/// Smallest contact radius, m, for a stable push of `edge` at one fence angle with margin
/// [`PUSH_MARGIN`]; at least `a` (the edge starts beyond the pivot). Infinite when no
/// radius works (omega <= 0 and the static condition fails).
pub fn min_radius_at(
    edge: &HullEdge,
    rho_m: f64,
    angle_rad: f64,
    omega_radps: f64,
    v_b_mps: f64,
    mu: f64,
) -> f64 {
    let k = 1.0 - PUSH_MARGIN;
    let floor = edge.a_m * (1.0 + 1e-9);
    if edge.a_m <= 0.0 || edge.b_m() <= 0.0 || mu < 0.0 {
        return f64::INFINITY;
    }
    if omega_radps <= 0.0 {
        let ok = push_ok(
            edge,
            rho_m,
            floor,
            angle_rad,
            omega_radps,
            v_b_mps,
            mu,
            PUSH_MARGIN,
        );
        return if ok { floor } else { f64::INFINITY };
    }
    let ft = push_wrench(edge, rho_m, 0.0, angle_rad, omega_radps, v_b_mps).tangential;
    let num = rho_m * rho_m * omega_radps - edge.h_m * ft;
    // F_n must exceed each of these (strictly positive) bounds.
    let fn_friction = if mu > 0.0 {
        ft.abs() / (k * mu)
    } else if ft == 0.0 {
        0.0
    } else {
        f64::INFINITY
    };
    let fn_offset = if num >= 0.0 {
        num / (k * edge.b_m())
    } else {
        -num / (k * edge.a_m)
    };
    let fn_min = fn_friction.max(fn_offset).max(1e-12 * v_b_mps.abs());
    let r = (fn_min - v_b_mps * angle_rad.cos()) / omega_radps;
    r.max(floor)
}

/// The minimum contact radius, m, for stable pushes of hull edge `edge` of `part` over
/// every fence angle between `from_rad` and `to_rad` (grid [`ANGLE_GRID_RAD`] plus both
/// ends) at fence rate `omega_radps` (> 0: counter-clockwise), belt speed `v_b_mps`,
/// fence friction `mu`.
pub fn min_contact_radius(
    part: &Part,
    edge: usize,
    from_rad: f64,
    to_rad: f64,
    omega_radps: f64,
    v_b_mps: f64,
    mu: f64,
) -> f64 {
    let e = &part.edges[edge];
    let (lo, hi) = (from_rad.min(to_rad), from_rad.max(to_rad));
    let n = ((hi - lo) / ANGLE_GRID_RAD).ceil() as usize;
    (0..=n)
        .map(|i| {
            if n == 0 {
                lo
            } else {
                lo + (hi - lo) * i as f64 / n as f64
            }
        })
        .map(|th| min_radius_at(e, part.rho_m, th, omega_radps, v_b_mps, mu))
        .fold(0.0, f64::max)
}

/// Fence-frame coordinates `(t, n)` of the hull vertices when `edge` lies flush on the
/// fence with the COM's foot at contact radius `r_m`.
pub fn hull_on_fence(part: &Part, edge: usize, r_m: f64) -> Vec<(f64, f64)> {
    let e = &part.edges[edge];
    part.hull
        .iter()
        .map(|p| {
            let q = p.rotate(-e.dir_rad);
            (r_m + q.x, e.h_m + q.y)
        })
        .collect()
}

/// Range `(min, max)` of `cos` over the interval `[lo, hi]` (rad, `lo <= hi`).
pub fn cos_range(lo: f64, hi: f64) -> (f64, f64) {
    use std::f64::consts::{PI, TAU};
    let (a, b) = (lo.cos(), hi.cos());
    let (mut mn, mut mx) = (a.min(b), a.max(b));
    // A multiple of 2 pi (max) or an odd multiple of pi (min) inside the interval.
    if (lo / TAU).ceil() * TAU <= hi {
        mx = 1.0;
    }
    if ((lo - PI) / TAU).ceil() * TAU + PI <= hi {
        mn = -1.0;
    }
    (mn, mx)
}

/// Range `(min, max)` of the world x of the part's hull while `edge` lies flush at
/// contact radius `r_m` and the fence turns between `from_rad` and `to_rad` (exact: each
/// vertex at fence coordinates `(t, n)` is at `x = |(t, n)| cos(theta + atan2(n, t))`).
pub fn x_range_on_arc(
    part: &Part,
    edge: usize,
    r_m: f64,
    from_rad: f64,
    to_rad: f64,
) -> (f64, f64) {
    let (lo, hi) = (from_rad.min(to_rad), from_rad.max(to_rad));
    hull_on_fence(part, edge, r_m).into_iter().fold(
        (f64::INFINITY, f64::NEG_INFINITY),
        |acc, (t, n)| {
            let (rho, phi) = (t.hypot(n), n.atan2(t));
            let (cmin, cmax) = cos_range(lo + phi, hi + phi);
            (acc.0.min(rho * cmin), acc.1.max(rho * cmax))
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cos_range_finds_interior_extremes() {
        let (mn, mx) = cos_range(-0.5, 0.5);
        assert!((mx - 1.0).abs() < 1e-15 && (mn - 0.5f64.cos()).abs() < 1e-15);
        let (mn, mx) = cos_range(3.0, 3.5);
        assert!((mn + 1.0).abs() < 1e-15 && (mx - 3.5f64.cos()).abs() < 1e-15);
        let (mn, mx) = cos_range(0.2, 0.4);
        assert!((mn - 0.4f64.cos()).abs() < 1e-15 && (mx - 0.2f64.cos()).abs() < 1e-15);
        let (mn, mx) = cos_range(-7.0, -6.0);
        assert!((mx - 1.0).abs() < 1e-15 && mn < mx);
    }
}
