//! Problems with known solutions: bound-constrained Rosenbrock, Hock–Schittkowski problems and
//! circle packings, each solved with both inner solvers.

mod common;

use auglag::{InnerSolver, Options, Problem, Solution, StopReason, minimize};

const SOLVERS: [InnerSolver; 3] = [
    InnerSolver::Spg,
    InnerSolver::ProjectedLbfgs,
    InnerSolver::TruncatedNewton,
];

/// Tolerances tighter than the assertions below (1e-6), so that a pass means the solver
/// reached the optimum and not merely stopped near it.
fn tight(solver: InnerSolver) -> Options {
    Options::default()
        .with_feasibility_tolerance(1e-8)
        .with_optimality_tolerance(1e-8)
        .with_complementarity_tolerance(1e-8)
        .with_inner_solver(solver)
        .with_max_inner_iterations(100_000)
}

fn print_run(name: &str, solver: InnerSolver, s: &Solution) {
    let r = &s.report;
    eprintln!(
        "{name} {solver:?}: {:?}, outer {}, inner {}, evals {}, f = {:.12e}, infeas {:.2e}, pg {:.2e}, rho {:.1e}",
        r.stop_reason,
        r.outer_iterations,
        r.inner_iterations,
        r.function_evaluations,
        r.objective,
        r.infeasibility,
        r.projected_gradient_norm,
        r.penalty
    );
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

// ---------------------------------------------------------------------------------------------
// Rosenbrock
// ---------------------------------------------------------------------------------------------

/// Chained (`chained = true`, f = Σᵢ 100(xᵢ₊₁ − xᵢ²)² + (1 − xᵢ)²) or extended (independent
/// pairs (x₂ᵢ, x₂ᵢ₊₁), Moré–Garbow–Hillstrom problem 21) Rosenbrock function with given bounds.
struct Rosenbrock {
    chained: bool,
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl Rosenbrock {
    /// The chained function in the box [lower, upper].
    fn chained(lower: Vec<f64>, upper: Vec<f64>) -> Self {
        Rosenbrock {
            chained: true,
            lower,
            upper,
        }
    }

    fn terms(&self) -> Vec<(usize, usize)> {
        let n = self.lower.len();
        if self.chained {
            (0..n - 1).map(|i| (i, i + 1)).collect()
        } else {
            (0..n / 2).map(|i| (2 * i, 2 * i + 1)).collect()
        }
    }
}

impl Problem for Rosenbrock {
    fn dim(&self) -> usize {
        self.lower.len()
    }
    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        common::write_box(&self.lower, &self.upper, lower, upper);
    }
    fn objective(&self, x: &[f64], mut grad: Option<&mut [f64]>) -> f64 {
        if let Some(g) = grad.as_deref_mut() {
            g.iter_mut().for_each(|v| *v = 0.0);
        }
        let mut f = 0.0;
        for (i, j) in self.terms() {
            let a = x[j] - x[i] * x[i];
            let b = 1.0 - x[i];
            f += 100.0 * a * a + b * b;
            if let Some(g) = grad.as_deref_mut() {
                g[i] += -400.0 * x[i] * a - 2.0 * b;
                g[j] += 200.0 * a;
            }
        }
        f
    }
}

fn rosenbrock_start(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| if i % 2 == 0 { -1.2 } else { 1.0 })
        .collect()
}

fn check_rosenbrock(name: &str, problem: &Rosenbrock, x_star: &[f64], f_star: f64) {
    let x0 = rosenbrock_start(problem.dim());
    for solver in SOLVERS {
        let s = minimize(problem, &x0, &tight(solver)).expect("valid problem");
        print_run(name, solver, &s);
        assert_eq!(
            s.report.stop_reason,
            StopReason::Converged,
            "{name} {solver:?}"
        );
        let err = max_abs_diff(&s.x, x_star);
        assert!(err <= 1e-6, "{name} {solver:?}: |x − x*|∞ = {err:e}");
        let f_err = (s.report.objective - f_star).abs();
        assert!(f_err <= 1e-10, "{name} {solver:?}: |f − f*| = {f_err:e}");
    }
}

#[test]
fn rosenbrock_2_with_inactive_bounds() {
    let p = Rosenbrock::chained(vec![-5.0; 2], vec![5.0; 2]);
    check_rosenbrock("rosenbrock2-inactive", &p, &[1.0, 1.0], 0.0);
}

/// With x₀ ≤ ½ the minimiser over x₁ is x₁ = x₀², leaving (1 − x₀)², so x* = (½, ¼), f* = ¼,
/// with ∂f/∂x₀ = −1 < 0 at the active upper bound.
#[test]
fn rosenbrock_2_with_active_bound() {
    let p = Rosenbrock::chained(vec![-2.0, -2.0], vec![0.5, 2.0]);
    check_rosenbrock("rosenbrock2-active", &p, &[0.5, 0.25], 0.25);
}

#[test]
fn rosenbrock_10_chained_with_inactive_bounds() {
    let p = Rosenbrock::chained(vec![-5.0; 10], vec![5.0; 10]);
    check_rosenbrock("rosenbrock10-inactive", &p, &[1.0; 10], 0.0);
}

/// Extended Rosenbrock (independent pairs): pair 0 has x₀ ≤ ½ (optimum (½, ¼), f = ¼), pair 1
/// has x₂ ≥ 3/2 (optimum (3/2, 9/4), f = ¼, ∂f/∂x₂ = 1 > 0 at the lower bound), the other
/// pairs are free in [−5, 5]² (optimum (1, 1)).
#[test]
fn rosenbrock_10_extended_with_active_bounds() {
    let mut lower = vec![-5.0; 10];
    let mut upper = vec![5.0; 10];
    upper[0] = 0.5;
    lower[2] = 1.5;
    let p = Rosenbrock {
        chained: false,
        lower,
        upper,
    };
    let x_star = [0.5, 0.25, 1.5, 2.25, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0];
    check_rosenbrock("rosenbrock10-active", &p, &x_star, 0.5);
}

// ---------------------------------------------------------------------------------------------
// Hock–Schittkowski
// ---------------------------------------------------------------------------------------------

/// A small dense test problem given by closures; gradients by hand.
struct Dense {
    n_eq: usize,
    n_ineq: usize,
    /// Lower and upper bounds; their length is the dimension.
    bounds: (Vec<f64>, Vec<f64>),
    f: fn(&[f64]) -> f64,
    df: fn(&[f64], &mut [f64]),
    /// Writes c(x) and, row by row, the Jacobian (m × n, row-major).
    c: fn(&[f64], &mut [f64], &mut [f64]),
}

impl Problem for Dense {
    fn dim(&self) -> usize {
        self.bounds.0.len()
    }
    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&self.bounds.0);
        upper.copy_from_slice(&self.bounds.1);
    }
    fn n_eq(&self) -> usize {
        self.n_eq
    }
    fn n_ineq(&self) -> usize {
        self.n_ineq
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        if let Some(g) = grad {
            (self.df)(x, g);
        }
        (self.f)(x)
    }
    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        let mut jac = vec![0.0; c.len() * self.dim()];
        (self.c)(x, c, &mut jac);
    }
    fn constraints_jt_times(&self, x: &[f64], w: &[f64], out: &mut [f64]) {
        let (m, n) = (w.len(), self.dim());
        let mut c = vec![0.0; m];
        let mut jac = vec![0.0; m * n];
        (self.c)(x, &mut c, &mut jac);
        for (i, &wi) in w.iter().enumerate() {
            for (o, &j) in out.iter_mut().zip(&jac[i * n..(i + 1) * n]) {
                *o += wi * j;
            }
        }
    }
}

fn check_hs(name: &str, p: &Dense, x0: &[f64], f_star: f64, x_star: Option<&[f64]>) {
    for solver in SOLVERS {
        for scaling in [false, true] {
            let options = tight(solver).with_scaling(scaling);
            let s = minimize(p, x0, &options).expect("valid problem");
            print_run(&format!("{name} scaling={scaling}"), solver, &s);
            assert_eq!(
                s.report.stop_reason,
                StopReason::Converged,
                "{name} {solver:?}"
            );
            let rel = (s.report.objective - f_star).abs() / f_star.abs().max(1.0);
            assert!(
                rel <= 1e-6,
                "{name} {solver:?}: relative objective error {rel:e}"
            );
            assert!(
                s.report.infeasibility <= 1e-6,
                "{name} {solver:?}: infeasibility {:e}",
                s.report.infeasibility
            );
            if let Some(x_star) = x_star {
                let err = max_abs_diff(&s.x, x_star);
                assert!(err <= 1e-4, "{name} {solver:?}: |x − x*|∞ = {err:e}");
            }
        }
    }
}

const INF: f64 = f64::INFINITY;

/// The bounds of a problem without bounds in `n` variables.
fn unbounded(n: usize) -> (Vec<f64>, Vec<f64>) {
    (vec![-INF; n], vec![INF; n])
}

/// HS 6: min (1 − x₁)² s.t. 10(x₂ − x₁²) = 0; x⁰ = (−1.2, 1); x* = (1, 1), f* = 0 (the
/// relative test then is absolute).
#[test]
fn hock_schittkowski_6() {
    let p = Dense {
        n_eq: 1,
        n_ineq: 0,
        bounds: unbounded(2),
        f: |x| (1.0 - x[0]).powi(2),
        df: |x, g| {
            g[0] = -2.0 * (1.0 - x[0]);
            g[1] = 0.0;
        },
        c: |x, c, j| {
            c[0] = 10.0 * (x[1] - x[0] * x[0]);
            j[0] = -20.0 * x[0];
            j[1] = 10.0;
        },
    };
    check_hs("HS6", &p, &[-1.2, 1.0], 0.0, Some(&[1.0, 1.0]));
}

/// HS 7: min ln(1 + x₁²) − x₂ s.t. (1 + x₁²)² + x₂² − 4 = 0; x⁰ = (2, 2);
/// x* = (0, √3), f* = −√3.
#[test]
fn hock_schittkowski_7() {
    let p = Dense {
        n_eq: 1,
        n_ineq: 0,
        bounds: unbounded(2),
        f: |x| (1.0 + x[0] * x[0]).ln() - x[1],
        df: |x, g| {
            g[0] = 2.0 * x[0] / (1.0 + x[0] * x[0]);
            g[1] = -1.0;
        },
        c: |x, c, j| {
            let a = 1.0 + x[0] * x[0];
            c[0] = a * a + x[1] * x[1] - 4.0;
            j[0] = 4.0 * a * x[0];
            j[1] = 2.0 * x[1];
        },
    };
    let s3 = 3f64.sqrt();
    check_hs("HS7", &p, &[2.0, 2.0], -s3, Some(&[0.0, s3]));
}

/// HS 21: min 0.01x₁² + x₂² − 100 s.t. 10x₁ − x₂ − 10 ≥ 0, 2 ≤ x₁ ≤ 50, −50 ≤ x₂ ≤ 50;
/// x⁰ = (−1, −1) (outside the box: projected); x* = (2, 0), f* = −99.96.
#[test]
fn hock_schittkowski_21() {
    let p = Dense {
        n_eq: 0,
        n_ineq: 1,
        bounds: (vec![2.0, -50.0], vec![50.0, 50.0]),
        f: |x| 0.01 * x[0] * x[0] + x[1] * x[1] - 100.0,
        df: |x, g| {
            g[0] = 0.02 * x[0];
            g[1] = 2.0 * x[1];
        },
        c: |x, c, j| {
            c[0] = -(10.0 * x[0] - x[1] - 10.0);
            j[0] = -10.0;
            j[1] = 1.0;
        },
    };
    check_hs("HS21", &p, &[-1.0, -1.0], -99.96, Some(&[2.0, 0.0]));
}

/// HS 35: min 9 − 8x₁ − 6x₂ − 4x₃ + 2x₁² + 2x₂² + x₃² + 2x₁x₂ + 2x₁x₃
/// s.t. 3 − x₁ − x₂ − 2x₃ ≥ 0, x ≥ 0; x⁰ = (½, ½, ½); x* = (4/3, 7/9, 4/9), f* = 1/9.
#[test]
fn hock_schittkowski_35() {
    let p = Dense {
        n_eq: 0,
        n_ineq: 1,
        bounds: (vec![0.0; 3], vec![INF; 3]),
        f: |x| {
            9.0 - 8.0 * x[0] - 6.0 * x[1] - 4.0 * x[2]
                + 2.0 * x[0] * x[0]
                + 2.0 * x[1] * x[1]
                + x[2] * x[2]
                + 2.0 * x[0] * x[1]
                + 2.0 * x[0] * x[2]
        },
        df: |x, g| {
            g[0] = -8.0 + 4.0 * x[0] + 2.0 * x[1] + 2.0 * x[2];
            g[1] = -6.0 + 4.0 * x[1] + 2.0 * x[0];
            g[2] = -4.0 + 2.0 * x[2] + 2.0 * x[0];
        },
        c: |x, c, j| {
            c[0] = x[0] + x[1] + 2.0 * x[2] - 3.0;
            j.copy_from_slice(&[1.0, 1.0, 2.0]);
        },
    };
    check_hs(
        "HS35",
        &p,
        &[0.5, 0.5, 0.5],
        1.0 / 9.0,
        Some(&[4.0 / 3.0, 7.0 / 9.0, 4.0 / 9.0]),
    );
}

/// HS 71: min x₁x₄(x₁ + x₂ + x₃) + x₃ s.t. x₁x₂x₃x₄ ≥ 25, Σxᵢ² = 40, 1 ≤ x ≤ 5;
/// x⁰ = (1, 5, 5, 1); x* ≈ (1, 4.7429994, 3.8211503, 1.3794082), f* = 17.0140173.
#[test]
fn hock_schittkowski_71() {
    let p = Dense {
        n_eq: 1,
        n_ineq: 1,
        bounds: (vec![1.0; 4], vec![5.0; 4]),
        f: |x| x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2],
        df: |x, g| {
            let s = x[0] + x[1] + x[2];
            g[0] = x[3] * s + x[0] * x[3];
            g[1] = x[0] * x[3];
            g[2] = x[0] * x[3] + 1.0;
            g[3] = x[0] * s;
        },
        c: |x, c, j| {
            c[0] = x.iter().map(|v| v * v).sum::<f64>() - 40.0;
            c[1] = 25.0 - x[0] * x[1] * x[2] * x[3];
            for i in 0..4 {
                j[i] = 2.0 * x[i];
            }
            j[4] = -x[1] * x[2] * x[3];
            j[5] = -x[0] * x[2] * x[3];
            j[6] = -x[0] * x[1] * x[3];
            j[7] = -x[0] * x[1] * x[2];
        },
    };
    check_hs(
        "HS71",
        &p,
        &[1.0, 5.0, 5.0, 1.0],
        17.014_017_3,
        Some(&[1.0, 4.742_999_4, 3.821_150_3, 1.379_408_2]),
    );
}

// ---------------------------------------------------------------------------------------------
// Circles in the smallest enclosing circle
// ---------------------------------------------------------------------------------------------

/// k unit circles with centres cᵢ in a circle of radius R centred at the origin: variables
/// (c₁, …, c_k, R), min R s.t. 4 − |cᵢ − cⱼ|² ≤ 0 (i < j) and |cᵢ|² − (R − 1)² ≤ 0,
/// R ≥ 3/2.
///
/// Why 3/2 and not the natural R ≥ 1: the gradient of |cᵢ|² − (R − 1)² with respect to R
/// vanishes at R = 1, so (R = 1, overlapping centres balanced between the two constraint
/// families) is a stationary point of the infeasibility on the box, and the penalty method can
/// stop there (it does, from the first start below, with `PenaltyTooLarge`). Any k ≥ 2 unit
/// circles need R ≥ 2, so R ≥ 3/2 cuts off no solution and is inactive at the optimum.
struct Circles {
    k: usize,
}

impl Circles {
    fn pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..self.k).flat_map(move |i| (i + 1..self.k).map(move |j| (i, j)))
    }
}

impl Problem for Circles {
    fn dim(&self) -> usize {
        2 * self.k + 1
    }
    fn bounds(&self, lower: &mut [f64], _upper: &mut [f64]) {
        lower[2 * self.k] = 1.5;
    }
    fn n_ineq(&self) -> usize {
        self.k * (self.k - 1) / 2 + self.k
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        if let Some(g) = grad {
            g.iter_mut().for_each(|v| *v = 0.0);
            g[2 * self.k] = 1.0;
        }
        x[2 * self.k]
    }
    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        let r = x[2 * self.k];
        let mut idx = 0;
        for (i, j) in self.pairs() {
            let dx = x[2 * i] - x[2 * j];
            let dy = x[2 * i + 1] - x[2 * j + 1];
            c[idx] = 4.0 - dx * dx - dy * dy;
            idx += 1;
        }
        for i in 0..self.k {
            c[idx] = x[2 * i].powi(2) + x[2 * i + 1].powi(2) - (r - 1.0).powi(2);
            idx += 1;
        }
    }
    fn constraints_jt_times(&self, x: &[f64], w: &[f64], out: &mut [f64]) {
        let r = x[2 * self.k];
        let mut idx = 0;
        for (i, j) in self.pairs() {
            let dx = x[2 * i] - x[2 * j];
            let dy = x[2 * i + 1] - x[2 * j + 1];
            out[2 * i] -= 2.0 * dx * w[idx];
            out[2 * i + 1] -= 2.0 * dy * w[idx];
            out[2 * j] += 2.0 * dx * w[idx];
            out[2 * j + 1] += 2.0 * dy * w[idx];
            idx += 1;
        }
        for i in 0..self.k {
            out[2 * i] += 2.0 * x[2 * i] * w[idx];
            out[2 * i + 1] += 2.0 * x[2 * i + 1] * w[idx];
            out[2 * self.k] -= 2.0 * (r - 1.0) * w[idx];
            idx += 1;
        }
    }
}

fn check_circles(k: usize, r_star: f64, starts: &[Vec<f64>]) {
    let p = Circles { k };
    for solver in SOLVERS {
        for (n, x0) in starts.iter().enumerate() {
            let s = minimize(&p, x0, &tight(solver)).expect("valid problem");
            print_run(&format!("circles{k} start {n}"), solver, &s);
            assert_eq!(
                s.report.stop_reason,
                StopReason::Converged,
                "k={k} start {n}"
            );
            let r = s.x[2 * k];
            let rel = (r - r_star).abs() / r_star;
            assert!(
                rel <= 1e-6,
                "k={k} start {n} {solver:?}: R = {r}, R* = {r_star}"
            );
            assert!(s.report.infeasibility <= 1e-6);
        }
    }
}

/// Two unit circles: R* = 2.
#[test]
fn two_circles_in_a_circle() {
    let starts = vec![
        vec![0.3, 0.1, -0.2, 0.4, 5.0],
        vec![1.0, 0.0, 0.0, 1.0, 1.0],
        vec![-3.0, 2.0, 4.0, -1.0, 10.0],
    ];
    check_circles(2, 2.0, &starts);
}

/// Three unit circles: R* = 1 + 2/√3 (centres on an equilateral triangle of side 2).
#[test]
fn three_circles_in_a_circle() {
    let starts = vec![
        vec![0.5, 0.1, -0.3, 0.6, 0.2, -0.7, 4.0],
        vec![2.0, 0.0, -1.0, 1.5, -1.0, -1.7, 1.0],
        vec![0.1, 3.0, 2.5, -1.0, -2.0, -2.2, 8.0],
    ];
    check_circles(3, 1.0 + 2.0 / 3f64.sqrt(), &starts);
}

// ---------------------------------------------------------------------------------------------
// A packer-sized problem: many variables, one equality
// ---------------------------------------------------------------------------------------------

/// min Σ (xᵢ − aᵢ)² s.t. Σ xᵢ = 1 with n = 20 000: x* = a − (Σa − 1)/n, λ* = 2(Σa − 1)/n.
struct Projection {
    a: Vec<f64>,
}

impl Problem for Projection {
    fn dim(&self) -> usize {
        self.a.len()
    }
    fn n_eq(&self) -> usize {
        1
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        if let Some(g) = grad {
            for ((gi, &xi), &ai) in g.iter_mut().zip(x).zip(&self.a) {
                *gi = 2.0 * (xi - ai);
            }
        }
        x.iter().zip(&self.a).map(|(x, a)| (x - a) * (x - a)).sum()
    }
    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        c[0] = x.iter().sum::<f64>() - 1.0;
    }
    fn constraints_jt_times(&self, _x: &[f64], w: &[f64], out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o += w[0]);
    }
}

/// Projected L-BFGS only: with Algencan's ρ₁ (here ≈ 7·10⁴, since f(0) ≈ 7·10³) the subproblem
/// Hessian 2I + ρ11ᵀ has condition number ≈ ρn/2 ≈ 7·10⁸, which a quasi-Newton method absorbs
/// (the ill-conditioning has rank one) but which makes SPG take thousands of iterations per
/// outer iteration.
#[test]
fn large_projection_onto_a_hyperplane() {
    let n = 20_000;
    let a: Vec<f64> = (0..n)
        .map(|i| ((i * 7919) % 1000) as f64 / 1000.0)
        .collect();
    let shift = (a.iter().sum::<f64>() - 1.0) / n as f64;
    let x_star: Vec<f64> = a.iter().map(|v| v - shift).collect();
    let p = Projection { a };
    let solver = InnerSolver::ProjectedLbfgs;
    let s = minimize(&p, &vec![0.0; n], &tight(solver)).expect("valid problem");
    print_run("projection20000", solver, &s);
    assert_eq!(s.report.stop_reason, StopReason::Converged);
    let err = max_abs_diff(&s.x, &x_star);
    assert!(err <= 1e-7, "|x − x*|∞ = {err:e}");
    let lambda_err = (s.equality_multipliers[0] - 2.0 * shift).abs();
    assert!(lambda_err <= 1e-6, "multiplier error {lambda_err:e}");
}
