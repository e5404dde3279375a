//! Pairs at the edges of the double range: every finite input gets its right answer.
//!
//! The fast path forms products of up to six input entries (the coefficients α, β of eq. 16),
//! which overflow for entries beyond about 2²⁴⁰ and underflow for tiny ellipsoids or tiny
//! separations. Two exact symmetries of the contact function bring any pair back into range:
//!
//! - **Affine invariance** (eq. 6): for an invertible A, r12 → A r12 and Qᵢ → A Qᵢ Aᵀ leave
//!   f(λ) and so μ² and λ₀ unchanged. With A = D diagonal and made of powers of two, each
//!   product in the coefficient formulas gains the same power of two (det D² for α and β), so
//!   no bit of the result changes: this only moves exponents.
//! - **Homogeneity**: μ²(s r12, Q1, Q2) = s² μ²(r12, Q1, Q2), λ₀ unchanged; with s a power of
//!   two, μ² is scaled back exactly (to +∞ or 0 where the true value is beyond the double
//!   range).
//!
//! D is chosen so that max(Q1ᵢᵢ, Q2ᵢᵢ) lies in [1, 4) on every axis, then s so that the largest
//! entry of D r12 lies in [1, 2). Positive definiteness is decided on each matrix balanced by
//! its own diagonal, a test that does not depend on units.
//!
//! One case remains out of reach of any rescaling shared by both matrices: an ellipsoid so much
//! smaller than the other (radius ratio beyond about 1e50) that the products of its own entries
//! underflow. Its size is then far below the larger one's rounding: μ² of the pair lies
//! between μ² with the small one replaced by a point and with it replaced by the ball of
//! radius 2⁻¹⁵⁰ that contains it, and these agree to 2⁻⁴⁷ relative whenever the larger
//! ellipsoid's smallest semi-axis exceeds 2⁻¹⁰² (after balancing). The ball stands in for it.
//!
//! Everything here runs only when the fast path meets an input outside its window, so the
//! ordinary path pays for one multiplication in its finiteness probe.

use crate::Contact;
use crate::contact::{check_positive_definite, contact_function_unrescued};
use crate::error::{Argument, Error};
use crate::sym::{Sym2, Sym3};

/// Entries at or above 2^(`UPPER` + 1) leave the fast path: its products of six entries stay
/// below 2¹⁰⁰⁰.
pub(crate) const UPPER: i32 = 240;

/// The probe's multiplier: x · `PROBE` overflows to ±∞ exactly when |x| ≥ about 2^(`UPPER` + 1),
/// so that x · P − x · P is NaN for those entries as for NaN and ±∞.
pub(crate) const PROBE: f64 = pow2(1023 - UPPER);

/// Largest entries below 2^−`LOWER` (r12 when non-zero, either Q) are rescaled too: the
/// products of the coefficients would approach the subnormal range.
const LOWER: i32 = 200;

/// The radius² of the ball that stands in for a vanishing ellipsoid (see the module docs).
const STAND_IN: f64 = pow2(-300);

/// 2^e for e in [−1022, 1023].
const fn pow2(e: i32) -> f64 {
    f64::from_bits(((e + 1023) as u64) << 52)
}

/// `r12` and the forms scaled by 2^−k and 4^−k, with k chosen so that the largest form entry
/// lies in [1, 4): a uniform scaling, under which f(λ) and μ² are invariant, that brings
/// ordinary pairs of any size into the fast path's window.
pub(crate) fn uniformly_rescaled(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> ([f64; 3], Sym3, Sym3) {
    let k = uniform_exponent(q1, q2);
    (
        r12.map(|x| scale_by_power_of_two(x, -k)),
        q1.map(|x| scale_by_power_of_two(x, -2 * k)),
        q2.map(|x| scale_by_power_of_two(x, -2 * k)),
    )
}

/// The k of [`uniformly_rescaled`]: lengths are divided by 2^k, forms by 4^k.
pub(crate) fn uniform_exponent(q1: &Sym3, q2: &Sym3) -> i32 {
    let largest = q1.iter().chain(q2).fold(0.0_f64, |m, x| m.max(x.abs()));
    if largest > 0.0 && largest.is_finite() {
        exponent(largest).div_euclid(2)
    } else {
        0
    }
}

/// x · 2^e, exact unless the result overflows (±∞) or is subnormal (rounded once, as a
/// product into that range is).
pub(crate) fn scale_by_power_of_two(x: f64, e: i32) -> f64 {
    let mut x = x;
    let mut e = e;
    while e > 1000 {
        x *= pow2(1000);
        e -= 1000;
    }
    while e < -1000 {
        // Two steps keep the intermediate normal, so only the last product can round.
        x *= pow2(-1000);
        e += 1000;
    }
    x * pow2(e)
}

/// The binary exponent of a finite non-zero x: x = m · 2^e with 1 ≤ |m| < 2.
fn exponent(x: f64) -> i32 {
    let biased = ((x.to_bits() >> 52) & 0x7ff) as i32;
    if biased == 0 {
        // Subnormal: the leading bit of the fraction.
        let fraction = x.to_bits() & ((1u64 << 52) - 1);
        -1022 - (fraction.leading_zeros() as i32 - 12) - 1
    } else {
        biased - 1023
    }
}

/// A symmetric form in packed storage, 2×2 or 3×3: what the rescaling needs to know of it.
pub(crate) trait Form: Copy {
    /// 2 or 3.
    const DIM: usize;
    /// For each stored entry, its row and column.
    const ENTRIES: &'static [(usize, usize)];
    /// The stored entries.
    fn entries(&self) -> &[f64];
    /// Mutable stored entries.
    fn entries_mut(&mut self) -> &mut [f64];
    /// Diagonal entry i.
    fn diagonal(&self, i: usize) -> f64 {
        let k = Self::ENTRIES
            .iter()
            .position(|&(r, c)| r == i && c == i)
            .unwrap_or(0);
        self.entries()[k]
    }
    /// The matrix s · I.
    fn scaled_identity(s: f64) -> Self;
    /// Sylvester's criterion, with the exact fallback of the fast path's check.
    fn check_positive_definite(argument: Argument, q: &Self) -> Result<(), Error>;
}

impl Form for Sym3 {
    const DIM: usize = 3;
    const ENTRIES: &'static [(usize, usize)] = &[(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
    fn entries(&self) -> &[f64] {
        self
    }
    fn entries_mut(&mut self) -> &mut [f64] {
        self
    }
    fn scaled_identity(s: f64) -> Self {
        [s, 0.0, 0.0, s, 0.0, s]
    }
    fn check_positive_definite(argument: Argument, q: &Self) -> Result<(), Error> {
        // An infinite magnitude sends the order-3 minor to its exact evaluation: this path is
        // rare, and the balanced matrix may not be positive definite, where no cheap bound
        // on the determinant's terms holds.
        let det = crate::sym::det_generic(q, &crate::sym::adjugate_generic(q));
        check_positive_definite(argument, q, det, f64::INFINITY)
    }
}

impl Form for Sym2 {
    const DIM: usize = 2;
    const ENTRIES: &'static [(usize, usize)] = &[(0, 0), (0, 1), (1, 1)];
    fn entries(&self) -> &[f64] {
        self
    }
    fn entries_mut(&mut self) -> &mut [f64] {
        self
    }
    fn scaled_identity(s: f64) -> Self {
        [s, 0.0, s]
    }
    fn check_positive_definite(argument: Argument, q: &Self) -> Result<(), Error> {
        crate::contact::check_positive_definite_2d(argument, q)
    }
}

/// Whether the pair lies in the fast path's window: the largest entry of r12 (when non-zero)
/// and of each matrix within [2^−`LOWER`, 2^(`UPPER` + 1)).
pub(crate) fn within_window<Q: Form>(r12: &[f64], q1: &Q, q2: &Q) -> bool {
    let largest = |xs: &[f64]| xs.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let inside = |m: f64| m >= pow2(-LOWER) && m < pow2(UPPER + 1);
    let r = largest(r12);
    (r == 0.0 || inside(r)) && inside(largest(q1.entries())) && inside(largest(q2.entries()))
}

/// Sylvester's criterion on `q` balanced by its own diagonal (D q D with Dᵢᵢ = 2^−⌊eᵢ/2⌋ for
/// qᵢᵢ = mᵢ 2^eᵢ): positive definiteness does not depend on the units, and neither does this
/// test. The value of a failing minor is scaled back to `q`'s units where that stays within the
/// double range (else the balanced matrix's minor, of the same sign, is given).
pub(crate) fn check_positive_definite_balanced<Q: Form>(
    argument: Argument,
    q: &Q,
) -> Result<(), Error> {
    let mut shifts = [0i32; 3];
    for (i, shift) in shifts.iter_mut().enumerate().take(Q::DIM) {
        let d = q.diagonal(i);
        if !crate::arith::is_positive(d) {
            // A non-positive diagonal entry: test the matrix as it is, which names the first
            // failing leading minor.
            return Q::check_positive_definite(argument, q).and(Err(Error::NotPositiveDefinite {
                argument,
                minor: i + 1,
                value: d,
            }));
        }
        *shift = -exponent(d).div_euclid(2);
    }
    let mut balanced = *q;
    for (k, &(i, j)) in Q::ENTRIES.iter().enumerate() {
        balanced.entries_mut()[k] = scale_by_power_of_two(q.entries()[k], shifts[i] + shifts[j]);
    }
    Q::check_positive_definite(argument, &balanced).map_err(|e| match e {
        Error::NotPositiveDefinite {
            argument,
            minor,
            value,
        } => {
            let shift: i32 = shifts[..minor].iter().sum();
            let unscaled = scale_by_power_of_two(value, -2 * shift);
            Error::NotPositiveDefinite {
                argument,
                minor,
                // Beyond the double range, the balanced matrix's minor (same sign) is told.
                value: if unscaled == 0.0 || unscaled.is_infinite() {
                    value
                } else {
                    unscaled
                },
            }
        }
        other => other,
    })
}

/// The pair moved into the window by the two exact symmetries (module docs): D r12 s, D Qᵢ D,
/// and the exponent 2e such that μ² of the original pair is 2^(2e) times μ² of this one.
struct Balanced<Q> {
    r12: [f64; 3],
    q1: Q,
    q2: Q,
    mu2_exponent: i32,
}

fn balance<Q: Form>(r12: &[f64], q1: &Q, q2: &Q) -> Balanced<Q> {
    let mut shifts = [0i32; 3];
    for (i, shift) in shifts.iter_mut().enumerate().take(Q::DIM) {
        // Both diagonals are positive (checked before).
        let d = q1.diagonal(i).max(q2.diagonal(i));
        *shift = -exponent(d).div_euclid(2);
    }
    let (mut b1, mut b2) = (*q1, *q2);
    for (k, &(i, j)) in Q::ENTRIES.iter().enumerate() {
        b1.entries_mut()[k] = scale_by_power_of_two(q1.entries()[k], shifts[i] + shifts[j]);
        b2.entries_mut()[k] = scale_by_power_of_two(q2.entries()[k], shifts[i] + shifts[j]);
    }
    // The largest exponent of D r12, found without forming D r12 (which may overflow).
    let e = r12
        .iter()
        .zip(shifts)
        .filter(|(x, _)| **x != 0.0)
        .map(|(&x, s)| exponent(x) + s)
        .max()
        .unwrap_or(0);
    let mut r = [0.0; 3];
    for (i, x) in r12.iter().enumerate() {
        r[i] = scale_by_power_of_two(*x, shifts[i] - e);
    }
    Balanced {
        r12: r,
        q1: b1,
        q2: b2,
        mu2_exponent: 2 * e,
    }
}

/// The ellipsoid that stands in for a vanishing one (module docs): `Some((q1, q2))` with the
/// smaller of the balanced pair replaced by the ball of radius² [`STAND_IN`] when it fits
/// inside that ball and the other one is large enough for the substitution to change μ² by
/// less than 2⁻⁴⁷ relative.
fn stand_in<Q: Form>(q1: &Q, q2: &Q) -> Option<(Q, Q)> {
    let trace = |q: &Q| (0..Q::DIM).map(|i| q.diagonal(i)).sum::<f64>();
    let (t1, t2) = (trace(q1), trace(q2));
    let (small, large) = if t2 <= t1 { (t2, q1) } else { (t1, q2) };
    // λmax(small) ≤ tr; λmin(large) ≥ det / tr^(DIM − 1), with det ≥ its leading minors'
    // product bound replaced by the balanced matrix's own determinant.
    let det = determinant(large);
    let smallest_eigenvalue = det / trace(large).powi(Q::DIM as i32 - 1);
    let fits = small <= STAND_IN && smallest_eigenvalue >= STAND_IN * pow2(96);
    fits.then(|| {
        let ball = Q::scaled_identity(STAND_IN);
        if t2 <= t1 { (*q1, ball) } else { (ball, *q2) }
    })
}

/// det q in double-double, rounded: an elongated balanced matrix has a determinant far below
/// the rounding error of its `f64` cofactor expansion.
fn determinant<Q: Form>(q: &Q) -> f64 {
    use crate::arith::{Arith, Dd};
    let e = q.entries();
    let d = |x: f64| Dd::lift(x);
    match Q::DIM {
        2 => (d(e[0]) * d(e[2]) - d(e[1]) * d(e[1])).to_f64(),
        _ => {
            let q3: Sym3 = [e[0], e[1], e[2], e[3], e[4], e[5]];
            let qd = crate::sym::lift6::<Dd>(&q3);
            crate::sym::det_generic(&qd, &crate::sym::adjugate_generic(&qd)).to_f64()
        }
    }
}

/// The contact function of a pair outside the fast path's window, through `kernel` (the fast
/// path itself, without this rescue) on the balanced pair.
fn contact_with<Q: Form>(
    r12: &[f64],
    q1: &Q,
    q2: &Q,
    kernel: impl Fn(&[f64; 3], &Q, &Q) -> Result<Contact, Error>,
) -> Result<Contact, Error> {
    check_positive_definite_balanced(Argument::Q1, q1)?;
    check_positive_definite_balanced(Argument::Q2, q2)?;
    let b = balance(r12, q1, q2);
    let contact = match kernel(&b.r12, &b.q1, &b.q2) {
        Err(Error::NotPositiveDefinite { .. }) => match stand_in(&b.q1, &b.q2) {
            Some((s1, s2)) => kernel(&b.r12, &s1, &s2),
            None => kernel(&b.r12, &b.q1, &b.q2),
        },
        other => other,
    }?;
    Ok(Contact {
        mu2: scale_by_power_of_two(contact.mu2, b.mu2_exponent),
        ..contact
    })
}

/// [`crate::contact_function`] for pairs outside the window (or whose fast path met an
/// underflow).
#[cold]
#[inline(never)]
pub(crate) fn contact_function(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<Contact, Error> {
    contact_with(r12, q1, q2, contact_function_unrescued)
}

/// [`crate::contact_function_2d`] for pairs outside the window.
#[cold]
#[inline(never)]
pub(crate) fn contact_function_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<Contact, Error> {
    contact_with(r12, q1, q2, |r, a, b| {
        crate::contact::contact_function_2d_unrescued(&[r[0], r[1]], a, b)
    })
}

/// [`crate::contact_function_refined`] for pairs outside the window.
#[cold]
#[inline(never)]
pub(crate) fn contact_function_refined(
    r12: &[f64; 3],
    q1: &Sym3,
    q2: &Sym3,
) -> Result<Contact, Error> {
    contact_with(r12, q1, q2, |r, a, b| {
        crate::contact::contact_function_refined_unrescued(r, a, b)
    })
}

/// The fast path's rescue inside the window's checks: `None` when the pair is inside the
/// window (the fast path's answer stands), else the rescaled answer.
#[cold]
#[inline(never)]
pub(crate) fn rescue(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Option<Result<Contact, Error>> {
    (!within_window(r12, q1, q2)).then(|| contact_function(r12, q1, q2))
}

/// [`rescue`] for ellipses.
#[cold]
#[inline(never)]
pub(crate) fn rescue_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Option<Result<Contact, Error>> {
    (!within_window(r12, q1, q2)).then(|| contact_function_2d(r12, q1, q2))
}

/// After the fast path refused a pair as not positive definite: the balanced test decides
/// (the refusal may come from an overflow or underflow of the fast path's determinants, for
/// very large, very small or very elongated ellipsoids), and a pair that passes it is answered
/// on the balanced pair: `balanced` is [`contact_function`](crate::contact_function) or [`contact_function_2d`] of the
/// pair.
#[cold]
#[inline(never)]
pub(crate) fn after_error(
    error: Error,
    balanced: impl FnOnce() -> Result<Contact, Error>,
) -> Result<Contact, Error> {
    match error {
        Error::NotPositiveDefinite { .. } => balanced(),
        e => Err(e),
    }
}

/// [`crate::overlap`] for pairs outside the window: the verdict μ² < 1 of the rescaled contact
/// function (μ² = +∞ beyond the double range: apart).
#[cold]
#[inline(never)]
pub(crate) fn overlap(r12: &[f64; 3], q1: &Sym3, q2: &Sym3) -> Result<bool, Error> {
    contact_function(r12, q1, q2).map(|c| c.mu2 < 1.0)
}

/// [`crate::overlap_2d`] for pairs outside the window.
#[cold]
#[inline(never)]
pub(crate) fn overlap_2d(r12: &[f64; 2], q1: &Sym2, q2: &Sym2) -> Result<bool, Error> {
    contact_function_2d(r12, q1, q2).map(|c| c.mu2 < 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponents_and_powers_are_exact() {
        for e in [-1074, -1050, -1022, -1, 0, 1, 500, 1023] {
            let x = scale_by_power_of_two(1.0, e);
            assert_eq!(exponent(x), e, "2^{e}");
            assert_eq!(scale_by_power_of_two(x, -e), 1.0);
        }
        assert_eq!(exponent(1.5), 0);
        assert_eq!(exponent(-3.0), 1);
        assert_eq!(scale_by_power_of_two(1.0, 1024), f64::INFINITY);
        assert_eq!(scale_by_power_of_two(1.0, -1080), 0.0);
        assert_eq!(scale_by_power_of_two(3.0, 2000), f64::INFINITY);
    }

    #[test]
    fn the_probe_catches_entries_beyond_the_window() {
        #[allow(clippy::eq_op)]
        let probe = |x: f64| {
            let y = x * PROBE;
            y - y
        };
        assert_eq!(probe(pow2(UPPER)), 0.0);
        assert_eq!(probe(-pow2(UPPER)), 0.0);
        assert!(probe(pow2(UPPER + 1)).is_nan());
        assert!(probe(f64::MAX).is_nan());
        assert_eq!(probe(f64::MIN_POSITIVE), 0.0);
    }

    #[test]
    fn balanced_positive_definiteness_does_not_depend_on_units() {
        for e in [-1000, -600, -300, 0, 300, 600, 1000] {
            let s = scale_by_power_of_two(1.0, e);
            let q: Sym3 = [1.0, 0.5, 0.25, 2.0, 0.1, 3.0].map(|x| x * s);
            assert_eq!(
                check_positive_definite_balanced(Argument::Q1, &q),
                Ok(()),
                "2^{e}"
            );
            let not: Sym3 = [1.0, 2.0, 0.0, 1.0, 0.0, 1.0].map(|x| x * s);
            assert!(matches!(
                check_positive_definite_balanced(Argument::Q2, &not),
                Err(Error::NotPositiveDefinite {
                    argument: Argument::Q2,
                    minor: 2,
                    value
                }) if value < 0.0
            ));
        }
        // Axes 2^±400 apart: the unbalanced determinant would underflow.
        let q: Sym3 = [pow2(800), 0.0, 0.0, pow2(-800), 0.0, 1.0];
        assert_eq!(check_positive_definite_balanced(Argument::Q1, &q), Ok(()));
    }
}
