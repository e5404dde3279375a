//! Repository chores for ellipack, run as `cargo xtask <command>` (alias in
//! `.cargo/config.toml`).

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use xtask::{Part, Run, workspace_root};

/// ellipack's repository tasks.
#[derive(Parser)]
#[command(name = "cargo xtask")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Regenerate and check the evidence: theory checks, snapshots, CSV data, figures and
    /// docs/validation.md. Exits non-zero if any check fails.
    Validate {
        /// The short run meant for CI (≤ 3 minutes on 2 cores).
        #[arg(long, global = true)]
        quick: bool,
        /// Write nothing; fail if a stable generated file differs from what the code produces.
        #[arg(long, global = true)]
        check: bool,
        /// Run one part only (default: all).
        #[command(subcommand)]
        part: Option<PartArg>,
    },
    /// Run the paper's instances (Tables 6.1–6.4) with the `ellipack pack` pipeline for a
    /// wall-clock budget each; write validation/paper_tables.csv, docs/paper-tables.md, the
    /// pictures and the packings.
    PaperTables {
        #[command(flatten)]
        options: xtask::paper_tables::Options,
        /// Run nothing: write the table, docs/paper-tables.md and the density-against-time
        /// figure again from the committed rows and histories.
        #[arg(long, conflicts_with_all = ["instances", "resume"])]
        report_only: bool,
    },
    /// Measure the periodic cell through the `ellipack pack` pipeline: variable cells with 1, 2
    /// and 4 items of three shapes, and a fixed cube of ellipsoids at packing fraction 0.60 and
    /// above; write validation/periodic_cells.csv and the table in docs/periodic.md.
    PeriodicCells(xtask::periodic_cells::Options),
    /// One local minimisation of m ellipsoids (1, 0.75, 0.5) in a ball against m, with each
    /// inner solver: iterations, evaluations, wall time, density, memory. Writes
    /// validation/scale.csv, docs/figures/scale.{svg,png} and a table in docs/packing.md.
    /// Two threads inside the model: `cargo run --release -p xtask --features rayon -- scale`.
    Scale(xtask::scale::Options),
    /// The random packings of validation/random/*.toml through the `ellipack pack` pipeline
    /// (two threads by default): packing fraction, wall time, peak memory, Q6 (2D: psi6),
    /// nematic order, contacts. Writes validation/random.csv and the table in docs/random.md.
    Random(xtask::random_study::Options),
    /// Ellipsoids (1, 0.75, 0.5) in a periodic box, one thread: ellipack beside hoomd-rs
    /// (hard-particle Monte Carlo with `QuickCompress`), density against wall time, and the
    /// cost of both overlap tests. Writes validation/periodic_peer*.csv, the figure
    /// docs/figures/periodic-density-time.{svg,png} and a section of docs/periodic.md. The
    /// peer needs xtask's `peer` feature:
    /// `cargo run --release -p xtask --features peer -- periodic-peer`.
    PeriodicPeer(PeerArgs),
    /// Run the parser fuzz suite (crates/ellipack/tests/fuzz.rs: random and mutated pairs,
    /// measure, scene, packing.csv, summary.json and packing.xyz files) with many more cases
    /// than the normal test run, in release mode. Exits non-zero if any input panics.
    Fuzz {
        /// Cases per parser (the normal test run uses 256).
        #[arg(long, default_value_t = 100_000)]
        cases: u32,
        /// Build in the dev profile instead of release (quicker to build, slower to run).
        #[arg(long)]
        dev: bool,
    },
}

/// The options of `cargo xtask periodic-peer`.
#[derive(clap::Args)]
struct PeerArgs {
    /// Wall seconds per run (default: 300 for N ≥ 1000, 120 below).
    #[arg(long)]
    seconds: Option<f64>,
    /// Numbers of ellipsoids.
    #[arg(long = "n", num_args = 1.., default_values_t = [100, 1000])]
    ns: Vec<usize>,
    /// Who packs.
    #[arg(long, value_enum, default_value_t = WhoArg::Both)]
    who: WhoArg,
    /// Random pairs of the overlap-test comparison (0: skip it; needs the peer).
    #[arg(long, default_value_t = 200_000)]
    overlap_pairs: usize,
    /// Scene file of our run, `{count}` standing for the count (default: a variable periodic
    /// cell).
    #[arg(long)]
    scene: Option<std::path::PathBuf>,
    /// Seed of the peer's simulation and of the random pairs.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The peer's largest trial translation.
    #[arg(long, default_value_t = xtask::periodic_peer::PeerMoves::default().translate)]
    peer_translate: f64,
    /// The peer's largest trial rotation (radians).
    #[arg(long, default_value_t = xtask::periodic_peer::PeerMoves::default().rotate)]
    peer_rotate: f64,
    /// Also run our random jammed packing of the same items (recorded as `random`).
    #[arg(long)]
    random: bool,
    /// Run nothing: write the figure and the section of docs/periodic.md again from the
    /// recorded rows.
    #[arg(long)]
    report_only: bool,
}

#[derive(clap::ValueEnum, Clone, Copy)]
enum WhoArg {
    /// hoomd-rs only.
    Peer,
    /// ellipack only.
    Ours,
    /// Both.
    Both,
}

#[derive(Subcommand, Clone, Copy)]
enum PartArg {
    /// Theory checks: each residual against its tolerance, PASS/FAIL.
    Theory,
    /// The insta snapshots (fixed pairs, check table), compared with the committed ones.
    Snapshots,
    /// Figures comparing both criteria (approach path, agreement and cost, packings).
    Figures,
    /// Stiff and extreme cases.
    Stiff,
    /// Error against run time; model time against m.
    Timing,
}

fn main() -> ExitCode {
    match Cli::parse().command {
        Command::Fuzz { cases, dev } => fuzz(cases, dev),
        Command::PeriodicCells(options) => {
            match xtask::periodic_cells::run_all(&workspace_root(), &options) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => failed(e),
            }
        }
        Command::PeriodicPeer(args) => periodic_peer(args),
        Command::Scale(options) => match xtask::scale::run_all(&workspace_root(), &options) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => failed(e),
        },
        Command::Random(options) => match xtask::random_study::run(&workspace_root(), &options) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => failed(e),
        },
        Command::PaperTables {
            mut options,
            report_only,
        } => {
            if report_only {
                options.instances.clear();
            } else if options.instances.is_empty() {
                options.instances = xtask::paper_tables::TARGETS
                    .iter()
                    .map(|s| s.to_string())
                    .collect();
            }
            with_problems(
                xtask::paper_tables::run_all(&workspace_root(), &options),
                "NOT CERTIFIED",
            )
        }
        Command::Validate { quick, check, part } => {
            let parts: Vec<Part> = match part {
                None => Part::ALL.to_vec(),
                Some(PartArg::Theory) => vec![Part::Theory],
                Some(PartArg::Snapshots) => vec![Part::Snapshots],
                Some(PartArg::Figures) => vec![Part::Figures],
                Some(PartArg::Stiff) => vec![Part::Stiff],
                Some(PartArg::Timing) => vec![Part::Timing],
            };
            let mut run = Run::new(workspace_root(), quick, check);
            if let Err(e) = run.run(&parts) {
                return failed(e);
            }
            // The report is the whole story: it is written only when every part ran.
            if part.is_none()
                && let Err(e) = xtask::report::write(&mut run)
            {
                return failed(e);
            }
            summarise(&run)
        }
    }
}

fn periodic_peer(args: PeerArgs) -> ExitCode {
    use xtask::periodic_peer::{Options, PEER_DISABLED, PERIODIC_SCENE, PeerMoves, Who};
    let who = match args.who {
        WhoArg::Peer => Who::Peer,
        WhoArg::Ours => Who::Ours,
        WhoArg::Both => Who::Both,
    };
    if who != Who::Ours && !args.report_only && !cfg!(feature = "peer") {
        eprintln!("error: {PEER_DISABLED}");
        return ExitCode::FAILURE;
    }
    let scene_template = match args.scene {
        None => PERIODIC_SCENE.to_string(),
        Some(path) => match std::fs::read_to_string(&path) {
            Ok(text) => text,
            Err(e) => {
                eprintln!("error: {}: {e}", path.display());
                return ExitCode::FAILURE;
            }
        },
    };
    let options = Options {
        seconds: args.seconds,
        ns: args.ns,
        who,
        overlap_pairs: args.overlap_pairs,
        scene_template,
        seed: args.seed,
        peer_moves: PeerMoves {
            translate: args.peer_translate,
            rotate: args.peer_rotate,
        },
        random: args.random,
        report_only: args.report_only,
    };
    with_problems(
        xtask::periodic_peer::run(&workspace_root(), &options),
        "NOT RUN",
    )
}

/// The exit code of a study that lists its problems: success when there are none, else each
/// printed after `label`; an error ends it.
fn with_problems(outcome: Result<Vec<String>, impl std::fmt::Display>, label: &str) -> ExitCode {
    match outcome {
        Ok(problems) if problems.is_empty() => ExitCode::SUCCESS,
        Ok(problems) => {
            for p in problems {
                eprintln!("{label}  {p}");
            }
            ExitCode::FAILURE
        }
        Err(e) => failed(e),
    }
}

/// Reports an error that ended a command and the exit code it gets.
fn failed(e: impl std::fmt::Display) -> ExitCode {
    eprintln!("error: {e}");
    ExitCode::FAILURE
}

/// The fuzz suite is an ordinary test target, so that the normal run and this long run share
/// every strategy; only the case count (`PROPTEST_CASES`) and the profile differ.
fn fuzz(cases: u32, dev: bool) -> ExitCode {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut command = std::process::Command::new(cargo);
    command
        .current_dir(workspace_root())
        .args(["test", "-p", "ellipack", "--test", "fuzz"])
        .env("PROPTEST_CASES", cases.to_string());
    if !dev {
        command.arg("--release");
    }
    eprintln!("fuzz: {cases} cases per parser");
    match command.status() {
        Ok(status) if status.success() => {
            eprintln!("fuzz: no panic in {cases} cases per parser");
            ExitCode::SUCCESS
        }
        Ok(status) => {
            eprintln!("fuzz: failed ({status}); the failing input is printed above");
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("error: cannot run cargo: {e}");
            ExitCode::FAILURE
        }
    }
}

fn summarise(run: &Run) -> ExitCode {
    let o = &run.outputs;
    eprintln!(
        "validate{}: {:.0} s, {} files written, {} unchanged",
        if run.quick { " --quick" } else { "" },
        run.start.elapsed().as_secs_f64(),
        o.written.len(),
        o.unchanged.len()
    );
    for s in &run.skipped {
        eprintln!("SKIPPED {s}");
    }
    for p in &o.stale {
        eprintln!(
            "STALE   {} (run `cargo xtask validate` and commit it)",
            p.display()
        );
    }
    for f in &run.failures {
        eprintln!("{f}");
    }
    if run.failures.is_empty() && o.stale.is_empty() {
        eprintln!("all checks passed");
        ExitCode::SUCCESS
    } else {
        eprintln!(
            "{} check(s) failed, {} stale file(s)",
            run.failures.len(),
            o.stale.len()
        );
        ExitCode::FAILURE
    }
}
