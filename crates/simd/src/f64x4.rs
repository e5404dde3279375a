//! Four `f64` lanes in one AVX register.
//!
//! Every arithmetic operation is the IEEE operation of `f64` applied lane by lane (add,
//! subtract, multiply, divide and square root correctly rounded; [`F64x4::mul_add`] rounded
//! once, as `f64::mul_add`; comparisons ordered, false for NaN), so a kernel written once for
//! `f64` and for `F64x4` gives the same bits in every lane.
//!
//! Why a vector type rather than `[f64; 4]`: written with arrays the optimiser keeps much of
//! a lane-wise kernel in scalars, splits the lanes and re-packs them with shuffles and stack
//! round trips; as one register every operation is one instruction.

use core::arch::x86_64::*;
use core::ops::{Add, BitAnd, BitOr, Div, Mul, Neg, Not, Sub};

/// Four `f64` lanes in one 256-bit register.
///
/// Created only by `unsafe` constructors whose contract is that the processor has AVX2 and
/// FMA; every operation on an existing value is therefore sound and safe to call.
#[derive(Clone, Copy, Debug)]
pub struct F64x4(__m256d);

/// One comparison flag per lane (all bits set or clear), as the AVX compares produce.
///
/// Created by comparisons of [`F64x4`] values or by the `unsafe` [`Mask4::from_bools_unchecked`].
#[derive(Clone, Copy, Debug)]
pub struct Mask4(__m256d);

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

/// A comparison of two vectors as a lane mask.
macro_rules! compare {
    ($(#[$doc:meta])* $method:ident, $predicate:ident) => {
        $(#[$doc])*
        #[inline(always)]
        pub fn $method(self, o: Self) -> Mask4 {
            // SAFETY: as in `add`.
            Mask4(unsafe { _mm256_cmp_pd::<$predicate>(self.0, o.0) })
        }
    };
}

impl F64x4 {
    /// `x` in every lane.
    ///
    /// # Safety
    /// The processor must have AVX2 and FMA.
    #[inline(always)]
    pub unsafe fn splat_unchecked(x: f64) -> Self {
        // SAFETY: the caller's contract.
        Self(unsafe { _mm256_set1_pd(x) })
    }

    /// The lanes `[a[0], a[1], a[2], a[3]]`.
    ///
    /// # Safety
    /// The processor must have AVX2 and FMA.
    #[inline(always)]
    pub unsafe fn from_array_unchecked(a: [f64; 4]) -> Self {
        // SAFETY: the caller's contract; `loadu` reads four doubles from a valid array.
        Self(unsafe { _mm256_loadu_pd(a.as_ptr()) })
    }

    /// The register itself as a vector, for operations this type does not name.
    ///
    /// # Safety
    /// The processor must have AVX2 and FMA.
    #[inline(always)]
    pub unsafe fn from_raw_unchecked(x: __m256d) -> Self {
        Self(x)
    }

    /// The register, for operations this type does not name.
    #[inline(always)]
    pub fn raw(self) -> __m256d {
        self.0
    }

    /// The lanes as an array.
    #[inline(always)]
    pub fn to_array(self) -> [f64; 4] {
        let mut out = [0.0; 4];
        // SAFETY: as in `add`; `storeu` writes four doubles into a valid array.
        unsafe { _mm256_storeu_pd(out.as_mut_ptr(), self.0) };
        out
    }

    /// `self · b + c` rounded once, lane by lane (as `f64::mul_add`).
    #[inline(always)]
    pub fn mul_add(self, b: Self, c: Self) -> Self {
        // SAFETY: FMA is available wherever an `F64x4` exists (see the type).
        Self(unsafe { _mm256_fmadd_pd(self.0, b.0, c.0) })
    }

    /// `|x|`: the sign bit cleared, as `f64::abs`.
    #[inline(always)]
    pub fn abs(self) -> Self {
        // SAFETY: as in `add`.
        Self(unsafe { _mm256_andnot_pd(_mm256_set1_pd(-0.0), self.0) })
    }

    /// The correctly rounded square root.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        // SAFETY: as in `add`.
        Self(unsafe { _mm256_sqrt_pd(self.0) })
    }

    /// `self.max(o)` lane by lane; `o` where `self` is NaN (as `f64::max` whenever `o` is
    /// not NaN).
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        // SAFETY: as in `add`. `max(a, b)` returns `b` when either is NaN.
        Self(unsafe { _mm256_max_pd(self.0, o.0) })
    }

    /// `self − o` in lanes 0 and 2, `self + o` in lanes 1 and 3 (one instruction).
    #[inline(always)]
    pub fn sub_add(self, o: Self) -> Self {
        // SAFETY: as in `add`.
        Self(unsafe { _mm256_addsub_pd(self.0, o.0) })
    }

    /// The two 128-bit halves exchanged: lanes `[2, 3, 0, 1]`.
    #[inline(always)]
    pub fn swap_halves(self) -> Self {
        // SAFETY: as in `add`.
        Self(unsafe { _mm256_permute2f128_pd::<0x01>(self.0, self.0) })
    }

    /// `a` where `mask` is set, `b` elsewhere.
    #[inline(always)]
    pub fn select(mask: Mask4, a: Self, b: Self) -> Self {
        // SAFETY: as in `add`. BLENDVPD takes its second operand where the sign bit is set.
        Self(unsafe { _mm256_blendv_pd(b.0, a.0, mask.0) })
    }

    compare!(
        /// `self > o`.
        gt,
        _CMP_GT_OQ
    );
    compare!(
        /// `self ≥ o`.
        ge,
        _CMP_GE_OQ
    );
    compare!(
        /// `self < o`.
        lt,
        _CMP_LT_OQ
    );
    compare!(
        /// `self ≤ o`.
        le,
        _CMP_LE_OQ
    );
    compare!(
        /// `self = o`.
        eq,
        _CMP_EQ_OQ
    );
}

impl Mask4 {
    /// The flags `b`.
    ///
    /// # Safety
    /// The processor must have AVX2 and FMA.
    #[inline(always)]
    pub unsafe fn from_bools_unchecked(b: [bool; 4]) -> Self {
        let lanes = b.map(|x| f64::from_bits(if x { u64::MAX } else { 0 }));
        // SAFETY: the caller's contract.
        Mask4(unsafe { F64x4::from_array_unchecked(lanes) }.0)
    }

    /// Bit k set when lane k is.
    #[inline(always)]
    pub fn bits(self) -> u32 {
        // SAFETY: as in `F64x4::add`.
        unsafe { _mm256_movemask_pd(self.0) as u32 }
    }

    /// The flags as booleans.
    #[inline(always)]
    pub fn to_bools(self) -> [bool; 4] {
        let bits = self.bits();
        core::array::from_fn(|k| bits >> k & 1 == 1)
    }

    /// Some lane is set.
    #[inline(always)]
    pub fn any(self) -> bool {
        self.bits() != 0
    }

    /// Every lane is set.
    #[inline(always)]
    pub fn all(self) -> bool {
        self.bits() == 0b1111
    }

    /// This flag and not `o`'s.
    #[inline(always)]
    pub fn and_not(self, o: Self) -> Self {
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

impl BitOr for Mask4 {
    type Output = Self;
    #[inline(always)]
    fn bitor(self, o: Self) -> Self {
        // SAFETY: as in `F64x4::add`.
        Self(unsafe { _mm256_or_pd(self.0, o.0) })
    }
}

impl Not for Mask4 {
    type Output = Self;
    #[inline(always)]
    fn not(self) -> Self {
        // SAFETY: as in `F64x4::add`.
        Self(unsafe { _mm256_xor_pd(self.0, _mm256_castsi256_pd(_mm256_set1_epi64x(-1))) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_lane_rounds_as_f64() {
        if !crate::has_avx2_fma() {
            return;
        }
        let a = [1.0 / 3.0, -2.5e300, f64::NAN, 1e-310];
        let b = [3.0, 7.1e10, 1.0, -0.0];
        // SAFETY: the processor has AVX2 and FMA, just checked.
        let (x, y) = unsafe {
            (
                F64x4::from_array_unchecked(a),
                F64x4::from_array_unchecked(b),
            )
        };
        let same = |v: F64x4, f: &dyn Fn(f64, f64) -> f64| {
            for k in 0..4 {
                assert_eq!(
                    v.to_array()[k].to_bits(),
                    f(a[k], b[k]).to_bits(),
                    "lane {k}"
                );
            }
        };
        same(x + y, &|p, q| p + q);
        same(x - y, &|p, q| p - q);
        same(x * y, &|p, q| p * q);
        same(x / y, &|p, q| p / q);
        same(-x, &|p, _| -p);
        same(x.abs(), &|p, _| p.abs());
        same(x.sqrt(), &|p, _| p.sqrt());
        same(x.mul_add(y, x), &|p, q| p.mul_add(q, p));
        let sa = x.sub_add(y).to_array();
        assert_eq!(sa[0].to_bits(), (a[0] - b[0]).to_bits());
        assert_eq!(sa[1].to_bits(), (a[1] + b[1]).to_bits());
        assert_eq!(x.gt(y).to_bools(), [false, false, false, true]);
        assert_eq!(x.le(y).to_bools(), [true, true, false, false]);
        assert!(!x.eq(x).all(), "NaN is not equal to itself");
        assert_eq!(F64x4::select(x.lt(y), x, y).to_array()[0], a[0]);
        assert_eq!(x.swap_halves().to_array()[0].to_bits(), a[2].to_bits());
        // SAFETY: as above.
        let m = unsafe { Mask4::from_bools_unchecked([true, false, true, false]) };
        assert_eq!((!m).to_bools(), [false, true, false, true]);
        assert_eq!(m.and_not(m).bits(), 0);
        assert!((m | !m).all());
    }
}
