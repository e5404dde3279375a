//! Arithmetic written once for one pair and for four pairs side by side.
//!
//! The pair kernel's formulas (the factor `F`, the direct projection solve, the gradient of
//! `d²`) are generic over [`Real`]: `f64` runs them for one pair, [`F64x4`] for four pairs in
//! the four lanes of one AVX register. Every lane performs exactly the IEEE operations of the
//! `f64` evaluation (add, subtract, multiply, divide and square root are correctly rounded, no
//! fused multiply–add is introduced), so the four-lane kernel gives the same bits as the
//! scalar one; only the control flow (branches for one pair, masks for four) is written twice.

use core::ops::{Add, BitAnd, Div, Mul, Neg, Sub};

/// The operations the pair kernel needs, on one value (`f64`) or on four lanes.
pub(crate) trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// The outcome of a comparison: `bool`, or one flag per lane.
    type Mask: Copy + BitAnd<Output = Self::Mask>;
    /// `x` (in every lane).
    fn splat(x: f64) -> Self;
    /// The correctly rounded square root.
    fn sqrt(self) -> Self;
    /// `|x|`.
    fn abs(self) -> Self;
    /// `self.max(o)` with `o` returned when `self` is NaN (as both `f64::max` and the AVX
    /// `max` do; the kernel never passes a NaN as `o`).
    fn max(self, o: Self) -> Self;
    /// `self ≥ o` (false for NaN).
    fn ge(self, o: Self) -> Self::Mask;
    /// `self ≤ o` (false for NaN).
    fn le(self, o: Self) -> Self::Mask;
    /// `if m { a } else { b }`, lane by lane.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
}

impl Real for f64 {
    type Mask = bool;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    simd::inherent_methods!(f64: sqrt() -> Self, abs() -> Self, max(o) -> Self);
    #[inline(always)]
    fn ge(self, o: Self) -> bool {
        self >= o
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn select(m: bool, a: Self, b: Self) -> Self {
        if m { a } else { b }
    }
}

/// `a` with `f` applied to every entry: `array::map` without its call (in the four-lane
/// kernel an out-of-line `map` or `from_fn` would leave the AVX register code it wraps out
/// of line too).
#[inline(always)]
pub(crate) fn each<T: Copy, const K: usize>(a: [T; K], f: impl Fn(T) -> T) -> [T; K] {
    let mut o = a;
    for k in 0..K {
        o[k] = f(a[k]);
    }
    o
}

/// `[T; N]` filled with `x`.
#[inline(always)]
pub(crate) fn splat_n<T: Real, const N: usize>(x: f64) -> [T; N] {
    [T::splat(x); N]
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx::lanes_of;
#[cfg(target_arch = "x86_64")]
pub(crate) use simd::{F64x4, Mask4};

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::Real;
    use simd::{F64x4, Mask4};

    /// The lanes `a`. Lane values are only created inside the AVX2 + FMA builds of
    /// `crate::batch` (after the processor was checked to have both), as every [`F64x4`].
    #[inline(always)]
    pub(crate) fn lanes_of(a: [f64; 4]) -> F64x4 {
        debug_assert!(simd::has_avx2_fma());
        // SAFETY: see above.
        unsafe { F64x4::from_array_unchecked(a) }
    }

    impl Real for F64x4 {
        type Mask = Mask4;
        #[inline(always)]
        fn splat(x: f64) -> Self {
            debug_assert!(simd::has_avx2_fma());
            // SAFETY: as in `lanes_of`.
            unsafe { F64x4::splat_unchecked(x) }
        }
        simd::inherent_methods!(
            F64x4: sqrt() -> Self, abs() -> Self, max(o) -> Self, ge(o) -> Mask4, le(o) -> Mask4
        );
        #[inline(always)]
        fn select(m: Mask4, a: Self, b: Self) -> Self {
            F64x4::select(m, a, b)
        }
    }
}
