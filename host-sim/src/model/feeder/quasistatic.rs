//! Quasistatic motion of a part on the belt touched by the fence: which contact mode
//! holds and how the part moves.
//!
//! ## Equations
//!
//! Inertia is neglected (quasistatic): the fence's contact wrench balances the belt's
//! support friction. With the ellipsoidal limit surface of [`super::support`], the
//! friction wrench is `-k M V_rel` with `M = diag(1, 1, rho^2)`, `k > 0` a scale and
//! `V_rel = V - V_belt` the part's twist relative to the belt, `V = (v, omega)` the COM
//! velocity and angular rate in the world, `V_belt = (0, -v_b, 0)`. Fence contact forces
//! are `lambda_j d_j` at points `p_j` (direction `d_j`, moment arm `q_j = p_j - c`),
//! wrench `w_j = (d_j, q_j x d_j)`. Balance `sum lambda_j w_j = k M V_rel` is homogeneous
//! in the forces, and every contact condition below is too, so `k` is absorbed into the
//! lambdas:
//!
//! ```text
//! V = V_belt + M^-1 sum_j lambda_j w_j                                   (1)
//! ```
//!
//! For a fence at angle theta turning at omega_f about the pivot (origin), with normal
//! `n = (-sin theta, cos theta)` (the part's side) and tangent `t = (cos theta, sin theta)`,
//! a contact point `p` has normal and tangential relative velocities
//!
//! ```text
//! g_n = (n, q x n) . V - omega_f (p x n),   g_t = (t, q x t) . V - omega_f (p x t)   (2)
//! ```
//!
//! (the fence point's velocity is `omega_f p^perp`, and `n . (omega q^perp) = omega q x n`).
//! Coulomb friction with fence coefficient mu: a contact **sticks** (`g_n = g_t = 0`,
//! `lambda_n >= 0`, `|lambda_t| <= mu lambda_n`), **slides** with `sigma = sign(g_t)`
//! (`g_n = 0`, force along `n - sigma mu t`, `lambda >= 0`), or **separates**
//! (`lambda = 0`, `g_n >= 0`). Two contacts on the (straight) fence line share the
//! tangential state: both touching forces the part to turn with the fence, so their
//! relative motion is the same slide along `t`.
//!
//! [`solve`] substitutes (1) into the active constraints of (2), solves the <= 3x3 linear
//! system for the lambdas, and accepts the first mode whose inequalities hold, in the
//! order line stick, line slide, point stick, point slide, free. Trying stick first is
//! the stable-pushing convention of Lynch & Mason (1996): a push is stable when sticking
//! is consistent; with a known, strictly convex limit surface the consistent modes here
//! are unique in every case the tests exercise.
//!
//! **Drift** is the free mode: `V = V_belt`, the part moves with the belt.

use super::geometry::{Pose, Vec2};
use super::part::Part;

/// Which contact mode holds between the fence and the part's hull vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// No contact: the part drifts with the belt.
    Free,
    /// One hull vertex touches and sticks to the fence.
    PointStick(usize),
    /// One hull vertex slides along the fence in direction `sigma` (+1 = +t).
    PointSlide(usize, i8),
    /// A hull edge lies flush on the fence and moves with it: a stable push.
    LineStick(usize, usize),
    /// A hull edge lies flush on the fence and slides along it in direction `sigma`.
    LineSlide(usize, usize, i8),
}

/// The fence's angle and angular rate at an instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fence {
    /// theta, rad from +x.
    pub angle_rad: f64,
    /// omega_f = d theta / dt, rad/s (> 0 counter-clockwise).
    pub rate_radps: f64,
}

impl Fence {
    /// Unit normal, pointing to the side the part lies on.
    pub fn normal(&self) -> Vec2 {
        Vec2::from_angle(self.angle_rad).perp()
    }
    /// Unit tangent, pointing from the pivot along the fence.
    pub fn tangent(&self) -> Vec2 {
        Vec2::from_angle(self.angle_rad)
    }
}

/// The physical constants of one instant's problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium {
    /// v_b, belt speed, m/s; the belt moves in -y (a negative value reverses it).
    pub belt_speed_mps: f64,
    /// mu, Coulomb friction between part and fence.
    pub fence_mu: f64,
}

/// The part's motion at an instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    /// COM velocity, world, m/s.
    pub com_mps: Vec2,
    /// Angular rate, rad/s.
    pub omega_radps: f64,
    /// The mode that holds.
    pub mode: Mode,
    /// Total fence force on the part along the fence normal, in the scale-free units of
    /// eq. (1) (m/s: the relative twist it causes); 0 when free.
    pub normal_force: f64,
    /// Total fence force along the fence tangent, same units.
    pub tangential_force: f64,
}

/// One unknown force: direction and application point.
#[derive(Clone, Copy)]
struct Force {
    dir: Vec2,
    at: Vec2,
}

struct Ctx<'a> {
    c: Vec2,
    rho2: f64,
    fence: Fence,
    medium: &'a Medium,
}

impl Ctx<'_> {
    fn wrench(&self, f: Force) -> [f64; 3] {
        [f.dir.x, f.dir.y, (f.at - self.c).cross(f.dir)]
    }
    fn belt(&self) -> [f64; 3] {
        [0.0, -self.medium.belt_speed_mps, 0.0]
    }
    /// Relative velocity of part minus fence at `p` along `dir` for twist `v` (eq. 2).
    fn rel(&self, v: &[f64; 3], p: Vec2, dir: Vec2) -> f64 {
        let w = self.wrench(Force { dir, at: p });
        w[0] * v[0] + w[1] * v[1] + w[2] * v[2] - self.fence.rate_radps * p.cross(dir)
    }
    /// Twist of eq. (1) for forces `fs` with magnitudes `lam`.
    fn twist(&self, fs: &[Force], lam: &[f64]) -> [f64; 3] {
        let mut v = self.belt();
        for (f, l) in fs.iter().zip(lam) {
            let w = self.wrench(*f);
            v[0] += l * w[0];
            v[1] += l * w[1];
            v[2] += l * w[2] / self.rho2;
        }
        v
    }
    /// Solves for the magnitudes of `fs` making the relative velocities at
    /// `rows = (point, direction)` zero.
    fn magnitudes(&self, fs: &[Force], rows: &[(Vec2, Vec2)]) -> Option<Vec<f64>> {
        let n = fs.len();
        let zero = vec![0.0; n];
        let v0 = self.twist(fs, &zero);
        let mut a = vec![vec![0.0; n + 1]; n];
        for (j, &(p, d)) in rows.iter().enumerate() {
            for k in 0..n {
                let mut unit = zero.clone();
                unit[k] = 1.0;
                let vk = self.twist(fs, &unit);
                a[j][k] = self.rel(&vk, p, d) - self.rel(&v0, p, d);
            }
            a[j][n] = -self.rel(&v0, p, d);
        }
        solve_dense(a)
    }
}

/// Gaussian elimination with partial pivoting on an augmented n x (n+1) matrix.
fn solve_dense(mut a: Vec<Vec<f64>>) -> Option<Vec<f64>> {
    let n = a.len();
    for col in 0..n {
        let piv = (col..n).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, piv);
        let (top, rest) = a.split_at_mut(col + 1);
        let pivot_row = &top[col];
        for row in rest.iter_mut() {
            let k = row[col] / pivot_row[col];
            for (x, p) in row.iter_mut().zip(pivot_row.iter()).skip(col) {
                *x -= k * p;
            }
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|c| a[r][c] * x[c]).sum();
        x[r] = (a[r][n] - s) / a[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Solves the instant's quasistatic problem for the part at `pose` with hull vertices
/// `touching` (indices into [`Part::hull`], at most 2, on the fence line).
pub fn solve(
    part: &Part,
    pose: &Pose,
    fence: Fence,
    medium: &Medium,
    touching: &[usize],
) -> Motion {
    let ctx = Ctx {
        c: pose.com_m,
        rho2: part.rho_m * part.rho_m,
        fence,
        medium,
    };
    let pts: Vec<(usize, Vec2)> = touching
        .iter()
        .map(|&i| (i, pose.to_world(part.hull[i])))
        .collect();
    let scale =
        medium.belt_speed_mps.abs() + fence.rate_radps.abs() * (pose.com_m.norm() + part.radius_m);
    let eps = 1e-9 * scale.max(1e-12);
    for cand in candidates(&pts) {
        if let Some(m) = try_mode(&ctx, &pts, cand, eps) {
            return m;
        }
    }
    // Unreachable in exact arithmetic (free is always a candidate once the others fail
    // and their inequalities are relaxed by eps); keep drifting rather than stop.
    let v = ctx.belt();
    Motion {
        com_mps: Vec2::new(v[0], v[1]),
        omega_radps: v[2],
        mode: Mode::Free,
        normal_force: 0.0,
        tangential_force: 0.0,
    }
}

fn candidates(pts: &[(usize, Vec2)]) -> Vec<Mode> {
    let mut out = Vec::with_capacity(10);
    if pts.len() == 2 {
        let (a, b) = (pts[0].0, pts[1].0);
        out.extend([
            Mode::LineStick(a, b),
            Mode::LineSlide(a, b, 1),
            Mode::LineSlide(a, b, -1),
        ]);
    }
    for &(i, _) in pts {
        out.push(Mode::PointStick(i));
    }
    for &(i, _) in pts {
        out.extend([Mode::PointSlide(i, 1), Mode::PointSlide(i, -1)]);
    }
    out.push(Mode::Free);
    out
}

/// Unknown forces, zero-velocity rows and active vertices of `mode`.
type System = (Vec<Force>, Vec<(Vec2, Vec2)>, Vec<usize>);

fn point_of(pts: &[(usize, Vec2)], i: usize) -> Vec2 {
    pts.iter()
        .find(|p| p.0 == i)
        .map(|p| p.1)
        .unwrap_or_default()
}

/// The linear system of `mode`: which forces are unknown and which relative velocities
/// vanish.
fn system(ctx: &Ctx, pts: &[(usize, Vec2)], mode: Mode) -> System {
    let (n, t, mu) = (ctx.fence.normal(), ctx.fence.tangent(), ctx.medium.fence_mu);
    let at = |i| point_of(pts, i);
    let slide = |s: i8| n - t.scale(f64::from(s) * mu);
    let f = |dir, at| Force { dir, at };
    match mode {
        Mode::Free => (vec![], vec![], vec![]),
        Mode::PointStick(i) => (
            vec![f(n, at(i)), f(t, at(i))],
            vec![(at(i), n), (at(i), t)],
            vec![i],
        ),
        Mode::PointSlide(i, s) => (vec![f(slide(s), at(i))], vec![(at(i), n)], vec![i]),
        Mode::LineStick(a, b) => {
            let fs = vec![f(n, at(a)), f(n, at(b)), f(t, at(a))];
            (fs, vec![(at(a), n), (at(b), n), (at(a), t)], vec![a, b])
        }
        Mode::LineSlide(a, b, s) => {
            let fs = vec![f(slide(s), at(a)), f(slide(s), at(b))];
            (fs, vec![(at(a), n), (at(b), n)], vec![a, b])
        }
    }
}

fn try_mode(ctx: &Ctx, pts: &[(usize, Vec2)], mode: Mode, eps: f64) -> Option<Motion> {
    let (n, t, mu) = (ctx.fence.normal(), ctx.fence.tangent(), ctx.medium.fence_mu);
    let at = |i| point_of(pts, i);
    let (forces, rows, active) = system(ctx, pts, mode);
    let lam = ctx.magnitudes(&forces, &rows)?;
    let v = ctx.twist(&forces, &lam);
    let ok = match mode {
        Mode::Free => true,
        Mode::PointStick(_) => lam[0] >= -eps && lam[1].abs() <= mu * lam[0] + eps,
        Mode::LineStick(..) => {
            lam[0] >= -eps && lam[1] >= -eps && lam[2].abs() <= mu * (lam[0] + lam[1]) + eps
        }
        Mode::PointSlide(i, s) => lam[0] >= -eps && f64::from(s) * ctx.rel(&v, at(i), t) > eps,
        Mode::LineSlide(a, _, s) => {
            lam.iter().all(|&l| l >= -eps) && f64::from(s) * ctx.rel(&v, at(a), t) > eps
        }
    };
    let separating = pts
        .iter()
        .filter(|p| !active.contains(&p.0))
        .all(|&(_, p)| ctx.rel(&v, p, n) >= -eps);
    let total = |d: Vec2| {
        forces
            .iter()
            .zip(&lam)
            .map(|(f, l)| l * f.dir.dot(d))
            .sum::<f64>()
    };
    (ok && separating).then(|| Motion {
        com_mps: Vec2::new(v[0], v[1]),
        omega_radps: v[2],
        mode,
        normal_force: total(n),
        tangential_force: total(t),
    })
}
