//! Minimum-container packing: one local minimisation of the model by the augmented Lagrangian,
//! from the paper's initial solutions, then an exact certificate and the least repair.
//!
//! The problem (paper Section 6, eqs. 19 and 33):
//!
//! ```text
//! minimise   area or volume of the container
//! subject to overlap(x) = Σ_{i<j} f_ij = 0,   containment(x) = 0,   container dims ≥ l_min
//! ```
//!
//! solved by [`auglag`] (PHR augmented Lagrangian, as Algencan) through a fused evaluation of
//! the model: the objective, both constraints and their gradients in one pass over the grid.
//!
//! The model satisfies its constraints only to a tolerance, so every result is certified with
//! PW85 verdicts and exact containment ([`Model::certify`]) and, if anything still overlaps
//! or sticks out, repaired ([`repair`]): scaling every centre and the container by s leaves
//! the shapes as they are and multiplies every pair's contact function by s², so the
//! overlapping pairs need s = max 1/μ_ij exactly; an item still outside is then held by
//! scaling the container alone by its containment scale t. The repair costs a factor (s·t)^N
//! in density, which is reported.
//!
//! # References
//! - E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//!   variables for packing ellipsoids*, J. Global Optim. 68 (2017), Section 6 (initial
//!   solutions, Algencan).

use crate::Error;
use crate::compression::{add_counts, compression};
use auglag::{Control, Options, Phr, Progress, Report};

/// The solver of the augmented Lagrangian's bound-constrained subproblems.
pub use auglag::InnerSolver;
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::{Certificate, Model, ModelGradient};
use std::cell::RefCell;

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
    /// ([`compression::FIRST_STEP`](crate::compression::FIRST_STEP) unless set: steps grow
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
    /// Sets [`LocalSettings::feasibility_tolerance`].
    with_feasibility_tolerance => feasibility_tolerance: f64,
    /// Sets [`LocalSettings::optimality_tolerance`].
    with_optimality_tolerance => optimality_tolerance: f64,
    /// Sets [`LocalSettings::max_outer_iterations`].
    with_max_outer_iterations => max_outer_iterations: usize,
    /// Sets [`LocalSettings::max_inner_iterations`].
    with_max_inner_iterations => max_inner_iterations: usize,
    /// Sets [`LocalSettings::inner_solver`].
    with_inner_solver => inner_solver: InnerSolver,
    /// Sets [`LocalSettings::cg_preconditioner_memory`].
    with_cg_preconditioner_memory => cg_preconditioner_memory: usize,
    /// Sets [`LocalSettings::polish_tolerance`].
    with_polish_tolerance => polish_tolerance: Option<f64>,
    /// Sets [`LocalSettings::fixed_container`].
    with_fixed_container => fixed_container: bool,
    /// Sets [`LocalSettings::method`].
    with_method => method: LocalMethod,
    /// Sets [`LocalSettings::largest_compression_step`].
    with_largest_compression_step => largest_compression_step: f64,
    /// Sets [`LocalSettings::fixed_orientations`].
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
            largest_compression_step: crate::compression::FIRST_STEP,
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
    let unit = if N == 2 {
        std::f64::consts::PI
    } else {
        4.0 * std::f64::consts::PI / 3.0
    };
    problem
        .semi_axes()
        .iter()
        .map(|l| unit * l.iter().product::<f64>())
        .sum()
}

/// One local minimisation from `x0`, certified and repaired. `observe` sees the solver's
/// progress at every iteration (objective and infeasibility at the end of each outer
/// iteration); returning `true` stops the solver, and the point reached is still certified and
/// repaired.
///
/// # Errors
/// [`Error::Model`] (`LengthMismatch`) when `x0` does not fit the problem; errors of the model on
/// non-finite variables at the start; [`Error::Solver`] when the solver refuses the start;
/// [`Error::NotCertifiable`] when no repair by a factor up to 4 certifies the point reached
/// (an item far outside the container).
pub fn local_minimisation<const N: usize>(
    problem: &mut Model<N>,
    x0: &[f64],
    settings: &LocalSettings,
    observe: &mut dyn FnMut(&Progress<'_>) -> bool,
) -> Result<LocalResult, Error> {
    check_start(problem, x0)?;
    problem.evaluate(x0, None)?;
    if settings.fixed_container {
        return placement(problem, x0, settings, observe);
    }
    match settings.method {
        LocalMethod::AugmentedLagrangian => lagrangian(problem, x0, settings, observe),
        LocalMethod::Compression => compression(problem, x0, settings, observe),
        LocalMethod::CompressionThenLagrangian => {
            let compressed = compression(problem, x0, settings, observe)?;
            if compressed.report.stop_reason == auglag::StopReason::Interrupted {
                return Ok(compressed);
            }
            // The compressed packing is certified: whatever the augmented Lagrangian does
            // after it, it is never lost.
            let Ok(refined) = lagrangian(problem, &compressed.x, settings, observe) else {
                return Ok(compressed);
            };
            let stop_reason = refined.report.stop_reason;
            let (mut kept, other) = if refined.density > compressed.density {
                (refined, compressed)
            } else {
                (compressed, refined)
            };
            add_counts(&mut kept.report, &other.report);
            kept.report.stop_reason = stop_reason;
            Ok(kept)
        }
    }
}

/// The augmented Lagrangian on the paper's model from `x0`, certified and repaired, with
/// the polish when the repair had something to do.
fn lagrangian<const N: usize>(
    problem: &mut Model<N>,
    x0: &[f64],
    settings: &LocalSettings,
    observe: &mut dyn FnMut(&Progress<'_>) -> bool,
) -> Result<LocalResult, Error> {
    let mut run = solver(settings, observe);
    let mut solve = |problem: &mut Model<N>, x: &[f64], feasibility: f64| {
        let adapter = Adapter::new(problem, centre_bound::<N>(x0), None);
        run(&adapter, x, feasibility)
    };
    let first = solve(problem, x0, settings.feasibility_tolerance)?;
    let mut best = certified(problem, first)?;
    if let Some(tolerance) = settings.polish_tolerance
        && best.repair_factor > 1.0
        && best.report.stop_reason != auglag::StopReason::Interrupted
    {
        let start = best.x_unrepaired.clone();
        let solution = solve(problem, &start, tolerance)?;
        let polished = certified(problem, solution)?;
        if polished.result.density > best.result.density {
            best = polished;
        }
    }
    Ok(best.result)
}

/// [`local_minimisation`] in feasibility mode: the container stays as the start gives it, the
/// solver drives overlap and containment to zero for items grown by [`FIXED_MARGIN`], and the
/// true items are certified. A point the first solve leaves uncertified is solved again from
/// where it stopped at the polish tolerance; the less infeasible of the two is returned.
fn placement<const N: usize>(
    problem: &mut Model<N>,
    x0: &[f64],
    settings: &LocalSettings,
    observe: &mut dyn FnMut(&Progress<'_>) -> bool,
) -> Result<LocalResult, Error> {
    let grown: Vec<[f64; N]> = problem
        .semi_axes()
        .iter()
        .map(|l| l.map(|v| v * (1.0 + FIXED_MARGIN)))
        .collect();
    let mut solver_model = Model::<N>::new(grown, problem.container_kind())?;
    let container = x0[problem.len() * Model::<N>::vars_per_body()..].to_vec();
    let mut run = solver(settings, observe);
    let mut solve = |x: &[f64], feasibility: f64| {
        let adapter = Adapter::new(
            &mut solver_model,
            centre_bound::<N>(x0),
            Some(container.clone()),
        );
        run(&adapter, x, feasibility)
    };
    let items = item_measure(problem);
    let judge = |problem: &mut Model<N>, solution: auglag::Solution| {
        let certificate = problem.certify(&solution.x)?;
        let objective = problem.evaluate(&solution.x, None)?.objective;
        Ok::<_, Error>(LocalResult {
            density: items / objective,
            density_before_repair: items / objective,
            repair_factor: 1.0,
            objective,
            certificate,
            report: solution.report,
            x: solution.x,
        })
    };
    let first = solve(x0, settings.feasibility_tolerance)?;
    let first = judge(problem, first)?;
    if first.certificate.is_feasible()
        || first.report.stop_reason == auglag::StopReason::Interrupted
    {
        return Ok(first);
    }
    let Some(tolerance) = settings.polish_tolerance else {
        return Ok(first);
    };
    let second = solve(&first.x, tolerance)?;
    let second = judge(problem, second)?;
    if second.certificate.is_feasible()
        || infeasibility(problem, &second.x)? <= infeasibility(problem, &first.x)?
    {
        Ok(second)
    } else {
        Ok(first)
    }
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

/// The start `x` as a result of its own, without minimising, when it is certified as it is
/// (no overlap, every item inside): a lattice start is, and so is a packing read back from a
/// finished run. `Ok(Err(certificate))` says what is wrong with a start that is not.
///
/// A run keeps this as its first best packing, so that it ends with a certified packing even
/// when its first local minimisation is cut off before it converges, and a resumed run never
/// writes a packing worse than the one it started from.
///
/// # Errors
/// [`Error::Model`] (`LengthMismatch`) when `x` does not fit the problem; errors of the model on
/// non-finite variables.
pub fn certified_start<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
) -> Result<Result<LocalResult, Certificate>, Error> {
    check_start(problem, x)?;
    let certificate = problem.certify(x)?;
    if !certificate.is_feasible() {
        return Ok(Err(certificate));
    }
    let objective = problem.evaluate(x, None)?.objective;
    let density = item_measure(problem) / objective;
    Ok(Ok(LocalResult {
        x: x.to_vec(),
        density,
        density_before_repair: density,
        repair_factor: 1.0,
        objective,
        certificate,
        // No solver ran: no iterations, no evaluations beyond the certificate's.
        report: Report {
            objective,
            best_feasible_objective: Some(objective),
            ..empty_report()
        },
    }))
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

/// A certified result with the solver's own point kept for a warm start.
pub(crate) struct Certified {
    pub(crate) result: LocalResult,
    x_unrepaired: Vec<f64>,
    repair_factor: f64,
    report: Report,
}

pub(crate) fn certified<const N: usize>(
    problem: &mut Model<N>,
    solution: auglag::Solution,
) -> Result<Certified, Error> {
    let repaired = repair(problem, &solution.x)?;
    certified_as(problem, solution, repaired)
}

/// [`certified`] with the repair of the solver's point already done (`repaired` as returned
/// by [`repair`] for `solution.x`).
pub(crate) fn certified_as<const N: usize>(
    problem: &mut Model<N>,
    solution: auglag::Solution,
    repaired: (Vec<f64>, f64, Certificate),
) -> Result<Certified, Error> {
    let (x, repair_factor, certificate) = repaired;
    let items = item_measure(problem);
    let before = problem.evaluate(&solution.x, None)?.objective;
    let objective = problem.evaluate(&x, None)?.objective;
    Ok(Certified {
        result: LocalResult {
            x,
            density: items / objective,
            density_before_repair: items / before,
            repair_factor,
            objective,
            certificate,
            report: solution.report.clone(),
        },
        x_unrepaired: solution.x,
        repair_factor,
        report: solution.report,
    })
}

/// A packing made of `x` by the least enlargement of its container found in two exact steps:
/// the centres and the container dilated by s = max 1/μ_ij over the overlapping pairs
/// (dilating the centres multiplies every pair's contact function μ² by s²), then the
/// container alone scaled about its centre by t, the largest containment scale of an item
/// still outside (the least factor that holds it, [`containment_scale`]; the centres stay, so
/// no pair changes). Returns the packing, the container's linear factor s·t ≥ 1 and the
/// certificate. Scaling the container alone costs far less than dilating everything: an item
/// a depth d outside needs t − 1 ≈ d/R of a container of size R, but a dilation only gains
/// (s − 1)·(R − |c|) on it, s − 1 ≈ d/r for an item of size r at the wall. When rounding leaves
/// anything uncertified, the least uniform dilation that certifies (by doubling and bisection)
/// is returned instead.
///
/// [`containment_scale`]: implicit_packing::certificate::containment_scale
///
/// # Errors
/// Errors of the model (non-finite variables); [`Error::NotCertifiable`] when no factor up to
/// 4 makes a packing (an item far outside the container).
pub fn repair<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
) -> Result<(Vec<f64>, f64, Certificate), Error> {
    let certificate = problem.certify(x)?;
    if certificate.is_feasible() {
        return Ok((x.to_vec(), 1.0, certificate));
    }
    match separated_then_held(problem, x, &certificate)? {
        Some(repaired) if repaired.1 <= MAX_DILATION => Ok(repaired),
        _ => least_uniform_dilation(problem, x, &certificate),
    }
}

/// The two exact steps of [`repair`] for a point `x` whose certificate is `certificate`: the
/// packing, its factor s·t and its certificate, or `None` when rounding leaves anything
/// uncertified.
pub(crate) fn separated_then_held<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
    certificate: &Certificate,
) -> Result<Option<(Vec<f64>, f64, Certificate)>, Error> {
    let (s, y, dilated) = if certificate.overlapping.is_empty() {
        (1.0, x.to_vec(), certificate.clone())
    } else {
        let s = pair_dilation(certificate);
        let y = dilate::<N>(problem, x, s);
        let dilated = problem.certify(&y)?;
        (s, y, dilated)
    };
    if !dilated.overlapping.is_empty() {
        return Ok(None);
    }
    if dilated.outside.is_empty() {
        return Ok(Some((y, s, dilated)));
    }
    let t = dilated.outside.iter().fold(1.0_f64, |t, o| t.max(o.scale)) * (1.0 + MARGIN);
    let z = container_scaled::<N>(problem, &y, t);
    let held = problem.certify(&z)?;
    Ok(held.is_feasible().then_some((z, s * t, held)))
}

/// Past this factor of the container's linear size a point is given up: an item far outside
/// (its centre outside the container, for a dilation) is no packing worth keeping.
const MAX_DILATION: f64 = 4.0;

/// A relative margin on every factor keeps the verdicts clear of rounding at tangency.
const MARGIN: f64 = 1e-12;

/// The dilation of centres and container that settles every overlapping pair of `certificate`
/// exactly, s = max 1/μ_ij (μ² grows as s²), with the margin.
fn pair_dilation(certificate: &Certificate) -> f64 {
    let s = certificate
        .overlapping
        .iter()
        .filter(|o| o.mu2 > 0.0)
        .fold(1.0_f64, |s, o| s.max(1.0 / o.mu2.sqrt()));
    s * (1.0 + MARGIN)
}

/// The least uniform dilation s ≥ 1 of the centres and the container after which `x` passes
/// [`Model::certify`] (`certificate` is that of `x`): the pairs' s = max 1/μ_ij, then
/// containment, which improves monotonically with s, by doubling and bisection.
fn least_uniform_dilation<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
    certificate: &Certificate,
) -> Result<(Vec<f64>, f64, Certificate), Error> {
    let mut s = pair_dilation(certificate);
    // Containment and any pair the formula could not settle: grow until certified, then
    // bisect back to the least factor that passes.
    let mut lo = 1.0;
    let mut y = dilate::<N>(problem, x, s);
    let mut cert = problem.certify(&y)?;
    // Dilation scales a centre and the container together, so an item whose centre is
    // outside the container is never repaired: past MAX_DILATION the point is given up.
    while !cert.is_feasible() {
        lo = s;
        s = 1.0 + 2.0 * (s - 1.0).max(1e-9);
        if s > MAX_DILATION {
            return Err(Error::NotCertifiable {
                max_dilation: MAX_DILATION,
                overlapping: cert.overlapping.len(),
                outside: cert.outside.len(),
            });
        }
        y = dilate::<N>(problem, x, s);
        cert = problem.certify(&y)?;
    }
    let mut hi = s;
    for _ in 0..60 {
        if hi - lo <= MARGIN * hi {
            break;
        }
        let mid = 0.5 * (lo + hi);
        let trial = dilate::<N>(problem, x, mid);
        let c = problem.certify(&trial)?;
        if c.is_feasible() {
            hi = mid;
            y = trial;
            cert = c;
        } else {
            lo = mid;
        }
    }
    Ok((y, hi, cert))
}

/// The container's dimensions of `x` multiplied by `t` (scaled about its centre); the items
/// stay.
fn container_scaled<const N: usize>(problem: &Model<N>, x: &[f64], t: f64) -> Vec<f64> {
    let bodies_end = problem.len() * Model::<N>::vars_per_body();
    let mut y = x.to_vec();
    y[bodies_end..].iter_mut().for_each(|v| *v *= t);
    y
}

/// Centres and container dimensions multiplied by `s`; angles unchanged ([`Model::dilated`]).
fn dilate<const N: usize>(problem: &Model<N>, x: &[f64], s: f64) -> Vec<f64> {
    problem.dilated(x, s)
}

/// The model as an [`auglag::Problem`]: objective = container measure, two equality
/// constraints h₁ = overlap, h₂ = containment, evaluated together. In energy mode (a fixed
/// container, [`Adapter::in_energy_mode`]) the objective is h₁ + h₂ and there are no constraints.
pub(crate) struct Adapter<'a, const N: usize> {
    model: RefCell<&'a mut Model<N>>,
    gradient: RefCell<ModelGradient>,
    /// The point of the last Hessian product, with its constraint values and gradients: a
    /// truncated-Newton step asks for many products at one point.
    hessian_point: RefCell<HessianPoint>,
    product: RefCell<ModelGradient>,
    lower: f64,
    centre_bound: f64,
    /// Feasibility mode: the container variables' fixed values; the objective is then 0.
    fixed: Option<Vec<f64>>,
    /// Angle variables held at these values: `(variable, value)`.
    frozen: Vec<(usize, f64)>,
    /// Energy mode: overlap + containment is the objective, unconstrained.
    energy: bool,
}

/// A point with the overlap and containment values and the three gradients there.
#[derive(Default)]
struct HessianPoint {
    x: Vec<f64>,
    overlap: f64,
    containment: f64,
    gradient: ModelGradient,
}

impl<'a, const N: usize> Adapter<'a, N> {
    pub(crate) fn new(model: &'a mut Model<N>, centre_bound: f64, fixed: Option<Vec<f64>>) -> Self {
        // Every item contains a ball of its smallest semi-axis, so no container dimension can
        // be smaller than the largest of those: a safe lower bound that keeps the container
        // from collapsing through zero during early iterations.
        let lower = model
            .semi_axes()
            .iter()
            .map(|l| l.iter().fold(f64::INFINITY, |a, &b| a.min(b)))
            .fold(0.0_f64, f64::max);
        Self {
            model: RefCell::new(model),
            gradient: RefCell::new(ModelGradient::default()),
            hessian_point: RefCell::new(HessianPoint::default()),
            product: RefCell::new(ModelGradient::default()),
            lower,
            centre_bound,
            fixed,
            frozen: Vec::new(),
            energy: false,
        }
    }

    /// Energy mode (with a fixed container only): the sum of the overlap and containment
    /// measures, `E = h₁ + h₂ ≥ 0` with `E = 0` exactly on packings, minimised as an objective
    /// without constraints. The penalty of the augmented Lagrangian, `λh + ρh²/2` with λ = 0
    /// in its first outer iteration, is quartic in the penetrations there; E is quadratic, as
    /// the overlap energies minimised in jamming studies. On random starts of 3·10⁴ and 10⁵
    /// ellipsoids compressed to φ = 0.6 the last placement took 751 and 1 000 inner
    /// iterations against 901 and 1 297 with the Lagrangian.
    pub(crate) fn in_energy_mode(mut self, energy: bool) -> Self {
        self.energy = energy && self.fixed.is_some();
        self
    }

    /// E and, when asked, ∇E (see [`Adapter::in_energy_mode`]); NaN where the model refuses `x`.
    fn energy(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        let mut model = self.model.borrow_mut();
        let Some(g) = grad else {
            return model
                .evaluate(x, None)
                .map_or(f64::NAN, |e| e.overlap + e.containment);
        };
        let mut mg = self.gradient.borrow_mut();
        match model.evaluate(x, Some(&mut mg)) {
            Ok(e) => {
                for ((g, o), c) in g.iter_mut().zip(&mg.overlap).zip(&mg.containment) {
                    *g = o + c;
                }
                e.overlap + e.containment
            }
            Err(_) => {
                g.fill(f64::NAN);
                f64::NAN
            }
        }
    }

    /// The same with the angle variables of the items marked in `items` held at their values
    /// in `x`: those items keep their orientation.
    pub(crate) fn with_frozen_orientations(mut self, items: &[bool], x: &[f64]) -> Self {
        let stride = Model::<N>::vars_per_body();
        self.frozen = items
            .iter()
            .enumerate()
            .filter(|(_, frozen)| **frozen)
            .flat_map(|(i, _)| (i * stride + N..(i + 1) * stride).map(|k| (k, x[k])))
            .filter(|(k, _)| *k < x.len())
            .collect();
        self
    }

    /// The factor of the objective in the Lagrangian: 0 in feasibility mode, where the
    /// container measure is a constant that must not pull on anything.
    fn objective_weight(&self, phr: &Phr<'_>) -> f64 {
        if self.fixed.is_some() {
            0.0
        } else {
            phr.objective_scale()
        }
    }

    /// Runs `f` on the model between two evaluations (its values are a function of the point
    /// alone, so a certificate taken here changes nothing the solver sees).
    pub(crate) fn with_model<R>(&self, f: impl FnOnce(&mut Model<N>) -> R) -> R {
        f(&mut self.model.borrow_mut())
    }

    fn body_variables(&self) -> usize {
        self.model.borrow().len() * Model::<N>::vars_per_body()
    }
}

impl<const N: usize> auglag::Problem for Adapter<'_, N> {
    fn dim(&self) -> usize {
        self.model.borrow().var_count()
    }

    fn bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        let start = self.body_variables();
        lower[start..].fill(self.lower);
        if self.model.borrow().container_kind() == ContainerShape::Periodic {
            // The tilts of a periodic cell (after its N diagonal entries) have either sign;
            // the bound only keeps them finite (the model is exact for any tilt).
            lower[start + N..].fill(-self.centre_bound);
            upper[start + N..].fill(self.centre_bound);
        }
        if let Some(fixed) = &self.fixed {
            lower[start..].copy_from_slice(fixed);
            upper[start..].copy_from_slice(fixed);
        }
        // Centres stay within a box far larger than any packing the start leads to: without
        // it a quasi-Newton step from a badly overlapping start could throw an item out to
        // 1e30, where the model refuses the point and the start is lost.
        let stride = Model::<N>::vars_per_body();
        for k in (0..start).filter(|k| k % stride < N) {
            lower[k] = -self.centre_bound;
            upper[k] = self.centre_bound;
        }
        for &(k, v) in &self.frozen {
            lower[k] = v;
            upper[k] = v;
        }
    }

    fn n_eq(&self) -> usize {
        if self.energy { 0 } else { 2 }
    }

    fn objective(&self, x: &[f64], grad: Option<&mut [f64]>) -> f64 {
        if self.energy {
            return self.energy(x, grad);
        }
        if self.fixed.is_some() {
            if let Some(g) = grad {
                g.fill(0.0);
            }
            return 0.0;
        }
        let mut model = self.model.borrow_mut();
        match grad {
            None => model.evaluate(x, None).map_or(f64::NAN, |e| e.objective),
            Some(g) => {
                let mut mg = self.gradient.borrow_mut();
                match model.evaluate(x, Some(&mut mg)) {
                    Ok(e) => {
                        g.copy_from_slice(&mg.objective);
                        e.objective
                    }
                    Err(_) => f64::NAN,
                }
            }
        }
    }

    fn constraints(&self, x: &[f64], c: &mut [f64]) {
        if self.energy {
            return;
        }
        match self.model.borrow_mut().evaluate(x, None) {
            Ok(e) => {
                c[0] = e.overlap;
                c[1] = e.containment;
            }
            Err(_) => c.fill(f64::NAN),
        }
    }

    fn constraints_jt_times(&self, x: &[f64], w: &[f64], out: &mut [f64]) {
        if self.energy {
            return;
        }
        let mut model = self.model.borrow_mut();
        let mut mg = self.gradient.borrow_mut();
        if model.evaluate(x, Some(&mut mg)).is_err() {
            out.fill(f64::NAN);
            return;
        }
        for (k, o) in out.iter_mut().enumerate() {
            *o += w[0] * mg.overlap[k] + w[1] * mg.containment[k];
        }
    }

    /// The model's exact products ([`Model::hessian_vector_product`]) assembled as the
    /// trait documents: sf ∇²V v + Σᵢ [λᵢ⁺ ∇²cᵢ v + ρ sᵢ² ∇cᵢ (∇cᵢᵀ v)] over the overlap and
    /// containment constraints.
    fn hessian_times(&self, x: &[f64], phr: &Phr<'_>, v: &[f64], out: &mut [f64]) -> bool {
        if self.energy {
            // The solver's difference quotient of gradients serves the energy.
            return false;
        }
        let mut model = self.model.borrow_mut();
        let mut at = self.hessian_point.borrow_mut();
        if at.x != x {
            let at = &mut *at;
            match model.evaluate(x, Some(&mut at.gradient)) {
                Ok(e) => {
                    at.x.clear();
                    at.x.extend_from_slice(x);
                    (at.overlap, at.containment) = (e.overlap, e.containment);
                }
                Err(_) => {
                    at.x.clear();
                    out.fill(f64::NAN);
                    return true;
                }
            }
        }
        let mut hv = self.product.borrow_mut();
        if model.hessian_vector_product(x, v, &mut hv).is_err() {
            out.fill(f64::NAN);
            return true;
        }
        let g = &at.gradient;
        let along = |gradient: &[f64]| gradient.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
        let sf = self.objective_weight(phr);
        let (d0, d1) = (
            phr.derivative(0, at.overlap),
            phr.derivative(1, at.containment),
        );
        let k0 = phr.curvature(0, at.overlap) * along(&g.overlap);
        let k1 = phr.curvature(1, at.containment) * along(&g.containment);
        for (k, o) in out.iter_mut().enumerate() {
            *o = sf * hv.objective[k]
                + d0 * hv.overlap[k]
                + d1 * hv.containment[k]
                + k0 * g.overlap[k]
                + k1 * g.containment[k];
        }
        true
    }

    fn lagrangian(&self, x: &[f64], phr: &Phr<'_>, grad: Option<&mut [f64]>) -> Option<f64> {
        if self.energy {
            let sf = phr.objective_scale();
            let value = match grad {
                None => self.energy(x, None),
                Some(g) => {
                    let value = self.energy(x, Some(&mut *g));
                    g.iter_mut().for_each(|v| *v *= sf);
                    value
                }
            };
            return Some(sf * value);
        }
        let sf = self.objective_weight(phr);
        let mut model = self.model.borrow_mut();
        Some(match grad {
            None => match model.evaluate(x, None) {
                Ok(e) => sf * e.objective + phr.term(0, e.overlap) + phr.term(1, e.containment),
                Err(_) => f64::NAN,
            },
            Some(g) => {
                let mut mg = self.gradient.borrow_mut();
                match model.evaluate(x, Some(&mut mg)) {
                    Ok(e) => {
                        let (d0, d1) = (
                            phr.derivative(0, e.overlap),
                            phr.derivative(1, e.containment),
                        );
                        for k in 0..g.len() {
                            g[k] =
                                sf * mg.objective[k] + d0 * mg.overlap[k] + d1 * mg.containment[k];
                        }
                        sf * e.objective + phr.term(0, e.overlap) + phr.term(1, e.containment)
                    }
                    Err(_) => {
                        g.fill(f64::NAN);
                        f64::NAN
                    }
                }
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::starts::lattice_start;

    /// In energy mode the objective is overlap + containment with its gradient (against
    /// central differences), the Lagrangian the same scaled, and there are no constraints.
    #[test]
    fn energy_mode_is_the_overlap_energy_without_constraints() {
        use auglag::Problem;
        let mut model = Model::<2>::new(vec![[2.0, 1.0]; 6], ContainerShape::Ellipsoid).unwrap();
        let mut x = lattice_start(&model);
        let n = x.len();
        // Centres (and angles) drawn together, the container shrunk more: overlaps and items
        // sticking out.
        for (k, v) in x.iter_mut().enumerate() {
            *v *= if k >= n - 2 { 0.7 } else { 0.8 };
        }
        let e = model.evaluate(&x, None).unwrap();
        assert!(e.overlap > 0.0 && e.containment > 0.0, "{e:?}");
        let container = x[n - 2..].to_vec();
        let adapter = Adapter::new(&mut model, 1e3, Some(container)).in_energy_mode(true);
        assert_eq!(adapter.n_eq(), 0);
        let mut g = vec![0.0; n];
        assert_eq!(
            adapter.objective(&x, Some(&mut g)),
            e.overlap + e.containment
        );
        let phr = Phr::new(10.0, 0, 0.5, &[], &[]);
        let mut gl = vec![0.0; n];
        assert_eq!(
            adapter.lagrangian(&x, &phr, Some(&mut gl)),
            Some(0.5 * (e.overlap + e.containment))
        );
        let h = 1e-6;
        for k in 0..n - 2 {
            let at = |t: f64| {
                let mut y = x.clone();
                y[k] += t;
                adapter.objective(&y, None)
            };
            let fd = (at(h) - at(-h)) / (2.0 * h);
            assert!(
                (fd - g[k]).abs() <= 1e-5 * (1.0 + g[k].abs()),
                "{k}: {fd} {}",
                g[k]
            );
            assert_eq!(gl[k], 0.5 * g[k]);
        }
    }

    /// The adapter's exact Hessian products against central differences of its own fused
    /// gradient, on an overlapping point, for ellipses and ellipsoids.
    #[test]
    fn hessian_products_match_differences_of_the_gradient() {
        fn check<const N: usize>(axes: [f64; N], kind: ContainerShape) {
            use auglag::Problem;
            let mut model = Model::<N>::new(vec![axes; 12], kind).unwrap();
            let mut x = lattice_start(&model);
            let n = x.len();
            // Shrink the container and shift the items: overlaps and items sticking out.
            for (k, v) in x.iter_mut().enumerate() {
                *v *= if k >= n - N { 0.85 } else { 1.0 };
                *v += 0.01 * ((k * 7919 % 13) as f64 - 6.0);
            }
            let adapter = Adapter::new(&mut model, 1e3, None);
            let (scales, multipliers) = ([0.5, 2.0], [0.3, -0.2]);
            let phr = Phr::new(10.0, 2, 0.7, &scales, &multipliers);
            let v: Vec<f64> = (0..n).map(|k| ((k * 31 % 17) as f64 - 8.0) / 8.0).collect();
            let mut hv = vec![0.0; n];
            assert!(adapter.hessian_times(&x, &phr, &v, &mut hv));
            let h = 1e-6;
            let gradient_at = |t: f64| {
                let y: Vec<f64> = x.iter().zip(&v).map(|(a, b)| a + t * b).collect();
                let mut g = vec![0.0; n];
                adapter.lagrangian(&y, &phr, Some(&mut g)).unwrap();
                g
            };
            let (plus, minus) = (gradient_at(h), gradient_at(-h));
            let scale = hv.iter().fold(1.0_f64, |m, a| m.max(a.abs()));
            for k in 0..n {
                let fd = (plus[k] - minus[k]) / (2.0 * h);
                assert!(
                    (hv[k] - fd).abs() <= 1e-5 * scale,
                    "{N}D, variable {k}: {} against {fd}",
                    hv[k]
                );
            }
            assert!(hv.iter().any(|&a| a != 0.0));
        }
        check([2.0, 1.0], ContainerShape::Ellipsoid);
        check([1.0, 0.75, 0.5], ContainerShape::Ball);
    }

    #[test]
    fn lattice_start_is_certified_feasible() {
        let mut p2 = Model::<2>::new(vec![[2.0, 1.0]; 30], ContainerShape::Ellipsoid).unwrap();
        let x = lattice_start(&p2);
        assert!(p2.certify(&x).unwrap().is_feasible());
        let mut p3 = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 27], ContainerShape::Box).unwrap();
        let x = lattice_start(&p3);
        assert!(p3.certify(&x).unwrap().is_feasible());
    }

    #[test]
    fn two_and_three_unit_circles_in_the_smallest_circle() {
        // Known optima: R = 2 for two unit circles, 1 + 2/√3 for three.
        for (m, optimum) in [(2, 2.0), (3, 1.0 + 2.0 / 3f64.sqrt())] {
            let mut p = Model::<2>::new(vec![[1.0, 1.0]; m], ContainerShape::Ball).unwrap();
            let mut x = lattice_start(&p);
            // Break the symmetry of the lattice start a little.
            x[2] += 0.1;
            let settings = LocalSettings {
                feasibility_tolerance: 1e-8,
                optimality_tolerance: 1e-8,
                ..LocalSettings::default()
            };
            let r = local_minimisation(&mut p, &x, &settings, &mut |_| false).unwrap();
            assert!(r.certificate.is_feasible());
            let radius = *r.x.last().unwrap();
            assert!(
                (radius - optimum).abs() < 1e-3 * optimum,
                "m = {m}: R = {radius} vs {optimum} ({:?})",
                r.report.stop_reason
            );
            assert!(r.density <= m as f64 / (optimum * optimum) * (1.0 + 1e-9));
        }
    }

    #[test]
    fn ellipses_in_an_ellipse_end_certified_and_denser_than_the_start() {
        let mut p = Model::<2>::new(vec![[2.0, 1.0]; 12], ContainerShape::Ellipsoid).unwrap();
        let x0 = lattice_start(&p);
        let start_density = item_measure(&p) / p.evaluate(&x0, None).unwrap().objective;
        let r = local_minimisation(&mut p, &x0, &LocalSettings::default(), &mut |_| false).unwrap();
        assert!(r.certificate.is_feasible());
        assert!(
            r.density > start_density,
            "{} vs start {start_density}",
            r.density
        );
        assert!(r.repair_factor >= 1.0 && r.density <= r.density_before_repair);
    }

    #[test]
    fn repair_holds_an_item_outside_by_scaling_the_container_alone() {
        let mut p = Model::<3>::new(vec![[1.0, 1.0, 1.0]; 2], ContainerShape::Ball).unwrap();
        // A unit sphere at 2.5 from the centre of a ball of radius 3 sticks out by 0.5: the
        // container needs t = 3.5/3, a uniform dilation s = 2 (2.5 s + 1 ≤ 3 s).
        let x = vec![
            2.5, 0.0, 0.0, 0.0, 0.0, 0.0, -1.5, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0,
        ];
        let (y, s, cert) = repair(&mut p, &x).unwrap();
        assert!(cert.is_feasible());
        assert!((s - 3.5 / 3.0).abs() < 1e-9, "{s}");
        assert_eq!(y[..12], x[..12]);
        assert!((y[12] - 3.5).abs() < 1e-9);
    }

    #[test]
    fn repair_holds_an_item_outside_a_box_by_scaling_its_half_sides() {
        let mut p = Model::<2>::new(vec![[2.0, 1.0]; 2], ContainerShape::Box).unwrap();
        // The first ellipse reaches x = 4.5 in a box of half-sides (4, 2): t = 4.5/4, and the
        // box keeps its aspect.
        let x = vec![2.5, 0.0, 0.0, -1.6, 0.0, 0.0, 4.0, 2.0];
        let (y, s, cert) = repair(&mut p, &x).unwrap();
        assert!(cert.is_feasible());
        assert!((s - 1.125).abs() < 1e-9, "{s}");
        assert_eq!(y[..6], x[..6]);
        assert!((y[6] - 4.5).abs() < 1e-9 && (y[7] - 2.25).abs() < 1e-9);
    }

    #[test]
    fn repair_separates_then_holds_by_the_product_of_the_two_factors() {
        let mut p = Model::<3>::new(vec![[1.0, 1.0, 1.0]; 2], ContainerShape::Ball).unwrap();
        // Unit spheres 1.5 apart in a ball of radius 1.2: s = 4/3 moves them to ±1 in a ball
        // of radius 1.6, which t = 2/1.6 then makes 2. A uniform dilation needs 1/0.45.
        let x = vec![
            0.75, 0.0, 0.0, 0.0, 0.0, 0.0, -0.75, 0.0, 0.0, 0.0, 0.0, 0.0, 1.2,
        ];
        let (y, s, cert) = repair(&mut p, &x).unwrap();
        assert!(cert.is_feasible());
        assert!((s - 4.0 / 3.0 * 1.25).abs() < 1e-9, "{s}");
        assert!((y[0] - 1.0).abs() < 1e-9 && (y[6] + 1.0).abs() < 1e-9);
        assert!((y[12] - 2.0).abs() < 1e-9, "{}", y[12]);
    }

    #[test]
    fn repair_separates_overlapping_items_by_the_least_dilation() {
        let mut p = Model::<3>::new(vec![[1.0, 1.0, 1.0]; 2], ContainerShape::Ball).unwrap();
        // Two unit spheres 1.5 apart in a ball of radius 3: μ = 0.75, s = 4/3.
        let x = vec![
            -0.75, 0.0, 0.0, 0.0, 0.0, 0.0, 0.75, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0,
        ];
        let (y, s, cert) = repair(&mut p, &x).unwrap();
        assert!(cert.is_feasible());
        assert!((s - 4.0 / 3.0).abs() < 1e-9, "{s}");
        assert!((y[6] - y[0] - 2.0).abs() < 1e-9);
    }

    #[test]
    fn interrupt_still_returns_a_certified_packing() {
        let mut p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 20], ContainerShape::Ball).unwrap();
        let x0 = lattice_start(&p);
        let mut calls = 0;
        let r = local_minimisation(&mut p, &x0, &LocalSettings::default(), &mut |_| {
            calls += 1;
            calls > 5
        })
        .unwrap();
        assert!(r.certificate.is_feasible());
        assert_eq!(r.report.stop_reason, auglag::StopReason::Interrupted);
    }
}
