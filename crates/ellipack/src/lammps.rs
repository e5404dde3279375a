//! The LAMMPS data file `packing.data` for `atom_style ellipsoid` (see [`lammps_data`]), and its
//! reader, with which tests and `cargo xtask` check what LAMMPS will read.

use crate::Error;
use crate::atoms::{Cell, bodies, shape_groups};
use crate::items_csv::num;
use crate::packing::Packing;
use std::fmt::Write as _;

/// The file name of the LAMMPS data file.
pub const LAMMPS_FILE: &str = "packing.data";

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
