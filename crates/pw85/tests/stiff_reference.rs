//! `objective` and `contact_details` on stiff pairs (needles, pancakes, size ratios up to 1e8,
//! upstream PW85's needle grid) against the 36-digit reference values of
//! `validation/reference/pw85_objective.csv` and `pw85_details.csv` (see that folder's README).

use std::collections::BTreeMap;
use testkit::reference::{path, relative_error};
use testkit::table::{Row, Table};

fn table(name: &str) -> Table {
    Table::read(path(name)).unwrap_or_else(|e| panic!("{e}"))
}

/// r12, Q1, Q2 of a row.
fn inputs(r: &Row<'_>) -> ([f64; 3], [f64; 6], [f64; 6]) {
    let num = |names| r.nums(names).unwrap_or_else(|e| panic!("{e}"));
    (
        num(["r12_x", "r12_y", "r12_z"]),
        r.nums(["q1_0", "q1_1", "q1_2", "q1_3", "q1_4", "q1_5"])
            .unwrap_or_else(|e| panic!("{e}")),
        r.nums(["q2_0", "q2_1", "q2_2", "q2_3", "q2_4", "q2_5"])
            .unwrap_or_else(|e| panic!("{e}")),
    )
}

/// |value − reference| / |reference| in the Euclidean norm.
fn vector_error(value: &[f64; 3], reference: &[f64; 3]) -> f64 {
    let norm = |v: [f64; 3]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    norm(core::array::from_fn(|k| value[k] - reference[k])) / norm(*reference)
}

/// The worst error per category and overall, with the case it was met on.
#[derive(Default)]
struct Worst {
    by_category: BTreeMap<String, f64>,
    overall: (f64, String),
}

impl Worst {
    fn add(&mut self, category: &str, id: &str, error: f64) {
        let w = self.by_category.entry(category.to_string()).or_insert(0.0);
        *w = w.max(error);
        if error > self.overall.0 || self.overall.1.is_empty() {
            self.overall = (error, id.to_string());
        }
    }
}

#[test]
fn objective_within_1e_13_on_stiff_pairs() {
    let t = table("pw85_objective.csv");
    assert_eq!(t.len(), 1107);
    let mut worst = Worst::default();
    for r in t.rows() {
        let (r12, q1, q2) = inputs(&r);
        let id = r.text("case_id").unwrap().to_string();
        let category = r.text("category").unwrap();
        let lambda = r.num("lambda").unwrap();
        let f =
            pw85::objective(lambda, &r12, &q1, &q2).unwrap_or_else(|e| panic!("case {id}: {e}"));
        worst.add(category, &id, relative_error(f, r.num("f_ref").unwrap()));
    }
    for (category, w) in &worst.by_category {
        println!("{category:<16} worst relative error of f(λ): {w:.3e}");
    }
    let (e, id) = &worst.overall;
    println!("worst {e:.3e} (case {id})");
    assert!(*e <= 1e-13, "f(λ) off by {e:.3e} relative on case {id}");
}

#[test]
fn contact_details_within_1e_12_on_stiff_pairs() {
    let t = table("pw85_details.csv");
    assert_eq!(t.len(), 490);
    let names = ["mu2", "lambda", "point", "normal", "grad_r12"];
    let mut worst: BTreeMap<&str, Worst> = names.iter().map(|&n| (n, Worst::default())).collect();
    for r in t.rows() {
        let (r12, q1, q2) = inputs(&r);
        let id = r.text("case_id").unwrap().to_string();
        let category = r.text("category").unwrap();
        let num3 = |names| r.nums(names).unwrap_or_else(|e| panic!("{e}"));
        let d = pw85::contact_details(&r12, &q1, &q2).unwrap_or_else(|e| panic!("case {id}: {e}"));
        let errors = [
            relative_error(d.contact.mu2, r.num("mu2_ref").unwrap()),
            (d.contact.lambda - r.num("lambda_ref").unwrap()).abs(),
            vector_error(&d.point, &num3(["point_x", "point_y", "point_z"])),
            vector_error(&d.normal, &num3(["normal_x", "normal_y", "normal_z"])),
            vector_error(
                &d.grad_r12,
                &num3(["grad_r12_x", "grad_r12_y", "grad_r12_z"]),
            ),
        ];
        for (name, e) in names.iter().zip(errors) {
            worst.get_mut(name).unwrap().add(category, &id, e);
        }
    }
    for (name, w) in &worst {
        for (category, e) in &w.by_category {
            println!("{name:<8} {category:<16} {e:.3e}");
        }
        println!("{name:<8} worst {:.3e} (case {})", w.overall.0, w.overall.1);
    }
    // μ² as `contact_function` promises; λ₀ absolute, as in `reference.rs`; the point, the
    // normal and ∂μ²/∂r12 relative, in the Euclidean norm.
    let bounds = [1e-13, 1e-12, 1e-12, 1e-12, 1e-12];
    for (name, bound) in names.iter().zip(bounds) {
        let (e, id) = &worst[name].overall;
        assert!(
            *e <= bound,
            "{name} off by {e:.3e} (bound {bound:.0e}) on case {id}"
        );
    }
}
