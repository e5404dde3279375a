//! Files for the programs that simulate or show a packing: a LAMMPS data file, a GSD file in
//! HOOMD's schema, and the container as a surface mesh (the extended XYZ file is in
//! [`crate::packing`]). `docs/files.md` gives each file's conventions.
//!
//! Every writer takes the packing and a [`Cell`]: today the axis-aligned box that encloses the
//! container and every item ([`Cell::enclosing`]), with no periodic direction and zero tilt. A
//! periodic or sheared cell is a [`Cell`] with other fields; the writers already put its tilt
//! factors and periodicity where each format keeps them.
//!
//! Conventions shared by the files:
//! * items are ellipsoids: an ellipse becomes the ellipsoid (a, b, min(a, b)) in the plane
//!   z = 0, rotated by θ about z;
//! * orientations are unit quaternions (the file's quaternion divided by its norm), Hamilton
//!   active rotations whose column k carries semi-axis k;
//! * one type per shape group: items with the same semi-axes (exactly), numbered in the order
//!   their first item appears.

use crate::Error;
pub use crate::atoms::{Body, Cell, GROUP_ELEMENTS, ShapeGroups, bodies, group_name, shape_groups};
use crate::packing::{Container, ContainerKind, Packing, num};
use implicit_packing::ContainerShape;
use std::fmt::Write as _;
use std::path::Path;

/// The file name of the LAMMPS data file.
pub const LAMMPS_FILE: &str = "packing.data";
/// The file name of the GSD file.
pub const GSD_FILE: &str = "packing.gsd";
/// The file name of the container's surface mesh.
pub const MESH_FILE: &str = "container.obj";

/// A file that `ellipack convert` and `ellipack pack` write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Format {
    /// [`LAMMPS_FILE`].
    Lammps,
    /// [`GSD_FILE`].
    Gsd,
    /// [`crate::xyz::XYZ_FILE`].
    Xyz,
    /// [`MESH_FILE`].
    Obj,
}

impl Format {
    /// Every format, in the order they are written.
    pub const ALL: [Format; 4] = [Format::Lammps, Format::Gsd, Format::Xyz, Format::Obj];

    /// The name on the command line: `lammps`, `gsd`, `xyz`, `obj`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Lammps => "lammps",
            Format::Gsd => "gsd",
            Format::Xyz => "xyz",
            Format::Obj => "obj",
        }
    }

    /// The file it is written to.
    pub fn file_name(self) -> &'static str {
        match self {
            Format::Lammps => LAMMPS_FILE,
            Format::Gsd => GSD_FILE,
            Format::Xyz => crate::xyz::XYZ_FILE,
            Format::Obj => MESH_FILE,
        }
    }

    /// The format of a name (case-insensitive, surrounding blanks ignored).
    ///
    /// # Errors
    /// [`Error::UnknownFormat`].
    pub fn from_name(name: &str) -> Result<Format, Error> {
        let wanted = name.trim();
        Format::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(wanted))
            .ok_or_else(|| Error::UnknownFormat {
                name: name.to_string(),
            })
    }
}

// ---------------------------------------------------------------------------------------------
// LAMMPS

/// The density given to every atom in the LAMMPS data file (mass = density × volume).
pub const LAMMPS_DENSITY: f64 = 1.0;

/// The text of [`LAMMPS_FILE`], a data file for `atom_style ellipsoid`:
///
/// ```text
/// LAMMPS data file (atom_style ellipsoid) written by ellipack: 100 ellipsoids, ball container
///
/// 100 atoms
/// 1 atom types
/// 100 ellipsoids
///
/// -3.83e0 3.83e0 xlo xhi
/// …
/// Atoms # ellipsoid
///
/// 1 1 1 1.0e0 x y z
/// …
/// Ellipsoids
///
/// 1 shapex shapey shapez quatw quati quatj quatk
/// ```
///
/// `Atoms` rows are `atom-ID atom-type ellipsoidflag density x y z` (IDs from 1 in the order of
/// packing.csv, one atom type per shape group from 1, density [`LAMMPS_DENSITY`]); `Ellipsoids`
/// rows give the three **diameters** and the unit quaternion, scalar first. The box bounds are
/// the cell's; a sheared cell adds the `xy xz yz` line. A 2D packing is read with `dimension 2`:
/// atoms at z = 0, rotated about z only, in a box whose z bounds straddle 0.
pub fn lammps_data(packing: &Packing, cell: &Cell) -> String {
    let bodies = bodies(packing.items());
    let groups = shape_groups(&bodies);
    let n = bodies.len();
    let mut out = format!(
        "LAMMPS data file (atom_style ellipsoid) written by ellipack: {n} {}, {} container, \
         {}D\n\n{n} atoms\n{} atom types\n{n} ellipsoids\n\n",
        packing.items().noun(),
        packing.container().kind(),
        cell.dimension,
        groups.semi_axes.len(),
    );
    let hi = cell.hi();
    for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
        let _ = writeln!(out, "{} {} {axis}lo {axis}hi", num(cell.lo[k]), num(hi[k]));
    }
    if cell.tilt.iter().any(|t| *t != 0.0) {
        let [xy, xz, yz] = cell.tilt;
        let _ = writeln!(out, "{} {} {} xy xz yz", num(xy), num(xz), num(yz));
    }
    out.push_str("\nAtoms # ellipsoid\n\n");
    for (i, b) in bodies.iter().enumerate() {
        let [x, y, z] = b.center;
        let _ = writeln!(
            out,
            "{} {} 1 {} {} {} {}",
            i + 1,
            groups.of_item[i] + 1,
            num(LAMMPS_DENSITY),
            num(x),
            num(y),
            num(z)
        );
    }
    out.push_str("\nEllipsoids\n\n");
    for (i, b) in bodies.iter().enumerate() {
        let shape = b.semi_axes.map(|l| num(2.0 * l));
        let q = b.quaternion.map(num);
        let _ = writeln!(out, "{} {} {}", i + 1, shape.join(" "), q.join(" "));
    }
    out
}

/// What [`read_lammps_data`] finds in a data file.
#[derive(Clone, Debug, PartialEq)]
pub struct LammpsData {
    /// The `atom types` count.
    pub atom_types: usize,
    /// (lo, hi) along x, y, z.
    pub bounds: [[f64; 2]; 3],
    /// xy, xz, yz (zero without the tilt line).
    pub tilt: [f64; 3],
    /// The `Atoms` rows in file order: (ID, type, ellipsoidflag, density, position).
    pub atoms: Vec<(u64, usize, u8, f64, [f64; 3])>,
    /// The `Ellipsoids` rows in file order: (ID, diameters, quaternion scalar first).
    pub ellipsoids: Vec<(u64, [f64; 3], [f64; 4])>,
}

/// Reads the data file that [`lammps_data`] writes (its header keywords and its two
/// sections; not every data file LAMMPS reads). `source_name` names it in messages.
///
/// # Errors
/// [`Error::Malformed`] naming the line: a header line or
/// section that is not ours, a field that is not a number, a row with the wrong number of
/// fields, counts that disagree.
pub fn read_lammps_data(text: &str, source_name: &str) -> Result<LammpsData, Error> {
    let bad = |line: usize, message: String| Error::Malformed {
        source_name: source_name.to_string(),
        line: line as u64 + 1,
        message,
    };
    let number = |line: usize, field: &str| -> Result<f64, Error> {
        field
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad(line, format!("`{field}` is not a finite number")))
    };
    let integer = |line: usize, field: &str| -> Result<u64, Error> {
        field
            .parse::<u64>()
            .map_err(|_| bad(line, format!("`{field}` is not a non-negative integer")))
    };
    let lines: Vec<&str> = text.lines().collect();
    let mut data = LammpsData {
        atom_types: 0,
        bounds: [[0.0; 2]; 3],
        tilt: [0.0; 3],
        atoms: Vec::new(),
        ellipsoids: Vec::new(),
    };
    let (mut atoms, mut ellipsoids) = (None, None);
    let mut bounds_seen = [false; 3];
    let mut section: Option<&str> = None;
    // The first line is a title.
    for (i, raw) in lines.iter().enumerate().skip(1) {
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let fields: Vec<&str> = content.split_whitespace().collect();
        if matches!(content, "Atoms" | "Ellipsoids") {
            section = Some(content);
            continue;
        }
        match section {
            None => match fields.as_slice() {
                [n, "atoms"] => atoms = Some(integer(i, n)?),
                [n, "ellipsoids"] => ellipsoids = Some(integer(i, n)?),
                [n, "atom", "types"] => data.atom_types = integer(i, n)? as usize,
                [lo, hi, low, high] if low.ends_with("lo") && high.ends_with("hi") => {
                    let k = ["xlo", "ylo", "zlo"]
                        .iter()
                        .position(|l| l == low)
                        .filter(|&k| *high == ["xhi", "yhi", "zhi"][k])
                        .ok_or_else(|| bad(i, format!("`{low} {high}`: not a box bound")))?;
                    data.bounds[k] = [number(i, lo)?, number(i, hi)?];
                    bounds_seen[k] = true;
                }
                [xy, xz, yz, "xy", "xz", "yz"] => {
                    data.tilt = [number(i, xy)?, number(i, xz)?, number(i, yz)?];
                }
                _ => return Err(bad(i, format!("`{content}`: not a header line"))),
            },
            Some("Atoms") => {
                let [id, kind, flag, density, x, y, z] = fields.as_slice() else {
                    return Err(bad(
                        i,
                        format!("an Atoms row has 7 fields, not {}", fields.len()),
                    ));
                };
                let kind = integer(i, kind)? as usize;
                if kind == 0 || kind > data.atom_types {
                    return Err(bad(
                        i,
                        format!("atom type {kind} is not in 1..={}", data.atom_types),
                    ));
                }
                let flag = match *flag {
                    "0" => 0,
                    "1" => 1,
                    other => return Err(bad(i, format!("ellipsoidflag `{other}` is not 0 or 1"))),
                };
                data.atoms.push((
                    integer(i, id)?,
                    kind,
                    flag,
                    number(i, density)?,
                    [number(i, x)?, number(i, y)?, number(i, z)?],
                ));
            }
            Some(_) => {
                let [id, rest @ ..] = fields.as_slice() else {
                    continue;
                };
                if rest.len() != 7 {
                    return Err(bad(
                        i,
                        format!("an Ellipsoids row has 8 fields, not {}", fields.len()),
                    ));
                }
                let mut v = [0.0; 7];
                for (slot, field) in v.iter_mut().zip(rest) {
                    *slot = number(i, field)?;
                }
                let [sx, sy, sz, qw, qi, qj, qk] = v;
                data.ellipsoids
                    .push((integer(i, id)?, [sx, sy, sz], [qw, qi, qj, qk]));
            }
        }
    }
    let last = lines.len().saturating_sub(1);
    if let Some(k) = bounds_seen.iter().position(|seen| !seen) {
        let axis = ["x", "y", "z"][k];
        return Err(bad(0, format!("no `{axis}lo {axis}hi` line")));
    }
    for (what, section, announced, found) in [
        ("atoms", "Atoms", atoms, data.atoms.len()),
        (
            "ellipsoids",
            "Ellipsoids",
            ellipsoids,
            data.ellipsoids.len(),
        ),
    ] {
        if announced != Some(found as u64) {
            return Err(bad(
                last,
                format!(
                    "the header announces {announced:?} {what}, the {section} section has {found}"
                ),
            ));
        }
    }
    Ok(data)
}

// ---------------------------------------------------------------------------------------------
// GSD

/// GSD's file identifier, the first 8 bytes.
const GSD_MAGIC: u64 = 0x65df_65df_65df_65df;
/// The GSD container version written (2.0: names in one null-separated list).
const GSD_VERSION: (u16, u16) = (2, 0);
/// The HOOMD schema version written.
const HOOMD_SCHEMA_VERSION: (u16, u16) = (1, 4);
const GSD_HEADER_SIZE: usize = 256;
const GSD_INDEX_ENTRY_SIZE: usize = 32;
/// The name list occupies whole blocks of this many bytes.
const GSD_NAME_BLOCK: usize = 64;

/// GSD's type codes.
#[derive(Clone, Copy)]
enum GsdType {
    U8 = 1,
    U32 = 3,
    U64 = 4,
    I8 = 5,
    F32 = 9,
}

/// One named N × M array of a frame.
struct GsdChunk {
    name: &'static str,
    kind: GsdType,
    rows: u64,
    columns: u32,
    bytes: Vec<u8>,
}

impl GsdChunk {
    fn f32(name: &'static str, columns: u32, values: &[f64]) -> GsdChunk {
        GsdChunk {
            name,
            kind: GsdType::F32,
            rows: (values.len() / columns as usize) as u64,
            columns,
            // HOOMD's schema stores these in single precision.
            bytes: values
                .iter()
                .flat_map(|v| (*v as f32).to_le_bytes())
                .collect(),
        }
    }

    /// Strings as the rows of an int8 array, each padded with zero bytes to the longest + 1.
    fn strings(name: &'static str, strings: &[String]) -> GsdChunk {
        let width = strings.iter().map(String::len).max().unwrap_or(0) + 1;
        let mut bytes = Vec::with_capacity(width * strings.len());
        for s in strings {
            bytes.extend_from_slice(s.as_bytes());
            bytes.resize(bytes.len() + width - s.len(), 0);
        }
        GsdChunk {
            name,
            kind: GsdType::I8,
            rows: strings.len() as u64,
            columns: width as u32,
            bytes,
        }
    }
}

/// The bytes of a GSD file (container version 2.0, little-endian) holding one frame of
/// `chunks`: header, index, name list, data.
fn gsd_file(application: &str, schema: &str, chunks: &[GsdChunk]) -> Vec<u8> {
    let entries = (chunks.len() + 1).max(16);
    let mut names: Vec<u8> = Vec::new();
    for c in chunks {
        names.extend_from_slice(c.name.as_bytes());
        names.push(0);
    }
    // At least one zero byte after the last name ends the list.
    let name_bytes = (names.len() / GSD_NAME_BLOCK + 1) * GSD_NAME_BLOCK;
    names.resize(name_bytes, 0);
    let index_at = GSD_HEADER_SIZE;
    let names_at = index_at + entries * GSD_INDEX_ENTRY_SIZE;
    let mut data_at = names_at + name_bytes;

    let mut out = Vec::with_capacity(data_at + chunks.iter().map(|c| c.bytes.len()).sum::<usize>());
    let version = |(major, minor): (u16, u16)| (u32::from(major) << 16) | u32::from(minor);
    out.extend_from_slice(&GSD_MAGIC.to_le_bytes());
    out.extend_from_slice(&(index_at as u64).to_le_bytes());
    out.extend_from_slice(&(entries as u64).to_le_bytes());
    out.extend_from_slice(&(names_at as u64).to_le_bytes());
    out.extend_from_slice(&((name_bytes / GSD_NAME_BLOCK) as u64).to_le_bytes());
    out.extend_from_slice(&version(HOOMD_SCHEMA_VERSION).to_le_bytes());
    out.extend_from_slice(&version(GSD_VERSION).to_le_bytes());
    let mut text_field = |text: &str| {
        let mut field = [0u8; 64];
        field[..text.len().min(63)].copy_from_slice(&text.as_bytes()[..text.len().min(63)]);
        out.extend_from_slice(&field);
    };
    text_field(application);
    text_field(schema);
    out.resize(GSD_HEADER_SIZE, 0);

    for (id, c) in chunks.iter().enumerate() {
        out.extend_from_slice(&0u64.to_le_bytes()); // frame
        out.extend_from_slice(&c.rows.to_le_bytes());
        out.extend_from_slice(&(data_at as i64).to_le_bytes());
        out.extend_from_slice(&c.columns.to_le_bytes());
        out.extend_from_slice(&(id as u16).to_le_bytes());
        out.push(c.kind as u8);
        out.push(0); // flags
        data_at += c.bytes.len();
    }
    // Unused entries are zero: location 0 marks the end of the index.
    out.resize(names_at, 0);
    out.extend_from_slice(&names);
    for c in chunks {
        out.extend_from_slice(&c.bytes);
    }
    out
}

/// The bytes of [`GSD_FILE`]: one frame (step 0) in HOOMD's schema.
///
/// * `configuration/box` = [Lx, Ly, Lz, xy, xz, yz] with HOOMD's tilt factors (LAMMPS's
///   divided by the lengths they shear along); in 2D, Lz = 0 as HOOMD requires;
///   `configuration/dimensions` = 2 or 3;
/// * `particles/position` relative to the cell's centre (HOOMD's box is centred at the origin),
///   `particles/orientation` the unit quaternion scalar first, both single precision;
/// * `particles/types` the group names ([`group_name`]), `particles/typeid` each item's group,
///   `particles/type_shapes` one JSON object per type, `{"type": "Ellipsoid", "a": …, "b": …,
///   "c": …}` with the **semi-axes** (radii) in full precision.
pub fn gsd_bytes(packing: &Packing, cell: &Cell) -> Vec<u8> {
    let bodies = bodies(packing.items());
    let groups = shape_groups(&bodies);
    let center = cell.center();
    let two_d = cell.dimension == 2;
    let [lx, ly, lz] = cell.lengths;
    let [xy, xz, yz] = cell.tilt;
    let hoomd_box = [
        lx,
        ly,
        if two_d { 0.0 } else { lz },
        xy / ly,
        if two_d { 0.0 } else { xz / lz },
        if two_d { 0.0 } else { yz / lz },
    ];
    let positions: Vec<f64> = bodies
        .iter()
        .flat_map(|b| [0, 1, 2].map(|k| b.center[k] - center[k]))
        .collect();
    let orientations: Vec<f64> = bodies.iter().flat_map(|b| b.quaternion).collect();
    let names: Vec<String> = (0..groups.semi_axes.len()).map(group_name).collect();
    let shapes: Vec<String> = groups
        .semi_axes
        .iter()
        .map(|[a, b, c]| format!(r#"{{"type": "Ellipsoid", "a": {a:?}, "b": {b:?}, "c": {c:?}}}"#))
        .collect();
    let n = bodies.len();
    let chunks = [
        GsdChunk {
            name: "configuration/step",
            kind: GsdType::U64,
            rows: 1,
            columns: 1,
            bytes: 0u64.to_le_bytes().to_vec(),
        },
        GsdChunk {
            name: "configuration/dimensions",
            kind: GsdType::U8,
            rows: 1,
            columns: 1,
            bytes: vec![cell.dimension as u8],
        },
        GsdChunk::f32("configuration/box", 1, &hoomd_box),
        GsdChunk {
            name: "particles/N",
            kind: GsdType::U32,
            rows: 1,
            columns: 1,
            bytes: (n as u32).to_le_bytes().to_vec(),
        },
        GsdChunk::strings("particles/types", &names),
        GsdChunk {
            name: "particles/typeid",
            kind: GsdType::U32,
            rows: n as u64,
            columns: 1,
            bytes: groups
                .of_item
                .iter()
                .flat_map(|g| (*g as u32).to_le_bytes())
                .collect(),
        },
        GsdChunk::strings("particles/type_shapes", &shapes),
        GsdChunk::f32("particles/position", 3, &positions),
        GsdChunk::f32("particles/orientation", 4, &orientations),
    ];
    gsd_file("ellipack", "hoomd", &chunks)
}

// ---------------------------------------------------------------------------------------------
// Surface mesh

/// Segments of a circle of latitude (and of a 2D container's outline).
pub const MESH_SEGMENTS: usize = 64;
/// Bands between the poles of a ball or ellipsoid.
pub const MESH_BANDS: usize = 32;

/// The text of [`MESH_FILE`], a Wavefront OBJ surface with outward-facing polygons
/// (counter-clockwise seen from outside) that OVITO and ParaView load:
/// * ball, ellipsoid: a latitude–longitude mesh, [`MESH_BANDS`] bands of [`MESH_SEGMENTS`]
///   quadrilaterals (triangles at the poles), its vertices on the surface (10 significant
///   digits);
/// * cuboid: its six faces;
/// * circle, ellipse, rectangle: the wall, the outline extruded over the cell's z extent (the
///   slab of the flattened ellipses), open at both ends so that the items stay visible; the
///   circle and ellipse with [`MESH_SEGMENTS`] vertices on the curve at each end.
pub fn mesh_obj(container: &Container, cell: &Cell) -> String {
    let mut vertices: Vec<[f64; 3]> = Vec::new();
    let mut faces: Vec<Vec<usize>> = Vec::new();
    let c = container.center();
    let half = container.half_extents();
    let periodic = container.kind().is_periodic();
    match container.kind().shape() {
        ContainerShape::Ball | ContainerShape::Ellipsoid if container.dimension() == 3 => {
            let r = [half[0], half[1], half[2]];
            let point = |polar: f64, azimuth: f64| {
                let (sp, cp) = polar.sin_cos();
                let (sa, ca) = azimuth.sin_cos();
                [
                    c[0] + r[0] * sp * ca,
                    c[1] + r[1] * sp * sa,
                    c[2] + r[2] * cp,
                ]
            };
            let pi = std::f64::consts::PI;
            vertices.push([c[0], c[1], c[2] + r[2]]);
            for band in 1..MESH_BANDS {
                let polar = pi * band as f64 / MESH_BANDS as f64;
                for s in 0..MESH_SEGMENTS {
                    vertices.push(point(polar, 2.0 * pi * s as f64 / MESH_SEGMENTS as f64));
                }
            }
            vertices.push([c[0], c[1], c[2] - r[2]]);
            let south = vertices.len() - 1;
            let ring = |band: usize, s: usize| 1 + (band - 1) * MESH_SEGMENTS + s % MESH_SEGMENTS;
            for s in 0..MESH_SEGMENTS {
                faces.push(vec![0, ring(1, s), ring(1, s + 1)]);
            }
            for band in 1..MESH_BANDS - 1 {
                for s in 0..MESH_SEGMENTS {
                    faces.push(vec![
                        ring(band, s),
                        ring(band + 1, s),
                        ring(band + 1, s + 1),
                        ring(band, s + 1),
                    ]);
                }
            }
            for s in 0..MESH_SEGMENTS {
                faces.push(vec![
                    ring(MESH_BANDS - 1, s),
                    south,
                    ring(MESH_BANDS - 1, s + 1),
                ]);
            }
        }
        ContainerShape::Box | ContainerShape::Periodic if container.dimension() == 3 => {
            let edges = cell.vectors();
            for k in 0..8 {
                let bit = |j: usize| k & (1 << j) != 0;
                vertices.push(if periodic {
                    // The cell spanned by its edge vectors (right-handed: det H > 0).
                    [0, 1, 2].map(|i| {
                        cell.lo[i] + (0..3).filter(|&j| bit(j)).map(|j| edges[j][i]).sum::<f64>()
                    })
                } else {
                    [0, 1, 2].map(|j| c[j] + if bit(j) { half[j] } else { -half[j] })
                });
            }
            // Vertex k has bit j set when it is on the + side along axis j.
            faces.extend([
                vec![0, 4, 6, 2], // x−
                vec![1, 3, 7, 5], // x+
                vec![0, 1, 5, 4], // y−
                vec![2, 6, 7, 3], // y+
                vec![0, 2, 3, 1], // z−
                vec![4, 5, 7, 6], // z+
            ]);
        }
        _ => {
            let edges = cell.vectors();
            let outline: Vec<[f64; 2]> = if periodic {
                let [x0, y0, _] = cell.lo;
                let ([ax, ay, _], [bx, by, _]) = (edges[0], edges[1]);
                vec![
                    [x0, y0],
                    [x0 + ax, y0 + ay],
                    [x0 + ax + bx, y0 + ay + by],
                    [x0 + bx, y0 + by],
                ]
            } else if container.kind() == ContainerKind::Rectangle {
                vec![
                    [c[0] - half[0], c[1] - half[1]],
                    [c[0] + half[0], c[1] - half[1]],
                    [c[0] + half[0], c[1] + half[1]],
                    [c[0] - half[0], c[1] + half[1]],
                ]
            } else {
                (0..MESH_SEGMENTS)
                    .map(|s| {
                        let t = 2.0 * std::f64::consts::PI * s as f64 / MESH_SEGMENTS as f64;
                        [c[0] + half[0] * t.cos(), c[1] + half[1] * t.sin()]
                    })
                    .collect()
            };
            let (z0, z1) = (cell.lo[2], cell.hi()[2]);
            let m = outline.len();
            for z in [z0, z1] {
                vertices.extend(outline.iter().map(|[x, y]| [*x, *y, z]));
            }
            for s in 0..m {
                let t = (s + 1) % m;
                faces.push(vec![s, t, m + t, m + s]);
            }
        }
    }
    let mut out = format!(
        "# {} container written by ellipack: {} vertices, {} faces\no container\n",
        container.kind(),
        vertices.len(),
        faces.len()
    );
    // A picture needs no more than 10 significant digits; 17 would double the file.
    for [x, y, z] in &vertices {
        let _ = writeln!(out, "v {x:.9e} {y:.9e} {z:.9e}");
    }
    for f in &faces {
        let indices: Vec<String> = f.iter().map(|i| (i + 1).to_string()).collect();
        let _ = writeln!(out, "f {}", indices.join(" "));
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Writing

/// Writes the files of `formats` for `packing` in `cell` (for a container,
/// [`Cell::enclosing`] it) into `dir` (which must exist), each atomically.
///
/// # Errors
/// [`Error::Write`] naming the file that could not be written; the files before it are
/// written.
pub fn write_formats(
    dir: &Path,
    packing: &Packing,
    cell: &Cell,
    formats: &[Format],
) -> Result<(), Error> {
    for format in formats {
        let path = dir.join(format.file_name());
        let bytes = match format {
            Format::Lammps => lammps_data(packing, cell).into_bytes(),
            Format::Gsd => gsd_bytes(packing, cell),
            Format::Xyz => crate::xyz::xyz_string_in(packing, cell).into_bytes(),
            Format::Obj => mesh_obj(packing.container(), cell).into_bytes(),
        };
        crate::output::write_atomically(&path, &bytes)?;
    }
    Ok(())
}

/// `ellipack convert`: reads the packing of `dir` (packing.csv and summary.json) and writes
/// the files of `formats` beside them, in the cell [`Cell::enclosing`] the packing (a periodic
/// cell reduced, its items wrapped into it: [`Packing::in_reduced_cell`]). The least
/// overlapping configuration of an unfinished run (`not_reached` in its summary) is refused
/// unless `unfinished`: its files would start a simulation from overlapping items.
///
/// # Errors
/// [`Error::NotAFolder`] when `dir` is not a folder, [`Error::UnfinishedFolder`], the
/// errors of
/// [`crate::packing::read_packing_dir`] (a missing or broken packing.csv or summary.json,
/// named with the line), and those of [`write_formats`].
pub fn convert(dir: &Path, formats: &[Format], unfinished: bool) -> Result<Packing, Error> {
    match std::fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(Error::NotAFolder {
                path: dir.to_path_buf(),
                reason: "it is a file; give the folder that holds packing.csv and summary.json"
                    .to_string(),
            });
        }
        Err(e) => {
            return Err(Error::NotAFolder {
                path: dir.to_path_buf(),
                reason: e.to_string(),
            });
        }
    }
    let (packing, summary) = crate::packing::read_packing_dir(dir)?;
    if summary.not_reached && !unfinished {
        return Err(Error::UnfinishedFolder {
            path: dir.to_path_buf(),
            overlapping_pairs: summary.certificate.overlapping_pairs,
            outside: summary.certificate.containment_violations,
        });
    }
    // A cell edited by hand, or written by another program, is stated reduced with its items
    // inside, as docs/files.md promises.
    let packing = packing.in_reduced_cell();
    write_formats(dir, &packing, &Cell::enclosing(&packing), formats)?;
    Ok(packing)
}
