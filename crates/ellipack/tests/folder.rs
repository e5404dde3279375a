//! An output folder holds one run's files or the previous run's, never a mix: stale pictures
//! and XYZ files go, the user's files stay, a failure before the swap leaves the old run whole,
//! and the leftovers of killed runs are cleaned up.

use ellipack::folder::Staging;
use ellipack::folder::read_packing_dir;
use ellipack::folder::write_files;
use ellipack::packing::{CertificateCounts, Summary};
use std::path::{Path, PathBuf};

mod common;
use common::{TempDir, assert_success, ellipack, is_symlink, names, pack_into, temp_dir};

/// A small 2D scene: five ellipses, two local minimisations.
fn scene(pictures: bool, xyz: bool) -> String {
    format!(
        "dimension = 2\nseed = 3\n[container]\nkind = \"circle\"\n[[shapes]]\ncount = 5\n\
         semi_axes = [1.5, 1.0]\n[solver]\ntime_limit = 600.0\nlocal_minimisations = 2\n\
         threads = 1\n[output]\npictures = {pictures}\nxyz = {xyz}\nimage_width = 200\n"
    )
}

fn pack(scene_path: &Path, out: &Path) {
    assert_success(&pack_into(scene_path, out));
}

/// A test folder holding `out/` and `scene.toml` (the scene of [`scene`]).
fn out_and_scene(name: &str, pictures: bool, xyz: bool) -> (TempDir, PathBuf, PathBuf) {
    let dir = temp_dir(name);
    let out = dir.join("out");
    std::fs::create_dir(&out).unwrap();
    let scene_path = dir.join("scene.toml");
    std::fs::write(&scene_path, scene(pictures, xyz)).unwrap();
    (dir, out, scene_path)
}

/// Every file of `out` with its bytes.
fn contents(out: &Path) -> Vec<(String, Vec<u8>)> {
    names(out)
        .into_iter()
        .map(|n| {
            let bytes = std::fs::read(out.join(&n)).unwrap();
            (n, bytes)
        })
        .collect()
}

/// `ellipack verify` accepts the folder, and its summary agrees with its packing.
fn assert_whole_run(out: &Path) {
    let verify = ellipack().arg("verify").arg(out).output().unwrap();
    let text = String::from_utf8_lossy(&verify.stdout);
    assert!(verify.status.success(), "{text}");
    assert!(
        !text.contains("note:"),
        "summary and packing disagree: {text}"
    );
    let (packing, summary) = read_packing_dir(out).unwrap();
    assert_eq!(summary.items, packing.items().len());
    assert_eq!(summary.density, packing.density());
}

#[test]
fn a_new_run_drops_stale_files_and_keeps_the_users() {
    let dir = temp_dir("stale");
    let out = dir.join("out");
    std::fs::create_dir(&out).unwrap();
    // The user's files, including the scene itself inside the output folder.
    let scene_path = out.join("scene.toml");
    std::fs::write(&scene_path, scene(true, true)).unwrap();
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    std::fs::create_dir(out.join("older")).unwrap();
    std::fs::write(out.join("older").join("packing.csv"), "kept").unwrap();
    pack(&scene_path, &out);
    for file in common::EXPORTS_AND_PICTURES
        .into_iter()
        .chain(["history.csv"])
    {
        assert!(out.join(file).exists(), "{file}");
    }
    std::fs::write(&scene_path, scene(false, false)).unwrap();
    pack(&scene_path, &out);
    assert_eq!(
        names(&out),
        [
            "container.obj",
            "history.csv",
            "notes.txt",
            "older",
            "packing.csv",
            "packing.data",
            "packing.gsd",
            "rdf.csv",
            "scene.toml",
            "structure.json",
            "summary.json"
        ]
    );
    assert_eq!(
        std::fs::read_to_string(out.join("notes.txt")).unwrap(),
        "mine"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("older").join("packing.csv")).unwrap(),
        "kept"
    );
    assert_whole_run(&out);
    assert_eq!(
        names(&dir),
        ["out"],
        "no staging folder left beside the output"
    );
}

#[test]
fn a_failure_while_writing_leaves_the_previous_run_whole() {
    let (dir, out, scene_path) = out_and_scene("crash", false, true);
    pack(&scene_path, &out);
    let before: Vec<(String, Vec<u8>)> = contents(&out);

    // Another packing (the container shrunk, so that its items stick out) written into the
    // staging folder; the write fails after the first file.
    let (packing, _) = read_packing_dir(&out).unwrap();
    let (mut container, items) = packing.into_parts();
    if let ellipack::packing::Container::Plane {
        shape: ellipack::packing::Centred::Ball { radius },
        ..
    } = &mut container
    {
        *radius *= 0.5;
    }
    let packing = ellipack::packing::Packing::new(container, items).unwrap();
    let summary = Summary::new(
        &packing,
        1.0,
        1.0,
        1,
        CertificateCounts {
            overlapping_pairs: 0,
            containment_violations: 0,
            min_mu2: None,
        },
    );
    let write_set = |into: &Path| -> Result<(), String> {
        ellipack::items_csv::write_csv(&into.join("packing.csv"), packing.items())
            .map_err(|e| e.to_string())?;
        Err("injected failure after the first file".into())
    };
    {
        let staging = Staging::begin(&out).unwrap();
        assert!(write_set(staging.path()).is_err());
    }
    let after: Vec<(String, Vec<u8>)> = contents(&out);
    assert!(before == after, "the folder changed");
    assert_whole_run(&out);

    // A run killed after writing every file but before the swap leaves its staging folder
    // (here: renamed to a process id that does not run); the folder is still the old run, and
    // the next run removes the leftover.
    let staging = Staging::begin(&out).unwrap();
    write_files(staging.path(), &packing, &summary, true).unwrap();
    let leftover = dir.join("out.ellipack-staging-999999999");
    std::fs::rename(staging.path(), &leftover).unwrap();
    drop(staging);
    assert_whole_run(&out);
    assert!(leftover.exists());
    pack(&scene_path, &out);
    assert!(!leftover.exists(), "the leftover staging folder is removed");
    assert_whole_run(&out);
}

#[test]
fn temporary_files_of_killed_runs_are_removed() {
    let (_dir, out, scene_path) = out_and_scene("temp", false, false);
    for file in ["packing.csv", "summary.json", "packing.png", "packing.gsd"] {
        std::fs::write(out.join(format!(".{file}.tmp-999999999")), "half written").unwrap();
    }
    std::fs::write(out.join(".mine.tmp-999999999"), "not ours").unwrap();
    pack(&scene_path, &out);
    assert_eq!(
        names(&out),
        [
            ".mine.tmp-999999999",
            "container.obj",
            "history.csv",
            "packing.csv",
            "packing.data",
            "packing.gsd",
            "rdf.csv",
            "structure.json",
            "summary.json"
        ]
    );
    assert_whole_run(&out);
}

#[cfg(unix)]
#[test]
fn a_symbolic_link_to_the_output_folder_stays_a_link() {
    let (dir, real, scene_path) = out_and_scene("link", false, false);
    let link = dir.join("link");
    std::os::unix::fs::symlink(&real, &link).unwrap();
    pack(&scene_path, &link);
    assert!(is_symlink(&link));
    assert!(real.join("packing.csv").exists());
    assert_whole_run(&link);
}

#[test]
fn a_run_killed_at_any_moment_leaves_one_whole_run() {
    let (dir, out, scene_path) = out_and_scene("kill", true, true);
    let started = std::time::Instant::now();
    pack(&scene_path, &out);
    let full = started.elapsed();
    let run_set = names(&out);
    // Kills spread over the whole run, the file writing at its end included.
    for k in 0..12u32 {
        let mut child = ellipack()
            .arg("pack")
            .arg(&scene_path)
            .arg("--out")
            .arg(&out)
            .arg("--seed")
            .arg((k + 10).to_string())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(full * (k + 1) / 12);
        let _ = child.kill();
        let _ = child.wait();
        assert_eq!(names(&out), run_set, "after a kill at {k}/12 of a run");
        assert_whole_run(&out);
    }
    pack(&scene_path, &out);
    assert_eq!(names(&dir), ["out", "scene.toml"], "leftovers removed");
}
