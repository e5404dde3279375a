//! `ellipack`: overlap of ellipsoids, from the command line.

use clap::{Parser, Subcommand, ValueEnum};
use ellipack::Error;
use ellipack::pairs::{Criterion, evaluate, read_pairs};
use std::path::PathBuf;
use std::process::ExitCode;

/// Decide whether ellipsoids overlap, and measure by how much.
#[derive(Parser)]
#[command(name = "ellipack", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
}

#[derive(Clone, Copy, ValueEnum)]
enum CriterionArg {
    Contact,
    Overlap,
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<(), Error> {
    match cli.command {
        Command::Contact {
            input,
            output,
            criterion,
        } => contact(input, output, criterion),
    }
}

fn contact(
    input: Option<PathBuf>,
    output: Option<PathBuf>,
    criterion: CriterionArg,
) -> Result<(), Error> {
    let (text, name) = match &input {
        Some(path) => (
            std::fs::read_to_string(path).map_err(|source| Error::Io {
                path: path.clone(),
                source,
            })?,
            path.display().to_string(),
        ),
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
