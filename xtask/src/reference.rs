//! The independent high-precision reference values of `validation/reference/` (or
//! `$ELLIPACK_REFERENCE_DIR`), read by the test kit's loader and handed out in the harness's
//! pair types: `pw85_contact.csv` and `blm_3d.csv`, `blm_2d.csv`.

use crate::error::Error;
use crate::sample::{Pair2, Pair3, Pw85Pair};
use std::path::PathBuf;
use testkit::reference;

/// The path of the reference file `name`.
pub fn path(name: &str) -> PathBuf {
    reference::path(name)
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

/// `pw85_contact.csv`.
pub fn contact_cases() -> Result<Vec<ContactCase>, Error> {
    Ok(reference::contact_cases()?
        .into_iter()
        .map(|c| ContactCase {
            mu2_minus_one: c.mu2_minus_one(),
            pair: Pw85Pair {
                r12: c.r12,
                q1: c.q1,
                q2: c.q2,
            },
            lambda: c.lambda,
            mu2: c.mu2,
            id: c.id,
            category: c.category,
        })
        .collect())
}

/// `blm_3d.csv`.
pub fn blm_3d() -> Result<Vec<BlmCase3>, Error> {
    Ok(reference::blm_3d()?
        .into_iter()
        .map(|c| BlmCase3 {
            pair: Pair3 {
                ci: c.ci,
                li: c.li,
                qi: c.qi,
                cj: c.cj,
                lj: c.lj,
                qj: c.qj,
            },
            x: c.x,
            u: c.u,
            d2: c.d2,
            eps: c.eps,
            f: c.f,
            mu2: c.mu2,
            id: c.id,
            category: c.category,
        })
        .collect())
}

/// `blm_2d.csv`.
pub fn blm_2d() -> Result<Vec<BlmCase2>, Error> {
    Ok(reference::blm_2d()?
        .into_iter()
        .map(|c| BlmCase2 {
            pair: Pair2 {
                ci: c.ci,
                li: c.li,
                ti: c.theta_i,
                cj: c.cj,
                lj: c.lj,
                tj: c.theta_j,
            },
            x: c.x,
            u: c.u,
            d2: c.d2,
            eps: c.eps,
            f: c.f,
            mu2: c.mu2,
            id: c.id,
            category: c.category,
        })
        .collect())
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
