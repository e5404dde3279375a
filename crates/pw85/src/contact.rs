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

use crate::arith::is_positive;
use crate::arith::{Arith, Dd, Mag, ValMag};
use crate::dispatch::multiversion;
use crate::error::{Argument, Error};
use crate::poly::{Coefficients, RationalForm, Search, coefficients_2d, pencil3};
use crate::sym::{Sym2, Sym3, mat_vec};

/// Relative error bound on μ² above which the coefficients are recomputed in double-double.
///
/// The bound is a worst case: on 20 000 pairs of the bench's distribution (aspect ratios up to
/// 10) the actual error never exceeded 0.26 × the bound, and stayed below 4e-15 wherever the
/// bound was below this threshold, while 1.5 % of the pairs were refined (at 1e-14, 38 % would
/// be). See the `calibration` test.
pub const REFINE_ABOVE: f64 = 1e-13;

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

multiversion! {
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
    pub fn contact_function(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<Contact, Error>
        => contact_function_portable;
}

#[inline(always)]
fn contact_function_portable(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<Contact, Error> {
    Ok(Prepared::new(r12, q1, q2)?.contact(|| crate::poly::coefficients::<Dd>(r12, q1, q2)))
}

/// [`contact_function`] with the coefficients always recomputed in double-double arithmetic
/// (about 32 significant digits), whatever the error bound says: a reference for checking the
/// fast path on random input, at about twice its cost. Its `error_estimate` bounds the
/// remaining error (below 1e-15 unless the pencil is singular to about 1e-16).
///
/// # Errors
/// As [`contact_function`].
pub fn contact_function_refined(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<Contact, Error> {
    let prepared = Prepared::new(r12, q1, q2)?;
    Ok(match prepared.normalised() {
        Some((scale, _)) => prepared.refine(|| crate::poly::coefficients::<Dd>(r12, q1, q2), scale),
        None => Contact::COINCIDENT,
    })
}

/// A validated pair with its `f64` Bernstein coefficients and their error bound: everything
/// before the λ iteration, shared by the scalar and the batched paths.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Prepared {
    /// The Bernstein coefficients, as computed in `f64`.
    pub rational: RationalForm,
    /// Σ|terms| of each coefficient: γ times this bounds its rounding error.
    pub bound: RationalForm,
}

impl Prepared {
    #[inline(always)]
    pub(crate) fn new(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<Self, Error> {
        check_inputs_finite(r12, q1, q2)?;
        // The coefficients and their error bound in one pass (two SIMD lanes).
        let c = crate::poly::coefficients::<ValMag>(r12, q1, q2);
        let value = |x: &ValMag| x.0[0];
        let magnitude = |x: &ValMag| x.0[1];
        let (beta, beta_bound) = (c.beta.map(|x| value(&x)), c.beta.map(|x| magnitude(&x)));
        check_positive_definite(Argument::Q1, q1, beta[0], beta_bound[0])?;
        check_positive_definite(Argument::Q2, q2, beta[3], beta_bound[3])?;
        Ok(Self {
            rational: RationalForm {
                alpha: c.alpha.map(|x| value(&x)),
                beta,
            },
            bound: RationalForm {
                alpha: c.alpha.map(|x| magnitude(&x)),
                beta: beta_bound,
            },
        })
    }

    #[inline(always)]
    pub(crate) fn new_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<Self, Error> {
        check_finite(Argument::R12, r12)?;
        check_finite(Argument::Q1, q1)?;
        check_finite(Argument::Q2, q2)?;
        check_positive_definite_2d(Argument::Q1, q1)?;
        check_positive_definite_2d(Argument::Q2, q2)?;
        Ok(Self {
            rational: coefficients_2d::<f64>(r12, q1, q2).to_f64(),
            bound: coefficients_2d::<Mag>(r12, q1, q2).to_f64(),
        })
    }

    /// Solves, checks the error bound and refines when needed: the whole contact function
    /// after validation.
    #[inline(always)]
    pub(crate) fn contact(&self, exact: impl FnOnce() -> Coefficients<Dd>) -> Contact {
        match self.normalised() {
            Some((scale, form)) => self.finish(scale, solve(&form), exact),
            None => Contact::COINCIDENT,
        }
    }

    /// The normalised form to solve, or `None` when r12 = 0 (f ≡ 0).
    #[inline(always)]
    pub(crate) fn normalised(&self) -> Option<(Scale, RationalForm)> {
        Scale::of(&self.rational).map(|s| (s, s.apply(&self.rational)))
    }

    /// μ² from the solution, after checking the error bound and, when it is too large,
    /// re-solving with the double-double coefficients from `exact`.
    #[inline(always)]
    pub(crate) fn finish(
        &self,
        scale: Scale,
        solution: Solution,
        exact: impl FnOnce() -> Coefficients<Dd>,
    ) -> Contact {
        let estimate = GAMMA_F64 * solution.amplification(&self.bound, scale) + EVAL;
        if estimate <= REFINE_ABOVE {
            return scale.contact(&solution, estimate, false);
        }
        self.refine(exact, scale)
    }

    /// The rare path: re-solve with double-double coefficients. Kept out of line so that the
    /// common path stays small.
    #[cold]
    #[inline(never)]
    fn refine(&self, exact: impl FnOnce() -> Coefficients<Dd>, fallback: Scale) -> Contact {
        let refined = exact().to_f64();
        let scale = Scale::of(&refined).unwrap_or(fallback);
        let solution = solve(&scale.apply(&refined));
        let estimate = GAMMA_DD * solution.amplification(&self.bound, scale) + EVAL;
        scale.contact(&solution, estimate, true)
    }
}

impl Contact {
    /// The contact of coincident centres (r12 = 0): f ≡ 0, every λ is a maximiser.
    pub(crate) const COINCIDENT: Contact = Contact {
        mu2: 0.0,
        lambda: 0.5,
        error_estimate: 0.0,
        refined: false,
    };
}

multiversion! {
    /// The contact function of two ellipses: `r12` ∈ ℝ², `q1`, `q2` stored as Q11, Q12, Q22.
    /// Same definition, conventions and errors as [`contact_function`] (the PW85 library has no 2D
    /// version).
    pub fn contact_function_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<Contact, Error>
        => contact_function_2d_portable;
}

#[inline(always)]
fn contact_function_2d_portable(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<Contact, Error> {
    Ok(Prepared::new_2d(r12, q1, q2)?.contact(|| coefficients_2d::<Dd>(r12, q1, q2)))
}

/// μ², λ₀, the contact point, the common normal and the gradients of μ² (see
/// [`ContactDetails`]). Costs one contact function and a 3×3 matrix–vector product.
///
/// # Errors
/// As [`contact_function`].
pub fn contact_details(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<ContactDetails, Error> {
    let contact =
        Prepared::new(r12, q1, q2)?.contact(|| crate::poly::coefficients::<Dd>(r12, q1, q2));
    let p = pencil3::<f64>(r12, q1, q2);
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
    // b(λ) = det Q(λ) from the same pieces: det is linear in each row, so the cofactor
    // expansion of Q(λ) against its own adjugate gives it.
    let q: Sym3 = core::array::from_fn(|k| s * q1[k] + t * q2[k]);
    let b = q[0] * adj[0] + q[1] * adj[1] + q[2] * adj[2];
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

/// Relative rounding error of evaluating f from exact non-negative Bernstein coefficients
/// (a handful of operations, each within u = 2⁻⁵³).
const EVAL: f64 = 8.0 * 0.5 * f64::EPSILON;

/// The normalisation that keeps the solver's arithmetic away from overflow: α and β are
/// divided by their largest entries, and μ² is scaled back at the end.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scale {
    alpha: f64,
    beta: f64,
}

/// The maximiser found by [`solve`], with a(λ₀) and b(λ₀) of the normalised form.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Solution {
    pub lambda: f64,
    pub f: f64,
    pub a: f64,
    pub b: f64,
}

impl Solution {
    /// Σ|terms| / value for a and b at λ₀, added: how much a relative error of the
    /// coefficients (measured against `bound`, their Σ|terms|, unnormalised) is amplified in f.
    fn amplification(&self, bound: &RationalForm, scale: Scale) -> f64 {
        bound.a(self.lambda) / (self.a * scale.alpha) + bound.b(self.lambda) / (self.b * scale.beta)
    }
}

/// The maximiser of a normalised rational form (coefficients non-negative, not all zero).
#[inline(always)]
pub(crate) fn solve(r: &RationalForm) -> Solution {
    let (form, mut search, reversed) = start(r);
    while !search.done {
        form.search_step(&mut search);
    }
    Solution::of(&form, &search, reversed)
}

/// Where to start: solve in whichever of λ and 1 − λ is small at the maximiser, so that it
/// keeps its relative precision (λ₀ = 1 − 1e-12 is not representable to better than 1e-4
/// relative in its distance to 1).
#[inline(always)]
pub(crate) fn start(r: &RationalForm) -> (RationalForm, Search, bool) {
    let t0 = r.initial_guess();
    if t0 > 0.5 {
        (r.reversed(), Search::new(1.0 - t0), true)
    } else {
        (*r, Search::new(t0), false)
    }
}

impl Solution {
    #[inline(always)]
    pub(crate) fn of(form: &RationalForm, search: &Search, reversed: bool) -> Self {
        let t = search.t;
        Solution {
            lambda: if reversed { 1.0 - t } else { t },
            f: search.f,
            a: form.a(t),
            b: form.b(t),
        }
    }
}

impl Scale {
    /// Powers of two near the largest α and β: multiplying by their reciprocals is exact, so
    /// normalising changes no digit, and costs no division.
    #[inline(always)]
    pub(crate) fn of(r: &RationalForm) -> Option<Self> {
        let alpha = r.alpha.iter().fold(0.0_f64, |m, &x| m.max(x));
        let beta = r.beta.iter().fold(0.0_f64, |m, &x| m.max(x));
        (alpha > 0.0 && beta > 0.0).then(|| Self {
            alpha: power_of_two_below(alpha),
            beta: power_of_two_below(beta),
        })
    }

    #[inline(always)]
    pub(crate) fn apply(&self, r: &RationalForm) -> RationalForm {
        // Mixed coefficients are non-negative in exact arithmetic; rounding may leave a tiny
        // negative value, which the error bound accounts for.
        let (ia, ib) = (1.0 / self.alpha, 1.0 / self.beta);
        RationalForm {
            alpha: r.alpha.map(|x| (x * ia).max(0.0)),
            beta: r.beta.map(|x| (x * ib).max(0.0)),
        }
    }

    #[inline(always)]
    fn contact(&self, s: &Solution, error_estimate: f64, refined: bool) -> Contact {
        Contact {
            mu2: s.f * (self.alpha / self.beta),
            lambda: s.lambda,
            error_estimate,
            refined,
        }
    }
}

/// The largest power of two ≤ x, for positive finite x; x itself for subnormal or huge x (where
/// the reciprocal of the power would not be representable), which only costs exactness of the
/// normalisation there.
#[inline(always)]
fn power_of_two_below(x: f64) -> f64 {
    let exponent = (x.to_bits() >> 52) & 0x7ff;
    if (1..2046).contains(&exponent) {
        f64::from_bits(exponent << 52)
    } else {
        x
    }
}

/// All fifteen inputs finite, checked in one pass (x − x is NaN exactly for NaN and ±∞); the
/// slow search for the culprit runs only when the check fails.
#[inline(always)]
pub(crate) fn check_inputs_finite(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<(), Error> {
    #[allow(clippy::eq_op)] // x − x is the point: NaN for NaN and ±∞, 0 otherwise.
    let probe = r12
        .iter()
        .chain(q1)
        .chain(q2)
        .fold(0.0, |acc, &x| acc + (x - x));
    if probe == 0.0 {
        return Ok(());
    }
    check_finite(Argument::R12, r12)?;
    check_finite(Argument::Q1, q1)?;
    check_finite(Argument::Q2, q2)
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
/// (a needle of aspect ratio 1e4 has det Q ≈ 1e-16 from entries of order 1). `det_magnitude`
/// is Σ|terms| of the determinant, as computed by the `Mag` arithmetic.
#[inline(always)]
pub(crate) fn check_positive_definite(
    argument: Argument,
    q: &Sym3,
    det: f64,
    det_magnitude: f64,
) -> Result<(), Error> {
    let fail = |minor, value| {
        Err(Error::NotPositiveDefinite {
            argument,
            minor,
            value,
        })
    };
    if !is_positive(q[0]) {
        return fail(1, q[0]);
    }
    let m2 = q[0] * q[3] - q[1] * q[1];
    if m2 <= GAMMA_F64 * (q[0] * q[3] + q[1] * q[1]) {
        let exact = (Dd::lift(q[0]) * Dd::lift(q[3]) - Dd::lift(q[1]) * Dd::lift(q[1])).to_f64();
        if !is_positive(exact) {
            return fail(2, exact);
        }
    }
    if det <= GAMMA_F64 * det_magnitude {
        let qd = crate::sym::lift6::<Dd>(q);
        let exact = crate::sym::det_generic(&qd, &crate::sym::adjugate_generic(&qd)).to_f64();
        if !is_positive(exact) {
            return fail(3, exact);
        }
    }
    Ok(())
}

/// Sylvester's criterion for a symmetric 2×2 matrix.
pub(crate) fn check_positive_definite_2d(argument: Argument, q: &Sym2) -> Result<(), Error> {
    if !is_positive(q[0]) {
        return Err(Error::NotPositiveDefinite {
            argument,
            minor: 1,
            value: q[0],
        });
    }
    let det = (Dd::lift(q[0]) * Dd::lift(q[2]) - Dd::lift(q[1]) * Dd::lift(q[1])).to_f64();
    if !is_positive(det) {
        return Err(Error::NotPositiveDefinite {
            argument,
            minor: 2,
            value: det,
        });
    }
    Ok(())
}

#[cfg(test)]
mod calibration {
    use super::*;
    use crate::poly::coefficients;

    /// Prints how the running error bound compares with the error actually made by the `f64`
    /// coefficients (against the double-double ones) on the bench's distribution of pairs.
    #[test]
    fn bound_versus_actual_error() {
        let mut state = 12345u64;
        let mut next = move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut rows = Vec::new();
        for _ in 0..20000 {
            let mut ell = |decades: f64| {
                let u = next();
                let s = 2f64.powf(2.0 * next() - 1.0);
                let thin = s * 10f64.powf(-decades * u);
                let q: [f64; 4] = core::array::from_fn(|_| 2.0 * next() - 1.0);
                crate::shape::from_axes_quaternion(&[s, thin, thin], &q).unwrap()
            };
            let (q1, q2) = (ell(1.0), ell(1.0));
            let r = [next() - 0.5, next() - 0.5, next() - 0.5];
            let fast = coefficients::<f64>(&r, &q1, &q2).to_f64();
            let scale = Scale::of(&fast).unwrap();
            let s1 = solve(&scale.apply(&fast));
            let bound = coefficients::<Mag>(&r, &q1, &q2).to_f64();
            let est = GAMMA_F64 * s1.amplification(&bound, scale) + EVAL;
            let exact = coefficients::<Dd>(&r, &q1, &q2).to_f64();
            let scale2 = Scale::of(&exact).unwrap();
            let s2 = solve(&scale2.apply(&exact));
            let (m1, m2) = (
                scale.contact(&s1, 0.0, false).mu2,
                scale2.contact(&s2, 0.0, true).mu2,
            );
            rows.push((est, ((m1 - m2) / m2).abs()));
        }
        for threshold in [1e-14, 3e-14, 1e-13, 3e-13, 1e-12] {
            let above = rows.iter().filter(|r| r.0 > threshold).count();
            let worst = rows
                .iter()
                .filter(|r| r.0 <= threshold)
                .fold(0.0_f64, |m, r| m.max(r.1));
            println!(
                "threshold {threshold:.0e}: {above:5} of {} refined, worst unrefined actual \
                 error {worst:.2e}",
                rows.len()
            );
        }
        let ratio = rows.iter().map(|r| r.1 / r.0).fold(0.0_f64, f64::max);
        println!("largest actual/bound ratio {ratio:.3}");
        // The bound is a bound, and below the refinement threshold the promise holds.
        assert!(ratio <= 1.0, "actual error exceeded the bound by {ratio}");
        let worst_unrefined = rows
            .iter()
            .filter(|r| r.0 <= REFINE_ABOVE)
            .fold(0.0_f64, |m, r| m.max(r.1));
        assert!(worst_unrefined <= 1e-13);
    }
}
