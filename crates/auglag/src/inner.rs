//! What the two inner (bound-constrained) solvers share: the smooth-function interface they
//! minimise, their settings, the iteration loop and the backtracking line search, and how they
//! report back to the outer loop. A solver itself ([`Method`]) only picks directions and keeps
//! its memory.

use crate::projection::{
    all_finite, clamp, copy, map_blocks, norm_inf, projected_gradient_norm, step_dot,
};
use crate::report::Control;

/// A smooth function on the box, evaluated with its gradient.
pub(crate) trait Smooth {
    /// Returns F(x) and overwrites `grad` with ∇F(x). Non-finite results are allowed and mean
    /// "outside the domain".
    fn value_grad(&mut self, x: &[f64], grad: &mut [f64]) -> f64;
    /// Number of evaluations so far (monotone), for the evaluation budget.
    fn evaluations(&self) -> usize;
    /// Overwrites `out` with ∇²F(x) v and returns true, or returns false when F offers no
    /// Hessian products (the caller then differences gradients).
    fn hessian_times(&mut self, x: &[f64], v: &[f64], out: &mut [f64]) -> bool {
        let _ = (x, v, out);
        false
    }
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

/// Where a step starts: the current iterate, with the box and the limits of its solve.
#[derive(Clone, Copy)]
pub(crate) struct Iterate<'a> {
    pub x: &'a [f64],
    /// ∇F(x).
    pub grad: &'a [f64],
    /// F(x).
    pub value: f64,
    /// ‖P(x − ∇F(x)) − x‖∞.
    pub projected_gradient: f64,
    pub lower: &'a [f64],
    pub upper: &'a [f64],
    pub settings: &'a InnerSettings,
}

/// What sets one inner solver apart from the other: how it picks the next iterate and what it
/// remembers between iterations. [`minimize`] runs the iteration loop they share.
pub(crate) trait Method {
    /// Clears the memory of a previous solve, at a start point with F = `value` and
    /// projected-gradient norm `pg`.
    fn begin(&mut self, value: f64, pg: f64);

    /// Searches from `at` for the next iterate; on success returns its value, with the point and
    /// its gradient left in [`trial`](Self::trial).
    fn step(&mut self, f: &mut dyn Smooth, at: Iterate<'_>) -> Result<f64, InnerStatus>;

    /// Learns from the step of iteration `k` from (`x`, `grad`) to the trial point, whose value
    /// is `value`; called before the trial point replaces `x`.
    fn accept(&mut self, k: usize, x: &[f64], grad: &[f64], value: f64);

    /// The point found by the last successful [`step`](Self::step) and its gradient.
    fn trial(&self) -> (&[f64], &[f64]);
}

/// Minimises `f` on [lower, upper] from `x` (already in the box) with `method`. On return `x`,
/// `grad` and the outcome's value describe the last iterate.
pub(crate) fn minimize(
    f: &mut dyn Smooth,
    x: &mut [f64],
    grad: &mut [f64],
    bounds: (&[f64], &[f64]),
    settings: &InnerSettings,
    method: &mut dyn Method,
    monitor: &mut Monitor<'_>,
) -> InnerOutcome {
    let (lower, upper) = bounds;
    let mut outcome = match InnerOutcome::start(f, x, grad) {
        Ok(outcome) => outcome,
        Err(outcome) => return outcome,
    };
    let mut value = outcome.value;
    let mut pg = projected_gradient_norm(x, grad, lower, upper);
    method.begin(value, pg);
    let mut k = 0;
    loop {
        let interrupt = || monitor(k, x, value, pg, f.evaluations());
        if let Some(done) = outcome.at_iteration(k, value, pg, settings, interrupt) {
            return done;
        }
        let at = Iterate {
            x,
            grad,
            value,
            projected_gradient: pg,
            lower,
            upper,
            settings,
        };
        let new_value = match method.step(f, at) {
            Ok(v) => v,
            Err(status) => {
                outcome.status = status;
                return outcome;
            }
        };
        method.accept(k, x, grad, new_value);
        let (x_trial, g_trial) = method.trial();
        copy(x, x_trial);
        copy(grad, g_trial);
        value = new_value;
        pg = projected_gradient_norm(x, grad, lower, upper);
        k += 1;
    }
}

/// Called once per inner iteration with (iteration, x, F(x), projected-gradient norm,
/// evaluations so far).
pub(crate) type Monitor<'m> = dyn FnMut(usize, &[f64], f64, f64, usize) -> Control + 'm;

/// Armijo constant: the fraction of the predicted decrease that a step must achieve.
const ARMIJO: f64 = 1e-4;

/// How many backtracking steps a line search tries before declaring failure.
const MAX_BACKTRACKS: usize = 60;

/// The sufficient-decrease test of a line search, with γ = [`ARMIJO`].
#[derive(Debug, Clone, Copy)]
pub(crate) enum Acceptance {
    /// Monotone, on the projected path: F(x(α)) ≤ F(x) + γ ∇F(x)ᵀ(x(α) − x), where
    /// ∇F(x)ᵀ(x(α) − x) < 0. Each backtrack takes α to between 0.1 and 0.5 times its value.
    ProjectedPath,
    /// Nonmonotone (GLL): F(x + αd) ≤ `reference` + γ α ∇F(x)ᵀd, `reference` being the largest
    /// of the last few accepted values. Each backtrack takes α to between 0.1 and 0.9 times its
    /// value.
    Nonmonotone {
        /// The largest of the recent values.
        reference: f64,
    },
}

/// Backtracking from `at` along the path x(α) = P(x + α d), α = 1 first, d = `direction` with
/// slope ∇F(x)ᵀd = `slope` < 0. On success returns F at the accepted point, which is left in
/// `trial.0` with its gradient in `trial.1`. A step whose value is equal to F(x) up to rounding
/// is also accepted when [`descends_by_gradients`] holds and it lowers the projected gradient.
pub(crate) fn line_search<S: Smooth + ?Sized>(
    f: &mut S,
    at: Iterate<'_>,
    (direction, slope): (&[f64], f64),
    acceptance: Acceptance,
    trial: (&mut [f64], &mut [f64]),
) -> Result<f64, InnerStatus> {
    let (x_trial, g_trial) = trial;
    let (x, grad, value) = (at.x, at.grad, at.value);
    let (lower, upper) = (at.lower, at.upper);
    let d_norm = norm_inf(direction);
    let x_scale = norm_inf(x).max(1.0);
    let mut alpha: f64 = 1.0;
    let mut last_finite = true;
    for _ in 0..MAX_BACKTRACKS {
        if f.evaluations() >= at.settings.max_evaluations {
            return Err(InnerStatus::MaxEvaluations);
        }
        map_blocks(x_trial, |start, t| {
            for (k, t) in t.iter_mut().enumerate() {
                let i = start + k;
                // Rounding in x + αd may step a hair outside the box; the clamp keeps
                // feasibility exact.
                *t = clamp(x[i] + alpha * direction[i], lower[i], upper[i]);
            }
        });
        let decrease = step_dot(grad, x_trial, x);
        let f_trial = f.value_grad(x_trial, g_trial);
        last_finite = f_trial.is_finite() && all_finite(g_trial);
        let sufficient = match acceptance {
            Acceptance::ProjectedPath => decrease < 0.0 && f_trial <= value + ARMIJO * decrease,
            Acceptance::Nonmonotone { reference } => f_trial <= reference + ARMIJO * alpha * slope,
        };
        if last_finite && sufficient {
            return Ok(f_trial);
        }
        if last_finite
            && descends_by_gradients((value, x, grad), (f_trial, x_trial, g_trial))
            && projected_gradient_norm(x_trial, g_trial, lower, upper) < at.projected_gradient
        {
            return Ok(f_trial);
        }
        let f_for_interp = if last_finite { f_trial } else { f64::NAN };
        let hi = match acceptance {
            Acceptance::ProjectedPath => 0.5,
            Acceptance::Nonmonotone { .. } => 0.9,
        };
        alpha = backtrack(alpha, value, slope, f_for_interp, 0.1, hi);
        if alpha * d_norm <= f64::EPSILON * x_scale {
            break;
        }
    }
    Err(if last_finite {
        InnerStatus::Stalled
    } else {
        InnerStatus::NonFinite
    })
}

/// Safeguarded minimiser of the quadratic interpolating φ(0), φ'(0) and φ(α), kept in
/// [lo·α, hi·α] (otherwise α/2) so that backtracking neither stalls nor overshoots.
fn backtrack(alpha: f64, f0: f64, slope: f64, f_alpha: f64, lo: f64, hi: f64) -> f64 {
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
fn descends_by_gradients(
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
