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

/// Minimize with the augmented Lagrangian method of `optimization_engine` (OpEn):
/// `F1(x) = c(x)` must lie in `C = (-inf, 0]^m`, `x` in the bound rectangle; PANOC
/// solves the inner problems with the same central-difference gradients. At most
/// `max_evals` inner iterations per outer iteration, 50 outer iterations.
pub fn alm(problem: &Problem, x0: &[f64], bounds: &[(f64, f64)], max_evals: usize) -> Solved {
    use optimization_engine::alm::{
        AlmCache, AlmFactory, AlmOptimizer, AlmProblem, NO_JACOBIAN_MAPPING, NO_MAPPING,
    };
    use optimization_engine::constraints::Rectangle;
    use optimization_engine::panoc::PANOCCache;
    use optimization_engine::FunctionCallResult;
    let n = x0.len();
    let m = problem.evaluate(x0, false).constraints.len();
    let cache = RefCell::new(Cache::new(problem));
    let f = |u: &[f64], cost: &mut f64| -> FunctionCallResult {
        let mut c = cache.borrow_mut();
        c.at(u, false);
        *cost = c.f;
        Ok(())
    };
    let df = |u: &[f64], grad: &mut [f64]| -> FunctionCallResult {
        let mut c = cache.borrow_mut();
        c.at(u, true);
        if let Some((gf, _)) = &c.grad {
            grad.copy_from_slice(gf);
        }
        Ok(())
    };
    let f1 = |u: &[f64], out: &mut [f64]| -> FunctionCallResult {
        let mut c = cache.borrow_mut();
        c.at(u, false);
        out.copy_from_slice(&c.c);
        Ok(())
    };
    let jf1t = |u: &[f64], d: &[f64], res: &mut [f64]| -> FunctionCallResult {
        let mut c = cache.borrow_mut();
        c.at(u, true);
        res.iter_mut().for_each(|r| *r = 0.0);
        if let Some((_, jc)) = &c.grad {
            for (row, di) in jc.iter().zip(d) {
                for (r, j) in res.iter_mut().zip(row) {
                    *r += j * di;
                }
            }
        }
        Ok(())
    };
    let zeros = vec![0.0; m];
    let y_max = vec![1e8; m];
    let lo: Vec<f64> = bounds.iter().map(|b| b.0).collect();
    let hi: Vec<f64> = bounds.iter().map(|b| b.1).collect();
    let set_c = Rectangle::new(None, Some(&zeros));
    let factory = AlmFactory::new(
        f,
        df,
        Some(f1),
        Some(jf1t),
        NO_MAPPING,
        NO_JACOBIAN_MAPPING,
        Some(set_c),
        0,
    );
    let alm_problem = AlmProblem::new(
        Rectangle::new(Some(&lo), Some(&hi)),
        Some(Rectangle::new(None, Some(&zeros))),
        Some(Rectangle::new(Some(&zeros), Some(&y_max))),
        |u: &[f64], xi: &[f64], cost: &mut f64| factory.psi(u, xi, cost),
        |u: &[f64], xi: &[f64], grad: &mut [f64]| factory.d_psi(u, xi, grad),
        Some(f1),
        NO_MAPPING,
        m,
        0,
    );
    let mut alm_cache = AlmCache::new(PANOCCache::new(n, 1e-5, 10), m, 0);
    let mut opt = AlmOptimizer::new(&mut alm_cache, alm_problem)
        .with_delta_tolerance(1e-6)
        .with_epsilon_tolerance(1e-5)
        .with_max_outer_iterations(50)
        .with_max_inner_iterations(max_evals)
        .with_initial_penalty(10.0)
        .with_penalty_update_factor(5.0);
    let mut x = x0.to_vec();
    let (status, iterations) = match opt.solve(&mut x) {
        Ok(r) => (format!("{:?}", r.exit_status()), r.num_inner_iterations()),
        Err(e) => (format!("{e:?}"), 0),
    };
    let c = cache.borrow();
    Solved {
        x,
        iterations,
        evaluations: c.evals,
        status,
    }
}
