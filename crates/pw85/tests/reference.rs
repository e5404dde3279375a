//! μ² against the independent 36-digit reference values of `validation/reference/pw85_contact.csv`
//! (305 cases in 12 categories; see that folder's README).

use std::collections::BTreeMap;
use testkit::reference::{self, ContactCase, relative_error};

fn cases() -> Vec<ContactCase> {
    reference::contact_cases().unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn mu2_within_1e_13_in_every_category() {
    let cases = cases();
    assert_eq!(cases.len(), 305);
    let mut by_category: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    let mut lambda_errors: BTreeMap<&str, f64> = BTreeMap::new();
    let mut worst = (0.0, String::new());
    for c in &cases {
        let contact = pw85::contact_function(&c.r12, &c.q1, &c.q2)
            .unwrap_or_else(|e| panic!("case {}: {e}", c.id));
        let err = relative_error(contact.mu2, c.mu2);
        if err > worst.0 {
            worst = (err, c.id.clone());
        }
        by_category.entry(&c.category).or_default().push(err);
        assert!(
            (0.0..=1.0).contains(&contact.lambda),
            "case {}: λ = {}",
            c.id,
            contact.lambda
        );
        if c.lambda.is_finite() && c.mu2 > 0.0 {
            // Absolute: near λ = 1 a double cannot hold λ₀ to better than 1e-16 absolute,
            // however precisely 1 − λ₀ is known inside the solver.
            let e = (contact.lambda - c.lambda).abs();
            let worst = lambda_errors.entry(&c.category).or_insert(0.0);
            *worst = worst.max(e);
            // λ₀ is a maximiser of a function that is flat there, so it is less sharp than μ²
            // (its rounding noise enters through f′): 1e-12 absolute holds on every case.
            assert!(
                e <= 1e-12,
                "case {} ({}): λ = {} vs {}",
                c.id,
                c.category,
                contact.lambda,
                c.lambda
            );
        }
    }
    println!(
        "{:<22} {:>5} {:>12} {:>12} {:>10}",
        "category", "cases", "max rel err", "median", "max |Δλ|"
    );
    for (category, errs) in &mut by_category {
        errs.sort_by(f64::total_cmp);
        println!(
            "{:<22} {:>5} {:>12.3e} {:>12.3e} {:>14.3e}",
            category,
            errs.len(),
            errs[errs.len() - 1],
            errs[errs.len() / 2],
            lambda_errors.get(category).copied().unwrap_or(0.0)
        );
    }
    println!("worst case: {} ({:.3e})", worst.1, worst.0);
    for (category, errs) in &by_category {
        let max = errs[errs.len() - 1];
        assert!(
            max <= 1e-13,
            "{category}: max relative error {max:e} > 1e-13"
        );
    }
}

#[test]
fn verdict_matches_reference_outside_2e_13_of_tangency() {
    for c in cases() {
        if (c.mu2 - 1.0).abs() <= 2e-13 {
            continue;
        }
        let verdict = pw85::overlap(&c.r12, &c.q1, &c.q2).unwrap();
        assert_eq!(
            verdict,
            c.mu2 < 1.0,
            "case {} ({}): μ²_ref = {}",
            c.id,
            c.category,
            c.mu2
        );
    }
}

/// x · 2^e for any e (two steps where 2^e alone is not a double).
fn times_power_of_two(x: f64, e: i32) -> f64 {
    let half = e / 2;
    x * 2f64.powi(half) * 2f64.powi(e - half)
}

/// Extreme-scale categories built from every reference case: the same geometry in units 2^k
/// (r12 · 2^k, Q · 2^2k), r12 alone scaled by 2^k (μ² · 2^2k) and both Q alone by 2^k (μ² · 2^−k),
/// for k out to the edges of the double range. Power-of-two scalings keep every input bit
/// (cases whose inputs would round into the subnormal range are left out), so the reference
/// value scales exactly, and the same 1e-13 applies; a reference μ² scaled beyond the double
/// range must come back as +∞ (apart) or below the smallest normal double (overlap).
#[test]
fn mu2_within_1e_13_at_extreme_scales() {
    let exact = |xs: &[f64], e: i32| {
        xs.iter()
            .all(|&x| times_power_of_two(times_power_of_two(x, e), -e) == x)
    };
    let mut checked: BTreeMap<String, (usize, f64)> = BTreeMap::new();
    // (name, exponent of r12, exponent of both Q); μ² scales by 2^(2 kr − kq).
    let scalings: Vec<(String, i32, i32)> = [-480, -300, 300, 480]
        .into_iter()
        .flat_map(|k: i32| {
            [
                (format!("units 2^{k}"), k, 2 * k),
                (format!("r12 · 2^{k}"), k, 0),
                (format!("r12 · 2^{}", 2 * k), 2 * k, 0),
                (format!("Q · 2^{}", 2 * k), 0, 2 * k),
            ]
        })
        .collect();
    for c in cases() {
        for (category, kr, kq) in &scalings {
            let (kr, kq) = (*kr, *kq);
            if !(exact(&c.r12, kr) && exact(&c.q1, kq) && exact(&c.q2, kq)) {
                continue;
            }
            let r12 = c.r12.map(|x| times_power_of_two(x, kr));
            let q1 = c.q1.map(|x| times_power_of_two(x, kq));
            let q2 = c.q2.map(|x| times_power_of_two(x, kq));
            let shift = 2 * kr - kq;
            let contact = pw85::contact_function(&r12, &q1, &q2)
                .unwrap_or_else(|e| panic!("case {} at {category}: {e}", c.id));
            let verdict = pw85::overlap(&r12, &q1, &q2)
                .unwrap_or_else(|e| panic!("case {} at {category}: overlap: {e}", c.id));
            let reference = times_power_of_two(c.mu2, shift);
            let err = if reference == f64::INFINITY {
                assert_eq!(contact.mu2, f64::INFINITY, "case {} at {category}", c.id);
                assert!(
                    !verdict,
                    "case {} at {category}: an infinite μ² is apart",
                    c.id
                );
                0.0
            } else if reference < f64::MIN_POSITIVE {
                assert!(
                    contact.mu2 < 2.0 * f64::MIN_POSITIVE,
                    "case {} at {category}",
                    c.id
                );
                assert!(verdict || c.mu2 == 0.0, "case {} at {category}", c.id);
                0.0
            } else {
                if (reference - 1.0).abs() > 2e-13 {
                    assert_eq!(verdict, reference < 1.0, "case {} at {category}", c.id);
                }
                relative_error(contact.mu2, reference)
            };
            let key = category.split(' ').next().unwrap_or("").to_string()
                + if category.contains('-') {
                    " (small)"
                } else {
                    " (large)"
                };
            let entry = checked.entry(key).or_insert((0, 0.0));
            entry.0 += 1;
            entry.1 = entry.1.max(err);
            assert!(
                err <= 1e-13,
                "case {} ({}) at {category}: relative error {err:e}",
                c.id,
                c.category
            );
        }
    }
    for (category, (count, worst)) in &checked {
        println!("{category:<16} {count:>5} cases, max relative error {worst:.3e}");
        assert!(
            *count > 500,
            "{category}: only {count} cases kept their bits"
        );
    }
    assert_eq!(checked.len(), 6);
}
