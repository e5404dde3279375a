//! `cargo xtask scale`: the cost of one local minimisation against the number of items m.
//!
//! Each run is what `ellipack pack` runs for a scene with `local_minimisations = 1`: the
//! packer's entry point (`ellipsoid_packer::Packer::run`) with the scene's default settings,
//! seed 1 — ellipsoids (1, 0.75, 0.5) in a ball from the packer's first start (the tightest cut
//! of the face-centred cubic lattice, every item turned by up to 0.01 rad); with the augmented
//! Lagrangian a first solve at the paper's feasibility tolerance 1e-4, the polish at 1e-10, the
//! certificate and the repair; with compression its certified placements. A run still going
//! when its wall-clock budget ends is stopped, and its best certified point is kept like any
//! other; its row says `budget`.
//!
//! Rows are kept by (m, method, threads) in `validation/scale.csv`, so that sizes and
//! solvers can be measured in separate invocations (a large m takes its whole budget; the
//! table is read again before each row is added, so invocations may run side by side); the
//! figure `docs/figures/scale.{svg,png}` and the table between the markers of
//! `docs/packing.md` are drawn from every row.
//!
//! Threads: the run uses `RAYON_NUM_THREADS` threads (every core by default) when xtask is
//! built with its `rayon` feature (`cargo run --release -p xtask --features rayon -- scale`),
//! one otherwise.

use crate::error::Error;
use crate::output::{Outputs, Stability};
use crate::periodic_peer::{from_columns, read_rows};
use crate::plot::{Corner, Figure, Kind, Panel, Series, render};
use auglag::InnerSolver;
use ellipsoid_packer::local::{LocalMethod, LocalSettings};
use ellipsoid_packer::multistart::{SolverEvent, SolverProgress};
use ellipsoid_packer::{Goal, MultiStartSettings, Observer, Outcome, Packer, Problem, Settings};
use implicit_packing::containment::ContainerShape;
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// What the study runs.
#[derive(Clone, Debug, clap::Args)]
pub struct Options {
    /// Numbers of items.
    #[arg(long, num_args = 1.., default_values_t = [100, 1000, 10_000, 100_000])]
    pub sizes: Vec<usize>,
    /// Methods: the augmented Lagrangian with the inner solver `lbfgs` (projected L-BFGS),
    /// `spg` (spectral projected gradient), `newton` (truncated Newton, preconditioned) or
    /// `newton-plain` (truncated Newton, plain conjugate gradients); `compression`;
    /// `compression+lbfgs` (compression, then the augmented Lagrangian).
    #[arg(long, num_args = 1.., default_values = ["lbfgs", "spg", "newton", "compression", "compression+lbfgs"])]
    pub solvers: Vec<String>,
    /// Wall-clock minutes per local minimisation; a run still going is stopped there and
    /// the point it reached certified and repaired.
    #[arg(long, default_value_t = 30.0)]
    pub budget_minutes: f64,
}

/// One local minimisation, measured.
#[derive(Clone, Debug, PartialEq)]
struct Row {
    m: usize,
    solver: String,
    threads: usize,
    /// `converged`, `max outer iterations`, `budget`, … (the kept solve's stop reason).
    stop: String,
    outer: usize,
    inner: usize,
    evaluations: usize,
    /// Hessian–vector products of the kept solve (truncated Newton only).
    hessian_products: usize,
    first_solve_seconds: f64,
    seconds: f64,
    /// The wall-clock budget the run was given.
    budget_minutes: f64,
    density: f64,
    density_before_repair: f64,
    certified: bool,
    /// Peak resident memory of the study's process when the row was measured.
    peak_rss_mib: f64,
    machine: String,
    commit: String,
}

fn study(message: String) -> Error {
    Error::Study {
        context: "scale".into(),
        message,
    }
}

/// The semi-axes of every item: the paper's ellipsoids of Tables 6.3 and 6.4.
const AXES: [f64; 3] = [1.0, 0.75, 0.5];

/// The run's seed, as a scene's `seed = 1`.
const SEED: u64 = 1;

/// The settings of one local minimisation by its name in the study: an inner solver of the
/// augmented Lagrangian, or compression (alone or followed by the augmented Lagrangian), whose
/// placements use projected L-BFGS.
fn local_settings(name: &str) -> Result<LocalSettings, Error> {
    let (solver, method) = match name {
        "lbfgs" => (
            InnerSolver::ProjectedLbfgs,
            LocalMethod::AugmentedLagrangian,
        ),
        "spg" => (InnerSolver::Spg, LocalMethod::AugmentedLagrangian),
        "newton" => (
            InnerSolver::TruncatedNewton,
            LocalMethod::AugmentedLagrangian,
        ),
        "newton-plain" => {
            return Ok(LocalSettings::default()
                .with_inner_solver(InnerSolver::TruncatedNewton)
                .with_cg_preconditioner_memory(0));
        }
        "compression" => (InnerSolver::ProjectedLbfgs, LocalMethod::Compression),
        "compression+lbfgs" => (
            InnerSolver::ProjectedLbfgs,
            LocalMethod::CompressionThenLagrangian,
        ),
        other => {
            return Err(study(format!(
                "unknown method `{other}` (lbfgs, spg, newton, newton-plain, compression, compression+lbfgs)"
            )));
        }
    };
    Ok(LocalSettings::default()
        .with_inner_solver(solver)
        .with_method(method))
}

/// Threads the model's pair sums use: rayon's pool with the `rayon` feature, else one.
fn threads() -> usize {
    if cfg!(feature = "rayon") {
        std::env::var("RAYON_NUM_THREADS")
            .ok()
            .and_then(|v| v.parse().ok())
            .filter(|&n| n > 0)
            .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from))
    } else {
        1
    }
}

/// The process's peak resident set in MiB (`VmHWM` of `/proc/self/status`; NaN elsewhere).
pub(crate) fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        })
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// Counts of one local minimisation over both of its solves, gathered from the progress
/// reports (each solve counts from zero).
#[derive(Default)]
struct Tally {
    outer: usize,
    inner: usize,
    evaluations: usize,
    /// The last report of the solve under way: (outer, inner, evaluations).
    current: (usize, usize, usize),
    /// When the second solve (the polish) began, from the run's start.
    polish_from: Option<Duration>,
}

impl Tally {
    /// Takes a report `now` = (outer, inner, evaluations) of the solve under way.
    fn see(&mut self, now: (usize, usize, usize), elapsed: Duration) {
        if now.2 < self.current.2 {
            self.close();
            self.polish_from.get_or_insert(elapsed);
        }
        self.current = now;
    }

    fn close(&mut self) {
        self.outer += self.current.0;
        self.inner += self.current.1;
        self.evaluations += self.current.2;
        self.current = (0, 0, 0);
    }
}

/// What the study hears of the run: the solver's counts, and whether the budget has run out.
struct Watch {
    start: Instant,
    budget: Duration,
    tally: Mutex<Tally>,
}

impl Observer for Watch {
    fn iteration(&self, p: &SolverProgress<'_>) {
        let elapsed = self.start.elapsed();
        if let Ok(mut tally) = self.tally.lock() {
            tally.see(
                (p.outer_iteration, p.total_inner_iterations, p.evaluations),
                elapsed,
            );
        }
        if let SolverEvent::Outer {
            objective,
            infeasibility,
            ..
        } = p.event
        {
            eprintln!(
                "  {:8.1} s  outer {:3}  inner {:7}  objective {objective:.6e}  infeasibility \
                 {infeasibility:.2e}",
                elapsed.as_secs_f64(),
                p.outer_iteration,
                p.total_inner_iterations,
            );
        }
    }

    fn should_stop(&self) -> bool {
        self.start.elapsed() >= self.budget
    }
}

/// One local minimisation of `m` ellipsoids with `solver`, stopped after `budget`: the run of a
/// scene with `local_minimisations = 1` ([`Packer::run`], as `ellipack pack` runs it).
fn measure(m: usize, solver: &str, budget: Duration) -> Result<Row, Error> {
    let failed = |e: &dyn std::fmt::Display| study(format!("m = {m}, {solver}: {e}"));
    let problem = Problem {
        semi_axes: vec![AXES; m],
        shape: ContainerShape::Ball,
        goal: Goal::Densest,
        resume: None,
    };
    let multistart = MultiStartSettings::recommended(3, SEED)
        .with_local(local_settings(solver)?)
        .with_max_local_minimisations(1)
        .with_threads(threads())
        .with_time_limit(None);
    let settings = Settings {
        multistart,
        orientations: Vec::new(),
    };
    let mut watch = Watch {
        start: Instant::now(),
        budget,
        tally: Mutex::new(Tally::default()),
    };
    let outcome = Packer::new(problem, settings)
        .and_then(|packer| packer.run(&mut watch))
        .map_err(|e| failed(&e))?;
    let Outcome::Packed(packed) = outcome else {
        return Err(study(format!("m = {m}, {solver}: no packing")));
    };
    let seconds = watch.start.elapsed().as_secs_f64();
    let mut tally = watch.tally.into_inner().map_err(|e| failed(&e))?;
    tally.close();
    let stop = if packed.interrupted {
        "budget".to_string()
    } else {
        stop_reason(packed.solver.stop_reason)
    };
    let density = packed.configuration.density();
    Ok(Row {
        m,
        solver: solver.to_string(),
        threads: threads(),
        stop,
        outer: tally.outer,
        inner: tally.inner,
        evaluations: tally.evaluations,
        hessian_products: packed.solver.hessian_products,
        first_solve_seconds: tally.polish_from.map_or(seconds, |d| d.as_secs_f64()),
        seconds,
        budget_minutes: budget.as_secs_f64() / 60.0,
        density,
        density_before_repair: packed.repair.map_or(density, |r| r.density_before),
        certified: packed.certificate.is_feasible(),
        peak_rss_mib: peak_rss_mib(),
        machine: crate::provenance::machine_with_threads(threads()),
        commit: crate::provenance::commit(),
    })
}

/// The stop reason in words for the table.
fn stop_reason(reason: auglag::StopReason) -> String {
    let debug = format!("{reason:?}");
    let mut words = String::new();
    for (k, c) in debug.chars().enumerate() {
        if c.is_uppercase() && k > 0 {
            words.push(' ');
        }
        words.push(c.to_ascii_lowercase());
    }
    words
}

/// Runs the study and rewrites its table, figure and section.
///
/// # Errors
/// An unknown solver, a non-positive budget, a table that cannot be read or an output that
/// cannot be written.
pub fn run_all(root: &Path, options: &Options) -> Result<(), Error> {
    if !(options.budget_minutes.is_finite() && options.budget_minutes > 0.0) {
        return Err(study(format!(
            "--budget-minutes must be positive, got {}",
            options.budget_minutes
        )));
    }
    for s in &options.solvers {
        local_settings(s)?;
    }
    let table = root.join("validation/scale.csv");
    read_table(&table)?;
    let budget = Duration::from_secs_f64(options.budget_minutes * 60.0);
    let mut sizes = options.sizes.clone();
    // Ascending, so that the process's peak memory after a row is that row's own.
    sizes.sort_unstable();
    for &m in &sizes {
        for solver in &options.solvers {
            eprintln!("m = {m}, {solver}, {} thread(s):", threads());
            let row = measure(m, solver, budget)?;
            eprintln!(
                "  density {:.5}, {:.1} s, {} ({} outer / {} inner iterations)",
                row.density, row.seconds, row.stop, row.outer, row.inner
            );
            // Read again: another invocation may have added rows since.
            let mut rows = read_table(&table)?;
            rows.retain(|r| !(r.m == row.m && r.solver == row.solver && r.threads == row.threads));
            rows.push(row);
            rows.sort_by(|a, b| {
                (a.m, a.threads, a.solver.as_str()).cmp(&(b.m, b.threads, b.solver.as_str()))
            });
            // Written after every run: a later size may take its whole budget.
            write_outputs(root, &table, &rows)?;
        }
    }
    Ok(())
}

fn write_outputs(root: &Path, table: &Path, rows: &[Row]) -> Result<(), Error> {
    let mut outputs = Outputs::new(false);
    outputs.write(table, csv(rows).as_bytes(), Stability::Volatile)?;
    render(
        &figure(rows),
        &root.join("docs/figures"),
        "scale",
        &mut outputs,
    )?;
    let doc_path = root.join("docs/packing.md");
    let doc = std::fs::read_to_string(&doc_path).map_err(crate::error::io(&doc_path))?;
    let text = between_markers(&doc, &markdown(rows)).ok_or_else(|| {
        study(format!(
            "{}: the markers {BEGIN} … {END} are missing",
            doc_path.display()
        ))
    })?;
    outputs.write(&doc_path, text.as_bytes(), Stability::Volatile)
}

const HEADER: &str = "m,solver,threads,stop,outer_iterations,inner_iterations,evaluations,\
                      hessian_products,first_solve_seconds,seconds,budget_minutes,density,\
                      density_before_repair,certified,peak_rss_mib,machine,commit";

/// Writes one line through `$format`: `$row`'s counts and times (`m` to `seconds`, the columns
/// the CSV file and the Markdown table share, in this order), then `$rest`, where the two
/// differ.
macro_rules! write_row {
    ($out:expr, $format:literal, $row:expr, $($rest:expr),+ $(,)?) => {
        writeln!(
            $out, $format, $row.m, $row.solver, $row.threads, $row.stop, $row.outer, $row.inner,
            $row.evaluations, $row.hessian_products, $row.first_solve_seconds, $row.seconds,
            $($rest),+
        )
    };
}

fn csv(rows: &[Row]) -> String {
    crate::output::table_text(&format!("{HEADER}\n"), rows, |out, r| {
        write_row!(
            out,
            "{},{},{},{},{},{},{},{},{:.2},{:.2},{},{:.6},{:.6},{},{:.1},\"{}\",{}",
            r,
            r.budget_minutes,
            r.density,
            r.density_before_repair,
            r.certified,
            r.peak_rss_mib,
            r.machine.replace('"', "'"),
            r.commit
        )
    })
}

fn read_table(path: &Path) -> Result<Vec<Row>, Error> {
    read_rows(path, |f| {
        Ok(from_columns!(f => Row {
            m, solver, threads, stop, outer: "outer_iterations", inner: "inner_iterations",
            evaluations, hessian_products, first_solve_seconds, seconds, budget_minutes, density,
            density_before_repair, certified, peak_rss_mib, machine, commit,
        }))
    })
}

/// Rows grouped by (solver, threads), in the table's order.
fn groups(rows: &[Row]) -> Vec<((String, usize), Vec<&Row>)> {
    let mut out: Vec<((String, usize), Vec<&Row>)> = Vec::new();
    for r in rows {
        let key = (r.solver.clone(), r.threads);
        match out.iter_mut().find(|(k, _)| *k == key) {
            Some((_, v)) => v.push(r),
            None => out.push((key, vec![r])),
        }
    }
    for (_, v) in &mut out {
        v.sort_by_key(|r| r.m);
    }
    out
}

fn figure(rows: &[Row]) -> Figure {
    let series = |value: fn(&Row) -> f64| -> Vec<Series> {
        groups(rows)
            .into_iter()
            .enumerate()
            .map(|(k, ((solver, threads), v))| Series {
                name: format!("{solver}, {threads} thread(s)"),
                points: v.iter().map(|r| (r.m as f64, value(r))).collect(),
                kind: Kind::LinePoints,
                color: k,
            })
            .collect()
    };
    Figure {
        panels: vec![
            Panel {
                title: "One local minimisation of m ellipsoids (1, 0.75, 0.5) in a ball: wall time"
                    .into(),
                x_label: "m".into(),
                y_label: "seconds (first solve, polish, certificate, repair)".into(),
                x_log: true,
                y_log: true,
                series: series(|r| r.seconds),
                legend: Corner::UpperLeft,
                ..Panel::default()
            },
            Panel {
                title: "Density of the certified packing (runs stopped by the budget included)"
                    .into(),
                x_label: "m".into(),
                y_label: "density".into(),
                x_log: true,
                series: series(|r| r.density),
                legend: Corner::LowerRight,
                ..Panel::default()
            },
        ],
        panel_height: 420,
    }
}

fn markdown(rows: &[Row]) -> String {
    crate::output::table_text(
        "| m | method | threads | stop | outer / inner iterations | evaluations | Hessian \
         products | first solve (s) | wall time (s) | ms per inner iteration | budget (min) | density | certified | peak memory (MiB) \
         | machine | commit |\n\
         |---:|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---|---|\n",
        rows,
        |out, r| {
            write_row!(
                out,
                "| {} | {} | {} | {} | {} / {} | {} | {} | {:.1} | {:.1} | {:.2} | {} | {:.5} | {} | {:.0} | {} | {} |",
                r,
                1e3 * r.seconds / r.inner.max(1) as f64,
                r.budget_minutes,
                r.density,
                if r.certified { "yes" } else { "no" },
                r.peak_rss_mib,
                r.machine,
                r.commit
            )
        },
    )
}

const BEGIN: &str = "<!-- scale: generated by `cargo xtask scale`; do not edit -->";
const END: &str = "<!-- scale: end -->";

/// `text` with what lies between the study's markers replaced by `table`.
fn between_markers(text: &str, table: &str) -> Option<String> {
    crate::output::between_markers(text, (BEGIN, END), table)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(m: usize, solver: &str) -> Row {
        Row {
            m,
            solver: solver.into(),
            threads: 1,
            stop: "converged".into(),
            outer: 27,
            inner: 27_917,
            evaluations: 28_475,
            hessian_products: 0,
            first_solve_seconds: 47.5,
            seconds: 70.61,
            budget_minutes: 30.0,
            density: 0.69023,
            density_before_repair: 0.69025,
            certified: true,
            peak_rss_mib: 21.5,
            machine: "Intel \"Xeon\", 2 cores".into(),
            commit: "abc1234".into(),
        }
    }

    #[test]
    fn the_table_reads_back_what_it_wrote() {
        let dir = std::env::temp_dir().join(format!("xtask-scale-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scale.csv");
        let rows = vec![row(100, "lbfgs"), row(1000, "spg")];
        std::fs::write(&path, csv(&rows)).unwrap();
        let back = read_table(&path).unwrap();
        assert_eq!(back.len(), 2);
        assert_eq!(back[1].m, 1000);
        assert_eq!(back[1].solver, "spg");
        assert_eq!(back[0].machine, "Intel 'Xeon', 2 cores");
        assert_eq!(back[0].inner, 27_917);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_malformed_table_names_its_line_and_column() {
        let dir = std::env::temp_dir().join(format!("xtask-scale-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scale.csv");
        let text = csv(&[row(100, "lbfgs")]).replace(",0.690230,", ",dense,");
        std::fs::write(&path, text).unwrap();
        let message = read_table(&path).unwrap_err().to_string();
        assert!(message.contains("density"), "{message}");
        assert!(message.contains('2'), "{message}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_tally_adds_both_solves() {
        let mut t = Tally::default();
        t.see((32, 62_056, 62_611), Duration::from_secs(44));
        t.see((33, 64_056, 64_632), Duration::from_secs(47));
        // The polish's first report counts from zero again.
        t.see((1, 4, 14), Duration::from_secs(48));
        t.see((2, 19, 36), Duration::from_secs(49));
        t.close();
        assert_eq!((t.outer, t.inner, t.evaluations), (35, 64_075, 64_668));
        assert_eq!(t.polish_from, Some(Duration::from_secs(48)));
    }

    #[test]
    fn stop_reasons_read_as_words() {
        assert_eq!(
            stop_reason(auglag::StopReason::MaxOuterIterations),
            "max outer iterations"
        );
        assert_eq!(stop_reason(auglag::StopReason::Converged), "converged");
    }

    #[test]
    fn the_section_replaces_only_what_lies_between_the_markers() {
        let text = format!("# Title\n\n{BEGIN}\nold\n{END}\nafter\n");
        let new = between_markers(&text, &markdown(&[row(100, "lbfgs")])).unwrap();
        assert!(
            new.contains("| 100 | lbfgs | 1 | converged | 27 / 27917 |"),
            "{new}"
        );
        assert!(new.ends_with(&format!("{END}\nafter\n")));
        assert!(between_markers("no markers", "x").is_none());
    }
}
