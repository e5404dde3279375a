//! Shared test helpers: bodies from the rows of the reference files
//! (`validation/reference/blm_*.csv`, read by `testkit::reference`).
#![allow(dead_code)]

use implicit_packing::{Body, Ellipse, Ellipsoid};
use testkit::reference::{Blm2Case, Blm3Case};

pub fn bodies_3d(r: &Blm3Case) -> (Ellipsoid, Ellipsoid) {
    let i = Body::from_quaternion(r.ci, r.li, r.qi)
        .unwrap_or_else(|e| panic!("case {} (line {}): body i: {e}", r.id, r.line));
    let j = Body::from_quaternion(r.cj, r.lj, r.qj)
        .unwrap_or_else(|e| panic!("case {} (line {}): body j: {e}", r.id, r.line));
    (i, j)
}

pub fn bodies_2d(r: &Blm2Case) -> (Ellipse, Ellipse) {
    let i = Body::ellipse(r.ci, r.li, r.theta_i)
        .unwrap_or_else(|e| panic!("case {} (line {}): body i: {e}", r.id, r.line));
    let j = Body::ellipse(r.cj, r.lj, r.theta_j)
        .unwrap_or_else(|e| panic!("case {} (line {}): body j: {e}", r.id, r.line));
    (i, j)
}

/// Relative error, or absolute error where the reference is below 1e-2 in magnitude (the
/// tolerance convention of the issue: relative 1e-12, absolute 1e-14 below 1e-2).
pub fn scaled_err(x: f64, reference: f64) -> f64 {
    let e = (x - reference).abs();
    if reference.abs() < 1e-2 {
        e * 1e2
    } else {
        e / reference.abs()
    }
}
