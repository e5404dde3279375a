//! `cargo xtask validate`: the evidence that ellipack's two overlap criteria — the
//! Perram–Wertheim contact function (crate `pw85`) and the implicit-variable overlap measure
//! (crate `implicit-packing`) — are right, how they compare, what they cost and where they
//! break.
//!
//! Each study is described by a scene file in `validation/scenes/` ([`scene`]) and implemented
//! by one module: [`theory`] (checks with residuals and tolerances), [`snapshots`] (insta
//! snapshots of fixed pairs), [`figures`] (approach paths, agreement against aspect ratio,
//! packings), [`stiff`] (extreme cases), [`timing`] (error against run time, model time).
//! Results go to `validation/results/` (CSV), `docs/figures/` (SVG, PNG) and
//! `docs/validation.md` ([`report`]), each written only when its content changed
//! ([`output`]).

pub mod error;
pub mod figures;
pub mod implicit;
pub mod model_time;
pub mod output;
pub mod packing;
pub mod paper_tables;
pub mod periodic_cells;
pub mod periodic_peer;
pub mod plot;
pub mod provenance;
pub mod random_study;
pub mod reference;
pub mod report;
pub mod sample;
pub mod scale;
pub mod scene;
pub mod snapshots;
pub mod stiff;
pub mod theory;
pub mod timing;

pub use error::Error;

use output::Outputs;
use report::Section;
use scene::{LoadedScene, Study};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The parts of `validate`, each a subcommand.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// Theory checks.
    Theory,
    /// insta snapshots.
    Snapshots,
    /// Figures comparing the criteria (approach, agreement, packings).
    Figures,
    /// Stiff and extreme cases.
    Stiff,
    /// Error against run time, model time.
    Timing,
}

impl Part {
    /// Every part, in the order `validate` runs them.
    pub const ALL: [Part; 5] = [
        Part::Theory,
        Part::Snapshots,
        Part::Figures,
        Part::Stiff,
        Part::Timing,
    ];

    /// The part a study belongs to.
    pub fn of(study: Study) -> Part {
        match study {
            Study::Theory => Part::Theory,
            Study::Approach | Study::Agreement | Study::Packing => Part::Figures,
            Study::Stiff => Part::Stiff,
            Study::ErrorTime | Study::ModelTime => Part::Timing,
        }
    }
}

/// The workspace root (the parent of `xtask/`).
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
}

/// Progress on stderr (the terminal), with the time since the start of the run.
pub fn progress(start: Instant) -> impl Fn(&str) {
    move |msg: &str| eprintln!("[{:>6.1} s] {msg}", start.elapsed().as_secs_f64())
}

/// Everything a run produces besides files.
pub struct Run {
    /// The workspace root.
    pub root: PathBuf,
    /// Where results, figures and the report go: the workspace itself for the full run, and
    /// `target/validate-quick/` for `--quick`, so that a CI-sized run never overwrites the
    /// committed full-size results.
    pub out: PathBuf,
    /// `--quick`.
    pub quick: bool,
    /// The file writer.
    pub outputs: Outputs,
    /// Report sections, in scene order.
    pub sections: Vec<Section>,
    /// Failed checks (one line each).
    pub failures: Vec<String>,
    /// Studies that could not run, and why.
    pub skipped: Vec<String>,
    /// When the run started.
    pub start: Instant,
}

impl Run {
    /// A run over the workspace at `root`.
    pub fn new(root: PathBuf, quick: bool, check: bool) -> Self {
        let out = if quick {
            root.join("target/validate-quick")
        } else {
            root.clone()
        };
        Run {
            root,
            out,
            quick,
            outputs: Outputs::new(check),
            sections: Vec::new(),
            failures: Vec::new(),
            skipped: Vec::new(),
            start: Instant::now(),
        }
    }

    /// Prints a progress line.
    pub fn say(&self, msg: &str) {
        progress(self.start)(msg);
    }

    /// `validation/results/<name>`.
    pub fn results(&self, name: &str) -> PathBuf {
        self.out.join("validation/results").join(name)
    }

    /// Writes `rows` under `header` to the scene's results file, if it names one.
    pub fn write_csv(
        &mut self,
        s: &LoadedScene,
        header: &[&str],
        rows: &[Vec<String>],
        stability: output::Stability,
    ) -> Result<(), Error> {
        if let Some(csv) = &s.scene.outputs.csv {
            let path = self.results(csv);
            let text = output::csv_text(header, rows);
            self.outputs.write(&path, text.as_bytes(), stability)?;
        }
        Ok(())
    }

    /// `docs/figures/`.
    pub fn figures_dir(&self) -> PathBuf {
        self.out.join("docs/figures")
    }

    /// Runs the selected parts over the scenes.
    pub fn run(&mut self, parts: &[Part]) -> Result<(), Error> {
        let scenes = scene::read_all(&self.root.join("validation/scenes"))?;
        self.say(&format!("{} scenes read", scenes.len()));
        for &part in parts {
            if part == Part::Snapshots {
                snapshots::run(self, &scenes)?;
                continue;
            }
            for s in scenes.iter().filter(|s| Part::of(s.scene.study) == part) {
                self.study(s)?;
            }
        }
        Ok(())
    }

    fn study(&mut self, s: &LoadedScene) -> Result<(), Error> {
        if !s.scene.needs.is_empty() {
            let why = format!(
                "{} ({}): skipped: needs {}",
                s.scene.title,
                s.name(),
                s.scene.needs.join(", ")
            );
            self.say(&why);
            self.skipped.push(why);
            self.sections.push(Section::skipped(s));
            return Ok(());
        }
        self.say(&format!("{} ({})", s.scene.title, s.name()));
        let section = match s.scene.study {
            Study::Theory => theory_study(self, s)?,
            Study::Approach => figures::approach(self, s)?,
            Study::Agreement => figures::agreement(self, s)?,
            Study::ErrorTime => timing::error_time(self, s)?,
            Study::Stiff => stiff::run(self, s)?,
            Study::ModelTime => model_time::run(self, s)?,
            Study::Packing => packing::run(self, s)?,
        };
        self.sections.push(section);
        Ok(())
    }
}

fn theory_study(run: &mut Run, s: &LoadedScene) -> Result<Section, Error> {
    let n = s.require_workload(run.quick, "pairs", s.workload(run.quick).pairs)?;
    let say = progress(run.start);
    let groups = theory::Groups {
        pw85: s.uses(scene::Criterion::Pw85),
        implicit: s.uses(scene::Criterion::Implicit),
    };
    let checks = theory::all(n, s.scene.seed, groups, &say)?;
    for c in &checks {
        println!("{}", c.line());
        if !c.passed() {
            run.failures.push(c.line());
        }
    }
    let rows: Vec<Vec<String>> = checks
        .iter()
        .map(|c| {
            vec![
                c.group.to_string(),
                format!("\"{}\"", c.name),
                output::short(c.residual),
                format!("{:.0e}", c.tolerance),
                c.cases.to_string(),
                if c.passed() { "PASS" } else { "FAIL" }.to_string(),
            ]
        })
        .collect();
    // The residuals are deterministic for a given seed and workload, but the quick and full
    // runs use different workloads: only the full run's file is committed as stable.
    run.write_csv(
        s,
        &["group", "check", "residual", "tolerance", "cases", "result"],
        &rows,
        output::Stability::Volatile,
    )?;
    Ok(report::theory_section(s, &checks, n, run.quick))
}
