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
    assert!(output.status.success());
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
    assert!(stderr.contains("missing column `r12_z`"), "{stderr}");
    let output = ellipack()
        .args(["contact", "--input", "/no/such/file.csv"])
        .output()
        .unwrap();
    assert!(!output.status.success());
    std::fs::remove_dir_all(&dir).unwrap();
}
