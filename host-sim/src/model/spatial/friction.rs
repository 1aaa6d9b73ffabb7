//! Coulomb friction at a bat: an effect that is off by default (`friction_coefficient` 0:
//! no code runs).
//!
//! The ball is a point mass without spin and the paddle infinitely heavy. The normal impulse
//! per unit mass is j_n = (1 + alpha) |u_n|, u_n = n . (b' - v_p) < 0; the relative velocity's
//! tangential part u_t = (b' - v_p) - u_n n is opposed by an impulse of at most mu j_n:
//!
//! ```text
//! |u_t| <= mu j_n:  b'+ -= u_t                      (sticks: leaves with the paddle's tangential velocity)
//! otherwise:        b'+ -= mu j_n u_t / |u_t|       (slides)
//! ```
//!
//! applied after the frictionless restitution law, which sets the normal part.

use dexter_core::spatial::dot;

/// Add Coulomb friction of coefficient `mu` (>= 0) to `after`, the ball's velocity after a
/// frictionless impact, given its velocity `before`, the paddle's velocity `paddle_mps` at
/// the contact, the unit normal `n` and the restitution `alpha`.
pub fn add_friction(
    mu: f64,
    n: &[f64; 3],
    before: &[f64; 3],
    paddle_mps: &[f64; 3],
    alpha: f64,
    after: &mut [f64; 3],
) {
    let rel: [f64; 3] = core::array::from_fn(|i| before[i] - paddle_mps[i]);
    let un = dot(n, &rel);
    let ut: [f64; 3] = core::array::from_fn(|i| rel[i] - un * n[i]);
    let slip = dot(&ut, &ut).sqrt();
    let bound = mu * (1.0 + alpha) * un.abs();
    let scale = if slip <= bound { 1.0 } else { bound / slip };
    for (a, t) in after.iter_mut().zip(ut) {
        *a -= scale * t;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Level resting paddle (n up), ball at (u, 0, -w): sliding takes mu (1 + alpha) w off
    /// u; enough friction stops the tangential motion; the normal part is untouched.
    #[test]
    fn sliding_and_sticking_by_hand() {
        let (n, still) = ([0.0, 0.0, 1.0], [0.0; 3]);
        let before = [1.0, 0.0, -3.0];
        let frictionless = [1.0, 0.0, 0.7 * 3.0];
        let mut slid = frictionless;
        add_friction(0.1, &n, &before, &still, 0.7, &mut slid);
        assert!((slid[0] - (1.0 - 0.1 * 1.7 * 3.0)).abs() < 1e-15);
        assert_eq!((slid[1], slid[2]), (0.0, frictionless[2]));
        let mut stuck = frictionless;
        add_friction(0.5, &n, &before, &still, 0.7, &mut stuck);
        assert!(stuck[0].abs() < 1e-15);
        // a paddle moving along x at the ball's speed: nothing to oppose
        let mut along = frictionless;
        add_friction(0.5, &n, &before, &[1.0, 0.0, 0.0], 0.7, &mut along);
        assert_eq!(along, frictionless);
    }
}
