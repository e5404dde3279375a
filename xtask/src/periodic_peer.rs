//! `cargo xtask periodic-peer`: ellipsoids (1, 0.75, 0.5) in a periodic box, packed by
//! ellipack and by hoomd-rs (hard-particle Monte Carlo with its `QuickCompress`), one thread
//! each, on this machine; and the cost of hoomd-rs's ellipsoid overlap test beside
//! `pw85::overlap` on the same random pairs.
//!
//! hoomd-rs is compiled only with the `peer` feature of xtask
//! (`cargo xtask --features peer periodic-peer` does not parse: the alias ends in `--`; use
//! `cargo run --release -p xtask --features peer -- periodic-peer`). Every packing fraction the
//! study records for the peer is certified by [`certify_periodic`] — implicit-packing's
//! certificate, the one every packing of ellipack passes: PW85 on every pair image within
//! reach — not by the peer's own test.
//!
//! Writes `validation/periodic_peer.csv` (the density–time points),
//! `validation/periodic_peer_runs.csv` (one row per run), `validation/periodic_peer_overlap.csv`
//! (the overlap-test cost), the figure `docs/figures/periodic-density-time.{svg,png}` and the
//! section between the markers in `docs/periodic.md`. A run replaces the rows of the
//! (who, N) it ran and keeps the others, so the peer and ours can be measured separately.

use crate::error::{self, Error};
use crate::output::{Outputs, Stability};
use crate::paper_tables::run_noting_gains;
use crate::plot::{Figure, Kind, Series, render};
use crate::provenance::{commit, machine};
use ellipack::pack::RunOptions;
use ellipack::scene::Scene;
use implicit_packing::certificate;
use implicit_packing::containment::Container;
use implicit_packing::shape::Body;
use pw85::Sym3;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Duration;

#[cfg(feature = "peer")]
mod hoomd;

/// Semi-axes of every ellipsoid of the study.
pub const SEMI_AXES: [f64; 3] = [1.0, 0.75, 0.5];

/// Volume of one ellipsoid (4/3 π a b c).
pub fn item_volume() -> f64 {
    4.0 / 3.0 * std::f64::consts::PI * SEMI_AXES[0] * SEMI_AXES[1] * SEMI_AXES[2]
}

/// The scene of our run: `{count}` stands for the number of ellipsoids. A periodic cell whose
/// lattice vectors are variables, the densest periodic packing ellipack can find.
pub const PERIODIC_SCENE: &str = r#"name = "{count} ellipsoids (1, 0.75, 0.5) in a variable periodic cell"
dimension = 3
seed = 1

[container]
kind = "periodic"
cell = "variable"

[[shapes]]
count = {count}
semi_axes = [1.0, 0.75, 0.5]

[solver]
threads = 1

[output]
pictures = false
"#;

/// The scene of our random run ([`PERIODIC_SCENE`] with a cube compressed until jammed from a
/// random start, `ellipsoid_packer::random`), `{count}` standing for the count.
pub fn random_scene() -> String {
    PERIODIC_SCENE
        .replace(
            "in a variable periodic cell",
            "random and jammed in a periodic cube",
        )
        .replace("cell = \"variable\"", "packing_fraction = \"jammed\"")
}

/// Who packs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Who {
    /// hoomd-rs.
    Peer,
    /// ellipack.
    Ours,
    /// Both, the peer first.
    Both,
}

impl Who {
    fn runs_peer(self) -> bool {
        matches!(self, Who::Peer | Who::Both)
    }
    fn runs_ours(self) -> bool {
        matches!(self, Who::Ours | Who::Both)
    }
}

/// The largest trial moves of the peer's Monte Carlo sweeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PeerMoves {
    /// Largest translation.
    pub translate: f64,
    /// Largest rotation angle (radians).
    pub rotate: f64,
}

impl Default for PeerMoves {
    /// The values of hoomd-rs's three-dimensional hard-shape tutorial (hard tetrahedra): 0.04
    /// for both. Of 0.04, 0.08 and 0.15 tried on 100 ellipsoids for 60 s, these compressed
    /// furthest.
    fn default() -> Self {
        PeerMoves {
            translate: 0.04,
            rotate: 0.04,
        }
    }
}

/// What to run.
#[derive(Clone, Debug)]
pub struct Options {
    /// Wall seconds per run; `None`: 300 s for N ≥ 1000, 120 s below.
    pub seconds: Option<f64>,
    /// Numbers of ellipsoids.
    pub ns: Vec<usize>,
    /// Who packs.
    pub who: Who,
    /// Random pairs of the overlap-test comparison (0: skip it).
    pub overlap_pairs: usize,
    /// The scene of our run, `{count}` standing for the count ([`PERIODIC_SCENE`] by default).
    pub scene_template: String,
    /// Seed of the peer's simulation and of the random pairs.
    pub seed: u64,
    /// The peer's trial-move sizes.
    pub peer_moves: PeerMoves,
    /// Also our random jammed packing ([`random_scene`]), recorded as `random`.
    pub random: bool,
    /// Run nothing: write the figure and the section again from the recorded rows.
    pub report_only: bool,
}

impl Options {
    /// The wall-time budget of a run with `n` items.
    pub fn budget(&self, n: usize) -> f64 {
        self.seconds
            .unwrap_or(if n >= 1000 { 300.0 } else { 120.0 })
    }
}

/// One recorded point: `who` had reached `packing_fraction` (certified) after `seconds`.
#[derive(Clone, Debug, PartialEq)]
pub struct Point {
    /// `peer` or `ours`.
    pub who: String,
    /// Number of ellipsoids.
    pub n: usize,
    /// Wall seconds since the start of the run.
    pub seconds: f64,
    /// Packing fraction (items' volume over the cell's).
    pub packing_fraction: f64,
}

/// The summary of one run.
#[derive(Clone, Debug, PartialEq)]
pub struct RunRow {
    /// `peer` or `ours`.
    pub who: String,
    /// Number of ellipsoids.
    pub n: usize,
    /// Wall-time budget.
    pub budget_seconds: f64,
    /// The last certified packing fraction.
    pub final_fraction: f64,
    /// When it was reached.
    pub final_seconds: f64,
    /// Configurations checked with the minimum-image PW85 certificate (peer), or local
    /// minimisations (ours).
    pub checks: u64,
    /// Configurations the peer's own test called overlap-free in which PW85 found an overlap
    /// (never recorded as a point).
    pub rejected: u64,
    /// Smallest μ² over the final packing's pairs (>1: no overlap), when computed.
    pub min_mu2: Option<f64>,
    /// Processor and cores.
    pub machine: String,
    /// Commit of the code that ran.
    pub commit: String,
    /// How the run was made (the peer's move sizes, our scene's name).
    pub protocol: String,
}

/// The overlap-test comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct OverlapRow {
    /// Pairs.
    pub pairs: usize,
    /// hoomd-rs, nanoseconds per pair.
    pub peer_ns: f64,
    /// `pw85::overlap`, nanoseconds per pair.
    pub pw85_ns: f64,
    /// hoomd-rs on the half of the pairs spread over |δ| ≤ 0.3.
    pub peer_ns_spread: f64,
    /// `pw85::overlap` on that half.
    pub pw85_ns_spread: f64,
    /// hoomd-rs on the near-tangent half.
    pub peer_ns_near: f64,
    /// `pw85::overlap` on that half.
    pub pw85_ns_near: f64,
    /// Pairs of opposite verdicts.
    pub disagreements: usize,
    /// The largest |μ² − 1| among them (0 if none).
    pub max_disagreement_mu2_minus_one: f64,
    /// Pairs that overlap (PW85).
    pub overlapping: usize,
    /// Processor and cores.
    pub machine: String,
    /// Commit of the code that ran.
    pub commit: String,
}

/// A periodic cell: its three lattice vectors (rows).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// `lattice[k]` is the k-th lattice vector.
    pub lattice: [[f64; 3]; 3],
}

impl Cell {
    /// An orthorhombic box with these edge lengths.
    pub fn orthorhombic(lengths: [f64; 3]) -> Cell {
        Cell {
            lattice: [
                [lengths[0], 0.0, 0.0],
                [0.0, lengths[1], 0.0],
                [0.0, 0.0, lengths[2]],
            ],
        }
    }

    /// Volume (absolute value of the determinant).
    pub fn volume(&self) -> f64 {
        let [a, b, c] = self.lattice;
        let cross = [
            b[1] * c[2] - b[2] * c[1],
            b[2] * c[0] - b[0] * c[2],
            b[0] * c[1] - b[1] * c[0],
        ];
        (a[0] * cross[0] + a[1] * cross[1] + a[2] * cross[2]).abs()
    }

    /// The container of implicit-packing: the cell matrix with the lattice vectors as its
    /// columns (upper triangular for the cells of hoomd-rs and LAMMPS).
    fn container(&self) -> Container<3> {
        let l = self.lattice;
        Container::Periodic {
            cell: std::array::from_fn(|r| std::array::from_fn(|c| l[c][r])),
        }
    }
}

/// The verdict of [`certify_periodic`].
#[derive(Clone, Debug, PartialEq)]
pub struct PeriodicCertificate {
    /// Pairs (i ≤ j: an item may meet its own image) with at least one overlapping image.
    pub overlapping_pairs: usize,
    /// The first overlapping pair, if any.
    pub first_overlap: Option<(usize, usize)>,
    /// Pair images whose enclosing balls meet (the ones PW85 decided).
    pub images_tested: usize,
    /// Smallest μ² over those images.
    pub min_mu2: Option<f64>,
}

impl PeriodicCertificate {
    /// No overlapping pair.
    pub fn is_certified(&self) -> bool {
        self.overlapping_pairs == 0
    }
}

/// Checks a periodic configuration with implicit-packing's certificate
/// ([`implicit_packing::certificate::certify`]): every pair image within reach, an item's
/// own images included, whose enclosing balls meet decided by PW85.
///
/// # Errors
/// [`Error::Study`] for mismatched lengths, an invalid orientation or cell, or a pair PW85
/// refuses.
pub fn certify_periodic(
    cell: &Cell,
    centres: &[[f64; 3]],
    quaternions: &[[f64; 4]],
) -> Result<PeriodicCertificate, Error> {
    let study = |message: String| Error::Study {
        context: "periodic certificate".into(),
        message,
    };
    if centres.len() != quaternions.len() {
        return Err(study(format!(
            "{} centres and {} orientations",
            centres.len(),
            quaternions.len()
        )));
    }
    let bodies = centres
        .iter()
        .zip(quaternions)
        .enumerate()
        .map(|(i, (&c, &q))| {
            Body::from_quaternion(c, SEMI_AXES, q).map_err(|e| study(format!("item {i}: {e}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let certificate =
        certificate::certify(&bodies, &cell.container()).map_err(|e| study(e.to_string()))?;
    let mut pairs = certificate.overlapping_pairs();
    pairs.dedup();
    Ok(PeriodicCertificate {
        overlapping_pairs: pairs.len(),
        first_overlap: pairs.first().copied(),
        images_tested: certificate.pairs_checked,
        min_mu2: certificate.min_mu2,
    })
}

/// One random pair of the overlap-test comparison: the first ellipsoid at the origin.
#[derive(Clone, Copy, Debug)]
pub struct RandomPair {
    /// Orientation of the first (w, x, y, z).
    pub q1: [f64; 4],
    /// Orientation of the second.
    pub q2: [f64; 4],
    /// Centre of the second.
    pub r12: [f64; 3],
    /// Quadratic form of the first.
    pub form1: Sym3,
    /// Quadratic form of the second.
    pub form2: Sym3,
    /// μ² − 1 by construction ((1 + δ)² − 1 for the distance (1 + δ) × contact distance).
    pub mu2_minus_one: f64,
}

/// `count` seeded pairs of ellipsoids (1, 0.75, 0.5): orientations uniform, direction
/// uniform, distance (1 + δ) times the contact distance along it, δ uniform in [−0.3, 0.3]
/// for half of the pairs and ±10^u, u uniform in [−14, −2], for the other half (the near-
/// tangent pairs where two tests can disagree).
///
/// # Errors
/// [`Error::Pw85`] if pw85 refuses a form (not expected).
pub fn random_pairs(count: usize, seed: u64) -> Result<Vec<RandomPair>, Error> {
    let mut rng = testkit::Rng::new(seed);
    let mut pairs = Vec::with_capacity(count);
    for k in 0..count {
        let q1 = rng.unit_quaternion();
        let q2 = rng.unit_quaternion();
        let u = rng.direction();
        let form1 = pw85::shape::from_axes_quaternion(&SEMI_AXES, &q1)
            .map_err(error::pw85("a random orientation"))?;
        let form2 = pw85::shape::from_axes_quaternion(&SEMI_AXES, &q2)
            .map_err(error::pw85("a random orientation"))?;
        // μ is proportional to the distance along a fixed direction: μ(r u) = r μ(u).
        let mu_unit = pw85::contact_function(&u, &form1, &form2)
            .map_err(error::pw85("a unit separation"))?
            .mu2
            .sqrt();
        let delta = if k % 2 == 0 {
            rng.range(-0.3, 0.3)
        } else {
            let sign = if rng.uniform() < 0.5 { -1.0 } else { 1.0 };
            sign * 10f64.powf(rng.range(-14.0, -2.0))
        };
        let distance = (1.0 + delta) / mu_unit;
        pairs.push(RandomPair {
            q1,
            q2,
            r12: u.map(|x| x * distance),
            form1,
            form2,
            mu2_minus_one: delta * (2.0 + delta),
        });
    }
    Ok(pairs)
}

/// Times `pw85::overlap` on the pairs (the fastest of `repeats` passes) and returns its
/// nanoseconds per pair and verdicts.
///
/// # Errors
/// [`Error::Pw85`] if pw85 refuses a pair.
pub fn time_pw85(pairs: &[RandomPair], repeats: usize) -> Result<(f64, Vec<bool>), Error> {
    let mut verdicts = vec![false; pairs.len()];
    let mut best = f64::INFINITY;
    for _ in 0..repeats.max(1) {
        let start = std::time::Instant::now();
        for (v, p) in verdicts.iter_mut().zip(pairs) {
            *v = pw85::overlap(
                std::hint::black_box(&p.r12),
                std::hint::black_box(&p.form1),
                &p.form2,
            )
            .map_err(error::pw85("a random pair"))?;
        }
        best = best.min(start.elapsed().as_secs_f64());
        std::hint::black_box(&verdicts);
    }
    Ok((best * 1e9 / pairs.len().max(1) as f64, verdicts))
}

/// Compares two lists of verdicts on the same pairs: the number of opposite verdicts and the
/// largest |μ² − 1| among them (μ² from `pw85::contact_function_refined`).
///
/// # Errors
/// [`Error::Pw85`] if pw85 refuses a pair.
pub fn disagreements(pairs: &[RandomPair], a: &[bool], b: &[bool]) -> Result<(usize, f64), Error> {
    let mut count = 0;
    let mut worst: f64 = 0.0;
    for ((p, x), y) in pairs.iter().zip(a).zip(b) {
        if x != y {
            count += 1;
            let c = pw85::contact_function_refined(&p.r12, &p.form1, &p.form2)
                .map_err(error::pw85("a disagreeing pair"))?;
            worst = worst.max((c.mu2 - 1.0).abs());
        }
    }
    Ok((count, worst))
}

/// Runs ellipack on `scene_text` (a scene file's text) for `seconds` of wall time on one
/// thread and returns the best certified density after each local minimisation that improved
/// it, and the run's summary row.
///
/// # Errors
/// [`Error::Pack`] when the scene does not parse or the packer refuses it.
pub fn run_ours(scene_text: &str, seconds: f64) -> Result<(Vec<Point>, RunRow), Error> {
    run_ours_as("ours", scene_text, seconds)
}

/// [`run_ours`] with its points and row recorded under `who`.
pub fn run_ours_as(
    who: &str,
    scene_text: &str,
    seconds: f64,
) -> Result<(Vec<Point>, RunRow), Error> {
    let mut scene =
        Scene::from_toml_str(scene_text, "periodic-peer scene").map_err(|e| Error::Pack {
            context: "our scene".into(),
            message: e.to_string(),
        })?;
    scene.solver.time_limit = Duration::from_secs_f64(seconds);
    scene.solver.threads = 1;
    let n = scene.item_count();
    let options = RunOptions::default();
    let mut points = Vec::new();
    let outcome = run_noting_gains(&scene, &options, None, |p| {
        eprintln!(
            "  ours N = {n}: {:8.1} s: {:.5}",
            p.elapsed.as_secs_f64(),
            p.best_density
        );
        points.push(Point {
            who: who.into(),
            n,
            seconds: p.elapsed.as_secs_f64(),
            packing_fraction: p.best_density,
        });
    })
    .map_err(|e| Error::Pack {
        context: format!("ellipack on {n} items"),
        message: e.to_string(),
    })?;
    let c = outcome.summary.certificate;
    if !c.is_certified() {
        return Err(Error::Pack {
            context: format!("ellipack on {n} items"),
            message: format!(
                "the final packing is not certified: {} overlapping pairs, {} containment violations",
                c.overlapping_pairs, c.containment_violations
            ),
        });
    }
    let (final_seconds, final_fraction) = points
        .last()
        .map_or((outcome.seconds_to_best, outcome.summary.density), |p| {
            (p.seconds, p.packing_fraction)
        });
    let row = RunRow {
        who: who.into(),
        n,
        budget_seconds: seconds,
        final_fraction,
        final_seconds,
        checks: outcome.summary.local_minimisations,
        rejected: 0,
        min_mu2: c.min_mu2,
        machine: machine(),
        commit: commit(),
        protocol: format!(
            "ellipack::pack::run, one thread, scene \"{}\"",
            scene.title()
        ),
    };
    Ok((points, row))
}

/// Runs the study and writes its files under `root`; returns the messages of runs that could
/// not be made (ours on a scene the packer refuses), which do not stop the others.
///
/// # Errors
/// Invalid options, the peer asked for without the `peer` feature, or a file that cannot be
/// written.
pub fn run(root: &Path, options: &Options) -> Result<Vec<String>, Error> {
    let bad = |message: String| Error::Study {
        context: "periodic-peer options".into(),
        message,
    };
    if options.report_only {
        write_all(root, Vec::new(), Vec::new(), None)?;
        return Ok(Vec::new());
    }
    if options.ns.is_empty() || options.ns.contains(&0) {
        return Err(bad(format!(
            "--n needs positive counts, got {:?}",
            options.ns
        )));
    }
    if let Some(s) = options.seconds
        && !(s.is_finite() && s > 0.0)
    {
        return Err(bad(format!("--seconds must be positive, got {s}")));
    }
    if !options.scene_template.contains("{count}") {
        return Err(bad(
            "the scene template must contain `{count}` where the count goes".into(),
        ));
    }
    if options.who.runs_peer() && !cfg!(feature = "peer") {
        return Err(peer_disabled());
    }
    let mut points = Vec::new();
    let mut runs = Vec::new();
    let mut problems = Vec::new();
    let overlap = if options.overlap_pairs > 0 && options.who.runs_peer() {
        Some(overlap_study(options.overlap_pairs, options.seed)?)
    } else {
        None
    };
    for &n in &options.ns {
        let seconds = options.budget(n);
        if options.who.runs_peer() {
            eprintln!("peer: hoomd-rs, {n} ellipsoids, {seconds} s");
            let (p, row) = run_peer(n, seconds, options.seed, options.peer_moves)?;
            points.extend(p);
            runs.push(row);
        }
        if options.who.runs_ours() {
            eprintln!("ours: ellipack, {n} ellipsoids, {seconds} s");
            let scene = options.scene_template.replace("{count}", &n.to_string());
            match run_ours(&scene, seconds) {
                Ok((p, row)) => {
                    points.extend(p);
                    runs.push(row);
                }
                Err(e) => problems.push(format!("ours, N = {n}: {e}")),
            }
            if options.random {
                eprintln!("random: ellipack, {n} ellipsoids jammed from a random start");
                let scene = random_scene().replace("{count}", &n.to_string());
                match run_ours_as("random", &scene, seconds) {
                    Ok((p, row)) => {
                        points.extend(p);
                        runs.push(row);
                    }
                    Err(e) => problems.push(format!("random, N = {n}: {e}")),
                }
            }
        }
    }
    // Nothing measured (our scene refused, say): the files keep what they hold.
    if !(runs.is_empty() && overlap.is_none()) {
        write_all(root, points, runs, overlap)?;
    }
    Ok(problems)
}

/// The overlap-test comparison on `count` random pairs.
#[cfg(feature = "peer")]
fn overlap_study(count: usize, seed: u64) -> Result<OverlapRow, Error> {
    eprintln!("overlap tests on {count} random pairs");
    let pairs = random_pairs(count, seed)?;
    // The two halves of `random_pairs` (even: spread, odd: near tangency), timed apart.
    let spread: Vec<RandomPair> = pairs.iter().step_by(2).copied().collect();
    let near: Vec<RandomPair> = pairs.iter().skip(1).step_by(2).copied().collect();
    let (peer_ns_spread, peer_spread) = hoomd::time_overlaps(&spread, 5)?;
    let (peer_ns_near, peer_near) = hoomd::time_overlaps(&near, 5)?;
    let (pw85_ns_spread, ours_spread) = time_pw85(&spread, 5)?;
    let (pw85_ns_near, ours_near) = time_pw85(&near, 5)?;
    let (a, b) = (spread.len() as f64, near.len() as f64);
    let mean = |x: f64, y: f64| (a * x + b * y) / (a + b).max(1.0);
    let (d_spread, worst_spread) = disagreements(&spread, &peer_spread, &ours_spread)?;
    let (d_near, worst_near) = disagreements(&near, &peer_near, &ours_near)?;
    let (disagreeing, worst) = (d_spread + d_near, worst_spread.max(worst_near));
    let ours: Vec<bool> = ours_spread.into_iter().chain(ours_near).collect();
    let row = OverlapRow {
        pairs: pairs.len(),
        peer_ns: mean(peer_ns_spread, peer_ns_near),
        pw85_ns: mean(pw85_ns_spread, pw85_ns_near),
        peer_ns_spread,
        pw85_ns_spread,
        peer_ns_near,
        pw85_ns_near,
        disagreements: disagreeing,
        max_disagreement_mu2_minus_one: worst,
        overlapping: ours.iter().filter(|v| **v).count(),
        machine: machine(),
        commit: commit(),
    };
    eprintln!(
        "  hoomd-rs {:.1} ns/pair, pw85::overlap {:.1} ns/pair, {} disagreements (|μ² − 1| ≤ {:.2e})",
        row.peer_ns, row.pw85_ns, row.disagreements, row.max_disagreement_mu2_minus_one
    );
    Ok(row)
}

#[cfg(not(feature = "peer"))]
fn overlap_study(_count: usize, _seed: u64) -> Result<OverlapRow, Error> {
    Err(peer_disabled())
}

/// hoomd-rs on `n` ellipsoids for `seconds`.
#[cfg(feature = "peer")]
fn run_peer(
    n: usize,
    seconds: f64,
    seed: u64,
    moves: PeerMoves,
) -> Result<(Vec<Point>, RunRow), Error> {
    hoomd::run_peer(n, seconds, seed, moves)
}

#[cfg(not(feature = "peer"))]
fn run_peer(
    _n: usize,
    _seconds: f64,
    _seed: u64,
    _moves: PeerMoves,
) -> Result<(Vec<Point>, RunRow), Error> {
    Err(peer_disabled())
}

fn peer_disabled() -> Error {
    Error::Study {
        context: "periodic-peer".into(),
        message: PEER_DISABLED.into(),
    }
}

/// What `periodic-peer` says when the peer is asked for in a build without it.
pub const PEER_DISABLED: &str = "hoomd-rs is not compiled in: run `cargo run --release -p xtask \
     --features peer -- periodic-peer …` (or `--who ours` without the peer)";

/// Merges the new results into the files under `root` (rows of runs not repeated are kept)
/// and regenerates the figure and the section of `docs/periodic.md`.
fn write_all(
    root: &Path,
    points: Vec<Point>,
    runs: Vec<RunRow>,
    overlap: Option<OverlapRow>,
) -> Result<(), Error> {
    let points_path = root.join("validation/periodic_peer.csv");
    let runs_path = root.join("validation/periodic_peer_runs.csv");
    let overlap_path = root.join("validation/periodic_peer_overlap.csv");
    let fresh: Vec<(String, usize)> = runs.iter().map(|r| (r.who.clone(), r.n)).collect();
    let mut all_points: Vec<Point> = read_points(&points_path)?
        .into_iter()
        .filter(|p| !fresh.contains(&(p.who.clone(), p.n)))
        .collect();
    all_points.extend(points);
    all_points.sort_by(|a, b| {
        (a.who.as_str(), a.n)
            .cmp(&(b.who.as_str(), b.n))
            .then(a.seconds.total_cmp(&b.seconds))
    });
    let mut all_runs: Vec<RunRow> = read_runs(&runs_path)?
        .into_iter()
        .filter(|r| !fresh.contains(&(r.who.clone(), r.n)))
        .collect();
    all_runs.extend(runs);
    all_runs.sort_by(|a, b| (a.who.as_str(), a.n).cmp(&(b.who.as_str(), b.n)));
    let overlap = match overlap {
        Some(o) => Some(o),
        None => read_overlap(&overlap_path)?,
    };

    let mut outputs = Outputs::new(false);
    outputs.write(
        &points_path,
        points_csv(&all_points).as_bytes(),
        Stability::Volatile,
    )?;
    outputs.write(
        &runs_path,
        runs_csv(&all_runs).as_bytes(),
        Stability::Volatile,
    )?;
    if let Some(o) = &overlap {
        outputs.write(
            &overlap_path,
            overlap_csv(o).as_bytes(),
            Stability::Volatile,
        )?;
    }
    render(
        &figure(&all_points, &all_runs),
        &root.join("docs/figures"),
        "periodic-density-time",
        &mut outputs,
    )?;
    let doc_path = root.join("docs/periodic.md");
    let doc = std::fs::read_to_string(&doc_path).unwrap_or_default();
    let text = splice_section(&doc, &section(&all_points, &all_runs, overlap.as_ref()));
    outputs.write(&doc_path, text.as_bytes(), Stability::Volatile)?;
    for p in &outputs.written {
        eprintln!("wrote {}", p.display());
    }
    Ok(())
}

const BEGIN: &str = "<!-- periodic-peer: generated by `cargo xtask periodic-peer`; do not edit -->";
const END: &str = "<!-- periodic-peer: end -->";

/// `doc` with the text between the markers replaced by `section` (appended, with the markers,
/// when the markers are absent).
pub fn splice_section(doc: &str, section: &str) -> String {
    let block = format!("{BEGIN}\n{section}{END}\n");
    match (doc.find(BEGIN), doc.find(END)) {
        (Some(b), Some(e)) if e > b => {
            let after = &doc[e + END.len()..];
            format!(
                "{}{block}{}",
                &doc[..b],
                after.strip_prefix('\n').unwrap_or(after)
            )
        }
        _ if doc.trim().is_empty() => format!("# Periodic packings\n\n{block}"),
        _ => format!("{}\n{block}", doc.trim_end_matches('\n').to_string() + "\n"),
    }
}

fn points_csv(points: &[Point]) -> String {
    let mut s = String::from("who,n,seconds,packing_fraction\n");
    for p in points {
        let _ = writeln!(
            s,
            "{},{},{:.3},{:.6}",
            p.who, p.n, p.seconds, p.packing_fraction
        );
    }
    s
}

fn runs_csv(runs: &[RunRow]) -> String {
    let mut s = String::from(
        "who,n,budget_seconds,final_seconds,final_fraction,checks,rejected,min_mu2,machine,commit,\
         protocol\n",
    );
    for r in runs {
        let _ = writeln!(
            s,
            "{},{},{:.0},{:.3},{:.6},{},{},{},\"{}\",{},\"{}\"",
            r.who,
            r.n,
            r.budget_seconds,
            r.final_seconds,
            r.final_fraction,
            r.checks,
            r.rejected,
            r.min_mu2.map_or(String::new(), |m| format!("{m:.9}")),
            r.machine.replace('"', "'"),
            r.commit,
            r.protocol.replace('"', "'"),
        );
    }
    s
}

fn overlap_csv(o: &OverlapRow) -> String {
    format!(
        "pairs,peer_ns_per_pair,pw85_ns_per_pair,peer_ns_spread,pw85_ns_spread,peer_ns_near,\
         pw85_ns_near,disagreements,max_disagreement_mu2_minus_one,overlapping,machine,commit\n\
         {},{:.1},{:.1},{:.1},{:.1},{:.1},{:.1},{},{:.3e},{},\"{}\",{}\n",
        o.pairs,
        o.peer_ns,
        o.pw85_ns,
        o.peer_ns_spread,
        o.pw85_ns_spread,
        o.peer_ns_near,
        o.pw85_ns_near,
        o.disagreements,
        o.max_disagreement_mu2_minus_one,
        o.overlapping,
        o.machine.replace('"', "'"),
        o.commit
    )
}

/// The rows of a CSV file the study wrote, as field lists keyed by the header (none if the
/// file does not exist yet).
fn read_table(path: &Path) -> Result<Vec<Vec<(String, String)>>, Error> {
    if !path.exists() {
        return Ok(Vec::new());
    }
    let mut reader = csv::Reader::from_path(path).map_err(|e| csv_error(path, 1, &e))?;
    let headers = reader
        .headers()
        .map_err(|e| csv_error(path, 1, &e))?
        .clone();
    let mut rows = Vec::new();
    for (k, record) in reader.records().enumerate() {
        let record = record.map_err(|e| csv_error(path, k as u64 + 2, &e))?;
        rows.push(
            headers
                .iter()
                .zip(record.iter())
                .map(|(h, v)| (h.to_string(), v.to_string()))
                .collect(),
        );
    }
    Ok(rows)
}

fn csv_error(path: &Path, line: u64, e: &csv::Error) -> Error {
    Error::Reference {
        path: path.to_path_buf(),
        line: e.position().map_or(line, |p| p.line()),
        message: e.to_string(),
    }
}

/// A field of a row read by [`read_table`], parsed; the error names the file, line and column.
fn field<T: std::str::FromStr>(
    path: &Path,
    line: usize,
    row: &[(String, String)],
    name: &str,
) -> Result<T, Error> {
    let value = row
        .iter()
        .find(|(h, _)| h == name)
        .map(|(_, v)| v.as_str())
        .ok_or_else(|| Error::Reference {
            path: path.to_path_buf(),
            line: line as u64,
            message: format!("no column `{name}`"),
        })?;
    value.parse().map_err(|_| Error::Reference {
        path: path.to_path_buf(),
        line: line as u64,
        message: format!("column `{name}`: cannot read `{value}`"),
    })
}

/// One row of a table being read: its values by column name, with the file and line for
/// errors.
pub(crate) struct Fields<'a> {
    path: &'a Path,
    line: usize,
    row: &'a [(String, String)],
}

impl Fields<'_> {
    pub(crate) fn get<T: std::str::FromStr>(&self, name: &str) -> Result<T, Error> {
        field(self.path, self.line, self.row, name)
    }

    /// The column `name` parsed, or `None` where it is blank: a value the run did not measure.
    pub(crate) fn optional<T: std::str::FromStr>(&self, name: &str) -> Result<Option<T>, Error> {
        let text: String = self.get(name)?;
        if text.is_empty() {
            Ok(None)
        } else {
            self.get(name).map(Some)
        }
    }
}

/// Every row of the table at `path`, made by `make`.
pub(crate) fn read_rows<T>(
    path: &Path,
    make: impl Fn(&Fields<'_>) -> Result<T, Error>,
) -> Result<Vec<T>, Error> {
    read_table(path)?
        .iter()
        .enumerate()
        .map(|(k, row)| {
            make(&Fields {
                path,
                line: k + 2,
                row,
            })
        })
        .collect()
}

/// The struct `$row` from one row of a table read by [`read_rows`] (`$fields`, a [`Fields`]),
/// its fields in the order listed: each parsed from the column of its own name, or of the name
/// given after `:`, by [`Fields::get`], or by the method of [`Fields`] given after `as`. A
/// reader so names each column once, not once for the field and again for the column.
macro_rules! from_columns {
    (@column $field:ident) => {
        stringify!($field)
    };
    (@column $field:ident $column:literal) => {
        $column
    };
    (@get $fields:ident, $column:expr) => {
        $fields.get($column)
    };
    (@get $fields:ident, $column:expr, $method:ident) => {
        $fields.$method($column)
    };
    ($fields:ident => $row:ident {
        $($field:ident $(: $column:literal)? $(as $method:ident)?),* $(,)?
    }) => {
        $row {
            $($field: $crate::periodic_peer::from_columns!(
                @get $fields,
                $crate::periodic_peer::from_columns!(@column $field $($column)?)
                $(, $method)?
            )?,)*
        }
    };
}
pub(crate) use from_columns;

fn read_points(path: &Path) -> Result<Vec<Point>, Error> {
    read_rows(path, |f| {
        Ok(from_columns!(f => Point { who, n, seconds, packing_fraction }))
    })
}

fn read_runs(path: &Path) -> Result<Vec<RunRow>, Error> {
    read_rows(path, |f| {
        Ok(from_columns!(f => RunRow {
            who, n, budget_seconds, final_fraction, final_seconds, checks, rejected,
            min_mu2 as optional, machine, commit, protocol,
        }))
    })
}

fn read_overlap(path: &Path) -> Result<Option<OverlapRow>, Error> {
    let rows = read_rows(path, |f| {
        Ok(from_columns!(f => OverlapRow {
            pairs, peer_ns: "peer_ns_per_pair", pw85_ns: "pw85_ns_per_pair", peer_ns_spread,
            pw85_ns_spread, peer_ns_near, pw85_ns_near, disagreements,
            max_disagreement_mu2_minus_one, overlapping, machine, commit,
        }))
    })?;
    Ok(rows.into_iter().next())
}

fn label(who: &str) -> &'static str {
    match who {
        "peer" => "hoomd-rs",
        "random" => "ellipack, random jammed",
        _ => "ellipack",
    }
}

/// The density–time figure: one line per (who, N).
fn figure(points: &[Point], runs: &[RunRow]) -> Figure {
    let mut series = Vec::new();
    for (k, r) in runs.iter().enumerate() {
        // A staircase: each fraction holds until the next one is reached, the last one until
        // the end of the run.
        let mut pts: Vec<(f64, f64)> = Vec::new();
        for p in points.iter().filter(|p| p.who == r.who && p.n == r.n) {
            if let Some(&(_, previous)) = pts.last() {
                pts.push((p.seconds, previous));
            }
            pts.push((p.seconds, p.packing_fraction));
        }
        if let Some(&(_, last)) = pts.last() {
            pts.push((r.budget_seconds, last));
        }
        series.push(Series {
            name: format!("{}, N = {}", label(&r.who), r.n),
            points: pts,
            kind: Kind::Line,
            color: k,
        });
    }
    crate::plot::density_against_time(
        "Ellipsoids (1, 0.75, 0.5), periodic cell, one thread",
        series,
    )
}

/// The best certified fraction of a run at `t` seconds (none before its first point).
fn fraction_at(points: &[Point], who: &str, n: usize, t: f64) -> Option<f64> {
    points
        .iter()
        .filter(|p| p.who == who && p.n == n && p.seconds <= t)
        .map(|p| p.packing_fraction)
        .fold(None, |m, f| Some(m.map_or(f, |m: f64| m.max(f))))
}

/// The first time a run reached `fraction` (none if it never did).
fn time_to(points: &[Point], who: &str, n: usize, fraction: f64) -> Option<f64> {
    points
        .iter()
        .filter(|p| p.who == who && p.n == n && p.packing_fraction >= fraction)
        .map(|p| p.seconds)
        .fold(None, |m, t| Some(m.map_or(t, |m: f64| m.min(t))))
}

const MARKS: [f64; 5] = [10.0, 30.0, 60.0, 120.0, 300.0];

fn section(points: &[Point], runs: &[RunRow], overlap: Option<&OverlapRow>) -> String {
    let mut s = String::from(
        "## Beside hoomd-rs: ellipsoids in a periodic box\n\n\
         Ellipsoids with semi-axes (1, 0.75, 0.5) in a periodic cell, one thread each, on the \
         machine named in each row. **hoomd-rs** 1.4 (`hoomd-mc`, hard-particle Monte Carlo) \
         follows its hard-shape tutorial: `QuickInsert` of the ellipsoids \
         (`Convex<Ellipsoid>`) at packing fraction 0.3 into a periodic cube, then \
         `QuickCompress` towards 0.74 with the `OverlapPenalty` Hamiltonian \
         (`ApproximateShapeOverlap`, resolution 0.01) and sweeps of translations and \
         rotations at temperature 1 (the largest moves are in the protocol column). Each time its box has shrunk and \
         its hard-shape Hamiltonian reports no overlap, the configuration is checked with \
         PW85 on every pair under the minimum-image convention, and only a certified \
         configuration is recorded; the checks are not counted in its wall time. **ellipack** \
         runs `ellipack::pack::run` on one thread with the scene of \
         `xtask/src/periodic_peer.rs` and records the best certified density after each local \
         minimisation: the densest periodic packing, its cell's lattice vectors among the \
         variables. **ellipack, random jammed** (`--random`) packs the same items from a \
         random start in a cube compressed until jammed (`random_scene`, \
         [random.md](random.md)): a disordered packing, as the peer's.\n\n",
    );
    s.push_str("| who | N | budget (s) |");
    for m in MARKS {
        let _ = write!(s, " at {m:.0} s |");
    }
    s.push_str(
        " final | reached at (s) | certified checks | rejected | min μ² | protocol | machine | \
         commit |\n|---|---:|---:|",
    );
    for _ in MARKS {
        s.push_str("---:|");
    }
    s.push_str("---:|---:|---:|---:|---:|---|---|---|\n");
    for r in runs {
        let _ = write!(
            s,
            "| {} | {} | {:.0} |",
            label(&r.who),
            r.n,
            r.budget_seconds
        );
        for m in MARKS {
            let cell = if m > r.budget_seconds {
                "".into()
            } else {
                fraction_at(points, &r.who, r.n, m).map_or("—".into(), |f| format!("{f:.4}"))
            };
            let _ = write!(s, " {cell} |");
        }
        let _ = writeln!(
            s,
            " {:.4} | {:.1} | {} | {} | {} | {} | {} | {} |",
            r.final_fraction,
            r.final_seconds,
            r.checks,
            r.rejected,
            r.min_mu2.map_or("—".into(), |m| format!("{m:.6}")),
            r.protocol,
            r.machine,
            r.commit
        );
    }
    s.push_str(
        "\n\"certified checks\" counts the peer's configurations checked with PW85 (for \
         ellipack, its local minimisations); \"rejected\" those the peer called overlap-free \
         and PW85 did not; min μ² is the smallest contact function over the pairs of the \
         final packing (above 1: no overlap).\n\n",
    );
    // Where both ran with the same N: how long ellipack took to pass the peer's final fraction.
    let mut ratios = String::new();
    for peer in runs.iter().filter(|r| r.who == "peer") {
        if let Some(ours) = runs.iter().find(|r| r.who == "ours" && r.n == peer.n) {
            let random = runs
                .iter()
                .find(|r| r.who == "random" && r.n == peer.n)
                .map_or("—".into(), |r| {
                    format!("{:.4} in {:.1} s", r.final_fraction, r.final_seconds)
                });
            let _ = writeln!(
                ratios,
                "| {} | {:.4} in {:.1} s | {:.4} | {} | {random} |",
                peer.n,
                peer.final_fraction,
                peer.final_seconds,
                ours.final_fraction,
                time_to(points, "ours", ours.n, peer.final_fraction)
                    .map_or("never".into(), |t| format!("{t:.1} s")),
            );
        }
    }
    if !ratios.is_empty() {
        s.push_str(
            "| N | hoomd-rs final | ellipack final | ellipack reached hoomd-rs's final at | \
             ellipack, random jammed |\n|---:|---:|---:|---:|---:|\n",
        );
        s.push_str(&ratios);
        s.push('\n');
    }
    s.push_str(
        "![Certified packing fraction against wall time](figures/periodic-density-time.png)\n\n",
    );
    if let Some(o) = overlap {
        let _ = write!(
            s,
            "### Overlap test\n\nOn the same {} random pairs of these ellipsoids (orientations \
             uniform, the second centre along a uniform direction at (1 + δ) times the contact \
             distance, δ uniform in [−0.3, 0.3] for half the pairs and ±10^u, u uniform in \
             [−14, −2], for the other half; {} overlap), the fastest of five passes, {} \
             build with default flags, one thread:\n\n\
             | test | ns per pair, all | spread half | near-tangent half |\n|---|---:|---:|---:|\n\
             | hoomd-rs `Convex<Ellipsoid>::intersects_at_global` (XenoCollide, as its \
             `HardShape` calls it) | {:.1} | {:.1} | {:.1} |\n\
             | `pw85::overlap` (quadratic forms precomputed) | {:.1} | {:.1} | {:.1} |\n\n\
             {} pairs get opposite verdicts{}. Machine: {}; commit {}.\n\n",
            o.pairs,
            o.overlapping,
            if cfg!(debug_assertions) {
                "debug"
            } else {
                "release"
            },
            o.peer_ns,
            o.peer_ns_spread,
            o.peer_ns_near,
            o.pw85_ns,
            o.pw85_ns_spread,
            o.pw85_ns_near,
            o.disagreements,
            if o.disagreements > 0 {
                format!(
                    ", all within |μ² − 1| ≤ {:.1e} of tangency (μ² by \
                     `pw85::contact_function_refined`)",
                    o.max_disagreement_mu2_minus_one
                )
            } else {
                String::new()
            },
            o.machine,
            o.commit
        );
    }
    s.push_str(
        "Reproduce: `cargo run --release -p xtask --features peer -- periodic-peer` (options \
         `--seconds`, `--n 100 1000`, `--who peer|ours|both`, `--overlap-pairs`, `--scene`, \
         `--peer-translate`, `--peer-rotate`); \
         without the `peer` feature only `--who ours` runs.\n",
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The certificate of two items (1, 0.75, 0.5), unturned, at `a` and `b` in `cell`.
    fn two_items(cell: &Cell, a: [f64; 3], b: [f64; 3]) -> PeriodicCertificate {
        certify_periodic(cell, &[a, b], &[[1.0, 0.0, 0.0, 0.0]; 2]).unwrap()
    }

    #[test]
    fn items_overlap_across_the_boundary_and_not_when_far_apart() {
        let cell = Cell::orthorhombic([10.0, 10.0, 10.0]);
        // 0.8 apart along their long axes through the face x = 0 / x = 10, 9.2 apart inside
        // the box.
        let across = two_items(&cell, [0.5, 5.0, 5.0], [9.7, 5.0, 5.0]);
        assert_eq!(across.overlapping_pairs, 1);
        assert_eq!(across.first_overlap, Some((0, 1)));
        let mu2 = across.min_mu2.unwrap();
        assert!(
            (mu2 - 0.16).abs() < 1e-12,
            "μ² = (0.8 / 2)² = 0.16, got {mu2}"
        );
        // The same pair with the second centre given three boxes farther out.
        let unwrapped = two_items(&cell, [0.5, 5.0, 5.0], [29.7, -15.0, 5.0]);
        assert_eq!(unwrapped.overlapping_pairs, 1);
        assert!((unwrapped.min_mu2.unwrap() - 0.16).abs() < 1e-12);

        let far = two_items(&cell, [2.0, 5.0, 5.0], [7.0, 5.0, 5.0]);
        assert!(far.is_certified());
        assert_eq!(far.images_tested, 0);
        // Across a corner: 0.4 apart along each axis through three faces.
        let corner = two_items(&cell, [0.2, 0.2, 0.2], [9.8, 9.8, 9.8]);
        assert_eq!(corner.overlapping_pairs, 1);
    }

    #[test]
    fn sheared_cells_use_the_nearest_image() {
        // Lattice a = (4.5, 0, 0), b = (4, 4.5, 0), c = (0, 0, 4.5). The nearest image of the
        // second centre is v = (−1.2, 0.3, 0) + … : items (1, 0.75, 0.5) along x, v along the
        // axis of the lattice vector b − a = (−0.5, 4.5, 0) shifted: the centres 0.4 apart
        // along y through the face, μ² = (0.4 / 1.5)².
        let cell = Cell {
            lattice: [[4.5, 0.0, 0.0], [4.0, 4.5, 0.0], [0.0, 0.0, 4.5]],
        };
        let c = two_items(&cell, [0.0, 0.0, 0.0], [4.0, 4.1, 0.0]);
        assert_eq!(c.overlapping_pairs, 1);
        let mu2 = c.min_mu2.unwrap();
        assert!((mu2 - (0.4_f64 / 1.5).powi(2)).abs() < 1e-12, "got {mu2}");
        let apart = two_items(&cell, [0.0, 0.0, 0.0], [4.0, 2.5, 0.0]);
        assert!(apart.is_certified());
    }

    #[test]
    fn an_item_that_meets_its_own_image_is_no_packing() {
        // The long axis (2 across) in a cell 1.5 wide.
        let cell = Cell::orthorhombic([1.5, 10.0, 10.0]);
        let c = two_items(&cell, [0.0; 3], [0.5, 5.0, 5.0]);
        assert_eq!(c.first_overlap, Some((0, 0)));
        assert_eq!(c.overlapping_pairs, 2);
    }

    #[test]
    fn random_pairs_are_at_the_distance_they_claim() {
        let pairs = random_pairs(40, 7).unwrap();
        for p in &pairs {
            let c = pw85::contact_function_refined(&p.r12, &p.form1, &p.form2).unwrap();
            let expected = 1.0 + p.mu2_minus_one;
            assert!(
                (c.mu2 - expected).abs() <= 1e-12 * expected,
                "μ² {} against {expected}",
                c.mu2
            );
        }
        let (ns, verdicts) = time_pw85(&pairs, 1).unwrap();
        assert!(ns > 0.0);
        for (p, v) in pairs.iter().zip(&verdicts) {
            if p.mu2_minus_one.abs() > 1e-9 {
                assert_eq!(*v, p.mu2_minus_one < 0.0);
            }
        }
    }

    #[test]
    fn splicing_replaces_only_the_generated_section() {
        let doc = format!("# Periodic\n\nThe model.\n\n{BEGIN}\nold\n{END}\nAfter.\n");
        let new = splice_section(&doc, "new\n");
        assert_eq!(
            new,
            format!("# Periodic\n\nThe model.\n\n{BEGIN}\nnew\n{END}\nAfter.\n")
        );
        let appended = splice_section("# Periodic\n\nThe model.\n", "new\n");
        assert!(appended.starts_with("# Periodic\n\nThe model.\n\n"));
        assert!(appended.ends_with(&format!("{BEGIN}\nnew\n{END}\n")));
    }

    #[test]
    fn ours_records_certified_densities_on_the_periodic_scene() {
        let scene = PERIODIC_SCENE.replace("{count}", "3");
        let (points, row) = run_ours(&scene, 1.0).unwrap();
        assert!(!points.is_empty());
        assert!(
            points
                .windows(2)
                .all(|w| w[0].packing_fraction < w[1].packing_fraction)
        );
        assert!(
            points
                .iter()
                .all(|p| p.packing_fraction > 0.0 && p.packing_fraction < 1.0)
        );
        assert_eq!(row.n, 3);
        assert_eq!(row.final_fraction, points.last().unwrap().packing_fraction);
    }
}
