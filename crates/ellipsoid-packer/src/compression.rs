//! Minimum container by compression: shrink a certified packing, place its items in the
//! smaller container, certify, and keep the smaller container whenever it certifies.
//!
//! Each step scales the centres and the container of the best packing by 1 − δ (the shapes
//! stay), which leaves overlaps of relative depth about δ. A placement in that fixed container
//! (the augmented Lagrangian of [`local`](crate::local) with objective 0) drives the model's
//! overlap and containment toward 0, and the repair of its point ([`repair`]: the pairs
//! separated by a dilation, the items still outside held by scaling the container alone, a
//! factor s ≥ 1 in all) gives a packing in a container scaled by (1 − δ)·s; a placement stops
//! as soon as that keeps [`KEPT_FRACTION`] of the step. A step whose packing is
//! denser than the best is kept; the next δ grows by half, up to [`FIRST_STEP`], when the step
//! gained at least a tenth of δ in density (unless the step before it was dropped or gained
//! less: then δ stays),
//! and halves otherwise. A step that is not denser is dropped and δ halves. The run ends when
//! δ falls below [`LAST_STEP`] or after [`JAMMED_AFTER`] steps in a row dropped or given up.
//! A start that is no packing is placed in its own container first (or, failing that,
//! dilated). A placement that minimises the overlap energy pulls apart the few pairs it
//! merged into one another (pulled to the distance of their enclosing balls).
//!
//! A placement in a container that still admits a packing is a zero-residual problem: its
//! infeasibility falls by orders of magnitude per outer iteration once the penalty has grown.
//! One whose infeasibility falls by less than [`STALL_FACTOR`] in its third working outer
//! iteration, or by less than [`LATE_STALL_FACTOR`] in a later one, while its inner solver
//! used all its iterations, is given up there: a container that is too small shows exactly
//! that, and a failed step would otherwise cost all its iterations. A step given up still
//! leaves the placement's point, which the repair makes a packing: it replaces the best when
//! it is denser, while δ halves as after any step given up. Near jamming most steps end so,
//! and their repaired points often gain: on 1e4 ellipsoids (1, 0.75, 0.5) in a ball, three of
//! eight steps given up gained, and the compression ended at 0.70829 after 15 238 inner
//! iterations, against 0.70660 after 18 616 when such steps left nothing.
//!
//! Compared with the augmented Lagrangian with the container among the variables (whose two
//! aggregated constraints have gradients that vanish on the feasible set, so that it acts as a
//! quadratic penalty with ρ → 10⁸ and caps its inner solver at every outer iteration on large
//! instances), compression reaches most of the density in a few placements and stops at a
//! jammed packing a little less dense; the container keeps the start's aspect ratios.
//!
//! # References
//! - E. G. Birgin, F. N. C. Sobral, *Minimizing the object dimensions in circle and sphere
//!   packing problems*, Comput. Oper. Res. 35 (2008): the container's size settled over
//!   feasibility problems.
//! - B. D. Lubachevsky, F. H. Stillinger, *Geometric properties of random disk packings*,
//!   J. Stat. Phys. 60 (1990): dense packings by compression.

use crate::Error;
use crate::problem::Adapter;
use crate::repair::{certified, certified_as, certified_start, repair, separated_then_held};
use crate::settings::{
    LocalResult, LocalSettings, add_counts, centre_bound, check_start, solver_options,
};
use auglag::{Control, Event, Progress, Report, StopReason};
use implicit_packing::model::{Certificate, Model};

/// The first relative shrink δ of the container's linear size, and the largest.
pub use crate::settings::FIRST_STEP;
/// The compression ends when δ falls below this.
pub const LAST_STEP: f64 = 1e-4;
/// The compression also ends when this many steps in a row were given up: the packing is
/// jammed. Measured on 1e4 ellipsoids (1, 0.75, 0.5) in a ball: in one run the last kept step
/// came after three given up (δ = 0.02, 0.01, 0.005) and the six after it (δ from 0.004 down
/// to 1e-4) all failed, at 10 s each; in another, four given up in a row (down to δ = 0.0025)
/// ended the run at 0.4 % less density. At m = 1e5 a step given up costs 100–170 s.
pub const JAMMED_AFTER: usize = 5;
/// A placement may stop before its tolerance: at the end of an outer iteration whose point,
/// dilated to a packing ([`repair`]), keeps this fraction κ of the step, a container
/// (1 − δ)·s ≤ 1 − κδ times the best one's. Polishing a placement to feasibility 1e-10 took
/// its last one or two outer iterations, a quarter of all the inner iterations of a 1e5 run;
/// the repair gives away at most (1 − κ)δ of the linear size, which shrinks with δ.
pub const KEPT_FRACTION: f64 = 0.9;
/// Outer iterations of one placement at most.
pub const PLACEMENT_OUTER_ITERATIONS: usize = 6;
/// Inner iterations of one outer iteration of a placement at most.
pub const PLACEMENT_INNER_ITERATIONS: usize = 1_000;
/// Optimality tolerance of a placement's subproblems. Without an objective, the Lagrangian's
/// gradient is as small as the overlap itself: the 1e-4 of the paper's solves would stop at
/// penetrations whose repair costs more than a step gains.
pub const PLACEMENT_OPTIMALITY: f64 = 1e-8;
/// In its third outer iteration that runs the inner solver, a placement whose infeasibility
/// falls by less than this factor is given up (later ones need [`LATE_STALL_FACTOR`]).
/// Measured on 1e4 ellipsoids (1, 0.75, 0.5) in a ball: placements that failed fell by 1.2–4.9×
/// there, those that succeeded by 35× or more; with 1e5 a successful first placement fell by
/// 20× only.
pub const STALL_FACTOR: f64 = 8.0;
/// From its fourth outer iteration that runs the inner solver on, the penalty is large and a
/// placement that will succeed converges fast: one whose infeasibility falls by less than this
/// factor is given up. Measured on the placements of the m = 1e4 and 1e5 runs of the scale
/// study: from the fourth working outer iteration on, those that reached feasibility 1e-10 fell
/// by 53× to 362× per outer iteration, those that did not by 8.8× to 14× (each such placement
/// cost 200–400 s at m = 1e5 before it ran out of outer iterations).
pub const LATE_STALL_FACTOR: f64 = 30.0;

/// How far past its target a compression with one ([`compression_to`]) aims: no step goes
/// beyond a container of measure `target·(1 − TARGET_OVERSHOOT)`, and a step that aims past
/// the target is accepted as soon as its point, dilated to the target's container, is a
/// packing — a dilation of `(1 − TARGET_OVERSHOOT)^(−1/N)`, 1 % of the linear size in 3D, left
/// to settle the last overlaps (each pair needs 1/μ: PW85 theory eq. (7)). The last overlaps
/// are the slow part of a placement: on 10⁴ ellipsoids (1, 0.75, 0.5) compressed to φ = 0.6,
/// aiming 0.1 % past the target with [`KEPT_FRACTION`] of the step as the acceptance ended
/// 4·10⁻⁶ short of it and took one more step (1 339 inner iterations in all); aiming 3 % past
/// it took 622.
pub const TARGET_OVERSHOOT: f64 = 0.03;

/// One local minimisation of the container by compression from `x0` (see the module
/// documentation). Each placement solves to the settings' polish tolerance (or, without one,
/// their feasibility tolerance) with their inner solver. `observe` sees every placement's
/// progress; returning `true` ends the run with the best packing so far, whose report then
/// says [`StopReason::Interrupted`].
///
/// The compression stops as soon as the container's area or volume is at most `target`
/// (`None`: compression to the end, a jammed packing). Each step is cut so that it aims no
/// further than `target·(1 − TARGET_OVERSHOOT)`, and a step aimed past the target places the
/// items by minimising the overlap energy (overlap plus containment, unconstrained) until its
/// point dilated to the target certifies. The packing returned may be denser than the target,
/// and a caller wanting the target exactly dilates it (a dilation by s ≥ 1 keeps a packing
/// one: μ² grows by s², PW85 theory eq. (7)). Whether the target was reached is
/// `result.objective <= target`.
///
/// `kept` is shown every packing the compression keeps, the first one (the start as a packing)
/// included: the density reached step by step.
///
/// # Errors
/// [`Error::Model`] (`LengthMismatch`) when `x0` does not fit the problem; errors of the model
/// on non-finite variables; [`Error::NotCertifiable`] when `x0` is no packing and no repair
/// by a factor up to 4 makes it one. A placement that fails in any way is a step not taken,
/// never an error: the best packing so far stands.
pub fn compression_to<const N: usize>(
    problem: &mut Model<N>,
    x0: &[f64],
    settings: &LocalSettings,
    target: Option<f64>,
    observe: &mut dyn FnMut(&Progress<'_>) -> bool,
    kept: &mut dyn FnMut(&LocalResult),
) -> Result<LocalResult, Error> {
    check_start(problem, x0)?;
    problem.evaluate(x0, None)?;
    let mut placer = Placer::new(settings, observe, target.is_some());
    let mut best = first_packing(problem, x0, &mut placer)?;
    kept(&best);
    let mut schedule = Schedule::new(settings.largest_compression_step);
    while let Some(step) = schedule.step()
        && !placer.interrupted
        && target.is_none_or(|t| best.objective > t)
    {
        // The linear shrink that takes the container to the aim below the target.
        let step = target.map_or(step, |t| {
            let aim = t * (1.0 - TARGET_OVERSHOOT);
            step.min(1.0 - (aim / best.objective).powf(1.0 / N as f64))
        });
        let trial = problem.dilated(&best.x, 1.0 - step);
        let enough = enough_dilation::<N>(step, best.objective, target);
        match placer.place(problem, &trial, Some(enough)) {
            Some(Placed::Solved(p)) if p.density > best.density => {
                // A step that gains less than a tenth of what it asked for (3δ in 3D) ends
                // against a jammed packing.
                schedule.kept(p.density >= best.density * (1.0 + 0.1 * step));
                best = p;
                kept(&best);
            }
            // A step given up still leaves a packing, its point repaired: kept when denser,
            // while the schedule goes on as after any step given up.
            Some(Placed::Stalled(p)) if p.density > best.density => {
                schedule.failed();
                best = p;
                kept(&best);
            }
            _ => schedule.failed(),
        }
    }
    let mut report = placer.total;
    report.stop_reason = if placer.interrupted {
        StopReason::Interrupted
    } else {
        StopReason::Converged
    };
    report.objective = best.objective;
    report.infeasibility = 0.0;
    report.best_feasible_objective = Some(best.objective);
    best.report = report;
    Ok(best)
}

/// The largest dilation of a step's placement that the step accepts: the one that leaves
/// [`KEPT_FRACTION`] κ of the step, `(1 − δ)·s = 1 − κδ`; or, for a step whose container of
/// measure `(1 − δ)^N·from` lies past the target, the one that lands on the target exactly.
fn enough_dilation<const N: usize>(step: f64, from: f64, target: Option<f64>) -> f64 {
    let trial = from * (1.0 - step).powi(N as i32);
    match target {
        Some(t) if trial < t => (t / trial).powf(1.0 / N as f64),
        _ => (1.0 - KEPT_FRACTION * step) / (1.0 - step),
    }
}

/// The relative shrinks δ of the compression's steps.
struct Schedule {
    step: f64,
    /// The largest δ.
    largest: f64,
    /// Whether the last step failed or gained little: the next kept step does not grow δ.
    held: bool,
    /// Steps given up in a row.
    failures: usize,
}

impl Schedule {
    fn new(largest: f64) -> Self {
        Self {
            step: FIRST_STEP.min(largest),
            largest,
            held: false,
            failures: 0,
        }
    }

    /// The next δ, or `None` when the compression has ended: δ below [`LAST_STEP`], or
    /// [`JAMMED_AFTER`] steps given up in a row.
    fn step(&self) -> Option<f64> {
        (self.step >= LAST_STEP && self.failures < JAMMED_AFTER).then_some(self.step)
    }

    /// A step whose packing was kept; `progress` when it gained at least a tenth of δ. δ
    /// grows by half (up to [`FIRST_STEP`]) after progress that followed a step with progress,
    /// stays after progress that followed a dropped step or a small gain, and halves without
    /// progress.
    fn kept(&mut self, progress: bool) {
        self.failures = 0;
        if !progress {
            self.step *= 0.5;
        } else if !self.held {
            self.step = (1.5 * self.step).min(self.largest);
        }
        self.held = !progress;
    }

    /// A step given up (the placement stalled, or its packing was no denser): δ halves.
    fn failed(&mut self) {
        self.failures += 1;
        self.step *= 0.5;
        self.held = true;
    }
}

/// Placements in fixed containers with the settings of compression, their counts summed, and
/// whether the observer stopped one (which ends the run).
struct Placer<'a> {
    options: auglag::Options,
    /// Whether placements minimise the overlap energy ([`Adapter::in_energy_mode`]) rather than
    /// solve the augmented Lagrangian of the feasibility problem.
    energy: bool,
    fixed_orientations: Vec<bool>,
    observe: &'a mut dyn FnMut(&Progress<'_>) -> bool,
    interrupted: bool,
    total: Report,
}

impl<'a> Placer<'a> {
    fn new(
        settings: &LocalSettings,
        observe: &'a mut dyn FnMut(&Progress<'_>) -> bool,
        energy: bool,
    ) -> Self {
        let tolerance = settings
            .polish_tolerance
            .unwrap_or(settings.feasibility_tolerance);
        let outer = settings
            .max_outer_iterations
            .min(PLACEMENT_OUTER_ITERATIONS);
        let inner = settings
            .max_inner_iterations
            .min(PLACEMENT_INNER_ITERATIONS);
        // An energy placement is one unconstrained minimisation, which ends at its inner
        // cap: it gets the budget of all the outer iterations of a Lagrangian one.
        let inner = if energy { inner * outer } else { inner };
        let limits = settings
            .clone()
            .with_optimality_tolerance(PLACEMENT_OPTIMALITY)
            .with_max_inner_iterations(inner)
            .with_max_outer_iterations(outer);
        Self {
            options: solver_options(&limits, tolerance),
            energy,
            fixed_orientations: settings.fixed_orientations.clone(),
            observe,
            interrupted: false,
            total: crate::settings::empty_report(),
        }
    }

    /// The items of `x` placed in its container, certified (repaired); `None` when the solver
    /// refused it or its point could not be repaired (a failed step: the best packing
    /// stands). With `enough`, the placement stops at the end of the first outer iteration
    /// whose point a dilation by at most `enough` makes a packing — in energy mode, whose
    /// single long outer iteration would otherwise run to its cap, also at inner iterations
    /// 10, 20, 32, … (a fifth more each time, so that the certificates cost a few percent of
    /// the placement) and whenever the energy has halved since the last try (it falls by
    /// orders of magnitude in a placement's last tenth). An energy placement whose point has
    /// a few pairs merged into one another ([`merged`](crate::merged)) pulls them apart and
    /// goes on from there with the rest of its inner iterations, [`PULLS_PER_PLACEMENT`]
    /// times at most. A placement the observer stopped is returned as it is, solved.
    fn place<const N: usize>(
        &mut self,
        problem: &mut Model<N>,
        x: &[f64],
        enough: Option<f64>,
    ) -> Option<Placed> {
        let mut x = x.to_vec();
        let mut total = crate::settings::empty_report();
        let mut pulls = 0;
        loop {
            let inner = self.options.max_inner_iterations - total.inner_iterations;
            let run = self.run(problem, &x, enough, inner)?;
            add_counts(&mut total, &run.solution.report);
            let left = total.inner_iterations < self.options.max_inner_iterations;
            let pull = !run.merged.is_empty() && pulls < PULLS_PER_PLACEMENT;
            if pull && left && !self.interrupted {
                x = crate::merged::pulled_apart(problem, &run.solution.x, &run.merged)?;
                pulls += 1;
                continue;
            }
            add_counts(&mut self.total, &total);
            let packing = match run.early {
                Some((x, repaired)) => {
                    certified_as(problem, auglag::Solution { x, ..run.solution }, repaired)
                }
                None => certified(problem, run.solution),
            };
            let packing = packing.ok()?.result;
            return Some(if run.stalled {
                Placed::Stalled(packing)
            } else {
                Placed::Solved(packing)
            });
        }
    }

    /// One minimisation of a placement from `x` with at most `inner` inner iterations (see
    /// [`Placer::place`]); in energy mode, stopped at a point with merged pairs. `None` when
    /// the solver refused `x`.
    fn run<const N: usize>(
        &mut self,
        problem: &mut Model<N>,
        x: &[f64],
        enough: Option<f64>,
        inner: usize,
    ) -> Option<Run> {
        let container = x[problem.layout().item_variables()..].to_vec();
        let adapter = Adapter::new(problem, centre_bound::<N>(x), Some(container))
            .with_frozen_orientations(&self.fixed_orientations, x)
            .in_energy_mode(self.energy);
        let options = self.options.clone().with_max_inner_iterations(inner);
        let mut stall = Stall::new(options.max_inner_iterations, self.energy);
        let mut early = None;
        let (mut merged, mut seen_merged) = (Vec::new(), Vec::new());
        // Energy placements: the next inner iteration to try the point at, and the energy
        // at the last try.
        let mut next_check = self.energy.then_some((FIRST_INNER_CHECK, f64::INFINITY));
        let (observe, interrupted, pull) = (&mut self.observe, &mut self.interrupted, self.energy);
        let solution = auglag::minimize_with_callback(&adapter, x, &options, |p: &Progress<'_>| {
            *interrupted |= observe(p);
            if *interrupted {
                return Control::Stop;
            }
            // A point good enough is kept even where the fall would say stall.
            let check = match (p.event, next_check.as_mut()) {
                (Event::Outer { .. }, _) => true,
                (Event::Inner { merit, .. }, Some((next, at)))
                    if p.total_inner_iterations >= *next || merit <= 0.5 * *at =>
                {
                    *next = p.total_inner_iterations + (p.total_inner_iterations / 5).max(10);
                    *at = merit;
                    true
                }
                _ => false,
            };
            if let (Some(limit), true) = (enough, check) {
                match adapter.with_model(|m| tried(m, p.x, limit, pull)) {
                    Tried::Packing(repaired) => {
                        early = Some((p.x.to_vec(), repaired));
                        return Control::Stop;
                    }
                    // Pairs merged at two tries in a row are stuck; others are still
                    // being pushed through one another and apart.
                    Tried::Merged(pairs) if pairs == seen_merged => {
                        merged = pairs;
                        return Control::Stop;
                    }
                    Tried::Merged(pairs) => seen_merged = pairs,
                    Tried::Neither => seen_merged.clear(),
                }
            }
            if stall.stalled(p) {
                Control::Stop
            } else {
                Control::Continue
            }
        })
        .ok()?;
        Some(Run {
            solution,
            stalled: (stall.stalled && early.is_none()) || !merged.is_empty(),
            early,
            merged,
        })
    }
}

/// Pulls of merged pairs in one placement at most: a placement whose pairs merge again after
/// as many pulls is given up there, as stalled (its container is too small for this path).
pub const PULLS_PER_PLACEMENT: usize = 2;

/// One minimisation of a placement ([`Placer::run`]) and how it ended.
struct Run {
    solution: auglag::Solution,
    /// Stopped early at a point that a small enough dilation makes a packing: the point and
    /// its repair.
    early: Option<(Vec<f64>, Repaired)>,
    /// Stopped at a point with these pairs merged.
    merged: Vec<(usize, usize)>,
    /// Given up as stalled.
    stalled: bool,
}

/// The first inner iteration of an energy placement at which its point is tried.
const FIRST_INNER_CHECK: usize = 10;

/// How a placement ended, with its packing (its point repaired).
enum Placed {
    /// Solved to its tolerance, or stopped early with a point good enough (or by the
    /// observer).
    Solved(LocalResult),
    /// Given up as stalled: the container is likely too small for the step asked.
    Stalled(LocalResult),
}

impl Placed {
    fn into_packing(self) -> LocalResult {
        match self {
            Placed::Solved(p) | Placed::Stalled(p) => p,
        }
    }
}

/// A point made a packing: its variables, the factor s of its repair and its certificate.
type Repaired = (Vec<f64>, f64, Certificate);

/// What a try of a placement's point found.
enum Tried {
    /// The repair of the point ([`repair`], its two exact steps only), its factor at most the
    /// limit.
    Packing(Repaired),
    /// A few pairs merged into one another ([`merged`](crate::merged)).
    Merged(Vec<(usize, usize)>),
    /// Neither: the placement goes on.
    Neither,
}

/// Tries the point `x` of a placement: its repair when its factor is at most `limit`; else,
/// with `pull`, its merged pairs. One certificate rejects most points: each overlapping pair
/// asks for a dilation of at least 1/μ. A point the model refuses is [`Tried::Neither`].
fn tried<const N: usize>(problem: &mut Model<N>, x: &[f64], limit: f64, pull: bool) -> Tried {
    let Ok(certificate) = problem.certify(x) else {
        return Tried::Neither;
    };
    let pairs_ask_too_much = certificate
        .overlapping
        .iter()
        .any(|o| !(o.mu2 > 0.0 && 1.0 / o.mu2.sqrt() <= limit));
    if pairs_ask_too_much {
        let merged = if pull {
            crate::merged::merged_pairs(&certificate, problem.len(), limit)
        } else {
            Vec::new()
        };
        return if merged.is_empty() {
            Tried::Neither
        } else {
            Tried::Merged(merged)
        };
    }
    match separated_then_held(problem, x, &certificate) {
        Ok(Some(repaired)) if repaired.1 <= limit => Tried::Packing(repaired),
        _ => Tried::Neither,
    }
}

/// The infeasibilities at the ends of a placement's outer iterations, and whether it fell by
/// less than [`STALL_FACTOR`] in the third outer iteration that ran the inner solver, or by
/// less than [`LATE_STALL_FACTOR`] in a later one, while the inner solver used all its
/// iterations. Outer iterations without inner iterations (the penalty still too small to move
/// anything) do not count. An inner solve that ended before its cap mostly solved its
/// subproblem (or its line search could go no further): the next outer iteration raises the
/// penalty, so a small fall there is no sign of a container too small (at m = 1e5 such falls
/// ended five placements in a row, each after 12–540 inner iterations). In energy mode the
/// energy takes the place of the infeasibility.
struct Stall {
    /// Inner iterations of one outer iteration at most.
    cap: usize,
    /// Whether the placement minimises the energy (the objective) rather than the
    /// infeasibility.
    energy: bool,
    /// Outer iterations that ran the inner solver.
    working: usize,
    inner: usize,
    previous: Option<f64>,
    stalled: bool,
}

impl Stall {
    fn new(cap: usize, energy: bool) -> Self {
        Self {
            cap,
            energy,
            working: 0,
            inner: 0,
            previous: None,
            stalled: false,
        }
    }

    fn stalled(&mut self, progress: &Progress<'_>) -> bool {
        if let Event::Outer {
            infeasibility,
            objective,
            ..
        } = progress.event
            && progress.total_inner_iterations > self.inner
        {
            let infeasibility = if self.energy {
                objective
            } else {
                infeasibility
            };
            let capped = progress.total_inner_iterations - self.inner >= self.cap;
            self.inner = progress.total_inner_iterations;
            self.working += 1;
            let factor = if self.working >= 4 {
                LATE_STALL_FACTOR
            } else {
                STALL_FACTOR
            };
            if self.working >= 3
                && capped
                && self
                    .previous
                    .is_some_and(|before| infeasibility > before / factor)
            {
                self.stalled = true;
            }
            self.previous = Some(infeasibility);
        }
        self.stalled
    }
}

/// `x0` as a packing: itself when it certifies; else its items placed in its container, or
/// failing that `x0` itself, made a packing by the least certifying dilation.
fn first_packing<const N: usize>(
    problem: &mut Model<N>,
    x0: &[f64],
    placer: &mut Placer<'_>,
) -> Result<LocalResult, Error> {
    if let Ok(packing) = certified_start(problem, x0)? {
        return Ok(packing);
    }
    if let Some(placed) = placer.place(problem, x0, None) {
        return Ok(placed.into_packing());
    }
    let (x, _, _) = repair(problem, x0)?;
    certified_start(problem, &x)?.map_err(|c| Error::NotCertifiable {
        max_dilation: 4.0,
        overlapping: c.overlapping.len(),
        outside: c.outside.len(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::local::{LocalMethod, item_measure, local_minimisation};
    use crate::starts::lattice_start;
    use implicit_packing::containment::ContainerShape;

    fn density<const N: usize>(p: &mut Model<N>, x: &[f64]) -> f64 {
        item_measure(p) / p.evaluate(x, None).unwrap().objective
    }

    #[test]
    fn a_placement_is_accepted_only_within_its_dilation() {
        let mut p = Model::<3>::new(vec![[1.0, 1.0, 1.0]; 2], ContainerShape::Ball).unwrap();
        // Unit spheres 1.5 apart in a ball of radius 3: the repair needs s = 4/3 exactly.
        let x = vec![-0.75, 0.0, 0.0, 0.75, 0.0, 0.0, 3.0];
        for pull in [false, true] {
            // 1/μ = 4/3: beyond the limit, but no merged pair.
            assert!(matches!(tried(&mut p, &x, 1.3, pull), Tried::Neither));
        }
        let Tried::Packing((y, s, cert)) = tried(&mut p, &x, 1.34, true) else {
            panic!("repaired within 1.34")
        };
        assert!(cert.is_feasible() && (s - 4.0 / 3.0).abs() < 1e-9);
        assert!((y[3] - y[0] - 2.0).abs() < 1e-9);
        // A packing needs nothing.
        let Tried::Packing((_, s, _)) = tried(&mut p, &y, 1.0, false) else {
            panic!("a packing")
        };
        assert_eq!(s, 1.0);
        // Centres 0.1 apart ask for 1/μ = 20: merged, pulled apart only when asked.
        let x = vec![-0.05, 0.0, 0.0, 0.05, 0.0, 0.0, 3.0];
        assert!(matches!(tried(&mut p, &x, 1.3, false), Tried::Neither));
        let Tried::Merged(pairs) = tried(&mut p, &x, 1.3, true) else {
            panic!("merged")
        };
        assert_eq!(pairs, vec![(0, 1)]);
    }

    /// A compression to the end with the default settings.
    fn compressed<const N: usize>(
        p: &mut Model<N>,
        x0: &[f64],
        observe: &mut dyn FnMut(&Progress<'_>) -> bool,
    ) -> LocalResult {
        compression_to(p, x0, &LocalSettings::default(), None, observe, &mut |_| {}).unwrap()
    }

    /// 20 ellipsoids cannot be placed in a container smaller than their volume: the placement
    /// stalls, and its point comes back repaired, a packing. The trial is a packing shrunk
    /// by 0.8, so the repair stays within its factor of 4.
    #[test]
    fn a_placement_given_up_leaves_its_point_repaired() {
        let mut p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 20], ContainerShape::Ball).unwrap();
        let x0 = lattice_start(&p);
        let packed =
            local_minimisation(&mut p, &x0, &LocalSettings::default(), &mut |_| false).unwrap();
        let trial = p.dilated(&packed.x, 0.8);
        let d = density(&mut p, &trial);
        assert!(d > 1.0, "{d}");
        let settings = LocalSettings::default().with_max_inner_iterations(20);
        let mut observe = |_: &Progress<'_>| false;
        let mut placer = Placer::new(&settings, &mut observe, false);
        match placer.place(&mut p, &trial, None) {
            Some(Placed::Stalled(packing)) => {
                assert!(packing.certificate.is_feasible());
                assert!(p.certify(&packing.x).unwrap().is_feasible());
                assert!(packing.repair_factor > 1.0);
            }
            Some(Placed::Solved(_)) => panic!("a container too small was not given up"),
            None => panic!("a placement given up left nothing"),
        }
        assert!(placer.total.inner_iterations > 0);
    }

    #[test]
    fn compression_ends_certified_denser_and_keeps_the_aspect_of_a_box() {
        let mut p = Model::<2>::new(vec![[2.0, 1.0]; 16], ContainerShape::Box).unwrap();
        let x0 = lattice_start(&p);
        let start = density(&mut p, &x0);
        let r = compressed(&mut p, &x0, &mut |_| false);
        assert!(p.certify(&r.x).unwrap().is_feasible());
        assert!(r.certificate.is_feasible());
        assert!(r.density > 1.05 * start, "{} from {start}", r.density);
        assert!((r.density - density(&mut p, &r.x)).abs() < 1e-12);
        let n = x0.len();
        let (a0, a) = (x0[n - 2] / x0[n - 1], r.x[n - 2] / r.x[n - 1]);
        assert!((a - a0).abs() < 1e-12 * a0, "aspect {a} against {a0}");
        assert_eq!(r.report.stop_reason, StopReason::Converged);
        assert!(r.report.outer_iterations > 0 && r.report.inner_iterations > 0);
    }

    #[test]
    fn an_overlapping_start_is_made_a_packing_first() {
        let mut p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 8], ContainerShape::Ball).unwrap();
        let x0 = p.dilated(&lattice_start(&p), 0.7);
        assert!(!p.certify(&x0).unwrap().is_feasible());
        let r = compressed(&mut p, &x0, &mut |_| false);
        assert!(p.certify(&r.x).unwrap().is_feasible());
    }

    #[test]
    fn an_interrupt_keeps_the_best_packing_so_far() {
        let mut p = Model::<3>::new(vec![[1.0, 0.75, 0.5]; 20], ContainerShape::Ball).unwrap();
        let x0 = lattice_start(&p);
        let start = density(&mut p, &x0);
        let mut calls = 0;
        let r = compressed(&mut p, &x0, &mut |_| {
            calls += 1;
            calls > 40
        });
        assert!(p.certify(&r.x).unwrap().is_feasible());
        assert_eq!(r.report.stop_reason, StopReason::Interrupted);
        assert!(r.density >= start);
    }

    /// The augmented Lagrangian after compression keeps the denser of the two and counts the
    /// iterations of both.
    #[test]
    fn compression_then_lagrangian_is_at_least_as_dense_as_compression() {
        let run = |method| {
            let mut p = Model::<2>::new(vec![[2.0, 1.0]; 12], ContainerShape::Ellipsoid).unwrap();
            let x0 = lattice_start(&p);
            let settings = LocalSettings::default().with_method(method);
            local_minimisation(&mut p, &x0, &settings, &mut |_| false).unwrap()
        };
        let (alone, both) = (
            run(LocalMethod::Compression),
            run(LocalMethod::CompressionThenLagrangian),
        );
        assert!(both.certificate.is_feasible());
        assert!(both.density >= alone.density);
        assert!(both.report.inner_iterations > alone.report.inner_iterations);
    }

    /// A step past the target is accepted where its dilated point lands on the target; any
    /// other keeps KEPT_FRACTION of the step.
    #[test]
    fn a_step_past_the_target_is_accepted_where_it_lands_on_it() {
        // From volume 1, δ = 0.1 leaves 0.729 in 3D.
        let s = enough_dilation::<3>(0.1, 1.0, Some(0.8));
        assert!((0.729 * s.powi(3) - 0.8).abs() < 1e-12, "{s}");
        let kept = (1.0 - KEPT_FRACTION * 0.1) / 0.9;
        assert_eq!(enough_dilation::<3>(0.1, 1.0, Some(0.7)), kept);
        assert_eq!(enough_dilation::<3>(0.1, 1.0, None), kept);
    }

    #[test]
    fn the_schedule_grows_after_two_gains_and_ends_when_jammed() {
        let mut schedule = Schedule::new(FIRST_STEP);
        assert_eq!(schedule.step(), Some(FIRST_STEP));
        schedule.failed();
        assert_eq!(schedule.step(), Some(FIRST_STEP / 2.0));
        // Progress right after a failure keeps δ; progress after progress grows it.
        schedule.kept(true);
        assert_eq!(schedule.step(), Some(FIRST_STEP / 2.0));
        schedule.kept(true);
        assert_eq!(schedule.step(), Some(0.75 * FIRST_STEP));
        schedule.kept(true);
        assert_eq!(schedule.step(), Some(FIRST_STEP));
        // A small gain halves δ and holds the next growth.
        schedule.kept(false);
        assert_eq!(schedule.step(), Some(FIRST_STEP / 2.0));
        schedule.kept(true);
        assert_eq!(schedule.step(), Some(FIRST_STEP / 2.0));
        // JAMMED_AFTER failures in a row end it while δ is still above LAST_STEP; a kept step
        // in between starts the count again.
        let mut schedule = Schedule::new(FIRST_STEP);
        schedule.failed();
        schedule.kept(true);
        for _ in 1..JAMMED_AFTER {
            schedule.failed();
            assert!(schedule.step().is_some());
        }
        schedule.failed();
        assert!(schedule.step >= LAST_STEP);
        assert_eq!(schedule.step(), None);
        // And δ below LAST_STEP ends it too.
        let mut schedule = Schedule::new(FIRST_STEP);
        while schedule.step().is_some() {
            schedule.kept(false);
        }
        assert!(schedule.step < LAST_STEP);
    }

    #[test]
    fn a_stall_is_seen_only_in_working_outer_iterations() {
        let mut stall = Stall::new(5, false);
        let values = [
            (1, 10, 1.0),
            (2, 10, 1.0),
            (3, 50, 1e-2),
            (4, 90, 1e-4),
            (5, 95, 5e-5),
        ];
        let mut seen = Vec::new();
        for (outer, inner, infeasibility) in values {
            let p = progress(outer, inner, infeasibility);
            seen.push(stall.stalled(&p));
        }
        // Outer 2 did no inner iterations; the third working one (outer 4) fell 100×, the
        // fourth only 2×.
        assert_eq!(seen, [false, false, false, false, true]);

        // The third working outer iteration needs a fall of 8×, the later ones 30×.
        let falls = |values: &[(usize, usize, f64)]| {
            let mut stall = Stall::new(10, false);
            values
                .iter()
                .map(|&(outer, inner, inf)| stall.stalled(&progress(outer, inner, inf)))
                .collect::<Vec<_>>()
        };
        let third = [(1, 10, 1.0), (2, 20, 0.5), (3, 30, 0.05)];
        assert_eq!(falls(&third), [false, false, false]);
        let mut fourth = third.to_vec();
        fourth.push((4, 40, 0.005));
        assert_eq!(falls(&fourth), [false, false, false, true]);
        fourth[3].2 = 0.001;
        assert_eq!(falls(&fourth), [false, false, false, false]);
    }

    #[test]
    fn a_small_fall_is_no_stall_when_the_inner_solve_ended_before_its_cap() {
        let run = |cap: usize| {
            let mut stall = Stall::new(cap, false);
            [(1, 10, 1.0), (2, 20, 0.5), (3, 30, 0.4), (4, 39, 0.39)]
                .iter()
                .map(|&(outer, inner, inf)| stall.stalled(&progress(outer, inner, inf)))
                .collect::<Vec<_>>()
        };
        assert_eq!(run(10), [false, false, true, true]);
        // Outer 3 used its cap of 10 and fell 1.25×: a stall (and it stays one). With a cap
        // of 11 neither outer 3 nor outer 4 (9 iterations) used its cap.
        assert_eq!(run(11), [false, false, false, false]);
    }

    fn progress(outer: usize, inner: usize, infeasibility: f64) -> Progress<'static> {
        Progress {
            outer_iteration: outer,
            inner_iteration: 0,
            total_inner_iterations: inner,
            evaluations: inner,
            x: &[],
            penalty: 1.0,
            safeguarded_multipliers: &[],
            event: Event::Outer {
                objective: 0.0,
                infeasibility,
                complementarity: 0.0,
                projected_gradient: 0.0,
            },
        }
    }
}
