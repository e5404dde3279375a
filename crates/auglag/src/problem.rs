//! The problem trait: the only way the solver sees a model.
//!
//! The solver treats
//!
//! ```text
//! minimise f(x)  subject to  h(x) = 0  (n_eq components),
//!                            g(x) ≤ 0  (n_ineq components),
//!                            l ≤ x ≤ u (componentwise, infinite bounds allowed).
//! ```
//!
//! Constraints are passed as one vector `c = [h; g]`, equalities first.

use crate::phr::Phr;

/// A smooth nonlinear program with bounds.
///
/// Every slice handed to these methods has the length the dimensions promise (`dim()` for points
/// and gradients, `n_eq() + n_ineq()` for constraint values and weights), so implementations may
/// index without checks. Methods must be deterministic: the solver's bit-for-bit
/// reproducibility rests on it.
///
/// A method may return NaN or ±∞ where the model is undefined; the inner line searches treat such
/// a trial point as "too far" and backtrack. Only a non-finite value at the starting point is an
/// error.
pub trait Problem {
    /// Number of variables n.
    fn dim(&self) -> usize;

    /// Writes the bounds l and u. Both slices arrive filled with −∞ and +∞, so a problem
    /// without bounds need not override this.
    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        let _ = (lower, upper);
    }

    /// Number of equality constraints h(x) = 0.
    fn n_eq(&self) -> usize {
        0
    }

    /// Number of inequality constraints g(x) ≤ 0.
    fn n_ineq(&self) -> usize {
        0
    }

    /// Returns f(x); when `grad` is `Some`, also **overwrites** it with ∇f(x). Value-only calls
    /// (`None`) should skip the gradient work.
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64;

    /// Writes c(x) = [h(x); g(x)] into `c` (length `n_eq() + n_ineq()`).
    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        let _ = (x, c);
    }

    /// **Adds** J(x)ᵀw to `out`, where J is the Jacobian of c = [h; g] (so
    /// `out += Σᵢ wᵢ ∇cᵢ(x)`). The solver calls it with the objective gradient already in `out`.
    fn constraints_jt_times(&self, x: &[f64], w: &[f64], out: &mut [f64]) {
        let _ = (x, w, out);
    }

    /// Optional fused evaluation of the augmented Lagrangian, for models whose constraints are
    /// sums of many cheap terms that are best visited once.
    ///
    /// Return `None` (the default) to let the solver combine [`objective`](Self::objective),
    /// [`constraints`](Self::constraints) and [`constraints_jt_times`](Self::constraints_jt_times).
    /// Otherwise return
    ///
    /// ```text
    /// L(x) = phr.objective_scale() · f(x) + Σᵢ phr.term(i, cᵢ(x))
    /// ```
    ///
    /// and, when `grad` is `Some`, overwrite it with
    /// `phr.objective_scale() · ∇f(x) + Σᵢ phr.derivative(i, cᵢ(x)) · ∇cᵢ(x)`.
    /// The result must agree with the unfused path up to rounding.
    fn lagrangian(&self, x: &[f64], phr: &Phr<'_>, grad: Option<&mut [f64]>) -> Option<f64> {
        let _ = (x, phr, grad);
        None
    }

    /// Optional product of the augmented Lagrangian's Hessian with a direction, for the
    /// truncated-Newton inner solver ([`InnerSolver::TruncatedNewton`]).
    ///
    /// Return `false` (the default) to let the solver use a difference quotient of gradients,
    /// (∇L(x + h v) − ∇L(x)) / h. Otherwise overwrite `out` with
    ///
    /// ```text
    /// ∇²L(x) v = phr.objective_scale() · ∇²f(x) v
    ///          + Σᵢ [ phr.derivative(i, cᵢ(x)) · ∇²cᵢ(x) v + phr.curvature(i, cᵢ(x)) · ∇cᵢ(x) (∇cᵢ(x)ᵀ v) ]
    /// ```
    ///
    /// and return `true`.
    ///
    /// [`InnerSolver::TruncatedNewton`]: crate::InnerSolver::TruncatedNewton
    fn hessian_times(&self, x: &[f64], phr: &Phr<'_>, v: &[f64], out: &mut [f64]) -> bool {
        let _ = (x, phr, v, out);
        false
    }
}

impl<P: Problem + ?Sized> Problem for &P {
    fn dim(&self) -> usize {
        (**self).dim()
    }
    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        (**self).bounds(lower, upper);
    }
    fn n_eq(&self) -> usize {
        (**self).n_eq()
    }
    fn n_ineq(&self) -> usize {
        (**self).n_ineq()
    }
    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        (**self).objective(x, grad)
    }
    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        (**self).constraints(x, c);
    }
    fn constraints_jt_times(&self, x: &[f64], w: &[f64], out: &mut [f64]) {
        (**self).constraints_jt_times(x, w, out);
    }
    fn lagrangian(&self, x: &[f64], phr: &Phr<'_>, grad: Option<&mut [f64]>) -> Option<f64> {
        (**self).lagrangian(x, phr, grad)
    }
    fn hessian_times(&self, x: &[f64], phr: &Phr<'_>, v: &[f64], out: &mut [f64]) -> bool {
        (**self).hessian_times(x, phr, v, out)
    }
}
