//! The theory checks: each computes a residual of an identity or theorem of the papers on many
//! inputs and compares its worst value with a tolerance chosen from the accuracy the crates
//! document (pw85: μ² to about 1e-15 on ordinary pairs; implicit-packing: U, d² to 1e-12).
//!
//! PW85 (theory chapter): eqs. 15–17 (coefficients of a, b), 18–20 (c = f′b²), 13 (equal
//! quadratic forms at λ₀), 14 (the scaled ellipsoids are tangent, checked with the other
//! criterion), spheres, invariances. Implicit-variable model (Birgin–Lobato–Martínez): Lemma
//! 4.3, Lemma 4.4, Prop. 3.3, Prop. 4.2, the KKT conditions of eq. 35, Appendix A.1 against
//! finite differences. The cell grid against brute force. Both reference files.

use crate::error::{self, Error};
use crate::implicit;
use crate::reference::{self, relative_error, scaled_error};
use crate::sample::Pw85Form as _;
use crate::sample::{self, Pair3, Rng, Spread};
use pw85::poly::{
    a_coefficients, b_coefficients, c_coefficients, eq13_forms, f_direct, pencil, polyval,
};
use pw85::sym::{det_sym, xt_adj_x};
use std::collections::{BTreeMap, BTreeSet};

/// One check: its worst residual against its tolerance.
#[derive(Debug, Clone)]
pub struct Check {
    /// Which part: "pw85", "implicit", "grid", "reference".
    pub group: &'static str,
    /// What is checked, with the equation number.
    pub name: String,
    /// Worst residual over the inputs (a count for verdict checks).
    pub residual: f64,
    /// The tolerance.
    pub tolerance: f64,
    /// Number of inputs.
    pub cases: usize,
    /// Where the worst residual occurred, or other detail.
    pub detail: String,
}

impl Check {
    /// NaN residuals fail.
    pub fn passed(&self) -> bool {
        self.residual <= self.tolerance
    }

    /// One line for the terminal.
    pub fn line(&self) -> String {
        format!(
            "{}  {:<9} {:<58} residual {:>9.2e}  tol {:>7.0e}  ({} cases{}{})",
            if self.passed() { "PASS" } else { "FAIL" },
            self.group,
            self.name,
            self.residual,
            self.tolerance,
            self.cases,
            if self.detail.is_empty() { "" } else { "; " },
            self.detail
        )
    }
}

/// Running maximum that remembers where it occurred.
#[derive(Debug, Default)]
struct Worst {
    value: f64,
    at: String,
    n: usize,
}

impl Worst {
    fn add(&mut self, v: f64, at: impl FnOnce() -> String) {
        self.n += 1;
        // A NaN residual is a failure and must stick: max() would drop it.
        if self.value.is_nan() {
            return;
        }
        if v.is_nan() || v > self.value {
            self.value = v;
            self.at = at();
        }
    }

    fn check(self, group: &'static str, name: &str, tolerance: f64) -> Check {
        Check {
            group,
            name: name.to_string(),
            residual: self.value,
            tolerance,
            cases: self.n,
            detail: if self.at.is_empty() {
                String::new()
            } else {
                format!("worst: {}", self.at)
            },
        }
    }
}

/// The tolerance of identities evaluated in f64 on ordinary pairs (aspect ratios ≤ 10): a few
/// dozen roundings of terms of the size of the scale, 1e-14 ≈ 45 u.
const ORDINARY: f64 = 1e-14;
/// Where the inputs themselves are rounded again (rotated or translated copies of a pair),
/// μ² moves by its condition number times u; 1e-13 allows a condition number of ~ 500.
const REROUNDED: f64 = 1e-13;
/// Eq. 13 at the returned λ₀: u₁ − u₂ = f′(λ) (envelope theorem), so the forms differ by
/// f″ δλ where δλ is the error of λ₀. pw85 stops its Newton iteration once the relative gain
/// of a step is below 1e-12 and then takes that step, which leaves δλ of order 1e-12 relative
/// to the curvature (μ² is insensitive to it, being stationary): 1e-10 is that bound with the
/// curvature of ordinary pairs (|λ² (ln f)″| ≲ 100).
const LAMBDA_SHARPNESS: f64 = 1e-10;
/// The accuracy the implicit-variable crate states for U and d² (its reference tests).
const IMPLICIT_ACCURACY: f64 = 1e-12;

fn pw85_moderate(rng: &mut Rng) -> Result<(Pair3, sample::Pw85Pair), Error> {
    let p = sample::pair_near_contact(rng, 10.0, 0.5, 1.5)?;
    let q = p.pw85()?;
    Ok((p, q))
}

fn diag_max(q: &[f64; 6]) -> f64 {
    q[0].max(q[3]).max(q[5])
}

fn contact(p: &sample::Pw85Pair) -> Result<pw85::Contact, Error> {
    pw85::contact_function(&p.r12, &p.q1, &p.q2).map_err(error::pw85("a theory-check pair"))
}

/// The PW85 checks on `n` random pairs.
pub fn pw85_checks(n: usize, seed: u64) -> Result<Vec<Check>, Error> {
    let mut rng = Rng::new(seed);
    let [mut ab, mut eq15, mut c_alg, mut c_fd, mut eq13, mut tangent] = <[Worst; 6]>::default();
    for k in 0..n {
        let (pair, p) = pw85_moderate(&mut rng)?;
        let (r, q1, q2) = (&p.r12, &p.q1, &p.q2);
        let a = a_coefficients(r, q1, q2);
        let b = b_coefficients(q1, q2);
        let c = c_coefficients(&a, &b);
        let d = diag_max(q1).max(diag_max(q2));
        let r2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
        for step in 0..=10 {
            let lam = f64::from(step) / 10.0;
            let q = pencil(lam, q1, q2);
            // Scales: every entry of an SPD matrix is at most its largest diagonal entry, so
            // |r|² d² bounds the terms of a(λ) and d³ those of b(λ).
            let ea = (polyval(&a, lam) - xt_adj_x(r, &q)).abs() / (r2 * d * d);
            let eb = (polyval(&b, lam) - det_sym(&q)).abs() / (d * d * d);
            ab.add(ea.max(eb), || format!("pair {k}, λ = {lam}"));
            if step > 0 && step < 10 {
                let (av, bv) = (polyval(&a, lam), polyval(&b, lam));
                let f15 = lam * (1.0 - lam) * av / bv;
                // f of eq. 11 by an LDLᵀ solve is accurate to about κ(Q(λ)) u: the residual is
                // measured in that unit, so that it stays ~ u on well and badly shaped pairs.
                let kappa = condition(&pencil(lam, q1, q2));
                eq15.add(
                    relative_error(f15, f_direct(lam, r, q1, q2)) / kappa,
                    || format!("pair {k}, λ = {lam}"),
                );
                // c = f′ b² with f′ from the quotient rule on the same polynomials: checks the
                // algebra of eqs. 20a–g independently of how a and b were obtained.
                let da = a[1] + 2.0 * a[2] * lam;
                let db = b[1] + 2.0 * b[2] * lam + 3.0 * b[3] * lam * lam;
                let quotient =
                    (1.0 - 2.0 * lam) * av * bv + lam * (1.0 - lam) * (da * bv - av * db);
                let abs_a: Vec<f64> = a.iter().map(|x| x.abs()).collect();
                let abs_b: Vec<f64> = b.iter().map(|x| x.abs()).collect();
                let scale = 8.0 * polyval(&abs_a, 1.0) * polyval(&abs_b, 1.0);
                c_alg.add((polyval(&c, lam) - quotient).abs() / scale, || {
                    format!("pair {k}, λ = {lam}")
                });
                // And against a five-point central difference of the direct f (eq. 11). The
                // poles of f (roots of b) can lie 0.01 outside [0, 1] for axis ratios of 10,
                // so the truncation h⁴ f⁽⁵⁾/30 is ≈ 1e-12 and the rounding κ u / h ≈ 1e-10 at
                // h = 1e-4.
                let h = 1e-4;
                let fx = |x: f64| f_direct(x, r, q1, q2);
                let fd = (8.0 * (fx(lam + h) - fx(lam - h))
                    - (fx(lam + 2.0 * h) - fx(lam - 2.0 * h)))
                    / (12.0 * h);
                let fp = polyval(&c, lam) / (bv * bv);
                let fscale = f_direct(0.5, r, q1, q2).abs().max(f15.abs());
                c_fd.add((fp - fd).abs() / fscale, || format!("pair {k}, λ = {lam}"));
            }
        }
        let ct = contact(&p)?;
        let (u1, u2) = eq13_forms(ct.lambda, r, q1, q2);
        eq13.add(
            relative_error(u1, ct.mu2).max(relative_error(u2, ct.mu2)),
            || format!("pair {k}"),
        );
        // Eq. 14: scaled by μ about their centres, the ellipsoids touch: the implicit-variable
        // criterion must find d² = 1 (and f = 0 up to rounding).
        let mu = ct.mu2.sqrt();
        let mut touching = pair;
        touching.li = pair.li.map(|l| l * mu);
        touching.lj = pair.lj.map(|l| l * mu);
        let t = implicit::term(&touching)?;
        tangent.add((t.d2 - 1.0).abs(), || format!("pair {k}"));
    }
    let mut checks = vec![
        ab.check(
            "pw85",
            "eqs. 16–17: sampled coefficients reproduce a(λ), b(λ)",
            ORDINARY,
        ),
        eq15.check(
            "pw85",
            "eq. 15: λ(1−λ)a/b equals f of eq. 11 (÷ κ(Q(λ)))",
            ORDINARY,
        ),
        c_alg.check(
            "pw85",
            "eqs. 18–20: c(λ) equals f′b² (quotient rule)",
            ORDINARY,
        ),
        c_fd.check(
            "pw85",
            "eq. 18: c/b² against a central difference of f",
            1e-8,
        ),
        eq13.check(
            "pw85",
            "eq. 13: both quadratic forms equal μ² at λ₀",
            LAMBDA_SHARPNESS,
        ),
        tangent.check(
            "pw85",
            "eq. 14: scaled by μ, d² = 1 (implicit criterion)",
            IMPLICIT_ACCURACY,
        ),
    ];
    checks.extend(invariance_checks(n, seed ^ 0x5eed)?);
    Ok(checks)
}

fn quat_mul(a: &[f64; 4], b: &[f64; 4]) -> [f64; 4] {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

fn invariance_checks(n: usize, seed: u64) -> Result<Vec<Check>, Error> {
    let mut rng = Rng::new(seed);
    let [
        mut spheres,
        mut rotation,
        mut shifted,
        mut scaling,
        mut swap,
    ] = <[Worst; 5]>::default();
    for k in 0..n {
        // Spheres: μ = |r| / (a1 + a2).
        let (a1, a2) = (rng.spread(0.1, 10.0), rng.spread(0.1, 10.0));
        let dist = rng.spread(0.05, 50.0);
        let r = rng.direction().map(|x| x * dist);
        let q1 = pw85::spheroid(a1, a1, &[0.0, 0.0, 1.0]).map_err(error::pw85("a sphere"))?;
        let q2 = pw85::spheroid(a2, a2, &[0.0, 0.0, 1.0]).map_err(error::pw85("a sphere"))?;
        let c = pw85::contact_function(&r, &q1, &q2).map_err(error::pw85("two spheres"))?;
        let norm = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
        let mu_ref = norm / (a1 + a2);
        spheres.add(relative_error(c.mu2, mu_ref * mu_ref), || {
            format!("pair {k}")
        });

        let (pair, p) = pw85_moderate(&mut rng)?;
        let base = contact(&p)?.mu2;

        let rot = rng.unit_quaternion();
        let rotated = Pair3 {
            ci: rotate(&rot, &pair.ci),
            cj: rotate(&rot, &pair.cj),
            oi: quat_mul(&rot, &pair.oi),
            oj: quat_mul(&rot, &pair.oj),
            ..pair
        };
        rotation.add(relative_error(contact(&rotated.pw85()?)?.mu2, base), || {
            format!("pair {k}")
        });

        let shift = rng.in_ball().map(|x| 10.0 * x);
        let moved = Pair3 {
            ci: [0, 1, 2].map(|m| pair.ci[m] + shift[m]),
            cj: [0, 1, 2].map(|m| pair.cj[m] + shift[m]),
            ..pair
        };
        shifted.add(relative_error(contact(&moved.pw85()?)?.mu2, base), || {
            format!("pair {k}")
        });

        let nu = 3.0;
        let scaled = Pair3 {
            ci: pair.ci.map(|x| nu * x),
            cj: pair.cj.map(|x| nu * x),
            li: pair.li.map(|x| nu * x),
            lj: pair.lj.map(|x| nu * x),
            ..pair
        };
        scaling.add(relative_error(contact(&scaled.pw85()?)?.mu2, base), || {
            format!("pair {k}")
        });

        let swapped = sample::Pw85Pair {
            r12: p.r12.map(|x| -x),
            q1: p.q2,
            q2: p.q1,
        };
        swap.add(relative_error(contact(&swapped)?.mu2, base), || {
            format!("pair {k}")
        });
    }
    Ok(vec![
        spheres.check("pw85", "spheres: μ = |r|/(a1 + a2)", ORDINARY),
        rotation.check("pw85", "invariance: common rotation", REROUNDED),
        shifted.check("pw85", "invariance: common translation", REROUNDED),
        scaling.check("pw85", "invariance: common scaling by 3", REROUNDED),
        swap.check("pw85", "invariance: swap (−r12, Q2, Q1)", ORDINARY),
    ])
}

/// v rotated by the unit quaternion q.
fn rotate(q: &[f64; 4], v: &[f64; 3]) -> [f64; 3] {
    let p = [0.0, v[0], v[1], v[2]];
    let conj = [q[0], -q[1], -q[2], -q[3]];
    let r = quat_mul(&quat_mul(q, &p), &conj);
    [r[1], r[2], r[3]]
}

/// All three eigenvalues of a symmetric 3×3 matrix, ascending (trigonometric closed form).
fn eigenvalues(a: &[[f64; 3]; 3]) -> [f64; 3] {
    let p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    if p == 0.0 {
        return [q; 3];
    }
    let b: [[f64; 3]; 3] = core::array::from_fn(|i| {
        core::array::from_fn(|j| (a[i][j] - if i == j { q } else { 0.0 }) / p)
    });
    let det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1])
        - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0])
        + b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
    let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
    let hi = q + 2.0 * p * phi.cos();
    let lo = q + 2.0 * p * (phi + 2.0 * std::f64::consts::FRAC_PI_3).cos();
    [lo, 3.0 * q - hi - lo, hi]
}

/// The condition number of a stored symmetric positive definite matrix.
fn condition(q: &[f64; 6]) -> f64 {
    let m = [[q[0], q[1], q[2]], [q[1], q[3], q[4]], [q[2], q[4], q[5]]];
    let e = eigenvalues(&m);
    e[2] / e[0].max(f64::MIN_POSITIVE)
}

fn mat_vec(s: &[[f64; 3]; 3], x: &[f64; 3]) -> [f64; 3] {
    core::array::from_fn(|r| s[r][0] * x[0] + s[r][1] * x[1] + s[r][2] * x[2])
}

fn norm(v: &[f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// The implicit-variable checks on `n` random pairs.
pub fn implicit_checks(n: usize, seed: u64) -> Result<Vec<Check>, Error> {
    let mut rng = Rng::new(seed);
    let mut lemma43 = Worst::default();
    let mut lemma43_bad = 0usize;
    let mut lemma44 = Worst::default();
    let mut prop33 = Worst::default();
    let mut prop42 = Worst::default();
    let mut kkt = Worst::default();
    for k in 0..n {
        let pair = sample::pair_near_contact(&mut rng, 10.0, 0.5, 1.5)?;
        let p = pair.pw85()?;
        let mu2 = contact(&p)?.mu2;
        let (i, j) = implicit::bodies(&pair)?;
        let t = implicit::term_of(&i, &j);
        // Lemma 4.3: f = 0 ⇔ no overlap ⇔ μ² ≥ 1. Pairs within 1e-12 of tangency are left
        // out: there the two criteria are each within their rounding of the boundary.
        if (mu2 - 1.0).abs() > 1e-12 {
            let agree = (t.f > 0.0) == (mu2 < 1.0);
            if !agree {
                lemma43_bad += 1;
                lemma43.at = format!("pair {k}: f = {:e}, μ² = {mu2}", t.f);
            }
            lemma43.n += 1;
        }
        // Lemma 4.4: f, U, d² invariant under a common scaling about the origin.
        let nu = [1e-3, 0.37, 1e3][k % 3];
        let (si, sj) = implicit::scaled(&i, &j, nu)?;
        let ts = implicit::term_of(&si, &sj);
        lemma44.add(
            scaled_error(ts.d2, t.d2).max(scaled_error(ts.u, t.u)),
            || format!("pair {k}, ν = {nu}"),
        );
        // Prop. 3.3: U ≥ ε on separated pairs; the tolerance (4 ε_mach relative) is the rounding
        // of ε (five operations) and of U.
        if mu2 > 1.0 + 1e-12 {
            prop33.add(((t.eps - t.u) / t.eps).max(0.0), || format!("pair {k}"));
        }
        if t.x_unique {
            let s = implicit::s_matrix(&i, &j);
            let sx = mat_vec(&s, &t.x);
            let res: [f64; 3] = core::array::from_fn(|m| t.x[m] + t.u * sx[m] - t.c[m]);
            // Backward-error normalisation: S is formed here (an error of u ‖S‖ per entry), so
            // each residual is divided by the size of its terms with ‖S‖ in place of S.
            let s_norm = eigenvalues(&s)[2];
            let xn = norm(&t.x);
            let scale = xn + t.u.abs() * s_norm * xn + norm(&t.c);
            let constraint = (t.x[0] * sx[0] + t.x[1] * sx[1] + t.x[2] * sx[2] - 1.0).abs()
                / (s_norm * xn * xn).max(1.0);
            kkt.add((norm(&res) / scale).max(constraint), || format!("pair {k}"));
        }
    }
    lemma43.value = lemma43_bad as f64;
    // Prop. 4.2 needs the centre inside: pairs much closer than contact.
    let mut inside = 0usize;
    for k in 0..n {
        let pair = sample::pair_near_contact(&mut rng, 10.0, 0.02, 0.6)?;
        let (i, j) = implicit::bodies(&pair)?;
        let t = implicit::term_of(&i, &j);
        if !t.centre_inside {
            continue;
        }
        inside += 1;
        let lmax = eigenvalues(&implicit::s_matrix(&i, &j))[2];
        // −1/λmax(S) ≤ U ≤ 0, with a relative margin of 1e-13 for λmax computed from a formed S.
        let below = (-1.0 / lmax - t.u) * lmax;
        prop42.add(below.max(t.u * lmax).max(0.0), || format!("pair {k}"));
    }
    let mut checks = vec![
        Check {
            group: "implicit",
            name: "Lemma 4.3: f = 0 ⇔ μ² ≥ 1 (disagreements)".into(),
            residual: lemma43.value,
            tolerance: 0.0,
            cases: lemma43.n,
            detail: lemma43.at,
        },
        lemma44.check(
            "implicit",
            "Lemma 4.4: U, d² invariant under scaling",
            IMPLICIT_ACCURACY,
        ),
        prop33.check(
            "implicit",
            "Prop. 3.3: U ≥ ε on separated pairs (violation)",
            4.0 * f64::EPSILON,
        ),
        prop42.check(
            "implicit",
            "Prop. 4.2: U ∈ [−1/λmax(S), 0], centre inside",
            REROUNDED,
        ),
        kkt.check(
            "implicit",
            "eqs. 22, 35: KKT residuals (backward error)",
            ORDINARY,
        ),
    ];
    if inside == 0 {
        checks[3].residual = f64::NAN;
        checks[3].detail = "no pair had its centre inside".into();
    }
    checks.push(derivative_check(n.min(2000), seed ^ 0xa1)?);
    Ok(checks)
}

/// Appendix A.1: ∇d² and ∇U with respect to both centres and both rotations against central
/// differences.
fn derivative_check(n: usize, seed: u64) -> Result<Check, Error> {
    let mut rng = Rng::new(seed);
    let mut worst = Worst::default();
    let h = 1e-6;
    for k in 0..n {
        let pair = sample::pair_near_contact(&mut rng, 10.0, 0.75, 0.98)?;
        let (i, j) = implicit::bodies(&pair)?;
        let t = implicit::term_of(&i, &j);
        // The gradients exist where X is unique and the centre outside (the hard case is a
        // kink of U).
        if !t.x_unique || t.centre_inside {
            continue;
        }
        let d = implicit::derivatives(&i, &j);
        let eval = |a: &implicit_packing::Ellipsoid, b: &implicit_packing::Ellipsoid| {
            let t = implicit::term_of(a, b);
            (t.d2, t.u)
        };
        let mut residual = 0.0f64;
        for axis in 0..3 {
            let mut e = [0.0; 3];
            e[axis] = h;
            let plus = |c: [f64; 3]| [c[0] + e[0], c[1] + e[1], c[2] + e[2]];
            let minus = |c: [f64; 3]| [c[0] - e[0], c[1] - e[1], c[2] - e[2]];
            let neg = e.map(|x| -x);
            let probes = [
                (
                    eval(&implicit::moved(&i, plus(i.centre()))?, &j),
                    eval(&implicit::moved(&i, minus(i.centre()))?, &j),
                    d.grad_d2.centre_i[axis],
                    d.grad_u.centre_i[axis],
                ),
                (
                    eval(&i, &implicit::moved(&j, plus(j.centre()))?),
                    eval(&i, &implicit::moved(&j, minus(j.centre()))?),
                    d.grad_d2.centre_j[axis],
                    d.grad_u.centre_j[axis],
                ),
                (
                    eval(&implicit::turned(&i, e)?, &j),
                    eval(&implicit::turned(&i, neg)?, &j),
                    d.grad_d2.angular_i[axis],
                    d.grad_u.angular_i[axis],
                ),
                (
                    eval(&i, &implicit::turned(&j, e)?),
                    eval(&i, &implicit::turned(&j, neg)?),
                    d.grad_d2.angular_j[axis],
                    d.grad_u.angular_j[axis],
                ),
            ];
            for (p, m, gd, gu) in probes {
                let fd_d2 = (p.0 - m.0) / (2.0 * h);
                let fd_u = (p.1 - m.1) / (2.0 * h);
                residual = residual
                    .max((fd_d2 - gd).abs() / (1.0 + gd.abs()))
                    .max((fd_u - gu).abs() / (1.0 + gu.abs()));
            }
        }
        worst.add(residual, || format!("pair {k}"));
    }
    // Central differences at h = 1e-6: truncation h² g‴ ≈ 1e-12 and rounding u/h ≈ 1e-10
    // relative; 1e-6 leaves room for curvature of U near contact.
    Ok(worst.check(
        "implicit",
        "App. A.1: ∇d², ∇U (centres, rotations) vs central differences",
        1e-6,
    ))
}

/// The cell grid against brute force, 2D and 3D.
pub fn grid_checks(n: usize, seed: u64) -> Result<Vec<Check>, Error> {
    let mut rng = Rng::new(seed);
    let m = n.clamp(100, 3000);
    // Side chosen for about ten neighbours within the cutoff per point.
    let side3 = (m as f64 * 4.0 * std::f64::consts::FRAC_PI_3 / 10.0).cbrt();
    let side2 = (m as f64 * std::f64::consts::PI / 10.0).sqrt();
    Ok(vec![
        grid_check::<3>(&mut rng, m, side3)?,
        grid_check::<2>(&mut rng, m, side2)?,
    ])
}

/// The pairs of `m` uniform points in a square or cube of side `side` that lie within 1 of each
/// other: the grid's against brute force.
fn grid_check<const D: usize>(rng: &mut Rng, m: usize, side: f64) -> Result<Check, Error> {
    let cutoff = 1.0;
    let points: Vec<[f64; D]> = (0..m)
        .map(|_| [0; D].map(|_| rng.range(0.0, side)))
        .collect();
    let grid_err = |e: cell_grid::Error| Error::Grid {
        message: e.to_string(),
    };
    let mut found = BTreeSet::new();
    cell_grid::Grid::<D>::build(&points, cutoff)
        .map_err(grid_err)?
        .for_each_pair_within(&points, |i, j, _| {
            found.insert((i.min(j), i.max(j)));
        })
        .map_err(grid_err)?;
    let mut brute = BTreeSet::new();
    for i in 0..m {
        for j in i + 1..m {
            let d2: f64 = (0..D).map(|k| (points[i][k] - points[j][k]).powi(2)).sum();
            if d2 < cutoff * cutoff {
                brute.insert((i, j));
            }
        }
    }
    Ok(Check {
        group: "grid",
        name: format!("{D}D grid pairs within cutoff = brute force (differences)"),
        residual: found.symmetric_difference(&brute).count() as f64,
        tolerance: 0.0,
        cases: m,
        detail: format!("{} pairs", brute.len()),
    })
}

/// The reference files against the accuracy bounds of the crates' issues: μ² to 1e-13
/// relative in every category and the verdict outside 2e-13 of tangency (pw85); U, d², X to
/// 1e-12, ε to 1e-15 and every verdict (implicit-packing).
pub fn reference_checks(groups: Groups) -> Result<Vec<Check>, Error> {
    let mut checks = Vec::new();
    if groups.pw85 {
        checks.extend(pw85_reference_checks()?);
    }
    if groups.implicit {
        checks.extend(blm_reference_checks()?);
    }
    Ok(checks)
}

fn pw85_reference_checks() -> Result<Vec<Check>, Error> {
    let cases = reference::contact_cases()?;
    let mut mu2 = Worst::default();
    let mut by_category: BTreeMap<&str, f64> = BTreeMap::new();
    let mut verdicts = Worst::default();
    let mut wrong = 0usize;
    for c in &cases {
        let ct = contact(&c.pair)?;
        let e = relative_error(ct.mu2, c.mu2);
        mu2.add(e, || format!("case {} ({})", c.id, c.category));
        let w = by_category.entry(&c.category).or_default();
        *w = w.max(e);
        if c.mu2_minus_one().abs() > 2e-13 {
            let v = pw85::overlap(&c.pair.r12, &c.pair.q1, &c.pair.q2)
                .map_err(error::pw85(format!("reference case {}", c.id)))?;
            verdicts.n += 1;
            if v != (c.mu2_minus_one() < 0.0) {
                wrong += 1;
                verdicts.at = format!("case {}", c.id);
            }
        }
    }
    verdicts.value = wrong as f64;
    Ok(vec![
        mu2.check(
            "reference",
            "pw85_contact.csv: μ² relative error, every category",
            1e-13,
        ),
        verdicts.check(
            "reference",
            "pw85_contact.csv: verdicts outside 2e-13 (wrong)",
            0.0,
        ),
    ])
}

/// The checks of one implicit-model reference file: `$term` is the measured pair term of its
/// case `$c`. A macro because the rows of `blm_3d.csv` and `blm_2d.csv` are two types with the
/// same fields.
macro_rules! blm_file {
    ($file:literal, $cases:expr, |$c:ident| $term:expr) => {{
        let (mut ud, mut x, mut eps, mut verdict) = blm_worst();
        for $c in &$cases {
            let t = $term;
            blm_add(
                (&mut ud, &mut x, &mut eps, &mut verdict),
                &$c.id,
                &$c.category,
                (t.u, t.d2, t.eps, t.f),
                ($c.u, $c.d2, $c.eps, $c.f, $c.mu2),
                $c.x.map(|r| (t.x.to_vec(), r.to_vec())),
            );
        }
        blm_checks($file, ud, x, eps, verdict)
    }};
}

fn blm_reference_checks() -> Result<Vec<Check>, Error> {
    let blm3 = reference::blm_3d()?;
    let mut checks = blm_file!("blm_3d.csv", blm3, |c| implicit::term(&c.pair)?);
    let blm2 = reference::blm_2d()?;
    checks.extend(blm_file!("blm_2d.csv", blm2, |c| {
        let (i, j) = implicit::ellipses(&c.pair)?;
        implicit::term_of(&i, &j)
    }));
    Ok(checks)
}

fn blm_worst() -> (Worst, Worst, Worst, Worst) {
    Default::default()
}

type Measured = (f64, f64, f64, f64);
type Expected = (f64, f64, f64, f64, f64);

fn blm_add(
    (ud, x, eps, verdict): (&mut Worst, &mut Worst, &mut Worst, &mut Worst),
    id: &str,
    category: &str,
    (u, d2, e, f): Measured,
    (u_ref, d2_ref, e_ref, f_ref, mu2_ref): Expected,
    xs: Option<(Vec<f64>, Vec<f64>)>,
) {
    let at = || format!("case {id} ({category})");
    ud.add(scaled_error(u, u_ref).max(scaled_error(d2, d2_ref)), at);
    eps.add(relative_error(e, e_ref), at);
    // X jumps between two branches in `near_hard` (the reference README says to compare U
    // and d² only there).
    if let Some((mine, theirs)) = xs
        && category != "near_hard"
    {
        let num: f64 = mine
            .iter()
            .zip(&theirs)
            .map(|(a, b)| (a - b) * (a - b))
            .sum();
        let den: f64 = theirs.iter().map(|b| b * b).sum();
        x.add((num / den).sqrt(), at);
    }
    let overlap_ref = f_ref > 0.0 || mu2_ref < 1.0;
    verdict.n += 1;
    if (f > 0.0) != overlap_ref {
        verdict.value += 1.0;
        verdict.at = at();
    }
}

fn blm_checks(file: &str, ud: Worst, x: Worst, eps: Worst, verdict: Worst) -> Vec<Check> {
    vec![
        ud.check(
            "reference",
            &format!("{file}: U, d² error"),
            IMPLICIT_ACCURACY,
        ),
        x.check(
            "reference",
            &format!("{file}: X relative error (X unique)"),
            IMPLICIT_ACCURACY,
        ),
        eps.check("reference", &format!("{file}: ε relative error"), 1e-15),
        verdict.check("reference", &format!("{file}: verdicts f > 0 (wrong)"), 0.0),
    ]
}

/// Which groups of checks a theory scene asks for (its `criteria`).
#[derive(Debug, Clone, Copy)]
pub struct Groups {
    /// PW85 identities, invariances and the PW85 reference file.
    pub pw85: bool,
    /// The implicit-variable model, the cell grid and the implicit reference files.
    pub implicit: bool,
}

/// Every selected theory check with `n` random pairs per check. The cross-criterion checks
/// (eq. 14 with d², Lemma 4.3 against μ²) call both crates whichever group they belong to.
pub fn all(
    n: usize,
    seed: u64,
    groups: Groups,
    progress: &dyn Fn(&str),
) -> Result<Vec<Check>, Error> {
    let mut checks = Vec::new();
    if groups.pw85 {
        progress("theory: PW85 identities and invariances");
        checks.extend(pw85_checks(n, seed)?);
    }
    if groups.implicit {
        progress("theory: implicit-variable model");
        checks.extend(implicit_checks(n, seed ^ 0x1b)?);
        // The grid serves the implicit model's O(m) evaluation (Section 5.2).
        progress("theory: cell grid against brute force");
        checks.extend(grid_checks(n, seed ^ 0x9d)?);
    }
    progress("theory: reference files");
    checks.extend(reference_checks(groups)?);
    Ok(checks)
}

/// The check table for the snapshot: residuals rounded to their decimal exponent, so that a
/// last-bit difference between machines does not change it.
pub fn table(checks: &[Check]) -> String {
    let mut s = String::new();
    for c in checks {
        let rounded = if c.residual == 0.0 {
            "0".to_string()
        } else if c.residual.is_nan() {
            "NaN".to_string()
        } else if c.tolerance == 0.0 || c.residual >= 1.0 {
            // Counts.
            format!("{}", c.residual)
        } else {
            format!("1e{}", c.residual.log10().ceil() as i32)
        };
        s.push_str(&format!(
            "{} | {:<9} | {:<62} | residual ≤ {:<6} | tol {:.0e}\n",
            if c.passed() { "PASS" } else { "FAIL" },
            c.group,
            c.name,
            rounded,
            c.tolerance
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(residual: f64, tolerance: f64) -> Check {
        Check {
            group: "t",
            name: "t".into(),
            residual,
            tolerance,
            cases: 1,
            detail: String::new(),
        }
    }

    #[test]
    fn a_check_fails_above_its_tolerance_and_on_nan() {
        assert!(check(1e-15, 1e-14).passed());
        assert!(!check(2e-14, 1e-14).passed());
        assert!(!check(f64::NAN, 1e-14).passed());
        assert!(!check(1.0, 0.0).passed());
    }

    #[test]
    fn nan_residual_sticks_in_the_running_maximum() {
        let mut w = Worst::default();
        w.add(1e-16, String::new);
        w.add(f64::NAN, || "here".into());
        w.add(1.0, String::new);
        assert!(w.value.is_nan());
        assert_eq!(w.at, "here");
    }

    #[test]
    fn eigenvalues_of_a_diagonal_and_a_rotated_matrix() {
        let e = eigenvalues(&[[3.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]]);
        assert!(
            (e[0] - 1.0).abs() < 1e-14 && (e[1] - 2.0).abs() < 1e-14 && (e[2] - 3.0).abs() < 1e-14
        );
        let c = condition(&[2.0, 1.0, 0.0, 2.0, 0.0, 5.0]);
        assert!((c - 5.0).abs() < 1e-13, "{c}");
    }

    #[test]
    fn the_grid_finds_the_pairs_brute_force_finds_in_3d_and_2d() {
        let checks = grid_checks(300, 5).unwrap();
        let names: Vec<&str> = checks.iter().map(|c| &c.name[..2]).collect();
        assert_eq!(names, ["3D", "2D"]);
        for c in &checks {
            assert_eq!(c.residual, 0.0, "{}: {}", c.name, c.detail);
            assert_ne!(c.detail, "0 pairs", "{}", c.name);
        }
    }

    #[test]
    fn each_implicit_reference_file_gives_its_four_checks() {
        let checks = blm_reference_checks().unwrap();
        let files: Vec<&str> = checks.iter().map(|c| &c.name[..10]).collect();
        assert_eq!(files, [["blm_3d.csv"; 4], ["blm_2d.csv"; 4]].concat());
        for c in &checks {
            assert!(c.passed(), "{c:?}");
            assert!(c.cases > 0, "{c:?}");
        }
    }
}
