//! The penalty terms of one augmented-Lagrangian subproblem (the Powell–Hestenes–Rockafellar
//! function), as a problem with fused hooks sees them.

/// The data of one augmented-Lagrangian subproblem, handed to
/// [`Problem::lagrangian`](crate::Problem::lagrangian) so that a fused implementation can form the penalty terms.
#[derive(Debug, Clone, Copy)]
pub struct Phr<'a> {
    penalty: f64,
    n_eq: usize,
    objective_scale: f64,
    constraint_scales: &'a [f64],
    multipliers: &'a [f64],
}

impl<'a> Phr<'a> {
    /// The subproblem with penalty ρ = `penalty`, the first `n_eq` constraints equalities,
    /// objective factor s_f, constraint factors sᵢ and safeguarded multipliers (one per
    /// constraint). The solver builds these; a problem's own tests can too, to check its
    /// fused hooks against the unfused formulas.
    pub fn new(
        penalty: f64,
        n_eq: usize,
        objective_scale: f64,
        constraint_scales: &'a [f64],
        multipliers: &'a [f64],
    ) -> Self {
        Self {
            penalty,
            n_eq,
            objective_scale,
            constraint_scales,
            multipliers,
        }
    }

    /// The penalty parameter ρ.
    pub fn penalty(&self) -> f64 {
        self.penalty
    }

    /// The factor s_f multiplying the objective (1 unless scaling is on).
    pub fn objective_scale(&self) -> f64 {
        self.objective_scale
    }

    /// The number of constraints, n_eq + n_ineq.
    pub fn n_constraints(&self) -> usize {
        self.multipliers.len()
    }

    /// The safeguarded multiplier of constraint `i` for this subproblem (in scaled units).
    pub fn multiplier(&self, i: usize) -> f64 {
        self.multipliers[i]
    }

    /// Penalty term of constraint `i` whose (unscaled) value is `c`: with c̃ = sᵢ c,
    /// c̃ (λ̄ᵢ + ρ c̃ / 2) for an equality or where λ̄ᵢ + ρ c̃ > 0, else −λ̄ᵢ² / (2ρ).
    pub fn term(&self, i: usize, c: f64) -> f64 {
        let cs = self.constraint_scales[i] * c;
        let m = self.multipliers[i];
        if i < self.n_eq || m + self.penalty * cs > 0.0 {
            cs * (m + 0.5 * self.penalty * cs)
        } else {
            -0.5 * m * m / self.penalty
        }
    }

    /// d term(i, c) / dc: the weight of ∇cᵢ in the gradient, sᵢ λᵢ⁺ with the first-order
    /// multiplier estimate λᵢ⁺.
    pub fn derivative(&self, i: usize, c: f64) -> f64 {
        self.constraint_scales[i] * self.estimate(i, c)
    }

    /// d² term(i, c) / dc²: the weight of ∇cᵢ ∇cᵢᵀ in the Hessian, ρ sᵢ² where the term is
    /// quadratic in c (equalities, and inequalities with λ̄ᵢ + ρ sᵢ c > 0), 0 elsewhere.
    pub fn curvature(&self, i: usize, c: f64) -> f64 {
        let s = self.constraint_scales[i];
        if i < self.n_eq || self.multipliers[i] + self.penalty * s * c > 0.0 {
            self.penalty * s * s
        } else {
            0.0
        }
    }

    /// First-order multiplier estimate λ̄ᵢ + ρ sᵢ c (clipped at 0 for inequalities).
    pub fn estimate(&self, i: usize, c: f64) -> f64 {
        let v = self.multipliers[i] + self.penalty * self.constraint_scales[i] * c;
        if i < self.n_eq { v } else { v.max(0.0) }
    }
}
