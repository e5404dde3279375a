//! Comma-separated tables read by column name.
//!
//! The reference files and the CLI's outputs have no quoted fields, so a line splits on
//! commas; a quoted field is reported as an error rather than read wrongly.

use std::fmt;
use std::path::{Path, PathBuf};

/// Why a table could not be read, naming the file and, for a cell, its line and column.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// The file could not be read.
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// The file has no header line.
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// The header has no column of this name.
    MissingColumn {
        /// The file.
        path: PathBuf,
        /// The column asked for.
        column: String,
    },
    /// A line has a different number of fields from the header, or a quoted field.
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong with it.
        message: String,
    },
    /// A cell that should hold a number does not.
    Number {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// The column.
        column: String,
        /// The cell's text.
        text: String,
        /// The parser's reason.
        source: std::num::ParseFloatError,
    },
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Io { path, .. } => write!(f, "{}: cannot read the file", path.display()),
            Error::Empty { path } => write!(f, "{}: no header line", path.display()),
            Error::MissingColumn { path, column } => {
                write!(f, "{}: no column `{column}`", path.display())
            }
            Error::Malformed {
                path,
                line,
                message,
            } => write!(f, "{}: line {line}: {message}", path.display()),
            Error::Number {
                path,
                line,
                column,
                text,
                ..
            } => write!(
                f,
                "{}: line {line}: column `{column}`: `{text}` is not a number",
                path.display()
            ),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io { source, .. } => Some(source),
            Error::Number { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// A table: its header and its non-blank lines, each with its line number.
#[derive(Debug, Clone)]
pub struct Table {
    path: PathBuf,
    header: Vec<String>,
    rows: Vec<(usize, Vec<String>)>,
}

impl Table {
    /// Reads the file at `path`.
    pub fn read(path: impl AsRef<Path>) -> Result<Table, Error> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Table::parse(path, &text)
    }

    /// Parses `text`; `path` names the source in errors.
    pub fn parse(path: impl AsRef<Path>, text: &str) -> Result<Table, Error> {
        let path = path.as_ref().to_path_buf();
        let mut lines = text.lines().enumerate();
        let header = match lines.next() {
            Some((_, h)) if !h.trim().is_empty() => split(h),
            _ => return Err(Error::Empty { path }),
        };
        let mut rows = Vec::new();
        for (k, l) in lines {
            if l.trim().is_empty() {
                continue;
            }
            let line = k + 1;
            let malformed = |message: String| Error::Malformed {
                path: path.clone(),
                line,
                message,
            };
            if l.contains('"') {
                return Err(malformed("quoted fields are not supported".into()));
            }
            let fields = split(l);
            if fields.len() != header.len() {
                return Err(malformed(format!(
                    "{} fields, the header has {}",
                    fields.len(),
                    header.len()
                )));
            }
            rows.push((line, fields));
        }
        Ok(Table { path, header, rows })
    }

    /// The file the table came from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The column names.
    pub fn header(&self) -> &[String] {
        &self.header
    }

    /// The index of the column `name`.
    pub fn column(&self, name: &str) -> Result<usize, Error> {
        self.header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| Error::MissingColumn {
                path: self.path.clone(),
                column: name.to_string(),
            })
    }

    /// The number of data rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether there is no data row.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The data rows in file order.
    pub fn rows(&self) -> impl Iterator<Item = Row<'_>> {
        self.rows.iter().map(move |(line, fields)| Row {
            table: self,
            line: *line,
            fields,
        })
    }
}

fn split(line: &str) -> Vec<String> {
    line.split(',').map(|s| s.trim().to_string()).collect()
}

/// One data row of a [`Table`].
#[derive(Debug, Clone, Copy)]
pub struct Row<'a> {
    table: &'a Table,
    line: usize,
    fields: &'a [String],
}

impl<'a> Row<'a> {
    /// The 1-based line of the row in its file.
    pub fn line(&self) -> usize {
        self.line
    }

    /// The cell in column `name`, trimmed.
    pub fn text(&self, name: &str) -> Result<&'a str, Error> {
        Ok(&self.fields[self.table.column(name)?])
    }

    /// The cell in column `name` as a number (`nan` and `inf` are accepted).
    pub fn num(&self, name: &str) -> Result<f64, Error> {
        let text = self.text(name)?;
        text.parse::<f64>().map_err(|source| Error::Number {
            path: self.table.path.clone(),
            line: self.line,
            column: name.to_string(),
            text: text.to_string(),
            source,
        })
    }

    /// The cell in column `name` as a number, or `None` where it is blank.
    pub fn opt(&self, name: &str) -> Result<Option<f64>, Error> {
        if self.text(name)?.is_empty() {
            Ok(None)
        } else {
            self.num(name).map(Some)
        }
    }

    /// The cells of the columns `names` as numbers.
    pub fn nums<const K: usize>(&self, names: [&str; K]) -> Result<[f64; K], Error> {
        let mut out = [0.0; K];
        for (o, name) in out.iter_mut().zip(names) {
            *o = self.num(name)?;
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_by_name_and_errors_naming_line_and_column() {
        let t = Table::parse("t.csv", "a,b,c\n1,2.5,\n\n3,x,4\n").unwrap();
        assert_eq!(t.len(), 2);
        let rows: Vec<Row<'_>> = t.rows().collect();
        assert_eq!(rows[0].nums(["a", "b"]).unwrap(), [1.0, 2.5]);
        assert_eq!(rows[0].opt("c").unwrap(), None);
        assert_eq!(rows[1].line(), 4);
        let e = rows[1].num("b").unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.csv: line 4: column `b`: `x` is not a number"
        );
        assert!(std::error::Error::source(&e).is_some());
        let e = rows[1].num("d").unwrap_err();
        assert_eq!(e.to_string(), "t.csv: no column `d`");
    }

    #[test]
    fn malformed_tables_are_errors() {
        let e = Table::parse("t.csv", "a,b\n1\n").unwrap_err();
        assert_eq!(e.to_string(), "t.csv: line 2: 1 fields, the header has 2");
        let e = Table::parse("t.csv", "a,b\n\"1,2\",3\n").unwrap_err();
        assert!(e.to_string().starts_with("t.csv: line 2: quoted"), "{e}");
        assert!(matches!(
            Table::parse("t.csv", ""),
            Err(Error::Empty { .. })
        ));
        let e = Table::read("/no/such/file.csv").unwrap_err();
        assert!(matches!(e, Error::Io { .. }), "{e}");
    }
}
