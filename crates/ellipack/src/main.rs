//! `ellipack`: overlap of ellipsoids, from the command line.

use clap::{Parser, Subcommand, ValueEnum};
use ellipack::Error;
use ellipack::export::Format;
use ellipack::packing::ContainerKind;
use ellipack::pairs::{Criterion, Summary, contact_stream};
use ellipack::{OutputFile, refuse_overwriting_input};
use std::fs::File;
use std::io::{BufReader, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use terminal::reader_gone;

mod commands;
mod report;
mod terminal;

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
    /// Writes packing.csv, summary.json, packing.xyz, packing.data, packing.gsd,
    /// container.obj, packing.svg and packing.png in the output folder, which is checked for writing before the run begins. The pictures are left out when drawing them would end
    /// more than 2 s (plus 5 % of the limit) past the time limit, or at a signal; `ellipack
    /// convert OUT --pictures` draws them. Every run ends with
    /// a certified packing: the start is one, and the best so far is kept. Ctrl-C, SIGTERM and
    /// SIGHUP stop the run and write the best certified packing found so far; with --resume, a
    /// run starts from the (certified) packing already in the folder and never writes a worse
    /// one.
    ///
    /// A scene whose [container] gives a size (radius, semi_axes, half_sides or
    /// packing_fraction) fills that container instead: the run ends at the first certified
    /// packing. When none is found in the time limit, the least overlapping configuration is
    /// written to OUT/unfinished/ (packing.csv, summary.json marked not_reached), never as
    /// OUT's packing.
    ///
    /// A random packing: packing_fraction = "jammed" in [container] (compressed from a random
    /// start until jammed), or start = "random" in [solver] with a container size (filled at
    /// exactly that fraction from a random start). Every folder also gets structure.json,
    /// rdf.csv and, with pictures, rdf.svg and orientations.svg (see `ellipack analyse`).
    ///
    /// Exit status: 0 a certified packing was written (the run finished, reached its time
    /// limit or was stopped by a signal); 1 an error, nothing written; 2 bad arguments; 4 a
    /// fixed container was not filled without overlap (see OUT/unfinished/).
    Pack(commands::PackArgs),
    /// Keep the best certified packing of several runs of one scene (the shards of a
    /// multi-start, or repeated runs): every input is verified again, packings of different
    /// scenes are refused, and a certified packing already in the output folder takes part, so
    /// it is never replaced by a worse one.
    ///
    /// Exit status: 0 the best certified packing is in the output folder; 1 an error (an
    /// unreadable input, different scenes, no certified input), nothing written.
    Merge {
        /// Packing folders (each with packing.csv and summary.json).
        #[arg(required = true)]
        folders: Vec<PathBuf>,
        /// The folder to hold the best packing (created if needed).
        #[arg(long)]
        out: PathBuf,
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
    Verify(commands::VerifyArgs),
    /// Write the files for other programs for a packing folder that `ellipack pack` wrote
    /// (read from its packing.csv and summary.json): packing.data (LAMMPS, atom_style
    /// ellipsoid), packing.gsd (HOOMD schema), packing.xyz (extended XYZ for ASE and OVITO) and
    /// container.obj (the container as a surface mesh). Each file is replaced atomically.
    ///
    /// Exit status: 0 the files were written; 1 the folder or its packing could not be read,
    /// or a file could not be written.
    Convert {
        /// The folder with packing.csv and summary.json.
        folder: PathBuf,
        /// The files to write, separated by commas: lammps, gsd, xyz, obj (default: all).
        #[arg(
            long,
            value_delimiter = ',',
            value_parser = parse_format,
            default_value = "lammps,gsd,xyz,obj"
        )]
        formats: Vec<Format>,
        /// Write the files of an unfinished run's least overlapping configuration
        /// (`OUT/unfinished`), which is refused otherwise: it is not a packing.
        #[arg(long)]
        unfinished: bool,
        /// Also draw packing.svg and packing.png (which `pack` leaves out when drawing them
        /// would run past its time limit).
        #[arg(long)]
        pictures: bool,
    },
    /// Measure the structure of a packing folder (packing.csv and summary.json): density,
    /// nematic order S and director of each body axis, Steinhardt Q4 and Q6 (3D) or the
    /// hexatic psi6 (2D), contacts from the PW85 contact function (mu < 1 + gap), the contact
    /// number Z and its distribution, rattlers, and g(r). Writes structure.json and rdf.csv
    /// into the folder (what `pack` writes with every packing) and prints a summary.
    ///
    /// Exit status: 0 the files were written; 1 the folder could not be read or the settings
    /// were refused.
    Analyse(commands::AnalyseArgs),
    /// List the paper's instances (Tables 6.1–6.4) with the paper's density.
    Instances,
    /// Evaluate the Perram–Wertheim contact function μ² of many pairs of ellipsoids or
    /// ellipses (μ² < 1: they overlap).
    ///
    /// Input columns, 3D: r12_x, r12_y, r12_z (c2 − c1), q1_0..q1_5 and q2_0..q2_5 (the upper
    /// triangle of each Q, row-major: Q11, Q12, Q13, Q22, Q23, Q33, for the ellipsoid
    /// (x − c)ᵀ Q⁻¹ (x − c) ≤ 1); 2D: r12_x, r12_y, q1_0..q1_2 and q2_0..q2_2 (Q11, Q12, Q22),
    /// detected from the header; optional case_id; other columns are ignored, a column named
    /// twice is an error. Output columns: case_id, mu2, lambda, overlap, error. A row that
    /// fails has its message in `error`; the other rows still run. Rows are streamed: a file
    /// of any length runs in constant memory.
    ///
    /// Exit status: 0 every row evaluated; 1 the command failed (unreadable or malformed file,
    /// output not writable: an --output file is left as it was); 3 some rows failed (see
    /// their `error` column), the others were written. A reader that closes the pipe early (`| head`) is
    /// not a failure: 0.
    Contact {
        /// The pairs (CSV). Without it, the bundled example pairs are evaluated.
        #[arg(long)]
        input: Option<PathBuf>,
        /// Where to write the results (CSV; a file is replaced atomically, keeping its mode and
        /// any symbolic link to it; a FIFO or a device is written into). Not the input file.
        /// Default: standard output.
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
    ///
    /// Exit status: 0 every row evaluated; 1 the command failed (an --output file is left as
    /// it was); 3 some rows failed (see their `error` column), the others were written.
    Measure {
        /// The pairs (CSV).
        #[arg(long)]
        input: PathBuf,
        /// Where to write the results (CSV; a file is replaced atomically, keeping its mode and
        /// any symbolic link to it; a FIFO or a device is written into). Not the input file.
        /// Default: standard output.
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

fn parse_shard(text: &str) -> Result<ellipack::pack::Shard, String> {
    let parse = |part: &str| part.trim().parse::<usize>().ok();
    let (k, n) = text
        .split_once('/')
        .and_then(|(k, n)| Some((parse(k)?, parse(n)?)))
        .ok_or_else(|| format!("`{text}` is not a shard: write K/N, e.g. 0/4"))?;
    ellipack::pack::Shard::new(k, n).map_err(|e| e.to_string())
}

/// Numbers separated by commas, as one value (a name other than `Vec` keeps clap from reading
/// the option as a list of values).
type Numbers = Vec<f64>;

fn numbers(text: &str) -> Result<Numbers, String> {
    text.split(',')
        .map(|part| {
            part.trim()
                .parse::<f64>()
                .map_err(|e| format!("`{part}` in `{text}` is not a number: {e}"))
        })
        .collect()
}

fn parse_format(name: &str) -> Result<Format, String> {
    Format::from_name(name).map_err(|e| e.to_string())
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
            crate::note!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<ExitCode, Box<dyn std::error::Error>> {
    Ok(match cli.command {
        Command::Pack(args) => commands::pack(args)?,
        Command::Merge { folders, out } => commands::merge(&folders, &out)?,
        Command::Verify(args) => commands::verify(args)?,
        Command::Convert {
            folder,
            formats,
            unfinished,
            pictures,
        } => commands::convert(&folder, &formats, unfinished, pictures)?,
        Command::Analyse(args) => commands::analyse(&args)?,
        Command::Instances => {
            crate::say!("{}", ellipack::instances::listing().trim_end());
            ExitCode::SUCCESS
        }
        Command::Contact {
            input,
            output,
            criterion,
        } => contact(input, output, criterion)?,
        Command::Measure { input, output } => measure(input, output)?,
    })
}

/// Exit status of `contact` and `measure` when some rows failed and the others were written.
const ROWS_FAILED: u8 = 3;

fn open_input(path: &Path) -> Result<BufReader<File>, Error> {
    File::open(path)
        .map(BufReader::new)
        .map_err(|source| ellipack::Error::Io {
            path: path.to_path_buf(),
            source,
        })
}

/// Runs `stream` into `output` (atomically) or standard output, says what happened, and
/// turns it into the exit status: 0, or [`ROWS_FAILED`] when some rows failed.
fn deliver(
    output: Option<&Path>,
    stream: impl FnOnce(&mut dyn Write, &str) -> Result<Summary, Error>,
) -> Result<ExitCode, Error> {
    let result = match output {
        Some(path) => OutputFile::create(path).and_then(|mut file| {
            let summary = stream(&mut file, &path.display().to_string())?;
            file.commit()?;
            Ok(summary)
        }),
        None => stream(
            &mut BufWriter::new(std::io::stdout().lock()),
            "<standard output>",
        ),
    };
    let summary = match result {
        Ok(summary) => summary,
        // The reader has seen enough (`ellipack contact | head`): not a failure.
        Err(Error::Write { source, .. } | ellipack::Error::Io { source, .. })
            if reader_gone(&source) =>
        {
            return Ok(ExitCode::SUCCESS);
        }
        Err(e) => return Err(e),
    };
    if summary.failed > 0 {
        crate::note!(
            "{} of {} rows failed: see their `error` column",
            summary.failed,
            summary.rows
        );
    }
    if let Some(path) = output {
        crate::note!("wrote {} rows to {}", summary.rows, path.display());
    }
    Ok(if summary.failed > 0 {
        ExitCode::from(ROWS_FAILED)
    } else {
        ExitCode::SUCCESS
    })
}

fn measure(input: PathBuf, output: Option<PathBuf>) -> Result<ExitCode, Error> {
    if let Some(output) = &output {
        refuse_overwriting_input(&input, output)?;
    }
    let reader = open_input(&input)?;
    let name = input.display().to_string();
    deliver(output.as_deref(), |out, destination| {
        ellipack::measure::measure_stream(reader, &name, out, destination)
    })
}

fn contact(
    input: Option<PathBuf>,
    output: Option<PathBuf>,
    criterion: CriterionArg,
) -> Result<ExitCode, Error> {
    if let (Some(input), Some(output)) = (&input, &output) {
        refuse_overwriting_input(input, output)?;
    }
    let criterion = match criterion {
        CriterionArg::Contact => Criterion::Contact,
        CriterionArg::Overlap => Criterion::Overlap,
    };
    match &input {
        Some(path) => {
            let reader = open_input(path)?;
            let name = path.display().to_string();
            deliver(output.as_deref(), |out, destination| {
                contact_stream(reader, &name, criterion, out, destination)
            })
        }
        None => {
            crate::note!("no --input given: evaluating the bundled example pairs");
            deliver(output.as_deref(), |out, destination| {
                contact_stream(
                    ellipack::EXAMPLE_PAIRS.as_bytes(),
                    "<built-in example>",
                    criterion,
                    out,
                    destination,
                )
            })
        }
    }
}
