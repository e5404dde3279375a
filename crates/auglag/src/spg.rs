//! Nonmonotone spectral projected gradient (SPG) for min F(x) on a box.
//!
//! Iteration k (the SPG2 variant of Birgin, Martínez & Raydan):
//!
//! ```text
//! d_k   = P(x_k − λ_k ∇F(x_k)) − x_k                      (feasible direction)
//! x_k+1 = x_k + α d_k, α ∈ {1, then safeguarded quadratic backtracking} such that
//!         F(x_k + α d_k) ≤ max_{0≤j<M} F(x_k−j) + γ α ∇F(x_k)ᵀd_k   (GLL, M = 10, γ = 1e-4)
//! λ_k+1 = clamp(sᵀs / sᵀy, λ_min, λ_max), or λ_max when sᵀy ≤ 0,
//!         s = x_k+1 − x_k, y = ∇F(x_k+1) − ∇F(x_k)
//! ```
//!
//! The Barzilai–Borwein step makes the method fast on well-scaled problems, and the
//! nonmonotone (Grippo–Lampariello–Lucidi) acceptance lets it take the occasional uphill
//! spectral step that a monotone search would cut short. Since d_k is a convex combination of
//! feasible points, x_k + α d_k stays in the box for α ≤ 1. Memory: five n-vectors.
//!
//! # References
//! - E. G. Birgin, J. M. Martínez, M. Raydan, "Nonmonotone spectral projected gradient methods
//!   on convex sets", SIAM J. Optim. 10(4), 1196–1211, 2000.
//! - L. Grippo, F. Lampariello, S. Lucidi, "A nonmonotone line search technique for Newton's
//!   method", SIAM J. Numer. Anal. 23(4), 707–716, 1986.
//! - J. Barzilai, J. M. Borwein, "Two-point step size gradient methods", IMA J. Numer. Anal. 8,
//!   141–148, 1988.

use crate::inner::{
    ARMIJO, InnerOutcome, InnerSettings, InnerStatus, MAX_BACKTRACKS, Monitor, Smooth, backtrack,
    descends_by_gradients,
};
use crate::projection::{all_finite, clamp, dot, norm_inf, projected_gradient_norm};

/// Buffers of the SPG method, allocated once and reused by every inner solve.
#[derive(Debug, Clone)]
pub(crate) struct SpgWorkspace {
    direction: Vec<f64>,
    x_trial: Vec<f64>,
    g_trial: Vec<f64>,
    /// Last M accepted values for the GLL reference value (a ring buffer).
    history: Vec<f64>,
    step_bounds: (f64, f64),
}

impl SpgWorkspace {
    /// `memory` is M of the GLL rule (≥ 1); `step_bounds` = (λ_min, λ_max).
    pub(crate) fn new(n: usize, memory: usize, step_bounds: (f64, f64)) -> Self {
        Self {
            direction: vec![0.0; n],
            x_trial: vec![0.0; n],
            g_trial: vec![0.0; n],
            history: vec![f64::NEG_INFINITY; memory.max(1)],
            step_bounds,
        }
    }
}

/// Minimises `f` on [lower, upper] from `x` (already in the box). On return `x`, `grad` and the
/// outcome's value describe the last iterate.
pub(crate) fn minimize<S: Smooth + ?Sized>(
    f: &mut S,
    x: &mut [f64],
    grad: &mut [f64],
    bounds: (&[f64], &[f64]),
    settings: &InnerSettings,
    ws: &mut SpgWorkspace,
    monitor: &mut Monitor<'_>,
) -> InnerOutcome {
    let (lower, upper) = bounds;
    let (step_min, step_max) = ws.step_bounds;
    let mut outcome = match InnerOutcome::start(f, x, grad) {
        Ok(outcome) => outcome,
        Err(outcome) => return outcome,
    };
    let mut value = outcome.value;
    ws.history.iter_mut().for_each(|h| *h = f64::NEG_INFINITY);
    ws.history[0] = value;
    let mut pg = projected_gradient_norm(x, grad, lower, upper);
    let mut step = if pg > 0.0 {
        (1.0 / pg).clamp(step_min, step_max)
    } else {
        1.0
    };
    let mut k = 0;
    loop {
        let interrupt = || monitor(k, x, value, pg, f.evaluations());
        if let Some(done) = outcome.at_iteration(k, value, pg, settings, interrupt) {
            return done;
        }
        for (((d, &xi), &gi), (&l, &u)) in ws
            .direction
            .iter_mut()
            .zip(x.iter())
            .zip(grad.iter())
            .zip(lower.iter().zip(upper))
        {
            *d = clamp(xi - step * gi, l, u) - xi;
        }
        let slope = dot(grad, &ws.direction);
        let reference = ws.history.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let search = Search {
            value,
            slope,
            reference,
            projected_gradient: pg,
        };
        let new_value = match line_search(f, (x, grad), &search, bounds, settings, ws) {
            Ok(v) => v,
            Err(status) => {
                outcome.status = status;
                return outcome;
            }
        };
        step = spectral_step(x, grad, ws);
        x.copy_from_slice(&ws.x_trial);
        grad.copy_from_slice(&ws.g_trial);
        value = new_value;
        k += 1;
        let slot = k % ws.history.len();
        ws.history[slot] = value;
        pg = projected_gradient_norm(x, grad, lower, upper);
    }
}

/// λ = clamp(sᵀs / sᵀy, λ_min, λ_max) (λ_max when sᵀy ≤ 0) from s = x⁺ − x and y = g⁺ − g,
/// with x⁺, g⁺ in the workspace; s and y are never stored.
fn spectral_step(x: &[f64], grad: &[f64], ws: &SpgWorkspace) -> f64 {
    let (step_min, step_max) = ws.step_bounds;
    let mut ss = 0.0;
    let mut sy = 0.0;
    for (((&xn, &xo), &gn), &go) in ws.x_trial.iter().zip(x).zip(&ws.g_trial).zip(grad) {
        let s = xn - xo;
        ss += s * s;
        sy += s * (gn - go);
    }
    if sy <= 0.0 {
        step_max
    } else {
        (ss / sy).clamp(step_min, step_max)
    }
}

/// What the line search needs to know about the current iterate.
struct Search {
    /// F(x).
    value: f64,
    /// ∇F(x)ᵀd < 0.
    slope: f64,
    /// The GLL reference max of the last M values.
    reference: f64,
    /// ‖P(x − ∇F(x)) − x‖∞, for the rounding-level acceptance.
    projected_gradient: f64,
}

/// GLL backtracking along `ws.direction`; on success returns F at the accepted point, which is
/// left in `ws.x_trial` with its gradient in `ws.g_trial`.
fn line_search<S: Smooth + ?Sized>(
    f: &mut S,
    (x, grad): (&[f64], &[f64]),
    search: &Search,
    bounds: (&[f64], &[f64]),
    settings: &InnerSettings,
    ws: &mut SpgWorkspace,
) -> Result<f64, InnerStatus> {
    let (lower, upper) = bounds;
    let d_norm = norm_inf(&ws.direction);
    let x_scale = norm_inf(x).max(1.0);
    let mut alpha: f64 = 1.0;
    let mut last_finite = true;
    for _ in 0..MAX_BACKTRACKS {
        if f.evaluations() >= settings.max_evaluations {
            return Err(InnerStatus::MaxEvaluations);
        }
        for ((((t, &xi), &di), &l), &u) in ws
            .x_trial
            .iter_mut()
            .zip(x)
            .zip(&ws.direction)
            .zip(lower)
            .zip(upper)
        {
            // Rounding in x + αd may step a hair outside the box; the clamp keeps feasibility exact.
            *t = clamp(xi + alpha * di, l, u);
        }
        let trial = f.value_grad(&ws.x_trial, &mut ws.g_trial);
        last_finite = trial.is_finite() && all_finite(&ws.g_trial);
        if last_finite && trial <= search.reference + ARMIJO * alpha * search.slope {
            return Ok(trial);
        }
        if last_finite
            && descends_by_gradients((search.value, x, grad), (trial, &ws.x_trial, &ws.g_trial))
            && projected_gradient_norm(&ws.x_trial, &ws.g_trial, lower, upper)
                < search.projected_gradient
        {
            return Ok(trial);
        }
        let f_for_interp = if last_finite { trial } else { f64::NAN };
        alpha = backtrack(alpha, search.value, search.slope, f_for_interp, 0.1, 0.9);
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
