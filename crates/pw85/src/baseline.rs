//! Straightforward solvers for μ², kept as baselines for benchmarks and for the error-against-
//! cost studies of `cargo xtask validate`. They take valid input (finite, positive definite:
//! see [`crate::contact_function`] for checked input) and a tolerance on λ.
//!
//! - [`bisection`]: the PW85 library's method — coefficients of a and b by sampling (eq. 17),
//!   c(λ) (eq. 20), bisection on c over [0, 1], μ² from eq. 15.
//! - [`brent`]: Brent's derivative-free maximisation of f(λ) (eq. 11), with an LDLᵀ solve of
//!   Q(λ) s = r12 at every evaluation.
//! - [`newton`]: Newton's method on c(λ), bracketed by bisection.
//!
//! # References
//! - R. P. Brent, *Algorithms for Minimization without Derivatives*, Prentice-Hall 1973, ch. 5.

use crate::poly::{a_coefficients, b_coefficients, c_coefficients, f_direct, polyval};
use crate::sym::Sym3;

/// What a baseline solver returns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The approximation of μ².
    pub mu2: f64,
    /// The approximation of λ₀.
    pub lambda: f64,
    /// How many times f (or c) was evaluated.
    pub evaluations: u32,
}

/// The rational form of eq. 15 with the monomial coefficients of eq. 17.
fn f_monomial(lambda: f64, a: &[f64; 3], b: &[f64; 4]) -> f64 {
    lambda * (1.0 - lambda) * polyval(a, lambda) / polyval(b, lambda)
}

/// Bisection on c(λ) (eq. 20) until the bracket is shorter than `tol`, as the PW85 library.
pub fn bisection(r12: &[f64; 3], q1: &Sym3, q2: &Sym3, tol: f64) -> Estimate {
    let a = a_coefficients(r12, q1, q2);
    let b = b_coefficients(q1, q2);
    let c = c_coefficients(&a, &b);
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    let mut evaluations = 0;
    while hi - lo > tol && evaluations < 200 {
        let mid = 0.5 * (lo + hi);
        evaluations += 1;
        if polyval(&c, mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let lambda = 0.5 * (lo + hi);
    Estimate {
        mu2: f_monomial(lambda, &a, &b),
        lambda,
        evaluations,
    }
}

/// Newton's method on c(λ) (eq. 20) from λ = ½, with bisection whenever a step leaves the
/// bracket; stops when a step is shorter than `tol`.
pub fn newton(r12: &[f64; 3], q1: &Sym3, q2: &Sym3, tol: f64) -> Estimate {
    let a = a_coefficients(r12, q1, q2);
    let b = b_coefficients(q1, q2);
    let c = c_coefficients(&a, &b);
    let dc: [f64; 6] = core::array::from_fn(|k| (k + 1) as f64 * c[k + 1]);
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    let mut lambda = 0.5;
    let mut evaluations = 0;
    while evaluations < 100 {
        evaluations += 1;
        let value = polyval(&c, lambda);
        if value > 0.0 {
            lo = lambda;
        } else {
            hi = lambda;
        }
        let mut next = lambda - value / polyval(&dc, lambda);
        if !(next > lo && next < hi) {
            next = 0.5 * (lo + hi);
        }
        let step = (next - lambda).abs();
        lambda = next;
        if step < tol {
            break;
        }
    }
    Estimate {
        mu2: f_monomial(lambda, &a, &b),
        lambda,
        evaluations,
    }
}

/// Brent's maximisation of f(λ) = λ(1 − λ) r12ᵀ Q(λ)⁻¹ r12 on [0, 1] (golden sections with
/// parabolic interpolation), each evaluation an LDLᵀ solve; `tol` is the absolute tolerance
/// on λ.
pub fn brent(r12: &[f64; 3], q1: &Sym3, q2: &Sym3, tol: f64) -> Estimate {
    // Brent minimises; work on g = −f.
    let g = |lambda: f64| -f_direct(lambda, r12, q1, q2);
    const GOLDEN: f64 = 0.381_966_011_250_105_1; // (3 − √5) / 2
    let sqrt_eps = f64::EPSILON.sqrt();
    let (mut a, mut b) = (0.0_f64, 1.0_f64);
    let mut x = a + GOLDEN * (b - a);
    let (mut w, mut v) = (x, x);
    let mut gx = g(x);
    let (mut gw, mut gv) = (gx, gx);
    let mut evaluations = 1;
    let (mut d, mut e) = (0.0_f64, 0.0_f64);
    while evaluations < 200 {
        let mid = 0.5 * (a + b);
        let tol1 = sqrt_eps * x.abs() + tol / 3.0;
        let tol2 = 2.0 * tol1;
        if (x - mid).abs() <= tol2 - 0.5 * (b - a) {
            break;
        }
        let mut golden = true;
        if e.abs() > tol1 {
            // Parabola through (v, gv), (w, gw), (x, gx); its vertex is x + p/q.
            let r = (x - w) * (gx - gv);
            let mut q = (x - v) * (gx - gw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            let previous = e;
            e = d;
            if p.abs() < (0.5 * q * previous).abs() && p > q * (a - x) && p < q * (b - x) {
                d = p / q;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = tol1.copysign(mid - x);
                }
                golden = false;
            }
        }
        if golden {
            e = if x >= mid { a - x } else { b - x };
            d = GOLDEN * e;
        }
        let u = if d.abs() >= tol1 {
            x + d
        } else {
            x + tol1.copysign(d)
        };
        let gu = g(u);
        evaluations += 1;
        if gu <= gx {
            if u >= x {
                a = x;
            } else {
                b = x;
            }
            (v, gv) = (w, gw);
            (w, gw) = (x, gx);
            (x, gx) = (u, gu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if gu <= gw || w == x {
                (v, gv) = (w, gw);
                (w, gw) = (u, gu);
            } else if gu <= gv || v == x || v == w {
                (v, gv) = (u, gu);
            }
        }
    }
    Estimate {
        mu2: -gx,
        lambda: x,
        evaluations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn baselines_agree_on_a_moderate_pair() {
        let r = [1.1, -0.4, 2.3];
        let q1 = [4.0, 1.0, -0.5, 3.0, 0.25, 2.0];
        let q2 = [1.5, -0.3, 0.2, 2.5, 0.7, 3.5];
        let exact = crate::contact_function(&r, &q1, &q2).unwrap();
        for e in [
            bisection(&r, &q1, &q2, 1e-14),
            newton(&r, &q1, &q2, 1e-14),
            brent(&r, &q1, &q2, 1e-10),
        ] {
            assert!(
                (e.mu2 - exact.mu2).abs() < 1e-13 * exact.mu2,
                "{e:?} vs {exact:?}"
            );
            assert!((e.lambda - exact.lambda).abs() < 1e-6);
        }
    }
}
