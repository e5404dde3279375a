//! The Powell–Hestenes–Rockafellar (PHR) augmented Lagrangian, the merit function that the inner
//! solvers minimise over the box.
//!
//! With penalty ρ > 0, safeguarded multipliers λ̄ (equalities) and μ̄ ≥ 0 (inequalities), and
//! optional scale factors s_f (objective) and sᵢ (constraints), writing c̃ᵢ = sᵢ cᵢ(x):
//!
//! ```text
//! L_ρ(x) = s_f f(x) + Σ_eq   c̃ᵢ (λ̄ᵢ + ρ c̃ᵢ / 2)
//!                   + Σ_ineq { c̃ᵢ (μ̄ᵢ + ρ c̃ᵢ / 2)   if μ̄ᵢ + ρ c̃ᵢ > 0
//!                            { −μ̄ᵢ² / (2ρ)          otherwise
//! ```
//!
//! which is the book's ρ/2 Σ (c̃ᵢ + λ̄ᵢ/ρ)² form minus a constant, written so that no two large
//! numbers are subtracted when λ̄/ρ is large. Its gradient is
//! `s_f ∇f + Σ sᵢ λᵢ⁺ ∇cᵢ` with the first-order multiplier estimates
//! λᵢ⁺ = λ̄ᵢ + ρ c̃ᵢ and μᵢ⁺ = max(0, μ̄ᵢ + ρ c̃ᵢ): at an inner solution, the projected gradient of
//! L_ρ *is* the projected gradient of the Lagrangian at the updated multipliers.
//!
//! # References
//! - E. G. Birgin, J. M. Martínez, *Practical Augmented Lagrangian Methods for Constrained
//!   Optimization*, SIAM, 2014, chapter 4 (the PHR function and Algorithm 4.1).
//! - M. J. D. Powell, "A method for nonlinear constraints in minimization problems", 1969;
//!   M. R. Hestenes, "Multiplier and gradient methods", JOTA 4, 1969;
//!   R. T. Rockafellar, "Augmented Lagrange multiplier functions and duality in nonconvex
//!   programming", SIAM J. Control 12, 1974.

use crate::error::Evaluation;
use crate::inner::Smooth;
use crate::phr::Phr;
use crate::problem::Problem;

/// The augmented Lagrangian of a [`Problem`] as a smooth function on the box, with the scratch
/// buffers it needs (allocated once per run) and evaluation counters.
pub(crate) struct AugmentedLagrangian<'p, P: ?Sized> {
    problem: &'p P,
    pub(crate) penalty: f64,
    pub(crate) n_eq: usize,
    pub(crate) objective_scale: f64,
    pub(crate) constraint_scales: Vec<f64>,
    /// Safeguarded multipliers λ̄ then μ̄, scaled units.
    pub(crate) multipliers: Vec<f64>,
    constraint_values: Vec<f64>,
    weights: Vec<f64>,
    pub(crate) function_evaluations: usize,
    pub(crate) gradient_evaluations: usize,
    pub(crate) constraint_evaluations: usize,
}

impl<'p, P: Problem + ?Sized> AugmentedLagrangian<'p, P> {
    pub(crate) fn new(problem: &'p P) -> Self {
        let m = problem.n_eq() + problem.n_ineq();
        Self {
            problem,
            penalty: 1.0,
            n_eq: problem.n_eq(),
            objective_scale: 1.0,
            constraint_scales: vec![1.0; m],
            multipliers: vec![0.0; m],
            constraint_values: vec![0.0; m],
            weights: vec![0.0; m],
            function_evaluations: 0,
            gradient_evaluations: 0,
            constraint_evaluations: 0,
        }
    }

    pub(crate) fn phr(&self) -> Phr<'_> {
        Phr::new(
            self.penalty,
            self.n_eq,
            self.objective_scale,
            &self.constraint_scales,
            &self.multipliers,
        )
    }

    /// Unscaled f(x), counted.
    pub(crate) fn objective(&mut self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        self.function_evaluations += 1;
        if grad.is_some() {
            self.gradient_evaluations += 1;
        }
        self.problem.objective(x, grad)
    }

    /// Unscaled c(x), counted.
    pub(crate) fn constraints(&mut self, x: &[f64], c: &mut [f64]) {
        if !c.is_empty() {
            self.constraint_evaluations += 1;
            self.problem.constraints(x, c);
        }
    }

    /// Adds J(x)ᵀw to `out` (unscaled); not counted, like the Jᵀw inside an evaluation.
    pub(crate) fn jt_times(&mut self, x: &[f64], w: &[f64], out: &mut [f64]) {
        self.problem.constraints_jt_times(x, w, out);
    }

    fn evaluate(&mut self, x: &[f64], mut grad: Option<&mut [f64]>) -> f64 {
        let wants_grad = grad.is_some();
        self.function_evaluations += 1;
        if wants_grad {
            self.gradient_evaluations += 1;
        }
        let phr = Phr::new(
            self.penalty,
            self.n_eq,
            self.objective_scale,
            &self.constraint_scales,
            &self.multipliers,
        );
        if let Some(v) = self.problem.lagrangian(x, &phr, grad.as_deref_mut()) {
            if !self.multipliers.is_empty() {
                self.constraint_evaluations += 1;
            }
            return v;
        }
        let mut value = self.problem.objective(x, grad.as_deref_mut());
        if self.objective_scale != 1.0 {
            value *= self.objective_scale;
            if let Some(g) = grad.as_deref_mut() {
                g.iter_mut().for_each(|gi| *gi *= self.objective_scale);
            }
        }
        if self.multipliers.is_empty() {
            return value;
        }
        self.constraint_evaluations += 1;
        self.problem.constraints(x, &mut self.constraint_values);
        let mut any_weight = false;
        for (i, (&c, w)) in self
            .constraint_values
            .iter()
            .zip(self.weights.iter_mut())
            .enumerate()
        {
            value += phr.term(i, c);
            *w = phr.derivative(i, c);
            any_weight |= *w != 0.0;
        }
        // Inactive inequalities contribute nothing: skipping the pass matters for the packer,
        // whose overlap sum is zero on most of the run.
        if let (Some(g), true) = (grad, any_weight) {
            self.problem.constraints_jt_times(x, &self.weights, g);
        }
        value
    }

    /// Finds which user function is not finite at `x` (called only after a failure, so the
    /// extra evaluations are not on the hot path).
    pub(crate) fn diagnose(&mut self, x: &[f64], grad: &mut [f64]) -> Evaluation {
        let f = self.objective(x, Some(grad));
        if !f.is_finite() {
            return Evaluation::Objective;
        }
        if grad.iter().any(|v| !v.is_finite()) {
            return Evaluation::ObjectiveGradient;
        }
        let mut c = std::mem::take(&mut self.constraint_values);
        self.constraints(x, &mut c);
        let bad = c.iter().position(|v| !v.is_finite());
        self.constraint_values = c;
        if let Some(index) = bad {
            return Evaluation::Constraint { index };
        }
        grad.iter_mut().for_each(|v| *v = 0.0);
        let ones = vec![1.0; self.weights.len()];
        self.jt_times(x, &ones, grad);
        if grad.iter().any(|v| !v.is_finite()) {
            Evaluation::ConstraintGradient
        } else {
            Evaluation::AugmentedLagrangian
        }
    }
}

impl<P: Problem + ?Sized> Smooth for AugmentedLagrangian<'_, P> {
    fn value_grad(&mut self, x: &[f64], grad: &mut [f64]) -> f64 {
        self.evaluate(x, Some(grad))
    }

    fn hessian_times(&mut self, x: &[f64], v: &[f64], out: &mut [f64]) -> bool {
        let phr = self.phr();
        self.problem.hessian_times(x, &phr, v, out)
    }

    fn evaluations(&self) -> usize {
        self.function_evaluations
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn term_matches_the_textbook_square_form_up_to_a_constant() {
        let scales = [2.0, 0.5];
        let mult = [0.3, 1.7];
        let rho = 3.0;
        let phr = Phr::new(rho, 1, 1.0, &scales, &mult);
        for &c in &[-2.0, -0.4, 0.0, 0.1, 1.5] {
            for i in 0..2 {
                let cs = scales[i] * c;
                let shifted = cs + mult[i] / rho;
                let t = if i == 0 { shifted } else { shifted.max(0.0) };
                let textbook = 0.5 * rho * t * t - 0.5 * mult[i] * mult[i] / rho;
                assert!((phr.term(i, c) - textbook).abs() <= 1e-12 * (1.0 + textbook.abs()));
                let h = 1e-6;
                let fd = (phr.term(i, c + h) - phr.term(i, c - h)) / (2.0 * h);
                assert!((phr.derivative(i, c) - fd).abs() <= 1e-6 * (1.0 + fd.abs()));
                let fd2 = (phr.derivative(i, c + h) - phr.derivative(i, c - h)) / (2.0 * h);
                assert!((phr.curvature(i, c) - fd2).abs() <= 1e-6 * (1.0 + fd2.abs()));
            }
        }
    }
}
