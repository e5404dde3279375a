//! `ellipack merge`: the best certified packing of several runs of one scene (the shards of a
//! multi-start spread over machines, or repeated runs), re-verified, into one folder.
//!
//! Every input is read and verified again (PW85 verdicts on every close pair, exact
//! containment): a folder's own summary is not trusted. Inputs must be packings of the same
//! items in the same kind of container; a packing already in the output folder takes part
//! too, so a merge never replaces a better certified packing with a worse one.

use crate::Error;
use crate::folder::read_packing_dir;
use crate::folder::{Published, RUN_FILES, Staging};
use crate::items_csv::CSV_FILE;
use crate::pack::verify;
use crate::packing::{Container, ContainerKind, Items, Packing, Summary};
use std::path::{Path, PathBuf};

/// One packing read for a merge, with its verification.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// Its folder.
    pub folder: PathBuf,
    /// Its density, computed from its files.
    pub density: f64,
    /// Whether it verified: no overlapping pair, no item outside.
    pub certified: bool,
}

/// What a merge did.
#[derive(Debug)]
pub struct MergeOutcome {
    /// Every input, in the order given, then the output folder's own packing if it had one.
    pub candidates: Vec<Candidate>,
    /// The index in `candidates` of the packing kept.
    pub best: usize,
    /// Whether the output folder was written (false when it already held the best packing).
    pub written: bool,
    /// How the files were published, when written.
    pub published: Option<Published>,
    /// Inputs with no packing (a run killed before writing one, or a fixed container's run
    /// that ended with only `unfinished/`), left out.
    pub skipped: Vec<PathBuf>,
}

/// The items and container that make two packings packings of the same scene: the container's
/// kind, and for a fixed container (or cell) the container itself.
#[derive(Debug, PartialEq)]
struct SceneKey {
    kind: ContainerKind,
    /// The container, when the run was given it (`fixed_container` in summary.json).
    fixed: Option<Container>,
    /// Every item's semi-axes, as bits, sorted: the items as a multiset.
    axes: Vec<Vec<u64>>,
}

impl SceneKey {
    fn of(packing: &Packing, summary: &Summary) -> Self {
        let mut axes: Vec<Vec<u64>> = match packing.items() {
            Items::Ellipses(items) => items
                .iter()
                .map(|e| e.semi_axes.iter().map(|a| a.to_bits()).collect())
                .collect(),
            Items::Ellipsoids(items) => items
                .iter()
                .map(|e| e.semi_axes.iter().map(|a| a.to_bits()).collect())
                .collect(),
        };
        axes.sort_unstable();
        Self {
            kind: packing.container().kind(),
            fixed: summary.fixed_container.then(|| packing.container().clone()),
            axes,
        }
    }

    /// How `other` differs from this key, if it does.
    fn difference(&self, other: &SceneKey) -> Option<String> {
        if self.kind != other.kind {
            return Some(format!("container {} against {}", other.kind, self.kind));
        }
        match (&self.fixed, &other.fixed) {
            (Some(a), Some(b)) if !same_container(a, b) => {
                return Some(format!(
                    "fixed container {} against {}",
                    described(b),
                    described(a)
                ));
            }
            (Some(a), None) => {
                return Some(format!(
                    "a variable container against the fixed {}",
                    described(a)
                ));
            }
            (None, Some(b)) => {
                return Some(format!(
                    "the fixed {} against a variable container",
                    described(b)
                ));
            }
            _ => {}
        }
        if self.axes.len() != other.axes.len() {
            return Some(format!(
                "{} items against {}",
                other.axes.len(),
                self.axes.len()
            ));
        }
        (self.axes != other.axes).then(|| "the items' semi-axes differ".to_string())
    }
}

/// A container in words: its kind and size, e.g. `ball of radius [6.0]`.
fn described(c: &Container) -> String {
    format!("{} of {} {:?}", c.kind(), c.size_name(), c.size())
}

/// Whether two fixed containers are one: the same kind, centre and size to 1e-12 relative (the
/// digits summary.json keeps).
fn same_container(a: &Container, b: &Container) -> bool {
    let close = |x: &[f64], y: &[f64]| {
        x.len() == y.len()
            && x.iter()
                .zip(y)
                .all(|(u, v)| (u - v).abs() <= 1e-12 * u.abs().max(v.abs()).max(1.0))
    };
    a.kind() == b.kind() && close(a.center(), b.center()) && close(&a.size(), &b.size())
}

/// Reads and verifies `folder`.
fn candidate(folder: &Path) -> Result<(Candidate, SceneKey), Error> {
    let (packing, summary) = read_packing_dir(folder).map_err(|source| Error::Unreadable {
        folder: folder.to_path_buf(),
        source: Box::new(source),
    })?;
    let certificate = verify(&packing).map_err(|source| Error::Unverifiable {
        folder: folder.to_path_buf(),
        source: Box::new(source),
    })?;
    let key = SceneKey::of(&packing, &summary);
    Ok((
        Candidate {
            folder: folder.to_path_buf(),
            density: packing.density(),
            certified: certificate.is_certified(),
        },
        key,
    ))
}

/// Merges the packings in `inputs` into `out`: skips folders without a packing, verifies each
/// other, refuses packings of different scenes (items, container kind, and a fixed container
/// against another or against a variable one), and writes the densest certified one's files (those `ellipack pack` writes) into
/// `out`, swapped in as a set. A certified packing already in `out` of the same scene takes
/// part: if it is the densest, nothing is written.
///
/// # Errors
/// [`Error`]: an unreadable input, different scenes, no certified input, or an output
/// folder that cannot be written. Nothing is written then.
pub fn merge(inputs: &[PathBuf], out: &Path) -> Result<MergeOutcome, Error> {
    if inputs.is_empty() {
        return Err(Error::NoInputs);
    }
    let mut candidates = Vec::with_capacity(inputs.len() + 1);
    let mut skipped = Vec::new();
    let mut first_key: Option<(PathBuf, SceneKey)> = None;
    let existing = out.join(CSV_FILE).exists();
    let output_is_input = inputs.iter().any(|i| same_folder(i, out));
    let folders = inputs
        .iter()
        .map(PathBuf::as_path)
        .chain((existing && !output_is_input).then_some(out));
    for folder in folders {
        if folder.is_dir() && !folder.join(CSV_FILE).exists() {
            skipped.push(folder.to_path_buf());
            continue;
        }
        let (c, key) = candidate(folder)?;
        match &first_key {
            None => first_key = Some((folder.to_path_buf(), key)),
            Some((first_folder, first)) => {
                if let Some(difference) = first.difference(&key) {
                    return Err(Error::DifferentScenes {
                        first: first_folder.clone(),
                        other: folder.to_path_buf(),
                        difference,
                    });
                }
            }
        }
        candidates.push(c);
    }
    let best = candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.certified)
        .fold(None::<usize>, |best, (k, c)| match best {
            Some(b) if candidates[b].density >= c.density => Some(b),
            _ => Some(k),
        })
        .ok_or(Error::NoneCertified {
            inputs: candidates.len(),
            skipped: skipped.len(),
        })?;
    if same_folder(&candidates[best].folder, out) {
        return Ok(MergeOutcome {
            candidates,
            best,
            written: false,
            published: None,
            skipped,
        });
    }
    std::fs::create_dir_all(out).map_err(|source| Error::OutputFolder {
        path: out.to_path_buf(),
        source,
    })?;
    let staging = Staging::begin(out)?;
    for name in RUN_FILES {
        let from = candidates[best].folder.join(name);
        if from.is_file() {
            std::fs::copy(&from, staging.path().join(name))
                .map_err(|source| Error::NotCopied { path: from, source })?;
        }
    }
    let published = staging.commit()?;
    Ok(MergeOutcome {
        candidates,
        best,
        written: true,
        published: Some(published),
        skipped,
    })
}

/// Whether two paths name the same existing folder.
fn same_folder(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}
