//! The `ellipack` binary end to end.

use std::path::PathBuf;
use std::process::Command;

fn ellipack() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ellipack"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ellipack-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn contact_accepts_the_reference_file_as_it_is() {
    let reference = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/reference/pw85_contact.csv");
    let dir = temp_dir("reference");
    let out = dir.join("results.csv");
    let status = ellipack()
        .args(["contact", "--input"])
        .arg(&reference)
        .arg("--output")
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success());
    let results = std::fs::read_to_string(&out).unwrap();
    let reference = std::fs::read_to_string(&reference).unwrap();
    let mut lines = results.lines();
    assert_eq!(lines.next(), Some("case_id,mu2,lambda,overlap,error"));
    let header: Vec<&str> = reference.lines().next().unwrap().split(',').collect();
    let mu2_col = header.iter().position(|h| *h == "mu2_ref").unwrap();
    let mut n = 0;
    for (ours, theirs) in lines.zip(reference.lines().skip(1)) {
        let ours: Vec<&str> = ours.split(',').collect();
        let theirs: Vec<&str> = theirs.split(',').collect();
        assert_eq!(ours[0], theirs[0], "case_id copied through");
        let (mu2, reference): (f64, f64) =
            (ours[1].parse().unwrap(), theirs[mu2_col].parse().unwrap());
        let err = if reference == 0.0 {
            mu2.abs()
        } else {
            ((mu2 - reference) / reference).abs()
        };
        assert!(err < 1e-13, "case {}: {mu2} vs {reference}", ours[0]);
        assert_eq!(ours[4], "", "no error");
        n += 1;
    }
    assert_eq!(n, 305);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn overlap_criterion_writes_only_the_verdict() {
    let output = ellipack()
        .args(["contact", "--criterion", "overlap"])
        .output()
        .unwrap();
    // One example pair is not positive definite: the documented status of failed rows.
    assert_eq!(output.status.code(), Some(3));
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(text.starts_with("case_id,overlap,error\n"));
    assert!(text.contains("\nunit-spheres-apart,false,\n"));
    assert!(text.contains("\npaper-shape-overlapping,true,\n"));
}

#[test]
fn malformed_file_is_an_error_naming_the_line() {
    let dir = temp_dir("malformed");
    let input = dir.join("bad.csv");
    let header = ellipack::pairs::PAIR_COLUMNS.join(",");
    std::fs::write(&input, format!("{header}\n1,2\n")).unwrap();
    let output = ellipack()
        .args(["contact", "--input"])
        .arg(&input)
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8(output.stderr).unwrap();
    assert!(stderr.contains("bad.csv: line 2"), "{stderr}");
    std::fs::write(&input, "r12_x,r12_y\n1,2\n").unwrap();
    let output = ellipack()
        .args(["contact", "--input"])
        .arg(&input)
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8(output.stderr).unwrap();
    assert!(stderr.contains("missing r12_z"), "{stderr}");
    let output = ellipack()
        .args(["contact", "--input", "/no/such/file.csv"])
        .output()
        .unwrap();
    assert!(!output.status.success());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Relative error, or absolute error where the reference is below 1e-2 (the bound of the
/// measure issue: 1e-12 relative, 1e-14 absolute).
fn within(value: f64, reference: f64) -> bool {
    if reference.abs() < 1e-2 {
        (value - reference).abs() <= 1e-14
    } else {
        ((value - reference) / reference).abs() <= 1e-12
    }
}

#[test]
fn measure_accepts_both_reference_files_as_they_are() {
    for (file, x_columns) in [("blm_3d.csv", 3), ("blm_2d.csv", 2)] {
        let reference = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/reference")
            .join(file);
        let output = ellipack()
            .args(["measure", "--input"])
            .arg(&reference)
            .output()
            .unwrap();
        assert!(
            output.status.success(),
            "{file}: {}",
            String::from_utf8_lossy(&output.stderr)
        );
        let results = String::from_utf8(output.stdout).unwrap();
        let reference = std::fs::read_to_string(&reference).unwrap();
        let mut lines = results.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(header.len(), 7 + x_columns, "{header:?}");
        let ref_header: Vec<&str> = reference.lines().next().unwrap().split(',').collect();
        let col = |name: &str| ref_header.iter().position(|h| *h == name).unwrap();
        let (u, d2, f) = (col("U"), col("d2"), col("f"));
        let mut n = 0;
        for (ours, theirs) in lines.zip(reference.lines().skip(1)) {
            let ours: Vec<&str> = ours.split(',').collect();
            let theirs: Vec<&str> = theirs.split(',').collect();
            assert_eq!(ours[0], theirs[0], "{file}: case_id copied through");
            let num = |s: &str| s.parse::<f64>().unwrap();
            assert!(
                within(num(ours[1]), num(theirs[u])),
                "{file} case {}: U",
                ours[0]
            );
            assert!(
                within(num(ours[2]), num(theirs[d2])),
                "{file} case {}: d2",
                ours[0]
            );
            assert_eq!(
                num(ours[4]) > 0.0,
                num(theirs[f]) > 0.0,
                "{file} case {}: verdict",
                ours[0]
            );
            assert_eq!(ours[5], (num(theirs[f]) > 0.0).to_string());
            assert_eq!(
                *ours.last().unwrap(),
                "",
                "{file} case {}: no error",
                ours[0]
            );
            n += 1;
        }
        assert!(n > 100, "{file}: {n} rows");
    }
}

#[test]
fn pack_writes_a_certified_packing_that_verify_accepts() {
    let dir = temp_dir("pack");
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        "dimension = 3\nseed = 2\n[container]\nkind = \"ball\"\n[[shapes]]\ncount = 6\n\
         semi_axes = [1.0, 0.75, 0.5]\n[solver]\ntime_limit = 30.0\nlocal_minimisations = 2\n\
         threads = 1\n",
    )
    .unwrap();
    let out = dir.join("out");
    let run = ellipack()
        .arg("pack")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for file in [
        "packing.csv",
        "summary.json",
        "packing.xyz",
        "packing.svg",
        "packing.png",
    ] {
        let len = std::fs::metadata(out.join(file))
            .map(|m| m.len())
            .unwrap_or(0);
        assert!(len > 0, "{file} missing or empty");
    }
    let summary = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(summary.contains("\"overlapping_pairs\": 0"), "{summary}");
    assert!(
        summary.contains("\"containment_violations\": 0"),
        "{summary}"
    );
    assert!(
        summary.contains("\"dilation\"") && summary.contains("\"density_before\""),
        "the repair is recorded: {summary}"
    );
    let verify = ellipack().arg("verify").arg(&out).output().unwrap();
    let text = String::from_utf8(verify.stdout).unwrap();
    assert!(
        verify.status.success() && text.contains("certified"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn pack_rejects_a_bad_scene_naming_key_and_line() {
    let dir = temp_dir("badscene");
    let scene = dir.join("bad.toml");
    std::fs::write(
        &scene,
        "dimension = 2\n[container]\nkind = \"ellipse\"\n[[shapes]]\ncount = 3\nsemi_axes = [2.0, -1.0]\n",
    )
    .unwrap();
    let run = ellipack()
        .arg("pack")
        .arg(&scene)
        .arg("--out")
        .arg(dir.join("o"))
        .output()
        .unwrap();
    assert!(!run.status.success());
    let stderr = String::from_utf8(run.stderr).unwrap();
    assert!(
        stderr.contains("bad.toml: line 6") && stderr.contains("semi_axes"),
        "{stderr}"
    );
    let run = ellipack()
        .args(["pack", "--instance", "no-such"])
        .output()
        .unwrap();
    assert!(!run.status.success());
    assert!(
        String::from_utf8(run.stderr)
            .unwrap()
            .contains("unknown instance")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[cfg(unix)]
#[test]
fn ctrl_c_writes_the_best_packing_so_far() {
    let dir = temp_dir("sigint");
    let out = dir.join("out");
    let child = ellipack()
        .args([
            "pack",
            "--instance",
            "ball-100",
            "--time-limit",
            "120",
            "--threads",
            "1",
            "--out",
        ])
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Long enough for the first local minimisation to be under way.
    std::thread::sleep(std::time::Duration::from_secs(3));
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let output = child.wait_with_output().unwrap();
    let text = String::from_utf8(output.stdout).unwrap();
    assert!(output.status.success(), "{text}");
    assert!(text.contains("(interrupted)"), "{text}");
    let verify = ellipack().arg("verify").arg(&out).output().unwrap();
    assert!(
        verify.status.success(),
        "{}",
        String::from_utf8_lossy(&verify.stdout)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
