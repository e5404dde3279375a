//! One packing run, from the problem to the certified packing as its items state it.
//!
//! [`Packer::run`] owns the whole run: it chooses and certifies the start (the paper's lattice
//! start, the densest small periodic cell tiled, a lattice start dilated into a fixed container,
//! a random sequential addition, or a packing to resume from), splits the time budget between
//! the start and the search, runs the multi-start of Section 6 ([`multistart`](mod@crate::multistart)) or the
//! random compression ([`crate::random`]), and certifies the result in the form it is handed
//! out: [`Item`]s (centre, semi-axes, θ or a quaternion) in a [`Container`] centred at the
//! origin, a periodic cell reduced and its items wrapped into it. A caller that writes those
//! values with round-trip precision writes a certified packing; nothing outside the packer sees
//! the solver's variables.
//!
//! # References
//! - E. G. Birgin, R. D. Lobato, J. M. Martínez, *A nonlinear programming model with implicit
//!   variables for packing ellipsoids*, J. Global Optim. 68 (2017), Section 6.

use crate::compression::compression_to;
use crate::error::{Error, StartDefects};
use crate::fixed::Unfinished;
use crate::local::{LocalMethod, item_measure};
use crate::multistart::{
    MultiStartProgress, MultiStartResult, MultiStartSettings, Observer, SolverProgress,
    SolverReport,
};
use crate::random::{Orientation, RandomPacking, RandomSettings, Target, random_packing_seen};
use crate::starts::{LatticeStart, fill_start, lattice_start};
use implicit_packing::certificate::{bodies_of, certify_items};
use implicit_packing::{Certificate, Container, ContainerShape, Item, Model};
use std::time::{Duration, Instant};

/// Items and their container as they are stated outside the model: centres relative to the
/// container's centre, which is the origin.
#[derive(Clone, Debug, PartialEq)]
pub struct Configuration<const N: usize> {
    /// The items, in the problem's order.
    pub items: Vec<Item<N>>,
    /// The container.
    pub container: Container<N>,
}

impl<const N: usize> Configuration<N> {
    /// Item area (2D) or volume (3D) over the container's.
    pub fn density(&self) -> f64 {
        let items = crate::settings::measure_of(self.items.iter().map(|i| i.semi_axes));
        items / self.container.measure().0
    }
}

/// What a run makes.
#[derive(Clone, Debug, PartialEq)]
pub enum Goal<const N: usize> {
    /// The densest packing: the container as small as the multi-start finds it.
    Densest,
    /// A packing in this container: the first certified one.
    Fill(Container<N>),
    /// A random packing ([`crate::random`]): compression from a random start in `container`
    /// to its packing fraction ([`Target::Fraction`]) or until jammed ([`Target::Jammed`]).
    Random {
        /// Where the compression ends.
        target: Target,
        /// The container of the random start (and of the packing, at a fraction).
        container: Container<N>,
    },
}

/// What to pack.
#[derive(Clone, Debug)]
pub struct Problem<const N: usize> {
    /// The items' semi-axes, in order.
    pub semi_axes: Vec<[f64; N]>,
    /// The container's shape.
    pub shape: ContainerShape,
    /// What the run makes.
    pub goal: Goal<N>,
    /// A certified packing of the same items to start from (a resumed run), in a container of
    /// the problem's shape.
    pub resume: Option<Configuration<N>>,
}

/// How to pack: the multi-start's settings (their seed, threads, time limit, shard and local
/// minimisation serve every goal) and the orientations of a random start.
#[derive(Clone, Debug)]
pub struct Settings {
    /// The multi-start; its `time_limit` is the whole run's, the start included, and `threads`
    /// 0 means every core.
    pub multistart: MultiStartSettings,
    /// Orientations of a random start, per item (items beyond the end: isotropic).
    pub orientations: Vec<Orientation>,
}

/// The repair of a packing made in a container the run chose: the container scaled by
/// `dilation` about its centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Repair {
    /// The container's linear factor (1: none needed).
    pub dilation: f64,
    /// The density of the solver's point, before the repair.
    pub density_before: f64,
}

/// A certified packing and how the run reached it.
#[derive(Clone, Debug)]
pub struct Packed<const N: usize> {
    /// The packing.
    pub configuration: Configuration<N>,
    /// Its certificate (of the items as stated): no overlapping pair, nothing outside.
    pub certificate: Certificate,
    /// The repair; `None` in a container of given size, which is never changed.
    pub repair: Option<Repair>,
    /// Local minimisations finished (1 for a random packing's compression).
    pub local_minimisations: usize,
    /// Starts abandoned because their local minimisation ended at an uncertifiable point.
    pub failed_starts: usize,
    /// New chains begun from fresh lattice starts.
    pub restarts: usize,
    /// Density of the start (the lattice start, the random start or the resumed packing).
    pub start_density: Option<f64>,
    /// Whether the packing is the start itself.
    pub start_kept: bool,
    /// From the start of the run to the packing.
    pub time_to_best: Duration,
    /// The whole run.
    pub wall_time: Duration,
    /// Whether the observer stopped the run.
    pub interrupted: bool,
    /// One row per finished local minimisation (per kept compression step of a random
    /// packing, the packing last), with times from the start of the run.
    pub history: Vec<MultiStartProgress>,
    /// The solver's report of the local minimisation that gave the packing (iterations,
    /// evaluations, why it stopped).
    pub solver: Box<SolverReport>,
}

/// A container of given size that the run could not fill: its least overlapping
/// configuration, never a packing.
#[derive(Clone, Debug)]
pub struct Unfilled<const N: usize> {
    /// The configuration (items may overlap or stick out).
    pub configuration: Configuration<N>,
    /// Its certificate (the overlapping pairs, the items outside).
    pub certificate: Certificate,
    /// The model's overlap plus containment violation there.
    pub infeasibility: f64,
    /// Local minimisations finished.
    pub local_minimisations: usize,
    /// The whole run.
    pub wall_time: Duration,
    /// Whether the observer stopped the run.
    pub interrupted: bool,
    /// As [`Packed::history`].
    pub history: Vec<MultiStartProgress>,
}

/// How a run ended.
#[derive(Clone, Debug)]
pub enum Outcome<const N: usize> {
    /// A certified packing.
    Packed(Packed<N>),
    /// A container of given size not filled.
    Unfilled(Unfilled<N>),
}

/// One packing run: [`Packer::new`] checks the problem, [`Packer::run`] packs.
pub struct Packer<const N: usize> {
    problem: Problem<N>,
    settings: Settings,
    model: Model<N>,
}

/// The most times the stated form of a packing is dilated (by 1 + 1e-12, 1e-11, …) to certify
/// it when the conversion to items put a tangent pair an ulp inside.
const STATING_DILATIONS: i32 = 6;

/// Relative difference within which a resumed packing's semi-axes and fixed container are the
/// problem's.
const SAME: f64 = 1e-12;

impl<const N: usize> Packer<N> {
    /// A run of `problem` with `settings`.
    ///
    /// # Errors
    /// The model's refusal of the items or the shape ([`Error::Model`]); a goal's or a resumed
    /// packing's container of another shape ([`Error::ContainerShape`]).
    pub fn new(problem: Problem<N>, settings: Settings) -> Result<Self, Error> {
        let model = Model::<N>::new(problem.semi_axes.clone(), problem.shape)?;
        let given = match &problem.goal {
            Goal::Densest => None,
            Goal::Fill(c) | Goal::Random { container: c, .. } => Some(c.kind()),
        };
        let resumed = problem.resume.as_ref().map(|r| r.container.kind());
        if let Some(found) = given
            .into_iter()
            .chain(resumed)
            .find(|&k| k != problem.shape)
        {
            return Err(Error::ContainerShape {
                found,
                expected: problem.shape,
            });
        }
        Ok(Packer {
            problem,
            settings,
            model,
        })
    }

    /// Packs: the start, then the multi-start (or the random compression) within the time
    /// limit, then the certificate of the packing as stated. The observer hears of every
    /// finished local minimisation and solver iteration, and stops the run when it says so;
    /// the best certified packing found by then is the outcome.
    ///
    /// # Errors
    /// A resumed packing that does not match the problem or is not certified; errors of the
    /// model and of the solver; [`Error::StoppedBeforeStart`].
    pub fn run(mut self, observer: &mut dyn Observer) -> Result<Outcome<N>, Error> {
        match self.problem.goal.clone() {
            Goal::Random { target, container } => self.random(target, &container, observer),
            Goal::Densest => self.multistart(None, observer),
            Goal::Fill(container) => self.multistart(Some(container.dimensions()), observer),
        }
    }

    /// The multi-start: from the lattice start (or the tiled periodic cell, or the resumed
    /// packing), in the container the run chooses or in the fixed one of variables `fixed`.
    fn multistart(
        &mut self,
        fixed: Option<Vec<f64>>,
        observer: &mut dyn Observer,
    ) -> Result<Outcome<N>, Error> {
        let resumed = self.problem.resume.is_some();
        let x0 = match (self.problem.resume.take(), &fixed) {
            (Some(start), _) => self.resumed(&start, fixed.as_deref())?,
            (None, Some(dims)) => fill_start(&mut self.model, &LatticeStart::centred(), dims)?,
            (None, None) => lattice_start(&self.model),
        };
        let mut settings = self.settings.multistart.clone();
        settings.threads = match settings.threads {
            0 => std::thread::available_parallelism().map_or(1, usize::from),
            n => n,
        };
        // A resumed run continues from its packing; its lattice starts were tried before.
        if resumed {
            settings.lattice_starts = 0;
        }
        let prelude = Instant::now();
        let x0 = if fixed.is_none() && !resumed {
            self.tiled_or(x0, &settings, &*observer)?
        } else {
            x0
        };
        let prelude = prelude.elapsed();
        settings.time_limit = settings.time_limit.map(|t| t.saturating_sub(prelude));
        let mut recorder = Recorder::new(observer, prelude);
        let (semi_axes, kind) = (&self.problem.semi_axes, self.problem.shape);
        let result = if fixed.is_some() {
            let model = Model::<N>::new(semi_axes.clone(), kind)?;
            crate::fill(model, &x0, &settings, &mut recorder)
        } else {
            crate::multistart(semi_axes, kind, &x0, &settings, &mut recorder)
        };
        let result = match result {
            Ok(result) => result,
            Err(Error::NotReached(u)) => return self.unfilled(&u, prelude, recorder.history),
            Err(e) => return Err(e),
        };
        self.packed(&result, fixed.is_none(), prelude, recorder.history)
    }

    /// The densest small periodic cell tiled ([`crate::tiling`]) when it is denser than the
    /// lattice start `x0`; `x0` otherwise. An eighth of the run per small cell, at most 8 s.
    fn tiled_or(
        &mut self,
        x0: Vec<f64>,
        settings: &MultiStartSettings,
        observer: &dyn Observer,
    ) -> Result<Vec<f64>, Error> {
        let eighth = settings.time_limit.map_or(MAX_PER_CELL, |t| t / 8);
        let per_cell = eighth.min(MAX_PER_CELL);
        let tiled = crate::tiling::tiled_start(&mut self.model, settings, per_cell, observer)?;
        let lattice = item_measure(&self.model) / self.model.evaluate(&x0, None)?.objective;
        Ok(match tiled {
            Some((y, density)) if density > lattice => y,
            _ => x0,
        })
    }

    /// A random packing: a random start, then compression to the container's fraction or
    /// until jammed; a resumed packing is compressed from (jammed) or checked at its fraction.
    fn random(
        &mut self,
        target: Target,
        container: &Container<N>,
        observer: &mut dyn Observer,
    ) -> Result<Outcome<N>, Error> {
        let began = Instant::now();
        let dims = container.dimensions();
        let ms = &self.settings.multistart;
        let mut local = ms.local.clone();
        local.method = LocalMethod::Compression;
        // One compression: the threads share its evaluations (0: every core).
        let threads = ms.threads;
        let time_limit = ms.time_limit;
        let settings = RandomSettings::new(target, ms.seed)
            .with_local(local.clone())
            .with_orientations(self.settings.orientations.clone())
            .with_threads(threads);
        let shared: &dyn Observer = &*observer;
        let mut observe = |p: &SolverProgress<'_>| {
            shared.iteration(p);
            shared.should_stop() || time_limit.is_some_and(|t| began.elapsed() >= t)
        };
        // The density of every packing the compression keeps, with its time: the history.
        let mut steps: Vec<(Duration, f64)> = Vec::new();
        let mut kept = |density: f64| steps.push((began.elapsed(), density));
        let made = match self.problem.resume.take() {
            None => random_packing_seen(&mut self.model, &dims, &settings, &mut observe, &mut kept),
            Some(start) => {
                let fraction = target == Target::Fraction;
                #[cfg(feature = "rayon")]
                self.model.set_threads(threads)?;
                let x0 = self.resumed(&start, fraction.then_some(dims.as_slice()))?;
                let aim = fraction.then_some(container.measure().0);
                compression_to(&mut self.model, &x0, &local, aim, &mut observe, &mut |p| {
                    kept(p.density)
                })
                .map(|packing| RandomPacking {
                    start_density: packing.density,
                    packing,
                })
            }
        };
        let made = match made {
            Ok(made) => made,
            Err(Error::NotReached(u)) => return self.unfilled(&u, Duration::ZERO, Vec::new()),
            Err(e) => return Err(e),
        };
        let interrupted = observer.should_stop();
        let wall_time = began.elapsed();
        steps.push((wall_time, made.packing.density));
        let history = kept_history(&steps);
        for row in &history {
            observer.finished(row);
        }
        let result = MultiStartResult {
            best: made.packing,
            local_minimisations: 1,
            failed_starts: 0,
            restarts: 0,
            time_to_best: wall_time,
            wall_time,
            interrupted,
            start_density: Some(made.start_density),
            start_kept: false,
        };
        self.packed(&result, target == Target::Jammed, Duration::ZERO, history)
    }

    /// The outcome of a run's certified `result` as stated; `repaired` when the run chose the
    /// container (a fixed one is never changed), `before` the time spent before `result`'s run.
    fn packed(
        &mut self,
        result: &MultiStartResult,
        repaired: bool,
        before: Duration,
        history: Vec<MultiStartProgress>,
    ) -> Result<Outcome<N>, Error> {
        let best = &result.best;
        let stated = self.stated(&best.x, repaired)?;
        let repair = repaired.then_some(Repair {
            dilation: best.repair_factor * stated.dilation,
            density_before: best.density_before_repair,
        });
        Ok(Outcome::Packed(Packed {
            configuration: stated.configuration,
            certificate: stated.certificate,
            repair,
            local_minimisations: result.local_minimisations,
            failed_starts: result.failed_starts,
            restarts: result.restarts,
            start_density: result.start_density,
            start_kept: result.start_kept,
            time_to_best: result.time_to_best + before,
            wall_time: result.wall_time + before,
            interrupted: result.interrupted,
            history,
            solver: Box::new(best.report.clone()),
        }))
    }

    /// The outcome of a container of given size not filled: its least overlapping point as
    /// stated.
    fn unfilled(
        &mut self,
        u: &Unfinished,
        before: Duration,
        history: Vec<MultiStartProgress>,
    ) -> Result<Outcome<N>, Error> {
        Ok(Outcome::Unfilled(Unfilled {
            configuration: self.configuration_at(&u.x)?,
            certificate: u.certificate.clone(),
            infeasibility: u.infeasibility,
            local_minimisations: u.local_minimisations,
            wall_time: u.wall_time + before,
            interrupted: u.interrupted,
            history,
        }))
    }

    /// The variables of a packing to resume from, checked against the problem (its items'
    /// semi-axes, the fixed container of variables `fixed`) and certified, since a resumed run
    /// keeps its start as the packing to beat.
    fn resumed(
        &mut self,
        start: &Configuration<N>,
        fixed: Option<&[f64]>,
    ) -> Result<Vec<f64>, Error> {
        let dims = start.container.dimensions();
        if let Some(expected) = fixed {
            let same = dims.len() == expected.len()
                && dims
                    .iter()
                    .zip(expected)
                    .all(|(a, b)| (a - b).abs() <= SAME * b.abs());
            if !same {
                return Err(Error::ResumeFixedSize {
                    found: dims,
                    expected: expected.to_vec(),
                });
            }
        }
        let axes = &self.problem.semi_axes;
        if start.items.len() != axes.len() {
            return Err(Error::ResumeItems {
                found: start.items.len(),
                expected: axes.len(),
            });
        }
        // The problem's semi-axes (equal to the packing's within 1e-12, checked here), so that
        // the model takes the bodies as its own.
        let mut items = start.items.clone();
        for (i, (item, l)) in items.iter_mut().zip(axes).enumerate() {
            let same = (0..N).all(|k| (item.semi_axes[k] - l[k]).abs() <= SAME * l[k].abs());
            if !same {
                return Err(Error::ResumeSemiAxes {
                    item: i,
                    found: item.semi_axes.to_vec(),
                    expected: l.to_vec(),
                });
            }
            item.semi_axes = *l;
        }
        let certificate = certify_items(&items, &start.container)?;
        if !certificate.is_feasible() {
            return Err(Error::StartNotCertified(Box::new(StartDefects::of(
                &certificate,
            ))));
        }
        Ok(self.model.pack_variables(&bodies_of(&items)?, &dims)?)
    }

    /// The packing of the certified variables `x` as stated, certified in that form: the
    /// conversion moves values by a few ulps, which can put a pair at exact tangency (an item
    /// touching its own image in a periodic cell, say) an ulp inside. When `may_dilate`, such
    /// a packing is dilated by the least of 1 + 1e-12, 1e-11, … that certifies its stated form.
    fn stated(&mut self, x: &[f64], may_dilate: bool) -> Result<Stated<N>, Error> {
        let mut dilation = 1.0;
        let mut step = 0;
        loop {
            let y = self.model.dilated(x, dilation);
            let configuration = self.configuration_at(&y)?;
            let certificate = certify_items(&configuration.items, &configuration.container)?;
            if certificate.is_feasible() || !may_dilate || step == STATING_DILATIONS {
                return Ok(Stated {
                    configuration,
                    certificate,
                    dilation,
                });
            }
            dilation = 1.0 + 1e-12 * 10f64.powi(step);
            step += 1;
        }
    }

    /// The configuration the variables `x` stand for, as stated: a periodic cell with its
    /// tilts reduced (the same lattice in the cell LAMMPS accepts) and the items wrapped into
    /// it.
    fn configuration_at(&mut self, x: &[f64]) -> Result<Configuration<N>, Error> {
        use implicit_packing::periodic::{reduced, to_cartesian, to_fractional};
        let container = match self.model.container_at(x)? {
            Container::Periodic { cell } => Container::Periodic {
                cell: reduced(&cell),
            },
            other => other,
        };
        let items = self
            .model
            .bodies_at(x)?
            .iter()
            .map(|body| {
                let mut item = Item::stating(body);
                if let Container::Periodic { cell } = &container {
                    let s = to_fractional(cell, &item.centre);
                    item.centre = to_cartesian(cell, &s.map(|v| v - v.floor()));
                }
                item
            })
            .collect();
        Ok(Configuration { items, container })
    }
}

/// The longest a small periodic cell of the tiled start may take.
const MAX_PER_CELL: Duration = Duration::from_secs(8);

/// A packing as stated, its certificate and the dilation that made it certified.
struct Stated<const N: usize> {
    configuration: Configuration<N>,
    certificate: Certificate,
    dilation: f64,
}

/// The history of a random packing from the densities of the packings its compression kept,
/// with their times: one row per kept step.
fn kept_history(steps: &[(Duration, f64)]) -> Vec<MultiStartProgress> {
    let mut best = 0.0_f64;
    steps
        .iter()
        .enumerate()
        .map(|(k, &(elapsed, density))| {
            best = best.max(density);
            MultiStartProgress {
                local_minimisations: k + 1,
                best_density: best,
                last_density: density,
                elapsed,
            }
        })
        .collect()
}

/// The caller's observer with the times of its progress counted from the start of the run
/// (the start took `by`), and the history kept.
struct Recorder<'a> {
    inner: &'a mut dyn Observer,
    by: Duration,
    history: Vec<MultiStartProgress>,
}

impl<'a> Recorder<'a> {
    fn new(inner: &'a mut dyn Observer, by: Duration) -> Self {
        Recorder {
            inner,
            by,
            history: Vec::new(),
        }
    }
}

impl Observer for Recorder<'_> {
    fn finished(&mut self, progress: &MultiStartProgress) {
        let mut progress = *progress;
        progress.elapsed += self.by;
        self.history.push(progress);
        self.inner.finished(&progress);
    }
    fn iteration(&self, progress: &SolverProgress<'_>) {
        self.inner.iteration(progress);
    }
    fn should_stop(&self) -> bool {
        self.inner.should_stop()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use implicit_packing::Orientation as Stated;

    fn settings(local_minimisations: usize) -> Settings {
        Settings {
            multistart: MultiStartSettings::paper(2, 3)
                .with_threads(1)
                .with_max_local_minimisations(local_minimisations),
            orientations: Vec::new(),
        }
    }

    fn problem<const N: usize>(
        semi_axes: [f64; N],
        m: usize,
        shape: ContainerShape,
        goal: Goal<N>,
    ) -> Problem<N> {
        Problem {
            semi_axes: vec![semi_axes; m],
            shape,
            goal,
            resume: None,
        }
    }

    fn packed<const N: usize>(outcome: Outcome<N>) -> Packed<N> {
        match outcome {
            Outcome::Packed(p) => p,
            Outcome::Unfilled(u) => panic!("not filled: {:?}", u.certificate),
        }
    }

    #[test]
    fn the_packing_handed_out_is_certified_as_its_items_state_it() {
        let p = problem([2.0, 1.0], 5, ContainerShape::Ball, Goal::Densest);
        let run = Packer::new(p, settings(2)).unwrap().run(&mut ()).unwrap();
        let run = packed(run);
        let c = &run.configuration;
        assert!(run.certificate.is_feasible());
        assert_eq!(
            certify_items(&c.items, &c.container).unwrap(),
            run.certificate
        );
        assert!(c.density() > 0.5, "{}", c.density());
        assert_eq!(run.local_minimisations, 2);
        assert_eq!(run.history.len(), 2);
        assert!(run.repair.is_some_and(|r| r.dilation >= 1.0));
        assert!(
            c.items
                .iter()
                .all(|i| matches!(i.orientation, Stated::Angle(_)))
        );
    }

    #[test]
    fn a_periodic_packing_has_its_items_in_its_reduced_cell() {
        let p = problem([1.0, 0.75, 0.5], 6, ContainerShape::Periodic, Goal::Densest);
        let mut s = settings(2);
        s.multistart.time_limit = Some(Duration::from_secs(3600));
        let run = packed(Packer::new(p, s).unwrap().run(&mut ()).unwrap());
        let Container::Periodic { cell } = run.configuration.container else {
            panic!("{:?}", run.configuration.container);
        };
        assert_eq!(cell, implicit_packing::periodic::reduced(&cell));
        for item in &run.configuration.items {
            let f = implicit_packing::periodic::to_fractional(&cell, &item.centre);
            assert!(f.iter().all(|v| (0.0..1.0 + 1e-12).contains(v)), "{f:?}");
        }
        assert!(run.certificate.is_feasible());
    }

    #[test]
    fn a_resumed_run_starts_from_its_packing_and_refuses_another() {
        let p = problem([2.0, 1.0], 5, ContainerShape::Ball, Goal::Densest);
        let first = packed(
            Packer::new(p.clone(), settings(1))
                .unwrap()
                .run(&mut ())
                .unwrap(),
        );
        let resumed = Problem {
            resume: Some(first.configuration.clone()),
            ..p.clone()
        };
        let again = packed(
            Packer::new(resumed, settings(1))
                .unwrap()
                .run(&mut ())
                .unwrap(),
        );
        let density = first.configuration.density();
        assert!(again.configuration.density() >= density * (1.0 - 1e-9));
        assert!(
            again
                .start_density
                .is_some_and(|d| (d - density).abs() <= 1e-9 * density)
        );

        let mut other = first.configuration.clone();
        other.items[3].semi_axes = [3.0, 1.0];
        let wrong = Problem {
            resume: Some(other),
            ..p.clone()
        };
        let err = Packer::new(wrong, settings(1)).unwrap().run(&mut ());
        assert!(
            matches!(err, Err(Error::ResumeSemiAxes { item: 3, .. })),
            "{err:?}"
        );

        let mut overlapping = first.configuration.clone();
        overlapping.items[1].centre = overlapping.items[0].centre;
        let bad = Problem {
            resume: Some(overlapping),
            ..p
        };
        match Packer::new(bad, settings(1)).unwrap().run(&mut ()) {
            Err(Error::StartNotCertified(d)) => assert_eq!(d.overlapping[0].0, 0),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_container_too_small_is_unfilled_and_never_a_packing() {
        // Five ellipses of area 2π in a disc of area 9π: fraction 1.11.
        let disc = Container::Ball { radius: 3.0 };
        let p = problem([2.0, 1.0], 5, ContainerShape::Ball, Goal::Fill(disc));
        match Packer::new(p, settings(2)).unwrap().run(&mut ()).unwrap() {
            Outcome::Unfilled(u) => {
                assert_eq!(u.configuration.container, disc);
                assert!(!u.certificate.is_feasible());
                assert!(u.infeasibility > 0.0);
            }
            Outcome::Packed(p) => panic!("packed at {}", p.configuration.density()),
        }
    }

    #[test]
    fn a_goal_in_another_container_shape_is_refused() {
        let square = Container::Box {
            half_sides: [5.0, 5.0],
        };
        let p = problem([2.0, 1.0], 5, ContainerShape::Ball, Goal::Fill(square));
        assert!(matches!(
            Packer::new(p, settings(1)),
            Err(Error::ContainerShape {
                found: ContainerShape::Box,
                expected: ContainerShape::Ball
            })
        ));
    }

    /// Nineteen unit circles in a circle, round items without angles whose pairs take the
    /// closed form: the recommended multi-start reaches the optimal radius 1 + √2 + √6 (Fodor
    /// 1999) to 1e-7 within three local minimisations, certified, and never below it.
    #[test]
    fn nineteen_circles_reach_their_optimal_circle() {
        let optimum = 1.0 + 2f64.sqrt() + 6f64.sqrt();
        let p = problem([1.0, 1.0], 19, ContainerShape::Ball, Goal::Densest);
        let settings = Settings {
            multistart: MultiStartSettings::recommended(2, 1)
                .with_threads(1)
                .with_max_local_minimisations(3)
                .with_time_limit(None),
            orientations: Vec::new(),
        };
        let run = packed(Packer::new(p, settings).unwrap().run(&mut ()).unwrap());
        assert!(run.certificate.is_feasible());
        let Container::Ball { radius } = run.configuration.container else {
            panic!("{:?}", run.configuration.container)
        };
        assert!(
            radius >= optimum * (1.0 - 1e-12) && radius <= optimum * (1.0 + 1e-7),
            "{radius} against {optimum}"
        );
    }

    #[test]
    fn a_random_packing_is_jammed_certified_with_its_history() {
        let cell =
            Container::from_dimensions(ContainerShape::Periodic, &[20.0, 20.0, 0.0]).unwrap();
        let goal = Goal::Random {
            target: Target::Jammed,
            container: cell,
        };
        let p = problem([1.0, 0.7], 40, ContainerShape::Periodic, goal);
        let run = packed(Packer::new(p, settings(1)).unwrap().run(&mut ()).unwrap());
        let c = &run.configuration;
        assert!(run.certificate.is_feasible());
        assert_eq!(
            certify_items(&c.items, &c.container).unwrap(),
            run.certificate
        );
        assert!(run.history.len() >= 2);
        let last = run.history.last().unwrap();
        assert!((last.last_density - c.density()).abs() <= 1e-6, "{last:?}");
        assert!(run.start_density.is_some_and(|d| d < c.density()));
    }
}
