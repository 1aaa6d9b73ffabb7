//! Rate-scheduled stable pushes: the fence's rate is a parameter of every push, chosen
//! angle by angle inside the window of rates at which the push is stable.
//!
//! ## Why (ours; the condensed paper only says the minimum contact radius "depends on ...
//! the angular rate of the fence relative to the conveyor speed")
//!
//! With edge `e` flush at contact radius r and fence angle theta, the stable-push
//! conditions of [`super::stability`] (`c = cos theta`, `s = sin theta`, `k = 1 -` margin)
//!
//! ```text
//! F_n = omega r + v_b c > 0,   F_t = v_b s - omega h,   o F_n = omega (rho^2 + h^2) - h v_b s
//! |F_t| <= k mu F_n,           -k a <= o <= k b
//! ```
//!
//! are each **linear in omega** once multiplied by `F_n > 0`:
//!
//! ```text
//! omega (k mu r + h)            >= v_b (s - k mu c)       (the part does not slide toward the pivot)
//! omega (h - k mu r)            <= v_b (s + k mu c)       (nor outward)
//! omega (rho^2 + h^2 - k b r)   <= v_b (h s + k b c)      (the resultant stays before the end vertex)
//! omega (rho^2 + h^2 + k a r)   >= v_b (h s - k a c)      (and beyond the start vertex)
//! ```
//!
//! so the stable rates at one angle form an interval, the **rate window** ([`window`]).
//! A fixed rate (the fastest, [`super::primitives::Drive::push_rate_radps`]) is stable only
//! above a radius that can be large: an edge whose center-of-mass foot lies close to its end
//! vertex (b small beside h) needs `o -> (rho^2 + h^2)/r <= k b`, e.g. 0.65 m for b = 1 mm,
//! h = 21 mm at 2 rad/s. Near theta = 0 a slower push keeps the resultant on the edge (the
//! limit omega -> 0 is the part at rest, o = -h tan theta); at larger theta a faster one
//! keeps it from sliding (at rest it slides once tan theta > mu). Choosing the rate angle by
//! angle therefore pushes such edges stably at small radii. For omega > 0 every bound above
//! loosens as r grows, so a rate stable at r is stable at every larger radius: the
//! **free-rate minimum radius** ([`EdgePush::min_radius_free`]) is the least radius at which
//! some rate in `[floor, omega_max]` is stable, and a push profile computed at a radius is
//! valid at every larger one. The floor ([`EdgePush::floor_radps`]) is `omega_max /
//! RATE_SPAN`, lowered on edges whose push from rest needs slower rates: with it every
//! stable edge can be pushed away from theta = 0 at every contact radius.
//!
//! A push is executed as a **profile** ([`EdgePush::profile`]): on every cell of the angle grid
//! [`ANGLE_GRID_RAD`] the fastest rate (at most the drive's push rate) stable at both of the
//! cell's ends, consecutive equal rates merged.

use super::part::HullEdge;
use super::sim::Schedule;
use super::stability::{min_radius_at, ANGLE_GRID_RAD, PUSH_MARGIN};

/// Slowest push rate as a fraction of the fastest where the physics allows it: rates span
/// `[omega_max / RATE_SPAN, omega_max]`, unless an edge needs slower ones
/// ([`EdgePush::floor_radps`]).
pub const RATE_SPAN: f64 = 64.0;

/// Rates tried (log-spaced over the span) when finding the free-rate minimum radius.
const RATE_STEPS: usize = 49;

/// The interval `[lo, hi]` of fence rates (rad/s, any sign) at which pushing `edge` at
/// contact radius `r_m` and fence angle `angle_rad` is stable with margin `margin`; empty
/// when `lo > hi`.
pub fn window(
    edge: &HullEdge,
    rho_m: f64,
    r_m: f64,
    angle_rad: f64,
    v_b_mps: f64,
    mu: f64,
    margin: f64,
) -> (f64, f64) {
    let (s, c) = angle_rad.sin_cos();
    let k = 1.0 - margin;
    let (h, a, b) = (edge.h_m, edge.a_m, edge.b_m());
    let j = rho_m * rho_m + h * h;
    // alpha omega >= beta (`true`) or alpha omega <= beta (`false`).
    let rows = [
        (r_m, -v_b_mps * c, true),
        (k * mu * r_m + h, v_b_mps * (s - k * mu * c), true),
        (h - k * mu * r_m, v_b_mps * (s + k * mu * c), false),
        (j - k * b * r_m, v_b_mps * (h * s + k * b * c), false),
        (j + k * a * r_m, v_b_mps * (h * s - k * a * c), true),
    ];
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for (alpha, beta, at_least) in rows {
        if alpha.abs() < 1e-300 {
            let holds = if at_least { beta <= 0.0 } else { beta >= 0.0 };
            if !holds {
                return (f64::INFINITY, f64::NEG_INFINITY);
            }
            continue;
        }
        let bound = beta / alpha;
        if at_least == (alpha > 0.0) {
            lo = lo.max(bound);
        } else {
            hi = hi.min(bound);
        }
    }
    (lo, hi)
}

/// Stable pushes of one hull edge: what every push computation of that edge shares (the
/// edge, the support's rho, the fastest push rate, the belt speed, the fence friction).
/// The methods take what varies: the contact radius and the fence angles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgePush<'a> {
    /// The hull edge flush on the fence.
    pub edge: &'a HullEdge,
    /// rho of the limit surface, m.
    pub rho_m: f64,
    /// Fastest push rate, rad/s (> 0).
    pub omega_max_radps: f64,
    /// Belt speed v_b, m/s.
    pub v_b_mps: f64,
    /// Fence friction mu.
    pub mu: f64,
}

impl EdgePush<'_> {
    /// The slowest rate a push of this edge may use, rad/s: `omega_max / RATE_SPAN`, or
    /// less where the edge needs it, a quarter of `v_b k min(b / (rho^2 + h^2), mu / h)`.
    ///
    /// Why that bound: at theta = 0 the rows of [`window`] read `omega r >= -v_b`,
    /// `omega (k mu r + h) >= -v_b k mu`, `omega (rho^2 + h^2 + k a r) >= -v_b k a` (all
    /// hold for omega > 0) and `omega (h - k mu r) <= v_b k mu`,
    /// `omega (rho^2 + h^2 - k b r) <= v_b k b`, whose bounds are at least `v_b k mu / h`
    /// and `v_b k b / (rho^2 + h^2)` for every r >= 0. So on a stable edge (a, b > 0,
    /// mu > 0) every rate in `(0, 4 floor]` is stable at theta = 0 **at every contact
    /// radius**: a push can start from the fence at rest whatever the radius, only slowly
    /// when the center of mass's foot is near the edge's end (b small beside h). A fixed
    /// floor `omega_max / 64` made such edges (b = 0.57 mm, h = 31 mm: 4 floor = 0.02
    /// rad/s < 2/64) unpushable below r = 0.86 m. The floor stays positive, so every push
    /// ends in bounded time.
    pub fn floor_radps(&self) -> f64 {
        let span = self.omega_max_radps / RATE_SPAN;
        let (e, k) = (self.edge, 1.0 - PUSH_MARGIN);
        let j = self.rho_m * self.rho_m + e.h_m * e.h_m;
        let physical = 0.25 * self.v_b_mps.abs() * k * (e.b_m() / j).min(self.mu / e.h_m);
        if e.a_m > 0.0 && e.b_m() > 0.0 && physical > 0.0 {
            span.min(physical)
        } else {
            span
        }
    }

    /// The window of stable rates at radius `r_m` and angle `angle_rad` ([`window`], margin
    /// [`PUSH_MARGIN`]).
    pub fn window(&self, r_m: f64, angle_rad: f64) -> (f64, f64) {
        window(
            self.edge,
            self.rho_m,
            r_m,
            angle_rad,
            self.v_b_mps,
            self.mu,
            PUSH_MARGIN,
        )
    }

    /// The fastest counter-clockwise rate in `[floor, omega_max]` stable over the cell
    /// between `from_rad` and `to_rad` at radius `r_m` (the window at both ends), or `None`.
    pub fn cell_rate(&self, r_m: f64, from_rad: f64, to_rad: f64) -> Option<f64> {
        let (w0, w1) = (self.window(r_m, from_rad), self.window(r_m, to_rad));
        let (lo, hi) = (w0.0.max(w1.0), w0.1.min(w1.1));
        let rate = hi.min(self.omega_max_radps);
        (rate >= lo && rate >= self.floor_radps()).then_some(rate)
    }

    /// The least contact radius, m, at which pushing counter-clockwise through fence angle
    /// `angle_rad` is stable at some rate in `[floor, omega_max]` (margin
    /// [`PUSH_MARGIN`]); infinite when none is.
    pub fn min_radius_free(&self, angle_rad: f64) -> f64 {
        let span = self.omega_max_radps / self.floor_radps();
        (0..RATE_STEPS)
            .map(|i| self.omega_max_radps * span.powf(-(i as f64) / (RATE_STEPS - 1) as f64))
            .map(|w| min_radius_at(self.edge, self.rho_m, angle_rad, w, self.v_b_mps, self.mu))
            .fold(f64::INFINITY, f64::min)
    }

    /// The profile of a counter-clockwise push at radius `r_m` from `from_rad` to `to_rad`
    /// (> `from_rad`): per grid cell the fastest stable rate up to `omega_max`, equal rates
    /// merged; `None` when some cell has no stable rate.
    pub fn profile(&self, r_m: f64, from_rad: f64, to_rad: f64) -> Option<Profile> {
        let (n, step) = cells(from_rad, to_rad);
        let mut out: Profile = Vec::new();
        for i in 0..n {
            let a0 = from_rad + step * i as f64;
            let a1 = if i + 1 == n { to_rad } else { a0 + step };
            let w = self.cell_rate(r_m, a0, a1)?;
            match out.last_mut() {
                Some(last) if last.1 == w => last.0 = a1,
                _ => out.push((a1, w)),
            }
        }
        Some(out)
    }

    /// The rate of the first cell of [`Self::profile`] (the fence's rate as the push starts).
    pub fn start_rate(&self, r_m: f64, from_rad: f64, to_rad: f64) -> Option<f64> {
        let (n, step) = cells(from_rad, to_rad);
        let a1 = if n == 1 { to_rad } else { from_rad + step };
        self.cell_rate(r_m, from_rad, a1)
    }

    /// Estimated time of a push at radius `r_m` from `from_rad` to `to_rad`, s: eight
    /// samples of the fastest stable rate (the floor where none is stable).
    pub fn time_estimate_s(&self, r_m: f64, from_rad: f64, to_rad: f64) -> f64 {
        const N: usize = 8;
        let step = (to_rad - from_rad) / N as f64;
        let floor = self.floor_radps();
        (0..N)
            .map(|i| {
                let (lo, hi) = self.window(r_m, from_rad + step * (i as f64 + 0.5));
                let w = hi.min(self.omega_max_radps);
                let w = if w >= lo { w } else { 0.0 };
                step.abs() / w.max(floor)
            })
            .sum()
    }
}

/// A push profile: `(angle reached, rate)` segments, in order.
pub type Profile = Vec<(f64, f64)>;

/// The cells of a push from `from_rad` to `to_rad`: their number and signed width.
fn cells(from_rad: f64, to_rad: f64) -> (usize, f64) {
    let n = ((to_rad - from_rad).abs() / ANGLE_GRID_RAD).ceil().max(1.0) as usize;
    (n, (to_rad - from_rad) / n as f64)
}

/// Time a profile takes from `from_rad`, s.
pub fn profile_time_s(from_rad: f64, p: &[(f64, f64)]) -> f64 {
    let mut a = from_rad;
    p.iter()
        .map(|&(to, w)| {
            let t = (to - a).abs() / w;
            a = to;
            t
        })
        .sum()
}

/// Appends the profile's segments to `s` (which must end at the profile's start angle).
pub fn extend(s: &mut Schedule, p: &[(f64, f64)]) {
    for &(to, w) in p {
        s.move_to(to, w);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::feeder::stability::push_ok;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    fn edge(a: f64, b: f64, h: f64) -> HullEdge {
        HullEdge {
            index: 0,
            dir_rad: 0.0,
            len_m: a + b,
            a_m: a,
            h_m: h,
        }
    }

    #[test]
    fn the_window_is_where_the_wrench_conditions_hold() {
        // push_ok evaluates the fence wrench F_n, F_t, o directly; the window must contain
        // exactly the rates it accepts (away from the window's ends).
        let mut rng = StdRng::seed_from_u64(3);
        let mut inside = 0;
        for _ in 0..20_000 {
            let e = edge(
                rng.random_range(0.001..0.03),
                rng.random_range(0.001..0.03),
                rng.random_range(0.003..0.03),
            );
            let rho = rng.random_range(0.005..0.02);
            let r = rng.random_range(0.01..0.5);
            let th = rng.random_range(-1.3..1.3);
            let w = rng.random_range(-3.0..3.0);
            let mu = rng.random_range(0.0..0.8);
            let (lo, hi) = window(&e, rho, r, th, 0.05, mu, PUSH_MARGIN);
            if (w - lo).abs() < 1e-9 || (w - hi).abs() < 1e-9 {
                continue;
            }
            let ok = push_ok(&e, rho, r, th, w, 0.05, mu, PUSH_MARGIN);
            assert_eq!(
                ok,
                lo <= w && w <= hi,
                "{e:?} rho {rho} r {r} th {th} w {w} mu {mu}"
            );
            inside += usize::from(ok);
        }
        assert!(inside > 1000, "{inside}");
    }

    #[test]
    fn a_slow_push_holds_an_edge_whose_foot_is_near_its_end() {
        // a = 6.9 mm, b = 0.96 mm, h = 21.1 mm, rho = 11.7 mm, mu = 0.3, v_b = 5 cm/s.
        // At 2 rad/s and theta = 0 the resultant's offset o = omega (rho^2 + h^2)/(omega r
        // + v_b) must stay below k b = 0.9 b: r >= (omega (rho^2 + h^2)/(k b) - v_b)/omega
        // = 0.650 m. At 2/64 rad/s, o <= k b holds for every r >= a, so the free-rate
        // minimum radius at theta = 0 is the floor a.
        let e = edge(0.0069, 0.00096, 0.0211);
        let (rho, vb, mu) = (0.0117, 0.05, 0.3);
        let push = |mu| EdgePush {
            edge: &e,
            rho_m: rho,
            omega_max_radps: 2.0,
            v_b_mps: vb,
            mu,
        };
        let j = rho * rho + e.h_m * e.h_m;
        let fixed = (2.0 * j / (0.9 * e.b_m()) - vb) / 2.0;
        assert!((min_radius_at(&e, rho, 0.0, 2.0, vb, mu) - fixed).abs() < 1e-9);
        assert!((fixed - 0.650).abs() < 0.005, "{fixed}");
        let free = push(mu).min_radius_free(0.0);
        assert!((free - e.a_m).abs() < 1e-9, "{free}");
        // A push from 0 to 60 deg at r = 0.17 m: a profile exists, slow at first (below
        // the hand bound omega <= k b v_b / (rho^2 + h^2 - k b r) = 0.098 rad/s at 0), and
        // every cell's rate lies in the window at both of its ends.
        let p = push(mu).profile(0.17, 0.0, 60f64.to_radians()).unwrap();
        let bound = 0.9 * e.b_m() * vb / (j - 0.9 * e.b_m() * 0.17);
        assert!(
            (bound - 0.098).abs() < 0.002 && p[0].1 <= bound + 1e-12,
            "{p:?}"
        );
        let mut a = 0.0;
        for &(to, w) in &p {
            for th in [a, to] {
                let (lo, hi) = window(&e, rho, 0.17, th, vb, mu, PUSH_MARGIN);
                // (to an ulp: a cell end and the next cell start are computed apart)
                assert!(lo <= w + 1e-12 && w <= hi + 1e-12, "{th} {w} {lo} {hi}");
            }
            a = to;
        }
        assert!(push(0.0).profile(0.17, 0.0, 60f64.to_radians()).is_none());
        let t = profile_time_s(0.0, &p);
        assert!(
            t > 60f64.to_radians() / 2.0,
            "slower than the fastest rate: {t}"
        );
    }

    #[test]
    fn an_edge_whose_foot_is_at_its_end_starts_slower_than_the_span() {
        // Part 44's edge 2 of the feeding sweep: a = 5.84 mm, b = 0.57 mm, h = 31.02 mm,
        // rho = 17.36 mm. At theta = 0 the end-vertex row bounds omega by
        // v_b k b / (rho^2 + h^2 - k b r) <= v_b k b / (rho^2 + h^2) = 0.0203 rad/s at
        // r -> 0, below 2/64: with the span's floor the least radius is where 2/64 rad/s
        // is stable, r = (rho^2 + h^2)/(k b) - v_b / (2/64) = 0.863 m (hand). The edge's
        // floor, a quarter of 0.0203 rad/s, makes every radius from a up workable.
        let e = edge(0.00584, 0.00057, 0.03102);
        let (rho, vb, mu) = (0.01736, 0.05, 0.3);
        let push = EdgePush {
            edge: &e,
            rho_m: rho,
            omega_max_radps: 2.0,
            v_b_mps: vb,
            mu,
        };
        let j = rho * rho + e.h_m * e.h_m;
        let top0 = vb * 0.9 * e.b_m() / j;
        assert!((top0 - 0.0203).abs() < 1e-4, "{top0}");
        assert!((push.floor_radps() - 0.25 * top0).abs() < 1e-12);
        let old = j / (0.9 * e.b_m()) - vb / (2.0 / 64.0);
        assert!((old - 0.863).abs() < 0.002, "{old}");
        assert!((min_radius_at(&e, rho, 0.0, 2.0 / 64.0, vb, mu) - old).abs() < 1e-9);
        assert!((push.min_radius_free(0.0) - e.a_m).abs() < 1e-9);
        for r in [0.006, 0.05, 0.2, 0.8, 2.0] {
            let (lo, hi) = push.window(r, 0.0);
            assert!(lo <= push.floor_radps() && 4.0 * push.floor_radps() <= hi + 1e-15);
            assert!(push.profile(r, 0.0, 30f64.to_radians()).is_some(), "{r}");
        }
        // An edge with room (b = 10 mm) keeps the span's floor.
        let wide = edge(0.01, 0.01, 0.02);
        let wide_push = EdgePush {
            edge: &wide,
            ..push
        };
        assert_eq!(wide_push.floor_radps(), 2.0 / 64.0);
    }
}
