//! What the two inner (bound-constrained) solvers share: the smooth-function interface they
//! minimise, their settings, and how they report back to the outer loop.

use crate::projection::all_finite;
use crate::report::Control;

/// A smooth function on the box, evaluated with its gradient.
pub(crate) trait Smooth {
    /// Returns F(x) and overwrites `grad` with ∇F(x). Non-finite results are allowed and mean
    /// "outside the domain".
    fn value_grad(&mut self, x: &[f64], grad: &mut [f64]) -> f64;
    /// Number of evaluations so far (monotone), for the evaluation budget.
    fn evaluations(&self) -> usize;
}

/// Settings of one inner solve.
#[derive(Debug, Clone, Copy)]
pub(crate) struct InnerSettings {
    /// Stop when ‖P(x − ∇F) − x‖∞ ≤ tolerance.
    pub tolerance: f64,
    /// Iteration cap for this solve.
    pub max_iterations: usize,
    /// Cap on `Smooth::evaluations()` (absolute, shared with the outer loop).
    pub max_evaluations: usize,
}

/// Why an inner solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum InnerStatus {
    /// Projected gradient below tolerance.
    Converged,
    /// Iteration cap.
    MaxIterations,
    /// Evaluation budget exhausted.
    MaxEvaluations,
    /// The monitor asked to stop.
    Interrupted,
    /// The line search could not decrease F (the step shrank to rounding level).
    Stalled,
    /// Only non-finite values were found along the search direction, or at the start.
    NonFinite,
}

/// The result of an inner solve; the final iterate, its value and gradient are left in the
/// caller's buffers.
#[derive(Debug, Clone, Copy)]
pub(crate) struct InnerOutcome {
    pub status: InnerStatus,
    pub iterations: usize,
    pub value: f64,
    pub projected_gradient: f64,
}

impl InnerOutcome {
    /// Evaluates `f` at the starting point `x` (the gradient into `grad`). `Err` is the outcome
    /// to return at once, with status `NonFinite`, when the value or the gradient is not finite.
    pub(crate) fn start<S: Smooth + ?Sized>(
        f: &mut S,
        x: &[f64],
        grad: &mut [f64],
    ) -> Result<Self, Self> {
        let value = f.value_grad(x, grad);
        let outcome = InnerOutcome {
            status: InnerStatus::NonFinite,
            iterations: 0,
            value,
            projected_gradient: f64::INFINITY,
        };
        if !value.is_finite() || !all_finite(grad) {
            Err(outcome)
        } else {
            Ok(outcome)
        }
    }

    /// Records iterate `k` with its value and projected-gradient norm, then applies
    /// [`InnerSettings::stop`]: `Some` is the outcome to return.
    pub(crate) fn at_iteration(
        &mut self,
        k: usize,
        value: f64,
        projected_gradient: f64,
        settings: &InnerSettings,
        interrupt: impl FnOnce() -> Control,
    ) -> Option<Self> {
        self.iterations = k;
        self.value = value;
        self.projected_gradient = projected_gradient;
        let status = settings.stop(k, projected_gradient, interrupt)?;
        self.status = status;
        Some(*self)
    }
}

impl InnerSettings {
    /// The tests both solvers apply at the top of iteration `k`, in order: converged, stopped
    /// by the monitor (`interrupt`, called only when not converged), out of iterations.
    pub(crate) fn stop(
        &self,
        k: usize,
        projected_gradient: f64,
        interrupt: impl FnOnce() -> Control,
    ) -> Option<InnerStatus> {
        if projected_gradient <= self.tolerance {
            Some(InnerStatus::Converged)
        } else if interrupt() == Control::Stop {
            Some(InnerStatus::Interrupted)
        } else if k >= self.max_iterations {
            Some(InnerStatus::MaxIterations)
        } else {
            None
        }
    }
}

/// Called once per inner iteration with (iteration, x, F(x), projected-gradient norm,
/// evaluations so far).
pub(crate) type Monitor<'m> = dyn FnMut(usize, &[f64], f64, f64, usize) -> Control + 'm;

/// Armijo constant: the fraction of the predicted decrease that a step must achieve.
pub(crate) const ARMIJO: f64 = 1e-4;

/// How many backtracking steps a line search tries before declaring failure.
pub(crate) const MAX_BACKTRACKS: usize = 60;

/// Safeguarded minimiser of the quadratic interpolating φ(0), φ'(0) and φ(α), kept in
/// [lo·α, hi·α] (otherwise α/2) so that backtracking neither stalls nor overshoots.
pub(crate) fn backtrack(alpha: f64, f0: f64, slope: f64, f_alpha: f64, lo: f64, hi: f64) -> f64 {
    if !f_alpha.is_finite() {
        // Outside the model's domain: retreat fast rather than interpolate a meaningless value.
        return 0.1 * alpha;
    }
    let denom = f_alpha - f0 - alpha * slope;
    let trial = -0.5 * alpha * alpha * slope / denom;
    if denom > 0.0 && trial >= lo * alpha && trial <= hi * alpha {
        trial
    } else {
        0.5 * alpha
    }
}

/// Relative slack on F allowed by [`descends_by_gradients`]: far above rounding noise, far
/// below any decrease the solvers care about.
const NOISE_SLACK: f64 = 1e-10;

/// Sufficient decrease judged from gradients instead of values, for steps where F(trial) and
/// F(x) are equal up to rounding noise.
///
/// Near a solution the decrease a step can achieve falls below what a sum of large terms can
/// resolve (a quadratic whose value is 0.08 but whose terms are of order 10 has noise 1e-15,
/// while the steps left decrease it by 1e-16), so the Armijo test on values rejects every
/// step although the gradient is still above tolerance. The trapezoid rule
/// F(x + s) − F(x) ≈ ½ (∇F(x) + ∇F(x + s))ᵀ s is exact for quadratics and has no
/// cancellation, so the Armijo test is applied to it instead, provided the values agree to
/// within a small relative slack. This is the idea of the approximate Wolfe conditions of
/// Hager & Zhang (SIAM J. Optim. 16(1), 170–192, 2005), applied on the projected path.
pub(crate) fn descends_by_gradients(
    (value, x, grad): (f64, &[f64], &[f64]),
    (trial, x_trial, g_trial): (f64, &[f64], &[f64]),
) -> bool {
    let mut predicted = 0.0;
    let mut trapezoid = 0.0;
    for i in 0..x.len() {
        let s = x_trial[i] - x[i];
        predicted += grad[i] * s;
        trapezoid += 0.5 * (grad[i] + g_trial[i]) * s;
    }
    predicted < 0.0
        && trapezoid <= ARMIJO * predicted
        && trial - value <= NOISE_SLACK * value.abs().max(trial.abs())
}
