//! Periodic cells through the command line: `kind = "periodic"` packs 2D and 3D cells to the
//! known densest lattice packings, `verify` re-checks every image, the files carry the cell
//! (triclinic LAMMPS box, `pbc` in extended XYZ), and a cell shrunk by hand is refused with
//! the item that overlaps its own image named.

use std::path::{Path, PathBuf};

mod common;
use common::{ellipack, pack_into, summary_json, temp_dir, text, verify_periodic};

/// A periodic scene of `count` items with the given semi-axes, one thread, its work bounded by
/// local minimisations (the time limit is far beyond it, so a slow machine ends alike).
fn scene(dir: &Path, count: usize, axes: &str, extra: &str) -> PathBuf {
    let dimension = axes.split(',').count();
    let path = dir.join("scene.toml");
    std::fs::write(
        &path,
        format!(
            "dimension = {dimension}\nseed = 3\n[container]\nkind = \"periodic\"\n{extra}\
             [[shapes]]\ncount = {count}\nsemi_axes = [{axes}]\n[solver]\ntime_limit = 600.0\n\
             local_minimisations = 8\nthreads = 1\n[output]\npictures = false\n"
        ),
    )
    .unwrap();
    path
}

fn pack_and_verify(count: usize, axes: &str, extra: &str) -> (f64, PathBuf, common::TempDir) {
    let dir = temp_dir(&format!("periodic-{count}-{}", axes.len()));
    let scene = scene(&dir, count, axes, extra);
    let out = dir.join("out");
    let o = pack_into(&scene, &out);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let v = ellipack().arg("verify").arg(&out).output().unwrap();
    assert!(v.status.success(), "{}", text(&v.stdout));
    let s = summary_json(&out);
    assert_eq!(s["container"]["kind"], "periodic");
    (s["density"].as_f64().unwrap(), out, dir)
}

/// Packs and verifies as [`pack_and_verify`], asserts that the density is `optimum` (to
/// 1e-4, never above it) and that packing.xyz is periodic along the axes `pbc` says; returns
/// the output folder, the test folder and packing.xyz.
fn reaches(
    optimum: f64,
    pbc: &str,
    count: usize,
    axes: &str,
    extra: &str,
) -> (PathBuf, common::TempDir, String) {
    let (density, out, dir) = pack_and_verify(count, axes, extra);
    assert!(
        density >= optimum * (1.0 - 1e-4) && density <= optimum * (1.0 + 1e-9),
        "{density}"
    );
    let xyz = std::fs::read_to_string(out.join("packing.xyz")).unwrap();
    assert!(xyz.contains(&format!("pbc=\"{pbc}\"")), "{xyz}");
    (out, dir, xyz)
}

#[test]
fn ellipses_reach_the_hexagonal_density_and_the_files_carry_the_cell() {
    let hexagonal = std::f64::consts::PI / 12f64.sqrt();
    let cell = "cell = \"variable\"\n";
    let (out, _dir, xyz) = reaches(hexagonal, "T T F", 4, "2.0, 1.0", cell);
    assert!(xyz.contains("container=periodic"), "{xyz}");
    let data = std::fs::read_to_string(out.join("packing.data")).unwrap();
    assert!(data.contains("xy xz yz"), "{data}");
}

#[test]
fn spheres_reach_the_fcc_density() {
    let fcc = std::f64::consts::PI / 18f64.sqrt();
    reaches(fcc, "T T T", 2, "1.0, 1.0, 1.0", "");
}

#[test]
fn a_shrunk_cell_is_refused_naming_the_item_and_its_image() {
    let (_, out, _dir) = pack_and_verify(1, "1.0, 1.0", "");
    let path = out.join("summary.json");
    let mut s = summary_json(&out);
    let lengths = s["container"]["lengths"].as_array().unwrap().clone();
    let shrunk: Vec<f64> = lengths.iter().map(|v| v.as_f64().unwrap() * 0.9).collect();
    s["container"]["lengths"] = serde_json::json!(shrunk);
    std::fs::write(&path, serde_json::to_string_pretty(&s).unwrap()).unwrap();
    let v = ellipack().arg("verify").arg(&out).output().unwrap();
    let said = text(&v.stdout) + &text(&v.stderr);
    assert!(!v.status.success(), "{said}");
    assert!(said.contains("overlapping"), "{said}");
    assert!(
        said.contains("0 and 0") || said.contains("(0, 0)"),
        "{said}"
    );
}

#[test]
fn a_cell_key_outside_a_periodic_container_is_refused() {
    let dir = temp_dir("periodic-bad-cell");
    let path = dir.join("scene.toml");
    for (kind, cell, size, expected) in [
        (
            "circle",
            "variable",
            "",
            "only a periodic container has a cell",
        ),
        ("periodic", "elastic", "", "must be \"variable\""),
        ("periodic", "fixed", "", "a fixed cell needs its size"),
        (
            "periodic",
            "variable",
            "lengths = [4.0, 4.0]\n",
            "a variable cell has no lengths",
        ),
    ] {
        std::fs::write(
            &path,
            format!(
                "dimension = 2\n[container]\nkind = \"{kind}\"\ncell = \"{cell}\"\n{size}\
                 [[shapes]]\ncount = 2\nsemi_axes = [1.0, 1.0]\n"
            ),
        )
        .unwrap();
        let o = ellipack().arg("pack").arg(&path).output().unwrap();
        let said = text(&o.stderr);
        assert!(!o.status.success());
        assert!(said.contains("line 4"), "{said}");
        assert!(said.contains(expected), "{said}");
    }
}

/// A fixed periodic cell, given by its lengths or by a packing fraction, is filled and kept:
/// the packing's cell is the scene's, the density the fraction asked for.
#[test]
fn fixed_cells_are_filled_and_kept() {
    for (size, n, lengths) in [
        ("lengths = [12.0, 10.0]\n", 2, Some(vec![12.0, 10.0])),
        ("packing_fraction = 0.55\n", 3, None),
    ] {
        let axes = if n == 2 { "2.0, 1.0" } else { "1.0, 0.75, 0.5" };
        let extra = format!("cell = \"fixed\"\n{size}");
        let (density, out, _dir) = pack_and_verify(12, axes, &extra);
        let s = summary_json(&out);
        let got: Vec<f64> = s["container"]["lengths"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let tilts = s["container"]["tilts"].as_array().unwrap();
        assert!(tilts.iter().all(|t| t.as_f64() == Some(0.0)), "{tilts:?}");
        match lengths {
            Some(l) => {
                assert_eq!(got, l);
                let area = 12.0 * std::f64::consts::PI * 2.0;
                assert!((density - area / 120.0).abs() < 1e-12, "{density}");
            }
            None => {
                assert!((density - 0.55).abs() < 1e-12, "{density}");
                assert!(got.iter().all(|&v| v == got[0]), "a cube: {got:?}");
            }
        }
    }
}

/// Unit spheres in a fixed periodic cube at 0.45 and 0.68: a body-centred cubic lattice holds
/// them (density 0.6802), so the run starts from a packing and needs no solver work.
#[test]
fn fixed_cells_a_lattice_fills_start_as_packings() {
    for (count, fraction) in [(2, 0.45), (16, 0.45), (16, 0.68)] {
        let extra = format!("cell = \"fixed\"\npacking_fraction = {fraction}\n");
        let (density, out, _dir) = pack_and_verify(count, "1.0, 1.0, 1.0", &extra);
        assert!((density - fraction).abs() < 1e-12, "{density}");
        assert_eq!(
            summary_json(&out)["start_kept"],
            true,
            "{count} at {fraction}"
        );
    }
}

/// Items long against their width ((8, 1, 1) ellipsoids, (40, 1) ellipses) pack in a
/// variable cell: the lattice start of one such item, a cell thinner than the item's reach
/// that was once refused, is used, and small cells of the tiled start that cannot be held are
/// skipped. One local minimisation each keeps the test short.
#[test]
fn elongated_items_pack_in_a_variable_cell() {
    let dir = temp_dir("periodic-elongated");
    for axes in ["8.0, 1.0, 1.0", "40.0, 1.0"] {
        let path = scene(&dir, 1, axes, "cell = \"variable\"\n");
        let text_of = std::fs::read_to_string(&path).unwrap();
        let one = text_of.replace("local_minimisations = 8", "local_minimisations = 1");
        assert_ne!(one, text_of);
        std::fs::write(&path, one).unwrap();
        let out = dir.join("out");
        let o = pack_into(&path, &out);
        assert!(o.status.success(), "({axes}): {}", text(&o.stderr));
        let v = ellipack().arg("verify").arg(&out).output().unwrap();
        assert!(v.status.success(), "{}", text(&v.stdout));
        let density = summary_json(&out)["density"].as_f64().unwrap();
        assert!(density > 0.74, "({axes}): {density}");
    }
}

/// A fixed cell far smaller than its items (a units typo: 0.07 for unit discs) is refused at
/// once: by `pack` when the scene is read (the items' area is 32057 times the cell's), by
/// `verify` before any image is made, naming how many times their enclosing balls cover it.
#[test]
fn a_cell_far_smaller_than_its_items_is_refused_at_once() {
    let dir = temp_dir("periodic-tiny");
    let tiny_cell = "cell = \"fixed\"\nlengths = [0.07, 0.07]\n";
    let path = scene(&dir, 50, "1.0, 1.0", tiny_cell);
    let o = pack_into(&path, &dir.join("out"));
    let said = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{said}");
    // Read from the scene: the items' area is that many times the cell's.
    assert!(
        said.contains("container.lengths") && said.contains("32057."),
        "{said}"
    );
    // 2 001 items, and 51 (whose pairs were once all checked, for 78 s): refused at once.
    let packing = dir.join("packing.csv");
    for (rows, step) in [(2001, 1e-5), (51, 1e-3)] {
        let mut csv = String::from("id,x,y,a,b,theta\n");
        for i in 0..rows {
            csv.push_str(&format!("{i},{},{},1,1,0\n", f64::from(i) * step, 0.03));
        }
        std::fs::write(&packing, csv).unwrap();
        let v = verify_periodic(&packing, "0.07,0.07");
        let said = text(&v.stdout) + &text(&v.stderr);
        assert_eq!(v.status.code(), Some(1), "{rows} rows: {said}");
        assert!(said.contains("times over"), "{rows} rows: {said}");
    }
}

/// `verify --container periodic` takes the cell of the packing's dimension: its lengths, with
/// or without tilts, in 2D and in 3D.
#[test]
fn verify_takes_a_periodic_cell_of_either_dimension() {
    let dir = temp_dir("periodic-verify-given");
    let cases = [
        ("id,x,y,a,b,theta\n0,0,0,1,1,0\n1,2,2,1,1,0\n", "4,4"),
        ("id,x,y,a,b,theta\n0,0,0,1,1,0\n1,2,2,1,1,0\n", "4,4,0.5"),
        (
            "id,x,y,z,a,b,c,qw,qx,qy,qz\n0,0,0,0,1,1,1,1,0,0,0\n1,2,2,2,1,1,1,1,0,0,0\n",
            "4,4,4",
        ),
        (
            "id,x,y,z,a,b,c,qw,qx,qy,qz\n0,0,0,0,1,1,1,1,0,0,0\n1,2,2,2,1,1,1,1,0,0,0\n",
            "4,4,4,0.5,0,0",
        ),
    ];
    for (csv, size) in cases {
        let packing = dir.join("packing.csv");
        std::fs::write(&packing, csv).unwrap();
        let v = verify_periodic(&packing, size);
        let said = text(&v.stdout) + &text(&v.stderr);
        assert_eq!(v.status.code(), Some(0), "--size {size}: {said}");
        assert!(said.contains("certified"), "{said}");
    }
}

/// The densest known crystal of spheroids of aspect ≥ √3, Donev et al.'s SM2 (two items per
/// cell, density 0.7707, Phys. Rev. Lett. 92, 255506, 2004), from the command line: prolate
/// and oblate spheroids of aspects 2 and 3, two items in a variable cell. The affine
/// face-centred cubic packing (0.7405), where lattice starts stay, is not enough.
#[test]
fn spheroids_reach_the_sm2_crystal() {
    const SM2: f64 = 0.770_73;
    let third = 1.0 / 3.0;
    for axes in [
        "2.0, 1.0, 1.0".to_string(),
        "3.0, 1.0, 1.0".to_string(),
        "1.0, 1.0, 0.5".to_string(),
        format!("1.0, 1.0, {third:?}"),
    ] {
        let dir = temp_dir("periodic-sm2");
        let path = scene(&dir, 2, &axes, "cell = \"variable\"\n");
        let text_of = std::fs::read_to_string(&path).unwrap();
        let more = text_of.replace("local_minimisations = 8", "local_minimisations = 42");
        std::fs::write(&path, more).unwrap();
        let out = dir.join("out");
        let o = pack_into(&path, &out);
        assert!(o.status.success(), "({axes}): {}", text(&o.stderr));
        let density = summary_json(&out)["density"].as_f64().unwrap();
        assert!(density > SM2 * (1.0 - 1e-4), "({axes}): {density}");
    }
}
