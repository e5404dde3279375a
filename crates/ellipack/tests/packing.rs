//! The packing files: exact round trips through CSV and JSON, an orientation-preserving round
//! trip through XYZ, and errors that name the file, line and column.

mod common;

use ellipack::Error;
use ellipack::packing::Centred;
use ellipack::packing::{self, CertificateCounts, Container, Item, Items, Packing, Summary};
use std::f64::consts::PI;

fn summary_of(p: &Packing) -> Summary {
    Summary::new(
        p,
        p.container().measure(),
        12.25,
        7,
        CertificateCounts {
            overlapping_pairs: 0,
            containment_violations: 0,
            min_mu2: Some(1.000_000_123_456_789),
        },
    )
}

/// Every kind of container, with items of its dimension.
fn every_kind() -> Vec<Packing> {
    let e2 = common::ellipses(4, true, 11);
    let e3 = common::ellipsoids(3, true, 12);
    let containers = [
        Container::plane([0.5, -0.25], Centred::Ball { radius: 40.0 }),
        Container::plane(
            [0.0, 0.0],
            Centred::Ellipsoid {
                semi_axes: [41.5, 40.0 + 1e-13],
            },
        ),
        Container::plane(
            [1.0 / 3.0, 0.0],
            Centred::Box {
                half_sides: [30.0, 31.0],
            },
        ),
        Container::space([0.0, 0.0, 0.0], Centred::Ball { radius: 9.75 }),
        Container::space(
            [1.0, 2.0, 3.0],
            Centred::Ellipsoid {
                semi_axes: [10.0, 11.0, 12.0],
            },
        ),
        Container::space(
            [0.0, -1e-300, 0.0],
            Centred::Box {
                half_sides: [7.0, 7.0, 7.5],
            },
        ),
    ];
    common::filled(containers, &e2, &e3)
}

#[test]
fn csv_and_json_round_trips_are_exact() {
    for p in every_kind() {
        let dir = common::temp_dir(&format!("roundtrip-{}", p.container().kind()));
        let summary = summary_of(&p);
        ellipack::folder::write_files(&dir, &p, &summary, true).unwrap();
        let (p2, s2) = ellipack::folder::read_packing_dir(&dir).unwrap();
        assert_eq!(p2, p, "{}", p.container().kind());
        assert_eq!(s2, summary);
        assert_eq!(common::names(&dir).len(), 3, "only the three files");
    }
}

#[test]
fn the_csv_has_the_documented_columns() {
    let p2 = common::ellipses(2, false, 1);
    let text = ellipack::items_csv::csv_string(p2.items());
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("id,x,y,a,b,theta"));
    let first: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(first[0], "0");
    // 17 significant digits: one before the point, sixteen after.
    let mantissa = first[3].split('e').next().unwrap();
    assert_eq!(mantissa.replace(['.', '-'], "").len(), 17, "{}", first[3]);
    assert_eq!(text.lines().count(), 5);
    let p3 = common::ellipsoids(2, false, 1);
    let text = ellipack::items_csv::csv_string(p3.items());
    assert_eq!(text.lines().next(), Some("id,x,y,z,a,b,c,qw,qx,qy,qz"));
    assert_eq!(text.lines().count(), 9);
}

#[test]
fn the_summary_has_the_documented_keys() {
    let p = &every_kind()[3];
    let json: serde_json::Value =
        serde_json::from_str(&ellipack::summary_json::summary_json(&summary_of(p)).unwrap())
            .unwrap();
    let container = &json["container"];
    assert_eq!(container["kind"], "ball");
    assert_eq!(container["radius"], 9.75);
    assert_eq!(container["center"], serde_json::json!([0.0, 0.0, 0.0]));
    for key in [
        "density",
        "objective",
        "wall_seconds",
        "local_minimisations",
        "items",
    ] {
        assert!(json[key].is_number(), "{key}");
    }
    let certificate = &json["certificate"];
    assert_eq!(certificate["overlapping_pairs"], 0);
    assert_eq!(certificate["containment_violations"], 0);
    assert!(certificate["min_mu2"].is_number());
    let d = json["density"].as_f64().unwrap();
    assert!((d - p.density()).abs() == 0.0);
    let rectangle = &every_kind()[2];
    let json: serde_json::Value = serde_json::from_str(
        &ellipack::summary_json::summary_json(&summary_of(rectangle)).unwrap(),
    )
    .unwrap();
    assert_eq!(
        json["container"]["half_sides"],
        serde_json::json!([30.0, 31.0])
    );
    assert_eq!(json["container"]["kind"], "rectangle");
}

#[test]
fn density_is_item_measure_over_container_measure() {
    let items = Items::Ellipses(vec![Item::ellipse([0.0, 0.0], [2.0, 1.0], 0.3); 3]);
    let circle = Container::plane([0.0, 0.0], Centred::Ball { radius: 4.0 });
    assert!((packing::density(&circle, &items) - 3.0 * 2.0 * PI / (16.0 * PI)).abs() < 1e-15);
    let rectangle = Container::plane(
        [0.0, 0.0],
        Centred::Box {
            half_sides: [3.0, 2.0],
        },
    );
    assert!((packing::density(&rectangle, &items) - 6.0 * PI / 24.0).abs() < 1e-15);
    let items = Items::Ellipsoids(vec![Item::ellipsoid(
        [0.0; 3],
        [1.0, 0.75, 0.5],
        [1.0, 0.0, 0.0, 0.0],
    )]);
    let ball = Container::space([0.0; 3], Centred::Ball { radius: 2.0 });
    assert!((packing::density(&ball, &items) - 0.375 / 8.0).abs() < 1e-15);
    let ellipsoid = Container::space(
        [0.0; 3],
        Centred::Ellipsoid {
            semi_axes: [1.0, 2.0, 3.0],
        },
    );
    assert!((packing::density(&ellipsoid, &items) - 0.375 / 6.0).abs() < 1e-15);
    let cuboid = Container::space(
        [0.0; 3],
        Centred::Box {
            half_sides: [1.0, 1.0, 1.0],
        },
    );
    assert!((packing::density(&cuboid, &items) - 4.0 / 3.0 * PI * 0.375 / 8.0).abs() < 1e-15);
}

#[test]
fn xyz_round_trip_keeps_positions_shapes_and_orientations() {
    for p in every_kind() {
        let text = ellipack::xyz::xyz_string(&p);
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), p.items().len().to_string());
        let comment = lines.next().unwrap();
        assert!(comment.contains(
            "Properties=species:S:1:pos:R:3:group:I:1:aspherical_shape:R:3:orientation:R:4"
        ));
        assert!(comment.contains("Lattice=\""), "{comment}");
        let back = ellipack::xyz::read_xyz(&text, "packing.xyz").unwrap();
        assert_eq!(back.container(), p.container());
        match (&back.items(), &p.items()) {
            (Items::Ellipsoids(a), Items::Ellipsoids(b)) => {
                // The file holds the unit quaternion: exactly the one the export computes, the
                // same rotation as the item's.
                let unit = ellipack::export::bodies(p.items());
                assert_eq!(a.len(), b.len());
                for ((x, y), u) in a.iter().zip(b).zip(&unit) {
                    assert_eq!((x.centre, x.semi_axes), (y.centre, y.semi_axes));
                    assert_eq!(x.quaternion(), u.quaternion);
                    for k in 0..4 {
                        assert!((x.quaternion()[k] - y.quaternion()[k]).abs() < 1e-15);
                    }
                }
            }
            (Items::Ellipses(a), Items::Ellipses(b)) => {
                assert_eq!(a.len(), b.len());
                for (x, y) in a.iter().zip(b) {
                    assert_eq!((x.centre, x.semi_axes), (y.centre, y.semi_axes));
                    // Same orientation: θ may come back shifted by a multiple of 2π.
                    let turns = (x.theta() - y.theta()) / (2.0 * PI);
                    assert!(
                        (turns - turns.round()).abs() < 1e-14,
                        "{} {}",
                        x.theta(),
                        y.theta()
                    );
                }
            }
            _ => panic!("dimension changed"),
        }
    }
}

/// The numbers of the first item's line of the XYZ file, after its species: x, y, z, group,
/// the semi-axes and the quaternion (x, y, z, w).
fn first_xyz_row(p: &Packing) -> Vec<f64> {
    ellipack::xyz::xyz_string(p)
        .lines()
        .nth(2)
        .unwrap()
        .split_whitespace()
        .skip(1)
        .map(|t| t.parse().unwrap())
        .collect()
}

#[test]
fn xyz_orientation_is_in_ovito_order() {
    // A quarter turn about z: Hamilton (w, x, y, z) = (cos π/4, 0, 0, sin π/4); OVITO wants
    // (x, y, z, w), so the last two columns are sin π/4 then cos π/4.
    let (s, c) = (PI / 4.0).sin_cos();
    let p = Packing::new(
        Container::space([0.0; 3], Centred::Ball { radius: 5.0 }),
        Items::Ellipsoids(vec![Item::ellipsoid(
            [1.0, 2.0, 3.0],
            [1.0, 0.75, 0.5],
            [c, 0.0, 0.0, s],
        )]),
    )
    .unwrap();
    let row = first_xyz_row(&p);
    assert_eq!(
        row,
        vec![1.0, 2.0, 3.0, 1.0, 1.0, 0.75, 0.5, 0.0, 0.0, s, c]
    );
    // The same rotation as an ellipse angle: θ = π/2.
    let p2 = Packing::new(
        Container::plane([0.0; 2], Centred::Ball { radius: 5.0 }),
        Items::Ellipses(vec![Item::ellipse([1.0, 2.0], [2.0, 1.0], PI / 2.0)]),
    )
    .unwrap();
    let row = first_xyz_row(&p2);
    assert!(
        (row[9] - s).abs() < 1e-16 && (row[10] - c).abs() < 1e-16,
        "{row:?}"
    );
    assert_eq!(&row[..7], &[1.0, 2.0, 0.0, 1.0, 2.0, 1.0, 1.0]);
}

#[track_caller]
fn assert_csv_error(text: &str, says: &[&str]) {
    let e = ellipack::items_csv::read_csv(text, "packing.csv")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("packing.csv: "), "{e}");
    for s in says {
        assert!(e.contains(s), "{e} should say {s:?}");
    }
}

#[test]
fn malformed_csv_names_file_line_and_column() {
    let good = "id,x,y,a,b,theta\n0,1,2,2,1,0.5\n";
    assert!(ellipack::items_csv::read_csv(good, "p.csv").is_ok());
    assert_csv_error(
        "id,x,y,a,b,theta\n0,1,2,2,1,0.5\n1,1,abc,2,1,0\n",
        &["line 3, column 3 (`y`)", "`abc` is not a finite number"],
    );
    assert_csv_error(
        "id,x,y,a,b,theta\n0,1,2,-2,1,0.5\n",
        &["line 2, column 4 (`a`)", "not positive"],
    );
    assert_csv_error(
        "id,x,y,a,b,theta\n0,1,2,2,1,inf\n",
        &["line 2, column 6 (`theta`)"],
    );
    assert_csv_error("id,x,y,a,b,theta\n0,1,2,2,1\n", &["line 2"]);
    assert_csv_error(
        "id,x,y,a,b,theta\nx,1,2,2,1,0\n",
        &["line 2, column 1 (`id`)"],
    );
    assert_csv_error(
        "id,x,a,b,theta\n0,1,2,1,0\n",
        &["line 1", "missing column `y`"],
    );
    assert_csv_error(
        "id,x,y,z,a,b,c,qw,qx,qy\n0,1,2,3,1,1,1,1,0,0\n",
        &["missing column `qz`"],
    );
    assert_csv_error(
        "id,x,y,z,a,b,c,qw,qx,qy,qz\n0,1,2,3,1,1,1,0,0,0,0\n",
        &["line 2, column 8 (`qw`)", "zero"],
    );
    // Columns in another order, and extra columns, are fine.
    let shuffled = "theta,b,a,y,x,id,note\n0.5,1,2,2,1,0,hello\n";
    match ellipack::items_csv::read_csv(shuffled, "p.csv").unwrap() {
        Items::Ellipses(v) => assert_eq!(v, vec![Item::ellipse([1.0, 2.0], [2.0, 1.0], 0.5)]),
        Items::Ellipsoids(_) => panic!("2D expected"),
    }
}

#[test]
fn malformed_summary_names_file_line_and_column() {
    let p = &every_kind()[0];
    let good = ellipack::summary_json::summary_json(&summary_of(p)).unwrap();
    let read_as = |text: &str, name: &str| {
        ellipack::summary_json::read_summary(text, name)
            .unwrap_err()
            .to_string()
    };
    let read = |text: &str| read_as(text, "s.json");
    let e = read_as(&good.replace("\"density\"", "\"densty\""), "summary.json");
    assert!(e.starts_with("summary.json: line "), "{e}");
    assert!(e.contains("missing field `density`"), "{e}");
    let line = good
        .lines()
        .position(|l| l.contains("\"objective\""))
        .unwrap()
        + 1;
    let bad = good.replace("\"objective\": ", "\"objective\": \"big\" ,\"x\":");
    let e = read_as(&bad, "summary.json");
    assert!(
        e.starts_with(&format!("summary.json: line {line}: column ")),
        "{e}"
    );
    assert!(e.contains("invalid type"), "{e}");
    let e = read(&good.replace("\"circle\"", "\"hexagon\""));
    assert!(e.contains("hexagon"), "{e}");
    let e = read(&good.replace("\"radius\": 40.0", "\"radius\": -40.0"));
    assert!(e.contains("radius"), "{e}");
    let e = read("{");
    assert!(e.starts_with("s.json: line 1: column "), "{e}");
    // A key the container does not have, and a cell of the wrong size.
    let e = read(&good.replace("\"radius\": 40.0", "\"radius\": 40.0, \"colour\": 1"));
    assert!(e.contains("unknown field `colour`"), "{e}");
    let cell = r#"{"kind": "periodic", "lengths": [1, 2, 3, 4], "tilts": [0]}"#;
    let text = format!(
        r#"{{"container": {cell}, "items": 1, "density": 0.1, "objective": 1,
        "wall_seconds": 0, "local_minimisations": 0, "certificate": {{"overlapping_pairs": 0,
        "containment_violations": 0, "min_mu2": null}}}}"#
    );
    let e = read(&text);
    assert!(e.contains("2 or 3 lengths"), "{e}");
}

#[test]
fn non_finite_summaries_are_refused_rather_than_written_as_null() {
    let p = &every_kind()[0];
    let mut s = summary_of(p);
    s.objective = f64::NAN;
    match ellipack::summary_json::summary_json(&s) {
        Err(Error::NonFinite { field, .. }) => assert_eq!(field, "objective"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn files_that_disagree_are_an_error() {
    let dir = common::temp_dir("disagree");
    let p2 = &every_kind()[0];
    let p3 = &every_kind()[3];
    let refused = |dir: &std::path::Path| {
        ellipack::folder::read_packing_dir(dir)
            .unwrap_err()
            .to_string()
    };
    ellipack::items_csv::write_csv(&dir.join("packing.csv"), p2.items()).unwrap();
    ellipack::summary_json::write_summary(&dir.join("summary.json"), &summary_of(p3)).unwrap();
    let e = refused(&dir);
    assert!(e.contains("ball"), "{e}");
    let mut s = summary_of(p2);
    s.items += 1;
    ellipack::summary_json::write_summary(&dir.join("summary.json"), &s).unwrap();
    let e = refused(&dir);
    assert!(e.contains("16 items") && e.contains("17"), "{e}");
    std::fs::remove_file(dir.join("summary.json")).unwrap();
    let e = refused(&dir);
    assert!(e.contains("summary.json"), "{e}");
}

#[test]
fn malformed_xyz_is_an_error_with_the_line() {
    let p = &every_kind()[3];
    let good = ellipack::xyz::xyz_string(p);
    let bad = good.replacen("27\n", "28\n", 1);
    let e = ellipack::xyz::read_xyz(&bad, "packing.xyz")
        .unwrap_err()
        .to_string();
    assert!(e.contains("28 items announced, 27 rows"), "{e}");
    let mut lines: Vec<String> = good.lines().map(String::from).collect();
    lines[4] = lines[4].replacen(" 1.0000000000000000e0", " x", 1);
    let e = ellipack::xyz::read_xyz(&lines.join("\n"), "packing.xyz")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("packing.xyz: line 5, column "), "{e}");
    let e = ellipack::xyz::read_xyz(&good.replace("orientation:R:4", "orientation:R:3"), "p.xyz")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("p.xyz: line 2: Properties="), "{e}");
}

#[test]
fn packings_refuse_impossible_items() {
    let c = Container::plane([0.0; 2], Centred::Ball { radius: 1.0 });
    let bad = Items::Ellipses(vec![Item::ellipse([0.0, f64::NAN], [1.0, 1.0], 0.0)]);
    assert!(Packing::new(c.clone(), bad).is_err());
    let three_d = Items::Ellipsoids(vec![]);
    assert!(Packing::new(c, three_d).is_err());
}

/// Mangled files give an error or a packing, never a panic.
#[test]
fn mangled_files_never_panic() {
    let mut rng = testkit::Rng::new(5);
    let pieces = [",", "\"", "\n", "é", " ", "-", "e", "0", "=", "nan", "\t"];
    let p2 = &every_kind()[1];
    let p3 = &every_kind()[5];
    let texts = [
        ellipack::items_csv::csv_string(p2.items()),
        ellipack::items_csv::csv_string(p3.items()),
        ellipack::xyz::xyz_string(p2),
        ellipack::xyz::xyz_string(p3),
        ellipack::summary_json::summary_json(&summary_of(p3)).unwrap(),
    ];
    for _ in 0..400 {
        for (which, original) in texts.iter().enumerate() {
            let mut text: Vec<char> = original.chars().collect();
            for _ in 0..1 + (rng.uniform() * 3.0) as usize {
                let at = (rng.uniform() * text.len() as f64) as usize;
                let piece = pieces[(rng.uniform() * pieces.len() as f64) as usize];
                if rng.uniform() < 0.5 {
                    text.remove(at);
                } else {
                    text.splice(at..at, piece.chars());
                }
            }
            let text: String = text.into_iter().collect();
            let _ = match which {
                0 | 1 => ellipack::items_csv::read_csv(&text, "p.csv").map(|_| ()),
                2 | 3 => ellipack::xyz::read_xyz(&text, "p.xyz").map(|_| ()),
                _ => ellipack::summary_json::read_summary(&text, "s.json").map(|_| ()),
            };
        }
    }
}

#[test]
fn containers_from_solver_variables() {
    use ellipack::packing::ContainerKind;
    for p in every_kind() {
        let c = p.container();
        assert_eq!(
            &Container::from_parts(c.kind(), c.center(), &c.size()).unwrap(),
            c
        );
    }
    let e = Container::from_parts(ContainerKind::Ball, &[0.0; 2], &[1.0]).unwrap_err();
    assert!(e.to_string().contains("3 centre values"), "{e}");
    let e = Container::from_parts(ContainerKind::Ellipse, &[0.0; 2], &[1.0]).unwrap_err();
    assert!(e.to_string().contains("2 size values"), "{e}");
    let e = Container::from_parts(ContainerKind::Cuboid, &[0.0; 3], &[1.0, 0.0, 1.0]).unwrap_err();
    assert!(e.to_string().contains("half_sides"), "{e}");
    let text = ellipack::xyz::xyz_string(&every_kind()[3])
        .replace("container_radius=", "container_radius=-");
    let e = ellipack::xyz::read_xyz(&text, "p.xyz")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("p.xyz: line 2: container_center, container_radius: radius"),
        "{e}"
    );
}
