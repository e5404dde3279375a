//! `ellipack`: overlap of ellipsoids, from the command line.

use clap::{Parser, Subcommand, ValueEnum};
use ellipack::Error;
use ellipack::packing::ContainerKind;
use ellipack::pairs::{Criterion, evaluate, read_pairs};
use std::path::PathBuf;
use std::process::ExitCode;

mod commands;

/// Decide whether ellipsoids overlap, and measure by how much.
#[derive(Parser)]
#[command(name = "ellipack", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Pack ellipses or ellipsoids into the smallest container: multi-start local
    /// minimisations of the implicit-variable model, each certified by PW85 verdicts and exact
    /// containment. Without a scene file or --instance, packs a built-in scene (30 ellipses
    /// (2, 1) in a minimum-area ellipse, 45 s).
    ///
    /// Writes packing.csv, summary.json, packing.xyz, packing.svg and packing.png in the
    /// output folder, which is checked for writing before the run begins. Every run ends with
    /// a certified packing: the start is one, and the best so far is kept. Ctrl-C, SIGTERM and
    /// SIGHUP stop the run and write the best certified packing found so far; with --resume, a
    /// run starts from the (certified) packing already in the folder and never writes a worse
    /// one.
    ///
    /// Exit status: 0 a certified packing was written (the run finished, reached its time
    /// limit or was stopped by a signal); 1 an error, nothing written; 2 bad arguments.
    Pack {
        /// The scene (TOML): dimension, container, shape groups, solver settings, seed.
        scene: Option<PathBuf>,
        /// One of the paper's instances instead of a scene (see `ellipack instances`).
        #[arg(long, conflicts_with = "scene")]
        instance: Option<String>,
        /// Output folder (created if needed). Default: the scene's, else `out`.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Wall-clock limit in seconds (overrides the scene's; positive, at most 1.8e19).
        #[arg(long)]
        time_limit: Option<f64>,
        /// Seed of the multi-start perturbations (overrides the scene's).
        #[arg(long)]
        seed: Option<u64>,
        /// Parallel starts (overrides the scene's; 0: every core).
        #[arg(long)]
        threads: Option<usize>,
        /// Start from the packing already in the output folder.
        #[arg(long)]
        resume: bool,
    },
    /// Re-check a packing independently (PW85 verdicts on every close pair, exact
    /// containment) and print its certificate. Exits with failure if any pair overlaps or any
    /// item sticks out.
    ///
    /// Overlapping pairs are listed by the `id` column of packing.csv with their μ², items
    /// outside with the factor t by which the container would have to grow about its centre to
    /// hold them (first 20 of each; all are counted). A hand-made packing needs only
    /// packing.csv and the container: a summary.json as short as
    /// `{"container": {"kind": "ball", "radius": 5}}`, or --container and --size.
    Verify {
        /// A folder with packing.csv and summary.json, or the path of packing.csv.
        packing: PathBuf,
        /// summary.json, when the first argument is packing.csv (default: the one beside it).
        #[arg(conflicts_with = "container")]
        summary: Option<PathBuf>,
        /// The container instead of a summary: circle, ellipse, rectangle (2D), ball,
        /// ellipsoid, cuboid (3D).
        #[arg(long, requires = "size", value_parser = parse_container_kind)]
        container: Option<ContainerKind>,
        /// The container's size: the radius, or the semi-axes or half sides separated by commas
        /// (`--size 1,2,3`).
        #[arg(
            long,
            requires = "container",
            value_delimiter = ',',
            allow_hyphen_values = true
        )]
        size: Option<Vec<f64>>,
        /// The container's centre, coordinates separated by commas (default: the origin).
        #[arg(
            long,
            requires = "container",
            value_delimiter = ',',
            allow_hyphen_values = true
        )]
        center: Option<Vec<f64>>,
    },
    /// List the paper's instances (Tables 6.1–6.4) with the paper's density.
    Instances,
    /// Evaluate the Perram–Wertheim contact function μ² of many pairs of ellipsoids (μ² < 1:
    /// they overlap).
    ///
    /// Input columns: r12_x, r12_y, r12_z (c2 − c1), q1_0..q1_5 and q2_0..q2_5 (the upper
    /// triangle of each Q, row-major: Q11, Q12, Q13, Q22, Q23, Q33, for the ellipsoid
    /// (x − c)ᵀ Q⁻¹ (x − c) ≤ 1); optional case_id; other columns are ignored. Output columns:
    /// case_id, mu2, lambda, overlap, error. A row that fails has its message in `error`; the
    /// other rows still run.
    Contact {
        /// The pairs (CSV). Without it, the bundled example pairs are evaluated.
        #[arg(long)]
        input: Option<PathBuf>,
        /// Where to write the results (CSV, written atomically). Default: standard output.
        #[arg(long)]
        output: Option<PathBuf>,
        /// `contact` computes μ², λ and the verdict; `overlap` only the verdict, which is
        /// cheaper.
        #[arg(long, value_enum, default_value_t = CriterionArg::Contact)]
        criterion: CriterionArg,
    },
    /// Evaluate the implicit-variable overlap measure of Birgin, Lobato and Martínez (the pair
    /// term f, the multiplier U, d² and the projection X) for many pairs.
    ///
    /// Input in the layout of the reference files: 3D `cix, ciy, ciz, ai, bi, ci_ax, qwi, qxi,
    /// qyi, qzi` and the same for j (quaternion w, x, y, z; semi-axis k along column k of the
    /// rotation); 2D `cix, ciy, ai, bi, theta_i, cjx, cjy, aj, bj, theta_j` (detected from the
    /// header). Output columns: case_id, U, d2, eps, f, overlap, X_1, X_2[, X_3], error; X is
    /// blank where the projection is not unique.
    Measure {
        /// The pairs (CSV).
        #[arg(long)]
        input: PathBuf,
        /// Where to write the results (CSV, written atomically). Default: standard output.
        #[arg(long)]
        output: Option<PathBuf>,
    },
}

fn parse_container_kind(name: &str) -> Result<ContainerKind, String> {
    ContainerKind::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = ContainerKind::ALL.iter().map(|k| k.name()).collect();
        format!(
            "`{name}` is not a container; the kinds are {}",
            names.join(", ")
        )
    })
}

#[derive(Clone, Copy, ValueEnum)]
enum CriterionArg {
    Contact,
    Overlap,
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode, Box<dyn std::error::Error>> {
    Ok(match cli.command {
        Command::Pack {
            scene,
            instance,
            out,
            time_limit,
            seed,
            threads,
            resume,
        } => commands::pack(commands::PackArgs {
            scene,
            instance,
            out,
            time_limit,
            seed,
            threads,
            resume,
        })?,
        Command::Verify {
            packing,
            summary,
            container,
            size,
            center,
        } => commands::verify(commands::VerifyArgs {
            packing,
            summary,
            container,
            size,
            center,
        })?,
        Command::Instances => {
            print!("{}", ellipack::instances::listing());
            ExitCode::SUCCESS
        }
        other => {
            run_table(other)?;
            ExitCode::SUCCESS
        }
    })
}

fn run_table(command: Command) -> Result<(), Error> {
    match command {
        Command::Contact {
            input,
            output,
            criterion,
        } => contact(input, output, criterion),
        Command::Measure { input, output } => measure(input, output),
        Command::Pack { .. } | Command::Verify { .. } | Command::Instances => Ok(()),
    }
}

fn read_input(path: &PathBuf) -> Result<String, Error> {
    std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.clone(),
        source,
    })
}

/// Writes a result table to `output` (atomically) or standard output, and says what happened.
fn deliver(table: &str, rows: usize, failed: usize, output: Option<&PathBuf>) -> Result<(), Error> {
    match output {
        Some(path) => ellipack::output::write_atomically(path, table.as_bytes())?,
        None => print!("{table}"),
    }
    if failed > 0 {
        eprintln!("{failed} of {rows} rows failed: see their `error` column");
    }
    if let Some(path) = output {
        eprintln!("wrote {rows} rows to {}", path.display());
    }
    Ok(())
}

fn measure(input: PathBuf, output: Option<PathBuf>) -> Result<(), Error> {
    let text = read_input(&input)?;
    let (table, failed) = ellipack::measure::measure(&text, &input.display().to_string())?;
    let rows = table.lines().count() - 1;
    deliver(&table, rows, failed, output.as_ref())
}

fn contact(
    input: Option<PathBuf>,
    output: Option<PathBuf>,
    criterion: CriterionArg,
) -> Result<(), Error> {
    let (text, name) = match &input {
        Some(path) => (read_input(path)?, path.display().to_string()),
        None => {
            eprintln!("no --input given: evaluating the bundled example pairs");
            (
                ellipack::EXAMPLE_PAIRS.to_string(),
                "<built-in example>".to_string(),
            )
        }
    };
    let rows = read_pairs(&text, &name)?;
    let criterion = match criterion {
        CriterionArg::Contact => Criterion::Contact,
        CriterionArg::Overlap => Criterion::Overlap,
    };
    let (table, failed) = evaluate(&rows, criterion);
    match &output {
        Some(path) => ellipack::output::write_atomically(path, table.as_bytes())?,
        None => print!("{table}"),
    }
    if failed > 0 {
        eprintln!(
            "{failed} of {} rows failed: see their `error` column",
            rows.len()
        );
    }
    if let Some(path) = &output {
        eprintln!("wrote {} rows to {}", rows.len(), path.display());
    }
    Ok(())
}
