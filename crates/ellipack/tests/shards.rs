//! A multi-start spread over shards (`ellipack pack --shard K/N`) and combined by
//! `ellipack merge`, run locally as a scheduler would run it.

mod common;
use common::{assert_success, ellipack, folder_with, refused, temp_dir, text};
use std::path::{Path, PathBuf};
use std::process::Output;

/// Six ellipses in a circle, three local minimisations per shard, no pictures.
const SCENE: &str = "dimension = 2\nseed = 5\n[container]\nkind = \"circle\"\n[[shapes]]\n\
                     count = 6\nsemi_axes = [2.0, 1.0]\n[solver]\ntime_limit = 600.0\n\
                     local_minimisations = 3\nthreads = 1\n[output]\npictures = false\n";

fn pack_shard(scene: &Path, shard: &str, out: &Path) -> Output {
    ellipack()
        .arg("pack")
        .arg(scene)
        .args(["--shard", shard, "--out"])
        .arg(out)
        .output()
        .unwrap()
}

fn merge(folders: &[PathBuf], out: &Path) -> Output {
    ellipack()
        .arg("merge")
        .args(folders)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

fn summary(folder: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(folder.join("summary.json")).unwrap()).unwrap()
}

fn density(folder: &Path) -> f64 {
    summary(folder)["density"].as_f64().unwrap()
}

fn csv(folder: &Path) -> String {
    std::fs::read_to_string(folder.join("packing.csv")).unwrap()
}

#[test]
fn three_shards_and_a_merge_keep_the_best_certified_packing() {
    let (dir, scene) = folder_with("shards", "scene.toml", SCENE);
    let shards: Vec<PathBuf> = (0..3).map(|k| dir.join(format!("shard-{k}"))).collect();
    for (k, folder) in shards.iter().enumerate() {
        assert_success(&pack_shard(&scene, &format!("{k}/3"), folder));
        let s = summary(folder);
        assert_eq!(s["shard"]["index"], k);
        assert_eq!(s["shard"]["count"], 3);
        assert_eq!(s["shard"]["seed"], 5);
    }
    // Disjoint start streams: the shards end in different packings.
    assert_ne!(csv(&shards[0]), csv(&shards[1]));
    assert_ne!(csv(&shards[1]), csv(&shards[2]));
    // A shard reproduces exactly.
    let again = dir.join("shard-1-again");
    assert_success(&pack_shard(&scene, "1/3", &again));
    assert_eq!(csv(&again), csv(&shards[1]));

    let best = dir.join("best");
    let output = merge(&shards, &best);
    assert_success(&output);
    let densest = shards
        .iter()
        .map(|f| density(f))
        .fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(density(&best), densest);
    let winner = shards.iter().find(|f| density(f) == densest).unwrap();
    assert_eq!(csv(&best), csv(winner));
    assert_success(&ellipack().arg("verify").arg(&best).output().unwrap());

    // A second merge of the worse shards only leaves the better packing in place.
    let worse: Vec<PathBuf> = shards
        .iter()
        .filter(|f| density(f) < densest)
        .cloned()
        .collect();
    if !worse.is_empty() {
        let output = merge(&worse, &best);
        assert_success(&output);
        assert!(text(&output.stdout).contains("already holds the best packing"));
        assert_eq!(density(&best), densest);
    }
}

#[test]
fn merge_refuses_other_scenes_and_uncertified_sets() {
    let (dir, scene) = folder_with("merge-refusals", "scene.toml", SCENE);
    let a = dir.join("a");
    assert_success(&pack_shard(&scene, "0/2", &a));
    let other_scene = dir.join("other.toml");
    std::fs::write(&other_scene, SCENE.replace("count = 6", "count = 5")).unwrap();
    let b = dir.join("b");
    assert_success(&pack_shard(&other_scene, "0/2", &b));
    let out = dir.join("out");
    let stderr = refused(&merge(&[a.clone(), b.clone()], &out));
    assert!(
        stderr.contains("not a packing of the same scene"),
        "{stderr}"
    );
    assert!(stderr.contains("5 items against 6"), "{stderr}");
    assert!(!out.exists(), "nothing is written on refusal");

    // An overlapping packing (two items moved onto each other) is not a candidate.
    let broken = dir.join("broken");
    std::fs::create_dir(&broken).unwrap();
    std::fs::copy(a.join("summary.json"), broken.join("summary.json")).unwrap();
    let mut lines: Vec<String> = csv(&a).lines().map(String::from).collect();
    let first_row = lines[1].clone();
    let id_of_third = lines[2].split(',').next().unwrap().to_string();
    let rest: Vec<&str> = first_row.splitn(2, ',').collect();
    lines[2] = format!("{id_of_third},{}", rest[1]);
    std::fs::write(broken.join("packing.csv"), lines.join("\n") + "\n").unwrap();
    let stderr = refused(&merge(std::slice::from_ref(&broken), &out));
    assert!(
        stderr.contains("none of the 1 packings read is certified"),
        "{stderr}"
    );
    let output = merge(&[broken, a.clone()], &out);
    assert_success(&output);
    assert_eq!(csv(&out), csv(&a));

    for bad in ["3/3", "1", "a/b", "1/0"] {
        let output = pack_shard(&scene, bad, &dir.join("never"));
        assert_eq!(output.status.code(), Some(2), "--shard {bad}");
        assert!(text(&output.stderr).contains("shard"), "--shard {bad}");
    }
}

/// Four unit circles in a circle: a fixed one (radius given, filled at once from the start),
/// or the smallest one (one local minimisation).
fn circles(dir: &Path, name: &str, size: &str) -> PathBuf {
    let scene = dir.join(format!("{name}.toml"));
    std::fs::write(
        &scene,
        format!(
            "dimension = 2\nseed = 5\n[container]\nkind = \"circle\"\n{size}[[shapes]]\n\
             count = 4\nsemi_axes = [1.0, 1.0]\n[solver]\ntime_limit = 60.0\n\
             local_minimisations = 1\nthreads = 1\n[output]\npictures = false\n"
        ),
    )
    .unwrap();
    let out = dir.join(name);
    assert_success(
        &ellipack()
            .arg("pack")
            .arg(&scene)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap(),
    );
    out
}

/// Packings of one fixed container merge; one of another fixed container, or of a variable
/// one, is refused as another scene (a ball of radius 6 never wins over the scene's 10).
#[test]
fn merge_compares_the_whole_container() {
    let dir = temp_dir("merge-containers");
    let ten = circles(&dir, "ten", "radius = 10.0\n");
    let ten_again = circles(&dir, "ten-again", "radius = 10.0\n");
    let six = circles(&dir, "six", "radius = 6.0\n");
    let smallest = circles(&dir, "smallest", "");
    assert_eq!(summary(&ten)["fixed_container"], true);
    assert!(summary(&smallest).get("fixed_container").is_none());
    assert_success(&merge(&[ten.clone(), ten_again], &dir.join("a")));
    for (other, expected) in [
        (
            &six,
            "fixed container circle of radius [6.0] against circle of radius [10.0]",
        ),
        (&smallest, "a variable container against the fixed circle"),
    ] {
        let stderr = refused(&merge(&[ten.clone(), other.clone()], &dir.join("b")));
        assert!(stderr.contains(expected), "{stderr}");
        assert!(!dir.join("b").join("packing.csv").exists());
    }
}

/// A shard folder without a packing (a killed job, or a fixed container's shard that ended
/// with only `unfinished/`) is skipped, as an uncertified shard is.
#[test]
fn merge_skips_folders_without_a_packing() {
    let dir = temp_dir("merge-empty-shard");
    let good = circles(&dir, "good", "");
    let killed = dir.join("killed");
    std::fs::create_dir_all(killed.join("unfinished")).unwrap();
    let best = dir.join("best");
    let output = merge(&[killed.clone(), good.clone()], &best);
    assert_success(&output);
    assert!(
        text(&output.stdout).contains("killed: no packing.csv"),
        "{}",
        text(&output.stdout)
    );
    assert_eq!(csv(&best), csv(&good));
    let stderr = refused(&merge(&[killed], &dir.join("none")));
    assert!(stderr.contains("1 folders held no packing"), "{stderr}");
}
