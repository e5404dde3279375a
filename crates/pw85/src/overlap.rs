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
//! 3. some iterate λ of the contact-function iteration has f(λ) > 1: no overlap;
//! 4. the tangent lines at the iterates bound max f below 1: overlap;
//!
//! each test with a margin for the rounding error of f. Pairs still undecided (|μ² − 1| within
//! that margin, or a badly conditioned pencil) get the full [`crate::contact_function`] with
//! its double-double refinement, and the verdict μ² < 1.

use crate::arith::Mag;
use crate::arith::is_positive;
use crate::contact::{
    Scale, Side, check_finite, check_inputs_finite, check_positive_definite,
    check_positive_definite_2d, orient,
};
use crate::dispatch::multiversion;
use crate::error::{Argument, Error};
use crate::poly::{
    OddsForm, OddsSearch, RationalForm, coefficients_2d, odds_numerator, odds_numerator_at,
};
use crate::sym::{
    Sym2, Sym3, adjugate_generic, det_generic, frobenius_generic, mixed_adjugate_generic,
    outer_generic, quadratic_form_generic,
};

/// Rounding-error factor of the short expression trees of the axis test (at most about six
/// roundings deep; 10 u as in the contact function's coefficients).
const GAMMA: f64 = 10.0 * 0.5 * f64::EPSILON;

/// Relative safety factor on the geometric sphere tests (their square roots and sums round).
const SPHERE_MARGIN: f64 = 1e-12;
/// Iterations of the bounded search before handing over to the full contact function.
const MAX_ITERATIONS: u32 = 12;

multiversion! {
    /// Whether two ellipsoids overlap: μ²(r12, Q1, Q2) < 1 (theory eq. 6), with the arguments and
    /// storage of [`crate::contact_function`]. Tangent ellipsoids (μ² = 1) do not overlap.
    ///
    /// Stops as soon as the answer is certain: the projections on the centre line disjoint (no
    /// overlap), the segment between the centres covered by the two ellipsoids' radial extents
    /// (overlap), an iterate λ with f(λ) > 1 (no overlap, since f(λ) ≤ μ²), or
    /// tangent lines of the concave f bounding max f below 1 (overlap), each with a margin for the
    /// rounding error of f. Only pairs within that margin of tangency, or with a badly conditioned
    /// pencil, pay for the full [`crate::contact_function`].
    ///
    /// # Errors
    /// As [`crate::contact_function`].
    ///
    /// # Example
    /// ```
    /// let needle = pw85::spheroid(0.1, 1.0, &[1.0, 0.0, 0.0])?;
    /// // Side by side, 0.15 apart across their thin direction: they overlap...
    /// assert!(pw85::overlap(&[0.0, 0.15, 0.0], &needle, &needle)?);
    /// // ...and 0.25 apart they do not.
    /// assert!(!pw85::overlap(&[0.0, 0.25, 0.0], &needle, &needle)?);
    /// # Ok::<(), pw85::Error>(())
    /// ```
    pub fn overlap(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<bool, Error>
        => fused overlap_portable;
}

#[inline(always)]
fn overlap_portable<const FMA: bool>(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<bool, Error> {
    check_inputs_finite::<FMA>(r12, q1, q2)?;
    let adj1 = adjugate_generic(q1);
    let adj2 = adjugate_generic(q2);
    let det1 = det_generic(q1, &adj1);
    let det2 = det_generic(q2, &adj2);
    // Q11 Q22 Q33 bounds each of the six terms of det Q (|Qᵢⱼ| ≤ √(QᵢᵢQⱼⱼ)).
    let (p1, p2) = (q1[0] * q1[3] * q1[5], q2[0] * q2[3] * q2[5]);
    check_positive_definite(Argument::Q1, q1, det1, det_magnitude(q1, det1, p1))?;
    check_positive_definite(Argument::Q2, q2, det2, det_magnitude(q2, det2, p2))?;

    let rr = outer_generic::<f64>(r12);
    let r2 = rr[0] + rr[3] + rr[5];
    let (d1, d2) = (q1[0].max(q1[3]).max(q1[5]), q2[0].max(q2[3]).max(q2[5]));
    // α₀ = r12ᵀ adj Q1 r12 and α₂ (eq. 16a at λ = 0, 1): the radial extents need them, and
    // so do the coefficients if the axis test does not decide.
    let alpha0 = quadratic_form_generic(&rr, &adj1);
    let alpha2 = quadratic_form_generic(&rr, &adj2);
    let axis = AxisTest {
        r2,
        d: [d1, d2],
        support2: [
            quadratic_form_generic(&rr, q1),
            quadratic_form_generic(&rr, q2),
        ],
        alpha: [alpha0, alpha2],
        det: [det1, det2],
        det_terms: [p1, p2],
    };
    if let Some(verdict) = axis.verdict() {
        return Ok(verdict);
    }

    let mixed = mixed_adjugate_generic(q1, q2);
    let fast = RationalForm {
        alpha: [alpha0, quadratic_form_generic(&rr, &mixed), alpha2],
        beta: [
            det1,
            frobenius_generic(&adj1, q2),
            frobenius_generic(&adj2, q1),
            det2,
        ],
    };
    let bound = CrudeBound {
        d1,
        d2,
        r2,
        k_b: 18.0,
        k_a: 6.0,
        dim: 3,
    };
    match bounded_search::<FMA>(&fast, &bound) {
        Some(verdict) => Ok(verdict),
        None => Ok(crate::contact_function(r12, q1, q2)?.mu2 < 1.0),
    }
}

multiversion! {
    /// Whether two ellipses overlap, with the arguments of [`crate::contact_function_2d`].
    ///
    /// # Errors
    /// As [`crate::contact_function_2d`].
    pub fn overlap_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<bool, Error>
        => fused overlap_2d_portable;
}

#[inline(always)]
fn overlap_2d_portable<const FMA: bool>(
    r12: &[f64; 2],
    q1: &Sym2,
    q2: &Sym2,
) -> Result<bool, Error> {
    check_finite(Argument::R12, r12)?;
    check_finite(Argument::Q1, q1)?;
    check_finite(Argument::Q2, q2)?;
    check_positive_definite_2d(Argument::Q1, q1)?;
    check_positive_definite_2d(Argument::Q2, q2)?;
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
        None => Ok(crate::contact_function_2d(r12, q1, q2)?.mu2 < 1.0),
    }
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
/// separated, 39.4 % overlapping), the spheres decided 9.8 %. The first iterate of the
/// search then decides 22.0 % of all pairs, the second 3.8 %, later ones 0.2 %.
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
    #[inline(always)]
    fn verdict(&self) -> Option<bool> {
        let Self {
            r2,
            d: [d1, d2],
            support2: [s1, s2],
            alpha: [a1, a2],
            det: [b1, b2],
            det_terms: [p1, p2],
        } = *self;
        let lo = r2.min(d1).min(d2);
        let hi = r2.max(d1).max(d2);
        if !(lo >= 1e-60 && hi <= 1e60) {
            return None;
        }
        let support = (s1 + GAMMA * 3.0 * d1 * r2).sqrt() + (s2 + GAMMA * 3.0 * d2 * r2).sqrt();
        let extent = ((b1 - GAMMA * 6.0 * p1) / (a1 + GAMMA * 6.0 * d1 * d1 * r2)).sqrt()
            + ((b2 - GAMMA * 6.0 * p2) / (a2 + GAMMA * 6.0 * d2 * d2 * r2)).sqrt();
        // Both tests before one branch (see `bounded_search`). A negative lower bound of det
        // gives NaN, which fails the comparison: no claim.
        let separated = support * (1.0 + SPHERE_MARGIN) < r2;
        let overlapping = extent > 1.0 + SPHERE_MARGIN;
        (separated || overlapping).then_some(!separated)
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
        let separated = f * (1.0 - err) > 1.0;
        let overlapping = upper + 10.0 * err * (f + upper) < 1.0;
        if separated || overlapping {
            return Some(!separated);
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

    /// The axis test on one pair, built exactly as [`overlap`] builds it.
    fn axis_verdict(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Option<bool> {
        let (adj1, adj2) = (adjugate_generic(q1), adjugate_generic(q2));
        let rr = outer_generic::<f64>(r12);
        let r2 = rr[0] + rr[3] + rr[5];
        AxisTest {
            r2,
            d: [q1[0].max(q1[3]).max(q1[5]), q2[0].max(q2[3]).max(q2[5])],
            support2: [
                quadratic_form_generic(&rr, q1),
                quadratic_form_generic(&rr, q2),
            ],
            alpha: [
                quadratic_form_generic(&rr, &adj1),
                quadratic_form_generic(&rr, &adj2),
            ],
            det: [det_generic(q1, &adj1), det_generic(q2, &adj2)],
            det_terms: [q1[0] * q1[3] * q1[5], q2[0] * q2[3] * q2[5]],
        }
        .verdict()
    }

    /// Every claim of the axis test agrees with μ² (double-double, error ≤ 1e-15 here), on
    /// spheres (where the separating-axis bound is exact, so tangent pairs sit right at its
    /// margin), needles and discs of aspect ratio up to 1e4, pairs within 1e-9 of tangency, and
    /// whole configurations scaled by 10^±25 and 10^±45 (the latter beyond the test's range,
    /// where it must abstain).
    #[test]
    fn axis_test_claims_are_right() {
        let mut next = crate::test_rng::uniform_stream(0xA515u64);
        let (mut decided, mut decided_scaled, mut decided_spheres) = (0, 0, 0);
        for i in 0..20_000 {
            let mut ellipsoid = |decades: f64| {
                let axes: [f64; 3] = core::array::from_fn(|_| 10f64.powf(-decades * next()));
                let q: [f64; 4] = core::array::from_fn(|_| 2.0 * next() - 1.0);
                crate::shape::from_axes_quaternion(&axes, &q).unwrap()
            };
            let decades = [0.0, 1.0, 4.0][i % 3];
            let (q1, q2) = (ellipsoid(decades), ellipsoid(decades));
            let dir = [next() - 0.5, next() - 0.5, next() - 0.5];
            let unit = crate::contact_function_refined(&dir, &q1, &q2).unwrap().mu2;
            let target = match i % 4 {
                0 | 1 => 2f64.powf(6.0 * next() - 3.0),
                _ => 1.0 + 2e-9 * (next() - 0.5),
            };
            // Scaling r by k and Q by k² leaves μ² unchanged.
            let k = [1.0, 1e-45, 1e45, 1e-25, 1e25][(i / 4) % 5];
            let r = dir.map(|x| x * (target / unit).sqrt() * k);
            let (q1, q2) = (q1.map(|x| x * k * k), q2.map(|x| x * k * k));
            let exact = crate::contact_function_refined(&r, &q1, &q2).unwrap().mu2;
            if let Some(verdict) = axis_verdict(&r, &q1, &q2) {
                assert!(
                    (exact - 1.0).abs() > 1e-13,
                    "pair {i}: a claim at μ² = {exact}"
                );
                assert_eq!(verdict, exact < 1.0, "pair {i}: μ² = {exact}");
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
