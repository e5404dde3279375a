//! `ellipack measure`: the implicit-variable overlap measure of Birgin, Lobato and Martínez for
//! many pairs, in the column layout of the reference files `blm_3d.csv` and `blm_2d.csv`.
//!
//! Input, 3D: `cix, ciy, ciz, ai, bi, ci_ax, qwi, qxi, qyi, qzi` for ellipsoid i (centre,
//! semi-axes along the columns of the rotation, quaternion (w, x, y, z)) and the same with `j`;
//! 2D: `cix, ciy, ai, bi, theta_i, cjx, cjy, aj, bj, theta_j`. The layout is detected from the
//! header (`ciz` present: 3D); `case_id` is copied through; other columns are ignored.
//!
//! Output: `case_id, U, d2, eps, f, overlap, X_1, X_2[, X_3], error`, 17 significant digits.
//! i is the ellipsoid mapped to the unit ball: U, d², X and f are not symmetric in (i, j).
//! `X` is left blank where the projection is not unique (the hard case).

use crate::Error;
use crate::pairs::Summary;
use crate::table::{NumericReader, csv_reader, exact, quote, read_header, short};
use implicit_packing::{Body, PairTerm, pair_term};
use std::io::{Read, Write};

/// Input columns of the 3D layout, in the order the pair is built from.
pub const COLUMNS_3D: [&str; 20] = [
    "cix", "ciy", "ciz", "ai", "bi", "ci_ax", "qwi", "qxi", "qyi", "qzi", "cjx", "cjy", "cjz",
    "aj", "bj", "cj_ax", "qwj", "qxj", "qyj", "qzj",
];

/// Input columns of the 2D layout.
pub const COLUMNS_2D: [&str; 10] = [
    "cix", "ciy", "ai", "bi", "theta_i", "cjx", "cjy", "aj", "bj", "theta_j",
];

/// Evaluates the pair term of every row of `text` and returns the output table and the number
/// of rows that failed.
///
/// # Errors
/// As [`measure_stream`].
pub fn measure(text: &str, source_name: &str) -> Result<(String, usize), Error> {
    let mut out = Vec::new();
    let summary = measure_stream(text.as_bytes(), source_name, &mut out, "<memory>")?;
    // Every field written is UTF-8: the case_id comes from a `str`, the rest is ours.
    Ok((String::from_utf8_lossy(&out).into_owned(), summary.failed))
}

/// Reads pairs from `input` row by row and writes each result line to `output` at once, so
/// that memory does not depend on the number of rows. The layout is detected from the header
/// (`ciz` present: 3D).
///
/// # Errors
/// [`Error::MalformedCsv`] for broken CSV structure, [`Error::MissingColumn`] or
/// [`Error::DuplicateColumn`] for the header, [`Error::Empty`] without rows (nothing is
/// written then), [`Error::Write`] when `output` refuses the data.
pub fn measure_stream<R: Read, W: Write + ?Sized>(
    input: R,
    source_name: &str,
    output: &mut W,
    destination: &str,
) -> Result<Summary, Error> {
    let mut reader = csv_reader(input);
    let header = read_header(&mut reader, source_name)?;
    let three_d = header.iter().any(|h| h == "ciz");
    let columns: &[&str] = if three_d { &COLUMNS_3D } else { &COLUMNS_2D };
    let mut rows = NumericReader::new(reader, &header, source_name, columns)?;
    let output_columns = if three_d {
        "U,d2,eps,f,overlap,X_1,X_2,X_3"
    } else {
        "U,d2,eps,f,overlap,X_1,X_2"
    };
    let blanks = ",".repeat(output_columns.matches(',').count());
    let write_error = |source| Error::Write {
        destination: destination.to_string(),
        source,
    };
    let mut summary = Summary::default();
    while let Some(row) = rows.next_row()? {
        if summary.rows == 0 {
            writeln!(output, "case_id,{output_columns},error").map_err(write_error)?;
        }
        summary.rows += 1;
        let id = quote(&row.case_id);
        let result = row.values.and_then(|v| {
            if three_d {
                evaluate_3d(&v)
            } else {
                evaluate_2d(&v)
            }
            .map_err(|e| format!("line {}: {e}", row.line))
        });
        match result {
            Ok(fields) => writeln!(output, "{id},{fields},"),
            Err(message) => {
                summary.failed += 1;
                writeln!(output, "{id},{blanks},{}", quote(&message))
            }
        }
        .map_err(write_error)?;
    }
    if summary.rows == 0 {
        return Err(Error::Empty {
            source_name: source_name.to_string(),
        });
    }
    output.flush().map_err(write_error)?;
    Ok(summary)
}

fn evaluate_3d(v: &[f64]) -> Result<String, String> {
    let i = Body::from_quaternion(
        [v[0], v[1], v[2]],
        [v[3], v[4], v[5]],
        [v[6], v[7], v[8], v[9]],
    )
    .map_err(|e| format!("ellipsoid i: {}", body_message(&e)))?;
    let j = Body::from_quaternion(
        [v[10], v[11], v[12]],
        [v[13], v[14], v[15]],
        [v[16], v[17], v[18], v[19]],
    )
    .map_err(|e| format!("ellipsoid j: {}", body_message(&e)))?;
    Ok(fields(&pair_term(&i, &j)))
}

fn evaluate_2d(v: &[f64]) -> Result<String, String> {
    let i = Body::ellipse([v[0], v[1]], [v[2], v[3]], v[4])
        .map_err(|e| format!("ellipse i: {}", body_message(&e)))?;
    let j = Body::ellipse([v[5], v[6]], [v[7], v[8]], v[9])
        .map_err(|e| format!("ellipse j: {}", body_message(&e)))?;
    Ok(fields(&pair_term(&i, &j)))
}

/// Why a body was refused, with its numbers written short: implicit-packing's own messages
/// print a value such as -1e300 with all its 301 digits.
fn body_message(e: &implicit_packing::Error) -> String {
    use implicit_packing::Error as E;
    match *e {
        E::NonFiniteCentre { axis, value, .. } => format!(
            "centre coordinate {axis} is {}; coordinates must be finite, |x| <= 1e30",
            short(value)
        ),
        E::InvalidSemiAxis { axis, value, .. } => format!(
            "semi-axis {axis} is {}; semi-axes must lie in [1e-30, 1e30]",
            short(value)
        ),
        E::NonFiniteAngle { angle, value, .. } => {
            format!(
                "rotation angle {angle} is {}, not a finite number",
                short(value)
            )
        }
        E::InvalidQuaternion {
            quaternion: [w, x, y, z],
            norm2,
            ..
        } => format!(
            "quaternion (w, x, y, z) = ({}, {}, {}, {}) has squared norm {}; a rotation needs \
             a finite unit quaternion (|q|² within 1e-6 of 1)",
            short(w),
            short(x),
            short(y),
            short(z),
            short(norm2)
        ),
        _ => e.to_string(),
    }
}

/// The output fields of one pair term, without the leading case_id and trailing error.
fn fields<const N: usize>(p: &PairTerm<N>) -> String {
    let x =
        p.x.iter()
            .map(|&x| if p.x_unique { exact(x) } else { String::new() })
            .collect::<Vec<_>>()
            .join(",");
    format!(
        "{},{},{},{},{},{x}",
        exact(p.u),
        exact(p.d2),
        exact(p.eps),
        exact(p.f),
        p.f > 0.0
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_d_row_and_a_bad_row() {
        let header = format!("case_id,{}\n", COLUMNS_2D.join(","));
        // Two unit circles 3 apart: c = (−3, 0) in the frame of i, X = (−1, 0), d² = 4, f = 0.
        let apart = "a,0,0,1,1,0,3,0,1,1,0\n";
        let bad = "b,0,0,-1,1,0,3,0,1,1,0\n";
        let (table, failed) = measure(&format!("{header}{apart}{bad}"), "t.csv").unwrap();
        assert_eq!(failed, 1, "{table}");
        let mut lines = table.lines();
        assert_eq!(
            lines.next(),
            Some("case_id,U,d2,eps,f,overlap,X_1,X_2,error")
        );
        let a: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(a[0], "a");
        let d2: f64 = a[2].parse().unwrap();
        assert!((d2 - 4.0).abs() < 1e-14, "{d2}");
        assert_eq!(a[4].parse::<f64>().unwrap(), 0.0);
        assert_eq!(a[5], "false");
        let b = lines.next().unwrap();
        assert!(b.starts_with("b,,,,,,,,") && b.contains("line 3"), "{b}");
    }
}
