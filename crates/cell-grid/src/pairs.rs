//! Enumeration of the pairs: cell against itself and against its forward neighbours.

use std::ops::Range;

use crate::error::Error;
use crate::grid::{Grid, Layout};

/// What to do with one item against a run of items, both given by their positions in cell
/// order.
pub(crate) trait CellPairs<const D: usize> {
    /// Item at position `x` against the items at positions `ys` (none of them `x`, no pair
    /// offered twice over a whole enumeration).
    fn span(&mut self, g: &Grid<D>, x: usize, ys: Range<usize>);

    /// Items `a` against items `b`, keeping only the pairs with position `y > x` (all of `b`
    /// when it lies after `a`; the upper triangle when `b` starts with `a`).
    #[inline]
    fn block(&mut self, g: &Grid<D>, a: Range<usize>, b: Range<usize>) {
        for x in a {
            self.span(g, x, b.start.max(x + 1)..b.end);
        }
    }

    /// All pairs inside one cell.
    #[inline]
    fn same(&mut self, g: &Grid<D>, a: Range<usize>) {
        for x in a.clone() {
            self.span(g, x, x + 1..a.end);
        }
    }

    /// All pairs between two distinct cells.
    #[inline]
    fn cross(&mut self, g: &Grid<D>, a: Range<usize>, b: Range<usize>) {
        for x in a {
            self.span(g, x, b.clone());
        }
    }
}

impl<const D: usize> Grid<D> {
    /// Visits each non-empty slot of `slots` against itself and against every neighbouring
    /// non-empty slot that comes after it, so that each unordered pair of cells is seen once
    /// when `slots` ranges over all slots (or once in total over a partition of them, which
    /// is how the parallel version splits the work). Empty slots are skipped.
    pub(crate) fn drive<V: CellPairs<D>>(&self, slots: Range<usize>, v: &mut V) {
        if self.layout == Layout::Dense && !self.any_periodic {
            // The forward half of the 3^D stencil, in the padded array, is: the next cell
            // along x, and for each forward row offset `h` (along y, z) the three cells
            // `h - 1, h, h + 1`. Consecutive cells own consecutive runs of `order`, so each of
            // these is one contiguous run: 5 runs in 3D instead of 13 cells, 2 in 2D. The
            // ghost layer keeps every index valid without a bounds test.
            let st = &self.start;
            for s in slots {
                let a = st[s]..st[s + 1];
                if a.is_empty() {
                    continue;
                }
                v.block(self, a.clone(), st[s]..st[s + 2]);
                for &h in &self.rows {
                    let t = s + h;
                    let ys = st[t - 1]..st[t + 2];
                    if !ys.is_empty() {
                        v.block(self, a.clone(), ys);
                    }
                }
            }
            return;
        }
        // General path: periodic wrap or hashed cells. With fewer than 3 cells along a
        // periodic axis, offsets -1 and +1 (or all three) name the same cell; keeping only
        // neighbours with a larger slot, and each of them once, still visits each pair of
        // cells exactly once.
        let mut seen = [0usize; 26];
        for s in slots {
            let a = self.start[s]..self.start[s + 1];
            if a.is_empty() {
                continue;
            }
            v.same(self, a.clone());
            let k = self.slot_coords_of(s);
            let mut n_seen = 0;
            'offsets: for o in &self.stencil {
                let mut nk = [0i64; D];
                for ax in 0..D {
                    let mut c = k[ax] + o[ax];
                    if self.periodic[ax] {
                        c = c.rem_euclid(self.dims[ax] as i64);
                    }
                    nk[ax] = c;
                }
                let Some(t) = self.find_slot(&nk) else {
                    continue;
                };
                if t <= s {
                    continue;
                }
                for &u in &seen[..n_seen] {
                    if u == t {
                        continue 'offsets;
                    }
                }
                seen[n_seen] = t;
                n_seen += 1;
                v.cross(self, a.clone(), self.start[t]..self.start[t + 1]);
            }
        }
    }

    /// Calls `f(i, j)` once for every pair `i < j` of items in the same or in adjacent cells.
    ///
    /// This is a superset of the pairs closer than the reach: every pair with
    /// `|c_i - c_j| < cutoff` (or `< r_i + r_j`) is among them, and never `i == j`. Use it
    /// when the caller's own test is cheaper than a distance, or needs all candidates (the
    /// paper evaluates its overlap term on exactly these pairs).
    ///
    /// Items kept out of the cells by the size split (see
    /// [`large_items`](Self::large_items)) are paired with every item of the cells within
    /// their search box and with every other large item.
    pub fn for_each_candidate_pair<F: FnMut(usize, usize)>(&self, mut f: F) {
        self.drive(0..self.slot_count(), &mut Candidates { f: &mut f });
        self.large_candidates(0..self.large_ids.len(), &mut f);
    }

    /// Candidates of the large items `ks` (indices into the large-item arrays): the items of
    /// the cells their reach touches, and the large items after them.
    pub(crate) fn large_candidates<F: FnMut(usize, usize)>(&self, ks: Range<usize>, f: &mut F) {
        for k in ks {
            let i = self.large_ids[k];
            let reach = self.large_r[k] + self.r_small;
            self.search(&self.large_pos[k], reach, |p, _, _| {
                let j = self.order[p];
                f(i.min(j), i.max(j));
            });
            for &j in &self.large_ids[k + 1..] {
                f(i, j);
            }
        }
    }

    /// Close pairs of the large items `ks` with the items of the cells and with the large
    /// items after them.
    pub(crate) fn large_close<F: FnMut(usize, usize, [f64; D], f64)>(
        &self,
        ks: Range<usize>,
        f: &mut F,
    ) {
        for k in ks {
            let i = self.large_ids[k];
            let (x, r) = (self.large_pos[k], self.large_r[k]);
            // Items in cells have radii of at most r_small: none beyond r + r_small can touch.
            self.search(&x, r + self.r_small, |p, d, d2| {
                let s = r + self.sorted_r[p];
                if d2 < s * s {
                    let j = self.order[p];
                    if i < j {
                        f(i, j, d, d2);
                    } else {
                        f(j, i, d.map(|t| -t), d2);
                    }
                }
            });
            for q in k + 1..self.large_ids.len() {
                let d = self.min_image_wrapped(&x, &self.large_pos[q]);
                let d2 = dot(&d, &d);
                let s = r + self.large_r[q];
                if d2 < s * s {
                    f(i, self.large_ids[q], d, d2);
                }
            }
        }
    }

    /// Calls `f(i, j, dist2)` once for every pair `i < j` with `|p_i - p_j| < cutoff`, or
    /// `< r_i + r_j` with per-item radii, where `dist2 = |p_i - p_j|^2` is computed from the
    /// caller's `points` (minimum image on periodic axes).
    ///
    /// The candidates come from the last build: `points` should be the positions that build
    /// saw (or positions moved by less than the caller's own skin, if the cutoff includes one).
    /// [`for_each_close_pair`](Self::for_each_close_pair) is faster: it reads the grid's
    /// cell-ordered copy instead of gathering from `points`.
    ///
    /// # Errors
    /// [`Error::PointCountMismatch`] if `points.len() != self.len()`.
    pub fn for_each_pair_within<F: FnMut(usize, usize, f64)>(
        &self,
        points: &[[f64; D]],
        mut f: F,
    ) -> Result<(), Error> {
        if points.len() != self.len() {
            return Err(Error::PointCountMismatch {
                expected: self.len(),
                found: points.len(),
            });
        }
        let c2 = self.cutoff * self.cutoff;
        let radii = self.radii_mode;
        self.for_each_candidate_pair(|i, j| {
            let d = self.min_image(points[i], points[j]);
            let d2 = dot(&d, &d);
            let lim = if radii {
                let s = self.radii[i] + self.radii[j];
                s * s
            } else {
                c2
            };
            if d2 < lim {
                f(i, j, d2);
            }
        });
        Ok(())
    }

    /// Calls `f(i, j, delta, dist2)` once for every pair `i < j` closer than the cutoff (or
    /// than `r_i + r_j`), with `delta = p_j - p_i` (minimum image on periodic axes) and
    /// `dist2 = |delta|^2`, using the positions of the last build.
    ///
    /// This is the fast path: positions are read in cell order, sequentially in memory.
    pub fn for_each_close_pair<F: FnMut(usize, usize, [f64; D], f64)>(&self, mut f: F) {
        self.close_pairs_over(0..self.slot_count(), &mut f);
        self.large_close(0..self.large_ids.len(), &mut f);
    }

    pub(crate) fn close_pairs_over<F: FnMut(usize, usize, [f64; D], f64)>(
        &self,
        slots: Range<usize>,
        f: F,
    ) {
        match (self.any_periodic, self.radii_mode) {
            (false, false) => self.drive(slots, &mut Close::<F, false, false> { f }),
            (false, true) => self.drive(slots, &mut Close::<F, false, true> { f }),
            (true, false) => self.drive(slots, &mut Close::<F, true, false> { f }),
            (true, true) => self.drive(slots, &mut Close::<F, true, true> { f }),
        }
    }

    /// Number of pairs closer than the reach (counts [`for_each_close_pair`](Self::for_each_close_pair)).
    pub fn count_close_pairs(&self) -> usize {
        let mut n = 0;
        self.for_each_close_pair(|_, _, _, _| n += 1);
        n
    }

    /// All pairs `(i, j)`, `i < j`, closer than the reach, in no particular order.
    pub fn close_pairs(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        self.for_each_close_pair(|i, j, _, _| out.push((i, j)));
        out
    }
}

#[inline(always)]
pub(crate) fn dot<const D: usize>(a: &[f64; D], b: &[f64; D]) -> f64 {
    let mut s = 0.0;
    for k in 0..D {
        s += a[k] * b[k];
    }
    s
}

pub(crate) struct Candidates<F> {
    pub(crate) f: F,
}

impl<const D: usize, F: FnMut(usize, usize)> CellPairs<D> for Candidates<F> {
    #[inline]
    fn span(&mut self, g: &Grid<D>, x: usize, ys: Range<usize>) {
        let i = g.order[x];
        for &j in &g.order[ys] {
            (self.f)(i.min(j), i.max(j));
        }
    }
}

/// Pair filter on the stored positions. `P`: some axis is periodic; `R`: per-item radii.
pub(crate) struct Close<F, const P: bool, const R: bool> {
    pub(crate) f: F,
}

impl<F, const P: bool, const R: bool> Close<F, P, R> {
    #[inline(always)]
    fn delta<const D: usize>(g: &Grid<D>, pa: &[f64; D], pb: &[f64; D]) -> [f64; D] {
        if P {
            // Stored positions are wrapped into the box, so |pb - pa| < L.
            g.min_image_wrapped(pa, pb)
        } else {
            let mut d = [0.0; D];
            for k in 0..D {
                d[k] = pb[k] - pa[k];
            }
            d
        }
    }
}

/// Candidates tested per batch before the survivors are handed to the callback.
const BATCH: usize = 64;

impl<F, const P: bool, const R: bool> Close<F, P, R> {
    /// Tests item `x` of cell `a` against items `ys` of cell `b` and calls back for the close
    /// ones.
    ///
    /// At packing density about a third of the candidates pass the distance test, the worst
    /// case for a branch predictor: a data-dependent branch per candidate costs more than the
    /// distance itself. So the test only appends the candidate's index to a small buffer
    /// (unconditional store, counter advanced by the comparison result), and the callback
    /// runs in a second, predictable loop over the survivors.
    #[inline(always)]
    fn batch<const D: usize>(
        &mut self,
        g: &Grid<D>,
        (i, pa, ra): (usize, &[f64; D], f64),
        ys: Range<usize>,
    ) where
        F: FnMut(usize, usize, [f64; D], f64),
    {
        let c2 = g.cutoff * g.cutoff;
        let ids = &g.order[ys.clone()];
        let ps = &g.sorted[ys.clone()];
        let rs = if R { &g.sorted_r[ys] } else { &[][..] };
        let mut hits = [0u8; BATCH];
        for (c, chunk) in ps.chunks(BATCH).enumerate() {
            let base = c * BATCH;
            let mut n = 0usize;
            for (k, pb) in chunk.iter().enumerate() {
                let d = Self::delta(g, pa, pb);
                let d2 = dot(&d, &d);
                let lim = if R {
                    let s = ra + rs[base + k];
                    s * s
                } else {
                    c2
                };
                // `n < BATCH` always; the mask only spares a bounds check.
                hits[n & (BATCH - 1)] = k as u8;
                n += usize::from(d2 < lim);
            }
            for &h in &hits[..n] {
                let y = base + usize::from(h);
                let d = Self::delta(g, pa, &ps[y]);
                let d2 = dot(&d, &d);
                let j = ids[y];
                if i < j {
                    (self.f)(i, j, d, d2);
                } else {
                    (self.f)(j, i, d.map(|t| -t), d2);
                }
            }
        }
    }
}

impl<const D: usize, F, const P: bool, const R: bool> CellPairs<D> for Close<F, P, R>
where
    F: FnMut(usize, usize, [f64; D], f64),
{
    #[inline]
    fn span(&mut self, g: &Grid<D>, x: usize, ys: Range<usize>) {
        let ra = if R { g.sorted_r[x] } else { 0.0 };
        self.batch(g, (g.order[x], &g.sorted[x], ra), ys);
    }

    /// One cell against one contiguous run: the same branch-free filter as
    /// [`batch`](Close::batch), with the survivors of all the cell's items collected
    /// together, so the set-up and the callback loop are paid once per run, not per item.
    #[inline]
    fn block(&mut self, g: &Grid<D>, a: Range<usize>, b: Range<usize>) {
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = "avx2,fma")]
            fn with_avx2<const D: usize, F, const P: bool, const R: bool>(
                s: &mut Close<F, P, R>,
                g: &Grid<D>,
                a: Range<usize>,
                b: Range<usize>,
            ) where
                F: FnMut(usize, usize, [f64; D], f64),
            {
                s.block_body::<D, true>(g, a, b);
            }
            if simd::has_avx2_fma() {
                // SAFETY: `with_avx2` only needs AVX2 and FMA, which the processor has.
                return unsafe { with_avx2(self, g, a, b) };
            }
        }
        self.block_body::<D, false>(g, a, b);
    }
}

impl<F, const P: bool, const R: bool> Close<F, P, R> {
    #[inline(always)]
    fn block_body<const D: usize, const AVX: bool>(
        &mut self,
        g: &Grid<D>,
        a: Range<usize>,
        b: Range<usize>,
    ) where
        F: FnMut(usize, usize, [f64; D], f64),
    {
        let c2 = g.cutoff * g.cutoff;
        // Each hit is the pair of positions packed in one `u64` (both are below 2^32, see
        // `MAX_ITEMS`): one 8-byte store per candidate instead of two.
        let mut hits = [0u64; BATCH];
        let mut n = 0usize;
        for x in a {
            let pa = g.sorted[x];
            let ra = if R { g.sorted_r[x] } else { 0.0 };
            let lo = b.start.max(x + 1);
            if lo >= b.end {
                continue;
            }
            let ps = &g.sorted[lo..b.end];
            let rs = if R { &g.sorted_r[lo..b.end] } else { &[][..] };
            // In 3D without periodic axes, whole quads of candidates four at a time (AVX2,
            // `close_quads3`), the rest (at most three) by the scalar loop below, which gives
            // the same verdicts. (Masked loads for the last partial quad measured slower.)
            let mut done = 0;
            #[cfg(target_arch = "x86_64")]
            if AVX && D == 3 && !P {
                // SAFETY (of the cast): D == 3, so `[f64; D]` is `[f64; 3]`.
                let ps3 = unsafe { &*(core::ptr::from_ref(ps) as *const [[f64; 3]]) };
                let quads = ps.len() / 4 * 4;
                while done < quads {
                    if n + QUAD_RUN > BATCH {
                        self.emit(g, &hits[..n]);
                        n = 0;
                    }
                    let end = quads.min(done + QUAD_RUN);
                    let code = (x as u64) << 32 | (lo + done) as u64;
                    let rs = if R { &rs[done..end] } else { &[][..] };
                    // SAFETY: AVX2 is available (`AVX` is only true in `block`'s AVX2
                    // build, after the processor was checked).
                    n = unsafe {
                        close_quads3::<R>(
                            &ps3[done..end],
                            rs,
                            (&pa[..3], ra, c2),
                            code,
                            &mut hits,
                            n,
                        )
                    };
                    done = end;
                }
                // The quads may have filled the buffer exactly; the scalar loop below expects
                // room for one more hit.
                if n == BATCH {
                    self.emit(g, &hits);
                    n = 0;
                }
            }
            for (k, pb) in ps.iter().enumerate().skip(done) {
                let d = Self::delta(g, &pa, pb);
                let d2 = dot(&d, &d);
                let lim = if R {
                    let s = ra + rs[k];
                    s * s
                } else {
                    c2
                };
                hits[n & (BATCH - 1)] = (x as u64) << 32 | (lo + k) as u64;
                n += usize::from(d2 < lim);
                if n == BATCH {
                    self.emit(g, &hits);
                    n = 0;
                }
            }
        }
        self.emit(g, &hits[..n]);
    }
}

/// Candidates per call of [`close_quads3`] (a multiple of 4): the hit buffer is flushed when
/// fewer slots than this are left.
#[cfg(target_arch = "x86_64")]
const QUAD_RUN: usize = 32;

/// The distance filter of [`Close::block`] on whole quads of 3D candidates `ps` (length a
/// multiple of 4, at most `BATCH - n`): appends to `hits[n..]` the codes `code + k` of the
/// candidates `k` closer than the limit ((`ra + rs[k]`)² with per-item radii `rs`, else `c2`)
/// to `pa`, and returns the new count.
///
/// Four stored points are three 256-bit loads, [x₀ y₀ z₀ x₁] [y₁ z₁ x₂ y₂] [z₂ x₃ y₃ z₃]:
/// the centre is subtracted in the same rotated layout, the squares are transposed to one
/// register per axis (two lane swaps, three blends, three shuffles), and summed
/// (x² + y²) + z², the same operations in the same order as the scalar `dot`, so the verdicts
/// are the same bits. Survivors are written without branches, as in the scalar loop.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn close_quads3<const R: bool>(
    ps: &[[f64; 3]],
    rs: &[f64],
    (pa, ra, c2): (&[f64], f64, f64),
    code: u64,
    hits: &mut [u64; BATCH],
    mut n: usize,
) -> usize {
    use core::arch::x86_64::*;
    debug_assert!(ps.len().is_multiple_of(4) && n + ps.len() <= BATCH && pa.len() == 3);
    debug_assert!(!R || rs.len() == ps.len());
    let (ax, ay, az) = (pa[0], pa[1], pa[2]);
    let c0 = _mm256_setr_pd(ax, ay, az, ax);
    let c1 = _mm256_setr_pd(ay, az, ax, ay);
    let c2v = _mm256_setr_pd(az, ax, ay, az);
    let vra = _mm256_set1_pd(ra);
    let vlim = _mm256_set1_pd(c2);
    for (q, quad) in ps.chunks_exact(4).enumerate() {
        let p = quad.as_ptr().cast::<f64>();
        // SAFETY: a quad of `[f64; 3]` is twelve contiguous doubles, and `rs` (when used) has
        // a radius for each of its points.
        let (v0, v1, v2, rr) = unsafe {
            (
                _mm256_loadu_pd(p),
                _mm256_loadu_pd(p.add(4)),
                _mm256_loadu_pd(p.add(8)),
                if R {
                    _mm256_loadu_pd(rs.as_ptr().add(4 * q))
                } else {
                    _mm256_setzero_pd()
                },
            )
        };
        let (d0, d1, d2) = (
            _mm256_sub_pd(v0, c0),
            _mm256_sub_pd(v1, c1),
            _mm256_sub_pd(v2, c2v),
        );
        let (a, b, c) = (
            _mm256_mul_pd(d0, d0),
            _mm256_mul_pd(d1, d1),
            _mm256_mul_pd(d2, d2),
        );
        // a = [x0 y0 | z0 x1], b = [y1 z1 | x2 y2], c = [z2 x3 | y3 z3] (squares).
        let u = _mm256_permute2f128_pd::<0x20>(a, c); // [x0 y0 | z2 x3]
        let w = _mm256_permute2f128_pd::<0x31>(a, c); // [z0 x1 | y3 z3]
        let s1 = _mm256_blend_pd::<0b1100>(u, b); // [x0 y0 | x2 y2]
        let s2 = _mm256_blend_pd::<0b1100>(w, u); // [z0 x1 | z2 x3]
        let s3 = _mm256_blend_pd::<0b1100>(b, w); // [y1 z1 | y3 z3]
        let xx = _mm256_shuffle_pd::<0b1010>(s1, s2); // [x0 x1 x2 x3]
        let yy = _mm256_shuffle_pd::<0b0101>(s1, s3); // [y0 y1 y2 y3]
        let zz = _mm256_shuffle_pd::<0b1010>(s2, s3); // [z0 z1 z2 z3]
        let dist2 = _mm256_add_pd(_mm256_add_pd(xx, yy), zz);
        let lim = if R {
            let r = _mm256_add_pd(vra, rr);
            _mm256_mul_pd(r, r)
        } else {
            vlim
        };
        let close = _mm256_movemask_pd(_mm256_cmp_pd::<_CMP_LT_OQ>(dist2, lim)) as usize;
        let base = code + 4 * q as u64;
        for t in 0..4 {
            hits[n & (BATCH - 1)] = base + t as u64;
            n += (close >> t) & 1;
        }
    }
    n
}

impl<F, const P: bool, const R: bool> Close<F, P, R> {
    /// Calls back for pairs of positions already known to be close.
    #[inline(always)]
    fn emit<const D: usize>(&mut self, g: &Grid<D>, hits: &[u64])
    where
        F: FnMut(usize, usize, [f64; D], f64),
    {
        for &h in hits {
            let (x, y) = ((h >> 32) as usize, (h & 0xffff_ffff) as usize);
            let d = Self::delta(g, &g.sorted[x], &g.sorted[y]);
            let d2 = dot(&d, &d);
            let (i, j) = (g.order[x], g.order[y]);
            if i < j {
                (self.f)(i, j, d, d2);
            } else {
                (self.f)(j, i, d.map(|t| -t), d2);
            }
        }
    }
}
