//! `ellipack pack` and `ellipack verify`: the terminal side (progress, Ctrl-C, files).

use ellipack::export::{Cell, Format, write_formats};
use ellipack::folder::{HISTORY_FILE, Published, Staging, write_files};
use ellipack::items_csv::{CSV_FILE, read_table_into};
use ellipack::pack::{
    MultiStartProgress, Observer, RunOptions, UNFINISHED_DIR, Unfinished, probe_output_folder,
    resume_start, run, time_limit_of, verify_detailed as check,
};
use ellipack::packing::{Container, ContainerKind};
use ellipack::render::{RenderOptions, write_pictures_until};
use ellipack::scene::{Overrides, Scene};
use ellipack::summary_json::{SUMMARY_FILE, read_stated_summary};
use implicit_packing::certificate::shown_mu2;
use indicatif::{ProgressBar, ProgressStyle};
use std::error::Error;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Duration;

// The arguments of `ellipack pack`; their doc comments are its --help.
#[derive(clap::Args)]
pub struct PackArgs {
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
    /// Threads (overrides the scene's; 0: every core): parallel starts, or the evaluations of a
    /// random packing's one compression.
    #[arg(long)]
    threads: Option<usize>,
    /// Start from the packing already in the output folder.
    #[arg(long)]
    resume: bool,
    /// Run shard K of N of the multi-start (`--shard 2/8`, K from 0): the N shards of one
    /// seed try disjoint starts, and each reproduces exactly. Combine their folders with
    /// `ellipack merge`.
    #[arg(long, value_parser = crate::parse_shard)]
    shard: Option<ellipack::pack::Shard>,
}

pub fn pack(args: PackArgs) -> Result<ExitCode, Box<dyn Error>> {
    let scene = match (&args.scene, &args.instance) {
        (Some(path), _) => Scene::from_file(path)?,
        (None, Some(name)) => ellipack::instances::by_name(name)
            .ok_or_else(|| {
                format!(
                    "unknown instance `{name}`; the instances are: {}",
                    ellipack::instances::names()
                )
            })?
            .scene(),
        (None, None) => {
            crate::note!(
                "no scene given: packing the built-in scene ({})",
                Scene::default_scene().title()
            );
            Scene::default_scene()
        }
    };
    let out = args
        .out
        .clone()
        .or_else(|| scene.output.directory.clone())
        .unwrap_or_else(|| PathBuf::from("out"));
    let scene = scene.overridden(&Overrides {
        time_limit: args.time_limit.map(time_limit_of).transpose()?,
        seed: args.seed,
        threads: args.threads,
    });
    let resume_from = if args.resume {
        Some(resume_start(&scene, &out)?)
    } else {
        None
    };
    // Before the run: a folder found unwritable afterwards would lose the packing.
    probe_output_folder(&out)?;
    let options = RunOptions {
        resume_from,
        shard: args.shard,
    };

    let interrupted = Arc::new(AtomicBool::new(false));
    {
        let flag = Arc::clone(&interrupted);
        // Ctrl-C, SIGTERM and SIGHUP (the `termination` feature of ctrlc: what `timeout`,
        // Slurm, systemd and a closed terminal send) all stop the run, which then writes its
        // best certified packing. Without a handler (another one already installed) a signal
        // simply ends the process.
        let _ = ctrlc::set_handler(move || flag.store(true, Ordering::SeqCst));
    }
    // indicatif draws nothing when stderr is not a terminal.
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    bar.enable_steady_tick(Duration::from_millis(200));
    bar.set_message(format!("{}: first local minimisation", scene.title()));
    let mut terminal = Terminal {
        bar: bar.clone(),
        best: AtomicU64::new(0f64.to_bits()),
        interrupted: Arc::clone(&interrupted),
    };
    let started = std::time::Instant::now();
    let outcome = run(&scene, &options, &mut terminal);
    bar.finish_and_clear();
    let outcome = match outcome {
        Ok(outcome) => outcome,
        Err(ellipack::Error::NotReached(unfinished)) => {
            return not_reached(&scene, &out, &unfinished);
        }
        Err(e) => return Err(e.into()),
    };
    let history = outcome.history.clone().into_text();

    // The whole set is written into a staging folder and swapped in, so that the folder never
    // holds a mix of this run's files and the previous run's; an error (or a kill) before the
    // commit leaves the previous set.
    let staging = Staging::begin(&out)?;
    let staged = staging.path();
    write_files(staged, &outcome.packing, &outcome.summary, scene.output.xyz)?;
    let cell = Cell::enclosing(&outcome.packing);
    write_formats(staged, &outcome.packing, &cell, &PACK_FORMATS)?;
    ellipack::write_atomically(&staged.join(HISTORY_FILE), history.as_bytes())?;
    let structure = ellipack::analysis::analyse(
        &outcome.packing,
        &ellipack::analysis::settings(
            structure::DEFAULT_CONTACT_GAP,
            outcome.summary.repair_dilation(),
        ),
    );
    match &structure {
        Ok(s) => ellipack::analysis::write_structure(staged, s)?,
        Err(e) => crate::note!("note: the structure was not measured: {e}"),
    }
    if scene.output.pictures {
        let options = RenderOptions {
            width: scene.output.image_width,
            label: scene.name.clone(),
        };
        // Pictures are the one optional file: drawing them stops at a signal, or when it
        // would run past the time limit by more than PICTURE_GRACE (plus 5 % of the limit).
        let limit = scene.solver.time_limit;
        let deadline = limit
            .checked_add(PICTURE_GRACE + limit / 20)
            .and_then(|d| started.checked_add(d));
        let stop = || {
            interrupted.load(Ordering::SeqCst)
                || deadline.is_some_and(|d| std::time::Instant::now() >= d)
        };
        match write_pictures_until(staged, &outcome.packing, &options, &stop) {
            Ok(()) => {
                if let Ok(s) = &structure {
                    ellipack::structure_plots::write_structure_pictures(
                        staged,
                        &outcome.packing,
                        s,
                    )?;
                }
            }
            Err(ellipack::Error::Stopped) => crate::note!(
                "note: packing.svg and packing.png were not drawn: the run was stopped or \
                 drawing would have run past its time limit (`ellipack convert {} --pictures` \
                 draws them)",
                out.display()
            ),
            Err(e) => return Err(e.into()),
        }
    }
    if let Published::InPlace(why) = staging.commit()? {
        crate::note!(
            "note: the files in {} were replaced one by one, not swapped in as a set ({})",
            out.display(),
            why.map_or_else(
                || "no staging folder could be made beside it".to_string(),
                |e| e.to_string()
            )
        );
    }
    crate::report::pack(&scene, &outcome, args.resume);
    let s = &outcome.summary;
    crate::say!("wrote {}", out.display());
    Ok(if s.certificate.is_certified() {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// Exit status of `pack` when a fixed container could not be filled without overlap.
const NOT_REACHED: u8 = 4;

/// A fixed container that was not filled: the message, and the least overlapping
/// configuration written to `out/unfinished/` (as a set, like a packing folder), never over
/// the packing in `out`.
fn not_reached(
    scene: &Scene,
    out: &Path,
    unfinished: &Unfinished,
) -> Result<ExitCode, Box<dyn Error>> {
    let history = unfinished.history.clone().into_text();
    let dir = out.join(UNFINISHED_DIR);
    std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let staging = Staging::begin(&dir)?;
    let staged = staging.path();
    write_files(staged, &unfinished.packing, &unfinished.summary, false)?;
    ellipack::write_atomically(&staged.join(HISTORY_FILE), history.as_bytes())?;
    staging.commit()?;
    crate::say!("{}", scene.title());
    crate::note!(
        "error: {}{}",
        ellipack::Error::NotReached(Box::new(unfinished.clone())),
        if unfinished.interrupted {
            " (stopped by a signal)"
        } else {
            ""
        }
    );
    crate::note!(
        "wrote the least overlapping configuration, which is not a packing, to {}; {} was not \
         written (a longer time limit or a lower packing fraction may reach one)",
        dir.display(),
        out.join(CSV_FILE).display()
    );
    Ok(ExitCode::from(NOT_REACHED))
}

/// `ellipack merge`: the best certified packing of `folders` into `out`.
pub fn merge(folders: &[PathBuf], out: &Path) -> Result<ExitCode, Box<dyn Error>> {
    let outcome = ellipack::merge::merge(folders, out)?;
    for folder in &outcome.skipped {
        crate::say!(
            "  {}: no packing.csv (a run stopped before writing, or an unfinished fixed \
             container): skipped",
            folder.display()
        );
    }
    for (k, c) in outcome.candidates.iter().enumerate() {
        crate::say!(
            "{} {}: density {:.6}{}",
            if k == outcome.best { "*" } else { " " },
            c.folder.display(),
            c.density,
            if c.certified {
                ""
            } else {
                " (not certified: skipped)"
            }
        );
    }
    let best = &outcome.candidates[outcome.best];
    if outcome.written {
        crate::say!("wrote {} (from {})", out.display(), best.folder.display());
    } else {
        crate::say!(
            "{} already holds the best packing: left as it was",
            out.display()
        );
    }
    if let Some(Published::InPlace(_)) = outcome.published {
        crate::note!(
            "note: the files in {} were replaced one by one, not swapped in as a set",
            out.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// How far past its time limit a run may go on drawing its pictures (besides 5 % of the limit).
const PICTURE_GRACE: Duration = Duration::from_secs(2);

/// The files for other programs that `ellipack pack` writes beside packing.csv (packing.xyz
/// is written with them, unless the scene turns it off).
const PACK_FORMATS: [Format; 3] = [Format::Lammps, Format::Gsd, Format::Obj];

/// The options of `ellipack analyse`.
#[derive(clap::Args)]
pub struct AnalyseArgs {
    /// The folder with packing.csv and summary.json.
    pub folder: PathBuf,
    /// Relative gap of a contact: two items touch when mu < (1 + gap)·s, s the repair
    /// dilation summary.json states (1 if none): the run dilated every pair it left
    /// touching to mu ≈ s.
    #[arg(long, default_value_t = structure::DEFAULT_CONTACT_GAP)]
    pub gap: f64,
    /// Bond cutoff of Q4, Q6 and psi6, a distance of centres (default: 1.4 mean equivalent
    /// diameters).
    #[arg(long)]
    pub bond_cutoff: Option<f64>,
    /// Largest r of g(r) (default: 5 mean equivalent diameters, at most half the smallest
    /// width of a periodic cell).
    #[arg(long)]
    pub rdf_range: Option<f64>,
    /// Bins of g(r).
    #[arg(long, default_value_t = structure::DEFAULT_RDF_BINS)]
    pub rdf_bins: usize,
}

/// `ellipack analyse`: the structure of a packing folder, written into it and summarised.
pub fn analyse(args: &AnalyseArgs) -> Result<ExitCode, Box<dyn Error>> {
    let summary_path = args.folder.join(SUMMARY_FILE);
    let text = std::fs::read_to_string(&summary_path).map_err(|source| ellipack::Error::Io {
        path: summary_path.clone(),
        source,
    })?;
    let summary_name = summary_path.display().to_string();
    let stated = read_stated_summary(&text, &summary_name)?;
    let (packing, _) = read_table_into(
        &args.folder.join(CSV_FILE),
        stated.container,
        stated.items,
        &summary_name,
    )?;
    let settings = ellipack::analysis::settings(args.gap, ellipack::analysis::stated_repair(&text))
        .with_bond_cutoff(args.bond_cutoff)
        .with_rdf_range(args.rdf_range)
        .with_rdf_bins(args.rdf_bins);
    let s = ellipack::analysis::analyse(&packing, &settings)?;
    ellipack::analysis::write_structure(&args.folder, &s)?;
    ellipack::structure_plots::write_structure_pictures(&args.folder, &packing, &s)?;
    let mut out = std::io::stdout().lock();
    let lines = structure_lines(&s);
    for line in lines {
        if writeln!(out, "{line}").is_err() {
            // The reader has gone (`ellipack analyse out | head -1`): nothing more to say.
            return Ok(ExitCode::SUCCESS);
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// The structure of a packing in a few lines, for the terminal.
fn structure_lines(s: &structure::Structure) -> Vec<String> {
    let mut lines = vec![format!(
        "{} items, density {:.5}, mean equivalent diameter {:.6}",
        s.items, s.density, s.mean_equivalent_diameter
    )];
    let axes: Vec<String> = s
        .nematic
        .iter()
        .map(|n| format!("axis {}: S = {:.4}", n.axis + 1, n.order))
        .collect();
    lines.push(if axes.is_empty() {
        "nematic order: none (every item is round)".to_string()
    } else {
        format!("nematic order: {}", axes.join(", "))
    });
    // "hexatic (bonds < 1.7000, 5.93 per item): psi6 = 0.7012, psi6_local_mean = 0.8120"
    let (kind, figures) = s.bond_order.named_figures();
    if let [(_, cutoff), (_, mean_bonds), order @ ..] = figures.as_slice() {
        let order: Vec<String> = order.iter().map(|(n, v)| format!("{n} = {v:.4}")).collect();
        lines.push(format!(
            "{kind} (bonds < {cutoff:.4}, {mean_bonds:.2} per item): {}",
            order.join(", ")
        ));
    }
    let c = &s.contacts;
    lines.push(format!(
        "contacts (mu < 1 + {:.1e}): {} pairs, Z = {:.3}; {} rattlers, Z without them = {:.3}",
        c.gap, c.pairs, c.mean_contacts, c.rattlers, c.mean_contacts_without_rattlers
    ));
    lines
}

/// `ellipack convert`: the files of `formats` for the packing in `folder`.
pub fn convert(
    folder: &Path,
    formats: &[Format],
    unfinished: bool,
    pictures: bool,
) -> Result<ExitCode, Box<dyn Error>> {
    let packing = ellipack::export::convert(folder, formats, unfinished)?;
    let mut names: Vec<&str> = formats.iter().map(|f| f.file_name()).collect();
    if pictures {
        write_pictures_until(folder, &packing, &RenderOptions::default(), &|| false)?;
        names.extend([ellipack::render::SVG_FILE, ellipack::render::PNG_FILE]);
    }
    crate::say!(
        "{} {} in a {} container: wrote {} in {}",
        packing.items().len(),
        packing.items().noun(),
        packing.container().kind(),
        names.join(", "),
        folder.display()
    );
    Ok(ExitCode::SUCCESS)
}

/// The arguments of `ellipack verify`.
#[derive(clap::Args)]
pub struct VerifyArgs {
    /// A folder with packing.csv and summary.json, or the path of packing.csv.
    pub packing: PathBuf,
    /// summary.json, when the first argument is packing.csv (default: the one beside it).
    #[arg(conflicts_with = "container")]
    pub summary: Option<PathBuf>,
    /// The container instead of a summary: circle, ellipse, rectangle (2D), ball,
    /// ellipsoid, cuboid (3D), periodic (a cell of the packing's dimension).
    #[arg(long, requires = "size", value_parser = crate::parse_container_kind)]
    pub container: Option<ContainerKind>,
    /// The container's size: the radius, or the semi-axes or half sides separated by commas
    /// (`--size 1,2,3`); a periodic cell's lengths, then its tilts if any (xy in 2D; xy,
    /// xz, yz in 3D).
    #[arg(long, requires = "container", allow_hyphen_values = true, value_parser = crate::numbers)]
    pub size: Option<crate::Numbers>,
    /// The container's centre, coordinates separated by commas (default: the origin).
    #[arg(long, requires = "container", allow_hyphen_values = true, value_parser = crate::numbers)]
    pub center: Option<crate::Numbers>,
}

/// How many offenders of each kind are printed (all are counted).
const OFFENDERS_SHOWN: usize = 20;

/// 3 when the header of the packing table at `path` has a `z` column, 2 when it has none, `None`
/// when it cannot be read (reading it again reports why).
fn header_dimension(path: &Path) -> Option<usize> {
    use std::io::BufRead;
    let mut line = String::new();
    std::io::BufReader::new(std::fs::File::open(path).ok()?)
        .read_line(&mut line)
        .ok()?;
    Some(if line.trim().split(',').any(|c| c.trim() == "z") {
        3
    } else {
        2
    })
}

pub fn verify(args: VerifyArgs) -> Result<ExitCode, Box<dyn Error>> {
    let csv_path = if args.packing.is_dir() {
        args.packing.join(CSV_FILE)
    } else {
        args.packing.clone()
    };
    let (packing, table, stated) = match (args.container, &args.size) {
        (Some(kind), Some(size)) => {
            // `periodic` names the cell of either dimension: the packing's header says which.
            let kind = match header_dimension(&csv_path) {
                Some(n) if kind.is_periodic() => {
                    ContainerKind::named("periodic", n).unwrap_or(kind)
                }
                _ => kind,
            };
            let center = args
                .center
                .clone()
                .unwrap_or_else(|| vec![0.0; kind.dimension()]);
            let container = Container::from_parts(kind, &center, size).map_err(|e| match e {
                ellipack::Error::Inconsistent { message, .. } => {
                    format!("--container {kind}: {message}")
                }
                other => other.to_string(),
            })?;
            let (packing, table) = read_table_into(&csv_path, container, None, "--container")?;
            (packing, table, None)
        }
        _ => {
            let summary_path = match &args.summary {
                Some(path) => path.clone(),
                None => csv_path
                    .parent()
                    .unwrap_or(Path::new("."))
                    .join(SUMMARY_FILE),
            };
            if args.summary.is_none() && !summary_path.exists() {
                return Err(format!(
                    "{}: not found; for a packing without a summary give the container, e.g. \
                     `--container ball --size 5` or `--container cuboid --size 1,2,3`",
                    summary_path.display()
                )
                .into());
            }
            let summary_name = summary_path.display().to_string();
            let text = std::fs::read_to_string(&summary_path)
                .map_err(|e| format!("{summary_name}: {e}"))?;
            let stated = read_stated_summary(&text, &summary_name)?;
            let (packing, table) = read_table_into(
                &csv_path,
                stated.container.clone(),
                stated.items,
                &summary_name,
            )?;
            (packing, table, stated.certificate)
        }
    };
    let verification = check(&packing)?;
    let certificate = verification.certificate;
    crate::say!(
        "{} {}, container: {}, density {:.5}",
        packing.items().len(),
        packing.items().noun(),
        packing.container().kind().name(),
        packing.density()
    );
    crate::say!(
        "certificate: {} overlapping pairs, {} containment violations, min μ² = {}",
        certificate.overlapping_pairs,
        certificate.containment_violations,
        certificate.min_mu2.map_or("—".into(), |m| shown_mu2(m, 12))
    );
    // Messages name items by the `id` column of packing.csv, which a person edited or sorted.
    let id = |row: usize| table.ids.get(row).copied().unwrap_or(row as u64);
    let pairs = &verification.overlapping_pairs;
    if !pairs.is_empty() {
        crate::say!("overlapping pairs (ids, μ² < 1), deepest first:");
        for p in pairs.iter().take(OFFENDERS_SHOWN) {
            crate::say!(
                "  {} and {}: μ² = {}",
                id(p.items.0),
                id(p.items.1),
                shown_mu2(p.mu2, 12)
            );
        }
        if pairs.len() > OFFENDERS_SHOWN {
            crate::say!("  … and {} more", pairs.len() - OFFENDERS_SHOWN);
        }
    }
    let outside = &verification.outside;
    if !outside.is_empty() {
        crate::say!(
            "outside the container (id, t: the item fits only in the container scaled by t \
             about its centre), worst first:"
        );
        for o in outside.iter().take(OFFENDERS_SHOWN) {
            let percent = 100.0 * (o.scale - 1.0);
            let percent = if percent >= 0.01 {
                format!("{percent:.2}")
            } else {
                format!("{percent:.1e}")
            };
            crate::say!(
                "  {}: t = {:.9} (the container would have to be {percent} % larger)",
                id(o.item),
                o.scale,
            );
        }
        if outside.len() > OFFENDERS_SHOWN {
            crate::say!("  … and {} more", outside.len() - OFFENDERS_SHOWN);
        }
    }
    // The counts are the verdict; the smallest μ² may differ in its last digits between runs
    // of the same certificate, and says nothing the counts do not.
    if let Some(stated) = stated.filter(|s| {
        (s.overlapping_pairs, s.containment_violations)
            != (
                certificate.overlapping_pairs,
                certificate.containment_violations,
            )
    }) {
        crate::say!(
            "note: summary.json states {} overlapping pairs, {} containment violations",
            stated.overlapping_pairs,
            stated.containment_violations
        );
    }
    Ok(if certificate.is_certified() {
        crate::say!("certified");
        ExitCode::SUCCESS
    } else {
        crate::say!("NOT certified");
        ExitCode::FAILURE
    })
}

/// The run as the terminal shows it: a spinner with the solver's objective and infeasibility
/// (worker threads) and the best certified density (known between local minimisations), and
/// Ctrl-C, SIGTERM or SIGHUP as the request to stop.
struct Terminal {
    bar: ProgressBar,
    best: AtomicU64,
    interrupted: Arc<AtomicBool>,
}

impl Observer for Terminal {
    fn finished(&mut self, p: &MultiStartProgress) {
        self.best.store(p.best_density.to_bits(), Ordering::Relaxed);
        // A fixed container's runs report no best density until their first packing.
        let best = if p.best_density > 0.0 {
            format!("best certified density {:.5}", p.best_density)
        } else {
            "no packing yet".to_string()
        };
        self.bar.set_message(format!(
            "{} local minimisations, last density {:.5}, {best}",
            p.local_minimisations, p.last_density
        ));
    }

    fn iteration(&self, p: &ellipsoid_packer::multistart::SolverProgress<'_>) {
        if let ellipsoid_packer::multistart::SolverEvent::Outer {
            objective,
            infeasibility,
            ..
        } = p.event
        {
            let best = f64::from_bits(self.best.load(Ordering::Relaxed));
            self.bar.set_message(format!(
                "objective {objective:.6}, infeasibility {infeasibility:.1e}, best certified \
                 density {best:.5}"
            ));
        }
    }

    fn should_stop(&self) -> bool {
        self.interrupted.load(Ordering::SeqCst)
    }
}
