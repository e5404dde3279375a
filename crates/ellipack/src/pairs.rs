//! Pairs of ellipsoids in CSV, as the PW85 reference files store them, and the results of
//! `ellipack contact`.
//!
//! Input: a header naming at least `r12_x, r12_y, r12_z, q1_0 … q1_5, q2_0 … q2_5` (Q in the
//! PW85 storage Q11, Q12, Q13, Q22, Q23, Q33), in any order; `case_id` is copied to the output
//! (else the 1-based row number is); every other column is ignored, so the reference file
//! `pw85_contact.csv` is accepted as it is.
//!
//! Output: `case_id, mu2, lambda, overlap, error` (or `case_id, overlap, error` for the verdict
//! alone), numbers with 17 significant digits so that they read back to the same double.

use crate::Error;
use crate::table::{exact, quote, read_numeric_rows};
use pw85::batch::Pair;

/// The input columns, in the order they fill a [`Pair`].
pub const PAIR_COLUMNS: [&str; 15] = [
    "r12_x", "r12_y", "r12_z", "q1_0", "q1_1", "q1_2", "q1_3", "q1_4", "q1_5", "q2_0", "q2_1",
    "q2_2", "q2_3", "q2_4", "q2_5",
];

/// One data row: its identity and either the pair or why it could not be read.
#[derive(Clone, Debug, PartialEq)]
pub struct PairRow {
    /// The `case_id` column, or the 1-based row number.
    pub case_id: String,
    /// The 1-based line of the file.
    pub line: u64,
    /// The pair, or a message naming the line and column of the cell that is not a number.
    pub pair: Result<Pair, String>,
}

/// Reads pairs from CSV text. `source_name` names the input in messages.
///
/// # Errors
/// [`Error::MalformedCsv`] (with the line) for broken CSV structure,
/// [`Error::MissingColumn`] when a required column is absent, [`Error::Empty`] without rows. A
/// cell that is not a number is not an error of the file: that row carries the message.
pub fn read_pairs(text: &str, source_name: &str) -> Result<Vec<PairRow>, Error> {
    Ok(read_numeric_rows(text, source_name, &PAIR_COLUMNS)?
        .into_iter()
        .map(|row| PairRow {
            case_id: row.case_id,
            line: row.line,
            pair: row.values.map(|v| Pair {
                r12: [v[0], v[1], v[2]],
                q1: core::array::from_fn(|k| v[3 + k]),
                q2: core::array::from_fn(|k| v[9 + k]),
            }),
        })
        .collect())
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

/// Evaluates every readable row and formats the result table. Returns the CSV text and the
/// number of rows that failed (bad cell, non-finite value, matrix not positive definite).
pub fn evaluate(rows: &[PairRow], criterion: Criterion) -> (String, usize) {
    let mut out = String::new();
    let mut failed = 0;
    match criterion {
        Criterion::Contact => out.push_str("case_id,mu2,lambda,overlap,error\n"),
        Criterion::Overlap => out.push_str("case_id,overlap,error\n"),
    }
    let pairs: Vec<Pair> = rows.iter().filter_map(|r| r.pair.clone().ok()).collect();
    let mut contacts = Vec::new();
    let mut verdicts = Vec::new();
    match criterion {
        Criterion::Contact => contacts = pw85::batch::contact_functions(&pairs),
        Criterion::Overlap => verdicts = pw85::batch::overlaps(&pairs),
    }
    let (mut contacts, mut verdicts) = (contacts.into_iter(), verdicts.into_iter());
    for row in rows {
        let id = quote(&row.case_id);
        let line = match (&row.pair, criterion) {
            (Err(message), Criterion::Contact) => format!("{id},,,,{}", quote(message)),
            (Err(message), Criterion::Overlap) => format!("{id},,{}", quote(message)),
            (Ok(_), Criterion::Contact) => match contacts.next() {
                Some(Ok(c)) => {
                    format!("{id},{},{},{},", exact(c.mu2), exact(c.lambda), c.mu2 < 1.0)
                }
                Some(Err(e)) => format!("{id},,,,{}", quote(&format!("line {}: {e}", row.line))),
                None => unreachable!("one result per readable row"),
            },
            (Ok(_), Criterion::Overlap) => match verdicts.next() {
                Some(Ok(v)) => format!("{id},{v},"),
                Some(Err(e)) => format!("{id},,{}", quote(&format!("line {}: {e}", row.line))),
                None => unreachable!("one result per readable row"),
            },
        };
        if line.ends_with(',') {
            out.push_str(&line);
        } else {
            failed += 1;
            out.push_str(&line);
        }
        out.push('\n');
    }
    (out, failed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bundled_example_reads_and_evaluates() {
        let rows = read_pairs(crate::EXAMPLE_PAIRS, "example").unwrap();
        assert_eq!(rows.len(), 9);
        let (table, failed) = evaluate(&rows, Criterion::Contact);
        assert_eq!(failed, 1, "{table}");
        let spheres = table.lines().nth(1).unwrap();
        assert!(
            spheres.starts_with("unit-spheres-apart,2.2500000000000000e0,"),
            "{spheres}"
        );
        let bad = table
            .lines()
            .find(|l| l.starts_with("not-positive-definite"))
            .unwrap();
        assert!(
            bad.contains("line 10") && bad.contains("Q2 is not positive definite"),
            "{bad}"
        );
    }

    #[test]
    fn a_bad_cell_fails_only_its_row() {
        let header = format!("case_id,{}\n", PAIR_COLUMNS.join(","));
        let good = "a,3,0,0,1,0,0,1,0,1,1,0,0,1,0,1\n";
        let bad = "b,3,0,zero,1,0,0,1,0,1,1,0,0,1,0,1\n";
        let rows = read_pairs(&format!("{header}{good}{bad}"), "t.csv").unwrap();
        let (table, failed) = evaluate(&rows, Criterion::Overlap);
        assert_eq!(failed, 1);
        assert!(table.contains("a,false,"));
        assert!(
            table.contains("line 3, column 4 (r12_z): `zero` is not a number"),
            "{table}"
        );
    }

    #[test]
    fn structural_errors_name_the_line() {
        let header = format!("{}\n", PAIR_COLUMNS.join(","));
        let ragged = "1,2,3\n";
        let err = read_pairs(&format!("{header}{ragged}"), "t.csv")
            .unwrap_err()
            .to_string();
        assert!(err.contains("t.csv: line 2"), "{err}");
        let err = read_pairs("r12_x,r12_y\n1,2\n", "t.csv")
            .unwrap_err()
            .to_string();
        assert!(err.contains("missing column `r12_z`"), "{err}");
        let err = read_pairs(&header, "t.csv").unwrap_err().to_string();
        assert!(err.contains("no rows"), "{err}");
    }
}
