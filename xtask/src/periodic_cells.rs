//! `cargo xtask periodic-cells`: the periodic cell measured through the `ellipack pack`
//! pipeline.
//!
//! * Variable cells with 1, 2 and 4 items of three shapes (spheres, ellipses (2, 1), ellipsoids
//!   (1, 0.75, 0.5)): the density reached and when, against the densest lattice packing where
//!   it is known (π/√12 for ellipses, π/√18 for spheres).
//! * 10 000 ellipsoids (1, 0.75, 0.5) in a fixed periodic cube at packing fraction 0.60: the
//!   wall time to a certified packing; then the fraction raised by 0.02 at a time, each run
//!   given what is left of a 10-minute budget, until one is not reached.
//!
//! Writes `validation/periodic_cells.csv` and the table between the markers of
//! `docs/periodic.md`.

use ellipack::pack::{RunOptions, run};
use ellipack::scene::Scene;
use ellipack::write_atomically;
use ellipsoid_packer::multistart::Callbacks;
use std::fmt::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};

/// What the study runs.
#[derive(Clone, Debug, clap::Args)]
pub struct Options {
    /// Seconds per variable-cell run.
    #[arg(long, default_value_t = 20.0)]
    pub seconds: f64,
    /// Items in the fixed cube.
    #[arg(long, default_value_t = 10_000)]
    pub items: usize,
    /// Minutes for the sweep of packing fractions of the fixed cube.
    #[arg(long, default_value_t = 10.0)]
    pub sweep_minutes: f64,
    /// Threads of the fixed-cube runs.
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
}

/// One measured run.
struct Row {
    study: &'static str,
    shape: String,
    items: usize,
    /// The packing fraction asked for (fixed cells).
    target: Option<f64>,
    density: Option<f64>,
    seconds: f64,
    local_minimisations: u64,
    known: Option<f64>,
}

/// The outcome of one run: the density of its certified packing (None: not reached), the
/// wall time to it (the time to the best packing of a variable cell; the whole run, start,
/// solves and certificates, for a fixed one, which ends at its first packing), and its local
/// minimisations.
fn pack(scene_text: &str, seconds: f64, threads: usize) -> Result<(Option<f64>, f64, u64), String> {
    let mut scene =
        Scene::from_toml_str(scene_text, "periodic-cells").map_err(|e| e.to_string())?;
    scene.solver.time_limit = Duration::from_secs_f64(seconds);
    scene.solver.threads = threads;
    let options = RunOptions::default();
    let start = Instant::now();
    match run(&scene, &options, &mut Callbacks::on_finished(|_| {})) {
        Ok(outcome) => Ok((
            Some(outcome.summary.density),
            if scene.fixed_container().is_some() {
                start.elapsed().as_secs_f64()
            } else {
                outcome.seconds_to_best
            },
            outcome.summary.local_minimisations,
        )),
        Err(ellipack::Error::NotReached(u)) => Ok((
            None,
            start.elapsed().as_secs_f64(),
            u.summary.local_minimisations,
        )),
        Err(e) => Err(e.to_string()),
    }
}

fn scene(dimension: usize, count: usize, axes: &[f64], container: &str, threads: usize) -> String {
    let axes: Vec<String> = axes.iter().map(|a| format!("{a:?}")).collect();
    format!(
        "dimension = {dimension}\nseed = 1\n[container]\nkind = \"periodic\"\n{container}\
         [[shapes]]\ncount = {count}\nsemi_axes = [{}]\n[solver]\nthreads = {threads}\n\
         [output]\npictures = false\n",
        axes.join(", ")
    )
}

/// Runs the study and writes its files under `root`.
///
/// # Errors
/// A message naming the run or the file that failed.
pub fn run_all(root: &Path, options: &Options) -> Result<(), String> {
    let hexagonal = std::f64::consts::PI / 12f64.sqrt();
    let fcc = std::f64::consts::PI / 18f64.sqrt();
    let shapes: [(&str, Vec<f64>, Option<f64>); 3] = [
        ("spheres", vec![1.0, 1.0, 1.0], Some(fcc)),
        ("ellipses (2, 1)", vec![2.0, 1.0], Some(hexagonal)),
        ("ellipsoids (1, 0.75, 0.5)", vec![1.0, 0.75, 0.5], None),
    ];
    let mut rows = Vec::new();
    for (name, axes, known) in &shapes {
        for items in [1, 2, 4] {
            let text = scene(axes.len(), items, axes, "cell = \"variable\"\n", 1);
            let (density, seconds, local) = pack(&text, options.seconds, 1)?;
            eprintln!("variable cell, {items} {name}: {density:?} at {seconds:.2} s");
            rows.push(Row {
                study: "variable cell",
                shape: name.to_string(),
                items,
                target: None,
                density,
                seconds,
                local_minimisations: local,
                known: *known,
            });
        }
    }
    let budget = options.sweep_minutes * 60.0;
    let sweep_start = Instant::now();
    let mut fraction: f64 = 0.60;
    loop {
        let left = budget - sweep_start.elapsed().as_secs_f64();
        if left <= 1.0 {
            break;
        }
        let text = scene(
            3,
            options.items,
            &[1.0, 0.75, 0.5],
            &format!("cell = \"fixed\"\npacking_fraction = {fraction:?}\n"),
            options.threads,
        );
        let (density, seconds, local) = pack(&text, left, options.threads)?;
        eprintln!("fixed cube at {fraction:.2}: {density:?} after {seconds:.1} s");
        rows.push(Row {
            study: "fixed cube",
            shape: "ellipsoids (1, 0.75, 0.5)".into(),
            items: options.items,
            target: Some(fraction),
            density,
            seconds,
            local_minimisations: local,
            known: None,
        });
        if density.is_none() {
            break;
        }
        fraction = ((fraction + 0.02) * 100.0).round() / 100.0;
    }
    write_atomically(
        &root.join("validation/periodic_cells.csv"),
        csv(&rows).as_bytes(),
    )
    .map_err(|e| e.to_string())?;
    let doc = root.join("docs/periodic.md");
    let text = std::fs::read_to_string(&doc).map_err(|e| format!("{}: {e}", doc.display()))?;
    let updated = between_markers(&text, &markdown(&rows, options))
        .ok_or_else(|| format!("{}: the periodic-cells markers are missing", doc.display()))?;
    write_atomically(&doc, updated.as_bytes()).map_err(|e| e.to_string())?;
    Ok(())
}

const BEGIN: &str = "<!-- periodic-cells:begin -->";
const END: &str = "<!-- periodic-cells:end -->";

/// `text` with what lies between the study's markers replaced by `table`.
fn between_markers(text: &str, table: &str) -> Option<String> {
    crate::output::between_markers(text, (BEGIN, END), table)
}

fn csv(rows: &[Row]) -> String {
    let mut out = String::from(
        "study,shape,items,target_fraction,density,seconds,local_minimisations,known_density\n",
    );
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{:.2},{},{}",
            r.study,
            r.shape.replace(',', ";"),
            r.items,
            r.target.map_or(String::new(), |t| format!("{t:.2}")),
            r.density.map_or(String::new(), |d| format!("{d:.6}")),
            r.seconds,
            r.local_minimisations,
            r.known.map_or(String::new(), |d| format!("{d:.6}")),
        );
    }
    out
}

fn markdown(rows: &[Row], options: &Options) -> String {
    let mut out = format!(
        "Generated by `cargo xtask periodic-cells` (commit {}, {}). Variable cells: {} s per \
         run, one thread; fixed cube: {} ellipsoids, {} threads, the fractions tried in turn \
         within {} minutes.\n\n\
         | study | items | target | density | known | seconds | local minimisations |\n\
         |---|---|---:|---:|---:|---:|---:|\n",
        crate::provenance::commit(),
        crate::provenance::machine_with_threads(options.threads),
        options.seconds,
        options.items,
        options.threads,
        options.sweep_minutes
    );
    for r in rows {
        let _ = writeln!(
            out,
            "| {} | {} {} | {} | {} | {} | {:.2} | {} |",
            r.study,
            r.items,
            r.shape,
            r.target.map_or("—".into(), |t| format!("{t:.2}")),
            r.density
                .map_or("not reached".into(), |d| format!("{d:.5}")),
            r.known.map_or("—".into(), |d| format!("{d:.5}")),
            r.seconds,
            r.local_minimisations,
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_replaces_only_what_lies_between_the_markers() {
        let text = format!("# Title\n\n{BEGIN}\nold table\n{END}\nafter\n");
        let new = between_markers(&text, "new table\n").unwrap();
        assert_eq!(
            new,
            format!("# Title\n\n{BEGIN}\nnew table\n{END}\nafter\n")
        );
        assert!(between_markers("no markers", "x").is_none());
    }
}
