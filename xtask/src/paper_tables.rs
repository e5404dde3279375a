//! `cargo xtask paper-tables`: the paper's instances (Tables 6.1–6.4, Section 6.1.2) run by the
//! same pipeline as `ellipack pack` (multi-start, certificate, repair), each for a wall-clock
//! budget, and reported beside the paper's densities.
//!
//! Writes `validation/paper_tables.csv`, `docs/paper-tables.md`, a picture per instance
//! (`docs/figures/paper_<name>.{svg,png}`) and the packings themselves
//! (`validation/paper-packings/<name>/packing.csv` + `summary.json`, which `ellipack verify`
//! re-checks and `ellipack pack --resume` continues from), and each run's history
//! (`validation/paper-runs/<name>.csv`, the density-against-time figure's data) with its row in
//! `validation/paper_latest_runs.csv` (every instance's latest run: the code version it ran
//! and how long it took to reach the paper). A fresh run whose packing is less dense than the
//! committed one (which must read back and verify) writes only its history and latest-run row
//! for that instance: its committed packing, picture and row stay.

use crate::plot::{Corner, Figure, Kind, Panel, Series, render};
use ellipack::folder::HISTORY_FILE;
use ellipack::folder::write_files;
use ellipack::instances::{INSTANCES, Instance, by_name, names};
use ellipack::pack::{RunOptions, RunOutcome, run};
use ellipack::render::{RenderOptions, png_bytes, svg_string};
use ellipack::scene::{Dimension, MethodName, Scene, SolverSettings};
use ellipack::write_atomically;
use ellipsoid_packer::multistart::{Callbacks, MultiStartProgress};
use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// The four instances the multi-start issue sets targets for.
pub const TARGETS: [&str; 4] = ["ellipse-100", "rectangle-100", "ball-100", "cuboid-100"];

/// What to run; also the options of `cargo xtask paper-tables`, whose help the field comments
/// are.
#[derive(Clone, Debug, clap::Args)]
pub struct Options {
    /// Minutes of wall time per instance.
    #[arg(long, default_value_t = 60.0)]
    pub minutes: f64,
    /// Instances (see `ellipack instances`). Default: the four of the multi-start targets.
    #[arg(long, num_args = 1..)]
    pub instances: Vec<String>,
    /// Parallel starts (0: every core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Continue from the committed packings: each instance starts from its packing in
    /// validation/paper-packings/, and its row adds this budget to the earlier one.
    #[arg(long)]
    pub resume: bool,
    /// How each local minimisation makes the container small: lagrangian (the paper's),
    /// compression or compression-lagrangian. Default: the scene's (lagrangian).
    #[arg(long, value_parser = method_named)]
    pub method: Option<MethodName>,
    /// The multi-start's random seed (default: the instance's, 0); it is written in each
    /// packing's summary.json.
    #[arg(long)]
    pub seed: Option<u64>,
    /// End each instance's run as soon as its best certified density reaches the paper's
    /// (within the same budget): the question is then how long the paper's density takes.
    #[arg(long)]
    pub until_paper: bool,
}

/// One instance's result.
#[derive(Clone, Debug)]
struct Row {
    instance: &'static Instance,
    density: f64,
    seconds_to_best: f64,
    local_minimisations: u64,
    failed_starts: usize,
    certified: bool,
    min_mu2: Option<f64>,
    /// Wall-time budget of the run.
    budget_seconds: f64,
    /// Processor, cores and threads used.
    machine: String,
    /// The local minimisation's method (its name in scene files).
    method: String,
    /// The repository's commit when the row ran (for rows older than the column: the commit
    /// that landed the packing).
    commit: String,
}

/// Runs the instances and writes the tables; returns a message for each instance that could
/// not be run or whose packing is not certified (none expected).
///
/// # Errors
/// An unknown instance name, or an output that cannot be written.
pub fn run_all(root: &Path, options: &Options) -> Result<Vec<String>, String> {
    let instances: Vec<&'static Instance> = options
        .instances
        .iter()
        .map(|n| {
            by_name(n)
                .ok_or_else(|| format!("unknown instance `{n}`; the instances are: {}", names()))
        })
        .collect::<Result<_, _>>()?;
    if !(options.minutes.is_finite() && options.minutes > 0.0) {
        return Err(format!(
            "--minutes must be positive, got {}",
            options.minutes
        ));
    }
    let threads = match options.threads {
        0 => std::thread::available_parallelism().map_or(1, usize::from),
        n => n,
    };
    let mut rows = Vec::new();
    let mut latest = Vec::new();
    let mut problems = Vec::new();
    for instance in instances {
        eprintln!(
            "{}: {} for {} min on {threads} threads",
            instance.name,
            instance.description(),
            options.minutes
        );
        let mut scene = instance.scene();
        if let Some(seed) = options.seed {
            scene.seed = seed;
        }
        let dir = root.join("validation/paper-packings").join(instance.name);
        // Resuming: the committed packing is the start to beat, and its row's budget, time to
        // best and local minimisations carry over.
        let earlier = if options.resume {
            let row = earlier_rows(&root.join("validation/paper_tables.csv"))
                .into_iter()
                .find(|r| r.instance.name == instance.name);
            let packing = ellipack::folder::read_packing_dir(&dir)
                .ok()
                .map(|(p, _)| p);
            row.zip(packing)
        } else {
            None
        };
        if options.resume && earlier.is_none() {
            eprintln!("  nothing to resume in {}: a fresh run", dir.display());
        }
        // A resumed row goes on with its own method unless another one is asked for.
        let earlier_method = earlier
            .as_ref()
            .and_then(|(row, _)| method_named(&row.method).ok());
        if let Some(method) = options.method.or(earlier_method) {
            scene.solver.method = method;
        }
        scene.solver.time_limit = Duration::from_secs_f64(options.minutes * 60.0);
        scene.solver.threads = threads;
        let run_options = RunOptions {
            resume_from: earlier.as_ref().map(|(_, p)| p.clone()),
            ..RunOptions::default()
        };
        let stop_at = instance.reference_density().filter(|_| options.until_paper);
        let outcome = run_noting_gains(&scene, &run_options, stop_at, |p| {
            eprintln!(
                "  {:8.1} s: best certified density {:.5} ({} local minimisations)",
                p.elapsed.as_secs_f64(),
                p.best_density,
                p.local_minimisations
            );
        })
        .map_err(|e| format!("{}: {e}", instance.name))?;
        // Every run's history is kept, also of a run whose packing is not kept: the figure
        // shows how the code of the latest run gets to its density.
        let history = outcome.history.clone().into_text();
        let runs = root.join(RUNS_DIR);
        std::fs::create_dir_all(&runs).map_err(|e| format!("{}: {e}", runs.display()))?;
        write_atomically(
            &runs.join(format!("{}.csv", instance.name)),
            history.as_bytes(),
        )
        .map_err(|e| e.to_string())?;
        let c = outcome.summary.certificate;
        latest.push(LatestRun {
            instance,
            density: outcome.summary.density,
            seconds_to_paper: instance
                .reference_density()
                .and_then(|paper| seconds_to_reach(&history, paper)),
            seconds_to_best: outcome.seconds_to_best,
            local_minimisations: outcome.summary.local_minimisations,
            budget_seconds: options.minutes * 60.0,
            until_paper: options.until_paper,
            resumed: earlier.is_some(),
            certified: c.is_certified(),
            method: scene.solver.method.name().to_string(),
            machine: crate::provenance::machine_with_threads(threads),
            commit: crate::provenance::commit(),
        });
        if !c.is_certified() {
            problems.push(format!(
                "{}: {} overlapping pairs, {} containment violations",
                instance.name, c.overlapping_pairs, c.containment_violations
            ));
        }
        // A fresh run never replaces a denser committed packing: its row and files stay.
        if earlier.is_none()
            && let Some(kept) = denser_committed(root, &dir, instance, outcome.summary.density)
        {
            eprintln!(
                "  kept the committed packing ({:.9}): denser than this run's {:.9}",
                kept.density, outcome.summary.density
            );
            rows.push(kept);
            continue;
        }
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        write_files(&dir, &outcome.packing, &outcome.summary, false).map_err(|e| e.to_string())?;
        // A resumed run's history starts at its own zero: the earlier runs' histories are not
        // kept, so the curve is this run's only.
        write_atomically(&dir.join(HISTORY_FILE), history.as_bytes()).map_err(|e| e.to_string())?;
        let picture = RenderOptions {
            width: 1200,
            label: Some(format!("{} ({} min)", instance.name, options.minutes)),
        };
        let figures = root.join("docs/figures");
        std::fs::create_dir_all(&figures).map_err(|e| format!("{}: {e}", figures.display()))?;
        let svg = svg_string(&outcome.packing, &picture).map_err(|e| e.to_string())?;
        let png = png_bytes(&outcome.packing, &picture).map_err(|e| e.to_string())?;
        write_atomically(
            &figures.join(format!("paper_{}.svg", instance.name)),
            svg.as_bytes(),
        )
        .map_err(|e| e.to_string())?;
        write_atomically(&figures.join(format!("paper_{}.png", instance.name)), &png)
            .map_err(|e| e.to_string())?;
        let mut row = Row {
            instance,
            density: outcome.summary.density,
            seconds_to_best: outcome.seconds_to_best,
            local_minimisations: outcome.summary.local_minimisations,
            failed_starts: outcome.failed_starts,
            certified: c.is_certified(),
            min_mu2: c.min_mu2,
            budget_seconds: options.minutes * 60.0,
            machine: crate::provenance::machine_with_threads(threads),
            method: scene.solver.method.name().to_string(),
            commit: crate::provenance::commit(),
        };
        if let Some((old, _)) = &earlier {
            // The table keeps nine decimals: the resumed packing itself reads back up to 5e-10
            // denser than its row, which is no gain.
            row.seconds_to_best = if row.density > old.density + 1e-9 {
                old.budget_seconds + row.seconds_to_best
            } else {
                old.seconds_to_best
            };
            row.budget_seconds += old.budget_seconds;
            row.local_minimisations += old.local_minimisations;
            row.failed_starts += old.failed_starts;
            if old.machine != row.machine {
                row.machine = format!("{} (resumed from: {})", row.machine, old.machine);
            }
            if old.method != row.method {
                row.method = format!("{} (resumed from: {})", row.method, old.method);
            }
        }
        rows.push(row);
    }
    let table = root.join("validation/paper_tables.csv");
    let rows = merged_by_instance(rows, earlier_rows(&table), |r| r.instance);
    write_atomically(&table, csv(&rows).as_bytes()).map_err(|e| e.to_string())?;
    let latest_table = root.join(LATEST_RUNS);
    let latest = merged_by_instance(latest, LatestRun::read_all(&latest_table), |r| r.instance);
    write_atomically(&latest_table, LatestRun::csv(&latest).as_bytes())
        .map_err(|e| e.to_string())?;
    let curves = curves(root, &rows);
    let mut outputs = crate::output::Outputs::new(false);
    render(
        &density_time_figure(&curves),
        &root.join("docs/figures"),
        DENSITY_TIME_FIGURE,
        &mut outputs,
    )
    .map_err(|e| e.to_string())?;
    write_atomically(
        &root.join("docs/paper-tables.md"),
        markdown(&rows, &curves, &latest).as_bytes(),
    )
    .map_err(|e| e.to_string())?;
    Ok(problems)
}

/// The base name of the density-against-time figure in `docs/figures`.
const DENSITY_TIME_FIGURE: &str = "paper_density_time";

/// The folder of each instance's latest run history, `<instance>.csv`.
const RUNS_DIR: &str = "validation/paper-runs";

/// The table of each instance's latest run.
const LATEST_RUNS: &str = "validation/paper_latest_runs.csv";

/// This run's rows and the earlier rows of the instances it did not run, in the order of
/// [`INSTANCES`]: rows of instances not run stay as the last run left them, so instances can be
/// run one at a time (each takes its full budget).
fn merged_by_instance<R>(
    mut rows: Vec<R>,
    earlier: Vec<R>,
    instance: impl Fn(&R) -> &'static Instance,
) -> Vec<R> {
    for old in earlier {
        if !rows.iter().any(|r| instance(r).name == instance(&old).name) {
            rows.push(old);
        }
    }
    rows.sort_by_key(|r| {
        INSTANCES
            .iter()
            .position(|i| i.name == instance(r).name)
            .unwrap_or(usize::MAX)
    });
    rows
}

/// Runs `scene` through the `ellipack pack` pipeline, calling `gained` with the report of each
/// local minimisation that raised the best certified density: the studies follow a long run by
/// its gains only, not by every start.
///
/// With `stop_at`, the run ends (as if interrupted, keeping its best certified packing) once
/// that density is reached.
///
/// # Errors
/// What [`run`] refuses.
pub(crate) fn run_noting_gains(
    scene: &Scene,
    options: &RunOptions,
    stop_at: Option<f64>,
    mut gained: impl FnMut(&MultiStartProgress) + Sync,
) -> Result<RunOutcome, ellipack::Error> {
    let mut best = 0.0;
    let reached = AtomicBool::new(false);
    run(
        scene,
        options,
        &mut Callbacks {
            finished: |p: &MultiStartProgress| {
                if p.best_density > best {
                    best = p.best_density;
                    gained(p);
                }
                if stop_at.is_some_and(|target| p.best_density >= target) {
                    reached.store(true, Ordering::Relaxed);
                }
            },
            iteration: |_: &ellipsoid_packer::multistart::SolverProgress<'_>| {},
            should_stop: || reached.load(Ordering::Relaxed),
        },
    )
}

/// An instance's latest run, whether or not it wrote the row: the table that says what one
/// version of the code does in a given budget.
#[derive(Clone, Debug, PartialEq)]
struct LatestRun {
    instance: &'static Instance,
    /// The run's best certified density.
    density: f64,
    /// Seconds from the run's start until its best certified density first reached the
    /// paper's (none: it did not).
    seconds_to_paper: Option<f64>,
    seconds_to_best: f64,
    local_minimisations: u64,
    budget_seconds: f64,
    /// Whether the run was to end at the paper's density (`--until-paper`).
    until_paper: bool,
    /// Whether the run went on from the committed packing (its times count from its own start).
    resumed: bool,
    certified: bool,
    /// The local minimisation's method (its name in scene files).
    method: String,
    /// Processor, cores and threads used.
    machine: String,
    commit: String,
}

impl LatestRun {
    const HEADER: &'static str = "instance,paper_density,density,ratio,seconds_to_paper,\
        seconds_to_best,local_minimisations,wall_budget_seconds,until_paper,resumed,certified,\
        method,machine,commit\n";

    fn csv(runs: &[LatestRun]) -> String {
        let mut out = String::from(Self::HEADER);
        for r in runs {
            let paper = r.instance.reference_density();
            let _ = writeln!(
                out,
                "{},{},{:.9},{},{},{:.1},{},{:.0},{},{},{},{},\"{}\",{}",
                r.instance.name,
                paper.map_or(String::new(), |d| format!("{d:.5}")),
                r.density,
                paper.map_or(String::new(), |d| format!("{:.5}", r.density / d)),
                r.seconds_to_paper
                    .map_or(String::new(), |t| format!("{t:.1}")),
                r.seconds_to_best,
                r.local_minimisations,
                r.budget_seconds,
                r.until_paper,
                r.resumed,
                r.certified,
                r.method,
                r.machine.replace('"', "'"),
                r.commit,
            );
        }
        out
    }

    /// The rows of an earlier table ([`read_rows`]).
    fn read_all(path: &Path) -> Vec<LatestRun> {
        read_rows(path, |field, instance, density| {
            let number = |name: &str| field(name).parse::<f64>().ok();
            LatestRun {
                instance,
                density,
                seconds_to_paper: number("seconds_to_paper"),
                seconds_to_best: number("seconds_to_best").unwrap_or(f64::NAN),
                local_minimisations: field("local_minimisations").parse().unwrap_or(0),
                budget_seconds: number("wall_budget_seconds").unwrap_or(f64::NAN),
                until_paper: field("until_paper") == "true",
                resumed: field("resumed") == "true",
                certified: field("certified") == "true",
                method: method_or_default(field("method")),
                machine: field("machine"),
                commit: field("commit"),
            }
        })
    }
}

/// Seconds from a run's start until the best density of its history first reached `paper`.
fn seconds_to_reach(history: &str, paper: f64) -> Option<f64> {
    best_density_steps(history, paper)
        .0
        .into_iter()
        .find(|&(_, ratio)| ratio >= 1.0)
        .map(|(t, _)| t)
}

/// One instance's best certified density against wall time, relative to the paper's.
struct Curve {
    instance: &'static Instance,
    /// (seconds, best density / paper density) at each local minimisation that improved it.
    points: Vec<(f64, f64)>,
    /// The end of the run's last local minimisation, up to which its best density holds.
    end_seconds: f64,
    /// Whether the run wrote the row's packing (else it ended less dense than the row).
    wrote_row: bool,
}

/// The curve of each row's latest run: its history in [`RUNS_DIR`], or for a run older than
/// that folder, the history in the packing's folder (written by the run that wrote it).
fn curves(root: &Path, rows: &[Row]) -> Vec<Curve> {
    rows.iter()
        .filter_map(|r| {
            let paper = r.instance.reference_density()?;
            let latest = root.join(RUNS_DIR).join(format!("{}.csv", r.instance.name));
            let packing = root
                .join("validation/paper-packings")
                .join(r.instance.name)
                .join(HISTORY_FILE);
            let text = std::fs::read_to_string(latest)
                .or_else(|_| std::fs::read_to_string(packing))
                .ok()?;
            let (points, end_seconds) = best_density_steps(&text, paper);
            let &(_, last) = points.last()?;
            Some(Curve {
                instance: r.instance,
                wrote_row: ended_at_the_row(last * paper, r.density),
                points,
                end_seconds,
            })
        })
        .collect()
}

/// Whether a run whose best density was `best` (a history's nine decimals) is the one that
/// wrote a row of density `row`: a run that did not ended strictly less dense.
fn ended_at_the_row(best: f64, row: f64) -> bool {
    best >= row - 2e-9
}

/// The rows of a history (`local_minimisation,seconds,density,best_density`) at which the
/// best density rose, as (seconds, best density / `paper`), and the time of its last row.
/// Rows that do not parse are skipped: the file is our own output, and a torn one only thins
/// the curve.
fn best_density_steps(history: &str, paper: f64) -> (Vec<(f64, f64)>, f64) {
    let mut steps: Vec<(f64, f64)> = Vec::new();
    let mut end: f64 = 0.0;
    for line in history.lines().skip(1) {
        let fields: Vec<&str> = line.split(',').collect();
        let (Some(Ok(seconds)), Some(Ok(best))) = (
            fields.get(1).map(|f| f.parse::<f64>()),
            fields.get(3).map(|f| f.parse::<f64>()),
        ) else {
            continue;
        };
        end = end.max(seconds);
        let ratio = best / paper;
        if steps.last().is_none_or(|&(_, r)| ratio > r) {
            steps.push((seconds, ratio));
        }
    }
    (steps, end)
}

/// Best density / paper density against wall time, a staircase per instance, one panel per
/// table of the paper (circle-231 with Table 6.1), the paper's 48-hour best at 1.
fn density_time_figure(curves: &[Curve]) -> Figure {
    let panel = |title: &str, sources: &[&str]| {
        let series = curves
            .iter()
            .filter(|c| sources.contains(&c.instance.source))
            .enumerate()
            .map(|(k, c)| Series {
                name: if c.wrote_row {
                    c.instance.name.to_string()
                } else {
                    format!("{} (latest run)", c.instance.name)
                },
                points: staircase(c),
                kind: Kind::Line,
                color: k,
            })
            .collect();
        Panel {
            title: title.into(),
            x_label: "wall time of the run (s), logarithmic".into(),
            x_log: true,
            y_label: "best certified density / paper's".into(),
            series,
            hlines: vec![(1.0, "paper (48 h)".into())],
            legend: Corner::UpperLeft,
            ..Panel::default()
        }
    };
    Figure {
        panels: vec![
            panel(
                "Ellipses (2, 1) in an ellipse (Table 6.1); circle-231 (Section 6.1.2)",
                &["Table 6.1", "Section 6.1.2"],
            ),
            panel("Ellipses (2, 1) in a rectangle (Table 6.2)", &["Table 6.2"]),
            panel(
                "Ellipsoids (1, 0.75, 0.5) in a ball (Table 6.3)",
                &["Table 6.3"],
            ),
            panel(
                "Ellipsoids (1, 0.75, 0.5) in a cuboid (Table 6.4)",
                &["Table 6.4"],
            ),
        ],
        panel_height: 480,
    }
}

/// A curve's points as a staircase: each ratio holds until the next, the last one until the
/// run's last local minimisation ended.
fn staircase(c: &Curve) -> Vec<(f64, f64)> {
    let mut points: Vec<(f64, f64)> = Vec::new();
    for &(t, r) in &c.points {
        if let Some(&(_, previous)) = points.last() {
            points.push((t, previous));
        }
        points.push((t, r));
    }
    if let Some(&(_, last)) = points.last() {
        points.push((c.end_seconds, last));
    }
    points
}

/// The committed row of `instance`, when it is at least as dense as `density` and its packing
/// in `dir` reads back and verifies (PW85 on every close pair, exact containment).
fn denser_committed(root: &Path, dir: &Path, instance: &Instance, density: f64) -> Option<Row> {
    let row = earlier_rows(&root.join("validation/paper_tables.csv"))
        .into_iter()
        .find(|r| r.instance.name == instance.name)
        .filter(|r| r.density >= density)?;
    let (packing, _) = ellipack::folder::read_packing_dir(dir).ok()?;
    ellipack::pack::verify(&packing)
        .ok()
        .filter(|c| c.is_certified())
        .map(|_| row)
}

/// The paper's time to its best solution and the local minimisations it took (Tables 6.1–6.4,
/// the fifth and fourth columns), by instance name.
const PAPER_TO_BEST: &[(&str, &str, u32)] = &[
    ("ellipse-100", "1d09h00m38s", 542),
    ("ellipse-200", "1d02h41m47s", 168),
    ("ellipse-300", "13h30m17s", 49),
    ("ellipse-400", "1d21h32m10s", 88),
    ("ellipse-500", "1d22h15m45s", 104),
    ("ellipse-1000", "1d22h10m38s", 22),
    ("rectangle-100", "1d15h24m55s", 5462),
    ("rectangle-200", "1d23h30m46s", 1811),
    ("rectangle-300", "1d23h30m27s", 839),
    ("rectangle-400", "1d15h37m55s", 425),
    ("rectangle-500", "1d15h01m11s", 773),
    ("rectangle-1000", "1d22h09m52s", 94),
    ("ball-100", "22h45m07s", 369),
    ("ball-200", "1d14h37m57s", 252),
    ("ball-300", "1d23h07m55s", 137),
    ("ball-400", "1d23h43m17s", 64),
    ("ball-500", "1d20h49m59s", 89),
    ("cuboid-100", "19h22m54s", 125),
    ("cuboid-200", "1d18h17m59s", 113),
    ("cuboid-300", "1d06h34m00s", 165),
    ("cuboid-400", "1d22h32m20s", 45),
    ("cuboid-500", "1d01h44m10s", 16),
];

/// The instance names of `rows`, comma-separated (`none` for no row).
fn names_of<'a>(rows: impl Iterator<Item = &'a Row>) -> String {
    names_of_instances(rows.map(|r| r.instance))
}

/// The names of `instances`, comma-separated (`none` for no instance).
fn names_of_instances(instances: impl Iterator<Item = &'static Instance>) -> String {
    let names: Vec<&str> = instances.map(|i| i.name).collect();
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}

/// The method of a scene file's `solver.method` key named `name`.
///
/// # Errors
/// A name that is none of them.
pub fn method_named(name: &str) -> Result<MethodName, String> {
    [
        MethodName::Lagrangian,
        MethodName::Compression,
        MethodName::CompressionLagrangian,
    ]
    .into_iter()
    .find(|m| m.name() == name)
    .ok_or_else(|| {
        format!("unknown method `{name}`: lagrangian, compression or compression-lagrangian")
    })
}

/// The paper's time to best and local minimisations to best of an instance, if it gives them.
fn paper_to_best(name: &str) -> Option<(&'static str, u32)> {
    PAPER_TO_BEST
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|&(_, t, k)| (t, k))
}

/// The rows of an earlier table at `path`, each made by `row` from its fields (by column
/// name; empty when missing), its instance and its density. None if the file is missing or
/// unreadable, and rows without a known instance or a density are skipped: the file is
/// regenerated, never an input anyone edits.
fn read_rows<R>(
    path: &Path,
    row: impl Fn(&dyn Fn(&str) -> String, &'static Instance, f64) -> R,
) -> Vec<R> {
    let Ok(mut reader) = csv::Reader::from_path(path) else {
        return Vec::new();
    };
    let Ok(headers) = reader.headers().cloned() else {
        return Vec::new();
    };
    let column = |name: &str| headers.iter().position(|h| h == name);
    let mut rows = Vec::new();
    for record in reader.records().flatten() {
        let field = |name: &str| {
            column(name)
                .and_then(|k| record.get(k))
                .unwrap_or("")
                .to_string()
        };
        let (Some(instance), Some(density)) = (
            by_name(&field("instance")),
            field("density").parse::<f64>().ok(),
        ) else {
            continue;
        };
        rows.push(row(&field, instance, density));
    }
    rows
}

/// A row's method: rows written before the column existed were all run with the default one.
fn method_or_default(method: String) -> String {
    if method.is_empty() {
        SolverSettings::defaults(Dimension::Two)
            .method
            .name()
            .to_string()
    } else {
        method
    }
}

/// The rows of an earlier `paper_tables.csv` ([`read_rows`]).
fn earlier_rows(path: &Path) -> Vec<Row> {
    read_rows(path, |field, instance, density| {
        let number = |name: &str| field(name).parse::<f64>().ok();
        Row {
            instance,
            density,
            seconds_to_best: number("seconds_to_best").unwrap_or(f64::NAN),
            local_minimisations: field("local_minimisations").parse().unwrap_or(0),
            failed_starts: field("failed_starts").parse().unwrap_or(0),
            certified: field("certified") == "true",
            min_mu2: number("min_mu2"),
            budget_seconds: number("wall_budget_seconds").unwrap_or(f64::NAN),
            machine: field("machine"),
            method: method_or_default(field("method")),
            commit: field("commit"),
        }
    })
}

fn csv(rows: &[Row]) -> String {
    let mut out = String::from(
        "instance,paper_density,paper_time_to_best,paper_local_minimisations_to_best,density,ratio,\
         seconds_to_best,local_minimisations,failed_starts,wall_budget_seconds,certified,min_mu2,\
         method,machine,commit\n",
    );
    for r in rows {
        let paper = r.instance.reference_density();
        let to_best = paper_to_best(r.instance.name);
        let _ = writeln!(
            out,
            "{},{},{},{},{:.9},{},{:.1},{},{},{:.0},{},{},{},\"{}\",{}",
            r.instance.name,
            paper.map_or(String::new(), |d| format!("{d:.5}")),
            to_best.map_or("", |p| p.0),
            to_best.map_or(String::new(), |p| p.1.to_string()),
            r.density,
            paper.map_or(String::new(), |d| format!("{:.5}", r.density / d)),
            r.seconds_to_best,
            r.local_minimisations,
            r.failed_starts,
            r.budget_seconds,
            r.certified,
            r.min_mu2.map_or(String::new(), |m| format!("{m:.9}")),
            r.method,
            r.machine.replace('"', "'"),
            r.commit,
        );
    }
    out
}

/// The page's section on the latest run of each instance: one table, and which commits and
/// budgets its rows ran with.
fn latest_runs_section(runs: &[LatestRun]) -> String {
    if runs.is_empty() {
        return String::new();
    }
    let mut commits: Vec<(&str, usize)> = Vec::new();
    for r in runs {
        match commits.iter_mut().find(|(c, _)| *c == r.commit) {
            Some((_, k)) => *k += 1,
            None => commits.push((&r.commit, 1)),
        }
    }
    let commits: Vec<String> = commits
        .iter()
        .map(|(c, k)| format!("`{c}` ({k} rows)"))
        .collect();
    let reached = runs.iter().filter(|r| r.seconds_to_paper.is_some()).count();
    let missed = names_of_instances(
        runs.iter()
            .filter(|r| r.seconds_to_paper.is_none())
            .map(|r| r.instance),
    );
    let mut out = format!(
        "## The latest run of each instance\n\n\
         Every run writes its row here, also a run that ended less dense than the committed \
         packing (`validation/paper_latest_runs.csv`): what one version of the code does in the \
         given budget. A run `until paper` ended as soon as its best certified density reached \
         the paper's; its density is then its first above the paper's, not the most it could \
         reach. A resumed run counts its times from its own start. Commits: {}. {reached} of {} \
         rows reached the paper's density; not reached: {missed}.\n\n\
         | instance | paper density (48 h) | latest run | latest / paper | reached the paper at (s) | time to best (s) | local minimisations | wall budget (min) | until paper | resumed | method | machine | certified | commit |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---|---|---|---|---|---|\n",
        commits.join(", "),
        runs.len(),
    );
    let yes_no = |b: bool| if b { "yes" } else { "no" };
    for r in runs {
        let paper = r.instance.reference_density();
        let _ = writeln!(
            out,
            "| {} | {} | {:.5} | {} | {} | {:.1} | {} | {:.0} | {} | {} | {} | {} | {} | {} |",
            r.instance.name,
            paper.map_or("—".into(), |d| format!("{d:.5}")),
            r.density,
            paper.map_or("—".into(), |d| format!("{:.4}", r.density / d)),
            r.seconds_to_paper.map_or("—".into(), |t| format!("{t:.1}")),
            r.seconds_to_best,
            r.local_minimisations,
            r.budget_seconds / 60.0,
            yes_no(r.until_paper),
            yes_no(r.resumed),
            r.method,
            r.machine,
            if r.certified { "yes" } else { "**no**" },
            r.commit,
        );
    }
    out.push('\n');
    out
}

fn markdown(rows: &[Row], curves: &[Curve], latest: &[LatestRun]) -> String {
    // The multi-start's settings as the rows ran them: the scene defaults (the same in 2D
    // and 3D), so that the page says what the code does.
    let d = SolverSettings::defaults(Dimension::Two);
    let mut out = format!(
        "# The paper's instances\n\nGenerated by `cargo xtask paper-tables` (do not edit; \
         each run replaces the rows of the instances it ran, except that a fresh run less dense \
         than the committed packing leaves that packing and its row as they were). Each \
         instance is packed by the pipeline of `ellipack pack`: the multi-start of \
         `ellipsoid-packer` (the paper's lattice start; the {} tightest cuts of the dense \
         lattice, every item turned by up to 0.01 rad; then perturbations of the best packing at \
         amplitudes 1, 1/2 and 1/4 of the paper's, every {}th start a further lattice start, \
         perturbations twice as wide after {} starts without a relative gain of 1e-5, half as wide \
         after each round with a failed perturbation that cost more than 4 times the evaluations of \
         the median successful one (down to a quarter), and a new \
         chain from fresh lattice starts after {} such starts), every local minimisation \
         certified with PW85 and exact containment and repaired, for the wall time, with the local method and on the machine given in its row \
         (`lagrangian`: the paper's augmented Lagrangian with the container among the \
         variables; `compression-lagrangian`: compression of the container first, then the \
         augmented Lagrangian from its packing; `cargo xtask paper-tables --method`). Each row \
         ran with the code of the commit in its row, which may differ from today's: `cargo \
         xtask paper-tables` runs the rows again with the code of the checkout, and the section \
         on the latest run of each instance gives what that code reached, also where it did not \
         replace the packing. The paper's figures are the best of a 48-hour multi-start \
         on an Intel i7-3770 (Birgin, Lobato, Martínez, Section 6; `≈` where the paper gives a \
         radius only). The packings are in `validation/paper-packings/<instance>/` (`ellipack \
         verify` re-checks them, `ellipack pack --instance <instance> --resume --out <that \
         folder>` continues them; `cargo xtask paper-tables --resume` does so for a row, whose \
         budget, time to best and local minimisations then count every run of it; `cargo xtask \
         paper-tables --report-only` writes this page again from the committed rows).\n\n\
         | instance | paper density (48 h) | paper: time to best (local minimisations) | ours | ours / paper | time to best (s) | local minimisations | wall budget (min) | method | machine | certified | commit |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---|---|---|---|\n",
        d.lattice_starts, d.fresh_lattice_every, d.widen_after, d.restart_after,
    );
    for r in rows {
        let paper = r.instance.reference_density();
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.5} | {} | {:.1} | {} | {:.0} | {} | {} | {} | {} |",
            r.instance.name,
            paper.map_or("—".into(), |d| format!("{d:.5}")),
            paper_to_best(r.instance.name).map_or("—".into(), |(t, k)| format!("{t} ({k})")),
            r.density,
            paper.map_or("—".into(), |d| format!("{:.4}", r.density / d)),
            r.seconds_to_best,
            r.local_minimisations,
            r.budget_seconds / 60.0,
            r.method,
            r.machine,
            if r.certified { "yes" } else { "**no**" },
            r.commit,
        );
    }
    out.push('\n');
    out.push_str(&latest_runs_section(latest));
    let curve_of = |r: &Row| curves.iter().find(|c| c.instance.name == r.instance.name);
    let _ = writeln!(
        out,
        "## Density against time\n\n\
         ![Best certified density over the paper's against wall time](figures/{DENSITY_TIME_FIGURE}.png)\n\n\
         The best certified density of each instance's latest run, over the paper's, after \
         each local minimisation that raised it (`validation/paper-runs/<instance>.csv`, which \
         every run writes; for a row whose latest run is older than that folder, `history.csv` \
         in the packing's folder; a resumed run's curve starts at its own zero). The latest run \
         wrote the row's packing for: {}. It ended less dense than the committed packing, \
         which an earlier run wrote, for: {} (`(latest run)` in the legend: the curve shows the \
         code of the latest run with its own budget, the row an earlier run). No curve: {} (no \
         history of a run, or one without a finished local minimisation).\n",
        names_of(
            rows.iter()
                .filter(|r| curve_of(r).is_some_and(|c| c.wrote_row))
        ),
        names_of(
            rows.iter()
                .filter(|r| curve_of(r).is_some_and(|c| !c.wrote_row))
        ),
        names_of(rows.iter().filter(|r| curve_of(r).is_none())),
    );
    for r in rows {
        let _ = writeln!(
            out,
            "![{}](figures/paper_{}.png)\n",
            r.instance.description(),
            r.instance.name
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_curve_steps_at_each_gain_and_ends_at_the_last_row() {
        let history = "local_minimisation,seconds,density,best_density\n\
                       1,2.0,0.80,0.80\n2,4.0,0.79,0.80\nnot,a,row\n3,6.5,0.90,0.90\n4,9.0,0.85,0.90\n";
        let (steps, end) = best_density_steps(history, 0.9);
        assert_eq!(steps.len(), 2);
        assert_eq!(steps[0].0, 2.0);
        assert!((steps[0].1 - 0.8 / 0.9).abs() < 1e-15);
        assert_eq!(steps[1], (6.5, 1.0));
        assert_eq!(end, 9.0);
        assert_eq!(
            best_density_steps("local_minimisation,seconds\n", 0.9).0,
            []
        );
    }

    #[test]
    fn the_paper_is_reached_at_the_first_best_at_or_above_it() {
        let history = "local_minimisation,seconds,density,best_density\n\
                       1,2.0,0.80,0.80\n2,4.0,0.899,0.899\n3,6.5,0.90,0.90\n4,9.0,0.95,0.95\n";
        assert_eq!(seconds_to_reach(history, 0.9), Some(6.5));
        assert_eq!(seconds_to_reach(history, 0.96), None);
    }

    /// The latest runs' table is read back to carry the rows of instances not run: no column
    /// may be lost.
    #[test]
    fn latest_runs_read_back_to_the_same_text() {
        let run = |name: &str, seconds_to_paper: Option<f64>, until_paper: bool| LatestRun {
            instance: by_name(name).expect("an instance"),
            density: 0.876543219,
            seconds_to_paper,
            seconds_to_best: 321.5,
            local_minimisations: 77,
            budget_seconds: 600.0,
            until_paper,
            resumed: !until_paper,
            certified: true,
            method: if until_paper {
                "lagrangian"
            } else {
                "compression-lagrangian"
            }
            .into(),
            machine: "AMD EPYC, 2 cores, 2 threads used".into(),
            commit: "abc1234".into(),
        };
        let runs = vec![
            run("ellipse-100", Some(120.25), true),
            run("circle-231", None, false),
        ];
        let path = std::env::temp_dir().join(format!("latest-runs-{}.csv", std::process::id()));
        std::fs::write(&path, LatestRun::csv(&runs)).expect("written");
        let back = LatestRun::read_all(&path);
        std::fs::remove_file(&path).expect("removed");
        assert_eq!(LatestRun::csv(&back), LatestRun::csv(&runs));
        assert_eq!(back[1].seconds_to_paper, None);
        assert!(back[0].until_paper && !back[0].resumed);
        let section = latest_runs_section(&back);
        assert!(
            section.contains("1 of 2 rows reached the paper's density; not reached: circle-231")
        );
        assert!(section.contains("`abc1234` (2 rows)"));
    }

    /// A run told to stop at a density ends at the first local minimisation that reaches it;
    /// without it, the run takes all the local minimisations it is given.
    #[test]
    fn a_run_ends_once_it_reaches_the_density_to_stop_at() {
        let mut scene = Scene::from_toml_str(
            "dimension = 2\nseed = 3\n[container]\nkind = \"circle\"\n\
             [[shapes]]\ncount = 5\nsemi_axes = [1.0, 0.5]\n",
            "five ellipses",
        )
        .expect("a scene");
        scene.solver.threads = 1;
        scene.solver.local_minimisations = Some(6);
        let options = RunOptions::default();
        let whole = run_noting_gains(&scene, &options, None, |_| {}).expect("packed");
        assert_eq!(whole.summary.local_minimisations, 6);
        let stopped = run_noting_gains(&scene, &options, Some(0.1), |_| {}).expect("packed");
        assert_eq!(stopped.summary.local_minimisations, 1);
        assert!(stopped.summary.density >= 0.1);
        assert!(stopped.summary.certificate.is_certified());
    }

    #[test]
    fn methods_are_read_by_their_scene_names() {
        assert_eq!(
            method_named("compression-lagrangian"),
            Ok(MethodName::CompressionLagrangian)
        );
        assert!(method_named("simulated-annealing").is_err());
    }

    /// A run ended at its row when its history's best (nine decimals) is the row's density.
    #[test]
    fn a_run_less_dense_than_its_row_did_not_write_it() {
        assert!(ended_at_the_row(0.896103638, 0.8961036381));
        assert!(ended_at_the_row(0.896103639, 0.896103638));
        assert!(!ended_at_the_row(0.896103630, 0.896103638));
        assert!(!ended_at_the_row(0.885636508, 0.886255838));
    }

    /// Rows of instances not run are carried over from the committed table: reading it and
    /// writing it again must lose no column, the commit and the method included.
    #[test]
    fn the_committed_table_reads_back_to_the_same_text() {
        let table = Path::new(env!("CARGO_MANIFEST_DIR")).join("../validation/paper_tables.csv");
        let text = std::fs::read_to_string(&table).expect("the committed table");
        let rows = earlier_rows(&table);
        assert_eq!(rows.len(), INSTANCES.len());
        assert!(rows.iter().all(|r| !r.commit.is_empty()));
        assert_eq!(csv(&rows), text);
    }

    /// A fresh run keeps the committed packing when it is at least as dense and verifies, and
    /// only then.
    #[test]
    fn a_denser_committed_packing_is_kept() {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let instance = by_name("ball-100").expect("an instance");
        let dir = repo.join("validation/paper-packings/ball-100");
        let committed = earlier_rows(&repo.join("validation/paper_tables.csv"))
            .into_iter()
            .find(|r| r.instance.name == "ball-100")
            .expect("a committed row")
            .density;
        let kept = denser_committed(&repo, &dir, instance, committed - 1e-6).expect("kept");
        assert_eq!(kept.density, committed);
        assert!(denser_committed(&repo, &dir, instance, committed).is_some());
        assert!(denser_committed(&repo, &dir, instance, committed + 1e-6).is_none());

        // A committed packing that does not read back (here: a folder without one) is no
        // reason to keep anything.
        let empty = std::env::temp_dir().join(format!("paper-tables-{}", std::process::id()));
        std::fs::create_dir_all(&empty).expect("a temporary folder");
        assert!(denser_committed(&repo, &empty, instance, 0.0).is_none());
        std::fs::remove_dir_all(&empty).expect("removed");
    }
}
