//! Multi-start: repeated local minimisations from perturbations of the most recent feasible
//! solution, run in parallel rounds, keeping the best certified packing (paper Section 6.1.1 and
//! 6.2).
//!
//! Each round runs one start per thread. Start 0 is the given point. The next
//! [`MultiStartSettings::lattice_starts`] starts are dense lattice starts (hexagonal and
//! face-centred cubic lattices in several orientations, shifts and container aspects): first
//! the 16 tightest cuts of the lattice ([`tightest_lattice_starts`]), then
//! [`LatticeStart::sequence`]; on each, every item is turned by up to 0.01 rad to break the
//! lattice's symmetry ([`turned`]). They reach structures that perturbations of one solution
//! rarely find. Every later start `k` perturbs the current solution with its own
//! generator seeded by `(seed, k)`: centres move by up to `fraction × container extent` per
//! coordinate, angles by up to `fraction × π` (the paper: 2.5 % in 2D, 10 % in 3D). The current
//! solution is the best packing so far ([`MultiStartSettings::from_best`], a monotonic basin
//! hopping) or, as in the paper, the best packing of the latest round (every result is
//! feasible after the repair). Rounds are deterministic, so the same seed and thread count
//! give the same packings, whatever the timing; only how many rounds fit in a time limit
//! depends on the machine.
//!
//! A run can be one *shard* of a multi-start spread over machines
//! ([`MultiStartSettings::shard`]): shard k of n takes the dense lattice starts numbered
//! k, n + k, 2n + k, … of the sequence and the perturbation streams `index · n + k`, so the
//! shards of one seed never repeat each other's starts, and each reproduces exactly. Shard 0
//! minimises from the given point, as an unsharded run; shard k > 0 first from that point
//! perturbed with stream k (so that the shards do not all begin with the same local
//! minimisation).
//!
//! A walk from the best packing settles in one structure: on 100 ellipses in a rectangle (two
//! threads) it found its best, 0.87435, after 566 starts and nothing better in the next 17
//! minutes. With [`MultiStartSettings::restart_after`] the walk is cut into *chains*: once
//! that many starts in a row have not improved the current chain's best packing (by more
//! than 1e-5 relative), a round of fresh dense lattice starts begins a new chain, which
//! perturbs its own best; the run keeps the best packing of all chains (iterated local
//! search with restarts). A chain adapts its perturbations: they move twice as far once it
//! has gone [`MultiStartSettings::widen_after`] starts without a gain, and half as far after
//! each round in which a perturbed start failed dearly (down to a quarter).
//!
//! # References
//! - E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//!   variables for packing ellipsoids*, J. Global Optim. 68 (2017), Section 6.

use crate::Error;
use crate::local::{LocalResult, LocalSettings, certified_start, local_minimisation};
use crate::starts::{LatticeStart, lattice_start_of, perturb, tightest_lattice_starts, turned};
use implicit_packing::containment::ContainerShape;
use implicit_packing::model::Model;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Settings of a multi-start run.
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct MultiStartSettings {
    /// Settings of each local minimisation.
    pub local: LocalSettings,
    /// Largest perturbation, as a fraction (0.025 in 2D and 0.1 in 3D in the paper).
    pub perturbation: f64,
    /// Seed of the perturbations.
    pub seed: u64,
    /// Dense lattice starts run after the given start and before any perturbation (0: none,
    /// as in the paper).
    pub lattice_starts: usize,
    /// Perturb the best packing so far (`true`) or, as the paper, the best packing of the
    /// latest round (`false`). With `true`, each round in which a perturbed start fails (no
    /// repair certifies its point) after more than 4 times the evaluations of the median
    /// perturbed start that succeeded halves the chain's perturbations from then on.
    pub from_best: bool,
    /// Amplitude levels of the perturbations: start `j` of the perturbation phase moves by up
    /// to `perturbation / 2^(j mod levels)` (1: always the full amplitude, as the paper), times
    /// the chain's factor (twice after `widen_after` starts without a gain, halved after a
    /// failed perturbation with `from_best`).
    pub perturbation_levels: u32,
    /// Every this many starts of the perturbation phase, one is a further dense lattice start
    /// instead, continuing the sequence (0: never).
    pub fresh_lattice_every: usize,
    /// With `from_best`: after this many starts in a row that did not improve the current
    /// chain's best packing by more than 1e-5 relative, the next round is one of fresh dense
    /// lattice starts and its best result begins a new chain (0: one chain, never restart).
    pub restart_after: usize,
    /// With `from_best`: once this many starts in a row have not improved the current chain's
    /// best packing (counted as for `restart_after`), its perturbations move twice as far,
    /// until the chain gains or a new one begins (0: never).
    pub widen_after: usize,
    /// Starts per round, run in parallel (one thread each).
    pub threads: usize,
    /// Stop after this many local minimisations (the first, from the given start, included).
    pub max_local_minimisations: usize,
    /// Stop once this much time has passed (checked between rounds, and inside each local
    /// minimisation through its interrupt).
    pub time_limit: Option<Duration>,
    /// Which part of a multi-start spread over several runs this run is (the whole by default).
    pub shard: Shard,
}

/// Shard `index` of `count`: one of `count` runs of the same multi-start whose start streams
/// are disjoint (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    index: usize,
    count: usize,
}

impl Shard {
    /// The whole multi-start: shard 0 of 1.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Shard `index` (from 0) of `count`.
    ///
    /// # Errors
    /// [`Error::Shard`] unless `index < count`.
    pub fn new(index: usize, count: usize) -> Result<Self, Error> {
        if index >= count {
            return Err(Error::Shard { index, count });
        }
        Ok(Self { index, count })
    }

    /// This shard's number, from 0.
    pub fn index(self) -> usize {
        self.index
    }

    /// How many shards the multi-start has.
    pub fn count(self) -> usize {
        self.count
    }

    /// The number in the whole multi-start's sequence of this shard's `n`-th item (a lattice
    /// start or a perturbation stream): `n · count + index`.
    fn global(self, n: usize) -> usize {
        n.saturating_mul(self.count).saturating_add(self.index)
    }
}

impl Default for Shard {
    fn default() -> Self {
        Self::WHOLE
    }
}

/// Starts without improvement after which a run begins a new chain, by default.
pub const RESTART_AFTER: usize = 300;
/// Starts without improvement after which a chain's perturbations move twice as far, by
/// default.
pub const WIDEN_AFTER: usize = 32;
/// Dense lattice starts of a run by default: four rounds of every lattice orientation in 3D,
/// eight in 2D.
pub const LATTICE_STARTS: usize = 16;
/// The wall-clock limit of a run by default.
pub const TIME_LIMIT: Duration = Duration::from_secs(60);

impl MultiStartSettings {
    /// A run's defaults for dimension `n`, the command's: the paper's perturbations of the best
    /// packing so far at three amplitudes, after [`LATTICE_STARTS`] dense lattice starts and
    /// with one every 8 starts, new chains after [`RESTART_AFTER`] starts without improvement,
    /// every core, until [`TIME_LIMIT`].
    pub fn recommended(n: usize, seed: u64) -> Self {
        Self {
            lattice_starts: LATTICE_STARTS,
            from_best: true,
            perturbation_levels: 3,
            fresh_lattice_every: 8,
            restart_after: RESTART_AFTER,
            widen_after: WIDEN_AFTER,
            threads: 0,
            max_local_minimisations: usize::MAX,
            time_limit: Some(TIME_LIMIT),
            ..Self::paper(n, seed)
        }
    }

    /// The paper's method for dimension `n`: its perturbation of the latest solution, no
    /// lattice starts, one thread, 100 local minimisations.
    pub fn paper(n: usize, seed: u64) -> Self {
        Self {
            local: LocalSettings::default(),
            perturbation: if n == 2 { 0.025 } else { 0.1 },
            seed,
            lattice_starts: 0,
            from_best: false,
            perturbation_levels: 1,
            fresh_lattice_every: 0,
            restart_after: 0,
            widen_after: 0,
            threads: 1,
            max_local_minimisations: 100,
            time_limit: None,
            shard: Shard::WHOLE,
        }
    }
}

auglag::with_setters!(MultiStartSettings:
    with_local => local: LocalSettings,
    with_perturbation => perturbation: f64,
    with_seed => seed: u64,
    with_lattice_starts => lattice_starts: usize,
    with_from_best => from_best: bool,
    with_perturbation_levels => perturbation_levels: u32,
    with_fresh_lattice_every => fresh_lattice_every: usize,
    with_restart_after => restart_after: usize,
    with_widen_after => widen_after: usize,
    with_threads => threads: usize,
    with_max_local_minimisations => max_local_minimisations: usize,
    with_time_limit => time_limit: Option<Duration>,
    with_shard => shard: Shard,
);

/// What a run reports at every finished local minimisation.
#[derive(Clone, Copy, Debug)]
pub struct MultiStartProgress {
    /// Local minimisations finished.
    pub local_minimisations: usize,
    /// Density of the best certified packing so far.
    pub best_density: f64,
    /// Density of the local minimisation just finished.
    pub last_density: f64,
    /// Time since the start of the run.
    pub elapsed: Duration,
}

/// The outcome of a multi-start run.
#[derive(Clone, Debug)]
pub struct MultiStartResult {
    /// The best certified packing.
    pub best: LocalResult,
    /// Local minimisations completed (a start cut off by the time limit or an interrupt is
    /// not counted, except the first; 0 when the run stopped before the first began or the
    /// first ended at a point that could not be certified).
    pub local_minimisations: usize,
    /// Starts abandoned because their local minimisation ended at a point that could not be
    /// certified (an item so far outside the container that no repair by a factor up to 4
    /// holds it).
    pub failed_starts: usize,
    /// Chains begun after the first ([`MultiStartSettings::restart_after`]).
    pub restarts: usize,
    /// When the best packing was found, from the start of the run.
    pub time_to_best: Duration,
    /// Wall time of the run.
    pub wall_time: Duration,
    /// Whether the run stopped because `interrupt` asked it to.
    pub interrupted: bool,
    /// Density of the start, when it is a certified packing as it is.
    pub start_density: Option<f64>,
    /// Whether the best packing is the start itself: no local minimisation found a denser
    /// certified packing.
    pub start_kept: bool,
}

/// What a run tells its caller, and how the caller stops it. Every method has a default (tell
/// nothing, never stop), so an observer implements only what it needs; `()` is the observer
/// that does nothing, and [`Callbacks`] makes one of three closures.
pub trait Observer: Sync {
    /// After every finished local minimisation, on the calling thread.
    fn finished(&mut self, _progress: &MultiStartProgress) {}
    /// At every iteration of the solver inside a local minimisation, on any thread of the run.
    fn iteration(&self, _progress: &SolverProgress<'_>) {}
    /// Whether to stop now: asked at every iteration and between local minimisations, on any
    /// thread. The run then returns its best certified packing.
    fn should_stop(&self) -> bool {
        false
    }
}

impl Observer for () {}

/// An [`Observer`] made of three closures.
pub struct Callbacks<F, I, S> {
    /// [`Observer::finished`].
    pub finished: F,
    /// [`Observer::iteration`].
    pub iteration: I,
    /// [`Observer::should_stop`].
    pub should_stop: S,
}

/// The solver's report at each iteration (see [`Observer::iteration`]).
pub use auglag::Progress as SolverProgress;

/// What a [`SolverProgress`] reports: an outer iteration of the augmented Lagrangian (with its
/// objective and infeasibility) or an inner one.
pub use auglag::Event as SolverEvent;

/// The solver's report of a local minimisation: its iterations, evaluations and why it stopped.
pub use auglag::Report as SolverReport;

impl<F> Callbacks<F, fn(&SolverProgress<'_>), fn() -> bool>
where
    F: FnMut(&MultiStartProgress) + Sync,
{
    /// An observer that hears only of finished local minimisations and never stops the run.
    pub fn on_finished(finished: F) -> Self {
        Callbacks {
            finished,
            iteration: |_| {},
            should_stop: || false,
        }
    }
}

impl<F, I, S> Observer for Callbacks<F, I, S>
where
    F: FnMut(&MultiStartProgress) + Sync,
    I: Fn(&SolverProgress<'_>) + Sync,
    S: Fn() -> bool + Sync,
{
    fn finished(&mut self, progress: &MultiStartProgress) {
        (self.finished)(progress);
    }
    fn iteration(&self, progress: &SolverProgress<'_>) {
        (self.iteration)(progress);
    }
    fn should_stop(&self) -> bool {
        (self.should_stop)()
    }
}

/// Runs the multi-start from `x0` (for example [`lattice_start`](crate::starts::lattice_start), or a packing read back to
/// resume a run). When `x0` is itself a certified packing it is the first best packing
/// ([`certified_start`]): the result is never less dense than the start, and a run stopped
/// at any moment has a certified packing to return. `progress` sees every finished local minimisation, in start order;
/// `observe` sees the solver's progress inside every local minimisation, from whichever thread
/// runs it; `interrupt` is polled often and stops the run, keeping the best packing found.
///
/// A container of given size is filled by [`crate::fixed::fill`] instead.
///
/// # Errors
/// Errors of the model or of the first local minimisation (a wrong-length `x0`, non-finite
/// values).
pub fn multistart<const N: usize>(
    semi_axes: &[[f64; N]],
    kind: ContainerShape,
    x0: &[f64],
    settings: &MultiStartSettings,
    observer: &mut dyn Observer,
) -> Result<MultiStartResult, Error> {
    let start = Instant::now();
    let out_of_time = || settings.time_limit.is_some_and(|t| start.elapsed() >= t);
    let mut problem = Model::<N>::new(semi_axes.to_vec(), kind)?;
    // A certified start is the first best packing: whatever happens to the first local
    // minimisation (cut off by the time limit at a point no repair certifies, or ending worse
    // than a packing it resumes from), the run has a certified packing at every moment.
    let start_result = certified_start(&mut problem, x0)?.ok();
    let start_density = start_result.as_ref().map(|r| r.density);
    let start_ready = start.elapsed();
    let mut failed_starts = 0;
    let mut done = 0;
    let shard = settings.shard;
    let perturbed;
    let first_start: &[f64] = if shard.index == 0 {
        x0
    } else {
        let stream = shard.global(0) as u64;
        perturbed = perturb::<N>(
            x0,
            problem.layout(),
            settings.perturbation,
            settings.seed,
            stream,
        );
        &perturbed
    };
    let first = if observer.should_stop() || out_of_time() {
        None
    } else {
        let result = local_minimisation(&mut problem, first_start, &settings.local, &mut |p| {
            observer.iteration(p);
            observer.should_stop() || out_of_time()
        });
        match result {
            Ok(r) => Some(r),
            Err(e) if start_result.is_none() => return Err(e),
            Err(_) => {
                failed_starts += 1;
                None
            }
        }
    };
    let mut time_to_best = start.elapsed();
    let first = match (first, start_result) {
        (Some(first), Some(given)) => {
            done = 1;
            let best_density = first.density.max(given.density);
            observer.finished(&MultiStartProgress {
                local_minimisations: done,
                best_density,
                last_density: first.density,
                elapsed: time_to_best,
            });
            if first.density > given.density {
                first
            } else {
                time_to_best = start_ready;
                given
            }
        }
        (Some(first), None) => {
            done = 1;
            observer.finished(&MultiStartProgress {
                local_minimisations: done,
                best_density: first.density,
                last_density: first.density,
                elapsed: time_to_best,
            });
            first
        }
        (None, Some(given)) => {
            time_to_best = start_ready;
            given
        }
        (None, None) => {
            // Only reachable when the start is not certified and the run was stopped before
            // its first local minimisation: nothing certified exists to return.
            return Err(Error::StoppedBeforeStart);
        }
    };
    let tightest = if uses_lattice_starts(settings) {
        tightest_lattice_starts(&problem, TIGHTEST_CUTS.max(settings.lattice_starts))
    } else {
        Vec::new()
    };
    let mut current = first.x.clone();
    // Starts cut off by the time limit or an interrupt; they still advance the start index.
    let mut cut_off = 0;
    let mut chain = Chain::new(&first);
    let mut best = first;
    let threads = settings.threads.max(1);
    while done < settings.max_local_minimisations && !(observer.should_stop() || out_of_time()) {
        let round = threads.min(settings.max_local_minimisations - done);
        let started = (done + failed_starts + cut_off).max(1);
        let restart = settings.from_best
            && settings.restart_after > 0
            && chain.stale >= settings.restart_after;
        // Shared with the round's threads; the calling thread hears of each result after it.
        let shared: &dyn Observer = &*observer;
        let out_of_time = &out_of_time;
        let origins: Vec<(usize, Start)> = (0..round)
            .map(|k| {
                let index = started + k;
                let origin = if restart {
                    Start::Lattice(RESTART_LATTICES + chain.restarts * threads + k)
                } else {
                    start_kind(settings, index)
                };
                (index, origin)
            })
            .collect();
        let starts: Vec<Vec<f64>> = origins
            .iter()
            .map(|&(index, origin)| match origin {
                Start::Lattice(n) => {
                    let n = shard.global(n);
                    turned::<N>(
                        &lattice_start_of(&problem, &lattice_start(&tightest, n)),
                        problem.layout(),
                        LATTICE_TURN,
                        settings.seed,
                        n as u64,
                    )
                }
                Start::Perturbed(amplitude) => perturb::<N>(
                    if settings.from_best {
                        &chain.best.x
                    } else {
                        &current
                    },
                    problem.layout(),
                    amplitude * chain.amplitude(settings),
                    settings.seed,
                    shard.global(index) as u64,
                ),
            })
            .collect();
        // The evaluations of each start: the cost of a start that fails, which has no report
        // of its own.
        let costs: Vec<AtomicUsize> = (0..round).map(|_| AtomicUsize::new(0)).collect();
        let numbered: Vec<(usize, Vec<f64>)> = starts.into_iter().enumerate().collect();
        let results = in_parallel(&numbered, threads, |(k, x)| {
            let counted = Counted {
                inner: shared,
                evaluations: &costs[*k],
                solve_evaluations: AtomicUsize::new(0),
            };
            minimise_start(semi_axes, kind, x, &settings.local, &counted, || {
                shared.should_stop() || out_of_time()
            })
        });
        let mut round_best: Option<LocalResult> = None;
        if restart {
            chain.restarts += 1;
        }
        let mut failed_costs = Vec::new();
        for ((result, (_, origin)), cost) in results.into_iter().zip(origins).zip(&costs) {
            let cost = cost.load(Ordering::Relaxed);
            // A start whose local minimisation ends at a point no repair can certify (an item
            // far outside the container) is a failed start, not a failed run: the
            // best packing so far stands.
            let result = match result {
                Ok(result) => result,
                Err(e) => {
                    failed_starts += 1;
                    if matches!(
                        (e, origin),
                        (Error::NotCertifiable { .. }, Start::Perturbed(_))
                    ) {
                        failed_costs.push(cost);
                    }
                    continue;
                }
            };
            if result.report.stop_reason == auglag::StopReason::Interrupted {
                // Cut off by the time limit or an interrupt, usually still at its perturbed
                // (infeasible) start: repaired, but not a result of the method, so it neither
                // counts nor seeds a chain. It is certified all the same, and compression's
                // steps are each a finished packing: a denser one is kept.
                cut_off += 1;
                if result.density > best.density {
                    best = result;
                    time_to_best = start.elapsed();
                }
                continue;
            }
            done += 1;
            chain.record(&result);
            if matches!(origin, Start::Perturbed(_)) {
                chain.succeeded_with(cost);
            }
            if result.density > best.density {
                best = result.clone();
                time_to_best = start.elapsed();
            }
            observer.finished(&MultiStartProgress {
                local_minimisations: done,
                best_density: best.density,
                last_density: result.density,
                elapsed: start.elapsed(),
            });
            if round_best
                .as_ref()
                .is_none_or(|b| result.density > b.density)
            {
                round_best = Some(result);
            }
        }
        if failed_costs.iter().any(|&c| chain.is_dear(c)) {
            chain.failed_round(settings);
        }
        if let Some(r) = round_best {
            if restart {
                chain.begin(&r);
            }
            current = r.x;
        }
    }
    let start_kept = start_density.is_some() && best.x == x0;
    Ok(MultiStartResult {
        best,
        start_density,
        start_kept,
        local_minimisations: done,
        failed_starts,
        restarts: chain.restarts,
        time_to_best,
        wall_time: start.elapsed(),
        interrupted: observer.should_stop(),
    })
}

/// Restart rounds take their lattice starts from this number of the sequence on, far past
/// those of the start indices (one per `fresh_lattice_every` starts).
const RESTART_LATTICES: usize = 10_000;

/// Halvings of a chain's perturbations at most ([`Chain::failed_round`]): a quarter of the
/// amplitude, the spread of the default amplitude levels. Failed starts are common on some
/// instances (84 in 322 local minimisations of 400 ellipses in a rectangle), and a chain
/// narrowed without end would stop moving.
const MAX_NARROWING: u32 = 2;

/// A failed start narrows its chain ([`Chain::failed_round`]) only when it cost more
/// evaluations of the model than this many times the median perturbed start that succeeded.
/// Evaluations measure what a start costs whatever the machine or load (about 6 500 a second for
/// 300 ellipsoids on one core, failed or not), where the solver's iterations do not: a start
/// that fails backtracks in its line searches, 15 evaluations an iteration. Where failures are
/// cheap, narrowing only holds the walk back: on 100 ellipses in a rectangle (seed 0, 2
/// threads) the first failure cost 151 660 evaluations against a median of 57 168, and
/// narrowing after it took the walk off the path that reaches 0.87500 at its 70th local
/// minimisation (it ended at 0.87443 after 1 142). On 300 ellipsoids (1, 0.75, 0.5) in a ball
/// the first cost 582 163 (89 s) against 37 687 (6 s) for the start beside it.
const DEAR_FAILURE: usize = 4;

/// Relative density gain below which a chain counts a start as no improvement (the
/// solver's tolerances leave differences of about 1e-7 between runs into the same packing).
const SIGNIFICANT_GAIN: f64 = 1e-5;

/// The chain of the walk from the best packing: its best packing and how many starts in a
/// row have not improved it.
struct Chain {
    best: LocalResult,
    stale: usize,
    restarts: usize,
    /// Rounds of this chain with a dear perturbed start that no repair certified.
    failed_rounds: u32,
    /// The evaluations of each perturbed start of the run that reached a packing.
    success_costs: Vec<usize>,
}

impl Chain {
    fn new(first: &LocalResult) -> Self {
        Self {
            best: first.clone(),
            stale: 0,
            restarts: 0,
            failed_rounds: 0,
            success_costs: Vec::new(),
        }
    }

    /// A finished start of this chain (a restart round's starts count for the new one). A
    /// better packing becomes the chain's best, but only a gain of more than
    /// [`SIGNIFICANT_GAIN`] keeps the chain alive: a walk that has settled still finds its
    /// packing again a little tighter, start after start.
    fn record(&mut self, result: &LocalResult) {
        if result.density > self.best.density * (1.0 + SIGNIFICANT_GAIN) {
            self.stale = 0;
        } else {
            self.stale += 1;
        }
        if result.density > self.best.density {
            self.best = result.clone();
        }
    }

    /// The factor of the perturbations' amplitude: 2 once the chain has gone
    /// [`MultiStartSettings::widen_after`] starts without a gain, else 1. A walk that returns
    /// to its best packing start after start is in a basin wider than its perturbations.
    fn widening(&self, settings: &MultiStartSettings) -> f64 {
        if settings.from_best && settings.widen_after > 0 && self.stale >= settings.widen_after {
            2.0
        } else {
            1.0
        }
    }

    /// The factor of the perturbations' amplitude: [`Chain::widening`], halved for each round
    /// of the chain in which a perturbed start failed ([`Chain::failed_round`]).
    fn amplitude(&self, settings: &MultiStartSettings) -> f64 {
        self.widening(settings) / f64::from(1u32 << self.failed_rounds)
    }

    /// A round in which a perturbed start ended at a point no repair certifies, and dearly
    /// ([`Chain::is_dear`]): with `from_best`, the chain's perturbations move half as far from
    /// now on, down to a quarter ([`MAX_NARROWING`]). Such a start moved further than the packing absorbs and is the
    /// dearest of all: from a packing of 300 ellipsoids (1, 0.75, 0.5) in a ball (0.67249, one
    /// local minimisation from the paper's start), starts perturbed at 0.1 failed after 165 s
    /// and 171 s (306 s with three pulls of their merged pairs), where starts at 0.05
    /// converged in 8–13 s; a round waits for its slowest start.
    fn failed_round(&mut self, settings: &MultiStartSettings) {
        if settings.from_best {
            self.failed_rounds = (self.failed_rounds + 1).min(MAX_NARROWING);
        }
    }

    /// A perturbed start that reached a packing after `evaluations` evaluations of the model.
    fn succeeded_with(&mut self, evaluations: usize) {
        self.success_costs.push(evaluations);
    }

    /// Whether a failed start of `evaluations` evaluations was dear: more than
    /// [`DEAR_FAILURE`] times the median perturbed start that reached a packing (every failure
    /// is, before one has).
    fn is_dear(&self, evaluations: usize) -> bool {
        let mut costs = self.success_costs.clone();
        costs.sort_unstable();
        costs
            .get(costs.len() / 2)
            .is_none_or(|&median| evaluations > DEAR_FAILURE * median)
    }

    /// A new chain from the best result of a restart round, even if worse than the old one.
    fn begin(&mut self, best: &LocalResult) {
        self.best = best.clone();
        self.stale = 0;
        self.failed_rounds = 0;
    }
}

/// An [`Observer`] that counts the evaluations of one start over all its solves (the pulls
/// and the polish solve again) and passes everything on.
struct Counted<'a> {
    inner: &'a dyn Observer,
    evaluations: &'a AtomicUsize,
    /// The evaluations of the current solve at its latest iteration.
    solve_evaluations: AtomicUsize,
}

impl Observer for Counted<'_> {
    fn iteration(&self, progress: &SolverProgress<'_>) {
        let seen = self
            .solve_evaluations
            .swap(progress.evaluations, Ordering::Relaxed);
        // A count below the last one is a new solve, counted from zero.
        let new = progress
            .evaluations
            .checked_sub(seen)
            .unwrap_or(progress.evaluations);
        self.evaluations.fetch_add(new, Ordering::Relaxed);
        self.inner.iteration(progress);
    }
    fn should_stop(&self) -> bool {
        self.inner.should_stop()
    }
}

/// `minimise` on every start, one thread each, in the order of the starts; a thread that
/// panicked gives [`Error::StartPanicked`]. With the `rayon` feature the `threads` are shared
/// out: each start runs inside a pool of `threads / starts` threads of its own (at least one),
/// which its model's evaluations use — one start of a round alone gets all of them, and a
/// start with one thread evaluates inline, without handing work to another thread. The
/// evaluations are the same bits on any number of threads, so the results do not depend on
/// the share.
pub(crate) fn in_parallel<T: Sync>(
    starts: &[T],
    threads: usize,
    minimise: impl Fn(&T) -> Result<LocalResult, Error> + Sync,
) -> Vec<Result<LocalResult, Error>> {
    let each = (threads / starts.len().max(1)).max(1);
    std::thread::scope(|scope| {
        let handles: Vec<_> = starts
            .iter()
            .map(|x| scope.spawn(|| on_threads(each, || minimise(x))))
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or(Err(Error::StartPanicked)))
            .collect()
    })
}

/// `f` inside a pool of `threads` threads of its own with the `rayon` feature; on the calling
/// thread without it.
fn on_threads<R: Send>(
    #[cfg_attr(not(feature = "rayon"), allow(unused_variables))] threads: usize,
    f: impl FnOnce() -> Result<R, Error> + Send,
) -> Result<R, Error> {
    #[cfg(feature = "rayon")]
    return implicit_packing::model::on_threads(threads, f)?;
    #[cfg(not(feature = "rayon"))]
    f()
}

/// The local minimisation of start `x` on a model of its own: each iteration goes to
/// `observer`, and it stops as soon as `stop` says so.
pub(crate) fn minimise_start<const N: usize>(
    semi_axes: &[[f64; N]],
    kind: ContainerShape,
    x: &[f64],
    local: &LocalSettings,
    observer: &dyn Observer,
    stop: impl Fn() -> bool,
) -> Result<LocalResult, Error> {
    let mut problem = Model::<N>::new(semi_axes.to_vec(), kind)?;
    local_minimisation(&mut problem, x, local, &mut |progress| {
        observer.iteration(progress);
        stop()
    })
}

/// Lattice starts that are the tightest cuts ([`tightest_lattice_starts`]) before
/// [`LatticeStart::sequence`] takes over, or all of [`MultiStartSettings::lattice_starts`]
/// when there are more.
const TIGHTEST_CUTS: usize = 16;

/// Largest turn (radians) of every item's angles on a lattice start ([`turned`]), which breaks
/// the lattice's symmetry.
const LATTICE_TURN: f64 = 0.01;

/// Whether a run's settings ever ask for a lattice start.
fn uses_lattice_starts(settings: &MultiStartSettings) -> bool {
    settings.lattice_starts > 0
        || settings.fresh_lattice_every > 0
        || (settings.from_best && settings.restart_after > 0)
}

/// Lattice start number `n` of a run: the tightest cuts first, then the sequence.
fn lattice_start<const N: usize>(tightest: &[LatticeStart<N>], n: usize) -> LatticeStart<N> {
    tightest
        .get(n)
        .copied()
        .unwrap_or_else(|| LatticeStart::sequence(n - tightest.len()))
}

/// Where start `index` (≥ 1) of a run comes from.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Start {
    /// Dense lattice start number n: the tightest cuts of the lattice, then
    /// [`LatticeStart::sequence`].
    Lattice(usize),
    /// A perturbation of the current solution with this largest relative amplitude.
    Perturbed(f64),
}

pub(crate) fn start_kind(settings: &MultiStartSettings, index: usize) -> Start {
    let lattice = settings.lattice_starts;
    if index <= lattice {
        return Start::Lattice(index - 1);
    }
    let j = index - lattice - 1;
    let every = settings.fresh_lattice_every;
    if every > 0 && j % every == every - 1 {
        return Start::Lattice(lattice + j / every);
    }
    let level = (j % settings.perturbation_levels.max(1) as usize) as i32;
    Start::Perturbed(settings.perturbation * 0.5f64.powi(level))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::starts::paper_start;

    fn run(threads: usize, seed: u64) -> MultiStartResult {
        let axes = vec![[2.0, 1.0]; 6];
        let x0 = paper_start(&axes, ContainerShape::Ellipsoid).unwrap();
        let settings = MultiStartSettings {
            threads,
            max_local_minimisations: 3,
            ..MultiStartSettings::paper(2, seed)
        };
        multistart(&axes, ContainerShape::Ellipsoid, &x0, &settings, &mut ()).unwrap()
    }

    /// The paper's start of 6 ellipses in an ellipse, certified as it is.
    fn six_ellipses() -> LocalResult {
        let axes = vec![[2.0, 1.0]; 6];
        let x0 = paper_start(&axes, ContainerShape::Ellipsoid).unwrap();
        let mut p = Model::<2>::new(axes, ContainerShape::Ellipsoid).unwrap();
        certified_start(&mut p, &x0).unwrap().unwrap()
    }

    #[test]
    fn a_chain_without_gains_widens_its_perturbations() {
        let first = six_ellipses();
        let settings = MultiStartSettings::recommended(2, 0).with_widen_after(3);
        let mut chain = Chain::new(&first);
        for stale in 0..3 {
            assert_eq!(chain.stale, stale);
            assert_eq!(chain.widening(&settings), 1.0);
            chain.record(&first);
        }
        assert_eq!(chain.widening(&settings), 2.0);
        assert_eq!(chain.widening(&settings.clone().with_widen_after(0)), 1.0);
        let mut denser = first.clone();
        denser.density *= 1.001;
        chain.record(&denser);
        assert_eq!(chain.widening(&settings), 1.0);
    }

    #[test]
    fn a_chain_whose_perturbation_failed_perturbs_half_as_far() {
        let first = six_ellipses();
        let settings = MultiStartSettings::recommended(2, 0).with_widen_after(1);
        let mut chain = Chain::new(&first);
        assert_eq!(chain.amplitude(&settings), 1.0);
        chain.failed_round(&settings);
        assert_eq!(chain.amplitude(&settings), 0.5);
        chain.failed_round(&settings);
        assert_eq!(chain.amplitude(&settings), 0.25);
        // Widening still doubles what the failures left.
        chain.record(&first);
        assert_eq!(chain.amplitude(&settings), 0.5);
        chain.failed_round(&settings);
        assert_eq!(
            chain.amplitude(&settings),
            0.5,
            "a quarter at most, widened"
        );
        chain.begin(&first);
        assert_eq!(chain.amplitude(&settings), 1.0);
        // Only a failure dearer than 4 times the median success narrows, once one succeeded.
        assert!(chain.is_dear(1));
        chain.succeeded_with(100);
        chain.succeeded_with(50);
        chain.succeeded_with(900);
        assert!(!chain.is_dear(400));
        assert!(chain.is_dear(401));
        // The paper's walk keeps its amplitude.
        let paper = MultiStartSettings::paper(2, 0);
        chain.failed_round(&paper);
        assert_eq!(chain.amplitude(&paper), 1.0);
    }

    #[test]
    fn lattice_starts_take_the_tightest_cuts_then_the_sequence() {
        let p = Model::<2>::new(vec![[2.0, 1.0]; 30], ContainerShape::Box).unwrap();
        let tightest = tightest_lattice_starts(&p, 3);
        assert_eq!(lattice_start(&tightest, 2), tightest[2]);
        assert_eq!(lattice_start(&tightest, 3), LatticeStart::sequence(0));
        assert_eq!(lattice_start(&tightest, 7), LatticeStart::sequence(4));
        assert_eq!(lattice_start::<2>(&[], 5), LatticeStart::sequence(5));
    }

    #[test]
    fn same_seed_and_threads_give_the_same_packing() {
        let a = run(2, 7);
        let b = run(2, 7);
        assert_eq!(a.best.x, b.best.x);
        assert_eq!(a.local_minimisations, 3);
        assert!(a.best.certificate.is_feasible());
    }

    /// Three shards of one seed: each reproduces exactly, none repeats another's first local
    /// minimisation, and shard 0 of 1 is the unsharded run.
    #[test]
    fn shards_are_reproducible_and_disjoint() {
        let axes = vec![[2.0, 1.0]; 6];
        let run_shard = |shard: Shard| {
            let settings = MultiStartSettings::paper(2, 11)
                .with_max_local_minimisations(2)
                .with_shard(shard);
            let (result, densities) =
                run_from_paper_start(&axes, ContainerShape::Ellipsoid, &settings);
            (result.best.x, densities)
        };
        let shards: Vec<_> = (0..3)
            .map(|k| run_shard(Shard::new(k, 3).unwrap()))
            .collect();
        assert_eq!(run_shard(Shard::new(1, 3).unwrap()), shards[1]);
        for a in 0..3 {
            for b in a + 1..3 {
                assert_ne!(shards[a].1[0], shards[b].1[0], "shards {a} and {b}");
            }
        }
        assert_eq!(run_shard(Shard::WHOLE).1[0], shards[0].1[0]);
        assert!(matches!(
            Shard::new(3, 3),
            Err(Error::Shard { index: 3, count: 3 })
        ));
    }

    #[test]
    fn the_best_is_at_least_the_first() {
        let settings = MultiStartSettings {
            max_local_minimisations: 3,
            ..MultiStartSettings::paper(3, 1)
        };
        let (r, densities) =
            run_from_paper_start(&[[1.0, 0.75, 0.5]; 6], ContainerShape::Ball, &settings);
        assert!(r.best.density >= densities[0]);
        assert!(r.best.certificate.is_feasible());
    }

    #[test]
    fn starts_run_through_lattices_then_perturbations_of_halving_amplitude() {
        let settings = MultiStartSettings {
            lattice_starts: 3,
            perturbation_levels: 2,
            fresh_lattice_every: 3,
            ..MultiStartSettings::paper(3, 1)
        };
        let kinds: Vec<String> = (1..=10)
            .map(|i| match start_kind(&settings, i) {
                Start::Lattice(n) => format!("L{n}"),
                Start::Perturbed(a) => format!("P{a}"),
            })
            .collect();
        assert_eq!(
            kinds,
            [
                "L0", "L1", "L2", "P0.1", "P0.05", "L3", "P0.05", "P0.1", "L4", "P0.1"
            ]
        );
    }

    /// A run on 7 ellipses (2, 1) in a box from the paper's start, with the density of every
    /// local minimisation in start order.
    fn run_7_in_a_box(settings: &MultiStartSettings) -> (MultiStartResult, Vec<f64>) {
        run_from_paper_start(&[[2.0, 1.0]; 7], ContainerShape::Box, settings)
    }

    /// A run from the paper's start, with the density of every local minimisation in start
    /// order.
    fn run_from_paper_start<const N: usize>(
        axes: &[[f64; N]],
        kind: ContainerShape,
        settings: &MultiStartSettings,
    ) -> (MultiStartResult, Vec<f64>) {
        let x0 = paper_start(axes, kind).unwrap();
        let mut densities = Vec::new();
        let r = multistart(
            axes,
            kind,
            &x0,
            settings,
            &mut Callbacks::on_finished(|p: &MultiStartProgress| densities.push(p.last_density)),
        )
        .unwrap();
        (r, densities)
    }

    #[test]
    fn lattice_starts_and_best_walk_are_reproducible_and_no_worse() {
        let settings = MultiStartSettings {
            threads: 2,
            max_local_minimisations: 6,
            lattice_starts: 3,
            from_best: true,
            perturbation_levels: 2,
            fresh_lattice_every: 2,
            ..MultiStartSettings::paper(2, 5)
        };
        let (a, da) = run_7_in_a_box(&settings);
        let (b, db) = run_7_in_a_box(&settings);
        assert_eq!(a.best.x, b.best.x);
        assert_eq!(da, db);
        assert_eq!(a.local_minimisations, 6);
        assert!(a.best.certificate.is_feasible());
        assert_eq!(a.best.density, da.iter().copied().fold(0.0, f64::max));
    }

    #[test]
    fn restarts_begin_new_chains_reproducibly() {
        let settings = MultiStartSettings {
            threads: 2,
            max_local_minimisations: 9,
            lattice_starts: 1,
            from_best: true,
            restart_after: 2,
            ..MultiStartSettings::paper(2, 3)
        };
        let (a, da) = run_7_in_a_box(&settings);
        let (b, db) = run_7_in_a_box(&settings);
        assert!(a.restarts >= 1, "no chain was restarted: {da:?}");
        assert_eq!((a.restarts, &a.best.x, &da), (b.restarts, &b.best.x, &db));
        assert_eq!(a.best.density, da.iter().copied().fold(0.0, f64::max));
        assert!(a.best.certificate.is_feasible());
        let (never, _) = run_7_in_a_box(&MultiStartSettings {
            restart_after: 0,
            ..settings.clone()
        });
        assert_eq!(never.restarts, 0);
    }

    #[test]
    fn a_chain_restarts_only_after_enough_stale_starts() {
        let result = |density: f64| {
            let axes = vec![[2.0, 1.0]; 2];
            let x0 = paper_start(&axes, ContainerShape::Box).unwrap();
            let mut p = Model::<2>::new(axes, ContainerShape::Box).unwrap();
            let mut r =
                local_minimisation(&mut p, &x0, &LocalSettings::default(), &mut |_| false).unwrap();
            r.density = density;
            r
        };
        let mut chain = Chain::new(&result(0.5));
        chain.record(&result(0.4));
        chain.record(&result(0.5));
        chain.record(&result(0.500_001));
        assert_eq!(chain.stale, 3, "none is an improvement");
        assert_eq!(chain.best.density, 0.500_001, "but the best is kept");
        chain.record(&result(0.6));
        assert_eq!((chain.stale, chain.best.density), (0, 0.6));
        chain.begin(&result(0.3));
        assert_eq!(
            (chain.stale, chain.best.density),
            (0, 0.3),
            "a new chain may start lower"
        );
    }

    #[test]
    fn perturbation_is_bounded_and_reproducible() {
        let x = vec![1.0, 2.0, 0.5, -1.0, 0.0, 0.1, 10.0, 5.0];
        let layout = implicit_packing::Layout::of(&[[2.0, 1.0]; 2]);
        let a = perturb::<2>(&x, &layout, 0.025, 3, 4);
        assert_eq!(a, perturb::<2>(&x, &layout, 0.025, 3, 4));
        assert_ne!(a, perturb::<2>(&x, &layout, 0.025, 3, 5));
        for k in 0..6 {
            let bound = 0.025
                * if k % 3 == 2 {
                    std::f64::consts::PI
                } else {
                    [10.0, 5.0][k % 3]
                };
            assert!((a[k] - x[k]).abs() <= bound);
        }
        assert_eq!(&a[6..], &x[6..], "the container is not perturbed");
    }

    /// Eight ellipses (2, 1) in a circle from the paper's start, watched by `observer`: the
    /// start and the run's result.
    fn eight_in_a_circle(observer: &mut dyn Observer) -> (Vec<f64>, MultiStartResult) {
        let axes = vec![[2.0, 1.0]; 8];
        let x0 = paper_start(&axes, ContainerShape::Ball).unwrap();
        let settings = MultiStartSettings::paper(2, 1);
        let r = multistart(&axes, ContainerShape::Ball, &x0, &settings, observer).unwrap();
        (x0, r)
    }

    #[test]
    fn an_interrupt_before_the_first_local_minimisation_keeps_the_start() {
        let (x0, r) = eight_in_a_circle(&mut Callbacks {
            finished: |_: &MultiStartProgress| {},
            iteration: |_: &SolverProgress<'_>| {},
            should_stop: || true,
        });
        assert!(r.interrupted && r.local_minimisations == 0);
        assert!(r.start_kept && r.best.x == x0);
        assert!(r.best.certificate.is_feasible());
    }

    #[test]
    fn a_first_local_minimisation_cut_off_early_keeps_a_denser_start() {
        let calls = std::sync::atomic::AtomicUsize::new(0);
        // Stopped at its first iteration, the first local minimisation returns a repaired
        // point near the start; whichever is denser is the best, and it is certified.
        let (x0, r) = eight_in_a_circle(&mut Callbacks {
            finished: |_: &MultiStartProgress| {},
            iteration: |_: &SolverProgress<'_>| {
                calls.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            },
            should_stop: || calls.load(std::sync::atomic::Ordering::SeqCst) > 0,
        });
        let start = r.start_density.unwrap();
        assert!(r.best.density >= start, "{} < {start}", r.best.density);
        assert_eq!(r.start_kept, r.best.x == x0);
        assert!(r.best.certificate.is_feasible());
    }
}
