//! The safeguarded augmented Lagrangian outer loop (Algencan's Algorithm 4.1).
//!
//! With ρ₁ > 0, λ̄¹ = 0, μ̄¹ = 0, τ = `required_decrease`, γ = `penalty_increase`, iteration k:
//!
//! ```text
//! 1. x^k ≈ argmin_{l≤x≤u} L_ρk(x, λ̄^k, μ̄^k)  to  ‖P(x − ∇L) − x‖∞ ≤ ε_k,
//!    ε_1 = √ε_opt, ε_k+1 = max(ε_opt, ε_k / 10)
//! 2. λ^k+1 = λ̄^k + ρk h(x^k),  μ^k+1 = max(0, μ̄^k + ρk g(x^k))
//! 3. V^k = max(g(x^k), −μ̄^k/ρk);  if k > 1 and
//!        max(‖h(x^k)‖∞, ‖V^k‖∞) > τ max(‖h(x^k−1)‖∞, ‖V^k−1‖∞)   then ρk+1 = γ ρk
//!    — except when x^k already meets the feasibility and complementarity tolerances
//! 4. λ̄^k+1 = clamp(λ^k+1, λ_min, λ_max),  μ̄^k+1 = clamp(μ^k+1, 0, μ_max)
//! ```
//!
//! It stops when max(‖h‖∞, ‖g₊‖∞) ≤ ε_feas, ‖min(−g, μ^k+1)‖∞ ≤ ε_compl and
//! ‖P(x − ∇ℓ(x, λ^k+1, μ^k+1)) − x‖∞ ≤ ε_opt (the last is the inner measure itself, by the
//! PHR identity in [`crate::lagrangian`]). The safeguarding box keeps the subproblems bounded
//! when the multiplier estimates diverge, which is what gives the method its global
//! convergence to feasible points (or to stationary points of the infeasibility). Measures
//! involving constraints are taken on the scaled problem, except the feasibility test, which is
//! always on the user's constraints.
//!
//! The lowest-objective outer iterate with infeasibility ≤ ε_feas is kept, and returned when the
//! run ends without convergence (an interrupt, a limit, a failure).
//!
//! # References
//! - E. G. Birgin, J. M. Martínez, *Practical Augmented Lagrangian Methods for Constrained
//!   Optimization*, SIAM, 2014: Algorithm 4.1 (outer loop), chapter 12 (Algencan's parameter
//!   choices: ρ₁, scaling, tolerances).
//! - R. Andreani, E. G. Birgin, J. M. Martínez, M. L. Schuverdt, "On augmented Lagrangian
//!   methods with general lower-level constraints", SIAM J. Optim. 18(4), 1286–1309, 2007.

use std::time::Instant;

use crate::error::{Error, Evaluation};
use crate::inner::{self, InnerOutcome, InnerSettings, InnerStatus, Method, Smooth};
use crate::lagrangian::AugmentedLagrangian;
use crate::options::{InnerSolver, Options};
use crate::problem::Problem;
use crate::projected_qn::LbfgsWorkspace;
use crate::projection::{norm_inf, project};
use crate::report::{Control, Event, Progress, Report, Solution, StopReason};
use crate::spg::SpgWorkspace;
use crate::truncated_newton::NewtonWorkspace;

/// Floor of the scale factors, so that a huge initial gradient cannot switch a function off.
const MIN_SCALE: f64 = 1e-8;

/// Minimises `problem` from `x0` (projected onto the bounds first) with `options`.
///
/// Equivalent to [`minimize_with_callback`] with a callback that never stops.
///
/// # Errors
/// See [`minimize_with_callback`].
pub fn minimize<P: Problem + ?Sized>(
    problem: &P,
    x0: &[f64],
    options: &Options,
) -> Result<Solution, Error> {
    minimize_with_callback(problem, x0, options, |_| Control::Continue)
}

/// Minimises `problem` from `x0`, calling `callback` at the start of every inner iteration and
/// at the end of every outer iteration; returning [`Control::Stop`] ends the run there with
/// [`StopReason::Interrupted`] and the best point so far.
///
/// Buffers are allocated once, before the first iteration. The run is deterministic: the same
/// problem, start and options give bit-identical results.
///
/// # Errors
/// Before any iteration: a dimension mismatch, invalid bounds or options, a non-finite start,
/// or a user function that is not finite at the projected start. Trouble during the run is
/// reported through [`Report::stop_reason`] instead.
pub fn minimize_with_callback<P, C>(
    problem: &P,
    x0: &[f64],
    options: &Options,
    mut callback: C,
) -> Result<Solution, Error>
where
    P: Problem + ?Sized,
    C: FnMut(&Progress<'_>) -> Control,
{
    let start = Instant::now();
    options.validate()?;
    let mut run = Run::new(problem, x0, options)?;
    let stop_reason = run.iterate(&mut callback);
    if run.last.is_none() {
        // Stopped before the first subproblem finished (an evaluation budget below what the
        // start needs): measure the start so that the report is not empty.
        run.last = run.measure().ok();
    }
    Ok(run.finish(stop_reason, start))
}

/// Values measured at the end of an outer iteration.
#[derive(Debug, Clone, Copy)]
struct OuterMeasures {
    objective: f64,
    infeasibility: f64,
    /// max(‖h̃‖∞, ‖Ṽ‖∞), the quantity whose decrease decides the penalty update.
    progress: f64,
    complementarity: f64,
}

enum InnerWorkspace {
    Spg(SpgWorkspace),
    Lbfgs(LbfgsWorkspace),
    Newton(NewtonWorkspace),
}

/// The state of one run; every buffer is allocated in `new`.
struct Run<'p, 'o, P: Problem + ?Sized> {
    options: &'o Options,
    al: AugmentedLagrangian<'p, P>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    x: Vec<f64>,
    grad: Vec<f64>,
    constraints: Vec<f64>,
    /// First-order multiplier estimates λ^k+1, μ^k+1 (scaled units).
    estimates: Vec<f64>,
    inner: InnerWorkspace,
    best_x: Vec<f64>,
    best: Option<(f64, f64)>,
    outer_iterations: usize,
    inner_iterations: usize,
    last: Option<OuterMeasures>,
    projected_gradient: f64,
}

impl<'p, 'o, P: Problem + ?Sized> Run<'p, 'o, P> {
    fn new(problem: &'p P, x0: &[f64], options: &'o Options) -> Result<Self, Error> {
        let n = problem.dim();
        let m = problem.n_eq() + problem.n_ineq();
        if x0.len() != n {
            return Err(Error::DimensionMismatch {
                what: "starting point",
                expected: n,
                found: x0.len(),
            });
        }
        let mut lower = vec![f64::NEG_INFINITY; n];
        let mut upper = vec![f64::INFINITY; n];
        problem.bounds(&mut lower, &mut upper);
        check_bounds(&lower, &upper)?;
        if let Some((index, &value)) = x0.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::NonFiniteStart { index, value });
        }
        let mut x = x0.to_vec();
        project(&mut x, &lower, &upper);
        let inner = match options.inner_solver {
            InnerSolver::Spg => InnerWorkspace::Spg(SpgWorkspace::new(
                n,
                options.spg_memory,
                options.spectral_step_bounds,
            )),
            InnerSolver::ProjectedLbfgs => {
                InnerWorkspace::Lbfgs(LbfgsWorkspace::new(n, options.lbfgs_memory))
            }
            InnerSolver::TruncatedNewton => InnerWorkspace::Newton(NewtonWorkspace::new(
                n,
                options.cg_iterations,
                options.cg_preconditioner_memory,
            )),
        };
        let mut run = Self {
            options,
            al: AugmentedLagrangian::new(problem),
            lower,
            upper,
            best_x: x.clone(),
            x,
            grad: vec![0.0; n],
            constraints: vec![0.0; m],
            estimates: vec![0.0; m],
            inner,
            best: None,
            outer_iterations: 0,
            inner_iterations: 0,
            last: None,
            projected_gradient: f64::INFINITY,
        };
        run.initialise()?;
        Ok(run)
    }

    /// Checks the start, then sets the scale factors and ρ₁.
    fn initialise(&mut self) -> Result<(), Error> {
        let scaling = self.options.scaling;
        let f0 = self
            .al
            .objective(&self.x, scaling.then_some(&mut self.grad[..]));
        if !f0.is_finite() {
            return Err(Error::NonFiniteAtStart {
                what: Evaluation::Objective,
            });
        }
        if scaling && self.grad.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFiniteAtStart {
                what: Evaluation::ObjectiveGradient,
            });
        }
        self.al.constraints(&self.x, &mut self.constraints);
        if let Some(index) = self.constraints.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFiniteAtStart {
                what: Evaluation::Constraint { index },
            });
        }
        if scaling {
            self.al.objective_scale = (1.0 / norm_inf(&self.grad).max(1.0)).max(MIN_SCALE);
            self.scale_constraints()?;
        }
        self.al.penalty = match self.options.initial_penalty {
            // Without constraints there is no penalty term; 0 says so in the report.
            _ if self.constraints.is_empty() => 0.0,
            Some(rho) => rho,
            None => self.algencan_initial_penalty(f0),
        };
        Ok(())
    }

    /// sᵢ = max(10⁻⁸, 1/max(1, ‖∇cᵢ(x⁰)‖∞)), each gradient obtained as Jᵀeᵢ.
    fn scale_constraints(&mut self) -> Result<(), Error> {
        let m = self.constraints.len();
        for i in 0..m {
            self.estimates.iter_mut().for_each(|w| *w = 0.0);
            self.estimates[i] = 1.0;
            self.grad.iter_mut().for_each(|g| *g = 0.0);
            self.al.jt_times(&self.x, &self.estimates, &mut self.grad);
            let norm = norm_inf(&self.grad);
            if !norm.is_finite() {
                return Err(Error::NonFiniteAtStart {
                    what: Evaluation::ConstraintGradient,
                });
            }
            self.al.constraint_scales[i] = (1.0 / norm.max(1.0)).max(MIN_SCALE);
        }
        self.estimates.iter_mut().for_each(|w| *w = 0.0);
        Ok(())
    }

    /// ρ₁ = max(10⁻⁸, min(10 max(1, |f̃(x⁰)|) / max(1, ½(‖h̃(x⁰)‖² + ‖g̃(x⁰)₊‖²)), 10⁸)):
    /// the penalty term starts comparable to the objective.
    fn algencan_initial_penalty(&self, f0: f64) -> f64 {
        let n_eq = self.al.n_eq;
        let squared_violation: f64 = self
            .constraints
            .iter()
            .zip(&self.al.constraint_scales)
            .enumerate()
            .map(|(i, (&c, &s))| {
                let v = if i < n_eq { s * c } else { (s * c).max(0.0) };
                v * v
            })
            .sum();
        let f0 = self.al.objective_scale * f0;
        let ratio = 10.0 * f0.abs().max(1.0) / (0.5 * squared_violation).max(1.0);
        ratio.clamp(1e-8, 1e8)
    }

    /// The outer loop; returns why it stopped.
    fn iterate<C: FnMut(&Progress<'_>) -> Control>(&mut self, callback: &mut C) -> StopReason {
        let eps_opt = self.options.optimality_tolerance;
        let unconstrained = self.constraints.is_empty();
        let mut inner_tolerance = if unconstrained {
            eps_opt
        } else {
            eps_opt.sqrt().max(eps_opt)
        };
        loop {
            if self.al.function_evaluations >= self.options.max_evaluations {
                return StopReason::MaxEvaluations;
            }
            self.outer_iterations += 1;
            let outcome = self.solve_subproblem(inner_tolerance, callback);
            self.inner_iterations += outcome.iterations;
            self.projected_gradient = outcome.projected_gradient;
            let measures = match self.measure() {
                Ok(m) => m,
                Err(what) => return self.non_finite(what, outcome.iterations),
            };
            self.keep_if_best(&measures);
            if let Some(reason) = self.inner_stop(&outcome, unconstrained) {
                self.last = Some(measures);
                return reason;
            }
            let previous = self.last.replace(measures);
            if let Some(reason) = self.outer_stop(&outcome, &measures, unconstrained) {
                return reason;
            }
            if let Err(reason) = self.update_penalty(&measures, previous) {
                return reason;
            }
            self.safeguard_multipliers();
            inner_tolerance = eps_opt.max(0.1 * inner_tolerance);
            if self.report_outer(&measures, callback) == Control::Stop {
                return StopReason::Interrupted;
            }
        }
    }

    /// The stopping test of the outer loop proper.
    fn outer_stop(
        &self,
        outcome: &InnerOutcome,
        m: &OuterMeasures,
        unconstrained: bool,
    ) -> Option<StopReason> {
        let o = self.options;
        if m.infeasibility <= o.feasibility_tolerance
            && m.complementarity <= o.complementarity_tolerance
            && outcome.projected_gradient <= o.optimality_tolerance
        {
            Some(StopReason::Converged)
        } else if unconstrained {
            // The single subproblem stopped short without hitting a limit: nothing in the
            // outer loop can change that.
            Some(StopReason::Stalled)
        } else if outcome.status == InnerStatus::Stalled
            && outcome.iterations == 0
            && m.infeasibility <= o.feasibility_tolerance
            && m.complementarity <= o.complementarity_tolerance
        {
            // Feasible and complementary, so the penalty stays, and the multipliers barely
            // move: the next subproblem is this one again, and would stall again (observed:
            // 35 outer iterations in a row without a step on a packing problem).
            Some(StopReason::Stalled)
        } else if self.outer_iterations >= o.max_outer_iterations {
            Some(StopReason::MaxOuterIterations)
        } else {
            None
        }
    }

    /// Step 3: ρ ← γρ unless the infeasibility–complementarity measure dropped by τ.
    fn update_penalty(
        &mut self,
        m: &OuterMeasures,
        previous: Option<OuterMeasures>,
    ) -> Result<(), StopReason> {
        let o = self.options;
        // Once feasible and complementary to tolerance, the measure sits at rounding level
        // and cannot keep halving; raising ρ then only ill-conditions the subproblems.
        let good_enough = m.infeasibility <= o.feasibility_tolerance
            && m.complementarity <= o.complementarity_tolerance;
        let Some(prev) = previous else {
            return Ok(());
        };
        if good_enough || m.progress <= o.required_decrease * prev.progress {
            return Ok(());
        }
        let rho = self.al.penalty * o.penalty_increase;
        if rho > o.max_penalty {
            return Err(StopReason::PenaltyTooLarge);
        }
        self.al.penalty = rho;
        Ok(())
    }

    /// Maps an inner stop that ends the whole run to its reason.
    fn inner_stop(&mut self, outcome: &InnerOutcome, unconstrained: bool) -> Option<StopReason> {
        match outcome.status {
            InnerStatus::Interrupted => Some(StopReason::Interrupted),
            InnerStatus::MaxEvaluations => Some(StopReason::MaxEvaluations),
            InnerStatus::NonFinite => {
                let what = self.al.diagnose(&self.x, &mut self.grad);
                Some(StopReason::NonFinite {
                    what,
                    outer_iteration: self.outer_iterations,
                    inner_iteration: outcome.iterations,
                })
            }
            InnerStatus::MaxIterations if unconstrained => Some(StopReason::MaxInnerIterations),
            _ => None,
        }
    }

    fn non_finite(&mut self, what: Evaluation, inner_iteration: usize) -> StopReason {
        StopReason::NonFinite {
            what,
            outer_iteration: self.outer_iterations,
            inner_iteration,
        }
    }

    /// Step 1: minimise the augmented Lagrangian over the box from the current x.
    fn solve_subproblem<C: FnMut(&Progress<'_>) -> Control>(
        &mut self,
        tolerance: f64,
        callback: &mut C,
    ) -> InnerOutcome {
        let settings = InnerSettings {
            tolerance,
            max_iterations: self.options.max_inner_iterations,
            max_evaluations: self.options.max_evaluations,
        };
        // The monitor cannot borrow `self.al` (the solver holds it mutably), so it gets copies
        // of the two values it reports; `estimates` is free during the inner solve.
        self.estimates.copy_from_slice(&self.al.multipliers);
        let (outer_iteration, done, penalty) = (
            self.outer_iterations,
            self.inner_iterations,
            self.al.penalty,
        );
        let multipliers = &self.estimates;
        let mut monitor = |it: usize, x: &[f64], merit: f64, pg: f64, evaluations: usize| {
            callback(&Progress {
                outer_iteration,
                inner_iteration: it,
                total_inner_iterations: done + it,
                evaluations,
                x,
                penalty,
                safeguarded_multipliers: multipliers,
                event: Event::Inner {
                    merit,
                    projected_gradient: pg,
                },
            })
        };
        let f: &mut dyn Smooth = &mut self.al;
        let bounds = (&self.lower[..], &self.upper[..]);
        let method: &mut dyn Method = match &mut self.inner {
            InnerWorkspace::Spg(ws) => ws,
            InnerWorkspace::Lbfgs(ws) => ws,
            InnerWorkspace::Newton(ws) => ws,
        };
        inner::minimize(
            f,
            &mut self.x,
            &mut self.grad,
            bounds,
            &settings,
            method,
            &mut monitor,
        )
    }

    /// Step 2 and the measures of steps 3 and of the stopping test, at the current x.
    fn measure(&mut self) -> Result<OuterMeasures, Evaluation> {
        let objective = self.al.objective(&self.x, None);
        if !objective.is_finite() {
            return Err(Evaluation::Objective);
        }
        self.al.constraints(&self.x, &mut self.constraints);
        let phr = self.al.phr();
        let n_eq = self.al.n_eq;
        let rho = phr.penalty();
        let mut m = OuterMeasures {
            objective,
            infeasibility: 0.0,
            progress: 0.0,
            complementarity: 0.0,
        };
        for (i, (&c, est)) in self.constraints.iter().zip(&mut self.estimates).enumerate() {
            if !c.is_finite() {
                return Err(Evaluation::Constraint { index: i });
            }
            let scaled = self.al.constraint_scales[i] * c;
            *est = phr.estimate(i, c);
            if i < n_eq {
                m.infeasibility = m.infeasibility.max(c.abs());
                m.progress = m.progress.max(scaled.abs());
            } else {
                m.infeasibility = m.infeasibility.max(c.max(0.0));
                let v = scaled.max(-phr.multiplier(i) / rho);
                m.progress = m.progress.max(v.abs());
                m.complementarity = m.complementarity.max((-scaled).min(*est).abs());
            }
        }
        Ok(m)
    }

    fn keep_if_best(&mut self, m: &OuterMeasures) {
        let feasible = m.infeasibility <= self.options.feasibility_tolerance;
        if feasible && self.best.is_none_or(|(f, _)| m.objective < f) {
            self.best = Some((m.objective, m.infeasibility));
            self.best_x.copy_from_slice(&self.x);
        }
    }

    /// Step 4: project the estimates onto the safeguarding box.
    fn safeguard_multipliers(&mut self) {
        let (lmin, lmax) = self.options.equality_multiplier_bounds;
        let mu_max = self.options.max_inequality_multiplier;
        let n_eq = self.al.n_eq;
        for (i, (bar, &est)) in self
            .al
            .multipliers
            .iter_mut()
            .zip(&self.estimates)
            .enumerate()
        {
            *bar = if i < n_eq {
                est.clamp(lmin, lmax)
            } else {
                est.clamp(0.0, mu_max)
            };
        }
    }

    fn report_outer<C: FnMut(&Progress<'_>) -> Control>(
        &self,
        m: &OuterMeasures,
        callback: &mut C,
    ) -> Control {
        callback(&Progress {
            outer_iteration: self.outer_iterations,
            inner_iteration: 0,
            total_inner_iterations: self.inner_iterations,
            evaluations: self.al.function_evaluations,
            x: &self.x,
            penalty: self.al.penalty,
            safeguarded_multipliers: &self.al.multipliers,
            event: Event::Outer {
                objective: m.objective,
                infeasibility: m.infeasibility,
                complementarity: m.complementarity,
                projected_gradient: self.projected_gradient,
            },
        })
    }

    fn finish(self, stop_reason: StopReason, start: Instant) -> Solution {
        let last = self.last.unwrap_or(OuterMeasures {
            objective: f64::NAN,
            infeasibility: f64::NAN,
            progress: f64::NAN,
            complementarity: f64::NAN,
        });
        let use_best = stop_reason != StopReason::Converged && self.best.is_some();
        let (x, objective, infeasibility) = match self.best {
            Some((f, infeas)) if use_best => (self.best_x, f, infeas),
            _ => (self.x, last.objective, last.infeasibility),
        };
        let n_eq = self.al.n_eq;
        let unscale =
            |(i, &e): (usize, &f64)| e * self.al.constraint_scales[i] / self.al.objective_scale;
        let multipliers: Vec<f64> = self.estimates.iter().enumerate().map(unscale).collect();
        Solution {
            x,
            equality_multipliers: multipliers[..n_eq].to_vec(),
            inequality_multipliers: multipliers[n_eq..].to_vec(),
            report: Report {
                stop_reason,
                outer_iterations: self.outer_iterations,
                inner_iterations: self.inner_iterations,
                function_evaluations: self.al.function_evaluations,
                gradient_evaluations: self.al.gradient_evaluations,
                constraint_evaluations: self.al.constraint_evaluations,
                hessian_products: match &self.inner {
                    InnerWorkspace::Newton(ws) => ws.cg_iterations,
                    _ => 0,
                },
                infeasibility,
                complementarity: last.complementarity,
                projected_gradient_norm: self.projected_gradient,
                penalty: self.al.penalty,
                objective,
                best_feasible_objective: self.best.map(|(f, _)| f),
                returned_best_feasible: use_best,
                wall_time: start.elapsed(),
            },
        }
    }
}

/// Rejects NaN bounds and lower > upper.
fn check_bounds(lower: &[f64], upper: &[f64]) -> Result<(), Error> {
    for (index, (&l, &u)) in lower.iter().zip(upper).enumerate() {
        let invalid = l.is_nan() || u.is_nan() || l > u;
        if invalid || l == f64::INFINITY || u == f64::NEG_INFINITY {
            return Err(Error::InvalidBounds {
                index,
                lower: l,
                upper: u,
            });
        }
    }
    Ok(())
}
