//! `cargo xtask paper-tables`: the paper's instances (Tables 6.1–6.4, Section 6.1.2) run by the
//! same pipeline as `ellipack pack` (multi-start, certificate, repair), each for a wall-clock
//! budget, and reported beside the paper's densities.
//!
//! Writes `validation/paper_tables.csv`, `docs/paper-tables.md`, a picture per instance
//! (`docs/figures/paper_<name>.{svg,png}`) and the packings themselves
//! (`validation/paper-packings/<name>/packing.csv` + `summary.json`, which `ellipack verify`
//! re-checks and `ellipack pack --resume` continues from).

use ellipack::instances::{Instance, by_name, names};
use ellipack::output::write_atomically;
use ellipack::pack::{RunOptions, run};
use ellipack::packing::write_files;
use ellipack::render::{RenderOptions, png_bytes, svg_string};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Duration;

/// The four instances the multi-start issue sets targets for.
pub const TARGETS: [&str; 4] = ["ellipse-100", "rectangle-100", "ball-100", "cuboid-100"];

/// What to run.
#[derive(Clone, Debug)]
pub struct Options {
    /// Wall-clock minutes per instance.
    pub minutes: f64,
    /// Instance names (see `ellipack instances`).
    pub instances: Vec<String>,
    /// Parallel starts (0: every core).
    pub threads: usize,
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
    let mut problems = Vec::new();
    for instance in instances {
        eprintln!(
            "{}: {} for {} min on {threads} threads",
            instance.name,
            instance.description(),
            options.minutes
        );
        let scene = instance.scene();
        let run_options = RunOptions {
            time_limit: Some(Duration::from_secs_f64(options.minutes * 60.0)),
            threads: Some(threads),
            ..RunOptions::default()
        };
        let mut best = 0.0;
        let outcome = run(
            &scene,
            &run_options,
            &mut |p| {
                if p.best_density > best {
                    best = p.best_density;
                    eprintln!(
                        "  {:8.1} s: best certified density {:.5} ({} local minimisations)",
                        p.elapsed.as_secs_f64(),
                        p.best_density,
                        p.local_minimisations
                    );
                }
            },
            &|_| {},
            &|| false,
        )
        .map_err(|e| format!("{}: {e}", instance.name))?;
        let c = outcome.summary.certificate;
        if !c.is_certified() {
            problems.push(format!(
                "{}: {} overlapping pairs, {} containment violations",
                instance.name, c.overlapping_pairs, c.containment_violations
            ));
        }
        let dir = root.join("validation/paper-packings").join(instance.name);
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        write_files(&dir, &outcome.packing, &outcome.summary, false).map_err(|e| e.to_string())?;
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
        rows.push(Row {
            instance,
            density: outcome.summary.density,
            seconds_to_best: outcome.seconds_to_best,
            local_minimisations: outcome.summary.local_minimisations,
            failed_starts: outcome.failed_starts,
            certified: c.is_certified(),
            min_mu2: c.min_mu2,
        });
    }
    let machine = machine(threads);
    write_atomically(
        &root.join("validation/paper_tables.csv"),
        csv(&rows, options.minutes, &machine).as_bytes(),
    )
    .map_err(|e| e.to_string())?;
    write_atomically(
        &root.join("docs/paper-tables.md"),
        markdown(&rows, options.minutes, &machine).as_bytes(),
    )
    .map_err(|e| e.to_string())?;
    Ok(problems)
}

/// The processor model and thread count, as far as the system tells.
fn machine(threads: usize) -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown processor".into());
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    format!("{model}, {cores} cores, {threads} threads used")
}

fn csv(rows: &[Row], minutes: f64, machine: &str) -> String {
    let mut out = String::from(
        "instance,paper_density,density,ratio,seconds_to_best,local_minimisations,failed_starts,\
         wall_budget_seconds,certified,min_mu2,machine\n",
    );
    for r in rows {
        let paper = r.instance.reference_density();
        let _ = writeln!(
            out,
            "{},{},{:.6},{},{:.1},{},{},{:.0},{},{},\"{machine}\"",
            r.instance.name,
            paper.map_or(String::new(), |d| format!("{d:.5}")),
            r.density,
            paper.map_or(String::new(), |d| format!("{:.5}", r.density / d)),
            r.seconds_to_best,
            r.local_minimisations,
            r.failed_starts,
            minutes * 60.0,
            r.certified,
            r.min_mu2.map_or(String::new(), |m| format!("{m:.9}")),
        );
    }
    out
}

fn markdown(rows: &[Row], minutes: f64, machine: &str) -> String {
    let mut out = format!(
        "# The paper's instances\n\nGenerated by `cargo xtask paper-tables --minutes {minutes}` \
         (do not edit). Each instance was packed by the pipeline of `ellipack pack` — the \
         multi-start of `implicit-packing` from the paper's lattice start, every local \
         minimisation certified with PW85 and exact containment and repaired — for \
         {minutes} minutes of wall time on {machine}. The paper's figures are the best of a \
         48-hour multi-start on an Intel i7-3770 (Birgin, Lobato, Martínez, Section 6; \
         `≈` where the paper gives a radius only). The packings are in \
         `validation/paper-packings/<instance>/` (`ellipack verify` re-checks them, \
         `ellipack pack --instance <instance> --resume --out <that folder>` continues them).\n\n\
         | instance | paper density (48 h) | ours | ours / paper | time to best (s) | local minimisations | certified |\n\
         |---|---:|---:|---:|---:|---:|---|\n"
    );
    for r in rows {
        let paper = r.instance.reference_density();
        let _ = writeln!(
            out,
            "| {} | {} | {:.5} | {} | {:.1} | {} | {} |",
            r.instance.name,
            paper.map_or("—".into(), |d| format!("{d:.5}")),
            r.density,
            paper.map_or("—".into(), |d| format!("{:.4}", r.density / d)),
            r.seconds_to_best,
            r.local_minimisations,
            if r.certified { "yes" } else { "**no**" },
        );
    }
    out.push('\n');
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
