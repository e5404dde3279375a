//! `ellipack pack` on fixed containers: a fraction the run reaches ends certified in the
//! scene's container exactly, and `ellipack verify` accepts it; one it cannot reach ends with
//! exit status 4, a message naming the fraction, the time and the overlap left, and the least
//! overlapping configuration in OUT/unfinished/, never as OUT's packing.

mod common;
use common::{ellipack, pack_into, pack_into_with, succeeded, summary_json, temp_dir, text};
use ellipack::packing::ContainerKind;
use ellipack::scene::Scene;
use std::path::Path;
use std::process::Output;

/// 20 ellipsoids (1, 0.75, 0.5) in a ball at packing fraction 0.45, one thread, at most 20
/// local minimisations (the time limit is far beyond them).
const BALL: &str = "dimension = 3\nseed = 1\n[container]\nkind = \"ball\"\n\
                    packing_fraction = 0.45\n[[shapes]]\ncount = 20\n\
                    semi_axes = [1.0, 0.75, 0.5]\n[solver]\ntime_limit = 600.0\n\
                    local_minimisations = 20\nthreads = 1\n\
                    [output]\npictures = false\n";

/// 12 ellipses (2, 1) in a square at packing fraction 0.95, which no packing reaches (the
/// densest packing of ellipses of one shape in the plane has 0.9069).
const SQUARE: &str = "dimension = 2\nseed = 1\n[container]\nkind = \"rectangle\"\n\
                      packing_fraction = 0.95\n[[shapes]]\ncount = 12\nsemi_axes = [2.0, 1.0]\n\
                      [solver]\ntime_limit = 2.0\nthreads = 1\n[output]\npictures = false\n";

fn pack(dir: &Path, scene: &str, out: &Path) -> Output {
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    pack_into(&path, out)
}

fn verify(folder: &Path) -> Output {
    ellipack().arg("verify").arg(folder).output().unwrap()
}

#[test]
fn a_ball_at_fraction_045_ends_certified_with_the_given_radius() {
    let dir = temp_dir("fixed-ball");
    let out = dir.join("out");
    let o = pack(&dir, BALL, &out);
    let said = text(&o.stdout) + &text(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{said}");
    let container = Scene::from_toml_str(BALL, "ball.toml")
        .unwrap()
        .fixed_container()
        .expect("a fixed ball");
    assert_eq!(container.kind(), ContainerKind::Ball);
    let radius = container.size()[0];
    let s = summary_json(&out);
    assert_eq!(s["container"]["kind"], "ball");
    assert_eq!(s["container"]["radius"].as_f64(), Some(radius), "{s}");
    let density = s["density"].as_f64().unwrap();
    assert!((density - 0.45).abs() < 1e-12, "{density}");
    assert_eq!(s["certificate"]["overlapping_pairs"], 0);
    assert_eq!(s["certificate"]["containment_violations"], 0);
    assert!(
        s.get("repair").is_none() && s.get("not_reached").is_none(),
        "{s}"
    );
    assert!(!out.join("unfinished").exists());
    let v = verify(&out);
    assert!(v.status.success(), "{}", text(&v.stdout));
    assert!(
        text(&v.stdout).contains("\ncertified"),
        "{}",
        text(&v.stdout)
    );
}

#[test]
fn an_impossible_fraction_ends_not_reached_with_the_unfinished_folder_only() {
    let dir = temp_dir("fixed-square");
    let out = dir.join("out");
    let o = pack(&dir, SQUARE, &out);
    let stderr = text(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{}{stderr}", text(&o.stdout));
    let seconds: f64 = stderr
        .split_once("packing fraction 0.9500 not reached in ")
        .and_then(|(_, rest)| rest.split_once(" s"))
        .and_then(|(number, _)| number.parse().ok())
        .unwrap_or_else(|| panic!("no fraction and time in {stderr}"));
    assert!(seconds >= 2.0, "{stderr}");
    assert!(stderr.contains("overlapping pairs"), "{stderr}");
    assert!(stderr.contains("unfinished"), "{stderr}");
    assert!(!out.join("packing.csv").exists());
    assert!(!out.join("summary.json").exists());
    let unfinished = out.join("unfinished");
    assert!(unfinished.join("packing.csv").is_file());
    let s = summary_json(&unfinished);
    assert_eq!(s["not_reached"], true, "{s}");
    let overlaps = s["certificate"]["overlapping_pairs"].as_u64().unwrap();
    let outside = s["certificate"]["containment_violations"].as_u64().unwrap();
    assert!(overlaps + outside > 0, "{s}");
    assert!((s["density"].as_f64().unwrap() - 0.95).abs() < 1e-12, "{s}");
    // The configuration is what the summary says: not a packing.
    let v = verify(&unfinished);
    assert!(!v.status.success());
    assert!(text(&v.stdout).contains("NOT certified"));
}

#[test]
fn a_certified_packing_in_the_folder_is_never_replaced_by_an_unfinished_run() {
    let dir = temp_dir("fixed-keep");
    let out = dir.join("out");
    // The same items in a minimum-area square first: a certified packing.
    let minimised = SQUARE.replace("packing_fraction = 0.95\n", "").replace(
        "time_limit = 2.0",
        "time_limit = 20.0\nlocal_minimisations = 1",
    );
    let first = pack(&dir, &minimised, &out);
    assert_eq!(first.status.code(), Some(0), "{}", text(&first.stderr));
    let before = std::fs::read(out.join("packing.csv")).unwrap();
    let summary_before = std::fs::read(out.join("summary.json")).unwrap();
    let o = pack(&dir, SQUARE, &out);
    assert_eq!(o.status.code(), Some(4), "{}", text(&o.stderr));
    assert!(
        std::fs::read(out.join("packing.csv")).unwrap() == before,
        "the certified packing was replaced"
    );
    assert!(
        std::fs::read(out.join("summary.json")).unwrap() == summary_before,
        "the certified packing's summary was replaced"
    );
    assert!(out.join("unfinished").join("summary.json").is_file());
    assert!(verify(&out).status.success());
}

#[test]
fn resuming_a_fixed_run_keeps_its_packing_and_refuses_another_size() {
    let dir = temp_dir("fixed-resume");
    let out = dir.join("out");
    assert_eq!(pack(&dir, BALL, &out).status.code(), Some(0));
    let before = std::fs::read(out.join("packing.csv")).unwrap();
    let scene = dir.join("scene.toml");
    let said = succeeded(&pack_into_with(&scene, &out, &["--resume"]), "");
    assert!(
        said.contains("already a packing in the fixed container"),
        "{said}"
    );
    // The start is written again as read back (its angles converted to quaternions anew),
    // so the numbers agree to rounding, not to the last digit.
    let again = std::fs::read_to_string(out.join("packing.csv")).unwrap();
    let numbers = |t: &str| -> Vec<f64> {
        t.lines()
            .skip(1)
            .flat_map(|l| l.split(',').map(|v| v.parse::<f64>().unwrap()))
            .collect()
    };
    let (a, b) = (
        numbers(&again),
        numbers(&String::from_utf8(before.clone()).unwrap()),
    );
    assert_eq!(a.len(), b.len());
    assert!(
        a.iter()
            .zip(&b)
            .all(|(x, y)| (x - y).abs() <= 1e-12 * (1.0 + y.abs())),
        "the resumed run wrote another packing"
    );
    let before = std::fs::read(out.join("packing.csv")).unwrap();
    // The same items at another fraction: the folder's ball is not the scene's.
    std::fs::write(&scene, BALL.replace("0.45", "0.4")).unwrap();
    let refused = pack_into_with(&scene, &out, &["--resume"]);
    assert_eq!(refused.status.code(), Some(1));
    assert!(
        text(&refused.stderr).contains("is not the scene's fixed container"),
        "{}",
        text(&refused.stderr)
    );
    assert!(
        std::fs::read(out.join("packing.csv")).unwrap() == before,
        "a refused run changed the packing"
    );
}
