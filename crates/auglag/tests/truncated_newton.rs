//! The truncated-Newton inner solver: Newton's convergence on an ill-conditioned quadratic,
//! with the problem's exact Hessian products or with difference quotients, and the
//! augmented Lagrangian's Hessian assembled from the documented formula.

use auglag::{InnerSolver, Options, Phr, Problem, StopReason, minimize};

/// f(x) = ½ Σ dᵢ (xᵢ − 1)² with dᵢ from 1 to 1e4, on xᵢ ≤ 0.5 for the first variables; with
/// `constrained`, also h(x) = Σ xᵢ − s = 0.
struct Quadratic {
    d: Vec<f64>,
    exact_hessian: bool,
    constrained: bool,
}

impl Quadratic {
    fn new(n: usize, exact_hessian: bool, constrained: bool) -> Self {
        let d = (0..n)
            .map(|i| 10f64.powf(4.0 * i as f64 / (n - 1) as f64))
            .collect();
        Self {
            d,
            exact_hessian,
            constrained,
        }
    }
}

impl Problem for Quadratic {
    fn dim(&self) -> usize {
        self.d.len()
    }
    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(f64::NEG_INFINITY);
        upper.fill(f64::INFINITY);
        upper[..3].fill(0.5);
    }
    fn n_eq(&self) -> usize {
        usize::from(self.constrained)
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        if let Some(g) = grad {
            for ((g, &d), &x) in g.iter_mut().zip(&self.d).zip(x) {
                *g = d * (x - 1.0);
            }
        }
        0.5 * self
            .d
            .iter()
            .zip(x)
            .map(|(d, x)| d * (x - 1.0) * (x - 1.0))
            .sum::<f64>()
    }
    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        if self.constrained {
            c[0] = x.iter().sum::<f64>() - 10.0;
        }
    }
    fn constraints_jt_times(&self, _x: &[f64], w: &[f64], out: &mut [f64]) {
        if self.constrained {
            out.iter_mut().for_each(|o| *o += w[0]);
        }
    }
    fn hessian_times(&self, x: &[f64], phr: &Phr<'_>, v: &[f64], out: &mut [f64]) -> bool {
        if !self.exact_hessian {
            return false;
        }
        let sf = phr.objective_scale();
        for ((o, &d), &vi) in out.iter_mut().zip(&self.d).zip(v) {
            *o = sf * d * vi;
        }
        if self.constrained {
            // ∇²h = 0; the rank-one term ρ s² ∇h ∇hᵀ v.
            let mut c = [0.0];
            self.constraints(x, &mut c);
            let w = phr.curvature(0, c[0]) * v.iter().sum::<f64>();
            out.iter_mut().for_each(|o| *o += w);
        }
        true
    }
}

fn solve(problem: &Quadratic, solver: InnerSolver) -> auglag::Solution {
    let options = Options::default()
        .with_inner_solver(solver)
        .with_optimality_tolerance(1e-8)
        .with_feasibility_tolerance(1e-8);
    minimize(problem, &vec![0.0; problem.dim()], &options).unwrap()
}

#[test]
fn newton_steps_solve_an_ill_conditioned_quadratic_in_few_iterations() {
    for exact in [true, false] {
        let problem = Quadratic::new(40, exact, false);
        let newton = solve(&problem, InnerSolver::TruncatedNewton);
        assert_eq!(
            newton.report.stop_reason,
            StopReason::Converged,
            "exact {exact}"
        );
        for (i, &x) in newton.x.iter().enumerate() {
            let expected = if i < 3 { 0.5 } else { 1.0 };
            assert!((x - expected).abs() < 1e-7, "x[{i}] = {x}, exact {exact}");
        }
        assert!(newton.report.hessian_products > 0);
        let lbfgs = solve(&problem, InnerSolver::ProjectedLbfgs);
        assert!(
            newton.report.inner_iterations * 3 < lbfgs.report.inner_iterations,
            "exact {exact}: Newton {} inner iterations, L-BFGS {}",
            newton.report.inner_iterations,
            lbfgs.report.inner_iterations
        );
    }
}

#[test]
fn exact_and_quotient_hessians_agree_on_a_constrained_problem() {
    let exact = solve(
        &Quadratic::new(20, true, true),
        InnerSolver::TruncatedNewton,
    );
    let quotients = solve(
        &Quadratic::new(20, false, true),
        InnerSolver::TruncatedNewton,
    );
    for solution in [&exact, &quotients] {
        assert_eq!(solution.report.stop_reason, StopReason::Converged);
        assert!((solution.x.iter().sum::<f64>() - 10.0).abs() < 1e-7);
    }
    for (a, b) in exact.x.iter().zip(&quotients.x) {
        assert!((a - b).abs() < 1e-6, "{a} against {b}");
    }
}

/// f(x) = Σ dᵢ φ(xᵢ − 1), φ(t) = t²/2 + t⁴/4, dᵢ from 1 to 1e4: ill-conditioned, and its
/// Hessian changes from one Newton step to the next. Unconstrained and unbounded: the trait's
/// defaults for `bounds`, `n_eq` and the constraints.
struct Quartic {
    d: Vec<f64>,
}

impl Problem for Quartic {
    fn dim(&self) -> usize {
        self.d.len()
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        if let Some(g) = grad {
            for ((g, &d), &x) in g.iter_mut().zip(&self.d).zip(x) {
                let t = x - 1.0;
                *g = d * (t + t * t * t);
            }
        }
        self.d
            .iter()
            .zip(x)
            .map(|(d, x)| {
                let t = x - 1.0;
                d * (0.5 * t * t + 0.25 * t.powi(4))
            })
            .sum()
    }
    fn hessian_times(&self, x: &[f64], phr: &Phr<'_>, v: &[f64], out: &mut [f64]) -> bool {
        let sf = phr.objective_scale();
        for (((o, &d), &x), &vi) in out.iter_mut().zip(&self.d).zip(x).zip(v) {
            let t = x - 1.0;
            *o = sf * d * (1.0 + 3.0 * t * t) * vi;
        }
        true
    }
}

/// The conjugate gradients preconditioned by the previous Newton step's pairs need fewer
/// Hessian products than plain ones, to the same minimiser.
#[test]
fn the_preconditioner_saves_hessian_products() {
    let n = 200;
    let problem = Quartic {
        d: (0..n)
            .map(|i| 10f64.powf(4.0 * i as f64 / (n - 1) as f64))
            .collect(),
    };
    let run = |pairs: usize| {
        let options = Options::default()
            .with_inner_solver(InnerSolver::TruncatedNewton)
            .with_cg_preconditioner_memory(pairs)
            .with_optimality_tolerance(1e-8);
        minimize(&problem, &vec![-1.0; n], &options).unwrap()
    };
    let plain = run(0);
    let preconditioned = run(7);
    for s in [&plain, &preconditioned] {
        assert_eq!(s.report.stop_reason, StopReason::Converged);
        assert!(s.x.iter().all(|&x| (x - 1.0).abs() < 1e-6));
    }
    assert!(
        preconditioned.report.hessian_products < plain.report.hessian_products,
        "preconditioned {} Hessian products, plain {}",
        preconditioned.report.hessian_products,
        plain.report.hessian_products
    );
    eprintln!(
        "Hessian products: preconditioned {}, plain {}; inner iterations {} and {}",
        preconditioned.report.hessian_products,
        plain.report.hessian_products,
        preconditioned.report.inner_iterations,
        plain.report.inner_iterations
    );
}
