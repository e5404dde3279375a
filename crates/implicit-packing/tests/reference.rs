//! The pair term against the independent 100-digit reference values
//! (`validation/reference/blm_3d.csv`, `blm_2d.csv`).
#![allow(clippy::needless_range_loop)]

use implicit_packing::{Body, Ellipse, Ellipsoid, Route, pair_term_by};
use std::collections::BTreeMap;
use testkit::reference::{self, Blm2Case, Blm3Case, scaled_error};

fn bodies_3d(r: &Blm3Case) -> (Ellipsoid, Ellipsoid) {
    let body = |c, l, q, which| named(Body::from_quaternion(c, l, q), &r.id, r.line, which);
    (
        body(r.pair.ci, r.pair.li, r.pair.oi, "i"),
        body(r.pair.cj, r.pair.lj, r.pair.oj, "j"),
    )
}

fn bodies_2d(r: &Blm2Case) -> (Ellipse, Ellipse) {
    let body = |c, l, t, which| named(Body::ellipse(c, l, t), &r.id, r.line, which);
    (
        body(r.pair.ci, r.pair.li, r.pair.oi, "i"),
        body(r.pair.cj, r.pair.lj, r.pair.oj, "j"),
    )
}

/// The body, or a panic naming the case, its line and which body of the pair failed.
#[track_caller]
fn named<B, E: std::fmt::Display>(body: Result<B, E>, id: &str, line: usize, which: &str) -> B {
    body.unwrap_or_else(|e| panic!("case {id} (line {line}): body {which}: {e}"))
}

#[derive(Default, Debug)]
struct Worst {
    n: usize,
    u: f64,
    d2: f64,
    x: f64,
    eps: f64,
    wrong_sign: usize,
}

fn table(name: &str, rows: &BTreeMap<String, Worst>) {
    println!(
        "{name}: category | cases | max err U | max err d2 | max rel err X | max rel err eps | wrong verdicts"
    );
    for (cat, w) in rows {
        println!(
            "{name}: {cat:24} | {:3} | {:9.2e} | {:9.2e} | {:9.2e} | {:9.2e} | {}",
            w.n, w.u, w.d2, w.x, w.eps, w.wrong_sign
        );
    }
}

/// The reference values of one case, the same for both files.
struct Expected<'a, const N: usize> {
    id: &'a str,
    category: &'a str,
    u: f64,
    d2: f64,
    eps: f64,
    f: f64,
    mu2: f64,
    x: Option<[f64; N]>,
}

/// The same fields of both files' rows.
macro_rules! expected_from {
    ($case:ty, $n:literal) => {
        impl<'a> From<&'a $case> for Expected<'a, $n> {
            fn from(c: &'a $case) -> Self {
                Expected {
                    id: &c.id,
                    category: &c.category,
                    u: c.u,
                    d2: c.d2,
                    eps: c.eps,
                    f: c.f,
                    mu2: c.mu2,
                    x: c.x,
                }
            }
        }
    };
}

expected_from!(Blm3Case, 3);
expected_from!(Blm2Case, 2);

fn check<const N: usize>(name: &str, rows: Vec<(Expected<'_, N>, implicit_packing::PairTerm<N>)>) {
    let mut worst: BTreeMap<String, Worst> = BTreeMap::new();
    let mut failures = Vec::new();
    for (r, p) in &rows {
        let cat = r.category.to_string();
        let w = worst.entry(cat.clone()).or_default();
        w.n += 1;
        let eu = scaled_error(p.u, r.u);
        let ed = scaled_error(p.d2, r.d2);
        let eps_ref = r.eps;
        let ee = (p.eps - eps_ref).abs() / eps_ref;
        w.u = w.u.max(eu);
        w.d2 = w.d2.max(ed);
        w.eps = w.eps.max(ee);
        let f_ref = r.f;
        let mu2 = r.mu2;
        // The verdict of the reference, confirmed by PW85 (they agree on every case).
        let overlap_ref = f_ref > 0.0 || mu2 < 1.0;
        if (p.f > 0.0) != overlap_ref {
            w.wrong_sign += 1;
            failures.push(format!(
                "{name} case {}: f = {:e}, reference f = {:e}, d2 = {:e}",
                r.id, p.f, f_ref, p.d2
            ));
        }
        if eu > 1e-12 || ed > 1e-12 {
            failures.push(format!(
                "{name} case {} ({cat}): err U {eu:.2e}, err d2 {ed:.2e}",
                r.id
            ));
        }
        if ee > 1e-15 {
            failures.push(format!("{name} case {}: eps rel err {ee:.2e}", r.id));
        }
        if cat != "near_hard"
            && let Some(xref) = r.x
        {
            let mut num = 0.0;
            let mut den = 0.0;
            for k in 0..N {
                num += (p.x[k] - xref[k]) * (p.x[k] - xref[k]);
                den += xref[k] * xref[k];
            }
            let ex = (num / den).sqrt();
            w.x = w.x.max(ex);
            if ex > 1e-12 {
                failures.push(format!("{name} case {} ({cat}): rel err X {ex:.2e}", r.id));
            }
        }
    }
    table(name, &worst);
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Every case of a file, its bodies built by `bodies`, through both routes of the pair term
/// (automatic and SVD).
fn check_both_routes<'a, const N: usize, C>(
    name: &str,
    cases: &'a [C],
    bodies: impl Fn(&C) -> (Body<N>, Body<N>),
) where
    &'a C: Into<Expected<'a, N>>,
{
    for (suffix, route) in [("", Route::Auto), ("-svd", Route::Svd)] {
        let rows = cases
            .iter()
            .map(|c| {
                let (i, j) = bodies(c);
                (c.into(), pair_term_by(&i, &j, route))
            })
            .collect();
        check::<N>(&format!("{name}{suffix}"), rows);
    }
}

#[test]
fn blm_3d_reference() {
    let cases = reference::blm_3d().unwrap_or_else(|e| panic!("{e}"));
    check_both_routes("3d", &cases, bodies_3d);
}

#[test]
fn blm_2d_reference() {
    let cases = reference::blm_2d().unwrap_or_else(|e| panic!("{e}"));
    check_both_routes("2d", &cases, bodies_2d);
}
