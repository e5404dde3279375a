//! Property test: strictly convex quadratics with random bounds (some infinite). The returned
//! point must satisfy the projected-gradient KKT condition, recomputed here independently, and
//! — the problem being convex — be no worse than random feasible points.

mod common;

use auglag::{InnerSolver, Options, Problem, StopReason, minimize};
use proptest::prelude::*;

/// f(x) = ½ xᵀAx + bᵀx with A = MᵀM + I/10 (row-major), on [lower, upper].
#[derive(Debug)]
struct Qp {
    n: usize,
    a: Vec<f64>,
    b: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl Qp {
    fn gradient(&self, x: &[f64]) -> Vec<f64> {
        (0..self.n)
            .map(|i| {
                let row = &self.a[i * self.n..(i + 1) * self.n];
                row.iter().zip(x).map(|(a, x)| a * x).sum::<f64>() + self.b[i]
            })
            .collect()
    }
}

impl Problem for Qp {
    fn dim(&self) -> usize {
        self.n
    }
    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        common::write_box(&self.lower, &self.upper, lower, upper);
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        let g = self.gradient(x);
        // ½xᵀAx + bᵀx = ½xᵀ(Ax + b) + ½bᵀx.
        let f = 0.5 * g.iter().zip(x).map(|(g, x)| g * x).sum::<f64>()
            + 0.5 * self.b.iter().zip(x).map(|(b, x)| b * x).sum::<f64>();
        if let Some(out) = grad {
            out.copy_from_slice(&g);
        }
        f
    }
}

/// Bound kinds: 0 none, 1 lower only, 2 upper only, 3 both.
fn qp_strategy() -> impl Strategy<Value = (Qp, Vec<f64>)> {
    (1usize..=6).prop_flat_map(|n| {
        (
            prop::collection::vec(-2.0f64..2.0, n * n),
            prop::collection::vec(-5.0f64..5.0, n),
            prop::collection::vec((0u8..4, -3.0f64..1.0, 0.0f64..4.0), n),
            prop::collection::vec(-4.0f64..4.0, n),
        )
            .prop_map(move |(m, b, kinds, x0)| {
                let mut a = vec![0.0; n * n];
                for i in 0..n {
                    for j in 0..n {
                        a[i * n + j] = (0..n).map(|k| m[k * n + i] * m[k * n + j]).sum::<f64>();
                    }
                    a[i * n + i] += 0.1;
                }
                let mut lower = vec![f64::NEG_INFINITY; n];
                let mut upper = vec![f64::INFINITY; n];
                for (i, &(kind, lo, width)) in kinds.iter().enumerate() {
                    if kind & 1 == 1 {
                        lower[i] = lo;
                    }
                    if kind & 2 == 2 {
                        upper[i] = lo + width;
                    }
                }
                (
                    Qp {
                        n,
                        a,
                        b,
                        lower,
                        upper,
                    },
                    x0,
                )
            })
    })
}

const TOL: f64 = 1e-9;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn solution_satisfies_projected_gradient_kkt((qp, x0) in qp_strategy(),
                                                 probes in prop::collection::vec(-6.0f64..6.0, 24)) {
        for solver in [
        InnerSolver::Spg,
        InnerSolver::ProjectedLbfgs,
        InnerSolver::TruncatedNewton,
    ] {
            let options = Options::default().with_optimality_tolerance(TOL).with_inner_solver(solver).with_max_inner_iterations(1_000_000);
            let s = minimize(&qp, &x0, &options).unwrap();
            prop_assert_eq!(s.report.stop_reason, StopReason::Converged);
            let g = qp.gradient(&s.x);
            for (i, (&xi, &gi)) in s.x.iter().zip(&g).enumerate() {
                prop_assert!(xi >= qp.lower[i] && xi <= qp.upper[i]);
                let step = (xi - gi).max(qp.lower[i]).min(qp.upper[i]) - xi;
                // The solver tested the same quantity; only summation order may differ.
                prop_assert!(
                    step.abs() <= TOL * (1.0 + 1e-6),
                    "{:?}: |P(x - g) - x|_{} = {:e}", solver, i, step
                );
            }
            let f = qp.objective(&s.x, None);
            for chunk in probes.chunks(qp.n).take(4) {
                let y: Vec<f64> = (0..qp.n)
                    .map(|i| chunk.get(i).copied().unwrap_or(0.0).max(qp.lower[i]).min(qp.upper[i]))
                    .collect();
                prop_assert!(f <= qp.objective(&y, None) + 1e-9 * (1.0 + f.abs()));
            }
        }
    }
}
