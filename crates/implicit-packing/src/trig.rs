//! Sines and cosines of an ellipsoid's three angles in one pass of four lanes.
//!
//! Every evaluation of the model turns `3 m` angles into rotations (eq. 2). The C library's
//! `sincos` is accurate for every argument, which costs it a general range reduction and
//! branches, a sizeable share of a model evaluation's instructions. The angles of
//! a packing are moderate, so the reduction by `π/2` needs only three fused multiply–adds, and
//! the three angles of an ellipsoid share one register.
//!
//! # Method
//! `n = round(2x/π)`, `r = x − n π/2` with `π/2 = P1 + P2 + P3` (`P1` the double nearest
//! `π/2`, `P2`, `P3` the next 53 bits each): each fused step rounds once, relative to the
//! remainder, so `r` is within about an ulp of the exact remainder while `|n| < 2²⁰`. On
//! `|r| ≤ π/4`, `sin r` and `cos r` are the minimax polynomials of fdlibm's `__kernel_sin` and
//! `__kernel_cos` (degrees 13 and 14, errors below 2⁻⁵⁸ on the interval), and the quadrant
//! `n mod 4` swaps and negates them. Measured against the C library on 9.2·10⁵ arguments
//! (uniform in `[−1, 1]`, `[−10, 10]` and `[−10⁴, 10⁴]`, and at and next to the multiples of
//! `π/2` up to ±3 142): at most 1 ulp apart (see the tests).
//!
//! Larger arguments (`|x| > 10⁵`, where the reduction would lose digits) and processors
//! without AVX2 and FMA take the C library's `sin_cos`.
//!
//! # References
//! W. J. Cody, W. Waite, *Software Manual for the Elementary Functions*, Prentice-Hall (1980):
//! the reduction with a split constant. The polynomial coefficients are those of fdlibm
//! (Sun Microsystems, 1993), `k_sin.c` and `k_cos.c`.

/// `π/2` in three parts: the double nearest, and the next two 53-bit pieces of the rest.
const PIO2: [f64; 3] = [
    core::f64::consts::FRAC_PI_2,
    6.123_233_995_736_766e-17,
    -1.497_384_904_859_169_8e-33,
];

/// `sin r = r + r³ (S1 + r² S2 + … + r¹⁰ S6)` on `|r| ≤ π/4`.
const SIN: [f64; 6] = [
    -1.666_666_666_666_663_2e-1,
    8.333_333_333_322_49e-3,
    -1.984_126_982_985_795e-4,
    2.755_731_370_707_007e-6,
    -2.505_076_025_340_686_3e-8,
    1.589_690_995_211_55e-10,
];

/// `cos r = 1 − r²/2 + r⁴ (C1 + r² C2 + … + r¹⁰ C6)` on `|r| ≤ π/4`.
const COS: [f64; 6] = [
    4.166_666_666_666_66e-2,
    -1.388_888_888_887_411e-3,
    2.480_158_728_947_673e-5,
    -2.755_731_435_139_066_3e-7,
    2.087_572_321_298_175e-9,
    -1.135_964_755_778_819_5e-11,
];

/// Beyond this `|x|` the reduction is left to the C library.
const REDUCTION_LIMIT: f64 = 1e5;

/// `(sin, cos)` of each of the three angles.
#[inline]
pub(crate) fn sin_cos3(angles: [f64; 3]) -> [(f64, f64); 3] {
    #[cfg(target_arch = "x86_64")]
    {
        if simd::has_avx2_fma() && angles.iter().all(|a| a.abs() <= REDUCTION_LIMIT) {
            // SAFETY: AVX2 and FMA were just detected.
            return unsafe { avx::sin_cos3(angles) };
        }
    }
    angles.map(f64::sin_cos)
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{COS, PIO2, SIN};
    use core::arch::x86_64::*;

    /// `p(z) = c0 + z c1 + … + z⁵ c5` by Horner's rule, fused.
    #[inline]
    #[target_feature(enable = "avx2,fma")]
    fn horner(z: __m256d, c: &[f64; 6]) -> __m256d {
        let mut p = _mm256_set1_pd(c[5]);
        for k in (0..5).rev() {
            p = _mm256_fmadd_pd(p, z, _mm256_set1_pd(c[k]));
        }
        p
    }

    /// The three angles in lanes 0–2 (lane 3 idle), all with `|x| ≤ 1e5`.
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn sin_cos3(a: [f64; 3]) -> [(f64, f64); 3] {
        let x = _mm256_setr_pd(a[0], a[1], a[2], 0.0);
        let n = _mm256_round_pd::<{ _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC }>(
            _mm256_mul_pd(x, _mm256_set1_pd(core::f64::consts::FRAC_2_PI)),
        );
        let mut r = _mm256_fnmadd_pd(n, _mm256_set1_pd(PIO2[0]), x);
        r = _mm256_fnmadd_pd(n, _mm256_set1_pd(PIO2[1]), r);
        r = _mm256_fnmadd_pd(n, _mm256_set1_pd(PIO2[2]), r);
        let z = _mm256_mul_pd(r, r);
        // sin r = r + (r z) S(z)
        let s = _mm256_fmadd_pd(_mm256_mul_pd(r, z), horner(z, &SIN), r);
        // cos r = w + (((1 − w) − z/2) + z² C(z)), w = 1 − z/2 rounded: the bracket
        // restores the rounding error of w exactly (Sterbenz), which for |r| near π/4 would
        // otherwise reach an ulp of the result (fdlibm's k_cos.c does the same).
        let one = _mm256_set1_pd(1.0);
        let hz = _mm256_mul_pd(_mm256_set1_pd(0.5), z);
        let w = _mm256_sub_pd(one, hz);
        let lost = _mm256_sub_pd(_mm256_sub_pd(one, w), hz);
        let c = _mm256_add_pd(
            w,
            _mm256_fmadd_pd(_mm256_mul_pd(z, z), horner(z, &COS), lost),
        );
        // Quadrant q = n mod 4: sin x = (s, c, −s, −c)[q], cos x = (c, −s, −c, s)[q].
        let q = _mm256_cvtepi32_epi64(_mm256_cvtpd_epi32(n));
        let odd = _mm256_castsi256_pd(_mm256_cmpeq_epi64(
            _mm256_and_si256(q, _mm256_set1_epi64x(1)),
            _mm256_set1_epi64x(1),
        ));
        let sin_sign = _mm256_castsi256_pd(_mm256_slli_epi64::<62>(_mm256_and_si256(
            q,
            _mm256_set1_epi64x(2),
        )));
        let cos_sign = _mm256_castsi256_pd(_mm256_slli_epi64::<62>(_mm256_and_si256(
            _mm256_add_epi64(q, _mm256_set1_epi64x(1)),
            _mm256_set1_epi64x(2),
        )));
        let sin = _mm256_xor_pd(_mm256_blendv_pd(s, c, odd), sin_sign);
        let cos = _mm256_xor_pd(_mm256_blendv_pd(c, s, odd), cos_sign);
        let mut so = [0.0; 4];
        let mut co = [0.0; 4];
        // SAFETY: unaligned stores into four-element arrays.
        unsafe {
            _mm256_storeu_pd(so.as_mut_ptr(), sin);
            _mm256_storeu_pd(co.as_mut_ptr(), cos);
        }
        [(so[0], co[0]), (so[1], co[1]), (so[2], co[2])]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ulps(a: f64, b: f64) -> u64 {
        if a == b {
            return 0;
        }
        if a.signum() != b.signum() {
            return (a.to_bits() & !(1 << 63)) + (b.to_bits() & !(1 << 63));
        }
        a.to_bits().abs_diff(b.to_bits())
    }

    /// Within 1 ulp of the C library's correctly rounded (in practice) `sin_cos`, on random
    /// angles of three scales, near multiples of `π/2` (where the reduction cancels), and on
    /// special values; beyond the reduction limit, the C library itself.
    #[test]
    fn within_one_ulp_of_the_c_library() {
        let mut rng = testkit::Rng::new(0x2545_f491_4f6c_dd1d);
        let mut args = vec![
            0.0,
            -0.0,
            1e-300,
            -1e-300,
            1e-8,
            core::f64::consts::FRAC_PI_4,
        ];
        for scale in [1.0, 10.0, 1e4] {
            args.extend((0..300_000).map(|_| scale * (2.0 * rng.uniform() - 1.0)));
        }
        for k in -2000i32..2000 {
            let x = f64::from(k) * core::f64::consts::FRAC_PI_2;
            args.extend([x, x.next_up(), x.next_down(), x + 1e-9, x - 1e-9]);
        }
        args.extend([2e5, -3e7, 1e300]);
        let mut worst = 0;
        for chunk in args.chunks(3) {
            let mut a = [0.0; 3];
            a[..chunk.len()].copy_from_slice(chunk);
            let got = sin_cos3(a);
            for (k, &x) in a.iter().enumerate() {
                let (s, c) = x.sin_cos();
                let e = ulps(got[k].0, s).max(ulps(got[k].1, c));
                assert!(e <= 1, "x = {x:e}: {:?} against ({s:e}, {c:e})", got[k]);
                worst = worst.max(e);
            }
        }
        #[cfg(target_arch = "x86_64")]
        if simd::has_avx2_fma() {
            // The reduction and the polynomials really run (not only the fallback).
            assert_eq!(worst, 1);
        }
    }
}
