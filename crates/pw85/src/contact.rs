//! The contact function μ² = max over 0 ≤ λ ≤ 1 of f(λ) (theory eq. 6), its maximiser λ₀, the
//! contact point x₀(λ₀) (eq. 9), the common normal, and the gradient of μ².
//!
//! # Algorithm
//! 1. The Bernstein coefficients of a(λ) and b(λ) (eq. 16, see [`crate::poly`]) are computed
//!    in `f64`, together with a running bound on their rounding error (every term replaced by
//!    its absolute value), the formulas of both ends of the pencil side by side in one
//!    four-lane pass ([`crate::lanes::Ends4`]).
//! 2. λ₀ is found in the odds u = λ / (1 − λ), as the positive root of the degree-6 polynomial
//!    p(u), the numerator c(λ) of f′ (eqs. 18–20) in that variable ([`OddsForm`]): a bracketed
//!    Halley iteration on p / (A B), started from the exact maximiser for two spheres of the
//!    ellipsoids' radial extents along r12 (2.5 evaluations on average, one division each).
//!    When the start is above u = 1 the problem is solved for 1 − λ (coefficients reversed),
//!    so that a maximiser close to 1 keeps its relative precision. Pencils whose polynomials
//!    span too many decades fall back to the bracketed Newton iteration in λ itself
//!    ([`RationalForm::maximise`]).
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

use crate::arith::{Arith, Dd, DdT, Mag};
use crate::arith::{is_positive, select_gt, select_sign};
use crate::error::{Argument, Error};
use crate::poly::{Coefficients, OddsForm, OddsSearch, RationalForm, Search, coefficients_2d};
use crate::sym::{Sym2, Sym3};
use simd::multiversion;

/// Relative error bound on μ² above which the coefficients are recomputed in double-double.
///
/// The bound is a worst case, so the threshold trades refinements (each costs more than an
/// ordinary call) against the error left unrefined: the `calibration` test prints, on
/// 20 000 pairs of the bench's distribution, how many pairs each threshold refines and the
/// worst actual error it leaves, and asserts that the actual error never exceeds the bound.
pub const REFINE_ABOVE: f64 = 1e-13;

/// Rounding-error factor γ of the coefficient formulas: their expression trees are at most
/// about ten operations deep, so |computed − exact| ≤ 10 u Σ|terms| (u = 2⁻⁵³), and ≈ 10 u_dd
/// in double-double (u_dd = 2⁻¹⁰⁴).
const GAMMA_F64: f64 = 10.0 * f64::EPSILON * 0.5;

/// The error bound that decides refinement counts the roundings of each coefficient's own
/// expression tree instead of the common [`GAMMA_F64`]: a computed sum of products is
/// Σ terms · ∏(1 + δᵢ) over the nᵢ roundings on each term's path, so its error is at most
/// γₙ Σ|terms| with γₙ = n u / (1 − n u) and n the deepest path (Higham, *Accuracy and
/// Stability*, §3.1, 3.4). In [`crate::poly::pencil3`]: x xᵀ 1 rounding, an adjugate entry 2
/// (product, difference), a mixed-adjugate entry 3 (product, sum, difference), the product
/// with the other factor 1, and the sums of the determinant 2 and of a quadratic form or
/// trace 3. Hence α₀, α₂ = r12ᵀ adj Qᵢ r12: 1 + 2 + 1 + 3 = 7; α₁ = r12ᵀ M r12: 1 + 3 + 1 + 3
/// = 8; β₀, β₃ = det Qᵢ: 2 + 1 + 2 = 5; β₁, β₂ = tr(adj Qᵢ Qⱼ): 2 + 1 + 3 = 6. The ellipses'
/// coefficients ([`crate::poly::coefficients_2d`], degree-elevated) are at most 5 (α₁; α₀ and
/// α₂ 4) and 4 (β) deep, within these.
const DEPTH_ALPHA: [f64; 3] = [7.0, 8.0, 7.0];
const DEPTH_BETA: [f64; 4] = [5.0, 6.0, 6.0, 5.0];

/// u = 2⁻⁵³ with a safety factor covering γₙ / (n u) − 1 ≤ 1e-15, the rounding of the
/// computed Σ|terms| (a sum of non-negative terms, at most 8 roundings deep) and of the
/// amplification's own evaluation.
const UNIT_ROUNDOFF: f64 = 0.5 * f64::EPSILON * (1.0 + 1e-6);
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

/// [`contact_function`](crate::contact_function) on two ellipsoids.
#[inline]
pub(crate) fn contact_function_3d(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<Contact, Error> {
    contact_function_dispatched(r12, q1, q2, true)
}

multiversion! {
    /// [`contact_function`](crate::contact_function), with (`rescue`) or without the rescue of pairs outside the fast
    /// path's window: [`crate::extreme`] runs the kernel without it on the rescaled pair. One
    /// dispatched function for both, so that a rescaled pair gives the same bits, and so that
    /// the kernel is compiled once (a second copy changed the optimiser's inlining decisions
    /// in the first).
    pub(crate) fn contact_function_dispatched(r12: &[f64; 3], q1: &Sym3, q2: &Sym3, rescue: bool) -> Result<Contact, Error>
        => fused contact_function_portable;
}

#[inline(always)]
pub(crate) fn contact_function_portable<const FMA: bool>(
    r12: &[f64; 3],
    q1: &Sym3,
    q2: &Sym3,
    rescue: bool,
) -> Result<Contact, Error> {
    if !check_inputs_finite::<FMA>(r12, q1, q2)? && rescue {
        return crate::extreme::contact_function(r12, q1, q2);
    }
    match Prepared::new::<FMA>(r12, q1, q2) {
        Ok(prepared) => prepared.contact::<FMA>(
            || exact_coefficients(r12, q1, q2),
            || {
                rescue
                    .then(|| crate::extreme::rescue(r12, q1, q2))
                    .flatten()
            },
        ),
        Err(e) if rescue => {
            crate::extreme::after_error(e, || crate::extreme::contact_function(r12, q1, q2))
        }
        Err(e) => Err(e),
    }
}

/// [`contact_function`](crate::contact_function) without the rescue of pairs outside the window.
#[inline]
pub(crate) fn contact_function_unrescued(
    r12: &[f64; 3],
    q1: &Sym3,
    q2: &Sym3,
) -> Result<Contact, Error> {
    contact_function_dispatched(r12, q1, q2, false)
}

multiversion! {
    /// The Bernstein coefficients computed in double-double arithmetic and rounded: the
    /// refinement's input (in its own dispatched function so that the exact products use the
    /// hardware FMA, as the refinement itself is kept out of line).
    pub(crate) fn exact_coefficients(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> RationalForm
        => fused exact_coefficients_portable;
}

#[inline(always)]
fn exact_coefficients_portable<const FMA: bool>(
    r12: &[f64; 3],
    q1: &Sym3,
    q2: &Sym3,
) -> RationalForm {
    crate::poly::coefficients::<DdT<FMA>>(r12, q1, q2).to_f64()
}

/// The ellipses' Bernstein coefficients computed in double-double arithmetic and rounded: the
/// 2D refinement's input (the twin of [`exact_coefficients`]).
pub(crate) fn exact_coefficients_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> RationalForm {
    coefficients_2d::<Dd>(r12, q1, q2).to_f64()
}

/// [`contact_function`](crate::contact_function) with the coefficients always recomputed in double-double arithmetic
/// (about 32 significant digits), whatever the error bound says: a reference for checking the
/// fast path on random input, at about twice its cost. Its `error_estimate` bounds the
/// remaining error (below 1e-15 unless the pencil is singular to about 1e-16).
///
/// # Errors
/// As [`contact_function`](crate::contact_function).
pub fn contact_function_refined(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<Contact, Error> {
    check_inputs_finite::<false>(r12, q1, q2)?;
    if crate::extreme::within_window(r12, q1, q2) {
        contact_function_refined_unrescued(r12, q1, q2)
    } else {
        crate::extreme::contact_function_refined(r12, q1, q2)
    }
}

/// [`contact_function_refined`] without the rescue of pairs outside the window.
pub(crate) fn contact_function_refined_unrescued(
    r12: &[f64; 3],
    q1: &Sym3,
    q2: &Sym3,
) -> Result<Contact, Error> {
    check_inputs_finite::<false>(r12, q1, q2)?;
    let prepared = Prepared::new::<false>(r12, q1, q2)?;
    Ok(match Scale::of(&prepared.rational) {
        Some(scale) => refine::<false>(&prepared, || exact_coefficients(r12, q1, q2), scale),
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
    /// The estimate of the relative error of μ² from the depth-weighted amplification of the
    /// coefficients' rounding errors (see [`Solution::weighted_amplification`]).
    #[inline(always)]
    pub(crate) fn estimate(weighted_amplification: f64) -> f64 {
        UNIT_ROUNDOFF * weighted_amplification + EVAL
    }

    /// Whether the estimate from the amplification x / d exceeds [`REFINE_ABOVE`], decided
    /// without the division: u x / d + EVAL > REFINE_ABOVE ⇔ u x > (REFINE_ABOVE − EVAL) d
    /// for d > 0. The division that gives the estimate itself is then off the path to the
    /// decision: at the end of every call, where the divisions of μ², λ and the estimate
    /// queue for the one divider (one division fewer there shows in the bench `contact`). A
    /// NaN fails the test, so it refines.
    #[inline(always)]
    pub(crate) fn needs_refinement((x, d): (f64, f64)) -> bool {
        use core::cmp::Ordering::{Equal, Less};
        let within = (UNIT_ROUNDOFF * x).partial_cmp(&((REFINE_ABOVE - EVAL) * d));
        !matches!(within, Some(Less | Equal))
    }

    /// Validates (the inputs' finiteness is the caller's) and computes the coefficients; `FMA` says whether this is the AVX2 + FMA
    /// build of a dispatched function (which selects the vector-register form of the
    /// four-lane pass, [`crate::lanes::Ends4Avx`]).
    #[inline(always)]
    pub(crate) fn new<const FMA: bool>(
        r12: &[f64; 3],
        q1: &Sym3,
        q2: &Sym3,
    ) -> Result<Self, Error> {
        // The coefficients and their error bound in one pass (four SIMD lanes).
        #[cfg(target_arch = "x86_64")]
        let (rational, bound) = if FMA {
            crate::lanes::coefficients_with_bound::<crate::lanes::Ends4Avx>(r12, q1, q2)
        } else {
            crate::lanes::coefficients_with_bound::<crate::lanes::Ends4>(r12, q1, q2)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let (rational, bound) =
            crate::lanes::coefficients_with_bound::<crate::lanes::Ends4>(r12, q1, q2);
        let (beta, beta_bound) = (rational.beta, bound.beta);
        check_positive_definite(Argument::Q1, q1, beta[0], beta_bound[0])?;
        check_positive_definite(Argument::Q2, q2, beta[3], beta_bound[3])?;
        Ok(Self { rational, bound })
    }

    /// The ellipses' twin of [`Prepared::new`] (the inputs' finiteness is the caller's).
    #[inline(always)]
    pub(crate) fn new_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<Self, Error> {
        check_positive_definite_2d(Argument::Q1, q1)?;
        check_positive_definite_2d(Argument::Q2, q2)?;
        Ok(Self {
            rational: coefficients_2d::<f64>(r12, q1, q2).to_f64(),
            bound: coefficients_2d::<Mag>(r12, q1, q2).to_f64(),
        })
    }

    /// Solves, checks the error bound and refines when needed: the whole contact function
    /// after validation.
    ///
    /// The normalisation ([`Scale`]) only keeps the solver away from overflow and underflow:
    /// dividing α and β by powers of two changes no bit of the result, since every operation
    /// of the solver scales exactly and μ² is scaled back. So where the powers are moderate
    /// ([`Scale::moderate`]) the form is solved as it is, with the fallback thresholds
    /// scaled instead, and the normalisation (the largest coefficients, their exponents)
    /// only decides a branch: it leaves the dependency chain between the coefficients and
    /// the first iterate.
    ///
    /// Returns the `Result` itself, built where it is returned: the rare paths are
    /// functions of their own, so that the common one writes its fields once. Merging a
    /// `Contact` from several paths made the compiler assemble it on the stack and copy it
    /// with a 16-byte load across two 8-byte stores, which store forwarding cannot serve
    /// (the load waits until the stores have retired and reached the cache).
    #[inline(always)]
    ///
    /// `rescue` is asked where the coefficients may have under- or overflowed (no scale, or
    /// one far from 1): `Some` answer from [`crate::extreme`] when the inputs lie outside the
    /// window where the coefficients are exact, `None` when the answer here stands.
    pub(crate) fn contact<const FMA: bool>(
        &self,
        exact: impl FnOnce() -> RationalForm,
        rescue: impl FnOnce() -> Option<Result<Contact, Error>>,
    ) -> Result<Contact, Error> {
        let Some(scale) = Scale::of(&self.rational) else {
            return rescue().unwrap_or(Ok(Contact::COINCIDENT));
        };
        let Some(tiny) = scale.moderate() else {
            if let Some(rescued) = rescue() {
                return rescued;
            }
            return normalised_contact::<FMA>(self, scale, exact);
        };
        let Some(solution) = solve_odds::<FMA>(&Scale::UNIT.apply(&self.rational), tiny) else {
            return lambda_contact::<FMA>(self, scale, exact);
        };
        let (x, d) = solution.weighted_amplification::<FMA>(&self.bound, Scale::UNIT);
        if Self::needs_refinement((x, d)) {
            return Ok(refine::<FMA>(self, exact, scale));
        }
        Ok(Scale::UNIT.contact(&solution, Self::estimate(x / d), false))
    }

    /// μ² from the solution, after checking the error bound and, when it is too large,
    /// re-solving with the double-double coefficients from `exact`.
    #[inline(always)]
    pub(crate) fn finish<const FMA: bool>(
        &self,
        scale: Scale,
        solution: Solution,
        exact: impl FnOnce() -> RationalForm,
    ) -> Contact {
        let (x, d) = solution.weighted_amplification::<FMA>(&self.bound, scale);
        if Self::needs_refinement((x, d)) {
            return refine::<FMA>(self, exact, scale);
        }
        scale.contact(&solution, Self::estimate(x / d), false)
    }
}

multiversion! {
    /// [`Prepared::contact`] on the normalised form, for pairs whose coefficients are too
    /// large or too small to be solved as they are (ellipsoids a million times smaller or
    /// larger than unit size, say).
    fn normalised_contact(
        prepared: &Prepared,
        scale: Scale,
        exact: impl FnOnce() -> RationalForm,
    ) -> Result<Contact, Error> => out_of_line normalised_contact_in;
}

#[inline(always)]
fn normalised_contact_in<const FMA: bool>(
    prepared: &Prepared,
    scale: Scale,
    exact: impl FnOnce() -> RationalForm,
) -> Result<Contact, Error> {
    let solution = solve::<FMA>(&scale.apply(&prepared.rational));
    Ok(prepared.finish::<FMA>(scale, solution, exact))
}

multiversion! {
    /// [`Prepared::contact`] where the odds iteration gave up: the λ iteration on the
    /// normalised form.
    #[cold]
    fn lambda_contact(
        prepared: &Prepared,
        scale: Scale,
        exact: impl FnOnce() -> RationalForm,
    ) -> Result<Contact, Error> => out_of_line lambda_contact_in;
}

#[inline(always)]
fn lambda_contact_in<const FMA: bool>(
    prepared: &Prepared,
    scale: Scale,
    exact: impl FnOnce() -> RationalForm,
) -> Result<Contact, Error> {
    let solution = solve_lambda(&scale.apply(&prepared.rational));
    Ok(prepared.finish::<FMA>(scale, solution, exact))
}

multiversion! {
    /// The rare path: re-solve with double-double coefficients. Kept out of line so that the
    /// common path stays small.
    #[cold]
    pub(crate) fn refine(
        prepared: &Prepared,
        exact: impl FnOnce() -> RationalForm,
        fallback: Scale,
    ) -> Contact => out_of_line refine_in;
}

#[inline(always)]
fn refine_in<const FMA: bool>(
    prepared: &Prepared,
    exact: impl FnOnce() -> RationalForm,
    fallback: Scale,
) -> Contact {
    let refined = exact();
    let scale = Scale::of(&refined).unwrap_or(fallback);
    let solution = solve::<FMA>(&scale.apply(&refined));
    let estimate = GAMMA_DD * solution.amplification(&prepared.bound, scale) + EVAL;
    scale.contact(&solution, estimate, true)
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
    /// Same definition, conventions and errors as [`contact_function`](crate::contact_function) (the PW85 library has no 2D
    /// version).
    pub(crate) fn contact_function_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<Contact, Error>
        => fused contact_function_2d_portable;
}

#[inline(always)]
pub(crate) fn contact_function_2d_portable<const FMA: bool>(
    r12: &[f64; 2],
    q1: &Sym2,
    q2: &Sym2,
) -> Result<Contact, Error> {
    if !inputs_finite_2d(r12, q1, q2)? {
        return crate::extreme::contact_function_2d(r12, q1, q2);
    }
    match Prepared::new_2d(r12, q1, q2) {
        Ok(prepared) => prepared.contact::<FMA>(
            || exact_coefficients_2d(r12, q1, q2),
            || crate::extreme::rescue_2d(r12, q1, q2),
        ),
        Err(e) => {
            crate::extreme::after_error(e, || crate::extreme::contact_function_2d(r12, q1, q2))
        }
    }
}

multiversion! {
    /// [`contact_function_2d`] without the rescue of pairs outside the window (see
    /// [`contact_function_unrescued`]).
    pub(crate) fn contact_function_2d_unrescued(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<Contact, Error>
        => fused contact_function_2d_unrescued_portable;
}

#[inline(always)]
fn contact_function_2d_unrescued_portable<const FMA: bool>(
    r12: &[f64; 2],
    q1: &Sym2,
    q2: &Sym2,
) -> Result<Contact, Error> {
    inputs_finite_2d(r12, q1, q2)?;
    Prepared::new_2d(r12, q1, q2)?.contact::<FMA>(|| exact_coefficients_2d(r12, q1, q2), || None)
}

/// The ellipses' twin of [`check_inputs_finite`]: `Ok(true)` inside the fast path's window,
/// `Ok(false)` for finite entries beyond it, the typed error for NaN or ±∞.
#[inline(always)]
pub(crate) fn inputs_finite_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<bool, Error> {
    #[allow(clippy::eq_op)] // x·P − x·P: NaN for NaN, ±∞ and entries beyond the window.
    let d = |x: f64| {
        let y = x * crate::extreme::PROBE;
        y - y
    };
    if (d(r12[0]) + d(q1[0]) + d(q2[0])) + (d(r12[1]) + d(q1[1]) + d(q2[1])) + (d(q1[2]) + d(q2[2]))
        == 0.0
    {
        return Ok(true);
    }
    check_finite(Argument::R12, r12)?;
    check_finite(Argument::Q1, q1)?;
    check_finite(Argument::Q2, q2)?;
    Ok(false)
}

/// The function whose maximum over λ is μ² (theory eqs. 10–11):
///
/// ```text
/// f(λ) = λ (1 − λ) r12ᵀ Q(λ)⁻¹ r12,   Q(λ) = (1 − λ) Q1 + λ Q2,   0 ≤ λ ≤ 1,
/// ```
///
/// evaluated from the Bernstein form of its numerator and denominator (eqs. 15–16), a sum of
/// non-negative terms. The cancellation sits in the seven coefficients (needles, pancakes,
/// very different sizes): their running error bound, carried to a(λ) and b(λ), decides
/// whether the `f64` coefficients are good to 1e-14 relative in f; otherwise they are
/// recomputed in double-double arithmetic, as [`contact_function`](crate::contact_function) does. The relative error
/// is then a few units in the last place (the reference file `pw85_objective.csv`: below
/// 1e-15 on needles, pancakes and size ratios up to 1e8). The PW85 library's `f_neg` is −f.
///
/// # Errors
/// As [`contact_function`](crate::contact_function), and [`Error::LambdaOutOfRange`] unless 0 ≤ λ ≤ 1.
///
/// # Example
/// ```
/// // Two unit spheres 3 apart: f(λ) = λ (1 − λ) · 9, largest at λ = ½.
/// let q = [1.0, 0.0, 0.0, 1.0, 0.0, 1.0];
/// let f = pw85::objective(0.25, &[3.0, 0.0, 0.0], &q, &q)?;
/// assert!((f - 0.25 * 0.75 * 9.0).abs() < 1e-15);
/// # Ok::<(), pw85::Error>(())
/// ```
pub fn objective(lambda: f64, r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<f64, Error> {
    if !(0.0..=1.0).contains(&lambda) {
        return Err(Error::LambdaOutOfRange { value: lambda });
    }
    check_finite(Argument::R12, r12)?;
    check_finite(Argument::Q1, q1)?;
    check_finite(Argument::Q2, q2)?;
    crate::extreme::check_positive_definite_balanced(Argument::Q1, q1)?;
    crate::extreme::check_positive_definite_balanced(Argument::Q2, q2)?;
    let (r, a, b) = crate::extreme::uniformly_rescaled(r12, q1, q2);
    // The coefficients with the bound of their rounding error (Σ|terms|, depth-weighted
    // below), in one pass as in `contact_function`; relative to a(λ) and b(λ), which are sums
    // of non-negative Bernstein terms, the bound gives at most u times `amplified` in f.
    // NaN (a = 0 from r12 = 0, or a coefficient rounded below zero) fails the test and
    // refines.
    let (fast, bound) = crate::lanes::coefficients_with_bound::<crate::lanes::Ends4>(&r, &a, &b);
    let (alpha_bound, beta_bound) = depth_weighted(&bound.alpha, &bound.beta);
    let [value_a, _, _, value_b, _, _] =
        crate::poly::pencil_values(&fast.alpha, &fast.beta, lambda);
    let amplified = amplification(
        &alpha_bound,
        &beta_bound,
        [lambda, value_a, value_b, 1.0, 1.0],
    );
    if UNIT_ROUNDOFF * amplified <= OBJECTIVE_REFINE_ABOVE {
        Ok(fast.f(lambda))
    } else {
        Ok(exact_coefficients(&r, &a, &b).f(lambda))
    }
}

/// Bound on the relative error that the `f64` coefficients may bring into [`objective`]
/// before they are recomputed in double-double: with the evaluation's own few units in the
/// last place, an unrefined f is within about 1.1e-14 of the exact one. An ordinary pair
/// (Σ|terms| within a few times the value) stays below it; the double-double coefficients
/// cost about twice the `f64` ones.
const OBJECTIVE_REFINE_ABOVE: f64 = 1e-14;

/// μ², λ₀, the contact point, the common normal and the gradients of μ² (see
/// [`ContactDetails`]).
///
/// μ² and λ₀ are [`contact_function`](crate::contact_function)'s, bit for bit. The rest is computed in double-double
/// arithmetic (about 32 digits), because two steps lose digits on stiff pairs:
///
/// 1. λ₀ itself: [`contact_function`](crate::contact_function) returns it to a few 1e-13 absolute on stiff pairs (μ² is
///    stationary there, eq. 12, so it does not need more), but x₀(λ) of eq. 9 moves with λ.
///    One to three Newton steps on the numerator p(u) of f′ (eqs. 18–20 in the odds
///    u = λ / (1 − λ), or in 1/u when λ₀ > ½ so that 1 − λ₀ keeps its relative precision),
///    with the coefficients in double-double, give (1 − λ₀, λ₀) to a few units in the last
///    place.
/// 2. Q(λ₀)⁻¹ r12 = adj Q(λ₀) r12 / det Q(λ₀) (eqs. 9–10) and Q1 Q(λ₀)⁻¹ r12: the adjugate,
///    determinant and products of a needle's or pancake's Q(λ) cancel by up to its squared
///    aspect ratio, in double-double still far below the last place.
///
/// On the reference file `pw85_details.csv` (needles, pancakes, upstream PW85's needle grid,
/// size ratios up to 1e8) the point, the normal and ∂μ²/∂r12 are within 1e-15 relative. The
/// inputs are first scaled by powers of two (exactly) so that the largest form entry is
/// near 1. Costs a contact function and about 0.5 µs more.
///
/// # Errors
/// As [`contact_function`](crate::contact_function).
pub fn contact_details(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<ContactDetails, Error> {
    // The dispatched entry point, so that the details agree with `contact_function` bit for bit.
    let contact = crate::contact_function(r12, q1, q2)?;
    // Lengths are divided by 2^k and forms by 4^k (exact): then y = Q⁻¹ r12 is 2^k times
    // the original one and the point 2^−k times.
    let k = crate::extreme::uniform_exponent(q1, q2);
    let (r, a, b) = crate::extreme::uniformly_rescaled(r12, q1, q2);
    let details = exact_details(&r, &a, &b, contact.lambda);
    let by = |x: f64, e: i32| crate::extreme::scale_by_power_of_two(x, e);
    let y = details.y.map(|x| by(x, -k));
    let [s, t] = details.weights;
    let ss = [
        y[0] * y[0],
        2.0 * y[0] * y[1],
        2.0 * y[0] * y[2],
        y[1] * y[1],
        2.0 * y[1] * y[2],
        y[2] * y[2],
    ];
    Ok(ContactDetails {
        contact,
        point: details.point.map(|x| by(x, k)),
        normal: details.normal,
        grad_r12: y.map(|x| 2.0 * t * s * x),
        grad_q1: ss.map(|x| -t * s * s * x),
        grad_q2: ss.map(|x| -t * t * s * x),
    })
}

/// What [`exact_details`] computes: (1 − λ₀, λ₀), y = Q(λ₀)⁻¹ r12, the point
/// (1 − λ₀) Q1 y (eq. 9a) and the unit normal y / |y|.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ExactDetails {
    pub weights: [f64; 2],
    pub y: [f64; 3],
    pub point: [f64; 3],
    pub normal: [f64; 3],
}

multiversion! {
    /// [`contact_details`] after the contact function, on the rescaled pair, from the
    /// contact function's λ: see there. Dispatched so that the double-double products use the
    /// hardware FMA.
    pub(crate) fn exact_details(r12: &[f64; 3], q1: &Sym3, q2: &Sym3, lambda: f64) -> ExactDetails
        => fused exact_details_portable;
}

#[inline(always)]
fn exact_details_portable<const FMA: bool>(
    r12: &[f64; 3],
    q1: &Sym3,
    q2: &Sym3,
    lambda: f64,
) -> ExactDetails {
    type D<const F: bool> = DdT<F>;
    let [s, t] = refined_weights::<FMA>(r12, q1, q2, lambda);
    let lift = D::<FMA>::lift;
    // Q(λ₀) = (1 − λ₀) Q1 + λ₀ Q2 (eq. 10): each entry's two products exact, their sum to
    // 2⁻¹⁰⁴ relative, whatever the sizes of Q1 and Q2.
    let q: [D<FMA>; 6] = core::array::from_fn(|k| lift(s) * lift(q1[k]) + lift(t) * lift(q2[k]));
    let adj = crate::sym::adjugate_generic(&q);
    let det = crate::sym::det_generic(&q, &adj).to_f64();
    let r = r12.map(lift);
    // v = adj Q(λ₀) r12 = det Q(λ₀) · y, and w = Q1 v (eq. 9a without the factors).
    let v = sym_mat_vec(&adj, &r);
    let w = sym_mat_vec(&crate::sym::lift6::<D<FMA>>(q1), &v);
    let v = v.map(Arith::to_f64);
    // Q(λ₀) is positive definite, so y has the direction of v: the normal needs no
    // division by the determinant.
    let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let normal = if norm > 0.0 {
        v.map(|x| x / norm)
    } else {
        [0.0; 3]
    };
    ExactDetails {
        weights: [s, t],
        y: v.map(|x| x / det),
        point: w.map(|x| s * (x.to_f64() / det)),
        normal,
    }
}

/// A x for a symmetric A in packed storage (Q11, Q12, Q13, Q22, Q23, Q33), in any arithmetic.
#[inline(always)]
fn sym_mat_vec<T: Arith>(a: &[T; 6], x: &[T; 3]) -> [T; 3] {
    [
        a[0] * x[0] + a[1] * x[1] + a[2] * x[2],
        a[1] * x[0] + a[3] * x[1] + a[4] * x[2],
        a[2] * x[0] + a[4] * x[1] + a[5] * x[2],
    ]
}

/// (1 − λ₀, λ₀) to a few units in the last place each, from the contact function's λ₀.
///
/// Newton's method on p(u) = A B + u (1 + u) (A′ B − A B′), the numerator of f′ (eqs. 18–20)
/// in the odds u = λ / (1 − λ) (see [`crate::poly::OddsForm`]), with the Bernstein
/// coefficients and p, p′ in double-double; for λ₀ > ½ on the reversed form (Q1 and Q2
/// swapped), whose odds are (1 − λ) / λ, so that a λ₀ near 1 keeps 1 − λ₀ to its relative
/// precision. The start is within about 1e-13 of the root (absolute in λ), and the root is
/// simple (f is strictly concave in the odds' sense: p decreases through it), so the steps
/// shrink quadratically; the loop ends at a step below 2⁻⁵⁸ relative, after three steps at
/// most, or at the first step that would leave (0, ∞) or is not finite (r12 = 0: p ≡ 0), then
/// keeping the last good u.
#[inline(always)]
fn refined_weights<const FMA: bool>(r12: &[f64; 3], q1: &Sym3, q2: &Sym3, lambda: f64) -> [f64; 2] {
    let Coefficients { alpha, beta } = crate::poly::coefficients::<DdT<FMA>>(r12, q1, q2);
    let reversed = lambda > 0.5;
    let (alpha, beta) = if reversed {
        let ([a0, a1, a2], [b0, b1, b2, b3]) = (alpha, beta);
        ([a2, a1, a0], [b3, b2, b1, b0])
    } else {
        (alpha, beta)
    };
    // 1 − λ is exact for λ ≥ ½ (Sterbenz), so the reversed odds start from all the
    // precision the double λ has.
    let mut u = if reversed {
        (1.0 - lambda) / lambda
    } else {
        lambda / (1.0 - lambda)
    };
    for _ in 0..3 {
        let (p, slope) = odds_numerator_and_slope(&alpha, &beta, DdT::<FMA>::lift(u));
        let step = p.to_f64() / slope.to_f64();
        let next = u - step;
        if !(next > 0.0 && next < f64::INFINITY) {
            break;
        }
        u = next;
        if step.abs() <= f64::from_bits((1023 - 58) << 52) * u {
            break;
        }
    }
    // λ = u / (1 + u), 1 − λ = 1 / (1 + u): each a few roundings from the exact value.
    let rho = 1.0 / (1.0 + u);
    if reversed {
        [u * rho, rho]
    } else {
        [rho, u * rho]
    }
}

/// p(u) and p′(u) in any arithmetic, with A(u) = α₀ + α₁u + α₂u² and
/// B(u) = β₀ + β₁u + β₂u² + β₃u³ (see [`crate::poly::OddsForm`]):
///
/// ```text
/// p(u)  = A B + u (1 + u) (A′ B − A B′),
/// p′(u) = A′ B + A B′ + (1 + 2u) (A′ B − A B′) + u (1 + u) (A″ B − A B″).
/// ```
#[inline(always)]
fn odds_numerator_and_slope<T: Arith>(alpha: &[T; 3], beta: &[T; 4], u: T) -> (T, T) {
    let [a0, a1, a2] = *alpha;
    let [b0, b1, b2, b3] = *beta;
    let (one, three) = (T::lift(1.0), T::lift(3.0));
    let a = a0 + (a1 + a2 * u) * u;
    let da = a1 + (a2 * u).twice();
    let dda = a2.twice();
    let b = b0 + (b1 + (b2 + b3 * u) * u) * u;
    let db = b1 + (b2.twice() + three * b3 * u) * u;
    let ddb = b2.twice() + (three * b3 * u).twice();
    let w = u * (one + u);
    let cross = da * b - a * db;
    let p = a * b + w * cross;
    let slope = da * b + a * db + (one + u.twice()) * cross + w * (dda * b - a * ddb);
    (p, slope)
}

/// Relative rounding error of evaluating f from exact non-negative coefficients (a dozen
/// roundings of non-negative quantities, each within u = 2⁻⁵³: 12 in [`Solution::at`], 13 in
/// the λ form of the fallback; their worst cases do not coincide, and 8 u is the allowance
/// this crate has used since its calibration).
const EVAL: f64 = 8.0 * 0.5 * f64::EPSILON;

/// The normalisation that keeps the solver's arithmetic away from overflow: α and β are
/// divided by their largest entries, and μ² is scaled back at the end.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scale {
    alpha: f64,
    beta: f64,
    /// 1 / alpha and 1 / beta, from the exponent bits: the division would sit on the latency
    /// chain between the coefficients and the first iterate.
    inv_alpha: f64,
    inv_beta: f64,
}

/// The maximiser found by [`solve`], with a(λ₀) and b(λ₀) of the normalised form.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Solution {
    pub lambda: f64,
    pub f: f64,
    pub a: f64,
    pub b: f64,
    /// Where the odds iteration found it: u, A(u), B(u) of the oriented form and whether it
    /// is reversed; `None` from the λ iteration.
    pub odds: Option<OddsPoint>,
}

/// A point of the odds iteration: [u, A(u), B(u)] of the oriented form, and its orientation.
///
/// The error estimate is formed at the iterate of the last evaluation, not at the returned
/// u one accepted step beyond it: there A and B are known when the last step is computed,
/// so the estimate no longer waits at the end of the call for A and B at the final u (the
/// tail of every call, with the divisions of μ² and λ). The accepted step is at most
/// [`crate::poly::HALLEY_LAST_STEP`] relative, so the estimate's ratios of polynomials with
/// non-negative coefficients move by a factor below (1 + 3e-5)⁶ between the two points;
/// [`odds_amplification`] allows 1.001. (An exit on a collapsed bracket returns that
/// iterate itself.)
#[derive(Clone, Copy, Debug)]
pub(crate) struct OddsPoint {
    pub u_a_b: [f64; 3],
    pub side: Side,
}

/// Which way [`orient`] turned the pencil: reversed (Q1 and Q2 swapped, λ ↔ 1 − λ) when the sign
/// bit is set. A double rather than a `bool` so that choosing by it is a blend of registers
/// ([`crate::arith::select_sign`]): the side is a coin toss on ordinary input, and as a branch
/// it was mispredicted once per call.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Side(f64);

impl Side {
    /// Reversed when `x > y`.
    #[inline(always)]
    pub(crate) fn of<const FMA: bool>(x: f64, y: f64) -> Self {
        Side(select_gt::<FMA>(x, y, -1.0, 1.0))
    }

    /// `swap` when reversed, else `keep`.
    #[inline(always)]
    pub(crate) fn pick<const FMA: bool>(self, keep: f64, swap: f64) -> f64 {
        select_sign::<FMA>(self.0, swap, keep)
    }

    /// [`oriented`] by this side. Written out rather than as `oriented` with a closure: a
    /// closure is compiled without the AVX2 target feature of the function it appears in,
    /// and when the optimiser did not inline it, each pick became a call into a closure
    /// that itself called the blend intrinsic out of line (six calls per contact function,
    /// a loss the bench `contact` shows).
    #[inline(always)]
    pub(crate) fn orient<const FMA: bool>(
        self,
        (alpha, beta): ([f64; 3], [f64; 4]),
    ) -> ([f64; 3], [f64; 4]) {
        let [a0, a1, a2] = alpha;
        let [b0, b1, b2, b3] = beta;
        (
            [self.pick::<FMA>(a0, a2), a1, self.pick::<FMA>(a2, a0)],
            [
                self.pick::<FMA>(b0, b3),
                self.pick::<FMA>(b1, b2),
                self.pick::<FMA>(b2, b1),
                self.pick::<FMA>(b3, b0),
            ],
        )
    }
}

impl Solution {
    /// Σ|terms| / value for a and b at λ₀, added: how much a relative error of the
    /// coefficients (measured against `bound`, their Σ|terms|, unnormalised) is amplified in f.
    fn amplification(&self, bound: &RationalForm, scale: Scale) -> f64 {
        amplification(
            &bound.alpha,
            &bound.beta,
            [self.lambda, self.a, self.b, scale.alpha, scale.beta],
        )
    }
}

impl Solution {
    /// [`Solution::amplification`] with each coefficient's Σ|terms| multiplied by the depth
    /// of its expression tree ([`DEPTH_ALPHA`], [`DEPTH_BETA`]): u times this bounds the
    /// relative error of f(λ₀) caused by the rounding of the `f64` coefficients. Returned as
    /// a fraction (x, d), d > 0 ([`odds_amplification`]).
    #[inline(always)]
    pub(crate) fn weighted_amplification<const FMA: bool>(
        &self,
        bound: &RationalForm,
        scale: Scale,
    ) -> (f64, f64) {
        let weighted = depth_weighted(&bound.alpha, &bound.beta);
        match self.odds {
            Some(OddsPoint {
                u_a_b: [u, big_a, big_b],
                side,
            }) => {
                let (alpha, beta) = side.orient::<FMA>(weighted);
                odds_amplification(
                    &alpha,
                    &beta,
                    [u, big_a, big_b, scale.inv_alpha, scale.inv_beta],
                )
            }
            None => (
                amplification(
                    &weighted.0,
                    &weighted.1,
                    [self.lambda, self.a, self.b, scale.alpha, scale.beta],
                ),
                1.0,
            ),
        }
    }
}

/// The Σ|terms| of the coefficients multiplied by the depths of their expression trees
/// ([`DEPTH_ALPHA`], [`DEPTH_BETA`]), in any arithmetic.
#[inline(always)]
pub(crate) fn depth_weighted<T: Arith>(alpha: &[T; 3], beta: &[T; 4]) -> ([T; 3], [T; 4]) {
    (
        core::array::from_fn(|k| alpha[k] * T::lift(DEPTH_ALPHA[k])),
        core::array::from_fn(|k| beta[k] * T::lift(DEPTH_BETA[k])),
    )
}

/// Coefficient lists in the orientation chosen by [`orient`]: `pick(keep, swap)` selects.
#[inline(always)]
pub(crate) fn oriented<T: Copy>(
    (alpha, beta): ([T; 3], [T; 4]),
    pick: impl Fn(T, T) -> T,
) -> ([T; 3], [T; 4]) {
    let [a0, a1, a2] = alpha;
    let [b0, b1, b2, b3] = beta;
    (
        [pick(a0, a2), a1, pick(a2, a0)],
        [pick(b0, b3), pick(b1, b2), pick(b2, b1), pick(b3, b0)],
    )
}

/// [`amplification`] at the odds u of the oriented form, from the oriented bounds and A(u),
/// B(u) of the normalised oriented form (`inv_alpha`, `inv_beta`: the normalisation). With
/// a = s²A, b = s³B (s = 1 / (1 + u)) and the bounds' polynomials likewise, the powers of s
/// cancel: Σ|terms| / value is Ā(u) / A(u) for a and B̄(u) / B(u) for b. So the estimate
/// needs neither λ nor s. It is returned as the fraction (x, d) = (Ā B + B̄ A, A B), so that
/// the decision to refine needs no division ([`Prepared::needs_refinement`]).
#[inline(always)]
pub(crate) fn odds_amplification<T: Arith>(
    bound_alpha: &[T; 3],
    bound_beta: &[T; 4],
    [u, big_a, big_b, inv_alpha, inv_beta]: [T; 5],
) -> (T, T) {
    let [a0, a1, a2] = *bound_alpha;
    let [b0, b1, b2, b3] = *bound_beta;
    let u2 = u * u;
    let bound_a = (a0 + a1 * u) + a2 * u2;
    let bound_b = (b0 + b1 * u) + (b2 + b3 * u) * u2;
    // 1.001: the estimate is taken one accepted step before the returned u ([`OddsPoint`]).
    (
        (bound_a * inv_alpha * big_b + bound_b * inv_beta * big_a) * T::lift(1.001),
        big_a * big_b,
    )
}

/// [`Solution::amplification`] in any arithmetic (the batch evaluates four lanes at once).
#[inline(always)]
pub(crate) fn amplification<T: Arith + core::ops::Div<Output = T>>(
    bound_alpha: &[T; 3],
    bound_beta: &[T; 4],
    [lambda, a, b, scale_alpha, scale_beta]: [T; 5],
) -> T {
    let [ba, _, _, bb, _, _] = crate::poly::pencil_values(bound_alpha, bound_beta, lambda);
    ba / (a * scale_alpha) + bb / (b * scale_beta)
}

/// [`Solution::at`] in any arithmetic: [λ, 1 − λ, f, a, b] at the odds u of an oriented
/// form.
///
/// With A(u) = α₀ + α₁u + α₂u², B(u) = β₀ + β₁u + β₂u² + β₃u³ (non-negative coefficients and
/// u ≥ 0, so evaluated without cancellation): λ = u / (1 + u), f = u A / ((1 + u) B) (eq. 15),
/// a = A / (1 + u)² and b = B / (1 + u)³ (eq. 16).
#[inline(always)]
pub(crate) fn odds_solution<T: Arith + core::ops::Div<Output = T>>(
    alpha: &[T; 3],
    beta: &[T; 4],
    u: T,
) -> [T; 5] {
    let [a0, a1, a2] = *alpha;
    let [b0, b1, b2, b3] = *beta;
    let one = T::lift(1.0);
    // Grouped (Estrin) rather than Horner: fewer roundings on the longest path (3 in A,
    // 5 in B) and a shorter dependency chain.
    let u2 = u * u;
    let big_a = (a0 + a1 * u) + a2 * u2;
    let big_b = (b0 + b1 * u) + (b2 + b3 * u) * u2;
    // 1 − λ directly, not by subtraction: when reversed it is the returned λ.
    let s = one / (one + u);
    [
        u * s,
        s,
        u * big_a / ((one + u) * big_b),
        s * s * big_a,
        s * s * s * big_b,
    ]
}

/// The maximiser of a normalised rational form (coefficients non-negative, not all zero):
/// Halley's iteration on the odds u = λ / (1 − λ) ([`OddsForm`]), from the exact maximiser for
/// two spheres of the ellipsoids' radial extents along r12.
#[inline(always)]
pub(crate) fn solve<const FMA: bool>(r: &RationalForm) -> Solution {
    solve_odds::<FMA>(r, crate::poly::Tiny::NORMALISED).unwrap_or_else(|| solve_lambda(r))
}

/// [`solve`] without its fallback: `None` where the odds iteration cannot be trusted and the
/// λ iteration ([`solve_lambda`]) must be used instead.
#[inline(always)]
pub(crate) fn solve_odds<const FMA: bool>(
    r: &RationalForm,
    tiny: crate::poly::Tiny,
) -> Option<Solution> {
    let (form, u0, side) = orient::<FMA>(r);
    let odds = OddsForm::new(&form.alpha, &form.beta);
    let mut search = OddsSearch::new(u0, tiny);
    let mut last = [u0, 0.0, 0.0];
    while !search.done {
        let terms = odds.halley_terms::<FMA>(search.u);
        last = [search.u, terms.a, terms.b];
        search.advance::<FMA>(terms.step_terms());
    }
    if search.fallback {
        return None;
    }
    Some(Solution::at::<FMA>(&form, search.u, side, last))
}

/// The bracketed Newton iteration in λ itself ([`RationalForm::search_step`]), for the pencils
/// whose polynomials in u span too many decades for [`solve`] (the products of its step
/// would underflow); it divides by a and b at every step instead.
#[cold]
#[inline(never)]
pub(crate) fn solve_lambda(r: &RationalForm) -> Solution {
    // The sphere start λ = 1 / (1 + ρ) with ρ = ρ₂/ρ₁, taken at the end it lies near: for
    // ρ < 1 the reversed form starts from 1 − λ = ρ / (1 + ρ) itself, which keeps its digits
    // where λ rounds to 1 (a second ellipsoid 1e16 times smaller than the first).
    let ratio = r.sphere_ratio();
    let (form, mut search, reversed) = if !(ratio > 0.0 && ratio < f64::INFINITY) {
        (*r, Search::new(0.5), false)
    } else if ratio < 1.0 {
        (r.reversed(), Search::new(ratio / (1.0 + ratio)), true)
    } else {
        (*r, Search::new(1.0 / (1.0 + ratio)), false)
    };
    while !search.done {
        form.search_step(&mut search);
    }
    Solution::of(&form, &search, reversed)
}

/// Where to start: the exact maximiser for two spheres whose radii are the radial extents
/// ρᵢ = (r̂ᵀ Qᵢ⁻¹ r̂)^(−1/2) of the ellipsoids along r12, u = ρ₁ / ρ₂ = √(α₂β₀ / (α₀β₃)). When it
/// exceeds 1 the reversed form (Q1 and Q2 swapped, λ ↔ 1 − λ) is solved instead, so that the
/// variable is small at whichever end the maximiser lies near and keeps its relative precision
/// (λ₀ = 1 − 1e-12 is not representable to better than 1e-4 relative in its distance to 1).
/// Returns the form to solve, u at the start and the side.
#[inline(always)]
pub(crate) fn orient<const FMA: bool>(r: &RationalForm) -> (RationalForm, f64, Side) {
    let (x, y) = (r.alpha[2] * r.beta[0], r.alpha[0] * r.beta[3]);
    // Blends rather than a branch: the side is a coin toss on ordinary input.
    let side = Side::of::<FMA>(x, y);
    let (alpha, beta) = side.orient::<FMA>((r.alpha, r.beta));
    let form = RationalForm { alpha, beta };
    (form, (x.min(y) / x.max(y)).sqrt(), side)
}

impl Solution {
    /// The solution at the odds u of the (oriented) `form`: λ = u / (1 + u), and with
    /// A(u) = α₀ + α₁u + α₂u², B(u) = β₀ + β₁u + β₂u² + β₃u³ (non-negative coefficients and
    /// u ≥ 0, so evaluated without cancellation), f = u A / ((1 + u) B) (eq. 15), a = A / (1 + u)² and
    /// b = B / (1 + u)³ (eq. 16). `last` is [u, A(u), B(u)] where the iteration evaluated
    /// last, one step before u: the error estimate is formed there ([`OddsPoint`]).
    #[inline(always)]
    pub(crate) fn at<const FMA: bool>(
        form: &RationalForm,
        u: f64,
        side: Side,
        last: [f64; 3],
    ) -> Self {
        let [t, s, f, a, b] = odds_solution(&form.alpha, &form.beta, u);
        Solution {
            lambda: side.pick::<FMA>(t, s),
            f,
            a,
            b,
            odds: Some(OddsPoint { u_a_b: last, side }),
        }
    }

    #[inline(always)]
    pub(crate) fn of(form: &RationalForm, search: &Search, reversed: bool) -> Self {
        let t = search.t;
        Solution {
            lambda: if reversed { 1.0 - t } else { t },
            f: search.f,
            a: form.a(t),
            b: form.b(t),
            odds: None,
        }
    }
}

impl Scale {
    /// No scaling: a placeholder for lanes that carry no pair.
    pub(crate) const UNIT: Scale = Scale {
        alpha: 1.0,
        beta: 1.0,
        inv_alpha: 1.0,
        inv_beta: 1.0,
    };

    /// Powers of two near the largest α and β: multiplying by their reciprocals is exact, so
    /// normalising changes no digit, and costs no division.
    #[inline(always)]
    pub(crate) fn of(r: &RationalForm) -> Option<Self> {
        let alpha = r.alpha.iter().fold(0.0_f64, |m, &x| m.max(x));
        let beta = r.beta.iter().fold(0.0_f64, |m, &x| m.max(x));
        (alpha > 0.0 && beta > 0.0).then(|| {
            let (alpha, inv_alpha) = power_of_two_below(alpha);
            let (beta, inv_beta) = power_of_two_below(beta);
            Self {
                alpha,
                beta,
                inv_alpha,
                inv_beta,
            }
        })
    }

    /// The thresholds for solving the form without this normalisation, when the powers are
    /// moderate: sα sβ in [2⁻¹²⁸, 2¹²⁸] and each in [2⁻⁵⁰⁰, 2⁵⁰⁰]. Then the solver's
    /// products (at most cubic in A B and its derivatives) stay as far from overflow and
    /// underflow as [`crate::poly::Tiny`] makes them for the normalised form, give or take
    /// 2³⁸⁴.
    #[inline(always)]
    pub(crate) fn moderate(&self) -> Option<crate::poly::Tiny> {
        const fn power(e: u64) -> f64 {
            f64::from_bits(e << 52)
        }
        let product = self.alpha * self.beta;
        let within = |x: f64, e: u64| x >= power(1023 - e) && x <= power(1023 + e);
        (within(self.alpha, 500) && within(self.beta, 500) && within(product, 128))
            .then(|| crate::poly::Tiny::scaled(product))
    }

    /// Whether both powers are far from the subnormal range (2⁻⁹⁰⁰ and above), where the
    /// coefficients kept their precision.
    #[inline(always)]
    pub(crate) fn is_normal(&self) -> bool {
        const SMALLEST: f64 = f64::from_bits((1023 - 900) << 52);
        self.alpha >= SMALLEST && self.beta >= SMALLEST
    }

    /// The powers of two that α and β were divided by.
    #[inline(always)]
    pub(crate) fn powers(&self) -> (f64, f64) {
        (self.alpha, self.beta)
    }

    /// α / β: f of the normalised form times this is f of the original one.
    #[inline(always)]
    pub(crate) fn ratio(&self) -> f64 {
        self.alpha * self.inv_beta
    }

    #[inline(always)]
    pub(crate) fn apply(&self, r: &RationalForm) -> RationalForm {
        // Mixed coefficients are non-negative in exact arithmetic; rounding may leave a tiny
        // negative value, which the error bound accounts for.
        let (ia, ib) = (self.inv_alpha, self.inv_beta);
        RationalForm {
            alpha: r.alpha.map(|x| (x * ia).max(0.0)),
            beta: r.beta.map(|x| (x * ib).max(0.0)),
        }
    }

    #[inline(always)]
    pub(crate) fn contact(&self, s: &Solution, error_estimate: f64, refined: bool) -> Contact {
        Contact {
            mu2: s.f * self.ratio(),
            lambda: s.lambda,
            error_estimate,
            refined,
        }
    }
}

/// [`Scale::of`] for four lanes at once, from the lanes' largest α and β; the same
/// operations, so the same bits, without moving each lane's coefficients through memory.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scale4 {
    alpha: crate::lanes::V4,
    beta: crate::lanes::V4,
    inv_alpha: crate::lanes::V4,
    inv_beta: crate::lanes::V4,
}

impl Scale4 {
    /// The scales of the lanes' forms (α and β coefficients, one lane per pair), and which
    /// lanes have one (where [`Scale::of`] is not `None`; false for r12 = 0).
    #[inline(always)]
    pub(crate) fn of(
        alpha: &[crate::lanes::V4; 3],
        beta: &[crate::lanes::V4; 4],
    ) -> (Self, [bool; crate::lanes::LANES]) {
        use crate::lanes::V4;
        let largest = |xs: &[V4]| {
            xs.iter().fold(V4::from_fn(|_| 0.0), |m, x| {
                V4::from_fn(|k| m.0[k].max(x.0[k]))
            })
        };
        let (a, b) = (largest(alpha), largest(beta));
        let positive = core::array::from_fn(|k| a.0[k] > 0.0 && b.0[k] > 0.0);
        let (alpha, inv_alpha) = powers_of_two_below4(a);
        let (beta, inv_beta) = powers_of_two_below4(b);
        (
            Self {
                alpha,
                beta,
                inv_alpha,
                inv_beta,
            },
            positive,
        )
    }

    /// Lane `k` as a [`Scale`].
    #[inline(always)]
    pub(crate) fn lane(&self, k: usize) -> Scale {
        Scale {
            alpha: self.alpha.0[k],
            beta: self.beta.0[k],
            inv_alpha: self.inv_alpha.0[k],
            inv_beta: self.inv_beta.0[k],
        }
    }

    /// The lanes picked from `source` (a lane index per lane).
    #[inline(always)]
    pub(crate) fn picked(&self, source: &[usize; crate::lanes::LANES]) -> Self {
        let pick = |x: crate::lanes::V4| crate::lanes::V4::from_fn(|k| x.0[source[k]]);
        Self {
            alpha: pick(self.alpha),
            beta: pick(self.beta),
            inv_alpha: pick(self.inv_alpha),
            inv_beta: pick(self.inv_beta),
        }
    }

    /// 1/sα and 1/sβ, lane-wise.
    #[inline(always)]
    pub(crate) fn inverses(&self) -> (crate::lanes::V4, crate::lanes::V4) {
        (self.inv_alpha, self.inv_beta)
    }

    /// sα / sβ lane-wise, as [`Scale::ratio`].
    #[inline(always)]
    pub(crate) fn ratio(&self) -> crate::lanes::V4 {
        self.alpha * self.inv_beta
    }
}

/// [`power_of_two_below`] lane-wise, with selects instead of the branch.
#[inline(always)]
fn powers_of_two_below4(x: crate::lanes::V4) -> (crate::lanes::V4, crate::lanes::V4) {
    use crate::lanes::V4;
    let exponent: [u64; crate::lanes::LANES] =
        core::array::from_fn(|k| (x.0[k].to_bits() >> 52) & 0x7ff);
    let normal = |k: usize| (1..2046).contains(&exponent[k]);
    let power = V4::from_fn(|k| f64::from_bits(exponent[k] << 52));
    let inverse = V4::from_fn(|k| f64::from_bits((2046 - exponent[k].min(2045)) << 52));
    let reciprocal = V4::from_fn(|k| 1.0 / x.0[k]);
    (
        V4::from_fn(|k| if normal(k) { power.0[k] } else { x.0[k] }),
        V4::from_fn(|k| {
            if normal(k) {
                inverse.0[k]
            } else {
                reciprocal.0[k]
            }
        }),
    )
}

/// Whether the cheap sufficient tests of [`check_positive_definite`] pass in every lane
/// (Q11 > 0, the leading 2×2 minor and det Q beyond their rounding bounds), given each
/// lane's det Q and its Σ|terms|: then the checks would all return `Ok` without looking
/// further, and the lanes need not be checked one by one.
#[inline(always)]
pub(crate) fn positive_definite4(
    q: &[crate::lanes::V4; 6],
    det: crate::lanes::V4,
    det_magnitude: crate::lanes::V4,
) -> bool {
    (0..crate::lanes::LANES).fold(true, |all, k| {
        let det_floor = GAMMA_F64 * det_magnitude.0[k];
        all & clearly_positive_definite([q[0].0[k], q[1].0[k], q[3].0[k]], det.0[k], det_floor)
    })
}

/// The cheap sufficient tests of [`check_positive_definite`] in one expression without
/// branches: Q11 > 0, the leading 2×2 minor beyond its rounding bound, and det Q above
/// `det_floor` (at least γ times a bound on its terms). Where they hold, the check returns
/// `Ok` without its exact fallbacks. `q` is (Q11, Q12, Q22).
#[inline(always)]
pub(crate) fn clearly_positive_definite(
    [q11, q12, q22]: [f64; 3],
    det: f64,
    det_floor: f64,
) -> bool {
    let minor = q11 * q22 - q12 * q12;
    (q11 > 0.0) & (minor > GAMMA_F64 * (q11 * q22 + q12 * q12)) & (det > det_floor)
}

/// The largest power of two ≤ x and its reciprocal, for positive finite x; x itself and 1 / x
/// for subnormal or huge x (where the reciprocal of the power would not be representable),
/// which only costs exactness of the normalisation there.
#[inline(always)]
fn power_of_two_below(x: f64) -> (f64, f64) {
    let exponent = (x.to_bits() >> 52) & 0x7ff;
    if (1..2046).contains(&exponent) {
        // 2^(e − 1023) and 2^(1023 − e): biased exponents e and 2046 − e, both in 1..=2045.
        (
            f64::from_bits(exponent << 52),
            f64::from_bits((2046 - exponent) << 52),
        )
    } else {
        (x, 1.0 / x)
    }
}

/// All fifteen inputs finite and inside the fast path's window, checked in one pass
/// (x·P − x·P is NaN exactly for NaN, ±∞ and |x| beyond 2^241, with P = [`crate::extreme::PROBE`],
/// and a sum is NaN iff a term is): `Ok(true)`. The slow search for a culprit runs only when
/// the check fails: the typed error for NaN or ±∞, `Ok(false)` for finite entries beyond the
/// window (answered by [`crate::extreme`]).
#[inline(always)]
pub(crate) fn check_inputs_finite<const FMA: bool>(
    r12: &[f64; 3],
    q1: &Sym3,
    q2: &Sym3,
) -> Result<bool, Error> {
    if all_finite::<FMA>(r12, q1, q2) {
        return Ok(true);
    }
    check_finite(Argument::R12, r12)?;
    check_finite(Argument::Q1, q1)?;
    check_finite(Argument::Q2, q2)?;
    Ok(false)
}

/// The probe of [`check_inputs_finite`]. In the AVX2 build the fifteen differences are four
/// 256-bit subtractions (the two rows of each matrix overlap in Q13, Q22) and one 128-bit one.
#[inline(always)]
fn all_finite<const FMA: bool>(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> bool {
    #[cfg(target_arch = "x86_64")]
    if FMA {
        use core::arch::x86_64::*;
        // SAFETY: `FMA` is true only in the AVX2 + FMA build of a dispatched function, after
        // the processor was checked to have AVX2. Every load reads inside its array: [0, 4)
        // and [2, 6) of the six entries, [0, 2) and [2] of r12.
        return unsafe {
            let probe = _mm256_set1_pd(crate::extreme::PROBE);
            let d4 = |p: *const f64| {
                let x = _mm256_mul_pd(_mm256_loadu_pd(p), probe);
                _mm256_sub_pd(x, x)
            };
            let q = _mm256_add_pd(
                _mm256_add_pd(d4(q1.as_ptr()), d4(q1.as_ptr().add(2))),
                _mm256_add_pd(d4(q2.as_ptr()), d4(q2.as_ptr().add(2))),
            );
            let probe2 = _mm_set1_pd(crate::extreme::PROBE);
            let r = _mm_mul_pd(_mm_loadu_pd(r12.as_ptr()), probe2);
            let r2 = _mm_mul_sd(_mm_load_sd(r12.as_ptr().add(2)), probe2);
            let r = _mm_add_pd(_mm_sub_pd(r, r), _mm_sub_pd(r2, r2));
            let s = _mm_add_pd(
                _mm_add_pd(_mm256_castpd256_pd128(q), _mm256_extractf128_pd::<1>(q)),
                r,
            );
            // Both lanes ordered (not NaN).
            _mm_movemask_pd(_mm_cmp_pd::<_CMP_ORD_Q>(s, s)) == 0b11
        };
    }
    #[allow(clippy::eq_op)] // x·P − x·P is the point: NaN for NaN, ±∞ and huge x, 0 otherwise.
    let d = |x: f64| {
        let y = x * crate::extreme::PROBE;
        y - y
    };
    // Four independent chains: fewer dependent additions than one.
    let chains: [f64; 4] = [
        d(r12[0]) + d(q1[2]) + d(q1[5]) + d(q2[3]),
        d(r12[1]) + d(q1[0]) + d(q1[4]) + d(q2[4]),
        d(r12[2]) + d(q1[1]) + d(q2[0]) + d(q2[5]),
        d(q1[3]) + d(q2[1]) + d(q2[2]),
    ];
    (chains[0] + chains[1]) + (chains[2] + chains[3]) == 0.0
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
        let mut rng = testkit::Rng::new(12345u64);
        let mut next = move || rng.uniform();
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
            let s1 = solve::<false>(&scale.apply(&fast));
            let bound = coefficients::<Mag>(&r, &q1, &q2).to_f64();
            let (x, d) = s1.weighted_amplification::<false>(&bound, scale);
            let est = Prepared::estimate(x / d);
            let exact = coefficients::<Dd>(&r, &q1, &q2).to_f64();
            let scale2 = Scale::of(&exact).unwrap();
            let s2 = solve::<false>(&scale2.apply(&exact));
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
