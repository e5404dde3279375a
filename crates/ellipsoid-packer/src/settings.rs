//! The settings and the result of one local minimisation, and what every kind of local
//! minimisation shares: the solver's options, the check of a start, the items' measure.

use crate::Error;
use crate::problem::Adapter;
use auglag::{Control, Options, Progress, Report};
use implicit_packing::model::{Certificate, Model};

/// The solver of the augmented Lagrangian's bound-constrained subproblems.
pub use auglag::InnerSolver;

/// The first relative shrink δ of a compression's container linear size, and the largest.
pub const FIRST_STEP: f64 = 0.02;

/// Settings of one local minimisation.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub struct LocalSettings {
    /// Feasibility tolerance on the two constraints (the paper's 1e-4).
    pub feasibility_tolerance: f64,
    /// Optimality tolerance (sup-norm of the projected gradient of the Lagrangian; 1e-4).
    pub optimality_tolerance: f64,
    /// Outer (augmented-Lagrangian) iterations at most.
    pub max_outer_iterations: usize,
    /// Inner iterations per subproblem at most.
    pub max_inner_iterations: usize,
    /// The bound-constrained inner solver.
    pub inner_solver: InnerSolver,
    /// With the truncated-Newton inner solver: conjugate-gradient pairs kept as the
    /// preconditioner of the next step (`auglag::Options::cg_preconditioner_memory`; 0:
    /// plain conjugate gradients).
    pub cg_preconditioner_memory: usize,
    /// Feasibility tolerance of a second, warm-started solve from the first one's point
    /// (`None`: no polish). With the paper's 1e-4 the model leaves penetrations of about 1 %
    /// of the semi-axes, whose repair costs several per cent of density; a polish at 1e-10
    /// costs a fraction of the first solve and leaves the repair almost nothing to do.
    pub polish_tolerance: Option<f64>,
    /// Feasibility mode: the container variables keep their values in the start (lower =
    /// upper bound), the objective is 0, and nothing is repaired, since a dilation would change
    /// the container: the result is certified or it is not ([`LocalResult::certificate`]).
    /// The solver works on items grown by [`FIXED_MARGIN`], so that a point it leaves barely
    /// infeasible for them is clear of overlap for the true items.
    pub fixed_container: bool,
    /// How the container is made small: the paper's augmented Lagrangian, compression, or
    /// both in turn.
    pub method: LocalMethod,
    /// The largest relative shrink δ of one compression step
    /// ([`FIRST_STEP`] unless set: steps grow
    /// to it while they gain).
    pub largest_compression_step: f64,
    /// Items whose orientation compression keeps (their angle variables fixed at the start
    /// of each placement), by item; empty or shorter: the others turn freely.
    pub fixed_orientations: Vec<bool>,
}

/// How one local minimisation makes the container small.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum LocalMethod {
    /// The augmented Lagrangian on the paper's model, the container's dimensions among the
    /// variables (first solve, then the polish).
    #[default]
    AugmentedLagrangian,
    /// Compression ([`compression`](crate::compression)): placements in fixed containers
    /// that shrink while they certify. Faster than the augmented Lagrangian on large
    /// instances and somewhat less dense; the container keeps the start's aspect ratios.
    Compression,
    /// Compression, then the augmented Lagrangian from its packing: the density of the
    /// augmented Lagrangian at a fraction of its iterations.
    CompressionThenLagrangian,
}

/// The relative growth of every semi-axis while a fixed container is filled
/// ([`LocalSettings::fixed_container`]). The penalty of the augmented Lagrangian approaches
/// the feasible set from outside and stops within its tolerance, at penetrations of about
/// 1e-5 of the semi-axes; the grown items absorb them, at the price of raising the packing
/// fraction the solver sees by a factor (1 + margin)ᴺ (0.3 % in 3D).
pub const FIXED_MARGIN: f64 = 1e-3;

auglag::with_setters!(LocalSettings:
    with_feasibility_tolerance => feasibility_tolerance: f64,
    with_optimality_tolerance => optimality_tolerance: f64,
    with_max_outer_iterations => max_outer_iterations: usize,
    with_max_inner_iterations => max_inner_iterations: usize,
    with_inner_solver => inner_solver: InnerSolver,
    with_cg_preconditioner_memory => cg_preconditioner_memory: usize,
    with_polish_tolerance => polish_tolerance: Option<f64>,
    with_fixed_container => fixed_container: bool,
    with_method => method: LocalMethod,
    with_largest_compression_step => largest_compression_step: f64,
    with_fixed_orientations => fixed_orientations: Vec<bool>,
);

impl Default for LocalSettings {
    fn default() -> Self {
        Self {
            feasibility_tolerance: 1e-4,
            optimality_tolerance: 1e-4,
            max_outer_iterations: 50,
            max_inner_iterations: 2_000,
            inner_solver: InnerSolver::ProjectedLbfgs,
            cg_preconditioner_memory: Options::default().cg_preconditioner_memory,
            polish_tolerance: Some(1e-10),
            fixed_container: false,
            method: LocalMethod::AugmentedLagrangian,
            largest_compression_step: FIRST_STEP,
            fixed_orientations: Vec::new(),
        }
    }
}

/// The outcome of one local minimisation: a certified packing (in feasibility mode,
/// [`LocalSettings::fixed_container`], the point reached, which its certificate may reject).
#[derive(Clone, Debug)]
pub struct LocalResult {
    /// The variables of the certified (repaired) packing.
    pub x: Vec<f64>,
    /// Item area or volume over container area or volume, after repair.
    pub density: f64,
    /// The same before repair (the solver's own point).
    pub density_before_repair: f64,
    /// The container's linear factor s ≥ 1 applied by the repair (1 when none was needed).
    pub repair_factor: f64,
    /// Container area or volume after repair.
    pub objective: f64,
    /// The certificate of the returned packing (no overlap, everything inside).
    pub certificate: Certificate,
    /// What the solver did.
    pub report: Report,
}

/// Item area (2D) or volume (3D) of all the problem's items.
pub fn item_measure<const N: usize>(problem: &Model<N>) -> f64 {
    measure_of(problem.semi_axes().iter().copied())
}

/// Area (2D) or volume (3D) of items of these semi-axes: π ab, or 4π abc / 3, summed.
pub(crate) fn measure_of<const N: usize>(semi_axes: impl Iterator<Item = [f64; N]>) -> f64 {
    let unit = if N == 2 {
        std::f64::consts::PI
    } else {
        4.0 * std::f64::consts::PI / 3.0
    };
    semi_axes.map(|l| unit * l.iter().product::<f64>()).sum()
}

/// How far `x` is from a packing: the model's overlap plus its containment violation (both 0
/// exactly at a packing). Fixed-container runs rank the points they could not certify by it.
///
/// # Errors
/// Errors of the model (a wrong length, non-finite variables).
pub fn infeasibility<const N: usize>(problem: &mut Model<N>, x: &[f64]) -> Result<f64, Error> {
    let e = problem.evaluate(x, None)?;
    Ok(e.overlap + e.containment)
}

/// Solves of an adapter from a point at a feasibility (and complementarity) tolerance, the
/// other limits from `settings`. `observe` may stop a solve; every later solve then stops at
/// its first report, so that an interrupt ends the whole local minimisation.
pub(crate) fn solver<'a, const N: usize>(
    settings: &'a LocalSettings,
    observe: &'a mut dyn FnMut(&Progress<'_>) -> bool,
) -> impl FnMut(&Adapter<'_, N>, &[f64], f64) -> Result<auglag::Solution, Error> + 'a {
    let mut interrupted = false;
    move |adapter, x, feasibility| {
        let options = solver_options(settings, feasibility);
        auglag::minimize_with_callback(adapter, x, &options, |progress: &Progress<'_>| {
            if interrupted || observe(progress) {
                interrupted = true;
                Control::Stop
            } else {
                Control::Continue
            }
        })
        .map_err(Error::Solver)
    }
}

/// The solver's options for a solve at a feasibility (and complementarity) tolerance, the
/// other limits from `settings`.
pub(crate) fn solver_options(settings: &LocalSettings, feasibility: f64) -> Options {
    Options::default()
        .with_feasibility_tolerance(feasibility)
        .with_optimality_tolerance(settings.optimality_tolerance)
        .with_complementarity_tolerance(feasibility)
        .with_max_outer_iterations(settings.max_outer_iterations)
        .with_max_inner_iterations(settings.max_inner_iterations)
        .with_inner_solver(settings.inner_solver)
        .with_cg_preconditioner_memory(settings.cg_preconditioner_memory)
        .with_scaling(true)
}

/// `LengthMismatch` unless the start `x` has one entry per variable of `problem`.
pub(crate) fn check_start<const N: usize>(problem: &Model<N>, x: &[f64]) -> Result<(), Error> {
    if x.len() == problem.var_count() {
        return Ok(());
    }
    Err(implicit_packing::Error::LengthMismatch {
        what: "initial point",
        expected: problem.var_count(),
        found: x.len(),
    }
    .into())
}

/// The report of no solve: no iterations, no evaluations, stopped before it began.
pub(crate) fn empty_report() -> Report {
    Report {
        stop_reason: auglag::StopReason::Interrupted,
        outer_iterations: 0,
        inner_iterations: 0,
        function_evaluations: 0,
        gradient_evaluations: 0,
        constraint_evaluations: 0,
        hessian_products: 0,
        infeasibility: 0.0,
        complementarity: 0.0,
        projected_gradient_norm: 0.0,
        penalty: 0.0,
        objective: f64::NAN,
        best_feasible_objective: None,
        returned_best_feasible: false,
        wall_time: std::time::Duration::ZERO,
    }
}

/// Ten times the extent of the start (its farthest centre plus its largest container
/// dimension): the box the centres are kept in during a local minimisation.
pub(crate) fn centre_bound<const N: usize>(x0: &[f64]) -> f64 {
    let extent = x0.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    10.0 * extent.max(1.0)
}

/// Adds the iteration and evaluation counts and the wall time of `more` to `total`.
pub(crate) fn add_counts(total: &mut Report, more: &Report) {
    total.outer_iterations += more.outer_iterations;
    total.inner_iterations += more.inner_iterations;
    total.function_evaluations += more.function_evaluations;
    total.gradient_evaluations += more.gradient_evaluations;
    total.constraint_evaluations += more.constraint_evaluations;
    total.hessian_products += more.hessian_products;
    total.wall_time += more.wall_time;
}
