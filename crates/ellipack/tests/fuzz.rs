//! Every parser of the command line (and the LAMMPS data file reader) fed random bytes and mutated valid files: byte flips,
//! truncation, duplicated lines and columns, extreme and non-finite numbers, odd unicode. No
//! input may panic, and every error must say something.
//!
//! The seed is fixed, so a run is reproducible; `PROPTEST_CASES` sets the number of cases
//! (256 by default; `cargo xtask fuzz --cases N` runs many more in release mode).

mod common;

use ellipack::pairs::{Criterion, PAIR_COLUMNS_2D, contact_stream, evaluate, read_pairs};
use ellipack::scene::Scene;
use ellipack::{export, measure, packing};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

fn config() -> Config {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|c| c.parse().ok())
        .unwrap_or(256);
    Config {
        cases,
        rng_seed: RngSeed::Fixed(0x00e1_1195_ac00),
        failure_persistence: None,
        ..Config::default()
    }
}

/// Numbers and words that parsers find hard.
const SPECIALS: &[&str] = &[
    "1e308",
    "-1.7976931348623157e308",
    "1e400",
    "4.9e-324",
    "1e-320",
    "-0",
    "0",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "Infinity",
    "18446744073709551616",
    "-9223372036854775809",
    "99999999999999999999999999999999",
    "0x10",
    "1_000",
    "",
    " ",
    "\"",
    "\"\"",
    ",",
    "\u{feff}",
    "\u{202e}1",
    "é",
    "𝔁",
    "\u{0}",
    "\r",
    "[",
    "{",
    "=",
];

#[derive(Clone, Debug)]
enum Mutation {
    FlipBit { at: usize, bit: u8 },
    Truncate { at: usize },
    DuplicateLine { line: usize },
    DeleteLine { line: usize },
    DuplicateField { line: usize, field: usize },
    ReplaceNumber { nth: usize, with: usize },
    Insert { at: usize, text: String },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        (any::<usize>(), 0u8..8).prop_map(|(at, bit)| Mutation::FlipBit { at, bit }),
        any::<usize>().prop_map(|at| Mutation::Truncate { at }),
        any::<usize>().prop_map(|line| Mutation::DuplicateLine { line }),
        any::<usize>().prop_map(|line| Mutation::DeleteLine { line }),
        (0usize..3, any::<usize>())
            .prop_map(|(line, field)| Mutation::DuplicateField { line, field }),
        (any::<usize>(), any::<usize>())
            .prop_map(|(nth, with)| Mutation::ReplaceNumber { nth, with }),
        (
            any::<usize>(),
            proptest::collection::vec(any::<char>(), 0..6)
        )
            .prop_map(|(at, chars)| Mutation::Insert {
                at,
                text: chars.into_iter().collect()
            }),
    ]
}

fn lines(bytes: &[u8]) -> Vec<Vec<u8>> {
    bytes.split(|b| *b == b'\n').map(<[u8]>::to_vec).collect()
}

fn apply(base: &[u8], mutations: &[Mutation]) -> Vec<u8> {
    let mut bytes = base.to_vec();
    for m in mutations {
        match m {
            Mutation::FlipBit { at, bit } => {
                if !bytes.is_empty() {
                    let at = at % bytes.len();
                    bytes[at] ^= 1 << bit;
                }
            }
            Mutation::Truncate { at } => bytes.truncate(at % (bytes.len() + 1)),
            Mutation::DuplicateLine { line } | Mutation::DeleteLine { line } => {
                let mut ls = lines(&bytes);
                let i = line % ls.len();
                if matches!(m, Mutation::DuplicateLine { .. }) {
                    ls.insert(i, ls[i].clone());
                } else {
                    ls.remove(i);
                }
                bytes = ls.join(&b'\n');
            }
            Mutation::DuplicateField { line, field } => {
                let mut ls = lines(&bytes);
                let i = line % ls.len();
                let mut fields: Vec<Vec<u8>> =
                    ls[i].split(|b| *b == b',').map(<[u8]>::to_vec).collect();
                let k = field % fields.len();
                fields.insert(k, fields[k].clone());
                ls[i] = fields.join(&b',');
                bytes = ls.join(&b'\n');
            }
            Mutation::ReplaceNumber { nth, with } => {
                let starts: Vec<usize> = (0..bytes.len())
                    .filter(|&i| {
                        bytes[i].is_ascii_digit() && (i == 0 || !bytes[i - 1].is_ascii_digit())
                    })
                    .collect();
                if !starts.is_empty() {
                    let start = starts[nth % starts.len()];
                    let end = (start..bytes.len())
                        .find(|&i| !(bytes[i].is_ascii_digit() || b".eE-+".contains(&bytes[i])))
                        .unwrap_or(bytes.len());
                    let special = SPECIALS[with % SPECIALS.len()].as_bytes();
                    bytes.splice(start..end, special.iter().copied());
                }
            }
            Mutation::Insert { at, text } => {
                let at = at % (bytes.len() + 1);
                bytes.splice(at..at, text.bytes());
            }
        }
    }
    bytes
}

/// A valid file and a few mutations of it, or plain random bytes, or random CSV-like text
/// under the file's own header (so that the row parsers are reached).
fn input(base: &'static str) -> impl Strategy<Value = Vec<u8>> {
    let header = base.lines().next().unwrap_or("").to_string();
    prop_oneof![
        3 => proptest::collection::vec(mutation(), 0..5)
            .prop_map(move |ms| apply(base.as_bytes(), &ms)),
        1 => proptest::collection::vec(any::<u8>(), 0..300),
        1 => proptest::collection::vec(
            proptest::sample::select(vec!["0", "1", "-2.5", "e", "1e300", ",", "\n", "\"", " ", "x", "NaN", "é"]),
            0..80,
        )
        .prop_map(move |parts| format!("{header}\n{}", parts.concat()).into_bytes()),
    ]
}

fn says_something(e: &dyn std::error::Error) {
    let message = e.to_string();
    assert!(
        !message.trim().is_empty(),
        "an error without a message: {e:?}"
    );
}

fn check_pairs(bytes: &[u8]) {
    for criterion in [Criterion::Contact, Criterion::Overlap] {
        let mut out = Vec::new();
        match contact_stream(bytes, "fuzz.csv", criterion, &mut out, "out") {
            Ok(summary) => {
                assert!(
                    String::from_utf8(out.clone()).is_ok(),
                    "the output is UTF-8"
                );
                assert_eq!(records(&out), summary.rows, "one output row per input row");
                assert!(summary.failed <= summary.rows);
            }
            Err(e) => says_something(&e),
        }
    }
    let text = String::from_utf8_lossy(bytes);
    match read_pairs(&text, "fuzz.csv") {
        Ok(table) => {
            let (out, failed) = evaluate(&table, Criterion::Contact);
            assert!(failed <= table.rows.len());
            assert_eq!(records(out.as_bytes()), table.rows.len());
        }
        Err(e) => says_something(&e),
    }
}

/// The data rows of a table we wrote, read back as CSV (a quoted field may hold a newline).
fn records(table: &[u8]) -> usize {
    let mut reader = csv::Reader::from_reader(table);
    let mut n = 0;
    for record in reader.records() {
        assert!(record.is_ok(), "our output is valid CSV: {record:?}");
        n += 1;
    }
    n
}

fn check_measure(bytes: &[u8]) {
    let mut out = Vec::new();
    match measure::measure_stream(bytes, "fuzz.csv", &mut out, "out") {
        Ok(summary) => {
            assert!(summary.failed <= summary.rows);
            assert!(String::from_utf8(out.clone()).is_ok());
            assert_eq!(records(&out), summary.rows);
        }
        Err(e) => says_something(&e),
    }
}

/// An input refused is refused in words: `read` of `bytes`, as text (lossily), named `name`.
fn read_says_something<T, E: std::error::Error>(
    bytes: &[u8],
    name: &str,
    read: fn(&str, &str) -> Result<T, E>,
) {
    if let Err(e) = read(&String::from_utf8_lossy(bytes), name) {
        says_something(&e);
    }
}

/// A scene read or refused in words; one that is read gives its container, its items and its
/// random goal without a panic, and reads back from its own TOML to the same scene.
fn check_scene(bytes: &[u8]) {
    match Scene::from_toml_str(&String::from_utf8_lossy(bytes), "fuzz.toml") {
        Err(e) => says_something(&e),
        Ok(scene) => {
            let _ = scene.fixed_container();
            let _ = scene.random_goal();
            assert_eq!(scene.item_semi_axes().len(), scene.item_count());
            let again = Scene::from_toml_str(&scene.to_toml_string(), "again.toml").unwrap();
            assert_eq!(again, scene);
        }
    }
}

#[test]
fn the_base_scenes_are_read() {
    for text in [
        PERIODIC_FIXED_SCENE,
        PERIODIC_VARIABLE_SCENE,
        FIXED_SCENE,
        RANDOM_SCENE,
    ] {
        Scene::from_toml_str(text, "base.toml").unwrap();
    }
}

fn check_packing_csv(bytes: &[u8]) {
    read_says_something(bytes, "packing.csv", ellipack::items_csv::read_csv);
}

fn check_summary(bytes: &[u8]) {
    read_says_something(bytes, "summary.json", ellipack::summary_json::read_summary);
}

fn check_xyz(bytes: &[u8]) {
    read_says_something(bytes, "packing.xyz", ellipack::xyz::read_xyz);
}

fn check_lammps(bytes: &[u8]) {
    read_says_something(bytes, "packing.data", ellipack::lammps::read_lammps_data);
}

fn lammps_text(p: &packing::Packing) -> String {
    ellipack::lammps::lammps_data(p, &export::Cell::enclosing(p))
}

/// A fixed periodic cell given by its lengths, with a second key that conflicts when a
/// mutation duplicates a line.
const PERIODIC_FIXED_SCENE: &str = "dimension = 3\nseed = 7\n[container]\nkind = \"periodic\"\n\
                                    cell = \"fixed\"\nlengths = [10.0, 12.0, 9.0]\n[[shapes]]\n\
                                    count = 16\nsemi_axes = [1.0, 0.75, 0.5]\n[solver]\n\
                                    time_limit = 5.0\nthreads = 1\n[output]\npictures = false\n";

/// A variable periodic cell of ellipses.
const PERIODIC_VARIABLE_SCENE: &str = "dimension = 2\n[container]\nkind = \"periodic\"\n\
                                       cell = \"variable\"\n[[shapes]]\ncount = 4\n\
                                       semi_axes = [2.0, 1.0]\n[solver]\n\
                                       local_minimisations = 3\n";

/// Fixed containers of every kind of size key: radius, semi-axes, half sides and a fraction.
const FIXED_SCENE: &str = "dimension = 3\n[container]\nkind = \"ball\"\nradius = 6.0\n\
                           [[shapes]]\ncount = 10\nsemi_axes = [1.0, 1.0, 1.0]\n[[shapes]]\n\
                           count = 3\nsemi_axes = [2.0, 0.5, 0.5]\n[solver]\ntime_limit = 2.0\n\
                           # semi_axes = [3.0, 4.0, 5.0]\n# half_sides = [4.0, 4.0, 4.0]\n\
                           # packing_fraction = 0.45\n";

/// A random packing: distributions, an orientation and the jammed target.
const RANDOM_SCENE: &str = "dimension = 3\nseed = 3\n[container]\nkind = \"periodic\"\n\
                            packing_fraction = \"jammed\"\n[[shapes]]\ncount = 50\n\
                            semi_axes = [1.0, 0.75, 0.5]\n\
                            size = { distribution = \"lognormal\", sigma = 0.2, min = 0.5, max = 2.0 }\n\
                            aspect = { distribution = \"uniform\", min = 1.0, max = 2.0 }\n\
                            orientation = { axis = [0.0, 0.0, 1.0], concentration = 4.0 }\n\
                            [solver]\nstart = \"random\"\n";

const PAIRS_2D: &str = "case_id,r12_x,r12_y,q1_0,q1_1,q1_2,q2_0,q2_1,q2_2\n\
                        apart,3,0,1,0,1,1,0,1\n\
                        close,1,0.5,4,1,1,1,0,1\n\
                        bad,1,0,1,2,1,1,0,1\n";

const MEASURE_2D: &str = "case_id,cix,ciy,ai,bi,theta_i,cjx,cjy,aj,bj,theta_j\n\
                          a,0,0,1,1,0,3,0,1,1,0\n\
                          b,0,0,2,1,0.3,1,1,1,0.5,1.2\n";

const MEASURE_3D: &str = "case_id,cix,ciy,ciz,ai,bi,ci_ax,qwi,qxi,qyi,qzi,cjx,cjy,cjz,aj,bj,cj_ax,qwj,qxj,qyj,qzj\n\
                          a,0,0,0,1,1,1,1,0,0,0,3,0,0,1,1,1,1,0,0,0\n\
                          b,0,0,0,2,1,0.5,0.5,0.5,0.5,0.5,1,1,0,1,0.7,0.4,1,0,0,0\n";

const SUMMARY: &str = r#"{
  "container": { "kind": "ellipse", "center": [0.0, 0.0], "semi_axes": [9.1, 7.5] },
  "items": 30,
  "density": 0.8790,
  "objective": 214.4,
  "wall_seconds": 12.5,
  "local_minimisations": 17,
  "certificate": { "overlapping_pairs": 0, "containment_violations": 0, "min_mu2": 1.0000003 },
  "repair": { "dilation": 1.0001, "density_before": 0.88 }
}"#;

/// Valid files written by the library itself, leaked so that strategies can hold them.
fn leak(text: String) -> &'static str {
    Box::leak(text.into_boxed_str())
}

#[test]
fn the_2d_base_file_is_a_2d_file() {
    assert_eq!(
        PAIRS_2D.lines().next().map(|h| h.split(',').count()),
        Some(PAIR_COLUMNS_2D.len() + 1)
    );
    assert!(read_pairs(PAIRS_2D, "b").is_ok());
    assert!(measure::measure(MEASURE_2D, "b").is_ok());
    assert!(measure::measure(MEASURE_3D, "b").is_ok());
    assert!(ellipack::summary_json::read_summary(SUMMARY, "b").is_ok());
}

/// One proptest a line: `name(base) => check` runs `check` on inputs made from the valid text
/// `base` by [`input`], with the cases and seed of [`config`].
macro_rules! fuzz_tests {
    ($($name:ident($base:expr) => $check:ident;)*) => {
        proptest! {
            #![proptest_config(config())]
            $(
                #[test]
                fn $name(bytes in input($base)) {
                    $check(&bytes);
                }
            )*
        }
    };
}

fuzz_tests! {
    pairs_3d(ellipack::EXAMPLE_PAIRS) => check_pairs;
    pairs_2d(PAIRS_2D) => check_pairs;
    measure_2d(MEASURE_2D) => check_measure;
    measure_3d(MEASURE_3D) => check_measure;
    scene(ellipack::scene::DEFAULT_SCENE) => check_scene;
    scene_periodic_fixed(PERIODIC_FIXED_SCENE) => check_scene;
    scene_periodic_variable(PERIODIC_VARIABLE_SCENE) => check_scene;
    scene_fixed_containers(FIXED_SCENE) => check_scene;
    scene_random(RANDOM_SCENE) => check_scene;
    packing_csv_2d(leak(ellipack::items_csv::csv_string(common::ellipses(2, true, 1).items())))
        => check_packing_csv;
    packing_csv_3d(leak(ellipack::items_csv::csv_string(common::ellipsoids(2, true, 2).items())))
        => check_packing_csv;
    summary_json(SUMMARY) => check_summary;
    packing_xyz_2d(leak(ellipack::xyz::xyz_string(&common::ellipses(2, true, 3)))) => check_xyz;
    packing_xyz_3d(leak(ellipack::xyz::xyz_string(&common::ellipsoids(2, false, 4))))
        => check_xyz;
    packing_data_2d(leak(lammps_text(&common::ellipses(2, true, 5)))) => check_lammps;
    packing_data_3d(leak(lammps_text(&common::ellipsoids(2, false, 6)))) => check_lammps;
}
