//! `ellipack convert`: the files for other programs from a packing folder, the formats chosen
//! by name, and bad folders or names refused with a message.

mod common;
use common::{assert_success, ellipack, names, temp_dir};
use ellipack::packing;
use std::path::Path;
use std::process::Output;

fn folder(name: &str) -> common::TempDir {
    let dir = temp_dir(name);
    let p = common::ellipsoids(2, false, 5);
    packing::write_files(&dir, &p, &common::certified_summary(&p), false).unwrap();
    dir
}

/// `ellipack convert <options> <dir>`, run to its end.
fn convert(options: &[&str], dir: &Path) -> Output {
    ellipack()
        .arg("convert")
        .args(options)
        .arg(dir)
        .output()
        .unwrap()
}

#[test]
fn convert_writes_every_format_or_the_ones_named() {
    let dir = folder("convert-all");
    let run = convert(&[], &dir);
    assert_success(&run);
    let said = String::from_utf8_lossy(&run.stdout);
    assert!(said.contains("8 ellipsoids in a cuboid container: wrote packing.data, packing.gsd, packing.xyz, container.obj"), "{said}");
    assert_eq!(
        names(&dir),
        [
            "container.obj",
            "packing.csv",
            "packing.data",
            "packing.gsd",
            "packing.xyz",
            "summary.json"
        ]
    );

    let dir = folder("convert-some");
    let run = convert(&["--formats", "lammps,obj"], &dir);
    assert_success(&run);
    assert_eq!(
        names(&dir),
        [
            "container.obj",
            "packing.csv",
            "packing.data",
            "summary.json"
        ]
    );
}

#[test]
fn convert_refuses_bad_names_and_folders() {
    let dir = folder("convert-bad");
    let run = convert(&["--formats", "lammps,vtk"], &dir);
    assert_eq!(run.status.code(), Some(2));
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(said.contains("`vtk` is not a file format"), "{said}");
    assert_eq!(names(&dir), ["packing.csv", "summary.json"]);

    let run = convert(&[], &dir.join("nothing"));
    assert_eq!(run.status.code(), Some(1));
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(said.contains("nothing: not a packing folder"), "{said}");

    std::fs::remove_file(dir.join("summary.json")).unwrap();
    let run = convert(&[], &dir);
    assert_eq!(run.status.code(), Some(1));
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(said.contains("summary.json"), "{said}");
    assert_eq!(names(&dir), ["packing.csv"]);
}
