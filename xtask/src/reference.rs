//! Readers for the independent high-precision reference values in `../shared/reference/`
//! (or `$ELLIPACK_REFERENCE_DIR`): `pw85_contact.csv` and `blm_3d.csv`, `blm_2d.csv`.

use crate::error::Error;
use crate::sample::{Pair2, Pair3, Pw85Pair};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Where the reference files are.
pub fn dir(root: &Path) -> PathBuf {
    match std::env::var_os("ELLIPACK_REFERENCE_DIR") {
        Some(d) => PathBuf::from(d),
        None => root.join("../shared/reference"),
    }
}

/// The reference μ², kept both as the nearest double and as the digit string (the 36 digits
/// matter when μ² is within 1e-15 of 1).
#[derive(Debug, Clone)]
pub struct ContactCase {
    /// `case_id`.
    pub id: String,
    /// `category`.
    pub category: String,
    /// The inputs (exact doubles).
    pub pair: Pw85Pair,
    /// λ₀ (NaN where r12 = 0).
    pub lambda: f64,
    /// μ², rounded to the nearest double.
    pub mu2: f64,
    /// μ² − 1 computed from the digit string (exact to the double's precision, even where
    /// μ² rounds to 1).
    pub mu2_minus_one: f64,
}

/// One row of `blm_3d.csv`.
#[derive(Debug, Clone)]
pub struct BlmCase3 {
    /// `case_id`.
    pub id: String,
    /// `category`.
    pub category: String,
    /// The pair.
    pub pair: Pair3,
    /// X, or `None` where it is not unique.
    pub x: Option<[f64; 3]>,
    /// U.
    pub u: f64,
    /// d².
    pub d2: f64,
    /// ε.
    pub eps: f64,
    /// f.
    pub f: f64,
    /// PW85 μ² of the same pair.
    pub mu2: f64,
}

/// One row of `blm_2d.csv`.
#[derive(Debug, Clone)]
pub struct BlmCase2 {
    /// `case_id`.
    pub id: String,
    /// `category`.
    pub category: String,
    /// The pair.
    pub pair: Pair2,
    /// X, or `None`.
    pub x: Option<[f64; 2]>,
    /// U.
    pub u: f64,
    /// d².
    pub d2: f64,
    /// ε.
    pub eps: f64,
    /// f.
    pub f: f64,
    /// PW85 μ².
    pub mu2: f64,
}

/// A CSV row with access by column name and errors naming file and line.
struct Row<'a> {
    path: &'a Path,
    line: u64,
    header: &'a HashMap<String, usize>,
    record: csv::StringRecord,
}

impl Row<'_> {
    fn error(&self, message: String) -> Error {
        Error::Reference {
            path: self.path.to_path_buf(),
            line: self.line,
            message,
        }
    }

    fn text(&self, key: &str) -> Result<&str, Error> {
        self.header
            .get(key)
            .and_then(|&k| self.record.get(k))
            .map(str::trim)
            .ok_or_else(|| self.error(format!("no column `{key}`")))
    }

    fn num(&self, key: &str) -> Result<f64, Error> {
        let t = self.text(key)?;
        t.parse::<f64>()
            .map_err(|_| self.error(format!("column `{key}`: `{t}` is not a number")))
    }

    fn opt(&self, key: &str) -> Result<Option<f64>, Error> {
        if self.text(key)?.is_empty() {
            Ok(None)
        } else {
            self.num(key).map(Some)
        }
    }

    fn nums<const K: usize>(&self, keys: [&str; K]) -> Result<[f64; K], Error> {
        let mut out = [0.0; K];
        for (o, k) in out.iter_mut().zip(keys) {
            *o = self.num(k)?;
        }
        Ok(out)
    }
}

fn read_rows<T>(
    path: &Path,
    mut each: impl FnMut(&Row<'_>) -> Result<T, Error>,
) -> Result<Vec<T>, Error> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| Error::Reference {
        path: path.to_path_buf(),
        line: 0,
        message: e.to_string(),
    })?;
    let header: HashMap<String, usize> = reader
        .headers()
        .map_err(|e| Error::Reference {
            path: path.to_path_buf(),
            line: 1,
            message: e.to_string(),
        })?
        .iter()
        .enumerate()
        .map(|(k, h)| (h.trim().to_string(), k))
        .collect();
    let mut out = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| Error::Reference {
            path: path.to_path_buf(),
            line: e.position().map_or(0, |p| p.line()),
            message: e.to_string(),
        })?;
        let line = record.position().map_or(0, |p| p.line());
        out.push(each(&Row {
            path,
            line,
            header: &header,
            record,
        })?);
    }
    Ok(out)
}

/// μ² − 1 from a decimal string, without rounding μ² first: the digits after the leading
/// "1." (or "9.99…e-1") are read as a small number.
fn minus_one(digits: &str, rounded: f64) -> f64 {
    let d = digits.trim();
    if let Some(rest) = d.strip_prefix("1.")
        && !rest.contains(['e', 'E'])
    {
        let frac: f64 = format!("0.{rest}").parse().unwrap_or(rounded - 1.0);
        return frac;
    }
    if let Some(mant) = d.strip_suffix("e-1")
        && let Some(rest) = mant.strip_prefix("9.")
    {
        // 9.abc…e-1 − 1 = −(1 − 0.abc…)/10, and 1 − 0.d₁…dₙ = 0.(9−d₁)…(9−dₙ) + 10⁻ⁿ: the
        // complement digit by digit avoids the cancellation of the subtraction.
        let digits: Vec<u8> = rest.bytes().filter(u8::is_ascii_digit).collect();
        let comp: String = digits
            .iter()
            .map(|&c| char::from(b'9' - (c - b'0')))
            .collect();
        if let Ok(v) = format!("0.{comp}").parse::<f64>() {
            let last = 10f64.powi(-(digits.len() as i32));
            return -(v + last) / 10.0;
        }
    }
    rounded - 1.0
}

/// `pw85_contact.csv`.
pub fn contact_cases(root: &Path) -> Result<Vec<ContactCase>, Error> {
    let path = dir(root).join("pw85_contact.csv");
    read_rows(&path, |r| {
        let mu2 = r.num("mu2_ref")?;
        let lambda = r.text("lambda_ref")?;
        Ok(ContactCase {
            id: r.text("case_id")?.to_string(),
            category: r.text("category")?.to_string(),
            pair: Pw85Pair {
                r12: r.nums(["r12_x", "r12_y", "r12_z"])?,
                q1: r.nums(["q1_0", "q1_1", "q1_2", "q1_3", "q1_4", "q1_5"])?,
                q2: r.nums(["q2_0", "q2_1", "q2_2", "q2_3", "q2_4", "q2_5"])?,
            },
            lambda: if lambda.eq_ignore_ascii_case("nan") {
                f64::NAN
            } else {
                r.num("lambda_ref")?
            },
            mu2,
            mu2_minus_one: minus_one(r.text("mu2_ref")?, mu2),
        })
    })
}

/// `blm_3d.csv`.
pub fn blm_3d(root: &Path) -> Result<Vec<BlmCase3>, Error> {
    let path = dir(root).join("blm_3d.csv");
    read_rows(&path, |r| {
        let x = match (r.opt("X_1")?, r.opt("X_2")?, r.opt("X_3")?) {
            (Some(a), Some(b), Some(c)) => Some([a, b, c]),
            _ => None,
        };
        Ok(BlmCase3 {
            id: r.text("case_id")?.to_string(),
            category: r.text("category")?.to_string(),
            pair: Pair3 {
                ci: r.nums(["cix", "ciy", "ciz"])?,
                li: r.nums(["ai", "bi", "ci_ax"])?,
                qi: r.nums(["qwi", "qxi", "qyi", "qzi"])?,
                cj: r.nums(["cjx", "cjy", "cjz"])?,
                lj: r.nums(["aj", "bj", "cj_ax"])?,
                qj: r.nums(["qwj", "qxj", "qyj", "qzj"])?,
            },
            x,
            u: r.num("U")?,
            d2: r.num("d2")?,
            eps: r.num("eps")?,
            f: r.num("f")?,
            mu2: r.num("mu2_pw85")?,
        })
    })
}

/// `blm_2d.csv`.
pub fn blm_2d(root: &Path) -> Result<Vec<BlmCase2>, Error> {
    let path = dir(root).join("blm_2d.csv");
    read_rows(&path, |r| {
        let x = match (r.opt("X_1")?, r.opt("X_2")?) {
            (Some(a), Some(b)) => Some([a, b]),
            _ => None,
        };
        Ok(BlmCase2 {
            id: r.text("case_id")?.to_string(),
            category: r.text("category")?.to_string(),
            pair: Pair2 {
                ci: r.nums(["cix", "ciy"])?,
                li: r.nums(["ai", "bi"])?,
                ti: r.num("theta_i")?,
                cj: r.nums(["cjx", "cjy"])?,
                lj: r.nums(["aj", "bj"])?,
                tj: r.num("theta_j")?,
            },
            x,
            u: r.num("U")?,
            d2: r.num("d2")?,
            eps: r.num("eps")?,
            f: r.num("f")?,
            mu2: r.num("mu2_pw85")?,
        })
    })
}

/// The error measure of the implicit-variable reference tests: relative where the reference is
/// at least 1e-2, absolute × 100 below (U and d² cross zero).
pub fn scaled_error(x: f64, reference: f64) -> f64 {
    let e = (x - reference).abs();
    if reference.abs() < 1e-2 {
        e * 1e2
    } else {
        e / reference.abs()
    }
}

/// Relative error, with 0 against 0 counting as exact.
pub fn relative_error(x: f64, reference: f64) -> f64 {
    if reference == 0.0 {
        x.abs()
    } else {
        ((x - reference) / reference).abs()
    }
}

#[cfg(test)]
mod tests {
    use super::minus_one;

    #[test]
    fn minus_one_keeps_digits_beyond_double_precision() {
        assert_eq!(minus_one("1.00000000000000000123", 1.0), 1.23e-18);
        let v = minus_one("9.99999999999999999e-1", 1.0);
        assert!((v + 1e-18).abs() < 1e-30, "{v}");
        assert_eq!(minus_one("2.5", 2.5), 1.5);
    }
}
