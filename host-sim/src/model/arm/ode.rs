//! The one integrator of the arm model: classic RK4 for psi'' = f(t, psi, psi').

/// One RK4 step of psi'' = acc(t, psi, psi').
pub fn rk4_step(
    acc: &impl Fn(f64, f64, f64) -> f64,
    t: f64,
    psi: f64,
    w: f64,
    h: f64,
) -> (f64, f64) {
    let k1 = (w, acc(t, psi, w));
    let k2 = (
        w + 0.5 * h * k1.1,
        acc(t + 0.5 * h, psi + 0.5 * h * k1.0, w + 0.5 * h * k1.1),
    );
    let k3 = (
        w + 0.5 * h * k2.1,
        acc(t + 0.5 * h, psi + 0.5 * h * k2.0, w + 0.5 * h * k2.1),
    );
    let k4 = (w + h * k3.1, acc(t + h, psi + h * k3.0, w + h * k3.1));
    (
        psi + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
        w + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
    )
}
