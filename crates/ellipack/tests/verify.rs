//! `ellipack verify` end to end: it names the offending items by their `id`, says by how much
//! an item sticks out, and checks a hand-made packing with only a container.

use ellipack::packing::Centred;
use std::path::Path;

mod common;
use common::{TempDir, ellipack, packing_folder, temp_dir, utf8};

fn verify(args: &[&str], dir: &Path) -> (bool, String, String) {
    let out = ellipack()
        .arg("verify")
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    (out.status.success(), utf8(out.stdout), utf8(out.stderr))
}

/// `ellipack verify packing.csv --container <kind> --size <size>` in `dir`.
fn verify_packing(dir: &Path, kind: &str, size: &str) -> (bool, String, String) {
    verify(&["packing.csv", "--container", kind, "--size", size], dir)
}

/// A fresh test folder holding `packing.csv` with the text `csv`.
fn folder_with_packing(name: &str, csv: &str) -> TempDir {
    let dir = temp_dir(name);
    std::fs::write(dir.join("packing.csv"), csv).unwrap();
    dir
}

/// Unit discs with ids that are not their row numbers: 10 and 7 overlap (centres 1.5 apart:
/// μ² = (1.5 / 2)² = 0.5625), 7 reaches 2.5 from the centre and 3 reaches 5√2 + 1.
const DISCS: &str = "id,x,y,a,b,theta\n10,0,0,1,1,0\n7,1.5,0,1,1,0\n3,5,5,1,1,0\n";

#[test]
fn verify_names_overlapping_pairs_and_items_outside_by_id() {
    let dir = folder_with_packing("names", DISCS);
    let (ok, text, err) = verify_packing(&dir, "circle", "2.4");
    assert!(!ok, "{text}{err}");
    assert!(
        text.contains("1 overlapping pairs, 2 containment violations"),
        "{text}"
    );
    assert!(text.contains("10 and 7: μ² = 0.562500000000"), "{text}");
    // t = (5√2 + 1) / 2.4 for id 3, 2.5 / 2.4 for id 7; worst first.
    let t3 = (5.0 * 2f64.sqrt() + 1.0) / 2.4;
    let line3 = format!("  3: t = {t3:.9}");
    let line7 = format!("  7: t = {:.9}", 2.5 / 2.4);
    let (p3, p7) = (text.find(&line3), text.find(&line7));
    assert!(p3.is_some() && p7.is_some() && p3 < p7, "{text}");
    assert!(text.contains("NOT certified"), "{text}");
}

#[test]
fn verify_lists_twenty_offenders_and_counts_the_rest() {
    // 25 pairs of discs on top of each other, far apart from the other pairs.
    let mut csv = String::from("id,x,y,a,b,theta\n");
    for k in 0..25 {
        let x = 10.0 * k as f64;
        csv.push_str(&format!(
            "{},{x},0,1,1,0\n{},{},0,1,1,0\n",
            2 * k,
            2 * k + 1,
            x + 0.5
        ));
    }
    let dir = folder_with_packing("bounded", &csv);
    let (ok, text, err) = verify_packing(&dir, "circle", "1000");
    assert!(!ok, "{err}");
    assert!(text.contains("25 overlapping pairs"), "{text}");
    assert_eq!(text.matches(": μ² = ").count(), 20, "{text}");
    assert!(text.contains("… and 5 more"), "{text}");
}

/// Two prolate spheroids along x, 3 apart, each reaching 2.5 from the origin.
const TWO_SPHEROIDS: &str =
    "id,x,y,z,a,b,c,qw,qx,qy,qz\n0,-1.5,0,0,1,0.5,0.5,1,0,0,0\n1,1.5,0,0,1,0.5,0.5,1,0,0,0\n";

#[test]
fn a_hand_made_packing_verifies_with_the_container_on_the_command_line() {
    let dir = folder_with_packing("hand", TWO_SPHEROIDS);
    let (ok, text, err) = verify_packing(&dir, "ball", "2.5");
    assert!(ok, "{text}{err}");
    assert!(
        text.contains("container: ball") && text.contains("\ncertified"),
        "{text}"
    );
    // A cuboid that is too short along x: each item reaches 2.5 from the centre, the half side
    // is 2, so t = 1.25.
    let (ok, text, _) = verify_packing(&dir, "cuboid", "2,1,1");
    assert!(!ok && text.contains("t = 1.250000000"), "{text}");
    // The same cuboid moved by its centre holds one item but not the other.
    let (ok, text, err) = verify(
        &[
            "packing.csv",
            "--container",
            "cuboid",
            "--size",
            "3,1,1",
            "--center",
            "-0.6,0,0",
        ],
        &dir,
    );
    assert!(!ok, "{err}");
    assert!(
        text.contains("0 overlapping pairs, 1 containment violations"),
        "{text}"
    );
    assert!(text.contains("  1: t = "), "{text}");
}

#[test]
fn a_hand_made_packing_verifies_with_a_minimal_summary() {
    let dir = folder_with_packing("minimal", DISCS);
    std::fs::write(
        dir.join("summary.json"),
        r#"{"container": {"kind": "rectangle", "half_sides": [7, 7]}}"#,
    )
    .unwrap();
    // The folder, the file with the summary beside it, and both named.
    for args in [
        vec!["."],
        vec!["packing.csv"],
        vec!["packing.csv", "summary.json"],
    ] {
        let (ok, text, err) = verify(&args, &dir);
        assert!(!ok, "{args:?}: {err}");
        assert!(
            text.contains("container: rectangle")
                && text.contains("1 overlapping pairs, 0 containment violations")
                && !text.contains("note:"),
            "{args:?}: {text}"
        );
    }
    // A stated item count that disagrees is an error naming both files.
    std::fs::write(
        dir.join("summary.json"),
        r#"{"container": {"kind": "circle", "radius": 9}, "items": 4}"#,
    )
    .unwrap();
    let (ok, _, err) = verify(&["."], &dir);
    assert!(
        !ok && err.contains("packing.csv") && err.contains("summary.json") && err.contains('4'),
        "{err}"
    );
}

#[test]
fn verify_without_a_container_says_how_to_give_one() {
    let dir = folder_with_packing("nosummary", DISCS);
    let (ok, _, err) = verify(&["packing.csv"], &dir);
    assert!(
        !ok && err.contains("summary.json") && err.contains("--container"),
        "{err}"
    );
    let (ok, _, err) = verify(&["packing.csv", "--container", "ball", "--size", "5"], &dir);
    assert!(!ok && err.contains("2D") && err.contains("ball"), "{err}");
    let (ok, _, err) = verify(&["packing.csv", "--container", "cube", "--size", "5"], &dir);
    assert!(
        !ok && err.contains("cube") && err.contains("cuboid"),
        "{err}"
    );
    let (ok, _, err) = verify_packing(&dir, "rectangle", "5");
    assert!(
        !ok && err.contains("rectangle") && err.contains("2"),
        "{err}"
    );
    let (ok, _, err) = verify(
        &[
            "packing.csv",
            "--container",
            "circle",
            "--size",
            "5",
            "--center",
            "1,2,3",
        ],
        &dir,
    );
    assert!(
        !ok && err.contains("--container circle: a circle needs 2 centre values, not 3"),
        "{err}"
    );
    let (ok, _, err) = verify_packing(&dir, "circle", "-5");
    assert!(!ok && err.contains("radius must be positive"), "{err}");
}

#[test]
fn duplicate_ids_are_an_error_naming_the_id_and_both_lines() {
    let dir = folder_with_packing(
        "dup",
        "id,x,y,a,b,theta\n10,0,0,1,1,0\n7,3,0,1,1,0\n10,6,0,1,1,0\n",
    );
    let (ok, _, err) = verify_packing(&dir, "circle", "9");
    assert!(!ok, "{err}");
    assert!(
        err.contains("packing.csv: line 4: id 10 is already the id of line 2"),
        "{err}"
    );
}

#[test]
fn the_table_keeps_ids_and_lines_and_read_csv_refuses_duplicates() {
    use ellipack::Error;
    use ellipack::items_csv::{read_csv, read_table};
    let table = read_table(DISCS, "p.csv").unwrap();
    assert_eq!(table.ids, [10, 7, 3]);
    assert_eq!(table.lines, [2, 3, 4]);
    let err = read_csv("id,x,y,a,b,theta\n5,0,0,1,1,0\n5,3,0,1,1,0\n", "p.csv").unwrap_err();
    assert!(
        matches!(
            err,
            Error::DuplicateId {
                id: 5,
                first_line: 2,
                line: 3,
                ..
            }
        ),
        "{err:?}"
    );
}

#[test]
fn a_minimal_summary_is_a_container_at_the_origin() {
    use ellipack::packing::Container;
    use ellipack::summary_json::{read_stated_summary, read_summary};
    let s =
        read_stated_summary(r#"{"container": {"kind": "ball", "radius": 5}}"#, "s.json").unwrap();
    assert_eq!(
        s.container,
        Container::space([0.0; 3], Centred::Ball { radius: 5.0 })
    );
    assert_eq!((s.items, s.certificate), (None, None));
    // A run's summary still needs its statistics.
    assert!(read_summary(r#"{"container": {"kind": "ball", "radius": 5}}"#, "s.json").is_err());
    let err = read_stated_summary(r#"{"container": {"kind": "ball", "radius": -1}}"#, "s.json")
        .unwrap_err()
        .to_string();
    assert!(err.contains("s.json") && err.contains("radius"), "{err}");
}

/// A periodic packing the model cannot hold is refused naming the item or the container's
/// value, never a model variable: a tilt of 1e308, an item 1e10 cells away.
#[test]
fn values_beyond_the_models_range_are_named_as_the_packing_states_them() {
    let dir = common::temp_dir("verify-range");
    let packing = dir.join("packing.csv");
    let cases = [
        (
            "0,0.5,0.5,0.2,0.2,0\n1,1.5,0.5,0.2,0.2,0\n",
            "4,4,1e308",
            "tilts must be finite, within ±1e30",
        ),
        (
            "0,0.5,0.5,0.2,0.2,0\n1,1e10,0.5,0.2,0.2,0\n",
            "1,1",
            "item 1's fractional coordinate along the cell edge a is 1e10",
        ),
    ];
    for (rows, size, expected) in cases {
        std::fs::write(&packing, format!("id,x,y,a,b,theta\n{rows}")).unwrap();
        let v = common::verify_periodic(&packing, size);
        let said = common::text(&v.stderr);
        assert_eq!(v.status.code(), Some(1), "{said}");
        assert!(said.contains(expected), "{said}");
        assert!(!said.contains("variable"), "{said}");
    }
}

/// Smaller messages: a periodic summary without `origin` reads as the origin; a stated
/// certificate differing only in its smallest μ² draws no note; resuming a 2D cell with a 3D
/// scene names both dimensions.
#[test]
fn small_messages_say_what_is_meant() {
    let dir = packing_folder(
        "verify-small",
        "id,x,y,a,b,theta\n0,0.5,0.5,0.2,0.2,0\n1,2,2,0.2,0.2,0\n",
        r#"{
            "container": {"kind": "periodic", "lengths": [4, 4], "tilts": [0]},
            "items": 2, "density": 0.0157, "objective": 16,
            "wall_seconds": 0, "local_minimisations": 0,
            "certificate": {"overlapping_pairs": 0, "containment_violations": 0, "min_mu2": 12.5}
        }"#,
    );
    let out = ellipack().arg("verify").arg(&*dir).output().unwrap();
    let said = utf8(out.stdout);
    assert!(out.status.success(), "{said}{}", utf8(out.stderr));
    assert!(!said.contains("note"), "{said}");
    std::fs::write(
        dir.join("scene.toml"),
        "dimension = 3\n[container]\nkind = \"periodic\"\n[[shapes]]\ncount = 2\n\
         semi_axes = [0.2, 0.2, 0.2]\n",
    )
    .unwrap();
    let out = ellipack()
        .arg("pack")
        .arg(dir.join("scene.toml"))
        .arg("--out")
        .arg(&*dir)
        .arg("--resume")
        .output()
        .unwrap();
    let said = utf8(out.stderr);
    assert!(
        said.contains("2D periodic cell") && said.contains("3D periodic cell"),
        "{said}"
    );
}
