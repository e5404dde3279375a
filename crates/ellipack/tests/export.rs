//! The files for other programs, read back by parsers of their own written here: the LAMMPS
//! data file and the GSD file give back the exact values (GSD's single precision aside), the
//! container mesh is a closed outward surface on the container, and bad input is an error that
//! names the file and line.

mod common;

use ellipack::Error;
use ellipack::export::{self, Body, Cell, Format, bodies, shape_groups};
use ellipack::gsd::GSD_FILE;
use ellipack::lammps::LAMMPS_FILE;
use ellipack::obj::MESH_FILE;
use ellipack::packing::Centred;
use ellipack::packing::{self, Container, ContainerKind, Item, Items, Packing};
use std::collections::HashMap;

/// Every kind of container with items of its dimension; the 2D items of several sizes (so
/// several shape groups), the 3D ones all alike, and one packing off the origin.
fn every_kind() -> Vec<Packing> {
    let e2 = common::ellipses(4, true, 21);
    let e3 = common::ellipsoids(3, true, 22);
    let r2 = e2.container().half_extents()[0];
    let r3 = e3.container().half_extents()[0];
    let containers = [
        Container::plane([0.0, 0.0], Centred::Ball { radius: r2 * 1.1 }),
        e2.container().clone(),
        Container::plane(
            [0.0, 0.0],
            Centred::Box {
                half_sides: [r2, r2 * 0.9],
            },
        ),
        e3.container().clone(),
        Container::space(
            [0.0; 3],
            Centred::Ellipsoid {
                semi_axes: [r3, r3 * 1.1, r3 * 1.2],
            },
        ),
        Container::space(
            [0.0; 3],
            Centred::Box {
                half_sides: [r3, r3, r3],
            },
        ),
    ];
    let mut out = common::filled(containers, &e2, &e3);
    // Off the origin, with a quaternion that is not of norm 1.
    out.push(
        Packing::new(
            Container::space([10.0, -5.0, 2.5], Centred::Ball { radius: 3.0 }),
            Items::Ellipsoids(vec![
                Item::ellipsoid([11.0, -5.0, 2.5], [1.0, 0.75, 0.5], [2.0, 0.0, 0.0, 2.0]),
                Item::ellipsoid([8.5, -5.0, 2.5], [0.5, 0.5, 0.5], [1.0, 0.0, 0.0, 0.0]),
            ]),
        )
        .unwrap(),
    );
    out
}

#[test]
fn bodies_are_unit_quaternion_ellipsoids_and_groups_are_distinct_semi_axes() {
    let p = Packing::new(
        Container::plane([0.0; 2], Centred::Ball { radius: 10.0 }),
        Items::Ellipses(vec![
            Item::ellipse([1.0, 2.0], [2.0, 1.0], std::f64::consts::PI),
            Item::ellipse([-3.0, 2.0], [1.0, 1.0], 0.0),
            Item::ellipse([4.0, -4.0], [2.0, 1.0], 0.5),
        ]),
    )
    .unwrap();
    let b = bodies(p.items());
    assert_eq!(b[0].center, [1.0, 2.0, 0.0]);
    assert_eq!(b[0].semi_axes, [2.0, 1.0, 1.0]);
    // A half turn about z.
    assert!(b[0].quaternion[0].abs() < 1e-16);
    assert_eq!(b[0].quaternion[1..], [0.0, 0.0, 1.0]);
    let g = shape_groups(&b);
    assert_eq!(g.semi_axes, vec![[2.0, 1.0, 1.0], [1.0, 1.0, 1.0]]);
    assert_eq!(g.of_item, vec![0, 1, 0]);
    let q = bodies(every_kind()[6].items())[0].quaternion;
    let expected = [0.5f64.sqrt(), 0.0, 0.0, 0.5f64.sqrt()];
    for k in 0..4 {
        assert!((q[k] - expected[k]).abs() < 2e-16, "{q:?}");
    }
    assert_eq!(export::group_name(0), "C");
    assert_eq!(export::group_name(1), "O");
    assert_eq!(export::group_name(24), "C1");
}

/// Whether the ends of the item's three axes lie in the cell's box.
fn inside(cell: &Cell, b: &Body) -> bool {
    // The test kit's rotation, not the exporter's: column k is the image of axis k.
    let r = testkit::shape::rotation(b.quaternion);
    let hi = cell.hi();
    (0..3).all(|j| {
        [-1.0, 1.0].into_iter().all(|sign| {
            (0..3).all(|k| {
                let x = b.center[k] + sign * r[k][j] * b.semi_axes[j];
                x >= cell.lo[k] - 1e-12 && x <= hi[k] + 1e-12
            })
        })
    })
}

#[test]
fn the_cell_encloses_the_container_and_the_items_centred_on_the_container() {
    for p in every_kind() {
        let cell = Cell::enclosing(&p);
        let c = p.container();
        let center = cell.center();
        assert_eq!(center[..c.dimension()], *c.center(), "{}", c.kind());
        for (length, half) in cell.lengths.iter().zip(c.half_extents()) {
            assert!(*length >= 2.0 * half);
        }
        assert_eq!(cell.tilt, [0.0; 3]);
        assert_eq!(cell.periodic, [false; 3]);
        assert_eq!(cell.dimension, c.dimension());
        for b in bodies(p.items()) {
            assert!(inside(&cell, &b), "{}: {b:?}", c.kind());
        }
        if c.dimension() == 2 {
            let thickest = bodies(p.items())
                .iter()
                .map(|b| b.semi_axes[2])
                .fold(0.0, f64::max);
            assert_eq!(cell.lo[2], -thickest);
            assert_eq!(cell.hi()[2], thickest);
        }
    }
    // An item sticking out of its container widens the cell.
    let p = Packing::new(
        Container::space(
            [0.0; 3],
            Centred::Box {
                half_sides: [1.0, 1.0, 1.0],
            },
        ),
        Items::Ellipsoids(vec![Item::ellipsoid(
            [1.0, 0.0, 0.0],
            [0.5, 0.25, 0.25],
            [1.0, 0.0, 0.0, 0.0],
        )]),
    )
    .unwrap();
    let cell = Cell::enclosing(&p);
    assert_eq!(cell.lo, [-1.5, -1.0, -1.0]);
    assert_eq!(cell.lengths, [3.0, 2.0, 2.0]);
}

#[test]
fn the_lammps_data_file_reads_back_exactly() {
    for p in every_kind() {
        let kind = p.container().kind();
        let cell = Cell::enclosing(&p);
        let text = ellipack::lammps::lammps_data(&p, &cell);
        let data = ellipack::lammps::read_lammps_data(&text, LAMMPS_FILE).unwrap();
        let b = bodies(p.items());
        let groups = shape_groups(&b);
        assert_eq!(data.atom_types, groups.semi_axes.len(), "{kind}");
        assert_eq!(data.atoms.len(), b.len());
        assert_eq!(data.ellipsoids.len(), b.len());
        let hi = cell.hi();
        let bounds: Vec<[f64; 2]> = (0..3).map(|k| [cell.lo[k], hi[k]]).collect();
        assert_eq!(data.bounds.to_vec(), bounds, "{kind}");
        assert_eq!(data.tilt, [0.0; 3]);
        assert!(!text.contains("xy xz yz"));
        for (i, body) in b.iter().enumerate() {
            let (id, kind_of, flag, density, x) = data.atoms[i];
            assert_eq!(id, i as u64 + 1);
            assert_eq!(kind_of, groups.of_item[i] + 1);
            assert_eq!((flag, density), (1, ellipack::lammps::LAMMPS_DENSITY));
            assert_eq!(x, body.center, "{kind}: item {i}");
            let (id, shape, q) = data.ellipsoids[i];
            assert_eq!(id, i as u64 + 1);
            assert_eq!(shape, body.semi_axes.map(|l| 2.0 * l), "diameters");
            assert_eq!(q, body.quaternion, "scalar first");
            let norm: f64 = q.iter().map(|v| v * v).sum();
            assert!((norm - 1.0).abs() < 4e-16);
        }
        match p.items() {
            Items::Ellipses(v) => {
                assert!(text.contains(", 2D\n"));
                assert!(data.bounds[2][0] < 0.0 && data.bounds[2][1] > 0.0);
                for ((_, _, _, _, x), (e, (_, _, q))) in
                    data.atoms.iter().zip(v.iter().zip(&data.ellipsoids))
                {
                    assert_eq!(x[..2], e.centre);
                    assert_eq!(x[2], 0.0);
                    assert_eq!((q[1], q[2]), (0.0, 0.0), "rotation about z only");
                    let turns = (2.0 * q[3].atan2(q[0]) - e.theta()) / (2.0 * std::f64::consts::PI);
                    assert!((turns - turns.round()).abs() < 1e-14);
                }
            }
            Items::Ellipsoids(v) => {
                for ((_, _, _, _, x), e) in data.atoms.iter().zip(v) {
                    assert_eq!(*x, e.centre);
                }
            }
        }
    }
}

#[test]
fn a_sheared_cell_writes_its_tilt_factors() {
    let p = &every_kind()[5];
    let mut cell = Cell::enclosing(p);
    cell.tilt = [0.5, -0.25, 0.125];
    let text = ellipack::lammps::lammps_data(p, &cell);
    assert!(
        text.contains(
            "5.0000000000000000e-1 -2.5000000000000000e-1 1.2500000000000000e-1 xy xz yz\n"
        )
    );
    let data = ellipack::lammps::read_lammps_data(&text, LAMMPS_FILE).unwrap();
    assert_eq!(data.tilt, [0.5, -0.25, 0.125]);

    // The same cell, periodic, in the XYZ and GSD files.
    cell.periodic = [true; 3];
    let xyz = ellipack::xyz::xyz_string_in(p, &cell);
    let comment = xyz.lines().nth(1).unwrap();
    assert!(comment.contains(r#"pbc="T T T""#), "{comment}");
    let lattice: Vec<f64> = comment
        .split("Lattice=\"")
        .nth(1)
        .and_then(|rest| rest.split('"').next())
        .unwrap()
        .split_whitespace()
        .map(|t| t.parse().unwrap())
        .collect();
    let [lx, ly, lz] = cell.lengths;
    assert_eq!(
        lattice,
        [lx, 0.0, 0.0, 0.5, ly, 0.0, -0.25, 0.125, lz],
        "rows a, b, c"
    );
    let (_, _, chunks) = read_gsd(&ellipack::gsd::gsd_bytes(p, &cell));
    let hoomd_box = [lx, ly, lz, 0.5 / ly, -0.25 / lz, 0.125 / lz].map(|v| v as f32);
    assert_eq!(f32s(&chunks["configuration/box"]), hoomd_box);
}

#[track_caller]
fn assert_lammps_error(text: &str, says: &[&str]) {
    let e = ellipack::lammps::read_lammps_data(text, "p.data").unwrap_err();
    assert!(matches!(e, Error::Malformed { .. }), "{e:?}");
    let e = e.to_string();
    for s in says {
        assert!(e.contains(s), "{e} should say {s:?}");
    }
}

#[test]
fn a_broken_lammps_data_file_is_an_error_naming_the_line() {
    let p = &every_kind()[3];
    let good = ellipack::lammps::lammps_data(p, &Cell::enclosing(p));
    let lines: Vec<&str> = good.lines().collect();
    let line_of = |prefix: &str| lines.iter().position(|l| l.starts_with(prefix)).unwrap();
    let edit = |line: usize, new: &str| {
        let mut v: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
        v[line] = new.to_string();
        v.join("\n")
    };
    let atoms = line_of("Atoms") + 2;
    assert_lammps_error(
        &edit(atoms, "1 1 1 1.0 x 0 0"),
        &["p.data: line ", &format!("line {}:", atoms + 1), "`x`"],
    );
    assert_lammps_error(
        &edit(atoms, "1 9 1 1.0 0 0 0"),
        &[&format!("line {}:", atoms + 1), "atom type 9"],
    );
    assert_lammps_error(&edit(atoms, "1 1 1 1.0 0 0"), &["7 fields, not 6"]);
    let ell = line_of("Ellipsoids") + 2;
    assert_lammps_error(
        &edit(ell, "1 2 1.5 1 1 0 0"),
        &[&format!("line {}:", ell + 1), "8 fields, not 7"],
    );
    assert_lammps_error(
        &good.replacen("27 atoms", "28 atoms", 1),
        &["28", "Atoms section has 27"],
    );
    assert_lammps_error(&edit(line_of("27 ellipsoids"), "27 balls"), &["27 balls"]);
    let z = line_of("-") + 2;
    assert!(lines[z].ends_with("zlo zhi"));
    assert_lammps_error(&edit(z, ""), &["line 1:", "no `zlo zhi` line"]);
}

/// A chunk of a GSD file as our reader below finds it.
struct Chunk {
    rows: u64,
    columns: u32,
    kind: u8,
    bytes: Vec<u8>,
}

/// Reads a one-frame GSD file: header, index, name list, chunks (layout of GSD 2.x).
fn read_gsd(bytes: &[u8]) -> (String, String, HashMap<String, Chunk>) {
    let u64_at = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
    let text_at = |at: usize| {
        let field = &bytes[at..at + 64];
        let end = field.iter().position(|b| *b == 0).unwrap();
        String::from_utf8(field[..end].to_vec()).unwrap()
    };
    assert_eq!(u64_at(0), 0x65df_65df_65df_65df, "magic");
    let (index_at, entries, names_at, name_blocks) =
        (u64_at(8), u64_at(16), u64_at(24), u64_at(32));
    let gsd_version = u32::from_le_bytes(bytes[44..48].try_into().unwrap());
    assert_eq!(gsd_version >> 16, 2, "GSD 2.x");
    let names_bytes = &bytes[names_at as usize..(names_at + 64 * name_blocks) as usize];
    assert_eq!(
        *names_bytes.last().unwrap(),
        0,
        "the name list ends with a zero"
    );
    let names: Vec<String> = names_bytes
        .split(|b| *b == 0)
        .take_while(|n| !n.is_empty())
        .map(|n| String::from_utf8(n.to_vec()).unwrap())
        .collect();
    let mut chunks = HashMap::new();
    for e in 0..entries as usize {
        let at = index_at as usize + 32 * e;
        let location = u64_at(at + 16);
        if location == 0 {
            break;
        }
        assert_eq!(u64_at(at), 0, "frame 0");
        let rows = u64_at(at + 8);
        let columns = u32::from_le_bytes(bytes[at + 24..at + 28].try_into().unwrap());
        let id = u16::from_le_bytes(bytes[at + 28..at + 30].try_into().unwrap());
        let kind = bytes[at + 30];
        assert_eq!(bytes[at + 31], 0, "flags");
        let size = match kind {
            1 | 5 => 1,
            3 | 9 => 4,
            4 | 10 => 8,
            other => panic!("type {other}"),
        };
        let len = rows as usize * columns as usize * size;
        let data = bytes[location as usize..location as usize + len].to_vec();
        chunks.insert(
            names[id as usize].clone(),
            Chunk {
                rows,
                columns,
                kind,
                bytes: data,
            },
        );
    }
    (text_at(48), text_at(112), chunks)
}

/// The values of a chunk of four-byte words of GSD type `kind`.
fn words<T>(c: &Chunk, kind: u8, from_le_bytes: fn([u8; 4]) -> T) -> Vec<T> {
    assert_eq!(c.kind, kind);
    c.bytes
        .chunks(4)
        .map(|b| from_le_bytes(b.try_into().unwrap()))
        .collect()
}

fn f32s(c: &Chunk) -> Vec<f32> {
    words(c, 9, f32::from_le_bytes)
}

fn u32s(c: &Chunk) -> Vec<u32> {
    words(c, 3, u32::from_le_bytes)
}

fn strings(c: &Chunk) -> Vec<String> {
    assert_eq!(c.kind, 5);
    c.bytes
        .chunks(c.columns as usize)
        .map(|row| {
            let end = row.iter().position(|b| *b == 0).unwrap();
            String::from_utf8(row[..end].to_vec()).unwrap()
        })
        .collect()
}

#[test]
fn the_gsd_file_holds_the_hoomd_chunks() {
    for p in every_kind() {
        let kind = p.container().kind();
        let cell = Cell::enclosing(&p);
        let (application, schema, chunks) = read_gsd(&ellipack::gsd::gsd_bytes(&p, &cell));
        assert_eq!(
            (application.as_str(), schema.as_str()),
            ("ellipack", "hoomd")
        );
        let b = bodies(p.items());
        let groups = shape_groups(&b);
        let n = b.len();
        assert_eq!(u32s(&chunks["particles/N"]), [n as u32]);
        assert_eq!(
            chunks["configuration/dimensions"].bytes,
            [p.container().dimension() as u8]
        );
        assert_eq!(chunks["configuration/step"].bytes, 0u64.to_le_bytes());
        let [lx, ly, lz] = cell.lengths;
        let lz = if cell.dimension == 2 { 0.0 } else { lz };
        let expected_box = [lx, ly, lz, 0.0, 0.0, 0.0].map(|v| v as f32);
        assert_eq!(f32s(&chunks["configuration/box"]), expected_box, "{kind}");
        let center = cell.center();
        let position = &chunks["particles/position"];
        assert_eq!((position.rows, position.columns), (n as u64, 3));
        let expected: Vec<f32> = b
            .iter()
            .flat_map(|x| [0, 1, 2].map(|k| (x.center[k] - center[k]) as f32))
            .collect();
        assert_eq!(f32s(position), expected);
        for row in f32s(position).chunks(3) {
            for (x, length) in row.iter().zip(cell.lengths) {
                assert!(x.abs() <= 0.5 * length as f32, "{kind}");
            }
        }
        let orientation: Vec<f32> = b
            .iter()
            .flat_map(|x| x.quaternion.map(|v| v as f32))
            .collect();
        assert_eq!(f32s(&chunks["particles/orientation"]), orientation);
        let typeid: Vec<u32> = groups.of_item.iter().map(|g| *g as u32).collect();
        assert_eq!(u32s(&chunks["particles/typeid"]), typeid);
        let names: Vec<String> = (0..groups.semi_axes.len())
            .map(export::group_name)
            .collect();
        assert_eq!(strings(&chunks["particles/types"]), names);
        let shapes = strings(&chunks["particles/type_shapes"]);
        assert_eq!(shapes.len(), groups.semi_axes.len());
        for (json, axes) in shapes.iter().zip(&groups.semi_axes) {
            let v: serde_json::Value = serde_json::from_str(json).unwrap();
            assert_eq!(v["type"], "Ellipsoid");
            let radii = ["a", "b", "c"].map(|k| v[k].as_f64().unwrap());
            assert_eq!(radii, *axes, "radii in full precision");
        }
    }
}

/// The vertices and faces (0-based) of an OBJ file.
fn read_obj(text: &str) -> (Vec<[f64; 3]>, Vec<Vec<usize>>) {
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for line in text.lines() {
        let mut fields = line.split_whitespace();
        match fields.next() {
            Some("v") => {
                let v: Vec<f64> = fields.map(|f| f.parse().unwrap()).collect();
                vertices.push([v[0], v[1], v[2]]);
            }
            Some("f") => faces.push(fields.map(|f| f.parse::<usize>().unwrap() - 1).collect()),
            Some("#" | "o") | None => {}
            Some(other) => panic!("unexpected OBJ line `{other}`"),
        }
    }
    (vertices, faces)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[test]
fn the_container_mesh_is_an_outward_surface_on_the_container() {
    for p in every_kind() {
        let c = p.container();
        let kind = c.kind();
        let cell = Cell::enclosing(&p);
        let (vertices, faces) = read_obj(&ellipack::obj::mesh_obj(c, &cell));
        let mut center = [0.0; 3];
        center[..c.dimension()].copy_from_slice(c.center());
        let half = c.half_extents();
        // Every vertex on the surface (the 2D wall: on the outline, at the slab's faces).
        for v in &vertices {
            let r: Vec<f64> = (0..c.dimension())
                .map(|k| (v[k] - center[k]) / half[k])
                .collect();
            let on = match c.kind() {
                ContainerKind::Rectangle | ContainerKind::Cuboid => {
                    r.iter().fold(0.0_f64, |m, x| m.max(x.abs()))
                }
                _ => r.iter().map(|x| x * x).sum::<f64>(),
            };
            assert!((on - 1.0).abs() < 1e-8, "{kind}: {v:?}");
            if c.dimension() == 2 {
                // Vertices are written with 10 significant digits.
                let at = |z: f64| (v[2] - z).abs() <= 1e-9 * z.abs();
                assert!(at(cell.lo[2]) || at(cell.hi()[2]), "{kind}: {v:?}");
            }
        }
        // Every face faces outward, and every edge is met once in each direction (a closed,
        // consistently oriented surface), except the open ends of a 2D wall.
        let mut edges: HashMap<(usize, usize), usize> = HashMap::new();
        let mut volume = 0.0;
        for f in &faces {
            assert!(f.len() >= 3 && f.iter().all(|i| *i < vertices.len()));
            let (a, b, d) = (vertices[f[0]], vertices[f[1]], vertices[f[2]]);
            let normal = cross(sub(b, a), sub(d, a));
            let centroid = f
                .iter()
                .fold([0.0; 3], |s, i| [0, 1, 2].map(|k| s[k] + vertices[*i][k]))
                .map(|s| s / f.len() as f64);
            let mut outward = sub(centroid, center);
            if c.dimension() == 2 {
                outward[2] = 0.0;
            }
            assert!(
                dot(normal, outward) > 0.0,
                "{kind}: face {f:?} faces inward"
            );
            for k in 0..f.len() {
                *edges.entry((f[k], f[(k + 1) % f.len()])).or_default() += 1;
                // The divergence theorem over the fan of triangles (f0, fk, fk+1).
                if k >= 1 && k + 1 < f.len() {
                    volume += dot(vertices[f[0]], cross(vertices[f[k]], vertices[f[k + 1]])) / 6.0;
                }
            }
        }
        assert!(
            edges.values().all(|n| *n == 1),
            "{kind}: an edge used twice"
        );
        let unmatched = edges
            .keys()
            .filter(|(a, b)| !edges.contains_key(&(*b, *a)))
            .count();
        if c.dimension() == 3 {
            assert_eq!(unmatched, 0, "{kind}: the surface is not closed");
            let measure = c.measure();
            assert!(
                volume > 0.0 && (volume - measure).abs() < 0.01 * measure,
                "{kind}: enclosed volume {volume}, container {measure}"
            );
        } else {
            let outline = if kind == packing::ContainerKind::Rectangle {
                4
            } else {
                ellipack::obj::MESH_SEGMENTS
            };
            assert_eq!(faces.len(), outline);
            assert_eq!(unmatched, 2 * outline, "{kind}: open at both ends");
        }
    }
}

#[test]
fn convert_writes_the_chosen_files_of_a_packing_folder() {
    let p = &every_kind()[1];
    let dir = common::temp_dir("export-convert");
    ellipack::folder::write_files(&dir, p, &common::certified_summary(p), false).unwrap();
    export::convert(&dir, &[Format::Gsd], false).unwrap();
    assert_eq!(
        common::names(&dir),
        [
            ellipack::items_csv::CSV_FILE,
            GSD_FILE,
            ellipack::summary_json::SUMMARY_FILE
        ]
    );
    let back = export::convert(&dir, &Format::ALL, false).unwrap();
    assert_eq!(&back, p);
    assert_eq!(
        common::names(&dir),
        [
            MESH_FILE,
            ellipack::items_csv::CSV_FILE,
            LAMMPS_FILE,
            GSD_FILE,
            ellipack::xyz::XYZ_FILE,
            ellipack::summary_json::SUMMARY_FILE
        ]
    );
    let text = std::fs::read_to_string(dir.join(LAMMPS_FILE)).unwrap();
    assert_eq!(text, ellipack::lammps::lammps_data(p, &Cell::enclosing(p)));
    let bytes = std::fs::read(dir.join(GSD_FILE)).unwrap();
    assert_eq!(bytes, ellipack::gsd::gsd_bytes(p, &Cell::enclosing(p)));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn convert_refuses_what_is_not_a_packing_folder() {
    let dir = common::temp_dir("export-bad");
    let missing = dir.join("missing");
    let e = export::convert(&missing, &Format::ALL, false).unwrap_err();
    assert!(matches!(e, Error::NotAFolder { .. }), "{e:?}");
    assert!(
        e.to_string().contains("missing: not a packing folder"),
        "{e}"
    );
    let file = dir.join("file.csv");
    std::fs::write(&file, "id\n").unwrap();
    let e = export::convert(&file, &Format::ALL, false)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("file.csv: not a packing folder: it is a file"),
        "{e}"
    );
    let empty = dir.join("empty");
    std::fs::create_dir(&empty).unwrap();
    let e = export::convert(&empty, &Format::ALL, false).unwrap_err();
    assert!(matches!(e, Error::Io { .. }), "{e:?}");
    assert!(e.to_string().contains("packing.csv"), "{e}");
    // A broken row is named by its line, and nothing is written.
    let p = &every_kind()[0];
    ellipack::folder::write_files(&empty, p, &common::certified_summary(p), false).unwrap();
    let csv = std::fs::read_to_string(empty.join(ellipack::items_csv::CSV_FILE)).unwrap();
    let broken = csv.replacen("\n0,", "\n0,nan-ish,", 1);
    std::fs::write(empty.join(ellipack::items_csv::CSV_FILE), broken).unwrap();
    let e = export::convert(&empty, &Format::ALL, false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("line 2"), "{e}");
    assert_eq!(
        common::names(&empty),
        [
            ellipack::items_csv::CSV_FILE,
            ellipack::summary_json::SUMMARY_FILE
        ]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn format_names_are_checked() {
    assert_eq!(Format::from_name(" GSD ").unwrap(), Format::Gsd);
    for f in Format::ALL {
        assert_eq!(Format::from_name(f.name()).unwrap(), f);
    }
    let e = Format::from_name("vtk").unwrap_err();
    assert!(matches!(e, Error::UnknownFormat { .. }));
    assert_eq!(
        e.to_string(),
        "`vtk` is not a file format; the formats are lammps, gsd, xyz, obj"
    );
}
