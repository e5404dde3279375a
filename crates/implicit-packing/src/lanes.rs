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
    /// `self > o` (false for NaN).
    fn gt(self, o: Self) -> Self::Mask;
    /// `if m { a } else { b }`, lane by lane.
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
}

impl Real for f64 {
    type Mask = bool;
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f64::max(self, o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> bool {
        self >= o
    }
    #[inline(always)]
    fn le(self, o: Self) -> bool {
        self <= o
    }
    #[inline(always)]
    fn gt(self, o: Self) -> bool {
        self > o
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
pub(crate) use avx::{F64x4, Mask4};

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::Real;
    use core::arch::x86_64::*;
    use core::ops::{Add, BitAnd, Div, Mul, Neg, Sub};

    /// Four `f64` lanes in one AVX register.
    ///
    /// Values of this type are created only inside functions compiled with AVX2 and FMA
    /// enabled (`#[target_feature(enable = "avx2,fma")]`) and called after the processor was
    /// checked to have both (see `crate::batch`): that is what makes the intrinsics below
    /// sound, and what lets them inline into their callers.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct F64x4(__m256d);

    /// One comparison flag per lane (all bits set or clear), as the AVX compares produce.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Mask4(__m256d);

    macro_rules! binary {
        ($trait:ident, $method:ident, $intrinsic:ident) => {
            impl $trait for F64x4 {
                type Output = Self;
                #[inline(always)]
                fn $method(self, o: Self) -> Self {
                    // SAFETY: AVX is available wherever an `F64x4` exists (see the type).
                    Self(unsafe { $intrinsic(self.0, o.0) })
                }
            }
        };
    }
    binary!(Add, add, _mm256_add_pd);
    binary!(Sub, sub, _mm256_sub_pd);
    binary!(Mul, mul, _mm256_mul_pd);
    binary!(Div, div, _mm256_div_pd);

    impl Neg for F64x4 {
        type Output = Self;
        #[inline(always)]
        fn neg(self) -> Self {
            // SAFETY: as in `add`. `-x` flips the sign bit, NaN included.
            Self(unsafe { _mm256_xor_pd(self.0, _mm256_set1_pd(-0.0)) })
        }
    }

    impl F64x4 {
        /// The lanes `[a[0], a[1], a[2], a[3]]`.
        #[inline(always)]
        pub(crate) fn from_array(a: [f64; 4]) -> Self {
            // SAFETY: as in `add`; `loadu` reads four doubles from a valid array.
            Self(unsafe { _mm256_loadu_pd(a.as_ptr()) })
        }

        /// The lanes as an array.
        #[inline(always)]
        pub(crate) fn to_array(self) -> [f64; 4] {
            let mut out = [0.0; 4];
            // SAFETY: as in `add`; `storeu` writes four doubles into a valid array.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), self.0) };
            out
        }

        #[inline(always)]
        fn compare<const P: i32>(self, o: Self) -> Mask4 {
            // SAFETY: as in `add`.
            Mask4(unsafe { _mm256_cmp_pd::<P>(self.0, o.0) })
        }
    }

    impl Mask4 {
        /// Bit k set when lane k is.
        #[inline(always)]
        pub(crate) fn bits(self) -> u32 {
            // SAFETY: as in `F64x4::add`.
            unsafe { _mm256_movemask_pd(self.0) as u32 }
        }
        /// Some lane is set.
        #[inline(always)]
        pub(crate) fn any(self) -> bool {
            self.bits() != 0
        }
        /// This flag and not `o`'s.
        #[inline(always)]
        pub(crate) fn and_not(self, o: Self) -> Self {
            // SAFETY: as in `F64x4::add` (`andnot(a, b)` is `!a & b`).
            Self(unsafe { _mm256_andnot_pd(o.0, self.0) })
        }
    }

    impl BitAnd for Mask4 {
        type Output = Self;
        #[inline(always)]
        fn bitand(self, o: Self) -> Self {
            // SAFETY: as in `F64x4::add`.
            Self(unsafe { _mm256_and_pd(self.0, o.0) })
        }
    }

    impl Real for F64x4 {
        type Mask = Mask4;
        #[inline(always)]
        fn splat(x: f64) -> Self {
            // SAFETY: as in `add`.
            Self(unsafe { _mm256_set1_pd(x) })
        }
        #[inline(always)]
        fn sqrt(self) -> Self {
            // SAFETY: as in `add`.
            Self(unsafe { _mm256_sqrt_pd(self.0) })
        }
        #[inline(always)]
        fn abs(self) -> Self {
            // SAFETY: as in `add`. Clears the sign bit, as `f64::abs`.
            Self(unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0) })
        }
        #[inline(always)]
        fn max(self, o: Self) -> Self {
            // SAFETY: as in `add`. `max(a, b)` returns `b` when either is NaN: with `a = self`
            // that is `f64::max`'s answer whenever `b` is not NaN.
            Self(unsafe { _mm256_max_pd(self.0, o.0) })
        }
        #[inline(always)]
        fn ge(self, o: Self) -> Mask4 {
            self.compare::<_CMP_GE_OQ>(o)
        }
        #[inline(always)]
        fn le(self, o: Self) -> Mask4 {
            self.compare::<_CMP_LE_OQ>(o)
        }
        #[inline(always)]
        fn gt(self, o: Self) -> Mask4 {
            self.compare::<_CMP_GT_OQ>(o)
        }
        #[inline(always)]
        fn select(m: Mask4, a: Self, b: Self) -> Self {
            // SAFETY: as in `add`. `blendv` takes `a` where the mask's sign bit is set.
            Self(unsafe { _mm256_blendv_pd(b.0, a.0, m.0) })
        }
    }
}
