//! The extended XYZ file of a packing, as ASE and OVITO read it, and its reader.

use crate::Error;
use crate::atoms::{Cell, GROUP_ELEMENTS, bodies, shape_groups};
use crate::items_csv::{num, write_text};
use crate::packing::{Container, ContainerKind, Item, Items, Packing};
use std::path::Path;

/// The file name of the extended XYZ file.
pub const XYZ_FILE: &str = "packing.xyz";

/// The `Properties` of [`XYZ_FILE`]: OVITO maps `aspherical_shape` to *Aspherical Shape* and
/// `orientation` to *Orientation*, a quaternion in OVITO's order (x, y, z, w); `group` is the
/// item's shape group (from 1).
pub const XYZ_PROPERTIES: &str =
    "species:S:1:pos:R:3:group:I:1:aspherical_shape:R:3:orientation:R:4";

/// The text of [`XYZ_FILE`], extended XYZ as ASE and OVITO read it.
///
/// ```text
/// 2
/// Lattice="8 0 0 0 8 0 0 0 8" Origin="-4 -4 -4" pbc="F F F" Properties=species:S:1:pos:R:3:group:I:1:aspherical_shape:R:3:orientation:R:4 dimension=3 container=ball container_center="0 0 0" container_radius=4
/// C x y z 1 a b c qx qy qz qw
/// ```
///
/// `species` is a chemical symbol standing for the item's shape group
/// ([`crate::export::GROUP_ELEMENTS`]: ASE needs an element), `group` the group's number from 1
/// (the LAMMPS atom type), `aspherical_shape` the semi-axes, `orientation` the unit quaternion
/// in OVITO's order (x, y, z, w) — OVITO's *Orientation* property is (X, Y, Z, W) with W the
/// scalar part. The cell (`Lattice`, `Origin`) is [`Cell::enclosing`], not
/// periodic. Ellipses are written at z = 0 as ellipsoids (a, b, min(a, b)) rotated by θ about
/// z, with `dimension=2`; the container is in the `container*` keys, which OVITO keeps as
/// global attributes and ASE in `Atoms.info`.
pub fn xyz_string(packing: &Packing) -> String {
    xyz_string_in(packing, &Cell::enclosing(packing))
}

/// [`xyz_string`] with the cell given: `Lattice` holds its edge vectors, `Origin` its lower
/// corner and `pbc` its periodicity.
pub fn xyz_string_in(packing: &Packing, cell: &Cell) -> String {
    let items = &packing.items;
    let container = &packing.container;
    let bodies = bodies(items);
    let groups = shape_groups(&bodies);
    let join = |v: &[f64]| v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(" ");
    let lattice = join(cell.vectors().as_flattened());
    let size = container.size();
    let size_value = if size.len() == 1 {
        num(size[0])
    } else {
        format!("\"{}\"", join(&size))
    };
    let pbc: Vec<&str> = cell
        .periodic
        .iter()
        .map(|p| if *p { "T" } else { "F" })
        .collect();
    let mut out = format!(
        "{}\nLattice=\"{lattice}\" Origin=\"{}\" pbc=\"{}\" Properties={XYZ_PROPERTIES} \
         dimension={} container={} container_center=\"{}\" container_{}={size_value}\n",
        items.len(),
        join(&cell.lo),
        pbc.join(" "),
        items.dimension(),
        container.kind().name(),
        join(container.center()),
        container.size_name(),
    );
    let elements = GROUP_ELEMENTS;
    for (b, g) in bodies.iter().zip(&groups.of_item) {
        let [w, x, y, z] = b.quaternion;
        let [cx, cy, cz] = b.center;
        let [a, bb, c] = b.semi_axes;
        out.push_str(&format!(
            "{} {} {} {}\n",
            elements[g % elements.len()],
            join(&[cx, cy, cz]),
            g + 1,
            join(&[a, bb, c, x, y, z, w])
        ));
    }
    out
}

/// Writes [`xyz_string`] to `path` atomically.
///
/// # Errors
/// [`Error::Write`] naming the file.
pub fn write_xyz(path: &Path, packing: &Packing) -> Result<(), Error> {
    write_text(path, &xyz_string(packing))
}

/// Splits an extended XYZ comment line into `key=value` pairs (values may be double-quoted).
fn xyz_pairs(line: &str) -> Result<Vec<(String, String)>, String> {
    let mut pairs = Vec::new();
    let mut chars = line.chars().peekable();
    loop {
        while chars.next_if(|c| c.is_whitespace()).is_some() {}
        if chars.peek().is_none() {
            return Ok(pairs);
        }
        let key: String =
            std::iter::from_fn(|| chars.next_if(|c| *c != '=' && !c.is_whitespace())).collect();
        if chars.next_if_eq(&'=').is_none() {
            return Err(format!("`{key}` has no `=value`"));
        }
        let value: String = if chars.next_if_eq(&'"').is_some() {
            let v: String = std::iter::from_fn(|| chars.next_if(|c| *c != '"')).collect();
            if chars.next_if_eq(&'"').is_none() {
                return Err(format!("the value of `{key}` has no closing quote"));
            }
            v
        } else {
            std::iter::from_fn(|| chars.next_if(|c| !c.is_whitespace())).collect()
        };
        pairs.push((key, value));
    }
}

/// Reads the [`XYZ_FILE`] that [`xyz_string`] writes (not arbitrary extended XYZ: the
/// `Properties` must be [`XYZ_PROPERTIES`] and the `dimension` and `container*` keys present).
/// Ellipses get θ = 2 atan2(q_z, q_w), the same orientation as written, within (−2π, 2π].
///
/// # Errors
/// [`Error::Malformed`] for a header that is not ours or a wrong number of rows,
/// [`Error::BadValue`] (line, column) for a field that is not a number or impossible.
pub fn read_xyz(text: &str, source_name: &str) -> Result<Packing, Error> {
    let malformed = |line: u64, message: String| Error::Malformed {
        source_name: source_name.to_string(),
        line,
        message,
    };
    let mut lines = text.lines();
    let count_text = lines.next().unwrap_or("").trim();
    let count: usize = count_text
        .parse()
        .map_err(|_| malformed(1, format!("`{count_text}` is not a number of items")))?;
    let comment = lines
        .next()
        .ok_or_else(|| malformed(2, "the comment line is missing".to_string()))?;
    let pairs = xyz_pairs(comment).map_err(|m| malformed(2, m))?;
    let get = |key: &str| {
        pairs
            .iter()
            .find(|(k, _)| k.eq_ignore_ascii_case(key))
            .map(|(_, v)| v.as_str())
            .ok_or_else(|| malformed(2, format!("the comment line has no `{key}=`")))
    };
    let properties = get("Properties")?;
    if properties != XYZ_PROPERTIES {
        return Err(malformed(
            2,
            format!("Properties={properties}: expected {XYZ_PROPERTIES}"),
        ));
    }
    let numbers = |key: &str| -> Result<Vec<f64>, Error> {
        get(key)?
            .split_whitespace()
            .map(|t| {
                t.parse::<f64>()
                    .map_err(|_| malformed(2, format!("{key}: `{t}` is not a number")))
            })
            .collect()
    };
    let dimension = get("dimension")?;
    let kind_name = get("container")?;
    let kind = ["2", "3"]
        .iter()
        .position(|d| *d == dimension)
        .and_then(|d| ContainerKind::named(kind_name, d + 2))
        .or_else(|| ContainerKind::from_name(kind_name))
        .ok_or_else(|| malformed(2, format!("container={kind_name}: unknown kind")))?;
    if dimension != kind.dimension().to_string() {
        return Err(malformed(
            2,
            format!("dimension={dimension} but container={kind_name}"),
        ));
    }
    let center = numbers("container_center")?;
    let size_key = match kind {
        ContainerKind::Circle | ContainerKind::Ball => "container_radius",
        ContainerKind::Ellipse | ContainerKind::Ellipsoid => "container_semi_axes",
        ContainerKind::Rectangle | ContainerKind::Cuboid => "container_half_sides",
        ContainerKind::Parallelogram | ContainerKind::Parallelepiped => "container_lengths",
    };
    let size = numbers(size_key)?;
    let container = Container::from_parts(kind, &center, &size).map_err(|e| {
        let message = match e {
            Error::Inconsistent { message, .. } => message,
            other => other.to_string(),
        };
        malformed(2, format!("container_center, {size_key}: {message}"))
    })?;
    const NAMES: [&str; 12] = [
        "species", "x", "y", "z", "group", "a", "b", "c", "qx", "qy", "qz", "qw",
    ];
    // The error of a bad value in field `k` (0-based, as in NAMES) of `line`.
    let bad_value = |line, k: usize, message| Error::BadValue {
        source_name: source_name.to_string(),
        line,
        column: k as u64 + 1,
        name: NAMES[k].to_string(),
        message,
    };
    let mut ellipses = Vec::new();
    let mut ellipsoids = Vec::new();
    let mut rows = 0;
    for (index, row) in lines.enumerate() {
        let line = index as u64 + 3;
        if row.trim().is_empty() {
            continue;
        }
        rows += 1;
        if rows > count {
            return Err(malformed(
                line,
                format!("more rows than the {count} announced"),
            ));
        }
        let fields: Vec<&str> = row.split_whitespace().collect();
        if fields.len() != NAMES.len() {
            return Err(malformed(
                line,
                format!("{} fields, expected {}", fields.len(), NAMES.len()),
            ));
        }
        if fields[4].parse::<u64>().map_or(true, |g| g == 0) {
            let message = format!("`{}` is not a group number (1, 2, …)", fields[4]);
            return Err(bad_value(line, 4, message));
        }
        let mut v = [0.0; 10];
        for (k, slot) in v.iter_mut().enumerate() {
            // Past the group column, value k is field k + 2.
            let f = if k < 3 { k + 1 } else { k + 2 };
            *slot = match fields[f].parse::<f64>() {
                Ok(x) if x.is_finite() => x,
                _ => {
                    let message = format!("`{}` is not a finite number", fields[f]);
                    return Err(bad_value(line, f, message));
                }
            };
        }
        let [x, y, z, a, b, c, qx, qy, qz, qw] = v;
        if let Some(k) = [a, b, c].iter().position(|l| *l <= 0.0) {
            let message = format!("semi-axis {} is not positive", v[k + 3]);
            return Err(bad_value(line, k + 5, message));
        }
        if kind.dimension() == 2 {
            ellipses.push(Item::ellipse([x, y], [a, b], 2.0 * qz.atan2(qw)));
        } else {
            ellipsoids.push(Item::ellipsoid([x, y, z], [a, b, c], [qw, qx, qy, qz]));
        }
    }
    if rows != count {
        return Err(malformed(
            1,
            format!("{count} items announced, {rows} rows found"),
        ));
    }
    let items = if kind.dimension() == 2 {
        Items::Ellipses(ellipses)
    } else {
        Items::Ellipsoids(ellipsoids)
    };
    Packing::new(container, items).map_err(|e| match e {
        Error::Inconsistent { message, .. } => Error::Inconsistent {
            source_name: source_name.to_string(),
            message,
        },
        other => other,
    })
}
