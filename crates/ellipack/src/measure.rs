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
use crate::table::{NumericReader, csv_reader, exact, quote, read_header};
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
/// [`Error::Malformed`] for broken CSV structure, [`Error::MissingColumn`] or
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

/// The pair in the units of its larger body, centred on body i.
///
/// The measure is invariant under a translation of both bodies and under scaling positions and
/// semi-axes together: c = P_i^−1/2 Q_iᵀ (c_i − c_j) and S of eqs. (21)–(22) are ratios of
/// lengths, so X, U, d² and f are too, and ε (Prop. 3.3) is a product of ratios. Centring on
/// c_i gives the model the difference it forms itself (c_i − c_j = −(c_j − c_i) exactly in
/// floating point), and a power-of-two scale changes no bit; so every pair of finite bodies whose
/// sizes and separation lie within the model's range relative to each other is evaluated,
/// whatever its units, with the same bits as in units near 1. `centres` and `axes` index the
/// row's centre coordinates (c_i then c_j, `dim` each) and semi-axes (body i's then body j's).
fn in_own_units(v: &[f64], dim: usize, centres: [usize; 2], axes: [usize; 2]) -> Vec<f64> {
    let mut out = v.to_vec();
    let semi_axes = || {
        (0..dim)
            .map(move |k| v[axes[0] + k])
            .chain((0..dim).map(move |k| v[axes[1] + k]))
    };
    let largest = semi_axes().fold(0.0_f64, f64::max);
    let usable = semi_axes().all(|a| a.is_finite() && a > 0.0)
        && (0..dim).all(|k| v[centres[0] + k].is_finite() && v[centres[1] + k].is_finite());
    if !usable || !largest.is_normal() {
        // The model names what is wrong with the row as it was given.
        return out;
    }
    // 2^−e with 2^e ≤ largest < 2^(e+1), applied in two steps so that neither overflows.
    let e = ((largest.to_bits() >> 52) & 0x7ff) as i32 - 1023;
    let scale = |x: f64| x * 2f64.powi(-e / 2) * 2f64.powi(-e + e / 2);
    for k in 0..dim {
        let (ci, cj) = (v[centres[0] + k], v[centres[1] + k]);
        out[centres[0] + k] = 0.0;
        out[centres[1] + k] = scale(cj - ci);
        out[axes[0] + k] = scale(v[axes[0] + k]);
        out[axes[1] + k] = scale(v[axes[1] + k]);
    }
    out
}

/// A body of a row that the model refuses: which one (`ellipsoid i`, `ellipse j`, …) and why.
#[derive(Debug, thiserror::Error)]
#[error("{body}: {source}")]
pub struct BodyError {
    /// `ellipsoid i`, `ellipsoid j`, `ellipse i` or `ellipse j`.
    pub body: &'static str,
    /// The model's reason.
    #[source]
    pub source: implicit_packing::Error,
}

/// The pair term of one row of the 3D layout (the values of [`COLUMNS_3D`], in that order),
/// evaluated exactly as `ellipack measure` evaluates it: in the units of the larger body,
/// centred on body i, so the result does not depend on the units of the row.
///
/// # Errors
/// [`BodyError`] naming the body the model refuses (a semi-axis that is not positive and
/// finite, a zero or non-finite quaternion, a non-finite centre).
pub fn pair_term_3d(row: &[f64; 20]) -> Result<PairTerm<3>, BodyError> {
    let v = &in_own_units(row, 3, [0, 10], [3, 13])[..];
    // Body i's ten values come first, body j's next.
    let body = |name, at: usize| {
        let w = &v[at..at + 10];
        Body::from_quaternion(
            [w[0], w[1], w[2]],
            [w[3], w[4], w[5]],
            [w[6], w[7], w[8], w[9]],
        )
        .map_err(|source| BodyError { body: name, source })
    };
    Ok(pair_term(
        &body("ellipsoid i", 0)?,
        &body("ellipsoid j", 10)?,
    ))
}

/// The pair term of one row of the 2D layout (the values of [`COLUMNS_2D`], in that order),
/// as [`pair_term_3d`].
///
/// # Errors
/// [`BodyError`] naming the ellipse the model refuses.
pub fn pair_term_2d(row: &[f64; 10]) -> Result<PairTerm<2>, BodyError> {
    let v = &in_own_units(row, 2, [0, 5], [2, 7])[..];
    let body = |name, at: usize| {
        Body::ellipse([v[at], v[at + 1]], [v[at + 2], v[at + 3]], v[at + 4])
            .map_err(|source| BodyError { body: name, source })
    };
    Ok(pair_term(&body("ellipse i", 0)?, &body("ellipse j", 5)?))
}

/// The row's values as the array of its layout (the reader gives one value per column).
fn row_of<const K: usize>(v: &[f64]) -> Result<&[f64; K], String> {
    v.try_into()
        .map_err(|_| format!("{} values where the layout has {K}", v.len()))
}

fn evaluate_3d(v: &[f64]) -> Result<String, String> {
    let term = pair_term_3d(row_of(v)?).map_err(|e| e.to_string())?;
    Ok(fields(&term))
}

fn evaluate_2d(v: &[f64]) -> Result<String, String> {
    let term = pair_term_2d(row_of(v)?).map_err(|e| e.to_string())?;
    Ok(fields(&term))
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

    /// Every pair of finite bodies is measured in any units: the same pair with positions and
    /// semi-axes scaled by 2^k, k across the double range, gives the same bits (rows beyond
    /// 1e30 or below 1e-30 included).
    #[test]
    fn the_measure_does_not_depend_on_units() {
        let scaled = |row: &[f64], k: i32, lengths: &[usize]| -> String {
            row.iter()
                .enumerate()
                .map(|(n, &x)| {
                    let x = if lengths.contains(&n) {
                        x * 2f64.powi(k / 2) * 2f64.powi(k - k / 2)
                    } else {
                        x
                    };
                    format!("{x:e}")
                })
                .collect::<Vec<_>>()
                .join(",")
        };
        let three = [
            0.3, -0.2, 0.1, 1.0, 0.75, 0.5, 0.5, 0.5, 0.5, 0.5, 1.1, 0.4, -0.3, 0.8, 0.6, 0.45,
            0.6, 0.0, 0.8, 0.0,
        ];
        let two = [0.1, 0.2, 2.0, 1.0, 0.3, 2.5, 1.0, 1.5, 0.7, -1.1];
        let lengths_3d: Vec<usize> = (0..6).chain(10..16).collect();
        let lengths_2d = [0, 1, 2, 3, 5, 6, 7, 8];
        let run = |columns: &[&str], row: String| {
            let header = format!("case_id,{}\n", columns.join(","));
            let (table, failed) = measure(&format!("{header}p,{row}\n"), "t.csv").unwrap();
            assert_eq!(failed, 0, "{table}");
            table.lines().nth(1).unwrap().to_string()
        };
        let base_3d = run(&COLUMNS_3D, scaled(&three, 0, &lengths_3d));
        let base_2d = run(&COLUMNS_2D, scaled(&two, 0, &lengths_2d));
        for k in [-1000, -900, -500, -120, -60, 60, 120, 500, 900, 1000] {
            assert_eq!(
                run(&COLUMNS_3D, scaled(&three, k, &lengths_3d)),
                base_3d,
                "2^{k}"
            );
            assert_eq!(
                run(&COLUMNS_2D, scaled(&two, k, &lengths_2d)),
                base_2d,
                "2D, 2^{k}"
            );
        }
    }
}
