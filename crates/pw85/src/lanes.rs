//! Four pairs side by side, lane by lane, for the batched path (and, in [`Ends4`], the two ends
//! of one pair's pencil with their magnitudes, for the scalar path).
//!
//! [`V4`] holds one `f64` per pair and does every operation lane-wise: written this way, the
//! compiler keeps the four lanes in one 256-bit register where AVX is available (two 128-bit
//! ones otherwise). Each lane performs exactly the operations of the scalar code in the same
//! order, so the batched results equal the scalar ones bit for bit; the lanes only differ in
//! when they stop, and a lane that has stopped keeps its state (selects, not branches).

use crate::arith::Arith;
use crate::poly::OddsForm;
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

impl Add for Ends4 {
    type Output = Ends4;
    #[inline(always)]
    fn add(self, o: Ends4) -> Ends4 {
        Ends4(self.0 + o.0)
    }
}
impl Sub for Ends4 {
    type Output = Ends4;
    #[allow(clippy::suspicious_arithmetic_impl)] // see SUB_SIGNS
    #[inline(always)]
    fn sub(self, o: Ends4) -> Ends4 {
        Ends4(self.0 + o.0 * SUB_SIGNS)
    }
}
impl Mul for Ends4 {
    type Output = Ends4;
    #[inline(always)]
    fn mul(self, o: Ends4) -> Ends4 {
        Ends4(self.0 * o.0)
    }
}
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

/// The arithmetic of [`crate::poly::coefficients_with_bound`]'s four-lane pass: [`Ends4`] in
/// the portable build, [`Ends4Avx`] in the AVX2 build.
pub(crate) trait EndsLanes: Arith {
    /// [a, b, |a|, |b|] in this type's layout.
    fn of(a: f64, b: f64) -> Self;
    /// [x(Q1), x(Q2), Σ|terms| of x(Q1), Σ|terms| of x(Q2)].
    fn lanes(self) -> [f64; 4];
}

impl EndsLanes for Ends4 {
    #[inline(always)]
    fn of(a: f64, b: f64) -> Self {
        Ends4(V4([a, b, a.abs(), b.abs()]))
    }
    #[inline(always)]
    fn lanes(self) -> [f64; 4] {
        // Left to itself the optimiser splits the four-lane expressions into one scalar chain
        // per lane read (more instructions than the vector form); materialising the result
        // keeps each operation one vector instruction. ([`Ends4Avx`] is a vector type and
        // needs no such help: there this barrier cost 8 instructions per call.)
        core::hint::black_box(self).0.0
    }
}

#[cfg(target_arch = "x86_64")]
pub(crate) use avx::Ends4Avx;

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::EndsLanes;
    use crate::arith::Arith;
    use core::arch::x86_64::{
        __m256d, _mm256_add_pd, _mm256_addsub_pd, _mm256_mul_pd, _mm256_setr_pd, _mm256_storeu_pd,
    };
    use core::ops::{Add, Mul, Sub};

    /// [`super::Ends4`] as one AVX register, lanes [x(Q1), Σ|terms|(Q1), x(Q2), Σ|terms|(Q2)]:
    /// written with `[f64; 4]` the optimiser splits the lanes into scalars and re-packs them
    /// into 128-bit halves with shuffles and stack spills (callgrind: 340 instructions per
    /// call in the coefficients); as a vector type every operation is one instruction. In this
    /// layout a − b is ADDSUBPD, which subtracts in the even (value) lanes and adds in the odd
    /// (magnitude) ones: the subtraction of the `f64` formula and the addition of the `Mag`
    /// one, each with its own rounding, so the results are the same bits as [`super::Ends4`].
    ///
    /// Values of this type are only created in the AVX2 + FMA build of a dispatched function
    /// (`FMA = true` in [`crate::dispatch::multiversion`]), after the processor was checked to
    /// have AVX2 and FMA: that is what makes the intrinsics below sound.
    #[derive(Clone, Copy, Debug)]
    pub(crate) struct Ends4Avx(__m256d);

    impl Add for Ends4Avx {
        type Output = Self;
        #[inline(always)]
        fn add(self, o: Self) -> Self {
            // SAFETY: AVX is available wherever an `Ends4Avx` exists (see the type).
            Self(unsafe { _mm256_add_pd(self.0, o.0) })
        }
    }
    impl Sub for Ends4Avx {
        type Output = Self;
        #[inline(always)]
        fn sub(self, o: Self) -> Self {
            // SAFETY: as in `add`.
            Self(unsafe { _mm256_addsub_pd(self.0, o.0) })
        }
    }
    impl Mul for Ends4Avx {
        type Output = Self;
        #[inline(always)]
        fn mul(self, o: Self) -> Self {
            // SAFETY: as in `add`.
            Self(unsafe { _mm256_mul_pd(self.0, o.0) })
        }
    }
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
            debug_assert!(crate::dispatch::has_avx2_fma());
            // SAFETY: only called in the AVX2 build (see the type).
            Self(unsafe { _mm256_setr_pd(a, a.abs(), b, b.abs()) })
        }
        #[inline(always)]
        fn lanes(self) -> [f64; 4] {
            let mut out = [0.0; 4];
            // SAFETY: as in `of`; `out` has room for four doubles.
            unsafe { _mm256_storeu_pd(out.as_mut_ptr(), self.0) };
            [out[0], out[2], out[1], out[3]]
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

/// Four lanes of truth values (the comparisons of the lane-wise search).
type Mask = [bool; LANES];

impl V4 {
    #[inline(always)]
    fn cmp(self, o: V4, f: impl Fn(f64, f64) -> bool) -> Mask {
        core::array::from_fn(|k| f(self.0[k], o.0[k]))
    }
    /// `self` where `mask` is true, `other` elsewhere.
    #[inline(always)]
    fn or_else(self, mask: Mask, other: V4) -> V4 {
        V4::from_fn(|k| if mask[k] { self.0[k] } else { other.0[k] })
    }
    #[inline(always)]
    fn abs(self) -> V4 {
        V4(self.0.map(f64::abs))
    }
    #[inline(always)]
    fn sqrt(self) -> V4 {
        V4(self.0.map(f64::sqrt))
    }
}

#[inline(always)]
fn and(a: Mask, b: Mask) -> Mask {
    core::array::from_fn(|k| a[k] & b[k])
}
#[inline(always)]
fn or(a: Mask, b: Mask) -> Mask {
    core::array::from_fn(|k| a[k] | b[k])
}
#[inline(always)]
fn not(a: Mask) -> Mask {
    a.map(|x| !x)
}

/// Four odds searches ([`crate::poly::OddsSearch`]) side by side, as four-lane values.
#[derive(Clone, Copy, Debug)]
pub(crate) struct OddsSearch4 {
    /// The current iterates; u₀ in the lanes that are done (and not `fallback`).
    pub u: V4,
    lo: V4,
    hi: V4,
    /// Iterations so far, as a float (exact: at most 101).
    iterations: V4,
    done: Mask,
    /// The lanes whose values left the trustworthy range ([`crate::poly::OddsSearch::fallback`]).
    pub fallback: Mask,
}

impl OddsSearch4 {
    #[inline(always)]
    fn new(u0: [f64; LANES]) -> Self {
        let ok: Mask = u0.map(|u| u > 0.0 && u < f64::INFINITY);
        Self {
            u: V4(u0),
            lo: V4::lift(0.0),
            hi: V4::lift(f64::INFINITY),
            iterations: V4::lift(0.0),
            done: not(ok),
            fallback: not(ok),
        }
    }

    /// [`crate::poly::OddsSearch::advance`] in every lane that is not done, with the same operations on
    /// the same values (so the same bits); the branches of the scalar rule become selects, so
    /// the four lanes stay in vector registers and no lane's branch is mispredicted. Every
    /// candidate of the scalar rule (Halley's point, the bracket's expansion, contraction or
    /// geometric midpoint) is computed in every lane, and the rule's decisions pick one.
    #[inline(always)]
    fn advance(&mut self, (p, n, v, step): (V4, V4, V4, V4)) {
        use crate::poly::HALLEY_LAST_STEP as TOL;
        let active = not(self.done);
        let u = self.u;
        let iterations = self.iterations + V4::from_fn(|k| if active[k] { 1.0 } else { 0.0 });
        let tiny = V4::lift(1e-60);
        let bad = or(
            not(and(
                v.cmp(tiny, |a, b| a > b),
                n.abs().cmp(tiny, |a, b| a > b),
            )),
            iterations.cmp(V4::lift(100.0), |a, b| a > b),
        );
        let below = p.cmp(V4::lift(0.0), |a, b| a > b);
        let lo = u.or_else(below, self.lo);
        let hi = self.hi.or_else(below, u);
        let next = u - step;
        let small = step.abs().cmp(V4::lift(TOL) * u, |a, b| a <= b);
        let trusted = (p * v)
            .abs()
            .cmp(V4::lift(2.0 * TOL) * u * n.abs(), |a, b| a <= b);
        let accept = and(
            and(small, trusted),
            and(next.cmp(lo, |a, b| a >= b), next.cmp(hi, |a, b| a <= b)),
        );
        let inside = and(
            and(next.cmp(lo, |a, b| a > b), next.cmp(hi, |a, b| a < b)),
            or(trusted, not(small)),
        );
        let expand = hi.cmp(V4::lift(f64::INFINITY), |a, b| a == b);
        let contract = lo.cmp(V4::lift(0.0), |a, b| a == b);
        let bisect = (lo * hi).sqrt();
        let fallback =
            (V4::lift(4.0) * u).or_else(expand, (V4::lift(0.25) * u).or_else(contract, bisect));
        let moved = next.or_else(or(accept, inside), fallback);
        // Accepted, or the bracket is down to adjacent doubles (the scalar rule's `next == u`).
        let finished = or(accept, moved.cmp(u, |a, b| a == b));
        let step_lanes = and(active, not(bad));
        self.iterations = iterations;
        self.lo = lo.or_else(step_lanes, self.lo);
        self.hi = hi.or_else(step_lanes, self.hi);
        self.u = moved.or_else(step_lanes, u);
        self.fallback = or(self.fallback, and(active, bad));
        self.done = or(self.done, or(and(active, bad), and(step_lanes, finished)));
    }
}

/// The odds iteration of [`crate::contact_function`] ([`crate::poly::OddsSearch`]) on four pairs at once,
/// from the starting points `u0`: the Halley terms and the step rule are both computed for all
/// lanes together ([`OddsSearch4::advance`]); a stopped lane's state is frozen.
#[inline(always)]
pub(crate) fn maximise4<const FMA: bool>(odds: &OddsForm<V4>, u0: [f64; LANES]) -> OddsSearch4 {
    let mut search = OddsSearch4::new(u0);
    while search.done.iter().any(|d| !d) {
        search.advance(odds.halley_terms::<FMA>(search.u));
    }
    search
}

#[cfg(test)]
mod tests {
    /// The vector-register form of the four-lane pass gives the same bits as the array form
    /// (and so as the scalar `f64` and `Mag` formulas), lanes in the same order.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn avx_ends_equal_portable_ends_bit_for_bit() {
        use crate::poly::coefficients_with_bound;
        if !crate::dispatch::has_avx2_fma() {
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
