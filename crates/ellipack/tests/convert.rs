//! `ellipack convert`: the files for other programs from a packing folder, the formats chosen
//! by name, and bad folders or names refused with a message.

mod common;
use common::{assert_success, ellipack, names, temp_dir};
use ellipack::packing::{self, CertificateCounts, Summary};

fn folder(name: &str) -> common::TempDir {
    let dir = temp_dir(name);
    let p = common::ellipsoids(2, false, 5);
    let summary = Summary::new(
        &p,
        p.container().measure(),
        1.0,
        1,
        CertificateCounts {
            overlapping_pairs: 0,
            containment_violations: 0,
            min_mu2: Some(1.5),
        },
    );
    packing::write_files(&dir, &p, &summary, false).unwrap();
    dir
}

#[test]
fn convert_writes_every_format_or_the_ones_named() {
    let dir = folder("convert-all");
    let run = ellipack().arg("convert").arg(&dir).output().unwrap();
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
    let run = ellipack()
        .args(["convert", "--formats", "lammps,obj"])
        .arg(&dir)
        .output()
        .unwrap();
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
    let run = ellipack()
        .args(["convert", "--formats", "lammps,vtk"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(said.contains("`vtk` is not a file format"), "{said}");
    assert_eq!(names(&dir), ["packing.csv", "summary.json"]);

    let run = ellipack()
        .arg("convert")
        .arg(dir.join("nothing"))
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(said.contains("nothing: not a packing folder"), "{said}");

    std::fs::remove_file(dir.join("summary.json")).unwrap();
    let run = ellipack().arg("convert").arg(&dir).output().unwrap();
    assert_eq!(run.status.code(), Some(1));
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(said.contains("summary.json"), "{said}");
    assert_eq!(names(&dir), ["packing.csv"]);
}
