//! What a run tells its caller: progress events for the callback while it runs, and the
//! [`Solution`] with its [`Report`] when it ends.

use std::fmt;
use std::time::Duration;

use crate::error::Evaluation;

/// The callback's answer: go on, or stop as soon as possible (between two iterations) and return
/// the best point so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    /// Keep iterating.
    Continue,
    /// Stop now; the run ends with [`StopReason::Interrupted`].
    Stop,
}

/// Where in the run a [`Progress`] event comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// Start of an inner iteration (before its line search).
    Inner {
        /// Augmented Lagrangian value L_ρ(x) of the current subproblem.
        merit: f64,
        /// ‖P(x − ∇L_ρ(x)) − x‖∞.
        projected_gradient: f64,
    },
    /// End of an outer iteration, after the multiplier and penalty updates. Not emitted for the
    /// outer iteration that ends the run (its values are in the [`Report`]).
    Outer {
        /// Unscaled objective f(x).
        objective: f64,
        /// Unscaled infeasibility max(‖h(x)‖∞, ‖g(x)₊‖∞, bound violation (always 0)).
        infeasibility: f64,
        /// Complementarity ‖min(−g̃(x), μ)‖∞ on the (scaled) inequality constraints.
        complementarity: f64,
        /// Projected gradient of the (scaled) Lagrangian at x with the new multipliers.
        projected_gradient: f64,
    },
}

/// The state handed to the callback.
#[derive(Debug, Clone, Copy)]
pub struct Progress<'a> {
    /// Current outer iteration, counted from 1.
    pub outer_iteration: usize,
    /// Inner iteration within the current subproblem, counted from 0.
    pub inner_iteration: usize,
    /// Inner iterations over the whole run so far.
    pub total_inner_iterations: usize,
    /// Evaluations of the augmented Lagrangian (objective calls) so far.
    pub evaluations: usize,
    /// Current iterate.
    pub x: &'a [f64],
    /// Penalty parameter ρ of the current subproblem (for `Outer`: of the next one).
    pub penalty: f64,
    /// Safeguarded multipliers [λ̄; μ̄] (scaled units) of the current subproblem (for `Outer`:
    /// of the next one); each lies in its safeguarding box.
    pub safeguarded_multipliers: &'a [f64],
    /// What happened.
    pub event: Event,
}

/// Why a run stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// Feasibility, complementarity and optimality tolerances all met.
    Converged,
    /// `max_outer_iterations` reached.
    MaxOuterIterations,
    /// Without general constraints there is a single subproblem, and it reached
    /// `max_inner_iterations`.
    MaxInnerIterations,
    /// The line search could not decrease the function any more although the projected
    /// gradient is above tolerance (stationary to within rounding, or a non-smooth/inaccurate
    /// gradient): without general constraints, in the single subproblem; with constraints, in a
    /// subproblem that could not take a single step from a point already feasible and
    /// complementary to tolerance, where further outer iterations would repeat it unchanged.
    Stalled,
    /// `max_evaluations` reached.
    MaxEvaluations,
    /// The callback returned [`Control::Stop`].
    Interrupted,
    /// The penalty parameter would exceed `max_penalty`: the problem is likely infeasible
    /// (or its constraints degenerate) near the point reached.
    PenaltyTooLarge,
    /// A user function returned NaN or ±∞ and backtracking could not find a finite point.
    NonFinite {
        /// Which function.
        what: Evaluation,
        /// Outer iteration (from 1).
        outer_iteration: usize,
        /// Inner iteration within that outer iteration (from 0).
        inner_iteration: usize,
    },
}

impl fmt::Display for StopReason {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Converged => write!(f, "converged"),
            Self::MaxOuterIterations => write!(f, "maximum number of outer iterations reached"),
            Self::MaxInnerIterations => write!(f, "maximum number of inner iterations reached"),
            Self::Stalled => write!(f, "line search stalled above the optimality tolerance"),
            Self::MaxEvaluations => write!(f, "maximum number of evaluations reached"),
            Self::Interrupted => write!(f, "interrupted by the callback"),
            Self::PenaltyTooLarge => {
                write!(
                    f,
                    "penalty parameter exceeded its maximum (infeasible problem?)"
                )
            }
            Self::NonFinite {
                what,
                outer_iteration,
                inner_iteration,
            } => write!(
                f,
                "NaN or infinity returned by {what} at outer iteration {outer_iteration}, \
                 inner iteration {inner_iteration}"
            ),
        }
    }
}

/// Statistics of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Report {
    /// Why the run stopped.
    pub stop_reason: StopReason,
    /// Outer (augmented Lagrangian) iterations.
    pub outer_iterations: usize,
    /// Inner iterations, summed over all subproblems.
    pub inner_iterations: usize,
    /// Calls of the objective (or of the fused hook).
    pub function_evaluations: usize,
    /// Of which with a gradient.
    pub gradient_evaluations: usize,
    /// Calls of the constraints (or of the fused hook when there are constraints).
    pub constraint_evaluations: usize,
    /// Hessian–vector products of the truncated-Newton inner solver (exact, or difference
    /// quotients counted also as evaluations); 0 with the other inner solvers.
    pub hessian_products: usize,
    /// Unscaled sup-norm infeasibility max(‖h‖∞, ‖g₊‖∞) at the returned point.
    pub infeasibility: f64,
    /// Complementarity ‖min(−g̃, μ)‖∞ at the last outer iterate.
    pub complementarity: f64,
    /// Sup-norm projected gradient of the (scaled) Lagrangian at the last outer iterate.
    pub projected_gradient_norm: f64,
    /// Final penalty parameter ρ (0 for a problem without general constraints).
    pub penalty: f64,
    /// Objective f at the returned point.
    pub objective: f64,
    /// Lowest objective among the outer iterates whose infeasibility was within tolerance.
    pub best_feasible_objective: Option<f64>,
    /// True when the run did not converge and the returned point is that best feasible iterate
    /// rather than the last one.
    pub returned_best_feasible: bool,
    /// Wall-clock time of the run.
    pub wall_time: Duration,
}

/// The result of a run: the returned point, multiplier estimates and the report.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// The returned point: the last iterate on convergence, otherwise the best feasible outer
    /// iterate if there was one, otherwise the last iterate.
    pub x: Vec<f64>,
    /// Multipliers of h(x) = 0 in the sign convention ∇f + Σ λᵢ∇hᵢ + Σ μᵢ∇gᵢ (unscaled), from
    /// the last outer iteration.
    pub equality_multipliers: Vec<f64>,
    /// Multipliers μ ≥ 0 of g(x) ≤ 0 (unscaled), from the last outer iteration.
    pub inequality_multipliers: Vec<f64>,
    /// Statistics.
    pub report: Report,
}

impl fmt::Display for Report {
    /// One line for logs: stop reason, iterations, evaluations and final measures.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: f = {:.10e}, infeasibility {:.2e}, projected gradient {:.2e}, \
             complementarity {:.2e}, {} outer / {} inner iterations, {} evaluations, \
             penalty {:.1e}, {:.3} s",
            self.stop_reason,
            self.objective,
            self.infeasibility,
            self.projected_gradient_norm,
            self.complementarity,
            self.outer_iterations,
            self.inner_iterations,
            self.function_evaluations,
            self.penalty,
            self.wall_time.as_secs_f64()
        )
    }
}
