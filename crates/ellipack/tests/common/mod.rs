//! Small packings for the tests: lattices that do not overlap, with varied orientations, so
//! that round trips and pictures exercise every column.

#![allow(dead_code)]

use ellipack::packing::Centred;
use ellipack::packing::{CertificateCounts, Container, Item, Items, Packing, Summary};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use testkit::Rng;

/// The files a run writes beside packing.csv and summary.json: for other programs and for
/// the eye.
pub const EXPORTS_AND_PICTURES: [&str; 6] = [
    "packing.xyz",
    "packing.data",
    "packing.gsd",
    "container.obj",
    "packing.svg",
    "packing.png",
];

/// Each container filled with the items of its dimension: those of `e2` or of `e3`.
pub fn filled(
    containers: impl IntoIterator<Item = Container>,
    e2: &Packing,
    e3: &Packing,
) -> Vec<Packing> {
    containers
        .into_iter()
        .map(|c| {
            let items = if c.dimension() == 2 {
                e2.items().clone()
            } else {
                e3.items().clone()
            };
            Packing::new(c, items).unwrap()
        })
        .collect()
}

/// The summary of a certified run of `p`: one local minimisation taking a second, the
/// closest pair at μ² = 1.5.
pub fn certified_summary(p: &Packing) -> Summary {
    Summary::new(
        p,
        p.container().measure(),
        1.0,
        1,
        CertificateCounts {
            overlapping_pairs: 0,
            containment_violations: 0,
            min_mu2: Some(1.5),
        },
    )
}

/// Ellipses (2, 1) (or of varied sizes when `mixed`) on a lattice of 4.2 × 4.2 cells, each
/// rotated freely (a (2, 1) ellipse fits in its cell whatever its angle), inside an ellipse
/// that holds every cell.
pub fn ellipses(n_side: usize, mixed: bool, seed: u64) -> Packing {
    let mut rng = Rng::new(seed);
    let mut items = Vec::new();
    let step = 4.2;
    let half = (n_side as f64 - 1.0) / 2.0;
    for i in 0..n_side {
        for j in 0..n_side {
            let (a, b) = if mixed {
                let a = rng.range(0.6, 2.0);
                (a, rng.range(0.3, a))
            } else {
                (2.0, 1.0)
            };
            items.push(Item::ellipse(
                [(i as f64 - half) * step, (j as f64 - half) * step],
                [a, b],
                rng.range(-3.2, 3.2),
            ));
        }
    }
    // Cells reach half·step + 2.1 from the centre along each axis; an ellipse with semi-axes
    // √2 times that holds the bounding square.
    let reach = (half * step + 2.1) * std::f64::consts::SQRT_2;
    let container = Container::plane(
        [0.0, 0.0],
        Centred::Ellipsoid {
            semi_axes: [reach * 1.05, reach],
        },
    );
    Packing::new(container, Items::Ellipses(items)).unwrap()
}

/// Ellipsoids (1, 0.75, 0.5) on a cubic lattice of spacing 2.05 (each fits in its cell
/// whatever its orientation), randomly oriented, inside a ball or cuboid holding every cell.
pub fn ellipsoids(n_side: usize, ball: bool, seed: u64) -> Packing {
    let mut rng = Rng::new(seed);
    let step = 2.05;
    let half = (n_side as f64 - 1.0) / 2.0;
    let mut items = Vec::new();
    for i in 0..n_side {
        for j in 0..n_side {
            for k in 0..n_side {
                let q = [
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                ];
                let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                items.push(Item::ellipsoid(
                    [
                        (i as f64 - half) * step,
                        (j as f64 - half) * step,
                        (k as f64 - half) * step,
                    ],
                    [1.0, 0.75, 0.5],
                    q.map(|x| x / norm),
                ));
            }
        }
    }
    let reach = half * step + 1.03;
    let container = if ball {
        Container::space(
            [0.0, 0.0, 0.0],
            Centred::Ball {
                radius: reach * 3f64.sqrt(),
            },
        )
    } else {
        Container::space(
            [0.0, 0.0, 0.0],
            Centred::Box {
                half_sides: [reach, reach, reach],
            },
        )
    };
    Packing::new(container, Items::Ellipsoids(items)).unwrap()
}

/// A fresh directory for one test, removed with all it holds when dropped (also when the test
/// fails).
pub struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TempDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for TempDir {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fresh directory for one test.
pub fn temp_dir(name: &str) -> TempDir {
    let dir = std::env::temp_dir().join(format!("ellipack-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempDir(dir)
}

/// The `ellipack` binary built for these tests.
pub fn ellipack() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ellipack"))
}

/// `ellipack <args>`, run to its end.
pub fn run(args: &[&str]) -> Output {
    ellipack().args(args).output().unwrap()
}

/// A fresh test folder `name` holding `file` with `text`: (the folder, the file).
pub fn folder_with(name: &str, file: &str, text: impl AsRef<[u8]>) -> (TempDir, PathBuf) {
    let dir = temp_dir(name);
    let path = dir.join(file);
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

/// A fresh test folder `name` holding a hand-made packing: `packing.csv` with the text `csv`
/// and `summary.json` with the text `summary`.
pub fn packing_folder(name: &str, csv: &str, summary: &str) -> TempDir {
    let dir = temp_dir(name);
    std::fs::write(dir.join("packing.csv"), csv).unwrap();
    std::fs::write(dir.join("summary.json"), summary).unwrap();
    dir
}

/// `ellipack verify <packing> --container periodic --size <size>`, run to its end.
pub fn verify_periodic(packing: &Path, size: &str) -> Output {
    ellipack()
        .arg("verify")
        .arg(packing)
        .args(["--container", "periodic", "--size", size])
        .output()
        .unwrap()
}

/// The names in `dir`, sorted, so that tests can compare a folder's whole listing.
pub fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// A process's output as text; lossy, because a failing test should show what it got.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The process's output as text, which must be UTF-8.
pub fn utf8(bytes: Vec<u8>) -> String {
    String::from_utf8(bytes).unwrap()
}

/// `ellipack <args> --input <input>`, run to its end.
pub fn on_input(args: &[&str], input: &Path) -> Output {
    ellipack()
        .args(args)
        .arg("--input")
        .arg(input)
        .output()
        .unwrap()
}

/// `ellipack pack <scene> --out <out>`, run to its end.
pub fn pack_into(scene: &Path, out: &Path) -> Output {
    pack_into_with(scene, out, &[])
}

/// `ellipack pack <scene> --out <out> <extra>`, run to its end.
pub fn pack_into_with(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    ellipack()
        .arg("pack")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

/// The summary.json of the run folder `out`.
pub fn summary_json(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// Asserts that the process exited with status 0, showing `context`, its standard output
/// and its standard error otherwise, and returns its standard output.
pub fn succeeded(output: &Output, context: &str) -> String {
    let stdout = text(&output.stdout);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{context}{stdout}{}",
        text(&output.stderr)
    );
    stdout
}

/// Asserts that the process succeeded, showing its standard error otherwise.
pub fn assert_success(output: &Output) {
    assert!(output.status.success(), "{}", text(&output.stderr));
}

/// Asserts that the process failed with status 1 (the command failed) and returns its
/// standard error.
pub fn refused(output: &Output) -> String {
    let stderr = text(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    stderr
}

/// Whether `path` is itself a symbolic link (not what it points to).
pub fn is_symlink(path: &Path) -> bool {
    std::fs::symlink_metadata(path)
        .unwrap()
        .file_type()
        .is_symlink()
}
