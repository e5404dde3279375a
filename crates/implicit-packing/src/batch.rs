//! Pair terms with their gradients four at a time: the model's kernel on many pairs.
//!
//! In a packing almost every pair that reaches the kernel (its enclosing balls meet and the
//! centre-line certificate does not separate it) takes the direct route of the projection
//! (centre outside, `cond(F) ≤ 8`) with `U ≥ ε`, where `∇f = −2 (1 − d²) ∇d²`. That route is a
//! chain of dependent 3×3 products: one pair keeps the processor waiting on latencies, four
//! pairs in the four lanes of an AVX register fill them. The model's queue collects the pairs
//! that reach the kernel and solves them four at a time; a lane that leaves the route (centre
//! inside, stiff shapes, `U < ε`, an iteration that does not settle) is handed to the scalar
//! [`pair_gradient`], which takes the SVD route for it.
//!
//! The four-lane kernel runs the same generic formulas as the scalar one
//! (`lanes::Real`): every result is the same bits as [`pair_gradient`]'s, and the
//! model's sums, added in the order the pairs arrive, are the same bits with or without it.
//! Without AVX2 and FMA the queue solves each pair with [`pair_gradient`].

use crate::derivatives::{PairGradient, pair_gradient};
#[cfg(any(test, feature = "internals"))]
use crate::error::Error;
use crate::pair::{
    CentreLine, bounding_spheres_apart, centre_line, certified_separated, overlap_measure,
};
use crate::shape::Body;

/// `f` and `∇f` of one pair, as [`pair_gradient`] returns them.
pub type Term<const N: usize> = (f64, PairGradient<N>);

/// A pair waiting for the kernel, with the centre line its certificate computed.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Waiting<const N: usize> {
    i: usize,
    j: usize,
    line: CentreLine<N>,
    /// Both items round: the closed form of module `round` solves the pair, not the kernel.
    round: bool,
}

/// What the queue computes for a pair: `f` with its gradient ([`WithGradient`]) or `f`
/// alone ([`ValueOnly`]).
pub(crate) trait Kernel<const N: usize> {
    /// The result for one pair.
    type Out;
    /// One pair by the scalar path (which decides every route).
    fn one(i: &Body<N>, j: &Body<N>) -> Self::Out;
    /// Four pairs on the four-lane direct route; `None` for a lane it does not cover, or
    /// everywhere without AVX2 and FMA.
    fn four(bodies: &[Body<N>], w: &[Waiting<N>; LANES]) -> [Option<Self::Out>; LANES];
}

/// `f` and `∇f` ([`pair_gradient`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct WithGradient;

/// `f` alone ([`overlap_measure`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ValueOnly;

impl<const N: usize> Kernel<N> for WithGradient {
    type Out = Term<N>;
    #[inline]
    fn one(i: &Body<N>, j: &Body<N>) -> Term<N> {
        pair_gradient(i, j)
    }
    #[inline]
    fn four(bodies: &[Body<N>], w: &[Waiting<N>; LANES]) -> [Option<Term<N>>; LANES] {
        #[cfg(target_arch = "x86_64")]
        if simd::has_avx2_fma() {
            // SAFETY: the processor has AVX2 and FMA, just checked.
            return unsafe { avx::terms(bodies, w) };
        }
        let _ = (bodies, w);
        [None; LANES]
    }
}

impl<const N: usize> Kernel<N> for ValueOnly {
    type Out = f64;
    #[inline]
    fn one(i: &Body<N>, j: &Body<N>) -> f64 {
        overlap_measure(i, j)
    }
    #[inline]
    fn four(bodies: &[Body<N>], w: &[Waiting<N>; LANES]) -> [Option<f64>; LANES] {
        #[cfg(target_arch = "x86_64")]
        if simd::has_avx2_fma() {
            // SAFETY: the processor has AVX2 and FMA, just checked.
            return unsafe { avx::values(bodies, w) };
        }
        let _ = (bodies, w);
        [None; LANES]
    }
}

/// Collects the pairs that need the kernel and solves them four at a time.
///
/// [`KernelQueue::push`] applies the bounding-sphere and centre-line tests at once (a pair
/// they settle has `f = 0` and is dropped); the others wait, and are solved four at a time
/// once [`CAPACITY`] of them are there (or at [`KernelQueue::flush`]). Every solved pair is
/// handed to `emit(i, j, result)` in the order the pairs were pushed, so a sum over the
/// emitted results adds them in the same order as a loop of scalar calls.
///
/// Why wait for so many: whether a candidate needs the kernel is a coin toss (about a third
/// do, at random), and so is whether it is the fourth. Branches on either would be
/// mispredicted on a large share of the candidates, so the certificate's verdict only advances
/// a count, and the one branch left, on a full queue, is taken once per [`CAPACITY`] pairs.
///
/// The pairs are held in a fixed array, not a `Vec`: the model allocates nothing per
/// evaluation.
#[derive(Debug, Clone)]
pub(crate) struct KernelQueue<const N: usize, K> {
    waiting: [Waiting<N>; CAPACITY],
    len: usize,
    kernel: core::marker::PhantomData<K>,
}

impl<const N: usize, K> Default for KernelQueue<N, K> {
    fn default() -> Self {
        let empty = Waiting {
            i: 0,
            j: 0,
            line: CentreLine {
                in_i: [0.0; N],
                in_j: [0.0; N],
                norm2: 0.0,
            },
            round: false,
        };
        Self {
            waiting: [empty; CAPACITY],
            len: 0,
            kernel: core::marker::PhantomData,
        }
    }
}

const LANES: usize = 4;

/// Pairs a [`KernelQueue`] holds before it solves them (a multiple of [`LANES`]; 4.6 kB of
/// centre lines in 3D, which stay in the first-level cache).
const CAPACITY: usize = 64;

impl<const N: usize, K: Kernel<N>> KernelQueue<N, K> {
    /// Adds the pair `(i, j)` of `bodies`; solves the waiting pairs when the queue is full.
    #[inline]
    pub(crate) fn push(
        &mut self,
        bodies: &[Body<N>],
        i: usize,
        j: usize,
        emit: &mut impl FnMut(usize, usize, &K::Out),
    ) {
        let (bi, bj) = (&bodies[i], &bodies[j]);
        if bounding_spheres_apart(bi, bj) {
            return;
        }
        let line = centre_line(bi, bj);
        // Two round items whose enclosing balls meet overlap or touch: no certificate needed.
        let round = bi.is_round() && bj.is_round();
        // Written in any case; the count advances only for a pair that must be solved.
        let keep = round || !certified_separated(bi, bj, &line);
        self.waiting[self.len] = Waiting { i, j, line, round };
        self.len += usize::from(keep);
        if self.len == CAPACITY {
            self.solve_fours(bodies, emit);
        }
    }

    /// Solves every waiting pair: four at a time, the last (fewer than four) one at a time.
    pub(crate) fn flush(
        &mut self,
        bodies: &[Body<N>],
        emit: &mut impl FnMut(usize, usize, &K::Out),
    ) {
        self.solve_fours(bodies, emit);
        for w in &self.waiting[..self.len] {
            emit(w.i, w.j, &K::one(&bodies[w.i], &bodies[w.j]));
        }
        self.len = 0;
    }

    /// Solves the waiting pairs four at a time and keeps the last (fewer than four) waiting.
    fn solve_fours(&mut self, bodies: &[Body<N>], emit: &mut impl FnMut(usize, usize, &K::Out)) {
        let (fours, _) = self.waiting[..self.len].as_chunks::<LANES>();
        for w in fours {
            // The kernel does not solve round pairs; four of them skip it.
            let solved = if w.iter().all(|p| p.round) {
                core::array::from_fn(|_| None)
            } else {
                K::four(bodies, w)
            };
            for (k, out) in solved.iter().enumerate() {
                let (i, j) = (w[k].i, w[k].j);
                match out {
                    Some(o) if !w[k].round => emit(i, j, o),
                    _ => emit(i, j, &K::one(&bodies[i], &bodies[j])),
                }
            }
        }
        let solved = fours.len() * LANES;
        self.waiting.copy_within(solved..self.len, 0);
        self.len -= solved;
    }
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use super::{LANES, Term, Waiting};
    use crate::derivatives::{PairGradient, PairVector, direct_gradient};
    use crate::lanes::{F64x4, Mask4, Real, lanes_of};
    use crate::pair::{BodyOf, DIRECT_CONDITION_LIMIT, epsilon_from_extremes, frame_factor};
    use crate::projection::{
        DIRECT_B2_LIMIT, DIRECT_MAX_ITERATIONS, DirectProjection, DirectStart, HalleyAt, norm2,
    };
    use crate::shape::Body;

    /// Four values, one per lane, from `f(lane)`.
    #[inline(always)]
    fn gather(f: impl Fn(usize) -> f64) -> F64x4 {
        lanes_of([f(0), f(1), f(2), f(3)])
    }

    #[inline(always)]
    fn gather_n<const N: usize>(f: impl Fn(usize, usize) -> f64) -> [F64x4; N] {
        let mut o = [F64x4::splat(0.0); N];
        for k in 0..N {
            o[k] = gather(|l| f(l, k));
        }
        o
    }

    #[inline(always)]
    fn gather_nn<const N: usize>(f: impl Fn(usize, usize, usize) -> f64) -> [[F64x4; N]; N] {
        let mut o = [[F64x4::splat(0.0); N]; N];
        for r in 0..N {
            o[r] = gather_n(|l, k| f(l, r, k));
        }
        o
    }

    /// `if m { a } else { b }` for a settled solution, lane by lane.
    #[inline(always)]
    fn select<const N: usize>(
        m: Mask4,
        a: &DirectProjection<N, F64x4>,
        b: &DirectProjection<N, F64x4>,
    ) -> DirectProjection<N, F64x4> {
        let pick = |x: F64x4, y: F64x4| F64x4::select(m, x, y);
        let mut out = *b;
        for k in 0..N {
            out.x[k] = pick(a.x[k], b.x[k]);
            out.c_minus_x[k] = pick(a.c_minus_x[k], b.c_minus_x[k]);
        }
        out.u = pick(a.u, b.u);
        out.d2 = pick(a.d2, b.d2);
        out
    }

    /// Four pairs on the direct route of the projection: the scalar path after the
    /// certificate (`setup_from`, `solve_direct`), lane by lane, with masks where it branches.
    struct Four<const N: usize> {
        /// Bit k set when lane k settled on the direct route.
        settled: u32,
        solved: DirectProjection<N, F64x4>,
        eps: F64x4,
        qi: [[F64x4; N]; N],
        li: [F64x4; N],
        inv_li: [F64x4; N],
    }

    /// Only called from the `#[target_feature(enable = "avx2,fma")]` functions below, into
    /// which it inlines.
    #[inline(always)]
    fn solve<const N: usize>(bodies: &[Body<N>], w: &[Waiting<N>; LANES]) -> Four<N> {
        let bi = [0, 1, 2, 3].map(|l| &bodies[w[l].i]);
        let bj = [0, 1, 2, 3].map(|l| &bodies[w[l].j]);
        let in_i = gather_n(|l, k| w[l].line.in_i[k]);
        let in_j = gather_n(|l, k| w[l].line.in_j[k]);
        let qi = gather_nn(|l, r, k| bi[l].rotation()[r][k]);
        let qj = gather_nn(|l, r, k| bj[l].rotation()[r][k]);
        let li = gather_n(|l, k| bi[l].semi_axes()[k]);
        let lj = gather_n(|l, k| bj[l].semi_axes()[k]);
        let inv_li = gather_n(|l, k| bi[l].inv_semi_axes()[k]);
        let inv_lj = gather_n(|l, k| bj[l].inv_semi_axes()[k]);
        let (imin, imax) = (
            gather(|l| bi[l].min_semi_axis()),
            gather(|l| bi[l].bounding_radius()),
        );
        let (jmin, jmax) = (
            gather(|l| bj[l].min_semi_axis()),
            gather(|l| bj[l].bounding_radius()),
        );

        let (c, b, f) = frame_factor(
            &in_i,
            &in_j,
            BodyOf {
                q: &qi,
                l: &li,
                inv_l: &inv_li,
            },
            BodyOf {
                q: &qj,
                l: &lj,
                inv_l: &inv_lj,
            },
        );
        let eps = epsilon_from_extremes(imin, imax, jmin, jmax);
        let splat = F64x4::splat;
        // `setup_from`'s `well_conditioned` and `solve_direct`'s tests on |b|².
        let well = (imax * jmax).le(splat(DIRECT_CONDITION_LIMIT) * (imin * jmin));
        let b2 = norm2(&b);
        let mut active = well & b2.gt(splat(1.0)) & b2.le(splat(DIRECT_B2_LIMIT));
        let start = DirectStart::new(&f, &c, b2);
        let mut u = start.u0;
        let zero = splat(0.0);
        let mut solved = DirectProjection {
            u: zero,
            x: [zero; N],
            c_minus_x: [zero; N],
            d2: zero,
        };
        let mut settled = 0u32;
        // `solve_outside_direct`'s loop; a lane leaves it when it settles or gives up.
        for _ in 0..DIRECT_MAX_ITERATIONS {
            if !active.any() {
                break;
            }
            let h = HalleyAt::at(&start.s, &c, u);
            // The scalar loop gives up on a step that is not finite.
            active = active & splat(f64::INFINITY).gt(h.step.abs());
            let now = active & h.settled(u);
            if now.any() {
                solved = select(now, &h.finish(&start.s, u), &solved);
                settled |= now.bits();
                active = active.and_not(now);
            }
            u = F64x4::select(active, h.next(u, start.lo), u);
        }
        Four {
            settled,
            solved,
            eps,
            qi,
            li,
            inv_li,
        }
    }

    /// `f = max{0, 1 − d²}² + max{0, ε − U}²` for four pairs: `overlap_measure` lane by lane.
    ///
    /// # Safety
    /// The processor must have AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn values<const N: usize>(
        bodies: &[Body<N>],
        w: &[Waiting<N>; LANES],
    ) -> [Option<f64>; LANES] {
        let four = solve(bodies, w);
        let zero = F64x4::splat(0.0);
        let a = (F64x4::splat(1.0) - four.solved.d2).max(zero);
        let b = (four.eps - four.solved.u).max(zero);
        let f = (a * a + b * b).to_array();
        core::array::from_fn(|l| (four.settled & (1 << l) != 0).then_some(f[l]))
    }

    /// `f` and `∇f` for four pairs: `pair_gradient`'s path for the direct route with
    /// `U ≥ ε`, lane by lane; the other lanes come back `None`.
    ///
    /// # Safety
    /// The processor must have AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn terms<const N: usize>(
        bodies: &[Body<N>],
        w: &[Waiting<N>; LANES],
    ) -> [Option<Term<N>>; LANES] {
        let four = solve(bodies, w);
        let delta = gather_n(|l, k| bodies[w[l].i].centre()[k] - bodies[w[l].j].centre()[k]);
        // The fast path of `pair_gradient` needs U ≥ ε (else ∇U, in the eigenbasis).
        let covered = four.settled & four.solved.u.ge(four.eps).bits();
        let zero = F64x4::splat(0.0);
        let a = (F64x4::splat(1.0) - four.solved.d2).max(zero);
        let overlapping = a.gt(zero).bits();
        let parts = direct_gradient(
            a,
            &four.solved,
            BodyOf {
                q: &four.qi,
                l: &four.li,
                inv_l: &four.inv_li,
            },
            &delta,
        );
        let fv = (a * a).to_array();
        let lanes = Lanes::of(&parts);
        core::array::from_fn(|l| {
            let bit = 1 << l;
            if covered & bit == 0 {
                None
            } else if overlapping & bit == 0 {
                Some((0.0, PairGradient::ZERO))
            } else {
                Some((fv[l], lanes.gradient(l)))
            }
        })
    }

    /// The gradient's lanes as arrays, to hand out lane by lane.
    struct Lanes<const N: usize> {
        centre_i: [[f64; LANES]; N],
        centre_j: [[f64; LANES]; N],
        angular_i: [[f64; LANES]; 3],
        angular_j: [[f64; LANES]; 3],
    }

    impl<const N: usize> Lanes<N> {
        #[inline(always)]
        fn of(g: &PairVector<F64x4, N>) -> Self {
            let mut out = Self {
                centre_i: [[0.0; LANES]; N],
                centre_j: [[0.0; LANES]; N],
                angular_i: [[0.0; LANES]; 3],
                angular_j: [[0.0; LANES]; 3],
            };
            for k in 0..N {
                out.centre_i[k] = g.centre_i[k].to_array();
                out.centre_j[k] = g.centre_j[k].to_array();
            }
            for k in 0..3 {
                out.angular_i[k] = g.angular_i[k].to_array();
                out.angular_j[k] = g.angular_j[k].to_array();
            }
            out
        }

        #[inline(always)]
        fn gradient(&self, l: usize) -> PairGradient<N> {
            PairGradient {
                centre_i: self.centre_i.map(|v| v[l]),
                centre_j: self.centre_j.map(|v| v[l]),
                angular_i: self.angular_i.map(|v| v[l]),
                angular_j: self.angular_j.map(|v| v[l]),
            }
        }
    }
}

/// `f` and `∇f` for each pair `(i, j)` of `bodies`, the same bits as [`pair_gradient`] on
/// each, computed four pairs at a time where the processor allows (about twice as fast per
/// pair in a packing; see the crate's `model` bench). For callers with their own neighbour
/// lists (a DEM or MD code); [`crate::model::Model`] uses the same kernel.
///
/// # Errors
/// [`Error::PairIndex`] naming the first pair with an index out of range (nothing is
/// computed then); [`Error::LengthMismatch`] if `out` is not as long as `pairs`.
///
/// # Example
/// ```
/// use implicit_packing::{Body, batch::pair_gradients};
/// use implicit_packing::derivatives::{PairGradient, pair_gradient};
/// let bodies: Vec<_> = (0..6)
///     .map(|k| Body::<3>::from_angles([0.9 * k as f64, 0.1, 0.0], [1.0, 0.75, 0.5], [0.3 * k as f64, 0.5, 0.1]))
///     .collect::<Result<_, _>>()?;
/// let pairs: Vec<(usize, usize)> = (0..5).map(|k| (k, k + 1)).collect();
/// let mut out = vec![(0.0, PairGradient::ZERO); pairs.len()];
/// pair_gradients(&bodies, &pairs, &mut out)?;
/// assert_eq!(out[2], pair_gradient(&bodies[2], &bodies[3]));
/// # Ok::<(), implicit_packing::Error>(())
/// ```
#[cfg(any(test, feature = "internals"))]
pub fn pair_gradients<const N: usize>(
    bodies: &[Body<N>],
    pairs: &[(usize, usize)],
    out: &mut [Term<N>],
) -> Result<(), Error> {
    Error::check_length("pair gradients", pairs.len(), out.len())?;
    if let Some((pair, &(i, j))) = pairs
        .iter()
        .enumerate()
        .find(|&(_, &(i, j))| i >= bodies.len() || j >= bodies.len())
    {
        return Err(Error::PairIndex {
            pair,
            indices: (i, j),
            len: bodies.len(),
        });
    }
    // The queue emits in push order; pairs it settles without the kernel are zero.
    out.fill((0.0, PairGradient::ZERO));
    let mut queue = KernelQueue::<N, WithGradient>::default();
    let mut next = 0;
    let mut emit = |i: usize, j: usize, t: &Term<N>| {
        // Skip the pairs the certificate settled: their terms stay zero.
        while pairs[next] != (i, j) {
            next += 1;
        }
        out[next] = *t;
        next += 1;
    };
    for &(i, j) in pairs {
        queue.push(bodies, i, j, &mut emit);
    }
    queue.flush(bodies, &mut emit);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (the tests need no random-number crate).
    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn bits<const N: usize>(t: &Term<N>) -> Vec<u64> {
        let g = &t.1;
        core::iter::once(t.0)
            .chain(g.centre_i)
            .chain(g.centre_j)
            .chain(g.angular_i)
            .chain(g.angular_j)
            .map(f64::to_bits)
            .collect()
    }

    /// Pairs of every kind the kernel meets: the paper's shape near contact (the direct
    /// route), deep overlaps (centre inside, `U < ε`), stiff shapes (the SVD route), distant
    /// pairs; `kind` cycles through them.
    fn pair_3d(rng: &mut Lcg, kind: usize) -> (Body<3>, Body<3>) {
        let body = |rng: &mut Lcg, axes: [f64; 3], spread: f64| {
            let c = [0.0; 3].map(|_| spread * (2.0 * rng.next() - 1.0));
            let angles = [6.3 * rng.next(), 3.2 * rng.next(), 6.3 * rng.next()];
            Body::from_angles(c, axes, angles).expect("valid body")
        };
        let s = 0.9 + 0.2 * rng.next();
        let paper = [s, 0.75 * s, 0.5 * s];
        match kind % 4 {
            0 => {
                // Centres 0.9 to 1.6 apart: near contact, as in a packing.
                let a = body(rng, paper, 0.0);
                let b = body(rng, paper, 0.0);
                let z: f64 = 2.0 * rng.next() - 1.0;
                let phi = 6.3 * rng.next();
                let r = (1.0 - z * z).sqrt();
                let d = (0.9 + 0.7 * rng.next()) * s;
                let c = [d * r * phi.cos(), d * r * phi.sin(), d * z];
                (a, b.with_centre(c).expect("finite"))
            }
            1 => (body(rng, paper, 0.45), body(rng, paper, 0.45)),
            2 => {
                let thin = 10f64.powf(-3.0 * rng.next());
                (
                    body(rng, [1.0, thin, thin], 0.6),
                    body(rng, [0.8, 0.5, 0.3 * thin], 0.6),
                )
            }
            _ => (body(rng, paper, 3.0), body(rng, paper, 3.0)),
        }
    }

    /// `n` pairs of [`pair_3d`], the pair `k` at bodies `2k`, `2k + 1`.
    fn pairs_3d(rng: &mut Lcg, n: usize) -> Vec<Body<3>> {
        (0..n)
            .flat_map(|k| {
                let (a, b) = pair_3d(rng, k);
                [a, b]
            })
            .collect()
    }

    /// Every lane the four-lane kernel answers is `pair_gradient`'s (or `overlap_measure`'s)
    /// answer, bit for bit, and it answers most lanes of the direct route (so that this test
    /// exercises it).
    #[test]
    fn four_lanes_are_the_scalar_kernel_bit_for_bit() {
        let mut rng = Lcg(17);
        let bodies = pairs_3d(&mut rng, 40_000);
        let mut waiting: [Vec<Waiting<3>>; 4] = Default::default();
        for p in 0..bodies.len() / 2 {
            let (i, j) = (2 * p, 2 * p + 1);
            let (bi, bj) = (&bodies[i], &bodies[j]);
            let line = centre_line(bi, bj);
            if !bounding_spheres_apart(bi, bj) && !certified_separated(bi, bj, &line) {
                waiting[p % 4].push(Waiting {
                    i,
                    j,
                    line,
                    round: false,
                });
            }
        }
        let has_lanes = simd::has_avx2_fma();
        for (kind, list) in waiting.iter().enumerate() {
            let (mut answered, mut nonzero, mut values) = (0, 0, 0);
            for chunk in list.chunks_exact(LANES) {
                let w: [Waiting<3>; LANES] = core::array::from_fn(|k| chunk[k]);
                for (k, term) in WithGradient::four(&bodies, &w).iter().enumerate() {
                    if let Some(t) = term {
                        let scalar = pair_gradient(&bodies[w[k].i], &bodies[w[k].j]);
                        assert_eq!(bits(t), bits(&scalar), "kind {kind}, pair {:?}", w[k]);
                        answered += 1;
                        nonzero += usize::from(t.0 > 0.0);
                    }
                }
                for (k, value) in ValueOnly::four(&bodies, &w).iter().enumerate() {
                    if let Some(v) = value {
                        let scalar = overlap_measure(&bodies[w[k].i], &bodies[w[k].j]);
                        assert_eq!(
                            v.to_bits(),
                            scalar.to_bits(),
                            "kind {kind}, pair {:?}",
                            w[k]
                        );
                        values += 1;
                    }
                }
            }
            let share = answered as f64 / list.len() as f64;
            println!(
                "kind {kind}: {} pairs reach the kernel, {answered} answered by the lanes ({nonzero} overlapping)",
                list.len()
            );
            if has_lanes {
                // The value needs no U ≥ ε: it covers at least the lanes the gradient does.
                assert!(values >= answered);
                match kind {
                    // Near contact: almost all on the direct route, most overlapping.
                    0 => assert!(share > 0.95 && nonzero > answered / 2, "share {share}"),
                    // Deep overlaps and stiff shapes: both the lanes and the fallback occur.
                    1 | 2 => assert!(share > 0.05 && share < 0.95, "kind {kind}: share {share}"),
                    _ => {}
                }
            }
        }
    }

    /// The public batch equals a loop of `pair_gradient` (3D and 2D, any length, repeated
    /// and distant pairs), and bad indices or lengths are typed errors.
    #[test]
    fn pair_gradients_equals_the_loop() {
        let mut rng = Lcg(5);
        let bodies = pairs_3d(&mut rng, 600);
        for len in [0, 1, 3, 4, 5, 599, 1203] {
            let pairs: Vec<(usize, usize)> = (0..len)
                .map(|k| {
                    let i = (k * 7) % bodies.len();
                    let j = if k % 5 == 0 {
                        i ^ 1
                    } else {
                        (k * 13 + 1) % bodies.len()
                    };
                    (i, j)
                })
                .collect();
            let mut out = vec![(f64::NAN, PairGradient::ZERO); len];
            pair_gradients(&bodies, &pairs, &mut out).expect("valid pairs");
            for (k, &(i, j)) in pairs.iter().enumerate() {
                assert_eq!(bits(&out[k]), bits(&pair_gradient(&bodies[i], &bodies[j])));
            }
        }
        let ellipses: Vec<Body<2>> = (0..400)
            .map(|k| {
                let c = [0.9 * (k % 20) as f64, 0.7 * (k / 20) as f64];
                let t = rng.next();
                Body::ellipse(c, [0.6 + 0.2 * t, 0.3], 6.3 * rng.next()).expect("valid")
            })
            .collect();
        let pairs: Vec<(usize, usize)> = (0..399).map(|k| (k, k + 1)).collect();
        let mut out = vec![(0.0, PairGradient::ZERO); pairs.len()];
        pair_gradients(&ellipses, &pairs, &mut out).expect("valid pairs");
        let overlapping = out.iter().filter(|t| t.0 > 0.0).count();
        assert!(overlapping > 100, "{overlapping}");
        for (k, &(i, j)) in pairs.iter().enumerate() {
            assert_eq!(
                bits(&out[k]),
                bits(&pair_gradient(&ellipses[i], &ellipses[j]))
            );
        }

        let mut two = vec![(0.0, PairGradient::ZERO); 2];
        assert_eq!(
            pair_gradients(&ellipses, &[(0, 1), (3, 400)], &mut two),
            Err(Error::PairIndex {
                pair: 1,
                indices: (3, 400),
                len: 400
            })
        );
        assert!(matches!(
            pair_gradients(&ellipses, &[(0, 1)], &mut two),
            Err(Error::LengthMismatch { .. })
        ));
    }
}
