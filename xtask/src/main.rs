//! Repository chores for ellipack, run as `cargo xtask <command>` (alias in
//! `.cargo/config.toml`).

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// ellipack's repository tasks.
#[derive(Parser)]
#[command(name = "cargo xtask")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Regenerate and check the evidence: theory checks, snapshots, CSV data and figures.
    ///
    /// Not implemented yet (a stub): the validation harness is the subject of the issue
    /// "`cargo xtask validate`". Until then it runs nothing and exits with failure, so that
    /// nobody mistakes it for a passing validation.
    Validate {
        /// The short run meant for CI.
        #[arg(long)]
        quick: bool,
    },
}

fn main() -> ExitCode {
    match Cli::parse().command {
        Command::Validate { quick } => {
            eprintln!(
                "cargo xtask validate{}: not implemented yet (see the issue \
                 \"cargo xtask validate\"); the test suite is `cargo test --workspace`",
                if quick { " --quick" } else { "" }
            );
            ExitCode::FAILURE
        }
    }
}
