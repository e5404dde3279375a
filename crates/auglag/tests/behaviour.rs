//! Behaviour of the outer loop and of the interface: safeguarded multipliers, best feasible
//! point, non-finite values, interrupts, determinism, input errors, the fused hook.

mod common;

use std::cell::Cell;

use auglag::{
    Control, Error, Evaluation, Event, InnerSolver, Options, Phr, Problem, StopReason, minimize,
    minimize_with_callback,
};

const SOLVERS: [InnerSolver; 3] = [
    InnerSolver::Spg,
    InnerSolver::ProjectedLbfgs,
    InnerSolver::TruncatedNewton,
];

/// min (x₀ − a)² + (x₁ − a)² s.t. x₀ + x₁ = 2 and, optionally, x₀ − b ≤ 0.
/// With a = 3 and no inequality: x* = (1, 1), λ* = 4 (∇f + λ∇h = 0 ⇒ 2(1 − 3) + λ = 0).
struct Quadratic {
    a: f64,
    with_ineq: Option<f64>,
}

impl Problem for Quadratic {
    fn dim(&self) -> usize {
        2
    }
    fn n_eq(&self) -> usize {
        1
    }
    fn n_ineq(&self) -> usize {
        usize::from(self.with_ineq.is_some())
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        if let Some(g) = grad {
            g[0] = 2.0 * (x[0] - self.a);
            g[1] = 2.0 * (x[1] - self.a);
        }
        (x[0] - self.a).powi(2) + (x[1] - self.a).powi(2)
    }
    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        c[0] = x[0] + x[1] - 2.0;
        if let Some(b) = self.with_ineq {
            c[1] = x[0] - b;
        }
    }
    fn constraints_jt_times(&self, _x: &[f64], w: &[f64], out: &mut [f64]) {
        out[0] += w[0];
        out[1] += w[0];
        if self.with_ineq.is_some() {
            out[0] += w[1];
        }
    }
}

#[test]
fn safeguarded_multipliers_stay_in_their_box() {
    // With b = 0.5: x* = (0.5, 1.5), λ* = 3, μ* = 2 (∇f + λ∇h + μ∇g = 0). Both boxes below
    // are too small to hold them, so the safeguard is exercised.
    let p = Quadratic {
        a: 3.0,
        with_ineq: Some(0.5),
    };
    for solver in SOLVERS {
        let options = Options::default()
            .with_equality_multiplier_bounds((-0.5, 0.5))
            .with_max_inequality_multiplier(0.25)
            .with_inner_solver(solver);
        let mut seen = 0;
        let mut clipped = false;
        let s = minimize_with_callback(&p, &[0.0, 0.0], &options, |pr| {
            let m = pr.safeguarded_multipliers;
            assert!((-0.5..=0.5).contains(&m[0]), "λ̄ = {} left its box", m[0]);
            assert!((0.0..=0.25).contains(&m[1]), "μ̄ = {} left its box", m[1]);
            clipped |= m[0] == 0.5 || m[1] == 0.25;
            seen += 1;
            Control::Continue
        })
        .unwrap();
        assert!(seen > 0 && clipped, "{solver:?}: the box was never reached");
        // Safeguarding degrades the method to a pure penalty method here, which still converges.
        assert_eq!(s.report.stop_reason, StopReason::Converged, "{solver:?}");
        assert!((s.x[0] - 0.5).abs() < 1e-3 && (s.x[1] - 1.5).abs() < 1e-3);
        eprintln!(
            "{solver:?}: outer {}, rho {:.1e}, x = {:?}",
            s.report.outer_iterations, s.report.penalty, s.x
        );
    }
}

/// min −x s.t. x² − 1 ≤ 0: the PHR iterates approach x* = 1 from outside, so the objective
/// −x rises towards −1 as the infeasibility falls; the first iterate inside the feasibility
/// tolerance has the lowest objective of all "feasible" ones.
struct Approach;

impl Problem for Approach {
    fn dim(&self) -> usize {
        1
    }
    fn n_ineq(&self) -> usize {
        1
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        if let Some(g) = grad {
            g[0] = -1.0;
        }
        -x[0]
    }
    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        c[0] = x[0] * x[0] - 1.0;
    }
    fn constraints_jt_times(&self, x: &[f64], w: &[f64], out: &mut [f64]) {
        out[0] += 2.0 * x[0] * w[0];
    }
}

/// Runs `Approach` to a stop and records (objective, infeasibility) at each outer iteration.
fn approach_history(
    options: &Options,
    stop_at_outer: Option<usize>,
) -> (auglag::Solution, Vec<(f64, f64)>) {
    let mut history = Vec::new();
    let s = minimize_with_callback(&Approach, &[0.0], options, |pr| {
        if let Event::Outer {
            objective,
            infeasibility,
            ..
        } = pr.event
        {
            history.push((objective, infeasibility));
            if Some(pr.outer_iteration) == stop_at_outer {
                return Control::Stop;
            }
        }
        Control::Continue
    })
    .unwrap();
    (s, history)
}

fn approach_options(solver: InnerSolver) -> Options {
    Options::default()
        .with_feasibility_tolerance(1e-3)
        .with_optimality_tolerance(1e-10)
        // Unreachable, so that the run goes on past the first feasible iterate.
        .with_complementarity_tolerance(1e-300)
        .with_max_outer_iterations(8)
        .with_inner_solver(solver)
}

fn check_best_feasible(s: &auglag::Solution, history: &[(f64, f64)], tol: f64) {
    let feasible: Vec<f64> = history.iter().filter(|h| h.1 <= tol).map(|h| h.0).collect();
    let best = feasible.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(!feasible.is_empty());
    // The scenario under test: a later feasible iterate is worse than the best one.
    let last = *feasible.last().unwrap();
    assert!(
        last > best,
        "no later feasible iterate was worse: {history:?}"
    );
    assert!(s.report.returned_best_feasible);
    assert_eq!(s.report.best_feasible_objective, Some(best));
    assert_eq!(s.report.objective, best);
    assert_eq!(-s.x[0], best);
    assert!(s.report.infeasibility <= tol);
}

#[test]
fn best_feasible_point_is_kept_when_later_iterates_are_worse() {
    for solver in SOLVERS {
        let options = approach_options(solver);
        let (s, history) = approach_history(&options, None);
        eprintln!("{solver:?}: {history:?}");
        assert_eq!(s.report.stop_reason, StopReason::MaxOuterIterations);
        check_best_feasible(&s, &history, options.feasibility_tolerance);
    }
}

#[test]
fn interrupt_at_an_outer_iteration_returns_the_best_feasible_point() {
    for solver in SOLVERS {
        let options = approach_options(solver).with_max_outer_iterations(50);
        let (s, history) = approach_history(&options, Some(6));
        assert_eq!(s.report.stop_reason, StopReason::Interrupted);
        assert_eq!(s.report.outer_iterations, 6);
        check_best_feasible(&s, &history, options.feasibility_tolerance);
    }
}

/// Extended Rosenbrock without bounds (for the interrupt and determinism tests).
struct Rosenbrock(usize);

impl Problem for Rosenbrock {
    fn dim(&self) -> usize {
        self.0
    }
    fn objective(&self, x: &[f64], mut grad: Option<&mut [f64]>) -> f64 {
        let mut f = 0.0;
        for i in (0..self.0).step_by(2) {
            let a = x[i + 1] - x[i] * x[i];
            let b = 1.0 - x[i];
            f += 100.0 * a * a + b * b;
            if let Some(g) = grad.as_deref_mut() {
                g[i] = -400.0 * x[i] * a - 2.0 * b;
                g[i + 1] = 200.0 * a;
            }
        }
        f
    }
}

#[test]
fn interrupt_inside_an_inner_solve_stops_early_with_a_better_point() {
    let p = Rosenbrock(100);
    let x0: Vec<f64> = (0..100)
        .map(|i| if i % 2 == 0 { -1.2 } else { 1.0 })
        .collect();
    let f0 = p.objective(&x0, None);
    for solver in SOLVERS {
        let mut calls = 0;
        let options = Options::default().with_inner_solver(solver);
        let s = minimize_with_callback(&p, &x0, &options, |pr| {
            calls += 1;
            if pr.total_inner_iterations >= 5 {
                Control::Stop
            } else {
                Control::Continue
            }
        })
        .unwrap();
        assert_eq!(s.report.stop_reason, StopReason::Interrupted, "{solver:?}");
        assert_eq!(s.report.inner_iterations, 5);
        assert_eq!(calls, 6);
        let f = p.objective(&s.x, None);
        assert_eq!(f, s.report.objective);
        assert!(f < f0, "{solver:?}: interrupted at f = {f}, start f = {f0}");
    }
}

#[test]
fn runs_are_bit_identical() {
    let p = Quadratic {
        a: 3.0,
        with_ineq: Some(0.5),
    };
    let r = Rosenbrock(20);
    let x0: Vec<f64> = (0..20).map(|i| (i as f64 * 0.37).sin()).collect();
    for solver in SOLVERS {
        let options = Options::default().with_inner_solver(solver);
        let a = minimize(&p, &[0.1, -0.3], &options).unwrap();
        let b = minimize(&p, &[0.1, -0.3], &options).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.x), bits(&b.x));
        assert_eq!(
            bits(&a.inequality_multipliers),
            bits(&b.inequality_multipliers)
        );
        assert_eq!(a.report.function_evaluations, b.report.function_evaluations);
        let a = minimize(&r, &x0, &options).unwrap();
        let b = minimize(&r, &x0, &options).unwrap();
        assert_eq!(bits(&a.x), bits(&b.x));
        assert_eq!(a.report.inner_iterations, b.report.inner_iterations);
    }
}

/// f(x) = (x − 1.5)² on x ∈ ℝ but NaN for x > 2 (think of a model undefined there), or NaN
/// everywhere once `poison_after` evaluations have been made.
struct Partial {
    calls: Cell<usize>,
    poison_after: usize,
    nan_constraint: bool,
}

impl Problem for Partial {
    fn dim(&self) -> usize {
        1
    }
    fn n_ineq(&self) -> usize {
        usize::from(self.nan_constraint)
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        self.calls.set(self.calls.get() + 1);
        if self.calls.get() > self.poison_after || x[0] > 2.0 {
            if let Some(g) = grad {
                g[0] = f64::NAN;
            }
            return f64::NAN;
        }
        if let Some(g) = grad {
            g[0] = 2.0 * (x[0] - 1.5) * 1e3;
        }
        (x[0] - 1.5).powi(2) * 1e3
    }
    fn constraints(&self, _x: &[f64], c: &mut [f64]) {
        c[0] = f64::NAN;
    }
}

#[test]
fn nan_outside_the_domain_is_backtracked_over() {
    for solver in SOLVERS {
        let p = Partial {
            calls: Cell::new(0),
            poison_after: usize::MAX,
            nan_constraint: false,
        };
        let options = Options::default().with_inner_solver(solver);
        // The first trial steps from x = −20 overshoot far beyond x = 2.
        let s = minimize(&p, &[-20.0], &options).unwrap();
        assert_eq!(s.report.stop_reason, StopReason::Converged, "{solver:?}");
        assert!((s.x[0] - 1.5).abs() < 1e-6, "{solver:?}: x = {}", s.x[0]);
    }
}

#[test]
fn persistent_nan_is_a_stop_reason_and_a_finite_point_is_returned() {
    for solver in SOLVERS {
        let p = Partial {
            calls: Cell::new(0),
            poison_after: 4,
            nan_constraint: false,
        };
        let options = Options::default().with_inner_solver(solver);
        let s = minimize(&p, &[-20.0], &options).unwrap();
        match s.report.stop_reason {
            StopReason::NonFinite {
                what: Evaluation::Objective,
                outer_iteration: 1,
                ..
            } => {}
            other => panic!("{solver:?}: unexpected stop {other:?}"),
        }
        assert!(s.x[0].is_finite());
        assert!(s.report.stop_reason.to_string().contains("the objective"));
    }
}

#[test]
fn nan_at_the_start_is_a_typed_error() {
    let p = Partial {
        calls: Cell::new(0),
        poison_after: 0,
        nan_constraint: false,
    };
    let e = minimize(&p, &[0.0], &Options::default()).unwrap_err();
    assert_eq!(
        e,
        Error::NonFiniteAtStart {
            what: Evaluation::Objective
        }
    );
    let p = Partial {
        calls: Cell::new(0),
        poison_after: usize::MAX,
        nan_constraint: true,
    };
    let e = minimize(&p, &[0.0], &Options::default()).unwrap_err();
    assert_eq!(
        e,
        Error::NonFiniteAtStart {
            what: Evaluation::Constraint { index: 0 }
        }
    );
    assert!(e.to_string().contains("constraint 0"));
}

/// A problem with fixed bounds, for the input checks.
struct Boxed {
    lower: Vec<f64>,
    upper: Vec<f64>,
}

impl Problem for Boxed {
    fn dim(&self) -> usize {
        self.lower.len()
    }
    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        common::write_box(&self.lower, &self.upper, lower, upper);
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        if let Some(g) = grad {
            g.copy_from_slice(x);
        }
        0.5 * x.iter().map(|v| v * v).sum::<f64>()
    }
}

#[test]
fn invalid_input_is_reported_with_its_index() {
    let p = Boxed {
        lower: vec![0.0, 2.0, 0.0],
        upper: vec![1.0, 1.0, 1.0],
    };
    let e = minimize(&p, &[0.0; 3], &Options::default()).unwrap_err();
    assert!(matches!(e, Error::InvalidBounds { index: 1, .. }), "{e:?}");
    assert!(e.to_string().contains("variable 1"), "{e}");

    let p = Boxed {
        lower: vec![0.0, f64::NAN],
        upper: vec![1.0, 1.0],
    };
    let e = minimize(&p, &[0.0; 2], &Options::default()).unwrap_err();
    assert!(matches!(e, Error::InvalidBounds { index: 1, .. }), "{e:?}");

    let p = Boxed {
        lower: vec![0.0; 2],
        upper: vec![1.0; 2],
    };
    let e = minimize(&p, &[0.0; 3], &Options::default()).unwrap_err();
    assert!(matches!(
        e,
        Error::DimensionMismatch {
            expected: 2,
            found: 3,
            ..
        }
    ));
    let e = minimize(&p, &[0.0, f64::INFINITY], &Options::default()).unwrap_err();
    assert!(matches!(e, Error::NonFiniteStart { index: 1, .. }));
    let bad = Options::default().with_feasibility_tolerance(-1.0);
    let e = minimize(&p, &[0.0; 2], &bad).unwrap_err();
    assert!(e.to_string().contains("feasibility_tolerance"), "{e}");
    let bad = Options::default().with_required_decrease(1.5);
    assert!(minimize(&p, &[0.0; 2], &bad).is_err());
}

/// `Quadratic` again, but answering through the fused hook.
struct Fused(Quadratic);

impl Problem for Fused {
    fn dim(&self) -> usize {
        self.0.dim()
    }
    fn n_eq(&self) -> usize {
        self.0.n_eq()
    }
    fn n_ineq(&self) -> usize {
        self.0.n_ineq()
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        self.0.objective(x, grad)
    }
    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        self.0.constraints(x, c);
    }
    fn lagrangian(&self, x: &[f64], phr: &Phr<'_>, grad: Option<&mut [f64]>) -> Option<f64> {
        let a = self.0.a;
        let h = x[0] + x[1] - 2.0;
        let mut value = phr.objective_scale() * self.0.objective(x, None) + phr.term(0, h);
        let wh = phr.derivative(0, h);
        let (g_ineq, wg) = match self.0.with_ineq {
            Some(b) => (x[0] - b, phr.derivative(1, x[0] - b)),
            None => (0.0, 0.0),
        };
        if self.0.with_ineq.is_some() {
            value += phr.term(1, g_ineq);
        }
        if let Some(g) = grad {
            g[0] = phr.objective_scale() * 2.0 * (x[0] - a) + wh + wg;
            g[1] = phr.objective_scale() * 2.0 * (x[1] - a) + wh;
        }
        Some(value)
    }
}

#[test]
fn fused_hook_gives_the_same_solution_as_the_default_path() {
    for solver in SOLVERS {
        for scaling in [false, true] {
            let options = Options::default()
                .with_inner_solver(solver)
                .with_scaling(scaling)
                .with_feasibility_tolerance(1e-9)
                .with_optimality_tolerance(1e-9)
                .with_complementarity_tolerance(1e-9);
            let plain = Quadratic {
                a: 3.0,
                with_ineq: Some(0.5),
            };
            let fused = Fused(Quadratic {
                a: 3.0,
                with_ineq: Some(0.5),
            });
            let a = minimize(&plain, &[0.0, 0.0], &options).unwrap();
            let b = minimize(&fused, &[0.0, 0.0], &options).unwrap();
            assert_eq!(a.report.stop_reason, StopReason::Converged);
            assert_eq!(b.report.stop_reason, StopReason::Converged);
            for (u, v) in a.x.iter().zip(&b.x) {
                assert!((u - v).abs() <= 1e-8, "{solver:?}: {:?} vs {:?}", a.x, b.x);
            }
            assert!((b.x[0] - 0.5).abs() <= 1e-8 && (b.x[1] - 1.5).abs() <= 1e-8);
            // Multipliers (∇f + λ∇h + μ∇g = 0): λ* = 3, μ* = 2.
            assert!((b.equality_multipliers[0] - 3.0).abs() <= 1e-6, "{:?}", b);
            assert!((b.inequality_multipliers[0] - 2.0).abs() <= 1e-6, "{:?}", b);
        }
    }
}

/// The default options with `solver` as the inner solver, then changed by `set`.
fn options_for(solver: InnerSolver, set: impl FnOnce(&mut Options)) -> Options {
    let mut options = Options::default().with_inner_solver(solver);
    set(&mut options);
    options
}

#[test]
fn evaluation_and_iteration_limits_stop_the_run() {
    let p = Rosenbrock(10);
    let x0 = vec![-1.2; 10];
    for solver in SOLVERS {
        let s = minimize(&p, &x0, &options_for(solver, |o| o.max_evaluations = 25)).unwrap();
        assert_eq!(s.report.stop_reason, StopReason::MaxEvaluations);
        assert!(s.report.function_evaluations <= 26);
        assert!(
            s.report
                .to_string()
                .starts_with("maximum number of evaluations")
        );
        // A budget spent by the start alone: no subproblem, but still a measured report.
        let s = minimize(&p, &x0, &options_for(solver, |o| o.max_evaluations = 1)).unwrap();
        assert_eq!(s.report.stop_reason, StopReason::MaxEvaluations);
        assert_eq!(s.report.outer_iterations, 0);
        assert_eq!(s.report.objective, p.objective(&x0, None));
        let options = options_for(solver, |o| o.max_inner_iterations = 7);
        let s = minimize(&p, &x0, &options).unwrap();
        assert_eq!(s.report.stop_reason, StopReason::MaxInnerIterations);
        assert_eq!(s.report.inner_iterations, 7);
    }
}
