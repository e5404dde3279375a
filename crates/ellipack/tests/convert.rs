//! `ellipack convert`: the files for other programs from a packing folder, the formats chosen
//! by name, and bad folders or names refused with a message.

mod common;
use common::{assert_success, ellipack, names, packing_folder, temp_dir};
use std::path::Path;
use std::process::Output;

fn folder(name: &str) -> common::TempDir {
    let dir = temp_dir(name);
    let p = common::ellipsoids(2, false, 5);
    ellipack::folder::write_files(&dir, &p, &common::certified_summary(&p), false).unwrap();
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

/// A hand-made periodic folder with an unreduced cell (xy = 25 with l_x = 10) and an item
/// outside it: the files state the reduced cell (|xy| ≤ l_x / 2) with every atom inside.
#[test]
fn convert_reduces_the_cell_and_wraps_the_items() {
    let dir = packing_folder(
        "convert-unreduced",
        "id,x,y,a,b,theta\n0,1,1,1,1,0\n1,38,4.5,1,1,0\n",
        r#"{"container": {"kind": "periodic", "origin": [0, 0], "lengths": [10, 8],
            "tilts": [25]}, "items": 2, "density": 0.07854, "objective": 80,
            "wall_seconds": 0, "local_minimisations": 0, "certificate": {"overlapping_pairs": 0,
            "containment_violations": 0, "min_mu2": null}}"#,
    );
    assert_success(&convert(&["--formats", "lammps"], &dir));
    let data = std::fs::read_to_string(dir.join("packing.data")).unwrap();
    let xy: f64 = data
        .lines()
        .find(|l| l.ends_with("xy xz yz"))
        .and_then(|l| l.split_whitespace().next())
        .unwrap()
        .parse()
        .unwrap();
    // The same lattice: xy changes by a multiple of l_x.
    assert!(
        xy.abs() <= 5.0 && ((xy - 25.0) / 10.0).fract() == 0.0,
        "{data}"
    );
    let back = ellipack::lammps::read_lammps_data(&data, "packing.data").unwrap();
    assert_eq!(back.tilt[0], xy);
    let [x_lo, y_lo] = [back.bounds[0][0], back.bounds[1][0]];
    let [lx, ly] = [back.bounds[0][1] - x_lo, back.bounds[1][1] - y_lo];
    for (id, _, _, _, p) in &back.atoms {
        // Fractional coordinates in the reduced cell (edges a = (l_x, 0), b = (xy, l_y)).
        let sy = (p[1] - y_lo) / ly;
        let sx = (p[0] - x_lo - sy * back.tilt[0]) / lx;
        assert!(
            (0.0..1.0).contains(&sx) && (0.0..1.0).contains(&sy),
            "atom {id}: {sx}, {sy}"
        );
    }
    assert_success(&ellipack().arg("verify").arg(&dir).output().unwrap());
}

/// `convert OUT/unfinished` is refused (its files would start a simulation from overlapping
/// items) unless asked for with --unfinished.
#[test]
fn convert_refuses_an_unfinished_configuration_unless_asked() {
    let dir = packing_folder(
        "convert-unfinished",
        "id,x,y,a,b,theta\n0,0,0,1,1,0\n1,1,0,1,1,0\n",
        r#"{"container": {"kind": "circle", "center": [0, 0], "radius": 3}, "items": 2,
            "density": 0.2222, "objective": 28.27, "wall_seconds": 1, "local_minimisations": 1,
            "certificate": {"overlapping_pairs": 1, "containment_violations": 0,
            "min_mu2": 0.25}, "not_reached": true}"#,
    );
    let run = convert(&[], &dir);
    let said = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{said}");
    assert!(
        said.contains("not a packing") && said.contains("--unfinished"),
        "{said}"
    );
    assert!(!dir.join("packing.data").exists());
    assert_success(&convert(&["--unfinished"], &dir));
    assert!(dir.join("packing.data").is_file());
}

/// `convert --pictures` draws the pictures that a run left out.
#[test]
fn convert_draws_the_pictures_when_asked() {
    let dir = folder("convert-pictures");
    assert_success(&convert(&["--pictures", "--formats", "xyz"], &dir));
    let listing = names(&dir);
    assert!(
        listing.contains(&"packing.png".to_string())
            && listing.contains(&"packing.svg".to_string()),
        "{listing:?}"
    );
}
