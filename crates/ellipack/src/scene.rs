//! The scene file of `ellipack pack` (TOML): what to pack, into which container, with which
//! solver settings, and what to write.
//!
//! ```toml
//! name = "30 ellipses in an ellipse"  # optional: used in picture titles
//! dimension = 2                       # 2: ellipses, 3: ellipsoids
//! seed = 1                            # optional (default 0): the multi-start's random seed,
//!                                     # 0 to 18446744073709551615 (a string "…" works too)
//!
//! [container]
//! kind = "ellipse"                    # 2D: circle | ellipse | rectangle | periodic
//!                                     # 3D: ball | ellipsoid | cuboid | periodic
//! # cell = "variable"                 # periodic only: the cell's lattice vectors are
//!                                     # variables (the densest periodic packing), or
//!                                     # "fixed": a given cell, with lengths or
//!                                     # packing_fraction
//! # A container of given size is filled, not minimised (at most one of these keys). One no
//! # packing fits (the items' area or volume beyond its own, an item longer than it reaches
//! # or thicker than its narrowest width) is refused when the scene is read.
//! # radius = 12.0                     # circle, ball
//! # semi_axes = [9.0, 7.0]            # ellipse, ellipsoid
//! # half_sides = [10.0, 8.0]          # rectangle, cuboid
//! # lengths = [20.0, 20.0]            # periodic, cell = "fixed": an orthogonal box
//! # packing_fraction = 0.6            # any kind: a circle or ball, a square or cube, a disc-
//! #                                   # or sphere-shaped ellipse or ellipsoid, sized so that
//! #                                   # the items fill this fraction of it
//! # packing_fraction = "jammed"       # a random packing compressed until jammed, in a
//! #                                   # container of that shape (a cube cell if periodic)
//!
//! [[shapes]]                          # one table per group of identical items
//! count = 20
//! semi_axes = [2.0, 1.0]              # dimension values, each in [1e-30, 1e30]; the whole
//!                                     # packing must lie within ±1.25e29 of its centre.
//!                                     # All equal (circles, balls): no angle variables and
//!                                     # a closed-form pair term: an evaluation of 1e4 balls
//!                                     # costs 1/2.8 of one of 1e4 ellipsoids (1/2.2 at
//!                                     # 1e5); two of three equal (spheroids): two angles
//!
//! [[shapes]]                          # several groups: mixed shapes
//! count = 10
//! semi_axes = [1.0, 1.0]
//! # Polydisperse groups, drawn once from the seed (stream = the group's index):
//! # size = { distribution = "lognormal", sigma = 0.25, min = 0.5, max = 2.0 }
//! #                                   # every semi-axis × s; "lognormal" (median 1, sigma of
//! #                                   # ln s), "normal" (mean 1, sigma) or "uniform" (min,
//! #                                   # max); min and max cut off (default 1e-3 and 1e3)
//! # aspect = { distribution = "uniform", min = 1.0, max = 2.0 }
//! #                                   # first semi-axis over the others × t, area or volume
//! #                                   # kept
//! # orientation = { axis = [1.0, 0.0], concentration = 20.0, fixed = true }
//! #                                   # random starts only: the first axis about `axis`
//! #                                   # (von Mises–Fisher in 3D, of 2θ in 2D; default
//! #                                   # isotropic); fixed: kept through the compression
//!
//! # [[shapes]]                        # a group from an item file (relative to the scene):
//! # file = "items.csv"                # header a, b (, c) and optionally theta (2D) or
//! #                                   # qw, qx, qy, qz (3D); other columns ignored
//!
//! [solver]                            # optional; the defaults are shown
//! feasibility_tolerance = 1e-4        # ε_feas, as in the paper's Section 6
//! optimality_tolerance = 1e-4         # ε_opt
//! time_limit = 60.0                   # seconds of wall clock (--time-limit overrides it)
//! threads = 0                         # 0: every core (--threads overrides it): shared by
//!                                     # the starts of a round (one start alone gets all);
//!                                     # the same bits on any number
//! # local_minimisations = 50          # cap on multi-start local minimisations (default: none)
//! inner_solver = "projected-lbfgs"    # or "spg", "truncated-newton"
//! method = "lagrangian"               # or "compression", "compression-lagrangian" (large m)
//! start = "lattice"                   # or "random": items at random positions and
//!                                     # orientations, compressed to the container's fraction
//!                                     # (needs a container size; "jammed" implies it)
//! perturbation = 0.025                # multi-start perturbation, relative (paper: 2.5 % in 2D,
//!                                     # 10 % in 3D: the default follows the dimension)
//! lattice_starts = 16                 # dense lattice starts before the perturbations
//! from_best = true                    # perturb the best packing (false: the latest, as the paper);
//!                                     # a failed perturbation dearer than 4 median
//!                                     # successes halves the later ones (to 1/4)
//! perturbation_levels = 3             # amplitudes perturbation, /2, /4 in turn (1: the paper's)
//! fresh_lattice_every = 8             # every 8th later start a new lattice start (0: never)
//! restart_after = 300                 # new chain from fresh lattice starts after 300 starts
//!                                     # without a 1e-5 gain (0: never; needs from_best)
//! widen_after = 32                    # perturbations twice as wide after 32 starts without
//!                                     # a gain, until the chain gains (0: never)
//!
//! [output]                            # optional; the defaults are shown
//! # directory = "out"                 # default directory (--out overrides it)
//! pictures = true                     # packing.svg and packing.png
//! xyz = true                          # packing.xyz
//! image_width = 1200                  # pixels
//! ```
//!
//! Reading it:
//!
//! ```
//! # let text = include_str!("scene.rs").lines()
//! #     .skip_while(|l| !l.starts_with("//! ```toml")).skip(1)
//! #     .take_while(|l| !l.starts_with("//! ```"))
//! #     .map(|l| l.strip_prefix("//! ").unwrap_or("")).collect::<Vec<_>>().join("\n");
//! use ellipack::scene::{Dimension, InnerSolverName, Scene};
//! use ellipack::packing::ContainerKind;
//!
//! let scene = Scene::from_toml_str(&text, "scene.toml").unwrap();
//! assert_eq!(scene.dimension, Dimension::Two);
//! assert_eq!(scene.container, ContainerKind::Ellipse);
//! assert_eq!(scene.item_count(), 30);
//! assert_eq!(scene.solver.inner_solver, InnerSolverName::ProjectedLbfgs);
//! assert_eq!(scene.solver.perturbation, 0.025);
//!
//! let err = Scene::from_toml_str("dimension = 2\n[container]\nkind = \"ball\"\n", "bad.toml")
//!     .unwrap_err();
//! assert_eq!(err.to_string(),
//!     "bad.toml: line 3, column 8: `container.kind`: a ball is a 3D container; \
//!      with dimension = 2 use circle, ellipse, rectangle or periodic");
//! ```
//!
//! A random packing (`start = "random"`, or `packing_fraction = "jammed"`) begins with random
//! sequential addition at a low fraction (0.35 in 2D, 0.2 in 3D) and compresses the
//! container, its shape kept, through certified placements
//! ([`ellipsoid_packer::random`]): to exactly the scene's fraction, or until no step can be
//! certified. It is one sample of a random packing, not a multi-start; the seed repeats it.
//!
//! Unknown keys, values of the wrong type and impossible values (a semi-axis ≤ 0, a count of
//! 0, no shapes, a container of the other dimension, a container size that does not fit the
//! kind or is not positive, a packing fraction outside (0, 1), two sizes, a distribution whose
//! cut-offs keep almost nothing, an orientation in a scene of lattice starts) are errors whose
//! message names the file, the line, the column and the key, as `shapes[1].count` (groups
//! counted from 0); an item file's errors name that file, its line and its column.

use crate::packing::{Container, ContainerKind};
use crate::table::short;
pub use crate::toml_keys::SceneError;
use crate::toml_keys::{line_column, toml_error};
use ellipsoid_packer::local::{InnerSolver, LocalMethod};
use ellipsoid_packer::multistart::{self, MultiStartSettings};
pub use ellipsoid_packer::random::{Distribution, Orientation};
use serde::Deserialize;
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Duration;
use toml::Spanned;

/// The built-in scene of `ellipack pack` without a scene file: 30 ellipses with semi-axes
/// (2, 1) in a minimum-area ellipse, short enough to finish well within a minute.
pub const DEFAULT_SCENE: &str = r#"# The built-in scene of `ellipack pack`.
name = "30 ellipses (2, 1) in a minimum-area ellipse"
dimension = 2
seed = 1

[container]
kind = "ellipse"

[[shapes]]
count = 30
semi_axes = [2.0, 1.0]

[solver]
time_limit = 45.0
"#;

/// The largest number of items a scene may ask for: far beyond what the solver handles in a
/// day, low enough that a typo (an extra zero or six) is caught before memory runs out.
pub const MAX_ITEMS: usize = 10_000_000;

/// The semi-axis lengths a scene accepts: those the packing model accepts
/// ([`implicit_packing::shape::MAX_MAGNITUDE`] and its reciprocal), checked here so that the
/// message names the scene's line and key.
pub const SEMI_AXIS_RANGE: (f64, f64) = (
    1.0 / implicit_packing::shape::MAX_MAGNITUDE,
    implicit_packing::shape::MAX_MAGNITUDE,
);

/// Ellipses or ellipsoids.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Dimension {
    /// Ellipses in the plane.
    Two,
    /// Ellipsoids in space.
    Three,
}

impl Dimension {
    /// 2 or 3.
    pub fn get(self) -> usize {
        match self {
            Dimension::Two => 2,
            Dimension::Three => 3,
        }
    }
}

/// The name, in a scene file, of the inner solver of the augmented Lagrangian's
/// bound-constrained subproblems ([`ellipsoid_packer::local::InnerSolver`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum InnerSolverName {
    /// Nonmonotone spectral projected gradient (`"spg"`).
    Spg,
    /// Active-set projected L-BFGS (`"projected-lbfgs"`).
    ProjectedLbfgs,
    /// Active-set truncated Newton with the model's exact Hessian–vector products
    /// (`"truncated-newton"`).
    TruncatedNewton,
}

impl InnerSolverName {
    /// The name of the packer's solver (`None`: one that scenes cannot name).
    pub fn of(solver: InnerSolver) -> Option<Self> {
        match solver {
            InnerSolver::Spg => Some(InnerSolverName::Spg),
            InnerSolver::ProjectedLbfgs => Some(InnerSolverName::ProjectedLbfgs),
            InnerSolver::TruncatedNewton => Some(InnerSolverName::TruncatedNewton),
            _ => None,
        }
    }

    /// The packer's solver of this name.
    pub fn solver(self) -> InnerSolver {
        match self {
            InnerSolverName::Spg => InnerSolver::Spg,
            InnerSolverName::ProjectedLbfgs => InnerSolver::ProjectedLbfgs,
            InnerSolverName::TruncatedNewton => InnerSolver::TruncatedNewton,
        }
    }

    /// The name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            InnerSolverName::Spg => "spg",
            InnerSolverName::ProjectedLbfgs => "projected-lbfgs",
            InnerSolverName::TruncatedNewton => "truncated-newton",
        }
    }
}

/// The name, in a scene file, of how one local minimisation makes the container small
/// ([`ellipsoid_packer::local::LocalMethod`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MethodName {
    /// The paper's augmented Lagrangian with the container among the variables
    /// (`"lagrangian"`).
    Lagrangian,
    /// Compression: placements in shrinking fixed containers (`"compression"`); much faster
    /// for thousands of items, somewhat less dense, the container's aspect kept.
    Compression,
    /// Compression, then the augmented Lagrangian from its packing
    /// (`"compression-lagrangian"`).
    CompressionLagrangian,
}

impl MethodName {
    /// The name of the packer's method (`None`: one that scenes cannot name).
    pub fn of(method: LocalMethod) -> Option<Self> {
        match method {
            LocalMethod::AugmentedLagrangian => Some(MethodName::Lagrangian),
            LocalMethod::Compression => Some(MethodName::Compression),
            LocalMethod::CompressionThenLagrangian => Some(MethodName::CompressionLagrangian),
            _ => None,
        }
    }

    /// The packer's method of this name.
    pub fn method(self) -> LocalMethod {
        match self {
            MethodName::Lagrangian => LocalMethod::AugmentedLagrangian,
            MethodName::Compression => LocalMethod::Compression,
            MethodName::CompressionLagrangian => LocalMethod::CompressionThenLagrangian,
        }
    }

    /// The name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            MethodName::Lagrangian => "lagrangian",
            MethodName::Compression => "compression",
            MethodName::CompressionLagrangian => "compression-lagrangian",
        }
    }
}

/// The name, in a scene file, of how a run starts (`solver.start`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StartName {
    /// Dense lattice starts, then the multi-start (`"lattice"`): the densest packing found.
    #[default]
    Lattice,
    /// A random packing (`"random"`): items at random positions and orientations, then
    /// compressed to the container's packing fraction or until jammed
    /// ([`ellipsoid_packer::random`]).
    Random,
}

impl StartName {
    /// The name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            StartName::Lattice => "lattice",
            StartName::Random => "random",
        }
    }
}

/// What a random packing ([`StartName::Random`]) compresses to, with its container.
#[derive(Clone, Debug, PartialEq)]
pub enum RandomGoal {
    /// The fixed container of the scene, at its packing fraction.
    Fraction(Container),
    /// Until jammed, in a container of this shape (its size is the run's).
    Jammed(Container),
}

/// The packing fraction of the container a jammed scene's shape is given at
/// ([`Scene::random_goal`]); any size would do, the run's start sets its own.
const JAMMED_SHAPE_FRACTION: f64 = 0.5;

/// A group of items: identical, drawn from size and aspect distributions, or read from an
/// item file.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeGroup {
    /// How many (≥ 1).
    pub count: usize,
    /// Their semi-axes (with distributions: the semi-axes of a factor 1; from a file: the
    /// first row's): as many as the dimension, each positive and finite.
    pub semi_axes: Vec<f64>,
    /// The distribution of the factor scaling every semi-axis of an item (`size`).
    pub size: Option<Distribution>,
    /// The distribution of the stretch of the first semi-axis against the others at constant
    /// area or volume (`aspect`; [`ellipsoid_packer::random::stretched`]).
    pub aspect: Option<Distribution>,
    /// How the items are oriented in a random start (`orientation`; `None`: isotropic).
    pub orientation: Option<Orientation>,
    /// Whether the items keep their start orientation through the compression of a random
    /// packing (`orientation.fixed`).
    pub fixed_orientation: bool,
    /// The items of an item file (`file`), when the group comes from one.
    pub file: Option<ItemFile>,
}

impl ShapeGroup {
    /// `count` identical items.
    pub fn identical(count: usize, semi_axes: Vec<f64>) -> Self {
        ShapeGroup {
            count,
            semi_axes,
            size: None,
            aspect: None,
            orientation: None,
            fixed_orientation: false,
            file: None,
        }
    }
}

/// The items of a group read from a CSV file: a header naming the columns `a`, `b` (and `c`
/// in 3D), optionally `theta` (2D) or `qw`, `qx`, `qy`, `qz` (3D) for the orientation in a
/// random start; other columns are ignored, so a `packing.csv` serves.
#[derive(Clone, Debug, PartialEq)]
pub struct ItemFile {
    /// The file, as the scene names it (relative to the scene's folder).
    pub path: PathBuf,
    /// Each row's semi-axes.
    pub semi_axes: Vec<Vec<f64>>,
    /// Each row's orientation, when the file gives them.
    pub orientations: Option<Vec<Vec<f64>>>,
}

/// Settings of the solver and the multi-start.
#[derive(Clone, Debug, PartialEq)]
pub struct SolverSettings {
    /// ε_feas (> 0; default 1e-4, the paper's).
    pub feasibility_tolerance: f64,
    /// ε_opt (> 0; default 1e-4, the paper's).
    pub optimality_tolerance: f64,
    /// Wall-clock limit of the whole run (default 60 s).
    pub time_limit: Duration,
    /// Worker threads; 0 means every available core.
    pub threads: usize,
    /// Cap on the multi-start's local minimisations; `None`: until the time limit.
    pub local_minimisations: Option<u64>,
    /// The subproblem solver.
    pub inner_solver: InnerSolverName,
    /// How one local minimisation makes the container small.
    pub method: MethodName,
    /// Largest relative perturbation of centres and angles between multi-start iterations, in
    /// [0, 1) (default: 0.025 in 2D, 0.10 in 3D, the paper's Section 6).
    pub perturbation: f64,
    /// Dense lattice starts (hexagonal / face-centred cubic, several orientations, shifts and
    /// container aspects) tried after the first start and before any perturbation.
    pub lattice_starts: u64,
    /// Perturb the best packing so far (default) rather than, as the paper, the latest one.
    /// With it, each round in which a perturbed start fails after more than 4 times the
    /// evaluations of the median perturbed start that succeeded halves the chain's
    /// perturbations from then on, down to a quarter.
    pub from_best: bool,
    /// Perturbations cycle through the amplitudes `perturbation / 2^k`, k < this (1: always
    /// the full amplitude, as the paper).
    pub perturbation_levels: u32,
    /// Every this many later starts, one is a new dense lattice start (0: never).
    pub fresh_lattice_every: u64,
    /// How the run starts: dense lattices and the multi-start, or a random packing.
    pub start: StartName,
    /// With `from_best`: after this many starts in a row without improving the current
    /// chain's best packing by more than 1e-5 relative, a round of fresh lattice starts
    /// begins a new chain (0: never).
    pub restart_after: u64,
    /// With `from_best`: after this many starts in a row without improving the current
    /// chain's best packing, its perturbations move twice as far until it gains (0: never).
    pub widen_after: u64,
}

/// Starts without improvement after which a run begins a new chain, unless the scene says
/// otherwise ([`ellipsoid_packer::multistart::RESTART_AFTER`]).
pub const DEFAULT_RESTART_AFTER: u64 = multistart::RESTART_AFTER as u64;

/// Default wall-clock limit of a run ([`ellipsoid_packer::multistart::TIME_LIMIT`]).
pub const DEFAULT_TIME_LIMIT: Duration = multistart::TIME_LIMIT;

impl SolverSettings {
    /// The defaults for a dimension: the packer's ([`MultiStartSettings::recommended`]).
    pub fn defaults(dimension: Dimension) -> Self {
        let n = match dimension {
            Dimension::Two => 2,
            Dimension::Three => 3,
        };
        let run = MultiStartSettings::recommended(n, 0);
        let wide = |v: usize| u64::try_from(v).unwrap_or(u64::MAX);
        SolverSettings {
            feasibility_tolerance: run.local.feasibility_tolerance,
            optimality_tolerance: run.local.optimality_tolerance,
            time_limit: run.time_limit.unwrap_or(DEFAULT_TIME_LIMIT),
            threads: run.threads,
            local_minimisations: None,
            // The packer's defaults are among the names (a test checks it).
            inner_solver: InnerSolverName::of(run.local.inner_solver)
                .unwrap_or(InnerSolverName::ProjectedLbfgs),
            method: MethodName::of(run.local.method).unwrap_or(MethodName::Lagrangian),
            perturbation: run.perturbation,
            lattice_starts: wide(run.lattice_starts),
            from_best: run.from_best,
            perturbation_levels: run.perturbation_levels,
            fresh_lattice_every: wide(run.fresh_lattice_every),
            start: StartName::Lattice,
            restart_after: wide(run.restart_after),
            widen_after: wide(run.widen_after),
        }
    }
}

/// A run's time limit of `seconds`: finite, positive, at least a nanosecond (a shorter limit
/// is a zero duration, no limit a clock can tell) and within a [`Duration`] (which would
/// otherwise panic). The one rule for the scene, the command line and Python.
pub fn time_limit(seconds: f64) -> Option<Duration> {
    if !(seconds.is_finite() && seconds > 0.0) {
        return None;
    }
    Duration::try_from_secs_f64(seconds)
        .ok()
        .filter(|d| !d.is_zero())
}

/// The run settings that the command line and Python may give instead of the scene's.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Overrides {
    /// Wall-clock limit.
    pub time_limit: Option<Duration>,
    /// Seed.
    pub seed: Option<u64>,
    /// Threads (0: every core).
    pub threads: Option<usize>,
}

impl Scene {
    /// The scene with `overrides` applied: where they enter a run, once.
    pub fn overridden(mut self, overrides: &Overrides) -> Scene {
        if let Some(t) = overrides.time_limit {
            self.solver.time_limit = t;
        }
        if let Some(seed) = overrides.seed {
            self.seed = seed;
        }
        if let Some(threads) = overrides.threads {
            self.solver.threads = threads;
        }
        self
    }
}

/// What to write besides `packing.csv` and `summary.json` (always written).
#[derive(Clone, Debug, PartialEq)]
pub struct OutputOptions {
    /// The output directory when `--out` is not given.
    pub directory: Option<PathBuf>,
    /// Write `packing.svg` and `packing.png` (default true).
    pub pictures: bool,
    /// Write `packing.xyz` (default true).
    pub xyz: bool,
    /// Width of the pictures in pixels, 200 to 8000 (default 1200).
    pub image_width: u32,
}

impl Default for OutputOptions {
    fn default() -> Self {
        OutputOptions {
            directory: None,
            pictures: true,
            xyz: true,
            image_width: 1200,
        }
    }
}

/// The size of a fixed container as a scene gives it (`[container]` keys): the run fills this
/// container instead of minimising one.
#[derive(Clone, Debug, PartialEq)]
pub enum ContainerSize {
    /// `radius` of a circle or ball.
    Radius(f64),
    /// `semi_axes` of an ellipse or ellipsoid (one per dimension).
    SemiAxes(Vec<f64>),
    /// `half_sides` of a rectangle or cuboid (one per dimension).
    HalfSides(Vec<f64>),
    /// `lengths` of a fixed periodic cell, an orthogonal box (one per dimension).
    Lengths(Vec<f64>),
    /// `packing_fraction`, in (0, 1): the circle or ball, the square or cube, or the disc- or
    /// sphere-shaped ellipse or ellipsoid that the items fill to this fraction.
    PackingFraction(f64),
    /// `packing_fraction = "jammed"`: a random packing compressed until jammed, in a container
    /// of the shape `PackingFraction` gives (a circle or ball, a square or cube, …) whose size
    /// the run finds.
    Jammed,
}

impl ContainerSize {
    /// The scene key.
    pub fn key(&self) -> &'static str {
        match self {
            ContainerSize::Radius(_) => "radius",
            ContainerSize::SemiAxes(_) => "semi_axes",
            ContainerSize::HalfSides(_) => "half_sides",
            ContainerSize::Lengths(_) => "lengths",
            ContainerSize::PackingFraction(_) | ContainerSize::Jammed => "packing_fraction",
        }
    }
}

/// A validated scene: everything a packing run needs to start.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// A name for titles, if given.
    pub name: Option<String>,
    /// 2D or 3D.
    pub dimension: Dimension,
    /// The container's shape (of the scene's dimension); its size is what the run minimises,
    /// unless `container_size` gives it.
    pub container: ContainerKind,
    /// The size of a fixed container, which the run fills without minimising; `None`: the
    /// run minimises the container.
    pub container_size: Option<ContainerSize>,
    /// The items, by group (at least one group).
    pub shapes: Vec<ShapeGroup>,
    /// Solver settings.
    pub solver: SolverSettings,
    /// The random seed of the multi-start.
    pub seed: u64,
    /// Output options.
    pub output: OutputOptions,
}

// The file as written, with the position of every value that validation may reject.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    name: Option<String>,
    dimension: Spanned<i64>,
    seed: Option<Spanned<RawScalar>>,
    container: RawContainer,
    shapes: Option<Spanned<Vec<Spanned<RawShapes>>>>,
    solver: Option<RawSolver>,
    output: Option<RawOutput>,
}

/// A number or a string as written, for the keys that take either (`seed`, `packing_fraction`):
/// integers of any size (TOML's are 64-bit signed, the parser passes larger ones on), so that
/// every u64 of `--seed` fits in a scene, written as a string beyond TOML's range.
enum RawScalar {
    Integer(i128),
    Real(f64),
    Text(String),
}

impl<'de> Deserialize<'de> for RawScalar {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = RawScalar;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number or a string")
            }
            fn visit_i64<E>(self, v: i64) -> Result<RawScalar, E> {
                Ok(RawScalar::Integer(v.into()))
            }
            fn visit_u64<E>(self, v: u64) -> Result<RawScalar, E> {
                Ok(RawScalar::Integer(v.into()))
            }
            fn visit_i128<E>(self, v: i128) -> Result<RawScalar, E> {
                Ok(RawScalar::Integer(v))
            }
            fn visit_u128<E>(self, v: u128) -> Result<RawScalar, E> {
                // Anything beyond i128 is beyond u64 too: the range check reports it.
                Ok(RawScalar::Integer(i128::try_from(v).unwrap_or(i128::MAX)))
            }
            fn visit_f64<E>(self, v: f64) -> Result<RawScalar, E> {
                Ok(RawScalar::Real(v))
            }
            fn visit_str<E>(self, v: &str) -> Result<RawScalar, E> {
                Ok(RawScalar::Text(v.to_string()))
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawContainer {
    kind: Spanned<ContainerKind>,
    cell: Option<Spanned<String>>,
    radius: Option<Spanned<f64>>,
    semi_axes: Option<Spanned<Vec<f64>>>,
    half_sides: Option<Spanned<Vec<f64>>>,
    lengths: Option<Spanned<Vec<f64>>>,
    packing_fraction: Option<Spanned<RawScalar>>,
}

impl RawContainer {
    /// The size keys given, with their spans, in the order of [`ContainerSize::key`]'s names.
    fn size_keys(&self) -> Vec<(&'static str, std::ops::Range<usize>)> {
        [
            ("radius", self.radius.as_ref().map(Spanned::span)),
            ("semi_axes", self.semi_axes.as_ref().map(Spanned::span)),
            ("half_sides", self.half_sides.as_ref().map(Spanned::span)),
            ("lengths", self.lengths.as_ref().map(Spanned::span)),
            (
                "packing_fraction",
                self.packing_fraction.as_ref().map(Spanned::span),
            ),
        ]
        .into_iter()
        .filter_map(|(key, span)| Some((key, span?)))
        .collect()
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawShapes {
    count: Option<Spanned<i64>>,
    semi_axes: Option<Spanned<Vec<f64>>>,
    size: Option<Spanned<RawDistribution>>,
    aspect: Option<Spanned<RawDistribution>>,
    orientation: Option<Spanned<RawOrientation>>,
    file: Option<Spanned<String>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDistribution {
    distribution: String,
    sigma: Option<f64>,
    min: Option<f64>,
    max: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOrientation {
    axis: Option<Vec<f64>>,
    concentration: Option<f64>,
    fixed: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSolver {
    feasibility_tolerance: Option<Spanned<f64>>,
    optimality_tolerance: Option<Spanned<f64>>,
    time_limit: Option<Spanned<f64>>,
    threads: Option<Spanned<i64>>,
    local_minimisations: Option<Spanned<i64>>,
    inner_solver: Option<InnerSolverName>,
    method: Option<MethodName>,
    start: Option<Spanned<StartName>>,
    perturbation: Option<Spanned<f64>>,
    lattice_starts: Option<Spanned<i64>>,
    from_best: Option<bool>,
    perturbation_levels: Option<Spanned<i64>>,
    fresh_lattice_every: Option<Spanned<i64>>,
    restart_after: Option<Spanned<i64>>,
    widen_after: Option<Spanned<i64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    directory: Option<String>,
    pictures: Option<bool>,
    xyz: Option<bool>,
    image_width: Option<Spanned<i64>>,
}

impl Scene {
    /// Parses and validates a scene. `source_name` names it in messages (a path, or
    /// `<built-in scene>`).
    ///
    /// # Errors
    /// [`SceneError`] naming the line, column and key of the first problem: TOML syntax,
    /// unknown keys, wrong types, missing `dimension`, `container.kind` or shapes, a
    /// dimension other than 2 or 3, a container of the other dimension, a count < 1, semi-axes
    /// that are not positive and finite or not `dimension` of them, tolerances, time limit or
    /// perturbation out of range.
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<Scene, SceneError> {
        Scene::parse(text, source_name, false)
    }

    fn parse(text: &str, source_name: &str, from_file: bool) -> Result<Scene, SceneError> {
        let raw: RawScene = toml::from_str(text).map_err(|e| toml_error(text, source_name, &e))?;
        Validator {
            text: Some(text),
            source_name,
            from_file,
        }
        .scene(raw)
    }

    /// A scene given as a table of values, as a scene file's TOML would parse (Python gives its
    /// dict so): the same checks as [`Scene::from_toml_str`], with messages that name the key
    /// (line and column 0: a table has no lines).
    ///
    /// # Errors
    /// As [`Scene::from_toml_str`].
    pub fn from_table(table: &toml::Table, source_name: &str) -> Result<Scene, SceneError> {
        use serde::Deserialize as _;
        let root = toml::Value::Table(table.clone());
        let raw =
            RawScene::deserialize(crate::scene_table::At::root(&root)).map_err(|e| SceneError {
                source_name: source_name.to_string(),
                line: 0,
                column: 0,
                key: if e.key.is_empty() {
                    "<scene>".to_string()
                } else {
                    e.key
                },
                message: crate::toml_keys::plain_types(&e.message),
            })?;
        Validator {
            text: None,
            source_name,
            from_file: false,
        }
        .scene(raw)
    }

    /// Reads and validates a scene file.
    ///
    /// # Errors
    /// A [`SceneError`] (line 1, key `<file>`) when the file cannot be read, else as
    /// [`Scene::from_toml_str`].
    pub fn from_file(path: &Path) -> Result<Scene, SceneError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            source_name: name.clone(),
            line: 1,
            column: 1,
            key: "<file>".to_string(),
            message: e.to_string(),
        })?;
        Scene::parse(&text, &name, true)
    }

    /// The built-in scene, [`DEFAULT_SCENE`].
    pub fn default_scene() -> Scene {
        // A unit test parses the constant, so this cannot fail in a released build.
        Scene::from_toml_str(DEFAULT_SCENE, "<built-in scene>")
            .unwrap_or_else(|e| panic!("the built-in scene is invalid: {e}"))
    }

    /// The total number of items.
    pub fn item_count(&self) -> usize {
        self.shapes.iter().map(|g| g.count).sum()
    }

    /// The semi-axes of every item in order (groups expanded), as ellipses; `None` in 3D.
    pub fn ellipse_axes(&self) -> Option<Vec<[f64; 2]>> {
        (self.dimension == Dimension::Two).then(|| self.expand(|l| [l[0], l[1]]))
    }

    /// The semi-axes of every item in order (groups expanded), as ellipsoids; `None` in 2D.
    pub fn ellipsoid_axes(&self) -> Option<Vec<[f64; 3]>> {
        (self.dimension == Dimension::Three).then(|| self.expand(|l| [l[0], l[1], l[2]]))
    }

    fn expand<T: Copy>(&self, convert: impl Fn(&[f64]) -> T) -> Vec<T> {
        self.item_semi_axes().iter().map(|l| convert(l)).collect()
    }

    /// The semi-axes of every item, groups in order: a group's distributions are drawn once,
    /// from stream `g` (the group's index) of the scene's seed, so the same scene always holds
    /// the same items.
    pub fn item_semi_axes(&self) -> Vec<Vec<f64>> {
        let mut out = Vec::with_capacity(self.item_count());
        for (g, group) in self.shapes.iter().enumerate() {
            if let Some(file) = &group.file {
                out.extend(file.semi_axes.iter().cloned());
            } else if group.size.is_none() && group.aspect.is_none() {
                out.extend(std::iter::repeat_n(group.semi_axes.clone(), group.count));
            } else {
                out.extend(drawn(group, self.seed, g).unwrap_or_else(|_| {
                    // Validation drew every group once: this cannot fail.
                    vec![group.semi_axes.clone(); group.count]
                }));
            }
        }
        out
    }

    /// How every item is oriented in a random start, groups in order.
    pub fn item_orientations(&self) -> Vec<Orientation> {
        let mut out = Vec::with_capacity(self.item_count());
        for group in &self.shapes {
            match (&group.file, &group.orientation) {
                (
                    Some(ItemFile {
                        orientations: Some(given),
                        ..
                    }),
                    _,
                ) => out.extend(given.iter().map(|o| Orientation::Given(o.clone()))),
                (_, Some(o)) => out.extend(std::iter::repeat_n(o.clone(), group.count)),
                _ => out.extend(std::iter::repeat_n(Orientation::Isotropic, group.count)),
            }
        }
        out
    }

    /// Whether each item keeps its start orientation through a random packing's compression.
    pub fn item_fixed_orientations(&self) -> Vec<bool> {
        self.shapes
            .iter()
            .flat_map(|g| std::iter::repeat_n(g.fixed_orientation, g.count))
            .collect()
    }

    /// Whether the items are not all alike within their groups (distributions or files).
    pub fn is_polydisperse(&self) -> bool {
        self.shapes
            .iter()
            .any(|g| g.size.is_some() || g.aspect.is_some() || g.file.is_some())
    }

    /// A one-line description: the name if given, else e.g. "30 ellipses (2, 1) in a
    /// minimum-area ellipse".
    pub fn title(&self) -> String {
        if let Some(name) = &self.name {
            return name.clone();
        }
        let n = self.item_count();
        let noun = match (self.dimension, n == 1) {
            (Dimension::Two, false) => "ellipses",
            (Dimension::Two, true) => "ellipse",
            (Dimension::Three, false) => "ellipsoids",
            (Dimension::Three, true) => "ellipsoid",
        };
        let axes = if self.is_polydisperse() {
            " of distributed sizes and shapes".to_string()
        } else if self.shapes.len() == 1 {
            let list: Vec<String> = self.shapes[0]
                .semi_axes
                .iter()
                .map(|l| l.to_string())
                .collect();
            format!(" ({})", list.join(", "))
        } else {
            format!(" of {} shapes", self.shapes.len())
        };
        let list = |v: &[f64]| {
            let v: Vec<String> = v.iter().map(|x| x.to_string()).collect();
            v.join(", ")
        };
        let kind = self.container;
        match &self.container_size {
            None => format!(
                "{n} {noun}{axes} in a minimum-{} {kind}",
                kind.measure_name()
            ),
            Some(ContainerSize::Radius(r)) => format!("{n} {noun}{axes} in a {kind} of radius {r}"),
            Some(ContainerSize::SemiAxes(v)) => {
                format!("{n} {noun}{axes} in a {kind} of semi-axes ({})", list(v))
            }
            Some(ContainerSize::HalfSides(v)) => {
                format!("{n} {noun}{axes} in a {kind} of half sides ({})", list(v))
            }
            Some(ContainerSize::Lengths(v)) => {
                format!("{n} {noun}{axes} in a {kind} of lengths ({})", list(v))
            }
            Some(ContainerSize::PackingFraction(f)) => {
                let random = match self.solver.start {
                    StartName::Random => "random ",
                    StartName::Lattice => "",
                };
                format!("{n} {noun}{axes}, {random}in a {kind} at packing fraction {f}")
            }
            Some(ContainerSize::Jammed) => {
                format!("{n} {noun}{axes}, random and jammed in a {kind}")
            }
        }
    }

    /// The total area (2D) or volume (3D) of the items.
    pub fn item_measure(&self) -> f64 {
        let unit = match self.dimension {
            Dimension::Two => std::f64::consts::PI,
            Dimension::Three => 4.0 * std::f64::consts::PI / 3.0,
        };
        self.item_semi_axes()
            .iter()
            .map(|l| unit * l.iter().product::<f64>())
            .sum()
    }

    /// The fixed container, centred at the origin, when the scene gives its size: with
    /// `packing_fraction` f, the container of the scene's kind whose area or volume is the
    /// items' over f — a circle or ball, a square or cube (rectangle, cuboid), a disc or
    /// sphere (ellipse, ellipsoid). `None` when the run minimises the container.
    pub fn fixed_container(&self) -> Option<Container> {
        let size = self.container_size.as_ref()?;
        let n = self.dimension.get();
        let dims: Vec<f64> = match size {
            ContainerSize::Jammed => return None,
            ContainerSize::Radius(r) => vec![*r; n],
            ContainerSize::SemiAxes(v)
            | ContainerSize::HalfSides(v)
            | ContainerSize::Lengths(v) => v.clone(),
            ContainerSize::PackingFraction(f) => self.container_at_fraction(*f),
        };
        Some(Container::unchecked(self.container, &vec![0.0; n], &dims))
    }

    /// Why a packing of the scene would lie beyond the magnitudes the model holds (centre
    /// coordinates within ±[`implicit_packing::shape::MAX_MAGNITUDE`]): its fixed container, or
    /// for a container the run shrinks the items themselves at a tenth of their area or volume,
    /// would reach beyond an eighth of it. `None` otherwise.
    pub fn beyond_model_range(&self) -> Option<String> {
        let n = self.dimension.get() as f64;
        let longest = self
            .item_semi_axes()
            .iter()
            .flatten()
            .copied()
            .fold(0.0, f64::max);
        let reach = match self.fixed_container() {
            Some(c) => c.half_extents().into_iter().fold(0.0, f64::max),
            None => (self.item_measure() / 0.1).powf(1.0 / n),
        } + 2.0 * longest;
        let limit = implicit_packing::shape::MAX_MAGNITUDE / 8.0;
        (!(0.0..=limit).contains(&reach)).then(|| {
            format!(
                "a packing of these items would reach {} from its centre, beyond the {} the \
                 model holds: rescale the lengths (or give a larger packing fraction)",
                short(reach),
                short(limit)
            )
        })
    }

    /// Why no packing of the scene's items fits its fixed container, when that is plain
    /// before any work: the items' total area or volume exceeds the container's, or an item
    /// cannot fit alone — its longest semi-axis beyond a ball's radius (or beyond the largest
    /// semi-axis or the half diagonal of other containers), or its shortest beyond the
    /// container's inradius (the item holds a ball of that radius). `None` otherwise, and for
    /// scenes that shrink their container.
    pub fn impossible_container(&self) -> Option<String> {
        let container = self.fixed_container()?;
        let fraction = self.item_measure() / container.measure();
        let what = self.container.measure_name();
        if fraction > 1.0 {
            return Some(format!(
                "the items' total {what} is {} times the container's: no packing exists",
                short(fraction)
            ));
        }
        if self.container.is_periodic() {
            return None;
        }
        let size = container.size();
        let (inradius, reach) = match self.container {
            ContainerKind::Circle | ContainerKind::Ball => (size[0], size[0]),
            ContainerKind::Rectangle | ContainerKind::Cuboid => (
                size.iter().copied().fold(f64::INFINITY, f64::min),
                size.iter().map(|h| h * h).sum::<f64>().sqrt(),
            ),
            _ => (
                size.iter().copied().fold(f64::INFINITY, f64::min),
                size.iter().copied().fold(0.0, f64::max),
            ),
        };
        self.item_semi_axes()
            .iter()
            .enumerate()
            .find_map(|(i, axes)| {
                let longest = axes.iter().copied().fold(0.0, f64::max);
                let shortest = axes.iter().copied().fold(f64::INFINITY, f64::min);
                if longest > reach {
                    Some(format!(
                        "item {i} (semi-axes {axes:?}) is longer than the container reaches \
                     ({}): no packing exists",
                        short(reach)
                    ))
                } else if shortest > inradius {
                    Some(format!(
                        "item {i} (semi-axes {axes:?}) is thicker than the container ({} across \
                     at its narrowest): no packing exists",
                        short(2.0 * inradius)
                    ))
                } else {
                    None
                }
            })
    }

    /// What a random packing compresses to (`solver.start = "random"`, or
    /// `packing_fraction = "jammed"`); `None` for a scene of the lattice starts.
    pub fn random_goal(&self) -> Option<RandomGoal> {
        if self.solver.start != StartName::Random {
            return None;
        }
        if self.container_size == Some(ContainerSize::Jammed) {
            let n = self.dimension.get();
            let dims = self.container_at_fraction(JAMMED_SHAPE_FRACTION);
            return Some(RandomGoal::Jammed(Container::unchecked(
                self.container,
                &vec![0.0; n],
                &dims,
            )));
        }
        self.fixed_container().map(RandomGoal::Fraction)
    }

    /// The dimensions of the container of the scene's kind that the items fill to fraction
    /// `f`: a circle or ball, a square or cube, a disc- or sphere-shaped ellipse or ellipsoid.
    fn container_at_fraction(&self, f: f64) -> Vec<f64> {
        let n = self.dimension.get();
        {
            {
                let measure = self.item_measure() / f;
                let unit = match (self.container, self.dimension) {
                    // (2h)ᴺ for a square or a cube of half side h.
                    (ContainerKind::Rectangle | ContainerKind::Cuboid, _) => 2f64.powi(n as i32),
                    // Lᴺ for a square or cubic cell of side L.
                    (ContainerKind::Parallelogram | ContainerKind::Parallelepiped, _) => 1.0,
                    (_, Dimension::Two) => std::f64::consts::PI,
                    (_, Dimension::Three) => 4.0 * std::f64::consts::PI / 3.0,
                };
                vec![(measure / unit).powf(1.0 / n as f64); n]
            }
        }
    }

    /// The scene as TOML that [`Scene::from_toml_str`] reads back to an equal scene (every
    /// setting written out, floats in their shortest exact form).
    pub fn to_toml_string(&self) -> String {
        let mut out = String::new();
        let line = |out: &mut String, key: &str, value: String| {
            out.push_str(key);
            out.push_str(" = ");
            out.push_str(&value);
            out.push('\n');
        };
        if let Some(name) = &self.name {
            line(&mut out, "name", toml_string(name));
        }
        line(&mut out, "dimension", self.dimension.get().to_string());
        // TOML integers stop at i64::MAX; the reader takes larger seeds as strings.
        if i64::try_from(self.seed).is_ok() {
            line(&mut out, "seed", self.seed.to_string());
        } else {
            line(&mut out, "seed", toml_string(&self.seed.to_string()));
        }
        out.push_str("\n[container]\n");
        line(&mut out, "kind", toml_string(self.container.name()));
        if self.container.is_periodic() {
            let cell = if self.container_size.is_some() {
                "fixed"
            } else {
                "variable"
            };
            line(&mut out, "cell", toml_string(cell));
        }
        match &self.container_size {
            None => {}
            Some(ContainerSize::Radius(r)) => line(&mut out, "radius", toml_float(*r)),
            Some(
                size @ (ContainerSize::SemiAxes(v)
                | ContainerSize::HalfSides(v)
                | ContainerSize::Lengths(v)),
            ) => {
                let v: Vec<String> = v.iter().map(|x| toml_float(*x)).collect();
                line(&mut out, size.key(), format!("[{}]", v.join(", ")));
            }
            Some(ContainerSize::PackingFraction(f)) => {
                line(&mut out, "packing_fraction", toml_float(*f));
            }
            Some(ContainerSize::Jammed) => {
                line(&mut out, "packing_fraction", toml_string("jammed"));
            }
        }
        for g in &self.shapes {
            out.push_str("\n[[shapes]]\n");
            if let Some(file) = &g.file {
                line(
                    &mut out,
                    "file",
                    toml_string(&file.path.display().to_string()),
                );
            } else {
                line(&mut out, "count", g.count.to_string());
                let axes: Vec<String> = g.semi_axes.iter().map(|l| toml_float(*l)).collect();
                line(&mut out, "semi_axes", format!("[{}]", axes.join(", ")));
            }
            for (key, d) in [("size", &g.size), ("aspect", &g.aspect)] {
                if let Some(d) = d {
                    line(&mut out, key, distribution_toml(d));
                }
            }
            let mut parts = Vec::new();
            if let Some(Orientation::Aligned {
                axis,
                concentration,
            }) = &g.orientation
            {
                let n = self.dimension.get();
                let axis: Vec<String> = axis[..n].iter().map(|v| toml_float(*v)).collect();
                parts.push(format!("axis = [{}]", axis.join(", ")));
                parts.push(format!("concentration = {}", toml_float(*concentration)));
            }
            if g.fixed_orientation {
                parts.push("fixed = true".to_string());
            }
            if !parts.is_empty() {
                line(
                    &mut out,
                    "orientation",
                    format!("{{ {} }}", parts.join(", ")),
                );
            }
        }
        let s = &self.solver;
        out.push_str("\n[solver]\n");
        line(
            &mut out,
            "feasibility_tolerance",
            toml_float(s.feasibility_tolerance),
        );
        line(
            &mut out,
            "optimality_tolerance",
            toml_float(s.optimality_tolerance),
        );
        line(
            &mut out,
            "time_limit",
            toml_float(s.time_limit.as_secs_f64()),
        );
        line(&mut out, "threads", s.threads.to_string());
        if let Some(n) = s.local_minimisations {
            line(&mut out, "local_minimisations", n.to_string());
        }
        line(&mut out, "inner_solver", toml_string(s.inner_solver.name()));
        line(&mut out, "method", toml_string(s.method.name()));
        line(&mut out, "start", toml_string(s.start.name()));
        line(&mut out, "perturbation", toml_float(s.perturbation));
        line(&mut out, "lattice_starts", s.lattice_starts.to_string());
        line(&mut out, "from_best", s.from_best.to_string());
        line(
            &mut out,
            "perturbation_levels",
            s.perturbation_levels.to_string(),
        );
        line(
            &mut out,
            "fresh_lattice_every",
            s.fresh_lattice_every.to_string(),
        );
        line(&mut out, "restart_after", s.restart_after.to_string());
        line(&mut out, "widen_after", s.widen_after.to_string());
        let o = &self.output;
        out.push_str("\n[output]\n");
        if let Some(dir) = &o.directory {
            line(
                &mut out,
                "directory",
                toml_string(&dir.display().to_string()),
            );
        }
        line(&mut out, "pictures", o.pictures.to_string());
        line(&mut out, "xyz", o.xyz.to_string());
        line(&mut out, "image_width", o.image_width.to_string());
        out
    }
}

impl fmt::Display for Scene {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.title())
    }
}

fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// Rust's `Debug` for f64 is the shortest string that reads back exactly, and always has a
/// `.` or an exponent, which TOML needs to see a float.
fn toml_float(x: f64) -> String {
    format!("{x:?}")
}

struct Validator<'a> {
    /// The scene's TOML text, `None` for a table (whose messages have no line).
    text: Option<&'a str>,
    source_name: &'a str,
    /// Whether `source_name` is the scene's path (item files are relative to its folder).
    from_file: bool,
}

impl Validator<'_> {
    fn error(&self, span: std::ops::Range<usize>, key: &str, message: String) -> SceneError {
        let (line, column) = self.text.map_or((0, 0), |t| line_column(t, span.start));
        SceneError {
            source_name: self.source_name.to_string(),
            line,
            column,
            key: key.to_string(),
            message,
        }
    }

    fn positive(&self, value: &Option<Spanned<f64>>, key: &str) -> Result<Option<f64>, SceneError> {
        match value {
            None => Ok(None),
            Some(v) if v.get_ref().is_finite() && *v.get_ref() > 0.0 => Ok(Some(*v.get_ref())),
            Some(v) => Err(self.error(
                v.span(),
                key,
                format!("must be positive and finite, not {}", short(*v.get_ref())),
            )),
        }
    }

    /// `container.cell`: only for a periodic cell; `"variable"` (the cell's lattice vectors
    /// are variables; the default without a size) or `"fixed"` (a given cell: `lengths` or
    /// `packing_fraction`, the default with one).
    fn cell(
        &self,
        raw: &RawContainer,
        kind: ContainerKind,
        size: Option<&ContainerSize>,
    ) -> Result<(), SceneError> {
        let Some(cell) = &raw.cell else {
            return Ok(());
        };
        if !kind.is_periodic() {
            return Err(self.error(
                cell.span(),
                "container.cell",
                format!("only a periodic container has a cell, not a {kind}"),
            ));
        }
        match (cell.get_ref().as_str(), size) {
            ("variable", None) | ("fixed", Some(_)) => Ok(()),
            ("variable", Some(size)) => Err(self.error(
                cell.span(),
                "container.cell",
                format!(
                    "a variable cell has no {}: write cell = \"fixed\" to fill a given cell",
                    size.key()
                ),
            )),
            ("fixed", None) => Err(self.error(
                cell.span(),
                "container.cell",
                "a fixed cell needs its size: lengths = [..] (an orthogonal box) or \
                 packing_fraction = .."
                    .to_string(),
            )),
            (other, _) => Err(self.error(
                cell.span(),
                "container.cell",
                format!(
                    "must be \"variable\" (the densest periodic packing) or \"fixed\" (a \
                     given cell), not {}",
                    crate::table::short_text(&format!("{other:?}"))
                ),
            )),
        }
    }

    fn scene(&self, raw: RawScene) -> Result<Scene, SceneError> {
        let dimension = match *raw.dimension.get_ref() {
            2 => Dimension::Two,
            3 => Dimension::Three,
            d => {
                return Err(self.error(
                    raw.dimension.span(),
                    "dimension",
                    format!("must be 2 (ellipses) or 3 (ellipsoids), not {d}"),
                ));
            }
        };
        let mut kind = *raw.container.kind.get_ref();
        if kind.is_periodic() {
            // `periodic` names the cell of the scene's dimension.
            kind = ContainerKind::named(kind.name(), dimension.get()).unwrap_or(kind);
        }
        if kind.dimension() != dimension.get() {
            let choices = match dimension {
                Dimension::Two => "circle, ellipse, rectangle or periodic",
                Dimension::Three => "ball, ellipsoid, cuboid or periodic",
            };
            return Err(self.error(
                raw.container.kind.span(),
                "container.kind",
                format!(
                    "a {kind} is a {}D container; with dimension = {} use {choices}",
                    kind.dimension(),
                    dimension.get()
                ),
            ));
        }
        let container_size = self.container_size(&raw.container, kind, dimension)?;
        self.cell(&raw.container, kind, container_size.as_ref())?;
        let seed = match &raw.seed {
            None => 0,
            Some(s) => {
                let (value, written) = match s.get_ref() {
                    RawScalar::Integer(n) => (u64::try_from(*n).ok(), n.to_string()),
                    RawScalar::Real(f) => (None, f.to_string()),
                    RawScalar::Text(t) => (t.trim().parse::<u64>().ok(), format!("{t:?}")),
                };
                value.ok_or_else(|| {
                    self.error(
                        s.span(),
                        "seed",
                        format!(
                            "must be a non-negative whole number, at most 18446744073709551615 \
                             (a seed beyond 9223372036854775807 may be written as a string, \
                             seed = \"18446744073709551615\"), not {}",
                            crate::table::short_text(&written)
                        ),
                    )
                })?
            }
        };
        let orientation_at: Option<(usize, std::ops::Range<usize>)> =
            raw.shapes.as_ref().and_then(|list| {
                list.get_ref()
                    .iter()
                    .enumerate()
                    .find_map(|(i, g)| g.get_ref().orientation.as_ref().map(|o| (i, o.span())))
            });
        let shapes_span = raw.shapes.as_ref().map_or(0..0, Spanned::span);
        let shapes = self.shapes(raw.shapes, dimension, seed)?;
        let start = raw
            .solver
            .as_ref()
            .and_then(|s| s.start.as_ref())
            .map(|s| (s.span(), *s.get_ref()));
        let mut solver = self.solver(raw.solver, dimension)?;
        match (start, &container_size) {
            (Some((span, StartName::Lattice)), Some(ContainerSize::Jammed)) => {
                return Err(self.error(
                    span,
                    "solver.start",
                    "packing_fraction = \"jammed\" is a random packing: write start = \
                     \"random\" or leave start out"
                        .to_string(),
                ));
            }
            (Some((span, StartName::Random)), None) => {
                return Err(self.error(
                    span,
                    "solver.start",
                    "a random packing needs its container: give [container] packing_fraction \
                     = 0.6 (or \"jammed\") or the container's size"
                        .to_string(),
                ));
            }
            (_, Some(ContainerSize::Jammed)) => solver.start = StartName::Random,
            _ => {}
        }
        if let (Some((i, span)), StartName::Lattice) = (orientation_at, solver.start) {
            return Err(self.error(
                span,
                &format!("shapes[{i}].orientation"),
                "orientations are drawn in random starts: give [solver] start = \"random\" \
                 (or packing_fraction = \"jammed\")"
                    .to_string(),
            ));
        }
        let output = self.output(raw.output)?;
        let scene = Scene {
            name: raw.name,
            dimension,
            container: kind,
            container_size,
            shapes,
            solver,
            seed,
            output,
        };
        // A refusal of the container names the size key the scene gave (the first of them);
        // one of items too large for the model, the shapes when no size was given.
        let size_key = raw.container.size_keys().into_iter().next();
        if let Some(reason) = scene.beyond_model_range() {
            let (key, span) = match (&size_key, scene.fixed_container()) {
                (Some((key, span)), Some(_)) => (format!("container.{key}"), span.clone()),
                _ => ("shapes".to_string(), shapes_span),
            };
            return Err(self.error(span, &key, reason));
        }
        if let Some(reason) = scene.impossible_container() {
            let (key, span) = size_key.unwrap_or(("kind", raw.container.kind.span()));
            return Err(self.error(span, &format!("container.{key}"), reason));
        }
        Ok(scene)
    }

    /// The size of a fixed container from the `[container]` keys, checked against the kind.
    fn container_size(
        &self,
        raw: &RawContainer,
        kind: ContainerKind,
        dimension: Dimension,
    ) -> Result<Option<ContainerSize>, SceneError> {
        let given = raw.size_keys();
        if given.len() > 1 {
            // The key written later in the file is the one reported.
            let mut by_position = given.clone();
            by_position.sort_by_key(|(_, span)| span.start);
            let (first, first_span) = &by_position[0];
            let (second, second_span) = &by_position[1];
            let first = match self.text {
                Some(text) => format!("{first} (line {})", line_column(text, first_span.start).0),
                None => first.to_string(),
            };
            return Err(self.error(
                second_span.clone(),
                &format!("container.{second}"),
                format!(
                    "a container has one size: give one of radius, semi_axes, half_sides, lengths or \
                     packing_fraction, not both {first} and {second}"
                ),
            ));
        }
        let size_of = |key: &str| match kind {
            ContainerKind::Circle | ContainerKind::Ball => key == "radius",
            ContainerKind::Ellipse | ContainerKind::Ellipsoid => key == "semi_axes",
            ContainerKind::Rectangle | ContainerKind::Cuboid => key == "half_sides",
            ContainerKind::Parallelogram | ContainerKind::Parallelepiped => key == "lengths",
        };
        let own_key = ["radius", "semi_axes", "half_sides", "lengths"]
            .into_iter()
            .find(|k| size_of(k))
            .unwrap_or("radius");
        let Some((key, span)) = given.into_iter().next() else {
            return Ok(None);
        };
        let full_key = format!("container.{key}");
        if key != "packing_fraction" && !size_of(key) {
            return Err(self.error(
                span,
                &full_key,
                format!(
                    "{} {kind} has no {}; give its {} = {} or packing_fraction",
                    if kind.name().starts_with(['a', 'e', 'i', 'o', 'u']) {
                        "an"
                    } else {
                        "a"
                    },
                    key.replace('_', " "),
                    own_key,
                    if own_key == "radius" {
                        "12.0".to_string()
                    } else {
                        format!("[{}]", vec!["…"; dimension.get()].join(", "))
                    }
                ),
            ));
        }
        let length = |v: f64, what: String| {
            if (SEMI_AXIS_RANGE.0..=SEMI_AXIS_RANGE.1).contains(&v) {
                Ok(v)
            } else {
                Err(self.error(
                    span.clone(),
                    &full_key,
                    format!(
                        "{what} is {}; it must be positive, in [{}, {}]",
                        short(v),
                        short(SEMI_AXIS_RANGE.0),
                        short(SEMI_AXIS_RANGE.1)
                    ),
                ))
            }
        };
        let lengths = |v: &Vec<f64>| {
            if v.len() != dimension.get() {
                return Err(self.error(
                    span.clone(),
                    &full_key,
                    format!(
                        "{} values for dimension = {}: give {}",
                        v.len(),
                        dimension.get(),
                        dimension.get()
                    ),
                ));
            }
            v.iter()
                .enumerate()
                .map(|(k, &x)| length(x, format!("value {}", k + 1)))
                .collect::<Result<Vec<f64>, _>>()
        };
        let given = |v: &Option<Spanned<Vec<f64>>>| {
            lengths(v.as_ref().map(Spanned::get_ref).unwrap_or(&Vec::new()))
        };
        Ok(Some(match key {
            "radius" => ContainerSize::Radius(length(
                raw.radius.as_ref().map_or(0.0, |r| *r.get_ref()),
                "the radius".into(),
            )?),
            "semi_axes" => ContainerSize::SemiAxes(given(&raw.semi_axes)?),
            "half_sides" => ContainerSize::HalfSides(given(&raw.half_sides)?),
            "lengths" => ContainerSize::Lengths(given(&raw.lengths)?),
            _ => {
                let f = match raw.packing_fraction.as_ref().map(Spanned::get_ref) {
                    Some(RawScalar::Real(f)) => *f,
                    Some(RawScalar::Integer(n)) => *n as f64,
                    Some(RawScalar::Text(w)) if w == "jammed" => {
                        return Ok(Some(ContainerSize::Jammed));
                    }
                    Some(RawScalar::Text(w)) => {
                        return Err(self.error(
                            span,
                            &full_key,
                            format!(
                                "must be a number in (0, 1) or \"jammed\" (a random packing \
                                 compressed until jammed), not {}",
                                crate::table::short_text(&format!("{w:?}"))
                            ),
                        ));
                    }
                    None => f64::NAN,
                };
                if !(f > 0.0 && f < 1.0) {
                    return Err(self.error(
                        span,
                        &full_key,
                        format!(
                            "must be in (0, 1): the fraction of the container the items fill, \
                             not {}",
                            short(f)
                        ),
                    ));
                }
                ContainerSize::PackingFraction(f)
            }
        }))
    }

    fn shapes(
        &self,
        raw: Option<Spanned<Vec<Spanned<RawShapes>>>>,
        dimension: Dimension,
        seed: u64,
    ) -> Result<Vec<ShapeGroup>, SceneError> {
        let empty = "the scene has nothing to pack: add a [[shapes]] table with `count` and \
                     `semi_axes`";
        let Some(raw) = raw else {
            return Err(self.error(0..0, "shapes", empty.to_string()));
        };
        if raw.get_ref().is_empty() {
            return Err(self.error(raw.span(), "shapes", empty.to_string()));
        }
        let mut total = 0usize;
        let mut groups = Vec::new();
        for (i, spanned) in raw.into_inner().into_iter().enumerate() {
            let span = spanned.span();
            let g = spanned.into_inner();
            let group = match &g.file {
                Some(file) => self.file_group(i, &g, file, dimension)?,
                None => self.drawn_group(i, &g, span, dimension)?,
            };
            let key = format!("shapes[{i}].count");
            total = total.saturating_add(group.count);
            if total > MAX_ITEMS {
                let span = g
                    .count
                    .as_ref()
                    .map_or(g.file.as_ref().map_or(0..0, Spanned::span), Spanned::span);
                return Err(self.error(
                    span,
                    &key,
                    format!("the scene would hold {total} items, more than {MAX_ITEMS}"),
                ));
            }
            if let Err(e) = drawn(&group, seed, i) {
                let span = g
                    .size
                    .as_ref()
                    .or(g.aspect.as_ref())
                    .map_or(0..0, Spanned::span);
                return Err(self.error(span, &format!("shapes[{i}]"), e.to_string()));
            }
            groups.push(group);
        }
        Ok(groups)
    }

    /// A group of `count` items of `semi_axes`, with their distributions and orientation.
    fn drawn_group(
        &self,
        i: usize,
        g: &RawShapes,
        span: std::ops::Range<usize>,
        dimension: Dimension,
    ) -> Result<ShapeGroup, SceneError> {
        let missing = |field: &str| {
            self.error(
                span.clone(),
                &format!("shapes[{i}].{field}"),
                format!(
                    "missing field `{field}`: each group needs count and semi_axes, or file = \
                     \"items.csv\""
                ),
            )
        };
        let count_value = g.count.as_ref().ok_or_else(|| missing("count"))?;
        let raw_axes = g.semi_axes.as_ref().ok_or_else(|| missing("semi_axes"))?;
        let count = *count_value.get_ref();
        if count < 1 {
            return Err(self.error(
                count_value.span(),
                &format!("shapes[{i}].count"),
                format!("must be at least 1, not {count}"),
            ));
        }
        // `count` is positive; beyond usize it is beyond MAX_ITEMS too.
        let count = usize::try_from(count).unwrap_or(usize::MAX);
        let axes = raw_axes.get_ref();
        let semi_axes = self.semi_axes(
            axes,
            raw_axes.span(),
            &format!("shapes[{i}].semi_axes"),
            dimension,
        )?;
        let mut group = ShapeGroup::identical(count, semi_axes);
        group.size = self.distribution(g.size.as_ref(), &format!("shapes[{i}].size"))?;
        group.aspect = self.distribution(g.aspect.as_ref(), &format!("shapes[{i}].aspect"))?;
        (group.orientation, group.fixed_orientation) =
            self.orientation(g.orientation.as_ref(), i, dimension)?;
        Ok(group)
    }

    /// The semi-axes of one item, checked: as many as the dimension, each in range.
    fn semi_axes(
        &self,
        axes: &[f64],
        span: std::ops::Range<usize>,
        key: &str,
        dimension: Dimension,
    ) -> Result<Vec<f64>, SceneError> {
        if axes.len() != dimension.get() {
            return Err(self.error(
                span,
                key,
                format!(
                    "{} values for dimension = {}: give {} semi-axes",
                    axes.len(),
                    dimension.get(),
                    dimension.get()
                ),
            ));
        }
        if let Some((k, l)) = axes
            .iter()
            .enumerate()
            .find(|(_, l)| !(SEMI_AXIS_RANGE.0..=SEMI_AXIS_RANGE.1).contains(*l))
        {
            return Err(self.error(
                span,
                key,
                format!(
                    "semi-axis {} is {}; every semi-axis must be positive, in [{}, {}]",
                    k + 1,
                    short(*l),
                    short(SEMI_AXIS_RANGE.0),
                    short(SEMI_AXIS_RANGE.1)
                ),
            ));
        }
        Ok(axes.to_vec())
    }

    /// A `size` or `aspect` table: `distribution` (`"lognormal"`, `"normal"`, `"uniform"`),
    /// `sigma` (lognormal, normal), `min` and `max` (cut-offs; required for uniform).
    fn distribution(
        &self,
        raw: Option<&Spanned<RawDistribution>>,
        key: &str,
    ) -> Result<Option<Distribution>, SceneError> {
        let Some(raw) = raw else { return Ok(None) };
        let (span, d) = (raw.span(), raw.get_ref());
        let refuse = |message: String| self.error(span.clone(), key, message);
        let needs = |value: Option<f64>, what: &str| {
            value.ok_or_else(|| refuse(format!("a {} distribution needs {what}", d.distribution)))
        };
        let bounds = (d.min.unwrap_or(1e-3), d.max.unwrap_or(1e3));
        let distribution = match d.distribution.as_str() {
            "lognormal" => Distribution::LogNormal {
                sigma: needs(d.sigma, "sigma (of ln s)")?,
                min: bounds.0,
                max: bounds.1,
            },
            "normal" => Distribution::Normal {
                sigma: needs(d.sigma, "sigma")?,
                min: bounds.0,
                max: bounds.1,
            },
            "uniform" => {
                if d.sigma.is_some() {
                    return Err(refuse(
                        "a uniform distribution has no sigma: give min and max".into(),
                    ));
                }
                Distribution::Uniform {
                    min: needs(d.min, "min")?,
                    max: needs(d.max, "max")?,
                }
            }
            other => {
                return Err(refuse(format!(
                    "distribution must be \"lognormal\", \"normal\" or \"uniform\", not {}",
                    crate::table::short_text(&format!("{other:?}"))
                )));
            }
        };
        match distribution.defect() {
            Some(defect) => Err(refuse(defect)),
            None => Ok(Some(distribution)),
        }
    }

    /// An `orientation` table: `axis` (the dimension's components) and `concentration` ≥ 0,
    /// both or neither, and `fixed`.
    fn orientation(
        &self,
        raw: Option<&Spanned<RawOrientation>>,
        i: usize,
        dimension: Dimension,
    ) -> Result<(Option<Orientation>, bool), SceneError> {
        let Some(raw) = raw else {
            return Ok((None, false));
        };
        let (span, o) = (raw.span(), raw.get_ref());
        let key = format!("shapes[{i}].orientation");
        let fixed = o.fixed.unwrap_or(false);
        let (axis, concentration) = match (&o.axis, o.concentration) {
            (Some(axis), Some(c)) => (axis, c),
            (None, None) => return Ok((None, fixed)),
            _ => {
                return Err(self.error(
                    span,
                    &key,
                    "give both axis and concentration (aligned), or neither (isotropic)".into(),
                ));
            }
        };
        let n = dimension.get();
        let norm = axis.iter().map(|v| v * v).sum::<f64>().sqrt();
        if axis.len() != n || !(norm > 0.0 && norm.is_finite()) {
            return Err(self.error(
                span,
                &key,
                format!("axis must be {n} finite values, not all zero"),
            ));
        }
        if !(concentration >= 0.0 && concentration.is_finite()) {
            return Err(self.error(
                span,
                &key,
                format!(
                    "concentration must be zero (isotropic) or positive and finite, not {}",
                    short(concentration)
                ),
            ));
        }
        let axis = std::array::from_fn(|k| axis.get(k).copied().unwrap_or(0.0));
        Ok((
            Some(Orientation::Aligned {
                axis,
                concentration,
            }),
            fixed,
        ))
    }

    /// A group read from an item file (relative to the scene's folder).
    fn file_group(
        &self,
        i: usize,
        g: &RawShapes,
        file: &Spanned<String>,
        dimension: Dimension,
    ) -> Result<ShapeGroup, SceneError> {
        let key = format!("shapes[{i}].file");
        let given = [
            ("count", g.count.as_ref().map(Spanned::span)),
            ("semi_axes", g.semi_axes.as_ref().map(Spanned::span)),
            ("size", g.size.as_ref().map(Spanned::span)),
            ("aspect", g.aspect.as_ref().map(Spanned::span)),
        ];
        if let Some((other, Some(span))) = given.into_iter().find(|(_, s)| s.is_some()) {
            return Err(self.error(
                span,
                &format!("shapes[{i}].{other}"),
                format!("a group read from a file has no {other}: the file's rows give the items"),
            ));
        }
        let path = PathBuf::from(file.get_ref());
        let full = match Path::new(self.source_name).parent() {
            Some(dir) if path.is_relative() && self.from_file => dir.join(&path),
            _ => path.clone(),
        };
        let text = std::fs::read_to_string(&full)
            .map_err(|e| self.error(file.span(), &key, format!("{}: {e}", full.display())))?;
        let items = read_item_file(&text, &full.display().to_string(), dimension)?;
        let count = items.semi_axes.len();
        let mut group = ShapeGroup::identical(count, items.semi_axes[0].clone());
        (group.orientation, group.fixed_orientation) =
            self.orientation(g.orientation.as_ref(), i, dimension)?;
        if group.orientation.is_some() && items.orientations.is_some() {
            return Err(self.error(
                file.span(),
                &format!("shapes[{i}].orientation"),
                "the file gives each item's orientation: leave axis and concentration out".into(),
            ));
        }
        group.file = Some(ItemFile { path, ..items });
        Ok(group)
    }

    fn solver(
        &self,
        raw: Option<RawSolver>,
        dimension: Dimension,
    ) -> Result<SolverSettings, SceneError> {
        let mut s = SolverSettings::defaults(dimension);
        let Some(raw) = raw else { return Ok(s) };
        if let Some(v) =
            self.positive(&raw.feasibility_tolerance, "solver.feasibility_tolerance")?
        {
            s.feasibility_tolerance = v;
        }
        if let Some(v) = self.positive(&raw.optimality_tolerance, "solver.optimality_tolerance")? {
            s.optimality_tolerance = v;
        }
        if let Some(v) = self.positive(&raw.time_limit, "solver.time_limit")? {
            let span = raw.time_limit.as_ref().map_or(0..0, Spanned::span);
            s.time_limit = time_limit(v).ok_or_else(|| {
                // Positive and finite already: too long for a clock, or below a nanosecond.
                let why = if v > 1.0 {
                    "is too long"
                } else {
                    "is shorter than a nanosecond"
                };
                self.error(
                    span,
                    "solver.time_limit",
                    format!("{} seconds {why}", short(v)),
                )
            })?;
        }
        if let Some(t) = &raw.threads {
            s.threads = usize::try_from(*t.get_ref()).map_err(|_| {
                self.error(
                    t.span(),
                    "solver.threads",
                    format!(
                        "must be 0 (every core) or a positive count, not {}",
                        t.get_ref()
                    ),
                )
            })?;
        }
        if let Some(n) = &raw.local_minimisations {
            s.local_minimisations = Some(self.count(n, "solver.local_minimisations", 1)?);
        }
        if let Some(solver) = raw.inner_solver {
            s.inner_solver = solver;
        }
        if let Some(method) = raw.method {
            s.method = method;
        }
        if let Some(start) = &raw.start {
            s.start = *start.get_ref();
        }
        if let Some(p) = &raw.perturbation {
            let v = *p.get_ref();
            if !(0.0..1.0).contains(&v) {
                return Err(self.error(
                    p.span(),
                    "solver.perturbation",
                    format!(
                        "must be in [0, 1) (a fraction, 0.025 is 2.5 %), not {}",
                        short(v)
                    ),
                ));
            }
            s.perturbation = v;
        }
        if let Some(n) = &raw.lattice_starts {
            s.lattice_starts = self.count(n, "solver.lattice_starts", 0)?;
        }
        if let Some(n) = &raw.fresh_lattice_every {
            s.fresh_lattice_every = self.count(n, "solver.fresh_lattice_every", 0)?;
        }
        if let Some(n) = &raw.restart_after {
            s.restart_after = self.count(n, "solver.restart_after", 0)?;
        }
        if let Some(n) = &raw.widen_after {
            s.widen_after = self.count(n, "solver.widen_after", 0)?;
        }
        if let Some(n) = &raw.perturbation_levels {
            let v = self.count(n, "solver.perturbation_levels", 1)?;
            s.perturbation_levels = u32::try_from(v.min(64)).unwrap_or(64);
        }
        if let Some(b) = raw.from_best {
            s.from_best = b;
        }
        Ok(s)
    }

    /// A whole number of at least `least` from the scene, or an error naming `key`.
    fn count(&self, n: &Spanned<i64>, key: &str, least: i64) -> Result<u64, SceneError> {
        let v = *n.get_ref();
        if v < least {
            return Err(self.error(
                n.span(),
                key,
                format!("must be a whole number of at least {least}, not {v}"),
            ));
        }
        Ok(v.unsigned_abs())
    }

    fn output(&self, raw: Option<RawOutput>) -> Result<OutputOptions, SceneError> {
        let mut o = OutputOptions::default();
        let Some(raw) = raw else { return Ok(o) };
        o.directory = raw.directory.map(PathBuf::from);
        o.pictures = raw.pictures.unwrap_or(o.pictures);
        o.xyz = raw.xyz.unwrap_or(o.xyz);
        if let Some(w) = &raw.image_width {
            let v = *w.get_ref();
            o.image_width = u32::try_from(v)
                .ok()
                .filter(|w| (200..=8000).contains(w))
                .ok_or_else(|| {
                    self.error(
                        w.span(),
                        "output.image_width",
                        format!("must be between 200 and 8000 pixels, not {v}"),
                    )
                })?;
        }
        Ok(o)
    }
}

/// The semi-axes of a group's items drawn from its distributions
/// ([`ellipsoid_packer::random::draw_semi_axes`], stream `g` of `seed`).
fn drawn(
    group: &ShapeGroup,
    seed: u64,
    g: usize,
) -> Result<Vec<Vec<f64>>, ellipsoid_packer::Error> {
    if group.size.is_none() && group.aspect.is_none() {
        return Ok(vec![group.semi_axes.clone(); group.count]);
    }
    let (size, aspect) = (group.size.as_ref(), group.aspect.as_ref());
    let g = g as u64;
    Ok(match *group.semi_axes.as_slice() {
        [a, b] => {
            ellipsoid_packer::random::draw_semi_axes(&[a, b], group.count, size, aspect, seed, g)?
                .into_iter()
                .map(|l| l.to_vec())
                .collect()
        }
        [a, b, c] => ellipsoid_packer::random::draw_semi_axes(
            &[a, b, c],
            group.count,
            size,
            aspect,
            seed,
            g,
        )?
        .into_iter()
        .map(|l| l.to_vec())
        .collect(),
        _ => vec![group.semi_axes.clone(); group.count],
    })
}

/// The TOML inline table of a distribution.
fn distribution_toml(d: &Distribution) -> String {
    match *d {
        Distribution::LogNormal { sigma, min, max } | Distribution::Normal { sigma, min, max } => {
            let name = if matches!(d, Distribution::LogNormal { .. }) {
                "lognormal"
            } else {
                "normal"
            };
            format!(
                "{{ distribution = \"{name}\", sigma = {}, min = {}, max = {} }}",
                toml_float(sigma),
                toml_float(min),
                toml_float(max)
            )
        }
        Distribution::Uniform { min, max } => format!(
            "{{ distribution = \"uniform\", min = {}, max = {} }}",
            toml_float(min),
            toml_float(max)
        ),
    }
}

/// An item file's rows ([`ItemFile`]); errors name the file, the line and the column.
fn read_item_file(text: &str, name: &str, dimension: Dimension) -> Result<ItemFile, SceneError> {
    let at = |line: usize, key: &str, message: String| SceneError {
        source_name: name.to_string(),
        line,
        column: 1,
        key: key.to_string(),
        message,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let Some((_, header)) = lines.next() else {
        return Err(at(
            1,
            "<header>",
            "the file is empty: give a header and one row per item".into(),
        ));
    };
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    let find = |c: &str| columns.iter().position(|h| *h == c);
    let axis_names: &[&str] = if dimension == Dimension::Two {
        &["a", "b"]
    } else {
        &["a", "b", "c"]
    };
    let orientation_names: &[&str] = if dimension == Dimension::Two {
        &["theta"]
    } else {
        &["qw", "qx", "qy", "qz"]
    };
    let mut axis_columns = Vec::new();
    for c in axis_names {
        axis_columns.push(find(c).ok_or_else(|| {
            at(
                1,
                "<header>",
                format!(
                    "no column `{c}`: the header must name {}",
                    axis_names.join(", ")
                ),
            )
        })?);
    }
    let orientation_columns: Option<Vec<usize>> =
        orientation_names.iter().map(|c| find(c)).collect();
    let mut semi_axes = Vec::new();
    let mut orientations = Vec::new();
    for (index, line) in lines {
        let number = index + 1;
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let value = |k: usize, name: &str| -> Result<f64, SceneError> {
            let field = fields.get(k).copied().unwrap_or("");
            field
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    at(
                        number,
                        name,
                        format!(
                            "{} is not a finite number",
                            crate::table::short_text(&format!("{field:?}"))
                        ),
                    )
                })
        };
        let mut l = Vec::with_capacity(axis_columns.len());
        for (&k, name) in axis_columns.iter().zip(axis_names) {
            let v = value(k, name)?;
            if !(SEMI_AXIS_RANGE.0..=SEMI_AXIS_RANGE.1).contains(&v) {
                return Err(at(
                    number,
                    name,
                    format!(
                        "the semi-axis is {}; every semi-axis must be positive, in [{}, {}]",
                        short(v),
                        short(SEMI_AXIS_RANGE.0),
                        short(SEMI_AXIS_RANGE.1)
                    ),
                ));
            }
            l.push(v);
        }
        semi_axes.push(l);
        if let Some(cols) = &orientation_columns {
            let o = cols
                .iter()
                .zip(orientation_names)
                .map(|(&k, name)| value(k, name))
                .collect::<Result<Vec<f64>, _>>()?;
            if o.len() == 4 {
                let norm2: f64 = o.iter().map(|v| v * v).sum();
                if (norm2 - 1.0).abs() > implicit_packing::shape::QUATERNION_TOLERANCE {
                    return Err(at(
                        number,
                        "qw",
                        format!("the quaternion's squared norm is {norm2}, not 1"),
                    ));
                }
            }
            orientations.push(o);
        }
        if semi_axes.len() > MAX_ITEMS {
            return Err(at(number, "<rows>", format!("more than {MAX_ITEMS} items")));
        }
    }
    if semi_axes.is_empty() {
        return Err(at(1, "<rows>", "the file has a header but no items".into()));
    }
    Ok(ItemFile {
        path: PathBuf::from(name),
        semi_axes,
        orientations: orientation_columns.map(|_| orientations),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_scene_parses() {
        let scene = Scene::default_scene();
        assert_eq!(scene.dimension, Dimension::Two);
        assert_eq!(scene.container, ContainerKind::Ellipse);
        assert_eq!(scene.item_count(), 30);
        assert_eq!(scene.shapes[0].semi_axes, vec![2.0, 1.0]);
        assert!(scene.solver.time_limit < Duration::from_secs(60));
    }

    #[test]
    fn the_default_solver_settings_are_the_packers() {
        let run = MultiStartSettings::recommended(3, 0);
        let s = SolverSettings::defaults(Dimension::Three);
        assert_eq!(
            InnerSolverName::of(run.local.inner_solver),
            Some(s.inner_solver)
        );
        assert_eq!(MethodName::of(run.local.method), Some(s.method));
        assert_eq!(s.inner_solver.solver(), run.local.inner_solver);
        assert_eq!(s.method.method(), run.local.method);
        assert_eq!(s.feasibility_tolerance, run.local.feasibility_tolerance);
        assert_eq!(SolverSettings::defaults(Dimension::Two).perturbation, 0.025);
    }
}
