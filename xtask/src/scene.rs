//! Scene files: `validation/scenes/*.toml`, one study each.
//!
//! A scene says which study it is, which criteria and quantities it needs, its shapes or
//! parameter sweeps, its workload for `--quick` and for the full run, and its outputs. The
//! harness computes only what the scene asks for: a `verdict`-only scene calls the verdict
//! functions and never μ² or gradients; `dimension = 2` runs the 2D code.
//!
//! Unknown keys are errors (a misspelt key silently ignored would run a different study than
//! the one written down), and every error names the file, the key and the line.

use crate::error::Error;
use serde::Deserialize;
use std::ops::Range;
use std::path::{Path, PathBuf};
use toml::Spanned;

/// Which study a scene describes (each is implemented by one function of the harness).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Study {
    /// The theory checks (`validate theory`).
    Theory,
    /// Figure 1: μ² − 1 and f along an approach path.
    Approach,
    /// Figure 2: verdict agreement and cost per evaluation against aspect ratio.
    Agreement,
    /// Figure 3: error against run time of every solver.
    ErrorTime,
    /// Figure 4: stiff and extreme cases.
    Stiff,
    /// Figure 5: model evaluation time against m (grid against all pairs).
    ModelTime,
    /// Figure 6: packings.
    Packing,
}

/// An overlap criterion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Criterion {
    /// The Perram–Wertheim contact function (crate `pw85`).
    Pw85,
    /// The implicit-variable overlap measure (crate `implicit-packing`).
    Implicit,
}

/// A quantity a scene may ask for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quantity {
    /// Overlap or not.
    Verdict,
    /// The contact function μ² (and λ).
    Mu2,
    /// The implicit-variable pair term f.
    F,
    /// The multiplier U, the projection X and d².
    U,
    /// Gradients.
    Gradients,
}

/// A PW85 solver (figure 3, 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Bisection on c(λ), as the PW85 library.
    Bisection,
    /// Brent's maximisation of f(λ).
    Brent,
    /// Newton on c(λ).
    Newton,
    /// `pw85::contact_function`.
    Ours,
    /// The projection solver of the implicit-variable model.
    Projection,
}

impl Method {
    /// The name used in tables, CSV files and legends.
    pub fn name(self) -> &'static str {
        match self {
            Method::Bisection => "bisection",
            Method::Brent => "brent",
            Method::Newton => "newton",
            Method::Ours => "ours",
            Method::Projection => "projection",
        }
    }

    /// Whether the method takes a tolerance on λ.
    pub fn has_tolerance(self) -> bool {
        matches!(self, Method::Bisection | Method::Brent | Method::Newton)
    }
}

/// How much work a study does.
#[derive(Debug, Clone, Copy, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Workload {
    /// Random pairs (per parameter value where the study sweeps one).
    #[serde(default)]
    pub pairs: usize,
    /// Points along a path.
    #[serde(default)]
    pub steps: usize,
    /// Timing repetitions over the pair set.
    #[serde(default)]
    pub repeats: usize,
    /// Largest m for which the all-pairs sum is evaluated (it costs m²/2 pair terms).
    #[serde(default)]
    pub all_pairs_up_to: usize,
    /// Largest number of items a study sweeps (0: no limit), so that quick runs skip the
    /// largest scenes.
    #[serde(default)]
    pub max_items: usize,
    /// Wall-time limit in seconds (multi-start runs).
    #[serde(default)]
    pub seconds: f64,
}

/// One fixed pair of ellipsoids: the first at the origin, the second along `direction`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShapePair {
    /// Legend name.
    pub name: String,
    /// Semi-axes of the first ellipsoid.
    pub axes_i: Spanned<Vec<f64>>,
    /// Semi-axes of the second ellipsoid.
    pub axes_j: Spanned<Vec<f64>>,
    /// Rotation of the first ellipsoid, quaternion (w, x, y, z); identity by default.
    #[serde(default = "identity")]
    pub quaternion_i: [f64; 4],
    /// Rotation of the second ellipsoid.
    #[serde(default = "identity")]
    pub quaternion_j: [f64; 4],
    /// Direction of the approach (centre of j relative to centre of i).
    pub direction: Spanned<Vec<f64>>,
}

fn identity() -> [f64; 4] {
    [1.0, 0.0, 0.0, 0.0]
}

fn empty() -> Spanned<Vec<f64>> {
    Spanned::new(0..0, Vec::new())
}

fn three() -> Spanned<u8> {
    Spanned::new(0..0, 3)
}

/// Output files of a study.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Outputs {
    /// CSV file name in `validation/results/`.
    pub csv: Option<String>,
    /// Figure base name in `docs/figures/` (`.svg` and `.png` are written).
    pub figure: Option<String>,
}

/// A scene as written in its file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Section title in the report.
    pub title: String,
    /// Which study.
    pub study: Study,
    /// 2 or 3.
    #[serde(default = "three")]
    pub dimension: Spanned<u8>,
    /// The criteria to evaluate.
    #[serde(default)]
    pub criteria: Vec<Criterion>,
    /// The quantities to compute.
    #[serde(default)]
    pub quantities: Vec<Quantity>,
    /// Fixed shape pairs.
    #[serde(default)]
    pub shapes: Vec<ShapePair>,
    /// Aspect ratios to sweep.
    #[serde(default = "empty")]
    pub aspect_ratios: Spanned<Vec<f64>>,
    /// Distances from tangency |μ² − 1| to sweep.
    #[serde(default = "empty")]
    pub tangency_gaps: Spanned<Vec<f64>>,
    /// Solver tolerances on λ.
    #[serde(default = "empty")]
    pub tolerances: Spanned<Vec<f64>>,
    /// Solvers.
    #[serde(default)]
    pub methods: Vec<Method>,
    /// Numbers of ellipsoids m (model studies).
    #[serde(default)]
    pub item_counts: Vec<usize>,
    /// Semi-axes of every ellipsoid of a model study.
    #[serde(default = "empty")]
    pub item_axes: Spanned<Vec<f64>>,
    /// `ellipack pack` scene files, relative to `validation/scenes/`, that the packing study
    /// solves with the command line's own pipeline and draws with its pictures.
    #[serde(default)]
    pub pack_scenes: Vec<String>,
    /// Seed of the pseudo-random pairs.
    #[serde(default)]
    pub seed: u64,
    /// Workload of `--quick`.
    #[serde(default)]
    pub quick: Workload,
    /// Workload of the full run.
    #[serde(default)]
    pub full: Workload,
    /// What the study needs that does not exist yet: a non-empty list makes the study report
    /// "skipped: needs …" instead of running.
    #[serde(default)]
    pub needs: Vec<String>,
    /// Output files.
    #[serde(default)]
    pub outputs: Outputs,
}

/// A scene with where it came from, for error messages.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    /// The file.
    pub path: PathBuf,
    /// Its text (to turn spans into line numbers).
    pub text: String,
    /// The parsed scene.
    pub scene: Scene,
}

/// 1-based line and column of a byte offset.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before
        .rfind('\n')
        .map_or(before.len(), |n| before.len() - n - 1)
        + 1;
    (line, column)
}

impl LoadedScene {
    /// Parses one scene file.
    pub fn read(path: &Path) -> Result<Self, Error> {
        let text = std::fs::read_to_string(path).map_err(crate::error::io(path))?;
        Self::parse(path, text)
    }

    /// Parses scene text (`path` only names it in errors).
    pub fn parse(path: &Path, text: String) -> Result<Self, Error> {
        let scene: Scene = toml::from_str(&text).map_err(|e| {
            let (line, column) = e.span().map_or((0, 0), |s| line_column(&text, s.start));
            Error::SceneSyntax {
                path: path.to_path_buf(),
                line,
                column,
                message: e.message().to_string(),
            }
        })?;
        let loaded = LoadedScene {
            path: path.to_path_buf(),
            text,
            scene,
        };
        loaded.validate()?;
        Ok(loaded)
    }

    /// An error naming `dimension` unless the scene is in `dimension` dimensions; `why` says
    /// what the study is written for.
    pub fn require_dimension(&self, dimension: u8, why: &str) -> Result<(), Error> {
        if *self.scene.dimension.get_ref() != dimension {
            return Err(self.value_error("dimension", self.scene.dimension.span(), why));
        }
        Ok(())
    }

    /// The scene's `item_axes`, which must be `n` semi-axes.
    pub fn item_axes(&self, n: usize) -> Result<&[f64], Error> {
        let axes = self.scene.item_axes.get_ref();
        if axes.len() != n {
            let message = format!("needs {n} semi-axes");
            return Err(self.value_error("item_axes", self.scene.item_axes.span(), message));
        }
        Ok(axes)
    }

    /// An error about the value of `key` at `span`.
    pub fn value_error(&self, key: &str, span: Range<usize>, message: impl Into<String>) -> Error {
        let line = if span.end == 0 {
            0
        } else {
            line_column(&self.text, span.start).0
        };
        Error::SceneValue {
            path: self.path.clone(),
            key: key.to_string(),
            line,
            message: message.into(),
        }
    }

    /// The workload for this run.
    pub fn workload(&self, quick: bool) -> Workload {
        if quick {
            self.scene.quick
        } else {
            self.scene.full
        }
    }

    /// The file name without directory, for messages.
    pub fn name(&self) -> String {
        self.path
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
    }

    /// Whether the scene asks for a quantity.
    pub fn wants(&self, q: Quantity) -> bool {
        self.scene.quantities.contains(&q)
    }

    /// Whether the scene asks for a criterion.
    pub fn uses(&self, c: Criterion) -> bool {
        self.scene.criteria.contains(&c)
    }

    /// Checks the values that the schema cannot: lengths, ranges, required lists.
    fn validate(&self) -> Result<(), Error> {
        let s = &self.scene;
        let dim = *s.dimension.get_ref();
        if dim != 2 && dim != 3 {
            return Err(self.value_error("dimension", s.dimension.span(), "must be 2 or 3"));
        }
        let positive = |key: &str, v: &Spanned<Vec<f64>>| -> Result<(), Error> {
            match v.get_ref().iter().find(|x| !(x.is_finite() && **x > 0.0)) {
                Some(x) => Err(self.value_error(
                    key,
                    v.span(),
                    format!("{x} is not a positive finite number"),
                )),
                None => Ok(()),
            }
        };
        positive("aspect_ratios", &s.aspect_ratios)?;
        positive("tangency_gaps", &s.tangency_gaps)?;
        positive("tolerances", &s.tolerances)?;
        positive("item_axes", &s.item_axes)?;
        if !s.item_axes.get_ref().is_empty() && s.item_axes.get_ref().len() != usize::from(dim) {
            return Err(self.value_error(
                "item_axes",
                s.item_axes.span(),
                format!("needs {dim} semi-axes (the scene's dimension)"),
            ));
        }
        for (k, pair) in s.shapes.iter().enumerate() {
            for (key, v) in [
                ("axes_i", &pair.axes_i),
                ("axes_j", &pair.axes_j),
                ("direction", &pair.direction),
            ] {
                let key = format!("shapes[{k}].{key}");
                if v.get_ref().len() != usize::from(dim) {
                    return Err(self.value_error(
                        &key,
                        v.span(),
                        format!(
                            "has {} entries, the scene's dimension is {dim}",
                            v.get_ref().len()
                        ),
                    ));
                }
            }
            positive(&format!("shapes[{k}].axes_i"), &pair.axes_i)?;
            positive(&format!("shapes[{k}].axes_j"), &pair.axes_j)?;
            if pair.direction.get_ref().iter().all(|x| *x == 0.0) {
                return Err(self.value_error(
                    &format!("shapes[{k}].direction"),
                    pair.direction.span(),
                    "is the zero vector",
                ));
            }
        }
        Ok(())
    }

    /// `aspect_ratios`, required non-empty.
    pub fn aspect_ratios(&self) -> Result<&[f64], Error> {
        self.required("aspect_ratios", &self.scene.aspect_ratios)
    }

    /// `tolerances`, required non-empty.
    pub fn tolerances(&self) -> Result<&[f64], Error> {
        self.required("tolerances", &self.scene.tolerances)
    }

    /// `tangency_gaps`, required non-empty.
    pub fn tangency_gaps(&self) -> Result<&[f64], Error> {
        self.required("tangency_gaps", &self.scene.tangency_gaps)
    }

    fn required<'a>(&self, key: &str, v: &'a Spanned<Vec<f64>>) -> Result<&'a [f64], Error> {
        if v.get_ref().is_empty() {
            Err(self.value_error(
                key,
                v.span(),
                format!("study `{:?}` needs a non-empty list", self.scene.study),
            ))
        } else {
            Ok(v.get_ref())
        }
    }

    /// Errors unless the workload has at least one of `what`.
    pub fn require_workload(&self, quick: bool, what: &str, n: usize) -> Result<usize, Error> {
        if n == 0 {
            Err(self.value_error(
                &format!("{}.{what}", if quick { "quick" } else { "full" }),
                0..0,
                "missing or zero",
            ))
        } else {
            Ok(n)
        }
    }
}

/// All scenes of a directory, sorted by file name.
pub fn read_all(dir: &Path) -> Result<Vec<LoadedScene>, Error> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(crate::error::io(dir))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    paths.sort();
    paths.iter().map(|p| LoadedScene::read(p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<LoadedScene, Error> {
        LoadedScene::parse(Path::new("t.toml"), text.to_string())
    }

    #[test]
    fn unknown_key_names_file_key_and_line() {
        let e = parse("title = \"x\"\nstudy = \"theory\"\nsede = 3\n").unwrap_err();
        let msg = e.to_string();
        assert!(msg.starts_with("t.toml:3:"), "{msg}");
        assert!(msg.contains("sede"), "{msg}");
    }

    #[test]
    fn wrong_length_names_key_and_line() {
        let text = "title = \"x\"\nstudy = \"approach\"\n[[shapes]]\nname = \"a\"\n\
                    axes_i = [1.0, 1.0]\naxes_j = [1.0, 1.0, 1.0]\ndirection = [1.0, 0.0, 0.0]\n";
        let msg = parse(text).unwrap_err().to_string();
        assert!(msg.contains("t.toml:5"), "{msg}");
        assert!(msg.contains("shapes[0].axes_i"), "{msg}");
    }

    #[test]
    fn bad_value_is_an_error_not_a_panic() {
        let msg = parse("title = \"x\"\nstudy = \"stiff\"\naspect_ratios = [1.0, -2.0]\n")
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("t.toml:3") && msg.contains("aspect_ratios"),
            "{msg}"
        );
        let msg = parse("title = 1\nstudy = \"stiff\"\n")
            .unwrap_err()
            .to_string();
        assert!(msg.contains("t.toml:1"), "{msg}");
    }
}
