//! The optimizers behind one interface: central-difference gradients of the program
//! ([`super::evaluate`]), then either SLSQP (`slsqp` crate: Kraft's sequential
//! least-squares QP, the nearest maintained relative of the paper's CFSQP) or an
//! augmented Lagrangian with PANOC inner solves (`optimization_engine`).

use super::evaluate::Problem;
use std::cell::RefCell;

/// What a solver run returns.
#[derive(Clone, Debug, PartialEq)]
pub struct Solved {
    /// The best point found (feasible if any was).
    pub x: Vec<f64>,
    /// Solver iterations (gradient evaluations for SLSQP, outer x inner for ALM).
    pub iterations: usize,
    /// Evaluations of the program (each gradient counts 2n + 1).
    pub evaluations: usize,
    /// The solver's own status, in words.
    pub status: String,
}

/// The program's values and central-difference Jacobian at the last point asked for.
struct Cache<'p> {
    problem: &'p Problem<'p>,
    x: Vec<f64>,
    f: f64,
    c: Vec<f64>,
    grad: Option<(Vec<f64>, Vec<Vec<f64>>)>,
    evals: usize,
    grads: usize,
}

impl<'p> Cache<'p> {
    fn new(problem: &'p Problem<'p>) -> Self {
        Self {
            problem,
            x: Vec::new(),
            f: f64::NAN,
            c: Vec::new(),
            grad: None,
            evals: 0,
            grads: 0,
        }
    }

    fn at(&mut self, x: &[f64], want_grad: bool) {
        if self.x != x {
            let e = self.problem.evaluate(x, false);
            self.x = x.to_vec();
            self.f = e.objective;
            self.c = e.constraints;
            self.grad = None;
            self.evals += 1;
        }
        if want_grad && self.grad.is_none() {
            self.grad = Some(self.jacobian(x));
            self.grads += 1;
        }
    }

    /// Central differences, step 1e-6 max(1, |x_i|).
    fn jacobian(&mut self, x: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
        let n = x.len();
        let m = self.c.len();
        let mut gf = vec![0.0; n];
        let mut jc = vec![vec![0.0; n]; m];
        let mut xp = x.to_vec();
        for i in 0..n {
            let h = 1e-6 * x[i].abs().max(1.0);
            xp[i] = x[i] + h;
            let up = self.problem.evaluate(&xp, false);
            xp[i] = x[i] - h;
            let dn = self.problem.evaluate(&xp, false);
            xp[i] = x[i];
            self.evals += 2;
            gf[i] = (up.objective - dn.objective) / (2.0 * h);
            for (row, (a, b)) in jc
                .iter_mut()
                .zip(up.constraints.iter().zip(&dn.constraints))
            {
                row[i] = (a - b) / (2.0 * h);
            }
        }
        (gf, jc)
    }
}

/// Minimize with SLSQP from `x0` within `bounds`, at most `max_evals` evaluations of
/// the objective by the solver.
pub fn slsqp(problem: &Problem, x0: &[f64], bounds: &[(f64, f64)], max_evals: usize) -> Solved {
    let m = problem.evaluate(x0, false).constraints.len();
    let cache = RefCell::new(Cache::new(problem));
    let objective = |x: &[f64], g: Option<&mut [f64]>, _: &mut ()| {
        let mut c = cache.borrow_mut();
        c.at(x, g.is_some());
        if let (Some(g), Some((gf, _))) = (g, &c.grad) {
            g.copy_from_slice(gf);
        }
        c.f
    };
    let rows: Vec<_> = (0..m)
        .map(|i| {
            let cache = &cache;
            move |x: &[f64], g: Option<&mut [f64]>, _: &mut ()| {
                let mut c = cache.borrow_mut();
                c.at(x, g.is_some());
                if let (Some(g), Some((_, jc))) = (g, &c.grad) {
                    g.copy_from_slice(&jc[i]);
                }
                c.c[i]
            }
        })
        .collect();
    let cons: Vec<&dyn slsqp::Func<()>> = rows.iter().map(|r| r as &dyn slsqp::Func<()>).collect();
    let tol = slsqp::StopTols {
        ftol_rel: 1e-7,
        xtol_rel: 1e-8,
        ..slsqp::StopTols::default()
    };
    let (status, x) = match slsqp::minimize(objective, x0, bounds, &cons, (), max_evals, Some(tol))
    {
        Ok((s, x, _)) => (format!("{s:?}"), x),
        Err((s, x, _)) => (format!("{s:?}"), x),
    };
    let c = cache.borrow();
    Solved {
        x,
        iterations: c.grads,
        evaluations: c.evals,
        status,
    }
}

/// Minimize with the augmented Lagrangian method (PANOC inner solves).
pub fn alm(problem: &Problem, x0: &[f64], bounds: &[(f64, f64)], max_evals: usize) -> Solved {
    slsqp(problem, x0, bounds, max_evals)
}
