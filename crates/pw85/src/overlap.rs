//! The yes/no question — do two ellipsoids overlap? — answered without computing μ² unless the
//! answer is within rounding error of the tangency.
//!
//! μ² < 1 iff the ellipsoids overlap (theory eq. 6). Every λ gives a lower bound f(λ) ≤ μ², and
//! since f is concave (a minimum of functions affine in λ, eq. 5) every tangent line gives an
//! upper bound. The verdict therefore stops at the first of:
//!
//! 1. the projections on the centre line are disjoint (support values along r̂): no overlap;
//! 2. the segment between the centres is covered by the two ellipsoids (radial extents along
//!    r̂): overlap;
//! 3. along the common normal Q(λ̂)⁻¹ r12 at a guessed λ̂ the projections are disjoint (no
//!    overlap), or the contact point x₀(λ̂) (eq. 9), slid towards one centre or the other,
//!    lies in both (overlap);
//! 4. some iterate λ of the contact-function iteration has f(λ) > 1: no overlap;
//! 5. the tangent lines at the iterates bound max f below 1: overlap;
//!
//! each test with a margin for the rounding error of f. Pairs still undecided (|μ² − 1| within
//! that margin, or a badly conditioned pencil) get the full [`crate::contact_function`] with
//! its double-double refinement, and the verdict μ² < 1.

use crate::arith::Mag;
use crate::arith::{is_positive, select_gt};
use crate::contact::{
    Scale, Side, check_inputs_finite, check_positive_definite, check_positive_definite_2d,
    clearly_positive_definite, orient,
};
use crate::error::{Argument, Error};
use crate::poly::{
    OddsForm, OddsSearch, RationalForm, coefficients_2d, odds_numerator, odds_numerator_at, pencil3,
};
use crate::sym::{
    Sym2, Sym3, adjugate_generic, det_generic, outer_generic, quadratic_form_generic,
};
use simd::multiversion;

/// Rounding-error factor of the short expression trees of the axis test (at most about six
/// roundings deep; 10 u as in the contact function's coefficients).
const GAMMA: f64 = 10.0 * 0.5 * f64::EPSILON;

/// Relative safety factor on the geometric sphere tests (their square roots and sums round).
const SPHERE_MARGIN: f64 = 1e-12;
/// Iterations of the bounded search before handing over to the full contact function.
const MAX_ITERATIONS: u32 = 12;

multiversion! {
    /// [`overlap`](crate::overlap) on two ellipsoids.
    pub(crate) fn overlap_3d(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<bool, Error>
        => fused overlap_portable;
}

#[inline(always)]
fn overlap_portable<const FMA: bool>(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<bool, Error> {
    if !check_inputs_finite::<FMA>(r12, q1, q2)? {
        return crate::extreme::overlap(r12, q1, q2);
    }
    let adj1 = adjugate_generic(q1);
    let adj2 = adjugate_generic(q2);
    let det1 = det_generic(q1, &adj1);
    let det2 = det_generic(q2, &adj2);
    // Q11 Q22 Q33 bounds each of the six terms of det Q (|Qᵢⱼ| ≤ √(QᵢᵢQⱼⱼ)).
    let (p1, p2) = (q1[0] * q1[3] * q1[5], q2[0] * q2[3] * q2[5]);
    if let Err(e) = check_both_positive_definite(q1, q2, [det1, det2], [p1, p2]) {
        return crate::extreme::after_error(e, || crate::extreme::contact_function(r12, q1, q2))
            .map(|c| c.mu2 < 1.0);
    }

    let axis = AxisTest::new(r12, [q1, q2], [&adj1, &adj2], [det1, det2], [p1, p2]);
    let Some((claims, extents)) = axis.claims::<FMA>() else {
        return undecided::<FMA>(r12, q1, q2, None);
    };
    if let Some(verdict) = claims.verdict() {
        return Ok(verdict);
    }
    undecided::<FMA>(r12, q1, q2, Some(extents))
}

multiversion! {
    /// The verdict on a pair the axis test left open: the contact-point test at the λ̂ the
    /// axis test's extents give (if they are in its range), then the bounded search.
    ///
    /// Out of line, and recomputing the little it shares with the axis test: inlined, the
    /// values it needs stayed live across the axis test, and the common path (three pairs
    /// in four) paid for spilling them to the stack (see the `overlap` line of the bench
    /// `contact`).
    fn undecided(
        r12: &[f64; 3],
        q1: &Sym3,
        q2: &Sym3,
        extents: Option<[f64; 2]>,
    ) -> Result<bool, Error> => out_of_line undecided_in;
}

#[inline(always)]
fn undecided_in<const FMA: bool>(
    r12: &[f64; 3],
    q1: &Sym3,
    q2: &Sym3,
    extents: Option<[f64; 2]>,
) -> Result<bool, Error> {
    let (adj1, adj2) = (adjugate_generic(q1), adjugate_generic(q2));
    if let Some(extents) = extents {
        let test = ContactPointTest {
            r12: *r12,
            q: [*q1, *q2],
            adj: [adj1, adj2],
            d: [largest_diagonal(q1), largest_diagonal(q2)],
            det_lower: [
                det_generic(q1, &adj1) - GAMMA * 6.0 * q1[0] * q1[3] * q1[5],
                det_generic(q2, &adj2) - GAMMA * 6.0 * q2[0] * q2[3] * q2[5],
            ],
        };
        if let Some(verdict) = test.claims::<FMA>(extents).verdict() {
            return Ok(verdict);
        }
    }
    searched::<FMA>(r12, q1, q2)
}

multiversion! {
    /// The bounded search, and the full contact function if that does not decide either
    /// (one pair in 160 on the bench), out of line so that the contact-point test keeps its
    /// registers.
    #[cold]
    fn searched(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<bool, Error> => out_of_line searched_in;
}

#[inline(always)]
fn searched_in<const FMA: bool>(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<bool, Error> {
    let fast = pencil3::<f64>(r12, q1, q2).coefficients.to_f64();
    let rr = outer_generic::<f64>(r12);
    let bound = CrudeBound {
        d1: largest_diagonal(q1),
        d2: largest_diagonal(q2),
        r2: rr[0] + rr[3] + rr[5],
        k_b: 18.0,
        k_a: 6.0,
        dim: 3,
    };
    match bounded_search::<FMA>(&fast, &bound) {
        Some(verdict) => Ok(verdict),
        None => Ok(crate::contact_function(r12, q1, q2)?.mu2 < 1.0),
    }
}

/// The largest diagonal entry of Q, which bounds every |Qᵢⱼ| of a positive definite Q. The
/// entries are finite here; a plain comparison is then `max` without its NaN handling.
#[inline(always)]
fn largest_diagonal(q: &Sym3) -> f64 {
    let larger = |a: f64, b: f64| if a > b { a } else { b };
    larger(larger(q[0], q[3]), q[5])
}

multiversion! {
    /// [`overlap`](crate::overlap) on two ellipses.
    pub(crate) fn overlap_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<bool, Error>
        => fused overlap_2d_portable;
}

#[inline(always)]
fn overlap_2d_portable<const FMA: bool>(
    r12: &[f64; 2],
    q1: &Sym2,
    q2: &Sym2,
) -> Result<bool, Error> {
    if !crate::contact::inputs_finite_2d(r12, q1, q2)? {
        return crate::extreme::overlap_2d(r12, q1, q2);
    }
    if let Err(e) = check_positive_definite_2d(Argument::Q1, q1)
        .and_then(|()| check_positive_definite_2d(Argument::Q2, q2))
    {
        return crate::extreme::after_error(e, || crate::extreme::contact_function_2d(r12, q1, q2))
            .map(|c| c.mu2 < 1.0);
    }
    let r2 = r12[0] * r12[0] + r12[1] * r12[1];
    let (det1, det2) = (q1[0] * q1[2] - q1[1] * q1[1], q2[0] * q2[2] - q2[1] * q2[1]);
    // In 2D, λmin = det / λmax ≥ det / tr.
    let spheres = Spheres {
        outer: (q1[0] + q1[2]).sqrt() + (q2[0] + q2[2]).sqrt(),
        inner: (det1 / (q1[0] + q1[2])).sqrt() + (det2 / (q2[0] + q2[2])).sqrt(),
    };
    if let Some(verdict) = spheres.verdict(r2) {
        return Ok(verdict);
    }
    let fast = coefficients_2d::<f64>(r12, q1, q2);
    let bound = CrudeBound {
        d1: q1[0].max(q1[2]),
        d2: q2[0].max(q2[2]),
        r2,
        k_b: 4.0,
        k_a: 2.0,
        dim: 2,
    };
    match bounded_search::<FMA>(&fast.to_f64(), &bound) {
        Some(verdict) => Ok(verdict),
        None => Ok(crate::contact::contact_function_2d(r12, q1, q2)?.mu2 < 1.0),
    }
}

/// Sylvester's criterion for both matrices, as [`check_positive_definite`], with one branch
/// in the common case: when both pass the cheap sufficient tests (Q11 > 0, the leading 2×2
/// minor and det Q beyond their rounding bounds, with the cheap bound on det Q of
/// [`det_magnitude`]), nothing else is looked at.
#[inline(always)]
fn check_both_positive_definite(
    q1: &Sym3,
    q2: &Sym3,
    det: [f64; 2],
    diagonal_product: [f64; 2],
) -> Result<(), Error> {
    // det > 1e-12 · 6 Q11 Q22 Q33 is where `det_magnitude` takes the cheap bound.
    let clear = |q: &Sym3, det: f64, p: f64| {
        clearly_positive_definite([q[0], q[1], q[3]], det, 1e-12 * 6.0 * p)
    };
    if clear(q1, det[0], diagonal_product[0]) & clear(q2, det[1], diagonal_product[1]) {
        return Ok(());
    }
    check_each_positive_definite(q1, q2, det, diagonal_product)
}

/// The rare path of [`check_both_positive_definite`]: each minor with its exact fallback.
#[cold]
#[inline(never)]
fn check_each_positive_definite(
    q1: &Sym3,
    q2: &Sym3,
    [det1, det2]: [f64; 2],
    [p1, p2]: [f64; 2],
) -> Result<(), Error> {
    check_positive_definite(Argument::Q1, q1, det1, det_magnitude(q1, det1, p1))?;
    check_positive_definite(Argument::Q2, q2, det2, det_magnitude(q2, det2, p2))
}

/// A bound on Σ|terms| of det Q as the cofactor expansion computes it. For the positive
/// definiteness check only its size relative to det Q matters, so the cheap bound 6 Q11 Q22 Q33
/// (each of the six terms of a determinant with |Qᵢⱼ| ≤ √(QᵢᵢQⱼⱼ) is at most the product of the
/// diagonal, `diagonal_product`) is used when it already proves det Q > 0, and the exact
/// Σ|terms| otherwise.
fn det_magnitude(q: &Sym3, det: f64, diagonal_product: f64) -> f64 {
    let cheap = 6.0 * diagonal_product;
    if det > 1e-12 * cheap {
        return cheap;
    }
    let m = crate::sym::lift6::<Mag>(q);
    det_generic(&m, &adjugate_generic(&m)).0
}

/// Radii sums of the bounding and inscribed circles of two ellipses (the 2D verdict's first
/// test).
struct Spheres {
    outer: f64,
    inner: f64,
}

impl Spheres {
    fn verdict(&self, r2: f64) -> Option<bool> {
        if r2 > self.outer * self.outer * (1.0 + SPHERE_MARGIN) {
            Some(false)
        } else if r2 < self.inner * self.inner * (1.0 - SPHERE_MARGIN) {
            Some(true)
        } else {
            None
        }
    }
}

/// The two cheap certificates along the centre line r̂ = r12 / |r12|, from quantities the
/// validation and the coefficients need anyway (theory eq. 16a at λ = 0 and 1):
///
/// - **separating axis**: the projections of the ellipsoids on r̂ are the intervals
///   cᵢ·r̂ ± hᵢ with the support values hᵢ = √(r̂ᵀ Qᵢ r̂); if h₁ + h₂ < |r12| the projections
///   are disjoint and so are the ellipsoids. With r12 unnormalised: √(r12ᵀQ₁r12) +
///   √(r12ᵀQ₂r12) < |r12|²;
/// - **covered segment**: the points c₁ + t r̂, 0 ≤ t ≤ ρ₁, lie in the first ellipsoid for its
///   radial extent ρ₁ = (r̂ᵀ Q₁⁻¹ r̂)^(−1/2), and likewise from c₂; if ρ₁ + ρ₂ > |r12| the two
///   pieces of the segment overlap and so do the ellipsoids. Unnormalised:
///   √(β₀/α₀) + √(β₃/α₂) > 1 with α₀ = r12ᵀ adj Q₁ r12, β₀ = det Q₁ (α₂, β₃ for Q₂).
///
/// The first dominates the bounding spheres (hᵢ ≤ √λmax(Qᵢ)), the second the inscribed ones
/// (ρᵢ ≥ √λmin(Qᵢ)); on the bench's 100 000 pairs they decide 74.0 % of the verdicts (34.6 %
/// separated, 39.4 % overlapping), the spheres decided 9.8 %. The [`ContactPointTest`] then
/// decides 25.4 % of all pairs, and 0.6 % are left to the search.
///
/// Rounding: with |Qᵢⱼ| ≤ √(QᵢᵢQⱼⱼ) ≤ d (d the largest diagonal entry) the terms of
/// r12ᵀQr12 sum to at most 3 d |r12|², those of r12ᵀ adj Q r12 to at most 6 d² |r12|² and those
/// of det Q to at most 6 Q11 Q22 Q33; γ times these bound the errors, the quantities are
/// moved by them to the safe side, and the final comparisons keep a relative margin
/// [`SPHERE_MARGIN`] for the square roots, divisions and sums. The test is only made when
/// |r12|², d₁ and d₂ are within [1e-60, 1e60]: then every product above stays far from
/// overflow, and the absolute errors of subnormal intermediates are negligible against the
/// margins (which are ≥ γ · 1e-180).
struct AxisTest {
    r2: f64,
    d: [f64; 2],
    /// r12ᵀ Qᵢ r12 = |r12|² hᵢ².
    support2: [f64; 2],
    /// r12ᵀ adj Qᵢ r12.
    alpha: [f64; 2],
    /// det Qᵢ and the bound Q11 Q22 Q33 on each of its terms.
    det: [f64; 2],
    det_terms: [f64; 2],
}

impl AxisTest {
    /// The test on the pair (r12, Q1, Q2), given adj Qᵢ, det Qᵢ and the bounds Q11 Q22 Q33
    /// on the terms of det Qᵢ.
    #[inline(always)]
    fn new(
        r12: &[f64; 3],
        [q1, q2]: [&Sym3; 2],
        [adj1, adj2]: [&Sym3; 2],
        det: [f64; 2],
        det_terms: [f64; 2],
    ) -> Self {
        let rr = outer_generic::<f64>(r12);
        AxisTest {
            r2: rr[0] + rr[3] + rr[5],
            d: [largest_diagonal(q1), largest_diagonal(q2)],
            support2: [
                quadratic_form_generic(&rr, q1),
                quadratic_form_generic(&rr, q2),
            ],
            // α₀ = r12ᵀ adj Q1 r12 and α₂ (eq. 16a at λ = 0, 1).
            alpha: [
                quadratic_form_generic(&rr, adj1),
                quadratic_form_generic(&rr, adj2),
            ],
            det,
            det_terms,
        }
    }

    /// The claims of the axis test, with the radial extents ρᵢ (lower bounds, in units of
    /// |r12|) that the contact-point test starts from; `None` where |r12|², d₁ or d₂ is
    /// outside [1e-60, 1e60] and the test is not made.
    #[inline(always)]
    fn claims<const FMA: bool>(&self) -> Option<(Claims, [f64; 2])> {
        let Self {
            r2,
            d: [d1, d2],
            support2: [s1, s2],
            alpha: [a1, a2],
            det: [b1, b2],
            det_terms: [p1, p2],
        } = *self;
        // The inputs are finite here, and `min`/`max` without their NaN handling are one
        // instruction each.
        let min = |a: f64, b: f64| if a < b { a } else { b };
        let max = |a: f64, b: f64| if a > b { a } else { b };
        if !(min(min(r2, d1), d2) >= 1e-60 && max(max(r2, d1), d2) <= 1e60) {
            return None;
        }
        let support = (s1 + GAMMA * 3.0 * d1 * r2).sqrt() + (s2 + GAMMA * 3.0 * d2 * r2).sqrt();
        let rho1 = ((b1 - GAMMA * 6.0 * p1) / (a1 + GAMMA * 6.0 * d1 * d1 * r2)).sqrt();
        let rho2 = ((b2 - GAMMA * 6.0 * p2) / (a2 + GAMMA * 6.0 * d2 * d2 * r2)).sqrt();
        // A negative lower bound of det gives NaN, which fails the comparison: no claim.
        let claims = Claims::of::<FMA>(
            [support * (1.0 + SPHERE_MARGIN), 1.0 + SPHERE_MARGIN],
            [r2, rho1 + rho2],
        );
        Some((claims, [rho1, rho2]))
    }
}

/// The certificates at a guessed λ̂, for pairs the axis test leaves open (the second stage
/// of the verdict), from the geometry of the contact point (theory eqs. 8–10):
///
/// - **separating axis along the common normal** n ∝ Q(λ̂)⁻¹ r12 (eq. 8): separated if
///   √(nᵀQ₁n) + √(nᵀQ₂n) < |n·r12|. Along Q(λ)⁻¹ r12 this is at least as strong as
///   f(λ) > 1 (Cauchy–Schwarz on (1 − λ)nᵀQ₁n + λ nᵀQ₂n = n·r12);
/// - **a point inside both**: x₀(λ̂) of eq. 9, with norms a = ‖x₀ − c₁‖ in the metric of
///   Q₁⁻¹ and b = ‖x₀ − c₂‖ in that of Q₂⁻¹. If it lies outside one ellipsoid, say b > 1,
///   the point slid towards c₂ until b = K (just below 1) has, by the triangle inequality,
///   first norm at most s a + (1 − s) ‖r12‖₁ with s = K/b, where ‖r12‖₁ = 1/ρ₁ is known from
///   the axis test; likewise towards c₁.
///
/// λ̂ = ρ₁/(ρ₁ + ρ₂) from the radial extents of the axis test (exact for spheres), i.e.
/// Q(λ̂) ∝ M = ρ₂Q₁ + ρ₁Q₂, n = adj(M) r12 and x₀ − c₁ = (ρ₂/det M) Q₁ n. On the bench's
/// pairs it decides 25 390 of the 26 009 the axis test leaves (97.6 %), the point with its
/// slides 95.5 % of the overlapping ones; λ̂ = ½ decided 91.6 %, the point without slides
/// 64.8 % of the overlapping.
///
/// Rounding: the certificates are evaluated at the computed n and x₀, whatever their own
/// rounding errors, so only the evaluation needs bounds. With |Qᵢⱼ| ≤ d and |adj Qᵢⱼ| ≤ 2d²,
/// nᵀQn has Σ|terms| ≤ d (Σ|nⱼ|)², n·r12 has Σ|nⱼ r₁₂ⱼ|, and yᵀ adj Q y has ≤ 2d² (Σ|yⱼ|)²;
/// [`POINT_GAMMA`] times these (which also covers the rounding of y − r12) moves each to its
/// safe side, and [`SPHERE_MARGIN`] covers the square roots and products of the final
/// comparisons, whose terms are all positive. No claim is made unless each error term is
/// above 1e-280 (the absolute errors of underflowed terms are then negligible), and
/// overflow or a determinant bound ≤ 0 gives ∞ − ∞ or NaN, which claims nothing.
struct ContactPointTest {
    r12: [f64; 3],
    q: [Sym3; 2],
    adj: [Sym3; 2],
    d: [f64; 2],
    /// Lower bounds of det Qᵢ.
    det_lower: [f64; 2],
}

/// Rounding-error factor of the contact-point test's evaluations (at most about eight
/// roundings deep, plus the rounding of y − r12).
const POINT_GAMMA: f64 = 16.0 * f64::EPSILON;

impl ContactPointTest {
    /// The claims at λ̂ = ρ₁/(ρ₁ + ρ₂), given the radial extents ρᵢ (lower bounds, in units
    /// of |r12|) of the axis test.
    #[inline(always)]
    fn claims<const FMA: bool>(&self, [rho1, rho2]: [f64; 2]) -> Claims {
        const G: f64 = POINT_GAMMA;
        let Self {
            r12,
            q: [q1, q2],
            adj: [adj1, adj2],
            d: [d1, d2],
            det_lower: [b1, b2],
        } = self;
        let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let abs_sum = |a: &[f64; 3]| a[0].abs() + a[1].abs() + a[2].abs();
        let m_form: Sym3 = core::array::from_fn(|k| rho2 * q1[k] + rho1 * q2[k]);
        let adj_m = adjugate_generic(&m_form);
        // n = adj(M) r12 = det(M) M⁻¹ r12 ∝ Q(λ̂)⁻¹ r12, and Qᵢ n.
        let n = crate::sym::mat_vec(&adj_m, r12);
        let (w1, w2) = (crate::sym::mat_vec(q1, &n), crate::sym::mat_vec(q2, &n));
        let (h1, h2, g) = (dot(&n, &w1), dot(&n, &w2), dot(&n, r12));
        let sn = abs_sum(&n);
        let sg = (n[0] * r12[0]).abs() + (n[1] * r12[1]).abs() + (n[2] * r12[2]).abs();
        let (e1, e2, eg) = (G * d1 * sn * sn, G * d2 * sn * sn, G * sg);
        let support = (h1 + e1).sqrt() + (h2 + e2).sqrt();

        // x₀ − c₁ = (1 − λ̂) Q₁ Q(λ̂)⁻¹ r12 = (ρ₂ / det M) Q₁ n (eq. 9a), and x₀ − c₂.
        let y = w1.map(|x| x * (rho2 / det_generic(&m_form, &adj_m)));
        let z = [y[0] - r12[0], y[1] - r12[1], y[2] - r12[2]];
        let (sy, sz) = (abs_sum(&y), abs_sum(&z));
        let (ey, ez) = (G * 2.0 * d1 * d1 * sy * sy, G * 2.0 * d2 * d2 * sz * sz);
        // a = av/ab and b = bv/bb, with numerators rounded up and denominators down.
        let [av, ab, bv, bb] = sqrt4::<FMA>([
            quadratic_form_generic(&outer_generic::<f64>(&y), adj1) + ey,
            *b1,
            quadratic_form_generic(&outer_generic::<f64>(&z), adj2) + ez,
            *b2,
        ]);
        // The point itself: max(a, b) < 1, times ab bb.
        let larger = |x: f64, y: f64| select_gt::<FMA>(x, y, x, y);
        let (inside, unit) = (larger(av * bb, bv * ab), ab * bb);
        // Slid towards c₂ (if b > K): K a/b + (1 − K/b)/ρ₁ < 1, times b ρ₁ ab bb; towards
        // c₁ (if a > K) in the same way. Each select picks a valid certificate either way.
        const K: f64 = 1.0 - 1e-9;
        let l1 = select_gt::<FMA>(bv, K * bb, K * av * bb * rho1 + bv * ab, inside);
        let r1 = select_gt::<FMA>(bv, K * bb, bv * ab * rho1 + K * unit, unit);
        let l2 = select_gt::<FMA>(av, K * ab, K * bv * ab * rho2 + av * bb, inside);
        let r2 = select_gt::<FMA>(av, K * ab, av * bb * rho2 + K * unit, unit);
        // The sign of a difference is exact (x − y < 0 iff x < y): the smaller one is
        // negative if either certificate holds. 0 · (sum of the roots) turns an infinite or
        // NaN root into NaN.
        let (o1, o2) = (
            l1 * (1.0 + SPHERE_MARGIN) - r1,
            l2 * (1.0 + SPHERE_MARGIN) - r2,
        );
        let outside = select_gt::<FMA>(o2, o1, o1, o2) + 0.0 * (av + ab + bv + bb);

        // Too small an error term: no claim (NaN).
        let smallest = e1.min(e2).min(eg).min(ey).min(ez);
        let valid = select_gt::<FMA>(smallest, 1e-280, 0.0, f64::NAN);
        Claims::of::<FMA>(
            [support * (1.0 + SPHERE_MARGIN) + valid, outside + valid],
            [g.abs() - eg, 0.0],
        )
    }
}

/// Four square roots in one instruction.
#[inline(always)]
fn sqrt4<const FMA: bool>(x: [f64; 4]) -> [f64; 4] {
    #[cfg(target_arch = "x86_64")]
    if FMA {
        use core::arch::x86_64::*;
        // SAFETY: `FMA` is true only in the AVX2 + FMA build of a dispatched function,
        // after the processor was checked to have AVX2.
        return unsafe {
            let mut out = [0.0; 4];
            _mm256_storeu_pd(
                out.as_mut_ptr(),
                _mm256_sqrt_pd(_mm256_loadu_pd(x.as_ptr())),
            );
            out
        };
    }
    x.map(f64::sqrt)
}

/// The two claims of a test, `separated` (bit 0) and `overlapping` (bit 1), as the bits of
/// one integer, so that the verdict is data and only "decided?" is a branch. Written as
/// two `bool`s, the compiler splits the test into one branch per claim, and which claim holds
/// is a coin toss on random pairs: a mispredicted branch at the end of a long chain of
/// square roots and divisions.
#[derive(Clone, Copy)]
struct Claims(u32);

impl Claims {
    /// Claims lhs[0] < rhs[0] (separated) and lhs[1] < rhs[1] (overlapping); NaN claims
    /// nothing.
    #[inline(always)]
    fn of<const FMA: bool>(lhs: [f64; 2], rhs: [f64; 2]) -> Self {
        #[cfg(target_arch = "x86_64")]
        if FMA {
            use core::arch::x86_64::*;
            // SAFETY: `FMA` is true only in the AVX2 + FMA build of a dispatched function,
            // after the processor was checked to have AVX2.
            return Self(unsafe {
                let l = _mm_set_pd(lhs[1], lhs[0]);
                let r = _mm_set_pd(rhs[1], rhs[0]);
                _mm_movemask_pd(_mm_cmp_pd::<_CMP_LT_OQ>(l, r)) as u32
            });
        }
        Self(u32::from(lhs[0] < rhs[0]) | (u32::from(lhs[1] < rhs[1]) << 1))
    }

    #[inline(always)]
    fn verdict(self) -> Option<bool> {
        (self.0 != 0).then_some(self.0 & 1 == 0)
    }
}

/// A cheap bound on the rounding error of the `f64` Bernstein coefficients, from the largest
/// diagonal entries dᵢ of Qᵢ (every |Qᵢⱼ| ≤ dᵢ for a positive definite matrix): Σ|terms| of
/// b(λ) is at most k_b D^dim and of a(λ) at most k_a |r|² D^(dim−1), D = (1 − λ) d₁ + λ d₂.
struct CrudeBound {
    d1: f64,
    d2: f64,
    r2: f64,
    k_b: f64,
    k_a: f64,
    dim: i32,
}

impl CrudeBound {
    /// Relative error bound of f at the odds u (see [`crate::poly::OddsForm`]) of the oriented
    /// pencil, given the unnormalised A(u) and B(u). With s = 1/(1 + u), a = s²A, b = s³B and
    /// D = s E, E = d₁ + u d₂ (d₁, d₂ swapped when the pencil is reversed), the bound
    /// k_b D^dim / b + k_a |r|² D^(dim−1) / a is s^(dim−3) (k_b E^dim / B + k_a |r|² E^(dim−1) / A):
    /// one division.
    #[inline(always)]
    fn relative<const FMA: bool>(&self, u: f64, side: Side, a: f64, b: f64) -> f64 {
        let d1 = side.pick::<FMA>(self.d1, self.d2);
        let d2 = side.pick::<FMA>(self.d2, self.d1);
        let e = d1 + u * d2;
        let (en, w) = if self.dim == 3 {
            (e * e, 1.0)
        } else {
            (e, 1.0 + u)
        };
        const GAMMA: f64 = 10.0 * 0.5 * f64::EPSILON;
        GAMMA * w * (self.k_b * en * e * a + self.k_a * self.r2 * en * b) / (a * b)
            + 8.0 * 0.5 * f64::EPSILON
    }
}

/// One side of the bracket of λ₀ with the tangent line of f there.
#[derive(Clone, Copy)]
struct Tangent {
    lambda: f64,
    f: f64,
    slope: f64,
}

/// Upper bound of a concave f on [0, 1] from its tangents at the bracket ends: the intersection
/// of the two lines, or the one line at the far end of the interval.
fn tangent_bound(lo: Option<Tangent>, hi: Option<Tangent>) -> f64 {
    match (lo, hi) {
        // Rounding noise in the sign of f′ next to the maximiser can leave the two sides out
        // of order; no bound is claimed then.
        (Some(l), Some(h)) if l.lambda > h.lambda => f64::INFINITY,
        (Some(l), Some(h)) => {
            // f_l + s_l (x − λ_l) = f_h + s_h (x − λ_h), s_l > 0 > s_h.
            let x = (h.f - l.f + l.slope * l.lambda - h.slope * h.lambda) / (l.slope - h.slope);
            l.f + l.slope * (x.clamp(l.lambda, h.lambda) - l.lambda)
        }
        (Some(l), None) => l.f + l.slope * (1.0 - l.lambda),
        (None, Some(h)) => h.f - h.slope * h.lambda,
        (None, None) => f64::INFINITY,
    }
}

/// The Halley iteration of [`crate::contact_function`] (on the odds u = λ / (1 − λ), see
/// [`crate::poly::OddsForm`]), stopped as soon as a lower bound f(λ) exceeds 1 or the tangent
/// upper bound falls below 1, beyond the rounding margin. `None` when neither happens: the
/// caller must compute μ² accurately.
///
/// At each iterate the terms of the step give the bounds almost for free: f = u A / ((1 + u) B)
/// (eq. 15) and, since p = u (1 + u) A B (ln f)′(u) and dλ/du = (1 + u)⁻², the slope in λ is
/// df/dλ = p / B². The tangent lines are taken in the solver's orientation (λ or 1 − λ), in
/// which f is concave as well.
#[inline(always)]
fn bounded_search<const FMA: bool>(rational: &RationalForm, bound: &CrudeBound) -> Option<bool> {
    if !is_positive(rational.alpha.iter().fold(0.0_f64, |m, &x| m.max(x))) {
        // r12 = 0: μ² = 0.
        return Some(true);
    }
    let scale = Scale::of(rational)?;
    let (form, u0, side) = orient::<FMA>(&scale.apply(rational));
    // The step's polynomials are formed only if the first iterate does not decide (most
    // verdicts need only p there).
    let p_coefficients = odds_numerator(&form.alpha, &form.beta);
    let mut odds: Option<OddsForm<f64>> = None;
    let mut search = OddsSearch::new(u0, crate::poly::Tiny::NORMALISED);
    let [a0, a1, a2] = form.alpha;
    let [b0, b1, b2, b3] = form.beta;
    let ratio = scale.ratio();
    let (a_scale, b_scale) = scale.powers();
    let (mut lo, mut hi): (Option<Tangent>, Option<Tangent>) = (None, None);
    for iteration in 0..MAX_ITERATIONS {
        let u = search.u;
        let p = odds_numerator_at::<FMA>(&p_coefficients, u);
        let u2 = u * u;
        let big_a = (a0 + a1 * u) + a2 * u2;
        let big_b = (b0 + b1 * u) + (b2 + b3 * u) * u2;
        let s = 1.0 / (1.0 + u);
        let f = u * big_a / ((1.0 + u) * big_b) * ratio;
        let err = bound.relative::<FMA>(u, side, big_a * a_scale, big_b * b_scale);
        // NaN (a degenerate pencil) gives up too.
        if !is_positive(1e-3 - err) {
            return None;
        }
        let tangent = Tangent {
            lambda: u * s,
            f,
            slope: p / (big_b * big_b) * ratio,
        };
        let upper = if iteration == 0 {
            // The first tangent alone bounds f at the far end of [0, 1]: at 1 where f rises
            // (p > 0), at 0 where it falls; what [`tangent_bound`] computes, written as a
            // select so that the side, a coin toss, costs no mispredicted branch.
            let end = if p > 0.0 { 1.0 } else { 0.0 };
            tangent.f + tangent.slope * (end - tangent.lambda)
        } else {
            if p > 0.0 {
                lo = Some(tangent);
            } else {
                hi = Some(tangent);
            }
            tangent_bound(lo, hi)
        };
        // A lower bound above 1 proves separation, an upper bound below 1 overlap (the slope
        // carries a larger relative error than f; 10× the margin of f covers it). Both tests
        // before one branch: the verdict itself is data, not control flow.
        let claims = Claims::of::<FMA>(
            [1.0, upper + 10.0 * err * (f + upper)],
            [f * (1.0 - err), 1.0],
        );
        if let Some(verdict) = claims.verdict() {
            return Some(verdict);
        }
        if iteration == 0 {
            if p > 0.0 {
                lo = Some(tangent);
            } else {
                hi = Some(tangent);
            }
        }
        if search.done {
            return None;
        }
        let odds = odds.get_or_insert_with(|| OddsForm::new(&form.alpha, &form.beta));
        search.advance::<FMA>(odds.halley_terms::<FMA>(u).step_terms());
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The axis test on one pair, built exactly as [`overlap`](crate::overlap) builds it, and the
    /// contact-point test where the axis test leaves the pair open.
    fn stage_verdicts<const FMA: bool>(
        r12: &[f64; 3],
        q1: &Sym3,
        q2: &Sym3,
    ) -> (Option<bool>, Option<bool>) {
        let (adj1, adj2) = (adjugate_generic(q1), adjugate_generic(q2));
        let (det1, det2) = (det_generic(q1, &adj1), det_generic(q2, &adj2));
        let (p1, p2) = (q1[0] * q1[3] * q1[5], q2[0] * q2[3] * q2[5]);
        let axis = AxisTest::new(r12, [q1, q2], [&adj1, &adj2], [det1, det2], [p1, p2]);
        let Some((claims, extents)) = axis.claims::<FMA>() else {
            return (None, None);
        };
        if let Some(verdict) = claims.verdict() {
            return (Some(verdict), None);
        }
        let test = ContactPointTest {
            r12: *r12,
            q: [*q1, *q2],
            adj: [adj1, adj2],
            d: axis.d,
            det_lower: [det1 - GAMMA * 6.0 * p1, det2 - GAMMA * 6.0 * p2],
        };
        (None, test.claims::<FMA>(extents).verdict())
    }

    /// A random pair (semi-axes 10^(−decades·U), U uniform, random orientations and
    /// direction) with the centres placed so that μ² = `target(next)`, the whole
    /// configuration then scaled by k (r by k, Q by k², which leaves μ² unchanged); and μ²
    /// in double-double.
    fn random_pair(
        next: &mut impl FnMut() -> f64,
        decades: f64,
        k: f64,
        target: impl FnOnce(&mut dyn FnMut() -> f64) -> f64,
    ) -> ([f64; 3], Sym3, Sym3, f64) {
        let mut ellipsoid = |decades: f64| {
            let axes: [f64; 3] = core::array::from_fn(|_| 10f64.powf(-decades * next()));
            let q: [f64; 4] = core::array::from_fn(|_| 2.0 * next() - 1.0);
            crate::shape::from_axes_quaternion(&axes, &q).unwrap()
        };
        let (q1, q2) = (ellipsoid(decades), ellipsoid(decades));
        let dir = [next() - 0.5, next() - 0.5, next() - 0.5];
        let unit = crate::contact_function_refined(&dir, &q1, &q2).unwrap().mu2;
        let target = target(next);
        let r = dir.map(|x| x * (target / unit).sqrt() * k);
        let (q1, q2) = (q1.map(|x| x * k * k), q2.map(|x| x * k * k));
        let exact = crate::contact_function_refined(&r, &q1, &q2).unwrap().mu2;
        (r, q1, q2, exact)
    }

    /// A claim (`verdict`: overlap) agrees with μ² = `exact` and is not made within the
    /// error of μ² (1e-15 here) of tangency.
    fn assert_right(pair: usize, verdict: bool, exact: f64) {
        assert!(
            (exact - 1.0).abs() > 1e-13,
            "pair {pair}: a claim at μ² = {exact}"
        );
        assert_eq!(verdict, exact < 1.0, "pair {pair}: μ² = {exact}");
    }

    fn axis_verdict(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Option<bool> {
        stage_verdicts::<false>(r12, q1, q2).0
    }

    /// Every claim of the contact-point test agrees with μ² (double-double, error ≤ 1e-15
    /// here), in the portable build and, where the processor has them, with the AVX2
    /// selects and square roots: on needles and discs of aspect ratio up to 1e6, pairs
    /// within 1e-9 of tangency and within 5 % of it, and whole configurations scaled by
    /// 10^±25 and 10^±45.
    #[test]
    fn contact_point_claims_are_right() {
        let mut rng = testkit::Rng::new(0xC0417u64);
        let mut next = move || rng.uniform();
        let (mut open, mut decided, mut decided_scaled, mut decided_near) = (0, 0, 0, 0);
        for i in 0..40_000 {
            let decades = [0.0, 1.0, 2.0, 6.0][i % 4];
            let k = [1.0, 1e-45, 1e45, 1e-25, 1e25][(i / 12) % 5];
            let (r, q1, q2, exact) = random_pair(&mut next, decades, k, |next| match (i / 4) % 3 {
                0 => 2f64.powf(0.6 * next() - 0.3),
                1 => 1.0 + 0.1 * (next() - 0.5),
                _ => 1.0 + 2e-9 * (next() - 0.5),
            });
            let mut builds = vec![stage_verdicts::<false>(&r, &q1, &q2)];
            #[cfg(target_arch = "x86_64")]
            if simd::has_avx2_fma() {
                builds.push(stage_verdicts::<true>(&r, &q1, &q2));
            }
            for (axis, point) in builds {
                let ran = axis.is_none() && (k == 1.0 || k == 1e25 || k == 1e-25);
                open += usize::from(ran && (exact - 1.0).abs() > 1e-6);
                if let Some(verdict) = point {
                    assert_right(i, verdict, exact);
                    decided += 1;
                    decided_scaled += usize::from(k != 1.0);
                    decided_near += usize::from((exact - 1.0).abs() < 0.05);
                }
            }
        }
        // Not vacuous: it decides most of what the axis test leaves open (and is not within
        // 1e-6 of tangency), also at scales 1e±25 and within 5 % of tangency.
        // (Measured: 9 744 of 21 776, 4 870 scaled, 5 866 near.)
        assert!(decided > open / 3, "{decided} of {open}");
        assert!(decided_scaled > 2_000, "{decided_scaled}");
        assert!(decided_near > 2_000, "{decided_near}");
    }

    /// Every claim of the axis test agrees with μ² (double-double, error ≤ 1e-15 here), on
    /// spheres (where the separating-axis bound is exact, so tangent pairs sit right at its
    /// margin), needles and discs of aspect ratio up to 1e4, pairs within 1e-9 of tangency, and
    /// whole configurations scaled by 10^±25 and 10^±45 (the latter beyond the test's range,
    /// where it must abstain).
    #[test]
    fn axis_test_claims_are_right() {
        let mut rng = testkit::Rng::new(0xA515u64);
        let mut next = move || rng.uniform();
        let (mut decided, mut decided_scaled, mut decided_spheres) = (0, 0, 0);
        for i in 0..20_000 {
            let decades = [0.0, 1.0, 4.0][i % 3];
            let k = [1.0, 1e-45, 1e45, 1e-25, 1e25][(i / 4) % 5];
            let (r, q1, q2, exact) = random_pair(&mut next, decades, k, |next| match i % 4 {
                0 | 1 => 2f64.powf(6.0 * next() - 3.0),
                _ => 1.0 + 2e-9 * (next() - 0.5),
            });
            if let Some(verdict) = axis_verdict(&r, &q1, &q2) {
                assert_right(i, verdict, exact);
                decided += 1;
                decided_scaled += usize::from(k != 1.0);
                decided_spheres += usize::from(decades == 0.0);
            }
        }
        // The test is not vacuous: it decides most far-from-tangent pairs, also at scales
        // 1e±25, and on spheres.
        assert!(decided > 5_000, "{decided}");
        assert!(decided_scaled > 2_000, "{decided_scaled}");
        assert!(decided_spheres > 2_000, "{decided_spheres}");
    }
}
