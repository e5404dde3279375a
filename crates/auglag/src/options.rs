//! Settings of a run. Defaults follow Algencan (Birgin & Martínez 2014, chapter 12) where the
//! book gives a value.

use crate::error::Error;

/// Which method minimises each augmented-Lagrangian subproblem over the box.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum InnerSolver {
    /// Nonmonotone spectral projected gradient: robust, cheap per iteration, slow on
    /// ill-conditioned problems.
    Spg,
    /// Active-set projected L-BFGS: faster on smooth, ill-conditioned problems.
    #[default]
    ProjectedLbfgs,
    /// Active-set truncated Newton: conjugate gradients on the free variables with
    /// Hessian–vector products (the problem's own, or difference quotients of gradients).
    TruncatedNewton,
}

/// Settings of [`minimize`](crate::minimize): start from `Options::default()` and change
/// what you need, with the `with_*` methods or by assigning fields.
///
/// ```
/// use auglag::{InnerSolver, Options};
/// let options = Options::default()
///     .with_inner_solver(InnerSolver::Spg)
///     .with_feasibility_tolerance(1e-8);
/// assert_eq!(options.max_outer_iterations, 50);
/// ```
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Options {
    /// ε_feas: stop when max(‖h‖∞, ‖g₊‖∞) ≤ this (unscaled). Default 1e-4.
    pub feasibility_tolerance: f64,
    /// ε_opt: stop when the projected gradient of the Lagrangian has sup-norm ≤ this; also the
    /// final inner tolerance. Default 1e-4.
    pub optimality_tolerance: f64,
    /// ε_compl: stop when ‖min(−g̃, μ)‖∞ ≤ this. Default 1e-4.
    pub complementarity_tolerance: f64,
    /// Cap on outer iterations (one is always done). Default 50.
    pub max_outer_iterations: usize,
    /// Cap on inner iterations per subproblem. Default 10 000.
    pub max_inner_iterations: usize,
    /// Cap on objective evaluations over the run. Default 1 000 000.
    pub max_evaluations: usize,
    /// Inner solver. Default [`InnerSolver::ProjectedLbfgs`].
    pub inner_solver: InnerSolver,
    /// L-BFGS memory m (pairs stored), 1 to 1024. Default 7.
    pub lbfgs_memory: usize,
    /// Nonmonotone memory M of the SPG line search (M = 1: monotone). Default 10.
    pub spg_memory: usize,
    /// Conjugate-gradient iterations per truncated-Newton step at most (≥ 1). Default 50.
    pub cg_iterations: usize,
    /// Pairs of the previous truncated-Newton step's conjugate-gradient iterations kept as
    /// the L-BFGS preconditioner of the next (Morales–Nocedal), 0 to 1024; 0 runs plain
    /// conjugate gradients. Default 7.
    pub cg_preconditioner_memory: usize,
    /// Safeguards [λ_min, λ_max] of the SPG spectral step. Default [1e-10, 1e10].
    pub spectral_step_bounds: (f64, f64),
    /// Initial penalty ρ₁; `None` (default) chooses it as Algencan does:
    /// ρ₁ = max(10⁻⁸, min(10 max(1, |f(x⁰)|) / max(1, ½(‖h(x⁰)‖² + ‖g(x⁰)₊‖²)), 10⁸)).
    pub initial_penalty: Option<f64>,
    /// Factor γ > 1 applied to ρ when the infeasibility–complementarity measure did not drop
    /// by the factor `required_decrease`. Default 10.
    pub penalty_increase: f64,
    /// τ ∈ (0, 1): required decrease of the infeasibility–complementarity measure per outer
    /// iteration. Default 0.5.
    pub required_decrease: f64,
    /// The run stops with [`StopReason::PenaltyTooLarge`](crate::StopReason::PenaltyTooLarge)
    /// instead of raising ρ beyond this (finite). Default 1e20.
    pub max_penalty: f64,
    /// Safeguarding box [λ_min, λ_max] of the equality multipliers. Default [−1e20, 1e20].
    pub equality_multiplier_bounds: (f64, f64),
    /// Upper end μ_max of the inequality multipliers' box [0, μ_max]. Default 1e20.
    pub max_inequality_multiplier: f64,
    /// Scale f by 1/max(1, ‖∇f(x⁰)‖∞) and each cᵢ by 1/max(1, ‖∇cᵢ(x⁰)‖∞) (Algencan's
    /// scaling, with factors floored at 1e-8). Default off.
    pub scaling: bool,
}

/// `with_*` methods setting one field each and returning the settings, for chained
/// construction of `#[non_exhaustive]` settings (this crate's and the packer's); each is
/// documented as setting its field, whose doc comment says what it means.
#[doc(hidden)]
#[macro_export]
macro_rules! with_setters {
    ($ty:ident: $($name:ident => $field:ident: $t:ty),* $(,)?) => {
        impl $ty { $(
            #[doc = concat!("Sets [`", stringify!($ty), "::", stringify!($field), "`].")]
            #[must_use] pub fn $name(mut self, value: $t) -> Self { self.$field = value; self }
        )* }
    };
}

with_setters!(Options:
    with_feasibility_tolerance => feasibility_tolerance: f64,
    with_optimality_tolerance => optimality_tolerance: f64,
    with_complementarity_tolerance => complementarity_tolerance: f64,
    with_max_outer_iterations => max_outer_iterations: usize,
    with_max_inner_iterations => max_inner_iterations: usize,
    with_max_evaluations => max_evaluations: usize,
    with_inner_solver => inner_solver: InnerSolver,
    with_lbfgs_memory => lbfgs_memory: usize,
    with_spg_memory => spg_memory: usize,
    with_cg_iterations => cg_iterations: usize,
    with_cg_preconditioner_memory => cg_preconditioner_memory: usize,
    with_spectral_step_bounds => spectral_step_bounds: (f64, f64),
    with_initial_penalty => initial_penalty: Option<f64>,
    with_penalty_increase => penalty_increase: f64,
    with_required_decrease => required_decrease: f64,
    with_max_penalty => max_penalty: f64,
    with_equality_multiplier_bounds => equality_multiplier_bounds: (f64, f64),
    with_max_inequality_multiplier => max_inequality_multiplier: f64,
    with_scaling => scaling: bool,
);

impl Default for Options {
    fn default() -> Self {
        Self {
            feasibility_tolerance: 1e-4,
            optimality_tolerance: 1e-4,
            complementarity_tolerance: 1e-4,
            max_outer_iterations: 50,
            max_inner_iterations: 10_000,
            max_evaluations: 1_000_000,
            inner_solver: InnerSolver::default(),
            lbfgs_memory: 7,
            spg_memory: 10,
            cg_iterations: 50,
            cg_preconditioner_memory: 7,
            spectral_step_bounds: (1e-10, 1e10),
            initial_penalty: None,
            penalty_increase: 10.0,
            required_decrease: 0.5,
            max_penalty: 1e20,
            equality_multiplier_bounds: (-1e20, 1e20),
            max_inequality_multiplier: 1e20,
            scaling: false,
        }
    }
}

/// Largest accepted `lbfgs_memory`: beyond this the O(m n) workspace is a mistake, not a choice.
const MAX_LBFGS_MEMORY: usize = 1024;

/// Largest accepted `spg_memory`.
const MAX_SPG_MEMORY: usize = 1_000_000;

fn require(
    name: &'static str,
    value: f64,
    ok: bool,
    requirement: &'static str,
) -> Result<(), Error> {
    if ok {
        Ok(())
    } else {
        Err(Error::InvalidOption {
            name,
            value,
            requirement,
        })
    }
}

impl Options {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), Error> {
        let positive = |v: f64| v > 0.0 && v.is_finite();
        require(
            "feasibility_tolerance",
            self.feasibility_tolerance,
            positive(self.feasibility_tolerance),
            "must be positive and finite",
        )?;
        require(
            "optimality_tolerance",
            self.optimality_tolerance,
            positive(self.optimality_tolerance),
            "must be positive and finite",
        )?;
        require(
            "complementarity_tolerance",
            self.complementarity_tolerance,
            positive(self.complementarity_tolerance),
            "must be positive and finite",
        )?;
        require(
            "lbfgs_memory",
            self.lbfgs_memory as f64,
            (1..=MAX_LBFGS_MEMORY).contains(&self.lbfgs_memory),
            "must lie in 1..=1024 (the workspace holds 2·m n-vectors)",
        )?;
        require(
            "spg_memory",
            self.spg_memory as f64,
            (1..=MAX_SPG_MEMORY).contains(&self.spg_memory),
            "must lie in 1..=1000000",
        )?;
        require(
            "cg_iterations",
            self.cg_iterations as f64,
            self.cg_iterations >= 1,
            "must be at least 1",
        )?;
        require(
            "cg_preconditioner_memory",
            self.cg_preconditioner_memory as f64,
            self.cg_preconditioner_memory <= MAX_LBFGS_MEMORY,
            "must lie in 0..=1024 (the workspace holds 4·m n-vectors)",
        )?;
        let (lo, hi) = self.spectral_step_bounds;
        require(
            "spectral_step_bounds.0",
            lo,
            positive(lo) && lo <= hi,
            "must be positive, finite and at most spectral_step_bounds.1",
        )?;
        require(
            "spectral_step_bounds.1",
            hi,
            positive(hi),
            "must be positive and finite",
        )?;
        if let Some(rho) = self.initial_penalty {
            require(
                "initial_penalty",
                rho,
                positive(rho),
                "must be positive and finite",
            )?;
        }
        require(
            "penalty_increase",
            self.penalty_increase,
            self.penalty_increase > 1.0 && self.penalty_increase.is_finite(),
            "must be finite and greater than 1",
        )?;
        require(
            "required_decrease",
            self.required_decrease,
            self.required_decrease > 0.0 && self.required_decrease < 1.0,
            "must lie in (0, 1)",
        )?;
        require(
            "max_penalty",
            self.max_penalty,
            positive(self.max_penalty),
            "must be positive and finite",
        )?;
        let (lmin, lmax) = self.equality_multiplier_bounds;
        require(
            "equality_multiplier_bounds.0",
            lmin,
            lmin <= 0.0,
            "must be at most 0 (so that 0 is a safeguarded multiplier)",
        )?;
        require(
            "equality_multiplier_bounds.1",
            lmax,
            lmax >= 0.0,
            "must be at least 0 (so that 0 is a safeguarded multiplier)",
        )?;
        require(
            "max_inequality_multiplier",
            self.max_inequality_multiplier,
            self.max_inequality_multiplier >= 0.0,
            "must be at least 0",
        )
    }
}
