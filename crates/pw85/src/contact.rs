//! The contact function μ² = max over 0 ≤ λ ≤ 1 of f(λ) (theory eq. 6), its maximiser λ₀, the
//! contact point x₀(λ₀) (eq. 9), the common normal, and the gradient of μ².
//!
//! # Algorithm
//! 1. The Bernstein coefficients of a(λ) and b(λ) (eq. 16, see [`crate::poly`]) are computed
//!    in `f64`, together with a running bound on their rounding error (every term replaced by
//!    its absolute value).
//! 2. λ₀ is found by a bracketed Newton iteration on λ(1 − λ)(ln f)′, started from the exact
//!    maximiser for two spheres of the ellipsoids' radial extents along r12
//!    ([`RationalForm::maximise`]). When λ₀ > ½ the problem is solved in the variable 1 − λ
//!    (coefficients reversed), so that a maximiser close to 1 keeps its relative precision.
//! 3. μ² = f(λ₀) is a sum of non-negative terms and is evaluated without cancellation. If the
//!    error bound of the coefficients says that f lost more than [`REFINE_ABOVE`] to
//!    cancellation (needles, pancakes, nearly singular pencils), the coefficients are
//!    recomputed in double-double arithmetic (≈ 32 digits), rounded, and step 2 is repeated.
//!    The ordinary case never pays for this.
//!
//! The PW85 library instead samples a and b at four points (eq. 17), whose cancellation cannot
//! be repaired afterwards, and bisects c(λ) (eq. 20) to a fixed tolerance, which stops λ early
//! when λ₀ is within that tolerance of 0 or 1 (an ellipsoid much larger than the other).
//!
//! # References
//! - J. W. Perram and M. S. Wertheim, "Statistical mechanics of hard ellipsoids. I. Overlap
//!   algorithm and the contact function", J. Comput. Phys. 58 (1985) 409–416.
//! - `pw85-theory.rst` (the PW85 library's theory chapter): equation numbers in this crate.

use crate::arith::{Arith, Dd, Mag};
use crate::error::{Argument, Error};
use crate::poly::{Coefficients, RationalForm, coefficients_2d, pencil3};
use crate::sym::{Sym2, Sym3, mat_vec};

/// Relative error bound on μ² above which the coefficients are recomputed in double-double.
pub const REFINE_ABOVE: f64 = 1e-14;

/// Rounding-error factor γ of the coefficient formulas: their expression trees are at most
/// about ten operations deep, so |computed − exact| ≤ 10 u Σ|terms| (u = 2⁻⁵³), and ≈ 10 u_dd
/// in double-double (u_dd = 2⁻¹⁰⁴).
const GAMMA_F64: f64 = 10.0 * f64::EPSILON * 0.5;
const GAMMA_DD: f64 = 10.0 * 4.930380657631324e-32;

/// The value of the contact function and where it is attained.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct Contact {
    /// μ² = F(r12, Q1, Q2) = max f(λ) (eq. 6): below 1 the ellipsoids overlap, at 1 they are
    /// externally tangent, above 1 they are apart.
    pub mu2: f64,
    /// The maximiser λ₀ ∈ [0, 1]. When r12 = 0, f ≡ 0 and every λ is a maximiser: λ = ½ is
    /// returned.
    pub lambda: f64,
    /// An estimate of the relative error of `mu2` (a bound on the rounding error of the
    /// coefficients, propagated to f(λ₀), plus the evaluation error).
    pub error_estimate: f64,
    /// Whether the coefficients were recomputed in double-double arithmetic.
    pub refined: bool,
}

/// Everything an MD or optimisation code asks of a contact: μ², λ₀, the contact point, the
/// common normal and the gradient of μ² with respect to r12, Q1 and Q2.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub struct ContactDetails {
    /// μ², λ₀ and the error estimate.
    pub contact: Contact,
    /// x₀(λ₀) − c1 = (1 − λ₀) Q1 Q(λ₀)⁻¹ r12 (eq. 9a): the point where the ellipsoids scaled by
    /// μ touch, relative to the first centre. (x₀ − c2 = this − r12, eq. 9b.)
    pub point: [f64; 3],
    /// The unit normal at x₀ of both scaled ellipsoids, pointing out of the first one:
    /// n ∝ Q1⁻¹ (x₀ − c1) ∝ Q(λ₀)⁻¹ r12 (eq. 8).
    pub normal: [f64; 3],
    /// ∂μ²/∂r12 = 2 λ₀ (1 − λ₀) Q(λ₀)⁻¹ r12 (envelope theorem: f′(λ₀) = 0).
    pub grad_r12: [f64; 3],
    /// ∂μ²/∂q1 for the six stored entries of Q1: with s = Q(λ₀)⁻¹ r12,
    /// ∂μ²/∂Q1 = −λ₀ (1 − λ₀)² s sᵀ, and an off-diagonal stored entry counts twice (it stands
    /// for Q_ij and Q_ji).
    pub grad_q1: [f64; 6],
    /// ∂μ²/∂q2 for the six stored entries of Q2: ∂μ²/∂Q2 = −λ₀² (1 − λ₀) s sᵀ, off-diagonal
    /// entries counted twice.
    pub grad_q2: [f64; 6],
}

/// The contact function μ² of two ellipsoids and its maximiser λ₀ (theory eqs. 6, 13).
///
/// `r12 = c2 − c1`; `q1`, `q2` are the quadratic forms of the ellipsoids
/// {m : (m − cᵢ)ᵀ Qᵢ⁻¹ (m − cᵢ) ≤ 1}, stored as Q11, Q12, Q13, Q22, Q23, Q33. The ellipsoids
/// overlap iff μ² < 1. Centres that coincide give μ² = 0 (not an error).
///
/// # Errors
/// [`Error::NonFinite`] for a NaN or infinite entry, [`Error::NotPositiveDefinite`] when Q1 or
/// Q2 is not positive definite.
///
/// # Example
/// ```
/// // Two unit spheres whose centres are 3 apart: μ = 3 / (1 + 1).
/// let q = pw85::spheroid(1.0, 1.0, &[0.0, 0.0, 1.0])?;
/// let c = pw85::contact_function(&[3.0, 0.0, 0.0], &q, &q)?;
/// assert!((c.mu2 - 2.25).abs() < 1e-15);
/// assert!((c.lambda - 0.5).abs() < 1e-15);
/// # Ok::<(), pw85::Error>(())
/// ```
pub fn contact_function(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<Contact, Error> {
    check_finite(Argument::R12, r12)?;
    check_finite(Argument::Q1, q1)?;
    check_finite(Argument::Q2, q2)?;
    let p = pencil3::<f64>(r12, q1, q2);
    check_positive_definite(Argument::Q1, q1, &p.adj1, p.coefficients.beta[0])?;
    check_positive_definite(Argument::Q2, q2, &p.adj2, p.coefficients.beta[3])?;
    Ok(solve_checked(
        &p.coefficients,
        || crate::poly::coefficients::<Mag>(r12, q1, q2),
        || crate::poly::coefficients::<Dd>(r12, q1, q2),
    )
    .0)
}

/// The contact function of two ellipses: `r12` ∈ ℝ², `q1`, `q2` stored as Q11, Q12, Q22.
/// Same definition, conventions and errors as [`contact_function`] (the PW85 library has no 2D
/// version).
pub fn contact_function_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<Contact, Error> {
    check_finite(Argument::R12, r12)?;
    check_finite(Argument::Q1, q1)?;
    check_finite(Argument::Q2, q2)?;
    check_positive_definite_2d(Argument::Q1, q1)?;
    check_positive_definite_2d(Argument::Q2, q2)?;
    Ok(solve_checked(
        &coefficients_2d::<f64>(r12, q1, q2),
        || coefficients_2d::<Mag>(r12, q1, q2),
        || coefficients_2d::<Dd>(r12, q1, q2),
    )
    .0)
}

/// μ², λ₀, the contact point, the common normal and the gradients of μ² (see
/// [`ContactDetails`]). Costs one contact function and a 3×3 matrix–vector product.
///
/// # Errors
/// As [`contact_function`].
pub fn contact_details(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<ContactDetails, Error> {
    check_finite(Argument::R12, r12)?;
    check_finite(Argument::Q1, q1)?;
    check_finite(Argument::Q2, q2)?;
    let p = pencil3::<f64>(r12, q1, q2);
    check_positive_definite(Argument::Q1, q1, &p.adj1, p.coefficients.beta[0])?;
    check_positive_definite(Argument::Q2, q2, &p.adj2, p.coefficients.beta[3])?;
    let (contact, rational) = solve_checked(
        &p.coefficients,
        || crate::poly::coefficients::<Mag>(r12, q1, q2),
        || crate::poly::coefficients::<Dd>(r12, q1, q2),
    );
    // adj Q(λ) = s² adj Q1 + st M + t² adj Q2, from the same (possibly refined) arithmetic as
    // the coefficients, so that s = adj Q(λ) r / b(λ) is as accurate as μ².
    let (adj1, mixed, adj2) = if contact.refined {
        let d = pencil3::<Dd>(r12, q1, q2);
        (
            d.adj1.map(Arith::to_f64),
            d.mixed.map(Arith::to_f64),
            d.adj2.map(Arith::to_f64),
        )
    } else {
        (p.adj1, p.mixed, p.adj2)
    };
    let t = contact.lambda;
    let s = 1.0 - t;
    let adj: Sym3 = core::array::from_fn(|k| s * s * adj1[k] + s * t * mixed[k] + t * t * adj2[k]);
    let b = rational.b(t);
    let sv = mat_vec(&adj, r12).map(|x| x / b);
    let norm = (sv[0] * sv[0] + sv[1] * sv[1] + sv[2] * sv[2]).sqrt();
    let normal = if norm > 0.0 {
        sv.map(|x| x / norm)
    } else {
        [0.0; 3]
    };
    let ss = [
        sv[0] * sv[0],
        2.0 * sv[0] * sv[1],
        2.0 * sv[0] * sv[2],
        sv[1] * sv[1],
        2.0 * sv[1] * sv[2],
        sv[2] * sv[2],
    ];
    Ok(ContactDetails {
        contact,
        point: mat_vec(q1, &sv).map(|x| s * x),
        normal,
        grad_r12: sv.map(|x| 2.0 * t * s * x),
        grad_q1: ss.map(|x| -t * s * s * x),
        grad_q2: ss.map(|x| -t * t * s * x),
    })
}

/// Solves with the `f64` coefficients, checks their error bound, and re-solves with
/// double-double coefficients when the bound is too large. Returns the contact and the
/// (normalised) rational form it was solved with.
#[inline]
pub(crate) fn solve_checked(
    fast: &Coefficients<f64>,
    magnitude: impl FnOnce() -> Coefficients<Mag>,
    exact: impl FnOnce() -> Coefficients<Dd>,
) -> (Contact, RationalForm) {
    let rational = fast.to_f64();
    let Some(scale) = Scale::of(&rational) else {
        // r12 = 0: a ≡ 0 and f ≡ 0.
        return (
            Contact {
                mu2: 0.0,
                lambda: 0.5,
                error_estimate: 0.0,
                refined: false,
            },
            rational,
        );
    };
    let solution = solve(&scale.apply(&rational));
    let bound = scale.apply(&magnitude().to_f64());
    let estimate = GAMMA_F64 * solution.amplification(&bound) + EVAL;
    if estimate <= REFINE_ABOVE {
        return (scale.contact(&solution, estimate, false), rational);
    }
    let refined = exact().to_f64();
    let scale = Scale::of(&refined).unwrap_or(scale);
    let solution = solve(&scale.apply(&refined));
    let estimate = GAMMA_DD * solution.amplification(&scale.apply(&bound)) + EVAL;
    (scale.contact(&solution, estimate, true), refined)
}

/// Relative rounding error of evaluating f from exact non-negative Bernstein coefficients
/// (a handful of operations, each within u = 2⁻⁵³).
const EVAL: f64 = 8.0 * 0.5 * f64::EPSILON;

/// The normalisation that keeps the solver's arithmetic away from overflow: α and β are
/// divided by their largest entries, and μ² is scaled back at the end.
#[derive(Clone, Copy, Debug)]
struct Scale {
    alpha: f64,
    beta: f64,
}

/// The maximiser found by [`solve`], with a(λ₀) and b(λ₀) of the normalised form.
#[derive(Clone, Copy, Debug)]
struct Solution {
    lambda: f64,
    f: f64,
    a: f64,
    b: f64,
}

impl Solution {
    /// Σ|terms| / value for a and b at λ₀, added: how much a relative error of the
    /// coefficients (measured against `bound`, their Σ|terms|) is amplified in f.
    fn amplification(&self, bound: &RationalForm) -> f64 {
        bound.a(self.lambda) / self.a + bound.b(self.lambda) / self.b
    }
}

/// The maximiser of a normalised rational form (coefficients non-negative, not all zero).
#[inline]
fn solve(r: &RationalForm) -> Solution {
    let t0 = r.initial_guess();
    // Solve in whichever of λ and 1 − λ is small at the maximiser, so that it keeps its
    // relative precision (λ₀ = 1 − 1e-12 is not representable to better than 1e-4 relative
    // in its distance to 1).
    let (lambda, f, a, b) = if t0 > 0.5 {
        let rev = r.reversed();
        let (t, f, _) = rev.maximise(1.0 - t0);
        (1.0 - t, f, rev.a(t), rev.b(t))
    } else {
        let (t, f, _) = r.maximise(t0);
        (t, f, r.a(t), r.b(t))
    };
    Solution { lambda, f, a, b }
}

impl Scale {
    fn of(r: &RationalForm) -> Option<Self> {
        let alpha = r.alpha.iter().fold(0.0_f64, |m, &x| m.max(x));
        let beta = r.beta.iter().fold(0.0_f64, |m, &x| m.max(x));
        (alpha > 0.0 && beta > 0.0).then_some(Self { alpha, beta })
    }

    fn apply(&self, r: &RationalForm) -> RationalForm {
        // Mixed coefficients are non-negative in exact arithmetic; rounding may leave a tiny
        // negative value, which the error bound accounts for.
        RationalForm {
            alpha: r.alpha.map(|x| (x / self.alpha).max(0.0)),
            beta: r.beta.map(|x| (x / self.beta).max(0.0)),
        }
    }

    fn contact(&self, s: &Solution, error_estimate: f64, refined: bool) -> Contact {
        Contact {
            mu2: s.f * (self.alpha / self.beta),
            lambda: s.lambda,
            error_estimate,
            refined,
        }
    }
}

pub(crate) fn check_finite(argument: Argument, values: &[f64]) -> Result<(), Error> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(Error::NonFinite {
            argument,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}

/// Sylvester's criterion on the leading principal minors Q11, Q11 Q22 − Q12², det Q, with the
/// last two decided in double-double when their `f64` value is within its rounding error of 0
/// (a needle of aspect ratio 1e4 has det Q ≈ 1e-16 from entries of order 1).
pub(crate) fn check_positive_definite(
    argument: Argument,
    q: &Sym3,
    adj: &Sym3,
    det: f64,
) -> Result<(), Error> {
    let fail = |minor, value| Err(Error::NotPositiveDefinite {
        argument,
        minor,
        value,
    });
    if !(q[0] > 0.0) {
        return fail(1, q[0]);
    }
    let m2 = adj[5];
    if m2 <= GAMMA_F64 * (q[0] * q[3] + q[1] * q[1]) {
        let exact = (Dd::lift(q[0]) * Dd::lift(q[3]) - Dd::lift(q[1]) * Dd::lift(q[1])).to_f64();
        if !(exact > 0.0) {
            return fail(2, exact);
        }
    }
    let det_bound = crate::sym::det_generic(
        &crate::sym::lift6::<Mag>(q),
        &crate::sym::adjugate_generic(&crate::sym::lift6::<Mag>(q)),
    );
    if det <= GAMMA_F64 * det_bound.0 {
        let qd = crate::sym::lift6::<Dd>(q);
        let exact = crate::sym::det_generic(&qd, &crate::sym::adjugate_generic(&qd)).to_f64();
        if !(exact > 0.0) {
            return fail(3, exact);
        }
    }
    Ok(())
}

/// Sylvester's criterion for a symmetric 2×2 matrix.
pub(crate) fn check_positive_definite_2d(argument: Argument, q: &Sym2) -> Result<(), Error> {
    if !(q[0] > 0.0) {
        return Err(Error::NotPositiveDefinite {
            argument,
            minor: 1,
            value: q[0],
        });
    }
    let det = (Dd::lift(q[0]) * Dd::lift(q[2]) - Dd::lift(q[1]) * Dd::lift(q[1])).to_f64();
    if !(det > 0.0) {
        return Err(Error::NotPositiveDefinite {
            argument,
            minor: 2,
            value: det,
        });
    }
    Ok(())
}
