//! Readers for the shared reference files (`../shared/reference/blm_*.csv`).
#![allow(dead_code)]

use implicit_packing::{Body, Ellipse, Ellipsoid};
use std::collections::HashMap;
use std::path::PathBuf;

pub fn reference_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/reference")
}

/// One row of a reference file as (column name → text).
pub struct Row {
    pub fields: HashMap<String, String>,
}

impl Row {
    pub fn num(&self, key: &str) -> f64 {
        let t = self
            .fields
            .get(key)
            .unwrap_or_else(|| panic!("no column {key}"));
        t.trim()
            .parse::<f64>()
            .unwrap_or_else(|_| panic!("column {key}: {t:?}"))
    }
    pub fn opt(&self, key: &str) -> Option<f64> {
        let t = self.fields.get(key)?.trim();
        if t.is_empty() {
            None
        } else {
            t.parse::<f64>().ok()
        }
    }
    pub fn text(&self, key: &str) -> &str {
        self.fields.get(key).map(|s| s.as_str()).unwrap_or("")
    }
}

pub fn read_csv(name: &str) -> Vec<Row> {
    let path = reference_dir().join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .expect("header")
        .split(',')
        .map(|s| s.to_string())
        .collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let fields = header
                .iter()
                .cloned()
                .zip(l.split(',').map(|s| s.to_string()))
                .collect();
            Row { fields }
        })
        .collect()
}

pub fn bodies_3d(r: &Row) -> (Ellipsoid, Ellipsoid) {
    let i = Body::from_quaternion(
        [r.num("cix"), r.num("ciy"), r.num("ciz")],
        [r.num("ai"), r.num("bi"), r.num("ci_ax")],
        [r.num("qwi"), r.num("qxi"), r.num("qyi"), r.num("qzi")],
    )
    .expect("valid i");
    let j = Body::from_quaternion(
        [r.num("cjx"), r.num("cjy"), r.num("cjz")],
        [r.num("aj"), r.num("bj"), r.num("cj_ax")],
        [r.num("qwj"), r.num("qxj"), r.num("qyj"), r.num("qzj")],
    )
    .expect("valid j");
    (i, j)
}

pub fn bodies_2d(r: &Row) -> (Ellipse, Ellipse) {
    let i = Body::ellipse(
        [r.num("cix"), r.num("ciy")],
        [r.num("ai"), r.num("bi")],
        r.num("theta_i"),
    )
    .expect("valid i");
    let j = Body::ellipse(
        [r.num("cjx"), r.num("cjy")],
        [r.num("aj"), r.num("bj")],
        r.num("theta_j"),
    )
    .expect("valid j");
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

/// A small deterministic generator (SplitMix64) so that the tests need no extra crate.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
    /// A uniformly distributed unit vector.
    pub fn unit3(&mut self) -> [f64; 3] {
        loop {
            let v = [
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            ];
            let n2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
            if n2 > 1e-4 && n2 <= 1.0 {
                let n = n2.sqrt();
                return [v[0] / n, v[1] / n, v[2] / n];
            }
        }
    }
}
