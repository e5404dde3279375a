//! SPG against projected L-BFGS on the chained Rosenbrock function, n = 1000, with bounds
//! [−5, 5] (inactive at the solution), to tolerance 1e-6. Both in one group, so the report
//! gives their ratio from one run.
//!
//! Then the solver's own cost per iteration at the size of a packing of 10 000 ellipsoids
//! (n = 60 000): 200 projected L-BFGS iterations on the same function, whose evaluation is
//! cheap next to the direction (two-loop recursion), projection and line search.

use std::hint::black_box;

use auglag::{InnerSolver, Options, Problem, StopReason, minimize};
use criterion::{Criterion, criterion_group, criterion_main};

struct Rosenbrock(usize);

impl Problem for Rosenbrock {
    fn dim(&self) -> usize {
        self.0
    }
    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.iter_mut().for_each(|l| *l = -5.0);
        upper.iter_mut().for_each(|u| *u = 5.0);
    }
    fn objective(&self, x: &[f64], mut grad: Option<&mut [f64]>) -> f64 {
        if let Some(g) = grad.as_deref_mut() {
            g.iter_mut().for_each(|v| *v = 0.0);
        }
        let mut f = 0.0;
        for i in 0..self.0 - 1 {
            let a = x[i + 1] - x[i] * x[i];
            let b = 1.0 - x[i];
            f += 100.0 * a * a + b * b;
            if let Some(g) = grad.as_deref_mut() {
                g[i] += -400.0 * x[i] * a - 2.0 * b;
                g[i + 1] += 200.0 * a;
            }
        }
        f
    }
}

fn inner_solvers(c: &mut Criterion) {
    let n = 1000;
    let problem = Rosenbrock(n);
    let x0: Vec<f64> = (0..n)
        .map(|i| if i % 2 == 0 { -1.2 } else { 1.0 })
        .collect();
    let mut group = c.benchmark_group("rosenbrock_1000");
    group.sample_size(10);
    for (name, solver) in [
        ("spg", InnerSolver::Spg),
        ("projected_lbfgs", InnerSolver::ProjectedLbfgs),
    ] {
        let options = Options::default()
            .with_optimality_tolerance(1e-6)
            .with_inner_solver(solver)
            .with_max_inner_iterations(1_000_000);
        let s = minimize(&problem, &x0, &options).expect("valid problem");
        assert_eq!(s.report.stop_reason, StopReason::Converged);
        eprintln!("{name}: {}", s.report);
        group.bench_function(name, |b| {
            b.iter(|| minimize(black_box(&problem), black_box(&x0), &options))
        });
    }
    group.finish();
    let n = 60_000;
    let problem = Rosenbrock(n);
    let x0: Vec<f64> = (0..n)
        .map(|i| if i % 2 == 0 { -1.2 } else { 1.0 })
        .collect();
    let options = Options::default()
        .with_optimality_tolerance(1e-12)
        .with_inner_solver(InnerSolver::ProjectedLbfgs)
        .with_max_inner_iterations(200);
    let mut group = c.benchmark_group("rosenbrock_60000");
    group.sample_size(10);
    group.bench_function("projected_lbfgs_200_iterations", |b| {
        b.iter(|| minimize(black_box(&problem), black_box(&x0), &options))
    });
    group.finish();
}

criterion_group!(benches, inner_solvers);
criterion_main!(benches);
