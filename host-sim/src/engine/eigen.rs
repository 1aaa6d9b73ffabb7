//! Eigenvalues of a small real matrix (n <= [`MAX_N`]), dimensionless: the characteristic
//! polynomial by Faddeev–LeVerrier (exact recurrences, n matrix products), then its roots by
//! the Aberth–Ehrlich simultaneous iteration (cubically convergent for simple roots, capped
//! at [`MAX_ITERATIONS`]), then one Newton polish per simple root. Complex roots of a real
//! polynomial are returned as conjugate pairs (re, im), im > 0 first.
//!
//! Accuracy: simple eigenvalues to a few ulp of the polynomial's conditioning; a double
//! eigenvalue (e.g. at kappa = 1 or kappa_crit, where the tilt pair merges) can only be
//! resolved to about sqrt(eps) relative — a property of the problem, not of the method.

/// Largest matrix size.
pub const MAX_N: usize = 6;
/// Cap on Aberth iterations.
pub const MAX_ITERATIONS: usize = 500;
/// Largest distance (relative) between a complex root and the conjugate of its partner,
/// and largest imaginary part of an unpaired root that is taken as rounding of a real one:
/// well above the ~1e-8 to which a double root is resolved.
pub const PAIR_TOL: f64 = 1e-6;

#[derive(Clone, Copy, Debug, PartialEq)]
struct C {
    re: f64,
    im: f64,
}

impl C {
    fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }
    fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn div(self, o: C) -> C {
        // Smith's algorithm
        if o.re.abs() >= o.im.abs() {
            let r = o.im / o.re;
            let d = o.re + o.im * r;
            C::new((self.re + self.im * r) / d, (self.im - self.re * r) / d)
        } else {
            let r = o.re / o.im;
            let d = o.re * r + o.im;
            C::new((self.re * r + self.im) / d, (self.im * r - self.re) / d)
        }
    }
    fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }
}

/// Coefficients c_0..=c_n of det(lambda I - A) (c_n = 1), Faddeev–LeVerrier.
pub fn characteristic_polynomial(a: &[Vec<f64>]) -> Vec<f64> {
    let n = a.len();
    let mut c = vec![0.0; n + 1];
    c[n] = 1.0;
    let mut m = vec![vec![0.0; n]; n];
    for k in 1..=n {
        // M_k = A M_{k-1} + c_{n-k+1} I
        let mut next = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in 0..n {
                let mut s = 0.0;
                for (p, mp) in m.iter().enumerate() {
                    s += a[i][p] * mp[j];
                }
                next[i][j] = s + if i == j { c[n - k + 1] } else { 0.0 };
            }
        }
        // c_{n-k} = -tr(A M_k) / k
        let mut tr = 0.0;
        for i in 0..n {
            for p in 0..n {
                tr += a[i][p] * next[p][i];
            }
        }
        c[n - k] = -tr / k as f64;
        m = next;
    }
    c
}

fn horner(c: &[f64], z: C) -> (C, C) {
    // p(z) and p'(z)
    let n = c.len() - 1;
    let mut p = C::new(c[n], 0.0);
    let mut dp = C::new(0.0, 0.0);
    for k in (0..n).rev() {
        dp = dp.mul(z).add(p);
        p = p.mul(z).add(C::new(c[k], 0.0));
    }
    (p, dp)
}

/// Eigenvalues of the square matrix `a` (rows; n <= [`MAX_N`]) as (re, im) pairs, sorted by
/// decreasing modulus; `None` if the matrix is empty, not square, too large or not finite,
/// or the iteration did not converge within its cap.
pub fn eigenvalues(a: &[Vec<f64>]) -> Option<Vec<(f64, f64)>> {
    let n = a.len();
    if n == 0
        || n > MAX_N
        || a.iter()
            .any(|r| r.len() != n || r.iter().any(|x| !x.is_finite()))
    {
        return None;
    }
    let c = characteristic_polynomial(a);
    // Cauchy bound on the roots' moduli
    let bound = 1.0 + c[..n].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut z: Vec<C> = (0..n)
        .map(|k| {
            let ang = 0.4 + 2.0 * core::f64::consts::PI * k as f64 / n as f64;
            C::new(0.5 * bound * ang.cos(), 0.5 * bound * ang.sin())
        })
        .collect();
    let mut converged = false;
    for _ in 0..MAX_ITERATIONS {
        let mut biggest = 0.0f64;
        for i in 0..n {
            let (p, dp) = horner(&c, z[i]);
            if p.abs() == 0.0 {
                continue;
            }
            let ratio = p.div(dp);
            let mut s = C::new(0.0, 0.0);
            for j in 0..n {
                if j != i {
                    s = s.add(C::new(1.0, 0.0).div(z[i].sub(z[j])));
                }
            }
            let w = ratio.div(C::new(1.0, 0.0).sub(ratio.mul(s)));
            if !(w.re.is_finite() && w.im.is_finite()) {
                continue;
            }
            z[i] = z[i].sub(w);
            biggest = biggest.max(w.abs() / z[i].abs().max(1e-300));
        }
        if biggest <= 4.0 * f64::EPSILON {
            converged = true;
            break;
        }
    }
    if !converged {
        // multiple roots converge linearly: accept if the residual is at rounding level
        let scale = c.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let ok = z.iter().all(|&zi| {
            let (p, _) = horner(&c, zi);
            p.abs() <= 1e-8 * scale * (1.0 + zi.abs()).powi(n as i32)
        });
        if !ok {
            return None;
        }
    }
    // clean up: tiny imaginary parts are rounding; conjugate pairs made exact
    let mut out: Vec<(f64, f64)> = z
        .iter()
        .map(|zi| {
            if zi.im.abs() <= 1e-13 * zi.abs().max(1.0) {
                (zi.re, 0.0)
            } else {
                (zi.re, zi.im)
            }
        })
        .collect();
    pair_conjugates(&mut out);
    out.sort_by(|a, b| {
        let (ma, mb) = (a.0.hypot(a.1), b.0.hypot(b.1));
        mb.total_cmp(&ma).then(b.1.total_cmp(&a.1))
    });
    Some(out)
}

/// Make the complex roots exact conjugate pairs: each root is paired with the nearest root
/// of opposite imaginary sign if that is its conjugate to within [`PAIR_TOL`]; an unpaired
/// root with an imaginary part below that is taken as real.
fn pair_conjugates(out: &mut [(f64, f64)]) {
    let n = out.len();
    let mut paired = vec![false; n];
    for i in 0..n {
        if paired[i] || out[i].1 == 0.0 {
            continue;
        }
        let mut best: Option<(usize, f64)> = None;
        for j in 0..n {
            if j == i || paired[j] || out[j].1 == 0.0 || out[j].1.signum() == out[i].1.signum() {
                continue;
            }
            let d = (out[j].0 - out[i].0).hypot(out[j].1 + out[i].1);
            if best.is_none_or(|(_, bd)| d < bd) {
                best = Some((j, d));
            }
        }
        // a partner is a conjugate only if it is one to within the accuracy of a double
        // root (two approximations of a near-double real root can both come out with
        // imaginary parts of one sign: neither is then paired with a far root)
        let scale = out[i].0.hypot(out[i].1).max(1.0);
        let best = best.filter(|&(_, d)| d <= PAIR_TOL * scale);
        if best.is_none() && out[i].1.abs() <= PAIR_TOL * scale {
            out[i].1 = 0.0;
        }
        if let Some((j, _)) = best {
            let re = 0.5 * (out[i].0 + out[j].0);
            let im = 0.5 * (out[i].1.abs() + out[j].1.abs());
            out[i] = (re, im);
            out[j] = (re, -im);
            paired[i] = true;
            paired[j] = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A near-double real root beside a complex pair (the lossless map's 1, 1 and eq. 11's
    /// pair at 1 < kappa < kappa_crit), perturbed in every entry: the roots near 1 can come
    /// out with imaginary parts of one sign; they must never be paired with the far pair.
    #[test]
    fn a_near_double_root_is_not_paired_with_a_far_root() {
        let (c, s) = (0.65f64, (1.0f64 - 0.65 * 0.65).sqrt());
        let base = [
            [c, 0.0, 0.0, s],
            [-33.7, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [-s, 0.0, 0.0, c],
        ];
        let mut state = 12345u64;
        for trial in 0..200 {
            let m: Vec<Vec<f64>> = base
                .iter()
                .map(|r| {
                    r.iter()
                        .map(|x| {
                            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                            x + 5e-10 * ((state >> 33) as f64 / (1u64 << 31) as f64 - 0.5)
                        })
                        .collect()
                })
                .collect();
            let ev = eigenvalues(&m).unwrap();
            let want = [(1.0, 0.0), (1.0, 0.0), (c, s), (c, -s)];
            for (re, im) in &ev {
                let d = want
                    .iter()
                    .map(|w| (re - w.0).hypot(im - w.1))
                    .fold(f64::INFINITY, f64::min);
                assert!(d < 1e-4, "trial {trial}: {ev:?}");
            }
        }
    }
}
