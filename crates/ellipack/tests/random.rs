//! Random packings from a scene: `packing_fraction = "jammed"` and `solver.start = "random"`
//! read and checked, a periodic cell and a ball filled at their fraction exactly, a jammed
//! cell of bidisperse discs, the same seed giving the same packing, and `ellipack analyse`.
//! The runs end by the compression's own rules (no test depends on the time limit).

mod common;
use common::{ellipack, pack_into, pack_into_with, succeeded, summary_json, temp_dir, text};
use ellipack::scene::{RandomGoal, Scene, StartName};
use std::path::Path;
use std::process::Output;

fn pack(dir: &Path, scene: &str, out: &Path) -> Output {
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    pack_into(&path, out)
}

/// Each scene text is refused with a message holding its expected part.
fn refused(cases: &[(String, &str)]) {
    for (text, expected) in cases {
        let message = Scene::from_toml_str(text, "bad.toml")
            .unwrap_err()
            .to_string();
        assert!(
            message.contains(expected),
            "{message}\nexpected: {expected}"
        );
    }
}

fn structure(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("structure.json")).unwrap()).unwrap()
}

/// 24 discs of radius 0.5 and 24 of radius 0.7 (O'Hern's 1 : 1.4 mixture) in a periodic
/// square, jammed.
const DISCS: &str = "dimension = 2\nseed = 3\n[container]\nkind = \"periodic\"\n\
                     packing_fraction = \"jammed\"\n[[shapes]]\ncount = 24\n\
                     semi_axes = [0.5, 0.5]\n[[shapes]]\ncount = 24\nsemi_axes = [0.7, 0.7]\n\
                     [solver]\ntime_limit = 600.0\nthreads = 1\n[output]\npictures = false\n";

#[test]
fn scenes_ask_for_random_packings_and_impossible_ones_are_refused() {
    let scene = Scene::from_toml_str(DISCS, "discs.toml").unwrap();
    assert_eq!(scene.solver.start, StartName::Random);
    assert!(matches!(scene.random_goal(), Some(RandomGoal::Jammed(_))));
    assert_eq!(scene.fixed_container(), None);
    let again = Scene::from_toml_str(&scene.to_toml_string(), "again.toml").unwrap();
    assert_eq!(again, scene);

    let fraction = DISCS.replace("\"jammed\"", "0.7") + "";
    let random = fraction.replace("threads = 1\n", "threads = 1\nstart = \"random\"\n");
    let scene = Scene::from_toml_str(&random, "f.toml").unwrap();
    assert!(matches!(scene.random_goal(), Some(RandomGoal::Fraction(_))));
    // Without start = "random", a fraction is filled from lattice starts.
    let lattice = Scene::from_toml_str(&fraction, "l.toml").unwrap();
    assert_eq!(lattice.random_goal(), None);

    let cases = [
        (
            DISCS.replace("\"jammed\"", "\"dense\""),
            "line 5, column 20: `container.packing_fraction`: must be a number in (0, 1) or \
             \"jammed\"",
        ),
        (
            DISCS.replace("threads = 1\n", "threads = 1\nstart = \"lattice\"\n"),
            "`solver.start`: packing_fraction = \"jammed\" is a random packing",
        ),
        (
            DISCS
                .replace("packing_fraction = \"jammed\"\n", "")
                .replace("threads = 1\n", "threads = 1\nstart = \"random\"\n"),
            "`solver.start`: a random packing needs its container",
        ),
        (
            DISCS.replace(
                "kind = \"periodic\"\n",
                "kind = \"periodic\"\ncell = \"variable\"\n",
            ),
            "`container.cell`: a variable cell has no packing_fraction",
        ),
    ];
    refused(&cases);
}

#[test]
fn bidisperse_discs_jam_certified_and_disordered_and_the_seed_repeats_them() {
    let dir = temp_dir("random-discs");
    let (a, b) = (dir.join("a"), dir.join("b"));
    let said = succeeded(&pack(&dir, DISCS, &a), "jammed discs");
    assert!(said.contains("random and jammed"), "{said}");
    succeeded(&pack(&dir, DISCS, &b), "jammed discs again");
    let csv = |p: &Path| std::fs::read_to_string(p.join("packing.csv")).unwrap();
    assert_eq!(csv(&a), csv(&b), "the same seed gave another packing");
    let verified = succeeded(
        &ellipack().arg("verify").arg(&a).output().unwrap(),
        "verify",
    );
    assert!(verified.contains("0 overlapping pairs"), "{verified}");
    let s = structure(&a);
    let density = s["density"].as_f64().unwrap();
    // Random close packing of this mixture is about 0.84 (O'Hern et al. 2003); 48 discs
    // jam a little below it, and well below the crystal's 0.9069.
    assert!(density > 0.78 && density < 0.88, "{density}");
    assert!(s["bond_order"]["psi6"].as_f64().unwrap() < 0.5);
    assert!(s["contacts"]["mean_contacts"].as_f64().unwrap() > 3.0);
    assert_eq!(summary_json(&a)["density"].as_f64().unwrap(), density);
}

#[test]
fn a_periodic_cube_and_a_ball_are_filled_at_their_fraction_exactly() {
    let dir = temp_dir("random-fraction");
    let cube = "dimension = 3\nseed = 2\n[container]\nkind = \"periodic\"\n\
                packing_fraction = 0.55\n[[shapes]]\ncount = 40\nsemi_axes = [1.0, 0.75, 0.5]\n\
                [solver]\ntime_limit = 600.0\nthreads = 1\nstart = \"random\"\n\
                [output]\npictures = false\n";
    let ball = "dimension = 2\nseed = 2\n[container]\nkind = \"circle\"\nradius = 9.0\n\
                [[shapes]]\ncount = 40\nsemi_axes = [1.2, 0.8]\n[solver]\ntime_limit = 600.0\n\
                threads = 1\nstart = \"random\"\n[output]\npictures = false\n";
    for (name, scene, density) in [
        ("cube", cube, 0.55),
        ("ball", ball, 40.0 * 1.2 * 0.8 / 81.0),
    ] {
        let out = dir.join(name);
        succeeded(&pack(&dir, scene, &out), name);
        let summary = summary_json(&out);
        let found = summary["density"].as_f64().unwrap();
        assert!((found - density).abs() < 1e-12, "{name}: {found}");
        let verified = succeeded(&ellipack().arg("verify").arg(&out).output().unwrap(), name);
        assert!(verified.contains("0 overlapping pairs"), "{verified}");
        assert!(out.join("structure.json").exists() && out.join("rdf.csv").exists());
    }
    let radius = summary_json(&dir.join("ball"))["container"]["radius"].clone();
    assert_eq!(radius.as_f64(), Some(9.0));
}

#[test]
fn analyse_writes_the_structure_of_any_folder_and_refuses_bad_settings() {
    let dir = temp_dir("random-analyse");
    let out = dir.join("out");
    succeeded(&pack(&dir, DISCS, &out), "discs");
    std::fs::remove_file(out.join("structure.json")).unwrap();
    let o = ellipack()
        .args(["analyse", "--bond-cutoff", "1.7"])
        .arg(&out)
        .output()
        .unwrap();
    let said = succeeded(&o, "analyse");
    assert!(said.contains("hexatic (bonds < 1.7000"), "{said}");
    assert_eq!(structure(&out)["bond_order"]["cutoff"].as_f64(), Some(1.7));
    let rdf = std::fs::read_to_string(out.join("rdf.csv")).unwrap();
    assert!(rdf.starts_with("r,g\n") && rdf.lines().count() == 201);
    for picture in ["rdf.svg", "orientations.svg"] {
        let svg = std::fs::read_to_string(out.join(picture)).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("48"), "{picture}");
    }
    let bad = ellipack()
        .args(["analyse", "--gap=-1"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(1));
    assert!(
        text(&bad.stderr).contains("contact gap"),
        "{}",
        text(&bad.stderr)
    );
}

/// Ellipses with lognormal sizes and uniform aspects, aligned along x, jammed in a square cell.
const POLY: &str = "dimension = 2\nseed = 4\n[container]\nkind = \"periodic\"\n\
                    packing_fraction = \"jammed\"\n[[shapes]]\ncount = 40\n\
                    semi_axes = [1.0, 0.5]\n\
                    size = { distribution = \"lognormal\", sigma = 0.3, min = 0.5, max = 2.0 }\n\
                    aspect = { distribution = \"uniform\", min = 1.0, max = 2.0 }\n\
                    orientation = { axis = [1.0, 0.0], concentration = 30.0 }\n\
                    [solver]\ntime_limit = 600.0\nthreads = 1\n[output]\npictures = false\n";

#[test]
fn polydisperse_groups_are_drawn_once_from_the_seed_and_written_back() {
    let scene = Scene::from_toml_str(POLY, "poly.toml").unwrap();
    let items = scene.item_semi_axes();
    assert_eq!(items.len(), 40);
    assert_eq!(items, scene.item_semi_axes(), "drawn again differently");
    for l in &items {
        let size = (l[0] * l[1] / 0.5).sqrt();
        let aspect = l[0] / l[1] / 2.0;
        assert!((0.5..=2.0).contains(&size), "{size}");
        assert!((1.0 - 1e-12..=2.0 + 1e-12).contains(&aspect), "{aspect}");
    }
    assert!(items.iter().any(|l| (l[0] - items[0][0]).abs() > 1e-3));
    let again = Scene::from_toml_str(&scene.to_toml_string(), "again.toml").unwrap();
    assert_eq!(again, scene);
    assert_eq!(again.item_semi_axes(), items);
    let other = Scene::from_toml_str(&POLY.replace("seed = 4", "seed = 5"), "o.toml").unwrap();
    assert_ne!(other.item_semi_axes(), items);
    assert!(
        scene.title().contains("distributed sizes"),
        "{}",
        scene.title()
    );
}

#[test]
fn impossible_distributions_orientations_and_item_files_are_refused_by_key_and_line() {
    let cases = [
        (
            POLY.replace("\"lognormal\", sigma = 0.3,", "\"gamma\","),
            "line 9, column 8: `shapes[0].size`: distribution must be \"lognormal\", \"normal\" \
             or \"uniform\", not \"gamma\"",
        ),
        (
            POLY.replace("sigma = 0.3, ", ""),
            "`shapes[0].size`: a lognormal distribution needs sigma",
        ),
        (
            POLY.replace("min = 1.0, max = 2.0", "min = 3.0, max = 2.0"),
            "line 10, column 10: `shapes[0].aspect`: the bounds must be positive and finite with \
             min ≤ max",
        ),
        (
            POLY.replace("axis = [1.0, 0.0]", "axis = [1.0, 0.0, 0.0]"),
            "`shapes[0].orientation`: axis must be 2 finite values, not all zero",
        ),
        (
            POLY.replace("packing_fraction = \"jammed\"", "packing_fraction = 0.5"),
            "`shapes[0].orientation`: orientations are drawn in random starts",
        ),
        (
            POLY.replace("count = 40\n", "count = 40\nfile = \"items.csv\"\n"),
            "`shapes[0].count`: a group read from a file has no count",
        ),
        (
            "dimension = 2\n[container]\nkind = \"circle\"\n[[shapes]]\ncount = 1\n".into(),
            "line 4, column 1: `shapes[0].semi_axes`: missing field `semi_axes`",
        ),
    ];
    refused(&cases);
}

#[test]
fn item_files_give_each_item_and_their_errors_name_file_line_and_column() {
    let dir = temp_dir("random-items");
    let scene_path = dir.join("scene.toml");
    let scene = "dimension = 3\nseed = 1\n[container]\nkind = \"periodic\"\n\
                 packing_fraction = \"jammed\"\n[[shapes]]\nfile = \"items.csv\"\n\
                 [[shapes]]\ncount = 10\nsemi_axes = [0.5, 0.5, 0.5]\n\
                 [solver]\ntime_limit = 600.0\nthreads = 1\n[output]\npictures = false\n";
    std::fs::write(&scene_path, scene).unwrap();
    let mut rows = String::from("id,a,b,c,qw,qx,qy,qz\n");
    for i in 0..20 {
        let a = 1.0 + 0.02 * i as f64;
        rows.push_str(&format!("{i},{a},0.7,0.5,1,0,0,0\n"));
    }
    std::fs::write(dir.join("items.csv"), &rows).unwrap();
    let read = Scene::from_file(&scene_path).unwrap();
    assert_eq!(read.item_count(), 30);
    let items = read.item_semi_axes();
    assert_eq!(items[19], vec![1.38, 0.7, 0.5]);
    assert_eq!(items[20], vec![0.5, 0.5, 0.5]);
    let out = dir.join("out");
    let said = succeeded(&pack_into(&scene_path, &out), "items from a file");
    assert!(said.contains("0 overlapping pairs"), "{said}");
    let packed = std::fs::read_to_string(out.join("packing.csv")).unwrap();
    let row: Vec<f64> = packed
        .lines()
        .nth(20)
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert_eq!(&row[4..7], &[1.38, 0.7, 0.5], "{row:?}");

    std::fs::write(dir.join("items.csv"), "a,b,c\n1,0.5,0.5\n1,x,0.5\n").unwrap();
    let message = Scene::from_file(&scene_path).unwrap_err().to_string();
    assert!(
        message.contains("items.csv: line 3, column 1: `b`: \"x\" is not a finite number"),
        "{message}"
    );
    std::fs::write(dir.join("items.csv"), "a,b\n1,0.5\n").unwrap();
    let message = Scene::from_file(&scene_path).unwrap_err().to_string();
    assert!(message.contains("no column `c`"), "{message}");
    std::fs::remove_file(dir.join("items.csv")).unwrap();
    let message = Scene::from_file(&scene_path).unwrap_err().to_string();
    assert!(
        message.contains("line 7, column 8: `shapes[0].file`: ") && message.contains("items.csv"),
        "{message}"
    );
}

/// Items that turn freely lose most of their start's order as they jam; items whose
/// orientation is fixed keep it (S₂ ≈ 0.98 for κ = 30).
#[test]
fn polydisperse_aligned_ellipses_jam_certified_and_fixed_ones_keep_their_order() {
    let dir = temp_dir("random-poly");
    let fixed = POLY.replace(
        "concentration = 30.0 }",
        "concentration = 30.0, fixed = true }",
    );
    let mut orders = Vec::new();
    for (name, scene) in [("free", POLY.to_string()), ("fixed", fixed)] {
        let out = dir.join(name);
        succeeded(&pack(&dir, &scene, &out), name);
        let verified = succeeded(&ellipack().arg("verify").arg(&out).output().unwrap(), name);
        assert!(verified.contains("0 overlapping pairs"), "{verified}");
        let s = structure(&out);
        orders.push(s["nematic"][0]["order"].as_f64().unwrap());
        if name == "fixed" {
            assert!(s["nematic"][0]["director"][0].as_f64().unwrap() > 0.99);
        }
    }
    assert!(orders[1] > 0.95, "{orders:?}");
    assert!(orders[1] > orders[0], "{orders:?}");
}

/// The scenes of docs/random.md's table parse and ask for random packings.
/// Kanapy's documented example (`validation/peers/kanapy`: 86 grains of lognormal sizes and
/// aspect ratios up to 3.2 in a periodic 40³ box at its fill fraction 0.64389): Kanapy's
/// own packing overlaps (199 pairs by `verify`), and the same items pack certified at that
/// fraction, in the same box.
#[test]
fn kanapys_example_items_pack_certified_at_its_fill_fraction() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../validation/peers/kanapy");
    let dir = temp_dir("random-kanapy");
    let out = dir.join("out");
    succeeded(
        &pack_into_with(&folder.join("scene.toml"), &out, &["--threads", "1"]),
        "kanapy scene: ",
    );
    let summary = summary_json(&out);
    assert_eq!(summary["items"].as_u64(), Some(86));
    let found = summary["density"].as_f64().unwrap();
    assert!((found - 0.6438889950839803).abs() < 1e-12, "{found}");
    let lengths = summary["container"]["lengths"].as_array().unwrap();
    assert!(
        lengths
            .iter()
            .all(|l| (l.as_f64().unwrap() - 40.0).abs() < 1e-9)
    );
    let verified = succeeded(
        &ellipack().arg("verify").arg(&out).output().unwrap(),
        "verify",
    );
    assert!(verified.contains("0 overlapping pairs"), "{verified}");
    let theirs = ellipack()
        .arg("verify")
        .arg(folder.join("kanapy-packing.csv"))
        .args(["--container", "periodic", "--size", "40,40,40"])
        .output()
        .unwrap();
    assert!(!theirs.status.success());
    assert!(text(&theirs.stdout).contains("199 overlapping pairs"));
}

#[test]
fn the_study_scenes_are_random_packings() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../validation/random");
    let mut count = 0;
    for entry in std::fs::read_dir(&folder).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let scene = Scene::from_file(&path).unwrap();
            assert!(scene.random_goal().is_some(), "{}", path.display());
            count += 1;
        }
    }
    assert!(count >= 5, "{count} scenes");
}

/// A jammed run resumed from its own folder compresses no worse; one whose scene asks for
/// another container kind is refused with nothing written.
#[test]
fn a_jammed_run_resumes_from_its_packing_and_refuses_another_container() {
    let dir = temp_dir("random-resume");
    let out = dir.join("out");
    succeeded(&pack(&dir, DISCS, &out), "discs");
    let before = summary_json(&out)["density"].as_f64().unwrap();
    let path = dir.join("scene.toml");
    let resumed = pack_into_with(&path, &out, &["--resume"]);
    succeeded(&resumed, "resumed");
    let after = summary_json(&out)["density"].as_f64().unwrap();
    assert!(after >= before, "{after} < {before}");
    std::fs::write(
        &path,
        DISCS.replace("kind = \"periodic\"", "kind = \"rectangle\""),
    )
    .unwrap();
    let refused = pack_into_with(&path, &out, &["--resume"]);
    assert_eq!(refused.status.code(), Some(1), "{}", text(&refused.stderr));
    assert!(
        text(&refused.stderr).contains("container"),
        "{}",
        text(&refused.stderr)
    );
    assert_eq!(summary_json(&out)["density"].as_f64().unwrap(), after);
}
