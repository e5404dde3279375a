//! A packing run: scene → model → multi-start → certified packing and its summary; and the
//! independent check of a packing read back from files.
//!
//! The numerical work lives in `ellipsoid-packer` (starts, local minimisation with repair, the
//! multi-start) on the model of `implicit-packing`; this module translates between the scene and
//! file formats of the command line and the model's variables `[c_1, Ω_1, …, c_m, Ω_m, dims]`
//! (Ω = θ in 2D, the angles [φ, θ, ψ] of eq. 2 in 3D), with containers centred at the origin.

use crate::packing::{
    CertificateCounts, Container, ContainerKind, EllipseItem, EllipsoidItem, Items, Packing,
    PackingError, Summary,
};
use crate::scene::{RandomGoal, Scene};
use ellipsoid_packer::compression::compression_seen;
use ellipsoid_packer::local::{LocalMethod, LocalSettings};
pub use ellipsoid_packer::multistart::{MultiStartProgress, Observer, Shard};
use ellipsoid_packer::multistart::{MultiStartSettings, multistart};
use ellipsoid_packer::random::{RandomPacking, RandomSettings, Target, random_packing_seen};
use ellipsoid_packer::starts::{LatticeStart, fill_start, lattice_start};
use implicit_packing::Body;
use implicit_packing::certificate::shown_mu2;
use implicit_packing::containment::{
    Container as SizedContainer, ContainerShape as ModelContainer,
};
use implicit_packing::model::Model;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Why a run or a check failed.
#[derive(Debug, thiserror::Error)]
pub enum PackError {
    /// The structure of a packing could not be measured.
    #[error("structure: {0}")]
    Structure(#[from] structure::Error),
    /// The model refused the problem.
    #[error("{0}")]
    Model(#[from] implicit_packing::Error),
    /// The packer could not give a certified packing.
    #[error("{0}")]
    Packer(#[from] ellipsoid_packer::Error),
    /// A packing file could not be read or written.
    #[error("{0}")]
    Packing(#[from] PackingError),
    /// A packing given to resume from does not match the scene.
    #[error("cannot resume: {0}")]
    Mismatch(String),
    /// A value of an item or of the container that the model cannot hold, named as the
    /// packing states it (not as a model variable).
    #[error("{what} is {value}; {rule}")]
    OutOfRange {
        /// The item and coordinate, or the container's value.
        what: String,
        /// The value, as the model saw it.
        value: String,
        /// What the model accepts.
        rule: &'static str,
    },
    /// The folder to resume from holds a packing in another kind of container than the scene's.
    #[error(
        "cannot resume from {summary}: its container is {found}, but the scene ({scene}) has \
         {expected}"
    )]
    ContainerMismatch {
        /// The folder's `summary.json`.
        summary: PathBuf,
        /// The container kind of the folder.
        found: ContainerKind,
        /// The container kind of the scene.
        expected: ContainerKind,
        /// The scene's title.
        scene: String,
    },
    /// The packing to resume from is not a certified packing.
    #[error("cannot resume: the packing to resume from is not certified: {0}")]
    StartNotCertified(StartDefects),
    /// The output folder cannot be created or written to.
    #[error("the output folder {path} is not writable: {source}")]
    OutputFolder {
        /// The folder.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// A fixed container that the run could not fill without overlap: the least overlapping
    /// configuration comes with the error, to be kept apart from packings.
    #[error(
        "packing fraction {:.4} not reached in {:.1} s: the least overlapping configuration \
         ({} local minimisations) has {} overlapping pairs{} and {} items outside the container \
         (model overlap {:.3e})",
        .0.summary.density,
        .0.summary.wall_seconds,
        .0.summary.local_minimisations,
        .0.summary.certificate.overlapping_pairs,
        .0.summary.certificate.min_mu2.map_or(String::new(), |m| format!(" (smallest μ² {})", shown_mu2(m, 6))),
        .0.summary.certificate.containment_violations,
        .0.infeasibility
    )]
    NotReached(Box<Unfinished>),
    /// A fixed container given both by the scene and by a packing to resume from, of
    /// different sizes.
    #[error(
        "cannot resume: the packing's container ({found:?}) is not the scene's fixed container \
         ({expected:?})"
    )]
    FixedSizeMismatch {
        /// The size of the packing's container.
        found: Vec<f64>,
        /// The size the scene gives.
        expected: Vec<f64>,
    },
    /// A time limit that is not a positive number of seconds a clock can count to.
    #[error(
        "the time limit must be a number of seconds from 1e-9 (a nanosecond) to {max:.3e} \
         (about 585 billion years), not {seconds:e}",
        max = Duration::MAX.as_secs_f64()
    )]
    TimeLimit {
        /// The seconds given.
        seconds: f64,
    },
}

/// The least overlapping configuration of a fixed-container run that found no packing: written
/// to `unfinished/` of the output folder, never as a packing.
#[derive(Clone, Debug)]
pub struct Unfinished {
    /// The configuration (items may overlap or stick out).
    pub packing: Packing,
    /// Its summary: the certificate's counts, [`Summary::not_reached`] set.
    pub summary: Summary,
    /// The model's overlap plus containment violation there (0 only at a packing).
    pub infeasibility: f64,
    /// Whether the run was stopped by a signal rather than by its time limit.
    pub interrupted: bool,
}

/// The folder inside the output folder that holds [`Unfinished`] configurations.
pub const UNFINISHED_DIR: &str = "unfinished";

/// What makes a packing to resume from uncertified: the items that overlap and those that
/// stick out (ids are the rows' ids in `packing.csv`, counted from 0).
#[derive(Clone, Debug, PartialEq)]
pub struct StartDefects {
    /// Overlapping pairs `(i, j, μ²)` (μ² < 1).
    pub overlapping: Vec<(usize, usize, f64)>,
    /// Items outside the container, each with the factor by which the container would have
    /// to grow about its centre to hold it.
    pub outside: Vec<(usize, f64)>,
}

/// How many overlapping pairs and items outside a message lists before it says "and n more".
const LISTED: usize = 8;

impl std::fmt::Display for StartDefects {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut parts = Vec::new();
        if !self.overlapping.is_empty() {
            let list = listed(&self.overlapping, |&(i, j, m)| {
                format!("{i} and {j} (μ² = {})", shown_mu2(m, 6))
            });
            let n = self.overlapping.len();
            parts.push(format!("{n} overlapping pairs: items {list}"));
        }
        if !self.outside.is_empty() {
            let list = listed(&self.outside, |&(i, s)| {
                format!("{i} (the container would have to grow by {:.3e})", s - 1.0)
            });
            let n = self.outside.len();
            parts.push(format!("{n} items outside the container: {list}"));
        }
        write!(f, "{}", parts.join("; "))
    }
}

/// The first [`LISTED`] of `items`, shown by `show` and separated by commas, and how many more
/// there are.
fn listed<T>(items: &[T], show: impl Fn(&T) -> String) -> String {
    let mut list: Vec<String> = items.iter().take(LISTED).map(show).collect();
    if items.len() > LISTED {
        list.push(format!("and {} more", items.len() - LISTED));
    }
    list.join(", ")
}

/// Converts a time limit in seconds, refusing what is not positive or beyond a [`Duration`]
/// (which would otherwise panic).
///
/// # Errors
/// [`PackError::TimeLimit`] for zero, negative, NaN, infinite, too large values, or values
/// below a nanosecond.
pub fn time_limit_of(seconds: f64) -> Result<Duration, PackError> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err(PackError::TimeLimit { seconds });
    }
    Duration::try_from_secs_f64(seconds)
        .ok()
        .filter(|d| !d.is_zero())
        .ok_or(PackError::TimeLimit { seconds })
}

/// Makes sure the output folder can be written before a run spends its time: creates it,
/// then creates and removes a probe file in it.
///
/// # Errors
/// [`PackError::OutputFolder`] naming the folder.
pub fn probe_output_folder(path: &Path) -> Result<(), PackError> {
    let error = |source| PackError::OutputFolder {
        path: path.to_path_buf(),
        source,
    };
    std::fs::create_dir_all(path).map_err(error)?;
    // An unnamed file (O_TMPFILE) is never seen in the folder, even when the run is killed
    // right here; file systems without it get a named probe, which the next run removes.
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        match std::fs::OpenOptions::new()
            .write(true)
            .custom_flags(libc::O_TMPFILE)
            .open(path)
        {
            Ok(_) => return Ok(()),
            Err(e)
                if matches!(
                    e.raw_os_error(),
                    Some(libc::EOPNOTSUPP | libc::EISDIR | libc::EINVAL)
                ) => {}
            Err(e) => return Err(error(e)),
        }
    }
    let probe = path.join(format!("{}{}", crate::folder::PROBE, std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map_err(error)?;
    std::fs::remove_file(&probe).map_err(error)
}

/// Reads the packing to resume from in `folder` (`packing.csv` and `summary.json`) and checks
/// that its container is of the scene's kind; [`run`] checks the items and the certificate.
///
/// # Errors
/// Errors of reading the files ([`PackError::Packing`]), and
/// [`PackError::ContainerMismatch`].
pub fn resume_start(scene: &Scene, folder: &Path) -> Result<Packing, PackError> {
    let (packing, _) = crate::packing::read_packing_dir(folder)?;
    let found = packing.container().kind();
    if found != scene.container {
        return Err(PackError::ContainerMismatch {
            summary: folder.join(crate::packing::SUMMARY_FILE),
            found,
            expected: scene.container,
            scene: scene.title(),
        });
    }
    Ok(packing)
}

/// The table written beside a run's packing as history.csv: one row per finished local
/// minimisation (its number, the seconds since the start, its density and the best certified
/// density so far).
#[derive(Clone, Debug)]
pub struct History(String);

impl History {
    /// The table with its header and no rows.
    pub fn new() -> Self {
        Self(String::from(
            "local_minimisation,seconds,density,best_density
",
        ))
    }

    /// Adds the row of a finished local minimisation.
    pub fn record(&mut self, p: &MultiStartProgress) {
        self.0.push_str(&format!(
            "{},{:.3},{:.9},{:.9}\n",
            p.local_minimisations,
            p.elapsed.as_secs_f64(),
            p.last_density,
            p.best_density
        ));
    }

    /// The CSV text.
    pub fn into_text(self) -> String {
        self.0
    }
}

impl Default for History {
    fn default() -> Self {
        Self::new()
    }
}

/// Command-line overrides of the scene's settings.
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
    /// Wall-clock limit (else the scene's).
    pub time_limit: Option<Duration>,
    /// Seed of the multi-start (else the scene's).
    pub seed: Option<u64>,
    /// Threads (else the scene's; 0 means every core).
    pub threads: Option<usize>,
    /// A packing of the same items to start from (resuming a run).
    pub resume_from: Option<Packing>,
    /// This run's part of a multi-start spread over several runs (else the whole).
    pub shard: Option<Shard>,
}

/// The outcome of [`run`].
#[derive(Clone, Debug)]
pub struct RunOutcome {
    /// The best certified packing.
    pub packing: Packing,
    /// Its summary (density, objective, wall time, local minimisations, certificate).
    pub summary: Summary,
    /// Density of the solver's point before the repair dilation.
    pub density_before_repair: f64,
    /// The repair's factor, the container's linear scale (1: none needed).
    pub repair_factor: f64,
    /// Seconds from the start to the best packing.
    pub seconds_to_best: f64,
    /// Whether the run was interrupted (Ctrl-C).
    pub interrupted: bool,
    /// Starts abandoned because their local minimisation ended at an uncertifiable point.
    pub failed_starts: usize,
    /// New chains begun from fresh lattice starts (`solver.restart_after`).
    pub restarts: usize,
    /// Density of the start (the lattice start, or the packing resumed from).
    pub start_density: Option<f64>,
    /// Whether the packing is the start itself: no local minimisation found a denser one.
    pub start_kept: bool,
}

/// Packs the scene's items: the paper's lattice start (or `options.resume_from`), then the
/// multi-start until the time limit or the cap on local minimisations, then the certificate.
/// A scene that gives its container's size ([`Scene::fixed_container`]) is filled instead,
/// from a lattice start dilated into that container, until the first certified packing.
///
/// # Errors
/// [`PackError`] when the model refuses the items or the resume packing does not match;
/// [`PackError::NotReached`], with the least overlapping configuration, when a fixed container
/// was not filled; [`PackError::FixedSizeMismatch`] when the packing to resume from is not in
/// the scene's fixed container.
pub fn run(
    scene: &Scene,
    options: &RunOptions,
    observer: &mut dyn Observer,
) -> Result<RunOutcome, PackError> {
    match (scene.ellipse_axes(), scene.ellipsoid_axes()) {
        (Some(axes), _) => run_n::<2>(scene, &axes, options, observer),
        (_, Some(axes)) => run_n::<3>(scene, &axes, options, observer),
        _ => Err(PackError::Mismatch("the scene has no items".into())),
    }
}

fn run_n<const N: usize>(
    scene: &Scene,
    axes: &[[f64; N]],
    options: &RunOptions,
    observer: &mut dyn Observer,
) -> Result<RunOutcome, PackError> {
    if let Some(goal) = scene.random_goal() {
        return run_random::<N>(scene, axes, goal, options, observer);
    }
    let kind = model_container(scene.container);
    let mut problem = Model::<N>::new(axes.to_vec(), kind)?;
    let fixed = scene.fixed_container().map(|c| model_dimensions(&c, kind));
    let x0 = match &options.resume_from {
        Some(packing) => resumed_start(&mut problem, packing, scene, fixed.as_deref(), axes)?,
        None => match &fixed {
            Some(dims) => fill_start(&mut problem, &LatticeStart::centred(), dims)?,
            None => lattice_start(&problem),
        },
    };
    let threads = match options.threads.unwrap_or(scene.solver.threads) {
        0 => std::thread::available_parallelism().map_or(1, usize::from),
        n => n,
    };
    let mut local = local_settings(scene);
    local.fixed_container = fixed.is_some();
    let count = |n: u64| usize::try_from(n).unwrap_or(usize::MAX);
    let mut settings = MultiStartSettings::paper(N, options.seed.unwrap_or(scene.seed));
    settings.local = local;
    settings.perturbation = scene.solver.perturbation;
    // A resumed run continues from its packing; its lattice starts were tried before.
    settings.lattice_starts = if options.resume_from.is_some() {
        0
    } else {
        count(scene.solver.lattice_starts)
    };
    settings.from_best = scene.solver.from_best;
    settings.perturbation_levels = scene.solver.perturbation_levels;
    settings.fresh_lattice_every = count(scene.solver.fresh_lattice_every);
    settings.restart_after = count(scene.solver.restart_after);
    settings.threads = threads;
    settings.max_local_minimisations = scene.solver.local_minimisations.map_or(usize::MAX, count);
    let time_limit = options.time_limit.unwrap_or(scene.solver.time_limit);
    // A variable periodic cell of identical items also starts from its densest small cell
    // tiled (ellipsoid_packer::tiling) when that is denser than the lattice start; the time
    // it takes counts in the run's.
    let prelude = Instant::now();
    let x0 = if fixed.is_none() && options.resume_from.is_none() {
        // An eighth of the run per small cell, at most 8 s: three cells take a fraction of it.
        let per_cell = (time_limit / 8).min(Duration::from_secs(8));
        let tiled =
            ellipsoid_packer::tiling::tiled_start(&mut problem, &settings, per_cell, &*observer)?;
        let lattice = problem.evaluate(&x0, None)?.objective;
        match tiled {
            Some((y, density))
                if density > ellipsoid_packer::local::item_measure(&problem) / lattice =>
            {
                y
            }
            _ => x0,
        }
    } else {
        x0
    };
    let prelude = prelude.elapsed();
    settings.time_limit = Some(time_limit.saturating_sub(prelude));
    settings.shard = options.shard.unwrap_or(Shard::WHOLE);
    let mut shifted = Shifted {
        inner: observer,
        by: prelude,
    };
    let result = match multistart(axes, kind, &x0, &settings, &mut shifted) {
        Ok(result) => result,
        Err(ellipsoid_packer::Error::NotReached(u)) => {
            return Err(not_reached(&mut problem, &u, scene.container));
        }
        Err(e) => return Err(e.into()),
    };
    let written = written_packing::<N>(
        &mut problem,
        &result.best.x,
        scene.container,
        fixed.is_none(),
    )?;
    let packing = written.packing;
    let mut summary = Summary::new(
        &packing,
        written.objective,
        (result.wall_time + prelude).as_secs_f64(),
        result.local_minimisations as u64,
        written.certificate,
    );
    // A fixed container is never repaired: its packings are certified as the solver left them.
    let repair_factor = result.best.repair_factor * written.dilation;
    summary.repair = fixed.is_none().then_some(crate::packing::Repair {
        dilation: repair_factor,
        density_before: result.best.density_before_repair,
    });
    summary.start_kept = result.start_kept;
    summary.fixed_container = fixed.is_some();
    summary.shard = options.shard.map(|shard| crate::packing::ShardOrigin {
        index: shard.index(),
        count: shard.count(),
        seed: settings.seed,
    });
    Ok(RunOutcome {
        packing,
        summary,
        density_before_repair: result.best.density_before_repair,
        repair_factor,
        seconds_to_best: (result.time_to_best + prelude).as_secs_f64(),
        interrupted: result.interrupted,
        failed_starts: result.failed_starts,
        restarts: result.restarts,
        start_density: result.start_density,
        start_kept: result.start_kept,
    })
}

/// The variables of a packing to resume from, checked against the scene: its fixed container
/// (`fixed`, the model's variables), its container kind, its items; and certified, since a
/// resumed run keeps its start as the packing to beat.
fn resumed_start<const N: usize>(
    problem: &mut Model<N>,
    packing: &Packing,
    scene: &Scene,
    fixed: Option<&[f64]>,
    axes: &[[f64; N]],
) -> Result<Vec<f64>, PackError> {
    let kind = problem.container_kind();
    if let Some(expected) = fixed {
        check_fixed_size(packing, expected, kind)?;
    }
    if packing.container().kind() != scene.container {
        return Err(PackError::Mismatch(format!(
            "the packing's container is {}, the scene's {}",
            packing.container().kind(),
            scene.container
        )));
    }
    let x0 = variables_of::<N>(packing, axes, kind)?;
    let certificate = problem
        .certify(&x0)
        .map_err(|e| named::<N>(e, axes.len(), kind))?;
    if !certificate.is_feasible() {
        return Err(PackError::StartNotCertified(start_defects(&certificate)));
    }
    Ok(x0)
}

/// Refuses a packing to resume from whose container is not the scene's fixed container
/// `expected` (its variables, to 1e-12 relative).
fn check_fixed_size(
    packing: &Packing,
    expected: &[f64],
    kind: ModelContainer,
) -> Result<(), PackError> {
    let found = model_dimensions(packing.container(), kind);
    let same = found.len() == expected.len()
        && found
            .iter()
            .zip(expected)
            .all(|(a, b)| (a - b).abs() <= 1e-12 * b.abs());
    if same {
        Ok(())
    } else {
        Err(PackError::FixedSizeMismatch {
            found,
            expected: expected.to_vec(),
        })
    }
}

/// The scene's solver settings, mapped once onto the packer's settings of one local
/// minimisation.
fn local_settings(scene: &Scene) -> LocalSettings {
    use ellipsoid_packer::local::InnerSolver;
    let mut local = LocalSettings::default();
    local.feasibility_tolerance = scene.solver.feasibility_tolerance;
    local.optimality_tolerance = scene.solver.optimality_tolerance;
    local.inner_solver = match scene.solver.inner_solver {
        crate::scene::InnerSolverName::Spg => InnerSolver::Spg,
        crate::scene::InnerSolverName::ProjectedLbfgs => InnerSolver::ProjectedLbfgs,
        crate::scene::InnerSolverName::TruncatedNewton => InnerSolver::TruncatedNewton,
    };
    local.method = match scene.solver.method {
        crate::scene::MethodName::Lagrangian => LocalMethod::AugmentedLagrangian,
        crate::scene::MethodName::Compression => LocalMethod::Compression,
        crate::scene::MethodName::CompressionLagrangian => LocalMethod::CompressionThenLagrangian,
    };
    local
}

/// The error of a fixed-container run that found no packing, with its least overlapping
/// configuration as the files hold it.
fn not_reached<const N: usize>(
    problem: &mut Model<N>,
    u: &ellipsoid_packer::fixed::Unfinished,
    kind: ContainerKind,
) -> PackError {
    let mut unfinished = || -> Result<PackError, PackError> {
        let packing = packing_of::<N>(problem, &u.x, kind)?;
        let objective = problem.evaluate(&u.x, None)?.objective;
        let mut summary = Summary::new(
            &packing,
            objective,
            u.wall_time.as_secs_f64(),
            u.local_minimisations as u64,
            certificate_of(&u.certificate),
        );
        summary.not_reached = true;
        summary.fixed_container = true;
        Ok(PackError::NotReached(Box::new(Unfinished {
            packing,
            summary,
            infeasibility: u.infeasibility,
            interrupted: u.interrupted,
        })))
    };
    unfinished().unwrap_or_else(|e| e)
}

/// A random packing of the scene's items ([`ellipsoid_packer::random`]): a random start, then
/// compression to the scene's packing fraction or until jammed, within the time limit. A
/// resumed jammed run compresses its packing further; a resumed run at a fraction is its
/// packing, checked. The observer hears of every packing the compression kept (the history:
/// one row per kept step, the written packing last), after the run.
fn run_random<const N: usize>(
    scene: &Scene,
    axes: &[[f64; N]],
    goal: RandomGoal,
    options: &RunOptions,
    observer: &mut dyn Observer,
) -> Result<RunOutcome, PackError> {
    let began = Instant::now();
    let kind = model_container(scene.container);
    let mut problem = Model::<N>::new(axes.to_vec(), kind)?;
    let (target, container) = match &goal {
        RandomGoal::Fraction(c) => (Target::Fraction, c),
        RandomGoal::Jammed(c) => (Target::Jammed, c),
    };
    let dims = model_dimensions(container, kind);
    let mut local = local_settings(scene);
    local.method = LocalMethod::Compression;
    local.fixed_orientations = scene.item_fixed_orientations();
    let seed = options.seed.unwrap_or(scene.seed);
    // One compression: the threads share its evaluations (0: every core).
    let threads = options.threads.unwrap_or(scene.solver.threads);
    let settings = RandomSettings::new(target, seed)
        .with_local(local.clone())
        .with_orientations(scene.item_orientations())
        .with_threads(threads);
    let time_limit = options.time_limit.unwrap_or(scene.solver.time_limit);
    let shared: &dyn Observer = &*observer;
    let mut observe = |p: &ellipsoid_packer::multistart::SolverProgress<'_>| {
        shared.iteration(p);
        shared.should_stop() || began.elapsed() >= time_limit
    };
    // The density of every packing the compression keeps, with its time: the run's history.
    let mut steps: Vec<(Duration, f64)> = Vec::new();
    let mut kept = |density: f64| steps.push((began.elapsed(), density));
    let made = match &options.resume_from {
        None => random_packing_seen(&mut problem, &dims, &settings, &mut observe, &mut kept),
        Some(packing) => {
            let fixed = (target == Target::Fraction).then_some(dims.as_slice());
            problem.set_threads(threads)?;
            let x0 = resumed_start(&mut problem, packing, scene, fixed, axes)?;
            let aim = (target == Target::Fraction)
                .then(|| problem.evaluate(&x0, None))
                .transpose()?;
            compression_seen(
                &mut problem,
                &x0,
                &local,
                aim.map(|e| e.objective),
                &mut observe,
                &mut |p| kept(p.density),
            )
            .map(|packing| RandomPacking {
                start_density: packing.density,
                packing,
            })
        }
    };
    let made = match made {
        Ok(made) => made,
        Err(ellipsoid_packer::Error::NotReached(u)) => {
            return Err(not_reached(&mut problem, &u, scene.container));
        }
        Err(e) => return Err(e.into()),
    };
    let interrupted = observer.should_stop();
    let elapsed = began.elapsed();
    steps.push((elapsed, made.packing.density));
    let mut best = 0.0_f64;
    for (k, &(at, density)) in steps.iter().enumerate() {
        best = best.max(density);
        observer.finished(&MultiStartProgress {
            local_minimisations: k + 1,
            best_density: best,
            last_density: density,
            elapsed: at,
        });
    }
    let jammed = target == Target::Jammed;
    let written = written_packing::<N>(&mut problem, &made.packing.x, scene.container, jammed)?;
    let packing = written.packing;
    let mut summary = Summary::new(
        &packing,
        written.objective,
        elapsed.as_secs_f64(),
        1,
        written.certificate,
    );
    let repair_factor = made.packing.repair_factor * written.dilation;
    summary.repair = jammed.then_some(crate::packing::Repair {
        dilation: repair_factor,
        density_before: made.packing.density_before_repair,
    });
    summary.start_kept = false;
    summary.fixed_container = !jammed;
    Ok(RunOutcome {
        packing,
        summary,
        density_before_repair: made.packing.density_before_repair,
        repair_factor,
        seconds_to_best: elapsed.as_secs_f64(),
        interrupted,
        failed_starts: 0,
        restarts: 0,
        start_density: Some(made.start_density),
        start_kept: false,
    })
}

/// An observer whose progress times start earlier, at the run's start, by `by` (the time
/// spent before the multi-start: the small cells of a periodic run).
struct Shifted<'a> {
    inner: &'a mut dyn Observer,
    by: Duration,
}

impl Observer for Shifted<'_> {
    fn finished(&mut self, progress: &MultiStartProgress) {
        let mut progress = *progress;
        progress.elapsed += self.by;
        self.inner.finished(&progress);
    }
    fn iteration(&self, progress: &ellipsoid_packer::multistart::SolverProgress<'_>) {
        self.inner.iteration(progress);
    }
    fn should_stop(&self) -> bool {
        self.inner.should_stop()
    }
}

/// A packing as the files hold it, with its own certificate.
struct Written {
    packing: Packing,
    objective: f64,
    certificate: CertificateCounts,
    /// The dilation applied to make the written form certified (1: none).
    dilation: f64,
}

/// The packing of the certified variables `x` as the files hold it (quaternions, a reduced
/// periodic cell, items wrapped into it, 17 significant digits), certified again in that form:
/// the conversion moves values by a few ulps, which can put a pair at exact tangency (an item
/// touching its own image in a periodic cell, say) an ulp inside. When `may_dilate`, such a
/// packing is dilated by the least of 1 + 1e-12, 1e-11, … that certifies its written form.
fn written_packing<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
    kind: ContainerKind,
    may_dilate: bool,
) -> Result<Written, PackError> {
    let mut dilation = 1.0;
    let mut step = 0;
    loop {
        let y = problem.dilated(x, dilation);
        let packing = packing_of::<N>(problem, &y, kind)?;
        let certificate = verify(&packing)?;
        if certificate.is_certified() || !may_dilate || step == 6 {
            return Ok(Written {
                objective: problem.evaluate(&y, None)?.objective,
                packing,
                certificate,
                dilation,
            });
        }
        dilation = 1.0 + 1e-12 * 10f64.powi(step);
        step += 1;
    }
}

/// The overlapping pairs (with μ²) and the items outside (with the container growth that
/// would hold each) of an uncertified point, from its certificate.
fn start_defects(certificate: &implicit_packing::model::Certificate) -> StartDefects {
    StartDefects {
        overlapping: certificate
            .overlapping
            .iter()
            .map(|o| (o.items.0, o.items.1, o.mu2))
            .collect(),
        outside: certificate
            .outside
            .iter()
            .map(|o| (o.item, o.scale))
            .collect(),
    }
}

/// Re-checks a packing from its files, independently of how it was made: PW85 verdicts on every
/// pair whose enclosing balls meet and exact containment (the model's certificate), and the
/// smallest μ² over those pairs.
///
/// # Errors
/// [`PackError`] when the items do not form a valid model (a zero semi-axis, NaN).
pub fn verify(packing: &Packing) -> Result<CertificateCounts, PackError> {
    verify_detailed(packing).map(|v| v.certificate)
}

/// Two items whose interiors overlap: `items` are their 0-based positions in the packing (rows
/// of `packing.csv`), the smaller first, and `mu2` their PW85 μ² (< 1).
pub type OverlappingPair = implicit_packing::certificate::Overlap;

/// An item that is not inside the container: `item` is its 0-based position in the packing (its
/// row of `packing.csv`), and `scale` by how much it sticks out, as a scale factor t > 1: the
/// item lies inside the container scaled by t about the container's centre, and in no smaller
/// scaling. For a ball of radius r, t·r is the largest distance of a point of the item from the
/// centre; for a box, the worst of (|cₖ| + sₖ) / Lₖ over the axes (cₖ the item's centre relative
/// to the container's, sₖ its half extent along axis k, Lₖ the half side).
pub type ItemOutside = implicit_packing::certificate::Outside;

/// [`verify`]'s certificate with the offenders it counts.
#[derive(Clone, Debug, PartialEq)]
pub struct Verification {
    /// The certificate (counts and smallest μ²), as [`verify`] returns it.
    pub certificate: CertificateCounts,
    /// Every overlapping pair, the smallest μ² (the deepest overlap) first.
    pub overlapping_pairs: Vec<OverlappingPair>,
    /// Every item outside the container, the largest scale first.
    pub outside: Vec<ItemOutside>,
}

/// [`verify`], naming the overlapping pairs with their μ² and the items outside with by how
/// much they stick out.
///
/// # Errors
/// As [`verify`].
pub fn verify_detailed(packing: &Packing) -> Result<Verification, PackError> {
    match &packing.items() {
        Items::Ellipses(v) => {
            let axes: Vec<[f64; 2]> = v.iter().map(|e| e.semi_axes).collect();
            verify_n::<2>(packing, &axes)
        }
        Items::Ellipsoids(v) => {
            let axes: Vec<[f64; 3]> = v.iter().map(|e| e.semi_axes).collect();
            verify_n::<3>(packing, &axes)
        }
    }
}

fn verify_n<const N: usize>(
    packing: &Packing,
    axes: &[[f64; N]],
) -> Result<Verification, PackError> {
    let kind = model_container(packing.container().kind());
    let mut problem = Model::<N>::new(axes.to_vec(), kind)?;
    let x = variables_of::<N>(packing, axes, kind)?;
    let model = problem
        .certify(&x)
        .map_err(|e| named::<N>(e, axes.len(), kind))?;
    let certificate = certificate_of(&model);
    let mut overlapping_pairs = model.overlapping;
    // Deepest first; the stable sort keeps the certificate's (i, j) order among equals.
    overlapping_pairs.sort_by(|a, b| a.mu2.total_cmp(&b.mu2));
    let mut outside = model.outside;
    outside.sort_by(|a, b| b.scale.total_cmp(&a.scale));
    Ok(Verification {
        certificate,
        overlapping_pairs,
        outside,
    })
}

/// A model error about "variable k" named as the packing states it: item i's centre
/// coordinate (or, in a periodic cell, its fractional coordinate along a cell edge), or its
/// orientation, or the container's value. Other errors pass unchanged.
fn named<const N: usize>(
    e: implicit_packing::Error,
    items: usize,
    kind: ModelContainer,
) -> PackError {
    use implicit_packing::Error as E;
    let stride = Model::<N>::vars_per_body();
    let periodic = kind == ModelContainer::Periodic;
    let what = |index: usize| {
        let axis = ["x", "y", "z"];
        let edge = ["a", "b", "c"];
        if index >= items * stride {
            format!("the container's value {}", index - items * stride + 1)
        } else {
            let (item, k) = (index / stride, index % stride);
            match k {
                k if k < N && periodic => {
                    format!(
                        "item {item}'s fractional coordinate along the cell edge {}",
                        edge[k]
                    )
                }
                k if k < N => format!("item {item}'s centre coordinate {}", axis[k]),
                _ => format!("item {item}'s orientation"),
            }
        }
    };
    match e {
        E::NonFiniteVariable { index, value } => PackError::OutOfRange {
            what: what(index),
            value: format!("{value:e}"),
            rule: "coordinates must be finite and within ±1e30 (rescale the packing, or check \
                   the container's size and tilts)",
        },
        E::FractionalOutOfRange { index, value } => PackError::OutOfRange {
            what: what(index),
            value: format!("{value:e}"),
            rule: "items of a periodic cell must lie within 2^30 cells of it (wrap them into \
                   the cell)",
        },
        other => PackError::Model(other),
    }
}

/// The bodies and the container of a packing, as the model and the certificate see them.
///
/// # Errors
/// [`PackError`] when the items do not form valid bodies (a zero semi-axis, NaN).
pub fn bodies_of<const N: usize>(
    packing: &Packing,
) -> Result<(Vec<Body<N>>, SizedContainer<N>), PackError> {
    let axes: Vec<[f64; N]> = match packing.items() {
        Items::Ellipses(v) => v
            .iter()
            .map(|e| std::array::from_fn(|k| e.semi_axes.get(k).copied().unwrap_or(f64::NAN)))
            .collect(),
        Items::Ellipsoids(v) => v
            .iter()
            .map(|e| std::array::from_fn(|k| e.semi_axes.get(k).copied().unwrap_or(f64::NAN)))
            .collect(),
    };
    let kind = model_container(packing.container().kind());
    let mut problem = Model::<N>::new(axes.clone(), kind)?;
    let x = variables_of::<N>(packing, &axes, kind)?;
    let container = problem.container_at(&x)?;
    Ok((problem.bodies_at(&x)?.to_vec(), container))
}

/// The summary's certificate: the counts and the smallest μ² of the one certificate.
fn certificate_of(model: &implicit_packing::model::Certificate) -> CertificateCounts {
    CertificateCounts {
        overlapping_pairs: model.overlapping.len() as u64,
        containment_violations: model.outside.len() as u64,
        min_mu2: model.min_mu2,
    }
}

/// The model's container for a container kind of the files.
pub fn model_container(kind: ContainerKind) -> ModelContainer {
    match kind {
        ContainerKind::Circle | ContainerKind::Ball => ModelContainer::Ball,
        ContainerKind::Ellipse | ContainerKind::Ellipsoid => ModelContainer::Ellipsoid,
        ContainerKind::Rectangle | ContainerKind::Cuboid => ModelContainer::Box,
        ContainerKind::Parallelogram | ContainerKind::Parallelepiped => ModelContainer::Periodic,
    }
}

/// A periodic cell's item centre `c` moved by a lattice translation into the cell (fractional
/// coordinates in `[0, 1)`), where the files show it.
fn wrapped<const N: usize>(cell: &[[f64; N]; N], c: [f64; N]) -> [f64; N] {
    use implicit_packing::periodic::{to_cartesian, to_fractional};
    let s = to_fractional(cell, &c);
    to_cartesian(cell, &s.map(|v| v - v.floor()))
}

/// The packing of the model's variables `x`.
fn packing_of<const N: usize>(
    problem: &mut Model<N>,
    x: &[f64],
    kind: ContainerKind,
) -> Result<Packing, PackError> {
    // A periodic cell is written with its tilts reduced: the same lattice in the cell LAMMPS
    // accepts.
    let shape = match problem.container_at(x)? {
        SizedContainer::Periodic { cell } => SizedContainer::Periodic {
            cell: implicit_packing::periodic::reduced(&cell),
        },
        other => other,
    };
    let bodies = problem.bodies_at(x)?;
    let centre = |b: &implicit_packing::Body<N>| match shape {
        SizedContainer::Periodic { cell } => wrapped(&cell, b.centre()),
        _ => b.centre(),
    };
    let items = if N == 2 {
        Items::Ellipses(
            bodies
                .iter()
                .map(|b| {
                    let (c, l, r) = (centre(b), b.semi_axes(), b.rotation());
                    EllipseItem {
                        center: [c[0], c[1]],
                        semi_axes: [l[0], l[1]],
                        theta: r[1][0].atan2(r[0][0]),
                    }
                })
                .collect(),
        )
    } else {
        Items::Ellipsoids(
            bodies
                .iter()
                .map(|b| {
                    let (c, l) = (centre(b), b.semi_axes());
                    let r = b.rotation();
                    let rot3 = [
                        [r[0][0], r[0][1], r[0][2]],
                        [r[1][0], r[1][1], r[1][2]],
                        [r[2][0], r[2][1], r[2][2]],
                    ];
                    EllipsoidItem {
                        center: [c[0], c[1], c[2]],
                        semi_axes: [l[0], l[1], l[2]],
                        quaternion: implicit_packing::shape::quaternion_from_rotation(&rot3),
                    }
                })
                .collect(),
        )
    };
    let dims: Vec<f64> = match shape {
        SizedContainer::Ball { radius } => vec![radius; N],
        SizedContainer::Ellipsoid { semi_axes } => semi_axes.to_vec(),
        SizedContainer::Box { half_sides } => half_sides.to_vec(),
        SizedContainer::Periodic { .. } => shape.dimensions(),
    };
    let container = Container::unchecked(kind, &[0.0; N], &dims);
    Ok(Packing::new(container, items)?)
}

/// The model's container variables of a container: the radius of a ball, else its semi-axes
/// or half sides.
fn model_dimensions(container: &Container, kind: ModelContainer) -> Vec<f64> {
    let size = container.size();
    match kind {
        ModelContainer::Ball => vec![size.first().copied().unwrap_or(0.0)],
        _ => size,
    }
}

/// The model's variables of a packing (centres relative to the container's centre), checking
/// that its items have the semi-axes `axes`, in order.
fn variables_of<const N: usize>(
    packing: &Packing,
    axes: &[[f64; N]],
    kind: ModelContainer,
) -> Result<Vec<f64>, PackError> {
    if packing.items().len() != axes.len() {
        return Err(PackError::Mismatch(format!(
            "the packing has {} items, the scene {}",
            packing.items().len(),
            axes.len()
        )));
    }
    let centre = packing.container().center().to_vec();
    let same = |a: &[f64], b: &[f64]| {
        a.iter()
            .zip(b)
            .all(|(p, q)| (p - q).abs() <= 1e-12 * q.abs())
    };
    let mismatch = |i: usize, found: &[f64]| {
        PackError::Mismatch(format!(
            "item {i} has semi-axes {found:?} in the packing, {:?} in the scene",
            axes[i]
        ))
    };
    let dims = model_dimensions(packing.container(), kind);
    // The bodies relative to the container's centre, with the scene's semi-axes (equal to the
    // packing's within 1e-12, checked here), so that the model takes them as its own.
    let axis = |i: usize, k: usize| axes[i].get(k).copied().unwrap_or(f64::NAN);
    match &packing.items() {
        Items::Ellipses(v) if N == 2 => {
            let mut bodies = Vec::with_capacity(v.len());
            for (i, e) in v.iter().enumerate() {
                if !same(&e.semi_axes, &axes[i]) {
                    return Err(mismatch(i, &e.semi_axes));
                }
                let l = [axis(i, 0), axis(i, 1)];
                let c = [e.center[0] - centre[0], e.center[1] - centre[1]];
                bodies.push(Body::ellipse(c, l, e.theta)?);
            }
            let axes: Vec<[f64; 2]> = bodies.iter().map(Body::semi_axes).collect();
            Ok(Model::<2>::new(axes, kind)?.pack_variables(&bodies, &dims)?)
        }
        Items::Ellipsoids(v) if N == 3 => {
            let mut bodies = Vec::with_capacity(v.len());
            for (i, e) in v.iter().enumerate() {
                if !same(&e.semi_axes, &axes[i]) {
                    return Err(mismatch(i, &e.semi_axes));
                }
                let l = [axis(i, 0), axis(i, 1), axis(i, 2)];
                let c = [
                    e.center[0] - centre[0],
                    e.center[1] - centre[1],
                    e.center[2] - centre[2],
                ];
                bodies.push(Body::from_quaternion(c, l, e.quaternion)?);
            }
            let axes: Vec<[f64; 3]> = bodies.iter().map(Body::semi_axes).collect();
            Ok(Model::<3>::new(axes, kind)?.pack_variables(&bodies, &dims)?)
        }
        _ => Err(PackError::Mismatch(
            "the packing has the other dimension".into(),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_history_has_its_header_and_a_row_per_local_minimisation() {
        let mut history = History::new();
        history.record(&MultiStartProgress {
            local_minimisations: 1,
            best_density: 0.5,
            last_density: 0.25,
            elapsed: Duration::from_millis(1500),
        });
        history.record(&MultiStartProgress {
            local_minimisations: 2,
            best_density: 0.625,
            last_density: 0.625,
            elapsed: Duration::from_secs(3),
        });
        assert_eq!(
            history.into_text(),
            "local_minimisation,seconds,density,best_density\n\
             1,1.500,0.250000000,0.500000000\n\
             2,3.000,0.625000000,0.625000000\n"
        );
    }

    #[test]
    fn a_small_scene_packs_certified_and_verify_agrees() {
        let scene = Scene::from_toml_str(
            "dimension = 2\nseed = 3\n[container]\nkind = \"circle\"\n[[shapes]]\ncount = 5\n\
             semi_axes = [1.5, 1.0]\n[solver]\ntime_limit = 600.0\nlocal_minimisations = 2\n\
             threads = 1\n",
            "t.toml",
        )
        .unwrap();
        let out = run(&scene, &RunOptions::default(), &mut ()).unwrap();
        assert!(out.summary.certificate.is_certified());
        assert!(out.summary.certificate.min_mu2.is_some_and(|m| m >= 1.0));
        assert_eq!(out.summary.local_minimisations, 2);
        let again = verify(&out.packing).unwrap();
        assert!(again.is_certified(), "{again:?}");
        // Resuming from the packing reproduces it as the start.
        let resumed = RunOptions {
            resume_from: Some(out.packing.clone()),
            ..RunOptions::default()
        };
        let out2 = run(&scene, &resumed, &mut ()).unwrap();
        assert!(out2.summary.density >= out.summary.density * (1.0 - 1e-6));
    }

    #[test]
    fn verify_rejects_an_overlapping_pair_and_an_item_outside() {
        let unit_disc_at = |x| EllipseItem {
            center: [x, 0.0],
            semi_axes: [1.0, 1.0],
            theta: 0.0,
        };
        let items = Items::Ellipses(vec![unit_disc_at(0.0), unit_disc_at(1.5)]);
        let packing = Packing::new(
            Container::Circle {
                center: [0.0, 0.0],
                radius: 2.4,
            },
            items,
        )
        .unwrap();
        let c = verify(&packing).unwrap();
        assert_eq!(c.overlapping_pairs, 1);
        assert_eq!(
            c.containment_violations, 1,
            "the second item reaches 2.5 > 2.4"
        );
        assert!(c.min_mu2.is_some_and(|m| m < 1.0));
        let v = verify_detailed(&packing).unwrap();
        assert_eq!(v.certificate, c);
        assert_eq!(v.overlapping_pairs.len(), 1);
        assert_eq!(v.overlapping_pairs[0].items, (0, 1));
        let mu2 = v.overlapping_pairs[0].mu2;
        assert!((mu2 - 0.5625).abs() <= 1e-13, "{mu2}");
        assert_eq!(v.outside.len(), 1);
        assert_eq!(v.outside[0].item, 1);
        assert!((v.outside[0].scale - 2.5 / 2.4).abs() <= 1e-13);
    }

    #[test]
    fn the_scale_of_an_item_outside_is_where_it_would_just_fit() {
        // An ellipse (2, 1) turned by 90° at (0, 3); the containers are centred at (1, 1), so
        // relative to their centre the item's boundary is (−1 − sin s, 2 + 2 cos s). The scale
        // is the largest value of the container's gauge on that boundary (sampled densely).
        let item = EllipseItem {
            center: [0.0, 3.0],
            semi_axes: [2.0, 1.0],
            theta: std::f64::consts::FRAC_PI_2,
        };
        let gauge_max = |gauge: &dyn Fn(f64, f64) -> f64| {
            (0..400_000)
                .map(|k| {
                    let s = k as f64 / 400_000.0 * std::f64::consts::TAU;
                    gauge(-1.0 - s.sin(), 2.0 + 2.0 * s.cos())
                })
                .fold(0.0, f64::max)
        };
        let cases: [(Container, f64); 3] = [
            (
                Container::Ellipse {
                    center: [1.0, 1.0],
                    semi_axes: [4.0, 2.0],
                },
                gauge_max(&|x, y| (x / 4.0).hypot(y / 2.0)),
            ),
            (
                Container::Rectangle {
                    center: [1.0, 1.0],
                    half_sides: [4.0, 2.0],
                },
                // max(2 / 4, 4 / 2): the top of the item, 4 above the centre.
                2.0,
            ),
            (
                Container::Circle {
                    center: [1.0, 1.0],
                    radius: 2.0,
                },
                gauge_max(&|x, y| x.hypot(y) / 2.0),
            ),
        ];
        for (container, expected) in cases {
            let packing = Packing::new(container, Items::Ellipses(vec![item])).unwrap();
            let v = verify_detailed(&packing).unwrap();
            assert_eq!(v.outside.len(), 1, "{packing:?}");
            let scale = v.outside[0].scale;
            assert!(
                (scale - expected).abs() <= 1e-9 * expected,
                "{:?}: {scale} vs {expected}",
                packing.container().kind()
            );
        }
    }
}
