//! Active-set truncated Newton for min F(x) on a box: Newton steps on the face of the box
//! where the iterate lives, solved inexactly by conjugate gradients with Hessian–vector
//! products.
//!
//! Iteration k:
//!
//! 1. The ε-active set of projected L-BFGS ([`crate::projected_qn`], Bertsekas): the free
//!    variables F are those not at (within ε of) a bound the gradient pushes against.
//! 2. Direction on F: conjugate gradients on ∇²_FF F(x) d_F = −∇_F F from d_F = 0, stopped
//!    when ‖r‖₂ ≤ η ‖∇_F F‖₂ with the forcing term η = min(½, √‖∇_F F‖₂) (superlinear
//!    convergence, Eisenstat–Walker / Dembo–Steihaug), after the iteration cap, or at a
//!    direction of non-positive curvature (then the last iterate is kept, or −∇_F F when it
//!    happens at the first iteration: Steihaug's rule without a trust region). The Hessian
//!    products come from F itself when it offers them ([`Smooth::hessian_times`]: for the
//!    augmented Lagrangian, [`crate::Problem::hessian_times`]) and are
//!    otherwise difference quotients of gradients, (∇F(x + h p) − ∇F(x)) / h with
//!    h = √ε_mach · max(1, ‖x‖∞) / ‖p‖∞, as Gencan's incremental quotients.
//! 3. Active variables are sent to their bounds and blocked components cleared, as in
//!    projected L-BFGS; then the projected Armijo search from α = 1 (the Newton step's natural
//!    length). A direction that is not of descent is replaced by −∇F.
//!
//! Preconditioner (Morales–Nocedal's automatic preconditioning): the conjugate gradients run
//! preconditioned by an L-BFGS inverse-Hessian approximation `M⁻¹` built from pairs
//! `(p_i, ∇²F p_i)` of the previous step's conjugate-gradient iterations (the last
//! [`Options::cg_preconditioner_memory`](crate::Options::cg_preconditioner_memory) with
//! positive curvature), restricted to the free variables as in projected L-BFGS. The pairs
//! cost nothing, the products being computed anyway; applying `M⁻¹` costs `O(m n)`. The first
//! step, without pairs, runs plain conjugate gradients. With `p₀ = z₀ = M⁻¹ r₀`:
//!
//! ```text
//! α = rᵀz / pᵀ∇²F p,   d ← d + α p,   r ← r − α ∇²F p,   z = M⁻¹ r,
//! β = r⁺ᵀz⁺ / rᵀz,     p ← z + β p
//! ```
//!
//! (stopping and the exit on non-positive curvature as above, on the unpreconditioned
//! residual `r`; at a first-iteration exit the direction is `z₀`, a descent direction since
//! `M⁻¹` is positive definite). Why not per-body blocks: the packing model's Hessian is
//! dominated by the pair terms, which couple bodies, and its blocks would cost twelve
//! directional derivatives per overlapping pair to form.
//!
//! # References
//! - R. S. Dembo, T. Steihaug, "Truncated-Newton algorithms for large-scale unconstrained
//!   optimization", Math. Program. 26, 190–212, 1983.
//! - S. C. Eisenstat, H. F. Walker, "Choosing the forcing terms in an inexact Newton method",
//!   SIAM J. Sci. Comput. 17(1), 16–32, 1996.
//! - E. G. Birgin, J. M. Martínez, "Large-scale active-set box-constrained optimization method
//!   with spectral projected gradients", Comput. Optim. Appl. 23, 101–125, 2002 (Gencan:
//!   truncated Newton inside faces, incremental quotients).
//! - D. P. Bertsekas, "Projected Newton methods for optimization problems with simple
//!   constraints", SIAM J. Control Optim. 20(2), 221–246, 1982.
//! - J. L. Morales, J. Nocedal, "Automatic preconditioning by limited memory quasi-Newton
//!   updating", SIAM J. Optim. 10(4), 1079–1096, 2000.

use crate::inner::{Acceptance, InnerStatus, Iterate, Method, Smooth, line_search};
use crate::projected_qn::{LbfgsWorkspace, complete_direction, mark_free};
use crate::projection::{dot, norm_inf};

/// Buffers of the truncated-Newton method, allocated once and reused by every inner solve.
#[derive(Debug, Clone)]
pub(crate) struct NewtonWorkspace {
    /// Cap on conjugate-gradient iterations per Newton step.
    max_cg: usize,
    /// 1.0 on free variables, 0.0 on active ones.
    free: Vec<f64>,
    direction: Vec<f64>,
    residual: Vec<f64>,
    search: Vec<f64>,
    product: Vec<f64>,
    /// x + h p and ∇F there, for difference quotients.
    shifted: Vec<f64>,
    shifted_grad: Vec<f64>,
    x_trial: Vec<f64>,
    g_trial: Vec<f64>,
    /// The preconditioned residual `z = M⁻¹ r`.
    preconditioned: Vec<f64>,
    /// `M⁻¹` of this step (the previous step's pairs) and the pairs this step collects;
    /// `None` without a preconditioner.
    preconditioner: Option<Box<(LbfgsWorkspace, LbfgsWorkspace)>>,
    /// Conjugate-gradient iterations over the run (for reports and studies).
    pub(crate) cg_iterations: usize,
}

impl NewtonWorkspace {
    /// Buffers for `n` variables, at most `max_cg` (≥ 1) conjugate-gradient iterations a step,
    /// preconditioned by `pairs` conjugate-gradient pairs of the previous step (0: none).
    pub(crate) fn new(n: usize, max_cg: usize, pairs: usize) -> Self {
        Self {
            preconditioned: vec![0.0; n],
            preconditioner: (pairs > 0)
                .then(|| Box::new((LbfgsWorkspace::new(n, pairs), LbfgsWorkspace::new(n, pairs)))),
            max_cg: max_cg.max(1),
            free: vec![1.0; n],
            direction: vec![0.0; n],
            residual: vec![0.0; n],
            search: vec![0.0; n],
            product: vec![0.0; n],
            shifted: vec![0.0; n],
            shifted_grad: vec![0.0; n],
            x_trial: vec![0.0; n],
            g_trial: vec![0.0; n],
            cg_iterations: 0,
        }
    }

    /// `product` = ∇²_FF F(x) `search` (the search direction is zero off F).
    fn hessian_times_search(
        &mut self,
        f: &mut dyn Smooth,
        x: &[f64],
        grad: &[f64],
    ) -> Result<(), InnerStatus> {
        if !f.hessian_times(x, &self.search, &mut self.product) {
            let h = f64::EPSILON.sqrt() * norm_inf(x).max(1.0) / norm_inf(&self.search);
            for ((s, &xi), &pi) in self.shifted.iter_mut().zip(x).zip(&self.search) {
                *s = xi + h * pi;
            }
            let value = f.value_grad(&self.shifted, &mut self.shifted_grad);
            if !value.is_finite() {
                return Err(InnerStatus::NonFinite);
            }
            for ((p, &gs), &g) in self.product.iter_mut().zip(&self.shifted_grad).zip(grad) {
                *p = (gs - g) / h;
            }
        }
        for (p, &fr) in self.product.iter_mut().zip(&self.free) {
            *p *= fr;
        }
        Ok(())
    }

    /// Step 2 of the module docs: the inexact Newton direction on the free variables, by
    /// conjugate gradients preconditioned with the previous step's pairs.
    fn newton_direction(
        &mut self,
        f: &mut dyn Smooth,
        at: &Iterate<'_>,
        all_free: bool,
    ) -> Result<(), InnerStatus> {
        for ((d, r), (&g, &fr)) in self
            .direction
            .iter_mut()
            .zip(self.residual.iter_mut())
            .zip(at.grad.iter().zip(&self.free))
        {
            *d = 0.0;
            *r = -g * fr;
        }
        if let Some(pair) = &mut self.preconditioner {
            let (current, collected) = &mut **pair;
            current.set_free(&self.free, all_free);
            collected.reset();
        }
        self.precondition();
        self.search.copy_from_slice(&self.preconditioned);
        let mut rr = dot(&self.residual, &self.residual);
        let mut rz = dot(&self.residual, &self.preconditioned);
        let g_norm = rr.sqrt();
        let tolerance = 0.5f64.min(g_norm.sqrt()) * g_norm;
        for k in 0..self.max_cg {
            if rr.sqrt() <= tolerance || f.evaluations() >= at.settings.max_evaluations {
                break;
            }
            self.hessian_times_search(f, at.x, at.grad)?;
            self.cg_iterations += 1;
            let curvature = dot(&self.search, &self.product);
            // Non-positive (or NaN) curvature along the search direction.
            let positive = curvature > f64::EPSILON * dot(&self.search, &self.search);
            if !positive {
                if k == 0 {
                    self.direction.copy_from_slice(&self.search);
                }
                break;
            }
            if let Some(pair) = &mut self.preconditioner {
                pair.1.store(&self.search, &self.product);
            }
            let alpha = rz / curvature;
            for (((d, r), &p), &hp) in self
                .direction
                .iter_mut()
                .zip(self.residual.iter_mut())
                .zip(&self.search)
                .zip(&self.product)
            {
                *d += alpha * p;
                *r -= alpha * hp;
            }
            self.precondition();
            rr = dot(&self.residual, &self.residual);
            let rz_next = dot(&self.residual, &self.preconditioned);
            let beta = rz_next / rz;
            rz = rz_next;
            for (p, &z) in self.search.iter_mut().zip(&self.preconditioned) {
                *p = z + beta * *p;
            }
        }
        if let Some(pair) = &mut self.preconditioner
            && pair.1.stored() > 0
        {
            let (current, collected) = &mut **pair;
            std::mem::swap(current, collected);
        }
        if self.direction.iter().all(|&d| d == 0.0) {
            // The loop did not run (tolerance met at once, or no budget): a gradient step.
            self.direction.copy_from_slice(&self.residual);
        }
        Ok(())
    }

    /// `preconditioned = M⁻¹ residual` (the residual itself without pairs).
    fn precondition(&mut self) {
        match &mut self.preconditioner {
            Some(pair) => {
                pair.0.apply(&self.residual, &mut self.preconditioned);
            }
            None => self.preconditioned.copy_from_slice(&self.residual),
        }
    }
}

impl Method for NewtonWorkspace {
    fn begin(&mut self, _value: f64, _pg: f64) {}

    fn step(&mut self, f: &mut dyn Smooth, at: Iterate<'_>) -> Result<f64, InnerStatus> {
        let (x, grad, lower, upper) = (at.x, at.grad, at.lower, at.upper);
        let all_free = mark_free(
            &mut self.free,
            (x, grad),
            (lower, upper),
            at.projected_gradient,
        );
        self.newton_direction(f, &at, all_free)?;
        complete_direction(&mut self.direction, &self.free, (x, grad), (lower, upper));
        let mut slope = dot(grad, &self.direction);
        if slope >= 0.0 {
            for ((d, &g), &fr) in self.direction.iter_mut().zip(grad).zip(&self.free) {
                *d = -g * fr;
            }
            complete_direction(&mut self.direction, &self.free, (x, grad), (lower, upper));
            slope = dot(grad, &self.direction);
            if slope >= 0.0 {
                return Err(InnerStatus::Stalled);
            }
        }
        line_search(
            f,
            at,
            (&self.direction, slope),
            Acceptance::ProjectedPath,
            (&mut self.x_trial, &mut self.g_trial),
        )
    }

    fn accept(&mut self, _k: usize, _x: &[f64], _grad: &[f64], _value: f64) {}

    fn trial(&self) -> (&[f64], &[f64]) {
        (&self.x_trial, &self.g_trial)
    }
}
