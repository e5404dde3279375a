//! Reductions over long slices.

/// Lanes of independent partial sums: two 256-bit registers in the AVX2 build.
const LANES: usize = 8;

/// The sum of the lanes, in a fixed pairwise order.
#[inline(always)]
fn combine(acc: [f64; LANES]) -> f64 {
    let quads = [
        acc[0] + acc[4],
        acc[1] + acc[5],
        acc[2] + acc[6],
        acc[3] + acc[7],
    ];
    (quads[0] + quads[2]) + (quads[1] + quads[3])
}

/// Σ aᵢ bᵢ with [`LANES`] partial sums, combined pairwise at the end.
///
/// One running sum makes every addition wait for the one before (about four cycles each);
/// independent partial sums let the additions overlap and fill vector registers. The
/// summation order is fixed by the slice length alone, so the result is the same in every
/// build and on every processor (no fused multiply–add: `a * b + c` is never contracted).
#[inline(always)]
fn dot_lanes<const FMA: bool>(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0; LANES];
    let (a_chunks, b_chunks) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let (a_tail, b_tail) = (a_chunks.remainder(), b_chunks.remainder());
    for (x, y) in a_chunks.zip(b_chunks) {
        for k in 0..LANES {
            acc[k] += x[k] * y[k];
        }
    }
    for (k, (x, y)) in a_tail.iter().zip(b_tail).enumerate() {
        acc[k] += x * y;
    }
    combine(acc)
}

/// Σ gᵢ (tᵢ − xᵢ) with [`LANES`] partial sums (as [`dot_lanes`]).
#[inline(always)]
fn step_dot_lanes<const FMA: bool>(g: &[f64], t: &[f64], x: &[f64]) -> f64 {
    let n = g.len().min(t.len()).min(x.len());
    let (g, t, x) = (&g[..n], &t[..n], &x[..n]);
    let mut acc = [0.0; LANES];
    let whole = n - n % LANES;
    for i in (0..whole).step_by(LANES) {
        for k in 0..LANES {
            acc[k] += g[i + k] * (t[i + k] - x[i + k]);
        }
    }
    for i in whole..n {
        acc[i - whole] += g[i] * (t[i] - x[i]);
    }
    combine(acc)
}

/// qᵢ ← qᵢ + a yᵢ, then Σ sᵢ qᵢ over the updated q, in one pass with [`LANES`] partial sums
/// (as [`dot_lanes`]).
#[inline(always)]
fn axpy_dot_lanes<const FMA: bool>(q: &mut [f64], a: f64, y: &[f64], s: &[f64]) -> f64 {
    let n = q.len().min(y.len()).min(s.len());
    let (q, y, s) = (&mut q[..n], &y[..n], &s[..n]);
    let mut acc = [0.0; LANES];
    let whole = n - n % LANES;
    for i in (0..whole).step_by(LANES) {
        for k in 0..LANES {
            let v = q[i + k] + a * y[i + k];
            q[i + k] = v;
            acc[k] += s[i + k] * v;
        }
    }
    for i in whole..n {
        let v = q[i] + a * y[i];
        q[i] = v;
        acc[i - whole] += s[i] * v;
    }
    combine(acc)
}

/// max |aᵢ| over [`LANES`] running maxima; NaN entries are skipped, as by `f64::max`, so the
/// result is the one of a single running maximum.
#[inline(always)]
fn norm_inf_lanes<const FMA: bool>(a: &[f64]) -> f64 {
    let mut m = [0.0f64; LANES];
    let chunks = a.chunks_exact(LANES);
    let tail = chunks.remainder();
    for c in chunks {
        for k in 0..LANES {
            m[k] = m[k].max(c[k].abs());
        }
    }
    let lanes = m.iter().fold(0.0, |acc: f64, &v| acc.max(v));
    tail.iter().fold(lanes, |acc, v| acc.max(v.abs()))
}

crate::multiversion! {
    /// The dot product Σ aᵢ bᵢ of two slices (over the shorter one's length), with eight
    /// independent partial sums: several times faster than one running sum on long slices,
    /// and the same bits in the portable and the AVX2 build.
    ///
    /// ```
    /// let a: Vec<f64> = (0..1000).map(f64::from).collect();
    /// assert_eq!(simd::dot(&a, &[1.0; 1000]), 499_500.0);
    /// ```
    pub fn dot(a: &[f64], b: &[f64]) -> f64 => fused dot_lanes;
}

crate::multiversion! {
    /// gᵀ(t − x), the directional change of the step from x to t (over the shortest slice's
    /// length), with eight partial sums as [`dot`], without storing t − x.
    ///
    /// ```
    /// assert_eq!(simd::step_dot(&[1.0, 2.0], &[3.0, 5.0], &[1.0, 1.0]), 10.0);
    /// ```
    pub fn step_dot(g: &[f64], t: &[f64], x: &[f64]) -> f64 => fused step_dot_lanes;
}

crate::multiversion! {
    /// qᵢ ← qᵢ + a yᵢ, and the dot product Σ sᵢ qᵢ with the updated q (over the shortest
    /// slice's length), in one pass over memory instead of two: the step of the L-BFGS
    /// two-loop recursion that updates q and takes the next pair's inner product with it.
    /// The sum has the order, and so the bits, of [`dot`] of the updated q.
    ///
    /// ```
    /// let mut q = [1.0, 2.0];
    /// assert_eq!(simd::axpy_dot(&mut q, 2.0, &[1.0, 1.0], &[1.0, 10.0]), 43.0);
    /// assert_eq!(q, [3.0, 4.0]);
    /// ```
    pub fn axpy_dot(q: &mut [f64], a: f64, y: &[f64], s: &[f64]) -> f64 => fused axpy_dot_lanes;
}

crate::multiversion! {
    /// The sup-norm max |aᵢ| (0 for an empty slice; NaN entries are skipped, as by
    /// `f64::max`), over eight running maxima.
    ///
    /// ```
    /// assert_eq!(simd::norm_inf(&[1.0, -7.0, f64::NAN, 3.0]), 7.0);
    /// ```
    pub fn norm_inf(a: &[f64]) -> f64 => fused norm_inf_lanes;
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec;
    use std::vec::Vec;

    #[test]
    fn every_length_matches_the_sum_in_exact_arithmetic() {
        // Small integers: every partial sum is exact, whatever the order.
        for n in 0..40 {
            let a: Vec<f64> = (0..n).map(|i| (i % 7) as f64 - 3.0).collect();
            let b: Vec<f64> = (0..n).map(|i| (i % 5) as f64 + 1.0).collect();
            let exact: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            assert_eq!(dot(&a, &b), exact, "n = {n}");
        }
    }

    #[test]
    fn both_builds_give_the_same_bits() {
        let a: Vec<f64> = (0..1003).map(|i| (i as f64 * 0.37).sin()).collect();
        let b: Vec<f64> = (0..1003).map(|i| (i as f64 * 0.11).cos() * 1e3).collect();
        assert_eq!(dot_lanes::<false>(&a, &b), dot(&a, &b));
        // Rounding stays at the level of the condition of the sum.
        let reference: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
        let scale: f64 = a.iter().zip(&b).map(|(x, y)| (x * y).abs()).sum();
        assert!((dot(&a, &b) - reference).abs() <= 1e-13 * scale);
    }

    #[test]
    fn lane_reductions_match_the_plain_loops_at_every_length() {
        for n in 0..41 {
            // Small integers: every partial sum is exact, whatever the order.
            let g: Vec<f64> = (0..n).map(|i| (i % 5) as f64 - 2.0).collect();
            let t: Vec<f64> = (0..n).map(|i| (i % 7) as f64).collect();
            let x: Vec<f64> = (0..n).map(|i| (i % 3) as f64).collect();
            let plain: f64 = (0..n).map(|i| g[i] * (t[i] - x[i])).sum();
            assert_eq!(step_dot(&g, &t, &x), plain, "n = {n}");
            let plain_max = g.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
            assert_eq!(norm_inf(&g), plain_max, "n = {n}");
        }
        // The largest entry counts wherever it sits, and NaN is skipped as by `f64::max`.
        let mut v = vec![1.0; 19];
        v[17] = -9.0;
        v[3] = f64::NAN;
        assert_eq!(norm_inf(&v), 9.0);
        v[17] = 1.0;
        v[9] = -4.0;
        assert_eq!(norm_inf(&v), 4.0);
    }

    #[test]
    fn axpy_dot_updates_q_and_gives_the_bits_of_dot() {
        for n in [0, 1, 7, 8, 9, 1003] {
            let y: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let s: Vec<f64> = (0..n).map(|i| (i as f64 * 0.11).cos() * 1e3).collect();
            let mut q: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).cos()).collect();
            let updated: Vec<f64> = q.iter().zip(&y).map(|(qi, yi)| qi + -0.3 * yi).collect();
            let d = axpy_dot(&mut q, -0.3, &y, &s);
            assert_eq!(q, updated, "n = {n}");
            assert_eq!(d.to_bits(), dot(&s, &updated).to_bits(), "n = {n}");
        }
    }

    #[test]
    fn the_shorter_slice_sets_the_length() {
        assert_eq!(dot(&[1.0, 2.0, 3.0], &[1.0, 1.0]), 3.0);
    }
}
