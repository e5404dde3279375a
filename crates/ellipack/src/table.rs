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

/// A header names the same column twice: a reader cannot know which one holds the data.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("column `{column}` appears twice in the header (columns {first} and {second})")]
pub struct DuplicateColumn {
    /// The column name.
    pub column: String,
    /// 1-based position of its first appearance.
    pub first: usize,
    /// 1-based position of its second appearance.
    pub second: usize,
}

/// The 0-based position of `name` in `header`, `None` when absent.
///
/// # Errors
/// [`DuplicateColumn`] when the header names it more than once.
pub fn column_position(
    header: &csv::StringRecord,
    name: &str,
) -> Result<Option<usize>, DuplicateColumn> {
    let mut found = header.iter().enumerate().filter(|(_, h)| *h == name);
    let first = found.next().map(|(i, _)| i);
    match (first, found.next()) {
        (Some(first), Some((second, _))) => Err(DuplicateColumn {
            column: name.to_string(),
            first: first + 1,
            second: second + 1,
        }),
        (first, _) => Ok(first),
    }
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

/// The CSV reader every table of the command line is read with.
pub fn csv_reader<R: std::io::Read>(input: R) -> csv::Reader<R> {
    csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .from_reader(input)
}

/// The header of a table (its first record), with broken CSV reported as [`Error::Malformed`].
///
/// # Errors
/// [`Error::Malformed`] when the first line is not valid CSV or not UTF-8, or the file is
/// empty.
pub fn read_header<R: std::io::Read>(
    reader: &mut csv::Reader<R>,
    source_name: &str,
) -> Result<csv::StringRecord, Error> {
    let header = reader
        .headers()
        .cloned()
        .map_err(|e| malformed(source_name, &e))?;
    if header.len() <= 1 && header.iter().all(str::is_empty) {
        return Err(Error::Malformed {
            source_name: source_name.to_string(),
            line: 1,
            message: "the file is empty: it must start with a header line naming its columns"
                .to_string(),
        });
    }
    Ok(header)
}

fn malformed(source_name: &str, e: &csv::Error) -> Error {
    Error::Malformed {
        source_name: source_name.to_string(),
        line: e.position().map_or(1, csv::Position::line),
        message: e.to_string(),
    }
}

/// Rows of a numeric table read one at a time, so that a file of any length is read in
/// constant memory.
pub struct NumericReader<R> {
    records: csv::StringRecordsIntoIter<R>,
    source_name: String,
    columns: Vec<String>,
    positions: Vec<usize>,
    id_column: Option<usize>,
    index: usize,
}

impl<R: std::io::Read> NumericReader<R> {
    /// Prepares to read the named numeric columns of every row of `reader`, whose header
    /// `header` has already been read. `source_name` names the input in messages.
    ///
    /// # Errors
    /// [`Error::MissingColumn`] when a requested column is absent, [`Error::DuplicateColumn`]
    /// when a requested column (or `case_id`) appears twice.
    pub fn new(
        reader: csv::Reader<R>,
        header: &csv::StringRecord,
        source_name: &str,
        columns: &[&str],
    ) -> Result<Self, Error> {
        let find = |name: &str| {
            column_position(header, name).map_err(|source| Error::DuplicateColumn {
                source_name: source_name.to_string(),
                source,
            })
        };
        let positions = columns
            .iter()
            .map(|&name| {
                find(name)?.ok_or_else(|| Error::MissingColumn {
                    source_name: source_name.to_string(),
                    column: name.to_string(),
                    expected: columns.join(", "),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            records: reader.into_records(),
            source_name: source_name.to_string(),
            columns: columns.iter().map(|c| (*c).to_string()).collect(),
            positions,
            id_column: find("case_id")?,
            index: 0,
        })
    }

    /// The next row, `None` at the end of the file.
    ///
    /// # Errors
    /// [`Error::Malformed`] (with the line) for broken CSV structure. A cell that is not a
    /// number is not an error of the file: its row carries the message.
    pub fn next_row(&mut self) -> Result<Option<NumericRow>, Error> {
        let Some(record) = self.records.next() else {
            return Ok(None);
        };
        let record = record.map_err(|e| malformed(&self.source_name, &e))?;
        self.index += 1;
        let line = record
            .position()
            .map_or(self.index as u64 + 1, csv::Position::line);
        let case_id = self
            .id_column
            .and_then(|c| record.get(c))
            .map_or_else(|| self.index.to_string(), str::to_string);
        let values = self
            .positions
            .iter()
            .zip(&self.columns)
            .map(|(&c, name)| {
                let cell = record.get(c).unwrap_or("");
                cell.parse::<f64>().map_err(|_| {
                    format!(
                        "line {line}, column {} ({name}): `{}` is not a number",
                        c + 1,
                        short_text(cell)
                    )
                })
            })
            .collect();
        Ok(Some(NumericRow {
            case_id,
            line,
            values,
        }))
    }

    /// How many rows have been read.
    pub fn rows_read(&self) -> usize {
        self.index
    }

    /// Reads every remaining row.
    ///
    /// # Errors
    /// As [`next_row`](Self::next_row), or [`Error::Empty`] when there is no row.
    pub fn read_all(mut self) -> Result<Vec<NumericRow>, Error> {
        let mut all = Vec::new();
        while let Some(row) = self.next_row()? {
            all.push(row);
        }
        if all.is_empty() {
            return Err(Error::Empty {
                source_name: self.source_name,
            });
        }
        Ok(all)
    }
}

/// Reads the named numeric columns of every row. `source_name` names the input in messages.
///
/// # Errors
/// [`Error::Malformed`] (with the line) for broken CSV structure,
/// [`Error::MissingColumn`] when a requested column is absent, [`Error::DuplicateColumn`] when
/// one appears twice, [`Error::Empty`] without rows. A cell that is not a number is not an
/// error of the file: its row carries the message.
pub fn read_numeric_rows(
    text: &str,
    source_name: &str,
    columns: &[&str],
) -> Result<Vec<NumericRow>, Error> {
    let mut reader = csv_reader(text.as_bytes());
    let header = read_header(&mut reader, source_name)?;
    NumericReader::new(reader, &header, source_name, columns)?.read_all()
}

/// A cell as quoted in a message: on one line (control characters escaped, as `\n`) and cut
/// to its first 40 characters, so that a huge cell does not flood the terminal.
pub fn short_text(cell: &str) -> String {
    const MAX: usize = 40;
    let mut out = String::new();
    for (i, c) in cell.chars().enumerate() {
        if i == MAX {
            out.push('…');
            break;
        }
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// A number as written in a message: short (`1e-300`, `-2.5e0`), with up to 6 significant
/// digits, because `{}` of an extreme double prints hundreds of digits.
pub fn short(x: f64) -> String {
    if x.is_finite() && x != 0.0 && (x.abs() >= 1e6 || x.abs() < 1e-4) {
        let s = format!("{x:.5e}");
        // Trailing zeros of the mantissa say nothing.
        match s.split_once('e') {
            Some((mantissa, exponent)) if mantissa.contains('.') => {
                let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
                format!("{mantissa}e{exponent}")
            }
            _ => s,
        }
    } else if x.is_finite() {
        let s = format!("{x:.6}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{x}")
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_messages_are_short() {
        assert_eq!(short(1e-300), "1e-300");
        assert_eq!(short(-1e300), "-1e300");
        assert_eq!(short(f64::MAX), "1.79769e308");
        assert_eq!(short(5e-324), "4.94066e-324");
        assert_eq!(short(-2.5), "-2.5");
        assert_eq!(short(3.0), "3");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(123456.7), "123456.7");
        assert_eq!(short(f64::NAN), "NaN");
        assert_eq!(short(f64::NEG_INFINITY), "-inf");
        for x in [1e-300, 7.3e201, -1.0 / 3.0, 1e-5, 999_999.9] {
            assert!(short(x).len() <= 12, "{x}: {}", short(x));
        }
    }

    #[test]
    fn cells_in_messages_are_short_and_on_one_line() {
        assert_eq!(short_text("abc"), "abc");
        assert_eq!(short_text("a\nb\u{0}"), "a\\nb\\u{0}");
        let long = "é".repeat(100);
        assert_eq!(short_text(&long), format!("{}…", "é".repeat(40)));
    }

    #[test]
    fn a_column_named_twice_is_found_with_both_positions() {
        let header = csv::StringRecord::from(vec!["a", "b", "a"]);
        assert_eq!(column_position(&header, "b"), Ok(Some(1)));
        assert_eq!(column_position(&header, "c"), Ok(None));
        let err = column_position(&header, "a").unwrap_err();
        assert_eq!((err.first, err.second), (1, 3));
    }
}
