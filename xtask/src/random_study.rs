//! `cargo xtask random`: the random packings of `validation/random/*.toml` through the
//! `ellipack pack` pipeline (`ellipack::pack::run`, the command's own path), each measured:
//! packing fraction, wall time, peak memory, and the structure of the packing written
//! (`ellipack::analysis`: bond order, nematic order, contacts).
//!
//! Rows are kept by scene in `validation/random.csv` (a run replaces the rows of the scenes it
//! ran), with each run's density after every kept compression step in
//! `validation/random_history.csv`; the table between the markers of `docs/random.md` and the
//! figures `docs/figures/random-density-time.{svg,png}` (every row) and
//! `docs/figures/random-time-items.{svg,png}` (the ellipsoids (1, 0.75, 0.5): wall time and
//! peak memory against their number, at φ = 0.6 and jammed) are drawn from the rows. The
//! scenes run in order of their item count, so that the peak memory of the process after each
//! run (it only grows) is that run's.

use crate::error::Error;
use crate::output::Outputs;
use crate::plot::{Corner, Figure, Kind, Panel, Series, render};
use crate::provenance::{commit, machine};
use crate::scale::peak_rss_mib;
use ellipack::pack::{RunOptions, run as pack_run};
use ellipack::scene::Scene;
use ellipsoid_packer::multistart::{Callbacks, MultiStartProgress};
use std::fmt::Write as _;
use std::path::Path;
use structure::BondOrder;

/// What the study runs.
#[derive(Clone, Debug, clap::Args)]
pub struct Options {
    /// Scene names in validation/random (without `.toml`); default: all of them.
    #[arg(long, num_args = 1..)]
    pub scenes: Vec<String>,
    /// Threads of each run (the scene's own otherwise).
    #[arg(long, default_value_t = 2)]
    pub threads: usize,
    /// Rewrite the table of docs/random.md from validation/random.csv without running.
    #[arg(long)]
    pub report_only: bool,
}

/// One measured random packing.
#[derive(Clone, Debug, PartialEq)]
struct Row {
    scene: String,
    items: usize,
    target: String,
    density: f64,
    seconds: f64,
    peak_mib: f64,
    /// Q₆ in 3D, ψ₆ in 2D.
    bond_order: f64,
    largest_nematic: f64,
    contacts: f64,
    rattlers: usize,
    certified: bool,
    machine: String,
    commit: String,
}

const BEGIN: &str = "<!-- BEGIN random table (cargo xtask random) -->";
const END: &str = "<!-- END random table -->";
const HEADER: &str = "scene,items,target,density,seconds,peak_mib,bond_order,largest_nematic,\
                      contacts,rattlers,certified,machine,commit";

fn study(message: String) -> Error {
    Error::Study {
        context: "random".into(),
        message,
    }
}

/// Runs the study (or only rewrites the report) under `root`.
///
/// # Errors
/// A scene that cannot be read or packed, a table that cannot be read or written.
pub fn run(root: &Path, options: &Options) -> Result<(), Error> {
    let table = root.join("validation").join("random.csv");
    let history = root.join("validation").join("random_history.csv");
    let mut rows = read_rows(&table)?;
    let mut points = read_history(&history)?;
    if !options.report_only {
        let mut scenes = Vec::new();
        let folder = root.join("validation").join("random");
        let mut names: Vec<String> = std::fs::read_dir(&folder)
            .map_err(|e| study(format!("{}: {e}", folder.display())))?
            .filter_map(|e| e.ok())
            .filter_map(|e| {
                let name = e.file_name().to_string_lossy().to_string();
                name.strip_suffix(".toml").map(str::to_string)
            })
            .filter(|n| options.scenes.is_empty() || options.scenes.contains(n))
            .collect();
        names.sort();
        for name in names {
            let path = folder.join(format!("{name}.toml"));
            let scene = Scene::from_file(&path).map_err(|e| study(e.to_string()))?;
            scenes.push((name, scene));
        }
        scenes.sort_by_key(|(_, s)| s.item_count());
        for (name, scene) in scenes {
            eprintln!("{name}: {} items", scene.item_count());
            let (row, seen) = measure(&name, &scene, options.threads)?;
            points.retain(|(scene, _, _)| *scene != name);
            points.extend(seen.into_iter().map(|(t, d)| (name.clone(), t, d)));
            std::fs::write(&history, history_csv(&points)).map_err(|e| study(e.to_string()))?;
            eprintln!(
                "  {:.5} in {:.1} s, {:.0} MiB, bond order {:.4}, Z {:.2}",
                row.density, row.seconds, row.peak_mib, row.bond_order, row.contacts
            );
            rows.retain(|r| r.scene != row.scene);
            rows.push(row);
            rows.sort_by_key(|r| (r.items, r.scene.clone()));
            std::fs::write(&table, csv(&rows)).map_err(|e| study(e.to_string()))?;
        }
    }
    let doc = root.join("docs").join("random.md");
    let text =
        std::fs::read_to_string(&doc).map_err(|e| study(format!("{}: {e}", doc.display())))?;
    let spliced = match (text.find(BEGIN), text.find(END)) {
        (Some(b), Some(e)) if e > b => format!(
            "{}{BEGIN}\n{}{END}{}",
            &text[..b],
            markdown(&rows),
            &text[e + END.len()..]
        ),
        _ => {
            return Err(study(format!(
                "{}: no markers {BEGIN} … {END}",
                doc.display()
            )));
        }
    };
    std::fs::write(&doc, spliced).map_err(|e| study(e.to_string()))?;
    let mut outputs = Outputs::new(false);
    let figures = root.join("docs/figures");
    render(
        &figure(&rows, &points),
        &figures,
        "random-density-time",
        &mut outputs,
    )?;
    render(&scaling(&rows), &figures, "random-time-items", &mut outputs)
}

/// The scenes of the scaling figure: ellipsoids (1, 0.75, 0.5), named `ellipsoids-m` (jammed)
/// and `ellipsoids-m-060` (φ = 0.6).
const SCALING_SCENES: &str = "ellipsoids-";

/// Wall time and peak memory against the number of ellipsoids (1, 0.75, 0.5), log–log: one
/// line at φ = 0.6, one jammed.
fn scaling(rows: &[Row]) -> Figure {
    let line = |jammed: bool, value: fn(&Row) -> f64, color: usize| Series {
        name: if jammed { "jammed" } else { "φ = 0.6" }.into(),
        points: rows
            .iter()
            .filter(|r| r.scene.starts_with(SCALING_SCENES) && (r.target == "jammed") == jammed)
            .map(|r| (r.items as f64, value(r)))
            .collect(),
        kind: Kind::LinePoints,
        color,
    };
    let panel = |title: &str, y_label: &str, value: fn(&Row) -> f64| Panel {
        title: title.into(),
        x_label: "ellipsoids (1, 0.75, 0.5) in a periodic cube, logarithmic".into(),
        x_log: true,
        y_label: y_label.into(),
        y_log: true,
        series: vec![line(false, value, 0), line(true, value, 1)],
        legend: Corner::UpperLeft,
        ..Panel::default()
    };
    Figure {
        panels: vec![
            panel(
                "Random packings: wall time of the whole run (start, compression, certificate)",
                "wall time (s), logarithmic",
                |r| r.seconds,
            ),
            panel(
                "Random packings: peak memory of the process",
                "peak memory (MiB), logarithmic",
                |r| r.peak_mib,
            ),
        ],
        panel_height: 480,
    }
}

/// Density against time of every scene's run: one line per scene, log time.
fn figure(rows: &[Row], points: &[(String, f64, f64)]) -> Figure {
    let series = rows
        .iter()
        .enumerate()
        .map(|(k, r)| Series {
            name: format!("{} ({})", r.scene, r.target),
            points: points
                .iter()
                .filter(|(scene, t, _)| *scene == r.scene && *t > 0.0)
                .map(|(_, t, d)| (*t, *d))
                .collect(),
            kind: Kind::LinePoints,
            color: k,
        })
        .collect();
    crate::plot::density_against_time(
        "Random packings: density of each kept compression step",
        series,
    )
}

fn history_csv(points: &[(String, f64, f64)]) -> String {
    let mut out = String::from("scene,seconds,density\n");
    for (scene, t, d) in points {
        let _ = writeln!(out, "{scene},{t:.3},{d:.6}");
    }
    out
}

fn read_history(path: &Path) -> Result<Vec<(String, f64, f64)>, Error> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(Vec::new());
    };
    text.lines()
        .enumerate()
        .skip(1)
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(k, l)| {
            let f: Vec<&str> = l.split(',').collect();
            let bad = || {
                study(format!(
                    "{}: line {}: not scene,seconds,density",
                    path.display(),
                    k + 1
                ))
            };
            match f.as_slice() {
                [scene, t, d] => Ok((
                    scene.to_string(),
                    t.parse().map_err(|_| bad())?,
                    d.parse().map_err(|_| bad())?,
                )),
                _ => Err(bad()),
            }
        })
        .collect()
}

/// One run: its row, and the (seconds, density) of every kept compression step.
fn measure(name: &str, scene: &Scene, threads: usize) -> Result<(Row, Vec<(f64, f64)>), Error> {
    let mut scene = scene.clone();
    scene.solver.threads = threads;
    let mut seen = Vec::new();
    let outcome = pack_run(
        &scene,
        &RunOptions::default(),
        &mut Callbacks::on_finished(|p: &MultiStartProgress| {
            seen.push((p.elapsed.as_secs_f64(), p.last_density));
        }),
    )
    .map_err(|e| study(format!("{name}: {e}")))?;
    let settings = ellipack::analysis::settings(
        structure::DEFAULT_CONTACT_GAP,
        outcome.summary.repair_dilation(),
    );
    let s = ellipack::analysis::analyse(&outcome.packing, &settings)
        .map_err(|e| study(format!("{name}: {e}")))?;
    let bond_order = match s.bond_order {
        BondOrder::Steinhardt { q6, .. } => q6,
        BondOrder::Hexatic { psi6, .. } => psi6,
    };
    let target = match &scene.container_size {
        Some(ellipack::scene::ContainerSize::PackingFraction(f)) => format!("{f}"),
        _ => "jammed".to_string(),
    };
    let row = Row {
        scene: name.to_string(),
        items: scene.item_count(),
        target,
        density: outcome.summary.density,
        seconds: outcome.seconds_to_best,
        peak_mib: peak_rss_mib(),
        bond_order,
        // NaN when every item is round: no axis has an order.
        largest_nematic: s.nematic.iter().map(|n| n.order).fold(f64::NAN, f64::max),
        contacts: s.contacts.mean_contacts,
        rattlers: s.contacts.rattlers,
        certified: outcome.summary.certificate.is_certified(),
        machine: machine(),
        commit: commit(),
    };
    Ok((row, seen))
}

/// Writes one line of `$row`'s fields, in the table's column order, through `$format`: the CSV
/// file and the Markdown table differ only in their format and in how they spell `certified`.
macro_rules! write_row {
    ($out:expr, $format:literal, $row:expr, $certified:expr) => {
        writeln!(
            $out,
            $format,
            $row.scene,
            $row.items,
            $row.target,
            $row.density,
            $row.seconds,
            $row.peak_mib,
            $row.bond_order,
            $row.largest_nematic,
            $row.contacts,
            $row.rattlers,
            $certified,
            $row.machine,
            $row.commit
        )
    };
}

fn csv(rows: &[Row]) -> String {
    crate::output::table_text(&format!("{HEADER}\n"), rows, |out, r| {
        write_row!(
            out,
            "{},{},{},{:.6},{:.2},{:.0},{:.4},{:.4},{:.3},{},{},\"{}\",{}",
            r,
            r.certified
        )
    })
}

fn read_rows(path: &Path) -> Result<Vec<Row>, Error> {
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(Vec::new());
    };
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let mut rows = Vec::new();
    for (k, record) in reader.records().enumerate() {
        let r = record.map_err(|e| study(format!("{}: row {}: {e}", path.display(), k + 1)))?;
        let field = |i: usize| r.get(i).unwrap_or("").to_string();
        let number = |i: usize| -> Result<f64, Error> {
            field(i).parse().map_err(|_| {
                study(format!(
                    "{}: line {}: column {} is not a number",
                    path.display(),
                    k + 2,
                    i + 1
                ))
            })
        };
        rows.push(Row {
            scene: field(0),
            items: number(1)? as usize,
            target: field(2),
            density: number(3)?,
            seconds: number(4)?,
            peak_mib: number(5)?,
            bond_order: number(6)?,
            largest_nematic: number(7)?,
            contacts: number(8)?,
            rattlers: number(9)? as usize,
            certified: field(10) == "true",
            machine: field(11),
            commit: field(12),
        });
    }
    Ok(rows)
}

fn markdown(rows: &[Row]) -> String {
    crate::output::table_text(
        "| scene (`validation/random/`) | items | target | φ | wall time | peak memory | Q₆ (2D: ψ₆) \
         | largest S | Z | rattlers | certified | machine, commit |\n\
         |---|---:|---|---:|---:|---:|---:|---:|---:|---:|---|---|\n",
        rows,
        |out, r| {
            write_row!(
                out,
                "| `{}` | {} | {} | {:.5} | {:.1} s | {:.0} MiB | {:.4} | {:.3} | {:.2} | {} | {} | {}, {} |",
                r,
                if r.certified { "yes" } else { "**no**" }
            )
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_reads_back_what_it_wrote() {
        let row = Row {
            scene: "spheres-1000".into(),
            items: 1000,
            target: "jammed".into(),
            density: 0.634081,
            seconds: 21.04,
            peak_mib: 31.0,
            bond_order: 0.0341,
            largest_nematic: 0.0401,
            contacts: 6.082,
            rattlers: 15,
            certified: true,
            machine: "AMD EPYC, 2 cores".into(),
            commit: "abc1234".into(),
        };
        let dir = std::env::temp_dir().join(format!("xtask-random-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("random.csv");
        std::fs::write(&path, csv(std::slice::from_ref(&row))).unwrap();
        assert_eq!(read_rows(&path).unwrap(), vec![row]);
        std::fs::write(
            &path,
            format!("{HEADER}\nx,many,jammed,1,1,1,1,1,1,1,true,m,c\n"),
        )
        .unwrap();
        let message = read_rows(&path).unwrap_err().to_string();
        assert!(message.contains("line 2: column 2"), "{message}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
