//! The independent high-precision reference values of `validation/reference/` (see the README
//! there for what each column is and how it was computed), as typed rows.

use crate::table::{Error, Row, Table};
use std::path::{Path, PathBuf};

/// The folder of the reference files: `$ELLIPACK_REFERENCE_DIR` when set, otherwise the
/// repository's `validation/reference/`.
///
/// The repository is found from the package cargo is testing or running
/// (`CARGO_MANIFEST_DIR` at run time), and only without cargo from this crate's folder as it
/// was at build time: a test binary that cargo reuses from a build in another copy of the
/// repository (CI builds a second clone into the same target folder) then still reads this
/// copy's files, not those of a copy that may be gone.
pub fn dir() -> PathBuf {
    if let Some(d) = std::env::var_os("ELLIPACK_REFERENCE_DIR") {
        return PathBuf::from(d);
    }
    let built = Path::new(env!("CARGO_MANIFEST_DIR"));
    std::env::var_os("CARGO_MANIFEST_DIR")
        .and_then(|running| find_from(Path::new(&running)))
        .or_else(|| find_from(built))
        .unwrap_or_else(|| built.join("../../validation/reference"))
}

/// The first `validation/reference` folder in `start` or above it.
fn find_from(start: &Path) -> Option<PathBuf> {
    start
        .ancestors()
        .map(|a| a.join("validation").join("reference"))
        .find(|d| d.is_dir())
}

/// The path of the reference file `name` (e.g. `"pw85_contact.csv"`).
pub fn path(name: &str) -> PathBuf {
    dir().join(name)
}

/// One row of `pw85_contact.csv`.
#[derive(Debug, Clone)]
pub struct ContactCase {
    /// 1-based line in the file.
    pub line: usize,
    /// `case_id`.
    pub id: String,
    /// `category`.
    pub category: String,
    /// `r12_x, r12_y, r12_z`.
    pub r12: [f64; 3],
    /// `q1_0 .. q1_5`: the first form, upper triangle row by row.
    pub q1: [f64; 6],
    /// `q2_0 .. q2_5`.
    pub q2: [f64; 6],
    /// `lambda_ref`, the maximiser; NaN where `r12 = 0`.
    pub lambda: f64,
    /// `mu2_ref` rounded to the nearest double.
    pub mu2: f64,
    /// `mu2_ref` as written (36 digits).
    pub mu2_digits: String,
}

impl ContactCase {
    /// μ² − 1 from the digits, without rounding μ² first: near tangency μ² rounds to 1 while
    /// μ² − 1 is still known to many digits.
    pub fn mu2_minus_one(&self) -> f64 {
        minus_one(&self.mu2_digits, self.mu2)
    }
}

fn minus_one(digits: &str, rounded: f64) -> f64 {
    if let Some(rest) = digits.strip_prefix("1.")
        && !rest.contains(['e', 'E'])
        && let Ok(frac) = format!("0.{rest}").parse::<f64>()
    {
        return frac;
    }
    if let Some(mantissa) = digits.strip_suffix("e-1")
        && let Some(rest) = mantissa.strip_prefix("9.")
        && rest.bytes().all(|c| c.is_ascii_digit())
    {
        // 9.d₁…dₙe-1 − 1 = −(1 − 0.d₁…dₙ)/10, and 1 − 0.d₁…dₙ = 0.(9−d₁)…(9−dₙ) + 10⁻ⁿ:
        // complementing digit by digit avoids the cancellation of the subtraction.
        let complement: String = rest
            .bytes()
            .map(|c| char::from(b'9' - (c - b'0')))
            .collect();
        if let Ok(v) = format!("0.{complement}").parse::<f64>() {
            let last = 10f64.powi(-(rest.len() as i32));
            return -(v + last) / 10.0;
        }
    }
    rounded - 1.0
}

/// Relative error, with 0 against a reference of 0 counting as exact (and any other value
/// against 0 as its absolute size).
pub fn relative_error(value: f64, reference: f64) -> f64 {
    if reference == 0.0 {
        value.abs()
    } else {
        ((value - reference) / reference).abs()
    }
}

/// The error measure of the implicit-variable values (U, d², which cross zero): relative where
/// the reference is at least 1e-2 in magnitude, and 100 × absolute below, so that one bound
/// of 1e-12 means 1e-12 relative or 1e-14 absolute.
pub fn scaled_error(value: f64, reference: f64) -> f64 {
    let e = (value - reference).abs();
    if reference.abs() < 1e-2 {
        e * 1e2
    } else {
        e / reference.abs()
    }
}

/// Two bodies in the packing paper's parametrisation: centres, semi-axes (along the columns of
/// the rotation) and orientations; `i` is the first (PW85's 1, the implicit model's unit ball).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyPair<const N: usize, O> {
    /// Centre of i.
    pub ci: [f64; N],
    /// Semi-axes of i.
    pub li: [f64; N],
    /// Orientation of i.
    pub oi: O,
    /// Centre of j.
    pub cj: [f64; N],
    /// Semi-axes of j.
    pub lj: [f64; N],
    /// Orientation of j.
    pub oj: O,
}

/// Two ellipsoids, oriented by unit quaternions `(w, x, y, z)`.
pub type EllipsoidPair = BodyPair<3, [f64; 4]>;

/// Two ellipses, oriented by the angles θ of their first semi-axes.
pub type EllipsePair = BodyPair<2, f64>;

/// One row of `blm_3d.csv` or `blm_2d.csv`: a pair of bodies and the implicit-variable measure
/// with body i mapped to the unit ball.
#[derive(Debug, Clone)]
pub struct BlmCase<const N: usize, O> {
    /// 1-based line in the file.
    pub line: usize,
    /// `case_id`.
    pub id: String,
    /// `category`.
    pub category: String,
    /// The pair: `cix…`, `ai…`, `qwi…` or `theta_i`, then the same of j.
    pub pair: BodyPair<N, O>,
    /// `X_1 … X_N`, or `None` where X is not unique (blank cells).
    pub x: Option<[f64; N]>,
    /// `U`.
    pub u: f64,
    /// `d2`.
    pub d2: f64,
    /// `eps`.
    pub eps: f64,
    /// `f`.
    pub f: f64,
    /// `mu2_pw85`: the PW85 contact function of the same pair.
    pub mu2: f64,
}

/// One row of `blm_3d.csv`.
pub type Blm3Case = BlmCase<3, [f64; 4]>;

/// One row of `blm_2d.csv`.
pub type Blm2Case = BlmCase<2, f64>;

fn rows<T>(name: &str, each: impl Fn(&Row<'_>) -> Result<T, Error>) -> Result<Vec<T>, Error> {
    let table = Table::read(path(name))?;
    table.rows().map(|r| each(&r)).collect()
}

fn all_or_none<const K: usize>(r: &Row<'_>, names: [&str; K]) -> Result<Option<[f64; K]>, Error> {
    let mut out = [0.0; K];
    for (o, name) in out.iter_mut().zip(names) {
        match r.opt(name)? {
            Some(v) => *o = v,
            None => return Ok(None),
        }
    }
    Ok(Some(out))
}

/// The rows of `pw85_contact.csv`.
pub fn contact_cases() -> Result<Vec<ContactCase>, Error> {
    rows("pw85_contact.csv", |r| {
        Ok(ContactCase {
            line: r.line(),
            id: r.text("case_id")?.to_string(),
            category: r.text("category")?.to_string(),
            r12: r.nums(["r12_x", "r12_y", "r12_z"])?,
            q1: r.nums(["q1_0", "q1_1", "q1_2", "q1_3", "q1_4", "q1_5"])?,
            q2: r.nums(["q2_0", "q2_1", "q2_2", "q2_3", "q2_4", "q2_5"])?,
            lambda: r.num("lambda_ref")?,
            mu2: r.num("mu2_ref")?,
            mu2_digits: r.text("mu2_ref")?.to_string(),
        })
    })
}

/// The rows of `blm_3d.csv`.
pub fn blm_3d() -> Result<Vec<Blm3Case>, Error> {
    rows("blm_3d.csv", |r| {
        let pair = EllipsoidPair {
            ci: r.nums(["cix", "ciy", "ciz"])?,
            li: r.nums(["ai", "bi", "ci_ax"])?,
            oi: r.nums(["qwi", "qxi", "qyi", "qzi"])?,
            cj: r.nums(["cjx", "cjy", "cjz"])?,
            lj: r.nums(["aj", "bj", "cj_ax"])?,
            oj: r.nums(["qwj", "qxj", "qyj", "qzj"])?,
        };
        blm_case(r, pair, ["X_1", "X_2", "X_3"])
    })
}

/// The rows of `blm_2d.csv`.
pub fn blm_2d() -> Result<Vec<Blm2Case>, Error> {
    rows("blm_2d.csv", |r| {
        let pair = EllipsePair {
            ci: r.nums(["cix", "ciy"])?,
            li: r.nums(["ai", "bi"])?,
            oi: r.num("theta_i")?,
            cj: r.nums(["cjx", "cjy"])?,
            lj: r.nums(["aj", "bj"])?,
            oj: r.num("theta_j")?,
        };
        blm_case(r, pair, ["X_1", "X_2"])
    })
}

/// A row of a `blm_*.csv` file with its pair read.
fn blm_case<const N: usize, O>(
    r: &Row<'_>,
    pair: BodyPair<N, O>,
    x: [&str; N],
) -> Result<BlmCase<N, O>, Error> {
    Ok(BlmCase {
        line: r.line(),
        id: r.text("case_id")?.to_string(),
        category: r.text("category")?.to_string(),
        pair,
        x: all_or_none(r, x)?,
        u: r.num("U")?,
        d2: r.num("d2")?,
        eps: r.num("eps")?,
        f: r.num("f")?,
        mu2: r.num("mu2_pw85")?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minus_one_keeps_digits_beyond_double_precision() {
        assert_eq!(minus_one("1.00000000000000000123", 1.0), 1.23e-18);
        let v = minus_one("9.99999999999999999e-1", 1.0);
        assert!((v + 1e-18).abs() < 1e-30, "{v}");
        assert_eq!(minus_one("2.5", 2.5), 1.5);
    }

    #[test]
    fn the_folder_is_found_from_any_package_of_the_repository() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let here = root.join("validation/reference").canonicalize().unwrap();
        for package in ["crates/testkit", "crates/pw85", "xtask", "."] {
            let found = find_from(&root.join(package)).unwrap();
            assert_eq!(found.canonicalize().unwrap(), here, "{package}");
        }
        // Another copy of the repository is read from its own folder.
        let other = std::env::temp_dir().join(format!("testkit-copy-{}", std::process::id()));
        std::fs::create_dir_all(other.join("validation/reference")).unwrap();
        std::fs::create_dir_all(other.join("crates/pw85")).unwrap();
        let found = find_from(&other.join("crates/pw85"));
        std::fs::remove_dir_all(&other).unwrap();
        assert_eq!(found, Some(other.join("validation").join("reference")));
    }

    #[test]
    fn error_measures() {
        assert_eq!(relative_error(3.0, 2.0), 0.5);
        assert_eq!(relative_error(-1e-3, 0.0), 1e-3);
        assert_eq!(scaled_error(1.5, 1.0), 0.5);
        assert_eq!(scaled_error(2e-3, 1e-3), 1e-3 * 1e2);
    }

    #[test]
    fn the_three_files_load_from_the_repository() {
        let contact = contact_cases().unwrap();
        assert_eq!(contact.len(), 305);
        assert!(contact.iter().any(|c| c.lambda.is_nan()));
        let b3 = blm_3d().unwrap();
        assert_eq!(b3.len(), 257);
        assert!(b3.iter().any(|c| c.x.is_none()) && b3.iter().any(|c| c.x.is_some()));
        assert_eq!(blm_2d().unwrap().len(), 104);
        // The first case's line, for errors that point into the file.
        assert_eq!(contact[0].line, 2);
    }
}
