//! Four pairs side by side, lane by lane, for the batched path (and, in [`Ends4`], the two ends
//! of one pair's pencil with their magnitudes, for the scalar path).
//!
//! [`V4`] holds one `f64` per pair and does every operation lane-wise: written this way, the
//! compiler keeps the four lanes in one 256-bit register where AVX is available (two 128-bit
//! ones otherwise). Each lane performs exactly the operations of the scalar code in the same
//! order, so the batched results equal the scalar ones bit for bit; the lanes only differ in
//! when they stop, and a lane that has stopped keeps its state (selects, not branches).

use crate::arith::{Arith, Fused, newtype_arith};
use crate::poly::{OddsForm, RationalForm};
use crate::sym::{
    Sym3, adjugate_generic, det_generic, frobenius_generic, mixed_adjugate_generic, outer_generic,
    quadratic_form_generic,
};
use core::ops::{Add, Div, Mul, Neg, Sub};

/// Number of lanes.
pub(crate) const LANES: usize = 4;

/// One value per lane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct V4(pub [f64; LANES]);

macro_rules! lanewise {
    ($trait:ident, $method:ident, $op:tt) => {
        impl $trait for V4 {
            type Output = V4;
            #[inline(always)]
            fn $method(self, o: V4) -> V4 {
                V4([
                    self.0[0] $op o.0[0],
                    self.0[1] $op o.0[1],
                    self.0[2] $op o.0[2],
                    self.0[3] $op o.0[3],
                ])
            }
        }
    };
}
lanewise!(Add, add, +);
lanewise!(Sub, sub, -);
lanewise!(Mul, mul, *);
lanewise!(Div, div, /);

impl Neg for V4 {
    type Output = V4;
    #[inline(always)]
    fn neg(self) -> V4 {
        V4(self.0.map(|x| -x))
    }
}

impl crate::arith::Fused for V4 {
    #[inline(always)]
    fn fused_mul_add(self, b: V4, c: V4) -> V4 {
        V4::from_fn(|k| self.0[k].mul_add(b.0[k], c.0[k]))
    }
}

impl Arith for V4 {
    #[inline(always)]
    fn lift(x: f64) -> Self {
        V4([x; LANES])
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self.0[0]
    }
}

/// Magnitudes, one per lane: the `Mag` arithmetic (differences add) on four pairs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct M4(pub [f64; LANES]);

impl Add for M4 {
    type Output = M4;
    #[inline(always)]
    fn add(self, o: M4) -> M4 {
        M4((V4(self.0) + V4(o.0)).0)
    }
}
impl Sub for M4 {
    type Output = M4;
    // Deliberate: the magnitude of a − b is |a| + |b|.
    #[allow(clippy::suspicious_arithmetic_impl)]
    #[inline(always)]
    fn sub(self, o: M4) -> M4 {
        M4((V4(self.0) + V4(o.0)).0)
    }
}
impl Mul for M4 {
    type Output = M4;
    #[inline(always)]
    fn mul(self, o: M4) -> M4 {
        M4((V4(self.0) * V4(o.0)).0)
    }
}
impl Arith for M4 {
    #[inline(always)]
    fn lift(x: f64) -> Self {
        M4([x.abs(); LANES])
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self.0[0]
    }
}

/// One pair's two ellipsoids side by side, with their magnitudes: lanes
/// [x(Q1), x(Q2), Σ|terms| of x(Q1), Σ|terms| of x(Q2)] for a formula x written once (the
/// [`crate::arith::Mag`] arithmetic in the last two lanes). The coefficient formulas of the
/// two ends of the pencil (adj Qᵢ, det Qᵢ, rᵀ adj Qᵢ r, tr(adj Qᵢ Qⱼ)) are the same formula
/// on Q1 and on Q2, so one evaluation gives four results in one 256-bit register; every lane
/// performs exactly the operations of the scalar `f64` (or `Mag`) evaluation, so the results
/// are the same bits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Ends4(pub V4);

/// a − b is a + (−1) b in the value lanes and a + b in the magnitude lanes: multiplying by
/// ±1 is exact, so each lane rounds exactly as its own subtraction or addition would.
const SUB_SIGNS: V4 = V4([-1.0, -1.0, 1.0, 1.0]);

newtype_arith!(Ends4, |a, b| a + b * SUB_SIGNS);
impl Arith for Ends4 {
    #[inline(always)]
    fn lift(x: f64) -> Self {
        Ends4(V4([x, x, x.abs(), x.abs()]))
    }
    #[inline(always)]
    fn to_f64(self) -> f64 {
        self.0.0[0]
    }
}

/// The arithmetic of [`coefficients_with_bound`]'s four-lane pass: [`Ends4`] in
/// the portable build, [`Ends4Avx`] in the AVX2 build.
pub(crate) trait EndsLanes: Arith {
    /// [a, b, |a|, |b|] in this type's layout.
    fn of(a: f64, b: f64) -> Self;
    /// [x(Q1), x(Q2), Σ|terms| of x(Q1), Σ|terms| of x(Q2)].
    fn lanes(self) -> [f64; 4];
    /// The two ends exchanged: `of(b, a)` from `of(a, b)`, by moving lanes.
    fn swapped(self) -> Self;
}

impl EndsLanes for Ends4 {
    #[inline(always)]
    fn of(a: f64, b: f64) -> Self {
        Ends4(V4([a, b, a.abs(), b.abs()]))
    }
    #[inline(always)]
    fn swapped(self) -> Self {
        let [a, b, ma, mb] = self.0.0;
        Ends4(V4([b, a, mb, ma]))
    }
    #[inline(always)]
    fn lanes(self) -> [f64; 4] {
        self.0.0
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx::{Ends4Avx, M4Avx};

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{EndsLanes, LANES, Lane4};
    use crate::arith::{Arith, Fused, newtype_arith};
    use core::arch::x86_64::{
        _mm_cvtsd_f64, _mm_unpackhi_pd, _mm256_and_pd, _mm256_blend_pd, _mm256_castpd256_pd128,
        _mm256_castsi256_pd, _mm256_extractf128_pd, _mm256_set1_pd, _mm256_setr_epi64x,
    };
    use simd::{F64x4, Mask4};

    /// [`super::Ends4`] as one AVX register, lanes [x(Q1), Σ|terms|(Q1), x(Q2), Σ|terms|(Q2)]:
    /// written with `[f64; 4]` the optimiser splits the lanes into scalars and re-packs them
    /// into 128-bit halves with shuffles and stack spills; as a vector type every operation
    /// is one instruction. In this layout a − b is ADDSUBPD ([`F64x4::sub_add`]), which
    /// subtracts in the even (value) lanes and adds in the odd (magnitude) ones: the
    /// subtraction of the `f64` formula and the addition of the `Mag` one, each with its own
    /// rounding, so the results are the same bits as [`super::Ends4`].
    ///
    /// Created only in the AVX2 + FMA build of a dispatched function (`FMA = true` in
    /// [`simd::multiversion`]), as every [`F64x4`].
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Ends4Avx(F64x4);

    // ADDSUBPD: see the type.
    newtype_arith!(Ends4Avx, |a, b| a.sub_add(b));
    impl Arith for Ends4Avx {
        #[inline(always)]
        fn lift(x: f64) -> Self {
            Self::of(x, x)
        }
        #[inline(always)]
        fn to_f64(self) -> f64 {
            self.lanes()[0]
        }
    }
    impl EndsLanes for Ends4Avx {
        #[inline(always)]
        fn of(a: f64, b: f64) -> Self {
            debug_assert!(simd::has_avx2_fma());
            // Two broadcasts, a blend and a mask: as `_mm256_setr_pd(a, |a|, b, |b|)` the
            // optimiser rebuilt the lanes from the finiteness probe's vector loads with
            // lane permutations and a stack round trip, on the path to every coefficient.
            // SAFETY: only called in the AVX2 + FMA build (see the type).
            Self(unsafe {
                let both = _mm256_blend_pd::<0b1100>(_mm256_set1_pd(a), _mm256_set1_pd(b));
                F64x4::from_raw_unchecked(_mm256_and_pd(
                    both,
                    _mm256_castsi256_pd(_mm256_setr_epi64x(-1, i64::MAX, -1, i64::MAX)),
                ))
            })
        }
        #[inline(always)]
        fn lanes(self) -> [f64; 4] {
            // From the registers rather than through a store and four loads (the coefficients
            // are on the critical path of every call).
            // SAFETY: as in `of`.
            unsafe {
                let low = _mm256_castpd256_pd128(self.0.raw());
                let high = _mm256_extractf128_pd::<1>(self.0.raw());
                let odd = |x| _mm_cvtsd_f64(_mm_unpackhi_pd(x, x));
                [_mm_cvtsd_f64(low), _mm_cvtsd_f64(high), odd(low), odd(high)]
            }
        }
        #[inline(always)]
        fn swapped(self) -> Self {
            // The 128-bit halves hold the two ends.
            Self(self.0.swap_halves())
        }
    }

    // [`super::V4`]'s arithmetic on [`F64x4`], for the four-lane solve of the AVX2 + FMA
    // build: written with `[f64; 4]` the optimiser keeps much of the lane-wise code in
    // scalars (callgrind counts almost as many instructions per pair as the scalar call).

    impl Arith for F64x4 {
        #[inline(always)]
        fn lift(x: f64) -> Self {
            debug_assert!(simd::has_avx2_fma());
            // SAFETY: lane values are only created in the AVX2 + FMA build.
            unsafe { F64x4::splat_unchecked(x) }
        }
        #[inline(always)]
        fn to_f64(self) -> f64 {
            self.to_array()[0]
        }
    }

    impl Fused for F64x4 {
        #[inline(always)]
        fn fused_mul_add(self, b: Self, c: Self) -> Self {
            self.mul_add(b, c)
        }
    }

    /// [`super::M4`] as one AVX register: magnitudes, a − b evaluated as |a| + |b| (the
    /// [`crate::arith::Mag`] arithmetic on four pairs).
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct M4Avx(F64x4);

    impl M4Avx {
        /// |x| lane-wise.
        #[inline(always)]
        pub(crate) fn of(x: [f64; LANES]) -> Self {
            Self(<F64x4 as Lane4>::from_array(x).abs())
        }
        #[inline(always)]
        pub(crate) fn to_array(self) -> [f64; LANES] {
            self.0.to_array()
        }
    }

    // The magnitude of a − b is |a| + |b|.
    newtype_arith!(M4Avx, |a, b| a + b);
    impl Arith for M4Avx {
        #[inline(always)]
        fn lift(x: f64) -> Self {
            Self(F64x4::lift(x.abs()))
        }
        #[inline(always)]
        fn to_f64(self) -> f64 {
            self.to_array()[0]
        }
    }

    impl Lane4 for F64x4 {
        type Mask = Mask4;
        #[inline(always)]
        fn from_array(a: [f64; LANES]) -> Self {
            debug_assert!(simd::has_avx2_fma());
            // SAFETY: lane values are only created in the AVX2 + FMA build.
            unsafe { F64x4::from_array_unchecked(a) }
        }
        #[inline(always)]
        fn to_array(self) -> [f64; LANES] {
            self.to_array()
        }
        simd::inherent_methods!(F64x4: abs() -> Self, sqrt() -> Self);
        simd::inherent_methods!(
            F64x4: gt(o) -> Mask4, ge(o) -> Mask4, lt(o) -> Mask4, le(o) -> Mask4, eq(o) -> Mask4
        );
        #[inline(always)]
        fn or_else(self, mask: Mask4, other: Self) -> Self {
            F64x4::select(mask, self, other)
        }
        #[inline(always)]
        fn and(a: Mask4, b: Mask4) -> Mask4 {
            a & b
        }
        #[inline(always)]
        fn or(a: Mask4, b: Mask4) -> Mask4 {
            a | b
        }
        #[inline(always)]
        fn not(a: Mask4) -> Mask4 {
            !a
        }
        #[inline(always)]
        fn mask(b: [bool; LANES]) -> Mask4 {
            // SAFETY: lane values are only created in the AVX2 + FMA build.
            unsafe { Mask4::from_bools_unchecked(b) }
        }
        #[inline(always)]
        fn bools(m: Mask4) -> [bool; LANES] {
            m.to_bools()
        }
        #[inline(always)]
        fn all(m: Mask4) -> bool {
            m.all()
        }
    }
}

impl V4 {
    /// |x| lane-wise, as the magnitude arithmetic's input.
    #[inline(always)]
    pub(crate) fn magnitude(self) -> M4 {
        M4(self.0.map(f64::abs))
    }
    #[inline(always)]
    pub(crate) fn from_fn(f: impl FnMut(usize) -> f64) -> Self {
        V4(core::array::from_fn(f))
    }
}

/// The lane type of the four-lane solve: [`V4`] in the portable build, [`simd::F64x4`] (one 256-bit
/// register, x86-64 only) in the AVX2 + FMA build. Every operation is lane-wise and rounds as
/// the `f64` operation does, so both give the scalar path's bits.
pub(crate) trait Lane4:
    Fused + Div<Output = Self> + Neg<Output = Self> + core::fmt::Debug
{
    /// Four truth values.
    type Mask: Copy + core::fmt::Debug;
    fn from_array(a: [f64; LANES]) -> Self;
    fn to_array(self) -> [f64; LANES];
    fn abs(self) -> Self;
    fn sqrt(self) -> Self;
    /// `self > o` (false for NaN, as `f64`'s comparisons; so are the others).
    fn gt(self, o: Self) -> Self::Mask;
    fn ge(self, o: Self) -> Self::Mask;
    fn lt(self, o: Self) -> Self::Mask;
    fn le(self, o: Self) -> Self::Mask;
    fn eq(self, o: Self) -> Self::Mask;
    /// `self` where `mask`, `other` elsewhere.
    fn or_else(self, mask: Self::Mask, other: Self) -> Self;
    fn and(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    fn or(a: Self::Mask, b: Self::Mask) -> Self::Mask;
    fn not(a: Self::Mask) -> Self::Mask;
    fn mask(b: [bool; LANES]) -> Self::Mask;
    fn bools(m: Self::Mask) -> [bool; LANES];
    fn all(m: Self::Mask) -> bool;
}

impl Lane4 for V4 {
    type Mask = [bool; LANES];
    #[inline(always)]
    fn from_array(a: [f64; LANES]) -> Self {
        V4(a)
    }
    #[inline(always)]
    fn to_array(self) -> [f64; LANES] {
        self.0
    }
    #[inline(always)]
    fn abs(self) -> Self {
        V4(self.0.map(f64::abs))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        V4(self.0.map(f64::sqrt))
    }
    #[inline(always)]
    fn gt(self, o: Self) -> Self::Mask {
        core::array::from_fn(|k| self.0[k] > o.0[k])
    }
    #[inline(always)]
    fn ge(self, o: Self) -> Self::Mask {
        core::array::from_fn(|k| self.0[k] >= o.0[k])
    }
    #[inline(always)]
    fn lt(self, o: Self) -> Self::Mask {
        core::array::from_fn(|k| self.0[k] < o.0[k])
    }
    #[inline(always)]
    fn le(self, o: Self) -> Self::Mask {
        core::array::from_fn(|k| self.0[k] <= o.0[k])
    }
    #[inline(always)]
    fn eq(self, o: Self) -> Self::Mask {
        core::array::from_fn(|k| self.0[k] == o.0[k])
    }
    #[inline(always)]
    fn or_else(self, mask: Self::Mask, other: Self) -> Self {
        V4::from_fn(|k| if mask[k] { self.0[k] } else { other.0[k] })
    }
    #[inline(always)]
    fn and(a: Self::Mask, b: Self::Mask) -> Self::Mask {
        core::array::from_fn(|k| a[k] & b[k])
    }
    #[inline(always)]
    fn or(a: Self::Mask, b: Self::Mask) -> Self::Mask {
        core::array::from_fn(|k| a[k] | b[k])
    }
    #[inline(always)]
    fn not(a: Self::Mask) -> Self::Mask {
        a.map(|x| !x)
    }
    #[inline(always)]
    fn mask(b: [bool; LANES]) -> Self::Mask {
        b
    }
    #[inline(always)]
    fn bools(m: Self::Mask) -> [bool; LANES] {
        m
    }
    #[inline(always)]
    fn all(m: Self::Mask) -> bool {
        m.iter().all(|&x| x)
    }
}

/// Four odds searches ([`crate::poly::OddsSearch`]) side by side, as four-lane values.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OddsSearch4<L: Lane4> {
    /// The current iterates; u₀ in the lanes that are done (and not `fallback`).
    pub u: L,
    lo: L,
    hi: L,
    /// Iterations so far, as a float (exact: at most 101).
    iterations: L,
    done: L::Mask,
    /// The lanes whose values left the trustworthy range ([`crate::poly::OddsSearch::fallback`]).
    pub fallback: L::Mask,
}

impl<L: Lane4> OddsSearch4<L> {
    #[inline(always)]
    fn new(u0: [f64; LANES]) -> Self {
        let ok = L::mask(u0.map(|u| u > 0.0 && u < f64::INFINITY));
        Self {
            u: L::from_array(u0),
            lo: L::lift(0.0),
            hi: L::lift(f64::INFINITY),
            iterations: L::lift(0.0),
            done: L::not(ok),
            fallback: L::not(ok),
        }
    }

    /// [`crate::poly::OddsSearch::advance`] in every lane that is not done, with the same
    /// operations on the same values (so the same bits); the branches of the scalar rule
    /// become selects, so the four lanes stay in vector registers and no lane's branch is
    /// mispredicted. Every candidate of the scalar rule (Halley's point, the bracket's
    /// expansion, contraction or geometric midpoint) is computed in every lane, and the
    /// rule's decisions pick one.
    #[inline(always)]
    fn advance(&mut self, (p, n, v, step): (L, L, L, L)) {
        use crate::poly::HALLEY_LAST_STEP as TOL;
        let c = L::lift;
        let active = L::not(self.done);
        let u = self.u;
        let iterations = self.iterations + c(1.0).or_else(active, c(0.0));
        let bad = L::or(
            L::not(L::and(v.gt(c(1e-60)), n.abs().gt(c(1e-60)))),
            iterations.gt(c(100.0)),
        );
        let below = p.gt(c(0.0));
        let lo = u.or_else(below, self.lo);
        let hi = self.hi.or_else(below, u);
        let next = u - step;
        let small = step.abs().le(c(TOL) * u);
        let trusted = (p * v).abs().le(c(2.0 * TOL) * u * n.abs());
        let accept = L::and(L::and(small, trusted), L::and(next.ge(lo), next.le(hi)));
        let inside = L::and(
            L::and(next.gt(lo), next.lt(hi)),
            L::or(trusted, L::not(small)),
        );
        let expand = hi.eq(c(f64::INFINITY));
        let contract = lo.eq(c(0.0));
        let bisect = (lo * hi).sqrt();
        let fallback = (c(4.0) * u).or_else(expand, (c(0.25) * u).or_else(contract, bisect));
        let moved = next.or_else(L::or(accept, inside), fallback);
        // Accepted, or the bracket is down to adjacent doubles (the scalar rule's `next == u`).
        let finished = L::or(accept, moved.eq(u));
        let step_lanes = L::and(active, L::not(bad));
        self.iterations = iterations;
        self.lo = lo.or_else(step_lanes, self.lo);
        self.hi = hi.or_else(step_lanes, self.hi);
        self.u = moved.or_else(step_lanes, u);
        self.fallback = L::or(self.fallback, L::and(active, bad));
        self.done = L::or(
            self.done,
            L::or(L::and(active, bad), L::and(step_lanes, finished)),
        );
    }
}

/// The odds iteration of [`crate::contact_function`] ([`crate::poly::OddsSearch`]) on four
/// pairs at once, from the starting points `u0`: the Halley terms and the step rule are both
/// computed for all lanes together ([`OddsSearch4::advance`]); a stopped lane's state is
/// frozen. Returns the maximisers, [u, A(u), B(u)] at each lane's last evaluation (as
/// [`crate::contact`]'s scalar solve keeps them) and the lanes that need the λ iteration.
#[inline(always)]
fn maximise4_in<const FMA: bool, L: Lane4>(
    alpha: &[V4; 3],
    beta: &[V4; 4],
    u0: [f64; LANES],
) -> (V4, [V4; 3], [bool; LANES]) {
    let odds = OddsForm::new(
        &alpha.map(|x| L::from_array(x.0)),
        &beta.map(|x| L::from_array(x.0)),
    );
    let mut search = OddsSearch4::<L>::new(u0);
    let mut last = [search.u, L::lift(0.0), L::lift(0.0)];
    while !L::all(search.done) {
        let terms = odds.halley_terms::<FMA>(search.u);
        let active = L::not(search.done);
        last = [
            search.u.or_else(active, last[0]),
            terms.a.or_else(active, last[1]),
            terms.b.or_else(active, last[2]),
        ];
        search.advance(terms.step_terms());
    }
    (
        V4(search.u.to_array()),
        last.map(|x| V4(x.to_array())),
        L::bools(search.fallback),
    )
}

/// The Bernstein coefficients of four pairs (one per lane) and their Σ|terms| (the
/// [`crate::arith::Mag`] arithmetic), from the lanes of r12, Q1 and Q2: the formulas of
/// [`crate::poly::pencil3`], in the lane type of the build (`FMA`: one 256-bit register per
/// quantity). Returns ((α, β), (Σ|α|, Σ|β|)).
#[inline(always)]
pub(crate) fn coefficients4<const FMA: bool>(
    r: [V4; 3],
    a: [V4; 6],
    b: [V4; 6],
) -> (crate::poly::Coefficients<V4>, ([V4; 3], [V4; 4])) {
    #[cfg(target_arch = "x86_64")]
    if FMA {
        use simd::F64x4;
        let value = crate::poly::pencil3_lifted(
            r.map(|x| <F64x4 as Lane4>::from_array(x.0)),
            a.map(|x| <F64x4 as Lane4>::from_array(x.0)),
            b.map(|x| <F64x4 as Lane4>::from_array(x.0)),
        )
        .coefficients;
        let bound = crate::poly::pencil3_lifted(
            r.map(|x| M4Avx::of(x.0)),
            a.map(|x| M4Avx::of(x.0)),
            b.map(|x| M4Avx::of(x.0)),
        )
        .coefficients;
        let v4 = |x: F64x4| V4(x.to_array());
        let m4 = |x: M4Avx| V4(x.to_array());
        return (
            crate::poly::Coefficients {
                alpha: value.alpha.map(v4),
                beta: value.beta.map(v4),
            },
            (bound.alpha.map(m4), bound.beta.map(m4)),
        );
    }
    let value = crate::poly::pencil3_lifted(r, a, b).coefficients;
    let bound = crate::poly::pencil3_lifted(
        r.map(V4::magnitude),
        a.map(V4::magnitude),
        b.map(V4::magnitude),
    )
    .coefficients;
    (
        value,
        (bound.alpha.map(|x| V4(x.0)), bound.beta.map(|x| V4(x.0))),
    )
}

/// [`maximise4_in`] on the oriented, normalised coefficients of four lanes, in the lane type
/// of the build (`FMA`: the AVX2 + FMA build, one 256-bit register per quantity). Returns the
/// maximisers u₀, [u, A(u), B(u)] at the last evaluation and the lanes that need the λ
/// iteration instead.
#[inline(always)]
pub(crate) fn maximise4<const FMA: bool>(
    alpha: &[V4; 3],
    beta: &[V4; 4],
    u0: [f64; LANES],
) -> (V4, [V4; 3], [bool; LANES]) {
    #[cfg(target_arch = "x86_64")]
    if FMA {
        return maximise4_in::<FMA, simd::F64x4>(alpha, beta, u0);
    }
    maximise4_in::<FMA, V4>(alpha, beta, u0)
}

/// The `f64` Bernstein coefficients and their Σ|terms| (the running error bound) in one pass:
/// the same expression trees as [`pencil3`](crate::poly::pencil3) in `f64` and in `Mag`, bit for bit, evaluated for
/// both ends of the pencil at once ([`Ends4`]). Returns (values, bounds).
#[inline(always)]
pub(crate) fn coefficients_with_bound<E: EndsLanes>(
    r12: &[f64; 3],
    q1: &Sym3,
    q2: &Sym3,
) -> (RationalForm, RationalForm) {
    let ends: [E; 6] = core::array::from_fn(|i| E::of(q1[i], q2[i]));
    let swapped: [E; 6] = ends.map(E::swapped);
    let rr = outer_generic::<E>(r12);
    let adj = adjugate_generic(&ends);
    // Lanes: (β₀, β₃), (α₀, α₂), (β₁, β₂) and α₁ (first lane; the second is M(Q2, Q1)).
    let det = det_generic(&ends, &adj);
    let outer = quadratic_form_generic(&rr, &adj);
    let cross = frobenius_generic(&adj, &swapped);
    let mixed = quadratic_form_generic(&rr, &mixed_adjugate_generic(&ends, &swapped));
    let [det, outer, cross, mixed] = [det, outer, cross, mixed].map(E::lanes);
    let pick = |k: usize| RationalForm {
        alpha: [outer[k], mixed[k], outer[k + 1]],
        beta: [det[k], cross[k], cross[k + 1], det[k + 1]],
    };
    (pick(0), pick(2))
}

#[cfg(test)]
mod tests {
    /// The vector-register form of the four-lane pass gives the same bits as the array form
    /// (and so as the scalar `f64` and `Mag` formulas), lanes in the same order.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_ends_equal_portable_ends_bit_for_bit() {
        use super::coefficients_with_bound;
        if !simd::has_avx2_fma() {
            return;
        }
        let mut x = 0.123_f64;
        let mut next = || {
            x = (x * 3.99 * (1.0 - x)).clamp(1e-9, 1.0 - 1e-9);
            x - 0.5
        };
        for _ in 0..2000 {
            let mut ellipsoid = || {
                let axes = [1.0, 0.3, 1e-3].map(|a| a * (1.0 + next()));
                let q = [next(), next(), next(), next()];
                crate::shape::from_axes_quaternion(&axes, &q).unwrap()
            };
            let (q1, q2) = (ellipsoid(), ellipsoid());
            let r12 = [next(), next(), 1e-6 * next()];
            let avx = coefficients_with_bound::<super::Ends4Avx>(&r12, &q1, &q2);
            let portable = coefficients_with_bound::<super::Ends4>(&r12, &q1, &q2);
            let bits = |(v, m): (crate::poly::RationalForm, crate::poly::RationalForm)| {
                [
                    v.alpha.to_vec(),
                    v.beta.to_vec(),
                    m.alpha.to_vec(),
                    m.beta.to_vec(),
                ]
                .concat()
                .into_iter()
                .map(f64::to_bits)
                .collect::<Vec<_>>()
            };
            assert_eq!(bits(avx), bits(portable));
        }
    }
}
