//! Three arithmetics for one piece of algebra.
//!
//! The coefficients of the rational form of f(λ) (eqs. 16a–16b) are polynomials in the entries
//! of Q1, Q2 and r12. They are written once, generically, and evaluated in
//!
//! - `f64`: the fast path;
//! - [`Mag`]: the same expression tree with every entry replaced by its absolute value and every
//!   subtraction by an addition. The result bounds the sum of the absolute values of the terms,
//!   so `γ · Mag` bounds the rounding error of the `f64` evaluation (the classical running error
//!   bound);
//! - [`Dd`]: double-double arithmetic (about 106 bits), used only when the bound says that `f64`
//!   lost too many digits to cancellation (needles, pancakes, near-singular pencils).
//!
//! # References
//! - T. J. Dekker, "A floating-point technique for extending the available precision",
//!   Numer. Math. 18 (1971) 224–242.
//! - N. J. Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., SIAM 2002, §3.3
//!   (running error analysis).

use core::ops::{Add, Mul, Sub};

/// `x > 0`, false for NaN: the test that input checks and iteration guards need, written once
/// so that NaN always takes the safe branch.
#[inline(always)]
pub(crate) fn is_positive(x: f64) -> bool {
    x > 0.0
}

/// The operations the coefficient formulas need.
pub(crate) trait Arith:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<Output = Self>
{
    /// The value of an input double in this arithmetic.
    fn lift(x: f64) -> Self;
    /// Rounded to the nearest double.
    fn to_f64(self) -> f64;
    /// Multiplication by two (exact in every arithmetic here).
    #[inline(always)]
    fn twice(self) -> Self {
        self + self
    }
}

impl Arith for f64 {
    #[inline(always)]
    fn lift(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self
    }
}

/// Arithmetics with a fused multiply–add (one rounding), for the λ iteration.
pub(crate) trait Fused: Arith {
    /// self · b + c with one rounding.
    fn fused_mul_add(self, b: Self, c: Self) -> Self;
}

impl Fused for f64 {
    #[inline(always)]
    fn fused_mul_add(self, b: Self, c: Self) -> Self {
        self.mul_add(b, c)
    }
}

/// a · b + c: fused when `FMA` (the processor has the instruction), else two roundings. The
/// scalar and the batched paths take the same `FMA` on a given machine, so their results
/// still agree bit for bit.
#[inline(always)]
pub(crate) fn mul_add<const FMA: bool, T: Fused>(a: T, b: T, c: T) -> T {
    if FMA {
        a.fused_mul_add(b, c)
    } else {
        a * b + c
    }
}

/// `if x > y { a } else { b }` without a branch: in the AVX2 + FMA build (`FMA`) a compare and
/// a blend of SSE registers. Left to itself the compiler turns a select of doubles into a
/// branch, and where the condition is a coin toss (which end of the pencil the maximiser is
/// near, which side of the root an iterate fell) the mispredictions cost more than the rest of
/// the step (measured with the bench `contact`).
#[inline(always)]
pub(crate) fn select_gt<const FMA: bool>(x: f64, y: f64, a: f64, b: f64) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if FMA {
        use core::arch::x86_64::{_mm_blendv_pd, _mm_cmpgt_pd, _mm_cvtsd_f64, _mm_set1_pd};
        // SAFETY: `FMA` is true only in the AVX2 + FMA build of a dispatched function, after
        // the processor was checked to have AVX2 (which includes SSE4.1's BLENDVPD). Both
        // lanes carry the operands (`set1`, not `set_sd`: the zeroing move it compiles to is
        // one that valgrind cannot decode, and the upper lane is never read).
        return unsafe {
            let mask = _mm_cmpgt_pd(_mm_set1_pd(x), _mm_set1_pd(y));
            _mm_cvtsd_f64(_mm_blendv_pd(_mm_set1_pd(b), _mm_set1_pd(a), mask))
        };
    }
    if x > y { a } else { b }
}

/// `if mask < 0 { a } else { b }` by the sign bit of `mask` (−0 and NaNs with the sign set
/// count as negative), without a branch where [`select_gt`] has none.
#[inline(always)]
pub(crate) fn select_sign<const FMA: bool>(mask: f64, a: f64, b: f64) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if FMA {
        use core::arch::x86_64::{_mm_blendv_pd, _mm_cvtsd_f64, _mm_set_sd};
        // SAFETY: as in `select_gt`; BLENDVPD reads only the sign bit of the mask.
        return unsafe {
            let pick = _mm_blendv_pd(_mm_set_sd(b), _mm_set_sd(a), _mm_set_sd(mask));
            _mm_cvtsd_f64(pick)
        };
    }
    if mask.is_sign_negative() { a } else { b }
}

/// Magnitude of an expression: evaluates Σ|terms| instead of Σ terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Mag(pub f64);

/// `Add`, `Sub` and `Mul` of a newtype `$ty` over an arithmetic: the sum and the product of
/// the wrapped values, and a − b as the expression `$sub` of the wrapped `$a` and `$b` (the
/// newtypes here are magnitudes or mixed lanes, whose a − b is not the wrapped difference).
macro_rules! newtype_arith {
    ($ty:ident, |$a:ident, $b:ident| $sub:expr) => {
        impl core::ops::Add for $ty {
            type Output = Self;
            #[inline(always)]
            fn add(self, o: Self) -> Self {
                Self(self.0 + o.0)
            }
        }
        impl core::ops::Sub for $ty {
            type Output = Self;
            // Deliberate: see `$sub` at the invocation.
            #[allow(clippy::suspicious_arithmetic_impl)]
            #[inline(always)]
            fn sub(self, o: Self) -> Self {
                let ($a, $b) = (self.0, o.0);
                Self($sub)
            }
        }
        impl core::ops::Mul for $ty {
            type Output = Self;
            #[inline(always)]
            fn mul(self, o: Self) -> Self {
                Self(self.0 * o.0)
            }
        }
    };
}
pub(crate) use newtype_arith;

// The magnitude of a − b is bounded by |a| + |b|.
newtype_arith!(Mag, |a, b| a + b);
impl Arith for Mag {
    #[inline(always)]
    fn lift(x: f64) -> Self {
        Mag(x.abs())
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self.0
    }
}

/// An unevaluated sum `hi + lo` with `|lo| ≤ ulp(hi)/2`. `FMA`: the exact product's error
/// term comes from a hardware fused multiply–add (only inside the AVX2 + FMA build) instead of
/// Dekker's splitting; both are exact, so the results are the same bits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct DdT<const FMA: bool> {
    pub hi: f64,
    pub lo: f64,
}

/// Double-double arithmetic for code outside the dispatched kernels.
pub(crate) type Dd = DdT<false>;

/// `a + b = s + e` exactly (Knuth).
#[inline(always)]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// `a + b = s + e` exactly, valid when |a| ≥ |b| (Dekker).
#[inline(always)]
fn fast_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

/// `a · b = p + e` exactly (barring overflow/underflow), with a hardware FMA when `FMA`.
#[inline(always)]
fn two_prod_with<const FMA: bool>(a: f64, b: f64) -> (f64, f64) {
    if FMA {
        let p = a * b;
        (p, a.mul_add(b, -p))
    } else {
        two_prod(a, b)
    }
}

/// `a · b = p + e` exactly (barring overflow/underflow).
#[inline(always)]
pub(crate) fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    #[cfg(target_feature = "fma")]
    {
        (p, a.mul_add(b, -p))
    }
    #[cfg(not(target_feature = "fma"))]
    {
        // Without a hardware FMA, `mul_add` is a slow library call: split each factor into
        // 26-bit halves whose products are exact (Dekker 1971).
        let (ah, al) = split(a);
        let (bh, bl) = split(b);
        (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
    }
}

#[cfg(not(target_feature = "fma"))]
#[inline(always)]
fn split(a: f64) -> (f64, f64) {
    // 2^27 + 1; inputs beyond ~1e300 would overflow here, far outside any physical scale.
    const SPLITTER: f64 = 134_217_729.0;
    let c = SPLITTER * a;
    let hi = c - (c - a);
    (hi, a - hi)
}

impl<const FMA: bool> Add for DdT<FMA> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        let (s, e) = two_sum(self.hi, o.hi);
        let (t, f) = two_sum(self.lo, o.lo);
        let (s, e) = fast_two_sum(s, e + t);
        let (hi, lo) = fast_two_sum(s, e + f);
        Self { hi, lo }
    }
}
impl<const FMA: bool> Sub for DdT<FMA> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        self + Self {
            hi: -o.hi,
            lo: -o.lo,
        }
    }
}
impl<const FMA: bool> Mul for DdT<FMA> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let (p, e) = two_prod_with::<FMA>(self.hi, o.hi);
        let e = e + (self.hi * o.lo + self.lo * o.hi);
        let (hi, lo) = fast_two_sum(p, e);
        Self { hi, lo }
    }
}
impl<const FMA: bool> Arith for DdT<FMA> {
    #[inline(always)]
    fn lift(x: f64) -> Self {
        Self { hi: x, lo: 0.0 }
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self.hi + self.lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_prod_is_exact_on_a_known_product() {
        // (1 + 2^-30)² = 1 + 2^-29 + 2^-60: the last term is lost in f64 and kept in the error.
        let a = 1.0 + 2f64.powi(-30);
        let (p, e) = two_prod(a, a);
        assert_eq!(p, 1.0 + 2f64.powi(-29));
        assert_eq!(e, 2f64.powi(-60));
    }

    #[test]
    fn dd_recovers_cancellation_that_f64_loses() {
        // (1 + 2^-40)(1 - 2^-40) - 1 = -2^-80: f64 gives 0.
        let x = 1.0 + 2f64.powi(-40);
        let y = 1.0 - 2f64.powi(-40);
        assert_eq!(x * y - 1.0, 0.0);
        let d = Dd::lift(x) * Dd::lift(y) - Dd::lift(1.0);
        assert_eq!(d.to_f64(), -(2f64.powi(-80)));
    }

    #[test]
    fn mag_turns_differences_into_sums() {
        let m = Mag::lift(-3.0) * Mag::lift(2.0) - Mag::lift(5.0);
        assert_eq!(m.to_f64(), 11.0);
    }
}
