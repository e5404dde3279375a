//! Pairs of ellipsoids in CSV, as the PW85 reference files store them, and the results of
//! `ellipack contact`.
//!
//! Input: a header naming at least `r12_x, r12_y, r12_z, q1_0 … q1_5, q2_0 … q2_5` (Q in the
//! PW85 storage Q11, Q12, Q13, Q22, Q23, Q33) for ellipsoids, or `r12_x, r12_y, q1_0 … q1_2,
//! q2_0 … q2_2` (Q11, Q12, Q22) for ellipses, in any order; `case_id` is copied to the output
//! (else the 1-based row number is); every other column is ignored, so the reference file
//! `pw85_contact.csv` is accepted as it is. A column named twice is an error.
//!
//! Output: `case_id, mu2, lambda, overlap, error` (or `case_id, overlap, error` for the verdict
//! alone), numbers with 17 significant digits so that they read back to the same double.

use crate::Error;
use crate::table::{NumericReader, NumericRow, csv_reader, exact, quote, read_header};
use pw85::Contact;
use pw85::batch::{Pair, Pair2d};
use std::io::{Read, Write};

/// The input columns of a 3D file, in the order they fill a [`Pair`].
pub const PAIR_COLUMNS: [&str; 15] = [
    "r12_x", "r12_y", "r12_z", "q1_0", "q1_1", "q1_2", "q1_3", "q1_4", "q1_5", "q2_0", "q2_1",
    "q2_2", "q2_3", "q2_4", "q2_5",
];

/// The input columns of a 2D file (ellipses, Q = [Q11, Q12, Q22]), in the order they fill a
/// [`Pair2d`].
pub const PAIR_COLUMNS_2D: [&str; 8] = [
    "r12_x", "r12_y", "q1_0", "q1_1", "q1_2", "q2_0", "q2_1", "q2_2",
];

/// Rows evaluated together through the batch kernels: large enough for their four-lane speed,
/// small enough that memory does not grow with the file.
pub const CHUNK_ROWS: usize = 4096;

/// Whether a pairs file holds ellipsoids or ellipses, decided from its header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// Ellipsoids: [`PAIR_COLUMNS`].
    ThreeD,
    /// Ellipses: [`PAIR_COLUMNS_2D`].
    TwoD,
}

impl Layout {
    /// The columns this layout reads.
    pub fn columns(self) -> &'static [&'static str] {
        match self {
            Layout::ThreeD => &PAIR_COLUMNS,
            Layout::TwoD => &PAIR_COLUMNS_2D,
        }
    }

    /// Decides the layout from a header: every 3D column present is 3D; every 2D column
    /// present and no column that only a 3D file has is 2D.
    ///
    /// # Errors
    /// [`Error::PairLayout`] naming what each layout lacks.
    pub fn of_header(header: &csv::StringRecord, source_name: &str) -> Result<Layout, Error> {
        let has = |c: &&str| header.iter().any(|h| h == *c);
        let missing = |columns: &[&str]| -> Vec<String> {
            columns
                .iter()
                .filter(|c| !has(c))
                .map(|c| (*c).to_string())
                .collect()
        };
        let missing_3d = missing(&PAIR_COLUMNS);
        if missing_3d.is_empty() {
            return Ok(Layout::ThreeD);
        }
        let missing_2d = missing(&PAIR_COLUMNS_2D);
        let only_3d: Vec<String> = PAIR_COLUMNS
            .iter()
            .filter(|c| !PAIR_COLUMNS_2D.contains(c) && has(c))
            .map(|c| (*c).to_string())
            .collect();
        if missing_2d.is_empty() && only_3d.is_empty() {
            return Ok(Layout::TwoD);
        }
        let two_d = if missing_2d.is_empty() {
            format!(
                "it also has {}, which only a 3D file has",
                only_3d.join(", ")
            )
        } else {
            format!("missing {}", missing_2d.join(", "))
        };
        Err(Error::PairLayout {
            source_name: source_name.to_string(),
            three_d: format!("missing {}", missing_3d.join(", ")),
            two_d,
        })
    }
}

/// The rows of a pairs file, read whole (the command streams them instead; see
/// [`contact_stream`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PairTable {
    /// 3D or 2D.
    pub layout: Layout,
    /// Each row's identity and values ([`Layout::columns`], in that order) or why a cell could
    /// not be read.
    pub rows: Vec<NumericRow>,
}

/// Reads pairs from CSV text. `source_name` names the input in messages.
///
/// # Errors
/// [`Error::Malformed`] (with the line) for broken CSV structure, [`Error::PairLayout`]
/// when the header is neither layout, [`Error::DuplicateColumn`] when a column appears twice,
/// [`Error::Empty`] without rows. A cell that is not a number is not an error of the file: that
/// row carries the message.
pub fn read_pairs(text: &str, source_name: &str) -> Result<PairTable, Error> {
    let (layout, reader) = open(text.as_bytes(), source_name)?;
    let rows = reader.read_all()?;
    Ok(PairTable { layout, rows })
}

fn open<R: Read>(input: R, source_name: &str) -> Result<(Layout, NumericReader<R>), Error> {
    let mut reader = csv_reader(input);
    let header = read_header(&mut reader, source_name)?;
    let layout = Layout::of_header(&header, source_name)?;
    let rows = NumericReader::new(reader, &header, source_name, layout.columns())?;
    Ok((layout, rows))
}

/// What `ellipack contact` computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Criterion {
    /// μ², λ and the verdict.
    Contact,
    /// The verdict alone (μ² is never computed unless the pair is within rounding of
    /// tangency).
    Overlap,
}

impl Criterion {
    fn header(self) -> &'static str {
        match self {
            Criterion::Contact => "case_id,mu2,lambda,overlap,error\n",
            Criterion::Overlap => "case_id,overlap,error\n",
        }
    }
}

/// How many rows a command evaluated, and how many of them failed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Data rows read.
    pub rows: usize,
    /// Rows whose `error` column is filled.
    pub failed: usize,
}

/// Evaluates every readable row and formats the result table. Returns the CSV text and the
/// number of rows that failed (bad cell, non-finite value, matrix not positive definite).
pub fn evaluate(table: &PairTable, criterion: Criterion) -> (String, usize) {
    let mut out = criterion.header().to_string();
    let mut failed = 0;
    for chunk in table.rows.chunks(CHUNK_ROWS) {
        failed += evaluate_chunk(chunk, table.layout, criterion, &mut out);
    }
    (out, failed)
}

/// Reads pairs from `input`, evaluates them [`CHUNK_ROWS`] at a time and writes the result
/// table to `output` as it goes, so that memory does not depend on the number of rows.
/// `source_name` and `destination` name the input and the output in messages.
///
/// # Errors
/// As [`read_pairs`] for the input (nothing is written when the header is wrong or the file
/// has no rows); [`Error::Write`] when `output` refuses the data (a closed pipe gives
/// [`std::io::ErrorKind::BrokenPipe`]).
pub fn contact_stream<R: Read, W: Write + ?Sized>(
    input: R,
    source_name: &str,
    criterion: Criterion,
    output: &mut W,
    destination: &str,
) -> Result<Summary, Error> {
    let (layout, mut rows) = open(input, source_name)?;
    let write_error = |source| Error::Write {
        destination: destination.to_string(),
        source,
    };
    let mut text = String::new();
    let summary = in_chunks(&mut rows, CHUNK_ROWS, |first, chunk| {
        text.clear();
        if first {
            text.push_str(criterion.header());
        }
        let failed = evaluate_chunk(chunk, layout, criterion, &mut text);
        output.write_all(text.as_bytes()).map_err(write_error)?;
        Ok(failed)
    })?;
    if summary.rows == 0 {
        return Err(Error::Empty {
            source_name: source_name.to_string(),
        });
    }
    output.flush().map_err(write_error)?;
    Ok(summary)
}

/// Reads `rows` in chunks of at most `chunk_rows` rows and hands each to `each` (with `true`
/// for the first chunk), which returns how many of its rows failed. An empty input calls
/// `each` never.
pub(crate) fn in_chunks<R: Read>(
    rows: &mut NumericReader<R>,
    chunk_rows: usize,
    mut each: impl FnMut(bool, &[NumericRow]) -> Result<usize, Error>,
) -> Result<Summary, Error> {
    let mut summary = Summary::default();
    let mut chunk = Vec::with_capacity(chunk_rows);
    let mut first = true;
    loop {
        chunk.clear();
        while chunk.len() < chunk_rows {
            match rows.next_row()? {
                Some(row) => chunk.push(row),
                None => break,
            }
        }
        if chunk.is_empty() {
            return Ok(summary);
        }
        summary.rows += chunk.len();
        summary.failed += each(first, &chunk)?;
        first = false;
    }
}

/// One pair's result, whichever the criterion.
enum Outcome {
    Contact(Contact),
    Verdict(bool),
}

fn pair_3d(v: &[f64]) -> Pair {
    Pair {
        r12: [v[0], v[1], v[2]],
        q1: core::array::from_fn(|k| v[3 + k]),
        q2: core::array::from_fn(|k| v[9 + k]),
    }
}

fn pair_2d(v: &[f64]) -> Pair2d {
    Pair2d {
        r12: [v[0], v[1]],
        q1: core::array::from_fn(|k| v[2 + k]),
        q2: core::array::from_fn(|k| v[5 + k]),
    }
}

/// The kernel's results for `values` (each a row in the layout's column order), through the
/// batch functions.
fn outcomes(
    values: &[&[f64]],
    layout: Layout,
    criterion: Criterion,
) -> Vec<Result<Outcome, pw85::Error>> {
    use pw85::batch::{BatchPair, Parallelism, contact_functions, overlaps};
    fn outcomes<P: BatchPair>(
        pairs: &[P],
        criterion: Criterion,
    ) -> Vec<Result<Outcome, pw85::Error>> {
        match criterion {
            Criterion::Contact => {
                let mut out = vec![Ok(pw85::batch::EMPTY_CONTACT); pairs.len()];
                contact_functions(pairs, &mut out, Parallelism::Serial);
                out.into_iter().map(|r| r.map(Outcome::Contact)).collect()
            }
            Criterion::Overlap => {
                let mut out = vec![Ok(false); pairs.len()];
                overlaps(pairs, &mut out, Parallelism::Serial);
                out.into_iter().map(|r| r.map(Outcome::Verdict)).collect()
            }
        }
    }
    match layout {
        Layout::ThreeD => {
            let pairs: Vec<Pair> = values.iter().map(|v| pair_3d(v)).collect();
            outcomes(&pairs, criterion)
        }
        Layout::TwoD => {
            let pairs: Vec<Pair2d> = values.iter().map(|v| pair_2d(v)).collect();
            outcomes(&pairs, criterion)
        }
    }
}

/// Evaluates `rows` and appends their result lines to `out`; returns how many failed.
fn evaluate_chunk(
    rows: &[NumericRow],
    layout: Layout,
    criterion: Criterion,
    out: &mut String,
) -> usize {
    let values: Vec<&[f64]> = rows
        .iter()
        .filter_map(|r| r.values.as_deref().ok())
        .collect();
    let mut results = outcomes(&values, layout, criterion).into_iter();
    let blanks = match criterion {
        Criterion::Contact => ",,",
        Criterion::Overlap => "",
    };
    let mut failed = 0;
    for row in rows {
        let id = quote(&row.case_id);
        let result = match &row.values {
            Err(message) => Err(message.clone()),
            // One result per readable row, in order; a missing one is reported, not panicked on.
            Ok(_) => match results.next() {
                Some(Ok(outcome)) => Ok(outcome),
                Some(Err(e)) => Err(format!("line {}: {e}", row.line)),
                None => Err(format!("line {}: no result was computed", row.line)),
            },
        };
        match result {
            Ok(Outcome::Contact(c)) => out.push_str(&format!(
                "{id},{},{},{},\n",
                exact(c.mu2),
                exact(c.lambda),
                c.mu2 < 1.0
            )),
            Ok(Outcome::Verdict(v)) => out.push_str(&format!("{id},{v},\n")),
            Err(message) => {
                failed += 1;
                out.push_str(&format!("{id},{blanks},{}\n", quote(&message)));
            }
        }
    }
    failed
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The message of the error that reading `text` as pairs gives.
    fn read_error(text: &str, source_name: &str) -> String {
        match read_pairs(text, source_name) {
            Ok(table) => panic!("{source_name} was read: {table:?}"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn the_bundled_example_reads_and_evaluates() {
        let table = read_pairs(crate::EXAMPLE_PAIRS, "example").unwrap();
        assert_eq!(table.layout, Layout::ThreeD);
        assert_eq!(table.rows.len(), 9);
        let (text, failed) = evaluate(&table, Criterion::Contact);
        assert_eq!(failed, 1, "{text}");
        let spheres = text.lines().nth(1).unwrap();
        assert!(
            spheres.starts_with("unit-spheres-apart,2.2500000000000000e0,"),
            "{spheres}"
        );
        let bad = text
            .lines()
            .find(|l| l.starts_with("not-positive-definite"))
            .unwrap();
        assert!(
            bad.contains("line 10") && bad.contains("Q2 is not positive definite"),
            "{bad}"
        );
        assert!(bad.starts_with("not-positive-definite,,,,\"line"), "{bad}");
    }

    #[test]
    fn a_bad_cell_fails_only_its_row() {
        let header = format!("case_id,{}\n", PAIR_COLUMNS.join(","));
        let good = "a,3,0,0,1,0,0,1,0,1,1,0,0,1,0,1\n";
        let bad = "b,3,0,zero,1,0,0,1,0,1,1,0,0,1,0,1\n";
        let table = read_pairs(&format!("{header}{good}{bad}"), "t.csv").unwrap();
        let (text, failed) = evaluate(&table, Criterion::Overlap);
        assert_eq!(failed, 1);
        assert!(text.contains("a,false,"));
        assert!(
            text.contains("b,,\"line 3, column 4 (r12_z): `zero` is not a number\""),
            "{text}"
        );
    }

    /// Two unit circles 3 apart and two overlapping ellipses, through the 2D kernel.
    #[test]
    fn a_2d_file_is_evaluated_by_the_2d_kernel() {
        let text = "case_id,r12_x,r12_y,q1_0,q1_1,q1_2,q2_0,q2_1,q2_2\n\
                    apart,3,0,1,0,1,1,0,1\n\
                    close,1,0,4,0,1,1,0,1\n\
                    bad,1,0,1,2,1,1,0,1\n";
        let table = read_pairs(text, "t.csv").unwrap();
        assert_eq!(table.layout, Layout::TwoD);
        let (out, failed) = evaluate(&table, Criterion::Contact);
        assert_eq!(failed, 1, "{out}");
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines[0], "case_id,mu2,lambda,overlap,error");
        let expected =
            pw85::contact_function(&[3.0, 0.0], &[1.0, 0.0, 1.0], &[1.0, 0.0, 1.0]).unwrap();
        assert_eq!(
            lines[1],
            format!(
                "apart,{},{},false,",
                exact(expected.mu2),
                exact(expected.lambda)
            )
        );
        assert!(lines[2].starts_with("close,") && lines[2].ends_with(",true,"));
        assert!(
            lines[3].starts_with("bad,,,,") && lines[3].contains("Q1 is not positive definite"),
            "{}",
            lines[3]
        );
        let (out, failed) = evaluate(&table, Criterion::Overlap);
        assert_eq!(failed, 1);
        assert!(out.contains("\napart,false,\nclose,true,\n"), "{out}");
    }

    /// A file that cannot be read names the file, the line and the columns at fault.
    #[test]
    fn file_errors_name_the_line_and_the_columns() {
        let columns = PAIR_COLUMNS.join(",");
        let row = "a,9,3,0,0,1,0,0,1,0,1,1,0,0,1,0,1\n";
        let mixed = "r12_x,r12_y,r12_z,q1_0,q1_1,q1_2,q2_0,q2_1,q2_2\n1,0,0,1,0,1,1,0,1\n";
        let cases: [(String, &str, &[&str]); 7] = [
            (format!("{columns}\n1,2,3\n"), "t.csv", &["t.csv: line 2"]),
            ("r12_x,r12_y\n1,2\n".into(), "t.csv", &["missing r12_z"]),
            (format!("{columns}\n"), "t.csv", &["no rows"]),
            (
                mixed.into(),
                "m.csv",
                &[
                    "m.csv: line 1",
                    "missing q1_3, q1_4, q1_5, q2_3, q2_4, q2_5",
                    "it also has r12_z",
                ],
            ),
            (
                "r12_x,r12_y,q1_0\n1,2,3\n".into(),
                "m.csv",
                &["missing q1_1, q1_2, q2_0, q2_1, q2_2"],
            ),
            (
                format!("case_id,r12_x,{columns}\n{row}"),
                "d.csv",
                &["d.csv: line 1: column `r12_x` appears twice in the header (columns 2 and 3)"],
            ),
            (
                format!("case_id,case_id,{columns}\nx,{row}"),
                "d.csv",
                &["`case_id` appears twice"],
            ),
        ];
        for (text, source_name, expected) in cases {
            let err = read_error(&text, source_name);
            for part in expected {
                assert!(err.contains(part), "{source_name}: {part}: {err}");
            }
        }
    }

    #[test]
    fn rows_are_read_and_evaluated_in_bounded_chunks() {
        let header = format!("case_id,{}\n", PAIR_COLUMNS.join(","));
        let mut text = header;
        let n = 10 * 7 + 3;
        for i in 0..n {
            text.push_str(&format!("{i},3,0,0,1,0,0,1,0,1,1,0,0,1,0,1\n"));
        }
        let (_, mut rows) = open(text.as_bytes(), "t.csv").unwrap();
        let mut sizes = Vec::new();
        let summary = in_chunks(&mut rows, 7, |first, chunk| {
            assert_eq!(first, sizes.is_empty());
            sizes.push(chunk.len());
            Ok(0)
        })
        .unwrap();
        assert_eq!(summary, Summary { rows: n, failed: 0 });
        assert!(sizes.iter().all(|&s| (1..=7).contains(&s)), "{sizes:?}");
        assert_eq!(sizes.len(), 11);

        let mut out = Vec::new();
        let summary =
            contact_stream(text.as_bytes(), "t.csv", Criterion::Overlap, &mut out, "o").unwrap();
        assert_eq!(summary.rows, n);
        let out = String::from_utf8(out).unwrap();
        assert_eq!(out.lines().count(), n + 1);
        assert_eq!(out.matches("case_id").count(), 1, "one header");
    }

    #[test]
    fn streaming_writes_the_same_table_as_the_whole_file() {
        for criterion in [Criterion::Contact, Criterion::Overlap] {
            let (whole, failed) =
                evaluate(&read_pairs(crate::EXAMPLE_PAIRS, "e").unwrap(), criterion);
            let mut out = Vec::new();
            let summary = contact_stream(
                crate::EXAMPLE_PAIRS.as_bytes(),
                "e",
                criterion,
                &mut out,
                "o",
            )
            .unwrap();
            assert_eq!(String::from_utf8(out).unwrap(), whole);
            assert_eq!(summary.failed, failed);
        }
    }

    #[test]
    fn an_empty_file_writes_nothing() {
        let mut out = Vec::new();
        let header = format!("{}\n", PAIR_COLUMNS.join(","));
        let err = contact_stream(
            header.as_bytes(),
            "e.csv",
            Criterion::Contact,
            &mut out,
            "o",
        )
        .unwrap_err();
        assert!(err.to_string().contains("e.csv: no rows"), "{err}");
        assert!(out.is_empty());
    }
}
