//! Projection onto the box Ω = {x : l ≤ x ≤ u} and the projected-gradient stationarity measure.
//!
//! The measure used everywhere (inner stopping test, reported optimality) is the sup-norm of the
//! projected gradient step,
//!
//! ```text
//! ‖P_Ω(x − ∇F(x)) − x‖∞,
//! ```
//!
//! which vanishes exactly at the first-order stationary points of F on Ω (Birgin & Martínez 2014,
//! §3.1 and chapter 9). Infinite bounds are handled by the IEEE comparisons in `clamp`.
//!
//! # References
//! - E. G. Birgin, J. M. Martínez, *Practical Augmented Lagrangian Methods for Constrained
//!   Optimization*, SIAM, 2014.

/// Projects one coordinate onto [lower, upper]; `max` then `min` keeps ±∞ bounds harmless.
#[inline]
pub(crate) fn clamp(v: f64, lower: f64, upper: f64) -> f64 {
    v.max(lower).min(upper)
}

/// Projects `x` onto the box in place.
pub(crate) fn project(x: &mut [f64], lower: &[f64], upper: &[f64]) {
    map_blocks(x, |start, x| {
        let bounds = lower[start..].iter().zip(&upper[start..]);
        for (xi, (&l, &u)) in x.iter_mut().zip(bounds) {
            *xi = clamp(*xi, l, u);
        }
    });
}

/// ‖P(x − g) − x‖∞ (a maximum: the same by blocks).
pub(crate) fn projected_gradient_norm(x: &[f64], g: &[f64], lower: &[f64], upper: &[f64]) -> f64 {
    let n = x.len().min(g.len()).min(lower.len()).min(upper.len());
    blocked(n, |r| {
        let (x, g) = (&x[r.clone()], &g[r.clone()]);
        x.iter()
            .zip(g)
            .zip(lower[r.clone()].iter().zip(&upper[r]))
            .map(|((&xi, &gi), (&l, &u))| (clamp(xi - gi, l, u) - xi).abs())
            .fold(0.0, f64::max)
    })
    .into_iter()
    .fold(0.0, f64::max)
}

/// Entries per block of the reductions over long vectors: a vector longer than this is
/// reduced block by block ([`simd`]'s eight partial sums in each) and the blocks' results are
/// added in order. The blocks run on rayon's current pool with the `rayon` feature; the sum
/// is the same bits on any number of threads, and for vectors up to one block it is
/// [`simd`]'s. At 6·10⁵ variables (10⁵ ellipsoids) the L-BFGS two-loop recursion makes some
/// thirty passes over such vectors per iteration.
pub(crate) const BLOCK: usize = 1 << 14;

/// `part(block)` for the blocks of `0..n` of [`BLOCK`] indices, in the order of the blocks (on
/// rayon's pool with the `rayon` feature).
fn blocked<R: Send>(n: usize, part: impl Fn(std::ops::Range<usize>) -> R + Sync + Send) -> Vec<R> {
    let block = |b: usize| part(b * BLOCK..((b + 1) * BLOCK).min(n));
    #[cfg(feature = "rayon")]
    if n > BLOCK {
        use rayon::prelude::*;
        return (0..n.div_ceil(BLOCK)).into_par_iter().map(block).collect();
    }
    (0..n.div_ceil(BLOCK).max(1)).map(block).collect()
}

/// Σ over the blocks of `0..n` of `part(block)`, in the order of the blocks.
fn blocked_sum(n: usize, part: impl Fn(std::ops::Range<usize>) -> f64 + Sync + Send) -> f64 {
    if n <= BLOCK {
        return part(0..n);
    }
    blocked(n, part).into_iter().fold(0.0, |sum, p| sum + p)
}

/// `f(start, chunk)` for the consecutive chunks of [`BLOCK`] entries of `v`, `start` the index
/// of the chunk's first entry, on rayon's pool with the `rayon` feature: element-wise updates
/// of `v` that read other vectors at the same indices. The chunks' results, in order.
pub(crate) fn map_blocks<T: Send, R: Send>(
    v: &mut [T],
    f: impl Fn(usize, &mut [T]) -> R + Sync + Send,
) -> Vec<R> {
    #[cfg(feature = "rayon")]
    if v.len() > BLOCK {
        use rayon::prelude::*;
        return v
            .par_chunks_mut(BLOCK)
            .enumerate()
            .map(|(b, c)| f(b * BLOCK, c))
            .collect();
    }
    v.chunks_mut(BLOCK)
        .enumerate()
        .map(|(b, c)| f(b * BLOCK, c))
        .collect()
}

/// `to ← from`, by blocks as [`map_blocks`].
pub(crate) fn copy(to: &mut [f64], from: &[f64]) {
    map_blocks(to, |start, to| {
        to.copy_from_slice(&from[start..start + to.len()])
    });
}

/// Euclidean inner product: eight partial sums in a fixed order ([`simd::dot`]) per block of
/// [`BLOCK`] entries, so that results are reproducible bit for bit on every processor and on
/// any number of threads, and long sums do not wait on one running total.
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    blocked_sum(n, |r| simd::dot(&a[r.clone()], &b[r]))
}

/// Sup-norm ([`simd::norm_inf`]: NaN entries are skipped, as by `f64::max`); a maximum, so
/// the same by blocks.
#[inline]
pub(crate) fn norm_inf(a: &[f64]) -> f64 {
    if a.len() <= BLOCK {
        return simd::norm_inf(a);
    }
    #[cfg(feature = "rayon")]
    {
        use rayon::prelude::*;
        a.par_chunks(BLOCK)
            .map(simd::norm_inf)
            .reduce(|| 0.0, f64::max)
    }
    #[cfg(not(feature = "rayon"))]
    a.chunks(BLOCK).map(simd::norm_inf).fold(0.0, f64::max)
}

/// gᵀ(t − x), the directional change of a step from x to t ([`simd::step_dot`] per block,
/// as [`dot`]).
#[inline]
pub(crate) fn step_dot(g: &[f64], t: &[f64], x: &[f64]) -> f64 {
    let n = g.len().min(t.len()).min(x.len());
    blocked_sum(n, |r| simd::step_dot(&g[r.clone()], &t[r.clone()], &x[r]))
}

/// qᵢ ← qᵢ + a yᵢ and Σ sᵢ qᵢ over the updated q in one pass ([`simd::axpy_dot`] per block,
/// the blocks' sums added in order as [`dot`]): the step of the L-BFGS two-loop recursion.
pub(crate) fn axpy_dot(q: &mut [f64], a: f64, y: &[f64], s: &[f64]) -> f64 {
    let n = q.len().min(y.len()).min(s.len());
    let (q, y, s) = (&mut q[..n], &y[..n], &s[..n]);
    if n <= BLOCK {
        return simd::axpy_dot(q, a, y, s);
    }
    #[cfg(feature = "rayon")]
    let parts: Vec<f64> = {
        use rayon::prelude::*;
        q.par_chunks_mut(BLOCK)
            .zip(y.par_chunks(BLOCK))
            .zip(s.par_chunks(BLOCK))
            .map(|((q, y), s)| simd::axpy_dot(q, a, y, s))
            .collect()
    };
    #[cfg(not(feature = "rayon"))]
    let parts = q
        .chunks_mut(BLOCK)
        .zip(y.chunks(BLOCK))
        .zip(s.chunks(BLOCK))
        .map(|((q, y), s)| simd::axpy_dot(q, a, y, s));
    parts.into_iter().fold(0.0, |sum, p| sum + p)
}

/// Applies `f` to every entry of `v` (by blocks as [`map_blocks`]).
pub(crate) fn for_each_entry(v: &mut [f64], f: impl Fn(&mut f64) + Sync + Send) {
    map_blocks(v, |_, chunk| chunk.iter_mut().for_each(&f));
}

/// True if every entry is finite.
#[inline]
pub(crate) fn all_finite(a: &[f64]) -> bool {
    blocked(a.len(), |r| a[r].iter().all(|v| v.is_finite()))
        .into_iter()
        .all(|b| b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Long vectors are reduced by blocks, the blocks' sums in order: on small integers every
    /// partial sum is exact, so the result is the exact sum; and the update of q is the
    /// plain one.
    #[test]
    fn blocked_reductions_are_the_sums_of_their_blocks() {
        let n = 3 * BLOCK + 17;
        let a: Vec<f64> = (0..n).map(|i| (i % 7) as f64 - 3.0).collect();
        let b: Vec<f64> = (0..n).map(|i| (i % 5) as f64 + 1.0).collect();
        let exact: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
        assert_eq!(dot(&a, &b), exact);
        let by_blocks = a
            .chunks(BLOCK)
            .zip(b.chunks(BLOCK))
            .fold(0.0, |s, (x, y)| s + simd::dot(x, y));
        assert_eq!(dot(&a, &b), by_blocks);
        let zero = vec![0.0; n];
        assert_eq!(step_dot(&a, &b, &zero), exact);
        let mut q = a.clone();
        let sq = axpy_dot(&mut q, 2.0, &b, &b);
        let expected: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + 2.0 * y).collect();
        assert_eq!(q, expected);
        assert_eq!(sq, expected.iter().zip(&b).map(|(x, y)| x * y).sum::<f64>());
        let mut peak = a.clone();
        peak[2 * BLOCK + 5] = -99.0;
        assert_eq!(norm_inf(&peak), 99.0);
        for_each_entry(&mut peak, |v| *v = -*v);
        assert_eq!(peak[2 * BLOCK + 5], 99.0);
    }

    /// The element-wise passes by blocks see each entry once, at its own index.
    #[test]
    fn blocks_see_every_entry_at_its_index() {
        let n = 2 * BLOCK + 3;
        let from: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let mut to = vec![-1.0; n];
        copy(&mut to, &from);
        assert_eq!(to, from);
        let starts = map_blocks(&mut to, |start, chunk| {
            chunk.iter_mut().for_each(|v| *v -= start as f64);
            start
        });
        assert_eq!(starts, [0, BLOCK, 2 * BLOCK]);
        assert_eq!(to[BLOCK + 4], 4.0);
        let (lower, upper) = (vec![2.0; n], vec![f64::INFINITY; n]);
        let mut x = from.clone();
        x[2 * BLOCK + 1] = -5.0;
        assert_eq!(
            projected_gradient_norm(&x, &vec![0.0; n], &lower, &upper),
            7.0
        );
        project(&mut x, &lower, &upper);
        assert_eq!(x[2 * BLOCK + 1], 2.0);
        assert_eq!(x[BLOCK], BLOCK as f64);
        assert!(all_finite(&x));
        x[2 * BLOCK + 2] = f64::NAN;
        assert!(!all_finite(&x));
    }

    #[test]
    fn projected_gradient_vanishes_only_where_the_gradient_points_out_of_the_box() {
        let l = [0.0, f64::NEG_INFINITY, -1.0];
        let u = [1.0, 2.0, f64::INFINITY];
        // At the lower bound with a positive gradient the step is blocked.
        assert_eq!(
            projected_gradient_norm(&[0.0, 0.0, 0.0], &[3.0, 0.0, 0.0], &l, &u),
            0.0
        );
        // With a negative gradient it is not, and the step is cut by the upper bound.
        assert_eq!(
            projected_gradient_norm(&[0.0, 0.0, 0.0], &[-3.0, 0.0, 0.0], &l, &u),
            1.0
        );
        // Infinite bounds never cut.
        assert_eq!(
            projected_gradient_norm(&[0.0, 0.0, 5.0], &[0.0, 7.0, -4.0], &l, &u),
            7.0
        );
        let mut x = [-2.0, -1e300, 1e300];
        project(&mut x, &l, &u);
        assert_eq!(x, [0.0, -1e300, 1e300]);
    }
}
