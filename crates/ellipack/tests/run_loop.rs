//! The packing run loop end to end: signals, the anytime property, the output folder checked
//! before the run, `--resume` and time limits.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Duration;

mod common;
use common::{ellipack, refused, succeeded, summary_json, temp_dir, text};

/// A 2D scene of `count` ellipses (2, 1) in a circle, one thread, no pictures.
fn scene(dir: &Path, count: usize, time_limit: f64, extra: &str) -> PathBuf {
    let path = dir.join("scene.toml");
    std::fs::write(
        &path,
        format!(
            "dimension = 2\nseed = 1\n[container]\nkind = \"circle\"\n[[shapes]]\n\
             count = {count}\nsemi_axes = [2.0, 1.0]\n[solver]\ntime_limit = {time_limit:?}\n\
             threads = 1\n{extra}[output]\npictures = false\n"
        ),
    )
    .unwrap();
    path
}

/// `ellipack verify` on a folder: its output, and whether it certified the packing.
fn verify(out: &Path) -> (bool, String) {
    let o = ellipack().arg("verify").arg(out).output().unwrap();
    (o.status.success(), text(&o.stdout) + &text(&o.stderr))
}

fn density(out: &Path) -> f64 {
    summary_json(out)["density"].as_f64().unwrap()
}

fn pack(args: &[&str]) -> Output {
    ellipack().arg("pack").args(args).output().unwrap()
}

/// `ellipack pack <scene> --out <out> --resume <extra>`.
fn resume(scene: &str, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![scene, "--out", out.to_str().unwrap(), "--resume"];
    args.extend_from_slice(extra);
    pack(&args)
}

/// Replaces `from` by `to` in the scene file `path`.
fn edit_scene(path: &Path, from: &str, to: &str) {
    let text_of_scene = std::fs::read_to_string(path).unwrap().replace(from, to);
    std::fs::write(path, text_of_scene).unwrap();
}

/// Starts a run that would last a minute, sends `signal` once it is under way, and checks
/// that the run stops soon, exits with status 0 and leaves a packing `verify` certifies.
fn stops_on(signal: &str) {
    let dir = temp_dir(&format!("signal-{signal}"));
    let scene = scene(&dir, 40, 60.0, "");
    let out = dir.join("out");
    let child = ellipack()
        .arg("pack")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let kill = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let stdout = succeeded(&child.wait_with_output().unwrap(), &format!("{signal}: "));
    // Stopped by the signal, not by its minute's time limit, on a machine of any speed.
    assert!(stdout.contains("(interrupted)"), "{signal}: {stdout}");
    let (certified, report) = verify(&out);
    assert!(certified, "{signal}: {report}");
}

#[test]
fn sigterm_stops_the_run_and_writes_the_best_certified_packing() {
    stops_on("TERM");
}

#[test]
fn sighup_stops_the_run_and_writes_the_best_certified_packing() {
    stops_on("HUP");
}

#[test]
fn a_time_limit_inside_the_first_local_minimisation_still_writes_a_certified_packing() {
    let dir = temp_dir("anytime");
    let scene = scene(&dir, 2000, 60.0, "");
    // 0.3 s and 1 s cut the first local minimisation of 2000 ellipses off at points far from
    // a packing: the repair certifies them at a fraction of the density, or not at all.
    for limit in ["0.3", "1"] {
        let out = dir.join(format!("out-{limit}"));
        let o = pack(&[
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--time-limit",
            limit,
        ]);
        assert!(
            o.status.success(),
            "{limit}: {}{}",
            text(&o.stdout),
            text(&o.stderr)
        );
        let (certified, report) = verify(&out);
        assert!(certified, "{limit}: {report}");
        // The lattice start alone has density 0.857: a run never writes less.
        assert!(density(&out) > 0.85, "{limit}: density {}", density(&out));
    }
    // A limit shorter than building and certifying the start: the start is written, and the
    // printout says how long it needed.
    let out = dir.join("out-tiny");
    let o = pack(&[
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--time-limit",
        "1e-6",
    ]);
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{stdout}{}", text(&o.stderr));
    assert!(
        stdout.contains("is shorter than building and certifying the start took"),
        "{stdout}"
    );
    assert!(verify(&out).0);
    assert!(density(&out) > 0.85);
}

#[test]
fn an_unwritable_output_folder_is_refused_before_the_run() {
    let dir = temp_dir("unwritable");
    // A minute of packing would be lost if the folder were found unwritable only at the end.
    let scene = scene(&dir, 12, 60.0, "");
    // /proc exists as a folder but takes no new files, even for root.
    let o = pack(&[scene.to_str().unwrap(), "--out", "/proc"]);
    let stderr = refused(&o);
    // Refused by the probe before the run: nothing was packed.
    assert!(
        !text(&o.stdout).contains("density"),
        "ran first: {}",
        text(&o.stdout)
    );
    assert!(
        stderr.contains("output folder /proc is not writable"),
        "{stderr}"
    );
    // A folder under a regular file cannot be created.
    let file = dir.join("file.txt");
    std::fs::write(&file, "x").unwrap();
    let under = file.join("out");
    let o = pack(&[scene.to_str().unwrap(), "--out", under.to_str().unwrap()]);
    let stderr = refused(&o);
    assert!(
        stderr.contains(&format!(
            "output folder {} is not writable",
            under.display()
        )),
        "{stderr}"
    );
}

#[test]
fn a_time_limit_beyond_any_clock_is_an_error_not_a_panic() {
    let dir = temp_dir("huge-limit");
    let scene = scene(&dir, 12, 60.0, "");
    for limit in ["1e20", "1.9e19", "1e300", "inf", "NaN", "0", "-1", "1e-320"] {
        let out = dir.join("out");
        let o = pack(&[
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            &format!("--time-limit={limit}"),
        ]);
        let stderr = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{limit}: {stderr}");
        assert!(
            stderr.contains("the time limit must be a number of seconds from 1e-9"),
            "{limit}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{limit}: {stderr}");
        assert!(!out.join("packing.csv").exists());
    }
    // The scene's own key: an error naming the key, no panic.
    for limit in ["1e20", "1e300", "1e-320"] {
        let path = dir.join("long.toml");
        let text_of_scene = std::fs::read_to_string(scene.clone())
            .unwrap()
            .replace("time_limit = 60.0", &format!("time_limit = {limit}"));
        std::fs::write(&path, text_of_scene).unwrap();
        let o = pack(&[
            path.to_str().unwrap(),
            "--out",
            dir.join("o").to_str().unwrap(),
        ]);
        let stderr = text(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{limit}: {stderr}");
        assert!(stderr.contains("solver.time_limit"), "{limit}: {stderr}");
        assert!(!stderr.contains("panicked"), "{limit}: {stderr}");
    }
}

/// A certified packing of 30 ellipses in `dir/out` after a few local minimisations.
fn finished_run(dir: &Path) -> (PathBuf, PathBuf) {
    let scene = scene(dir, 30, 60.0, "local_minimisations = 4\n");
    let out = dir.join("out");
    let o = pack(&[scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    (scene, out)
}

#[test]
fn resume_never_writes_a_worse_packing_than_its_start() {
    let dir = temp_dir("resume-no-worse");
    let (scene, out) = finished_run(&dir);
    let start = density(&out);
    let mut kept = false;
    for limit in ["1e-6", "0.02", "0.05", "0.1", "0.2", "0.4"] {
        let before = density(&out);
        let o = resume(scene.to_str().unwrap(), &out, &["--time-limit", limit]);
        let stdout = text(&o.stdout);
        assert!(o.status.success(), "{limit}: {stdout}{}", text(&o.stderr));
        let after = density(&out);
        assert!(after >= before, "{limit}: {before} → {after}");
        let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
        if after == before {
            assert!(stdout.contains("wrote the start"), "{limit}: {stdout}");
            assert!(
                summary.contains("\"start_kept\": true"),
                "{limit}: {summary}"
            );
            kept = true;
        } else {
            assert!(!summary.contains("start_kept"), "{limit}: {summary}");
        }
        let (certified, report) = verify(&out);
        assert!(certified, "{limit}: {report}");
    }
    assert!(density(&out) >= start);
    // At least the run stopped before its first local minimisation keeps its start.
    assert!(kept, "a short resumed run keeps its start and says so");
}

/// Rewrites row `row` of `packing.csv` with the centre `(x, y)`.
fn move_item(out: &Path, row: usize, x: f64, y: f64) {
    let path = out.join("packing.csv");
    let csv = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<String> = csv
        .lines()
        .enumerate()
        .map(|(k, line)| {
            if k == row + 1 {
                let mut fields: Vec<String> = line.split(',').map(String::from).collect();
                fields[1] = format!("{x:e}");
                fields[2] = format!("{y:e}");
                fields.join(",")
            } else {
                line.to_string()
            }
        })
        .collect();
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
}

fn centre(out: &Path, row: usize) -> (f64, f64) {
    let csv = std::fs::read_to_string(out.join("packing.csv")).unwrap();
    let line = csv.lines().nth(row + 1).unwrap();
    let f: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
    (f[1], f[2])
}

#[test]
fn resume_refuses_a_start_with_overlapping_items_or_items_outside() {
    let dir = temp_dir("resume-bad-start");
    let (scene, out) = finished_run(&dir);
    let (x, y) = centre(&out, 3);
    move_item(&out, 7, x, y);
    let o = resume(scene.to_str().unwrap(), &out, &["--time-limit", "1"]);
    let stderr = refused(&o);
    assert!(stderr.contains("not certified"), "{stderr}");
    assert!(stderr.contains("items 3 and 7 (μ² = 0.000000)"), "{stderr}");

    // Item 7 far outside the container instead.
    move_item(&out, 7, 1e3, 0.0);
    let o = resume(scene.to_str().unwrap(), &out, &["--time-limit", "1"]);
    let stderr = refused(&o);
    assert!(
        stderr.contains("1 items outside the container: 7 (the container would have to grow by"),
        "{stderr}"
    );
}

#[test]
fn resume_refuses_a_folder_of_another_container_or_other_items() {
    let dir = temp_dir("resume-mismatch");
    let (_, out) = finished_run(&dir);
    let packing_before = std::fs::read_to_string(out.join("packing.csv")).unwrap();
    // The same items in a rectangle: the folder's circle does not fit the scene.
    let other = dir.join("other");
    std::fs::create_dir_all(&other).unwrap();
    let rectangle = scene(&other, 30, 60.0, "").to_str().unwrap().to_string();
    edit_scene(
        Path::new(&rectangle),
        "kind = \"circle\"",
        "kind = \"rectangle\"",
    );
    let o = resume(&rectangle, &out, &[]);
    let stderr = refused(&o);
    assert!(
        stderr.contains(&format!(
            "cannot resume from {}: its container is circle, but the scene",
            out.join("summary.json").display()
        )),
        "{stderr}"
    );
    assert!(stderr.contains("has rectangle"), "{stderr}");
    // Other semi-axes.
    let bigger = scene(&other, 30, 60.0, "").to_str().unwrap().to_string();
    edit_scene(Path::new(&bigger), "[2.0, 1.0]", "[3.0, 1.0]");
    let o = resume(&bigger, &out, &[]);
    let stderr = refused(&o);
    assert!(
        stderr.contains("item 0 has semi-axes [2.0, 1.0] in the packing, [3.0, 1.0] in the scene"),
        "{stderr}"
    );
    // The folder is left as it was.
    assert_eq!(
        std::fs::read_to_string(out.join("packing.csv")).unwrap(),
        packing_before
    );
}

/// `method = "compression"` in a scene runs compression in every local minimisation, and the
/// folder certifies.
#[test]
fn a_scene_with_the_compression_method_packs_and_certifies() {
    let dir = temp_dir("compression-method");
    let compression = "local_minimisations = 3\nmethod = \"compression\"\n";
    let scene = scene(&dir, 30, 600.0, compression);
    let out = dir.join("out");
    let o = pack(&[scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let (certified, said) = verify(&out);
    assert!(certified, "{said}");
    assert!(density(&out) > 0.7, "{}", density(&out));
}
