//! The independent high-precision reference values of `validation/reference/` (or
//! `$ELLIPACK_REFERENCE_DIR`), read by the test kit's loader: each row of the kit, with its
//! inputs also in the harness's pair types.

use crate::error::Error;
use crate::sample::{Pair2, Pair3, Pw85Pair};
use std::ops::Deref;
use std::path::PathBuf;
use testkit::reference;
pub use testkit::reference::{relative_error, scaled_error};

/// The path of the reference file `name`.
pub fn path(name: &str) -> PathBuf {
    reference::path(name)
}

/// A row of the kit (its fields through `Deref`) with its inputs as one of the harness's pairs.
#[derive(Debug, Clone)]
pub struct Case<R, P> {
    /// The inputs in the harness's pair type.
    pub pair: P,
    row: R,
}

impl<R, P> Deref for Case<R, P> {
    type Target = R;
    fn deref(&self) -> &R {
        &self.row
    }
}

/// One row of `pw85_contact.csv`.
pub type ContactCase = Case<reference::ContactCase, Pw85Pair>;
/// One row of `blm_3d.csv`.
pub type BlmCase3 = Case<reference::Blm3Case, Pair3>;
/// One row of `blm_2d.csv`.
pub type BlmCase2 = Case<reference::Blm2Case, Pair2>;

/// Each of the kit's `rows` with its inputs as the harness's pair, made by `pair`: the
/// reference files differ only in their row and pair types.
fn cases<R, P>(rows: Vec<R>, pair: impl Fn(&R) -> P) -> Vec<Case<R, P>> {
    rows.into_iter()
        .map(|row| Case {
            pair: pair(&row),
            row,
        })
        .collect()
}

/// `pw85_contact.csv`.
pub fn contact_cases() -> Result<Vec<ContactCase>, Error> {
    Ok(cases(reference::contact_cases()?, |row| Pw85Pair {
        r12: row.r12,
        q1: row.q1,
        q2: row.q2,
    }))
}

/// `blm_3d.csv`.
pub fn blm_3d() -> Result<Vec<BlmCase3>, Error> {
    Ok(cases(reference::blm_3d()?, |row| row.pair))
}

/// `blm_2d.csv`.
pub fn blm_2d() -> Result<Vec<BlmCase2>, Error> {
    Ok(cases(reference::blm_2d()?, |row| row.pair))
}
