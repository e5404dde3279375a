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

use crate::inner::{Acceptance, InnerStatus, Iterate, Method, Smooth, line_search};
use crate::projection::{clamp, dot};

/// Buffers of the SPG method, allocated once and reused by every inner solve.
#[derive(Debug, Clone)]
pub(crate) struct SpgWorkspace {
    direction: Vec<f64>,
    x_trial: Vec<f64>,
    g_trial: Vec<f64>,
    /// Last M accepted values for the GLL reference value (a ring buffer).
    history: Vec<f64>,
    step_bounds: (f64, f64),
    /// λ of the current iteration.
    lambda: f64,
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
            lambda: 1.0,
        }
    }
}

impl Method for SpgWorkspace {
    fn begin(&mut self, value: f64, pg: f64) {
        self.history.iter_mut().for_each(|h| *h = f64::NEG_INFINITY);
        self.history[0] = value;
        let (step_min, step_max) = self.step_bounds;
        self.lambda = if pg > 0.0 {
            (1.0 / pg).clamp(step_min, step_max)
        } else {
            1.0
        };
    }

    fn step(&mut self, f: &mut dyn Smooth, at: Iterate<'_>) -> Result<f64, InnerStatus> {
        for (((d, &xi), &gi), (&l, &u)) in self
            .direction
            .iter_mut()
            .zip(at.x)
            .zip(at.grad)
            .zip(at.lower.iter().zip(at.upper))
        {
            *d = clamp(xi - self.lambda * gi, l, u) - xi;
        }
        let slope = dot(at.grad, &self.direction);
        let reference = self
            .history
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let trial = (&mut self.x_trial[..], &mut self.g_trial[..]);
        let acceptance = Acceptance::Nonmonotone { reference };
        line_search(f, at, (&self.direction, slope), acceptance, trial)
    }

    fn accept(&mut self, k: usize, x: &[f64], grad: &[f64], value: f64) {
        self.lambda = spectral_step(x, grad, self);
        let slot = (k + 1) % self.history.len();
        self.history[slot] = value;
    }

    fn trial(&self) -> (&[f64], &[f64]) {
        (&self.x_trial, &self.g_trial)
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
