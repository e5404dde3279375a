//! The items table `packing.csv`: one row per item, `id,x,y,a,b,theta` (2D) or
//! `id,x,y,z,a,b,c,qw,qx,qy,qz` (3D); `id` counts from 0. Numbers have 17 significant digits, so
//! that they read back to the same double.

use crate::Error;
use crate::packing::{Container, Item, Items, Packing};
use std::path::Path;

/// The file name of the items table.
pub const CSV_FILE: &str = "packing.csv";

/// The columns of [`CSV_FILE`] for ellipses.
pub const CSV_COLUMNS_2D: [&str; 6] = ["id", "x", "y", "a", "b", "theta"];

/// The columns of [`CSV_FILE`] for ellipsoids.
pub const CSV_COLUMNS_3D: [&str; 11] = ["id", "x", "y", "z", "a", "b", "c", "qw", "qx", "qy", "qz"];

/// 17 significant digits: enough for every double to read back to itself.
pub(crate) fn num(x: f64) -> String {
    format!("{x:.16e}")
}

/// The text of [`CSV_FILE`].
pub fn csv_string(items: &Items) -> String {
    let columns: &[&str] = match items {
        Items::Ellipses(_) => &CSV_COLUMNS_2D,
        Items::Ellipsoids(_) => &CSV_COLUMNS_3D,
    };
    let mut out = columns.join(",");
    out.push('\n');
    let mut row = |id: usize, fields: &[f64]| {
        out.push_str(&id.to_string());
        for f in fields {
            out.push(',');
            out.push_str(&num(*f));
        }
        out.push('\n');
    };
    match items {
        Items::Ellipses(v) => {
            for (id, e) in v.iter().enumerate() {
                let [x, y] = e.centre;
                let [a, b] = e.semi_axes;
                row(id, &[x, y, a, b, e.theta()]);
            }
        }
        Items::Ellipsoids(v) => {
            for (id, e) in v.iter().enumerate() {
                let [x, y, z] = e.centre;
                let [a, b, c] = e.semi_axes;
                let [qw, qx, qy, qz] = e.quaternion();
                row(id, &[x, y, z, a, b, c, qw, qx, qy, qz]);
            }
        }
    }
    out
}

/// Writes [`csv_string`] to `path` atomically.
///
/// # Errors
/// [`Error::Write`] naming the file.
pub fn write_csv(path: &Path, items: &Items) -> Result<(), Error> {
    write_text(path, &csv_string(items))
}

/// Writes `text` to `path` atomically.
pub(crate) fn write_text(path: &Path, text: &str) -> Result<(), Error> {
    crate::output::write_atomically(path, text.as_bytes())
}

/// Reads [`CSV_FILE`] text. The header decides the dimension: with any of `z, c, qw, qx, qy,
/// qz` it must hold every 3D column, else every 2D column; columns may come in any order and
/// other columns are ignored. `source_name` names the file in messages.
///
/// # Errors
/// [`Error::Malformed`] for broken CSV, an empty file, a column named twice or no item
/// line, [`Error::MissingColumn`], and [`Error::BadValue`] (line, column, name)
/// for a cell that is not a finite number, a semi-axis that is not positive, a zero quaternion
/// or an `id` that is not an integer; [`Error::DuplicateId`] naming both lines when two
/// rows share an `id`.
pub fn read_csv(text: &str, source_name: &str) -> Result<Items, Error> {
    read_table(text, source_name).map(|table| table.items)
}

/// The rows of [`CSV_FILE`] as read: the items, and for each its `id` and its line, so that
/// messages can name an item the way the file does.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The items, in the order of the rows.
    pub items: Items,
    /// The `id` of each row.
    pub ids: Vec<u64>,
    /// The 1-based line of each row.
    pub lines: Vec<u64>,
}

/// Reads [`CSV_FILE`] text as [`read_csv`] does, keeping each row's `id` and line.
///
/// # Errors
/// Those of [`read_csv`].
pub fn read_table(text: &str, source_name: &str) -> Result<Table, Error> {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let malformed = |e: csv::Error| Error::Malformed {
        source_name: source_name.to_string(),
        line: e.position().map_or(1, csv::Position::line),
        message: e.to_string(),
    };
    let header = reader.headers().map_err(malformed)?.clone();
    let three_d = header
        .iter()
        .any(|h| CSV_COLUMNS_3D.contains(&h) && !CSV_COLUMNS_2D.contains(&h));
    let expected: &[&'static str] = if three_d {
        &CSV_COLUMNS_3D
    } else {
        &CSV_COLUMNS_2D
    };
    if header.len() <= 1 && header.iter().all(str::is_empty) {
        return Err(Error::Malformed {
            source_name: source_name.to_string(),
            line: 1,
            message: format!(
                "the file is empty: a packing starts with the header {} and has one line per item",
                expected.join(",")
            ),
        });
    }
    let mut index = Vec::with_capacity(expected.len());
    for &column in expected {
        let i = crate::table::column_position(&header, column)
            .map_err(|e| Error::Malformed {
                source_name: source_name.to_string(),
                line: 1,
                message: e.to_string(),
            })?
            .ok_or_else(|| Error::MissingColumn {
                source_name: source_name.to_string(),
                column: column.to_string(),
                expected: expected.join(","),
            })?;
        index.push(i);
    }
    let mut ellipses = Vec::new();
    let mut ellipsoids = Vec::new();
    let mut ids = Vec::new();
    let mut lines = Vec::new();
    let mut first_line_of = std::collections::HashMap::new();
    for record in reader.records() {
        let record = record.map_err(malformed)?;
        let line = record.position().map_or(0, csv::Position::line);
        let bad = |k: usize, message: String| Error::BadValue {
            source_name: source_name.to_string(),
            line,
            column: index[k] as u64 + 1,
            name: expected[k].to_string(),
            message,
        };
        // Every column of the record exists: the csv reader rejects rows of another length.
        let cell = |k: usize| record.get(index[k]).unwrap_or("");
        let id_text = cell(0);
        let Ok(id) = id_text.parse::<u64>() else {
            return Err(bad(0, format!("`{id_text}` is not a non-negative integer")));
        };
        if let Some(&first_line) = first_line_of.get(&id) {
            return Err(Error::DuplicateId {
                source_name: source_name.to_string(),
                id,
                first_line,
                line,
            });
        }
        first_line_of.insert(id, line);
        ids.push(id);
        lines.push(line);
        let mut values = [0.0; 10];
        for (k, slot) in values.iter_mut().enumerate().take(expected.len() - 1) {
            let text = cell(k + 1);
            *slot = match text.parse::<f64>() {
                Ok(v) if v.is_finite() => v,
                _ => return Err(bad(k + 1, format!("`{text}` is not a finite number"))),
            };
        }
        let axes = if three_d { 4..7 } else { 3..5 };
        for k in axes {
            if values[k - 1] <= 0.0 {
                return Err(bad(k, format!("semi-axis {} is not positive", cell(k))));
            }
        }
        if three_d {
            let [x, y, z, a, b, c, qw, qx, qy, qz] = values;
            if [qw, qx, qy, qz].iter().all(|q| *q == 0.0) {
                return Err(bad(
                    7,
                    "the quaternion (qw, qx, qy, qz) is zero".to_string(),
                ));
            }
            ellipsoids.push(Item::ellipsoid([x, y, z], [a, b, c], [qw, qx, qy, qz]));
        } else {
            let [x, y, a, b, theta, ..] = values;
            ellipses.push(Item::ellipse([x, y], [a, b], theta));
        }
    }
    if ellipses.is_empty() && ellipsoids.is_empty() {
        return Err(Error::Malformed {
            source_name: source_name.to_string(),
            line: 2,
            message: format!(
                "no items: after the header {}, a packing has one line per item",
                expected.join(",")
            ),
        });
    }
    let items = if three_d {
        Items::Ellipsoids(ellipsoids)
    } else {
        Items::Ellipses(ellipses)
    };
    Ok(Table { items, ids, lines })
}

/// Reads `packing.csv` as a [`Table`] and puts its items into `container`, checking that they
/// agree (dimension; the item count when `items` is given). `container_source` names where the
/// container came from in messages.
///
/// # Errors
/// [`Error::Io`] naming the file, those of [`read_table`], and
/// [`Error::Inconsistent`] when the table and the container disagree.
pub fn read_table_into(
    csv_path: &Path,
    container: Container,
    items: Option<usize>,
    container_source: &str,
) -> Result<(Packing, Table), Error> {
    let csv_name = csv_path.display().to_string();
    let text = std::fs::read_to_string(csv_path).map_err(|source| Error::Io {
        path: csv_path.to_path_buf(),
        source,
    })?;
    let table = read_table(&text, &csv_name)?;
    let inconsistent = |message: String| Error::Inconsistent {
        source_name: csv_name.clone(),
        message,
    };
    if container.dimension() != table.items.dimension() {
        return Err(inconsistent(format!(
            "{}D items (by the header) but {container_source} gives a {} container",
            table.items.dimension(),
            container.kind()
        )));
    }
    if let Some(n) = items.filter(|n| *n != table.items.len()) {
        return Err(inconsistent(format!(
            "{} items, but {container_source} says `items`: {n}",
            table.items.len()
        )));
    }
    let packing = Packing::new(container, table.items.clone()).map_err(|e| match e {
        Error::Inconsistent { message, .. } => inconsistent(message),
        other => other,
    })?;
    Ok((packing, table))
}
