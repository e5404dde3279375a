//! `ellipack contact` and `measure` as a script sees them: what they read, where they write,
//! and the exit status.

use std::io::{BufRead, BufReader, Read};
use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::Path;
use std::process::{Command, Stdio};

mod common;
use common::{ellipack, folder_with, is_symlink, names, on_input, run, temp_dir, utf8};

const HEADER_3D: &str =
    "case_id,r12_x,r12_y,r12_z,q1_0,q1_1,q1_2,q1_3,q1_4,q1_5,q2_0,q2_1,q2_2,q2_3,q2_4,q2_5";

/// Runs `ellipack <command>` on `input`, which must fail with status 1 (the command failed);
/// its standard error, which must be UTF-8.
fn refused_on(command: &str, input: &Path) -> String {
    let out = on_input(&[command], input);
    assert_eq!(out.status.code(), Some(1));
    utf8(out.stderr)
}

fn pairs_3d(rows: usize) -> String {
    let mut text = format!("{HEADER_3D}\n");
    for i in 0..rows {
        text.push_str(&format!("{i},3,0,0,1,0,0,1,0,1,1,0,0,1,0,1\n"));
    }
    text
}

fn contact(input: &Path, output: &Path) -> std::process::Output {
    write_to("contact", input, output)
}

/// `ellipack <command> --input <input> --output <output>`, run to its end.
fn write_to(command: &str, input: &Path, output: &Path) -> std::process::Output {
    ellipack()
        .args([command, "--input"])
        .arg(input)
        .arg("--output")
        .arg(output)
        .output()
        .unwrap()
}

#[test]
fn a_2d_file_goes_through_the_2d_kernel() {
    let (_dir, input) = folder_with(
        "2d",
        "ellipses.csv",
        "q2_2,case_id,r12_x,r12_y,q1_0,q1_1,q1_2,q2_0,q2_1,note\n\
         1,apart,3,0,4,0,1,1,0,x\n\
         1,close,1,0.5,4,1,1,1,0,y\n",
    );
    let output = on_input(&["contact"], &input);
    assert_eq!(output.status.code(), Some(0), "{output:?}");
    let text = utf8(output.stdout);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "case_id,mu2,lambda,overlap,error");
    for (line, (id, r12, q1)) in lines[1..].iter().zip([
        ("apart", [3.0, 0.0], [4.0, 0.0, 1.0]),
        ("close", [1.0, 0.5], [4.0, 1.0, 1.0]),
    ]) {
        let c = pw85::contact_function(&r12, &q1, &[1.0, 0.0, 1.0]).unwrap();
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(fields[0], id);
        assert_eq!(fields[1].parse::<f64>().unwrap(), c.mu2, "{line}");
        assert_eq!(fields[2].parse::<f64>().unwrap(), c.lambda, "{line}");
        assert_eq!(fields[3], (c.mu2 < 1.0).to_string());
        assert_eq!(fields[4], "");
    }
    let output = on_input(&["contact", "--criterion", "overlap"], &input);
    assert_eq!(
        utf8(output.stdout),
        "case_id,overlap,error\napart,false,\nclose,true,\n"
    );
    std::fs::write(
        &input,
        "r12_x,r12_y,r12_z,q1_0,q1_1,q1_2,q2_0,q2_1,q2_2\n1,0,0,1,0,1,1,0,1\n",
    )
    .unwrap();
    let stderr = refused_on("contact", &input);
    assert!(
        stderr.contains("line 1") && stderr.contains("missing q1_3") && stderr.contains("r12_z"),
        "{stderr}"
    );
}

#[test]
fn the_output_may_not_be_the_input() {
    let text = pairs_3d(2);
    let (dir, input) = folder_with("same", "pairs.csv", &text);
    std::os::unix::fs::symlink(&input, dir.join("link.csv")).unwrap();
    std::fs::hard_link(&input, dir.join("hard.csv")).unwrap();
    let dotted = dir.join(".").join("pairs.csv");
    for output in [
        input.clone(),
        dotted,
        dir.join("link.csv"),
        dir.join("hard.csv"),
    ] {
        for command in ["contact", "measure"] {
            let out = write_to(command, &input, &output);
            assert_eq!(out.status.code(), Some(1), "{command} {output:?}");
            let stderr = utf8(out.stderr);
            assert!(stderr.contains("is the input file"), "{stderr}");
            assert_eq!(std::fs::read_to_string(&input).unwrap(), text, "untouched");
        }
    }
    assert_eq!(names(&dir), ["hard.csv", "link.csv", "pairs.csv"]);
}

#[test]
fn dev_null_stays_a_character_device() {
    let out = run(&["contact", "--output", "/dev/null"]);
    assert_eq!(out.status.code(), Some(3), "one example row fails");
    let kind = std::fs::metadata("/dev/null").unwrap().file_type();
    assert!(kind.is_char_device(), "/dev/null is still a device");
}

#[test]
fn dev_stdout_is_written_through() {
    let (dir, input) = folder_with("stdout", "pairs.csv", pairs_3d(3));
    let out = on_input(&["contact", "--output", "/dev/stdout"], &input);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(utf8(out.stdout).lines().count(), 4);
    // Standard output redirected to a file: the file receives the table, and is not replaced.
    let target = dir.join("redirected.csv");
    let file = std::fs::File::create(&target).unwrap();
    let status = ellipack()
        .args(["contact", "--output", "/dev/stdout", "--input"])
        .arg(&input)
        .stdout(file)
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    assert_eq!(std::fs::read_to_string(&target).unwrap().lines().count(), 4);
    assert_eq!(names(&dir), ["pairs.csv", "redirected.csv"]);
    // The same for standard error, whose file also receives the messages.
    let file = std::fs::File::create(&target).unwrap();
    let status = ellipack()
        .args(["contact", "--output", "/dev/stderr", "--input"])
        .arg(&input)
        .stderr(file)
        .status()
        .unwrap();
    assert!(status.success());
    let text = std::fs::read_to_string(&target).unwrap();
    assert!(
        text.starts_with("case_id,") && text.contains("wrote 3 rows to /dev/stderr"),
        "{text}"
    );
    assert_eq!(names(&dir), ["pairs.csv", "redirected.csv"]);
}

#[test]
fn a_fifo_is_written_into() {
    let (dir, input) = folder_with("fifo", "pairs.csv", pairs_3d(5));
    let fifo = dir.join("results.fifo");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut text = String::new();
            std::fs::File::open(&fifo)
                .unwrap()
                .read_to_string(&mut text)
                .unwrap();
            text
        })
    };
    let out = contact(&input, &fifo);
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    let text = reader.join().unwrap();
    assert!(
        text.starts_with("case_id,mu2,lambda,overlap,error\n0,"),
        "{text}"
    );
    assert_eq!(text.lines().count(), 6);
    assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    assert_eq!(names(&dir), ["pairs.csv", "results.fifo"]);
}

#[test]
fn a_symlink_is_kept_and_its_target_written() {
    let (dir, input) = folder_with("symlink", "pairs.csv", pairs_3d(2));
    std::fs::create_dir(dir.join("store")).unwrap();
    let target = dir.join("store").join("results.csv");
    std::fs::write(&target, "old").unwrap();
    let link = dir.join("latest.csv");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let out = contact(&input, &link);
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    assert!(is_symlink(&link));
    assert_eq!(std::fs::read_to_string(&target).unwrap().lines().count(), 3);
    assert_eq!(names(&dir.join("store")), ["results.csv"]);
    // A link to a file not written yet: the file appears where the link points.
    let fresh = dir.join("store").join("fresh.csv");
    let dangling = dir.join("dangling.csv");
    std::os::unix::fs::symlink("store/fresh.csv", &dangling).unwrap();
    let out = contact(&input, &dangling);
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    assert!(is_symlink(&dangling));
    assert_eq!(std::fs::read_to_string(&fresh).unwrap().lines().count(), 3);
}

#[test]
fn a_replaced_file_keeps_its_mode() {
    let (dir, input) = folder_with("mode", "pairs.csv", pairs_3d(2));
    let output = dir.join("results.csv");
    std::fs::write(&output, "old").unwrap();
    std::fs::set_permissions(&output, std::fs::Permissions::from_mode(0o640)).unwrap();
    let out = contact(&input, &output);
    assert_eq!(out.status.code(), Some(0), "{out:?}");
    assert_eq!(std::fs::read_to_string(&output).unwrap().lines().count(), 3);
    let mode = std::fs::metadata(&output).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o640);
}

#[test]
fn a_failure_midway_leaves_no_temporary_file_and_the_old_output() {
    let dir = temp_dir("midway");
    let input = dir.join("pairs.csv");
    // Rows enough for several chunks to be written before the broken row is reached.
    let mut text = pairs_3d(20_000);
    text.push_str("broken,1,2\n");
    std::fs::write(&input, text).unwrap();
    let output = dir.join("results.csv");
    std::fs::write(&output, "old").unwrap();
    let out = contact(&input, &output);
    assert_eq!(out.status.code(), Some(1));
    let stderr = utf8(out.stderr);
    assert!(stderr.contains("line 20002"), "{stderr}");
    assert_eq!(std::fs::read_to_string(&output).unwrap(), "old");
    assert_eq!(names(&dir), ["pairs.csv", "results.csv"]);
}

#[test]
fn a_closed_pipe_ends_quietly() {
    let dir = temp_dir("pipe");
    let input = dir.join("pairs.csv");
    // Far more than a pipe's buffer: the writer is still writing when the reader leaves.
    std::fs::write(&input, pairs_3d(100_000)).unwrap();
    for criterion in ["contact", "overlap"] {
        let mut child = ellipack()
            .args(["contact", "--criterion", criterion, "--input"])
            .arg(&input)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut first = String::new();
        let stdout = child.stdout.take().unwrap();
        BufReader::new(stdout).read_line(&mut first).unwrap();
        // The reader and the pipe's read end are dropped here.
        assert!(first.starts_with("case_id,"), "{first}");
        let out = child.wait_with_output().unwrap();
        let stderr = utf8(out.stderr);
        assert_eq!(out.status.code(), Some(0), "{stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

#[test]
fn duplicate_columns_are_errors_naming_the_column() {
    let (_dir, input) = folder_with(
        "duplicate",
        "pairs.csv",
        format!("{HEADER_3D},q1_4\n0,3,0,0,1,0,0,1,0,1,1,0,0,1,0,1,7\n"),
    );
    let stderr = refused_on("contact", &input);
    assert!(
        stderr.contains("column `q1_4` appears twice in the header (columns 9 and 17)"),
        "{stderr}"
    );
    let header = ellipack::measure::COLUMNS_2D.join(",");
    std::fs::write(&input, format!("{header},theta_j\n0,0,1,1,0,3,0,1,1,0,1\n")).unwrap();
    let stderr = refused_on("measure", &input);
    assert!(
        stderr.contains("column `theta_j` appears twice"),
        "{stderr}"
    );
}

#[test]
fn the_exit_status_says_whether_rows_failed() {
    let (_dir, input) = folder_with("status", "pairs.csv", pairs_3d(3));
    let status = |command: &str| on_input(&[command], &input).status.code();
    assert_eq!(status("contact"), Some(0), "every row fine");
    std::fs::write(
        &input,
        format!("{HEADER_3D}\na,3,0,0,1,0,0,1,0,1,1,0,0,1,0,1\nb,3,0,0,-1,0,0,1,0,1,1,0,0,1,0,1\n"),
    )
    .unwrap();
    assert_eq!(
        status("contact"),
        Some(3),
        "a row failed, the others written"
    );
    std::fs::write(&input, format!("{HEADER_3D}\n")).unwrap();
    assert_eq!(status("contact"), Some(1), "the command failed");
    let header = ellipack::measure::COLUMNS_2D.join(",");
    std::fs::write(&input, format!("{header}\n0,0,1,1,0,3,0,1,1,0\n")).unwrap();
    assert_eq!(status("measure"), Some(0));
    std::fs::write(
        &input,
        format!("{header}\n0,0,1,1,0,3,0,1,1,0\n0,0,-1,1,0,3,0,1,1,0\n"),
    )
    .unwrap();
    assert_eq!(status("measure"), Some(3));
    std::fs::write(&input, "nothing,here\n1,2\n").unwrap();
    assert_eq!(status("measure"), Some(1));
    let help = run(&["contact", "--help"]);
    let help = utf8(help.stdout);
    assert!(help.contains("Exit status") && help.contains("3"), "{help}");
}
