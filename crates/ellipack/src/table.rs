//! Numeric tables in CSV, as the reference files and our own outputs store them: a header
//! naming the columns, a `case_id` copied through when present, and every other column ignored
//! unless a reader asks for it.

use crate::Error;

/// One data row: its identity and either the requested values, in the order asked, or why
/// they could not be read.
#[derive(Clone, Debug, PartialEq)]
pub struct NumericRow {
    /// The `case_id` column, or the 1-based row number.
    pub case_id: String,
    /// The 1-based line of the file.
    pub line: u64,
    /// The values, or a message naming the line and column of the cell that is not a number.
    pub values: Result<Vec<f64>, String>,
}

/// Whether the header of `text` names every one of `columns` (for choosing between layouts,
/// such as the 2D and 3D measure files).
pub fn has_columns(text: &str, columns: &[&str]) -> bool {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    reader
        .headers()
        .is_ok_and(|h| columns.iter().all(|c| h.iter().any(|x| x == *c)))
}

/// Reads the named numeric columns of every row. `source_name` names the input in messages.
///
/// # Errors
/// [`Error::MalformedCsv`] (with the line) for broken CSV structure,
/// [`Error::MissingColumn`] when a requested column is absent, [`Error::Empty`] without rows.
/// A cell that is not a number is not an error of the file: its row carries the message.
pub fn read_numeric_rows(
    text: &str,
    source_name: &str,
    columns: &[&str],
) -> Result<Vec<NumericRow>, Error> {
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let malformed = |e: csv::Error| Error::MalformedCsv {
        source_name: source_name.to_string(),
        line: e.position().map_or(0, csv::Position::line),
        message: e.to_string(),
    };
    let header = reader.headers().map_err(malformed)?.clone();
    let find = |name: &str| header.iter().position(|h| h == name);
    let positions = columns
        .iter()
        .map(|&name| {
            find(name).ok_or_else(|| Error::MissingColumn {
                source_name: source_name.to_string(),
                column: name.to_string(),
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let id_column = find("case_id");
    let mut rows = Vec::new();
    for (index, record) in reader.records().enumerate() {
        let record = record.map_err(malformed)?;
        let line = record
            .position()
            .map_or(index as u64 + 2, csv::Position::line);
        let case_id = id_column
            .and_then(|c| record.get(c))
            .map_or_else(|| (index + 1).to_string(), str::to_string);
        let values = positions
            .iter()
            .zip(columns)
            .map(|(&c, name)| {
                let cell = record.get(c).unwrap_or("");
                cell.parse::<f64>().map_err(|_| {
                    format!(
                        "line {line}, column {} ({name}): `{cell}` is not a number",
                        c + 1
                    )
                })
            })
            .collect();
        rows.push(NumericRow {
            case_id,
            line,
            values,
        });
    }
    if rows.is_empty() {
        return Err(Error::Empty {
            source_name: source_name.to_string(),
        });
    }
    Ok(rows)
}

/// A CSV field, quoted when it needs to be.
pub fn quote(field: &str) -> String {
    if field.contains([',', '"', '\n']) {
        format!("\"{}\"", field.replace('"', "\"\""))
    } else {
        field.to_string()
    }
}

/// A number with 17 significant digits: reads back to the same double.
pub fn exact(x: f64) -> String {
    format!("{x:.16e}")
}
