//! A packing run as the command line and the files see it: the scene mapped once to the
//! packer's problem and settings ([`ellipsoid_packer::run`]), the packer's certified outcome
//! mapped once to a [`Packing`] and its [`Summary`]; and the independent check of a packing read
//! back from files ([`implicit_packing::certificate::certify_items`] on its items as stated).
//!
//! Containers are centred at the origin in the packer; a packing's items are its items
//! relative to its container's centre.

use crate::Error;
use crate::packing::{CertificateCounts, Container, Items, Packing, Summary};
use crate::scene::{RandomGoal, Scene};
use ellipsoid_packer::Target;
use ellipsoid_packer::local::LocalSettings;
use ellipsoid_packer::multistart::MultiStartSettings;
pub use ellipsoid_packer::multistart::{MultiStartProgress, Observer, Shard};
use ellipsoid_packer::run::{
    Configuration, Goal, Outcome, Packed, Packer, Problem, Settings, Unfilled,
};
use implicit_packing::certificate::{bodies_of as stated_bodies, certify_items};
use implicit_packing::{Body, Container as SizedContainer, Item};
use std::path::Path;
use std::time::Duration;

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
    /// The run's history.csv.
    pub history: History,
}

/// The folder inside the output folder that holds [`Unfinished`] configurations.
pub const UNFINISHED_DIR: &str = "unfinished";

/// Converts a time limit in seconds ([`crate::scene::time_limit`]).
///
/// # Errors
/// [`Error::TimeLimit`] for zero, negative, NaN, infinite, too large values, or values
/// below a nanosecond.
pub fn time_limit_of(seconds: f64) -> Result<Duration, Error> {
    crate::scene::time_limit(seconds).ok_or(Error::TimeLimit { seconds })
}

/// Makes sure the output folder can be written before a run spends its time: creates it,
/// then creates and removes a probe file in it.
///
/// # Errors
/// [`Error::OutputFolder`] naming the folder.
pub fn probe_output_folder(path: &Path) -> Result<(), Error> {
    let error = |source| Error::OutputFolder {
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
/// Errors of reading the files ([`Error::Io`], [`Error::Malformed`], …), and
/// [`Error::ContainerMismatch`].
pub fn resume_start(scene: &Scene, folder: &Path) -> Result<Packing, Error> {
    let (packing, _) = crate::folder::read_packing_dir(folder)?;
    let found = packing.container().kind();
    if found != scene.container {
        return Err(Error::ContainerMismatch {
            summary: folder.join(crate::summary_json::SUMMARY_FILE),
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
#[derive(Clone, Debug, PartialEq)]
pub struct History(String);

impl History {
    /// The table of a run's rows.
    pub fn of(rows: &[MultiStartProgress]) -> Self {
        let mut text = String::from("local_minimisation,seconds,density,best_density\n");
        for p in rows {
            text.push_str(&format!(
                "{},{:.3},{:.9},{:.9}\n",
                p.local_minimisations,
                p.elapsed.as_secs_f64(),
                p.last_density,
                p.best_density
            ));
        }
        History(text)
    }

    /// The CSV text.
    pub fn into_text(self) -> String {
        self.0
    }
}

/// What a run starts from besides its scene (whose settings the command line overrides
/// through [`Scene::overridden`]).
#[derive(Clone, Debug, Default)]
pub struct RunOptions {
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
    /// The run's history.csv.
    pub history: History,
}

/// Packs the scene's items with the packer ([`Packer::run`]): the scene and the options mapped
/// to its problem and settings, its certified packing mapped to the files' form. A scene that
/// gives its container's size ([`Scene::fixed_container`]) is filled until the first certified
/// packing; a random scene ([`Scene::random_goal`]) is compressed from a random start.
///
/// # Errors
/// [`Error`] when the model refuses the items or the resume packing does not match;
/// [`Error::NotReached`], with the least overlapping configuration, when a fixed container
/// was not filled; [`Error::FixedSizeMismatch`] when the packing to resume from is not in
/// the scene's fixed container.
pub fn run(
    scene: &Scene,
    options: &RunOptions,
    observer: &mut dyn Observer,
) -> Result<RunOutcome, Error> {
    match (scene.ellipse_axes(), scene.ellipsoid_axes()) {
        (Some(axes), _) => run_n::<2>(scene, axes, options, observer),
        (_, Some(axes)) => run_n::<3>(scene, axes, options, observer),
        _ => Err(Error::Mismatch("the scene has no items".into())),
    }
}

fn run_n<const N: usize>(
    scene: &Scene,
    semi_axes: Vec<[f64; N]>,
    options: &RunOptions,
    observer: &mut dyn Observer,
) -> Result<RunOutcome, Error> {
    let shape = scene.container.shape();
    let goal = match (scene.random_goal(), scene.fixed_container()) {
        (Some(RandomGoal::Fraction(c)), _) => Goal::Random {
            target: Target::Fraction,
            container: sized::<N>(&c)?,
        },
        (Some(RandomGoal::Jammed(c)), _) => Goal::Random {
            target: Target::Jammed,
            container: sized::<N>(&c)?,
        },
        (None, Some(c)) => Goal::Fill(sized::<N>(&c)?),
        (None, None) => Goal::Densest,
    };
    let resume = match &options.resume_from {
        Some(packing) => Some(configuration_of::<N>(packing)?),
        None => None,
    };
    let problem = Problem {
        semi_axes,
        shape,
        goal,
        resume,
    };
    let settings = settings_of(scene, options, N);
    let seed = settings.multistart.seed;
    let outcome = Packer::new(problem, settings)
        .and_then(|packer| packer.run(observer))
        .map_err(as_scene_says)?;
    match outcome {
        Outcome::Packed(packed) => packed_outcome(packed, options, seed),
        Outcome::Unfilled(unfilled) => Err(not_reached(unfilled)?),
    }
}

/// The packer's settings of the scene, with the command line's overrides.
fn settings_of(scene: &Scene, options: &RunOptions, n: usize) -> Settings {
    let count = |n: u64| usize::try_from(n).unwrap_or(usize::MAX);
    let mut multistart = MultiStartSettings::paper(n, scene.seed);
    multistart.local = local_settings(scene);
    if scene.random_goal().is_some() {
        multistart.local.fixed_orientations = scene.item_fixed_orientations();
    }
    multistart.perturbation = scene.solver.perturbation;
    multistart.lattice_starts = count(scene.solver.lattice_starts);
    multistart.from_best = scene.solver.from_best;
    multistart.perturbation_levels = scene.solver.perturbation_levels;
    multistart.fresh_lattice_every = count(scene.solver.fresh_lattice_every);
    multistart.restart_after = count(scene.solver.restart_after);
    multistart.widen_after = count(scene.solver.widen_after);
    multistart.threads = scene.solver.threads;
    multistart.max_local_minimisations = scene.solver.local_minimisations.map_or(usize::MAX, count);
    multistart.time_limit = Some(scene.solver.time_limit);
    multistart.shard = options.shard.unwrap_or(Shard::WHOLE);
    Settings {
        multistart,
        orientations: scene.item_orientations(),
    }
}

/// The scene's solver settings, mapped once onto the packer's settings of one local
/// minimisation.
fn local_settings(scene: &Scene) -> LocalSettings {
    let mut local = LocalSettings::default();
    local.feasibility_tolerance = scene.solver.feasibility_tolerance;
    local.optimality_tolerance = scene.solver.optimality_tolerance;
    local.inner_solver = scene.solver.inner_solver.solver();
    local.method = scene.solver.method.method();
    local
}

/// The packer's refusals of a packing to resume from, said as the scene's (the packer knows
/// a problem, the user wrote a scene).
fn as_scene_says(e: ellipsoid_packer::Error) -> Error {
    use ellipsoid_packer::Error as E;
    match e {
        E::ResumeItems { found, expected } => Error::Mismatch(format!(
            "the packing has {found} items, the scene {expected}"
        )),
        E::ResumeSemiAxes {
            item,
            found,
            expected,
        } => Error::Mismatch(format!(
            "item {item} has semi-axes {found:?} in the packing, {expected:?} in the scene"
        )),
        E::ResumeFixedSize { found, expected } => Error::FixedSizeMismatch { found, expected },
        E::Model(e) => named(e),
        other => Error::Packer(other),
    }
}

/// A configuration of the packer as the files hold it, with its summary: the container's
/// measure as the objective, the run's wall time and local minimisations, the certificate.
fn written<const N: usize>(
    configuration: &Configuration<N>,
    wall_time: Duration,
    local_minimisations: usize,
    certificate: &implicit_packing::Certificate,
) -> Result<(Packing, Summary), Error> {
    let packing = packing_of(configuration)?;
    let summary = Summary::new(
        &packing,
        configuration.container.measure().0,
        wall_time.as_secs_f64(),
        local_minimisations as u64,
        certificate_of(certificate),
    );
    Ok((packing, summary))
}

/// The run's outcome as the files hold it.
fn packed_outcome<const N: usize>(
    packed: Packed<N>,
    options: &RunOptions,
    seed: u64,
) -> Result<RunOutcome, Error> {
    let (packing, mut summary) = written(
        &packed.configuration,
        packed.wall_time,
        packed.local_minimisations,
        &packed.certificate,
    )?;
    summary.repair = packed.repair.map(|r| crate::packing::Repair {
        dilation: r.dilation,
        density_before: r.density_before,
    });
    // Only a container of given size is never repaired.
    summary.fixed_container = packed.repair.is_none();
    summary.start_kept = packed.start_kept;
    summary.shard = options.shard.map(|shard| crate::packing::ShardOrigin {
        index: shard.index(),
        count: shard.count(),
        seed,
    });
    Ok(RunOutcome {
        density_before_repair: packed.repair.map_or(summary.density, |r| r.density_before),
        repair_factor: packed.repair.map_or(1.0, |r| r.dilation),
        packing,
        summary,
        seconds_to_best: packed.time_to_best.as_secs_f64(),
        interrupted: packed.interrupted,
        failed_starts: packed.failed_starts,
        restarts: packed.restarts,
        start_density: packed.start_density,
        start_kept: packed.start_kept,
        history: History::of(&packed.history),
    })
}

/// The error of a fixed-container run that found no packing, with its least overlapping
/// configuration as the files hold it.
fn not_reached<const N: usize>(u: Unfilled<N>) -> Result<Error, Error> {
    let (packing, mut summary) = written(
        &u.configuration,
        u.wall_time,
        u.local_minimisations,
        &u.certificate,
    )?;
    summary.not_reached = true;
    summary.fixed_container = true;
    Ok(Error::NotReached(Box::new(Unfinished {
        packing,
        summary,
        infeasibility: u.infeasibility,
        interrupted: u.interrupted,
        history: History::of(&u.history),
    })))
}

/// Re-checks a packing from its files, independently of how it was made: PW85 verdicts on every
/// pair whose enclosing balls meet and exact containment (the one certificate), and the
/// smallest μ² over those pairs.
///
/// # Errors
/// [`Error`] when the items do not form valid bodies (a zero semi-axis, NaN).
pub fn verify(packing: &Packing) -> Result<CertificateCounts, Error> {
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
pub fn verify_detailed(packing: &Packing) -> Result<Verification, Error> {
    let model = match packing.items() {
        Items::Ellipses(_) => certified::<2>(packing)?,
        Items::Ellipsoids(_) => certified::<3>(packing)?,
    };
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

/// The certificate of a packing's items as stated.
fn certified<const N: usize>(packing: &Packing) -> Result<implicit_packing::Certificate, Error> {
    let c = configuration_of::<N>(packing)?;
    certify_items(&c.items, &c.container).map_err(named)
}

/// A model error about an item's values named as the packing states them: item i's centre
/// coordinate, or its fractional coordinate along a cell edge. Other errors pass unchanged.
fn named(e: implicit_packing::Error) -> Error {
    use implicit_packing::Error as E;
    let axis = ["x", "y", "z"];
    let edge = ["a", "b", "c"];
    match e {
        E::NonFiniteCentre {
            item: Some(item),
            axis: k,
            value,
        } => Error::OutOfRange {
            what: format!("item {item}'s centre coordinate {}", axis[k.min(2)]),
            value: format!("{value:e}"),
            rule: "coordinates must be finite and within ±1e30 (rescale the packing, or check \
                   the container's size and tilts)",
        },
        E::ItemFarFromCell {
            item,
            edge: k,
            value,
        } => Error::OutOfRange {
            what: format!(
                "item {item}'s fractional coordinate along the cell edge {}",
                edge[k.min(2)]
            ),
            value: format!("{value:e}"),
            rule: "items of a periodic cell must lie within 2^30 cells of it (wrap them into \
                   the cell)",
        },
        other => Error::Model(other),
    }
}

/// The bodies and the container of a packing, as the certificate sees them.
///
/// # Errors
/// [`Error`] when the items do not form valid bodies (a zero semi-axis, NaN).
pub fn bodies_of<const N: usize>(
    packing: &Packing,
) -> Result<(Vec<Body<N>>, SizedContainer<N>), Error> {
    let c = configuration_of::<N>(packing)?;
    Ok((stated_bodies(&c.items).map_err(named)?, c.container))
}

/// The summary's certificate: the counts and the smallest μ² of the one certificate.
fn certificate_of(model: &implicit_packing::Certificate) -> CertificateCounts {
    CertificateCounts {
        overlapping_pairs: model.overlapping.len() as u64,
        containment_violations: model.outside.len() as u64,
        min_mu2: model.min_mu2,
    }
}

/// The container of the files as the packer's, centred at the origin, checked by the model.
fn sized<const N: usize>(container: &Container) -> Result<SizedContainer<N>, Error> {
    let shape = container.kind().shape();
    Ok(SizedContainer::from_dimensions(shape, &container.size())?)
}

/// The items of a packing relative to its container's centre, and its container, as the packer
/// and the certificate take them.
fn configuration_of<const N: usize>(packing: &Packing) -> Result<Configuration<N>, Error> {
    let container = packing.container();
    let centre = container.center();
    let mut items: Vec<Item<N>> = packing
        .items()
        .in_dimension()
        .ok_or_else(|| Error::Mismatch("the packing has the other dimension".into()))?;
    for item in &mut items {
        for (x, c) in item.centre.iter_mut().zip(centre) {
            *x -= c;
        }
    }
    let container = sized::<N>(container)?;
    Ok(Configuration { items, container })
}

/// The packing the files hold of a configuration of the packer.
fn packing_of<const N: usize>(configuration: &Configuration<N>) -> Result<Packing, Error> {
    let items = Items::of(&configuration.items);
    let container = Container::placed([0.0; N], &configuration.container);
    Packing::new(container, items)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::packing::Centred;

    #[test]
    fn the_history_has_its_header_and_a_row_per_local_minimisation() {
        let history = History::of(&[
            MultiStartProgress {
                local_minimisations: 1,
                best_density: 0.5,
                last_density: 0.25,
                elapsed: Duration::from_millis(1500),
            },
            MultiStartProgress {
                local_minimisations: 2,
                best_density: 0.625,
                last_density: 0.625,
                elapsed: Duration::from_secs(3),
            },
        ]);
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
        let unit_disc_at = |x| Item::ellipse([x, 0.0], [1.0, 1.0], 0.0);
        let items = Items::Ellipses(vec![unit_disc_at(0.0), unit_disc_at(1.5)]);
        let packing = Packing::new(
            Container::plane([0.0, 0.0], Centred::Ball { radius: 2.4 }),
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
        let item = Item::ellipse([0.0, 3.0], [2.0, 1.0], std::f64::consts::FRAC_PI_2);
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
                Container::plane(
                    [1.0, 1.0],
                    Centred::Ellipsoid {
                        semi_axes: [4.0, 2.0],
                    },
                ),
                gauge_max(&|x, y| (x / 4.0).hypot(y / 2.0)),
            ),
            (
                Container::plane(
                    [1.0, 1.0],
                    Centred::Box {
                        half_sides: [4.0, 2.0],
                    },
                ),
                // max(2 / 4, 4 / 2): the top of the item, 4 above the centre.
                2.0,
            ),
            (
                Container::plane([1.0, 1.0], Centred::Ball { radius: 2.0 }),
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
