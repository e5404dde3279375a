//! A user's bound-constrained problem through the [`auglag::Problem`] trait: Rosenbrock's
//! function in a box that cuts off its unconstrained minimum (1, 1).
//!
//! ```text
//! minimise (1 − x₀)² + 100 (x₁ − x₀²)²   subject to   −1.5 ≤ x₀ ≤ 0.5,  −0.5 ≤ x₁ ≤ 2
//! ```
//!
//! For fixed x₀ the best x₁ is x₀², which leaves (1 − x₀)², decreasing on the box: the
//! minimum is (0.5, 0.25) with value 0.25, on the bound x₀ = 0.5. Both inner solvers are run
//! from the same start.
//!
//! Run with `cargo run --release -p auglag --example bounded_rosenbrock`.

use auglag::{InnerSolver, Options, Problem, minimize};

struct BoundedRosenbrock;

impl Problem for BoundedRosenbrock {
    fn dim(&self) -> usize {
        2
    }

    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&[-1.5, -0.5]);
        upper.copy_from_slice(&[0.5, 2.0]);
    }

    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        let (a, b) = (1.0 - x[0], x[1] - x[0] * x[0]);
        if let Some(g) = grad {
            g[0] = -2.0 * a - 400.0 * x[0] * b;
            g[1] = 200.0 * b;
        }
        a * a + 100.0 * b * b
    }
}

fn main() -> Result<(), auglag::Error> {
    let start = [-1.2, 1.0];
    for (name, inner) in [
        ("spectral projected gradient", InnerSolver::Spg),
        ("projected L-BFGS", InnerSolver::ProjectedLbfgs),
        ("truncated Newton", InnerSolver::TruncatedNewton),
    ] {
        let options = Options::default().with_inner_solver(inner);
        let solution = minimize(&BoundedRosenbrock, &start, &options)?;
        let report = &solution.report;
        println!(
            "{name}: x = ({:.6}, {:.6}), f = {:.6}, {:?} after {} iterations, \
             {} evaluations; projected gradient {:.1e}",
            solution.x[0],
            solution.x[1],
            report.objective,
            report.stop_reason,
            report.inner_iterations,
            report.function_evaluations,
            report.projected_gradient_norm
        );
        let error = (solution.x[0] - 0.5)
            .abs()
            .max((solution.x[1] - 0.25).abs());
        assert!(error < 1e-4, "{name} ended {error:.1e} from (0.5, 0.25)");
    }
    Ok(())
}
