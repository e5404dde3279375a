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
use crate::table::{exact, has_columns, quote, read_numeric_rows};
use implicit_packing::{Body, PairTerm, pair_term};

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
/// As [`crate::table::read_numeric_rows`]: broken CSV structure, a missing column, no rows.
pub fn measure(text: &str, source_name: &str) -> Result<(String, usize), Error> {
    if has_columns(text, &["ciz"]) {
        let rows = read_numeric_rows(text, source_name, &COLUMNS_3D)?;
        Ok(table(rows, "U,d2,eps,f,overlap,X_1,X_2,X_3", |v| {
            let i = Body::from_quaternion(
                [v[0], v[1], v[2]],
                [v[3], v[4], v[5]],
                [v[6], v[7], v[8], v[9]],
            )
            .map_err(|e| format!("ellipsoid i: {e}"))?;
            let j = Body::from_quaternion(
                [v[10], v[11], v[12]],
                [v[13], v[14], v[15]],
                [v[16], v[17], v[18], v[19]],
            )
            .map_err(|e| format!("ellipsoid j: {e}"))?;
            Ok(fields(&pair_term(&i, &j)))
        }))
    } else {
        let rows = read_numeric_rows(text, source_name, &COLUMNS_2D)?;
        Ok(table(rows, "U,d2,eps,f,overlap,X_1,X_2", |v| {
            let i = Body::ellipse([v[0], v[1]], [v[2], v[3]], v[4])
                .map_err(|e| format!("ellipse i: {e}"))?;
            let j = Body::ellipse([v[5], v[6]], [v[7], v[8]], v[9])
                .map_err(|e| format!("ellipse j: {e}"))?;
            Ok(fields(&pair_term(&i, &j)))
        }))
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

fn table(
    rows: Vec<crate::table::NumericRow>,
    columns: &str,
    evaluate: impl Fn(&[f64]) -> Result<String, String>,
) -> (String, usize) {
    let blanks = ",".repeat(columns.matches(',').count());
    let mut out = format!("case_id,{columns},error\n");
    let mut failed = 0;
    for row in rows {
        let id = quote(&row.case_id);
        match row
            .values
            .and_then(|v| evaluate(&v).map_err(|e| format!("line {}: {e}", row.line)))
        {
            Ok(fields) => out.push_str(&format!("{id},{fields},\n")),
            Err(message) => {
                failed += 1;
                out.push_str(&format!("{id},{blanks},{}\n", quote(&message)));
            }
        }
    }
    (out, failed)
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
